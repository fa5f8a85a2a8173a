"""mlplc2.evaluate (mlplc2.evaluator, scores of mlplc2.evaluation.score): runs scored against ground truth.

* The paper's metrics: the loader, object-level and clip-level metrics on a generated scene
  and on hand-made rows, inputs given twice, incomplete results, the CLI.
* The warning metrics (docs/evaluation.md, "Warning metrics") on small hand-made cases,
  at 10 fps (``WARN_FPS``; see that section).
"""

from __future__ import annotations

import copy
import csv
import json
import math
import shutil
import sys
import warnings

import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2._validation import InputError, InputTypeError, InputValueError
from mlplc2.cli import main
from mlplc2.evaluator import EARLY_S, LATE_S, Evaluation, EvaluationWarning, evaluate, load_ground_truth
from mlplc2.io import write_video
from mlplc2.runner import COLUMNS, TARGET_COLUMNS, RunResult
from mlplc2.evaluation.truth import TRACK_COLUMNS
from mlplc2.evaluation.score import LAPSE_S

FPS = 30.0


# ---------------------------------------------------------------------------
# a generated scene with known truth, run once
# ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """Two dark squares looming one after the other over a scrolling background (160x120, 50 frames),
    fixed in the image: the paper's stimulus, run with the paper's model."""
    d = tmp_path_factory.mktemp("scene")
    st = stimuli.scene([stimuli.SceneObject(center=(50, 40), onset=3, approach=20, hold=5, recede=0),
                        stimuli.SceneObject(center=(120, 80), onset=20, approach=20, hold=5, recede=0)],
                       size=(160, 120), frames=50, background="procedural", scroll=1.0)
    video = d / "clips" / "two.avi"
    video.parent.mkdir()
    write_video(video, st.frames, FPS)
    gt = {"videos": {"clips/two.avi": st.to_ground_truth()}}
    # the paper's model: the objects stay put while the background scrolls under them, which a
    # stabilised model would take for a pan and carry its fields off them
    res = mlplc2.run(video, ["mlplc2", "lgmd2"], out=d / "two_out", quiet=True, plot=False, stabilise=False)
    return {"dir": d, "video": video, "gt": gt, "result": res, "stim": st}


def test_known_scene_detections_and_latencies(scene):
    ev = evaluate(scene["result"], scene["gt"])
    assert list(ev.models) == ["mlplc2", "lgmd2"]
    objs = [o for o in ev.objects if o["model"] == "mlplc2"]
    assert [o["object"] for o in objs] == [1, 2]
    for o in objs:
        assert o["detected"] is True
        assert 0 <= o["latency_field"] <= 8          # a field within a few frames of the onset
        assert o["error_detect"] <= 8.0 and o["error_life"] <= 8.0
        assert o["fields"] == 1
        assert o["alarmed"] and o["latency_field"] < o["latency_alarm"] <= 20 + 25
    s = ev.models["mlplc2"]
    assert (s["objects"], s["detected"], s["false_alarms"], s["fields_total"]) == (2, 2, 0, 2)
    assert s["detection_rate"] == 1.0
    assert s["minutes"] == pytest.approx(50 / FPS / 60, abs=1e-4)
    # LGMD2 does not localise: no detection metrics, only alarms
    lg = ev.models["lgmd2"]
    assert lg["detected"] is None and lg["fields_total"] is None and lg["localises"] is False


def test_folder_and_video_inputs_give_the_same_scores(scene):
    ev_mem = evaluate(scene["result"], scene["gt"])
    ev_dir = evaluate(scene["dir"] / "two_out", scene["gt"])
    assert ev_dir.models == ev_mem.models
    assert ev_dir.objects == ev_mem.objects
    ev_vid = evaluate(scene["video"], scene["gt"], models=["mlplc2"], run_options={"stabilise": False})  # as the fixture ran
    assert ev_vid.models["mlplc2"] == ev_mem.models["mlplc2"]
    # a parent folder is searched for results
    assert evaluate(scene["dir"], scene["gt"]).models == ev_mem.models


def _shifted(res: RunResult, dx: float) -> RunResult:
    rows = [dict(r, x=None if r["x"] is None else r["x"] + dx) for r in res.rows]
    fields = {m: [dict(f, x=f["x"] + dx) for f in fs] for m, fs in res.fields.items()}
    return RunResult(source=res.source, models=res.models, fps=res.fps, size=res.size, model_size=res.model_size,
                     start=res.start, n_frames=res.n_frames, rows=rows, fields=fields)


def test_shifted_result_is_a_miss(scene):
    res = scene["result"]
    ev = evaluate(_shifted(res, 60.0), scene["gt"], models=["mlplc2"])
    s = ev.models["mlplc2"]
    assert s["detected"] == 0 and s["alarmed"] == 0
    assert all(o["detected"] is False and o["fields"] == 0 for o in ev.objects)
    # the alarms that were hits are now false alarms, one per alarming field
    n_alarming = sum(1 for f in res.fields["mlplc2"] if f["first_alarm_frame"] is not None)
    assert n_alarming >= 1 and s["false_alarms"] == n_alarming
    assert s["false_alarms_per_min"] == pytest.approx(n_alarming / (50 / FPS / 60), rel=1e-3)
    # a small shift (within the match radius) still matches
    assert evaluate(_shifted(res, 5.0), scene["gt"], models=["mlplc2"]).models["mlplc2"]["detected"] == 2


def test_gt_size_rescales_results(scene):
    """Results of a run on a 2x larger copy of the video are scored in ground-truth pixels."""
    res = scene["result"]
    big = _shifted(res, 0.0)
    big.size = (res.size[0] * 2, res.size[1] * 2)
    big.rows = [dict(r, x=None if r["x"] is None else 2 * r["x"], y=None if r["y"] is None else 2 * r["y"])
                for r in res.rows]
    assert evaluate(big, scene["gt"], models=["mlplc2"]).objects == \
        evaluate(res, scene["gt"], models=["mlplc2"]).objects


# ---------------------------------------------------------------------------
# hand-made rows: exact numbers
# ---------------------------------------------------------------------------
def _result(source, frames, *, field_rows=None, alarms=(), model="mlplc2", fps=FPS, size=(200, 100)):
    """RunResult with rows per frame: ``field_rows[frame] = [(id, x, y, collision)]`` or, for an
    LGMD-like model, one row per frame with collision on ``alarms``."""
    rows = []
    for f in range(frames):
        fr = (field_rows or {}).get(f)
        if fr:
            for fid, x, y, c in fr:
                rows.append({"frame": f, "time_s": f / fps, "model": model, "field_id": fid, "x": x, "y": y,
                             "response": 1.0, "collision": int(c)})
        else:
            rows.append({"frame": f, "time_s": f / fps, "model": model, "field_id": None, "x": None, "y": None,
                         "response": 0.0, "collision": int(f in alarms)})
    ids = sorted({fid for v in (field_rows or {}).values() for fid, *_ in v})
    fields = {model: [{"id": i, "x": 0, "y": 0, "born": 0, "died": None, "peak_response": 1, "peak_frame": 0,
                       "first_alarm_frame": None} for i in ids]}
    return RunResult(source=source, models=[model], fps=fps, size=size, model_size=size, n_frames=frames,
                     rows=rows, fields=fields)


OBJ_GT = {"videos": {"v.avi": {"size": [200, 100], "frames": 120, "objects": [
    {"id": 1, "center": [50, 50], "polarity": "dark", "approach": [10, 50], "hold": [50, 60]},
    {"id": 2, "center": [150, 50], "polarity": "dark", "recede": [0, 40]}]}}}


def test_object_metrics_exact():
    fr = {}
    for f in range(14, 70):                      # field 1 near object 1 from frame 14 to 69
        fr.setdefault(f, []).append((1, 53.0, 54.0, 30 <= f < 40))
    for f in range(5, 30):                       # field 2 on the receding object: alarm 20-24 = false alarm
        fr.setdefault(f, []).append((2, 150.0, 50.0, 20 <= f < 25))
    for f in range(90, 100):                     # field 3 far from everything, alarm at 95 = false alarm
        fr.setdefault(f, []).append((3, 100.0, 10.0, f >= 95))
    for f in range(80, 84):                      # field 1's area after the tail (50 + 25 = 75): false alarm
        fr.setdefault(f, []).append((4, 50.0, 50.0, True))
    ev = evaluate(_result("/data/v.avi", 120, field_rows=fr), OBJ_GT)
    (o,) = ev.objects
    assert o["detected"] and o["detect_frame"] == 14 and o["latency_field"] == 4 and o["field"] == 1
    assert o["error_detect"] == 5.0 and o["error_life"] == 5.0   # (3, 4) off during 14..59
    assert o["alarm_frame"] == 30 and o["latency_alarm"] == 20 and o["fields"] == 1
    s = ev.models["mlplc2"]
    assert s["false_alarms"] == 3 and s["false_alarm_frames"] == 5 + 5 + 4
    assert s["false_alarms_per_min"] == pytest.approx(3 / (120 / 30 / 60))
    assert s["fields_total"] == 4
    # a longer tail explains field 4's alarm
    ev2 = evaluate(_result("/data/v.avi", 120, field_rows=fr), OBJ_GT, tail=40)
    assert ev2.models["mlplc2"]["false_alarms"] == 2
    # a smaller radius misses the field 5 px away
    assert evaluate(_result("/data/v.avi", 120, field_rows=fr), OBJ_GT, match_radius=4).objects[0]["detected"] is False


def test_non_localising_alarms_and_false_alarms():
    alarms = set(range(40, 45)) | set(range(100, 103))
    ev = evaluate(_result("v.avi", 120, alarms=alarms, model="lgmd2"), OBJ_GT)
    (o,) = ev.objects
    assert o["detected"] is None and o["alarm_frame"] == 40 and o["latency_alarm"] == 30
    assert ev.models["lgmd2"]["false_alarms"] == 1 and ev.models["lgmd2"]["false_alarm_frames"] == 3


def test_label_only_clips_have_no_object_level_false_alarms():
    """Alarms on a clip with only a clip-level label are its TP/FP outcome, not object-level
    false alarms; FA/min is over the videos with object-level truth."""
    gt = {"videos": {"clipA.avi": OBJ_GT["videos"]["v.avi"], "clipB.avi": {"label": "collision", "collision_frame": 45}}}
    fr_a = {f: [(1, 50.0, 50.0, 30 <= f < 40)] for f in range(12, 60)}
    fr_b = {f: [(1, 80.0, 50.0, 30 <= f < 40 or 50 <= f < 55)] for f in range(12, 60)}
    ev = evaluate([_result("clipA.avi", 120, field_rows=fr_a), _result("clipB.avi", 60, field_rows=fr_b)], gt)
    s = ev.models["mlplc2"]
    assert (s["videos"], s["objects"], s["alarmed"], s["tp"]) == (2, 1, 1, 1)
    assert s["false_alarms"] == 0 and s["false_alarm_frames"] == 0 and s["false_alarms_per_min"] == 0.0
    b = next(v for v in ev.videos if v["video"] == "clipB.avi")
    assert b["outcome"] == "TP" and b["false_alarms"] is None and b["object_level"] is False
    # an unexplained alarm on the object-level clip is counted per minute of that clip only (120 frames)
    fr_a[100] = [(2, 150.0, 90.0, True)]
    s = evaluate([_result("clipA.avi", 120, field_rows=fr_a), _result("clipB.avi", 60, field_rows=fr_b)],
                 gt).models["mlplc2"]
    assert s["false_alarms"] == 1 and s["false_alarms_per_min"] == pytest.approx(1 / (120 / FPS / 60))
    # only label-only clips: no false-alarm figures at all
    only_b = evaluate(_result("clipB.avi", 60, field_rows=fr_b), gt)
    assert only_b.models["mlplc2"]["false_alarms"] is None and only_b.models["mlplc2"]["false_alarms_per_min"] is None
    assert "| - | - |" in only_b.object_table()
    # its row of the per-video table counts no objects: "-" (a new user read "detected 0/0" as a miss), while the
    # object-level clip keeps its counts
    rows = {line.split(" | ")[1]: line for line in ev.video_table().splitlines()[2:]}
    assert "| 60 | - | - | - |" in rows["clipB.avi"] and "| TP |" in rows["clipB.avi"]
    assert "| 120 | 1 | 1/1 | 1/1 |" in rows["clipA.avi"]


def test_clip_level_metrics():
    gt = {"videos": {
        "a.mp4": {"label": "collision", "collision_frame": 20},
        "b.mp4": {"label": "collision", "collision_frame": 20},
        "c.mp4": {"label": "no_collision"},
        "d.mp4": {"label": "no_collision"},
        "e.mp4": {"label": "collision"},
    }}
    results = [_result("x/a.mp4", 30, alarms={15, 16}, model="lgmd1"),   # TP, warning 5 frames
               _result("x/b.mp4", 30, alarms={25}, model="lgmd1"),       # alarm too late: FN
               _result("x/c.mp4", 30, alarms={3}, model="lgmd1"),        # FP
               _result("x/d.mp4", 30, model="lgmd1"),                    # TN
               _result("x/e.mp4", 30, alarms={29}, model="lgmd1")]       # TP, no collision frame
    ev = evaluate(results, gt)
    s = ev.models["lgmd1"]
    assert (s["clips"], s["tp"], s["fp"], s["tn"], s["fn"]) == (5, 2, 1, 1, 1)
    assert s["accuracy"] == pytest.approx(3 / 5)
    assert s["precision"] == pytest.approx(2 / 3, abs=1e-4) and s["recall"] == pytest.approx(2 / 3, abs=1e-4)
    assert s["warning_s"] == pytest.approx(5 / 30, abs=1e-4)
    assert [v["outcome"] for v in ev.videos] == ["TP", "FN", "FP", "TN", "TP"]
    md = ev.to_markdown()
    assert "| lgmd1 | 5 | 2 | 1 | 1 | 1 | 0.60 | 0.67 | 0.67 | 0.17 |" in md


def test_the_clip_table_is_named_for_the_field_alarm_it_scores():
    """The clip-level outcome and lead are the field alarm's (any field, anywhere): beside the targets'
    warnings on a labelled clip (warned: no), the table must not read as a warning (ux9, session 18)."""
    gt = {"videos": {"a.mp4": {"label": "collision", "collision_frame": 20, "track": [[0, 100.0, 80.0, 20.0]]}}}
    ev = evaluate(_result("x/a.mp4", 30, alarms={15, 16}, field_rows={15: [(1, 300.0, 200.0, True)],
                                                                    16: [(1, 300.0, 200.0, True)]}), gt)
    assert ev.videos[0]["outcome"] == "TP" and ev.models["mlplc2"]["warning_s"] == pytest.approx(5 / 30, abs=1e-4)
    md = ev.to_markdown(details=True)
    table = md.split("Field alarm on labelled clips", 1)[1].split("\n\n")[1]
    assert table.splitlines()[0].endswith("| recall | alarm lead (s) |")
    assert "warning (s)" not in md and "| alarm outcome |" in md
    lines = [line for line in md.splitlines() if line.startswith("| mlplc2 | x/a.mp4") or line.startswith("| mlplc2 | a.mp4")]
    assert any("| no |" in line for line in lines)                  # the targets' warning: none


def test_markdown_and_json_round_trip(scene, tmp_path):
    ev = evaluate(scene["result"], scene["gt"])
    md = ev.to_markdown()
    assert md.splitlines()[0].startswith("| model |") and "| mlplc2 | 1 | 2 | 2/2 |" in md
    files = ev.write(tmp_path / "ev")
    data = json.loads(files["evaluation.json"].read_text())
    assert data["models"]["mlplc2"]["detected"] == 2 and len(data["objects"]) == 4
    assert data["settings"]["match_radius"] == 20.0 and data["settings"]["tail"] == 25
    assert "| model |" in files["evaluation.md"].read_text()


def test_to_dataframe_tables(scene):
    pd = pytest.importorskip("pandas")
    ev = evaluate(scene["result"], scene["gt"])
    objs = ev.to_dataframe()
    assert isinstance(objs, pd.DataFrame) and len(objs) == len(ev.objects) == 4
    assert list(objs.columns) == list(ev.objects[0])  # the keys of evaluation.json's objects
    assert list(objs[objs.model == "mlplc2"].latency_field) == \
        [o["latency_field"] for o in ev.objects if o["model"] == "mlplc2"]
    assert list(objs[objs.model == "mlplc2"]["object"]) == [1, 2]
    assert bool(objs[objs.model == "mlplc2"]["detected"].all())
    videos = ev.to_dataframe("videos")
    assert sorted(videos.model) == ["lgmd2", "mlplc2"] and set(videos.video) == {"clips/two.avi"}
    models = ev.to_dataframe("models").set_index("model")
    assert models.loc["mlplc2", "detected"] == 2 and models.loc["mlplc2", "model_name"] == "mlplc2"
    assert models.loc["mlplc2", "detection_rate"] == ev.models["mlplc2"]["detection_rate"]
    with pytest.raises(InputValueError, match="kind must be one of objects, videos, models, warning_objects, warning_videos, got 'fields'"):
        ev.to_dataframe("fields")


# ---------------------------------------------------------------------------
# ground-truth loading and matching
# ---------------------------------------------------------------------------
def test_paper_ground_truth_loads(paper_dir):
    gt = load_ground_truth(paper_dir / "ground_truth.json")
    assert len(gt) == 8
    six = gt.match(paper_dir / "scenes" / "outdoor_3_black_expand_multi_6.avi")
    assert six.size == (320, 240) and len(six.objects) == 6 and six.objects[0].approach == (5, 45)
    assert gt.match("/elsewhere/test_grating.avi").key == "basic/test_grating.avi"
    assert gt.match("/elsewhere/unknown.avi") is None


def test_stimulus_ground_truth_entry(tmp_path):
    """A single entry (as written by 'mlplc2 stimulus') is accepted and matched by its video name."""
    st = stimuli.six_objects(background="plain")
    entry = {"name": "six_objects", "video": "six.mp4", **st.to_ground_truth()}
    gt = load_ground_truth(entry)
    assert gt.match(tmp_path / "six.mp4") is not None and gt.match(tmp_path / "other.mp4") is None
    anon = load_ground_truth(st.to_ground_truth())
    assert anon.match("anything.avi") is not None


def test_matching_by_suffix_and_ambiguity():
    e = {"size": [10, 10], "frames": 5, "objects": []}
    gt = load_ground_truth({"videos": {"a/x.avi": e, "b/x.avi": e, "y.avi": e}})
    assert gt.match("/data/a/x.avi").key == "a/x.avi"
    assert gt.match("/data/y.avi").key == "y.avi"
    with pytest.raises(InputValueError, match="ambiguous"):
        gt.match("/data/c/x.avi")


def test_track_and_kind():
    gt = load_ground_truth({"videos": {"t.avi": {"size": [100, 100], "frames": 30, "objects": [
        {"id": "car", "track": [[20, 60, 50], [0, 40, 50]], "kind": "approaching", "interval": [0, 20]}]}}})
    (o,) = gt["t.avi"].objects
    assert o.approach == (0, 20) and o.center_at(10) == (50.0, 50.0) and o.center_at(25) == (60.0, 50.0)
    fr = {f: [(1, 40 + f, 50, f >= 15)] for f in range(2, 30)}
    ev = evaluate(_result("t.avi", 30, field_rows=fr, size=(100, 100)), gt)
    (r,) = ev.objects
    assert r["detected"] and r["latency_field"] == 2 and r["error_detect"] == 0.0
    assert r["error_life"] == 0.0 and r["latency_alarm"] == 15


GOOD = {"size": [320, 240], "frames": 100, "objects": [{"id": 1, "center": [10, 20], "approach": [0, 40]}]}


@pytest.mark.parametrize("mutate, message", [
    (lambda e: e.pop("objects"), "needs 'objects'"),
    (lambda e: e["objects"][0].update(approach=[40, 10]), "end > start"),
    (lambda e: e["objects"][0].update(approach=[0]), "interval"),
    (lambda e: e["objects"][0].pop("center"), "needs a 'center'"),
    (lambda e: e["objects"][0].update(center=[1, "a"]), "finite number"),
    (lambda e: e["objects"][0].update(track=[[0, 1]]), r"\[frame, x, y\]"),
    (lambda e: e["objects"][0].update(polarity="grey"), "polarity"),
    (lambda e: e["objects"][0].update(kind="flying"), "kind"),
    (lambda e: e["objects"][0].update(kind=["approaching"]), "kind"),     # unhashable: not a raw TypeError
    (lambda e: e.update(size=[320]), "size"),
    (lambda e: e.update(frames=1.5), "integer"),
    (lambda e: e.update(objects={}), "list"),
    (lambda e: e.update(label="maybe"), "label"),
    (lambda e: e.update(label="no_collision", collision_frame=3), "collision frame"),
])
def test_malformed_ground_truth(mutate, message):
    entry = copy.deepcopy(GOOD)
    mutate(entry)
    with pytest.raises(InputValueError, match=message):
        load_ground_truth({"videos": {"v.avi": entry}})


def test_malformed_ground_truth_files(tmp_path):
    with pytest.raises(InputValueError, match="not found"):
        load_ground_truth(tmp_path / "none.json")
    with pytest.raises(InputValueError, match="is a folder, not a ground truth JSON file$"):
        load_ground_truth(tmp_path)
    (tmp_path / "ground_truth.json").write_text("{}")
    with pytest.raises(InputValueError, match="is a folder.*did you mean its ground_truth.json"):
        load_ground_truth(tmp_path)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputValueError, match="not valid JSON"):
        load_ground_truth(bad)
    bad.write_text("[1, 2]")
    with pytest.raises(InputValueError, match="JSON object"):
        load_ground_truth(bad)
    bad.write_text('{"videos": {}}')
    with pytest.raises(InputValueError, match="non-empty"):
        load_ground_truth(bad)


def test_an_error_in_a_one_entry_file_names_the_file_apart(tmp_path):
    """The error in a file of one entry (what `mlplc2 stimulus --gt` writes) puts the file's name apart
    from the place in it, as in a file of several (it read 'gt.json.objects[0].approach')."""
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps({**GOOD, "objects": [{"center": [1, 2], "approach": [10, 5]}]}))
    with pytest.raises(InputValueError, match=r"^\S*gt\.json: entry\.objects\[0\]\.approach: interval"):
        load_ground_truth(gt)
    gt.write_text(json.dumps({"videos": {"v.avi": {**GOOD, "objects": [{"center": [1, 2], "approach": [10, 5]}]}}}))
    with pytest.raises(InputValueError, match=r"^\S*gt\.json: videos\['v\.avi'\]\.objects\[0\]\.approach: interval"):
        load_ground_truth(gt)


def test_evaluate_errors(scene):
    with pytest.raises(InputValueError, match="no ground truth"):
        evaluate(scene["result"], {"videos": {"other.avi": GOOD}})
    with pytest.raises(InputValueError, match="unknown model"):
        evaluate(scene["result"], scene["gt"], models=["nope"])
    with pytest.raises(InputValueError, match="match_radius"):
        evaluate(scene["result"], scene["gt"], match_radius=0)


def test_a_model_the_results_lack_is_named(scene):
    """Asked for a model the results do not hold, the error names it (it said only 'no model output')."""
    with pytest.raises(InputValueError, match="^nothing to evaluate: the results hold no output of lgmd1$"):
        evaluate(scene["dir"] / "two_out", scene["gt"], models=["lgmd1"])


def test_a_one_entry_truth_for_another_video_names_that_video(scene, tmp_path):
    """The truth of `mlplc2 stimulus --gt` names its video; a run of a renamed copy is not scored, and the
    error says which video the entry is for (it said only 'no ground truth in gt.json for copy.avi')."""
    _cut_folder(scene["dir"] / "two_out", tmp_path / "copy", 50, video=str(tmp_path / "copy.avi"))
    entry = {**scene["gt"]["videos"]["clips/two.avi"], "video": "two.avi"}
    with pytest.raises(InputValueError, match=r"for \S*copy\.avi \(its one entry is for video 'two\.avi'\)$"):
        evaluate(tmp_path / "copy", entry)


def test_a_run_of_standard_input_says_how_to_score_it(scene, tmp_path, capsys):
    """`mlplc2 run -` records its video as '-', which no key matches: the message says how to score it
    (the clip's entry alone), and that way scores it as the file's run is scored."""
    _cut_folder(scene["dir"] / "two_out", tmp_path / "piped", 50, video="-")
    with pytest.raises(InputValueError, match=r"no ground truth in .* for - \(a run of standard input .* entry alone"):
        evaluate(tmp_path / "piped", scene["gt"], models=["mlplc2"])
    entry = {k: v for k, v in scene["gt"]["videos"]["clips/two.avi"].items() if k != "video"}
    assert (evaluate(tmp_path / "piped", entry, models=["mlplc2"]).models
            == evaluate(scene["dir"] / "two_out", scene["gt"], models=["mlplc2"]).models)
    # beside a run that is scored, the CLI's warning line has the same hint
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps(scene["gt"]))
    assert main(["evaluate", str(scene["dir"] / "two_out"), str(tmp_path / "piped"), "--gt", str(gt), "-q"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mlplc2: warning: -: no ground truth for it in "), err
    assert "a run of standard input has no video name" in err[0]


@pytest.mark.parametrize("kw, error, message", [
    ({"models": 5}, InputTypeError, "models must be"),
    ({"models": [None]}, InputTypeError, "model names"),
    ({"models": []}, InputValueError, "models needs at least one model name"),
    ({"match_radius": "x"}, InputTypeError, "match_radius must be a number"),
    ({"match_radius": None}, InputTypeError, "match_radius must be a number"),
    ({"match_radius": True}, InputTypeError, "match_radius must be a number"),
    ({"match_radius": float("nan")}, InputValueError, "match_radius must be a finite number"),
    ({"run_options": 5}, InputTypeError, "run_options"),
])
def test_bad_arguments_are_input_errors(kw, error, message):
    with pytest.raises(error, match=message) as exc:
        evaluate(_result("v.avi", 120), OBJ_GT, **kw)
    assert isinstance(exc.value, InputError) and "\n" not in str(exc.value)


# ---------------------------------------------------------------------------
# inputs given twice, incomplete results, inputs that are not results
# ---------------------------------------------------------------------------
def test_overlapping_inputs_are_scored_once(scene, tmp_path):
    """A results folder reached twice (a parent folder and the folder itself, or the
    same folder twice) is scored once, with a warning."""
    once = evaluate(scene["dir"], scene["gt"])
    assert once.warnings == []
    for inputs, message in (([scene["dir"], scene["dir"] / "two_out"], "two_out: its results are already given by"),
                            ([scene["dir"] / "two_out", scene["dir"]], "1 of its 1 result folders|already given"),
                            ([scene["dir"], scene["dir"]], "given more than once"),
                            ([scene["result"], scene["result"]], "given more than once")):
        with pytest.warns(EvaluationWarning, match=message):
            ev = evaluate(inputs, scene["gt"])
        assert ev.models == once.models and ev.objects == once.objects and len(ev.warnings) == 1
        assert ev.models["mlplc2"]["videos"] == 1 and ev.models["mlplc2"]["objects"] == 2


def test_results_folder_with_other_videos_warns(scene, tmp_path):
    """A folder that holds results is read as results: a video beside them that has none (such as
    the shared clips' folder after one `mlplc2 run clip.mp4` wrote clip_mlplc2/ there) is named in a
    warning instead of being left out silently; a video whose results are there is not."""
    shutil.copytree(scene["dir"] / "two_out", tmp_path / "two_out")
    shutil.copy(scene["video"], tmp_path / "two.avi")
    with warnings.catch_warnings():
        warnings.simplefilter("error", EvaluationWarning)
        ev = evaluate(tmp_path, scene["gt"])
    assert ev.warnings == [] and ev.models["mlplc2"]["videos"] == 1
    shutil.copy(scene["video"], tmp_path / "other.avi")
    with pytest.warns(EvaluationWarning, match=r"read as results \(1 result folder\(s\) in it\), so its 1 "
                                               r"video\(s\) without results there are not run or scored: other.avi;"):
        ev = evaluate(tmp_path, scene["gt"])
    assert len(ev.warnings) == 1 and ev.models["mlplc2"]["videos"] == 1


def test_two_result_folders_for_one_video_are_an_error(scene, tmp_path):
    shutil.copytree(scene["dir"] / "two_out", tmp_path / "copy")
    with pytest.raises(InputValueError, match="two_out and .*copy both hold mlplc2 results for .*two.avi"):
        evaluate([scene["dir"] / "two_out", tmp_path / "copy"], scene["gt"], models=["mlplc2"])
    # the same for two results in memory, and for a results folder and its video
    with pytest.raises(InputValueError, match="a RunResult of .*two.avi and another RunResult .* both hold"):
        evaluate([scene["result"], copy.copy(scene["result"])], scene["gt"], models=["mlplc2"])
    with pytest.raises(InputValueError, match=r"two_out and .*two.avi \(run now\) both hold mlplc2"):
        evaluate([scene["dir"] / "two_out", scene["video"]], scene["gt"], models=["mlplc2"])


def _cut_folder(src, dst, n, **flags):
    """Copy of results folder ``src`` as if the run had stopped after ``n`` frames."""
    dst.mkdir()
    info = json.loads((src / "fields.json").read_text())
    info.update(n_frames=n, **flags)
    (dst / "fields.json").write_text(json.dumps(info))
    with open(src / "responses.csv", newline="") as f, open(dst / "responses.csv", "w", newline="") as g:
        rows = list(csv.reader(f))
        csv.writer(g).writerows([rows[0]] + [r for r in rows[1:] if int(r[0]) < n])


def test_incomplete_results_warn(scene, tmp_path):
    """An interrupted run is scored, with a warning and the count of approaching
    objects after its last frame (object 2 approaches from frame 20)."""
    _cut_folder(scene["dir"] / "two_out", tmp_path / "cut", 18, complete=False, interrupted=True)
    with pytest.warns(EvaluationWarning, match=r"cut: incomplete results \(the run was interrupted after 18 "
                                               r"frames\).* 1 approaching object\(s\) outside"):
        ev = evaluate(tmp_path / "cut", scene["gt"], models=["mlplc2"])
    s = ev.models["mlplc2"]
    assert (s["objects"], s["objects_outside"], s["incomplete_videos"]) == (1, 1, 1)
    assert ev.videos[0]["complete"] is False and ev.videos[0]["objects_outside"] == 1
    assert "1 approaching object(s) outside the processed frames" in ev.to_markdown()
    files = ev.write(tmp_path / "ev")
    assert "incomplete results" in files["evaluation.md"].read_text()
    assert json.loads(files["evaluation.json"].read_text())["warnings"] == ev.warnings
    # a truncated video (fields.json) and a truncated RunResult say so
    _cut_folder(scene["dir"] / "two_out", tmp_path / "trunc", 18, complete=False, truncated=True)
    with pytest.warns(EvaluationWarning, match="stopped decoding after 18 frames"):
        evaluate(tmp_path / "trunc", scene["gt"], models=["mlplc2"])
    res = copy.copy(scene["result"])
    res.truncated, res.message = True, "frame 30 could not be decoded"
    with pytest.warns(EvaluationWarning, match="could not be decoded.* 0 approaching"):
        evaluate(res, scene["gt"], models=["mlplc2"])
    # a complete run gives no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert evaluate(scene["dir"] / "two_out", scene["gt"]).warnings == []


def test_cli_evaluate_warns_on_incomplete_results(scene, tmp_path, capsys):
    _cut_folder(scene["dir"] / "two_out", tmp_path / "cut", 18, complete=False, interrupted=True)
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps(scene["gt"]))
    with warnings.catch_warnings():   # as outside pytest: a Python warning would reach stderr
        warnings.simplefilter("always", EvaluationWarning)
        warnings.showwarning = lambda msg, cat, *a, **k: print(f"{cat.__name__}: {msg}", file=sys.stderr)
        assert main(["evaluate", str(tmp_path / "cut"), "--gt", str(gt), "-m", "mlplc2"]) == 0
    cap = capsys.readouterr()
    lines = [ln for ln in cap.err.splitlines() if "incomplete results" in ln]
    assert len(lines) == 1 and lines[0].startswith("mlplc2: warning: "), cap.err   # one line, not Python's
    assert "(the run was interrupted after 18 frames)" in lines[0] and "EvaluationWarning" not in cap.err
    assert "1 approaching object(s) outside the processed frames" in cap.out


def test_a_run_that_ends_before_the_contact_says_so(scene, tmp_path, capsys):
    """A run stopped before a labelled collision (`mlplc2 run --end`, complete as asked) scores it as missed:
    the evaluation says why in one warning line (it said nothing)."""
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps({"clips": {"clips/two.avi": {"label": "collision", "contact_frame": 45}}}))
    assert main(["run", str(scene["video"]), "-m", "lgmd2", "--end", "10", "--out", str(tmp_path / "part"),
                 "-q"]) == 0
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("always", EvaluationWarning)
        warnings.showwarning = lambda msg, cat, *a, **k: print(f"{cat.__name__}: {msg}", file=sys.stderr)
        assert main(["evaluate", str(tmp_path / "part"), "--gt", str(gt)]) == 0
    cap = capsys.readouterr()
    assert cap.err.splitlines() == [f"mlplc2: warning: {tmp_path / 'part'}: the results end at frame 9, before the "
                                    f"contact at frame 45 of clips/two.avi: a collision not warned of by then is "
                                    f"scored as missed"], cap.err
    assert "| lgmd2 | clips/two.avi | collision | no |" in cap.out
    # a run that reaches the contact: no such line
    with warnings.catch_warnings():
        warnings.simplefilter("error", EvaluationWarning)
        evaluate(scene["dir"] / "two_out", json.loads(gt.read_text()), models=["lgmd2"])


def test_inputs_that_are_not_results(scene, tmp_path):
    """Say what is wrong instead of 'no ground truth'."""
    text = tmp_path / "afile"
    text.write_text("hello\n")
    empty = tmp_path / "emptydir"
    empty.mkdir()
    partial = tmp_path / "partial"
    partial.mkdir()
    shutil.copy(scene["dir"] / "two_out" / "responses.csv", partial)
    for item, message in ((text, "afile: not a results folder .* nor a video"),
                          (empty, "emptydir: no results in this folder .* and no images"),
                          (partial, "partial: no fields.json next to responses.csv, the run did not finish")):
        with pytest.raises(InputValueError, match="nothing to evaluate: .*" + message) as exc:
            evaluate(item, scene["gt"])
        assert "no ground truth" not in str(exc.value)
    # next to good results, they are warnings and the rest is scored
    with pytest.warns(EvaluationWarning) as rec:
        ev = evaluate([scene["dir"] / "two_out", text, partial], scene["gt"])
    msgs = [str(w.message) for w in rec]
    assert any("afile: not a results folder" in m for m in msgs) and any("partial: no fields.json" in m for m in msgs)
    assert ev.models["mlplc2"]["videos"] == 1 and ev.skipped == []
    # a video without ground truth is still 'skipped' (no ground truth)
    video = tmp_path / "other.avi"
    shutil.copy(scene["video"], video)
    with pytest.raises(InputValueError, match="no ground truth .* for .*other.avi"):
        evaluate(video, scene["gt"])


def test_cli_evaluate_gt_folder(scene, tmp_path, capsys):
    assert main(["evaluate", str(scene["dir"] / "two_out"), "--gt", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mlplc2: error:") and "is a folder, not a ground truth JSON file" in err


# ---------------------------------------------------------------------------
# command line
# ---------------------------------------------------------------------------
def test_cli_evaluate(scene, tmp_path, capsys):
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps(scene["gt"]))
    code = main(["evaluate", str(scene["dir"] / "two_out"), "--gt", str(gt), "--out", str(tmp_path / "ev"),
                 "-m", "mlplc2"])
    out = capsys.readouterr().out
    assert code == 0
    assert "| mlplc2 | 1 | 2 | 2/2 |" in out and "lgmd2" not in out.split("wrote")[0]
    assert (tmp_path / "ev" / "evaluation.md").is_file() and (tmp_path / "ev" / "evaluation.json").is_file()
    ev = json.loads((tmp_path / "ev" / "evaluation.json").read_text())
    assert list(ev["models"]) == ["mlplc2"]


def test_cli_evaluate_folder_of_videos(tmp_path, capsys):
    """A folder of videos is read as batch reads it: each video is run and scored."""
    clips = tmp_path / "clips"
    clips.mkdir()
    truth = {}
    for name, center in (("a.avi", (30, 30)), ("b.avi", (60, 40))):
        st = stimuli.scene([stimuli.SceneObject(center=center, onset=2, approach=16, hold=4, recede=0)],
                           size=(96, 72), frames=24, background="plain", scroll=0.0)
        write_video(clips / name, st.frames, FPS)
        truth[name] = st.to_ground_truth()
    (tmp_path / "gt.json").write_text(json.dumps({"videos": truth}))
    assert main(["evaluate", str(clips), "--gt", str(tmp_path / "gt.json"), "-m", "mlplc2,lgmd2",
                 "--out", str(tmp_path / "ev"), "-q"]) == 0
    assert capsys.readouterr().err == ""
    ev = json.loads((tmp_path / "ev" / "evaluation.json").read_text())
    assert sorted(ev["models"]) == ["lgmd2", "mlplc2"]
    assert sorted(v["video"] for v in ev["videos"] if v["model"] == "mlplc2") == ["a.avi", "b.avi"]
    assert ev["models"]["mlplc2"]["objects"] == 2


def test_cli_evaluate_bad_gt(scene, tmp_path, capsys):
    gt = tmp_path / "gt.json"
    gt.write_text('{"videos": {"x.avi": {"size": [1, 1]}}}')
    assert main(["evaluate", str(scene["dir"] / "two_out"), "--gt", str(gt)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mlplc2: error:") and "needs 'objects'" in err and len(err.strip().splitlines()) == 1


def test_evaluation_type():
    assert isinstance(evaluate(_result("v.avi", 120), OBJ_GT), Evaluation)
    assert mlplc2.evaluate is evaluate


def test_missing_input(scene, tmp_path):
    with pytest.raises(InputValueError, match="no such file"):
        evaluate(tmp_path / "nothing.avi", scene["gt"])


# =============================================================================
# The warning metrics (docs/evaluation.md, "Warning metrics") on small hand-made cases
# =============================================================================
# Every case is built by hand: ground truth as a dict (3-D objects with ``kind``, ``contact_frame``
# and a track; labelled clips with ``contact_frame``, ``danger_onset_frame`` and the collider's
# track) and model outputs as :class:`~mlplc2.runner.RunResult` s (or a results folder), so every
# expected number below is worked out on paper from the definitions. No model runs.
#
# Frame rate 10 fps throughout (``WARN_FPS``): ``LATE_S`` and ``EARLY_S`` (0.5 s) are 5 frames.
WARN_FPS = 10.0
SIZE = (200, 100)


def test_windows_are_half_a_second():
    """The expected numbers below assume 0.5 s windows (5 frames at 10 fps)."""
    assert (LATE_S, EARLY_S) == (0.5, 0.5)


# ---------------------------------------------------------------------------
# builders
# ---------------------------------------------------------------------------
def T(frame, tid, x, y, *, warn=False, ttc=None, w=8.0, h=8.0, miss=None):
    """One targets.csv row (as the runner writes them)."""
    return {"frame": frame, "model": None, "target_id": tid, "x": x, "y": y, "width": w, "height": h,
            "ttc_s": ttc, "miss": miss, "warning": int(warn), "fields": "", "azimuth_deg": None,
            "elevation_deg": None, "ttc_age_s": None if ttc is None else 0.0}


def result(source, frames, *, targets=(), alarms=(), fields=None, model="mlplc2", size=SIZE, fps=WARN_FPS, scale=1.0):
    """A RunResult of ``frames`` frames: per frame the rows of ``fields[frame] = [(id, x, y, alarm)]``,
    else one field-less row (``collision`` on ``alarms``); and the given target rows. ``scale``
    multiplies every position and size (a run at another size)."""
    rows = []
    for f in range(frames):
        for fid, x, y, c in (fields or {}).get(f, [(None, None, None, f in set(alarms))]):
            rows.append({"frame": f, "time_s": f / fps, "model": model, "field_id": fid,
                         "x": None if x is None else x * scale, "y": None if y is None else y * scale,
                         "response": 0.0, "collision": int(c)})
    trows = []
    for t in targets:
        t = dict(t, model=model)
        for k in ("x", "y", "width", "height"):
            t[k] = t[k] * scale
        trows.append(t)
    sz = (int(size[0] * scale), int(size[1] * scale))
    return RunResult(source=source, models=[model], fps=fps, size=sz, model_size=sz, n_frames=frames,
                     rows=rows, fields={model: []}, targets=trows)


def obj(oid, kind, frames, x, y, width, *, contact=None, ttc=None, height=None):
    """A 3-D object tracked over ``frames`` at (x, y); ``width(f)``/``ttc(f)`` callables or constants."""
    wf = width if callable(width) else (lambda f: width)
    hf = height if callable(height) else (wf if height is None else (lambda f: height))
    tf = ttc if callable(ttc) else (lambda f: ttc)
    rows = [[f, x, y, wf(f), hf(f), tf(f), 0.0 if kind == "collision" else None] for f in frames]
    return {"id": oid, "kind": kind, "contact_frame": contact, "track_columns": list(TRACK_COLUMNS),
            "track": rows}


def video_truth(objects, frames=30, size=SIZE):
    return {"size": list(size), "frames": frames, "fps": WARN_FPS, "objects": objects}


def growing(f):
    return 10.0 + f            # px: >= 16 from frame 6 on


def colliding(oid=1, x=50, y=50, contact=20):
    """A collision object at (x, y), in view in frames [0, contact), width 10 + f, true TTC (contact - f) / fps."""
    return obj(oid, "collision", range(contact), x, y, growing, contact=float(contact),
               ttc=lambda f: (contact - f) / WARN_FPS)


def warn_summary(ev, model="mlplc2"):
    return ev.models[model]["warnings"]


def wobj(ev, model="mlplc2", video=None, oid=1):
    return next(o for o in ev.warning_objects
                if o["model"] == model and o["object"] == oid and (video is None or o["video"] == video))


def wvid(ev, video, model="mlplc2"):
    return next(v for v in ev.warning_videos if v["model"] == model and v["video"] == video)


# ---------------------------------------------------------------------------
# collision objects: warned before contact, lead time, TTC at the warning, distance
# ---------------------------------------------------------------------------
def test_first_warning_on_the_object_gives_lead_ttc_and_distance():
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    targets = ([T(f, 1, 53, 54) for f in range(3, 8)]                  # on it, not warning yet
               + [T(f, 1, 53, 54, warn=True) for f in range(8, 20)]    # warns from frame 8
               + [T(5, 2, 150, 50, warn=True)]                         # a warning elsewhere: not on it
               + [T(10, 3, 50, 50, warn=True)])                        # a later warning on it
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    o = wobj(ev)
    assert o["warned"] is True and o["warning_frame"] == 8
    assert o["lead_s"] == pytest.approx(1.2)               # (20 - 8) / 10
    assert o["ttc_at_warning_s"] == pytest.approx(1.2)     # the track's true TTC at frame 8
    assert o["warning_distance_px"] == pytest.approx(5.0)  # (53, 54) from the centre (50, 50)
    s = warn_summary(ev)
    assert (s["collision_objects"], s["warned"], s["warned_rate"]) == (1, 1, 1.0)
    assert s["lead_median_s"] == pytest.approx(1.2) and s["warning_distance_median_px"] == pytest.approx(5.0)


def test_warning_only_after_contact_is_a_miss():
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    ev = evaluate(result("a.mp4", 30, targets=[T(f, 1, 50, 50, warn=True) for f in range(20, 23)]), gt)
    o = wobj(ev)
    assert o["warned"] is False and o["lead_s"] is None and o["warning_frame"] is None
    s = warn_summary(ev)
    assert (s["warned"], s["warned_rate"], s["lead_median_s"]) == (0, 0.0, None)
    # the warnings just after contact (within LATE_S) are not false either
    assert wvid(ev, "a.mp4")["false_frames"] == 0


def test_a_warning_that_goes_on_into_contact_stays_the_objects():
    """A target that warned on the collision object and goes on warning without a break in the last
    LATE_S (5 frames) before its contact is the object's wherever its box centre has gone (the box
    grows past the view at contact); a break, or a centre off the object earlier, is false."""
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}     # contact at 20
    off = (150, 90)
    targets = ([T(f, 1, 50, 50, warn=True) for f in range(10, 15)]          # on the object ...
               + [T(f, 1, *off, warn=True) for f in range(15, 20)]          # ... then past it, unbroken
               + [T(f, 2, 50, 50, warn=True) for f in range(5, 9)]          # on it, a break at 9 ...
               + [T(f, 2, *off, warn=True) for f in range(16, 20)]          # ... then off it: false
               + [T(f, 3, 50, 50, warn=True) for f in range(3, 10)]         # on it ...
               + [T(f, 3, *off, warn=True) for f in range(10, 15)])         # ... off it before the last 0.5 s
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    v = wvid(ev, "a.mp4")
    assert v["false_episodes"] == 2 and v["false_frames"] == len(set(range(16, 20)) | set(range(10, 15)))


def test_a_warning_that_goes_on_through_contact_stays_the_objects_for_late_s():
    """The same unbroken warning, its centre past the object, goes on after the contact at 20: the
    object's for LATE_S (frames 20-25: at the contact a 3-D object's projection may have left the
    view, so its position there cannot place the warning); a warning born there after the contact,
    and the unbroken one after LATE_S, are false."""
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}     # contact at 20
    off = (150, 90)
    targets = ([T(f, 1, 50, 50, warn=True) for f in range(10, 15)]          # on the object ...
               + [T(f, 1, *off, warn=True) for f in range(15, 28)]          # ... then past it, through contact
               + [T(f, 2, *off, warn=True) for f in range(21, 23)])         # born off it after the contact
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    v = wvid(ev, "a.mp4")
    assert wobj(ev)["warned"] is True
    assert v["false_frames"] == len({21, 22} | {26, 27})
    assert v["false_episodes"] == 2


def test_a_warning_anywhere_while_the_collider_fills_the_view_is_not_false():
    """A collider seen by a panning camera has a corner behind the camera plane a frame before its
    contact (its tracked width is not finite, mlplc2.stimuli.world): it fills the view, so a target
    over the whole view warning then, or a frame later, is the hit, not a false warning; the same
    warning two frames before, off the object's box, is false."""
    from mlplc2.stimuli.world.scenes import ApproachObject, approach

    stim = approach([ApproachObject.collision(ttc_s=0.301, at=(20, 20))], size=(160, 120), camera="pan",
                    camera_speed=30, supersample=1)
    vt = stim.truth()
    last = vt.objects[0].track[-1]                  # frame 9, contact at 9.03
    assert last.width is None and vt.objects[0].contact_frame - 1 <= last.frame
    gt = {"videos": {"a.mp4": vt.to_dict()}}
    n = stim.frames.shape[0]
    corner = [T(f, 1, 150, 110, warn=True) for f in (last.frame, last.frame + 1)]   # 170 px from its centre
    v = wvid(evaluate(result("a.mp4", n, targets=corner, size=(160, 120), fps=stim.fps), gt), "a.mp4")
    assert v["false_frames"] == 0
    early = [T(last.frame - 3, 2, 150, 110, warn=True)]
    v = wvid(evaluate(result("a.mp4", n, targets=early, size=(160, 120), fps=stim.fps), gt), "a.mp4")
    assert v["false_episodes_by_cause"] == {"background": 1}


