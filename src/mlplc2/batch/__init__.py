"""Run many (video, model, parameter set) combinations, on Dask (the ``mlplc2 batch`` command).

Every combination is one task: :func:`mlplc2.run` on one video with one model
and one parameter set, writing ``responses.csv`` and ``fields.json`` into
``OUT/<video>/<param set>/<model>/`` and then, last, a ``done.json`` marker
holding the task's summary row. :func:`batch` submits the tasks to a
``distributed`` cluster through Dask's public API (``Client.submit``,
``distributed.as_completed``; by default on a :class:`distributed.LocalCluster`
it starts and stops itself, or ``Client(address)`` of an existing scheduler),
shows progress as they finish, and writes one row per (video, model, parameter set) to
``OUT/results.csv`` (a model shares one task between parameter sets that
differ only in parameters it does not use). A rerun skips the
tasks whose ``done.json`` exists (with ``plot=True`` it draws their missing
``responses.png`` from the saved outputs); a task that fails (corrupt video,
...) is reported with ``status = "error"`` and its one-line message, and is
retried by the next run. Ctrl-C raises :class:`BatchInterrupted` after writing
``results.csv`` for the tasks finished.

Dask is imported only when a cluster is used; ``workers=0`` (or ``scheduler="sync"``)
runs the tasks one after the other in this process without it.

The parameter sets (overrides, sweeps, ids and labels) are made by :mod:`mlplc2.batch.sweep`.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import hashlib
import json
import logging
import math
import os
import sys
import time
import warnings
from collections import Counter
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from .._files import atomic_path, write_csv, write_json
from .._signals import interrupts
from .._validation import InputError, InputTypeError, InputValueError, check_int
from .sweep import (model_overrides, model_params, param_label, param_set_id, param_sets, parse_sweep,
                    restrict)

__all__ = ["batch", "BatchResult", "BatchInterrupted", "param_sets", "model_params", "parse_sweep",
           "start_local_cluster", "param_label", "RESULT_COLUMNS", "DONE_MARKER"]

#: Columns of ``results.csv``, in order.
RESULT_COLUMNS = ("video", "model", "label", "param_set", "params", "stabilise", "n_frames", "fields", "alarms",
                  "first_alarm_frame", "warnings", "first_warning_frame", "seconds", "status", "error", "out")
#: Written last into a task's folder: the task is finished when it exists.
DONE_MARKER = "done.json"




# ---------------------------------------------------------------------------
# one task
# ---------------------------------------------------------------------------
def _one_line(text: str) -> str:
    return " ".join(str(text).split()) or "unknown error"


def run_task(task: dict) -> dict:
    """Run one (video, model, parameter set) task; return its results row.

    Never raises for a bad video: the row then has ``status = "error"`` and
    the one-line message. Writes ``done.json`` last (not for errors). A task
    marked ``"replot"`` is finished: only its missing ``responses.png`` is
    drawn from the saved outputs."""
    if task.get("replot"):
        return _plot_saved(task)
    out = Path(task["out"])
    row = _error_row(task)
    t0 = time.perf_counter()
    try:
        from ..io import TruncatedInputWarning
        from ..runner import run

        params = model_params(task["pset"], task["model"])
        (out / DONE_MARKER).unlink(missing_ok=True)  # the outputs are about to change
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TruncatedInputWarning)
            res = run(task.get("source", task["video"]), [task["model"]], out=out, quiet=True, progress=False, params=params,
                      plot=False, keep_rows=False, **task.get("run_options", {}))
        if task.get("plot") and res.n_frames:
            _plot(task, f" (input truncated after {res.n_frames} frames)" if res.truncated else "")
        alarms = res.alarms[task["model"]]
        targets = res.target_summaries.get(task["model"])  # None: a model without targets
        warned = [t["first_warning_frame"] for t in targets or () if t["first_warning_frame"] is not None]
        row.update(n_frames=res.n_frames, stabilise=res.stabilise.get(task["model"]),
                   fields=len(res.fields.get(task["model"], [])),
                   alarms=alarms["count"], first_alarm_frame=alarms["first"],
                   warnings=None if targets is None else len(warned), first_warning_frame=min(warned, default=None),
                   status="truncated" if res.truncated else "ok", error=_one_line(res.message) if res.truncated else "")
    except Exception as exc:  # noqa: BLE001 - reported in the table, the batch goes on
        msg = str(exc)
        if isinstance(exc, OSError) and getattr(exc, "filename", None) and exc.strerror:
            msg = f"{exc.filename}: {exc.strerror}"
        row["error"] = _one_line(msg if isinstance(exc, InputError) else f"{type(exc).__name__}: {msg}")
    row["seconds"] = round(time.perf_counter() - t0, 3)
    if row["status"] != "error":
        write_json(out / DONE_MARKER, {**row, "pset": task["pset"], "run_options": task.get("run_options", {})})
    return row


def _error_row(task: dict, error: str = "") -> dict:
    """The row of a task that failed with the one-line message ``error``."""
    return {"video": task["video"], "model": task["model"], "param_set": task["param_set"],
            "params": json.dumps(task["overrides"], sort_keys=True), "stabilise": None, "n_frames": None, "fields": None,
            "alarms": None, "first_alarm_frame": None, "warnings": None, "first_warning_frame": None,
            "seconds": None, "status": "error", "error": error,
            "out": task["rel_out"]}


def _plot_saved(task: dict) -> dict:
    """Draw ``responses.png`` of a finished task from its ``responses.csv`` and
    ``fields.json`` (as :func:`mlplc2.run` would have with ``plot=True``); return its saved row."""
    row = _done_row(task)
    if row is None:  # its outputs changed meanwhile: run it
        return run_task({**task, "replot": False})
    try:
        _plot(task)
    except Exception as exc:  # noqa: BLE001 - reported in the table, the batch goes on
        row.update(status="error", error=_one_line(f"responses.png: {type(exc).__name__}: {exc}"))
    return row


#: Plot titles longer than this are cut (:func:`param_label`; done.json holds the whole set).
TITLE_WIDTH = 90


def _plot(task: dict, note: str = "") -> None:
    """``responses.png`` of a task from its saved ``responses.csv`` and ``fields.json``, titled
    with its video and :func:`param_label` (as :func:`mlplc2.run` draws it, which names no parameters)."""
    from ..plots import plot_responses

    out = Path(task["out"])
    summary = json.loads((out / "fields.json").read_text(encoding="utf-8"))
    video = Path(str(summary.get("video") or task["video"])).name
    label = param_label(task["model"], task["overrides"], width=TITLE_WIDTH - len(video) - len(note),
                        tag=task["param_set"])
    targets = out / "targets.csv"
    plot_responses(out / "responses.csv", out / "responses.png", fields=summary.get("models"),
                   title=f"{video}: {label}{note}", fps=summary.get("fps"),
                   targets=targets if targets.is_file() else None)


def _done_row(task: dict) -> dict | None:
    """The saved row of a finished task, if its outputs are complete."""
    out = Path(task["out"])
    if not all((out / name).is_file() for name in (DONE_MARKER, "responses.csv", "fields.json")):
        return None
    try:
        saved = json.loads((out / DONE_MARKER).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return None
    if saved.get("pset") != task["pset"] or saved.get("video") != task["video"] \
            or saved.get("run_options", {}) != task.get("run_options", {}) \
            or "warnings" not in saved or "stabilise" not in saved:  # done before results.csv had these columns
        return None
    return {k: saved.get(k) for k in RESULT_COLUMNS}


# ---------------------------------------------------------------------------
# the batch
# ---------------------------------------------------------------------------
@dataclass
class BatchResult:
    """What :func:`batch` did.

    ``rows``: one dict per (video, parameter set, model) (keys
    :data:`RESULT_COLUMNS`, in that order); ``table``: path of
    ``results.csv``; ``tasks``: distinct runs (a model shares one run between
    parameter sets that differ only in parameters it does not use), so
    ``len(rows) >= tasks``; ``ran`` / ``skipped``: runs run now / already done
    (``ran + skipped == tasks`` unless interrupted); ``failed_runs``: those of
    the ``ran`` that failed; ``plotted``: done runs whose missing
    ``responses.png`` was drawn now (``plot=True``); ``failed``: rows with
    ``status == "error"`` (a failed run shared by several rows counts once in
    ``failed_runs``, once per row here); ``seconds``: wall time; ``videos``: the inputs.
    """

    rows: list[dict]
    table: Path
    out: Path
    videos: list[str]
    param_sets: dict[str, dict]
    ran: int = 0
    skipped: int = 0
    failed: int = 0
    seconds: float = 0.0
    scheduler: str = "sync"
    tasks: int = 0
    plotted: int = 0
    failed_runs: int = 0

    @property
    def videos_per_min(self) -> float:
        return len(self.videos) / self.seconds * 60.0 if self.seconds > 0 else math.inf

    def to_dataframe(self):
        """``rows`` as a pandas DataFrame, columns :data:`RESULT_COLUMNS`."""
        import pandas as pd
        return pd.DataFrame(self.rows, columns=list(RESULT_COLUMNS))


class BatchInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`batch`; ``results.csv`` was written for the tasks finished.

    ``.result`` is the :class:`BatchResult` of those tasks; the message says
    how many of all tasks they are and where their table is.
    """

    def __init__(self, message: str, result: BatchResult):
        super().__init__(message)
        self.result = result


