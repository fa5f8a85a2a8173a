"""The scores of one model's run on one video against its ground truth, and per model over
all videos (the metrics of ``mlplc2 evaluate``; ``docs/evaluation.md``).

:class:`ModelRun`
    one model's output on one video, reduced to what scoring needs (fields and alarms per
    frame, targets per frame), in the ground truth's pixels by :meth:`ModelRun.in_pixels_of`.
object level (the paper's metrics; :func:`score_run`)
    per approaching object: detected or not (a field within the match radius of its centre,
    :func:`mlplc2.evaluation.match.centre_distance`), latency to the first field and to the
    first alarm, localisation error, fields created; false alarms (onsets and frames) that no
    approaching object explains (:func:`mlplc2.evaluation.match.alarm_explained`).
clip level (:func:`score_run`)
    a labelled clip's outcome: TP / FN (alarm before the collision frame or not), FP / TN, and
    the warning time.
warning metrics (:func:`score_warnings`, for truth that says which objects will hit:
:func:`warning_truth`)
    collision objects warned before contact (:func:`mlplc2.evaluation.match.nearest_object`), lead
    time, false warnings per cause (:func:`mlplc2.evaluation.match.warning_cause`) and their
    episodes, time-to-contact errors (RTE, MiD: :func:`mid_error`) and coverage,
    fragmentation; per labelled clip warned / missed / unplaced / false.
per model (:func:`summarise`, :func:`summarise_warnings`)
    the means, medians, rates and per-1000-frame counts of the tables.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field, replace
from typing import Any

from .match import CAUSES, alarm_explained, centre_distance, episodes, nearest_object, on_object, warning_cause
from .record import TargetRow
from .truth import ObjectTruth, VideoTruth

__all__ = ["ModelRun", "score_run", "score_warnings", "warning_truth", "summarise", "summarise_warnings",
           "TTC_BINS", "MIN_TTC_WIDTH", "FRAGMENT_SHARE", "EARLY_S", "LATE_S", "SEEN_S", "HIDDEN_SHARE",
           "MID_INTERVAL_S", "LAPSE_S", "mid_error", "unseen", "hidden_frames"]

#: Bins of the true time to contact (s) for the TTC errors (lower bound inclusive).
TTC_BINS = ((0.0, 1.0), (1.0, 3.0), (3.0, 6.0))
#: TTC coverage counts the frames in which a collision object is at least this wide (px).
MIN_TTC_WIDTH = 16.0
#: Fragmentation counts the frames in which a collision object is at most this share of the frame's
#: larger side wide: beyond it the object covers most of the view, and the boxes at its edges (the
#: ground at its foot, the sky beside it) lie "on" it by the match radius.
FRAGMENT_SHARE = 0.5
#: Real clips: a warning earlier than the danger onset minus this (s) is false.
EARLY_S = 0.5
#: A warning on a collision object up to this long (s) after its contact is neither true nor false.
LATE_S = 0.5
#: A 3-D collision object is scored only when it is seen in at least half of the frames of its last
#: ``SEEN_S`` seconds before contact: in view (a track row) and not hidden behind nearer objects
#: (``HIDDEN_SHARE``). A camera that turned away from it (a pan, a tilt) or a vehicle in front of it
#: leaves nothing to warn of, whatever the model (docs/evaluation.md, "Warning metrics").
SEEN_S = 1.0
#: A 3-D object is hidden in a frame when at least this share of its image box (within the image) lies
#: in the boxes of nearer 3-D objects (depth from the truth: physical width over image width).
HIDDEN_SHARE = 0.75
#: A warned collision object's warning lapsed when no warning stood for it for at least this long (s) between its
#: first warning and its contact (``warning_gap_s``): a blip that a robot cannot act on, then silence.
LAPSE_S = 0.2
#: MiD (the TSTTC benchmark's motion-in-depth error) compares the depth ratio over this interval (s):
#: TSTTC's frame interval (10 fps).
MID_INTERVAL_S = 0.1


def mid_error(true_ttc: float, est_ttc: float, interval: float = MID_INTERVAL_S) -> float:
    """MiD of one time-to-contact estimate, as the TSTTC benchmark computes it: the depth ratio
    over ``interval`` implied by a TTC, ``s = ttc / (ttc + interval)``, compared in log space,
    ``|ln s(est) - ln s(true)| x 10^4`` (positive TTCs)."""
    return abs(math.log(est_ttc / (est_ttc + interval)) - math.log(true_ttc / (true_ttc + interval))) * 1e4


@dataclass
class ModelRun:
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

    def fields_at(self, f: int) -> list[tuple[int, float, float, bool]] | tuple:
        """``(field id, x, y, collision)`` of every field in frame ``f``."""
        return self.frame_fields.get(f, ())

    def alarms_at(self, f: int) -> list[tuple]:
        """``(field id, x, y)`` of every field in alarm in frame ``f``; for a model that does not localise,
        ``(None, None, None)`` for the frame's alarm."""
        if self.localises:
            return [(fid, x, y) for fid, x, y, c in self.frame_fields.get(f, ()) if c]
        return [(None, None, None)] if self.frame_alarm.get(f) else []

    def warnings_at(self, f: int) -> list[tuple]:
        """``(key, x, y)`` of every warning in frame ``f`` (key: target or field id; x None: a global alarm):
        its targets' warnings (a model with targets), else its alarms (:meth:`alarms_at`)."""
        if self.has_targets:
            return [(t.id, t.x, t.y) for t in self.frame_targets.get(f, ()) if t.warning]
        return self.alarms_at(f)

    def in_pixels_of(self, truth: VideoTruth) -> "ModelRun":
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


