"""Robustness (issue 7): bad frames and files get one clear error, nothing computed is
lost, outputs stay finite and bounded on any input, memory stays flat on long runs.

* API input checks of ``Model.step`` (the full table of bad inputs and the scaling of
  the accepted dtypes); the per-model contract is in ``test_contract.py``.
* CLI input checks that ``test_cli.py`` does not already cover (it has: missing file,
  folder without images, text file named .mp4, unknown model, bad/zero ``--resize``,
  ``--resize`` with ``--scale``, ``--end`` before ``--start``, no source, bad ``--fps``,
  a truncated AVI, Ctrl-C via an in-process ``KeyboardInterrupt``). Here: zero-frame
  and one-frame videos, frames smaller than the models' minimum, a corrupt or
  differently sized image inside a sequence, a real SIGINT to the console script.
* Numerical safety with Hypothesis: random sequences of noise, constant frames,
  black/white flashes, extreme contrast and out-of-range values.
* A 20 000-frame run of MLPLC2 with flat memory and bounded field history.
"""

from __future__ import annotations

import csv
import gc
import json
import math
import os
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mlplc2
from mlplc2 import InputError, Params
from mlplc2._validation import InputTypeError, InputValueError, as_gray
from mlplc2.cli import main
from mlplc2.io import write_video
from mlplc2.models import REGISTRY
from mlplc2.models.lplc2 import _LPLC2Family
from mlplc2.runner import COLUMNS

from .helpers import check_outputs_agree

NAMES = sorted(REGISTRY)
LPLC2_FAMILY = [n for n in NAMES if issubclass(REGISTRY[n], _LPLC2Family)]
H, W = 48, 64


# =============================================================================
# API input checks: every bad frame, its exception class and its exact message
# =============================================================================
def _masked():
    return np.ma.masked_array(np.zeros((H, W)), mask=np.eye(H, W, dtype=bool))


