"""Tests of mlplc2.io: reading, streaming and writing videos and image sequences."""

from __future__ import annotations

import threading

import cv2
import numpy as np
import pytest

from mlplc2._validation import InputError, InputValueError
from mlplc2.io import (FrameSource, TruncatedInputWarning, VideoWriter, open_source, parse_resize, read_video,
                       write_lossless_video, write_video)

W, H, T = 160, 120, 24


def _frames(n=T, w=W, h=H):
    """RGB frames: frame i has a red block whose width encodes i, on grey."""
    out = []
    for i in range(n):
        f = np.full((h, w, 3), 90, np.uint8)
        f[10:40, 10:10 + 4 * (i % 30) + 4] = (220, 20, 20)
        out.append(f)
    return out


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    d = tmp_path_factory.mktemp("io")
    frames = _frames()
    paths = {"avi": d / "v.avi", "mp4": d / "v.mp4"}
    write_video(paths["avi"], frames, 25.0)
    write_video(paths["mp4"], frames, 25.0)
    return paths, frames


# -- read_video ----------------------------------------------------------------
@pytest.mark.parametrize("kind", ["avi", "mp4"])
def test_read_video_shape_fps_rgb(videos, kind):
    paths, frames = videos
    arr, fps = read_video(paths[kind])
    assert arr.shape == (T, H, W, 3) and arr.dtype == np.uint8
    assert fps == pytest.approx(25.0)
    # RGB order: the block is red, not blue
    block = arr[5, 15:35, 15:25].reshape(-1, 3).mean(axis=0)
    assert block[0] > 150 and block[2] < 80
    assert np.abs(arr.astype(int) - np.stack(frames)).mean() < 6


def test_read_video_pyav_backend_matches_opencv(videos):
    paths, _ = videos
    a, fa = read_video(paths["avi"])
    b, fb = read_video(paths["avi"], decoder="pyav")
    assert a.shape == b.shape and fa == fb
    assert np.abs(a.astype(int) - b).mean() < 3


# -- open_source ----------------------------------------------------------------
def test_stream_indices_start_end(videos):
    paths, _ = videos
    src = open_source(paths["avi"], start=5, end=12)
    assert isinstance(src, FrameSource)
    assert src.frame_count == T and src.total == 7 and src.size == (W, H)
    items = list(src)
    assert [i for i, _ in items] == list(range(5, 12))
    assert all(f.shape == (H, W, 3) and f.dtype == np.uint8 for _, f in items)
    assert not src.truncated


def test_stream_resize_mapping_and_original(videos):
    paths, _ = videos
    src = open_source(paths["mp4"], resize="80x40", keep_original=True)
    assert src.out_size == (80, 40) and src.size == (W, H)
    assert src.scale_x == pytest.approx(2.0) and src.scale_y == pytest.approx(3.0)
    assert src.to_input(10, 10) == pytest.approx((20.0, 30.0))
    idx, small, orig = next(iter(src))
    assert small.shape == (40, 80, 3) and orig.shape == (H, W, 3) and idx == 0
    src.close()


