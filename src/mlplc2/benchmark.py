"""``mlplc2 benchmark``: the standard suite of realistic approaches, every model, one report.

One command measures how early and how reliably each model warns (``docs/benchmark.md``):

1. **Generated suite** (:func:`suite`): fixed seeds of :func:`mlplc2.stimuli.random_scene`,
   3-D scenes with exact ground truth (collisions, pass-bys, receding, translating and
   static distractors; plain and textured backgrounds, a panning and a tilting camera,
   forward ego-motion over a textured ground) and the settings of real use (:data:`REAL_USE`:
   a dashcam drive, a drone, a hand-held camera; :mod:`mlplc2.stimuli.world.realuse`),
   320x240 at 30 fps, written losslessly (FFV1 ``.mkv``, byte-reproducible) with their ground
   truth (``scenes/``; reused when already there).
2. **Real clips**, when ``../shared/data/real`` is present: its clips (not the full-resolution
   copies) and the paper's four UAV clips, with the hand labels of its ``ground_truth.json``.
3. Every model (:data:`MODELS`) runs on every video through :func:`mlplc2.batch.batch`
   (a local Dask cluster by default, ``scheduler=`` for a real one; finished tasks are kept).
4. :func:`mlplc2.evaluate` scores the runs: the warning metrics (collision objects
   warned before contact, lead time, false warnings by cause, time-to-contact errors,
   fragmentation, real clips warned / missed / false).
5. ``benchmark.md`` / ``.csv`` / ``.json`` (with a table per setting, still and moving
   cameras) and three plots: lead time per model, TTC estimate
   against the true TTC, false warnings by cause.

``quick=True`` runs a small subset (4 short scenes, no real clips) in well under a minute:
the test suite runs it.
"""

from __future__ import annotations

import json
import numbers
import time
import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from ._validation import InputValueError
from .models.base import PACKAGE_MODELS

__all__ = ["Scene", "suite", "benchmark", "by_setting", "BenchmarkResult", "BenchmarkWarning", "MODELS", "REAL_DIR",
           "SUITE_GT", "COLUMNS", "REAL_USE", "setting_names"]

#: Every model the benchmark compares, in table order (the optical-flow baseline last).
MODELS = PACKAGE_MODELS
#: Where the labelled real clips are looked for, relative to the current folder and to the checkout.
REAL_DIR = Path("..") / "shared" / "data" / "real"
#: File name of the generated suite's ground truth (in ``scenes/``).
SUITE_GT = "ground_truth.json"
#: The horizontal field of view (degrees) of the generated scenes' camera, unless ``--hfov`` says otherwise; the
#: models run without ``hfov_deg`` then, so the 60 degrees they assume is the truth.
SUITE_HFOV = 60.0


@dataclass(frozen=True)
class Scene:
    """One scene of the generated suite: the arguments of :func:`mlplc2.stimuli.random_scene`."""

    name: str
    seed: int
    background: str
    camera: str
    appearance: str | None = None
    duration_s: float = 6.0
    noise_std: float = 0.0
    blur_px: float = 0.0
    kinds: tuple[str, ...] | None = None
    index: int | None = None
    hfov_deg: float = 60.0

    def generate(self):
        from .stimuli import random_scene

        if self.camera in REAL_USE:
            from .stimuli.world.realuse import real_use_scene

            return real_use_scene(self.camera, self.index, self.seed, duration_s=self.duration_s,
                                  noise_std=self.noise_std, blur_px=self.blur_px, hfov_deg=self.hfov_deg)
        return random_scene(self.seed, background=self.background, camera=self.camera,
                            appearance=self.appearance, duration_s=self.duration_s, noise_std=self.noise_std,
                            blur_px=self.blur_px, kinds=self.kinds, hfov_deg=self.hfov_deg)


#: The settings of real use (:mod:`mlplc2.stimuli.world.realuse`), five scenes each, after the others.
REAL_USE = ("drive", "drone", "handheld")
#: The backgrounds and camera motions of the suite, five scenes each.
_SETTINGS = (("plain", "static"), ("texture", "static"), ("texture", "pan"), ("texture", "tilt"),
             ("ground", "forward"), ("ground", "static"))
