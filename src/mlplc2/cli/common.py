"""What every ``mlplc2`` subcommand shares: the exit codes, the one-line parser errors, the
:class:`Subcommand` entry, printing (:func:`say`, :func:`warn`), the number types of the
options, and the repeat (``--skip-repeats``, ...) and warning (``--horizon``, ``--max-miss``)
options with the run options they give.
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import math
import os
import re
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from .._validation import InputValueError, did_you_mean
from ..io import parse_resize
from ..models.base import REGISTRY, REPEAT_THRESHOLD
from . import EXIT_INPUT, EXIT_INTERRUPTED, EXIT_OK, EXIT_TRUNCATED, PROG  # noqa: F401 - the subcommands' import


class UsageError(Exception):
    """argparse error turned into an exception (one line, exit 2)."""


class Parser(argparse.ArgumentParser):
    def error(self, message):  # noqa: D102 - one line instead of usage + message
        bad = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        hint = choice_hint(bad.group(1), re.findall(r"'([^']*)'", bad.group(2))) if bad else ""
        raise UsageError(f"{message}{hint} (see '{self.prog} --help')")


def choice_hint(word: str, choices) -> str:
    """``"; did you mean 'X'?"`` for the choice closest to a mistyped ``word``, else ``""``.
    Options are compared without their dashes (``--colour`` is not ``--scroll``) and need a closer match
    (:func:`~mlplc2._validation.did_you_mean` with cutoff 0.7, commands and choices 0.6)."""
    bare = {c.lstrip("-"): c for c in choices}
    close = did_you_mean(word.lstrip("-"), bare, cutoff=0.6 if word[:1] != "-" else 0.7)
    return f"; did you mean '{bare[close]}'?" if close else ""


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


def say(args, *lines: str) -> None:
    if not getattr(args, "quiet", False):
        for line in lines:
            out(line)


def out(text: str, end: str = "\n") -> None:
    """Print ``text`` to standard output, flushed. When its reader has gone (``mlplc2 params | head -1``:
    a closed pipe) the rest of the output goes nowhere, and the command goes on: its files are written
    and its exit code is its own, as if the reader had read everything (no ``[Errno 32] Broken pipe``)."""
    try:
        print(text, end=end, flush=True)
    except BrokenPipeError:
        stdout_gone()


def flush_stdout() -> None:
    """Flush standard output at the end of a command (:func:`out`'s rule for a reader that has gone)."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        stdout_gone()
    except (OSError, ValueError):  # a closed or odd stdout: nothing more to say there
        pass


class QuietStderr:
    """``sys.stderr`` for a command: its messages and progress bars, except that a reader that has
    gone (``mlplc2 run clip.mp4 2>&1 | head -3``) makes them go nowhere instead of raising
    ``BrokenPipeError`` into the run (which stopped it there, without its summaries, exit 1)."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._gone()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._gone()

    def _gone(self) -> None:
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
        except (OSError, ValueError, AttributeError):  # pragma: no cover - a stream without a file descriptor
            pass

    def __getattr__(self, name):
        return getattr(self._stream, name)


def stdout_gone() -> None:
    """Standard output's reader has gone: point its file descriptor at ``os.devnull``, so that what is
    still buffered, and the interpreter's last flush, go nowhere instead of failing again."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # pragma: no cover - a stdout without a file descriptor
        pass


def warn(message: str) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


#: The line :func:`compile_notice` prints while Numba compiles.
COMPILING = f"{PROG}: compiling the fast kernels (first run only) ..."


@contextmanager
def compile_notice(models: list[str], quiet: bool = False) -> Iterator[None]:
    """Print :data:`COMPILING` on stderr, once, when Numba starts compiling a kernel inside.

    The compiled kernels are cached on disk (``mlplc2.neuropils._fast.jit``), so this happens in
    the first process after an install or upgrade, where the first frame then takes tens of
    seconds. Numba signals a compilation (its ``numba:compile`` event) only after a cache miss:
    a run that loads the kernels from the cache prints nothing. Only for models that take a
    ``backend`` (those with compiled kernels), so that the others do not import Numba."""
    uses_numba = any("backend" in inspect.signature(REGISTRY[name]).parameters for name in models)
    if quiet or not uses_numba or importlib.util.find_spec("numba") is None:
        yield
        return
    from numba.core import event

    said = threading.Event()   # kernels compile in the front end's worker threads too

    class Notice(event.Listener):
        def on_start(self, ev) -> None:
            if not said.is_set():
                said.set()
                print(COMPILING, file=sys.stderr, flush=True)

        def on_end(self, ev) -> None:
            pass

    with event.install_listener("numba:compile", Notice()):
        yield


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


nonneg_int = number_type(int, lambda v: v >= 0, "an integer >= 0")
pos_int = number_type(int, lambda v: v >= 1, "a positive integer")
pos_float = number_type(float, lambda v: math.isfinite(v) and v > 0, "a positive number")
hfov_degrees = number_type(float, lambda v: math.isfinite(v) and 0 < v < 180, "degrees in (0, 180)")
nonneg_float = number_type(float, lambda v: math.isfinite(v) and v >= 0, "a number >= 0")


def holdouts(text: str) -> int | list[int]:
    """An argparse ``type`` for ``--holdout``: ``'N'`` -> N, or the holdouts to pool, ``'21-25'`` or ``'3,7,21-25'``
    -> ``[3, 7, 21, 22, 23, 24, 25]`` (integers >= 0, each once, in order; one holdout however written is N)."""
    out: list[int] = []
    try:
        for part in text.replace(" ", "").split(","):
            lo, sep, hi = part.partition("-")
            a, b = int(lo), int(hi) if sep else int(lo)
            if a < 0 or b < a:
                raise ValueError
            out += [v for v in range(a, b + 1) if v not in out]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N, a range A-B or a comma-separated list of them "
                                         f"(integers >= 0), got {text!r}") from None
    return out[0] if len(out) == 1 else out


