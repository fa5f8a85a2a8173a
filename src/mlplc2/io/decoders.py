"""Decoders: one per kind of input (a video by OpenCV or PyAV, a sequence of images, a camera),
each an iterator of RGB frames with its fps, size and frame count; :func:`open_decoder` picks
one for a source, :func:`expand_inputs` lists the inputs of a batch.
"""

from __future__ import annotations

import glob as _glob
import logging
import math
import os
import re
import stat
import sys
import time
from pathlib import Path

import numpy as np

from .._validation import InputError, InputTypeError, InputValueError
from .formats import (IMAGE_EXTENSIONS, STDIN, VIDEO_EXTENSIONS, is_camera, is_live, is_url, mp4_without_index,
                      stated_count, without_password)

log = logging.getLogger(__name__)

#: Consecutive packets that cannot be decoded (damaged) that PyAV skips before a video counts as
#: ending there: a damaged frame in the middle of a file or a stream is skipped, not the end of the run.
MAX_DAMAGED = 30


def _natural_key(path: str):
    """Sort key: 'frame2.png' before 'frame10.png'."""
    return [int(tok) if tok.isdigit() else tok.lower() for tok in re.split(r"(\d+)", path)]



# ---------------------------------------------------------------------------
# decoders: each is an iterator of RGB frames plus fps / size / count
# ---------------------------------------------------------------------------
class Decoder:
    """Base of the per-kind decoders (all run in one thread at a time)."""

    #: The container's timestamp (s) of the frame :meth:`read` returned last, None without one.
    time_s: float | None = None
    #: The container's timestamp (s) of its first frame (read or skipped), None where not known.
    start_s: float | None = None
    #: Frames skipped just before the frame :meth:`read` returned last: damaged ones (a packet
    #: that could not be decoded) and those predicted from them, up to the next key frame (PyAV).
    gap: int = 0
    #: Whether a damaged frame is skipped (PyAV) rather than the end of the video (OpenCV).
    skips_damaged: bool = False

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


class _OpenCVDecoder(Decoder):
    def __init__(self, target, name: str, camera: bool = False):
        import cv2

        self._cv2 = cv2
        self.name = name
        self._camera = camera
        #: Set when a camera stops delivering frames (a file simply ends).
        self.error: str | None = None
        #: After the first failed read of a file: whether frames still decode after it (True: a damaged
        #: frame in the middle, which --decoder pyav skips; False: the file ends there, cut or not).
        self.goes_on: bool | None = None
        self.cap = cv2.VideoCapture(target)
        if not self.cap.isOpened():
            self.cap.release()
            if camera:
                found = sorted(_glob.glob("/dev/video*")) if sys.platform.startswith("linux") else None
                where = ("" if found is None else f" (cameras here: {', '.join(found)})" if found
                         else " (no camera here: no /dev/video*)")
                raise InputValueError(f"cannot open camera {target}: none at that index, or another program "
                                      f"holds it{where}")
            raise InputValueError(_not_a_video(target, name, "OpenCV"))
        fps = self.cap.get(cv2.CAP_PROP_FPS)
        self.fps = float(fps) if fps and math.isfinite(fps) and 0 < fps < 1000 else None
        self.frame_count = None if camera else stated_count(self.cap.get(cv2.CAP_PROP_FRAME_COUNT))
        self.size = (int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))

    def grab(self) -> bool:
        if not self.cap.grab():
            return False
        self._started()
        return True

    def _started(self) -> None:
        if self.start_s is None and not self._camera:
            ms = self.cap.get(self._cv2.CAP_PROP_POS_MSEC)
            self.start_s = ms / 1000.0 if ms is not None and math.isfinite(ms) and ms >= 0 else None

    def read(self):
        # A damaged frame ends the file here: OpenCV's reads after one give earlier frames' pictures
        # (its decoding threads' old buffers; measured on FFV1), so it cannot be skipped (PyAV can).
        ok, frame = self.cap.read()
        if not ok or frame is None:
            if self._camera:
                self.error = "the camera delivered no frame"
            elif self.goes_on is None:   # a damaged frame, or the end (of the file, or of what is left of it)?
                self.goes_on = any(self.cap.grab() for _ in range(3))
            return None
        self._started()
        ms = self.cap.get(self._cv2.CAP_PROP_POS_MSEC)
        self.time_s = ms / 1000.0 if ms is not None and math.isfinite(ms) and ms >= 0 else None
        if frame.ndim == 2:
            return self._cv2.cvtColor(frame, self._cv2.COLOR_GRAY2RGB)
        return self._cv2.cvtColor(frame, self._cv2.COLOR_BGR2RGB)

    def close(self):
        self.cap.release()