_APPEARANCES = ("dark", "bright", "textured", None, None)
_DURATIONS = (5.0, 7.0, 10.0, 6.0, 8.0)
#: The objects of the five scenes of each setting: 5 collision objects (two at once in one
#: scene), 3 pass-bys and 3 other distractors per setting; one scene without a collision.
_KINDS = (("collision",), ("collision", "pass"), ("pass", "static", "translate"), ("collision", "recede"),
          ("collision", "collision", "pass"))


def suite(quick: bool = False, settings: Sequence[str] | None = None, holdout: int | Sequence[int] = 0,
          hfov_deg: float | None = None) -> list[Scene]:
    """The generated scenes: 30 (every background and camera motion of :data:`_SETTINGS` with
    dark, bright, textured and mixed objects, the objects of :data:`_KINDS`, 5-10 s, sensor
    noise and optics blur on every other scene) and 15 of real use (:data:`REAL_USE`), or 4
    short ones (``quick``).

    ``settings`` keeps only those settings (names as in :func:`setting_names`); ``holdout`` > 0
    draws every scene with other seeds (``seed + 1000 * holdout``, named ``..._hN``: other textures,
    speeds, turns and object paths in the same settings), for checking a figure on scenes nothing was tuned on;
    a sequence of holdouts gives each one's scenes in turn (0 the standard suite's), to pool them in one report.
    ``hfov_deg`` (None: :data:`SUITE_HFOV`, 60 degrees) renders every scene through a camera of that horizontal
    field of view (the same draws; named ``..._fD`` when it is not 60): a check of the defaults, set at 60, on the
    lenses of real cameras. The settings of real use place their objects in metres, so they are the same worlds
    seen through another lens (a wider one: smaller objects, more of the roadside); the other settings place each
    object by its width in the image at its onset (3-12 px), so their objects start as large as at 60 degrees,
    nearer, and the background's geometry changes with the lens."""
    if settings is not None:
        unknown = sorted(set(settings) - set(setting_names()))
        if unknown:
            raise InputValueError(f"unknown benchmark setting(s) {', '.join(unknown)}; "
                                  f"choose from {', '.join(setting_names())}")
    if quick:
        return [Scene("quick_plain_static", 901, "plain", "static", "dark", 4.0, kinds=("collision", "pass")),
                Scene("quick_texture_pan", 902, "texture", "pan", "bright", 4.0, noise_std=2.0,
                      kinds=("collision", "translate")),
                Scene("quick_ground_forward", 903, "ground", "forward", "textured", 4.0, kinds=("collision",)),
                Scene("quick_texture_static", 904, "texture", "static", None, 4.0, noise_std=2.0,
                      kinds=("collision", "recede", "pass"))]
    scenes = []
    for i, (bg, cam) in enumerate(_SETTINGS):
        for k in range(5):
            seed = 100 + 10 * i + k
            scenes.append(Scene(f"{bg}_{cam}_{k}", seed, bg, cam, _APPEARANCES[k], _DURATIONS[k],
                                noise_std=2.0 if k % 2 else 0.0, blur_px=0.5 if k % 2 else 0.0, kinds=_KINDS[k]))
    for i, use in enumerate(REAL_USE):
        for k in range(5):
            scenes.append(Scene(f"{use}_{k}", 300 + 10 * i + k, "ground", use, duration_s=_DURATIONS[k],
                                noise_std=2.0 if k % 2 else 0.0, blur_px=0.5 if k % 2 else 0.0,
                                index=k))
    if settings is not None:
        scenes = [sc for sc in scenes if _setting_of(sc) in settings]
    scenes = [sc if not h else replace(sc, name=f"{sc.name}_h{h}", seed=sc.seed + 1000 * h)
              for h in _holdouts(holdout) for sc in scenes]
    from .camera import check_hfov

    hfov = check_hfov(SUITE_HFOV if hfov_deg is None else hfov_deg)
    if hfov != SUITE_HFOV:
        scenes = [replace(sc, name=f"{sc.name}_f{hfov:g}", hfov_deg=hfov) for sc in scenes]
    return scenes