def point_xy(text: str) -> tuple[float, float]:
    """An argparse ``type`` for ``--heading``: ``'X,Y'`` -> ``(X, Y)``, two finite numbers (pixels)."""
    parts = text.replace(" ", "").split(",")
    try:
        x, y = (float(v) for v in parts)
    except ValueError:
        x = y = math.nan
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"expected X,Y (two numbers, pixels of the input), got {text!r}")
    return x, y


def frame_size(text: str) -> tuple[int, int]:
    """An argparse ``type`` for ``--resize``: ``'WxH'`` -> ``(W, H)`` (:func:`mlplc2.io.parse_resize`'s
    checks; its message as a one-line usage error, as the other options')."""
    try:
        return parse_resize(text, name="size")
    except InputValueError as exc:
        message, prefix = str(exc), f"bad size {text!r}: "
        if message.startswith(prefix):
            message = f"{message[len(prefix):]}, got {text!r}"
        raise argparse.ArgumentTypeError(message) from None


def add_repeat_options(p: argparse.ArgumentParser, help: str) -> None:
    """``--skip-repeats`` (a plain flag: threshold ``REPEAT_THRESHOLD``), ``--repeat-level N``
    (that threshold instead; implies skipping) and ``--every-frame`` (never hold), read back by
    :func:`repeat_threshold_option`; without them the models detect duplicated frames themselves."""
    p.add_argument("--skip-repeats", action="store_true", help=help)
    p.add_argument("--repeat-level", type=nonneg_float, metavar="N",
                   help=f"grey-level change up to which a frame counts as a repeat (default "
                        f"{REPEAT_THRESHOLD:g}); implies --skip-repeats")
    p.add_argument("--every-frame", action="store_true",
                   help="step the models on every frame, duplicates too (by default the models hold "
                        "their output on duplicated frames when the video looks duplicated)")


def repeat_threshold_option(args) -> float | str | None:
    """``Model.repeat_threshold`` asked for by :func:`add_repeat_options`: a level, None
    (``--every-frame``) or ``"auto"`` (no option: the models' duplicate detection)."""
    if args.every_frame and (args.skip_repeats or args.repeat_level is not None):
        raise InputValueError("--every-frame cannot be combined with --skip-repeats or --repeat-level")
    if args.repeat_level is not None:
        return args.repeat_level
    if args.skip_repeats:
        return REPEAT_THRESHOLD
    return None if args.every_frame else "auto"


def add_warning_options(p: argparse.ArgumentParser, what: str = "") -> None:
    """``--horizon S``, ``--max-miss W`` and ``--alarm-warns`` / ``--no-alarm-warns``: the warning settings of the target
    layer (``TargetParams.horizon_s``, ``.max_miss``, ``.alarm_warns``), read back by
    :func:`target_options`."""
    from ..targets import TargetParams

    d = TargetParams()
    p.add_argument("--horizon", type=nonneg_float, metavar="S",
                   help=f"{what}a target warns only when its time to contact is at most S seconds "
                        f"(TargetParams.horizon_s, default {d.horizon_s:g}; docs/targets.md)")
    p.add_argument("--max-miss", type=nonneg_float, metavar="W",
                   help=f"{what}... and its predicted miss at contact at most W object extents "
                        f"(widths across, heights up and down; "
                        f"TargetParams.max_miss, default {d.max_miss:g})")
    p.add_argument("--alarm-warns", action=argparse.BooleanOptionalAction, default=None,
                   help=f"{what}a target owning a field in collision alarm warns unless its own measurement "
                        "says otherwise (TargetParams.alarm_warns; on by default; --no-alarm-warns: only "
                        "the target's own fit warns, fewer false warnings on a moving camera and fewer "
                        "collisions warned; docs/model.md)")


def target_options(args) -> dict:
    """The ``target_params`` of :func:`mlplc2.run` asked for by :func:`add_warning_options`: a
    dict of :class:`~mlplc2.targets.TargetParams` fields (JSON-able, for batch tasks; empty: the
    defaults), checked here so that a bad value is one error before anything runs."""
    from ..targets import TargetParams

    options = {}
    if args.horizon is not None:
        options["horizon_s"] = args.horizon
    if args.max_miss is not None:
        options["max_miss"] = args.max_miss
    if getattr(args, "alarm_warns", None) is not None:
        options["alarm_warns"] = args.alarm_warns
    TargetParams().replace(**options)
    return options


def add_stabilise_option(p: argparse.ArgumentParser, prefix: str = "") -> None:
    """``--stabilise`` / ``--no-stabilise`` (None: the runner's default, ``RunOptions.stabilise``)."""
    p.add_argument("--stabilise", action=argparse.BooleanOptionalAction, default=None,
                   help=f"{prefix}gaze stabilisation for the LPLC2 family (as mlplc2 run; on by default, "
                        "--no-stabilise: the paper's model)")


def video_run_options(args) -> dict:
    """The ``run_options`` of ``mlplc2 evaluate`` and ``batch``: ``--resize``, the repeat, the warning
    and the stabilisation options."""
    options = {"resize": args.resize} if args.resize else {}
    if getattr(args, "stabilise", None) is not None:
        options["stabilise"] = args.stabilise
    if repeat_threshold_option(args) != "auto":  # --skip-repeats / --repeat-level / --every-frame
        options["repeat_threshold"] = repeat_threshold_option(args)
    if target_options(args):  # --horizon / --max-miss / --alarm-warns: part of each task's options
        options["target_params"] = target_options(args)
    return options


def one_line(text: str) -> str:
    return " ".join(text.split()) or "unknown error"
