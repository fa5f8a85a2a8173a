"""``mlplc2 stimulus``: one option per parameter of the generator (:mod:`mlplc2.stimuli`),
read from its signature; writes the video and its ground truth (:func:`mlplc2.stimuli.write`).
"""

from __future__ import annotations

import argparse
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

from .._validation import InputTypeError, InputValueError
from .common import EXIT_OK, Subcommand, one_line, say, warn


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
    from .. import stimuli

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

    from .. import stimuli

    if args.name not in stimuli.NAMES:
        raise InputValueError(f"unknown stimulus {args.name!r}; choose from {', '.join(stimuli.NAMES)} "
                              f"(see 'mlplc2 stimulus --help')")
    given = {k[len(_STIM):]: v for k, v in vars(args).items() if k.startswith(_STIM)}
    options = _stimulus_options(args.name, given, _stimulus_table())
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            video, gt = stimuli.write(args.name, args.out, gt=args.gt, **options)
    except (InputValueError, InputTypeError) as exc:
        # the generator names its parameters in Python: name the options given as written here
        msg = new = str(exc)
        for pname in options:
            new = re.sub(rf"(?<![\w\-/.]){re.escape(pname)}(?![\w\-/.])", _flag(pname), new)
        if new == msg:
            raise
        raise type(exc)(f"{new} (see 'mlplc2 stimulus --help')") from None
    for w in caught:  # the generator's own warnings (an object never visible, ...) as one line each
        if issubclass(w.category, UserWarning):
            warn(one_line(str(w.message)))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    say(args, f"wrote {video} and {gt}")
    return EXIT_OK


STIMULUS = Subcommand("stimulus", "write a synthetic stimulus video and its ground truth", _add_stimulus,
                      _cmd_stimulus)
