"""One place for checking user input (frames, fps, sizes).

Every check raises a subclass of :class:`InputError` with a one-line message.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["InputError", "InputValueError", "InputTypeError", "as_gray", "check_fps"]

#: Rec. 601 luma weights for RGB -> grey (retina input, NOTES 2).
LUMA_RGB = np.array([0.299, 0.587, 0.114], dtype=np.float32)


class InputError(Exception):
    """Base class of every error about bad input (frames, files, arguments)."""


class InputValueError(InputError, ValueError):
    """An input with the right type but a wrong value (shape, size, NaN, ...)."""


class InputTypeError(InputError, TypeError):
    """An input of the wrong type (non-numeric dtype, not an array, ...)."""


def check_fps(fps) -> float:
    """Return ``fps`` as a float, or raise if it is not a positive finite number."""
    try:
        value = float(fps)
    except (TypeError, ValueError):
        raise InputTypeError(f"fps must be a number, got {fps!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise InputValueError(f"fps must be a positive finite number, got {fps!r}")
    return value


def as_gray(frame, *, min_size: int = 1, name: str = "frame") -> np.ndarray:
    """Convert a frame to a C-contiguous float32 grey image on the 0-255 scale.

    Accepted input: ``(H, W)`` grey, ``(H, W, 3)`` RGB or ``(H, W, 4)`` RGBA
    (alpha ignored). ``uint8`` and float arrays are taken as 0-255 already;
    ``uint16`` is divided by 257 (65535 -> 255); other integer types are taken
    as 0-255 and clipped. NaN or infinite pixels are rejected. The input array
    is never modified (read-only and non-contiguous arrays are fine).
    """
    if not isinstance(frame, np.ndarray):
        try:
            frame = np.asarray(frame)
        except Exception:  # noqa: BLE001 - anything unconvertible is a type error
            raise InputTypeError(f"{name} must be a numpy array, got {type(frame).__name__}") from None
    kind = frame.dtype.kind
    if kind not in "uif":
        raise InputTypeError(f"{name} must have a numeric dtype (uint8, uint16 or float), got {frame.dtype}")
    if frame.ndim == 3:
        channels = frame.shape[2]
        if channels not in (1, 3, 4):
            raise InputValueError(
                f"{name} must have 1, 3 (RGB) or 4 (RGBA) channels, got {channels} (shape {frame.shape})")
    elif frame.ndim != 2:
        raise InputValueError(f"{name} must be 2-D (H, W) or 3-D (H, W, C), got shape {frame.shape}")
    h, w = frame.shape[:2]
    if h < min_size or w < min_size:
        raise InputValueError(f"{name} is {w}x{h} pixels; the model needs at least {min_size}x{min_size}")
    if kind == "f":
        if not np.isfinite(frame).all():
            raise InputValueError(f"{name} contains NaN or infinite pixels")
        scale = 1.0
    elif frame.dtype == np.uint16:
        scale = 1.0 / 257.0
    else:
        scale = 1.0
    if frame.ndim == 3:
        if frame.shape[2] == 1:
            gray = frame[:, :, 0].astype(np.float32)
        else:
            rgb = frame[:, :, :3].astype(np.float32)
            gray = rgb @ LUMA_RGB
    else:
        gray = frame.astype(np.float32, copy=True)
    if scale != 1.0:
        gray *= np.float32(scale)
    if kind in "iu" and frame.dtype not in (np.uint8, np.uint16):
        np.clip(gray, 0, 255, out=gray)
    return np.ascontiguousarray(gray)
