"""How much does a difference nobody can see move the benchmark's figures? (a measurement, not a test)

The benchmark's scenes are written losslessly, so two runs of one version give the same table; but the same
scene seen by another copy of the same camera (another draw of the sensor's noise, a rounding to 8 bits that falls
the other way) is not the same file. ``make`` writes such a replicate of a benchmark's scene files: every frame
plus Gaussian noise of ``--sigma`` grey levels (default 0.5: about a third of the pixels change by one grey level,
below the scenes' own sensor noise of 2 grey levels), seeded by ``--seed`` and the file's name, rounded back to
``uint8`` and written losslessly (FFV1, as the benchmark writes them), with the same ``ground_truth.json``. The
benchmark reuses scene files it finds in its ``--out`` folder, so the replicate is run as the original was::

    python benchmarks/replicate.py make OUT REP --seed 1          # OUT: a benchmark's --out folder
    python -m mlplc2 benchmark --out REP -m mlplc2 --no-real [the original's --holdout / --settings / --hfov]
    python benchmarks/replicate.py compare OUT REP [OUT2 REP2 ...]

``compare`` reads the pairs' ``evaluation.json`` and prints, pooled over the pairs: the figures of each side (colliders
warned, lead median and 10th percentile, false episodes and frames, TTC coverage) and, per setting, the collision
objects whose first warning is the same (within ``--frames`` frames, default 2: issue 22's item 7) or which neither
run warns, those warned by one run only, the spread of the first warnings that moved, and the same count for the
paper's field alarm on each object (the layer the targets are built on: how steady a first decision of the model's own
front end is under the same noise). A design whose figures
differ from the original's by no more than a replicate's do is not shown better or worse by them
(docs/benchmark.md, "Replicates").
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shutil
import sys
from pathlib import Path

import numpy as np

from mlplc2._progress import bar
from mlplc2.io import read_video, write_lossless_video

GT = "ground_truth.json"


def seed_for(name: str, seed: int) -> int:
    """The noise generator's seed for the file ``name``: ``seed`` and the name, so that each file of a replicate
    gets its own draw and the same call the same one."""
    return int.from_bytes(hashlib.sha256(f"{seed}:{name}".encode()).digest()[:8], "little")


def dither(frames, sigma: float, seed: int):
    """Yield ``frames`` (grey ``uint8``) plus Gaussian noise of ``sigma`` grey levels, rounded and clipped to
    ``uint8``."""
    rng = np.random.default_rng(seed)
    for f in frames:
        noisy = f.astype(np.float32) + rng.normal(0.0, sigma, f.shape).astype(np.float32)
        yield np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def make(src: Path, dst: Path, seed: int, sigma: float, progress: bool = True) -> list[Path]:
    """Write the replicate of benchmark folder ``src``'s scene files into ``dst/scenes`` (see the module's text);
    returns the files written."""
    scenes = src / "scenes"
    if not (scenes / GT).is_file():
        raise SystemExit(f"{scenes}: no {GT} there (give a benchmark's --out folder)")
    videos = sorted(scenes.glob("*.mkv"))
    if not videos:
        raise SystemExit(f"{scenes}: no scene files (*.mkv) there")
    if sigma <= 0:
        raise SystemExit(f"--sigma must be above 0 (got {sigma})")
    if dst.resolve() == src.resolve():
        raise SystemExit(f"{dst}: the replicate would overwrite its original: give another folder")
    out = dst / "scenes"
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(scenes / GT, out / GT)
    written = []
    for v in bar(videos, desc="replicate", unit="scene", disable=not progress):
        frames, fps = read_video(v, decoder="pyav")      # grey scenes, decoded as RGB: one channel is the grey
        written.append(write_lossless_video(out / v.name, dither(frames[..., 0], sigma, seed_for(v.name, seed)), fps))
    return written


def _setting(video: str) -> str:
    """The setting of a benchmark scene's file name (``drive_3_h36_f90.mkv`` -> ``drive``)."""
    stem = video.rsplit(".", 1)[0].split("_h")[0]
    parts = stem.split("_")
    return "_".join(parts[:-1]) if parts[-1].isdigit() else stem


def _colliders(folder: Path) -> dict:
    e = json.loads((folder / "evaluation.json").read_text())
    return {(o["video"], o["object"]): o for o in e["warning_objects"] if o["model"] == "mlplc2"}


def stability(pairs: list[tuple[dict, dict]], frames: int = 2, key: str = "warning_frame") -> dict:
    """Per setting (and ``"all"``): ``n`` collision objects in both runs of a pair, ``same`` first warned within
    ``frames`` frames of each other or by neither run, ``one`` warned by one run only, ``moved`` the first warnings'
    differences (frames) beyond ``frames``, ``none`` neither run's. ``pairs``: (original, replicate) colliders as :func:`_colliders`.
    ``key``: the frame compared, the target warning's (``warning_frame``) or the paper's field alarm's on the object
    (``alarm_frame``, the layer the targets are built on); None: none in that run."""
    out: dict = {}
    for a, b in pairs:
        for name, o in a.items():
            p = b.get(name)
            if p is None:
                continue
            x, y = o.get(key), p.get(key)
            for s in (_setting(name[0]), "all"):
                r = out.setdefault(s, {"n": 0, "same": 0, "none": 0, "one": 0, "moved": []})
                r["n"] += 1
                if x is None and y is None:
                    r["same"] += 1
                    r["none"] += 1
                elif x is None or y is None:
                    r["one"] += 1
                elif abs(y - x) <= frames:
                    r["same"] += 1
                else:
                    r["moved"].append(y - x)
    return out


