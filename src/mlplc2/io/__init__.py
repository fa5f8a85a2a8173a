"""Video input and output: a minimal reader, a streaming frame source, a writer.

* :func:`read_video` decodes a whole video into memory (for short clips).
* :func:`open_source` streams frames one at a time from a video file, a folder
  of images, a glob pattern, a camera, a URL (RTSP, HTTP(S), ...) or standard input
  (``'-'``), decoding in a background thread so decoding and the model overlap; memory
  does not depend on the video length. A live source (a camera, RTSP) keeps only the
  newest frame when its consumer falls behind, counting the ones skipped.
* :func:`write_video` / :class:`VideoWriter` write MP4 (H.264 via PyAV) or AVI
  (MJPG) atomically.

The modules: :mod:`.formats` (suffixes, the frame format, sizes), :mod:`.decoders` (one per
kind of input; :func:`expand_inputs`), :mod:`.source` (:class:`FrameSource`, :func:`open_source`,
:func:`read_video`), :mod:`.writer` (:class:`VideoWriter`, :func:`write_video`, :func:`write_lossless_video`: FFV1 .mkv).

Frames are always RGB ``uint8`` arrays of shape ``(H, W, 3)``. Sizes are given
as ``(W, H)`` (OpenCV convention), shapes as ``(H, W)`` (numpy convention).

OpenCV is the default decoder. PyAV, also a core dependency, decodes on request
(``decoder="pyav"``) and encodes every MP4 as H.264, which browsers play. Where PyAV is
missing or its FFmpeg has no H.264 encoder, MP4 files are written by OpenCV
(``mp4v``, which browsers do not play), with one :class:`VideoCodecWarning`.
"""

from __future__ import annotations

from .decoders import expand_inputs
from .formats import (DEFAULT_FPS, IMAGE_EXTENSIONS, VIDEO_EXTENSIONS, TruncatedInputWarning, VideoCodecWarning,
                      is_camera, parse_resize)
from .source import FrameSource, open_source, read_video
from .writer import VideoWriter, check_video_output, write_lossless_video, write_video

__all__ = ["read_video", "open_source", "FrameSource", "write_video", "write_lossless_video", "VideoWriter",
           "TruncatedInputWarning", "VideoCodecWarning",
           "parse_resize", "expand_inputs", "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS", "DEFAULT_FPS"]
