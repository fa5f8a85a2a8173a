"""Video input and output: a minimal reader, a streaming frame source, a writer.

* :func:`read_video` decodes a whole video into memory (for short clips).
* :func:`open_source` streams frames one at a time from a video file, a folder
  of images, a glob pattern or a camera, decoding in a background thread so
  decoding and the model overlap; memory does not depend on the video length.
* :func:`write_video` / :class:`VideoWriter` write MP4 (H.264 via PyAV) or AVI
  (MJPG) atomically.

Frames are always RGB ``uint8`` arrays of shape ``(H, W, 3)``. Sizes are given
as ``(W, H)`` (OpenCV convention), shapes as ``(H, W)`` (numpy convention).

OpenCV is the default decoder. PyAV, also a core dependency, decodes on request
(``decoder="pyav"``) and encodes every MP4 as H.264, which browsers play. Where PyAV is
missing or its FFmpeg has no H.264 encoder, MP4 files are written by OpenCV
(``mp4v``, which browsers do not play), with one :class:`VideoCodecWarning`.
"""

from __future__ import annotations

import glob as _glob
import itertools
import logging
import math
import os
import queue
import re
import threading
import warnings
from collections.abc import Iterable, Iterator
from fractions import Fraction
from pathlib import Path

import numpy as np

from ._files import check_output_file, replace, temporary_path
from ._validation import InputError, InputTypeError, InputValueError, check_fps

__all__ = ["read_video", "open_source", "FrameSource", "write_video", "VideoWriter",
           "TruncatedInputWarning", "VideoCodecWarning",
           "parse_resize", "expand_inputs", "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS", "DEFAULT_FPS"]

log = logging.getLogger(__name__)

#: File suffixes read as still images when a folder or a glob pattern is given.
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm", ".pbm")
#: Suffixes :class:`VideoWriter` knows (.avi -> MJPG, anything else -> MP4).
VIDEO_EXTENSIONS = (".mp4", ".m4v", ".mov", ".avi", ".mkv")
#: Frame rate assumed for image sequences and for videos that do not state one.
DEFAULT_FPS = 30.0

_QUEUE_SIZE = 4


class TruncatedInputWarning(UserWarning):
    """The input stopped decoding before its stated end; results cover the frames before."""


class VideoCodecWarning(UserWarning):
    """An MP4 is written with OpenCV's ``mp4v`` instead of H.264 (PyAV missing or without libx264)."""


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------
def _natural_key(path: str):
    """Sort key: 'frame2.png' before 'frame10.png'."""
    return [int(tok) if tok.isdigit() else tok.lower() for tok in re.split(r"(\d+)", path)]


def parse_resize(text, *, name: str = "resize") -> tuple[int, int]:
    """Parse ``'WxH'`` (e.g. ``'320x240'``) or a ``(W, H)`` pair into two positive ints.

    ``name`` is the option named in the error message (the CLI passes ``--resize``).
    """
    if isinstance(text, str):
        m = re.fullmatch(r"\s*(\d+)\s*[xX×,]\s*(\d+)\s*", text)
        if not m:
            raise InputValueError(f"bad {name} {text!r}: expected WxH with positive integers, e.g. 320x240")
        w, h = int(m.group(1)), int(m.group(2))
    else:
        try:
            w, h = (int(v) for v in text)
        except (TypeError, ValueError):
            raise InputValueError(f"bad {name} {text!r}: expected (W, H) or 'WxH', e.g. 320x240") from None
    if w < 1 or h < 1:
        raise InputValueError(f"bad {name} {text!r}: width and height must be positive")
    _check_model_size(w, h, f"{name} {w}x{h}")
    return w, h


#: Largest frame (pixels) a resize or scale may ask for: 8K UHD, 7680 x 4320. The models keep
#: ~26 float32 planes per stream (~3.5 GB at this size); a typo such as 20000x20000 would
#: otherwise try to allocate tens of GB before failing.
MAX_RESIZE_PIXELS = 7680 * 4320


def _out_size(w: int, h: int, resize, scale) -> tuple[int, int]:
    """(W, H) the models see: the frame size, ``resize`` or the size times ``scale``."""
    if resize is not None and scale is not None:
        raise InputValueError("give either resize or scale, not both")
    if resize is not None:
        return parse_resize(resize)
    if scale is None:
        return int(w), int(h)
    try:
        s = float(scale)
    except (TypeError, ValueError, OverflowError):
        s = math.nan
    if isinstance(scale, bool) or not math.isfinite(s) or s <= 0:
        raise InputValueError(f"bad scale {scale!r}: expected a positive number")
    _check_model_size(w * s, h * s, f"scale {scale!r} (frames of {w * s:.0f}x{h * s:.0f})")
    return max(1, round(w * s)), max(1, round(h * s))


