"""The settings of real use: a dashcam drive, a drone, a hand-held camera (:func:`real_use_scene`).

Each scene is an :func:`~mlplc2.stimuli.world.approach` with a
:class:`~mlplc2.stimuli.world.camera.CameraPath` camera and exact truth:

* ``"drive"``: a car camera 1.3 m above a textured road at 8-25 m/s, turning at up to 3 deg/s,
  with a pitch bounce (0.3-0.6 deg, 1-2 Hz) and a little shake; beside the road, static
  hedges, walls and parked cars (textured or dark squares at 2.8-4.5 m from the path, kind
  ``"pass"``: the camera passes them); oncoming traffic and slower cars in the next lane that
  the camera overtakes (``"pass"``), a car that overtakes the camera (``"recede"``); a lead
  vehicle that has braked (slower than the camera, ``"collision"``) and crossing traffic that
  hits (``"collision"``).
* ``"drone"``: forward flight at 3-8 m/s, 6 m above the ground, yawing at up to 10 deg/s and
  rolling (3-6 deg, 0.3-0.5 Hz); birds and other drones from every side (above, below, left,
  right) that hit or pass.
* ``"handheld"``: a camera held by a walker (0-1.5 m/s) with shake (0.3-0.8 deg RMS per axis,
  0.5-2 cm), 1.5 m above the ground; thrown balls and passers-by that hit or pass, an object
  that moves away.

Objects are placed by where the vehicle will be (:func:`meeting`, :func:`roadside`), so a
turning path still meets its collisions and passes its roadside objects beside it. An object's
velocity is constant in the world: a braking lead car is one already slower than the camera.
The five scenes of a setting (``index`` 0-4) hold the kinds of the benchmark's other settings
(a collision; a collision and a pass; passes and no collision; a collision and a receding
object; two collisions and a pass), plus the drive's roadside objects; the rest is drawn
from ``seed``.
"""

from __future__ import annotations

import numpy as np

from ..._validation import InputValueError, check_int
from .._common import ApproachStimulus
from .camera import CameraPath
from .render import sub_seed
from .scenes import ApproachObject, approach

__all__ = ["real_use_scene", "meeting", "roadside", "REAL_USE_SETTINGS"]

#: The settings of :func:`real_use_scene`.
REAL_USE_SETTINGS: tuple[str, ...] = ("drive", "drone", "handheld")
#: The kinds of the moving objects of scenes 0-4 of a setting (as the benchmark's ``_KINDS``).
_KINDS = (("collision",), ("collision", "pass"), ("pass", "pass", "recede"), ("collision", "recede"),
          ("collision", "collision", "pass"))


def meeting(path: CameraPath, onset_s: float, start, ttc_s: float, aim=(0.0, 0.0)) -> tuple[float, float, float]:
    """The constant world velocity (along the vehicle's axes at ``onset_s``) that takes an object
    from ``start`` (vehicle axes at the onset, relative to the vehicle) to the vehicle's position
    plus ``aim`` (x, y in its axes then, m) ``ttc_s`` s later: there its relative Z is 0."""
    c0, v0 = path.vehicle(onset_s)
    c1, v1 = path.vehicle(onset_s + ttc_s)
    target = c1 + v1 @ np.array([aim[0], aim[1], 0.0])
    vel = (v0.T @ (target - c0) - np.asarray(start, np.float64)) / ttc_s
    return tuple(float(v) for v in vel)


def roadside(path: CameraPath, onset_s: float, pass_s: float, lateral: tuple[float, float]):
    """The start (vehicle axes at ``onset_s``) of a static object the vehicle passes ``pass_s`` s
    later at ``lateral`` (x, y in its axes then, m)."""
    c0, v0 = path.vehicle(onset_s)
    c1, v1 = path.vehicle(onset_s + pass_s)
    return tuple(float(v) for v in v0.T @ (c1 + v1 @ np.array([lateral[0], lateral[1], 0.0]) - c0))


