"""A classical optical-flow baseline (not part of the paper): ``flow``.

What a robotics engineer would build instead of a bio-inspired model, measured on the same
benchmark with the same targets and warning rule (``docs/flow.md`` has the equations, the
choices and the figures). Per frame:

1. **Frame flow.** Dense optical flow ``F`` (OpenCV's DIS, Kroeger et al. 2016;
   ``FlowParams.preset``) from the frame ``baseline`` frames back to this one.
2. **Camera motion** (:func:`camera_motion`): one or two homographies fitted by RANSAC to the
   flow (the ground and the sky of a camera driving forward), the background's flow ``C``; the
   focus of expansion (:func:`focus_of_expansion`, :attr:`FlowTTC.foe`).
3. **Candidates** (:func:`divergence`): regions where the divergence of ``F - C`` exceeds
   ``min_divergence`` and the frame's noise. A region that no growing target claims becomes a
   target when its box (:func:`mlplc2.targets.change_box`) grew, alike in both directions, over
   the last ``TargetParams.change_frames`` frames in the object's own flow, as the LPLC2
   family's candidates must.
4. **The object's own flow** (:func:`object_flow`): Farneback's flow (2003) on the target's box
   resampled to ``patch`` x ``patch`` samples, and the per-axis expansion and shift fitted to
   its normal flow in two layers (object and background).
5. **Time to contact.** The box follows that fit; the estimator of the LPLC2 family's targets
   (:func:`mlplc2.targets.estimate`) gives ``ttc_s``, ``miss`` and the warning, with looming
   evidence = sustained significant growth (``TargetParams.confirm_frames``).

It has no attention fields; its alarm (``Output.collision``) is "any target warns" and its
response the largest expansion rate (1/s).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .._validation import Valid, check_fields
from ..camera import check_hfov, focal_length
from ..params import ParameterSet, document_parameters, param, param_of
from ..targets.alignment import pyramid
from ..targets.change import change_box
from ..targets.layer import Observation, Target, Track, count_down, estimate
from ..targets.params import TargetParams
from .base import WORK_WIDTH, Model, Output, register

__all__ = ["FlowTTC", "FlowParams", "ObjectFlow", "object_flow", "camera_motion", "CameraMotion",
           "focus_of_expansion", "divergence"]

#: Smallest frame side (px) DIS computes a flow for; smaller frames give no targets.
MIN_FLOW_SIZE = 12
_PRESETS = {"ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST, "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
            "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM}
#: Farneback's settings on the resampled patch, except its window (``FlowParams.window``):
#: pyramid scale, levels, iterations, polynomial neighbourhood and its Gaussian sigma (OpenCV's
#: recommended values for poly_n = 5).
FARNEBACK = {"pyr_scale": 0.5, "levels": 3, "iterations": 3, "poly_n": 5, "poly_sigma": 1.1}
#: Samples added around the patch on each side and left out of the fit: Farneback's flow is
#: unreliable within a few samples of the patch's border (up to 0.5 sample between two equal
#: images; below 1e-4 from 6 samples in).
PAD = 6


@document_parameters("Parameters")
@dataclass(frozen=True)
class FlowParams(ParameterSet):
    """Parameters of the optical-flow baseline (:class:`FlowTTC`); the warning and TTC
    settings are the targets' (:class:`mlplc2.targets.TargetParams`)."""

    preset: str = param("medium", "DIS optical flow preset of the frame flow (speed against accuracy).",
                        valid=Valid.choice(*_PRESETS))
    baseline: int = param(4, """The frame flow is computed from the frame this many frames back to this one:
                          an object far away grows by a small fraction of a pixel per frame, four frames
                          make its flow four times larger than DIS's noise.""", unit="frames",
                          valid=Valid.integer(1, 30))
    min_gradient: float = param(3.0, """Frame flow where the grey level's gradient (Sobel, locally averaged
                                energy) is weaker than this is left out of the divergence: a uniform
                                area has no flow of its own (DIS returns noise there, several px on a
                                plain background with sensor noise).""", unit="grey levels/px",
                                valid=Valid.real(minimum=0))
    cell: int = param(8, "Side of the cells the divergence is averaged over.", unit="px", valid=Valid.integer(2))
    min_divergence: float = param(0.006, """A cell is a candidate when the divergence of the flow less the
                                  camera's exceeds this per frame (0.006 = a time to contact of 11 s at 30
                                  fps) ...""", unit="1/frame", valid=Valid.real(minimum=0))
    noise_k: float = param(4.0, """... and by this many times the frame's robust spread of the divergence
                           (1.4826 x the median absolute deviation over the cells).""",
                           valid=Valid.real(minimum=0))
    min_cells: int = param(2, "Fewest connected cells that make a candidate region.", unit="cells",
                           valid=Valid.integer(1))
    grid: int = param(8, "Spacing of the flow vectors the camera motion and the FOE are fitted to.", unit="px",
                      valid=Valid.integer(1))
    camera_tolerance: float = param(0.5, """RANSAC inlier distance of the camera's homography
                                    (``cv2.findHomography``) per frame of the baseline.""", unit="px",
                                    valid=Valid.real(minimum=0))
    second_layer: float = param(0.3, """A second background layer (homography) is fitted to the outliers of the
                                first when it explains at least this fraction of the flow vectors (1 = never):
                                the ground and the sky of a camera driving forward.""",
                                valid=Valid.real(minimum=0, maximum=1))
    min_foe_flow: float = param(0.2, """Frame-flow vectors shorter than this per frame of the baseline are left
                                out of the focus of expansion.""", unit="px/frame", valid=Valid.real(minimum=0))
    patch: int = param(48, "Side of the resampled patch a target's own flow is computed on (step 4).",
                       unit="samples", valid=Valid.integer(16, 256))
    margin: float = param_of(TargetParams, "margin")     # the same definition as the targets'
    window: int = param(5, """Averaging window of Farneback's flow on the patch (odd): smaller follows the
                        object's boundary more closely (less of the still background blended into its
                        flow), larger is smoother.""", unit="samples", valid=Valid.integer(3, 31))
    layer_iterations: int = param(3, "Rounds of the object / camera layer assignment of the patch's samples.",
                                  valid=Valid.integer(0, 20))
    max_expansion: float = param(0.3, """Largest expansion rate of an accepted fit (log-scale per frame; 0.3 =
                                 35 % per frame, a time to contact of 0.1 s at 30 fps): beyond it the fit
                                 failed.""", unit="1/frame", valid=Valid.real(minimum=0))
    refit: float = param(0.1, """Each frame a target's box moves this fraction of the way (geometrically
                         for its size) towards the box of its object's layer in the patch (the 2-98 %
                         weighted quantiles of its samples' positions): a box that started too large,
                         too small or on one edge of the object settles on the object. 0 = the box only
                         follows the flow.""", valid=Valid.real(minimum=0, maximum=1))
    claim: float = param(8.0, """A region whose centre lies within a target's box widened by a quarter of its
                         larger side plus this belongs to the target (no new candidate).""", unit="px",
                         valid=Valid.real(minimum=0))
    max_targets: int = param(12, "Upper bound on simultaneous targets.", unit="targets", valid=Valid.integer(0))
    idle_frames: int = param(10, """Frames a target lives with neither a candidate region under it (while it
                             grows) nor looming evidence.""", unit="frames", valid=Valid.integer(0))

    def __post_init__(self) -> None:
        check_fields(self, "FlowParams")


