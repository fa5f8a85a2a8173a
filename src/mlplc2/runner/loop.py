"""The run itself: :func:`run` (every frame of a source through the models, the outputs written as it goes, the
summaries at the end) and :func:`stream` (each frame's JSON line yielded, nothing written)."""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import replace
from pathlib import Path

from .._signals import interrupts
from .._validation import InputValueError
from .._files import write_json
from ..backend import one_fewer, threads, workers
from ..io import FrameSource, TruncatedInputWarning, VideoWriter
from ..models.base import Model
from .frames import Frames, GyroEnded, OutputFailed
from .options import RunOptions, run_options
from .prepare import open_run
from .result import RunInterrupted, RunResult


def run(source, models: Sequence[str | Model] | str = ("mlplc2",), *, out=None, options: RunOptions | None = None,
        **keywords) -> RunResult:
    """Run models over a video, a folder of images, a glob pattern or a camera.

    Parameters
    ----------
    source : str, path-like or int
        Input; see :func:`mlplc2.io.open_source`.
    models : sequence of str or Model
        Registry names (``mlplc2.available_models()``) or model instances. All
        models see the same decoded frames (decoded once). An instance is reset and
        given the run's ``hfov_deg``, ``repeat_threshold`` and ``target_params`` where set.
    out : path, None or False
        Output folder (created). ``None``: ``<stem>_mlplc2/`` next to the
        input. ``False``: write nothing, only return the result.
    options : RunOptions, optional
        How to read, build and write (:class:`RunOptions`; default: its defaults).
    **keywords
        Fields of :class:`RunOptions` (``fps``, ``resize``, ``scale``, ``start``, ``end``,
        ``video``, ``quiet``, ``params``, ``progress``, ``plot``, ``decoder``, ``hfov_deg``,
        ``keep_rows``, ``repeat_threshold``, ``draw_fields``, ``target_params``), which
        replace those of ``options``.

    Returns
    -------
    RunResult

    Raises
    ------
    InputError
        Bad input (missing file, not a video, unknown model, bad resize, ...); or a gyro whose
        samples end before a frame of a source of unknown length (a stream), after writing the
        outputs of the frames done (``fields.json``: ``error``, not complete).
    RunInterrupted
        On Ctrl-C, after writing the outputs of the frames done
        (``fields.json`` then says ``"interrupted": true``). A Ctrl-C during a frame
        takes effect when the frame is finished; a second one stops at once.

    Warns
    -----
    TruncatedInputWarning
        The input stopped decoding early; the outputs cover the frames decoded
        and ``result.truncated`` is True.
    """
    options = run_options(options, keywords)
    with workers():
        src, built, result = open_run(source, models, options, out)
        return _loop(src, built, result, result.out, options)


def stream(source, models: Sequence[str | Model] | str | Model = "mlplc2", *, options: RunOptions | None = None,
           **keywords) -> Iterator[dict]:
    """Run models over a source and yield each frame's results as it is done.

    The same as ``mlplc2 run SOURCE --jsonl -`` from Python: each item is the dict of one JSON
    line (schema 1, docs/robot.md: ``frame``, ``time_s``, ``skipped``, ``warning``, ``models``,
    ``targets``). ``source``, ``models`` and the keywords are those of :func:`run` (``source`` may
    also be an opened :class:`~mlplc2.io.FrameSource`); nothing is written. Stop by breaking out
    of the loop (or ``max_frames`` / ``duration_s``): closing the generator (a ``for`` loop over
    ``stream(...)`` drops it at the ``break``; one kept in a name: its ``close()``) closes the
    source and stops and joins the worker threads (:func:`mlplc2.backend.workers`).

    >>> for line in mlplc2.stream("rtsp://camera/stream", hfov_deg=90):   # doctest: +SKIP
    ...     if line["warning"]:
    ...         brake()
    """
    options = replace(run_options(options, keywords, "stream"), video=False, keep_rows=False)
    with workers():
        src, built, result = open_run(source, models, options, False)
        frames = Frames(src, built, result, options)
        t0 = time.perf_counter()
        try:
            for item in src:
                try:
                    line = frames.step(item)
                except GyroEnded as exc:    # the gyro gave out (a file's samples end, a live gyro's bad value)
                    raise InputValueError(f"{exc}; the lines cover the {result.n_frames} frames before") from None
                yield line
                if options.done(result.n_frames, time.perf_counter() - t0):
                    break
            else:
                _warn_ended(src)
        finally:
            src.close()
            frames.recorder.close()      # its spill files


def _warn_ended(src: FrameSource) -> None:
    """What :func:`stream` says when its source ran out (``run`` records it in its result and ``fields.json``): a
    stream that stopped on an error or a file cut short (:class:`TruncatedInputWarning`), frames that could not be
    decoded and were skipped."""
    if src.truncated or src.dropped:
        warnings.warn(src.message or f"{src.name}: the input stopped early", TruncatedInputWarning, stacklevel=3)
    if src.damaged:
        warnings.warn(damaged_message(src.name, src.damaged), TruncatedInputWarning, stacklevel=3)


