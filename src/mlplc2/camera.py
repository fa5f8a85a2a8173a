"""The camera: pinhole geometry (focal length, bearing), in one place for the models and the stimuli.

Bearing convention: azimuth positive to the right, elevation positive up,
``azimuth = atan((x - cx) / f)``, ``elevation = atan((cy - y) / f)`` with
``(cx, cy) = ((W - 1) / 2, (H - 1) / 2)`` in pixel-index coordinates (the centre
of pixel column ``i`` is at ``x = i``) and ``f = (W / 2) / tan(hfov / 2)``.
"""

from __future__ import annotations

import math

from ._validation import check_real

__all__ = ["check_hfov", "focal_length", "bearing"]


def check_hfov(hfov_deg, *, required: bool = False) -> float | None:
    """Validate a horizontal field of view in degrees, in (0, 180); None (unknown) unless ``required``."""
    if hfov_deg is None and not required:
        return None
    return check_real(hfov_deg, "hfov_deg", positive=True, below=180)


def focal_length(width: int, hfov_deg: float | None) -> float | None:
    """Pinhole focal length in px, ``(W / 2) / tan(hfov / 2)``; None when ``hfov_deg`` is None (unknown)."""
    hfov = check_hfov(hfov_deg)
    if hfov is None:
        return None
    return (width / 2.0) / math.tan(math.radians(hfov) / 2.0)


def bearing(x: float, y: float, shape: tuple[int, int], focal: float | None) -> tuple[float, float]:
    """(azimuth, elevation) of pixel (x, y): degrees given ``focal`` (px), else px offsets.

    Azimuth positive right, elevation positive up; the optical axis passes
    through ((W - 1) / 2, (H - 1) / 2).
    """
    h, w = shape
    dx = x - (w - 1) / 2.0
    dy = (h - 1) / 2.0 - y
    if focal is None:
        return float(dx), float(dy)
    return math.degrees(math.atan2(dx, focal)), math.degrees(math.atan2(dy, focal))
