"""One place for checking user input (frames, fps, sizes).

Every check raises a subclass of :class:`InputError` with a one-line message. A mistyped
name gets the closest known one (:func:`did_you_mean`, :func:`did_you_mean_hint`).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

__all__ = ["InputError", "InputValueError", "InputTypeError", "InputWarning", "as_gray", "check_unit_scale",
           "check_fps", "check_real", "check_reals", "check_int", "check_bool", "Valid", "check_fields",
           "did_you_mean", "did_you_mean_hint",
           "FLOAT32_MAX", "FLOAT32_TINY", "INT_MAX"]

#: Largest finite float32 (3.4028235e+38). A parameter that enters the models' float32 maths
#: must not exceed it: ``np.float32`` would turn it into inf (and inf x 0 into NaN).
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: Smallest positive normal float32 (1.1754944e-38). A parameter that must be > 0 must be at
#: least this: smaller values become 0 or lose their precision in float32, where 0 / 0 = NaN
#: and x ** 0 = 1 (and the reference and fast front ends then disagree).
FLOAT32_TINY = float(np.finfo(np.float32).tiny)
#: Largest integer parameter (2**31 - 1): sizes and counts stay within every index type used.
INT_MAX = 2**31 - 1

#: Rec. 601 luma weights for RGB -> grey (retina input, NOTES 2).
LUMA_RGB = np.array([0.299, 0.587, 0.114], dtype=np.float32)


class InputError(Exception):
    """Base class of every error about bad input (frames, files, arguments)."""


class InputValueError(InputError, ValueError):
    """An input with the right type but a wrong value (shape, size, NaN, ...)."""


class InputTypeError(InputError, TypeError):
    """An input of the wrong type (non-numeric dtype, not an array, ...)."""


class InputWarning(UserWarning):
    """An input that is valid but probably not what was meant (e.g. a float frame on a 0-1 scale)."""


def check_unit_scale(frame, gray: np.ndarray, name: str = "frame") -> bool:
    """Warn (:class:`InputWarning`, one line) when a float ``frame`` looks like a 0-1 image.

    Float frames are taken on the 0-255 scale (:func:`as_gray`); a frame whose brightest pixel
    is above 0 but at most 1 is then almost black, and the models answer nothing. ``gray`` is
    the converted frame. Returns True when it warned (callers warn once).
    """
    if not (isinstance(frame, np.ndarray) and frame.dtype.kind == "f"):
        return False
    top = float(gray.max())
    if 0.0 < top <= 1.0:
        import warnings

        warnings.warn(f"{name} is a float image whose maximum is {top:.3g}: frames are read on the 0-255 "
                      f"scale, so a 0-1 image gives (almost) no response; multiply it by 255",
                      InputWarning, stacklevel=3)
        return True
    return False


def check_fps(fps) -> float:
    """Return ``fps`` as a float, or raise if it is not a positive finite number
    (a bool, a string or None is an :class:`InputTypeError`)."""
    return check_real(fps, "fps", positive=True)


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
        # Element-wise in a C-ordered float32 copy, never ``@``: the matrix product's rounding
        # depends on the memory layout (NumPy 2.4 keeps a Fortran layout and rounds otherwise),
        # and a frame must give the same grey image however it is stored.
        rgb = np.ascontiguousarray(frame, dtype=np.float32)
        gray = rgb[:, :, 0] * LUMA_RGB[0]
        gray += rgb[:, :, 1] * LUMA_RGB[1]
        gray += rgb[:, :, 2] * LUMA_RGB[2]
    else:
        gray = frame.astype(np.float32, order="C", copy=True)
    if dtype == np.uint16:
        gray *= np.float32(1.0 / 257.0)
    elif kind in "iu" and dtype != np.uint8:
        np.clip(gray, 0, 255, out=gray)
    return np.ascontiguousarray(gray)


# ---------------------------------------------------------------------------
# Mistyped names
# ---------------------------------------------------------------------------
def did_you_mean(word: str, names: Iterable[str], *, cutoff: float = 0.6) -> str | None:
    """The name of ``names`` closest to the mistyped ``word``, or None when none is close enough
    (:func:`difflib.get_close_matches`: similarity ratio at least ``cutoff``). The comparison is
    exact (case and dashes count): a caller that ignores them lower-cases or strips ``word`` first."""
    close = difflib.get_close_matches(word, list(names), n=1, cutoff=cutoff)
    return close[0] if close else None


def did_you_mean_hint(word: str, names: Iterable[str], *, cutoff: float = 0.6, otherwise: str = "") -> str:
    """``"did you mean 'X'?"`` for the name ``X`` of ``names`` closest to ``word``
    (:func:`did_you_mean`), else ``otherwise``: the one wording of every such hint."""
    close = did_you_mean(word, names, cutoff=cutoff)
    return otherwise if close is None else f"did you mean {close!r}?"


# ---------------------------------------------------------------------------
# Parameters (Params, TargetParams, LGMD2Params, LGMD1Params)
# ---------------------------------------------------------------------------
def _show(value) -> str:
    """A one-line, bounded repr of ``value`` for error messages (arrays by their shape)."""
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape}"
    text = " ".join(repr(value).split())
    return text if len(text) <= 80 else text[:77] + "..."


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def check_real(value, name: str, *, minimum: float | None = None, below: float | None = None,
               positive: bool = False, maximum: float = FLOAT32_MAX) -> float:
    """Return ``value`` as a Python float, or raise with a one-line message.

    Accepted: a real number (``int``, ``float``, NumPy integer or floating scalar; not a
    bool, string, None or array: :class:`InputTypeError`) that is finite, within float32's
    range (``|value| <= FLOAT32_MAX``) and within the bounds (:class:`InputValueError`):
    ``minimum`` (inclusive), ``below`` (exclusive upper bound), ``maximum`` (inclusive) and
    ``positive`` (> 0 and at least ``FLOAT32_TINY``, float32's smallest normal number).
    """
    if _is_bool(value) or not isinstance(value, numbers.Real):
        raise InputTypeError(f"{name} must be a number, got {_show(value)}")
    try:
        v = float(value)
    except (OverflowError, ValueError, TypeError):   # an int too large for a float
        v = 1e308 if value > 0 else -1e308           # out of float32's range below
    if not math.isfinite(v):
        raise InputValueError(f"{name} must be a finite number, got {_show(value)}")
    if positive and not v > 0:
        raise InputValueError(f"{name} must be > 0, got {_show(value)}")
    if minimum is not None and v < minimum:
        raise InputValueError(f"{name} must be >= {minimum:g}, got {_show(value)}")
    if below is not None and not v < below:
        raise InputValueError(f"{name} must be < {below:g}, got {_show(value)}")
    if v > maximum or -v > FLOAT32_MAX:
        if maximum >= FLOAT32_MAX:
            raise InputValueError(f"{name} must lie within float32's range (magnitude <= {FLOAT32_MAX:.8g}), "
                                  f"got {_show(value)}")
        raise InputValueError(f"{name} must be <= {maximum:g}, got {_show(value)}")
    if positive and v < FLOAT32_TINY:
        raise InputValueError(f"{name} must be >= {FLOAT32_TINY:.8g} (float32's smallest normal number), "
                              f"got {_show(value)}")
    return v


def check_reals(value, name: str, count: int, what: str = "", **bounds) -> tuple[float, ...]:
    """Return a sequence of ``count`` numbers (tuple, list or 1-D array) as a tuple of Python
    floats, each checked by :func:`check_real` with ``bounds``; ``what`` names the entries."""
    if isinstance(value, (str, bytes)) or _is_bool(value) or isinstance(value, numbers.Number):
        items = None
    else:
        try:
            items = list(value)
        except TypeError:
            items = None
    label = f" ({what})" if what else ""
    if items is None:
        raise InputTypeError(f"{name} must be a sequence of {count} numbers{label}, got {_show(value)}")
    if len(items) != count:
        raise InputValueError(f"{name} must have {count} values{label}, got {_show(value)}")
    return tuple(check_real(x, f"{name}[{i}]", **bounds) for i, x in enumerate(items))


def check_int(value, name: str, *, minimum: int = 0, maximum: int | None = INT_MAX) -> int:
    """Return ``value`` as a Python int, or raise with a one-line message.

    Accepted: a Python or NumPy integer (not a bool) in ``[minimum, maximum]`` (``maximum=None``:
    no upper bound, for a count that only bounds itself, such as a stimulus phase longer than
    its video). Strings, None, arrays and other non-numbers raise :class:`InputTypeError`;
    bools, floats (even integral ones) and integers out of range :class:`InputValueError`.
    """
    if not _is_bool(value) and not isinstance(value, numbers.Number):
        raise InputTypeError(f"{name} must be an integer >= {minimum}, got {_show(value)}")
    top = math.inf if maximum is None else maximum
    if _is_bool(value) or not isinstance(value, numbers.Integral) or not minimum <= value <= top:
        too_big = not _is_bool(value) and isinstance(value, numbers.Real) and value > top
        bound = f"in [{minimum}, {maximum}]" if too_big else f">= {minimum}"
        raise InputValueError(f"{name} must be an integer {bound}, got {_show(value)}")
    return int(value)


def check_bool(value, name: str) -> bool:
    """Return ``value`` as a Python bool: only ``True``/``False`` (or NumPy bools) are accepted,
    so that a string such as ``"no"`` is not silently taken as true."""
    if not _is_bool(value):
        raise InputTypeError(f"{name} must be True or False, got {_show(value)}")
    return bool(value)


@dataclass(frozen=True)
class Valid:
    """The values a parameter accepts, kept in its dataclass field's metadata (``"valid"``):
    :func:`check_fields` enforces it with the checks above, and ``str()`` describes it in
    the parameter tables (``help(mlplc2.Params)``, docs/model.md), so the range shown is the
    range enforced.

    ``kind`` is ``"real"`` (:func:`check_real` with ``minimum``, ``below``, ``maximum``,
    ``positive``), ``"int"`` (:func:`check_int` with ``minimum``, ``maximum``), ``"bool"``
    (:func:`check_bool`), ``"choice"`` (one of the strings ``choices``) or ``"reals"`` (a
    sequence of ``count`` numbers, :func:`check_reals`, the entries named by ``what``, each with
    ``minimum`` or ``positive``). ``also`` states a constraint between fields, checked by the
    class itself, for the tables.
    """

    kind: str
    minimum: float | None = None
    below: float | None = None
    maximum: float | None = None
    positive: bool = False
    choices: tuple[str, ...] = ()
    also: str = ""
    count: int = 0
    what: str = ""

    @classmethod
    def real(cls, *, minimum=None, below=None, maximum=None, positive=False, also="") -> "Valid":
        return cls("real", minimum, below, maximum, positive, also=also)

    @classmethod
    def integer(cls, minimum: int = 0, maximum: int | None = None, *, also="") -> "Valid":
        return cls("int", minimum, None, maximum, also=also)

    @classmethod
    def boolean(cls) -> "Valid":
        return cls("bool")

    @classmethod
    def choice(cls, *choices: str) -> "Valid":
        return cls("choice", choices=tuple(choices))

    @classmethod
    def reals(cls, count: int, what: str, *, minimum=None, positive=False) -> "Valid":
        """A sequence of ``count`` numbers (``what`` names them), each checked like :meth:`real`."""
        return cls("reals", minimum, None, None, positive, count=count, what=what)

    @classmethod
    def point(cls) -> "Valid":
        """None or a pair of numbers (x, y)."""
        return cls("point")

    def check(self, value, name: str):
        """``value`` converted (Python float, int, bool or str), or a one-line InputError naming ``name``."""
        if self.kind == "real":
            bounds = {} if self.maximum is None else {"maximum": self.maximum}
            return check_real(value, name, minimum=self.minimum, below=self.below, positive=self.positive, **bounds)
        if self.kind == "int":
            return check_int(value, name, minimum=self.minimum, maximum=INT_MAX if self.maximum is None else self.maximum)
        if self.kind == "bool":
            return check_bool(value, name)
        if self.kind == "point":
            return None if value is None else check_reals(value, name, 2, "x, y")
        if self.kind == "reals":
            return check_reals(value, name, self.count, self.what, minimum=self.minimum,
                               positive=self.positive)
        if not isinstance(value, str) or value not in self.choices:
            raise InputValueError(f"{name} must be {' or '.join(map(repr, self.choices))}, got {_show(value)}")
        return str(value)

    def __str__(self) -> str:
        if self.kind == "bool":
            text = "True or False"
        elif self.kind == "point":
            text = "None or (x, y)"
        elif self.kind == "choice":
            text = " or ".join(f'"{c}"' for c in self.choices)
        else:
            low = "(0" if self.positive else None if self.minimum is None else f"[{self.minimum:g}"
            high = (f"{self.below:g})" if self.below is not None
                    else None if self.maximum is None else f"{self.maximum:g}]")
            if low and high:
                text = f"in {low}, {high}"
            elif low:
                text = ("> " if low[0] == "(" else ">= ") + low[1:]
            elif high:
                text = ("< " if high[-1] == ")" else "<= ") + high[:-1]
            else:
                text = "any number"
            if self.kind == "int":
                text = f"integer {text}"
            elif self.kind == "reals":
                text = f"{self.count} numbers {text} ({self.what})"
            elif text.startswith("in "):
                text = text[3:]
        return f"{text}; {self.also}" if self.also else text


def check_fields(obj, prefix: str) -> None:
    """Check (and convert in place) every field of the frozen dataclass ``obj`` whose metadata
    holds a :class:`Valid`, in the order of the fields; errors are named ``prefix.field``."""
    for f in dataclasses.fields(obj):
        valid = f.metadata.get("valid")
        if valid is not None:
            object.__setattr__(obj, f.name, valid.check(getattr(obj, f.name), f"{prefix}.{f.name}"))