# ---------------------------------------------------------------------------
# object and clip level (the paper's metrics)
# ---------------------------------------------------------------------------
def score_run(run: ModelRun, truth: VideoTruth, *, radius: float, tail: int) -> tuple[dict, list[dict]]:
    """The object- and clip-level scores of one run: its row of the per-video table and one row
    per approaching object in the processed frames (those outside are counted, not scored)."""
    run = run.in_pixels_of(truth)
    first, last = run.start, run.start + run.n_frames  # processed frames [first, last)
    births = _births(run)
    approaching = [a for a in (_with_approach(o) for o in truth.objects if o.approaching) if a is not None]
    objects = []
    outside = 0
    for o in approaching:
        w0, w1 = max(o.approach[0], first), min(o.approach[1] + tail, last)
        if w0 >= w1:
            outside += 1  # outside the processed frames: not scored, counted
            continue
        objects.append(_score_object(run, truth, o, w0, w1, births, radius=radius))
    alarm_frames = sorted(f for f, a in run.frame_alarm.items() if a)
    fa_events, fa_frames = _false_alarms(run, approaching, radius=radius, tail=tail)
    if not truth.object_level:  # a clip-level label only: no object-level false alarms
        fa_events = fa_frames = None
    outcome, warning_s = _clip_outcome(truth, alarm_frames, run.fps)
    localises = run.localises
    video = {"model": run.label, "video": truth.key, "source": run.source, "frames": run.n_frames,
             "seconds": round(run.n_frames / run.fps, 6), "localises": localises,
             "places_warnings": bool(localises or run.has_targets),
             "complete": run.incomplete is None, "object_level": truth.object_level,
             "fields": len(run.fields) if localises or run.fields else None,
             "objects": len(objects), "objects_outside": outside,
             "detected": sum(1 for r in objects if r["detected"]),
             "alarmed": sum(1 for r in objects if r["alarmed"]),
             "false_alarms": fa_events, "false_alarm_frames": fa_frames,
             "first_alarm_frame": alarm_frames[0] if alarm_frames else None,
             "label": truth.label, "collision_frame": truth.collision_frame, "outcome": outcome,
             "warning_s": warning_s}
    return video, objects


def _births(run: ModelRun) -> dict[int, tuple[int, float, float]]:
    """Field id -> (frame, x, y) of its first row."""
    births: dict[int, tuple[int, float, float]] = {}
    for f in sorted(run.frame_fields):
        for fid, x, y, _ in run.fields_at(f):
            births.setdefault(fid, (f, x, y))
    return births


