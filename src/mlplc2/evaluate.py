"""Score model outputs against ground truth (the ``mlplc2 evaluate`` command).

Two kinds of truth (:mod:`mlplc2.evaluation.truth`; schema in ``docs/evaluation.md``):

object level
    the objects and their phases (the paper's ``ground_truth.json``), scored per approaching
    object: detected or not, latency to the first field within the match radius and to the
    first alarm, localisation error, fields created; and false alarms per minute of video.
clip level
    ``"label": "collision" | "no_collision"`` with an optional ``collision_frame``, scored as a
    binary classification (alarm before the collision frame = true positive, alarm in a
    no-collision clip = false positive): accuracy, precision, recall and warning time.

Truth that says which objects will hit (3-D objects with a ``kind``, labelled clips with the
collider's track) also gets the **warning metrics** (``docs/evaluation.md``, "Warning metrics";
:func:`_score_warnings`): collision objects warned before contact, lead time, false warnings
per 1000 frames by cause, time-to-contact errors (RTE, MiD) and coverage, fragmentation, and
per clip warned / missed / false.

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
import statistics
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable

from ._validation import InputTypeError, InputValueError, check_int, check_real

__all__ = ["evaluate", "Evaluation", "EvaluationWarning", "load_ground_truth", "GroundTruth", "VideoTruth",
           "ObjectTruth", "PHASES", "KINDS", "DEFAULT_TAIL", "DEFAULT_MATCH_RADIUS", "TTC_BINS", "MIN_TTC_WIDTH",
           "EARLY_S", "LATE_S", "MID_INTERVAL_S", "mid_error"]

#: Bins of the true time to contact (s) for the TTC errors (lower bound inclusive).
TTC_BINS = ((0.0, 1.0), (1.0, 3.0), (3.0, 6.0))
#: TTC coverage counts the frames in which a collision object is at least this wide (px).
MIN_TTC_WIDTH = 16.0
#: Real clips: a warning earlier than the danger onset minus this (s) is false.
EARLY_S = 0.5
#: A warning on a collision object up to this long (s) after its contact is neither true nor false.
LATE_S = 0.5
#: MiD (the TSTTC benchmark's motion-in-depth error) compares the depth ratio over this interval (s):
#: TSTTC's frame interval (10 fps).
MID_INTERVAL_S = 0.1


def mid_error(true_ttc: float, est_ttc: float, interval: float = MID_INTERVAL_S) -> float:
    """MiD of one time-to-contact estimate, as the TSTTC benchmark computes it: the depth ratio
    over ``interval`` implied by a TTC, ``s = ttc / (ttc + interval)``, compared in log space,
    ``|ln s(est) - ln s(true)| x 10^4`` (positive TTCs)."""
    return abs(math.log(est_ttc / (est_ttc + interval)) - math.log(true_ttc / (true_ttc + interval))) * 1e4

from .evaluation.tracks import (CAUSES, DEFAULT_MATCH_RADIUS, DEFAULT_TAIL, TargetRow, alarm_explained, centre_distance,
                     episodes, on_object, warning_cause)
from .evaluation.truth import KINDS, PHASES, GroundTruth, ObjectTruth, VideoTruth, read_json
from .evaluation.truth import load as load_ground_truth

#: Row order of the comparison table (other registered models follow, alphabetically).
MODEL_ORDER = ("mlplc2", "slplc2", "lplc2", "lgmd2", "lgmd1", "flow")


class EvaluationWarning(UserWarning):
    """Something :func:`evaluate` scored with a caveat or did not score (one line;
    also in :attr:`Evaluation.warnings`): an input given twice, incomplete results,
    an input that is neither results nor a video."""


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
    # frame -> the targets of that frame (models with targets: their warning is the targets' warning)
    frame_targets: dict[int, list[TargetRow]] = field(default_factory=dict)
    has_targets: bool = False
    localises: bool = False  # its fields have meaningful positions (Model.localises)

    def alarms_at(self, f: int) -> list[tuple]:
        """``(field id, x, y)`` of every field in alarm in frame ``f``; for a model that does not localise,
        ``(None, None, None)`` for the frame's alarm."""
        if self.localises:
            return [(fid, x, y) for fid, x, y, c in self.frame_fields.get(f, ()) if c]
        return [(None, None, None)] if self.frame_alarm.get(f) else []

    def in_pixels_of(self, truth: VideoTruth) -> "_Run":
        """The run with its field and target positions in ``truth``'s pixels (when its size differs)."""
        if not (truth.size and self.size and tuple(self.size) != tuple(truth.size)):
            return self
        sx, sy = truth.size[0] / self.size[0], truth.size[1] / self.size[1]
        return replace(self, frame_fields={f: [(fid, x * sx, y * sy, c) for fid, x, y, c in rows]
                                           for f, rows in self.frame_fields.items()},
                       frame_targets={f: [replace(t, x=t.x * sx, y=t.y * sy,
                                                  width=None if t.width is None else t.width * sx,
                                                  height=None if t.height is None else t.height * sy) for t in rows]
                                      for f, rows in self.frame_targets.items()})


