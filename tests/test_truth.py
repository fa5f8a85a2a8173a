"""mlplc2.evaluation.truth as the one ground-truth type: what the stimulus generators emit, what they write
and what the loader reads back."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from mlplc2 import stimuli as S
from mlplc2.evaluation import truth
from mlplc2.stimuli import world as approach

#: ``to_ground_truth()`` of every case below, recorded with the code before the generators
#: emitted :class:`mlplc2.evaluation.truth.ObjectTruth` (commit 278bca0, when they had their own truth
#: types): the JSON they write must not change.
FIXTURE = Path(__file__).parent / "fixtures" / "generator_truth.json"


def _cases():
    out = {name: (lambda name=name: S.generate(name, size=40, frames=12)) for name in S.BASIC_NAMES}
    out["four_phase"] = lambda: S.four_phase(approach=6, hold=3, recede=5, background="plain")
    out["six_objects"] = lambda: S.six_objects(background="plain")
    out["looming"] = lambda: S.looming(size=(64, 48), contact_time=0.5, duration=0.6)
    out["scene"] = lambda: S.scene([S.SceneObject(center=(20.5, 12.0), onset=1, approach=4, hold=2, recede=3,
                                                  polarity="bright"),
                                    S.SceneObject(center=(40.0, 30.0), onset=0, approach=5, hold=1, recede=4,
                                                  looming="physical", half_size=0.2, speed=4.0, contact_frame=7.5)],
                                   size=(64, 48), frames=12, background="plain")
    out["approach_mixed"] = lambda: S.generate("approach", kind="mixed", n_objects=5, size=(48, 36),
                                               duration_s=0.4, supersample=1)
    out["approach_pan"] = lambda: S.random_scene(3, size=(48, 36), camera="pan", background="plain", fps=10.0,
                                                 duration_s=2.0, supersample=1)
    return out


CASES = _cases()


@pytest.fixture(scope="module")
def generated():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # objects never in view at these small sizes
        return {name: make() for name, make in CASES.items()}


def test_every_case_is_recorded():
    assert set(json.loads(FIXTURE.read_text())) == set(CASES)


@pytest.mark.parametrize("name", sorted(CASES))
def test_generators_write_the_json_they_wrote_before(generated, name):
    """Byte for byte (key order, ints against floats) the JSON of the generators' own truth types."""
    recorded = json.loads(FIXTURE.read_text())[name]
    gt = generated[name].to_ground_truth()
    assert json.dumps(gt) == json.dumps(recorded)
    # and in the documented layout: docs/stimuli.md for 3-D entries, ground_truth.json otherwise
    three_d = name.startswith("approach")
    assert list(gt) == ["size", "frames", "fps"] + (["camera", "background"] if three_d else []) + ["objects"]
    layout = list(truth.OBJECT_LAYOUTS["3d" if three_d else "2d"]) + ["track_columns", "track", "sizes"]
    for obj in gt["objects"]:
        assert list(obj) == [k for k in layout if k in obj], obj.keys()
        if three_d:
            assert {"contact_frame", "miss", "approach", "track"} <= set(obj)
            assert obj["track_columns"] == list(truth.TRACK_COLUMNS)
        else:
            assert "sizes" in obj and "polarity" in obj


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_loader_reads_back_what_the_generators_write(generated, name, tmp_path):
    stim = generated[name]
    assert all(type(o) is truth.ObjectTruth for o in stim.objects)
    loaded = truth.load(json.loads(json.dumps(stim.to_ground_truth())))["*"]
    assert loaded.objects == stim.objects
    assert loaded.to_dict() == stim.to_ground_truth() and loaded.size == stim.size
    # through a file written by truth.save, under a key
    path = truth.save(truth.GroundTruth({"v.avi": stim.truth()}), tmp_path / "gt.json")
    again = truth.load(path)["v.avi"]
    assert again.objects == stim.objects and again.camera == stim.truth().camera


def test_one_object_type_under_every_name():
    assert S.ObjectTruth is truth.ObjectTruth and approach.ObjectTrack is truth.ObjectTruth
    assert S.ObjectTrack is truth.ObjectTruth


def test_track_points_are_rows():
    """A track point unpacks as a row of TRACK_COLUMNS (the 3-D generator's rows were tuples)."""
    p = truth.TrackPoint(3, 1.5, 2.0, 4.0, 5.0, 0.5, 0.1)
    frame, x, y, *_, ttc, miss = p
    assert (frame, x, y, ttc, miss) == (3, 1.5, 2.0, 0.5, 0.1) and p[3] == p.width == 4.0
    assert p._asdict() == dict(zip(truth.TRACK_COLUMNS, p))
