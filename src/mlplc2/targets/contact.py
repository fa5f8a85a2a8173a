"""Time to contact and course from a track's history.

:func:`fit_contact`: the least-squares line ``1 / S = a + b t`` through the accumulated scale
``S``, contact at ``-a / b`` frames, its standard error by the delta method (:class:`ContactFit`);
:func:`fit_course`: the lines through the centre's offset from the heading point in object
widths (horizontally) and heights (vertically), evaluated at contact (the miss distance;
``docs/targets.md``, steps 5-6);
:func:`expansion_centre`: the fixed point of the box's scaling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["ContactFit", "fit_contact", "fit_course", "expansion_centre"]


@dataclass(frozen=True)
class ContactFit:
    """The ``1 / S`` line of :func:`fit_contact`: the contact ``ttc`` (frames after the newest
    frame; None without significant growth), its standard error, the t-statistic of the growth
    (positive = growing) and the growth rate d(log S)/dt (1/frame) at the newest frame."""

    ttc: float | None
    sigma: float | None
    tstat: float
    rate: float


def fit_contact(frames, log_scale) -> ContactFit | None:
    """Least-squares line ``1 / S = a + b t`` through the accumulated scale ``S = exp(log_scale)``.

    For an object approaching at constant speed ``1 / S`` falls linearly to 0 at contact, so
    the contact lies ``-a / b`` frames after the newest frame (t = 0 there, ``1 / S = 1``).
    None with fewer than 3 frames.
    """
    n = len(frames)
    if n < 3:
        return None
    # plain floats: a dozen points, so NumPy's per-call overhead would be most of the cost
    t_end, ls_end = float(frames[-1]), float(log_scale[-1])
    t = [float(f) - t_end for f in frames]
    y = [math.exp(ls_end - float(v)) for v in log_scale]
    tm, ym = sum(t) / n, sum(y) / n
    dt = [v - tm for v in t]
    sxx = sum([d * d for d in dt])
    if sxx <= 0:
        return None
    b = sum([d * (v - ym) for d, v in zip(dt, y)]) / sxx
    a = ym - b * tm
    s2 = sum([(v - (a + b * tv)) ** 2 for v, tv in zip(y, t)]) / max(n - 2, 1)
    sb = math.sqrt(s2 / sxx) if s2 > 0 else 1e-12
    tstat = -b / sb
    rate = -b / a if a > 0 else 0.0
    if not b < 0 or not a > 0:
        return ContactFit(None, None, tstat, rate)
    ttc = -a / b
    # delta method: var(a) = s2 (1/n + tm^2/sxx), cov(a, b) = -tm s2 / sxx
    va = s2 * (1.0 / n + tm * tm / sxx)
    cab = -tm * s2 / sxx
    ga, gb = -1.0 / b, a / (b * b)
    sigma = math.sqrt(max(ga * ga * va + 2 * ga * gb * cab + gb * gb * s2 / sxx, 0.0))
    return ContactFit(ttc, sigma, tstat, rate)


def fit_course(frames, xs, ys, widths, heading: tuple[float, float], ttc: float,
               heights=None) -> tuple[float, float] | None:
    """Predicted offset at contact from the heading point, per axis in the object's own extent
    along it ``(right, down)``: the lines through ``(x - x_h) / w`` and ``(y - y_h) / h`` over
    ``frames``, evaluated ``ttc`` frames after the newest one (``docs/targets.md``, step 6; its
    length is the miss distance). ``heights``: the box's heights (None: the widths, the course
    in widths on both axes)."""
    n = len(frames)
    heights = widths if heights is None else heights
    if n < 2 or any(float(w) <= 0 for w in widths) or any(float(v) <= 0 for v in heights):
        return None
    t_end = float(frames[-1])
    t = [float(f) - t_end for f in frames]
    tm = sum(t) / n
    dt = [v - tm for v in t]
    sxx = sum([d * d for d in dt])
    if sxx <= 0:
        return None

    def at(pos, origin, sizes):
        z = [(float(q) - origin) / float(w) for q, w in zip(pos, sizes)]
        zm = sum(z) / n
        b = sum([d * (v - zm) for d, v in zip(dt, z)]) / sxx
        return zm + b * (ttc - tm)

    return at(xs, heading[0], widths), at(ys, heading[1], heights)


def expansion_centre(xs, ys, log_scale, min_growth: float = 0.05) -> tuple[float, float] | None:
    """The point the box's image expands about (px): for a scaling by ``S`` about ``(x_e, y_e)``
    the centre moves as ``x = x_e + S (x_0 - x_e) / S_0``, a line in ``S``; the least-squares
    lines of ``x`` and ``y`` against ``S = exp(log_scale)`` give it as their value at ``S = 0``.
    None with fewer than 3 points or a growth (largest less smallest log-scale) under ``min_growth``
    (the lines' intercepts lie too far from the points to say anything)."""
    n = len(xs)
    if n < 3 or max(log_scale) - min(log_scale) < min_growth:
        return None
    top = max(log_scale)
    s = [math.exp(float(v) - top) for v in log_scale]
    sm = sum(s) / n
    ds = [v - sm for v in s]
    sss = sum([d * d for d in ds])

    def at0(q):
        qm = sum(float(v) for v in q) / n
        return qm - sm * sum([d * (float(v) - qm) for d, v in zip(ds, q)]) / sss

    return at0(xs), at0(ys)
