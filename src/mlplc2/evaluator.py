"""The application of ``mlplc2 evaluate``: read run results (or run the models), score them
against ground truth, write the report. (``mlplc2.evaluator``, as ``mlplc2.runner`` is the
application of ``mlplc2 run``; the function :func:`evaluate` is ``mlplc2.evaluate``.)

Two kinds of truth (:mod:`mlplc2.evaluation.truth`; schema in ``docs/evaluation.md``):

object level
    the objects and their phases (the paper's ``ground_truth.json``), scored per approaching
    object: detected or not, latency to the first field within the match radius and to the
    first alarm, localisation error, fields created; and false alarms per minute of video.
clip level
    ``"label": "collision" | "no_collision"`` with an optional ``collision_frame``, scored as a
    binary classification (alarm before the collision frame = true positive, alarm in a
    no-collision clip = false positive): accuracy, precision, recall and the alarm's lead time (``warning_s``).

Truth that says which objects will hit (3-D objects with a ``kind``, labelled clips with the
collider's track) also gets the **warning metrics** (``docs/evaluation.md``, "Warning metrics";
:func:`mlplc2.evaluation.score.score_warnings`): collision objects warned before contact, lead
time, false warnings per 1000 frames by cause, time-to-contact errors (RTE, MiD) and coverage,
fragmentation, and per clip warned / missed / unplaced / false. The scores themselves are
:mod:`mlplc2.evaluation.score`; this module reads the inputs (:class:`~mlplc2.runner.RunResult`,
results folders, videos), orders the models and writes the tables.

:func:`evaluate` takes run results (a :class:`~mlplc2.runner.RunResult`, an
output folder with ``responses.csv`` and ``fields.json``, a ``mlplc2 batch``
folder) or videos (the models are run first) and returns an
:class:`Evaluation` with per-object, per-video and per-model tables, as
Markdown (:meth:`Evaluation.to_markdown`) and JSON (:meth:`Evaluation.to_dict`)."""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from ._validation import InputError, InputTypeError, InputValueError, check_int, check_real

from .evaluation.match import DEFAULT_MATCH_RADIUS, DEFAULT_TAIL
from .evaluation.record import TargetRow, read_responses, read_targets
from .evaluation.score import (EARLY_S, LATE_S, MID_INTERVAL_S, MIN_TTC_WIDTH, TTC_BINS, ModelRun, mid_error,
                               score_run, score_warnings, summarise, summarise_warnings, warning_truth)
from .evaluation.truth import KINDS, PHASES, GroundTruth, ObjectTruth, VideoTruth, read_json
from .evaluation.truth import load as load_ground_truth
from .models.base import PACKAGE_MODELS

__all__ = ["evaluate", "Evaluation", "EvaluationWarning", "load_ground_truth", "GroundTruth", "VideoTruth",
           "ObjectTruth", "PHASES", "KINDS", "DEFAULT_TAIL", "DEFAULT_MATCH_RADIUS", "TTC_BINS", "MIN_TTC_WIDTH",
           "EARLY_S", "LATE_S", "MID_INTERVAL_S", "mid_error"]

#: Row order of the comparison table (other registered models follow, alphabetically).
MODEL_ORDER = PACKAGE_MODELS


class EvaluationWarning(UserWarning):
    """Something :func:`evaluate` scored with a caveat or did not score (one line;
    also in :attr:`Evaluation.warnings`): an input given twice, incomplete results,
    an input that is neither results nor a video."""


# ---------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------
def _model_says(model: str, flag: str) -> bool:
    """The registered model's class attribute ``flag`` (``Model.localises``, ``Model.has_targets``);
    False for a model not registered. evaluate keeps no rule of its own."""
    from .models.base import REGISTRY

    return bool(getattr(REGISTRY.get(model), flag, False))


def _runs_from_rows(source, rows, fields_by_model, *, fps, size, start, n_frames, models, param_set=None,
                    params=None, origin="", ident=None, incomplete=None, video_known=True, target_rows=(),
                    targets_known=True):
    from .batch import param_label

    per: dict[str, ModelRun] = {}

    def new(m, fields):
        if params or param_set in (None, "", "default"):
            label = param_label(m, params)
        else:  # a parameter set whose overrides are not recorded
            label = f"{m}@{param_set}"
        return ModelRun(str(source), m, label, fps, size, start, n_frames, list(fields), {}, {}, param_set,
                        dict(params or {}), origin or str(source), ident, incomplete, video_known,
                        has_targets=_model_says(m, "has_targets") and targets_known,
                        localises=_model_says(m, "localises"))

    for r in rows:
        m = r["model"]
        if models is not None and m not in models:
            continue
        run = per.get(m)
        if run is None:
            run = per[m] = new(m, fields_by_model.get(m, []))
        f = int(r["frame"])
        coll = bool(int(r["collision"]))
        run.frame_alarm[f] = run.frame_alarm.get(f, False) or coll
        if r["field_id"] not in (None, ""):
            run.frame_fields.setdefault(f, []).append((int(r["field_id"]), float(r["x"]), float(r["y"]), coll))
    for m in fields_by_model:
        if m not in per and (models is None or m in models):
            per[m] = new(m, fields_by_model[m])
    for r in target_rows:
        run = per.get(r["model"])
        if run is not None:
            run.frame_targets.setdefault(int(r["frame"]), []).append(TargetRow.from_row(r))
    return list(per.values())