def damaged_message(name: str, damaged: list[int]) -> str:
    """The line that names the frames of ``name`` that could not be decoded and were skipped (``damaged``: their
    indices; the CLI's warning after a run, :func:`stream`'s)."""
    shown = ", ".join(map(str, damaged[:5])) + (", ..." if len(damaged) > 5 else "")
    return f"{name}: {len(damaged)} damaged frame(s) could not be decoded ({shown}); skipped"


def _loop(src: FrameSource, built: list[Model], result: RunResult, out_dir, options: RunOptions) -> RunResult:
    from .._progress import bar as progress_bar

    frames = Frames(src, built, result, options)
    interrupted = False
    failed: OutputFailed | None = None
    gyro_ended: GyroEnded | None = None
    bar = None
    # Ctrl-C / SIGTERM while a frame is in progress is deferred to the end of that frame
    # (stop.between): responses.csv, targets.csv and fields.json always cover the same frames.
    with interrupts(defer=True) as stop, threads(one_fewer() if options.spare_core and src.resized and not src.live else None):
        t0 = time.perf_counter()
        try:
            frames.open(out_dir)
            t0 = time.perf_counter()
            for item in stop.between(src):
                frames.step(item)
                if bar is None:
                    # the bar (and its clock) starts after the first frame, which may compile the
                    # kernels (tens of seconds, once per install): its rate and ETA never count it
                    bar = progress_bar(total=src.total, initial=1, unit="frame", leave=False,
                                       disable=not (options.progress and not options.quiet),
                                       desc=Path(src.name).name or src.name)
                else:
                    bar.update()
                if options.done(result.n_frames, time.perf_counter() - t0) or (frames.lines and frames.lines.gone):
                    break
            # A signal during the last frame (or the one the loop stopped after: Ctrl-C in a shell also
            # ends the reader of the JSON lines) is the run's interrupt, not one after its summaries:
            # fields.json said "complete" and the exit was a bare "interrupted".
            stop.check()
        except KeyboardInterrupt:
            interrupted = True
        except GyroEnded as exc:
            gyro_ended = exc
        except OutputFailed as exc:
            failed = exc
            if frames.vw is not None and exc.name == "annotated.mp4":
                frames.vw.abort()
                frames.vw = None
        except BaseException:
            if frames.vw is not None:
                frames.vw.abort()
            raise
        finally:
            result.seconds = time.perf_counter() - t0
            if bar is not None:
                bar.close()
            frames.close_csv(failed is not None)
            src.close()
        frames.summarise(interrupted, failed)
        if gyro_ended is not None:
            result.error = str(gyro_ended)
        if out_dir is not None:
            try:
                _finish(result, out_dir, frames.vw, options.plot)
            except BaseException as exc:
                if frames.vw is not None:
                    frames.vw.abort()
                if failed is None or not isinstance(exc, OSError):
                    raise
                # the summaries failed too (the same full disk): the first failure is the one to name
        if result.truncated:
            warnings.warn(result.message, TruncatedInputWarning, stacklevel=3)
        if failed is not None:
            cause = failed.__cause__
            raise OSError(getattr(cause, "errno", None), f"{getattr(cause, 'strerror', None) or cause}; the other "
                          f"outputs cover the {result.n_frames} frames before", failed.path) from cause
        if gyro_ended is not None:
            raise InputValueError(f"{gyro_ended}; the outputs cover the {result.n_frames} frames before")
        if interrupted:
            raise RunInterrupted(result)
    return result


def _finish(result: RunResult, out_dir: Path, vw: VideoWriter | None, plot: bool) -> None:
    """The summaries, small ones first: ``fields.json``, ``responses.png``, then ``annotated.mp4``
    (finishing the video may need more room than the disk has left)."""
    path = out_dir / "fields.json"
    write_json(path, result.summary())
    result.files["fields.json"] = path
    if plot and result.n_frames:
        from ..plots import plot_responses

        path = out_dir / "responses.png"
        title = f"{Path(result.source).name}: {', '.join(result.models)}"
        if result.interrupted or result.truncated or result.error:
            why = "interrupted" if result.interrupted else result.error or "input truncated"
            title += f" ({why} after {result.n_frames} frames)"
        rows = result.rows or result.files.get("responses.csv")
        targets = result.targets or result.files.get("targets.csv")
        if rows is not None:
            plot_responses(rows, path, fields=result.fields, title=title, fps=result.fps, targets=targets)
        result.files["responses.png"] = path
    if vw is not None:
        if vw.n_frames:
            result.files["annotated.mp4"] = vw.close()
        else:
            vw.abort()
