"""Speed benchmark of the LPLC2 family (``mlplc2 bench``; its options are in :mod:`mlplc2.cli`).

For every model and frame size it reports, measured in the same run:

* ms/frame and frames/s of the model with the fast front end (median over ``--frames``
  frames after a warm-up; the frames are generated in memory beforehand, so no decoding is
  timed; the time is that of ``model.step(uint8 frame)``, input conversion, front end,
  attention fields and the target layer included; every frame at its own size: the models run
  with ``work_width=None`` and ``repeat_threshold=None``, so the larger sizes measure the
  pipeline there, not the default reduction to 320 px);
* the same for the reference front end (``backend="reference"``, fewer frames) and the
  speed-up;
* a memory-bandwidth probe: the time to copy the float32 planes the fast pipeline touches
  (:func:`mlplc2.neuropils._fast_frontend.plane_count`: N = 26 planes with the default parameters, 28 with the
  relative floor ``Params.n_floor``; the kernels do 54 or 64 plane reads + writes,
  :func:`mlplc2.neuropils._fast_frontend.plane_traffic`) with the same thread count, and the
  ratio of the model's time to it;
* the peak memory one stream allocates (``tracemalloc``: model state, scratch and one
  frame's output maps; Numba's row buffers and OpenCV's strip buffers are not traced and
  are a few rows).

``mlplc2 bench --latency`` (:func:`time_latency`) times the whole ``mlplc2 run`` path instead, on
an H.264 clip of the same scene at each source size (320x240, 1280x720): decoding alone, the
model alone (on the frames in memory), ``run`` end to end (decoding in its thread beside the
model, the JSON lines written), and the latency from a frame's decoding to its JSON line.

The input is a procedural background scrolling by one pixel per frame with five dark squares
approaching at different places and times (sizes scaled with the frame), so that mLPLC2
keeps a few attention fields; the table reports the largest number of fields seen.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
import tracemalloc
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._validation import InputValueError
from .params import Params

__all__ = ["BenchRow", "parse_sizes", "synthetic_frames", "bandwidth_probe", "time_model",
           "run_bench", "format_table", "format_pipeline", "describe", "DEFAULT_SIZES", "LATENCY_SIZES", "LatencyRow",
           "time_latency", "format_latency"]

DEFAULT_SIZES = "100x100,320x240,640x480,1280x720"
#: Source sizes of ``mlplc2 bench --latency``: the models' working width and an HD camera.
LATENCY_SIZES = "320x240,1280x720"


@dataclass
class BenchRow:
    model: str
    size: tuple[int, int]
    threads: int
    frames: int
    fields: int
    ms: float
    ref_ms: float | None
    fe_ms: float
    ref_fe_ms: float | None
    probe_ms: float
    planes: int
    peak_mb: float
    #: the pipeline as ``mlplc2 run`` builds it (gaze stabilisation on): ms/frame on the turning
    #: (scrolling) scene and on the same scene from a still camera; the flow baseline as ``run``
    #: builds it on the turning scene (None: not measured, ``pipeline=False``)
    run_ms: float | None = None
    still_ms: float | None = None
    flow_ms: float | None = None

    @property
    def run_vs_reference(self) -> float | None:
        """How many times faster the stabilised pipeline runs than the plain NumPy reference model."""
        return None if self.ref_ms is None or not self.run_ms else self.ref_ms / self.run_ms

    @property
    def run_vs_flow(self) -> float | None:
        """How many times faster the stabilised pipeline runs than the flow baseline."""
        return None if self.flow_ms is None or not self.run_ms else self.flow_ms / self.run_ms

    @property
    def fps(self) -> float:
        return 1000.0 / self.ms if self.ms > 0 else float("inf")

    @property
    def speedup(self) -> float | None:
        return None if self.ref_ms is None else self.ref_ms / self.ms

    @property
    def fe_speedup(self) -> float | None:
        return None if self.ref_fe_ms is None else self.ref_fe_ms / self.fe_ms

    @property
    def probe_ratio(self) -> float:
        return self.ms / self.probe_ms if self.probe_ms > 0 else float("inf")


def parse_sizes(text: str) -> list[tuple[int, int]]:
    """'320x240,640x480' -> [(320, 240), (640, 480)] (width x height)."""
    sizes = []
    for part in str(text).split(","):
        part = part.strip().lower()
        if not part:
            continue
        try:
            w, h = (int(v) for v in part.split("x"))
        except ValueError:
            raise InputValueError(f"--sizes: expected WxH[,WxH...], got {part!r}") from None
        if w < 16 or h < 16:
            raise InputValueError(f"--sizes: {part} is too small (at least 16x16)")
        sizes.append((w, h))
    if not sizes:
        raise InputValueError("--sizes needs at least one WxH")
    return sizes


def synthetic_frames(width: int, height: int, n: int, seed: int = 0, scroll: float = 1.0) -> np.ndarray:
    """(n, H, W) uint8: scrolling background + five dark looming squares, like the four-phase scene.

    The background is one procedural texture made for 320x240, resized to the frame, scrolling
    by ``scroll`` px per frame (1: a slow pan, which gaze stabilisation compensates; 0: a still
    camera); the squares grow by 2 px per frame as in the paper's scenes (up to 79 px,
    at most 40 % of the frame's smaller side), one starting every n/10 frames. The attention
    fields have a fixed size in pixels (R_AF = 40), so this keeps about one field per square at
    every frame size (up to five).
    """
    from .stimuli import SceneObject, procedural_background, scene

    texture = procedural_background(320 + n + 16, 240, seed=seed)
    spots = [(0.5, 0.5), (0.25, 0.3), (0.75, 0.7), (0.25, 0.72), (0.78, 0.28)]
    objs = []
    for k, (fx, fy) in enumerate(spots):
        onset = min(k * max(n // 10, 1), n - 1)
        approach = max(min(40, n - onset), 1)
        objs.append(SceneObject(center=(fx * width, fy * height), onset=onset, approach=approach,
                                hold=n, recede=0, max_side=min(79.0, 0.4 * min(width, height))))
    return scene(objs, size=(width, height), frames=n, background=texture, scroll=float(scroll)).frames


def bandwidth_probe(width: int, height: int, planes: int, repeats: int = 15) -> float:
    """Fastest copy (ms) of ``planes`` float32 (H, W) planes: plane k -> plane k + 1, so the
    working set is ``planes + 1`` planes and the traffic ``planes`` reads + ``planes`` writes.

    ``np.copyto`` (memcpy) split over Numba's thread count like the front end's bands, and on
    one thread; the faster of the two, and the fastest of ``repeats`` tries (not the median): a
    bandwidth figure is what the machine can do, the strictest yardstick for the ratio."""
    import numba

    from .neuropils._fast import copy_chain

    stack = np.ones((planes + 1, height * width), np.float32)
    best = float("inf")
    for threads in sorted({1, numba.get_num_threads()}):
        copy_chain(stack, threads)
        for _ in range(repeats):
            t0 = time.perf_counter()
            copy_chain(stack, threads)
            best = min(best, time.perf_counter() - t0)
    return 1e3 * best


def time_model(name: str, frames: np.ndarray, backend: str | None, warmup: int, fps: float = 30.0,
               as_run: bool = False):
    """(median ms per step, max fields) of model ``name`` over ``frames[warmup:]``.

    ``backend``: the front end's (None: the model's default; ``flow`` has none). ``as_run``: gaze
    stabilisation as ``mlplc2 run`` sets it (:class:`mlplc2.runner.RunOptions`, on by default)
    where the model has it; otherwise the paper's model, unstabilised."""
    from .models.base import get_model
    from .runner import RunOptions

    cls = get_model(name)
    kw = {} if backend is None else {"backend": backend}
    if as_run and cls.stabilises:
        kw["stabilise"] = bool(RunOptions().stabilise)
    model = cls(fps=fps, work_width=None, repeat_threshold=None, **kw)  # every frame, full size
    for f in frames[:warmup]:
        model.step(f)
    times = []
    fields = 0
    for f in frames[warmup:]:
        t0 = time.perf_counter()
        out = model.step(f)
        times.append(time.perf_counter() - t0)
        fields = max(fields, len(out.fields))
    return 1e3 * statistics.median(times), fields


