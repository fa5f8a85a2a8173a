"""Actionable targets: time to collision, expansion rate and bearing per attention field.

Every attention field gets, each frame, an estimate of

* the **time to collision** ``ttc_s`` (seconds), from the optical expansion of
  the edges around the field centre: ``tau = s / (ds/dt)`` where ``s`` is the
  size of the expanding object on the image plane;
* the **expansion rate** ``expansion_rate``: d(theta)/dt of the object's
  angular size theta (full width), in degrees per second when the camera's
  horizontal field of view is known, else d(s)/dt in pixels per second;
* the **bearing** ``azimuth_deg`` / ``elevation_deg`` of the expansion centre
  (degrees from the optical axis given the field of view, else pixel offsets
  from the image centre).

Method (see ``docs/targets.md`` for the measurements behind every choice)
-------------------------------------------------------------------------
1. *Edges* (:func:`measure_extent`). From the field centre, four strips of
   ``2 band + 1`` px run along the field's row and column to the frame border.
   In each, the outward component of the lobula-plate local motion (LM_r to the
   right, LM_l to the left, LM_u upwards, LM_d downwards; positive part) gives a
   1-D profile. The *nearest outward edge complex* (lobes closer than ``gap`` px
   merged) is located and its **outer boundary** (where the profile falls below
   ``rel_edge`` x its peak, sub-pixel) is taken. The local-motion lobes trail the
   true edge by a nearly constant ``edge_offset`` px (6-7 px for edge speeds
   0.5-8 px/frame with the default front end), which is added back. The object's
   width is ``d_right + d_left`` and its height ``d_up + d_down``: both are
   independent of where the field centre lies inside the object, and the
   midpoints give the expansion centre. ``s`` = mean of width and height.
2. *Filter* (:class:`TargetTracker`). The last ``window`` valid sizes
   (frames at most ``max_age`` old) are fitted by least squares with
   ``1 / s = a + b t``: for an object approaching at constant speed the image
   size is ``s = f L / Z`` with ``Z`` linear in time, so ``1/s`` is exactly
   linear and its zero crossing ``t_c = -a / b`` is the contact frame.
   ``ttc_s = (t_c - lag - t) / fps``. A fit needs ``min_points`` sizes spanning
   at least ``min_span`` frames, a negative slope (growth), a small residual and
   an implied edge speed the front end can follow; it is robust (the largest
   subset of >= ``min_inliers`` of the sizes that passes wins, outliers are
   forgotten) and reported only once two successive fits agree on ``t_c``
   (``confirm_frames`` / ``confirm_rel``). After a field has measured once, its
   strips start from the estimated expansion centre; a new field inside an
   object already tracked continues that track.
3. *Saturation / coasting.* When the edges move faster than ``max_edge_speed``
   px/frame the correlators alias and the lobes fall far behind the edge; when an
   edge leaves the frame it cannot be located. Such frames add no measurement
   and the estimate *coasts* on the last fit (``t_c`` unchanged, so ``ttc_s``
   keeps counting down) for at most ``coast_frames`` frames, then becomes None.

Because ``s = f tan(theta)`` (image-plane size), ``s / (ds/dt)`` is the exact
time to collision of a fronto-parallel object approaching at constant speed, at
any angle and anywhere in the image; the classic ``theta / (dtheta/dt)`` is its
small-angle approximation. No field of view is needed for ``ttc_s``.

Bearing convention: azimuth positive to the right, elevation positive up,
``azimuth = atan((x - cx) / f)``, ``elevation = atan((cy - y) / f)`` with
``(cx, cy) = ((W - 1) / 2, (H - 1) / 2)`` in pixel-index coordinates (the centre
of pixel column ``i`` is at ``x = i``) and ``f = (W / 2) / tan(hfov / 2)``.
Without a field of view the same two attributes hold ``x - cx`` and ``cy - y``
in pixels.
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ._validation import InputValueError
from .lobula_plate import LocalMotion

__all__ = ["TargetParams", "Extent", "TargetEstimate", "TargetTracker", "measure_extent", "edge_distance",
           "fit_contact", "bearing", "focal_length", "rank_by_ttc"]


@dataclass(frozen=True)
class TargetParams:
    """Parameters of the target estimators (defaults measured on ``stimuli.looming``)."""

    band: int = 2
    """Half-width (px) of the strips along the field's row and column."""
    min_peak: float = 0.05
    """Smallest outward LM (profile mean, after the gain) that counts as an edge."""
    noise_k: float = 3.0
    """An edge complex must exceed ``noise_k`` x the 75th percentile of its profile (noise floor)."""
    rel_start: float = 0.3
    """An edge complex must reach ``rel_start`` x the largest value within ``local`` px of its start."""
    local: int = 20
    """Px beyond the start of a complex searched for a stronger edge (see ``rel_start``)."""
    rel_edge: float = 0.25
    """Outer boundary of the edge complex: where it falls below ``rel_edge`` x its peak."""
    gap: int = 6
    """Lobes closer than this (px) belong to one edge complex (fast edges make 2-3 lobes)."""
    edge_offset: float = 6.5
    """Px the outer boundary of the LM lobes trails the true edge (added back)."""
    window: int = 6
    """Sizes used in the ``1/s`` regression."""
    max_age: int = 10
    """Sizes older than this (frames) are dropped."""
    min_points: int = 4
    """Fewest sizes for a fit."""
    min_span: int = 3
    """Fewest frames between the first and last size of a fit."""
    lag: float = 0.0
    """Frames the measured size lags the true one (subtracted from the contact frame)."""
    max_edge_speed: float = 8.0
    """Px/frame (per edge) above which the front end aliases: measurements stop, the fit coasts."""
    coast_frames: int = 10
    """Frames an estimate may coast on its last fit without a new measurement."""
    max_ttc_s: float = 60.0
    """Longer estimates are reported as None (no measurable approach)."""
    max_residual: float = 0.1
    """Largest rms relative residual of the ``1/s`` fit that is accepted."""
    confirm_frames: float = 1.5
    confirm_rel: float = 0.25
    """A fit is reported once the next fit's contact frame agrees within
    ``max(confirm_frames, confirm_rel x ttc)`` frames (a fit to junk is unstable)."""
    min_inliers: float = 0.6
    """Outlier rejection may drop at most this complement: a fit keeps >= 60 % of the sizes."""
    max_deviation: float = 0.2
    """A size further than this (relative) from the fit's prediction contradicts the fit."""

    def __post_init__(self) -> None:
        for name in ("band", "gap", "local", "window", "max_age", "min_points", "min_span", "coast_frames"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ValueError(f"TargetParams.{name} must be an integer >= 0, got {v!r}")
        if self.min_points < 2:
            raise ValueError(f"TargetParams.min_points must be >= 2, got {self.min_points!r}")
        for name in ("min_peak", "noise_k", "rel_start", "rel_edge", "edge_offset", "lag", "max_edge_speed", "max_ttc_s",
                     "max_residual", "max_deviation", "min_inliers",
                     "confirm_frames", "confirm_rel"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v < 0:
                raise ValueError(f"TargetParams.{name} must be a finite number >= 0, got {v!r}")


@dataclass(frozen=True)
class Extent:
    """One frame's measurement of the expanding object around a field centre (pixels).

    ``width``/``height`` are None when the edges on one side of that axis were
    not found; ``cx``/``cy`` the expansion centre (field centre where unknown);
    ``edges`` the estimated true edge positions (right x, left x, upper y,
    lower y), None where not found.
    """

    width: float | None
    height: float | None
    cx: float
    cy: float
    edges: tuple[float | None, float | None, float | None, float | None] = (None, None, None, None)

    @property
    def size(self) -> float | None:
        vals = [v for v in (self.width, self.height) if v is not None]
        return float(sum(vals) / len(vals)) if vals else None


@dataclass(frozen=True)
class TargetEstimate:
    """The estimates of one field in one frame (None where not estimable).

    ``status``: "tracking" (fit updated this frame), "coasting" (no usable
    measurement this frame; the last fit is extrapolated), "no_fit" (not yet
    enough measurements or no growth), "saturated" (edges too fast or out of
    frame and nothing to coast on).
    """

    ttc_s: float | None = None
    expansion_rate: float | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    size_px: float | None = None
    center: tuple[float, float] | None = None
    status: str = "no_fit"


def focal_length(width: int, hfov_deg: float | None) -> float | None:
    """Pinhole focal length in px, ``(W / 2) / tan(hfov / 2)``; None without a field of view."""
    if hfov_deg is None:
        return None
    return (width / 2.0) / math.tan(math.radians(float(hfov_deg)) / 2.0)


def check_hfov(hfov_deg) -> float | None:
    """Validate a horizontal field of view in degrees (None allowed)."""
    if hfov_deg is None:
        return None
    try:
        v = float(hfov_deg)
    except (TypeError, ValueError):
        raise InputValueError(f"hfov_deg must be a number in (0, 180), got {hfov_deg!r}") from None
    if not math.isfinite(v) or not 0 < v < 180:
        raise InputValueError(f"hfov_deg must be a number in (0, 180), got {hfov_deg!r}")
    return v


def bearing(x: float, y: float, shape: tuple[int, int], focal: float | None) -> tuple[float, float]:
    """(azimuth, elevation) of pixel (x, y): degrees given ``focal`` (px), else px offsets.

    Azimuth positive right, elevation positive up; the optical axis passes
    through ((W - 1) / 2, (H - 1) / 2).
    """
    h, w = shape
    dx = x - (w - 1) / 2.0
    dy = (h - 1) / 2.0 - y
    if focal is None:
        return float(dx), float(dy)
    return math.degrees(math.atan2(dx, focal)), math.degrees(math.atan2(dy, focal))


def edge_distance(profile: np.ndarray, params: TargetParams = TargetParams()) -> float | None:
    """Distance (px from the centre) of the outer boundary of the nearest outward edge complex.

    ``profile[k]`` is the outward LM at distance ``k + 1`` px. Lobes closer
    than ``gap`` px form one complex. Going outwards, the first complex whose
    peak exceeds the noise floor (``max(min_peak, noise_k x`` the profile's
    75th percentile``)``) and ``rel_start`` x the largest value within
    ``local`` px of its start is the edge (so a weak ripple just before a
    strong edge is skipped, but a strong edge of *another* object further out
    does not hide this object's weaker one). Returns None when no edge is found
    or the complex reaches the end of the profile (the edge is at or beyond the
    frame border). ``edge_offset`` is *not* added.
    """
    p = np.maximum(np.asarray(profile, dtype=np.float64), 0.0)
    if p.size < 2:
        return None
    q75 = int(0.75 * (p.size - 1))
    floor = max(params.min_peak, params.noise_k * float(np.partition(p, q75)[q75]))
    sig = np.flatnonzero(p >= 0.5 * floor)
    if sig.size == 0:
        return None
    breaks = np.flatnonzero(np.diff(sig) > params.gap)
    starts = np.r_[sig[0], sig[breaks + 1]]
    ends = np.r_[sig[breaks], sig[-1]]
    for i0, i1 in zip(starts.tolist(), ends.tolist()):
        seg = p[i0:i1 + 1]
        peak = float(seg.max())
        if peak < floor or peak < params.rel_start * float(p[i0:i0 + params.local].max()):
            continue
        level = params.rel_edge * peak
        k = i0 + int(np.flatnonzero(seg >= level)[-1])
        if k + 1 >= p.size:
            return None
        frac = (p[k] - level) / max(p[k] - p[k + 1], 1e-12)
        return float(k + 1 + min(max(frac, 0.0), 1.0))
    return None


def measure_extent(lm: LocalMotion, x: int, y: int, params: TargetParams = TargetParams()) -> Extent:
    """Width, height and centre of the outward-expanding edges around (x, y).

    Cost: four strips of ``2 band + 1`` px from the centre to the frame border.
    """
    h, w = lm.magnitude.shape
    x = int(min(max(x, 0), w - 1))
    y = int(min(max(y, 0), h - 1))
    b = params.band
    r0, r1 = max(y - b, 0), min(y + b + 1, h)
    c0, c1 = max(x - b, 0), min(x + b + 1, w)
    right = lm.r[r0:r1, x + 1:].mean(axis=0, dtype=np.float64) if x + 1 < w else np.zeros(0)
    left = lm.l[r0:r1, :x][:, ::-1].mean(axis=0, dtype=np.float64) if x > 0 else np.zeros(0)
    down = lm.d[y + 1:, c0:c1].mean(axis=1, dtype=np.float64) if y + 1 < h else np.zeros(0)
    up = lm.u[:y, c0:c1][::-1].mean(axis=1, dtype=np.float64) if y > 0 else np.zeros(0)
    dr, dl, du, dd = (edge_distance(p, params) for p in (right, left, up, down))
    off = params.edge_offset
    width = height = None
    cx, cy = float(x), float(y)
    if dr is not None and dl is not None:
        width = dr + dl + 2 * off
        cx = x + (dr - dl) / 2.0
    if du is not None and dd is not None:
        height = du + dd + 2 * off
        cy = y + (dd - du) / 2.0
    edges = (None if dr is None else x + dr + off, None if dl is None else x - dl - off,
             None if du is None else y - du - off, None if dd is None else y + dd + off)
    return Extent(width, height, cx, cy, edges)


def _line_fit(frames, sizes):
    """Least squares ``1/s = a + b t``: (a, b, relative residuals) or None if degenerate."""
    t = np.asarray(frames, dtype=np.float64)
    s = np.asarray(sizes, dtype=np.float64)
    if t.size < 2 or np.ptp(t) == 0 or np.any(s <= 0):
        return None
    yv = 1.0 / s
    tm = t.mean()
    dt = t - tm
    b = float(np.dot(dt, yv - yv.mean()) / np.dot(dt, dt))
    a = float(yv.mean() - b * tm)
    return a, b, (yv - (a + b * t)) / yv


def fit_contact(frames, sizes) -> tuple[float, float, float] | None:
    """Least-squares ``1/s = a + b t``; returns (contact_frame, slope b, rms relative residual).

    For a constant-speed approach ``1/s`` is linear in time and vanishes at
    contact, so the contact frame is ``-a / b``. None when the sizes do not
    grow (b >= 0) or are degenerate.
    """
    res = _line_fit(frames, sizes)
    if res is None or not res[1] < 0:
        return None
    a, b, rel = res
    return -a / b, b, float(np.sqrt(np.mean(rel ** 2)))


@dataclass
class TargetTracker:
    """Per-field state of the estimators: recent sizes and the last fit."""

    params: TargetParams = field(default_factory=TargetParams)
    history: deque = field(default_factory=deque)   # (frame, size, cx, cy)
    contact: float | None = None     # estimated contact frame of the last fit
    slope: float | None = None       # d(1/s)/dt of the last fit (1/px per frame)
    fit_frame: int | None = None     # frame of the last fit
    center: tuple[float, float] | None = None
    misses: int = 0                  # consecutive measurements that contradict the fit
    confirmed: bool = False          # the fit agrees with the previous one (estimates reported)

    def reset(self) -> None:
        self.history.clear()
        self.contact = self.slope = self.fit_frame = None
        self.center = None
        self.misses = 0
        self.confirmed = False

    def _refit(self, frame: int) -> bool:
        """Fit the history robustly; True if a fit was accepted.

        Every subset that drops at most ``1 - min_inliers`` of the sizes is
        tried (at most a few dozen tiny fits: the window is 6 sizes); the
        accepted fit keeps the most sizes, then has the smallest residual. The
        sizes it leaves out (outliers, e.g. a field born on the object's edge
        first measures the wrong thing) are forgotten.
        """
        p = self.params
        pts = list(self.history)
        n = len(pts)
        need = max(p.min_points, math.ceil(p.min_inliers * n))
        best = None
        for k in range(n, need - 1, -1):
            for keep in itertools.combinations(range(n), k):
                sub = [pts[i] for i in keep]
                if sub[-1][0] - sub[0][0] < p.min_span:
                    continue
                line = _line_fit([q[0] for q in sub], [q[1] for q in sub])
                if line is None:
                    continue
                a, b, rel = line
                if not b < 0:
                    continue
                y_last = a + b * sub[-1][0]           # 1/s at the last size
                rms = float(np.sqrt(np.mean(rel ** 2)))
                # Accept: growing, contact ahead, small residual, and edges no faster than the
                # front end can follow (a fit claiming faster edges was fitted to something else).
                if (-a / b > frame and rms <= p.max_residual and y_last > 0
                        and -b / (y_last * y_last) / 2.0 <= p.max_edge_speed):
                    if best is None or rms < best[0]:
                        best = (rms, a, b, sub)
            if best is not None:
                break
        if best is None:
            return False
        _, a, b, sub = best
        contact = -a / b
        # Confirmed when two successive fits agree on the contact frame.
        tol = max(p.confirm_frames, p.confirm_rel * (contact - frame))
        if self.contact is not None and abs(contact - self.contact) <= tol:
            self.confirmed = True
        elif not (self.confirmed and self.contact is not None and abs(contact - self.contact) <= 2 * tol):
            self.confirmed = False
        self.contact, self.slope, self.fit_frame = contact, b, frame
        self.history = deque(sub)
        return True

    def _predicted_size(self, frame: float) -> float | None:
        if self.contact is None or self.slope is None:
            return None
        y = -self.slope * (self.contact - frame)   # 1/s at frame (measurement time base)
        return 1.0 / y if y > 0 else math.inf

    def covers(self, x: float, y: float, frame: int) -> bool:
        """Whether (x, y) lies inside the object this tracker measured within ``max_age`` frames."""
        if not self.history or self.center is None or frame - self.history[-1][0] > self.params.max_age:
            return False
        size = self.history[-1][1]
        pred = self._predicted_size(frame)
        if pred is not None and math.isfinite(pred) and self.fit_frame is not None \
                and frame - self.fit_frame <= self.params.coast_frames:
            size = max(size, pred)
        half = size / 2.0
        return abs(x - self.center[0]) <= half and abs(y - self.center[1]) <= half

    def adopt(self, other: "TargetTracker") -> None:
        """Start from another tracker's measurements (a new field inside an object already tracked)."""
        self.history = deque(other.history)
        self.contact, self.slope, self.fit_frame = other.contact, other.slope, other.fit_frame
        self.center = other.center
        self.confirmed = other.confirmed

    def update(self, lm: LocalMotion, x: int, y: int, frame: int, fps: float,
               focal: float | None = None) -> TargetEstimate:
        """Measure around field centre (x, y) in this frame's maps and return the estimates.

        Once an expansion centre is known the strips start from it instead of
        the field centre (the field centre is where the edge was when the field
        was born, often a corner of the object).
        """
        p = self.params
        h, w = lm.magnitude.shape
        if self.center is not None and self.history:
            mx, my = int(round(self.center[0])), int(round(self.center[1]))
            if not (0 <= mx < w and 0 <= my < h):
                mx, my = x, y
        else:
            mx, my = x, y
        ext = measure_extent(lm, mx, my, p)
        size = ext.size
        cx, cy = ext.cx, ext.cy
        if size is None and self.center is not None and self.history:
            # Edges beyond the frame border (object partly out of view): half-sizes of the
            # edges still found, measured from the known expansion centre (at least two).
            c = self.center
            e = ext.edges
            halves = [v for v in (None if e[0] is None else e[0] - c[0], None if e[1] is None else c[0] - e[1],
                                  None if e[2] is None else c[1] - e[2], None if e[3] is None else e[3] - c[1])
                      if v is not None]
            if len(halves) >= 2 and min(halves) > 0:
                size = 2.0 * float(np.mean(halves))
                cx, cy = c
        while self.history and frame - self.history[0][0] > p.max_age:
            self.history.popleft()
        status = "no_fit"
        if size is not None and self.contact is not None:
            s_pred = self._predicted_size(frame)
            if s_pred is None or not math.isfinite(s_pred) or abs(size - s_pred) > p.max_deviation * s_pred:
                # A size the fit does not predict; two in a row and the fit is dropped.
                self.misses += 1
                if self.misses >= 2:
                    self.contact = self.slope = self.fit_frame = None
                    self.misses = 0
                    self.confirmed = False
            else:
                self.misses = 0
            if self.contact is not None and -self.slope * s_pred * s_pred / 2.0 > p.max_edge_speed:
                # Aliasing: edges faster than max_edge_speed px/frame leave lobes far behind
                # the edge. Such sizes are not fitted; the estimate coasts.
                size = None
                status = "saturated"
        if size is not None:
            self.history.append((frame, size, cx, cy))
            while len(self.history) > p.window:
                self.history.popleft()
            # Fit, rejecting outliers (e.g. a field born on the object's edge first measures
            # the wrong thing).
            if self._refit(frame):
                status = "tracking"
                self.misses = 0
            self.center = (float(statistics.median(h[2] for h in self.history)),
                           float(statistics.median(h[3] for h in self.history)))
        est_center = self.center if self.center is not None and self.history else (float(x), float(y))
        az, el = bearing(est_center[0], est_center[1], lm.magnitude.shape, focal)
        ttc = rate = s_now = None
        if self.contact is not None and frame - self.fit_frame > p.coast_frames:
            self.contact = self.slope = self.fit_frame = None
            self.confirmed = False
        if self.contact is not None and self.contact - p.lag - frame <= 0:
            status = "passed"              # the predicted contact is over: no estimate
        elif self.contact is not None and not self.confirmed:
            status = "unconfirmed"
        elif self.contact is not None:
            if status == "no_fit":
                status = "coasting"
            ttc_frames = self.contact - p.lag - frame
            ttc = ttc_frames / fps
            if ttc > p.max_ttc_s:
                ttc = None
            y_now = -self.slope * ttc_frames
            s_now = 1.0 / y_now
            ds = -self.slope / (y_now * y_now) * fps          # px per second
            if focal is None:
                rate = ds
            else:
                half = s_now / (2.0 * focal)
                rate = math.degrees(ds / focal / (1.0 + half * half))
        return TargetEstimate(ttc_s=ttc, expansion_rate=rate, azimuth_deg=az, elevation_deg=el,
                              size_px=s_now if s_now is not None else size, center=est_center, status=status)


def rank_by_ttc(items, key=lambda f: f.ttc_s):
    """``items`` ordered by time to collision (smallest first); those without one keep their order, last."""
    with_ttc = sorted((i for i in items if key(i) is not None), key=key)
    return with_ttc + [i for i in items if key(i) is None]