def setting_names() -> list[str]:
    """The settings of the full suite, in table order (``plain_static`` ... ``handheld``)."""
    return [f"{bg}_{cam}" for bg, cam in _SETTINGS] + list(REAL_USE)


def _holdouts(holdout: int | Sequence[int]) -> list[int]:
    """``holdout`` as the list of holdouts it names (each once, in order; 0 the standard suite)."""
    hs = [holdout] if isinstance(holdout, numbers.Integral) else list(holdout)
    if not hs or any(isinstance(h, bool) or not isinstance(h, numbers.Integral) or h < 0 for h in hs):
        raise InputValueError(f"holdout must be an integer >= 0 or a non-empty list of them, got {holdout!r}")
    return list(dict.fromkeys(int(h) for h in hs))


def _generate(scenes: Sequence[Scene], folder: Path, progress: bool) -> tuple[list[Path], Path]:
    """Write every scene's video and one ground-truth file; scenes already written with the same
    description are kept."""
    from ._files import write_json
    from ._progress import bar as progress_bar
    from .io import write_lossless_video

    folder.mkdir(parents=True, exist_ok=True)
    gt_path = folder / SUITE_GT
    old: dict = {}
    if gt_path.is_file():
        try:
            old = json.loads(gt_path.read_text(encoding="utf-8")).get("videos", {})
        except (json.JSONDecodeError, UnicodeDecodeError, AttributeError):
            old = {}
    videos, entries = [], {}
    for sc in progress_bar(scenes, desc="generating scenes", unit="scene", disable=not progress, leave=False):
        path = folder / f"{sc.name}.mkv"
        key = path.name
        spec = json.loads(json.dumps(asdict(sc)))      # as stored (tuples become lists)
        if path.is_file() and old.get(key, {}).get("scene") == spec:
            entries[key] = old[key]
        else:
            stim = sc.generate()
            write_lossless_video(path, stim.frames, stim.fps)
            entries[key] = {"scene": spec, **stim.to_ground_truth()}
        videos.append(path)
    write_json(gt_path, {"about": "mlplc2 benchmark: generated suite (mlplc2.benchmark.suite)",
                         "videos": entries}, indent=None)
    return videos, gt_path


def _real_inputs(real) -> tuple[list[Path], Path | None]:
    """The labelled real clips (``real`` folder and the paper's ``uav/`` beside it), and their labels."""
    if real is None:
        return [], None
    real = Path(real)
    gt = real / "ground_truth.json"
    if not gt.is_file():
        return [], None
    from .evaluation.truth import load

    truth = load(gt)
    return [p for base in (real, real.parent / "paper") for p in sorted(base.rglob("*"))
            if p.is_file() and "fullres" not in p.name and p.suffix.lower() in (".mp4", ".avi")
            and truth.match(p) is not None], gt


def default_real_dir() -> Path | None:
    """``../shared/data/real`` from the current folder, else beside the package's checkout."""
    here = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
    return next((cand for cand in (REAL_DIR, here) if (cand / "ground_truth.json").is_file()), None)


#: Columns of ``benchmark.csv`` (one row per model).
COLUMNS = ("model", "collision_objects", "warned", "warned_pct", "lead_median_s", "lead_p10_s", "warnings_lapsed",
           "ttc_at_warning_median_s", "false_frames_per_1000", "false_frames_pct", "false_episodes_per_1000",
           "false_episodes_pass", "false_episodes_distractor", "false_episodes_background",
           "ttc_rte_pct_0-1s", "ttc_rte_pct_1-3s", "ttc_rte_pct_3-6s", "ttc_mid_0-1s", "ttc_mid_1-3s",
           "ttc_mid_3-6s", "ttc_coverage_pct", "targets_per_object", "clips", "clips_warned", "clips_missed",
           "clips_false", "clip_lead_median_s", "ms_per_frame")


