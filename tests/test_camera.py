"""Camera geometry and camera motion (mlplc2.camera): known answers on rendered 3-D scenes.

The scenes come from :func:`mlplc2.stimuli.approach`, whose camera turns or drives with an exact,
known motion (a pan about the camera's y axis, a tilt about its x axis, a forward drive whose
focus of expansion is the principal point), so every expected value here is physics, not output
of the code under test.
"""

import math

import numpy as np
import pytest

from mlplc2 import stimuli
import mlplc2.camera as camera_module
from mlplc2.camera import CameraMotion, MotionEstimator, bearing, focal_length

from .helpers import score_collision

FPS = 30.0


def _frames(camera, speed, background="texture", size=(320, 240), frames=12, objects=()):
    st = stimuli.approach(list(objects), size=size, fps=FPS, frames=frames, background=background, camera=camera,
                          camera_speed=speed, noise_std=2.0, seed=5)
    return st.frames


def _estimates(frames, **kw):
    est = MotionEstimator(hfov_deg=60.0, **kw)
    return [est.apply(f) for f in frames][1:]


def test_focal_length_and_bearing_of_a_pinhole_camera():
    f = focal_length(320, 60.0)
    assert f == pytest.approx(160.0 / math.tan(math.radians(30.0)))
    assert focal_length(320, None) is None
    assert bearing(159.5, 119.5, (240, 320), f) == pytest.approx((0.0, 0.0))
    az, el = bearing(319.5, 0.0, (240, 320), f)
    assert az == pytest.approx(30.0) and el > 0


@pytest.mark.parametrize("camera, speed, axis", [("pan", 10.0, 1), ("pan", -25.0, 1), ("tilt", 6.0, 0)])
def test_rotation_of_a_panning_or_tilting_camera_is_measured(camera, speed, axis):
    """The camera's own turn per frame (deg/s / fps), within 5 %, about the right axis and sign."""
    true = math.radians(speed) / FPS
    for m in _estimates(_frames(camera, speed)):
        assert m.omega[axis] == pytest.approx(true, rel=0.05)
        others = [abs(v) for i, v in enumerate(m.omega) if i != axis]
        assert max(others) < 0.1 * abs(true)
        assert m.rotation_confidence > 0.7
        assert m.heading is None                      # a pure rotation has no heading


def test_a_still_camera_measures_no_motion():
    for m in _estimates(_frames("static", 0.0)):
        assert max(abs(v) for v in m.omega) < 2e-4   # < 0.04 px at 320 px, 60 deg
        assert m.heading is None


def test_heading_of_a_camera_driving_forward_is_the_principal_point():
    ms = _estimates(_frames("forward", 8.0, background="ground", frames=16))
    heads = np.array([m.heading for m in ms if m.heading is not None])
    assert len(heads) >= 0.8 * len(ms)
    assert np.median(heads[:, 0]) == pytest.approx(159.5, abs=8)
    assert np.median(heads[:, 1]) == pytest.approx(119.5, abs=8)
    assert all(max(abs(v) for v in m.omega) < 1e-3 for m in ms)  # no turn


@pytest.mark.parametrize("hfov", [60.0, 90.0])
def test_the_heading_of_a_fast_drive_is_measured_through_a_wide_lens(hfov):
    """At 15 m/s over the ground the points near the camera move too far to be followed, and through a
    90-degree lens the rest of the ground moves under the tracking precision: a share of 0.15-0.3 of the
    followed points shows the expansion (``camera.FAST_EXPANDING_SHARE``, fast: ``FAST_EXPANSION``), every one
    about the principal point (the truth of a forward drive)."""
    frames = stimuli.approach([], size=(320, 240), fps=FPS, hfov_deg=hfov, frames=16, background="ground",
                              camera="forward", camera_speed=15.0, noise_std=2.0, seed=5).frames
    est = MotionEstimator(hfov_deg=hfov)
    ms = [est.apply(f) for f in frames][1:]
    heads = np.array([m.heading for m in ms if m.heading is not None])
    assert len(heads) >= 0.8 * len(ms)
    assert np.median(np.hypot(heads[:, 0] - 159.5, heads[:, 1] - 119.5)) < 8.0


