"""The fast front end (mlplc2.neuropils._fast_frontend) against the reference (mlplc2.neuropils.frontend.FrontEnd), the oracle.

LM maps agree to 1e-4 of their largest value (in practice ~1e-6: only x ** 0.9 is computed
differently); mLPLC2 with either backend makes the same fields. No timings here: see
``mlplc2 bench`` and benchmarks/README.md.
"""

from __future__ import annotations

import copy
import functools
import logging
import pickle

import numba
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.neuropils import _fast, _fast_attention, _fast_frontend, attention
from mlplc2.backend import make_frontend
from mlplc2.neuropils.frontend import FrontEnd
from mlplc2.neuropils.lobula_plate import LocalMotion

from .conftest import read_gray

MAPS = ("r", "l", "d", "u", "magnitude")


RTOL = 1e-4
ATOL = 1e-6


def assert_maps_close(ref: LocalMotion, fast: LocalMotion, where: str = "") -> None:
    for name in MAPS:
        a, b = getattr(ref, name), getattr(fast, name)
        assert a.shape == b.shape and b.dtype == np.float32
        scale = float(np.abs(a).max())
        err = float(np.abs(a - b).max())
        assert err <= RTOL * scale + ATOL, f"{where} LM_{name}: max |fast - ref| = {err:g}, max |ref| = {scale:g}"


def run_both(frames, params=None, fps=30.0, fast=None):
    params = mlplc2.Params() if params is None else params
    ref = FrontEnd(params, fps)
    fast = _fast_frontend.FastFrontEnd(params, fps) if fast is None else fast
    for i, frame in enumerate(frames):
        gray = np.asarray(frame, np.float32)
        assert_maps_close(ref.step(gray), fast.step(gray), where=f"frame {i}")
    return ref, fast


@functools.lru_cache(maxsize=1)
def four_phase() -> np.ndarray:
    frames = stimuli.four_phase().frames
    frames.flags.writeable = False
    return frames


def noise(shape, n=8, seed=0):
    return np.random.default_rng(seed).integers(0, 256, (n, *shape)).astype(np.uint8)


# --- LM maps -------------------------------------------------------------------------------
STIMULI = {
    "four_phase": lambda: four_phase()[:14],
    "four_phase_two_objects": lambda: four_phase()[318:330],
    "dark_approach": lambda: stimuli.basic("dark_approach").frames[::3],
    "bright_recede": lambda: stimuli.basic("bright_recede").frames[::4],
    "grating": lambda: stimuli.basic("grating").frames[:10],
    "translating": lambda: stimuli.basic("translating").frames[::4],
    "noise_37x53": lambda: noise((37, 53)),
    "noise_5x7": lambda: noise((5, 7)),
    "noise_3x3": lambda: noise((3, 3)),
    "noise_tall_300x41": lambda: noise((300, 41), n=5),
}


@pytest.mark.parametrize("name", list(STIMULI))
def test_lm_maps_match_reference(name):
    run_both(STIMULI[name]())


PARAMS = {
    "extras": mlplc2.Params(after_image=0.1, average_distances=False, n_c=3, tau_1=60.0, beta=1.0),
    "gammas": mlplc2.Params(gamma_on=0.7, gamma_off=1.3, leaky_slope=0.01, lm_gain=10.0, epsilon=0.2),
    "square_gammas_literal_kernels": mlplc2.Params(gamma_on=2.0, gamma_off=1.0, normalise_kernels=False,
                                                   r_i=4, r_e=2, r_c=7, w_i=0.5),
}


@pytest.mark.parametrize("fps", [30.0, 120.0, 7.5])
@pytest.mark.parametrize("variant", list(PARAMS))
def test_lm_maps_match_reference_other_params(variant, fps):
    frames = list(four_phase()[20:28, 30:150, 60:260]) + list(noise((120, 200), n=3))
    run_both(frames, PARAMS[variant], fps)


