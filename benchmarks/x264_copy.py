"""Write one libx264 copy of a video (a helper of ``encoding_invariance.py``, run in a process of its own).

    python benchmarks/x264_copy.py SRC DST [--size WxH] [--crf 20]

Decodes ``SRC`` with PyAV, resizes each frame to ``--size`` when given (``cv2.INTER_AREA`` when it shrinks,
``cv2.INTER_LINEAR`` when it grows), and encodes it with libx264 (CRF ``--crf``, preset ``veryfast``, yuv420p,
one thread, the source's frame rate) into ``DST``. It imports nothing of the package: libx264 through PyAV gave
different bytes for the same call after a model had run in the same process (docs/history.md, "Encoding and
size"), so every copy is written by a fresh interpreter whose history is only this file.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import av
import cv2
import numpy as np

#: The encoder's settings; ``encoding_invariance.py`` keys its cache on them.
OPTIONS = {"preset": "veryfast", "threads": "1"}


def write_copy(src: Path, dst: Path, size: tuple[int, int] | None, crf: int = 20) -> tuple[int, int]:
    """``src`` re-encoded with libx264 into ``dst``, each frame resized to ``size`` (W, H) first when given;
    returns the copy's size."""
    with av.open(str(src)) as inp:
        vs = inp.streams.video[0]
        rate = vs.average_rate or 30
        with av.open(str(dst), "w") as out:
            os_ = None
            for frame in inp.decode(vs):
                img = frame.to_ndarray(format="rgb24")
                if size is not None:
                    interp = cv2.INTER_AREA if size[0] < img.shape[1] else cv2.INTER_LINEAR
                    img = cv2.resize(img, size, interpolation=interp)
                if os_ is None:
                    os_ = out.add_stream("libx264", rate=rate)
                    os_.width, os_.height = img.shape[1], img.shape[0]
                    os_.pix_fmt = "yuv420p"
                    os_.options = {"crf": str(crf), **OPTIONS}
                for pkt in os_.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="rgb24")):
                    out.mux(pkt)
            if os_ is None:
                raise SystemExit(f"{src}: no video frames")
            for pkt in os_.encode():
                out.mux(pkt)
            return os_.width, os_.height


def _size(text: str) -> tuple[int, int]:
    w, _, h = text.partition("x")
    return int(w), int(h)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src", type=Path)
    ap.add_argument("dst", type=Path)
    ap.add_argument("--size", type=_size, help="WxH to resize every frame to first")
    ap.add_argument("--crf", type=int, default=20)
    args = ap.parse_args(argv)
    write_copy(args.src, args.dst, args.size, args.crf)
    return 0


if __name__ == "__main__":
    sys.exit(main())