def _incomplete_reason(n_frames, interrupted, truncated, message=None, complete=True) -> str | None:
    """Why a run's results are incomplete (``None``: they are complete)."""
    if interrupted:
        return f"the run was interrupted after {n_frames} frames"
    if truncated:
        return f"the video stopped decoding after {n_frames} frames" + (f" ({message})" if message else "")
    if not complete:
        return f"the run is marked incomplete after {n_frames} frames"
    return None


def _runs_from_result(res, models, origin=None) -> list[ModelRun]:
    reason = _incomplete_reason(res.n_frames, getattr(res, "interrupted", False), getattr(res, "truncated", False),
                                getattr(res, "message", None))
    return _runs_from_rows(res.source, res.rows, res.fields, fps=res.fps, size=tuple(res.size), start=res.start,
                           n_frames=res.n_frames, models=models, origin=origin or f"a RunResult of {res.source}",
                           ident=("object", id(res)), incomplete=reason, target_rows=res.targets)


def _read_folder(folder: Path, models) -> list[ModelRun]:
    csv_path = folder / "responses.csv"
    rows = read_responses(csv_path)
    fj = folder / "fields.json"
    info = read_json(fj) if fj.is_file() else {}
    if not isinstance(info, Mapping):
        raise InputValueError(f"{fj}: not a fields.json of mlplc2 run (expected a JSON object)")
    dj = folder / "done.json"
    try:  # the batch's record of the task, if any (unreadable: none)
        done = json.loads(dj.read_text(encoding="utf-8")) if dj.is_file() else {}
    except (json.JSONDecodeError, UnicodeDecodeError):
        done = {}
    if not isinstance(done, Mapping):
        done = {}
    frames = sorted({int(r["frame"]) for r in rows})
    try:
        fps = info.get("fps")
        if not fps:
            times = [(int(r["frame"]), float(r["time_s"])) for r in rows if r.get("time_s") not in (None, "")]
            pos = [(fr, t) for fr, t in times if fr > 0 and t > 0]
            fps = pos[0][0] / pos[0][1] if pos else 30.0
        fps = float(fps)
        start = int(info.get("start", frames[0] if frames else 0))
        n_frames = int(info.get("n_frames", len(frames)))
        size = tuple(int(v) for v in info["size"]) if info.get("size") else None
    except (TypeError, ValueError):
        raise InputValueError(f"{fj if info else csv_path}: malformed fps, start, n_frames or size") from None
    if not math.isfinite(fps) or fps <= 0:
        raise InputValueError(f"{fj if info else csv_path}: fps must be a positive number, got {fps!r}")
    source = info.get("video") or done.get("video") or str(folder)
    try:  # the overrides a batch task ran with (JSON text in done.json)
        params = json.loads(done["params"]) if done.get("params") else {}
    except (TypeError, ValueError):
        params = {}
    if not isinstance(params, Mapping):
        params = {}
    if not info:
        incomplete = "no fields.json next to responses.csv, the run did not finish"
    else:
        incomplete = _incomplete_reason(n_frames, info.get("interrupted"), info.get("truncated"),
                                        complete=info.get("complete") is not False)
    tp = folder / "targets.csv"
    target_rows = read_targets(tp) if tp.is_file() else None  # None: older results, the alarm is the warning
    return _runs_from_rows(source, rows, info.get("models", {}), fps=fps, size=size, start=start,
                           n_frames=n_frames, models=models, param_set=done.get("param_set"), params=params,
                           origin=str(folder), ident=("path", _path_key(folder)), incomplete=incomplete,
                           video_known=bool(info.get("video") or done.get("video")), target_rows=target_rows or [],
                           targets_known=target_rows is not None)


def _path_key(path) -> str:
    return os.path.normcase(os.path.realpath(os.fspath(path)))


def _videos_without_results(folder: Path, found: list) -> list[str]:
    """Names of the video files directly in ``folder`` that none of the result folders ``found``
    (their ``fields.json`` ``"video"``) was made from."""
    from .io.formats import VIDEO_EXTENSIONS

    videos = sorted(q.name for q in folder.iterdir() if q.is_file() and q.suffix.lower() in VIDEO_EXTENSIONS)
    if not videos:
        return []
    done = set()
    for f in found:
        try:
            done.add(Path(str(json.loads((Path(f) / "fields.json").read_text()).get("video") or "")).name)
        except (OSError, ValueError, AttributeError):
            pass
    return [v for v in videos if v not in done]