def time_frontend(frames: np.ndarray, backend: str, warmup: int, fps: float = 30.0) -> float:
    """Median ms of the front end alone (Eq. 1-12) on float32 frames."""
    from .backend import make_frontend

    fe = make_frontend(Params(), fps, backend)
    gray = [np.asarray(f, np.float32) for f in frames]
    for g in gray[:warmup]:
        fe.step(g)
    times = []
    for g in gray[warmup:]:
        t0 = time.perf_counter()
        fe.step(g)
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def peak_memory_mb(name: str, frames: np.ndarray, backend: str = "auto", n: int = 4) -> float:
    """Peak bytes (MB) allocated while one stream is built and steps ``n`` frames (tracemalloc)."""
    from .models.base import get_model

    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        model = get_model(name)(fps=30.0, backend=backend, work_width=None, repeat_threshold=None)
        for f in frames[:n]:
            model.step(f)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak / 2**20


def run_bench(sizes=None, models=("mlplc2",), threads: int | None = None, frames: int = 100,
              ref_frames: int = 12, warmup: int = 10, reference: bool = True, rounds: int = 1,
              progress=None, pipeline: bool = True):
    """Run the benchmark; returns a list of :class:`BenchRow`.

    ``pipeline``: also time each model as ``mlplc2 run`` builds it (gaze stabilisation on) on the
    turning scene and on a still one, and the flow baseline on the turning scene
    (:func:`format_pipeline`).

    Each figure is a median over the frames of one round; with ``rounds`` > 1 the whole
    measurement is repeated and the smallest median kept, which filters out other processes
    that share the CPU for a while (the load average is printed with the table).
    """
    import numba

    from .neuropils import _fast, _fast_frontend

    _fast.set_threads(numba.get_num_threads() if threads is None else threads)
    n_threads = numba.get_num_threads()
    sizes = parse_sizes(DEFAULT_SIZES) if sizes is None else sizes
    planes = _fast_frontend.plane_count(Params().n_floor > 0)
    rows = []
    for w, h in sizes:
        video = synthetic_frames(w, h, warmup + max(frames, ref_frames))
        still = synthetic_frames(w, h, warmup + frames, scroll=0.0) if pipeline else None
        fast_video = video[:warmup + frames]
        ref_video = video[:warmup + ref_frames]
        best: dict = {}

        def keep(key, value):
            best[key] = value if key not in best else min(best[key], value)

        for r in range(max(1, rounds)):
            if progress:
                progress(f"{w}x{h} round {r + 1}/{rounds} ...")
            keep("probe", bandwidth_probe(w, h, planes))
            keep("fe", time_frontend(fast_video, "numba", warmup))
            if reference:
                keep("ref_fe", time_frontend(ref_video, "reference", warmup))
            for name in models:
                ms, fields = time_model(name, fast_video, "numba", warmup)
                keep((name, "ms"), ms)
                best[(name, "fields")] = fields
                if reference:
                    keep((name, "ref"), time_model(name, ref_video, "reference", warmup)[0])
                if pipeline:
                    keep((name, "run"), time_model(name, fast_video, "numba", warmup, as_run=True)[0])
                    keep((name, "still"), time_model(name, still, "numba", warmup, as_run=True)[0])
            if pipeline:
                keep("flow", time_model("flow", fast_video, None, warmup, as_run=True)[0])
        for name in models:
            peak = peak_memory_mb(name, video)
            rows.append(BenchRow(name, (w, h), n_threads, frames, best[(name, "fields")], best[(name, "ms")],
                                 best.get((name, "ref")), best["fe"], best.get("ref_fe"), best["probe"],
                                 planes, peak, best.get((name, "run")), best.get((name, "still")),
                                 best.get("flow")))
    return rows