def _score_object(run: ModelRun, truth: VideoTruth, o: ObjectTruth, w0: int, w1: int,
                  births: dict[int, tuple[int, float, float]], *, radius: float) -> dict:
    """One approaching object scored over frames ``[w0, w1)``: the first field within ``radius`` of
    its centre (a model that localises), the localisation errors, the fields born on it, the first
    alarm on it."""
    last = run.start + run.n_frames
    a0 = o.approach[0]
    rec = {"model": run.label, "video": truth.key, "object": o.id, "onset": a0,
           "approach": list(o.approach), "detected": None, "detect_frame": None, "latency_field": None,
           "field": None, "error_detect": None, "error_life": None, "fields": None,
           "alarmed": False, "alarm_frame": None, "latency_alarm": None}
    if run.localises:
        rec["detected"] = False
        for f in range(w0, w1):
            near = [(centre_distance(x, y, o, f), fid) for fid, x, y, _ in run.fields_at(f)]
            near = [n for n in near if n[0] <= radius]
            if near:
                d, fid = min(near)
                rec.update(detected=True, detect_frame=f, latency_field=f - a0, field=fid,
                           error_detect=round(d, 2))
                break
        if rec["detected"]:
            errs = [centre_distance(x, y, o, f) for f in range(rec["detect_frame"], min(o.life_end(), last))
                    for fid, x, y, _ in run.fields_at(f) if fid == rec["field"]]
            rec["error_life"] = round(sum(errs) / len(errs), 2) if errs else None
        rec["fields"] = sum(1 for b, x, y in births.values()
                            if w0 <= b < w1 and centre_distance(x, y, o, b) <= radius)
    for f in range(w0, w1):
        if any(x is None or centre_distance(x, y, o, f) <= radius for _, x, y in run.alarms_at(f)):
            rec.update(alarmed=True, alarm_frame=f, latency_alarm=f - a0)
            break
    return rec


def _false_alarms(run: ModelRun, approaching: list[ObjectTruth], *, radius: float,
                  tail: int) -> tuple[int, int]:
    """False alarms (onsets, frames): alarm onsets (per field for localising models, per frame
    signal otherwise) that no approaching object explains (:func:`~mlplc2.evaluation.match.alarm_explained`)."""
    fa_events = fa_frames = 0
    prev: set = set()   # the alarms of the frame before
    for f in range(run.start, run.start + run.n_frames):
        now = run.alarms_at(f)
        bad = [fid for fid, x, y in now if not alarm_explained(f, approaching, x, y, radius=radius, tail=tail)]
        fa_frames += bool(bad)
        fa_events += sum(fid not in prev for fid in bad)
        prev = {fid for fid, _, _ in now}
    return fa_events, fa_frames


def _clip_outcome(truth: VideoTruth, alarm_frames: list[int], fps: float) -> tuple[str | None, float | None]:
    """A labelled clip's outcome (TP, FN, FP, TN; None without a label) and, for a TP with a
    collision frame, the field alarm's lead (s; ``warning_s``, a historical name: not the targets' warning)."""
    if truth.label is None:
        return None, None
    if truth.label != "collision":
        return ("FP" if alarm_frames else "TN"), None
    cf = truth.collision_frame
    before = [f for f in alarm_frames if cf is None or f < cf]
    if not before:
        return "FN", None
    return "TP", (round((cf - before[0]) / fps, 4) if cf is not None else None)


# ---------------------------------------------------------------------------
# warning metrics (3-D truth with kinds, and labelled clips)
# ---------------------------------------------------------------------------
def warning_truth(truth: VideoTruth) -> bool:
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


