"""How a :class:`~mlplc2.evaluation.record.Record` is held against the ground truth: the one
matcher and the one false-alarm and false-warning rules.

matching
    :func:`centre_distance` (the paper's metrics: a field stands for an object when its centre
    lies within :data:`DEFAULT_MATCH_RADIUS` of the object's centre; :func:`fields_near`,
    :func:`first_field`, :func:`match_fields`) and :func:`box_distance` (the warning metrics: a
    target is on an object when its centre lies within the match radius of the object's box,
    so large objects are matched anywhere on them; :func:`on_object`; :func:`nearest_object`: the
    one object a target or warning stands for in a frame: a warning warns of that object only,
    and a target counts for it only, in the targets on an object and their times to contact).
false alarms (the paper's metrics)
    :func:`alarm_explained`: an alarm is explained when it lies within the match radius of an
    object that approaches, up to :data:`DEFAULT_TAIL` frames after its approach (a global
    alarm: when any object does); :func:`false_alarms` lists a Record's unexplained ones.
false warnings (the warning metrics, another question)
    :func:`warning_cause`: a warning is true when the object it stands for
    (:func:`nearest_object`) is on a collision course before its contact; otherwise its cause is
    ``"pass"`` (on a pass-by object),
    ``"distractor"`` (on a receding, translating or static object) or ``"background"``;
    :func:`episodes` counts its runs of frames.

Coordinates are those of the ground truth (the video's own pixels).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import Any

from .record import FieldHistory, Record
from .truth import ObjectTruth, VideoTruth, load

__all__ = ["centre_distance", "fields_near", "first_field", "box_distance", "on_object", "nearest_object",
           "alarm_explained",
           "false_alarms", "warning_cause", "episodes", "match_fields", "DEFAULT_MATCH_RADIUS", "DEFAULT_TAIL",
           "CAUSES"]

#: Match radius in ground-truth pixels (a field or target this close stands for the object).
DEFAULT_MATCH_RADIUS = 20.0
#: Frames after the end of an approach during which a detection or alarm still counts for it.
DEFAULT_TAIL = 25
#: Causes of a false warning (:func:`warning_cause`).
CAUSES = ("pass", "distractor", "background")


# ---------------------------------------------------------------------------
# matching
# ---------------------------------------------------------------------------
def centre_distance(x: float, y: float, obj: ObjectTruth, frame: int) -> float:
    """Distance (px) from (x, y) to the object's centre at ``frame`` (inf without a centre)."""
    c = obj.center_at(frame)
    return math.inf if c is None else math.hypot(x - c[0], y - c[1])


def fields_near(fields: Iterable[FieldHistory], obj: ObjectTruth, start: int, end: int,
                radius: float = DEFAULT_MATCH_RADIUS) -> list[FieldHistory]:
    """The fields born in ``[start, end)`` that stand for ``obj``: their centre lies within
    ``radius`` of the object's at their birth (:func:`centre_distance`); in the order given."""
    return [f for f in fields if start <= f.born < end and centre_distance(f.x, f.y, obj, f.born) <= radius]


def first_field(rec: Record, obj: ObjectTruth,
                radius: float = DEFAULT_MATCH_RADIUS) -> tuple[FieldHistory, int, float] | None:
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


def nearest_object(x: float, y: float, frame: int, truth: VideoTruth,
                   radius: float = DEFAULT_MATCH_RADIUS,
                   hidden: Mapping[Any, Collection[int]] | None = None) -> ObjectTruth | None:
    """The one object a target at (x, y) stands for at ``frame``: of the objects in view then
    (the clip's collider always), the one whose box lies nearest (:func:`box_distance`, within
    ``radius``; among equals the nearer centre, then the first); None when none is that near.
    A target between two objects counts for one of them only: beside a passing car, the target
    on the car is not a second target of the collision object next to it (fragmentation).
    ``hidden``: object id -> the frames in which it is hidden behind nearer objects
    (:func:`mlplc2.evaluation.score.hidden_frames`); a hidden object stands for no target then (a
    warning on the lead vehicle is the lead vehicle's, not that of a small car behind it whose
    centre lies nearer)."""
    best, key = None, None
    for o in list(truth.objects) + ([truth.collider] if truth.collider is not None else []):
        if not (_present(o, frame) or o is truth.collider):
            continue
        if hidden is not None and frame in hidden.get(o.id, ()):
            continue
        d = box_distance(x, y, o, frame)
        if d <= radius and (key is None or (d, centre_distance(x, y, o, frame)) < key):
            best, key = o, (d, centre_distance(x, y, o, frame))
    return best


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
                  radius: float = DEFAULT_MATCH_RADIUS, tail: int = 0,
                  hidden: Mapping[Any, Collection[int]] | None = None) -> tuple[str, ObjectTruth | None]:
    """Whether a warning at (x, y) in ``frame`` is true, and on what.

    A warning with a position stands for one object, the one :func:`nearest_object` gives (its
    box nearest within ``radius``, among equals the nearer centre). Returns ``("true", obj)`` when
    that object is on a collision course (``collides``; the labelled ``collider`` of a clip) up to
    ``tail`` frames after its contact, else ``(cause, obj)`` with cause one of :data:`CAUSES`:
    ``"pass"`` (a pass-by object), ``"distractor"`` (another object: receding, translating,
    static, or a collider after its contact) or ``"background"`` (no object that near; ``obj``
    None). A warning on a passing car 10 px beside a collision object's box warns of the car: it
    is false, not a warning of the collision. A warning without a position (``x`` None: a global
    alarm) is true while a collision object is in view before its contact, else it takes the
    cause of the objects in view (pass-by first). ``hidden``: as in :func:`nearest_object` (for a
    warning with a position).
    """
    def live(o):
        return o.collides and (o.contact_frame is None or frame <= o.contact_frame + tail)

    if x is not None:
        o = nearest_object(x, y, frame, truth, radius, hidden)
        if o is None:
            return "background", None
        return ("true" if live(o) else "pass" if o.kind == "pass" else "distractor"), o
    seen = [o for o in list(truth.objects) + ([truth.collider] if truth.collider is not None else [])
            if _present(o, frame) or o is truth.collider]
    for verdict, of in (("true", live), ("pass", lambda o: o.kind == "pass"), ("distractor", lambda o: True)):
        hit = next((o for o in seen if of(o)), None)
        if hit is not None:
            return verdict, hit
    return "background", None


def episodes(frames: Iterable[int]) -> int:
    """Number of runs of consecutive frames in ``frames``."""
    frames = set(frames)
    return sum(f - 1 not in frames for f in frames)


def match_fields(fields: list[dict], truth, *, radius: float = DEFAULT_MATCH_RADIUS) -> list[dict]:
    """For each ground-truth object with a centre, the field that stands for it.

    Among the fields born while the object is on screen, the one with the largest peak
    response whose centre lies within ``radius`` px of the object's
    (:func:`centre_distance`, the matcher of the paper's metrics), else the
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
