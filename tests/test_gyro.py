"""A gyro instead of the estimated rotation (issue 22 item 1): ``Model.step(frame, t, gyro=...)``,
``mlplc2.run(..., gyro=)`` and ``mlplc2 run --gyro FILE.csv``.

The scenes are rendered by :func:`mlplc2.stimuli.approach` with a :class:`~mlplc2.stimuli.CameraPath`
whose true rotation per frame is known (``stimulus.camera["omega"]``): the expected values are the
rendered camera's, not output of the code under test.
"""

import json
import math
from fractions import Fraction

import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.cli import main
from mlplc2.io.gyro import Gyro

from .helpers import score_collision

FPS = 30.0
RATE = math.radians(12.0)              # rad/s: a pan to the right at 12 deg/s


def _pan(objects=(), frames=12, size=(320, 240)):
    st = stimuli.approach(list(objects), size=size, fps=FPS, frames=frames, background="texture",
                          camera=stimuli.CameraPath(yaw_rate_dps=math.degrees(RATE)), noise_std=2.0, seed=5)
    return st, _rates(st)


def _rates(st):
    """The gyro of the rendered camera: its rate (rad/s) at each frame. ``camera["omega"][k]`` is the turn
    from frame k - 1 to k (none before frame 0); the path turns at a constant rate, at frame 0 too."""
    omega = np.array(st.camera["omega"])
    omega[0] = omega[1]
    return omega * FPS


def _motions(frames, rates=None):
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True, hfov_deg=60.0)
    out = []
    for k, f in enumerate(frames):
        model.step(f, gyro=None if rates is None else rates[k])
        out.append(model.camera_motion)
    return out[1:]


def test_a_given_gyro_rate_agrees_with_the_estimate_on_a_pan():
    st, rates = _pan()
    assert rates[:, 1] == pytest.approx(RATE) and not rates[:, [0, 2]].any()   # the path's truth: a pan right is +wy
    for est, given in zip(_motions(st.frames), _motions(st.frames, rates)):
        assert given.given and not est.given
        assert given.omega == pytest.approx((0.0, RATE / FPS, 0.0), abs=1e-12)   # rad/s over the 1/30 s interval
        assert np.allclose(est.omega, given.omega, atol=0.05 * RATE / FPS)
        assert given.rotation_confidence > 0.7               # the images agree with the gyro


def test_a_wrong_sign_gyro_is_flagged_by_the_images():
    st, rates = _pan()
    for m in _motions(st.frames, -rates):
        assert m.given and m.omega[1] < 0
        assert m.rotation_confidence < 0.2                   # the images disagree: CameraMotion says so


def test_a_model_given_the_true_gyro_warns_the_collision_with_the_right_time_to_contact():
    """As tests/test_camera.py's stabilised pan, with the gyro in place of the estimate: one target
    on the object whose time to contact follows the truth within 15 % in the last second, a
    warning before contact and none on the static world."""
    obj = stimuli.ApproachObject.collision(ttc_s=2.0, at=(200.0, 110.0), width_px=8.0)
    st = stimuli.approach([obj], size=(320, 240), fps=FPS, background="texture",
                          camera=stimuli.CameraPath(yaw_rate_dps=10.0), noise_std=2.0, seed=2)
    rates = _rates(st)
    truth = st.objects[0]
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True, hfov_deg=60.0)
    outputs = []
    for k, f in enumerate(st.frames):
        outputs.append(model.step(f, gyro=rates[k]))
        assert model.camera_motion.given
    errors, warned, false = score_collision(outputs, truth, FPS)
    assert warned and false == 0
    assert errors and float(np.median(errors)) < 0.15


def test_held_frames_accumulate_the_gyro_over_the_held_interval():
    """A video whose every frame is shown twice (held: no step) with a gyro at each 1/30 s: the
    processed frame's rotation is the gyro's over both intervals (trapezoid of the rates)."""
    st, _ = _pan(frames=6, size=(160, 120))
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True, hfov_deg=60.0, repeat_threshold=16.0)
    given = []
    for k, f in enumerate(np.repeat(st.frames, 2, axis=0)):
        rate = (0.0, 0.1 * (k + 1), 0.0)                       # rad/s, growing: a trapezoid is exact
        out = model.step(f, gyro=rate)
        if not out.repeated and k:
            given.append((k, model.rotation_given))
    assert len(given) == 5
    for k, rot in given:      # rates 0.1 (k - 1), 0.1 k, 0.1 (k + 1) at frames k - 2, k - 1, k: 0.2 k / 30 rad
        assert rot == pytest.approx((0.0, 0.2 * k / FPS, 0.0))


