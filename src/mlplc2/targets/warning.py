"""The warning rule of the target layer (``docs/targets.md``, steps 5-8): a track's time to
contact (:func:`~mlplc2.targets.contact.fit_contact`), its course against the heading
(:func:`course`), the warning (:func:`estimate`), the field alarm as evidence (:func:`alarm_warns`,
:func:`on_path`, :func:`keeps_bearing`) and the times to contact held or counted down
(:func:`held`, :func:`count_down`), and the vetoes the target layer applies after :func:`estimate`
(:func:`layer_vetoes`). Shared by every model with targets (the LPLC2 family and the
optical-flow baseline) through :class:`~mlplc2.targets.layer.TargetLayer`, which forms and follows
the tracks."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..camera import bearing
from .alignment import align
from .contact import fit_centre_course, fit_contact, fit_course
from .params import TargetParams
from .track import EPS as _EPS, MIN_POINTS, Target, Track

__all__ = ["estimate", "course", "alarm_warns", "fresh", "on_path", "keeps_bearing", "grew_alike", "drift", "cut_keeps_bearing", "cut_course", "holds", "off_path", "wide", "rises", "fleeting", "seed_course",
           "slow", "rising", "count_down", "confirmed", "anisotropic", "passed_by", "held", "spans_view", "fits", "exits", "flat", "relapse", "blind_until", "heading_grows", "tiny", "young", "alarm_holds", "layer_vetoes",
           "MIN_POINTS"]

def course(t: Track, heading: tuple[float, float], ttc: float, span: float,
           yaw: bool = False, centre: float | None = None, alarm: bool = False) -> tuple[float, float] | None:
    """The predicted miss of track ``t`` (:func:`fit_course`: right in its widths, down in its
    heights), ``ttc`` frames after its newest observation, against ``heading`` (px, this frame's
    pixels), from its last observations whose box was wholly inside the frame (``Track.inside``:
    a cut box gives neither the object's centre nor its size); None when they are too
    few for a fit over ``span`` clock units (:func:`fits`). The centres are the camera's
    stabilised ones (less its turn); with ``yaw`` (``TargetParams.course_yaw``) the horizontal ones
    keep the camera's horizontal turn (each frame's own pixels, :class:`Observation`): the course
    in the vehicle's axes, which turn with its path. ``centre`` (``TargetParams.course_centre``: the least growth
    over the points, ``centre_growth``; None: off): the course from the box's own expansion centre
    (:func:`fit_centre_course`) instead, where it is measured; with ``alarm`` (a field of the track in collision alarm
    this frame) the shorter of the two."""
    inside = list(t.inside) if t.inside else [q for q in t.history if not q.cut]
    if not fits(inside, span):
        return None
    ahead = ttc + (t.history[-1].frame - inside[-1].frame)
    xs = [q.x + q.ox for q in inside] if yaw else [q.x for q in inside]
    ys, widths = [q.y for q in inside], [q.width for q in inside]
    heights = [q.width if q.height is None else q.height for q in inside]
    own = None if centre is None else fit_centre_course(xs, ys, [q.log_scale for q in inside], widths, heights,
                                                          min_growth=centre)
    if own is not None and not alarm:        # the line is needed only without the expansion centre, or beside it
        return own
    timed = fit_course([q.frame for q in inside], xs, ys, widths, heading, ahead, heights=heights)
    if own is None or timed is None:
        return timed if own is None else own
    return own if math.hypot(*own) < math.hypot(*timed) else timed


def fits(obs, span: float) -> bool:
    """Whether observations ``obs`` (oldest first) are enough for a fit: at least :data:`MIN_POINTS`
    of them over at least ``span`` clock units (``TargetParams.min_frames`` - 1 frame intervals at
    ``nominal_fps``: :meth:`TargetParams.span`)."""
    return len(obs) >= MIN_POINTS and obs[-1].frame - obs[0].frame >= span - _EPS


def count_down(targets, elapsed: float) -> tuple[Target, ...]:
    """``targets`` held ``elapsed`` seconds (a repeated frame): each ``ttc_s`` counts down (and its
    ``ttc_age_s`` grows by as much); an estimate whose contact has passed becomes None and loses its
    warning; re-sorted by urgency."""
    out = []
    for t in targets:
        if t.ttc_s is not None:
            left = t.ttc_s - elapsed
            age = None if t.ttc_age_s is None else t.ttc_age_s + elapsed
            t = replace(t, ttc_s=left, ttc_age_s=age) if left > 0 else \
                replace(t, ttc_s=None, miss=None, warning=False, ttc_sigma_s=None, miss_xy=None, ttc_age_s=None)
        out.append(t)
    return tuple(sorted(out, key=Target.urgency))


def alarm_warns(t: Track, p: TargetParams, index: int, ttc: float | None, miss: float | None,
                heading: tuple[float, float] | None = None, shape: tuple[int, int] | None = None) -> bool:
    """The field alarm as evidence (``alarm_warns``; docs/targets.md, step 7): a target that owns an
    attention field in collision alarm this frame (the paper's fatal field, ``Params.alarm_threshold``)
    warns, unless its own measurement says otherwise: its box did not grow over its history
    (receding, static), its fit found no time to contact although its history is long enough
    (``min_frames``: no significant or no isotropic growth, as the ground or a wall beside the
    path), or it has a time to contact beyond ``horizon_s`` or a course beyond ``max_miss``
    (passing). No ``max_ttc_sigma`` needed. Without a course (its fit too short, or its box cut
    by the border) the alarm warns only for a box wholly inside a frame of ``shape`` (h, w) that
    lies on the path now (:func:`on_path`) or keeps its bearing while it grows
    (:func:`keeps_bearing`; a warning that begins so, on a box whose history grew alike in both directions,
    ``bearing_isotropic``, :func:`grew_alike`), against ``heading`` (px): the field alarm alone cannot tell an object
    that will pass beside the camera (a roadside wall, a passing car, the ground) from one that hits. With
    ``alarm_onset_miss``, an alarm past its first frame in a row begins a warning only on a course within
    ``onset_miss`` (:func:`wide`)."""
    if not p.alarm_warns or t.last_alarm != index:
        return False
    if len(t.history) > 1 and t.history[-1].log_scale - t.history[0].log_scale <= 0:
        return False
    if ttc is None and fits(t.history, t.fit_span):   # the fit's "no"
        return False
    if ttc is not None and ttc > p.horizon_s:
        return False
    if miss is not None:
        if p.alarm_onset_miss and not t.warned and wide(p, miss) \
                and (t.alarm_courses > 0 if p.alarm_onset_course else t.alarm_run > 1):
            return False
        return miss <= p.max_miss
    if heading is None or shape is None or t.cut(shape, p.border) or t.grounded:
        return False
    return on_path(t, p, heading) or (keeps_bearing(t, heading, p.bearing_drift)
                                      and (t.warned or not p.bearing_isotropic or grew_alike(t, p)))


def on_path(t: Track, p: TargetParams, heading: tuple[float, float]) -> bool:
    """Whether track ``t``'s box lies on the camera's path now: its centre's offset from ``heading``
    (px), horizontally in its widths and vertically in its heights (the units of the course's miss),
    is at most ``max_miss``: the miss of an object that comes straight on from where it is."""
    return math.hypot((t.cx - heading[0]) / max(t.w, 1.0), (t.cy - heading[1]) / max(t.h, 1.0)) <= p.max_miss


#: :func:`keeps_bearing`: the least drift of the static world (px) that a box's jitter cannot fake
MIN_DRIFT_PX = 2.0
#: :func:`grew_alike`: the log-anisotropy (``log(ky / kx)``) one frame's image alignment gives a box that grows
#: alike in both directions (its noise: the young tracks of the benchmark's colliders that began a warning so
#: gained 0.00-0.04; docs/history.md, "A bearing kept by a box that stretches")
SKEW_NOISE = 0.05


def grew_alike(t: Track, p: TargetParams) -> bool:
    """``bearing_isotropic`` (docs/history.md, "A bearing kept by a box that stretches"): whether track ``t``'s box
    grew alike in both directions over its history, as an approaching object's does: the log-anisotropy it gained at
    most ``max_anisotropy`` times its log-growth plus :data:`SKEW_NOISE` (the growth test of every seed,
    :meth:`~mlplc2.targets.layer.TargetLayer._grows`, with the noise of one frame's alignment). A box over the
    ground, over a wall along the path or over the gap beside a passing object stretches along one axis, and its
    centre, held by the edges it lies between, drifts as little as an object on a collision course: its
    :func:`keeps_bearing` says nothing. True with fewer than two observations (the seed's own alignment is judged by
    :func:`anisotropic`)."""
    if len(t.history) < 2:
        return True
    q0, q1 = t.history[0], t.history[-1]
    return abs(q1.anisotropy - q0.anisotropy) <= p.max_anisotropy * (q1.log_scale - q0.log_scale) + SKEW_NOISE


def keeps_bearing(t: Track, heading: tuple[float, float], fraction: float) -> bool:
    """Whether track ``t`` keeps its bearing while it grows, as an object on a collision course
    does, over its history (two observations at least; on its first frame, the alarm seed's
    alignment against the frame ``change_frames`` before, ``Track.seed_move``): the static world (and an object that
    will pass) expands about the heading (the focus of expansion of a camera that does not turn),
    so its centre drifts away from ``heading`` (px) by its offset times the growth, ``r0 (S - 1)``,
    while the centre of an object on a collision course stays put. True when the static world's
    drift is at least ``MIN_DRIFT_PX`` and the box's is at most ``fraction`` of it (``TargetParams.bearing_drift``:
    0 an object on a collision course, 1 the static world). The
    centres are the observations' (less the camera's turn, :class:`Observation`)."""
    ratio = drift(t, heading)
    return ratio is not None and ratio <= fraction


def drift(t: Track, heading: tuple[float, float], *, away: bool = False) -> float | None:
    """How far track ``t``'s centre drifted away from ``heading`` (px) over its history, as a fraction
    of the static world's drift over the same growth, ``r0 (S - 1)`` (0: it keeps its bearing, as an
    object on a collision course; 1: the static world); on its first frame, from the alarm seed's
    alignment (``Track.seed_move``). None when the static world's drift is under ``MIN_DRIFT_PX``
    (a box near the heading, or one that did not grow: the ratio says nothing) or nothing is known;
    with ``away``, a box whose centre moved away from the heading by more than ``MIN_DRIFT_PX`` (more
    than its jitter can fake) while the static world there would drift less (it began at the
    heading) gets the ratio over ``MIN_DRIFT_PX``: more than the static world's drift, > 1."""
    if len(t.history) >= 2:
        q0, q1 = t.history[0], t.history[-1]
        x0, y0, x1, y1, growth = q0.x, q0.y, q1.x, q1.y, q1.log_scale - q0.log_scale
    elif t.seed_move is not None:          # its first frame: the seed's own alignment
        dx, dy, growth = t.seed_move
        x1, y1 = t.cx, t.cy
        x0, y0 = x1 - dx, y1 - dy
    else:
        return None
    r0 = math.hypot(x0 - heading[0], y0 - heading[1])
    r1 = math.hypot(x1 - heading[0], y1 - heading[1])
    static = r0 * math.expm1(growth)
    if static < MIN_DRIFT_PX:
        return (r1 - r0) / MIN_DRIFT_PX if away and r1 - r0 > MIN_DRIFT_PX else None
    return (r1 - r0) / static