def test_an_approaching_object_before_a_still_camera_gives_no_heading_until_it_fills_much_of_the_view():
    """A textured square (0.8 m) approaching a still camera from 4 m at 8 m/s, off the centre: on frames 8-9 it
    holds 16-22 % of the followed points, expanding fast about its own centre, but at one rate (one depth): not
    the static world of a fast drive, which lies at many depths (``camera.FAST_DEPTHS``), no heading."""
    obj = stimuli.ApproachObject(kind="collision", shape="square", appearance="textured", width_m=0.8,
                                 start=(0.3, 0.1, 4.0), velocity=(0.0, 0.0, -8.0), seed=3)
    ms = _estimates(_frames("static", 0.0, objects=[obj], frames=16))
    assert all(m.heading is None for m in ms[:9])        # frames 1-9


def test_the_heading_of_a_slow_forward_drive_is_measured_over_several_frames():
    """At 2 m/s (the benchmark's ground_forward) the ground moves ~0.6 px a frame at the reduced size: too
    little for a heading between two frames; over 3 frames (``heading_frames``) it is the principal point."""
    frames = _frames("forward", 2.0, background="ground", frames=24)
    alone = _estimates(frames, heading_frames=1)[3:]
    ms = _estimates(frames, heading_frames=3)[3:]
    assert sum(m.heading is not None for m in alone) <= 0.5 * len(alone)
    heads = np.array([m.heading for m in ms if m.heading is not None])
    assert len(heads) >= 0.8 * len(ms)
    assert np.median(heads[:, 0]) == pytest.approx(159.5, abs=8)
    assert np.median(heads[:, 1]) == pytest.approx(119.5, abs=8)
    assert all(m.heading_confidence > 0.5 and 0 < m.expansion < 0.05 for m in ms if m.heading is not None)


@pytest.mark.parametrize("camera, speed", [("static", 0.0), ("pan", 10.0), ("tilt", 6.0)])
def test_the_heading_over_several_frames_stays_away_from_a_camera_that_does_not_translate(camera, speed):
    assert all(m.heading is None for m in _estimates(_frames(camera, speed), heading_frames=3))


def test_a_given_gyro_rate_agrees_with_the_estimate_of_a_pan():
    frames = _frames("pan", 12.0)
    est = _estimates(frames)
    true = (0.0, math.radians(12.0) / FPS, 0.0)
    given = MotionEstimator(hfov_deg=60.0)
    outs = [given.apply(f, omega=true) for f in frames][1:]
    for m, g in zip(est, outs):
        assert g.given and g.omega == true
        assert np.allclose(m.omega, g.omega, atol=0.05 * true[1])


def test_objects_that_move_on_their_own_do_not_bend_the_estimate():
    """A large object crossing the view of a panning camera: the rotation stays the camera's."""
    obj = stimuli.ApproachObject.translating(at=(90.0, 120.0), width_px=90.0, speed_mps=3.0, appearance="textured")
    true = math.radians(10.0) / FPS
    for m in _estimates(_frames("pan", 10.0, objects=[obj])):
        assert m.omega[1] == pytest.approx(true, rel=0.08)


def test_textureless_frames_give_no_confident_motion():
    frames = [np.full((120, 160), 128, np.uint8)] * 4
    for m in _estimates(frames):
        assert m.omega == (0.0, 0.0, 0.0) and m.rotation_confidence == 0.0


def test_the_homography_of_a_rotation_moves_the_far_scene_like_the_camera():
    """A pan to the right by one degree moves the principal point's scene f tan(1 deg) px to the left."""
    f = focal_length(320, 60.0)
    m = CameraMotion(omega=(0.0, math.radians(1.0), 0.0))
    p = m.homography((240, 320), f) @ np.array([159.5, 119.5, 1.0])
    assert p[0] / p[2] == pytest.approx(159.5 - f * math.tan(math.radians(1.0)), abs=1e-6)
    assert p[1] / p[2] == pytest.approx(119.5, abs=1e-6)


