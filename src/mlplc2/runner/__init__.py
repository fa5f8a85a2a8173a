"""Run one or several models over a video, an image sequence or a camera.

:func:`run` decodes the frames once (streamed, in a background thread) and
steps every model on each frame, writing as it goes:

``responses.csv``
    one row per active field per frame (``frame,time_s,model,field_id,x,y,response,collision``),
    flushed after every frame: a run stopped by Ctrl-C leaves a valid file. A signal
    (Ctrl-C, SIGTERM) that arrives during a frame takes effect once the frame is written,
    so ``responses.csv``, ``targets.csv`` and ``fields.json`` always cover the same frames.
``fields.json``
    one summary per attention field (centre, birth, death, peak, first alarm) and, under
    ``"targets"``, one per target (life, first estimate, first warning and the estimates
    then, see ``docs/targets.md``).
``targets.csv``
    (models with targets) one row per target per frame:
    ``frame,model,target_id,x,y,width,height,ttc_s,miss,warning,fields,azimuth_deg,elevation_deg,ttc_age_s,ttc_sigma_s,held_by``
    (input pixels; time to contact in s, miss in object extents (widths across, heights up and down), empty while not estimable;
    the bearing in degrees only with ``hfov_deg``; ``fields`` the ids of its attention fields,
    space-separated; ``ttc_age_s`` the seconds since ``ttc_s`` was measured: 0 when this frame's fit
    gave it, more when it is the last one held and counted down, empty without ``ttc_s``; ``ttc_sigma_s``
    the standard error of ``ttc_s`` in s, that of the fit it came from; ``held_by`` the rule that held back a
    warning on that frame, :attr:`Target.held_by <mlplc2.targets.Target.held_by>`, else empty).
``responses.png``
    response against frame, one panel per model, and under a model with targets their time to
    contact with the warning frames marked (see :mod:`mlplc2.plots`).
``annotated.mp4``
    (``video=True``) the input with the targets (or fields) drawn, the warning target named in
    the header (:func:`mlplc2.plots.annotate_frame`).

The summary files are written under a hidden temporary name and renamed
when complete, so a file with its final name is never half-written.

Its options are one :class:`RunOptions` (keywords of :func:`run` build it); the models are
built from them. What a run gives, :class:`~mlplc2.runner.result.RunResult` and the columns of
its files, is in :mod:`mlplc2.runner.result` (re-exported here).
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import logging
import time
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

from .._signals import interrupts
from .._validation import InputTypeError, InputValueError, as_gray
from .._files import write_json
from ..backend import one_fewer, threads, workers
from ..io import FrameSource, TruncatedInputWarning, VideoWriter, open_source
from ..io.gyro import Gyro
from ..io.formats import STDIN, without_password
from ..models.base import (Model, available_models, check_repeat_threshold, frame_change, get_model,
                          looks_duplicated, resolve_names)
from ..params import Params
from ..plots import DRAW_FIELDS
from ..targets import TargetParams, check_hfov
from ..evaluation.match import match_fields
from ..evaluation.record import Recorder, response_rows
from .folders import default_out_dir, is_the_input, prepare_out_dir
from .live import CsvFile, JsonLines, Latency, frame_record
from .result import COLUMNS, TARGET_COLUMNS, RunInterrupted, RunResult

__all__ = ["run", "stream", "RunOptions", "RunResult", "RunInterrupted", "TruncatedInputWarning", "COLUMNS", "TARGET_COLUMNS",
           "default_out_dir", "demo", "DemoResult"]

log = logging.getLogger(__name__)


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


def _run_options(options: RunOptions | None, keywords: Mapping[str, Any], caller: str = "run") -> RunOptions:
    """``options`` with the fields given as keywords changed (no ``options``: the defaults)."""
    unknown = [k for k in keywords if k not in _OPTION_NAMES]
    if unknown:
        close = difflib.get_close_matches(unknown[0], _OPTION_NAMES + ("models",), n=1)
        hint = f"did you mean {close[0]!r}?" if close else "the keywords are mlplc2.runner.RunOptions' fields"
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r} ({hint})")
    if options is not None and not isinstance(options, RunOptions):
        raise InputTypeError(f"options must be a RunOptions, got {type(options).__name__}")
    options = RunOptions(**keywords) if options is None else replace(options, **keywords)
    return options if options.gyro is None else replace(options, gyro=Gyro.load(options.gyro))


def _model_list(models) -> list:
    """Model instances as given, registry names and groups resolved to names."""
    if isinstance(models, (str, Model)):
        models = [models]
    if not isinstance(models, Iterable):
        raise InputTypeError(f"models must be a model, a model name or a list of them, got {type(models).__name__}")
    return [n for m in models for n in ([m] if isinstance(m, Model) else resolve_names(m))]


def _names(models: list) -> list[str]:
    return [m.name if isinstance(m, Model) else str(m).strip().lower() for m in models]


def _model_options(options: RunOptions, names: list[str]) -> RunOptions:
    """``options`` with ``target_params`` coerced and a dict of ``params`` keyed by model name
    (lower case); a key that names no model of the run is an error."""
    target_params = TargetParams.coerce(options.target_params, "target_params")
    params = options.params
    if isinstance(params, Mapping):
        params = {str(k).strip().lower(): v for k, v in params.items()}
        unknown = sorted(k for k in params if k not in names)
        family = {f.name for f in dataclasses.fields(Params)}
        if unknown and all(k in family for k in unknown):     # reproduce(params=...) takes such a dict
            name = next((n for n in names if n in ("mlplc2", "slplc2", "lplc2")), "mlplc2")
            first = unknown[0]
            raise InputValueError(f"params: {', '.join(unknown)} {'is a field' if len(unknown) == 1 else 'are fields'} "
                                  f"of mlplc2.Params, not a model name: give params=mlplc2.Params({first}=...) or "
                                  f"params={{{name!r}: {{{first!r}: ...}}}}")
        if unknown:
            raise InputValueError(f"params: {', '.join(unknown)} is not a model of this run "
                                  f"({', '.join(dict.fromkeys(names))}); give one Params for every "
                                  f"model or a dict {{model name: params}}")
    return replace(options, params=params, target_params=target_params)


def _new_model(name: str, fps: float, options: RunOptions, **override) -> Model:
    """The registry model ``name`` built with the run's options (``override``: keywords that win)."""
    cls = get_model(name)
    p = options.params.get(name) if isinstance(options.params, Mapping) else options.params
    kw = {"hfov_deg": options.hfov_deg} if (options.hfov_deg is not None and cls.has_targets) else {}
    if options.target_params is not None and cls.has_targets:
        kw["target_params"] = options.target_params
    if cls.stabilises:
        kw["stabilise"] = bool(options.stabilise)
    if options.repeat_threshold != "model default":
        kw["repeat_threshold"] = options.repeat_threshold
    kw.update(override)
    return cls(fps=fps, **kw) if p is None else cls(fps=fps, params=p, **kw)


