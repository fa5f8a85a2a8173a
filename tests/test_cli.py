"""mlplc2.cli: end-to-end tests of the ``mlplc2`` command line (in-process via ``main``, and the
console script): ``run`` on videos and image folders, bad input (exit 2 and one line, also for
zero-frame and tiny videos, corrupt images, bad options), truncated input and Ctrl-C,
``stimulus`` and ``demo``, output folders, ``--skip-repeats`` and the repeat options of ``run``,
``evaluate`` and ``batch``. (``mlplc2.run`` called directly: ``tests/test_runner.py``; a real
signal to the console script: ``tests/test_signals.py``.)"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import cli, stimuli
from mlplc2.cli import SUBCOMMANDS, Subcommand, main
from mlplc2.io import open_source, write_video
from mlplc2.models import REGISTRY
from mlplc2.models.base import REPEAT_THRESHOLD
from mlplc2.runner import COLUMNS, RunInterrupted, run

from .conftest import CX, CY, H, T, W
from .helpers import NOISE_H, NOISE_W, check_outputs_agree, duplicated, noise_frames

NAMES = sorted(REGISTRY)



def _read_csv(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = [dict(zip(header, r)) for r in reader]
    return header, rows


def _one_error_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("mlplc2: error: "), err
    assert "Traceback" not in err
    return lines[0]


def _frame_count(path):
    cap = cv2.VideoCapture(str(path))
    n = 0
    size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
    while cap.read()[0]:
        n += 1
    cap.release()
    return n, size


# -- the main path ---------------------------------------------------------------
def test_run_avi_resize_maps_fields_back(data, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["run", str(data["avi"]), "--resize", "160x120", "--out", str(out), "--video", "--quiet"])
    assert rc == 0
    assert capsys.readouterr().out == ""  # --quiet
    header, rows = _read_csv(out / "responses.csv")
    assert header == list(COLUMNS) == ["frame", "time_s", "model", "field_id", "x", "y", "response",
                                       "collision"]
    assert sorted({int(r["frame"]) for r in rows}) == list(range(T))
    assert {r["model"] for r in rows} == {"mlplc2"}
    for r in rows:
        assert float(r["time_s"]) == pytest.approx(int(r["frame"]) / 30.0, abs=1e-6)
        assert r["collision"] in ("0", "1")
        assert float(r["response"]) >= 0
        if r["field_id"]:
            assert 0 <= float(r["x"]) < W and 0 <= float(r["y"]) < H
        else:
            assert r["x"] == r["y"] == "" and float(r["response"]) == 0
    # the strongest field sits on the square's centre, in input pixels
    summary = json.loads((out / "fields.json").read_text())
    assert summary["size"] == [W, H] and summary["model_size"] == [160, 120]
    assert summary["fps"] == 30.0 and summary["n_frames"] == T and summary["complete"]
    fields = summary["models"]["mlplc2"]
    assert fields
    best = max(fields, key=lambda f: f["peak_response"])
    assert best["peak_response"] > 0
    assert math.hypot(best["x"] - CX, best["y"] - CY) < 12  # 6 model pixels at this resize
    # fields.json agrees with the CSV
    by_id = {}
    for r in rows:
        if r["field_id"]:
            by_id.setdefault(int(r["field_id"]), []).append(r)
    assert {f["id"] for f in fields} == set(by_id)
    for f in fields:
        frames = sorted(int(r["frame"]) for r in by_id[f["id"]])
        assert f["born"] == frames[0]
        assert f["died"] == (None if frames[-1] == T - 1 else frames[-1] + 1)
        peak_row = max(by_id[f["id"]], key=lambda r: float(r["response"]))
        assert f["peak_response"] == pytest.approx(float(peak_row["response"]))
        if f["first_alarm_frame"] is not None:
            assert min(int(r["frame"]) for r in by_id[f["id"]] if r["collision"] == "1") == f[
                "first_alarm_frame"]
    # a real figure
    png = out / "responses.png"
    assert png.stat().st_size > 15_000
    img = cv2.imread(str(png))
    assert img is not None and img.std() > 10
    # the annotated video has the input's frames and size
    assert _frame_count(out / "annotated.mp4") == (T, (W, H))
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temp files left


def test_run_mp4_several_models(data, tmp_path, capsys):
    out = tmp_path / "multi"
    models = ["mlplc2,lplc2", "slplc2"]
    extra = [m for m in ("lgmd2", "lgmd1") if m in mlplc2.available_models()]
    argv = ["run", str(data["mp4"]), "--out", str(out), "--scale", "0.5", "--end", "30"]
    for m in models + extra:
        argv += ["--model", m]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "30 frames" in text and "320x240 -> 160x120" in text
    _, rows = _read_csv(out / "responses.csv")
    names = ["mlplc2", "lplc2", "slplc2"] + extra
    for name in names:
        frames = [int(r["frame"]) for r in rows if r["model"] == name]
        assert sorted(set(frames)) == list(range(30)), name
    for r in rows:
        if r["model"] == "lplc2" and r["field_id"]:  # one cell at the frame centre, in input pixels
            assert (float(r["x"]), float(r["y"])) == (160.0, 120.0)
    for name in extra:  # no fields: one row per frame with empty field columns
        mine = [r for r in rows if r["model"] == name]
        assert len(mine) == 30 and all(r["field_id"] == r["x"] == r["y"] == "" for r in mine)
    summary = json.loads((out / "fields.json").read_text())
    assert list(summary["models"]) == names
    assert not (out / "annotated.mp4").exists()


def test_run_summary_names_each_warning_target(data, tmp_path, capsys):
    # a robotics user reads the console first: the summary says which target warned, from which frame, where, how
    # soon and on what course, as targets.csv has it at that frame (the square in front of the camera warns)
    out = tmp_path / "summary"
    assert main(["run", str(data["mp4"]), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    _, rows = _read_csv(out / "targets.csv")
    first = {}
    for r in rows:
        if r["warning"] == "1":
            first.setdefault(r["target_id"], r)
    assert first, "the looming square warns"
    for tid, r in first.items():
        line = next(ln for ln in text.splitlines() if ln.strip().startswith(f"T{tid} warned from frame "))
        assert f"from frame {r['frame']} " in line
        assert f"at ({float(r['x']):.0f}, {float(r['y']):.0f})" in line
        if r["ttc_s"]:
            assert f"time to contact {float(r['ttc_s']):.2f} s" in line
        else:
            assert "no time to contact yet (the field alarm's warning)" in line
        if r["miss"]:
            assert f"miss {float(r['miss']):.2f} extents" in line     # the name of targets.csv's column
    # ... and on which frames: each run of frames it warned on, as targets.csv's warning column has them
    summary = json.loads((out / "fields.json").read_text())["targets"]["mlplc2"]
    for tid in first:
        frames = sorted(int(r["frame"]) for r in rows if r["target_id"] == tid and r["warning"] == "1")
        runs = []
        for f in frames:
            shown = [int(r["frame"]) for r in rows if r["target_id"] == tid and int(r["frame"]) < f]
            if runs and shown and max(shown) == runs[-1][1]:
                runs[-1][1] = f
            else:
                runs.append([f, f])
        t = next(t for t in summary if str(t["id"]) == tid)
        assert t["warning_runs"] == runs and sum(b - a + 1 for a, b in runs) == t["warning_frames"]
        # the row of its first warning lists its fields as the target's own "fields" does: ids, not a CSV cell
        assert t["at_first_warning"]["fields"] == [int(v) for v in first[tid]["fields"].split()]
        assert set(t["at_first_warning"]["fields"]) <= set(t["fields"])
        line = next(ln for ln in text.splitlines() if ln.strip().startswith(f"T{tid} warned from frame "))
        spans = ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs[:4])
        assert f"({spans}" in line


def test_run_image_folder_default_out_and_fps(data, capsys):
    rc = main(["run", str(data["images"]), "--fps", "20", "--start", "5", "--quiet"])
    assert rc == 0
    out = data["images"].parent / "frames_mlplc2"
    _, rows = _read_csv(out / "responses.csv")
    frames = sorted({int(r["frame"]) for r in rows})
    assert frames == list(range(5, 40))
    r = next(r for r in rows if r["frame"] == "10")
    assert float(r["time_s"]) == pytest.approx(0.5)
    summary = json.loads((out / "fields.json").read_text())
    assert summary["fps"] == 20.0 and summary["start"] == 5
    assert all(f["born"] >= 5 for f in summary["models"]["mlplc2"])
    assert (out / "responses.png").exists()


# -- bad input: exit 2 and one line ------------------------------------------------
@pytest.mark.parametrize("case", ["missing", "empty_dir", "text_mp4", "unknown_model", "bad_resize",
                                  "bad_resize_zero", "resize_and_scale", "end_before_start", "no_source",
                                  "bad_fps", "huge_resize", "huge_scale", "overflow_scale"])
def test_bad_input_exit_2(case, data, tmp_path, capsys):
    video = str(data["avi"])
    argv = {
        "missing": ["run", str(tmp_path / "missing.mp4")],
        "empty_dir": ["run", str(tmp_path)],
        "text_mp4": ["run", str(tmp_path / "fake.mp4")],
        "unknown_model": ["run", video, "--model", "mlplc2,nosuchmodel"],
        "bad_resize": ["run", video, "--resize", "big"],
        "bad_resize_zero": ["run", video, "--resize", "0x120"],
        "resize_and_scale": ["run", video, "--resize", "160x120", "--scale", "0.5"],
        "end_before_start": ["run", video, "--start", "10", "--end", "5"],
        "no_source": ["run"],
        "bad_fps": ["run", video, "--fps", "-3"],
        "huge_resize": ["run", video, "--resize", "20000x20000"],
        "huge_scale": ["run", video, "--scale", "100"],
        "overflow_scale": ["run", video, "--scale", "1e308"],
    }[case]
    if case == "text_mp4":
        (tmp_path / "fake.mp4").write_text("not a video\n")
    rc = main(argv + ["--out", str(tmp_path / "o")] if case != "no_source" else argv)
    assert rc == 2
    line = _one_error_line(capsys.readouterr().err)
    expect = {"missing": "no such file", "empty_dir": "no images", "text_mp4": "not a video",
              "unknown_model": "unknown model 'nosuchmodel'", "bad_resize": "argument --resize: expected WxH with positive integers, e.g. 320x240, got 'big' (see 'mlplc2 run --help')",
              "bad_resize_zero": "argument --resize: width and height must be positive", "resize_and_scale": "not allowed with",
              "end_before_start": "--end", "no_source": "source", "bad_fps": "--fps",
              "huge_resize": "argument --resize: size 20000x20000 is too large", "huge_scale": "scale 100.0 (frames of 32000x24000) is too large",
              "overflow_scale": "is too large"}[case]
    assert expect in line
    assert not (tmp_path / "o" / "fields.json").exists()


def test_no_command_and_version(capsys):
    assert main([]) == 2
    _one_error_line(capsys.readouterr().err)
    assert main(["--version"]) == 0
    assert mlplc2.__version__ in capsys.readouterr().out


# -- truncated input and Ctrl-C --------------------------------------------------------
def test_truncated_video_keeps_outputs_and_exits_nonzero(data, tmp_path, capsys):
    cut = tmp_path / "cut.avi"
    raw = data["avi"].read_bytes()
    cut.write_bytes(raw[: int(len(raw) * 0.6)])
    out = tmp_path / "out"
    rc = main(["run", str(cut), "--out", str(out), "--quiet", "--video"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "mlplc2: warning:" in err and "Traceback" not in err
    summary = json.loads((out / "fields.json").read_text())
    k = summary["n_frames"]
    assert 0 < k < T and summary["truncated"] and not summary["complete"]
    assert f"frame {k} " in err
    _, rows = _read_csv(out / "responses.csv")
    assert sorted({int(r["frame"]) for r in rows}) == list(range(k))
    assert _frame_count(out / "annotated.mp4")[0] == k
    assert (out / "responses.png").exists()


def test_a_damaged_frame_is_skipped_named_and_the_run_goes_on(tmp_path, capsys):
    from tests.test_io import _damaged_video
    path, _, key = _damaged_video(tmp_path)
    out = tmp_path / "out"
    rc = main(["run", str(path), "--decoder", "pyav", "-m", "lgmd1", "--out", str(out), "--quiet"])
    assert rc == 0
    err = capsys.readouterr().err
    assert f"{key - 20} damaged frame(s) could not be decoded (20, " in err and "Traceback" not in err
    summary = json.loads((out / "fields.json").read_text())
    assert summary["complete"] and summary["frames_damaged"] == list(range(20, key))
    _, rows = _read_csv(out / "responses.csv")
    assert sorted({int(r["frame"]) for r in rows}) == [f for f in range(40) if not 20 <= f < key]


def test_ctrl_c_exit_130_and_valid_csv(data, tmp_path, monkeypatch, capsys):
    k = 12
    original = mlplc2.MLPLC2.step

    def step(self, frame, *args, **kwargs):
        if self.frame_index == k:
            raise KeyboardInterrupt
        return original(self, frame, *args, **kwargs)

    monkeypatch.setattr(mlplc2.MLPLC2, "step", step)
    out = tmp_path / "out"
    rc = main(["run", str(data["avi"]), "--out", str(out), "--quiet", "--video"])
    assert rc == 130
    assert "interrupted after 12 frames" in capsys.readouterr().err
    header, rows = _read_csv(out / "responses.csv")
    assert header == list(COLUMNS)
    assert sorted({int(r["frame"]) for r in rows}) == list(range(k))
    summary = json.loads((out / "fields.json").read_text())
    assert summary["interrupted"] and summary["n_frames"] == k
    assert check_outputs_agree(out, ["mlplc2"]) == k  # targets.csv and the summaries too
    assert _frame_count(out / "annotated.mp4")[0] == k
    with pytest.raises(RunInterrupted) as info:
        run(data["avi"], out=False, quiet=True)
    assert info.value.result.n_frames == k


# -- the subcommand table and the console script ----------------------------------------
def test_subcommand_table_is_extensible(capsys):
    saved = list(SUBCOMMANDS)
    try:
        SUBCOMMANDS.append(Subcommand("hello", "say hello", lambda p: p.add_argument("--name", default="fly"),
                                      lambda a: print(f"hello {a.name}") or 0))
        assert main(["hello", "--name", "lplc2"]) == 0
        assert capsys.readouterr().out == "hello lplc2\n"
    finally:
        SUBCOMMANDS[:] = saved


def test_console_script_help():
    exe = Path(sys.executable).with_name("mlplc2")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "mlplc2.cli"]
    proc = subprocess.run(cmd + ["--help"], capture_output=True, text=True, timeout=60,
                          env={**os.environ, "COLUMNS": "100"})
    assert proc.returncode == 0, proc.stderr
    for word in ("run", "stimulus", "demo"):
        assert word in proc.stdout
    # run's line names every kind of source, streams and stdin included (until session 14: "a video,
    # image folder or camera", which sent a new user with an RTSP camera elsewhere)
    run_help = " ".join(proc.stdout.split("    run ", 1)[1].split("stimulus", 1)[0].split())
    assert "stream URL or stdin (-)" in run_help and "--jsonl" in run_help, run_help


def test_python_dash_m_mlplc2():
    """``python -m mlplc2`` is the command line, with its exit codes."""
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "--version"], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"mlplc2 {mlplc2.__version__}"
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "/no/such/clip.avi"], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2 and _one_error_line(proc.stderr)


# -- stimulus and demo (need mlplc2.stimuli) ------------------------------------------------
def test_stimulus_command(tmp_path, capsys):
    stimuli = pytest.importorskip("mlplc2.stimuli")
    out = tmp_path / "six.mp4"
    assert main(["stimulus", "six_objects", "--out", str(out), "--seed", "3", "--quiet"]) == 0
    gt = json.loads((tmp_path / "six_gt.json").read_text())
    stim = stimuli.six_objects(seed=3)
    assert gt["frames"] == len(stim) and len(gt["objects"]) == 6
    assert _frame_count(out) == (len(stim), stim.size)
    assert main(["stimulus", "nosuch", "--out", str(out)]) == 2
    assert "unknown stimulus" in _one_error_line(capsys.readouterr().err)
    assert main(["stimulus", "test_black_approach", "--out", str(out), "--seed", "1"]) == 2
    _one_error_line(capsys.readouterr().err)


def _truth(stim):
    return json.loads(json.dumps(stim.to_ground_truth()))


def test_stimulus_options_reach_the_generator(tmp_path, capsys):
    """Every generator parameter is an option (dashes for underscores; WxH sizes, X,Y points)."""
    from mlplc2 import stimuli

    out = tmp_path / "loom.avi"
    assert main(["stimulus", "looming", "--size", "96x72", "--center", "30,40", "--contact-time", "0.5",
                 "--fps", "20", "--half-size", "0.25", "--polarity", "bright", "--out", str(out), "-q"]) == 0
    gt = json.loads((tmp_path / "loom_gt.json").read_text())
    want = _truth(stimuli.looming(size=(96, 72), center=(30.0, 40.0), contact_time=0.5, fps=20.0, half_size=0.25,
                                  polarity="bright"))
    assert {k: gt[k] for k in want} == want
    assert gt["size"] == [96, 72] and gt["objects"][0]["center"] == [30, 40] and gt["fps"] == 20
    assert _frame_count(out) == (want["frames"], (96, 72))
    # a basic test: --size is its square side, --frames its length
    assert main(["stimulus", "grating", "--size", "40", "--frames", "6", "--out", str(tmp_path / "g.avi"), "-q"]) == 0
    assert json.loads((tmp_path / "g_gt.json").read_text()) == \
        {"name": "grating", "video": "g.avi", **_truth(stimuli.generate("grating", size=40, frames=6))}
    # 'none' for an Optional parameter, a number for a background that takes a grey level
    assert main(["stimulus", "looming", "--size", "64x48", "--center", "none", "--duration", "none",
                 "--background", "128", "--contact-time", "0.3", "--out", str(tmp_path / "n.avi"), "-q"]) == 0
    assert json.loads((tmp_path / "n_gt.json").read_text())["objects"][0]["center"] == [32, 24]
    assert capsys.readouterr().err == ""
    # the generator's warnings are one line each
    assert main(["stimulus", "looming", "--size", "64x48", "--center", "900,900", "--contact-time", "0.3",
                 "--out", str(tmp_path / "w.avi"), "-q"]) == 0
    assert capsys.readouterr().err.splitlines() == [
        "mlplc2: warning: objects[0] at (900, 900) is never visible in the 64x48 frames (outside the frame)"]


@pytest.mark.parametrize("args, expect", [
    (["dark_approach", "--seed", "3"], "--seed: stimulus 'dark_approach' has no such option (its options: "
                                       "--size, --frames, --fps; see 'mlplc2 stimulus --help')"),
    (["looming", "--size", "100"], "--size: expected WxH (e.g. 320x240), got '100' (see 'mlplc2 stimulus --help')"),
    (["looming", "--size", "0x10"], "--size: width must be an integer >= 1, got 0 (see 'mlplc2 stimulus --help')"),
    (["looming", "--center", "3"], "--center: expected X,Y"),
    (["looming", "--contact-time", "soon"], "--contact-time: expected a number, got 'soon'"),
    (["four_phase", "--hold", "2.5"], "--hold: expected an integer, got '2.5'"),
    (["looming", "--half-size", "-1"], "--half-size must be > 0, got -1.0 (see 'mlplc2 stimulus --help')"),
    (["grating", "--colour", "red"], "unrecognized arguments: --colour red (see 'mlplc2 stimulus --help')"),
])
def test_stimulus_option_errors_name_the_option(args, expect, tmp_path, capsys):
    assert main(["stimulus", *args, "--out", str(tmp_path / "v.avi")]) == 2
    assert expect in _one_error_line(capsys.readouterr().err)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, hint", [
    (["rnu", "x.mp4"], "invalid choice: 'rnu' (choose from 'run', "),
    (["run", "x.mp4", "--jsnl", "-"], "unrecognized arguments: --jsnl -; did you mean '--jsonl'? (see 'mlplc2 run --help')"),
    (["run", "x.mp4", "--maxframes=3"], "did you mean '--max-frames'?"),
    (["benchmark", "--out", "x", "--holdot", "1"], "did you mean '--holdout'?"),
])
def test_a_mistyped_command_or_option_is_named_with_the_closest_one(argv, hint, capsys):
    assert main(argv) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert hint in line and "did you mean" in line
    if argv[0] == "rnu":
        assert line.endswith("; did you mean 'run'? (see 'mlplc2 --help')")


def test_a_word_like_no_option_gets_no_guess(capsys):
    assert main(["run", "x.mp4", "--zzzzzz"]) == 2
    assert "did you mean" not in capsys.readouterr().err


def test_stimulus_help_lists_each_stimulus_and_its_options(capsys):
    from mlplc2 import stimuli

    assert main(["stimulus", "--help"]) == 0
    text = capsys.readouterr().out
    listing = text[text.index("stimuli and the options each takes"):]
    groups = []  # [names text, options text]: names indented 2, their options 6
    for line in listing.split("\n\n")[0].splitlines()[1:]:
        if line.startswith("      "):
            groups[-1][1] += " " + line.strip()
        elif groups and not groups[-1][1]:
            groups[-1][0] += " " + line.strip()
        else:
            groups.append([line.strip(), ""])
    blocks = {name: opts for names, opts in groups for name in names.rstrip(":").split(", ")}
    assert set(blocks) == set(stimuli.NAMES)
    for name in stimuli.NAMES:
        flags = re.findall(r"(--[a-z][a-z0-9-]*)", blocks[name])
        assert flags == ["--" + p.replace("_", "-") for p in stimuli.parameters(name)], name
    assert "--contact-time F [2]" in blocks["looming"] and "--size WxH [320x240]" in blocks["looming"]
    assert "--size N [100]" in blocks["grating"]


def test_stimulus_options_of_a_new_generator(monkeypatch, tmp_path, capsys):
    """A generator added to mlplc2.stimuli gets its options without CLI code: tuples, str, bool
    (a --flag / --no-flag), Optional."""
    from mlplc2 import stimuli

    seen = {}

    def approach3d(*, size: tuple[int, int] = (64, 48), start: tuple[float, float, float] = (0.0, 0.0, 5.0),
                   mode: str = "linear", invert: bool = False, speed: float | None = None, frames: int = 4,
                   scale: float | tuple[float, float] = 1.0):
        seen.clear()
        seen.update(size=size, start=start, mode=mode, invert=invert, speed=speed, frames=frames, scale=scale)
        return stimuli.scene([], size=size, frames=frames, background="plain", scroll=0.0, name="approach3d")

    monkeypatch.setitem(stimuli.GENERATORS, "approach3d", approach3d)
    monkeypatch.setattr(stimuli, "NAMES", stimuli.NAMES + ("approach3d",))
    out = str(tmp_path / "a.avi")
    assert main(["stimulus", "approach3d", "--start", "1,-2,7.5", "--mode", "ballistic", "--invert",
                 "--speed", "2.5", "--size", "32x24", "--scale", "2,3", "--out", out, "-q"]) == 0
    assert seen == {"size": (32, 24), "start": (1.0, -2.0, 7.5), "mode": "ballistic", "invert": True,
                    "speed": 2.5, "frames": 4, "scale": (2.0, 3.0)}
    assert main(["stimulus", "approach3d", "--no-invert", "--speed", "none", "--scale", "0.5", "--out", out,
                 "-q"]) == 0
    assert seen["invert"] is False and seen["speed"] is None and seen["size"] == (64, 48) and seen["scale"] == 0.5
    assert main(["stimulus", "approach3d", "--start", "1,2", "--out", out]) == 2
    assert "--start: expected X,Y,Z" in _one_error_line(capsys.readouterr().err)
    assert main(["stimulus", "approach3d", "--contact-time", "1", "--out", out]) == 2
    assert "--contact-time: stimulus 'approach3d' has no such option" in _one_error_line(capsys.readouterr().err)
    assert main(["stimulus", "--help"]) == 0
    text = capsys.readouterr().out
    assert "--start X,Y,Z" in text and "--invert, --no-invert" in text and "approach3d:" in text


def test_no_generator_parameter_shadows_a_stimulus_command_option():
    from mlplc2 import stimuli
    from mlplc2.cli import STIMULUS_OWN_OPTIONS

    for name in stimuli.NAMES:
        assert not set(stimuli.parameters(name)) & set(STIMULUS_OWN_OPTIONS), name


@pytest.mark.slow
def test_demo_command(tmp_path, capsys):
    pytest.importorskip("mlplc2.stimuli")
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--scene", "six_objects"]) == 0
    text = capsys.readouterr().out
    assert "matched an object" in text
    assert re.match(r"demo scene .*demo\.mp4 \(\d+ frames\) with mlplc2, .* in \d+\.\d s \(\d+\.\d frames/s\)$",
                    text.splitlines()[0]), text
    assert (out / "demo.mp4").exists() and (out / "demo_gt.json").exists()
    res = out / "demo_mlplc2"
    for name in ("responses.csv", "fields.json", "responses.png", "annotated.mp4"):
        assert (res / name).exists(), name
    summary = json.loads((res / "fields.json").read_text())
    assert {"mlplc2", "slplc2", "lplc2"} <= set(summary["models"])


def test_demo_runs_the_papers_model_unless_told_to_stabilise(tmp_path, monkeypatch, capsys):
    """The demo's scenes (the paper's Fig. 4 and 5) scroll their background behind a still camera while
    the objects keep their places in the image: stabilised, the scroll is taken for a pan. So `mlplc2 demo`
    runs the paper's model and says so; `--stabilise` runs the models as `mlplc2 run` builds them."""
    import mlplc2.runner as runner
    import mlplc2.runner.demonstration as demonstration

    real_run, seen = runner.run, []

    def spy(source, models, **kw):                       # a few frames are enough to see the options
        seen.append(kw.get("stabilise", runner.RunOptions.stabilise))
        return real_run(source, models, **{**kw, "max_frames": 3, "video": False})

    monkeypatch.setattr(demonstration, "run", spy)       # the run demo() calls
    for extra in ([], ["--stabilise"]):
        assert main(["demo", "--out", str(tmp_path / "demo"), "--scene", "six_objects", *extra]) == 0
    err = capsys.readouterr().err
    assert seen == [False, True]
    assert "without gaze stabilisation" in err and "--stabilise" in err
    assert "gaze stabilisation on" in err


