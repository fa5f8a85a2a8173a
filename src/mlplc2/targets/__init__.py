"""Targets: one per approaching object, with its time to contact, course and a collision warning.

The attention fields of the LPLC2 family (:mod:`mlplc2.neuropils.attention`, Eq. 13-16) say *where* the
local motion looms. A :class:`TargetLayer` turns them into what a robot acts on: one
:class:`Target` per object, with a stable id, its apparent size, the time to contact
``ttc_s``, the predicted ``miss`` distance at contact and a ``warning``. Nothing here changes
the fields: the paper's model is untouched. ``docs/targets.md`` gives the method step by step
and the measurements behind every choice, ``docs/benchmark.md`` the figures.

Per frame (:meth:`TargetLayer.step`): candidates from the attention fields and from the
strongest local motion or grey-level change outside every target; their box (:func:`change_box`,
else the edges of the outward local motion, :func:`measure_extent`); their growth d(log size)/dt,
measured in the image by aligning the object's patch between frames (:func:`align`); the time to
contact from the line through ``1 / S`` (:func:`fit_contact`); the lateral ``miss`` at contact
from the course (:func:`fit_course`); and the warning rule (:func:`estimate`,
:class:`TargetParams`). The paper's field alarm (``Field.collision``, the "fatal" field) is a
separate signal and stays as it is.

Bearings follow the convention of :mod:`mlplc2.camera`.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from .._validation import InputValueError, Valid, check_fields, check_real
from ..camera import bearing, check_hfov, focal_length
from ..neuropils.lobula_plate import LocalMotion
from ..params import ParameterSet, document_parameters, param

__all__ = ["TargetParams", "Target", "TargetLayer", "Track", "Extent", "Alignment", "measure_extent", "edge_distance",
           "align", "change_box", "pyramid", "fit_contact", "fit_course", "estimate", "count_down", "bearing", "focal_length",
           "check_hfov"]

_FLOATS = (np.dtype(np.float32), np.dtype(np.float64))


@document_parameters("Parameters")
@dataclass(frozen=True)
class TargetParams(ParameterSet):
    """Parameters of the target layer: candidates, the image measurement, time to contact,
    course and the warning (one set for every input; ``docs/targets.md``).

    Valid values (the table below; checked at construction; one-line
    :class:`mlplc2.InputError` otherwise, a ``ValueError`` or ``TypeError``):
    integers are Python or NumPy integers (not bools), stored as Python ints;
    numbers are finite Python or NumPy scalars (not bools, strings or arrays) within
    float32's range, stored as Python floats; ``heading`` is None or two numbers.
    """

    # --- candidates and their box ---------------------------------------------------------
    band: int = param(2, "Half-width of the strips along a seed's row and column (:func:`measure_extent`).",
                      unit="px", valid=Valid.integer(0))
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
    max_shift: float = param(40.0, """A candidate box whose centre lies further than this (in x or y) from
                             its seed point is dropped: it encloses two things, or background (40 = R_AF).""",
                             unit="px", valid=Valid.real(minimum=0))
    claim: float = param(12.0, """Margin around a target's box that belongs to it: no new candidate is
                         sought there (the front end's local motion spreads about r_Di = 11 px beyond a
                         moving edge).""", unit="px", valid=Valid.real(minimum=0))
    seed_lm: float = param(0.5, """Local motion (LM, Eq. 12) above which the strongest point outside every
                           target and attention field also seeds a candidate (one per frame), far below
                           the field threshold T_a = 10: a far object grows by a fraction of a pixel per
                           frame. 0 = attention fields only.""", valid=Valid.real(minimum=0))
    seed_contrast: float = param(20.0, """... and above this many times the frame's mean LM (a salient
                                 point, not a moving background).""", valid=Valid.real(minimum=0))
    seed_change: float = param(6.0, """When no local motion stands out, the largest grey-level change over
                               the last ``change_frames`` frames outside every target and field seeds a
                               candidate (:meth:`TargetLayer._change_seed`) when it is at least this
                               much and ``seed_contrast`` times the frame's mean change. 0 = off.""",
                               unit="grey levels", valid=Valid.real(minimum=0))
    change_frames: int = param(4, """A faint candidate's box is the region that changed over this many
                               frames (:func:`change_box`): a slow edge moves a fraction of a pixel per
                               frame.""", unit="frames", valid=Valid.integer(1))
    min_growth: float = param(0.005, """A candidate becomes a target only when its box grew by at least this
                              much (log of the scale) over the last ``change_frames`` frames, alike in
                              both directions (``max_anisotropy``): a patch of background that slides
                              with a turning camera, a receding or a static object does not grow. 0.005
                              over 4 frames is a time to contact of 27 s at 30 fps. 0 = no test.""",
                              valid=Valid.real(minimum=0))
    max_targets: int = param(12, "Upper bound on simultaneous targets (no new candidate while this many exist).",
                             unit="targets", valid=Valid.integer(0))
    # --- the image measurement ------------------------------------------------------------
    patch: int = param(32, "Side of the resampled patch the alignment works on (:func:`align`).",
                       unit="samples", valid=Valid.integer(8, 256))
    margin: float = param(1.5, "Patch half-side = ``margin`` x half the box's larger side + 3 px.",
                          valid=Valid.real(minimum=1))
    iterations: int = param(10, "Most Gauss-Newton iterations per alignment.", valid=Valid.integer(1))
    max_residual: float = param(25.0, "Largest rms residual of an accepted alignment (0-255 scale).",
                                unit="grey levels", valid=Valid.real(minimum=0))
    max_fails: int = param(3, "Consecutive failed alignments after which a target is dropped.",
                           unit="frames", valid=Valid.integer(1))
    # --- time to contact and course -------------------------------------------------------
    window: int = param(12, "Frames of the ``1 / S`` line fit (:func:`fit_contact`) and of the course.",
                        unit="frames", valid=Valid.integer(3, 1000, also=">= min_frames"))
    min_frames: int = param(5, "Fewest frames a fit needs.", unit="frames",
                            valid=Valid.integer(3, 1000, also="<= window"))
    min_tstat: float = param(3.0, "The growth (the fit's slope) must be this many standard errors from 0.",
                             valid=Valid.real(minimum=0))
    max_ttc_s: float = param(10.0, "Longer times to contact are reported as None (no measurable approach).",
                             unit="s", valid=Valid.real(minimum=0))
    heading: tuple[float, float] | None = param(None, """Heading point (x, y) in the model's frames; None =
                                                the principal point ((W - 1) / 2, (H - 1) / 2): the camera
                                                moves along its optical axis, or stands still.""",
                                                unit="px", valid=Valid.point())
    max_anisotropy: float = param(0.35, """Largest difference of the vertical and horizontal growth
                                  (log ky - log kx over the fit's frames) relative to the growth of a
                                  looming target: a fronto-parallel object grows alike in both directions
                                  (0), the ground ahead of a moving camera twice as fast vertically
                                  (0.67), a wall beside its path the other way round (-0.67).""",
                                  valid=Valid.real(minimum=0))
    # --- the warning ------------------------------------------------------------------------
    horizon_s: float = param(1.0, "A target warns only when its ``ttc_s`` is at most this ...", unit="s",
                             valid=Valid.real(minimum=0))
    max_miss: float = param(1.0, "... its predicted miss at contact at most this ...", unit="object widths",
                            valid=Valid.real(minimum=0))
    max_ttc_sigma: float = param(0.3, "... its contact time known to this fraction (standard error / ttc) ...",
                                 valid=Valid.real(minimum=0))
    evidence_frames: int = param(15, """... and it shows looming evidence: one of its attention fields
                                 answered within this many frames ...""", unit="frames", valid=Valid.integer(0))
    confirm_frames: int = param(6, "... or its growth has been significant for this many frames in a row.",
                                unit="frames", valid=Valid.integer(0))
    idle_frames: int = param(30, "Frames without an estimate or an answering field after which a target is dropped.",
                             unit="frames", valid=Valid.integer(0))

    def __post_init__(self) -> None:
        check_fields(self, "TargetParams")
        if self.min_frames > self.window:
            raise InputValueError(f"TargetParams.min_frames must be <= window ({self.window}), "
                                  f"got {self.min_frames!r}")