class BenchmarkWarning(UserWarning):
    """A batch task of the benchmark that failed (not scored) or whose video stopped decoding
    early (scored as far as it decoded); one line each, also in ``benchmark.md`` / ``.json``."""


@dataclass
class BenchmarkResult:
    """What :func:`benchmark` measured (also in ``benchmark.json``).

    ``failed``: one dict per batch task that did not finish cleanly (``video``, ``model`` label,
    ``status`` ``"error"`` or ``"truncated"``, ``error``, ``out``): a failed task leaves its model
    without results on that video, so that model's metrics do not count it."""

    rows: list[dict]
    evaluation: Any
    scenes: list[str]
    clips: list[str]
    seconds: float
    files: dict[str, Path] = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    failed: list[dict] = field(default_factory=list)
    settings_table: list[dict] = field(default_factory=list)

    def to_markdown(self) -> str:
        return _markdown(self)


def _row(model: str, summary: dict, ms: float | None) -> dict:
    w = summary.get("warnings") or {}

    def pct(v):
        return None if v is None else round(100.0 * v, 1)

    c = w.get("false_episodes_per_1000_by_cause") or {}
    row = {k: w.get(k) for k in COLUMNS}  # most columns are the warning metric of that name
    row.update(model=model, warned_pct=pct(w.get("warned_rate")), false_episodes_pass=c.get("pass"),
               false_episodes_distractor=c.get("distractor"), false_episodes_background=c.get("background"),
               ttc_coverage_pct=pct(w.get("ttc_coverage")), targets_per_object=w.get("fragmentation"),
               ms_per_frame=None if ms is None else round(ms, 2))
    return row


def _setting_of(sc: Scene) -> str:
    """The setting a scene belongs to: ``background_camera``, or the setting of real use."""
    return sc.camera if sc.camera in REAL_USE else f"{sc.background}_{sc.camera}"


def by_setting(ev, scenes: Sequence[Scene], models: Sequence[str]) -> list[dict]:
    """Per setting of the generated suite, then for the still and the moving cameras together: per
    model the collision objects warned before contact (of those scored), those not scored because
    they were out of view or hidden in their last second (``unseen``), and the false-warning episodes per 1000 scored frames (from ``ev.warning_objects`` / ``ev.warning_videos``)."""
    group = {f"{sc.name}.mkv": _setting_of(sc) for sc in scenes}
    still = {_setting_of(sc): sc.camera == "static" for sc in scenes}
    names = list(dict.fromkeys(group.values()))
    rows = []
    for label, members in [(n, {n}) for n in names] + [
            ("still camera", {n for n in names if still[n]}), ("moving camera", {n for n in names if not still[n]})]:
        row = {"setting": label, "scenes": sum(1 for g in group.values() if g in members)}
        for m in models:
            objs = [o for o in ev.warning_objects if o["model"] == m and group.get(o["video"]) in members
                    and o.get("contact_frame") is not None]
            vids = [v for v in ev.warning_videos if v["model"] == m and group.get(v["video"]) in members]
            frames = sum(v["frames_scored"] for v in vids)
            row[m] = {"warned": sum(1 for o in objs if o["warned"]), "collision_objects": len(objs),
                      "unseen": sum(v.get("collision_objects_unseen", 0) for v in vids),
                      "false_episodes_per_1000": round(1000.0 * sum(v["false_episodes"] for v in vids) / frames, 2)
                      if frames else None}
        rows.append(row)
    return rows


def _setting_markdown(rows: list[dict], models: Sequence[str]) -> list[str]:
    """The per-setting table of ``benchmark.md``: warned / collision objects, false episodes per 1000 frames."""
    if not rows:
        return []
    lines = ["", "Per setting (warned / collision objects, + those out of view before contact, not scored; "
             "false-warning episodes per 1000 frames):", "",
             "| setting | scenes | " + " | ".join(models) + " |", "|" + "|".join(["---"] * (len(models) + 2)) + "|"]
    for r in rows:
        cells = [f"{r[m]['warned']}/{r[m]['collision_objects']}"
                 + (f" (+{r[m]['unseen']} unseen)" if r[m].get("unseen") else "")
                 + f"; {_fmt(r[m]['false_episodes_per_1000'])}" for m in models]
        lines.append(f"| {r['setting']} | {r['scenes']} | " + " | ".join(cells) + " |")
    return lines


