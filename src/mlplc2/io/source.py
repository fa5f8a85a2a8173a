"""The streaming source: :func:`open_source` gives a :class:`FrameSource`, which decodes in a
background thread (decoding and the models overlap; memory does not depend on the video
length) and resizes the frames; :func:`read_video` decodes a short clip into memory.
"""

from __future__ import annotations

import math
import queue
import threading
import time
import warnings
from collections.abc import Iterator

import numpy as np

from .._validation import InputValueError, InputWarning, check_fps
from .decoders import Decoder, open_decoder
from .formats import DEFAULT_FPS, TruncatedInputWarning, is_camera, is_live, output_size, parse_resize

_QUEUE_SIZE = 4


# ---------------------------------------------------------------------------
# the streaming source
# ---------------------------------------------------------------------------
class FrameSource:
    """Iterable of ``(index, frame)`` decoded in a background thread.

    Build it with :func:`open_source`. ``index`` is the frame's 0-based index
    in the source (so the first frame yielded is ``start``); ``frame`` is RGB
    ``uint8`` of shape ``(H, W, 3)`` at :attr:`out_size` (after resizing).
    With ``keep_original=True`` the items are ``(index, frame, original)``,
    ``original`` being the frame at the input size.

    Attributes
    ----------
    fps : float
        Frame rate: the ``fps`` given, else the container's, else 30.
    size : (int, int)
        ``(W, H)`` of the input frames.
    out_size : (int, int)
        ``(W, H)`` of the frames yielded (``size`` unless resized).
    scale_x, scale_y : float
        ``W_in / W_out`` and ``H_in / H_out``: multiply a model coordinate by
        these to get input pixels (see :meth:`to_input`).
    frame_count : int or None
        Frames in the whole source as the container states it (None if unknown,
        e.g. a camera).
    total : int or None
        Frames this source is expected to yield given ``start`` and ``end``.
    n_read : int
        Frames yielded so far.
    time_s : float or None
        Time (s) of the frame yielded last: the container's timestamp (PyAV ``frame.time``,
        OpenCV ``CAP_PROP_POS_MSEC``), None where the source has none or ``fps`` was given
        (frame count / fps then); pass it to ``Model.step(frame, t)``.
    truncated : bool
        True when decoding stopped before the stated end (damaged or cut file);
        :attr:`message` then names the frame where it stopped.
    live : bool
        Frames arrive in real time (a camera, an RTSP stream): the decoding thread never
        waits for the consumer; it keeps only the newest decoded frame, so a consumer that
        falls behind gets the newest frame and the ones in between are skipped (the gap in
        ``index``; :attr:`skipped`, :attr:`n_skipped`); from its opening on, so that the first
        frame given is the newest too, not one buffered while the caller built its models (without
        ``end``). Not live (a file, HTTP, stdin): every
        frame in order, the thread waits when the queue is full.
    decoded_at : float
        ``time.perf_counter()`` when the decoder gave the frame last yielded (before its
        reduction): the start of its latency.
    skipped : int
        Frames skipped just before the frame last yielded (live only); :attr:`n_skipped` all of them.
    dropped : bool
        A stream or camera stopped with an error (connection lost, no frame): :attr:`message`
        says so; the frames before it were yielded.
    damaged : list of int
        The frames that could not be decoded (a damaged packet of a file or a stream), skipped;
        the frames after them are yielded with their own indices.
    """

    #: Seconds :meth:`close` waits for a stream's or a camera's decoding thread (waiting on a read
    #: nothing answers: a stalled stdin) before it leaves the thread to end on its own.
    CLOSE_WAIT_S = 1.0

    def __init__(self, decoder: Decoder, kind: str, *, fps=None, start: int = 0, end: int | None = None,
                 resize=None, scale=None, keep_original: bool = False, queue_size: int = _QUEUE_SIZE,
                 live: bool = False):
        self._dec = decoder
        self.kind = kind
        self.live = bool(live)
        self.decoded_at = 0.0
        self.skipped = self.n_skipped = 0
        self.dropped = False
        self.name = decoder.name
        self.fps = check_fps(fps) if fps is not None else (decoder.fps or DEFAULT_FPS)
        # the container's timestamps, unless the caller set the rate (then frame count / fps)
        self._timed = fps is None
        self.time_s: float | None = None
        self.start = int(start)
        self.end = None if end is None else int(end)
        self.keep_original = keep_original
        self.frame_count = decoder.frame_count
        self.truncated = False
        self.truncated_at: int | None = None
        self.message: str | None = None
        self.n_read = 0
        self.damaged: list[int] = []      # decoders.MAX_DAMAGED in a row at most
        # First frame read now, in the caller's thread, so that empty or
        # undecodable inputs fail at open time with a clear message.
        skipped = decoder.skip(self.start) if self.start else 0
        first = decoder.read() if skipped == self.start and (self.end is None or self.end > self.start) else None
        if first is None:
            decoder.close()
            if self.end is not None and self.end <= self.start:
                raise InputValueError(f"end ({self.end}) must be larger than start ({self.start})")
            if self.start:   # nothing to process; the start frame one past the last included
                raise InputValueError(f"{self.name}: start frame {self.start} is past the end ({skipped} frames)")
            why = getattr(decoder, "error", None)
            raise InputValueError(f"{self.name}: video has no frames (empty or undecodable)" + (f": {why}" if why else ""))
        h, w = first.shape[:2]
        self.size = (int(w), int(h))
        try:
            self.out_size = output_size(w, h, resize, scale)
        except BaseException:
            decoder.close()
            raise
        self.scale_x = w / self.out_size[0]
        self.scale_y = h / self.out_size[1]
        if self.frame_count is not None:
            stop = self.frame_count if self.end is None else min(self.end, self.frame_count)
            self.total: int | None = max(stop - self.start, 0)
        else:
            self.total = None if self.end is None else self.end - self.start
        self._first = first
        self._first_time = decoder.time_s
        self._first_decoded: float | None = None
        self._centres = False
        self._queue: queue.Queue = queue.Queue(maxsize=1 if self.live else queue_size)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._iterated = False
        self._items: Iterator[tuple] | None = None   # the decoding thread's frames, once started
        self._ahead: list[tuple] = []                # frames read ahead (peek), with their state
        self._ahead_error: BaseException | None = None
        # Live: the source runs on while the caller builds its models; until iteration begins a
        # thread reads on and keeps only the newest frame (the others count as skipped), so that
        # the first frames given are not the ones buffered meanwhile (seconds old).
        self._drained = 0
        self._drained_to_end = False
        self._drainer: threading.Thread | None = None
        if self.live and self.end is None:
            self._drainer = threading.Thread(target=self._drain, name="mlplc2-drain", daemon=True)
            self._drainer.start()

    def reduce_to(self, size: tuple[int, int]) -> None:
        """Yield frames at ``size`` ``(W, H)`` from now on, reduced in the decoding thread (before
        iterating; :func:`mlplc2.run` gives the models' working size here)."""
        if self._iterated or self._items is not None:
            raise RuntimeError("reduce_to must be called before iterating (and before peek)")
        self.out_size = (int(size[0]), int(size[1]))
        self.scale_x = self.size[0] / self.out_size[0]
        self.scale_y = self.size[1] / self.out_size[1]
        self._centres = True

    def span_s(self) -> tuple[float, float | None]:
        """The times (s) the first and the last frame will have, on the clock of :attr:`time_s` (its
        container timestamps from the first frame's on, else frame index / fps); the last is None
        when :attr:`total` is unknown (a stream, a camera) and estimated at the frame rate."""
        first = self._first_time if self._timed and self._first_time is not None else self.start / self.fps
        return first, None if not self.total else first + (self.total - 1) / self.fps

    # -- mapping --------------------------------------------------------------
    @property
    def resized(self) -> bool:
        return self.out_size != self.size

    def to_input(self, x: float, y: float) -> tuple[float, float]:
        """Map a point from model (resized) pixels to input pixels:
        ``(x * W_in / W_out, y * H_in / H_out)``; after :meth:`reduce_to`, pixel centres onto pixel
        centres, ``(x + 0.5) * W_in / W_out - 0.5``, as a model reducing its frames itself does."""
        if self._centres:
            return (x + 0.5) * self.scale_x - 0.5, (y + 0.5) * self.scale_y - 0.5
        return x * self.scale_x, y * self.scale_y

    def to_model(self, x: float, y: float) -> tuple[float, float]:
        """Map a point from input pixels to model (resized) pixels: the inverse of :meth:`to_input`."""
        if self._centres:
            return (x + 0.5) / self.scale_x - 0.5, (y + 0.5) / self.scale_y - 0.5
        return x / self.scale_x, y / self.scale_y

    # -- decoding thread ------------------------------------------------------
    def _drain(self) -> None:
        """Live, before iteration: read on, keeping the newest frame as the first to give."""
        while not (self._stop.is_set() or self._iterated):
            frame = self._dec.read()
            if frame is None:
                self._drained_to_end = True
                return
            self._first, self._first_time, self._first_decoded = frame, self._dec.time_s, time.perf_counter()
            self._drained += 1

    def _stop_draining(self, timeout: float | None = None) -> None:
        if self._drainer is not None:
            self._drainer.join(timeout)
            self._drainer = None

    def _prepare(self, frame: np.ndarray):
        if self.resized:
            import cv2

            small = cv2.resize(frame, self.out_size, interpolation=cv2.INTER_AREA)
        else:
            small = frame
        return (small, frame) if self.keep_original else (small,)

    def _put(self, item) -> bool:
        if self.live and item[0] == "frame":
            return self._replace(item)
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _replace(self, item) -> bool:
        """Live: put the newest frame, replacing a frame not yet taken (counted as skipped)."""
        while not self._stop.is_set():
            try:
                self._queue.put_nowait(item)
                return True
            except queue.Full:
                try:
                    old = self._queue.get_nowait()
                except queue.Empty:
                    continue
                item = (*item[:4], item[4] + old[4] + 1)
        return False

    def _work(self) -> None:
        dec = self._dec
        index = self.start + self._drained
        try:
            frame, t, decoded = self._first, self._first_time, self._first_decoded or time.perf_counter()
            self._first, skipped = None, self._drained
            while frame is not None:
                payload = (self._prepare(frame), t)
                if not self._put(("frame", index, payload, decoded, skipped)):
                    return
                index, skipped = index + 1, 0
                if self.end is not None and index >= self.end:
                    break
                frame = None if self._drained_to_end else dec.read()
                t, decoded = dec.time_s, time.perf_counter()
                gap = getattr(dec, "gap", 0)        # damaged frames skipped: the index counts them
                if frame is not None and gap:
                    self.damaged.extend(range(index, index + gap))
                    index += gap
                    if self.end is not None and index >= self.end:
                        break
            self._put(("end", index, None, 0.0, 0))
        except BaseException as exc:  # noqa: BLE001 - handed to the consumer thread
            self._put(("error", index, exc, 0.0, 0))
        finally:
            dec.close()

    def peek(self, n: int) -> list[tuple]:
        """The first ``n`` items iterating will yield (fewer when the source ends first), read ahead
        now, before iterating (a source that is not live: a live one would skip frames meanwhile);
        iterating yields them again first, each with its own :attr:`time_s`, :attr:`decoded_at`
        and :attr:`skipped`, then the others. An error of the source while reading ahead is raised
        after the items before it, as it would have been."""
        if self.live or self._iterated:
            raise RuntimeError("peek needs a source that is not live, before iterating it")
        self._items = self._frames()
        while len(self._ahead) < n:
            try:
                item = next(self._items)
            except StopIteration:
                break
            except Exception as exc:  # noqa: BLE001 - the source's own error, raised in its place
                self._ahead_error = exc
                break
            self._ahead.append((item, self.time_s, self.decoded_at, self.skipped, self.n_read, self.n_skipped))
        return [a[0] for a in self._ahead]

    def __iter__(self) -> Iterator[tuple]:
        if self._iterated:
            raise RuntimeError("a FrameSource can be iterated only once")
        self._iterated = True
        items, self._items = self._items or self._frames(), None
        try:
            while self._ahead:
                item, self.time_s, self.decoded_at, self.skipped, self.n_read, self.n_skipped = self._ahead.pop(0)
                yield item
            if self._ahead_error is not None:
                raise self._ahead_error
            yield from items
        finally:
            items.close()
            self.close()

    def _frames(self) -> Iterator[tuple]:
        """The decoding thread's frames (started here), setting the attributes of each as it is yielded."""
        self._stop_draining()
        self._thread = threading.Thread(target=self._work, name="mlplc2-decode", daemon=True)
        self._thread.start()
        try:
            while True:
                kind, index, payload, self.decoded_at, self.skipped = self._queue.get()
                if kind == "frame":
                    self.n_read += 1
                    self.n_skipped += self.skipped
                    self.time_s = self._timestamp(payload[1])
                    yield (index, *payload[0])
                elif kind == "end":
                    self._check_end(index)
                    return
                else:
                    raise payload
        finally:
            self.close()

    def _timestamp(self, t: float | None) -> float | None:
        """The time (s) of the frame yielded next: the container's timestamp (None: the source has
        none, or ``fps`` was given); one that is missing or does not increase (a damaged container)
        is the last one plus 1 / fps. Without a timestamp on the first frame, None throughout."""
        last = self.time_s
        if last is None:
            self._timed = self._timed and t is not None and self.n_read == 1
            return t if self._timed else None
        if t is None or not t > last:
            return last + 1.0 / self.fps
        return t

    def _check_end(self, index: int) -> None:
        """Decide whether the stream stopped early (index = first frame not decoded)."""
        expected = self.frame_count if self.end is None else (
            min(self.end, self.frame_count) if self.frame_count is not None else None)
        failed_image = getattr(self._dec, "failed", None)
        error = getattr(self._dec, "error", None)
        if self.kind in ("stream", "camera") and error is not None:
            self.dropped = True
            # frames of the source, the ones a live source skipped included
            self.message = (f"{self.name}: the stream stopped after {index - self.start} frames ({error}); "
                            "results cover the frames before it")
        elif failed_image is not None:
            self.truncated, self.truncated_at = True, index
            self.message = f"{self.name}: {failed_image} (frame {index}); stopped there"
        elif (self.kind == "video" or (self.kind == "stream" and not self.live)) and expected is not None \
                and index < expected and not self._reached_length():
            # a file, or one read whole from a pipe or HTTP that states its count
            self.truncated, self.truncated_at = True, index
            # the hint only where frames decode after the stop (OpenCV's probe): for a cut file it cannot help
            self.message = (f"{self.name}: decoding stopped at frame {index} of {expected} "
                            "(file truncated or damaged); results cover frames before it"
                            + (" (frames decode after it: --decoder pyav skips a damaged frame and goes on)"
                               if getattr(self._dec, "goes_on", None) else ""))
        elif self.end is not None and index < self.end:   # a clip shorter than the end asked for: ran to its end
            warnings.warn(f"{self.name} has {index} frames: end frame {self.end} is past its end; "
                          f"the run went to its last frame", InputWarning, stacklevel=2)

    def _reached_length(self) -> bool:
        """Whether the last frame decoded lies at the end of the length the container states: the count
        was then an estimate, not frames lost. OpenCV counts a Matroska file's frames as its duration
        times its frame rate, too many where frames were dropped (a variable frame rate) and the
        timestamps kept."""
        fps, first, last = self._dec.fps, self._dec.start_s, self._dec.time_s
        return (self.frame_count is not None and fps is not None and first is not None and last is not None
                and last - first + 1.5 / fps >= self.frame_count / fps)

    def close(self) -> None:
        """Stop the decoding thread and release the input (idempotent)."""
        self._stop.set()
        drainer = self._drainer
        self._stop_draining(self.CLOSE_WAIT_S)     # waiting on a read too, perhaps
        if drainer is not None and drainer.is_alive():
            return                                 # it still reads: the decoder is left to the exit
        if self._thread is not None and self._thread is not threading.current_thread():
            # A stream's decoding thread may wait on a read that nothing answers (stdin or a camera that
            # stalled): after a while it is left to end on its own (a daemon: it does not hold the exit).
            deadline = time.monotonic() + (self.CLOSE_WAIT_S if self.kind in ("stream", "camera") else math.inf)
            while self._thread.is_alive() and time.monotonic() < deadline:
                try:
                    while True:
                        self._queue.get_nowait()
                except queue.Empty:
                    pass
                self._thread.join(timeout=0.05)
        elif self._thread is None:
            self._dec.close()

    def __enter__(self) -> "FrameSource":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        w, h = self.size
        return (f"FrameSource({self.name!r}, kind={self.kind!r}, size={w}x{h}, "
                f"out_size={self.out_size[0]}x{self.out_size[1]}, fps={self.fps:g}, frame_count={self.frame_count})")