def cut_keeps_bearing(t: Track, p: TargetParams, ttc: float | None, heading: tuple[float, float]) -> bool:
    """``cut_drift`` (docs/history.md, "Objects missed"): whether track ``t``, whose box is cut by the
    border, may begin its fit's warning under ``cut_onset_s`` because it keeps its bearing while it
    grows: a time to contact this frame, and its centre drifted away from ``heading`` (px) by at most
    ``cut_drift`` of the static world's drift (:func:`drift`; unknown: no). The static world beside the
    path sweeps out of view through the border expanding about the heading; an object on a collision
    course near the border does not."""
    if p.cut_drift <= 0 or ttc is None:
        return False
    ratio = drift(t, heading)
    return ratio is not None and ratio <= p.cut_drift


def cut_course(t: Track, p: TargetParams, ttc: float | None, heading: tuple[float, float],
               shape: tuple[int, int]) -> bool:
    """``cut_course`` (docs/history.md, "Objects missed", session 12): whether track ``t``, whose box is cut
    by the border of a frame of ``shape`` (h, w) and so has no course (:func:`course` takes only the
    boxes wholly inside), stands on a collision course because it keeps its bearing while it grows: a time
    to contact this frame, and its centre drifted away from ``heading`` (px) by at most ``cut_course_drift``
    of the static world's drift (:func:`drift`; unknown: no)."""
    if not p.cut_course or ttc is None or not t.cut(shape, p.border):
        return False
    ratio = drift(t, heading)
    return ratio is not None and ratio <= p.cut_course_drift