def test_a_false_warning_that_changes_cause_is_one_episode():
    """A target's false warning that slides from a passing object onto the background without a
    break is one episode (the user saw one false warning), counted for the cause of its first
    frame; a break starts another."""
    gt = {"videos": {"a.mp4": video_truth([colliding(),
                                           obj(2, "pass", range(0, 12), 150, 50, 20.0)])}}   # in view in frames 0-11
    targets = ([T(f, 5, 150, 50, warn=True) for f in range(8, 12)]        # on the passing object: "pass" ...
               + [T(f, 5, 150, 90, warn=True) for f in range(12, 15)]     # ... on into the background, unbroken
               + [T(f, 5, 150, 90, warn=True) for f in range(17, 19)])    # a break, then again: a second episode
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    v = wvid(ev, "a.mp4")
    assert v["false_frames"] == 9
    assert v["false_episodes"] == 2 and v["false_episodes_by_cause"] == {"pass": 1, "background": 1}


def test_lead_time_median_and_10th_percentile_over_objects_and_videos():
    """Six collision objects in two videos, warned 2.0, 1.5, 1.0, 0.5, 0.2 s before contact and never."""
    xs = (30, 80, 130)
    def truth(ids):
        return video_truth([obj(i, "collision", range(30), x, 50, 10.0, contact=30.0, ttc=lambda f: (30 - f) / WARN_FPS)
                            for i, x in zip(ids, xs)], frames=40, size=(160, 100))
    gt = {"videos": {"a.mp4": truth((1, 2, 3)), "b.mp4": truth((4, 5, 6))}}
    first = {("a.mp4", 30): 10, ("a.mp4", 80): 15, ("a.mp4", 130): 20, ("b.mp4", 30): 25, ("b.mp4", 80): 28}
    runs = []
    for video in ("a.mp4", "b.mp4"):
        tg = [T(f, x, x, 50, warn=True) for (v, x), f0 in first.items() if v == video for f in range(f0, 30)]
        runs.append(result(video, 40, targets=tg, size=(160, 100)))
    ev = evaluate(runs, gt)
    leads = sorted(o["lead_s"] for o in ev.warning_objects if o["warned"])
    assert leads == pytest.approx([0.2, 0.5, 1.0, 1.5, 2.0])
    s = warn_summary(ev)
    assert (s["collision_objects"], s["warned"]) == (6, 5)
    assert s["warned_rate"] == pytest.approx(5 / 6, abs=1e-4)
    assert s["lead_median_s"] == pytest.approx(1.0)
    # 10th percentile, linear interpolation: position 0.1 * 4 = 0.4 between 0.2 and 0.5
    assert s["lead_p10_s"] == pytest.approx(0.2 + 0.4 * 0.3)
    assert s["ttc_at_warning_median_s"] == pytest.approx(1.0)


