"""The general camera trajectory of the 3-D approaches (CameraPath), the settings of real use
(drive, drone, hand-held) and their lossless writing: small sizes, a few seconds in all."""

import dataclasses
import hashlib
import json
import math

import cv2
import numpy as np
import pytest

from mlplc2._validation import InputValueError
from mlplc2.benchmark import REAL_USE, by_setting, suite
from mlplc2.evaluation.truth import load
from mlplc2.io import read_video, write_lossless_video
from mlplc2.stimuli import ApproachObject, CameraPath, approach
from mlplc2.stimuli.world.realuse import meeting, real_use_scene

SIZE = (96, 72)
F = (SIZE[0] / 2) / math.tan(math.radians(30))          # the focal length of a 60 deg view (px)
CX, CY = (SIZE[0] - 1) / 2, (SIZE[1] - 1) / 2


def _far(kind="pass"):
    """A small object far ahead that approaches slowly (so the path's kind checks pass)."""
    return ApproachObject(kind=kind, width_m=0.5, start=(-20.0, 0.0, 50.0), velocity=(0.0, 0.0, -1.0))


def test_a_yaw_turn_moves_the_far_scene_by_the_right_pixels():
    rate = 6.0                                             # deg/s: 3 deg in 15 frames at 30 fps
    stim = approach([_far()], size=(160, 120), frames=16, background="texture",
                    camera=CameraPath(yaw_rate_dps=rate), supersample=1, seed=2)
    f = (160 / 2) / math.tan(math.radians(30))
    a, b = (stim.frames[k][30:90, 40:120].astype(np.float32) for k in (0, 15))
    (dx, dy), _ = cv2.phaseCorrelate(a, b)
    assert dx == pytest.approx(-f * math.tan(math.radians(rate * 15 / 30)), abs=0.5)   # turning right: the scene moves left
    assert dy == pytest.approx(0.0, abs=0.3)
    omega = np.array(stim.camera["omega"])
    assert np.allclose(omega[1:], [0.0, math.radians(rate / 30), 0.0], atol=1e-12)  # a pan right is +y
    assert omega[0].tolist() == [0.0, 0.0, 0.0]


def test_the_heading_of_a_forward_drive_is_the_principal_point_even_in_a_turn():
    for path in (CameraPath(speed_mps=12.0), CameraPath(speed_mps=12.0, yaw_rate_dps=4.0)):
        stim = approach([_far()], size=SIZE, frames=20, camera=path, supersample=1)
        assert np.allclose(stim.camera["heading"], [[CX, CY]] * 20, atol=1e-6)


def test_a_pitch_bounce_moves_the_heading_down_when_the_camera_looks_up():
    b, hz = 2.0, 1.0
    stim = approach([_far()], size=SIZE, frames=30, fps=30.0, camera=CameraPath(speed_mps=10.0, bounce_deg=b, bounce_hz=hz),
                    supersample=1)
    heading = np.array(stim.camera["heading"])
    pitch = np.radians(b) * np.sin(2 * math.pi * hz * np.arange(30) / 30.0)
    assert np.allclose(heading[:, 0], CX, atol=1e-6)
    assert np.allclose(heading[:, 1], CY + F * np.tan(pitch), atol=1e-3)


def test_shake_is_smooth_and_reproducible_by_its_seed():
    def run(seed):
        return approach([_far()], size=SIZE, frames=30, background="texture", supersample=1,
                        camera=CameraPath(speed_mps=1.0, shake_deg=0.5, shake_m=0.01, shake_seed=seed))

    a, b, c = run(3), run(3), run(4)
    assert np.array_equal(a.frames, b.frames) and a.camera["omega"] == b.camera["omega"]
    assert a.camera["omega"] != c.camera["omega"]
    omega = np.degrees(np.linalg.norm(np.array(a.camera["omega"])[1:], axis=1))
    assert 0 < omega.max() < 1.0                      # smooth: under a degree per frame


def test_a_collision_aimed_along_a_turning_path_hits_where_and_when_it_was_aimed():
    path = CameraPath(speed_mps=15.0, yaw_rate_dps=3.0, bounce_deg=0.5)
    start, width = (-4.0, 0.2, 30.0), 1.8
    car = ApproachObject(kind="collision", shape="square", width_m=width, start=start, onset=3,
                         velocity=meeting(path, 3 / 30.0, start, 1.5, aim=(0.3, 0.0)))
    # a parked car straight ahead on the straight-on line misses the turning path: not a collision
    parked = ApproachObject(kind="pass", shape="square", width_m=width, start=(3.0, 0.2, 25.0), velocity=(0, 0, 0))
    stim = approach([car, parked], size=SIZE, frames=40, camera=path, supersample=1)
    truth = stim.objects[0]
    assert truth.contact_frame == pytest.approx(3 + 1.5 * 30, abs=1 / 64)
    assert truth.miss == pytest.approx(0.3 / width, abs=1e-3)
    assert stim.objects[1].kind == "pass" and stim.objects[1].miss > 1.0
    with pytest.raises(ValueError, match="misses the camera centre"):   # straight at it would miss in the turn
        approach([ApproachObject(kind="collision", width_m=width, start=(0, 0, 30.0), velocity=(0, 0, 0))],
                 size=SIZE, frames=10, camera=path)


