"""Approaches in 3-D seen by a pinhole camera, with exact ground truth (docs/stimuli.md).

The paper's stimuli are squares growing linearly on a scrolling picture
(:mod:`mlplc2.stimuli`). Here flat objects (discs and squares, dark, bright or
carrying their own texture) of a physical width move at constant 3-D velocity
in front of a pinhole camera that may stand still, pan, tilt or move forward
over a textured ground plane. Where an object appears and how large follow
from the projection, so a constant-speed approach grows as 1 / (time to
contact): slowly at first, very fast at the end.

Conventions
-----------
* Camera frame: the camera centre at the origin looking along +Z, X right,
  Y down. Image origin top-left, pixel centres at integer coordinates
  (column ``x``, row ``y``), principal point ``((W - 1) / 2, (H - 1) / 2)``,
  focal length ``f = (W / 2) / tan(hfov / 2)`` px (as
  :func:`mlplc2.camera.focal_length` and :func:`mlplc2.camera.bearing`).
  A point ``(X, Y, Z)`` with ``Z > 0`` is seen at
  ``x = cx + f X / Z``, ``y = cy + f Y / Z``.
* World frame: the camera frame at frame 0. ``camera="pan"`` turns the camera
  about its Y axis at ``camera_speed`` deg/s (positive: to the right, so the
  scene moves left), ``"tilt"`` about its X axis (positive: up, so the scene
  moves down), ``"forward"`` moves it along +Z at ``camera_speed`` m/s.
* An object's ``start`` and ``velocity`` are given along the axes of the
  camera at the object's onset frame, ``start`` relative to the camera's
  position then: an object made by :meth:`ApproachObject.collision` with
  ``at=(x, y)`` is seen at ``(x, y)`` at its onset, whatever the camera did
  before. The velocity is the object's own (in the world); a forward-moving
  camera adds ``-camera_speed`` to its relative Z velocity. Objects are
  fronto-parallel to the camera at their onset (their plane keeps its
  orientation in the world, so a panning camera sees it in perspective).
* Contact and miss are properties of the motion relative to the camera
  centre, which rotation does not change: in the object's frame (the camera
  axes at its onset, moving with the camera) the relative position is
  ``D(t) = start + v_rel (t - t_onset)``; contact is when ``D_z`` reaches 0
  (``contact_frame``, fractional), the miss is ``|D_xy| / width`` then, and
  the true time to contact at frame ``k`` is ``(contact_frame - k) / fps``.

Kinds (checked against the motion by :func:`approach`)
------------------------------------------------------
``collision``: relative Z velocity < 0 and miss < :data:`COLLISION_MISS`
(0.5 widths: the object's centre reaches the camera plane within half a width
of the camera centre); ``pass``: approaching with a miss of at least
:data:`PASS_MIN_MISS` (1 width, so neither a disc nor a square's corner
touches the camera): it grows, slides outwards and leaves the image before
contact; ``recede``: relative Z velocity > 0; ``translate``: relative Z
velocity 0, lateral velocity not 0; ``static``: no relative motion.

Rendering
---------
Every pixel's ray is intersected with the object's plane (a homography per
object and frame, evaluated only in the object's bounding box) on a
``supersample x supersample`` grid of sub-pixel samples; each sample counts the
share of its cell inside the outline (from its signed distance to it, exact for
a straight edge) and their mean is the pixel's coverage, so sub-pixel growth
shows as grey-level changes. Objects are drawn far to near (painter's order by
the depth Z of their centre); an object is drawn until it reaches the camera
plane (contact) while its centre is in front of the camera and nearer than
:data:`FAR_M`. Textured objects carry a
:func:`~mlplc2.stimuli.procedural_background` pattern fixed on the object,
sampled through the projection from a box-filter mip-map. Backgrounds: ``"plain"`` (:func:`mlplc2.stimuli.plain_level`),
``"texture"`` (a procedural texture at infinity, a panorama sampled by ray
direction: it moves only when the camera turns) and ``"ground"`` (a textured
ground plane ``camera_height_m`` below the camera under the far texture, each
pixel's ray intersected with the plane and filtered by its footprint, so the
far ground blurs instead of aliasing). Then optional optics blur
(``blur_px``, Gaussian sigma) and sensor noise (``noise_std`` grey levels),
rounded to ``uint8``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .._validation import (InputTypeError, InputValueError, check_fps, check_int, check_real, check_reals)
from ..camera import check_hfov, focal_length
from ._common import (MAX_STIMULUS_BYTES, ApproachStimulus, check_choice, check_size,
                        plain_level, procedural_background)
from ..evaluation.truth import ObjectTruth, TrackPoint

__all__ = [
    "ApproachObject",
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

#: Object kinds (motion relative to the camera).
APPROACH_KINDS: tuple[str, ...] = ("collision", "pass", "recede", "translate", "static")
#: Object outlines.
APPROACH_SHAPES: tuple[str, ...] = ("disc", "square")
#: Object appearances: grey level 0, 255, or their own procedural texture.
APPROACH_APPEARANCES: tuple[str, ...] = ("dark", "bright", "textured")
#: Backgrounds of :func:`approach`.
APPROACH_BACKGROUNDS: tuple[str, ...] = ("plain", "texture", "ground")
#: Camera motions of :func:`approach`.
CAMERA_MOTIONS: tuple[str, ...] = ("static", "pan", "tilt", "forward")

#: A collision's centre reaches the camera plane closer than this to the camera centre (widths).
COLLISION_MISS = 0.5
#: Largest aim offset (widths) :meth:`ApproachObject.collision` accepts.
COLLISION_AIM = 0.25
#: A pass misses the camera centre by at least this (widths): a disc's edge (0.5) and a square's
#: corner (0.71) stay clear of the camera.
PASS_MIN_MISS = 1.0
#: Lateral miss (widths) of the passes of :func:`random_scene` and the issue's benchmark.
PASS_MISS_WIDTHS = (2.0, 6.0)
#: Objects whose centre is farther than this (m) are not drawn.
FAR_M = 1000.0
#: Default physical width of an object (m).
DEFAULT_WIDTH_M = 0.5
#: Camera speed when none is given: pan/tilt deg/s, forward m/s.
DEFAULT_CAMERA_SPEED = {"static": 0.0, "pan": 10.0, "tilt": 4.0, "forward": 2.0}
#: Largest total camera rotation (deg): the far texture is an equirectangular panorama, which
#: must not wrap around (pan) or reach the zenith or nadir (tilt, including half the view).
MAX_PAN_DEG = 360.0
MAX_ELEVATION_DEG = 85.0
#: Side (texels, a power of 2) of an object's own texture, mapped onto its width.
OBJECT_TEXTURE_PX = 128
#: Side (texels, a power of 2) of the ground texture and its scale (m per texel). The texture is
#: periodic (``procedural_background(..., periodic=True)``) and tiles the plane every
#: 1024 x 0.01 = 10.24 m without seams.
GROUND_TEXTURE_PX = 1024
GROUND_TEXEL_M = 0.01
#: Sub-rows per pixel row on which the ground is sampled.
GROUND_SUBROWS = 4
#: Extra panorama margin (px) around the directions the camera sees.
_PANORAMA_MARGIN = 4


# ---------------------------------------------------------------------------
# Objects
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ApproachObject:
    """One flat object of an :func:`approach` scene.

    Parameters
    ----------
    kind : {"collision", "pass", "recede", "translate", "static"}
        Its motion relative to the camera (checked by :func:`approach`; see
        the module docstring).
    shape : {"disc", "square"}
        Outline; ``width_m`` is the disc's diameter or the square's side.
    appearance : {"dark", "bright", "textured"}
        Grey level 0, 255, or a procedural texture fixed on the object.
    width_m : float
        Physical width in metres (> 0).
    start : tuple of float
        ``(X, Y, Z)`` in metres at the onset frame, along the axes of the
        camera then and relative to its position then; ``Z > 0``.
    velocity : tuple of float
        ``(vx, vy, vz)`` in m/s, the object's own velocity in the world, along
        the same axes (a forward-moving camera adds its own motion).
    onset : int
        First frame of the object's life (absent before).
    seed : int or None
        Seed of its texture (``"textured"``); None: derived from the scene's
        seed and the object's position in the list.
    """

    kind: str
    shape: str = "disc"
    appearance: str = "dark"
    width_m: float = DEFAULT_WIDTH_M
    start: tuple[float, float, float] = (0.0, 0.0, 10.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, -5.0)
    onset: int = 0
    seed: int | None = None

    def __post_init__(self):
        check_choice(self.kind, "kind", APPROACH_KINDS)
        check_choice(self.shape, "shape", APPROACH_SHAPES)
        check_choice(self.appearance, "appearance", APPROACH_APPEARANCES)
        object.__setattr__(self, "width_m", check_real(self.width_m, "width_m", positive=True))
        start = check_reals(self.start, "start", 3, "X, Y, Z in m")
        if not start[2] > 0:
            raise InputValueError(f"start Z must be > 0 (in front of the camera), got {start[2]!r}")
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "velocity", check_reals(self.velocity, "velocity", 3, "vx, vy, vz in m/s"))
        object.__setattr__(self, "onset", check_int(self.onset, "onset"))
        if self.seed is not None:
            object.__setattr__(self, "seed", check_int(self.seed, "seed"))

    # -- convenience constructors (what a benchmark needs) ----------------------------------
    @classmethod
    def collision(cls, ttc_s: float = 2.0, *, at: tuple[float, float] | None = None,
                  width_m: float | None = None, width_px: float | None = None, speed_mps: float = 5.0,
                  miss_widths: float = 0.0, side: str | float = "right", shape: str = "disc",
                  appearance: str = "dark", onset: int = 0, seed: int | None = None,
                  size: tuple[int, int] = (320, 240), hfov_deg: float = 60.0,
                  ego_speed_mps: float = 0.0) -> ApproachObject:
        """An object seen at ``at`` at its onset that hits the camera ``ttc_s`` s later.

        Parameters
        ----------
        ttc_s : float
            Time to contact at the onset (s, > 0).
        at : tuple of float or None
            ``(x, y)`` image position (px) at the onset; None: the principal point.
        width_m, width_px : float or None
            Physical width (m) or apparent width at the onset (px); at most one
            (neither: :data:`DEFAULT_WIDTH_M`).
        speed_mps : float
            Closing speed along the optical axis relative to the camera (m/s,
            > 0): the object starts at ``Z = speed_mps * ttc_s``.
        miss_widths : float
            Where its centre crosses the camera plane, in widths from the camera
            centre (``0 <= miss_widths <= COLLISION_AIM``).
        side : {"right", "left", "below", "above"} or float
            Direction of that offset (an image-plane angle in degrees: 0 right,
            90 below, 180 left, 270 above).
        shape, appearance, onset, seed
            As in :class:`ApproachObject`.
        size, hfov_deg
            The camera the position and apparent width refer to (as given to
            :func:`approach`).
        ego_speed_mps : float
            The camera's forward speed in the scene (``camera="forward"``): the
            object's own velocity is chosen so that the motion relative to the
            camera is as asked.
        """
        miss = check_real(miss_widths, "miss_widths", minimum=0.0)
        if miss > COLLISION_AIM:
            raise InputValueError(f"miss_widths of a collision must be <= {COLLISION_AIM} widths, got "
                                  f"{miss_widths!r} (use ApproachObject.pass_by)")
        return cls._approaching("collision", ttc_s, at, width_m, width_px, speed_mps, miss, side, shape,
                                appearance, onset, seed, size, hfov_deg, ego_speed_mps)

    @classmethod
    def pass_by(cls, ttc_s: float = 2.0, *, miss_widths: float = 3.0, side: str | float = "right",
                at: tuple[float, float] | None = None, width_m: float | None = None,
                width_px: float | None = None, speed_mps: float = 5.0, shape: str = "disc",
                appearance: str = "dark", onset: int = 0, seed: int | None = None,
                size: tuple[int, int] = (320, 240), hfov_deg: float = 60.0,
                ego_speed_mps: float = 0.0) -> ApproachObject:
        """An object that approaches like :meth:`collision` but misses the camera.

        Its centre crosses the camera plane ``ttc_s`` s after the onset,
        ``miss_widths`` widths (>= :data:`PASS_MIN_MISS`; the benchmark uses 2-6)
        from the camera centre towards ``side``: it grows, slides outwards to
        that side and leaves the image before then. Other parameters as in
        :meth:`collision`.
        """
        miss = check_real(miss_widths, "miss_widths", minimum=PASS_MIN_MISS)
        return cls._approaching("pass", ttc_s, at, width_m, width_px, speed_mps, miss, side, shape,
                                appearance, onset, seed, size, hfov_deg, ego_speed_mps)

    @classmethod
    def receding(cls, *, at: tuple[float, float] | None = None, distance_m: float = 5.0,
                 width_m: float | None = None, width_px: float | None = None, speed_mps: float = 2.0,
                 shape: str = "disc", appearance: str = "dark", onset: int = 0, seed: int | None = None,
                 size: tuple[int, int] = (320, 240), hfov_deg: float = 60.0,
                 ego_speed_mps: float = 0.0) -> ApproachObject:
        """An object at depth ``distance_m`` seen at ``at`` that moves away along its line of
        sight (its image stays at ``at`` and shrinks), Z increasing at ``speed_mps`` relative to
        the camera. Other parameters as in :meth:`collision`."""
        ray, z, width = _place(at, distance_m, width_m, width_px, size, hfov_deg)
        speed = check_real(speed_mps, "speed_mps", positive=True)
        rel = tuple(speed * c for c in ray)
        return cls._make("recede", z, ray, width, rel, shape, appearance, onset, seed, ego_speed_mps)

    @classmethod
    def translating(cls, *, at: tuple[float, float] | None = None, distance_m: float = 5.0,
                    width_m: float | None = None, width_px: float | None = None, speed_mps: float = 1.0,
                    direction_deg: float = 0.0, shape: str = "disc", appearance: str = "dark",
                    onset: int = 0, seed: int | None = None, size: tuple[int, int] = (320, 240),
                    hfov_deg: float = 60.0, ego_speed_mps: float = 0.0) -> ApproachObject:
        """An object at depth ``distance_m`` seen at ``at`` moving parallel to the image plane
        at ``speed_mps`` towards ``direction_deg`` (0 right, 90 down) relative to the camera.
        Other parameters as in :meth:`collision`."""
        ray, z, width = _place(at, distance_m, width_m, width_px, size, hfov_deg)
        speed = check_real(speed_mps, "speed_mps", positive=True)
        a = math.radians(check_real(direction_deg, "direction_deg"))
        rel = (speed * math.cos(a), speed * math.sin(a), 0.0)
        return cls._make("translate", z, ray, width, rel, shape, appearance, onset, seed, ego_speed_mps)

    @classmethod
    def static(cls, *, at: tuple[float, float] | None = None, distance_m: float = 5.0,
               width_m: float | None = None, width_px: float | None = None, shape: str = "disc",
               appearance: str = "dark", onset: int = 0, seed: int | None = None,
               size: tuple[int, int] = (320, 240), hfov_deg: float = 60.0,
               ego_speed_mps: float = 0.0) -> ApproachObject:
        """An object at depth ``distance_m`` seen at ``at`` that keeps still relative to the
        camera (with a forward-moving camera it moves with it). Other parameters as in
        :meth:`collision`."""
        ray, z, width = _place(at, distance_m, width_m, width_px, size, hfov_deg)
        return cls._make("static", z, ray, width, (0.0, 0.0, 0.0), shape, appearance, onset, seed,
                         ego_speed_mps)

    @classmethod
    def _approaching(cls, kind, ttc_s, at, width_m, width_px, speed_mps, miss, side, shape, appearance,
                     onset, seed, size, hfov_deg, ego_speed_mps) -> ApproachObject:
        ttc = check_real(ttc_s, "ttc_s", positive=True)
        speed = check_real(speed_mps, "speed_mps", positive=True)
        ray, z, width = _place(at, speed * ttc, width_m, width_px, size, hfov_deg)
        a = _side_angle(side)
        aim = (miss * width * math.cos(a), miss * width * math.sin(a))
        start = (z * ray[0], z * ray[1], z)
        rel = ((aim[0] - start[0]) / ttc, (aim[1] - start[1]) / ttc, -speed)
        return cls._make(kind, z, ray, width, rel, shape, appearance, onset, seed, ego_speed_mps)

    @classmethod
    def _make(cls, kind, z, ray, width, rel, shape, appearance, onset, seed, ego_speed_mps) -> ApproachObject:
        ego = check_real(ego_speed_mps, "ego_speed_mps")
        return cls(kind=kind, shape=shape, appearance=appearance, width_m=width,
                   start=(z * ray[0], z * ray[1], z), velocity=(rel[0], rel[1], rel[2] + ego), onset=onset,
                   seed=seed)


_SIDES = {"right": 0.0, "below": 90.0, "left": 180.0, "above": 270.0}


def _side_angle(side) -> float:
    if isinstance(side, str):
        if side not in _SIDES:
            raise InputValueError(f"side must be one of {', '.join(_SIDES)} or an angle in degrees, got {side!r}")
        return math.radians(_SIDES[side])
    return math.radians(check_real(side, "side"))


def _place(at, distance, width_m, width_px, size, hfov_deg):
    """Ray ``(X/Z, Y/Z, 1)`` through image point ``at``, depth and physical width."""
    w, h = check_size(size)
    f = focal_length(w, check_hfov(hfov_deg, required=True))
    z = check_real(distance, "distance_m", positive=True)
    if at is None:
        x, y = (w - 1) / 2.0, (h - 1) / 2.0
    else:
        x, y = check_reals(at, "at", 2, "x, y in px")
    if width_m is not None and width_px is not None:
        raise InputValueError("give width_m or width_px, not both")
    if width_px is not None:
        width = check_real(width_px, "width_px", positive=True) * z / f
    else:
        width = check_real(DEFAULT_WIDTH_M if width_m is None else width_m, "width_m", positive=True)
    return (((x - (w - 1) / 2.0) / f), ((y - (h - 1) / 2.0) / f), 1.0), z, width


# ---------------------------------------------------------------------------
# Ground truth
# ---------------------------------------------------------------------------

#: The older name of the 3-D truth: one :class:`mlplc2.evaluation.truth.ObjectTruth` per object, with its
#: ``kind``, ``approach`` (the frames in view while approaching), ``contact_frame``, ``miss``,
#: a ``track`` of :class:`mlplc2.evaluation.truth.TrackPoint` (one row per frame in which the object is at
#: least partly in view: the projection of its centre, the extent of its outline, None while
#: part of it is behind the camera, the true time to contact and the predicted miss) and the
#: object as given in ``extra`` (``shape``, ``width_m``, ``onset``, ``start_m``,
#: ``velocity_mps``); its ``polarity`` is the object's appearance. docs/stimuli.md "Ground truth".
ObjectTrack = ObjectTruth


# ---------------------------------------------------------------------------
# Camera
# ---------------------------------------------------------------------------

class _Camera:
    """The pinhole camera and its motion over ``n`` frames."""

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


# ---------------------------------------------------------------------------
# Geometry of one object over the frames
# ---------------------------------------------------------------------------

class _Geometry:
    """Per-frame camera-frame pose, homography and image extent of one object."""

    def __init__(self, obj: ApproachObject, cam: _Camera):
        self.obj = obj
        self.r = obj.width_m / 2.0
        k0 = obj.onset
        self.frames = np.arange(k0, cam.n)
        tau = (self.frames - k0) / cam.fps
        ego = cam.speed if cam.motion == "forward" else 0.0
        self.v_rel = np.array(obj.velocity) - np.array([0.0, 0.0, ego])
        rel = np.array(obj.start)[None, :] + tau[:, None] * self.v_rel[None, :]   # object frame
        # camera frame at frame k: R(k)^T R(k0) (rotation about one fixed axis: by -(angle_k - angle_k0))
        if len(self.frames):
            M = cam.rotation(cam.angle[k0] - cam.angle[self.frames]) if cam.motion in ("pan", "tilt") else \
                np.broadcast_to(np.eye(3), (len(self.frames), 3, 3))
        else:
            M = np.zeros((0, 3, 3))
        self.P = np.einsum("kij,kj->ki", M, rel)           # centre, camera frame
        e1, e2 = M[:, :, 0], M[:, :, 1]                    # object axes, camera frame
        self.H = np.einsum("ij,kjl->kil", cam.K, np.stack([e1, e2, self.P], -1))   # plane (m) -> image
        z = self.P[:, 2]
        # drawn until it reaches the camera plane (its own Z; contact), while its centre is in
        # front of the camera and nearer than FAR_M
        self.drawn = (rel[:, 2] > 0) & (z > 0) & (z < FAR_M)
        with np.errstate(divide="ignore"):
            self.px_per_m = cam.f / z            # image scale at the centre (exact without rotation)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.x = cam.cx + cam.f * self.P[:, 0] / z
            self.y = cam.cy + cam.f * self.P[:, 1] / z
            self.Hinv = np.linalg.inv(np.where(self.drawn[:, None, None], self.H, np.eye(3)))
        # bounding box of the projected bounding square; whole image if a corner is behind the camera
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], np.float64) * self.r
        q = self.P[:, None, :] + corners[None, :, 0, None] * e1[:, None, :] + corners[None, :, 1, None] * e2[:, None, :]
        qz = q[:, :, 2]
        self.whole = qz.min(axis=1) > 0                     # the bounding square is in front of the camera
        with np.errstate(divide="ignore", invalid="ignore"):
            qx = cam.cx + cam.f * q[:, :, 0] / qz
            qy = cam.cy + cam.f * q[:, :, 1] / qz
        self.box = np.stack([qx.min(1), qx.max(1), qy.min(1), qy.max(1)], -1)
        # extent of the projected outline (exact): corners for a square, the dual conic for a disc
        if obj.shape == "square":
            width, height = self.box[:, 1] - self.box[:, 0], self.box[:, 3] - self.box[:, 2]
            front = self.whole
        else:
            dual = np.einsum("kij,j,klj->kil", self.H, np.array([self.r ** 2, self.r ** 2, -1.0]), self.H)
            c33 = dual[:, 2, 2]
            with np.errstate(divide="ignore", invalid="ignore"):
                width = 2.0 * np.sqrt(np.maximum(dual[:, 0, 2] ** 2 - dual[:, 0, 0] * c33, 0.0)) / np.abs(c33)
                height = 2.0 * np.sqrt(np.maximum(dual[:, 1, 2] ** 2 - dual[:, 1, 1] * c33, 0.0)) / np.abs(c33)
            front = z - self.r * np.hypot(e1[:, 2], e2[:, 2]) > 0
        self.width = np.where(front, width, np.nan)
        self.height = np.where(front, height, np.nan)
        # contact and miss (motion relative to the camera centre, object frame)
        self.contact = None
        self.miss = None
        if self.v_rel[2] < 0:
            tc = -obj.start[2] / self.v_rel[2]
            self.contact = float(obj.onset + tc * cam.fps)
            at = np.array(obj.start) + tc * self.v_rel
            self.miss = float(math.hypot(at[0], at[1]) / obj.width_m)

    def check_kind(self, i: int) -> None:
        """Raise unless the declared kind matches the relative motion."""
        kind, vz = self.obj.kind, self.v_rel[2]
        speed = float(np.linalg.norm(self.v_rel))
        tol = 1e-9 * max(1.0, speed)
        where = f"objects[{i}] (kind {kind!r})"
        if kind in ("collision", "pass"):
            if not vz < -tol:
                raise InputValueError(f"{where} does not approach the camera (relative vz = {vz:g} m/s)")
            if kind == "collision" and not self.miss < COLLISION_MISS:
                raise InputValueError(f"{where} misses the camera centre by {self.miss:.3g} widths; a collision "
                                      f"needs < {COLLISION_MISS} (use kind 'pass')")
            if kind == "pass" and not self.miss >= PASS_MIN_MISS:
                raise InputValueError(f"{where} misses the camera centre by {self.miss:.3g} widths; a pass "
                                      f"needs >= {PASS_MIN_MISS}")
        elif kind == "recede" and not vz > tol:
            raise InputValueError(f"{where} does not move away from the camera (relative vz = {vz:g} m/s)")
        elif kind == "translate" and not (abs(vz) <= tol and speed > tol):
            raise InputValueError(f"{where} must move parallel to the image plane (relative vz = {vz:g} m/s, "
                                  f"speed {speed:g} m/s)")
        elif kind == "static" and not speed <= tol:
            raise InputValueError(f"{where} moves relative to the camera at {speed:g} m/s")

    def truth(self, oid: int, visible: np.ndarray, fps: float) -> ObjectTruth:
        obj = self.obj
        rows = []
        approaching = self.v_rel[2] < 0
        for j in np.flatnonzero(visible):
            k = int(self.frames[j])
            ttc = float((self.contact - k) / fps) if approaching else None
            rows.append(TrackPoint(k, float(self.x[j]), float(self.y[j]), _opt(self.width[j]), _opt(self.height[j]),
                                   ttc, self.miss))
        span = (rows[0].frame, rows[-1].frame + 1) if approaching and rows else None
        return ObjectTruth(id=oid, kind=obj.kind, polarity=obj.appearance, approach=span, track=tuple(rows),
                           contact_frame=self.contact, miss=self.miss,
                           extra={"shape": obj.shape, "width_m": obj.width_m, "onset": int(obj.onset),
                                  "start_m": list(obj.start), "velocity_mps": list(obj.velocity)})


def _opt(value: float) -> float | None:
    return None if not np.isfinite(value) else float(value)


# ---------------------------------------------------------------------------
# Textures
# ---------------------------------------------------------------------------

def _seed(seed: int, *key: int) -> int:
    """An independent 32-bit seed for one purpose of a scene."""
    return int(np.random.SeedSequence([seed, *key]).generate_state(1)[0])


def _mipmap(texture: np.ndarray) -> list[np.ndarray]:
    """Box-filter pyramid (2 x 2 means) of a power-of-2 square texture, down to 1 x 1."""
    levels = [np.asarray(texture, np.float32)]
    while levels[-1].shape[0] > 1:
        t = levels[-1]
        n = t.shape[0] // 2
        levels.append(t.reshape(n, 2, n, 2).mean(axis=(1, 3)))
    return levels


def _sample(tex: np.ndarray, mx: np.ndarray, my: np.ndarray, *, wrap: bool = False) -> np.ndarray:
    """Bilinear samples of ``tex`` at the points ``(mx, my)`` (1-D, texel centres at integers;
    beyond the border the texture repeats if ``wrap``, else is mirrored)."""
    import cv2

    n = mx.size
    cols = 4096                                  # cv2.remap: fewer than 32767 columns
    rows = -(-n // cols)
    grid = []
    for m, size in ((mx, tex.shape[1]), (my, tex.shape[0])):
        g = np.zeros(rows * cols, np.float32)
        g[:n] = m
        if wrap:   # into [0, size): cv2.remap is many times faster inside the texture
            g -= np.float32(size) * np.floor(g * np.float32(1.0 / size))
        grid.append(g.reshape(rows, cols))
    border = cv2.BORDER_WRAP if wrap else cv2.BORDER_REFLECT
    return cv2.remap(tex, grid[0], grid[1], cv2.INTER_LINEAR, borderMode=border).ravel()[:n]


# ---------------------------------------------------------------------------
# Backgrounds
# ---------------------------------------------------------------------------

class _Background:
    """Renders the background of each frame (float32 ``(H, W)``)."""

    def __init__(self, kind: str, cam: _Camera, level: float, seed: int):
        import cv2

        self.cv2 = cv2
        self.kind, self.cam, self.level = kind, cam, level
        self.cache: np.ndarray | None = None          # the last frame (reused while nothing moves)
        self.sky: np.ndarray | None = None            # the far texture of the last frame
        self.maps = None                              # panorama coordinates of the pixels
        w, h = cam.w, cam.h
        self.rays = cam.rays(np.arange(w, dtype=np.float64)[None, :],
                             np.arange(h, dtype=np.float64)[:, None])      # (H, W, 3)
        if kind in ("texture", "ground"):
            # panorama: azimuth x elevation at f px per radian, covering every direction seen
            border = np.concatenate([self.rays[0], self.rays[-1], self.rays[:, 0], self.rays[:, -1]])
            angles = np.unique(np.concatenate([cam.angle[[0, -1]], cam.angle[::max(1, cam.n // 64)]]))
            az, el = self._angles(np.einsum("aij,pj->api", cam.rotation(angles), border))
            m = _PANORAMA_MARGIN / cam.f
            self.az0, self.el0 = az.min() - m, el.min() - m
            pw = int(math.ceil((az.max() - az.min()) * cam.f)) + 2 * _PANORAMA_MARGIN + 2
            ph = int(math.ceil((el.max() - el.min()) * cam.f)) + 2 * _PANORAMA_MARGIN + 2
            self.panorama = procedural_background(pw, ph, _seed(seed, 1)).astype(np.float32)
        self.ground = _Ground(cam, _seed(seed, 2)) if kind == "ground" else None

    @staticmethod
    def _angles(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.arctan2(d[..., 0], d[..., 2]), np.arctan2(d[..., 1], np.hypot(d[..., 0], d[..., 2]))

    def frame(self, k: int) -> np.ndarray:
        """A new float32 ``(H, W)`` background of frame ``k``."""
        cam = self.cam
        if self.kind == "plain":
            return np.full((cam.h, cam.w), self.level, np.float32)
        rotating = cam.motion in ("pan", "tilt")
        if self.cache is not None and not rotating and not (self.ground and cam.motion == "forward"):
            return self.cache.copy()                       # nothing in the background moves
        if self.sky is None or rotating:
            if self.maps is None or cam.motion == "tilt":
                az, el = self._angles(self.rays @ cam.rotation(cam.angle[k]).T)     # world directions
                self.maps = (((az - self.az0) * cam.f).astype(np.float32),
                             ((el - self.el0) * cam.f).astype(np.float32), cam.angle[k])
            mx, my, angle = self.maps
            if cam.motion == "pan":          # panning adds to every direction's azimuth
                mx = mx + np.float32((cam.angle[k] - angle) * cam.f)
            self.sky = self.cv2.remap(self.panorama, mx, my, self.cv2.INTER_LINEAR,
                                      borderMode=self.cv2.BORDER_REFLECT)
        img = self.ground.render(self.sky, k) if self.ground else self.sky.copy()
        self.cache = img.copy()
        return img


class _Ground:
    """A textured ground plane ``camera_height_m`` below the camera (Y = +height).

    Each pixel is sampled on :data:`GROUND_SUBROWS` sub-rows (the ground's footprint is longest
    along the image's columns); every sample's ray is intersected with the plane, and the
    periodic texture is read from the box-filter mip-map at the level of the sample's footprint
    (the larger of the pixel's extent along x and the sub-row's along y, in texels, measured on
    the pixel's middle sub-row; trilinear interpolation), so the far ground blurs instead of
    aliasing. Samples whose ray does not
    reach the ground (above the horizon) keep the far texture; the sub-row mean also
    anti-aliases the horizon. The rays, footprints and levels are computed once, except for a
    tilting camera: moving forward only shifts the ground points, panning turns them about
    the vertical axis (the footprints do not change).
    """

    def __init__(self, cam: _Camera, seed: int):
        self.cam = cam
        self.levels = _mipmap(procedural_background(GROUND_TEXTURE_PX, GROUND_TEXTURE_PX, seed, periodic=True))
        sub = (np.arange(GROUND_SUBROWS) + 0.5) / GROUND_SUBROWS - 0.5
        ys = (np.arange(cam.h)[:, None] + sub[None, :]).ravel()[:, None]
        # float32: the ground points need no more (the far ones read coarse levels), at half the cost
        self.rays = cam.rays(np.arange(cam.w, dtype=np.float64)[None, :], ys).astype(np.float32)
        self.plan = None

    def _setup(self, rot: np.ndarray) -> None:
        """Ground points (texels from the camera), mip-map levels and weights of the samples."""
        cam = self.cam
        d = self.rays @ rot.T.astype(np.float32)
        below = d[..., 1] > 1e-6
        s = np.float32(cam.height / GROUND_TEXEL_M) / np.where(below, d[..., 1], np.nan)   # ray length, texels
        gx = s * d[..., 0]
        gz = s * d[..., 2]
        # footprint per pixel (from its middle sub-row) along x and per sub-row along y
        S = GROUND_SUBROWS
        px, pz = gx[S // 2::S], gz[S // 2::S]
        with np.errstate(invalid="ignore"):
            fx = np.hypot(np.diff(px, axis=1), np.diff(pz, axis=1))
            fy = np.hypot(np.diff(px, axis=0), np.diff(pz, axis=0)) / S
        fx = np.concatenate([fx, fx[:, -1:]], axis=1) if cam.w > 1 else np.full(px.shape, np.nan, np.float32)
        fy = np.concatenate([fy, fy[-1:]], axis=0) if cam.h > 1 else np.full(px.shape, np.nan, np.float32)
        top = len(self.levels) - 1
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.repeat(np.clip(np.log2(np.fmax(fx, fy)), 0.0, float(top)), S, axis=0)
        idx = np.flatnonzero(below)
        lam = lam.ravel()[idx]
        lam[~np.isfinite(lam)] = top                                  # next to the horizon
        lo = np.floor(lam).astype(np.int64)
        frac = (lam - lo).astype(np.float32)
        # each sample reads two levels; group the reads by level
        which = np.concatenate([np.arange(idx.size), np.arange(idx.size)])
        level = np.concatenate([lo, np.minimum(lo + 1, top)])
        weight = np.concatenate([1.0 - frac, frac])
        keep = weight > 0
        which, level, weight = which[keep], level[keep], weight[keep]
        order = np.argsort(level, kind="stable")
        bounds = np.searchsorted(level[order], np.arange(top + 2))
        groups = []
        for lv in range(top + 1):
            j = order[bounds[lv]:bounds[lv + 1]]
            if j.size:
                groups.append((lv, which[j], weight[j]))
        self.plan = (idx, gx.ravel()[idx], gz.ravel()[idx], groups)

    def render(self, sky: np.ndarray, k: int) -> np.ndarray:
        cam = self.cam
        if self.plan is None or cam.motion == "tilt":
            self._setup(cam.rotation(cam.angle[k] if cam.motion == "tilt" else 0.0))
        idx, gx, gz, groups = self.plan
        if cam.motion == "pan":
            c, s = math.cos(cam.angle[k]), math.sin(cam.angle[k])
            gx, gz = c * gx + s * gz, c * gz - s * gx
        ox, oz = cam.position[k, 0] / GROUND_TEXEL_M, cam.position[k, 2] / GROUND_TEXEL_M
        acc = np.zeros(idx.size, np.float32)
        for level, which, weight in groups:
            tex = self.levels[level]
            n = tex.shape[0]
            scale = 2.0 ** -level        # level-0 texel t -> level texel t * scale - (1 - scale) / 2
            # the camera's offset is wrapped into one period first (float64): the texture tiles
            mx = gx[which] * scale + ((ox * scale) % n - 0.5 * (1.0 - scale))
            mz = gz[which] * scale + ((oz * scale) % n - 0.5 * (1.0 - scale))
            acc[which] += weight * _sample(tex, mx, mz, wrap=True)    # a sample once per level
        sub = np.repeat(sky, GROUND_SUBROWS, axis=0)
        sub.ravel()[idx] = acc
        return sub.reshape(cam.h, GROUND_SUBROWS, cam.w).mean(axis=1)


# ---------------------------------------------------------------------------
# Objects on one frame
# ---------------------------------------------------------------------------

def _draw(img: np.ndarray, geo: _Geometry, j: int, ss: int, level: float,
          texture: list[np.ndarray] | None) -> bool:
    """Composite object ``geo`` at its frame index ``j`` onto ``img`` (in place); True if it
    covers any sub-pixel sample of the image."""
    import cv2

    h, w = img.shape
    if geo.whole[j]:
        x0, x1, y0, y1 = geo.box[j]
        i0, i1 = max(0, int(math.floor(x0))), min(w - 1, int(math.ceil(x1)))
        r0, r1 = max(0, int(math.floor(y0))), min(h - 1, int(math.ceil(y1)))
        if i0 > i1 or r0 > r1:
            return False
    else:
        i0, i1, r0, r1 = 0, w - 1, 0, h - 1
    nx, ny = i1 - i0 + 1, r1 - r0 + 1
    offs = (np.arange(ss, dtype=np.float64) + 0.5) / ss - 0.5
    xs = (np.arange(i0, i1 + 1, dtype=np.float64)[:, None] + offs[None, :]).ravel()[None, :]
    ys = (np.arange(r0, r1 + 1, dtype=np.float64)[:, None] + offs[None, :]).ravel()[:, None]
    hi = geo.Hinv[j]
    den = (hi[2, 0] * xs + hi[2, 2]) + hi[2, 1] * ys
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(den > 0, 1.0 / den, np.nan)
        u = ((hi[0, 0] * xs + hi[0, 2]) + hi[0, 1] * ys) * inv
        v = ((hi[1, 0] * xs + hi[1, 2]) + hi[1, 1] * ys) * inv
        r = geo.r
        dist = np.hypot(u, v) if geo.obj.shape == "disc" else np.maximum(np.abs(u), np.abs(v))
        # each sample's share of its own cell (1/ss px wide) inside the outline, from its signed
        # distance to the outline: exact for a straight edge, so coverage changes smoothly
        sub = np.clip(0.5 - (dist - r) * (geo.px_per_m[j] * ss), 0.0, 1.0)
    sub = np.nan_to_num(sub, nan=0.0).astype(np.float32)
    if not sub.any():
        return False
    cover = sub.reshape(ny, ss, nx, ss).mean(axis=(1, 3))
    if texture is None:
        patch = img[r0:r1 + 1, i0:i1 + 1]
        patch += (np.float32(level) - patch) * cover
        return True
    # textured: sample the object's mip-map level whose texels match the sub-pixel samples
    wpx = geo.width[j] if np.isfinite(geo.width[j]) else float(w)
    lvl = int(np.clip(math.floor(math.log2(max(OBJECT_TEXTURE_PX / max(wpx * ss, 1e-9), 1.0))), 0,
                      len(texture) - 1))
    tex = texture[lvl]
    n = tex.shape[0]
    inside = sub > 0
    mx = np.where(inside, (u / (2 * r) + 0.5) * n - 0.5, 0.0).astype(np.float32)
    my = np.where(inside, (v / (2 * r) + 0.5) * n - 0.5, 0.0).astype(np.float32)
    vals = cv2.remap(tex, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    paint = (vals * sub).reshape(ny, ss, nx, ss).mean(axis=(1, 3))
    patch = img[r0:r1 + 1, i0:i1 + 1]
    patch *= 1.0 - cover
    patch += paint
    return True


# ---------------------------------------------------------------------------
# The generator
# ---------------------------------------------------------------------------

def approach(objects, *, size: tuple[int, int] = (320, 240), fps: float = 30.0, hfov_deg: float = 60.0,
             frames: int | None = None, duration_s: float | None = None, background: str = "plain",
             camera: str = "static", camera_speed: float = 0.0, camera_height_m: float = 1.0,
             noise_std: float = 0.0, blur_px: float = 0.0, supersample: int = 4, seed: int = 0,
             name: str = "approach") -> ApproachStimulus:
    """Render flat objects moving in 3-D in front of a (moving) pinhole camera, with their truth.

    Parameters
    ----------
    objects : ApproachObject or sequence of ApproachObject
        The objects (``id`` = 1-based position).
    size : tuple of int
        ``(W, H)`` in pixels.
    fps : float
        Frame rate.
    hfov_deg : float
        Horizontal field of view (degrees, in (0, 180)).
    frames, duration_s : int or float or None
        Length (at most one of them). Neither: until the last contact of an
        approaching object (``ceil(contact_frame) + 1`` frames), or 150 frames
        without one.
    background : {"plain", "texture", "ground"}
        ``"plain"``: uniform grey :func:`mlplc2.stimuli.plain_level` (250 if
        every object is dark, 0 if every one is bright, else 128);
        ``"texture"``: a procedural texture at infinity; ``"ground"``: a
        textured ground plane below the horizon, the far texture above.
    camera : {"static", "pan", "tilt", "forward"}
        Camera motion (module docstring).
    camera_speed : float
        Pan or tilt rate (deg/s, positive right / up) or forward speed (m/s);
        must be 0 for a static camera.
    camera_height_m : float
        Height of the camera above the ground plane (m, ``"ground"``).
    noise_std : float
        Standard deviation of additive Gaussian sensor noise (grey levels).
    blur_px : float
        Sigma (px) of a Gaussian optics blur applied before the noise (0: none).
    supersample : int
        Sub-pixel samples per pixel side for the objects' anti-aliasing (1-16).
    seed : int
        Seed of the textures and the noise.
    name : str
        Name stored in the result.

    Returns
    -------
    ApproachStimulus
        ``frames`` ``uint8 (T, H, W)``; ``objects`` one 3-D :class:`~mlplc2.evaluation.truth.ObjectTruth`
        per object; :meth:`ApproachStimulus.to_ground_truth` gives the JSON
        entry of docs/stimuli.md.

    Examples
    --------
    >>> from mlplc2.stimuli import ApproachObject, approach
    >>> obj = ApproachObject.collision(ttc_s=0.5, width_px=4.0, size=(64, 48))
    >>> stim = approach([obj], size=(64, 48), frames=10)
    >>> stim.frames.shape, stim.objects[0].contact_frame
    ((10, 48, 64), 15.0)
    """
    if isinstance(objects, ApproachObject):
        objects = [objects]
    if isinstance(objects, (str, bytes)) or not hasattr(objects, "__iter__"):
        raise InputTypeError(f"objects must be a sequence of ApproachObject, got {type(objects).__name__}")
    objects = list(objects)
    for i, o in enumerate(objects):
        if not isinstance(o, ApproachObject):
            raise InputTypeError(f"objects[{i}] must be an ApproachObject, got {type(o).__name__}")
    w, h = check_size(size)
    fps = check_fps(fps)
    focal_length(w, check_hfov(hfov_deg, required=True))                  # checks hfov_deg
    hfov = float(hfov_deg)
    background = check_choice(background, "background", APPROACH_BACKGROUNDS)
    camera = check_choice(camera, "camera", CAMERA_MOTIONS)
    speed = check_real(camera_speed, "camera_speed")
    if camera == "static" and speed != 0:
        raise InputValueError(f"camera_speed must be 0 for a static camera, got {camera_speed!r}")
    height = check_real(camera_height_m, "camera_height_m", positive=True)
    noise = check_real(noise_std, "noise_std", minimum=0.0)
    blur = check_real(blur_px, "blur_px", minimum=0.0)
    ss = check_int(supersample, "supersample", minimum=1, maximum=16)
    seed = check_int(seed, "seed")
    if frames is not None and duration_s is not None:
        raise InputValueError("give frames or duration_s, not both")
    if frames is not None:
        n = check_int(frames, "frames", minimum=1)
    elif duration_s is not None:
        n = int(round(check_real(duration_s, "duration_s", positive=True) * fps))
        if n < 1:
            raise InputValueError(f"duration_s {duration_s!r} is shorter than one frame at {fps:g} fps")
    else:
        probe = _Camera(w, h, hfov, fps, camera, speed, height, 1)
        contacts = [g.contact for g in (_Geometry(o, probe) for o in objects) if g.contact is not None]
        n = int(math.ceil(max(contacts))) + 1 if contacts else 150
    if n * w * h > MAX_STIMULUS_BYTES:
        raise InputValueError(f"{n} frames of {w}x{h} need {n * w * h / 2**30:.1f} GiB; at most "
                              f"{MAX_STIMULUS_BYTES / 2**30:.0f} GiB")
    cam = _Camera(w, h, hfov, fps, camera, speed, height, n)
    turn = abs(speed) * (n - 1) / fps
    if camera == "pan" and turn > MAX_PAN_DEG:
        raise InputValueError(f"camera_speed {speed:g} deg/s pans the camera {turn:.0f} deg over {n} frames; "
                              f"at most {MAX_PAN_DEG:.0f}")
    if camera == "tilt":
        half_v = math.degrees(math.atan((h / 2.0) / cam.f))
        if turn + half_v > MAX_ELEVATION_DEG:
            raise InputValueError(f"camera_speed {speed:g} deg/s tilts the camera {turn:.0f} deg over {n} frames; "
                                  f"at most {MAX_ELEVATION_DEG - half_v:.0f} with this view")
    geos = [_Geometry(o, cam) for o in objects]
    for i, g in enumerate(geos):
        g.check_kind(i)
        if g.obj.onset >= n:
            raise InputValueError(f"objects[{i}].onset {g.obj.onset} is outside the video (0..{n - 1})")

    level = plain_level([o.appearance for o in objects])
    bg = _Background(background, cam, level, seed)
    textures = [_mipmap(procedural_background(OBJECT_TEXTURE_PX, OBJECT_TEXTURE_PX,
                                              o.seed if o.seed is not None else _seed(seed, 3, i)))
                if o.appearance == "textured" else None for i, o in enumerate(objects)]
    levels = [0.0 if o.appearance == "dark" else 255.0 for o in objects]
    visible = [np.zeros(len(g.frames), bool) for g in geos]
    video = np.empty((n, h, w), np.uint8)
    rng = np.random.default_rng(_seed(seed, 4))
    import cv2

    for k in range(n):
        img = bg.frame(k)
        alive = [(g.P[k - g.obj.onset, 2], i) for i, g in enumerate(geos)
                 if k >= g.obj.onset and g.drawn[k - g.obj.onset]]
        for _, i in sorted(alive, reverse=True):          # far to near
            j = k - geos[i].obj.onset
            visible[i][j] = _draw(img, geos[i], j, ss, levels[i], textures[i])
        if blur > 0:
            img = cv2.GaussianBlur(img, (0, 0), blur)
        if noise > 0:
            img = img + rng.normal(0.0, noise, img.shape).astype(np.float32)
        np.rint(np.clip(img, 0, 255), out=img)
        video[k] = img
    truths = []
    for i, (g, vis) in enumerate(zip(geos, visible)):
        if not vis.any():
            warnings.warn(f"objects[{i}] ({g.obj.kind}) is never in view in the {w}x{h} frames", stacklevel=2)
        truths.append(g.truth(i + 1, vis, fps))
    return ApproachStimulus(video, fps, tuple(truths), name, camera=cam.to_dict(), background=background)


def approach_scene(*, kind: str = "collision", n_objects: int | None = None, appearance: str = "dark",
                   shape: str = "disc", background: str = "plain", camera: str = "static",
                   camera_speed: float | None = None, camera_height_m: float = 1.0, ttc_s: float = 2.0,
                   speed_mps: float = 5.0, width_m: float = DEFAULT_WIDTH_M, miss_widths: float | None = None,
                   size: tuple[int, int] = (320, 240), fps: float = 30.0, hfov_deg: float = 60.0,
                   duration_s: float | None = None, noise_std: float = 0.0, blur_px: float = 0.0,
                   supersample: int = 4, seed: int = 0) -> ApproachStimulus:
    """A ready-made :func:`approach` scene (the ``"approach"`` generator of ``mlplc2 stimulus``).

    One object at the principal point, or ``n_objects`` at seeded random
    positions in the middle 60 % of the image, all with the same onset (frame
    0), ``ttc_s``, ``speed_mps`` and ``width_m``.

    Parameters
    ----------
    kind : str
        One of ``"collision"``, ``"pass"``, ``"recede"``, ``"translate"``,
        ``"static"``, or ``"mixed"``: kinds in the order collision, pass,
        translate, recede, static, repeated.
    n_objects : int or None
        Number of objects; None: 1, or 3 for ``"mixed"``.
    appearance : str
        ``"dark"``, ``"bright"`` or ``"textured"``.
    shape : str
        ``"disc"`` or ``"square"``.
    background : str
        ``"plain"``, ``"texture"`` or ``"ground"`` (see :func:`approach`).
    camera : str
        ``"static"``, ``"pan"``, ``"tilt"`` or ``"forward"``.
    camera_speed : float or None
        Pan/tilt deg/s or forward m/s; None: :data:`DEFAULT_CAMERA_SPEED`.
    camera_height_m : float
        Camera height above the ground plane (m).
    ttc_s : float
        Time to contact at the onset of collisions and passes (s); the other
        kinds start at the same depth, ``speed_mps * ttc_s``.
    speed_mps : float
        Closing speed of collisions and passes, receding speed, translation
        speed (m/s, relative to the camera; translations at a fifth of it).
    width_m : float
        Physical width of every object (m).
    miss_widths : float or None
        Miss of collisions (<= 0.25) and passes (>= 1) in widths; None: 0 for
        collisions, 3 for passes. A pass slides away from the image centre
        (to the right from the centre itself).
    size : tuple of int
        ``(W, H)`` in pixels.
    fps : float
        Frame rate.
    hfov_deg : float
        Horizontal field of view (degrees).
    duration_s : float or None
        Length (s); None: ``ttc_s`` plus one frame.
    noise_std : float
        Sensor noise (grey levels).
    blur_px : float
        Optics blur sigma (px).
    supersample : int
        Sub-pixel samples per pixel side.
    seed : int
        Seed of the positions, textures and noise.

    Returns
    -------
    ApproachStimulus
    """
    kind = check_choice(kind, "kind", APPROACH_KINDS + ("mixed",))
    fps = check_fps(fps)
    count = (3 if kind == "mixed" else 1) if n_objects is None else check_int(n_objects, "n_objects", minimum=1)
    camera = check_choice(camera, "camera", CAMERA_MOTIONS)
    cam_speed = DEFAULT_CAMERA_SPEED[camera] if camera_speed is None else check_real(camera_speed, "camera_speed")
    ego = cam_speed if camera == "forward" else 0.0
    w, h = check_size(size)
    ttc = check_real(ttc_s, "ttc_s", positive=True)
    speed = check_real(speed_mps, "speed_mps", positive=True)
    seed = check_int(seed, "seed")
    rng = np.random.default_rng(_seed(seed, 5))
    order = ("collision", "pass", "translate", "recede", "static")
    objs = []
    for i in range(count):
        k = order[i % len(order)] if kind == "mixed" else kind
        if count == 1:
            at = ((w - 1) / 2.0, (h - 1) / 2.0)
        else:
            at = (float(rng.uniform(0.2, 0.8) * (w - 1)), float(rng.uniform(0.2, 0.8) * (h - 1)))
        common = dict(at=at, width_m=width_m, shape=shape, appearance=appearance, size=(w, h),
                      hfov_deg=hfov_deg, ego_speed_mps=ego)
        if k == "collision":
            objs.append(ApproachObject.collision(ttc, speed_mps=speed,
                                                 miss_widths=0.0 if miss_widths is None else miss_widths,
                                                 **common))
        elif k == "pass":
            dx, dy = at[0] - (w - 1) / 2.0, at[1] - (h - 1) / 2.0
            side = math.degrees(math.atan2(dy, dx)) if (dx or dy) else "right"
            objs.append(ApproachObject.pass_by(ttc, speed_mps=speed, side=side,
                                               miss_widths=3.0 if miss_widths is None else miss_widths, **common))
        elif k == "recede":
            objs.append(ApproachObject.receding(distance_m=speed * ttc, speed_mps=speed, **common))
        elif k == "translate":
            objs.append(ApproachObject.translating(distance_m=speed * ttc, speed_mps=speed / 5.0,
                                                   direction_deg=float(rng.uniform(0, 360)), **common))
        else:
            objs.append(ApproachObject.static(distance_m=speed * ttc, **common))
    frames = int(math.ceil(ttc * fps)) + 1 if duration_s is None else None
    return approach(objs, size=(w, h), fps=fps, hfov_deg=hfov_deg, frames=frames, duration_s=duration_s,
                    background=background, camera=camera, camera_speed=cam_speed,
                    camera_height_m=camera_height_m, noise_std=noise_std, blur_px=blur_px,
                    supersample=supersample, seed=seed, name="approach")


def random_scene(seed: int, *, background: str = "texture", camera: str = "static", appearance: str | None = None,
                 shape: str | None = None, n_objects: int | None = None, kinds: Sequence[str] | None = None,
                 camera_speed: float | None = None,
                 camera_height_m: float = 1.0, size: tuple[int, int] = (320, 240), fps: float = 30.0,
                 hfov_deg: float = 60.0, duration_s: float = 5.0, noise_std: float = 0.0,
                 blur_px: float = 0.0, supersample: int = 4) -> ApproachStimulus:
    """A varied but reproducible scene for benchmarks: the same ``seed`` gives the same scene.

    1-3 objects (``n_objects`` to fix it): the first a collision or a pass
    (even odds), the others collisions, passes (miss 2-6 widths) or
    distractors (translating, receding, static). Onsets in the first third of
    the clip; collisions and passes reach the camera plane between 40 % of the
    remaining time after their onset and 5 frames before the end, at a closing
    speed of 2-8 m/s, 3-12 px wide at their onset; positions in the middle
    60 % of the image; collisions aim within :data:`COLLISION_AIM` widths of
    the camera centre in a random direction, passes towards a random side.

    Parameters
    ----------
    seed : int
        The scene's seed (objects, textures, noise).
    background, camera, camera_height_m, size, fps, hfov_deg, noise_std, blur_px, supersample
        As in :func:`approach`.
    appearance, shape : str or None
        Of every object; None: drawn per object.
    n_objects : int or None
        Number of objects; None: 1-3, drawn (or ``len(kinds)``).
    kinds : sequence of str or None
        The kind of each object, in order (``"collision"``, ``"pass"``, ``"recede"``,
        ``"translate"``, ``"static"``); None: drawn as described above. The other draws do
        not depend on it, so a seed's positions, sizes and timings stay the same.
    camera_speed : float or None
        As in :func:`approach`; None: :data:`DEFAULT_CAMERA_SPEED`.
    duration_s : float
        Length of the clip (s, at least 2 s).

    Returns
    -------
    ApproachStimulus
    """
    seed = check_int(seed, "seed")
    camera = check_choice(camera, "camera", CAMERA_MOTIONS)
    cam_speed = DEFAULT_CAMERA_SPEED[camera] if camera_speed is None else check_real(camera_speed, "camera_speed")
    ego = cam_speed if camera == "forward" else 0.0
    w, h = check_size(size)
    fps = check_fps(fps)
    dur = check_real(duration_s, "duration_s", minimum=2.0)
    n = int(round(dur * fps))
    rng = np.random.default_rng(_seed(seed, 6))
    count = int(rng.integers(1, 4)) if n_objects is None else check_int(n_objects, "n_objects", minimum=1)
    if kinds is not None:
        kinds = [check_choice(k, "kinds", APPROACH_KINDS) for k in kinds]
        if not kinds or (n_objects is not None and len(kinds) != count):
            raise InputValueError(f"kinds must name one kind per object (n_objects={count}), got {kinds!r}")
        count = len(kinds)
    f = focal_length(w, check_hfov(hfov_deg, required=True))
    objs = []
    for i in range(count):
        if i == 0:
            kind = str(rng.choice(["collision", "pass"]))
        else:
            kind = str(rng.choice(APPROACH_KINDS, p=[0.25, 0.25, 0.15, 0.2, 0.15]))
        if kinds is not None:
            kind = kinds[i]
        common = dict(
            at=(float(rng.uniform(0.2, 0.8) * (w - 1)), float(rng.uniform(0.2, 0.8) * (h - 1))),
            shape=str(rng.choice(APPROACH_SHAPES)) if shape is None else shape,
            appearance=str(rng.choice(APPROACH_APPEARANCES)) if appearance is None else appearance,
            onset=int(rng.integers(0, max(1, n // 3))), size=(w, h), hfov_deg=hfov_deg, ego_speed_mps=ego)
        if kind in ("collision", "pass"):
            onset = common["onset"]
            first = onset + 0.4 * (n - onset)
            contact = float(rng.uniform(first, n - 5))
            extra = dict(ttc_s=(contact - onset) / fps, speed_mps=float(rng.uniform(2.0, 8.0)),
                         width_px=float(rng.uniform(3.0, 12.0)), side=float(rng.uniform(0.0, 360.0)))
            if kind == "collision":
                objs.append(ApproachObject.collision(miss_widths=float(rng.uniform(0.0, COLLISION_AIM)),
                                                     **extra, **common))
            else:
                objs.append(ApproachObject.pass_by(miss_widths=float(rng.uniform(*PASS_MISS_WIDTHS)),
                                                   **extra, **common))
        else:
            z = float(rng.uniform(3.0, 15.0))
            extra = dict(distance_m=z, width_px=float(rng.uniform(8.0, 30.0)))
            if kind == "translate":
                px_per_frame = float(rng.uniform(1.0, 4.0))
                objs.append(ApproachObject.translating(speed_mps=px_per_frame * fps * z / f,
                                                       direction_deg=float(rng.uniform(0.0, 360.0)),
                                                       **extra, **common))
            elif kind == "recede":
                objs.append(ApproachObject.receding(speed_mps=float(rng.uniform(1.0, 4.0)), **extra, **common))
            else:
                objs.append(ApproachObject.static(**extra, **common))
    return approach(objs, size=(w, h), fps=fps, hfov_deg=hfov_deg, frames=n, background=background,
                    camera=camera, camera_speed=cam_speed, camera_height_m=camera_height_m,
                    noise_std=noise_std, blur_px=blur_px, supersample=supersample, seed=seed,
                    name=f"random_scene_{seed}")
