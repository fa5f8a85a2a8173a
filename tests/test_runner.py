"""mlplc2.runner.run called directly (not through the CLI): results without outputs, the
DataFrame, rows streamed to disk only, a truncated input's warning, and the checks of its
arguments. (``mlplc2 run``: ``tests/test_cli.py``; interrupts: ``tests/test_signals.py``; the
clip ``data`` is the square approach of ``tests/conftest.py``.)"""

from __future__ import annotations

import json

import numpy as np
import pytest

import mlplc2
from mlplc2.runner import COLUMNS, TruncatedInputWarning, run

from .conftest import T


def test_truncated_video_warns_in_python(data, tmp_path):
    cut = tmp_path / "cut.avi"
    raw = data["avi"].read_bytes()
    cut.write_bytes(raw[: int(len(raw) * 0.5)])
    with pytest.warns(TruncatedInputWarning, match="stopped at frame"):
        res = run(cut, out=False, quiet=True)
    assert res.truncated and 0 < res.n_frames < T


def test_stream_says_when_its_source_was_cut_short_and_leaves_no_file_open(data, tmp_path):
    """``stream`` over a file cut in half yields the frames before the cut, then warns as ``run`` does (a robot must
    tell a camera that died from a stream that ended); a complete file warns nothing, and no spill file of the
    recorder is left open (``ResourceWarning``)."""
    import gc
    import warnings

    cut = tmp_path / "cut.avi"
    raw = data["avi"].read_bytes()
    cut.write_bytes(raw[: int(len(raw) * 0.5)])
    with pytest.warns(TruncatedInputWarning, match="stopped at frame"):
        lines = list(mlplc2.stream(cut))
    assert 0 < len(lines) < T
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(list(mlplc2.stream(data["avi"]))) == T
        gc.collect()