@pytest.mark.parametrize("camera, speed", [("pan", 12.0), ("tilt", -6.0)])
def test_gaze_stabilisation_silences_the_static_world_of_a_turning_camera(camera, speed):
    """The front end (Eq. 1-12) with its state carried into each new frame's pixels answers a
    textured static world seen by a turning camera as it answers the same world seen still."""
    from mlplc2.neuropils.frontend import FrontEnd
    from mlplc2.params import Params

    def p99(frames, compensate):
        fe, est, f = FrontEnd(Params(), FPS), MotionEstimator(hfov_deg=60.0), focal_length(320, 60.0)
        levels = []
        for fr in frames:
            g = fr.astype(np.float32)
            m = est.apply(fr)
            if compensate and not m.still:
                fe.compensate(m.homography(g.shape, f), g)
            levels.append(float(np.percentile(fe.step(g).magnitude, 99)))
        return float(np.median(levels[3:]))

    still = p99(_frames("static", 0.0), False)
    turning = _frames(camera, speed)
    assert p99(turning, False) > 20 * still           # the turn drowns everything ...
    assert p99(turning, True) < 2 * still             # ... unless the gaze is stabilised


def test_both_front_ends_stabilise_alike():
    """The compiled front end carries its state as the reference does (the LM maps agree)."""
    pytest.importorskip("numba")
    from mlplc2.neuropils._fast_frontend import FastFrontEnd
    from mlplc2.neuropils.frontend import FrontEnd
    from mlplc2.params import Params

    frames = _frames("pan", -15.0, size=(160, 120), frames=8)
    ends = [FrontEnd(Params(), FPS), FastFrontEnd(Params(), FPS)]
    est, f = MotionEstimator(hfov_deg=60.0), focal_length(160, 60.0)
    for fr in frames:
        g = fr.astype(np.float32)
        m = est.apply(fr)
        maps = []
        for fe in ends:
            if not m.still:
                fe.compensate(m.homography(g.shape, f), g)
            maps.append(fe.step(g).magnitude)
        assert np.allclose(maps[0], maps[1], atol=1e-4 * max(1.0, float(maps[0].max())))


@pytest.mark.parametrize("name", ["MLPLC2", "SLPLC2", "LPLC2"])
def test_a_stabilised_model_honours_the_model_contract(name):
    """MLPLC2, SLPLC2 and LPLC2 (stabilise=True) pass every check of mlplc2.testing (streaming = batch, reset,
    pickling, determinism, bad input, size change, ...)."""
    import mlplc2
    from mlplc2.testing import run_checks

    assert run_checks(lambda: getattr(mlplc2, name)(fps=FPS, stabilise=True))


def test_stabilised_targets_of_a_panning_camera_keep_their_time_to_contact():
    """A collision seen by a camera panning at 10 deg/s: with gaze stabilisation mLPLC2 gives the
    object one target whose time to contact follows the truth (within 15 %) in the last second,
    and warns before contact; the static textured world gives no warning."""
    import mlplc2

    obj = stimuli.ApproachObject.collision(ttc_s=2.0, at=(200.0, 110.0), width_px=8.0)
    st = stimuli.approach([obj], size=(320, 240), fps=FPS, background="texture", camera="pan", camera_speed=10.0,
                          noise_std=2.0, seed=2)
    truth = st.objects[0]
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True)
    errors, warned, false = score_collision((model.step(f) for f in st.frames), truth, FPS)
    assert warned and false == 0
    assert errors and float(np.median(errors)) < 0.15


@pytest.mark.parametrize("path", [dict(roll_deg=4.0, roll_hz=1.0), dict(yaw_rate_dps=8.0, speed_mps=6.0, bounce_deg=1.0),
                                  dict(shake_deg=0.5, shake_seed=3)], ids=["roll", "drive-turn-bounce", "shake"])
def test_estimated_rotation_follows_the_truth_of_a_camera_path(path):
    """A roll, a turning and bouncing drive, a hand-held shake (stimuli.CameraPath: the truth gives the
    camera's rotation per frame, in the convention of CameraMotion): the estimate is within 15 % of
    the largest true rotation on every frame."""
    st = stimuli.approach([], size=(320, 240), fps=FPS, frames=14, background="ground" if path.get("speed_mps")
                          else "texture", camera=stimuli.CameraPath(**path), noise_std=2.0, seed=5)
    truth = np.array(st.to_ground_truth()["camera"]["omega"])[1:]
    est = np.array([m.omega for m in _estimates(st.frames)])
    scale = np.abs(truth).max()
    assert scale > 1e-3
    assert np.abs(est - truth).max() < 0.15 * scale


