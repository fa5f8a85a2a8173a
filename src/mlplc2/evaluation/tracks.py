"""What models said, frame by frame, and how it is held against the truth.

One home for what every scorer and recorder needs (``mlplc2 run``, ``mlplc2 evaluate``,
``mlplc2 benchmark``, ``mlplc2 reproduce``, the tests):

:class:`Record` / :class:`Recorder`
    one model's outputs on one video: per frame the global alarm and response, the
    attention fields (id, centre, response, alarm) and the targets (id, centre, size, time
    to contact, miss, warning); per field its life (birth, death, peak, first alarm) and per
    target its summary. A :class:`Recorder` fills Records from :class:`~mlplc2.Output`
    objects as a video is processed: its series may be switched off and the fields that died
    spilled to a temporary file for long runs (``mlplc2 run``, whose ``fields.json`` is
    :meth:`Recorder.summaries` and :meth:`Recorder.target_summaries`); :func:`record` runs a
    model over frames with every series (``mlplc2 reproduce``, the tests).
matching
    :func:`centre_distance` (the paper's metrics: a field stands for an object when its centre
    lies within :data:`DEFAULT_MATCH_RADIUS` of the object's centre; :func:`fields_near`,
    :func:`first_field`) and :func:`box_distance` (the warning metrics: a target is on an
    object when its centre lies within the match radius of the object's box, so large objects
    are matched anywhere on them; :func:`on_object`).
false alarms (the paper's metrics)
    :func:`alarm_explained`: an alarm is explained when it lies within the match radius of an
    object that approaches, up to :data:`DEFAULT_TAIL` frames after its approach (a global
    alarm: when any object does); :func:`false_alarms` lists a Record's unexplained ones.
false warnings (the warning metrics, another question)
    :func:`warning_cause`: a warning is true when it is on an object on a collision course
    before its contact; otherwise its cause is ``"pass"`` (on a pass-by object),
    ``"distractor"`` (on a receding, translating or static object) or ``"background"``.

Coordinates are those of the ground truth (the video's own pixels).
"""

from __future__ import annotations

import json
import math
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .truth import ObjectTruth, VideoTruth, load

__all__ = ["FieldTrack", "TargetRow", "TargetTrack", "Record", "Recorder", "record", "centre_distance",
           "fields_near", "first_field", "box_distance", "on_object", "alarm_explained", "false_alarms",
           "warning_cause", "episodes", "response_rows", "match_fields", "DEFAULT_MATCH_RADIUS", "DEFAULT_TAIL", "CAUSES"]

#: Match radius in ground-truth pixels (a field or target this close stands for the object).
DEFAULT_MATCH_RADIUS = 20.0
#: Frames after the end of an approach during which a detection or alarm still counts for it.
DEFAULT_TAIL = 25
#: Causes of a false warning (:func:`warning_cause`).
CAUSES = ("pass", "distractor", "background")


# ---------------------------------------------------------------------------
# records
# ---------------------------------------------------------------------------
def _px(v: float | None) -> float | None:
    """A position or size in the output files: px, 2 decimals."""
    return None if v is None else round(float(v), 2)


def _sig(v: float) -> float:
    """A response in the output files: 7 significant digits."""
    v = float(v)
    return float(f"{v:.7g}") if math.isfinite(v) else v


def response_rows(index: int, time_s: float, name: str, out, to_input) -> list[dict]:
    """The ``responses.csv`` rows of one model's :class:`~mlplc2.models.Output` at frame ``index``:
    one per field (centre mapped to input pixels by ``to_input(x, y)``), or one frame-wide row."""
    if not out.fields:
        return [{"frame": index, "time_s": time_s, "model": name, "field_id": None, "x": None, "y": None,
                 "response": _sig(out.response), "collision": int(bool(out.collision))}]
    rows = []
    for f in out.fields:
        x, y = to_input(f.x, f.y)
        rows.append({"frame": index, "time_s": time_s, "model": name, "field_id": f.id, "x": _px(x),
                     "y": _px(y), "response": _sig(f.response), "collision": int(bool(f.collision))})
    return rows


