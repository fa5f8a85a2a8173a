"""Approaches in 3-D seen by a moving pinhole camera, with exact ground truth (docs/stimuli.md).

The paper's stimuli are squares growing linearly on a scrolling picture
(:mod:`mlplc2.stimuli.paper`). Here flat objects (discs and squares, dark,
bright or carrying their own texture) of a physical width move at constant 3-D
velocity in front of a pinhole camera that may stand still, pan, tilt or move
forward over a textured ground plane, or follow a :class:`CameraPath` (forward speed, turns,
pitch bounce, roll and hand-held shake combined, with the rotation and heading per frame in the
truth); a constant-speed approach then grows as 1 / (time to contact). The subpackage, by concept (each module's docstring
holds its equations):

* :mod:`~mlplc2.stimuli.world.scenes`: the public generators, :class:`ApproachObject`,
  :func:`approach`, :func:`approach_scene`, :func:`random_scene`, and the kinds of motion;
* :mod:`~mlplc2.stimuli.world.render`: textures, the background (far texture, ground
  plane), drawing the objects with sub-pixel coverage, optics blur and sensor noise;
* :mod:`~mlplc2.stimuli.world.geometry`: each object's pose, homography and extent in
  the image per frame, its contact, miss and truth;
* :mod:`~mlplc2.stimuli.world.camera`: the camera's motion and projection (the focal
  length of :func:`mlplc2.camera.focal_length`).

This package re-exports the public names of those modules.
"""

from .._common import ApproachStimulus
from .camera import CAMERA_MOTIONS, DEFAULT_CAMERA_SPEED, MAX_ELEVATION_DEG, MAX_PAN_DEG, CameraPath
from .geometry import COLLISION_MISS, DEFAULT_WIDTH_M, FAR_M, PASS_MIN_MISS, ObjectTrack
from .render import APPROACH_BACKGROUNDS, GROUND_SUBROWS, GROUND_TEXEL_M, GROUND_TEXTURE_PX, OBJECT_TEXTURE_PX
from .scenes import (APPROACH_APPEARANCES, APPROACH_KINDS, APPROACH_SHAPES, COLLISION_AIM, PASS_MISS_WIDTHS,
                     ApproachObject, approach, approach_scene, random_scene)

__all__ = [
    "ApproachObject",
    "CameraPath",
    "ObjectTrack",
    "ApproachStimulus",
    "approach",
    "approach_scene",
    "random_scene",
    "APPROACH_KINDS",
    "APPROACH_SHAPES",
    "APPROACH_APPEARANCES",
    "APPROACH_BACKGROUNDS",
    "CAMERA_MOTIONS",
]
