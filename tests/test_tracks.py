"""mlplc2.evaluation.tracks as the one recorder, matcher and false-alarm rule of the edge code."""

from __future__ import annotations

import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.evaluation import tracks, truth
from mlplc2.neuropils.attention import Field
from mlplc2.evaluate import evaluate
from mlplc2.runner import RunResult
from mlplc2.evaluation.tracks import match_fields

OBJ = truth.ObjectTruth(id=1, center=(50.0, 50.0), polarity="dark", approach=(10, 50), hold=(50, 60))
RECEDING = truth.ObjectTruth(id=2, center=(150.0, 50.0), polarity="dark", recede=(0, 40))


def _field_rows():
    """frame -> [(field id, x, y, alarm)]: one field on the approaching object, one on the
    receding object in alarm, one far from everything in alarm, one on the approaching object
    in alarm after its tail."""
    fr: dict[int, list] = {}
    for f in range(14, 70):
        fr.setdefault(f, []).append((1, 53.0, 54.0, 30 <= f < 40))
    for f in range(5, 30):
        fr.setdefault(f, []).append((2, 150.0, 50.0, 20 <= f < 25))
    for f in range(90, 100):
        fr.setdefault(f, []).append((3, 100.0, 10.0, f >= 95))
    for f in range(80, 84):
        fr.setdefault(f, []).append((4, 50.0, 50.0, True))
    return fr


def _record(fr, n=120) -> tracks.Record:
    rec = tracks.Recorder(["mlplc2"])
    born: dict[int, int] = {}
    for f in range(n):
        fields = tuple(Field(i, x, y, 40.0, 1.0, c, born.setdefault(i, f)) for i, x, y, c in fr.get(f, ()))
        rec.update(f, "mlplc2", mlplc2.Output(frame=f, response=1.0, fields=fields,
                                              collision=any(c for *_, c in fr.get(f, ()))))
    return rec.records["mlplc2"]


def _result(fr, n=120) -> RunResult:
    rows = []
    for f in range(n):
        for fid, x, y, c in fr.get(f, ()):
            rows.append({"frame": f, "time_s": f / 30.0, "model": "mlplc2", "field_id": fid, "x": x, "y": y,
                         "response": 1.0, "collision": int(c)})
        if f not in fr:
            rows.append({"frame": f, "time_s": f / 30.0, "model": "mlplc2", "field_id": None, "x": None, "y": None,
                         "response": 0.0, "collision": 0})
    return RunResult(source="v.avi", models=["mlplc2"], fps=30.0, size=(200, 100), model_size=(200, 100),
                     n_frames=n, rows=rows, fields={"mlplc2": []})


GT = {"videos": {"v.avi": {"size": [200, 100], "frames": 120,
                           "objects": [OBJ.to_dict(), RECEDING.to_dict()]}}}


@pytest.mark.parametrize("tail", [25, 40])
def test_evaluate_and_the_reproduction_count_the_same_false_alarms(tail):
    """One rule (tracks.alarm_explained): the frames the reproduction and the scene tests call
    false (tracks.false_alarms) are the frames evaluate counts."""
    fr = _field_rows()
    bad = tracks.false_alarms(_record(fr), [OBJ, RECEDING], tail=tail)
    frames = {f for f, _ in bad}
    expected = set(range(20, 25)) | set(range(95, 100)) | (set(range(80, 84)) if tail == 25 else set())
    assert frames == expected and {fid for _, fid in bad} == ({2, 3, 4} if tail == 25 else {2, 3})
    ev = evaluate(_result(fr), GT, tail=tail)
    assert ev.models["mlplc2"]["false_alarm_frames"] == len(frames)


@pytest.mark.parametrize("frame, xy, explained", [
    (10, (50.0, 50.0), True), (9, (50.0, 50.0), False),          # from the approach onset
    (74, (50.0, 50.0), True), (75, (50.0, 50.0), False),         # up to tail (25) frames after its end
    (30, (50.0, 70.0), True), (30, (50.0, 70.01), False),        # within the match radius (20 px)
    (30, (150.0, 50.0), False),                                  # on the receding object: not explained
    (30, None, True), (80, None, False),                         # a global alarm needs only the time
])
def test_alarm_explained(frame, xy, explained):
    x, y = xy if xy is not None else (None, None)
    assert tracks.alarm_explained(frame, [OBJ, RECEDING], x, y) is explained


def test_first_field_and_fields_near_use_the_match_radius():
    rec = _record({12: [(7, 69.0, 50.0, False)], 13: [(7, 69.0, 50.0, False), (8, 50.0, 55.0, False)]})
    f, latency, error = tracks.first_field(rec, OBJ)
    assert (f.id, latency, error) == (7, 2, 19.0)
    assert [f.id for f in tracks.fields_near(rec.fields.values(), OBJ, 13, 50)] == [8]
    assert tracks.first_field(rec, OBJ, radius=10.0)[0].id == 8


