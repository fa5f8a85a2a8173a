"""Figures and annotated frames for the outputs of :func:`mlplc2.run`.

Matplotlib is imported inside the functions (Agg canvas, no pyplot, no global
backend change), so importing :mod:`mlplc2` stays light.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = ["plot_responses", "annotate_frame", "read_responses"]

#: RGB colours of the annotated video.
ALARM_RGB = (230, 30, 30)
CALM_RGB = (40, 220, 60)


def read_responses(path) -> list[dict]:
    """Read a ``responses.csv`` written by :func:`mlplc2.run` into row dicts
    (numbers parsed, empty cells -> None)."""
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            rows.append({
                "frame": int(r["frame"]), "time_s": float(r["time_s"]), "model": r["model"],
                "field_id": int(r["field_id"]) if r["field_id"] else None,
                "x": float(r["x"]) if r["x"] else None, "y": float(r["y"]) if r["y"] else None,
                "response": float(r["response"]), "collision": int(r["collision"]),
            })
    return rows


def _series(rows: Sequence[dict]):
    """{model: {"fields": {id: (frames, responses)}, "plain": (frames, responses)}} in row order."""
    models: dict[str, dict] = {}
    for r in rows:
        m = models.setdefault(r["model"], {"fields": {}, "plain": ([], [])})
        if r["field_id"] is None:
            m["plain"][0].append(r["frame"])
            m["plain"][1].append(r["response"])
        else:
            fr, resp = m["fields"].setdefault(r["field_id"], ([], []))
            fr.append(r["frame"])
            resp.append(r["response"])
    return models


def _segments(frames: list[int], values: list[float]):
    """Split a field's series where frames are not consecutive (NaN gaps)."""
    fr = np.asarray(frames, dtype=float)
    val = np.asarray(values, dtype=float)
    if len(fr) > 1:
        breaks = np.nonzero(np.diff(fr) > 1)[0] + 1
        fr = np.insert(fr, breaks, np.nan)
        val = np.insert(val, breaks, np.nan)
    return fr, val


