"""What the target layer keeps of each object and frame: a :class:`Track` (its history of
:class:`Observation` records, the points the fits use), the :class:`Target` it reports each
frame, and the pyramids of past frames carried through the camera's turns (:class:`Carried`).
"""

from __future__ import annotations

import math
import os
import threading
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..camera import warp

__all__ = ["Target", "Observation", "Track", "Carried", "Turn", "carry_ahead", "release_carry", "MIN_POINTS", "EPS"]

#: Fewest observations of a fit (:func:`fit_contact` needs 3): the floor of ``TargetParams.min_frames``
#: for a camera slower than ``TargetParams.nominal_fps``.
MIN_POINTS = 3
#: Slack of the comparisons of clock spans (frame intervals; timestamps off the grid by rounding).
EPS = 1e-6


@dataclass(frozen=True)
class Target:
    """One approaching object in one frame (what models return in ``Output.targets``).

    Attributes
    ----------
    id : int
        Stable id (1, 2, ...), kept while the object is tracked.
    x, y : float
        Centre of the object's box (its expansion centre), in the pixels of the model's frames.
    width, height : float
        Apparent size (px).
    ttc_s : float or None
        Time to contact in seconds; None while the growth is not significant, unless the target
        had one within ``hold_frames`` (its last one, counted down; not a warning).
    miss : float or None
        Predicted miss distance at contact, in the object's own extent (the length of
        ``miss_xy``; 0 = dead centre); None without ``ttc_s``.
    warning : bool
        On a collision course (``miss <= max_miss``) with ``ttc_s <= horizon_s``, contact time
        known, and looming evidence; or one of its fields in collision alarm and nothing of its
        own measurement against it (:func:`alarm_warns`; see :class:`TargetParams`).
    fields : tuple of int
        Ids of the attention fields inside the target.
    born : int
        Frame of the target's creation.
    looming : bool
        Looming evidence this frame (an answering field recently, or sustained growth).
    expansion : float or None
        Measured growth rate d(log size)/dt in 1/s (None before two frames).
    ttc_sigma_s : float or None
        Standard error of ``ttc_s`` (s) as the fit gives it (the scatter of the box's sizes about the
        fitted line): how steady the measurement was, not how far ``ttc_s`` is from the truth
        (``benchmarks/ttc_sigma.py``: within 2 of it on 34 % of the benchmark's estimates).
    azimuth_deg, elevation_deg : float or None
        Bearing of the centre in degrees (azimuth positive right, elevation positive up)
        when the model was given the camera's field of view; None otherwise.
    miss_xy : (float, float) or None
        Where the object's centre passes the camera plane, from the heading point: right in
        object widths, down in object heights; ``miss`` is its length.
    ttc_age_s : float or None
        Seconds since ``ttc_s`` was measured: 0.0 when this frame's fit gave it; a time to contact
        held through frames without a fit (``hold_frames``, counted down) or through a repeated
        frame is as old as the time since the frame of its fit. None without ``ttc_s``.
    held_by : str or None
        Why ``warning`` is False on a frame where something spoke for one: the name of the
        :class:`TargetParams` rule that held it back (``"onset_fall"``: the time to contact did not
        fall as an approach's does; ``"onset_miss"``: a course within ``max_miss`` but beyond
        ``onset_miss`` for a warning to begin; ``"alarm_frames"``: a field alarm too young to begin
        one without a course; ...: the rules of docs/targets.md, the row ``warning``). Given where the
        time to contact is within ``horizon_s`` with the course within ``max_miss`` and looming
        evidence, or a field alarm or a warning was vetoed; None otherwise, and on every frame that warns.
    """

    id: int
    x: float
    y: float
    width: float
    height: float
    ttc_s: float | None = None
    miss: float | None = None
    warning: bool = False
    fields: tuple[int, ...] = ()
    born: int = 0
    looming: bool = False
    expansion: float | None = None
    ttc_sigma_s: float | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    miss_xy: tuple[float, float] | None = None
    ttc_age_s: float | None = None
    held_by: str | None = None

    def urgency(self) -> tuple:
        """Sort key, most urgent first: warnings, then the shortest ``ttc_s``, then the larger."""
        return (not self.warning, math.inf if self.ttc_s is None else self.ttc_s,
                -(self.width * self.height), self.id)

