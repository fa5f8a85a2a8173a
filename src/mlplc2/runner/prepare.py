"""What a run does before its first frame (:func:`open_run`): the models resolved, built from the options or
adopted, the source opened and checked against them (frame size, aspect ratio, heading, gyro), its first frames
pre-scanned for duplicates (:data:`PRESCAN_FRAMES`), the output folder made and the
:class:`~mlplc2.runner.result.RunResult` to fill."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from .._validation import InputTypeError, InputValueError, as_gray
from ..io import FrameSource, open_source
from ..io.formats import STDIN, without_password
from ..models.base import (Model, check_repeat_threshold, frame_change, get_model, looks_duplicated,
                           resolve_names)
from ..params import Params
from ..plots import DRAW_FIELDS
from ..targets import TargetParams, check_hfov
from .folders import is_the_input, prepare_out_dir
from .options import RunOptions
from .result import RunResult


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


def open_run(source, models, options: RunOptions, out) -> tuple[FrameSource, list[Model], RunResult]:
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
