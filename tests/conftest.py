"""Shared fixtures: the paper's data folder (tests skip cleanly without it)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

PAPER = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "paper"


def read_gray(path: Path) -> list[np.ndarray]:
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
    cap.release()
    return frames


@pytest.fixture(scope="session")
def paper_dir() -> Path:
    if not (PAPER / "ground_truth.json").exists():
        pytest.skip("the paper's data (../shared/data/paper) is absent")
    return PAPER


@pytest.fixture(scope="session")
def paper_truth(paper_dir) -> dict:
    return json.loads((paper_dir / "ground_truth.json").read_text())["videos"]