def _opt4(v: float | None) -> float | None:
    """A time to contact, miss or bearing in the output files: 4 decimals, empty when unknown."""
    return None if v is None else round(float(v), 4) + 0.0  # + 0.0: no "-0.0"


@dataclass
class FieldTrack:
    """One attention field over its life (frames are the video's frame indices).

    ``x``, ``y``: its centre at its peak response (the first frame of a plateau), in video
    pixels (mLPLC2 fields stay where they were born; sLPLC2's follows the motion);
    ``frames``, ``responses``, ``alarms``: its per-frame series (a :class:`Recorder` with
    ``series=True``)."""

    id: int
    x: float
    y: float
    radius: float
    born: int
    died: int | None = None
    peak_response: float = 0.0
    peak_frame: int | None = None
    first_alarm_frame: int | None = None
    frames: list[int] = field(default_factory=list)
    responses: list[float] = field(default_factory=list)
    alarms: list[int] = field(default_factory=list)

    @property
    def first_alarm(self) -> int | None:
        return self.first_alarm_frame

    @property
    def peak(self) -> float:
        return self.peak_response

    @property
    def last(self) -> int | None:
        return self.frames[-1] if self.frames else None

    def summary(self) -> dict:
        """The field's entry of ``fields.json`` (docs/cli.md): rounded as in ``responses.csv``."""
        return {"id": self.id, "x": _px(self.x), "y": _px(self.y), "born": self.born, "died": self.died,
                "peak_response": _sig(self.peak_response), "peak_frame": self.peak_frame,
                "first_alarm_frame": self.first_alarm_frame}


@dataclass(frozen=True)
class TargetRow:
    """One target in one frame (video pixels)."""

    id: int
    x: float
    y: float
    width: float | None = None
    height: float | None = None
    ttc_s: float | None = None
    miss: float | None = None
    warning: bool = False
    fields: tuple[int, ...] = ()
    azimuth_deg: float | None = None
    elevation_deg: float | None = None

    def values(self) -> dict:
        """Its cells of ``targets.csv`` after ``frame, model, target_id`` (rounded; None: empty)."""
        return {"x": _px(self.x), "y": _px(self.y), "width": _px(self.width), "height": _px(self.height),
                "ttc_s": _opt4(self.ttc_s), "miss": _opt4(self.miss), "warning": int(bool(self.warning)),
                "fields": " ".join(map(str, self.fields)), "azimuth_deg": _opt4(self.azimuth_deg),
                "elevation_deg": _opt4(self.elevation_deg)}


@dataclass
class TargetTrack:
    """One target over its life: the summary ``fields.json`` writes under ``"targets"``
    (docs/targets.md): life, frames, first estimate, first warning and the estimates then."""

    id: int
    born: int
    died: int | None = None
    frames: int = 0
    first_ttc_frame: int | None = None
    first_warning_frame: int | None = None
    warning_frames: int = 0
    at_first_warning: TargetRow | None = None
    fields: set[int] = field(default_factory=set)
    last_frame: int | None = None
    last: TargetRow | None = None

    def summary(self) -> dict:
        return {"id": self.id, "born": self.born, "died": self.died, "frames": self.frames,
                "first_ttc_frame": self.first_ttc_frame, "first_warning_frame": self.first_warning_frame,
                "warning_frames": self.warning_frames,
                "at_first_warning": None if self.at_first_warning is None else self.at_first_warning.values(),
                "fields": sorted(self.fields), "last": {"frame": self.last_frame, **self.last.values()}}


