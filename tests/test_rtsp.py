"""RTSP end to end: a clip served over RTSP on 127.0.0.1 gives the file's results, a live RTSP
stream faster than its consumer is taken at its newest frame with the skipped frames counted, and
a stream that stops ends the run cleanly with what was written kept and one line saying so.

No RTSP server is installed here, so the test is one: :class:`_RTSPServer` answers OPTIONS,
DESCRIBE (an SDP for JPEG, RTP payload type 26, RFC 2435), SETUP (RTP interleaved over the RTSP
TCP connection, which mlplc2 asks for) and PLAY, then sends RTP packets made by FFmpeg's own RTP
muxer (PyAV, ``format="rtp"``, sent to a UDP socket on 127.0.0.1 and collected) from the JPEG
frames of an MJPEG file. mlplc2 reads it with FFmpeg's RTSP demuxer, as it reads a camera's RTSP
server; the frames it decodes are the file's, bit for bit, so the results must be the file's.
"""

from __future__ import annotations

import json
import select
import socket
import struct
import threading
import time

import numpy as np
import pytest

import mlplc2
from mlplc2.cli import main
from mlplc2.io import TruncatedInputWarning, decoders

from .helpers import jsonl_results

av = pytest.importorskip("av")

SDP = ("v=0\r\no=- 0 0 IN IP4 127.0.0.1\r\ns=clip\r\nc=IN IP4 0.0.0.0\r\nt=0 0\r\n"
       "m=video 0 RTP/AVP 26\r\na=framerate:30\r\na=control:streamid=0\r\n")


def _need(kind: str, name: str) -> None:
    available = av.formats_available if kind == "format" else av.codecs_available
    if name not in available:
        pytest.skip(f"PyAV's FFmpeg has no {name} {kind} (needed to serve and read RTSP)")


@pytest.fixture(scope="module")
def rtsp_clip(data, tmp_path_factory):
    """The 60 frames of the ``data`` clip as an MJPEG file RTP can carry (RFC 2435: baseline JPEG,
    4:2:0, standard Huffman tables, two quantisation tables, no restart markers), and its RTP
    packets."""
    for kind, name in (("format", "rtp"), ("format", "rtsp"), ("format", "matroska"), ("codec", "mjpeg")):
        _need(kind, name)
    path = tmp_path_factory.mktemp("rtsp") / "clip.mkv"
    with av.open(str(data["avi"])) as src:
        _write_mjpeg(path, (frame.to_ndarray(format="rgb24") for frame in src.decode(video=0)), 30)
    return path, _rtp_packets(path)


