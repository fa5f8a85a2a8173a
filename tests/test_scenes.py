"""Sec. IV-B: multi-object scenes on a scrolling background (Fig. 4 and Fig. 5 designs),
generated here and, when present, the paper's own videos. One parameter set throughout.

A cross-cutting suite of the paper's results (the sibling of ``test_selectivity.py``): the
LPLC2 family (mlplc2.models.lplc2) on scenes of mlplc2.stimuli, localisation scored by
mlplc2.evaluation.match against mlplc2.evaluation.truth."""

from __future__ import annotations

import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.evaluation import truth
from mlplc2.evaluation.match import false_alarms, fields_near, first_field
from mlplc2.evaluation.record import record

from .conftest import read_gray

MAX_LATENCY = 7   # frames from approach onset to the field (paper: "within 7 frames")
MAX_ERROR = 10.0  # px between field centre and true centre


def check_localisation(frames, objects, fps=30.0):
    """mLPLC2 on ``frames``; every approaching object of ``objects`` (ObjectTruth) gets a field
    in time and in place, and no alarm is false (the paper's rules, mlplc2.evaluation.match)."""
    rec = record(mlplc2.MLPLC2(fps=fps), frames)
    for o in objects:
        if not o.approach:
            continue
        hit = first_field(rec, o)
        assert hit is not None, f"object {o.id} at {o.center} got no field"
        _, latency, error = hit
        assert latency <= MAX_LATENCY, f"object {o.id}: field after {latency} frames"
        assert error <= MAX_ERROR, f"object {o.id}: field {error:.1f} px from centre"
    assert false_alarms(rec, objects) == []
    return rec


def paper_objects(paper_dir, name):
    return truth.load(paper_dir / "ground_truth.json")[name].objects


@pytest.fixture(scope="module")
def four_phase():
    return stimuli.four_phase(seed=0)


@pytest.fixture(scope="module")
def six_objects():
    return stimuli.six_objects(seed=0)


def test_four_phase_generated(four_phase):
    rec = check_localisation(four_phase.frames, four_phase.objects)
    # Every approaching object raises an alarm on its own field.
    alarmed = {f.id for f in rec.alarmed()}
    assert len(alarmed) >= 5
    assert len(rec.fields) <= 20  # few spurious fields (the authors' code: 84)


def test_six_objects_generated(six_objects):
    check_localisation(six_objects.frames, six_objects.objects)


def phase_peaks(model_name, frames):
    model = mlplc2.get_model(model_name)(fps=30.0)
    resp = [model.step(f).response for f in frames]
    return [max(resp[k * 100:k * 100 + 100]) for k in range(4)]


def test_slplc2_silent_for_two_simultaneous_objects(four_phase):
    peaks = phase_peaks("slplc2", four_phase.frames)
    assert peaks[0] > 0
    assert peaks[3] < 0.05 * peaks[0]


def test_lplc2_answers_only_the_central_object(four_phase):
    peaks = phase_peaks("lplc2", four_phase.frames)
    assert peaks[0] > 0
    assert peaks[2] < 0.05 * peaks[0] and peaks[3] < 0.05 * peaks[0]


def test_lplc2_silent_on_off_centre_object():
    """A single object in a corner does not drive the frame-centred LPLC2."""
    st = stimuli.scene([stimuli.SceneObject(center=(240, 60), onset=0)], frames=60, seed=3)
    model = mlplc2.LPLC2(fps=30.0)
    centred = stimuli.scene([stimuli.SceneObject(center=(160, 120), onset=0)], frames=60, seed=3)
    off = max(model.step(f).response for f in st.frames)
    model.reset()
    on = max(model.step(f).response for f in centred.frames)
    assert on > 0 and off < 0.25 * on


def test_no_alarm_without_approach():
    """A scrolling background with a receding object only: no collision alarm at all."""
    st = stimuli.scene([stimuli.SceneObject(center=(160, 120), onset=0, approach=0, hold=20,
                                            recede=40)], frames=80, seed=5)
    model = mlplc2.MLPLC2(fps=30.0)
    assert not any(model.step(f).collision for f in st.frames)


@pytest.mark.paper
def test_paper_four_phase(paper_dir):
    name = "scenes/outdoor_2_black_4_period.avi"
    rec = check_localisation(read_gray(paper_dir / name), paper_objects(paper_dir, name))
    assert len(rec.fields) < 84  # the authors' code created 84 fields


@pytest.mark.paper
def test_paper_six_objects(paper_dir):
    """Localisation, and the extra fields as docs/model.md "Measured behaviour" describes them:
    one field per object raises the alarm; the fields on no object raise none, and all but
    one of them never answer (that one answers the edge of object 1 below the alarm level;
    the docs once said none of them answers)."""
    name = "scenes/outdoor_3_black_expand_multi_6.avi"
    objects = paper_objects(paper_dir, name)
    rec = check_localisation(read_gray(paper_dir / name), objects)
    born = rec.fields
    on_objects = {f.id for o in objects for f in fields_near(born.values(), o, *o.approach)}
    extra = [fid for fid in born if fid not in on_objects]
    peak = {fid: f.peak for fid, f in born.items()}
    alarmed = {f.id for f in rec.alarmed()}
    assert len(born) - len(extra) == len(objects) == 6 and alarmed == set(born) - set(extra)
    answering = [fid for fid in extra if peak[fid] > 0]
    assert len(extra) == 6 and len(answering) == 1, {fid: peak[fid] for fid in extra}
    assert 0 < peak[answering[0]] < mlplc2.Params().alarm_threshold / mlplc2.Params().alarm_window


@pytest.mark.paper
def test_paper_four_phase_baselines(paper_dir):
    frames = read_gray(paper_dir / "scenes/outdoor_2_black_4_period.avi")
    s = phase_peaks("slplc2", frames)
    assert s[3] < 0.05 * max(s)
    lp = phase_peaks("lplc2", frames)
    assert lp[0] > 0 and max(lp[2], lp[3]) < 0.05 * lp[0]