def _fmt(v, digits: int = 2) -> str:
    if v is None:
        return "-"
    return f"{v:.{digits}f}" if isinstance(v, float) else str(v)


def _holdout_text(holdout: int | list[int]) -> str:
    """``holdout`` as the report names it: ``7``, or runs of consecutive holdouts, ``0, 21-43``."""
    hs = [holdout] if isinstance(holdout, int) else sorted(holdout)
    runs: list[list[int]] = []
    for h in hs:
        if runs and h == runs[-1][1] + 1:
            runs[-1][1] = h
        else:
            runs.append([h, h])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs)


#: Below the table of ``benchmark.md``: what its columns mean, in short (docs/benchmark.md, "What it measures").
_LEGEND = (
    "Columns: *warned*: collision objects warned before contact (a warning on the object); *lead*: how long "
    "before contact the first warning came (median, 10th percentile); *lapsed*: warned objects whose warning then "
    "went silent for 0.2 s or more before contact; *false episodes*: runs of frames warning of something that will "
    "not hit, per 1000 frames, and by cause; *false frames*: frames with a false warning; *TTC error*: median "
    "relative error of the time to contact per bin of the true one; *TTC coverage*: frames of a collision object "
    "(16 px or wider) with an estimate on it; *targets/object*: targets that stood for one collision object (1 is "
    "ideal); *real clips*: the labelled clips warned, missed, with a false warning, and their median lead; "
    "*ms/frame*: a task's wall time per frame (decoding and writing included, on a shared machine: `mlplc2 bench` "
    "measures the model). `evaluation.md` beside this file scores the paper's field alarms and object "
    "detections on the same runs. Every definition: docs/benchmark.md, \"What it measures\".")


def _markdown(res: BenchmarkResult) -> str:
    st = res.settings
    hold = st.get("holdout") or 0
    drawn = "" if hold == 0 else f", holdout{'s' if isinstance(hold, list) else ''} {_holdout_text(hold)}"
    lines = [f"Generated suite: {len(res.scenes)} scenes ({st.get('frames', 0)} frames{drawn}); real clips: "
             f"{len(res.clips)}; {res.seconds:.0f} s.", "",
             "| model | warned | lead median (s) | lead p10 (s) | lapsed | false episodes /1000 fr | false frames (%) "
             "| pass / distractor / background (episodes /1000) | TTC error 0-1 s | 1-3 s | 3-6 s "
             "| TTC coverage | targets/object | real clips warned | missed | false | lead (s) | ms/frame |",
             "|" + "|".join(["---"] * 18) + "|"]
    for r in res.rows:
        lines.append(
            f"| {r['model']} | {_fmt(r['warned'])}/{_fmt(r['collision_objects'])} ({_fmt(r['warned_pct'], 0)} %) "
            f"| {_fmt(r['lead_median_s'])} | {_fmt(r['lead_p10_s'])} | {_fmt(r['warnings_lapsed'])} "
            f"| {_fmt(r['false_episodes_per_1000'])} "
            f"| {_fmt(r['false_frames_pct'])} | {_fmt(r['false_episodes_pass'])} / {_fmt(r['false_episodes_distractor'])} "
            f"/ {_fmt(r['false_episodes_background'])} "
            + "".join(f"| {_fmt(r[f'ttc_rte_pct_{b}'], 0)}{'' if r[f'ttc_rte_pct_{b}'] is None else ' %'} "
                      for b in ("0-1s", "1-3s", "3-6s"))
            + f"| {_fmt(r['ttc_coverage_pct'], 0)}{'' if r['ttc_coverage_pct'] is None else ' %'} "
            f"| {_fmt(r['targets_per_object'])} | "
            + (f"{_fmt(r['clips_warned'])}/{_fmt(r['clips'])} | {_fmt(r['clips_missed'])} | {_fmt(r['clips_false'])} "
               f"| {_fmt(r['clip_lead_median_s'])} " if r['clips'] else "- | - | - | - ")
            + f"| {_fmt(r['ms_per_frame'])} |")
    lines += ["", _LEGEND]
    positionless = res.evaluation.position_notes() if res.evaluation is not None else []
    if positionless:
        lines += ["", *positionless]
    lines += _setting_markdown(res.settings_table, [r["model"] for r in res.rows])
    clip = res.evaluation.clip_warning_table() if res.evaluation is not None else ""
    if clip:
        lines += ["", "Real clips:", "", clip]
    if res.failed:
        lines += ["", f"Tasks that did not finish cleanly ({len(res.failed)}; a failed task's model has no results "
                      f"on that video, and its metrics above leave the video out):", ""]
        lines += [f"- {_failure(f)}" for f in res.failed]
    return "\n".join(lines) + "\n"


