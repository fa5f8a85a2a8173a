"""What models said, frame by frame, and how it is held against the truth.

One home for three things every scorer needs (``mlplc2 evaluate``, ``mlplc2 benchmark``,
``mlplc2 reproduce``, the tests):

:class:`Record` / :class:`Recorder`
    one model's outputs on one video: per frame the global alarm, the attention fields
    (id, centre, response, alarm) and the targets (id, centre, size, time to contact, miss,
    warning); per field its life (birth, death, peak, first alarm). A :class:`Recorder` fills
    Records from :class:`~mlplc2.Output` objects as a video is processed (its series may be
    switched off for long runs); :func:`read_results` rebuilds them from an output folder.
matching
    :func:`centre_distance` (the paper's metrics: a field stands for an object when its centre
    lies within the match radius of the object's centre) and :func:`box_distance` (the warning
    metrics: a target is on an object when its centre lies within the match radius of the
    object's box, so large objects are matched anywhere on them).
false warnings
    :func:`warning_cause`: a warning is true when it is on an object on a collision course
    before its contact; otherwise its cause is ``"pass"`` (on a pass-by object),
    ``"distractor"`` (on a receding, translating or static object) or ``"background"``.

Coordinates are those of the ground truth (the video's own pixels); a Record made at another
size is mapped with :meth:`Record.scaled`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace

from .truth import ObjectTruth, VideoTruth

__all__ = ["FieldTrack", "TargetRow", "Record", "Recorder", "centre_distance", "box_distance", "on_object",
           "warning_cause", "episodes", "DEFAULT_MATCH_RADIUS", "DEFAULT_TAIL", "CAUSES"]

#: Match radius in ground-truth pixels (a field or target this close stands for the object).
DEFAULT_MATCH_RADIUS = 20.0
#: Frames after the end of an approach during which a detection or alarm still counts for it.
DEFAULT_TAIL = 25
#: Causes of a false warning (:func:`warning_cause`).
CAUSES = ("pass", "distractor", "background")


# ---------------------------------------------------------------------------
# records
# ---------------------------------------------------------------------------
@dataclass
class FieldTrack:
    """One attention field over its life (frames are the video's frame indices)."""

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


@dataclass(frozen=True)
class TargetRow:
    """One target in one frame (ground-truth pixels)."""

    id: int
    x: float
    y: float
    width: float | None = None
    height: float | None = None
    ttc_s: float | None = None
    miss: float | None = None
    warning: bool = False
    fields: tuple[int, ...] = ()


@dataclass
class Record:
    """One model's outputs on one video.

    ``fields_at[frame]``: ``(field_id, x, y, response, collision)`` of every field that frame;
    ``targets_at[frame]``: its :class:`TargetRow` s; ``alarm[frame]``: the model's global
    alarm (``Output.collision``). ``has_targets``: the model makes targets (its warning is then
    the targets' warnings; else its alarm). ``localises``: its fields have meaningful positions.
    """

    model: str
    source: str = ""
    fps: float = 30.0
    size: tuple[int, int] | None = None
    start: int = 0
    n_frames: int = 0
    alarm: dict[int, bool] = field(default_factory=dict)
    fields_at: dict[int, list[tuple[int, float, float, float, bool]]] = field(default_factory=dict)
    targets_at: dict[int, list[TargetRow]] = field(default_factory=dict)
    fields: dict[int, FieldTrack] = field(default_factory=dict)
    has_targets: bool = False
    localises: bool = False
    label: str = ""

    @property
    def frames(self) -> range:
        """The processed frames."""
        return range(self.start, self.start + self.n_frames)

    def warnings_at(self, frame: int) -> list[TargetRow]:
        """The warning targets of ``frame``."""
        return [t for t in self.targets_at.get(frame, ()) if t.warning]

    def warned(self, frame: int) -> bool:
        """The model's warning this frame: any target warning (models with targets), else the alarm."""
        if self.has_targets:
            return any(t.warning for t in self.targets_at.get(frame, ()))
        return bool(self.alarm.get(frame))

    def scaled(self, sx: float, sy: float) -> "Record":
        """A copy with every position and size multiplied by (sx, sy) (model -> truth pixels)."""
        if sx == 1.0 and sy == 1.0:
            return self
        s = math.sqrt(sx * sy)
        fields_at = {f: [(i, x * sx, y * sy, r, c) for i, x, y, r, c in rows] for f, rows in self.fields_at.items()}
        targets_at = {f: [replace(t, x=t.x * sx, y=t.y * sy,
                                  width=None if t.width is None else t.width * sx,
                                  height=None if t.height is None else t.height * sy) for t in rows]
                      for f, rows in self.targets_at.items()}
        fields = {i: replace(ft, x=ft.x * sx, y=ft.y * sy, radius=ft.radius * s) for i, ft in self.fields.items()}
        size = None if self.size is None else (int(round(self.size[0] * sx)), int(round(self.size[1] * sy)))
        return replace(self, fields_at=fields_at, targets_at=targets_at, fields=fields, size=size)


class Recorder:
    """Fills one :class:`Record` per model from the models' outputs, frame by frame.

    ``offset``: the video frame index of model frame 0 (``--start``); ``to_input``: maps model
    pixels to video pixels (``--resize``); ``series``: keep the per-frame rows and each field's
    per-frame responses (False keeps only each field's summary and the alarms: flat memory).
    """

    def __init__(self, models: Sequence, *, fps: float = 30.0, source: str = "", size=None, offset: int = 0,
                 to_input=None, series: bool = True):
        self.offset = offset
        self.to_input = to_input or (lambda x, y: (x, y))
        self.series = series
        self.records: dict[str, Record] = {}
        self._alive: dict[str, set[int]] = {}
        for m in models:
            name = m if isinstance(m, str) else m.name
            self.records[name] = Record(model=name, source=source, fps=fps, size=size, start=offset,
                                        has_targets=bool(getattr(m, "has_targets", False)),
                                        localises=bool(getattr(m, "localises", False)), label=name)
            self._alive[name] = set()

    def update(self, index: int, name: str, out) -> list[FieldTrack]:
        """Add ``out`` (an :class:`~mlplc2.Output`) of model ``name`` at video frame ``index``.
        Returns the fields that died this frame (for callers that spill them)."""
        rec = self.records[name]
        rec.n_frames = index - rec.start + 1
        rec.alarm[index] = bool(out.collision)
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
        if self.series:
            if rows:
                rec.fields_at[index] = rows
            targets = getattr(out, "targets", ())
            if targets:
                rec.targets_at[index] = [self._target_row(t) for t in targets]
        died = [rec.fields[i] for i in self._alive[name] - present]
        for ft in died:
            ft.died = index
        self._alive[name] = present
        return died

    def _target_row(self, t) -> TargetRow:
        x, y = self.to_input(t.x, t.y)
        x1, y1 = self.to_input(t.x + t.width, t.y + t.height)
        return TargetRow(t.id, float(x), float(y), float(x1 - x), float(y1 - y), t.ttc_s, t.miss, bool(t.warning),
                         tuple(t.fields))


# ---------------------------------------------------------------------------
# matching
# ---------------------------------------------------------------------------
def centre_distance(x: float, y: float, obj: ObjectTruth, frame: int) -> float:
    """Distance (px) from (x, y) to the object's centre at ``frame`` (inf without a centre)."""
    c = obj.center_at(frame)
    return math.inf if c is None else math.hypot(x - c[0], y - c[1])


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


def _present(obj: ObjectTruth, frame: int) -> bool:
    """Whether ``obj`` is in the video at ``frame`` (in view for tracked 3-D truth)."""
    if obj.kind is not None and obj.track:
        return obj.in_track(frame)
    spans = [getattr(obj, p) for p in ("approach", "hold", "recede", "translate") if getattr(obj, p)]
    if spans:
        return min(s[0] for s in spans) <= frame < max(s[1] for s in spans)
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

    for _, o in sorted(cands, key=lambda c: (not live(c[1]), c[0])):
        if live(o):
            return "true", o
    for _, o in sorted(cands, key=lambda c: c[0]):
        if o.kind == "pass":
            return "pass", o
    if cands:
        return "distractor", min(cands, key=lambda c: c[0])[1]
    return "background", None


def episodes(frames: Iterable[int]) -> int:
    """Number of runs of consecutive frames in ``frames``."""
    n, prev = 0, None
    for f in sorted(set(frames)):
        if prev is None or f != prev + 1:
            n += 1
        prev = f
    return n