@dataclass
class Record:
    """One model's outputs on one video.

    Always: ``fields`` (id -> :class:`FieldTrack`, their summaries; with ``spill`` only the
    live ones), ``targets`` (id -> :class:`TargetTrack`), ``alarm_count`` and
    ``first_alarm_frame`` (frames with ``Output.collision``). With ``series`` (the default)
    also per frame: ``alarm[frame]`` (``Output.collision``), ``response_at[frame]``
    (``Output.response``), ``fields_at[frame]``: ``(field_id, x, y, response, collision)`` of
    every field, ``targets_at[frame]``: its :class:`TargetRow` s; and each field's series.
    ``has_targets``: the model makes targets (its warning is then the targets' warnings; else
    its alarm). ``localises``: its fields have meaningful positions.
    """

    model: str
    source: str = ""
    fps: float = 30.0
    size: tuple[int, int] | None = None
    start: int = 0
    n_frames: int = 0
    alarm: dict[int, bool] = field(default_factory=dict)
    response_at: dict[int, float] = field(default_factory=dict)
    fields_at: dict[int, list[tuple[int, float, float, float, bool]]] = field(default_factory=dict)
    targets_at: dict[int, list[TargetRow]] = field(default_factory=dict)
    fields: dict[int, FieldTrack] = field(default_factory=dict)
    targets: dict[int, TargetTrack] = field(default_factory=dict)
    alarm_count: int = 0
    first_alarm_frame: int | None = None
    has_targets: bool = False
    localises: bool = False
    label: str = ""

    @property
    def frames(self) -> range:
        """The processed frames."""
        return range(self.start, self.start + self.n_frames)

    @property
    def response(self) -> np.ndarray:
        """``Output.response`` of every processed frame (series), as an array."""
        return np.array([self.response_at.get(f, 0.0) for f in self.frames], dtype=float)

    @property
    def collision(self) -> np.ndarray:
        """``Output.collision`` of every processed frame (series), as an array."""
        return np.array([bool(self.alarm.get(f)) for f in self.frames], dtype=bool)

    def alarmed(self) -> list[FieldTrack]:
        """The fields that raised an alarm, in order of birth."""
        return [f for f in self.fields.values() if f.first_alarm_frame is not None]


