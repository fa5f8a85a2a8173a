"""mlplc2.models.lplc2: properties of the LPLC2 family over many frames.

* With small fields and a low T_a (many candidates) the field count stays within
  ``max_fields`` (Hypothesis; the harness is the all-model one of ``test_base.py``).
* Long runs: 20 000 frames of MLPLC2 with flat memory and a bounded field history; the
  history cap and the field count are settings.
* A held (repeated) frame counts each target's time to contact down (``_hold``).

(The paper's selectivity and localisation: ``tests/test_selectivity.py`` and
``tests/test_scenes.py``; attention fields on hand-made maps: ``tests/test_attention.py``.)
"""

from __future__ import annotations

import gc
import os
import tracemalloc

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mlplc2
from mlplc2 import Params, stimuli
from mlplc2.models.base import REPEAT_THRESHOLD

from .test_base import _make_frame, _run_and_settle


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(5, 30), max_fields=st.integers(1, 4),
       r_af=st.integers(2, 12))
def test_mlplc2_field_count_bounded_with_small_fields(seed, n, max_fields, r_af):
    """Small fields and a low T_a make many candidates; max_fields must still hold."""
    rng = np.random.default_rng(seed)
    params = Params(max_fields=max_fields, r_af=r_af, t_a=0.5, grace=2, d=3)
    frames = [_make_frame(str(rng.choice(["noise", "salt_pepper", "checker", "square"])), rng)
              for _ in range(n)]
    _run_and_settle("mlplc2", frames, params)


