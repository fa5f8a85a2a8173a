"""Does the first target warning depend on how a clip was encoded or scaled? (a measurement, not a test)

For every labelled real clip (``../shared/data/real``) and the paper's UAV clips (``../shared/data/paper/uav``)
this makes copies with PyAV (no ffmpeg binary needed; ``x264_copy.py``, each in a process of its own, one
encoder thread: the same bytes at every call) and keeps them in ``--cache`` (default
``~/.cache/mlplc2/encoding_copies``), named by the source's SHA-256 and the settings, so that two runs measure the
same files:

``orig``      the clip as it is;
``x264``      re-encoded with libx264, CRF 20, at its own size;
``320x240``   scaled to 320x240 (``cv2.INTER_AREA``; the aspect ratio may change), libx264 CRF 20;
``2x``        scaled to twice its size (``cv2.INTER_LINEAR``), libx264 CRF 20 (skipped above 960 px wide:
              minutes of encoding on two cores);

runs the models (default ``mlplc2`` and ``flow``) on each with ``mlplc2.run`` (defaults: ``repeat_threshold="auto"``,
``work_width=320``) and prints, per clip, copy and model, the first warning frame, the warning target's position
(in the clip's native pixels) and whether it lies on the colliding object (within 20 px of its labelled box,
``evaluation.match.on_object``), the frames mLPLC2 held as repeats and each file's SHA-256, then per clip and model
where the field of the first alarm lies (native px) and when it was born, where each copy's run first parts from the
original's (the first field born elsewhere, the first frame whose target boxes differ: ``parting``), how far apart
the first warnings lie and whether issue 22's item 7 holds (every copy warns first within 2 frames of
the others, on the colliding object; on a clip without a collision no copy warns). (A ``320x240`` copy of a clip
that is 320x240 already is an x264 copy too.) ``*_fullres`` clips are scored against the labels of their 320x240
version, scaled.

    python benchmarks/encoding_invariance.py [--data ../shared/data] [--clip helmet] [--model mlplc2] [--json out.json]
        [--cache DIR]

With ``--hfov 45,60,78,90,120`` it measures the field of view instead of the encoding: each clip as it is (the
``*_fullres`` copies left out) run with ``hfov_deg`` at each value (``none``: not given, 60 degrees assumed), and
prints per clip and value the first warning frame, its position and whether it lies on the colliding object, the
first field alarm, then one line per clip and model: ``first warning by field of view`` (the clip's contact frame
in brackets). Default model there: ``mlplc2`` alone. (Session 18: 9 clips x 6 values, 184 s on two cores at a load of ~12.)

    python benchmarks/encoding_invariance.py --hfov none,45,60,78,90,120 [--clip ...] [--model ...] [--json out.json]

With ``--heading centre`` it measures a given heading the same way: each clip as it is, with the heading estimated
(``none``) and with the frame's centre given as the heading (``centre``: ``target_params={"heading": ...}``, as
``mlplc2 run --heading`` gives it, what docs/cli.md advises for a camera that drives along its optical axis).

    python benchmarks/encoding_invariance.py --heading centre [--clip ...] [--model ...] [--json out.json]

The first run writes the copies (411 s for all of them and mLPLC2 on two cores at a load of about 20); later runs
reuse them (305 s at a load of 25; the model runs took ~65 s on a quiet machine in session 10).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import av

import mlplc2
from mlplc2.evaluation.match import on_object
from mlplc2.evaluation.truth import load

COPIES = ("orig", "x264", "320x240", "2x")
MAX_2X_WIDTH = 960
CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "mlplc2" / "encoding_copies"
WRITER = Path(__file__).resolve().with_name("x264_copy.py")
sys.path.insert(0, str(WRITER.parent))
from x264_copy import OPTIONS  # noqa: E402  (the writer's settings, part of the cache key)


def clips(data: Path) -> list[tuple[Path, str]]:
    """(video, ground-truth key) of every clip measured; the key of a ``*_fullres`` clip is its small version's."""
    out = []
    for p in sorted((data / "real").glob("*")) + sorted((data / "paper" / "uav").glob("*")):
        if p.suffix not in (".avi", ".mp4"):
            continue
        key = p.name.replace("_fullres.mp4", ".avi")
        out.append((p, f"uav/{key}" if p.parent.name == "uav" else key))
    return out


