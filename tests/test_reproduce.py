"""`mlplc2 reproduce --quick`: every claim of Sec. IV passes, except the documented
known deviations (flagged in report.json only while they still fail)."""

from __future__ import annotations

import json
import re

import pytest

from mlplc2 import cli, reproduce

# The documented deviations (docs/model.md "Open problems" and docs/reproduce.md
# "Deviations found"). Adding one to mlplc2.reproduce.KNOWN_DEVIATIONS must be a
# deliberate edit of this list too, so no new failure slips through unnoticed.
DOCUMENTED = {
    # docs/reproduce.md "Deviations found"
    "IV-B4.lgmd2.recede",
    # docs/model.md "Open problems"
    "IV-A.silent.lplc2.bright_recede",
    "IV-A.silent.slplc2.bright_recede",
    "IV-B5.persistence",
}

# Lines the report must contain (the claims named in issue 5).
REQUIRED = (
    [f"IV-A.silent.{m}.{s}" for m in ("lplc2", "slplc2", "mlplc2")
     for s in ("dark_recede", "bright_recede", "translating", "grating")]
    + [f"IV-A.dark_over_bright.{m}" for m in ("lplc2", "slplc2", "mlplc2")]
    + ["IV-A.lgmd2.bright_recede", "IV-A.lgmd2.translating"]
    + [f"IV-B4.lgmd2.phase{k}" for k in range(1, 5)]
    + [f"IV-B4.latency.obj{i}" for i in range(1, 6)] + [f"IV-B4.error.obj{i}" for i in range(1, 6)]
    + ["IV-B4.slplc2.phase4", "IV-B4.lplc2.phase2", "IV-B4.lplc2.phase3", "IV-B4.lplc2.phase4",
       "IV-B4.fields", "IV-B4.no_false_alarm"]
    + [f"IV-B5.latency.obj{i}" for i in range(1, 7)] + [f"IV-B5.error.obj{i}" for i in range(1, 7)]
    + ["IV-B5.persistence", "IV-B5.fields", "IV-B5.no_false_alarm"]
)


def check_report(doc: dict) -> None:
    claims = doc["claims"]
    ids = [c["id"] for c in claims]
    assert len(ids) == len(set(ids)), "claim ids must be unique"
    for c in claims:
        assert c["status"] in ("PASS", "FAIL")
        if c["status"] == "PASS":
            assert not c["known_deviation"], f"{c['id']} passes but is flagged"
        else:
            assert c["known_deviation"], f"unexpected FAIL: {c['id']}: {c['claim']}: {c['measured']}"
            assert "known deviation" in c["note"] and "docs/" in c["note"]
    flagged = {c["id"] for c in claims if c["known_deviation"]}
    assert flagged <= DOCUMENTED, f"flagged but not documented: {sorted(flagged - DOCUMENTED)}"
    s = doc["summary"]
    assert s["claims"] == len(claims)
    assert s["pass"] + s["fail"] == len(claims)
    assert s["known_deviation"] == len(flagged) and s["unexpected_fail"] == 0


def test_known_deviations_are_the_documented_set():
    assert set(reproduce.KNOWN_DEVIATIONS) == DOCUMENTED


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    rc = cli.main(["reproduce", "--quick", "--out", str(out), "--quiet"])
    assert rc == 0
    return out, json.loads((out / "report.json").read_text())


@pytest.mark.slow
def test_quick_reproduction_passes(quick_report):
    out, doc = quick_report
    assert doc["quick"] is True
    check_report(doc)
    ids = {c["id"] for c in doc["claims"]}
    missing = [i for i in REQUIRED if i not in ids]
    assert not missing, f"report lacks {missing}"