def test_models_that_cannot_use_a_gyro_say_why():
    frame = np.zeros((60, 80), np.uint8)
    for model, why in [(mlplc2.MLPLC2(fps=FPS), "stabilise=False"), (mlplc2.MLPLC2(fps=FPS, stabilise=True), "hfov"),
                       (mlplc2.get_model("lgmd2")(fps=FPS), "takes no gyro")]:
        with pytest.raises(mlplc2.InputError, match=why) as err:
            model.step(frame, gyro=(0.0, 0.1, 0.0))
        assert "--" not in str(err.value)                     # Python's names, not the command line's
        model.step(frame)                                     # the error changed no state
        assert model.frame_index == 1
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True, hfov_deg=60.0)
    for bad in [(0.0, 0.1), (0.0, float("nan"), 0.0), "fast"]:
        with pytest.raises(mlplc2.InputError, match="gyro"):
            model.step(frame, gyro=bad)


def _csv(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def test_the_gyro_file_is_interpolated_at_each_time(tmp_path):
    g = Gyro.load(_csv(tmp_path / "g.csv", "t,wz,wy,wx,temp\n0,0,0,1,20\n1,3,2,-1,21\n"))
    assert g.at(0.25, FPS) == pytest.approx((0.5, 0.5, 0.75))  # columns by name, others ignored
    assert g.at(1.0 + 0.5 / FPS, FPS) == pytest.approx((-1.0, 2.0, 3.0))   # half a frame past the end: held
    with pytest.raises(mlplc2.InputError, match="covers t = 0 to 1 s"):
        g.at(1.2, FPS)
    assert Gyro.load(np.array([[0, 1, 2, 3], [2, 1, 2, 3]])).at(1.0, FPS) == (1.0, 2.0, 3.0)
    # a source of unknown length (a stream): where its frames start, not 'the run's frames are at 0 s'
    with pytest.raises(mlplc2.InputError, match=r"covers t = 1 to 2 s but the run's frames start at 0 s \("):
        Gyro.load(np.array([[1, 0, 0, 0], [2, 0, 0, 0]])).check_covers(0.0, None, FPS)


def test_a_gyro_whose_times_look_like_milliseconds_is_warned_of_once():
    """A 100 Hz gyro logged in milliseconds covers a short clip's frames (0-9990 against 0-1 s), so the span
    check passes and the wrong rates would be used without a word; its samples 300 frame intervals apart say it."""
    t = np.arange(1000) * 10.0                                   # 100 Hz in ms
    g = Gyro.load(np.column_stack([t, np.zeros((1000, 3))]))
    with pytest.warns(mlplc2.InputWarning, match=r"10 s apart at the median, 300 frame intervals: is t in seconds"):
        g.check_covers(0.0, 1.0, 30.0)
    g.at(0.5, 30.0)                                              # once: no second warning (warnings are errors here)
    seconds = Gyro.load(np.column_stack([t / 1000.0, np.zeros((1000, 3))]))
    seconds.check_covers(0.0, 1.0, 30.0)                         # the same gyro in seconds: silent
    Gyro.load(np.array([[0, 1, 2, 3], [60, 1, 2, 3]])).check_covers(0.0, 1.0, 30.0)  # two samples: a constant rate


@pytest.mark.parametrize("text, match", [("t,wx,wy\n0,0,0\n1,0,0\n", "missing: wz"),
                                         ("t,wx,wy,wz\n0,0,0,0\n0.5,0,x,0\n", "line 3"),
                                         ("t,wx,wy,wz\n0,0,0,0\n0,1,0,0\n", "t must increase"),
                                         ("t,wx,wy,wz\n0,0,0,0\n", "at least 2 samples"),
                                         ("", r"missing: t, wx, wy, wz\)$"),
                                         # another separator: the message shows the line it read
                                         ("t;wx;wy;wz\n0;0;0;0\n1;0;0;0\n",
                                          r"comma-separated .*missing: t, wx, wy, wz; "
                                          r"its first line: 't;wx;wy;wz'\)$")])
def test_a_malformed_gyro_file_is_one_clear_error(tmp_path, text, match):
    with pytest.raises(mlplc2.InputError, match=match):
        Gyro.load(_csv(tmp_path / "g.csv", text))


def _folder(tmp_path, frames):
    d = tmp_path / "frames"
    d.mkdir()
    for k, f in enumerate(frames):
        cv2.imwrite(str(d / f"{k:03d}.png"), f)
    return d


def test_run_gives_the_gyro_to_the_models_that_stabilise(tmp_path):
    st, rates = _pan(frames=6, size=(160, 120))
    src = _folder(tmp_path, st.frames)
    rows = np.column_stack([np.arange(6) / FPS, rates])
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True)
    mlplc2.run(src, [model, "lgmd2"], out=False, gyro=rows, hfov_deg=60.0, quiet=True)
    assert model.camera_motion.given and model.camera_motion.omega[1] == pytest.approx(RATE / FPS)
    with pytest.raises(mlplc2.InputError, match=r"covers t = 0 to 0.1 s but the run's frames are at 0 to 0.166667"):
        mlplc2.run(src, "mlplc2", out=False, gyro=rows[:4], hfov_deg=60.0, quiet=True)
    # a robot's epoch clock, not shifted to the video's: the message shows where the samples lie (it read
    # 'covers t = 1.73325e+09 to 1.73325e+09 s', both ends alike)
    epoch = rows + [1733250000.125, 0, 0, 0]
    with pytest.raises(mlplc2.InputError, match=r"covers t = 1733250000\.125 to 1733250000\.292 s but the run's "
                                                 r"frames are at 0 to 0\.166667 s"):
        mlplc2.run(src, "mlplc2", out=False, gyro=epoch, hfov_deg=60.0, quiet=True)


