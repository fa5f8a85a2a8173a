"""Progress on stderr: a redrawn bar on a terminal, sparse plain lines anywhere else (a robot's log)."""

import io
import subprocess
import sys

import mlplc2
from mlplc2 import _progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_terminal_gets_the_redrawn_bar():
    term = Terminal()
    bar = _progress.bar(total=3, desc="clip", unit="frame", stream=term, mininterval=0, miniters=1)
    for _ in range(3):
        bar.update()
    bar.close()
    assert "\r" in term.getvalue() and "3/3" in term.getvalue()


def test_a_log_gets_no_carriage_return_and_nothing_for_a_short_run(data, capsys):
    """A run shorter than PLAIN_EVERY_S, stderr not a terminal (capsys): not one progress byte
    (it was a ``\\r`` redraw per update, filling a robot's log unless ``-q`` was given)."""
    res = mlplc2.run(str(data["avi"]), ["lgmd1"], out=False, progress=True)
    assert res.n_frames > 10
    assert capsys.readouterr().err == ""


def test_a_log_gets_whole_lines_every_plain_every_s(data, capsys, monkeypatch):
    monkeypatch.setattr(_progress, "PLAIN_EVERY_S", 0.0)
    res = mlplc2.run(str(data["avi"]), ["lgmd1"], out=False, progress=True)
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "\r" not in err and err.endswith("\n") and lines
    assert all(line.startswith("square.avi: ") and f"/{res.n_frames} frame [" in line for line in lines), err


def test_the_command_line_writes_no_redraws_to_a_pipe(data, tmp_path):
    """``mlplc2 run clip`` under a robot (stderr a pipe or a log file, no ``-q``)."""
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", str(data["avi"]), "-m", "lgmd1",
                           "--out", str(tmp_path / "o")], capture_output=True, timeout=300)
    err = proc.stderr.decode()   # bytes: text=True would turn each \r into \n
    assert proc.returncode == 0, err
    assert "\r" not in err and "frame [" not in err and "it/s" not in err, err