# -- a real clip from the paper -----------------------------------------------------------
@pytest.mark.paper
def test_paper_car_fullres_mapped_back(paper_dir, tmp_path):
    clip = paper_dir / "uav" / "car_attack_fullres.mp4"
    if not clip.exists():
        pytest.skip("car_attack_fullres.mp4 absent")
    out = tmp_path / "car"
    rc = main(["run", str(clip), "--resize", "320x240", "--video", "--out", str(out), "--quiet"])
    assert rc == 0
    _, rows = _read_csv(out / "responses.csv")
    pts = [(float(r["x"]), float(r["y"])) for r in rows if r["field_id"]]
    assert pts
    assert all(0 <= x < 1012 and 0 <= y < 738 for x, y in pts)
    assert any(x > 320 or y > 240 for x, y in pts)
    assert _frame_count(out / "annotated.mp4") == (81, (1012, 738))


def test_stimulus_output_paths(tmp_path, capsys):
    """Bad output names fail before anything is written; a new ground-truth folder is created."""
    (tmp_path / "folder").mkdir()
    cases = {"is a directory": ["--out", str(tmp_path / "folder")],
             "cannot write .mkv": ["--out", str(tmp_path / "v.mkv")],
             "cannot write a file without a suffix": ["--out", str(tmp_path / "v")],
             "both be written to": ["--out", str(tmp_path / "same.avi"), "--gt", str(tmp_path / "same.avi")]}
    for expect, args in cases.items():
        assert main(["stimulus", "grating", *args]) == 2
        assert expect in _one_error_line(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder"]
    assert main(["stimulus", "grating", "--out", str(tmp_path / "a" / "g.avi"),
                 "--gt", str(tmp_path / "b" / "g.json"), "-q"]) == 0
    assert (tmp_path / "a" / "g.avi").is_file() and json.loads((tmp_path / "b" / "g.json").read_text())["frames"] == 50


def test_output_file_blocked_by_a_folder_names_the_file(data, tmp_path, capsys):
    """fields.json cannot be written (a folder of that name): the error names fields.json, and
    no hidden temporary file is left behind."""
    out = tmp_path / "o"
    (out / "fields.json").mkdir(parents=True)
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "8", "-q"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert line.endswith("o/fields.json: Is a directory"), line
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]


