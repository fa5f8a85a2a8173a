"""The per-frame contract every model honours, and the model registry.

Every model is built as ``Model(fps=..., params=...)`` and offers
``step(frame) -> Output``, ``reset()`` and ``run(frames)``. The CLI's
``--model`` names come from :data:`REGISTRY` (filled by :func:`register`).
"""

from __future__ import annotations

import abc
import dataclasses
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, ClassVar

import cv2
import numpy as np

from .._validation import InputTypeError, InputValueError, as_gray, check_fps, check_int, check_unit_scale
from ..neuropils.attention import Field

__all__ = ["Output", "Model", "REGISTRY", "REPEAT_THRESHOLD", "MAX_REPEATS", "CLOCK_TOLERANCE", "WORK_WIDTH", "register",
           "get_model", "available_models", "resolve_names", "looks_duplicated", "repeat_split", "frame_change",
           "REPEAT_WINDOW"]


def _eight_bit(frame, min_size: int) -> bool:
    """Whether ``frame`` is an 8-bit image that :func:`~mlplc2._validation.as_gray` accepts as it is (a ``uint8``
    array, (H, W) or (H, W, 1, 3 or 4), at least ``min_size`` px each way): :meth:`Model.step` then reduces it to
    the working width before making it grey, as the decoding thread of ``mlplc2 run`` does."""
    return (type(frame) is np.ndarray and frame.dtype == np.uint8
            and (frame.ndim == 2 or (frame.ndim == 3 and frame.shape[2] in (1, 3, 4)))
            and min(frame.shape[:2]) >= min_size)


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
        Collision alarm this frame (LPLC2 family: any field in alarm, the paper's "fatal"
        field; LGMD: the global spike rule).
    spike : bool
        A spike this frame (LGMD models; the LPLC2 family spikes when it alarms).
    repeated : bool
        The frame repeated the last processed one (see ``Model.repeat_threshold``): the
        model did not step, and this output is the previous one with this frame's index, as
        the model's ``_hold`` ages it (the models with targets count each ``ttc_s`` down).
    targets : tuple of Target
        The approaching objects (:class:`mlplc2.targets.Target`: size, time to contact,
        miss, warning), most urgent first; empty for models without targets (LGMD).
    time_s : float
        The frame's time in seconds: the ``t`` given to ``Model.step``, else the frame count
        over ``fps`` (``docs/model.md``, "Time").
    """

    frame: int
    response: float
    fields: tuple[Field, ...] = ()
    collision: bool = False
    spike: bool = False
    repeated: bool = False
    targets: tuple = ()
    time_s: float | None = None

    @property
    def warning(self) -> bool:
        """Any target warns (a collision course within the horizon; ``docs/targets.md``)."""
        return any(t.warning for t in self.targets)

    @property
    def most_urgent(self):
        """The most urgent target (warning first, then the shortest ``ttc_s``), or None."""
        return self.targets[0] if self.targets else None


#: Suggested fixed ``Model.repeat_threshold`` (grey levels, 0-255; the default is ``"auto"``, which
#: decides from the frames themselves): duplicated frames in the paper's clips differ from their
#: original by at most 15 grey levels (compression noise), frames with real motion there by 15-255
#: (docs/model.md, "Repeated frames"). Not the default because a slow, faint change (a far object
#: looming) also stays under it for a few frames and would be sampled less often.
REPEAT_THRESHOLD = 16.0
#: Longest run of repeated frames held as duplicates (a 6 fps source stored at 30 fps repeats
#: each frame 4 times; the paper's raptor clip has runs of up to 5). From the next repeat on
#: the scene is taken to be still and every frame steps the model again, so it settles.
MAX_REPEATS = 5
#: Timestamps within this fraction of a frame interval (1 / fps) of the frame grid of the
#: first timestamp count as on it (``docs/model.md``, "Time"): rounding and the jitter of
#: container time bases (1 ms at 30 fps is 3 % of an interval) leave a constant rate one,
#: with the outputs of frame count / fps; anything further off is taken as given.
CLOCK_TOLERANCE = 0.05


#: Frames the "auto" repeat detection looks back on (``Model.repeat_threshold = "auto"``).
REPEAT_WINDOW = 30
#: Side (px, at the working size) of the blocks :func:`frame_change` averages the change over:
#: compression noise (zero-mean, a few grey levels a pixel) averages out within a block, a real
#: change (an edge that moved, even by 1 px) does not.
REPEAT_BLOCK = 8
#: Changes below this (grey levels, block mean) count as this much in :func:`repeat_split`: the
#: compression noise of copies (block means of 0-9 on the real clips and their copies, most under
#: 4) is alike below it, so gaps within the copies' noise do not count.
REPEAT_FLOOR = 4.0
#: :func:`repeat_split`: a gap between copies and new frames is a ratio of at least this between
#: neighbouring changes in size order (new frames of ``tests/helpers.duplicated``'s four-phase
#: scene: 1.6 times its copies' +-6 grey levels of white noise; the real clips: 4 and more) ...
REPEAT_GAP = 1.5
#: ... and a difference of at least this many grey levels.
REPEAT_STEP = 3.0
#: :func:`repeat_split` takes the widest such gap instead of the first when it is at least this many
#: times as wide (as a ratio's logarithm): copies whose picture changed in part (an encoder's partial
#: update: block changes of 7-18 among copies of 0-4 and new frames of 187-245 in the helmet clip's
#: x264 copy) then stay copies, while new frames of two speeds (10-12 after 25-43) keep the first gap.
REPEAT_WIDEST = 2.0
#: Fewest frame-to-frame changes :func:`repeat_split` judges (6 let single early frames of 3 of the 46
#: scenes of the benchmark's suite be held).
REPEAT_MIN = 12
#: Default working width (px) of every model (``Model.work_width``): wider frames are reduced to
#: it (keeping their aspect) before the models see them, and the outputs are mapped back to the
#: frame's pixels, so one parameter set (pixel radii, thresholds, the paper's 320x240) gives the
#: same answers at any input resolution. The paper's videos are 320 px wide or less: unchanged.
WORK_WIDTH = 320


def frame_change(a: np.ndarray, b: np.ndarray) -> float:
    """How much frame ``b`` differs from ``a`` (grey, same size) for the "auto" repeat test: the
    largest mean absolute difference over blocks of :data:`REPEAT_BLOCK` px (grey levels, 0-255).
    Unlike the largest single pixel change it hardly depends on the compression noise of a copy;
    unlike the change of reduced frames it keeps a texture's 1 px shift (docs/model.md, "Repeated
    frames")."""
    d = cv2.absdiff(a, b)
    h, w = d.shape[:2]
    cells = (max(w // REPEAT_BLOCK, 1), max(h // REPEAT_BLOCK, 1))
    return float(cv2.resize(d, cells, interpolation=cv2.INTER_AREA).max())


def repeat_split(changes) -> float | None:
    """The level separating copies from new frames when a run of frame-to-frame changes
    (:func:`frame_change`, in order) looks like a video whose frames were duplicated, else None.

    The changes (those under :data:`REPEAT_FLOOR` count as it), in size order, split in two
    classes at the first gap (neighbours at least :data:`REPEAT_GAP` times and
    :data:`REPEAT_STEP` grey levels apart) that leaves at least 15 % of them below (copies: a
    25 fps video shown at 30 fps repeats one frame in 6) and 15 % above (new frames), or at the
    widest such gap when it is :data:`REPEAT_WIDEST` times as wide (as logarithms). The video
    looks duplicated when there are at least :data:`REPEAT_MIN` changes, there is such a gap,
    and a copy follows a new frame at least once per 8 frames (a smooth video, small changes
    first and large ones later, is not taken for one). The level is the gap's geometric middle:
    relative to this video's own copies and new frames, so a noisier or larger encoding of the
    same video splits its frames alike."""
    d = np.maximum(np.asarray(changes, dtype=np.float64), REPEAT_FLOOR)
    n = d.size
    if n < REPEAT_MIN:
        return None
    e = np.sort(d)
    m = int(np.ceil(0.15 * n))                  # split i: copies e[:i], new frames e[i:]
    lo, hi = e[m - 1:n - m], e[m:n - m + 1]
    wide = np.flatnonzero((hi >= REPEAT_GAP * lo) & (hi - lo >= REPEAT_STEP))
    if wide.size == 0:
        return None
    ratio = np.log(hi[wide] / lo[wide])
    i = wide[np.argmax(ratio)] if ratio.max() >= REPEAT_WIDEST * ratio[0] else wide[0]
    level = float(np.sqrt(lo[i] * hi[i]))
    starts = np.count_nonzero((d[:-1] > level) & (d[1:] <= level))
    return level if starts >= max(1, n // 8) else None


def looks_duplicated(changes) -> bool:
    """Whether a run of frame-to-frame changes (:func:`frame_change`, in order) looks like a video
    whose frames were duplicated (:func:`repeat_split`)."""
    return repeat_split(changes) is not None


def check_repeat_threshold(value) -> float | str | None:
    """``value`` as a non-negative float, ``"auto"``, or None (repeat detection off)."""
    if value is None or (isinstance(value, str) and value == "auto"):
        return value
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"repeat_threshold must be a number of grey levels, 'auto' or None, got {value!r}") from None
    if not (v >= 0 and np.isfinite(v)):
        raise InputValueError(f"repeat_threshold must be a finite number >= 0 or None, got {value!r}")
    return v


def _to_frame(out: Output, sx: float, sy: float) -> Output:
    """``out`` of a working frame mapped to the frame given (pixel centres: ``x = (x' + 0.5) s - 0.5``)."""
    def px(v, s):
        return (v + 0.5) * s - 0.5

    fields = tuple(dataclasses.replace(f, x=px(f.x, sx), y=px(f.y, sy), radius=f.radius * sx) for f in out.fields)
    targets = tuple(dataclasses.replace(t, x=px(t.x, sx), y=px(t.y, sy), width=t.width * sx, height=t.height * sy)
                    for t in out.targets)
    return dataclasses.replace(out, fields=fields, targets=targets)


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


#: The package's own models, in the order of every comparison table (the LPLC2 family, the LGMD
#: models, the optical-flow baseline last): ``mlplc2.benchmark.MODELS``, ``mlplc2.evaluator.MODEL_ORDER``.
PACKAGE_MODELS = ("mlplc2", "slplc2", "lplc2", "lgmd2", "lgmd1", "flow")


def resolve_names(value, *, what: str = "models") -> list[str]:
    """The model names in ``value``: a name, a comma-separated string (``"mlplc2,lgmd2"``) or a
    list of them (the CLI's repeated ``--model``), case-insensitive and stripped, each once in
    the order given. An unknown name raises :class:`~mlplc2.InputValueError` listing the valid
    ones; ``what`` names the argument in the messages (``"--model"`` for the CLI)."""
    if isinstance(value, str):
        items = [value]
    elif isinstance(value, Iterable) and not isinstance(value, (bytes, dict)):
        items = list(value)
    else:
        raise InputTypeError(f"{what} must be a model name or a list of names, got {type(value).__name__}")
    names: list[str] = []
    for item in items:
        if not isinstance(item, str):
            raise InputTypeError(f"{what} must be model names (str), got {item!r}")
        for part in item.split(","):
            name = part.strip().lower()
            if not name:
                continue
            if name not in REGISTRY:
                raise InputValueError(_unknown(name))
            if name not in names:
                names.append(name)
    if not names:
        raise InputValueError(f"{what} needs at least one model name")
    return names


def get_model(name: str) -> type["Model"]:
    """The model class registered as ``name`` (case-insensitive)."""
    try:
        return REGISTRY[name.lower()]
    except KeyError:
        raise InputValueError(_unknown(name)) from None


def param_defaults(name: str) -> dict:
    """The default parameters of the model registered as ``name``, by field name: its ``params``' ``to_dict()`` (a
    :class:`~mlplc2.params.ParameterSet`) or any dataclass's fields (a model of your own, docs/testing.md); {} for a
    model whose parameters are no dataclass."""
    params = get_model(name)(fps=30.0).params
    if hasattr(params, "to_dict"):
        return params.to_dict()
    if dataclasses.is_dataclass(params):
        return {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
    return {}


def _unknown(name: str) -> str:
    """The one-line error for a model name nobody registered."""
    return (f"unknown model {name!r}; choose from {', '.join(available_models())} (a model of your own: "
            "register it first, from the command line in a script that calls mlplc2.cli.main: docs/testing.md)")


class Model(abc.ABC):
    """Base class: input checks, frame counting and the ``run`` loop.

    Subclasses implement :meth:`_step` on a validated float32 grey frame
    (0-255) and :meth:`_reset`.
    """

    name: ClassVar[str] = "model"
    #: Smallest frame side (pixels) the model accepts; smaller frames raise
    #: :class:`~mlplc2.InputError` naming this minimum. Every frame of at least this size must
    #: give finite outputs (``mlplc2.testing.check_minimum_size``).
    min_size: ClassVar[int] = 3
    #: True for models whose outputs carry attention fields (``Output.fields``).
    has_fields: ClassVar[bool] = False
    #: True for models whose fields' positions mean something: a field sits where what it answers
    #: to is (evaluation scores them against the objects); False without fields, or for fields
    #: that stay put whatever moves.
    localises: ClassVar[bool] = False
    #: True for models whose outputs carry targets (``Output.targets``): their warning is the
    #: targets' warning; models without targets warn with their alarm (``Output.collision``).
    has_targets: ClassVar[bool] = False
    #: True for models built with ``stabilise=`` (gaze stabilisation: the camera's rotation
    #: compensated before the front end; docs/model.md, "Camera motion").
    stabilises: ClassVar[bool] = False
    #: Whether this model compensates the camera's rotation before its front end (gaze stabilisation; an instance's
    #: ``stabilise=``, always for the optical-flow baseline): ``fields.json`` and ``results.csv`` record it.
    stabilise: bool = False

    def __init__(self, fps: float = 30.0, params: Any = None, repeat_threshold: float | str | None = "auto",
                 work_width: int | None = WORK_WIDTH):
        self.fps = check_fps(fps)
        self.params = params
        self.repeat_threshold = check_repeat_threshold(repeat_threshold)
        """A frame in which no pixel differs from the last processed frame by more than this
        many grey levels (0-255) is a repeat (a duplicated frame of a frame-rate conversion,
        compression noise aside): the model does not step and returns its last output
        (``Output.repeated``), at most :data:`MAX_REPEATS` times in a row. ``"auto"`` (the
        default): while the last :data:`REPEAT_WINDOW` frames look duplicated, a frame whose
        :func:`frame_change` from the last processed one is at most the level
        :func:`repeat_split` finds between their copies and new frames, whatever the encoding's
        noise; else every frame steps (``mlplc2.run`` looks at the first frames of a video first
        and primes the model, :meth:`prime_repeats`, to hold from the start). None: every frame
        steps. See docs/model.md, "Repeated frames"."""
        self.work_width = None if work_width is None else check_int(work_width, "work_width", minimum=16)
        """Frames wider than this (px) are reduced to it, keeping their aspect (``cv2.INTER_AREA``),
        before the model's stages; fields and targets come back in the frame's own pixels
        (``model.maps`` stays at the working size). None: every frame at its own size.
        Default :data:`WORK_WIDTH` = 320 (the paper's videos)."""
        self._scale_warned = False
        self._diffs: deque = deque(maxlen=REPEAT_WINDOW)
        self._forget()

    def _forget(self) -> None:
        """The base's state back to that of a new model (the unit-scale warning aside)."""
        self._shape: tuple[int, int] | None = None
        self._frame = 0
        self._last_gray: np.ndarray | None = None
        self._last_out: Output | None = None
        self._repeats = 0
        self._prev_in: np.ndarray | None = None      # the previous input frame ("auto" repeats)
        self._diffs.clear()
        self._primed = 0                              # changes of prime_repeats still ahead
        self._work: tuple[int, int] | None = None     # (W, H) of the working frames, None: as given
        self._input_map = None                        # input pixels -> the frames' (set_input_map)
        self._t0: float | None = None      # time (s) of frame 0: the clock's origin
        self._t_last: float | None = None  # time (s) of the last frame
        self.clock: float = 0              # this frame's time in frame intervals since frame 0
        self._clock_done: float = 0        # clock of the last processed (not held) frame
        self.interval: float = 1           # frame intervals since the last processed frame

    def _advance(self, t) -> tuple[float, float]:
        """(clock, time_s) of the next frame taken at ``t`` seconds (None: one frame interval after
        the last). The clock counts frame intervals (1 / fps) since frame 0; timestamps within
        :data:`CLOCK_TOLERANCE` of the frame grid sit on it (whole numbers: constant rates step
        as without timestamps). Raises :class:`~mlplc2.InputError` before any state changes."""
        if t is None:
            if self._t_last is None:
                return 0, 0.0
            return self.clock + 1, self._t0 + (self.clock + 1) / self.fps
        if isinstance(t, (bool, np.bool_)) or not isinstance(t, (int, float, np.integer, np.floating)):
            raise InputTypeError(f"frame {self._frame}: t must be a time in seconds (a number), got {t!r}")
        t = float(t)
        if not np.isfinite(t):
            raise InputValueError(f"frame {self._frame}: t must be a finite time in seconds, got {t!r}")
        if self._t_last is None:
            return 0, t
        if not t > self._t_last:
            raise InputValueError(f"frame {self._frame}: timestamps must increase, got t = {t!r} s after "
                                  f"{self._t_last!r} s")   # repr: all the digits a camera's epoch clock needs
        raw = (t - self._t0) * self.fps
        whole = round(raw)
        clock = whole if abs(raw - whole) <= CLOCK_TOLERANCE else raw
        if clock <= self.clock:     # the last frame's time was moved onto the grid past this one
            clock = self.clock + (t - self._t_last) * self.fps
        return clock, t

    @property
    def frame_index(self) -> int:
        """Index the next frame will get."""
        return self._frame

    def gyro_refusal(self) -> str | None:
        """Why this model takes no gyro (None: it takes one); the models that stabilise take one
        (:class:`mlplc2.models.gaze.GazeStabilisation`)."""
        return f"model {self.name!r} does not compensate the camera's motion: it takes no gyro"

    def _check_gyro(self, gyro) -> np.ndarray | None:
        """``gyro`` of :meth:`step` as a float64 (wx, wy, wz) in rad/s, or None; raises before any state changes."""
        if gyro is None:
            return None
        why = self.gyro_refusal()
        if why is not None:
            raise InputValueError(why)
        try:
            g = np.asarray(gyro, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputTypeError(f"frame {self._frame}: gyro must be three numbers (wx, wy, wz) in rad/s, "
                                 f"got {gyro!r}") from None
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputValueError(f"frame {self._frame}: gyro must be three finite numbers (wx, wy, wz) in rad/s, "
                                  f"got {gyro!r}")
        return g

    def _see_gyro(self, rate: np.ndarray | None, dt: float | None, processed: bool) -> None:
        """The gyro's rate at this frame (:meth:`_check_gyro`; None: none given), ``dt`` seconds after the
        last frame (None: the first), and whether the model steps on this frame (else it holds it): what
        the models that stabilise integrate (:class:`mlplc2.models.gaze.GazeStabilisation`). Nothing
        here: a model that does not stabilise takes no gyro (:meth:`gyro_refusal`)."""

    def step(self, frame: np.ndarray, t: float | None = None, *, gyro=None) -> Output:
        """Process one frame: (H, W) grey, (H, W, 1), (H, W, 3) RGB or (H, W, 4) RGBA, 0-255.

        ``t``: the frame's time in seconds (a camera's or container's timestamp); every time
        constant and the times to contact then use the real interval since the last processed
        frame (variable rates, dropped frames). None: one frame interval (1 / ``fps``) after
        the last frame. Timestamps must increase (:class:`~mlplc2.InputError` otherwise); at a
        constant rate (``t = i / fps``) the outputs are those without ``t`` (``docs/model.md``, "Time").

        ``gyro``: the camera's angular velocity at this frame, ``(wx, wy, wz)`` in rad/s about its x
        (right), y (down) and z (forward) axes (a pan to the right is ``+wy``), for the models that
        stabilise (``stabilise=True``; they need ``hfov_deg``): the rotation since the last processed
        frame is then the gyro's, integrated over the real intervals (held frames' included), and
        is not estimated from the images (``docs/model.md``, "Camera motion"). Other models raise
        :class:`~mlplc2.InputError`. Give it on every frame: a frame without it leaves the rotation
        to the images until the next processed frame.

        Colour frames are RGB: OpenCV's ``VideoCapture``/``imread`` give BGR, so convert them
        first (``cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)``, or pass ``COLOR_BGR2GRAY``'s grey image).
        A float frame whose maximum lies in (0, 1] is most likely a 0-1 image: the model
        warns once (:class:`mlplc2.InputWarning`); multiply it by 255.

        Scaling and rejected inputs are those of :func:`mlplc2._validation.as_gray`
        (uint16 / 257; floats and other integers clipped to 0-255; bool, non-numeric
        dtypes and NaN/inf rejected). Every frame after the first must have the
        first frame's size until :meth:`reset`. ``frame`` is never modified.
        A rejected frame raises :class:`~mlplc2.InputError` (a ``ValueError`` or
        ``TypeError``) before any state changes, so the model can go on.
        """
        # an 8-bit frame wider than the working width is reduced as it is (its channels), then made grey: what
        # ``mlplc2 run`` and ``stream`` do in their decoding thread, so that a loop of step() on the same frames
        # gives their outputs (the other order differs by the rounding to 8 bits, which moves warnings)
        raw = _eight_bit(frame, self.min_size)
        gray = None if raw else as_gray(frame, min_size=self.min_size)
        shape = frame.shape[:2] if raw else gray.shape
        clock, time_s = self._advance(t)
        rate = self._check_gyro(gyro)
        if self._shape is None:
            h, w = shape
            if self.work_width is not None and w > self.work_width:
                self._work = (self.work_width, max(int(round(h * self.work_width / w)), self.min_size))
            self._shape = shape
        elif shape != self._shape:
            h0, w0 = self._shape
            h, w = shape
            raise InputValueError(
                f"frame {self._frame} is {w}x{h} but earlier frames were {w0}x{h0}; call reset() to change size")
        if raw:
            small = frame if self._work is None else cv2.resize(np.ascontiguousarray(frame), self._work,
                                                               interpolation=cv2.INTER_AREA)
            gray = as_gray(small, min_size=self.min_size)
        elif not self._scale_warned:
            self._scale_warned = check_unit_scale(frame, gray)
        first = self._t_last is None
        dt = None if first else time_s - self._t_last
        self.clock, self._t_last = clock, time_s
        if first:
            self._t0 = time_s
        if self._work is not None and not raw:
            gray = cv2.resize(gray, self._work, interpolation=cv2.INTER_AREA)
        if self._is_repeat(gray):
            self._repeats += 1
            if self._repeats <= MAX_REPEATS:
                self._see_gyro(rate, dt, processed=False)
                out = self._held_output(time_s)
                self._frame += 1
                return out
            # A longer run is a still scene, not a duplicated frame: step as usual.
        else:
            self._repeats = 0
            if self.repeat_threshold is not None:
                if self._last_gray is None:
                    self._last_gray = gray.copy()
                else:
                    np.copyto(self._last_gray, gray)
        self.interval = 1 if first else clock - self._clock_done
        self._clock_done = clock
        self._see_gyro(rate, dt, processed=True)
        out = dataclasses.replace(self._step(gray, self._frame), time_s=time_s)
        if self._work is not None:
            out = _to_frame(out, self._shape[1] / self._work[0], self._shape[0] / self._work[1])
        self._frame += 1
        self._last_out = out
        return out

    def set_input_map(self, to_frames) -> None:
        """How the pixels of the input the user gave map onto the frames this model is given:
        ``to_frames(x, y) -> (x, y)``, or None (the same pixels). :func:`mlplc2.run` sets it after
        resizing the video (``--resize``, ``--scale``, or its reduction to the working width in the
        decoding thread: :meth:`mlplc2.io.FrameSource.to_model`), so that ``TargetParams.heading``,
        given in the input's pixels as every output is, means the same point whatever size the
        frames reach the model at. :meth:`reset` forgets it."""
        self._input_map = to_frames

    def _work_heading(self) -> tuple[float, float] | None:
        """``TargetParams.heading`` (the input's pixels; None stays None) in the working frame's
        pixels: the one mapping of a fixed heading, for every model with targets (the course,
        the warning and the camera-motion estimate read it there)."""
        tp = getattr(self, "target_params", None)
        return None if tp is None else self._work_point(tp.heading)

    def _work_point(self, point: tuple[float, float] | None) -> tuple[float, float] | None:
        """``point`` (x, y), in the pixels of the input (:meth:`set_input_map`; without one, of the
        frames given), in the working frame's pixels (the inverse of the mapping of the outputs;
        None stays None)."""
        if point is not None and self._input_map is not None:
            point = tuple(float(v) for v in self._input_map(float(point[0]), float(point[1])))
        if point is None or self._work is None:
            return point
        sx, sy = self._work[0] / self._shape[1], self._work[1] / self._shape[0]
        return (point[0] + 0.5) * sx - 0.5, (point[1] + 0.5) * sy - 0.5

    def prime_repeats(self, changes) -> None:
        """Give a model left on ``"auto"`` the frame-to-frame changes (:func:`frame_change`, at the
        working size) of the video's first frames, measured ahead (``mlplc2.run`` does): until it
        has seen :data:`REPEAT_WINDOW` frames of its own, it judges repeats on these, so a
        duplicated video is held from its first copy. Call it before the first frame."""
        self._diffs.clear()
        self._diffs.extend(float(c) for c in list(changes)[:REPEAT_WINDOW])
        self._primed = len(self._diffs)

    def _is_repeat(self, gray: np.ndarray) -> bool:
        """Whether ``gray`` (working size) repeats the last processed frame: its largest pixel change
        at most ``repeat_threshold``; for ``"auto"`` its :func:`frame_change` at most the level
        :func:`repeat_split` finds in the last :data:`REPEAT_WINDOW` frame-to-frame changes."""
        if self.repeat_threshold != "auto":
            last = self._last_gray
            return (self.repeat_threshold is not None and last is not None
                    and cv2.norm(gray, last, cv2.NORM_INF) <= self.repeat_threshold)
        prev = self._prev_in
        if prev is None:
            self._prev_in = gray.copy()
            return False
        if self._primed:
            self._primed -= 1     # this change is in the window already (prime_repeats)
        else:
            self._diffs.append(frame_change(gray, prev))
        np.copyto(prev, gray)
        level = repeat_split(self._diffs)
        return level is not None and frame_change(gray, self._last_gray) <= level

    def _held_output(self, time_s: float) -> Output:
        """The last output for a repeated frame: this frame's index and time, ``repeated`` set, and
        what the model's :meth:`_hold` makes of the time elapsed since the processed frame."""
        held = self._hold(self._last_out, (self.clock - self._clock_done) / self.fps)
        return dataclasses.replace(held, frame=self._frame, repeated=True, time_s=time_s)

    def _hold(self, last: Output, elapsed: float) -> Output:
        """The output held ``elapsed`` seconds after ``last`` (models with clocks override it)."""
        return last

    @staticmethod
    def _check_params(value, cls, what: str, label: str):
        """``value`` (None: ``cls()``), which must be a ``cls``: else "``what`` must be ``label``"."""
        value = cls() if value is None else value
        if not isinstance(value, cls):
            raise InputTypeError(f"{what} must be {label}, got {type(value).__name__}")
        return value

    def reset(self) -> None:
        """Forget all state: the next frame is frame 0 and may have a new size."""
        self._forget()
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
