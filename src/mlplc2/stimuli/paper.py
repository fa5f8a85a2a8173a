"""The 2-D synthetic stimuli of the mLPLC2 paper (Sec. IV-A and IV-B), with exact ground truth.

Every generator returns a :class:`Stimulus`: grey ``uint8`` frames of shape
``(T, H, W)`` plus one :class:`ObjectTruth` per object (centre, polarity,
phase intervals, side length per frame, contact frame; the one ground-truth type,
:class:`mlplc2.evaluation.truth.ObjectTruth`). Coordinates are pixels,
``x`` = column, ``y`` = row, origin at the top-left corner; frame indices are
0-based and intervals are half-open ``[start, end)``, exactly as in the
paper's ``ground_truth.json``. Everything is vectorised with NumPy (no loop
over pixels) and deterministic for a given ``seed``.

Map to the paper (Sec. IV, "Experimental Evaluation")
----------------------------------------------------
``dark_approach``, ``dark_recede``, ``bright_approach``, ``bright_recede``,
``translating``, ``grating``
    Sec. IV-A, Fig. 3 (the six columns, in this order, see
    :data:`BASIC_NAMES`): 100x100 px, 50 frames, 30 fps. Built by
    :func:`basic`. They reproduce the paper's ``basic/test_*.avi`` files
    pixel for pixel up to codec noise, including these details of the files:

    * background and "white" are grey level 250, not 255; dark is 0;
    * approach: side ``1 + 2 t`` px centred on (50, 50) (1 -> 99 px);
    * recede: side ``1 + 2 (T - t)`` px (101 -> 3 px, i.e. frame ``t`` of the
      recede equals frame ``T - t`` of a one-frame-longer approach; frame 0
      is entirely dark);
    * translating: a dark bar 21 px wide and 41 px tall (rows 30-70, drawn
      as an inclusive 20x40 rectangle) whose left edge is at ``x = 2 t``;
    * grating: vertical square wave of period 40 px (dark bars 21 px, light
      19 px) moving right by 1 px per frame.

``four_phase``
    Sec. IV-B, Fig. 4 (``scenes/outdoor_2_black_4_period.avi``): 320x240,
    400 frames, four phases of 100 frames (approach 40, hold 20, recede 40) on
    a background scrolling left by 1 px per frame. Built by :func:`four_phase`.

``six_objects``
    Sec. IV-B, Fig. 5 (``scenes/outdoor_3_black_expand_multi_6.avi``):
    320x240, 120 frames, six dark squares with onsets 5, 15, 25, 45, 55, 65;
    approach 40 frames, hold 10 frames, then the square disappears. Built by
    :func:`six_objects`.

``looming``
    Not in the paper: a physically correct constant-speed approach (angular
    half-size ``atan(l / (v (t_c - t)))``) for time-to-collision tests. Built
    by :func:`looming`.

Arbitrary multi-object scenes are made with :func:`scene` and
:class:`SceneObject`. (3-D approaches are in :mod:`mlplc2.stimuli.world`; the
names of :mod:`mlplc2.stimuli.dispatch` cover both families.)

Square geometry: a square of side ``s`` centred at ``(cx, cy)`` covers the
columns ``floor(cx - s/2 + 0.5)`` .. ``floor(cx + s/2 + 0.5) - 1`` (and the
same for rows), clipped to the frame. Growing ``s`` by 2 px per frame thus
moves each edge by exactly 1 px per frame, and the centre stays exact.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .._validation import InputValueError, as_gray, check_fps
from ..camera import check_hfov, focal_length
from ..evaluation.truth import ObjectTruth
from ._common import (MAX_STIMULUS_BYTES, Stimulus, check_choice, check_count, check_number, check_size,
                      plain_level, procedural_background)

__all__ = ["SceneObject", "BASIC_NAMES", "basic", "scene", "four_phase", "six_objects", "looming", "BASIC_WHITE",
           "DARK_LEVEL", "BRIGHT_LEVEL", "FOUR_PHASE_CENTERS", "SIX_OBJECT_CENTERS", "SIX_OBJECT_ONSETS",
           "MAX_SCROLL_PX"]

#: Column order of Fig. 3 (Sec. IV-A).
BASIC_NAMES: tuple[str, ...] = (
    "dark_approach", "dark_recede", "bright_approach", "bright_recede", "translating", "grating")
#: Grey level of "white" in the paper's basic test videos (not 255).
BASIC_WHITE = 250
#: Grey levels of dark and bright squares in scenes.
DARK_LEVEL = 0
BRIGHT_LEVEL = 255

_POLARITIES = ("dark", "bright")

#: Object centres of Fig. 4 (ground_truth.json, outdoor_2_black_4_period).
FOUR_PHASE_CENTERS: tuple[tuple[tuple[float, float], ...], ...] = (
    ((160.0, 120.0),), ((240.0, 60.0),), ((80.0, 180.0),), ((80.0, 60.0), (240.0, 180.0)))
#: Object centres and onsets of Fig. 5 (ground_truth.json, outdoor_3_black_expand_multi_6).
SIX_OBJECT_CENTERS: tuple[tuple[float, float], ...] = (
    (240.0, 60.0), (80.0, 120.0), (192.0, 180.0), (80.0, 60.0), (240.0, 120.0), (128.0, 180.0))
SIX_OBJECT_ONSETS: tuple[int, ...] = (5, 15, 25, 45, 55, 65)


@dataclass(frozen=True)
class SceneObject:
    """One square object of a :func:`scene`.

    Parameters
    ----------
    center : tuple of float
        ``(x, y)`` centre in pixels (may lie outside the frame; the square is
        clipped).
    onset : int
        First frame of the approach (or of the first existing phase).
    approach, hold, recede : int
        Lengths in frames of the three consecutive phases (any may be 0).
        Outside them the object is absent.
    polarity : {"dark", "bright"}
        Dark squares are drawn with grey level 0, bright ones with 255.
    growth : float
        Linear looming: side increase in px per frame (2 = 1 px per edge).
    start_side : float
        Linear looming: side at the first approach frame (the paper: 1 px).
    peak_side : float or None
        Side during ``hold`` and at the first recede frame. ``None``: the last
        approach side (``start_side + growth * (approach - 1)``, or
        ``start_side`` without approach), as in Fig. 4;
        Fig. 5 holds at ``start_side + growth * approach``. During recede the
        side shrinks by ``growth`` px per frame from ``peak_side`` ("linear");
        "physical" recedes as the time reverse of its approach (scaled to
        start at ``peak_side`` if given; required without approach).
    max_side : float or None
        Optional cap on the side length (px).
    looming : {"linear", "physical"}
        "linear": the paper's squares growing by ``growth`` px per frame.
        "physical": a square of half-size ``half_size`` m approaching at
        ``speed`` m/s; its side is ``2 f tan(theta)`` with
        ``theta = atan(l / (v (t_c - t)))`` and ``f`` from ``hfov_deg`` (see
        :func:`mlplc2.camera.focal_length`). The recede is the time reverse.
    half_size : float
        Physical half-size ``l`` in metres ("physical" only).
    speed : float
        Approach speed ``v`` in m/s ("physical" only).
    contact_frame : float or None
        "physical" only: the (fractional, absolute) frame index at which the
        object would reach the eye; ``None`` = ``onset + approach`` (contact
        one frame after the last approach frame). Must be > the last approach
        frame.
    """

    center: tuple[float, float]
    onset: int = 0
    approach: int = 40
    hold: int = 20
    recede: int = 40
    polarity: str = "dark"
    growth: float = 2.0
    start_side: float = 1.0
    peak_side: float | None = None
    max_side: float | None = None
    looming: str = "linear"
    half_size: float = 0.5
    speed: float = 5.0
    contact_frame: float | None = None


# ---------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------


def _draw_square(frame: np.ndarray, center: tuple[float, float], side: float, level: int) -> None:
    """Fill a square (in place) on one ``(H, W)`` frame, clipped to the frame (edges as in the
    module docstring, "Square geometry")."""
    if side <= 0:
        return
    h, w = frame.shape
    x0, x1, y0, y1 = (np.floor(c + d * side / 2.0 + 0.5) for c in center for d in (-1, 1))
    x0, x1 = int(max(x0, 0)), int(min(x1, w))
    y0, y1 = int(max(y0, 0)), int(min(y1, h))
    if x1 > x0 and y1 > y0:
        frame[y0:y1, x0:x1] = level


def _physical_sides(frames_idx: np.ndarray, contact_frame: float, fps: float, half_size: float,
                    speed: float, focal: float) -> np.ndarray:
    """Side length in px of a constant-speed approach at (absolute) frame indices."""
    remaining = (contact_frame - frames_idx) / fps          # seconds to contact
    distance = speed * remaining                             # metres
    theta = np.arctan(half_size / distance)                  # angular half-size
    return 2.0 * focal * np.tan(theta)


# ---------------------------------------------------------------------------
# Backgrounds
# ---------------------------------------------------------------------------


def _fit_height(image: np.ndarray, height: int) -> np.ndarray:
    """Bring an image to ``height`` rows: centre-crop if it is at most 25 % taller
    (how the paper's scenes were cut from their 251-row backgrounds), else resize
    keeping the aspect ratio."""
    import cv2

    h, w = image.shape
    if h == height:
        return image
    if height < h <= 1.25 * height:
        top = (h - height) // 2
        return image[top:top + height]
    new_w = max(1, int(round(w * height / h)))
    interp = cv2.INTER_AREA if height < h else cv2.INTER_LINEAR
    return cv2.resize(image, (new_w, height), interpolation=interp)


def _background_strip(background, width: int, height: int, need: int, seed: int) -> np.ndarray:
    """Return a float32 ``(height, >= need)`` strip for a scrolling scene."""
    import cv2

    if isinstance(background, (int, float, np.integer, np.floating)) and not isinstance(background, bool):
        level = check_number(background, "background level")
        if not 0 <= level <= 255:
            raise InputValueError(f"a uniform background level must be in 0..255, got {background!r}")
        return np.full((height, need), level, np.float32)
    if isinstance(background, str) and background == "procedural":
        return procedural_background(need, height, seed).astype(np.float32)
    if isinstance(background, (str, os.PathLike)):
        path = os.fspath(background)
        if not os.path.isfile(path):
            raise InputValueError(
                f"background must be 'procedural', 'plain', a grey level, an image path or an array; "
                f"no such file: {path!r}")
        image = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise InputValueError(f"cannot read background image {path!r}")
        strip = _fit_height(image, height).astype(np.float32)
    elif isinstance(background, np.ndarray):
        gray = as_gray(background, name="background")
        strip = _fit_height(np.clip(gray, 0, 255).astype(np.float32), height)
    else:
        raise InputValueError(
            "background must be 'procedural', 'plain', a grey level (0-255), an image path or an array, "
            f"got {background!r}")
    if strip.shape[1] < need:
        strip = np.tile(strip, (1, -(-need // strip.shape[1])))
    return strip


def _scrolled(strip: np.ndarray, offsets: np.ndarray, width: int) -> np.ndarray:
    """Frames ``(T, H, W)`` showing strip columns ``[offset_t, offset_t + W)`` (linear interpolation)."""
    t = len(offsets)
    h = strip.shape[0]
    out = np.empty((t, h, width), np.float32)
    cols = np.arange(width)
    for i, off in enumerate(offsets):
        base = int(math.floor(off))
        frac = float(off - base)
        if frac < 1e-9:
            out[i] = strip[:, base:base + width]
        else:
            left = strip[:, base + cols]
            right = strip[:, np.minimum(base + cols + 1, strip.shape[1] - 1)]
            out[i] = left * (1.0 - frac) + right * frac
    return out


# ---------------------------------------------------------------------------
# Basic stimuli (Sec. IV-A, Fig. 3)
# ---------------------------------------------------------------------------

def basic(name: str, *, size: int = 100, frames: int = 50, fps: float = 30.0) -> Stimulus:
    """One of the six basic stimuli of Sec. IV-A (Fig. 3).

    Parameters
    ----------
    name : str
        One of :data:`BASIC_NAMES`: "dark_approach", "dark_recede",
        "bright_approach", "bright_recede", "translating", "grating".
    size : int
        Frame width and height in pixels (the paper: 100). Bar geometry
        scales with ``size`` (rounded to whole pixels).
    frames : int
        Number of frames (the paper: 50).
    fps : float
        Frame rate (the paper's files: 30).

    Returns
    -------
    Stimulus
        Dark = 0 on a 250 background, bright = 250 on 0 (the paper's files).

    Notes
    -----
    The exact geometry, that of the paper's video files, is in the module docstring.
    """
    if name not in BASIC_NAMES:
        raise InputValueError(f"unknown basic stimulus {name!r}; valid names: {', '.join(BASIC_NAMES)}")
    size = check_count(size, "size", 1)
    n = check_count(frames, "frames", 1)
    fps = check_fps(fps)
    t = np.arange(n)
    scale = size / 100.0

    if name in ("dark_approach", "dark_recede", "bright_approach", "bright_recede"):
        polarity = "dark" if name.startswith("dark") else "bright"
        fg, bg = (0, BASIC_WHITE) if polarity == "dark" else (BASIC_WHITE, 0)
        cx = cy = size / 2.0
        sides = 1.0 + 2.0 * t if name.endswith("approach") else 1.0 + 2.0 * (n - t)
        video = np.full((n, size, size), bg, np.uint8)
        for i in range(n):
            _draw_square(video[i], (cx, cy), float(sides[i]), fg)
        phase = {"approach": (0, n)} if name.endswith("approach") else {"recede": (0, n)}
        obj = ObjectTruth(id=1, center=(cx, cy), polarity=polarity, sizes=tuple(float(s) for s in sides),
                          **phase)
        return Stimulus(video, fps, (obj,), name)

    if name == "translating":
        bar_w = int(round(20 * scale)) + 1      # inclusive 20 x 40 rectangle, as in the paper's file
        bar_h = int(round(40 * scale)) + 1
        top = int(round(30 * scale))
        speed = 2
        cols = np.arange(size)
        left = speed * t[:, None]
        inside_x = (cols[None, :] >= left) & (cols[None, :] < left + bar_w)        # (T, W)
        rows = np.arange(size)
        inside_y = (rows >= top) & (rows < top + bar_h)                              # (H,)
        mask = inside_y[None, :, None] & inside_x[:, None, :]
        video = np.where(mask, np.uint8(0), np.uint8(BASIC_WHITE)).astype(np.uint8)
        obj = ObjectTruth(id=1, center=((bar_w - 1) / 2.0, top + (bar_h - 1) / 2.0), polarity="dark",
                          translate=(0, n), sizes=(float(bar_w),) * n, velocity=(float(speed), 0.0),
                          extra={"note": f"{bar_w}x{bar_h} px dark bar (rows {top}-{top + bar_h - 1}) moving "
                                         f"right at {speed} px/frame on white; left edge at x = {speed} t"})
        return Stimulus(video, fps, (obj,), name)

    # grating
    bar = max(1, int(round(20 * scale)))
    period = 2 * bar
    cols = np.arange(size)
    phase_ = np.mod(cols[None, :] - bar - t[:, None], period)                        # (T, W)
    dark = phase_ <= bar                                                             # bar + 1 px dark
    row = np.where(dark, np.uint8(0), np.uint8(BASIC_WHITE)).astype(np.uint8)
    video = np.ascontiguousarray(np.broadcast_to(row[:, None, :], (n, size, size)))
    obj = ObjectTruth(id=1, center=None, polarity="dark", translate=(0, n), sizes=(float(bar),) * n,
                      velocity=(1.0, 0.0),
                      extra={"note": f"full-field square-wave grating, bar width {bar} px (period {period} px), "
                                     f"moving right at 1 px/frame"})
    return Stimulus(video, fps, (obj,), name)


# ---------------------------------------------------------------------------
# Scenes (Sec. IV-B, Fig. 4 and 5)
# ---------------------------------------------------------------------------

def _object_sides(obj: SceneObject, n: int, fps: float, focal: float) -> tuple[np.ndarray, float | None]:
    """Side length per frame (0 when absent) and contact frame of one scene object."""
    sides = np.zeros(n, np.float64)
    a0 = obj.onset
    a1 = a0 + obj.approach
    h1 = a1 + obj.hold
    contact = None
    if obj.looming == "physical":
        contact = float(a1 if obj.contact_frame is None else obj.contact_frame)
    if a0 >= n:
        return sides, contact  # starts after the last frame
    # Phases past the last frame are never drawn: cut them there (they may be huge).
    obj = dataclasses.replace(obj, approach=min(obj.approach, n - a0), hold=min(obj.hold, max(0, n - a1)),
                              recede=min(obj.recede, max(0, n - h1)))
    if obj.looming == "linear":
        approach_sides = obj.start_side + obj.growth * np.arange(obj.approach)
    else:
        approach_sides = _physical_sides(np.arange(a0, a0 + obj.approach, dtype=np.float64), contact, fps,
                                         obj.half_size, obj.speed, focal)
    if obj.peak_side is not None:
        peak = float(obj.peak_side)
    elif obj.approach > 0:
        peak = float(approach_sides[-1])
    elif obj.looming == "linear":
        peak = obj.start_side
    else:
        raise InputValueError("a physical object with no approach needs peak_side")
    if obj.looming == "linear":
        recede_sides = peak - obj.growth * np.arange(obj.recede)
    elif obj.approach == 0:
        # No approach to reverse: recede at ``speed`` from the distance at which the square
        # spans ``peak_side`` (side = 2 f l / distance, as in _physical_sides).
        if not peak > 0:
            raise InputValueError("a physical object with no approach needs peak_side > 0")
        start = obj.half_size * 2.0 * focal / peak
        recede_sides = 2.0 * focal * obj.half_size / (start + obj.speed * np.arange(obj.recede) / fps)
    else:
        recede_sides = approach_sides[::-1][:obj.recede] if obj.recede <= obj.approach else np.concatenate(
            [approach_sides[::-1], np.full(obj.recede - obj.approach, approach_sides[0])])
        if obj.peak_side is not None and obj.recede:
            recede_sides = recede_sides * (peak / max(float(recede_sides[0]), 1e-12))
    full = np.concatenate([approach_sides, np.full(obj.hold, peak), recede_sides])
    full = np.maximum(full, 0.0)
    if obj.max_side is not None:
        full = np.minimum(full, obj.max_side)
    idx = np.arange(a0, a0 + len(full))
    keep = (idx >= 0) & (idx < n)
    sides[idx[keep]] = full[keep]
    return sides, contact


def _check_object(obj, n: int, i: int) -> SceneObject:
    if not isinstance(obj, SceneObject):
        raise InputValueError(f"objects[{i}] must be a SceneObject, got {type(obj).__name__}")
    try:
        cx, cy = obj.center
        cx = check_number(cx, f"objects[{i}].center x")
        cy = check_number(cy, f"objects[{i}].center y")
    except (TypeError, ValueError):
        raise InputValueError(f"objects[{i}].center must be (x, y), got {obj.center!r}") from None
    onset = check_count(obj.onset, f"objects[{i}].onset", 0)
    if onset >= n:
        raise InputValueError(f"objects[{i}].onset {onset} is outside the video (0..{n - 1})")
    approach = check_count(obj.approach, f"objects[{i}].approach", 0)
    hold = check_count(obj.hold, f"objects[{i}].hold", 0)
    recede = check_count(obj.recede, f"objects[{i}].recede", 0)
    if approach + hold + recede == 0:
        raise InputValueError(f"objects[{i}] has no frames: approach, hold and recede are all 0")
    check_choice(obj.polarity, "polarity", _POLARITIES)
    check_choice(obj.looming, f"objects[{i}].looming", ("linear", "physical"))
    check_number(obj.growth, f"objects[{i}].growth", nonneg=True)
    check_number(obj.start_side, f"objects[{i}].start_side", nonneg=True)
    if obj.peak_side is not None:
        check_number(obj.peak_side, f"objects[{i}].peak_side", nonneg=True)
    if obj.max_side is not None:
        check_number(obj.max_side, f"objects[{i}].max_side", positive=True)
    if obj.looming == "physical":
        check_number(obj.half_size, f"objects[{i}].half_size", positive=True)
        check_number(obj.speed, f"objects[{i}].speed", positive=True)
        if obj.contact_frame is not None:
            c = check_number(obj.contact_frame, f"objects[{i}].contact_frame")
            if approach and c <= onset + approach - 1:
                raise InputValueError(f"objects[{i}].contact_frame {c} must be after the last approach frame "
                                      f"{onset + approach - 1}")
    return SceneObject(center=(cx, cy), onset=onset, approach=approach, hold=hold, recede=recede,
                       polarity=obj.polarity, growth=float(obj.growth), start_side=float(obj.start_side),
                       peak_side=obj.peak_side, max_side=obj.max_side, looming=obj.looming,
                       half_size=float(obj.half_size), speed=float(obj.speed), contact_frame=obj.contact_frame)


def _interval(start: int, length: int, n: int) -> tuple[int, int] | None:
    return None if length <= 0 or start >= n else (start, min(start + length, n))


MAX_SCROLL_PX = 100_000


def scene(objects: Sequence[SceneObject], *, size: tuple[int, int] = (320, 240), frames: int = 100,
          fps: float = 30.0, background: Any = "procedural", scroll: float = 1.0, seed: int = 0,
          hfov_deg: float = 60.0, name: str = "scene") -> Stimulus:
    """Square objects drawn over a (scrolling) background, as in Fig. 4 and 5.

    Parameters
    ----------
    objects : sequence of SceneObject
        The objects, drawn in order (later ones on top). They may overlap in
        space and time.
    size : tuple of int
        ``(W, H)`` in pixels.
    frames : int
        Number of frames ``T``.
    fps : float
        Frame rate; also converts frames to seconds for physical looming.
    background : "procedural", "plain", float, path or numpy.ndarray
        "procedural": :func:`procedural_background` (seeded by ``seed``);
        "plain": uniform grey 250 if every object is dark, 0 if every object
        is bright, else 128; a number: that uniform grey level; a path: an
        image read with OpenCV, converted to grey, resized to ``H`` rows
        keeping its aspect ratio and tiled horizontally if it is too narrow;
        an array: ``(h, w)`` grey or ``(h, w, 3)`` RGB, handled like an image.
    scroll : float
        Background speed in px per frame; positive = content moves left
        (camera panning right). Frame ``t`` shows background columns
        ``[t * scroll, t * scroll + W)`` (shifted so the smallest offset is 0
        when ``scroll < 0``); fractional offsets use linear interpolation.
    seed : int
        Seed of the procedural background.
    hfov_deg : float
        Horizontal field of view (degrees) for physical looming: focal length
        ``f = (W / 2) / tan(hfov / 2)`` px.
    name : str
        Name stored in the result.

    Returns
    -------
    Stimulus
    """
    w, h = check_size(size)
    n = check_count(frames, "frames", 1)
    fps = check_fps(fps)
    scroll = check_number(scroll, "scroll")
    seed = check_count(seed, "seed", 0)
    focal = focal_length(w, check_hfov(hfov_deg, required=True))
    if isinstance(objects, SceneObject):
        objects = [objects]
    checked = [_check_object(o, n, i) for i, o in enumerate(objects)]
    video = _scrolling_background(background, checked, n, (w, h), scroll, seed)
    truths, all_sides = [], []
    for i, obj in enumerate(checked):
        sides, contact = _object_sides(obj, n, fps, focal)
        all_sides.append(sides)
        half = 0.5 * float(sides.max())
        cx, cy = obj.center
        if half < 0.5 or cx + half < 0 or cy + half < 0 or cx - half > w - 1 or cy - half > h - 1:
            warnings.warn(f"objects[{i}] at ({cx:g}, {cy:g}) is never visible in the {w}x{h} frames "
                          f"{'(its side is 0)' if half < 0.5 else '(outside the frame)'}",
                          stacklevel=2)
        truths.append(_square_truth(i + 1, obj, sides, contact, n))
    for t in range(n):
        for obj, sides in zip(checked, all_sides):
            if sides[t] > 0:
                _draw_square(video[t], obj.center, float(sides[t]),
                             DARK_LEVEL if obj.polarity == "dark" else BRIGHT_LEVEL)
    return Stimulus(video, fps, tuple(truths), name)


def _scrolling_background(background, objects: list[SceneObject], n: int, size: tuple[int, int], scroll: float,
                          seed: int) -> np.ndarray:
    """The ``uint8 (T, H, W)`` background of :func:`scene`, scrolled by ``scroll`` px per frame."""
    w, h = size
    if isinstance(background, str) and background == "plain":
        background = plain_level([o.polarity for o in objects])
    if n * w * h > MAX_STIMULUS_BYTES:
        raise InputValueError(f"{n} frames of {w}x{h} need {n * w * h / 2**30:.1f} GiB; at most "
                              f"{MAX_STIMULUS_BYTES / 2**30:.0f} GiB (generate it in parts)")
    offsets = np.arange(n, dtype=np.float64) * scroll
    offsets -= offsets.min()
    if offsets.max() > MAX_SCROLL_PX:
        raise InputValueError(f"scroll {scroll!r} px per frame over {n} frames moves the background "
                              f"{offsets.max():.0f} px; at most {MAX_SCROLL_PX}")
    need = w + int(math.ceil(offsets.max())) + 1
    strip = _background_strip(background, w, h, need, seed)
    return np.clip(np.rint(_scrolled(strip, offsets, w)), 0, 255).astype(np.uint8)


def _square_truth(oid: int, obj: SceneObject, sides: np.ndarray, contact: float | None, n: int) -> ObjectTruth:
    """The truth of one square of :func:`scene`: its phases, its side per frame, its contact."""
    a0, a1 = obj.onset, obj.onset + obj.approach
    h1 = a1 + obj.hold
    return ObjectTruth(
        id=oid, center=obj.center, polarity=obj.polarity,
        approach=_interval(a0, obj.approach, n), hold=_interval(a1, obj.hold, n),
        recede=_interval(h1, obj.recede, n), sizes=tuple(float(s) for s in sides),
        contact_frame=contact,
        extra={"half_size": float(obj.half_size), "speed": float(obj.speed)} if obj.looming == "physical" else {})


def four_phase(*, background: Any = "procedural", seed: int = 0, fps: float = 30.0, scroll: float = 1.0,
               polarity: str = "dark", approach: int = 40, hold: int = 20, recede: int = 40) -> Stimulus:
    """The four-phase stimulus of Fig. 4 (Sec. IV-B).

    320x240, 400 frames: phase ``k`` (frames ``100 k`` .. ``100 k + 99``) shows
    a square at (160, 120), then (240, 60), then (80, 180), then two squares
    at (80, 60) and (240, 180) together. Each phase: approach 40 frames
    (side 1 -> 79 px, +2 px/frame), hold 20 frames at 79 px, recede 40 frames
    (79 -> 1 px), as in ``scenes/outdoor_2_black_4_period.avi``. The
    background scrolls left by ``scroll`` px per frame.

    Parameters
    ----------
    background, seed, fps, scroll
        See :func:`scene`. The paper used ``backgrounds/outdoor_2.jpg``.
    polarity : {"dark", "bright"}
        Polarity of every square (the paper: dark).
    approach, hold, recede : int
        Phase lengths in frames; their sum must be at most 100.

    Returns
    -------
    Stimulus
    """
    approach = check_count(approach, "approach", 0)
    hold = check_count(hold, "hold", 0)
    recede = check_count(recede, "recede", 0)
    if approach + hold + recede > 100:
        raise InputValueError(f"approach + hold + recede must be at most 100 frames (one phase), "
                              f"got {approach + hold + recede}")
    check_choice(polarity, "polarity", _POLARITIES)
    objs = [SceneObject(center=c, onset=100 * k, approach=approach, hold=hold, recede=recede,
                        polarity=polarity)
            for k, centers in enumerate(FOUR_PHASE_CENTERS) for c in centers]
    return scene(objs, size=(320, 240), frames=400, fps=fps, background=background, scroll=scroll,
                 seed=seed, name="four_phase")


def six_objects(*, background: Any = "procedural", seed: int = 0, fps: float = 30.0, scroll: float = 1.0,
                polarity: str = "dark") -> Stimulus:
    """The six-object stimulus of Fig. 5 (Sec. IV-B).

    320x240, 120 frames; squares at the centres of
    ``scenes/outdoor_3_black_expand_multi_6.avi`` with onsets 5, 15, 25, 45,
    55, 65: approach 40 frames (side 1 -> 79 px), hold 10 frames at 81 px
    (as in the paper's file), then the square disappears (no recede).

    Parameters
    ----------
    background, seed, fps, scroll
        See :func:`scene`. The paper used ``backgrounds/outdoor_3.jpg``.
    polarity : {"dark", "bright"}
        Polarity of every square (the paper: dark).

    Returns
    -------
    Stimulus
    """
    check_choice(polarity, "polarity", _POLARITIES)
    objs = [SceneObject(center=c, onset=o, approach=40, hold=10, recede=0, polarity=polarity,
                        peak_side=81.0)
            for c, o in zip(SIX_OBJECT_CENTERS, SIX_OBJECT_ONSETS)]
    return scene(objs, size=(320, 240), frames=120, fps=fps, background=background, scroll=scroll,
                 seed=seed, name="six_objects")


def looming(*, size: tuple[int, int] = (320, 240), center: tuple[float, float] | None = None,
            half_size: float = 0.5, speed: float = 5.0, contact_time: float = 2.0,
            duration: float | None = None, fps: float = 30.0, polarity: str = "dark",
            background: Any = "plain", scroll: float = 0.0, seed: int = 0,
            hfov_deg: float = 60.0) -> Stimulus:
    """A single physically correct constant-speed approach (time-to-collision tests).

    A square of half-size ``l = half_size`` m moves straight at the eye at
    ``v = speed`` m/s and would touch it at ``t_c = contact_time`` s. At time
    ``t = frame / fps`` its angular half-size is
    ``theta = atan(l / (v (t_c - t)))`` and its side on the image is
    ``2 f tan(theta)`` px with ``f = (W / 2) / tan(hfov / 2)``. The approach
    ends before the first frame whose side would exceed ``max(W, H)``; after
    it (if ``duration`` asks for more frames) the object is gone. The truth
    records ``contact_frame = contact_time * fps``.

    Parameters
    ----------
    size : tuple of int
        ``(W, H)`` in pixels.
    center : tuple of float or None
        ``(x, y)`` of the expansion centre; ``None`` = frame centre.
    half_size, speed, contact_time : float
        ``l`` (m), ``v`` (m/s), ``t_c`` (s); all > 0.
    duration : float or None
        Length of the video in seconds; ``None`` = until the approach ends.
    fps : float
        Frame rate.
    polarity : {"dark", "bright"}
        Dark (0) or bright (255) square.
    background : "plain", "procedural", float, path or numpy.ndarray
        See :func:`scene` ("plain" = 250 for dark, 0 for bright).
    scroll : float
        Background scroll in px per frame (default static).
    seed : int
        Seed of the procedural background.
    hfov_deg : float
        Horizontal field of view in degrees.

    Returns
    -------
    Stimulus
    """
    w, h = check_size(size)
    fps = check_fps(fps)
    half_size = check_number(half_size, "half_size", positive=True)
    speed = check_number(speed, "speed", positive=True)
    contact_time = check_number(contact_time, "contact_time", positive=True)
    check_choice(polarity, "polarity", _POLARITIES)
    focal = focal_length(w, check_hfov(hfov_deg, required=True))
    if center is None:
        center = (w / 2.0, h / 2.0)
    contact = contact_time * fps
    n_before = int(math.ceil(contact))                   # frames with t < t_c
    sides = _physical_sides(np.arange(n_before, dtype=np.float64), contact, fps, half_size, speed, focal)
    n_approach = int(np.count_nonzero(sides <= max(w, h)))
    if n_approach == 0:
        raise InputValueError(f"the object already exceeds the frame at frame 0 (side {sides[0]:.0f} px > {max(w, h)} px); "
                              f"use a smaller half_size or a larger speed * contact_time")
    if duration is None:
        n = n_approach
    else:
        duration = check_number(duration, "duration", positive=True)
        n = int(round(duration * fps))
        if n < 1:
            raise InputValueError(f"duration {duration} s is shorter than one frame at {fps} fps")
    obj = SceneObject(center=center, onset=0, approach=min(n_approach, n), hold=0, recede=0,
                      polarity=polarity, looming="physical", half_size=half_size, speed=speed,
                      contact_frame=contact)
    return scene([obj], size=(w, h), frames=n, fps=fps, background=background, scroll=scroll, seed=seed,
                 hfov_deg=hfov_deg, name="looming")