def holds(t: Track, heading: tuple[float, float]) -> bool:
    """Whether track ``t``'s box holds ``heading`` (px): the camera's path runs through it now."""
    return abs(t.cx - heading[0]) <= t.w / 2.0 and abs(t.cy - heading[1]) <= t.h / 2.0


def off_path(t: Track, p: TargetParams, index: int, heading: tuple[float, float] | None, *,
             steady: bool = False, miss: float | None = None) -> bool:
    """``path_drift`` (docs/history.md, "A warning that begins off the path"): whether a warning that
    would begin this frame on track ``t`` is the static world's, so does not begin: the camera
    translates (``heading``: the measured heading, px; None: none measured, no test), no field of
    ``t`` is in collision alarm this frame (the field alarm is evidence of its own, issue 22 item 4),
    its box does not hold the heading (:func:`holds`) and its centre drifts away from the heading by
    more than ``path_drift`` of the static world's drift (:func:`drift`), or, where the static world
    would barely drift (a box that began at the heading), by more than ``MIN_DRIFT_PX``: the static
    world beside the path expands about the heading, while an object on a collision course keeps its
    bearing. With ``alarm_path``, a field in alarm exempts the box only where it has no course (``miss`` None) or
    the heading is not ``steady`` (:attr:`TargetLayer.steady`: measured on most of the last frames); else its drift
    may be at most ``alarm_path`` (0.5): a translation measured frame after frame is the one the static world expands
    about, and a box whose course the alarm would begin on drifts away from it as the static world does or as an
    object passing beside the path."""
    if p.path_drift <= 0 or heading is None or holds(t, heading):
        return False
    limit = p.path_drift
    if t.last_alarm == index:
        if not (p.alarm_path > 0 and steady and miss is not None):
            return False
        limit = p.alarm_path
    ratio = drift(t, heading, away=True)
    return ratio is not None and ratio > limit


def fresh(t: Track, p: TargetParams, fps: float, index: float, measured: tuple[float, float] | None,
          interval: float | None = None, miss: float | None = None) -> bool:
    """``fresh_ttc`` (docs/history.md, "False warnings, session 18"): whether a warning that would begin this frame
    (clock ``index``) on track ``t`` is the static world's, found already near: the camera translates
    (``measured``: the measured heading, px; None: none measured, no test), no field of ``t`` is in collision
    alarm this frame, the track's first time to contact (``Track.first_ttc``) was under ``fresh_ttc`` (it was
    never seen approaching from beyond it), its box does not hold the heading (:func:`holds`) and its centre
    drifted away from the heading by more than ``fresh_drift`` of the static world's drift (:func:`drift`, with
    ``away``); not on a frame that follows a camera slower than ``nominal_fps`` (:func:`slow`: its track has few
    observations before its contact, its first time to contact comes late by the clock alone). The road and the
    ground beside a passing car seeded near the camera expand about the heading (a drift of 0.1-0.4 on a box
    that also holds the car); an object on a collision course found that late keeps its bearing. Only a box whose
    course ``miss`` (None: none known, no test) misses by more than ``fresh_miss``: a collider that will pass
    near the middle of the camera's extent drifts little less than that (``drift`` is about its miss over its
    offset from the heading, in its widths)."""
    if p.fresh_ttc <= 0 or measured is None or t.last_alarm == index or t.first_ttc is None \
            or t.first_ttc >= p.fresh_ttc or holds(t, measured) or slow(t, p, fps, index, interval) \
            or miss is None or miss <= p.fresh_miss:
        return False
    ratio = drift(t, measured, away=True)
    return ratio is not None and ratio > p.fresh_drift


def wide(p: TargetParams, miss: float) -> bool:
    """``onset_miss`` (docs/history.md, "A course that crosses max_miss"): whether the fit's course
    ``miss`` is too wide to begin a warning: a passing object's box holds its sweep and the
    background beside it, so its miss is measured short and crosses ``max_miss`` from above.
    The field alarm with a course is not held to it (:func:`alarm_warns`: ``max_miss``)."""
    return 0 < p.onset_miss < miss


def _older(t: Track, then: float, own_run: bool) -> tuple[float, float, float | None] | None:
    """Track ``t``'s newest estimate (clock, time to contact in s, its standard error) at clock ``then`` or before
    (``Track.ttcs``), the older one :func:`rises` and :func:`stalls` compare with; None where it has no time to
    contact, or (``own_run``) the fit's run of estimates began after ``then`` (``Track.streak_since``: nothing of its
    own to compare with)."""
    then += _EPS
    if own_run and then < t.streak_since - _EPS:
        return None
    old = next(((clock, v, sd) for clock, v, sd in reversed(t.ttcs) if clock <= then), None)
    return None if old is None or old[1] is None else old


def rises(t: Track, p: TargetParams, fps: float, index: int, ttc: float | None,
          sigma: float | None = None) -> bool:
    """``countdown_frames`` (docs/history.md, "A course that crosses max_miss"): whether track ``t``'s
    time to contact ``ttc`` (s) at clock ``index`` exceeds its time to contact of ``countdown_frames``
    frames (at ``nominal_fps``) before (its newest estimate at least that old, ``Track.ttcs``) by more
    than ``sigma`` (s, the standard error of ``ttc``; None: 0): an approach's falls by the time
    between them. False when either is unknown or the rule is off."""
    if p.countdown_frames <= 0 or ttc is None:
        return False
    old = _older(t, index - p.span(p.countdown_frames, fps), p.rise_streak and sigma is not None)
    if old is None:
        return False
    both = p.rise_sigma and sigma is not None and old[2] is not None
    return ttc > old[1] + (math.hypot(sigma, old[2]) if both else (sigma or 0.0))


def stalls(t: Track, p: TargetParams, fps: float, index: int, ttc: float | None,
           sigma: float | None = None) -> bool:
    """``onset_fall``: whether track ``t``'s time to contact ``ttc`` (s) at clock ``index`` lies above its own of
    ``fall_frames`` frames (at ``nominal_fps``) before (its newest estimate at least that old, ``Track.ttcs``, of the
    same run of fits, ``Track.streak_since``) less ``onset_fall`` times the time between them, by more than the standard
    error of their difference (``sigma`` and the older one's combined, where both are known): it does not fall as an
    approach's does. False when either is unknown or the rule is off."""
    if p.onset_fall <= 0 or ttc is None:
        return False
    old = _older(t, index - p.span(p.fall_frames, fps), True)
    if old is None:
        return False
    margin = math.hypot(sigma, old[2]) if sigma is not None and old[2] is not None else 0.0
    return ttc > old[1] - p.onset_fall * (index - old[0]) / fps + margin


