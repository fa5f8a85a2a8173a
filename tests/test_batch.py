"""Batch runs over many videos on a 2-worker Dask LocalCluster (started here, no external service)."""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mlplc2 import stimuli
from mlplc2._validation import InputTypeError, InputValueError
from mlplc2.io import expand_inputs
from mlplc2.batch import (DONE_MARKER, RESULT_COLUMNS, BatchInterrupted, batch, param_label,
                          param_set_id, param_sets, parse_sweep, start_local_cluster)
from mlplc2.cli import main
from mlplc2.evaluator import evaluate
from mlplc2.io import write_video

MODELS = ["mlplc2", "lgmd2"]


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    """Six small generated clips (96x72, 24 frames), one looming square each, at different places."""
    d = tmp_path_factory.mktemp("videos")
    paths, truth = [], {}
    centers = [(30, 30), (60, 40), (48, 36), (70, 20), (20, 50), (50, 25)]
    for k, c in enumerate(centers):
        st = stimuli.scene([stimuli.SceneObject(center=c, onset=2, approach=16, hold=4, recede=0)],
                           size=(96, 72), frames=24, background="plain", scroll=0.0)
        p = d / f"clip{k}.avi"
        write_video(p, st.frames, 30.0)
        paths.append(str(p))
        truth[p.name] = st.to_ground_truth()
    return {"dir": d, "paths": paths, "gt": {"videos": truth}}


