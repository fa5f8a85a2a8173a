"""One switch between the reference NumPy code and the compiled (Numba) kernels.

A model picks its :class:`Backend` once, at construction (``backend="auto" | "numba" |
"reference"``), and every per-frame stage that has a compiled version takes it from there:
the front end (Eq. 1-12, :class:`mlplc2.neuropils._fast_frontend.FastFrontEnd`), the quadrant sums of
Eq. 14 (:func:`mlplc2.neuropils._fast_attention.quadrant_sums`), the edge scans and the image alignment of the target
layer (:func:`mlplc2.targets._fast_extent.edges4`, :func:`mlplc2.targets._fast_align.align_patch`).
``"reference"`` never imports Numba. Both give the same fields and targets; the LM maps agree
to ~1e-6, the edge scans bit for bit, the alignments to ~1e-12.
"""

from __future__ import annotations

import logging
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from ._validation import InputValueError

__all__ = ["BACKENDS", "Backend", "resolve", "make_frontend", "fast_available", "warm_kernels", "threads", "one_fewer", "workers"]

#: "auto" (compiled when Numba imports, else reference, with a logged warning), "numba"
#: (compiled, ImportError without Numba) and "reference" (plain NumPy/OpenCV, the oracle).
BACKENDS = ("auto", "numba", "reference")

_log = logging.getLogger("mlplc2")
_FAST_ERROR: str | None = None
_WARNED = False
_WARM = False
_WARM_PARAMS: set = set()   # the parameter sets whose front-end kernels are loaded (_warm_frontend)


def fast_available() -> bool:
    """True when the compiled kernels (Numba) can be imported."""
    global _FAST_ERROR
    try:
        from .neuropils import _fast_attention, _fast_frontend  # noqa: F401
        from .targets import _fast_align, _fast_change, _fast_extent  # noqa: F401
    except Exception as exc:  # noqa: BLE001 - ImportError, or numba failing to initialise
        _FAST_ERROR = f"{type(exc).__name__}: {exc}"
        return False
    return True


@dataclass(frozen=True)
class Backend:
    """The implementation of each stage that has two: ``name`` is "numba" or "reference"."""

    name: str
    frontend_class: type
    quadrant_sums: Callable
    edge_kernel: Callable | None
    align_kernel: Callable | None
    change_kernel: Callable | None = None

    def frontend(self, params, fps: float):
        """A new front end (Eq. 1-12) for ``params`` at ``fps`` (its kernels loaded for these
        ``params`` first: :func:`_warm_frontend`)."""
        if self.name == "numba":
            _warm_frontend(params)
        return self.frontend_class(params, fps)


def resolve(backend: str = "auto") -> Backend:
    """The :class:`Backend` for ``backend`` (one of :data:`BACKENDS`)."""
    global _WARNED
    if backend not in BACKENDS:
        raise InputValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend != "reference":
        if fast_available():
            from .neuropils import _fast_attention, _fast_frontend
            from .targets import _fast_align, _fast_change, _fast_extent

            warm_kernels()
            return Backend("numba", _fast_frontend.FastFrontEnd, _fast_attention.quadrant_sums, _fast_extent.edges4,
                           _fast_align.align_patch, _fast_change.nearest_change)
        if backend == "numba":
            raise ImportError(f"the numba backend is unavailable ({_FAST_ERROR})")
        if not _WARNED:
            _log.warning("mlplc2: Numba is unavailable (%s); using the slower reference front end", _FAST_ERROR)
            _WARNED = True
    from .neuropils.attention import quadrant_sums
    from .neuropils.frontend import FrontEnd

    return Backend("reference", FrontEnd, quadrant_sums, None, None)