def test_state_before_the_power_is_bit_identical():
    """Everything up to T4/T5 uses the reference's own float32 operations (same OpenCV
    Gaussians, same numpy tanh, same order, no fused multiply-add): N and M-hat are
    bit-identical; only x ** gamma differs (within 1e-6)."""
    ref, fast = run_both(four_phase()[:8])
    pad = fast._pad
    n_prev = fast._n_prev[:, pad:-pad, pad:-pad]
    assert np.array_equal(n_prev[0], ref.state.n_prev["on"])
    assert np.array_equal(n_prev[1], ref.state.n_prev["off"])
    assert not fast._n_prev[:, :pad].any() and not fast._n_prev[:, :, -pad:].any()  # zero border
    for c, channel in enumerate(("on", "off")):
        for k, direction in enumerate("rldu"):
            assert np.array_equal(fast._m[c, k], ref.state.m_prev[channel][direction])


def _assert_same_state(ref, fast):
    pad = fast._pad
    _assert_same_warp(fast._p[0], ref.state.p_prev)
    _assert_same_warp(fast._n_prev[0, pad:-pad, pad:-pad], ref.state.n_prev["on"])
    _assert_same_warp(fast._n_prev[1, pad:-pad, pad:-pad], ref.state.n_prev["off"])
    assert not fast._n_prev[:, :pad].any() and not fast._n_prev[:, :, -pad:].any()  # zero border
    for c, channel in enumerate(("on", "off")):
        for k, direction in enumerate("rldu"):
            _assert_same_warp(fast._m[c, k], ref.state.m_prev[channel][direction])
            _assert_same_warp(fast._m_rows[:, c, k], ref.state.m_prev[channel][direction])