def plot_responses(rows, path, *, fields: dict | None = None, title: str | None = None, top: int = 12,
                   fps: float | None = None, dpi: int = 110) -> Path:
    """Paper-style response plot: one panel per model, response against frame.

    Parameters
    ----------
    rows : list of dict or path
        Rows of ``responses.csv`` (as in :attr:`RunResult.rows`) or the CSV path.
    path : path
        PNG to write (atomically).
    fields : dict, optional
        Field summaries per model (``fields.json``'s ``"models"``); used for the
        legend (centre and presence period). Without it, centres are the mean
        of the rows.
    title : str, optional
        Figure title.
    top : int
        Fields shown in colour and in the legend, the ``top`` largest peaks;
        the others are drawn thin and grey.
    fps : float, optional
        Adds a time axis (seconds) on top of the first panel.

    Notes
    -----
    Each field of an LPLC2-family model gets its own colour and a legend entry
    ``#id (x, y) born-died`` (input pixels, frames; ``died`` blank when alive at
    the end), like the paper's Fig. 5. A field's first alarm is marked with a
    triangle. Models without fields (LGMD) are one black line.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    from .io import atomic_path

    if isinstance(rows, (str, Path)):
        rows = read_responses(rows)
    data = _series(rows)
    n = max(len(data), 1)
    fig = Figure(figsize=(9.5, 1.0 + 2.6 * n), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    all_frames = [r["frame"] for r in rows] or [0]
    x0, x1 = min(all_frames), max(all_frames)
    for ax, (model, d) in zip(axes, data.items()):
        summaries = {s["id"]: s for s in (fields or {}).get(model, [])}
        if d["fields"]:
            ranked = sorted(d["fields"], key=lambda k: -max(d["fields"][k][1]))
            shown = sorted(ranked[:top])  # legend in id (= birth) order
            cmap = _colours(len(shown))
            for fid in ranked[top:]:
                fr, val = _segments(*d["fields"][fid])
                ax.plot(fr, val, color="0.7", lw=0.7, zorder=1)
            for c, fid in zip(cmap, shown):
                fr, val = _segments(*d["fields"][fid])
                ax.plot(fr, val, color=c, lw=1.5, label=_label(fid, summaries.get(fid), d["fields"][fid]),
                        zorder=2)
                s = summaries.get(fid)
                if s and s.get("first_alarm_frame") is not None:
                    k = s["first_alarm_frame"]
                    frs = d["fields"][fid][0]
                    if k in frs:
                        ax.plot([k], [d["fields"][fid][1][frs.index(k)]], marker="v", color=c, ms=6, zorder=3)
            handles, labels = ax.get_legend_handles_labels()
            if len(ranked) > top:
                handles.append(Line2D([], [], color="0.7", lw=0.7))
                labels.append(f"{len(ranked) - top} more fields")
            ax.legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      title="field (x, y) frames", title_fontsize=7, frameon=False)
        else:
            fr, val = d["plain"]
            ax.plot(fr, val, color="k", lw=1.5, label="response")
        ax.set_title(model, fontsize=10, loc="left")
        ax.set_ylabel("response (a.u.)")
        ax.grid(alpha=0.3)
        ax.set_xlim(x0, max(x1, x0 + 1))
    axes[-1].set_xlabel("frame")
    if fps:
        sec = axes[0].secondary_xaxis("top", functions=(lambda f: f / fps, lambda t: t * fps))
        sec.set_xlabel("time (s)", fontsize=8)
        sec.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=11)
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    return path


def _colours(k: int):
    from matplotlib import colormaps

    if k <= 10:
        return [colormaps["tab10"](i) for i in range(k)]
    order = list(range(0, 20, 2)) + list(range(1, 20, 2))  # dark shades first, then light
    return [colormaps["tab20"](order[i % 20]) for i in range(k)]


def _label(fid: int, summary: dict | None, series) -> str:
    if summary is not None:
        x, y = summary["x"], summary["y"]
        born = summary["born"]
        died = summary["died"]
    else:
        x = y = math.nan
        born, died = series[0][0], None
    span = f"{born}-{'' if died is None else died}"
    return f"#{fid} ({x:.0f}, {y:.0f}) {span}"


def annotate_frame(frame: np.ndarray, outputs, names: Sequence[str], scale_x: float = 1.0,
                   scale_y: float = 1.0, *, primary: int | None = 0, index: int | None = None) -> np.ndarray:
    """Draw attention fields and responses on a copy of an RGB frame.

    The fields of ``outputs[primary]`` are drawn as ellipses (circles unless
    the model frames were resized anisotropically) of the field radius scaled
    to input pixels, with ``id:response`` beside them: red while in alarm,
    green otherwise. A header lists every model's response (red ``ALARM``
    when its collision flag is set).
    """
    import cv2

    img = np.ascontiguousarray(frame[:, :, :3], dtype=np.uint8).copy()
    h, w = img.shape[:2]
    fs = max(0.3, min(w, h) / 600.0)
    th = 1 if fs < 0.6 else 2
    if primary is not None and outputs[primary].fields:
        for f in outputs[primary].fields:
            c = ALARM_RGB if f.collision else CALM_RGB
            cx, cy = int(round(f.x * scale_x)), int(round(f.y * scale_y))
            ax = max(1, int(round(f.radius * scale_x)))
            ay = max(1, int(round(f.radius * scale_y)))
            cv2.ellipse(img, (cx, cy), (ax, ay), 0, 0, 360, c, th + (1 if f.collision else 0), cv2.LINE_AA)
            cv2.drawMarker(img, (cx, cy), c, cv2.MARKER_CROSS, max(4, int(8 * fs * 2)), th)
            ttc = getattr(f, "ttc_s", None)  # time to collision (docs/targets.md)
            label = f"{f.id}:{_fmt(f.response)}" + ("" if ttc is None else f" ttc {ttc:.2f}s")
            _text(img, label, (cx + 4, cy - 4), c, fs)
    y = 4
    for name, out in zip(names, outputs):
        alarm = bool(out.collision)
        label = f"{name} {_fmt(out.response)}" + (" ALARM" if alarm else "")
        y += int(26 * fs) + 4
        _text(img, label, (4, y), ALARM_RGB if alarm else (255, 255, 255), fs)
    if index is not None:
        _text(img, f"frame {index}", (4, h - 6), (255, 255, 255), fs)
    return img


def _fmt(v: float) -> str:
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"


def _text(img, text: str, org, colour, fs: float) -> None:
    import cv2

    font = cv2.FONT_HERSHEY_SIMPLEX
    th = 1 if fs < 0.6 else 2
    (tw, tht), base = cv2.getTextSize(text, font, fs, th + 2)
    h, w = img.shape[:2]
    org = (int(min(max(org[0], 0), max(w - tw, 0))), int(min(max(org[1], tht + 1), max(h - base, tht + 1))))
    cv2.putText(img, text, org, font, fs, (0, 0, 0), th + 2, cv2.LINE_AA)
    cv2.putText(img, text, org, font, fs, colour, th, cv2.LINE_AA)