def _expand_inputs(results, notes: list[str]) -> list:
    """The inputs, with folders holding results replaced by the result folders they
    contain, and other folders by the videos in them (:func:`mlplc2.io.expand_inputs`:
    a folder of images stays one input); an item given twice (the same folder, video or
    RunResult) is kept once, with a note in ``notes``."""
    from .runner import RunResult

    if results is None:
        raise InputValueError("no results to evaluate")
    if isinstance(results, (str, Path, RunResult)) or not isinstance(results, Iterable):
        results = [results]
    items = []
    seen: dict[Any, str] = {}  # key -> the input that gave it first
    for r in results:
        if isinstance(r, (str, Path)):
            p = Path(r)
            cands: list = [r]
            if p.is_dir() and not (p / "responses.csv").is_file():
                found = sorted(q.parent for q in p.rglob("responses.csv"))
                if found:
                    cands = found
                    left = _videos_without_results(p, found)
                    if left:  # such as clip_mlplc2/, the default output of `mlplc2 run clip.mp4`, beside other clips
                        notes.append(f"{r}: read as results ({len(found)} result folder(s) in it), so its "
                                     f"{len(left)} video(s) without results there are not run or scored: "
                                     f"{', '.join(left[:5])}{', ...' if len(left) > 5 else ''}; give the videos "
                                     f"by name to run the models on them")
                else:  # no results: its videos (or the folder, of images), as mlplc2 batch reads it
                    from .io import expand_inputs

                    try:
                        cands = expand_inputs([r])
                    except InputValueError:
                        pass  # neither videos nor images: reported by evaluate()
            keys = [("path", _path_key(c)) for c in cands]
        else:
            cands, keys = [r], [("object", id(r))]
        name = str(r if isinstance(r, (str, Path)) else getattr(r, "source", type(r).__name__))
        dup, earlier = 0, []
        for c, k in zip(cands, keys):
            if k in seen:
                dup += 1
                if seen[k] not in earlier:
                    earlier.append(seen[k])
                continue
            seen[k] = name
            items.append(c)
        if dup == len(cands):
            notes.append(f"{name}: given more than once; scored once" if earlier == [name] else
                         f"{name}: its results are already given by {', '.join(earlier)}; scored once")
        elif dup:
            notes.append(f"{name}: {dup} of its {len(cands)} result folders are also given by "
                         f"{', '.join(earlier)}; each is scored once")
    return items


# ---------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------
def _fmt(v, digits=1, pct=False) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if pct:
        return f"{100 * v:.0f}%"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


#: Model labels longer than this are shortened in the Markdown tables (the JSON keeps them whole).
LABEL_WIDTH = 40

#: The title of the clip-level table (:meth:`Evaluation.clip_table`): it scores the paper's field alarm, which a
#: clip's targets may not share (a TP there beside "warned: no" in the warnings on labelled clips).
CLIP_ALARM_TITLE = ("Field alarm on labelled clips (the paper's clip-level score: any field in collision alarm, "
                    "anywhere in the frame, before contact; for a model without fields its collision alarm; not the "
                    "targets' warning, below):\n\n")


