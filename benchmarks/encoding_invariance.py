"""Does the first target warning depend on how a clip was encoded or scaled? (a measurement, not a test)

For every labelled real clip (``../shared/data/real``) and the paper's UAV clips (``../shared/data/paper/uav``)
this writes copies into a temporary folder with PyAV (no ffmpeg binary needed):

``orig``      the clip as it is;
``x264``      re-encoded with libx264, CRF 20, at its own size;
``320x240``   scaled to 320x240 (``cv2.INTER_AREA``; the aspect ratio may change), libx264 CRF 20;
``2x``        scaled to twice its size (``cv2.INTER_LINEAR``), libx264 CRF 20 (skipped above 960 px wide:
              minutes of encoding on two cores);

runs the models (default ``mlplc2`` and ``flow``) on each with ``mlplc2.run`` (defaults: ``repeat_threshold="auto"``,
``work_width=320``) and prints, per clip, copy and model, the first warning frame, the warning target's position
(in the clip's native pixels) and whether it lies on the colliding object (within 20 px of its labelled box,
``evaluation.match.on_object``) and the frames mLPLC2 held as repeats, then per clip and model how far apart the
first warnings lie. (A ``320x240`` copy of a clip that is 320x240 already is an x264 copy too.) ``*_fullres`` clips are scored
against the labels of their 320x240 version, scaled.

    python benchmarks/encoding_invariance.py [--data ../shared/data] [--clip helmet] [--model mlplc2] [--json out.json]

Takes some minutes on two cores (the x264 encodes of the full-resolution clips dominate).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import av
import cv2
import numpy as np

import mlplc2
from mlplc2.evaluation.match import on_object
from mlplc2.evaluation.truth import load

COPIES = ("orig", "x264", "320x240", "2x")
MAX_2X_WIDTH = 960


def clips(data: Path) -> list[tuple[Path, str]]:
    """(video, ground-truth key) of every clip measured; the key of a ``*_fullres`` clip is its small version's."""
    out = []
    for p in sorted((data / "real").glob("*")) + sorted((data / "paper" / "uav").glob("*")):
        if p.suffix not in (".avi", ".mp4"):
            continue
        key = p.name.replace("_fullres.mp4", ".avi")
        out.append((p, f"uav/{key}" if p.parent.name == "uav" else key))
    return out


def write_copy(src: Path, dst: Path, size: tuple[int, int] | None, crf: int = 20) -> tuple[int, int]:
    """``src`` re-encoded with libx264 (CRF ``crf``, yuv420p, the same frame rate) into ``dst``, each frame
    resized to ``size`` (W, H) first when given; returns the copy's size."""
    with av.open(str(src)) as inp:
        vs = inp.streams.video[0]
        rate = vs.average_rate or 30
        with av.open(str(dst), "w") as out:
            os_ = None
            for frame in inp.decode(vs):
                img = frame.to_ndarray(format="rgb24")
                if size is not None:
                    interp = cv2.INTER_AREA if size[0] < img.shape[1] else cv2.INTER_LINEAR
                    img = cv2.resize(img, size, interpolation=interp)
                if os_ is None:
                    os_ = out.add_stream("libx264", rate=rate)
                    os_.width, os_.height = img.shape[1], img.shape[0]
                    os_.pix_fmt = "yuv420p"
                    os_.options = {"crf": str(crf), "preset": "veryfast"}
                for pkt in os_.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="rgb24")):
                    out.mux(pkt)
            for pkt in os_.encode():
                out.mux(pkt)
            return os_.width, os_.height


def first_warning(result, model: str) -> dict | None:
    """The first ``targets.csv`` row of ``model`` with its warning set (the warning target), or None."""
    rows = [r for r in result.targets if r["model"] == model and r["warning"]]
    return min(rows, key=lambda r: r["frame"]) if rows else None