def _check_model_size(w: float, h: float, what: str) -> None:
    if w * h > MAX_RESIZE_PIXELS:
        raise InputValueError(f"{what} is too large: {w * h / 1e6:.0f} megapixels, at most "
                              f"{MAX_RESIZE_PIXELS / 1e6:.1f} (7680x4320)")


def _to_rgb(frame: np.ndarray) -> np.ndarray:
    """Any uint8 grey / RGB / RGBA array -> (H, W, 3) RGB uint8."""
    frame = np.asarray(frame)
    if frame.dtype != np.uint8:
        frame = np.clip(frame, 0, 255).astype(np.uint8)
    if frame.ndim == 2:
        frame = frame[:, :, None]
    if frame.ndim == 3 and frame.shape[2] == 1:
        return np.repeat(frame, 3, axis=2)
    if frame.ndim == 3 and frame.shape[2] == 4:
        return np.ascontiguousarray(frame[:, :, :3])
    if frame.ndim == 3 and frame.shape[2] == 3:
        return frame
    raise InputValueError(f"frame must be (H, W), (H, W, 3) or (H, W, 4), got shape {frame.shape}")


def is_camera(source) -> bool:
    if isinstance(source, (int, np.integer)):
        return not isinstance(source, bool)
    return isinstance(source, str) and source.strip().isdigit() and not os.path.exists(source)


# ---------------------------------------------------------------------------
# decoders: each is an iterator of RGB frames plus fps / size / count
# ---------------------------------------------------------------------------
class _Decoder:
    """Base of the per-kind decoders (all run in one thread at a time)."""

    fps: float | None = None
    size: tuple[int, int] = (0, 0)
    frame_count: int | None = None
    name: str = ""

    def skip(self, n: int) -> int:
        """Skip ``n`` frames; return how many were really skipped."""
        done = 0
        while done < n and self.grab():
            done += 1
        return done

    def grab(self) -> bool:
        """Skip one frame; False at the end."""
        return self.read() is not None

    def read(self) -> np.ndarray | None:  # pragma: no cover - abstract
        raise NotImplementedError

    def close(self) -> None:
        pass


class _OpenCVDecoder(_Decoder):
    def __init__(self, target, name: str, camera: bool = False):
        import cv2

        self._cv2 = cv2
        self.name = name
        self.cap = cv2.VideoCapture(target)
        if not self.cap.isOpened():
            self.cap.release()
            if camera:
                raise InputValueError(f"cannot open camera {target}")
            raise InputValueError(f"{name}: not a video file OpenCV can read (unknown format or damaged)")
        fps = self.cap.get(cv2.CAP_PROP_FPS)
        self.fps = float(fps) if fps and math.isfinite(fps) and 0 < fps < 1000 else None
        count = self.cap.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(count) if not camera and count and count > 0 else None
        self.size = (int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))

    def grab(self) -> bool:
        return self.cap.grab()

    def read(self):
        ok, frame = self.cap.read()
        if not ok or frame is None:
            return None
        if frame.ndim == 2:
            return self._cv2.cvtColor(frame, self._cv2.COLOR_GRAY2RGB)
        return self._cv2.cvtColor(frame, self._cv2.COLOR_BGR2RGB)

    def close(self):
        self.cap.release()


class _PyAVDecoder(_Decoder):
    def __init__(self, path: str, name: str):
        try:
            import av
        except ImportError:
            raise InputError("decoder 'pyav' needs PyAV, which is not installed: pip install av") from None
        self.name = name
        self._av = av
        try:
            self.container = av.open(path)
        except av.error.FFmpegError:
            raise InputValueError(f"{name}: not a video file PyAV can read (unknown format or damaged)") from None
        if not self.container.streams.video:
            self.container.close()
            raise InputValueError(f"{name}: has no video stream")
        stream = self.container.streams.video[0]
        stream.thread_type = "AUTO"
        rate = stream.average_rate or stream.guessed_rate
        self.fps = float(rate) if rate else None
        self.frame_count = int(stream.frames) or None
        self.size = (int(stream.codec_context.width), int(stream.codec_context.height))
        self._frames = self.container.decode(stream)

    def read(self):
        try:
            frame = next(self._frames)
        except StopIteration:
            return None
        except self._av.error.FFmpegError as exc:
            log.debug("PyAV stopped decoding %s: %s", self.name, exc)
            return None
        return frame.to_ndarray(format="rgb24")

    def close(self):
        self.container.close()


