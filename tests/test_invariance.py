"""The same clip, encoded or scaled differently, gives the same answers (issue 22 item 7).

A synthetic collision whose images repeat 4 times (a 7.5 fps source in a 30 fps container, as
the helmet and dashcam clips of ``../shared/data/real``), written lossy with PyAV's libx264 at
320x240 and at twice that size: the models hold the same copies whatever the encoding
(``Model.repeat_threshold="auto"``: :func:`mlplc2.models.base.repeat_split`) and their first
target warnings agree. What the "auto" repeat test must not hold: a real 1 px/frame scroll, a slow
looming object, a still scene; what it must: a 25 fps video shown at 30 fps (one copy in 6).
``benchmarks/encoding_invariance.py`` measures the same on the real clips.
"""

from __future__ import annotations

import av
import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli

REPEAT = 4


def _write(frames, path, size=None, crf=20):
    """``frames`` (grey) resized to ``size`` (default: their own) and written with libx264 at CRF ``crf``."""
    size = size or frames[0].shape[::-1]
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
    return path


class _Held(mlplc2.LGMD2):
    """A cheap model that records the frames it held (the decision is the base class's, alike for every model)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.held: list[int] = []

    def step(self, frame, t=None):
        out = super().step(frame, t)
        if out.repeated:
            self.held.append(out.frame)
        return out


def _held(path) -> list[int]:
    """The frames ``mlplc2.run`` holds as repeats over ``path`` (its pre-scan included)."""
    probe = _Held(fps=30.0)
    mlplc2.run(str(path), [probe], out=False, quiet=True, progress=False, plot=False)
    return probe.held


@pytest.fixture(scope="module")
def copies(tmp_path_factory):
    """The same collision (a dark square at 2 s, on a textured background) as 320x240 lossless (CRF 0),
    320x240 CRF 20 and CRF 30, 640x480 CRF 20 and 200x150 CRF 20; each image 4 times."""
    stim = stimuli.looming(size=(320, 240), center=(180, 110), contact_time=2.0, duration=2.2,
                           background="procedural", fps=30.0 / REPEAT)
    frames = [np.asarray(f, dtype=np.uint8) for f in stim.frames for _ in range(REPEAT)]
    d = tmp_path_factory.mktemp("inv")
    paths = {}
    for name, size, crf in (("320_crf20", (320, 240), 20), ("320_crf0", (320, 240), 0), ("320_crf30", (320, 240), 30),
                            ("640_crf20", (640, 480), 20), ("200_crf20", (200, 150), 20)):
        paths[name] = _write(frames, d / f"{name}.mp4", size, crf)
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
    """The first warnings of the copies at 320x240 (CRF 0 and 20) and 640x480 lie within 2 frames of each
    other, on the square."""
    paths, _ = copies
    firsts = {name: _run(paths[name])[1] for name in ("320_crf20", "320_crf0", "640_crf20")}
    assert all(w is not None for w in firsts.values()), firsts
    frames = [w[0] for w in firsts.values()]
    assert max(frames) - min(frames) <= 2, firsts
    assert all(abs(x - 180) < 30 and abs(y - 110) < 30 for _, x, y in firsts.values()), firsts


def test_encoding_and_size_hold_the_same_copies(copies):
    """Whatever noise the encoding (CRF 0, 20, 30) or the scaling (200x150, 640x480) left on them, the
    copies held are the same: exactly the repeated images, from the first one on. (With the largest
    single pixel change against 16 grey levels, mlplc2.run held 41 copies at 320x240 CRF 20 and 47 at
    640x480 and lossless.)"""
    paths, n = copies
    held = {name: _held(p) for name, p in paths.items()}
    assert all(h == held["320_crf0"] for h in held.values()), {name: sorted(set(h) ^ set(held["320_crf0"]))
                                                               for name, h in held.items()}
    # before contact (frame 60; from then on the square fills the view and the images stand still)
    assert [k for k in held["320_crf0"] if k < 56] == [k for k in range(56) if k % REPEAT]


def _texture(w, h, seed=0):
    rng = np.random.default_rng(seed)
    t = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 2.0)
    return cv2.normalize(t, None, 40, 215, cv2.NORM_MINMAX)


def test_a_scroll_of_one_pixel_a_frame_is_never_held(tmp_path):
    """A texture that moves 1 px every frame changes every frame: nothing is held, compressed or not; the
    same scroll made of 15 fps images shown twice holds exactly the copies (the new frames step)."""
    tex = _texture(400, 120)
    frames = [np.round(tex[:, k:k + 160]).astype(np.uint8) for k in range(60)]
    for crf in (0, 20):
        assert _held(_write(frames, tmp_path / f"scroll{crf}.mp4", crf=crf)) == []
    doubled = [f for f in frames[:30] for _ in range(2)]
    assert _held(_write(doubled, tmp_path / "scroll_doubled.mp4")) == list(range(1, 60, 2))


def test_a_slow_looming_object_is_never_held(tmp_path):
    """A small object far away approaching slowly (a few edge pixels change a little each frame) is sampled
    on every frame, compressed at CRF 20 as well."""
    from mlplc2.stimuli import ApproachObject, approach

    slow = approach([ApproachObject.collision(ttc_s=5.0, width_px=4.0, speed_mps=2.0)], background="plain",
                    duration_s=3.0, seed=1)
    frames = [np.asarray(f, dtype=np.uint8) for f in slow.frames]
    assert _held(_write(frames, tmp_path / "slow.mp4")) == []
    faint = [np.uint8(128) + (f // 8) for f in frames]    # the same at an eighth of the contrast
    assert _held(_write(faint, tmp_path / "faint.mp4")) == []


def test_a_still_scene_is_never_held(tmp_path):
    """A still textured scene with sensor noise (+-3 grey levels), compressed: no frame is held."""
    rng = np.random.default_rng(2)
    tex = _texture(160, 120, seed=2)
    frames = [np.clip(tex + rng.integers(-3, 4, tex.shape), 0, 255).astype(np.uint8) for _ in range(60)]
    assert _held(_write(frames, tmp_path / "still.mp4")) == []


def test_twenty_five_in_thirty_holds_the_copies(tmp_path):
    """A 25 fps scroll converted to 30 fps (every 5th image shown twice: one copy in 6 frames) holds exactly
    the copies (the real clip sudden_turning_vehicle.mp4 is made so)."""
    tex = _texture(400, 120)
    images = [np.round(tex[:, 2 * k:2 * k + 160]).astype(np.uint8) for k in range(60)]
    frames, copies = [], []
    for k, img in enumerate(images):
        frames.append(img)
        if k % 5 == 4:
            copies.append(len(frames))
            frames.append(img)
    assert _held(_write(frames, tmp_path / "pulldown.mp4")) == copies


def _module(name):
    """``benchmarks/NAME.py`` as a module."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _encoding_check():
    """``benchmarks/encoding_invariance.py`` as a module."""
    return _module("encoding_invariance")