def _adopt_instance(m: Model, models: list, fps: float, options: RunOptions) -> Model:
    """A model instance the caller built: reset, and given the run's field of view, repeat
    threshold and target settings where the run has them (the caller's object is the one that runs)."""
    if sum(isinstance(o, Model) and o.name == m.name for o in models) > 1:
        raise InputValueError(f"two models named {m.name!r} in one run: results are kept per "
                              f"model name; run them separately")
    if abs(m.fps - fps) > 1e-6 * fps:
        warnings.warn(f"model {m.name!r} was built for {m.fps:g} fps but the input runs at "
                      f"{fps:g} fps; its time constants and time-to-collision use {m.fps:g}",
                      stacklevel=6)
    m.reset()
    if options.hfov_deg is not None and hasattr(m, "hfov_deg"):
        m.hfov_deg = check_hfov(options.hfov_deg)
    if options.repeat_threshold != "model default":
        m.repeat_threshold = check_repeat_threshold(options.repeat_threshold)
    if options.target_params is not None and m.has_targets:
        m.target_params = options.target_params
    return m


def _build_models(models: list, fps: float, options: RunOptions) -> list[Model]:
    """One model per name (the first of each), built from the options, or adopted when given built."""
    options = _model_options(options, _names(models))
    built: list[Model] = []
    seen = set()
    for m in models:
        if isinstance(m, Model):
            if m.name in seen:
                raise InputValueError(f"two models named {m.name!r} in one run: results are kept per "
                                      f"model name; run them separately")
            model = _adopt_instance(m, models, fps, options)
        else:
            model = _new_model(str(m).strip().lower(), fps, options)
        if model.name in seen:
            continue
        seen.add(model.name)
        built.append(model)
    if not built:
        raise InputValueError("no model given")
    return built


def _check_frame_size(src: FrameSource, models: Sequence[Model]) -> None:
    """Frames (after resizing) smaller than a model's ``min_size``: one clear error."""
    need = max(m.min_size for m in models)
    w, h = src.out_size
    if w < need or h < need:
        resized = " after resizing" if src.out_size != src.size else ""
        raise InputValueError(f"{src.name}: frames are {w}x{h} pixels{resized}; "
                              f"the models need at least {need}x{need}")


#: :func:`_check_aspect`: the largest change of the frames' aspect ratio (relative) that ``resize`` makes unremarked
ASPECT_TOLERANCE = 0.05


