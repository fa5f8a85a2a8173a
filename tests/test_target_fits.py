"""The line fits of the target layer (mlplc2.targets.fit_contact, fit_course) against exact
constant-velocity approaches and against NumPy's least squares (np.polyfit) as the oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mlplc2.targets import fit_contact, fit_course


def approach(frames, contact):
    """log S of an object closing at constant speed that reaches the camera at frame ``contact``:
    ``S = Z0 / Z`` with ``Z`` linear in time."""
    return [math.log((contact - frames[0]) / (contact - f)) for f in frames]


@pytest.mark.parametrize("contact", [130.0, 260.5, 1000.0])
def test_contact_of_an_exact_approach(contact):
    frames = list(range(100, 112))
    fit = fit_contact(frames, approach(frames, contact))
    assert fit.ttc == pytest.approx(contact - frames[-1], rel=1e-9)
    assert fit.sigma == pytest.approx(0.0, abs=1e-6 * (contact - frames[-1]))
    assert fit.tstat > 1e6
    # the growth rate d(log S)/dt at the newest frame: 1 / (frames to contact)
    assert fit.rate == pytest.approx(1.0 / (contact - frames[-1]), rel=1e-9)


def test_contact_fit_matches_least_squares():
    rng = np.random.default_rng(3)
    for _ in range(50):
        n = int(rng.integers(3, 15))
        frames = [int(f) for f in np.sort(rng.choice(60, n, replace=False)) + 500]
        log_s = [float(v) for v in np.cumsum(rng.normal(0.02, 0.01, n))]
        fit = fit_contact(frames, log_s)
        t = np.array(frames, float) - frames[-1]
        y = np.exp(log_s[-1] - np.array(log_s))
        (b, a), unscaled = np.polyfit(t, y, 1, cov="unscaled")
        s2 = float(np.sum((y - (a + b * t)) ** 2)) / max(n - 2, 1)
        cov = s2 * unscaled                         # of (b, a)
        assert fit.tstat == pytest.approx(-b / math.sqrt(cov[0, 0]), rel=1e-7)
        if b < 0 < a:
            grad = np.array([a / b ** 2, -1.0 / b])  # of ttc = -a / b with respect to (b, a)
            assert fit.ttc == pytest.approx(-a / b, rel=1e-9)
            assert fit.sigma == pytest.approx(math.sqrt(grad @ cov @ grad), rel=1e-6)
        else:
            assert fit.ttc is None and fit.sigma is None


def test_contact_fit_needs_three_distinct_frames():
    assert fit_contact([1, 2], [0.0, 0.1]) is None
    assert fit_contact([5, 5, 5], [0.0, 0.1, 0.2]) is None
    receding = fit_contact(list(range(10)), [-0.02 * i for i in range(10)])
    assert receding.ttc is None and receding.tstat < 0


def test_course_of_a_constant_velocity_object():
    # x(t) = x0 + vx t, width w(t) = f W / Z(t): (x - xh) / w is linear in time
    frames = list(range(20, 32))
    contact = 60.0
    heading = (160.0, 120.0)
    big_x, big_y, width_m = 0.4, -0.2, 0.5           # metres at contact, object width
    xs, ys, ws = [], [], []
    for f in frames:
        z = (contact - f) * 0.1                     # metres
        ws.append(300.0 * width_m / z)
        xs.append(heading[0] + 300.0 * (big_x + 0.01 * (f - contact)) / z)
        ys.append(heading[1] + 300.0 * big_y / z)
    miss = fit_course(frames, xs, ys, ws, heading, contact - frames[-1])
    assert miss == pytest.approx((big_x / width_m, big_y / width_m), abs=1e-9)
    assert fit_course(frames[:1], xs[:1], ys[:1], ws[:1], heading, 10.0) is None
    assert fit_course(frames, xs, ys, [0.0] + ws[1:], heading, 10.0) is None
