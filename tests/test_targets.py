"""Issue 9: time to collision, expansion rate, bearing and threat ranking per attention field.

Ground truth: ``stimuli.looming`` / ``stimuli.scene(looming="physical")``, constant-speed
approaches with a known contact frame; true TTC at frame t = (contact_frame - t) / fps.

"Last second" (docs/targets.md): the frames t with 0 < contact_frame - t <= fps on which the
object is drawn. The generator stops an approach before the object outgrows the frame, so for
large or slow objects the window ends early (it is then shorter than one second).
A frame without an estimate counts as a miss (infinite error) in the median.
"""

from __future__ import annotations

import csv
import json
import math
import pickle

import numpy as np
import pytest

from mlplc2 import stimuli
from mlplc2._validation import InputTypeError, InputValueError
from mlplc2.attention import Field
from mlplc2.cli import main
from mlplc2.io import write_video
from mlplc2.models import LPLC2, MLPLC2, Output
from mlplc2.runner import COLUMNS, TARGET_COLUMNS
from mlplc2.targets import TargetParams, TargetTracker, bearing, edge_distance, fit_contact, focal_length

FPS = 30.0
HFOV = 60.0


def _last_second(obj, n):
    return [t for t in range(n) if obj.sizes[t] > 0 and 0 < obj.contact_frame - t <= FPS + 1e-9]


def _errors(stim, ttcs):
    """Relative TTC errors over the last second (None -> inf)."""
    obj = stim.objects[0]
    out = []
    for t in _last_second(obj, len(stim)):
        true = (obj.contact_frame - t) / FPS
        out.append(math.inf if ttcs[t] is None else abs(ttcs[t] - true) / true)
    return np.array(out)


def _run_model(stim, model):
    return [model.step(f) for f in stim.frames]


# ---------------------------------------------------------------------------
# pure functions
# ---------------------------------------------------------------------------
def test_fit_contact_is_exact_for_constant_speed():
    t = np.arange(10, 16)
    sizes = 300.0 / (40.0 - t)  # s = f L / (v (t_c - t)), contact at frame 40
    contact, slope, resid = fit_contact(t, sizes)
    assert contact == pytest.approx(40.0, abs=1e-9)
    assert slope < 0 and resid < 1e-12
    assert fit_contact(t, sizes[::-1]) is None  # shrinking: no contact
    assert fit_contact([3, 3], [10, 12]) is None


def test_robust_fit_keeps_the_newest_size():
    """A fit that drops the current size is no new fit and confirms nothing (the cause of a
    junk estimate persisting for 10 frames on a scrolling background, docs/targets.md)."""
    from collections import deque

    tr = TargetTracker(TargetParams(max_residual=0.1))   # loose enough to accept the junk fit first
    # junk first sizes of a field (true sizes ~66-72 px, contact at frame 75)
    tr.history = deque([(25, 83.2, 228, 121), (26, 90.5, 252, 121), (28, 85.2, 242, 120), (29, 110.1, 239, 143)])
    assert tr._refit(29) and not tr.confirmed
    junk = tr.contact
    for frame, size in [(30, 77.0), (31, 77.8)]:
        tr.history.append((frame, size, 240, 120))
        if tr._refit(frame):
            assert tr.history[-1][0] == frame       # the accepted fit kept the newest size
        assert not (tr.confirmed and abs(tr.contact - junk) < 1.5)