def fleeting(t: Track, p: TargetParams, heading: tuple[float, float] | None) -> bool:
    """``alarm_frames`` (docs/history.md, "The field alarm on the static world"): whether the field
    alarm of track ``t`` is too young to begin a warning without a course: the camera translates
    (``heading``: the measured heading, px; None: none measured, no test), its box does not hold the
    heading (:func:`holds`), a field of it has been in collision alarm fewer than ``alarm_frames``
    frames in a row (``Track.alarm_run``) and, with ``alarm_course``, the course of its seed's own
    alignment (:func:`seed_course`) is unknown or passes beyond ``max_miss``."""
    if p.alarm_frames <= 1 or heading is None or holds(t, heading) or t.alarm_run >= p.alarm_frames:
        return False
    if p.alarm_course:
        miss = seed_course(t, heading)
        if miss is not None and math.hypot(*miss) <= p.max_miss:
            return False
    return True


def anisotropic(t: Track, p: TargetParams, heading: tuple[float, float] | None) -> bool:
    """``alarm_isotropic`` (docs/history.md, "The field alarm's seed that does not loom"): whether the field alarm
    without a course of track ``t`` does not begin a warning because its seed's own alignment over
    ``change_frames`` (``Track.seed_move``, ``Track.seed_skew``) fails the growth test every other seed
    passes (``min_growth``, ``max_anisotropy``): the camera translates (``heading``: the measured heading,
    px; None: no test), the box does not hold the heading (:func:`holds`), and the seed grew by less than
    ``min_growth`` or unlike in both directions. The ground, a wall along the path or the edge where the
    static world's surfaces meet alarm as the camera moves forward, and grow unlike in both directions; an
    approaching object grows alike. A seed whose alignment did not come back (``seed_return``, ``Track.seed_refused``)
    measured no looming and fails the test. A track without its seed's alignment (born before its alarm): no test
    (its own box's history was measured too, session 14, and delayed a real clip's warning past its alarm
    on a scaled copy: docs/model.md)."""
    if not p.alarm_isotropic or heading is None or holds(t, heading):
        return False
    if t.seed_refused:           # its seed's alignment did not come back (``seed_return``): no looming measured
        return True
    if t.seed_move is None or t.seed_skew is None:
        return False
    growth, skew = t.seed_move[2], t.seed_skew
    return growth < p.min_growth or abs(skew) > p.max_anisotropy * growth


def passed_by(t: Track, p: TargetParams) -> bool:
    """``refind_drift``: whether track ``t``, refound after a gap, took over from a lost track that drifted away
    from the heading by more than ``refind_drift`` of the static world's drift (``Track.lost_drift``)."""
    return p.refind_drift > 0 and t.lost_drift is not None and t.lost_drift > p.refind_drift


def seed_course(t: Track, heading: tuple[float, float]) -> tuple[float, float] | None:
    """``alarm_course``: the course of an alarm seed on its first frame (one observation) from its own
    alignment over ``change_frames`` (``Track.seed_move``): where its centre passes the camera plane
    against ``heading`` (px), right in its widths and down in its heights (the units of
    :func:`course`). An object at lateral offset X and width W lies ``u = X / W`` extents from the
    heading at any depth: ``u`` changes only by its own lateral motion, and the box's scale S over the
    interval puts its contact ``1 / (S - 1)`` intervals ahead, so ``miss = u1 + (u1 - u0) / (S - 1)``:
    the static world keeps ``u`` (it passes at its offset), an object on a collision course keeps its
    bearing (``u`` falls to 0 at contact). None for a track with more observations (its course waits
    for the fit, ``min_frames``: the seed's interval is as long as a fit's span, a young track's
    history shorter), without the seed's alignment, or when the box did not grow."""
    if len(t.history) != 1 or t.seed_move is None:
        return None
    dx, dy, growth = t.seed_move
    s1 = math.expm1(growth)
    if s1 <= _EPS or t.w <= 0 or t.h <= 0:
        return None
    k = math.exp(growth)
    u1 = ((t.cx - heading[0]) / t.w, (t.cy - heading[1]) / t.h)
    u0 = ((t.cx - dx - heading[0]) * k / t.w, (t.cy - dy - heading[1]) * k / t.h)
    return u1[0] + (u1[0] - u0[0]) / s1, u1[1] + (u1[1] - u0[1]) / s1


def exits(t: Track, p: TargetParams, shape: tuple[int, int], heading: tuple[float, float],
          miss: float | None) -> bool:
    """``cut_exit`` (docs/history.md, "A warning that leaves through the border"): whether the warning of
    track ``t``, which has warned and whose warning began on a box wholly inside the frame
    (``Track.onset_cut``), is held back this frame: its box is cut by the border of a frame of
    ``shape`` (h, w) while it does not hold ``heading`` (px; :func:`holds`) and its course ``miss``
    (None: none known, no test) exceeds ``cut_exit``. What leaves the view through the border beside
    the path (a passing object, the ground, a roadside object) passes; the box of an object on a
    collision course spreads over the view about the path."""
    return t.warned and not t.onset_cut and _leaves(t, p, shape, heading, miss)


def _leaves(t: Track, p: TargetParams, shape: tuple[int, int], heading: tuple[float, float],
            miss: float | None, ahead: bool = False) -> bool:
    """``cut_exit``'s test: track ``t``'s box is cut by the border of a frame of ``shape`` (h, w), does not hold
    ``heading`` (px) and its course ``miss`` (None: no test) exceeds ``cut_exit``; with ``cut_exit_onset`` no
    warning begins on such a box either. With ``ahead`` (``exit_ahead``, at a warning's onset) a box that the
    border cuts one frame on (:meth:`Track.cut_ahead`) counts as cut."""
    return (p.cut_exit > 0 and miss is not None and miss > p.cut_exit
            and (t.cut(shape, p.border) or (ahead and t.cut_ahead(shape, p.border))) and not holds(t, heading))


def flat(t: Track, p: TargetParams, heading: tuple[float, float] | None) -> bool:
    """``flat_onset`` (docs/history.md, "A flat box across the path"): whether a warning that would begin this
    frame on track ``t`` is a roadside object's that runs along the path, so does not begin: the camera
    translates (``heading``: the measured heading, px; None: none measured, no test), the box holds the
    heading (:func:`holds`) and is more than ``flat_onset`` times wider than tall. Seen in perspective, an
    object along the path reaches towards the focus of expansion, so its box spans the heading and expands
    about it (a short course), flat; a compact object on a collision course that holds the heading is seen
    about as wide as tall."""
    return p.flat_onset > 0 and heading is not None and holds(t, heading) and t.w > p.flat_onset * t.h


