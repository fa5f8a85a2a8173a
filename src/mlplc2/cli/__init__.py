"""Command line: ``mlplc2 run | stimulus | demo | evaluate | batch | benchmark | ...`` (see docs/cli.md).

Thin by design: each subcommand parses its arguments and calls one public
function (:func:`mlplc2.run`, :func:`mlplc2.stimuli.write`,
:func:`mlplc2.runner.demo`). Subcommands live in the :data:`SUBCOMMANDS`
table; adding one is one :class:`Subcommand` entry (its options and its handler, which
calls the public function of the module that implements it), in the module of its group:
:mod:`.run` (run, demo), :mod:`.stimulus`, :mod:`.studies` (evaluate, batch, benchmark,
reproduce), :mod:`.tools` (params, bench); :mod:`.common` holds what they share.
The package is the only place with argparse, printing and exit codes.

Exit codes: 0 success; 2 bad input (one line ``mlplc2: error: ...`` on
stderr, no traceback) and also a truncated or damaged video (after writing
the outputs for the frames that decoded); 130 after Ctrl-C (the outputs for
the frames done are written).
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from .._signals import interrupts
from .._validation import InputError
from . import run, stimulus, studies, tools
from .common import (EXIT_INPUT, EXIT_INTERRUPTED, EXIT_OK, EXIT_TRUNCATED, PROG, Parser, QuietStderr, Subcommand,
                     UsageError, did_you_mean, flush_stdout, number_type, one_line, warn)
from .stimulus import STIMULUS_OWN_OPTIONS

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS",
           "EXIT_OK", "EXIT_INPUT", "EXIT_TRUNCATED", "EXIT_INTERRUPTED"]

#: Subcommands in help order. Add one entry per new subcommand.
SUBCOMMANDS: list[Subcommand] = [run.RUN, stimulus.STIMULUS, run.DEMO, studies.EVALUATE, studies.BATCH,
                                 studies.BENCHMARK, studies.REPRODUCE, tools.PARAMS, tools.BENCH]


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    parser = Parser(prog=PROG, description="mLPLC2 looming detection: run models on videos, "
                                            "make stimuli, see a demo.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=Parser)
    for cmd in SUBCOMMANDS:
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        cmd.add_arguments(p)
        p.set_defaults(_handler=cmd.handler, _parser=p)
    return parser


def one_line(text: str) -> str:
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
    warn(one_line(str(message)))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mlplc2`` console script; returns the exit code.

    SIGTERM (what batch schedulers and ``timeout`` send) is handled like Ctrl-C: the
    outputs of the frames done are written and the exit code is 130 (``mlplc2._signals``).
    Warnings are printed as one line each, ``mlplc2: warning: ...``.
    """
    stderr = sys.stderr
    with interrupts(sigterm=True), warnings.catch_warnings():
        warnings.showwarning = _show_warning
        sys.stderr = QuietStderr(stderr)    # a reader of stderr that has gone is no error either
        try:
            return _main(argv)
        finally:
            flush_stdout()  # a reader that has gone (`| head -1`) is no error (cli.common.out)
            sys.stderr.flush()
            sys.stderr = stderr


def _main(argv: list[str] | None) -> int:
    _quiet_decoders()
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:  # pointing at the subcommand's help, not the top level's
            options = [o for a in args._parser._actions for o in a.option_strings]
            hint = did_you_mean(extra[0].split("=")[0], options) if extra[0].startswith("--") else ""
            raise UsageError(f"unrecognized arguments: {' '.join(extra)}{hint} (see '{PROG} {args.command} --help')")
    except UsageError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0)
    try:
        return int(args._handler(args))
    except InputError as exc:
        print(f"{PROG}: error: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        line = f"{exc.filename}: {exc.strerror}" if exc.strerror and exc.filename else str(exc) or type(exc).__name__
        print(f"{PROG}: error: {one_line(line)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