def test_collision_object_outside_the_processed_frames_is_not_scored():
    """A run that stopped (or started) where the object is not yet (no longer) before its contact:
    not a miss, only counted."""
    late = obj(1, "collision", range(10, 20), 50, 50, growing, contact=20.0, ttc=lambda f: (20 - f) / WARN_FPS)
    gt = {"videos": {"a.mp4": video_truth([late, colliding(2, x=150)])}}
    ev = evaluate(result("a.mp4", 8, targets=[T(f, 1, 150, 50, warn=True) for f in range(5, 8)]), gt)
    assert [o["object"] for o in ev.warning_objects] == [2]
    s = warn_summary(ev)
    assert (s["collision_objects"], s["warned"], s["collision_objects_outside"]) == (1, 1, 1)


def test_collision_object_out_of_view_before_contact_is_not_scored():
    """A turning camera that looked away: an object in view up to 1.5 s before its contact and
    again only in its last frame (it passes the camera's edge) cannot be warned of: not a miss, only
    counted (``collision_objects_unseen``). One in view through half of its last second is scored."""
    contact = 40
    ttc = lambda f: (contact - f) / WARN_FPS                                  # noqa: E731
    gone = obj(1, "collision", [*range(0, 25), contact - 1], 50, 50, growing, contact=float(contact), ttc=ttc)
    half = obj(2, "collision", range(0, 35), 150, 50, growing, contact=float(contact), ttc=ttc)
    gt = {"videos": {"a.mp4": video_truth([gone, half], frames=45)}}
    ev = evaluate(result("a.mp4", 45), gt)
    assert [o["object"] for o in ev.warning_objects] == [2]
    assert wvid(ev, "a.mp4")["collision_objects_unseen"] == 1
    s = warn_summary(ev)
    assert (s["collision_objects"], s["warned"], s["collision_objects_unseen"]) == (1, 0, 1)


