"""Score model outputs against ground truth (the ``mlplc2 evaluate`` command).

Two kinds of truth (schema in ``docs/evaluation.md``):

object level
    per video, the objects with their centre (or a per-frame track) and the
    frame intervals of their phases (``approach``, ``hold``, ``recede``,
    ``translate``), as in the paper's ``ground_truth.json``. Scored per
    approaching object: detected or not, latency to the first field within
    the match radius and to the first alarm, localisation error, fields
    created; and false alarms per minute of video.
clip level
    ``"label": "collision" | "no_collision"`` with an optional
    ``collision_frame``. Scored as a binary classification (alarm before the
    collision frame = true positive, alarm in a no-collision clip = false
    positive): accuracy, precision, recall and warning time.

:func:`evaluate` takes run results (a :class:`~mlplc2.runner.RunResult`, an
output folder with ``responses.csv`` and ``fields.json``, a ``mlplc2 batch``
folder) or videos (the models are run first) and returns an
:class:`Evaluation` with per-object, per-video and per-model tables, as
Markdown (:meth:`Evaluation.to_markdown`) and JSON (:meth:`Evaluation.to_dict`).
"""

from __future__ import annotations

import csv
import json
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any, Iterable

from ._validation import InputTypeError, InputValueError, check_int, check_real

__all__ = ["evaluate", "Evaluation", "EvaluationWarning", "load_ground_truth", "GroundTruth", "VideoTruth",
           "ObjectTruth", "PHASES", "KINDS", "DEFAULT_TAIL", "DEFAULT_MATCH_RADIUS"]

#: Phase intervals an object may have, ``[start, end)`` in frames.
PHASES = ("approach", "hold", "recede", "translate")
#: ``"kind"`` values and the phase each stands for (``"kind"`` + ``"interval"`` is a shorthand).
KINDS = {"approaching": "approach", "static": "hold", "receding": "recede", "translating": "translate"}
#: Frames after the end of an approach during which a detection or alarm still counts for it.
DEFAULT_TAIL = 25
#: Match radius in ground-truth pixels.
DEFAULT_MATCH_RADIUS = 20.0
_LABELS = ("collision", "no_collision")
#: Row order of the comparison table (other registered models follow, alphabetically).
MODEL_ORDER = ("mlplc2", "slplc2", "lplc2", "lgmd2", "lgmd1")


class EvaluationWarning(UserWarning):
    """Something :func:`evaluate` scored with a caveat or did not score (one line;
    also in :attr:`Evaluation.warnings`): an input given twice, incomplete results,
    an input that is neither results nor a video."""


# ---------------------------------------------------------------------------
# ground truth
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ObjectTruth:
    """One object of a video's ground truth (coordinates in ground-truth pixels)."""

    id: Any
    center: tuple[float, float] | None = None
    track: tuple[tuple[int, float, float], ...] = ()
    polarity: str | None = None
    approach: tuple[int, int] | None = None
    hold: tuple[int, int] | None = None
    recede: tuple[int, int] | None = None
    translate: tuple[int, int] | None = None

    @property
    def approaching(self) -> bool:
        return self.approach is not None

    def center_at(self, frame: int) -> tuple[float, float] | None:
        """Centre at ``frame``: the track linearly interpolated (held constant
        before its first and after its last point), else ``center``."""
        if self.track:
            t = self.track
            if frame <= t[0][0]:
                return (t[0][1], t[0][2])
            if frame >= t[-1][0]:
                return (t[-1][1], t[-1][2])
            lo, hi = 0, len(t) - 1
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if t[mid][0] <= frame:
                    lo = mid
                else:
                    hi = mid
            (f0, x0, y0), (f1, x1, y1) = t[lo], t[hi]
            a = (frame - f0) / (f1 - f0)
            return (x0 + a * (x1 - x0), y0 + a * (y1 - y0))
        return self.center

    def life_end(self) -> int:
        """End of approach + the hold that directly follows it (exclusive)."""
        end = self.approach[1]
        if self.hold is not None and self.hold[0] <= end:
            end = max(end, self.hold[1])
        return end


@dataclass(frozen=True)
class VideoTruth:
    """Ground truth of one video: objects and/or a clip-level label."""

    key: str
    size: tuple[int, int] | None = None
    frames: int | None = None
    fps: float | None = None
    objects: tuple[ObjectTruth, ...] = ()
    label: str | None = None
    collision_frame: int | None = None

    @property
    def object_level(self) -> bool:
        return bool(self.objects) or self.label is None


class GroundTruth(Mapping):
    """Video key -> :class:`VideoTruth`, with :meth:`match` to find a video's truth."""

    def __init__(self, videos: Mapping[str, VideoTruth], source: str = "<dict>"):
        self._videos = dict(videos)
        self.source = source

    def __getitem__(self, key):
        return self._videos[key]

    def __iter__(self):
        return iter(self._videos)

    def __len__(self):
        return len(self._videos)

    def match(self, video) -> VideoTruth | None:
        """The truth of ``video`` (a path): the key that is the longest suffix of
        its path (``scenes/a.avi`` matches ``/data/paper/scenes/a.avi``), else the
        key with the same basename; ``None`` if none. Ambiguous basenames raise."""
        parts = PurePosixPath(str(video).replace("\\", "/")).parts
        best, best_len = None, 0
        for key in self._videos:
            kparts = PurePosixPath(key.replace("\\", "/")).parts
            kparts = tuple(p for p in kparts if p not in (".", ""))
            if kparts and len(kparts) <= len(parts) and tuple(parts[-len(kparts):]) == kparts:
                if len(kparts) > best_len:
                    best, best_len = key, len(kparts)
        if best is not None:
            return self._videos[best]
        name = parts[-1] if parts else ""
        same = [k for k in self._videos if PurePosixPath(k.replace("\\", "/")).name == name]
        if len(same) > 1:
            raise InputValueError(f"{video}: ambiguous ground truth, several keys have its name: {', '.join(same)}")
        if same:
            return self._videos[same[0]]
        if len(self._videos) == 1:
            only = next(iter(self._videos.values()))
            if only.key == "*":
                return only
        return None


