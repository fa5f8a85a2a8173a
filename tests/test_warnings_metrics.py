"""The warning metrics (docs/evaluation.md, "Warning metrics") on small hand-made cases.

Every case is built by hand: ground truth as a dict (3-D objects with ``kind``, ``contact_frame``
and a track; labelled clips with ``contact_frame``, ``danger_onset_frame`` and the collider's
track) and model outputs as :class:`~mlplc2.runner.RunResult` s (or a results folder), so every
expected number below is worked out on paper from the definitions. No model runs.

Frame rate 10 fps throughout: ``LATE_S`` and ``EARLY_S`` (0.5 s) are 5 frames.
"""

from __future__ import annotations

import csv
import json
import math

import pytest

from mlplc2.evaluate import EARLY_S, LATE_S, evaluate
from mlplc2.runner import COLUMNS, TARGET_COLUMNS, RunResult
from mlplc2.truth import TRACK_COLUMNS

FPS = 10.0
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
            "elevation_deg": None}


def result(source, frames, *, targets=(), alarms=(), fields=None, model="mlplc2", size=SIZE, fps=FPS, scale=1.0):
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
    return {"size": list(size), "frames": frames, "fps": FPS, "objects": objects}


def growing(f):
    return 10.0 + f            # px: >= 16 from frame 6 on


def colliding(oid=1, x=50, y=50, contact=20):
    """A collision object at (x, y), in view in frames [0, contact), width 10 + f, true TTC (contact - f) / fps."""
    return obj(oid, "collision", range(contact), x, y, growing, contact=float(contact),
               ttc=lambda f: (contact - f) / FPS)


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


