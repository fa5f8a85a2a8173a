"""The presynaptic front end of the LPLC2 family: Eq. 1-12, frame by frame.

``FrontEnd.step(gray)`` runs retina -> lamina -> medulla -> lobula plate on
one grey frame (float32, 0-255) and returns the :class:`LocalMotion` maps.
All state between frames is held explicitly in :class:`FrontEndState`.

:class:`FrontEnd` is the plain reference implementation (the tests' oracle);
:func:`mlplc2.backend.make_frontend` picks the fast one (:class:`mlplc2.neuropils._fast.FastFrontEnd`:
OpenCV + fused Numba kernels, same results to ~1e-6) by default. This module imports
neither: the fast one imports :func:`set_coefficients` from here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .lamina import gaussian_kernel_1d, on_off, vdog
from .lobula_plate import LocalMotion, local_motion
from .medulla import DIRECTIONS, contrast_normalise, lowpass_alpha, motion_detectors
from ..camera import warp
from ..params import Params
from .retina import photoreceptors

__all__ = ["FrontEnd", "FrontEndState", "set_coefficients", "use_interval"]


@dataclass
class FrontEndState:
    """Everything the front end remembers from the previous frame."""

    p_prev: np.ndarray | None = None
    """P(t-1), the previous grey frame (Eq. 1)."""
    onoff_prev: tuple[np.ndarray, np.ndarray] | None = None
    """ON/OFF of the previous frame (only used with an after-image, Eq. 5)."""
    n_prev: dict[str, np.ndarray] = field(default_factory=dict)
    """Contrast-normalised N(t-1) per channel ('on', 'off'), for the delays of Eq. 8."""
    m_prev: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    """M-hat(t-1) per channel and direction, for Eq. 10."""


def set_coefficients(front_end, params: Params, fps: float) -> None:
    """Give a front end its ``params``, ``fps`` and the filter coefficients both
    implementations share: the delay coefficients ``alphas`` (Eq. 8, one per sampling
    distance) and ``alpha_out`` (Eq. 10) (:func:`mlplc2.neuropils.medulla.lowpass_alpha`), and the 1-D
    Gaussian factors ``k_e``, ``k_i``, ``k_c`` (Eq. 3)."""
    front_end.params = params
    front_end.fps = float(fps)
    front_end.alphas = tuple(lowpass_alpha(tau, front_end.fps) for tau in params.delays_ms())
    front_end.alpha_out = lowpass_alpha(params.tau_out, front_end.fps)
    front_end.interval = 1
    front_end.coefficient_cache = {1: (front_end.alphas, front_end.alpha_out)}
    front_end.k_e = gaussian_kernel_1d(params.r_e, params.sigma_e, normalise=params.normalise_kernels)
    front_end.k_i = gaussian_kernel_1d(params.r_i, params.sigma_i, normalise=params.normalise_kernels)
    front_end.k_c = gaussian_kernel_1d(params.r_c, params.sigma_c, normalise=params.normalise_kernels)


def use_interval(front_end, interval: float) -> bool:
    """The delay coefficients of Eq. 8 and 10 for a frame ``interval`` frame intervals (1 / fps
    each) after the last: alpha = tau_i / (tau_i + tau) with tau_i = 1000 ``interval`` / fps ms,
    the real interval (``docs/model.md``, "Time"). Cached per interval: the same interval again
    costs nothing. True when the coefficients changed."""
    if interval == front_end.interval:
        return False
    cache = front_end.coefficient_cache
    coeffs = cache.get(interval)
    if coeffs is None:
        if len(cache) > 64:      # a variable rate: forget all but the nominal interval's
            cache = front_end.coefficient_cache = {1: cache[1]}
        rate = front_end.fps / interval
        coeffs = cache[interval] = (tuple(lowpass_alpha(tau, rate) for tau in front_end.params.delays_ms()),
                                    lowpass_alpha(front_end.params.tau_out, rate))
    front_end.alphas, front_end.alpha_out = coeffs
    front_end.interval = interval
    return True


class FrontEnd:
    """Reference implementation of Eq. 1-12 in plain NumPy/OpenCV (``backend="reference"``).

    Parameters
    ----------
    params : Params
        Model parameters (Table I).
    fps : float
        Frame rate; the frame interval tau_i = 1000 / fps ms sets the delay
        coefficients alpha = tau_i / (tau_i + tau) of Eq. 8 and 10.
    """

    backend = "reference"

    def __init__(self, params: Params, fps: float):
        set_coefficients(self, params, fps)
        self.state = FrontEndState()

    def reset(self) -> None:
        self.state = FrontEndState()

    def compensate(self, homography: np.ndarray, gray: np.ndarray) -> None:
        """Gaze stabilisation: carry the state of the previous frame into this frame's pixels.

        ``homography`` maps the previous frame onto this one (the camera's rotation,
        :meth:`mlplc2.camera.CameraMotion.homography`); ``gray`` is this frame, which fills the
        uncovered border of P(t-1) (no change where nothing was seen before). The delayed signals
        N(t-1) and M-hat(t-1) of Eq. 8-10 (and the after-image of Eq. 5) follow, zero where uncovered.
        Call it before :meth:`step` of the frame; a still camera never calls it (nothing resampled).
        """
        st = self.state
        if st.p_prev is None:
            return
        st.p_prev = warp(st.p_prev, homography, fill=gray)
        if st.onoff_prev is not None:
            st.onoff_prev = tuple(warp(a, homography) for a in st.onoff_prev)
        st.n_prev = {c: warp(a, homography) for c, a in st.n_prev.items()}
        st.m_prev = {c: {d: warp(a, homography) for d, a in ms.items()} for c, ms in st.m_prev.items()}

    def step(self, gray: np.ndarray, interval: float = 1) -> LocalMotion:
        """Eq. 1-12 on ``gray``, taken ``interval`` frame intervals (1 / fps) after the last frame."""
        use_interval(self, interval)
        p, st = self.params, self.state
        l = photoreceptors(gray, st.p_prev)                       # Eq. 1
        st.p_prev = gray
        lv = vdog(l, self.k_e, self.k_i, p.w_i)                  # Eq. 2-4
        on, off = on_off(lv, st.onoff_prev, p.after_image)       # Eq. 5
        if p.after_image:
            st.onoff_prev = (on, off)
        t = {}
        for channel, signal in (("on", on), ("off", off)):
            n = contrast_normalise(signal, self.k_c, p.epsilon, p.n_floor, p.n_floor_radius)  # Eq. 6-7
            n_prev = st.n_prev.get(channel)
            if n_prev is None:
                n_prev = np.zeros_like(n)
                st.m_prev[channel] = {k: np.zeros_like(n) for k in DIRECTIONS}
            t[channel], st.m_prev[channel] = motion_detectors(   # Eq. 8-10
                n, n_prev, st.m_prev[channel], self.alphas, self.alpha_out, p.beta,
                p.average_distances)
            st.n_prev[channel] = n
        return local_motion(t["on"], t["off"], gamma_on=p.gamma_on,   # Eq. 11-12
                            gamma_off=p.gamma_off, leaky_slope=p.leaky_slope, gain=p.lm_gain)