@dataclass(frozen=True)
class _WarningRules:
    """What decides the warnings of one run on one video: the frames scored ``[first, end)`` (a
    collision clip: up to its contact), the collision objects (``colliders``, a clip's
    ``collider`` among them; ``blind``: its position is unknown), ``late`` (frames after a contact
    that are neither true nor false), ``early_before`` (a labelled clip: a warning before this
    frame is false) and the match ``radius``."""

    first: int
    last: int
    end: int
    fps: float
    clip: bool
    collider: ObjectTruth | None
    blind: bool
    colliders: list[ObjectTruth]
    late: int
    early_before: float | None
    radius: float
    hidden: dict[Any, set[int]]

    def nearest(self, x: float, y: float, f: int, truth: VideoTruth) -> ObjectTruth | None:
        """The object a warning or target at (x, y) stands for in frame ``f``
        (:func:`mlplc2.evaluation.match.nearest_object`; not one hidden behind nearer objects then)."""
        return nearest_object(x, y, f, truth, self.radius, self.hidden)


def _warning_rules(run: ModelRun, truth: VideoTruth, radius: float) -> _WarningRules:
    first, last = run.start, run.start + run.n_frames
    fps = run.fps
    clip = truth.label is not None
    collider = truth.collider
    if clip and truth.label == "collision" and collider is None:  # no track: no warning can be placed on it
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
    hidden = {o.id: hidden_frames(o, truth) for o in truth.objects}
    return _WarningRules(first, last, end, fps, clip, collider, blind, colliders, late, early_before, radius, hidden)


def score_warnings(run: ModelRun, truth: VideoTruth, *, radius: float) -> tuple[dict, list[dict]]:
    """The warning metrics of one run (``docs/evaluation.md``, "Warning metrics").

    A model's warning is its targets' warnings (models with targets), else its alarm: the fields
    in alarm of a model that localises, the frame's alarm of one that does not. Collision objects
    (``kind == "collision"``, a clip's collider) are warned when a warning stands for them (lies
    nearest them, :func:`mlplc2.evaluation.match.nearest_object`) before contact; every other warning is false, with its
    cause (:func:`mlplc2.evaluation.match.warning_cause`), except within ``LATE_S`` after a contact, on
    the object that hit. On a labelled clip, frames from the contact on are not scored, and a
    warning before the danger onset minus ``EARLY_S`` is false ("early"), as is one off the
    collider ("elsewhere"). On a collision clip without the collider's track no warning can be placed
    on the collider: a warning there is ``unplaced`` (its own outcome, never ``warned`` nor false). A
    collision object none of whose frames before contact were processed (an interrupted or partial
    run) is not scored, only counted (``collision_objects_outside``); nor is a 3-D one out of view
    in most of its last :data:`SEEN_S` before contact (``collision_objects_unseen``, :func:`unseen`).
    """
    run = run.in_pixels_of(truth)
    rules = _warning_rules(run, truth, radius)
    objects = []
    outside = 0
    hidden = [o for o in rules.colliders if o is not rules.collider and unseen(o, rules.fps, truth)]
    for o in rules.colliders:
        if o in hidden:
            continue
        rec = _score_collider(run, truth, o, rules)
        if rec is None:
            outside += 1
        else:
            objects.append(rec)
    false_frames, episodes_by = _false_warnings(run, truth, rules)
    all_false = set().union(*false_frames.values()) if false_frames else set()
    outcome = None
    if rules.clip:
        hit = truth.label == "collision"
        warned = any(r["warned"] for r in objects)
        unplaced = any(r["unplaced"] for r in objects)
        outcome = {"label": truth.label, "warned": warned if hit else None,
                   "missed": (not warned and not unplaced) if hit else None, "false": bool(all_false),
                   "lead_s": next((r["lead_s"] for r in objects if r["warned"]), None),
                   "unplaced": unplaced if hit else None,
                   "unplaced_lead_s": next((r["unplaced_lead_s"] for r in objects if r["unplaced"]), None),
                   "alarm_lead_s": next((r["alarm_lead_s"] for r in objects if r["alarm_frame"] is not None), None)}
    video = {"model": run.label, "video": truth.key, "frames_scored": max(rules.end - rules.first, 0),
             "clip": rules.clip, "collision_objects_outside": outside, "collision_objects_unseen": len(hidden),
             "false_frames": len(all_false), "false_episodes": sum(episodes_by.values()),
             "false_frames_by_cause": {c: len(v) for c, v in sorted(false_frames.items())},
             "false_episodes_by_cause": dict(sorted(episodes_by.items())), "outcome": outcome}
    return video, objects


