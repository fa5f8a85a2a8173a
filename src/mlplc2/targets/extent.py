"""The box of a candidate from the edges of the outward local motion around a point.

From a seed point, four strips run along its row and column; in each, the outward component of
the local motion (LM_r, LM_l, LM_u, LM_d of Eq. 12) is a profile whose nearest edge complex is
the object's edge (:func:`edge_distance`, :func:`measure_extent`, :class:`Extent`;
``docs/targets.md``, step 2). The compiled twin of the four scans is
:func:`mlplc2.targets._fast_extent.edges4` (bit-identical).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

from ..neuropils.lobula_plate import LocalMotion
from .params import TargetParams

__all__ = ["Extent", "edge_distance", "measure_extent"]

_FLOATS = (np.dtype(np.float32), np.dtype(np.float64))


@dataclass(frozen=True)
class Extent:
    """One frame's measurement of the expanding object around a field centre (pixels).

    ``width``/``height`` are None when the edges on one side of that axis were
    not found; ``cx``/``cy`` the expansion centre (field centre where unknown);
    ``edges`` the estimated true edge positions (right x, left x, upper y,
    lower y), None where not found.
    """

    width: float | None
    height: float | None
    cx: float
    cy: float
    edges: tuple[float | None, float | None, float | None, float | None] = (None, None, None, None)

    @property
    def size(self) -> float | None:
        vals = [v for v in (self.width, self.height) if v is not None]
        return float(sum(vals) / len(vals)) if vals else None


def _edge_distances(prof: np.ndarray, lens, scale, params: TargetParams) -> list:
    """:func:`edge_distance` of several profiles at once (rows of ``prof``).

    ``prof``: (m, L) float64, row ``i`` valid in ``[:lens[i]]`` and -inf beyond (padding),
    ``L > max(lens)``; row ``i`` holds ``scale[i]`` x the profile (strip *sums*: every test
    below is a ratio, except the floor ``min_peak``, which is scaled).

    Only the samples above half the noise floor matter (a complex's peak, the largest
    value near its start and its outer boundary are all among them once the peak passes
    the floor), so after one sort (the floors) and one threshold the scan is a short
    Python loop over those samples, stopping at each row's first edge.
    """
    m, width = prof.shape
    srt = np.sort(prof, axis=1)                         # the padding sorts first
    floors = []
    for i in range(m):
        n = lens[i]
        q = float(srt[i, width - n + int(0.75 * (n - 1))]) if n > 0 else 0.0   # 75th percentile
        floors.append(max(params.min_peak * scale[i], params.noise_k * max(q, 0.0)))
    thr = np.array(floors)
    r, c = np.nonzero(prof >= 0.5 * thr[:, None])      # the padding never counts
    out = [None] * m
    if r.size == 0:
        return out
    vals = prof[r, c].tolist()
    r = r.tolist()
    c = c.tolist()
    ns = len(r)
    gap, local, rel_start, rel_edge = params.gap, params.local, params.rel_start, params.rel_edge
    i = 0
    while i < ns:
        row = r[i]
        floor = floors[row]
        row_end = bisect.bisect_right(r, row, i)
        # complexes of this row, outwards, until the first that passes
        while i < row_end:
            j = i
            peak = vals[i]
            while j + 1 < row_end and c[j + 1] - c[j] <= gap:
                j += 1
                if vals[j] > peak:
                    peak = vals[j]
            if peak >= floor:
                near = peak
                k = j + 1
                lim = c[i] + local
                while k < row_end and c[k] < lim:
                    if vals[k] > near:
                        near = vals[k]
                    k += 1
                if peak >= rel_start * near:
                    level = rel_edge * peak
                    k = j
                    while vals[k] < level:
                        k -= 1
                    ck = c[k]
                    if ck + 1 < lens[row]:
                        a, b = vals[k], max(float(prof[row, ck + 1]), 0.0)
                        frac = (a - level) / max(a - b, 1e-12 * scale[row])
                        out[row] = float(ck + 1 + min(max(frac, 0.0), 1.0))
                    break
            i = j + 1
        i = row_end
    return out


def edge_distance(profile: np.ndarray, params: TargetParams = TargetParams()) -> float | None:
    """Distance (px from the centre) of the outer boundary of the nearest outward edge complex.

    ``profile[k]`` is the outward LM at distance ``k + 1`` px. Lobes closer
    than ``gap`` px form one complex. Going outwards, the first complex whose
    peak exceeds the noise floor (``max(min_peak, noise_k x`` the profile's
    75th percentile``)``) and ``rel_start`` x the largest value within
    ``local`` px of its start is the edge (so a weak ripple just before a
    strong edge is skipped, but a strong edge of *another* object further out
    does not hide this object's weaker one). Returns None when no edge is found
    or the complex reaches the end of the profile (the edge is at or beyond the
    frame border). ``edge_offset`` is *not* added.
    """
    p = np.asarray(profile, dtype=np.float64).ravel()
    n = p.size
    if n < 2:
        return None
    prof = np.full((1, n + 1), -np.inf)
    prof[0, :n] = p
    return _edge_distances(prof, [n], [1.0], params)[0]


def _strip_profiles(lm: LocalMotion, x: int, y: int, band: int):
    """The four outward profiles around (x, y) as rows of one padded array.

    Rows: right (LM_r along the row), left (LM_l), up (LM_u along the column), down
    (LM_d); each the *sum* over the ``2 band + 1`` px wide strip (float64), from distance 1
    to the frame border, -inf beyond (padding). Returns (array (4, max(W, H) + 1),
    lengths, number of pixels summed per row).
    """
    h, w = lm.magnitude.shape
    r0, r1 = max(y - band, 0), min(y + band + 1, h)
    c0, c1 = max(x - band, 0), min(x + band + 1, w)
    lens = [w - 1 - x, x, y, h - 1 - y]
    prof = np.full((4, max(w, h) + 1), -np.inf)
    add = np.add.reduce
    f64 = np.float64
    if lens[0]:
        add(lm.r[r0:r1, x + 1:], axis=0, dtype=f64, out=prof[0, :lens[0]])
    if lens[1]:
        add(lm.l[r0:r1, x - 1::-1], axis=0, dtype=f64, out=prof[1, :lens[1]])
    if lens[2]:
        add(lm.u[y - 1::-1, c0:c1], axis=1, dtype=f64, out=prof[2, :lens[2]])
    if lens[3]:
        add(lm.d[y + 1:, c0:c1], axis=1, dtype=f64, out=prof[3, :lens[3]])
    nr, nc = float(r1 - r0), float(c1 - c0)
    return prof, lens, [nr, nr, nc, nc]


def measure_extent(lm: LocalMotion, x: int, y: int, params: TargetParams = TargetParams(), *,
                   kernel=None) -> Extent:
    """Width, height and centre of the outward-expanding edges around (x, y).

    From (x, y), four strips of ``2 band + 1`` px run along the row and the column to the frame
    border; in each, the outward component of the local motion (LM_r to the right, LM_l to the
    left, LM_u upwards, LM_d downwards; positive part) is a profile whose nearest edge complex
    (lobes closer than ``gap`` px merged, above a noise floor) is the object's edge; its outer
    boundary, plus ``edge_offset`` (the lobes trail the true edge), is the edge position.

    ``kernel``: the compiled version of the four scans (:func:`mlplc2.targets._fast_extent.edges4`,
    bit-identical; :mod:`mlplc2.backend` chooses it), or None for the NumPy code.
    """
    h, w = lm.magnitude.shape
    x = int(min(max(x, 0), w - 1))
    y = int(min(max(y, 0), h - 1))
    r, l, u, d = lm.r, lm.l, lm.u, lm.d  # noqa: E741
    if kernel is not None and params.rel_edge <= 1.0 and r.dtype in _FLOATS and r.dtype == l.dtype == u.dtype == d.dtype \
            and r.shape == l.shape == u.shape == d.shape == (h, w):
        dist = kernel(r, l, u, d, x, y, int(params.band), float(params.min_peak), float(params.noise_k),
                           float(params.rel_start), float(params.rel_edge), int(params.gap), int(params.local))
        dr, dl, du, dd = [None if v < 0 else v for v in dist]
    else:
        prof, lens, scale = _strip_profiles(lm, x, y, params.band)
        dr, dl, du, dd = _edge_distances(prof, lens, scale, params)
    off = params.edge_offset
    width = height = None
    cx, cy = float(x), float(y)
    if dr is not None and dl is not None:
        width = dr + dl + 2 * off
        cx = x + (dr - dl) / 2.0
    if du is not None and dd is not None:
        height = du + dd + 2 * off
        cy = y + (dd - du) / 2.0
    edges = (None if dr is None else x + dr + off, None if dl is None else x - dl - off,
             None if du is None else y - du - off, None if dd is None else y + dd + off)
    return Extent(width, height, cx, cy, edges)

