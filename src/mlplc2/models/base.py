"""The per-frame contract every model honours, and the model registry.

Every model is built as ``Model(fps=..., params=...)`` and offers
``step(frame) -> Output``, ``reset()`` and ``run(frames)``. The CLI's
``--model`` names come from :data:`REGISTRY` (filled by :func:`register`).
"""

from __future__ import annotations

import abc
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._validation import InputValueError, as_gray, check_fps
from ..attention import Field

__all__ = ["Output", "Model", "REGISTRY", "register", "get_model", "available_models"]


@dataclass(frozen=True)
class Output:
    """What a model returns for one frame.

    Attributes
    ----------
    frame : int
        0-based index of the frame since construction or the last ``reset()``.
    response : float
        The model's output this frame: the membrane potential for the LGMD
        models; for the LPLC2 family the largest attention-field response.
    fields : tuple of Field
        Active attention fields (empty for models that do not localise).
    collision : bool
        Collision alarm this frame (LPLC2 family: any field in alarm).
    spike : bool
        A spike this frame (LGMD models; the LPLC2 family spikes when it alarms).
    """

    frame: int
    response: float
    fields: tuple[Field, ...] = ()
    collision: bool = False
    spike: bool = False

    @property
    def most_urgent(self) -> Field | None:
        """The field with the smallest time to collision (``Field.ttc_s``).

        Ties go to the larger response, then the smaller id. Without any TTC
        estimate this frame: the field with the largest response. None without fields.
        """
        if not self.fields:
            return None
        timed = [f for f in self.fields if getattr(f, "ttc_s", None) is not None]
        if timed:
            return min(timed, key=lambda f: (f.ttc_s, -f.response, f.id))
        return max(self.fields, key=lambda f: f.response)

    @property
    def threats(self) -> tuple[Field, ...]:
        """Fields with a time-to-collision estimate, most urgent first (the ``Field.rank`` order)."""
        timed = [f for f in self.fields if getattr(f, "ttc_s", None) is not None]
        return tuple(sorted(timed, key=lambda f: (f.ttc_s, -f.response, f.id)))


REGISTRY: dict[str, type["Model"]] = {}


def register(name: str):
    """Class decorator: make a model available under ``name`` (CLI ``--model``)."""

    def deco(cls):
        cls.name = name
        REGISTRY[name] = cls
        return cls

    return deco


def available_models() -> list[str]:
    return sorted(REGISTRY)


def get_model(name: str) -> type["Model"]:
    """The model class registered as ``name`` (case-insensitive)."""
    try:
        return REGISTRY[name.lower()]
    except KeyError:
        raise InputValueError(
            f"unknown model {name!r}; choose from {', '.join(available_models())}") from None


class Model(abc.ABC):
    """Base class: input checks, frame counting and the ``run`` loop.

    Subclasses implement :meth:`_step` on a validated float32 grey frame
    (0-255) and :meth:`_reset`.
    """

    name: ClassVar[str] = "model"
    #: Smallest frame side (pixels) the model accepts; smaller frames raise
    #: :class:`~mlplc2.InputError` naming this minimum. 3 for every model: an
    #: LPLC2 field needs a centre row and column plus one pixel per quadrant, and
    #: the LGMD lateral inhibition and grouping are 3x3 neighbourhoods. Frames
    #: smaller than the LPLC2 filter windows (11 and 23 px) or than a field
    #: (2 R_AF + 1 = 81 px) are numerically safe (zero borders; every output
    #: finite, tested), but the default parameters are meant for about 320x240.
    min_size: ClassVar[int] = 3
    #: True for models whose output has attention fields (positions); False for whole-field neurons.
    localises: ClassVar[bool] = False

    def __init__(self, fps: float = 30.0, params: Any = None):
        self.fps = check_fps(fps)
        self.params = params
        self._shape: tuple[int, int] | None = None
        self._frame = 0

    @property
    def frame_index(self) -> int:
        """Index the next frame will get."""
        return self._frame

    def step(self, frame: np.ndarray) -> Output:
        """Process one frame: (H, W) grey, (H, W, 1), (H, W, 3) RGB or (H, W, 4) RGBA, 0-255.

        Scaling and rejected inputs are those of :func:`mlplc2._validation.as_gray`
        (uint16 / 257; floats and other integers clipped to 0-255; bool, non-numeric
        dtypes and NaN/inf rejected). Every frame after the first must have the
        first frame's size until :meth:`reset`. ``frame`` is never modified.
        A rejected frame raises :class:`~mlplc2.InputError` (a ``ValueError`` or
        ``TypeError``) before any state changes, so the model can go on.
        """
        gray = as_gray(frame, min_size=self.min_size)
        if self._shape is None:
            self._shape = gray.shape
        elif gray.shape != self._shape:
            h0, w0 = self._shape
            h, w = gray.shape
            raise InputValueError(
                f"frame {self._frame} is {w}x{h} but earlier frames were {w0}x{h0}; call reset() to change size")
        out = self._step(gray, self._frame)
        self._frame += 1
        return out

    def reset(self) -> None:
        """Forget all state: the next frame is frame 0 and may have a new size."""
        self._shape = None
        self._frame = 0
        self._reset()

    def run(self, frames: Iterable[np.ndarray]) -> Iterator[Output]:
        """Step through ``frames`` lazily, yielding one Output per frame."""
        for frame in frames:
            yield self.step(frame)

    @abc.abstractmethod
    def _step(self, gray: np.ndarray, index: int) -> Output: ...

    @abc.abstractmethod
    def _reset(self) -> None: ...

    def __repr__(self) -> str:
        return f"{type(self).__name__}(fps={self.fps:g})"