def test_robust_fit_matches_brute_force():
    """The fast paths of the subset search give the all-subsets answer (random histories)."""
    import itertools
    from collections import deque

    rng = np.random.default_rng(0)
    p = TargetParams()
    tr = TargetTracker(p)
    for _ in range(300):
        n = int(rng.integers(2, 7))
        frames = np.sort(rng.choice(np.arange(30, 42), n, replace=False))
        sizes = 400.0 / (rng.uniform(45, 90) - frames) * (1 + rng.normal(0, rng.choice([0.01, 0.05, 0.2]), n))
        sizes = np.abs(sizes) + 0.1
        tr.history = deque((int(f), float(v), 0.0, 0.0) for f, v in zip(frames, sizes))
        got = tr._robust_fit(int(frames[-1]))
        need = max(p.min_points, math.ceil(p.min_inliers * n))
        best = None
        for k in range(n, need - 1, -1):              # largest subset with the newest size, then smallest rms
            for keep in itertools.combinations(range(n - 1), k - 1):
                idx = list(keep) + [n - 1]
                t, y = frames[idx] - frames[-1], 1.0 / sizes[idx]
                if -t[0] < p.min_span:
                    continue
                b, a = np.polyfit(t, y, 1)
                rms = math.sqrt(np.mean(((y - a - b * t) / y) ** 2))
                if b < 0 < a and rms <= p.max_residual and -b / a / a / 2 <= p.max_edge_speed:
                    if best is None or rms < best[0]:
                        best = (rms, frames[-1] - a / b, tuple(idx))
            if best is not None:
                break
        assert (got is None) == (best is None)
        if got is not None:
            assert got[2] == best[2] and got[0] == pytest.approx(best[1], rel=1e-6)


# ---------------------------------------------------------------------------
# the Numba kernels (mlplc2._fast_targets) against the NumPy code (the oracle)
# ---------------------------------------------------------------------------
@pytest.fixture
def fast_targets():
    pytest.importorskip("numba")
    from mlplc2 import targets

    fast = targets._fast_targets()
    assert fast is not None
    return fast


def _numpy_path(monkeypatch):
    from mlplc2 import targets

    monkeypatch.setattr(targets, "_FAST", False)


def _random_lm(rng, h, w, kind):
    """LM maps with edges (lobes of several widths), noise, exact ties and all-negative strips."""
    from mlplc2.lobula_plate import LocalMotion

    maps = []
    for _ in range(4):
        if kind == "ties":        # few distinct values: ties everywhere (floors, peaks, boundaries)
            a = rng.integers(-2, 4, (h, w)).astype(np.float32) * np.float32(0.25)
        elif kind == "negative":  # no outward motion: the profiles are <= 0
            a = -rng.random((h, w), dtype=np.float32)
        elif kind == "zeros":
            a = np.zeros((h, w), np.float32)
        else:
            a = (rng.normal(0, {"quiet": 0.01, "noisy": 0.3}[kind], (h, w))).astype(np.float32)
            for _ in range(int(rng.integers(1, 6))):    # edges: lobes, some close together
                c = int(rng.integers(0, max(w, h)))
                amp = float(rng.choice([0.05, 0.5, 2.0]))
                width = int(rng.integers(1, 8))
                if rng.random() < 0.5:
                    a[:, c:c + width] += np.float32(amp)
                else:
                    a[c:c + width, :] += np.float32(amp)
        maps.append(a)
    return LocalMotion(r=maps[0], l=maps[1], d=maps[2], u=maps[3], magnitude=np.abs(maps[0]))


