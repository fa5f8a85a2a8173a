"""A classical optical-flow baseline (not part of the paper): ``flow``.

What a robotics engineer would build instead of a bio-inspired model, measured on the same
benchmark with the same camera motion, tracker, course and warning as the LPLC2 family, so
that the benchmark compares the front ends (``docs/flow.md`` has the equations, the choices
and the figures). Per frame:

1. **Camera motion** (:class:`mlplc2.camera.MotionEstimator`, the LPLC2 family's): the
   camera's rotation since the last frame; when it turned, the frames kept and the target
   layer's state are carried into this frame's pixels (gaze stabilisation, always on).
2. **Frame flow.** Dense optical flow ``F`` (OpenCV's DIS, Kroeger et al. 2016;
   ``FlowParams.preset``) from the frame ``baseline`` frames back to this one.
3. **Candidate regions** (:func:`divergence`, :func:`regions`): where the divergence of ``F``
   exceeds ``min_divergence`` and the frame's noise.
4. **Targets**: the regions are the front end's candidates and looming evidence for the
   target layer (:class:`mlplc2.targets.TargetLayer`), as the attention fields are the LPLC2
   family's: a region under a target is its evidence (an answering field), one outside every
   target a seed. The layer finds the box, checks that it grows, follows it, fits the time to
   contact and the course and warns (:func:`mlplc2.targets.estimate`).

It has no attention fields; its alarm (``Output.collision``) is "any target warns" and its
response the largest expansion rate (1/s).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from typing import ClassVar

import cv2
import numpy as np

from .._validation import Valid, check_fields
from ..backend import resolve
from ..camera import CameraMotion, MotionEstimator, check_hfov, focal_length, warp
from ..params import ParameterSet, document_parameters, param, param_of
from ..targets.alignment import sample_patch
from ..targets.change import change_box
from ..targets.layer import TargetLayer
from ..targets.warning import count_down
from ..targets.params import TargetParams
from .base import WORK_WIDTH, Model, Output, register
from .gaze import GazeStabilisation

__all__ = ["FlowTTC", "FlowParams", "Region", "ObjectFlow", "object_flow", "divergence", "regions"]

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
    """Parameters of the optical-flow baseline's front end (:class:`FlowTTC`); the tracker,
    time to contact, course and warning settings are the targets' (:class:`mlplc2.targets.TargetParams`)."""

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
    min_divergence: float = param(0.006, """A cell is a candidate when the divergence of the flow exceeds this
                                  per frame (0.006 = a time to contact of 11 s at 30 fps) ...""",
                                  unit="1/frame", valid=Valid.real(minimum=0))
    noise_k: float = param(4.0, """... and by this many times the frame's robust spread of the divergence
                           (1.4826 x the median absolute deviation over the cells).""",
                           valid=Valid.real(minimum=0))
    min_cells: int = param(1, "Fewest connected cells that make a candidate region.", unit="cells",
                           valid=Valid.integer(1))
    patch: int = param(48, "Side of the resampled patch a target's own flow is computed on (the growth evidence).",
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

    def __post_init__(self) -> None:
        check_fields(self, "FlowParams")


# ---------------------------------------------------------------------------
# stage functions
# ---------------------------------------------------------------------------
def divergence(flow: np.ndarray, gray: np.ndarray, cell: int, min_gradient: float) -> np.ndarray:
    """The divergence ``du/dx + dv/dy`` (Sobel / 8) of the flow, averaged over cells of
    ``cell`` px; zero where ``gray`` has no structure (the Gaussian-averaged gradient energy
    below ``min_gradient ** 2``; DIS's flow there is noise)."""
    h, w = flow.shape[:2]
    g = np.asarray(gray, np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    energy = cv2.GaussianBlur(gx * gx + gy * gy, (0, 0), 1.0)
    res = np.asarray(flow, np.float32) * (energy >= np.float32(min_gradient) ** 2)[..., None]
    du = cv2.Sobel(res[..., 0], cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    dv = cv2.Sobel(res[..., 1], cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    return cv2.resize(du + dv, (max(w // cell, 1), max(h // cell, 1)), interpolation=cv2.INTER_AREA)


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


def _patch(levels: list[np.ndarray], cx: float, cy: float, half: float, n: int) -> tuple[np.ndarray, float]:
    """The ``n + 2 PAD`` square of samples centred on (cx, cy), spacing ``s = 2 half / n`` px, bilinear
    (:func:`mlplc2.targets.alignment.sample_patch`, the image alignment's sampler) from the pyramid level whose
    pixel is at most 1.5 samples (the coarsest such: :func:`~mlplc2.targets.align` takes the finest level whose
    samples are at most 1.5 px); returns it and ``s``."""
    s = 2.0 * half / n
    level = 0
    while level + 1 < len(levels) and 2 ** (level + 1) <= 1.5 * s:
        level += 1
    out, _ = sample_patch(levels, level, cx, cy, s, s, n + 2 * PAD)
    return out, s


def object_flow(prev: list[np.ndarray], cur: list[np.ndarray], cx: float, cy: float, half: float, *,
                n: int = 48, window: int = 5, layer_iterations: int = 3, max_expansion: float = 0.3,
                min_gradient: float = 3.0) -> ObjectFlow | None:
    """The expansion and shift of the object in the square of half-side ``half`` px around
    (cx, cy) from ``prev`` to ``cur`` (two :func:`mlplc2.targets.pyramid` s, the camera's rotation
    taken out: the background is still): docs/flow.md, step 4. None when the patch has too little
    structure, lies outside the frame, or the fit exceeds ``max_expansion``.
    """
    h, w = cur[0].shape
    a, s = _patch(prev, cx, cy, half, n)
    b, _ = _patch(cur, cx, cy, half, n)
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
    rc = np.abs(normal)                      # how well the still background explains each sample
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
    # twice as well as the still background (where the two nearly agree a sample could be either)
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


@dataclass(frozen=True)
class Region:
    """A candidate region of the frame flow, what the target layer takes as a field seed:
    ``id``, centre ``x``, ``y`` and ``radius`` (half its larger side) in px, ``box`` (centre,
    width, height: its cells), its largest ``divergence`` per frame. Its ``response`` is 0: a
    region is a seed, not looming evidence (a target of ``flow`` warns on sustained growth,
    ``TargetParams.confirm_frames``)."""

    id: int
    x: int
    y: int
    radius: int
    box: tuple[float, float, float, float]
    divergence: float
    response: ClassVar[float] = 0.0


def regions(div: np.ndarray, params: FlowParams, first_id: int = 1) -> list[Region]:
    """The candidate regions of ``div`` (per frame, cells of ``params.cell`` px): 8-connected
    cells with ``div > max(min_divergence, noise_k x 1.4826 MAD(div))``, at least ``min_cells``
    of them, the frame's outermost cells left out (new content enters there when the camera
    turns, and DIS's flow at the border is least reliable); the largest first, ids from ``first_id``."""
    p, c = params, params.cell
    spread = 1.4826 * float(np.median(np.abs(div - np.median(div))))
    mask = (div > max(p.min_divergence, p.noise_k * spread)).astype(np.uint8)
    mask[0] = mask[-1] = 0
    mask[:, 0] = mask[:, -1] = 0
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    found = []
    for r in range(1, n):
        x0, y0, bw, bh, area = (int(v) for v in stats[r])
        if area >= p.min_cells:
            x, y = (x0 + bw / 2.0) * c - 0.5, (y0 + bh / 2.0) * c - 0.5
            found.append((area, x, y, float(bw * c), float(bh * c), float(div[labels == r].max())))
    found.sort(key=lambda r: -r[0])
    return [Region(first_id + i, int(round(x)), int(round(y)), int(max(bw, bh) // 2), (x, y, bw, bh), top)
            for i, (_, x, y, bw, bh, top) in enumerate(found)]


@register("flow")
class FlowTTC(GazeStabilisation, Model):
    """Optical-flow time to contact (a classical baseline, not the paper's): see the module docstring.

    Parameters
    ----------
    fps : float
    params : FlowParams, optional
    hfov_deg : float, optional, keyword-only
        Horizontal field of view (degrees): targets carry their bearing; the camera-motion
        estimate assumes 60 degrees without it (:class:`mlplc2.camera.MotionEstimator`).
    target_params : mlplc2.targets.TargetParams, optional, keyword-only
        Tracker, TTC, course and warning settings (the same defaults as the LPLC2 family's targets).

    Examples
    --------
    >>> import numpy as np, mlplc2
    >>> model = mlplc2.get_model("flow")(fps=30.0)
    >>> model.step(np.zeros((120, 160), np.uint8)).targets
    ()
    """

    has_targets = True
    #: the flow baseline always compensates the camera's rotation (docs/model.md, "Camera motion")
    stabilise = True

    def __init__(self, fps: float = 30.0, params: FlowParams | None = None, *, hfov_deg: float | None = None,
                 target_params: TargetParams | None = None, repeat_threshold: float | str | None = "auto",
                 work_width: int | None = WORK_WIDTH):
        params = self._check_params(params, FlowParams, "params", "mlplc2.models.flow.FlowParams")
        target_params = self._check_params(target_params, TargetParams, "target_params", "mlplc2.targets.TargetParams")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        self.hfov_deg = check_hfov(hfov_deg)
        self.target_params = target_params
        impl = resolve("auto")
        self._align_kernel = impl.align_kernel
        self._change_kernel = impl.change_kernel
        self._camera = MotionEstimator(hfov_deg=hfov_deg)
        self._reset()

    def _hold(self, last: Output, elapsed: float) -> Output:
        """A repeated frame: the targets' times to contact count down (:func:`~mlplc2.targets.count_down`)."""
        return replace(last, targets=count_down(last.targets, elapsed))

    def _reset(self) -> None:
        self._frames: deque = deque(maxlen=self.params.baseline)   # (uint8 frame, clock, seen), in this frame's pixels
        self._dis = None
        self._layer: TargetLayer | None = None
        self._next_region = 1
        self._camera.reset()
        self.camera_motion: CameraMotion | None = None
        """The camera's motion measured at the last frame (:class:`mlplc2.camera.CameraMotion`:
        rotation, heading), None before the first frame."""
        self.flow: np.ndarray | None = None
        """The last frame flow (H, W, 2): from ``baseline`` frames back (fewer in the first
        frames), the camera's rotation taken out."""

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_dis"] = None                 # OpenCV objects do not pickle; rebuilt on the next frame
        return state

    def _measure(self, prev: list[np.ndarray], cur: list[np.ndarray], t, half: float, frames: float):
        """The target layer's growth evidence (``TargetLayer(measure=...)``): the object's own flow
        (:func:`object_flow`) from ``prev`` to ``cur``, ``frames`` frames apart, as the layer's
        move (shift, factors on width and height, log-scale and log-anisotropy gained); the box
        moves ``refit`` of the way to the object's layer (shrinking only), the growth is the fit's."""
        p = self.params
        of = object_flow(prev, cur, t.cx, t.cy, half, n=p.patch, window=p.window,
                         layer_iterations=p.layer_iterations, max_expansion=frames * p.max_expansion,
                         min_gradient=p.min_gradient)
        if of is None:
            return None
        dx, dy, fx, fy = of.dx, of.dy, math.exp(of.kx), math.exp(of.ky)
        if of.box is not None and p.refit > 0:       # the box settles on the object's layer
            bx, by, bw, bh = of.box
            dx += p.refit * (bx - t.cx - dx)
            dy += p.refit * (by - t.cy - dy)
            fx *= min(max(bw, 1.0) / (t.w * fx), 1.0) ** p.refit
            fy *= min(max(bh, 1.0) / (t.h * fy), 1.0) ** p.refit
        return dx, dy, fx, fy, 0.5 * (of.kx + of.ky), of.ky - of.kx

    def _stabilise(self, gray: np.ndarray, cur: np.ndarray) -> None:
        """Gaze stabilisation, as the LPLC2 family's (docs/model.md, "Camera motion"): when the
        camera turned, the frames kept and the target layer are carried into this frame's pixels."""
        hom = self._turn(cur, gray.shape)
        if hom is None:
            return
        ones = np.ones(cur.shape, np.float32)
        kept = [(warp(img, hom, fill=cur), clock, warp(ones if seen is None else seen, hom, fill=0.0))
                for img, clock, seen in self._frames]
        self._frames.clear()
        self._frames.extend(kept)
        if self._layer is not None:
            self._layer.compensate(hom, gray)

    def _refine(self, region: Region, past: np.ndarray, cur: np.ndarray) -> Region:
        """The region's box is the region that changed around it since the flow's earlier frame
        (:func:`mlplc2.targets.change.change_box`, the layer's own box of a faint candidate) when
        there is one near it: an object's whole outline, tight on a small object (its cells are
        whole 8-px cells) and not one edge of a larger one; else its cells (a background that
        changes everywhere, e.g. the ground of a forward drive, has no compact changed region)."""
        box = change_box(past, cur, region.x, region.y, int(self.target_params.max_shift), kernel=self._change_kernel)
        if box is None or max(abs(box[0] - region.x), abs(box[1] - region.y)) > self.target_params.max_shift:
            return region
        return replace(region, box=box)

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p = self.params
        cur = np.rint(gray).astype(np.uint8)    # gray is on 0-255 already (as_gray)
        gray = cur.astype(np.float32)            # one input for every stage: an RGB frame of equal channels
                                                 # answers exactly as its grey level (testing.check_channels)
        h, w = cur.shape
        if min(h, w) < MIN_FLOW_SIZE:            # DIS needs 12 px: no flow, no targets
            return Output(frame=index, response=0.0)
        if self._frames and self._frames[-1][0].shape != cur.shape:
            self._reset()
        if self._layer is None:
            tp = self.target_params
            if tp.heading is not None:                     # the heading in working pixels
                tp = tp.replace(heading=self._work_heading())
            self._layer = TargetLayer(tp, self.fps, align_kernel=self._align_kernel, change_kernel=self._change_kernel,
                                      focal=focal_length(w, self.hfov_deg), measure=self._measure)
        self._stabilise(gray, cur)
        found: list[Region] = []
        if self._frames:
            if self._dis is None:
                self._dis = cv2.DISOpticalFlow_create(_PRESETS[p.preset])
            past, then, seen = self._frames[0]
            k = self.clock - then                # the flow's baseline in frame intervals (the real time)
            self.flow = self._dis.calc(past, cur, None)
            div = divergence(self.flow, gray, p.cell, p.min_gradient) / k
            if seen is not None:                 # what the turn uncovered since: no flow of its own
                cells = cv2.resize(seen, div.shape[::-1], interpolation=cv2.INTER_AREA) >= 0.999
                div[cv2.erode(cells.astype(np.uint8), np.ones((5, 5), np.uint8)) == 0] = 0.0
            found = [self._refine(r, past, cur) for r in regions(div, p, self._next_region)]
            self._next_region += len(found)
        self._frames.append((cur, self.clock, None))
        targets = tuple(replace(t, fields=()) for t in self._layer.step(gray, None, found, index, self.clock))
        response = max((t.expansion or 0.0 for t in targets), default=0.0)
        warn = any(t.warning for t in targets)
        return Output(frame=index, response=float(max(response, 0.0)), collision=warn, spike=warn, targets=targets)