def measured(data: Path, names: list[str]):
    """(video, key, truth, native, size) of each clip of :func:`clips` whose name holds one of ``names``
    (all when empty): its labels (None without), the size its labels are in (its own without) and its own size."""
    real = load(data / "real" / "ground_truth.json")
    for video, key in clips(data):
        if names and not any(c in video.name for c in names):
            continue
        truth = real.get(key)
        with av.open(str(video)) as c:
            size = (c.streams.video[0].width, c.streams.video[0].height)
        yield video, key, truth, (tuple(truth.size) if truth is not None and truth.size else size), size


def sha256(path: Path) -> str:
    """The file's SHA-256, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def cached_copy(src: Path, src_sha: str, copy: str, size: tuple[int, int] | None, cache: Path,
                crf: int = 20) -> Path:
    """The ``copy`` of ``src`` (re-encoded with libx264, CRF ``crf``, resized to ``size`` first when given), from
    ``cache`` when it holds one of the same source bytes and settings, else written there by
    ``x264_copy.py`` in a process of its own (libx264 through PyAV is not repeatable within a process that
    has run a model; a fresh one gives the same bytes every time: docs/history.md, "Encoding and size")."""
    settings = json.dumps({"size": size, "crf": crf, **OPTIONS, "av": av.__version__}, sort_keys=True)
    key = hashlib.sha256(f"{src_sha} {settings}".encode()).hexdigest()[:16]
    dst = cache / f"{src.stem}_{copy}_{key}.mp4"
    if not dst.exists():
        cache.mkdir(parents=True, exist_ok=True)
        part = dst.with_suffix(f".{os.getpid()}.part.mp4")
        cmd = [sys.executable, str(WRITER), str(src), str(part), "--crf", str(crf)]
        if size is not None:
            cmd += ["--size", f"{size[0]}x{size[1]}"]
        try:
            subprocess.run(cmd, check=True)
            part.replace(dst)
        finally:
            part.unlink(missing_ok=True)
    return dst


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


def measure(video: Path, truth, native: tuple[int, int], models: list[str],
            hfov_deg: float | None = None, target_params: dict | None = None) -> dict[str, dict]:
    """Per model: first warning frame, position in the labels' pixels, on the collider or not; and the
    indices of the frames held as repeats. ``hfov_deg``: the run's field of view (None: not given);
    ``target_params``: the run's (None: the defaults)."""
    with av.open(str(video)) as c:
        fps = float(c.streams.video[0].average_rate or 30)
    probe = _HeldFrames(fps=fps)
    res = mlplc2.run(str(video), [*models, probe], out=False, quiet=True, progress=False, plot=False,
                     hfov_deg=hfov_deg, target_params=target_params)
    sx, sy = native[0] / res.size[0], native[1] / res.size[1]
    nat = lambda x, y: ((x + 0.5) * sx - 0.5, (y + 0.5) * sy - 0.5)  # noqa: E731
    out = {}
    for m in models:
        fields = res.fields.get(m, [])
        alarmed = [f for f in fields if f.get("first_alarm_frame") is not None]
        alarm_field = min(alarmed, key=lambda f: f["first_alarm_frame"]) if alarmed else None
        boxes: dict[int, list] = {}
        for r in res.targets:
            if r["model"] == m:
                boxes.setdefault(r["frame"], []).append((*nat(r["x"], r["y"]), r["width"] * sx, r["height"] * sy))
        out[m] = {"frame": None, "held": res.repeated.get(m, 0), "duplicated": res.duplicated,
                  "held_frames": probe.held, "alarm": res.alarms.get(m, {}).get("first"),
                  "alarm_field": None if alarm_field is None else
                  [*(round(v) for v in nat(alarm_field["x"], alarm_field["y"])), alarm_field["born"]],
                  "_births": sorted((f["born"], *nat(f["x"], f["y"])) for f in fields),
                  "_boxes": {k: sorted(v) for k, v in boxes.items()}}
        row = first_warning(res, m)
        if row is not None:
            x, y = nat(row["x"], row["y"])
            col = truth.collider if truth is not None else None
            on = None if col is None or not col.track else bool(on_object(x, y, col, row["frame"]))
            out[m].update(frame=row["frame"], x=round(x), y=round(y), on=on)
    return out


