"""Command line: ``mlplc2 run | stimulus | demo | evaluate | batch | benchmark | ...`` (see docs/cli.md).

Thin by design: each subcommand parses its arguments and calls one public
function (:func:`mlplc2.run`, :func:`mlplc2.stimuli.write`,
:func:`mlplc2.runner.demo`). Subcommands live in the :data:`SUBCOMMANDS`
table; adding one is one :class:`Subcommand` entry (its options and its handler, which
calls the public function of the module that implements it).

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

from ._signals import interrupts
from ._validation import InputError, InputValueError
from .io import parse_resize
from .models.base import MAX_REPEATS, REPEAT_THRESHOLD, available_models, resolve_names

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS",
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
_pos_int = number_type(int, lambda v: v >= 1, "a positive integer")
_pos_float = number_type(float, lambda v: math.isfinite(v) and v > 0, "a positive number")
_hfov = number_type(float, lambda v: math.isfinite(v) and 0 < v < 180, "degrees in (0, 180)")
_nonneg_float = number_type(float, lambda v: math.isfinite(v) and v >= 0, "a number >= 0")


def _add_repeat_options(p: argparse.ArgumentParser, help: str) -> None:
    """``--skip-repeats`` (a plain flag: threshold ``REPEAT_THRESHOLD``), ``--repeat-level N``
    (that threshold instead; implies skipping) and ``--every-frame`` (never hold), read back by
    :func:`_repeat_threshold`; without them the models detect duplicated frames themselves."""
    p.add_argument("--skip-repeats", action="store_true", help=help)
    p.add_argument("--repeat-level", type=_nonneg_float, metavar="N",
                   help=f"grey-level change up to which a frame counts as a repeat (default "
                        f"{REPEAT_THRESHOLD:g}); implies --skip-repeats")
    p.add_argument("--every-frame", action="store_true",
                   help="step the models on every frame, duplicates too (by default the models hold "
                        "their output on duplicated frames when the video looks duplicated)")


def _repeat_threshold(args) -> float | str | None:
    """``Model.repeat_threshold`` asked for by :func:`_add_repeat_options`: a level, None
    (``--every-frame``) or ``"auto"`` (no option: the models' duplicate detection)."""
    if args.every_frame and (args.skip_repeats or args.repeat_level is not None):
        raise InputValueError("--every-frame cannot be combined with --skip-repeats or --repeat-level")
    if args.repeat_level is not None:
        return args.repeat_level
    if args.skip_repeats:
        return REPEAT_THRESHOLD
    return None if args.every_frame else "auto"


def _add_warning_options(p: argparse.ArgumentParser, what: str = "") -> None:
    """``--horizon S`` and ``--max-miss W``: the warning settings of the target layer
    (``TargetParams.horizon_s``, ``.max_miss``), read back by :func:`_target_options`."""
    from .targets import TargetParams

    d = TargetParams()
    p.add_argument("--horizon", type=_nonneg_float, metavar="S",
                   help=f"{what}a target warns only when its time to contact is at most S seconds "
                        f"(TargetParams.horizon_s, default {d.horizon_s:g}; docs/targets.md)")
    p.add_argument("--max-miss", type=_nonneg_float, metavar="W",
                   help=f"{what}... and its predicted miss at contact at most W object widths "
                        f"(TargetParams.max_miss, default {d.max_miss:g})")


def _target_options(args) -> dict:
    """The ``target_params`` of :func:`mlplc2.run` asked for by :func:`_add_warning_options`: a
    dict of :class:`~mlplc2.targets.TargetParams` fields (JSON-able, for batch tasks; empty: the
    defaults), checked here so that a bad value is one error before anything runs."""
    from .targets import TargetParams

    options = {}
    if args.horizon is not None:
        options["horizon_s"] = args.horizon
    if args.max_miss is not None:
        options["max_miss"] = args.max_miss
    TargetParams().replace(**options)
    return options


def _video_run_options(args) -> dict:
    """The ``run_options`` of ``mlplc2 evaluate`` and ``batch``: ``--resize``, the repeat and the warning options."""
    options = {"resize": parse_resize(args.resize, name="--resize")} if args.resize else {}
    if _repeat_threshold(args) != "auto":  # --skip-repeats / --repeat-level / --every-frame
        options["repeat_threshold"] = _repeat_threshold(args)
    if _target_options(args):  # --horizon / --max-miss: part of each task's options
        options["target_params"] = _target_options(args)
    return options


def _add_run(p: argparse.ArgumentParser) -> None:
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
    p.add_argument("--video", action="store_true", help="also write annotated.mp4 with the targets drawn")
    fields = p.add_mutually_exclusive_group()
    fields.add_argument("--fields", action="store_true",
                        help="with --video: also draw the attention fields that respond or alarm (by default "
                             "the video shows the targets only)")
    fields.add_argument("--all-fields", action="store_true",
                        help="with --video: also draw every attention field")
    p.add_argument("--hfov", type=_hfov, metavar="DEG",
                   help="camera's horizontal field of view in degrees: targets.csv / fields.json give "
                        "bearings in degrees (default: pixels from the image centre); see docs/targets.md")
    p.add_argument("--decoder", choices=("opencv", "pyav"), default="opencv",
                   help="video decoder (default: opencv)")
    p.add_argument("--backend", dest="decoder", choices=("opencv", "pyav"), default=argparse.SUPPRESS,
                   help=argparse.SUPPRESS)  # the old name of --decoder, kept for old command lines
    _add_repeat_options(p, f"hold the models' output on duplicated frames: frames in which no pixel "
                          f"changed by more than {REPEAT_THRESHOLD:g} grey levels (--repeat-level) since the "
                          f"last processed one, at most {MAX_REPEATS} in a row; for videos whose frames were "
                          f"repeated to raise the frame rate (docs/model.md)")
    _add_warning_options(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_run(args) -> int:
    from .runner import RunInterrupted, TruncatedInputWarning, run

    models = resolve_names(args.model or ["mlplc2"], what="--model")
    resize = parse_resize(args.resize, name="--resize") if args.resize is not None else None
    if args.end is not None and args.end <= args.start:
        raise InputValueError(f"--end ({args.end}) must be larger than --start ({args.start})")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TruncatedInputWarning)  # reported below as one line
        try:
            result = run(args.source, models, out=args.out, fps=args.fps, resize=resize, scale=args.scale,
                         start=args.start, end=args.end, video=args.video, quiet=args.quiet,
                         hfov_deg=args.hfov, keep_rows=False, repeat_threshold=_repeat_threshold(args),
                         decoder=args.decoder, draw_fields="all" if args.all_fields else "responding" if args.fields else "auto",
                         target_params=_target_options(args) or None)
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
        targets = result.target_summaries.get(name)
        if targets:
            warned = [t for t in targets if t["first_warning_frame"] is not None]
            lines.append(f"  {name}: {len(targets)} target(s), {len(warned)} warned"
                         + (f" (first warning at frame {min(t['first_warning_frame'] for t in warned)})"
                            if warned else ""))
    if result.out is not None:
        lines.append(f"outputs in {result.out}: {', '.join(sorted(result.files))}")
    _say(args, *lines)
    held = max(result.repeated.values(), default=0)
    if held and not (args.quiet or args.skip_repeats or args.repeat_level is not None):
        print(f"{PROG}: note: the video repeats its frames (duplicated frames): the models held their output on "
              f"{held} of {result.n_frames} frames (--every-frame processes every frame)", file=sys.stderr)


# ---------------------------------------------------------------------------
# stimulus
# ---------------------------------------------------------------------------
#: ``mlplc2 stimulus``'s own options: a generator parameter of one of these names cannot be set
#: from the command line (none has one; tests/test_cli.py checks).
STIMULUS_OWN_OPTIONS = ("name", "out", "gt", "quiet", "help")
_STIM = "stimulus_option__"  # argparse dest prefix of the generators' options


def _flag(name: str) -> str:
    """A Python parameter name as a command-line option: ``contact_time`` -> ``--contact-time``."""
    return "--" + name.replace("_", "-")


@dataclass(frozen=True)
class _OptionKind:
    """How ``mlplc2 stimulus`` reads one generator parameter: its metavar, what it expects
    (for help and errors), ``parse(text)`` (raises ValueError) and whether it is an on/off flag."""

    metavar: str
    expected: str
    parse: Callable[[str], object]
    flag: bool = False


def _parse_bool(text: str) -> bool:
    t = text.strip().lower()
    if t in ("1", "true", "yes", "on"):
        return True
    if t in ("0", "false", "no", "off"):
        return False
    raise ValueError(text)


def _parse_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(text)
    return value


def _number_or_text(text: str):
    try:
        return _parse_float(text)
    except ValueError:
        return text


def _tuple_kind(name: str, args: tuple) -> _OptionKind | None:
    """Tuples of numbers: ``WxH`` for a 2-tuple named ``size`` / ``*_size``, else ``X,Y`` (``X,Y,Z``, ...)."""
    variable = len(args) == 2 and args[1] is Ellipsis
    elems = args[:1] if variable else args
    if not elems or any(e not in (int, float) for e in elems):
        return None
    sizes = len(args) == 2 and not variable and (name == "size" or name.endswith("_size"))
    sep = "x" if sizes else ","
    what = "integers" if all(e is int for e in elems) else "numbers"
    if sizes:
        metavar, expected = "WxH", "WxH (e.g. 320x240)"
    elif variable:
        metavar, expected = "V1,V2,...", f"comma-separated {what}"
    else:
        metavar = ",".join("XYZ"[i] if len(elems) <= 3 else f"V{i + 1}" for i in range(len(elems)))
        expected = f"{metavar} ({len(elems)} {what})"

    def parse(text: str) -> tuple:
        parts = text.lower().split(sep) if sizes else text.split(sep)
        if not variable and len(parts) != len(elems):
            raise ValueError(text)
        types_ = [elems[0]] * len(parts) if variable else list(elems)
        return tuple(int(p) if t is int else _parse_float(p) for t, p in zip(types_, parts))

    return _OptionKind(metavar, expected, parse)


def _option_kind(param) -> _OptionKind:
    """The :class:`_OptionKind` of a generator parameter, from its annotation (int, float, str,
    bool, Optional, tuples of numbers; unannotated: the default's type; anything else, such as
    Any: a number if it reads as one, else text). An Optional parameter also takes ``none``."""
    import inspect
    import types
    import typing

    ann, default = param.annotation, param.default
    optional = default is None
    if typing.get_origin(ann) in (typing.Union, types.UnionType):
        args = typing.get_args(ann)
        rest = [a for a in args if a is not type(None)]
        optional = optional or len(rest) < len(args)
        if len(rest) > 1:  # float | tuple[float, float], ...: the first that reads the text
            kinds = [_option_kind(param.replace(annotation=a, default=inspect.Parameter.empty)) for a in rest]

            def first(text: str, kinds=kinds):
                for k in kinds:
                    try:
                        return k.parse(text)
                    except ValueError:
                        pass
                raise ValueError(text)

            kind = _OptionKind("|".join(k.metavar for k in kinds), " or ".join(k.expected for k in kinds), first)
            return _optional(kind) if optional else kind
        ann = rest[0]
    if ann is inspect.Parameter.empty or isinstance(ann, str):  # unannotated or unresolved
        if isinstance(default, tuple) and default:
            ann = tuple[tuple(type(v) for v in default)]
        else:
            ann = type(default) if isinstance(default, (bool, int, float, str)) else typing.Any
    kind = None
    if ann is bool:
        kind = _OptionKind("", "true or false", _parse_bool, flag=True)
    elif ann is int:
        kind = _OptionKind("N", "an integer", int)
    elif ann is float:
        kind = _OptionKind("F", "a number", _parse_float)
    elif ann is str:
        kind = _OptionKind("TEXT", "text", str)
    elif typing.get_origin(ann) is tuple:
        kind = _tuple_kind(param.name, typing.get_args(ann))
    if kind is None:
        kind = _OptionKind("VALUE", "a number or text", _number_or_text)
    return _optional(kind) if optional else kind


def _optional(kind: _OptionKind) -> _OptionKind:
    """``kind`` that also reads ``none`` (as None)."""
    def parse(text: str, inner=kind.parse):
        return None if text.strip().lower() == "none" else inner(text)

    return _OptionKind(kind.metavar, f"{kind.expected}, or none", parse, kind.flag)


def _show_default(value, kind: _OptionKind) -> str:
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, tuple):
        return ("x" if kind.metavar == "WxH" else ",").join(_show_default(v, kind) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _stimulus_table() -> dict[str, dict[str, tuple]]:
    """stimulus name -> {parameter name: (inspect.Parameter, _OptionKind)}, from the generators."""
    from . import stimuli

    return {name: {p: (param, _option_kind(param)) for p, param in stimuli.parameters(name).items()
                   if p not in STIMULUS_OWN_OPTIONS}
            for name in stimuli.NAMES}


def _stimulus_epilog(table) -> str:
    """Per stimulus (those with the same options together), its options and their defaults."""
    import textwrap

    groups: dict[tuple, list[str]] = {}
    for name, opts in table.items():
        # no-break spaces inside one option, so that a line never splits '--seed N [0]'
        key = tuple(f"{_flag(p)}{' ' + k.metavar if k.metavar else ''} [{_show_default(param.default, k)}]"
                    .replace(" ", "\xa0") for p, (param, k) in opts.items())
        groups.setdefault(key, []).append(name)
    lines = ["stimuli and the options each takes [default]:"]
    for key, names in groups.items():
        lines.append(textwrap.fill(", ".join(names) + ":", 78, initial_indent="  ", subsequent_indent="  "))
        lines.append(textwrap.fill("  ".join(key) or "(no options)", 78, initial_indent="      ",
                                   subsequent_indent="      ", break_on_hyphens=False).replace("\xa0", " "))
    lines += ["", textwrap.fill("Options use dashes here and underscores in Python (--contact-time is "
                                "contact_time of mlplc2.stimuli.looming); one whose value may be 'none' "
                                "takes the word none.", 78)]
    return "\n".join(lines)


def _add_stimulus(p: argparse.ArgumentParser) -> None:
    table = _stimulus_table()
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.epilog = _stimulus_epilog(table)
    p.add_argument("name", help="stimulus name (mlplc2.stimuli.NAMES; listed below with their options)")
    p.add_argument("--out", "-o", required=True, metavar="FILE.mp4", help="video to write (.mp4 or .avi)")
    p.add_argument("--gt", metavar="FILE.json", help="ground truth JSON (default: <stem>_gt.json beside it)")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing on success")
    per_option: dict[str, dict[str, list[str]]] = {}  # parameter -> {expected: [stimuli]}
    kinds: dict[str, list[_OptionKind]] = {}
    for name, opts in table.items():
        for pname, (_, kind) in opts.items():
            per_option.setdefault(pname, {}).setdefault(kind.expected, []).append(name)
            kinds.setdefault(pname, []).append(kind)
    group = p.add_argument_group("stimulus options (the generators' parameters; which stimulus takes "
                                 "which: below)")
    for pname, by_kind in per_option.items():
        help_ = "; ".join(f"{exp} ({', '.join(names)})" for exp, names in by_kind.items()).replace("%", "%%")
        if all(k.flag for k in kinds[pname]):
            group.add_argument(_flag(pname), dest=_STIM + pname, action=argparse.BooleanOptionalAction,
                               default=argparse.SUPPRESS, help=help_)
        else:
            metavar = "|".join(dict.fromkeys(k.metavar or "true|false" for k in kinds[pname]))
            group.add_argument(_flag(pname), dest=_STIM + pname, metavar=metavar, default=argparse.SUPPRESS,
                               help=help_)


def _stimulus_options(name: str, given: dict, table) -> dict:
    """The generator keyword arguments from the command-line texts ``given`` (one-line errors)."""
    accepted = table[name]
    options = {}
    for pname, text in given.items():
        if pname not in accepted:
            flags = ", ".join(_flag(p) for p in accepted) or "none"
            raise InputValueError(f"{_flag(pname)}: stimulus {name!r} has no such option (its options: {flags}; "
                                  f"see 'mlplc2 stimulus --help')")
        kind = accepted[pname][1]
        if isinstance(text, bool):  # an on/off flag
            options[pname] = text
            continue
        try:
            options[pname] = kind.parse(text)
        except ValueError:
            raise InputValueError(f"{_flag(pname)}: expected {kind.expected}, got {text!r} "
                                  f"(see 'mlplc2 stimulus --help')") from None
    return options


def _cmd_stimulus(args) -> int:
    import re

    from . import stimuli

    if args.name not in stimuli.NAMES:
        raise InputValueError(f"unknown stimulus {args.name!r}; choose from {', '.join(stimuli.NAMES)} "
                              f"(see 'mlplc2 stimulus --help')")
    given = {k[len(_STIM):]: v for k, v in vars(args).items() if k.startswith(_STIM)}
    options = _stimulus_options(args.name, given, _stimulus_table())
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            video, gt = stimuli.write(args.name, args.out, gt=args.gt, **options)
    except InputValueError as exc:
        # the generator names its parameters in Python: name the options given as written here
        msg = new = str(exc)
        for pname in options:
            new = re.sub(rf"(?<![\w\-/.]){re.escape(pname)}(?![\w\-/.])", _flag(pname), new)
        if new == msg:
            raise
        raise InputValueError(f"{new} (see 'mlplc2 stimulus --help')") from None
    for w in caught:  # the generator's own warnings (an object never visible, ...) as one line each
        if issubclass(w.category, UserWarning):
            _warn(_one_line(str(w.message)))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
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
                        "or videos, folders of videos or of images (the models are run first)")
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
    _add_repeat_options(p, "for video inputs: hold the models' output on duplicated frames "
                          "(as in 'mlplc2 run --skip-repeats')")
    _add_warning_options(p, "for video inputs: ")
    p.add_argument("--details", action="store_true", help="also print the per-video table")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")


