"""The tools: ``mlplc2 params`` (the parameter tables) and ``mlplc2 bench`` (the speed
benchmark, :mod:`mlplc2.bench`).
"""

from __future__ import annotations

import argparse
import sys

from .._validation import InputValueError
from ..models.base import available_models, resolve_names
from .common import EXIT_OK, Subcommand, out, pos_int


# ---------------------------------------------------------------------------
# params: the parameter tables (one source: the fields' metadata, mlplc2.params)
# ---------------------------------------------------------------------------
def _add_params(p: argparse.ArgumentParser) -> None:
    which = p.add_mutually_exclusive_group()
    which.add_argument("--targets", action="store_true",
                       help="the target estimators' TargetParams instead of the model's Params")
    which.add_argument("--lgmd2", action="store_true", help="the LGMD2 baseline's LGMD2Params")
    which.add_argument("--lgmd1", action="store_true", help="the LGMD1 baseline's LGMD1Params")
    which.add_argument("--flow", action="store_true", help="the flow baseline's FlowParams")
    p.add_argument("--markdown", action="store_true",
                   help="as the Markdown table of docs/model.md (docs/targets.md with --targets)")


def _cmd_params(args) -> int:
    from ..models.flow import FlowParams
    from ..models.lgmd import LGMD1Params, LGMD2Params
    from ..params import Params, parameter_table
    from ..targets import TargetParams

    cls = TargetParams if args.targets else LGMD2Params if args.lgmd2 else LGMD1Params if args.lgmd1 else \
        FlowParams if args.flow else Params
    if cls is TargetParams and not args.markdown:  # 128 rows: the few a user sets first (a new user's trial)
        out("The ones a user sets (mlplc2 run --horizon, --max-miss, --alarm-warns, --heading): horizon_s, max_miss, "
            "alarm_warns, heading. The others are the target layer's own, set once for every input with the "
            "benchmark (docs/targets.md says why each has its value).\n")
    out(parameter_table(cls, markdown=args.markdown), end="")
    if cls is Params and not args.markdown:   # the descriptions cite docs/model.md's numbers (a researcher's trial)
        out("Equation numbers are docs/model.md's (NOTES.md's): they count the vDoG subtraction as Eq. 4, so their "
            "Eq. 5-16 are the paper's Eq. 4-15.")
    return EXIT_OK


# ---------------------------------------------------------------------------
# bench (timing in mlplc2.bench; benchmarks/README.md)
# ---------------------------------------------------------------------------
def _add_bench(p: argparse.ArgumentParser) -> None:
    from ..bench import DEFAULT_SIZES

    from ..bench import LATENCY_SIZES

    p.add_argument("--sizes", metavar="WxH,...",
                   help=f"frame sizes (default {DEFAULT_SIZES}; with --latency {LATENCY_SIZES})")
    p.add_argument("--latency", action="store_true",
                   help="time `mlplc2 run` instead, on an H.264 clip per size: decoding alone, the model alone, "
                        "run end to end, and the latency from a frame's decoding to its JSON line "
                        "(median, 99th percentile, max)")
    p.add_argument("--models", "--model", "-m", dest="models", action="append", metavar="NAME",
                   help="LPLC2-family model(s), repeatable or comma-separated (default: mlplc2)")
    p.add_argument("--threads", type=pos_int, metavar="N",
                   help="threads for the fast front end and OpenCV (default: Numba's, i.e. all cores)")
    p.add_argument("--frames", type=pos_int, default=100, metavar="N",
                   help="timed frames per model and size after 10 warm-up frames (default 100)")
    p.add_argument("--ref-frames", type=pos_int, default=12, metavar="N",
                   help="timed frames of the reference front end (default 12)")
    p.add_argument("--rounds", type=pos_int, default=1, metavar="R",
                   help="repeat every measurement R times and keep the smallest median (default 1)")
    p.add_argument("--no-reference", action="store_true", help="skip the reference front end")
    p.add_argument("--no-pipeline", action="store_true",
                   help="skip the second table: the pipeline as `mlplc2 run` builds it (gaze stabilisation on) "
                        "on a turning and a still scene, against the reference and the flow baseline")
    p.add_argument("--quiet", "-q", action="store_true", help="only the table")


def _cmd_bench(args) -> int:
    from ..bench import DEFAULT_SIZES, describe, format_pipeline, format_table, parse_sizes, run_bench

    names = resolve_names(args.models or ["mlplc2"], what="--models")
    family = [m for m in ("mlplc2", "slplc2", "lplc2") if m in available_models()]
    bad = [n for n in names if n not in family]
    if bad:
        raise InputValueError(f"--models: {', '.join(bad)} not benchmarked; choose from {', '.join(family)}")
    if args.latency:
        from ..bench import LATENCY_SIZES, format_latency, time_latency

        rows = [time_latency(w, h, frames=args.frames + 10, model=name)
                for w, h in parse_sizes(args.sizes or LATENCY_SIZES) for name in names]
        out(format_latency(rows))
        return EXIT_OK
    sizes = parse_sizes(args.sizes or DEFAULT_SIZES)

    def progress(msg):
        if not args.quiet:
            print(msg, file=sys.stderr, flush=True)

    rows = run_bench(sizes, names, threads=args.threads, frames=args.frames, ref_frames=args.ref_frames,
                     reference=not args.no_reference, rounds=args.rounds, progress=progress,
                     pipeline=not args.no_pipeline)
    out(format_table(rows))
    if not args.no_pipeline:
        out("\n" + format_pipeline(rows))
    if not args.quiet:
        out("\n" + describe(args.frames, args.rounds))
    return EXIT_OK


PARAMS = Subcommand("params", "print the parameters: Table I symbol, unit, default, valid values (--markdown: "
                    "and the description of each)",
                    _add_params, _cmd_params)
BENCH = Subcommand("bench", "time the LPLC2 models per frame size: ms/frame, reference, bandwidth probe, memory",
                   _add_bench, _cmd_bench)