class Recorder:
    """Fills one :class:`Record` per model from the models' outputs, frame by frame: the one
    recorder of ``mlplc2 run`` (``fields.json``), ``mlplc2 reproduce`` and the tests.

    ``offset``: the video frame index of model frame 0 (``--start``); ``to_input``: maps model
    pixels to video pixels (``--resize``); ``series``: keep the per-frame rows and each field's
    per-frame responses (False keeps only the summaries: flat memory in the frames);
    ``spill``: a field that died leaves memory for an anonymous temporary file (flat memory
    in the fields too: long or live runs); :meth:`summaries` still lists it. :meth:`close`
    the recorder (or use it in a ``with`` block) to delete that file.
    """

    def __init__(self, models: Sequence, *, fps: float = 30.0, source: str = "", size=None, offset: int = 0,
                 to_input=None, series: bool = True, spill: bool = False):
        self.offset = offset
        self.to_input = to_input or (lambda x, y: (x, y))
        self.series = series
        self.records: dict[str, Record] = {}
        self._alive: dict[str, set[int]] = {}
        self._alive_targets: dict[str, set[int]] = {}
        self._spill: dict[str, Any] | None = {} if spill else None
        for m in models:
            name = m if isinstance(m, str) else m.name
            self.records[name] = Record(model=name, source=source, fps=fps, size=size, start=offset,
                                        has_targets=bool(getattr(m, "has_targets", False)),
                                        localises=bool(getattr(m, "localises", False)), label=name)
            self._alive[name] = set()
            self._alive_targets[name] = set()

    def update(self, index: int, name: str, out) -> list[TargetRow]:
        """Add ``out`` (an :class:`~mlplc2.Output`) of model ``name`` at video frame ``index``.
        Returns the frame's targets as :class:`TargetRow` s (video pixels: ``targets.csv``)."""
        rec = self.records[name]
        rec.n_frames = index - rec.start + 1
        if out.collision:
            rec.alarm_count += 1
            if rec.first_alarm_frame is None:
                rec.first_alarm_frame = index
        if self.series:
            rec.alarm[index] = bool(out.collision)
            rec.response_at[index] = float(out.response)
        present = set()
        rows = []
        for f in out.fields:
            present.add(f.id)
            x, y = self.to_input(f.x, f.y)
            ft = rec.fields.get(f.id)
            if ft is None:
                ft = rec.fields[f.id] = FieldTrack(f.id, float(x), float(y), float(f.radius), f.born + self.offset,
                                                   peak_response=float(f.response), peak_frame=index)
            elif f.response > ft.peak_response:      # the first frame of a plateau stays the peak
                ft.peak_response, ft.peak_frame = float(f.response), index
                ft.x, ft.y = float(x), float(y)
            if f.collision and ft.first_alarm_frame is None:
                ft.first_alarm_frame = index
            if self.series:
                ft.frames.append(index)
                ft.responses.append(float(f.response))
                if f.collision:
                    ft.alarms.append(index)
                rows.append((f.id, float(x), float(y), float(f.response), bool(f.collision)))
        for fid in self._alive[name] - present:
            ft = rec.fields[fid]
            ft.died = index
            if self._spill is not None:
                spill = self._spill.get(name)
                if spill is None:
                    spill = self._spill[name] = tempfile.TemporaryFile("w+", encoding="utf-8")
                spill.write(json.dumps(ft.summary()) + "\n")
                del rec.fields[fid]
        self._alive[name] = present
        targets = [self._target_row(t) for t in getattr(out, "targets", ())]
        self._update_targets(index, rec, name, targets)
        if self.series:
            if rows:
                rec.fields_at[index] = rows
            if targets:
                rec.targets_at[index] = targets
        return targets

    def _target_row(self, t) -> TargetRow:
        x, y = self.to_input(t.x, t.y)
        x1, y1 = self.to_input(t.x + t.width, t.y + t.height)
        return TargetRow(t.id, float(x), float(y), float(x1 - x), float(y1 - y), t.ttc_s, t.miss, bool(t.warning),
                         tuple(t.fields), getattr(t, "azimuth_deg", None), getattr(t, "elevation_deg", None))

    def _update_targets(self, index: int, rec: Record, name: str, rows: list[TargetRow]) -> None:
        """Per target: life, frames, first estimate and first warning (with the estimate then)."""
        seen = set()
        for t in rows:
            seen.add(t.id)
            tt = rec.targets.get(t.id)
            if tt is None:
                tt = rec.targets[t.id] = TargetTrack(t.id, born=index)
            tt.frames += 1
            tt.fields.update(t.fields)
            if t.ttc_s is not None and tt.first_ttc_frame is None:
                tt.first_ttc_frame = index
            if t.warning:
                tt.warning_frames += 1
                if tt.first_warning_frame is None:
                    tt.first_warning_frame, tt.at_first_warning = index, t
            tt.last_frame, tt.last = index, t
        for tid in self._alive_targets[name] - seen:
            if rec.targets[tid].died is None:
                rec.targets[tid].died = index
        self._alive_targets[name] = seen

    def summaries(self, name: str) -> list[dict]:
        """The field summaries of model ``name`` (``fields.json`` ``"models"``), by id, spilled ones too."""
        out = [ft.summary() for ft in self.records[name].fields.values()]
        spill = None if self._spill is None else self._spill.get(name)
        if spill is not None:
            spill.seek(0)
            out += [json.loads(line) for line in spill]
            spill.seek(0, 2)
        return sorted(out, key=lambda d: d["id"])

    def target_summaries(self, name: str) -> list[dict]:
        """The target summaries of model ``name`` (``fields.json`` ``"targets"``), by id."""
        targets = self.records[name].targets
        return [targets[k].summary() for k in sorted(targets)]

    def close(self) -> None:
        """Delete the spill files (the summaries of the fields that died are then lost)."""
        for f in (self._spill or {}).values():
            f.close()
        if self._spill:
            self._spill.clear()

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def record(model, frames, *, progress=None) -> Record:
    """Run ``model`` (a :class:`~mlplc2.models.Model`) over ``frames`` and record every output
    with its series (frame indices: ``Output.frame``). ``progress``: an object with
    ``update(1)`` (a tqdm bar), called once per frame."""
    rec = Recorder([model], fps=model.fps)
    for frame in frames:
        out = model.step(frame)
        rec.update(out.frame, model.name, out)
        if progress is not None:
            progress.update(1)
    return rec.records[model.name]


