"""Live sources and the stream of results (mlplc2.io streams, mlplc2.runner.live, ``mlplc2 run
--jsonl``, ``mlplc2.stream``): a clip over HTTP and through stdin gives the file's results; the
JSON lines arrive while the run goes on; a live source faster than the model keeps the delay
bounded and counts the frames it skipped; a dropped stream keeps what was written."""

from __future__ import annotations

import functools
import io
import http.server
import json
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import mlplc2
from mlplc2.cli import main
from mlplc2.io import FrameSource
from mlplc2.io.decoders import Decoder
from mlplc2.runner.live import Latency

from .helpers import disc_with_gap, jsonl_results


@pytest.fixture
def http_dir(tmp_path):
    """Serve ``tmp_path / "www"`` on 127.0.0.1; yields (folder, base URL)."""
    root = tmp_path / "www"
    root.mkdir()
    handler = functools.partial(_QuietHandler, directory=str(root))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield root, f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def _lines(path):
    return jsonl_results(path.read_text())


def _late_index_mp4(clip):
    """Write an MP4 whose index (moov atom) comes after its frames (most cameras' and phones'
    files, nc07.mp4 of the real clips); return its bytes."""
    import av

    with av.open(str(clip), "w") as out:      # PyAV's MP4 muxer writes the index last by default
        stream = out.add_stream("mpeg4", rate=30)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        rng = np.random.default_rng(0)    # noise: a file (150 kB) larger than FFmpeg's read buffer
        for _ in range(30):
            frame = av.VideoFrame.from_ndarray(rng.integers(0, 256, (120, 160, 3), dtype=np.uint8), format="rgb24")
            out.mux(stream.encode(frame))
        out.mux(stream.encode(None))
    data = clip.read_bytes()
    assert data.find(b"moov") > data.find(b"mdat")
    return data


def test_an_mp4_with_its_index_at_the_end_on_stdin_says_why_it_cannot_be_read(tmp_path):
    """FFmpeg cannot seek back in a pipe to the frames of an MP4 whose index (moov atom) comes
    after them: one error line that says so and what to do, exit 2, nothing written."""
    data = _late_index_mp4(tmp_path / "late_index.mp4")
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-o", str(tmp_path / "s")],
                          input=data, capture_output=True, timeout=120)   # a pipe (a file could seek)
    proc.stderr = proc.stderr.decode()
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "index (moov atom) is at its end" in proc.stderr
    assert "give its path" in proc.stderr and not (tmp_path / "s").exists()