@pytest.mark.parametrize("setting", REAL_USE)
def test_a_real_use_scene_generates_and_its_truth_parses(setting, tmp_path):
    stim = real_use_scene(setting, 1, 5, duration_s=2.0, size=SIZE, supersample=1)
    gt = tmp_path / "ground_truth.json"
    gt.write_text(json.dumps({"videos": {"s.mkv": stim.to_ground_truth()}}))
    video = load(gt).match(tmp_path / "s.mkv")
    kinds = [o.kind for o in video.objects]
    assert "collision" in kinds and "pass" in kinds
    assert len(video.camera["omega"]) == len(video.camera["heading"]) == len(stim.frames)
    if setting == "drive":                               # the roadside: passed, never a collision
        roadside = [o for o in stim.objects if o.extra["velocity_mps"] == [0.0, 0.0, 0.0]]
        assert len(roadside) == 6 and {o.kind for o in roadside} == {"pass"}
        assert all(o.miss >= 1.0 for o in roadside)


def test_the_suite_adds_five_scenes_per_setting_of_real_use_and_keeps_the_rest():
    full, quick = suite(), suite(quick=True)
    assert len(full) == 45 and [s.name for s in full[:30]][::5] == [
        "plain_static_0", "texture_static_0", "texture_pan_0", "texture_tilt_0", "ground_forward_0", "ground_static_0"]
    assert [s.name for s in full[30:]] == [f"{u}_{k}" for u in REAL_USE for k in range(5)]
    assert [s.name for s in quick] == ["quick_plain_static", "quick_texture_pan", "quick_ground_forward",
                                       "quick_texture_static"]


def test_a_holdout_suite_draws_the_same_settings_with_other_seeds():
    std, held = suite(settings=["drive", "texture_pan"]), suite(settings=["drive", "texture_pan"], holdout=1)
    assert [s.name for s in std] == [f"texture_pan_{k}" for k in range(5)] + [f"drive_{k}" for k in range(5)]
    assert [s.name for s in held] == [f"{s.name}_h1" for s in std]
    assert all(h.seed != s.seed and (h.camera, h.background, h.index) == (s.camera, s.background, s.index)
               for h, s in zip(held, std))
    # drive_0: another draw of the same kind of road (its first 2 s of 5: the seeds are the scenes')
    a, b = (dataclasses.replace(s, duration_s=2.0).generate() for s in (std[5], held[5]))
    assert a.frames.shape == b.frames.shape and not np.array_equal(a.frames[0], b.frames[0])


def test_holdouts_pooled_are_each_holdouts_scenes_in_turn():
    """``holdout=[0, 1, 2]`` (``--holdout 0-2``): the standard suite's scenes, then holdout 1's, then 2's, each as
    drawn alone (names and seeds), so one report pools them; a holdout named twice counts once."""
    one = [suite(settings=["drone"], holdout=h) for h in (0, 1, 2)]
    pooled = suite(settings=["drone"], holdout=[0, 1, 2, 1])
    assert [(s.name, s.seed) for s in pooled] == [(s.name, s.seed) for part in one for s in part]
    assert len({s.name for s in pooled}) == 15
    with pytest.raises(InputValueError, match="holdout must be"):
        suite(holdout=[])
    with pytest.raises(InputValueError, match="holdout must be"):
        suite(holdout=[3, -1])


def test_by_setting_separates_still_and_moving_cameras():
    class Ev:
        warning_objects = [{"model": "m", "video": "plain_static_0.mkv", "contact_frame": 9, "warned": True},
                           {"model": "m", "video": "drive_0.mkv", "contact_frame": 9, "warned": False},
                           {"model": "m", "video": "drive_1.mkv", "contact_frame": 9, "warned": True}]
        warning_videos = [{"model": "m", "video": "plain_static_0.mkv", "frames_scored": 500, "false_episodes": 1},
                          {"model": "m", "video": "drive_0.mkv", "frames_scored": 1000, "false_episodes": 0},
                          {"model": "m", "video": "drive_1.mkv", "frames_scored": 1000, "false_episodes": 3,
                           "collision_objects_unseen": 1}]

    scenes = [s for s in suite() if s.name in ("plain_static_0", "drive_0", "drive_1")]
    rows = {r["setting"]: r for r in by_setting(Ev(), scenes, ["m"])}
    assert rows["drive"]["m"] == {"warned": 1, "collision_objects": 2, "unseen": 1, "false_episodes_per_1000": 1.5}
    assert rows["still camera"]["m"] == {"warned": 1, "collision_objects": 1, "unseen": 0,
                                         "false_episodes_per_1000": 2.0}
    assert rows["moving camera"]["scenes"] == 2


def test_lossless_writing_is_byte_reproducible_and_exact(tmp_path):
    frames = np.random.default_rng(0).integers(0, 256, (6, 24, 32)).astype(np.uint8)
    a, b = write_lossless_video(tmp_path / "a.mkv", frames, 30.0), write_lossless_video(tmp_path / "b.mkv", frames, 30.0)
    assert hashlib.sha256(a.read_bytes()).digest() == hashlib.sha256(b.read_bytes()).digest()
    back = np.asarray(read_video(a)[0])
    assert np.array_equal(back[..., 0] if back.ndim == 4 else back, frames)