def test_rerun_in_the_same_folder_removes_stale_outputs(data, tmp_path):
    """A folder never mixes two runs: the second run (no --video, no localising model) leaves
    no annotated.mp4 or targets.csv from the first."""
    out = tmp_path / "o"
    (out).mkdir()
    (out / "notes.txt").write_text("mine\n")
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "12", "--video", "-q"]) == 0
    assert {"annotated.mp4", "targets.csv"} <= {p.name for p in out.iterdir()}
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "12", "-m", "lgmd2", "-q"]) == 0
    names = {p.name for p in out.iterdir()}
    assert "annotated.mp4" not in names and "targets.csv" not in names
    assert {"responses.csv", "fields.json", "notes.txt"} <= names
    assert list(json.loads((out / "fields.json").read_text())["models"]) == ["lgmd2"]


def test_output_folder_that_is_a_file(data, tmp_path, capsys):
    (tmp_path / "afile").write_text("x\n")
    assert main(["run", str(data["avi"]), "--out", str(tmp_path / "afile"), "-q"]) == 2
    assert "afile: is a file, expected a folder" in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("argv, path", [
    (["demo", "--out", "{f}", "-q"], "{f}: is a file, where a folder is needed"),
    (["run", "{avi}", "--out", "{f}/sub", "-q"], "{f}/sub: {f} is a file, not a folder"),
    (["run", "{avi}", "--out", "{t}/o", "--jsonl", "{f}/lines.jsonl", "-q"],
     "{f}: is a file, where a folder is needed"),
    (["stimulus", "grating", "--out", "{f}/g.avi"], "{f}: is a file, where a folder is needed"),
])
def test_a_file_where_a_folder_is_needed_is_said_so(data, tmp_path, capsys, argv, path):
    """An output folder (or a folder above an output) that is a file: one line that says so, from every
    command, not the system's 'afile: File exists' or 'Not a directory'."""
    f = tmp_path / "afile"
    f.write_text("x\n")
    fill = {"f": f, "t": tmp_path, "avi": data["avi"]}
    assert main([a.format(**fill) for a in argv]) == 2
    assert _one_error_line(capsys.readouterr().err) == "mlplc2: error: " + path.format(**fill)
    assert f.read_text() == "x\n"