@pytest.mark.parametrize("kind", ["quiet", "noisy", "ties", "negative", "zeros"])
def test_fast_extent_matches_numpy(fast_targets, kind):
    """edges4 gives the NumPy path's four edge distances bit for bit (every border, odd params)."""
    from mlplc2.targets import _edge_distances, _strip_profiles

    rng = np.random.default_rng(7)
    params = [TargetParams(), TargetParams(min_peak=0.0), TargetParams(noise_k=0.0), TargetParams(band=0, gap=0),
              TargetParams(band=5, local=0, rel_start=1.0), TargetParams(rel_edge=1.0, noise_k=10.0),
              TargetParams(rel_edge=0.0, min_peak=0.0, noise_k=0.0)]
    checked = found = 0
    for h, w in [(240, 320), (31, 17), (3, 2), (1, 1)]:
        lm = _random_lm(rng, h, w, kind)
        pts = [(0, 0), (w - 1, h - 1), (0, h - 1), (w - 1, 0), (1, 1), (w // 2, h // 2)]
        pts += [(int(rng.integers(0, w)), int(rng.integers(0, h))) for _ in range(20)]
        pts = [(min(x, w - 1), min(y, h - 1)) for x, y in pts]     # inside the frame (as measure_extent)
        for p in params:
            for x, y in pts:
                prof, lens, scale = _strip_profiles(lm, x, y, p.band)
                want = _edge_distances(prof, lens, scale, p)
                got = fast_targets.edges4(lm.r, lm.l, lm.u, lm.d, x, y, p.band, p.min_peak, p.noise_k,
                                          p.rel_start, p.rel_edge, p.gap, p.local)
                assert [None if v < 0 else v for v in got] == want, (h, w, x, y, p)
                checked += 1
                found += sum(v is not None for v in want)
    assert checked and (found > 0) == (kind not in ("negative", "zeros"))


def test_fast_measure_extent_matches_numpy(fast_targets, monkeypatch):
    """measure_extent (fast by default) equals the NumPy path, float64 maps included."""
    from mlplc2.lobula_plate import LocalMotion
    from mlplc2.targets import measure_extent

    rng = np.random.default_rng(3)
    cases = []
    for kind in ("quiet", "noisy", "ties"):
        lm = _random_lm(rng, 120, 160, kind)
        cases.append(lm)
        cases.append(LocalMotion(*(getattr(lm, n).astype(np.float64) for n in ("r", "l", "d", "u", "magnitude"))))
    pts = [(-5, 300), (0, 0), (159, 119)] + [(int(rng.integers(0, 160)), int(rng.integers(0, 120))) for _ in range(30)]
    fast = [measure_extent(lm, x, y) for lm in cases for x, y in pts]
    _numpy_path(monkeypatch)
    assert [measure_extent(lm, x, y) for lm in cases for x, y in pts] == fast
    assert sum(e.width is not None for e in fast) > 10


def _history(rng, n, kind):
    frames = np.sort(rng.choice(np.arange(30, 42), n, replace=False))
    if kind == "constant":      # no growth: the slope is 0 up to rounding (its sign decides)
        sizes = np.full(n, float(rng.choice([40.0, 55.3, 1.0 / 3.0])))
        if rng.random() < 0.5:
            sizes[int(rng.integers(0, n))] *= 1 + rng.choice([1e-15, 0.3, -0.3])
    else:
        sizes = 400.0 / (rng.uniform(45, 90) - frames) * (1 + rng.normal(0, rng.choice([0.01, 0.05, 0.2]), n))
        sizes = np.abs(sizes) + 0.1
    return [(int(f), float(v), 0.0, 0.0) for f, v in zip(frames, sizes)]


def test_fast_robust_fit_matches_numpy(fast_targets, monkeypatch):
    """The compiled fits equal the NumPy path's bit for bit (the full set and the subset search)."""
    from collections import deque

    rng = np.random.default_rng(11)
    tr = TargetTracker(TargetParams())
    hists = [_history(rng, int(rng.integers(2, 7)), kind) for kind in ("growth", "constant") for _ in range(400)]
    hists.append([(30, 40.0, 0, 0), (31, -1.0, 0, 0), (32, 42.0, 0, 0), (33, 43.0, 0, 0)])   # a size <= 0
    fast = []
    for hist in hists:
        tr.history = deque(hist)
        fast.append(tr._robust_fit(hist[-1][0]))
    _numpy_path(monkeypatch)
    for hist, got in zip(hists, fast):
        tr.history = deque(hist)
        assert got == tr._robust_fit(hist[-1][0]), hist
    assert sum(r is not None and len(r[2]) < len(h) for r, h in zip(fast, hists)) > 10     # a subset won
    assert sum(r is not None and r[2] == tuple(range(len(h))) for r, h in zip(fast, hists)) > 10


@pytest.mark.parametrize("make", [lambda: stimuli.six_objects().frames[:90],
                                  lambda: _two_objects(False, 1.0, 1).frames])
def test_fast_targets_model_estimates_identical(fast_targets, monkeypatch, make):
    """The model gives the same estimates per field per frame with and without the kernels."""
    frames = make()

    def run():
        model = MLPLC2(fps=FPS, hfov_deg=HFOV)
        return [[(fl.id, fl.ttc_s, fl.expansion_rate, fl.azimuth_deg, fl.elevation_deg, fl.rank)
                 for fl in model.step(f).fields]
                + [(fl.id, fl.estimate) for fl in model._fields] for f in frames]

    fast = run()
    _numpy_path(monkeypatch)
    assert run() == fast
    assert sum(fl[1] is not None for out in fast for fl in out if len(fl) == 6) > 20


def test_edge_distance_outer_boundary_and_nearest_edge():
    p = np.zeros(120)
    p[20:26] = [1, 4, 8, 8, 4, 1]           # this object's edge
    p[80:86] = [10, 40, 80, 80, 40, 10]     # a much stronger edge of another object further out
    d = edge_distance(p)
    # outer boundary at 25 % of the lobe peak (8 -> 2), between distances 25 and 26
    assert 25.0 < d < 26.0
    q = np.zeros(60)
    q[55:60] = 5.0                          # complex running into the frame border
    assert edge_distance(q) is None
    assert edge_distance(np.zeros(50)) is None
    noisy = np.full(100, 1.0)               # uniform noise: nothing stands out
    assert edge_distance(noisy) is None


def test_bearing_sign_convention():
    shape = (240, 320)
    f = focal_length(320, 60.0)
    assert f == pytest.approx(160 / math.tan(math.radians(30)))
    assert bearing(159.5, 119.5, shape, f) == pytest.approx((0.0, 0.0))
    az, el = bearing(319.5, 0.0, shape, f)
    assert az == pytest.approx(30.0) and el > 0           # right and up are positive
    assert bearing(0.0, 239.0, shape, None) == pytest.approx((-159.5, -119.5))  # pixels without hfov


def test_target_params_and_hfov_validated():
    with pytest.raises(ValueError):
        TargetParams(window=-1)
    with pytest.raises(ValueError):
        TargetParams(min_points=1)
    for bad in (0, 180, -5, float("nan")):
        with pytest.raises(InputValueError):
            MLPLC2(fps=FPS, hfov_deg=bad)
    for bad in ("wide", "60", True):
        with pytest.raises(InputTypeError):
            MLPLC2(fps=FPS, hfov_deg=bad)
    with pytest.raises(TypeError):
        MLPLC2(FPS, None, 60.0)  # hfov_deg is keyword-only


@pytest.mark.parametrize("kwargs", [
    dict(window=0), dict(window=1), dict(rel_edge=1.01), dict(rel_start=1.5), dict(min_inliers=2.0),
    dict(window=17), dict(min_points=7), dict(lag=float("inf")), dict(max_shift=float("nan")),
    dict(edge_offset=1e39), dict(band=True), dict(window=6.0), dict(coast_frames=2**40)])
def test_target_params_reject_values_that_crash_the_tracker(kwargs):
    """window=0 (IndexError in _median) and rel_edge > 1 (IndexError in the edge scan) passed
    validation and crashed in model.step(); now every bad value fails at construction."""
    with pytest.raises(InputValueError) as info:
        TargetParams(**kwargs)
    assert str(info.value).startswith("TargetParams.") and "\n" not in str(info.value)


@pytest.mark.parametrize("value", ["0.3", None, np.array([0.3]), [0.3]])
def test_target_params_type_errors(value):
    with pytest.raises(InputTypeError, match="TargetParams.rel_start must be a number"):
        TargetParams(rel_start=value)
    with pytest.raises(InputTypeError, match="TargetParams.window"):
        TargetParams(window=value)


def test_target_params_numpy_scalars_stored_as_python_numbers():
    p = TargetParams(window=np.int64(8), band=np.int32(3), lag=np.float32(1.5), rel_edge=np.float64(0.25))
    assert (type(p.window), type(p.band), type(p.lag), type(p.rel_edge)) == (int, int, float, float)
    assert p == TargetParams(window=8, band=3, lag=1.5)
    assert TargetParams(window=16, min_points=2, min_inliers=0.0).window == 16      # the bounds are valid
    assert TargetParams(rel_edge=1.0, rel_start=0.0, min_inliers=1.0).rel_edge == 1.0


def test_output_most_urgent_and_threats():
    a = Field(1, 10, 10, 40, response=500.0, collision=False, born=0, ttc_s=1.2, rank=2)
    b = Field(2, 50, 10, 40, response=10.0, collision=False, born=0, ttc_s=0.4, rank=1)
    c = Field(3, 90, 10, 40, response=900.0, collision=False, born=0)
    out = Output(frame=0, response=900.0, fields=(a, b, c))
    assert out.most_urgent is b
    assert out.threats == (b, a)
    no_ttc = Output(frame=0, response=900.0, fields=(c, Field(4, 0, 0, 40, 5.0, False, 0)))
    assert no_ttc.most_urgent is c and no_ttc.threats == ()
    assert Output(frame=0, response=0.0).most_urgent is None


# ---------------------------------------------------------------------------
# time to collision on generated constant-speed approaches
# ---------------------------------------------------------------------------
# (polarity, background, half_size m, speed m/s, centre) -- l / v from 0.05 s to 0.2 s,
# centred and off-centre; the image trajectory depends on l / v only.
DARK_GRID = [
    ("plain", 0.5, 5.0, None),
    ("plain", 1.0, 5.0, (90, 70)),
    ("plain", 0.25, 5.0, (230, 170)),
    ("procedural", 0.5, 5.0, (230, 170)),
    ("procedural", 0.5, 2.5, None),
    ("procedural", 1.0, 10.0, (100, 150)),
]


@pytest.mark.parametrize("polarity,background", [("dark", "plain"), ("bright", "plain"),
                                                 ("dark", "procedural"), ("bright", "procedural")])
def test_ttc_estimator_on_model_maps(polarity, background):
    """The estimator itself, fed with the model's own LM maps at the object's centre.

    Separates the estimator from the attention mechanism: on a textured background mLPLC2
    gives a bright approach its fields late, on the corners (docs/targets.md).
    """
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, background=background,
                           polarity=polarity, hfov_deg=HFOV)
    x, y = (int(v) for v in stim.objects[0].center)
    model, tracker = MLPLC2(fps=FPS), TargetTracker()
    ttcs = []
    for t, frame in enumerate(stim.frames):
        model.step(frame)
        ttcs.append(tracker.update(model.maps, x, y, t, FPS).ttc_s)
    err = _errors(stim, ttcs)
    assert np.median(err) < 0.25, (np.round(err, 2), np.median(err))


# Bright squares: plain background across l / v and positions; on the textured background
# the cases where mLPLC2 gives the square a field early enough (docs/targets.md, "Bright square").
BRIGHT_GRID = [
    ("plain", 0.5, 5.0, None),
    ("plain", 0.5, 5.0, (90, 70)),
    ("plain", 1.0, 5.0, None),
    ("plain", 1.0, 2.5, (90, 70)),
    ("procedural", 1.0, 5.0, (90, 70)),
    ("procedural", 1.0, 2.5, None),
]


# Frames of the last second that must carry an estimate: dark squares get their fields earlier.
MIN_ESTIMATES = {"dark": 15, "bright": 10}


@pytest.mark.parametrize("polarity,background,half_size,speed,center",
                         [("dark", *case) for case in DARK_GRID] + [("bright", *case) for case in BRIGHT_GRID])
def test_ttc_approach_end_to_end(polarity, background, half_size, speed, center):
    stim = stimuli.looming(half_size=half_size, speed=speed, contact_time=2.0, center=center,
                           background=background, polarity=polarity, hfov_deg=HFOV)
    outs = _run_model(stim, MLPLC2(fps=FPS, hfov_deg=HFOV))
    err = _errors(stim, [None if o.most_urgent is None else o.most_urgent.ttc_s for o in outs])
    assert err.size >= MIN_ESTIMATES[polarity]
    assert np.median(err) < 0.25, (np.round(err, 2), np.median(err))
    # the ranking attribute agrees with the order of the estimates
    for o in outs:
        ranked = sorted((f for f in o.fields if f.rank is not None), key=lambda f: f.rank)
        assert [f.rank for f in ranked] == list(range(1, len(ranked) + 1))
        assert [f.ttc_s for f in ranked] == sorted(f.ttc_s for f in ranked)
        assert all((f.rank is None) == (f.ttc_s is None) for f in o.fields)


def test_lplc2_frame_cell_estimates_ttc_too():
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, hfov_deg=HFOV)
    outs = _run_model(stim, LPLC2(fps=FPS))
    err = _errors(stim, [o.fields[0].ttc_s if o.fields else None for o in outs])
    assert np.median(err) < 0.25