def parting(a: dict, b: dict, unit: float) -> str:
    """Where run ``b`` of a copy first parts from run ``a`` of the original (``measure``'s rows of one model;
    ``unit``: native px per working px): the first field born elsewhere (more than 4 working px) or not
    at all, and the first frame whose target boxes differ in number or by more than 6 working px."""
    fa, fb = a["_births"], b["_births"]
    born = next((min(p[0], q[0]) for p, q in zip(fa, fb)
                 if p[0] != q[0] or max(abs(p[1] - q[1]), abs(p[2] - q[2])) > 4 * unit), None)
    if born is None and len(fa) != len(fb):              # one has a field more
        born = max(fa, fb, key=len)[min(len(fa), len(fb))][0]
    ta, tb = a["_boxes"], b["_boxes"]
    boxes = next((k for k in sorted(set(ta) | set(tb)) if len(ta.get(k, ())) != len(tb.get(k, ()))
                  or any(max(abs(u - v) for u, v in zip(p, q)) > 6 * unit for p, q in zip(ta[k], tb[k]))), None)
    return f"fields part at {born if born is not None else '-'}, targets at {boxes if boxes is not None else '-'}"


def held_diff(a: list[int], b: list[int]) -> str:
    """The frames held in one list and not the other (``-k``: only in ``a``, ``+k``: only in ``b``)."""
    sa, sb = set(a), set(b)
    return " ".join([f"-{k}" for k in sorted(sa - sb)] + [f"+{k}" for k in sorted(sb - sa)]) or "same frames"


def verdict(rows: list[dict], collision: bool) -> str:
    """Issue 22 item 7 on one clip and model: every copy warns first within 2 frames of the others, on the
    colliding object (a clip without a collision: no copy warns)."""
    got = [r["frame"] for r in rows if r["frame"] is not None]
    if not got:
        what = "never warns on any copy"
    elif len(got) < len(rows):
        what = f"warns on {len(got)} of {len(rows)} copies"
    else:
        what = f"first warnings within {max(got) - min(got)} frames"
    met = (not got) if not collision else (
        len(got) == len(rows) and max(got) - min(got) <= 2 and all(r["on"] for r in rows))
    return f"{what}; item 7 {'met' if met else 'NOT met'}"


def fmt(r: dict) -> str:
    if r["frame"] is None:
        return "never"
    on = {True: "on", False: "OFF", None: "-"}[r["on"]]
    return f"{r['frame']:>3} ({r['x']:>4},{r['y']:>4}) {on}"


def hfov_values(text: str) -> list[float | None]:
    """``--hfov``'s comma-separated degrees (``none``: not given)."""
    return [None if v.strip().lower() == "none" else float(v) for v in text.split(",") if v.strip()]


def by_setting(data: Path, names: list[str], models: list[str], settings: dict, what: str) -> dict:
    """The first warning of each clip as it is (no ``*_fullres`` copy) under each of ``settings`` (a label -> a
    function of the clip's size (w, h) giving :func:`measure`'s keywords); ``what``: the settings' name."""
    table = {}
    for video, key, truth, native, size in measured(data, names):
        if "_fullres" in video.name:
            continue
        rows = {}
        for name, kwargs in settings.items():
            rows[name] = r = measure(video, truth, native, models, **kwargs(size))
            for m in models:
                r[m].pop("_births"), r[m].pop("_boxes"), r[m].pop("held_frames")
            print(f"{video.name:34s} {what} {name:6s} " + "  ".join(f"{m}: {fmt(r[m]):24s}" for m in models)
                  + f" first alarm {r[models[0]]['alarm']}", flush=True)
        col = truth.collider if truth is not None and truth.label == "collision" else None
        if col is not None and getattr(col, "contact_frame", None) is not None:
            contact = f" (contact {col.contact_frame:g})"
        else:
            contact = " (no collision)" if truth is not None and truth.label != "collision" else ""
        for m in models:
            false = truth is not None and truth.label != "collision"       # any warning there is false
            seq = ", ".join(f"{k}->{'none' if r[m]['frame'] is None else r[m]['frame']}"
                            + ("" if r[m]["frame"] is None or (r[m]["on"] in (None, True) and not false)
                               else " (false)" if false else " OFF")
                            for k, r in rows.items())
            print(f"{'':34s} {m}: first warning by {what}{contact}: {seq}", flush=True)
        table[video.name] = rows
    return table