def _write_mjpeg(path, frames, fps) -> None:
    """RGB frames to an MJPEG file whose JPEGs RTP can carry."""
    with av.open(str(path), "w") as out:
        stream = None
        for rgb in frames:
            if stream is None:
                stream = out.add_stream("mjpeg", rate=fps,
                                        options={"huffman": "default", "force_duplicated_matrix": "1"})
                stream.width, stream.height, stream.pix_fmt = rgb.shape[1], rgb.shape[0], "yuvj420p"
                stream.codec_context.thread_count = 1  # slice threads would add restart markers
            out.mux(stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")))
        out.mux(stream.encode(None))


def _rtp_packets(path) -> list[tuple[int, bytes]]:
    """The clip's packets through FFmpeg's RTP muxer, as ``(channel, packet)``: RTP (0) and the
    RTCP sender reports (1) it sends to the next port, collected from two UDP sockets here."""
    rtp, rtcp = _udp_pair()
    packets: list[tuple[int, bytes]] = []
    with rtp, rtcp, av.open(str(path)) as src, \
            av.open(f"rtp://127.0.0.1:{rtp.getsockname()[1]}", "w", format="rtp") as out:
        video = src.streams.video[0]
        stream = out.add_stream_from_template(video)
        for packet in src.demux(video):
            if packet.size == 0:
                continue
            packet.stream = stream
            out.mux(packet)
            wait = 0.5                           # one JPEG frame is several RTP packets
            while ready := select.select([rtp, rtcp], [], [], wait)[0]:
                packets.extend((int(sock is rtcp), sock.recv(65536)) for sock in ready)
                wait = 0.02
    return packets


def _udp_pair():
    """Two UDP sockets on 127.0.0.1 on ports P (even) and P + 1, as RTP and RTCP use."""
    for _ in range(50):
        rtp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        rtp.bind(("127.0.0.1", 0))
        port = rtp.getsockname()[1]
        rtcp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            if port % 2:
                raise OSError("odd port")
            rtcp.bind(("127.0.0.1", port + 1))
        except OSError:
            rtp.close()
            rtcp.close()
            continue
        for sock in (rtp, rtcp):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        return rtp, rtcp
    pytest.skip("no two free UDP ports P, P + 1 on 127.0.0.1")


class _RTSPServer:
    """One RTSP session on 127.0.0.1: the RTP and RTCP packets interleaved on the RTSP connection
    after PLAY (``$``, channel, length, packet), the first ``upto`` of them;
    then it closes the connection, or with ``stall=True`` keeps it open and sends nothing."""

    def __init__(self, packets, *, upto=None, stall=False):
        self.packets, self.upto, self.stall = packets, upto, stall
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.url = f"rtsp://127.0.0.1:{self.sock.getsockname()[1]}/clip"
        self.methods: list[str] = []
        self.done = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        try:
            conn, _ = self.sock.accept()
        except OSError:
            return
        with conn, conn.makefile("rb") as f:
            while not self._answer(conn, f):
                pass
            if self.stall:
                self.done.wait(30)
            # Half-close, then read what the client still sends (RTCP reports) until it closes:
            # closing with unread data would reset the connection and lose the frames in flight.
            conn.shutdown(socket.SHUT_WR)
            conn.settimeout(30)
            while f.read(65536):
                pass

    def _answer(self, conn, f) -> bool:
        """Answer one request (skipping the client's interleaved RTCP); True when done."""
        first = f.read(1)
        while first == b"$":
            _, n = struct.unpack(">BH", f.read(3))
            f.read(n)
            first = f.read(1)
        if not first:
            return True
        method, url = (first + f.readline()).decode().split()[:2]
        headers = {}
        for line in iter(f.readline, b"\r\n"):
            if not line:
                return True
            key, _, value = line.decode().partition(":")
            headers[key.strip().lower()] = value.strip()
        f.read(int(headers.get("content-length", 0)))
        self.methods.append(method)
        extra, body = {
            "OPTIONS": ("Public: OPTIONS, DESCRIBE, SETUP, PLAY, TEARDOWN\r\n", ""),
            "DESCRIBE": (f"Content-Base: {url}/\r\nContent-Type: application/sdp\r\n", SDP),
            "SETUP": ("Transport: RTP/AVP/TCP;unicast;interleaved=0-1\r\nSession: 1234\r\n", ""),
        }.get(method, ("Session: 1234\r\n", ""))
        conn.sendall((f"RTSP/1.0 200 OK\r\nCSeq: {headers.get('cseq', '0')}\r\n{extra}"
                      f"Content-Length: {len(body)}\r\n\r\n{body}").encode())
        if method == "PLAY":
            self._play(conn)
            return True
        return method == "TEARDOWN"

    def _play(self, conn):
        for channel, packet in self.packets[:self.upto]:
            conn.sendall(struct.pack(">cBH", b"$", channel, len(packet)) + packet)

    def close(self):
        self.done.set()
        self.sock.close()


@pytest.fixture
def serve(rtsp_clip):
    servers = []

    def start(**kw):
        servers.append(_RTSPServer(rtsp_clip[1], **kw))
        return servers[-1]

    yield start
    for server in servers:
        server.close()


def _lines(path):
    return jsonl_results(path.read_text())


def test_rtsp_gives_the_results_of_the_file(rtsp_clip, serve, tmp_path, capsys):
    """Every frame (``--no-live``: the run reads each, the server waits on TCP): the same JSON
    lines, timestamps from RTP included, and the same targets.csv as the file."""
    clip, _ = rtsp_clip
    server = serve()
    common = ["--every-frame", "-q", "--decoder", "pyav"]
    assert main(["run", str(clip), "-o", str(tmp_path / "f"), "--jsonl", str(tmp_path / "f.jsonl"), *common]) == 0
    assert main(["run", server.url, "--no-live", "-o", str(tmp_path / "r"), "--jsonl", str(tmp_path / "r.jsonl"),
                 *common]) == 0
    assert server.methods[:4] == ["OPTIONS", "DESCRIBE", "SETUP", "PLAY"]
    from_file = _lines(tmp_path / "f.jsonl")
    assert len(from_file) == 60 and any(line["warning"] for line in from_file)
    assert _lines(tmp_path / "r.jsonl") == from_file
    assert (tmp_path / "r" / "targets.csv").read_text() == (tmp_path / "f" / "targets.csv").read_text()
    summary = json.loads((tmp_path / "r" / "fields.json").read_text())
    assert summary["n_frames"] == 60 and summary["frames_skipped"] == 0


def test_a_live_rtsp_stream_faster_than_its_consumer_skips_to_the_newest_frame(serve):
    """The server sends all 60 frames at once; a consumer taking 20 ms a line gets the newest
    frame each time, and the frames in between are counted as skipped. The server then ends the stream, which
    ``stream`` says as ``run`` does (a camera that went away)."""
    server = serve()
    src = mlplc2.io.open_source(server.url)
    lines = []
    with pytest.warns(TruncatedInputWarning, match=r"the stream stopped after 60 frames"):
        for line in mlplc2.stream(src, "mlplc2", repeat_threshold=None):
            lines.append(line)
            time.sleep(0.02)
    frames = [line["frame"] for line in lines]
    skipped = [line["skipped"] for line in lines]
    assert frames[-1] == 59 and len(frames) + sum(skipped) == 60 and sum(skipped) > 0
    assert all(b - a - 1 == s for a, b, s in zip(frames, frames[1:], skipped[1:]))
    assert src.live and src.n_skipped == sum(skipped)
    assert src.dropped and "the stream stopped after 60 frames (the server ended it)" in src.message
    assert np.allclose([line["time_s"] for line in lines], [round(f / 30, 3) for f in frames], atol=1e-6)


def test_a_live_rtsp_stream_opened_early_starts_at_its_newest_frame(serve):
    """While the caller builds its models the stream runs on (here: the whole clip arrives); the
    first frame given is then the newest, not one buffered meanwhile, the others counted."""
    src = mlplc2.io.open_source(serve().url)
    time.sleep(1.0)                       # the models being built
    with src:
        items = [(index, src.skipped) for index, _ in src]
    first, skipped = items[0]
    assert first > 30 and skipped == first
    assert items[-1][0] == 59 and src.n_skipped + len(items) == 60


@pytest.mark.parametrize("stall", [False, True], ids=["closed", "stalled"])
def test_an_rtsp_stream_that_stops_ends_the_run_keeping_what_was_written(rtsp_clip, serve, tmp_path, capsys,
                                                                         monkeypatch, stall):
    """The server stops after about half the clip: it closes the connection, or keeps it open and
    sends nothing (a camera that hangs; the wait for data shortened to 1 s here)."""
    monkeypatch.setattr(decoders._PyAVDecoder, "TIMEOUT_S", 1.0)
    server = serve(upto=len(rtsp_clip[1]) // 2, stall=stall)
    code = main(["run", server.url, "--no-live", "-o", str(tmp_path / "o"), "--jsonl", str(tmp_path / "o.jsonl"),
                 "-q"])
    err = capsys.readouterr().err
    assert code == 0
    assert len(err.strip().splitlines()) == 1 and "the stream stopped after" in err and "Traceback" not in err
    summary = json.loads((tmp_path / "o" / "fields.json").read_text())
    n = summary["n_frames"]
    assert 20 < n < 40 and summary["dropped"] and not summary["complete"]
    assert [line["frame"] for line in _lines(tmp_path / "o.jsonl")] == list(range(n))