def _mover(rng, path: CameraPath, kind: str, fps: float, n: int, height: float, where: str,
           appearance: str, width: float, own_speed: float) -> ApproachObject:
    """A moving object: ``kind`` collision / pass / recede, from ``where`` ("ahead", "left", "right",
    "above", "below"), ``width`` m, closing on the path at its own speed ``own_speed`` m/s."""
    onset = int(rng.integers(0, max(1, n // 4)))
    t0 = onset / fps
    shape = "square" if width > 1.0 else str(rng.choice(["disc", "square"]))
    if kind == "recede":          # ahead beside the path, faster than the camera
        y0 = height - width / 2 if height < 3.0 else 0.0          # on the ground, or in the air (in view)
        start = (float(rng.choice([-1.0, 1.0])) * 3.2, y0, float(rng.uniform(6.0, 12.0)))
        vel = (0.0, 0.0, path.speed_mps + own_speed)
        return ApproachObject(kind="recede", shape=shape, appearance=appearance, width_m=width, start=start,
                              velocity=vel, onset=onset)
    ttc = float(rng.uniform(0.45, 0.85)) * (n - 5 - onset) / fps
    closing = path.speed_mps + own_speed
    depth = max(closing * ttc, 4.0)
    side = {"ahead": (0.0, 0.0), "left": (-1.0, 0.0), "right": (1.0, 0.0), "above": (0.0, -1.0),
            "below": (0.0, 1.0)}[where]
    reach = float(rng.uniform(0.15, 0.3)) * depth                 # seen 9-17 deg off the axis
    y0 = height - width / 2 if height < 3.0 else 0.0              # on the ground, or in the air
    start = (side[0] * reach, y0 + side[1] * reach if height >= 3.0 or side[1] < 0 else y0, depth)
    if kind == "collision":
        aim = (float(rng.uniform(-0.2, 0.2)) * width, float(rng.uniform(-0.2, 0.2)) * width)
    else:
        lat = float(rng.uniform(2.0, 4.0)) * width * (-1.0 if side[0] <= 0 else 1.0)
        aim = (lat, float(rng.uniform(-0.2, 0.2)) * width)
    return ApproachObject(kind=kind, shape=shape, appearance=appearance, width_m=width, start=start,
                          velocity=meeting(path, t0, start, ttc, aim), onset=onset)


def _drive(rng, index: int, fps: float, n: int) -> tuple[CameraPath, list[ApproachObject], float, str]:
    speed = float(rng.uniform(8.0, 25.0))
    path = CameraPath(speed_mps=speed, yaw_rate_dps=float(rng.uniform(-3.0, 3.0)) if index % 2 else 0.0,
                      bounce_deg=float(rng.uniform(0.3, 0.6)), bounce_hz=float(rng.uniform(1.0, 2.0)),
                      shake_deg=0.05, shake_m=0.002, shake_seed=int(rng.integers(1 << 30)))
    height = 1.3
    objs = []
    for j in range(6):                       # hedges, walls and parked cars passed on both sides
        what = ("hedge", "wall", "parked")[j % 3]
        width = {"hedge": 1.5, "wall": 2.0, "parked": 1.6}[what]
        lateral = (1.0 if j % 2 else -1.0) * (2.8 if what == "parked" else float(rng.uniform(3.5, 4.5)))
        pass_s = (0.35 + 0.1 * j) * n / fps
        start = roadside(path, 0.0, pass_s, (lateral, height - width / 2))
        objs.append(ApproachObject(kind="pass", shape="square", appearance="dark" if what == "parked" else "textured",
                                   width_m=width, start=start, velocity=(0.0, 0.0, 0.0)))
    for j, kind in enumerate(_KINDS[index]):
        if kind == "collision":
            where = "ahead" if j == 0 else str(rng.choice(["left", "right"]))
            # a lead car slower than the camera by 2-6 m/s; crossing traffic closes at the camera's speed
            own = -speed + float(rng.uniform(2.0, 6.0)) if where == "ahead" else 0.0
            objs.append(_mover(rng, path, kind, fps, n, height, where, "dark", 1.8, own))
        elif kind == "pass":
            oncoming = j % 2 == 0
            objs.append(_mover(rng, path, kind, fps, n, height, "left" if oncoming else "right", "bright", 1.8,
                               float(rng.uniform(8.0, 15.0)) if oncoming else -speed + float(rng.uniform(3.0, 6.0))))
        else:
            objs.append(_mover(rng, path, kind, fps, n, height, "ahead", "bright", 1.8, float(rng.uniform(3.0, 6.0))))
    return path, objs, height, "ground"


def _drone(rng, index: int, fps: float, n: int) -> tuple[CameraPath, list[ApproachObject], float, str]:
    path = CameraPath(speed_mps=float(rng.uniform(3.0, 8.0)), yaw_rate_dps=float(rng.uniform(-10.0, 10.0)),
                      roll_deg=float(rng.uniform(3.0, 6.0)), roll_hz=float(rng.uniform(0.3, 0.5)),
                      bounce_deg=float(rng.uniform(0.5, 1.5)), bounce_hz=float(rng.uniform(0.3, 0.8)),
                      shake_deg=0.1, shake_m=0.005, shake_seed=int(rng.integers(1 << 30)))
    sides = ["left", "right", "above", "below", "ahead"]
    objs = [_mover(rng, path, kind, fps, n, 6.0, sides[(index + j) % 5], str(rng.choice(["dark", "textured"])),
                   float(rng.uniform(0.3, 0.8)), float(rng.uniform(2.0, 8.0))) for j, kind in enumerate(_KINDS[index])]
    return path, objs, 6.0, "ground"


def _handheld(rng, index: int, fps: float, n: int) -> tuple[CameraPath, list[ApproachObject], float, str]:
    path = CameraPath(speed_mps=float(rng.uniform(0.0, 1.5)), shake_deg=float(rng.uniform(0.3, 0.8)),
                      shake_m=float(rng.uniform(0.005, 0.02)), shake_seed=int(rng.integers(1 << 30)))
    sides = ["ahead", "left", "right", "above", "below"]
    objs = [_mover(rng, path, kind, fps, n, 6.0, sides[(index + 2 * j) % 5], str(rng.choice(["dark", "textured"])),
                   float(rng.uniform(0.2, 0.5)), float(rng.uniform(3.0, 8.0))) for j, kind in enumerate(_KINDS[index])]
    return path, objs, 1.5, "ground" if index % 2 else "texture"


def real_use_scene(setting: str, index: int, seed: int, *, duration_s: float = 6.0, size=(320, 240),
                   fps: float = 30.0, noise_std: float = 0.0, blur_px: float = 0.0,
                   supersample: int = 4, hfov_deg: float = 60.0) -> ApproachStimulus:
    """Scene ``index`` (0-4: its kinds) of ``setting`` ("drive", "drone", "handheld"; the module
    docstring), drawn from ``seed``: the same arguments give the same scene. ``hfov_deg``: the camera's
    horizontal field of view (the same world seen through another lens; :func:`approach`)."""
    if setting not in REAL_USE_SETTINGS:
        raise InputValueError(f"setting must be one of {', '.join(REAL_USE_SETTINGS)}, got {setting!r}")
    index = check_int(index, "index", minimum=0, maximum=len(_KINDS) - 1)
    n = int(round(duration_s * fps))
    rng = np.random.default_rng(sub_seed(check_int(seed, "seed"), 8))
    make = {"drive": _drive, "drone": _drone, "handheld": _handheld}[setting]
    path, objs, height, background = make(rng, index, fps, n)
    return approach(objs, size=size, fps=fps, hfov_deg=hfov_deg, frames=n, background=background, camera=path,
                    camera_height_m=height, noise_std=noise_std, blur_px=blur_px, supersample=supersample,
                    seed=seed, name=f"{setting}_{index}_{seed}")