def test_stream_scale(videos):
    paths, _ = videos
    with open_source(paths["avi"], scale=0.5) as src:
        assert src.out_size == (W // 2, H // 2)


def test_stream_early_close_stops_thread(videos):
    paths, _ = videos
    before = {t.ident for t in threading.enumerate()}
    src = open_source(paths["avi"])
    for i, _ in src:
        if i == 2:
            break
    src.close()
    left = [t for t in threading.enumerate() if t.ident not in before and t.name == "mlplc2-decode"]
    assert not left
    assert src._queue.maxsize <= 8  # bounded: memory independent of length


def test_frames_read_ahead_are_given_again_with_their_own_times(videos):
    """``FrameSource.peek``: the first frames read before iterating (the repeat scan of a stream read
    once) are yielded again, each with the index, frame, time and count it has without peeking."""
    paths, _ = videos

    def seen(src):
        return [(i, f.tobytes(), src.time_s, src.n_read, src.skipped) for i, f in src]

    plain = seen(open_source(paths["avi"], decoder="pyav", start=2))
    src = open_source(paths["avi"], decoder="pyav", start=2)
    ahead = src.peek(5)
    assert [i for i, _ in ahead] == [2, 3, 4, 5, 6] and src.n_read == 5
    assert seen(src) == plain and len(plain) == T - 2 and plain[1][2] == pytest.approx(3 / 25)
    short = open_source(paths["avi"], end=3)
    assert len(short.peek(10)) == 3 and [i for i, _ in short] == [0, 1, 2]   # the source ended first
    with open_source(paths["avi"], live=True) as live, pytest.raises(RuntimeError, match="not live"):
        live.peek(3)                                   # a live source would skip frames meanwhile



def test_an_error_while_reading_ahead_comes_after_the_frames_before_it():
    from mlplc2.io.decoders import Decoder

    class Failing(Decoder):
        name, fps, n = "failing", 30.0, 0

        def read(self):
            self.n += 1
            if self.n > 3:
                raise OSError("the device went away")
            return np.full((H, W, 3), self.n, np.uint8)

    src = FrameSource(Failing(), "stream")
    assert len(src.peek(10)) == 3
    got = []
    with pytest.raises(OSError, match="went away"):
        for i, f in src:
            got.append((i, int(f[0, 0, 0])))
    assert got == [(0, 1), (1, 2), (2, 3)]


def test_fps_override(videos):
    paths, _ = videos
    with open_source(paths["avi"], fps=12.5) as src:
        assert src.fps == 12.5


def test_image_folder_natural_order_and_glob(tmp_path):
    d = tmp_path / "imgs"
    d.mkdir()
    for i in (1, 2, 10, 3):
        f = np.full((H, W, 3), i * 20, np.uint8)
        cv2.imwrite(str(d / f"f{i}.png"), f)
    (d / "notes.txt").write_text("not an image")
    src = open_source(d)
    assert src.fps == 30.0 and src.frame_count == 4 and src.kind == "images"
    levels = [int(f[0, 0, 0]) for _, f in src]
    assert levels == [20, 40, 60, 200]
    levels = [int(f[0, 0, 0]) for _, f in open_source(str(d / "f*.png"))]
    assert levels == [20, 40, 60, 200]


def test_image_size_mismatch_stops_like_a_damaged_image(tmp_path):
    """An image of another size ends the sequence there: frames before it are kept."""
    cv2.imwrite(str(tmp_path / "a1.png"), np.zeros((20, 30, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "a2.png"), np.zeros((20, 30, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "a3.png"), np.zeros((22, 30, 3), np.uint8))
    src = open_source(tmp_path)
    assert len(list(src)) == 2
    assert src.truncated and src.truncated_at == 2
    assert "a3.png is 30x22, not 30x20 like the first image (frame 2); stopped there" in src.message


# -- errors ---------------------------------------------------------------------
def test_missing_file(tmp_path):
    """A missing file is named; the hint on streams only where the name is not a video's or an image's
    (a URL without its scheme), not after a mistyped clip's path."""
    with pytest.raises(InputValueError, match=r"nope.mp4: no such file or directory$"):
        open_source(tmp_path / "nope.mp4")
    with pytest.raises(InputValueError, match=r"no such file or directory \(a stream: a URL such as rtsp://"):
        open_source("192.168.1.20:554/stream1")


def test_empty_directory(tmp_path):
    with pytest.raises(InputValueError, match="no images"):
        open_source(tmp_path)


def test_glob_without_match(tmp_path):
    with pytest.raises(InputValueError, match="no files match"):
        open_source(str(tmp_path / "*.png"))


def test_glob_of_videos_points_at_batch(tmp_path):
    """A pattern that matches videos (``'clips/*.mp4'``) is not an image sequence: the error says so and
    names `mlplc2 batch`, as for a folder of videos (until session 14 it said only "are not images")."""
    for name in ("a.mp4", "b.mp4"):
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / "n.txt").write_text("x")
    with pytest.raises(InputValueError, match=r"are not images \(they are videos: run them all with `mlplc2 batch`"):
        open_source(str(tmp_path / "*.mp4"))
    with pytest.raises(InputValueError, match=r"are not images$"):
        open_source(str(tmp_path / "*.txt"))
    with pytest.raises(InputValueError, match="it holds videos: run them all with `mlplc2 batch`"):
        open_source(tmp_path)


def test_text_file_named_mp4(tmp_path):
    p = tmp_path / "fake.mp4"
    p.write_text("this is not a video\n" * 10)
    with pytest.raises(InputValueError, match="not a video"):
        open_source(p)


def test_zero_frame_video(tmp_path):
    p = tmp_path / "zero.avi"
    w = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 30, (W, H))
    w.release()
    with pytest.raises(InputValueError, match="no frames"):
        open_source(p)


def test_missing_camera():
    """One line that says what may be wrong, and on Linux which cameras there are."""
    import glob
    import sys

    with pytest.raises(InputError, match="cannot open camera 97: none at that index, or another program holds it") \
            as err:
        open_source(97)
    if sys.platform.startswith("linux"):
        found = sorted(glob.glob("/dev/video*"))
        assert str(err.value).endswith(f"(cameras here: {', '.join(found)})" if found else "(no camera here: no /dev/video*)")


@pytest.mark.parametrize("bad", ["abc", "320", "0x240", "320x-2", "x", (0, 3), "3x4x5"])
def test_bad_resize(videos, bad):
    with pytest.raises(InputValueError, match="bad resize"):
        open_source(videos[0]["avi"], resize=bad)


def test_parse_resize_ok():
    assert parse_resize("320x240") == (320, 240)
    assert parse_resize(" 64X48 ") == (64, 48)
    assert parse_resize((10, 20)) == (10, 20)


@pytest.mark.parametrize("kwargs, match", [
    ({"resize": "10x10", "scale": 0.5}, "not both"),
    ({"scale": -1}, "bad scale"),
    ({"start": 3, "end": 3}, "larger than start"),
    ({"start": -1}, "start must be"),
    ({"start": 500}, "past the end"),
    ({"fps": 0}, "fps"),
])
def test_bad_options(videos, kwargs, match):
    with pytest.raises(InputError, match=match):
        open_source(videos[0]["avi"], **kwargs)


def test_truncated_avi(tmp_path):
    p = tmp_path / "cut.avi"
    write_video(p, _frames(40), 30.0)
    data = p.read_bytes()
    p.write_bytes(data[: int(len(data) * 0.6)])
    src = open_source(p)
    got = [i for i, _ in src]
    assert 0 < len(got) < 40 and got == list(range(len(got)))
    assert src.truncated and src.truncated_at == len(got)
    assert f"frame {len(got)}" in src.message
    with pytest.warns(TruncatedInputWarning, match=f"stopped at frame {len(got)} of 40"):
        arr, _ = read_video(p)
    assert len(arr) == len(got)


def test_truncated_mp4_we_wrote_still_decodes(tmp_path):
    """Our MP4s put the index first (faststart), so a cut file keeps its first frames."""
    pytest.importorskip("av")
    p = tmp_path / "cut.mp4"
    write_video(p, _frames(60), 30.0)
    data = p.read_bytes()
    p.write_bytes(data[: int(len(data) * 0.6)])
    src = open_source(p)
    got = [i for i, _ in src]
    assert 0 < len(got) < 60
    assert src.truncated and f"frame {len(got)}" in src.message


def test_a_matroska_file_with_dropped_frames_is_whole_and_a_cut_one_is_not(tmp_path):
    """A camera that drops frames and keeps their timestamps (a variable frame rate): OpenCV states its
    count as its duration times its rate, 59 for the 40 frames kept here; the run read all 40 and
    ended at the stated length, so it is whole (until session 54: "decoding stopped at frame 40 of 59
    (file truncated or damaged)", exit 2). The same file cut short is still truncated."""
    av = pytest.importorskip("av")
    from fractions import Fraction

    kept = [k for k in range(60) if k % 3 != 2]
    p = tmp_path / "vfr.mkv"
    with av.open(str(p), "w") as out:
        stream = out.add_stream("ffv1", rate=30)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        stream.time_base = Fraction(1, 1000)
        for k, f in zip(kept, _frames(60)):
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(f[:48, :64]), format="rgb24")
            frame.pts, frame.time_base = round(k * 1000 / 30), Fraction(1, 1000)
            out.mux(stream.encode(frame))
        out.mux(stream.encode(None))
    src = open_source(p, decoder="opencv")
    assert src.frame_count == 59      # the estimate this test is about: the last frame kept is 58
    times = [src.time_s for _ in src]
    assert len(times) == 40 and not src.truncated, src.message
    assert times[:3] == pytest.approx([0.0, 1 / 30, 3 / 30], abs=2e-3)     # the camera's clock, frame 2 dropped
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(p.read_bytes()[: int(p.stat().st_size * 0.6)])
    src = open_source(cut, decoder="opencv")
    got = [i for i, _ in src]
    assert 0 < len(got) < 40 and src.truncated, (len(got), src.message)