def _not_a_video(path, name: str, decoder: str) -> str:
    """The error for a file that ``decoder`` cannot open; it says so when it is an MP4/MOV whose index
    (moov atom, written at the end) was cut off (:func:`~mlplc2.io.formats.mp4_without_index`)."""
    if isinstance(path, (str, os.PathLike)) and mp4_without_index(path):
        return (f"{name}: an MP4/MOV file without its index (moov atom): it was cut off before its end "
                f"(an unfinished recording or copy), and such a file cannot be decoded at all")
    return f"{name}: not a video file {decoder} can read (unknown format or damaged)"


def _unknown_host(url) -> str | None:
    """Why a URL did not open when its host name does not resolve (a typo, no network):
    ``host 'NAME' not found``; None otherwise. FFmpeg says only "Input/output error" then."""
    import socket
    from urllib.parse import urlsplit

    try:
        host = urlsplit(str(url)).hostname
    except ValueError:
        return None
    if not host:
        return None
    try:
        socket.getaddrinfo(host, None)
    except socket.gaierror:
        return f"host {host!r} not found"
    except (OSError, UnicodeError):
        return None
    return None


class _PyAVDecoder(Decoder):
    """A video file, a URL (``stream=True``) or a binary file object (stdin) decoded by PyAV."""

    skips_damaged = True

    #: Seconds PyAV waits to open a URL or for its next packet before the stream counts as dropped.
    TIMEOUT_S = 10.0

    def __init__(self, path, name: str, stream: bool = False):
        try:
            import av
        except ImportError:
            raise InputError("decoder 'pyav' needs PyAV, which is not installed: pip install av") from None
        self.name = name
        self._av = av
        self._source = path
        #: Why decoding of a stream stopped early (an FFmpeg error), None at a clean end.
        self.error: str | None = None
        # A real-time stream (RTSP, ...: a camera) has no end of its own: its end is the stream
        # stopping (FFmpeg reports a closed connection or an RTCP BYE as the end of the input).
        self._realtime = stream and is_live(path)
        self._pipe = hasattr(path, "read")   # a file object (stdin): FFmpeg cannot seek back in it
        # An HTTP server that ignores range requests cannot seek either (a file served whole, in order).
        self._http = not self._pipe and str(path).lower().startswith(("http:", "https:"))
        self._decoded = 0
        options = {"rtsp_transport": "tcp"} if str(path).lower().startswith("rtsp") else None
        began = time.monotonic()
        try:
            self.container = av.open(path, mode="r", options=options, timeout=self.TIMEOUT_S if stream else None)
        except (av.error.FFmpegError, OSError) as exc:
            if stream:
                # FFmpeg names a server that never answers "Immediate exit requested" or "Invalid data"
                # FFmpeg's own words, without PyAV's "[Errno -875574520] ...: 'URL'" around them
                why = (f"no answer within {self.TIMEOUT_S:g} s" if time.monotonic() - began >= self.TIMEOUT_S
                       else _unknown_host(path) or _one_line(getattr(exc, "strerror", None) or str(exc)))
                if why.startswith("Invalid data found"):   # an answer, but not a video (a text file, a web page)
                    why += ": what came is not a video FFmpeg can read"
                raise InputValueError(f"{name}: cannot open the stream ({why})") from None
            raise InputValueError(_not_a_video(path, name, "PyAV")) from None
        if not self.container.streams.video:
            self.container.close()
            raise InputValueError(f"{name}: has no video stream")
        stream = self.container.streams.video[0]
        stream.thread_type = "AUTO"
        rate = stream.average_rate or stream.guessed_rate
        self.fps = float(rate) if rate else None
        self.frame_count = stated_count(stream.frames)
        self.size = (int(stream.codec_context.width), int(stream.codec_context.height))
        self._frames = self._decode(stream)

    def _decode(self, stream):
        """The stream's frames, packet by packet. A packet that cannot be decoded (damaged) is
        skipped, and so are the frames decoded after it up to the next key frame (they are
        predicted from the damaged one: an FFV1 frame's coder state, an H.264 P-frame's picture;
        measured on FFV1, they come out as garbage without an error); all are counted in
        :attr:`gap`. More than :data:`MAX_DAMAGED` undecodable packets in a row end the video."""
        gap, bad, waiting = 0, 0, False
        for packet in self.container.demux(stream):
            try:
                frames = packet.decode()
            except self._av.error.InvalidDataError:
                if bad >= MAX_DAMAGED:
                    raise
                gap, bad, waiting = gap + 1, bad + 1, True
                continue
            bad = 0
            for frame in frames:
                if waiting and not frame.key_frame:
                    gap += 1
                    continue
                self.gap, gap, waiting = gap, 0, False
                yield frame

    def read(self):
        self.gap = 0
        try:
            frame = next(self._frames)
        except StopIteration:
            if self._realtime:
                self.error = "the server ended it"
            return None
        except (self._av.error.FFmpegError, OSError) as exc:
            log.debug("PyAV stopped decoding %s: %s", self.name, exc)
            # FFmpeg's own words, without PyAV's "[Errno 5] ...: 'URL'" around them (the URL, its password too)
            self.error = _one_line(getattr(exc, "strerror", None) or str(exc))
            if not self._decoded and "mp4" in self.container.format.name:
                if self._pipe:
                    self.error = ("an MP4/MOV file whose index (moov atom) is at its end cannot be read from a "
                                  "pipe: give its path instead")
                elif self._http:
                    self.error = ("an MP4/MOV file whose index (moov atom) is at its end needs a server that "
                                  "answers range requests (Python's http.server does not): serve it from one "
                                  "that does, or give its path")
            return None
        self._decoded += 1
        self.time_s = None if frame.time is None else float(frame.time)
        return frame.to_ndarray(format="rgb24")

    def close(self):
        self.container.close()
        if isinstance(self._source, _Pipe):
            self._source.close()