def relapse(t: Track, p: TargetParams, index: int, miss: float | None) -> bool:
    """``reonset_miss`` (docs/history.md, "A flat box across the path"): whether the warning of track ``t``, which
    has warned and whose last frame was no warning, does not begin again this frame (clock ``index``): no field
    of it is in collision alarm this frame and its course ``miss`` (None: none known, no test) exceeds
    ``reonset_miss``. A box whose warning lapsed has mostly slid off its object (onto a neighbour, a passing
    object, the background): its course straddles both and misses; an object on a collision course keeps a
    short one."""
    return p.reonset_miss > 0 and t.last_alarm != index and miss is not None and miss > p.reonset_miss


def blind_until(targets, p: TargetParams, fps: float, now: float, shape: tuple[int, int], until: float) -> float:
    """``contact_blind`` (docs/history.md, "False warnings, session 15"): the clock up to
    which no other warning begins, given this frame's ``targets`` (clock ``now``) in a frame of ``shape``
    (h, w): the predicted contact (``ttc_s``) plus ``contact_blind`` frames of each target warning on a box
    wider or taller than the frame (the object fills the view), or ``until`` (the window so far) if later."""
    if p.contact_blind <= 0:
        return until
    h, w = shape
    for o in targets:
        if o.warning and o.ttc_s is not None and (o.width > w or o.height > h):
            until = max(until, now + o.ttc_s * fps + p.span(p.contact_blind, fps))
    return until


def heading_grows(t: Track, p: TargetParams, ttc: float, heading: tuple[float, float], gray: np.ndarray,
                  prev: list[np.ndarray], cur: list[np.ndarray], seconds: float, kernel=None) -> bool:
    """``heading_growth`` (docs/history.md, "What lies at the heading"): whether what lies at ``heading`` (px) in
    the box of track ``t``, whose time to contact is ``ttc`` (s), grows as that time to contact says. The patch about
    the heading (side ``heading_patch`` of the box's smaller one) is aligned (:func:`align`) from ``prev`` to ``cur``
    (pyramids ``seconds`` apart; ``gray``: this frame); it grows ``log(1 + seconds / ttc)`` if it is what the box's
    time to contact is of. False when it grew less than ``heading_growth`` of that, within twice the alignment's
    standard error. True (no test) where the box is under ``heading_min``, a uniform region's (``Track.uniform``),
    or the patch's grey levels vary by less than ``uniform_tol`` (nothing to align), or the alignment fails."""
    if p.heading_growth <= 0 or ttc <= 0 or t.uniform or min(t.w, t.h) < p.heading_min:
        return True
    x, y = heading
    r = max(p.heading_patch * min(t.w, t.h) / 2.0, 3.0)
    x0, y0 = max(int(x - r), 0), max(int(y - r), 0)
    patch = gray[y0:max(int(y + r) + 1, y0), x0:max(int(x + r) + 1, x0)]
    if patch.size < 4 or float(patch.std()) < p.uniform_tol:
        return True
    al = align(prev, cur, x, y, p.margin * r + 3.0, (r, r), n=p.patch, iterations=p.iterations, kernel=kernel)
    if al is None or al.residual > p.max_residual or al.scale <= 0:
        return True
    return math.log(al.scale) + 2.0 * al.sigma >= p.heading_growth * math.log1p(seconds / ttc)


def spans_view(t: Track, p: TargetParams, shape: tuple[int, int]) -> bool:
    """``view_hold``: whether the box of track ``t`` is as wide or as tall as a frame of ``shape`` (h, w), within
    1 px: the object fills the view (its box, a uniform region's, is cut at the frame's edges; its growth there is
    no longer the object's). A box larger than the frame still measures its object's growth."""
    h, w = shape
    return p.view_hold and (abs(t.w - w) <= 1 or abs(t.h - h) <= 1)


def held(t: Track, p: TargetParams, fps: float, now: float, view: bool = False) -> tuple:
    """(ttc_s, sigma_s, miss, miss_xy) of track ``t``'s last time to contact (``Track.held``) counted
    down to clock ``now``, while it is at most ``hold_frames`` old (any age over the ``view``, :func:`spans_view`)
    and its contact has not passed (as :func:`count_down` for a held frame); else four None. Reported, never a
    warning."""
    if t.held is None or p.hold_frames == 0 or (now - t.held[0] > p.span(p.hold_frames, fps) + _EPS and not view):
        return None, None, None, None
    left = t.held[1] - (now - t.held[0]) / fps
    return (left, *t.held[2:]) if left > 0 else (None, None, None, None)


def held_onset(t: Track, p: TargetParams, index: float, ttc: float | None, miss: float | None,
               shape: tuple[int, int], measured: tuple[float, float] | None) -> bool:
    """``held_onset`` (docs/history.md, "The box on what moves with it, on a cut box and from a moving camera"):
    whether a warning begins on track ``t``'s time to contact held, ``ttc`` (s, :func:`held`), this frame (clock
    ``index``) whose fit gave none: its last streak of fits was at least ``held_onset`` long, ``ttc`` is within
    ``horizon_s``, the course held ``miss`` within ``onset_miss`` (:func:`wide`), the box is not cut by the border
    of a frame of ``shape`` (h, w) (``held_cut``: or keeps its bearing, :func:`cut_keeps_bearing`, against the
    ``measured`` heading), not off the path (:func:`off_path`, against the ``measured`` heading) and not
    flat (:func:`flat`), and the track's warning was not spent."""
    return (p.held_onset > 0 and t.streak == 0 and t.held_streak >= p.held_onset and ttc is not None
            and ttc <= p.horizon_s and miss is not None and not wide(p, miss) and not t.spent
            and (not t.cut(shape, p.border)
                 or (p.held_cut and measured is not None and cut_keeps_bearing(t, p, ttc, measured)))
            and not off_path(t, p, index, measured) and not flat(t, p, measured) and not tiny(t, p))


def confirmed(t: Track, p: TargetParams, now: float, far: bool) -> bool:
    """``onset_confirm``: whether a warning the rule decided on track ``t`` this frame (clock ``now``) is shown: it was
    decided on the track's frame before too (``Track.decided``), a field of it is in collision alarm this frame (the
    paper's alarm is evidence at once: issue 22 item 4), the frame lies ``far`` from the one before (more than a
    nominal frame interval: :meth:`~mlplc2.targets.layer.TargetLayer._far`), or the rule is off."""
    return not p.onset_confirm or t.decided or t.last_alarm == now or far


