"""What :mod:`mlplc2.io` reads and writes: file suffixes, the frame format, sizes.

Frames are always RGB ``uint8`` arrays of shape ``(H, W, 3)`` (:func:`to_rgb`). Sizes are
given as ``(W, H)`` (OpenCV convention), shapes as ``(H, W)`` (numpy convention);
:func:`parse_resize` and :func:`output_size` give the size the models see.
"""

from __future__ import annotations

import math
import os
import re

import numpy as np

from .._validation import InputValueError

#: File suffixes read as still images when a folder or a glob pattern is given.
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm", ".pbm")
#: Suffixes :class:`VideoWriter` knows (.avi -> MJPG, anything else -> MP4).
VIDEO_EXTENSIONS = (".mp4", ".m4v", ".mov", ".avi", ".mkv")
#: Frame rate assumed for image sequences and for videos that do not state one.
DEFAULT_FPS = 30.0

def mp4_without_index(path) -> bool:
    """Whether ``path`` is an MP4/MOV file (an ``ftyp`` box first) whose top-level boxes hold no
    ``moov``, the index: a file whose index was to come at its end, cut off before it (a copy or a
    recording that stopped). FFmpeg and OpenCV cannot open such a file at all. False for anything
    else, and for a file that cannot be read."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            at, first = 0, True
            while at + 8 <= size:
                f.seek(at)
                head = f.read(16)
                box, kind = int.from_bytes(head[:4], "big"), head[4:8]
                if first and kind != b"ftyp":
                    return False
                if kind == b"moov":
                    return False
                if box == 1 and len(head) == 16:     # a 64-bit size
                    box = int.from_bytes(head[8:16], "big")
                elif box == 0:                       # to the end of the file
                    box = size - at
                if box < 8:
                    return not first                 # not a box: past the boxes an ftyp began
                at, first = at + box, False
            return not first
    except (OSError, TypeError, ValueError):
        return False


class TruncatedInputWarning(UserWarning):
    """The input stopped decoding before its stated end; results cover the frames before."""


class VideoCodecWarning(UserWarning):
    """An MP4 is written with OpenCV's ``mp4v`` instead of H.264 (PyAV missing or without libx264)."""


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


def output_size(w: int, h: int, resize, scale) -> tuple[int, int]:
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


def to_rgb(frame: np.ndarray) -> np.ndarray:
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


#: The frame count FFmpeg's AVI muxer states when it cannot go back to write the real one: an AVI
#: written to a pipe (``ffmpeg -f v4l2 -i /dev/video0 -f avi -``, a camera tool's ``--output -``),
#: or a file saved from one (``... | tee rec.avi``). A count this large or larger (414 days at
#: 30 frames/s) is no count (:func:`stated_count`): read as one it made a live camera's first
#: JSON line wait for the read-ahead of the repeated-frame check (``FrameSource.peek``: 60 frames,
#: 2 s), and its end a "decoding stopped at frame N of 1073741824" truncation (exit 2).
AVI_UNKNOWN_COUNT = 1 << 30


def stated_count(count) -> int | None:
    """A container's frame count as :attr:`Decoder.frame_count` takes it: None when it states none
    (0, negative, not a number) or FFmpeg's placeholder for an unknown one (:data:`AVI_UNKNOWN_COUNT`)."""
    try:
        n = int(count)
    except (TypeError, ValueError, OverflowError):
        return None
    return n if 0 < n < AVI_UNKNOWN_COUNT else None


#: The source that means standard input (``mlplc2 run -``).
STDIN = "-"
#: URL schemes of live streams: frames arrive in real time, so a run that falls behind takes the
#: newest frame and skips the others (``open_source(live=None)``). HTTP(S) is not among them (it
#: serves files as often as cameras): give ``live=True`` (``--live``) for an HTTP camera.
LIVE_SCHEMES = ("rtsp", "rtsps", "rtmp", "rtmps", "rtp", "srt", "udp", "tcp")


def is_url(source) -> bool:
    """Whether ``source`` is a URL (``scheme://...``, e.g. ``rtsp://``, ``http://``) and not an existing path."""
    return (isinstance(source, str) and re.match(r"[A-Za-z][A-Za-z0-9+.-]*://", source) is not None
            and not os.path.exists(source))


def without_password(source):
    """``source`` as messages and ``fields.json`` name it: a URL's password replaced by ``***``
    (``rtsp://admin:secret@cam/s`` -> ``rtsp://admin:***@cam/s``; the decoder is given the URL as is),
    anything else unchanged."""
    if not is_url(source):
        return source
    scheme, rest = source.split("://", 1)
    netloc = re.split(r"[/?#]", rest, maxsplit=1)[0]
    if "@" not in netloc or ":" not in netloc.rsplit("@", 1)[0]:
        return source
    userinfo, host = netloc.rsplit("@", 1)
    return f"{scheme}://{userinfo.split(':', 1)[0]}:***@{host}{rest[len(netloc):]}"


def is_live(source) -> bool:
    """Whether ``source`` is live by default: a camera or a URL of :data:`LIVE_SCHEMES`."""
    return is_camera(source) or (is_url(source) and source.split(":", 1)[0].lower() in LIVE_SCHEMES)


def is_camera(source) -> bool:
    if isinstance(source, (int, np.integer)):
        return not isinstance(source, bool)
    return isinstance(source, str) and source.strip().isdigit() and not os.path.exists(source)