class _Pipe:
    """Standard input as FFmpeg reads it: each ``read(n)`` returns what has arrived (up to ``n`` bytes),
    waiting only when nothing has. ``sys.stdin.buffer.read(n)`` waits for all ``n`` bytes (FFmpeg asks for
    32 KB, several frames of a camera's stream), so frames came in bursts, and those sent before the
    camera stalled came only after it. Reads go to a raw duplicate of the descriptor, so that a read
    left waiting at exit (the decoding thread, on a stalled pipe) holds no lock of ``sys.stdin``'s."""

    def __init__(self, buffer):
        peek = getattr(buffer, "peek", None)
        # peek waits for the first bytes; read1 takes only those already buffered
        self._head = buffer.read1(len(peek(1))) if peek is not None else b""
        self.empty = peek is not None and not self._head
        try:
            self._raw, self._own = open(os.dup(buffer.fileno()), "rb", buffering=0), True
        except (AttributeError, OSError, ValueError):   # not a descriptor (a test's BytesIO): read it as it is
            self._raw, self._own = buffer, False

    def read(self, n: int = -1) -> bytes:
        if self._head:
            n = len(self._head) if n is None or n < 0 else n
            out, self._head = self._head[:n], self._head[n:]
            return out
        return self._raw.read(n)

    def close(self) -> None:
        if self._own:
            self._raw.close()


