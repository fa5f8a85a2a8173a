"""The target layer proper: the tracker (:class:`TargetLayer`, over the :class:`Track` records of
:mod:`.track`) and the warning
rule (:func:`estimate`, :func:`count_down`), giving one :class:`Target` per approaching object.

Per frame (:meth:`TargetLayer.step`; ``docs/targets.md``, steps 1-8): candidates from the
attention fields (Eq. 13-16) and from the strongest local motion (Eq. 12) or grey-level change
outside every target; their box (:mod:`.change`, else :mod:`.extent`); that it grows and how
fast (:mod:`.align`); time to contact and course (:mod:`.contact`); the warning rule.
A track's history is a deque of :class:`Observation` records, the points the fits use.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace
from types import SimpleNamespace

import cv2
import numpy as np

from ..neuropils.lobula_plate import LocalMotion
from .alignment import align, pyramid
from .change import (SUPPORT_PAD, Support, affine_change_box, change_box, ground_kappa, ground_reference, moving_extent,
                     uniform_box, uniform_region, uniform_spread)
from .extent import measure_extent
from .params import TargetParams
from .track import EPS as _EPS, Carried, Observation, Target, Track, Turn, carry_ahead
from .warning import blind_until, drift, estimate, heading_grows, holds, keeps_bearing, layer_vetoes, spans_view, young

__all__ = ["Target", "Observation", "Track", "TargetLayer", "Carried"]

#: :meth:`TargetLayer.see_heading`: the weight of a frame's sure heading estimate in the smoothed heading
HEADING_GAIN = 0.2
#: :attr:`TargetLayer.steady` (``alarm_path``): a heading is steady when it was measured on at least ``STEADY_SHARE``
#: of the last ``STEADY_FRAMES`` processed frames, ``STEADY_MIN`` of them seen at least (a camera driving or flying
#: forward: every frame; the real dashcam clips: 3-45 % of their frames; docs/history.md, "The alarm's course against a
#: steady heading")
STEADY_FRAMES = 15
STEADY_MIN = 10
STEADY_SHARE = 0.8
#: ``support_reseat``: the box put on the part that moves with it is at least this many px on a side
_MIN_SIDE = 6.0


class TargetLayer:
    """From attention fields to targets, frame by frame (``step``); explicit state, ``reset``.

    Parameters
    ----------
    params : TargetParams
    fps : float
        Frame rate (frames -> seconds).
    kernel : callable, optional
        Compiled edge scan for :func:`measure_extent` (:mod:`mlplc2.backend`); None = NumPy.
    align_kernel : callable, optional
        Compiled image alignment for :func:`align` (:mod:`mlplc2.backend`); None = NumPy.
    change_kernel : callable, optional
        Compiled last steps of :func:`change_box` (:mod:`mlplc2.backend`, the same boxes); None = OpenCV.
    focal : float, optional
        Focal length in px (from the camera's field of view): targets then carry bearings.
    measure : callable, optional
        Another front end's growth evidence in place of the image alignment (the optical-flow
        baseline's patch flow): ``measure(prev, cur, track, half, frames)`` with two pyramids
        ``frames`` frames apart (processed frames, or frame intervals) gives the track's move
        (shift, factors on width and height, log-scale and log-anisotropy gained) or None;
        None = :func:`align`.
    """

    def __init__(self, params: TargetParams | None = None, fps: float = 30.0, *, kernel=None,
                 align_kernel=None, focal: float | None = None, measure=None, change_kernel=None):
        self.measure = measure
        self.params = TargetParams() if params is None else params
        self.fps = float(fps)
        self.kernel = kernel
        self.align_kernel = align_kernel
        self.change_kernel = change_kernel
        self.focal = focal
        self.reset()

    def reset(self) -> None:
        self._settle()
        self._hot: tuple[list[int], list[int]] = ([], [])   # levels read last frame: of the last and the oldest frame
        self._ground: dict = {}                  # ground_change: this frame's ground-carried references, by level
        self._levels = None
        self._tracks: list[Track] = []
        self._lost: list[tuple[float, Track]] = []   # (clock, track) of the tracks lost lately (:meth:`_refind`)
        self._next = 1
        self._prev: Carried | None = None
        self._clock: float = 0       # clock of the last frame (frame intervals)
        self._before: float | None = None   # ... and of the frame processed before it (None: none)
        self._past: deque = deque()        # pyramids of the last frames (:meth:`_keep_past`)
        self._past_t: deque = deque()      # ... and their clocks
        self._now: tuple[np.ndarray, list[np.ndarray]] | None = None          # this frame's (gray, pyramid)
        self._size: tuple[int, int] | None = None   # this frame's (w, h)
        self.heading: tuple[float, float] | None = None   # the measured heading, smoothed (:meth:`see_heading`)
        self._seen = False                 # a heading measured for this frame (:meth:`see_heading`)
        self._seen_frames: deque = deque(maxlen=STEADY_FRAMES)   # ... for the last processed frames (:attr:`steady`)
        self.steady = False                # the heading is steady this frame (``alarm_path``)
        self._blind_until = -math.inf   # contact_blind: no warning begins up to this clock

    def see_heading(self, point: tuple[float, float] | None, confidence: float) -> None:
        """This frame's measured heading (the focus of expansion, px of this frame: ``CameraMotion.heading``)
        and its confidence (0-1): :attr:`heading` moves towards it by ``HEADING_GAIN`` times the
        confidence (an exponential average over ~1 / ``HEADING_GAIN`` frames of a sure estimate; a
        frame without one leaves it). The course's tests without a fit (:func:`on_path`,
        :func:`keeps_bearing`) use it; until one is measured, ``TargetParams.heading`` or the
        principal point. A frame with one counts towards :attr:`steady`."""
        self._seen = point is not None and confidence > 0
        if point is None or not confidence > 0:
            return
        if self.heading is None:
            self.heading = (float(point[0]), float(point[1]))
            return
        k = HEADING_GAIN * min(float(confidence), 1.0)
        self.heading = (self.heading[0] + k * (point[0] - self.heading[0]),
                        self.heading[1] + k * (point[1] - self.heading[1]))

    def _settle(self) -> None:
        """Wait for the levels :meth:`carry_ahead` is carrying (none: nothing to wait for)."""
        job, self._job = getattr(self, "_job", None), None
        if job is not None:
            job.result()

    def carry_ahead(self, clock: float) -> None:
        """Start carrying, in a thread of their own, the levels of the kept pyramids this frame
        (``clock``) will likely read: those its last and its oldest kept frame had read the frame
        before (:func:`~mlplc2.targets.track.carry_ahead`: the same values, and every level always
        carried by the same thread for the same inputs). Called by the model after its front end,
        while it works out its fields; nothing on one thread. docs/history.md, "Decoding beside the model"."""
        if self._prev is None or cv2.getNumThreads() < 2:
            return
        span = self.params.span(self.params.change_frames, self.fps) - _EPS
        i = 0                                             # the oldest kept after :meth:`_keep_past`
        while len(self._past_t) - i > 1 and clock - self._past_t[i + 1] >= span:
            i += 1
        jobs = dict.fromkeys([(self._prev, k) for k in self._hot[0]] + [(self._past[i], k) for k in self._hot[1]])
        jobs = [(c, k) for c, k in jobs if k < len(c) and c.pending(k)]
        if jobs:
            self._job = carry_ahead(jobs)

    def _pyramid(self, gray: np.ndarray) -> list[np.ndarray]:
        """This frame's pyramid, made once for :meth:`compensate` and :meth:`step`."""
        if self._now is None or self._now[0] is not gray:
            self._now = (gray, pyramid(gray))
        return self._now[1]

    def compensate(self, homography: np.ndarray, gray: np.ndarray) -> None:
        """Gaze stabilisation (as the front end's): the images kept of the last frames and every
        target's box carried into this frame's pixels (``homography``: previous frame -> this one;
        ``gray``: this frame, which fills what the turn uncovers). The turn adds to each track's
        ``ox``, ``oy``, so that its course (:func:`fit_course`) stays the object's own.
        The kept pyramids take the turn lazily (:class:`Carried`: a level is resampled when read,
        to the values of resampling it every turn; composing the turns into one resampling raised
        the false warnings, docs/model.md, "Camera motion")."""
        self._settle()
        turn = Turn(homography, self._pyramid(gray))        # shared: its level matrices and masks made once
        for levels in self._past:
            levels.turn(turn)
        for t in self._tracks:
            x, y, z = homography @ np.array([t.cx, t.cy, 1.0])
            dx, dy = x / z - t.cx, y / z - t.cy
            t.cx, t.cy = t.cx + dx, t.cy + dy
            t.ox, t.oy = t.ox + dx, t.oy + dy

    # -- one frame -----------------------------------------------------------------------
    def step(self, gray: np.ndarray, lm: LocalMotion | None, fields, index: int,
             clock: float | None = None) -> tuple[Target, ...]:
        """Targets of this frame. ``gray``: the model's float32 grey frame; ``lm``: its LM maps
        (None for a front end without them, the optical-flow baseline: no LM seed, no edge box);
        ``fields``: the attention fields (objects with ``id``, ``x``, ``y``, ``radius``, ``response``;
        another front end's candidate regions play their part: evidence under a target when
        their response is > 0, else a seed);
        ``clock``: the frame's time in frame intervals since frame 0 (None: ``index``), which the
        fits of the time to contact and the course use (``docs/model.md``, "Time")."""
        p = self.params
        # alarm_path: whether the heading was measured on most of the last frames (STEADY_FRAMES)
        self._seen_frames.append(self._seen)
        self._seen = False
        self.steady = len(self._seen_frames) >= STEADY_MIN and sum(self._seen_frames) >= STEADY_SHARE * len(self._seen_frames)
        clock = index if clock is None else clock
        levels = self._pyramid(gray)
        h, w = gray.shape
        self._size = (w, h)
        self._ground, self._levels = {}, levels
        self._keep_past(clock)
        last, oldest = self._prev, (self._past[0] if self._past else None)
        interval = None if self._prev is None else clock - self._clock
        if interval is not None:                 # follow: every track into this frame
            self._follow(levels, clock, interval, w, h, lm, gray)
        far = interval is not None and self._far(interval)
        self._before = None if self._prev is None else self._clock
        self._clock = now = clock    # the stamps and spans below are clocks (TargetParams.nominal_fps)
        if p.support_reseat > 0:
            for t in self._tracks:
                self._reseat_support(t)
        if p.affine_reseat > 0 and self._past:
            for t in self._tracks:
                self._reseat_affine(t, gray)
        self._merge(now)
        seeds, split, passed = self._field_seeds(fields, now)            # seeds: the fields no track owns,
        extra = self._motion_seeds(lm, levels, fields, interval, now, seeds)  # ... then LM and change
        self._start(seeds, extra, split, passed, lm, gray, levels, index, now, far)   # ... each a new track
        self._prev = Carried(levels)
        self._past.append(self._prev)
        self._past_t.append(clock)
        out, early = self._targets(fields, gray, index, now, interval, far)  # course and warning, per track
        self._blind_until = blind_until(out, p, self.fps, now, (h, w), self._blind_until)
        self._absorb(out, now)
        self._drop_idle(now)
        self._hot = (sorted(last.read) if last else [], sorted(oldest.read) if oldest else [])
        for c in self._past:
            c.read.clear()
        self._settle()
        keep = {t.id for t in self._tracks if not t.shadow}
        out = [o if o.id not in early else replace(o, ttc_s=early[o.id][0], ttc_sigma_s=early[o.id][1], ttc_age_s=0.0)
               for o in out if o.id in keep]
        return tuple(sorted(out, key=Target.urgency))

    def _field_seeds(self, fields, now: float) -> tuple[list, dict, set]:
        """Each field owned by the smallest track that holds it (:meth:`_own`), else a seed: ``(seeds, split,
        passed)``, the seeds ``(x, y, field)``; ``split`` (``alarm_split``): field id -> the owner its seed may
        replace; ``passed`` (``split_passed``): the fields of ``split`` whose owner's contact has passed."""
        seeds, split, passed = [], {}, set()
        for f in fields:
            owners = [t for t in self._tracks if t.contains(f.x, f.y, self._own_margin(t, f)) and not t.shadow]
            if owners:
                owner = min(owners, key=lambda t: t.size)
                plain = self._splits(owner, f)
                if plain or self._splits_passed(owner, f):
                    if not plain:
                        passed.add(f.id)
                    split[f.id] = owner
                    seeds.append((int(f.x), int(f.y), f))
                else:
                    self._own(owner, f, now)
            else:
                seeds.append((int(f.x), int(f.y), f))
        return seeds, split, passed

    def _motion_seeds(self, lm: LocalMotion | None, levels, fields, interval: float | None, now: float,
                      seeds: list) -> set:
        """The seeds of the strongest LM outside every track and field (``seed_lm``), else of grey-level change,
        added to ``seeds`` as ``(x, y, None)`` while there is room (``max_targets``); returns the extra ones
        (``lm_seeds``; ``seed_focus``, ``seed_shadow`` test them)."""
        p = self.params
        extra = set()
        if lm is not None and p.seed_lm > 0 and self._count() + len(seeds) < p.max_targets:
            # a track claims its box and the blur of the front end around it (the lamina's
            # inhibitory window, r_Di = 11 px): LM there is the tracked object's own
            from ..neuropils.attention import argmax_outside

            zones = [self._claim(t) for t in self._tracks if not (self._opened(t, now) or t.shadow)]
            zones += [(int(f.x), int(f.y), int(f.radius)) for f in fields]
            hidden = [self._claim(t) for t in self._tracks    # seed_shadow: claimed from the extra seeds only
                      if t.shadow and not self._opened(t, now)]
            n = self._seeds(interval)
            found = True                 # the first seeds' search found a candidate; once it finds none, the
            for i in range(n):
                if i < n // p.lm_seeds and not found:    # ... extra seeds still look (their own contrast)
                    continue
                if i >= n // p.lm_seeds and hidden is not None:
                    zones, hidden = zones + hidden, None
                more = i >= n // p.lm_seeds and p.extra_change > 0     # TargetParams.extra_change: a change seed
                cand = None if more else argmax_outside(lm.magnitude, zones)
                if cand is None or not cand[2] > max(p.seed_lm, p.seed_contrast * float(lm.magnitude.mean())):
                    cand = self._change_seed(levels, zones, *((p.extra_change, p.extra_window) if more else (0.0, 0.0)))
                if cand is None:
                    if more or p.extra_change <= 0:
                        break
                    found = False
                    continue
                seeds.append((cand[0], cand[1], None))
                zones.append((int(cand[0]), int(cand[1]), int(p.claim)))
                if i >= n // p.lm_seeds:         # an extra seed: TargetParams.seed_focus tests it
                    extra.add((cand[0], cand[1]))
        return extra

    def _start(self, seeds, extra: set, split: dict, passed: set, lm: LocalMotion | None, gray: np.ndarray, levels,
               index: int, now: float, far: bool) -> None:
        """A new track on each seed (:meth:`_field_seeds`, :meth:`_motion_seeds`) outside every track, on the first
        of its boxes (:meth:`_boxes`) that is a part of a track (its field then owned by that track) or grows
        (:meth:`_grows`), while there is room (``max_targets``); a split field's (``alarm_split``) replaces its owner."""
        p = self.params
        h, w = gray.shape
        for x, y, f in seeds:
            if self._count() >= p.max_targets:
                break
            hide = p.seed_shadow and f is None and (x, y) in extra   # seed_shadow: a shadow target, if any
            owner = None if f is None else split.get(f.id)              # alarm_split: the owner it may replace
            if owner is not None and not any(o is owner for o in self._tracks):
                owner = None                     # replaced already by another of its fields
            if any(t.contains(x, y) for t in self._tracks
                   if t is not owner and not ((f is None and self._opened(t, now)) or (t.shadow and not hide))):
                continue
            alarm = self._alarming(f)
            t = host = None
            for box, swept in self._boxes(lm, gray, x, y, f, alarm, every=far):
                t = Track(self._next, index, *box, birth=now, span=p.span(p.window - 1, self.fps), keep=p.window)
                host = next((o for o in self._tracks if o is not owner and self._hosts(o, t)
                             and not (f is None and self._opened(o, now)) and (hide or not o.shadow)), None)
                t.uniform = swept is None or (hide and p.shadow_uniform)   # shadow_uniform: a shadow's region too
                focus = f is None and (x, y) in extra
                if host is not None or self._grows(levels, t, alarm=alarm, focus=focus):
                    break
                t = None
            if owner is not None and f.id in passed and t is not None and self._is_field_box(t, f, w, h):
                self._own(owner, f, now)         # split_passed: only with a box of its own
                continue
            if host is not None:          # a part of an object already tracked
                if f is not None:
                    self._seat_on_alarm(host, t, alarm)
                    self._own(host, f, now)
                continue
            if owner is not None and (t is None or owner.size < p.alarm_split * t.size
                                      or (self.heading is not None and not holds(t, self.heading)
                                          and not self._seed_keeps_bearing(t))):
                self._own(owner, f, now)         # alarm_split: no box of its own, not much smaller, or off the path
                continue
            if t is None:
                continue
            if owner is not None:                # alarm_split: the seed's box replaces its owner
                self._tracks = [o for o in self._tracks if o is not owner]
            t.grown = not alarm and p.min_growth > 0   # the growth test made it a target (confirm_birth)
            t.behind = any(self._opened(o, now) and o.contains(t.cx, t.cy) for o in self._tracks)
            t.history = deque([Observation(now, 0.0, t.cx, t.cy, t.w, 0.0, height=t.h)])
            t.inside = deque(t.history)
            t.shadow = hide
            if hide or not self._refind(t, now):
                self._next += 1
            if f is not None:
                self._own(t, f, now)
            self._tracks.append(t)

    def _targets(self, fields, gray: np.ndarray, index: int, now: float, interval: float | None,
                 far: bool) -> tuple[list[Target], dict]:
        """Every track's :class:`Target` this frame: its time to contact, course and warning (:func:`estimate`), the
        layer's vetoes on it (:func:`layer_vetoes`); ``seed_shadow``: a shadow shown on its first time to contact
        (:meth:`_show`). Returns them and ``young_ttc``'s times to contact by target id, shown once every decision
        is taken (:func:`young`)."""
        p = self.params
        h, w = gray.shape
        alive = {f.id for f in fields}
        out, shown, early = [], [], {}
        for t in self._tracks:
            t.grounded = p.ground_alarm > 0 and t.last_alarm == index and self._grounded(t, gray)
            t.fields &= alive
            warned = t.warned
            o = estimate(t, p, self.fps, now, (h, w), self.focal, heading=self.heading, interval=interval,
                         heading_steady=self.steady)
            if t.shadow and t.last_estimate >= t.birth:    # seed_shadow: its first time to contact shows it
                t.shadow = False
                shown.append(t)
                held = t.held                    # refound now as a new target would be (its own time to contact kept)
                if self._refind(t, now):
                    t.held = held
                    o = replace(o, id=t.id, born=t.born)
            o = layer_vetoes(o, t, p, warned, now, far, self._blind_until, self._heading_grows, self._supported)
            if o.ttc_s is None and (guess := young(t, p, self.fps, now, (h, w))) is not None:
                early[o.id] = guess              # young_ttc: shown once every decision is taken
            out.append(o)
        return self._show(out, shown, now), early

    def _show(self, out: list[Target], shown: list[Track], now: float) -> list[Target]:
        """``seed_shadow``: a target born this frame over a ``shown`` shadow (half its box or more) is its: dropped,
        its fields and answer the shadow's; ``out`` without it."""
        if not shown:
            return out
        ids = {id(t) for t in shown}
        gone = {id(o) for o in self._tracks if not o.shadow and id(o) not in ids and abs(o.birth - now) <= _EPS
                and any(t.overlap(o) >= 0.5 for t in shown)}
        for t in shown:
            for o in self._tracks:
                if id(o) in gone and t.overlap(o) >= 0.5:
                    t.fields |= o.fields
                    t.last_answer = max(t.last_answer, o.last_answer)
        out = [o for t, o in zip(self._tracks, out) if id(t) not in gone]
        self._tracks = [t for t in self._tracks if id(t) not in gone]
        return out

    def _keep_past(self, clock: float) -> None:
        """Forget the kept frames older than needed: the newest frame at least ``change_frames``
        (``nominal_fps``) before ``clock`` stays the oldest (:meth:`_reference`)."""
        span = self.params.span(self.params.change_frames, self.fps) - _EPS
        while len(self._past_t) > 1 and clock - self._past_t[1] >= span:
            self._past.popleft()
            self._past_t.popleft()

    def _reference(self):
        """(pyramid, clock units before the last frame) of the frame ``change_frames`` (``nominal_fps``)
        before this one, the oldest kept (:meth:`_keep_past`); None while no frame is that old."""
        span = self.params.span(self.params.change_frames, self.fps)
        if not self._past or self._clock - self._past_t[0] < span - _EPS:
            return None
        return self._past[0], self._clock - self._past_t[0]

    def _ground_motion(self) -> tuple[float, tuple[float, float]] | None:
        """``ground_change``: this frame's ground motion, ``(kappa, horizon point)`` at level 1
        (:func:`~mlplc2.targets.change.ground_kappa` between the oldest kept frame and this one, about the measured
        heading; found once a frame); None where the option is off or no heading is measured."""
        if not self.params.ground_change or self.heading is None or self._levels is None or not self._past:
            return None
        if "kappa" not in self._ground:
            hx, hy = self.heading
            self._ground["kappa"] = ground_kappa(self._past[0][1], self._levels[1], (hx / 2.0, hy / 2.0))
        return self._ground["kappa"]

    def _ground_found(self) -> bool:
        """Whether this frame's ground moved as the plane (:meth:`_ground_motion`: ``kappa`` > 0); where it did not (no
        ground in view, or one that is no plane) the carried frame would be the kept one and say nothing."""
        motion = self._ground_motion()
        return motion is not None and motion[0] > 0

    def _oldest(self, level: int) -> np.ndarray:
        """Level ``level`` of the oldest kept frame (:meth:`_reference`) with its ground carried into this frame's
        pixels (:meth:`_ground_motion`; as kept where none is found): what changed there does not lie on the ground."""
        past = self._past[0][level]
        if not self._ground_found():
            return past
        if level not in self._ground:
            k, (hx, hy) = self._ground["kappa"]
            scale = 2.0 ** (1 - level)          # level 1 -> this level's pixels
            self._ground[level] = ground_reference(past, k / scale, (hx * scale, hy * scale))
        return self._ground[level]

    def _grounded(self, t: Track, gray: np.ndarray) -> bool:
        """``ground_alarm``: whether the change of track ``t``'s box below the horizon, against the oldest kept frame
        with its ground carried (:meth:`_oldest`), is less than ``ground_alarm`` times its change against that frame
        as kept: a patch of the road (at least half the box below the horizon; a ground found this frame)."""
        if not self._ground_found():
            return False
        ref = self._oldest(0)
        hy = self._ground["kappa"][1][1] * 2.0        # level 1 -> this frame's pixels
        h, w = gray.shape
        x0, x1 = max(int(t.cx - t.w / 2), 0), min(int(math.ceil(t.cx + t.w / 2)), w)
        y0, y1 = max(int(t.cy - t.h / 2), int(math.ceil(hy)) + 2, 0), min(int(math.ceil(t.cy + t.h / 2)), h)
        if x1 - x0 < 4 or y1 - y0 < max(4, t.h / 2):
            return False
        now = gray[y0:y1, x0:x1]
        kept = float(np.abs(now - self._past[0][0][y0:y1, x0:x1]).mean())
        carried = float(np.abs(now - ref[y0:y1, x0:x1]).mean())
        return carried < self.params.ground_alarm * kept

    def _own(self, t: Track, f, index: float) -> None:
        """Track ``t`` owns attention field ``f`` this frame: its answer (``response`` > 0) is
        looming evidence, its collision alarm (the paper's fatal field) the alarm evidence of
        the warning rule (:func:`alarm_warns`); a target born this frame then gets its
        :meth:`_seed_move`."""
        t.fields.add(f.id)
        if f.response > 0:
            t.last_answer = index
        if getattr(f, "collision", False):
            if t.last_alarm != index:    # the frames in a row are processed ones: a held repeat is no gap
                follows = self._before is not None and abs(t.last_alarm - self._before) <= _EPS
                t.alarm_run = t.alarm_run + 1 if follows else 1
                if not follows:
                    t.alarm_courses = 0
            t.last_alarm = index
            if self._alarming(f) and len(t.history) == 1 and t.seed_move is None:
                move = self._seed_move(t)
                if move is not None:
                    t.seed_move, t.seed_skew = move[:3], move[3]

    def _splits(self, t: Track, f) -> bool:
        """``TargetParams.alarm_split``: whether field ``f``, which track ``t`` would own, is a seed of its own: it is in
        collision alarm (:meth:`_alarming`) and ``t`` has not warned (``split_warned``: not for more than
        ``warn_through`` frames) and has no time to contact within ``horizon_s`` (none yet, or its last one beyond;
        ``split_course``: or on a course that misses). The seed's box then replaces ``t`` in :meth:`step` where it
        grows, holds the measured heading (where one is) and ``t`` is at least ``alarm_split`` times its size."""
        p = self.params
        quiet = not t.warned or (p.split_warned and not t.last_warned
                                 and self._clock - t.last_warning > p.span(p.warn_through, self.fps) + _EPS)
        return p.alarm_split > 0 and self._alarming(f) and quiet and not t.shadow \
            and (t.held is None or t.held[1] is None or t.held[1] > p.horizon_s
                 or (p.split_course and t.held[3] is not None and t.held[3] > p.max_miss))

    def _splits_passed(self, t: Track, f) -> bool:
        """``TargetParams.split_passed``: whether field ``f`` in collision alarm, which track ``t`` would own and which
        :meth:`_splits` keeps with it, is a seed of its own all the same because ``t``'s contact has passed
        (:meth:`_opened`: the box of an object that hit). Its seed replaces ``t`` only with a box of its own found
        (not the field's extent, :meth:`_field_box`: the remains of the object that hit are no object), under the
        conditions of ``alarm_split``."""
        p = self.params
        return p.split_passed and p.alarm_split > 0 and self._alarming(f) and not t.shadow \
            and self._opened(t, self._clock)

    @classmethod
    def _is_field_box(cls, t: Track, f, w: int, h: int) -> bool:
        """Whether track ``t``'s box is field ``f``'s own extent (:meth:`_field_box`): no box was found for its seed."""
        return all(abs(a - b) < 1e-6 for a, b in zip((t.cx, t.cy, t.w, t.h), cls._field_box(f, w, h)))

    def _seed_keeps_bearing(self, t: Track) -> bool:
        """``split_bearing``: whether the box of a new seed ``t`` kept its bearing over ``change_frames`` (its own
        alignment, :meth:`_seed_move`, kept as ``Track.seed_move`` for the warning rule): :func:`keeps_bearing` with
        ``bearing_drift``, as an object on a collision course off the path does."""
        p = self.params
        if not p.split_bearing or self.heading is None:
            return False
        move = self._seed_move(t)
        if move is None:
            return False
        t.seed_move, t.seed_skew = move[:3], move[3]
        return keeps_bearing(t, self.heading, p.bearing_drift)

    def _seed_move(self, t: Track) -> tuple[float, float, float, float] | None:
        """The shift (px), log-scale and log-anisotropy gained by the box of ``t`` since the oldest
        frame kept (``change_frames`` before, :meth:`_reference`; the image alignment of :meth:`_grows`),
        so that :func:`keeps_bearing` can answer on a target's first frame; None when there is no such
        frame or the alignment fails, or (``TargetParams.seed_return``) when the alignment run backwards
        from where it ended does not come back to the box (the forward-backward check of trackers): a
        patch that moved too far for the alignment to follow, as the road just ahead of a car seen
        through a wide lens, gives a shift and growth that say nothing."""
        p = self.params
        ref = self._reference()
        if ref is None or self._now is None:
            return None
        half = p.margin * t.size / 2.0 + 3.0
        if self.measure is not None:
            move = self.measure(ref[0], self._now[1], t, half, float(ref[1]))
            return None if move is None else (float(move[0]), float(move[1]), float(move[4]), float(move[5]))
        al = align(ref[0], self._now[1], t.cx, t.cy, half, (t.w / 2.0, t.h / 2.0), n=p.patch,
                   iterations=p.iterations, kernel=self.align_kernel)
        if al is None or al.residual > p.max_residual or al.scale <= 0:
            return None
        if p.seed_return > 0:      # the alignment run backwards from where it ended must come back
            back = align(self._now[1], ref[0], t.cx + al.dx, t.cy + al.dy, half * al.scale,
                         (al.kx * t.w / 2.0, al.ky * t.h / 2.0), n=p.patch, iterations=p.iterations,
                         kernel=self.align_kernel)
            if back is None or math.hypot(al.dx + back.dx, al.dy + back.dy) > p.seed_return * max(min(t.w, t.h), 1.0):
                t.seed_refused = True
                return None
            t.seed_refused = False
        return float(al.dx), float(al.dy), math.log(al.scale), float(al.anisotropy)

    def _heading_grows(self, t: Track, o: Target) -> bool:
        """``heading_growth``: from a translating camera (a measured heading), whether what lies at the heading in
        the box of track ``t`` (target ``o``) grew since the oldest frame kept (``change_frames`` before,
        :meth:`_reference`) as the target's time to contact says (:func:`heading_grows`); True (no test) where the
        box does not hold the heading (:func:`holds`) or nothing is measured."""
        if self.heading is None or o.ttc_s is None or self._now is None or not holds(t, self.heading):
            return True
        ref = self._reference()
        if ref is None:
            return True
        return heading_grows(t, self.params, o.ttc_s, self.heading, self._now[0], ref[0], self._now[1],
                             float(ref[1]) / self.fps, self.align_kernel)

    def _supported(self, t: Track, o: Target) -> bool:
        """``onset_support``: whether the course of track ``t`` (target ``o``) still passes within ``onset_support``
        when counted in the extent of the part of its box that moved as the box did since the frame ``change_frames``
        before (:meth:`_reference`; :func:`moving_extent`, the box then from the track's own history) rather than in
        the box's own extent: a box twice as wide as the passing object it holds puts a course 1.5 object widths off
        the path at 0.75. The box's extent over that part's, per axis (at least 1: never a shorter course),
        multiplies its course. True (no test) without a course, without a frame that old or an observation of the
        track at it, on a uniform region's box (measured afresh, not moved: ``Track.uniform``), or where fewer than
        ``support_min`` pixels moved with the box."""
        p = self.params
        if p.onset_support <= 0 or o.miss_xy is None:
            return True
        ext = self._support(t)
        if ext is None or ext.pixels < p.support_min:
            return True
        rw, rh = max(t.w / max(ext.width, 1.0), 1.0), max(t.h / max(ext.height, 1.0), 1.0)
        return math.hypot(o.miss_xy[0] * rw, o.miss_xy[1] * rh) <= p.onset_support

    def _support(self, t: Track) -> Support | None:
        """:func:`moving_extent` of track ``t``'s box against the frame ``change_frames`` before (:meth:`_reference`;
        the box then from the track's own history); None without a frame that old, an observation of the track at
        it, or on a uniform region's box (measured afresh, not moved: ``Track.uniform``)."""
        if self._now is None or t.uniform:
            return None
        ref = self._reference()
        if ref is None:
            return None
        then = self._clock - ref[1]
        old = [q for q in t.history if q.frame <= then + _EPS]
        if not old or then - old[-1].frame > 1.0 + _EPS:
            return None
        q = old[-1]
        return moving_extent(ref[0][0], self._now[0], (t.cx, t.cy, t.w, t.h),
                             (q.x + t.ox, q.y + t.oy, q.width, q.width if q.height is None else q.height))

    def _reseat_support(self, t: Track) -> None:
        """``support_reseat``: put the box of track ``t`` on the part of it that moves with it (:meth:`_support`), on
        each axis where the box is more than ``support_reseat`` times that part's span and at least
        ``support_still`` of the box beyond that part is seen to stay still (textured background the box's
        motion does not explain; a plain one, or a dark object's plain body, says nothing). Only on a track that
        has had a time to contact of its own (a box that grew over the background beside its object measures a
        wrong one; a track without one warns of nothing), not on a box cut by the border, only where at least
        twice ``support_min`` pixels moved with the box, and never onto a part of another track (the part that
        moves is then that track's object: :meth:`_merge` would make the two one and keep this one's history,
        the background's). Any frame the box has grown over the background again."""
        p = self.params
        if self._size is None or t.held is None or t.held[0] < t.birth or t.cut((self._size[1], self._size[0]), p.border):
            return
        ext = self._support(t)
        if ext is None or ext.pixels < 2 * p.support_min:
            return
        k, share = p.support_reseat, p.support_still
        cx, cy, w, h = t.cx, t.cy, t.w, t.h
        if w > k * max(ext.width, 1.0) and ext.still[0] >= share * ext.beyond[0]:
            cx, w = ext.x, max(SUPPORT_PAD * ext.width, _MIN_SIDE)
        if h > k * max(ext.height, 1.0) and ext.still[1] >= share * ext.beyond[1]:
            cy, h = ext.y, max(SUPPORT_PAD * ext.height, _MIN_SIDE)
        if (w, h) == (t.w, t.h):
            return
        part = Track(-1, 0, cx, cy, w, h)
        if any(o is not t and not o.shadow and o.overlap(part) >= 0.5 for o in self._tracks):
            return
        t.reseat((cx, cy, w, h))

    def _reseat_affine(self, t: Track, gray: np.ndarray) -> None:
        """``affine_reseat``: put the box of young track ``t`` (no time to contact yet) on the region that changed
        since the oldest kept frame (``change_frames`` before) about its centre once the window's affine motion is
        undone (:func:`affine_change_box`, at least ``affine_inliers`` of its corners fitting that motion), where
        that region is ``affine_reseat`` to ``affine_reseat_max`` times smaller than the box (the square root of the
        areas), its centre lies in the box and it is no part of another track; once per track (``Track.affine_put``).
        Not on a uniform region's box (measured afresh), a shadow, a box cut by the border or one wider than the
        window."""
        p = self.params
        if t.uniform or t.shadow or t.warned or t.held is not None or t.affine_put \
                or t.size > 2 * p.max_shift or t.cut(gray.shape, p.border):
            return
        box = affine_change_box(self._past[0][0], gray, int(round(t.cx)), int(round(t.cy)), int(p.max_shift),
                                inliers=p.affine_inliers)
        if box is None and p.ground_change and self.heading is not None and t.cy + t.h / 2.0 > self.heading[1] \
                and self._ground_found():
            # ground_change: the change against the oldest frame with its ground carried (a box over the road)
            box = change_box(self._oldest(0), gray, int(round(t.cx)), int(round(t.cy)), int(p.max_shift),
                             kernel=self.change_kernel)
        if box is None:
            return
        cx, cy, w, h = box
        shrink = math.sqrt(t.w * t.h / (w * h))      # how many times smaller the region is
        if abs(cx - t.cx) > t.w / 2.0 or abs(cy - t.cy) > t.h / 2.0 or shrink < p.affine_reseat \
                or 0 < p.affine_reseat_max < shrink:
            return
        part = Track(-1, 0, cx, cy, w, h)
        if any(o is not t and not o.shadow and o.overlap(part) >= 0.5 for o in self._tracks):
            return
        t.affine_put = True
        t.reseat(box)

    def _claim(self, t: Track) -> tuple:
        """The seed zone of track ``t`` (x, y, half-side): its box and ``claim`` px beyond, a square
        of its larger side."""
        return int(round(t.cx)), int(round(t.cy)), int(t.size / 2.0 + self.params.claim)

    @staticmethod
    def _hosts(o: Track, t: Track) -> bool:
        """Whether box ``t`` is a part of track ``o``: most of the smaller of the two lies in the other."""
        return o.overlap(t) >= 0.5

    def _own_margin(self, t: Track, f) -> float:
        """How far beyond its box a track owns a field: a quarter of its size (plus 4 px), none for
        a field in alarm (:meth:`_alarming`): the warning of an alarm lies on the target's centre, so
        a box beside the field must not take it; the field then seeds a target of its own."""
        return 0.0 if self._alarming(f) else 0.25 * t.size + 4.0

    def _alarming(self, f) -> bool:
        """Whether field ``f`` is in collision alarm and alarms count as evidence
        (``alarm_warns``): such a seed needs only some growth (:meth:`_grows`), since the
        alarm is the sum of the field's LPLC2 responses (Eq. 14-16), which only expansion in all
        four quadrants raises, and it takes the field's own extent when no box is found."""
        return f is not None and self.params.alarm_warns and bool(getattr(f, "collision", False))

    @staticmethod
    def _field_box(f, w: int, h: int) -> tuple[float, float, float, float]:
        """The box of a field in alarm when neither the change nor the edges give one: its
        receptive field (centre, side 2 r_AF), clipped to the frame."""
        x0, x1 = max(f.x - f.radius, 0.0), min(f.x + f.radius, w - 1.0)
        y0, y1 = max(f.y - f.radius, 0.0), min(f.y + f.radius, h - 1.0)
        return (x0 + x1) / 2.0, (y0 + y1) / 2.0, max(x1 - x0, 2.0), max(y1 - y0, 2.0)

    def _change_seed(self, levels, zones, contrast: float = 0.0, window: float = 0.0):
        """A candidate where the image changed most over the last ``change_frames`` frames (at
        half resolution, outside the zones of targets and fields), when that change stands out:
        at least ``seed_change`` grey levels and ``seed_contrast`` times the frame's mean change.
        An object that grows straight at the camera moves its edges a fraction of a pixel per
        frame, too little for the local motion, while the grey levels along its edge change
        steadily; a moving background changes everywhere and seeds nothing here. ``contrast``: that
        factor instead (``TargetParams.extra_change``, the extra seeds'; 0: ``seed_contrast``);
        ``window`` (``extra_window``): the change against the mean change of a window that wide
        around each point, at least ``contrast`` times it (and ``seed_change`` grey levels)."""
        p = self.params
        ref = self._reference()
        if p.seed_change <= 0 or ref is None or len(levels) < 2:
            return None
        d = cv2.blur(cv2.absdiff(levels[1], ref[0][1]), (3, 3))
        if window > 0:                           # extra_window: the change against its surround's
            k = max(int(window) // 2, 3)
            r = d / np.maximum(cv2.blur(d, (k, k)), 1.0)
            r[d < p.seed_change] = 0
            d = r
        for zx, zy, r in zones:                  # at half resolution
            x0, x1 = max((zx - r) // 2, 0), max((zx + r) // 2 + 1, 0)
            y0, y1 = max((zy - r) // 2, 0), max((zy + r) // 2 + 1, 0)
            d[y0:y1, x0:x1] = 0
        _, top, _, (x, y) = cv2.minMaxLoc(d)
        if window > 0:
            return (2 * x + 1, 2 * y + 1) if top >= contrast else None
        if top < max(p.seed_change, (contrast or p.seed_contrast) * float(d.mean())):
            return None
        return 2 * x + 1, 2 * y + 1

    def _grows(self, levels, t: Track, alarm: bool = False, focus: bool = False) -> bool:
        """Whether the candidate grew, alike in both directions, over the last ``change_frames``
        frames (the image alignment of :func:`align` against the oldest frame kept): a patch of
        background that slides with a turning camera, a receding or a static object does not
        become a target. With ``focus`` (an extra LM seed) and ``seed_focus``, it must also have
        grown about a point near its box (:meth:`_focused`). Without that frame yet (the first
        frames) no growth is seen: only an ``alarm`` makes a target (issue 22 item 7: which
        candidate the codec's noise picked on a clip's first frames decided its tracks). The seed of a field in
        collision ``alarm`` (:meth:`_alarming`) only must not be seen not to grow (an alignment
        that fails says nothing): the alarm is the expansion evidence, and its box may hold
        background or be cut by the border."""
        p = self.params
        ref = self._reference()
        if p.min_growth <= 0:
            return True
        if ref is None:                          # no growth seen yet: only an alarm is evidence
            return alarm
        half = p.margin * t.size / 2.0 + 3.0
        if self.measure is not None:             # another front end's growth evidence
            move = self.measure(ref[0], levels, t, half, float(ref[1]))
            t.growth = None if move is None else (float(ref[1]), float(move[4]))
            return move is not None and move[4] >= p.min_growth and abs(move[5]) <= p.max_anisotropy * move[4]
        al = align(ref[0], levels, t.cx, t.cy, half, (t.w / 2.0, t.h / 2.0), n=p.patch,
                   iterations=p.iterations, kernel=self.align_kernel)
        if al is None or al.residual > p.max_residual:
            return alarm
        t.motion = (al.dx / ref[1], al.dy / ref[1], math.log(al.scale) / ref[1])
        g = math.log(al.scale)
        t.growth = (float(ref[1]), g)
        if alarm:
            return g > 0
        return g >= p.min_growth and abs(al.anisotropy) <= p.max_anisotropy * g \
            and not (focus and not self._focused(t, al))

    def _focused(self, t: Track, al) -> bool:
        """``TargetParams.seed_focus``: whether the alignment ``al`` of candidate ``t`` (scale ``s``, shift ``d``
        of its centre) expands about a point within ``seed_focus`` half-sizes of its box from the centre (the
        fixed point ``-d / (s - 1)``): ``|d| <= (s - 1) seed_focus w / 2`` (``h / 2``) plus ``focus_slack``.
        An object on a collision course expands about where it will hit, inside its own image; the static world
        seen from a translating camera about the heading, outside a patch beside the path; a passing object
        about a point beside it. A box cut by the border (``TargetParams.border``) has neither the object's
        centre nor its size: it fails. Always with ``seed_focus`` 0 (off)."""
        p = self.params
        if p.seed_focus <= 0:
            return True
        if self._size is not None and t.cut((self._size[1], self._size[0]), p.border):
            return False
        grow = al.scale - 1.0
        return abs(al.dx) <= grow * p.seed_focus * t.w / 2.0 + p.focus_slack \
            and abs(al.dy) <= grow * p.seed_focus * t.h / 2.0 + p.focus_slack

    def _seeds(self, interval: float | None) -> int:
        """How many LM seeds (outside every target and field) this frame may give: one per nominal
        frame (``TargetParams.nominal_fps``) the interval since the last frame stands for, at most
        ``change_frames`` (the growth test's span); one at the first frame or at the nominal rate. A
        camera at 7.5 fps thus seeds as often in time as one at 30 fps: between distant frames a fast
        object is often not the strongest LM (issue 23: the thrown helmet, the thrower's body). Each counts
        ``TargetParams.lm_seeds`` times."""
        k = self.params.lm_seeds                 # TargetParams.lm_seeds per nominal frame
        if interval is None:
            return k
        n = int(round(interval / self.params.span(1, self.fps)))
        return k * max(1, min(n, self.params.change_frames))

    def _far(self, interval: float) -> bool:
        """Whether frames ``interval`` clock units apart are more than one nominal frame apart (a
        camera slower than ``TargetParams.nominal_fps``, or a dropped frame): a fast object then moves
        and grows beyond what the layer's measurements assume (:meth:`_boxes`, :meth:`_align_track`)."""
        return interval > self.params.span(1, self.fps) + _EPS

    def _boxes(self, lm: LocalMotion | None, gray: np.ndarray, x: int, y: int, field=None, alarm: bool = False,
               every: bool = False):
        """The boxes of a candidate at (x, y), in the order they are tried (the first that is a part of
        a track or grows, :meth:`_grows`, is taken): the region that changed over the last frames
        (:func:`change_box`, tight for a small object), else the edges of the local motion
        (:func:`measure_extent`; without LM maps, the ``box`` the front end gave its candidate
        ``field``, if any), the edges first for a ``field`` seed; each only when it holds the seed
        within ``max_shift``. When neither does, the seed of a field in ``alarm`` takes the field's
        own extent (:meth:`_field_box`). With ``every`` (the frames lie far apart, :meth:`_far`) the
        second box is tried too when the first does not grow: between distant frames the change of a
        fast object is the union of where it was and where it is, cut at ``max_shift``, and such a
        part does not align (the 7.5 fps helmet clip: its change box holds only the helmet's top).
        At the nominal rate only the first box is tried (trying both there changed the benchmark
        both ways: docs/model.md, "Time")."""
        p = self.params

        def edges():
            if lm is None:                       # a front end without LM maps (flow): its own box
                return getattr(field, "box", None)
            ext = measure_extent(lm, x, y, p, kernel=self.kernel)
            if ext.width is None or ext.height is None:
                return None
            return ext.cx, ext.cy, ext.width, ext.height

        def change():
            if not self._past:
                return None
            return change_box(self._past[0][0], gray, x, y, int(p.max_shift), kernel=self.change_kernel)

        if p.uniform_tol > 0 and (p.uniform_lm or field is not None):   # TargetParams.uniform_tol: a uniform object's whole extent
            box = uniform_box(gray, x, y, p.claim, p.uniform_tol, fill=p.uniform_fill, aspect=p.uniform_aspect)
            if box is not None:
                yield box, None                  # None: a uniform region's box (Track.uniform)
        found = False
        for find in ((edges, change) if field is not None else (change, edges)):
            box = find()
            if box is not None and max(abs(box[0] - x), abs(box[1] - y)) <= p.max_shift:
                found = True
                yield box, find is change
                if not every:
                    break
        if not found and alarm:
            yield self._field_box(field, gray.shape[1], gray.shape[0]), False

    def _follow(self, levels, clock: float, interval: float, w: int, h: int, lm=None, gray=None) -> None:
        """Move and grow every track with the image alignment (between far frames, else its box
        measured afresh, :meth:`_remeasure`); drop the lost ones. ``view_hold``: a warning track whose box is the
        view (:func:`~mlplc2.targets.warning.spans_view`) is kept where its alignment fails, and dropped, not to be
        refound, once the contact its time to contact held predicts has passed."""
        p = self.params
        kept = []
        for t in self._tracks:
            if t.warned and spans_view(t, p, (h, w)) and t.held is not None \
                    and t.held[1] <= (clock - t.held[0]) / self.fps:
                continue                         # view_hold: over the view past the contact its time to contact held:
                                                 # dropped, not to be refound (the object has reached the camera)
            half = p.margin * t.size / 2.0 + 3.0
            if self.measure is not None:         # another front end's growth evidence
                move = self.measure(self._prev, levels, t, half, interval)
            else:
                al = self._align_track(levels, t, half, interval)
                move = None if al is None else (al.dx, al.dy, al.kx, al.ky, math.log(al.scale), al.anisotropy)
                if move is None and gray is not None:
                    move = self._remeasure(lm, gray, t, interval)
            if move is None and t.last_warned and spans_view(t, p, (h, w)):
                kept.append(t)                   # view_hold: the view is the object, nothing to align; kept while it warns
                continue
            if t.follow(move, clock, self.fps, (h, w), p.max_fails, interval=interval, border=p.border):
                if move is not None and gray is not None:
                    self._adopt_uniform(t, gray)
                    self._reseat_uniform(t, gray)
                kept.append(t)
            else:
                self._lose(t, clock)
        self._tracks = kept

    def _count(self) -> int:
        """The tracks that count against ``max_targets``: all but the shadows (``seed_shadow``: a target born
        from an extra seed, without a time to contact yet; until its first one it is not output, owns no
        attention field, claims no seed but the extra seeds', hosts no box but an extra seed's, is neither
        remembered for :meth:`_refind` nor refound, and yields to any other target over it, :meth:`_merge`;
        docs/history.md, "Shadow targets")."""
        return sum(not t.shadow for t in self._tracks)

    def _two_contacts(self, o: Track, t: Track) -> bool:
        """``merge_ttc``: whether tracks ``o`` and ``t`` both measured a time to contact on the last frame and the
        larger is at least ``merge_ttc`` times the smaller: two objects whose contacts come apart (a collider's box
        grown over the view at its contact and a second collider's box beside it), not one object's two boxes."""
        k = self.params.merge_ttc
        if k <= 0 or self._before is None or o.held is None or t.held is None:
            return False
        if o.held[0] < self._before - _EPS or t.held[0] < self._before - _EPS:
            return False
        a, b = sorted((max(o.held[1], 1e-6), max(t.held[1], 1e-6)))
        return b >= k * a

    def _seat_on_alarm(self, host: Track, box: Track, alarm: bool) -> None:
        """``TargetParams.alarm_reseat``: the box found for the seed of a field in collision ``alarm`` is larger than
        the track ``host`` that is a part of it (:meth:`_hosts`: most of the host lies in it) and is a uniform region's
        box (a uniform object's whole extent, :func:`uniform_box`): the host, an edge or a strip of the object the field
        alarms on, is put on that box (:meth:`Track.reseat`: its history carried with it, its growth its own) and
        follows the region from then on (``Track.uniform``).
        The field alarm's box is the object; without this the host kept the alarm with its own course, that of a
        strip beside the object's centre, and vetoed it (docs/history.md, "An alarm seed over a smaller track")."""
        if not (self.params.alarm_reseat and alarm and box.uniform) or host.w * host.h >= box.w * box.h:
            return
        host.reseat((box.cx, box.cy, box.w, box.h))
        host.uniform = True
        host.grown_from = (host.log_s, host.aniso)     # onset_isotropy: the strip's stretch is not the object's

    def _adopt_uniform(self, t: Track, gray: np.ndarray) -> None:
        """``TargetParams.uniform_adopt``: a track that is an edge or a strip of a uniform object (its centre on a
        compact uniform region wholly in view, larger than its box and holding most of it) is put on that region and
        follows it from then on (``Track.uniform``), as :meth:`_seat_on_alarm` does for an alarm's box."""
        p = self.params
        if not (p.uniform_adopt and p.uniform_tol > 0) or t.uniform or t.shadow or t.warned:
            return
        box = uniform_region(gray, t.cx, t.cy, p.uniform_tol, fill=p.uniform_fill, aspect=p.uniform_aspect, cut=False)
        if box is None or box[2] * box[3] <= t.w * t.h:
            return
        if t.overlap(SimpleNamespace(cx=box[0], cy=box[1], w=box[2], h=box[3])) < 0.5:    # of the smaller: t's box
            return
        t.reseat(box)
        t.uniform = True
        t.grown_from = (t.log_s, t.aniso)        # onset_isotropy: the strip's stretch is not the object's

    def _reseat_uniform(self, t: Track, gray: np.ndarray) -> None:
        """``TargetParams.uniform_reseat``: a track seeded on a uniform region is put on the uniform
        region at its centre (:func:`uniform_region`) when that is a compact object whose centre lies
        inside the box and whose area is within a factor 2 of the box's (:meth:`Track.reseat`); with
        ``uniform_growth`` its growth is the region's (with ``uniform_spread``, its spread's: :func:`uniform_spread`)."""
        p = self.params
        if not (p.uniform_reseat and p.uniform_tol > 0 and t.uniform):
            return
        found = uniform_spread(gray, t.cx, t.cy, p.uniform_tol, fill=p.uniform_fill, aspect=p.uniform_aspect,
                               spread=p.uniform_growth and p.uniform_spread)
        if found is None or not t.contains(found[0][0], found[0][1]):
            return
        box, spread = found
        if not 0.5 <= box[2] * box[3] / (t.w * t.h) <= 2.0:
            return
        t.reseat(box)
        if not p.uniform_growth or not t.history:
            return
        h, w = gray.shape
        if box[0] - box[2] / 2.0 < 0 or box[1] - box[3] / 2.0 < 0 or box[0] + box[2] / 2.0 > w - 1 \
                or box[1] + box[3] / 2.0 > h - 1:
            t.region = None                      # a cut region is not the object's size
            return
        sw, sh = (box[2], box[3]) if spread is None else spread      # uniform_spread: its spread, not its box
        if t.region is not None:                 # the region's growth since it was last measured
            pw, ph, ls, an = t.region
            t.log_s = ls + 0.5 * math.log(sw * sh / (pw * ph))
            t.aniso = an + math.log((sh / ph) / (sw / pw))
            last = t.history[-1]._replace(log_scale=t.log_s, anisotropy=t.aniso)
            if t.inside and abs(t.inside[-1].frame - last.frame) <= _EPS:
                t.inside[-1] = last
            t.history[-1] = last
        t.region = (sw, sh, t.log_s, t.aniso)

    def _absorb(self, out, now: float) -> None:
        """``absorb_frames``: drop (not to be refound, but by ``refind_late``) the targets without a time to contact
        for that many frames (since their last one, or their birth) whose centre lies in a warning target's box plus
        a quarter of its size; the warning target takes their fields (docs/history.md, "Targets per object, session 15")."""
        n = self.params.absorb_frames
        warn = [t for t, o in zip(self._tracks, out) if o.warning] if n > 0 else []
        if not warn:
            return
        span = self.params.span(n, self.fps) + _EPS
        ids = {t.id for t in warn}
        kept = []
        for t in self._tracks:
            host = None if t.id in ids or now - max(t.last_estimate, t.birth) <= span else \
                next((o for o in warn if o.contains(t.cx, t.cy, 0.25 * o.size + 4.0)), None)
            if host is None:
                kept.append(t)
            else:
                host.fields |= t.fields
                if self.params.refind_late > 0:          # refound late only, by its id (:meth:`_refind`)
                    t.absorbed = True
                    self._lose(t, now)
        self._tracks = kept

    def _drop_idle(self, now: float) -> None:
        """Drop the tracks without a time to contact or an answering field for ``idle_frames``."""
        idle = self.params.span(self.params.idle_frames, self.fps) + _EPS
        kept = []
        for t in self._tracks:
            if now - max(t.last_answer, t.last_estimate, t.birth) <= idle:
                kept.append(t)
            else:
                self._lose(t, now)
        self._tracks = kept

    def _opened(self, t: Track, now: float) -> bool:
        """``passed_seeds`` (on by default): whether the box of track ``t`` no longer claims the LM and change
        seeds inside it, for good once its contact has passed (:meth:`_contact_passed`), whether or not it
        spans the view (a passing object's box, grown over a collider beside it, too): no seed zone, and a box
        seeded there is not a part of it, then or later (:meth:`_merge`); it keeps the
        attention fields it owns (after a contact they are the collider's own) and counts against
        ``max_targets``. docs/history.md, "Objects missed", session 14."""
        if self.params.passed_seeds and not t.opened and self._contact_passed(t, now):
            t.opened = True
        return self.params.passed_seeds and t.opened

    def _contact_passed(self, t: Track, now: float) -> bool:
        """Whether the contact of track ``t``'s last time to contact (``Track.held``) has passed with no
        time to contact since. Not for a last time to contact taken over from a lost track
        (:meth:`_refind`): it is not the track's own."""
        if t.held is None or t.held[0] < t.birth:    # none of its own
            return False
        return now - t.held[0] > t.held[1] * self.fps + _EPS

    def _lose(self, t: Track, now: float) -> None:
        """Remember track ``t``, lost at clock ``now``, for ``refind_frames`` (:meth:`_refind`); not a shadow."""
        if t.shadow:                             # seed_shadow: not remembered
            return
        span = self.params.span(max(self.params.refind_frames, self.params.refind_late), self.fps) + _EPS
        self._lost = [(c, o) for c, o in self._lost if now - c <= span and o.id != t.id]
        if self.params.refind_frames > 0 or self.params.refind_late > 0:
            self._lost.append((now, t))

    def _refind(self, t: Track, now: float) -> bool:
        """Whether new track ``t`` is a track lost lately (``refind_frames``; :meth:`_lose`): its
        centre lies in the lost one's last box plus a quarter of its size (as a field it would own,
        :meth:`_own_margin`) and its size is within a factor of 3 of that box's (a factor of 2 and
        the box alone: 0.07 more targets per collision object, docs/model.md).
        It then takes over the lost track's id, frame of birth, last time to contact
        (``Track.held``, ``hold_frames``) and warning state whole (``Track.warned``,
        ``Track.last_warned``, ``Track.onset_cut``: the same object, so a warning that ran on the lost
        track's last frame runs on, one that had lapsed is a lapsed one; docs/history.md, "Target
        bookkeeping"), not its history (the new box is measured afresh: its size against the old
        box's would be a jump in the log-scale fit); the newest such wins. ``refind_late``: else a track
        lost more than ``refind_frames`` (or absorbed, :meth:`_absorb`) and at most that many frames before,
        whose last centre lies in the new box and of a size within a factor of 4, gives it its id and frame of
        birth only: labels, nothing the layer does (the new track keeps its own age for :meth:`_merge`,
        ``Track.order``; docs/history.md, "Targets per object, session 16")."""
        span = self.params.span(self.params.refind_frames, self.fps) + _EPS
        live = {o.id for o in self._tracks}
        for c, o in reversed(self._lost):
            if now - c <= span and o.id not in live and not o.absorbed and o.contains(t.cx, t.cy, 0.25 * o.size) \
                    and max(t.size / o.size, o.size / t.size) <= 3.0:
                self._lost.remove((c, o))
                t.id, t.born, t.held, t.order = o.id, o.born, o.held, o.order
                t.warned, t.last_warned, t.onset_cut, t.last_warning = o.warned, o.last_warned, o.onset_cut, o.last_warning
                t.first_ttc = o.first_ttc if o.first_ttc is not None else t.first_ttc   # the object's (fresh_ttc)
                if self.params.refind_drift > 0 and self.heading is not None:   # refind_drift
                    seen = [v for v in (drift(o, self.heading), o.lost_drift) if v is not None]
                    t.lost_drift = max(seen) if seen else None
                return True
        late = self.params.span(self.params.refind_late, self.fps) + _EPS
        for c, o in reversed(self._lost):            # refind_late: the id only, the object's old centre inside the new box
            if self.params.refind_late > 0 and (o.absorbed or now - c > span) and now - c <= late \
                    and o.id not in live and t.contains(o.cx, o.cy) and max(t.size / o.size, o.size / t.size) <= 4.0:
                self._lost.remove((c, o))
                t.order, t.id, t.born = t.id, o.id, o.born
                self._next += 1                      # its own id number stays used (its age, ``order``)
                return True
        return False

    def _align_track(self, levels, t: Track, half: float, interval: float):
        """The alignment of track ``t`` from the last frame to this one (:func:`align`), None when it
        fails or leaves more than ``max_residual``. It starts from no motion; when that fails and
        the frames lie more than one nominal frame apart (a camera slower than ``nominal_fps``,
        or a dropped frame), again from the track's own last motion carried over the interval
        (``Track.motion``, constant velocity): a fast object then moves and grows beyond what the
        iteration finds from rest (the 7.5 fps helmet clip: ~10 px and x1.3 between frames)."""
        p = self.params
        box = (t.w / 2.0, t.h / 2.0)
        al = align(self._prev, levels, t.cx, t.cy, half, box, n=p.patch, iterations=p.iterations,
                   kernel=self.align_kernel)
        carried = None if t.motion is None else tuple(v * interval for v in t.motion)
        # ... a motion carried beyond what the iteration can hold (a log-scale of 1, a shift past the patch: a long gap
        # in the frames' times) is no start
        if (al is None or al.residual > p.max_residual) and carried is not None and self._far(interval) \
                and abs(carried[2]) < 1.0 and math.hypot(carried[0], carried[1]) < 2.0 * half:
            dx, dy, g = carried
            al = align(self._prev, levels, t.cx, t.cy, half, box, n=p.patch, iterations=p.iterations,
                       kernel=self.align_kernel, guess=(math.exp(g), dx, dy))
        if al is None or al.residual > p.max_residual:
            return None
        t.motion = (al.dx / interval, al.dy / interval, math.log(al.scale) / interval)
        return al

    def _remeasure(self, lm: LocalMotion | None, gray: np.ndarray, t: Track, interval: float):
        """Between frames more than one nominal frame apart (:meth:`_far`), the move of a growing track
        whose alignment failed (:meth:`_align_track`): a box measured afresh (:meth:`_boxes`: the change
        since the last frame, else the edges) where the track's own motion carries it, taken when its
        size grew by a factor within ``TargetParams.remeasure`` of the growth that motion predicts
        (log-scales from 1 / ``remeasure`` to ``remeasure`` times it). The box keeps its shape (one
        scale, the square root of the areas' ratio): a box cut differently is no anisotropy. A fast
        object between distant frames turns and changes its look beyond what the alignment holds (the
        7.5 fps helmet clip, 21 -> 25: its box aligns to no residual under 32 from any start tried,
        while the change box there grew x1.28 against x1.26 predicted). None otherwise."""
        p = self.params
        if p.remeasure <= 1 or t.motion is None or not self._far(interval):
            return None
        dx, dy, g = (v * interval for v in t.motion)
        if not g > 0:
            return None
        x, y = t.cx + dx, t.cy + dy
        for box, _ in self._boxes(lm, gray, int(round(x)), int(round(y)), every=True):
            s = 0.5 * math.log(box[2] * box[3] / (t.w * t.h))
            if g / p.remeasure <= s <= g * p.remeasure:
                k = math.exp(s)
                t.motion = ((box[0] - t.cx) / interval, (box[1] - t.cy) / interval, s / interval)
                return box[0] - t.cx, box[1] - t.cy, k, k, s, 0.0
        return None

    def _merge(self, index: int) -> None:
        """Two tracks are one object when most of the smaller box lies in the larger (:meth:`_hosts`):
        keep the older."""
        tracks = sorted(self._tracks, key=lambda t: t.order or t.id)
        out: list[Track] = []
        for t in tracks:
            if t.shadow:                         # seed_shadow: merged after the others
                continue
            host = next((o for o in out if self._hosts(o, t)
                         and not (t.behind and self._opened(o, index)) and not self._two_contacts(o, t)), None)
            if host is None:
                out.append(t)
            else:
                self._lose(t, index)
                host.fields |= t.fields
                host.last_answer = max(host.last_answer, t.last_answer)
                if t.last_alarm > host.last_alarm or (t.last_alarm == host.last_alarm and t.alarm_run > host.alarm_run):
                    host.last_alarm, host.alarm_run = t.last_alarm, t.alarm_run
                    host.alarm_courses = t.alarm_courses
        for t in tracks:                         # seed_shadow: a shadow over another target yields to it
            if t.shadow and not any(o.overlap(t) >= 0.5 for o in out):
                out.append(t)
        self._tracks = out

