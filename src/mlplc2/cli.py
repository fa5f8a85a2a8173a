"""Command line: ``mlplc2 run | stimulus | demo`` (see docs/cli.md).

Thin by design: each subcommand parses its arguments and calls one public
function (:func:`mlplc2.run`, :func:`mlplc2.runner.write_stimulus`,
:func:`mlplc2.runner.demo`). Subcommands live in the :data:`SUBCOMMANDS`
table; adding one (``reproduce``, ``bench``, ``evaluate``, ``batch``) is one
:class:`Subcommand` entry, or a call to :func:`add_subcommand` from the
module that implements it.

Exit codes: 0 success; 2 bad input (one line ``mlplc2: error: ...`` on
stderr, no traceback) and also a truncated or damaged video (after writing
the outputs for the frames that decoded); 130 after Ctrl-C (the outputs for
the frames done are written).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ._signals import interrupts
from ._validation import InputError, InputValueError
from .models.base import MAX_REPEATS, REPEAT_THRESHOLD

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS", "add_subcommand",
           "EXIT_OK", "EXIT_INPUT", "EXIT_TRUNCATED", "EXIT_INTERRUPTED"]

EXIT_OK = 0
EXIT_INPUT = 2
#: A truncated/damaged input still gives outputs but exits non-zero (same code as bad input).
EXIT_TRUNCATED = 2
EXIT_INTERRUPTED = 130

PROG = "mlplc2"


class _UsageError(Exception):
    """argparse error turned into an exception (one line, exit 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # noqa: D102 - one line instead of usage + message
        raise _UsageError(f"{message} (see '{self.prog} --help')")


@dataclass(frozen=True)
class Subcommand:
    """One ``mlplc2 NAME`` subcommand.

    ``add_arguments(parser)`` declares its options; ``handler(args) -> int``
    runs it and returns the exit code (raise :class:`InputError` for bad
    input: :func:`main` turns it into one line and exit 2).
    """

    name: str
    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    handler: Callable[[argparse.Namespace], int]


def _say(args, *lines: str) -> None:
    if not getattr(args, "quiet", False):
        for line in lines:
            print(line)


def _warn(message: str) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


# ---------------------------------------------------------------------------
# run
# ---------------------------------------------------------------------------
def _model_names(values) -> list[str]:
    """--model may be repeated and comma-separated; checked against the registry."""
    from .models.base import available_models

    names: list[str] = []
    for v in values or ["mlplc2"]:
        for name in v.split(","):
            name = name.strip().lower()
            if not name:
                continue
            if name not in available_models():
                raise InputValueError(f"unknown model {name!r}; choose from {', '.join(available_models())}")
            if name not in names:
                names.append(name)
    if not names:
        raise InputValueError("--model needs at least one model name")
    return names


def number_type(cast, ok, expected: str):
    """An argparse ``type``: ``cast(text)``, accepted when ``ok(value)``; else
    "expected <expected>, got '<text>'" (argparse turns it into a one-line usage error)."""

    def parse(text: str):
        try:
            value = cast(text)
        except ValueError:
            value = None
        if value is None or not ok(value):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value

    return parse


_nonneg_int = number_type(int, lambda v: v >= 0, "an integer >= 0")
_pos_float = number_type(float, lambda v: math.isfinite(v) and v > 0, "a positive number")
_hfov = number_type(float, lambda v: math.isfinite(v) and 0 < v < 180, "degrees in (0, 180)")
_nonneg_float = number_type(float, lambda v: math.isfinite(v) and v >= 0, "a number >= 0")


def _add_run(p: argparse.ArgumentParser) -> None:
    from .models.base import available_models

    p.add_argument("source", help="video file (AVI, MP4, ...), folder of images, glob pattern "
                                  "('frames/*.png', quoted) or camera index (0, 1, ...)")
    p.add_argument("--model", "-m", action="append", metavar="NAME",
                   help=f"model(s) to run, repeatable or comma-separated; one of "
                        f"{', '.join(available_models())} (default: mlplc2)")
    p.add_argument("--out", "-o", metavar="DIR",
                   help="output folder (default: <stem>_mlplc2/ next to the input)")
    p.add_argument("--fps", type=_pos_float, metavar="F",
                   help="frame rate to assume (default: the video's; images: 30)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--resize", metavar="WxH",
                      help="resize frames before the models (e.g. 320x240); coordinates in the "
                           "outputs stay in input pixels")
    size.add_argument("--scale", type=_pos_float, metavar="S", help="resize by a factor (e.g. 0.5)")
    p.add_argument("--start", type=_nonneg_int, default=0, metavar="N", help="first frame (0-based)")
    p.add_argument("--end", type=_nonneg_int, metavar="N", help="stop before this frame")
    p.add_argument("--video", action="store_true", help="also write annotated.mp4 with the fields drawn")
    p.add_argument("--all-fields", action="store_true",
                   help="with --video: draw every field, not only those that respond or are in alarm")
    p.add_argument("--hfov", type=_hfov, metavar="DEG",
                   help="camera's horizontal field of view in degrees: targets.csv / fields.json give "
                        "bearings in degrees (default: pixels from the image centre); see docs/targets.md")
    p.add_argument("--backend", choices=("opencv", "pyav"), default="opencv",
                   help="video decoder (default: opencv)")
    p.add_argument("--skip-repeats", type=_nonneg_float, nargs="?", const=REPEAT_THRESHOLD, metavar="LEVEL",
                   help=f"hold the models' output on duplicated frames: frames in which no pixel changed "
                        f"by more than LEVEL grey levels (default LEVEL {REPEAT_THRESHOLD:g}) since the last "
                        f"processed one, at most {MAX_REPEATS} in a row; for videos whose frames were "
                        f"repeated to raise the frame rate (docs/model.md)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_run(args) -> int:
    from .io import parse_resize
    from .runner import RunInterrupted, TruncatedInputWarning, run

    models = _model_names(args.model)
    resize = parse_resize(args.resize, name="--resize") if args.resize is not None else None
    if args.end is not None and args.end <= args.start:
        raise InputValueError(f"--end ({args.end}) must be larger than --start ({args.start})")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TruncatedInputWarning)  # reported below as one line
        try:
            result = run(args.source, models, out=args.out, fps=args.fps, resize=resize, scale=args.scale,
                         start=args.start, end=args.end, video=args.video, quiet=args.quiet,
                         hfov_deg=args.hfov, keep_rows=False, repeat_threshold=args.skip_repeats,
                         backend=args.backend, draw_fields="all" if args.all_fields else "responding")
        except RunInterrupted as exc:
            return _report_interrupt(exc)
    _print_run_summary(args, result)
    if result.truncated:
        _warn(result.message)
        return EXIT_TRUNCATED
    return EXIT_OK


def _timing(result) -> str:
    """``in 12.3 s (32.5 frames/s)``: the wall time of a run's frame loop and its rate."""
    rate = result.n_frames / result.seconds if result.seconds > 0 else math.inf
    return f"in {result.seconds:.1f} s ({rate:.1f} frames/s)"


def _report_interrupt(exc) -> int:
    """One line for a run stopped by Ctrl-C or SIGTERM (``runner.RunInterrupted``)."""
    res = exc.result
    print(f"{PROG}: interrupted after {res.n_frames} frames; outputs for them are in {res.out}", file=sys.stderr)
    return EXIT_INTERRUPTED


def _print_run_summary(args, result) -> None:
    w, h = result.size
    mw, mh = result.model_size
    size = f"{w}x{h}" + (f" -> {mw}x{mh}" if (mw, mh) != (w, h) else "")
    lines = [f"{result.n_frames} frames of {result.source} ({size}, {result.fps:g} fps) {_timing(result)}"]
    for name in result.models:
        fields = result.fields.get(name, [])
        if fields:
            alarms = [f for f in fields if f["first_alarm_frame"] is not None]
            lines.append(f"  {name}: {len(fields)} field(s), {len(alarms)} in alarm")
            for f in sorted(fields, key=lambda f: -f["peak_response"])[:6]:
                alarm = f", alarm at frame {f['first_alarm_frame']}" if f["first_alarm_frame"] is not None else ""
                lines.append(f"    #{f['id']} at ({f['x']:.0f}, {f['y']:.0f}), frames {f['born']}-"
                             f"{'' if f['died'] is None else f['died']}, peak {f['peak_response']:.3g} "
                             f"at frame {f['peak_frame']}{alarm}")
        else:
            first_alarm = result.alarms[name]["first"]
            first = f", first alarm at frame {first_alarm}" if first_alarm is not None else ", no alarm"
            lines.append(f"  {name}: no fields{first}")
    if result.out is not None:
        lines.append(f"outputs in {result.out}: {', '.join(sorted(result.files))}")
    _say(args, *lines)


# ---------------------------------------------------------------------------
# stimulus
# ---------------------------------------------------------------------------
def _add_stimulus(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", help="stimulus name (mlplc2.stimuli.NAMES, e.g. four_phase, six_objects)")
    p.add_argument("--out", "-o", required=True, metavar="FILE.mp4", help="video to write (.mp4 or .avi)")
    p.add_argument("--gt", metavar="FILE.json", help="ground truth JSON (default: <stem>_gt.json beside it)")
    p.add_argument("--seed", type=int, help="seed of the procedural background")
    p.add_argument("--background", metavar="procedural|plain|PATH",
                   help="background: 'procedural', 'plain' or an image file")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing on success")


def _cmd_stimulus(args) -> int:
    from .runner import write_stimulus

    try:
        from . import stimuli
    except ImportError:  # pragma: no cover - the module ships with the package
        raise InputError("mlplc2.stimuli is not available in this installation") from None
    if args.name not in stimuli.NAMES:
        raise InputValueError(f"unknown stimulus {args.name!r}; choose from {', '.join(stimuli.NAMES)}")
    options = {}
    if args.seed is not None:
        options["seed"] = args.seed
    if args.background is not None:
        bg = args.background
        if bg not in ("procedural", "plain") and not Path(bg).is_file():
            raise InputValueError(f"--background {bg!r}: not 'procedural', 'plain' or an existing image file")
        options["background"] = bg
    video, gt = write_stimulus(args.name, args.out, gt=args.gt, **options)
    _say(args, f"wrote {video} and {gt}")
    return EXIT_OK


# ---------------------------------------------------------------------------
# demo
# ---------------------------------------------------------------------------
def _add_demo(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", "-o", default="mlplc2_demo", metavar="DIR",
                   help="folder for demo.mp4, its ground truth and the outputs (default: ./mlplc2_demo)")
    p.add_argument("--scene", choices=("four_phase", "six_objects"), default="four_phase",
                   help="which multi-object scene (default: four_phase, 400 frames)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_demo(args) -> int:
    from .runner import RunInterrupted, demo

    try:
        d = demo(args.out, scene=args.scene, quiet=args.quiet)
    except RunInterrupted as exc:
        return _report_interrupt(exc)
    lines = [f"demo scene {d.video} ({d.result.n_frames} frames) with {', '.join(d.result.models)} "
             f"{_timing(d.result)}",
             "  object  centre        frames    mlplc2 field  centre        error   first alarm"]
    for m in d.matches:
        cx, cy = m["center"]
        t0, t1 = m["frames"]
        if m["field"] is None:
            lines.append(f"  {m['object']:>6}  ({cx:>3.0f}, {cy:>3.0f})  {t0:>3}-{t1:<4}  none")
            continue
        fx, fy = m["field_center"]
        alarm = "-" if m["first_alarm_frame"] is None else str(m["first_alarm_frame"])
        lines.append(f"  {m['object']:>6}  ({cx:>3.0f}, {cy:>3.0f})  {t0:>3}-{t1:<4}  #{m['field']:<11} "
                     f"({fx:>3.0f}, {fy:>3.0f})  {m['distance']:>5.1f}px  {alarm}")
    n_fields = len(d.result.fields.get("mlplc2", []))
    matched = {m["field"] for m in d.matches if m["field"] is not None}
    lines.append(f"  mlplc2 made {n_fields} field(s); {len(matched)} matched an object")
    lines.append(f"outputs in {d.result.out}: {', '.join(sorted(d.result.files))}")
    _say(args, *lines)
    return EXIT_OK


# ---------------------------------------------------------------------------
# evaluate (docs/evaluation.md)
# ---------------------------------------------------------------------------
def _add_evaluate(p: argparse.ArgumentParser) -> None:
    p.add_argument("inputs", nargs="+", metavar="RESULTS_OR_VIDEOS",
                   help="output folders of 'mlplc2 run' / 'mlplc2 batch' (responses.csv + fields.json), "
                        "or videos (the models are run first)")
    p.add_argument("--gt", required=True, metavar="GT.json", help="ground truth (see docs/evaluation.md)")
    p.add_argument("--model", "-m", action="append", metavar="NAME",
                   help="model(s) to score, repeatable or comma-separated (default: all in the results; "
                        "for videos: all registered models)")
    p.add_argument("--out", "-o", metavar="DIR", help="write evaluation.md and evaluation.json here")
    p.add_argument("--match-radius", type=_pos_float, default=20.0, metavar="PX",
                   help="a field this close to an object's centre stands for it (default 20, ground-truth pixels)")
    p.add_argument("--tail", type=_nonneg_int, default=25, metavar="FRAMES",
                   help="frames after an approach during which its fields/alarms still count (default 25)")
    p.add_argument("--resize", metavar="WxH", help="for video inputs: resize frames before the models")
    p.add_argument("--skip-repeats", type=_nonneg_float, nargs="?", const=REPEAT_THRESHOLD, metavar="LEVEL",
                   help="for video inputs: hold the models' output on duplicated frames "
                        "(as in 'mlplc2 run --skip-repeats')")
    p.add_argument("--details", action="store_true", help="also print the per-video table")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")


def _cmd_evaluate(args) -> int:
    from .evaluate import EvaluationWarning, evaluate
    from .io import parse_resize

    models = _model_names(args.model) if args.model else None
    options = {"resize": parse_resize(args.resize, name="--resize")} if args.resize else {}
    if args.skip_repeats is not None:
        options["repeat_threshold"] = args.skip_repeats
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EvaluationWarning)  # reported below, one line each
        ev = evaluate(args.inputs, args.gt, models=models, match_radius=args.match_radius, tail=args.tail,
                      run_options=options, progress=not args.quiet)
    for w in ev.warnings:
        _warn(w)
    for s in ev.skipped:
        _warn(f"{s}: no ground truth for it in {args.gt}; not scored")
    _say(args, ev.to_markdown(details=args.details))
    if args.out:
        files = ev.write(args.out)
        _say(args, f"wrote {', '.join(str(f) for f in files.values())}")
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
    p.add_argument("--workers", type=_nonneg_int, metavar="N",
                   help="local cluster workers (default min(4, CPUs); 0 = sequential, no Dask)")
    p.add_argument("--resize", metavar="WxH", help="resize frames before the models")
    p.add_argument("--skip-repeats", type=_nonneg_float, nargs="?", const=REPEAT_THRESHOLD, metavar="LEVEL",
                   help="hold the models' output on duplicated frames (as in 'mlplc2 run --skip-repeats')")
    p.add_argument("--plot", action="store_true", help="also write each task's responses.png")
    p.add_argument("--force", action="store_true", help="rerun tasks that are already done")
    p.add_argument("--parquet", action="store_true", help="also write results.parquet (needs pandas, pyarrow)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_batch(args) -> int:
    from .batch import BatchInterrupted, batch
    from .io import parse_resize

    models = _model_names(args.model)
    options = {"resize": parse_resize(args.resize, name="--resize")} if args.resize else {}
    if args.skip_repeats is not None:
        options["repeat_threshold"] = args.skip_repeats
    try:
        res = batch(args.inputs, args.out, models=models, params=args.params, sweep=args.sweep,
                    scheduler=args.scheduler, workers=args.workers, run_options=options, plot=args.plot,
                    progress=not args.quiet, force=args.force, parquet=args.parquet)
    except BatchInterrupted as exc:
        if args.quiet:  # with progress output batch() has already said it
            print(f"{PROG}: {_one_line(str(exc))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    reported = set()
    for r in res.rows:
        if r["status"] in ("error", "truncated") and r["out"] not in reported:  # once per task
            reported.add(r["out"])
            _warn(f"{r['video']} ({r['model']}, {r['out']}): {r['error']}")
    plotted = f" ({res.plotted} of them plotted now)" if res.plotted else ""
    _say(args, f"{len(res.rows)} task(s): {res.ran} ran, {res.skipped} already done{plotted}, {res.failed} failed; "
               f"{len(res.videos)} video(s) in {res.seconds:.1f} s on {res.scheduler}",
         f"results in {res.table}")
    return EXIT_INPUT if res.failed else EXIT_OK


# ---------------------------------------------------------------------------
# reproduce (implemented in mlplc2.reproduce, imported only when used)
# ---------------------------------------------------------------------------
def _add_reproduce(p: argparse.ArgumentParser) -> None:
    from .reproduce import add_arguments

    add_arguments(p)


def _cmd_reproduce(args) -> int:
    from .reproduce import cli_handler

    return cli_handler(args)


# ---------------------------------------------------------------------------
# bench (implemented in mlplc2.bench; benchmarks/README.md)
# ---------------------------------------------------------------------------
def _add_bench(p: argparse.ArgumentParser) -> None:
    from .bench import add_arguments

    add_arguments(p)


def _cmd_bench(args) -> int:
    from .bench import cli_handler

    return cli_handler(args)


# ---------------------------------------------------------------------------
# the table and main
# ---------------------------------------------------------------------------
#: Subcommands in help order. Add one entry per new subcommand.
SUBCOMMANDS: list[Subcommand] = [
    Subcommand("run", "run models on a video, image folder or camera; write CSV, JSON, PNG (and MP4)",
               _add_run, _cmd_run),
    Subcommand("stimulus", "write a synthetic stimulus video and its ground truth", _add_stimulus,
               _cmd_stimulus),
    Subcommand("demo", "generate a multi-object scene, run the models on it, compare with the truth",
               _add_demo, _cmd_demo),
    Subcommand("evaluate", "score results (or videos) against ground truth; per-model comparison table",
               _add_evaluate, _cmd_evaluate),
    Subcommand("batch", "run every (video, model, parameter set) as a Dask task; one results table",
               _add_batch, _cmd_batch),
    Subcommand("reproduce", "run the paper's Sec. IV experiments; write Fig. 3-6 and a PASS/FAIL report",
               _add_reproduce, _cmd_reproduce),
    Subcommand("bench", "time the LPLC2 models per frame size: ms/frame, reference, bandwidth probe, memory",
               _add_bench, _cmd_bench),
]


def add_subcommand(name: str, help: str, add_arguments, handler) -> Subcommand:
    """Register a subcommand (replacing one of the same name)."""
    cmd = Subcommand(name, help, add_arguments, handler)
    SUBCOMMANDS[:] = [c for c in SUBCOMMANDS if c.name != name] + [cmd]
    return cmd


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = _Parser(prog=PROG, description="mLPLC2 looming detection: run models on videos, "
                                            "make stimuli, see a demo.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=_Parser)
    for cmd in SUBCOMMANDS:
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        cmd.add_arguments(p)
        p.set_defaults(_handler=cmd.handler)
    return parser


def _oserror_line(exc: OSError) -> str:
    if exc.strerror and exc.filename:
        return f"{exc.filename}: {exc.strerror}"
    return str(exc) or type(exc).__name__


def _one_line(text: str) -> str:
    return " ".join(text.split()) or "unknown error"


def _quiet_decoders() -> None:
    """Keep FFmpeg's and OpenCV's own log lines off stderr: errors are reported
    as one ``mlplc2: error:`` line instead. Set ``OPENCV_FFMPEG_LOGLEVEL`` /
    ``OPENCV_LOG_LEVEL`` to see them (FFmpeg reads its level once per process)."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    if "OPENCV_LOG_LEVEL" not in os.environ:
        try:
            import cv2

            cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
        except (ImportError, AttributeError):  # pragma: no cover - old or absent OpenCV
            pass


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ARG001
    """``warnings.showwarning`` of the CLI: one line, ``mlplc2: warning: ...``."""
    _warn(_one_line(str(message)))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mlplc2`` console script; returns the exit code.

    SIGTERM (what batch schedulers and ``timeout`` send) is handled like Ctrl-C: the
    outputs of the frames done are written and the exit code is 130 (``mlplc2._signals``).
    Warnings are printed as one line each, ``mlplc2: warning: ...``.
    """
    with interrupts(sigterm=True), warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _main(argv)


def _main(argv: list[str] | None) -> int:
    _quiet_decoders()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0)
    try:
        return int(args._handler(args))
    except InputError as exc:
        print(f"{PROG}: error: {_one_line(str(exc))}", file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        print(f"{PROG}: error: {_one_line(_oserror_line(exc))}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