def test_the_encoding_check_writes_each_copy_once_and_the_same_every_time(tmp_path, monkeypatch):
    """The check's copies are written by a process of their own: two writes of the same copy (into two caches)
    give the same bytes, a second call with the same cache reuses the file without writing, and other settings
    make another file."""
    enc = _encoding_check()
    src = _write([np.round(_texture(200, 64)[:, k:k + 96]).astype(np.uint8) for k in range(20)],
                 tmp_path / "src.mp4", crf=0)
    sha = enc.sha256(src)
    first = enc.cached_copy(src, sha, "x264", None, tmp_path / "a")
    again = enc.cached_copy(src, sha, "x264", None, tmp_path / "b")
    assert first.read_bytes() == again.read_bytes()
    assert enc.sha256(first) != sha                          # a copy, not the source
    monkeypatch.setattr(enc.subprocess, "run", lambda *a, **k: pytest.fail("wrote a cached copy again"))
    assert enc.cached_copy(src, sha, "x264", None, tmp_path / "a") == first
    monkeypatch.undo()
    small = enc.cached_copy(src, sha, "320x240", (48, 32), tmp_path / "a")
    assert small != first and small.exists()
    with av.open(str(small)) as c:
        assert (c.streams.video[0].width, c.streams.video[0].height) == (48, 32)