class _ImageDecoder(_Decoder):
    def __init__(self, files: list[str], name: str):
        import cv2

        self._cv2 = cv2
        self.name = name
        self.files = files
        self.frame_count = len(files)
        self._i = 0
        self.failed: str | None = None
        first = cv2.imread(files[0], cv2.IMREAD_COLOR)
        if first is None:
            raise InputValueError(f"{files[0]}: not an image OpenCV can read")
        self.size = (first.shape[1], first.shape[0])

    def skip(self, n: int) -> int:
        done = min(n, len(self.files) - self._i)
        self._i += done
        return done

    def read(self):
        if self._i >= len(self.files):
            return None
        path = self.files[self._i]
        frame = self._cv2.imread(path, self._cv2.IMREAD_COLOR)
        if frame is None:
            self.failed = f"could not decode image {path}"
            return None
        if (frame.shape[1], frame.shape[0]) != self.size:
            # Like an undecodable image: stop here, keep the outputs for the frames before.
            w0, h0 = self.size
            self.failed = f"image {path} is {frame.shape[1]}x{frame.shape[0]}, not {w0}x{h0} like the first image"
            return None
        self._i += 1
        return self._cv2.cvtColor(frame, self._cv2.COLOR_BGR2RGB)


def expand_inputs(inputs) -> list[str]:
    """Videos to process: files as given; a folder holding video files gives
    each of them (sorted); a folder of images is one image-sequence input;
    glob patterns are expanded. Missing paths raise InputValueError."""
    if isinstance(inputs, (str, Path)):
        inputs = [inputs]
    out: list[str] = []
    for item in inputs:
        s = str(item)
        p = Path(s)
        if p.is_dir():
            vids = sorted(str(q) for q in p.iterdir() if q.is_file() and q.suffix.lower() in VIDEO_EXTENSIONS)
            if vids:
                out.extend(vids)
            elif any(q.suffix.lower() in IMAGE_EXTENSIONS for q in p.iterdir() if q.is_file()):
                out.append(s)
            else:
                raise InputValueError(f"{s}: folder has neither videos nor images")
        elif p.exists():
            out.append(s)
        elif any(ch in s for ch in "*?["):
            matches = sorted(_glob.glob(s))
            if not matches:
                raise InputValueError(f"{s}: pattern matches no file")
            out.extend(matches)
        else:
            raise InputValueError(f"{s}: no such file or folder")
    first: dict[str, str] = {}  # each file once, where it first appears
    for s in out:
        first.setdefault(os.path.abspath(s), s)
    unique = list(first.values())
    if not unique:
        raise InputValueError("no input videos")
    return unique


def _image_files(source: str) -> tuple[list[str], str]:
    p = Path(source)
    if p.is_dir():
        files = [str(f) for f in p.iterdir() if f.is_file() and f.suffix.lower() in IMAGE_EXTENSIONS]
        if not files:
            videos = any(f.suffix.lower() in VIDEO_EXTENSIONS for f in p.iterdir())
            hint = "; it holds videos: run them all with `mlplc2 batch`" if videos else ""
            raise InputValueError(
                f"{source}: directory has no images ({', '.join(e[1:] for e in IMAGE_EXTENSIONS[:5])}, ...)"
                + hint)
        return sorted(files, key=_natural_key), str(p)
    files = [f for f in _glob.glob(source) if os.path.isfile(f)]
    if not files:
        raise InputValueError(f"{source}: no files match this pattern")
    images = [f for f in files if Path(f).suffix.lower() in IMAGE_EXTENSIONS]
    if not images:
        raise InputValueError(f"{source}: the files matching this pattern are not images")
    return sorted(images, key=_natural_key), source