@dataclass(frozen=True)
class Target:
    """One approaching object in one frame (what models return in ``Output.targets``).

    Attributes
    ----------
    id : int
        Stable id (1, 2, ...), kept while the object is tracked.
    x, y : float
        Centre of the object's box (its expansion centre), in the pixels of the model's frames.
    width, height : float
        Apparent size (px).
    ttc_s : float or None
        Time to contact in seconds; None while the growth is not significant.
    miss : float or None
        Predicted lateral miss distance at contact, in object widths (0 = dead centre); None
        without ``ttc_s``.
    warning : bool
        On a collision course (``miss <= max_miss``) with ``ttc_s <= horizon_s``, contact time
        known, and looming evidence (see :class:`TargetParams`).
    fields : tuple of int
        Ids of the attention fields inside the target.
    born : int
        Frame of the target's creation.
    looming : bool
        Looming evidence this frame (an answering field recently, or sustained growth).
    expansion : float or None
        Measured growth rate d(log size)/dt in 1/s (None before two frames).
    ttc_sigma_s : float or None
        Standard error of ``ttc_s`` (s).
    azimuth_deg, elevation_deg : float or None
        Bearing of the centre in degrees (azimuth positive right, elevation positive up)
        when the model was given the camera's field of view; None otherwise.
    miss_xy : (float, float) or None
        Where the object's centre passes the camera plane, from the heading point, in object
        widths (right, down): ``miss`` is its length.
    """

    id: int
    x: float
    y: float
    width: float
    height: float
    ttc_s: float | None = None
    miss: float | None = None
    warning: bool = False
    fields: tuple[int, ...] = ()
    born: int = 0
    looming: bool = False
    expansion: float | None = None
    ttc_sigma_s: float | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    miss_xy: tuple[float, float] | None = None

    def urgency(self) -> tuple:
        """Sort key, most urgent first: warnings, then the shortest ``ttc_s``, then the larger."""
        return (not self.warning, math.inf if self.ttc_s is None else self.ttc_s,
                -(self.width * self.height), self.id)