def hfov_settings(values: list[float | None]) -> dict:
    """``--hfov``'s values as :func:`by_setting`'s settings."""
    return {"none" if v is None else f"{v:g}": (lambda size, v=v: {"hfov_deg": v}) for v in values}


#: ``--heading centre``: each clip without a heading (estimated) and with the frame's centre given as the heading
#: (a camera that drives along its optical axis: docs/cli.md, ``--heading``)
HEADING_SETTINGS = {"none": lambda size: {},
                    "centre": lambda size: {"target_params": {"heading": ((size[0] - 1) / 2.0, (size[1] - 1) / 2.0)}}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[1] / ".." / "shared" / "data")
    ap.add_argument("--clip", action="append", default=[], help="only clips whose name contains this (repeatable)")
    ap.add_argument("--model", action="append", default=[], help="models (default mlplc2 and flow)")
    ap.add_argument("--copy", action="append", default=[], choices=COPIES, help="only these copies (repeatable)")
    ap.add_argument("--json", type=Path, help="also write the table as JSON")
    ap.add_argument("--cache", type=Path, default=CACHE,
                    help=f"where the copies are kept, named by source checksum and settings (default {CACHE})")
    what = ap.add_mutually_exclusive_group()
    what.add_argument("--hfov", type=hfov_values, metavar="DEG,DEG,...",
                      help="measure the field of view instead: each clip as it is at these values (none: not given)")
    what.add_argument("--heading", choices=["centre"],
                      help="measure a given heading instead: each clip as it is without one and with the frame's "
                           "centre given")
    args = ap.parse_args(argv)
    if args.hfov or args.heading:
        settings = hfov_settings(args.hfov) if args.hfov else HEADING_SETTINGS
        table = by_setting(args.data, args.clip, args.model or ["mlplc2"], settings,
                           "field of view" if args.hfov else "heading")
        if args.json:
            args.json.write_text(json.dumps(table, indent=1))
        return 0
    models = args.model or ["mlplc2", "flow"]
    copies = args.copy or list(COPIES)
    table = {}
    for video, key, truth, native, size in measured(args.data, args.clip):
        src_sha = sha256(video)
        rows = {}
        for copy in copies:
            if copy == "2x" and size[0] > MAX_2X_WIDTH:
                continue
            target = {"orig": None, "x264": None, "320x240": (320, 240), "2x": (2 * size[0], 2 * size[1])}[copy]
            path = video if copy == "orig" else cached_copy(video, src_sha, copy, target, args.cache)
            rows[copy] = measure(path, truth, native, models)
            rows[copy]["sha256"] = src_sha if copy == "orig" else sha256(path)
            print(f"{video.name:34s} {copy:8s} " + "  ".join(f"{m}: {fmt(rows[copy][m]):24s}" for m in models)
                  + f" held {rows[copy][models[0]]['held']}, first alarm {rows[copy][models[0]]['alarm']},"
                  f" sha256 {rows[copy]['sha256'][:16]}", flush=True)
        first = next(iter(rows.values()))
        ref = first[models[0]]["held_frames"]
        for copy, r in rows.items():
            print(f"{'':34s} held ({copy}): " + (held_diff(ref, r[models[0]]["held_frames"]) if copy != "orig"
                                                 else " ".join(map(str, ref)) or "none"), flush=True)
        for m in models:
            for copy, r in rows.items():
                print(f"{'':34s} {m} ({copy}): first alarm's field at {r[m]['alarm_field'] or '-'} (x, y, born)"
                      + ("" if r is first else "; " + parting(first[m], r[m], native[0] / 320)), flush=True)
        for r in rows.values():
            for m in models:
                r[m].pop("_births"), r[m].pop("_boxes")
        collision = truth is not None and truth.label == "collision"
        for m in models:
            print(f"{'':34s} {m}: {verdict([r[m] for k, r in rows.items()], collision)}", flush=True)
        table[video.name] = rows
    if args.json:
        args.json.write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