# ---------------------------------------------------------------------------
# matching
# ---------------------------------------------------------------------------
def centre_distance(x: float, y: float, obj: ObjectTruth, frame: int) -> float:
    """Distance (px) from (x, y) to the object's centre at ``frame`` (inf without a centre)."""
    c = obj.center_at(frame)
    return math.inf if c is None else math.hypot(x - c[0], y - c[1])


def fields_near(fields: Iterable[FieldTrack], obj: ObjectTruth, start: int, end: int,
                radius: float = DEFAULT_MATCH_RADIUS) -> list[FieldTrack]:
    """The fields born in ``[start, end)`` that stand for ``obj``: their centre lies within
    ``radius`` of the object's at their birth (:func:`centre_distance`); in the order given."""
    return [f for f in fields if start <= f.born < end and centre_distance(f.x, f.y, obj, f.born) <= radius]


def first_field(rec: Record, obj: ObjectTruth,
                radius: float = DEFAULT_MATCH_RADIUS) -> tuple[FieldTrack, int, float] | None:
    """The paper's detection of an approaching ``obj``: the first field born during its
    approach that stands for it (:func:`fields_near`; the nearest of those born first), with
    its latency (frames from the approach onset) and centre error (px); None if there is none."""
    a0, a1 = obj.approach
    hits = fields_near(rec.fields.values(), obj, a0, a1, radius)
    if not hits:
        return None
    f = min(hits, key=lambda f: (f.born, centre_distance(f.x, f.y, obj, f.born)))
    return f, f.born - a0, centre_distance(f.x, f.y, obj, f.born)


def box_distance(x: float, y: float, obj: ObjectTruth, frame: int) -> float:
    """Distance (px) from (x, y) to the object's box at ``frame`` (0 inside it); the centre
    distance when its size is unknown."""
    c = obj.center_at(frame)
    if c is None:
        return math.inf
    p = obj.point_at(frame)
    w = obj.width_at(frame)
    h = p.height if p is not None and p.height is not None else w
    if w is None:
        return math.hypot(x - c[0], y - c[1])
    dx = max(abs(x - c[0]) - w / 2.0, 0.0)
    dy = max(abs(y - c[1]) - h / 2.0, 0.0)
    return math.hypot(dx, dy)


def on_object(x: float, y: float, obj: ObjectTruth, frame: int, radius: float = DEFAULT_MATCH_RADIUS) -> bool:
    """Whether (x, y) is on ``obj`` at ``frame``: within ``radius`` of its box (:func:`box_distance`)."""
    return box_distance(x, y, obj, frame) <= radius


# ---------------------------------------------------------------------------
# false alarms (the paper's metrics) and false warnings (the warning metrics)
# ---------------------------------------------------------------------------
def alarm_explained(frame: int, objects: Iterable[ObjectTruth], x: float | None = None, y: float | None = None, *,
                    radius: float = DEFAULT_MATCH_RADIUS, tail: int = DEFAULT_TAIL) -> bool:
    """The paper's rule for an alarm: it is explained when an object approaches at ``frame``
    or did up to ``tail`` frames before (``[approach start, approach end + tail)``) and, for
    the alarm of a field at ``(x, y)``, the field lies within ``radius`` of that object's
    centre (:func:`centre_distance`). A global alarm (``x`` None) needs only the time."""
    for o in objects:
        if o.approach is not None and o.approach[0] <= frame < o.approach[1] + tail \
                and (x is None or centre_distance(x, y, o, frame) <= radius):
            return True
    return False


def false_alarms(rec: Record, objects: Sequence[ObjectTruth], *, radius: float = DEFAULT_MATCH_RADIUS,
                 tail: int = DEFAULT_TAIL) -> list[tuple[int, int]]:
    """``(frame, field id)`` of every frame in which a field is in alarm that
    :func:`alarm_explained` does not explain, by frame then id (needs the series)."""
    return sorted((frame, fid) for frame, rows in rec.fields_at.items() for fid, x, y, _, alarm in rows
                  if alarm and not alarm_explained(frame, objects, x, y, radius=radius, tail=tail))