def figures(folders: list[Path]) -> dict:
    """The benchmark's figures pooled over ``folders`` (mLPLC2, generated scenes): warned, lead median and p10,
    false episodes and frames (and per 1000 / %), TTC coverage."""
    warned = n = fe = ff = fr = est = tf = 0
    leads = []
    for d in folders:
        e = json.loads((d / "evaluation.json").read_text())
        for o in e["warning_objects"]:
            if o["model"] != "mlplc2":
                continue
            n += 1
            if o["warned"]:
                warned += 1
                if o["lead_s"] is not None:
                    leads.append(o["lead_s"])
            est += o["ttc_estimated"] or 0
            tf += o["ttc_frames"] or 0
        for v in e["warning_videos"]:
            if v["model"] == "mlplc2":
                fe += v.get("false_episodes") or 0
                ff += v.get("false_frames") or 0
                fr += v.get("frames_scored") or 0
    return {"warned": warned, "n": n, "lead_median": float(np.median(leads)) if leads else None,
            "lead_p10": float(np.quantile(leads, 0.1)) if leads else None, "false_episodes": fe,
            "false_frames": ff, "frames": fr, "fe_per_1000": 1000 * fe / fr if fr else None,
            "ff_pct": 100 * ff / fr if fr else None, "coverage": est / tf if tf else None}


def _row(name: str, f: dict) -> str:
    def num(v, fmt):
        return "-" if v is None else format(v, fmt)
    return (f"| {name} | {f['warned']}/{f['n']} | {num(f['lead_median'], '.2f')} / {num(f['lead_p10'], '.2f')} | "
            f"{f['false_episodes']} ({num(f['fe_per_1000'], '.2f')}) | {f['false_frames']} ({num(f['ff_pct'], '.2f')} %) | "
            f"{num(None if f['coverage'] is None else 100 * f['coverage'], '.1f')} % |")


def compare(folders: list[Path], frames: int = 2) -> str:
    """The report of ``compare`` (Markdown) for ``folders`` = original, replicate, original, replicate, ..."""
    if len(folders) < 2 or len(folders) % 2:
        raise SystemExit("compare takes pairs: ORIGINAL REPLICATE [ORIGINAL REPLICATE ...]")
    for d in folders:
        if not (d / "evaluation.json").is_file():
            raise SystemExit(f"{d}: no evaluation.json there (run the benchmark into it first)")
    orig, rep = folders[0::2], folders[1::2]
    lines = ["| run | colliders warned | lead median / p10 (s) | false episodes (/1000 fr) | false frames | TTC coverage |",
             "|---|---|---|---|---|---|",
             _row("original", figures(orig)), _row("replicate", figures(rep)), "",
             f"| setting | collision objects | first warning the same (within {frames} frames, or none) | "
             f"warned by one run only | moved further: median, largest (frames) | the field alarm on it the same "
             f"(of those alarmed by either run) |",
             "|---|---|---|---|---|---|"]
    pairs = [(_colliders(a), _colliders(b)) for a, b in zip(orig, rep)]
    st, alarm = stability(pairs, frames), stability(pairs, frames, key="alarm_frame")
    for s in sorted(st, key=lambda k: (k == "all", k)):
        r, q = st[s], alarm[s]
        moved = np.abs(np.array(r["moved"])) if r["moved"] else None
        spread = "-" if moved is None else f"{len(moved)}: {np.median(moved):.0f}, {moved.max():.0f}"
        lines.append(f"| {'**all**' if s == 'all' else s} | {r['n']} | {r['same']} ({100 * r['same'] / r['n']:.0f} %) | "
                     f"{r['one']} | {spread} | {q['same']} ({100 * q['same'] / q['n']:.0f} %; "
                     f"{q['same'] - q['none']} of {q['n'] - q['none']}) |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("make", help="write a replicate of a benchmark folder's scene files")
    m.add_argument("src", type=Path, help="a benchmark's --out folder (its scenes/ are read)")
    m.add_argument("dst", type=Path, help="the replicate's folder (scenes/ written there)")
    m.add_argument("--seed", type=int, default=1, help="the noise's seed (default 1)")
    m.add_argument("--sigma", type=float, default=0.5, help="the noise, grey levels (default 0.5)")
    m.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    c = sub.add_parser("compare", help="figures and first warnings of original / replicate pairs")
    c.add_argument("folders", type=Path, nargs="+", metavar="ORIGINAL REPLICATE")
    c.add_argument("--frames", type=int, default=2, help="first warnings this close are the same (default 2)")
    args = ap.parse_args(argv)
    if args.cmd == "make":
        n = len(make(args.src, args.dst, args.seed, args.sigma, progress=not args.quiet))
        print(f"{n} scene files written to {args.dst / 'scenes'} (seed {args.seed}, sigma {args.sigma})")
    else:
        print(compare(args.folders, args.frames))
    return 0


if __name__ == "__main__":
    sys.exit(main())
