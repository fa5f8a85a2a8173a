"""A live RTSP stream faster than the models: the delay from a frame's arrival to its JSON line.

The RTSP server of tests/test_rtsp.py (on 127.0.0.1, RTP interleaved over TCP) sends a 320x240
MJPEG clip (a square looming on noise) one frame every ``--period-ms``; ``mlplc2.stream`` reads
it (live unless ``--no-live``) with the ``--models``. The delay of a line is the time from the
server's sending of its frame's last packet to the line; printed as one JSON object: its
median, 99th percentile and maximum (the first line left out), its maximum in each quarter of
the run (bounded: the later quarters stay near a few of the models' steps; growing: the frames
queue up), the lines, the frames skipped and the models' median time per line.

    PYTHONPATH=src python benchmarks/rtsp_live_delay.py --frames 600 --period-ms 16.7 \\
        --models mlplc2,lplc2,slplc2,flow [--no-live]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import struct
import tempfile
import time
from pathlib import Path

import numpy as np

import mlplc2

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("test_rtsp", HERE.parent / "tests" / "test_rtsp.py")
T = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(T)


def frames(n, w=320, h=240):
    bg = np.random.default_rng(0).integers(60, 200, (h, w), dtype=np.uint8)
    for i in range(n):
        f = bg.copy()
        r = 4 + (i * 100) // n
        f[h // 2 - r:h // 2 + r, w // 2 - r:w // 2 + r] = 0
        yield np.repeat(f[:, :, None], 3, 2)


class PacedServer(T._RTSPServer):
    """Sends frame k at ``k * period`` after PLAY; ``sent[k]``: when its last packet was sent."""

    period = 1 / 30

    def _play(self, conn):
        self.sent, k, last_ts, t0 = [], -1, None, time.perf_counter()
        for channel, packet in self.packets:
            if channel == 0 and (ts := struct.unpack(">I", packet[4:8])[0]) != last_ts:  # a new frame
                if k >= 0:
                    self.sent.append(time.perf_counter())
                k, last_ts = k + 1, ts
                time.sleep(max(0.0, t0 + k * self.period - time.perf_counter()))
            conn.sendall(struct.pack(">cBH", b"$", channel, len(packet)) + packet)
        self.sent.append(time.perf_counter())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--period-ms", type=float, default=1000 / 30)
    ap.add_argument("--models", default="mlplc2")
    ap.add_argument("--no-live", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        clip = Path(tmp) / "clip.mkv"
        T._write_mjpeg(clip, frames(args.frames), 30)
        packets = T._rtp_packets(clip)
    server = PacedServer(packets)
    server.period = args.period_ms / 1000
    src = mlplc2.io.open_source(server.url, live=not args.no_live)
    delays, steps, last = [], [], None
    for line in mlplc2.stream(src, args.models.split(",")):
        now = time.perf_counter()
        while len(server.sent) <= line["frame"]:   # its send time is noted just after sending
            time.sleep(0.0005)
        delays.append(now - server.sent[line["frame"]])
        if last is not None:
            steps.append(now - last)
        last = now
    server.close()
    d = np.array(delays[1:]) * 1000
    q = len(d) // 4
    print(json.dumps({
        "frames": args.frames, "period_ms": args.period_ms, "live": not args.no_live, "models": args.models,
        "lines": len(delays), "skipped": src.n_skipped,
        "models_ms_per_line_median": round(float(np.median(steps)) * 1000, 1),
        "delay_ms": {"median": round(float(np.median(d)), 1), "p99": round(float(np.percentile(d, 99)), 1),
                     "max": round(float(d.max()), 1)},
        "delay_max_ms_by_quarter": [round(float(d[i * q:(i + 1) * q].max()), 1) for i in range(4)]}))


if __name__ == "__main__":
    main()