def test_a_live_gyro_is_asked_each_frames_rate_and_gives_what_its_samples_give(tmp_path):
    """A robot's IMU read as the frames come: ``stream(..., gyro=rate)`` asks ``rate(t)`` once per frame with the
    frame's time and gives the models what the same rates given as samples give; None leaves a frame to the images;
    anything but three finite numbers is one clear error that names the frame's time."""
    from .helpers import jsonl_results

    st, rates = _pan(frames=6, size=(160, 120))
    src = _folder(tmp_path, st.frames)
    rows = np.column_stack([np.arange(6) / FPS, rates])
    asked = []

    def rate(t):
        asked.append(t)
        return tuple(rates[int(round(t * FPS))])

    live = mlplc2.MLPLC2(fps=FPS, stabilise=True)
    lines = list(mlplc2.stream(src, [live], gyro=rate, hfov_deg=60.0))
    assert asked == pytest.approx(list(np.arange(6) / FPS), abs=1e-6)
    assert live.camera_motion.given and live.camera_motion.omega[1] == pytest.approx(RATE / FPS)
    sampled = mlplc2.MLPLC2(fps=FPS, stabilise=True)
    strip = lambda ls: jsonl_results("\n".join(json.dumps(line) for line in ls))     # noqa: E731
    assert strip(lines) == strip(mlplc2.stream(src, [sampled], gyro=rows, hfov_deg=60.0))
    images = mlplc2.MLPLC2(fps=FPS, stabilise=True)
    list(mlplc2.stream(src, [images], gyro=lambda t: None, hfov_deg=60.0))
    assert not images.camera_motion.given
    with pytest.raises(mlplc2.InputError, match=r"gave \(0\.1, nan, 0\.0\) at t = 0 s; expected three finite"):
        list(mlplc2.stream(src, "mlplc2", gyro=lambda t: (0.1, float("nan"), 0.0), hfov_deg=60.0))