def test_no_estimate_without_expansion():
    """Translating bar and static scene: no time to collision."""
    stim = stimuli.generate("translating")
    outs = _run_model(stim, MLPLC2(fps=FPS))
    assert all(f.ttc_s is None for o in outs for f in o.fields)
    still = np.full((20, 120, 160), 128, np.uint8)
    still[:, 40:80, 60:100] = 0
    model = MLPLC2(fps=FPS)
    assert all(not model.step(frame).fields for frame in still)


# ---------------------------------------------------------------------------
# ranking: two objects approaching at once
# ---------------------------------------------------------------------------
def _two_objects(swap: bool, scroll: float, seed: int = 0):
    # The later-contact object is *larger* on the image, so ranking by size or response would fail.
    spec = [((80, 120), 0.5, 60.0), ((240, 120), 1.0, 75.0)]
    if swap:
        spec = [((80, 120), 1.0, 75.0), ((240, 120), 0.5, 60.0)]
    objs = [stimuli.SceneObject(center=c, approach=48, hold=0, recede=0, looming="physical", half_size=h,
                                speed=5.0, contact_frame=tc) for c, h, tc in spec]
    return stimuli.scene(objs, size=(320, 240), frames=48, background="procedural", scroll=scroll,
                         hfov_deg=HFOV, seed=seed)


