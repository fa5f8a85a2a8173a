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
* ``"path"`` (a :class:`CameraPath`: the settings of real use, a drive, a drone, a hand-held
  camera) combines them per frame. A *vehicle* moves forward at ``speed_mps`` along its
  heading, which turns at ``yaw_rate_dps`` (positive: right), so its centre follows a circular
  arc in the ground plane: ``C(t) = (v/r) (1 - cos rt, 0, sin rt)`` (``C(t) = (0, 0, v t)`` for
  ``r = 0``), vehicle-to-world rotation ``V(t) = R_y(r t)``. The camera on it is rotated by a
  pitch bounce ``R_x(b sin 2 pi f_b t)`` (positive: up), a roll ``R_z(a sin 2 pi f_a t)`` and a
  hand-held shake ``Rodrigues(s(t))``: camera-to-world ``R(t) = V(t) R_x R_z R_shake``, and its
  centre is shaken by ``V(t) u(t)``. Each of the three components of the shake rotation
  ``s(t)`` (rad) and translation ``u(t)`` (m) is a sum of :data:`SHAKE_TERMS` sinusoids of
  0.5-4 Hz with random phases (from ``shake_seed``), scaled to an RMS of ``shake_deg`` and
  ``shake_m``: smooth, and the same for the same seed. The truth records, per frame, the
  rotation ``omega`` since the previous frame (the rotation vector of ``R(k-1)^T R(k)``: rad
  per frame in the camera's axes x right, y down, z forward, a pan to the right ``+y``, as
  :class:`mlplc2.camera.CameraMotion`) and the ``heading`` (the focus of expansion: the
  centre's velocity in the camera's axes, projected; None while it points behind).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dataclasses import asdict, dataclass

from ..._validation import InputValueError, check_int, check_real
from ...camera import check_hfov, focal_length, rotation_matrix

__all__ = ["Camera", "CameraPath", "CAMERA_MOTIONS", "DEFAULT_CAMERA_SPEED", "MAX_PAN_DEG", "MAX_ELEVATION_DEG",
           "SHAKE_TERMS", "MAX_PATH_YAW_DEG"]

#: Camera motions of :func:`mlplc2.stimuli.world.approach`.
CAMERA_MOTIONS: tuple[str, ...] = ("static", "pan", "tilt", "forward")
#: Camera speed when none is given: pan/tilt deg/s, forward m/s.
DEFAULT_CAMERA_SPEED = {"static": 0.0, "pan": 10.0, "tilt": 4.0, "forward": 2.0}
#: Largest total camera rotation (deg): the far texture is an equirectangular panorama, which
#: must not wrap around (pan) or reach the zenith or nadir (tilt, including half the view).
MAX_PAN_DEG = 360.0
MAX_ELEVATION_DEG = 85.0
#: Sinusoids per component of a :class:`CameraPath`'s shake.
SHAKE_TERMS = 3
#: Largest heading change (deg) of a :class:`CameraPath` over a clip (the panorama must not wrap).
MAX_PATH_YAW_DEG = 120.0