@dataclass
class Evaluation:
    """What :func:`evaluate` computed.

    Attributes
    ----------
    models : dict
        Per model label, the summary over all videos: ``mlplc2``, or for batch
        results with non-default parameters the model and its overrides,
        ``mlplc2[r_af=30,t_a=8]`` (:func:`mlplc2.batch.param_label`); each
        summary also gives ``model_name``, ``param_set`` (the batch id) and
        ``params`` (the overrides, a dict).
    videos : list of dict
        One row per (model, video).
    objects : list of dict
        One row per (model, video, approaching object).
    settings : dict
        ``match_radius``, ``tail``, ground-truth source.
    skipped : list of str
        Inputs without ground truth (not scored).
    warnings : list of str
        One line per caveat, also issued as :class:`EvaluationWarning`: inputs
        given more than once (scored once), incomplete results (interrupted or
        truncated runs: approaching objects after the processed frames are not
        scored), inputs that are neither results nor videos (not scored).
    warning_videos : list of dict
        Warning metrics per (model, video) with 3-D or clip-level truth: false warnings by cause,
        the clip's outcome (``docs/evaluation.md``, "Warning metrics").
    warning_objects : list of dict
        Per (model, video, collision object): warned, lead time, true TTC at the warning,
        targets on it, and its TTC estimates (true, estimated) per frame.
    """

    models: dict[str, dict]
    videos: list[dict]
    objects: list[dict]
    settings: dict
    skipped: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    warning_videos: list[dict] = field(default_factory=list)
    warning_objects: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"settings": self.settings, "models": self.models, "videos": self.videos,
                "objects": self.objects, "warning_videos": self.warning_videos,
                "warning_objects": self.warning_objects, "skipped": self.skipped, "warnings": self.warnings}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), indent=kw.pop("indent", 1), **kw)

    def to_dataframe(self, kind: str = "objects"):
        """One of the tables as a pandas DataFrame,
        one row per dict, its keys the columns (as in ``evaluation.json``; docs/evaluation.md):

        ``"objects"`` (default)
            :attr:`objects`: one row per (model label, video, approaching object).
        ``"videos"``
            :attr:`videos`: one row per (model label, video).
        ``"models"``
            :attr:`models`: one row per model label (column ``model``), the summary.
        ``"warning_objects"``, ``"warning_videos"``
            :attr:`warning_objects`, :attr:`warning_videos`: the warning metrics.

        The ``model`` column holds the label (``mlplc2[t_a=8]`` for a batch parameter set);
        ``model_name`` and ``params`` of the ``"models"`` table give the model and its overrides.
        """
        tables = {"objects": self.objects, "videos": self.videos, "models": list(self.models.values()),
                  "warning_objects": self.warning_objects, "warning_videos": self.warning_videos}
        if kind not in tables:
            raise InputValueError(f"kind must be one of {', '.join(tables)}, got {kind!r}")
        import pandas as pd
        return pd.DataFrame(tables[kind])

    def _shown(self) -> tuple[dict[str, str], list[str]]:
        """Label -> what the Markdown tables show, and one note per model whose labels are
        shortened: a model with a label longer than :data:`LABEL_WIDTH` shows its labels
        without the overrides common to all of them (a leading ``…``, named in the note)
        and cut to that width."""
        from .batch import param_label

        shown = {lb: lb for lb in self.models}
        swept = {s["model_name"] for s in self.models.values() if s.get("params")}
        for lb, s in self.models.items():      # beside the same model's other parameter sets: say it
            if not s.get("params") and s["model_name"] in swept and lb == s["model_name"]:
                shown[lb] = f"{lb} (defaults)"
        notes = []
        by_model: dict[str, list[str]] = {}
        for lb, s in self.models.items():
            if s.get("params"):
                by_model.setdefault(s["model_name"], []).append(lb)
        for m, labels in by_model.items():
            if all(len(lb) <= LABEL_WIDTH for lb in labels):
                continue
            sets = [self.models[lb]["params"] for lb in labels]
            shared = {k: v for k, v in sets[0].items() if all(k in p and p[k] == v for p in sets[1:])} \
                if len(sets) > 1 else {}
            for lb in labels:
                s = self.models[lb]
                shown[lb] = param_label(m, s["params"], shared=shared, width=LABEL_WIDTH, tag=s["param_set"])
            if shared:
                notes.append(f"- {m}: `…` stands for {param_label(m, shared)[len(m) + 1:-1]}, common to its "
                             f"{len(labels)} parameter sets (each in full in evaluation.json)")
        return shown, notes

    def object_table(self) -> str:
        """Markdown: object-level metrics per model."""
        shown = self._shown()[0]
        head = ("| model | videos | objects | detected | field latency (fr) | loc. err. at det. (px) "
                "| loc. err. life (px) | fields/object | fields | alarmed | alarm latency (fr) "
                "| false alarms | FA/min |")
        lines = [head, "|" + "|".join(["---"] * 13) + "|"]
        for s in self.models.values():
            det = "-" if s["detected"] is None else f"{s['detected']}/{s['objects']}"
            lines.append(
                f"| {shown[s['model']]} | {s['videos']} | {s['objects']} | {det} | {_fmt(s['latency_field'])} "
                f"| {_fmt(s['error_detect'])} | {_fmt(s['error_life'])} | {_fmt(s['fields_per_object'], 2)} "
                f"| {_fmt(s['fields_total'])} | {s['alarmed']}/{s['objects']} | {_fmt(s['latency_alarm'])} "
                f"| {_fmt(s['false_alarms'])} | {_fmt(s['false_alarms_per_min'], 2)} |")
        return "\n".join(lines)

    def clip_table(self) -> str:
        """Markdown: clip-level metrics per model (empty string without clip-level truth): the paper's
        score of the field alarm (any field in alarm, anywhere in the frame), not the targets' warning
        (:meth:`clip_warning_table`); its lead column is the JSON's ``warning_s``, the alarm's lead."""
        if not any(s["clips"] for s in self.models.values()):
            return ""
        shown = self._shown()[0]
        lines = ["| model | clips | TP | FP | TN | FN | accuracy | precision | recall | alarm lead (s) |",
                 "|" + "|".join(["---"] * 10) + "|"]
        for s in self.models.values():
            lines.append(f"| {shown[s['model']]} | {s['clips']} | {s['tp']} | {s['fp']} | {s['tn']} | {s['fn']} "
                         f"| {_fmt(s['accuracy'], 2)} | {_fmt(s['precision'], 2)} | {_fmt(s['recall'], 2)} "
                         f"| {_fmt(s['warning_s'], 2)} |")
        return "\n".join(lines)

    def video_table(self) -> str:
        """Markdown: one row per (model, video); ``alarm outcome``: the clip-level outcome of the field alarm."""
        shown = self._shown()[0]
        lines = ["| model | video | frames | objects | detected | alarmed | fields | false alarms | first alarm "
                 "| alarm outcome |", "|" + "|".join(["---"] * 10) + "|"]
        for v in self.videos:
            # a clip labelled as a whole (docs/evaluation.md, the clip format) has no objects to count: its
            # alarm is scored by "alarm outcome"
            level = v.get("object_level", True)
            det = "-" if not (v["localises"] and level) else f"{v['detected']}/{v['objects']}"
            objects, alarmed = (v["objects"], f"{v['alarmed']}/{v['objects']}") if level else ("-", "-")
            lines.append(f"| {shown[v['model']]} | {v['video']} | {v['frames']} | {objects} | {det} "
                         f"| {alarmed} | {_fmt(v['fields'])} | {_fmt(v['false_alarms'])} "
                         f"| {_fmt(v['first_alarm_frame'])} | {v['outcome'] or '-'} |")
        return "\n".join(lines)

    def warning_table(self) -> str:
        """Markdown: the warning metrics per model (empty without 3-D truth): collision objects
        warned before contact, lead time, true TTC and distance at the first warning, false
        warnings by cause, TTC errors (median RTE / MiD per true-TTC bin), coverage, fragmentation."""
        rows = [(lb, s["warnings"]) for lb, s in self.models.items() if s.get("warnings")
                and s["warnings"]["collision_objects"]]
        if not rows:
            return ""
        shown, _ = self._shown()
        bins = [f"{lo:g}-{hi:g}s" for lo, hi in TTC_BINS]
        lines = ["| model | warned | lead median (s) | lead p10 (s) | TTC at warning (s) | distance (px) "
                 "| false frames /1000 | false episodes /1000 "
                 "| by cause: pass / distractor / background (episodes /1000) "
                 + "".join(f"| TTC error {lo:g}-{hi:g} s (RTE / MiD) " for lo, hi in TTC_BINS)
                 + "| TTC coverage | targets/object |",
                 "|" + "|".join(["---"] * (12 + len(TTC_BINS))) + "|"]

        def ttc_cell(w, b):
            rte, mid = w[f"ttc_rte_pct_{b}"], w[f"ttc_mid_{b}"]
            return "-" if rte is None else f"{rte:.0f} % / {mid:.0f}"

        for lb, w in rows:
            c = w["false_episodes_per_1000_by_cause"]
            lines.append(
                f"| {shown[lb]} | {w['warned']}/{w['collision_objects']} ({_fmt(w['warned_rate'], pct=True)}) "
                f"| {_fmt(w['lead_median_s'], 2)} | {_fmt(w['lead_p10_s'], 2)} "
                f"| {_fmt(w['ttc_at_warning_median_s'], 2)} | {_fmt(w['warning_distance_median_px'], 1)} "
                f"| {_fmt(w['false_frames_per_1000'], 1)} | {_fmt(w['false_episodes_per_1000'], 2)} "
                f"| {_fmt(c['pass'], 2)} / {_fmt(c['distractor'], 2)} / {_fmt(c['background'], 2)} "
                + "".join(f"| {ttc_cell(w, b)} " for b in bins)
                + f"| {_fmt(w['ttc_coverage'], pct=True)} | {_fmt(w['fragmentation'], 2)} |")
        return "\n".join(lines)

    def clip_warning_table(self) -> str:
        """Markdown: per labelled clip and model, warned / missed / false, the lead time and that of
        the field alarm on the collider (models with targets); a
        warning that cannot be placed on the collider (no track) apart, as "unplaced"."""
        clips = [v for v in self.warning_videos if v["clip"]]
        if not clips:
            return ""
        shown, _ = self._shown()
        lines = ["| model | clip | label | warned | lead (s) | field alarm lead (s) | unplaced warning (s before contact) "
                 "| false warnings (frames) |", "|---|---|---|---|---|---|---|---|"]
        for v in clips:
            o = v["outcome"]
            unplaced = _fmt(o["unplaced"]) if not o["unplaced"] else f"yes, {_fmt(o['unplaced_lead_s'], 2)}"
            lines.append(f"| {shown.get(v['model'], v['model'])} | {v['video']} | {o['label']} "
                         f"| {_fmt(o['warned'])} | {_fmt(o['lead_s'], 2)} | {_fmt(o.get('alarm_lead_s'), 2)} "
                         f"| {unplaced} | {v['false_frames']} |")
        return "\n".join(lines)

    def notes(self) -> str:
        """Markdown: approaching objects not scored because they lie outside the
        processed frames (incomplete or partial runs), per model, and what shortened
        labels leave out; empty if none."""
        shown, lines = self._shown()
        lines += self.position_notes()
        for s in self.models.values():
            if s["objects_outside"]:
                inc = s["incomplete_videos"]
                lines.append(f"- {shown[s['model']]}: {s['objects_outside']} approaching object(s) outside the "
                             f"processed frames, not scored" + (f" ({inc} incomplete result(s))" if inc else ""))
        return "\n".join(lines)

    def position_notes(self) -> list[str]:
        """One Markdown line per model scored whose warnings have no position (neither fields that localise nor
        targets: LGMD1, LGMD2, a model of your own that gives only an alarm): its warning counts on every object in
        view, so its warned and lead figures are not those of a model that must place its warning on the collider."""
        shown = self._shown()[0]
        return [f"- {shown.get(lb, lb)} gives no positions: each of its warnings counts on every object in view "
                "(docs/evaluation.md, \"Warning metrics\"), so its warned and lead figures are not comparable with "
                "a model that places its warnings" for lb, s in self.models.items()
                if not s.get("places_warnings", s.get("localises"))]

    def to_markdown(self, details: bool = False) -> str:
        """The per-model comparison table(s); ``details`` adds the per-video table."""
        parts = [self.object_table()] if any(s["objects"] or not s["clips"] for s in self.models.values()) else []
        warn, cw = self.warning_table(), self.clip_warning_table()
        clip = self.clip_table()
        parts += [self.notes(), clip and CLIP_ALARM_TITLE + clip,
                  warn and "Warnings (collision objects of 3-D truth):\n\n" + warn,
                  cw and "Warnings on labelled clips (the targets' warnings, on the collider; the field alarm's "
                         "lead on it beside):\n\n" + cw,
                  self.video_table() if details else ""]
        return "\n\n".join(p for p in parts if p)

    def write(self, out) -> dict[str, Path]:
        """Write ``evaluation.md`` and ``evaluation.json`` into folder ``out``."""
        from ._files import write_text

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        st = self.settings
        md = (f"# Evaluation\n\nGround truth: `{st['ground_truth']}`; match radius {st['match_radius']:g} px, "
              f"tail {st['tail']} frames.\n\n{_READING}\n\n{self.to_markdown(details=True)}\n")
        if self.warnings:
            md += "\nWarnings:\n\n" + "".join(f"- {w}\n" for w in self.warnings)
        files = {}
        for name, text in (("evaluation.md", md), ("evaluation.json", self.to_json() + "\n")):
            path = out / name
            write_text(path, text)
            files[name] = path
        return files


