"""Retina: photoreceptor layer, Eq. 1 of the paper.

Each photoreceptor holds the grey-level brightness P(x, y, t) (0-255 scale,
colour converted to luminance by :func:`mlplc2._validation.as_gray`) and
outputs the change since the previous frame.
"""

from __future__ import annotations

import numpy as np

__all__ = ["photoreceptors"]


def photoreceptors(p: np.ndarray, p_prev: np.ndarray | None) -> np.ndarray:
    """Eq. 1: L(x, y, t) = P(x, y, t) - P(x, y, t - 1).

    On the first frame (``p_prev is None``) there is no change: L = 0.
    """
    if p_prev is None:
        return np.zeros_like(p, dtype=np.float32)
    return np.subtract(p, p_prev, dtype=np.float32)
