"""Figures and annotated frames for the outputs of :func:`mlplc2.run`.

Matplotlib is imported inside the functions (Agg canvas, no pyplot, no global
backend change), so importing :mod:`mlplc2` stays light.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ._files import atomic_path
from ._validation import InputValueError
from .evaluation.record import read_responses, read_targets

__all__ = ["plot_responses", "annotate_frame", "header_text", "read_responses", "read_targets", "plot_timeline",
           "DRAW_FIELDS"]

#: RGB colours of the annotated video.
ALARM_RGB = (230, 30, 30)
CALM_RGB = (40, 220, 60)


def _series(rows: Sequence[dict]):
    """{model: {"fields": {id: (frames, responses)}, "plain": (frames, responses)}} in row order."""
    models: dict[str, dict] = {}
    for r in rows:
        m = models.setdefault(r["model"], {"fields": {}, "plain": ([], [])})
        fr, resp = m["plain"] if r["field_id"] is None else m["fields"].setdefault(r["field_id"], ([], []))
        fr.append(r["frame"])
        resp.append(r["response"])
    return models


def gap_segments(frames: Sequence[int], values: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """A field's series as float arrays, split by NaN where frames are not consecutive (gaps in the line)."""
    fr = np.asarray(frames, dtype=float)
    val = np.asarray(values, dtype=float)
    if len(fr) > 1:
        breaks = np.nonzero(np.diff(fr) > 1)[0] + 1
        fr = np.insert(fr, breaks, np.nan)
        val = np.insert(val, breaks, np.nan)
    return fr, val


def plot_responses(rows, path, *, fields: dict | None = None, title: str | None = None, top: int = 12,
                   fps: float | None = None, targets=None, dpi: int = 110) -> Path:
    """Paper-style response plot: one panel per model, response against frame; under the panel
    of a model with targets, their time to contact against frame, warning frames marked.

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
    targets : list of dict or path, optional
        Rows of ``targets.csv`` (as in :attr:`RunResult.targets`) or the CSV path: each model
        with rows gets a second panel, the timeline of its targets (:func:`plot_timeline`).

    Notes
    -----
    Each field of an LPLC2-family model gets its own colour and a legend entry
    ``#id (x, y) born-died`` (input pixels, frames; ``died`` blank when alive at
    the end), like the paper's Fig. 5. A field's first alarm is marked with a
    triangle. Models without fields (LGMD) are one black line.
    """
    if isinstance(rows, (str, Path)):
        rows = read_responses(rows)
    if isinstance(targets, (str, Path)):
        targets = read_targets(targets)
    data = _series(rows)
    timelines: dict[str, list[dict]] = {}
    for r in targets or ():
        timelines.setdefault(r["model"], []).append(r)
    panels = [(model, kind) for model in data for kind in ("responses", "targets")
              if kind == "responses" or model in timelines]
    n = max(len(panels), 1)
    fig = figure(9.5, 1.0 + 2.6 * n)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    all_frames = [r["frame"] for r in rows] or [0]
    x0, x1 = min(all_frames), max(all_frames)
    for ax, (model, kind) in zip(axes, panels):
        ax.set_xlim(x0, max(x1, x0 + 1))
        if kind == "targets":
            plot_timeline(ax, timelines[model], model, top=top)
            continue
        d = data[model]
        summaries = {s["id"]: s for s in (fields or {}).get(model, [])}
        if d["fields"]:
            ranked = sorted(d["fields"], key=lambda k: -max(d["fields"][k][1]))
            shown = sorted(ranked[:top])  # legend in id (= birth) order
            cmap = colours(len(shown))
            for fid in ranked[top:]:
                ax.plot(*gap_segments(*d["fields"][fid]), color="0.7", lw=0.7, zorder=1)
            for c, fid in zip(cmap, shown):
                frs, vals = d["fields"][fid]
                s = summaries.get(fid)
                ax.plot(*gap_segments(frs, vals), color=c, lw=1.5, label=_label(fid, s, (frs, vals)), zorder=2)
                k = s.get("first_alarm_frame") if s else None
                if k is not None and k in frs:
                    ax.plot([k], [vals[frs.index(k)]], marker="v", color=c, ms=6, zorder=3)
            _side_legend(ax, len(ranked) - top, "fields", "field (x, y) frames")
        else:
            fr, val = d["plain"]
            ax.plot(fr, val, color="k", lw=1.5, label="response")
        ax.set_title(model, fontsize=10, loc="left")
        ax.set_ylabel("response (a.u.)")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("frame")
    if fps:
        sec = axes[0].secondary_xaxis("top", functions=(lambda f: f / fps, lambda t: t * fps))
        sec.set_xlabel("time (s)", fontsize=8)
        sec.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=11)
    return save_png(fig, path, dpi)