#: The first lines of ``evaluation.md``: which table scores what (docs/evaluation.md).
_READING = ("The first table scores the attention fields as the paper does: every approaching object (colliding or "
            "not), *detected* by a field near it, *alarmed* by the model's collision flag. \"Warnings\" scores the "
            "targets' warnings (or the LGMD models' alarms) on the objects that will hit, as `benchmark.md` does; "
            "the last table gives each video (\"-\": a clip labelled as a whole, whose alarm the clip outcome "
            "scores). Every definition: docs/evaluation.md.")


def evaluate(results, gt, *, models: Sequence[str] | str | None = None, match_radius: float = DEFAULT_MATCH_RADIUS,
             tail: int = DEFAULT_TAIL, run_options: Mapping[str, Any] | None = None,
             progress: bool = False) -> Evaluation:
    """Score run results against ground truth.

    Parameters
    ----------
    results : RunResult, path, or a list of them
        Each item is a :class:`~mlplc2.runner.RunResult`, an output folder of
        ``mlplc2 run`` / ``mlplc2 batch`` (``responses.csv`` + ``fields.json``;
        a folder without ``responses.csv`` is searched recursively for them),
        or a video, a folder of videos (each of them) or an image folder (the
        models are then run first, nothing is written).
    gt : path, dict or GroundTruth
        Ground truth (see :func:`load_ground_truth`). A result's video is
        matched to a key by relative-path suffix, else by basename.
    models : list of str, optional
        Models to score (default: all in the results; for videos: all registered).
    match_radius : float
        A field within this distance (ground-truth pixels) of an object's centre
        stands for it.
    tail : int
        Frames after the end of an approach during which a field or alarm
        still counts for that object (not as a false alarm).
    run_options : dict, optional
        Extra keyword arguments of :func:`mlplc2.run` for video inputs (``resize``, ...).
    progress : bool
        Show the progress bar when running models on videos.

    Returns
    -------
    Evaluation
    """
    from .models.base import available_models, resolve_names

    if models is not None:
        models = resolve_names(models)
    match_radius = check_real(match_radius, "match_radius", positive=True)
    tail = check_int(tail, "tail", minimum=0)
    if run_options is not None and not isinstance(run_options, Mapping):
        raise InputTypeError(f"run_options must be a dict of mlplc2.run options, got {type(run_options).__name__}")
    truth = load_ground_truth(gt)

    notes: list[str] = []     # warnings, in order
    problems: list[str] = []  # inputs not scored for another reason than missing ground truth
    runs = _collect_runs(results, truth, models, run_options, progress, notes, problems)
    sc = _score_runs(runs, truth, problems, radius=match_radius, tail=tail)
    for origin, (reason, n) in sc.incomplete.items():
        notes.append(f"{origin}: incomplete results ({reason}); scored as they are, "
                     f"{n} approaching object(s) outside the processed frames not scored")
    for (origin, video), (end, contact) in sc.ended_early.items():
        notes.append(f"{origin}: the results end at frame {end}, before the contact at frame {contact:g} of "
                     f"{video}: a collision not warned of by then is scored as missed")
    if not sc.videos:
        _issue(notes)
        raise _nothing_to_evaluate(problems, sc.skipped, truth, models)
    notes.extend(f"{p}; not scored" for p in problems)
    _issue(notes)
    order = list(MODEL_ORDER) + [m for m in available_models() if m not in MODEL_ORDER]
    keys: dict[str, set] = {}              # per model, the parameters its sets change (a sweep's)
    for r in sc.by_label.values():
        keys.setdefault(r.model, set()).update(r.params)
    labels = sorted(sc.by_label, key=lambda lb: _rank(sc.by_label[lb], lb, order, keys.get(sc.by_label[lb].model)))
    summary = {lb: {"model": lb, "model_name": sc.by_label[lb].model,
                    "param_set": sc.by_label[lb].param_set or "default", "params": sc.by_label[lb].params,
                    **summarise(lb, sc.videos, sc.objects),
                    "warnings": summarise_warnings(lb, sc.wvideos, sc.wobjects) or None} for lb in labels}
    sc.wvideos.sort(key=lambda v: (labels.index(v["model"]), v["video"]))
    sc.wobjects.sort(key=lambda o: (labels.index(o["model"]), o["video"], str(o["object"])))
    sc.videos.sort(key=lambda v: (labels.index(v["model"]), v["video"]))
    sc.objects.sort(key=lambda o: (labels.index(o["model"]), o["video"], o["onset"], str(o["object"])))
    settings = {"ground_truth": truth.source, "match_radius": match_radius, "tail": tail}
    return Evaluation(summary, sc.videos, sc.objects, settings, sc.skipped, notes, sc.wvideos, sc.wobjects)