def _failure(f: dict) -> str:
    """One line on a task that did not finish cleanly."""
    what = "failed, not scored" if f["status"] == "error" else "stopped decoding early, scored as far as it decoded"
    return f"{f['video']} ({f['model']}, runs/{f['out']}): {what}: {f['error']}"


def _plots(res: BenchmarkResult, out: Path) -> dict[str, Path]:
    """lead_time.png, ttc.png, false_warnings.png (:func:`mlplc2.plots.figure`, written atomically)."""
    from .plots import figure, save_png

    ev = res.evaluation
    models = [r["model"] for r in res.rows]
    files = {}

    def save(fig, name: str) -> None:
        files[name] = save_png(fig, out / name, dpi=110)

    # lead time per model
    width = max(4.2, 1.2 + 1.1 * len(models))     # the title's two lines fit over one or two models
    fig = figure(width, 3.6)
    ax = fig.subplots()
    for i, m in enumerate(models):
        objs = [o for o in ev.warning_objects if o["model"] == m and o["object"] != "collider"
                and o.get("contact_frame") is not None]
        leads = [o["lead_s"] for o in objs if o["warned"] and o["lead_s"] is not None]
        missed = sum(1 for o in objs if not o["warned"])
        ax.scatter([i + (k % 7 - 3) * 0.04 for k in range(len(leads))], leads, s=10, alpha=0.7)
        if missed:
            ax.text(i, -0.15, f"{missed} missed", ha="center", va="top", fontsize=7, color="crimson")
    ax.axhline(0.25, color="grey", lw=0.8, ls="--")
    ax.set_xticks(range(len(models)), models)
    ax.set_xlim(-0.6, len(models) - 0.4)
    ax.set_ylabel("lead time before contact (s)")
    ax.set_ylim(bottom=-0.5)
    ax.set_title("Collision objects of the generated suite:\nwarning lead time", fontsize=10)
    save(fig, "lead_time.png")
    # TTC estimate against truth
    with_ttc = [m for m in models if any(o["ttc_errors"] for o in ev.warning_objects if o["model"] == m)]
    if with_ttc:
        fig = figure(3.0 * len(with_ttc), 3.2)
        axes = fig.subplots(1, len(with_ttc), squeeze=False)[0]
        for ax, m in zip(axes, with_ttc):
            pts = [e for o in ev.warning_objects if o["model"] == m for e in o["ttc_errors"]]
            ax.scatter([t for t, _ in pts], [e for _, e in pts], s=3, alpha=0.3)
            ax.plot([0, 6], [0, 6], color="grey", lw=0.8)
            ax.set_xlim(0, 6)
            ax.set_ylim(0, 8)
            ax.set_title(m, fontsize=9)
            ax.set_xlabel("true TTC (s)")
        axes[0].set_ylabel("estimated TTC (s)")
        save(fig, "ttc.png")
    # false warnings by cause
    fig = figure(width, 3.4)
    ax = fig.subplots()
    bottom = [0.0] * len(models)
    for cause, key in (("pass-by", "false_episodes_pass"), ("distractor", "false_episodes_distractor"),
                       ("background", "false_episodes_background")):
        vals = [r[key] or 0.0 for r in res.rows]
        ax.bar(range(len(models)), vals, bottom=bottom, label=cause)
        bottom = [b + v for b, v in zip(bottom, vals)]
    ax.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax.set_xticks(range(len(models)), models)
    ax.set_ylabel("false-warning episodes per 1000 frames")
    ax.legend(fontsize=7)
    ax.set_title("False warnings on the generated suite,\nby cause", fontsize=10)
    save(fig, "false_warnings.png")
    return files