class Observation(NamedTuple):
    """One frame of a track's history (what the fits use): the frame's time in frame intervals
    (1 / fps) since frame 0 (the model's clock: the frame index at a constant rate), the accumulated
    log-scale, the box's centre less the camera's turn (``Track.ox``, ``Track.oy``), its width,
    the accumulated log-anisotropy, whether the box was cut by the image's border
    (``TargetParams.border``: then its centre and size are not the object's), its height
    (None: as its width), the unit of the vertical course (:func:`fit_course`), and the camera's
    horizontal turn then (``Track.ox``: ``x + ox`` is the centre's x in that frame's own pixels, the
    horizontal course in the vehicle's axes, ``TargetParams.course_yaw``)."""

    frame: int
    log_scale: float
    x: float
    y: float
    width: float
    anisotropy: float
    cut: bool = False
    height: float | None = None
    ox: float = 0.0


def _reaches(cx: float, cy: float, w: float, h: float, shape: tuple[int, int], border: float) -> bool:
    """Whether the box (centre ``cx``, ``cy``, width ``w``, height ``h``) reaches within ``border`` px of the edge
    of a frame of ``shape`` (h, w)."""
    fh, fw = shape
    return (cx - w / 2.0 < border or cy - h / 2.0 < border
            or cx + w / 2.0 > fw - 1 - border or cy + h / 2.0 > fh - 1 - border)


