"""The demo (the ``mlplc2 demo`` command): a generated multi-object scene, the models run on it, their fields
matched to the objects."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from ..evaluation.match import match_fields
from ..models.base import available_models
from .loop import run
from .result import RunResult


#: Models the demo runs (those registered).
DEMO_MODELS = ("mlplc2", "slplc2", "lplc2", "lgmd2")


@dataclass
class DemoResult:
    """What :func:`demo` made: the run, the ground truth and the field/object matches."""

    result: RunResult
    truth: dict
    video: Path
    matches: list[dict]


def demo(out="mlplc2_demo", *, scene: str = "four_phase", quiet: bool = False, progress: bool = True,
         video: bool = True, stabilise: bool = False) -> DemoResult:
    """Generate a multi-object scene, run the models on it and match fields to objects.

    Writes ``demo.mp4`` and ``demo_gt.json`` into ``out``, then
    :func:`run` (``mlplc2``, ``slplc2``, ``lplc2`` and ``lgmd2`` when it is
    registered; ``video=True``) with its outputs in ``out/demo_mlplc2``.

    ``stabilise``: gaze stabilisation (:attr:`RunOptions.stabilise`). False by default, unlike
    :func:`run`: the scenes are the paper's Fig. 4 and 5, whose background scrolls behind a still
    camera while the objects keep their places in the image (docs/history.md, "LPLC2's cell and the
    paper's scenes under gaze stabilisation"); stabilised, the scroll is taken for a pan and the objects then drift with
    the camera, one edge standing still.

    ``matches`` has one entry per ground-truth object (see :func:`match_fields`):
    the mLPLC2 field that stands for it and the distance in pixels.
    """
    from .. import stimuli

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    video_path, gt_path = stimuli.write(scene, out / "demo.mp4")
    truth = json.loads(gt_path.read_text(encoding="utf-8"))
    names = [m for m in DEMO_MODELS if m in available_models()]
    res = run(video_path, names, out=out / "demo_mlplc2", video=video, quiet=quiet, progress=progress,
              stabilise=bool(stabilise))
    return DemoResult(res, truth, video_path, match_fields(res.fields.get("mlplc2", []), truth))
