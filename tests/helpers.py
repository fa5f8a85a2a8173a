"""Helpers shared by the tests (not part of the package API): scoring of the scene tests, and
the check that the outputs of an interrupted run agree."""

from __future__ import annotations

import csv
import json
import math


def run_fields(model, frames):
    """Run ``model`` and collect per-field birth position and alarms, and per-frame outputs."""
    born, outs = {}, []
    for frame in frames:
        out = model.step(frame)
        outs.append(out)
        for f in out.fields:
            born.setdefault(f.id, (f.born, f.x, f.y))
    return born, outs


def first_field(born, center, onset, end, radius=20.0):
    """(latency, error) of the first field born in [onset, end) within ``radius`` of ``center``."""
    hits = [(b, math.hypot(x - center[0], y - center[1])) for b, x, y in born.values()
            if onset <= b < end and math.hypot(x - center[0], y - center[1]) <= radius]
    if not hits:
        return None
    b, err = min(hits)
    return b - onset, err


def false_alarms(outs, objects, radius=20.0, tail=25):
    """Frames with a field in alarm that is not near an object approaching (or just after)."""
    bad = []
    for out in outs:
        for f in out.fields:
            if not f.collision:
                continue
            near = any(o.get("approach") and o["approach"][0] <= out.frame < o["approach"][1] + tail
                       and math.hypot(f.x - o["center"][0], f.y - o["center"][1]) <= radius
                       for o in objects)
            if not near:
                bad.append((out.frame, f.id))
    return bad


def _read_csv(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def check_outputs_agree(out, models, *, localising="mlplc2") -> int:
    """``responses.csv``, ``targets.csv`` and ``fields.json`` in ``out`` cover the same frames,
    ``0 .. n_frames - 1`` (a run from frame 0): every model has rows for exactly these frames,
    ``targets.csv`` has no later frame (and the same targets per frame as the summaries say
    were alive), and no field or target summary names a later frame. Returns ``n_frames``."""
    summary = json.loads((out / "fields.json").read_text())
    n = summary["n_frames"]
    rows = _read_csv(out / "responses.csv")
    for name in models:
        assert sorted({int(r["frame"]) for r in rows if r["model"] == name}) == list(range(n)), name
    trows = [r for r in _read_csv(out / "targets.csv") if r["model"] == localising]
    assert all(int(r["frame"]) < n for r in trows)
    for f in summary["models"][localising]:
        assert f["born"] < n and f["peak_frame"] < n and (f["died"] is None or f["died"] <= n)
    counts: dict[int, int] = {}
    for r in trows:
        counts[int(r["target_id"])] = counts.get(int(r["target_id"]), 0) + 1
    for t in summary["targets"][localising]:       # a target's rows are the frames of its life
        assert t["born"] < n and (t["died"] is None or t["died"] <= n) and counts.get(t["id"], 0) == t["frames"]
    assert set(counts) == {t["id"] for t in summary["targets"][localising]}
    return n