@dataclass
class Track:
    """Mutable state of one target: box, accumulated log-scale and anisotropy, the recent
    history the fits use (:class:`Observation` records), and the evidence
    counters; ``inside``: the last observations (at most the history's length) whose box was not
    cut, the course's points (:func:`course`). ``ox``, ``oy``: the camera's turn accumulated at the box since its birth (px; 0
    unless the model measures the camera's motion): the history's positions are the box's less
    it, so that the course (:func:`fit_course`) is the object's own, not the pan's."""

    id: int
    born: int
    cx: float
    cy: float
    w: float
    h: float
    log_s: float = 0.0
    aniso: float = 0.0                               # accumulated log(ky / kx)
    grown_from: tuple = (0.0, 0.0)   # (log_s, aniso) where its box was put on its object (``onset_isotropy`` counts from there)
    history: deque = field(default_factory=deque)   # of Observation
    inside: deque = field(default_factory=deque)    # the last observations whose box was not cut
    fails: int = 0
    last_answer: float = -(10 ** 9)    # clock of the frame an attention field of it last answered
    last_alarm: float = -(10 ** 9)     # clock of the frame a field of it was last in collision alarm
    alarm_run: int = 0                 # processed frames in a row, up to ``last_alarm``, with a field of it in collision alarm
    alarm_courses: int = 0             # of those frames, the ones on which its fit gave a course (``alarm_onset_course``)
    last_estimate: float = -(10 ** 9)  # clock of its last time to contact
    streak: int = 0
    held_streak: int = 0               # the length of the streak of fits that last ended (``held_onset``)
    stalls: int = 0                    # frames a warning was held back as its time to contact did not fall (``stall_hold``)
    streak_since: float = 0.0          # clock of the first estimate of the streak
    evidence_since: float = 0.0        # ... or of the streak it bridged (``evidence_bridge``): the growth streak's start
    birth: float = 0.0                 # clock of its creation (``born``: its frame index)
    span: float = math.inf             # the window (``TargetParams.window``) in clock units
    keep: int = 0                      # ... which keeps at least this many observations
    fit_span: float = 0.0              # the span a fit needs (``min_frames``) in clock units (:func:`estimate`)
    fields: set = field(default_factory=set)
    rate: float | None = None
    seed_move: tuple | None = None     # (dx, dy, log-scale) of an alarm's seed since ``change_frames`` before (TargetLayer._seed_move)
    seed_skew: float | None = None     # and its log-anisotropy (``alarm_isotropic``)
    seed_refused: bool = False         # its seed's alignment did not come back (``seed_return``): no measure of looming
    ox: float = 0.0
    oy: float = 0.0
    warned: bool = False               # it has warned (a warning then holds below ``cut_onset_s``)
    last_warned: bool = False          # its last frame was a warning (``reonset_miss``)
    last_warning: float = -(10 ** 9)   # clock of its last frame with a warning (``split_warned``)
    decided: bool = False              # the warning rule decided a warning on its last frame, shown or not (``onset_confirm``)
    held: tuple | None = None          # (clock, ttc_s, sigma_s, miss, miss_xy) of its last time to contact (``hold_frames``)
    first_ttc: float | None = None     # its first time to contact (s), of its own fit or the lost track's it was refound from (``fresh_ttc``)
    ttcs: deque = field(default_factory=lambda: deque(maxlen=32))   # (clock, ttc_s or None, sigma_s or None) of its last estimates
    spent: bool = False                # its warning ended for good: its time to contact rose (``countdown_frames``)
    onset_cut: bool = False            # its warning began on a box cut by the border (``cut_exit``)
    motion: tuple | None = None        # its last measured move per clock unit: (dx, dy, log scale)
    growth: tuple | None = None        # its growth test's (clock units back, log-scale grown since) at its birth (``young_ttc``)
    grown: bool = False                # made a target by the growth test, not a field alarm (``confirm_birth``)
    early: bool = False                # its streak began on its first fit after a growth test (``confirm_birth``)
    tries: int = 0                     # frames on which its history was long enough for a fit (``confirm_birth``)
    behind: bool = False               # born inside the box of a target whose contact had passed (``passed_seeds``)
    opened: bool = False               # its contact passed (``passed_seeds``): for good, a later fit notwithstanding
    lost_drift: float | None = None    # the drift of the lost track(s) it was refound from (``refind_drift``)
    absorbed: bool = False             # absorbed by a warning target (``absorb_frames``): refound late only (``refind_late``)
    order: int = 0                     # refound late (``refind_late``): the id it was created with, its age in :meth:`TargetLayer._merge`
    uniform: bool = False              # seeded on a uniform region's box (``TargetParams.uniform_reseat``)
    affine_put: bool = False           # its box was put on what moved against the background (``affine_reseat``)
    grounded: bool = False             # its box's change is the ground plane's this frame (``ground_alarm``)
    shadow: bool = False               # a shadow target (``TargetParams.seed_shadow``): no time to contact yet
    region: tuple | None = None        # (w, h, log-scale, log-anisotropy) at its last uniform region (``uniform_growth``)

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        return abs(x - self.cx) <= self.w / 2.0 + margin and abs(y - self.cy) <= self.h / 2.0 + margin

    def cut(self, shape: tuple[int, int], border: float) -> bool:
        """Whether the box reaches within ``border`` px of the edge of a frame of ``shape`` (h, w)."""
        return _reaches(self.cx, self.cy, self.w, self.h, shape, border)

    def cut_ahead(self, shape: tuple[int, int], border: float) -> bool:
        """Whether the box, moved and grown one frame on as over its last two observations (the centre's shift, the
        width's and height's ratios), reaches within ``border`` px of the edge of a frame of ``shape`` (h, w); as
        :meth:`cut` with fewer than two observations."""
        if len(self.history) < 2:
            return self.cut(shape, border)
        q0, q1 = self.history[-2], self.history[-1]
        steps = max(q1.frame - q0.frame, EPS)
        fw = (q1.width / max(q0.width, EPS)) ** (1.0 / steps)
        h0 = q0.width if q0.height is None else q0.height
        h1 = q1.width if q1.height is None else q1.height
        fh = (h1 / max(h0, EPS)) ** (1.0 / steps)
        return _reaches(self.cx + (q1.x - q0.x) / steps, self.cy + (q1.y - q0.y) / steps,
                        self.w * max(fw, 1.0), self.h * max(fh, 1.0), shape, border)

    @property
    def size(self) -> float:
        return max(self.w, self.h)

    def overlap(self, other: Track) -> float:
        """Area of the intersection of the two boxes over the area of the smaller."""
        a, b = self, other
        ix = min(a.cx + a.w / 2, b.cx + b.w / 2) - max(a.cx - a.w / 2, b.cx - b.w / 2)
        iy = min(a.cy + a.h / 2, b.cy + b.h / 2) - max(a.cy - a.h / 2, b.cy - b.h / 2)
        if ix <= 0 or iy <= 0:
            return 0.0
        return ix * iy / max(min(a.w * a.h, b.w * b.h), 1e-9)

    def reseat(self, box: tuple[float, float, float, float]) -> None:
        """Put the box on ``box`` (cx, cy, w, h: the object measured afresh, ``TargetParams.uniform_reseat``), its
        history carried with it: every observation's position moved by the same shift and its sizes
        scaled by the same factors, so the course's lines (positions in box sizes) see no jump; the
        log-scale, the growth, stays the alignment's."""
        dx, dy = box[0] - self.cx, box[1] - self.cy
        fx, fy = max(box[2], 1.0) / self.w, max(box[3], 1.0) / self.h

        def moved(q: Observation) -> Observation:
            return q._replace(x=q.x + dx, y=q.y + dy, width=q.width * fx,
                              height=None if q.height is None else q.height * fy)

        self.history = deque(moved(q) for q in self.history)
        self.inside = deque(moved(q) for q in self.inside)
        self.cx, self.cy, self.w, self.h = box[0], box[1], max(box[2], 1.0), max(box[3], 1.0)

    def _trim(self, obs: deque) -> None:
        """Drop the observations older than the window (``span`` clock units before the newest),
        keeping at least ``keep``: the window counts time, not frames (``TargetParams.nominal_fps``)."""
        while len(obs) > max(self.keep, MIN_POINTS) and obs[-1].frame - obs[0].frame > self.span + EPS:
            obs.popleft()

    def follow(self, move: tuple | None, clock: float, fps: float, shape: tuple[int, int], max_fails: int, *,
               box: tuple | None = None, refit: float = 0.0, camera=None, interval: float = 1,
               border: float | None = None) -> bool:
        """Move and grow the box by this frame's measurement (:func:`align`); False when it is lost: its
        centre left the frame (``shape`` = (h, w)), it is under 2 px or over 4 frames wide, or
        the measurement (``move`` = None) failed ``max_fails`` times in a row. ``move``: shift
        (px), factors on width and height, log-scale and log-anisotropy gained. With ``box``
        the box then moves ``refit`` of the way towards it (shrinking only); ``camera.flow`` at
        the box (the camera's image motion) adds to ``ox``, ``oy``. ``clock``: the frame's time
        (frame intervals, :class:`Observation`), ``interval`` frame intervals after the last one;
        ``border`` (px): the observation is marked cut when the box lies within it of the frame's edge."""
        if move is None:
            self.fails += 1
            return self.fails < max_fails
        dx, dy, fx, fy, growth, skew = move
        self.fails = 0
        self.cx += dx
        self.cy += dy
        self.w *= fx
        self.h *= fy
        if box is not None and refit > 0:
            self.cx += refit * (box[0] - self.cx)
            self.cy += refit * (box[1] - self.cy)
            self.w *= min(max(box[2], 1.0) / self.w, 1.0) ** refit
            self.h *= min(max(box[3], 1.0) / self.h, 1.0) ** refit
        self.log_s += growth
        self.aniso += skew
        self.rate = growth * fps / interval
        if camera is not None:
            du, dv = camera.flow(self.cx - dx, self.cy - dy)
            self.ox += float(du)
            self.oy += float(dv)
        h, w = shape
        obs = Observation(clock, self.log_s, self.cx - self.ox, self.cy - self.oy, self.w, self.aniso,
                          border is not None and self.cut(shape, border), self.h, self.ox)
        self.history.append(obs)
        self._trim(self.history)
        if not obs.cut:                  # the course's points outlive the window while the box is cut
            self.inside.append(obs)
            self._trim(self.inside)
        return not (self.size < 2.0 or self.size > 4.0 * max(w, h)
                    or not (0 <= self.cx <= w - 1 and 0 <= self.cy <= h - 1))