def _sideways_over_ground(frames=8, step=0.15, height=1.0, size=(320, 240), hfov=60.0):
    """A camera 1 m above a textured ground plane, moving sideways (0.15 m a frame) without turning,
    a flat sky above the horizon: the ground's image moves in proportion to its nearness (parallax:
    nothing at the horizon, most at the bottom), which a pan plus a roll imitates."""
    import cv2

    w, h = size
    f = focal_length(w, hfov)
    rng = np.random.default_rng(4)
    tex = cv2.GaussianBlur(rng.uniform(0, 255, (1024, 1024)).astype(np.float32), (0, 0), 1.5)
    tex = cv2.normalize(tex, None, 20, 235, cv2.NORM_MINMAX)
    u, v = np.meshgrid(np.arange(w) - (w - 1) / 2.0, np.arange(h) - (h - 1) / 2.0 + 0.35 * f)  # horizon near the top
    ground = v / f > 1e-3
    depth = np.where(ground, height * f / np.where(ground, v, 1.0), 0.0)
    out = []
    for k in range(frames):
        gx = ((depth * u / f + k * step) * 40.0 + 512.0).astype(np.float32)    # 40 texels a metre
        gz = (depth * 40.0).astype(np.float32)
        img = cv2.remap(tex, gx, np.minimum(gz, 1023), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        img = np.where(ground & (gz < 1023), img, 200.0)
        out.append(np.clip(img + rng.normal(0, 2.0, img.shape), 0, 255).astype(np.uint8))
    return out


def test_a_sideways_translation_over_the_ground_is_not_taken_for_a_rotation():
    """The camera does not turn: no rotation is measured (the fit of a rotation with an expansion about a
    heading in view read this parallax as a pan of ~60 mrad a frame and a roll of ~-30, and compensated it)."""
    for m in _estimates(_sideways_over_ground()):
        assert m.still or m.rotation_confidence < camera_module.MIN_ROTATION_CONFIDENCE


def test_the_compiled_fit_agrees_with_the_numpy_fit():
    """mlplc2._fast_camera.fit_rounds gives the NumPy fit's rotation and heading (to 1e-9)."""
    pytest.importorskip("numba")
    import mlplc2.camera as camera

    rng = np.random.default_rng(1)
    x, y = rng.uniform(-0.5, 0.5, 100), rng.uniform(-0.4, 0.4, 100)
    omega = np.array([0.002, -0.006, 0.001])
    a = camera._rotational_flow(x, y)
    depth = rng.uniform(2.0, 20.0, 100)
    d = a @ omega + np.stack([(x - 0.05), (y + 0.02)], -1) * (0.1 / depth)[:, None]
    d[:10] += rng.normal(0, 0.02, (10, 2))                     # outliers: objects of their own
    fast = camera._fit_motion(x, y, d, None, None, 1 / 277.0)
    camera._FAST[:] = [None]                                    # the NumPy rounds
    try:
        slow = camera._fit_motion(x, y, d, None, None, 1 / 277.0)
    finally:
        camera._FAST.clear()
    assert np.allclose(fast[0], slow[0], rtol=1e-9, atol=1e-12)
    assert np.allclose(fast[1], slow[1], rtol=1e-9, atol=1e-12)
    assert fast[2:] == pytest.approx(slow[2:], rel=1e-9)
    assert np.allclose(fast[0], omega, atol=6e-4)               # and both find the rotation (10 %)


def test_compensation_is_none_for_a_still_an_unsure_or_a_tiny_rotation():
    """``camera.compensation``, the one stabilisation test of every model: a still camera, a rotation
    few points agree with and one that moves no pixel by STILL_PX are not compensated (no resampling);
    a sure pan is, by its homography."""
    from mlplc2.camera import MIN_ROTATION_CONFIDENCE, compensation

    shape, focal = (240, 320), focal_length(320, 60.0)
    pan = CameraMotion(omega=(0.0, 0.01, 0.0), rotation_confidence=0.9)
    assert compensation(CameraMotion(rotation_confidence=1.0), shape, focal) is None
    assert compensation(CameraMotion(omega=(0.0, 0.01, 0.0), rotation_confidence=MIN_ROTATION_CONFIDENCE / 2),
                        shape, focal) is None
    assert compensation(CameraMotion(omega=(0.0, 1e-5, 0.0), rotation_confidence=0.9), shape, focal) is None
    assert np.allclose(compensation(pan, shape, focal), pan.homography(shape, focal))



def test_kept_pyramids_are_carried_as_if_warped_every_turn():
    """The target layer's kept pyramids take a turn lazily (targets.track.Carried), to the values of
    warping each level at each turn in order, with the grey levels of that turn's frame where the
    earlier frame saw nothing (composing the turns into one resampling changed the warnings)."""
    from mlplc2.camera import warp
    from mlplc2.targets import TargetLayer
    from mlplc2.targets.alignment import pyramid

    rng = np.random.default_rng(3)
    frames = [rng.uniform(0, 255, (64, 80)).astype(np.float32) for _ in range(3)]
    turns = [np.array([[1.0, 0.0, 0.5], [0.0, 1.0, -0.3], [0.0, 0.0, 1.0]]),
             np.array([[1.0, 0.01, 0.7], [-0.01, 1.0, 0.2], [1e-5, 0.0, 1.0]])]
    layer = TargetLayer(fps=FPS)
    layer.step(frames[0], None, [], 0)
    for hom, frame in zip(turns, frames[1:]):
        layer.compensate(hom, frame)
    expected = frames[0]
    for hom, frame in zip(turns, frames[1:]):
        expected = warp(expected, hom, fill=frame)
    s = np.array([[0.5, 0.0, -0.25], [0.0, 0.5, -0.25], [0.0, 0.0, 1.0]])   # level 1: x_1 = (x + 0.5) / 2 - 0.5
    oldest = layer._past[0]
    assert np.array_equal(oldest[0], expected)
    level1 = pyramid(frames[0])[1]
    for hom, frame in zip(turns, frames[1:]):
        level1 = warp(level1, s @ hom @ np.linalg.inv(s), fill=pyramid(frame)[1])
    assert np.allclose(oldest[1], level1, atol=1e-3)


def test_every_kept_pyramid_is_carried_as_if_warped_alone():
    """The kept pyramids share each turn (targets.track.Turn: its level homographies and the mask
    of what it uncovers made once, at the first level read): every kept pyramid, read in any
    order, has the values of warping it alone at each turn, with that turn's frame where it saw
    nothing, whichever pyramid made the shared mask."""
    from mlplc2.camera import warp
    from mlplc2.targets import TargetLayer
    from mlplc2.targets.alignment import pyramid

    rng = np.random.default_rng(5)
    frames = [rng.uniform(0, 255, (64, 80)).astype(np.float32) for _ in range(5)]
    turns = [np.array([[1.0, 0.0, 2.5], [0.0, 1.0, -1.3], [0.0, 0.0, 1.0]]),
             np.array([[1.0, 0.02, -1.7], [-0.02, 1.0, 0.9], [1e-4, 0.0, 1.0]]),
             np.array([[0.98, 0.0, 3.0], [0.0, 1.02, 2.0], [0.0, -1e-4, 1.0]])]
    layer = TargetLayer(fps=FPS)
    layer.step(frames[0], None, [], 0)
    layer.step(frames[1], None, [], 1)
    for k, (hom, frame) in enumerate(zip(turns, frames[2:])):
        layer.compensate(hom, frame)
        layer.step(frame, None, [], k + 2)
    s = np.array([[0.5, 0.0, -0.25], [0.0, 0.5, -0.25], [0.0, 0.0, 1.0]])   # level 1: x_1 = (x + 0.5) / 2 - 0.5
    kept = list(layer._past)
    assert len(kept) == 5
    for i in (3, 1, 0, 2):                   # the newer pyramids first: their masks serve the older
        expected0, expected1 = frames[i], pyramid(frames[i])[1]
        for hom, frame in list(zip(turns, frames[2:]))[max(i - 1, 0):]:
            expected0 = warp(expected0, hom, fill=frame)
            expected1 = warp(expected1, s @ hom @ np.linalg.inv(s), fill=pyramid(frame)[1])
        assert np.array_equal(kept[i][0], expected0), i
        assert np.allclose(kept[i][1], expected1, atol=1e-3), i


def test_the_estimators_grid_follows_the_frame_size():
    """The grid's points are made once per frame size (camera._grid_points): a clip whose size
    changes is tracked on the new size's grid, as a fresh estimator would."""
    small = _frames("pan", -15.0, size=(160, 120), frames=3)
    large = _frames("pan", -15.0, size=(200, 150), frames=3)
    est = MotionEstimator(hfov_deg=60.0)
    seen = [est.apply(f) for f in small] + [est.apply(f) for f in large]
    fresh = MotionEstimator(hfov_deg=60.0)
    alone = [fresh.apply(f) for f in large]
    assert seen[4:] == alone[1:] and seen[4].points > 8


def test_the_border_a_fast_pan_uncovers_makes_no_local_motion():
    """A textured static world seen by a camera panning right at 40 deg/s (~9 px a frame at 320 px):
    with gaze stabilisation the strip the turn uncovers (the new frame fills P(t-1) there, the
    delayed signals of Eq. 8-10 start from 0) and the seam beside it make no local motion: under a
    tenth of T_a, where a field is born (Eq. 13); no field is born and no target made. (With P(t-1)
    filled with 0 there instead of the new frame, that strip's LM reached 11.8; as it is, 0.44.)"""
    import mlplc2
    from mlplc2.params import Params

    frames = _frames("pan", 40.0, frames=14)
    model = mlplc2.MLPLC2(fps=FPS, hfov_deg=60.0, stabilise=True)
    entering = []
    for k, fr in enumerate(frames):
        out = model.step(fr)
        assert not out.fields and not out.targets, k
        if k >= 2:
            entering.append(float(model.maps.magnitude[:, -45:].max()))    # 3 frames' turn + the lamina's window
    assert max(entering) < 0.1 * Params().t_a


def test_the_levels_read_last_frame_are_carried_ahead_in_a_thread_of_their_own():
    """On two threads, a stabilised model carries the kept pyramids' levels its target layer read the
    frame before through the new turn in a thread of its own while it works out its fields
    (TargetLayer.carry_ahead); the targets are those of one thread, where every level is carried
    when read."""
    import threading

    from mlplc2 import MLPLC2
    from mlplc2.backend import threads
    from mlplc2.bench import synthetic_frames
    from mlplc2.targets import track

    frames = synthetic_frames(160, 120, 40)       # a slow pan with approaching squares
    where = []
    apply = track.Turn.apply

    def spy(self, *args):
        where.append(threading.current_thread().name.startswith("mlplc2-carry"))
        return apply(self, *args)

    track.Turn.apply = spy
    try:
        runs = {}
        for n in (1, 2):
            where.clear()
            with threads(n):
                model = MLPLC2(fps=30.0, stabilise=True, repeat_threshold=None)
                runs[n] = [[(t.id, t.warning, vars(t)) for t in model.step(f).targets] for f in frames]
            runs[n, "ahead"] = sum(where)
            runs[n, "warps"] = len(where)
    finally:
        track.Turn.apply = apply
    assert runs[1, "ahead"] == 0 and runs[2, "ahead"] > runs[2, "warps"] / 2
    assert sum(map(len, runs[1])) > 20
    for a, b in zip(runs[1], runs[2]):
        assert [t[:2] for t in a] == [t[:2] for t in b]
        for (_, _, va), (_, _, vb) in zip(a, b):
            for key, value in va.items():
                other = vb[key]
                assert value == other or np.isclose(value, other, rtol=1e-6), key



@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="needs os.fork")
def test_a_forked_child_carries_ahead_in_a_thread_of_its_own():
    """A process forked after the carry thread started (multiprocessing's fork) has no such thread:
    its first carry must start one, not wait for ever on the parent's."""
    import os

    from mlplc2.targets import track

    track.carry_ahead([]).result(timeout=10)     # the parent's thread exists
    pid = os.fork()
    if pid == 0:                                 # the child: exit 0 only if its carry ran
        code = 1
        try:
            track.carry_ahead([]).result(timeout=10)
            code = 0
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


