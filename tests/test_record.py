"""mlplc2.evaluation.record as the one recorder of per-frame outputs (``mlplc2 run``, ``reproduce``)."""

from __future__ import annotations

import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.evaluation.record import Recorder, record
from mlplc2.neuropils.attention import Field


def test_record_keeps_the_series_the_reproduction_draws():
    st = stimuli.looming(size=(64, 48), contact_time=0.6, duration=0.6)
    model = mlplc2.MLPLC2(fps=st.fps)
    outs = [model.step(f) for f in st.frames]
    model.reset()
    rec = record(model, st.frames)
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
    rec = Recorder(["m"], series=False, offset=5)
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
    tracker = Recorder(["m"])
    for k, r in enumerate((5.0, 12058.344999, 12058.344999, 12058.344999, 100.0)):
        f = Field(1, 10.0, 10.0, 40.0, r, False, 0)
        tracker.update(k, "m", mlplc2.Output(frame=k, response=r, fields=(f,)))
    (s,) = tracker.summaries("m")
    assert s["peak_frame"] == 1 and s["peak_response"] == pytest.approx(12058.34, abs=0.01)


def test_the_output_files_read_back_with_one_line_errors(tmp_path):
    """read_responses / read_targets (``mlplc2 evaluate``, the plots): parsed rows, rows without a frame skipped,
    a one-line InputValueError for a file that is not a responses.csv or has a cell that does not parse, and
    None for a targets.csv written before the target layer (no target_id)."""
    from mlplc2._validation import InputValueError
    from mlplc2.evaluation.record import read_responses, read_targets

    p = tmp_path / "responses.csv"
    p.write_text("frame,time_s,model,field_id,x,y,response,collision\n0,0.0,m,,,,1.5,0\n,,,,,,,\n"
                 "1,0.1,m,3,2.5,4.0,2.0,1\n")
    assert read_responses(p) == [
        {"frame": 0, "time_s": 0.0, "model": "m", "field_id": None, "x": None, "y": None, "response": 1.5,
         "collision": 0},
        {"frame": 1, "time_s": 0.1, "model": "m", "field_id": 3, "x": 2.5, "y": 4.0, "response": 2.0,
         "collision": 1}]
    p.write_text("frame,model,field_id,x,y\n0,m,,,\n")
    with pytest.raises(InputValueError, match=r"responses.csv: not a responses.csv \(missing columns collision\)$"):
        read_responses(p)
    p.write_text("frame,model,field_id,x,y,collision\n0,m,,,,yes\n")
    with pytest.raises(InputValueError, match=r"responses.csv: malformed row$"):
        read_responses(p)
    t = tmp_path / "targets.csv"
    t.write_text("frame,model,x,y\n0,m,1,2\n")
    assert read_targets(t) is None
    t.write_text("frame,model,target_id,x,y,warning\n0,m,1,,2,0\n")
    with pytest.raises(InputValueError, match=r"targets.csv: malformed row$"):
        read_targets(t)