#: Upper limit (s) of the time-to-contact axis of :func:`plot_timeline`: early estimates of tens
#: of seconds would squeeze the last second before contact, where warnings happen.
TTC_AXIS_S = 5.0



def _side_legend(ax, more: int, what: str, title: str) -> None:
    """The legend right of ``ax``; ``more`` > 0 lines not drawn in colour are counted in a last entry."""
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    if more > 0:
        handles.append(Line2D([], [], color="0.7", lw=0.7))
        labels.append(f"{more} more {what}")
    ax.legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              title=title, title_fontsize=7, frameon=False)

def plot_timeline(ax, rows: Sequence[dict], model: str, *, top: int = 12) -> None:
    """One model's targets on ``ax``: time to contact (s) against frame, one line per target
    (gaps while it has no estimate), its warning frames as filled dots on the line. The
    ``top`` targets that warn first (then those with the most estimates) get a colour and a
    legend entry ``T<id> warns <first>-<last>`` (or ``no warning``); the others are thin and grey."""
    series: dict[int, tuple[list, list, list]] = {}
    for r in rows:
        if r["ttc_s"] is not None:
            fr, ttc, warn = series.setdefault(r["target_id"], ([], [], []))
            fr.append(r["frame"])
            ttc.append(r["ttc_s"])
            warn.append(bool(r["warning"]))

    def first_warning(tid):
        fr, _, warn = series[tid]
        return next((f for f, w in zip(fr, warn) if w), math.inf)

    ranked = sorted(series, key=lambda tid: (first_warning(tid), -len(series[tid][0]), tid))
    shown = sorted(ranked[:top])
    for tid in ranked[top:]:
        ax.plot(*gap_segments(*series[tid][:2]), color="0.7", lw=0.7, zorder=1)
    for c, tid in zip(colours(len(shown)), shown):
        fr, ttc, warn = series[tid]
        wf = [f for f, w in zip(fr, warn) if w]
        label = f"T{tid} warns {wf[0]}-{wf[-1]}" if wf else f"T{tid} no warning"
        ax.plot(*gap_segments(fr, ttc), color=c, lw=1.3, label=label, zorder=2)
        if wf:
            ax.plot(wf, [v for v, w in zip(ttc, warn) if w], ls="none", marker="o", ms=3.5, color=c,
                    mec="k", mew=0.4, zorder=3)
    if series:
        _side_legend(ax, len(ranked) - top, "targets", "target (dots: warning)")
    else:
        ax.text(0.5, 0.5, "no time to contact estimated", transform=ax.transAxes, ha="center", va="center",
                fontsize=8, color="0.4")
    top_s = max((v for _, ttc, _ in series.values() for v in ttc), default=1.0)
    ax.set_ylim(0.0, min(max(top_s * 1.05, 0.5), TTC_AXIS_S))
    ax.set_title(f"{model}: targets", fontsize=10, loc="left")
    ax.set_ylabel("time to contact (s)")
    ax.grid(alpha=0.3)