def test_demo_matches_with_the_match_radius_of_the_metrics():
    """The demo's matcher used 25 px where every other matched at 20: a strong field 22 px
    away no longer stands for the object when a weaker one lies on it."""
    fields = [{"id": 1, "x": 72.0, "y": 50.0, "born": 12, "peak_response": 9.0, "first_alarm_frame": 20},
              {"id": 2, "x": 52.0, "y": 50.0, "born": 14, "peak_response": 1.0, "first_alarm_frame": None}]
    (m,) = match_fields(fields, {"size": [200, 100], "objects": [OBJ.to_dict()]})
    assert tracks.DEFAULT_MATCH_RADIUS == 20.0
    assert m["field"] == 2 and m["distance"] == 2.0 and m["frames"] == [10, 60]


def test_record_keeps_the_series_the_reproduction_draws():
    st = stimuli.looming(size=(64, 48), contact_time=0.6, duration=0.6)
    model = mlplc2.MLPLC2(fps=st.fps)
    outs = [model.step(f) for f in st.frames]
    model.reset()
    rec = tracks.record(model, st.frames)
    assert rec.n_frames == len(st.frames) and rec.frames == range(len(st.frames))
    assert np.array_equal(rec.response, [o.response for o in outs])
    assert np.array_equal(rec.collision, [o.collision for o in outs])
    assert rec.fields and {f.id for o in outs for f in o.fields} == set(rec.fields)
    for f in rec.fields.values():
        mine = [(o.frame, g.response, g.collision) for o in outs for g in o.fields if g.id == f.id]
        assert list(zip(f.frames, f.responses)) == [(k, r) for k, r, _ in mine]
        assert f.alarms == [k for k, _, c in mine if c] and f.peak == max(r for _, r, _ in mine)
    assert rec.alarmed() == [f for f in rec.fields.values() if f.alarms]


def test_flat_recorder_keeps_no_series_and_counts_alarms():
    rec = tracks.Recorder(["m"], series=False, offset=5)
    for k in range(5, 9):
        f = Field(1, 10.0, 10.0, 40.0, float(k), k >= 7, 0)
        rec.update(k, "m", mlplc2.Output(frame=k - 5, response=float(k), fields=(f,), collision=k >= 7))
    r = rec.records["m"]
    assert r.alarm == {} and r.fields_at == {} and r.fields[1].frames == []
    assert (r.alarm_count, r.first_alarm_frame, r.n_frames) == (2, 7, 4)
    (s,) = rec.summaries("m")
    assert s == {"id": 1, "x": 10.0, "y": 10.0, "born": 5, "died": None, "peak_response": 8.0, "peak_frame": 8,
                 "first_alarm_frame": 7}


# -- the recorder of a run: dead fields spilled to disk, the peak of a plateau ------------
def test_field_summaries_keep_only_live_fields_in_memory():
    """keep_rows=False: a field that died leaves memory (it is spilled to a temporary file)."""
    from mlplc2.neuropils.attention import Field
    from mlplc2.evaluation.tracks import Recorder

    tracker = Recorder(["m"], series=False, spill=True)
    for k in range(200):   # a new field every frame, each living 3 frames
        fields = tuple(Field(i, 10.0, 10.0, 40.0, 1.0, False, i) for i in range(max(0, k - 2), k + 1))
        tracker.update(k, "m", mlplc2.Output(frame=k, response=1.0, fields=fields))
    assert len(tracker.records["m"].fields) == 3
    summaries = tracker.summaries("m")
    assert [s["id"] for s in summaries] == list(range(200))
    assert all(s["died"] == s["id"] + 3 for s in summaries[:-3])
    tracker.close()


def test_peak_frame_is_the_first_frame_of_a_plateau():
    """A response held on later frames (duplicates) leaves the peak at its first frame, also when
    the stored value is rounded (it used to move to the last frame of the plateau)."""
    from mlplc2.neuropils.attention import Field
    from mlplc2.evaluation.tracks import Recorder

    tracker = Recorder(["m"])
    for k, r in enumerate((5.0, 12058.344999, 12058.344999, 12058.344999, 100.0)):
        f = Field(1, 10.0, 10.0, 40.0, r, False, 0)
        tracker.update(k, "m", mlplc2.Output(frame=k, response=r, fields=(f,)))
    (s,) = tracker.summaries("m")
    assert s["peak_frame"] == 1 and s["peak_response"] == pytest.approx(12058.34, abs=0.01)