def test_the_compiled_texture_test_and_conversion_give_opencvs_and_numpys_values():
    """The estimate's texture test at the grid's points alone (``_fast_camera.grid_texture``) gives
    what the whole-image Sobel + 7x7 box filter of OpenCV gives there, bit for bit (integer
    gradients, their sums exact), and ``to_uint8`` is NumPy's clip and cast (truncation); a grid
    point nearer than 4 px to the border takes OpenCV's path (``_grid_points``' flag)."""
    pytest.importorskip("numba")
    import cv2
    from mlplc2 import _fast_camera

    rng = np.random.default_rng(3)
    est = MotionEstimator()
    for shape in ((120, 160), (100, 100), (90, 160), (240, 200)):
        for img in (rng.integers(0, 256, shape, dtype=np.uint8),
                    cv2.GaussianBlur(rng.integers(0, 256, shape, dtype=np.uint8), (5, 5), 1.5)):
            _, rows, cols, inside = est._grid_points(img.shape)
            assert inside
            gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3)
            gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3)
            assert np.array_equal(_fast_camera.grid_texture(img, rows, cols),
                                  cv2.blur(gx * gx + gy * gy, (7, 7))[rows, cols])
    assert not est._grid_points((60, 80))[3]                  # points 3 px from the border: OpenCV's path
    gray = rng.uniform(-30.0, 290.0, (37, 53)).astype(np.float32)
    gray[0, :4] = (0.0, 254.999, 255.0, 0.5)
    out = np.empty(gray.shape, np.uint8)
    _fast_camera.to_uint8(gray, out)
    assert np.array_equal(out, np.clip(gray, 0, 255).astype(np.uint8))
    assert np.array_equal(est._reduce(gray)[0], np.clip(gray, 0, 255).astype(np.uint8))


