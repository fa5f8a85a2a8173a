"""Time from the camera: ``Model.step(frame, t)`` (docs/model.md, "Time")."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from mlplc2 import InputError
from mlplc2.models.base import REGISTRY
from mlplc2.stimuli import approach_scene

FPS = 30.0


@pytest.fixture(scope="module")
def frames():
    st = approach_scene(kind="collision", ttc_s=1.5, size=(160, 120), fps=FPS, background="texture")
    return list(st.frames)


def _outputs(name, frames, times=None, fps_=FPS, **kw):
    m = REGISTRY[name](fps=fps_, **kw)
    return [m.step(f) if times is None else m.step(f, t) for f, t in zip(frames, times or [None] * len(frames))]


def _same(a, b):
    return [(o.frame, o.response, o.collision, o.spike, o.repeated, o.fields, o.targets) for o in a] == \
           [(o.frame, o.response, o.collision, o.spike, o.repeated, o.fields, o.targets) for o in b]


@pytest.mark.parametrize("name,kw", [("mlplc2", {}), ("mlplc2", {"backend": "reference"}), ("lgmd2", {}),
                                     ("flow", {})])
def test_constant_rate_timestamps_change_nothing(frames, name, kw):
    """t = i / fps, from any start, gives exactly the outputs without t (bit for bit)."""
    n = len(frames) if kw.get("backend") != "reference" else 20
    plain = _outputs(name, frames[:n], **kw)
    for t0 in (0.0, 12.345):
        timed = _outputs(name, frames[:n], [t0 + i / FPS for i in range(n)], **kw)
        assert _same(plain, timed)
        assert [o.time_s for o in timed] == [t0 + i / FPS for i in range(n)]
    assert [o.time_s for o in plain] == [i / FPS for i in range(n)]
    if name == "mlplc2" and n == len(frames):
        assert any(t.ttc_s is not None for o in plain for t in o.targets)   # the fits were exercised


def test_timestamps_must_increase(frames):
    m = REGISTRY["mlplc2"](fps=FPS)
    m.step(frames[0], 1.0)
    for bad in (1.0, 0.5, float("nan"), "1.5", True):
        with pytest.raises(InputError, match="frame 1"):
            m.step(frames[1], bad)
    out = m.step(frames[1], 1.0 + 1 / FPS)          # the model goes on, nothing changed
    assert (out.frame, out.time_s) == (1, 1.0 + 1 / FPS)


def test_a_camera_clock_out_of_order_is_named_with_all_its_digits(frames):
    """An epoch clock (s since 1970) that steps back by 50 ms: the error gives both times in full, not
    ``1.76e+09 s after 1.76e+09 s`` (a user's trial, session 26)."""
    m = REGISTRY["lgmd2"](fps=FPS)
    m.step(frames[0], 1760000000.6)
    with pytest.raises(InputError, match=r"t = 1760000000\.55 s after 1760000000\.6 s"):
        m.step(frames[1], 1760000000.55)


def _first_warning(outs):
    return next((o for o in outs if o.warning), None)


def test_dropped_frames_keep_time_to_contact(frames):
    """Every 4th frame dropped (timestamps kept): the times to contact stay within 10 % of the complete
    scene's and the warning comes at most 2 frames later."""
    full = _outputs("mlplc2", frames, [i / FPS for i in range(len(frames))])
    kept = [i for i in range(len(frames)) if i % 4 != 3]
    dropped = _outputs("mlplc2", [frames[i] for i in kept], [i / FPS for i in kept])
    compared = 0
    h, w = frames[0].shape[:2]

    def fills(t):                     # a box as wide or as tall as the frame (TargetParams.view_hold)
        return t.width >= w - 1 or t.height >= h - 1

    for i, o in zip(kept, dropped):
        a, b = full[i].most_urgent, o.most_urgent
        # compared while contact is more than one frame interval away: below that a tenth of a
        # frame's rounding is more than 10 % (frame 45, 0.4 frames before contact: 0.0136 against 0.0170 s).
        # Where a box fills the frame, its run holds the time to contact of its last fit before (view_hold),
        # which the two runs made a frame apart: there they agree within a third of a frame interval (frame
        # 44: 0.045 against 0.054 s), a fit's scatter carried on, not 10 % of what is left
        if a is not None and b is not None and a.ttc_s is not None and b.ttc_s is not None and a.ttc_s > 1 / FPS:
            tol = 1 / (3 * FPS) if fills(a) or fills(b) else 0.1 * a.ttc_s
            assert abs(b.ttc_s - a.ttc_s) <= tol, (i, a.ttc_s, b.ttc_s)
            compared += 1
    assert compared >= 10
    wf, wd = _first_warning(full), _first_warning(dropped)
    assert wf is not None and wd is not None
    assert wd.time_s * FPS <= wf.frame + 2 + 1e-9


def test_a_slow_camera_warns_when_a_fast_one_does(frames):
    """The approach at 7.5 fps, as its own rate or shown at 30 fps with every frame 4 times (the helmet
    clip): the layer's windows span the same time (TargetParams.nominal_fps), so the first warning comes
    within one of its frames of the 30 fps one's, and the times to contact agree within 10 % (while more
    than two of its frames are left). (Counting
    observations, the 7.5 fps fit waited for 5 of them: 0.53 s, two frames later.)"""
    fast = _outputs("mlplc2", frames)
    slow = _outputs("mlplc2", frames[::4], [4 * k / FPS for k in range(len(frames[::4]))], fps_=7.5)
    held = _outputs("mlplc2", [frames[4 * (i // 4)] for i in range(len(frames))],
                    [i / FPS for i in range(len(frames))], repeat_threshold=0.0)
    assert sum(o.repeated for o in held) == len(frames) - len(slow)
    wf = _first_warning(fast)
    assert wf is not None
    for outs in (slow, held):
        w = _first_warning(outs)
        assert w is not None and abs(w.time_s - wf.time_s) <= 4 / FPS + 1e-9, (w and w.time_s, wf.time_s)
        for o in outs:
            a, b = fast[round(o.time_s * FPS)].most_urgent, o.most_urgent
            if a is not None and b is not None and a.ttc_s is not None and b.ttc_s is not None \
                    and a.ttc_s > 8 / FPS and not o.repeated:
                assert abs(b.ttc_s - a.ttc_s) <= 0.1 * a.ttc_s + 1e-9, (o.time_s, a.ttc_s, b.ttc_s)


def test_repeated_frames_step_with_the_real_interval():
    """A 15 fps scene stored at 30 fps (every frame twice): the held copies do not step, the next new frame
    steps with the real interval: the front end's maps are those of the 15 fps frames, and a held
    frame counts the time to contact down by its time."""
    st = approach_scene(kind="collision", ttc_s=1.5, size=(160, 120), fps=15.0, background="texture")
    distinct = list(st.frames)[:16]
    slow = REGISTRY["mlplc2"](fps=15.0)
    doubled = REGISTRY["mlplc2"](fps=FPS, repeat_threshold=0.0)
    for k, f in enumerate(distinct):
        slow.step(f)
        a = doubled.step(f, 2 * k / FPS)
        assert not a.repeated
        np.testing.assert_allclose(doubled.maps.magnitude, slow.maps.magnitude, rtol=1e-5, atol=1e-6)
        b = doubled.step(f, (2 * k + 1) / FPS)
        assert b.repeated and b.time_s == (2 * k + 1) / FPS
        for ta, tb in zip(a.targets, b.targets):
            if ta.ttc_s is not None and tb.ttc_s is not None:
                assert tb.ttc_s == pytest.approx(ta.ttc_s - 1 / FPS)


def _vfr_video(path, times_ms):
    """A small video whose frames carry the given timestamps (ms), as a variable-rate camera writes them."""
    av = pytest.importorskip("av")
    from fractions import Fraction

    c = av.open(str(path), "w")
    s = c.add_stream("mpeg4", rate=30)
    s.width, s.height, s.pix_fmt = 64, 48, "yuv420p"
    s.time_base = Fraction(1, 1000)
    for i, t in enumerate(times_ms):
        f = av.VideoFrame.from_ndarray(np.full((48, 64, 3), 20 * i, np.uint8), format="rgb24")
        f.pts, f.time_base = t, Fraction(1, 1000)
        for p in s.encode(f):
            c.mux(p)
    for p in s.encode():
        c.mux(p)
    c.close()


# the container's frame count is its duration times its rate (10 here): a variable-rate file reads as cut short
@pytest.mark.filterwarnings("ignore::mlplc2.io.formats.TruncatedInputWarning")
@pytest.mark.parametrize("decoder", ["opencv", "pyav"])
def test_run_uses_the_container_timestamps(tmp_path, decoder):
    import mlplc2

    times = [0, 33, 67, 100, 167, 200, 300]              # two frames dropped
    path = tmp_path / "vfr.mkv"
    _vfr_video(path, times)
    res = mlplc2.run(str(path), "lgmd1", out=False, decoder=decoder, quiet=True, plot=False)
    assert [r["time_s"] for r in res.rows] == [t / 1000 for t in times]
    res = mlplc2.run(str(path), "lgmd1", out=False, decoder=decoder, quiet=True, plot=False, fps=10.0)
    assert [r["time_s"] for r in res.rows] == [round(i / 10.0, 6) for i in range(len(times))]


def _textured_square(cx, cy, side, texture):
    img = np.full((240, 320), 200.0, np.float32)
    patch = cv2.resize(texture, (int(round(side)), int(round(side))), interpolation=cv2.INTER_AREA)
    x0, y0 = int(round(cx - side / 2)), int(round(cy - side / 2))
    img[y0:y0 + patch.shape[0], x0:x0 + patch.shape[1]] = patch
    return cv2.GaussianBlur(img, (0, 0), 1.0)


def test_a_fast_object_is_followed_between_distant_frames():
    """A 7.5 fps camera (frames 4 nominal frames apart): a textured object 1.4 s from contact that crosses
    22 px per frame is followed to the end, its box on the object in every frame, and gets a time to
    contact (the target layer's alignment, retried from the track's own motion; from rest it loses the
    object after two frames). The object's size is 24 px x 1.4 / (1.4 - t)."""
    from types import SimpleNamespace

    from mlplc2.targets import TargetLayer

    rng = np.random.default_rng(1)
    texture = cv2.GaussianBlur(rng.uniform(0, 120, (200, 200)).astype(np.float32), (0, 0), 4) * 2
    layer = TargetLayer(fps=FPS)
    ttc = None
    for k in range(9):
        side = 24 * 1.4 / (1.4 - 4 * k / FPS)
        cx, cy = 260 - 22 * k, 150 - 5.5 * k
        # in collision alarm: on the first frame no growth can be seen yet, and only an alarm makes a target
        seed = SimpleNamespace(id=1, x=cx, y=cy, radius=40, response=1.0, box=(cx, cy, side, side), collision=True)
        out = layer.step(_textured_square(cx, cy, side, texture), None, [seed] if k == 0 else [], 4 * k, 4 * k)
        assert len(out) == 1 and abs(out[0].x - cx) < side / 2 and abs(out[0].y - cy) < side / 2, (k, out)
        ttc = out[0].ttc_s if out[0].ttc_s is not None else ttc
    assert ttc is not None and 0 < ttc < 1.0


def test_a_long_gap_in_the_frames_times_carries_no_motion_past_what_an_alignment_holds():
    """A camera that pauses (1000 s between two frames): the track's own motion carried over the gap would move and
    scale its box without bound (an overflow in the alignment's samples); it is no start for the alignment then,
    and the step goes on without a warning of NumPy's."""
    import warnings
    from types import SimpleNamespace

    from mlplc2.targets import TargetLayer

    rng = np.random.default_rng(1)
    texture = cv2.GaussianBlur(rng.uniform(0, 120, (200, 200)).astype(np.float32), (0, 0), 4) * 2
    layer = TargetLayer(fps=FPS)
    for k in range(4):
        side = 24 * 1.4 / (1.4 - 4 * k / FPS)
        cx, cy = 260 - 22 * k, 150 - 5.5 * k
        seed = SimpleNamespace(id=1, x=cx, y=cy, radius=40, response=1.0, box=(cx, cy, side, side), collision=True)
        clock = 4 * k if k < 3 else 8 + 1000 * FPS
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            layer.step(_textured_square(cx, cy, side, texture), None, [seed] if k == 0 else [], clock, clock)


def test_a_frame_seeds_once_per_nominal_interval_it_stands_for():
    """The LM seeds a frame may give count time, not frames: one per nominal frame (30 fps) since the
    last frame, at least one, at most change_frames (a long gap is not a flood of candidates)."""
    from mlplc2.targets import TargetLayer, TargetParams

    p = TargetParams(lm_seeds=1)                 # one seed per nominal frame (the default is 2: docs/model.md)
    for fps, interval, seeds in ((30.0, 1.0, 1), (7.5, 1.0, 4), (10.0, 1.0, 3), (30.0, 4.0, 4), (30.0, 30.0, 4),
                                 (60.0, 1.0, 1), (7.5, None, 1)):
        assert TargetLayer(p, fps)._seeds(interval) == seeds, (fps, interval)
    assert p.change_frames == 4


def test_the_helmet_thrown_at_a_slow_camera_gets_a_target(real_dir):
    """The 7.5 fps helmet clip (320x240, every frame 4 times): from the frame where the flying helmet is
    first a candidate (17) the model has a target whose centre lies within the helmet's labelled width
    of its labelled centre (ground_truth.json). Between frames 133 ms apart the strongest LM is not the
    helmet's (with one LM seed a frame the candidates at 17 lie 56-62 px from it); a frame seeds once per
    nominal frame interval it stands for (``TargetLayer._seeds``: 4 here, 1 at 30 fps)."""
    import json

    import mlplc2

    truth = json.loads((real_dir / "ground_truth.json").read_text())["clips"]["helmet_attack.avi"]
    track = {f: (x, y, w) for f, x, y, w in truth["track"]}
    rows = mlplc2.run(real_dir / "helmet_attack.avi", ["mlplc2"], out=False, progress=False).targets
    for frame in (17, 21):
        x, y, w = track[frame]
        here = [r for r in rows if r["frame"] == frame]
        assert any(math.hypot(r["x"] - x, r["y"] - y) <= w for r in here), (frame, here)
    # ... and is held through its turn at 25 (x1.5; its alignment fails from every start, the box measured
    # afresh where its motion carries it grew as that motion says: TargetLayer._remeasure), so that its
    # third observation gives a time to contact: under 1 s (the contact, 29, is 4 frames = 0.13 s away)
    x, y, w = track[25]
    on = [r for r in rows if r["frame"] == 25 and math.hypot(r["x"] - x, r["y"] - y) <= w]
    assert any(r["ttc_s"] is not None and 0 < r["ttc_s"] < 1.0 for r in on), on
    # ... and that first time to contact, the last frame before contact, begins the warning, on the helmet
    # (``slow_evidence``, ``slow_onset``: docs/history.md, "A slow camera's first estimate")
    warned = [r for r in rows if r["warning"]]
    assert warned and min(r["frame"] for r in warned) < truth["contact_frame"], warned[:1]
    first = [r for r in warned if r["frame"] == min(q["frame"] for q in warned)]
    assert any(math.hypot(r["x"] - x, r["y"] - y) <= w for r in first), first


def _square_approach(fps_step, contact, offset=0.0, n=None):
    """The target layer's first warning (clock, 30 fps intervals) on a textured square coming straight at a
    camera that shows a frame every ``fps_step`` intervals: its side 20 px x contact / (contact - t), its centre
    ``offset`` of its sides right of the principal point (the heading), seeded at clock 4 (the first with a
    frame ``change_frames`` before), up to 3 intervals before ``contact`` (it then fills the view); and every
    target seen."""
    from types import SimpleNamespace

    from mlplc2.targets import TargetLayer

    rng = np.random.default_rng(1)
    texture = cv2.GaussianBlur(rng.uniform(0, 120, (200, 200)).astype(np.float32), (0, 0), 4) * 2
    layer = TargetLayer(fps=FPS)
    first, seen = None, []
    for t in range(0, contact - 2, fps_step):
        side = 20.0 * contact / (contact - t)
        cx, cy = 159.5 + offset * side, 119.5
        seed = SimpleNamespace(id=1, x=cx, y=cy, radius=40, response=0.0, box=(cx, cy, side, side), collision=False)
        out = layer.step(_textured_square(cx, cy, side, texture), None, [seed] if t == 4 else [], t, t)
        seen += [(t, o) for o in out]
        if first is None and any(o.warning for o in out):
            first = t
    return first, seen


def test_a_slow_camera_warns_from_its_first_time_to_contact():
    """A square 0.67 s (20 intervals at 30 fps) from contact, straight at the camera: at 30 fps its target warns
    at clock 13 (first time to contact at 8, a streak of estimates over 5 intervals: ``confirm_frames``); a
    7.5 fps camera's first fit (a time to contact with a course; ``young_ttc`` shows one sooner, without a
    course) comes at 12 (3 frames, 0.27 s before contact) and a streak would need 2 more of its frames, past
    contact. Its log-scale rising at every frame over that span is the evidence (``slow_evidence``): it warns at
    12, by the first of its frames after the 30 fps warning, before contact (without: no warning before contact)."""
    fast, _ = _square_approach(1, 20)
    slow, seen = _square_approach(4, 20)
    assert fast is not None and fast < 20
    assert slow is not None and slow < 20 and slow <= fast + 4, (fast, slow)
    estimates = [t for t, o in seen if o.miss is not None]     # the fit's (``young_ttc`` shows one sooner, no course)
    assert estimates and slow == estimates[0]           # on its first time to contact


def test_a_slow_camera_first_course_within_max_miss_begins_a_warning():
    """The same square 0.9 of its widths right of the heading, keeping that bearing: it passes 0.9 widths
    from the camera's point, within ``max_miss`` (1.0; the camera's own size). A 7.5 fps camera's first time
    to contact (clock 12, 0.27 s before contact) measures that course (0.8-1.0) and has no earlier one it could
    have fallen from (``onset_miss`` holds a passing object's course as it falls through ``max_miss``):
    ``slow_onset`` lets it begin the warning there, before contact (without: none before contact)."""
    slow, seen = _square_approach(4, 20, offset=0.9)
    first = next((t, o) for t, o in seen if o.miss is not None)   # the first fit's (``young_ttc``'s has no course)
    assert first[0] == 12 and 0.8 < first[1].miss <= 1.0, first
    assert slow == 12