def _present(obj: ObjectTruth, frame: int) -> bool:
    """Whether ``obj`` is in the video at ``frame`` (in view for tracked 3-D truth)."""
    if obj.kind is not None and obj.track:
        return obj.in_track(frame)
    if obj.span is not None:
        return obj.span[0] <= frame < obj.span[1]
    return obj.in_track(frame) if obj.track else True


def warning_cause(x: float | None, y: float | None, frame: int, truth: VideoTruth, *,
                  radius: float = DEFAULT_MATCH_RADIUS, tail: int = 0) -> tuple[str, ObjectTruth | None]:
    """Whether a warning at (x, y) in ``frame`` is true, and on what.

    Returns ``("true", obj)`` for a warning on an object on a collision course (``collides``;
    the labelled ``collider`` of a clip) up to ``tail`` frames after its contact, else
    ``(cause, obj)`` with cause one of :data:`CAUSES`: ``"pass"`` (on a pass-by object),
    ``"distractor"`` (on another object: receding, translating, static, or a collider after its
    contact) or ``"background"`` (on no object; ``obj`` None). A warning without a position
    (``x`` None: a global alarm) is true while a collision object is in view before its
    contact, else it takes the cause of the objects in view (pass-by first).
    """
    objects = list(truth.objects) + ([truth.collider] if truth.collider is not None else [])
    cands = []
    for o in objects:
        if not _present(o, frame) and not (o is truth.collider):
            continue
        if x is None:
            cands.append((0.0, o))
        else:
            d = box_distance(x, y, o, frame)
            if d <= radius:
                cands.append((d, o))

    def live(o):
        return o.collides and (o.contact_frame is None or frame <= o.contact_frame + tail)

    # the nearest candidate of the first class that has one (min keeps the first of equals)
    for verdict, of in (("true", live), ("pass", lambda o: o.kind == "pass"), ("distractor", lambda o: True)):
        hits = [c for c in cands if of(c[1])]
        if hits:
            return verdict, min(hits, key=lambda c: c[0])[1]
    return "background", None


def episodes(frames: Iterable[int]) -> int:
    """Number of runs of consecutive frames in ``frames``."""
    frames = set(frames)
    return sum(f - 1 not in frames for f in frames)


def match_fields(fields: list[dict], truth, *, radius: float = DEFAULT_MATCH_RADIUS) -> list[dict]:
    """For each ground-truth object with a centre, the field that stands for it.

    Among the fields born while the object is on screen, the one with the largest peak
    response whose centre lies within ``radius`` px of the object's
    (:func:`mlplc2.evaluation.tracks.centre_distance`, the matcher of the paper's metrics), else the
    nearest one (``None`` when no field was born meanwhile). ``fields``: field summaries
    (``fields.json``); ``truth``: the demo's ground truth (a JSON entry) or a
    :class:`~mlplc2.evaluation.truth.VideoTruth`.
    """
    video = truth if isinstance(truth, VideoTruth) else next(iter(load(truth).values()))
    matches = []
    for obj in video.objects:
        if obj.center is None:
            continue
        t0, t1 = obj.span or (0, math.inf)
        cand = [f for f in fields if t0 <= f["born"] < t1]

        def dist(f):
            return centre_distance(f["x"], f["y"], obj, f["born"])

        near = [f for f in cand if dist(f) <= radius]
        if near:  # the strongest field near the object (a field may be replaced while it looms)
            best = max(near, key=lambda f: (f["peak_response"], -f["born"]))
        else:
            best = min(cand, key=dist, default=None)
        matches.append({
            "object": obj.id, "center": list(obj.center), "frames": [t0, t1],
            "field": None if best is None else best["id"],
            "field_center": None if best is None else [best["x"], best["y"]],
            "distance": None if best is None else round(dist(best), 1),
            "first_alarm_frame": None if best is None else best["first_alarm_frame"],
        })
    return matches
