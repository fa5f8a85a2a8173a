"""The studies: ``mlplc2 evaluate`` (:func:`mlplc2.evaluate.evaluate`), ``batch``
(:func:`mlplc2.batch.batch`), ``benchmark`` (:func:`mlplc2.benchmark.benchmark`) and ``reproduce``
(:func:`mlplc2.reproduce.reproduce`).
"""

from __future__ import annotations

import argparse
import sys
import warnings

from .._validation import InputValueError
from ..models.base import resolve_names
from .common import (EXIT_INPUT, EXIT_INTERRUPTED, EXIT_OK, EXIT_TRUNCATED, PROG, Subcommand, add_repeat_options,
                     add_stabilise_option, add_warning_options, frame_size, hfov_degrees, holdouts, nonneg_int, one_line,
                     pos_float, say, target_options, video_run_options, warn)


# ---------------------------------------------------------------------------
# evaluate (docs/evaluation.md)
# ---------------------------------------------------------------------------
def _add_evaluate(p: argparse.ArgumentParser) -> None:
    p.add_argument("inputs", nargs="+", metavar="RESULTS_OR_VIDEOS",
                   help="output folders of 'mlplc2 run' / 'mlplc2 batch' (responses.csv + fields.json), "
                        "or videos, folders of videos or of images (the models are run first)")
    p.add_argument("--gt", required=True, metavar="GT.json", help="ground truth (see docs/evaluation.md)")
    p.add_argument("--model", "-m", action="append", metavar="NAME",
                   help="model(s) to score, repeatable or comma-separated (default: all in the results; "
                        "for videos: all registered models)")
    p.add_argument("--out", "-o", metavar="DIR", help="write evaluation.md and evaluation.json here")
    p.add_argument("--match-radius", type=pos_float, default=20.0, metavar="PX",
                   help="a field this close to an object's centre stands for it (default 20, ground-truth pixels)")
    p.add_argument("--tail", type=nonneg_int, default=25, metavar="FRAMES",
                   help="frames after an approach during which its fields/alarms still count (default 25)")
    p.add_argument("--resize", type=frame_size, metavar="WxH", help="for video inputs: resize frames before the models")
    add_repeat_options(p, "for video inputs: hold the models' output on duplicated frames "
                          "(as in 'mlplc2 run --skip-repeats')")
    add_warning_options(p, "for video inputs: ")
    add_stabilise_option(p, "for video inputs: ")
    p.add_argument("--details", action="store_true", help="also print the per-video table")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")


def _cmd_evaluate(args) -> int:
    from ..evaluator import EvaluationWarning, evaluate, unnamed_source_hint

    models = resolve_names(args.model, what="--model") if args.model else None
    options = video_run_options(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EvaluationWarning)  # reported below, one line each
        ev = evaluate(args.inputs, args.gt, models=models, match_radius=args.match_radius, tail=args.tail,
                      run_options=options, progress=not args.quiet)
    for w in ev.warnings:
        warn(w)
    for s in ev.skipped:
        warn(f"{s}: no ground truth for it in {args.gt}; not scored{unnamed_source_hint(s)}")
    say(args, ev.to_markdown(details=args.details))
    if args.out:
        files = ev.write(args.out)
        say(args, f"wrote {', '.join(str(f) for f in files.values())}")
    return EXIT_OK