def layer_vetoes(o: Target, t: Track, p: TargetParams, warned: bool, now: float, far: bool, blind: float,
                 grows, supported) -> Target:
    """The target layer's own vetoes on target ``o`` of track ``t`` (its :func:`estimate` at clock ``now``; ``warned``:
    ``Track.warned`` before it), applied in this order after every rule of :func:`estimate`. A warning that would begin
    does not: ``contact_blind`` while ``now`` lies within ``blind`` (:func:`blind_until`: the view filled by an object
    about to hit), ``heading_growth`` on a box over the heading where what lies at the heading does not grow
    (``grows(t, o)`` False: :func:`heading_grows`), ``onset_support`` on one whose course, counted in the extent of
    what moved with it, misses (``supported(t, o)`` False); each held back so leaves the track as before
    (``Track.warned``, and not warning on its last frame) with the rule in ``Target.held_by``. ``grows`` and
    ``supported`` (the layer's, which read its kept frames) are asked only for such a warning, in turn. A warning
    so decided (``Track.last_warning``, ``Track.decided``) is shown only when :func:`confirmed` (``onset_confirm``;
    ``far``: the frame lies far from the one before)."""
    if o.warning and not warned:
        rule = "contact_blind" if now <= blind + _EPS else "heading_growth" if not grows(t, o) else \
            "onset_support" if not supported(t, o) else None
        if rule is not None:
            o, t.warned, t.last_warned = replace(o, warning=False, held_by=rule), warned, False
    if o.warning:
        t.last_warning = now
    decided = o.warning
    if decided and not confirmed(t, p, now, far):
        o = replace(o, warning=False, held_by="onset_confirm")
    t.decided = decided
    return o


def tiny(t: Track, p: TargetParams) -> bool:
    """``onset_px``: whether track ``t``'s box is under ``onset_px`` on its smaller side (too small to begin a
    warning)."""
    return min(t.w, t.h) < p.onset_px


def alarm_holds(t: Track, p: TargetParams, now: float, ttc: float | None) -> bool:
    """``alarm_hold``: whether the running warning of track ``t`` (it warned on its last frame, ``Track.last_warned``,
    and its warning is not spent: its time to contact did not rise, ``countdown_frames``) goes on at clock ``now``: a
    field of it is in collision alarm this frame (the paper's fatal field) and it has a time to contact ``ttc`` (this
    frame's fit or the one held, :func:`held`), whatever its course. The target was judged on a collision course when
    it began to warn; the box of a part of an object that fills the view (its course counted in the part's own extent)
    then misses by more than the object, and its fit lapses as the box stretches, while the alarm goes on. A warning
    that lapsed does not begin again so (that cost false warnings: docs/history.md, "A warning held by the field
    alarm")."""
    return p.alarm_hold and t.last_warned and not t.spent and t.last_alarm == now and ttc is not None


def through(t: Track, p: TargetParams, fps: float, now: float, ttc: float | None, miss: float | None,
            view: bool = False) -> bool:
    """``warn_through`` (docs/history.md, "A warning held to contact"): whether track ``t``'s running warning goes on at
    clock ``now``, where its own measurement does not (no fit, a fit not yet evident or too uncertain), on its time to
    contact ``ttc`` (s; without a fit the one held, :func:`held`) and course ``miss``: its last fit at most
    ``warn_through`` frames old, ``ttc`` within ``horizon_s`` and ``miss`` within ``reonset_miss`` (the course on which
    a lapsed warning returns: a box that slid off its object, or a passing object's, straddles it and misses), or
    within ``max_miss`` while a field of it is in collision alarm this frame (``through_alarm``: the box of a part of
    an object that fills the view misses by more, in its own extent, than the object). Over the ``view``
    (``view_hold``, :func:`spans_view`) however old its last fit, ``warn_through`` 0 included."""
    return ((p.warn_through > 0 or view) and ttc is not None and miss is not None and t.held is not None
            and (view or now - t.held[0] <= p.span(p.warn_through, fps) + _EPS) and ttc <= p.horizon_s
            and miss <= (p.max_miss if p.through_alarm and t.last_alarm == now else p.reonset_miss))


def slow(t: Track, p: TargetParams, fps: float, index: float, interval: float | None) -> bool:
    """Whether track ``t`` was observed on this frame (clock ``index``) and the frame processed before it
    lies ``interval`` clock units back, more than one nominal frame (``nominal_fps``): a camera slower than
    ``nominal_fps``, or a dropped frame (not a gap in the track's own history, a failed measurement)."""
    return (interval is not None and interval > p.span(1, fps) + _EPS and len(t.history) >= 2
            and abs(t.history[-1].frame - index) <= _EPS)


def rising(t: Track, since: float) -> bool:
    """Whether track ``t``'s log-scale rose at every observation after clock ``since``, from an observation
    at or before it."""
    h = t.history
    i = len(h) - 1
    while i > 0 and h[i].frame > since + _EPS:
        if not h[i].log_scale > h[i - 1].log_scale:
            return False
        i -= 1
    return h[i].frame <= since + _EPS and i < len(h) - 1


def _evident(t: Track, p: TargetParams, fps: float, now: float, heading: tuple[float, float] | None = None,
             interval: float | None = None) -> bool:
    """Looming evidence of track ``t`` at clock ``now``: a field of it answered within ``evidence_frames``,
    or its growth has been significant over ``confirm_frames`` frames in a row (spans of time at
    ``nominal_fps``: :meth:`TargetParams.span`; a streak that resumed after a short lapse counts from
    the streak it bridged, ``evidence_bridge``, ``Track.evidence_since``), counted from its birth
    (``confirm_birth``) when its streak
    began on its first fit after the growth test and its box holds ``heading`` (px) or drifted away
    from it by at most ``confirm_birth_drift`` of the static world's drift, or (``slow_evidence``, its
    newest observation far from the one before, :func:`slow`) its log-scale rose at every observation
    over that span (:func:`rising`)."""
    if now - t.last_answer <= p.span(p.evidence_frames, fps) + _EPS:
        return True
    if p.confirm_frames == 0:
        return True
    span = p.span(p.confirm_frames - 1, fps)
    since = t.evidence_since
    if t.early and heading is not None:
        ratio = drift(t, heading)
        if holds(t, heading) or (ratio is not None and ratio <= p.confirm_birth_drift):
            since = min(since, t.birth)
    if t.streak > 0 and now - since >= span - _EPS:
        return True
    return p.slow_evidence and slow(t, p, fps, now, interval) and rising(t, now - span)


