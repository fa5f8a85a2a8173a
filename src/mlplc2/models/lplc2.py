"""The LPLC2 family: MLPLC2 (multiple attention fields), SLPLC2 (one roaming
field) and LPLC2 (one fixed cell spanning the frame), sharing one front end."""

from __future__ import annotations

from collections import deque
from dataclasses import replace

import numpy as np

from ..camera import CameraMotion, MotionEstimator
from ..neuropils.attention import AttentionField, argmax_outside, gate_area, lplc2_response, quadrant_areas
from ..backend import resolve
from ..neuropils.lobula_plate import LocalMotion
from ..params import Params
from ..targets import TargetLayer, TargetParams, check_hfov, count_down, focal_length
from .base import WORK_WIDTH, Model, Output, register
from .gaze import GazeStabilisation

__all__ = ["MLPLC2", "SLPLC2", "LPLC2"]


class _LPLC2Family(GazeStabilisation, Model):
    """Shared machinery: front end (Eq. 1-12) + attention-field bookkeeping + the target layer."""

    # min_size 3 (the base's): a field needs a centre row and column plus one pixel per quadrant.
    # Frames smaller than the filter windows (11 and 23 px) or than a field (2 R_AF + 1 = 81 px)
    # are numerically safe (zero borders; every output finite, tested), but the default
    # parameters are meant for about 320x240.
    has_fields = True
    localises = True
    has_targets = True
    stabilises = True

    def __init__(self, fps: float = 30.0, params: Params | None = None, *, hfov_deg: float | None = None,
                 target_params: TargetParams | None = None, backend: str = "auto",
                 repeat_threshold: float | str | None = "auto", work_width: int | None = WORK_WIDTH,
                 stabilise: bool = False):
        params = self._check_params(params, Params, "params", "mlplc2.Params")
        target_params = self._check_params(target_params, TargetParams, "target_params", "mlplc2.targets.TargetParams")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        self.hfov_deg = check_hfov(hfov_deg)
        """Horizontal field of view (degrees) of the camera, or None. Given: targets carry their
        bearing (``Target.azimuth_deg`` / ``elevation_deg``); time to contact and course need none."""
        self.target_params = target_params
        impl = resolve(backend)
        self.backend = impl.name
        """Implementation in use: "numba" (fast, the default) or "reference" (:mod:`mlplc2.backend`)."""
        self.frontend = impl.frontend(params, self.fps)
        self._quadrant_sums = impl.quadrant_sums
        self._edge_kernel = impl.edge_kernel
        self._align_kernel = impl.align_kernel
        self._change_kernel = impl.change_kernel
        self._fields: list[AttentionField] = []
        self._next_id = 1                                  # id of the next field (1, 2, ...)
        self.maps: LocalMotion | None = None
        """The lobula-plate maps (LM_r, LM_l, LM_d, LM_u, LM) of the last frame, for inspection."""
        self._layer: TargetLayer | None = None
        self.stabilise = bool(stabilise)
        """Gaze stabilisation (docs/model.md, "Camera motion"): the camera's rotation is estimated
        every frame (:class:`mlplc2.camera.MotionEstimator`) and the front end's state, the fields
        and the targets are carried into the new frame's pixels before it is processed, so that
        the model sees what a camera that does not turn would see. False: the paper's model."""
        self._camera = MotionEstimator(hfov_deg=hfov_deg) if self.stabilise else None
        self.camera_motion: CameraMotion | None = None
        """The camera's motion measured at the last frame (with ``stabilise``), else None."""

    def _front(self, gray: np.ndarray) -> LocalMotion:
        """Eq. 1-12 on ``gray``, after gaze stabilisation when the model has it."""
        if self._camera is not None:
            self._stabilise(gray)
        lm = self.frontend.step(gray, self.interval)
        if self._camera is not None and self._layer is not None:   # the kept images' turns, beside Eq. 13-16
            self._layer.carry_ahead(self.clock)
        self.maps = lm
        return lm

    def _stabilise(self, gray: np.ndarray) -> None:
        """Carry the state into this frame's pixels when the camera turned (:attr:`stabilise`)."""
        hom = self._turn(gray, gray.shape)
        if hom is None:
            return
        self.frontend.compensate(hom, gray)
        self._carry_fields(hom, gray.shape)
        if self._layer is not None:
            self._layer.compensate(hom, gray)

    def _carry_fields(self, hom: np.ndarray, shape: tuple[int, int]) -> None:
        """Move each attention field's centre with the camera's turn (homography ``hom``), so that a field
        stays on the part of the world it answers to (mLPLC2's fields, sLPLC2's roaming field)."""
        h, w = shape
        for f in self._fields:
            x, y, z = hom @ np.array([f.x, f.y, 1.0])
            f.x = int(min(max(round(x / z), 0), w - 1))
            f.y = int(min(max(round(y / z), 0), h - 1))

    def _hold(self, last: Output, elapsed: float) -> Output:
        """A repeated frame: the targets' times to contact count down (:func:`~mlplc2.targets.count_down`)."""
        return replace(last, targets=count_down(last.targets, elapsed))

    def _reset(self) -> None:
        self.frontend.reset()
        self._fields = []
        self._next_id = 1
        self.maps = None
        self._layer = None
        if self._camera is not None:
            self._camera.reset()
        self.camera_motion = None

    # -- field bookkeeping ---------------------------------------------------
    def _new_field(self, x: int, y: int, index: int, radius: int) -> AttentionField:
        p = self.params
        f = AttentionField(id=self._next_id, x=int(x), y=int(y), born=index, radius=radius,
                           history=deque(maxlen=max(p.d, p.alarm_window)))
        self._next_id += 1
        self._fields.append(f)
        return f

    def _integrate(self, f: AttentionField, lm: LocalMotion) -> None:
        """Eq. 14-15 for one field, plus its alarm state."""
        p = self.params
        f.quadrants = self._quadrant_sums(lm, f.x, f.y, f.radius, p.field_shape)
        areas = quadrant_areas(f.x, f.y, f.radius, lm.magnitude.shape, p.field_shape)
        f.response = lplc2_response(f.quadrants, [p.q_min * gate_area(a, p.r_af) for a in areas])
        f.history.append(f.response)
        recent = list(f.history)[-p.alarm_window:]
        f.collision = sum(recent) >= p.alarm_threshold

    def _survivors(self, index: int) -> list[AttentionField]:
        """Eq. 16: the fields kept at frame ``index``; a field ``grace`` frames old or more (frames given, held
        repeats included: a time, as the paper's model, which steps every frame, would judge it) whose responses
        over the last ``d`` processed frames sum under ``t_d`` is removed, but never the last field (the one whose
        kept responses sum highest stays, the oldest of equals)."""
        p = self.params
        keep = [f for f in self._fields if not (index - f.born >= p.grace and sum(list(f.history)[-p.d:]) < p.t_d)]
        if not keep and self._fields:
            keep = [max(self._fields, key=lambda f: (sum(f.history), -f.born))]
        return keep

    def _output(self, gray, index: int) -> Output:
        """This frame's fields, and the targets the target layer makes of them."""
        if self._layer is None:
            tp = self.target_params
            if tp.heading is not None:                     # the heading in working pixels
                tp = tp.replace(heading=self._work_heading())
            self._layer = TargetLayer(tp, self.fps, kernel=self._edge_kernel, align_kernel=self._align_kernel,
                                      change_kernel=self._change_kernel,
                                      focal=focal_length(gray.shape[1], self.hfov_deg))
        targets = self._layer.step(gray, self.maps, self._fields, index, self.clock)
        fields = tuple(f.snapshot() for f in self._fields)
        response = max((f.response for f in fields), default=0.0)
        collision = any(f.collision for f in fields)
        return Output(frame=index, response=response, fields=fields, collision=collision,
                      spike=collision, targets=targets)


