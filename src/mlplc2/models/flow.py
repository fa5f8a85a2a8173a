"""A classical optical-flow baseline (not part of the paper): ``flow``.

What a robotics engineer would reach for instead of a bio-inspired model, measured on the
same benchmark with the same warning rule:

1. dense optical flow between the previous frame and this one (OpenCV's DIS, Kroeger et al.
   2016; preset ``FlowParams.preset``);
2. the camera's own image motion, a global affine flow fitted robustly to a grid of the flow
   vectors (``cv2.estimateAffine2D``, RANSAC): a pan or tilt is its translation, forward
   ego-motion its expansion about the focus of expansion (FOE, the fixed point of the affine
   map, :attr:`FlowTTC.foe`);
3. the expansion of the flow, its divergence ``du/dx + dv/dy`` averaged over cells of
   ``cell`` px: an object approaching at constant speed expands at ``d(log s)/dt = div / 2``,
   i.e. ``ttc = 2 / div``;
4. candidate regions: connected cells that expand faster than the camera's own motion does
   there (by ``min_divergence`` per frame); each is followed from frame to frame (the box
   moves with the mean flow in it and is re-fitted to the region), its log-scale accumulates
   ``div / 2`` per frame, and the same estimator as the LPLC2 family's targets
   (:func:`mlplc2.targets.estimate`: ``1 / S`` line, course, horizon, miss) gives ``ttc_s``,
   ``miss`` and the warning, with looming evidence = sustained growth (``confirm_frames``).

It has no attention fields; its alarm (``Output.collision``) is "any target warns" and its
response the largest expansion rate (1/s).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .._validation import InputTypeError, Valid, check_fields
from ..params import ParameterSet, document_parameters, param
from ..targets import Target, TargetParams, Track, check_hfov, count_down, estimate, focal_length
from .base import WORK_WIDTH, Model, Output, register

__all__ = ["FlowTTC", "FlowParams"]

#: Smallest frame side (px) DIS computes a flow for; smaller frames give no targets.
MIN_FLOW_SIZE = 12
_PRESETS = {"ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST, "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
            "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM}


@document_parameters("Parameters")
@dataclass(frozen=True)
class FlowParams(ParameterSet):
    """Parameters of the optical-flow baseline (:class:`FlowTTC`); the warning and TTC
    settings are the targets' (:class:`mlplc2.targets.TargetParams`)."""

    preset: str = param("medium", "DIS optical flow preset (speed against accuracy).",
                        valid=Valid.choice(*_PRESETS))
    cell: int = param(8, "Side of the cells the divergence is averaged over.", unit="px", valid=Valid.integer(2))
    min_divergence: float = param(0.006, """A cell is a candidate when its divergence exceeds the camera's own
                                  there by this much (per frame; 0.006 = a time to contact of 11 s at 30 fps).""",
                                  unit="1/frame", valid=Valid.real(minimum=0))
    min_cells: int = param(3, "Fewest connected cells that make a candidate region.", unit="cells",
                           valid=Valid.integer(1))
    grid: int = param(8, "Spacing of the flow vectors the global (camera) motion is fitted to.", unit="px",
                      valid=Valid.integer(1))
    max_targets: int = param(12, "Upper bound on simultaneous targets.", unit="targets", valid=Valid.integer(0))
    idle_frames: int = param(10, "Frames a target lives without a candidate region under it.", unit="frames",
                             valid=Valid.integer(0))

    def __post_init__(self) -> None:
        check_fields(self, "FlowParams")