@dataclass(frozen=True)
class CameraPath:
    """A general camera trajectory (``camera=CameraPath(...)`` in :func:`mlplc2.stimuli.world.approach`):
    forward speed (m/s), yaw rate of the heading (deg/s, positive right), pitch bounce and roll
    (amplitude deg, frequency Hz, sinusoids), hand-held shake (RMS rotation deg and translation m
    per axis, smooth and random from ``shake_seed``). See the module docstring for the equations."""

    speed_mps: float = 0.0
    yaw_rate_dps: float = 0.0
    bounce_deg: float = 0.0
    bounce_hz: float = 1.0
    roll_deg: float = 0.0
    roll_hz: float = 0.5
    shake_deg: float = 0.0
    shake_m: float = 0.0
    shake_seed: int = 0

    def __post_init__(self):
        for name in ("speed_mps", "yaw_rate_dps", "bounce_deg", "roll_deg"):
            object.__setattr__(self, name, check_real(getattr(self, name), name))
        for name in ("bounce_hz", "roll_hz", "shake_deg", "shake_m"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, minimum=0.0))
        object.__setattr__(self, "shake_seed", check_int(self.shake_seed, "shake_seed"))

    def _shake(self, t: np.ndarray, which: int, rms: float) -> np.ndarray:
        """``(len(t), 3)`` smooth random shake (rotation ``which=0``, translation 1) of RMS ``rms``."""
        out = np.zeros((len(t), 3))
        if rms == 0:
            return out
        rng = np.random.default_rng(np.random.SeedSequence([self.shake_seed, 7, which]))
        for axis in range(3):
            freq = rng.uniform(0.5, 4.0, SHAKE_TERMS)
            phase = rng.uniform(0.0, 2 * math.pi, SHAKE_TERMS)
            amp = rng.uniform(0.5, 1.0, SHAKE_TERMS)
            amp *= rms / math.sqrt(float(np.sum(amp ** 2)) / 2.0)
            out[:, axis] = np.sin(2 * math.pi * freq[None, :] * t[:, None] + phase[None, :]) @ amp
        return out

    def vehicle(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The vehicle's (smooth path's) position ``C(t)`` (…, 3) and rotation ``V(t)`` (…, 3, 3)."""
        t = np.asarray(t, dtype=np.float64)
        r = math.radians(self.yaw_rate_dps)
        psi = r * t
        if r == 0:
            pos = np.stack([np.zeros_like(t), np.zeros_like(t), self.speed_mps * t], -1)
        else:
            pos = np.stack([self.speed_mps / r * (1.0 - np.cos(psi)), np.zeros_like(t),
                            self.speed_mps / r * np.sin(psi)], -1)
        return pos, _rot_y(psi)

    def pose(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The camera's centre (n, 3) and camera-to-world rotation (n, 3, 3) at times ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        pos, V = self.vehicle(t)
        pitch = np.radians(self.bounce_deg) * np.sin(2 * math.pi * self.bounce_hz * t)
        roll = np.radians(self.roll_deg) * np.sin(2 * math.pi * self.roll_hz * t)
        shake = self._shake(t, 0, math.radians(self.shake_deg))
        R = V @ _rot_x(pitch) @ _rot_z(roll) @ np.array([rotation_matrix(s) for s in shake])
        pos = pos + np.einsum("kij,kj->ki", V, self._shake(t, 1, self.shake_m))
        return pos, R

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _rot_x(a: np.ndarray) -> np.ndarray:
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return np.moveaxis(np.array([[o, z, z], [z, c, -s], [z, s, c]]), (0, 1), (-2, -1))


def _rot_y(a: np.ndarray) -> np.ndarray:
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return np.moveaxis(np.array([[c, z, s], [z, o, z], [-s, z, c]]), (0, 1), (-2, -1))


def _rot_z(a: np.ndarray) -> np.ndarray:
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return np.moveaxis(np.array([[c, -s, z], [s, c, z], [z, z, o]]), (0, 1), (-2, -1))


class Camera:
    """The pinhole camera and its motion over ``n`` frames: focal length ``f``, principal point
    ``(cx, cy)``, intrinsic matrix ``K``, per-frame turn ``angle`` (rad) and ``position`` (m)."""

    def __init__(self, w: int, h: int, hfov: float, fps: float, motion: str, speed: float, height: float, n: int,
                 path: CameraPath | None = None):
        self.w, self.h, self.hfov, self.fps, self.path = w, h, hfov, fps, path
        self.motion, self.speed, self.height, self.n = motion, speed, height, n
        self.f = focal_length(w, check_hfov(hfov, required=True))
        self.cx, self.cy = (w - 1) / 2.0, (h - 1) / 2.0
        self.K = np.array([[self.f, 0.0, self.cx], [0.0, self.f, self.cy], [0.0, 0.0, 1.0]])
        t = np.arange(n, dtype=np.float64) / fps
        self.angle = np.radians(speed * t) if motion in ("pan", "tilt") else np.zeros(n)
        self.position = np.zeros((n, 3))
        if motion == "forward":
            self.position[:, 2] = speed * t
        if motion == "path":        # R: camera-to-world rotation per frame
            self.position, self.R = path.pose(t)

    def omega(self) -> np.ndarray:
        """``(n, 3)`` the rotation since the previous frame (rad per frame, camera axes; 0 at frame 0)."""
        import cv2

        out = np.zeros((self.n, 3))
        for k in range(1, self.n):
            out[k] = cv2.Rodrigues(self.R[k - 1].T @ self.R[k])[0].ravel()
        return out

    def heading(self) -> list:
        """Per frame the focus of expansion ``[x, y]`` (px; None while the centre moves backwards or
        stands still): the centre's velocity (a central difference of 1e-4 s) in the camera's axes."""
        t = np.arange(self.n, dtype=np.float64) / self.fps
        dt = 1e-4
        vel = (self.path.pose(t + dt)[0] - self.path.pose(t - dt)[0]) / (2 * dt)
        vc = np.einsum("kji,kj->ki", self.R, vel)
        return [[float(self.cx + self.f * v[0] / v[2]), float(self.cy + self.f * v[1] / v[2])]
                if v[2] > 1e-6 * max(1.0, float(np.linalg.norm(v))) else None for v in vc]

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
        out = {"hfov_deg": self.hfov, "focal_px": self.f, "motion": self.motion, "speed": self.speed}
        if self.motion == "path":
            out.update(path=self.path.to_dict(), omega=[[float(v) for v in w] for w in self.omega()],
                       heading=self.heading())
        return out

    def check_turn(self) -> None:
        """Raise unless the whole turn stays within :data:`MAX_PAN_DEG` (pan) or keeps the view
        within :data:`MAX_ELEVATION_DEG` of the horizon (tilt): the far texture's panorama limits."""
        speed, n, fps = self.speed, self.n, self.fps
        if self.motion == "path":
            turn = abs(self.path.yaw_rate_dps) * (n - 1) / fps
            if turn > MAX_PATH_YAW_DEG:
                raise InputValueError(f"yaw_rate_dps {self.path.yaw_rate_dps:g} turns the camera {turn:.0f} deg "
                                      f"over {n} frames; at most {MAX_PATH_YAW_DEG:.0f}")
            return
        turn = abs(speed) * (n - 1) / fps
        if self.motion == "pan" and turn > MAX_PAN_DEG:
            raise InputValueError(f"camera_speed {speed:g} deg/s pans the camera {turn:.0f} deg over {n} frames; "
                                  f"at most {MAX_PAN_DEG:.0f}")
        if self.motion == "tilt":
            half_v = math.degrees(math.atan((self.h / 2.0) / self.f))
            if turn + half_v > MAX_ELEVATION_DEG:
                raise InputValueError(f"camera_speed {speed:g} deg/s tilts the camera {turn:.0f} deg over {n} frames; "
                                      f"at most {MAX_ELEVATION_DEG - half_v:.0f} with this view")