#: name -> (frame factory, exception class, exact message). The table of the issue's note.
BAD_FRAMES = {
    "1-D": (lambda: np.zeros(W, np.uint8), InputValueError,
            "frame must be 2-D (H, W) or 3-D (H, W, C), got shape (64,)"),
    "4-D (a batch)": (lambda: np.zeros((2, H, W, 3), np.uint8), InputValueError,
                      "frame must be 2-D (H, W) or 3-D (H, W, C), got shape (2, 48, 64, 3)"),
    "0-D scalar": (lambda: np.float64(7.0), InputValueError,
                   "frame must be 2-D (H, W) or 3-D (H, W, C), got shape ()"),
    "2 channels": (lambda: np.zeros((H, W, 2), np.uint8), InputValueError,
                   "frame must have 1, 3 (RGB) or 4 (RGBA) channels, got 2 (shape (48, 64, 2))"),
    "5 channels": (lambda: np.zeros((H, W, 5), np.uint8), InputValueError,
                   "frame must have 1, 3 (RGB) or 4 (RGBA) channels, got 5 (shape (48, 64, 5))"),
    "channels first": (lambda: np.zeros((3, H, W), np.uint8), InputValueError,
                       "frame must have 1, 3 (RGB) or 4 (RGBA) channels, got 64 (shape (3, 48, 64)); "
                       "channels-first? use np.moveaxis(frame, 0, -1)"),
    "2x2 (too small)": (lambda: np.zeros((2, 2), np.uint8), InputValueError,
                        "frame is 2x2 pixels; the model needs at least 3x3"),
    "1 row": (lambda: np.zeros((1, W), np.uint8), InputValueError,
              "frame is 64x1 pixels; the model needs at least 3x3"),
    "0x0 RGB": (lambda: np.zeros((0, 0, 3), np.uint8), InputValueError,
                "frame is 0x0 pixels; the model needs at least 3x3"),
    "NaN pixel": (lambda: np.where(np.eye(H, W, dtype=bool), np.nan, 100.0), InputValueError,
                  "frame contains NaN or infinite pixels"),
    "+inf pixel": (lambda: np.where(np.eye(H, W, dtype=bool), np.inf, 100.0), InputValueError,
                   "frame contains NaN or infinite pixels"),
    "-inf float16 RGB": (lambda: np.full((H, W, 3), -np.inf, np.float16), InputValueError,
                         "frame contains NaN or infinite pixels"),
    "masked pixels": (_masked, InputValueError,
                      "frame is a masked array with masked pixels; fill them first (e.g. frame.filled(0))"),
    "bool": (lambda: np.ones((H, W), bool), InputTypeError,
             "frame has dtype bool, which is ambiguous (0/1 or 0/255); convert it first, "
             "e.g. frame.astype(np.uint8) * 255"),
    "object": (lambda: np.zeros((H, W), object), InputTypeError,
               "frame must have a numeric dtype (uint8, uint16, other integers or float), got object"),
    "str array": (lambda: np.full((H, W), "a"), InputTypeError,
                  "frame must have a numeric dtype (uint8, uint16, other integers or float), got <U1"),
    "bytes array": (lambda: np.full((H, W), b"a"), InputTypeError,
                    "frame must have a numeric dtype (uint8, uint16, other integers or float), got |S1"),
    "complex": (lambda: np.zeros((H, W), complex), InputTypeError,
                "frame must have a numeric dtype (uint8, uint16, other integers or float), got complex128"),
    "datetime64": (lambda: np.zeros((H, W), "datetime64[s]"), InputTypeError,
                   "frame must have a numeric dtype (uint8, uint16, other integers or float), "
                   "got datetime64[s]"),
    "void": (lambda: np.zeros((H, W), "V4"), InputTypeError,
             "frame must have a numeric dtype (uint8, uint16, other integers or float), got |V4"),
    "None": (lambda: None, InputTypeError, "frame must be a numpy array of numbers, got NoneType"),
    "str": (lambda: "frame.png", InputTypeError, "frame must be a numpy array of numbers, got str"),
    "ragged list": (lambda: [[1, 2, 3], [4, 5]], InputTypeError,
                    "frame must be a numpy array of numbers, got list"),
    "dict": (lambda: {"a": 1}, InputTypeError, "frame must be a numpy array of numbers, got dict"),
}


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("case", list(BAD_FRAMES))
def test_bad_frame_message(name, case):
    factory, exc_type, message = BAD_FRAMES[case]
    model = REGISTRY[name]()
    with pytest.raises(exc_type) as info:
        model.step(factory())
    err = info.value
    assert isinstance(err, InputError) and isinstance(err, (ValueError, TypeError))
    assert isinstance(err, TypeError if exc_type is InputTypeError else ValueError)
    assert str(err) == message
    assert "\n" not in str(err)
    assert model.frame_index == 0


def test_bad_frame_errors_are_importable_from_the_package():
    assert mlplc2.InputError is InputError
    assert issubclass(InputValueError, InputError) and issubclass(InputValueError, ValueError)
    assert issubclass(InputTypeError, InputError) and issubclass(InputTypeError, TypeError)


# -- accepted dtypes and their scaling to 0-255 ---------------------------------------
def _gradient():
    x = np.linspace(0, 255, W)
    y = np.linspace(0, 1, H)[:, None]
    return np.round(x[None, :] * y).astype(np.uint8)  # every value 0..255 occurs somewhere