@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    import os

    before = {k: os.environ.get(k) for k in ("NUMBA_NUM_THREADS", "MALLOC_TRIM_THRESHOLD_")}
    cluster, client = start_local_cluster(2)
    # The workers' environment must not leak into this process (a later Numba compile here
    # would fail on a changed NUMBA_NUM_THREADS).
    assert {k: os.environ.get(k) for k in before} == before
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def test_local_cluster_workers(client):
    """The workers of start_local_cluster ignore Ctrl-C (this process closes them), run without
    Dask's MALLOC_TRIM_THRESHOLD_ (which makes the models several times slower) and share the
    cores between their Numba threads."""
    def worker_state():
        import numba

        return (signal.getsignal(signal.SIGINT) == signal.SIG_IGN, os.environ.get("MALLOC_TRIM_THRESHOLD_"),
                numba.get_num_threads())

    threads = int(os.environ.get("NUMBA_NUM_THREADS") or max(1, (os.cpu_count() or 1) // 2))
    assert list(client.run(worker_state).values()) == [(True, None, threads)] * 2
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # here: Ctrl-C still interrupts


def _comparable(rows):
    return [{k: r[k] for k in RESULT_COLUMNS if k != "seconds"} for r in rows]


def _read_table(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_cluster_matches_sequential(videos, client, tmp_path):
    seq = batch(videos["paths"], tmp_path / "seq", models=MODELS, workers=0, progress=False)
    dist = batch(videos["paths"], tmp_path / "dist", models=MODELS, client=client, progress=False)
    assert seq.scheduler == "sync" and dist.scheduler.startswith("tcp://")
    assert len(seq.rows) == len(dist.rows) == 12
    assert all(r["status"] == "ok" for r in dist.rows)
    assert _comparable(seq.rows) == _comparable(dist.rows)
    t_seq, t_dist = _read_table(seq.table), _read_table(dist.table)
    assert list(t_seq[0]) == list(RESULT_COLUMNS)
    assert [{k: v for k, v in r.items() if k != "seconds"} for r in t_seq] == \
        [{k: v for k, v in r.items() if k != "seconds"} for r in t_dist]
    # per-row outputs: one folder per task, readable by evaluate
    for r in dist.rows:
        folder = tmp_path / "dist" / r["out"]
        assert (folder / "responses.csv").is_file() and (folder / "fields.json").is_file()
        assert json.loads((folder / DONE_MARKER).read_text())["status"] == "ok"
    ev = evaluate(tmp_path / "dist", videos["gt"], models=["mlplc2"])
    assert ev.models["mlplc2"]["objects"] == 6 and ev.models["mlplc2"]["videos"] == 6


def test_corrupt_video_is_reported(videos, client, tmp_path):
    bad = tmp_path / "broken.avi"
    bad.write_bytes(b"RIFF" + b"\x00garbage" * 500)
    inputs = videos["paths"][:3] + [str(bad)]
    res = batch(inputs, tmp_path / "out", models=["mlplc2"], client=client, progress=False)
    status = {r["video"]: r for r in res.rows}
    assert status[str(bad)]["status"] == "error" and "broken.avi" in status[str(bad)]["error"]
    assert "\n" not in status[str(bad)]["error"]
    assert [status[v]["status"] for v in videos["paths"][:3]] == ["ok"] * 3
    assert res.failed == 1 and len(_read_table(res.table)) == 4
    # the rerun retries only the failed task
    again = batch(inputs, tmp_path / "out", models=["mlplc2"], workers=0, progress=False)
    assert (again.ran, again.skipped, again.failed) == (1, 3, 1)


def test_sweep_gives_two_result_sets(videos, client, tmp_path):
    res = batch(videos["paths"][:2], tmp_path / "sw", models=MODELS, sweep=["t_a=8,12"], client=client,
                progress=False)
    assert len(res.param_sets) == 2
    ids = sorted(res.param_sets)
    assert {json.dumps(p, sort_keys=True) for p in res.param_sets.values()} == {'{"t_a": 8}', '{"t_a": 12}'}
    assert len(res.rows) == 2 * 2 * 2
    ml = [r for r in res.rows if r["model"] == "mlplc2"]
    assert sorted({r["param_set"] for r in ml}) == ids and sorted({r["params"] for r in ml}) == \
        ['{"t_a": 12}', '{"t_a": 8}']
    for pid in ids:
        assert (tmp_path / "sw" / "clip0" / pid / "mlplc2" / DONE_MARKER).is_file()
    # LGMD2 does not use t_a: one run per video, shared by both parameter sets
    lg = [r for r in res.rows if r["model"] == "lgmd2"]
    assert {r["out"] for r in lg} == {"clip0/default/lgmd2", "clip1/default/lgmd2"} and res.tasks == 6
    ev = evaluate(tmp_path / "sw", videos["gt"], models=["mlplc2"])
    assert sorted(ev.models) == ["mlplc2[t_a=12]", "mlplc2[t_a=8]"]
    assert sorted(ev.models[lb]["param_set"] for lb in ev.models) == ids


def test_param_label():
    assert param_label("mlplc2") == param_label("mlplc2", {}) == "mlplc2"
    assert param_label("mlplc2", {"t_a": 8, "r_af": 30}) == "mlplc2[r_af=30,t_a=8]"
    assert param_label("lgmd2", {"lgmd2": {"a_on": 0.5}}) == "lgmd2[lgmd2.a_on=0.5]"
    assert param_label("mlplc2", {"field_shape": "disc", "normalise_kernels": False}) == \
        "mlplc2[field_shape=disc,normalise_kernels=false]"
    assert param_label("mlplc2", {"t_a": 8, "r_af": 30, "d": 5}, shared={"r_af": 30, "d": 5}) == "mlplc2[…,t_a=8]"
    many = {f"p{i}": i for i in range(20)}
    cut = param_label("mlplc2", many, width=30, tag="p12345678")
    assert cut.startswith("mlplc2[p0=0,p1=1,") and cut.endswith(",…] p12345678") and len(cut) <= 30 + 10


def test_sweep_labels_name_the_parameters(videos, tmp_path, monkeypatch):
    """results.csv, the plot titles and evaluate's tables and JSON name the overridden
    parameters (folder names keep the ids); long labels are shortened in the Markdown tables only."""
    import mlplc2.plots

    titles = []
    monkeypatch.setattr(mlplc2.plots, "plot_responses", lambda *a, title=None, **k: titles.append(title))
    base = {"r_af": 30, "alarm_window": 4, "max_fields": 12}
    res = batch(videos["paths"][:1], tmp_path / "o", models=MODELS, params=base, sweep=["t_a=8,12"], workers=0,
                progress=False, plot=True)
    full = {t: f"mlplc2[alarm_window=4,max_fields=12,r_af=30,t_a={t}]" for t in (8, 12)}
    table = _read_table(res.table)
    assert list(table[0]) == list(RESULT_COLUMNS)
    assert [(r["model"], r["label"]) for r in table] == [("mlplc2", full[8]), ("lgmd2", "lgmd2"),
                                                          ("mlplc2", full[12]), ("lgmd2", "lgmd2")]
    assert sorted(titles) == sorted([f"clip0.avi: {full[8]}", f"clip0.avi: {full[12]}", "clip0.avi: lgmd2"])
    ev = evaluate(tmp_path / "o", videos["gt"])
    assert list(ev.models) == [full[8], full[12], "lgmd2"]  # t_a=8 before t_a=12
    assert ev.models[full[8]]["params"] == {**base, "t_a": 8} and ev.models[full[8]]["model_name"] == "mlplc2"
    assert ev.models["lgmd2"]["params"] == {} and ev.models["lgmd2"]["param_set"] == "default"
    assert {v["model"] for v in ev.to_dict()["videos"]} == {full[8], full[12], "lgmd2"}
    md = ev.to_markdown(details=True)
    assert "| mlplc2[…,t_a=8] | 1 |" in md and "| mlplc2[…,t_a=12] | clip0.avi |" in md
    assert "- mlplc2: `…` stands for alarm_window=4,max_fields=12,r_af=30, common to its 2 parameter sets" in md
    assert "@p" not in md and "@p" not in ev.to_json()


def test_rerun_skips_finished_tasks(videos, tmp_path):
    first = batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=False)
    assert (first.ran, first.skipped) == (2, 0)
    again = batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=False)
    assert (again.ran, again.skipped) == (0, 2)
    assert _comparable(again.rows) == _comparable(first.rows)
    assert [r["seconds"] for r in again.rows] == [r["seconds"] for r in first.rows]  # read back, not rerun
    (tmp_path / "o" / first.rows[1]["out"] / DONE_MARKER).unlink()   # an unfinished task
    third = batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=False)
    assert (third.ran, third.skipped) == (1, 1)
    forced = batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=False, force=True)
    assert forced.ran == 2