def unseen(o: ObjectTruth, fps: float, video: VideoTruth | None = None) -> bool:
    """Whether the 3-D collision object ``o`` is not seen in more than half of the frames of its last
    :data:`SEEN_S` before contact: out of view (no track row; a camera that turned away from it) or,
    given its ``video``, hidden behind nearer objects (:func:`hidden_frames`), so no warning can be
    asked of it. False without a track or a contact."""
    cf = o.contact_frame
    if not o.track or cf is None:
        return False
    window = range(max(int(math.ceil(cf - SEEN_S * fps)), 0), int(math.ceil(cf)))       # true TTC <= SEEN_S
    if not window:
        return False
    seen = {p.frame for p in o.track} - (hidden_frames(o, video) if video is not None else set())
    return sum(f in seen for f in window) < 0.5 * len(window)


def _depth_box(o: ObjectTruth, p) -> tuple[float, tuple[float, float, float, float]] | None:
    """A 3-D track row's depth up to the camera's focal length (physical width over image width: the
    larger side, as a turned plane only shrinks) and image box; None without either (a 2-D or
    labelled object, a row whose object is partly behind the camera)."""
    width_m = o.extra.get("width_m")
    if not isinstance(width_m, (int, float)) or p.width is None or p.height is None or max(p.width, p.height) <= 0:
        return None
    w, h = p.width / 2.0, p.height / 2.0
    return width_m / max(p.width, p.height), (p.x - w, p.x + w, p.y - h, p.y + h)


def _covered_share(box, covers) -> float:
    """The share of ``box`` (x0, x1, y0, y1) inside the union of the boxes ``covers`` (exact: the
    rectangles cut on the grid of their edges)."""
    x0, x1, y0, y1 = box
    area = (x1 - x0) * (y1 - y0)
    covers = [(max(a, x0), min(b, x1), max(c, y0), min(d, y1)) for a, b, c, d in covers]
    covers = [c for c in covers if c[0] < c[1] and c[2] < c[3]]
    if area <= 0 or not covers:
        return 0.0
    xs = sorted({v for c in covers for v in c[:2]})
    ys = sorted({v for c in covers for v in c[2:]})
    inside = sum((xa - xb) * (ya - yb) for xb, xa in zip(xs, xs[1:]) for yb, ya in zip(ys, ys[1:])
                 if any(c[0] <= xb and xa <= c[1] and c[2] <= yb and ya <= c[3] for c in covers))
    return inside / area


def hidden_frames(o: ObjectTruth, video: VideoTruth) -> set[int]:
    """The frames in which the 3-D object ``o`` is hidden: at least :data:`HIDDEN_SHARE` of its image box
    (within the image when its size is known) lies in the boxes of the nearer 3-D objects of ``video``
    (:func:`_depth_box`). Empty for objects without a physical width (2-D stimuli, labelled clips)."""
    others = [(v, {p.frame: p for p in v.track}) for v in video.objects if v is not o and v.track]
    hidden = set()
    for p in o.track:
        own = _depth_box(o, p)
        if own is None:
            continue
        depth, box = own
        if video.size:
            box = (max(box[0], 0.0), min(box[1], float(video.size[0])),
                   max(box[2], 0.0), min(box[3], float(video.size[1])))
        covers = [db[1] for v, rows in others if p.frame in rows
                  for db in [_depth_box(v, rows[p.frame])] if db is not None and db[0] < depth]
        if covers and _covered_share(box, covers) >= HIDDEN_SHARE:
            hidden.add(p.frame)
    return hidden


