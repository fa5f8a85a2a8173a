"""LGMD baselines: LGMD2 (Fu et al.) and LGMD1 (Yue & Rind 2006).

Both are whole-field looming detectors: one neuron integrates every pixel, so
they neither localise nor separate objects (``Output.fields`` is empty).
``docs/model.md`` (Baselines) gives the equations, the parameter sources and every choice
made where the sources differ.

* :class:`LGMD2` - Fu & Yue (2015) and Fu, Hu, Peng, Rind & Yue, "A robust
  collision perception visual neural network with specific selectivity to
  darker objects" (IEEE TCYB 2020): biased ON/OFF pathways with delayed lateral
  inhibition, adaptive inhibition, grouping, spike-frequency adaptation.
* :class:`LGMD1` - Yue & Rind, "Collision detection in complex dynamic scenes
  using an LGMD-based visual neural network with feature enhancement" (IEEE
  TNN 2006): P/E/I/S layers, grouping (feature enhancement) and feed-forward
  inhibition.

Everything is vectorised (OpenCV ``filter2D`` / ``blur`` with replicated
borders, NumPy elementwise); per-pixel state is float32, whole-field sums are
float64.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .._validation import FLOAT32_MAX, InputValueError, check_bool, check_int, check_real, check_reals
from ..neuropils.lamina import on_off
from ..neuropils.medulla import delayed, lowpass_alpha
from ..params import ParameterSet
from ..neuropils.retina import photoreceptors
from .base import WORK_WIDTH, Model, Output, register

__all__ = ["LGMD2Params", "LGMD1Params", "LGMD2", "LGMD1", "highpass_coeff",
           "stable_sigmoid", "RESTING_POTENTIAL"]

#: Sigmoid membrane potential with no input (sigmoid(0)); both models rest here.
RESTING_POTENTIAL = 0.5
#: Largest LGMD2 summation weight theta_1..3 (``a_on``, ``a_off``, ``a_onoff``; published 0.5-1):
#: the grouping layer squares S (G = S Ce) in float32, and an infinite S makes G NaN.
SUM_WEIGHT_MAX = 1e6
#: Smallest ``LGMD2Params.t_pm``: the adaptive weight PM / T_PM (PM, a mean |frame difference|,
#: is at most 255) must stay within float32's range (an infinite weight times 0 is NaN).
T_PM_MIN = 255.0 / FLOAT32_MAX

_BORDER = cv2.BORDER_REPLICATE


def highpass_coeff(tau_ms: float, fps: float) -> float:
    """Coefficient of the first-order high-pass of the SFA: tau / (tau + tau_i)."""
    tau_i = 1000.0 / fps
    return tau_ms / (tau_ms + tau_i)


def stable_sigmoid(x: float) -> float:
    """1 / (1 + exp(-x)) without overflow for any finite (or infinite) x."""
    if x >= 0:
        return 1.0 / (1.0 + math.exp(-x))
    z = math.exp(x)
    return z / (1.0 + z)


def _ring_kernels(centre: float, nearest: float, diagonal: float) -> tuple[np.ndarray, ...]:
    """Split a 3x3 kernel into its centre, 4-nearest and diagonal parts."""
    c, n, d = centre, nearest, diagonal
    return tuple(np.array(k, np.float32) for k in ([[0, 0, 0], [0, c, 0], [0, 0, 0]], [[0, n, 0], [n, 0, n], [0, n, 0]],
                                                   [[d, 0, d], [0, 0, 0], [d, 0, d]]))


def _check(cls_name: str, obj, positive=(), non_negative=(), ints=(), bools=()) -> None:
    """Validate (and store as Python floats / ints / bools) the named fields of a frozen
    parameter dataclass (``_validation.check_real`` / ``check_int`` / ``check_bool``)."""
    for name in positive:
        object.__setattr__(obj, name, check_real(getattr(obj, name), f"{cls_name}.{name}", positive=True))
    for name in non_negative:
        object.__setattr__(obj, name, check_real(getattr(obj, name), f"{cls_name}.{name}", minimum=0))
    for name in ints:
        object.__setattr__(obj, name, check_int(getattr(obj, name), f"{cls_name}.{name}", minimum=1))
    for name in bools:
        object.__setattr__(obj, name, check_bool(getattr(obj, name), f"{cls_name}.{name}"))


# ---------------------------------------------------------------------------
# Grouping layer, shared (Yue & Rind 2006 feature enhancement; Fu et al.)
# ---------------------------------------------------------------------------
def _grouping(s: np.ndarray, c_w: float, delta_c: float, c_de: float, t_de: float) -> np.ndarray:
    """Passing-coefficient grouping: Ce = 3x3 box mean of S, w = max|Ce| / C_w + Delta_C,
    G = S Ce / w, G <- 0 where G C_de < T_de."""
    ce = cv2.blur(s, (3, 3), borderType=_BORDER)
    w = float(np.abs(ce).max()) / c_w + delta_c
    g = s * ce
    g *= np.float32(1.0 / w)
    g[g * np.float32(c_de) < np.float32(t_de)] = 0.0
    return g


# ---------------------------------------------------------------------------
# LGMD2
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LGMD2Params(ParameterSet):
    """Parameters of the LGMD2 network (Fu et al., IEEE TCYB 2020; Fu & Yue 2015).

    Defaults follow Fu's open-source LGMD2 ("lgmd2OpenSource", the code of the
    TCYB paper) except where ``docs/model.md`` (Baselines) says otherwise (``a_on``, the
    biased-ON weight from the mLPLC2 authors' Python LGMD2). Time constants are
    in ms and become filter coefficients from the frame rate.

    Valid values (one-line :class:`mlplc2.InputError` otherwise): numbers are finite
    Python or NumPy scalars (not bools, strings or arrays) within float32's range,
    stored as Python floats; those that must be > 0 are at least 1.18e-38 (float32's
    smallest normal number), ``t_pm`` at least 7.5e-37 (``T_PM_MIN``); ``dc`` < 1;
    ``a_on``, ``a_off``, ``a_onoff`` <= 1e6 (``SUM_WEIGHT_MAX``); the kernels and
    delays are sequences of 3 such numbers; ``n_ts`` an integer >= 1;
    ``recursive_delay`` True or False.
    """

    dc: float = 0.1
    """d_c: fraction of the previous ON/OFF value added to the current one (after-image)."""
    on_kernel: tuple[float, float, float] = (2.0, 0.5, 0.25)
    """W_on (centre, 4-nearest, diagonal): 3x3 lateral-inhibition weights, ON pathway."""
    off_kernel: tuple[float, float, float] = (1.0, 0.25, 0.125)
    """W_off (centre, 4-nearest, diagonal): 3x3 lateral-inhibition weights, OFF pathway."""
    tau_on: tuple[float, float, float] = (15.0, 30.0, 45.0)
    """tau_on (ms; centre, nearest, diagonal): delays of the ON inhibition."""
    tau_off: tuple[float, float, float] = (60.0, 120.0, 180.0)
    """tau_off (ms; centre, nearest, diagonal): delays of the OFF inhibition."""
    recursive_delay: bool = False
    """If False (published code) the delayed signal is alpha X(t) + (1 - alpha) X(t-1), a
    fractional one-frame delay; if True a recursive low-pass alpha X(t) + (1 - alpha) Y(t-1)."""
    tau_pm: float = 90.0
    """tau_PM (ms): low-pass time constant of the mean luminance change PM (adaptive inhibition)."""
    t_pm: float = 8.0
    """T_PM (grey levels): w_on = max(w_on_base, PM / T_PM), likewise w_off."""
    w_on_base: float = 1.0
    """Baseline (floor) of the adaptive ON inhibition weight w_on."""
    w_off_base: float = 0.5
    """Baseline (floor) of the adaptive OFF inhibition weight w_off."""
    a_on: float = 0.5
    """theta_1: weight of S_on in the summation S = theta_1 S_on + theta_2 S_off + theta_3 S_on S_off."""
    a_off: float = 1.0
    """theta_2: weight of S_off in the summation."""
    a_onoff: float = 1.0
    """theta_3: weight of the supra-linear S_on S_off term."""
    c_w: float = 4.0
    """C_w: grouping scale w = max|Ce| / C_w + Delta_C."""
    delta_c: float = 0.01
    """Delta_C: small constant of the grouping scale."""
    c_de: float = 0.5
    """C_de: decay coefficient of the grouping threshold (G kept where G C_de >= T_de)."""
    t_de: float = 15.0
    """T_de: grouping (decay) threshold."""
    c_sig: float = 1.0
    """C_sig: sigmoid coefficient, K = 1 / (1 + exp(-sum(G) / (N_cells C_sig)))."""
    tau_sfa: float = 800.0
    """tau_SFA (ms): time constant of the spike-frequency-adaptation high-pass."""
    t_sfa: float = 0.003
    """T_SFA: K increases larger than this reset the SFA to the high-passed K."""
    c_spi: float = 4.0
    """C_spi: spike scale, spikes = floor(exp(C_spi (K_sfa - T_sp)))."""
    t_sp: float = 0.78
    """T_sp: spiking threshold on the adapted membrane potential."""
    n_ts: int = 8
    """N_ts (spikes): collision when the spikes counted over consecutive spiking frames reach this."""

    def __post_init__(self) -> None:
        for name in ("on_kernel", "off_kernel", "tau_on", "tau_off"):
            bound = {"positive": True} if name.startswith("tau") else {"minimum": 0}
            object.__setattr__(self, name, check_reals(getattr(self, name), f"LGMD2Params.{name}", 3,
                                                       "centre, nearest, diagonal", **bound))
        _check("LGMD2Params", self,
               positive=("tau_pm", "t_pm", "c_w", "delta_c", "c_sig", "tau_sfa", "c_spi"),
               non_negative=("dc", "w_on_base", "w_off_base", "c_de", "t_de", "t_sfa", "t_sp"),
               ints=("n_ts",), bools=("recursive_delay",))
        for name in ("a_on", "a_off", "a_onoff"):
            object.__setattr__(self, name, check_real(getattr(self, name), f"LGMD2Params.{name}", minimum=0,
                                                      maximum=SUM_WEIGHT_MAX))
        if self.dc >= 1:
            raise InputValueError(f"LGMD2Params.dc must be < 1, got {self.dc!r}")
        if self.t_pm < T_PM_MIN:
            raise InputValueError(f"LGMD2Params.t_pm must be >= {T_PM_MIN:.2g} (PM / t_pm, PM <= 255, must stay "
                                  f"within float32's range), got {self.t_pm!r}")


@register("lgmd2")
class LGMD2(Model):
    """LGMD2 looming detector with specific selectivity to darker objects.

    ``Output.response`` is the membrane potential after spike-frequency
    adaptation (resting value 0.5, below 1), the trace Fu et al. plot;
    ``collision`` is raised after ``n_ts`` spikes in consecutive spiking frames.

    Examples
    --------
    >>> import numpy as np
    >>> m = LGMD2(fps=30)
    >>> m.step(np.full((20, 20), 255, np.uint8)).response
    0.5
    """

    def __init__(self, fps: float = 30.0, params: LGMD2Params | None = None, *,
                 repeat_threshold: float | str | None = "auto", work_width: int | None = WORK_WIDTH):
        params = self._check_params(params, LGMD2Params, "params", "LGMD2Params")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        p = params
        self.alpha_on = tuple(lowpass_alpha(t, self.fps) for t in p.tau_on)
        self.alpha_off = tuple(lowpass_alpha(t, self.fps) for t in p.tau_off)
        self.alpha_pm = lowpass_alpha(p.tau_pm, self.fps)
        self.hp_sfa = highpass_coeff(p.tau_sfa, self.fps)
        self._k_on = _ring_kernels(*p.on_kernel)
        self._k_off = _ring_kernels(*p.off_kernel)
        self._reset()

    def _reset(self) -> None:
        self._gray_prev: np.ndarray | None = None
        self._on_prev: np.ndarray | None = None
        self._off_prev: np.ndarray | None = None
        self._on_delay: list[np.ndarray] | None = None
        self._off_delay: list[np.ndarray] | None = None
        self._pm = 0.0
        self._k_prev = RESTING_POTENTIAL
        self._sfa_prev = RESTING_POTENTIAL
        self._n_spikes = 0
        self.state: dict = {}
        """Scalars of the last frame (pm, w_on, w_off, sum_g, k, k_sfa, spikes), for inspection."""

    def _inhibition(self, x, x_prev, delayed_prev, alphas, kernels):
        total = None
        out = []
        for a, k, y_prev in zip(alphas, kernels, delayed_prev):
            d = delayed(x, y_prev if self.params.recursive_delay else x_prev, a)   # the lamina's Eq. 8 delay
            out.append(d)
            conv = cv2.filter2D(d, cv2.CV_32F, k, borderType=_BORDER)
            total = conv if total is None else total + conv
        return total, out

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p = self.params
        pr = photoreceptors(gray, self._gray_prev)
        self._gray_prev = gray
        if self._on_prev is None:
            zeros = np.zeros_like(gray)
            self._on_prev, self._off_prev = zeros, zeros
            self._on_delay, self._off_delay = [zeros] * 3, [zeros] * 3

        # adaptive inhibition from the low-passed mean luminance change
        pm_now = float(np.abs(pr).mean(dtype=np.float64))
        self._pm = self.alpha_pm * pm_now + (1.0 - self.alpha_pm) * self._pm
        w_on = max(p.w_on_base, self._pm / p.t_pm)
        w_off = max(p.w_off_base, self._pm / p.t_pm)

        # ON/OFF half-wave rectification with after-image (the lamina's Eq. 5)
        on, off = on_off(pr, (self._on_prev, self._off_prev), p.dc)

        inh_on, self._on_delay = self._inhibition(on, self._on_prev, self._on_delay, self.alpha_on, self._k_on)
        inh_off, self._off_delay = self._inhibition(off, self._off_prev, self._off_delay, self.alpha_off,
                                                    self._k_off)
        self._on_prev, self._off_prev = on, off

        s_on = np.maximum(on - np.float32(w_on) * inh_on, 0)
        s_off = np.maximum(off - np.float32(w_off) * inh_off, 0)
        s = np.float32(p.a_on) * s_on + np.float32(p.a_off) * s_off + np.float32(p.a_onoff) * s_on * s_off

        g = _grouping(s, p.c_w, p.delta_c, p.c_de, p.t_de)
        sum_g = float(g.sum(dtype=np.float64))
        k = stable_sigmoid(sum_g / (g.size * p.c_sig))

        # spike-frequency adaptation (high-pass of K, floored at rest)
        diff = k - self._k_prev
        k_sfa = self.hp_sfa * (self._sfa_prev + diff) if diff <= p.t_sfa else self.hp_sfa * k
        k_sfa = max(k_sfa, RESTING_POTENTIAL)
        self._k_prev, self._sfa_prev = k, k_sfa

        spikes = int(math.floor(math.exp(min(p.c_spi * (k_sfa - p.t_sp), 50.0))))
        self._n_spikes = self._n_spikes + spikes if spikes > 0 else 0
        collision = self._n_spikes >= p.n_ts
        self.state = dict(pm=self._pm, w_on=w_on, w_off=w_off, sum_g=sum_g, k=k, k_sfa=k_sfa, spikes=spikes)
        return Output(frame=index, response=float(k_sfa), fields=(), collision=bool(collision),
                      spike=spikes > 0)


# ---------------------------------------------------------------------------
# LGMD1
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LGMD1Params(ParameterSet):
    """Parameters of the LGMD1 network (Yue & Rind, IEEE TNN 2006).

    Inhibition, grouping, spiking and FFI follow Yue & Rind (2006) with the values
    of Fu's open-source re-implementation (``LGMDSingle``) and his LGMD2 code for
    the shared grouping layer; ``docs/model.md`` (Baselines, "LGMD1 ...") compares every
    value and rule with the published model.

    Valid values: as for :class:`LGMD2Params` (``w_i_kernel`` 2 numbers >= 0, ``signed``
    True or False).
    """

    w_i_kernel: tuple[float, float] = (0.25, 0.125)
    """w_I (4-nearest, diagonal): 3x3 lateral-inhibition kernel (centre 0), one-frame delay."""
    w_i: float = 0.6
    """W_I: weight of the inhibition in S = E - W_I I."""
    c_w: float = 4.0
    """C_w: grouping scale w = max|Ce| / C_w + Delta_C."""
    delta_c: float = 0.01
    """Delta_C: small constant of the grouping scale."""
    c_de: float = 0.5
    """C_de: decay coefficient of the grouping threshold."""
    t_de: float = 15.0
    """T_de: grouping (decay) threshold (G kept where G C_de >= T_de)."""
    c_sig: float = 1.0
    """C_sig: sigmoid coefficient, kappa = 1 / (1 + exp(-sum|G| / (N_cells C_sig)))."""
    t_sp: float = 0.78
    """T_sp: spiking threshold on kappa."""
    n_ts: int = 5
    """n_ts (frames): collision after this many consecutive spiking frames."""
    t_ffi: float = 10.0
    """T_FFI (grey levels): LGMD output suppressed when the FFI, the mean |P| of the previous
    frame, reaches this."""
    signed: bool = False
    """If True, Yue & Rind's signed layers: E = P, I from the signed P(t-1), S = E - W_I I
    (not rectified), membrane sum over |G|, so inhibition from a neighbour of the opposite
    polarity adds to the excitation. If False (default, a documented deviation): magnitudes,
    E = |P|, I from |P(t-1)|, S = [E - W_I I]+: inhibition always inhibits."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "w_i_kernel", check_reals(self.w_i_kernel, "LGMD1Params.w_i_kernel", 2,
                                                           "nearest, diagonal", minimum=0))
        _check("LGMD1Params", self, positive=("c_w", "delta_c", "c_sig", "t_ffi"),
               non_negative=("w_i", "c_de", "t_de", "t_sp"), ints=("n_ts",), bools=("signed",))