def figure(width: float, height: float):
    """A matplotlib Figure of ``width`` x ``height`` inches, constrained layout, on its own Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_png(fig, path, dpi: int) -> Path:
    """Write ``fig`` to ``path`` as PNG at ``dpi``, atomically (folders created); returns ``path``."""
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    return path


def colours(k: int) -> list:
    """``k`` distinct matplotlib colours: tab10, or tab20 (dark shades first) beyond 10."""
    from matplotlib import colormaps

    if k <= 10:
        return [colormaps["tab10"](i) for i in range(k)]
    order = list(range(0, 20, 2)) + list(range(1, 20, 2))  # dark shades first, then light
    return [colormaps["tab20"](order[i % 20]) for i in range(k)]


def _label(fid: int, summary: dict | None, series) -> str:
    s = summary if summary is not None else {"x": math.nan, "y": math.nan, "born": series[0][0], "died": None}
    return f"#{fid} ({s['x']:.0f}, {s['y']:.0f}) {s['born']}-{'' if s['died'] is None else s['died']}"


#: Which attention fields ``annotate_frame`` draws: "auto" (none when the model has targets, else
#: those that respond or alarm), "none", "responding", "all".
DRAW_FIELDS = ("auto", "none", "responding", "all")
#: Target outlines: warning, with a time to contact, without one yet.
WARN_RGB = ALARM_RGB
TIMED_RGB = (255, 170, 0)
TARGET_RGB = (90, 170, 255)
#: Label backgrounds of the annotated video: the header and the frame number.
PANEL_RGB = (20, 20, 20)
#: The paper's field alarm: an attention field in collision alarm (its outline, cross and label) and a header row
#: whose model's fields alarm while none of its targets warns. Violet, not the red of a warning (a target's, or an
#: LGMD model's alarm, which is that model's warning).
FIELD_ALARM_RGB = (130, 70, 170)


def annotate_frame(frame: np.ndarray, outputs, names: Sequence[str], scale_x: float = 1.0,
                   scale_y: float = 1.0, *, primary: int | None = 0, index: int | None = None,
                   field_shape: str = "square", draw_fields: str = "auto") -> np.ndarray:
    """Draw targets, attention fields and responses on a copy of an RGB frame.

    The targets of ``outputs[primary]`` (``Output.targets``) are drawn as boxes of their
    apparent size, clipped to the frame, labelled ``T<id>`` with the time to contact and the
    predicted miss once known: red, thicker and ``T<id> WARNING`` while warning (orange with a
    time to contact, blue without one). On a frame narrower than ``SMALL_FRAME_WIDTH`` (320 px)
    the label is short, ``T<id> <ttc> s`` (``T<id> WARN <ttc> s``), without the miss.

    The fields of ``outputs[primary]`` are drawn in their real shape, scaled to input
    pixels: a square of half-side ``radius`` (``field_shape="square"``, the default of
    :class:`mlplc2.Params`) or a disc of that radius (``"disc"``), a rectangle or an
    ellipse when the model frames were resized anisotropically. Each gets a cross at its
    centre and a label ``#id response`` (and ``ttc`` once estimated). Fields in alarm are
    violet (``FIELD_ALARM_RGB``, the paper's field alarm, not a warning), the others green.
    ``draw_fields``: "auto" (default) draws no field when the model
    has targets and else only the fields that respond (response > 0) or are in alarm,
    "responding" those, "all" every field, "none" none. A header at the top left has one row per
    model (:func:`header_text`: the warning target and its time to contact, ``field alarm (paper)``,
    or the response; on red while a target warns or a model without fields alarms, on violet while
    only the attention fields alarm), and ``index`` is
    shown at the bottom left.

    Text size, line widths and margins scale with the frame size (``_Style``; smaller text below
    320 px wide), and every
    label sits on a filled box, placed where it hides no other label, so it reads on any
    background.
    """
    if draw_fields not in DRAW_FIELDS:
        raise InputValueError(f"draw_fields must be one of {', '.join(map(repr, DRAW_FIELDS))}, "
                              f"got {draw_fields!r}")
    img = np.ascontiguousarray(frame[:, :, :3], dtype=np.uint8).copy()
    style = _Style(*img.shape[:2])
    labels = _Labels(img, style)
    _header_labels(labels, outputs, names, index)  # placed first: the other labels keep clear of them
    if primary is not None:
        out = outputs[primary]
        mode = draw_fields if draw_fields != "auto" else ("none" if out.targets else "responding")
        if mode != "none":
            for f in out.fields:
                if mode == "all" or f.response > 0 or f.collision:
                    _draw_field(img, labels, f, style, scale_x, scale_y, field_shape)
        for t in reversed(out.targets):            # the most urgent last: on top
            _draw_target(img, labels, t, style, scale_x, scale_y)
    labels.draw()  # last: on top of the outlines
    return img


#: Frames narrower than this (px) get smaller text and short target labels (``_Style``).
SMALL_FRAME_WIDTH = 320
#: The smallest font scale of the overlay (a 160-px frame's): OpenCV's simplex font still reads there.
MIN_FONT_SCALE = 0.25


class _Style:
    """Sizes of the overlay for one frame size: everything scales with ``u = min(H, W) / 240``.

    Font scale ``0.45 u``: "mlplc2 1.5" is 11 px high (ascender to descender) at 320x240,
    34 px at 1280x720, on a box 19 and 60 px high (measured with OpenCV 5.0); at least 0.35,
    and below ``SMALL_FRAME_WIDTH`` at least ``0.35 W / 320`` (not under ``MIN_FONT_SCALE``), so
    that labels on a 160x120 frame take less of it. There the target labels are short
    (``short``: no miss, ``WARN``). Field outlines are ``round(u)`` px wide (one more in alarm).
    """

    def __init__(self, h: int, w: int):
        u = max(min(h, w), 1) / 240.0
        self.short = w < SMALL_FRAME_WIDTH
        floor = max(0.35 * min(w, SMALL_FRAME_WIDTH) / SMALL_FRAME_WIDTH, MIN_FONT_SCALE)
        self.font_scale = max(floor, 0.45 * u)
        self.text_thickness = max(1, int(round(self.font_scale * 1.4)))
        self.line = max(1, int(round(u)))
        self.pad = max(2, int(round(2.5 * u)))
        self.margin = max(2, int(round(3 * u)))
        self.gap = max(1, int(round(1.5 * u)))
        self.cross = max(5, int(round(8 * u)))


def _text_on(bg) -> tuple[int, int, int]:
    """Black or white, whichever contrasts more with ``bg`` (Rec. 601 luma)."""
    luma = 0.299 * bg[0] + 0.587 * bg[1] + 0.114 * bg[2]
    return (0, 0, 0) if luma > 140 else (255, 255, 255)


class _Labels:
    """The text labels of one frame: each placed where it overlaps no label placed before,
    then all drawn on top of the outlines (:meth:`draw`).

    A label is ``text`` in black or white on a filled ``bg`` box. ``add`` takes candidate
    positions, each ``(x, y, anchor)`` with ``anchor`` "top" (``(x, y)`` is the box's
    top-left corner) or "bottom" (its bottom-left corner), and uses the first one whose box,
    moved inside the frame, overlaps no earlier label (else the first one). A label wider than
    the frame is written smaller, to fit it.
    """

    def __init__(self, img: np.ndarray, style: _Style):
        import cv2

        self._cv2 = cv2
        self.img = img
        self.style = style
        self.items: list[tuple[str, tuple, tuple[int, int, int, int], int, float]] = []

    def size(self, text: str, font_scale: float | None = None) -> tuple[int, int, int]:
        """``(width, height, text height)`` of the box of ``text`` (at the style's font scale, or ``font_scale``)."""
        st = self.style
        (tw, th), base = self._cv2.getTextSize(text, self._cv2.FONT_HERSHEY_SIMPLEX,
                                               st.font_scale if font_scale is None else font_scale, st.text_thickness)
        return tw + 2 * st.pad, th + base + 2 * st.pad, th

    def _fit(self, text: str) -> tuple[int, int, int, float]:
        """The box of ``text`` and its font scale: the style's, or smaller where the box would be wider than the frame."""
        scale = self.style.font_scale
        bw, bh, th = self.size(text)
        w = self.img.shape[1]
        while bw > w and scale > 0.1:
            scale *= max(min((w - 2 * self.style.pad) / max(bw - 2 * self.style.pad, 1), 0.95), 0.1)
            bw, bh, th = self.size(text, scale)
        return bw, bh, th, scale

    def _box(self, x: float, y: float, anchor: str, bw: int, bh: int) -> tuple[int, int, int, int]:
        h, w = self.img.shape[:2]
        x0 = min(max(int(x), 0), max(w - bw, 0))
        y0 = min(max(int(y) - (bh if anchor == "bottom" else 0), 0), max(h - bh, 0))
        return x0, y0, min(x0 + bw, w), min(y0 + bh, h)

    def add(self, text: str, bg, *candidates: tuple[float, float, str]) -> tuple[int, int, int, int]:
        """Place one label (see the class docstring); returns its box ``(x0, y0, x1, y1)``."""
        bw, bh, th, scale = self._fit(text)
        boxes = [self._box(x, y, anchor, bw, bh) for x, y, anchor in candidates]
        box = next((b for b in boxes if not self._hits(b)), None)
        if box is None:  # every candidate hides a label: the first one, moved down below them
            box = boxes[0]
            for _ in range(len(self.items)):
                hits = self._hits(box)
                if not hits:
                    break
                box = self._box(box[0], max(o[3] for o in hits) + self.style.gap, "top", bw, bh)
            if self._hits(box):
                box = boxes[0]
        self.items.append((text, tuple(int(c) for c in bg), box, th, scale))
        return box

    def _hits(self, box) -> list[tuple[int, int, int, int]]:
        """The boxes of the labels placed so far that ``box`` overlaps."""
        return [other for _, _, other, _, _ in self.items if _overlap(box, other)]

    def draw(self) -> None:
        cv2, st = self._cv2, self.style
        for text, bg, (x0, y0, x1, y1), th, scale in self.items:
            cv2.rectangle(self.img, (x0, y0), (x1 - 1, y1 - 1), bg, cv2.FILLED)
            cv2.putText(self.img, text, (x0 + st.pad, y0 + st.pad + th), cv2.FONT_HERSHEY_SIMPLEX,
                        scale, _text_on(bg), st.text_thickness, cv2.LINE_AA)


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def header_text(name: str, out) -> str:
    """One model's header row: ``mlplc2 WARNING T3 0.80 s`` while a target warns (the most
    urgent: the shortest time to contact; ``+k`` more warning), ``field alarm (paper)`` while an
    attention field is in collision alarm (the paper's signal, not the targets' warning; ``field
    alarm`` after a warning; ``ALARM`` for a model without fields, whose alarm is its warning), and
    ``response <r>`` (Eq. 15, a.u.) unless a target warns."""
    warning = sorted((t for t in getattr(out, "targets", ()) if t.warning), key=lambda t: t.urgency())
    parts = []
    if warning:
        t = warning[0]
        ttc = "" if t.ttc_s is None else f" {t.ttc_s:.2f} s"
        parts.append(f"WARNING T{t.id}{ttc}" + (f" +{len(warning) - 1}" if len(warning) > 1 else ""))
    if out.collision:
        parts.append(("field alarm" if warning else "field alarm (paper)") if out.fields else "ALARM")
    if not warning:
        parts.append(f"response {_fmt(out.response)}")
    return f"{name} " + ", ".join(parts)


def _header_labels(labels: _Labels, outputs, names: Sequence[str], index: int | None) -> None:
    """Top left, one row per model (:func:`header_text`): on red while it warns (a target warns, or a
    model without fields is in alarm), on violet while only its attention fields alarm (the paper's
    field alarm), else dark grey; bottom left: the frame number."""
    st = labels.style
    y = st.margin
    for name, out in zip(names, outputs):
        warns = any(t.warning for t in getattr(out, "targets", ())) or (bool(out.collision) and not out.fields)
        bg = ALARM_RGB if warns else FIELD_ALARM_RGB if out.collision else PANEL_RGB
        y = labels.add(header_text(name, out), bg, (st.margin, y, "top"))[3] + st.gap
    if index is not None:
        labels.add(f"frame {index}", PANEL_RGB, (st.margin, labels.img.shape[0] - st.margin, "bottom"))


def _draw_target(img: np.ndarray, labels: _Labels, t, style: _Style, scale_x: float, scale_y: float) -> None:
    """One target: a box of its apparent size, clipped to the frame (all four sides show), and a
    label ``T<id> <ttc> s miss <m>``; a warning target's box is thicker, edged in white, and
    its label reads ``T<id> WARNING <ttc> s miss <m>``. On a small frame (``style.short``) the
    label is ``T<id> <ttc> s``, ``T<id> WARN <ttc> s`` while warning."""
    import cv2

    colour = WARN_RGB if t.warning else TIMED_RGB if t.ttc_s is not None else TARGET_RGB
    h, w = img.shape[:2]
    line = style.line + (2 if t.warning else 0)
    half = (line + (2 if t.warning else 0)) // 2
    cx, cy = t.x * scale_x, t.y * scale_y
    hw, hh = max(t.width * scale_x / 2.0, 1.0), max(t.height * scale_y / 2.0, 1.0)
    x0, x1 = (min(max(int(round(v)), half), max(w - 1 - half, half)) for v in (cx - hw, cx + hw))
    y0, y1 = (min(max(int(round(v)), half), max(h - 1 - half, half)) for v in (cy - hh, cy + hh))
    if t.warning:  # a white edge: the box stands out on dark and on red backgrounds
        cv2.rectangle(img, (x0, y0), (x1, y1), (255, 255, 255), line + 2)
    cv2.rectangle(img, (x0, y0), (x1, y1), colour, line)
    text = f"T{t.id}" + ((" WARN" if style.short else " WARNING") if t.warning else "")
    if t.ttc_s is not None:
        text += f" {t.ttc_s:.2f} s"
        if t.miss is not None and not style.short:
            text += f" miss {t.miss:.1f}"
    labels.add(text, colour, (x0, y0 - half, "bottom"), (x0, y1 + half, "top"), (x0 + half, y0 + half, "top"),
               (x0 + half, y1 - half, "bottom"))


def _draw_field(img: np.ndarray, labels: _Labels, f, style: _Style, scale_x: float, scale_y: float,
                shape: str) -> None:
    """One attention field: its outline (square or disc), a centre cross and its label; violet
    (``FIELD_ALARM_RGB``) in collision alarm, else green."""
    import cv2

    colour = FIELD_ALARM_RGB if f.collision else CALM_RGB
    cx, cy = int(round(f.x * scale_x)), int(round(f.y * scale_y))
    ax = max(1, int(round(f.radius * scale_x)))
    ay = max(1, int(round(f.radius * scale_y)))
    line = style.line + (1 if f.collision else 0)
    if shape == "disc":
        cv2.ellipse(img, (cx, cy), (ax, ay), 0, 0, 360, colour, line, cv2.LINE_AA)
    else:
        cv2.rectangle(img, (cx - ax, cy - ay), (cx + ax, cy + ay), colour, line)
    cv2.drawMarker(img, (cx, cy), colour, cv2.MARKER_CROSS, style.cross, style.line)
    text = f"#{f.id} {_fmt(f.response)}"
    h, w = img.shape[:2]
    edge = (line + 1) // 2
    left, top, bottom = cx - ax - edge, cy - ay - edge, cy + ay + edge
    if 0 <= cx - ax < w and 0 <= cy - ay < h:  # above the top-left corner, else below the bottom-left one
        candidates = [(left, top, "bottom"), (left, bottom, "top"), (left + 2 * edge, top + 2 * edge, "top")]
    else:  # a field larger than the frame (LPLC2's one cell): beside its centre
        candidates = [(cx + style.cross, cy - style.cross, "bottom"), (cx + style.cross, cy + style.cross, "top")]
    labels.add(text, colour, *candidates)


def _fmt(v: float) -> str:
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"