def format_table(rows) -> str:
    """A Markdown table of the rows."""
    head = ("| model | size | threads | fields | ms/frame | frames/s | reference ms | speed-up | "
            "front end ms | reference front end ms | front-end speed-up | probe ms (N planes) | "
            "x probe | peak MB/stream |")
    lines = [head, "|" + "---|" * 14]

    def opt(v, fmt):
        return "-" if v is None else format(v, fmt)

    for r in rows:
        lines.append(f"| {r.model} | {r.size[0]}x{r.size[1]} | {r.threads} | {r.fields} | {r.ms:.2f} | "
                     f"{r.fps:.0f} | {opt(r.ref_ms, '.1f')} | {opt(r.speedup, '.1f')}x | {r.fe_ms:.2f} | "
                     f"{opt(r.ref_fe_ms, '.1f')} | {opt(r.fe_speedup, '.1f')}x | {r.probe_ms:.2f} ({r.planes}) | "
                     f"{r.probe_ratio:.1f} | {r.peak_mb:.1f} |")
    return "\n".join(lines)


def format_pipeline(rows) -> str:
    """A Markdown table of the pipeline as ``mlplc2 run`` builds it (rows measured with ``pipeline``)."""
    def opt(v, fmt):
        return "-" if v is None else format(v, fmt)

    lines = ["| model | size | threads | run pipeline ms/frame, turning | still | reference ms (NumPy, paper's "
             "model) | x reference | flow ms, turning | x flow |", "|" + "---|" * 9]
    for r in rows:
        if r.run_ms is None:
            continue
        lines.append(f"| {r.model} | {r.size[0]}x{r.size[1]} | {r.threads} | {r.run_ms:.2f} | "
                     f"{opt(r.still_ms, '.2f')} | {opt(r.ref_ms, '.1f')} | {opt(r.run_vs_reference, '.1f')}x | "
                     f"{opt(r.flow_ms, '.2f')} | {opt(r.run_vs_flow, '.1f')}x |")
    return "\n".join(lines)


