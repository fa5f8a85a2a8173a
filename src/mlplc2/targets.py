"""Actionable targets: time to collision, expansion rate and bearing per attention field.

Every attention field gets, each frame, an estimate of

* the **time to collision** ``ttc_s`` (seconds), from the optical expansion of
  the edges around the field centre: ``tau = s / (ds/dt)`` where ``s`` is the
  size of the expanding object on the image plane;
* the **expansion rate** ``expansion_rate``: d(theta)/dt of the object's
  angular size theta (full width), in degrees per second when the camera's
  horizontal field of view is known, else d(s)/dt in pixels per second;
* the **bearing** ``azimuth_deg`` / ``elevation_deg`` of the expansion centre
  (degrees from the optical axis given the field of view, else pixel offsets
  from the image centre).

The four are reported together or not at all: all None until a confirmed fit
gives a time to collision (the field's own centre, ``Field.x`` / ``Field.y``, is
always there, but it is where the field was born, often a corner of the object).

Method (see ``docs/targets.md`` for the measurements behind every choice)
-------------------------------------------------------------------------
1. *Edges* (:func:`measure_extent`). From the field centre, four strips of
   ``2 band + 1`` px run along the field's row and column to the frame border.
   In each, the outward component of the lobula-plate local motion (LM_r to the
   right, LM_l to the left, LM_u upwards, LM_d downwards; positive part) gives a
   1-D profile. The *nearest outward edge complex* (lobes closer than ``gap`` px
   merged) is located and its **outer boundary** (where the profile falls below
   ``rel_edge`` x its peak, sub-pixel) is taken. The local-motion lobes trail the
   true edge by a nearly constant ``edge_offset`` px (6-7 px for edge speeds
   0.5-8 px/frame with the default front end), which is added back. The object's
   width is ``d_right + d_left`` and its height ``d_up + d_down``: both are
   independent of where the field centre lies inside the object, and the
   midpoints give the expansion centre. ``s`` = mean of width and height.
2. *Filter* (:class:`TargetTracker`). The last ``window`` valid sizes
   (frames at most ``max_age`` old) are fitted by least squares with
   ``1 / s = a + b t``: for an object approaching at constant speed the image
   size is ``s = f L / Z`` with ``Z`` linear in time, so ``1/s`` is exactly
   linear and its zero crossing ``t_c = -a / b`` is the contact frame.
   ``ttc_s = (t_c - lag - t) / fps``. A fit needs ``min_points`` sizes spanning
   at least ``min_span`` frames, a negative slope (growth), a small residual and
   an implied edge speed the front end can follow; it is robust (the largest
   subset of >= ``min_inliers`` of the sizes that passes wins, outliers are
   forgotten; every subset keeps the newest size, so a fit never outlives the
   data that contradict it) and reported only once two successive fits agree on
   ``t_c`` (``confirm_frames`` / ``confirm_rel``). After a field has measured
   once, its strips start from the estimated expansion centre; a new field
   inside an object already tracked continues that track, and the fields of one
   object share the frame's measurement and fit (``cache`` of
   :meth:`TargetTracker.update`).
3. *Saturation / coasting.* When the edges move faster than ``max_edge_speed``
   px/frame (as predicted by a confirmed fit) the correlators alias and the lobes fall far behind the edge; when an
   edge leaves the frame it cannot be located. Such frames add no measurement
   and the estimate *coasts* on the last fit (``t_c`` unchanged, so ``ttc_s``
   keeps counting down) for at most ``coast_frames`` frames, then becomes None.

Because ``s = f tan(theta)`` (image-plane size), ``s / (ds/dt)`` is the exact
time to collision of a fronto-parallel object approaching at constant speed, at
any angle and anywhere in the image; the classic ``theta / (dtheta/dt)`` is its
small-angle approximation. No field of view is needed for ``ttc_s``.

Bearing convention: azimuth positive to the right, elevation positive up,
``azimuth = atan((x - cx) / f)``, ``elevation = atan((cy - y) / f)`` with
``(cx, cy) = ((W - 1) / 2, (H - 1) / 2)`` in pixel-index coordinates (the centre
of pixel column ``i`` is at ``x = i``) and ``f = (W / 2) / tan(hfov / 2)``.
Without a field of view the same two attributes hold ``x - cx`` and ``cy - y``
in pixels.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ._validation import InputValueError, Valid, check_fields, check_real
from .lobula_plate import LocalMotion
from .params import document_parameters, param

__all__ = ["TargetParams", "Extent", "TargetEstimate", "TargetTracker", "measure_extent", "edge_distance",
           "fit_contact", "bearing", "focal_length", "rank_by_ttc"]

_FAST = None    # the module mlplc2._fast_targets once imported, False without Numba (tests set False)
_FLOATS = (np.dtype(np.float32), np.dtype(np.float64))
#: Largest ``TargetParams.window``: the robust fit tries every subset of the window's sizes
#: that keeps the newest one, up to 2 ** (window - 1) of them (32768 at 16; 16 at the default 6).
WINDOW_MAX = 16


def _fast_targets():
    """The Numba kernels (:mod:`mlplc2._fast_targets`), imported on first use; None without Numba.

    They compute what the NumPy code below computes (which stays the fallback and the oracle
    of ``tests/test_targets.py``), bit for bit: the edge distances of :func:`measure_extent`
    and the subset search of :meth:`TargetTracker._robust_fit`.
    """
    global _FAST
    if _FAST is None:
        try:
            from . import _fast_targets as mod
        except Exception:  # noqa: BLE001 - ImportError, or numba failing to initialise
            mod = False
        _FAST = mod
    return _FAST or None


@document_parameters("Parameters")
@dataclass(frozen=True)
class TargetParams:
    """Parameters of the target estimators (defaults measured on ``stimuli.looming``).

    Valid values (the table below; checked at construction; one-line
    :class:`mlplc2.InputError` otherwise, a ``ValueError`` or ``TypeError``):
    integers are Python or NumPy integers (not bools) up to 2**31 - 1, stored as
    Python ints, with ``min_points <= window`` (``WINDOW_MAX`` = 16: the robust fit
    tries up to ``2 ** (window - 1)`` subsets); numbers are finite Python or NumPy
    scalars (not bools, strings or arrays) within float32's range, stored as Python
    floats.
    """

    band: int = param(2, "Half-width of the strips along the field's row and column.", unit="px",
                      valid=Valid.integer(0))
    min_peak: float = param(0.08, "Smallest outward LM (profile mean, after the gain) that counts as an edge.",
                            valid=Valid.real(minimum=0))
    noise_k: float = param(3.0, """An edge complex must exceed ``noise_k`` x the 75th percentile of its
                           profile (noise floor).""", valid=Valid.real(minimum=0))
    rel_start: float = param(0.3, """An edge complex must reach ``rel_start`` x the largest value within
                             ``local`` px of its start.""", valid=Valid.real(minimum=0, maximum=1))
    local: int = param(20, "How far beyond the start of a complex a stronger edge is searched for (see ``rel_start``).",
                       unit="px", valid=Valid.integer(0))
    rel_edge: float = param(0.25, "Outer boundary of the edge complex: where it falls below ``rel_edge`` x its peak.",
                            valid=Valid.real(minimum=0, maximum=1))
    gap: int = param(6, "Lobes closer than this belong to one edge complex (fast edges make 2-3 lobes).",
                     unit="px", valid=Valid.integer(0))
    edge_offset: float = param(6.5, "How far the outer boundary of the LM lobes trails the true edge (added back).",
                               unit="px", valid=Valid.real(minimum=0))
    window: int = param(6, "Sizes used in the ``1/s`` regression.", unit="sizes",
                        valid=Valid.integer(2, WINDOW_MAX, also=">= min_points"))
    max_age: int = param(10, "Sizes older than this are dropped.", unit="frames", valid=Valid.integer(0))
    min_points: int = param(4, "Fewest sizes for a fit.", unit="sizes",
                            valid=Valid.integer(2, WINDOW_MAX, also="<= window"))
    min_span: int = param(3, "Fewest frames between the first and last size of a fit.", unit="frames",
                          valid=Valid.integer(0))
    lag: float = param(0.0, "Frames the measured size lags the true one (subtracted from the contact frame).",
                       unit="frames", valid=Valid.real(minimum=0))
    max_edge_speed: float = param(8.0, """Edge speed (per edge) above which the front end aliases:
                                  measurements stop, the fit coasts.""", unit="px/frame",
                                  valid=Valid.real(minimum=0))
    coast_frames: int = param(10, "Frames an estimate may coast on its last fit without a new measurement.",
                              unit="frames", valid=Valid.integer(0))
    max_ttc_s: float = param(60.0, "Longer estimates are reported as None (no measurable approach).",
                             unit="s", valid=Valid.real(minimum=0))
    max_residual: float = param(0.07, """Largest rms relative residual of the ``1/s`` fit that is accepted
                                (0.1 until session 3: fits to sizes that jump, on static or receding objects
                                over a moving background, passed; docs/targets.md, "Where it fails").""",
                                valid=Valid.real(minimum=0))
    confirm_frames: float = param(1.5, """A fit is reported once the next fit's contact frame agrees within
                                  ``max(confirm_frames, confirm_rel x ttc)`` frames (a fit to junk is
                                  unstable): the absolute part.""", unit="frames", valid=Valid.real(minimum=0))
    confirm_rel: float = param(0.15, """The relative part of the agreement ``max(confirm_frames, confirm_rel
                               x ttc)`` that confirms a fit (see ``confirm_frames``).""",
                               valid=Valid.real(minimum=0))
    min_inliers: float = param(0.6, """Outlier rejection may drop at most this complement: a fit keeps
                               >= 60 % of the sizes.""", valid=Valid.real(minimum=0, maximum=1))
    max_shift: float = param(40.0, """While a track has no size yet, a measured expansion centre further
                             than this (in x or y) from the field centre is rejected: it lies outside the
                             field (R_AF = 40), so the edges found are most likely two things taken for one
                             (or background).""", unit="px", valid=Valid.real(minimum=0))
    max_deviation: float = param(0.2, "A size further than this (relative) from the fit's prediction contradicts the fit.",
                                 valid=Valid.real(minimum=0))

    def __post_init__(self) -> None:
        check_fields(self, "TargetParams")
        if self.window < self.min_points:
            raise InputValueError(f"TargetParams.window must be >= min_points ({self.min_points}): a fit needs "
                                  f"min_points of the last window sizes, got {self.window!r}")


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


@dataclass(frozen=True)
class TargetEstimate:
    """The estimates of one field in one frame (None where not estimable).

    ``ttc_s``, ``expansion_rate``, ``azimuth_deg`` and ``elevation_deg`` are all
    set or all None: they need a confirmed fit of the object's growth (and
    ``ttc_s <= max_ttc_s``). ``size_px`` (the fit's size, else this frame's
    measured size, else None) and ``center`` (the expansion centre, or the field
    centre while none is known) are diagnostics.

    ``status``: "tracking" (fit updated this frame), "coasting" (no usable
    measurement this frame; the last fit is extrapolated), "no_fit" (not yet
    enough measurements or no growth), "saturated" (edges too fast or out of
    frame and nothing to coast on), "unconfirmed" (a fit not yet confirmed by
    the next one), "passed" (the predicted contact is over).
    """

    ttc_s: float | None = None
    expansion_rate: float | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    size_px: float | None = None
    center: tuple[float, float] | None = None
    status: str = "no_fit"


def focal_length(width: int, hfov_deg: float | None) -> float | None:
    """Pinhole focal length in px, ``(W / 2) / tan(hfov / 2)``; None without a field of view."""
    if hfov_deg is None:
        return None
    return (width / 2.0) / math.tan(math.radians(float(hfov_deg)) / 2.0)


def check_hfov(hfov_deg) -> float | None:
    """Validate a horizontal field of view in degrees (None allowed)."""
    if hfov_deg is None:
        return None
    return check_real(hfov_deg, "hfov_deg", positive=True, below=180)


def bearing(x: float, y: float, shape: tuple[int, int], focal: float | None) -> tuple[float, float]:
    """(azimuth, elevation) of pixel (x, y): degrees given ``focal`` (px), else px offsets.

    Azimuth positive right, elevation positive up; the optical axis passes
    through ((W - 1) / 2, (H - 1) / 2).
    """
    h, w = shape
    dx = x - (w - 1) / 2.0
    dy = (h - 1) / 2.0 - y
    if focal is None:
        return float(dx), float(dy)
    return math.degrees(math.atan2(dx, focal)), math.degrees(math.atan2(dy, focal))


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


def measure_extent(lm: LocalMotion, x: int, y: int, params: TargetParams = TargetParams()) -> Extent:
    """Width, height and centre of the outward-expanding edges around (x, y).

    Cost: four strips of ``2 band + 1`` px from the centre to the frame border, summed,
    sorted and thresholded together; then a short scan (:func:`_edge_distances`). With Numba,
    all of it in one compiled pass (:func:`mlplc2._fast_targets.edges4`, same results).
    """
    h, w = lm.magnitude.shape
    x = int(min(max(x, 0), w - 1))
    y = int(min(max(y, 0), h - 1))
    fast = _FAST if _FAST is not None else _fast_targets()
    r, l, u, d = lm.r, lm.l, lm.u, lm.d  # noqa: E741
    if fast and params.rel_edge <= 1.0 and r.dtype in _FLOATS and r.dtype == l.dtype == u.dtype == d.dtype \
            and r.shape == l.shape == u.shape == d.shape == (h, w):
        dist = fast.edges4(r, l, u, d, x, y, int(params.band), float(params.min_peak), float(params.noise_k),
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


def _line_fit(frames, sizes):
    """Least squares ``1/s = a + b t``: (a, b, relative residuals) or None if degenerate."""
    t = np.asarray(frames, dtype=np.float64)
    s = np.asarray(sizes, dtype=np.float64)
    if t.size < 2 or np.ptp(t) == 0 or np.any(s <= 0):
        return None
    yv = 1.0 / s
    tm = t.mean()
    dt = t - tm
    b = float(np.dot(dt, yv - yv.mean()) / np.dot(dt, dt))
    a = float(yv.mean() - b * tm)
    return a, b, (yv - (a + b * t)) / yv


def fit_contact(frames, sizes) -> tuple[float, float, float] | None:
    """Least-squares ``1/s = a + b t``; returns (contact_frame, slope b, rms relative residual).

    For a constant-speed approach ``1/s`` is linear in time and vanishes at
    contact, so the contact frame is ``-a / b``. None when the sizes do not
    grow (b >= 0) or are degenerate.
    """
    res = _line_fit(frames, sizes)
    if res is None or not res[1] < 0:
        return None
    a, b, rel = res
    return -a / b, b, float(np.sqrt(np.mean(rel ** 2)))


@functools.lru_cache(maxsize=64)
def _subsets(n: int, need: int):
    """The subsets of ``n`` sizes a robust fit tries: each keeps the newest one (index ``n - 1``).

    Returns (mask (m, n) of 0/1 floats, subset sizes (m,), index of each subset's first size
    (m,)), largest subsets first, each size in lexicographic order.
    """
    rows = []
    for k in range(n, need - 1, -1):
        for keep in itertools.combinations(range(n - 1), k - 1):
            row = [0.0] * n
            for i in keep:
                row[i] = 1.0
            row[n - 1] = 1.0
            rows.append(row)
    mask = np.array(rows, dtype=np.float64).reshape(len(rows), n)
    sizes, first = mask.sum(axis=1), mask.argmax(axis=1)
    for arr in (mask, sizes, first):
        arr.flags.writeable = False     # shared by every tracker (lru_cache)
    return mask, sizes, first


@functools.lru_cache(maxsize=64)
def _subset_keeps(n: int, need: int) -> tuple:
    """The kept indices of each row of ``_subsets(n, need)`` (tuples)."""
    return tuple(tuple(np.flatnonzero(row).tolist()) for row in _subsets(n, need)[0])


def _median(values) -> float:
    v = sorted(values)
    m = len(v) // 2
    return float(v[m]) if len(v) % 2 else (v[m - 1] + v[m]) / 2.0


@dataclass
class TargetTracker:
    """Per-field state of the estimators: recent sizes and the last fit."""

    params: TargetParams = field(default_factory=TargetParams)
    history: deque = field(default_factory=deque)   # (frame, size, cx, cy)
    contact: float | None = None     # estimated contact frame of the last fit
    slope: float | None = None       # d(1/s)/dt of the last fit (1/px per frame)
    fit_frame: int | None = None     # frame of the last fit
    center: tuple[float, float] | None = None
    misses: int = 0                  # consecutive measurements that contradict the fit
    confirmed: bool = False          # the fit agrees with the previous one (estimates reported)
    last: tuple | None = None        # (frame, TargetEstimate) of the last update

    def reset(self) -> None:
        self.history.clear()
        self.contact = self.slope = self.fit_frame = None
        self.center = None
        self.misses = 0
        self.confirmed = False
        self.last = None

    def _robust_fit(self, frame: int):
        """The accepted robust fit of the history: (contact frame, slope, kept indices) or None.

        Every subset that keeps the newest size and drops at most ``1 - min_inliers`` of the
        sizes is fitted at once (one small matrix product: at most 16 subsets of <= 6
        sizes); the accepted fit keeps the most sizes, then has the smallest residual.
        The newest size must be kept: a fit that disowns the current measurement is not a
        new fit, and "confirming" an old fit on the same old sizes is no confirmation.
        """
        p = self.params
        pts = self.history
        n = len(pts)
        need = max(p.min_points, math.ceil(p.min_inliers * n))
        if n < need or n < 2:
            return None
        t_new = pts[-1][0]
        tl = [q[0] - t_new for q in pts]                     # <= 0, newest at 0
        if min(q[1] for q in pts) <= 0:
            return None
        yl = [1.0 / q[1] for q in pts]
        # The full set first, in plain floats: when it passes (steady tracking) it is the
        # answer (the largest subset), and the subset search below is not needed.
        if -tl[0] >= p.min_span:
            st, sy = sum(tl), sum(yl)
            stt = sum(v * v for v in tl)
            sty = sum(u * v for u, v in zip(tl, yl))
            den = n * stt - st * st
            if den > 0:
                b = (n * sty - st * sy) / den
                a = (sy - b * st) / n
                if b < 0 < a and -b / (a * a) / 2.0 <= p.max_edge_speed:
                    ss = sum(((v - a - b * u) / v) ** 2 for u, v in zip(tl, yl))
                    if math.sqrt(ss / n) <= p.max_residual:
                        return t_new - a / b, b, tuple(range(n))
        if need >= n:
            return None
        fast = _FAST if _FAST is not None else _fast_targets()
        if fast:
            # The same search compiled (mlplc2._fast_targets.subset_fit), one subset at a time;
            # the two sums that are not exact in any order still come from NumPy (BLAS), so
            # the fits are bit-identical.
            t = np.array(tl, dtype=np.float64)
            yv = np.array(yl)
            mask, _, first = _subsets(n, need)
            j, a, b = fast.subset_fit(t, yv, mask, first, mask @ yv, mask @ (t * yv), float(p.min_span),
                                      float(p.max_edge_speed), float(p.max_residual))
            if j < 0:
                return None
            return t_new - a / b, b, _subset_keeps(n, need)[j]
        t = np.array(tl)
        yv = np.array(yl)
        mask, k, first = _subsets(n, need)
        st, sy = mask @ t, mask @ yv
        stt, sty = mask @ (t * t), mask @ (t * yv)
        with np.errstate(divide="ignore", invalid="ignore"):
            den = k * stt - st * st
            b = (k * sty - st * sy) / den
            a = (sy - b * st) / k                    # 1/s at the newest frame
            rel = (yv - a[:, None] - b[:, None] * t) / yv
            rel2 = mask * (rel * rel)
            rms = np.sqrt(rel2.sum(axis=1) / k)
            speed = -b / (a * a) / 2.0               # px/frame per edge at the newest frame
            # Accept: growing, contact ahead, small residual, and edges no faster than the
            # front end can follow (a fit claiming faster edges was fitted to something else).
            ok = ((-t[first] >= p.min_span) & (den > 0) & (b < 0) & (a > 0)
                  & (rms <= p.max_residual) & (speed <= p.max_edge_speed))
        idx = np.flatnonzero(ok)
        if idx.size == 0:
            return None
        best = idx[k[idx] == k[idx[0]]]
        j = int(best[np.argmin(rms[best])])
        return t_new - float(a[j]) / float(b[j]), float(b[j]), tuple(np.flatnonzero(mask[j]).tolist())

    def _refit(self, frame: int, cache: dict | None = None) -> bool:
        """Fit the history robustly (:meth:`_robust_fit`); True if a fit was accepted.

        The sizes the accepted fit leaves out (outliers, e.g. a field born on the
        object's edge first measures the wrong thing) are forgotten.
        """
        p = self.params
        if cache is not None:
            key = ("fit", frame, tuple((q[0], q[1]) for q in self.history))
            res = cache.get(key, _MISSING)
            if res is _MISSING:
                res = cache[key] = self._robust_fit(frame)
        else:
            res = self._robust_fit(frame)
        if res is None:
            return False
        contact, b, keep = res
        # Confirmed when two successive fits agree on the contact frame.
        tol = max(p.confirm_frames, p.confirm_rel * (contact - frame))
        if self.contact is not None and abs(contact - self.contact) <= tol:
            self.confirmed = True
        elif not (self.confirmed and self.contact is not None and abs(contact - self.contact) <= 2 * tol):
            self.confirmed = False
        self.contact, self.slope, self.fit_frame = contact, b, frame
        if len(keep) < len(self.history):
            pts = self.history
            self.history = deque(pts[i] for i in keep)
        return True

    def _predicted_size(self, frame: float) -> float | None:
        if self.contact is None or self.slope is None:
            return None
        y = -self.slope * (self.contact - frame)   # 1/s at frame (measurement time base)
        return 1.0 / y if y > 0 else math.inf

    def covers(self, x: float, y: float, frame: int) -> bool:
        """Whether (x, y) lies inside the object this tracker measured within ``max_age`` frames."""
        if not self.history or self.center is None or frame - self.history[-1][0] > self.params.max_age:
            return False
        size = self.history[-1][1]
        pred = self._predicted_size(frame)
        if pred is not None and math.isfinite(pred) and self.fit_frame is not None \
                and frame - self.fit_frame <= self.params.coast_frames:
            size = max(size, pred)
        half = size / 2.0
        return abs(x - self.center[0]) <= half and abs(y - self.center[1]) <= half

    def adopt(self, other: "TargetTracker") -> None:
        """Start from another tracker's measurements (a new field inside an object already tracked)."""
        self.history = deque(other.history)
        self.contact, self.slope, self.fit_frame = other.contact, other.slope, other.fit_frame
        self.center = other.center
        self.confirmed = other.confirmed
        self.misses = other.misses
        self.last = other.last

    def update(self, lm: LocalMotion, x: int, y: int, frame: int, fps: float,
               focal: float | None = None, cache: dict | None = None) -> TargetEstimate:
        """Measure around field centre (x, y) in this frame's maps and return the estimates.

        Once an expansion centre is known the strips start from it instead of
        the field centre (the field centre is where the edge was when the field
        was born, often a corner of the object).

        ``cache``: an optional dict shared by the trackers of *one* frame (same ``lm``,
        ``frame`` and ``params``; start a new one every frame). Trackers measuring from the
        same point or fitting the same sizes (fields on one object) then do that work once.
        """
        if self.last is not None and self.last[0] == frame:
            # Adopted from a tracker that has already measured this frame: same track, same
            # estimate (measuring again would count this frame's size twice).
            return self.last[1]
        p = self.params
        h, w = lm.magnitude.shape
        if self.center is not None and self.history:
            mx, my = int(round(self.center[0])), int(round(self.center[1]))
            if not (0 <= mx < w and 0 <= my < h):
                mx, my = x, y
        else:
            mx, my = x, y
        if cache is not None:
            key = ("extent", mx, my)
            ext = cache.get(key)
            if ext is None:
                ext = cache[key] = measure_extent(lm, mx, my, p)
        else:
            ext = measure_extent(lm, mx, my, p)
        size = ext.size
        cx, cy = ext.cx, ext.cy
        if size is not None and not self.history and max(abs(cx - mx), abs(cy - my)) > p.max_shift:
            # A new track's first edges enclose a point far from the field centre they were
            # sought from: two objects (or an object and background) taken for one.
            size = None
        if size is None and self.center is not None and self.history:
            # Edges beyond the frame border (object partly out of view): half-sizes of the
            # edges still found, measured from the known expansion centre (at least two).
            c = self.center
            e = ext.edges
            halves = [v for v in (None if e[0] is None else e[0] - c[0], None if e[1] is None else c[0] - e[1],
                                  None if e[2] is None else c[1] - e[2], None if e[3] is None else e[3] - c[1])
                      if v is not None]
            if len(halves) >= 2 and min(halves) > 0:
                size = 2.0 * sum(halves) / len(halves)
                cx, cy = c
        while self.history and frame - self.history[0][0] > p.max_age:
            self.history.popleft()
        status = "no_fit"
        if size is not None and self.contact is not None:
            s_pred = self._predicted_size(frame)
            if self.confirmed and s_pred is not None and math.isfinite(s_pred) \
                    and -self.slope * s_pred * s_pred / 2.0 > p.max_edge_speed:
                # Aliasing: edges faster than max_edge_speed px/frame leave lobes far behind
                # the edge. Such sizes are neither fitted nor held against a confirmed fit;
                # the estimate coasts. (An unconfirmed fit vetoes nothing: a fit to junk
                # predicting fast edges would otherwise block every correction.)
                size = None
                status = "saturated"
            elif s_pred is None or not math.isfinite(s_pred) or abs(size - s_pred) > p.max_deviation * s_pred:
                # A size the fit does not predict; two in a row and the fit is dropped.
                self.misses += 1
                if self.misses >= 2:
                    self.contact = self.slope = self.fit_frame = None
                    self.misses = 0
                    self.confirmed = False
            else:
                self.misses = 0
        if size is not None:
            self.history.append((frame, size, cx, cy))
            while len(self.history) > p.window:
                self.history.popleft()
            # Fit, rejecting outliers (e.g. a field born on the object's edge first measures
            # the wrong thing).
            if self._refit(frame, cache):
                status = "tracking"
                self.misses = 0
            self.center = (_median([q[2] for q in self.history]), _median([q[3] for q in self.history]))
        est_center = self.center if self.center is not None and self.history else (float(x), float(y))
        ttc = rate = s_now = az = el = None
        if self.contact is not None and frame - self.fit_frame > p.coast_frames:
            self.contact = self.slope = self.fit_frame = None
            self.confirmed = False
        if self.contact is not None and self.contact - p.lag - frame <= 0:
            status = "passed"              # the predicted contact is over: no estimate
        elif self.contact is not None and not self.confirmed:
            status = "unconfirmed"
        elif self.contact is not None:
            if status == "no_fit":
                status = "coasting"
            ttc_frames = self.contact - p.lag - frame
            ttc = ttc_frames / fps
            y_now = -self.slope * ttc_frames
            s_now = 1.0 / y_now
            if ttc > p.max_ttc_s:
                ttc = None                 # no measurable approach: no rate and no bearing either
            else:
                ds = -self.slope / (y_now * y_now) * fps          # px per second
                if focal is None:
                    rate = ds
                else:
                    half = s_now / (2.0 * focal)
                    rate = math.degrees(ds / focal / (1.0 + half * half))
                # The bearing of the expansion centre, reported with the time to collision only:
                # before a confirmed fit the centre may rest on junk first sizes, and before any
                # size the only point known is the field centre, often a corner of the object
                # (docs/targets.md, "Bearing").
                c = self.center if self.center is not None else est_center
                az, el = bearing(c[0], c[1], (h, w), focal)
        est = TargetEstimate(ttc_s=ttc, expansion_rate=rate, azimuth_deg=az, elevation_deg=el,
                             size_px=s_now if s_now is not None else size, center=est_center, status=status)
        self.last = (frame, est)
        return est


_MISSING = object()


def rank_by_ttc(items, key=lambda f: f.ttc_s):
    """``items`` ordered by time to collision (smallest first); those without one keep their order, last."""
    with_ttc = sorted((i for i in items if key(i) is not None), key=key)
    return with_ttc + [i for i in items if key(i) is None]