# =============================================================================
# Long runs: flat memory, bounded history
# =============================================================================
def _long_stream(n: int, h: int = 48, w: int = 64, seed: int = 0):
    """A scrolling texture with noise and a dark square looming at changing places (cheap)."""
    rng = np.random.default_rng(seed)
    tex = rng.integers(100, 200, (h, w), dtype=np.uint8).astype(np.int16)
    tex = (tex + np.roll(tex, 1, 1) + np.roll(tex, 1, 0)) // 3
    noise = [rng.integers(-6, 7, (h, w)).astype(np.int16) for _ in range(7)]
    centres = [(w // 4, h // 4), (3 * w // 4, h // 4), (w // 4, 3 * h // 4), (3 * w // 4, 3 * h // 4),
               (w // 2, h // 2)]
    for i in range(n):
        f = np.roll(tex, i % w, axis=1) + noise[i % 7]
        k = i % 40
        if k < 24:
            cx, cy = centres[(i // 40) % len(centres)]
            f[max(cy - k - 1, 0):cy + k + 2, max(cx - k - 1, 0):cx + k + 2] = 15
        yield np.clip(f, 0, 255).astype(np.uint8)


def _rss_bytes() -> int | None:
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def _check_bounded(model) -> None:
    p = model.params
    assert len(model._fields) <= p.max_fields
    for f in model._fields:
        assert f.history.maxlen == max(p.d, p.alarm_window)
        assert len(f.history) <= f.history.maxlen


@pytest.mark.slow
def test_long_run_flat_memory_and_bounded_history():
    """20 000 frames through MLPLC2 (hundreds of fields born and removed on the way).

    tracemalloc costs about 4x per frame, so it traces two windows of 1 200 frames, early
    and late: the live Python/NumPy memory may grow neither within a window nor from one
    window to the other by more than 64 KiB (about 50 bytes a frame; one 64x48 float32 map
    is 12 KiB; measured 2-3 KiB; keeping each frame's Output alive grows it by ~500 KiB).
    RSS is cheap, covers all 20 000 frames and the native allocations tracemalloc cannot
    see (numba, OpenCV internals): < 16 MiB growth after warm-up. The field
    list and every field's history stay within their settings (max_fields, max(d,
    alarm_window))."""
    n = 20_000
    windows = [(1_000, 2_200), (18_700, 19_900)]
    settle = 200  # frames into a window before its baseline (all live state re-allocated while traced)
    model = mlplc2.MLPLC2(fps=30.0)
    base: dict[int, int] = {}
    ends: list[int] = []
    peaks: list[int] = []
    rss0 = rss1 = None
    max_fields = max_hist = last_id = alarms = 0
    assert not tracemalloc.is_tracing()
    try:
        for i, frame in enumerate(_long_stream(n)):
            for w0, w1 in windows:
                if i == w0:
                    gc.collect()
                    tracemalloc.start()
                elif i == w0 + settle:
                    gc.collect()
                    base[w0] = tracemalloc.get_traced_memory()[0]
                    tracemalloc.reset_peak()
                elif i == w1:
                    gc.collect()
                    cur, peak = tracemalloc.get_traced_memory()
                    ends.append(cur - base[w0])
                    peaks.append(peak)
                    tracemalloc.stop()
            if i == 2_000:
                rss0 = _rss_bytes()
            out = model.step(frame)
            max_fields = max(max_fields, len(out.fields))
            alarms += out.collision
            for f in out.fields:
                last_id = max(last_id, f.id)
            if i % 1000 == 0:
                _check_bounded(model)
                max_hist = max([max_hist] + [len(f.history) for f in model._fields])
        gc.collect()
        rss1 = _rss_bytes()
    finally:
        tracemalloc.stop()
    print(f'\nlong run: last id {last_id}, alarms {alarms}, window growth {ends}, baselines {base}, '
          f'peaks {peaks}, rss {rss0} -> {rss1}')
    assert model.frame_index == n
    _check_bounded(model)
    assert max_fields <= model.params.max_fields
    assert max_hist <= max(model.params.d, model.params.alarm_window)
    assert last_id > 200, last_id  # many fields were born and removed during the run
    kib = 1024
    assert len(ends) == len(base) == 2
    assert all(abs(g) < 64 * kib for g in ends), ends  # flat within each traced window
    assert abs(base[windows[1][0]] - base[windows[0][0]]) < 64 * kib, base  # and late == early
    assert max(peaks) < 4 * 1024 * kib, peaks  # live memory of the model itself stays small
    if rss0 is not None and rss1 is not None:
        assert rss1 - rss0 < 16 * 1024 * kib, (rss0, rss1)


def test_history_cap_is_a_setting():
    """The per-field history is max(d, alarm_window) long and the field count max_fields."""
    p = Params(d=3, alarm_window=7, max_fields=2, r_af=6, t_a=0.5, grace=1, t_d=0.0)
    model = mlplc2.MLPLC2(params=p)
    seen = 0
    for frame in _long_stream(300):
        out = model.step(frame)
        assert len(out.fields) <= 2
        seen = max(seen, len(out.fields))
        _check_bounded(model)
        assert all(f.history.maxlen == 7 for f in model._fields)
    assert seen == 2
    assert max(len(f.history) for f in model._fields) == 7


# =============================================================================
# Held (repeated) frames: the time to contact counts down
# =============================================================================
def test_held_time_to_contact_counts_down():
    """While frames are held, each target's time to contact falls by the time elapsed since the
    processed frame (the object keeps approaching), and nothing else changes."""
    st = stimuli.looming(contact_time=2.0, fps=30.0)
    model = mlplc2.MLPLC2(fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    timed = None
    for k, f in enumerate(st.frames):
        out = model.step(f)
        if k > 20 and any(t.ttc_s is not None for t in out.targets):
            timed = (f, out)
            break
    assert timed is not None, "no time-to-contact estimate on the looming stimulus"
    frame, last = timed
    for n in range(1, 4):
        held = model.step(frame)
        assert held.repeated and held.response == last.response
        assert [(f.id, f.x, f.y, f.response) for f in held.fields] == [(f.id, f.x, f.y, f.response) for f in last.fields]
        old = {t.id: t for t in last.targets}
        for a in held.targets:
            b = old[a.id]
            assert (a.x, a.y, a.width, a.height) == (b.x, b.y, b.width, b.height)
            if b.ttc_s is None or b.ttc_s - n / 30.0 <= 0:   # no estimate once the contact is over
                assert a.ttc_s is None and not a.warning
            else:
                assert a.ttc_s == pytest.approx(b.ttc_s - n / 30.0)


def test_held_time_to_contact_ends_at_contact():
    """A held estimate whose contact time has passed becomes None and loses its warning (as on a
    stepped frame), and the targets are ordered again by urgency."""
    from mlplc2.models.base import Output
    from mlplc2.targets import Target

    model = mlplc2.MLPLC2(fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    frame = np.full((60, 80), 128, np.uint8)
    model.step(frame)
    soon = Target(1, 10.0, 10.0, 20.0, 20.0, ttc_s=0.02, miss=0.1, warning=True, azimuth_deg=-3.0)
    later = Target(2, 50.0, 30.0, 10.0, 10.0, ttc_s=0.5, miss=0.2, warning=True, azimuth_deg=1.0)
    model._last_out = Output(frame=0, response=900.0, collision=True, targets=(soon, later))
    held = model.step(frame)                       # one frame (1/30 s) later: past the first contact
    assert held.repeated and held.response == 900.0 and held.collision
    b, a = held.targets                            # re-ordered: the one still warning comes first
    assert (a.id, a.ttc_s, a.miss, a.warning) == (1, None, None, False)
    assert b.id == 2 and b.ttc_s == pytest.approx(0.5 - 1 / 30.0) and b.warning and b.azimuth_deg == 1.0
    assert held.most_urgent is b and held.warning
