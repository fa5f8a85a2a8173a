"""The figures of ``mlplc2 reproduce`` (the paper's Fig. 3-6), from the traces of
:func:`mlplc2.reproduce.reproduce`.

Matplotlib is imported inside the functions (Agg canvas, no pyplot, no global
backend change), so importing :mod:`mlplc2` stays light.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._validation import LUMA_RGB
from ..plots import colours as _colours, figure, gap_segments, save_png
from ..evaluation.match import DEFAULT_MATCH_RADIUS, fields_near
from .claims import LABELS, MODELS, STIMULUS_LABELS

__all__ = ["fig3_selectivity", "fig4_four_phases", "fig5_six_objects", "fig6_real_clips", "size_profile"]


def _gray(frame) -> np.ndarray:
    a = np.asarray(frame)
    if a.ndim == 3:
        a = a[..., :3].astype(np.float32) @ LUMA_RGB
    return a


def size_profile(obj, n: int) -> np.ndarray:
    """Side length (px) of a square object (:class:`mlplc2.evaluation.truth.ObjectTruth`) at every frame:
    its ``sizes`` if given, else from its phases (the paper's squares grow and shrink by 2 px
    per frame)."""
    s = np.zeros(n)
    if obj.sizes:
        v = np.asarray(obj.sizes, float)[:n]
        s[:v.size] = v
        return s
    side = 0.0
    if obj.approach:
        a0, a1 = obj.approach
        t = np.arange(a0, min(a1, n))
        s[t] = 2.0 * (t - a0 + 1)
        side = 2.0 * (a1 - a0)
    if obj.hold:
        h0, h1 = obj.hold
        s[h0:min(h1, n)] = side
    if obj.recede:
        r0, r1 = obj.recede
        t = np.arange(r0, min(r1, n))
        s[t] = np.maximum(side - 2.0 * (t - r0), 0)
    return s


def _presence_bars(ax, objects, n: int, colours) -> None:
    """Object presence: one lane per object; the bar spans the frames where the
    object is visible and its height follows the object's side length (legend: the centres)."""
    profiles = [size_profile(o, n) for o in objects]
    smax = max((float(p.max()) for p in profiles), default=1.0) or 1.0
    x = np.arange(n)
    k = len(objects)
    for i, (o, c, s) in enumerate(zip(objects, colours, profiles)):
        base = k - 1 - i
        ax.fill_between(x, base, base + 0.85 * s / smax, where=s > 0, color=c, alpha=0.8, step="mid", lw=0,
                        label=f"object {o.id} at ({o.center[0]:.0f}, {o.center[1]:.0f})")
    ax.set_yticks([k - 1 - i + 0.4 for i in range(k)])
    ax.set_yticklabels([f"obj {o.id}" for o in objects], fontsize=7)
    ax.set_ylim(0, k)
    ax.set_ylabel(f"objects\n(bar height = side,\nmax {smax:.0f} px)", fontsize=8)
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)


def _field_lines(ax, trace, colours_by_id, *, normalise: float | None = None, top: int = 14) -> None:
    """One line per field (gaps where it did not exist), alarm onsets marked."""
    from matplotlib.lines import Line2D

    fields = list(trace.fields.values())
    ranked = sorted(fields, key=lambda f: -f.peak)
    shown = {f.id for f in ranked[:top]}
    for f in sorted(fields, key=lambda f: f.id):
        fr, val = gap_segments(f.frames, f.responses)
        if normalise:
            val = val / normalise
        if f.id in shown:
            c = colours_by_id[f.id]
            ls = "--" if any(colours_by_id.get(g) == c for g in trace.fields if g < f.id) else "-"
            died = "end" if f.last == trace.n_frames - 1 else str(f.last + 1)
            alarm = "" if f.first_alarm is None else f", alarm {f.first_alarm}"
            ax.plot(fr, val, color=c, lw=1.5, ls=ls, label=f"#{f.id} ({f.x:.0f}, {f.y:.0f}) {f.born}-{died}{alarm}")
            if f.first_alarm is not None:
                k = f.frames.index(f.first_alarm)
                v = f.responses[k] / normalise if normalise else f.responses[k]
                ax.plot([f.first_alarm], [v], marker="v", color=c, ms=7, mec="k", mew=0.5, zorder=4)
        else:
            ax.plot(fr, val, color="0.65", lw=0.7)
    handles, labels = ax.get_legend_handles_labels()
    if len(fields) > top:
        handles.append(Line2D([], [], color="0.65", lw=0.7))
        labels.append(f"{len(fields) - top} more fields (small peaks)")
    if any(f.first_alarm is not None for f in fields):
        handles.append(Line2D([], [], ls="", marker="v", color="0.3", ms=7))
        labels.append("first alarm")
    if not fields:
        ax.text(0.5, 0.5, "no field created", transform=ax.transAxes, ha="center", va="center", color="0.4")
    else:
        ax.legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False,
                  title="field (x, y) born-died", title_fontsize=7)


