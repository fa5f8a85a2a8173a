"""Writing videos: :class:`VideoWriter` (one frame at a time) and :func:`write_video` write MP4
(H.264 via PyAV; OpenCV ``mp4v`` with a :class:`VideoCodecWarning` where PyAV cannot) or AVI
(MJPG) atomically: the file appears under its name only when complete.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Iterable
from fractions import Fraction
from pathlib import Path

import numpy as np

from .._files import check_output_file, replace, temporary_path
from .._validation import InputValueError, check_fps
from .formats import VideoCodecWarning, to_rgb

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
        rgb = to_rgb(frame)
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


def write_lossless_video(path, frames: Iterable[np.ndarray], fps: float) -> Path:
    """Write grey ``uint8 (H, W)`` ``frames`` losslessly (FFV1 in Matroska, ``.mkv``, via PyAV) to
    ``path`` atomically. The muxer and encoder run ``bitexact`` (no random segment id, no
    version strings), so the same frames give the same bytes. Returns the path written."""
    import av

    path = Path(path)
    if path.suffix.lower() != ".mkv":
        raise InputValueError(f"{path}: a lossless video is written as .mkv (FFV1)")
    tmp = temporary_path(path)
    n = 0
    try:
        with av.open(str(tmp), "w", format="matroska", options={"fflags": "+bitexact"}) as container:
            stream = container.add_stream("ffv1", rate=Fraction(check_fps(fps)).limit_denominator(1001))
            stream.pix_fmt = "gray"
            stream.codec_context.options = {"flags": "+bitexact"}
            for frame in frames:
                if n == 0:
                    stream.height, stream.width = frame.shape[:2]
                for packet in stream.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(frame, np.uint8),
                                                                       format="gray")):
                    container.mux(packet)
                n += 1
            if n == 0:
                raise InputValueError(f"{path}: no frames to write")
            for packet in stream.encode():
                container.mux(packet)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    replace(tmp, path)
    return path


def check_video_output(path) -> Path:
    """Return ``path`` as a Path, or raise unless it can name a video :class:`VideoWriter` writes."""
    path = check_output_file(path, what="video")
    if path.suffix.lower() not in VIDEO_SUFFIXES_OUT:
        raise InputValueError(f"{path}: cannot write {path.suffix or 'a file without a suffix'}; "
                              f"name the video .mp4 (H.264) or .avi (MJPG)")
    return path