def test_the_encoding_check_says_where_two_runs_part():
    """``parting``: the first field born elsewhere (beyond 4 working px) or not at all, and the first frame
    whose target boxes differ (in number, or beyond 6 working px)."""
    enc = _encoding_check()
    a = {"_births": [(1, 10.0, 10.0), (5, 50.0, 50.0)], "_boxes": {4: [(20.0, 20.0, 8.0, 8.0)], 6: []}}
    same = {"_births": [(1, 13.0, 10.0), (5, 50.0, 47.0)], "_boxes": {4: [(25.0, 20.0, 8.0, 8.0)], 6: []}}
    assert enc.parting(a, same, 1.0) == "fields part at -, targets at -"
    moved = {"_births": [(1, 10.0, 10.0), (5, 55.0, 50.0)], "_boxes": {4: [(20.0, 20.0, 8.0, 8.0)],
                                                                       6: [(1.0, 1.0, 2.0, 2.0)]}}
    assert enc.parting(a, moved, 1.0) == "fields part at 5, targets at 6"
    assert enc.parting(a, moved, 2.0) == "fields part at -, targets at 6"     # 5 native px = 2.5 working px
    fewer = {"_births": [(1, 10.0, 10.0)], "_boxes": {}}
    assert enc.parting(a, fewer, 1.0) == "fields part at 5, targets at 4"


def test_a_replicate_is_the_same_scene_seen_with_noise_nobody_can_see(tmp_path):
    """``benchmarks/replicate.py make``: every scene file of a benchmark folder again, losslessly, with its labels;
    each frame differs from the original by Gaussian noise of 0.5 grey levels rounded to 8 bits (a third of the
    pixels by one level, none by more than a few); the same seed writes the same bytes, another seed and another
    file other draws."""
    from mlplc2.io import read_video, write_lossless_video

    rep = _module("replicate")
    src = tmp_path / "bench" / "scenes"
    src.mkdir(parents=True)
    frames = [np.round(_texture(120, 64)[:, k:k + 80]).astype(np.uint8) for k in range(6)]
    write_lossless_video(src / "drive_0.mkv", frames, 30.0)
    write_lossless_video(src / "drone_0.mkv", frames, 30.0)
    (src / "ground_truth.json").write_text('{"videos": {}}')
    rep.make(tmp_path / "bench", tmp_path / "a", seed=1, sigma=0.5, progress=False)
    rep.make(tmp_path / "bench", tmp_path / "b", seed=1, sigma=0.5, progress=False)
    rep.make(tmp_path / "bench", tmp_path / "c", seed=2, sigma=0.5, progress=False)
    a = tmp_path / "a" / "scenes"
    assert (a / "ground_truth.json").read_text() == '{"videos": {}}'
    copy = list(read_video(a / "drive_0.mkv")[0][..., 0])
    assert len(copy) == len(frames)
    diff = np.array([c.astype(int) - f.astype(int) for c, f in zip(copy, frames)])
    assert 0.25 < np.mean(diff != 0) < 0.40           # P(|N(0, 0.5)| > 0.5) = 0.32
    assert np.abs(diff).max() <= 3 and abs(diff.mean()) < 0.05
    assert (a / "drive_0.mkv").read_bytes() == (tmp_path / "b" / "scenes" / "drive_0.mkv").read_bytes()
    assert (a / "drive_0.mkv").read_bytes() != (tmp_path / "c" / "scenes" / "drive_0.mkv").read_bytes()
    other = read_video(a / "drone_0.mkv")[0][..., 0].astype(int) - np.array(frames, dtype=int)
    assert np.any(other != diff)                          # each file its own draw
    with pytest.raises(SystemExit, match="no ground_truth.json"):
        rep.make(tmp_path / "a" / "scenes", tmp_path / "d", seed=1, sigma=0.5, progress=False)
    with pytest.raises(SystemExit, match="sigma"):
        rep.make(tmp_path / "bench", tmp_path / "d", seed=1, sigma=0.0, progress=False)
    with pytest.raises(SystemExit, match="overwrite its original"):
        rep.make(tmp_path / "bench", tmp_path / "bench", seed=1, sigma=0.5, progress=False)