def describe(frames: int, rounds: int) -> str:
    """What the columns of :func:`format_table` measure (printed under the table)."""
    import os

    from .neuropils import _fast_frontend

    traffic = sum(_fast_frontend.plane_traffic(Params().n_floor > 0).values())
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return (f"ms/frame: median of model.step over {frames} in-memory uint8 frames (no decoding; "
            f"smallest of {rounds} round(s)): front end, attention fields and target estimates. "
            f"front end: Eq. 1-12 alone. probe: fastest copy of the N float32 planes one stream touches "
            f"({traffic} plane reads+writes per frame in the kernels), same threads; 'x probe' = "
            f"ms/frame / probe. Second table: the pipeline as `mlplc2 run` builds it (gaze stabilisation "
            f"on: camera motion, front end, fields, targets) on the same scrolling (turning) scene and on it "
            f"from a still camera; x reference = reference ms (the paper's model on the plain NumPy front "
            f"end, turning scene) / run ms, turning; x flow = the flow baseline's ms (as run builds it, "
            f"turning scene) / run ms, turning. Load average after the run: {load}.")


# ---------------------------------------------------------------------------
# latency and end to end (mlplc2 bench --latency)
# ---------------------------------------------------------------------------
@dataclass
class LatencyRow:
    """Per source size: ms per frame of decoding alone, the model alone, ``run`` end to end (as it
    runs by default; with the model on every thread, ``run_all_ms``, where the default leaves a core to
    the decoding thread, ``RunOptions.spare_core``, else None; and on one thread fewer: ``run_fewer_ms``,
    None on one core), each
    by the wall clock and as CPU time of the process (``*_cpu_ms``: every thread's), and, played
    as a live camera at 30 frames/s, the latency from decoding to the JSON line (ms) and the
    frames skipped; ``threads``: the model's threads; ``load``: the 1-minute load average after."""

    model: str
    size: tuple[int, int]
    frames: int
    decode_ms: float
    model_ms: float
    run_ms: float
    latency: dict
    skipped: int = 0
    decode_cpu_ms: float = 0.0
    model_cpu_ms: float = 0.0
    run_cpu_ms: float = 0.0
    run_fewer_ms: float | None = None
    run_fewer_cpu_ms: float | None = None
    threads: int = 1
    load: float | None = None
    run_all_ms: float | None = None
    run_all_cpu_ms: float | None = None


class _Paced:
    """A decoder that hands out its frames no faster than ``fps`` by the wall clock, like a camera."""

    def __init__(self, decoder, fps: float):
        self._dec, self._period, self._t0, self._k = decoder, 1.0 / fps, None, 0
        self.name, self.fps, self.size, self.frame_count = decoder.name, fps, decoder.size, None

    @property
    def time_s(self):
        return self._dec.time_s

    def skip(self, n: int) -> int:
        return self._dec.skip(n)

    def read(self):
        self._t0 = time.perf_counter() if self._t0 is None else self._t0
        wait = self._t0 + self._k * self._period - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        self._k += 1
        return self._dec.read()

    def close(self) -> None:
        self._dec.close()


def _cpu_s() -> float:
    """CPU time of the process so far (s): every thread's, user and system."""
    t = os.times()
    return t.user + t.system


def _per_frame(work) -> tuple[float, float, int]:
    """``work()`` (returning its number of frames) timed: wall ms and CPU ms per frame, frames."""
    w0, c0 = time.perf_counter(), _cpu_s()
    n = max(int(work()), 1)
    return 1e3 * (time.perf_counter() - w0) / n, 1e3 * (_cpu_s() - c0) / n, n