def test_the_progress_bar_ends_once(videos, tmp_path, capsys, monkeypatch):
    import tqdm

    from mlplc2 import _progress

    class EveryUpdate(tqdm.tqdm):   # every update drawn, however fast the tasks (tqdm reads its TQDM_*
        def __init__(self, *args, **kwargs):   # environment once, at import: no use here)
            super().__init__(*args, **{**kwargs, "mininterval": 0, "miniters": 1})

    monkeypatch.setattr(tqdm, "tqdm", EveryUpdate)
    monkeypatch.setattr(_progress, "on_terminal", lambda stream: True)   # the bar a terminal gets
    batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=True)
    err = capsys.readouterr().err   # captured: every redraw stays in the text
    assert err.count("1/2") == 1 and err.count("2/2") == 1 and err.endswith("\n"), err


def test_param_sets_and_ids(tmp_path):
    assert parse_sweep(["t_a=8,10", "lgmd2.a_on=0.5"]) == {"t_a": [8, 10], "lgmd2.a_on": [0.5]}
    sets = param_sets({"beta": 1.2}, ["t_a=8,10", "d=5,6"], ["mlplc2"])
    assert len(sets) == 4 and all(s["beta"] == 1.2 for s in sets)
    assert len({param_set_id(s) for s in sets}) == 4
    assert param_set_id({"t_a": 8, "d": 5}) == param_set_id({"d": 5, "t_a": 8})
    assert param_set_id({}) == "default"
    f = tmp_path / "p.json"
    f.write_text('{"t_a": 12}')
    assert param_sets(f) == [{"t_a": 12}]
    with pytest.raises(InputValueError, match="unknown parameter"):
        param_sets({"nope": 1})
    # a target-layer field, flat, in a "targets" section (as fields.json records it) or in a model's section: one
    # error that names it and the options that set it (a new user's --params of horizon_s: "unknown parameter")
    for pset, name in (({"horizon_s": 2.0}, "'horizon_s'"), ({"targets": {"horizon_s": 2.0}}, "'targets'"),
                       ({"mlplc2": {"targets": {"horizon_s": 2.0}}}, "'mlplc2.targets'"),
                       ({"mlplc2": {"max_miss": 2.0}}, "'mlplc2.max_miss'")):
        with pytest.raises(InputValueError, match=f"{name} belongs to the target layer .*--horizon, --max-miss"):
            param_sets(pset)
    with pytest.raises(InputValueError, match="t_a"):
        param_sets({"t_a": -1})
    with pytest.raises(InputValueError, match="PARAM=V1"):
        parse_sweep(["t_a"])
    f.write_text("{bad")
    with pytest.raises(InputValueError, match="not valid JSON"):
        param_sets(f)


