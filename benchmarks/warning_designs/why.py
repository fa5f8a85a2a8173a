"""Which rule opens each copy's first target warning, and which rule holds back each field alarm (a measurement
aid, not part of the package; docs/history.md, "Encoding and size", session 13).

For every clip of ``benchmarks/encoding_invariance.py`` and each copy already in its ``--cache``, runs mLPLC2 with
``mlplc2.targets.layer.estimate`` and ``mlplc2.targets.warning.alarm_warns`` wrapped, and prints per copy the first
warnings that began (frame, target id and birth frame, position in the labels' pixels, on the collider or not,
time to contact, miss, the rule that opened it: ``fit`` (the fit's course), ``fit+cut_course``, ``alarm+course``
(a field alarm with the fit's course), ``alarm:on_path`` / ``alarm:keeps_bearing`` (a field alarm without a
course)) and the field alarms the target's own measurement held back (``shrunk``, ``nofit:...`` with the fit's
time to contact, t-statistic, growth, anisotropy and whether it passed ``max_anisotropy``, ``ttc>``, ``miss>``,
``cut/nohead``, ``offpath/drift``)::

    PYTHONPATH=src python benchmarks/warning_designs/why.py --cache /tmp/x/cache [--clip bear] [--json out.json]

With ``benchmarks/warning_designs`` on ``PYTHONPATH`` and ``MLPLC2_WARNING_DESIGN`` set it traces a design.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


import mlplc2
import mlplc2.targets.layer as _layer
import mlplc2.targets.warning as _warning
from mlplc2.evaluation.match import on_object
from mlplc2.targets.contact import fit_contact

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import encoding_invariance as E  # noqa: E402

EVENTS, VETOES, CUR = [], [], {}
_alarm_warns, _cut_course, _estimate = _warning.alarm_warns, _warning.cut_course, _layer.estimate


def held_back(t, p, index, ttc, miss, heading, shape) -> str:
    """Why ``alarm_warns`` said no to a track in collision alarm (its tests in order)."""
    if len(t.history) > 1 and t.history[-1].log_scale - t.history[0].log_scale <= 0:
        return "shrunk"
    if ttc is None and _warning.fits(t.history, t.fit_span):
        ls = [q.log_scale for q in t.history]
        f = fit_contact([q.frame for q in t.history], ls)
        g, sk = ls[-1] - ls[0], t.history[-1].anisotropy - t.history[0].anisotropy
        if f is None or f.ttc is None:
            return f"nofit:no approach (t {f.tstat if f else 0:.1f}, growth {g:.2f})"
        fps = CUR.get("fps", 30.0)
        return (f"nofit:ttc {f.ttc / fps:.2f}+-{f.sigma / fps:.2f} s, t {f.tstat:.1f}, growth {g:.2f}, "
                f"skew {sk:.2f}, isotropic {g > 0 and abs(sk) <= p.max_anisotropy * g}")
    if ttc is not None and ttc > p.horizon_s:
        return f"ttc {ttc:.2f} > horizon"
    if miss is not None:
        if p.alarm_onset_miss and not t.warned and _warning.wide(p, miss) \
                and (t.alarm_courses > 0 if p.alarm_onset_course else t.alarm_run > 1):
            return f"onset_miss: course {miss:.2f} beyond onset_miss past the alarm's first frame"
        return f"miss {miss:.2f} > {p.max_miss:.2f}"
    if heading is None or shape is None or t.cut(shape, p.border):
        return "cut/no heading"
    return "offpath/drift"


def alarm_warns(t, p, index, ttc, miss, heading=None, shape=None):
    r = _alarm_warns(t, p, index, ttc, miss, heading, shape)
    if r:
        CUR["rule"] = ("alarm+course" if miss is not None else
                       "alarm:on_path" if _warning.on_path(t, p, heading) else "alarm:keeps_bearing")
    elif p.alarm_warns and t.last_alarm == index:
        VETOES.append(dict(frame=index, id=t.id, born=t.born, history=len(t.history),
                           why=held_back(t, p, index, ttc, miss, heading, shape)))
    return r


def cut_course(*a, **k):
    r = _cut_course(*a, **k)
    CUR["cut_course"] = CUR.get("cut_course") or r
    return r


def estimate(t, p, fps, index, shape, focal=None, heading=None, **kw):
    CUR.clear()
    CUR["fps"] = fps
    before = t.warned
    o = _estimate(t, p, fps, index, shape, focal, heading=heading, **kw)
    if o.warning and not before:
        rule = CUR.get("rule") or ("fit+cut_course" if CUR.get("cut_course") else "fit")
        EVENTS.append(dict(frame=index, id=t.id, born=t.born, ttc=o.ttc_s, miss=o.miss, rule=rule))
    return o


_warning.alarm_warns, _warning.cut_course, _layer.estimate = alarm_warns, cut_course, estimate


def trace(path, truth, native) -> dict:
    EVENTS.clear(), VETOES.clear()
    res = mlplc2.run(str(path), ["mlplc2"], out=False, quiet=True, progress=False, plot=False)
    sx, sy = native[0] / res.size[0], native[1] / res.size[1]
    rows = {(r["frame"], r["target_id"]): r for r in res.targets if r["model"] == "mlplc2" and r["warning"]}
    col = truth.collider if truth is not None else None
    out = []
    for e in EVENTS:                       # the warnings that began and were not vetoed after (a slanted box)
        r = rows.get((round(e["frame"]), e["id"]))
        if r is None:
            continue
        x, y = (r["x"] + 0.5) * sx - 0.5, (r["y"] + 0.5) * sy - 0.5
        on = None if col is None or not col.track else bool(on_object(x, y, col, r["frame"]))
        out.append(dict(e, frame=r["frame"], x=round(x), y=round(y), on=on))
    return dict(warnings=out, vetoes=list(VETOES), alarm=res.alarms.get("mlplc2", {}).get("first"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[2] / ".." / "shared" / "data")
    ap.add_argument("--cache", type=Path, default=E.CACHE)
    ap.add_argument("--clip", action="append", default=[])
    ap.add_argument("--json", type=Path)
    ap.add_argument("--vetoes", type=int, default=6, help="field alarms held back to print per copy")
    args = ap.parse_args(argv)
    table = {}
    for video, key, truth, native, _ in E.measured(args.data, args.clip):
        for copy in E.COPIES:
            paths = [video] if copy == "orig" else sorted(args.cache.glob(f"{video.stem}_{copy}_*.mp4"))
            if not paths:
                continue
            r = table[f"{video.name} {copy}"] = trace(paths[0], truth, native)
            print(f"{video.name:32s} {copy:8s} first field alarm {r['alarm']}", flush=True)
            for w in r["warnings"][:3]:
                on = {True: "on", False: "OFF", None: "-"}[w["on"]]
                ttc = "-" if w["ttc"] is None else f"{w['ttc']:.2f}"
                miss = "-" if w["miss"] is None else f"{w['miss']:.2f}"
                print(f"    warns {w['frame']:4d}  target {w['id']} (born {w['born']}) at ({w['x']}, {w['y']}) {on}, "
                      f"ttc {ttc} s, miss {miss}: {w['rule']}", flush=True)
            for v in r["vetoes"][:args.vetoes]:
                print(f"    alarm held back {v['frame']:6.1f}  target {v['id']} (born {v['born']}, "
                      f"{v['history']} obs): {v['why']}", flush=True)
    if args.json:
        args.json.write_text(json.dumps(table, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