# Several background seeds: on a scrolling background the early sizes of the later object are
# junk on some seeds and not others (a fit to junk once ranked it first, see docs/targets.md).
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("swap,scroll", [(False, 0.0), (True, 0.0), (False, 1.0)])
def test_ranking_puts_earlier_contact_first(swap, scroll, seed):
    stim = _two_objects(swap, scroll, seed)
    f = stimuli.focal_length_px(320, HFOV)
    earlier = min(stim.objects, key=lambda o: o.contact_frame).id

    def owner(fl):  # the object the field's bearing points at
        x = 159.5 + f * math.tan(math.radians(fl.azimuth_deg))
        y = 119.5 - f * math.tan(math.radians(fl.elevation_deg))
        return min(stim.objects, key=lambda o: math.hypot(x - o.center[0], y - o.center[1])).id

    good = bad = 0
    for out in _run_model(stim, MLPLC2(fps=FPS, hfov_deg=HFOV)):
        if len({owner(fl) for fl in out.threats}) == 2:  # both objects have an estimate
            assert out.threats[0] is out.most_urgent and out.most_urgent.rank == 1
            if owner(out.most_urgent) == earlier:
                good += 1
            else:
                bad += 1
    assert good >= 8 and good >= 9 * bad, (good, bad)


# ---------------------------------------------------------------------------
# bearing
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("center,hfov", [((230, 170), 60.0), ((90, 70), 60.0), ((200, 80), 90.0)])
def test_bearing_of_an_approaching_object(center, hfov):
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, center=center, hfov_deg=hfov)
    f = stimuli.focal_length_px(320, hfov)
    want_az = math.degrees(math.atan((center[0] - 160) / f))
    want_el = math.degrees(math.atan((120 - center[1]) / f))
    outs = _run_model(stim, MLPLC2(fps=FPS, hfov_deg=hfov))
    est = [o.most_urgent for o in outs[-20:] if o.most_urgent is not None and o.most_urgent.ttc_s is not None]
    assert len(est) >= 10
    assert abs(np.median([e.azimuth_deg for e in est]) - want_az) < 1.0
    assert abs(np.median([e.elevation_deg for e in est]) - want_el) < 1.0
    for e in est:
        assert abs(e.azimuth_deg - want_az) < 1.0 and abs(e.elevation_deg - want_el) < 1.0
        assert e.expansion_rate > 0