def _pan_then_loom(size=(160, 120), step=4, pan=25, still=10, loom=30):
    """A camera panning over a far texture by ``step`` px a frame for ``pan`` frames (further than half the
    frame), then still; ``still`` frames later a dark square looms at the frame centre (+1 px a side a frame)."""
    from mlplc2.stimuli import procedural_background

    w, h = size
    bg = procedural_background(w + step * pan + 1, h, seed=3)
    frames = [bg[:, step * t: step * t + w].copy() for t in range(pan + 1)]
    for k in range(still + loom):
        f = bg[:, step * pan: step * pan + w].copy()
        if k >= still:
            half = k - still + 1
            f[h // 2 - half: h // 2 + half, w // 2 - half: w // 2 + half] = 0
        frames.append(f)
    return frames, pan + 1


def test_lplc2s_cell_stays_at_the_frame_centre_under_gaze_stabilisation():
    """LPLC2's one cell is retinotopic: at the centre of the frame whatever the camera did. After a pan
    longer than half the frame, an object looming at the centre of the still camera's view: the
    stabilised LPLC2 answers it as the paper's model does. (Carried with the turns as an attention
    field is, the cell went with the pan to the border and never answered again: the flat LPLC2 panel
    of ``mlplc2 demo``, whose background scrolls.)"""
    import mlplc2

    frames, start = _pan_then_loom()
    h, w = frames[0].shape
    answers = {}
    for stabilise in (False, True):
        model = mlplc2.LPLC2(fps=FPS, stabilise=stabilise)
        outs = [model.step(f) for f in frames]
        assert all((o.fields[0].x, o.fields[0].y) == (w // 2, h // 2) for o in outs)
        answers[stabilise] = [o.response for o in outs[start:]]
    assert max(answers[False]) > 0                       # the paper's model sees the object ...
    assert max(answers[True]) >= 0.8 * max(answers[False])   # ... and so does the stabilised one
    assert sum(r > 0 for r in answers[True]) >= 0.8 * sum(r > 0 for r in answers[False])