def _check_aspect(src: FrameSource) -> None:
    """A warning when ``resize`` stretches the frames (their aspect ratio changes by more than
    ``ASPECT_TOLERANCE``): an object's growth differs across the axes then, its box, course and bearing are
    distorted and the warnings change (a user's trial, session 31: the 426x240 dashcam clip resized to 320x240
    lost its only warning). The models reduce a frame to their working width themselves, keeping its shape."""
    (w, h), (ow, oh) = src.size, src.out_size
    if w and h and ow and oh and abs((ow / oh) / (w / h) - 1.0) > ASPECT_TOLERANCE:
        keep = max(int(round(h * ow / w)), 1)
        warnings.warn(f"{src.name}: resizing {w}x{h} frames to {ow}x{oh} changes their aspect ratio "
                      f"({w / h:.2f} -> {ow / oh:.2f}), which distorts the objects' growth and the warnings; "
                      f"keep it (e.g. {ow}x{keep}) or leave the resizing to the models", stacklevel=4)


def _check_heading(src: FrameSource, built: list[Model]) -> None:
    """A warning when a given heading (``TargetParams.heading``, ``--heading``) lies outside the input's frame: a
    camera may look sideways to where it goes, but a point off the frame is most often one in another frame's pixels
    (a robotics user's trial, session 32: ``--heading 1000,1000`` on a 426x240 clip, taken silently)."""
    w, h = src.size
    for m in built:
        heading = getattr(getattr(m, "target_params", None), "heading", None)
        if heading is not None and w and h and not (0 <= heading[0] <= w - 1 and 0 <= heading[1] <= h - 1):
            warnings.warn(f"{src.name}: the heading ({heading[0]:g}, {heading[1]:g}) lies outside the {w}x{h} frame; "
                          f"it is taken in the input's pixels (x from 0 to {w - 1}, y from 0 to {h - 1})", stacklevel=4)
            return


def _prepare_models(source, models: list, src: FrameSource, options: RunOptions) -> tuple[list[Model], bool | None]:
    """The run's models, and whether the first frames looked duplicated (:func:`_prescan_changes`:
    the models with ``repeat_threshold="auto"`` are then primed to hold duplicates from the first frame on);
    None when no model is left to find out (every model's ``repeat_threshold`` set)."""
    built = _build_models(models, src.fps, options)
    _check_frame_size(src, built)  # before any output exists: a bad size writes nothing
    _check_aspect(src)
    _check_heading(src, built)
    refusals = [m.gyro_refusal() for m in built]
    if options.gyro is not None and None not in refusals:   # no model takes it: the first one says why
        raise InputValueError(f"{options.gyro.name}: {refusals[0]}")
    if options.gyro is not None:                            # it spans the frames (when their number is known)
        options.gyro.check_covers(*src.span_s(), src.fps)  # on the clock of the frames' times (their timestamps)
    widths = {m.work_width for m in built}
    w, h = src.size
    if len(widths) == 1 and None not in widths and not src.resized and w > (work := widths.pop()):
        # The models' reduction to their working width (Model.work_width), done in the decoding thread.
        src.reduce_to((work, max(int(round(h * work / w)), max(m.min_size for m in built))))
    for m in built:          # TargetParams.heading is in the input's pixels, as every output
        m.set_input_map(src.to_model if src.resized else None)
    auto = [m for m in built if m.repeat_threshold == "auto"]
    changes = _prescan_changes(source, auto, src, options) if auto else None
    duplicated = None if changes is None else looks_duplicated(changes)
    if duplicated:
        for m in auto:
            m.prime_repeats(changes)
    return built, duplicated


def run(source, models: Sequence[str | Model] | str = ("mlplc2",), *, out=None, options: RunOptions | None = None,
        **keywords) -> RunResult:
    """Run models over a video, a folder of images, a glob pattern or a camera.

    Parameters
    ----------
    source : str, path-like or int
        Input; see :func:`mlplc2.io.open_source`.
    models : sequence of str or Model
        Registry names (``mlplc2.available_models()``) or model instances. All
        models see the same decoded frames (decoded once). An instance is reset and
        given the run's ``hfov_deg``, ``repeat_threshold`` and ``target_params`` where set.
    out : path, None or False
        Output folder (created). ``None``: ``<stem>_mlplc2/`` next to the
        input. ``False``: write nothing, only return the result.
    options : RunOptions, optional
        How to read, build and write (:class:`RunOptions`; default: its defaults).
    **keywords
        Fields of :class:`RunOptions` (``fps``, ``resize``, ``scale``, ``start``, ``end``,
        ``video``, ``quiet``, ``params``, ``progress``, ``plot``, ``decoder``, ``hfov_deg``,
        ``keep_rows``, ``repeat_threshold``, ``draw_fields``, ``target_params``), which
        replace those of ``options``.

    Returns
    -------
    RunResult

    Raises
    ------
    InputError
        Bad input (missing file, not a video, unknown model, bad resize, ...); or a gyro whose
        samples end before a frame of a source of unknown length (a stream), after writing the
        outputs of the frames done (``fields.json``: ``error``, not complete).
    RunInterrupted
        On Ctrl-C, after writing the outputs of the frames done
        (``fields.json`` then says ``"interrupted": true``). A Ctrl-C during a frame
        takes effect when the frame is finished; a second one stops at once.

    Warns
    -----
    TruncatedInputWarning
        The input stopped decoding early; the outputs cover the frames decoded
        and ``result.truncated`` is True.
    """
    options = _run_options(options, keywords)
    with workers():
        src, built, result = _open(source, models, options, out)
        return _loop(src, built, result, result.out, options)