def test_as_gray_scaling():
    g8 = _gradient()
    ref = g8.astype(np.float32)
    out = as_gray(g8)
    assert out.dtype == np.float32 and out.flags.c_contiguous and np.array_equal(out, ref)
    # uint16: / 257 (65535 -> 255; 8-bit values v * 257 map back exactly)
    assert np.allclose(as_gray(g8.astype(np.uint16) * 257), ref, atol=1e-4)
    assert as_gray(np.full((3, 3), 65535, np.uint16)).max() == pytest.approx(255.0)
    # float: taken as 0-255 (not 0-1), clipped to [0, 255], any float width
    for dt in (np.float16, np.float32, np.float64, np.longdouble):
        assert np.array_equal(as_gray(g8.astype(dt)), ref), dt
    wild = np.array([[-1e300, -1.0, 0.0], [128.5, 255.0, 256.0], [1e30, 1e300, 3e38]])
    assert as_gray(wild).tolist() == [[0, 0, 0], [128.5, 255, 255], [255, 255, 255]]
    # other integers: taken as 0-255 and clipped
    for dt in (np.int8, np.int16, np.int32, np.int64, np.uint32, np.uint64):
        v = np.array([[-128 if np.dtype(dt).kind == "i" else 0, 0, 100], [127, 255, 1000], [2, 3, 4]])
        v = np.clip(v, np.iinfo(dt).min, np.iinfo(dt).max).astype(dt)
        assert as_gray(v).tolist() == np.clip(v.astype(np.float64), 0, 255).tolist(), dt
    # nested lists of numbers and masked arrays without masked pixels are fine
    assert np.array_equal(as_gray([[0, 128, 255]] * 3), np.array([[0, 128, 255]] * 3, np.float32))
    assert np.array_equal(as_gray(np.ma.masked_array(g8, mask=False)), ref)
    # RGB -> Rec. 601 luma; alpha ignored; (H, W, 1) is grey
    rgb = np.zeros((3, 3, 3), np.uint8)
    rgb[..., 0] = 255
    assert as_gray(rgb)[0, 0] == pytest.approx(0.299 * 255, rel=1e-6)
    rgba = np.concatenate([rgb, np.full((3, 3, 1), 7, np.uint8)], axis=-1)
    assert np.array_equal(as_gray(rgba), as_gray(rgb))
    assert np.array_equal(as_gray(g8[:, :, None]), ref)


def test_as_gray_returns_a_new_array():
    f = np.full((5, 5), 10.0, np.float32)
    g = as_gray(f)
    g += 1
    assert f[0, 0] == 10.0  # never a view of the input
    ro = np.full((5, 5, 3), 300.0)
    ro.flags.writeable = False
    assert as_gray(ro).max() == 255.0 and ro.max() == 300.0


@pytest.mark.parametrize("name", NAMES)
def test_equivalent_dtypes_give_identical_outputs(name):
    rng = np.random.default_rng(3)
    base = [cv2.GaussianBlur(rng.integers(0, 256, (H, W)).astype(np.uint8), (5, 5), 0) for _ in range(10)]

    def run(frames):
        m = REGISTRY[name]()
        return [m.step(f) for f in frames]

    ref = run(base)
    assert run([f.astype(np.float64) for f in base]) == ref
    assert run([f.astype(np.int64) for f in base]) == ref
    assert run([f.astype(np.float32) * 2.0 - 255.0 for f in base]) == run(
        [np.clip(f.astype(np.float32) * 2.0 - 255.0, 0, 255) for f in base])
    u16 = run([f.astype(np.uint16) * 257 for f in base])
    for a, b in zip(u16, ref):  # /257 in float32: equal up to rounding
        assert a.response == pytest.approx(b.response, rel=1e-3, abs=1e-3)


# =============================================================================
# CLI: what test_cli.py does not cover
# =============================================================================
def _noise_frames(n, w=W, h=H, seed=0):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def _one_line(err: str, kind: str = "error") -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"mlplc2: {kind}: "), err
    assert "Traceback" not in err
    return lines[0]


def _csv_rows(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        return header, [dict(zip(header, r)) for r in reader]


def _written(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir()) if out.exists() else []


def test_cli_zero_frame_video(tmp_path, capsys):
    p = tmp_path / "zero.avi"
    w = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 30, (W, H))
    w.release()
    out = tmp_path / "o"
    assert main(["run", str(p), "--out", str(out), "--quiet"]) == 2
    line = _one_line(capsys.readouterr().err)
    assert line == f"mlplc2: error: {p}: video has no frames (empty or undecodable)"
    assert _written(out) == []


def test_cli_zero_byte_file(tmp_path, capsys):
    p = tmp_path / "empty.mp4"
    p.write_bytes(b"")
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "not a video file" in _one_line(capsys.readouterr().err)
    assert _written(tmp_path / "o") == []