@register("lgmd1")
class LGMD1(Model):
    """LGMD1 looming detector with feature enhancement and feed-forward inhibition.

    ``Output.response`` is the sigmoid membrane potential kappa (resting value
    0.5); it is held at rest while the FFI is at or above ``t_ffi``.

    Examples
    --------
    >>> import numpy as np
    >>> LGMD1().step(np.zeros((10, 10))).response
    0.5
    """

    # min_size 3 (the base's): the lateral inhibition and grouping here and in LGMD2 are 3x3 neighbourhoods.

    def __init__(self, fps: float = 30.0, params: LGMD1Params | None = None, *,
                 repeat_threshold: float | str | None = "auto", work_width: int | None = WORK_WIDTH):
        params = self._check_params(params, LGMD1Params, "params", "LGMD1Params")
        super().__init__(fps=fps, params=params, repeat_threshold=repeat_threshold, work_width=work_width)
        kn, kd = params.w_i_kernel
        self._kernel = np.array([[kd, kn, kd], [kn, 0.0, kn], [kd, kn, kd]], np.float32)
        self._reset()

    def _reset(self) -> None:
        self._gray_prev: np.ndarray | None = None
        self._p_prev: np.ndarray | None = None
        self._n_spikes = 0
        self.state: dict = {}
        """Scalars of the last frame (ffi, suppressed, sum_g, kappa), for inspection."""

    def _step(self, gray: np.ndarray, index: int) -> Output:
        p = self.params
        pr = photoreceptors(gray, self._gray_prev)
        self._gray_prev = gray
        p_prev = np.zeros_like(pr) if self._p_prev is None else self._p_prev
        self._p_prev = pr
        e_prev = np.abs(p_prev)

        ffi = float(e_prev.mean(dtype=np.float64))
        suppressed = ffi >= p.t_ffi
        if suppressed:
            sum_g = 0.0
        else:
            w_i = np.float32(p.w_i)
            if p.signed:
                s = pr - w_i * cv2.filter2D(p_prev, cv2.CV_32F, self._kernel, borderType=_BORDER)
            else:
                s = np.maximum(np.abs(pr) - w_i * cv2.filter2D(e_prev, cv2.CV_32F, self._kernel,
                                                               borderType=_BORDER), 0)
            g = _grouping(s, p.c_w, p.delta_c, p.c_de, p.t_de)
            sum_g = float(np.abs(g).sum(dtype=np.float64))
        kappa = stable_sigmoid(sum_g / (pr.size * p.c_sig))
        spike = kappa >= p.t_sp
        self._n_spikes = self._n_spikes + 1 if spike else 0
        collision = self._n_spikes >= p.n_ts
        self.state = dict(ffi=ffi, suppressed=suppressed, sum_g=sum_g, kappa=kappa)
        return Output(frame=index, response=float(kappa), fields=(), collision=bool(collision),
                      spike=bool(spike))
