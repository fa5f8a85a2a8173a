"""Medulla: contrast normalisation (Eq. 6-7) and T4/T5 motion detectors (Eq. 8-10).

T4 cells (ON channel) and T5 cells (OFF channel) are triple-correlation
Hassenstein-Reichardt detectors that sample their own position and one at a
distance s = 1..N_c in one cardinal direction, each distance with its own
("dynamic") delay, and sum over the distances.

Direction convention (``docs/model.md``, NOTES 9): the detector for direction
v at x correlates the *current* signal at the neighbour x + s v with the
delayed signals at both positions,

    M_v,s(x) = (N(x + s v) - beta N(x)) D_s(x) D_s(x + s v),

so an edge that was at x and is now at x + s v excites it. Coordinates:
x = column, y = row; "down" is increasing row, "up" decreasing row.
"""

from __future__ import annotations

import cv2
import numpy as np

from .lamina import gaussian_filter

__all__ = ["DIRECTIONS", "contrast_normalise", "local_max", "lowpass_alpha", "delayed", "shift", "correlator", "motion_detectors"]

#: Unit steps (dx, dy) of the four cardinal directions: right, left, down, up.
DIRECTIONS: dict[str, tuple[int, int]] = {"r": (1, 0), "l": (-1, 0), "d": (0, 1), "u": (0, -1)}


def contrast_normalise(n: np.ndarray, k_c: np.ndarray, epsilon: float, floor: float = 0.0,
                       floor_radius: int = 10) -> np.ndarray:
    """Eq. 6-7: N <- tanh(N / (epsilon + K_c * N)), then the relative floor: N set to 0
    where it is below ``floor`` times the largest N within ``floor_radius`` px
    (``Params.n_floor``; ``floor = 0``: the paper, no floor)."""
    n_hat = gaussian_filter(n, k_c)
    out = np.tanh(n / (np.float32(epsilon) + n_hat)).astype(np.float32, copy=False)
    if floor:
        out[out < np.float32(floor) * local_max(out, floor_radius)] = 0
    return out


def local_max(a: np.ndarray, radius: int) -> np.ndarray:
    """Largest value of ``a`` in the (2 radius + 1)^2 square around each pixel (0 outside the frame)."""
    k = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.dilate(a, k, borderType=cv2.BORDER_CONSTANT, borderValue=0)


def lowpass_alpha(tau_ms: float, fps: float) -> float:
    """Coefficient of the delays of Eq. 8 and 10 (a first-order low-pass with time constant
    ``tau_ms``): alpha = tau_i / (tau_i + tau), tau_i = 1000 / fps (the frame interval, ms)."""
    tau_i = 1000.0 / fps
    return tau_i / (tau_i + tau_ms)


def delayed(n: np.ndarray, n_prev: np.ndarray, alpha: float) -> np.ndarray:
    """Eq. 8 (and 10): two-tap delay alpha * N(t) + (1 - alpha) * N(t - 1)."""
    a = np.float32(alpha)
    return a * n + (np.float32(1) - a) * n_prev


def shift(a: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """Return b with b[y, x] = a[y + dy, x + dx], zero where that is outside the frame."""
    h, w = a.shape
    b = np.zeros_like(a)
    if abs(dx) >= w or abs(dy) >= h:
        return b
    ys_dst = slice(max(0, -dy), h - max(0, dy))
    xs_dst = slice(max(0, -dx), w - max(0, dx))
    ys_src = slice(max(0, dy), h - max(0, -dy))
    xs_src = slice(max(0, dx), w - max(0, -dx))
    b[ys_dst, xs_dst] = a[ys_src, xs_src]
    return b


def correlator(n: np.ndarray, d: np.ndarray, dx: int, dy: int, beta: float) -> np.ndarray:
    """Eq. 9: triple correlation for one direction and one sampling distance."""
    n_far = shift(n, dx, dy)
    d_far = shift(d, dx, dy)
    return (n_far - np.float32(beta) * n) * d * d_far


def motion_detectors(n: np.ndarray, n_prev: np.ndarray, m_prev: dict[str, np.ndarray],
                     alphas: tuple[float, ...], alpha_out: float, beta: float,
                     average: bool = True) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Eq. 8-10 for one channel: the four directional T4 (or T5) maps.

    ``alphas[s - 1]`` is the Eq. 8 coefficient of sampling distance s. With
    ``average`` the sum of Eq. 10 is divided by N_c (``docs/model.md``). Returns
    (T maps, M-hat maps); the latter are the state for the next frame.
    """
    m_hat = {}
    t = {}
    delayed_s = [delayed(n, n_prev, a) for a in alphas]
    for name, (ux, uy) in DIRECTIONS.items():
        total = np.zeros_like(n)
        for s, d in enumerate(delayed_s, start=1):
            total += correlator(n, d, ux * s, uy * s, beta)
        if average:
            total /= np.float32(len(alphas))
        m_hat[name] = total
        t[name] = delayed(total, m_prev[name], alpha_out)
    return t, m_hat
