"""The options of a run: :class:`RunOptions`, and :func:`run_options`, which builds one from the keywords of
:func:`~mlplc2.runner.run` and :func:`~mlplc2.runner.stream`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

from .._validation import InputTypeError, did_you_mean_hint
from ..io.gyro import Gyro


@dataclass(frozen=True)
class RunOptions:
    """How :func:`run` reads the input, builds the models and writes the outputs.

    ``mlplc2.run(source, models, fps=..., video=...)`` builds one from its keywords;
    ``run(source, models, options=RunOptions(...), video=True)`` takes one and changes the
    fields given as keywords. Nothing is checked here: :func:`run` checks the values in the
    order it uses them.

    Attributes
    ----------
    fps : float, optional
        Frame rate to use instead of the container's (images: 30).
    resize : (W, H) or 'WxH', optional
        Frames are resized before the models see them; field coordinates in
        the outputs are mapped back to input pixels (``x * W_in / W``).
    scale : float, optional
        Or resize by a factor.
    start, end : int
        Process source frames ``start <= frame < end``.
    decoder : {'opencv', 'pyav'}
        Video decoder (:func:`mlplc2.io.open_source`).
    params : Params or dict, optional
        Passed as ``params=`` to every model, or a dict ``{name: params}``.
    hfov_deg : float, optional
        Horizontal field of view of the camera in degrees, given to the models
        with attention fields: bearings in ``targets.csv`` / ``fields.json`` are
        then degrees from the optical axis (else input pixels from the image
        centre); see ``docs/targets.md``.
    repeat_threshold : float, "auto" or None, optional
        Treat a frame in which no pixel differs from the last processed one by more than
        this many grey levels as a duplicate: the models hold their last output for it
        (``Model.repeat_threshold``; 16 suits videos made by repeating frames, such as the
        paper's clips). ``"auto"`` (the models' default): 16 while the video looks duplicated;
        None: every frame steps the models. Not given (``"model default"``): the models' own setting.
    target_params : TargetParams or dict, optional
        Settings of the targets (time to contact, course, warning: ``horizon_s``,
        ``max_miss``, ...; :class:`mlplc2.targets.TargetParams`) for every model with
        targets; a dict gives the fields to change from the defaults.
    stabilise : bool
        Gaze stabilisation for the models that have it (the LPLC2 family): the camera's rotation
        estimated every frame and compensated before the front end (docs/model.md, "Camera
        motion"). True (the default, here only: every run, stream, batch and benchmark takes it
        from this field); False: the paper's model (as ``mlplc2 reproduce`` and the model classes).
    gyro : path, (N, 4) array, Gyro or callable, optional
        The camera's angular velocity: a CSV with columns ``t, wx, wy, wz`` (s on the video's clock,
        rad/s in the camera's axes) or its rows (:class:`mlplc2.io.gyro.Gyro`), interpolated at each
        frame's time and given to the models that stabilise instead of the estimated rotation; or, for a
        live source, a callable ``rate(t)`` asked once per frame with the frame's time, returning
        ``(wx, wy, wz)`` or None (:class:`mlplc2.io.gyro.LiveGyro`); needs
        ``hfov_deg`` (docs/robot.md, "Frame rate, field of view and a gyro").
    video : bool
        Also write ``annotated.mp4``: the input frames with the targets (or fields) of the
        first model with targets or fields drawn, and a header row per model: its warning
        target, its field alarm or its response (:func:`mlplc2.plots.annotate_frame`).
    draw_fields : {'auto', 'none', 'responding', 'all'}
        Which attention fields ``annotated.mp4`` shows besides the targets: "auto" (default)
        none for a model with targets, else those that respond (response > 0) or are in
        alarm; "responding" those (CLI ``--fields``); "all" every field (``--all-fields``).
    plot : bool
        Write ``responses.png`` (with the targets' timeline, :func:`mlplc2.plots.plot_timeline`).
    keep_rows : bool
        Keep every row of ``responses.csv``/``targets.csv`` in ``RunResult.rows``/
        ``.targets`` (default). Set False for long or live runs: memory then stays
        flat whatever the length (the rows are in the CSV files, and the summaries of fields
        that have died wait in a temporary file until ``fields.json`` is written; the CLI does
        this). ``RunResult.to_dataframe()`` then reads ``responses.csv``.
    quiet : bool
        No progress bar.
    progress : bool
        Show a tqdm progress bar on stderr (unless ``quiet``).
    live : bool, optional
        Take the newest frame when the models fall behind, skipping the others (counted:
        ``RunResult.skipped``, ``"skipped"`` on the stream); default: cameras and RTSP (and
        other real-time URL schemes) are live, files, HTTP(S) and stdin not
        (:func:`mlplc2.io.open_source`).
    jsonl : path, '-' or text file, optional
        Also write one JSON line per frame there (``'-'``: standard output), flushed as each
        frame is done (:mod:`mlplc2.runner.live`; docs/robot.md).
    max_frames : int, optional
        Stop after this many frames (e.g. of a live source).
    duration_s : float, optional
        Stop after this many seconds of wall time.
    spare_core : bool
        :func:`run` on a source not live resized in its decoding thread: the models on one thread fewer (same outputs).
    """

    fps: float | None = None
    resize: Any = None
    scale: float | None = None
    start: int = 0
    end: int | None = None
    decoder: str = "opencv"
    params: Any = None
    hfov_deg: float | None = None
    repeat_threshold: float | str | None = "model default"
    target_params: Any = None
    stabilise: bool = True
    gyro: Any = None
    video: bool = False
    draw_fields: str = "auto"
    plot: bool = True
    keep_rows: bool = True
    quiet: bool = False
    progress: bool = True
    live: bool | None = None
    jsonl: Any = None
    max_frames: int | None = None
    duration_s: float | None = None
    spare_core: bool = True

    def source_options(self) -> dict[str, Any]:
        """The keywords of :func:`mlplc2.io.open_source` that choose the frames."""
        return {"fps": self.fps, "start": self.start, "end": self.end, "resize": self.resize,
                "scale": self.scale, "decoder": self.decoder, "live": self.live}

    def done(self, n_frames: int, seconds: float) -> bool:
        """Whether a run that did ``n_frames`` in ``seconds`` stops here (``max_frames``, ``duration_s``)."""
        return ((self.max_frames is not None and n_frames >= self.max_frames)
                or (self.duration_s is not None and seconds >= self.duration_s))


_OPTION_NAMES = tuple(f.name for f in fields(RunOptions))


def run_options(options: RunOptions | None, keywords: Mapping[str, Any], caller: str = "run") -> RunOptions:
    """``options`` with the fields given as keywords changed (no ``options``: the defaults)."""
    unknown = [k for k in keywords if k not in _OPTION_NAMES]
    if unknown:
        hint = did_you_mean_hint(unknown[0], _OPTION_NAMES + ("models",),
                                 otherwise="the keywords are mlplc2.runner.RunOptions' fields")
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r} ({hint})")
    if options is not None and not isinstance(options, RunOptions):
        raise InputTypeError(f"options must be a RunOptions, got {type(options).__name__}")
    options = RunOptions(**keywords) if options is None else replace(options, **keywords)
    return options if options.gyro is None else replace(options, gyro=Gyro.load(options.gyro))
