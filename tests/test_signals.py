"""Ctrl-C and SIGTERM never split a frame between the outputs (issue 14, item 4).

``mlplc2._signals.interrupts`` is the one context manager that sets what SIGINT and
SIGTERM do: the CLI makes SIGTERM interrupt like Ctrl-C, the frame loop of ``run``
defers an interrupt to the end of the frame in progress, batch ignores SIGINT while
Dask's workers start. Signals are raised in this process (``signal.raise_signal``), at
chosen points of a frame; at the end, a real signal is sent to the console script
running in a child process.
"""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import mlplc2
from mlplc2._signals import interrupts
from mlplc2.cli import main
from mlplc2.io import VideoWriter, write_video
from mlplc2.runner import COLUMNS, RunInterrupted, run
from mlplc2.evaluation.record import Recorder

from .helpers import check_outputs_agree, noise_frames

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")

K = 6  # the frame during which the signal arrives


@pytest.fixture(autouse=True)
def _handlers_restored():
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    assert {s: signal.getsignal(s) for s in before} == before


# -- the context manager ------------------------------------------------------------------
def test_deferred_interrupt_waits_for_the_end_of_the_item():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts(defer=True) as stop:
            for i in stop.between(range(10)):
                done.append(f"start {i}")
                if i == 2:
                    signal.raise_signal(signal.SIGINT)
                    assert stop.pending == signal.SIGINT
                done.append(f"end {i}")
    assert done == ["start 0", "end 0", "start 1", "end 1", "start 2", "end 2"]


def test_second_signal_interrupts_at_once():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts(defer=True) as stop:
            for i in stop.between(range(10)):
                if i == 1:
                    signal.raise_signal(signal.SIGINT)
                    done.append("after the first")
                    signal.raise_signal(signal.SIGINT)
                    done.append("after the second")
    assert done == ["after the first"]


def test_signal_while_waiting_for_the_next_item_interrupts_at_once():
    """A decoder or camera that stalls must not hold Ctrl-C: nothing is in progress then."""

    def items():
        yield 0
        signal.raise_signal(signal.SIGINT)  # arrives while the loop waits for item 1
        yield 1

    got = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts(defer=True) as stop:
            for i in stop.between(items()):
                got.append(i)
    assert got == [0]


def test_pending_interrupt_is_raised_when_the_block_ends():
    with pytest.raises(KeyboardInterrupt):
        with interrupts(defer=True):
            signal.raise_signal(signal.SIGINT)
    with interrupts(defer=True) as stop:
        pass
    assert stop.pending is None and stop.installed


def test_sigterm_interrupts_like_ctrl_c_and_nests():
    with interrupts(sigterm=True):
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGTERM)
        with pytest.raises(KeyboardInterrupt):
            with interrupts(defer=True) as stop:  # deferred like SIGINT inside the frame loop
                signal.raise_signal(signal.SIGTERM)
                assert stop.pending == signal.SIGTERM
    assert signal.getsignal(signal.SIGTERM) is not signal.default_int_handler


def test_other_handlers_are_left_alone():
    seen = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    try:
        with interrupts(defer=True, ) as stop:
            signal.raise_signal(signal.SIGINT)  # the application's own handler runs, nothing deferred
        assert seen == [signal.SIGINT] and stop.pending is None and not stop.installed
    finally:
        signal.signal(signal.SIGINT, previous)
    with interrupts(defer=True):  # SIGTERM's default (terminate) is not an interrupt: untouched
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL


def test_ignore_sigint_while_workers_start():
    with interrupts(ignore=True):
        assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
        signal.raise_signal(signal.SIGINT)  # ignored
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with pytest.raises(ValueError, match="cannot be combined"):
        interrupts(ignore=True, defer=True)


def test_outside_the_main_thread_nothing_changes():
    out = {}

    def work():
        with interrupts(defer=True, sigterm=True) as stop:
            out["items"] = list(stop.between(range(3)))
        out["installed"] = stop.installed

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert out == {"items": [0, 1, 2], "installed": False}