def _collect_runs(results, truth: GroundTruth, models, run_options, progress: bool, notes: list[str],
                  problems: list[str]) -> list[ModelRun]:
    """The runs of every input (:func:`_expand_inputs`): RunResults and results folders as they are,
    videos run first (those without ground truth are not run: a placeholder run without a model);
    inputs that are neither go to ``problems``."""
    from .io import IMAGE_EXTENSIONS, VIDEO_EXTENSIONS
    from .models.base import available_models
    from .runner import RunResult, run

    runs: list[ModelRun] = []
    for item in _expand_inputs(results, notes):
        if isinstance(item, RunResult):
            runs.extend(_runs_from_result(item, models))
        elif isinstance(item, (str, Path)) and Path(item).is_dir() and (Path(item) / "responses.csv").is_file():
            runs.extend(_read_folder(Path(item), models))
        elif isinstance(item, (str, Path)):
            p = Path(item)
            if not p.exists() and not any(ch in str(item) for ch in "*?["):
                raise InputValueError(f"{item}: no such file or folder")
            if truth.match(item) is None:  # do not run models on a video that cannot be scored
                if p.is_dir() and not any(f.is_file() and f.suffix.lower() in IMAGE_EXTENSIONS for f in p.iterdir()):
                    problems.append(f"{item}: no results in this folder (no responses.csv in it or below), "
                                    f"no videos and no images")
                elif p.is_file() and p.suffix.lower() not in VIDEO_EXTENSIONS + IMAGE_EXTENSIONS:
                    problems.append(f"{item}: not a results folder (responses.csv + fields.json) nor a video "
                                    f"({', '.join(VIDEO_EXTENSIONS)}) or image")
                else:
                    runs.append(ModelRun(str(item), "", "", 30.0, None, 0, 0, [], {}, {}))
                continue
            names = models or available_models()
            res = run(item, names, out=False, quiet=not progress, **dict(run_options or {}))
            runs.extend(_runs_from_result(res, models, origin=f"{item} (run now)"))
        else:
            raise InputValueError(f"cannot evaluate {type(item).__name__}: give a RunResult, a results folder "
                                  f"or a video path")
    return runs


