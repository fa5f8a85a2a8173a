"""Lamina: vDoG with polarity selectivity (Eq. 2-4) and the ON/OFF split (Eq. 5).

The large monocular cells (LMCs) filter the photoreceptor change L with a
narrow excitatory Gaussian K_e and a broad inhibitory Gaussian K_i (Eq. 2-3).
The vDoG is polarity selective (``docs/model.md``): the inhibition can only
shrink the excitation, never flip or enlarge it, and the output keeps the sign
of E: L_vDoG = sign(E) * max(|E| - w_i |I|, 0). Half-wave
rectification then splits it into ON (brightening) and OFF (darkening)
channels (Eq. 5).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["gaussian_kernel_1d", "gaussian_filter", "vdog", "on_off"]


def gaussian_kernel_1d(radius: int, sigma: float, *, normalise: bool = True) -> np.ndarray:
    """1-D factor of the 2-D Gaussian K of Eq. 3 on the window [-radius, radius].

    The 2-D kernel of Eq. 3 is the outer product of this vector with itself.
    With ``normalise`` the 2-D kernel sums to 1; otherwise the values are
    those of Eq. 3, ``exp(-(u^2 + v^2) / (2 sigma^2)) / (2 pi sigma^2)``.
    """
    u = np.arange(-radius, radius + 1, dtype=np.float64)
    g = np.exp(-(u**2) / (2.0 * sigma**2))
    if normalise:
        g /= g.sum()
    else:
        g /= np.sqrt(2.0 * np.pi) * sigma
    return g.astype(np.float32)


def gaussian_filter(image: np.ndarray, kernel_1d: np.ndarray) -> np.ndarray:
    """Eq. 2 (and 7): correlate ``image`` with the separable kernel (zero outside the frame: no photoreceptor, no signal)."""
    return cv2.sepFilter2D(image, cv2.CV_32F, kernel_1d, kernel_1d, borderType=cv2.BORDER_CONSTANT)


def vdog(l: np.ndarray, k_e: np.ndarray, k_i: np.ndarray, w_i: float) -> np.ndarray:
    """Eq. 2-4: vDoG with polarity selectivity, sign(E) * max(|E| - w_i |I|, 0)."""
    e = gaussian_filter(l, k_e)
    i = gaussian_filter(l, k_i)
    magnitude = np.maximum(np.abs(e) - np.float32(w_i) * np.abs(i), 0)
    return np.copysign(magnitude, e).astype(np.float32, copy=False)


def on_off(l_vdog: np.ndarray, prev: tuple[np.ndarray, np.ndarray] | None = None,
           after_image: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 5: half-wave rectification into ON = max(L, 0) and OFF = max(-L, 0).

    OFF is returned as a non-negative magnitude of darkening. ``after_image``
    adds that fraction of the previous ON/OFF values (0 in the paper).
    """
    on = np.maximum(l_vdog, 0)
    off = np.maximum(-l_vdog, 0)
    if after_image and prev is not None:
        on += np.float32(after_image) * prev[0]
        off += np.float32(after_image) * prev[1]
    return on, off