def _score_collider(run: ModelRun, truth: VideoTruth, o: ObjectTruth, rules: _WarningRules) -> dict | None:
    """One collision object: its first warning before contact, the targets (fields) on it while in
    view (fragmentation) and its time-to-contact estimates; None when none of its frames before
    contact were processed."""
    fps, radius, collider = rules.fps, rules.radius, rules.collider
    cf = o.contact_frame if o.contact_frame is not None else (truth.contact_frame if o is collider else None)
    start = max(rules.first, o.track[0].frame) if o.track and o is not collider else rules.first
    stop = min(rules.end, int(math.ceil(cf)) if cf is not None else rules.last)
    if start >= stop:
        return None
    rec = {"model": run.label, "video": truth.key, "object": o.id, "kind": "collision",
           "contact_frame": cf, "warned": False, "warning_frame": None, "lead_s": None,
           "ttc_at_warning_s": None, "warning_distance_px": None, "unplaced": False, "unplaced_frame": None,
           "unplaced_lead_s": None, "alarm_frame": None, "alarm_lead_s": None, "warning_kept": None,
           "warning_gap_s": None, "targets": None, "ttc_frames": 0, "ttc_estimated": 0, "ttc_errors": []}
    ids, held = set(), None   # held: the target (field) that stood for the object last (_standing)
    blind = rules.blind and o is collider   # its position is unknown: no warning can be placed on it
    for f in range(start, stop):
        if blind and not rec["unplaced"] and (rules.early_before is None or f >= rules.early_before) \
                and run.warnings_at(f):
            rec.update(unplaced=True, unplaced_frame=f,
                       unplaced_lead_s=None if cf is None else round((cf - f) / fps, 4))
        if not blind and not rec["warned"] and (rules.early_before is None or f >= rules.early_before):
            for key, x, y in run.warnings_at(f):
                if x is None or rules.nearest(x, y, f, truth) is o:
                    c = o.center_at(f)
                    true = o.ttc_at(f, fps)
                    rec.update(warned=True, warning_frame=f,
                               lead_s=None if cf is None else round((cf - f) / fps, 4),
                               ttc_at_warning_s=None if true is None else round(true, 4),
                               warning_distance_px=None if x is None or c is None else round(
                                   math.hypot(x - c[0], y - c[1]), 2))
                    break
        if run.has_targets and run.localises and not blind and rec["alarm_frame"] is None \
                and (rules.early_before is None or f >= rules.early_before) \
                and any(rules.nearest(x, y, f, truth) is o for _, x, y in run.alarms_at(f)):
            # the paper's field alarm on the object (what the targets are built on), for comparison
            rec.update(alarm_frame=f, alarm_lead_s=None if cf is None else round((cf - f) / fps, 4))
        # fragmentation and time to contact: the targets (fields) on the object while in view
        if o.track and not o.in_track(f) and o is not collider:
            continue
        width = o.width_at(f)
        # fragmentation counts while the object covers at most half the view: in the last frames
        # before contact every box at its edges lies on it (FRAGMENT_SHARE)
        fits = width is None or truth.size is None or width <= FRAGMENT_SHARE * max(truth.size)
        if run.has_targets:
            # the targets this object stands for: each target counts for the one object it lies
            # nearest (a target on a neighbour within the radius is the neighbour's, not a fragment)
            on = [t for t in run.frame_targets.get(f, ()) if rules.nearest(t.x, t.y, f, truth) is o]
            if fits and on:
                held = _standing([(t.id, t.x, t.y) for t in on], held, o.center_at(f))
                ids.add(held)
            # the true time to contact as it is recorded (4 decimals): a frame a hair before the contact
            # (under 0.05 ms) records 0, which no relative error is measured against
            true = o.ttc_at(f, fps)
            true = None if true is None else round(true, 4)
            if o is not collider and width is not None and width >= MIN_TTC_WIDTH and true is not None \
                    and true > 0:
                rec["ttc_frames"] += 1
                est = [t for t in on if t.ttc_s is not None and t.ttc_s > 0]
                if est:
                    c = o.center_at(f)
                    t = min(est, key=lambda t: math.hypot(t.x - c[0], t.y - c[1]))
                    rec["ttc_estimated"] += 1
                    rec["ttc_errors"].append((true, round(t.ttc_s, 4)))
        elif run.localises and fits:
            on = [(fid, x, y) for fid, x, y, _ in run.fields_at(f) if rules.nearest(x, y, f, truth) is o]
            if on:
                held = _standing(on, held, o.center_at(f))
                ids.add(held)
    rec["targets"] = len(ids) if (run.has_targets or run.localises) else None
    if rec["warned"] and cf is not None:
        rec["warning_kept"], rec["warning_gap_s"] = _kept(run, truth, o, rules, rec["warning_frame"], stop)
    return rec