def warm_kernels() -> None:
    """Load (or compile) every kernel a model calls, once per process, when the model is built.

    The front end's (:func:`_warm_frontend`) would load at a model's first frame, while a run's
    decoding thread queues the next ones; the quadrant sums (Eq. 14: the first field), the image alignment (the first target's growth)
    and the edge scans (its first extent) would load at the frame that first needs them, tens of
    milliseconds in the middle of a live run (a compile: seconds). Each is called here once on
    a small blank frame through its public caller, so with the argument types of a run's calls.
    The camera-motion fit of gaze stabilisation (:mod:`mlplc2._fast_camera`, on by default in
    ``mlplc2 run``) is called directly, with the types :mod:`mlplc2.camera` passes: it used to
    compile at a first run's second frame, silently (23 s on 2 busy cores); so are the estimate's
    conversion to uint8 and texture test (``to_uint8``, ``grid_texture``).
    """
    global _WARM
    if _WARM:
        return
    import numpy as np

    from .neuropils import _fast_attention
    from .neuropils.lobula_plate import LocalMotion
    from .targets import _fast_align, _fast_change, _fast_extent
    from .targets.alignment import align, pyramid
    from .targets.change import change_box
    from .targets.extent import measure_extent

    maps = np.zeros((5, 32, 32), np.float32)
    lm = LocalMotion(maps[0], maps[1], maps[2], maps[3], maps[4])
    for shape in ("square", "disc"):
        _fast_attention.quadrant_sums(lm, 16, 16, 8, shape)
    measure_extent(lm, 16, 16, kernel=_fast_extent.edges4)
    levels = pyramid(np.zeros((32, 32), np.float32))
    align(levels, levels, 16.0, 16.0, 8.0, (4.0, 4.0), kernel=_fast_align.align_patch)
    change_box(levels[0], levels[0] + np.eye(32, dtype=np.float32) * 50, 16, 16, 12, kernel=_fast_change.nearest_change)
    try:   # as mlplc2.camera does: without a usable Numba cache or kernel, the fit runs in NumPy
        from . import _fast_camera
    except Exception:  # noqa: BLE001
        _fast_camera = None
    if _fast_camera is not None:
        points = np.linspace(-0.5, 0.5, 8)
        _fast_camera.fit_rounds(points, points[::-1].copy(), np.zeros(8), np.zeros(8), np.zeros(3), np.zeros(2),
                                True, True, 0.01, 1)
        _fast_camera.to_uint8(np.zeros((32, 32), np.float32), np.empty((32, 32), np.uint8))
        _fast_camera.grid_texture(np.zeros((32, 32), np.uint8), np.array([8, 16]), np.array([8, 16]))
    _warm_frontend()
    _WARM = True


def _warm_frontend(params=None) -> None:
    """The front end's kernels for ``params`` (default :class:`~mlplc2.params.Params`; once per process
    for each parameter set: N_c is a compile-time constant of the kernels, the relative floor runs a
    kernel of its own), on three blank 320 x 240 frames and one carry: a first run used to compile them
    at its first frame, while the decoding thread queued the next frames, whose latency then held the
    compilation (a 17 s 99th percentile on a 25-frame clip piped through stdin, 2 busy cores); a model
    with other parameters still did so until session 11. Compiled kernels take a few milliseconds here."""
    import numpy as np

    from .neuropils._fast_frontend import FastFrontEnd
    from .params import Params

    params = Params() if params is None else params
    if params in _WARM_PARAMS:
        return
    fe = FastFrontEnd(params, 30.0)
    blank = np.zeros((240, 320), np.float32)
    for _ in range(3):
        fe.step(blank)
    fe.compensate(np.eye(3), blank)
    _WARM_PARAMS.add(params)


def make_frontend(params, fps: float, backend: str = "auto"):
    """The front end of ``backend`` (:data:`BACKENDS`), built as ``(params, fps)``.

    "auto" gives the fast front end, or the reference with a logged warning (once per
    process) when Numba is unavailable; "numba" raises ImportError then.
    """
    return resolve(backend).frontend(params, fps)


@contextmanager
def threads(n: int | None) -> Iterator[int]:
    """Run the block with ``n`` threads for the compiled front end and OpenCV
    (:func:`mlplc2.neuropils._fast.set_threads`; None: as they are), and give back the counts
    found on entry when it ends, also on an error. Yields the count in force. Without Numba,
    nothing changes and it yields 1."""
    if not fast_available():
        yield 1
        return
    import cv2
    import numba

    from .neuropils import _fast

    before, before_cv = numba.get_num_threads(), cv2.getNumThreads()
    try:
        if n is not None:
            _fast.set_threads(n)
        yield numba.get_num_threads()
    finally:
        numba.set_num_threads(before)
        cv2.setNumThreads(before_cv)


def one_fewer() -> int | None:
    """One thread fewer than in force for the compiled front end and OpenCV, for a run whose decoding
    thread resizes a file's frames beside the model (:class:`mlplc2.runner.RunOptions`, ``spare_core``;
    docs/history.md, "Decoding beside the model"); None (as they are) on one thread or without Numba."""
    with threads(None) as n:
        return n - 1 if n > 1 else None


_RUNS = 0
_RUNS_LOCK = threading.Lock()


@contextmanager
def workers() -> Iterator[None]:
    """Around a run or a stream (:func:`mlplc2.run`, :func:`mlplc2.stream`): when the last one going
    ends (returns, fails, or its generator is closed), the worker threads its models started are
    stopped and joined: the front end's band pool (:func:`mlplc2.neuropils._fast.release_pool`) and
    the target layer's carry thread (:func:`mlplc2.targets.track.release_carry`). A model's next
    frame starts them anew (a few threads, well under a millisecond)."""
    global _RUNS
    with _RUNS_LOCK:
        _RUNS += 1
    try:
        yield
    finally:
        with _RUNS_LOCK:
            _RUNS -= 1
            last = _RUNS == 0
        if last:
            from .targets.track import release_carry

            release_carry()
            fast = sys.modules.get("mlplc2.neuropils._fast")   # never imported (no Numba): no pool
            if fast is not None:
                fast.release_pool()