@dataclass
class _Scores:
    """The scores of every run, as :func:`_score_runs` gathers them: the per-(model, video) and
    per-object rows (``videos``, ``objects``; ``wvideos``, ``wobjects``: the warning metrics), the
    videos without ground truth (``skipped``), a run per model label (``by_label``: its model and
    parameters) and, per incomplete origin, (reason, approaching objects outside)."""

    videos: list[dict] = field(default_factory=list)
    objects: list[dict] = field(default_factory=list)
    wvideos: list[dict] = field(default_factory=list)
    wobjects: list[dict] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    by_label: dict[str, ModelRun] = field(default_factory=dict)
    incomplete: dict[str, tuple[str, int]] = field(default_factory=dict)
    # (origin, video) -> (last processed frame, contact frame) of a collision the run ended before, unwarned
    ended_early: dict[tuple[str, str], tuple[int, float]] = field(default_factory=dict)


def _score_runs(runs: list[ModelRun], truth: GroundTruth, problems: list[str], *, radius: float,
                tail: int) -> _Scores:
    """Score each run against its video's truth (:func:`~mlplc2.evaluation.score.score_run`, and
    :func:`~mlplc2.evaluation.score.score_warnings` where the truth says which objects will hit);
    two runs of one label and video from different inputs are an error."""
    sc = _Scores()
    claimed: dict[tuple[str, str], ModelRun] = {}  # (model label, video) -> the run scored for it
    for r in runs:
        t = truth.match(r.source) if r.model else None
        if t is None and r.model and not r.video_known:
            msg = f"{r.origin}: {r.incomplete}, so its video is unknown"
            if msg not in problems:
                problems.append(msg)
            continue
        if t is None:
            if r.source not in sc.skipped:
                sc.skipped.append(r.source)
            continue
        key = (r.label, _video_key(r.source))
        prev = claimed.setdefault(key, r)
        if prev is not r and prev.ident != r.ident:
            other = r.origin if r.origin != prev.origin else f"another {r.origin.removeprefix('a ')}"
            raise InputValueError(f"{prev.origin} and {other} both hold {r.label} results for {r.source}; "
                                  f"evaluate one of them (or each separately)")
        v, o = score_run(r, t, radius=radius, tail=tail)
        sc.by_label.setdefault(r.label, r)
        sc.videos.append(v)
        sc.objects.extend(o)
        if warning_truth(t):
            wv, wo = score_warnings(r, t, radius=radius)
            sc.wvideos.append(wv)
            sc.wobjects.extend(wo)
            last = r.start + r.n_frames
            for rec in wo:
                cf = rec["contact_frame"]
                if cf is not None and last < math.ceil(cf) and not rec["warned"] and not rec["unplaced"]:
                    sc.ended_early.setdefault((r.origin, t.key), (last - 1, cf))
        if r.incomplete is not None:
            reason, n = sc.incomplete.get(r.origin, (r.incomplete, 0))
            sc.incomplete[r.origin] = (reason, max(n, v["objects_outside"]))
    return sc