# ---------------------------------------------------------------------------
# the box of a candidate: the edges of the outward local motion around a point
# ---------------------------------------------------------------------------
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

    ``kernel``: the compiled version of the four scans (:func:`mlplc2.targets._fast.edges4`,
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


# ---------------------------------------------------------------------------
# the image measurement: scale and shift of a patch between two frames
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Alignment:
    """Scales and shift of a patch from the previous frame to this one (:func:`align`).

    ``kx``, ``ky``: the horizontal and vertical scale (size now / size before); ``dx``, ``dy``:
    shift (px) of the patch centre; ``residual``: rms grey-level difference left (weighted);
    ``sigma``: standard error of ``log scale`` from the Gauss-Newton normal equations.
    """

    kx: float
    ky: float
    dx: float
    dy: float
    residual: float
    sigma: float

    @property
    def scale(self) -> float:
        """The mean scale ``sqrt(kx ky)`` (an approaching object: its growth)."""
        return math.sqrt(self.kx * self.ky)

    @property
    def anisotropy(self) -> float:
        """``log(ky / kx)``: 0 for a fronto-parallel object; a ground plane grows twice as fast
        vertically as horizontally, a wall beside the path the other way round."""
        return math.log(self.ky / self.kx)


def pyramid(gray: np.ndarray, smallest: int = 16) -> list[np.ndarray]:
    """The frame and its successive halvings (``cv2.pyrDown``) down to ``smallest`` px."""
    levels = [gray]
    while min(levels[-1].shape) >= 2 * smallest:
        levels.append(cv2.pyrDown(levels[-1]))
    return levels


_GRIDS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _grid(n: int):
    """Patch coordinates (u, v) centred on the patch centre, and the index vector (cached)."""
    if n not in _GRIDS:
        u = np.arange(n, dtype=np.float32) - (n - 1) / 2.0
        uu, vv = np.meshgrid(u, u)
        _GRIDS[n] = (uu, vv, np.arange(n, dtype=np.float32))
    return _GRIDS[n]


def _sample(levels, level: int, cx: float, cy: float, step_x: float, step_y: float, n: int):
    """``n`` x ``n`` bilinear samples of pyramid ``level`` around (cx, cy) (level-0 px) every
    ``step_x`` / ``step_y`` level-0 px, and the mask of the samples that fall inside the frame."""
    img = levels[level]
    f = float(1 << level)
    sx, sy = step_x / f, step_y / f
    ox = (cx + 0.5) / f - 0.5 - (n - 1) / 2.0 * sx
    oy = (cy + 0.5) / f - 0.5 - (n - 1) / 2.0 * sy
    m = np.array([[sx, 0.0, ox], [0.0, sy, oy]], np.float32)
    patch = cv2.warpAffine(img, m, (n, n), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                           borderMode=cv2.BORDER_REPLICATE)
    idx = _grid(n)[2]
    h, w = img.shape
    xs, ys = ox + idx * sx, oy + idx * sy
    inside = ((ys >= 0) & (ys <= h - 1))[:, None] & ((xs >= 0) & (xs <= w - 1))[None, :]
    return patch, inside


def align(prev: list[np.ndarray], cur: list[np.ndarray], cx: float, cy: float, half: float,
          box: tuple[float, float], *, n: int = 32, iterations: int = 10, kernel=None) -> Alignment | None:
    """Scales and shift of the patch of half-side ``half`` px around (cx, cy) from ``prev`` to
    ``cur`` (two :func:`pyramid` s), weighted on the object's box (half-width, half-height px).

    Gauss-Newton on ``cur(c + d + K (x - c)) = prev(x)`` with ``K = diag(kx, ky)`` (the four
    parameters log kx, log ky, dx, dy), using the previous patch's gradients
    (forward-additive with a fixed Hessian); ``n`` x ``n`` samples are taken from the pyramid
    level whose pixel is at most 1.5 samples, so the cost does not depend on the object's size;
    samples outside the frame get no weight. None when the patch has too little texture or the
    iteration does not settle.

    ``kernel``: the compiled version (:func:`mlplc2.targets._fast.align_patch`, the same
    alignment to ~1e-12; :mod:`mlplc2.backend` chooses it) for float32 pyramids, or None.
    """
    step = 2.0 * half / n
    level = 0 if step <= 1.5 else min(int(math.ceil(math.log2(step / 1.5))), len(prev) - 1)
    if kernel is not None and prev[level].dtype == cur[level].dtype == np.float32 \
            and prev[level].ndim == cur[level].ndim == 2:
        ok, *out = kernel(prev[level], cur[level], level, float(cx), float(cy), step, float(box[0]),
                          float(box[1]), int(n), int(iterations))
        return Alignment(*out) if ok else None
    uu, vv, _ = _grid(n)
    a, inside = _sample(prev, level, cx, cy, step, step, n)
    a = cv2.GaussianBlur(a, (0, 0), 0.8)
    gx = cv2.Sobel(a, cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    gy = cv2.Sobel(a, cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    # weights: 1 on the box, falling to 0 over a fifth of its half-size beyond it
    hw, hh = max(box[0], 1.0) / step, max(box[1], 1.0) / step
    wgt = (np.clip((1.2 * hw - np.abs(uu)) / (0.2 * hw), 0, 1) * np.clip((1.2 * hh - np.abs(vv)) / (0.2 * hh), 0, 1)
           * inside).astype(np.float32).ravel()
    jac = np.stack([(gx * uu).ravel(), (gy * vv).ravel(), gx.ravel(), gy.ravel()], 1)
    # the normal equations in float64: float32 sums would depend on the BLAS's summation order
    jw = (jac * wgt[:, None]).astype(np.float64)
    hess = jw.T @ jac
    if not np.all(np.isfinite(hess)) or np.linalg.cond(hess) > 1e7:
        return None
    hinv = np.linalg.inv(hess)
    px = py = tx = ty = 0.0
    r = None
    for _ in range(max(iterations, 1)):
        kx, ky = math.exp(px), math.exp(py)
        b, inside_b = _sample(cur, level, cx + tx * step, cy + ty * step, step * kx, step * ky, n)
        b = cv2.GaussianBlur(b, (0, 0), 0.8)
        r = (b - a).ravel()
        w_it = jw if inside_b.all() else jw * inside_b.ravel()[:, None]
        d0, d1, d2, d3 = hinv @ (w_it.T @ r)
        px -= d0
        py -= d1
        tx -= d2 * kx
        ty -= d3 * ky
        if not (abs(px) < 1.0 and abs(py) < 1.0 and abs(tx) < n and abs(ty) < n):
            return None
        if abs(d0) < 1e-5 and abs(d1) < 1e-5 and abs(d2) < 1e-3 and abs(d3) < 1e-3:
            break
    wsum = float(wgt.sum())
    res = math.sqrt(float(wgt @ (r * r)) / wsum) if wsum > 0 else math.inf
    var = 0.25 * (hinv[0, 0] + hinv[1, 1] + 2 * hinv[0, 1])     # of (log kx + log ky) / 2
    return Alignment(math.exp(px), math.exp(py), tx * step, ty * step, res, res * math.sqrt(max(float(var), 0.0)))


# ---------------------------------------------------------------------------
# time to contact and course from a track
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ContactFit:
    """The ``1 / S`` line of :func:`fit_contact`: the contact ``ttc`` (frames after the newest
    frame; None without significant growth), its standard error, the t-statistic of the growth
    (positive = growing) and the growth rate d(log S)/dt (1/frame) at the newest frame."""

    ttc: float | None
    sigma: float | None
    tstat: float
    rate: float


def fit_contact(frames, log_scale) -> ContactFit | None:
    """Least-squares line ``1 / S = a + b t`` through the accumulated scale ``S = exp(log_scale)``.

    For an object approaching at constant speed ``1 / S`` falls linearly to 0 at contact, so
    the contact lies ``-a / b`` frames after the newest frame (t = 0 there, ``1 / S = 1``).
    None with fewer than 3 frames.
    """
    n = len(frames)
    if n < 3:
        return None
    # plain floats: a dozen points, so NumPy's per-call overhead would be most of the cost
    t_end, ls_end = float(frames[-1]), float(log_scale[-1])
    t = [float(f) - t_end for f in frames]
    y = [math.exp(ls_end - float(v)) for v in log_scale]
    tm, ym = sum(t) / n, sum(y) / n
    dt = [v - tm for v in t]
    sxx = sum([d * d for d in dt])
    if sxx <= 0:
        return None
    b = sum([d * (v - ym) for d, v in zip(dt, y)]) / sxx
    a = ym - b * tm
    s2 = sum([(v - (a + b * tv)) ** 2 for v, tv in zip(y, t)]) / max(n - 2, 1)
    sb = math.sqrt(s2 / sxx) if s2 > 0 else 1e-12
    tstat = -b / sb
    rate = -b / a if a > 0 else 0.0
    if not b < 0 or not a > 0:
        return ContactFit(None, None, tstat, rate)
    ttc = -a / b
    # delta method: var(a) = s2 (1/n + tm^2/sxx), cov(a, b) = -tm s2 / sxx
    va = s2 * (1.0 / n + tm * tm / sxx)
    cab = -tm * s2 / sxx
    ga, gb = -1.0 / b, a / (b * b)
    sigma = math.sqrt(max(ga * ga * va + 2 * ga * gb * cab + gb * gb * s2 / sxx, 0.0))
    return ContactFit(ttc, sigma, tstat, rate)


def fit_course(frames, xs, ys, widths, heading: tuple[float, float], ttc: float) -> tuple[float, float] | None:
    """Predicted offset at contact from the heading point, in object widths ``(right, down)``:
    the lines through ``(x - x_h) / w`` and ``(y - y_h) / w`` over ``frames``, evaluated
    ``ttc`` frames after the newest one (its length is the miss distance)."""
    n = len(frames)
    if n < 2 or any(float(w) <= 0 for w in widths):
        return None
    t_end = float(frames[-1])
    t = [float(f) - t_end for f in frames]
    tm = sum(t) / n
    dt = [v - tm for v in t]
    sxx = sum([d * d for d in dt])
    if sxx <= 0:
        return None

    def at(pos, origin):
        z = [(float(q) - origin) / float(w) for q, w in zip(pos, widths)]
        zm = sum(z) / n
        b = sum([d * (v - zm) for d, v in zip(dt, z)]) / sxx
        return zm + b * (ttc - tm)

    return at(xs, heading[0]), at(ys, heading[1])


def _even_dft_size(n: int) -> int:
    """The largest m <= n that is even and its own optimal DFT size (``cv2.getOptimalDFTSize``)."""
    m = n
    while m > 2 and (m % 2 or cv2.getOptimalDFTSize(m) != m):
        m -= 1
    return m


def change_box(prev: np.ndarray, cur: np.ndarray, x: int, y: int, radius: int, *, min_change: float = 3.0,
               rel: float = 0.2) -> tuple[float, float, float, float] | None:
    """Box ``(cx, cy, w, h)`` of the region that changed between two frames around (x, y).

    Within ``radius`` px of (x, y), the window's own image motion (a turning camera moves the
    background as a whole) is found by phase correlation and undone; then the pixels whose
    grey level still changed by at least ``max(min_change, rel x`` the largest change``)`` are
    joined (3 x 3 dilation) and the connected region nearest to (x, y) is taken: for a small
    object growing against its background, the ring of its edge, hence its size to a pixel,
    long before its edges move a pixel per frame. None when nothing changed or the region
    reaches the window's border (a background that does not move as a whole: no compact
    object to box).
    """
    h, w = cur.shape
    x0, x1 = max(x - radius, 0), min(x + radius + 1, w)
    y0, y1 = max(y - radius, 0), min(y + radius + 1, h)
    if x1 - x0 < 8 or y1 - y0 < 8:
        return None
    # OpenCV's phase correlation reports a spurious half-pixel shift of identical windows whose
    # DFT size is odd (81 px: (0.5, 0.5)); an even DFT size has none
    x1, y1 = x0 + _even_dft_size(x1 - x0), y0 + _even_dft_size(y1 - y0)
    a = np.ascontiguousarray(prev[y0:y1, x0:x1], dtype=np.float32)
    b = np.ascontiguousarray(cur[y0:y1, x0:x1], dtype=np.float32)
    (sx, sy), _ = cv2.phaseCorrelate(a, b, cv2.createHanningWindow(a.shape[::-1], cv2.CV_32F))
    if abs(sx) > 0.5 or abs(sy) > 0.5:      # the background moved: compare it with itself
        m = np.array([[1.0, 0.0, -sx], [0.0, 1.0, -sy]], np.float32)
        b = cv2.warpAffine(b, m, (b.shape[1], b.shape[0]), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        border = int(math.ceil(max(abs(sx), abs(sy)))) + 1
    else:
        border = 0
    d = cv2.absdiff(b, a)
    if border:                               # the replicated margin is not a change
        d[:border] = 0
        d[-border:] = 0
        d[:, :border] = 0
        d[:, -border:] = 0
    top = float(d.max())
    if top < min_change:
        return None
    mask = cv2.dilate((d >= max(min_change, rel * top)).astype(np.uint8), np.ones((3, 3), np.uint8))
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    best, best_d = None, math.inf
    for k in range(1, n):
        bx, by, bw, bh = (int(v) for v in stats[k, :4])
        dx = max(bx - (x - x0), 0, (x - x0) - (bx + bw - 1))
        dy = max(by - (y - y0), 0, (y - y0) - (by + bh - 1))
        dist = math.hypot(dx, dy)
        if dist < best_d:
            best, best_d = (bx, by, bw, bh), dist
    if best is None or best_d > radius / 4.0:
        return None
    bx, by, bw, bh = best
    inner_x = (x0 > 0 and bx == 0) or (x1 < w and bx + bw == x1 - x0)
    inner_y = (y0 > 0 and by == 0) or (y1 < h and by + bh == y1 - y0)
    if inner_x or inner_y:
        return None
    # the dilation added a pixel on each side
    return x0 + bx + bw / 2.0 - 0.5, y0 + by + bh / 2.0 - 0.5, max(bw - 2.0, 1.0), max(bh - 2.0, 1.0)


# ---------------------------------------------------------------------------
# the layer
# ---------------------------------------------------------------------------
@dataclass
class Track:
    """Mutable state of one target: box, accumulated log-scale and anisotropy, the recent
    ``(frame, log_scale, cx, cy, width, anisotropy)`` history the fits use, and the evidence
    counters. ``ox``, ``oy``: the camera's turn accumulated at the box since its birth (px; 0
    unless the model measures the camera's motion): the history's positions are the box's less
    it, so that the course (:func:`fit_course`) is the object's own, not the pan's."""

    id: int
    born: int
    cx: float
    cy: float
    w: float
    h: float
    log_s: float = 0.0
    aniso: float = 0.0                               # accumulated log(ky / kx)
    history: deque = field(default_factory=deque)   # (frame, log_s, cx, cy, w, aniso)
    fails: int = 0
    last_answer: int = -(10 ** 9)      # frame an attention field of it last answered
    last_estimate: int = -(10 ** 9)    # frame of its last time to contact
    streak: int = 0
    fields: set = field(default_factory=set)
    rate: float | None = None
    ox: float = 0.0
    oy: float = 0.0

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        return abs(x - self.cx) <= self.w / 2.0 + margin and abs(y - self.cy) <= self.h / 2.0 + margin

    @property
    def size(self) -> float:
        return max(self.w, self.h)

    def overlap(self, other: Track) -> float:
        """Area of the intersection of the two boxes over the area of the smaller."""
        a, b = self, other
        ix = min(a.cx + a.w / 2, b.cx + b.w / 2) - max(a.cx - a.w / 2, b.cx - b.w / 2)
        iy = min(a.cy + a.h / 2, b.cy + b.h / 2) - max(a.cy - a.h / 2, b.cy - b.h / 2)
        if ix <= 0 or iy <= 0:
            return 0.0
        return ix * iy / max(min(a.w * a.h, b.w * b.h), 1e-9)

    def follow(self, move: tuple | None, index: int, fps: float, shape: tuple[int, int], max_fails: int, *,
               box: tuple | None = None, refit: float = 0.0, camera=None) -> bool:
        """Move and grow the box by this frame's measurement (:func:`align`); False when it is lost: its
        centre left the frame (``shape`` = (h, w)), it is under 2 px or over 4 frames wide, or
        the measurement (``move`` = None) failed ``max_fails`` times in a row. ``move``: shift
        (px), factors on width and height, log-scale and log-anisotropy gained. With ``box``
        the box then moves ``refit`` of the way towards it (shrinking only); ``camera.flow`` at
        the box (the camera's image motion) adds to ``ox``, ``oy``."""
        if move is None:
            self.fails += 1
            return self.fails < max_fails
        dx, dy, fx, fy, growth, skew = move
        self.fails = 0
        self.cx += dx
        self.cy += dy
        self.w *= fx
        self.h *= fy
        if box is not None and refit > 0:
            self.cx += refit * (box[0] - self.cx)
            self.cy += refit * (box[1] - self.cy)
            self.w *= min(max(box[2], 1.0) / self.w, 1.0) ** refit
            self.h *= min(max(box[3], 1.0) / self.h, 1.0) ** refit
        self.log_s += growth
        self.aniso += skew
        self.rate = growth * fps
        if camera is not None:
            du, dv = camera.flow(self.cx - dx, self.cy - dy)
            self.ox += float(du)
            self.oy += float(dv)
        self.history.append((index, self.log_s, self.cx - self.ox, self.cy - self.oy, self.w, self.aniso))
        h, w = shape
        return not (self.size < 2.0 or self.size > 4.0 * max(w, h)
                    or not (0 <= self.cx <= w - 1 and 0 <= self.cy <= h - 1))


class TargetLayer:
    """From attention fields to targets, frame by frame (``step``); explicit state, ``reset``.

    Parameters
    ----------
    params : TargetParams
    fps : float
        Frame rate (frames -> seconds).
    kernel : callable, optional
        Compiled edge scan for :func:`measure_extent` (:mod:`mlplc2.backend`); None = NumPy.
    align_kernel : callable, optional
        Compiled image alignment for :func:`align` (:mod:`mlplc2.backend`); None = NumPy.
    focal : float, optional
        Focal length in px (from the camera's field of view): targets then carry bearings.
    """

    def __init__(self, params: TargetParams | None = None, fps: float = 30.0, *, kernel=None,
                 align_kernel=None, focal: float | None = None):
        self.params = TargetParams() if params is None else params
        self.fps = float(fps)
        self.kernel = kernel
        self.align_kernel = align_kernel
        self.focal = focal
        self.reset()

    def reset(self) -> None:
        self._tracks: list[Track] = []
        self._next = 1
        self._prev: list[np.ndarray] | None = None
        self._past: deque = deque(maxlen=max(self.params.change_frames, 1))   # pyramids of the last frames

    # -- one frame -----------------------------------------------------------------------
    def step(self, gray: np.ndarray, lm: LocalMotion, fields, index: int) -> tuple[Target, ...]:
        """Targets of this frame. ``gray``: the model's float32 grey frame; ``lm``: its LM maps;
        ``fields``: the attention fields (objects with ``id``, ``x``, ``y``, ``response``)."""
        p = self.params
        levels = pyramid(gray)
        h, w = gray.shape
        if self._prev is not None:
            self._follow(levels, index, w, h)
        self._merge()
        seeds = []
        for f in fields:
            owners = [t for t in self._tracks if t.contains(f.x, f.y, 0.25 * t.size + 4.0)]
            if owners:
                t = min(owners, key=lambda t: t.size)
                t.fields.add(f.id)
                if f.response > 0:
                    t.last_answer = index
            else:
                seeds.append((int(f.x), int(f.y), f))
        if p.seed_lm > 0 and len(self._tracks) + len(seeds) < p.max_targets:
            from ..neuropils.attention import argmax_outside

            # a track claims its box and the blur of the front end around it (the lamina's
            # inhibitory window, r_Di = 11 px): LM there is the tracked object's own
            zones = [(int(round(t.cx)), int(round(t.cy)), int(t.size / 2.0 + p.claim)) for t in self._tracks]
            zones += [(int(f.x), int(f.y), int(f.radius)) for f in fields]
            cand = argmax_outside(lm.magnitude, zones)
            if cand is None or not cand[2] > max(p.seed_lm, p.seed_contrast * float(lm.magnitude.mean())):
                cand = self._change_seed(levels, zones)
            if cand is not None:
                seeds.append((cand[0], cand[1], None))
        for x, y, f in seeds:
            if len(self._tracks) >= p.max_targets:
                break
            if any(t.contains(x, y) for t in self._tracks):
                continue
            box = self._box(lm, gray, x, y, field_seed=f is not None)
            if box is None:
                continue
            t = Track(self._next, index, *box)
            host = next((o for o in self._tracks if o.overlap(t) >= 0.5), None)
            if host is not None:          # a part of an object already tracked
                if f is not None:
                    host.fields.add(f.id)
                    if f.response > 0:
                        host.last_answer = index
                continue
            if not self._grows(levels, t):
                continue
            t.history = deque([(index, 0.0, t.cx, t.cy, t.w, 0.0)], maxlen=p.window)
            self._next += 1
            if f is not None:
                t.fields.add(f.id)
                if f.response > 0:
                    t.last_answer = index
            self._tracks.append(t)
        self._prev = levels
        self._past.append(levels)
        alive = {f.id for f in fields}
        out = []
        for t in self._tracks:
            t.fields &= alive
            out.append(estimate(t, p, self.fps, index, (h, w), self.focal))
        self._tracks = [t for t in self._tracks if index - max(t.last_answer, t.last_estimate, t.born) <= p.idle_frames]
        keep = {t.id for t in self._tracks}
        return tuple(sorted((o for o in out if o.id in keep), key=Target.urgency))

    def _change_seed(self, levels, zones):
        """A candidate where the image changed most over the last ``change_frames`` frames (at
        half resolution, outside the zones of targets and fields), when that change stands out:
        at least ``seed_change`` grey levels and ``seed_contrast`` times the frame's mean change.
        An object that grows straight at the camera moves its edges a fraction of a pixel per
        frame, too little for the local motion, while the grey levels along its edge change
        steadily; a moving background changes everywhere and seeds nothing here."""
        p = self.params
        if p.seed_change <= 0 or len(self._past) < p.change_frames or len(levels) < 2:
            return None
        d = cv2.blur(cv2.absdiff(levels[1], self._past[0][1]), (3, 3))
        for zx, zy, zr in zones:                 # at half resolution
            x0, x1 = max((zx - zr) // 2, 0), max((zx + zr) // 2 + 1, 0)
            y0, y1 = max((zy - zr) // 2, 0), max((zy + zr) // 2 + 1, 0)
            d[y0:y1, x0:x1] = 0
        _, top, _, (x, y) = cv2.minMaxLoc(d)
        if top < max(p.seed_change, p.seed_contrast * float(d.mean())):
            return None
        return 2 * x + 1, 2 * y + 1

    def _grows(self, levels, t: Track) -> bool:
        """Whether the candidate grew, alike in both directions, over the last ``change_frames``
        frames (the image alignment of :func:`align` against the oldest frame kept): a patch of
        background that slides with a turning camera, a receding or a static object does not
        become a target. Without that frame yet (the first frames), True."""
        p = self.params
        if p.min_growth <= 0 or len(self._past) < p.change_frames:
            return True
        half = p.margin * t.size / 2.0 + 3.0
        al = align(self._past[0], levels, t.cx, t.cy, half, (t.w / 2.0, t.h / 2.0), n=p.patch,
                   iterations=p.iterations, kernel=self.align_kernel)
        if al is None or al.residual > p.max_residual:
            return False
        g = math.log(al.scale)
        return g >= p.min_growth and abs(al.anisotropy) <= p.max_anisotropy * g

    def _box(self, lm: LocalMotion, gray: np.ndarray, x: int, y: int, field_seed: bool):
        """The box of a candidate at (x, y): the region that changed over the last frames
        (:func:`change_box`, tight for a small object), else the edges of the local motion
        (:func:`measure_extent`). None when neither finds a box holding the seed within
        ``max_shift``."""
        p = self.params

        def edges():
            ext = measure_extent(lm, x, y, p, kernel=self.kernel)
            if ext.width is None or ext.height is None:
                return None
            return ext.cx, ext.cy, ext.width, ext.height

        def change():
            if not self._past:
                return None
            return change_box(self._past[0][0], gray, x, y, int(p.max_shift))

        for find in ((edges, change) if field_seed else (change, edges)):
            box = find()
            if box is not None and max(abs(box[0] - x), abs(box[1] - y)) <= p.max_shift:
                return box
        return None

    def _follow(self, levels, index: int, w: int, h: int) -> None:
        """Move and grow every track with the image alignment; drop the lost ones."""
        p = self.params
        kept = []
        for t in self._tracks:
            half = p.margin * t.size / 2.0 + 3.0
            al = align(self._prev, levels, t.cx, t.cy, half, (t.w / 2.0, t.h / 2.0), n=p.patch,
                       iterations=p.iterations, kernel=self.align_kernel)
            move = None if al is None or al.residual > p.max_residual else \
                (al.dx, al.dy, al.kx, al.ky, math.log(al.scale), al.anisotropy)
            if t.follow(move, index, self.fps, (h, w), p.max_fails):
                kept.append(t)
        self._tracks = kept

    def _merge(self) -> None:
        """Two tracks are one object when most of the smaller box lies in the larger: keep the older."""
        tracks = sorted(self._tracks, key=lambda t: t.id)
        out: list[Track] = []
        for t in tracks:
            host = next((o for o in out if o.overlap(t) >= 0.5), None)
            if host is None:
                out.append(t)
            else:
                host.fields |= t.fields
                host.last_answer = max(host.last_answer, t.last_answer)
        self._tracks = out


def count_down(targets, elapsed: float) -> tuple[Target, ...]:
    """``targets`` held ``elapsed`` seconds (a repeated frame): each ``ttc_s`` counts down; an estimate
    whose contact has passed becomes None and loses its warning; re-sorted by urgency."""
    out = []
    for t in targets:
        if t.ttc_s is not None:
            left = t.ttc_s - elapsed
            t = replace(t, ttc_s=left) if left > 0 else replace(t, ttc_s=None, miss=None, warning=False,
                                                                 ttc_sigma_s=None, miss_xy=None)
        out.append(t)
    return tuple(sorted(out, key=Target.urgency))


def estimate(t: Track, p: TargetParams, fps: float, index: int, shape: tuple[int, int],
             focal: float | None = None) -> Target:
    """The :class:`Target` of track ``t`` this frame: time to contact (:func:`fit_contact`),
    course (:func:`fit_course`) and the warning rule (``docs/targets.md``, step 7). Shared
    by every model with targets (the LPLC2 family and the optical-flow baseline)."""
    h, w = shape
    frames = [q[0] for q in t.history]
    ttc = sigma = miss = miss_xy = None
    fit = fit_contact(frames, [q[1] for q in t.history]) if len(frames) >= p.min_frames else None
    # an approaching object grows alike in both directions; the ground ahead (or a wall beside
    # the path) grows twice as fast in one, and a box that slides over a moving edge stretches
    # along the motion: none of them is an object approaching, none gets a time to contact
    isotropic = True
    if fit is not None and fit.ttc is not None:
        growth = t.history[-1][1] - t.history[0][1]
        skew = t.history[-1][5] - t.history[0][5]
        isotropic = growth > 0 and abs(skew) <= p.max_anisotropy * growth
    if isotropic and fit is not None and fit.ttc is not None and fit.tstat >= p.min_tstat \
            and fit.ttc / fps <= p.max_ttc_s:
        ttc, sigma = fit.ttc / fps, fit.sigma / fps
        heading = p.heading if p.heading is not None else ((w - 1) / 2.0, (h - 1) / 2.0)
        miss_xy = fit_course(frames, [q[2] for q in t.history], [q[3] for q in t.history],
                             [q[4] for q in t.history], heading, fit.ttc)
        miss = None if miss_xy is None else math.hypot(*miss_xy)
        t.streak += 1
        t.last_estimate = index
    else:
        t.streak = 0
    looming = ttc is not None and (index - t.last_answer <= p.evidence_frames or t.streak >= p.confirm_frames)
    warning = bool(looming and miss is not None and ttc <= p.horizon_s and miss <= p.max_miss
                   and sigma <= p.max_ttc_sigma * ttc)
    az = el = None
    if focal is not None:
        az, el = bearing(t.cx, t.cy, (h, w), focal)
    def num(v):
        return None if v is None else float(v)

    return Target(t.id, float(t.cx), float(t.cy), float(t.w), float(t.h), ttc_s=num(ttc), miss=num(miss),
                  warning=warning, fields=tuple(sorted(t.fields)), born=t.born, looming=looming,
                  expansion=num(t.rate), ttc_sigma_s=num(sigma), azimuth_deg=num(az), elevation_deg=num(el),
                  miss_xy=None if miss_xy is None else (float(miss_xy[0]), float(miss_xy[1])))