def _assert_same_warp(fast, ref):
    """A plane carried by the compiled front end (a four-channel warp for M-hat, warps shared over
    threads) against the reference's one warp per plane: bit for bit with OpenCV 5.0. OpenCV 5.1
    computes a few pixels next to the uncovered border along another path (four channels; a warp
    run in a worker thread): measured at most 30 of 76 800 pixels, 1e-10 apart on values of
    0.01-0.08, a float32 unit in the last place; those may differ by that much, nothing else."""
    if np.array_equal(fast, ref):
        return
    differ = fast != ref
    assert np.count_nonzero(differ) <= 1e-3 * ref.size, "the warp differs beyond OpenCV's border sampling"
    np.testing.assert_allclose(fast, ref, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("threads", [1, 2])
def test_the_carried_state_is_the_references_bit_for_bit(threads):
    """Gaze stabilisation: the compiled front end warps P(t-1), N(t-1) and M-hat(t-1) into its
    spare buffers, shared over its threads, and swaps them; the carried state, and the state of
    the next frames, are the reference's (one warp per plane) bit for bit, on one thread or two."""
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip("one core")
    old = numba.get_num_threads()
    _fast.set_threads(threads)
    try:
        frames = [np.asarray(f, np.float32) for f in four_phase()[20:30]]      # 320 x 240: two bands
        ref, fast = run_both(frames[:6])
        assert len(fast._bands) == threads
        turn = np.array([[0.999, 0.02, 2.3], [-0.02, 0.999, -1.4], [1e-5, -2e-5, 1.0]])
        for gray in frames[6:]:
            ref.compensate(turn, gray)
            fast.compensate(turn, gray)
            _assert_same_state(ref, fast)
            assert_maps_close(ref.step(gray), fast.step(gray))
        _assert_same_state(ref, fast)
    finally:
        _fast.set_threads(old)


@pytest.mark.parametrize("n_c", [1, 2, 8])
def test_any_number_of_distances_is_bit_identical_up_to_the_power(n_c):
    """The motion kernels unroll the loop over the N_c distances (N_c is compiled in, one
    specialisation per N_c): every N_c gives the reference's N and M-hat bit for bit, with
    the M-hat planes stored row-interleaved, and LM maps within the tolerance."""
    params = mlplc2.Params(n_c=n_c, tau_1=30.0, beta=0.5)
    frames = list(four_phase()[24:30, 20:140, 40:200]) + list(noise((120, 160), n=2, seed=7))
    ref, fast = run_both(frames, params)
    pad = fast._pad
    assert pad == n_c
    n_prev = fast._n_prev[:, pad:-pad, pad:-pad]
    assert np.array_equal(n_prev[0], ref.state.n_prev["on"])
    assert np.array_equal(n_prev[1], ref.state.n_prev["off"])
    for c, channel in enumerate(("on", "off")):
        for k, direction in enumerate("rldu"):
            m_ref = ref.state.m_prev[channel][direction]
            assert m_ref.any()
            assert np.array_equal(fast._m[c, k], m_ref)
            assert np.array_equal(fast._m_rows[:, c, k], m_ref)


@pytest.mark.parametrize("floor, radius", [(0.0, 10), (0.6, 3), (0.2, 25)])
def test_n_floor_paths_bit_identical_in_bands(monkeypatch, floor, radius):
    """Params.n_floor: without it N goes straight into the padded planes; with it every band
    forms N on n_floor_radius rows of context and floors it against its local maximum. Either
    way N (hence M-hat) is the reference's bit for bit, with one band or many."""
    params = mlplc2.Params(n_floor=floor, n_floor_radius=radius)
    frames = list(four_phase()[30:36, 10:130, 30:190])
    for bands in (1, 4):
        fast = _fast_frontend.FastFrontEnd(params, 30.0)
        monkeypatch.setattr(fast, "_nbands", lambda h, w, bands=bands: bands)
        ref, fast = run_both(frames, params, fast=fast)
        pad = fast._pad
        for c, channel in enumerate(("on", "off")):
            n_ref = ref.state.n_prev[channel]
            assert np.array_equal(fast._n_prev[c, pad:-pad, pad:-pad], n_ref)
            if floor:
                assert (n_ref == 0).sum() > (fast._n_prev[c] == 0).size // 20  # the floor acts


def test_bands_give_identical_results(monkeypatch):
    """Splitting the rows into bands (threads) changes nothing, bit for bit."""
    frames = four_phase()[30:38]
    one = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    monkeypatch.setattr(one, "_nbands", lambda h, w: 1)
    many = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    monkeypatch.setattr(many, "_nbands", lambda h, w: 5)
    for i, f in enumerate(frames):
        a, b = one.step(f.astype(np.float32)), many.step(f.astype(np.float32))
        if i == 3:  # the band count may change between frames
            monkeypatch.setattr(many, "_nbands", lambda h, w: 2)
        for name in MAPS:
            assert np.array_equal(getattr(a, name), getattr(b, name))


def test_a_failing_band_raises_without_hanging(monkeypatch):
    """A phase that raises on any band (the calling thread's or a pool thread's) releases the
    spin barriers of the others and the exception reaches the caller; the front end keeps working."""
    fe = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    monkeypatch.setattr(fe, "_nbands", lambda h, w: 3)
    frame = noise((90, 120), n=1)[0].astype(np.float32)
    fe.step(frame)
    phase2 = fe._phase2
    for bad in (0, 2):
        def failing(bd, bad=bad):
            if bd is fe._bands[bad]:
                raise RuntimeError(f"band {bad}")
            return phase2(bd)

        monkeypatch.setattr(fe, "_phase2", failing)
        with pytest.raises(RuntimeError, match=f"band {bad}"):
            fe.step(frame)
    monkeypatch.setattr(fe, "_phase2", phase2)
    fe.reset()
    run_both(noise((90, 120), n=3, seed=4), fast=fe)


def test_thread_count_sets_bands():
    fe = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert fe._nbands(720, 1280) == 1
        numba.set_num_threads(before)
        assert fe._nbands(720, 1280) == before
        assert fe._nbands(20, 20) == 1  # small frames: no threads
    finally:
        numba.set_num_threads(before)


def test_reset_and_new_size_match_a_fresh_front_end():
    fast = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    for f in noise((40, 50), n=4):
        fast.step(f.astype(np.float32))
    fast.reset()
    run_both(noise((33, 61), n=4, seed=3), fast=fast)


def test_maps_are_new_arrays_each_frame():
    fast = _fast_frontend.FastFrontEnd(mlplc2.Params(), 30.0)
    frames = noise((30, 40), n=3)
    first = fast.step(frames[0].astype(np.float32))
    kept = first.magnitude.copy()
    fast.step(frames[1].astype(np.float32))
    fast.step(frames[2].astype(np.float32))
    assert np.array_equal(first.magnitude, kept)


# --- attention helpers -----------------------------------------------------------------------
@pytest.mark.parametrize("shape", ["square", "disc"])
def test_quadrant_sums_match_attention(shape):
    rng = np.random.default_rng(1)
    for _ in range(60):
        h, w = (int(v) for v in rng.integers(3, 90, 2))
        lm = LocalMotion(*[rng.random((h, w), dtype=np.float32) * 10 - 2 for _ in range(5)])
        fields = [(int(rng.integers(0, w)), int(rng.integers(0, h)), int(rng.integers(0, 40)))
                  for _ in range(3)] + [(w // 2, h // 2, max(h, w))]
        for x, y, r in fields:
            np.testing.assert_allclose(_fast_attention.quadrant_sums(lm, x, y, r, shape),
                                       attention.quadrant_sums(lm, x, y, r, shape), rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(_fast_attention.quadrant_sums_all(lm, fields, shape),
                                   [attention.quadrant_sums(lm, *f, shape) for f in fields], rtol=1e-12, atol=1e-9)


# --- models with either backend ---------------------------------------------------------------
def field_key(out):
    return [(f.id, f.x, f.y, f.born) for f in out.fields]


def compare_models(frames, name="mlplc2"):
    cls = mlplc2.models.base.get_model(name)
    fast, ref = cls(fps=30.0, backend="numba"), cls(fps=30.0, backend="reference")
    assert fast.backend == "numba" and ref.backend == "reference"
    created = 0
    for i, frame in enumerate(frames):
        a, b = fast.step(frame), ref.step(frame)
        assert field_key(a) == field_key(b), f"frame {i}"
        for fa, fb in zip(a.fields, b.fields):
            assert fa.response == pytest.approx(fb.response, rel=1e-4, abs=1e-3)
            assert fa.collision == fb.collision
        assert a.collision == b.collision
        created = max([created] + [f.id for f in a.fields])
    return created


def test_fields_identical_on_a_generated_scene():
    assert compare_models(stimuli.six_objects(seed=0).frames) >= 6


@pytest.mark.parametrize("name", ["slplc2", "lplc2"])
def test_other_family_models_identical(name):
    compare_models(four_phase()[:40], name)


@pytest.mark.paper
@pytest.mark.slow
@pytest.mark.parametrize("video", ["outdoor_2_black_4_period.avi", "outdoor_3_black_expand_multi_6.avi"])
def test_fields_identical_on_paper_scenes(paper_dir, video):
    assert compare_models(read_gray(paper_dir / "scenes" / video)) >= 5


def test_default_backend_is_fast_and_model_pickles():
    model = mlplc2.MLPLC2(fps=30.0)
    assert model.backend == "numba"
    frames = stimuli.six_objects().frames[:30]
    for f in frames[:20]:
        model.step(f)
    twin = pickle.loads(pickle.dumps(model))
    clone = copy.deepcopy(model)
    for f in frames[20:]:
        a, b, c = model.step(f), twin.step(f), clone.step(f)
        assert a == b == c


# --- backend selection -----------------------------------------------------------------------
def test_make_frontend_backends():
    p = mlplc2.Params()
    assert isinstance(make_frontend(p, 30.0, "reference"), FrontEnd)
    assert isinstance(make_frontend(p, 30.0, "numba"), _fast_frontend.FastFrontEnd)
    assert isinstance(make_frontend(p, 30.0), _fast_frontend.FastFrontEnd)
    with pytest.raises(ValueError, match="backend"):
        make_frontend(p, 30.0, "cuda")
    with pytest.raises(ValueError, match="backend"):
        mlplc2.MLPLC2(backend="fast")


def test_without_numba_auto_falls_back_with_a_warning(monkeypatch, caplog):
    from mlplc2 import backend

    monkeypatch.setattr(backend, "fast_available", lambda: False)
    monkeypatch.setattr(backend, "_WARNED", False)
    with caplog.at_level(logging.WARNING, logger="mlplc2"):
        model = mlplc2.MLPLC2(fps=30.0)
    assert model.backend == "reference"
    assert "Numba is unavailable" in caplog.text
    with pytest.raises(ImportError):
        make_frontend(mlplc2.Params(), 30.0, "numba")


def test_jit_without_a_writable_cache(monkeypatch):
    """Where Numba cannot cache (no writable location) the kernels still compile."""
    real = numba.njit

    def njit(*args, cache=False, **kwargs):
        if cache:
            raise RuntimeError("cannot cache function: no locator available")
        return real(*args, **kwargs)

    monkeypatch.setattr(numba, "njit", njit)

    @_fast.jit()
    def add_one(x):
        return x + 1

    assert add_one(1) == 2


# --- the benchmark (logic only; no timing is checked) ------------------------------------------
def test_bench_runs_and_formats():
    from mlplc2 import bench

    rows = bench.run_bench([(48, 40)], ["mlplc2"], frames=3, ref_frames=2, warmup=2)
    (row,) = rows
    assert row.ms > 0 and row.ref_ms > 0 and row.probe_ms > 0 and row.peak_mb > 0
    assert row.planes == _fast_frontend.plane_count(mlplc2.Params().n_floor > 0) == 26
    table = bench.format_table(rows)
    assert "| mlplc2 | 48x40 |" in table
    assert bench.parse_sizes("320x240, 64x48") == [(320, 240), (64, 48)]
    with pytest.raises(ValueError):
        bench.parse_sizes("320by240")


def test_bench_times_the_pipeline_as_run_builds_it(monkeypatch):
    """The second table times the model stabilised, as `mlplc2 run` builds it (the main table
    times the paper's model), on a turning and a still scene, with the flow baseline beside it."""
    from mlplc2 import bench
    from mlplc2.models.lplc2 import MLPLC2

    seen = []
    step = MLPLC2.step

    def spy(self, frame, *a, **k):
        seen.append(self.stabilise)
        return step(self, frame, *a, **k)

    monkeypatch.setattr(MLPLC2, "step", spy)
    assert bench.time_model("mlplc2", bench.synthetic_frames(48, 40, 3), "numba", 1, as_run=True)[0] > 0
    assert seen and all(seen)
    seen.clear()
    bench.time_model("mlplc2", bench.synthetic_frames(48, 40, 3), "numba", 1)
    assert seen and not any(seen)
    still, turning = bench.synthetic_frames(48, 40, 3, scroll=0.0), bench.synthetic_frames(48, 40, 3)
    assert np.array_equal(still[0, 0], still[2, 0]) and not np.array_equal(turning[0, 0], turning[2, 0])  # row 0: no square
    (row,) = bench.run_bench([(48, 40)], ["mlplc2"], frames=2, ref_frames=2, warmup=1)
    assert row.run_ms > 0 and row.still_ms > 0 and row.flow_ms > 0
    assert row.run_vs_reference == pytest.approx(row.ref_ms / row.run_ms)
    assert row.run_vs_flow == pytest.approx(row.flow_ms / row.run_ms)
    assert "| mlplc2 | 48x40 | " in bench.format_pipeline([row])
    (bare,) = bench.run_bench([(48, 40)], ["mlplc2"], frames=2, ref_frames=2, warmup=1, pipeline=False)
    assert bare.run_ms is None and bench.format_pipeline([bare]).count("\n") == 1


def test_bench_cli(capsys):
    from mlplc2.cli import main

    assert main(["bench", "--sizes", "40x32", "--frames", "2", "--ref-frames", "1", "--quiet"]) == 0
    assert "| mlplc2 | 40x32 |" in capsys.readouterr().out
    assert main(["bench", "--models", "lgmd2", "--sizes", "40x32"]) == 2



def _run_script(tmp_path, name: str, source: str, **env) -> str:
    """Run ``source`` as a script in a new Python process (what a later run of ``mlplc2`` is) and
    return its stdout; the test fails with the script's output when it exits non-zero."""
    import os
    import subprocess
    import sys

    script = tmp_path / name
    script.write_text(source)
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=240,
                          env=dict(os.environ, **env))
    assert proc.returncode == 0, proc.stdout + proc.stderr[-2000:]
    return proc.stdout


_TWO_STREAMS = r"""
import os, sys, threading, time
import numpy as np, mlplc2
from mlplc2.neuropils import _fast
frames = [np.random.default_rng(k).integers(0, 256, (480, 640)).astype(np.uint8) for k in range(3)]
real_pool = _fast.pool
class SlowSubmit:  # a thread switch after every submit: the band tasks of two frames interleave
    def __init__(self, pool): self.pool = pool
    def submit(self, *a, **k):
        f = self.pool.submit(*a, **k); time.sleep(0.002); return f
_fast.pool = lambda n: SlowSubmit(real_pool(n))
done = [0, 0]
maps = [[], []]
def work(i):
    m = mlplc2.MLPLC2(fps=30.0)
    for k in range(6):
        m.step(frames[k % 3]); done[i] += 1
        maps[i].append(m.maps.magnitude.copy())
ts = [threading.Thread(target=work, args=(i,), daemon=True) for i in range(2)]
for t in ts: t.start()
for t in ts: t.join(60)
same = all(np.array_equal(a, b) for a, b in zip(*maps))
print("done", done, "same", same)
sys.stdout.flush()
os._exit(0 if done == [6, 6] and same else 1)
"""


def test_two_streams_in_two_threads_do_not_deadlock(tmp_path):
    """Two models stepping at once in two threads share the band pool: with 4 bands per frame
    and their tasks interleaved in the pool's queue, each frame's bands must still all run
    (regression: every worker waited for a sibling queued behind the other frame's tasks)."""
    out = _run_script(tmp_path, "two_streams.py", _TWO_STREAMS, NUMBA_NUM_THREADS="4")
    assert "done [6, 6] same True" in out


# --- the on-disk cache of the compiled kernels (issue 23) ---------------------------------------
_NEW_PROCESS = """
import mlplc2
from mlplc2 import stimuli
from mlplc2.neuropils import _fast
model = mlplc2.MLPLC2(fps=30.0)
for frame in stimuli.basic("dark_approach", frames=30).frames:
    model.step(frame)
used = [k for k in _fast.KERNELS if k.signatures]
print("used", len(used), "hits", sum(sum(k.stats.cache_hits.values()) for k in used),
      "misses", sum(sum(k.stats.cache_misses.values()) for k in used))
"""


def _mlplc2_on_an_approach():
    model = mlplc2.MLPLC2(fps=30.0)
    for frame in stimuli.basic("dark_approach", frames=30).frames:
        model.step(frame)


def test_a_new_process_loads_the_kernels_from_the_disk_cache(tmp_path):
    """The first run compiles the kernels (tens of seconds) and caches them on disk; a later
    process loads every one it uses from there (Numba's ``stats``: hits, no misses), so only the
    first run after an install or upgrade stalls on its first frame."""
    _mlplc2_on_an_approach()   # compiled here, or loaded: either way the cache now holds them
    words = _run_script(tmp_path, "new_process.py", _NEW_PROCESS).split()
    used, hits, misses = (int(words[words.index(key) + 1]) for key in ("used", "hits", "misses"))
    assert used >= 5                      # the front end's and the motion kernels at least
    assert misses == 0 and hits >= used   # nothing compiled in the new process



_LATER_FRAMES = """
import mlplc2
from mlplc2 import stimuli
from mlplc2.neuropils import _fast
frames = stimuli.basic("dark_approach", frames=40).frames
model = mlplc2.MLPLC2(fps=30.0, params=mlplc2.Params(PARAMS))
loaded = {k.__name__: len(k.signatures) for k in _fast.KERNELS}
targets = 0
for frame in frames:
    targets += len(model.step(frame).targets)
late = sorted(k.__name__ for k in _fast.KERNELS if len(k.signatures) != loaded[k.__name__])
print("targets", targets, "late", ",".join(late) or "none")
"""


@pytest.mark.parametrize("params", ["", "n_c=3"])
def test_no_kernel_loads_once_the_model_is_built(tmp_path, params):
    """Every kernel a model calls is loaded when it is built (``backend.warm_kernels``): the quadrant
    sums, the edge scans and the image alignment used to load at the frame that first needed them,
    tens of milliseconds in the middle of a live run (issue 23: the latency's tail), and the front
    end's kernels at the first frame, while the decoding thread queued the next frames, whose
    latency then held a first run's compilation (17 s 99th percentile through stdin). A new
    process, so that no other test has loaded them. Also with other parameters (N_c is a compile-time
    constant of the front end's kernels): they were warmed with the default ones until session 11."""
    _mlplc2_on_an_approach()   # the disk cache holds the kernels: the new process loads them
    words = _run_script(tmp_path, "later_frames.py", _LATER_FRAMES.replace("PARAMS", params)).split()
    assert int(words[words.index("targets") + 1]) > 0   # the scene makes targets: their kernels run
    assert words[words.index("late") + 1] == "none"


def test_threads_block_gives_back_the_thread_counts_also_on_an_error():
    """backend.threads(n): the block runs with n threads, and the counts found before (Numba's and
    OpenCV's) are back afterwards, also when the block raises (bench --latency times `run` with one
    thread fewer and must leave the process as it found it)."""
    import cv2
    import numba

    from mlplc2.backend import threads

    before, before_cv = numba.get_num_threads(), cv2.getNumThreads()
    with threads(1) as n:
        assert n == 1 and numba.get_num_threads() == 1 and cv2.getNumThreads() == 1
    assert (numba.get_num_threads(), cv2.getNumThreads()) == (before, before_cv)
    with pytest.raises(RuntimeError):
        with threads(1):
            raise RuntimeError("boom")
    assert (numba.get_num_threads(), cv2.getNumThreads()) == (before, before_cv)
    with threads(None) as n:
        assert n == before


def test_bench_latency_row_and_table():
    """bench --latency (logic only; no timing is checked): every figure is there, the model's
    threads are given back, and the run with one thread fewer is timed where there are two (with
    every thread only where the default run leaves a core to the decoding thread: not at 64x48)."""
    import numba

    from mlplc2 import bench

    before = numba.get_num_threads()
    row = bench.time_latency(64, 48, frames=8)
    assert numba.get_num_threads() == before and row.threads == before
    assert row.frames == 8 and row.latency and set(row.latency) == {"median_ms", "p99_ms", "max_ms"}
    assert min(row.decode_ms, row.model_ms, row.run_ms) > 0
    assert min(row.decode_cpu_ms, row.model_cpu_ms, row.run_cpu_ms) >= 0   # the CPU clock ticks in 10 ms
    assert (row.run_fewer_ms is not None) == (before > 1) and row.run_all_ms is None
    table = bench.format_latency([row])
    assert "| mlplc2 | 64x48 | 8 |" in table and table.count("\n") == 2


_STABILISED = """
import numpy as np
import mlplc2
from mlplc2 import _fast_camera
model = mlplc2.MLPLC2(fps=30.0, stabilise=True)
kernels = (_fast_camera.fit_rounds, _fast_camera.to_uint8, _fast_camera.grid_texture)
built = sum(len(k.signatures) for k in kernels)
texture = np.random.default_rng(0).uniform(0, 255, (120, 220))
for i in range(6):                     # a camera that pans over a texture: the motion fit runs
    model.step(texture[:, 2 * i:2 * i + 160].copy())
print("built", built, "after", sum(len(k.signatures) for k in kernels), "kinds", sum(bool(k.signatures) for k in kernels))
"""


def test_gaze_stabilisation_loads_its_kernel_when_the_model_is_built(tmp_path):
    """The camera-motion fit (``mlplc2._fast_camera``, on by default in ``mlplc2 run``/``demo``)
    is loaded with the other kernels when the model is built, under the ``compiling`` line: it
    used to compile at the second frame of a first run (23 s with the progress bar standing at
    frame 1; a live run's second frame waited as long) and to load from the cache there later."""
    words = _run_script(tmp_path, "stabilised.py", _STABILISED).split()
    built, after = int(words[words.index("built") + 1]), int(words[words.index("after") + 1])
    assert after >= 1          # the run used the compiled fit
    assert int(words[words.index("kinds") + 1]) == 3   # and the conversion and texture kernels
    assert built == after      # and nothing was loaded or compiled after the model was built