def _nothing_to_evaluate(problems: list[str], skipped: list[str], truth: GroundTruth,
                         models: list[str] | None) -> InputValueError:
    """The error when no run was scored: the problems of the inputs, else the videos without truth."""
    if problems:
        return InputValueError(f"nothing to evaluate: {'; '.join(problems[:3])}"
                               f"{' ...' if len(problems) > 3 else ''}")
    if skipped:
        return InputValueError(f"no ground truth in {truth.source} for {', '.join(skipped[:3])}"
                               f"{' ...' if len(skipped) > 3 else ''}"
                               f"{unnamed_source_hint(skipped[0]) or _one_key_hint(truth)}")
    if models:
        return InputValueError(f"nothing to evaluate: the results hold no output of {', '.join(models)}")
    return InputValueError("nothing to evaluate (no model output in the results)")


def _one_key_hint(truth: GroundTruth) -> str:
    """The key of a ground truth of one entry (its ``"video"``: what `mlplc2 stimulus` wrote it for), which the
    run's video did not match; else ``""``."""
    return f" (its one entry is for video {next(iter(truth))!r})" if len(truth) == 1 else ""


def unnamed_source_hint(source: str) -> str:
    """Why the run of ``source`` matches no ground-truth key when it was standard input (``-``) or a camera
    (its index), which have no file name, and what to give instead (docs/evaluation.md); else ``""``."""
    if source != "-" and not source.isdigit():
        return ""
    what = "standard input" if source == "-" else f"camera {source}"
    return (f" (a run of {what} has no video name to match a key: give the clip's entry alone as the ground "
            f"truth, without \"video\", and it applies to any run; docs/evaluation.md)")


def _rank(r: ModelRun, label: str, order: list[str], keys=None) -> tuple:
    """Sort key of a model label: model order, then parameter values (numbers as numbers: t_a=8
    before t_a=12), a parameter ``keys`` names (those the model's other sets change) that this set
    leaves at its default counted at the default value (a sweep's default among its values)."""
    params = dict(r.params)
    missing = [k for k in keys or () if k not in params]
    if missing:
        from .models.base import param_defaults
        try:
            defaults = param_defaults(r.model)
        except (InputError, TypeError, ValueError):   # a model not registered here: its sets as recorded
            defaults = {}
        params.update({k: defaults[k] for k in missing if k in defaults})
    values = [(k, (0, v, "") if isinstance(v, (int, float)) and not isinstance(v, bool)
               else (1, 0, json.dumps(v, sort_keys=True))) for k, v in sorted(params.items())]
    return order.index(r.model) if r.model in order else 99, r.model, values, label


def _video_key(source: str) -> str:
    """A result's video, comparable across result folders (the path as recorded, resolved if it exists)."""
    source = str(source)
    return _path_key(source) if os.path.exists(source) else os.path.normcase(os.path.normpath(source))


def _issue(notes: list[str]) -> None:
    for note in notes:
        warnings.warn(note, EvaluationWarning, stacklevel=3)
