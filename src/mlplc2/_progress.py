"""Progress on stderr, the one way every long command shows it (``run``, ``batch``, ``evaluate``,
``benchmark``, ``reproduce``).

On a terminal: a tqdm bar, redrawn in place (``\\r``). Anywhere else (a robot's log, a file, a
pipe, a scheduler's output) a redrawn bar only fills the log: there, a plain line, without
``\\r``, at most one every :data:`PLAIN_EVERY_S` seconds (none at all for a shorter job), e.g.
``clip.mp4: 900/5400 frame [00:30<02:30, 30.0frame/s]``. ``--quiet`` silences both.
"""

from __future__ import annotations

import sys
import time

#: Seconds between two progress lines when stderr is not a terminal (the first comes after as
#: long: a job shorter than that writes none).
PLAIN_EVERY_S = 30.0

#: The plain line: tqdm's text without its bar.
PLAIN_FORMAT = "{desc}: {n_fmt}/{total_fmt} {unit} [{elapsed}<{remaining}, {rate_fmt}]"


def on_terminal(stream) -> bool:
    """Whether ``stream`` is a terminal (a stream without ``isatty`` is not)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):  # no isatty, or a closed stream
        return False


class _Lines:
    """A file for tqdm off a terminal: each redraw becomes a whole line, at most one every
    ``every`` seconds; the clearing redraws (blank) and the carriage returns are dropped."""

    def __init__(self, stream, every: float):
        self.stream, self.every = stream, every
        self.last = time.monotonic()

    def write(self, text: str) -> None:
        line = text.replace("\r", "").strip()
        now = time.monotonic()
        if line and now - self.last >= self.every:
            self.last = now
            self.stream.write(line + "\n")
            self.stream.flush()

    def flush(self) -> None:
        pass


def bar(iterable=None, *, disable: bool = False, stream=None, **kwargs):
    """A tqdm progress bar on ``stream`` (``sys.stderr``) when it is a terminal, plain lines
    (:class:`_Lines`) when it is not; ``kwargs`` go to ``tqdm``."""
    from tqdm import tqdm

    stream = sys.stderr if stream is None else stream
    if disable or on_terminal(stream):
        return tqdm(iterable, disable=disable, file=stream, dynamic_ncols=True, **kwargs)
    return tqdm(iterable, file=_Lines(stream, PLAIN_EVERY_S), bar_format=PLAIN_FORMAT, **kwargs)