def _contact(t: Track, p: TargetParams, fit, fps: float, index: float) -> tuple[float, float] | None:
    """The time to contact (s) of ``fit`` (a :class:`ContactFit` over track ``t``'s history, or None) and its standard
    error, counted from clock ``index``, when it passes the tests a time to contact must pass: significant growth
    (``min_tstat``), a contact within ``max_ttc_s`` and still ahead, and growth alike in both directions
    (``max_anisotropy``: the ground ahead, or a wall beside the path, grows twice as fast in one direction, and a box
    that slides over a moving edge stretches along the motion; none of them is an object approaching). None otherwise."""
    if fit is None or fit.ttc is None or fit.tstat < p.min_tstat or fit.ttc / fps > p.max_ttc_s:
        return None
    growth = t.history[-1].log_scale - t.history[0].log_scale
    skew = t.history[-1].anisotropy - t.history[0].anisotropy
    # the fit's contact is counted from its newest observation: a frame whose measurement failed
    # (``max_fails``) added none, and the contact is that much nearer
    ago = index - t.history[-1].frame
    if not (growth > 0 and abs(skew) <= p.max_anisotropy * growth) or fit.ttc <= ago:
        return None
    return (fit.ttc - ago) / fps, fit.sigma / fps


def young(t: Track, p: TargetParams, fps: float, index: float, shape: tuple[int, int]) -> tuple[float, float] | None:
    """``young_ttc``: the time to contact (s) and its standard error shown on track ``t`` at clock ``index`` while
    its history is too short for a fit (:func:`fits`: under ``min_frames``): the line fit (:func:`fit_contact`) over
    the observations it has and, while they begin at its birth, the growth its growth test measured before it
    (``Track.growth``: the log-scale over ``change_frames``, a point that far back), at least ``MIN_POINTS`` points,
    when it passes the tests of a fit's (:func:`_contact`). Shown only: no warning, course, countdown or held time
    to contact rests on it. None otherwise, and on a box that fills a frame of ``shape`` (h, w) (:func:`spans_view`)."""
    if not p.young_ttc or not t.history or fits(t.history, t.fit_span) or spans_view(t, p, shape):
        return None
    frames, scales = [q.frame for q in t.history], [q.log_scale for q in t.history]
    if t.growth is not None and abs(frames[0] - t.birth) <= _EPS:
        frames, scales = [frames[0] - t.growth[0], *frames], [scales[0] - t.growth[1], *scales]
    if len(frames) < MIN_POINTS:
        return None
    return _contact(t, p, fit_contact(frames, scales), fps, index)