def test_inputs(videos, tmp_path):
    assert expand_inputs(videos["dir"]) == sorted(videos["paths"])
    assert expand_inputs(str(videos["dir"] / "clip[01].avi")) == videos["paths"][:2]
    with pytest.raises(InputValueError, match="no such file"):
        expand_inputs(tmp_path / "missing.avi")
    # two videos with the same stem get distinct folders
    (tmp_path / "a").mkdir()
    shutil.copy(videos["paths"][0], tmp_path / "a" / "clip0.avi")
    res = batch([videos["paths"][0], tmp_path / "a" / "clip0.avi"], tmp_path / "o", models=["lgmd2"], workers=0,
                progress=False)
    assert len({r["out"] for r in res.rows}) == 2


def test_dask_and_pandas_are_core_dependencies():
    """The README's commands after a plain ``pip install .`` (``mlplc2 benchmark``, ``mlplc2 batch
    --workers 2``) need Dask and pandas: they are in the base install, and the old extras stay as
    empty aliases so that ``pip install 'mlplc2[dask]'`` still works (issue 24, item 2)."""
    tomllib = pytest.importorskip("tomllib")
    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    if not pyproject.exists():
        pytest.skip("not a source checkout")
    project = tomllib.loads(pyproject.read_text())["project"]
    deps = [d.replace(" ", "").split("#")[0] for d in project["dependencies"]]
    assert any(d.startswith("dask[distributed]>=") for d in deps)
    assert any(d.startswith("pandas>=") for d in deps)
    assert project["optional-dependencies"]["dask"] == project["optional-dependencies"]["pandas"] == []