def stream(source, models: Sequence[str | Model] | str | Model = "mlplc2", *, options: RunOptions | None = None,
           **keywords) -> Iterator[dict]:
    """Run models over a source and yield each frame's results as it is done.

    The same as ``mlplc2 run SOURCE --jsonl -`` from Python: each item is the dict of one JSON
    line (schema 1, docs/robot.md: ``frame``, ``time_s``, ``skipped``, ``warning``, ``models``,
    ``targets``). ``source``, ``models`` and the keywords are those of :func:`run` (``source`` may
    also be an opened :class:`~mlplc2.io.FrameSource`); nothing is written. Stop by breaking out
    of the loop (or ``max_frames`` / ``duration_s``): closing the generator (a ``for`` loop over
    ``stream(...)`` drops it at the ``break``; one kept in a name: its ``close()``) closes the
    source and stops and joins the worker threads (:func:`mlplc2.backend.workers`).

    >>> for line in mlplc2.stream("rtsp://camera/stream", hfov_deg=90):   # doctest: +SKIP
    ...     if line["warning"]:
    ...         brake()
    """
    options = replace(_run_options(options, keywords, "stream"), video=False, keep_rows=False)
    with workers():
        src, built, result = _open(source, models, options, False)
        frames = _Frames(src, built, result, options)
        t0 = time.perf_counter()
        try:
            for item in src:
                try:
                    line = frames.step(item)
                except _GyroEnded as exc:    # the gyro gave out (a file's samples end, a live gyro's bad value)
                    raise InputValueError(f"{exc}; the lines cover the {result.n_frames} frames before") from None
                yield line
                if options.done(result.n_frames, time.perf_counter() - t0):
                    break
            else:
                _warn_ended(src)
        finally:
            src.close()
            frames.recorder.close()      # its spill files


def _warn_ended(src: FrameSource) -> None:
    """What :func:`stream` says when its source ran out (``run`` records it in its result and ``fields.json``): a
    stream that stopped on an error or a file cut short (:class:`TruncatedInputWarning`), frames that could not be
    decoded and were skipped."""
    if src.truncated or src.dropped:
        warnings.warn(src.message or f"{src.name}: the input stopped early", TruncatedInputWarning, stacklevel=3)
    if src.damaged:
        warnings.warn(damaged_message(src.name, src.damaged), TruncatedInputWarning, stacklevel=3)


def damaged_message(name: str, damaged: list[int]) -> str:
    """The line that names the frames of ``name`` that could not be decoded and were skipped (``damaged``: their
    indices; the CLI's warning after a run, :func:`stream`'s)."""
    shown = ", ".join(map(str, damaged[:5])) + (", ..." if len(damaged) > 5 else "")
    return f"{name}: {len(damaged)} damaged frame(s) could not be decoded ({shown}); skipped"