def estimate(t: Track, p: TargetParams, fps: float, index: int, shape: tuple[int, int],
             focal: float | None = None, heading: tuple[float, float] | None = None,
             interval: float | None = None, heading_steady: bool = False) -> Target:
    """The :class:`Target` of track ``t`` this frame: time to contact (:func:`fit_contact`),
    course (:func:`course`) and the warning rule (``docs/targets.md``, step 7). Shared
    by every model with targets (the LPLC2 family and the optical-flow baseline). ``index``: the
    frame's clock (frame intervals at ``fps`` since frame 0: the frame index at a constant rate),
    the stamp of the track's evidence. ``heading``: the measured heading (px, this frame's;
    :meth:`TargetLayer.see_heading`), None: ``TargetParams.heading`` or the principal point. ``interval``:
    clock units since the frame processed before this one (None: none; ``slow_evidence``, ``slow_onset``).
    ``heading_steady``: the heading was measured on most of the last frames (:attr:`TargetLayer.steady`; ``alarm_path``,
    ``course_yaw``)."""
    h, w = shape
    measured = heading
    t.fit_span = p.span(p.min_frames - 1, fps)
    frames = [q.frame for q in t.history]     # clocks: frame intervals (a fit's ttc / fps is in s)
    ttc = sigma = miss = miss_xy = None
    if heading is None:
        heading = p.heading if p.heading is not None else ((w - 1) / 2.0, (h - 1) / 2.0)
    first = t.held is None                    # no time to contact before this frame (slow_onset)
    view = t.last_warned and spans_view(t, p, shape)  # view_hold: a warning over the view (its growth not the object's)
    fit = None if view or not fits(t.history, t.fit_span) else fit_contact(frames, [q.log_scale for q in t.history])
    t.tries += fit is not None
    found = _contact(t, p, fit, fps, index)
    if found is not None:
        ttc, sigma = found
        miss_xy = course(t, heading, fit.ttc, t.fit_span, yaw=p.course_yaw and heading_steady,
                         centre=p.centre_growth if p.course_centre else None, alarm=t.last_alarm == index)
        miss = None if miss_xy is None else math.hypot(*miss_xy)
        if t.streak == 0:       # confirm_birth: the growth test before its birth and every fit since
            t.streak_since = index
            # evidence_bridge: after a short lapse of a long enough streak the growth seen before it still counts
            bridged = (p.evidence_bridge > 0 and t.held is not None and t.held[0] >= t.birth
                       and t.held_streak >= p.confirm_frames
                       and index - t.held[0] <= p.span(p.evidence_bridge, fps) + _EPS)
            if not bridged:
                t.evidence_since, t.early = index, p.confirm_birth and t.grown and t.tries == 1
        t.streak += 1
        t.last_estimate = index
        t.held = (index, ttc, sigma, miss, miss_xy)
        if t.first_ttc is None:
            t.first_ttc = ttc
    else:
        if t.streak:
            t.held_streak = t.streak
        t.streak = 0
    looming = ttc is not None and _evident(t, p, fps, index, heading, interval)
    # without a course (its box cut by the border), a cut box that keeps its bearing (cut_course)
    steady = miss is None and cut_course(t, p, ttc, heading, shape)
    warning = bool(looming and (miss is not None or steady) and ttc <= p.horizon_s and (steady or miss <= p.max_miss)
                   and sigma <= p.max_ttc_sigma * ttc
                   and (t.warned or steady or not wide(p, miss)
                        or (p.slow_onset and first and slow(t, p, fps, index, interval))))
    # the rule that held back a warning (Target.held_by): first the parts of the main rule beyond the time to
    # contact, the course and the looming evidence, then each veto below that turns a warning off
    held_by = None
    if not warning and looming and ttc <= p.horizon_s and (steady or (miss is not None and miss <= p.max_miss)):
        held_by = "max_ttc_sigma" if sigma > p.max_ttc_sigma * ttc else "onset_miss"
    # the field alarm it is built on (issue 22, item 4), unless the target's own measurement vetoes it,
    # and, without a course from a translating camera, once it has lasted (alarm_frames) and on a seed
    # that grows alike in both directions (alarm_isotropic)
    if not warning and alarm_warns(t, p, index, ttc, miss, heading, shape):
        held_by = None if t.warned or miss is not None else \
            "alarm_frames" if fleeting(t, p, measured) else "passed_seeds" if t.behind else \
            "alarm_isotropic" if anisotropic(t, p, measured) else "refind_drift" if passed_by(t, p) else None
        warning = held_by is None
    if t.last_alarm == index and miss is not None:   # an alarm frame judged with a course (alarm_onset_course)
        t.alarm_courses += 1
    # a warning begins on a box cut by the border only while the contact is cut_onset_s away: the
    # static world beside the path sweeps out of view through the border with a short time to contact
    if warning and not t.warned and t.cut(shape, p.border) and (ttc is None or ttc < p.cut_onset_s) \
            and not cut_keeps_bearing(t, p, ttc, heading):
        warning, held_by = False, "cut_onset_s"
    # ... nor on a cut box off the heading whose course misses it (cut_exit_onset)
    if warning and not t.warned and p.cut_exit_onset and _leaves(t, p, shape, heading, miss, p.exit_ahead):
        warning, held_by = False, "cut_exit_onset"
    # ... and, from a translating camera, only on a box on the path or keeping its bearing (path_drift)
    if warning and not t.warned and off_path(t, p, index, measured, steady=heading_steady, miss=miss):
        warning, held_by = False, "path_drift"
    # ... and, on a track found already near its contact, only on a box that keeps its bearing closely (fresh_ttc)
    if warning and not t.warned and fresh(t, p, fps, index, measured, interval, miss):
        warning, held_by = False, "fresh_ttc"
    # ... and not on a flat box across the path: a roadside object along it, seen in perspective (flat_onset)
    if warning and not t.warned and flat(t, p, measured):
        warning, held_by = False, "flat_onset"
    # ... and only on a box that grew alike in both directions since its birth (onset_isotropy; since it was put on
    # its object, alarm_reseat: Track.grown_from); a uniform region's box takes its aspect from its region, measured
    # afresh, and is not held (isotropy_uniform)
    stretch = abs(t.aniso - t.grown_from[1])
    if warning and not t.warned and p.onset_isotropy > 0 and stretch > p.onset_stretch \
            and (p.isotropy_uniform or not t.uniform) \
            and stretch > p.onset_isotropy * max(t.log_s - t.grown_from[0], 0.0):
        warning, held_by = False, "onset_isotropy"
    # ... and only while its time to contact counts down (countdown_onset; beyond its standard error: countdown_sigma)
    if warning and not t.warned and p.countdown_onset and rises(t, p, fps, index, ttc, sigma if p.countdown_sigma else None):
        warning, held_by = False, "countdown_onset"
        t.stalls += 1
    # ... and only while its time to contact falls as an approach's does (onset_fall), and never once held back on
    # stall_hold frames for a time to contact that did not fall (with countdown_onset's)
    if warning and not t.warned and (0 < p.stall_hold <= t.stalls
                                     or stalls(t, p, fps, index, ttc, sigma if p.stall_sigma else None)):
        warning, held_by = False, "onset_fall"
        t.stalls += 1
    # ... and not on a box a few pixels across, whose growth its alignment cannot measure (onset_px)
    if warning and not t.warned and tiny(t, p):
        warning, held_by = False, "onset_px"
    began = t.warned
    if warning and not began:
        t.onset_cut = t.cut(shape, p.border)
    t.warned = t.warned or warning
    if ttc is None:
        ttc, sigma, miss, miss_xy = held(t, p, fps, index, view)
    # ... or begins on the time to contact held, after a long streak of fits (held_onset)
    if not warning and not began and held_onset(t, p, index, ttc, miss, shape, measured):
        warning = t.warned = True
    # ... goes on while a field of it is in collision alarm and it has a time to contact, whatever its course (alarm_hold)
    if not warning and began and alarm_holds(t, p, index, ttc):
        warning = True
    # ... goes on through frames without a fit, on the time to contact held (warn_through; over the view, view_hold)
    if not warning and began and t.last_warned and through(t, p, fps, index, ttc, miss, view):
        warning = True
    # ... goes on while cut by the border off the heading only on a course through its box (cut_exit), or while the
    # field alarm holds it (alarm_hold: a field of it in collision alarm, a time to contact)
    if warning and began and exits(t, p, shape, heading, miss) and not alarm_holds(t, p, index, ttc):
        warning, held_by = False, "cut_exit"
    # ... and goes on only while its time to contact counts down (countdown_frames)
    if warning and began and rises(t, p, fps, index, ttc, sigma):
        t.spent = True
    # ... and, once lapsed, begins again without the field alarm only on a short course (reonset_miss)
    if warning and began and not t.last_warned and relapse(t, p, index, miss):
        warning, held_by = False, "reonset_miss"
    if warning and t.spent:
        warning, held_by = False, "countdown_frames"
    held_by = None if warning else held_by
    t.last_warned = warning
    # (the time to contact a refound track took over from the lost one, Track.held, is not its own:
    # its countdown starts from its own fit)
    own = t.held is None or t.held[0] >= t.birth
    t.ttcs.append((index, ttc if own else None, sigma if own else None))
    # the age of the time to contact shown: 0 when this frame's fit gave it, else the time since the
    # frame of the fit it was held from (Track.held; a refound track's too, own or not)
    age = None if ttc is None or t.held is None else max(index - t.held[0], 0.0) / fps
    az = el = None
    if focal is not None:
        az, el = bearing(t.cx, t.cy, (h, w), focal)
    def num(v):
        return None if v is None else float(v)

    return Target(t.id, float(t.cx), float(t.cy), float(t.w), float(t.h), ttc_s=num(ttc), miss=num(miss),
                  warning=warning, fields=tuple(sorted(t.fields)), born=t.born, looming=looming,
                  expansion=num(t.rate), ttc_sigma_s=num(sigma), azimuth_deg=num(az), elevation_deg=num(el),
                  miss_xy=None if miss_xy is None else (float(miss_xy[0]), float(miss_xy[1])), ttc_age_s=num(age),
                  held_by=held_by)
