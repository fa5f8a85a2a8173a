"""Shared fixtures: the paper's data folder (tests skip cleanly without it) and ``data``, a
small clip of a dark square approaching at a known centre (an AVI, an MP4 and a folder of
images; ``tests/test_cli.py`` and ``tests/test_runner.py``)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from mlplc2.io import write_video

PAPER = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "paper"

# A dark square approaching (growing 4 px/frame) at a known centre, 320x240.
CX, CY = 200, 100
W, H, T = 320, 240, 60


def read_gray(path: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
    cap.release()
    return frames


def _listing(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")} if root.is_dir() else set()


@pytest.fixture(scope="session", autouse=True)
def shared_data_untouched():
    """``../shared/data`` is read-only input: no test may write into it (a run's default output
    folder lies next to its input; a test of a clip there passes ``out=False`` or a tmp folder)."""
    root = PAPER.parent
    before = _listing(root)
    yield
    added = sorted(_listing(root) - before)
    assert not added, f"tests wrote into {root}: {added[:5]}"


@pytest.fixture(scope="session")
def paper_dir() -> Path:
    if not (PAPER / "ground_truth.json").exists():
        pytest.skip("the paper's data (../shared/data/paper) is absent")
    return PAPER


@pytest.fixture(scope="session")
def paper_truth(paper_dir) -> dict:
    return json.loads((paper_dir / "ground_truth.json").read_text())["videos"]


def _square_frames(n=T, w=W, h=H, cx=CX, cy=CY):
    rng = np.random.default_rng(0)
    bg = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 4)
    bg = cv2.normalize(bg, None, 90, 230, cv2.NORM_MINMAX).astype(np.uint8)
    for i in range(n):
        f = bg.copy()
        side = 0 if i < 5 else 4 * (i - 5) + 2
        if side:
            cv2.rectangle(f, (cx - side // 2, cy - side // 2), (cx + side // 2, cy + side // 2), 0, -1)
        yield cv2.cvtColor(f, cv2.COLOR_GRAY2RGB)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    out = {"avi": d / "square.avi", "mp4": d / "square.mp4", "images": d / "frames"}
    write_video(out["avi"], _square_frames(), 30.0)
    write_video(out["mp4"], _square_frames(), 30.0)
    out["images"].mkdir()
    for i, f in enumerate(_square_frames(40, 160, 120, 100, 50)):
        cv2.imwrite(str(out["images"] / f"img{i}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    return out


@pytest.fixture(scope="session")
def real_dir() -> Path:
    """The labelled real clips (``../shared/data/real`` of the checkout, else of the current folder)."""
    from mlplc2.benchmark import default_real_dir

    for cand in (PAPER.parent / "real", default_real_dir()):
        if cand is not None and (cand / "ground_truth.json").exists():
            return cand
    pytest.skip("the real clips (../shared/data/real) are absent")