def _expansion(flow: np.ndarray, cx: float, cy: float, hw: float, hh: float):
    """Least-squares ``u = sx (x - cx) + tx``, ``v = sy (y - cy) + ty`` over the box of half-sizes
    (hw, hh) around (cx, cy): the horizontal and vertical expansion rates (d log size per frame)
    and the shift (tx, ty)."""
    h, w = flow.shape[:2]
    x0, x1 = int(max(round(cx - hw), 0)), int(min(round(cx + hw) + 1, w))
    y0, y1 = int(max(round(cy - hh), 0)), int(min(round(cy + hh) + 1, h))
    if x1 - x0 < 2 or y1 - y0 < 2:
        return 0.0, 0.0, (0.0, 0.0)
    f = flow[y0:y1, x0:x1]
    xs = np.arange(x0, x1, dtype=np.float32) - np.float32(cx)
    ys = np.arange(y0, y1, dtype=np.float32) - np.float32(cy)
    u, v = f[..., 0], f[..., 1]
    mx, my = float(xs.mean()), float(ys.mean())
    mu, mv = float(u.mean()), float(v.mean())
    dx, dy = xs - mx, ys - my
    den_x, den_y = float((dx * dx).sum()) * len(ys), float((dy * dy).sum()) * len(xs)
    sx = float((u * dx[None, :]).sum()) / den_x if den_x > 0 else 0.0
    sy = float((v * dy[:, None]).sum()) / den_y if den_y > 0 else 0.0
    return sx, sy, (mu - sx * mx, mv - sy * my)


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
        params = FlowParams() if params is None else params
        if not isinstance(params, FlowParams):
            raise InputTypeError(f"params must be mlplc2.models.flow.FlowParams, got {type(params).__name__}")
        target_params = TargetParams() if target_params is None else target_params
        if not isinstance(target_params, TargetParams):
            raise InputTypeError(f"target_params must be mlplc2.targets.TargetParams, got {type(target_params).__name__}")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        self.hfov_deg = check_hfov(hfov_deg)
        self.target_params = target_params
        self._reset()

    def _reset(self) -> None:
        self._prev: np.ndarray | None = None
        self._dis = None
        self._tracks: list[Track] = []
        self._next = 1
        self.foe: tuple[float, float] | None = None
        """The focus of expansion of the camera's own motion in the last frame (px), None without one."""
        self.flow: np.ndarray | None = None
        """The last frame's dense flow (H, W, 2), for inspection."""

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_dis"] = None                 # OpenCV objects do not pickle; rebuilt on the next frame
        return state

    def _camera_motion(self, flow: np.ndarray):
        """The global affine flow (2 x 3, ``x' = A x + t``) of a grid of flow vectors, or None."""
        g = self.params.grid
        h, w = flow.shape[:2]
        ys, xs = np.mgrid[g // 2:h:g, g // 2:w:g]
        src = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float32)
        dst = src + flow[ys.ravel(), xs.ravel()]
        if len(src) < 6:
            return None
        m, _ = cv2.estimateAffine2D(src, dst, method=cv2.RANSAC, ransacReprojThreshold=0.5, maxIters=200,
                                    confidence=0.99, refineIters=5)
        return m

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p, tp = self.params, self.target_params
        cur = np.rint(gray).astype(np.uint8)    # gray is on 0-255 already (as_gray)
        h, w = cur.shape
        if min(h, w) < MIN_FLOW_SIZE:            # DIS needs 12 px: no flow, no targets
            return Output(frame=index, response=0.0)
        if self._prev is None or self._prev.shape != cur.shape:
            self._prev = cur
            return Output(frame=index, response=0.0)
        if self._dis is None:
            self._dis = cv2.DISOpticalFlow_create(_PRESETS[p.preset])
        flow = self._dis.calc(self._prev, cur, None)
        self._prev = cur
        self.flow = flow
        # expansion per cell: divergence of the flow, and of the camera's own (affine) motion
        du = cv2.Sobel(flow[..., 0], cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
        dv = cv2.Sobel(flow[..., 1], cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
        c = p.cell
        gh, gw = max(h // c, 1), max(w // c, 1)
        div = cv2.resize(du + dv, (gw, gh), interpolation=cv2.INTER_AREA)
        m = self._camera_motion(flow)
        own = 0.0
        self.foe = None
        if m is not None:
            a = m[:, :2] - np.eye(2)
            own = float(a[0, 0] + a[1, 1])
            try:
                self.foe = tuple(float(v) for v in np.linalg.solve(a, -m[:, 2]))
            except np.linalg.LinAlgError:
                self.foe = None
        mask = (div - own > p.min_divergence).astype(np.uint8)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        regions = []
        for k in range(1, n):
            x0, y0, bw, bh, area = (int(v) for v in stats[k])
            if area < p.min_cells:
                continue
            d = float(div[labels == k].mean())
            regions.append(((x0 + bw / 2.0) * c - 0.5, (y0 + bh / 2.0) * c - 0.5, bw * c, bh * c, d))
        # follow the tracks: move with the mean flow in the box, grow by exp(div / 2)
        used = set()
        kept = []
        for t in self._tracks:
            best = None
            for i, r in enumerate(regions):
                if i in used:
                    continue
                if abs(r[0] - t.cx) <= (r[2] + t.w) / 2 and abs(r[1] - t.cy) <= (r[3] + t.h) / 2:
                    if best is None or r[2] * r[3] > regions[best][2] * regions[best][3]:
                        best = i
            # the flow in the box's inner part, fitted by a similarity: u = s (x - cx) + tx (and v):
            # the divergence averaged over a box that holds the whole object would be ~0 (the
            # flux through a border where the background is still)
            rx, ry, shift = _expansion(flow, t.cx, t.cy, 0.375 * t.w, 0.375 * t.h)
            rate = 0.5 * (rx + ry)
            t.cx += shift[0]
            t.cy += shift[1]
            t.w *= math.exp(rx)
            t.h *= math.exp(ry)
            if best is not None:
                used.add(best)
                r = regions[best]
                t.cx, t.cy = 0.7 * t.cx + 0.3 * r[0], 0.7 * t.cy + 0.3 * r[1]
                t.w, t.h = 0.7 * t.w + 0.3 * r[2], 0.7 * t.h + 0.3 * r[3]
                t.last_seen = index
            t.log_s += rate
            t.aniso += ry - rx
            t.rate = rate * self.fps
            t.history.append((index, t.log_s, t.cx, t.cy, t.w, t.aniso))
            if not (0 <= t.cx <= w - 1 and 0 <= t.cy <= h - 1) or index - t.last_seen > p.idle_frames:
                continue
            kept.append(t)
        self._tracks = kept
        for i, r in enumerate(regions):
            if i in used or len(self._tracks) >= p.max_targets:
                continue
            t = Track(self._next, index, r[0], r[1], r[2], r[3])
            t.history = deque([(index, 0.0, t.cx, t.cy, t.w, 0.0)], maxlen=tp.window)
            t.last_seen = index
            self._next += 1
            self._tracks.append(t)
        focal = focal_length(w, self.hfov_deg)
        # looming evidence is sustained growth only (no attention field can answer)
        targets = tuple(sorted((estimate(t, tp, self.fps, index, (h, w), focal) for t in self._tracks),
                               key=Target.urgency))
        response = max((t.expansion or 0.0 for t in targets), default=0.0)
        warn = any(t.warning for t in targets)
        return Output(frame=index, response=float(max(response, 0.0)), collision=warn, spike=warn, targets=targets)

    def _hold(self, last: Output, elapsed: float) -> Output:
        return replace(last, targets=count_down(last.targets, elapsed))