def _bad(where: str, message: str) -> InputValueError:
    return InputValueError(f"{where}: {message}")


def _int(value, where: str, minimum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not float(value).is_integer():
        raise _bad(where, f"expected an integer, got {value!r}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise _bad(where, f"expected an integer >= {minimum}, got {value}")
    return value


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
        raise _bad(where, f"expected a finite number, got {value!r}")
    return float(value)


def _interval(value, where: str) -> tuple[int, int]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _bad(where, f"expected an interval [start, end), got {value!r}")
    start, end = _int(value[0], where, 0), _int(value[1], where, 0)
    if end <= start:
        raise _bad(where, f"interval [start, end) must have end > start, got {list(value)}")
    return start, end


def _point(value, where: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _bad(where, f"expected [x, y], got {value!r}")
    return _number(value[0], where), _number(value[1], where)


def _parse_object(obj, where: str, index: int) -> ObjectTruth:
    if not isinstance(obj, Mapping):
        raise _bad(where, f"expected an object (JSON dict), got {type(obj).__name__}")
    oid = obj.get("id", index + 1)
    center = _point(obj["center"], f"{where}.center") if obj.get("center") is not None else None
    track: list[tuple[int, float, float]] = []
    if obj.get("track") is not None:
        raw = obj["track"]
        if not isinstance(raw, (list, tuple)) or not raw:
            raise _bad(f"{where}.track", "expected a non-empty list of [frame, x, y]")
        for k, p in enumerate(raw):
            if not isinstance(p, (list, tuple)) or len(p) != 3:
                raise _bad(f"{where}.track[{k}]", f"expected [frame, x, y], got {p!r}")
            track.append((_int(p[0], f"{where}.track[{k}]", 0), _number(p[1], f"{where}.track[{k}]"),
                          _number(p[2], f"{where}.track[{k}]")))
        track.sort()
        if len({p[0] for p in track}) != len(track):
            raise _bad(f"{where}.track", "a frame appears twice")
    phases = {p: _interval(obj[p], f"{where}.{p}") for p in PHASES if obj.get(p) is not None}
    if obj.get("kind") is not None:
        kind = obj["kind"]
        if not isinstance(kind, str) or kind not in KINDS:
            raise _bad(f"{where}.kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")
        if obj.get("interval") is not None:
            phases.setdefault(KINDS[kind], _interval(obj["interval"], f"{where}.interval"))
        elif KINDS[kind] not in phases:
            raise _bad(where, f"kind {kind!r} needs an 'interval' [start, end) or a {KINDS[kind]!r} interval")
    polarity = obj.get("polarity")
    if polarity is not None and polarity not in ("dark", "bright"):
        raise _bad(f"{where}.polarity", f"expected 'dark' or 'bright', got {polarity!r}")
    if "approach" in phases and center is None and not track:
        raise _bad(where, "an approaching object needs a 'center' [x, y] or a 'track'")
    return ObjectTruth(id=oid, center=center, track=tuple(track), polarity=polarity, **phases)


def _parse_entry(key: str, entry, where: str) -> VideoTruth:
    if not isinstance(entry, Mapping):
        raise _bad(where, f"expected a JSON object, got {type(entry).__name__}")
    if "objects" not in entry and "label" not in entry:
        raise _bad(where, "a video entry needs 'objects' (object level) or 'label' (clip level)")
    size = None
    if entry.get("size") is not None:
        s = entry["size"]
        if not isinstance(s, (list, tuple)) or len(s) != 2:
            raise _bad(f"{where}.size", f"expected [W, H], got {s!r}")
        size = (_int(s[0], f"{where}.size", 1), _int(s[1], f"{where}.size", 1))
    frames = _int(entry["frames"], f"{where}.frames", 1) if entry.get("frames") is not None else None
    fps = None
    if entry.get("fps") is not None:
        fps = _number(entry["fps"], f"{where}.fps")
        if fps <= 0:
            raise _bad(f"{where}.fps", f"expected a positive number, got {fps}")
    objects = entry.get("objects", [])
    if not isinstance(objects, (list, tuple)):
        raise _bad(f"{where}.objects", f"expected a list, got {type(objects).__name__}")
    objs = tuple(_parse_object(o, f"{where}.objects[{i}]", i) for i, o in enumerate(objects))
    label = entry.get("label")
    if label is not None and label not in _LABELS:
        raise _bad(f"{where}.label", f"expected 'collision' or 'no_collision', got {label!r}")
    cf = entry.get("collision_frame")
    if cf is not None:
        if label != "collision":
            raise _bad(f"{where}.collision_frame", "only a clip labelled 'collision' has a collision frame")
        cf = _int(cf, f"{where}.collision_frame", 0)
    return VideoTruth(key=key, size=size, frames=frames, fps=fps, objects=objs, label=label, collision_frame=cf)


def load_ground_truth(gt) -> GroundTruth:
    """Read ground truth: a path to a JSON file, or the parsed JSON.

    Accepted: ``{"videos": {KEY: ENTRY, ...}}`` (the paper's ``ground_truth.json``;
    other top-level keys are ignored) or a single ``ENTRY`` (as written by
    ``mlplc2 stimulus``), whose key is its ``"video"`` field (matched by
    basename), else ``"*"`` (applies to any video). Raises
    :class:`~mlplc2.InputValueError` naming the offending field.
    """
    if isinstance(gt, GroundTruth):
        return gt
    source = "<dict>"
    if isinstance(gt, (str, Path)):
        source = str(gt)
        data = _read_json(gt)
    else:
        data = gt
    return _parse_ground_truth(data, source)


def _read_json(path):
    """The parsed content of the ground-truth file ``path`` (one-line errors)."""
    path = Path(path)
    if path.is_dir():
        hint = " (did you mean its ground_truth.json?)" if (path / "ground_truth.json").is_file() else ""
        raise InputValueError(f"{path}: is a folder, not a ground truth JSON file{hint}")
    if not path.is_file():
        raise InputValueError(f"{path}: ground truth file not found")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputValueError(f"{path}: not valid JSON ({exc})") from None


def _parse_ground_truth(data, source: str) -> GroundTruth:
    if not isinstance(data, Mapping):
        raise InputValueError(f"{source}: ground truth must be a JSON object, got {type(data).__name__}")
    if "videos" in data:
        videos = data["videos"]
        if not isinstance(videos, Mapping) or not videos:
            raise InputValueError(f"{source}: 'videos' must be a non-empty object {{name: entry}}")
        parsed = {str(k): _parse_entry(str(k), v, f"{source}: videos[{k!r}]") for k, v in videos.items()}
    else:
        key = str(data.get("video") or "*")
        parsed = {key: _parse_entry(key, data, source)}
    return GroundTruth(parsed, source)


# ---------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------
@dataclass
class _Run:
    """One model's output on one video, reduced to what scoring needs."""

    source: str
    model: str
    label: str
    fps: float
    size: tuple[int, int] | None
    start: int
    n_frames: int
    fields: list[dict]
    # frame -> [(field_id, x, y, collision)] for rows with a field; frame -> alarm for all rows
    frame_fields: dict[int, list[tuple[int, float, float, bool]]]
    frame_alarm: dict[int, bool]
    param_set: str | None = None
    params: dict = field(default_factory=dict)  # the parameter overrides it ran with (batch: done.json)
    # where the run came from (results folder or input, for messages) and its identity (two runs of one
    # label and video from different identities are an error); why it is incomplete (None: complete)
    origin: str = ""
    ident: Any = None
    incomplete: str | None = None
    # False when the folder does not say which video it is (no fields.json nor done.json)
    video_known: bool = True


def _localises(model: str) -> bool:
    """mLPLC2 and sLPLC2 localise; LPLC2 (one frame-wide cell) and the LGMDs do not."""
    from .models.base import REGISTRY
    from .models.lplc2 import LPLC2, _LPLC2Family

    cls = REGISTRY.get(model)
    return cls is not None and issubclass(cls, _LPLC2Family) and not issubclass(cls, LPLC2)


def _runs_from_rows(source, rows, fields_by_model, *, fps, size, start, n_frames, models, param_set=None,
                    params=None, origin="", ident=None, incomplete=None, video_known=True):
    from .batch import param_label

    per: dict[str, _Run] = {}

    def new(m, fields):
        if params or param_set in (None, "", "default"):
            label = param_label(m, params)
        else:  # a parameter set whose overrides are not recorded
            label = f"{m}@{param_set}"
        return _Run(str(source), m, label, fps, size, start, n_frames, list(fields), {}, {}, param_set,
                    dict(params or {}), origin or str(source), ident, incomplete, video_known)

    for r in rows:
        m = r["model"]
        if models is not None and m not in models:
            continue
        run = per.get(m)
        if run is None:
            run = per[m] = new(m, fields_by_model.get(m, []))
        f = int(r["frame"])
        coll = bool(int(r["collision"]))
        run.frame_alarm[f] = run.frame_alarm.get(f, False) or coll
        if r["field_id"] not in (None, ""):
            run.frame_fields.setdefault(f, []).append((int(r["field_id"]), float(r["x"]), float(r["y"]), coll))
    for m in fields_by_model:
        if m not in per and (models is None or m in models):
            per[m] = new(m, fields_by_model[m])
    return list(per.values())


def _incomplete_reason(n_frames, interrupted, truncated, message=None, complete=True) -> str | None:
    """Why a run's results are incomplete (``None``: they are complete)."""
    if interrupted:
        return f"the run was interrupted after {n_frames} frames"
    if truncated:
        return f"the video stopped decoding after {n_frames} frames" + (f" ({message})" if message else "")
    if not complete:
        return f"the run is marked incomplete after {n_frames} frames"
    return None


def _runs_from_result(res, models, origin=None) -> list["_Run"]:
    reason = _incomplete_reason(res.n_frames, getattr(res, "interrupted", False), getattr(res, "truncated", False),
                                getattr(res, "message", None))
    return _runs_from_rows(res.source, res.rows, res.fields, fps=res.fps, size=tuple(res.size), start=res.start,
                           n_frames=res.n_frames, models=models, origin=origin or f"a RunResult of {res.source}",
                           ident=("object", id(res)), incomplete=reason)


def _read_folder(folder: Path, models) -> list["_Run"]:
    csv_path = folder / "responses.csv"
    with open(csv_path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        missing = {"frame", "model", "field_id", "x", "y", "collision"} - set(reader.fieldnames or ())
        if missing:
            raise InputValueError(f"{csv_path}: not a responses.csv (missing columns {', '.join(sorted(missing))})")
        try:
            rows = [r for r in reader if r["frame"] not in (None, "")]
            for r in rows:
                int(r["frame"]), int(r["collision"])
        except (TypeError, ValueError):
            raise InputValueError(f"{csv_path}: malformed row") from None
    info: dict = {}
    fj = folder / "fields.json"
    if fj.is_file():
        try:
            info = json.loads(fj.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputValueError(f"{fj}: not valid JSON ({exc})") from None
        if not isinstance(info, Mapping):
            raise InputValueError(f"{fj}: not a fields.json of mlplc2 run (expected a JSON object)")
    done: dict = {}
    dj = folder / "done.json"
    if dj.is_file():
        try:
            done = json.loads(dj.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError):
            done = {}
        if not isinstance(done, Mapping):
            done = {}
    frames = sorted({int(r["frame"]) for r in rows})
    try:
        fps = info.get("fps")
        if not fps:
            times = [(int(r["frame"]), float(r["time_s"])) for r in rows if r.get("time_s") not in (None, "")]
            pos = [(fr, t) for fr, t in times if fr > 0 and t > 0]
            fps = pos[0][0] / pos[0][1] if pos else 30.0
        fps = float(fps)
        start = int(info.get("start", frames[0] if frames else 0))
        n_frames = int(info.get("n_frames", len(frames)))
        size = tuple(int(v) for v in info["size"]) if info.get("size") else None
    except (TypeError, ValueError):
        raise InputValueError(f"{fj if info else csv_path}: malformed fps, start, n_frames or size") from None
    if not math.isfinite(fps) or fps <= 0:
        raise InputValueError(f"{fj if info else csv_path}: fps must be a positive number, got {fps!r}")
    source = info.get("video") or done.get("video") or str(folder)
    try:  # the overrides a batch task ran with (JSON text in done.json)
        params = json.loads(done["params"]) if done.get("params") else {}
    except (TypeError, ValueError):
        params = {}
    if not isinstance(params, Mapping):
        params = {}
    if not info:
        incomplete = "no fields.json next to responses.csv, the run did not finish"
    else:
        incomplete = _incomplete_reason(n_frames, info.get("interrupted"), info.get("truncated"),
                                        complete=info.get("complete") is not False)
    return _runs_from_rows(source, rows, info.get("models", {}), fps=fps, size=size, start=start,
                           n_frames=n_frames, models=models, param_set=done.get("param_set"), params=params,
                           origin=str(folder),
                           ident=("path", _path_key(folder)), incomplete=incomplete, video_known=bool(info.get("video") or done.get("video")))


def _path_key(path) -> str:
    return os.path.normcase(os.path.realpath(os.fspath(path)))


def _expand_inputs(results, notes: list[str]) -> list:
    """The inputs, with folders holding results replaced by the result folders they
    contain, and other folders by the videos in them (:func:`mlplc2.batch.expand_inputs`:
    a folder of images stays one input); an item given twice (the same folder, video or
    RunResult) is kept once, with a note in ``notes``."""
    from .runner import RunResult

    if results is None:
        raise InputValueError("no results to evaluate")
    if isinstance(results, (str, Path, RunResult)) or not isinstance(results, Iterable):
        results = [results]
    items = []
    seen: dict[Any, str] = {}  # key -> the input that gave it first
    for r in results:
        if isinstance(r, (str, Path)):
            p = Path(r)
            cands: list = [r]
            if p.is_dir() and not (p / "responses.csv").is_file():
                found = sorted(q.parent for q in p.rglob("responses.csv"))
                if found:
                    cands = found
                else:  # no results: its videos (or the folder, of images), as mlplc2 batch reads it
                    from .batch import expand_inputs

                    try:
                        cands = expand_inputs([r])
                    except InputValueError:
                        pass  # neither videos nor images: reported by evaluate()
            keys = [("path", _path_key(c)) for c in cands]
        else:
            cands, keys = [r], [("object", id(r))]
        name = str(r if isinstance(r, (str, Path)) else getattr(r, "source", type(r).__name__))
        dup, earlier = 0, []
        for c, k in zip(cands, keys):
            if k in seen:
                dup += 1
                if seen[k] not in earlier:
                    earlier.append(seen[k])
                continue
            seen[k] = name
            items.append(c)
        if dup == len(cands):
            notes.append(f"{name}: given more than once; scored once" if earlier == [name] else
                         f"{name}: its results are already given by {', '.join(earlier)}; scored once")
        elif dup:
            notes.append(f"{name}: {dup} of its {len(cands)} result folders are also given by "
                         f"{', '.join(earlier)}; each is scored once")
    return items


# ---------------------------------------------------------------------------
# scoring
# ---------------------------------------------------------------------------
def _mean(values) -> float | None:
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


def _score_run(run: _Run, truth: VideoTruth, *, radius: float, tail: int) -> tuple[dict, list[dict]]:
    first, last = run.start, run.start + run.n_frames  # processed frames [first, last)
    sx = sy = 1.0
    if truth.size and run.size and tuple(run.size) != tuple(truth.size):
        sx, sy = truth.size[0] / run.size[0], truth.size[1] / run.size[1]
    localises = _localises(run.model)

    def fields_at(f):
        return [(fid, x * sx, y * sy, c) for fid, x, y, c in run.frame_fields.get(f, ())]

    births: dict[int, tuple[int, float, float]] = {}
    for f in sorted(run.frame_fields):
        for fid, x, y, _ in fields_at(f):
            births.setdefault(fid, (f, x, y))

    approaching = [o for o in truth.objects if o.approaching]

    def window(o):
        return max(o.approach[0], first), min(o.approach[1] + tail, last)

    objects = []
    outside = 0
    for o in approaching:
        w0, w1 = window(o)
        if w0 >= w1:
            outside += 1  # outside the processed frames: not scored, counted
            continue
        a0 = o.approach[0]
        rec = {"model": run.label, "video": truth.key, "object": o.id, "onset": a0,
               "approach": list(o.approach), "detected": None, "detect_frame": None, "latency_field": None,
               "field": None, "error_detect": None, "error_life": None, "fields": None,
               "alarmed": False, "alarm_frame": None, "latency_alarm": None}
        if localises:
            rec["detected"] = False
            for f in range(w0, w1):
                c = o.center_at(f)
                near = [(math.hypot(x - c[0], y - c[1]), fid) for fid, x, y, _ in fields_at(f)]
                near = [n for n in near if n[0] <= radius]
                if near:
                    d, fid = min(near)
                    rec.update(detected=True, detect_frame=f, latency_field=f - a0, field=fid,
                               error_detect=round(d, 2))
                    break
            if rec["detected"]:
                errs = []
                for f in range(rec["detect_frame"], min(o.life_end(), last)):
                    c = o.center_at(f)
                    for fid, x, y, _ in fields_at(f):
                        if fid == rec["field"]:
                            errs.append(math.hypot(x - c[0], y - c[1]))
                rec["error_life"] = round(sum(errs) / len(errs), 2) if errs else None
            n = 0
            for fid, (b, x, y) in births.items():
                if w0 <= b < w1:
                    c = o.center_at(b)
                    if math.hypot(x - c[0], y - c[1]) <= radius:
                        n += 1
            rec["fields"] = n
            for f in range(w0, w1):
                c = o.center_at(f)
                if any(cl and math.hypot(x - c[0], y - c[1]) <= radius for _, x, y, cl in fields_at(f)):
                    rec.update(alarmed=True, alarm_frame=f, latency_alarm=f - a0)
                    break
        else:
            for f in range(w0, w1):
                if run.frame_alarm.get(f):
                    rec.update(alarmed=True, alarm_frame=f, latency_alarm=f - a0)
                    break
        objects.append(rec)

    # false alarms: alarm onsets (per field for localising models, per frame signal otherwise)
    def explained(f, xy=None):
        for o in approaching:
            w0, w1 = window(o)
            if w0 <= f < w1:
                if xy is None:
                    return True
                c = o.center_at(f)
                if math.hypot(xy[0] - c[0], xy[1] - c[1]) <= radius:
                    return True
        return False

    fa_events = fa_frames = 0
    alarm_frames = sorted(f for f, a in run.frame_alarm.items() if a)
    if localises:
        prev: set[int] = set()
        for f in range(first, last):
            now = set()
            bad_frame = False
            for fid, x, y, c in fields_at(f):
                if not c:
                    continue
                now.add(fid)
                if not explained(f, (x, y)):
                    bad_frame = True
                    if fid not in prev:
                        fa_events += 1
            fa_frames += bad_frame
            prev = now
    else:
        prev_alarm = False
        for f in range(first, last):
            a = bool(run.frame_alarm.get(f))
            if a and not explained(f):
                fa_frames += 1
                if not prev_alarm:
                    fa_events += 1
            prev_alarm = a
    if not truth.object_level:  # a clip-level label only: no object-level false alarms
        fa_events = fa_frames = None
    video = {"model": run.label, "video": truth.key, "source": run.source, "frames": run.n_frames,
             "seconds": round(run.n_frames / run.fps, 6), "localises": localises,
             "complete": run.incomplete is None, "object_level": truth.object_level,
             "fields": len(run.fields) if localises or run.fields else None,
             "objects": len(objects), "objects_outside": outside,
             "detected": sum(1 for r in objects if r["detected"]),
             "alarmed": sum(1 for r in objects if r["alarmed"]),
             "false_alarms": fa_events, "false_alarm_frames": fa_frames,
             "first_alarm_frame": alarm_frames[0] if alarm_frames else None,
             "label": truth.label, "collision_frame": truth.collision_frame, "outcome": None,
             "warning_s": None}
    if truth.label is not None:
        if truth.label == "collision":
            cf = truth.collision_frame
            before = [f for f in alarm_frames if cf is None or f < cf]
            if before:
                video["outcome"] = "TP"
                if cf is not None:
                    video["warning_s"] = round((cf - before[0]) / run.fps, 4)
            else:
                video["outcome"] = "FN"
        else:
            video["outcome"] = "FP" if alarm_frames else "TN"
    return video, objects


def _summarise(label: str, videos: list[dict], objects: list[dict]) -> dict:
    vids = [v for v in videos if v["model"] == label]
    objs = [o for o in objects if o["model"] == label]
    localises = any(v["localises"] for v in vids)
    minutes = sum(v["seconds"] for v in vids) / 60.0
    obj_vids = [v for v in vids if v["object_level"]]  # false alarms: object-level truth only
    obj_minutes = sum(v["seconds"] for v in obj_vids) / 60.0
    s: dict[str, Any] = {"model": label, "videos": len(vids), "minutes": round(minutes, 4),
                         "localises": localises, "objects": len(objs),
                         "objects_outside": sum(v["objects_outside"] for v in vids),
                         "incomplete_videos": sum(1 for v in vids if not v["complete"])}
    if localises:
        det = [o for o in objs if o["detected"]]
        s.update(detected=len(det), detection_rate=len(det) / len(objs) if objs else None,
                 latency_field=_mean(o["latency_field"] for o in det),
                 error_detect=_mean(o["error_detect"] for o in det),
                 error_life=_mean(o["error_life"] for o in det),
                 fields_per_object=_mean(o["fields"] for o in objs))
    else:
        s.update(detected=None, detection_rate=None, latency_field=None, error_detect=None, error_life=None,
                 fields_per_object=None)
    al = [o for o in objs if o["alarmed"]]
    fa = sum(v["false_alarms"] for v in obj_vids) if obj_vids else None
    fields = [v["fields"] for v in vids if v["fields"] is not None]
    s.update(alarmed=len(al), alarm_rate=len(al) / len(objs) if objs else None,
             latency_alarm=_mean(o["latency_alarm"] for o in al),
             fields_total=sum(fields) if fields else None,
             false_alarms=fa,
             false_alarm_frames=sum(v["false_alarm_frames"] for v in obj_vids) if obj_vids else None,
             false_alarms_per_min=fa / obj_minutes if obj_vids and obj_minutes > 0 else None)
    clips = [v for v in vids if v["outcome"] is not None]
    tp = sum(v["outcome"] == "TP" for v in clips)
    fp = sum(v["outcome"] == "FP" for v in clips)
    tn = sum(v["outcome"] == "TN" for v in clips)
    fn = sum(v["outcome"] == "FN" for v in clips)
    s.update(clips=len(clips), tp=tp, fp=fp, tn=tn, fn=fn,
             accuracy=(tp + tn) / len(clips) if clips else None,
             precision=tp / (tp + fp) if tp + fp else None,
             recall=tp / (tp + fn) if tp + fn else None,
             warning_s=_mean(v["warning_s"] for v in clips if v["outcome"] == "TP"))
    for k, v in s.items():
        if isinstance(v, float):
            s[k] = round(v, 4)
    return s


# ---------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------
def _fmt(v, digits=1, pct=False) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if pct:
        return f"{100 * v:.0f}%"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


#: Model labels longer than this are shortened in the Markdown tables (the JSON keeps them whole).
LABEL_WIDTH = 40


@dataclass
class Evaluation:
    """What :func:`evaluate` computed.

    Attributes
    ----------
    models : dict
        Per model label, the summary over all videos: ``mlplc2``, or for batch
        results with non-default parameters the model and its overrides,
        ``mlplc2[r_af=30,t_a=8]`` (:func:`mlplc2.batch.param_label`); each
        summary also gives ``model_name``, ``param_set`` (the batch id) and
        ``params`` (the overrides, a dict).
    videos : list of dict
        One row per (model, video).
    objects : list of dict
        One row per (model, video, approaching object).
    settings : dict
        ``match_radius``, ``tail``, ground-truth source.
    skipped : list of str
        Inputs without ground truth (not scored).
    warnings : list of str
        One line per caveat, also issued as :class:`EvaluationWarning`: inputs
        given more than once (scored once), incomplete results (interrupted or
        truncated runs: approaching objects after the processed frames are not
        scored), inputs that are neither results nor videos (not scored).
    """

    models: dict[str, dict]
    videos: list[dict]
    objects: list[dict]
    settings: dict
    skipped: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"settings": self.settings, "models": self.models, "videos": self.videos,
                "objects": self.objects, "skipped": self.skipped, "warnings": self.warnings}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), indent=kw.pop("indent", 1), **kw)

    def to_dataframe(self, kind: str = "objects"):
        """One of the tables as a pandas DataFrame (needs pandas: ``pip install 'mlplc2[pandas]'``),
        one row per dict, its keys the columns (as in ``evaluation.json``; docs/evaluation.md):

        ``"objects"`` (default)
            :attr:`objects`: one row per (model label, video, approaching object).
        ``"videos"``
            :attr:`videos`: one row per (model label, video).
        ``"models"``
            :attr:`models`: one row per model label (column ``model``), the summary.

        The ``model`` column holds the label (``mlplc2[t_a=8]`` for a batch parameter set);
        ``model_name`` and ``params`` of the ``"models"`` table give the model and its overrides.
        """
        tables = {"objects": self.objects, "videos": self.videos, "models": list(self.models.values())}
        if kind not in tables:
            raise InputValueError(f"kind must be one of {', '.join(tables)}, got {kind!r}")
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Evaluation.to_dataframe needs pandas: pip install 'mlplc2[pandas]'") from None
        return pd.DataFrame(tables[kind])

    def _shown(self) -> tuple[dict[str, str], list[str]]:
        """Label -> what the Markdown tables show, and one note per model whose labels are
        shortened: a model with a label longer than :data:`LABEL_WIDTH` shows its labels
        without the overrides common to all of them (a leading ``…``, named in the note)
        and cut to that width."""
        from .batch import param_label

        shown = {lb: lb for lb in self.models}
        notes = []
        by_model: dict[str, list[str]] = {}
        for lb, s in self.models.items():
            if s.get("params"):
                by_model.setdefault(s["model_name"], []).append(lb)
        for m, labels in by_model.items():
            if all(len(lb) <= LABEL_WIDTH for lb in labels):
                continue
            sets = [self.models[lb]["params"] for lb in labels]
            shared = {k: v for k, v in sets[0].items() if all(k in p and p[k] == v for p in sets[1:])} \
                if len(sets) > 1 else {}
            for lb in labels:
                s = self.models[lb]
                shown[lb] = param_label(m, s["params"], shared=shared, width=LABEL_WIDTH, tag=s["param_set"])
            if shared:
                notes.append(f"- {m}: `…` stands for {param_label(m, shared)[len(m) + 1:-1]}, common to its "
                             f"{len(labels)} parameter sets (each in full in evaluation.json)")
        return shown, notes

    def object_table(self) -> str:
        """Markdown: object-level metrics per model."""
        shown = self._shown()[0]
        head = ("| model | videos | objects | detected | field latency (fr) | loc. err. at det. (px) "
                "| loc. err. life (px) | fields/object | fields | alarmed | alarm latency (fr) "
                "| false alarms | FA/min |")
        lines = [head, "|" + "|".join(["---"] * 13) + "|"]
        for s in self.models.values():
            det = "-" if s["detected"] is None else f"{s['detected']}/{s['objects']}"
            lines.append(
                f"| {shown[s['model']]} | {s['videos']} | {s['objects']} | {det} | {_fmt(s['latency_field'])} "
                f"| {_fmt(s['error_detect'])} | {_fmt(s['error_life'])} | {_fmt(s['fields_per_object'], 2)} "
                f"| {_fmt(s['fields_total'])} | {s['alarmed']}/{s['objects']} | {_fmt(s['latency_alarm'])} "
                f"| {_fmt(s['false_alarms'])} | {_fmt(s['false_alarms_per_min'], 2)} |")
        return "\n".join(lines)

    def clip_table(self) -> str:
        """Markdown: clip-level metrics per model (empty string without clip-level truth)."""
        if not any(s["clips"] for s in self.models.values()):
            return ""
        shown = self._shown()[0]
        lines = ["| model | clips | TP | FP | TN | FN | accuracy | precision | recall | warning (s) |",
                 "|" + "|".join(["---"] * 10) + "|"]
        for s in self.models.values():
            lines.append(f"| {shown[s['model']]} | {s['clips']} | {s['tp']} | {s['fp']} | {s['tn']} | {s['fn']} "
                         f"| {_fmt(s['accuracy'], 2)} | {_fmt(s['precision'], 2)} | {_fmt(s['recall'], 2)} "
                         f"| {_fmt(s['warning_s'], 2)} |")
        return "\n".join(lines)

    def video_table(self) -> str:
        """Markdown: one row per (model, video)."""
        shown = self._shown()[0]
        lines = ["| model | video | frames | objects | detected | alarmed | fields | false alarms | first alarm "
                 "| clip |", "|" + "|".join(["---"] * 10) + "|"]
        for v in self.videos:
            det = "-" if not v["localises"] else f"{v['detected']}/{v['objects']}"
            lines.append(f"| {shown[v['model']]} | {v['video']} | {v['frames']} | {v['objects']} | {det} "
                         f"| {v['alarmed']}/{v['objects']} | {_fmt(v['fields'])} | {_fmt(v['false_alarms'])} "
                         f"| {_fmt(v['first_alarm_frame'])} | {v['outcome'] or '-'} |")
        return "\n".join(lines)

    def notes(self) -> str:
        """Markdown: approaching objects not scored because they lie outside the
        processed frames (incomplete or partial runs), per model, and what shortened
        labels leave out; empty if none."""
        shown, lines = self._shown()
        for s in self.models.values():
            if s["objects_outside"]:
                inc = s["incomplete_videos"]
                lines.append(f"- {shown[s['model']]}: {s['objects_outside']} approaching object(s) outside the "
                             f"processed frames, not scored" + (f" ({inc} incomplete result(s))" if inc else ""))
        return "\n".join(lines)

    def to_markdown(self, details: bool = False) -> str:
        """The per-model comparison table(s); ``details`` adds the per-video table."""
        parts = []
        if any(s["objects"] or not s["clips"] for s in self.models.values()):
            parts.append(self.object_table())
        notes = self.notes()
        if notes:
            parts.append(notes)
        clip = self.clip_table()
        if clip:
            parts.append(clip)
        if details:
            parts.append(self.video_table())
        return "\n\n".join(parts)

    def write(self, out) -> dict[str, Path]:
        """Write ``evaluation.md`` and ``evaluation.json`` into folder ``out``."""
        from .io import atomic_path

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        st = self.settings
        md = (f"# Evaluation\n\nGround truth: `{st['ground_truth']}`; match radius {st['match_radius']:g} px, "
              f"tail {st['tail']} frames.\n\n{self.to_markdown(details=True)}\n")
        if self.warnings:
            md += "\nWarnings:\n\n" + "".join(f"- {w}\n" for w in self.warnings)
        files = {}
        for name, text in (("evaluation.md", md), ("evaluation.json", self.to_json() + "\n")):
            path = out / name
            with atomic_path(path) as tmp:
                Path(tmp).write_text(text, encoding="utf-8")
            files[name] = path
        return files


def evaluate(results, gt, *, models: Sequence[str] | str | None = None, match_radius: float = DEFAULT_MATCH_RADIUS,
             tail: int = DEFAULT_TAIL, run_options: Mapping[str, Any] | None = None,
             progress: bool = False) -> Evaluation:
    """Score run results against ground truth.

    Parameters
    ----------
    results : RunResult, path, or a list of them
        Each item is a :class:`~mlplc2.runner.RunResult`, an output folder of
        ``mlplc2 run`` / ``mlplc2 batch`` (``responses.csv`` + ``fields.json``;
        a folder without ``responses.csv`` is searched recursively for them),
        or a video, a folder of videos (each of them) or an image folder (the
        models are then run first, nothing is written).
    gt : path, dict or GroundTruth
        Ground truth (see :func:`load_ground_truth`). A result's video is
        matched to a key by relative-path suffix, else by basename.
    models : list of str, optional
        Models to score (default: all in the results; for videos: all registered).
    match_radius : float
        A field within this distance (ground-truth pixels) of an object's centre
        stands for it.
    tail : int
        Frames after the end of an approach during which a field or alarm
        still counts for that object (not as a false alarm).
    run_options : dict, optional
        Extra keyword arguments of :func:`mlplc2.run` for video inputs (``resize``, ...).
    progress : bool
        Show the progress bar when running models on videos.

    Returns
    -------
    Evaluation
    """
    from .io import IMAGE_EXTENSIONS, VIDEO_EXTENSIONS
    from .models.base import available_models
    from .runner import RunResult, run

    if isinstance(models, str):
        models = [m.strip().lower() for m in models.split(",") if m.strip()]
    elif models is not None:
        if not isinstance(models, Iterable):
            raise InputTypeError(f"models must be a model name or a list of names, got {type(models).__name__}")
        models = list(models)
        for m in models:
            if not isinstance(m, str):
                raise InputTypeError(f"models must be model names (str), got {m!r}")
        models = [m.strip().lower() for m in models]
    if models is not None:
        if not models:
            raise InputValueError("models is empty: give at least one model name (or None for all)")
        known = available_models()
        for m in models:
            if m not in known:
                raise InputValueError(f"unknown model {m!r}; choose from {', '.join(known)}")
    match_radius = check_real(match_radius, "match_radius", positive=True)
    tail = check_int(tail, "tail", minimum=0)
    if run_options is not None and not isinstance(run_options, Mapping):
        raise InputTypeError(f"run_options must be a dict of mlplc2.run options, got {type(run_options).__name__}")
    truth = load_ground_truth(gt)

    notes: list[str] = []     # warnings, in order
    problems: list[str] = []  # inputs not scored for another reason than missing ground truth
    runs: list[_Run] = []
    for item in _expand_inputs(results, notes):
        if isinstance(item, RunResult):
            runs.extend(_runs_from_result(item, models))
        elif isinstance(item, (str, Path)) and Path(item).is_dir() and (Path(item) / "responses.csv").is_file():
            runs.extend(_read_folder(Path(item), models))
        elif isinstance(item, (str, Path)):
            p = Path(item)
            if not p.exists() and not any(ch in str(item) for ch in "*?["):
                raise InputValueError(f"{item}: no such file or folder")
            if truth.match(item) is None:  # do not run models on a video that cannot be scored
                if p.is_dir() and not any(f.is_file() and f.suffix.lower() in IMAGE_EXTENSIONS for f in p.iterdir()):
                    problems.append(f"{item}: no results in this folder (no responses.csv in it or below), "
                                    f"no videos and no images")
                elif p.is_file() and p.suffix.lower() not in VIDEO_EXTENSIONS + IMAGE_EXTENSIONS:
                    problems.append(f"{item}: not a results folder (responses.csv + fields.json) nor a video "
                                    f"({', '.join(VIDEO_EXTENSIONS)}) or image")
                else:
                    runs.append(_Run(str(item), "", "", 30.0, None, 0, 0, [], {}, {}))
                continue
            names = models or available_models()
            res = run(item, names, out=False, quiet=not progress, **dict(run_options or {}))
            runs.extend(_runs_from_result(res, models, origin=f"{item} (run now)"))
        else:
            raise InputValueError(f"cannot evaluate {type(item).__name__}: give a RunResult, a results folder "
                                  f"or a video path")
    videos: list[dict] = []
    objects: list[dict] = []
    skipped: list[str] = []
    claimed: dict[tuple[str, str], _Run] = {}  # (model label, video) -> the run scored for it
    by_label: dict[str, _Run] = {}  # model label -> a run scored under it (its model and parameters)
    incomplete: dict[str, tuple[str, int]] = {}  # origin -> (reason, approaching objects outside)
    for r in runs:
        t = truth.match(r.source) if r.model else None
        if t is None and r.model and not r.video_known:
            msg = f"{r.origin}: {r.incomplete}, so its video is unknown"
            if msg not in problems:
                problems.append(msg)
            continue
        if t is None:
            if r.source not in skipped:
                skipped.append(r.source)
            continue
        key = (r.label, _video_key(r.source))
        prev = claimed.setdefault(key, r)
        if prev is not r and prev.ident != r.ident:
            other = r.origin if r.origin != prev.origin else f"another {r.origin.removeprefix('a ')}"
            raise InputValueError(f"{prev.origin} and {other} both hold {r.label} results for {r.source}; "
                                  f"evaluate one of them (or each separately)")
        v, o = _score_run(r, t, radius=match_radius, tail=tail)
        by_label.setdefault(r.label, r)
        videos.append(v)
        objects.extend(o)
        if r.incomplete is not None:
            reason, n = incomplete.get(r.origin, (r.incomplete, 0))
            incomplete[r.origin] = (reason, max(n, v["objects_outside"]))
    for origin, (reason, n) in incomplete.items():
        notes.append(f"{origin}: incomplete results ({reason}); scored as they are, "
                     f"{n} approaching object(s) outside the processed frames not scored")
    if not videos:
        _issue(notes)
        if problems:
            raise InputValueError(f"nothing to evaluate: {'; '.join(problems[:3])}"
                                  f"{' ...' if len(problems) > 3 else ''}")
        if skipped:
            raise InputValueError(f"no ground truth in {truth.source} for {', '.join(skipped[:3])}"
                                  f"{' ...' if len(skipped) > 3 else ''}")
        raise InputValueError("nothing to evaluate (no model output in the results)")
    notes.extend(f"{p}; not scored" for p in problems)
    _issue(notes)
    order = list(MODEL_ORDER) + [m for m in available_models() if m not in MODEL_ORDER]

    def rank(lb):  # model order, then parameter values (numbers as numbers: t_a=8 before t_a=12)
        r = by_label[lb]
        values = [(k, (0, v, "") if isinstance(v, (int, float)) and not isinstance(v, bool)
                   else (1, 0, json.dumps(v, sort_keys=True))) for k, v in sorted(r.params.items())]
        return order.index(r.model) if r.model in order else 99, r.model, values, lb

    labels = sorted(by_label, key=rank)
    summary = {lb: {"model": lb, "model_name": by_label[lb].model, "param_set": by_label[lb].param_set or "default",
                    "params": by_label[lb].params, **_summarise(lb, videos, objects)} for lb in labels}
    videos.sort(key=lambda v: (labels.index(v["model"]), v["video"]))
    objects.sort(key=lambda o: (labels.index(o["model"]), o["video"], o["onset"], str(o["object"])))
    settings = {"ground_truth": truth.source, "match_radius": match_radius, "tail": tail}
    return Evaluation(summary, videos, objects, settings, skipped, notes)


def _video_key(source: str) -> str:
    """A result's video, comparable across result folders (the path as recorded, resolved if it exists)."""
    source = str(source)
    return _path_key(source) if os.path.exists(source) else os.path.normcase(os.path.normpath(source))


def _issue(notes: list[str]) -> None:
    for note in notes:
        warnings.warn(note, EvaluationWarning, stacklevel=3)
