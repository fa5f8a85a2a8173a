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

from .._validation import FLOAT32_MAX, Valid, check_fields
from ..neuropils.lamina import on_off
from ..neuropils.medulla import delayed, lowpass_alpha
from ..params import ParameterSet, document_parameters, param
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
@document_parameters("Parameters")
@dataclass(frozen=True)
class LGMD2Params(ParameterSet):
    """Parameters of the LGMD2 network (Fu et al., IEEE TCYB 2020; Fu & Yue 2015).

    Defaults follow Fu's open-source LGMD2 ("lgmd2OpenSource", the code of the
    TCYB paper) except where ``docs/model.md`` (Baselines) says otherwise (``a_on``, the
    biased-ON weight from the mLPLC2 authors' Python LGMD2). Time constants are
    in ms and become filter coefficients from the frame rate.

    Valid values (the table below; one-line :class:`mlplc2.InputError` otherwise): numbers
    are finite Python or NumPy scalars (not bools, strings or arrays) within float32's range,
    stored as Python floats; those that must be > 0 are at least 1.18e-38 (float32's
    smallest normal number); ``t_pm`` at least 7.5e-37 (``T_PM_MIN``); ``a_on``, ``a_off``,
    ``a_onoff`` at most 1e6 (``SUM_WEIGHT_MAX``).
    """

    dc: float = param(0.1, "Fraction of the previous ON/OFF value added to the current one (after-image).",
                      symbol="d_c", valid=Valid.real(minimum=0, below=1))
    on_kernel: tuple[float, float, float] = param(
        (2.0, 0.5, 0.25), "3x3 lateral-inhibition weights of the ON pathway (centre, 4-nearest, diagonal).",
        symbol="W_on", valid=Valid.reals(3, "centre, nearest, diagonal", minimum=0))
    off_kernel: tuple[float, float, float] = param(
        (1.0, 0.25, 0.125), "3x3 lateral-inhibition weights of the OFF pathway (centre, 4-nearest, diagonal).",
        symbol="W_off", valid=Valid.reals(3, "centre, nearest, diagonal", minimum=0))
    tau_on: tuple[float, float, float] = param(
        (15.0, 30.0, 45.0), "Delays of the ON inhibition (centre, nearest, diagonal).",
        symbol="tau_on", unit="ms", valid=Valid.reals(3, "centre, nearest, diagonal", positive=True))
    tau_off: tuple[float, float, float] = param(
        (60.0, 120.0, 180.0), "Delays of the OFF inhibition (centre, nearest, diagonal).",
        symbol="tau_off", unit="ms", valid=Valid.reals(3, "centre, nearest, diagonal", positive=True))
    recursive_delay: bool = param(False, """If False (published code) the delayed signal is
                                  alpha X(t) + (1 - alpha) X(t-1), a fractional one-frame delay; if True a
                                  recursive low-pass alpha X(t) + (1 - alpha) Y(t-1).""", valid=Valid.boolean())
    tau_pm: float = param(90.0, "Low-pass time constant of the mean luminance change PM (adaptive inhibition).",
                          symbol="tau_PM", unit="ms", valid=Valid.real(positive=True))
    t_pm: float = param(8.0, """w_on = max(w_on_base, PM / T_PM), likewise w_off. At least ``T_PM_MIN``: PM / T_PM
                        (PM, a mean |frame difference|, is at most 255) must stay within float32's range.""",
                        symbol="T_PM", unit="grey level", valid=Valid.real(minimum=T_PM_MIN))
    w_on_base: float = param(1.0, "Baseline (floor) of the adaptive ON inhibition weight w_on.",
                             symbol="w_on^0", valid=Valid.real(minimum=0))
    w_off_base: float = param(0.5, "Baseline (floor) of the adaptive OFF inhibition weight w_off.",
                              symbol="w_off^0", valid=Valid.real(minimum=0))
    a_on: float = param(0.5, "Weight of S_on in the summation S = theta_1 S_on + theta_2 S_off + theta_3 S_on S_off.",
                        symbol="theta_1", valid=Valid.real(minimum=0, maximum=SUM_WEIGHT_MAX))
    a_off: float = param(1.0, "Weight of S_off in the summation.",
                         symbol="theta_2", valid=Valid.real(minimum=0, maximum=SUM_WEIGHT_MAX))
    a_onoff: float = param(1.0, "Weight of the supra-linear S_on S_off term.",
                           symbol="theta_3", valid=Valid.real(minimum=0, maximum=SUM_WEIGHT_MAX))
    c_w: float = param(4.0, "Grouping scale w = max|Ce| / C_w + Delta_C.", symbol="C_w",
                       valid=Valid.real(positive=True))
    delta_c: float = param(0.01, "Small constant of the grouping scale.", symbol="Delta_C",
                           valid=Valid.real(positive=True))
    c_de: float = param(0.5, "Decay coefficient of the grouping threshold (G kept where G C_de >= T_de).",
                        symbol="C_de", valid=Valid.real(minimum=0))
    t_de: float = param(15.0, "Grouping (decay) threshold.", symbol="T_de", valid=Valid.real(minimum=0))
    c_sig: float = param(1.0, "Sigmoid coefficient, K = 1 / (1 + exp(-sum(G) / (N_cells C_sig))).",
                         symbol="C_sig", valid=Valid.real(positive=True))
    tau_sfa: float = param(800.0, "Time constant of the spike-frequency-adaptation high-pass.",
                           symbol="tau_SFA", unit="ms", valid=Valid.real(positive=True))
    t_sfa: float = param(0.003, "K increases larger than this reset the SFA to the high-passed K.",
                         symbol="T_SFA", valid=Valid.real(minimum=0))
    c_spi: float = param(4.0, "Spike scale, spikes = floor(exp(C_spi (K_sfa - T_sp))).",
                         symbol="C_spi", valid=Valid.real(positive=True))
    t_sp: float = param(0.78, "Spiking threshold on the adapted membrane potential.",
                        symbol="T_sp", valid=Valid.real(minimum=0))
    n_ts: int = param(8, "Collision when the spikes counted over consecutive spiking frames reach this.",
                      symbol="N_ts", unit="spikes", valid=Valid.integer(1))

    def __post_init__(self) -> None:
        check_fields(self, "LGMD2Params")


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
        self._coeffs: dict = {}
        self._use_interval(1)
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

    def _use_interval(self, interval: float) -> None:
        """The filter coefficients for a frame ``interval`` frame intervals after the last processed
        one (the real interval tau_i = 1000 ``interval`` / fps ms; ``docs/model.md``, "Time"), cached."""
        c = self._coeffs.get(interval)
        if c is None:
            if len(self._coeffs) > 64:
                self._coeffs = {1: self._coeffs[1]}
            p, rate = self.params, self.fps / interval
            c = self._coeffs[interval] = (tuple(lowpass_alpha(t, rate) for t in p.tau_on),
                                          tuple(lowpass_alpha(t, rate) for t in p.tau_off),
                                          lowpass_alpha(p.tau_pm, rate), highpass_coeff(p.tau_sfa, rate))
        self.alpha_on, self.alpha_off, self.alpha_pm, self.hp_sfa = c

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
        self._use_interval(self.interval)
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
@document_parameters("Parameters")
@dataclass(frozen=True)
class LGMD1Params(ParameterSet):
    """Parameters of the LGMD1 network (Yue & Rind, IEEE TNN 2006).

    Inhibition, grouping, spiking and FFI follow Yue & Rind (2006): their signed layers,
    the values of Fu's open-source re-implementation (``LGMDSingle``) and his LGMD2 code for
    the shared grouping layer, W_I of Sun et al.'s implementation, and C_sig = C_w (the
    grouping gain divided out); ``docs/model.md`` (Baselines, "LGMD1 ...") compares every
    value and rule with the published model.

    Valid values: the table below, numbers as for :class:`LGMD2Params`.
    """

    w_i_kernel: tuple[float, float] = param(
        (0.25, 0.125), "3x3 lateral-inhibition kernel (4-nearest, diagonal; centre 0), one-frame delay.",
        symbol="w_I", valid=Valid.reals(2, "nearest, diagonal", minimum=0))
    w_i: float = param(0.4, "Weight of the inhibition in S = E - W_I I (Sun et al.'s value).", symbol="W_I",
                       valid=Valid.real(minimum=0))
    c_w: float = param(4.0, "Grouping scale w = max|Ce| / C_w + Delta_C.", symbol="C_w",
                       valid=Valid.real(positive=True))
    delta_c: float = param(0.01, "Small constant of the grouping scale.", symbol="Delta_C",
                           valid=Valid.real(positive=True))
    c_de: float = param(0.5, "Decay coefficient of the grouping threshold.", symbol="C_de",
                        valid=Valid.real(minimum=0))
    t_de: float = param(15.0, "Grouping (decay) threshold (G kept where G C_de >= T_de).", symbol="T_de",
                        valid=Valid.real(minimum=0))
    c_sig: float = param(4.0, """Sigmoid coefficient, kappa = 1 / (1 + exp(-sum|G| / (N_cells C_sig))). The
                         published 1 with the grouping gain C_w = 4 divided out (docs/model.md, LGMD1
                         "Operating point").""", symbol="C_sig", valid=Valid.real(positive=True))
    t_sp: float = param(0.78, "Spiking threshold on kappa.", symbol="T_sp", valid=Valid.real(minimum=0))
    n_ts: int = param(5, "Collision after this many consecutive spiking frames.", symbol="n_ts", unit="frames",
                      valid=Valid.integer(1))
    t_ffi: float = param(10.0, """LGMD output suppressed when the FFI, the mean |P| of the previous frame,
                         reaches this.""", symbol="T_FFI", unit="grey level", valid=Valid.real(positive=True))
    signed: bool = param(True, """If True (default), Yue & Rind's signed layers: E = P, I from the signed
                         P(t-1), S = E - W_I I (not rectified), membrane sum over |G|, so inhibition from a
                         neighbour of the opposite polarity adds to the excitation. If False: magnitudes,
                         E = |P|, I from |P(t-1)|, S = [E - W_I I]+: inhibition always inhibits.""",
                         valid=Valid.boolean())

    def __post_init__(self) -> None:
        check_fields(self, "LGMD1Params")


@register("lgmd1")
class LGMD1(Model):
    """LGMD1 looming detector with feature enhancement and feed-forward inhibition.

    ``Output.response`` is the sigmoid membrane potential kappa (resting value
    0.5); it is held at rest while the FFI is at or above ``t_ffi``, and on the first two
    frames (before I and the FFI have a previous frame).

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
        self._steps = 0
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
        # P exists from the second frame, I and the FFI (from P(t-1)) from the third: until then
        # the membrane rests (docs/model.md, LGMD1 "Start"), so that motion already under way
        # when the input starts is not a burst of uninhibited, unsuppressed excitation
        self._steps += 1
        if suppressed or self._steps < 3:
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
