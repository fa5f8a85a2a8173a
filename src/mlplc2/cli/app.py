"""The ``mlplc2`` command line proper (:func:`mlplc2.cli.main` imports it when it runs): the
parser built from :data:`SUBCOMMANDS`, the exit codes of errors (the package docstring).
"""

from __future__ import annotations

import argparse
import errno
import os
import sys
import warnings
from pathlib import Path

from .._validation import InputError
from . import run, stimulus, studies, tools
from .common import (EXIT_INPUT, EXIT_INTERRUPTED, PROG, Parser, QuietStderr, Subcommand, UsageError, choice_hint,
                     flush_stdout, one_line, warn)
from .stimulus import STIMULUS_OWN_OPTIONS

__all__ = ["run_command", "build_parser", "Subcommand", "SUBCOMMANDS", "STIMULUS_OWN_OPTIONS"]

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


#: The errors of a folder that cannot be written (no permission, a read-only file system).
_NOT_WRITABLE = (errno.EACCES, errno.EPERM, errno.EROFS)


def _is_input(args, filename) -> bool:
    """Whether ``filename`` (an OSError's) names one of the command's inputs (``SOURCE``, ``INPUTS``), not an output."""
    if filename is None:
        return False
    given = [getattr(args, "source", None), *(getattr(args, "inputs", None) or [])]
    return any(g is not None and os.fsdecode(filename) == str(g) for g in given)


def _os_error_line(exc: OSError, output: bool = False) -> str:
    """``PATH: REASON`` of an ``OSError``; a file where a folder is needed (an output folder, or a folder above
    an output, that is a file) is said so instead of the system's "File exists" / "Not a directory"; an
    ``output`` path that does not exist could not be made: ``cannot create PATH: REASON``."""
    if not (exc.strerror and exc.filename):
        return str(exc) or type(exc).__name__
    if isinstance(exc, (FileExistsError, NotADirectoryError)):
        path = Path(os.fsdecode(exc.filename))
        blocker = next((p for p in (path, *path.parents) if p.exists() and not p.is_dir()), None)
        if blocker == path:
            return f"{exc.filename}: is a file, where a folder is needed"
        if blocker is not None:
            return f"{exc.filename}: {blocker} is a file, not a folder"
    if output and not os.path.lexists(exc.filename):
        return f"cannot create {os.fsdecode(exc.filename)}: {exc.strerror}"
    return f"{exc.filename}: {exc.strerror}"


def run_command(argv: list[str] | None = None) -> int:
    """:func:`mlplc2.cli.main` once its modules are loaded (it holds the signal handling): the
    exit code. Warnings are printed as one line each, ``mlplc2: warning: ...``."""
    stderr = sys.stderr
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        sys.stderr = QuietStderr(stderr)    # a reader of stderr that has gone is no error either
        try:
            return _main(argv)
        finally:
            flush_stdout()  # a reader that has gone (`| head -1`) is no error (cli.common.out)
            sys.stderr.flush()
            sys.stderr = stderr


#: Options whose value may begin with a minus sign (a point left of or above the frame): ``--heading -5,10`` is
#: read as ``--heading=-5,10``, where argparse would take ``-5,10`` for an option of its own.
_SIGNED_OPTIONS = ("--heading",)


def _signed_values(argv: list[str]) -> list[str]:
    """``argv`` with each of :data:`_SIGNED_OPTIONS` joined to a following value that begins with a minus sign."""
    out: list[str] = []
    for a in argv:
        if out and out[-1] in _SIGNED_OPTIONS and a[:1] == "-" and (a[1:2].isdigit() or a[1:2] == "."):
            out[-1] = f"{out[-1]}={a}"
        else:
            out.append(a)
    return out


def _main(argv: list[str] | None) -> int:
    _quiet_decoders()
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(_signed_values(sys.argv[1:] if argv is None else list(argv)))
        if extra:  # pointing at the subcommand's help, not the top level's
            options = [o for a in args._parser._actions for o in a.option_strings]
            hint = choice_hint(extra[0].split("=")[0], options) if extra[0].startswith("--") else ""
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
        line = _os_error_line(exc, output=not _is_input(args, exc.filename))
        if exc.errno in _NOT_WRITABLE and "out" in vars(args) and not _is_input(args, exc.filename):
            line += " (write the outputs elsewhere with --out DIR)"   # the default output folder lies beside the input
        print(f"{PROG}: error: {one_line(line)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