@register("mlplc2")
class MLPLC2(_LPLC2Family):
    """mLPLC2: LPLC2 ensemble with bottom-up multiple attention (Algorithm 1).

    Parameters
    ----------
    fps : float
        Frame rate of the input (sets the frame interval tau_i of Eq. 8 and 10).
    params : Params, optional
        Model parameters; by default ``Params()``: Table I's values but ``epsilon``, and the extras
        (docs/model.md, "Deviations from the paper, in one list").
    hfov_deg : float, optional, keyword-only
        Horizontal field of view of the camera in degrees: targets then carry their bearing
        (``Target.azimuth_deg``, ``elevation_deg``). Time to contact and miss need none.
    stabilise : bool, keyword-only
        Gaze stabilisation (docs/model.md, "Camera motion"): the camera's rotation is estimated
        every frame and the state is carried into the new frame's pixels before the front end.
        False (the default): none, as in the paper, which also steps every frame at its own size
        (``repeat_threshold=None, work_width=None``; ``mlplc2 reproduce`` holds the duplicated frames of
        the paper's clips, docs/reproduce.md).
    target_params : mlplc2.targets.TargetParams, optional, keyword-only
        Settings of the target layer: time to contact, course, warning (``docs/targets.md``).
    backend : {"auto", "numba", "reference"}, keyword-only
        Implementation (:mod:`mlplc2.backend`): the fast OpenCV + Numba one by default, the
        plain reference one on request or when Numba is unavailable (it never imports
        Numba). Both give the same fields; the LM maps agree to ~1e-6. The neuropil modules
        (:mod:`mlplc2.neuropils`) are the reference: an edit there changes ``"reference"`` only.
    repeat_threshold : float, "auto" or None, keyword-only
        Which frames are repeats the model holds instead of stepping (duplicated frames of a
        frame-rate conversion; docs/model.md, "Repeated frames"): ``"auto"`` (the default) decides
        from the frames themselves, a number is the largest change (grey levels) of a repeat, None
        steps every frame.
    work_width : int or None, keyword-only
        Frames wider than this (px; default 320, the paper's videos) are reduced to it, keeping
        their aspect, before the front end; outputs stay in the frame's own pixels. None: every
        frame at its own size (docs/model.md, "Working width").

    Attributes
    ----------
    maps : LocalMotion or None
        The lobula-plate maps of the last frame (``LM_r``, ``LM_l``, ``LM_d``, ``LM_u`` and
        ``LM``, Eq. 11-12, at the working size), for inspection; None before the first frame.
    backend : str
        The implementation in use, ``"numba"`` or ``"reference"``.

    Examples
    --------
    >>> import numpy as np, mlplc2
    >>> model = mlplc2.MLPLC2(fps=30.0)
    >>> out = model.step(np.zeros((120, 160), np.uint8))
    >>> out.response, out.fields, out.targets
    (0.0, (), ())
    """

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p = self.params
        lm = self._front(gray)
        # Eq. 13: at most one new field per frame, at the largest LM outside all fields.
        if len(self._fields) < p.max_fields:
            # A responding field also claims the blurred edges just beyond it (``exclusion``).
            zones = [(f.x, f.y, round(p.exclusion * f.radius) if f.response > 0 else f.radius)
                     for f in self._fields]
            cand = argmax_outside(lm.magnitude, zones, p.field_shape)
            if cand is not None and cand[2] > p.t_a:
                self._new_field(cand[0], cand[1], index, p.r_af)
        # Eq. 14-15 for every field, then Eq. 16 removal (never the last field).
        for f in self._fields:
            self._integrate(f, lm)
        self._fields = self._survivors(index)
        return self._output(gray, index)


