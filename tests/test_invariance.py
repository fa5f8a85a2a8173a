"""The same clip, encoded or scaled differently, gives the same answers (issue 22 item 7).

A synthetic collision whose images repeat 4 times (a 7.5 fps source in a 30 fps container, as
the helmet and dashcam clips of ``../shared/data/real``), written lossy with PyAV's libx264 at
320x240 and at twice that size: their first target warnings agree, and (open) the models should
hold the same copies (``Model.repeat_threshold``). ``benchmarks/encoding_invariance.py`` measures
the same on the real clips.
"""

from __future__ import annotations

import av
import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.io import open_source
from mlplc2.models.base import REPEAT_THRESHOLD

REPEAT = 4


def _write(frames, path, size, crf):
    """``frames`` (grey) resized to ``size`` and written with libx264 at CRF ``crf`` (yuv420p)."""
    with av.open(str(path), "w") as out:
        s = out.add_stream("libx264", rate=30)
        s.width, s.height = size
        s.pix_fmt = "yuv420p"
        s.options = {"crf": str(crf), "preset": "veryfast"}
        for f in frames:
            img = f if f.shape[::-1] == size else cv2.resize(f, size, interpolation=cv2.INTER_LINEAR)
            rgb = np.ascontiguousarray(np.repeat(img[:, :, None], 3, axis=2))
            for pkt in s.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                out.mux(pkt)
        for pkt in s.encode():
            out.mux(pkt)


@pytest.fixture(scope="module")
def copies(tmp_path_factory):
    """The same collision (a dark square at 2 s, on a textured background) as 320x240 lossless (CRF 0),
    320x240 CRF 20 and 640x480 CRF 20; each image 4 times."""
    stim = stimuli.looming(size=(320, 240), center=(180, 110), contact_time=2.0, duration=2.2,
                           background="procedural", fps=30.0 / REPEAT)
    frames = [np.asarray(f, dtype=np.uint8) for f in stim.frames for _ in range(REPEAT)]
    d = tmp_path_factory.mktemp("inv")
    paths = {}
    for name, size, crf in (("320_crf20", (320, 240), 20), ("320_crf0", (320, 240), 0),
                            ("640_crf20", (640, 480), 20)):
        paths[name] = d / f"{name}.mp4"
        _write(frames, paths[name], size, crf)
    return paths, len(frames)


def _run(path):
    """mlplc2 over ``path``: (frames held, (first warning frame, x, y) in 320x240 pixels or None)."""
    res = mlplc2.run(str(path), ["mlplc2"], out=False, quiet=True, progress=False, plot=False)
    warned = [r for r in res.targets if r["warning"]]
    if not warned:
        return res.repeated["mlplc2"], None
    first = min(warned, key=lambda r: r["frame"])
    scale = 320 / res.size[0]
    return res.repeated["mlplc2"], (first["frame"], first["x"] * scale, first["y"] * scale)


def test_encoding_and_size_warn_alike(copies):
    """The first warnings of the three copies lie within 2 frames of each other, on the square."""
    paths, _ = copies
    firsts = {name: _run(p)[1] for name, p in paths.items()}
    assert all(w is not None for w in firsts.values()), firsts
    frames = [w[0] for w in firsts.values()]
    assert max(frames) - min(frames) <= 2, firsts
    assert all(abs(x - 180) < 30 and abs(y - 110) < 30 for _, x, y in firsts.values()), firsts


def _held(path) -> list[int]:
    """The frames a model holds as repeats (``Output.repeated``) when stepped over ``path``
    (LGMD2: the decision is the base class's, the same for every model; mlplc2.run's prescan aside)."""
    model = mlplc2.LGMD2(fps=30.0, repeat_threshold=REPEAT_THRESHOLD)
    src = open_source(str(path))
    try:
        return [k for k, item in enumerate(src) if model.step(item[1]).repeated]
    finally:
        src.close()


@pytest.mark.xfail(strict=True, reason="open (issue 22 item 7): the repeat test compares single pixels, so the "
                   "compression noise on a copy decides (mlplc2.run held 41 copies at 320x240 CRF 20, 47 at "
                   "640x480 and lossless); comparing 80 px wide frames held them alike but also held real 1 px "
                   "motion (docs/model.md, 'Encoding and size')")
def test_encoding_and_size_hold_the_same_copies(copies):
    """The same copies are held whatever noise the encoding or the scaling left on them."""
    paths, _ = copies
    held = {name: _held(p) for name, p in paths.items()}
    assert held["320_crf20"] == held["320_crf0"] == held["640_crf20"], held
