"""SIGINT (Ctrl-C) and SIGTERM: the one context manager, :class:`interrupts`, that the package uses.

Python turns SIGINT into a ``KeyboardInterrupt`` raised wherever the main thread
happens to be. Raised in the middle of a frame, that can leave one output file a frame
ahead of another. Every place that changes what a signal does goes through
:class:`interrupts` instead:

* ``mlplc2.cli.main``: ``interrupts(sigterm=True)``. SIGTERM (what ``timeout`` and batch
  schedulers send) interrupts like Ctrl-C.
* the frame loop of :func:`mlplc2.run`: ``interrupts(defer=True)``. An interrupt that
  arrives while a frame is in progress waits until the frame is finished. A second one
  interrupts at once.
* :mod:`mlplc2.batch`: ``interrupts(ignore=True)`` while Dask's worker processes start
  (they inherit the ignored SIGINT).

An *interrupting* signal is one whose handler raises ``KeyboardInterrupt``: SIGINT
under Python's default handler, and SIGTERM inside ``interrupts(sigterm=True)``. The
blocks change only these signals. Any other handler (an application's own, ``SIG_IGN``,
SIGTERM's default) is left alone, except that ``ignore=True`` ignores SIGINT whatever
its handler. Handlers can only be set from the main thread. In any other thread a block
changes nothing and never defers anything, so :func:`mlplc2.run` still works when
called from a worker thread.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterable, Iterator

__all__ = ["interrupts"]

_MARK = "_mlplc2_interrupts"  # attribute set on the handlers installed here that interrupt


def _interrupting(handler) -> bool:
    return handler is signal.default_int_handler or bool(getattr(handler, _MARK, False))


class interrupts:  # noqa: N801 - used like contextlib.suppress / warnings.catch_warnings
    """Context manager that sets what SIGINT and SIGTERM do inside a block (see the module docstring).

    Parameters
    ----------
    sigterm : bool
        SIGTERM interrupts like Ctrl-C: ``KeyboardInterrupt``.
    defer : bool
        An interrupting signal sets :attr:`pending` and the block's code goes on. The code
        calls :meth:`check` (or iterates :meth:`between`) at points where stopping is
        safe. A second signal interrupts at once. If the block ends normally with an
        interrupt still pending and not yet raised, it is raised on exit: an interrupt is
        never lost.
    ignore : bool
        SIGINT is ignored (``SIG_IGN``). Processes started inside the block inherit
        this. SIGTERM is left alone, so that they can still be terminated.

    Examples
    --------
    >>> from mlplc2._signals import interrupts
    >>> with interrupts(defer=True) as stop:
    ...     done = [item for item in stop.between(range(3))]
    >>> done, stop.pending
    ([0, 1, 2], None)
    """

    def __init__(self, *, sigterm: bool = False, defer: bool = False, ignore: bool = False):
        if ignore and (defer or sigterm):
            raise ValueError("interrupts(ignore=True) cannot be combined with sigterm or defer")
        self.sigterm = sigterm
        self.defer = defer
        self.ignore = ignore
        self.pending: int | None = None
        """The number of the first signal deferred in this block (None: none)."""
        self._raised = False
        self._waiting = False
        self._saved: list[tuple[int, object]] = []
        self.installed = False
        """True when this block changed a handler (never outside the main thread)."""

    # -- the handler ----------------------------------------------------------------
    def _wrap(self, base):
        def handler(signum, frame):
            if self.defer and self.pending is None and not self._waiting:
                self.pending = signum
                return
            base(signum, frame)  # interrupts: raises KeyboardInterrupt

        setattr(handler, _MARK, True)
        return handler

    def __enter__(self) -> "interrupts":
        if threading.current_thread() is not threading.main_thread():
            return self
        try:
            for sig in (signal.SIGINT, signal.SIGTERM):
                previous = signal.getsignal(sig)
                if self.ignore:
                    if sig != signal.SIGINT:
                        continue
                    new = signal.SIG_IGN
                elif self.sigterm and sig == signal.SIGTERM and not _interrupting(previous):
                    new = self._wrap(signal.default_int_handler)
                elif _interrupting(previous) and self.defer:
                    new = self._wrap(previous)
                else:
                    continue
                signal.signal(sig, new)
                self._saved.append((sig, previous))
        except (ValueError, OSError):  # pragma: no cover - interpreters without signal support
            self._restore()
        self.installed = bool(self._saved)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self._restore()
        if exc_type is None:
            self.check()

    def _restore(self) -> None:
        while self._saved:
            sig, previous = self._saved.pop()
            signal.signal(sig, previous if previous is not None else signal.SIG_DFL)

    # -- for the code inside a deferring block ---------------------------------------------
    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if an interrupt is pending and was not raised yet."""
        if self.pending is not None and not self._raised:
            self._raised = True
            raise KeyboardInterrupt

    def between(self, items: Iterable) -> Iterator:   # no typing.TypeVar: mlplc2.cli loads this first
        """Yield ``items`` one at a time, with the safe points between them.

        An interrupt that arrives while the caller works on an item is raised (as
        ``KeyboardInterrupt``) when the caller asks for the next item. One that arrives
        while waiting for the next item (a slow decoder, a camera that stalls) is raised
        at once. Nothing is in progress then, and the item being fetched is dropped.
        """
        it = iter(items)
        while True:
            self.check()
            self._waiting = True
            try:
                item = next(it)
            except StopIteration:
                return
            finally:
                self._waiting = False
            yield item
