"""Bottom-up attention fields: creation (Eq. 13), four-quadrant integration
(Eq. 14-15) and removal (Eq. 16), as in Algorithm 1 of the paper.

An attention field (AF) is an LPLC2 cell placed where the local motion is
most salient. Its four dendritic arbours each integrate the motion of one
quadrant in the two outward directions of that quadrant:

    Q1 (upper right) = sum LM_r + LM_u     Q2 (upper left)  = sum LM_l + LM_u
    Q3 (lower left)  = sum LM_l + LM_d     Q4 (lower right) = sum LM_r + LM_d

and the cell fires only when all four arbours are excited (Eq. 15).
Coordinates: x = column, y = row (origin top-left), "up" = decreasing row.
The centre row and column of a field belong to no quadrant, so the four
quadrants are mirror images of one another.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .lobula_plate import LocalMotion

__all__ = ["AttentionField", "Field", "quadrant_sums", "quadrant_areas", "gate_area", "lplc2_response", "field_mask",
           "argmax_outside"]


@dataclass(frozen=True)
class Field:
    """Snapshot of one attention field in one frame (what models return).

    ``x`` is the column and ``y`` the row of the centre in the pixels of the
    frames given to the model; ``radius`` the half-side (R_AF); ``response`` the
    LPLC2 output of Eq. 15; ``collision`` the field's alarm (the paper's "fatal"
    field: its responses over the last ``alarm_window`` frames reach
    ``alarm_threshold``); ``born`` the frame index at creation; ``quadrants``
    the four arbour integrals Q1..Q4 of Eq. 14. What the field's object will do
    (time to contact, course, warning) is in ``Output.targets``
    (:mod:`mlplc2.targets`).
    """

    id: int
    x: float
    y: float
    radius: float
    response: float
    collision: bool
    born: int
    quadrants: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)


@dataclass
class AttentionField:
    """Mutable state of one attention field (an LPLC2 cell)."""

    id: int
    x: int
    y: int
    born: int
    radius: int
    history: deque = field(default_factory=deque)
    response: float = 0.0
    quadrants: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    collision: bool = False

    def snapshot(self) -> Field:
        return Field(self.id, float(self.x), float(self.y), float(self.radius), self.response,
                     self.collision, self.born, self.quadrants)


def _window(cx: int, cy: int, r: int, shape: tuple[int, int]):
    """Slices of the four quadrants (Q1..Q4) of a field, clipped to the frame."""
    h, w = shape
    up = slice(max(cy - r, 0), max(min(cy, h), 0))
    down = slice(min(max(cy + 1, 0), h), min(cy + r + 1, h))
    left = slice(max(cx - r, 0), max(min(cx, w), 0))
    right = slice(min(max(cx + 1, 0), w), min(cx + r + 1, w))
    return (up, right), (up, left), (down, left), (down, right)


_DISC_CACHE: dict[int, np.ndarray] = {}


def field_mask(r: int) -> np.ndarray:
    """Boolean (2r+1, 2r+1) disc of radius r (used for ``field_shape='disc'``)."""
    if r not in _DISC_CACHE:
        yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
        _DISC_CACHE[r] = (xx * xx + yy * yy) <= r * r
    return _DISC_CACHE[r]


def _disc_part(cx: int, cy: int, r: int, rows: slice, cols: slice) -> np.ndarray:
    """The part of the disc of radius r centred on (cx, cy) that the frame slices ``rows, cols`` cover."""
    return field_mask(r)[rows.start - cy + r:rows.stop - cy + r, cols.start - cx + r:cols.stop - cx + r]


def quadrant_sums(lm: LocalMotion, cx: int, cy: int, r: int, shape: str = "square"
                  ) -> tuple[float, float, float, float]:
    """Eq. 14: the four quadrant integrals Q1..Q4 of a field centred at (cx, cy)."""
    pairs = ((lm.r, lm.u), (lm.l, lm.u), (lm.l, lm.d), (lm.r, lm.d))
    out = []
    for (rows, cols), (a, b) in zip(_window(cx, cy, r, lm.magnitude.shape), pairs):
        a, b = a[rows, cols], b[rows, cols]
        if shape == "disc":
            m = _disc_part(cx, cy, r, rows, cols)
            a, b = a[m], b[m]
        out.append(float(np.sum(a, dtype=np.float64) + np.sum(b, dtype=np.float64)))
    return tuple(out)


def quadrant_areas(cx: int, cy: int, r: int, frame_shape: tuple[int, int], shape: str = "square"
                   ) -> tuple[int, ...]:
    """Number of pixels of each quadrant Q1..Q4 inside the frame (of the disc with ``shape='disc'``)."""
    if shape == "disc":
        return tuple(int(np.count_nonzero(_disc_part(cx, cy, r, rows, cols)))
                     for rows, cols in _window(cx, cy, r, frame_shape))
    return tuple((rows.stop - rows.start) * (cols.stop - cols.start)
                 for rows, cols in _window(cx, cy, r, frame_shape))


def gate_area(area: float, r_af: int) -> float:
    """Area (px) that scales the arbour threshold of a quadrant of ``area`` pixels.

    Up to a full attention-field quadrant (R_AF^2) it is the area itself, so a field
    clipped by the frame border needs proportionally less; beyond, it grows as
    sqrt(area * R_AF^2): a larger cell (the frame-wide LPLC2) integrates more
    background, but the signal of one object does not grow with the cell.
    """
    full = float(r_af) * float(r_af)
    return float(area) if area <= full else math.sqrt(float(area) * full)


def lplc2_response(q, thresholds=0.0) -> float:
    """Eq. 15: LPLC2 = bool(all Q_i > threshold_i) * (Q1 + Q2 + Q3 + Q4).

    ``thresholds`` is one number or one per quadrant (the arbour thresholds).
    """
    t = np.asarray(thresholds, dtype=np.float64)
    if t.shape != (4,):                     # one number for all four (broadcast only then: it costs ~20 us)
        t = np.broadcast_to(t, (4,))
    if all(qi > ti for qi, ti in zip(q, t)):
        return float(sum(q))
    return 0.0


def argmax_outside(lm_map: np.ndarray, zones, shape: str = "square"):
    """Eq. 13: (x, y, value) of the largest LM outside every zone (None if no pixel left).

    ``zones`` is a sequence of (x, y, r): excluded squares (or discs) of
    half-side r centred on (x, y).
    """
    if not zones:
        idx = int(np.argmax(lm_map))
        y, x = divmod(idx, lm_map.shape[1])
        return x, y, float(lm_map[y, x])
    masked = lm_map.copy()
    h, w = masked.shape
    for fx, fy, r in zones:
        rows = slice(max(fy - r, 0), min(fy + r + 1, h))
        cols = slice(max(fx - r, 0), min(fx + r + 1, w))
        if rows.start >= rows.stop or cols.start >= cols.stop:
            continue  # the zone lies outside the frame
        if shape == "disc":
            masked[rows, cols][_disc_part(fx, fy, r, rows, cols)] = -np.inf
        else:
            masked[rows, cols] = -np.inf
    idx = int(np.argmax(masked))
    y, x = divmod(idx, w)
    value = float(masked[y, x])
    if value == -np.inf:
        return None
    return x, y, value