def test_an_output_folder_that_cannot_be_made_is_said_so(data, tmp_path, monkeypatch, capsys):
    """An output folder the system cannot make (ENOENT from mkdir, as under /proc): 'cannot create PATH:
    REASON', not the bare 'PATH: No such file or directory' of a missing input (a user's trial, session 31)."""
    import errno
    from pathlib import Path

    def refuse(self, *a, **k):
        raise FileNotFoundError(errno.ENOENT, "No such file or directory", str(self))

    monkeypatch.setattr(Path, "mkdir", refuse)
    out = tmp_path / "nope" / "o"
    assert main(["run", str(data["avi"]), "--out", str(out), "-q"]) == 2
    assert _one_error_line(capsys.readouterr().err) == f"mlplc2: error: cannot create {out}: No such file or directory"


def test_an_output_folder_that_cannot_be_written_points_to_out(data, tmp_path, monkeypatch, capsys):
    """The default output folder lies beside the input, which may be a read-only data folder: the one error
    line names the folder and says how to write elsewhere (a user's trial, session 26)."""
    import errno
    from pathlib import Path

    clip = tmp_path / "clip.avi"
    clip.write_bytes(data["avi"].read_bytes())
    mkdir = Path.mkdir

    def read_only(self, *a, **k):
        if self.name == "clip_mlplc2":
            raise OSError(errno.EROFS, "Read-only file system", str(self))
        return mkdir(self, *a, **k)

    monkeypatch.setattr(Path, "mkdir", read_only)
    assert main(["run", str(clip), "--end", "6", "-q"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert line == f"mlplc2: error: cannot create {tmp_path / 'clip_mlplc2'}: Read-only file system " \
                   "(write the outputs elsewhere with --out DIR)", line
    import cv2

    def unreadable(path, *a, **k):       # an input that cannot be read is not an output's fault
        raise PermissionError(errno.EACCES, "Permission denied", str(clip))

    monkeypatch.setattr(cv2, "VideoCapture", unreadable)
    assert main(["run", str(clip), "--out", str(tmp_path / "o"), "-q"]) == 2
    assert _one_error_line(capsys.readouterr().err) == f"mlplc2: error: {clip}: Permission denied"


def test_params_says_whose_equation_numbers_it_cites(capsys):
    """`mlplc2 params` cites docs/model.md's equation numbers, one higher than the compiled paper's from Eq. 4 on:
    its last line says so (a researcher's trial, session 32: easy to mis-cite); the baselines' tables do not need it."""
    assert main(["params"]) == 0
    assert capsys.readouterr().out.strip().splitlines()[-1].endswith("Eq. 5-16 are the paper's Eq. 4-15.")
    assert main(["params", "--lgmd2"]) == 0
    assert "Eq. 5-16" not in capsys.readouterr().out


def test_the_outputs_record_whether_each_model_stabilised_its_gaze(data, tmp_path, capsys):
    """A researcher's trial (session 51): the stabilised mLPLC2 of ``mlplc2 run`` and the paper's model
    (``--no-stabilise``) give other fields on the same clip, and neither ``fields.json`` nor ``results.csv`` said
    which ran. Now ``fields.json`` ``"stabilise"`` and the batch's ``stabilise`` column do, and the run's summary
    names the models that compensated the camera's rotation."""
    import csv

    for flag, on in ((None, True), ("--no-stabilise", False)):
        out = tmp_path / f"o{on}"
        capsys.readouterr()
        assert main(["run", str(data["avi"]), "--out", str(out), "-m", "mlplc2,lgmd2", "--end", "12",
                     *([flag] if flag else [])]) == 0
        printed = capsys.readouterr()
        assert json.loads((out / "fields.json").read_text())["stabilise"] == {"mlplc2": on, "lgmd2": False}
        assert ("gaze stabilised (the camera's rotation compensated): mlplc2;" in printed.out + printed.err) == on
    assert main(["batch", str(data["avi"]), "--out", str(tmp_path / "b"), "-m", "mlplc2,lgmd2", "--no-stabilise",
                 "-q"]) == 0
    with (tmp_path / "b" / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {r["model"]: r["stabilise"] for r in rows} == {"mlplc2": "False", "lgmd2": "False"}


def test_run_params_file_reaches_the_models_and_is_recorded(data, tmp_path, capsys):
    """`mlplc2 run --params FILE.json` (the format of `batch --params`): a collision threshold no response reaches
    silences the looming square's alarms, the LGMD2 section reaches LGMD2, and fields.json records what each
    model ran with (a user's trial, session 26: the option was refused)."""
    def alarms(out):
        rows = (out / "responses.csv").read_text().splitlines()[1:]
        return sum(1 for r in rows if r.split(",")[2] == "mlplc2" and r.split(",")[7] == "1")

    plain, quiet = tmp_path / "plain", tmp_path / "quiet"
    assert main(["run", str(data["avi"]), "--out", str(plain), "-m", "mlplc2,lgmd2", "-q"]) == 0
    assert alarms(plain) > 0
    assert json.loads((plain / "fields.json").read_text())["params"] == {"mlplc2": {}, "lgmd2": {}}
    f = tmp_path / "p.json"
    f.write_text(json.dumps({"alarm_threshold": 1e12, "lgmd2": {"n_ts": 3}}))
    assert main(["run", str(data["avi"]), "--out", str(quiet), "-m", "mlplc2,lgmd2", "--params", str(f),
                 "--horizon", "2", "-q"]) == 0
    assert alarms(quiet) == 0
    assert json.loads((quiet / "fields.json").read_text())["params"] == {
        "mlplc2": {"alarm_threshold": 1e12, "targets": {"horizon_s": 2.0}}, "lgmd2": {"n_ts": 3}}
    # a file that changes only another model's parameters (a researcher's trial, session 32: taken silently)
    capsys.readouterr()
    assert main(["run", str(data["avi"]), "--out", str(tmp_path / "other"), "-m", "lgmd1", "--params", str(f),
                 "-q", "--end", "3"]) == 0
    assert f"{f}: changes none of the parameters of lgmd1" in capsys.readouterr().err
    f.write_text(json.dumps({"alarm_treshold": 5}))
    assert main(["run", str(data["avi"]), "--out", str(tmp_path / "bad"), "--params", str(f), "-q"]) == 2
    assert "unknown parameter 'alarm_treshold'" in _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "bad").exists()


def test_an_output_folder_given_as_the_input_is_refused(data, tmp_path, capsys):
    """`mlplc2 run OUT` on a run's own output folder ran its responses.png as a one-frame video (exit 0,
    'no fields, no alarm'); it is one error line, and nothing is written."""
    out = tmp_path / "o"
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "6", "-q"]) == 0
    assert (out / "responses.png").is_file()
    capsys.readouterr()
    assert main(["run", str(out), "--out", str(tmp_path / "again"), "-q"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "an output folder of `mlplc2 run`" in line and "not a folder of frames" in line, line
    assert not (tmp_path / "again").exists()


def test_output_folder_may_not_be_the_frame_folder(data, capsys):
    before = sorted(p.name for p in data["images"].iterdir())
    assert main(["run", str(data["images"]), "--out", str(data["images"]), "-q"]) == 2
    assert "folder of input frames" in _one_error_line(capsys.readouterr().err)
    assert sorted(p.name for p in data["images"].iterdir()) == before


def test_bench_rejects_more_threads_than_the_machine_allows(capsys):
    import numba

    n = int(numba.config.NUMBA_NUM_THREADS) + 1
    assert main(["bench", "--sizes", "32x32", "--threads", str(n), "--no-reference", "-q"]) == 2
    assert f"got {n}" in _one_error_line(capsys.readouterr().err)


def test_run_decoder_option_reaches_the_decoder(data, tmp_path, monkeypatch, capsys):
    """--decoder pyav (or its old name --backend) decodes with PyAV: without PyAV importable it is a one-line error (it used
    to be ignored, and the run decoded with OpenCV)."""
    pytest.importorskip("av")
    out = tmp_path / "o"
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "6", "--decoder", "pyav", "-q"]) == 0
    assert json.loads((out / "fields.json").read_text())["n_frames"] == 6
    monkeypatch.setitem(sys.modules, "av", None)   # import av now fails
    assert main(["run", str(data["avi"]), "--out", str(tmp_path / "p"), "--backend", "pyav", "-q"]) == 2
    assert "needs PyAV" in _one_error_line(capsys.readouterr().err)


