"""Repeated (duplicated) frames: Model.repeat_threshold and ``mlplc2 run --skip-repeats``."""

from __future__ import annotations

import numpy as np
import pytest

import mlplc2
from mlplc2 import InputError, cli, stimuli
from mlplc2.models.base import MAX_REPEATS, REGISTRY, REPEAT_THRESHOLD

from .conftest import read_gray


def _duplicated(frames, every=3, copies=2, noise=6, seed=0):
    """Each ``every``-th frame repeated ``copies`` times with +-``noise`` grey levels of jitter
    (a frame-rate conversion of a compressed video); returns (frames, index of the original)."""
    rng = np.random.default_rng(seed)
    out, origin = [], []
    for i, f in enumerate(frames):
        out.append(f)
        origin.append(i)
        if i % every == 0:
            for _ in range(copies):
                jitter = rng.integers(-noise, noise + 1, f.shape)
                out.append(np.clip(f.astype(np.int16) + jitter, 0, 255).astype(np.uint8))
                origin.append(i)
    return out, origin


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_duplicates_are_held_and_do_not_change_the_model(name):
    frames = stimuli.four_phase(seed=0).frames[:60]
    dup, origin = _duplicated(frames)
    plain = REGISTRY[name](fps=30.0)
    ref = [plain.step(f) for f in frames]
    model = REGISTRY[name](fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    outs = [model.step(f) for f in dup]
    for k, out in enumerate(outs):
        assert out.frame == k
        first = k == 0 or origin[k] != origin[k - 1]
        assert out.repeated == (not first)
        want = ref[origin[k]]
        assert out.response == want.response
        if REGISTRY[name].has_fields or not REGISTRY[name].has_targets:
            # (the flow baseline's alarm is its targets' warning, which counts the skipped frames' time)
            assert out.collision == want.collision
        assert [(f.x, f.y, f.response) for f in out.fields] == [(f.x, f.y, f.response) for f in want.fields]


def test_without_threshold_every_frame_steps():
    frames = stimuli.four_phase(seed=0).frames[:30]
    dup, _ = _duplicated(frames)
    model = mlplc2.MLPLC2(fps=30.0, repeat_threshold=None)
    assert not any(model.step(f).repeated for f in dup)


def test_duplicated_video_detected_by_default():
    """By default ("auto") the model finds out that a video repeats its frames and holds the
    copies, once it has seen a few of them; a smooth video (a slow approach, small changes first
    and large ones later) is not taken for one."""
    frames = stimuli.four_phase(seed=0).frames[:60]
    dup, origin = _duplicated(frames)
    model = mlplc2.MLPLC2(fps=30.0)
    assert model.repeat_threshold == "auto"
    flags = [model.step(f).repeated for f in dup]
    copies = [k for k in range(1, len(dup)) if origin[k] == origin[k - 1]]
    assert sum(flags[k] for k in copies[len(copies) // 3:]) >= 0.9 * len(copies[len(copies) // 3:])
    assert not any(flags[k] for k in range(1, len(dup)) if origin[k] != origin[k - 1])   # new frames step
    from mlplc2.stimuli import ApproachObject, approach

    slow = approach([ApproachObject.collision(ttc_s=5.0, width_px=4.0, speed_mps=2.0)], background="plain",
                    duration_s=4.5, seed=1)                # anti-aliased: a change every frame
    for cls in (mlplc2.MLPLC2, mlplc2.LGMD2):
        model = cls(fps=30.0)
        assert not any(model.step(f).repeated for f in slow.frames)
    with pytest.raises(InputError):
        cli._repeat_threshold(cli.build_parser().parse_args(["run", "x.avi", "--every-frame", "--skip-repeats"]))


def test_a_still_scene_is_not_held_forever():
    """After MAX_REPEATS held frames the scene counts as still and the model steps (and settles)."""
    st = stimuli.scene([stimuli.SceneObject(center=(160, 120), onset=0, approach=30, hold=0, recede=0)],
                       frames=30, background="plain")
    model = mlplc2.MLPLC2(fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    assert max(model.step(f).response for f in st.frames) > 0
    tail = [model.step(st.frames[-1]) for _ in range(60)]
    assert all(o.repeated for o in tail[:MAX_REPEATS])
    assert not any(o.repeated for o in tail[MAX_REPEATS:])
    assert tail[-1].response == 0.0 and not tail[-1].collision


def test_slow_drift_is_measured_against_the_last_processed_frame():
    """Changes below the threshold accumulate: the frame that takes the total over it steps."""
    base = np.full((60, 80), 100, np.uint8)
    model = mlplc2.LGMD2(fps=30.0, repeat_threshold=10)
    flags = [model.step(base + np.uint8(4 * k)).repeated for k in range(8)]
    # 0 steps; +4, +8 repeat; +12 steps; +16, +20 repeat; +24 steps; +28 repeats
    assert flags == [False, True, True, False, True, True, False, True]


@pytest.mark.parametrize("bad", [-1, float("nan"), "x"])
def test_bad_threshold_is_a_clear_error(bad):
    with pytest.raises(mlplc2.InputError, match="repeat_threshold"):
        mlplc2.MLPLC2(fps=30.0, repeat_threshold=bad)


def test_cli_skip_repeats(tmp_path, capsys):
    video = tmp_path / "dup.avi"
    frames, _ = _duplicated(stimuli.four_phase(seed=0).frames[:20])
    from mlplc2.io import write_video

    write_video(video, np.stack(frames), 30.0)
    assert cli.main(["run", str(video), "--skip-repeats", "--out", str(tmp_path / "o"), "-q"]) == 0
    assert (tmp_path / "o" / "responses.csv").exists()
    # a plain flag: the file after it is the source, not a level
    assert cli.main(["run", "--skip-repeats", str(video), "--out", str(tmp_path / "q"), "-q"]) == 0
    held = (tmp_path / "q" / "responses.csv").read_text()
    assert held == (tmp_path / "o" / "responses.csv").read_text()
    assert cli.main(["run", str(video), "--out", str(tmp_path / "r"), "-q"]) == 0
    assert held != (tmp_path / "r" / "responses.csv").read_text()  # holding changed the responses
    assert cli.main(["run", str(video), "--repeat-level", "-1", "--out", str(tmp_path / "p"), "-q"]) == 2
    assert "--repeat-level" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["run", "evaluate", "batch"])
@pytest.mark.parametrize("argv, level", [([], "auto"), (["--skip-repeats"], REPEAT_THRESHOLD),
                                         (["--repeat-level", "4"], 4.0),
                                         (["--skip-repeats", "--repeat-level", "0"], 0.0),
                                         (["--every-frame"], None)])
def test_repeat_options_reach_the_run(command, argv, level, monkeypatch):
    """--skip-repeats is a flag (threshold REPEAT_THRESHOLD), --repeat-level N sets the level
    and implies it, on run, evaluate and batch."""
    import importlib

    seen = []

    class Stop(Exception):
        pass

    def fake(*args, **kw):
        opts = kw if command == "run" else kw.get("run_options") or {}
        seen.append(opts.get("repeat_threshold"))
        raise Stop

    module, name = {"run": ("mlplc2.runner", "run"), "evaluate": ("mlplc2.evaluate", "evaluate"),
                    "batch": ("mlplc2.batch", "batch")}[command]
    monkeypatch.setattr(importlib.import_module(module), name, fake)
    extra = {"run": [], "evaluate": ["--gt", "gt.json"], "batch": ["--out", "b"]}[command]
    with pytest.raises(Stop):
        cli.main([command, *argv, "clip.avi", *extra])
    # run() gets the models' duplicate detection ("auto") by default; evaluate and batch leave
    # it to run()'s default (nothing in run_options)
    assert seen == [None if (level == "auto" and command != "run") else level]


@pytest.mark.paper
def test_raptor_clip_alarms_once_duplicates_are_held(paper_dir):
    """uav/bird_attack_2.avi repeats most frames (real changes every 3-6 frames): stepped on
    every frame, the correlators get one frame of motion between several of stillness (no
    alarm); holding the duplicates, mLPLC2 raises its alarm on the raptor (docs/model.md,
    "Repeated frames")."""
    frames = read_gray(paper_dir / "uav" / "bird_attack_2.avi")
    plain = mlplc2.MLPLC2(fps=30.0, repeat_threshold=None)
    assert not any(plain.step(f).collision for f in frames)
    held = mlplc2.MLPLC2(fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    alarms = [k for k, f in enumerate(frames) if held.step(f).collision]
    assert alarms and alarms[0] < 30  # the raptor fills the view from frame ~33
    # by default the duplicates are found without the user knowing (issue 16): a model on its own
    # after a few copies, mlplc2.run from the first frames of the video on
    auto = mlplc2.MLPLC2(fps=30.0)
    assert sum(auto.step(f).repeated for f in frames) >= 12
    res = mlplc2.run(paper_dir / "uav" / "bird_attack_2.avi", ["mlplc2"], out=False, progress=False)
    assert res.duplicated and res.repeated["mlplc2"] == 29
    assert res.alarms["mlplc2"]["first"] is not None and res.alarms["mlplc2"]["first"] < 30


def test_batch_passes_skip_repeats(tmp_path):
    frames, _ = _duplicated(stimuli.four_phase(seed=0).frames[:12])
    from mlplc2.io import write_video

    write_video(tmp_path / "v.avi", np.stack(frames), 30.0)
    assert cli.main(["batch", str(tmp_path / "v.avi"), "--out", str(tmp_path / "b"), "--workers", "0",
                     "--skip-repeats", "-q"]) == 0
    import json

    done = list((tmp_path / "b").rglob("*.json"))
    assert any(json.loads(p.read_text()).get("run_options", {}).get("repeat_threshold") == REPEAT_THRESHOLD
               for p in done)


def test_evaluate_passes_skip_repeats(tmp_path):
    st = stimuli.four_phase(seed=0)
    frames, origin = _duplicated(st.frames[:40])
    from mlplc2.io import write_video

    write_video(tmp_path / "v.avi", np.stack(frames), 30.0)
    import json

    gt = {"videos": {"v.avi": {"size": [320, 240], "frames": len(frames), "objects": []}}}
    (tmp_path / "gt.json").write_text(json.dumps(gt))
    assert cli.main(["evaluate", str(tmp_path / "v.avi"), "--gt", str(tmp_path / "gt.json"), "-m", "mlplc2",
                     "--skip-repeats", "-q"]) == 0


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