@pytest.mark.parametrize("other_x, other_width_m, other_frames, hidden", [
    (100, 2.0, range(40), True),       # behind the nearer object all its last second
    (117.5, 2.0, range(40), True),     # 3/4 of its box behind it
    (120, 2.0, range(40), False),      # half of its box behind it
    (150, 2.0, range(40), False),      # beside it
    (100, 20.0, range(40), False),     # in front of it (the other object is farther)
    (100, 2.0, range(35), False),      # behind it in only half of its last second
])
def test_collision_object_hidden_behind_a_nearer_object_is_not_scored(other_x, other_width_m, other_frames, hidden):
    """A collision object 10 px and 1 m wide (depth 1/10 of the focal length) at (100, 50), with
    another object 40 px wide: 2 m wide it is nearer (2/40 = 1/20), 20 m farther (1/2). Hidden
    (``HIDDEN_SHARE``: at least 3/4 of its box within the nearer object's) in more than half of its
    last second (frames 30-39), it cannot be warned of: not a miss, only counted as unseen."""
    contact = 40
    ttc = lambda f: (contact - f) / WARN_FPS                                  # noqa: E731
    target = dict(obj(1, "collision", range(contact), 100, 50, 10.0, contact=float(contact), ttc=ttc), width_m=1.0)
    other = dict(obj(2, "static", other_frames, other_x, 50, 40.0), width_m=other_width_m)
    ev = evaluate(result("a.mp4", 45), {"videos": {"a.mp4": video_truth([target, other], frames=45)}})
    assert wvid(ev, "a.mp4")["collision_objects_unseen"] == int(hidden)
    assert [o["object"] for o in ev.warning_objects] == ([] if hidden else [1])