def _open(source, models, options: RunOptions, out) -> tuple[FrameSource, list[Model], RunResult]:
    """The opened source, the built models and the result to fill (its ``out``: the folder
    made, None for ``out=False``); everything cheap is checked before anything is decoded."""
    models = _model_list(models)
    if options.draw_fields not in DRAW_FIELDS:
        raise InputValueError(f"draw_fields must be one of {', '.join(map(repr, DRAW_FIELDS))}, "
                              f"got {options.draw_fields!r}")
    jsonl = options.jsonl
    if jsonl is not None and not hasattr(jsonl, "write") and jsonl != STDIN and Path(jsonl).is_dir():
        raise InputValueError(f"{jsonl}: is a folder; the JSON lines (--jsonl, jsonl=) go to a file or - (standard output)")
    if jsonl is not None and not hasattr(jsonl, "write") and jsonl != STDIN and is_the_input(source, jsonl):
        raise InputValueError(f"{jsonl}: is the input video, which the JSON lines would overwrite: write them to "
                              f"another file (e.g. {Path(jsonl).with_suffix('.jsonl').name})")
    if isinstance(source, FrameSource):
        src = source
    else:
        src = open_source(source, keep_original=options.video, **options.source_options())
    made_lines = None
    try:
        built, duplicated = _prepare_models(source, models, src, options)
        if jsonl is not None and not hasattr(jsonl, "write") and jsonl != STDIN \
                and (not Path(jsonl).exists() or Path(jsonl).is_file()):   # never a named pipe: its reader would see an end
            # opened once before the output folder is made, so that a path that cannot be written
            # (a folder without permission, a read-only disk) leaves no empty output folder behind
            made_lines = None if Path(jsonl).exists() else Path(jsonl)
            Path(jsonl).parent.mkdir(parents=True, exist_ok=True)
            open(jsonl, "a", encoding="utf-8").close()
        out_dir = None if out is False else prepare_out_dir(source, src, out)
    except BaseException:
        src.close()
        if made_lines is not None and made_lines.is_file() and made_lines.stat().st_size == 0:
            made_lines.unlink()
        raise
    result = RunResult(source=str(src.name if isinstance(source, FrameSource) else without_password(source)),
                       models=[m.name for m in built], fps=src.fps, size=src.size,
                       model_size=src.out_size, start=src.start, duplicated=duplicated, out=out_dir,
                       repeated={m.name: 0 for m in built},
                       hfov_deg=next((m.hfov_deg for m in built if getattr(m, "hfov_deg", None) is not None),
                                     None), params={m.name: _changed(m) for m in built},
                       stabilise={m.name: bool(getattr(m, "stabilise", False)) for m in built})
    return src, built, result


def _params_dict(p) -> dict:
    """A model's parameters as a dict: a :class:`~mlplc2.params.ParameterSet`'s ``to_dict()``, a plain dataclass's
    fields (a user's own model, docs/testing.md), else nothing (None, or an object the run cannot read)."""
    if hasattr(p, "to_dict"):
        return p.to_dict()
    if dataclasses.is_dataclass(p) and not isinstance(p, type):
        return dataclasses.asdict(p)
    return {}


def _changed(model: Model) -> dict:
    """The parameters ``model`` runs with that differ from its defaults (``fields.json`` ``"params"``); those of its
    target layer under ``"targets"``. A model whose parameter class has no defaults: all of them."""
    def diff(p) -> dict:
        values = _params_dict(p)
        try:
            default = _params_dict(type(p)())
        except Exception:  # noqa: BLE001 - a user's parameter class that needs arguments: no defaults to compare
            return values
        return {k: v for k, v in values.items() if default.get(k) != v}

    out = diff(model.params)
    targets = getattr(model, "target_params", None) if model.has_targets else None
    changed = {} if targets is None else diff(targets)
    return {**out, "targets": changed} if changed else out


#: Frames of a video :func:`run` looks at first to tell whether its frames were duplicated.
PRESCAN_FRAMES = 60


def _prescan_changes(source, auto: list[Model], src: FrameSource, options: RunOptions) -> list[float]:
    """For a video or image sequence with models whose ``repeat_threshold`` is ``"auto"`` (``auto``):
    the frame-to-frame changes of its first :data:`PRESCAN_FRAMES` frames
    (:func:`mlplc2.models.base.frame_change`, at the models' working size). When they look duplicated
    (:func:`mlplc2.models.base.looks_duplicated`) those models are primed with them
    (``Model.prime_repeats``) and hold duplicates from the first copy on instead of finding out
    after a few frames. A file is opened a second time for it; a source read once (stdin, HTTP, an
    opened :class:`~mlplc2.io.FrameSource`) that is a file, its frame count stated (an AVI or MP4
    sent through a pipe), is read ahead on itself (:meth:`~mlplc2.io.FrameSource.peek`: its first
    line waits for those frames); a camera, a live source and a stream without a stated count (a
    camera's or an encoder's: Matroska, MPEG-TS, MJPEG), whose first lines would then be seconds
    old, are not scanned (no changes): their models find out after a few frames (docs/model.md,
    "Repeated frames")."""
    import cv2

    once = src.kind == "stream" or isinstance(source, FrameSource)
    if not auto or src.kind == "camera" or (once and (src.live or src.frame_count is None)):
        return []
    width = min((m.work_width for m in auto if m.work_width is not None), default=None)
    # Every one of the first frames, also for a file read --live (a live reader would hand over a
    # sample that depends on the machine's speed, and the decision with it).
    scan = None if once else open_source(source, **{**options.source_options(), "live": False})
    diffs, prev = [], None
    try:
        for k, item in enumerate(src.peek(PRESCAN_FRAMES) if once else scan):
            if k >= PRESCAN_FRAMES:
                break
            g = as_gray(item[1])
            if width is not None and g.shape[1] > width:
                g = cv2.resize(g, (width, max(int(round(g.shape[0] * width / g.shape[1])), 3)),
                               interpolation=cv2.INTER_AREA)
            if prev is not None:
                diffs.append(frame_change(g, prev))
            prev = g
    finally:
        if scan is not None:
            scan.close()
    return diffs



