"""The compiled (Numba) kernels' shared tooling: the ``jit`` options and the threads.

* :func:`jit`: ``numba.njit`` with the options every kernel of the package uses
  (``fastmath=False``: the float operations of the reference in the reference's order, no fused
  multiply-add; ``nogil``; NumPy's error model) and an on-disk cache when one can be written,
  so that only the first process after an install or upgrade compiles (docs/cli.md, "First
  run"); later processes load the machine code. Every kernel made by it is in
  :data:`KERNELS` (its ``stats.cache_hits`` / ``cache_misses`` say which were loaded or compiled).
  The kernels: :mod:`mlplc2.neuropils._fast_frontend` (Eq. 1-7 and the front end),
  :mod:`mlplc2.neuropils._fast_motion` (Eq. 8-12), :mod:`mlplc2.neuropils._fast_attention`
  (Eq. 14) and :mod:`mlplc2.targets._fast` (the target layer).
* The thread pool the front end's bands run on (:func:`pool`, :data:`BANDS_LOCK`) and the spin
  barrier between their phases (:func:`spin_wait`): waking a sleeping thread costs ~35 us here,
  and three wake-ups per frame used to cost 10-15 % of a 320x240 frame, so the barriers spin
  without the GIL (~1 us per poll).
* :func:`set_threads` (``mlplc2 bench --threads``) and :func:`copy_chain`, the memory-bandwidth
  probe of ``mlplc2 bench``, split over the same pool as the front end's bands.
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import cv2
import numba
import numpy as np

from .._validation import check_int

__all__ = ["jit", "KERNELS", "pool", "release_pool", "BANDS_LOCK", "DONE", "spin_ok", "spin_wait", "set_threads", "copy_chain"]


#: Every dispatcher :func:`jit` made, in definition order (for ``stats`` and the tests).
KERNELS: list = []


def jit(**options):
    """``numba.njit`` with an on-disk cache when one can be written, without one otherwise.

    Numba tries, in order, ``NUMBA_CACHE_DIR`` (when set), the source's ``__pycache__`` and the
    user's cache folder (``~/.cache/numba``), skipping each one it cannot write: a read-only
    install (site-packages of a system Python) caches in the user's folder with no setting.
    Where no location is writable ``cache=True`` raises at decoration time; compile without it
    (every process then compiles on first use).
    """
    base = dict(fastmath=False, nogil=True, error_model="numpy")
    base.update(options)

    def deco(func):
        try:
            kernel = numba.njit(cache=True, **base)(func)
        except (RuntimeError, OSError):  # pragma: no cover - depends on the file system
            kernel = numba.njit(cache=False, **base)(func)
        KERNELS.append(kernel)
        return kernel

    return deco


# ---------------------------------------------------------------------------
# Threads
# ---------------------------------------------------------------------------
_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0
_POOL_LOCK = threading.Lock()

#: Held while one frame's bands run on the shared pool. The bands of a frame wait for each
#: other (spin barriers); without it, two streams stepping in two threads could interleave
#: their band tasks in the pool's queue so that every worker waits for a sibling still
#: queued behind the other stream's tasks: a deadlock (3 or more bands).
BANDS_LOCK = threading.Lock()


def pool(n: int) -> ThreadPoolExecutor:
    """The shared thread pool, grown to at least ``n`` workers."""
    global _POOL, _POOL_SIZE
    with _POOL_LOCK:
        if _POOL is None or _POOL_SIZE < n:
            old = _POOL
            _POOL = ThreadPoolExecutor(max_workers=n, thread_name_prefix="mlplc2-band")
            _POOL_SIZE = n
            if old is not None:
                old.shutdown(wait=False)
        return _POOL


def release_pool() -> None:
    """Stop and join the pool's threads (none running: every frame waits for its bands under
    :data:`BANDS_LOCK`); the next frame with bands starts a new pool."""
    global _POOL, _POOL_SIZE
    with BANDS_LOCK, _POOL_LOCK:
        old, _POOL, _POOL_SIZE = _POOL, None, 0
    if old is not None:
        old.shutdown(wait=True)


def _copy_slice(stack: np.ndarray, lo: int, hi: int) -> None:
    for k in range(stack.shape[0] - 1):
        np.copyto(stack[k + 1, lo:hi], stack[k, lo:hi])


def copy_chain(stack: np.ndarray, threads: int | None = None) -> None:
    """Memory-bandwidth probe of ``mlplc2 bench``: copy plane k into plane k + 1 of the
    (N + 1, H * W) ``stack`` for k = 0..N-1 with ``np.copyto`` (memcpy), split like the front
    end's bands: one slice per thread (default ``numba.get_num_threads()``), same thread pool."""
    size = stack.shape[1]
    n = max(1, int(numba.get_num_threads() if threads is None else threads))
    cuts = [size * k // n for k in range(n + 1)]
    if n == 1:
        _copy_slice(stack, 0, size)
        return
    futs = [pool(n - 1).submit(_copy_slice, stack, lo, hi) for lo, hi in zip(cuts[1:-1], cuts[2:])]
    _copy_slice(stack, cuts[0], cuts[1])
    for f in futs:
        f.result()


#: ``arrive`` value of a band that finished the frame (or failed).
DONE = 1 << 30

#: Polls (~0.5 us each) before the spin barrier falls back to sleeping.
_POLLS = 20000

# libc's sched_yield, called by symbol (resolved in the process at link time; unlike a ctypes
# pointer, this keeps the kernel cacheable).
_sched_yield = numba.types.ExternalFunction("sched_yield", numba.types.int32())


@jit()
def _spin(arrive, stage, polls):
    """Poll (``sched_yield`` between polls, which also keeps LLVM from hoisting the loads) until
    every entry of ``arrive`` is at least ``stage``, at most ``polls`` times; True when reached."""
    n = arrive.shape[0]
    for _ in range(polls):
        lo = arrive[0]
        for k in range(1, n):
            v = arrive[k]
            lo = v if v < lo else lo
        if lo >= stage:
            return True
        _sched_yield()
    return False


_SPIN_OK: bool | None = None


def spin_ok() -> bool:
    """Whether :func:`_spin` compiles here (``sched_yield`` is a POSIX symbol); checked once."""
    global _SPIN_OK
    if _SPIN_OK is None:
        try:
            _spin(np.zeros(1, np.int64), 0, 1)
            _SPIN_OK = True
        except Exception:  # pragma: no cover - platforms without sched_yield
            _SPIN_OK = False
    return _SPIN_OK


def spin_wait(arrive: np.ndarray, stage: int) -> None:
    """Spin barrier: wait, without the GIL, until every band's ``arrive`` entry is >= ``stage``.

    Waking a sleeping thread (a future, a lock) costs ~35 us here, as much as a phase of a
    small frame; a poll costs ~1 us. After ~20000 polls (a band held up: a busy machine) it
    sleeps 50 us between rounds of polls instead of keeping a shared core busy.
    """
    if _spin(arrive, stage, _POLLS):
        return
    while not _spin(arrive, stage, 20):
        time.sleep(5e-5)


def set_threads(n: int) -> None:
    """Use ``n`` threads for the fast front end (Numba's thread count) and OpenCV.

    ``n`` must be between 1 and Numba's ``NUMBA_NUM_THREADS`` (by default the number of cores).
    """
    limit = int(numba.config.NUMBA_NUM_THREADS)
    n = check_int(n, f"threads (1 to {limit} on this machine: the number of cores, or NUMBA_NUM_THREADS)",
                  minimum=1, maximum=limit)
    numba.set_num_threads(n)
    cv2.setNumThreads(int(n))
