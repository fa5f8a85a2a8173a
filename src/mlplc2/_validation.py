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
    """Convert a frame to a new C-contiguous float32 grey image on the 0-255 scale.

    Accepted input
        ``(H, W)`` grey, ``(H, W, 1)``, ``(H, W, 3)`` RGB or ``(H, W, 4)`` RGBA
        (alpha ignored), at least ``min_size`` pixels high and wide; a numpy
        array or anything :func:`numpy.asarray` turns into a numeric array
        (nested lists of numbers). RGB becomes grey with the Rec. 601 weights.

    Scaling to the 0-255 scale the model thresholds assume
        * ``uint8``: as is.
        * ``uint16``: divided by 257, so 65535 -> 255.
        * other integer types (``int8`` ... ``uint64``): taken as 0-255 and
          clipped to [0, 255].
        * float (``float16`` ... ``longdouble``): taken as 0-255 (not 0-1: a
          0-1 image must be multiplied by 255 first) and clipped to [0, 255],
          so extreme values cannot overflow the model's float32 state.

    Rejected, with :class:`InputTypeError`: non-numeric dtypes (object, str,
    bytes, datetime, void, complex) and ``bool`` (ambiguous: 0/1 or 0/255;
    convert first); with :class:`InputValueError`: a wrong number of
    dimensions or channels, a frame smaller than ``min_size``, NaN or infinite
    pixels (never silently replaced) and masked arrays with masked pixels.

    The input array is never modified (read-only, non-contiguous and
    Fortran-ordered arrays are fine): the result is always a new array.
    """
    if not isinstance(frame, np.ndarray):
        try:
            arr = np.asarray(frame)
        except Exception:  # noqa: BLE001 - anything unconvertible is a type error
            arr = None
        if arr is None or arr.dtype.kind not in "biufc":
            raise InputTypeError(f"{name} must be a numpy array of numbers, got {type(frame).__name__}")
        frame = arr
    elif isinstance(frame, np.ma.MaskedArray):
        if np.ma.is_masked(frame):
            raise InputValueError(f"{name} is a masked array with masked pixels; fill them first "
                                  f"(e.g. {name}.filled(0))")
        frame = np.ma.getdata(frame)
    dtype = frame.dtype
    kind = dtype.kind
    if kind == "b":
        raise InputTypeError(f"{name} has dtype bool, which is ambiguous (0/1 or 0/255); "
                             f"convert it first, e.g. {name}.astype(np.uint8) * 255")
    if kind not in "uif":
        raise InputTypeError(f"{name} must have a numeric dtype (uint8, uint16, other integers or float), "
                             f"got {dtype}")
    if frame.ndim == 3:
        channels = frame.shape[2]
        if channels not in (1, 3, 4):
            hint = ("; channels-first? use np.moveaxis(frame, 0, -1)"
                    if frame.shape[0] in (1, 3, 4) else "")
            raise InputValueError(
                f"{name} must have 1, 3 (RGB) or 4 (RGBA) channels, got {channels} (shape {frame.shape}){hint}")
    elif frame.ndim != 2:
        raise InputValueError(f"{name} must be 2-D (H, W) or 3-D (H, W, C), got shape {frame.shape}")
    h, w = frame.shape[:2]
    if h < min_size or w < min_size:
        raise InputValueError(f"{name} is {w}x{h} pixels; the model needs at least {min_size}x{min_size}")
    if frame.ndim == 3:
        frame = frame[:, :, 0] if frame.shape[2] == 1 else frame[:, :, :3]
    if kind == "f":
        if not np.isfinite(frame).all():
            raise InputValueError(f"{name} contains NaN or infinite pixels")
        if frame.min() < 0 or frame.max() > 255:
            frame = np.clip(frame, 0, 255)  # in the input's own dtype: no overflow, input untouched
    if frame.ndim == 3:
        gray = frame.astype(np.float32) @ LUMA_RGB
    else:
        gray = frame.astype(np.float32, order="C", copy=True)
    if dtype == np.uint16:
        gray *= np.float32(1.0 / 257.0)
    elif kind in "iu" and dtype != np.uint8:
        np.clip(gray, 0, 255, out=gray)
    return np.ascontiguousarray(gray)