def _field_colours(trace, objects=None, object_colours=None, radius: float = DEFAULT_MATCH_RADIUS) -> dict:
    """Colour per field id: the colour of the object it sits on (born while the object is
    present, within ``radius`` px: :func:`mlplc2.evaluation.match.fields_near`) when ``objects`` are
    given, else a palette; fields on no object get shades of a second palette."""
    from matplotlib import colormaps

    ids = sorted(trace.fields)
    if not objects:
        return dict(zip(ids, _colours(len(ids))))
    present = [np.nonzero(size_profile(o, trace.n_frames) > 0)[0] for o in objects]
    out, spare = {}, 0
    other = colormaps["Dark2"]
    for fid in ids:
        match = next((c for o, c, p in zip(objects, object_colours, present)
                      if p.size and fields_near([trace.fields[fid]], o, p[0], p[-1] + 1, radius)), None)
        if match is None:
            match = other(spare % 8)
            spare += 1
        out[fid] = match
    return out


def _draw_fields(ax, trace, frame_index: int, colours_by_id) -> None:
    from matplotlib.patches import Rectangle

    for f in trace.fields.values():
        if frame_index not in f.frames:
            continue
        alarm = frame_index in f.alarms
        ax.add_patch(Rectangle((f.x - f.radius, f.y - f.radius), 2 * f.radius, 2 * f.radius, fill=False,
                               ec=colours_by_id.get(f.id, "w"), lw=2.2 if alarm else 1.2,
                               ls="-" if alarm else "--"))
        ax.plot([f.x], [f.y], marker="+", color=colours_by_id.get(f.id, "w"), ms=8, mew=1.5)
        ax.text(f.x + 3, f.y - 3, f"#{f.id}" + (" ALARM" if alarm else ""), color="w", fontsize=6,
                bbox=dict(boxstyle="square,pad=0.1", fc=colours_by_id.get(f.id, "k"), ec="none", alpha=0.8))