class _ImageDecoder(Decoder):
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
        if [Path(f).name for f in files] == ["responses.png"] and (p / "fields.json").is_file():
            raise InputValueError(f"{source}: an output folder of `mlplc2 run` (fields.json, responses.png), "
                                  f"not a folder of frames: run the video it came from (\"video\" in its "
                                  f"fields.json), or score it with `mlplc2 evaluate`")
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
        videos = any(Path(f).suffix.lower() in VIDEO_EXTENSIONS for f in files)
        hint = " (they are videos: run them all with `mlplc2 batch`, or one at a time)" if videos else ""
        raise InputValueError(f"{source}: the files matching this pattern are not images{hint}")
    return sorted(images, key=_natural_key), source


def _is_fifo(path: str) -> bool:
    try:
        return stat.S_ISFIFO(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def _one_line(text: str) -> str:
    return " ".join(str(text).split()) or "unknown error"


def open_decoder(source, decoder: str) -> tuple[Decoder, str]:
    """Return (decoder, kind) with kind in {'video', 'images', 'camera', 'stream'}.

    A URL (:func:`~.formats.is_url`: RTSP, HTTP(S), ...) and ``'-'`` (standard input, any
    container FFmpeg reads from a pipe) are streams, always decoded by PyAV."""
    if decoder not in ("opencv", "pyav"):
        raise InputValueError(f"unknown decoder {decoder!r}; choose 'opencv' or 'pyav'")
    if is_camera(source):
        index = int(source)
        return _OpenCVDecoder(index, f"camera {index}", camera=True), "camera"
    if isinstance(source, str) and source == STDIN:
        if sys.stdin.isatty():  # nothing piped in: FFmpeg would wait for the keyboard
            raise InputValueError("stdin: standard input is a terminal, not a video: pipe one in "
                                  "(cat clip.mkv | mlplc2 run -)")
        pipe = _Pipe(sys.stdin.buffer)
        if pipe.empty:   # FFmpeg would say "Invalid data found when processing input"
            raise InputValueError("stdin: standard input is empty: no video was piped in")
        return _PyAVDecoder(pipe, "stdin", stream=True), "stream"
    if is_url(source):
        return _PyAVDecoder(source, without_password(source), stream=True), "stream"
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str):
        shape = getattr(source, "shape", None)
        what = type(source).__name__ + (f" of shape {tuple(shape)}" if shape is not None else "")
        hint = ("; to run on frames in memory, step the model: model.run(frames)"
                if shape is not None or hasattr(source, "frames") else "")
        raise InputTypeError(f"source must be a path, a URL, '-', a glob pattern or a camera index, got a {what}{hint}")
    if os.path.isdir(source):
        files, name = _image_files(source)
        return _ImageDecoder(files, name), "images"
    if os.path.isfile(source):
        if os.path.getsize(source) == 0:   # the decoders would call it an unknown format
            raise InputValueError(f"{source}: empty file (0 bytes)")
        if Path(source).suffix.lower() in IMAGE_EXTENSIONS:
            return _ImageDecoder([source], source), "images"
        if decoder == "pyav":
            return _PyAVDecoder(source, source), "video"
        return _OpenCVDecoder(source, source), "video"
    if _is_fifo(source):   # a named pipe (mkfifo) a camera tool writes into: read as stdin is
        return _PyAVDecoder(_Pipe(open(source, "rb")), source, stream=True), "stream"
    if any(ch in source for ch in "*?["):
        files, name = _image_files(source)
        return _ImageDecoder(files, name), "images"
    named = Path(source).suffix.lower() in VIDEO_EXTENSIONS + IMAGE_EXTENSIONS   # a file's name: no hint on streams
    raise InputValueError(f"{source}: no such file or directory" + ("" if named else
                          " (a stream: a URL such as rtsp://HOST/PATH or http://HOST/PATH, or - for standard input)"))