def _cmd_evaluate(args) -> int:
    from .evaluate import EvaluationWarning, evaluate

    models = resolve_names(args.model, what="--model") if args.model else None
    options = _video_run_options(args)
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
    _add_repeat_options(p, "hold the models' output on duplicated frames (as in 'mlplc2 run --skip-repeats')")
    _add_warning_options(p)
    p.add_argument("--plot", action="store_true", help="also write each task's responses.png")
    p.add_argument("--force", action="store_true", help="rerun tasks that are already done")
    p.add_argument("--parquet", action="store_true", help="also write results.parquet (needs pandas, pyarrow)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_batch(args) -> int:
    from .batch import BatchInterrupted, batch

    models = resolve_names(args.model or ["mlplc2"], what="--model")
    options = _video_run_options(args)
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
            _warn(f"{r['video']} ({r['label']}, {r['out']}): {r['error']}")
    plotted = f" ({res.plotted} of them plotted now)" if res.plotted else ""
    # counted in runs, which add up: tasks that differ only in parameters a model does not use share its run
    runs = f" in {res.tasks} run(s)" if res.tasks != len(res.rows) else ""
    _say(args, f"{len(res.rows)} task(s){runs}: {res.ran - res.failed_runs} ran, {res.skipped} already done{plotted}, "
               f"{res.failed_runs} failed; {len(res.videos)} video(s) in {res.seconds:.1f} s on {res.scheduler}",
         f"results in {res.table}")
    return EXIT_INPUT if res.failed else EXIT_OK


# ---------------------------------------------------------------------------
# benchmark (docs/benchmark.md)
# ---------------------------------------------------------------------------
def _add_benchmark(p: argparse.ArgumentParser) -> None:
    from .benchmark import MODELS

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
    p.add_argument("--workers", type=_nonneg_int, metavar="N",
                   help="local cluster workers (default min(4, CPUs); 0 = sequential, no Dask)")
    _add_warning_options(p)
    p.add_argument("--force", action="store_true", help="rerun tasks that are already done")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bars and no table")


def _cmd_benchmark(args) -> int:
    from .batch import BatchInterrupted
    from .benchmark import benchmark

    models = resolve_names(args.model, what="--model") if args.model else None
    real = None if args.no_real else (args.real if args.real is not None else "auto")
    try:
        res = benchmark(args.out, quick=args.quick, models=models, real=real, scheduler=args.scheduler,
                        workers=args.workers, target_params=_target_options(args) or None,
                        progress=not args.quiet, force=args.force)
    except BatchInterrupted as exc:
        if args.quiet:  # with progress output batch() has already said it
            print(f"{PROG}: {_one_line(str(exc))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    _say(args, res.to_markdown().rstrip("\n"), f"wrote {', '.join(str(f) for f in res.files.values())}")
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

    from .reproduce import reproduce

    if args.data is not None and not Path(args.data).is_dir():
        raise InputValueError(f"--data {args.data}: not a folder")
    res = reproduce(args.data, args.out, quick=args.quick, quiet=args.quiet, params=args.params)
    for s in res.damaged:
        _warn(s)
    failing = [f"  {c.status}  {c.claim}: {c.measured}"
               + (f" ({c.docs['file']}, \"{c.docs['section']}\")" if c.docs else "")
               for c in res.claims if not c.passed]
    _say(args, f"{len(res.claims)} claims: {res.summary}", f"  parameters: {res.parameters}", *failing,
         *(f"  note: {s}" for s in res.skipped if s not in res.damaged),
         f"outputs in {res.out}: {', '.join(sorted(res.files))}")
    return EXIT_TRUNCATED if res.damaged else EXIT_OK


# ---------------------------------------------------------------------------
# params: the parameter tables (one source: the fields' metadata, mlplc2.params)
# ---------------------------------------------------------------------------
def _add_params(p: argparse.ArgumentParser) -> None:
    p.add_argument("--targets", action="store_true",
                   help="the target estimators' TargetParams instead of the model's Params")
    p.add_argument("--markdown", action="store_true",
                   help="as the Markdown table of docs/model.md (docs/targets.md with --targets)")


def _cmd_params(args) -> int:
    from .params import Params, parameter_table
    from .targets import TargetParams

    print(parameter_table(TargetParams if args.targets else Params, markdown=args.markdown), end="")
    return EXIT_OK


# ---------------------------------------------------------------------------
# bench (timing in mlplc2.bench; benchmarks/README.md)
# ---------------------------------------------------------------------------
def _add_bench(p: argparse.ArgumentParser) -> None:
    from .bench import DEFAULT_SIZES

    p.add_argument("--sizes", default=DEFAULT_SIZES, metavar="WxH,...",
                   help=f"frame sizes (default {DEFAULT_SIZES})")
    p.add_argument("--models", "--model", "-m", dest="models", action="append", metavar="NAME",
                   help="LPLC2-family model(s), repeatable or comma-separated (default: mlplc2)")
    p.add_argument("--threads", type=_pos_int, metavar="N",
                   help="threads for the fast front end and OpenCV (default: Numba's, i.e. all cores)")
    p.add_argument("--frames", type=_pos_int, default=100, metavar="N",
                   help="timed frames per model and size after 10 warm-up frames (default 100)")
    p.add_argument("--ref-frames", type=_pos_int, default=12, metavar="N",
                   help="timed frames of the reference front end (default 12)")
    p.add_argument("--rounds", type=_pos_int, default=1, metavar="R",
                   help="repeat every measurement R times and keep the smallest median (default 1)")
    p.add_argument("--no-reference", action="store_true", help="skip the reference front end")
    p.add_argument("--quiet", "-q", action="store_true", help="only the table")


def _cmd_bench(args) -> int:
    from .bench import describe, format_table, parse_sizes, run_bench

    names = resolve_names(args.models or ["mlplc2"], what="--models")
    family = [m for m in ("mlplc2", "slplc2", "lplc2") if m in available_models()]
    bad = [n for n in names if n not in family]
    if bad:
        raise InputValueError(f"--models: {', '.join(bad)} not benchmarked; choose from {', '.join(family)}")
    sizes = parse_sizes(args.sizes)

    def progress(msg):
        if not args.quiet:
            print(msg, file=sys.stderr, flush=True)

    rows = run_bench(sizes, names, threads=args.threads, frames=args.frames, ref_frames=args.ref_frames,
                     reference=not args.no_reference, rounds=args.rounds, progress=progress)
    print(format_table(rows))
    if not args.quiet:
        print("\n" + describe(args.frames, args.rounds))
    return EXIT_OK


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
    Subcommand("benchmark", "the standard suite of generated approaches (+ real clips), every model: how early "
                            "and how reliably each warns", _add_benchmark, _cmd_benchmark),
    Subcommand("reproduce", "run the paper's Sec. IV experiments; write Fig. 3-6 and a PASS/FAIL report",
               _add_reproduce, _cmd_reproduce),
    Subcommand("params", "print the parameters: Table I symbol, unit, default, valid values, description",
               _add_params, _cmd_params),
    Subcommand("bench", "time the LPLC2 models per frame size: ms/frame, reference, bandwidth probe, memory",
               _add_bench, _cmd_bench),
]


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
        args, extra = parser.parse_known_args(argv)
        if extra:  # pointing at the subcommand's help, not the top level's
            raise _UsageError(f"unrecognized arguments: {' '.join(extra)} (see '{PROG} {args.command} --help')")
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
        line = f"{exc.filename}: {exc.strerror}" if exc.strerror and exc.filename else str(exc) or type(exc).__name__
        print(f"{PROG}: error: {_one_line(line)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