def _standing(on: list[tuple], held, centre) -> object:
    """The one target (field) that stands for an object in a frame, of those ``on`` it ((id, x, y), each lying
    nearest it within the match radius): the one that stood for it last (``held``) while it still lies on it,
    else the one nearest its ``centre`` (CLEAR MOT's correspondence, Bernardin & Stiefelhagen 2008). Its targets
    (fragmentation) are the ids that stood for it: a second target beside its own, or one of the background that
    passes within the match radius while its own stands, is none of them."""
    if any(i == held for i, _, _ in on):
        return held
    if centre is None:
        return on[0][0]
    return min(on, key=lambda t: math.hypot(t[1] - centre[0], t[2] - centre[1]))[0]


def _kept(run: ModelRun, truth: VideoTruth, o: ObjectTruth, rules: _WarningRules, first: int,
          stop: int) -> tuple[float, float]:
    """(share, longest gap in s) of the frames from a collision object's first warning ``first`` up to its
    contact (``stop``, exclusive) in which a warning stands for it: lies nearest it, or goes on without a break
    from one that did within ``LATE_S`` before its contact (its box past the view: the rule of
    :func:`_false_warnings`)."""
    keys: set = set()
    on = gap = longest = 0
    for f in range(first, stop):
        near = o.contact_frame is not None and f >= o.contact_frame - rules.late
        keys = {key for key, x, y in run.warnings_at(f)
                if x is None or (near and key in keys) or rules.nearest(x, y, f, truth) is o}
        on += bool(keys)
        gap = 0 if keys else gap + 1
        longest = max(longest, gap)
    n = stop - first
    return (round(on / n, 4), round(longest / rules.fps, 4)) if n > 0 else (1.0, 0.0)


def _false_warnings(run: ModelRun, truth: VideoTruth,
                    rules: _WarningRules) -> tuple[dict[str, set[int]], dict[str, int]]:
    """False warnings: their frames per cause, and their episodes per cause (runs of consecutive
    frames in which one target gives a false warning, each counted once, for the cause of its first
    frame: a warning that slides from a passing object onto the background is one episode). A target's warning that was on a collision object and goes on without a
    break within ``LATE_S`` before that object's contact, and on within ``LATE_S`` after it, is the
    object's wherever its box has grown (past the view, its centre off the object): the mirror of
    :func:`_just_hit`, which places a warning after the contact by the object's position at the
    contact (where a 3-D object's projection may already have left the view)."""
    false_frames: dict[str, set[int]] = {}
    runs: dict = {}         # target key -> {frame: cause} of its false warnings
    held: dict = {}         # target key -> the collision object its unbroken warning was on
    for f in range(rules.first, rules.end):
        now = {}
        for key, x, y in run.warnings_at(f):
            o = held.get(key)
            if o is not None and o.contact_frame is not None \
                    and o.contact_frame - rules.late <= f <= o.contact_frame + rules.late:
                now[key] = o                # the warning of the object about to hit (or that hit), its box past the view
                continue
            cause = _false_cause(x, y, f, truth, rules)
            if cause is not None:
                false_frames.setdefault(cause, set()).add(f)
                runs.setdefault(key, {}).setdefault(f, cause)
            elif x is not None:
                o = rules.nearest(x, y, f, truth)
                if any(o is c for c in rules.colliders):
                    now[key] = o
        held = now
    episodes_by: dict[str, int] = {}
    for causes in runs.values():
        for f, cause in causes.items():
            if f - 1 not in causes:         # an episode's first frame
                episodes_by[cause] = episodes_by.get(cause, 0) + 1
    return false_frames, episodes_by