# -- what a new user sees (issue 14) ------------------------------------------------------
def test_summary_gives_frames_seconds_and_rate(data, tmp_path, capsys):
    """The progress bar goes away at the end; the summary keeps the rate, and fields.json the time."""
    out = tmp_path / "o"
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "20"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    m = re.fullmatch(r"20 frames of .*square\.avi \(320x240, 30 fps\) in (\d+\.\d) s \((\d+\.\d) frames/s\)", first)
    assert m, first
    seconds = json.loads((out / "fields.json").read_text())["seconds"]
    assert seconds > 0 and float(m.group(1)) == pytest.approx(seconds, abs=0.05)
    assert float(m.group(2)) == pytest.approx(20 / seconds, rel=0.05)
    res = run(data["avi"], out=False, end=5, progress=False)
    assert res.seconds > 0 and res.summary()["seconds"] == round(res.seconds, 3)


def test_all_fields_option_reaches_the_overlay(data, tmp_path, monkeypatch):
    import mlplc2.plots as plots

    seen = []
    real = plots.annotate_frame

    def spy(*args, **kwargs):
        seen.append((kwargs["draw_fields"], kwargs["field_shape"]))
        return real(*args, **kwargs)

    monkeypatch.setattr(plots, "annotate_frame", spy)
    base = ["run", str(data["avi"]), "--end", "3", "--video", "-q"]
    assert main(base + ["--out", str(tmp_path / "a")]) == 0
    assert main(base + ["--out", str(tmp_path / "b"), "--all-fields"]) == 0
    assert seen == [("auto", "square")] * 3 + [("all", "square")] * 3
    seen.clear()
    run(data["avi"], out=tmp_path / "c", end=2, video=True, progress=False, params=mlplc2.Params(field_shape="disc"))
    assert seen == [("auto", "disc")] * 2
    with pytest.raises(mlplc2.InputError, match="draw_fields"):
        run(data["avi"], out=False, draw_fields="some")


@pytest.mark.filterwarnings("default::mlplc2.io.VideoCodecWarning")
def test_video_without_h264_is_one_warning_line(data, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "av", None)   # as if PyAV were not installed
    out = tmp_path / "o"
    assert main(["run", str(data["avi"]), "--out", str(out), "--end", "4", "--video", "-q"]) == 0
    err = capsys.readouterr().err
    assert err == ("mlplc2: warning: annotated.mp4: written as MP4 'mp4v' by OpenCV, which browsers do not "
                   "play, not H.264: PyAV is not installed (pip install av)\n")
    assert _frame_count(out / "annotated.mp4")[0] == 4


# -- more bad input: empty, tiny and corrupt videos and images, bad options (64x48 noise clips)
def _one_line(err: str, kind: str = "error") -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"mlplc2: {kind}: "), err
    assert "Traceback" not in err
    return lines[0]


def _written(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir()) if out.exists() else []


def test_cli_zero_frame_video(tmp_path, capsys):
    p = tmp_path / "zero.avi"
    w = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 30, (NOISE_W, NOISE_H))
    w.release()
    out = tmp_path / "o"
    assert main(["run", str(p), "--out", str(out), "--quiet"]) == 2
    line = _one_line(capsys.readouterr().err)
    assert line == f"mlplc2: error: {p}: video has no frames (empty or undecodable)"
    assert _written(out) == []


def test_cli_zero_byte_file(tmp_path, capsys):
    p = tmp_path / "empty.mp4"
    p.write_bytes(b"")
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert _one_line(capsys.readouterr().err) == f"mlplc2: error: {p}: empty file (0 bytes)"
    assert _written(tmp_path / "o") == []


@pytest.mark.parametrize("n", [1, 2])
def test_a_one_frame_video_says_that_no_model_could_respond(tmp_path, capsys, n):
    """A single image or a one-frame clip is valid (below), but its summary's "no fields, no alarm"
    would read as "nothing approaches": a note says that one frame shows no motion."""
    p = write_video(tmp_path / f"short{n}.avi", noise_frames(n), 30.0)
    assert main(["run", str(p), "--out", str(tmp_path / "o")]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if "note: one frame only" in line]
    assert len(notes) == (n == 1)
    # the summary's first line counts in words: "1 frame of", "2 frames of" (it said "1 frames of")
    assert captured.out.startswith(f"{n} frame{'s' if n > 1 else ''} of "), captured.out


def test_cli_says_when_the_frames_are_smaller_than_the_defaults_were_set_for(tmp_path, capsys):
    """A 160x120 clip: a note on stderr that the models saw frames narrower than the 320 px the defaults were set
    at (a new user's trial, session 47: such copies of two real clips never warned); none at 320x240 (the
    size measured), at 160x120 scaled by 2 (what the models see), or with --quiet."""
    small = write_video(tmp_path / "small.avi", noise_frames(4, 160, 120), 30.0)
    big = write_video(tmp_path / "big.avi", noise_frames(4, 320, 240), 30.0)
    for source, extra, noted in [(small, [], True), (small, ["--quiet"], False), (big, [], False),
                                 (small, ["--scale", "2"], False)]:
        assert main(["run", str(source), "--out", str(tmp_path / "o"), "--model", "mlplc2", *extra]) == 0
        err = capsys.readouterr().err
        assert ("the models saw 160x120 frames, narrower than the 320 px" in err) == noted, (source.name, extra)