def test_bearing_only_with_time_to_collision():
    """docs/targets.md: ttc_s, expansion_rate, azimuth_deg, elevation_deg and rank are set
    together or all None. The bearing used to fall back to the field centre (born on an edge
    or corner of the object, up to ~14 deg off) while no TTC existed."""
    center = (230, 170)
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, center=center, hfov_deg=HFOV)
    f = stimuli.focal_length_px(320, HFOV)
    want = (math.degrees(math.atan((center[0] - 159.5) / f)), math.degrees(math.atan((119.5 - center[1]) / f)))
    names = ("ttc_s", "expansion_rate", "azimuth_deg", "elevation_deg", "rank")
    with_ttc = without = 0
    for out in _run_model(stim, MLPLC2(fps=FPS, hfov_deg=HFOV)):
        for fl in out.fields:
            vals = [getattr(fl, k) for k in names]
            assert all(v is None for v in vals) or all(v is not None for v in vals), (out.frame, vals)
            if fl.ttc_s is None:
                without += 1
            else:
                with_ttc += 1
                assert abs(fl.azimuth_deg - want[0]) < 1.0 and abs(fl.elevation_deg - want[1]) < 1.0
    assert with_ttc >= 10 and without >= 5      # both cases occur
    # an estimate longer than max_ttc_s ("no measurable approach") carries no rate or bearing either
    outs = _run_model(stim, MLPLC2(fps=FPS, hfov_deg=HFOV, target_params=TargetParams(max_ttc_s=0.0)))
    assert all(getattr(fl, k) is None for o in outs for fl in o.fields for k in names)
    assert sum(len(o.fields) for o in outs) > 20