def test_the_replicate_comparison_holds_a_first_warning_the_same_within_two_frames():
    """``stability``: per setting, a collision object first warned within 2 frames by both runs, or by neither,
    is the same; warned by one run only, or further apart, it is not (issue 22's item 7 on the benchmark)."""
    rep = _module("replicate")
    assert [rep._setting(v) for v in ("drive_3_h28_f90.mkv", "ground_forward_0_h36_f90.mkv", "texture_pan_4.mkv",
                                      "plain_static_2.mkv", "drone_1_h92.mkv")] == \
        ["drive", "ground_forward", "texture_pan", "plain_static", "drone"]

    def obj(frame):
        return {"warned": frame is not None, "warning_frame": frame}
    a = {("drive_0_h1.mkv", 7): obj(10), ("drive_1_h1.mkv", 7): obj(10), ("drone_0_h1.mkv", 1): obj(40),
         ("texture_pan_4.mkv", 1): obj(None), ("drive_2_h1.mkv", 7): obj(30)}
    b = {("drive_0_h1.mkv", 7): obj(12), ("drive_1_h1.mkv", 7): obj(15), ("drone_0_h1.mkv", 1): obj(None),
         ("texture_pan_4.mkv", 1): obj(None)}                     # drive_2 is not in the replicate: not counted
    st = rep.stability([(a, b)])
    assert st["drive"] == {"n": 2, "same": 1, "none": 0, "one": 0, "moved": [5]}
    assert st["drone"] == {"n": 1, "same": 0, "none": 0, "one": 1, "moved": []}
    assert st["texture_pan"] == {"n": 1, "same": 1, "none": 1, "one": 0, "moved": []}
    assert st["all"]["n"] == 4 and st["all"]["same"] == 2
    assert rep.stability([(a, b)], frames=5)["drive"]["same"] == 2
    # the field alarm's first frame on each object, counted alike (a missing frame: none in that run)
    alarm_a = {("drive_0_h1.mkv", 7): {"alarm_frame": 20}, ("drive_1_h1.mkv", 7): {"alarm_frame": None}}
    alarm_b = {("drive_0_h1.mkv", 7): {"alarm_frame": 19}, ("drive_1_h1.mkv", 7): {"alarm_frame": 31}}
    assert rep.stability([(alarm_a, alarm_b)], key="alarm_frame")["drive"] == {"n": 2, "same": 1, "none": 0, "one": 1, "moved": []}


def test_the_sigma_check_counts_estimates_within_two_sigma_of_the_truth(tmp_path):
    """``benchmarks/ttc_sigma.py``: the truth of a scene folder's colliders (0-3 s only, the first collider alive),
    and the summary line: errors, the median sigma and the share of estimates within 2 sigma of the truth."""
    import json

    sig = _module("ttc_sigma")
    cols = ["frame", "x", "y", "width", "height", "ttc_s", "miss"]
    gt = {"videos": {"drive_0.mkv": {"objects": [
        {"kind": "pass", "track_columns": cols, "track": [[5, 1.0, 1.0, 4.0, 4.0, 0.5, 3.0]]},
        {"kind": "collision", "track_columns": cols, "track": [[5, 40.0, 30.0, 8.0, 8.0, 3.5, 0.1],
                                                                [6, 41.0, 31.0, 9.0, 9.0, 1.0, 0.1]]}]},
        "plain_static_0.mkv": {"objects": []}}}
    (tmp_path / "ground_truth.json").write_text(json.dumps(gt))
    (setting, path, truth), = list(sig._scenes(tmp_path))           # the scene without a collider is left out
    assert setting == "drive" and path == tmp_path / "drive_0.mkv"
    assert truth(5) is None                                          # 3.5 s: beyond 3 s
    assert truth(6) == (41.0, 31.0, 1.0) and truth(7) is None
    rows = [(1.1, 0.1, 1.0), (1.0, 0.1, 1.0), (0.5, 0.1, 1.0), (2.0, 0.2, 1.0)]   # |z| 1, 0, 5, 5
    line = sig._line("drive", rows)
    assert "rows     4" in line and "within 2 sigma 50%" in line and "median |z| 3.0" in line
    assert "median sigma 0.100 s" in line and "median error 0.300 s (30.0%)" in line
    # --real: the labelled contact, or (--growth) the labelled boxes' own expansion: a box 13 -> 17 px wide over the
    # 8 frames about frame 10 (15 px there) at 10 frames/s grows 5 px/s: 3.0 s, where the contact label says 2.0 s
    real = tmp_path / "real"
    real.mkdir()
    (real / "a.mp4").write_bytes(b"")
    clip = {"label": "collision", "fps": 10.0, "contact_frame": 30, "track": [[0, 10.0, 12.0, 10.0], [20, 30.0, 12.0, 20.0]]}
    (real / "ground_truth.json").write_text(json.dumps({"clips": {"a.mp4": clip, "b.mp4": clip}}))   # b.mp4 absent
    (key, path, contact), = list(sig._real(real))
    (_, _, growth), = list(sig._real(real, growth=True))
    assert key == "a.mp4" and path == real / "a.mp4"
    assert contact(10) == pytest.approx((20.0, 12.0, 2.0)) and contact(30) is None and contact(21) is None
    assert growth(10) == pytest.approx((20.0, 12.0, 3.0)) and growth(2) is None     # its 8 frames not all labelled

