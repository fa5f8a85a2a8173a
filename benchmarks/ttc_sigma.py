"""How far can ``ttc_sigma_s`` be trusted? (a measurement, not a test)

Every target row whose time to contact was measured on that frame (``ttc_age_s`` 0) and whose box holds the
colliding object's centre is compared with the object's true time to contact: ``z = (ttc_s - true) / ttc_sigma_s``.
Were ``ttc_sigma_s`` the error's standard deviation, about 95 % of the rows would lie within 2 sigma.

``--real DIR``: the labelled real clips (``DIR/ground_truth.json``, ``"clips"``; the paper's UAV clips under
``DIR/../paper`` too): the true time to contact is ``(contact_frame - frame) / fps``, the centre the labelled track's,
interpolated; with ``--growth``, the time to contact of the labelled boxes' own expansion instead (their width over
its growth a second, across the 8 frames about the frame, interpolated between the labelled frames): a label's
contact is where the object touches the vehicle or fills the view, which comes before the contact with the camera's
plane that an expansion measures (``car_attack``: the car passes over the camera; ``night_rear_end``: it hits the
car's rear, behind the camera). ``--scenes DIR``: a benchmark's scene folder (``OUT/scenes`` of ``mlplc2 benchmark``, its
``ground_truth.json``, ``"videos"``): the renderer's exact ``ttc_s`` and centre of each collider, 0-3 s. Each video
is run as ``mlplc2.stream`` runs it (the defaults; ``--hfov`` given to every video of ``--scenes``).

    python benchmarks/ttc_sigma.py --real ../shared/data/real [--growth]
    python benchmarks/ttc_sigma.py --scenes bench/scenes [--hfov 90]

Prints per clip (``--real``) or per setting (``--scenes``): rows, median absolute error (s) and median relative
error, median ``ttc_sigma_s``, median ``|z|`` and the share within 2 sigma; then all of them pooled.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import mlplc2


def _rows(path: Path, truth, hfov: float | None) -> list[tuple[float, float, float]]:
    """(estimate, sigma, true) of every own-fit target row on the object: ``truth(frame)`` gives (x, y, ttc) or None."""
    out = []
    for line in mlplc2.stream(str(path), "mlplc2", hfov_deg=hfov):
        at = truth(line["frame"])
        if at is None:
            continue
        x, y, true = at
        for t in line["targets"]:
            if t["ttc_s"] is None or t["ttc_age_s"] != 0.0 or not t["ttc_sigma_s"]:
                continue
            if abs(t["x"] - x) <= t["width"] / 2 and abs(t["y"] - y) <= t["height"] / 2:
                out.append((t["ttc_s"], t["ttc_sigma_s"], true))
    return out


def _real(root: Path, growth: bool = False):
    clips = json.loads((root / "ground_truth.json").read_text())["clips"]
    for key, v in clips.items():
        if v["label"] != "collision":
            continue
        path = next((p for p in (root / key, root.parent / "paper" / key) if p.exists()), None)
        if path is None:
            continue
        fps, contact = v["fps"], v["contact_frame"]
        track = np.asarray(v["track"], float)

        def truth(f, track=track, fps=fps, contact=contact):
            if f >= contact or not track[0, 0] <= f <= track[-1, 0]:
                return None
            x, y = float(np.interp(f, track[:, 0], track[:, 1])), float(np.interp(f, track[:, 0], track[:, 2]))
            if not growth:
                return x, y, (contact - f) / fps
            if not (track[0, 0] <= f - GROWTH_SPAN / 2 and f + GROWTH_SPAN / 2 <= track[-1, 0]):
                return None
            w0, w, w1 = (float(np.interp(g, track[:, 0], track[:, 3])) for g in (f - GROWTH_SPAN / 2, f, f + GROWTH_SPAN / 2))
            return (x, y, w * GROWTH_SPAN / fps / (w1 - w0)) if w1 > w0 else None
        yield key, path, truth


#: ``--growth``: the frames across which a labelled box's expansion is measured
GROWTH_SPAN = 8


def _scenes(root: Path):
    videos = json.loads((root / "ground_truth.json").read_text())["videos"]
    for name, v in sorted(videos.items()):
        tracks = []
        for o in v["objects"]:
            if o["kind"] == "collision":
                cols = o["track_columns"]
                tracks.append({int(r[0]): dict(zip(cols, r)) for r in o["track"]})
        if not tracks:
            continue

        def truth(f, tracks=tracks):
            for tr in tracks:       # the first collider alive at f whose time to contact is 0-3 s
                r = tr.get(f)
                if r is not None and r.get("ttc_s") is not None and 0 < r["ttc_s"] <= 3:
                    return r["x"], r["y"], r["ttc_s"]
            return None
        yield name.split("_")[0], root / name, truth


def _line(label: str, rows) -> str:
    a = np.asarray(rows, float)
    err = np.abs(a[:, 0] - a[:, 2])
    z = (a[:, 0] - a[:, 2]) / a[:, 1]
    return (f"{label:32s} rows {len(a):5d}  median error {np.median(err):.3f} s ({np.median(err / a[:, 2]):.1%})  "
            f"median sigma {np.median(a[:, 1]):.3f} s  median |z| {np.median(np.abs(z)):.1f}  "
            f"within 2 sigma {np.mean(np.abs(z) <= 2):.0%}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--real", type=Path, help="the labelled real clips' folder (../shared/data/real)")
    ap.add_argument("--scenes", type=Path, help="a benchmark's scene folder (OUT/scenes)")
    ap.add_argument("--hfov", type=float, default=None, help="field of view given with --scenes (degrees)")
    ap.add_argument("--growth", action="store_true",
                    help="with --real: the labelled boxes' expansion as the truth, not the labelled contact")
    args = ap.parse_args(argv)
    if (args.real is None) == (args.scenes is None):
        ap.error("give one of --real DIR and --scenes DIR")
    if args.growth and args.real is None:
        ap.error("--growth goes with --real")
    source = _real(args.real, args.growth) if args.real else _scenes(args.scenes)
    groups: dict[str, list] = {}
    for label, path, truth in source:
        groups.setdefault(label, []).extend(_rows(path, truth, None if args.real else args.hfov))
    for label, rows in groups.items():
        if rows:
            print(_line(label, rows))
    pooled = [r for rows in groups.values() for r in rows]
    if pooled:
        print(_line("all", pooled))


if __name__ == "__main__":
    main()
