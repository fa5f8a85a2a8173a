"""Helpers shared by the tests (not part of the package API): the check that the outputs of an
interrupted run agree, small noise clips, and clips with duplicated frames. (Recording and
scoring model outputs: :mod:`mlplc2.evaluation.record`, :mod:`mlplc2.evaluation.match`.)"""

from __future__ import annotations

import csv
import json

import numpy as np


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


#: The size of :func:`noise_frames` (the small clips of the input checks).
NOISE_W, NOISE_H = 64, 48


def noise_frames(n, w=NOISE_W, h=NOISE_H, seed=0):
    """``n`` RGB frames of uniform noise, ``h`` x ``w``."""
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def duplicated(frames, every=3, copies=2, noise=6, seed=0):
    """Each ``every``-th frame repeated ``copies`` times with +-``noise`` grey levels of jitter
    (a frame-rate conversion of a compressed video); returns (frames, index of the original)."""
    rng = np.random.default_rng(seed)
    out, origin = [], []
    for i, f in enumerate(frames):
        out.append(f)
        origin.append(i)
        if i % every == 0:
            for _ in range(copies):
                jitter = rng.integers(-noise, noise + 1, f.shape)
                out.append(np.clip(f.astype(np.int16) + jitter, 0, 255).astype(np.uint8))
                origin.append(i)
    return out, origin


def score_collision(outputs, truth, fps: float):
    """Targets of ``outputs`` (one :class:`mlplc2.Output` per frame) against one collision object's
    ``truth`` (:class:`mlplc2.stimuli` ground truth): the relative errors of the time to contact of
    the targets on the object in its last second, whether one of them warned before contact, and
    the warnings elsewhere (frames x targets)."""
    errors, warned, false = [], False, 0
    for out in outputs:
        k = out.frame
        if k >= truth.contact_frame or not truth.in_track(k):
            continue
        p = truth.point_at(k)
        true_ttc = (truth.contact_frame - k) / fps
        for t in out.targets:
            near = abs(t.x - p.x) < max(20.0, p.width) and abs(t.y - p.y) < max(20.0, p.width)
            if near and t.ttc_s is not None and true_ttc <= 1.0:
                errors.append(abs(t.ttc_s - true_ttc) / true_ttc)
            warned |= near and t.warning
            false += (not near) and t.warning
    return errors, warned, false


def disc_with_gap(n=46, contact=70, r0=6.0, gap=(30, 33), at=(200, 110)):
    """uint8 grey frames (240 x 320) of a dark disc approaching at constant speed (radius r0 * contact / (contact - k),
    contact at frame ``contact``) on a plain background, hidden during the frames of ``gap`` (an occlusion: the
    image alignment fails there, the track is lost and refound)."""
    import cv2

    frames = []
    for k in range(n):
        img = np.full((240, 320), 150, np.uint8)
        if not gap[0] <= k < gap[1]:
            r = r0 * contact / (contact - k)
            cv2.circle(img, (at[0] * 16, at[1] * 16), int(round(r * 16)), 30, -1, lineType=cv2.LINE_AA, shift=4)
        frames.append(img)
    return frames


#: the JSON lines' keys of the computer's clock (docs/robot.md): they differ between any two runs
CLOCK_KEYS = ("wall_s", "latency_ms")


def jsonl_results(text: str) -> list[dict]:
    """The JSON lines in ``text`` without their clock keys (:data:`CLOCK_KEYS`): what two runs on the same frames
    must share."""
    lines = [json.loads(line) for line in text.splitlines()]
    return [{k: v for k, v in line.items() if k not in CLOCK_KEYS} for line in lines]

