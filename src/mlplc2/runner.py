"""Run one or several models over a video, an image sequence or a camera.

:func:`run` decodes the frames once (streamed, in a background thread) and
steps every model on each frame, writing as it goes:

``responses.csv``
    one row per active field per frame (``frame,time_s,model,field_id,x,y,response,collision``),
    flushed after every frame: a run stopped by Ctrl-C leaves a valid file.
``fields.json``
    one summary per attention field (centre, birth, death, peak, first alarm).
``responses.png``
    response against frame, one panel per model (see :mod:`mlplc2.plots`).
``annotated.mp4``
    (``video=True``) the input with the fields drawn.

The summary files are written under a hidden temporary name and renamed
when complete, so a file with its final name is never half-written.
"""

from __future__ import annotations

import csv
import io
import json
import logging
import math
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .io import FrameSource, TruncatedInputWarning, VideoWriter, atomic_path, open_source
from .models.base import Model, Output, get_model

__all__ = ["run", "RunResult", "RunInterrupted", "TruncatedInputWarning", "COLUMNS", "default_out_dir",
           "write_stimulus", "demo", "DemoResult", "match_fields"]

log = logging.getLogger(__name__)

#: Columns of ``responses.csv``, in order.
COLUMNS = ("frame", "time_s", "model", "field_id", "x", "y", "response", "collision")


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run`; the outputs for the frames done were written.

    ``.result`` is the :class:`RunResult` of the frames processed.
    """

    def __init__(self, result: "RunResult"):
        super().__init__(f"interrupted after {result.n_frames} frames")
        self.result = result


@dataclass
class RunResult:
    """What :func:`run` computed.

    Attributes
    ----------
    rows : list of dict
        The rows of ``responses.csv`` (keys :data:`COLUMNS`; ``None`` where the
        CSV cell is empty; ``collision`` is 0 or 1).
    fields : dict
        Per model name, the list of field summaries written to ``fields.json``.
    fps : float
        Frame rate used (``time_s = frame / fps``).
    n_frames : int
        Frames processed.
    truncated : bool
        The input stopped decoding early (see ``message``).
    interrupted : bool
        The run was stopped by Ctrl-C.
    files : dict
        Output name -> path of the files written (empty with ``out=False``).
    """

    source: str
    models: list[str]
    fps: float
    size: tuple[int, int]
    model_size: tuple[int, int]
    start: int = 0
    n_frames: int = 0
    rows: list[dict] = field(default_factory=list)
    fields: dict[str, list[dict]] = field(default_factory=dict)
    truncated: bool = False
    interrupted: bool = False
    message: str | None = None
    out: Path | None = None
    files: dict[str, Path] = field(default_factory=dict)

    def to_dataframe(self):
        """``rows`` as a pandas DataFrame (needs pandas: ``pip install 'mlplc2[pandas]'``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("RunResult.to_dataframe needs pandas: pip install 'mlplc2[pandas]'") from None
        df = pd.DataFrame(self.rows, columns=list(COLUMNS))
        df["field_id"] = df["field_id"].astype("Int64")
        df["x"] = df["x"].astype("float64")
        df["y"] = df["y"].astype("float64")
        df["collision"] = df["collision"].astype(bool)
        return df

    def summary(self) -> dict[str, Any]:
        """The content of ``fields.json``."""
        return {
            "video": self.source,
            "fps": self.fps,
            "size": list(self.size),
            "model_size": list(self.model_size),
            "start": self.start,
            "n_frames": self.n_frames,
            "complete": not (self.truncated or self.interrupted),
            "truncated": self.truncated,
            "interrupted": self.interrupted,
            "models": self.fields,
        }


class _FieldTracker:
    """Follows the fields of one model across frames to build their summaries."""

    def __init__(self, offset: int):
        self.offset = offset  # source index of model frame 0
        self.fields: dict[int, dict] = {}
        self.alive: set[int] = set()

    def update(self, index: int, out: Output, to_input) -> None:
        present = set()
        for f in out.fields:
            present.add(f.id)
            x, y = to_input(f.x, f.y)
            s = self.fields.get(f.id)
            if s is None:
                s = self.fields[f.id] = {
                    "id": f.id, "x": _r(x), "y": _r(y), "born": f.born + self.offset, "died": None,
                    "peak_response": _num(f.response), "peak_frame": index, "first_alarm_frame": None,
                }
            elif f.response > s["peak_response"]:
                s.update(x=_r(x), y=_r(y), peak_response=_num(f.response), peak_frame=index)
            if f.collision and s["first_alarm_frame"] is None:
                s["first_alarm_frame"] = index
        for fid in self.alive - present:
            self.fields[fid]["died"] = index
        self.alive = present

    def summaries(self) -> list[dict]:
        return [self.fields[k] for k in sorted(self.fields)]


def _r(v: float) -> float:
    return round(float(v), 2)


def _num(v: float) -> float:
    v = float(v)
    return float(f"{v:.7g}") if math.isfinite(v) else v


def _rows(index: int, time_s: float, name: str, out: Output, to_input) -> list[dict]:
    if not out.fields:
        return [{"frame": index, "time_s": time_s, "model": name, "field_id": None, "x": None, "y": None,
                 "response": _num(out.response), "collision": int(bool(out.collision))}]
    rows = []
    for f in out.fields:
        x, y = to_input(f.x, f.y)
        rows.append({"frame": index, "time_s": time_s, "model": name, "field_id": f.id, "x": _r(x),
                     "y": _r(y), "response": _num(f.response), "collision": int(bool(f.collision))})
    return rows


def default_out_dir(source) -> Path:
    """``<stem>_mlplc2/`` next to the input (camera N: ``./cameraN_mlplc2``)."""
    from .io import _is_camera

    if _is_camera(source):
        return Path.cwd() / f"camera{int(source)}_mlplc2"
    p = Path(source)
    if p.is_dir():
        p = p.resolve()
        return p.parent / f"{p.name}_mlplc2"
    if any(ch in str(source) for ch in "*?[") and not p.exists():
        parent = p.parent
        while any(ch in str(parent) for ch in "*?["):
            parent = parent.parent
        parent = parent.resolve()
        return parent.parent / f"{parent.name}_mlplc2"
    return p.parent / f"{p.stem}_mlplc2"


def _build_models(models, fps: float, params) -> list[Model]:
    if isinstance(models, (str, Model)):
        models = [models]
    built: list[Model] = []
    seen = set()
    for m in models:
        if isinstance(m, Model):
            model = m
            model.reset()
        else:
            name = str(m).strip().lower()
            cls = get_model(name)
            p = params.get(name) if isinstance(params, Mapping) else params
            model = cls(fps=fps) if p is None else cls(fps=fps, params=p)
        if model.name in seen:
            continue
        seen.add(model.name)
        built.append(model)
    if not built:
        from ._validation import InputValueError

        raise InputValueError("no model given")
    return built


def _primary(models: Sequence[Model]) -> int | None:
    """Index of the first model of the LPLC2 family (the one drawn on the video)."""
    from .models.lplc2 import _LPLC2Family

    for i, m in enumerate(models):
        if isinstance(m, _LPLC2Family):
            return i
    return None


def run(source, models: Sequence[str | Model] | str = ("mlplc2",), *, out=None, fps=None, resize=None,
        scale=None, start: int = 0, end: int | None = None, video: bool = False, quiet: bool = False,
        params=None, progress: bool = True, plot: bool = True, backend: str = "opencv") -> RunResult:
    """Run models over a video, a folder of images, a glob pattern or a camera.

    Parameters
    ----------
    source : str, path-like or int
        Input; see :func:`mlplc2.io.open_source`.
    models : sequence of str or Model
        Registry names (``mlplc2.available_models()``) or model instances. All
        models see the same decoded frames (decoded once).
    out : path, None or False
        Output folder (created). ``None``: ``<stem>_mlplc2/`` next to the
        input. ``False``: write nothing, only return the result.
    fps : float, optional
        Frame rate to use instead of the container's (images: 30).
    resize : (W, H) or 'WxH', optional
        Frames are resized before the models see them; field coordinates in
        the outputs are mapped back to input pixels (``x * W_in / W``).
    scale : float, optional
        Or resize by a factor.
    start, end : int
        Process source frames ``start <= frame < end``.
    video : bool
        Also write ``annotated.mp4``: the input frames with the fields of the
        first LPLC2-family model drawn, and every model's response in a header.
    quiet : bool
        No progress bar.
    params : Params or dict, optional
        Passed as ``params=`` to every model, or a dict ``{name: params}``.
    progress : bool
        Show a tqdm progress bar on stderr (unless ``quiet``).
    plot : bool
        Write ``responses.png``.
    backend : {'opencv', 'pyav'}
        Video decoder.

    Returns
    -------
    RunResult

    Raises
    ------
    InputError
        Bad input (missing file, not a video, unknown model, bad resize, ...).
    RunInterrupted
        On Ctrl-C, after writing the outputs of the frames done
        (``fields.json`` then says ``"interrupted": true``).

    Warns
    -----
    TruncatedInputWarning
        The input stopped decoding early; the outputs cover the frames decoded
        and ``result.truncated`` is True.
    """
    # Validate everything cheap before decoding anything.
    if isinstance(models, str):
        models = [s for s in models.split(",") if s.strip()]
    for m in models:
        if not isinstance(m, Model):
            get_model(str(m).strip())
    src = open_source(source, fps=fps, start=start, end=end, resize=resize, scale=scale,
                      keep_original=video, backend=backend)
    try:
        built = _build_models(models, src.fps, params)
    except BaseException:
        src.close()
        raise
    names = [m.name for m in built]
    result = RunResult(source=str(source), models=names, fps=src.fps, size=src.size,
                       model_size=src.out_size, start=src.start)
    out_dir = None
    if out is not False:
        out_dir = Path(out) if out is not None else default_out_dir(source)
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except BaseException:
            src.close()
            raise
        result.out = out_dir
    return _loop(src, built, names, result, out_dir, video=video, show=progress and not quiet, plot=plot)


def _loop(src: FrameSource, built, names, result: RunResult, out_dir, *, video, show, plot) -> RunResult:
    from tqdm import tqdm

    trackers = [_FieldTracker(src.start) for _ in built]
    primary = _primary(built)
    csv_file = writer = vw = None
    interrupted = False
    bar = None
    try:
        if out_dir is not None:
            csv_path = out_dir / "responses.csv"
            csv_file = open(csv_path, "w", newline="", buffering=1, encoding="utf-8")
            buf = io.StringIO()
            writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
            writer.writeheader()
            csv_file.write(buf.getvalue())
            csv_file.flush()
            result.files["responses.csv"] = csv_path
            if video:
                vw = VideoWriter(out_dir / "annotated.mp4", src.fps, src.size)
        bar = tqdm(total=src.total, disable=not show, unit="frame", file=sys.stderr,
                   desc=Path(src.name).name or src.name, dynamic_ncols=True, leave=False)
        to_input = src.to_input
        fps = src.fps
        for item in src:
            index, frame = item[0], item[1]
            outputs = [m.step(frame) for m in built]
            time_s = round(index / fps, 6)
            frame_rows = []
            for name, out, tracker in zip(names, outputs, trackers):
                frame_rows.extend(_rows(index, time_s, name, out, to_input))
                tracker.update(index, out, to_input)
            if writer is not None:
                # One write() per frame, then flush: an interrupt leaves whole frames only.
                buf.seek(0)
                buf.truncate()
                writer.writerows(frame_rows)
                csv_file.write(buf.getvalue())
                csv_file.flush()
            result.rows.extend(frame_rows)
            if vw is not None:
                from .plots import annotate_frame

                vw.write(annotate_frame(item[2], outputs, names, src.scale_x, src.scale_y, primary=primary,
                                        index=index))
            result.n_frames += 1
            bar.update()
    except KeyboardInterrupt:
        interrupted = True
    except BaseException:
        if vw is not None:
            vw.abort()
        raise
    finally:
        if bar is not None:
            bar.close()
        if csv_file is not None:
            csv_file.close()
        src.close()

    result.interrupted = interrupted
    result.truncated = src.truncated
    result.message = src.message
    # Fields still alive at the end keep died = None.
    result.fields = {name: t.summaries() for name, t in zip(names, trackers)}
    if out_dir is not None:
        try:
            _finish(result, out_dir, vw, plot)
        except BaseException:
            if vw is not None:
                vw.abort()
            raise
    if result.truncated:
        warnings.warn(result.message, TruncatedInputWarning, stacklevel=3)
    if interrupted:
        raise RunInterrupted(result)
    return result


def _finish(result: RunResult, out_dir: Path, vw: VideoWriter | None, plot: bool) -> None:
    path = out_dir / "fields.json"
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(result.summary(), f, indent=1)
            f.write("\n")
    result.files["fields.json"] = path
    if vw is not None:
        if vw.n_frames:
            result.files["annotated.mp4"] = vw.close()
        else:
            vw.abort()
    if plot and result.n_frames:
        from .plots import plot_responses

        path = out_dir / "responses.png"
        title = f"{Path(result.source).name}: {', '.join(result.models)}"
        plot_responses(result.rows, path, fields=result.fields, title=title, fps=result.fps)
        result.files["responses.png"] = path


# ---------------------------------------------------------------------------
# stimulus files and the demo (the `mlplc2 stimulus` and `mlplc2 demo` commands)
# ---------------------------------------------------------------------------
def write_stimulus(name: str, out, *, gt=None, **options) -> tuple[Path, Path]:
    """Generate stimulus ``name`` (:func:`mlplc2.stimuli.generate`) and write it.

    Writes the video to ``out`` (``.mp4`` H.264, or ``.avi`` MJPG) and its
    ground truth to ``gt`` (default: ``<out stem>_gt.json`` beside it).
    ``options`` go to the generator (e.g. ``seed``, ``background``).
    Returns ``(video_path, gt_path)``.
    """
    from . import stimuli
    from .io import write_video

    stim = stimuli.generate(name, **options)
    out = Path(out)
    gt_path = Path(gt) if gt is not None else out.with_name(f"{out.stem}_gt.json")
    write_video(out, stim.frames, stim.fps, stim.size)
    truth = dict(stim.to_ground_truth())
    truth = {"name": name, "video": out.name, **truth}
    with atomic_path(gt_path) as tmp:
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(truth, f, indent=1, default=_json_default)
            f.write("\n")
    return out, gt_path


def _json_default(obj):
    import numpy as np

    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


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
         video: bool = True) -> DemoResult:
    """Generate a multi-object scene, run the models on it and match fields to objects.

    Writes ``demo.mp4`` and ``demo_gt.json`` into ``out``, then
    :func:`run` (``mlplc2``, ``slplc2``, ``lplc2`` and ``lgmd2`` when it is
    registered; ``video=True``) with its outputs in ``out/demo_mlplc2``.

    ``matches`` has one entry per ground-truth object (see :func:`match_fields`):
    the mLPLC2 field that stands for it and the distance in pixels.
    """
    from .models.base import available_models

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    video_path, gt_path = write_stimulus(scene, out / "demo.mp4")
    with open(gt_path, encoding="utf-8") as f:
        truth = json.load(f)
    names = [m for m in DEMO_MODELS if m in available_models()]
    res = run(video_path, names, out=out / "demo_mlplc2", video=video, quiet=quiet, progress=progress)
    return DemoResult(res, truth, video_path, match_fields(res.fields.get("mlplc2", []), truth))


def match_fields(fields: list[dict], truth: dict, *, radius: float = 25.0) -> list[dict]:
    """For each ground-truth object, the field that stands for it.

    Among the fields born while the object is on screen, the one with the
    largest peak response within ``radius`` px of the object's centre, else
    the nearest one (``None`` when no field was born meanwhile).
    """
    matches = []
    for obj in truth.get("objects", []):
        if obj.get("center") is None:
            continue
        cx, cy = obj["center"]
        spans = [obj[k] for k in ("approach", "hold", "recede", "translate") if obj.get(k)]
        t0 = min(s[0] for s in spans) if spans else 0
        t1 = max(s[1] for s in spans) if spans else math.inf
        cand = [f for f in fields if t0 <= f["born"] < t1]
        near = [f for f in cand if math.hypot(f["x"] - cx, f["y"] - cy) <= radius]
        if near:  # the strongest field near the object (a field may be replaced while it looms)
            best = max(near, key=lambda f: (f["peak_response"], -f["born"]))
        else:
            best = min(cand, key=lambda f: math.hypot(f["x"] - cx, f["y"] - cy), default=None)
        matches.append({
            "object": obj.get("id"), "center": [cx, cy], "frames": [t0, t1],
            "field": None if best is None else best["id"],
            "field_center": None if best is None else [best["x"], best["y"]],
            "distance": None if best is None else round(math.hypot(best["x"] - cx, best["y"] - cy), 1),
            "first_alarm_frame": None if best is None else best["first_alarm_frame"],
        })
    return matches
