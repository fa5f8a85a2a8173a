"""``mlplc2 benchmark`` on the command line (the quick suite), failed tasks in its report, and the
warning options (``--horizon``, ``--max-miss``) of ``run``, ``batch``, ``evaluate`` and ``benchmark``."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import warnings
import shutil
from pathlib import Path

import pytest

import mlplc2.benchmark as benchmark_module
import mlplc2.runner as runner_module
import mlplc2.runner.prepare as prepare_module
from mlplc2.benchmark import COLUMNS, MODELS, BenchmarkWarning, benchmark, suite
from mlplc2 import stimuli
from mlplc2.cli import main
from mlplc2.io import write_video
from mlplc2.targets import TargetParams


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """``mlplc2 benchmark --quick --workers 0`` once (all models, 4 short scenes; ~15 s)."""
    out = tmp_path_factory.mktemp("bench") / "b"
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        rc = main(["benchmark", "--out", str(out), "--quick", "--workers", "0"])
    return {"out": out, "rc": rc, "stdout": stdout.getvalue(), "stderr": stderr.getvalue()}


def test_quick_benchmark_prints_the_table_and_writes_the_report(quick):
    out = quick["out"]
    assert quick["rc"] == 0, quick["stderr"][-2000:]
    lines = quick["stdout"].splitlines()
    assert lines[0].startswith("Generated suite: 4 scenes (480 frames); real clips: 0;")
    first = lines[:lines.index("", 2)]                 # the model table, before the per-setting one
    rows = [ln for ln in first if ln.startswith("| ") and not ln.startswith("| model ")]
    assert [r.split("|")[1].strip() for r in rows] == list(MODELS)
    names = ("benchmark.md", "benchmark.json", "benchmark.csv", "evaluation.md", "evaluation.json",
             "lead_time.png", "false_warnings.png")
    assert lines[-1].startswith("wrote ") and all(str(out / n) in lines[-1] for n in names)
    assert all((out / n).is_file() for n in names)
    report = json.loads((out / "benchmark.json").read_text())
    assert report["settings"]["quick"] is True and report["settings"]["models"] == list(MODELS)
    assert report["settings"]["real"] is None and report["failed"] == []
    assert report["scenes"] == [s.name for s in suite(quick=True)]
    with open(out / "benchmark.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert list(table[0]) == list(COLUMNS) and [r["model"] for r in table] == list(MODELS)
    # one collision object per quick scene, for every model
    assert all(r["collision_objects"] == "4" for r in table)
    ev = json.loads((out / "evaluation.json").read_text())
    for r in table:
        warned = sum(o["warned"] for o in ev["warning_objects"] if o["model"] == r["model"])
        assert int(r["warned"]) == warned
    # per setting: the still cameras (plain, texture) and the moving ones (pan, forward) add up
    by = {r["setting"]: r for r in report["by_setting"]}
    assert by["still camera"]["scenes"] == by["moving camera"]["scenes"] == 2
    for r in table:
        m = r["model"]
        assert by["still camera"][m]["warned"] + by["moving camera"][m]["warned"] == int(r["warned"])
        assert by["texture_pan"][m]["collision_objects"] == 1
    assert "| moving camera | 2 |" in (out / "benchmark.md").read_text()
    assert "# mlplc2 benchmark" in (out / "benchmark.md").read_text()
    # the report says what its columns mean (a new user met "lapsed" and "TTC error ... 6 %" undefined), and
    # docs/benchmark.md defines each of them
    md = (out / "benchmark.md").read_text()
    docs = (Path(__file__).resolve().parents[1] / "docs" / "benchmark.md").read_text()
    keys = [ln.split(" | ")[0][2:] for ln in docs.split("| column of `benchmark.md` | meaning |", 1)[1].splitlines()[2:]
            if ln.startswith("| ")]
    for name in ("warned", "lead", "lapsed", "false episodes", "false frames", "TTC error", "TTC coverage",
                 "targets/object", "real clips", "ms/frame"):
        assert f"*{name}*" in md, name
        assert any(k.startswith(name) for k in keys), name


def test_quick_benchmark_rerun_reuses_the_tasks_and_quiet_prints_nothing(quick, capsys):
    before = (quick["out"] / "runs" / "results.csv").read_text()
    assert main(["benchmark", "--out", str(quick["out"]), "--quick", "--workers", "0", "-q"]) == 0
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""
    after = (quick["out"] / "runs" / "results.csv").read_text()
    assert after == before          # nothing reran: the same rows, the same task seconds


def _failing_run(monkeypatch, model="lgmd2", video="quick_texture_pan"):
    real = runner_module.run

    def run(source, models, **kw):
        if video in str(source) and model in models:
            raise RuntimeError("decoder exploded")
        return real(source, models, **kw)

    monkeypatch.setattr(runner_module, "run", run)


@pytest.mark.filterwarnings("default::mlplc2.benchmark.BenchmarkWarning")   # as outside pytest
def test_failed_tasks_are_listed_and_warned(quick, tmp_path, monkeypatch, capsys):
    """A task that fails leaves its model without results on that video: the report says so
    (benchmark.md, benchmark.json, one warning line) instead of scoring the model on fewer
    objects silently; the command exits 2, as mlplc2 batch does."""
    out = tmp_path / "b"
    shutil.copytree(quick["out"] / "scenes", out / "scenes")   # the generated videos are reused
    _failing_run(monkeypatch)
    with pytest.warns(BenchmarkWarning) as record:
        res = benchmark(out, quick=True, models=["lgmd1", "lgmd2"], workers=0, progress=False)
    assert len(record) == 1
    msg = str(record[0].message)
    assert "quick_texture_pan.mkv (lgmd2, runs/quick_texture_pan/default/lgmd2): failed, not scored" in msg
    assert "RuntimeError: decoder exploded" in msg
    assert [(f["model"], f["status"]) for f in res.failed] == [("lgmd2", "error")]
    rows = {r["model"]: r for r in res.rows}
    assert rows["lgmd2"]["collision_objects"] == 3 and rows["lgmd1"]["collision_objects"] == 4
    assert msg in (out / "benchmark.md").read_text()
    assert json.loads((out / "benchmark.json").read_text())["failed"] == res.failed
    # the command line: the failed task is retried (and fails again), the others are reused
    capsys.readouterr()
    assert main(["benchmark", "--out", str(out), "--quick", "-m", "lgmd1,lgmd2", "--workers", "0", "-q"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [f"mlplc2: warning: {msg}"]


@pytest.mark.filterwarnings("default::mlplc2.benchmark.BenchmarkWarning")   # as outside pytest
def test_a_benchmark_without_the_real_clips_it_looked_for_says_so(tmp_path, monkeypatch):
    """The full suite looks for the real clips (``../shared/data/real``): where there are none it says
    so before it starts (a report without them is not silently the usual one); --no-real is quiet."""
    import mlplc2.benchmark as bm

    class Stop(Exception):
        pass

    def stop(*a, **kw):
        raise Stop
    monkeypatch.setattr(bm, "default_real_dir", lambda: None)
    monkeypatch.setattr(bm, "_generate", stop)
    with pytest.warns(BenchmarkWarning, match="no labelled real clips found"), pytest.raises(Stop):
        benchmark(tmp_path / "b", models=["lgmd1"], workers=0, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", BenchmarkWarning)
        with pytest.raises(Stop):
            benchmark(tmp_path / "b", models=["lgmd1"], real=None, workers=0, progress=False)


# ---------------------------------------------------------------------------
# options reach benchmark() and mlplc2.run
# ---------------------------------------------------------------------------
def test_benchmark_options_reach_benchmark(monkeypatch, tmp_path, capsys):
    seen = []

    class Result:
        files = {"benchmark.md": tmp_path / "benchmark.md"}
        failed = []

        def to_markdown(self):
            return "TABLE\n"

    def spy(out, **kw):
        seen.append((out, kw))
        return Result()

    monkeypatch.setattr(benchmark_module, "benchmark", spy)
    real = tmp_path / "real"
    assert main(["benchmark", "--out", "o", "--quick", "--models", "mlplc2", "-m", "lgmd2", "--real", str(real),
                 "--scheduler", "tcp://h:8786", "--horizon", "2.5", "--max-miss", "0.5", "--stabilise", "--force",
                 "--settings", "drive, drone", "--holdout", "2", "--hfov", "90"]) == 0
    assert capsys.readouterr().out == f"TABLE\nwrote {tmp_path / 'benchmark.md'}\n"
    out, kw = seen[-1]
    assert out == "o" and kw == {"quick": True, "models": ["mlplc2", "lgmd2"], "real": str(real),
                                 "scheduler": "tcp://h:8786", "workers": None,
                                 "target_params": {"horizon_s": 2.5, "max_miss": 0.5}, "stabilise": True,
                                 "progress": True, "force": True, "settings": ["drive", "drone"], "holdout": 2,
                                 "hfov_deg": 90.0}
    assert main(["benchmark", "--out", "o", "--no-real", "--workers", "2", "-q"]) == 0
    assert seen[-1][1] == {"quick": False, "models": None, "real": None, "scheduler": None, "workers": 2,
                           "target_params": None, "stabilise": None, "progress": False, "force": False,
                           "settings": None, "holdout": 0, "hfov_deg": None}
    assert main(["benchmark", "--out", "o"]) == 0 and seen[-1][1]["real"] == "auto"
    # a range or list of holdouts: pooled in one report
    assert main(["benchmark", "--out", "o", "--holdout", "3, 21-23"]) == 0 and seen[-1][1]["holdout"] == [3, 21, 22, 23]
    assert main(["benchmark", "--out", "o", "--no-stabilise"]) == 0 and seen[-1][1]["stabilise"] is False


@pytest.mark.parametrize("holdout, line", [
    (0, "Generated suite: 2 scenes (60 frames); real clips: 0; 1 s."),
    (7, "Generated suite: 2 scenes (60 frames, holdout 7); real clips: 0; 1 s."),
    ([0, 21, 22, 23, 30], "Generated suite: 2 scenes (60 frames, holdouts 0, 21-23, 30); real clips: 0; 1 s."),
])
def test_the_report_names_the_holdouts_its_scenes_were_drawn_from(holdout, line):
    res = benchmark_module.BenchmarkResult([], None, ["a", "b"], [], 1.0, settings={"frames": 60, "holdout": holdout})
    assert res.to_markdown().splitlines()[0] == line


@pytest.mark.parametrize("args, expect", [
    (["benchmark"], "the following arguments are required: --out"),
    (["benchmark", "--out", "o", "--real", "r", "--no-real"], "not allowed with argument"),
    (["benchmark", "--out", "o", "--horizon", "-1"], "--horizon: expected a number >= 0, got '-1'"),
    (["benchmark", "--out", "o", "--max-miss", "x"], "--max-miss: expected a number >= 0, got 'x'"),
    (["benchmark", "--out", "o", "-m", "nope"], "unknown model 'nope'"),
    (["benchmark", "--out", "o", "--settings", "drive,highway"], "unknown benchmark setting(s) highway"),
    (["benchmark", "--out", "o", "--holdout", "-1"], "--holdout"),
    (["benchmark", "--out", "o", "--holdout", "25-21"], "--holdout: expected N, a range A-B or a comma-separated"),
    (["benchmark", "--out", "o", "--holdout", "21,x"], "--holdout: expected N, a range A-B or a comma-separated"),
    (["benchmark", "--out", "o", "--hfov", "180", "--no-real"], "--hfov: expected degrees in (0, 180)"),
    (["run", "v.mp4", "--horizon", "1e40"], "horizon_s"),
    (["batch", "v.mp4", "--out", "o", "--max-miss", "nan"], "--max-miss: expected a number >= 0, got 'nan'"),
])
def test_bad_options_are_one_line_errors(args, expect, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mlplc2: error: ") and expect in err[0], err


def test_bad_real_folder_is_one_line_error(tmp_path, capsys):
    assert main(["benchmark", "--out", str(tmp_path / "o"), "--real", str(tmp_path)]) == 2
    assert "no ground_truth.json there" in capsys.readouterr().err


@pytest.fixture()
def built(monkeypatch):
    """The target parameters every model built by mlplc2.run gets (None: the defaults)."""
    seen = []
    real = prepare_module._build_models

    def spy(models, fps, options):
        seen.append(options.target_params)
        return real(models, fps, options)

    monkeypatch.setattr(prepare_module, "_build_models", spy)
    return seen


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    path = tmp_path_factory.mktemp("clip") / "loom.avi"
    stim = stimuli.looming(size=(96, 72), contact_time=0.4, duration=0.3)
    write_video(path, stim.frames, stim.fps)
    gt = path.with_suffix(".json")
    gt.write_text(json.dumps(stim.to_ground_truth()))
    return {"video": path, "gt": gt}


def test_warning_options_reach_the_target_layer(clip, built, tmp_path):
    v = str(clip["video"])
    assert main(["run", v, "--out", str(tmp_path / "r"), "--horizon", "2.5", "--max-miss", "0.5", "-q"]) == 0
    assert main(["run", v, "--out", str(tmp_path / "d"), "-q"]) == 0
    assert main(["batch", v, "--out", str(tmp_path / "b"), "--horizon", "3", "--workers", "0", "-q"]) == 0
    assert main(["evaluate", v, "--gt", str(clip["gt"]), "-m", "mlplc2", "--max-miss", "2", "-q"]) == 0
    assert main(["run", v, "--out", str(tmp_path / "a"), "--alarm-warns", "-q"]) == 0
    assert built == [{"horizon_s": 2.5, "max_miss": 0.5}, None, {"horizon_s": 3.0}, {"max_miss": 2.0},
                     {"alarm_warns": True}]
    # the batch task records them (a rerun with other values reruns the task)
    done = json.loads(next((tmp_path / "b").rglob("done.json")).read_text())
    assert done["run_options"] == {"stabilise": True, "target_params": {"horizon_s": 3.0}}   # the default, recorded
    # and mlplc2.run makes them the models' TargetParams
    model = prepare_module._build_models(["mlplc2"], 30.0, runner_module.RunOptions(target_params=built[0]))[0]
    assert model.target_params == TargetParams(horizon_s=2.5, max_miss=0.5)


@pytest.mark.parametrize("extra", [["--settings", "drive"], ["--settings", "drivee"], ["--holdout", "1"], ["--holdout", "1-2"],
                                   ["--hfov", "90"]])
def test_quick_with_settings_or_holdout_is_a_one_line_error(extra, tmp_path, monkeypatch, capsys):
    """``--quick`` has its own four scenes: ``--settings`` and ``--holdout`` (which choose among the
    full suite's) were dropped silently with it, a misspelt setting too, and the run measured
    something else than asked. Now one error line before anything is generated."""
    def generate(*args, **kwargs):
        raise AssertionError("scenes generated")

    monkeypatch.setattr(benchmark_module, "_generate", generate)
    assert main(["benchmark", "--out", str(tmp_path / "o"), "--quick", *extra]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mlplc2: error: ") and "--quick" in err[0], err
    assert not (tmp_path / "o").exists()


def test_another_lens_renders_the_same_worlds_through_it_and_tells_the_models(tmp_path, monkeypatch, capsys):
    """``--hfov D`` renders the generated scenes through a camera of field of view D (the same draws; named
    ..._fD): in the settings of real use, placed in metres, the same world, so an object at the same place is
    smaller by the ratio of the focal lengths, tan(30 deg) / tan(D / 2); the models are given D (as a user who
    knows the lens); the real clips, whose lens is their own, need --no-real: one error line otherwise, before
    anything is generated."""
    import math

    std, wide = suite(settings=["drive"]), suite(settings=["drive"], hfov_deg=90)
    assert [s.name + "_f90" for s in std] == [s.name for s in wide] and {s.hfov_deg for s in wide} == {90.0}
    assert suite(hfov_deg=60) == suite()                           # the suite's own lens: the same scenes
    a, b = std[0].generate().truth(), wide[0].generate().truth()
    assert (a.camera["hfov_deg"], b.camera["hfov_deg"]) == (60.0, 90.0)
    oa, ob = a.objects[0], b.objects[0]
    frame = next(p.frame for p in oa.track if p.width and p.width > 20)
    ratio = ob.width_at(frame) / oa.width_at(frame)
    assert ratio == pytest.approx(math.tan(math.radians(30)) / math.tan(math.radians(45)), rel=0.02)

    def generate(*args, **kwargs):
        raise AssertionError("scenes generated")

    monkeypatch.setattr(benchmark_module, "_generate", generate)
    assert main(["benchmark", "--out", str(tmp_path / "o"), "--hfov", "90"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "--no-real" in err[0], err
    seen = {}

    def batch(videos, out, **kw):
        seen.update(kw)
        raise KeyboardInterrupt

    monkeypatch.setattr(benchmark_module, "_generate", lambda scenes, folder, progress: ([], folder / "gt.json"))
    import mlplc2.batch as batch_module

    monkeypatch.setattr(batch_module, "batch", batch)
    with pytest.raises(KeyboardInterrupt):
        benchmark(tmp_path / "o", real=None, hfov_deg=90, models=["mlplc2"], progress=False)
    assert seen["run_options"] == {"hfov_deg": 90.0}