def test_lead_time_median_and_10th_percentile_over_objects_and_videos():
    """Six collision objects in two videos, warned 2.0, 1.5, 1.0, 0.5, 0.2 s before contact and never."""
    xs = (30, 80, 130)
    def truth(ids):
        return video_truth([obj(i, "collision", range(30), x, 50, 10.0, contact=30.0, ttc=lambda f: (30 - f) / FPS)
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
    late = obj(1, "collision", range(10, 20), 50, 50, growing, contact=20.0, ttc=lambda f: (20 - f) / FPS)
    gt = {"videos": {"a.mp4": video_truth([late, colliding(2, x=150)])}}
    ev = evaluate(result("a.mp4", 8, targets=[T(f, 1, 150, 50, warn=True) for f in range(5, 8)]), gt)
    assert [o["object"] for o in ev.warning_objects] == [2]
    s = warn_summary(ev)
    assert (s["collision_objects"], s["warned"], s["collision_objects_outside"]) == (1, 1, 1)


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
        obj(2, "pass", range(28), 150, 50, 10.0, contact=29.0, ttc=lambda f: (29 - f) / FPS),
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
    assert v["false_episodes_by_cause"] == {"background": 1, "distractor": 1, "pass": 1}
    s = warn_summary(ev, "lgmd2")
    assert s["false_frames_per_1000"] == pytest.approx(100.0)
    assert s["ttc_coverage"] is None and s["fragmentation"] is None
    assert all(s[f"ttc_n_{b}"] == 0 for b in ("0-1s", "1-3s", "3-6s"))


def test_global_alarm_before_the_object_is_in_view_is_background():
    gt = {"videos": {"a.mp4": video_truth([obj(1, "collision", range(10, 20), 50, 50, growing, contact=20.0,
                                               ttc=lambda f: (20 - f) / FPS)])}}
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


# ---------------------------------------------------------------------------
# fragmentation: distinct targets per collision object
# ---------------------------------------------------------------------------
def test_fragmentation_counts_distinct_targets_while_the_object_fits_the_frame():
    big = obj(2, "collision", range(30), 150, 50, lambda f: 250.0 if f >= 25 else 10.0, contact=30.0,
              ttc=lambda f: (30 - f) / FPS)
    gt = {"videos": {"a.mp4": video_truth([colliding(), big], frames=32)}}
    targets = ([T(f, 1, 50, 50) for f in range(3, 11)] + [T(f, 5, 52, 50) for f in range(12, 16)]   # two on 1
               + [T(10, 7, 100, 90)]                            # on neither
               + [T(10, 8, 150, 50)]                            # on 2
               + [T(27, 9, 10, 10)])                            # "on" 2 only while it is wider than the frame
    ev = evaluate(result("a.mp4", 32, targets=targets), gt)
    assert wobj(ev, oid=1)["targets"] == 2
    assert wobj(ev, oid=2)["targets"] == 1
    assert warn_summary(ev)["fragmentation"] == pytest.approx(1.5)


# ---------------------------------------------------------------------------
# labelled clips
# ---------------------------------------------------------------------------
def _clips():
    track = [[0, 100, 50, 20], [30, 100, 50, 80]]       # the collider grows from 20 to 80 px
    collision = {"label": "collision", "fps": FPS, "size": list(SIZE), "contact_frame": 30,
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
    assert v1["outcome"] == {"label": "collision", "warned": True, "missed": False, "false": True, "lead_s": 1.5}
    assert v1["frames_scored"] == 30
    assert v1["false_frames_by_cause"] == {"early": 2, "elsewhere": 1}
    v2 = wvid(ev, "c2.mp4")
    assert v2["outcome"]["warned"] is False and v2["outcome"]["missed"] is True and v2["outcome"]["false"] is True
    assert v2["false_frames_by_cause"] == {"early": 5}
    assert wvid(ev, "c3.mp4")["outcome"] == {"label": "no_collision", "warned": None, "missed": None,
                                             "false": True, "lead_s": None}
    assert wvid(ev, "c4.mp4")["outcome"]["false"] is False
    s = warn_summary(ev)
    assert (s["clips"], s["clips_collision"], s["clips_warned"], s["clips_missed"], s["clips_false"]) == (4, 2, 1, 1, 3)
    assert s["clip_lead_median_s"] == pytest.approx(1.5)
    # clips are not part of the generated-suite metrics
    assert s["collision_objects"] == 0 and s["frames"] == 0 and s["false_frames_per_1000"] is None
    table = ev.clip_warning_table()
    assert "| mlplc2 | c1.mp4 | collision | yes | 1.50 | 3 |" in table
    assert "| mlplc2 | c2.mp4 | collision | no | - | 5 |" in table
    assert "| mlplc2 | c4.mp4 | no_collision | - | - | 0 |" in table


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
    """Without the collider's track its position is unknown: every warning from the danger onset
    - 0.5 s to the contact is on it (the early rule still holds)."""
    gt = {"clips": {"c.mp4": {"label": "collision", "collision_frame": 30, "danger_onset_frame": 20},
                    "d.mp4": {"label": "collision", "contact_frame": 30}}}
    runs = [result("c.mp4", 40, targets=[T(f, 1, 10, 10, warn=True) for f in (12, 17, 18)]),
            result("d.mp4", 40, alarms=[25], model="lgmd2")]
    ev = evaluate(runs, gt)
    v = wvid(ev, "c.mp4")
    assert v["outcome"] == {"label": "collision", "warned": True, "missed": False, "false": True, "lead_s": 1.3}
    assert v["false_frames_by_cause"] == {"early": 1}
    assert wvid(ev, "d.mp4", "lgmd2")["outcome"]["lead_s"] == pytest.approx(0.5)
    assert wobj(ev, oid="collider", video="c.mp4")["warning_distance_px"] is None


# ---------------------------------------------------------------------------
# results at another size than the truth; results folders
# ---------------------------------------------------------------------------
def _case():
    gt = {"videos": {"a.mp4": video_truth([colliding(), obj(2, "pass", range(28), 150, 50, 10.0, contact=29.0)])}}
    targets = ([T(f, 1, 53, 54, warn=True, ttc=(20 - f) / FPS * 1.1) for f in range(8, 20)]
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