def _key_frames(subfig, scene, trace, indices, colours_by_id, object_colours) -> None:
    """One row of key frames ``indices`` on ``subfig``: the fields of ``trace`` and the true
    centres of the objects present (``x``, in their ``object_colours``)."""
    for ax, t in zip(np.atleast_1d(subfig.subplots(1, len(indices))), indices):
        ax.imshow(_gray(scene.frames[t]), cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        if trace is not None:
            _draw_fields(ax, trace, t, colours_by_id)
        for o, c in zip(scene.objects, object_colours):
            if size_profile(o, scene.n)[t] > 0:
                ax.plot([o.center[0]], [o.center[1]], marker="x", color=c, ms=6, mew=1.5)
        ax.set_title(f"frame {t}", fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    subfig.suptitle("key frames with the mLPLC2 fields (dashed square; solid = in alarm; x = true object centre)",
                    fontsize=9)


# ---------------------------------------------------------------------------
# Fig. 3
# ---------------------------------------------------------------------------
def fig3_selectivity(basic: dict, traces: dict, path, *, source: str = "", dpi: int = 110) -> Path:
    """Fig. 3: 6 basic stimuli (columns) x LGMD2, LPLC2, sLPLC2, mLPLC2 (rows),
    response against frame, stimulus snapshots (frames 5, 25, 45) on top."""
    names = list(basic)
    models = [m for m in MODELS if m in traces]
    fig = figure(2.5 * len(names) + 0.6, 1.4 + 1.9 * len(models) + 0.9)
    gs = fig.add_gridspec(len(models) + 1, len(names), height_ratios=[0.9] + [1.0] * len(models))
    from matplotlib.lines import Line2D

    for j, name in enumerate(names):
        sc = basic[name]
        ax = fig.add_subplot(gs[0, j])
        picks = [t for t in (5, 25, 45) if t < sc.n] or [0]
        strip = []
        for t in picks:
            g = _gray(sc.frames[t])
            strip += [g, np.full((g.shape[0], 3), 128.0)]
        ax.imshow(np.hstack(strip[:-1]), cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(STIMULUS_LABELS.get(name, name), fontsize=10, fontweight="bold")
        ax.set_xlabel("frames " + ", ".join(map(str, picks)), fontsize=7)
    for i, m in enumerate(models):
        ymax = max(float(traces[m][n].response.max()) for n in names)
        ymin = 0.5 if m.startswith("lgmd") else 0.0
        dark = float(traces[m]["dark_approach"].response.max()) if "dark_approach" in traces[m] else 0.0
        for j, name in enumerate(names):
            ax = fig.add_subplot(gs[i + 1, j])
            r = traces[m][name].response
            ax.plot(np.arange(r.size), r, color="k", lw=1.4)
            if m.startswith("lgmd"):
                ax.axhline(0.5, color="tab:blue", lw=0.8, ls=":")
                ax.set_ylim(0.48, max(ymax, 0.55) + 0.12)  # headroom for the peak label
            else:
                ax.axhline(0.05 * dark, color="tab:red", lw=0.8, ls="--")
                ax.set_ylim(ymin - 0.03 * max(ymax, 1), max(ymax, 1) * 1.3)  # headroom for the peak label
            ax.set_xlim(0, max(r.size - 1, 1))
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
            if j == 0:
                unit = "membrane potential" if m.startswith("lgmd") else "response (a.u.)"
                ax.set_ylabel(f"{LABELS[m]}\n{unit}", fontsize=9)
            else:
                ax.set_yticklabels([])
            if i == len(models) - 1:
                ax.set_xlabel("frame (30 fps)", fontsize=8)
            else:
                ax.set_xticklabels([])
            ax.text(0.97, 0.93, f"peak {r.max():.3g}" if r.max() < 100 else f"peak {r.max():.0f}",
                    transform=ax.transAxes, ha="right", va="top", fontsize=7, color="0.3",
                    bbox=dict(boxstyle="square,pad=0.15", fc="white", ec="none", alpha=0.85))
    handles = [Line2D([], [], color="k", lw=1.4), Line2D([], [], color="tab:red", lw=0.8, ls="--"),
               Line2D([], [], color="tab:blue", lw=0.8, ls=":")]
    labels = ["model response (LGMD2: membrane potential after SFA; LPLC2 family: largest field response)",
              "5 % of the model's dark-approach peak (selectivity threshold)", "LGMD2 resting potential 0.5"]
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle("Fig. 3 - responses to the six basic motion patterns (100x100 px, 50 frames)"
                 + (f"\ninput: {source}" if source else ""), fontsize=11)
    return save_png(fig, path, dpi)


# ---------------------------------------------------------------------------
# Fig. 4
# ---------------------------------------------------------------------------
def fig4_four_phases(scene, traces: dict, path, *, source: str = "", dpi: int = 110, note: str | None = None) -> Path:
    """Fig. 4: four-phase scene; key frames, object presence, LGMD2, LPLC2, sLPLC2
    and every mLPLC2 field (centre in the legend)."""
    models = [m for m in MODELS if m in traces]
    n = scene.n
    tr = traces.get("mlplc2")
    ocol = _colours(len(scene.objects))
    cols = _field_colours(tr, scene.objects, ocol) if tr is not None else {}
    keys = [t for t in (30, 130, 230, 330) if t < n]
    if len(keys) < 4:
        keys = [min(30 + 100 * k, n - 1) for k in range(max(1, n // 100))]
    fig = figure(13.5, 3.0 + 1.1 + 2.0 * len(models))
    sub = fig.subfigures(2, 1, height_ratios=[2.4, 1.1 + 2.0 * len(models)])
    _key_frames(sub[0], scene, tr, keys, cols, ocol)
    axes = sub[1].subplots(len(models) + 1, 1, sharex=True, height_ratios=[0.8] + [1.0] * len(models))
    _presence_bars(axes[0], scene.objects, n, ocol)
    for k in range(1, n // 100):
        for ax in axes:
            ax.axvline(100 * k, color="0.5", lw=0.8, ls=":")
    for ax, m in zip(axes[1:], models):
        if m == "mlplc2":
            _field_lines(ax, tr, cols)
            ax.set_ylabel("mLPLC2\nfield response (a.u.)", fontsize=8)
        else:
            r = traces[m].response
            unit = "membrane potential" if m.startswith("lgmd") else "response (a.u.)"
            ax.plot(np.arange(r.size), r, color="k", lw=1.2, label=LABELS[m])
            if m.startswith("lgmd"):
                ax.axhline(0.5, color="tab:blue", lw=0.8, ls=":", label="resting potential")
                ax.set_ylim(0.49, max(0.8, float(r.max()) + 0.02))
            ax.set_ylabel(f"{LABELS[m]}\n{unit}", fontsize=8)
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
        ax.grid(alpha=0.3)
        ax.set_title(LABELS[m] + (": every attention field (colour = the object it sits on, "
                                          "dashed = a later field on the same object)" if m == "mlplc2" else ""),
                     fontsize=9, loc="left")
    for k in range(max(1, n // 100)):
        axes[0].text(100 * k + 50, 1.02, f"phase {k + 1}", transform=axes[0].get_xaxis_transform(),
                     ha="center", va="bottom", fontsize=8)
    axes[-1].set_xlabel("frame (30 fps); dotted lines: phase boundaries")
    axes[-1].set_xlim(0, max(n - 1, 1))
    fig.suptitle("Fig. 4 - four phases: dark objects approach (40 frames), hold (20), recede (40) "
                 "on a background scrolling left" + (f" [{note}]" if note else "")
                 + (f"\ninput: {source}" if source else ""), fontsize=11)
    return save_png(fig, path, dpi)


# ---------------------------------------------------------------------------
# Fig. 5
# ---------------------------------------------------------------------------
def fig5_six_objects(scene, trace, path, *, source: str = "", dpi: int = 110) -> Path:
    """Fig. 5: six staggered objects; key frames, object presence and every mLPLC2 field."""
    n = scene.n
    ocol = _colours(len(scene.objects))
    cols = _field_colours(trace, scene.objects, ocol)
    keys = [t for t in (20, 50, 80, 110) if t < n] or [n - 1]
    fig = figure(13.5, 8.2)
    sub = fig.subfigures(2, 1, height_ratios=[2.4, 4.4])
    _key_frames(sub[0], scene, trace, keys, cols, ocol)
    ax0, ax1 = sub[1].subplots(2, 1, sharex=True, height_ratios=[0.8, 1.4])
    _presence_bars(ax0, scene.objects, n, ocol)
    ax0.set_title("objects present (each disappears after a 10-frame hold)", fontsize=9, loc="left")
    _field_lines(ax1, trace, cols)
    ax1.set_ylabel("mLPLC2 field response (a.u.)")
    ax1.set_title("mLPLC2: every attention field (colour = the object it sits on, dashed = a later field "
                  "on the same object)", fontsize=9, loc="left")
    ax1.grid(alpha=0.3)
    ax1.set_xlabel("frame (30 fps)")
    ax1.set_xlim(0, max(n - 1, 1))
    fig.suptitle("Fig. 5 - six dark objects appear at frames 5, 15, 25, 45, 55, 65 and expand"
                 + (f"\ninput: {source}" if source else ""), fontsize=11)
    return save_png(fig, path, dpi)


# ---------------------------------------------------------------------------
# Fig. 6
# ---------------------------------------------------------------------------
def fig6_real_clips(clips: list, traces: dict, path, *, dpi: int = 110) -> Path:
    """Fig. 6: mLPLC2 on real clips; per clip a key frame (the frame of the largest
    response) with the fields drawn, and the normalised response of every field."""
    k = max(1, len(clips))
    fig = figure(14.0, 2.9 * k + 0.8)
    rows = np.atleast_1d(fig.subfigures(k, 1))
    for row, sc in zip(rows, clips):
        tr = traces[sc.name]
        cols = _field_colours(tr)
        axk, axr = row.subplots(1, 2, width_ratios=[1.0, 2.4])
        t = int(np.argmax(tr.response)) if tr.response.max() > 0 else sc.n // 2
        frame = np.asarray(sc.frames[t])
        axk.imshow(frame if frame.ndim == 3 else _gray(frame), cmap=None if frame.ndim == 3 else "gray",
                   interpolation="nearest")
        _draw_fields(axk, tr, t, cols)
        axk.set_xlim(0, frame.shape[1])
        axk.set_ylim(frame.shape[0], 0)
        axk.set_xticks([])
        axk.set_yticks([])
        axk.set_title(f"{sc.source}, frame {t} (largest response)", fontsize=8)
        peak = max((f.peak for f in tr.fields.values()), default=0.0)
        _field_lines(axr, tr, cols, normalise=peak if peak > 0 else None, top=10)
        axr.axvline(t, color="0.4", lw=0.8, ls=":")
        axr.set_xlim(0, max(sc.n - 1, 1))
        axr.set_ylabel("normalised response\n(field / clip peak)", fontsize=8)
        axr.set_xlabel("frame (%g fps); dotted: key frame" % sc.fps, fontsize=8)
        axr.grid(alpha=0.3)
        axr.set_title(f"mLPLC2 on {sc.source}: {len(tr.fields)} fields, {len(tr.alarmed())} in alarm",
                      fontsize=9, loc="left")
    fig.suptitle("Fig. 6 - mLPLC2 on real UAV clips (fields: dashed square, solid = in alarm; "
                 "responses normalised by the clip's largest field response)\n", fontsize=11)
    return save_png(fig, path, dpi)