def open_source(source, *, fps=None, start: int = 0, end: int | None = None, resize=None, scale=None,
                keep_original: bool = False, decoder: str = "opencv", live: bool | None = None) -> FrameSource:
    """Open a video file, a folder of images, a glob pattern, a camera or a stream for streaming.

    Parameters
    ----------
    source : str, path-like or int
        A video file (anything OpenCV/FFmpeg reads: AVI, MP4, ...), a folder
        of images or a glob pattern such as ``'frames/*.png'`` (sorted
        naturally: ``2.png`` before ``10.png``), a camera index (an int or
        a string of digits that is not an existing path), a URL (``rtsp://``,
        ``http(s)://``, anything FFmpeg opens; decoded by PyAV) or ``'-'``: standard input
        (any container FFmpeg reads from a pipe; PyAV).
    fps : float, optional
        Frame rate to use instead of the container's (images: default 30).
    start, end : int
        Yield frames ``start <= index < end`` (``end=None``: to the last).
    resize : (W, H) or 'WxH', optional
        Resize every frame to this size before yielding it.
    scale : float, optional
        Or resize by this factor (e.g. 0.5). Not together with ``resize``.
    keep_original : bool
        Also yield the frame at the input size: items ``(index, frame, original)``.
    decoder : {'opencv', 'pyav'}
        Video decoder (of files; streams are decoded by PyAV, cameras by OpenCV).
    live : bool, optional
        Take the newest frame when the consumer falls behind, skipping the others
        (:attr:`FrameSource.live`). Default: a camera and the URLs of
        :data:`~mlplc2.io.formats.LIVE_SCHEMES` (RTSP, ...) are live; files, HTTP(S) and stdin not.

    Returns
    -------
    FrameSource
        Iterate it once to get ``(index, frame)``; use it as a context manager
        (or call ``close()``) to stop early.

    Raises
    ------
    InputValueError
        Missing file, directory without images, a file that is not a video,
        a video with no frames, a bad ``resize``/``scale``/``start``/``end``.
    """
    start = int(start)
    if start < 0:
        raise InputValueError(f"start must be >= 0, got {start}")
    if end is not None and int(end) <= start:
        raise InputValueError(f"end ({end}) must be larger than start ({start})")
    if resize is not None:
        resize = parse_resize(resize)
    if fps is not None:
        fps = check_fps(fps)
    reader, kind = open_decoder(source, decoder)
    return FrameSource(reader, kind, fps=fps, start=start, end=end, resize=resize, scale=scale,
                       keep_original=keep_original, live=is_live(source) if live is None else live)


def read_video(path, *, decoder: str = "opencv") -> tuple[np.ndarray, float]:
    """Decode a whole video into memory.

    Returns
    -------
    frames : ndarray, shape (T, H, W, 3), uint8
        RGB frames.
    fps : float
        The container's frame rate (30 if it states none).

    Raises
    ------
    InputValueError
        Missing file, not a video, no frames.

    Notes
    -----
    A truncated file gives the frames that decode, with a
    :class:`TruncatedInputWarning` naming the frame where decoding stopped.
    Use :func:`open_source` for long videos (memory independent of length).
    """
    if is_camera(path):
        raise InputValueError("read_video reads files; use open_source for a camera")
    src = open_source(path, decoder=decoder)
    frames = [f for _, f in src]
    if src.truncated:
        warnings.warn(src.message, TruncatedInputWarning, stacklevel=2)
    return np.stack(frames), src.fps