class _OutputFailed(Exception):
    """Writing one of the per-frame outputs failed (an OSError: a full disk, a device that refuses):
    the run stops at that frame, and :func:`_loop` still writes the summaries of the frames done.
    ``name`` is the output as ``fields.json``'s ``"error"`` names it (``annotated.mp4``,
    ``responses.csv``, ``targets.csv``, the JSON lines' path or ``stdout``), ``path`` the file's path
    for the one-line error; the OSError is its ``__cause__``."""

    def __init__(self, name: str, path: str):
        super().__init__(name)
        self.name, self.path = name, path


class _GyroEnded(Exception):
    """The gyro's samples end before a frame's time (a source of unknown length, e.g. stdin, whose
    span could not be checked before the run), or a live gyro (:class:`~mlplc2.io.gyro.LiveGyro`) gave no rate:
    the run stops before that frame, :func:`_loop` writes the summaries of the frames done (``error``: the message;
    not complete), then raises it as an :class:`~mlplc2.InputError` (:func:`stream` too)."""


class _Frames:
    """The per-frame work of :func:`run`: step every model, record, write each output's share."""

    def __init__(self, src: FrameSource, built: list[Model], result: RunResult, options: RunOptions):
        self.src, self.built, self.result, self.options = src, built, result, options
        self.names = result.models
        self.recorder = Recorder(built, fps=src.fps, source=str(src.name), size=src.size, offset=src.start,
                                 to_input=src.to_input, series=False, spill=not options.keep_rows)
        self.primary = next((i for i, m in enumerate(built) if m.has_fields), None)  # the model drawn on the video
        self.field_shape = (getattr(built[self.primary].params, "field_shape", "square")
                            if self.primary is not None else "square")
        self.responses = self.targets = self.vw = self.lines = None
        self.latency = Latency()

    def open(self, out_dir: Path | None) -> None:
        """The per-frame outputs: the JSON lines, ``responses.csv``, ``targets.csv`` and ``annotated.mp4``."""
        if self.options.jsonl is not None:
            self.lines = JsonLines(self.options.jsonl)
        if out_dir is None:
            return
        self.responses = CsvFile(out_dir / "responses.csv", COLUMNS)
        self.result.files["responses.csv"] = self.responses.path
        if any(m.has_targets for m in self.built):
            self.targets = CsvFile(out_dir / "targets.csv", TARGET_COLUMNS)
            self.result.files["targets.csv"] = self.targets.path
        if self.options.video:
            self.vw = VideoWriter(out_dir / "annotated.mp4", self.src.fps, self.src.size)

    def step(self, item: tuple) -> dict:
        """One frame: the models step, then the frame's share of every output, together; returns
        the frame's JSON line (:func:`~mlplc2.runner.live.frame_record`). Its latency runs from the
        frame's decoding to its JSON line, written before its CSV rows (without ``jsonl``: to where it would be)."""
        index, frame = item[0], item[1]
        names, result, src = self.names, self.result, self.src
        time_s = round(index / src.fps if src.time_s is None else src.time_s, 6)
        try:
            rate = None if self.options.gyro is None else self.options.gyro.at(time_s, src.fps)
        except InputValueError as exc:  # a source of unknown length outran the gyro: stop, keep the frames done
            raise _GyroEnded(str(exc)) from None
        # the gyro only to the models that take it (a model of the user's may not know the keyword)
        outputs = [m.step(frame, src.time_s) if rate is None or m.gyro_refusal() else
                   m.step(frame, src.time_s, gyro=rate) for m in self.built]
        if self.vw is not None:
            from ..plots import annotate_frame

            img = annotate_frame(item[2], outputs, names, src.scale_x, src.scale_y, primary=self.primary,
                                 index=index, field_shape=self.field_shape, draw_fields=self.options.draw_fields)
            try:
                self.vw.write(img)
            except OSError as exc:  # a full disk: this frame goes nowhere, the others' outputs are kept
                raise _OutputFailed("annotated.mp4", str(self.vw.path)) from exc
        # The frame's share of every output, together: the JSON line first (its latency ends there), the CSV rows after.
        target_rows = []
        for name, out in zip(names, outputs):
            if out.repeated:
                result.repeated[name] += 1
            target_rows.extend({"frame": index, "model": name, "target_id": t.id, **t.values()}
                               for t in self.recorder.update(index, name, out))
        record = frame_record(index, time_s, src.skipped, self.built, outputs, target_rows, wall_s=time.time(),
                              latency_ms=1e3 * (time.perf_counter() - src.decoded_at))
        if self.lines is not None:
            try:
                delivered = self.lines.write(record)
            except OSError as exc:  # not a reader that went away (that is False): a full disk, /dev/full
                raise _OutputFailed(self.lines.name, self.lines.name) from exc
            if not delivered:
                self.result.reader_gone = True
            if not delivered and self.result.message is None:
                self.result.message = (f"the reader of the JSON lines went away (frame {index} not delivered); "
                                       f"stopped there")
        line_at = time.perf_counter()
        frame_rows = [row for name, out in zip(names, outputs)
                      for row in response_rows(index, time_s, name, out, src.to_input)]
        for csv_file, rows in ((self.targets, target_rows), (self.responses, frame_rows)):
            if csv_file is not None and (rows or csv_file is self.responses):
                try:
                    csv_file.write(rows)
                except OSError as exc:
                    raise _OutputFailed(csv_file.path.name, str(csv_file.path)) from exc
        result.n_frames += 1
        if result.n_frames > 1:  # the first frame's step builds the models' state (and compiles): not latency
            self.latency.add(line_at - src.decoded_at)
        if self.options.keep_rows:
            result.targets.extend(target_rows)
            result.rows.extend(frame_rows)
        result.skipped += src.skipped
        return record

    def close_csv(self, failed: bool = False) -> None:
        """Close the CSV files and the JSON lines; after a failed write (``failed``) closing the file
        that failed would fail again (its unwritten rest): that is not a second error."""
        closes = [f.file.close for f in (self.responses, self.targets) if f is not None]
        closes += [self.lines.close] if self.lines is not None else []
        for close in closes:
            try:
                close()
            except OSError:
                if not failed:
                    raise

    def summarise(self, interrupted: bool, failed: _OutputFailed | None = None) -> None:
        """The run's end state and the summaries of its fields and targets into ``result``."""
        result, recorder, names = self.result, self.recorder, self.names
        result.interrupted = interrupted
        if failed is not None:
            cause = failed.__cause__
            result.error = f"{failed.name}: {getattr(cause, 'strerror', None) or cause}"
        result.truncated = self.src.truncated
        result.dropped, result.damaged = self.src.dropped, self.src.damaged
        result.message = self.src.message or result.message
        result.latency = self.latency.stats()
        # One decision on duplicated frames: the pre-scan's, or a model left to find out held frames.
        if result.duplicated is False and any(result.repeated[m.name] for m in self.built
                                              if m.repeat_threshold == "auto"):
            result.duplicated = True
        # Fields still alive at the end keep died = None.
        with recorder:
            result.fields = {name: recorder.summaries(name) for name in names}
            result.target_summaries = {name: recorder.target_summaries(name) for name in names
                                       if recorder.records[name].has_targets}
            result.alarms = {name: {"count": r.alarm_count, "first": r.first_alarm_frame, "peak": r.peak_response,
                                    "peak_frame": r.peak_frame}
                             for name, r in recorder.records.items()}