def _model_says(model: str, flag: str) -> bool:
    """The registered model's class attribute ``flag`` (``Model.localises``, ``Model.has_targets``);
    False for a model not registered. evaluate keeps no rule of its own."""
    from .models.base import REGISTRY

    return bool(getattr(REGISTRY.get(model), flag, False))


def _target_row(r) -> TargetRow:
    """A ``targets.csv`` row (dict of strings or numbers) as a :class:`TargetRow`."""
    def num(v):
        return None if v in (None, "") else float(v)

    fields = r.get("fields") or ""
    return TargetRow(int(r["target_id"]), float(r["x"]), float(r["y"]), num(r.get("width")), num(r.get("height")),
                     num(r.get("ttc_s")), num(r.get("miss")), bool(int(float(r.get("warning") or 0))),
                     tuple(int(v) for v in str(fields).split()))


def _runs_from_rows(source, rows, fields_by_model, *, fps, size, start, n_frames, models, param_set=None,
                    params=None, origin="", ident=None, incomplete=None, video_known=True, target_rows=(),
                    targets_known=True):
    from .batch import param_label

    per: dict[str, _Run] = {}

    def new(m, fields):
        if params or param_set in (None, "", "default"):
            label = param_label(m, params)
        else:  # a parameter set whose overrides are not recorded
            label = f"{m}@{param_set}"
        return _Run(str(source), m, label, fps, size, start, n_frames, list(fields), {}, {}, param_set,
                    dict(params or {}), origin or str(source), ident, incomplete, video_known,
                    has_targets=_model_says(m, "has_targets") and targets_known, localises=_model_says(m, "localises"))

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
    for r in target_rows:
        run = per.get(r["model"])
        if run is not None:
            run.frame_targets.setdefault(int(r["frame"]), []).append(_target_row(r))
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
                           ident=("object", id(res)), incomplete=reason, target_rows=res.targets)


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
    fj = folder / "fields.json"
    info = read_json(fj) if fj.is_file() else {}
    if not isinstance(info, Mapping):
        raise InputValueError(f"{fj}: not a fields.json of mlplc2 run (expected a JSON object)")
    dj = folder / "done.json"
    try:  # the batch's record of the task, if any (unreadable: none)
        done = json.loads(dj.read_text(encoding="utf-8")) if dj.is_file() else {}
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
    target_rows = []
    targets_known = False  # without the target layer's targets.csv (older results) the alarm is the warning
    tp = folder / "targets.csv"
    if tp.is_file():
        with open(tp, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            if "target_id" in (reader.fieldnames or ()):   # targets.csv of the target layer
                targets_known = True
                try:
                    target_rows = [r for r in reader if r.get("frame") not in (None, "")]
                    for r in target_rows:
                        int(r["frame"]), _target_row(r)
                except (TypeError, ValueError, KeyError):
                    raise InputValueError(f"{tp}: malformed row") from None
    return _runs_from_rows(source, rows, info.get("models", {}), fps=fps, size=size, start=start,
                           n_frames=n_frames, models=models, param_set=done.get("param_set"), params=params,
                           origin=str(folder), ident=("path", _path_key(folder)), incomplete=incomplete,
                           video_known=bool(info.get("video") or done.get("video")), target_rows=target_rows,
                           targets_known=targets_known)


def _path_key(path) -> str:
    return os.path.normcase(os.path.realpath(os.fspath(path)))


def _expand_inputs(results, notes: list[str]) -> list:
    """The inputs, with folders holding results replaced by the result folders they
    contain, and other folders by the videos in them (:func:`mlplc2.io.expand_inputs`:
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
                    from .io import expand_inputs

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


def _with_approach(o: ObjectTruth) -> ObjectTruth | None:
    """``o`` with an ``approach`` interval for the paper's object metrics: its own, else (a 3-D
    collision or pass-by given with a track but no ``approach``) its tracked frames; None
    without either (nothing to score it on)."""
    if o.approach is not None:
        return o
    if not o.track:
        return None
    return replace(o, approach=(o.track[0].frame, o.track[-1].frame + 1))


def _score_run(run: _Run, truth: VideoTruth, *, radius: float, tail: int) -> tuple[dict, list[dict]]:
    run = run.in_pixels_of(truth)
    first, last = run.start, run.start + run.n_frames  # processed frames [first, last)
    localises = run.localises

    def fields_at(f):
        return run.frame_fields.get(f, ())

    births: dict[int, tuple[int, float, float]] = {}
    for f in sorted(run.frame_fields):
        for fid, x, y, _ in fields_at(f):
            births.setdefault(fid, (f, x, y))

    approaching = [a for a in (_with_approach(o) for o in truth.objects if o.approaching) if a is not None]

    objects = []
    outside = 0
    for o in approaching:
        w0, w1 = max(o.approach[0], first), min(o.approach[1] + tail, last)
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
                near = [(centre_distance(x, y, o, f), fid) for fid, x, y, _ in fields_at(f)]
                near = [n for n in near if n[0] <= radius]
                if near:
                    d, fid = min(near)
                    rec.update(detected=True, detect_frame=f, latency_field=f - a0, field=fid,
                               error_detect=round(d, 2))
                    break
            if rec["detected"]:
                errs = [centre_distance(x, y, o, f) for f in range(rec["detect_frame"], min(o.life_end(), last))
                        for fid, x, y, _ in fields_at(f) if fid == rec["field"]]
                rec["error_life"] = round(sum(errs) / len(errs), 2) if errs else None
            rec["fields"] = sum(1 for b, x, y in births.values()
                                if w0 <= b < w1 and centre_distance(x, y, o, b) <= radius)
        for f in range(w0, w1):
            if any(x is None or centre_distance(x, y, o, f) <= radius for _, x, y in run.alarms_at(f)):
                rec.update(alarmed=True, alarm_frame=f, latency_alarm=f - a0)
                break
        objects.append(rec)

    # false alarms: alarm onsets (per field for localising models, per frame signal otherwise) that
    # no approaching object explains (mlplc2.evaluation.tracks.alarm_explained)
    def explained(f, x=None, y=None):
        return alarm_explained(f, approaching, x, y, radius=radius, tail=tail)

    fa_events = fa_frames = 0
    alarm_frames = sorted(f for f, a in run.frame_alarm.items() if a)
    prev: set = set()   # the alarms of the frame before
    for f in range(first, last):
        now = run.alarms_at(f)
        bad = [fid for fid, x, y in now if not explained(f, x, y)]
        fa_frames += bool(bad)
        fa_events += sum(fid not in prev for fid in bad)
        prev = {fid for fid, _, _ in now}
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


# ---------------------------------------------------------------------------
# warning metrics (3-D truth with kinds, and labelled clips)
# ---------------------------------------------------------------------------
def _warning_truth(truth: VideoTruth) -> bool:
    """Whether the truth says which objects will hit (3-D kinds, or a clip label)."""
    return truth.label is not None or any(o.kind is not None for o in truth.objects)


def _median(values) -> float | None:
    v = [x for x in values if x is not None]
    return float(statistics.median(v)) if v else None


def _quantile(values, q: float) -> float | None:
    """The ``q`` quantile (linear interpolation, as ``numpy.quantile``)."""
    v = sorted(x for x in values if x is not None)
    if not v:
        return None
    pos = q * (len(v) - 1)
    lo = int(math.floor(pos))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def _score_warnings(run: _Run, truth: VideoTruth, *, radius: float) -> tuple[dict, list[dict]]:
    """The warning metrics of one run (``docs/evaluation.md``, "Warning metrics").

    A model's warning is its targets' warnings (models with targets), else its alarm: the fields
    in alarm of a model that localises, the frame's alarm of one that does not. Collision objects
    (``kind == "collision"``, a clip's collider) are warned when a warning lies on them
    (:func:`mlplc2.evaluation.tracks.on_object`) before contact; every other warning is false, with its
    cause (:func:`mlplc2.evaluation.tracks.warning_cause`), except within ``LATE_S`` after a contact, on
    the object that hit. On a labelled clip, frames from the contact on are not scored, and a
    warning before the danger onset minus ``EARLY_S`` is false ("early"), as is one off the
    collider ("elsewhere"; a collision clip without the collider's track: every warning is on it). A collision object none of whose frames before contact were
    processed (an interrupted or partial run) is not scored, only counted (``collision_objects_outside``).
    """
    run = run.in_pixels_of(truth)
    first, last = run.start, run.start + run.n_frames
    fps = run.fps
    clip = truth.label is not None
    collider = truth.collider
    if clip and truth.label == "collision" and collider is None:  # no track: any warning may be on it
        collider = ObjectTruth(id="collider", kind="collision", contact_frame=truth.contact_frame)
    blind = collider is not None and not collider.track   # the collider's position is unknown
    colliders = [o for o in truth.objects if o.collides] + ([collider] if collider is not None else [])
    late = int(round(LATE_S * fps))
    end = last
    if clip and truth.label == "collision" and truth.contact_frame is not None:
        end = min(last, int(math.ceil(truth.contact_frame)))
    early_before = None
    if clip and truth.danger_onset_frame is not None:
        early_before = truth.danger_onset_frame - EARLY_S * fps
    localises = run.localises

    def warnings_at(f):
        """(key, x, y) of every warning in frame f (key: target or field id; x None: a global alarm)."""
        if run.has_targets:
            return [(t.id, t.x, t.y) for t in run.frame_targets.get(f, ()) if t.warning]
        return run.alarms_at(f)

    objects = []
    outside = 0
    for o in colliders:
        cf = o.contact_frame if o.contact_frame is not None else (truth.contact_frame if o is collider else None)
        start = max(first, o.track[0].frame) if o.track and o is not collider else first
        stop = min(end, int(math.ceil(cf)) if cf is not None else last)
        if start >= stop:
            outside += 1
            continue
        rec = {"model": run.label, "video": truth.key, "object": o.id, "kind": "collision",
               "contact_frame": cf, "warned": False, "warning_frame": None, "lead_s": None,
               "ttc_at_warning_s": None, "warning_distance_px": None, "targets": None, "ttc_frames": 0,
               "ttc_estimated": 0, "ttc_errors": []}
        ids = set()
        for f in range(start, stop):
            if not rec["warned"] and (early_before is None or f >= early_before):
                for key, x, y in warnings_at(f):
                    if x is None or (blind and o is collider) or on_object(x, y, o, f, radius):
                        c = o.center_at(f)
                        true = o.ttc_at(f, fps)
                        rec.update(warned=True, warning_frame=f,
                                   lead_s=None if cf is None else round((cf - f) / fps, 4),
                                   ttc_at_warning_s=None if true is None else round(true, 4),
                                   warning_distance_px=None if x is None or c is None else round(
                                       math.hypot(x - c[0], y - c[1]), 2))
                        break
            # fragmentation and time to contact: the targets (fields) on the object while in view
            if o.track and not o.in_track(f) and o is not collider:
                continue
            width = o.width_at(f)
            # fragmentation counts while the object fits in the frame: in the last frames before
            # contact it covers the view, and every target anywhere lies on it
            fits = width is None or truth.size is None or width <= max(truth.size)
            if run.has_targets:
                on = [t for t in run.frame_targets.get(f, ()) if on_object(t.x, t.y, o, f, radius)]
                if fits:
                    ids.update(t.id for t in on)
                true = o.ttc_at(f, fps)
                if o is not collider and width is not None and width >= MIN_TTC_WIDTH and true is not None \
                        and true > 0:
                    rec["ttc_frames"] += 1
                    est = [t for t in on if t.ttc_s is not None and t.ttc_s > 0]
                    if est:
                        c = o.center_at(f)
                        t = min(est, key=lambda t: math.hypot(t.x - c[0], t.y - c[1]))
                        rec["ttc_estimated"] += 1
                        rec["ttc_errors"].append((round(true, 4), round(t.ttc_s, 4)))
            elif localises and fits:
                ids.update(fid for fid, x, y, _ in run.frame_fields.get(f, ()) if on_object(x, y, o, f, radius))
        rec["targets"] = len(ids) if (run.has_targets or localises) else None
        objects.append(rec)

    # false warnings: per frame, per cause; episodes per (target, cause)
    false_frames: dict[str, set[int]] = {}
    runs: dict[tuple, list[int]] = {}

    def just_hit(x, y, f):
        """A warning up to LATE_S after a collision object's contact, where it last was."""
        for o in colliders:
            cf = o.contact_frame
            if cf is not None and cf <= f <= cf + late and (x is None or on_object(x, y, o, min(f, cf), radius)):
                return True
        return False

    for f in range(first, end):
        for key, x, y in warnings_at(f):
            if just_hit(x, y, f):
                continue
            if early_before is not None and f < early_before:
                cause = "early"
            elif blind:
                continue                     # a collision clip without a track: on its collider
            else:
                verdict, _ = warning_cause(x, y, f, truth, radius=radius, tail=late)
                if verdict == "true":
                    continue
                cause = verdict if not clip else "elsewhere"
            false_frames.setdefault(cause, set()).add(f)
            runs.setdefault((key, cause), []).append(f)
    episodes_by: dict[str, int] = {}
    for (key, cause), frames in runs.items():
        episodes_by[cause] = episodes_by.get(cause, 0) + episodes(frames)
    all_false = set().union(*false_frames.values()) if false_frames else set()
    outcome = None
    if clip:
        warned = any(r["warned"] for r in objects)
        outcome = {"label": truth.label, "warned": warned if truth.label == "collision" else None,
                   "missed": (not warned) if truth.label == "collision" else None, "false": bool(all_false),
                   "lead_s": next((r["lead_s"] for r in objects if r["warned"]), None)}
    video = {"model": run.label, "video": truth.key, "frames_scored": max(end - first, 0), "clip": clip,
             "collision_objects_outside": outside,
             "false_frames": len(all_false), "false_episodes": sum(episodes_by.values()),
             "false_frames_by_cause": {c: len(v) for c, v in sorted(false_frames.items())},
             "false_episodes_by_cause": dict(sorted(episodes_by.items())), "outcome": outcome}
    return video, objects


def _summarise_warnings(label: str, wvideos: list[dict], wobjects: list[dict]) -> dict:
    """Per model: collision objects warned, lead time, false warnings by cause, TTC errors, fragmentation."""
    vids = [v for v in wvideos if v["model"] == label]
    objs = [o for o in wobjects if o["model"] == label]
    if not vids:
        return {}
    synth = [v for v in vids if not v["clip"]]
    sobjs = [o for o in objs if not any(v["video"] == o["video"] and v["clip"] for v in vids)]
    warned = [o for o in sobjs if o["warned"]]
    frames = sum(v["frames_scored"] for v in synth)
    per_k = (lambda n: round(1000.0 * n / frames, 3)) if frames else (lambda n: None)
    s: dict[str, Any] = {
        "collision_objects": len(sobjs), "warned": len(warned),
        "collision_objects_outside": sum(v["collision_objects_outside"] for v in synth),
        "warned_rate": round(len(warned) / len(sobjs), 4) if sobjs else None,
        "lead_median_s": _median(o["lead_s"] for o in warned),
        "lead_p10_s": _quantile([o["lead_s"] for o in warned], 0.1),
        "ttc_at_warning_median_s": _median(o["ttc_at_warning_s"] for o in warned),
        "warning_distance_median_px": _median(o["warning_distance_px"] for o in warned),
        "frames": frames,
        "false_frames_per_1000": per_k(sum(v["false_frames"] for v in synth)),
        "false_episodes_per_1000": per_k(sum(v["false_episodes"] for v in synth)),
        "false_frames_per_1000_by_cause": {c: per_k(sum(v["false_frames_by_cause"].get(c, 0) for v in synth))
                                           for c in CAUSES},
        "false_episodes_per_1000_by_cause": {c: per_k(sum(v["false_episodes_by_cause"].get(c, 0) for v in synth))
                                             for c in CAUSES},
        "false_frames_pct": round(100.0 * sum(v["false_frames"] for v in synth) / frames, 3) if frames else None,
        "fragmentation": _mean(o["targets"] for o in sobjs if o["targets"] is not None),
    }
    errs = [e for o in sobjs for e in o["ttc_errors"]]
    for lo, hi in TTC_BINS:
        b = [(t, e) for t, e in errs if lo <= t < hi]
        key = f"{lo:g}-{hi:g}s"
        s[f"ttc_rte_pct_{key}"] = None if not b else round(100.0 * _median(abs(e - t) / t for t, e in b), 2)
        s[f"ttc_mid_{key}"] = None if not b else round(_median(mid_error(t, e) for t, e in b), 1)
        s[f"ttc_n_{key}"] = len(b)
    tf = sum(o["ttc_frames"] for o in sobjs)
    s["ttc_coverage"] = round(sum(o["ttc_estimated"] for o in sobjs) / tf, 4) if tf else None
    clips = [v for v in vids if v["clip"]]
    cc = [v for v in clips if v["outcome"]["label"] == "collision"]
    s.update(clips=len(clips), clips_collision=len(cc), clips_warned=sum(bool(v["outcome"]["warned"]) for v in cc),
             clips_missed=sum(bool(v["outcome"]["missed"]) for v in cc),
             clips_false=sum(bool(v["outcome"]["false"]) for v in clips),
             clip_lead_median_s=_median(v["outcome"]["lead_s"] for v in cc if v["outcome"]["warned"]))
    return s


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
    tp, fp, tn, fn = (sum(v["outcome"] == o for v in clips) for o in ("TP", "FP", "TN", "FN"))
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
    warning_videos : list of dict
        Warning metrics per (model, video) with 3-D or clip-level truth: false warnings by cause,
        the clip's outcome (``docs/evaluation.md``, "Warning metrics").
    warning_objects : list of dict
        Per (model, video, collision object): warned, lead time, true TTC at the warning,
        targets on it, and its TTC estimates (true, estimated) per frame.
    """

    models: dict[str, dict]
    videos: list[dict]
    objects: list[dict]
    settings: dict
    skipped: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    warning_videos: list[dict] = field(default_factory=list)
    warning_objects: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"settings": self.settings, "models": self.models, "videos": self.videos,
                "objects": self.objects, "warning_videos": self.warning_videos,
                "warning_objects": self.warning_objects, "skipped": self.skipped, "warnings": self.warnings}

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
        ``"warning_objects"``, ``"warning_videos"``
            :attr:`warning_objects`, :attr:`warning_videos`: the warning metrics.

        The ``model`` column holds the label (``mlplc2[t_a=8]`` for a batch parameter set);
        ``model_name`` and ``params`` of the ``"models"`` table give the model and its overrides.
        """
        tables = {"objects": self.objects, "videos": self.videos, "models": list(self.models.values()),
                  "warning_objects": self.warning_objects, "warning_videos": self.warning_videos}
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

    def warning_table(self) -> str:
        """Markdown: the warning metrics per model (empty without 3-D truth): collision objects
        warned before contact, lead time, true TTC and distance at the first warning, false
        warnings by cause, TTC errors (median RTE / MiD per true-TTC bin), coverage, fragmentation."""
        rows = [(lb, s["warnings"]) for lb, s in self.models.items() if s.get("warnings")
                and s["warnings"]["collision_objects"]]
        if not rows:
            return ""
        shown, _ = self._shown()
        bins = [f"{lo:g}-{hi:g}s" for lo, hi in TTC_BINS]
        lines = ["| model | warned | lead median (s) | lead p10 (s) | TTC at warning (s) | distance (px) "
                 "| false frames /1000 | false episodes /1000 "
                 "| by cause: pass / distractor / background (episodes /1000) "
                 + "".join(f"| TTC error {lo:g}-{hi:g} s (RTE / MiD) " for lo, hi in TTC_BINS)
                 + "| TTC coverage | targets/object |",
                 "|" + "|".join(["---"] * (12 + len(TTC_BINS))) + "|"]

        def ttc_cell(w, b):
            rte, mid = w[f"ttc_rte_pct_{b}"], w[f"ttc_mid_{b}"]
            return "-" if rte is None else f"{rte:.0f} % / {mid:.0f}"

        for lb, w in rows:
            c = w["false_episodes_per_1000_by_cause"]
            lines.append(
                f"| {shown[lb]} | {w['warned']}/{w['collision_objects']} ({_fmt(w['warned_rate'], pct=True)}) "
                f"| {_fmt(w['lead_median_s'], 2)} | {_fmt(w['lead_p10_s'], 2)} "
                f"| {_fmt(w['ttc_at_warning_median_s'], 2)} | {_fmt(w['warning_distance_median_px'], 1)} "
                f"| {_fmt(w['false_frames_per_1000'], 1)} | {_fmt(w['false_episodes_per_1000'], 2)} "
                f"| {_fmt(c['pass'], 2)} / {_fmt(c['distractor'], 2)} / {_fmt(c['background'], 2)} "
                + "".join(f"| {ttc_cell(w, b)} " for b in bins)
                + f"| {_fmt(w['ttc_coverage'], pct=True)} | {_fmt(w['fragmentation'], 2)} |")
        return "\n".join(lines)

    def clip_warning_table(self) -> str:
        """Markdown: per labelled clip and model, warned / missed / false and the lead time."""
        clips = [v for v in self.warning_videos if v["clip"]]
        if not clips:
            return ""
        shown, _ = self._shown()
        lines = ["| model | clip | label | warned | lead (s) | false warnings (frames) |", "|---|---|---|---|---|---|"]
        for v in clips:
            o = v["outcome"]
            lines.append(f"| {shown.get(v['model'], v['model'])} | {v['video']} | {o['label']} "
                         f"| {_fmt(o['warned'])} | {_fmt(o['lead_s'], 2)} | {v['false_frames']} |")
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
        parts = [self.object_table()] if any(s["objects"] or not s["clips"] for s in self.models.values()) else []
        warn, cw = self.warning_table(), self.clip_warning_table()
        parts += [self.notes(), self.clip_table(), warn and "Warnings (collision objects of 3-D truth):\n\n" + warn,
                  cw and "Warnings on labelled clips:\n\n" + cw, self.video_table() if details else ""]
        return "\n\n".join(p for p in parts if p)

    def write(self, out) -> dict[str, Path]:
        """Write ``evaluation.md`` and ``evaluation.json`` into folder ``out``."""
        from ._files import write_text

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
            write_text(path, text)
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
    from .models.base import available_models, resolve_names
    from .runner import RunResult, run

    if models is not None:
        models = resolve_names(models)
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
    wvideos: list[dict] = []     # warning metrics, per (model, video) and per collision object
    wobjects: list[dict] = []
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
        if _warning_truth(t):
            wv, wo = _score_warnings(r, t, radius=match_radius)
            wvideos.append(wv)
            wobjects.extend(wo)
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
                    "params": by_label[lb].params, **_summarise(lb, videos, objects),
                    "warnings": _summarise_warnings(lb, wvideos, wobjects) or None} for lb in labels}
    wvideos.sort(key=lambda v: (labels.index(v["model"]), v["video"]))
    wobjects.sort(key=lambda o: (labels.index(o["model"]), o["video"], str(o["object"])))
    videos.sort(key=lambda v: (labels.index(v["model"]), v["video"]))
    objects.sort(key=lambda o: (labels.index(o["model"]), o["video"], o["onset"], str(o["object"])))
    settings = {"ground_truth": truth.source, "match_radius": match_radius, "tail": tail}
    return Evaluation(summary, videos, objects, settings, skipped, notes, wvideos, wobjects)


def _video_key(source: str) -> str:
    """A result's video, comparable across result folders (the path as recorded, resolved if it exists)."""
    source = str(source)
    return _path_key(source) if os.path.exists(source) else os.path.normcase(os.path.normpath(source))


def _issue(notes: list[str]) -> None:
    for note in notes:
        warnings.warn(note, EvaluationWarning, stacklevel=3)
