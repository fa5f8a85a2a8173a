"""The inputs of ``mlplc2 reproduce``: the paper's videos and ``ground_truth.json`` (``--data``),
or the generated stimuli of :mod:`mlplc2.stimuli`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from collections.abc import Mapping
from typing import Any

import numpy as np

from .._validation import InputValueError
from ..evaluation.truth import ObjectTruth, parse, read_json

__all__ = ["Scene", "load_inputs", "load_paper_objects", "PAPER_BASIC_FILES", "FOUR_PHASE_FILE",
           "SIX_OBJECTS_FILE"]

#: Paper file of each basic stimulus (``DATA/basic/``).
PAPER_BASIC_FILES = {"dark_approach": "test_black_approach.avi", "dark_recede": "test_black_recede.avi",
                     "bright_approach": "test_white_approach.avi", "bright_recede": "test_white_recede.avi",
                     "translating": "test_translating.avi", "grating": "test_grating.avi"}
FOUR_PHASE_FILE = "scenes/outdoor_2_black_4_period.avi"
SIX_OBJECTS_FILE = "scenes/outdoor_3_black_expand_multi_6.avi"


@dataclass
class Scene:
    """Frames of one input and the ground truth of its objects (:class:`mlplc2.evaluation.truth.ObjectTruth`)."""

    name: str
    frames: Any
    fps: float
    objects: list[ObjectTruth]
    source: str

    @property
    def n(self) -> int:
        return len(self.frames)


def _read(path: Path):
    """(frames, fps) of a complete video; a missing, unreadable or truncated file raises
    :class:`~mlplc2.InputValueError` (the claims need every frame of the paper's videos)."""
    from ..io import open_source

    if not path.is_file():
        raise InputValueError(f"{path}: missing (expected the paper's data layout, see docs/reproduce.md)")
    src = open_source(path)
    frames = [f for _, f in src]
    if src.truncated:
        raise InputValueError(f"{path}: decoding stopped at frame {src.truncated_at} (file truncated or damaged); "
                              f"the reproduction needs the complete video")
    return np.stack(frames), float(src.fps)


def load_paper_objects(gt_path: Path) -> dict[str, list[ObjectTruth]]:
    """The objects of every video of the paper's ``ground_truth.json`` (``{key: [ObjectTruth]}``),
    read by the loader of ``mlplc2 evaluate`` (:func:`mlplc2.evaluation.truth.load`): a malformed file
    raises :class:`~mlplc2.InputValueError` naming the field. The two scenes must have
    object-level entries whose objects have a ``center`` (the reproduction does not follow
    tracks)."""
    raw = read_json(gt_path)
    if not isinstance(raw, Mapping) or not isinstance(raw.get("videos"), Mapping):
        raise InputValueError(f"{gt_path}: expected {{\"videos\": {{name: entry}}}} (the paper's ground_truth.json)")
    objects = {key: list(vt.objects) for key, vt in parse(raw, str(gt_path)).items()}
    for rel in (FOUR_PHASE_FILE, SIX_OBJECTS_FILE):
        if rel not in objects:
            raise InputValueError(f"{gt_path}: no entry for {rel}")
        if not objects[rel]:
            raise InputValueError(f"{gt_path}: videos[{rel!r}]: no 'objects' (the reproduction needs them)")
        for i, o in enumerate(objects[rel]):
            if o.center is None and (o.approach or o.hold or o.recede or o.sizes):
                raise InputValueError(f"{gt_path}: videos[{rel!r}].objects[{i}]: needs a 'center' [x, y] "
                                      f"(mlplc2 reproduce does not follow a 'track')")
    return objects


def load_inputs(data: Path | None, *, quick: bool = False, seed: int = 0) -> dict:
    """The inputs of every experiment: ``{"basic": {name: Scene}, "four_phase": Scene,
    "six_objects": Scene, "clips": [Scene], "source": str}``."""
    from .. import stimuli

    out: dict[str, Any] = {"basic": {}, "clips": []}
    if data is None:
        out["source"] = f"generated stimuli (mlplc2.stimuli, procedural background, seed {seed})"
        for name in stimuli.BASIC_NAMES:
            st = stimuli.basic(name)
            out["basic"][name] = Scene(name, st.frames, st.fps, list(st.objects), f"stimuli.basic({name!r})")
        for key, make in (("four_phase", stimuli.four_phase), ("six_objects", stimuli.six_objects)):
            st = make(seed=seed)
            out[key] = Scene(key, st.frames, st.fps, list(st.objects), f"stimuli.{key}(seed={seed})")
        return out
    data = Path(data)
    gt_path = data / "ground_truth.json"
    if not gt_path.is_file():
        raise InputValueError(f"--data {data}: no ground_truth.json (expected the paper's data folder)")
    objects = load_paper_objects(gt_path)
    out["source"] = f"the paper's videos in {data}"
    for name, fname in PAPER_BASIC_FILES.items():
        rel = f"basic/{fname}"
        frames, fps = _read(data / rel)
        out["basic"][name] = Scene(name, frames, fps, objects.get(rel, []), rel)
    for key, rel in (("four_phase", FOUR_PHASE_FILE), ("six_objects", SIX_OBJECTS_FILE)):
        frames, fps = _read(data / rel)
        out[key] = Scene(key, frames, fps, objects[rel], rel)
    out["damaged"] = []
    if not quick:
        for path in sorted((data / "uav").glob("*.avi"), key=lambda p: p.name.lower()):
            try:
                frames, fps = _read(path)
            except InputValueError as exc:   # an optional clip: skipped, said in the report
                out["damaged"].append(f"uav/{path.name} skipped: {exc}")
                continue
            out["clips"].append(Scene(path.stem, frames, fps, [], f"uav/{path.name}"))
    return out

