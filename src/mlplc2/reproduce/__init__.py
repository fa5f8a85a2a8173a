"""``mlplc2 reproduce``: the experiments of Sec. IV of the paper, their figures
and a line-by-line PASS/FAIL report of every quantitative claim.

:func:`reproduce` runs, with one parameter set (the defaults, or ``params``):

* Sec. IV-A (Fig. 3): LGMD2, LPLC2, sLPLC2 and mLPLC2 on the six basic stimuli;
* Sec. IV-B (Fig. 4): the four models on the 400-frame four-phase scene;
* Sec. IV-B (Fig. 5): mLPLC2 on the six-object scene;
* Sec. IV-C (Fig. 6): mLPLC2 on every ``uav/*.avi`` clip of ``data`` (only
  with ``data``),

then writes ``fig3_selectivity.png``, ``fig4_four_phases.png``,
``fig5_six_objects.png``, ``fig6_real_clips.png``, ``report.md`` and
``report.json`` (see docs/reproduce.md).

Without ``data`` the stimuli are generated (:mod:`mlplc2.stimuli`,
procedural background, seed 0); with ``data`` (the paper's data folder) the
paper's videos and ``ground_truth.json`` are used.

Every claim is ``PASS``, ``FAIL``, or ``FAIL (known deviation)``: a failure
listed in :data:`KNOWN_DEVIATIONS` (shown in docs/reproduce.md), flagged
``known_deviation`` with the docs section that explains it; a claim that
passes is never flagged. ``params`` (``--params FILE.json``) replaces the
defaults with another parameter set, the same for every input.

The package: :mod:`.inputs` (the videos or generated stimuli and their objects),
:mod:`.claims` (the claims, their thresholds and :data:`KNOWN_DEVIATIONS`),
:mod:`.figures` (Fig. 3-6) and :mod:`.report` (:class:`ReproduceResult`, ``report.md``,
``report.json``). The command line (``mlplc2 reproduce``, its exit codes and messages) is in
:mod:`mlplc2.cli`.
"""

from __future__ import annotations

import time
from pathlib import Path

from ..models.base import REPEAT_THRESHOLD
from ..evaluation.record import Record, record
from .claims import FAMILY, KNOWN_DEVIATIONS, MODELS, STATUS_KNOWN, Claim, KnownDeviation, check_claims
from .inputs import FOUR_PHASE_FILE, PAPER_BASIC_FILES, SIX_OBJECTS_FILE, Scene, load_inputs, load_paper_objects
from .report import ReproduceResult, write_json, write_markdown

__all__ = ["reproduce", "ReproduceResult", "Claim", "KNOWN_DEVIATIONS", "KnownDeviation", "STATUS_KNOWN",
           "FAMILY", "MODELS", "PAPER_BASIC_FILES", "FOUR_PHASE_FILE", "SIX_OBJECTS_FILE", "Scene", "load_inputs",
           "load_paper_objects", "run_model", "REPEAT_THRESHOLD"]

#: The files :func:`reproduce` writes (an earlier run's are deleted first).
OUTPUTS = ("fig3_selectivity.png", "fig4_four_phases.png", "fig5_six_objects.png", "fig6_real_clips.png",
           "report.json", "report.md")


def run_model(name: str, frames, fps: float, progress=None, params=None) -> Record:
    """Run model ``name`` (registry name; its default parameters, or ``params``; duplicated
    frames held: :data:`REPEAT_THRESHOLD`) over ``frames``; its outputs as a
    :class:`mlplc2.evaluation.record.Record` with every series (``response``, ``collision``, ``fields``).

    Every model of the reproduction holds duplicated frames (``Model.repeat_threshold``): the
    paper's real clips repeat many frames (the raptor clip most of them); the synthetic
    stimuli change on every frame, so their results are the same with or without it.
    """
    from ..models import get_model

    extra = {} if params is None else {"params": params}
    model = get_model(name)(fps=fps, repeat_threshold=REPEAT_THRESHOLD, **extra)
    return record(model, frames, progress=progress)


