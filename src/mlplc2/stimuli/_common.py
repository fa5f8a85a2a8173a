"""What every stimulus generator shares (:mod:`mlplc2.stimuli.paper`, :mod:`mlplc2.stimuli.world`): the
result types (:class:`Stimulus`, :class:`ApproachStimulus`), the argument checks, the plain and
procedural backgrounds (1/f noise, blobs, optics blur) and the size limit. Both families import
it; neither imports the other (import-linter: ``paper | world``).

The checks here are thin wrappers over :mod:`mlplc2._validation`'s, so that a stimulus refuses what
every other argument check refuses (a string such as ``'5'``, a bool, None: an
:class:`~mlplc2._validation.InputTypeError`) with the same one-line message: :func:`check_number`
is :func:`~mlplc2._validation.check_real`; :func:`check_count` is
:func:`~mlplc2._validation.check_int` that also takes an integral float (``frames=50.0``) and has
no upper bound.
:func:`check_choice` names the options in its message."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .._validation import InputTypeError, InputValueError, check_int, check_real
from ..evaluation.truth import ObjectTruth, VideoTruth

__all__ = ["Stimulus", "ApproachStimulus", "MAX_STIMULUS_BYTES", "OPTICS_BLUR_PX", "check_choice", "check_count",
           "check_number", "check_size", "plain_level", "procedural_background", "blur"]


@dataclass(frozen=True, eq=False)
class Stimulus:
    """Frames of a synthetic stimulus and their ground truth.

    Attributes
    ----------
    frames : numpy.ndarray
        ``uint8`` array of shape ``(T, H, W)``, grey levels 0-255.
    fps : float
        Frame rate (frames per second).
    objects : tuple of ObjectTruth
        Ground truth of every object.
    name : str
        Name of the stimulus (one of :data:`NAMES`, or "scene").
    """

    frames: np.ndarray
    fps: float = 30.0
    objects: tuple[ObjectTruth, ...] = ()
    name: str = "stimulus"

    @property
    def size(self) -> tuple[int, int]:
        """``(W, H)`` in pixels."""
        return (int(self.frames.shape[2]), int(self.frames.shape[1]))

    def __len__(self) -> int:
        return int(self.frames.shape[0])

    def truth(self) -> VideoTruth:
        """The ground truth of this stimulus (:class:`mlplc2.evaluation.truth.VideoTruth`, key ``name``)."""
        return VideoTruth(key=self.name, size=self.size, frames=len(self), fps=float(self.fps), objects=self.objects)

    def to_ground_truth(self) -> dict[str, Any]:
        """Return a JSON-ready dict in the schema of one ``ground_truth.json`` "videos" entry
        (:meth:`truth` as JSON, :meth:`mlplc2.evaluation.truth.VideoTruth.to_dict`).

        Keys: ``"size"`` ``[W, H]``, ``"frames"`` ``T``, ``"fps"``, ``"objects"``
        (list of :meth:`ObjectTruth.to_dict`, with only the phases that exist,
        plus ``"sizes"`` per frame and, for physical looming,
        ``"contact_frame"``, ``"half_size"`` and ``"speed"``).
        """
        return self.truth().to_dict()

    def object(self, object_id: int) -> ObjectTruth:
        """Return the :class:`ObjectTruth` with ``id == object_id``."""
        for obj in self.objects:
            if obj.id == object_id:
                return obj
        raise InputValueError(
            f"no object with id {object_id!r}; valid ids: {[o.id for o in self.objects]}")

    def center_at(self, frame: int, object_id: int = 1) -> tuple[float, float] | None:
        """Centre ``(x, y)`` of object ``object_id`` at ``frame`` (``None`` for a grating)."""
        if not 0 <= int(frame) < len(self):
            raise InputValueError(f"frame {frame} is outside the video (0..{len(self) - 1})")
        return self.object(object_id).center_at(int(frame))


@dataclass(frozen=True, eq=False)
class ApproachStimulus(Stimulus):
    """A :class:`Stimulus` of :func:`mlplc2.stimuli.world.approach`, with its camera and background.

    Its ``objects`` are 3-D :class:`ObjectTruth` (a ``kind``, a per-frame ``track`` of
    :class:`mlplc2.evaluation.truth.TrackPoint` with the time to contact and the miss).

    Attributes
    ----------
    camera : dict
        ``{"hfov_deg", "focal_px", "motion", "speed"}``.
    background : str
        ``"plain"``, ``"texture"`` or ``"ground"``.
    """

    camera: dict | None = None
    background: str = "plain"

    def truth(self) -> VideoTruth:
        """The ground truth of this stimulus, with its camera and background (docs/stimuli.md,
        "Ground truth"; :meth:`to_ground_truth` gives its JSON)."""
        return dataclasses.replace(super().truth(), camera=dict(self.camera or {}), background=self.background)


def check_choice(value, name: str, options: Sequence[str]) -> str:
    if not isinstance(value, str) or value not in options:
        raise InputValueError(f"{name} must be one of {', '.join(options)}, got {value!r}")
    return value


def check_count(value, name: str, minimum: int = 0) -> int:
    """``value`` as an int >= ``minimum`` (:func:`~mlplc2._validation.check_int`, no upper bound:
    an approach may outlast the video; the size limit bounds the frames); an integral float
    (``50.0``, ``np.float64(50.0)``) counts as its integer."""
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        value = int(value)
    return check_int(value, name, minimum=minimum, maximum=None)


def check_number(value, name: str, *, positive: bool = False, nonneg: bool = False) -> float:
    """``value`` as a finite float (:func:`~mlplc2._validation.check_real`): > 0 if ``positive``,
    >= 0 if ``nonneg``."""
    return check_real(value, name, positive=positive, minimum=0.0 if nonneg else None)


def check_size(size) -> tuple[int, int]:
    try:
        w, h = size
    except (TypeError, ValueError):
        raise InputValueError(f"size must be (width, height), got {size!r}") from None
    try:
        return check_count(w, "width", 1), check_count(h, "height", 1)
    except (InputValueError, InputTypeError) as exc:   # named, so that `mlplc2 stimulus` can say --size
        raise type(exc)(f"size: {exc}") from None


def plain_level(appearances: Sequence[str]) -> float:
    """Grey level of a plain background for objects of these appearances: 250 (the paper's
    "white") if every one is dark, 0 if every one is bright, else mid-grey 128."""
    kinds = set(appearances)
    return 250.0 if kinds == {"dark"} else 0.0 if kinds == {"bright"} else 128.0


#: Standard deviation (px) of the blur standing for the camera optics in procedural backgrounds.
OPTICS_BLUR_PX = 1.0


def procedural_background(width: int, height: int, seed: int = 0, *, periodic: bool = False) -> np.ndarray:
    """Natural-like grey texture: 1/f noise plus a few blurred blobs, seen through
    slightly blurring optics (``OPTICS_BLUR_PX``).

    The amplitude spectrum of the noise falls as ``1/f`` (power ``1/f^2``, as
    in natural images); a handful of soft blobs adds large-scale structure.
    Grey levels are mapped so that the 2nd and 98th percentiles land on 60 and
    220 (mean about 140, standard deviation about 40, like the paper's
    ``outdoor_2.jpg`` scaled to 240 rows: mean 146, std 40), then clipped to
    30-240.

    Parameters
    ----------
    width, height : int
        Size in pixels. For a scrolling scene use
        ``width >= W + frames * scroll``.
    seed : int
        Seed of :func:`numpy.random.default_rng`; the same seed gives the same
        texture.
    periodic : bool
        Make the texture tile seamlessly (blobs wrap around the borders and the
        blurs are circular; the noise is periodic anyway): for the ground plane
        of :func:`mlplc2.stimuli.world.approach`. ``False`` gives the texture as
        before (the same for a seed).

    Returns
    -------
    numpy.ndarray
        ``uint8`` array of shape ``(height, width)``.
    """
    import cv2

    width = check_count(width, "width", 1)
    height = check_count(height, "height", 1)
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((height, width))
    fy = np.fft.fftfreq(height)[:, None]
    fx = np.fft.rfftfreq(width)[None, :]
    f = np.sqrt(fx * fx + fy * fy)
    f[0, 0] = 1.0
    amp = 1.0 / np.maximum(f, 1.0 / max(width, height))
    amp[0, 0] = 0.0
    tex = np.fft.irfft2(np.fft.rfft2(noise) * amp, s=(height, width))
    tex /= tex.std() + 1e-12
    # a few soft blobs (bushes, clouds, ...)
    blobs = np.zeros((height, width), np.float32)
    n_blobs = max(3, int(round(width * height / 20000)))
    for _ in range(n_blobs):
        cx, cy = int(rng.integers(0, width)), int(rng.integers(0, height))
        ax = int(rng.integers(max(2, height // 16), max(3, height // 4)))
        ay = int(rng.integers(max(2, height // 16), max(3, height // 4)))
        angle = float(rng.uniform(0, 180))
        value = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.8, 1.6))
        for dx, dy in ([(dx, dy) for dx in (-width, 0, width) for dy in (-height, 0, height)]
                       if periodic else [(0, 0)]):
            cv2.ellipse(blobs, (cx + dx, cy + dy), (ax, ay), angle, 0, 360, value, -1)
    sigma = max(1.0, height / 40.0)
    blobs = blur(blobs, sigma, periodic)
    tex = tex + blobs.astype(np.float64)
    # Camera optics: a 1-px Gaussian blur. Without it the 1/f texture changes by ~16 grey
    # levels per pixel of scroll, far busier than the paper's photographs (2.7 for
    # outdoor_2.jpg, 8.8 for outdoor_3.jpg); with it ~5.
    tex = blur(tex, OPTICS_BLUR_PX, periodic)
    lo, hi = np.percentile(tex, [2.0, 98.0])
    tex = 60.0 + (tex - lo) * (160.0 / max(hi - lo, 1e-12))
    return np.clip(np.rint(tex), 30, 240).astype(np.uint8)


def blur(image: np.ndarray, sigma: float, periodic: bool) -> np.ndarray:
    """Gaussian blur; circular (the image wrapped around its borders) if ``periodic``."""
    import cv2

    if not periodic:
        return cv2.GaussianBlur(image, (0, 0), sigma)
    pad = int(math.ceil(4 * sigma))
    h, w = image.shape
    big = np.pad(image, ((pad, pad), (pad, pad)), mode="wrap")
    return cv2.GaussianBlur(big, (0, 0), sigma, borderType=cv2.BORDER_REFLECT)[pad:pad + h, pad:pad + w]


#: Largest generated video (bytes of uint8 grey frames) and background shift (px) ``scene``
#: accepts: a typo (a million frames, a scroll of 1e6 px per frame) fails at once instead of
#: trying to allocate many GiB.
MAX_STIMULUS_BYTES = 4 * 2**30