def test_bearing_in_pixels_without_hfov():
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, center=(230, 170))
    outs = _run_model(stim, MLPLC2(fps=FPS))
    est = [o.most_urgent for o in outs[-15:] if o.most_urgent is not None and o.most_urgent.ttc_s is not None]
    assert est
    assert abs(np.median([e.azimuth_deg for e in est]) - 70.0) < 3.0     # 230 - 160 px, right
    assert abs(np.median([e.elevation_deg for e in est]) + 50.0) < 3.0   # 50 px below the centre


def test_model_with_estimates_pickles_and_resets():
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0)
    m = MLPLC2(fps=FPS, hfov_deg=HFOV)
    first = [o.most_urgent and o.most_urgent.ttc_s for o in _run_model(stim, m)]
    clone = pickle.loads(pickle.dumps(m))
    assert clone.hfov_deg == HFOV
    m.reset()
    again = [o.most_urgent and o.most_urgent.ttc_s for o in _run_model(stim, m)]
    assert first == again


# ---------------------------------------------------------------------------
# command line
# ---------------------------------------------------------------------------
def test_cli_run_writes_targets(tmp_path, capsys):
    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0, center=(200, 100))
    video = write_video(tmp_path / "loom.avi", stim.frames, FPS)
    out = tmp_path / "res"
    assert main(["run", str(video), "--out", str(out), "--hfov", "60", "--quiet"]) == 0
    with open(out / "responses.csv", newline="") as fh:
        assert next(csv.reader(fh)) == list(COLUMNS)
    with open(out / "targets.csv", newline="") as fh:
        reader = csv.reader(fh)
        assert next(reader) == list(TARGET_COLUMNS["deg"]) == ["frame", "model", "field_id", "ttc_s",
                                                               "expansion_rate_deg_s", "azimuth_deg",
                                                               "elevation_deg", "rank"]
        rows = [dict(zip(TARGET_COLUMNS["deg"], r)) for r in reader]
    timed = [r for r in rows if r["ttc_s"]]
    assert timed and all(r["rank"] for r in timed)
    last = max(int(r["frame"]) for r in timed)
    final = [r for r in timed if int(r["frame"]) == last and r["rank"] == "1"][0]
    true = (stim.objects[0].contact_frame - last) / FPS
    assert abs(float(final["ttc_s"]) - true) / true < 0.25
    f = stimuli.focal_length_px(320, 60.0)
    assert abs(float(final["azimuth_deg"]) - math.degrees(math.atan(40 / f))) < 1.0
    summary = json.loads((out / "fields.json").read_text())
    assert summary["hfov_deg"] == 60.0
    fields = summary["models"]["mlplc2"]
    assert all("at_peak" in fl and "last_estimate" in fl for fl in fields)
    assert any(fl["last_estimate"] and fl["last_estimate"]["ttc_s"] is not None for fl in fields)
    assert all(list(fl["at_peak"]) == ["ttc_s", "expansion_rate_deg_s", "azimuth_deg", "elevation_deg", "rank"]
               for fl in fields)
    # without a field of view the same columns are pixels, and say so
    assert main(["run", str(video), "--out", str(tmp_path / "px"), "--start", "30", "--quiet"]) == 0
    with open(tmp_path / "px" / "targets.csv", newline="") as fh:
        reader = csv.reader(fh)
        assert next(reader) == list(TARGET_COLUMNS["px"]) == ["frame", "model", "field_id", "ttc_s",
                                                              "expansion_rate_px_s", "azimuth_px", "elevation_px",
                                                              "rank"]
        px = [dict(zip(TARGET_COLUMNS["px"], r)) for r in reader]
    px_timed = [r for r in px if r["ttc_s"]]
    assert px_timed and all(abs(float(r["azimuth_px"]) - 40) < 4 for r in px_timed)  # 200 - 160 px, right
    summary = json.loads((tmp_path / "px" / "fields.json").read_text())
    assert summary["hfov_deg"] is None
    estimates = [fl[k] for fl in summary["models"]["mlplc2"] for k in ("at_peak", "last_estimate") if fl[k]]
    assert estimates and all("azimuth_px" in e and "expansion_rate_px_s" in e and "azimuth_deg" not in e
                             for e in estimates)
    # a field of view outside (0, 180): one error line, exit 2
    assert main(["run", str(video), "--out", str(tmp_path / "bad"), "--hfov", "180", "--quiet"]) == 2
    assert "--hfov" in capsys.readouterr().err


def test_run_refuses_models_with_different_fields_of_view(tmp_path):
    """One targets.csv has one unit: models in degrees and in pixels cannot share a run."""
    from mlplc2 import SLPLC2, run

    stim = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0)
    video = write_video(tmp_path / "loom.avi", stim.frames[:5], FPS)
    out = tmp_path / "res"
    with pytest.raises(InputValueError, match=r"different fields of view \(hfov_deg 60.0, None\)"):
        run(video, [MLPLC2(fps=FPS, hfov_deg=60.0), SLPLC2(fps=FPS)], out=out, progress=False)
    assert not (out / "targets.csv").exists()
    res = run(video, [MLPLC2(fps=FPS, hfov_deg=60.0), SLPLC2(fps=FPS)], out=False, hfov_deg=60.0)
    assert res.n_frames == 5  # the run's hfov_deg gives both the same