@pytest.mark.parametrize("small_width_m, lead_warned", [(1.0, True), (0.1, False)])
def test_a_warning_on_the_lead_vehicle_is_not_scored_for_a_car_hidden_behind_it(small_width_m, lead_warned):
    """A lead vehicle on a collision course, 40 px and 2 m wide (depth 1/20 of the focal length) at (100, 50),
    and a small car 10 px wide at (104, 50), inside its box: 1 m wide it is farther (1/10), hidden behind the lead
    vehicle, and a warning at (105, 50), nearer the small car's centre, is the lead vehicle's (warned, nothing
    false); 0.1 m wide it is nearer (1/100), in front of it, and the same warning is the small car's (false)."""
    contact = 30
    ttc = lambda f: (contact - f) / WARN_FPS                                  # noqa: E731
    lead = dict(obj(1, "collision", range(contact), 100, 50, 40.0, contact=float(contact), ttc=ttc), width_m=2.0)
    small = dict(obj(2, "pass", range(contact), 104, 50, 10.0), width_m=small_width_m)
    gt = {"videos": {"a.mp4": video_truth([lead, small], frames=35)}}
    ev = evaluate(result("a.mp4", 35, targets=[T(f, 1, 105, 50, warn=True) for f in range(10, contact)]), gt)
    assert wobj(ev)["warned"] is lead_warned
    assert (wvid(ev, "a.mp4")["false_episodes"] == 0) is lead_warned