# ---------------------------------------------------------------------------
# stage functions
# ---------------------------------------------------------------------------
def _homography_flow(h: np.ndarray, xs, ys, k: float):
    """``k (H(x) - x)`` at the points ``(xs, ys)``."""
    den = h[2, 0] * xs + h[2, 1] * ys + h[2, 2]
    return (k * ((h[0, 0] * xs + h[0, 1] * ys + h[0, 2]) / den - xs),
            k * ((h[1, 0] * xs + h[1, 1] * ys + h[1, 2]) / den - ys))


@dataclass(frozen=True)
class CameraMotion:
    """The camera's own image motion over ``frames`` frames: homographies that map a pixel of
    the earlier frame to the later one, the dominant one ``H`` (3 x 3) and possibly a second
    background layer ``H2``. A homography is exact for a turning camera (pan, tilt:
    ``K R K^-1``) and for a plane seen from a moving one: a camera driving forward sees two,
    the ground and the far scene (the sky, which does not move). The background's flow is
    ``H(x) - x``."""

    H: np.ndarray
    frames: float
    H2: np.ndarray | None = None

    def flow(self, xs, ys, frames: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """The dominant layer's flow (px) at the points ``(xs, ys)`` (broadcast) over ``frames``
        frames (the homography's flow scaled linearly: small motions)."""
        return _homography_flow(self.H, xs, ys, frames / self.frames)

    def flows(self, xs, ys, frames: float = 1.0) -> list[tuple[np.ndarray, np.ndarray]]:
        """The flow of every layer (:meth:`flow`), the dominant one first."""
        return [_homography_flow(h, xs, ys, frames / self.frames) for h in (self.H, self.H2) if h is not None]

    def turning(self, cx: float, cy: float, width: float, ratio: float = 0.25) -> bool:
        """Whether the dominant motion is a turn (pan, tilt) rather than the camera's
        translation: its flow at the principal point (cx, cy) exceeds, ``1 / ratio`` times
        over, the flow its expansion there makes at the image's side (``width / 2`` px away). A
        turn moves the whole image alike to first order; a translation over the ground or
        towards a wall expands it about the focus of expansion."""
        d = width / 4.0
        u0, v0 = self.flow(np.float64(cx), np.float64(cy), self.frames)
        ur, _ = self.flow(np.float64(cx + d), np.float64(cy), self.frames)
        ul, _ = self.flow(np.float64(cx - d), np.float64(cy), self.frames)
        _, vd = self.flow(np.float64(cx), np.float64(cy + d), self.frames)
        _, vu = self.flow(np.float64(cx), np.float64(cy - d), self.frames)
        div = (ur - ul + vd - vu) / (2.0 * d)
        return bool(abs(div) * width / 2.0 < ratio * math.hypot(u0, v0))


def _fit_homography(src: np.ndarray, dst: np.ndarray, tolerance: float):
    if len(src) < 8:
        return None, None
    m, inl = cv2.findHomography(src, dst, cv2.RANSAC, tolerance, maxIters=200, confidence=0.99)
    if m is None or not np.isfinite(m).all() or abs(m[2, 2]) < 1e-12:
        return None, None
    return m / m[2, 2], inl.ravel().astype(bool)


def camera_motion(flow: np.ndarray, frames: float = 1.0, grid: int = 8, tolerance: float = 0.5,
                  second_layer: float = 0.3) -> CameraMotion | None:
    """The camera's own image motion (:class:`CameraMotion`) from the flow vectors on a grid of
    spacing ``grid``: the homography fitted by RANSAC (``cv2.findHomography``, inliers within
    ``tolerance`` px), and a second one fitted to its outliers when it explains at least
    ``second_layer`` of all the vectors (a moving object rarely covers that much before its
    contact); None without a fit. ``frames``: the frames the flow spans."""
    h, w = flow.shape[:2]
    ys, xs = np.mgrid[grid // 2:h:grid, grid // 2:w:grid]
    src = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float32)
    dst = src + flow[ys.ravel(), xs.ravel()]
    m, inl = _fit_homography(src, dst, tolerance)
    if m is None:
        return None
    m2 = None
    out = ~inl
    if second_layer < 1 and out.sum() >= second_layer * len(src):
        m2, inl2 = _fit_homography(src[out], dst[out], tolerance)
        if m2 is not None and inl2.sum() < second_layer * len(src):
            m2 = None
    return CameraMotion(m, float(frames), m2)


def focus_of_expansion(flow: np.ndarray, grid: int = 8, min_flow: float = 0.2,
                       iterations: int = 5) -> tuple[float, float] | None:
    """The point the flow lines radiate from (px), or None.

    Every grid vector longer than ``min_flow`` defines a line; the point ``q`` minimising the
    weighted squared distances to the lines, ``sum w_i (n_i . (q - p_i))^2`` (``n_i`` the
    unit normal of vector i at ``p_i``, ``w_i`` its length), is refitted ``iterations`` times
    with Cauchy weights on the distances (independently moving objects are outliers). None
    with fewer than 20 vectors, when the lines are nearly parallel (a pan: the smaller
    eigenvalue of the normal matrix below a tenth of the larger) or when most vectors point
    towards ``q`` (a focus of contraction).
    """
    h, w = flow.shape[:2]
    ys, xs = np.mgrid[grid // 2:h:grid, grid // 2:w:grid]
    f = flow[ys.ravel(), xs.ravel()].astype(np.float64)
    p = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float64)
    mag = np.hypot(f[:, 0], f[:, 1])
    keep = mag > min_flow
    if keep.sum() < 20:
        return None
    f, p, mag = f[keep], p[keep], mag[keep]
    n = np.stack([-f[:, 1], f[:, 0]], 1) / mag[:, None]
    c = np.einsum("ij,ij->i", n, p)                  # n . p
    wt = mag.copy()
    q = None
    for _ in range(iterations + 1):
        a = (n * wt[:, None]).T @ n
        ev = np.linalg.eigvalsh(a)
        if ev[0] < 0.1 * ev[1]:
            return None
        q = np.linalg.solve(a, (n * (wt * c)[:, None]).sum(0))
        d = np.abs(n @ q - c)
        scale = max(float(np.median(d)), 0.5)
        wt = mag / (1.0 + (d / (2.0 * scale)) ** 2)
    if float(np.average(np.sign(np.einsum("ij,ij->i", f, p - q)), weights=wt)) < 0.5:
        return None
    return float(q[0]), float(q[1])


@dataclass(frozen=True)
class ObjectFlow:
    """What :func:`object_flow` measured in a patch: per-axis expansion rates ``kx``, ``ky``
    (log-scale per frame), the shift ``dx``, ``dy`` of the patch's centre (px), and the box of
    the object's layer in the later frame (centre ``x``, ``y`` and size ``width``, ``height``
    in px; None when it has too few samples)."""

    kx: float
    ky: float
    dx: float
    dy: float
    box: tuple[float, float, float, float] | None = None


def _sample(levels: list[np.ndarray], cx: float, cy: float, half: float, n: int) -> tuple[np.ndarray, float, int]:
    """The ``n + 2 PAD`` square of samples centred on (cx, cy), spacing ``s = 2 half / n`` px,
    bilinear from the pyramid level whose pixel is at most 1.5 samples; returns it, ``s`` and
    the level."""
    s = 2.0 * half / n
    level = 0
    while level + 1 < len(levels) and 2 ** (level + 1) <= 1.5 * s:
        level += 1
    k = 2.0 ** level
    m = n + 2 * PAD
    x0 = cx - half - PAD * s + 0.5 * s               # centre of sample 0 (px of the frame)
    y0 = cy - half - PAD * s + 0.5 * s
    warp = np.array([[s / k, 0.0, (x0 + 0.5) / k - 0.5], [0.0, s / k, (y0 + 0.5) / k - 0.5]], np.float32)
    out = cv2.warpAffine(levels[level], warp, (m, m), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                         borderMode=cv2.BORDER_REPLICATE)
    return out, s, level


def object_flow(prev: list[np.ndarray], cur: list[np.ndarray], cx: float, cy: float, half: float,
                camera: CameraMotion | None, *, frames: float = 1.0, n: int = 48, window: int = 5, layer_iterations: int = 3,
                max_expansion: float = 0.3, min_gradient: float = 3.0) -> ObjectFlow | None:
    """The expansion and shift of the object in the square of half-side ``half`` px around
    (cx, cy) from ``prev`` to ``cur`` (two :func:`mlplc2.targets.pyramid` s): step 4 of the
    module docstring. ``camera``: the camera's motion (:func:`camera_motion`) or None (a still
    one); ``frames``: the frames from ``prev`` to ``cur``. None when the patch has too little structure, lies outside the frame, or the
    fit exceeds ``max_expansion``.
    """
    h, w = cur[0].shape
    a, s, _ = _sample(prev, cx, cy, half, n)
    b, _, _ = _sample(cur, cx, cy, half, n)
    m = n + 2 * PAD
    # sample coordinates: centred on the patch (samples), and in the frame (px)
    j = np.arange(m, dtype=np.float64) - (m - 1) / 2.0
    xs, ys = cx + s * j, cy + s * j
    inside_x = (xs >= -0.5) & (xs <= w - 0.5)
    inside_y = (ys >= -0.5) & (ys <= h - 0.5)
    inner = np.zeros(m, bool)
    inner[PAD:m - PAD] = True
    valid = (inside_y & inner)[:, None] & (inside_x & inner)[None, :]
    if not valid.any():
        return None
    if np.array_equal(a, b):                         # nothing changed: no motion (exactly)
        return ObjectFlow(0.0, 0.0, 0.0, 0.0)
    flow = cv2.calcOpticalFlowFarneback(a, b, None, winsize=window, flags=0, **FARNEBACK)
    # the normal flow: the flow's component along the grey level's gradient (of the mean of
    # the two patches), the one the aperture problem leaves determined at an edge
    mean = 0.5 * (a + b)
    gx = cv2.Sobel(mean, cv2.CV_32F, 1, 0, ksize=3).astype(np.float64)
    gy = cv2.Sobel(mean, cv2.CV_32F, 0, 1, ksize=3).astype(np.float64)
    g = np.hypot(gx, gy)
    nx, ny = gx / np.maximum(g, 1e-9), gy / np.maximum(g, 1e-9)
    # weight: the gradient's magnitude (grey levels per px of the frame) above min_gradient
    w0 = np.where(valid, np.maximum(g * (0.125 / s) - min_gradient, 0.0), 0.0)
    if w0.sum() <= 1e-6 * w0.size:
        return None
    normal = nx * flow[..., 0] + ny * flow[..., 1]
    # the camera's normal flow at the samples, in samples per frame
    if camera is None:
        rc = np.abs(normal)
    else:                                    # the background layer that explains it best
        rc = np.min([np.abs(normal - (nx * uc + ny * vc) / s)
                     for uc, vc in camera.flows(xs[None, :], ys[:, None], frames)], axis=0)
    dj = np.broadcast_to(j[None, :], g.shape)
    di = np.broadcast_to(j[:, None], g.shape)
    rows = np.stack([nx, nx * dj, ny, ny * di], -1)          # (tx, kx, ty, ky)
    wt = w0
    for it in range(layer_iterations + 1):
        par = _solve(rows, normal, wt)
        if par is None:
            return None
        if it == layer_iterations:
            break
        wt = w0 * (np.abs(normal - rows @ par) <= rc)
    tx, kx, ty, ky = (float(v) for v in par)
    if not (abs(kx) <= max_expansion and abs(ky) <= max_expansion):
        return None
    # the object's layer, earlier frame: the samples the object's motion explains at least
    # twice as well as the camera's (where the two nearly agree a sample could be either)
    box = None
    support = w0 * (np.abs(normal - rows @ par) <= 0.5 * rc)
    ex, ey = _extent(j, support.sum(0)), _extent(j, support.sum(1))
    if ex is not None and ey is not None:
        (x0, x1), (y0, y1) = ex, ey
        # moved to the later frame with the object's motion
        box = (cx + s * (0.5 * (x0 + x1) * (1.0 + kx) + tx), cy + s * (0.5 * (y0 + y1) * (1.0 + ky) + ty),
               s * (x1 - x0) * (1.0 + kx), s * (y1 - y0) * (1.0 + ky))
    return ObjectFlow(float(kx), float(ky), float(tx * s), float(ty * s), box)


def _extent(x: np.ndarray, w: np.ndarray, tail: float = 0.02) -> tuple[float, float] | None:
    """The ``tail`` and ``1 - tail`` weighted quantiles of the sample positions ``x`` (each
    sample one unit wide), or None without weight."""
    total = float(w.sum())
    if total <= 0:
        return None
    cum = np.concatenate([[0.0], np.cumsum(w) / total])
    edges = np.concatenate([x - 0.5, [x[-1] + 0.5]])
    return float(np.interp(tail, cum, edges)), float(np.interp(1.0 - tail, cum, edges))


def _solve(rows: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray | None:
    """Weighted least squares ``rows @ p = y`` (rows: (..., k)), or None when ill-conditioned
    (the smallest eigenvalue of the normal matrix below 1e-6 of the largest: e.g. one straight
    edge cannot tell expansion from shift)."""
    r = rows.reshape(-1, rows.shape[-1])
    ww = w.ravel()
    keep = ww > 0
    if keep.sum() < rows.shape[-1]:
        return None
    r, ww, yy = r[keep], ww[keep], y.ravel()[keep]
    a = (r * ww[:, None]).T @ r
    ev = np.linalg.eigvalsh(a)
    if not ev[-1] > 0 or ev[0] < 1e-6 * ev[-1]:
        return None
    return np.linalg.solve(a, (r * (ww * yy)[:, None]).sum(0))


def divergence(flow: np.ndarray, gray: np.ndarray, camera: CameraMotion | None, frames: float, cell: int,
               min_gradient: float) -> np.ndarray:
    """The divergence ``du/dx + dv/dy`` (Sobel) of the flow left after the camera's motion,
    ``F - C``, averaged over cells of ``cell`` px; zero where ``gray`` has no structure (the
    Gaussian-averaged gradient energy below ``min_gradient ** 2``; DIS's flow there is noise)."""
    h, w = flow.shape[:2]
    res = flow
    if camera is not None:                   # less the background layer nearest to it
        best = None
        for uc, vc in camera.flows(np.arange(w, dtype=np.float32)[None, :], np.arange(h, dtype=np.float32)[:, None],
                                   frames):
            r = np.stack(np.broadcast_arrays(flow[..., 0] - uc, flow[..., 1] - vc), -1).astype(np.float32)
            if best is None:
                best = r
            else:
                closer = (r * r).sum(-1) < (best * best).sum(-1)
                best[closer] = r[closer]
        res = best
    g = np.asarray(gray, np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    energy = cv2.GaussianBlur(gx * gx + gy * gy, (0, 0), 1.0)
    res = res * (energy >= np.float32(min_gradient) ** 2)[..., None]
    du = cv2.Sobel(res[..., 0], cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    dv = cv2.Sobel(res[..., 1], cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    return cv2.resize(du + dv, (max(w // cell, 1), max(h // cell, 1)), interpolation=cv2.INTER_AREA)


@dataclass
class _FlowTrack(Track):
    """A target's state (:class:`mlplc2.targets.Track`, whose ``ox``, ``oy`` accumulate the
    camera's turn at its box) plus its evidence in processed frames."""

    # the frames processed (repeated frames skipped, Model.repeat_threshold) when a candidate
    # region was last found under it, and when it last showed looming evidence
    seen: int = 0
    loomed: int = -(10 ** 9)


def _grew(t: Track, tp: TargetParams) -> bool:
    """Whether the track grew by ``min_growth`` over its history, alike in both directions
    (``max_anisotropy``); True while it is younger than ``change_frames``."""
    if len(t.history) < tp.change_frames:
        return True
    g = t.history[-1].log_scale - t.history[0].log_scale
    return g >= tp.min_growth and abs(t.history[-1].anisotropy - t.history[0].anisotropy) <= tp.max_anisotropy * g


@register("flow")
class FlowTTC(Model):
    """Optical-flow time to contact (a classical baseline, not the paper's): see the module docstring.

    Parameters
    ----------
    fps : float
    params : FlowParams, optional
    hfov_deg : float, optional, keyword-only
        Horizontal field of view (degrees): targets carry their bearing.
    target_params : mlplc2.targets.TargetParams, optional, keyword-only
        TTC, course and warning settings (the same defaults as the LPLC2 family's targets).

    Examples
    --------
    >>> import numpy as np, mlplc2
    >>> model = mlplc2.get_model("flow")(fps=30.0)
    >>> model.step(np.zeros((120, 160), np.uint8)).targets
    ()
    """

    has_targets = True

    def __init__(self, fps: float = 30.0, params: FlowParams | None = None, *, hfov_deg: float | None = None,
                 target_params: TargetParams | None = None, repeat_threshold: float | str | None = "auto", work_width: int | None = WORK_WIDTH):
        params = self._check_params(params, FlowParams, "params", "mlplc2.models.flow.FlowParams")
        target_params = self._check_params(target_params, TargetParams, "target_params", "mlplc2.targets.TargetParams")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        self.hfov_deg = check_hfov(hfov_deg)
        self.target_params = target_params
        self._reset()

    def _hold(self, last: Output, elapsed: float) -> Output:
        """A repeated frame: the targets' times to contact count down (:func:`~mlplc2.targets.count_down`)."""
        return replace(last, targets=count_down(last.targets, elapsed))

    def _reset(self) -> None:
        self._frames: deque = deque(maxlen=max(self.params.baseline, self.target_params.change_frames))
        self._levels: list[np.ndarray] | None = None      # pyramid of the previous frame
        self._past_levels: list[np.ndarray] | None = None   # pyramid of the frame change_frames back
        self._past_warped: np.ndarray | None = None        # that frame, the camera's motion undone
        self._dis = None
        self._tracks: list[_FlowTrack] = []
        self._next = 1
        self._steps = 0                                    # frames processed with a flow
        self.foe: tuple[float, float] | None = None
        """The focus of expansion of the last frame flow (px), None without one."""
        self.camera: CameraMotion | None = None
        """The camera's own image motion in the last frame flow, None without one."""
        self.flow: np.ndarray | None = None
        """The last frame flow (H, W, 2): from ``baseline`` frames back (fewer in the first frames)."""

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_dis"] = None                 # OpenCV objects do not pickle; rebuilt on the next frame
        return state

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p, tp = self.params, self.target_params
        cur = np.rint(gray).astype(np.uint8)    # gray is on 0-255 already (as_gray)
        h, w = cur.shape
        if min(h, w) < MIN_FLOW_SIZE:            # DIS needs 12 px: no flow, no targets
            return Output(frame=index, response=0.0)
        levels = pyramid(gray)
        if not self._frames or self._frames[-1][0].shape != cur.shape:
            self._frames.clear()
            self._tracks = []
            self._frames.append((cur, gray, self.clock))
            self._levels = levels
            return Output(frame=index, response=0.0)
        if self._dis is None:
            self._dis = cv2.DISOpticalFlow_create(_PRESETS[p.preset])
        n = min(p.baseline, len(self._frames))
        flow = self._dis.calc(self._frames[-n][0], cur, None)
        k = self.clock - self._frames[-n][2]     # the flow's baseline in frame intervals (the real time)
        cam = camera_motion(flow, k, p.grid, p.camera_tolerance * k, p.second_layer)
        self.flow, self.camera = flow, cam
        self.foe = focus_of_expansion(flow, p.grid, p.min_foe_flow * k)
        self._steps += 1
        self._follow(levels, cam, w, h)
        self._merge()
        self._past_levels = self._past_warped = None
        self._candidates(divergence(flow, gray, cam, k, p.cell, p.min_gradient) / k, cam, gray, levels, index)
        self._frames.append((cur, gray, self.clock))
        self._levels = levels
        focal = focal_length(w, self.hfov_deg)
        if tp.heading is not None:                         # the heading in working pixels
            tp = tp.replace(heading=self._work_point(tp.heading))
        out = [estimate(t, tp, self.fps, index, (h, w), focal) for t in self._tracks]
        for t, o in zip(self._tracks, out):
            if o.looming:
                t.loomed = self._steps
        alive = [self._steps - max(t.seen, t.loomed) <= p.idle_frames for t in self._tracks]
        self._tracks = [t for t, a in zip(self._tracks, alive) if a]
        targets = tuple(sorted((o for o, a in zip(out, alive) if a), key=Target.urgency))
        response = max((t.expansion or 0.0 for t in targets), default=0.0)
        warn = any(t.warning for t in targets)
        return Output(frame=index, response=float(max(response, 0.0)), collision=warn, spike=warn, targets=targets)

    def _half(self, t: Track) -> float:
        return self.params.margin * t.size / 2.0 + 3.0

    def _follow(self, levels, cam, w: int, h: int) -> None:
        """Move and grow every target with its own flow (step 4); drop the lost ones."""
        p, tp = self.params, self.target_params
        turning = cam is not None and cam.turning((w - 1) / 2.0, (h - 1) / 2.0, w)
        kept = []
        for t in self._tracks:
            of = object_flow(self._levels, levels, t.cx, t.cy, self._half(t), cam, n=p.patch, window=p.window,
                             layer_iterations=p.layer_iterations, max_expansion=p.max_expansion,
                             min_gradient=p.min_gradient)
            move = None if of is None else \
                (of.dx, of.dy, math.exp(of.kx), math.exp(of.ky), 0.5 * (of.kx + of.ky), of.ky - of.kx)
            # refit: towards the object's layer; the camera's share of the box's motion: a stabilised course
            if t.follow(move, self.clock, self.fps, (h, w), tp.max_fails, box=None if of is None else of.box,
                        refit=p.refit, camera=cam if turning else None, interval=self.interval):
                kept.append(t)
        self._tracks = kept

    def _merge(self) -> None:
        """Two targets are one object when most of the smaller box lies in the larger: keep the
        one with the latest looming evidence, else the older."""
        out: list[Track] = []
        for t in sorted(self._tracks, key=lambda t: (-t.loomed, t.id)):
            host = next((o for o in out if o.overlap(t) >= 0.5), None)
            if host is None:
                out.append(t)
            else:
                host.seen = max(host.seen, t.seen)
        self._tracks = out

    def _candidates(self, div: np.ndarray, cam, gray, levels, index: int) -> None:
        """Regions that expand faster than the camera's motion (step 3; ``div``: per frame, the
        camera's removed): claimed by a target, or new ones."""
        p, tp = self.params, self.target_params
        c = p.cell
        spread = 1.4826 * float(np.median(np.abs(div - np.median(div))))
        mask = (div > max(p.min_divergence, p.noise_k * spread)).astype(np.uint8)
        # the outermost cells: new content enters there when the camera turns, and DIS's
        # flow at the frame's border is least reliable
        mask[0] = mask[-1] = 0
        mask[:, 0] = mask[:, -1] = 0
        n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        regions = []
        for r in range(1, n):
            x0, y0, bw, bh, area = (int(v) for v in stats[r])
            if area >= p.min_cells:
                regions.append((area, (x0 + bw / 2.0) * c - 0.5, (y0 + bh / 2.0) * c - 0.5, bw * c, bh * c))
        ready = len(self._frames) >= tp.change_frames
        # a target claims the regions around it while it grows alike in both directions (one
        # on the background, or on the ground ahead, neither hides nor keeps alive an object's
        # regions)
        growing = [t for t in self._tracks if _grew(t, tp)]
        for _, x, y, bw, bh in sorted(regions, reverse=True):       # the largest first
            owners = [t for t in growing if t.contains(x, y, 0.25 * t.size + p.claim)]
            if owners:
                for t in owners:
                    t.seen = self._steps
                continue
            if not ready or len(self._tracks) >= p.max_targets:
                continue
            box = change_box(self._still_past(cam), gray, int(round(x)), int(round(y)), int(tp.max_shift))
            if box is None or max(abs(box[0] - x), abs(box[1] - y)) > tp.max_shift:
                if max(bw, bh) > 2 * tp.max_shift:      # no compact object (change_box's window)
                    continue
                box = (x, y, float(bw), float(bh))
            t = _FlowTrack(self._next, index, *box)
            if any(o.overlap(t) >= 0.5 for o in self._tracks) or not self._grows(t, levels, cam):
                continue
            t.history = deque([Observation(self.clock, 0.0, t.cx, t.cy, t.w, 0.0)], maxlen=tp.window)   # ox = oy = 0
            t.seen = self._steps
            self._next += 1
            self._tracks.append(t)

    def _still_past(self, cam: CameraMotion | None) -> np.ndarray:
        """The frame ``change_frames`` back, warped by the camera's motion since (once per frame):
        what changed between it and this frame is the objects' own motion."""
        if self._past_warped is None:
            c = self.target_params.change_frames
            past, then = self._frames[-c][1:]
            self._past_warped = past
            if cam is not None:
                h, w = past.shape
                xs, ys = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
                uc, vc = cam.flow(xs, ys, self.clock - then)     # over the real time since
                if max(float(np.abs(uc).max()), float(np.abs(vc).max())) > 0.05:
                    self._past_warped = cv2.remap(past, (xs - uc).astype(np.float32), (ys - vc).astype(np.float32),
                                                  cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        return self._past_warped

    def _grows(self, t: Track, levels, cam) -> bool:
        """Whether the candidate's own flow over the last ``change_frames`` frames grew by
        ``min_growth``, alike in both directions (``max_anisotropy``), as the LPLC2 family's
        candidates must (:class:`mlplc2.targets.TargetParams`)."""
        p, tp = self.params, self.target_params
        if tp.min_growth <= 0:
            return True
        if self._past_levels is None:
            self._past_levels = pyramid(self._frames[-tp.change_frames][1])
        span = self.clock - self._frames[-tp.change_frames][2]     # frame intervals since that frame
        of = object_flow(self._past_levels, levels, t.cx, t.cy, self._half(t), cam, frames=span,
                         n=p.patch, window=p.window, layer_iterations=p.layer_iterations,
                         max_expansion=span * p.max_expansion, min_gradient=p.min_gradient)
        if of is None:
            return False
        g = 0.5 * (of.kx + of.ky)
        return g >= tp.min_growth and abs(of.ky - of.kx) <= tp.max_anisotropy * g
