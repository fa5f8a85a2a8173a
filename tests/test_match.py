"""mlplc2.evaluation.match as the one matcher and false-alarm rule of the edge code."""

from __future__ import annotations

import pytest

import mlplc2
from mlplc2.evaluation import match, truth
from mlplc2.evaluation.match import match_fields
from mlplc2.evaluation.record import Record, Recorder
from mlplc2.evaluator import evaluate
from mlplc2.neuropils.attention import Field
from mlplc2.runner import RunResult

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


def _record(fr, n=120) -> Record:
    rec = Recorder(["mlplc2"])
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
    """One rule (match.alarm_explained): the frames the reproduction and the scene tests call
    false (match.false_alarms) are the frames evaluate counts."""
    fr = _field_rows()
    bad = match.false_alarms(_record(fr), [OBJ, RECEDING], tail=tail)
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
    assert match.alarm_explained(frame, [OBJ, RECEDING], x, y) is explained


def test_first_field_and_fields_near_use_the_match_radius():
    rec = _record({12: [(7, 69.0, 50.0, False)], 13: [(7, 69.0, 50.0, False), (8, 50.0, 55.0, False)]})
    f, latency, error = match.first_field(rec, OBJ)
    assert (f.id, latency, error) == (7, 2, 19.0)
    assert [f.id for f in match.fields_near(rec.fields.values(), OBJ, 13, 50)] == [8]
    assert match.first_field(rec, OBJ, radius=10.0)[0].id == 8


def test_demo_matches_with_the_match_radius_of_the_metrics():
    """The demo's matcher used 25 px where every other matched at 20: a strong field 22 px
    away no longer stands for the object when a weaker one lies on it."""
    fields = [{"id": 1, "x": 72.0, "y": 50.0, "born": 12, "peak_response": 9.0, "first_alarm_frame": 20},
              {"id": 2, "x": 52.0, "y": 50.0, "born": 14, "peak_response": 1.0, "first_alarm_frame": None}]
    (m,) = match_fields(fields, {"size": [200, 100], "objects": [OBJ.to_dict()]})
    assert match.DEFAULT_MATCH_RADIUS == 20.0
    assert m["field"] == 2 and m["distance"] == 2.0 and m["frames"] == [10, 60]