@pytest.mark.parametrize("camera, speed, scored", [("pan", 10.0, False), ("static", 0.0, True)])
def test_a_rendered_pan_that_turns_away_from_its_collision_does_not_score_it(camera, speed, scored):
    """A collision aimed at the camera from the left of the view: a camera panning right at 10 deg/s
    has lost it 1.2 s before contact (its truth says so), the same camera standing still has not."""
    o = stimuli.ApproachObject.collision(ttc_s=3.0, at=(15.0, 30.0), width_px=4.0, size=(80, 60), speed_mps=3.0)
    st = stimuli.approach([o], size=(80, 60), fps=WARN_FPS, camera=camera, camera_speed=speed,
                          background="texture", supersample=1)
    ev = evaluate(result("a.mp4", len(st.frames), size=(80, 60)), {"videos": {"a.mp4": st.to_ground_truth()}})
    assert len(ev.warning_objects) == int(scored)
    assert wvid(ev, "a.mp4")["collision_objects_unseen"] == int(not scored)


def test_3d_truth_without_approach_intervals_gets_the_object_metrics_too():
    """The paper's object metrics score a 3-D collision or pass-by given only by its track over
    its tracked frames (no TypeError for a missing ``approach``)."""
    gt = {"videos": {"a.mp4": video_truth([colliding(), obj(2, "recede", range(29), 110, 80, 6.0)])}}
    ev = evaluate(result("a.mp4", 30, fields={f: [(1, 50, 50, f >= 12)] for f in range(4, 20)}), gt)
    (o,) = [o for o in ev.objects if o["model"] == "mlplc2"]
    assert o["object"] == 1 and o["approach"] == [0, 20]
    assert o["detected"] and o["latency_field"] == 4 and o["alarm_frame"] == 12


# ---------------------------------------------------------------------------
# false warnings: frames and episodes per 1000 frames, by cause
# ---------------------------------------------------------------------------
def _scene_with_distractors():
    """Collision object 1 at (50, 50) (frames 0-19, contact 20), pass-by 2 at (150, 50) (frames 0-27),
    receding 3 at (110, 80) (frames 0-28); 30 frames."""
    return {"videos": {"a.mp4": video_truth([
        colliding(),
        obj(2, "pass", range(28), 150, 50, 10.0, contact=29.0, ttc=lambda f: (29 - f) / WARN_FPS),
        obj(3, "recede", range(29), 110, 80, 6.0)])}}


def test_false_warnings_by_cause():
    targets = ([T(f, 2, 150, 50, warn=True) for f in (*range(10, 15), 20, 21)]  # pass-by: 7 frames, 2 runs
               + [T(f, 3, 180, 10, warn=True) for f in (0, 1)]                 # background: 2 frames, 1 run
               + [T(5, 4, 110, 80, warn=True)]                                 # receding: 1 frame
               + [T(f, 1, 50, 50, warn=True) for f in range(8, 27)])           # true to 19, late 20-25, 26 false
    ev = evaluate(result("a.mp4", 30, targets=targets), _scene_with_distractors())
    v = wvid(ev, "a.mp4")
    assert v["frames_scored"] == 30
    assert v["false_frames_by_cause"] == {"background": 3, "distractor": 1, "pass": 7}
    assert v["false_episodes_by_cause"] == {"background": 2, "distractor": 1, "pass": 2}
    assert v["false_frames"] == 11            # frames 0, 1, 5, 10-14, 20, 21, 26
    assert v["false_episodes"] == 5
    s = warn_summary(ev)
    assert s["frames"] == 30
    assert s["false_frames_per_1000"] == pytest.approx(11 / 30 * 1000, abs=1e-3)
    assert s["false_episodes_per_1000"] == pytest.approx(5 / 30 * 1000, abs=1e-3)
    assert s["false_frames_per_1000_by_cause"] == pytest.approx(
        {"pass": 7000 / 30, "distractor": 1000 / 30, "background": 3000 / 30}, abs=1e-3)
    assert s["false_episodes_per_1000_by_cause"] == pytest.approx(
        {"pass": 2000 / 30, "distractor": 1000 / 30, "background": 2000 / 30}, abs=1e-3)
    assert s["false_frames_pct"] == pytest.approx(100 * 11 / 30, abs=1e-3)
    assert wobj(ev)["warning_frame"] == 8


def test_a_warning_that_moves_off_the_object_is_a_new_false_episode_only_once():
    """One target warning in frames 10-15: on the collision object to 12, then on the background:
    one false episode (13-15), three false frames."""
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    targets = [T(f, 1, 50, 50, warn=True) for f in range(10, 13)] + [T(f, 1, 150, 20, warn=True) for f in range(13, 16)]
    v = wvid(evaluate(result("a.mp4", 30, targets=targets), gt), "a.mp4")
    assert v["false_frames_by_cause"] == {"background": 3} and v["false_episodes_by_cause"] == {"background": 1}


def test_global_alarm_model():
    """An LGMD-like model (no targets, no position): its alarm is its warning. It warns a collision
    object in view; after contact + LATE_S its alarm takes the cause of the objects in view."""
    alarms = [3, 4, 5, 6,      # collision object in view: true, warned at 3
              22, 23, 24,      # within LATE_S after the contact at 20: neither true nor false
              27,              # pass-by (and receding) in view: "pass"
              28,              # only the receding object in view: "distractor"
              29]              # nothing in view: "background"
    ev = evaluate(result("a.mp4", 30, alarms=alarms, model="lgmd2"), _scene_with_distractors())
    o = wobj(ev, "lgmd2")
    assert o["warned"] and o["warning_frame"] == 3 and o["lead_s"] == pytest.approx(1.7)
    assert o["ttc_at_warning_s"] == pytest.approx(1.7)
    assert o["warning_distance_px"] is None and o["targets"] is None     # no position, no targets
    v = wvid(ev, "a.mp4", "lgmd2")
    assert v["false_frames_by_cause"] == {"background": 1, "distractor": 1, "pass": 1}
    # frames 27-29 are one unbroken false alarm: one episode, for the cause of its first frame
    assert v["false_episodes"] == 1 and v["false_episodes_by_cause"] == {"pass": 1}
    s = warn_summary(ev, "lgmd2")
    assert s["false_frames_per_1000"] == pytest.approx(100.0)
    assert s["ttc_coverage"] is None and s["fragmentation"] is None
    assert all(s[f"ttc_n_{b}"] == 0 for b in ("0-1s", "1-3s", "3-6s"))


def test_global_alarm_before_the_object_is_in_view_is_background():
    gt = {"videos": {"a.mp4": video_truth([obj(1, "collision", range(10, 20), 50, 50, growing, contact=20.0,
                                               ttc=lambda f: (20 - f) / WARN_FPS)])}}
    ev = evaluate(result("a.mp4", 30, alarms=[5, 6, 12], model="lgmd2"), gt)
    assert wobj(ev, "lgmd2")["warning_frame"] == 12
    assert wvid(ev, "a.mp4", "lgmd2")["false_frames_by_cause"] == {"background": 2}


# ---------------------------------------------------------------------------
# time to contact: RTE and MiD per true-TTC bin, coverage
# ---------------------------------------------------------------------------
def test_ttc_errors_per_bin_and_coverage():
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    targets = [T(3, 1, 50, 50, ttc=9.0),          # width 13 < 16 px: not scored
               T(8, 1, 50, 50, ttc=1.2),          # true 1.2: exact
               T(9, 1, 50, 50, ttc=1.21),         # true 1.1: 10 % too late
               T(9, 5, 60, 50, ttc=5.0),          # also on it, but further from the centre: not the one
               T(10, 1, 50, 50, ttc=1.5),         # true 1.0: 50 %
               T(11, 1, 50, 50),                  # no estimate
               T(12, 6, 150, 50, ttc=1.0),        # an estimate off the object
               T(15, 1, 50, 50, ttc=0.25)]        # true 0.5: half
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    o = wobj(ev)
    assert o["ttc_frames"] == 14                   # frames 6-19: at least 16 px wide, before contact
    assert o["ttc_estimated"] == 4                 # frames 8, 9, 10, 15
    pairs = sorted(tuple(e) for e in o["ttc_errors"])          # (true, estimate) per frame
    assert [v for e in pairs for v in e] == pytest.approx([0.5, 0.25, 1.0, 1.5, 1.1, 1.21, 1.2, 1.2])
    s = warn_summary(ev)
    assert s["ttc_coverage"] == pytest.approx(4 / 14, abs=1e-4)
    assert (s["ttc_n_0-1s"], s["ttc_n_1-3s"], s["ttc_n_3-6s"]) == (1, 3, 0)
    # median relative error: |1.21 - 1.1| / 1.1 = 10 % is the middle of 0, 10, 50 %
    assert s["ttc_rte_pct_1-3s"] == pytest.approx(10.0)
    assert s["ttc_rte_pct_0-1s"] == pytest.approx(50.0)
    assert s["ttc_rte_pct_3-6s"] is None and s["ttc_mid_3-6s"] is None
    # MiD (TSTTC): |log(s_est) - log(s_true)| * 1e4 with the motion in depth over 0.1 s,
    # s(ttc) = ttc / (ttc + 0.1): ln(1.21 / 1.31) - ln(1.1 / 1.2) = 0.0076046
    assert s["ttc_mid_1-3s"] == pytest.approx(76.0, abs=0.06)
    # ln(0.5 / 0.6) - ln(0.25 / 0.35) = 0.1541507
    assert s["ttc_mid_0-1s"] == pytest.approx(1541.5, abs=0.06)