def test_cli_gyro_errors_are_one_line_and_write_nothing(tmp_path, capsys):
    st, rates = _pan(frames=4, size=(160, 120))
    src = _folder(tmp_path, st.frames)
    good = _csv(tmp_path / "g.csv", "t,wx,wy,wz\n0,0,0.2,0\n1,0,0.2,0\n")
    for args, match in [(["--gyro", str(good)], "field of view (--hfov)"),
                        (["--gyro", str(good), "--hfov", "60", "--no-stabilise"], "(--no-stabilise)"),
                        (["--gyro", str(tmp_path / "none.csv"), "--hfov", "60"], "cannot read the gyro file")]:
        out = tmp_path / "out"
        assert main(["run", str(src), "--out", str(out), "-q", *args]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and match in err, err
        assert not out.exists()
    assert main(["run", str(src), "--out", str(tmp_path / "ok"), "-q", "--gyro", str(good), "--hfov", "60"]) == 0


def test_the_flow_baseline_takes_the_gyro_too():
    st, rates = _pan(frames=4, size=(160, 120))
    model = mlplc2.get_model("flow")(fps=FPS, hfov_deg=60.0)
    for k, f in enumerate(st.frames):
        model.step(f, gyro=rates[k])
    assert model.camera_motion.given and model.camera_motion.omega[1] == pytest.approx(RATE / FPS)
    with pytest.raises(mlplc2.InputError, match="field of view"):
        mlplc2.get_model("flow")(fps=FPS).step(st.frames[0], gyro=rates[0])


def test_a_fixed_heading_is_given_in_the_pixels_of_the_frames_given():
    """``TargetParams.heading`` (the one place for a known heading) reaches the camera-motion
    estimate in working pixels: frames 480 px wide work at 320, so the principal point (239.5, 179.5)
    is (159.5, 119.5) there; the estimate then reports it exactly (estimated, it would wander by pixels)."""
    st = stimuli.approach([], size=(480, 360), fps=FPS, frames=10, background="ground",
                          camera=stimuli.CameraPath(speed_mps=8.0), noise_std=2.0, seed=5)
    from mlplc2.targets import TargetParams
    model = mlplc2.MLPLC2(fps=FPS, stabilise=True, target_params=TargetParams(heading=(239.5, 179.5)))
    heads = []
    for f in st.frames:
        model.step(f)
        heads.append(model.camera_motion.heading)
    heads = [h for h in heads if h is not None]
    assert len(heads) >= 4 and all(h == pytest.approx((159.5, 119.5), abs=1e-6) for h in heads)


def test_a_given_rotation_is_compensated_whatever_the_images_say():
    """A gyro is compensated even where the images cannot tell (no texture: confidence 0); an estimate is not."""
    from mlplc2.camera import CameraMotion

    assert CameraMotion(omega=(0.0, 0.01, 0.0), rotation_confidence=0.0, given=True).trusted
    assert not CameraMotion(omega=(0.0, 0.01, 0.0), rotation_confidence=0.0).trusted
    assert not CameraMotion(rotation_confidence=1.0, given=True).trusted      # no rotation: nothing to do


def test_a_gyro_short_of_the_frames_timestamps_is_refused_before_the_run(tmp_path, capsys):
    """A clip whose timestamps start at 2 s (frames 2 to 3.97 s, PyAV's clock) and a gyro of 0 to 2 s:
    refused before any output, not at the first frame past 2 s (the check used index / fps)."""
    av = pytest.importorskip("av")
    clip = tmp_path / "late.mp4"
    with av.open(str(clip), "w") as c:
        s = c.add_stream("mpeg4", rate=30)
        s.width, s.height, s.pix_fmt = 160, 120, "yuv420p"
        for k, f in enumerate(np.random.default_rng(0).integers(0, 256, (60, 120, 160, 3), dtype=np.uint8)):
            frame = av.VideoFrame.from_ndarray(f, format="rgb24")
            frame.pts, frame.time_base = 60 + k, Fraction(1, 30)
            c.mux(s.encode(frame))
        c.mux(s.encode())
    gyro = _csv(tmp_path / "g.csv", "t,wx,wy,wz\n0,0,0.2,0\n2,0,0.2,0\n")
    out = tmp_path / "o"
    assert main(["run", str(clip), "--decoder", "pyav", "--hfov", "60", "--gyro", str(gyro), "--out", str(out),
                 "-q"]) == 2
    assert capsys.readouterr().err.startswith(f"mlplc2: error: {gyro}: the gyro covers t = 0 to 2 s but the run's "
                                              "frames are at 2 to 3.96667 s")
    assert not out.exists()


def test_a_gyro_that_ends_on_a_source_of_unknown_length_stops_the_run_keeping_its_outputs(tmp_path):
    """A Matroska clip piped to stdin (its length unknown until its end, so the gyro's span cannot be checked
    before the run) and a gyro of 0 to 1 s: the run stops at the first frame past the gyro (1 s plus
    :data:`~mlplc2.io.gyro.SLACK` of a frame: frame 32 at 1.067 s), with one line naming the gyro, and
    ``fields.json`` written for the 32 frames done (not complete), as a reader that goes away leaves it."""
    av = pytest.importorskip("av")
    import json
    import subprocess
    import sys

    clip = tmp_path / "clip.mkv"
    with av.open(str(clip), "w") as c:
        s = c.add_stream("ffv1", rate=30)
        s.width, s.height, s.pix_fmt = 160, 120, "yuv420p"
        for f in np.random.default_rng(0).integers(0, 256, (60, 120, 160, 3), dtype=np.uint8):
            c.mux(s.encode(av.VideoFrame.from_ndarray(f, format="rgb24")))
        c.mux(s.encode())
    gyro = _csv(tmp_path / "g.csv", "t,wx,wy,wz\n0,0,0.2,0\n1,0,0.2,0\n")
    out = tmp_path / "o"
    with open(clip, "rb") as stdin:
        proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "--hfov", "60", "--gyro", str(gyro),
                               "-o", str(out), "-q"], stdin=stdin, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"mlplc2: error: {gyro}: the gyro covers t = 0 to 1 s but a frame is at 1.067 s")
    assert proc.stderr.rstrip().endswith("the outputs cover the 32 frames before")
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == 32 and not summary["complete"] and str(gyro) in summary["error"]
    frames = {line.split(",")[0] for line in (out / "responses.csv").read_text().splitlines()[1:]}
    assert frames == {str(k) for k in range(32)}          # every frame done is in the CSV, and none after
