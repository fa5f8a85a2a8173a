"""The moving pinhole camera of the 3-D approaches: its motion over the frames and its projection.

* Camera frame: the camera centre at the origin looking along +Z, X right,
  Y down. Image origin top-left, pixel centres at integer coordinates
  (column ``x``, row ``y``), principal point ``((W - 1) / 2, (H - 1) / 2)``,
  focal length ``f = (W / 2) / tan(hfov / 2)`` px (the one
  :func:`mlplc2.camera.focal_length`, as :func:`mlplc2.camera.bearing`).
  A point ``(X, Y, Z)`` with ``Z > 0`` is seen at
  ``x = cx + f X / Z``, ``y = cy + f Y / Z`` (intrinsic matrix ``K``).
* World frame: the camera frame at frame 0. ``"pan"`` turns the camera
  about its Y axis at ``speed`` deg/s (positive: to the right, so the
  scene moves left), ``"tilt"`` about its X axis (positive: up, so the scene
  moves down), ``"forward"`` moves it along +Z at ``speed`` m/s. Frame ``k`` is
  at time ``k / fps``.
* The far texture is an equirectangular panorama: a pan turns at most
  :data:`MAX_PAN_DEG`, a tilt keeps the view within :data:`MAX_ELEVATION_DEG`
  of the horizon (:meth:`Camera.check_turn`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..._validation import InputValueError
from ...camera import check_hfov, focal_length

__all__ = ["Camera", "CAMERA_MOTIONS", "DEFAULT_CAMERA_SPEED", "MAX_PAN_DEG", "MAX_ELEVATION_DEG"]

#: Camera motions of :func:`mlplc2.stimuli.world.approach`.
CAMERA_MOTIONS: tuple[str, ...] = ("static", "pan", "tilt", "forward")
#: Camera speed when none is given: pan/tilt deg/s, forward m/s.
DEFAULT_CAMERA_SPEED = {"static": 0.0, "pan": 10.0, "tilt": 4.0, "forward": 2.0}
#: Largest total camera rotation (deg): the far texture is an equirectangular panorama, which
#: must not wrap around (pan) or reach the zenith or nadir (tilt, including half the view).
MAX_PAN_DEG = 360.0
MAX_ELEVATION_DEG = 85.0


class Camera:
    """The pinhole camera and its motion over ``n`` frames: focal length ``f``, principal point
    ``(cx, cy)``, intrinsic matrix ``K``, per-frame turn ``angle`` (rad) and ``position`` (m)."""

    def __init__(self, w: int, h: int, hfov: float, fps: float, motion: str, speed: float, height: float, n: int):
        self.w, self.h, self.hfov, self.fps = w, h, hfov, fps
        self.motion, self.speed, self.height, self.n = motion, speed, height, n
        self.f = focal_length(w, check_hfov(hfov, required=True))
        self.cx, self.cy = (w - 1) / 2.0, (h - 1) / 2.0
        self.K = np.array([[self.f, 0.0, self.cx], [0.0, self.f, self.cy], [0.0, 0.0, 1.0]])
        t = np.arange(n, dtype=np.float64) / fps
        self.angle = np.radians(speed * t) if motion in ("pan", "tilt") else np.zeros(n)
        self.position = np.zeros((n, 3))
        if motion == "forward":
            self.position[:, 2] = speed * t

    def rotation(self, angle) -> np.ndarray:
        """Camera-to-world rotation(s) for turn ``angle`` (rad; array -> (..., 3, 3))."""
        a = np.asarray(angle, dtype=np.float64)
        c, s = np.cos(a), np.sin(a)
        o, z = np.ones_like(a), np.zeros_like(a)
        if self.motion == "pan":      # forward axis turns towards +X
            rows = [[c, z, s], [z, o, z], [-s, z, c]]
        elif self.motion == "tilt":   # forward axis turns towards -Y (up)
            rows = [[o, z, z], [z, c, -s], [z, s, c]]
        else:
            rows = [[o, z, z], [z, o, z], [z, z, o]]
        return np.moveaxis(np.array(rows), (0, 1), (-2, -1))

    def rays(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Camera-frame rays ``(X/Z, Y/Z, 1)`` of pixels (broadcast shapes, stacked last)."""
        xs, ys = np.broadcast_arrays(xs, ys)
        return np.stack([(xs - self.cx) / self.f, (ys - self.cy) / self.f, np.ones_like(xs, dtype=np.float64)], -1)

    def to_dict(self) -> dict[str, Any]:
        return {"hfov_deg": self.hfov, "focal_px": self.f, "motion": self.motion, "speed": self.speed}

    def check_turn(self) -> None:
        """Raise unless the whole turn stays within :data:`MAX_PAN_DEG` (pan) or keeps the view
        within :data:`MAX_ELEVATION_DEG` of the horizon (tilt): the far texture's panorama limits."""
        speed, n, fps = self.speed, self.n, self.fps
        turn = abs(speed) * (n - 1) / fps
        if self.motion == "pan" and turn > MAX_PAN_DEG:
            raise InputValueError(f"camera_speed {speed:g} deg/s pans the camera {turn:.0f} deg over {n} frames; "
                                  f"at most {MAX_PAN_DEG:.0f}")
        if self.motion == "tilt":
            half_v = math.degrees(math.atan((self.h / 2.0) / self.f))
            if turn + half_v > MAX_ELEVATION_DEG:
                raise InputValueError(f"camera_speed {speed:g} deg/s tilts the camera {turn:.0f} deg over {n} frames; "
                                      f"at most {MAX_ELEVATION_DEG - half_v:.0f} with this view")