def test_an_mp4_with_its_index_at_the_end_over_http_without_ranges_says_why(tmp_path, http_dir, capsys):
    """Python's http.server (the first server a user tries) answers no range requests, so FFmpeg
    cannot seek to the index at the end: one line that says so and what to do (it said
    "Input/output error"), exit 2, nothing written."""
    root, base = http_dir
    _late_index_mp4(root / "late_index.mp4")
    assert main(["run", f"{base}/late_index.mp4", "-q", "-o", str(tmp_path / "h")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "index (moov atom) is at its end" in err and "range requests" in err
    assert not (tmp_path / "h").exists()


def test_a_text_file_over_http_is_not_a_video(tmp_path, http_dir, capsys):
    """What the server sends decodes as no video: the error line says so in words (until session 14 only
    FFmpeg's "Invalid data found when processing input")."""
    root, base = http_dir
    (root / "notes.txt").write_text("not a video\n" * 20)
    assert main(["run", f"{base}/notes.txt", "-q", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"mlplc2: error: {base}/notes.txt: cannot open the stream (Invalid data found when processing "
                   f"input: what came is not a video FFmpeg can read)")
    assert not (tmp_path / "o").exists()


def test_http_and_stdin_give_the_results_of_the_file(data, tmp_path, http_dir, capsys):
    clip = data["avi"]
    root, base = http_dir
    (root / "clip.avi").write_bytes(clip.read_bytes())
    common = ["--every-frame", "-q"]
    assert main(["run", str(clip), "-o", str(tmp_path / "f"), "--jsonl", str(tmp_path / "f.jsonl"), *common]) == 0
    assert main(["run", f"{base}/clip.avi", "-o", str(tmp_path / "h"), "--jsonl", str(tmp_path / "h.jsonl"),
                 *common]) == 0
    with open(clip, "rb") as stdin:
        proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-o", str(tmp_path / "s"),
                               "--jsonl", "-", *common], stdin=stdin, capture_output=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    from_file = _lines(tmp_path / "f.jsonl")
    assert len(from_file) == 60 and any(line["targets"] for line in from_file)
    assert _lines(tmp_path / "h.jsonl") == from_file
    assert jsonl_results(proc.stdout.decode()) == from_file
    for out in ("h", "s"):
        assert (tmp_path / out / "targets.csv").read_text() == (tmp_path / "f" / "targets.csv").read_text()


def test_run_on_an_empty_stdin_says_so(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-q", "-o", str(tmp_path / "e")],
                          stdin=subprocess.DEVNULL, capture_output=True, timeout=120)
    err = proc.stderr.decode()
    assert proc.returncode == 2 and err == "mlplc2: error: stdin: standard input is empty: no video was piped in\n"
    assert not (tmp_path / "e").exists()


def test_run_on_stdin_from_a_terminal_says_so_instead_of_waiting(tmp_path):
    """``mlplc2 run -`` typed without a pipe: one error line at once (it waited for the keyboard)."""
    import os
    import pty

    leader, tty = pty.openpty()
    try:
        proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-q", "-o", str(tmp_path / "t")],
                              stdin=tty, capture_output=True, timeout=60)
    finally:
        os.close(tty)
        os.close(leader)
    err = proc.stderr.decode()
    assert proc.returncode == 2 and err.count("\n") == 1 and "standard input is a terminal" in err
    assert not (tmp_path / "t").exists()


def test_a_truncated_video_on_stdin_is_reported_as_from_a_file(data, tmp_path):
    """A cut AVI (its header states 60 frames) piped in: the frames that decode are processed and
    one warning line says where decoding stopped, exit 2, as for the file (it ended with exit 0
    and nothing said)."""
    clip = data["avi"].read_bytes()
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-q", "-o", str(tmp_path / "s")],
                          input=clip[: len(clip) * 2 // 3], capture_output=True, timeout=120)
    err = proc.stderr.decode()
    assert proc.returncode == 2, err
    assert err.count("\n") == 1 and "stdin: decoding stopped at frame" in err and "of 60" in err
    summary = json.loads((tmp_path / "s" / "fields.json").read_text())
    assert summary["truncated"] and 0 < summary["n_frames"] < 60



def _piped_in_two(clip: bytes, split: int, out) -> tuple[dict, list[str], str]:
    """``mlplc2 run - --jsonl -`` fed ``clip[:split]``, then (once its first JSON line has come, the
    process still running and its stdin still open) the rest: (the first line, the other lines, stderr)."""
    import select

    with subprocess.Popen([sys.executable, "-m", "mlplc2", "run", "-", "--jsonl", "-", "-o", str(out)],
                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        try:
            proc.stdin.write(clip[:split])
            proc.stdin.flush()
            assert select.select([proc.stdout], [], [], 90)[0], "no line before the rest of the clip was sent"
            first = json.loads(proc.stdout.readline())
            assert proc.poll() is None
            proc.stdin.write(clip[split:])
            proc.stdin.close()
            rest = proc.stdout.read().decode().splitlines()
            err = proc.stderr.read().decode()
            assert proc.wait(timeout=120) == 0, err
        finally:
            proc.kill()
    return first, rest, err

def test_jsonl_lines_arrive_while_the_run_goes_on(data, tmp_path):
    """The first line is read while the process still runs: its stdin (the clip) is not closed yet.
    The clip is a stream as a camera tool sends it, Matroska without a frame count (an AVI states
    its count: a file, read 60 frames ahead for its repeat check first, docs/cli.md "Live sources")."""
    av = pytest.importorskip("av")
    from mlplc2.io import read_video

    with av.open(str(tmp_path / "clip.mkv"), "w") as out:
        stream = out.add_stream("ffv1", rate=30)
        stream.width, stream.height, stream.pix_fmt = 320, 240, "yuv420p"
        for f in read_video(data["avi"])[0]:
            out.mux(stream.encode(av.VideoFrame.from_ndarray(f, format="rgb24")))
        out.mux(stream.encode(None))
    clip = (tmp_path / "clip.mkv").read_bytes()
    first, rest, err = _piped_in_two(clip, len(clip) * 3 // 4, tmp_path / "o")
    assert first["schema"] == 1 and first["frame"] == 0 and first["skipped"] == 0
    assert set(first) >= {"time_s", "warning", "targets", "models"}
    # the computer's clock when the line was made, and the time since the frame's decoding (a robot's age of a line)
    assert abs(first["wall_s"] - time.time()) < 600 and first["latency_ms"] >= 0
    assert len(rest) == 59 and all(line.startswith("{") for line in rest)  # stdout: the JSON lines alone
    assert "60 frames of stdin" in err  # the summary went to stderr, naming the source as the progress bar does


def _camera_stream(path, n=60, size=(160, 120)) -> bytes:
    """A camera tool's stream, as ``ffmpeg -f v4l2 ... -f matroska -`` sends it: MJPEG in Matroska,
    a few KB a frame (a square that grows on noise)."""
    av = pytest.importorskip("av")
    w, h = size
    bg = np.random.default_rng(0).integers(60, 200, (h, w), dtype=np.uint8)
    with av.open(str(path), "w") as out:
        stream = out.add_stream("mjpeg", rate=30)
        stream.width, stream.height, stream.pix_fmt = w, h, "yuvj420p"
        for k in range(n):
            f = bg.copy()
            f[h // 2 - 2 - k // 2:h // 2 + 2 + k // 2, w // 2 - 2 - k // 2:w // 2 + 2 + k // 2] = 0
            out.mux(stream.encode(av.VideoFrame.from_ndarray(np.repeat(f[:, :, None], 3, axis=2), format="rgb24")))
        out.mux(stream.encode(None))
    return path.read_bytes()


def test_frames_piped_in_reach_the_models_as_they_arrive(tmp_path):
    """The first frames of a camera's stream give their lines while the camera goes on: the run does not
    wait for 32 KB of stdin (FFmpeg's read size, 5-8 such frames) before it decodes the first. Until session
    54 stdin was read through ``sys.stdin.buffer``, whose ``read(n)`` waits for all ``n`` bytes: lines came in
    bursts, and the frames sent just before a camera stalled only after the stall."""
    clip = _camera_stream(tmp_path / "cam.mkv")
    split = 20000              # the header and the first few frames, less than one of FFmpeg's reads
    assert split < 32768 < len(clip)
    first, rest, err = _piped_in_two(clip, split, tmp_path / "o")
    assert first["frame"] == 0 and len(rest) == 59, err


def test_ctrl_c_while_a_piped_camera_stalls_keeps_the_outputs_and_exits(tmp_path):
    """SIGINT while stdin is open but nothing comes (a stalled camera): the one-line message, exit 130 and
    the outputs of the frames so far, at once; until session 54 the run waited for the next bytes, then
    died at exit on the lock of ``sys.stdin`` its decoding thread held."""
    import select
    import signal

    clip = _camera_stream(tmp_path / "cam.mkv")
    with subprocess.Popen([sys.executable, "-m", "mlplc2", "run", "-", "--jsonl", "-", "-o", str(tmp_path / "o")],
                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        try:
            proc.stdin.write(clip[:40000])
            proc.stdin.flush()
            assert select.select([proc.stdout], [], [], 90)[0], "no line before the stall"
            time.sleep(1.0)            # the frames sent are processed; then nothing more comes
            proc.send_signal(signal.SIGINT)
            code = proc.wait(timeout=60)
            err = proc.stderr.read().decode()
            lines = proc.stdout.read().decode().splitlines()
        finally:
            proc.kill()
    assert code == 130, err
    assert err.startswith("mlplc2: interrupted after ") and err.count("\n") == 1, err
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert summary["interrupted"] and summary["n_frames"] >= len(lines) >= 1


@pytest.mark.skipif(not hasattr(__import__("os"), "mkfifo"), reason="named pipes are POSIX")
def test_a_named_pipe_is_read_as_a_stream(tmp_path):
    """``mlplc2 run cam.fifo``, a named pipe a camera tool writes into, is read as stdin is (until session 54:
    "no such file or directory", as if it were not there)."""
    import os

    clip = _camera_stream(tmp_path / "cam.mkv")
    fifo = tmp_path / "cam.fifo"
    os.mkfifo(fifo)
    writer = threading.Thread(target=fifo.write_bytes, args=(clip,), daemon=True)
    writer.start()
    proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", str(fifo), "--jsonl", "-", "-o", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=300)
    writer.join(timeout=10)
    assert proc.returncode == 0, proc.stderr
    assert [json.loads(line)["frame"] for line in proc.stdout.splitlines()] == list(range(60))


def test_jsonl_given_twice_is_one_line_not_the_last_silently(tmp_path, capsys):
    """``--jsonl - --jsonl FILE`` kept the last and said nothing: no line came on stdout."""
    assert main(["run", "whatever.avi", "--jsonl", "-", "--jsonl", str(tmp_path / "x.jsonl")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--jsonl: given twice" in err and "tee" in err, err


class _Clock(Decoder):
    """A live camera stand-in: frame k is ready at ``t0 + k * period`` (read waits for it; a source
    that lags its schedule reads on without waiting); a square on noise that grows. ``produced``
    counts the frames delivered so far."""

    def __init__(self, n, period):
        self.name, self.fps, self.size = "clock", 1.0 / period, (160, 120)
        self.n, self.period, self.produced, self.t0 = n, period, 0, None
        rng = np.random.default_rng(1)
        self.bg = rng.integers(60, 200, (120, 160), dtype=np.uint8)

    def read(self):
        if self.produced >= self.n:
            return None
        self.t0 = time.perf_counter() if self.t0 is None else self.t0
        wait = self.t0 + self.produced * self.period - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        f = self.bg.copy()
        s = 2 + (self.produced // 4) % 40
        f[60 - s:60 + s, 80 - s:80 + s] = 0
        self.produced += 1
        return np.repeat(f[:, :, None], 3, axis=2)


@pytest.mark.parametrize("live", [True, False])
def test_a_live_source_faster_than_the_model_skips_to_the_newest_frame(live):
    # Frame counts and a median, not a bound on every delay, so that a loaded machine does not fail it
    # (it failed at load ~12): the source runs on for as long as the test needs (however long the
    # models take to build or compile), the consumer takes 12 lines.
    period, work = 0.003, 0.06        # the source: 333 frames/s; the consumer: 60 ms a frame and its step
    dec = _Clock(10**7, period)
    src = FrameSource(dec, "camera", live=live)
    lines, due, delays = [], [], []     # due: the newest frame the camera had filmed when the next was asked
    gen = mlplc2.stream(src, "mlplc2", repeat_threshold=None)
    for line in gen:
        delays.append(time.perf_counter() - (dec.t0 + line["frame"] * period))  # since it was due
        lines.append(line)
        if len(lines) == 12:
            break
        time.sleep(work)
        due.append(int((time.perf_counter() - dec.t0) / period))
    gen.close()
    frames = [line["frame"] for line in lines]
    assert frames == sorted(set(frames))
    assert sum(line["skipped"] for line in lines) == src.n_skipped == frames[-1] + 1 - len(frames)
    if live:                            # each line: (about) the newest frame when it was asked for
        assert all(b - a - 1 == line["skipped"] for a, b, line in zip(frames, frames[1:], lines[1:]))
        lag = sorted(d - f for f, d in zip(frames[1:], due))   # frames; ~20 come during each wait
        assert lag[len(lag) // 2] < 10, (frames, due)   # the median: a loaded machine may stall a few
        assert src.n_skipped > 11 * 4
    else:                               # a file is read frame by frame: nothing skipped, the lag grows
        assert frames == list(range(12)) and src.n_skipped == 0
        assert all(b - a > work - period for a, b in zip(delays[1:], delays[2:])), delays


def test_run_stops_after_max_frames_and_reports_latency(data, tmp_path, capsys):
    assert main(["run", str(data["avi"]), "-o", str(tmp_path / "o"), "--max-frames", "7"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("7 frames of")
    assert "latency from decoding to results: median" in out
    assert "(a file: the wait in the decoding queue included" in out   # not a live source's latency
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert summary["n_frames"] == 7 and set(summary["latency_ms"]) == {"median_ms", "p99_ms", "max_ms"}


class _DroppingHandler(http.server.BaseHTTPRequestHandler):
    payload = b""

    def do_GET(self):  # noqa: N802 - http.server's name
        self.send_response(200)
        self.send_header("Content-Length", str(len(self.payload)))
        self.end_headers()
        self.wfile.write(self.payload[: len(self.payload) // 2])   # then the connection drops
        self.wfile.flush()
        self.connection.shutdown(2)

    def log_message(self, *args):
        pass


def test_a_dropped_stream_ends_cleanly_keeping_what_was_written(data, tmp_path, capsys):
    handler = type("H", (_DroppingHandler,), {"payload": data["avi"].read_bytes()})
    server = http.server.HTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}/clip.avi"
        code = main(["run", url, "-o", str(tmp_path / "o"), "--jsonl", str(tmp_path / "o.jsonl"), "-q"])
    finally:
        server.shutdown()
        server.server_close()
    err = capsys.readouterr().err
    assert code == 0
    assert len(err.strip().splitlines()) == 1 and "the stream stopped after" in err and "Traceback" not in err
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    n = summary["n_frames"]
    assert 5 < n < 60 and summary["dropped"] and not summary["complete"]
    assert len(_lines(tmp_path / "o.jsonl")) == n


def test_a_urls_password_is_in_no_message_file_or_folder_name(data, tmp_path, monkeypatch, capsys):
    """``rtsp://user:password@HOST/PATH`` goes to FFmpeg as is (docs/robot.md); the error lines, the
    summary, ``fields.json`` and the default folder's name show ``user:***@`` (they showed the
    password, and a URL without a path named the folder after ``user_password_host``)."""
    handler = type("H", (_DroppingHandler,), {"payload": data["avi"].read_bytes()})
    server = http.server.HTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    monkeypatch.chdir(tmp_path)
    try:
        url = f"http://robot:s3cret@127.0.0.1:{server.server_address[1]}"
        code = main(["run", url, "--jsonl", str(tmp_path / "o.jsonl")])
    finally:
        server.shutdown()
        server.server_close()
    captured = capsys.readouterr()
    assert code == 0 and "the stream stopped after" in captured.err
    shown = f"http://robot:***@127.0.0.1:{server.server_address[1]}"
    assert f"{shown}: the stream stopped" in captured.err and f"of {shown} " in captured.out
    folders = [p.name for p in tmp_path.iterdir() if p.is_dir()]
    assert folders == ["127.0.0_mlplc2"], folders      # the host's name (its port dropped as a suffix)
    assert json.loads((tmp_path / folders[0] / "fields.json").read_text())["video"] == shown
    assert main(["run", "rtsp://robot:s3cret@no-such-camera.invalid/s", "-q"]) == 2
    everything = captured.out + captured.err + capsys.readouterr().err
    everything += "".join(p.read_text() for p in (tmp_path / folders[0]).glob("*.*") if p.suffix in (".json", ".csv"))
    assert "s3cret" not in everything


@pytest.mark.parametrize("source", ["rtsp://127.0.0.1:9/none", "http://127.0.0.1:9/none.mp4"])
def test_an_unreachable_stream_is_one_line(source, capsys):
    assert main(["run", source, "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"mlplc2: error: {source}: cannot open the stream") and "\n" not in err
    assert "Errno" not in err and err.count(source) == 1          # FFmpeg's words: the URL is named once


def test_a_missing_file_on_a_server_is_one_line_that_says_404(tmp_path, capsys):
    import functools
    import http.server
    import threading

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(tmp_path)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/none.mp4"
    try:
        assert main(["run", url, "-q", "--out", str(tmp_path / "o")]) == 2
    finally:
        server.shutdown()
        server.server_close()
    assert capsys.readouterr().err.strip() == f"mlplc2: error: {url}: cannot open the stream (Server returned 404 Not Found)"


@pytest.mark.parametrize("scheme", ["http", "rtsp"])
def test_a_server_that_never_answers_is_one_line_that_says_so(scheme, monkeypatch, capsys):
    """A port that accepts the connection and sends nothing: after the wait (shortened to 1 s) one
    line says there was no answer (FFmpeg's own words were "Immediate exit requested" for HTTP
    and "Invalid data found when processing input" for RTSP)."""
    import socket

    from mlplc2.io import decoders

    monkeypatch.setattr(decoders._PyAVDecoder, "TIMEOUT_S", 1.0)
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(4)
        url = f"{scheme}://127.0.0.1:{server.getsockname()[1]}/stream"
        assert main(["run", url, "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"mlplc2: error: {url}: cannot open the stream (no answer within 1 s)"


@pytest.mark.parametrize("scheme", ["http", "rtsp"])
def test_a_host_name_that_does_not_resolve_is_named(scheme, tmp_path, capsys):
    """A mistyped camera host: one line that names it (FFmpeg's own words were "Input/output
    error"). ``.invalid`` never resolves (RFC 2606). Nothing is written."""
    url = f"{scheme}://no-such-camera.invalid/stream1"
    assert main(["run", url, "-q", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"mlplc2: error: {url}: cannot open the stream (host 'no-such-camera.invalid' not found)"
    assert not (tmp_path / "o").exists()


def test_latency_percentiles():
    lat = Latency()
    for ms in range(1, 201):            # 1 .. 200 ms
        lat.add(ms / 1000)
    assert lat.stats() == {"median_ms": 100.5, "p99_ms": 198.0, "max_ms": 200.0}
    assert Latency().stats() == {}


def test_wide_frames_are_reduced_to_the_working_width_in_the_decoding_thread(tmp_path):
    """The models get 320 px frames from the decoding thread and give the answers of a model
    that reduces the full frames itself (positions in input pixels; equal but for the outputs' rounding)."""
    from mlplc2.io import write_video

    rng = np.random.default_rng(2)
    bg = rng.integers(80, 220, (480, 640), dtype=np.uint8)
    frames = []
    for i in range(30):
        f = bg.copy()
        s = 4 + 6 * i
        f[200 - s // 2:200 + s // 2, 400 - s // 2:400 + s // 2] = 0
        frames.append(np.repeat(f[:, :, None], 3, axis=2))
    clip = write_video(tmp_path / "wide.avi", frames, 30.0)
    decoded = list(mlplc2.io.open_source(clip))
    result = mlplc2.run(clip, ["mlplc2"], out=False, repeat_threshold=None, quiet=True)
    assert result.size == (640, 480) and result.model_size == (320, 240)
    model = mlplc2.MLPLC2(fps=30.0, repeat_threshold=None)
    full = [model.step(f) for _, f in decoded][-1]
    run_targets = [t for t in result.targets if t["frame"] == 29]
    assert full.targets and len(run_targets) == len(full.targets)
    for row, t in zip(run_targets, full.targets):
        assert abs(row["x"] - t.x) <= 0.005 and abs(row["y"] - t.y) <= 0.005 and abs(row["width"] - t.width) <= 0.005
        assert abs(row["ttc_s"] - t.ttc_s) <= 0.0005


def test_the_consumer_of_docs_robot_md_brakes_on_a_warning(tmp_path):
    """The ``brake.py`` of docs/robot.md, fed two JSON lines, prints one BRAKE line."""
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot.md").read_text()
    code = "# brake.py" + doc.split("```python\n# brake.py")[1].split("```")[0]
    quiet = {"schema": 1, "frame": 3, "time_s": 0.1, "skipped": 0, "warning": False, "models": {}, "targets": []}
    target = {"model": "mlplc2", "id": 1, "x": 1, "y": 1, "width": 9, "height": 9, "ttc_s": 0.42, "miss": 0.1,
              "azimuth_deg": None, "elevation_deg": None, "ttc_age_s": 0.0, "warning": True}
    loud = dict(quiet, frame=4, warning=True, targets=[target])
    proc = subprocess.run([sys.executable, "-c", code], input=f"{json.dumps(quiet)}\n{json.dumps(loud)}\n",
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "BRAKE at frame 4: contact in 0.42 s\n"


def test_a_reader_that_goes_away_stops_the_run_keeping_its_outputs(data, tmp_path):
    with subprocess.Popen([sys.executable, "-m", "mlplc2", "run", str(data["avi"]), "--jsonl", "-", "-q",
                           "-o", str(tmp_path / "o")], stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        json.loads(proc.stdout.readline())
        proc.stdout.close()  # the robot stack stops reading
        err = proc.stderr.read().decode()
        assert proc.wait(timeout=120) == 0, err
    assert err.count("\n") == 1 and "the reader of the JSON lines went away" in err and "Traceback" not in err
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    assert 1 <= summary["n_frames"] < 60
    assert summary["reader_gone"] and not summary["complete"]       # the clip was not read to its end


def test_a_live_url_is_decoded_with_the_newest_frame_taken(data, tmp_path):
    """``tcp://`` (a live scheme, like ``rtsp://``, which has no server here): a sender faster than
    real time; the run takes the newest frames, and the lines account for every frame."""
    import socket

    payload = data["avi"].read_bytes()
    server = socket.create_server(("127.0.0.1", 0))

    def send():
        conn, _ = server.accept()
        with conn:
            conn.sendall(payload)

    threading.Thread(target=send, daemon=True).start()
    try:
        url = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        assert main(["run", url, "-o", str(tmp_path / "o"), "--jsonl", str(tmp_path / "o.jsonl"), "-q",
                     "--every-frame"]) == 0
    finally:
        server.close()
    lines = _lines(tmp_path / "o.jsonl")
    frames = [line["frame"] for line in lines]
    assert frames[-1] == 59 and len(frames) + sum(line["skipped"] for line in lines) == 60
    assert all(b - a - 1 == line["skipped"] for a, b, line in zip(frames, frames[1:], lines[1:]))
    assert json.loads((tmp_path / "o" / "fields.json").read_text())["frames_skipped"] == 60 - len(frames)


def test_a_misspelt_keyword_names_the_function_and_the_likely_one():
    with pytest.raises(TypeError, match=r"^stream\(\) got an unexpected keyword argument 'max_frame' "
                                        r"\(did you mean 'max_frames'\?\)$"):
        next(mlplc2.stream("clip.mp4", max_frame=3))
    with pytest.raises(TypeError, match=r"^run\(\) got an unexpected keyword argument 'nonsense' \(the keywords "
                                        r"are mlplc2.runner.RunOptions' fields\)$"):
        mlplc2.run("clip.mp4", nonsense=1)


_WORKERS = r"""
import sys, threading
import mlplc2
from mlplc2 import stimuli
from mlplc2.io import write_video

st = stimuli.approach([], size=(320, 240), fps=30.0, frames=20, background="texture",
                      camera=stimuli.CameraPath(yaw_rate_dps=10.0), noise_std=2.0, seed=1)
clip = str(write_video(sys.argv[1], st.frames, 30.0))


def ours():
    return sorted({t.name.split("_")[0] for t in threading.enumerate() if t.name.startswith("mlplc2")})


gen = mlplc2.stream(clip, hfov_deg=60.0)       # kept in a name: the loop's break does not close it
for k, line in enumerate(gen):
    if k == 8:
        print("during", ours())
        break
gen.close()
print("closed", ours())
for k, line in enumerate(mlplc2.stream(clip, hfov_deg=60.0)):
    if k == 8:
        break                                   # the generator is dropped: CPython closes it at once
print("dropped", ours())
mlplc2.run(clip, out=False, hfov_deg=60.0, quiet=True)
print("run", ours())
"""


def test_closing_a_stream_stops_and_joins_its_worker_threads(tmp_path):
    """A panning camera on 4 Numba threads: the model runs the decoding thread, the front end's band
    pool and the target layer's carry thread; closing the generator after a ``break`` (or dropping it)
    stops and joins every one of them, and so does the end of a run (until session 15 the band pool
    and the carry thread outlived both)."""
    import os

    script = tmp_path / "workers.py"
    script.write_text(_WORKERS)
    proc = subprocess.run([sys.executable, str(script), str(tmp_path / "pan.avi")], capture_output=True, text=True,
                          timeout=240, env=dict(os.environ, NUMBA_NUM_THREADS="4"))
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = dict(line.split(" ", 1) for line in proc.stdout.splitlines())
    assert lines["during"] == "['mlplc2-band', 'mlplc2-carry', 'mlplc2-decode']"   # the threads to stop are there
    assert lines["closed"] == lines["dropped"] == lines["run"] == "[]"


def test_a_duplicated_clip_on_stdin_and_over_http_holds_its_copies_as_the_file_does(tmp_path, http_dir):
    """A clip whose every third frame is repeated twice (a frame-rate conversion): the file is scanned
    for copies before the run and its copies are held from the first one; stdin and HTTP, read once,
    read their first frames ahead on the source itself (``FrameSource.peek``) and give the file's JSON
    lines and held frames (until session 15 they found the copies only after 12 frames: the
    real helmet_attack.avi then warned at frame 43, after contact, instead of 25)."""
    from mlplc2 import stimuli
    from mlplc2.io import write_video

    from .helpers import duplicated

    frames, origin = duplicated(stimuli.four_phase(seed=0).frames[:20])
    clip = write_video(tmp_path / "dup.avi", np.stack(frames), 30.0)
    root, base = http_dir
    (root / "dup.avi").write_bytes(clip.read_bytes())
    assert main(["run", str(clip), "-o", str(tmp_path / "f"), "--jsonl", str(tmp_path / "f.jsonl"), "-q"]) == 0
    assert main(["run", f"{base}/dup.avi", "-o", str(tmp_path / "h"), "--jsonl", str(tmp_path / "h.jsonl"),
                 "-q"]) == 0
    with open(clip, "rb") as stdin:
        proc = subprocess.run([sys.executable, "-m", "mlplc2", "run", "-", "-o", str(tmp_path / "s"), "--jsonl", "-",
                               "-q"], stdin=stdin, capture_output=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    copies = sum(a == b for a, b in zip(origin, origin[1:]))
    held = json.loads((tmp_path / "f" / "fields.json").read_text())["frames_held"]["mlplc2"]
    assert held == copies == 14                       # the file holds every copy, the first ones too
    from_file = _lines(tmp_path / "f.jsonl")
    assert _lines(tmp_path / "h.jsonl") == from_file
    assert jsonl_results(proc.stdout.decode()) == from_file
    for out in ("h", "s"):
        summary = json.loads((tmp_path / out / "fields.json").read_text())
        assert summary["frames_held"]["mlplc2"] == held and summary["duplicated"] and summary["complete"]
        assert (tmp_path / out / "targets.csv").read_text() == (tmp_path / "f" / "targets.csv").read_text()


def _avi_through_a_pipe(frames, fps=30.0) -> bytes:
    """The bytes FFmpeg's AVI muxer writes to a pipe (``ffmpeg -f v4l2 -i /dev/video0 -f avi -``): it
    cannot go back to write the frame count, and states 2**30 frames instead."""
    import os

    av = pytest.importorskip("av")
    r, w = os.pipe()
    got: list[bytes] = []
    def read():
        with os.fdopen(r, "rb") as f:
            got.append(f.read())

    reader = threading.Thread(target=read)
    reader.start()
    with os.fdopen(w, "wb") as pipe, av.open(pipe, "w", format="avi") as out:
        stream = out.add_stream("mjpeg", rate=int(fps))
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuvj420p"
        for f in frames:
            out.mux(stream.encode(av.VideoFrame.from_ndarray(f, format="rgb24")))
        out.mux(stream.encode(None))
    reader.join()
    return got[0]


def test_an_avi_written_to_a_pipe_is_a_stream_of_unknown_length(data, tmp_path):
    """A camera piped in as AVI: its placeholder count (2**30) is no count. The first JSON line comes
    before the 60th frame is sent (the placeholder made it a file, read 60 frames ahead for its
    repeat check: a live camera's first line waited 2 s), and its end is no truncation (it was
    "decoding stopped at frame 60 of 1073741824", exit 2)."""
    from mlplc2.io import open_source, read_video

    clip = _avi_through_a_pipe(read_video(data["avi"])[0])
    av = pytest.importorskip("av")
    with av.open(io.BytesIO(clip)) as c:
        assert c.streams.video[0].frames == 1 << 30      # what FFmpeg states: the case in point
    first, rest, err = _piped_in_two(clip, len(clip) // 2, tmp_path / "o")     # 30 of the 60 frames first
    assert first["frame"] == 0 and len(rest) == 59 and "decoding stopped" not in err
    (tmp_path / "rec.avi").write_bytes(clip)              # saved from the pipe (`... | tee rec.avi`)
    for decoder in ("opencv", "pyav"):
        with open_source(str(tmp_path / "rec.avi"), decoder=decoder) as src:
            assert src.frame_count is None and src.total is None
    res = mlplc2.run(str(tmp_path / "rec.avi"), ["lgmd1"], out=False, progress=False)
    assert res.n_frames == 60 and not res.truncated


def _disc_hidden_for_three_frames(n=42):
    """RGB frames of :func:`tests.helpers.disc_with_gap`: its track is lost and refound, showing the old time to
    contact counted down until its own fit is back."""
    return [np.repeat(img[:, :, None], 3, axis=2) for img in disc_with_gap(n=n)]


def test_each_target_says_how_old_its_time_to_contact_is_and_how_sure(tmp_path):
    """``ttc_age_s`` in the JSON lines (``mlplc2.stream``) and in ``targets.csv`` (its last columns, with
    ``ttc_sigma_s``): 0 on a frame whose fit measured ``ttc_s``; on the frames after the occlusion, where the time
    to contact shown is the one measured before it counted down, the time since that frame (whole frames at 30
    frames/s), and ``ttc_s`` is the one shown then less it, with that fit's standard error; null (empty) without
    ``ttc_s``, and the standard error a positive fraction of ``ttc_s`` with it. The lines and the file agree."""
    import csv

    from mlplc2.evaluation.record import TargetRow
    from mlplc2.io import write_video

    clip = write_video(tmp_path / "gap.avi", _disc_hidden_for_three_frames(), 30.0)
    lines = list(mlplc2.stream(clip, "mlplc2", repeat_threshold=None))
    mlplc2.run(clip, ["mlplc2"], out=tmp_path / "o", repeat_threshold=None, quiet=True)
    with open(tmp_path / "o" / "targets.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames[-3:] == ["ttc_age_s", "ttc_sigma_s", "held_by"]
        rows = {(int(r["frame"]), int(r["target_id"])): r for r in reader}
    shown = {}                                    # (frame, id): the JSON target
    for line in lines:
        for t in line["targets"]:
            assert "ttc_age_s" in t and (t["ttc_s"] is None) == (t["ttc_age_s"] is None)
            row = rows[line["frame"], t["id"]]
            assert row["ttc_age_s"] == ("" if t["ttc_age_s"] is None else str(t["ttc_age_s"]))
            assert TargetRow.from_row(row).ttc_age_s == t["ttc_age_s"]
            assert (t["ttc_s"] is None) == (t["ttc_sigma_s"] is None)
            assert row["ttc_sigma_s"] == ("" if t["ttc_sigma_s"] is None else str(t["ttc_sigma_s"]))
            if t["ttc_s"] is not None:
                assert 0 < t["ttc_sigma_s"] < t["ttc_s"]
            assert t["held_by"] == (row["held_by"] or None) and not (t["warning"] and t["held_by"])
            shown[line["frame"], t["id"]] = t
    held = []
    for (k, tid), t in shown.items():
        if t["ttc_age_s"]:
            ago = round(t["ttc_age_s"] * 30)
            assert t["ttc_age_s"] == pytest.approx(ago / 30, abs=1e-4) and ago >= 1
            then = shown[k - ago, tid]                # the frame of the fit it was held from
            assert then["ttc_age_s"] == 0.0 and t["ttc_s"] == pytest.approx(then["ttc_s"] - t["ttc_age_s"], abs=2e-4)
            assert t["ttc_sigma_s"] == then["ttc_sigma_s"]
            held.append(k)
    assert held and set(held) <= set(range(33, 42))   # only after the occlusion
    assert sum(t["ttc_age_s"] == 0.0 for t in shown.values()) > 20


def test_a_targets_csv_written_before_ttc_age_s_still_loads():
    """An older ``targets.csv`` has no ``ttc_age_s`` or ``ttc_sigma_s`` column: its rows read with neither."""
    from mlplc2.evaluation.record import TargetRow

    old = {"frame": "5", "model": "mlplc2", "target_id": "2", "x": "10.5", "y": "20", "width": "8", "height": "8",
           "ttc_s": "0.75", "miss": "0.1", "warning": "1", "fields": "3 4", "azimuth_deg": "", "elevation_deg": ""}
    row = TargetRow.from_row(old)
    assert (row.id, row.ttc_s, row.warning, row.fields, row.ttc_age_s, row.ttc_sigma_s) == (2, 0.75, True, (3, 4), None,
                                                                                            None)
    assert TargetRow.from_row(dict(old, ttc_age_s="0.0333")).ttc_age_s == pytest.approx(1 / 30, abs=1e-4)
    assert TargetRow.from_row(dict(old, ttc_s="", ttc_age_s="")).ttc_age_s is None


def test_a_targets_csv_row_reads_back_every_cell_it_was_written_with():
    """``mlplc2 evaluate`` reads ``targets.csv`` back: a row read and written again is the row (the bearing too)."""
    from mlplc2.evaluation.record import TargetRow

    row = {"x": "10.5", "y": "20.0", "width": "8.0", "height": "6.0", "ttc_s": "0.75", "miss": "0.1", "warning": "1",
           "fields": "3 4", "azimuth_deg": "12.5", "elevation_deg": "-3.25", "ttc_age_s": "0.0333",
           "ttc_sigma_s": "0.0412", "held_by": ""}
    again = TargetRow.from_row(dict(row, frame="5", model="mlplc2", target_id="2")).values()
    assert {k: ("" if v is None else str(v)) for k, v in again.items()} == row
    row["held_by"], row["warning"] = "onset_fall", "0"                 # the rule that held a warning back
    again = TargetRow.from_row(dict(row, frame="5", model="mlplc2", target_id="2")).values()
    assert {k: ("" if v is None else str(v)) for k, v in again.items()} == row


def test_a_decoder_of_ones_own_gives_the_cameras_clock_across_dropped_frames():
    """The ``SDKCamera`` decoder of docs/robot.md ("Your own camera and its clock") around a camera that drops every
    third frame: each line carries the camera's capture time, and the time to contact is the one of that clock
    (counted in frames delivered, the disc would seem to arrive half as late again)."""
    from pathlib import Path

    from tests.helpers import disc_with_gap

    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot.md").read_text()
    code = "import mlplc2\n" + doc.split("### Your own camera and its clock")[1].split("```python\n")[1].split(
        "for r in mlplc2.stream")[0]
    space: dict = {}
    exec(code, space)                   # noqa: S102 - the documented class, as a user copies it

    contact = 70                        # frame (at 30 fps) of the disc's contact
    frames = disc_with_gap(n=64, contact=contact, gap=(0, 0))
    kept = [k for k in range(len(frames)) if k % 3 != 2]

    class Camera:                       # an SDK's camera: an RGB frame and its capture time, None at the end
        def __init__(self):
            self.i, self.closed = 0, False

        def grab(self):
            if self.i == len(kept):
                return None, None
            k = kept[self.i]
            self.i += 1
            return np.repeat(frames[k][:, :, None], 3, axis=2), k / 30.0

        def close(self):
            self.closed = True

    camera = Camera()
    lines = list(mlplc2.stream(FrameSource(space["SDKCamera"](camera), "camera"), repeat_threshold=None))
    assert camera.closed
    assert [line["time_s"] for line in lines] == pytest.approx([k / 30.0 for k in kept], abs=1e-6)   # 6 decimals
    estimates = [(line["time_s"], t["ttc_s"]) for line in lines for t in line["targets"] if t["ttc_s"] is not None
                 and t["ttc_age_s"] == 0 and line["time_s"] >= 40 / 30.0]
    assert len(estimates) >= 8
    errors = [abs(ttc - (contact / 30.0 - t)) / (contact / 30.0 - t) for t, ttc in estimates]
    assert sorted(errors)[len(errors) // 2] < 0.1, estimates
    assert any(line["warning"] for line in lines)