def _loop(src: FrameSource, built: list[Model], result: RunResult, out_dir, options: RunOptions) -> RunResult:
    from .._progress import bar as progress_bar

    frames = _Frames(src, built, result, options)
    interrupted = False
    failed: _OutputFailed | None = None
    gyro_ended: _GyroEnded | None = None
    bar = None
    # Ctrl-C / SIGTERM while a frame is in progress is deferred to the end of that frame
    # (stop.between): responses.csv, targets.csv and fields.json always cover the same frames.
    with interrupts(defer=True) as stop, threads(one_fewer() if options.spare_core and src.resized and not src.live else None):
        t0 = time.perf_counter()
        try:
            frames.open(out_dir)
            t0 = time.perf_counter()
            for item in stop.between(src):
                frames.step(item)
                if bar is None:
                    # the bar (and its clock) starts after the first frame, which may compile the
                    # kernels (tens of seconds, once per install): its rate and ETA never count it
                    bar = progress_bar(total=src.total, initial=1, unit="frame", leave=False,
                                       disable=not (options.progress and not options.quiet),
                                       desc=Path(src.name).name or src.name)
                else:
                    bar.update()
                if options.done(result.n_frames, time.perf_counter() - t0) or (frames.lines and frames.lines.gone):
                    break
            # A signal during the last frame (or the one the loop stopped after: Ctrl-C in a shell also
            # ends the reader of the JSON lines) is the run's interrupt, not one after its summaries:
            # fields.json said "complete" and the exit was a bare "interrupted".
            stop.check()
        except KeyboardInterrupt:
            interrupted = True
        except _GyroEnded as exc:
            gyro_ended = exc
        except _OutputFailed as exc:
            failed = exc
            if frames.vw is not None and exc.name == "annotated.mp4":
                frames.vw.abort()
                frames.vw = None
        except BaseException:
            if frames.vw is not None:
                frames.vw.abort()
            raise
        finally:
            result.seconds = time.perf_counter() - t0
            if bar is not None:
                bar.close()
            frames.close_csv(failed is not None)
            src.close()
        frames.summarise(interrupted, failed)
        if gyro_ended is not None:
            result.error = str(gyro_ended)
        if out_dir is not None:
            try:
                _finish(result, out_dir, frames.vw, options.plot)
            except BaseException as exc:
                if frames.vw is not None:
                    frames.vw.abort()
                if failed is None or not isinstance(exc, OSError):
                    raise
                # the summaries failed too (the same full disk): the first failure is the one to name
        if result.truncated:
            warnings.warn(result.message, TruncatedInputWarning, stacklevel=3)
        if failed is not None:
            cause = failed.__cause__
            raise OSError(getattr(cause, "errno", None), f"{getattr(cause, 'strerror', None) or cause}; the other "
                          f"outputs cover the {result.n_frames} frames before", failed.path) from cause
        if gyro_ended is not None:
            raise InputValueError(f"{gyro_ended}; the outputs cover the {result.n_frames} frames before")
        if interrupted:
            raise RunInterrupted(result)
    return result