def test_a_frame_a_hair_before_the_contact_gives_no_ttc_error():
    """A frame whose true time to contact is positive but under the 0.1 ms the errors are recorded to
    (holdout 40's scenes had one) is not scored: no relative error divides by a true 0."""
    gt = {"videos": {"a.mp4": video_truth([colliding(contact=20)])}}
    gt["videos"]["a.mp4"]["objects"][0]["track"][19][5] = 2e-5      # frame 19: 0.00002 s to contact
    targets = [T(18, 1, 50, 50, ttc=0.3), T(19, 1, 50, 50, ttc=0.05)]    # true 0.2 at frame 18: 50 % late
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    assert [tuple(e) for e in wobj(ev)["ttc_errors"]] == [(0.2, 0.3)]
    assert warn_summary(ev)["ttc_rte_pct_0-1s"] == pytest.approx(50.0)


# ---------------------------------------------------------------------------
# fragmentation: distinct targets per collision object
# ---------------------------------------------------------------------------
def test_fragmentation_counts_distinct_targets_while_the_object_covers_at_most_half_the_view():
    """Targets per object count while the object is at most half the frame's larger side wide
    (FRAGMENT_SHARE): beyond, boxes at its edges (the ground at its foot) lie "on" it."""
    big = obj(2, "collision", range(30), 150, 50,
              lambda f: 250.0 if f >= 25 else 150.0 if f >= 20 else 10.0, contact=30.0,
              ttc=lambda f: (30 - f) / WARN_FPS)
    gt = {"videos": {"a.mp4": video_truth([colliding(), big], frames=32)}}
    targets = ([T(f, 1, 50, 50) for f in range(3, 11)] + [T(f, 5, 52, 50) for f in range(12, 16)]   # two on 1
               + [T(10, 7, 100, 90)]                            # on neither
               + [T(10, 8, 150, 50)]                            # on 2
               + [T(22, 6, 215, 50)]                            # at 2's edge while it is 150 of 200 px wide
               + [T(27, 9, 10, 10)])                            # "on" 2 only while it is wider than the frame
    ev = evaluate(result("a.mp4", 32, targets=targets), gt)
    assert wobj(ev, oid=1)["targets"] == 2
    assert wobj(ev, oid=2)["targets"] == 1
    assert warn_summary(ev)["fragmentation"] == pytest.approx(1.5)


def test_one_target_a_frame_stands_for_an_object_the_one_that_stood_for_it_before():
    """Fragmentation counts the targets that stood for the object, one a frame (CLEAR MOT's correspondence): its
    own target, while it lasts, even where a target of the background passes nearer its centre within the match
    radius (not a second target of it: a false target, scored by its warnings, if any); when its own is lost the
    nearest one takes over, and is a second."""
    gt = {"videos": {"a.mp4": video_truth([colliding()], frames=22)}}
    own = [T(f, 1, 56, 50) for f in range(2, 12)]                          # 6 px right of its centre
    passing = [T(f, 4, 30 + 4 * (f - 4), 52) for f in range(4, 10)]      # x 30-50: through the centre
    ev = evaluate(result("a.mp4", 22, targets=own + passing), gt)
    assert wobj(ev)["targets"] == 1
    later = [T(f, 9, 48, 50) for f in range(13, 18)]                       # the object's after its own is lost
    ev = evaluate(result("a.mp4", 22, targets=own + passing + later), gt)
    assert wobj(ev)["targets"] == 2



def test_a_target_on_a_neighbour_is_the_neighbours_not_a_fragment_of_the_collision_object():
    """A target counts for the one object it lies nearest: the target on a passing car 15 px beside
    the collision object's box is the car's (within the match radius of both boxes), so the
    collision object keeps one target, and that target's time to contact is not the collider's."""
    passing = obj(2, "pass", range(20), 90, 50, 20)                 # box x 80-100; the collider's 42-64
    gt = {"videos": {"a.mp4": video_truth([colliding(), passing], frames=22)}}
    targets = ([T(f, 1, 50, 50, ttc=(20 - f) / WARN_FPS) for f in range(5, 12)]
               + [T(f, 2, 75, 50, ttc=0.1) for f in range(5, 18)])   # 5 px from the car, 12-18 px from the collider
    ev = evaluate(result("a.mp4", 22, targets=targets), gt)
    o = wobj(ev, oid=1)
    assert o["targets"] == 1
    assert o["ttc_errors"] and all(est == pytest.approx(true, rel=1e-3) for true, est in o["ttc_errors"])

def test_a_warning_on_a_passing_car_beside_the_collision_object_is_the_cars_false_warning():
    """A warning stands for the one object it lies nearest: a target warning on a passing car 5 px
    from the car's box and 12-18 px from the collision object's box (within the match radius of
    both) warns of the car. It is a false warning ("pass") and does not warn the collision object,
    which is warned only by the target on it, later."""
    passing = obj(2, "pass", range(20), 90, 50, 20)                 # box x 80-100; the collider's 42-64
    gt = {"videos": {"a.mp4": video_truth([colliding(), passing], frames=22)}}
    targets = ([T(f, 2, 75, 50, warn=True) for f in range(4, 8)]       # on the car
               + [T(f, 1, 50, 50, warn=True) for f in range(12, 20)])  # on the collision object
    ev = evaluate(result("a.mp4", 22, targets=targets), gt)
    o = wobj(ev, oid=1)
    assert o["warned"] and o["warning_frame"] == 12
    v = wvid(ev, "a.mp4")
    assert v["false_frames_by_cause"] == {"pass": 4} and v["false_episodes"] == 1


def test_a_warning_on_one_of_two_collision_objects_does_not_warn_the_other():
    """Two collision objects side by side (boxes 17 px apart at the start): the warning on the left
    one lies within the match radius of the right one's box, but it warns of the left one only."""
    left, right = colliding(1, x=50, contact=20), colliding(2, x=80, contact=25)
    gt = {"videos": {"a.mp4": video_truth([left, right])}}
    targets = [T(f, 1, 58, 50, warn=True) for f in range(3, 20)]     # on the left one, 7-15 px from the right one's box
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    assert wobj(ev, oid=1)["warned"] and wobj(ev, oid=1)["warning_frame"] == 3
    assert not wobj(ev, oid=2)["warned"]
    assert wvid(ev, "a.mp4")["false_frames"] == 0


# ---------------------------------------------------------------------------
# labelled clips
# ---------------------------------------------------------------------------
def _clips():
    track = [[0, 100, 50, 20], [30, 100, 50, 80]]       # the collider grows from 20 to 80 px
    collision = {"label": "collision", "fps": WARN_FPS, "size": list(SIZE), "contact_frame": 30,
                 "danger_onset_frame": 20, "track": track}
    return {"clips": {"c1.mp4": collision, "c2.mp4": dict(collision), "c3.mp4": {"label": "no_collision"},
                      "c4.mp4": {"label": "no_collision"}}}


def test_clip_rules_early_elsewhere_and_after_contact():
    """danger onset 20, EARLY_S = 5 frames: a warning before frame 15 is false ("early"), from 15 on
    it is a warning on the collider; a warning off the collider is false ("elsewhere"); frames from the
    contact (30) on are not scored."""
    c1 = ([T(f, 1, 100, 50, warn=True) for f in (12, 13)]               # early
          + [T(f, 1, 100, 50, warn=True) for f in range(15, 30)]        # from the onset - 0.5 s: warned at 15
          + [T(18, 2, 10, 10, warn=True)]                               # elsewhere
          + [T(f, 2, 10, 10, warn=True) for f in (31, 32)])             # after contact: not scored
    c2 = [T(f, 1, 100, 50, warn=True) for f in range(10, 15)]           # only early: missed
    c3 = [T(5, 1, 20, 20, warn=True)]                                   # a no-collision clip with a warning
    runs = [result("c1.mp4", 40, targets=c1), result("c2.mp4", 40, targets=c2), result("c3.mp4", 40, targets=c3),
            result("c4.mp4", 40)]
    ev = evaluate(runs, _clips())
    v1 = wvid(ev, "c1.mp4")
    assert v1["outcome"] == {"label": "collision", "warned": True, "missed": False, "false": True, "lead_s": 1.5,
                             "unplaced": False, "unplaced_lead_s": None, "alarm_lead_s": None}
    assert v1["frames_scored"] == 30
    assert v1["false_frames_by_cause"] == {"early": 2, "elsewhere": 1}
    v2 = wvid(ev, "c2.mp4")
    assert v2["outcome"]["warned"] is False and v2["outcome"]["missed"] is True and v2["outcome"]["false"] is True
    assert v2["false_frames_by_cause"] == {"early": 5}
    assert wvid(ev, "c3.mp4")["outcome"] == {"label": "no_collision", "warned": None, "missed": None,
                                             "false": True, "lead_s": None, "unplaced": None,
                                             "unplaced_lead_s": None, "alarm_lead_s": None}
    assert wvid(ev, "c4.mp4")["outcome"]["false"] is False
    s = warn_summary(ev)
    assert (s["clips"], s["clips_collision"], s["clips_warned"], s["clips_missed"], s["clips_false"]) == (4, 2, 1, 1, 3)
    assert s["clip_lead_median_s"] == pytest.approx(1.5)
    # clips are not part of the generated-suite metrics
    assert s["collision_objects"] == 0 and s["frames"] == 0 and s["false_frames_per_1000"] is None
    table = ev.clip_warning_table()
    assert "| mlplc2 | c1.mp4 | collision | yes | 1.50 | - | no | 3 |" in table
    assert "| mlplc2 | c2.mp4 | collision | no | - | - | no | 5 |" in table
    assert "| mlplc2 | c4.mp4 | no_collision | - | - | - | - | 0 |" in table


def test_field_alarm_on_the_collider_against_the_warning():
    """Issue 22: the first field alarm on a clip's collider beside its first warning. c1: the alarm
    on the collider at 16 (one off it at 15 does not count), the warning at 18: later; c2: the
    alarm at 17, the warning at 15: not later; a model without targets has no alarm_frame."""
    on, off = (100, 50), (10, 10)
    f1 = {f: [(1, *off, True)] for f in (15,)} | {f: [(2, *on, True)] for f in range(16, 30)}
    f2 = {f: [(2, *on, f >= 17)] for f in range(10, 30)}
    runs = [result("c1.mp4", 40, fields=f1, targets=[T(f, 1, 100, 50, warn=True) for f in range(18, 30)]),
            result("c2.mp4", 40, fields=f2, targets=[T(f, 1, 100, 50, warn=True) for f in range(15, 30)]),
            result("c1.mp4", 40, alarms=range(16, 30), model="lgmd2")]
    ev = evaluate(runs, _clips())
    o1, o2 = wobj(ev, oid="collider", video="c1.mp4"), wobj(ev, oid="collider", video="c2.mp4")
    assert (o1["alarm_frame"], o1["alarm_lead_s"], o1["warning_frame"]) == (16, pytest.approx(1.4), 18)
    assert (o2["alarm_frame"], o2["warning_frame"]) == (17, 15)
    assert wvid(ev, "c1.mp4")["outcome"]["alarm_lead_s"] == pytest.approx(1.4)
    assert warn_summary(ev)["clips_later_than_alarm"] == 1
    assert wobj(ev, "lgmd2", oid="collider", video="c1.mp4")["alarm_frame"] is None
    assert "| mlplc2 | c1.mp4 | collision | yes | 1.20 | 1.40 | no | 0 |" in ev.clip_warning_table()