def test_cli_messages_name_flags_not_keywords(videos, tmp_path, capsys, monkeypatch):
    """A message on the command line names its flags, never a Python keyword (``parquet=True``)."""
    monkeypatch.setitem(sys.modules, "pyarrow", None)   # import pyarrow -> ImportError
    assert main(["batch", videos["paths"][0], "--out", str(tmp_path / "o"), "-m", "lgmd2", "--workers", "0",
                 "--parquet", "-q"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "--parquet" in line and "=True" not in line and "pyarrow" in line


def test_cli_batch_on_scheduler(videos, client, tmp_path, capsys):
    pfile = tmp_path / "params.json"
    pfile.write_text('{"t_a": 12}')
    code = main(["batch", *videos["paths"][:2], "--out", str(tmp_path / "o"), "--models", "mlplc2,lgmd2",
                 "--params", str(pfile), "--sweep", "d=5,10", "--scheduler", client.scheduler_info()["address"], "-q"])
    assert code == 0
    rows = _read_table(tmp_path / "o" / "results.csv")
    assert len(rows) == 2 * 2 * 2 and {r["status"] for r in rows} == {"ok"}
    # d=10 is the default: no override
    assert {r["params"] for r in rows if r["model"] == "mlplc2"} == {'{"d": 5, "t_a": 12}', '{"t_a": 12}'}
    # bad input: one line, exit 2
    assert main(["batch", str(tmp_path / "none.avi"), "--out", str(tmp_path / "x"), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "mlplc2: error:" in err and "no such file" in err


def test_relative_inputs_run_on_workers_that_work_in_another_folder(videos, client, tmp_path, monkeypatch):
    """A cluster's workers run in folders of their own (other machines): a relative input, checked here,
    reached them as given and was "no such file or directory" there (and the benchmark's scenes under a
    relative ``--out`` with it). It goes as an absolute path; the row keeps it as given."""
    before = client.run(os.getcwd)
    client.run(os.chdir, str(tmp_path))                 # the workers elsewhere: no clip there
    try:
        monkeypatch.chdir(Path(videos["paths"][0]).parent)
        res = batch(["clip0.avi"], tmp_path / "o", models=["lgmd2"], client=client, progress=False)
    finally:
        for worker, cwd in before.items():
            client.run(os.chdir, cwd, workers=[worker])
    assert [(r["video"], r["status"]) for r in res.rows] == [("clip0.avi", "ok")], res.rows


def test_a_scheduler_without_a_worker_or_with_one_without_mlplc2_is_one_line(videos, tmp_path, monkeypatch):
    """The tasks waited without a word on a scheduler with no worker, or on a worker that cannot import
    mlplc2 (it cannot unpickle a task: the task is neither run nor failed)."""
    distributed = pytest.importorskip("distributed")
    import mlplc2.batch as batch_module

    monkeypatch.setattr(batch_module, "WAIT_FOR_WORKERS_S", 1.0)
    with distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        with pytest.raises(InputValueError, match=r"has no worker \(waited 1 s\): start some there"):
            batch(videos["paths"][0], tmp_path / "o", models=["lgmd2"], scheduler=address, progress=False)
        cluster.scale(1)
        with distributed.Client(address) as c:
            c.wait_for_workers(1, timeout=60)
            c.run(exec, "import sys; sys.modules['mlplc2.batch'] = None")   # as if mlplc2 were not installed there
        with pytest.raises(InputValueError, match="cannot import mlplc2 .*install it there"):
            batch(videos["paths"][0], tmp_path / "o", models=["lgmd2"], scheduler=address, progress=False)
    assert not (tmp_path / "o").exists()


def test_cli_batch_failure_exit_code(videos, tmp_path, capsys):
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"not a video")
    code = main(["batch", videos["paths"][0], str(bad), "--out", str(tmp_path / "o"), "-m", "lgmd2",
                 "--workers", "0", "-q"])
    assert code == 2
    err = capsys.readouterr().err
    assert "mlplc2: warning:" in err and "bad.avi" in err
    rows = _read_table(tmp_path / "o" / "results.csv")
    assert [r["status"] for r in rows] == ["ok", "error"]


_SUMMARY = re.compile(r"^(\d+) task\(s\)(?: in (\d+) run\(s\))?: (\d+) ran, (\d+) already done, (\d+) failed;", re.M)


def _summary_counts(text):
    m = _SUMMARY.search(text)
    assert m, text
    tasks, runs, ran, done, failed = (int(g) if g else None for g in m.groups())
    return tasks, runs or tasks, ran, done, failed


def test_cli_batch_summary_adds_up(videos, tmp_path, capsys):
    """Tasks that share a run (LGMD2 does not use t_a, which LPLC2 is swept over) are counted once: ran + already
    done + failed = runs, and the line says how many runs the tasks took."""
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"not a video")
    argv = ["batch", videos["paths"][0], str(bad), "--out", str(tmp_path / "o"), "-m", "lplc2,lgmd2",
            "--sweep", "t_a=8,12", "--workers", "0"]
    for rerun in (False, True):
        assert main(argv) == 2
        cap = capsys.readouterr()
        tasks, runs, ran, done, failed = _summary_counts(cap.out)
        assert (tasks, runs) == (8, 6) and ran + done + failed == runs
        assert (ran, done, failed) == ((0, 3, 3) if rerun else (3, 0, 3))
        assert len(_read_table(tmp_path / "o" / "results.csv")) == tasks
        assert cap.err.count("mlplc2: warning:") == 3  # each failed run, once
    # without shared runs the line counts tasks only, and they add up too
    assert main(["batch", *videos["paths"][:2], "--out", str(tmp_path / "p"), "-m", "lgmd2", "--workers", "0"]) == 0
    assert _summary_counts(capsys.readouterr().out) == (2, 2, 2, 0, 0)
    res = batch([videos["paths"][0], str(bad)], tmp_path / "q", models=["lplc2", "lgmd2"], sweep=["t_a=8,12"],
                workers=0, progress=False)
    assert (len(res.rows), res.tasks, res.ran, res.skipped, res.failed_runs, res.failed) == (8, 6, 6, 0, 3, 4)


def test_parquet_table(videos, tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    res = batch(videos["paths"][:2], tmp_path / "o", models=["lgmd2"], workers=0, progress=False, parquet=True)
    df = pd.read_parquet(tmp_path / "o" / "results.parquet")
    assert list(df.columns) == list(RESULT_COLUMNS) and len(df) == 2
    assert df["n_frames"].tolist() == [r["n_frames"] for r in res.rows] == [24, 24]


def _one_error_line(err):
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mlplc2: error:"), err
    return lines[0]


def test_scheduler_address_is_checked_first(videos, tmp_path, capsys):
    pytest.importorskip("distributed")
    out = tmp_path / "o"
    assert main(["batch", videos["paths"][0], "--out", str(out), "--scheduler", "notanaddress", "-q"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "'notanaddress'" in line and "tcp://HOST:PORT" in line
    assert not out.exists()   # nothing written before the address is checked
    for bad in ("tcp://host:abc", "tcp://host:0", "foo://host:1", "tcp://:8786"):
        with pytest.raises(InputValueError, match="scheduler address"):
            batch(videos["paths"][0], out, scheduler=bad, progress=False)
    with pytest.raises(InputTypeError, match="scheduler"):
        batch(videos["paths"][0], out, scheduler=8786, progress=False)
    assert not out.exists()


def test_workers_scheduler_client_conflict(videos, tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["batch", videos["paths"][0], "--out", str(out), "--workers", "0", "--scheduler",
                 "tcp://127.0.0.1:1", "-q"]) == 2
    assert "cannot be combined" in _one_error_line(capsys.readouterr().err)
    with pytest.raises(InputValueError, match="cannot be combined"):
        batch(videos["paths"][0], out, workers=2, scheduler="tcp://127.0.0.1:1", progress=False)
    with pytest.raises(InputValueError, match="client cannot be combined"):
        batch(videos["paths"][0], out, client=object(), workers=0, progress=False)
    assert not out.exists()
    res = batch(videos["paths"][0], out, models=["lgmd2"], workers=0, scheduler="sync", progress=False)
    assert res.scheduler == "sync" and res.ran == 1


def test_plot_on_rerun_draws_missing_plots(videos, client, tmp_path):
    paths = videos["paths"][:2]
    first = batch(paths, tmp_path / "o", models=["lgmd2"], workers=0, progress=False)
    pngs = [tmp_path / "o" / r["out"] / "responses.png" for r in first.rows]
    assert not any(p.exists() for p in pngs)
    again = batch(paths[:1], tmp_path / "o", models=["lgmd2"], workers=0, progress=False, plot=True)
    assert (again.ran, again.skipped, again.plotted) == (0, 1, 1)
    assert pngs[0].stat().st_size > 0 and not pngs[1].exists()
    assert _comparable(again.rows) == _comparable(first.rows[:1])
    assert again.rows[0]["seconds"] == first.rows[0]["seconds"]   # the task was not rerun
    # on a cluster too; a task that has its plot is left alone
    dist = batch(paths, tmp_path / "o", models=["lgmd2"], client=client, progress=False, plot=True)
    assert (dist.ran, dist.skipped, dist.plotted) == (0, 2, 1) and pngs[1].stat().st_size > 0
    assert _comparable(dist.rows) == _comparable(first.rows)
    assert batch(paths, tmp_path / "o", models=["lgmd2"], workers=0, progress=False, plot=True).plotted == 0


def test_interrupt_writes_table_and_says_where(videos, tmp_path, monkeypatch, capsys):
    import mlplc2.batch as batch_module

    calls = []
    real = batch_module.run_task

    def run_then_interrupt(task):
        calls.append(task)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(batch_module, "run_task", run_then_interrupt)
    out = tmp_path / "o"
    with pytest.raises(KeyboardInterrupt) as info:
        batch(videos["paths"][:3], out, models=["lgmd2"], workers=0)
    exc = info.value
    assert isinstance(exc, BatchInterrupted)
    assert "1 of 3 task(s) done" in str(exc) and str(out / "results.csv") in str(exc)
    assert len(exc.result.rows) == exc.result.ran == 1 and exc.result.tasks == 3
    assert len(_read_table(out / "results.csv")) == 1
    assert f"batch: {exc}" in capsys.readouterr().err   # with the progress bar
    calls.clear()   # the CLI under -q: one line with the counts, exit 130
    assert main(["batch", *map(str, videos["paths"][:3]), "--out", str(tmp_path / "q"), "-m", "lgmd2",
                 "--workers", "0", "--force", "-q"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mlplc2: interrupted with 1 of 3 task(s) done"), err


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="POSIX process groups")
def test_ctrl_c_on_local_cluster_is_one_line(tmp_path):
    """Ctrl-C reaches the whole process group, Dask workers included: no worker
    tracebacks or Dask warnings, just the CLI's line."""
    pytest.importorskip("distributed")
    clips = tmp_path / "clips"
    clips.mkdir()
    st = stimuli.scene([stimuli.SceneObject(center=(80, 60), onset=2, approach=100, hold=4, recede=0)],
                       size=(160, 120), frames=110, background="plain", scroll=0.0)
    for k in range(8):
        write_video(clips / f"c{k}.avi", st.frames, 30.0)
    out = tmp_path / "o"
    cmd = [sys.executable, "-c", "import sys; from mlplc2.cli import main; sys.exit(main())", "batch", str(clips),
           "--out", str(out), "-m", "mlplc2,slplc2", "--workers", "2", "-q"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 120
        while not list(out.glob(f"*/*/*/{DONE_MARKER}")) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)   # as a terminal does
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mlplc2: interrupted"), err
    assert len(_read_table(out / "results.csv")) < 16   # the rows of the tasks received


def test_parameters_of_every_section_are_checked(videos, tmp_path, capsys):
    # a section of a model that does not run is checked too
    with pytest.raises(InputValueError, match="nosuch"):
        param_sets({"lgmd2": {"nosuch": 1}}, models=["mlplc2"])
    with pytest.raises(InputValueError, match="nosuch"):
        param_sets(None, ["lgmd2.nosuch=1"], ["mlplc2"])
    with pytest.raises(InputValueError, match="lgmd2.*t_sp"):
        param_sets({"lgmd2": {"t_sp": -1}}, models=["mlplc2"])
    # and Params fields when no LPLC2-family model runs
    with pytest.raises(InputValueError, match="t_a"):
        param_sets({"t_a": -1}, models=["lgmd2"])
    # a value of the wrong type: one line naming the parameter and the value
    for given in [dict(sweep=["t_a=abc"]), dict(params={"t_a": "abc"}), dict(params={"t_a": "abc"}, models=["lgmd2"])]:
        with pytest.raises(InputTypeError, match=r"^parameters: t_a must be a number, got 'abc'$"):
            param_sets(**given)
    with pytest.raises(InputTypeError, match=r"lgmd2.on_kernel must be a list of 3 numbers, got \[1, 2\]"):
        param_sets({"lgmd2": {"on_kernel": [1, 2]}})
    with pytest.raises(InputTypeError, match="normalise_kernels must be true or false, got 1"):
        param_sets(None, ["normalise_kernels=1"])
    out = tmp_path / "o"
    for option in (["--sweep", "lgmd2.nosuch=1"], ["--sweep", "t_a=abc"]):
        assert main(["batch", videos["paths"][0], "--out", str(out), "--workers", "0", "-q", *option]) == 2
        _one_error_line(capsys.readouterr().err)
        assert not out.exists()


def test_a_sweep_sets_the_parameters_of_a_model_of_ones_own(videos, tmp_path, monkeypatch):
    """A model written as docs/testing.md shows, its parameters a plain frozen dataclass (no ``replace``, no
    ``to_dict``), takes a ``--sweep`` and a parameter file's section, and a name it lacks is one line: batch crashed
    with ``'LumParams' object has no attribute 'replace'`` (a researcher's trial, session 53). A swept value that no
    model run reads, and an empty value, are one-line errors (they ran the same task twice, or dropped it)."""
    from dataclasses import dataclass

    from mlplc2.batch import sweep as sweep_module
    from mlplc2.models import Model, Output, base

    @dataclass(frozen=True)
    class LumParams:
        threshold: float = 1.5

    class LumLoom(Model):
        name = "lumloom"

        def __init__(self, fps=30.0, params=None, **kwargs):
            super().__init__(fps=fps, params=LumParams() if params is None else params, **kwargs)

        def _reset(self):
            pass

        def _step(self, gray, index):
            return Output(frame=index, response=float(gray.mean()), collision=bool(gray.mean() > self.params.threshold))

    monkeypatch.setitem(base.REGISTRY, "lumloom", LumLoom)
    sweep_module._param_class.cache_clear()      # the parameter class of each name is cached
    try:
        sets = param_sets(None, ["lumloom.threshold=1.5,5"], ["mlplc2", "lumloom"])
        assert sets == [{}, {"lumloom": {"threshold": 5}}]
        assert sweep_module.model_params({"lumloom": {"threshold": 5}}, "lumloom") == LumParams(threshold=5)
        with pytest.raises(InputValueError, match="^parameters for lumloom: LumParams has no parameter 'thresold' "
                                                  r"\(did you mean 'threshold'\?\)$"):
            param_sets({"lumloom": {"thresold": 5}}, models=["lumloom"])
        out = tmp_path / "sweep"
        batch([videos["paths"][0]], out, models=["lumloom"], sweep=["lumloom.threshold=1.5,500"], workers=0,
              progress=False)
        with open(out / "results.csv", newline="") as f:
            rows = {json.loads(r["params"] or "{}").get("threshold", 1.5): r for r in csv.DictReader(f)}
        assert sorted(rows) == [1.5, 500] and int(rows[1.5]["alarms"]) > 0 == int(rows[500]["alarms"])
    finally:
        sweep_module._param_class.cache_clear()
    with pytest.raises(InputValueError, match="^--sweep lgmd2.a_on: lgmd2 is not among the models run \\(mlplc2\\)$"):
        param_sets(None, ["lgmd2.a_on=1,2"], ["mlplc2"])
    with pytest.raises(InputValueError, match="^--sweep t_a: a Params field, read only by the LPLC2 family"):
        param_sets(None, ["t_a=8,12"], ["lgmd2"])
    with pytest.raises(InputValueError, match="an empty value"):
        parse_sweep(["t_a=8,,"])


def test_default_values_are_no_override():
    assert param_sets(None, ["t_a=8,10,10.0"]) == [{"t_a": 8}, {}]   # t_a = 10 is the default
    assert [param_set_id(s) for s in param_sets(None, ["t_a=10"])] == ["default"]
    assert param_sets({"lgmd2": {"a_on": 0.5, "on_kernel": [2, 0.5, 0.25]}, "beta": 1.5}) == [{}]
    # an LPLC2-family section entry is compared with the flat value it overrides
    assert param_sets({"t_a": 12, "mlplc2": {"t_a": 10}}) == [{"t_a": 12, "mlplc2": {"t_a": 10}}]
    assert param_sets({"t_a": 12, "mlplc2": {"t_a": 12}}) == [{"t_a": 12}]


def test_cli_batch_warns_about_truncated_inputs(videos, tmp_path, capsys):
    """A damaged video that decodes in part: its rows say "truncated" and the CLI prints one
    warning line per task (the results cover the frames decoded)."""
    data = Path(videos["paths"][0]).read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) * 6 // 10])
    out = tmp_path / "o"
    assert main(["batch", str(cut), "--out", str(out), "-m", "lgmd2", "--workers", "0", "-q"]) == 0
    rows = _read_table(out / "results.csv")
    assert [r["status"] for r in rows] == ["truncated"] and 0 < int(rows[0]["n_frames"]) < 24
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("mlplc2: warning: ") and "cut.avi" in err[0], err


def test_results_table_has_the_target_warnings(tmp_path):
    """results.csv says how many targets warned and when first (issue 24, item 6): the same as the
    task's targets.csv; empty for a model without targets."""
    st = stimuli.looming(size=(96, 72), contact_time=1.0, duration=1.2, fps=30.0, background="plain")
    write_video(tmp_path / "loom.avi", st.frames, 30.0)
    batch([str(tmp_path / "loom.avi")], tmp_path / "o", models=["mlplc2", "lgmd2"], workers=0, progress=False)
    with open(tmp_path / "o" / "results.csv", newline="") as f:
        rows = {r["model"]: r for r in csv.DictReader(f)}
    with open(tmp_path / "o" / rows["mlplc2"]["out"] / "targets.csv", newline="") as f:
        warned = [r for r in csv.DictReader(f) if r["warning"] == "1"]
    assert warned, "the looming square should be warned of"
    assert int(rows["mlplc2"]["warnings"]) == len({r["target_id"] for r in warned})
    assert int(rows["mlplc2"]["first_warning_frame"]) == min(int(r["frame"]) for r in warned)
    assert rows["lgmd2"]["warnings"] == rows["lgmd2"]["first_warning_frame"] == ""