class Turn:
    """One turn of the camera (``homography``: previous frame -> this one, level-0 pixels; ``now``:
    this frame's pyramid, which fills what the turn uncovers), shared by every kept pyramid
    (:class:`Carried`): the homography in a level's pixels and the pixels the turn uncovers there
    (their flat indices) are found once, at the first kept level of that size it carries, and
    reused for the others (they are where the resampling reaches beyond the image: the same for
    every finite image of that size; the grey frames are finite, :mod:`mlplc2._validation`); only
    they are filled from this frame (a strip, not a pass over the level)."""

    __slots__ = ("homography", "now", "_levels")

    def __init__(self, homography: np.ndarray, now) -> None:
        self.homography, self.now = homography, now
        self._levels: dict = {}            # (level, shape, level-0 width) -> (homography there, uncovered pixels' flat indices)

    def apply(self, img: np.ndarray, k: int, w0: int) -> np.ndarray:
        """``img`` (level ``k`` of a pyramid whose level 0 is ``w0`` px wide) carried through this turn:
        :func:`mlplc2.camera.warp` with this frame's level ``k`` as its fill; ``img`` itself when this
        frame has no level of that size."""
        now = self.now
        if not (k < len(now) and now[k].shape == img.shape):
            return img
        key = (k, img.shape, w0)
        known = self._levels.get(key)
        if known is None:
            s = img.shape[1] / w0                           # pixel centres: x_k = (x + 0.5) s - 0.5
            o = 0.5 * s - 0.5
            sm = np.array([[s, 0.0, o], [0.0, s, o], [0.0, 0.0, 1.0]])
            sm_inv = np.array([[1.0 / s, 0.0, -o / s], [0.0, 1.0 / s, -o / s], [0.0, 0.0, 1.0]])
            known = (sm @ self.homography @ sm_inv, None)
        out = warp(img, known[0], fill=math.nan)            # NaN where the turn uncovers
        if known[1] is None:                                # the uncovered pixels, by flat index
            known = self._levels[key] = (known[0], np.flatnonzero(np.isnan(out)))
        if known[1].size:                                   # as warp(img, ..., fill=now[k]); a turn uncovers
            out.ravel()[known[1]] = np.ravel(now[k])[known[1]]   # a strip: no pass over the whole level
        return out