def _false_cause(x: float | None, y: float | None, f: int, truth: VideoTruth, rules: _WarningRules) -> str | None:
    """The cause of a false warning at (x, y) in frame ``f``; None when it is not false."""
    if _just_hit(x, y, f, rules):
        return None
    if rules.early_before is not None and f < rules.early_before:
        return "early"
    if rules.blind:
        return None                     # a collision clip without a track: unplaced, neither true nor false
    verdict, _ = warning_cause(x, y, f, truth, radius=rules.radius, tail=rules.late, hidden=rules.hidden)
    if verdict == "true":
        return None
    return verdict if not rules.clip else "elsewhere"


def _just_hit(x: float | None, y: float | None, f: int, rules: _WarningRules) -> bool:
    """A warning up to LATE_S after a collision object's contact, where it last was, or anywhere
    from a frame before its contact while it fills the view (:func:`_fills_view`)."""
    for o in rules.colliders:
        cf = o.contact_frame
        if cf is None or not cf - 1 <= f <= cf + rules.late:
            continue
        if _fills_view(o, min(f, cf)) or (cf <= f and (x is None or on_object(x, y, o, min(f, cf), rules.radius))):
            return True
    return False


def _fills_view(obj: ObjectTruth, frame: float) -> bool:
    """Whether a tracked object's size at ``frame`` is not finite: a corner of it lies at or
    behind the camera plane (3-D truth, :mod:`mlplc2.stimuli.world`; a clip's label without a size
    is not), so its image spreads over the view and has no box: a collision object does so in the
    last frame before its contact."""
    p = obj.point_at(frame) if obj.track else None
    return p is not None and p.width is None and p.ttc_s is not None     # ttc_s: 3-D truth, not a label


# ---------------------------------------------------------------------------
# per model
# ---------------------------------------------------------------------------
def summarise_warnings(label: str, wvideos: list[dict], wobjects: list[dict]) -> dict:
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
        "collision_objects_unseen": sum(v.get("collision_objects_unseen", 0) for v in synth),
        "warned_rate": round(len(warned) / len(sobjs), 4) if sobjs else None,
        "lead_median_s": _median(o["lead_s"] for o in warned),
        "lead_p10_s": _quantile([o["lead_s"] for o in warned], 0.1),
        "ttc_at_warning_median_s": _median(o["ttc_at_warning_s"] for o in warned),
        "warning_distance_median_px": _median(o["warning_distance_px"] for o in warned),
        "warning_kept_median": _median(o["warning_kept"] for o in warned if o.get("warning_kept") is not None),
        "warnings_lapsed": sum(1 for o in warned if (o.get("warning_gap_s") or 0.0) >= LAPSE_S - 1e-9),
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
             clips_unplaced=sum(bool(v["outcome"]["unplaced"]) for v in cc),
             clips_false=sum(bool(v["outcome"]["false"]) for v in clips),
             clip_lead_median_s=_median(v["outcome"]["lead_s"] for v in cc if v["outcome"]["warned"]),
             clips_later_than_alarm=sum(_later_than_alarm(v["outcome"]) for v in cc))
    return s


def _later_than_alarm(outcome: dict) -> bool:
    """Whether a clip's warning on the collider came later than the field alarm on it, or not at all."""
    alarm = outcome.get("alarm_lead_s")
    return alarm is not None and (outcome["lead_s"] is None or outcome["lead_s"] < alarm)


def summarise(label: str, videos: list[dict], objects: list[dict]) -> dict:
    """Per model: the object-level metrics, false alarms and the clip-level classification."""
    vids = [v for v in videos if v["model"] == label]
    objs = [o for o in objects if o["model"] == label]
    localises = any(v["localises"] for v in vids)
    places = any(v.get("places_warnings", v["localises"]) for v in vids)
    minutes = sum(v["seconds"] for v in vids) / 60.0
    obj_vids = [v for v in vids if v["object_level"]]  # false alarms: object-level truth only
    obj_minutes = sum(v["seconds"] for v in obj_vids) / 60.0
    s: dict[str, Any] = {"model": label, "videos": len(vids), "minutes": round(minutes, 4),
                         "localises": localises, "places_warnings": places, "objects": len(objs),
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

