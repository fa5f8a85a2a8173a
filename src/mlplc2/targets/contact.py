"""Time to contact and course from a track's history.

:func:`fit_contact`: the least-squares line ``1 / S = a + b t`` through the accumulated scale
``S``, contact at ``-a / b`` frames, its standard error by the delta method (:class:`ContactFit`);
:func:`fit_course`: the lines through the centre's offset from the heading point in object
widths (horizontally) and heights (vertically), evaluated at contact (the miss distance;
``docs/targets.md``, steps 5-6);
:func:`fit_centre_course`: the same miss from the box's own expansion centre, neither the heading nor the time to
contact needed; :func:`expansion_centre`: that fixed point of the box's scaling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["ContactFit", "fit_contact", "fit_course", "fit_centre_course", "expansion_centre"]


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


def _against_scale(log_scale, min_growth: float):
    """``S = exp(log_scale)`` (1 at the newest point) and the line-fit of a series against it: a function of a
    series giving its least-squares ``(intercept at S = 0, slope)``; None with fewer than 3 points or a growth
    (largest less smallest log-scale) under ``min_growth`` (the line's ends lie too far from the points to say
    anything)."""
    n = len(log_scale)
    if n < 3 or max(log_scale) - min(log_scale) < min_growth:
        return None
    top = float(log_scale[-1])
    s = [math.exp(float(v) - top) for v in log_scale]
    sm = sum(s) / n
    ds = [v - sm for v in s]
    sss = sum([d * d for d in ds])
    if sss <= 0:
        return None

    def line(q):
        qm = sum(float(v) for v in q) / n
        slope = sum([d * (float(v) - qm) for d, v in zip(ds, q)]) / sss
        return qm - sm * slope, slope

    return s, line


def expansion_centre(xs, ys, log_scale, min_growth: float = 0.05) -> tuple[float, float] | None:
    """The point the box's image expands about (px): for a scaling by ``S`` about ``(x_e, y_e)``
    the centre moves as ``x = x_e + S (x_0 - x_e) / S_0``, a line in ``S``; the least-squares
    lines of ``x`` and ``y`` against ``S = exp(log_scale)`` give it as their value at ``S = 0``.
    None with fewer than 3 points or a growth (largest less smallest log-scale) under ``min_growth``
    (the lines' intercepts lie too far from the points to say anything)."""
    fit = _against_scale(log_scale, min_growth)
    if fit is None:
        return None
    return fit[1](xs)[0], fit[1](ys)[0]


def fit_centre_course(xs, ys, log_scale, widths, heights=None,
                      min_growth: float = 0.05) -> tuple[float, float] | None:
    """Predicted offset at contact per axis in the object's own extent ``(right, down)``, as :func:`fit_course`'s,
    from the box's own expansion centre: an object at a lateral offset ``X`` (its width ``W``) images at
    ``x = x_h + f X / Z`` with width ``w = f W / Z``, and at a constant closing velocity ``X / W`` is linear in time
    and ``1 / w`` too, so ``x = x_e + m w``: the centre is a line in the box's size whose slope ``m`` is ``X / W`` at
    contact (``1 / w = 0``) and whose intercept is the expansion centre ``x_e`` (the image of the closing
    velocity, the heading for the static world). The slope of the line of ``x`` against ``S = exp(log_scale)``
    (the alignment's accumulated scale, steadier than the box's width) over the box's size per unit ``S`` (``w = c S``,
    least squares through the origin) is ``m``. Neither the heading point nor the time to contact enters: a collider
    far off the principal point (one a panning camera turns towards, seen in stabilised pixels) keeps its centre
    as it grows, a slope of 0, where the line in time evaluated at a time to contact 20 % long misses by 20 % of its
    offset in widths (docs/targets.md, step 6). None as :func:`expansion_centre` (too few points or too little
    growth), or without a positive size. ``heights``: the box's heights (None: the widths)."""
    heights = widths if heights is None else heights
    fit = _against_scale(log_scale, min_growth)
    if fit is None:
        return None
    s, line = fit
    s2 = sum(v * v for v in s)
    cw = sum(float(w) * v for w, v in zip(widths, s)) / s2
    ch = sum(float(h) * v for h, v in zip(heights, s)) / s2
    if cw <= 0 or ch <= 0:
        return None
    return line(xs)[1] / cw, line(ys)[1] / ch