def _stabilise(stabilise) -> bool:
    """Whether the run stabilises the gaze: ``stabilise``, or the runner's default when None."""
    from .runner import RunOptions

    return RunOptions.stabilise if stabilise is None else bool(stabilise)


def benchmark(out, *, quick: bool = False, models: Sequence[str] | str | None = None, real="auto",
              scheduler: str | None = None, workers: int | None = None, target_params=None,
              stabilise: bool | None = None, settings: Sequence[str] | None = None,
              holdout: int | Sequence[int] = 0, hfov_deg: float | None = None, progress: bool = True,
              force: bool = False) -> BenchmarkResult:
    """Run the benchmark into folder ``out`` (see the module docstring).

    Parameters
    ----------
    out : path
        Output folder: ``scenes/`` (the generated videos and their truth), ``runs/`` (the batch),
        ``benchmark.md``, ``benchmark.csv``, ``benchmark.json``, ``evaluation.json`` and the plots.
    quick : bool
        4 short scenes and no real clips (the test suite's run).
    models : list of str, optional
        Registry names (default :data:`MODELS`).
    real : "auto", path or None
        Folder of the labelled real clips (``ground_truth.json`` inside): "auto" looks for
        :data:`REAL_DIR`; None leaves them out. Ignored with ``quick``.
    scheduler, workers
        As in :func:`mlplc2.batch.batch` (default: a local Dask cluster).
    target_params : TargetParams or dict, optional
        Target and warning settings for the models with targets (``horizon_s``, ``max_miss``, ...).
    stabilise : bool, optional
        Gaze stabilisation for the models that have it; None: the runner's default, on
        (:attr:`mlplc2.runner.RunOptions.stabilise`).
    settings : list of str, optional
        Only these settings of the generated suite (:func:`setting_names`; default all). Not with ``quick``.
    holdout : int or sequence of int
        0 for the standard suite; N > 0 draws every scene with other seeds (:func:`suite`); a sequence pools the
        scenes of those holdouts in one report (each setting's figures over all of them). Not with ``quick``.
    hfov_deg : float, optional
        Render the generated scenes through a camera of this horizontal field of view (degrees, in (0, 180);
        None: :data:`SUITE_HFOV`, 60) and give it to the models (``hfov_deg`` of :func:`mlplc2.run`, as a user who
        knows the lens would): how the defaults, set at 60, hold on another lens. Not with the real clips, whose
        field of view is their own (``real=None``), nor with ``quick``.
    progress : bool
        Progress bars on stderr.
    force : bool
        Rerun tasks already done.
    """
    from .batch import batch
    from .evaluator import EvaluationWarning, evaluate
    from .models.base import available_models, resolve_names
    from .targets import TargetParams

    t0 = time.perf_counter()
    holds = _holdouts(holdout)
    if quick and (settings is not None or holds != [0] or hfov_deg is not None):   # the full suite's scenes
        raise InputValueError("--settings, --holdout and --hfov choose among the full suite's scenes: not with "
                              "--quick (its own four scenes)")
    from .camera import check_hfov

    hfov = None if hfov_deg is None else check_hfov(hfov_deg)
    if hfov is not None and hfov != SUITE_HFOV and real is not None:
        raise InputValueError("--hfov renders the generated scenes through another lens; the real clips have their "
                              "own: add --no-real")
    models = resolve_names(models) if models else [m for m in MODELS if m in available_models()]
    tp = TargetParams.coerce(target_params, "target_params")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputValueError(f"{out}: is a file, expected a folder for the benchmark")
    real_dir = None if quick or real is None else (default_real_dir() if real == "auto" else Path(real))
    if real not in ("auto", None) and not quick and not (Path(real) / "ground_truth.json").is_file():
        raise InputValueError(f"{real}: no ground_truth.json there (the labelled real clips)")
    if real == "auto" and not quick and real_dir is None:
        warnings.warn(f"no labelled real clips found ({REAL_DIR} from here, nor beside the checkout): the report "
                      "has none; --real DIR gives them, --no-real leaves them out", BenchmarkWarning, stacklevel=2)
    scenes = suite(quick, settings=settings, holdout=holds, hfov_deg=hfov)
    videos, suite_gt = _generate(scenes, out / "scenes", progress)
    clips, real_gt = _real_inputs(real_dir)
    run_options = {}
    if tp is not None:
        run_options["target_params"] = {k: v for k, v in tp.to_dict().items() if getattr(type(tp)(), k) != v}
    if stabilise is not None:
        run_options["stabilise"] = bool(stabilise)
    if hfov is not None and hfov != SUITE_HFOV:
        run_options["hfov_deg"] = hfov
    res = batch([str(v) for v in videos + clips], out / "runs", models=models, scheduler=scheduler,
                workers=workers, run_options=run_options, progress=progress, force=force)
    failed, seen = [], set()
    for r in res.rows:  # once per task (a task shared by parameter sets has several rows)
        if r.get("status") not in (None, "ok") and r.get("out") not in seen:
            seen.add(r.get("out"))
            failed.append({"video": str(r.get("video")), "model": r.get("label") or r.get("model"),
                           "status": r["status"], "error": r.get("error") or "", "out": r.get("out")})
    for f in failed:
        warnings.warn(_failure(f), BenchmarkWarning, stacklevel=2)
    gts = [suite_gt] + ([real_gt] if real_gt is not None else [])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EvaluationWarning)
        ev = evaluate(out / "runs", gts, models=models)
    frames = sum(int(round(sc.duration_s * 30)) for sc in scenes)
    speed: dict[str, list[float]] = {}
    for r in res.rows:
        if r.get("seconds") and r.get("n_frames"):
            speed.setdefault(r["model"], []).append(1000.0 * float(r["seconds"]) / float(r["n_frames"]))
    rows = []
    for m in models:
        s = ev.models.get(m)
        if s is None:
            continue
        ms = sorted(speed.get(m, []))
        rows.append(_row(m, s, ms[len(ms) // 2] if ms else None))
    result = BenchmarkResult(rows, ev, [sc.name for sc in scenes], [str(c) for c in clips],
                             time.perf_counter() - t0,
                             settings={"quick": quick, "frames": frames, "models": models,
                                       "target_params": run_options.get("target_params", {}),
                                       "stabilise": _stabilise(stabilise),
                                       "holdout": holds[0] if len(holds) == 1 else holds,
                                       "hfov_deg": SUITE_HFOV if hfov is None else hfov,
                                       "settings": None if settings is None else list(settings),
                                       "real": None if real_dir is None else str(real_dir),
                                       "scheduler": res.scheduler}, failed=failed,
                             settings_table=by_setting(ev, scenes, [r["model"] for r in rows]))
    _write(result, out)
    return result


def _write(res: BenchmarkResult, out: Path) -> None:
    from ._files import write_csv, write_text

    write_text(out / "benchmark.md", "# mlplc2 benchmark\n\n" + res.to_markdown())
    write_text(out / "benchmark.json", json.dumps({"settings": res.settings, "models": res.rows, "scenes": res.scenes,
                                                   "by_setting": res.settings_table, "clips": res.clips,
                                                   "failed": res.failed,
                                                   "seconds": round(res.seconds, 1)}, indent=1) + "\n")
    write_csv(out / "benchmark.csv", res.rows, COLUMNS)
    files = {name: out / name for name in ("benchmark.md", "benchmark.json", "benchmark.csv")}
    files.update(res.evaluation.write(out))
    files.update(_plots(res, out))
    res.files = files