class Carried:
    """A pyramid of a past frame carried through the camera's turns since (gaze stabilisation),
    each level resampled only when it is read: on reading, the turns not yet applied to that
    level are applied in turn (:meth:`turn` records them, :meth:`Turn.apply`), each exactly as an
    eager carry would (bilinear, :func:`mlplc2.camera.warp`, with the grey levels of the frame of
    that turn where the earlier frame saw nothing), so the values are those of warping every level
    every turn, while a level never read is never resampled. Indexing and ``len`` as the list it
    stands for."""

    def __init__(self, levels):
        self.levels = list(levels)
        self._w0 = self.levels[0].shape[1]
        self._turns: list[Turn] = []
        self._done = [0] * len(self.levels)      # turns applied to each level
        self._ahead: dict[int, threading.Event] = {}   # levels being carried in :func:`carry_ahead`'s thread
        self.read: set[int] = set()              # levels read (the target layer clears it every frame)

    def turn(self, turn: Turn) -> None:
        """One more turn (one :class:`Turn` shared by every kept pyramid)."""
        self._turns.append(turn)

    def __len__(self) -> int:
        return len(self.levels)

    def __getitem__(self, k: int) -> np.ndarray:
        k = range(len(self.levels))[k]
        ahead = self._ahead.pop(k, None)
        if ahead is not None:                    # carried in the other thread: wait for it there
            ahead.wait()
        self.read.add(k)
        return self._carry(k)

    def pending(self, k: int) -> bool:
        """Whether level ``k`` has turns not yet applied."""
        return self._done[k] < len(self._turns)

    def _carry(self, k: int) -> np.ndarray:
        img = self.levels[k]
        for turn in self._turns[self._done[k]:]:
            img = turn.apply(img, k, self._w0)
        self.levels[k], self._done[k] = img, len(self._turns)
        return img


_AHEAD: list = []
_AHEAD_LOCK = threading.Lock()
os.register_at_fork(after_in_child=_AHEAD.clear)   # a forked child has no such thread: it starts its own


def carry_ahead(jobs: list[tuple[Carried, int]]) -> Future:
    """Carry the levels ``jobs`` (pyramid, level) through their pending turns in a thread of their
    own, in order, while the caller goes on; reading such a level (``Carried[k]``) waits for it. The
    values are those of carrying them when read; which thread carries a level depends on ``jobs``
    alone, never on timing. The caller waits for the returned future before the next turn."""
    events = [threading.Event() for _ in jobs]
    for (c, k), event in zip(jobs, events):
        c._ahead[k] = event

    def work() -> None:
        try:
            for (c, k), event in zip(jobs, events):
                c._carry(k)
                event.set()
        finally:                                 # a failure: the reader carries the level itself
            for event in events:
                event.set()

    with _AHEAD_LOCK:
        if not _AHEAD:
            _AHEAD.append(ThreadPoolExecutor(1, thread_name_prefix="mlplc2-carry"))
        return _AHEAD[0].submit(work)


def release_carry() -> None:
    """Stop and join :func:`carry_ahead`'s thread once its jobs are done; the next job starts a new one."""
    with _AHEAD_LOCK:
        ahead = _AHEAD.pop() if _AHEAD else None
    if ahead is not None:
        ahead.shutdown(wait=True)