def time_latency(width: int, height: int, frames: int = 150, model: str = "mlplc2") -> LatencyRow:
    """Write the scene of :func:`synthetic_frames` at ``width`` x ``height`` as an H.264 MP4 (30
    fps), then time, one after the other in this process: decoding it as ``run`` decodes it
    (:func:`mlplc2.io.open_source`, reduced in its thread to the models' working size, nothing
    else), ``model`` stepping on the frames in memory (as ``run`` builds it: frames wider than 320
    px reduced, gaze stabilisation on where the model has it; every frame stepped),
    :func:`mlplc2.run` on the clip writing its JSON lines (``jsonl``) and CSV files (its frame
    loop's ms per frame; as it runs by default, which leaves a core to the decoding thread where that
    reduces the frames: ``RunOptions.spare_core``), the same with the model on every thread (where the
    default leaves a core) and on one thread fewer, and ``run`` on the clip played as a live camera
    (frames handed out at 30 frames/s; the newest taken): its latency from a frame's decoding to its
    JSON line. Each
    time also as the process's CPU time per frame (every thread), which a busy machine blurs less."""
    from .backend import threads
    from .io import FrameSource, open_source, write_video
    from .io.decoders import open_decoder
    from .models.base import get_model
    from .runner import run

    video = synthetic_frames(width, height, frames)
    cls = get_model(model)
    m = cls(fps=30.0, repeat_threshold=None, **({"stabilise": True} if cls.stabilises else {}))
    options = dict(jsonl=os.devnull, quiet=True, plot=False, repeat_threshold=None)
    with tempfile.TemporaryDirectory(prefix="mlplc2-latency-") as tmp:
        clip = write_video(Path(tmp) / "clip.mp4", video, 30.0)

        def decode() -> int:
            src = open_source(clip)
            if m.work_width is not None and width > m.work_width:  # as run reduces it (Model.work_width)
                src.reduce_to((m.work_width, max(int(round(height * m.work_width / width)), m.min_size)))
            return sum(1 for _ in src)

        def alone() -> int:
            for f in video[1:]:
                m.step(f)
            return len(video) - 1

        def end_to_end(out: str, n_threads: int | None, spare_core: bool = True):
            def work() -> int:
                with threads(n_threads):
                    box.append(run(clip, [model], out=Path(tmp) / out, spare_core=spare_core, **options))
                return box[-1].n_frames
            box: list = []
            _, cpu, _ = _per_frame(work)
            return 1e3 * box[-1].seconds / max(box[-1].n_frames, 1), cpu, box[-1].n_frames

        decode_ms, decode_cpu, _ = _per_frame(decode)
        m.step(video[0])  # warm-up: state built, kernels loaded
        model_ms, model_cpu, _ = _per_frame(alone)
        with threads(None) as n_threads:
            pass
        run_ms, run_cpu, n = end_to_end("out", None)
        fewer_ms = fewer_cpu = all_ms = all_cpu = None
        if n_threads > 1:
            fewer_ms, fewer_cpu, _ = end_to_end("fewer", n_threads - 1, False)
            if m.work_width is not None and width > m.work_width:     # run leaves a core to the decoding
                all_ms, all_cpu, _ = end_to_end("all", None, False)   # thread by default: every thread
        camera = FrameSource(_Paced(open_decoder(str(clip), "opencv")[0], 30.0), "camera", live=True)
        live = run(camera, [model], out=Path(tmp) / "live", **options)
    return LatencyRow(model, (width, height), n, decode_ms, model_ms, run_ms, live.latency, live.skipped,
                      decode_cpu, model_cpu, run_cpu, fewer_ms, fewer_cpu, n_threads, os.getloadavg()[0], all_ms,
                      all_cpu)


def format_latency(rows) -> str:
    """A Markdown table of :class:`LatencyRow` s (ms per frame: wall clock / CPU time)."""
    def both(wall, cpu):
        return "-" if wall is None else f"{wall:.2f} / {cpu:.2f}"

    lines = ["| model | source | frames | threads | decode ms/frame | model ms/frame | run ms/frame | "
             "run, every thread | run, one thread fewer | max(decode, model) / run | live: latency median ms | "
             "p99 ms | max ms | skipped | load |", "|" + "---|" * 15]
    for r in rows:
        lat = r.latency
        lines.append(f"| {r.model} | {r.size[0]}x{r.size[1]} | {r.frames} | {r.threads} | "
                     f"{both(r.decode_ms, r.decode_cpu_ms)} | {both(r.model_ms, r.model_cpu_ms)} | "
                     f"{both(r.run_ms, r.run_cpu_ms)} | {both(r.run_all_ms, r.run_all_cpu_ms)} | "
                     f"{both(r.run_fewer_ms, r.run_fewer_cpu_ms)} | "
                     f"{100 * max(r.decode_ms, r.model_ms) / r.run_ms:.0f} % | "
                     f"{lat.get('median_ms', 0):.1f} | {lat.get('p99_ms', 0):.1f} | {lat.get('max_ms', 0):.1f} | "
                     f"{r.skipped} | {'-' if r.load is None else f'{r.load:.1f}'} |")
    return "\n".join(lines)