def _damaged_video(tmp_path):
    """40 frames (FFV1) whose frame 20 is damaged (bytes of its packet changed: its slice CRC fails),
    and the index of the next key frame."""
    p = tmp_path / "damaged.mkv"
    frames = [f[..., 0] for f in _frames(40)]               # the red block's width encodes the index
    write_lossless_video(p, frames, 30.0)
    import av
    with av.open(str(p)) as c:          # where frame 20's packet lies in the file
        packets = [k for k in c.demux(c.streams.video[0]) if k.size]
        at, size = packets[20].pos, packets[20].size
        key = next(i for i, k in enumerate(packets) if i > 20 and k.is_keyframe)
    data = bytearray(p.read_bytes())
    data[at + size // 4:at + size // 2] = bytes((b * 7 + 13) & 255 for b in data[at + size // 4:at + size // 2])
    p.write_bytes(bytes(data))          # the packet's bytes, not the container's
    return p, frames, key


def test_a_damaged_frame_in_the_middle_is_skipped_not_the_end(tmp_path):
    """PyAV: a damaged packet mid-file costs its frame and those predicted from it up to the next key
    frame (FFV1's coder state; they decode as garbage without an error), not the rest of the run:
    the frames after come with their own indices and times (their content says which frame they
    are), the skipped ones are named."""
    p, frames, key = _damaged_video(tmp_path)
    src = open_source(p, decoder="pyav")
    got = {i: f for i, f in src}
    assert not src.truncated and src.message is None
    assert src.damaged == list(range(20, key)) and key < 40   # the damaged frame, those predicted from it
    assert sorted(list(got) + src.damaged) == list(range(40))
    for i, f in got.items():            # grey written, RGB read: a few levels of range conversion
        assert np.abs(f[..., 0].astype(int) - frames[i]).max() <= 4, i
    assert abs(src.time_s - 39 / 30.0) < 1e-3


def test_opencv_stops_at_a_damaged_frame_and_names_the_decoder_that_goes_on(tmp_path):
    """OpenCV's reads after a damaged frame give earlier frames' pictures: it stops there, and says so."""
    p, _, _ = _damaged_video(tmp_path)
    src = open_source(p, decoder="opencv")
    got = [i for i, _ in src]
    assert got == list(range(20)) and src.truncated and src.truncated_at == 20
    assert "--decoder pyav" in src.message


# -- writing --------------------------------------------------------------------
def test_write_odd_size_mp4_is_padded(tmp_path):
    pytest.importorskip("av")
    frames = _frames(5, w=81, h=61)
    p = write_video(tmp_path / "odd.mp4", frames, 30.0)
    arr, _ = read_video(p)
    assert arr.shape == (5, 62, 82, 3)


def test_write_avi_and_opencv_mp4_and_grey(tmp_path):
    grey = [np.full((H, W), 128, np.uint8)] * 6
    for name, encoder in (("g.avi", None), ("g.mp4", "opencv")):
        p = write_video(tmp_path / name, grey, 30.0, (W, H), encoder=encoder)
        arr, fps = read_video(p)
        assert arr.shape == (6, H, W, 3) and fps == pytest.approx(30.0)
        assert abs(float(arr.mean()) - 128) < 4
    assert sorted(f.name for f in tmp_path.iterdir()) == ["g.avi", "g.mp4"]  # no temp files left


def test_writer_is_atomic(tmp_path):
    p = tmp_path / "a.mp4"
    w = VideoWriter(p, 30.0, (W, H))
    w.write(_frames(1)[0])
    assert not p.exists()
    w.abort()
    assert not p.exists() and list(tmp_path.iterdir()) == []
    with pytest.raises(InputValueError, match="no frames"):
        write_video(p, [], 30.0, (W, H))
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputValueError, match="80x60"):
        with VideoWriter(p, 30.0, (W, H)) as w:
            w.write(np.zeros((60, 80, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


# -- H.264 by default (issue 14, item 1) ---------------------------------------------------
def test_pyav_is_a_core_dependency():
    """MP4 output is H.264 (which browsers play) for every install, not only with an extra."""
    tomllib = pytest.importorskip("tomllib")
    from pathlib import Path

    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    if not pyproject.exists():
        pytest.skip("not a source checkout")
    project = tomllib.loads(pyproject.read_text())["project"]
    assert any(d.replace(" ", "").startswith("av>=") for d in project["dependencies"])
    assert project["optional-dependencies"]["video"] == []  # kept: pip install "mlplc2[video]" works


def test_mp4_is_h264(tmp_path):
    av = pytest.importorskip("av")
    p = write_video(tmp_path / "h.mp4", _frames(4), 30.0)
    with av.open(str(p)) as c:
        assert c.streams.video[0].codec_context.name == "h264"


@pytest.mark.parametrize("why", ["no PyAV", "no libx264"])
def test_mp4_falls_back_to_opencv_with_one_warning(tmp_path, monkeypatch, why):
    import sys
    import warnings

    from mlplc2.io import VideoCodecWarning

    if why == "no PyAV":
        monkeypatch.setitem(sys.modules, "av", None)  # import av -> ImportError
        expect = "PyAV is not installed"
    else:
        av = pytest.importorskip("av")

        def no_codec(name, mode="r"):
            raise av.codec.codec.UnknownCodecError(name)

        monkeypatch.setattr(av.codec, "Codec", no_codec)
        expect = "PyAV's FFmpeg has no H.264 encoder"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        p = write_video(tmp_path / "f.mp4", _frames(6), 30.0)
    assert [str(w.message) for w in caught if w.category is VideoCodecWarning] == [
        f"f.mp4: written as MP4 'mp4v' by OpenCV, which browsers do not play, not H.264: {expect}"
        + (" (pip install av)" if why == "no PyAV" else " (UnknownCodecError: libx264)")]
    assert len(caught) == 1
    arr, _ = read_video(p)
    assert arr.shape == (6, H, W, 3)


# -- atomic writes (mlplc2._files) --------------------------------------------------
def test_atomic_writes_from_many_threads_to_one_path_never_collide(tmp_path):
    """Each writer gets its own temporary file (mkstemp), so the final file is always one
    writer's whole text, never a mix, and no temporary file is left behind."""
    from concurrent.futures import ThreadPoolExecutor

    from mlplc2._files import write_text

    path = tmp_path / "out.json"
    texts = [str(i) * 20000 for i in range(10)]
    with ThreadPoolExecutor(8) as ex:
        list(ex.map(lambda s: write_text(path, s), texts * 4))
    assert path.read_text() in texts
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_a_failed_atomic_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    from mlplc2._files import atomic_path

    path = tmp_path / "fields.json"
    path.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            tmp.write_text("half")
            raise RuntimeError("disk full")
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["fields.json"]


def test_atomic_files_get_the_usual_mode(tmp_path):
    import os
    import stat

    from mlplc2._files import write_text

    write_text(tmp_path / "a.txt", "x")
    (tmp_path / "b.txt").write_text("x")
    mode = lambda name: stat.S_IMODE(os.stat(tmp_path / name).st_mode)  # noqa: E731
    assert mode("a.txt") == mode("b.txt")