def _finish(result: RunResult, out_dir: Path, vw: VideoWriter | None, plot: bool) -> None:
    """The summaries, small ones first: ``fields.json``, ``responses.png``, then ``annotated.mp4``
    (finishing the video may need more room than the disk has left)."""
    path = out_dir / "fields.json"
    write_json(path, result.summary())
    result.files["fields.json"] = path
    if plot and result.n_frames:
        from ..plots import plot_responses

        path = out_dir / "responses.png"
        title = f"{Path(result.source).name}: {', '.join(result.models)}"
        if result.interrupted or result.truncated or result.error:
            why = "interrupted" if result.interrupted else result.error or "input truncated"
            title += f" ({why} after {result.n_frames} frames)"
        rows = result.rows or result.files.get("responses.csv")
        targets = result.targets or result.files.get("targets.csv")
        if rows is not None:
            plot_responses(rows, path, fields=result.fields, title=title, fps=result.fps, targets=targets)
        result.files["responses.png"] = path
    if vw is not None:
        if vw.n_frames:
            result.files["annotated.mp4"] = vw.close()
        else:
            vw.abort()


# ---------------------------------------------------------------------------
# the demo (the `mlplc2 demo` command)
# ---------------------------------------------------------------------------
#: Models the demo runs (those registered).
DEMO_MODELS = ("mlplc2", "slplc2", "lplc2", "lgmd2")


@dataclass
class DemoResult:
    """What :func:`demo` made: the run, the ground truth and the field/object matches."""

    result: RunResult
    truth: dict
    video: Path
    matches: list[dict]


def demo(out="mlplc2_demo", *, scene: str = "four_phase", quiet: bool = False, progress: bool = True,
         video: bool = True, stabilise: bool = False) -> DemoResult:
    """Generate a multi-object scene, run the models on it and match fields to objects.

    Writes ``demo.mp4`` and ``demo_gt.json`` into ``out``, then
    :func:`run` (``mlplc2``, ``slplc2``, ``lplc2`` and ``lgmd2`` when it is
    registered; ``video=True``) with its outputs in ``out/demo_mlplc2``.

    ``stabilise``: gaze stabilisation (:attr:`RunOptions.stabilise`). False by default, unlike
    :func:`run`: the scenes are the paper's Fig. 4 and 5, whose background scrolls behind a still
    camera while the objects keep their places in the image (docs/history.md, "LPLC2's cell and the
    paper's scenes under gaze stabilisation"); stabilised, the scroll is taken for a pan and the objects then drift with
    the camera, one edge standing still.

    ``matches`` has one entry per ground-truth object (see :func:`match_fields`):
    the mLPLC2 field that stands for it and the distance in pixels.
    """
    from .. import stimuli

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    video_path, gt_path = stimuli.write(scene, out / "demo.mp4")
    truth = json.loads(gt_path.read_text(encoding="utf-8"))
    names = [m for m in DEMO_MODELS if m in available_models()]
    res = run(video_path, names, out=out / "demo_mlplc2", video=video, quiet=quiet, progress=progress,
              stabilise=bool(stabilise))
    return DemoResult(res, truth, video_path, match_fields(res.fields.get("mlplc2", []), truth))