def reproduce(data=None, out="mlplc2_reproduce", *, quick: bool = False, quiet: bool = False,
              figures: bool = True, seed: int = 0, params=None) -> ReproduceResult:
    """Run the experiments of Sec. IV, write the figures and the report.

    Parameters
    ----------
    data : path or None
        The paper's data folder (``basic/``, ``scenes/``, ``uav/``,
        ``ground_truth.json``); ``None``: generated stimuli.
    out : path
        Output folder (created).
    quick : bool
        Reduced set for CI: every experiment of Sec. IV-A and IV-B at full
        length, but the real clips (Sec. IV-C, Fig. 6) are skipped even with
        ``data`` and the figures are drawn at 70 instead of 110 dpi.
    quiet : bool
        No progress bar on stderr.
    figures : bool
        Write the PNG figures.
    seed : int
        Seed of the generated procedural background (ignored with ``data``).
    params : Params, dict or path to a JSON file, optional
        One parameter set for every input instead of the defaults, read and checked as
        ``mlplc2 batch --params`` reads it (:func:`mlplc2.batch.param_sets`): ``Params``
        fields for the LPLC2 family, plus an optional ``{"lgmd2": {...}}`` section. Bad
        parameters raise :class:`~mlplc2.InputError` before anything is read or written.
    """
    from .._progress import bar as progress_bar
    from ..batch import model_params, param_sets

    t_start = time.perf_counter()
    out = Path(out)
    pset = param_sets(params, None, MODELS)[0] if params is not None else {}
    model_args = {m: model_params(pset, m) for m in MODELS}
    inputs = load_inputs(None if data is None else Path(data), quick=quick, seed=seed)  # checked before any output
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    for name in OUTPUTS:   # never leave an earlier run's figure beside this report
        (out / name).unlink(missing_ok=True)
    skipped = list(inputs.get("damaged", []))
    if data is None:
        skipped.append("no --data: Fig. 6 (real UAV clips) skipped and the real-clip claims not checked")
    elif quick:
        skipped.append("--quick: Fig. 6 (real UAV clips) skipped")
    elif not inputs["clips"]:
        skipped.append(f"no readable uav/*.avi in {data}: Fig. 6 skipped")

    basic = inputs["basic"]
    total = (sum(s.n for s in basic.values()) * len(MODELS) + inputs["four_phase"].n * len(MODELS)
             + inputs["six_objects"].n + sum(s.n for s in inputs["clips"]))
    bar = progress_bar(total=total, desc="reproduce", unit="frame", disable=quiet, leave=False)
    try:
        basic_traces = {m: {name: run_model(m, sc.frames, sc.fps, bar, model_args[m]) for name, sc in basic.items()}
                        for m in MODELS}
        fp = inputs["four_phase"]
        fp_traces = {m: run_model(m, fp.frames, fp.fps, bar, model_args[m]) for m in MODELS}
        six = inputs["six_objects"]
        six_trace = run_model("mlplc2", six.frames, six.fps, bar, model_args["mlplc2"])
        clip_traces = {sc.name: run_model("mlplc2", sc.frames, sc.fps, bar, model_args["mlplc2"])
                       for sc in inputs["clips"]}
    except KeyboardInterrupt:
        if created and not any(out.iterdir()):
            out.rmdir()   # nothing was written yet: leave no empty folder behind
        raise
    finally:
        bar.close()

    claims = check_claims(basic_traces, fp, fp_traces, six, six_trace, inputs["clips"], clip_traces)

    paths = []
    if figures:
        from . import figures as figs

        dpi, source = (70 if quick else 110), inputs["source"]
        paths = [figs.fig3_selectivity(basic, basic_traces, out / "fig3_selectivity.png", source=source, dpi=dpi),
                 figs.fig4_four_phases(fp, fp_traces, out / "fig4_four_phases.png", source=source, dpi=dpi),
                 figs.fig5_six_objects(six, six_trace, out / "fig5_six_objects.png", source=source, dpi=dpi)]
        if inputs["clips"]:
            paths.append(figs.fig6_real_clips(inputs["clips"], clip_traces, out / "fig6_real_clips.png", dpi=dpi))
    files = {p.name: str(p) for p in paths}
    seconds = time.perf_counter() - t_start
    result = ReproduceResult(out, claims, files, inputs["source"], quick, skipped, seconds,
                             list(inputs.get("damaged", [])), pset)
    files["report.json"] = str(write_json(result, out / "report.json"))
    files["report.md"] = str(write_markdown(result, out / "report.md"))
    return result

