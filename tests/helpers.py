"""Scoring helpers shared by the scene tests (not part of the package API)."""

from __future__ import annotations

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