@register("slplc2")
class SLPLC2(_LPLC2Family):
    """sLPLC2: at most one attention field (paper Sec. IV-A), born at the first frame whose LM exceeds
    T_a somewhere and centred every frame on the LM-weighted centroid of the salient motion, the pixels
    whose LM exceeds T_a (docs/model.md); on a frame without any it stays where it was."""

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p = self.params
        lm = self._front(gray)
        mag = lm.magnitude
        if not self._fields and float(mag.max()) > p.t_a:
            self._new_field(0, 0, index, p.r_af)
        if self._fields:
            f = self._fields[0]
            # Centroid of the salient local motion: LM above T_a, the level Eq. 13 calls
            # salient (docs/model.md). With every pixel weighted, a moving background
            # would pin the centroid to the frame centre.
            salient = np.where(mag > p.t_a, mag, np.float32(0))
            total = float(salient.sum(dtype=np.float64))
            if total > 0:
                h, w = mag.shape
                f.x = int(round(float(salient.sum(axis=0, dtype=np.float64) @ np.arange(w)) / total))
                f.y = int(round(float(salient.sum(axis=1, dtype=np.float64) @ np.arange(h)) / total))
            self._integrate(f, lm)
        return self._output(gray, index)


@register("lplc2")
class LPLC2(_LPLC2Family):
    """LPLC2 (Hua et al. 2022 as used in the paper): one cell at the frame centre
    whose four quadrants span the whole frame; same front end and output rule.

    Its one field sits at the frame centre whatever moves, so it does not localise
    (``localises`` False); the target layer still measures the object its cell answers to.
    """

    localises = False

    def _carry_fields(self, hom: np.ndarray, shape: tuple[int, int]) -> None:
        """Nothing: the cell is retinotopic, fixed at the centre of the frame (of the stabilised view, whose
        pixels are the new frame's), whatever the camera does. Carried with the turns, as an attention field
        is, it left the centre at the pan's rate and, pinned to the border, never answered again
        (docs/history.md, "LPLC2's cell and the paper's scenes under gaze stabilisation")."""

    def _step(self, gray: np.ndarray, index: int) -> Output:
        lm = self._front(gray)
        if not self._fields:
            h, w = gray.shape
            self._new_field(w // 2, h // 2, 0, max(h, w))
        self._integrate(self._fields[0], lm)
        return self._output(gray, index)