# -- run(): a signal during a frame -------------------------------------------------------
def _frames(n=20, w=96, h=72):
    out = []
    for i in range(n):
        f = np.full((h, w, 3), 170, np.uint8)
        s = 2 + 2 * i  # a dark square looming at the centre: fields, targets and alarms
        f[h // 2 - s // 2:h // 2 + s // 2 + 1, w // 2 - s // 2:w // 2 + s // 2 + 1] = 20
        out.append(f)
    return out


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    return write_video(tmp_path_factory.mktemp("sig") / "loom.avi", _frames(), 30.0)


def _signal_during(monkeypatch, where: str, sig) -> None:
    """Raise ``sig`` once, during frame K, inside ``where``."""
    def hook(original, frame_of):
        def wrapper(self, *args, **kwargs):
            if frame_of(self, *args) == K and not fired:
                fired.append(1)
                signal.raise_signal(sig)
            return original(self, *args, **kwargs)
        return wrapper

    fired: list = []
    if where == "model":
        monkeypatch.setattr(mlplc2.MLPLC2, "step", hook(mlplc2.MLPLC2.step, lambda m, frame, *a: m.frame_index))
    elif where == "video":
        monkeypatch.setattr(VideoWriter, "write", hook(VideoWriter.write, lambda w, frame: w.n_frames))
    elif where == "summaries":
        monkeypatch.setattr(Recorder, "update", hook(Recorder.update, lambda t, index, *a: index))


@pytest.mark.parametrize("where", ["model", "video", "summaries"])
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_signal_during_a_frame_finishes_it_first(clip, tmp_path, monkeypatch, capsys, where, sig):
    """The frame in progress is finished, in every output, then the run stops (exit 130)."""
    _signal_during(monkeypatch, where, getattr(signal, sig))
    out = tmp_path / "o"
    assert main(["run", str(clip), "--out", str(out), "-m", "mlplc2,lgmd2", "--video", "--quiet"]) == 130
    n = check_outputs_agree(out, ["mlplc2", "lgmd2"])
    assert n == K + 1 and f"interrupted after {K + 1} frames" in capsys.readouterr().err
    assert json.loads((out / "fields.json").read_text())["interrupted"]


def test_run_api_defers_ctrl_c_too(clip, monkeypatch):
    _signal_during(monkeypatch, "model", signal.SIGINT)
    with pytest.raises(RunInterrupted) as info:
        run(clip, ["mlplc2", "lgmd2"], out=False, progress=False)
    res = info.value.result
    assert res.n_frames == K + 1 and res.interrupted
    assert sorted({r["frame"] for r in res.rows if r["model"] == "lgmd2"}) == list(range(K + 1))


def test_run_from_another_thread(clip, tmp_path):
    """Handlers can only be set from the main thread: run() works without them elsewhere."""
    box = {}
    t = threading.Thread(target=lambda: box.update(res=run(clip, ["mlplc2", "lgmd2"], out=tmp_path / "t",
                                                           progress=False)))
    t.start()
    t.join()
    assert box["res"].n_frames == 20 and check_outputs_agree(tmp_path / "t", ["mlplc2", "lgmd2"]) == 20


# -- a real signal to the console script ------------------------------------------------
def _csv_rows(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        return header, [dict(zip(header, r)) for r in reader]


def _console_script() -> list[str]:
    exe = Path(sys.executable).with_name("mlplc2")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "mlplc2.cli"]


@pytest.mark.skipif(sys.platform == "win32", reason="signals to a child process are POSIX")
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_real_signal_leaves_valid_outputs(tmp_path, sig):
    """A real Ctrl-C (SIGINT), or SIGTERM as sent by `timeout` and batch schedulers, to the
    console script mid-run with the decoder thread busy: the frames done are saved.
    (test_cli.py raises KeyboardInterrupt in-process; this sends the signal.)"""
    n = 900
    p = write_video(tmp_path / "long.avi", noise_frames(n, 160, 120), 30.0)
    out = tmp_path / "o"
    # SIGINT as in a terminal, even when pytest runs in the background (which ignores it, and
    # an ignored SIGINT is inherited: the run would not stop).
    proc = subprocess.Popen(_console_script() + ["run", str(p), "--out", str(out), "-m", "mlplc2,lgmd2",
                                                 "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    csv_path = out / "responses.csv"
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline:  # wait until it is inside the frame loop
            if csv_path.exists() and csv_path.stat().st_size > 3000:
                break
            if proc.poll() is not None:
                pytest.fail(f"finished before the interrupt: {proc.communicate()}")
            time.sleep(0.02)
        proc.send_signal(getattr(signal, sig))
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    summary = json.loads((out / "fields.json").read_text())
    k = summary["n_frames"]
    assert 0 < k < n and summary["interrupted"] and not summary["complete"]
    assert f"interrupted after {k} frames" in err
    header, rows = _csv_rows(csv_path)
    assert header == list(COLUMNS)
    assert all(len(r) == len(COLUMNS) and None not in r.values() for r in rows)
    for name in ("mlplc2", "lgmd2"):  # every processed frame complete, none beyond
        assert sorted({int(r["frame"]) for r in rows if r["model"] == name}) == list(range(k))
    assert [int(r["frame"]) for r in rows if r["model"] == "lgmd2"] == list(range(k))
    # the three outputs agree: no frame in responses.csv or targets.csv at or past n_frames
    assert check_outputs_agree(out, ["mlplc2", "lgmd2"]) == k
    assert not [q for q in out.iterdir() if q.name.startswith(".")]


# Imports the console script's way (`from mlplc2.cli import main`) after a hook that turns the first
# import of MODULE into a Ctrl-C: the signal arriving while the command's modules load.
_CTRL_C_AT_IMPORT = """
import sys
class CtrlC:
    def find_spec(self, name, path=None, target=None):
        if name == sys.argv[1]:
            raise KeyboardInterrupt
sys.meta_path.insert(0, CtrlC())
from mlplc2.cli import main
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.parametrize("module, argv", [("numpy", ["--help"]), ("cv2", ["run", "clip.avi"]),
                                          ("mlplc2.runner", ["run", "clip.avi"])])
def test_ctrl_c_while_the_modules_load_is_one_line_and_130(module, argv):
    """Ctrl-C in the first few tenths of a second of any command (NumPy, OpenCV, Numba loading)
    is no traceback: the command's modules load under its signal handling."""
    done = subprocess.run([sys.executable, "-c", _CTRL_C_AT_IMPORT, module, *argv], capture_output=True,
                          text=True, timeout=120)
    assert (done.returncode, done.stderr) == (130, "mlplc2: interrupted\n"), done.stderr