@pytest.mark.parametrize("n", [1, 2])
def test_cli_one_and_two_frame_videos_are_valid(tmp_path, capsys, n):
    """One frame has no motion (every model at rest) but is a valid input: exit 0, all outputs."""
    p = write_video(tmp_path / f"short{n}.avi", noise_frames(n), 30.0)
    out = tmp_path / "o"
    models = ",".join(NAMES)
    assert main(["run", str(p), "--out", str(out), "--model", models, "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    written = _written(out)
    assert {"fields.json", "responses.csv", "responses.png"} <= set(written)
    assert not [name for name in written if name.startswith(".")]  # no temporary file left
    header, rows = _read_csv(out / "responses.csv")
    assert header == list(COLUMNS)
    for name in NAMES:
        mine = [r for r in rows if r["model"] == name]
        assert sorted({int(r["frame"]) for r in mine}) == list(range(n))
        first = [r for r in mine if r["frame"] == "0"]
        rest = 0.5 if name.startswith("lgmd") else 0.0  # no change yet: at rest
        assert all(float(r["response"]) == rest and r["collision"] == "0" for r in first)
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == n and summary["complete"] and not summary["truncated"]


@pytest.mark.parametrize("how", ["images", "resize", "scale"])
def test_cli_frames_smaller_than_the_models_minimum(tmp_path, capsys, how):
    if how == "images":
        d = tmp_path / "tiny"
        d.mkdir()
        for i in range(3):
            cv2.imwrite(str(d / f"f{i}.png"), np.full((2, 2, 3), 40 * i, np.uint8))
        argv, expect = [str(d)], f"mlplc2: error: {d}: frames are 2x2 pixels; the models need at least 3x3"
    else:
        p = write_video(tmp_path / "v.avi", noise_frames(4), 30.0)
        opt = ["--resize", "2x40"] if how == "resize" else ["--scale", "0.03"]
        size = "2x40" if how == "resize" else "2x1"
        argv = [str(p), *opt]
        expect = f"mlplc2: error: {p}: frames are {size} pixels after resizing; the models need at least 3x3"
    out = tmp_path / "o"
    assert main(["run", *argv, "--out", str(out), "--quiet"]) == 2
    assert _one_line(capsys.readouterr().err) == expect
    assert _written(out) == []  # checked before any output exists


def test_cli_corrupt_image_in_sequence_keeps_frames_before(tmp_path, capsys):
    d = tmp_path / "seq"
    d.mkdir()
    for i, f in enumerate(noise_frames(8)):
        cv2.imwrite(str(d / f"f{i}.png"), f)
    (d / "f5.png").write_bytes(b"\x89PNG garbage")
    out = tmp_path / "o"
    assert main(["run", str(d), "--out", str(out), "--model", "mlplc2,lgmd2", "--quiet"]) == 2
    line = _one_line(capsys.readouterr().err, kind="warning")
    assert "f5.png" in line and "(frame 5)" in line
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == 5 and summary["truncated"] and not summary["complete"]
    _, rows = _read_csv(out / "responses.csv")
    assert sorted({int(r["frame"]) for r in rows}) == list(range(5))
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_cli_image_of_another_size_in_sequence(tmp_path, capsys):
    """Exit 2 and one line naming the image; the CSV holds whole rows for the frames before it."""
    d = tmp_path / "seq"
    d.mkdir()
    for i, f in enumerate(noise_frames(6)):
        cv2.imwrite(str(d / f"f{i}.png"), f)
    cv2.imwrite(str(d / "f6.png"), np.zeros((NOISE_H + 2, NOISE_W, 3), np.uint8))
    out = tmp_path / "o"
    assert main(["run", str(d), "--out", str(out), "--model", "lgmd2", "--quiet"]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith(("mlplc2: error: ", "mlplc2: warning: "))
    assert "f6.png" in lines[0] and "64x50" in lines[0] and "64x48" in lines[0]
    header, rows = _read_csv(out / "responses.csv")
    assert header == list(COLUMNS)
    assert [int(r["frame"]) for r in rows] == list(range(6))  # lgmd2: one row per frame


def test_cli_only_undecodable_images(tmp_path, capsys):
    d = tmp_path / "bad"
    d.mkdir()
    (d / "a.png").write_bytes(b"not a png")
    assert main(["run", str(d), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert _one_line(capsys.readouterr().err) == f"mlplc2: error: {d / 'a.png'}: not an image OpenCV can read"
    assert _written(tmp_path / "o") == []


@pytest.mark.parametrize("argv, expect", [
    (["--model", ""], "--model needs at least one model name"),
    (["--model", ",,"], "--model needs at least one model name"),
    (["--fps", "nan"], "argument --fps: expected a positive number, got 'nan'"),
    (["--fps", "inf"], "argument --fps: expected a positive number, got 'inf'"),
    (["--scale", "0"], "argument --scale: expected a positive number, got '0'"),
    (["--start", "-1"], "argument --start: expected an integer >= 0, got '-1'"),
    (["--start", "99"], "start frame 99 is past the end (4 frames)"),
    (["--start", "4"], "start frame 4 is past the end (4 frames)"),   # one past the last: nothing to process
    (["--end", "0"], "--end (0) must be larger than --start (0)"),
    (["--resize", "320x"], "argument --resize: expected WxH with positive integers, e.g. 320x240, got '320x' "
                           "(see 'mlplc2 run --help')"),
    (["--backend", "gstreamer"], "argument --backend: invalid choice: 'gstreamer'"),
])
def test_cli_more_bad_options(tmp_path, capsys, argv, expect):
    p = write_video(tmp_path / "v.avi", noise_frames(4), 30.0)
    out = tmp_path / "o"
    assert main(["run", str(p), *argv, "--out", str(out), "--quiet"]) == 2
    assert expect in _one_line(capsys.readouterr().err)
    assert _written(out) == []


@pytest.mark.filterwarnings("default::mlplc2.InputWarning")
@pytest.mark.parametrize("argv, frames", [(["--end", "9"], 4), (["--start", "2", "--end", "9"], 2)])
def test_an_end_past_the_clip_says_how_many_frames_it_has(tmp_path, capsys, argv, frames):
    p = write_video(tmp_path / "v.avi", noise_frames(4), 30.0)
    assert main(["run", str(p), *argv, "--out", str(tmp_path / "o"), "--quiet"]) == 0
    assert capsys.readouterr().err == (f"mlplc2: warning: {p} has 4 frames: end frame 9 is past its end; "
                                       "the run went to its last frame\n")
    assert json.loads((tmp_path / "o" / "fields.json").read_text())["n_frames"] == frames
    assert main(["run", str(p), "--end", "4", "--out", str(tmp_path / "e"), "--quiet"]) == 0   # its end: no note
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("command", ["run", "evaluate", "batch"])
def test_a_bad_resize_says_where_the_help_is(tmp_path, capsys, command):
    assert main([command, str(tmp_path / "v.avi"), "--resize", "3x"]) == 2
    assert _one_line(capsys.readouterr().err) == (
        "mlplc2: error: argument --resize: expected WxH with positive integers, e.g. 320x240, got '3x' "
        f"(see 'mlplc2 {command} --help')")


def test_cli_out_is_a_file(tmp_path, capsys):
    p = write_video(tmp_path / "v.avi", noise_frames(4), 30.0)
    f = tmp_path / "taken"
    f.write_text("x")
    assert main(["run", str(p), "--out", str(f), "--quiet"]) == 2
    assert str(f) in _one_line(capsys.readouterr().err)
    assert f.read_text() == "x"


# -- repeated frames: --skip-repeats, --repeat-level, --every-frame ------------------------
def test_cli_skip_repeats(tmp_path, capsys):
    video = tmp_path / "dup.avi"
    frames, _ = duplicated(stimuli.four_phase(seed=0).frames[:20])
    from mlplc2.io import write_video

    write_video(video, np.stack(frames), 30.0)
    # the paper's model (the four-phase scene scrolls its background under still objects)
    assert cli.main(["run", str(video), "--skip-repeats", "--out", str(tmp_path / "o"), "-q", "--no-stabilise"]) == 0
    assert (tmp_path / "o" / "responses.csv").exists()
    # a plain flag: the file after it is the source, not a level
    assert cli.main(["run", "--skip-repeats", str(video), "--out", str(tmp_path / "q"), "-q", "--no-stabilise"]) == 0
    held = (tmp_path / "q" / "responses.csv").read_text()
    assert held == (tmp_path / "o" / "responses.csv").read_text()
    assert cli.main(["run", str(video), "--out", str(tmp_path / "r"), "-q", "--no-stabilise"]) == 0
    assert held != (tmp_path / "r" / "responses.csv").read_text()  # holding changed the responses
    assert cli.main(["run", str(video), "--repeat-level", "-1", "--out", str(tmp_path / "p"), "-q"]) == 2
    assert "--repeat-level" in capsys.readouterr().err


def test_the_summary_says_how_many_frames_skip_repeats_held(tmp_path, capsys):
    """7 frames repeated twice each, within +-6 grey levels, as lossless PNGs: --skip-repeats (16 levels)
    holds the 14 copies, and the summary says so (no prescan with the flag, so no note line)."""
    import cv2

    frames, _ = duplicated(stimuli.four_phase(seed=0).frames[:20])
    (tmp_path / "f").mkdir()
    for i, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / "f" / f"{i:03d}.png"), f)
    assert cli.main(["run", str(tmp_path / "f"), "--skip-repeats", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "repeated frames: the models held their output on 14 of 34 frames" in out


def test_run_summary_lists_only_fields_that_responded(monkeypatch, capsys):
    """Issue 24, item 6: the summary's six strongest fields leave out fields whose peak is 0."""
    import mlplc2.runner as runner
    from mlplc2.runner import RunResult

    def field(fid, peak):
        return {"id": fid, "x": 10.0 * fid, "y": 5.0, "born": fid, "died": None, "peak_response": peak,
                "peak_frame": fid, "first_alarm_frame": None}

    fields = [field(1, 0.0), field(2, 40.0), field(3, 0.0), field(4, 7.0)]
    res = RunResult(source="clip.avi", models=["mlplc2"], fps=30.0, size=(64, 48), model_size=(64, 48),
                    n_frames=10, fields={"mlplc2": fields}, alarms={"mlplc2": {"count": 0, "first": None}})
    monkeypatch.setattr(runner, "run", lambda *a, **k: res)
    assert cli.main(["run", "clip.avi"]) == 0
    out = capsys.readouterr().out
    assert "mlplc2: 4 field(s), 0 in alarm" in out
    assert re.findall(r"#(\d+) at", out) == ["2", "4"]


def test_fields_without_video_is_an_error(data, tmp_path, capsys):
    """--fields / --all-fields draw on annotated.mp4: without --video they would do nothing, so
    they are a one-line error and nothing is written."""
    for flag in ("--fields", "--all-fields"):
        out = tmp_path / flag.strip("-")
        assert cli.main(["run", str(data["avi"]), flag, "--out", str(out), "-q"]) == 2
        err = capsys.readouterr().err
        assert err.strip() == f"mlplc2: error: {flag} draws on annotated.mp4: give --video too"
        assert not out.exists()


def test_default_output_folders_are_ignored_by_git():
    """Issue 24, item 6: what the README's commands write in a checkout (mlplc2 demo's and
    mlplc2 reproduce's default folders, mlplc2 run's <stem>_mlplc2/) is not left untracked."""
    import shutil

    root = Path(__file__).resolve().parents[1]
    if shutil.which("git") is None or not (root / ".git").exists():
        pytest.skip("not a git checkout")
    parser = cli.build_parser()
    outs = [parser.parse_args(["demo"]).out, parser.parse_args(["reproduce"]).out, "clip_mlplc2", "bench",
            "six.mp4", "six_gt.json"]
    # and every --out / --gt / --jsonl of the commands shown in README.md and docs/robot.md (until session 14 the
    # README's "--gt six.json" and robot.md's "--out run0" were left untracked)
    import re

    for doc in (root / "README.md", root / "docs" / "robot.md"):
        for block in re.findall(r"```bash\n(.*?)```", doc.read_text(encoding="utf-8"), re.S):
            outs += [v for v in re.findall(r"--(?:out|gt|jsonl)\s+(\S+)", block) if v != "-" and not v.isupper()]
    assert len(outs) > 8, outs   # the blocks were found
    for out in outs:
        probe = f"{out}/x.csv" if "." not in out else out
        assert subprocess.run(["git", "check-ignore", "-q", probe], cwd=root).returncode == 0, out


def _png_folder(d, frames):
    d.mkdir()
    for i, f in enumerate(frames):
        cv2.imwrite(str(d / f"f{i:03d}.png"), f)
    return d


def test_one_decision_on_repeated_frames(tmp_path, capsys):
    """Issue 24, item 3: the printed note and fields.json's "duplicated" say the same, also when
    the copies start after the pre-scan's 60 frames (the models find out then and hold frames);
    "frames_held" has every model's entry, 0 when it held none."""
    late = _png_folder(tmp_path / "late", noise_frames(70, seed=1) + duplicated(noise_frames(40, seed=2))[0])
    assert cli.main(["run", str(late), "-m", "mlplc2,lgmd2", "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert set(summary["frames_held"]) == {"mlplc2", "lgmd2"} and summary["frames_held"]["mlplc2"] > 0
    assert summary["duplicated"] is True and "note: the video repeats its frames" in err
    plain = _png_folder(tmp_path / "plain", noise_frames(30, seed=3))
    assert cli.main(["run", str(plain), "-m", "mlplc2,lgmd2", "--out", str(tmp_path / "p")]) == 0
    summary = json.loads((tmp_path / "p" / "fields.json").read_text())
    assert summary["frames_held"] == {"mlplc2": 0, "lgmd2": 0} and summary["duplicated"] is False
    assert "note: the video repeats" not in capsys.readouterr().err
    # --every-frame: no model is left to find out, so there is no decision (null) and no note
    assert cli.main(["run", str(late), "-m", "mlplc2", "--every-frame", "--out", str(tmp_path / "e")]) == 0
    summary = json.loads((tmp_path / "e" / "fields.json").read_text())
    assert summary["duplicated"] is None and summary["frames_held"] == {"mlplc2": 0}
    assert "note: the video repeats" not in capsys.readouterr().err


def test_a_file_read_live_is_prescanned_frame_by_frame(tmp_path, capsys, monkeypatch):
    """A clip whose frames were duplicated says so also with --live: the pre-scan of its first
    frames reads every one of them (a live reader hands over a sample, whose duplicates depend
    on the machine's speed: the loom clip of the README once said "repeats its frames", on
    0 of 1 frames held)."""
    import mlplc2.runner.prepare

    frames, _ = duplicated(noise_frames(20, w=320, h=240, seed=4))
    clip = _png_folder(tmp_path / "dup", frames)
    opened = []

    def recording(*args, **keywords):   # which sources the run opens, live or frame by frame
        opened.append(keywords.get("live"))
        return open_source(*args, **keywords)

    monkeypatch.setattr(mlplc2.runner.prepare, "open_source", recording)   # the run's and the pre-scan's
    assert cli.main(["run", str(clip), "--live", "-q", "--out", str(tmp_path / "o")]) == 0
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert summary["duplicated"] is True
    assert sorted(opened) == [False, True]   # the pre-scan frame by frame, the run live
    capsys.readouterr()


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

    module, name = {"run": ("mlplc2.runner", "run"), "evaluate": ("mlplc2.evaluator", "evaluate"),
                    "batch": ("mlplc2.batch", "batch")}[command]
    monkeypatch.setattr(importlib.import_module(module), name, fake)
    extra = {"run": [], "evaluate": ["--gt", "gt.json"], "batch": ["--out", "b"]}[command]
    with pytest.raises(Stop):
        cli.main([command, *argv, "clip.avi", *extra])
    # run() gets the models' duplicate detection ("auto") by default; evaluate and batch leave
    # it to run()'s default (nothing in run_options)
    assert seen == [None if (level == "auto" and command != "run") else level]


def test_batch_passes_skip_repeats(tmp_path):
    frames, _ = duplicated(stimuli.four_phase(seed=0).frames[:12])
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
    frames, origin = duplicated(st.frames[:40])
    from mlplc2.io import write_video

    write_video(tmp_path / "v.avi", np.stack(frames), 30.0)
    import json

    gt = {"videos": {"v.avi": {"size": [320, 240], "frames": len(frames), "objects": []}}}
    (tmp_path / "gt.json").write_text(json.dumps(gt))
    assert cli.main(["evaluate", str(tmp_path / "v.avi"), "--gt", str(tmp_path / "gt.json"), "-m", "mlplc2",
                     "--skip-repeats", "-q"]) == 0


def test_compile_notice_says_once_when_numba_compiles(capsys):
    """The first run after an install compiles the kernels (tens of seconds on frame 1): the CLI
    says so in one stderr line; nothing when nothing compiles (the kernels come from the disk
    cache, or no model has compiled kernels), or with --quiet."""
    numba = pytest.importorskip("numba")
    from mlplc2.cli.common import COMPILING, compile_notice

    def fresh():   # a new function: Numba must compile it (no cache)
        return numba.njit(lambda x: x + 1)

    with compile_notice(["mlplc2"]):
        assert fresh()(1) == 2 and fresh()(2) == 3
    assert capsys.readouterr().err.splitlines() == [COMPILING]
    compiled = fresh()
    compiled(1)
    with compile_notice(["mlplc2"]):
        compiled(2)                       # already compiled: no event
    with compile_notice(["lgmd1", "flow"]):
        fresh()(1)                        # no model with compiled kernels: not listened to
    with compile_notice(["mlplc2"], quiet=True):
        fresh()(1)
    assert capsys.readouterr().err == ""


class _Called(Exception):
    pass


@pytest.mark.parametrize("command, target", [("batch", "mlplc2.batch.batch"),
                                             ("evaluate", "mlplc2.evaluator.evaluate")])
@pytest.mark.parametrize("flag, value", [("--no-stabilise", False), ("--stabilise", True), (None, None)])
def test_batch_and_evaluate_take_the_stabilise_flags_of_run(command, target, flag, value, monkeypatch, tmp_path):
    """README: run, stream, batch and benchmark stabilise by default and ``--no-stabilise`` turns it
    off; ``mlplc2 batch`` (and ``evaluate`` on videos) refused the flag (exit 2). It reaches the runs'
    options; without it the runner's default (``RunOptions.stabilise``) stands."""
    seen = {}

    def fake(*args, run_options=None, **kwargs):
        seen.update(run_options or {})
        raise _Called

    monkeypatch.setattr(target, fake)
    argv = [command, str(tmp_path / "clip.avi"), *([flag] if flag else [])]
    argv += ["--out", str(tmp_path / "o")] if command == "batch" else ["--gt", str(tmp_path / "gt.json")]
    with pytest.raises(_Called):
        main(argv)
    assert seen.get("stabilise") is value


# -- a reader of standard output that goes away (`mlplc2 ... | head -1`) ---------------------
def _with_closed_stdout(args: list[str]) -> subprocess.CompletedProcess:
    """``python -m mlplc2 ARGS`` whose standard output is a pipe nobody reads: its reader has gone
    (as ``| head -1`` after its line, or ``| true``)."""
    r, w = os.pipe()
    os.close(r)
    try:
        return subprocess.run([sys.executable, "-m", "mlplc2", *args], stdout=w, stderr=subprocess.PIPE,
                              text=True, timeout=300)
    finally:
        os.close(w)


@pytest.mark.parametrize("cut", [False, True])
def test_a_closed_standard_error_does_not_stop_the_run(cut, data, tmp_path):
    """``mlplc2 run clip.avi 2>&1 | head -1``: the progress bar, the summary and the warning meet a
    pipe whose reader has gone. The run goes on to its end and writes its summaries, with its own
    exit code (the progress bar's ``BrokenPipeError`` stopped it: exit 1, no fields.json)."""
    clip = data["avi"]
    if cut:
        clip = tmp_path / "cut.avi"
        raw = data["avi"].read_bytes()
        clip.write_bytes(raw[: int(len(raw) * 0.6)])
    r, w = os.pipe()
    os.close(r)
    try:
        proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", str(clip), "-m", "lgmd1", "--out",
                               str(tmp_path / "o")], stdout=w, stderr=w, timeout=300)
    finally:
        os.close(w)
    assert proc.returncode == (2 if cut else 0)
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert summary["truncated"] == cut and (summary["n_frames"] < T if cut else summary["complete"])


def test_a_closed_standard_output_is_no_error():
    """``mlplc2 params | head -1`` with ``head`` gone: the command's own exit code and nothing on
    stderr (it was ``mlplc2: error: [Errno 32] Broken pipe``, exit 2)."""
    proc = _with_closed_stdout(["params"])
    assert (proc.returncode, proc.stderr) == (0, "")


def test_a_closed_standard_output_keeps_the_runs_outputs_and_its_warning(data, tmp_path):
    """The summary of a run on a truncated clip goes to a closed pipe: the outputs are written, the
    warning line still says where decoding stopped, and the exit code is the truncation's (2), not
    an error about the pipe."""
    cut = tmp_path / "cut.avi"
    raw = data["avi"].read_bytes()
    cut.write_bytes(raw[: int(len(raw) * 0.6)])
    proc = _with_closed_stdout(["run", str(cut), "-m", "lgmd2", "--out", str(tmp_path / "o")])
    assert proc.returncode == 2
    assert "decoding stopped at frame" in proc.stderr and "Broken pipe" not in proc.stderr
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert summary["truncated"] and 0 < summary["n_frames"] < T


# -- a cut file: what the one line says (a new user's session 13) ---------------------------
def test_a_cut_mp4_whose_index_was_at_its_end_is_named_so(tmp_path, capsys):
    """An MP4 whose index (moov atom) comes at its end, as OpenCV's ``mp4v`` writer, most cameras
    and phones write it, cut in half: no decoder can open it. The line says why (it was "not a
    video file OpenCV can read (unknown format or damaged)"), for either decoder; the whole file,
    and a file that is no MP4 at all, keep their own outcome."""
    whole = tmp_path / "whole.mp4"
    vw = cv2.VideoWriter(str(whole), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (64, 48))
    for i in range(30):
        vw.write(np.full((48, 64, 3), 8 * i, np.uint8))
    vw.release()
    raw = whole.read_bytes()
    assert raw.rfind(b"moov") > len(raw) // 2            # the index is at the end
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(raw[: len(raw) // 2])
    text = tmp_path / "text.mp4"
    text.write_text("hello\n")
    for decoder in ("opencv", "pyav"):
        assert main(["run", str(cut), "-q", "-m", "lgmd1", "--decoder", decoder, "--out", str(tmp_path / "o")]) == 2
        err = _one_error_line(capsys.readouterr().err)
        assert "without its index (moov atom)" in err and "cut off" in err, err
        assert main(["run", str(text), "-q", "-m", "lgmd1", "--decoder", decoder]) == 2
        assert "not a video file" in _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "o").exists()
    assert main(["run", str(whole), "-q", "-m", "lgmd1", "--out", str(tmp_path / "w")]) == 0
    from mlplc2.io.formats import mp4_without_index

    assert mp4_without_index(cut) and not mp4_without_index(whole) and not mp4_without_index(text)


def test_the_pyav_hint_of_a_stop_only_where_frames_decode_after_it(data, tmp_path, capsys):
    """OpenCV stops at a cut and at a damaged frame alike. Its warning pointed at ``--decoder pyav``
    ("skips a damaged frame and goes on") for a file cut short too, where PyAV stops at the same
    frame: the hint now comes only when frames decode after the stop."""
    from tests.test_io import _damaged_video

    cut = tmp_path / "cut.avi"
    raw = data["avi"].read_bytes()
    cut.write_bytes(raw[: int(len(raw) * 0.6)])
    assert main(["run", str(cut), "-q", "-m", "lgmd1", "--out", str(tmp_path / "a")]) == 2
    err = _one_line(capsys.readouterr().err, "warning")
    assert "decoding stopped at frame" in err and "--decoder pyav" not in err, err
    damaged, _, _ = _damaged_video(tmp_path)
    assert main(["run", str(damaged), "-q", "-m", "lgmd1", "--out", str(tmp_path / "b")]) == 2
    err = _one_line(capsys.readouterr().err, "warning")
    assert "decoding stopped at frame 20 of 40" in err and "--decoder pyav skips a damaged frame" in err, err


def test_an_output_that_is_the_input_video_is_refused_and_the_video_kept(data, tmp_path, capsys):
    """``--jsonl clip.mp4`` (for ``clip.jsonl``) truncated the input video it was reading, and a run on
    ``OUT/annotated.mp4`` with ``--out OUT`` deleted it first (a folder never mixes two runs): both
    are one error line now, before anything is written, and the video is unchanged."""
    video = tmp_path / "clip.mp4"
    video.write_bytes(data["mp4"].read_bytes())
    before = video.read_bytes()
    assert main(["run", str(video), "-q", "-m", "lgmd1", "--jsonl", str(video), "--out", str(tmp_path / "o")]) == 2
    assert "is the input video" in _one_line(capsys.readouterr().err)
    assert video.read_bytes() == before and not (tmp_path / "o").exists()
    out = tmp_path / "out"
    out.mkdir()
    again = out / "annotated.mp4"
    again.write_bytes(before)
    assert main(["run", str(again), "-q", "-m", "lgmd1", "--out", str(out)]) == 2
    assert "choose another --out" in _one_line(capsys.readouterr().err)
    assert again.read_bytes() == before and sorted(p.name for p in out.iterdir()) == ["annotated.mp4"]
    assert main(["run", str(again), "-q", "-m", "lgmd1", "--out", str(tmp_path / "elsewhere")]) == 0


def test_a_json_lines_path_that_cannot_be_written_leaves_no_output_folder(data, tmp_path, capsys):
    """``--jsonl`` into a place that cannot hold it: one error line and nothing written (the empty
    output folder was left behind: the folder was made before the JSON lines were opened)."""
    blocker = tmp_path / "notes.txt"
    blocker.write_text("a file, not a folder\n")
    out = tmp_path / "o"
    assert main(["run", str(data["avi"]), "-q", "-m", "lgmd1", "--jsonl", str(blocker / "x.jsonl"),
                 "--out", str(out)]) == 2
    assert str(blocker) in _one_line(capsys.readouterr().err)
    assert not out.exists() and blocker.read_text() == "a file, not a folder\n"
    # and a JSON lines file made for a run whose output folder then fails is not left behind
    lines = tmp_path / "run.jsonl"
    assert main(["run", str(data["avi"]), "-q", "-m", "lgmd1", "--jsonl", str(lines), "--out", str(blocker)]) == 2
    assert "expected a folder" in _one_line(capsys.readouterr().err) and not lines.exists()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes")
def test_json_lines_to_a_named_pipe_reach_its_reader_whole(data, tmp_path):
    """``--jsonl FIFO`` (a robot stack reading a named pipe): the pipe is opened once, so its reader
    gets every line and then its end (a check that opened it before the run would hand the reader
    an empty stream and leave the run waiting for another)."""
    import threading

    fifo = tmp_path / "lines"
    os.mkfifo(fifo)
    got = []

    def read():
        with open(fifo, encoding="utf-8") as f:
            got.extend(f.read().splitlines())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", str(data["avi"]), "-q", "-m", "lgmd1", "--jsonl",
                           str(fifo), "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    reader.join(timeout=30)
    assert proc.returncode == 0, proc.stderr
    assert [json.loads(line)["frame"] for line in got] == list(range(T))


@pytest.mark.parametrize("stop", ["end", "max_frames"])
def test_ctrl_c_during_the_last_frame_is_the_runs_interrupt(stop, data, tmp_path, monkeypatch, capsys):
    """Ctrl-C that arrives during the last frame of a run (deferred to the frame's end), here the
    video's last or the one ``--max-frames`` stops after: the run is interrupted, with the frames
    done. (It was raised only after the summaries: fields.json said ``"complete": true``, and the
    line was a bare ``mlplc2: interrupted``. In a shell, Ctrl-C also ends the reader of
    ``--jsonl -``, which stops the loop the same way.)"""
    import signal

    last = T - 1 if stop == "end" else 19
    original = mlplc2.LGMD1.step

    def step(self, frame, *args, **kwargs):
        if self.frame_index == last:
            os.kill(os.getpid(), signal.SIGINT)   # deferred by the run: the frame is finished first
        return original(self, frame, *args, **kwargs)

    monkeypatch.setattr(mlplc2.LGMD1, "step", step)
    out = tmp_path / "out"
    argv = ["run", str(data["avi"]), "-m", "lgmd1", "--out", str(out), "-q"]
    assert main(argv + (["--max-frames", str(last + 1)] if stop == "max_frames" else [])) == 130
    assert f"interrupted after {last + 1} frames" in capsys.readouterr().err
    summary = json.loads((out / "fields.json").read_text())
    assert summary["interrupted"] and not summary["complete"] and summary["n_frames"] == last + 1
