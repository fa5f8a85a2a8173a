"""``TargetParams.heading`` is in the pixels of the input, as every output (issue 22, session 18, ux9).

``mlplc2.run`` reduces a video wider than the models' working width (320 px) in its decoding thread,
and ``--resize`` resizes it before the models: the heading given must still mean the same point of the
input. A looming square off the frame's centre, written at 320x240 and at twice that size (each pixel
a 2x2 block: the working frames are the same), with the heading at the square's centre: the same
targets, warnings and courses (``miss``) at both sizes, through ``mlplc2.run`` and a model stepped by
hand alike; before the fix the 640x480 run read the heading in working pixels (far outside the
frame) and its courses missed.
"""

from __future__ import annotations

import csv
import re
import warnings

import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.cli import main
from mlplc2.targets import TargetParams

CENTRE = (200.0, 150.0)          # the square's centre at 320x240 (px); the principal point is (159.5, 119.5)


def _twice(x: float) -> float:
    """A 320x240 pixel coordinate at 640x480 (pixel centres onto pixel centres)."""
    return 2 * x + 0.5


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    stim = stimuli.looming(size=(320, 240), center=CENTRE, contact_time=1.6, duration=1.6,
                           background="procedural", fps=30.0)
    frames = [np.asarray(f, dtype=np.uint8) for f in stim.frames]
    d = tmp_path_factory.mktemp("heading")
    for name, scale in (("small", 1), ("large", 2)):
        (d / name).mkdir()
        for i, f in enumerate(frames):
            img = f if scale == 1 else cv2.resize(f, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
            cv2.imwrite(str(d / name / f"{i:04d}.png"), img)
    return d, frames


def _rows(result, scale=1):
    """(frame, target id, warning, miss, x, y) of every target row, x and y at 320x240."""
    return [(int(r["frame"]), int(r["target_id"]), str(r["warning"]) in ("True", "1"),
             None if r["miss"] in (None, "") else round(float(r["miss"]), 3),
             round((float(r["x"]) + 0.5) / scale - 0.5, 1), round((float(r["y"]) + 0.5) / scale - 0.5, 1))
            for r in result.targets]


def _run(path, heading, model="mlplc2", **kw):
    return mlplc2.run(str(path), [model], out=False, quiet=True, progress=False, plot=False,
                      target_params={"heading": heading}, **kw)


@pytest.mark.parametrize("model", ["mlplc2", "flow"])
def test_a_heading_in_input_pixels_means_the_same_point_at_twice_the_size(clips, model):
    d, _ = clips
    small = _rows(_run(d / "small", CENTRE, model))
    large = _rows(_run(d / "large", (_twice(CENTRE[0]), _twice(CENTRE[1])), model), scale=2)
    assert any(w for _, _, w, *_ in small)                   # the square warns, on its own course
    assert large == small


def test_the_heading_is_the_same_point_for_run_and_for_a_model_stepped_by_hand(clips):
    """The model reduces the 640x480 frames itself when stepped by hand, ``mlplc2.run`` in its decoding
    thread: the heading at the square's centre in the input's pixels gives the same targets (every frame
    stepped: ``run``'s look at the first frames for duplicates, ``prime_repeats``, is not the point here)."""
    d, frames = clips
    heading = (_twice(CENTRE[0]), _twice(CENTRE[1]))
    model = mlplc2.MLPLC2(fps=30.0, target_params=TargetParams(heading=heading), repeat_threshold=None)
    by_hand = []
    for f in frames:
        out = model.step(cv2.resize(f, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST))
        by_hand += [(out.frame, t.id, t.warning) for t in out.targets]
    run = [(f, i, w) for f, i, w, *_ in _rows(_run(d / "large", heading, repeat_threshold=None))]
    assert run == by_hand and any(w for *_, w in run)


def test_a_resized_run_reads_the_heading_in_the_input_pixels(clips):
    """``resize`` to 320x240 (the models' frames) takes the heading in the 640x480 input's pixels too."""
    d, _ = clips
    heading = (_twice(CENTRE[0]), _twice(CENTRE[1]))
    resized = _rows(_run(d / "large", heading, resize=(320, 240)), scale=2)
    small = _rows(_run(d / "small", CENTRE))
    assert [(f, i, w) for f, i, w, *_ in resized] == [(f, i, w) for f, i, w, *_ in small]


def test_run_takes_a_heading_and_refuses_a_bad_one(clips, tmp_path, capsys):
    d, _ = clips
    for bad in ("1", "x,2", "1,2,3", "nan,1"):
        assert main(["run", str(d / "small"), "--heading", bad, "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err
        assert "--heading" in err and "expected X,Y" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "bad").exists()
    out = tmp_path / "given"
    assert main(["run", str(d / "large"), "--heading", f"{_twice(CENTRE[0])},{_twice(CENTRE[1])}",
                 "--out", str(out), "-q"]) == 0
    with open(out / "targets.csv", newline="") as fh:
        written = [(int(r["frame"]), r["warning"] == "1") for r in csv.DictReader(fh)]
    direct = _rows(_run(d / "large", (_twice(CENTRE[0]), _twice(CENTRE[1]))))
    assert written == [(f, w) for f, _, w, *_ in direct] and any(w for _, w in written)


def test_a_heading_left_of_the_frame_is_given_as_any_other(clips, tmp_path, capsys):
    """``--heading -5,10`` (a new user's try: argparse took ``-5,10`` for an option, "expected one argument") is the
    heading (-5, 10), as ``--heading=-5,10`` is: the same targets, and the warning that it lies outside the frame."""
    d, _ = clips
    rows = []
    for args in (["--heading", "-5,10"], ["--heading=-5,10"], ["--heading", "-.5,10"]):
        out = tmp_path / f"h{len(rows)}"
        with warnings.catch_warnings():
            warnings.simplefilter("always")            # the command's own line on stderr, not the suite's error
            assert main(["run", str(d / "small"), *args, "--out", str(out), "-q"]) == 0
        assert re.search(r"the heading \(-0?\.?5, 10\) lies outside", capsys.readouterr().err)
        rows.append((out / "targets.csv").read_text())
    assert rows[0] == rows[1]
    assert main(["run", str(d / "small"), "--heading", "--out", str(tmp_path / "none")]) == 2   # no value: one line
    assert "--heading: expected one argument" in capsys.readouterr().err