@pytest.mark.parametrize("n", [1, 2])
def test_cli_one_and_two_frame_videos_are_valid(tmp_path, capsys, n):
    """One frame has no motion (every model at rest) but is a valid input: exit 0, all outputs."""
    p = write_video(tmp_path / f"short{n}.avi", _noise_frames(n), 30.0)
    out = tmp_path / "o"
    models = ",".join(NAMES)
    assert main(["run", str(p), "--out", str(out), "--model", models, "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    written = _written(out)
    assert {"fields.json", "responses.csv", "responses.png"} <= set(written)
    assert not [name for name in written if name.startswith(".")]  # no temporary file left
    header, rows = _csv_rows(out / "responses.csv")
    assert header == list(COLUMNS)
    for name in NAMES:
        mine = [r for r in rows if r["model"] == name]
        assert sorted({int(r["frame"]) for r in mine}) == list(range(n))
        first = [r for r in mine if r["frame"] == "0"]
        rest = 0.5 if name.startswith("lgmd") else 0.0  # no change yet: at rest
        assert all(float(r["response"]) == rest and r["collision"] == "0" for r in first)
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == n and summary["complete"] and not summary["truncated"]


@pytest.mark.parametrize("how", ["images", "resize", "scale"])
def test_cli_frames_smaller_than_the_models_minimum(tmp_path, capsys, how):
    if how == "images":
        d = tmp_path / "tiny"
        d.mkdir()
        for i in range(3):
            cv2.imwrite(str(d / f"f{i}.png"), np.full((2, 2, 3), 40 * i, np.uint8))
        argv, expect = [str(d)], f"mlplc2: error: {d}: frames are 2x2 pixels; the models need at least 3x3"
    else:
        p = write_video(tmp_path / "v.avi", _noise_frames(4), 30.0)
        opt = ["--resize", "2x40"] if how == "resize" else ["--scale", "0.03"]
        size = "2x40" if how == "resize" else "2x1"
        argv = [str(p), *opt]
        expect = f"mlplc2: error: {p}: frames are {size} pixels after resizing; the models need at least 3x3"
    out = tmp_path / "o"
    assert main(["run", *argv, "--out", str(out), "--quiet"]) == 2
    assert _one_line(capsys.readouterr().err) == expect
    assert _written(out) == []  # checked before any output exists


def test_cli_corrupt_image_in_sequence_keeps_frames_before(tmp_path, capsys):
    d = tmp_path / "seq"
    d.mkdir()
    for i, f in enumerate(_noise_frames(8)):
        cv2.imwrite(str(d / f"f{i}.png"), f)
    (d / "f5.png").write_bytes(b"\x89PNG garbage")
    out = tmp_path / "o"
    assert main(["run", str(d), "--out", str(out), "--model", "mlplc2,lgmd2", "--quiet"]) == 2
    line = _one_line(capsys.readouterr().err, kind="warning")
    assert "f5.png" in line and "(frame 5)" in line
    summary = json.loads((out / "fields.json").read_text())
    assert summary["n_frames"] == 5 and summary["truncated"] and not summary["complete"]
    _, rows = _csv_rows(out / "responses.csv")
    assert sorted({int(r["frame"]) for r in rows}) == list(range(5))
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_cli_image_of_another_size_in_sequence(tmp_path, capsys):
    """Exit 2 and one line naming the image; the CSV holds whole rows for the frames before it."""
    d = tmp_path / "seq"
    d.mkdir()
    for i, f in enumerate(_noise_frames(6)):
        cv2.imwrite(str(d / f"f{i}.png"), f)
    cv2.imwrite(str(d / "f6.png"), np.zeros((H + 2, W, 3), np.uint8))
    out = tmp_path / "o"
    assert main(["run", str(d), "--out", str(out), "--model", "lgmd2", "--quiet"]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith(("mlplc2: error: ", "mlplc2: warning: "))
    assert "f6.png" in lines[0] and "64x50" in lines[0] and "64x48" in lines[0]
    header, rows = _csv_rows(out / "responses.csv")
    assert header == list(COLUMNS)
    assert [int(r["frame"]) for r in rows] == list(range(6))  # lgmd2: one row per frame


def test_cli_only_undecodable_images(tmp_path, capsys):
    d = tmp_path / "bad"
    d.mkdir()
    (d / "a.png").write_bytes(b"not a png")
    assert main(["run", str(d), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert _one_line(capsys.readouterr().err) == f"mlplc2: error: {d / 'a.png'}: not an image OpenCV can read"
    assert _written(tmp_path / "o") == []


@pytest.mark.parametrize("argv, expect", [
    (["--model", ""], "--model needs at least one model name"),
    (["--model", ",,"], "--model needs at least one model name"),
    (["--fps", "nan"], "argument --fps: expected a positive number, got 'nan'"),
    (["--fps", "inf"], "argument --fps: expected a positive number, got 'inf'"),
    (["--scale", "0"], "argument --scale: expected a positive number, got '0'"),
    (["--start", "-1"], "argument --start: expected an integer >= 0, got '-1'"),
    (["--start", "99"], "start frame 99 is past the end (4 frames)"),
    (["--end", "0"], "--end (0) must be larger than --start (0)"),
    (["--resize", "320x"], "bad --resize '320x': expected WxH with positive integers, e.g. 320x240"),
    (["--backend", "gstreamer"], "argument --backend: invalid choice: 'gstreamer'"),
])
def test_cli_more_bad_options(tmp_path, capsys, argv, expect):
    p = write_video(tmp_path / "v.avi", _noise_frames(4), 30.0)
    out = tmp_path / "o"
    assert main(["run", str(p), *argv, "--out", str(out), "--quiet"]) == 2
    assert expect in _one_line(capsys.readouterr().err)
    assert _written(out) == []


def test_cli_out_is_a_file(tmp_path, capsys):
    p = write_video(tmp_path / "v.avi", _noise_frames(4), 30.0)
    f = tmp_path / "taken"
    f.write_text("x")
    assert main(["run", str(p), "--out", str(f), "--quiet"]) == 2
    assert str(f) in _one_line(capsys.readouterr().err)
    assert f.read_text() == "x"


def _console_script() -> list[str]:
    exe = Path(sys.executable).with_name("mlplc2")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "mlplc2.cli"]


@pytest.mark.skipif(sys.platform == "win32", reason="signals to a child process are POSIX")
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_real_signal_leaves_valid_outputs(tmp_path, sig):
    """A real Ctrl-C (SIGINT), or SIGTERM as sent by `timeout` and batch schedulers, to the
    console script mid-run with the decoder thread busy: the frames done are saved.
    (test_cli.py raises KeyboardInterrupt in-process; this sends the signal.)"""
    n = 900
    p = write_video(tmp_path / "long.avi", _noise_frames(n, 160, 120), 30.0)
    out = tmp_path / "o"
    # SIGINT as in a terminal, even when pytest runs in the background (which ignores it, and
    # an ignored SIGINT is inherited: the run would not stop).
    proc = subprocess.Popen(_console_script() + ["run", str(p), "--out", str(out), "-m", "mlplc2,lgmd2",
                                                 "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    csv_path = out / "responses.csv"
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline:  # wait until it is inside the frame loop
            if csv_path.exists() and csv_path.stat().st_size > 3000:
                break
            if proc.poll() is not None:
                pytest.fail(f"finished before the interrupt: {proc.communicate()}")
            time.sleep(0.02)
        proc.send_signal(getattr(signal, sig))
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    summary = json.loads((out / "fields.json").read_text())
    k = summary["n_frames"]
    assert 0 < k < n and summary["interrupted"] and not summary["complete"]
    assert f"interrupted after {k} frames" in err
    header, rows = _csv_rows(csv_path)
    assert header == list(COLUMNS)
    assert all(len(r) == len(COLUMNS) and None not in r.values() for r in rows)
    for name in ("mlplc2", "lgmd2"):  # every processed frame complete, none beyond
        assert sorted({int(r["frame"]) for r in rows if r["model"] == name}) == list(range(k))
    assert [int(r["frame"]) for r in rows if r["model"] == "lgmd2"] == list(range(k))
    # the three outputs agree: no frame in responses.csv or targets.csv at or past n_frames
    assert check_outputs_agree(out, ["mlplc2", "lgmd2"]) == k
    assert not [q for q in out.iterdir() if q.name.startswith(".")]


# =============================================================================
# Numerical safety (Hypothesis)
# =============================================================================
KINDS = ("noise", "constant", "black", "white", "salt_pepper", "checker", "square", "stripes")


def _make_frame(kind: str, rng: np.random.Generator, h: int = H, w: int = W) -> np.ndarray:
    if kind == "noise":
        return rng.integers(0, 256, (h, w), dtype=np.uint8)
    if kind == "constant":
        return np.full((h, w), rng.integers(0, 256), np.uint8)
    if kind == "black":
        return np.zeros((h, w), np.uint8)
    if kind == "white":
        return np.full((h, w), 255, np.uint8)
    if kind == "salt_pepper":  # extreme contrast at every pixel
        return (rng.integers(0, 2, (h, w)) * 255).astype(np.uint8)
    if kind == "checker":
        s = int(rng.integers(1, 9))
        yy, xx = np.mgrid[0:h, 0:w]
        return (((yy + int(rng.integers(0, s))) // s + xx // s) % 2 * 255).astype(np.uint8)
    if kind == "square":
        f = np.full((h, w), rng.integers(100, 256), np.uint8)
        cx, cy, r = int(rng.integers(0, w)), int(rng.integers(0, h)), int(rng.integers(1, max(h, w)))
        f[max(cy - r, 0):cy + r + 1, max(cx - r, 0):cx + r + 1] = rng.integers(0, 60)
        return f
    if kind == "stripes":
        period = int(rng.integers(2, 16))
        phase = int(rng.integers(0, period))
        return np.tile(((np.arange(w) + phase) % period < period // 2) * np.uint8(255), (h, 1))
    raise AssertionError(kind)


def _encode(frame: np.ndarray, how: str) -> np.ndarray:
    """The same picture in another accepted dtype/layout."""
    if how == "uint16":
        return frame.astype(np.uint16) * 257
    if how == "float_wild":  # 0 -> huge negative, 255 -> huge positive: clipped back to 0 / 255
        f = frame.astype(np.float64)
        return np.where(frame == 0, -1e300, np.where(frame == 255, 1e300, f))
    if how == "rgb":
        return np.repeat(frame[:, :, None], 3, axis=2)
    return frame


@st.composite
def sequences(draw):
    seed = draw(st.integers(0, 2**32 - 1))
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=1, max_size=14))
    # flashes: runs of alternating black/white
    if draw(st.booleans()):
        at = draw(st.integers(0, len(kinds)))
        kinds[at:at] = ["black", "white"] * draw(st.integers(1, 3))
    how = draw(st.sampled_from(["uint8", "uint16", "float_wild", "rgb"]))
    return seed, kinds, how


STATIC = 40  # frames of a static scene after which every model must be silent


def _check_output(name, model, out, shape):
    h, w = shape
    assert math.isfinite(out.response)
    _check_targets(out)
    if name in LPLC2_FAMILY:
        assert out.response >= 0
        assert len(out.fields) <= model.params.max_fields
        assert len({f.id for f in out.fields}) == len(out.fields)
        for f in out.fields:
            assert 0 <= f.x < w and 0 <= f.y < h, (f.x, f.y)
            assert math.isfinite(f.response) and f.response >= 0
            assert all(math.isfinite(q) for q in f.quadrants)
        assert out.response == max((f.response for f in out.fields), default=0.0)
        for k in ("r", "l", "d", "u", "magnitude"):
            assert np.isfinite(getattr(model.maps, k)).all()
    elif REGISTRY[name].has_targets:       # the optical-flow baseline: the largest expansion rate (1/s)
        assert out.response >= 0 and out.fields == ()
    else:
        assert 0.5 <= out.response <= 1.0  # sigmoid membrane potential, resting 0.5
        assert out.fields == ()
        assert all(math.isfinite(v) for v in model.state.values() if isinstance(v, float))


def _check_targets(out):
    for t in out.targets:                  # target estimates: finite where present
        for k in ("x", "y", "width", "height", "ttc_s", "miss", "expansion", "ttc_sigma_s"):
            v = getattr(t, k)
            assert v is None or math.isfinite(v), (k, v)
        assert t.width > 0 and t.height > 0
        assert t.ttc_s is None or t.ttc_s > 0
        assert not t.warning or (t.ttc_s is not None and t.miss is not None)


def _run_and_settle(name, frames, params=None):
    model = REGISTRY[name]() if params is None else REGISTRY[name](params=params)
    shape = frames[0].shape[:2]
    for f in frames:
        _check_output(name, model, model.step(f), shape)
    # return to silence on a static scene (the last frame held)
    tail = [model.step(frames[-1]) for _ in range(STATIC)]
    for out in tail:
        _check_output(name, model, out, shape)
    for out in tail[-(STATIC - 15):]:  # the last 25 of the 40 static frames
        assert not out.collision and not out.spike and not out.warning
        if name in LPLC2_FAMILY or REGISTRY[name].has_targets:
            assert out.response == 0.0     # no field answers (LPLC2); nothing expands (flow)
        else:
            assert out.response == 0.5
    if name in LPLC2_FAMILY:
        assert float(model.maps.magnitude.max()) == 0.0  # no motion left anywhere
        if name == "mlplc2":
            assert len(tail[-1].fields) <= 1  # Eq. 16 removed every silent field but the last
    return model


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(sequences())
def test_every_model_finite_bounded_and_settles(seq):
    seed, kinds, how = seq
    rng = np.random.default_rng(seed)
    frames = [_encode(_make_frame(k, rng), how) for k in kinds]
    for name in NAMES:
        _run_and_settle(name, frames)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(5, 30), max_fields=st.integers(1, 4),
       r_af=st.integers(2, 12))
def test_mlplc2_field_count_bounded_with_small_fields(seed, n, max_fields, r_af):
    """Small fields and a low T_a make many candidates; max_fields must still hold."""
    rng = np.random.default_rng(seed)
    params = Params(max_fields=max_fields, r_af=r_af, t_a=0.5, grace=2, d=3)
    frames = [_make_frame(str(rng.choice(["noise", "salt_pepper", "checker", "square"])), rng)
              for _ in range(n)]
    _run_and_settle("mlplc2", frames, params)


@settings(max_examples=15, deadline=None)
@given(h=st.integers(3, 12), w=st.integers(3, 12), seed=st.integers(0, 2**32 - 1))
def test_tiny_frames_are_numerically_safe(h, w, seed):
    """Frames down to the 3x3 minimum, far smaller than the filter windows and R_AF."""
    rng = np.random.default_rng(seed)
    frames = [_make_frame(k, rng, h, w) for k in ("noise", "salt_pepper", "black", "white", "noise")]
    for name in NAMES:
        _run_and_settle(name, frames)


# =============================================================================
# Long runs: flat memory, bounded history
# =============================================================================
def _long_stream(n: int, h: int = 48, w: int = 64, seed: int = 0):
    """A scrolling texture with noise and a dark square looming at changing places (cheap)."""
    rng = np.random.default_rng(seed)
    tex = rng.integers(100, 200, (h, w), dtype=np.uint8).astype(np.int16)
    tex = (tex + np.roll(tex, 1, 1) + np.roll(tex, 1, 0)) // 3
    noise = [rng.integers(-6, 7, (h, w)).astype(np.int16) for _ in range(7)]
    centres = [(w // 4, h // 4), (3 * w // 4, h // 4), (w // 4, 3 * h // 4), (3 * w // 4, 3 * h // 4),
               (w // 2, h // 2)]
    for i in range(n):
        f = np.roll(tex, i % w, axis=1) + noise[i % 7]
        k = i % 40
        if k < 24:
            cx, cy = centres[(i // 40) % len(centres)]
            f[max(cy - k - 1, 0):cy + k + 2, max(cx - k - 1, 0):cx + k + 2] = 15
        yield np.clip(f, 0, 255).astype(np.uint8)


def _rss_bytes() -> int | None:
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def _check_bounded(model) -> None:
    p = model.params
    assert len(model._fields) <= p.max_fields
    for f in model._fields:
        assert f.history.maxlen == max(p.d, p.alarm_window)
        assert len(f.history) <= f.history.maxlen


@pytest.mark.slow
def test_long_run_flat_memory_and_bounded_history():
    """20 000 frames through MLPLC2 (hundreds of fields born and removed on the way).

    tracemalloc costs about 4x per frame, so it traces two windows of 1 200 frames, early
    and late: the live Python/NumPy memory may grow neither within a window nor from one
    window to the other by more than 64 KiB (about 50 bytes a frame; one 64x48 float32 map
    is 12 KiB; measured 2-3 KiB; keeping each frame's Output alive grows it by ~500 KiB).
    RSS is cheap, covers all 20 000 frames and the native allocations tracemalloc cannot
    see (numba, OpenCV internals): < 16 MiB growth after warm-up. The field
    list and every field's history stay within their settings (max_fields, max(d,
    alarm_window))."""
    n = 20_000
    windows = [(1_000, 2_200), (18_700, 19_900)]
    settle = 200  # frames into a window before its baseline (all live state re-allocated while traced)
    model = mlplc2.MLPLC2(fps=30.0)
    base: dict[int, int] = {}
    ends: list[int] = []
    peaks: list[int] = []
    rss0 = rss1 = None
    max_fields = max_hist = last_id = alarms = 0
    assert not tracemalloc.is_tracing()
    try:
        for i, frame in enumerate(_long_stream(n)):
            for w0, w1 in windows:
                if i == w0:
                    gc.collect()
                    tracemalloc.start()
                elif i == w0 + settle:
                    gc.collect()
                    base[w0] = tracemalloc.get_traced_memory()[0]
                    tracemalloc.reset_peak()
                elif i == w1:
                    gc.collect()
                    cur, peak = tracemalloc.get_traced_memory()
                    ends.append(cur - base[w0])
                    peaks.append(peak)
                    tracemalloc.stop()
            if i == 2_000:
                rss0 = _rss_bytes()
            out = model.step(frame)
            max_fields = max(max_fields, len(out.fields))
            alarms += out.collision
            for f in out.fields:
                last_id = max(last_id, f.id)
            if i % 1000 == 0:
                _check_bounded(model)
                max_hist = max([max_hist] + [len(f.history) for f in model._fields])
        gc.collect()
        rss1 = _rss_bytes()
    finally:
        tracemalloc.stop()
    print(f'\nlong run: last id {last_id}, alarms {alarms}, window growth {ends}, baselines {base}, '
          f'peaks {peaks}, rss {rss0} -> {rss1}')
    assert model.frame_index == n
    _check_bounded(model)
    assert max_fields <= model.params.max_fields
    assert max_hist <= max(model.params.d, model.params.alarm_window)
    assert last_id > 200, last_id  # many fields were born and removed during the run
    kib = 1024
    assert len(ends) == len(base) == 2
    assert all(abs(g) < 64 * kib for g in ends), ends  # flat within each traced window
    assert abs(base[windows[1][0]] - base[windows[0][0]]) < 64 * kib, base  # and late == early
    assert max(peaks) < 4 * 1024 * kib, peaks  # live memory of the model itself stays small
    if rss0 is not None and rss1 is not None:
        assert rss1 - rss0 < 16 * 1024 * kib, (rss0, rss1)


def test_history_cap_is_a_setting():
    """The per-field history is max(d, alarm_window) long and the field count max_fields."""
    p = Params(d=3, alarm_window=7, max_fields=2, r_af=6, t_a=0.5, grace=1, t_d=0.0)
    model = mlplc2.MLPLC2(params=p)
    seen = 0
    for frame in _long_stream(300):
        out = model.step(frame)
        assert len(out.fields) <= 2
        seen = max(seen, len(out.fields))
        _check_bounded(model)
        assert all(f.history.maxlen == 7 for f in model._fields)
    assert seen == 2
    assert max(len(f.history) for f in model._fields) == 7