@pytest.mark.slow
def test_quick_reproduction_outputs(quick_report):
    out, doc = quick_report
    for name in ("fig3_selectivity.png", "fig4_four_phases.png", "fig5_six_objects.png"):
        data = (out / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    assert not (out / "fig6_real_clips.png").exists()
    md = (out / "report.md").read_text()
    assert "Fig. 6" in md and "skipped" in md
    # one table line per claim, with its status
    rows = [line for line in md.splitlines() if line.startswith("| ") and not line.startswith("| status")]
    assert len(rows) == len(doc["claims"])
    for line, c in zip(rows, doc["claims"]):
        assert c["status"] in line
        if c["paper"]:
            assert c["paper"].split(" (")[0] in line


def test_bad_data_folder(tmp_path, capsys):
    rc = cli.main(["reproduce", "--data", str(tmp_path), "--out", str(tmp_path / "o"), "--quiet"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("mlplc2: error:") and "ground_truth.json" in err
    rc = cli.main(["reproduce", "--data", str(tmp_path / "missing"), "--quiet"])
    assert rc == 2


GOOD_GT = {"videos": {
    reproduce.FOUR_PHASE_FILE: {"objects": [{"id": 1, "center": [160, 120], "approach": [0, 40], "hold": [40, 60]}]},
    reproduce.SIX_OBJECTS_FILE: {"objects": [{"id": 1, "center": [60, 60], "approach": [5, 45]}]}}}


def _bad_gt(kind):
    if kind == "invalid JSON":
        return "{not json"
    gt = json.loads(json.dumps(GOOD_GT))
    obj = gt["videos"][reproduce.FOUR_PHASE_FILE]["objects"][0]
    if kind == "no objects":
        del gt["videos"][reproduce.FOUR_PHASE_FILE]["objects"]
    elif kind == "no center":
        del obj["center"]
    elif kind == "track only":
        del obj["center"]
        obj["track"] = [[0, 160, 120]]
    elif kind == "list kind":
        obj["kind"] = ["approaching"]
    elif kind == "label only":
        gt["videos"][reproduce.SIX_OBJECTS_FILE] = {"label": "collision"}
    elif kind == "no videos":
        gt = {"about": "x"}
    return json.dumps(gt)


@pytest.mark.parametrize("kind, message", [
    ("invalid JSON", "not valid JSON"),
    ("no objects", "needs 'objects'"),
    ("no center", r"objects\[0\]: an approaching object needs a 'center'"),
    ("track only", r"objects\[0\]: needs a 'center'"),
    ("list kind", r"objects\[0\].kind: expected one of"),
    ("label only", "no 'objects'"),
    ("no videos", "expected {\"videos\""),
])
def test_bad_ground_truth_is_one_line_error(tmp_path, capsys, kind, message):
    """A malformed DATA/ground_truth.json is checked (as 'mlplc2 evaluate' does) before
    any video is read or any output is written: one error line, exit 2."""
    data = tmp_path / "data"
    data.mkdir()
    (data / "ground_truth.json").write_text(_bad_gt(kind))
    rc = cli.main(["reproduce", "--quick", "--data", str(data), "--out", str(tmp_path / "o"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("mlplc2: error:") and len(err.strip().splitlines()) == 1
    assert "ground_truth.json" in err and re.search(message, err), err
    assert not (tmp_path / "o").exists()


def test_good_ground_truth_reaches_the_videos(tmp_path, capsys):
    """The same check passes a well-formed file: the next error is the missing video."""
    data = tmp_path / "data"
    data.mkdir()
    (data / "ground_truth.json").write_text(json.dumps(GOOD_GT))
    assert cli.main(["reproduce", "--quick", "--data", str(data), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "basic/test_black_approach.avi: missing" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.paper
def test_paper_ground_truth_objects_unchanged(paper_dir, paper_truth):
    """Checking the paper's file leaves its objects as they are (so the claims do not change)."""
    objects = reproduce.load_paper_objects(paper_dir / "ground_truth.json")
    assert objects == {k: v.get("objects", []) for k, v in paper_truth.items()}


@pytest.mark.paper
@pytest.mark.slow
def test_quick_reproduction_on_paper_videos(paper_dir, tmp_path):
    rc = cli.main(["reproduce", "--quick", "--data", str(paper_dir), "--out", str(tmp_path), "--quiet"])
    assert rc == 0
    check_report(json.loads((tmp_path / "report.json").read_text()))


def _paper_copy(paper_dir, root):
    """A data folder of symlinks to the paper's basic tests, scenes and ground truth."""
    root.mkdir()
    (root / "ground_truth.json").symlink_to(paper_dir / "ground_truth.json")
    for sub in ("basic", "scenes"):
        (root / sub).mkdir()
        for f in (paper_dir / sub).glob("*.avi"):
            (root / sub / f.name).symlink_to(f)
    return root


@pytest.mark.paper
def test_truncated_scene_is_an_error_before_any_output(paper_dir, tmp_path, capsys):
    """The claims need every frame: a cut scene stops the run with one line (it used to give
    PASS lines computed on the frames that decoded, and exit 0)."""
    data = _paper_copy(paper_dir, tmp_path / "data")
    scene = data / "scenes" / "outdoor_2_black_4_period.avi"
    blob = scene.resolve().read_bytes()
    scene.unlink()
    scene.write_bytes(blob[:200_000])
    rc = cli.main(["reproduce", "--quick", "--data", str(data), "--out", str(tmp_path / "o"), "--quiet"])
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "outdoor_2_black_4_period.avi: decoding stopped at frame" in err[0], err
    assert "the reproduction needs the complete video" in err[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.paper
@pytest.mark.slow
def test_damaged_clip_is_skipped_and_the_rest_written(paper_dir, tmp_path, capsys):
    """An unreadable clip in uav/ is skipped with a warning line (exit 2); every figure and the
    report are still written, the report says what was skipped, and an earlier run's files in
    the output folder do not survive."""
    data = _paper_copy(paper_dir, tmp_path / "data")
    (data / "uav").mkdir()
    (data / "uav" / "bird_attack_2.avi").symlink_to(paper_dir / "uav" / "bird_attack_2.avi")
    (data / "uav" / "bogus.avi").write_text("not a video\n")
    out = tmp_path / "o"
    out.mkdir()
    (out / "fig6_real_clips.png").write_bytes(b"stale")
    rc = cli.main(["reproduce", "--data", str(data), "--out", str(out), "--quiet"])
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mlplc2: warning: uav/bogus.avi skipped: "), err
    assert (out / "fig6_real_clips.png").read_bytes()[:4] == b"\x89PNG"   # drawn anew (one clip)
    report = json.loads((out / "report.json").read_text())
    assert any(s.startswith("uav/bogus.avi skipped") for s in report["skipped"])
    assert "uav/bogus.avi skipped" in (out / "report.md").read_text()
    assert not any("bogus" in c["id"] for c in report["claims"])


def test_interrupt_before_any_output_leaves_no_folder(tmp_path, monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(reproduce, "run_model", interrupted)
    assert cli.main(["reproduce", "--quick", "--out", str(tmp_path / "o"), "--quiet"]) == 130
    assert capsys.readouterr().err.strip() == "mlplc2: interrupted"
    assert not (tmp_path / "o").exists()
