"""Command line: ``mlplc2 run | stimulus | demo | evaluate | batch | benchmark | ...`` (see docs/cli.md).

Thin by design: each subcommand parses its arguments and calls one public
function (:func:`mlplc2.run`, :func:`mlplc2.stimuli.write`,
:func:`mlplc2.runner.demo`). Subcommands live in the :data:`SUBCOMMANDS`
table; adding one is one :class:`Subcommand` entry (its options and its handler, which
calls the public function of the module that implements it), in the module of its group:
:mod:`.run` (run, demo), :mod:`.stimulus`, :mod:`.studies` (evaluate, batch, benchmark,
reproduce), :mod:`.tools` (params, bench); :mod:`.common` holds what they share and
:mod:`.app` the parser. The package is the only place with argparse, printing and exit codes.

This module imports nothing heavy: :func:`main` loads the rest (NumPy, OpenCV, Numba: a few
tenths of a second) with its signal handling already in place, so that Ctrl-C at any moment
ends the command with one line and exit code 130, never a traceback.

Exit codes: 0 success; 2 bad input (one line ``mlplc2: error: ...`` on
stderr, no traceback) and also a truncated or damaged video (after writing
the outputs for the frames that decoded); 130 after Ctrl-C (the outputs for
the frames done are written).
"""

from __future__ import annotations

import sys

from .._signals import interrupts

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS",
           "EXIT_OK", "EXIT_INPUT", "EXIT_TRUNCATED", "EXIT_INTERRUPTED"]

EXIT_OK = 0
EXIT_INPUT = 2
#: A truncated/damaged input still gives outputs but exits non-zero (same code as bad input).
EXIT_TRUNCATED = 2
EXIT_INTERRUPTED = 130

PROG = "mlplc2"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mlplc2`` console script; returns the exit code.

    SIGTERM (what batch schedulers and ``timeout`` send) is handled like Ctrl-C: the
    outputs of the frames done are written and the exit code is 130 (``mlplc2._signals``).
    Either signal at any moment, while the modules load too, gives one ``mlplc2: interrupted``
    line. Warnings are printed as one line each, ``mlplc2: warning: ...``.
    """
    try:
        with interrupts(sigterm=True):
            from .app import run_command   # the parser and the subcommands' modules

            return run_command(argv)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def __getattr__(name: str):
    """The parser's names (:data:`SUBCOMMANDS`, :func:`build_parser`, ...), from :mod:`.app` when first used."""
    if name in ("build_parser", "Subcommand", "SUBCOMMANDS", "STIMULUS_OWN_OPTIONS"):
        from . import app

        return getattr(app, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
