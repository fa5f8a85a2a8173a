"""The depth coherence of a box (issue 22: the static world of a forward drive never warns):
:func:`mlplc2.targets.slant.slant` on exact image motions, and a drive over a textured ground."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from mlplc2.targets.alignment import pyramid
from mlplc2.targets.slant import slant

H, W = 240, 320
XH, YH = 160.0, 80.0                   # heading point = horizon row (px)


def _texture() -> np.ndarray:
    rng = np.random.default_rng(3)
    return cv2.GaussianBlur((rng.random((H, W)) * 255).astype(np.float32), (0, 0), 1.5)


def _warped(prev: np.ndarray, inverse) -> np.ndarray:
    """``prev`` moved by the image motion whose inverse maps this frame's (x, y) to prev's."""
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    mx, my = inverse(xs, ys)
    return cv2.remap(prev, mx.astype(np.float32), my.astype(np.float32), cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REFLECT)


def test_a_fronto_parallel_object_scales_alike_everywhere():
    # an object closing straight on: its image scales by 8 % about (150, 130), one scale rate
    prev = _texture()
    k, (ex, ey) = 1.08, (150.0, 130.0)
    cur = _warped(prev, lambda x, y: (ex + (x - ex) / k, ey + (y - ey) / k))
    box = (150.0, 130.0, 60.0, 60.0)
    s = slant(pyramid(prev), pyramid(cur), box, (150.0, 130.0, 60.0 * k, 60.0 * k))
    assert s is not None and abs(s[0]) < 0.1 and abs(s[1]) < 0.1


@pytest.mark.parametrize("top", [YH, YH + 40.0])
def test_the_ground_ahead_of_a_moving_camera_is_slanted(top):
    # the ground plane seen from a camera moving forward: a point d px below the horizon moves to
    # d / (1 - c d) (c = dZ / (f h_c)), its scale rate c d grows with the row. For a box from row
    # `top` to top + 80 the scale rate changes from its centre to its foot by 40 / (centre - YH)
    # of its mean: 1 for a box that reaches up to the horizon, 0.5 for one 40 px below it
    prev = _texture()
    c = 0.08 / 80.0

    def inverse(x, y):
        d = (y - YH) / (1.0 + (y - YH) * c)             # prev's row below the horizon
        return np.where(y > YH, XH + (x - XH) * (1.0 - d * c), x), np.where(y > YH, YH + d, y)

    cur = _warped(prev, inverse)
    cy = top + 40.0
    s = slant(pyramid(prev), pyramid(cur), (XH, cy, 80.0, 80.0), (XH, cy, 80.0, 80.0))
    assert s is not None and abs(s[0]) < 0.1
    assert s[1] == pytest.approx(40.0 / (cy - YH), abs=0.2)


def test_a_drive_past_roadside_objects_does_not_warn_of_the_ground_beside_them():
    # a dashcam over a textured road past hedges, walls and parked cars, with no object on a
    # collision course in its first 40 frames: a box over a roadside object and the ground up to
    # the path warns at frame 26 (a time to contact of ~0.2 s, its miss within 1) without the slant test
    from mlplc2.models import MLPLC2
    from mlplc2.stimuli.world.realuse import real_use_scene
    from mlplc2.targets import TargetParams

    frames = real_use_scene("drive", 2, 1, duration_s=3.0, size=(160, 120), supersample=1).frames[:40]

    def warnings(p):
        model = MLPLC2(fps=30.0, stabilise=True, target_params=p)
        return [(i, t.id) for i, frame in enumerate(frames) for t in model.step(frame).targets if t.warning]

    bare = TargetParams(uniform_tol=0.0)                    # without the uniform box (on since session 15)
    assert warnings(bare)                                   # the static world warns without the test (off) ...
    assert not warnings(replace(bare, max_slant=0.5))       # ... and does not with it
    assert not warnings(TargetParams())                     # the defaults: the box re-seated on its object
