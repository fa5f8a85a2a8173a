"""Synthetic stimuli with exact ground truth: the mLPLC2 paper's 2-D stimuli and 3-D approaches.

Every generator returns a :class:`Stimulus`: grey ``uint8`` frames of shape
``(T, H, W)`` plus one :class:`ObjectTruth` per object (the one ground-truth
type, :class:`mlplc2.evaluation.truth.ObjectTruth`), deterministic for a given
``seed``. This package only re-exports the public names of its modules:

* :mod:`~mlplc2.stimuli.paper`: the paper's stimuli (Sec. IV-A, Fig. 3: :func:`basic`;
  Sec. IV-B, Fig. 4 and 5: :func:`four_phase`, :func:`six_objects`, any :func:`scene` of
  :class:`SceneObject` squares on a scrolling background) and a physical :func:`looming`;
* :mod:`~mlplc2.stimuli.world`: flat objects moving in 3-D in front of a pinhole camera
  that may pan, tilt or move forward over a ground plane (:class:`ApproachObject`,
  :func:`approach`, :func:`approach_scene`, :func:`random_scene`; docs/stimuli.md);
* :mod:`~mlplc2.stimuli.dispatch`: the stimuli by name (:data:`NAMES`, :func:`generate`,
  :func:`parameters`, :func:`write`; the CLI's ``mlplc2 stimulus NAME``);
* :mod:`~mlplc2.stimuli._common`: what they share (:class:`Stimulus`,
  :class:`ApproachStimulus`, :func:`procedural_background`, :func:`plain_level`).
"""

from __future__ import annotations

from ..evaluation.truth import ObjectTruth
from ._common import (MAX_STIMULUS_BYTES, OPTICS_BLUR_PX, ApproachStimulus, Stimulus, plain_level,
                      procedural_background)
from .dispatch import GENERATORS, NAMES, generate, parameters, write
from .paper import (BASIC_NAMES, BASIC_WHITE, BRIGHT_LEVEL, DARK_LEVEL, FOUR_PHASE_CENTERS, MAX_SCROLL_PX,
                    SIX_OBJECT_CENTERS, SIX_OBJECT_ONSETS, SceneObject, basic, four_phase, looming, scene,
                    six_objects)
from .world import ApproachObject, CameraPath, ObjectTrack, approach, approach_scene, random_scene

__all__ = [
    "ObjectTruth",
    "Stimulus",
    "SceneObject",
    "BASIC_NAMES",
    "NAMES",
    "basic",
    "scene",
    "four_phase",
    "six_objects",
    "looming",
    "procedural_background",
    "generate",
    "write",
    "parameters",
    "plain_level",
    # 3-D approaches (mlplc2.stimuli.world)
    "ApproachObject",
    "CameraPath",
    "ObjectTrack",
    "ApproachStimulus",
    "approach",
    "approach_scene",
    "random_scene",
]