class _HeldFrames(mlplc2.LGMD2):
    """A cheap model that records which frames it held as repeats (``Output.repeated``): the decision
    is the base class's, the same for every model of the run (``mlplc2.run`` primes them alike)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.held: list[int] = []

    def step(self, frame, t=None):
        out = super().step(frame, t)
        if out.repeated:
            self.held.append(out.frame)
        return out


def measure(video: Path, truth, native: tuple[int, int], models: list[str]) -> dict[str, dict]:
    """Per model: first warning frame, position in the labels' pixels, on the collider or not; and the
    indices of the frames held as repeats."""
    with av.open(str(video)) as c:
        fps = float(c.streams.video[0].average_rate or 30)
    probe = _HeldFrames(fps=fps)
    res = mlplc2.run(str(video), [*models, probe], out=False, quiet=True, progress=False, plot=False)
    sx, sy = native[0] / res.size[0], native[1] / res.size[1]
    out = {}
    for m in models:
        row = first_warning(res, m)
        if row is None:
            out[m] = {"frame": None, "held": res.repeated.get(m, 0), "duplicated": res.duplicated,
                      "held_frames": probe.held, "alarm": res.alarms.get(m, {}).get("first")}
            continue
        x, y = (row["x"] + 0.5) * sx - 0.5, (row["y"] + 0.5) * sy - 0.5
        col = truth.collider if truth is not None else None
        on = None if col is None or not col.track else bool(on_object(x, y, col, row["frame"]))
        out[m] = {"frame": row["frame"], "x": round(x), "y": round(y), "on": on,
                  "held": res.repeated.get(m, 0), "duplicated": res.duplicated, "held_frames": probe.held,
                  "alarm": res.alarms.get(m, {}).get("first")}
    return out


def held_diff(a: list[int], b: list[int]) -> str:
    """The frames held in one list and not the other (``-k``: only in ``a``, ``+k``: only in ``b``)."""
    sa, sb = set(a), set(b)
    return " ".join([f"-{k}" for k in sorted(sa - sb)] + [f"+{k}" for k in sorted(sb - sa)]) or "same frames"


def fmt(r: dict) -> str:
    if r["frame"] is None:
        return "never"
    on = {True: "on", False: "OFF", None: "-"}[r["on"]]
    return f"{r['frame']:>3} ({r['x']:>4},{r['y']:>4}) {on}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[1] / ".." / "shared" / "data")
    ap.add_argument("--clip", action="append", default=[], help="only clips whose name contains this (repeatable)")
    ap.add_argument("--model", action="append", default=[], help="models (default mlplc2 and flow)")
    ap.add_argument("--copy", action="append", default=[], choices=COPIES, help="only these copies (repeatable)")
    ap.add_argument("--json", type=Path, help="also write the table as JSON")
    args = ap.parse_args(argv)
    models = args.model or ["mlplc2", "flow"]
    copies = args.copy or list(COPIES)
    real = load(args.data / "real" / "ground_truth.json")
    table = {}
    with tempfile.TemporaryDirectory(prefix="mlplc2_enc_") as tmp:
        for video, key in clips(args.data):
            if args.clip and not any(c in video.name for c in args.clip):
                continue
            truth = real.get(key)
            with av.open(str(video)) as c:
                size = (c.streams.video[0].width, c.streams.video[0].height)
            native = tuple(truth.size) if truth is not None and truth.size else size
            rows = {}
            for copy in copies:
                if copy == "orig":
                    path = video
                else:
                    if copy == "2x" and size[0] > MAX_2X_WIDTH:
                        continue
                    target = {"x264": None, "320x240": (320, 240), "2x": (2 * size[0], 2 * size[1])}[copy]
                    path = Path(tmp) / f"{video.stem}_{copy}.mp4"
                    write_copy(video, path, target)
                rows[copy] = measure(path, truth, native, models)
                print(f"{video.name:34s} {copy:8s} " + "  ".join(f"{m}: {fmt(rows[copy][m]):24s}" for m in models)
                      + f" held {rows[copy][models[0]]['held']}, first alarm {rows[copy][models[0]]['alarm']}",
                      flush=True)
            ref = next(iter(rows.values()))[models[0]]["held_frames"]
            for copy, r in rows.items():
                print(f"{'':34s} held ({copy}): " + (held_diff(ref, r[models[0]]["held_frames"]) if copy != "orig"
                                                     else " ".join(map(str, ref)) or "none"), flush=True)
            for m in models:
                frames = [r[m]["frame"] for r in rows.values()]
                got = [f for f in frames if f is not None]
                if not got:
                    what = "never warns on any copy"
                elif len(got) < len(frames):
                    what = f"warns on {len(got)} of {len(frames)} copies"
                else:
                    what = f"first warnings within {max(got) - min(got)} frames"
                print(f"{'':34s} {m}: {what}", flush=True)
            table[video.name] = rows
    if args.json:
        args.json.write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
