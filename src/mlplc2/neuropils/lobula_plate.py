"""Lobula plate: local motion in four directions (Eq. 11) and its magnitude (Eq. 12)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LocalMotion", "leaky_relu", "local_motion"]


@dataclass(frozen=True)
class LocalMotion:
    """The lobula-plate maps of one frame (float32, shape (H, W)).

    ``r, l, d, u`` are LM_r, LM_l, LM_d, LM_u of Eq. 11 (after the gain);
    ``magnitude`` is LM of Eq. 12.
    """

    r: np.ndarray
    l: np.ndarray  # noqa: E741 - the paper's name
    d: np.ndarray
    u: np.ndarray
    magnitude: np.ndarray

    def direction(self, name: str) -> np.ndarray:
        return getattr(self, name)


def leaky_relu(x: np.ndarray, slope: float) -> np.ndarray:
    """f of Eq. 11: x where x >= 0, slope * x otherwise."""
    return np.where(x >= 0, x, np.float32(slope) * x).astype(np.float32, copy=False)


def _opponent(t4_a, t4_b, t5_a, t5_b, gamma_on, gamma_off):
    a = np.maximum(t4_a, 0) ** np.float32(gamma_on) + np.maximum(t5_a, 0) ** np.float32(gamma_off)
    b = np.maximum(t4_b, 0) ** np.float32(gamma_on) + np.maximum(t5_b, 0) ** np.float32(gamma_off)
    return a - b


def local_motion(t4: dict[str, np.ndarray], t5: dict[str, np.ndarray], *, gamma_on: float,
                 gamma_off: float, leaky_slope: float, gain: float) -> LocalMotion:
    """Eq. 11-12.

    r = T4_r^gamma_1 + T5_r^gamma_2 (T4/T5 rectified first, NOTES 10), likewise
    l, d, u; LM_r = gain * f(r - l), LM_l = gain * f(l - r), LM_d, LM_u the same
    vertically; H = max(LM_r, LM_l), V = max(LM_d, LM_u), LM = sqrt(H^2 + V^2).
    """
    g = np.float32(gain)
    horiz = _opponent(t4["r"], t4["l"], t5["r"], t5["l"], gamma_on, gamma_off)
    vert = _opponent(t4["d"], t4["u"], t5["d"], t5["u"], gamma_on, gamma_off)
    lm_r = g * leaky_relu(horiz, leaky_slope)
    lm_l = g * leaky_relu(-horiz, leaky_slope)
    lm_d = g * leaky_relu(vert, leaky_slope)
    lm_u = g * leaky_relu(-vert, leaky_slope)
    h = np.maximum(lm_r, lm_l)
    v = np.maximum(lm_d, lm_u)
    return LocalMotion(lm_r, lm_l, lm_d, lm_u, np.sqrt(h * h + v * v))