def _open_decoder(source, decoder: str) -> tuple[_Decoder, str]:
    """Return (decoder, kind) with kind in {'video', 'images', 'camera'}."""
    if decoder not in ("opencv", "pyav"):
        raise InputValueError(f"unknown decoder {decoder!r}; choose 'opencv' or 'pyav'")
    if is_camera(source):
        index = int(source)
        return _OpenCVDecoder(index, f"camera {index}", camera=True), "camera"
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str):
        shape = getattr(source, "shape", None)
        what = type(source).__name__ + (f" of shape {tuple(shape)}" if shape is not None else "")
        hint = ("; to run on frames in memory, step the model: model.run(frames)"
                if shape is not None or hasattr(source, "frames") else "")
        raise InputTypeError(f"source must be a path, a glob pattern or a camera index, got a {what}{hint}")
    if os.path.isdir(source):
        files, name = _image_files(source)
        return _ImageDecoder(files, name), "images"
    if os.path.isfile(source):
        if Path(source).suffix.lower() in IMAGE_EXTENSIONS:
            return _ImageDecoder([source], source), "images"
        if decoder == "pyav":
            return _PyAVDecoder(source, source), "video"
        return _OpenCVDecoder(source, source), "video"
    if any(ch in source for ch in "*?["):
        files, name = _image_files(source)
        return _ImageDecoder(files, name), "images"
    raise InputValueError(f"{source}: no such file or directory")


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
    truncated : bool
        True when decoding stopped before the stated end (damaged or cut file);
        :attr:`message` then names the frame where it stopped.
    """

    def __init__(self, decoder: _Decoder, kind: str, *, fps=None, start: int = 0, end: int | None = None,
                 resize=None, scale=None, keep_original: bool = False, queue_size: int = _QUEUE_SIZE):
        self._dec = decoder
        self.kind = kind
        self.name = decoder.name
        self.fps = check_fps(fps) if fps is not None else (decoder.fps or DEFAULT_FPS)
        self.start = int(start)
        self.end = None if end is None else int(end)
        self.keep_original = keep_original
        self.frame_count = decoder.frame_count
        self.truncated = False
        self.truncated_at: int | None = None
        self.message: str | None = None
        self.n_read = 0
        # First frame read now, in the caller's thread, so that empty or
        # undecodable inputs fail at open time with a clear message.
        skipped = decoder.skip(self.start) if self.start else 0
        if skipped < self.start:
            decoder.close()
            raise InputValueError(f"{self.name}: start frame {self.start} is past the end ({skipped} frames)")
        first = decoder.read() if (self.end is None or self.end > self.start) else None
        if first is None:
            decoder.close()
            if self.end is not None and self.end <= self.start:
                raise InputValueError(f"end ({self.end}) must be larger than start ({self.start})")
            if self.start:
                raise InputValueError(f"{self.name}: no frame at or after start frame {self.start}")
            raise InputValueError(f"{self.name}: video has no frames (empty or undecodable)")
        h, w = first.shape[:2]
        self.size = (int(w), int(h))
        try:
            self.out_size = _out_size(w, h, resize, scale)
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
        self._queue: queue.Queue = queue.Queue(maxsize=queue_size)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._iterated = False

    # -- mapping --------------------------------------------------------------
    @property
    def resized(self) -> bool:
        return self.out_size != self.size

    def to_input(self, x: float, y: float) -> tuple[float, float]:
        """Map a point from model (resized) pixels to input pixels:
        ``(x * W_in / W_out, y * H_in / H_out)``."""
        return x * self.scale_x, y * self.scale_y

    # -- decoding thread ------------------------------------------------------
    def _prepare(self, frame: np.ndarray):
        if self.resized:
            import cv2

            small = cv2.resize(frame, self.out_size, interpolation=cv2.INTER_AREA)
        else:
            small = frame
        return (small, frame) if self.keep_original else (small,)

    def _put(self, item) -> bool:
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _work(self) -> None:
        dec = self._dec
        index = self.start
        try:
            frame = self._first
            self._first = None
            while frame is not None:
                if not self._put(("frame", index, self._prepare(frame))):
                    return
                index += 1
                if self.end is not None and index >= self.end:
                    break
                frame = dec.read()
            self._put(("end", index, None))
        except BaseException as exc:  # noqa: BLE001 - handed to the consumer thread
            self._put(("error", index, exc))
        finally:
            dec.close()

    def __iter__(self) -> Iterator[tuple]:
        if self._iterated:
            raise RuntimeError("a FrameSource can be iterated only once")
        self._iterated = True
        self._thread = threading.Thread(target=self._work, name="mlplc2-decode", daemon=True)
        self._thread.start()
        try:
            while True:
                kind, index, payload = self._queue.get()
                if kind == "frame":
                    self.n_read += 1
                    yield (index, *payload)
                elif kind == "end":
                    self._check_end(index)
                    return
                else:
                    raise payload
        finally:
            self.close()

    def _check_end(self, index: int) -> None:
        """Decide whether the stream stopped early (index = first frame not decoded)."""
        expected = self.frame_count if self.end is None else (
            min(self.end, self.frame_count) if self.frame_count is not None else None)
        failed_image = getattr(self._dec, "failed", None)
        if failed_image is not None:
            self.truncated, self.truncated_at = True, index
            self.message = f"{self.name}: {failed_image} (frame {index}); stopped there"
        elif self.kind == "video" and expected is not None and index < expected:
            self.truncated, self.truncated_at = True, index
            self.message = (f"{self.name}: decoding stopped at frame {index} of {expected} "
                            "(file truncated or damaged); results cover frames before it")

    def close(self) -> None:
        """Stop the decoding thread and release the input (idempotent)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            while self._thread.is_alive():
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
                keep_original: bool = False, decoder: str = "opencv") -> FrameSource:
    """Open a video file, a folder of images, a glob pattern or a camera for streaming.

    Parameters
    ----------
    source : str, path-like or int
        A video file (anything OpenCV/FFmpeg reads: AVI, MP4, ...), a folder
        of images or a glob pattern such as ``'frames/*.png'`` (sorted
        naturally: ``2.png`` before ``10.png``), or a camera index (an int or
        a string of digits that is not an existing path).
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
        Video decoder.

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
    reader, kind = _open_decoder(source, decoder)
    return FrameSource(reader, kind, fps=fps, start=start, end=end, resize=resize, scale=scale,
                       keep_original=keep_original)


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


# ---------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------
def _h264_unavailable() -> str | None:
    """Why PyAV cannot encode H.264 here (None: it can)."""
    try:
        import av
    except ImportError:
        return "PyAV is not installed (pip install av)"
    try:
        av.codec.Codec("libx264", "w")
    except Exception as exc:  # noqa: BLE001 - UnknownCodecError, or an FFmpeg build without it
        return f"PyAV's FFmpeg has no H.264 encoder ({type(exc).__name__}: {exc})"
    return None


#: Suffixes :class:`VideoWriter` writes: MP4 (H.264) and AVI (MJPG).
VIDEO_SUFFIXES_OUT = (".mp4", ".avi")


class VideoWriter:
    """Write RGB frames to ``path`` one at a time; the file appears only on :meth:`close`.

    ``.avi`` -> MJPG (OpenCV). ``.mp4`` -> MP4 H.264 (``libx264``,
    ``yuv420p``, moov atom first so a cut file still plays) via PyAV. Where PyAV
    is missing or cannot encode H.264, OpenCV ``mp4v`` instead, with a
    :class:`VideoCodecWarning` that says so. H.264 needs even dimensions: odd
    ones are padded by one black row/column on the bottom/right.

    Frames go to a hidden temporary name in the same folder, renamed to
    ``path`` when :meth:`close` succeeds; :meth:`abort` deletes it instead.
    """

    def __init__(self, path, fps: float, size: tuple[int, int], *, encoder: str | None = None,
                 quality: int = 23):
        self.path = Path(path)
        self.fps = check_fps(fps)
        w, h = (int(v) for v in size)
        if w < 1 or h < 1:
            raise InputValueError(f"bad video size {size!r}")
        self.size = (w, h)
        check_video_output(self.path)
        suffix = self.path.suffix.lower()
        self.codec = "mjpg" if suffix == ".avi" else "h264"
        if encoder is None:
            encoder = "opencv"
            if self.codec == "h264":
                why = _h264_unavailable()
                if why is None:
                    encoder = "pyav"
                else:
                    warnings.warn(f"{self.path.name}: written as MP4 'mp4v' by OpenCV, which browsers do not "
                                  f"play, not H.264: {why}", VideoCodecWarning, stacklevel=3)
        self.encoder = encoder
        if encoder not in ("pyav", "opencv"):
            raise InputValueError(f"unknown encoder {encoder!r}; choose 'opencv' or 'pyav'")
        self.tmp = temporary_path(self.path)
        self.n_frames = 0
        self._closed = False
        try:
            self._open(quality)
        except BaseException:
            self._remove_tmp()
            raise

    def _open(self, quality) -> None:
        w, h = self.size
        if self.encoder == "pyav":
            import av

            self.enc_size = (w + w % 2, h + h % 2)
            self._container = av.open(str(self.tmp), "w", format="mp4",
                                      options={"movflags": "+faststart"})
            self._stream = self._container.add_stream("libx264", rate=Fraction(self.fps).limit_denominator(1001))
            self._stream.width, self._stream.height = self.enc_size
            self._stream.pix_fmt = "yuv420p"
            self._stream.options = {"crf": str(quality), "preset": "veryfast"}
        else:
            import cv2

            self._cv2 = cv2
            self.enc_size = (w, h)
            fourccs = ("MJPG",) if self.codec == "mjpg" else ("mp4v", "avc1")
            self._writer = None
            for code in fourccs:
                wr = cv2.VideoWriter(str(self.tmp), cv2.VideoWriter_fourcc(*code), self.fps, self.enc_size)
                if wr.isOpened():
                    self._writer = wr
                    break
                wr.release()
            if self._writer is None:
                raise OSError(f"{self.path}: OpenCV cannot open a video writer ({'/'.join(fourccs)})")

    def write(self, frame: np.ndarray) -> None:
        """Append one frame: (H, W) grey or (H, W, 3) RGB uint8 at :attr:`size`."""
        rgb = _to_rgb(frame)
        h, w = rgb.shape[:2]
        if (w, h) != self.size:
            raise InputValueError(f"frame is {w}x{h} but the video is {self.size[0]}x{self.size[1]}")
        ew, eh = self.enc_size
        if (ew, eh) != (w, h):
            rgb = np.pad(rgb, ((0, eh - h), (0, ew - w), (0, 0)))
        if self.encoder == "pyav":
            import av

            vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
            for packet in self._stream.encode(vf):
                self._container.mux(packet)
        else:
            self._writer.write(self._cv2.cvtColor(rgb, self._cv2.COLOR_RGB2BGR))
        self.n_frames += 1

    def close(self) -> Path:
        """Finish the file and move it to its final name; returns the path."""
        if self._closed:
            return self.path
        self._closed = True
        try:
            if self.encoder == "pyav":
                for packet in self._stream.encode():
                    self._container.mux(packet)
                self._container.close()
            else:
                self._writer.release()
        except BaseException:
            self._remove_tmp()
            raise
        if self.n_frames == 0 or not self.tmp.exists():
            self._remove_tmp()
            raise InputValueError(f"{self.path}: no frames to write")
        replace(self.tmp, self.path)
        return self.path

    def abort(self) -> None:
        """Stop and delete the temporary file; nothing appears at ``path``."""
        if self._closed:
            return
        self._closed = True
        try:
            if self.encoder == "pyav":
                self._container.close()
            else:
                self._writer.release()
        except Exception:  # noqa: BLE001 - best effort while giving up
            pass
        self._remove_tmp()

    def _remove_tmp(self) -> None:
        try:
            self.tmp.unlink()
        except FileNotFoundError:
            pass

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def write_video(path, frames: Iterable[np.ndarray], fps: float, size: tuple[int, int] | None = None, *,
                encoder: str | None = None, quality: int = 23) -> Path:
    """Write ``frames`` (grey or RGB uint8) to ``path`` atomically; see :class:`VideoWriter`
    (``quality``: the H.264 CRF, lower is closer to lossless).

    ``size`` is ``(W, H)``; if omitted it is taken from the first frame.
    Returns the path written.
    """
    it = iter(frames)
    if size is None:
        try:
            first = next(it)
        except StopIteration:
            raise InputValueError(f"{path}: no frames to write") from None
        size = (first.shape[1], first.shape[0])
        it = itertools.chain([first], it)
    with VideoWriter(path, fps, size, encoder=encoder, quality=quality) as writer:
        for frame in it:
            writer.write(frame)
    return writer.path


def check_video_output(path) -> Path:
    """Return ``path`` as a Path, or raise unless it can name a video :class:`VideoWriter` writes."""
    path = check_output_file(path, what="video")
    if path.suffix.lower() not in VIDEO_SUFFIXES_OUT:
        raise InputValueError(f"{path}: cannot write {path.suffix or 'a file without a suffix'}; "
                              f"name the video .mp4 (H.264) or .avi (MJPG)")
    return path