def _video_keys(videos: list[str]) -> dict[str, str]:
    """Folder name of each video: its stem, with 6 hex digits of a hash of its path where stems repeat."""
    stems = {v: Path(v).stem if Path(v).suffix else Path(v).name for v in videos}
    count = Counter(stems.values())
    return {v: s if count[s] == 1 else f"{s}-{hashlib.sha1(os.path.abspath(v).encode()).hexdigest()[:6]}"
            for v, s in stems.items()}


def _write_table(rows: list[dict], out: Path, parquet: bool) -> None:
    """``results.csv`` (and ``results.parquet``), atomically."""
    write_csv(out / "results.csv", ({k: ("" if r.get(k) is None else r.get(k)) for k in RESULT_COLUMNS} for r in rows),
              RESULT_COLUMNS)
    if parquet:
        import pandas as pd

        df = pd.DataFrame(rows, columns=list(RESULT_COLUMNS))
        for col in ("n_frames", "fields", "alarms", "first_alarm_frame", "warnings", "first_warning_frame"):
            df[col] = df[col].astype("Int64")
        df["seconds"] = df["seconds"].astype("float64")
        with atomic_path(out / "results.parquet") as tmp:
            df.to_parquet(tmp, index=False)


def start_local_cluster(workers: int, **kwargs):
    """``distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)`` and a
    Client on it: ``(cluster, client)``. ``kwargs`` go to ``LocalCluster``.

    The scheduler's HTTP server (the dashboard, if bokeh is installed) takes a free port
    (``dashboard_address=":0"``) and the cluster logs critical messages only
    (``silence_logs=logging.CRITICAL``: a task's failure is in its row), unless given. The
    workers

    * ignore Ctrl-C (SIGINT, ignored while they start: they inherit it). This process handles
      it and closes the cluster, so an interrupt prints no worker tracebacks;
    * run without Dask's ``MALLOC_TRIM_THRESHOLD_`` (``distributed.nanny.pre-spawn-environ``):
      any glibc malloc variable freezes the mmap threshold at 128 KiB, and every frame-sized
      array is then mmap'd and zero-filled anew (measured: LGMD2 10x, mLPLC2 2x slower);
    * get ``NUMBA_NUM_THREADS = CPUs // workers`` (unless set), so that the fast front end's
      bands of all workers share the cores.
    """
    import dask
    from distributed import Client, LocalCluster

    kwargs.setdefault("dashboard_address", ":0")
    kwargs.setdefault("silence_logs", logging.CRITICAL)
    env = {} if "NUMBA_NUM_THREADS" in os.environ else \
        {"NUMBA_NUM_THREADS": str(max(1, (os.cpu_count() or 1) // max(1, workers)))}
    no_trim = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
    with interrupts(ignore=True), dask.config.set(no_trim):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, env=env, **kwargs)
    return cluster, Client(cluster)


def _bad_address(address, why) -> InputValueError:
    return InputValueError(f"scheduler address {address!r} is not valid ({_one_line(str(why))}); "
                           f"expected tcp://HOST:PORT")


#: Address schemes of a Dask scheduler (distributed's comm backends).
_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")


def _check_scheduler(address) -> None:
    """A one-line error for a scheduler address that is not ``SCHEME://HOST:PORT`` (port 1-65535),
    before anything runs or any Client is made: a Client on a malformed address may wait until it
    times out."""
    if not isinstance(address, str):
        raise InputTypeError(f"scheduler must be an address such as tcp://HOST:8786, got {address!r}")
    try:
        url = urlsplit(address if "://" in address else f"tcp://{address}")
        if url.scheme not in _SCHEMES:
            raise ValueError(f"unknown address scheme {url.scheme!r}; known: {', '.join(_SCHEMES)}")
        port = url.port      # ValueError unless an integer in 0-65535
        if url.scheme != "inproc" and not (url.hostname and port):
            raise ValueError("no host or port 1-65535")
    except ValueError as exc:
        raise _bad_address(address, exc) from None


@contextlib.contextmanager
def _client(scheduler: str | None, workers: int | None, client) -> Iterator[tuple[Any, str]]:
    """``(client, name of its scheduler)`` for the tasks: ``client`` (left running), a Client
    on the scheduler at ``scheduler``, or one on a local cluster of ``workers`` (both closed after)."""
    from distributed import Client

    if client is not None:
        yield client, client.scheduler_info()["address"]
    elif scheduler:
        try:
            own = Client(scheduler)
        except ValueError as exc:  # not an address (unknown scheme, no port, ...)
            raise _bad_address(scheduler, exc) from None
        with own:
            _check_workers(own, scheduler)
            yield own, scheduler
    else:
        n = workers or min(4, os.cpu_count() or 1)
        cluster, own = start_local_cluster(n)
        with cluster, own:
            yield own, f"LocalCluster({n} workers)"


#: Seconds a batch waits for a running scheduler (``scheduler=``) to have a worker before it gives up.
WAIT_FOR_WORKERS_S = 30.0


def _check_workers(client, address: str) -> None:
    """A one-line error, before any task is sent, for a running scheduler without workers (waited for
    :data:`WAIT_FOR_WORKERS_S`) or with a worker that cannot import mlplc2: the tasks would wait on
    it without a word (a task a worker cannot unpickle is neither run nor failed)."""
    try:
        client.wait_for_workers(1, timeout=WAIT_FOR_WORKERS_S)
    except (TimeoutError, asyncio.TimeoutError):
        raise InputValueError(f"the scheduler at {address} has no worker (waited {WAIT_FOR_WORKERS_S:g} s): start "
                              f"some there with `dask worker {address}`") from None
    # a builtin with a fixed statement: nothing of mlplc2's needs unpickling on the worker for this test
    answers = client.run(exec, "import mlplc2.batch", on_error="return")
    for worker, answer in sorted(answers.items()):
        if isinstance(answer, BaseException):
            raise InputValueError(f"worker {worker} of {address} cannot import mlplc2 "
                                  f"({type(answer).__name__}: {_one_line(str(answer))}): install it there, the "
                                  f"same version as here") from None


def _completed(jobs: list[tuple[int, dict]], client, remote: bool = False) -> Iterator[tuple[int, dict]]:
    """``(index, row)`` of each job as it finishes: run here one after the other (``client`` None),
    or on ``client``'s cluster (``remote``: one not started here, whose workers' working directories are
    their own)."""
    if client is None:
        for i, t in jobs:
            yield i, run_task(t)
        return
    from distributed import as_completed

    # a remote worker's working directory is its own (another machine's): each input goes as an absolute
    # path; the rows keep the path as given
    futures = {client.submit(run_task, {**t, "source": _absolute(t["video"])} if remote else t, pure=False): (i, t)
               for i, t in jobs}
    for fut in as_completed(futures):
        i, t = futures[fut]
        try:
            row = fut.result()
        except Exception as exc:  # noqa: BLE001 - a worker died, ...
            row = _error_row(t, _one_line(f"{type(exc).__name__}: {exc}"))
        yield i, row


def _absolute(video: str) -> str:
    """``video`` as an absolute path where it is a path here (a file, a folder); else as it is."""
    return os.path.abspath(video) if os.path.exists(video) else video


def _model_run_options(options: Mapping[str, Any], model: str) -> dict:
    """The run options that concern ``model``: the targets' settings only for models with
    targets, gaze stabilisation only for models that have it (so that changing them does not
    rerun the others)."""
    from ..models.base import get_model

    from ..runner import RunOptions

    cls = get_model(model)
    skip = {k for k, needs in (("target_params", cls.has_targets), ("stabilise", cls.stabilises)) if not needs}
    if cls.stabilises:    # recorded even when it is the runner's default: a run made before the default
        options = {"stabilise": RunOptions.stabilise, **options}       # changed is not taken for one made after
    return {k: v for k, v in options.items() if k not in skip}


def batch(inputs, out, *, models: Sequence[str] | str = ("mlplc2",), params=None, sweep=None,
          scheduler: str | None = None, workers: int | None = None, client=None,
          run_options: Mapping[str, Any] | None = None, plot: bool = False, progress: bool = True,
          force: bool = False, parquet: bool = False) -> BatchResult:
    """Run every (video, model, parameter set) as a task and tabulate the results.

    Everything is checked (inputs, parameters, options, the scheduler address)
    before anything is written or run.

    Parameters
    ----------
    inputs : path or list of paths
        Videos, image folders, folders of videos, glob patterns (see :func:`mlplc2.io.expand_inputs`).
    out : path
        Output folder: ``results.csv`` plus ``<video>/<param set>/<model>/``
        with each task's ``responses.csv``, ``fields.json`` and ``done.json``.
    models : list of str
        Registry names.
    params : dict, Params or path to a JSON file, optional
        Parameter overrides (``Params`` fields; ``{"lgmd2": {...}}`` sections
        for other models' parameter classes).
    sweep : list of "NAME=V1,V2,..." or dict, optional
        Parameters to sweep; the Cartesian product gives the parameter sets.
    scheduler : str, optional
        ``tcp://host:port`` of a running Dask scheduler (its workers must see
        the same paths); ``"sync"`` runs sequentially here without Dask.
    workers : int, optional
        Workers of the local cluster started by default
        (``LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)``);
        default ``min(4, CPU count)``; ``0`` runs sequentially here without Dask.
    client : distributed.Client, optional
        Use this client (its cluster is left running).
        At most one of ``scheduler``, ``workers`` and ``client`` may be given.
    run_options : dict, optional
        Extra keyword arguments of :func:`mlplc2.run` (``resize``, ``start``, ``end``, ...).
    plot : bool
        Also write each task's ``responses.png``; for a task already done
        without it, it is drawn from the saved outputs (the task is not rerun).
    progress : bool
        Progress bar (tqdm on stderr) as tasks finish.
    force : bool
        Rerun tasks that are already done.
    parquet : bool
        Also write ``results.parquet`` (needs pandas and pyarrow).

    Returns
    -------
    BatchResult

    Raises
    ------
    BatchInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``), after writing ``results.csv``
        for the tasks finished.
    """
    from ..models.base import resolve_names

    names = resolve_names(models)
    workers, sequential = _check_cluster_options(scheduler, workers, client, parquet)
    from ..io import expand_inputs

    videos = expand_inputs(inputs)
    sets = param_sets(params, sweep, names)
    ids = {param_set_id(s): s for s in sets}
    plan = _plan(videos, ids, names, Path(out), dict(run_options or {}), plot)
    state = _BatchState(plan, *_saved_rows(plan.tasks, force, plot))
    return _run_jobs(state, scheduler, workers, client, sequential, progress, parquet)


def _check_cluster_options(scheduler, workers, client, parquet: bool) -> tuple[int | None, bool]:
    """Check the cluster options (and that pyarrow is there when needed):
    ``workers`` checked, and whether the tasks run here one after the other, without Dask."""
    if workers is not None:
        workers = check_int(workers, "workers", minimum=0)
    if client is not None and (scheduler is not None or workers is not None):
        raise InputValueError("client cannot be combined with scheduler or workers: its cluster runs the tasks")
    if scheduler is not None and workers is not None and not (scheduler == "sync" and workers == 0):
        raise InputValueError("--scheduler and --workers cannot be combined: --workers N starts a local cluster "
                              "(0: runs the tasks here without Dask), --scheduler ADDRESS uses a running one")
    sequential = scheduler == "sync" or (workers == 0 and scheduler is None and client is None)
    if scheduler not in (None, "sync"):
        _check_scheduler(scheduler)
    if parquet:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InputValueError("results.parquet needs pyarrow: pip install 'mlplc2[parquet]'") from None
    return workers, sequential


@dataclass
class _Plan:
    """The tasks of a batch, and per row of ``results.csv`` its (task index, parameter set id)."""

    videos: list[str]
    ids: dict[str, dict]
    out: Path
    tasks: list[dict]
    slots: list[tuple[int, str]]


def _plan(videos: list[str], ids: dict[str, dict], names: list[str], out: Path, run_options: dict,
          plot: bool) -> _Plan:
    """One row per (video, parameter set, model); one task per distinct (video, model, the
    parameters that apply to that model): an LGMD model is not rerun for each value of a
    swept Params field it does not use."""
    keys = _video_keys(videos)
    tasks: list[dict] = []
    slots: list[tuple[int, str]] = []  # per row: (task index, parameter set id)
    by_out: dict[str, int] = {}
    for v in videos:
        for pid, pset in ids.items():
            for m in names:
                own = restrict(pset, m)
                rel = Path(keys[v]) / param_set_id(own) / m
                key = rel.as_posix()
                if key not in by_out:
                    by_out[key] = len(tasks)
                    over = model_overrides(own, m)
                    tasks.append({"video": v, "model": m, "label": param_label(m, over),
                                  "param_set": param_set_id(own), "pset": own, "overrides": over,
                                  "out": str((out / rel).resolve()), "rel_out": key, "plot": plot,
                                  "run_options": _model_run_options(run_options, m)})
                slots.append((by_out[key], pid))
    return _Plan(videos, ids, out, tasks, slots)


def _saved_rows(tasks: list[dict], force: bool, plot: bool) -> tuple[dict[int, dict], list[int], list[int]]:
    """The rows of the tasks already done (``done.json``), the tasks to run, and the finished
    tasks that only lack ``responses.png``."""
    rows: dict[int, dict] = {}
    todo = []    # tasks to run
    replot = []  # finished tasks that only lack responses.png
    for i, t in enumerate(tasks):
        saved = None if force else _done_row(t)
        if saved is None:
            todo.append(i)
            continue
        rows[i] = saved
        if plot and saved.get("n_frames") and not (Path(t["out"]) / "responses.png").is_file():
            replot.append(i)
    return rows, todo, replot


@dataclass
class _BatchState:
    """A batch as it runs: the rows so far and what is left."""

    plan: _Plan
    rows: dict[int, dict]
    todo: list[int]
    replot: list[int]
    used: str = "sync"
    finished: set[int] = dataclasses.field(default_factory=set)  # jobs done in this call
    t0: float = 0.0

    def jobs(self) -> list[tuple[int, dict]]:
        tasks = self.plan.tasks
        return [(i, tasks[i]) for i in self.todo] + [(i, {**tasks[i], "replot": True}) for i in self.replot]

    def result(self) -> BatchResult:
        """The result of the tasks done (read back, or finished now)."""
        plan, rows, tasks = self.plan, self.rows, self.plan.tasks
        ordered = [{**rows[i], "label": tasks[i]["label"], "param_set": pid} for i, pid in plan.slots if i in rows]
        ran = [i for i in self.todo if i in self.finished]
        return BatchResult(rows=ordered, table=plan.out / "results.csv", out=plan.out, videos=plan.videos,
                           param_sets=plan.ids, ran=len(ran), skipped=len(tasks) - len(self.todo),
                           failed=sum(r["status"] == "error" for r in ordered),
                           seconds=time.perf_counter() - self.t0, scheduler=self.used, tasks=len(tasks),
                           plotted=sum(i in self.finished for i in self.replot),
                           failed_runs=sum(rows[i]["status"] == "error" for i in ran))


def _run_jobs(state: _BatchState, scheduler, workers, client, sequential: bool, progress: bool,
              parquet: bool) -> BatchResult:
    """Run the jobs (here or on the cluster), with a progress bar; write ``results.csv``."""
    jobs = state.jobs()
    tasks, out, rows = state.plan.tasks, state.plan.out, state.rows
    state.t0 = time.perf_counter()
    from .._progress import bar as progress_bar

    bar = progress_bar(total=len(tasks), initial=len(tasks) - len(jobs), disable=not progress, unit="task",
                       desc="batch")
    prepared = False
    local = not (sequential or not jobs) and not scheduler and client is None
    if local:                            # start_local_cluster: the workers and this process ignore Ctrl-C meanwhile
        bar.set_description_str("batch: starting workers (Ctrl-C is ignored until they run)")
    try:
        with contextlib.nullcontext((None, "sync")) if sequential or not jobs else \
                _client(scheduler, workers, client) as (c, state.used):
            if local:
                bar.set_description_str("batch")
            out.mkdir(parents=True, exist_ok=True)  # once the cluster is up: nothing is written before
            for pid, pset in state.plan.ids.items():  # what each parameter set id stands for
                write_json(out / f"param_set_{pid}.json", pset)
            prepared = True
            for i, row in _completed(jobs, c, remote=bool(scheduler) and scheduler != "sync" or client is not None):
                rows[i] = row
                state.finished.add(i)
                if bar.n + 1 < bar.total:
                    bar.update()
                else:            # the last task: close() draws the full bar (drawn here too, it came twice)
                    bar.n += 1
    except KeyboardInterrupt:
        res = state.result()
        if prepared:
            _write_table(res.rows, out, parquet)
            message = f"interrupted with {len(rows)} of {len(tasks)} task(s) done; their rows are in {res.table}"
        else:
            message = f"interrupted before any task ran; nothing written to {out}"
        if progress:
            bar.write(f"batch: {message}", file=sys.stderr)
        raise BatchInterrupted(message, res) from None
    finally:
        bar.close()
    res = state.result()
    _write_table(res.rows, out, parquet)
    return res
