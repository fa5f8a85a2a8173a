"""When does each stage first see a collision object? (issue 22's diagnosis; docs/history.md, "Camera motion: the benchmark
with and without stabilisation", "Why the drone's collisions are warned late", and "A finer channel for small objects")

For every collision object of the scenes of one setting (a benchmark's ``scenes/`` folder with its
``ground_truth.json``), the true time to contact (s) when, with ``MLPLC2(fps, hfov_deg=60,
stabilise=True)`` and the defaults: a field holding the object's centre first answers (Eq. 15 > 0)
and first alarms; a target whose box holds the centre first appears, first carries a time to
contact and first warns::

    python benchmarks/drone_timeline.py /tmp/suite0/scenes [--setting drone]

``--centred`` instead places an LPLC2 unit (Eq. 14-15, the ``q_min`` gate) on the object's true
centre every frame, R_AF 40 and 20, on the coarse front end (Table I), a fine one (half its
windows and sigmas) and the two merged (the fine LM_v where the coarse LM < 1): first answer / first
alarm (5 responses summed >= 10000). Minutes per setting on two cores.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import mlplc2
from mlplc2.backend import make_frontend
from mlplc2.camera import MotionEstimator
from mlplc2.io.source import read_video
from mlplc2.neuropils.attention import gate_area, lplc2_response, quadrant_areas, quadrant_sums
from mlplc2.neuropils.lobula_plate import LocalMotion

FINE = dict(r_e=3, sigma_e=5.0, r_i=6, sigma_i=10.0, r_c=3, sigma_c=10.0)


def holds(box_x, box_y, half_w, half_h, x, y) -> bool:
    return abs(box_x - x) <= half_w and abs(box_y - y) <= half_h


def timeline(frames, fps, objs):
    model = mlplc2.MLPLC2(fps, hfov_deg=60, stabilise=True)
    first = {o["id"]: {} for o in objs}
    for i, frame in enumerate(frames):
        out = model.step(frame)
        for o in objs:
            r = o["rows"].get(i)
            if r is None or None in r[1:6]:         # not in view
                continue
            _, x, y, w, h, ttc, _ = r
            seen = first[o["id"]]
            near = [f for f in out.fields if holds(f.x, f.y, f.radius, f.radius, x, y)]
            on = [t for t in out.targets if holds(t.x, t.y, max(t.width, w) / 2, max(t.height, h) / 2, x, y)]
            for key, hit in (("field", any(f.response > 0 for f in near)), ("alarm", any(f.collision for f in near)),
                             ("target", bool(on)), ("ttc", any(t.ttc_s is not None for t in on)),
                             ("warning", any(t.warning for t in on))):
                if hit:
                    seen.setdefault(key, round(ttc, 2))
    return first


def merged(coarse: LocalMotion, fine: LocalMotion, silent: float = 1.0) -> LocalMotion:
    use = coarse.magnitude < silent
    return LocalMotion(*(np.where(use, getattr(fine, k), getattr(coarse, k)) for k in ("r", "l", "d", "u", "magnitude")))


def centred(frames, fps, objs):
    p = mlplc2.Params()
    ends = make_frontend(p, fps), make_frontend(p.replace(**FINE), fps)
    cam = MotionEstimator(hfov_deg=60)
    res = {}
    for i, frame in enumerate(frames):
        g = (frame[..., :3] @ np.array([0.299, 0.587, 0.114])).astype(np.float32)
        _, hom = cam.turn(g, g.shape, hfov_deg=60)
        if hom is not None:
            for fe in ends:
                fe.compensate(hom, g)
        c, f = (fe.step(g) for fe in ends)
        for o in objs:
            r = o["rows"].get(i)
            x, y = (int(round(r[1])), int(round(r[2]))) if r is not None and None not in r[1:6] else (-1, -1)
            if not (0 <= x < g.shape[1] and 0 <= y < g.shape[0]):
                continue
            for name, lm in (("coarse", c), ("fine", f), ("merged", merged(c, f))):
                for radius in (40, 20):
                    resp = lplc2_response(quadrant_sums(lm, x, y, radius), [
                        p.q_min * gate_area(a, radius) for a in quadrant_areas(x, y, radius, g.shape)])
                    s = res.setdefault((o["id"], f"{name} R{radius}"), [None, None, []])
                    s[2].append(resp)
                    if resp > 0 and s[0] is None:
                        s[0] = round(r[5], 2)
                    if sum(s[2][-p.alarm_window:]) >= p.alarm_threshold and s[1] is None:
                        s[1] = round(r[5], 2)
    return {o["id"]: {k: f"{v[0]}/{v[1]}" for (oid, k), v in res.items() if oid == o["id"]} for o in objs}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes")
    ap.add_argument("--setting", default="drone")
    ap.add_argument("--centred", action="store_true")
    a = ap.parse_args()
    truth = json.load(open(f"{a.scenes}/ground_truth.json"))["videos"]
    for name, video in sorted(truth.items()):
        if not name.startswith(a.setting + "_"):
            continue
        frames, fps = read_video(f"{a.scenes}/{name}")
        objs = [dict(o, rows={int(r[0]): r for r in o["track"]}) for o in video["objects"] if o["kind"] == "collision"]
        result = (centred if a.centred else timeline)(frames, fps, objs)
        for o in objs:
            print(name, o["id"], o["appearance"], f"{o['width_m']:.2f} m", result[o["id"]], flush=True)


if __name__ == "__main__":
    main()