def test_global_alarm_on_clips():
    runs = [result("c1.mp4", 40, alarms=[10, 17, 18], model="lgmd2"),   # early at 10, warned at 17
            result("c3.mp4", 40, alarms=[], model="lgmd2")]
    ev = evaluate(runs, _clips())
    o = wvid(ev, "c1.mp4", "lgmd2")["outcome"]
    assert o["warned"] is True and o["false"] is True and o["lead_s"] == pytest.approx(1.3)
    assert wvid(ev, "c3.mp4", "lgmd2")["outcome"]["false"] is False
    # the clip-level classification of the same alarms: an alarm before contact is a TP
    assert ev.models["lgmd2"]["tp"] == 1 and ev.models["lgmd2"]["tn"] == 1


def test_collision_clip_without_a_track():
    """Without the collider's track its position is unknown: a warning from the danger onset - 0.5 s
    to the contact cannot be placed on it. It is reported apart ("unplaced", with its time before
    contact), never as warned with a lead time (it may lie on the background); the early rule
    still holds, and a clip without any warning before contact is missed."""
    gt = {"clips": {"c.mp4": {"label": "collision", "collision_frame": 30, "danger_onset_frame": 20},
                    "d.mp4": {"label": "collision", "contact_frame": 30},
                    "e.mp4": {"label": "collision", "contact_frame": 30}}}
    runs = [result("c.mp4", 40, targets=[T(f, 1, 10, 10, warn=True) for f in (12, 17, 18)]),
            result("d.mp4", 40, alarms=[25], model="lgmd2"),
            result("e.mp4", 40, targets=[T(f, 1, 10, 10, warn=True) for f in (31, 32)])]   # after contact only
    ev = evaluate(runs, gt)
    v = wvid(ev, "c.mp4")
    assert v["outcome"] == {"label": "collision", "warned": False, "missed": False, "false": True, "lead_s": None,
                            "unplaced": True, "unplaced_lead_s": 1.3, "alarm_lead_s": None}
    assert v["false_frames_by_cause"] == {"early": 1}
    d = wvid(ev, "d.mp4", "lgmd2")["outcome"]
    assert (d["warned"], d["lead_s"], d["unplaced"], d["unplaced_lead_s"]) == (False, None, True, pytest.approx(0.5))
    e = wvid(ev, "e.mp4")["outcome"]
    assert (e["warned"], e["missed"], e["unplaced"]) == (False, True, False)
    o = wobj(ev, oid="collider", video="c.mp4")
    assert (o["warned"], o["warning_frame"], o["unplaced_frame"]) == (False, None, 17)
    s = warn_summary(ev)
    assert (s["clips_warned"], s["clips_missed"], s["clips_unplaced"], s["clip_lead_median_s"]) == (0, 1, 1, None)
    assert "| mlplc2 | c.mp4 | collision | no | - | - | yes, 1.30 | 1 |" in ev.clip_warning_table()


# ---------------------------------------------------------------------------
# results at another size than the truth; results folders
# ---------------------------------------------------------------------------
def _case():
    gt = {"videos": {"a.mp4": video_truth([colliding(), obj(2, "pass", range(28), 150, 50, 10.0, contact=29.0)])}}
    targets = ([T(f, 1, 53, 54, warn=True, ttc=(20 - f) / WARN_FPS * 1.1) for f in range(8, 20)]
               + [T(f, 2, 150, 50, warn=True) for f in (10, 11)])
    return gt, targets


def test_results_at_another_size_are_scaled_to_the_truth():
    gt, targets = _case()
    base = evaluate(result("a.mp4", 30, targets=targets), gt)
    double = evaluate(result("a.mp4", 30, targets=targets, scale=2.0), gt)
    assert double.warning_objects == base.warning_objects
    assert double.warning_videos == base.warning_videos
    assert wobj(double)["warning_distance_px"] == pytest.approx(5.0)    # truth pixels
    assert wvid(double, "a.mp4")["false_frames_by_cause"] == {"pass": 2}
    # unscaled, the doubled positions miss the object: the test can fail
    gt_unsized = {"videos": {"a.mp4": dict(gt["videos"]["a.mp4"], size=None)}}
    assert wobj(evaluate(result("a.mp4", 30, targets=targets, scale=2.0), gt_unsized))["warned"] is False


def _write_folder(folder, res: RunResult):
    folder.mkdir(parents=True)
    with open(folder / "responses.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(res.rows)
    with open(folder / "targets.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=TARGET_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(res.targets)
    (folder / "fields.json").write_text(json.dumps(
        {"video": res.source, "fps": res.fps, "size": list(res.size), "start": 0, "n_frames": res.n_frames,
         "complete": True, "models": {m: [] for m in res.models}}))


def test_results_folder_scores_like_the_run_result(tmp_path):
    gt, targets = _case()
    res = result("a.mp4", 30, targets=targets)
    _write_folder(tmp_path / "a_mlplc2", res)
    ev = evaluate(tmp_path / "a_mlplc2", gt)
    mem = evaluate(res, gt)
    assert ev.warning_objects == mem.warning_objects and ev.warning_videos == mem.warning_videos
    assert wobj(ev)["warning_frame"] == 8 and ev.models["mlplc2"]["warnings"] == mem.models["mlplc2"]["warnings"]


def test_results_folder_with_a_targets_csv_from_before_ttc_age_s_scores_alike(tmp_path):
    """A ``targets.csv`` written before its ``ttc_age_s``, ``ttc_sigma_s`` and ``held_by`` columns (the last ones)
    loads and scores as a new one."""
    assert TARGET_COLUMNS[-3:] == ("ttc_age_s", "ttc_sigma_s", "held_by")
    gt, targets = _case()
    res = result("a.mp4", 30, targets=targets)
    _write_folder(tmp_path / "new", res)
    _write_folder(tmp_path / "old", res)
    with open(tmp_path / "old" / "targets.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=TARGET_COLUMNS[:-3], extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        w.writerows(res.targets)
    old, new = evaluate(tmp_path / "old", gt), evaluate(tmp_path / "new", gt)
    assert old.warning_objects == new.warning_objects and wobj(old)["warning_frame"] == 8
    assert old.models["mlplc2"]["warnings"] == new.models["mlplc2"]["warnings"]


def test_results_folder_without_targets_csv_is_scored_by_its_alarm(tmp_path):
    """Results of a model with targets but no targets.csv (written before the target layer):
    its fields in alarm are its warnings, not "never warned"."""
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    fields = {f: [(1, 52, 50, f >= 12), (2, 150, 20, f == 3)] for f in range(3, 16)}
    res = result("a.mp4", 30, fields=fields)
    _write_folder(tmp_path / "old", res)
    (tmp_path / "old" / "targets.csv").unlink()
    ev = evaluate(tmp_path / "old", gt)
    o = wobj(ev)
    assert o["warned"] and o["warning_frame"] == 12 and o["lead_s"] == pytest.approx(0.8)
    assert o["warning_distance_px"] == pytest.approx(2.0) and o["targets"] == 1     # field 1 only
    assert wvid(ev, "a.mp4")["false_frames_by_cause"] == {"background": 1}          # field 2 at frame 3


# ---------------------------------------------------------------------------
# the Markdown table
# ---------------------------------------------------------------------------
def test_warning_table_shows_the_metrics():
    gt, targets = _case()
    ev = evaluate([result("a.mp4", 30, targets=targets), result("a.mp4", 30, alarms=[15], model="lgmd2")], gt)
    table = ev.warning_table()
    head, _, mrow, lrow = table.splitlines()
    assert mrow.startswith("| mlplc2 | 1/1 (100%) | 1.20 | 1.20 | 1.20 | 5.0 |")
    assert lrow.startswith("| lgmd2 | 1/1 (100%) | 0.50 | 0.50 | 0.50 | - |")
    assert "distance" in head and "MiD" in head
    cells = [c.strip() for c in mrow.strip("|").split("|")]
    cols = [c.strip() for c in head.strip("|").split("|")]
    # 2 pass-by frames, one episode, of 30 frames
    assert cells[cols.index("false frames /1000")] == "66.7"
    assert cells[cols.index("false episodes /1000")] == "33.33"
    # est = 1.1 x true: 10 % at every frame; MiD at true 0.1-0.9 s is not one number, but RTE is
    assert cells[cols.index("TTC error 0-1 s (RTE / MiD)")].startswith("10 % / ")
    assert cells[cols.index("TTC error 3-6 s (RTE / MiD)")] == "-"
    assert cells[cols.index("distance (px)")] == "5.0"
    assert math.isclose(warn_summary(ev)["ttc_coverage"], 12 / 14, abs_tol=1e-4)


def test_a_warning_that_lapses_before_contact_is_counted():
    """Two colliders warned 1.0 s before contact (10 fps, contact at 20): one warning held to contact, one that
    blinks for a frame and is silent for 0.9 s. Both are warned (the first warning counts); only the second
    lapsed (silent for at least LAPSE_S), and its share of frames kept is 1 of 10."""
    gt = {"videos": {"a.mp4": video_truth([colliding(1, x=50), colliding(2, x=150)])}}
    targets = ([T(f, 1, 50, 50, warn=True) for f in range(10, 20)]                # held to contact
               + [T(10, 2, 150, 50, warn=True)]                                   # a blink ...
               + [T(f, 2, 150, 50) for f in range(11, 20)])                       # ... then silence
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    held, blink = wobj(ev, oid=1), wobj(ev, oid=2)
    assert held["warned"] and blink["warned"] and held["lead_s"] == blink["lead_s"] == pytest.approx(1.0)
    assert held["warning_kept"] == pytest.approx(1.0) and held["warning_gap_s"] == pytest.approx(0.0)
    assert blink["warning_kept"] == pytest.approx(0.1) and blink["warning_gap_s"] == pytest.approx(0.9)
    s = warn_summary(ev)
    assert s["warnings_lapsed"] == 1 and s["warning_kept_median"] == pytest.approx(0.55)


def test_a_short_break_in_a_warning_is_not_a_lapse():
    """A warning silent for one frame (0.1 s at 10 fps, under LAPSE_S) before contact has not lapsed."""
    assert LAPSE_S > 0.1
    gt = {"videos": {"a.mp4": video_truth([colliding()])}}
    targets = [T(f, 1, 50, 50, warn=f != 15) for f in range(10, 20)]
    ev = evaluate(result("a.mp4", 30, targets=targets), gt)
    assert wobj(ev)["warning_gap_s"] == pytest.approx(0.1) and wobj(ev)["warning_kept"] == pytest.approx(0.9)
    assert warn_summary(ev)["warnings_lapsed"] == 0