# ---------------------------------------------------------------------------
# batch (docs/evaluation.md)
# ---------------------------------------------------------------------------
def _add_batch(p: argparse.ArgumentParser) -> None:
    p.add_argument("inputs", nargs="+", metavar="INPUTS",
                   help="videos, folders of videos, image folders or quoted glob patterns")
    p.add_argument("--out", "-o", required=True, metavar="DIR", help="output folder (results.csv + per-video outputs)")
    p.add_argument("--models", "--model", "-m", dest="model", action="append", metavar="NAME",
                   help="model(s), repeatable or comma-separated (default: mlplc2)")
    p.add_argument("--params", metavar="FILE.json", help="JSON object of Params fields overriding the defaults")
    p.add_argument("--sweep", action="append", metavar="PARAM=V1,V2,...",
                   help="sweep a parameter, repeatable (Cartesian product); MODEL.PARAM for one model's own")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="tcp://host:8786 of a running Dask scheduler (default: start a local cluster)")
    p.add_argument("--workers", type=nonneg_int, metavar="N",
                   help="local cluster workers (default min(4, CPUs); 0 = sequential, no Dask)")
    p.add_argument("--resize", type=frame_size, metavar="WxH", help="resize frames before the models")
    add_repeat_options(p, "hold the models' output on duplicated frames (as in 'mlplc2 run --skip-repeats')")
    add_warning_options(p)
    add_stabilise_option(p)
    p.add_argument("--plot", action="store_true", help="also write each task's responses.png")
    p.add_argument("--force", action="store_true", help="rerun tasks that are already done")
    p.add_argument("--parquet", action="store_true", help="also write results.parquet (needs pyarrow)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_batch(args) -> int:
    from ..batch import BatchInterrupted, batch

    models = resolve_names(args.model or ["mlplc2"], what="--model")
    options = video_run_options(args)
    if args.parquet:  # said here with the flag's name (batch() says it with the file's)
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InputValueError("--parquet needs pyarrow: pip install 'mlplc2[parquet]'") from None
    try:
        res = batch(args.inputs, args.out, models=models, params=args.params, sweep=args.sweep,
                    scheduler=args.scheduler, workers=args.workers, run_options=options, plot=args.plot,
                    progress=not args.quiet, force=args.force, parquet=args.parquet)
    except BatchInterrupted as exc:
        if args.quiet:  # with progress output batch() has already said it
            print(f"{PROG}: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    reported = set()
    for r in res.rows:
        if r["status"] in ("error", "truncated") and r["out"] not in reported:  # once per task
            reported.add(r["out"])
            warn(f"{r['video']} ({r['label']}, {r['out']}): {r['error']}")
    plotted = f" ({res.plotted} of them plotted now)" if res.plotted else ""
    # counted in runs, which add up: tasks that differ only in parameters a model does not use share its run
    runs = f" in {res.tasks} run(s)" if res.tasks != len(res.rows) else ""
    say(args, f"{len(res.rows)} task(s){runs}: {res.ran - res.failed_runs} ran, {res.skipped} already done{plotted}, "
               f"{res.failed_runs} failed; {len(res.videos)} video(s) in {res.seconds:.1f} s on {res.scheduler}",
         f"results in {res.table}")
    return EXIT_INPUT if res.failed else EXIT_OK


# ---------------------------------------------------------------------------
# benchmark (docs/benchmark.md)
# ---------------------------------------------------------------------------
def _add_benchmark(p: argparse.ArgumentParser) -> None:
    from ..benchmark import MODELS

    p.add_argument("--out", "-o", required=True, metavar="DIR",
                   help="output folder: scenes/ (generated videos), runs/ (the batch; finished tasks are reused), "
                        "benchmark.md/.csv/.json, evaluation.md/.json and the plots")
    p.add_argument("--quick", action="store_true", help="4 short scenes and no real clips (the test suite's run)")
    p.add_argument("--models", "--model", "-m", dest="model", action="append", metavar="NAME",
                   help=f"model(s), repeatable or comma-separated (default: {','.join(MODELS)})")
    real = p.add_mutually_exclusive_group()
    real.add_argument("--real", metavar="DIR",
                      help="folder of the labelled real clips, with their ground_truth.json (default: "
                           "../shared/data/real when it is there)")
    real.add_argument("--no-real", action="store_true", help="leave the real clips out")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="tcp://host:8786 of a running Dask scheduler (default: start a local cluster)")
    p.add_argument("--workers", type=nonneg_int, metavar="N",
                   help="local cluster workers (default min(4, CPUs); 0 = sequential, no Dask)")
    add_warning_options(p)
    add_stabilise_option(p)
    p.add_argument("--settings", metavar="NAMES",
                   help="only these settings of the generated suite, comma-separated (e.g. drive,drone; "
                        "default all: plain_static ... handheld, docs/benchmark.md)")
    p.add_argument("--holdout", type=holdouts, default=0, metavar="N",
                   help="N > 0: draw every scene with other seeds (other textures, speeds, turns), to check "
                        "a figure on scenes nothing was tuned on (default 0, the standard suite); a range or "
                        "list (21-40, 3,7,21-25) pools those holdouts in one report, each setting's figures "
                        "over all of them")
    p.add_argument("--hfov", type=hfov_degrees, metavar="DEG",
                   help="render the generated scenes through a camera of this horizontal field of view (default "
                        "60, the value the defaults were set at) and give it to the models, as a user who knows "
                        "the lens would (scenes named ..._fDEG); with --no-real")
    p.add_argument("--force", action="store_true", help="rerun tasks that are already done")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bars and no table")


def _cmd_benchmark(args) -> int:
    from ..batch import BatchInterrupted
    from ..benchmark import benchmark

    models = resolve_names(args.model, what="--model") if args.model else None
    real = None if args.no_real else (args.real if args.real is not None else "auto")
    try:
        res = benchmark(args.out, quick=args.quick, models=models, real=real, scheduler=args.scheduler,
                        workers=args.workers, target_params=target_options(args) or None,
                        stabilise=args.stabilise, progress=not args.quiet, force=args.force,
                        settings=None if args.settings is None else [s.strip() for s in args.settings.split(",")
                                                                     if s.strip()],
                        holdout=args.holdout, hfov_deg=args.hfov)
    except BatchInterrupted as exc:
        if args.quiet:  # with progress output batch() has already said it
            print(f"{PROG}: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    say(args, res.to_markdown().rstrip("\n"), f"wrote {', '.join(str(f) for f in res.files.values())}")
    return EXIT_INPUT if any(f["status"] == "error" for f in res.failed) else EXIT_OK


# ---------------------------------------------------------------------------
# reproduce (implemented in mlplc2.reproduce, imported only when used; docs/reproduce.md)
# ---------------------------------------------------------------------------
def _add_reproduce(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", metavar="DIR",
                   help="the paper's data folder (basic/, scenes/, uav/, ground_truth.json); "
                        "default: generated stimuli")
    p.add_argument("--out", "-o", default="mlplc2_reproduce", metavar="DIR",
                   help="output folder for the figures and report (default: ./mlplc2_reproduce)")
    p.add_argument("--quick", action="store_true",
                   help="reduced set for CI: no real clips (Fig. 6), low-resolution figures")
    p.add_argument("--params", metavar="FILE.json",
                   help="JSON object of Params fields overriding the defaults for every input (the format of "
                        "'mlplc2 batch --params'; 'mlplc2 params' lists the fields)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_reproduce(args) -> int:
    """The summary and every failing claim on stdout; a damaged clip (skipped) is a warning
    line, also under ``--quiet``, and exit 2."""
    from pathlib import Path

    from ..reproduce import reproduce

    if args.data is not None and not Path(args.data).is_dir():
        raise InputValueError(f"--data {args.data}: not a folder")
    res = reproduce(args.data, args.out, quick=args.quick, quiet=args.quiet, params=args.params)
    for s in res.damaged:
        warn(s)
    failing = [f"  {c.status}  {c.claim}: {c.measured}"
               + (f" ({c.docs['file']}, \"{c.docs['section']}\")" if c.docs else "")
               for c in res.claims if not c.passed]
    say(args, f"{len(res.claims)} claims: {res.summary}", f"  parameters: {res.parameters}", *failing,
         *(f"  note: {s}" for s in res.skipped if s not in res.damaged),
         f"outputs in {res.out}: {', '.join(sorted(res.files))}")
    return EXIT_TRUNCATED if res.damaged else EXIT_OK


EVALUATE = Subcommand("evaluate", "score results (or videos) against ground truth; per-model comparison table",
                      _add_evaluate, _cmd_evaluate)
BATCH = Subcommand("batch", "run every (video, model, parameter set) as a Dask task; one results table",
                   _add_batch, _cmd_batch)
BENCHMARK = Subcommand("benchmark", "the standard suite of generated approaches (+ real clips), every model: how "
                                    "early and how reliably each warns", _add_benchmark, _cmd_benchmark)
REPRODUCE = Subcommand("reproduce", "run the paper's Sec. IV experiments; write Fig. 3-6 and a PASS/FAIL report",
                       _add_reproduce, _cmd_reproduce)