def test_a_heading_outside_the_frame_warns(data):
    """``--heading`` / ``TargetParams.heading`` is in the input's pixels: a point off the frame (most often one in
    another frame's pixels) gets one warning that says the frame's range; one inside it, none."""
    import warnings

    from mlplc2.targets import TargetParams

    from .conftest import H, W

    with pytest.warns(UserWarning, match=rf"heading \(1000, 1000\) lies outside the {W}x{H} frame"):
        run(data["avi"], out=False, quiet=True, max_frames=2, target_params=TargetParams(heading=(1000.0, 1000.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run(data["avi"], out=False, quiet=True, max_frames=2, target_params=TargetParams(heading=(W / 2, H / 2)))


def test_a_resize_that_stretches_the_frames_warns(data):
    """resize= (--resize) that changes the frames' aspect ratio distorts every object's growth: one warning that
    says so and how to keep the shape; a resize that keeps it (within 5 %), none."""
    import warnings

    from .conftest import H, W

    with pytest.warns(UserWarning, match=rf"resizing {W}x{H} frames to {W}x{H // 2} changes their aspect ratio"):
        run(data["avi"], out=False, quiet=True, resize=(W, H // 2), max_frames=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run(data["avi"], out=False, quiet=True, resize=(W // 2, H // 2), max_frames=2)


def test_run_api_without_outputs_and_dataframe(data, tmp_path):
    res = run(str(data["images"]), ["mlplc2", "lplc2"], out=False, progress=False)
    assert res.out is None and res.files == {} and res.n_frames == 40
    # a notebook shows the repr: a few lines, not the rows (a new user's 47-frame clip printed 55,849 characters)
    text = repr(res)
    assert len(text.splitlines()) == 4 and len(text) < 600 and str(res.rows[0]) not in text
    first = {m: res.alarms[m]["first"] for m in res.models}
    assert f"mlplc2: collision alarm on {res.alarms['mlplc2']['count']} frames (first {first['mlplc2']})" in text
    warned = [t["first_warning_frame"] for t in res.target_summaries["mlplc2"] if t["first_warning_frame"] is not None]
    assert (f"first warning at frame {min(warned)}" if warned else "first warning none") in text
    assert "complete" in text.splitlines()[0] and "no files written" in text
    assert not (data["images"].parent / "nothing").exists()
    pd = pytest.importorskip("pandas")
    df = res.to_dataframe()
    assert list(df.columns) == list(COLUMNS) and len(df) == len(res.rows)
    assert isinstance(df, pd.DataFrame) and str(df["field_id"].dtype) == "Int64"


def test_keep_rows_false_streams_to_disk_only(data, tmp_path):
    """Long/live runs: rows go to the CSV only, the result keeps no per-frame rows."""
    kept = run(str(data["avi"]), ["mlplc2", "lgmd2"], out=tmp_path / "a", progress=False)
    lean = run(str(data["avi"]), ["mlplc2", "lgmd2"], out=tmp_path / "b", progress=False, keep_rows=False)
    assert lean.rows == [] and lean.targets == [] and kept.rows
    assert (tmp_path / "a" / "responses.csv").read_text() == (tmp_path / "b" / "responses.csv").read_text()
    assert (tmp_path / "b" / "responses.png").stat().st_size > 10_000
    for name in ("mlplc2", "lgmd2"):
        frames = sorted({r["frame"] for r in kept.rows if r["model"] == name and r["collision"]})
        responses = {r["frame"]: r["response"] for r in kept.rows if r["model"] == name and r["field_id"] is None}
        peak = max(r["response"] for r in kept.rows if r["model"] == name)
        assert lean.alarms[name] == {"count": len(frames), "first": frames[0] if frames else None,
                                     "peak": pytest.approx(peak, rel=1e-6), "peak_frame": lean.alarms[name]["peak_frame"]}
        if name == "lgmd2":               # the summary's "(peak P at frame F)" of a model without fields
            assert responses[lean.alarms[name]["peak_frame"]] == pytest.approx(peak, rel=1e-6)
    # the summaries of dead fields wait on disk, and come back complete and in order
    assert lean.fields == kept.fields and any(f["died"] is not None for f in lean.fields["mlplc2"])
    a, b = (json.loads((tmp_path / d / "fields.json").read_text()) for d in "ab")
    assert a.pop("seconds") > 0 and b.pop("seconds") > 0  # the measured wall time differs from run to run
    assert a.pop("latency_ms")["max_ms"] > 0 and b.pop("latency_ms")["max_ms"] > 0  # and so do the latencies
    assert json.dumps(a) == json.dumps(b)  # the rest identical, in the same order
    # the files read back are the rows kept (mlplc2 evaluate and the plots read them so)
    from mlplc2.evaluation.record import read_responses, read_targets
    assert read_responses(tmp_path / "a" / "responses.csv") == kept.rows
    assert read_targets(tmp_path / "a" / "targets.csv") == kept.targets and kept.targets
    # the table is read back from responses.csv
    pytest.importorskip("pandas")
    a, b = kept.to_dataframe(), lean.to_dataframe()
    assert a.equals(b), (a.dtypes, b.dtypes)


def test_run_api_rejects_ambiguous_models_and_params(data):
    from mlplc2._validation import InputError

    # a dict of Params fields, as reproduce(params=...) takes (a researcher's trial, session 51): the fix named
    with pytest.raises(InputError, match=r"t_a is a field of mlplc2\.Params, not a model name: give "
                                         r"params=mlplc2\.Params\(t_a=\.\.\.\) or params=\{'mlplc2'"):
        run(data["avi"], ["mlplc2"], out=False, end=5, params={"t_a": 1000})
    with pytest.raises(InputError, match="mlpcl2 is not a model"):
        run(data["avi"], ["mlplc2"], out=False, end=5, params={"mlpcl2": mlplc2.Params()})
    with pytest.raises(InputError, match="two models named 'mlplc2'"):
        run(data["avi"], [mlplc2.MLPLC2(fps=30.0), mlplc2.MLPLC2(fps=30.0, params=mlplc2.Params(t_a=20.0))],
            out=False, end=5)
    with pytest.warns(UserWarning, match="built for 60 fps but the input runs at 30 fps"):
        run(data["avi"], [mlplc2.MLPLC2(fps=60.0)], out=False, end=3)
    res = run(data["avi"], ["mlplc2", "lgmd2"], out=False, end=5, params={"mlplc2": mlplc2.Params(t_a=20.0)})
    assert res.models == ["mlplc2", "lgmd2"]
    # keys are model names in any case or spacing, and they are applied (not only accepted)
    from mlplc2.models.lgmd import LGMD2Params

    calls = []
    real = mlplc2.models.lgmd.LGMD2.__init__

    def spy(self, *a, **k):
        calls.append(k.get("params"))
        real(self, *a, **k)

    import unittest.mock
    with unittest.mock.patch.object(mlplc2.models.lgmd.LGMD2, "__init__", spy):
        run(data["avi"], ["lgmd2"], out=False, end=3, params={" LGMD2": LGMD2Params(dc=0.5)})
    assert calls and calls[0].dc == 0.5


def test_run_api_on_an_array_says_what_to_do():
    from mlplc2._validation import InputError

    frames = np.zeros((10, 40, 40), np.uint8)
    with pytest.raises(InputError) as exc:
        run(frames, ["mlplc2"], out=False)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 200 and "ndarray of shape (10, 40, 40)" in msg and "model.run(frames)" in msg


def test_full_disk_during_video_keeps_the_other_outputs(data, tmp_path, monkeypatch, capsys):
    """Issue 24 item 5: the annotated video hits a full disk at frame K. The run stops with one
    OSError; responses.csv, targets.csv, fields.json and responses.png are there, covering
    frames 0 .. K-1 and saying the run is not complete; no annotated.mp4 or temporary file."""
    import errno

    from mlplc2.io import VideoWriter

    k = 20
    write = VideoWriter.write

    def full_after_k(self, frame):
        if self.n_frames >= k:
            raise OSError(errno.ENOSPC, "No space left on device")
        write(self, frame)

    monkeypatch.setattr(VideoWriter, "write", full_after_k)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space left on device") as info:
        run(str(data["avi"]), ["mlplc2", "lgmd2"], out=out, video=True, quiet=True, end=k + 5)
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(out / "annotated.mp4")
    assert "\n" not in str(info.value) and f"{k} frames before" in str(info.value)
    names = {p.name for p in out.iterdir()}
    assert names == {"responses.csv", "targets.csv", "fields.json", "responses.png"}, names
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == k and summary["complete"] is False
    assert summary["error"] == "annotated.mp4: No space left on device"
    assert summary["models"]["mlplc2"]  # the fields of the frames done
    for csv_name in ("responses.csv", "targets.csv"):
        frames = {int(line.split(",")[0]) for line in (out / csv_name).read_text().splitlines()[1:]}
        assert frames and max(frames) == k - 1, (csv_name, sorted(frames))
    assert (out / "responses.png").stat().st_size > 10_000
    # through the CLI: one line on stderr, naming the file; the outputs kept
    from mlplc2.cli import main

    capsys.readouterr()
    assert main(["run", str(data["avi"]), "--video", "-q", "--end", "25", "--out", str(tmp_path / "cli")]) != 0
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "annotated.mp4: No space left on device" in err, err
    assert (tmp_path / "cli" / "fields.json").is_file() and (tmp_path / "cli" / "responses.png").is_file()


def test_responses_png_gets_the_targets_timeline(data, tmp_path, monkeypatch):
    """responses.png is drawn with the targets (issue 24 item 4): their rows, or targets.csv when
    the run keeps no rows."""
    import mlplc2.plots

    seen = []
    monkeypatch.setattr(mlplc2.plots, "plot_responses", lambda rows, path, targets=None, **kw: seen.append(targets))
    kept = run(str(data["avi"]), ["mlplc2"], out=tmp_path / "a", quiet=True, end=30)
    run(str(data["avi"]), ["mlplc2"], out=tmp_path / "b", quiet=True, end=30, keep_rows=False)
    assert kept.targets and seen[0] == kept.targets
    assert seen[1] == tmp_path / "b" / "targets.csv"


def test_progress_bar_starts_after_the_first_frame(data, monkeypatch):
    """The first frame can take tens of seconds (Numba compiling the kernels on the first run):
    the bar is made after it, with that frame counted in (initial=1), so that its rate and time
    left never extrapolate from it (issue 23: "22.97s/frame, ETA 2:32:44")."""
    import tqdm

    made = []

    class Bar:
        def __init__(self, *args, **kwargs):
            made.append(kwargs)
            self.n = kwargs.get("initial", 0)

        def update(self, n=1):
            self.n += n

        def close(self):
            made.append(self.n)

    monkeypatch.setattr(tqdm, "tqdm", Bar)
    steps = []
    real_step = mlplc2.LGMD1.step
    monkeypatch.setattr(mlplc2.LGMD1, "step", lambda self, f, *a, **k: (steps.append(len(made)), real_step(self, f, *a, **k))[1])
    res = run(str(data["images"]), ["lgmd1"], out=False, progress=True)
    assert steps[0] == 0 and all(k == 1 for k in steps[1:])   # no bar while frame 1 runs
    assert made[0]["initial"] == 1 and made[-1] == res.n_frames == len(steps)


@pytest.fixture
def built(monkeypatch):
    """Every model built while the test runs, in order."""
    import mlplc2.models.base as base

    made = []
    init = base.Model.__init__

    def spy(self, *args, **kwargs):
        init(self, *args, **kwargs)
        made.append(self)

    monkeypatch.setattr(base.Model, "__init__", spy)
    return made


def test_stabilise_reaches_the_models_that_have_it(data, built):
    """run(..., stabilise=True) (CLI --stabilise) builds the LPLC2 family with gaze stabilisation
    and the other models as they are (``Model.stabilise`` False: LGMD2 compensates nothing)."""
    run(str(data["avi"]), ["mlplc2", "lgmd2"], out=False, quiet=True, end=5, stabilise=True)
    kinds = {type(m).__name__: getattr(m, "stabilise", None) for m in built}
    assert kinds == {"MLPLC2": True, "LGMD2": False}


def test_stabilisation_is_on_by_default_for_run_and_stream_and_off_for_reproduce(data, built):
    """The LPLC2 family stabilises its gaze in run (CLI mlplc2 run), stream and batch unless told not to
    (--no-stabilise); the reproduction of the paper runs the paper's model, as do the model classes."""
    from mlplc2.cli import main
    from mlplc2.reproduce import run_model

    run(str(data["avi"]), ["mlplc2", "slplc2"], out=False, quiet=True, end=3)
    assert [m.stabilise for m in built] == [True, True]
    built.clear()
    next(iter(mlplc2.stream(str(data["avi"]), "lplc2", end=3)))
    assert [m.stabilise for m in built] == [True]
    for flag, expect in (([], True), (["--no-stabilise"], False), (["--stabilise"], True)):
        built.clear()
        assert main(["run", str(data["avi"]), "-m", "mlplc2", "--out", str(data["avi"].parent / "o"), "-q",
                     "--end", "3", *flag]) == 0
        assert [m.stabilise for m in built] == [expect], flag
    built.clear()
    run_model("mlplc2", [np.zeros((24, 32), np.uint8)] * 3, 30.0)
    assert [m.stabilise for m in built] == [False]
    assert mlplc2.MLPLC2(fps=30.0).stabilise is False


def test_a_file_reduced_in_the_decoding_thread_leaves_it_a_core(data):
    """RunOptions.spare_core: while the decoding thread resizes a file's frames, the model steps on one
    thread fewer (the front end's and OpenCV's counts, given back after the run); a file at its own
    size, spare_core=False and a live source keep every thread; the outputs are the same either way."""
    import cv2
    import numba

    from mlplc2.backend import threads

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one core: no thread to spare")
    seen = []

    class Spy(mlplc2.MLPLC2):
        def step(self, frame, t=None, **kw):
            seen.append((numba.get_num_threads(), cv2.getNumThreads()))
            return super().step(frame, t, **kw)

    results = {}
    with threads(2):
        for key, kw in (("spare", {"scale": 0.5}), ("all", {"scale": 0.5, "spare_core": False}),
                        ("own size", {}), ("live", {"scale": 0.5, "live": True})):
            seen.clear()
            results[key] = run(str(data["avi"]), [Spy(fps=30.0, stabilise=True)], out=False, quiet=True, end=12,
                               **kw)
            assert set(seen) == {(1, 1) if key == "spare" else (2, 2)}, key
            assert (numba.get_num_threads(), cv2.getNumThreads()) == (2, 2)
    assert results["spare"].targets == results["all"].targets and results["spare"].rows == results["all"].rows


@pytest.mark.parametrize("failing", ["responses.csv", "targets.csv", "jsonl"])
def test_full_disk_on_a_csv_or_the_json_lines_names_it_and_keeps_the_rest(failing, data, tmp_path, monkeypatch,
                                                                          capsys):
    """A per-frame output other than the video hits a full disk at frame K: as for annotated.mp4,
    one error naming that file (it was ``[Errno 28] No space left on device``, no path, and no
    fields.json), the run stops there and fields.json says so for the K frames before."""
    import errno

    from mlplc2.cli import main
    from mlplc2.runner import live

    k = 15
    csv_write, line_write = live.CsvFile.write, live.JsonLines.write
    done = {}

    def full_csv(self, rows):
        if self.path.name == failing and done.setdefault(self.path.name, 0) > k:  # the header, then k frames
            raise OSError(errno.ENOSPC, "No space left on device")
        done[self.path.name] = done.get(self.path.name, 0) + 1
        csv_write(self, rows)

    def full_lines(self, record):
        if failing == "jsonl" and record["frame"] >= k:
            raise OSError(errno.ENOSPC, "No space left on device")
        return line_write(self, record)

    monkeypatch.setattr(live.CsvFile, "write", full_csv)
    monkeypatch.setattr(live.JsonLines, "write", full_lines)
    out = tmp_path / "out"
    jsonl = tmp_path / "lines.jsonl"
    path = str(jsonl) if failing == "jsonl" else str(out / failing)
    with pytest.raises(OSError, match="No space left on device") as info:
        run(str(data["avi"]), ["mlplc2"], out=out, quiet=True, jsonl=jsonl)
    assert info.value.errno == errno.ENOSPC and info.value.filename == path
    summary = json.loads((out / "fields.json").read_text())
    name = path if failing == "jsonl" else failing
    assert summary["complete"] is False and summary["error"] == f"{name}: No space left on device"
    frames = [json.loads(line)["frame"] for line in jsonl.read_text().splitlines()]
    n = summary["n_frames"]
    assert f"{n} frames before" in str(info.value) and frames == list(range(len(frames)))
    if failing == "jsonl":
        assert n == k == len(frames)
    if failing == "responses.csv":
        assert n == k and {int(line.split(",")[0]) for line in (out / "responses.csv").read_text().splitlines()[1:]} \
            == set(range(k))
    # through the CLI: one line on stderr, naming the file
    done.clear()
    capsys.readouterr()
    assert main(["run", str(data["avi"]), "-q", "--out", str(tmp_path / "cli"), "--jsonl", str(jsonl)]) == 2
    err = capsys.readouterr().err
    cli_path = path if failing == "jsonl" else str(tmp_path / "cli" / failing)
    assert err.strip().splitlines() == [f"mlplc2: error: {cli_path}: No space left on device; the other outputs "
                                        f"cover the {json.loads((tmp_path / 'cli' / 'fields.json').read_text())['n_frames']}"
                                        f" frames before"], err


def _colour_loom(w=480, h=270, n=40):
    """A colour clip wider than the working width: a textured background and a red square that grows."""
    import cv2

    rng = np.random.default_rng(3)
    bg = cv2.GaussianBlur(rng.uniform(0, 255, (h, w, 3)).astype(np.float32), (0, 0), 3)
    bg = cv2.normalize(bg, None, 40, 230, cv2.NORM_MINMAX).astype(np.uint8)
    for i in range(n):
        f = bg.copy()
        side = 0 if i < 5 else 6 * (i - 5) + 4
        if side:
            cv2.rectangle(f, (w // 2 - side // 2, h // 2 - side // 2), (w // 2 + side // 2, h // 2 + side // 2),
                          (200, 30, 60), -1)
        yield f


def test_a_step_loop_over_wide_frames_gives_what_run_and_stream_give(tmp_path):
    """``mlplc2 run`` and ``stream`` reduce a clip wider than the working width in their decoding thread, as 8-bit
    colour frames; a user's own loop of ``Model.step`` over the full-size frames must give the same outputs (a
    reduction after the grey conversion differs by the rounding to 8 bits, which moved a real clip's warnings by
    15-20 frames)."""
    from mlplc2.io import open_source
    from mlplc2.io.writer import write_video

    path = write_video(tmp_path / "wide.avi", _colour_loom(), 30.0)
    wide = [f for _, f in open_source(path)]
    src = open_source(path)
    src.reduce_to((320, 180))                     # what run() does with a 480x270 clip
    small = [f for _, f in src]
    assert wide[0].shape == (270, 480, 3) and small[0].shape == (180, 320, 3)
    own, runs = mlplc2.MLPLC2(fps=30.0), mlplc2.MLPLC2(fps=30.0)
    a = [own.step(f) for f in wide]
    b = [runs.step(f) for f in small]
    assert any(o.response > 0 for o in b)         # the square looms: the responses test the frames' values
    assert [(o.response, o.collision, len(o.fields), o.warning) for o in a] == \
        [(o.response, o.collision, len(o.fields), o.warning) for o in b]


def test_a_model_of_ones_own_runs_beside_the_packages(data, tmp_path):
    """A model written as docs/testing.md shows (its parameters a plain frozen dataclass) and one without parameters
    run in ``run`` and ``stream`` beside the package's models, and the run records what each ran with: the runner read
    parameters with ``ParameterSet.to_dict`` and crashed on them (a researcher's trial, session 32)."""
    from dataclasses import dataclass

    from mlplc2.models import Model, Output

    @dataclass(frozen=True)
    class DarkeningParams:
        threshold: float = 2.0

    class Darkening(Model):
        def __init__(self, fps=30.0, params=None, **kwargs):
            super().__init__(fps=fps, params=DarkeningParams() if params is None else params, **kwargs)

        def _reset(self):
            pass

        def _step(self, gray, index):
            return Output(frame=index, response=float(gray.mean()), collision=bool(gray.mean() < self.params.threshold))

    class Bare(Model):
        def _reset(self):
            pass

        def _step(self, gray, index):
            return Output(frame=index, response=float(gray.max()))

    Darkening.name, Bare.name = "darkening", "bare"
    result = run(data["avi"], ["lgmd2", Darkening(params=DarkeningParams(threshold=3.0)), Bare()], out=False,
                 quiet=True, end=5)
    assert result.n_frames == 5
    assert result.params == {"lgmd2": {}, "darkening": {"threshold": 3.0}, "bare": {}}
    lines = list(mlplc2.stream(data["avi"], [Darkening(), Bare()], end=5))
    assert len(lines) == 5 and set(lines[0]["models"]) == {"darkening", "bare"}

