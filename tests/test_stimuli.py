"""Tests of mlplc2.stimuli: geometry measured from the frames, ground truth, paper files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mlplc2 import stimuli as S
from mlplc2._validation import InputError
from mlplc2.camera import focal_length
from mlplc2.evaluation.truth import PHASES

from .conftest import PAPER, read_gray


def _read_video(path: Path) -> np.ndarray:
    return np.array(read_gray(path))


def _need_paper(*parts: str) -> Path:
    path = PAPER.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{path} not available")
    return path


def _bbox(mask: np.ndarray):
    ys, xs = np.nonzero(mask)
    return xs.min(), xs.max(), ys.min(), ys.max()


# --------------------------------------------------------------------- basics

@pytest.mark.parametrize("name", S.BASIC_NAMES)
def test_basic_shapes_dtype_fps(name):
    stim = S.basic(name)
    assert stim.frames.shape == (50, 100, 100)
    assert stim.frames.dtype == np.uint8
    assert stim.fps == 30.0
    assert stim.name == name
    assert len(stim.objects) == 1
    assert len(stim.objects[0].sizes) == 50
    gt = stim.to_ground_truth()
    assert gt["size"] == [100, 100] and gt["frames"] == 50


def test_basic_names_order():
    assert S.BASIC_NAMES == ("dark_approach", "dark_recede", "bright_approach", "bright_recede",
                             "translating", "grating")
    assert set(S.BASIC_NAMES) <= set(S.NAMES)


@pytest.mark.parametrize("polarity", ["dark", "bright"])
def test_approach_square_grows_2px_per_frame_and_is_centred(polarity):
    stim = S.basic(f"{polarity}_approach")
    obj = stim.objects[0]
    level = 0 if polarity == "dark" else S.BASIC_WHITE
    background = S.BASIC_WHITE if polarity == "dark" else 0
    assert stim.frames[0, 0, 0] == background
    for t in range(50):
        mask = stim.frames[t] == level
        side = 2 * t + 1
        assert mask.sum() == side * side, t
        x0, x1, y0, y1 = _bbox(mask)
        assert x1 - x0 + 1 == side and y1 - y0 + 1 == side
        assert (x0 + x1) / 2 == obj.center[0] and (y0 + y1) / 2 == obj.center[1]
        assert obj.sizes[t] == side
    areas = (stim.frames == level).sum(axis=(1, 2))
    # side grows by 2 px/frame: area difference (2t+3)^2 - (2t+1)^2 = 8t + 8
    assert np.array_equal(np.diff(areas), 8 * np.arange(49) + 8)
    assert stim.center_at(10) == (50.0, 50.0)


@pytest.mark.parametrize("polarity", ["dark", "bright"])
def test_recede_is_time_reverse_of_approach(polarity):
    app = S.basic(f"{polarity}_approach").frames
    rec = S.basic(f"{polarity}_recede").frames
    # the paper's recede file: frame t has side 1 + 2 (T - t) (101 -> 3 px), i.e. frame t of the
    # recede equals frame T - t of the approach; frame 0 is all object.
    assert np.array_equal(rec[1:], app[:0:-1])
    level = 0 if polarity == "dark" else S.BASIC_WHITE
    assert (rec[0] == level).all()


def test_translating_bar_moves_right_2px_per_frame():
    stim = S.basic("translating")
    lefts = []
    for t in range(40):
        x0, x1, y0, y1 = _bbox(stim.frames[t] == 0)
        assert (x1 - x0 + 1, y1 - y0 + 1) == (21, 41)
        assert (y0, y1) == (30, 70)
        lefts.append(x0)
    assert np.all(np.diff(lefts) == 2)
    assert lefts[0] == 0
    cx0 = stim.center_at(0)[0]
    assert stim.center_at(7)[0] == cx0 + 14


def test_grating_moves_right_1px_per_frame():
    stim = S.basic("grating")
    f = stim.frames
    assert (f[:, :1, :] == f).all()             # vertical bars: every row equal
    for t in range(49):
        assert np.array_equal(f[t + 1, :, 1:], f[t, :, :-1])
    row = f[0, 0] == 0
    assert row.sum() in (41, 43, 42)            # 2.5 periods of 40 px with 21-px dark bars
    assert np.array_equal(f[0], f[40])          # period 40 px at 1 px/frame


def test_basic_dark_approach_matches_paper_video():
    video = _read_video(_need_paper("basic", "test_black_approach.avi"))
    ours = S.basic("dark_approach").frames
    assert video.shape == ours.shape
    mad = np.abs(video.astype(np.int16) - ours).mean(axis=(1, 2))
    assert mad.max() < 4.0


@pytest.mark.parametrize("name,file", [
    ("dark_recede", "test_black_recede.avi"), ("bright_approach", "test_white_approach.avi"),
    ("bright_recede", "test_white_recede.avi"), ("translating", "test_translating.avi"),
    ("grating", "test_grating.avi")])
def test_other_basics_match_paper_videos(name, file):
    video = _read_video(_need_paper("basic", file))
    ours = S.basic(name).frames
    mad = np.abs(video.astype(np.int16) - ours).mean(axis=(1, 2))
    assert mad.max() < 4.0


# --------------------------------------------------------------------- scenes

def test_procedural_background_scrolls_left_1px_per_frame():
    obj = S.SceneObject(center=(100, 100), onset=5, approach=10, hold=0, recede=0)
    stim = S.scene([obj], size=(160, 120), frames=30, seed=3)
    f = stim.frames.astype(np.int16)
    for t in range(29):
        # content moves left: frame t+1 column x shows what frame t had at column x + 1
        diff = f[t + 1, :, :-1] - f[t, :, 1:]
        no_object = np.ones(diff.shape, bool)
        for tt in (t, t + 1):
            side = stim.objects[0].sizes[tt]
            if side > 0:
                lo = math.floor(100 - side / 2 + 0.5) - 2
                hi = math.floor(100 + side / 2 + 0.5) + 2
                no_object[max(lo, 0):hi, max(lo - 1, 0):hi] = False
        assert np.abs(diff[no_object]).max() == 0, t


def test_fractional_scroll_interpolates():
    bg = np.tile(np.arange(200, dtype=np.float32)[None, :], (10, 1))
    stim = S.scene([], size=(20, 10), frames=5, background=bg, scroll=0.5)
    assert np.array_equal(stim.frames[2, 0], np.arange(1, 21))
    assert np.all(np.abs(stim.frames[1, 0].astype(float) - (np.arange(20) + 0.5)) <= 0.5)


def test_procedural_background_statistics_and_determinism():
    a = S.procedural_background(720, 240, seed=1)
    b = S.procedural_background(720, 240, seed=1)
    c = S.procedural_background(720, 240, seed=2)
    assert a.shape == (240, 720) and a.dtype == np.uint8
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert 120 < a.mean() < 160 and 30 < a.std() < 50
    assert np.percentile(a, 2) >= 55 and np.percentile(a, 98) <= 225


def test_procedural_background_contrast_like_paper():
    path = _need_paper("backgrounds", "outdoor_2.jpg")
    cv2 = pytest.importorskip("cv2")
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    img = cv2.resize(img, (round(img.shape[1] * 240 / img.shape[0]), 240), interpolation=cv2.INTER_AREA)
    ours = S.procedural_background(720, 240, seed=0)
    assert abs(ours.std() - img.std()) < 10
    assert abs(ours.mean() - img.mean()) < 25


def test_four_phase_truth_and_squares():
    stim = S.four_phase(seed=0)
    assert stim.frames.shape == (400, 240, 320) and stim.frames.dtype == np.uint8
    gt = stim.to_ground_truth()
    centers = [o["center"] for o in gt["objects"]]
    assert centers == [[160, 120], [240, 60], [80, 180], [80, 60], [240, 180]]
    assert gt["objects"][0]["approach"] == [0, 40]
    assert gt["objects"][0]["hold"] == [40, 60]
    assert gt["objects"][0]["recede"] == [60, 100]
    assert gt["objects"][4]["approach"] == [300, 340]
    sizes = np.array(stim.objects[0].sizes)
    assert np.array_equal(sizes[:40], 1 + 2 * np.arange(40))
    assert (sizes[40:60] == 79).all()
    assert np.array_equal(sizes[60:100], sizes[:40][::-1])
    assert (sizes[100:] == 0).all()
    # the square is really there (procedural background never reaches 0)
    for oid, t in [(1, 50), (2, 150), (3, 250), (4, 350), (5, 350)]:
        cx, cy = stim.center_at(t, oid)
        patch = stim.frames[t, int(cy) - 39:int(cy) + 40, int(cx) - 39:int(cx) + 40]
        assert (patch == 0).all()
    assert (stim.frames[99] == 0).sum() == 1 and (stim.frames[100] == 0).sum() == 1


def test_four_phase_matches_paper_scene():
    video = _read_video(_need_paper("scenes", "outdoor_2_black_4_period.avi"))
    bg = _need_paper("backgrounds", "outdoor_2.jpg")
    ours = S.four_phase(background=str(bg)).frames
    assert video.shape == ours.shape
    mad = np.abs(video.astype(np.int16) - ours).mean(axis=(1, 2))
    assert mad.max() < 6.0


def test_six_objects_truth_matches_paper_entry():
    stim = S.six_objects()
    assert stim.frames.shape == (120, 240, 320)
    gt = stim.to_ground_truth()
    path = PAPER / "ground_truth.json"
    if path.exists():
        ref = json.loads(path.read_text())["videos"]["scenes/outdoor_3_black_expand_multi_6.avi"]
        for mine, theirs in zip(gt["objects"], ref["objects"], strict=True):
            for key, value in theirs.items():
                assert mine[key] == value, key
    obj = stim.objects[0]
    assert obj.approach == (5, 45) and obj.hold == (45, 55) and obj.recede is None
    assert obj.sizes[44] == 79 and obj.sizes[45] == 81 and obj.sizes[55] == 0


def test_overlapping_objects_and_clipping():
    objs = [S.SceneObject(center=(5, 5), approach=30, hold=0, recede=0),
            S.SceneObject(center=(60, 40), onset=10, approach=10, hold=5, recede=5, polarity="bright")]
    stim = S.scene(objs, size=(80, 60), frames=40, background="plain")
    assert stim.frames[0, 0, 0] == 128                  # mixed polarities -> mid grey
    assert stim.objects[0].sizes[29] == 59
    # side 59 centred at (5, 5) covers columns/rows -24..34 -> 0..34 after clipping
    assert (stim.frames[29] == 0).sum() == 35 ** 2
    assert (stim.frames[15] == 255).sum() == 11 ** 2


def test_physical_looming_follows_atan_law():
    stim = S.looming(half_size=0.5, speed=5.0, contact_time=2.0, fps=30.0, hfov_deg=60.0)
    obj = stim.objects[0]
    w, h = stim.size
    f = (w / 2) / math.tan(math.radians(30))
    assert obj.contact_frame == pytest.approx(60.0)
    assert obj.extra["half_size"] == 0.5 and obj.extra["speed"] == 5.0
    assert obj.approach == (0, len(stim))
    for t in range(len(stim)):
        theta = math.atan(0.5 / (5.0 * (2.0 - t / 30.0)))
        expected = 2 * f * math.tan(theta)
        mask = stim.frames[t] == 0
        measured = math.sqrt(mask.sum()) if expected < h else mask.any(axis=0).sum()
        assert abs(measured - expected) <= 1.0, (t, measured, expected)
        assert obj.sizes[t] == pytest.approx(expected)
    # stops before the side exceeds the frame
    assert obj.sizes[-1] <= max(w, h)
    nxt = 2 * f * 0.5 / (5.0 * (2.0 - len(stim) / 30.0))
    assert nxt > max(w, h)


def test_looming_duration_and_textured_background():
    stim = S.looming(duration=2.5, background="procedural", seed=4, polarity="bright")
    assert len(stim) == 75
    obj = stim.objects[0]
    assert obj.approach[1] < 60
    assert all(s == 0 for s in obj.sizes[obj.approach[1]:])
    gt = stim.to_ground_truth()
    assert set(gt["objects"][0]) >= {"contact_frame", "half_size", "speed", "sizes", "approach"}


def test_physical_scene_object():
    obj = S.SceneObject(center=(160, 120), approach=20, hold=5, recede=20, looming="physical",
                        half_size=0.3, speed=4.0, contact_frame=40.0)
    stim = S.scene([obj], frames=50, background="plain")
    sizes = np.array(stim.objects[0].sizes)
    assert stim.objects[0].contact_frame == 40.0
    assert np.all(np.diff(sizes[:20]) > 0)
    assert np.array_equal(sizes[25:45], sizes[:20][::-1])


# ----------------------------------------------------------------- truth dict

def test_ground_truth_json_round_trip_and_schema():
    stims = [S.basic(n) for n in S.BASIC_NAMES] + [S.four_phase(), S.six_objects(), S.looming()]
    allowed_obj_keys = {"id", "center", "polarity", "approach", "hold", "recede", "translate", "note",
                        "sizes", "contact_frame", "half_size", "speed", "velocity"}
    for stim in stims:
        gt = stim.to_ground_truth()
        assert json.loads(json.dumps(gt)) == gt
        assert {"size", "frames", "objects"} <= set(gt)
        for obj in gt["objects"]:
            assert set(obj) <= allowed_obj_keys
            assert len(obj["sizes"]) == gt["frames"]
            assert obj["polarity"] in ("dark", "bright")
    path = PAPER / "ground_truth.json"
    if not path.exists():
        pytest.skip("paper ground truth not available")
    ref = json.loads(path.read_text())["videos"]
    files = {"dark_approach": "basic/test_black_approach.avi", "dark_recede": "basic/test_black_recede.avi",
             "bright_approach": "basic/test_white_approach.avi", "bright_recede": "basic/test_white_recede.avi",
             "translating": "basic/test_translating.avi", "grating": "basic/test_grating.avi",
             "four_phase": "scenes/outdoor_2_black_4_period.avi",
             "six_objects": "scenes/outdoor_3_black_expand_multi_6.avi"}
    for stim in stims[:-1]:
        mine, theirs = stim.to_ground_truth(), ref[files[stim.name]]
        assert mine["size"] == theirs["size"] and mine["frames"] == theirs["frames"]
        assert len(mine["objects"]) == len(theirs["objects"])
        for a, b in zip(mine["objects"], theirs["objects"]):
            assert set(b) - {"note"} <= set(a)
            assert set(a) & set(PHASES) == set(b) & set(PHASES)
            for key in set(b) - {"note"}:
                assert a[key] == b[key], (stim.name, key)


def test_determinism():
    a = S.generate("four_phase", seed=7)
    b = S.generate("four_phase", seed=7)
    c = S.generate("four_phase", seed=8)
    assert np.array_equal(a.frames, b.frames)
    assert not np.array_equal(a.frames, c.frames)
    assert a.to_ground_truth() == b.to_ground_truth()


def test_generate_dispatches_every_name():
    for name in S.NAMES:
        if name in S.BASIC_NAMES:
            stim = S.generate(name, frames=10)
            assert stim.frames.shape == (10, 100, 100)
        else:
            stim = S.generate(name)
        assert stim.name == name
        assert stim.frames.dtype == np.uint8 and stim.frames.ndim == 3


def test_image_and_array_backgrounds(tmp_path):
    cv2 = pytest.importorskip("cv2")
    img = (np.arange(60)[None, :] * 4 + np.zeros((30, 1))).astype(np.uint8)
    path = tmp_path / "bg.png"
    cv2.imwrite(str(path), img)
    a = S.scene([], size=(80, 60), frames=50, background=str(path), scroll=1.0)
    b = S.scene([], size=(80, 60), frames=50, background=img, scroll=1.0)
    assert a.frames.shape == (50, 60, 80)
    assert np.array_equal(a.frames, b.frames)
    rgb = np.repeat(img[:, :, None], 3, axis=2)
    c = S.scene([], size=(80, 60), frames=50, background=rgb, scroll=1.0)
    assert np.abs(c.frames.astype(int) - a.frames).max() <= 1


# --------------------------------------------------------------------- errors

def test_errors_are_clear():
    with pytest.raises(InputError, match="valid names: dark_approach, dark_recede"):
        S.generate("nope")
    with pytest.raises(InputError, match="valid options: size, frames, fps"):
        S.generate("dark_approach", colour="red")
    with pytest.raises(InputError, match="valid names"):
        S.basic("looming")
    with pytest.raises(InputError, match="size must be an integer >= 1"):
        S.basic("grating", size=-5)
    with pytest.raises(InputError, match="onset 500 is outside the video"):
        S.scene([S.SceneObject(center=(10, 10), onset=500)], frames=100)
    with pytest.raises(InputError, match="polarity must be one of dark, bright"):
        S.scene([S.SceneObject(center=(10, 10), polarity="grey")], frames=100)
    with pytest.raises(InputError, match="looming must be one of linear, physical"):
        S.scene([S.SceneObject(center=(10, 10), looming="quadratic")], frames=100)
    with pytest.raises(InputError, match="speed must be > 0"):
        S.looming(speed=-1.0)
    with pytest.raises(InputError, match="width must be an integer >= 1"):
        S.looming(size=(0, 240))
    with pytest.raises(InputError, match="background must be"):
        S.scene([S.SceneObject(center=(10, 10))], frames=100, background="/no/such/file.jpg")
    with pytest.raises(InputError, match="fps"):
        S.generate("six_objects", fps=0)
    with pytest.raises(InputError, match="at most 100 frames"):
        S.four_phase(approach=60, hold=30, recede=40)
    with pytest.raises(InputError, match="no object with id 9"):
        S.basic("dark_approach").center_at(0, 9)
    with pytest.raises(InputError) as info:
        S.generate("grating", x=1)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("call, expect", [
    (lambda: S.looming(speed="5"), "speed must be a number, got '5'"),
    (lambda: S.looming(half_size=None), "half_size must be a number, got None"),
    (lambda: S.scene([S.SceneObject(center=(10, 10))], frames=20, scroll="1"), "scroll must be a number, got '1'"),
    (lambda: S.scene([S.SceneObject(center=(10, 10), growth="2")], frames=20),
     "objects[0].growth must be a number, got '2'"),
    (lambda: S.four_phase(hold="2"), "hold must be an integer >= 0, got '2'"),
    (lambda: S.basic("grating", frames=True), "frames must be an integer >= 1, got True"),
    (lambda: S.looming(size=("64", 48)), "size: width must be an integer >= 1, got '64'"),
])
def test_a_number_given_as_text_is_refused_as_everywhere_else(call, expect):
    """The stimuli's checks are _validation's: a string is no number (InputTypeError, one line),
    as check_real / check_int say it for every other argument."""
    from mlplc2._validation import InputTypeError, InputValueError

    with pytest.raises((InputTypeError, InputValueError)) as info:
        call()
    assert str(info.value) == expect
    assert isinstance(info.value, InputValueError if "True" in expect else InputTypeError)


def test_the_stimuli_still_take_integral_floats_and_numpy_numbers():
    a = S.basic("grating", size=32, frames=np.float64(5.0))
    assert len(a) == 5
    b = S.looming(size=(64.0, 48), speed=np.float32(20.0), half_size=np.int64(1), contact_time=0.3)
    assert b.size == (64, 48)


def test_unknown_option_error_gives_both_spellings_and_the_help():
    with pytest.raises(InputError) as info:
        S.generate("looming", contact=1.0)
    msg = str(info.value)
    assert "valid options: size, center, half_size" in msg and "contact_time" in msg
    assert "--half-size" in msg and "--contact-time" in msg and "see 'mlplc2 stimulus --help'" in msg
    assert list(S.parameters("looming"))[:3] == ["size", "center", "half_size"]
    assert S.parameters("grating")["size"].annotation is int  # annotations resolved to types


def test_physical_recede_without_approach_moves_away_at_its_speed():
    """A physical object that only holds and recedes starts at peak_side and shrinks as a
    square of half-size l moving away at v: side = 2 f l / (d0 + v t), d0 = 2 f l / peak."""
    fps, l, v, peak = 30.0, 0.5, 5.0, 30.0
    obj = S.SceneObject(center=(50, 40), onset=0, approach=0, hold=2, recede=10, looming="physical",
                        peak_side=peak, half_size=l, speed=v)
    st = S.scene([obj], size=(100, 80), frames=14, fps=fps, background="plain", hfov_deg=60.0)
    truth = st.to_ground_truth()["objects"][0]
    assert truth["recede"] == [2, 12]
    f = focal_length(100, 60.0)
    d0 = 2 * f * l / peak
    expect = [peak, peak] + [2 * f * l / (d0 + v * k / fps) for k in range(10)] + [0, 0]
    assert np.allclose(truth["sizes"], expect, atol=1e-6)
    for k in (0, 5, 11):  # the drawn square has the reported side (+-1 px of rounding)
        dark = (np.asarray(st.frames[k]) < 128)
        dark = dark if dark.ndim == 2 else dark[..., 0]
        assert abs(int(dark[40].sum()) - expect[k]) <= 1.5
    assert not (np.asarray(st.frames[12]) < 128).any()
    with pytest.raises(InputError, match="needs peak_side > 0"):
        S.scene([S.SceneObject(center=(50, 40), approach=0, hold=2, recede=10, looming="physical",
                               peak_side=0.0)], size=(100, 80), frames=14)


def test_scene_refuses_huge_requests_and_warns_about_invisible_objects():
    obj = S.SceneObject(center=(50, 40))
    with pytest.raises(InputError, match="moves the background"):
        S.scene([obj], size=(100, 80), scroll=1e6)
    with pytest.raises(InputError, match="GiB"):
        S.scene([obj], size=(100, 80), frames=10**6)
    st = S.scene([S.SceneObject(center=(50, 40), approach=10**12)], size=(100, 80), frames=20)
    sizes = st.to_ground_truth()["objects"][0]["sizes"]
    assert sizes == [1 + 2 * k for k in range(20)]  # an approach longer than the video: its first frames
    with pytest.warns(UserWarning, match=r"objects\[0\] at \(500, 500\) is never visible"):
        S.scene([S.SceneObject(center=(500, 500))], size=(100, 80), frames=20)
    with pytest.warns(UserWarning, match="its side is 0"):
        S.scene([S.SceneObject(center=(50, 40), start_side=0, growth=0)], size=(100, 80), frames=20)
