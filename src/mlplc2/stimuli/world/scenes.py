"""The public generators of 3-D approaches: the objects (:class:`ApproachObject`), the renderer
(:func:`approach`) and two ready-made scenes (:func:`approach_scene`, :func:`random_scene`).

Flat objects (discs and squares, dark, bright or carrying their own texture)
of a physical width move at constant 3-D velocity in front of a pinhole camera
(:mod:`~mlplc2.stimuli.world.camera`) that may stand still, pan, tilt or move
forward over a textured ground plane. Where an object appears and how large
follow from the projection (:mod:`~mlplc2.stimuli.world.geometry`), so a
constant-speed approach grows as 1 / (time to contact): slowly at first, very
fast at the end. An object's ``start`` and ``velocity`` are given along the
axes of the camera at its onset frame, ``start`` relative to the camera's
position then: an object made by :meth:`ApproachObject.collision` with
``at=(x, y)`` is seen at ``(x, y)`` at its onset, whatever the camera did
before.

Kinds (checked against the motion by :func:`approach`)
------------------------------------------------------
``collision``: relative Z velocity < 0 and miss < ``COLLISION_MISS``
(0.5 widths: the object's centre reaches the camera plane within half a width
of the camera centre); ``pass``: approaching with a miss of at least
``PASS_MIN_MISS`` (1 width, so neither a disc nor a square's corner
touches the camera): it grows, slides outwards and leaves the image before
contact; ``recede``: relative Z velocity > 0; ``translate``: relative Z
velocity 0, lateral velocity not 0; ``static``: no relative motion.

:func:`approach` runs in named steps: check the arguments, fix the length
(:func:`_frame_count`), place the camera and the objects (:func:`_geometries`),
draw the frames (:func:`mlplc2.stimuli.world.render.render`) and collect the
truth (:func:`_truths`). The scenes draw their objects from a seeded generator
of their own (:func:`~mlplc2.stimuli.world.render.sub_seed` keys 5 and 6) in a
fixed order, so a seed always gives the same scene.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..._validation import InputTypeError, InputValueError, check_fps, check_int, check_real, check_reals
from ...camera import check_hfov, focal_length
from .._common import MAX_STIMULUS_BYTES, ApproachStimulus, check_choice, check_size
from .camera import CAMERA_MOTIONS, DEFAULT_CAMERA_SPEED, Camera, CameraPath
from .geometry import DEFAULT_WIDTH_M, PASS_MIN_MISS, ObjectGeometry, place, side_angle, turned
from .render import APPROACH_BACKGROUNDS, render, sub_seed

__all__ = ["ApproachObject", "approach", "approach_scene", "random_scene", "APPROACH_KINDS", "APPROACH_SHAPES",
           "APPROACH_APPEARANCES", "COLLISION_AIM", "PASS_MISS_WIDTHS"]

#: Object kinds (motion relative to the camera).
APPROACH_KINDS: tuple[str, ...] = ("collision", "pass", "recede", "translate", "static")
#: Object outlines.
APPROACH_SHAPES: tuple[str, ...] = ("disc", "square")
#: Object appearances: grey level 0, 255, or their own procedural texture.
APPROACH_APPEARANCES: tuple[str, ...] = ("dark", "bright", "textured")
#: Largest aim offset (widths) :meth:`ApproachObject.collision` accepts.
COLLISION_AIM = 0.25
#: Lateral miss (widths) of the passes of :func:`random_scene` and the issue's benchmark.
PASS_MISS_WIDTHS = (2.0, 6.0)


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
        ray, z, width = place(at, distance_m, width_m, width_px, size, hfov_deg)
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
        ray, z, width = place(at, distance_m, width_m, width_px, size, hfov_deg)
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
        ray, z, width = place(at, distance_m, width_m, width_px, size, hfov_deg)
        return cls._make("static", z, ray, width, (0.0, 0.0, 0.0), shape, appearance, onset, seed,
                         ego_speed_mps)

    @classmethod
    def _approaching(cls, kind, ttc_s, at, width_m, width_px, speed_mps, miss, side, shape, appearance,
                     onset, seed, size, hfov_deg, ego_speed_mps) -> ApproachObject:
        ttc = check_real(ttc_s, "ttc_s", positive=True)
        speed = check_real(speed_mps, "speed_mps", positive=True)
        ray, z, width = place(at, speed * ttc, width_m, width_px, size, hfov_deg)
        a = side_angle(side)
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


# ---------------------------------------------------------------------------
# The renderer
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
    camera : {"static", "pan", "tilt", "forward"} or CameraPath
        Camera motion (:mod:`mlplc2.stimuli.world.camera`); a
        :class:`~mlplc2.stimuli.world.camera.CameraPath` combines forward motion, turns, pitch
        bounce, roll and shake (motion ``"path"``; ``camera_speed`` stays 0).
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
    objects = _object_list(objects)
    w, h = check_size(size)
    fps = check_fps(fps)
    focal_length(w, check_hfov(hfov_deg, required=True))                  # checks hfov_deg
    hfov = float(hfov_deg)
    background = check_choice(background, "background", APPROACH_BACKGROUNDS)
    path = camera if isinstance(camera, CameraPath) else None
    camera, speed, height = _check_camera("path" if path else camera, camera_speed, camera_height_m, path)
    noise = check_real(noise_std, "noise_std", minimum=0.0)
    blur = check_real(blur_px, "blur_px", minimum=0.0)
    ss = check_int(supersample, "supersample", minimum=1, maximum=16)
    seed = check_int(seed, "seed")
    view = (w, h, hfov, fps, camera, speed, height)                        # Camera(*view, n)
    n = _frame_count(frames, duration_s, fps, objects, view, path)
    if n * w * h > MAX_STIMULUS_BYTES:
        raise InputValueError(f"{n} frames of {w}x{h} need {n * w * h / 2**30:.1f} GiB; at most "
                              f"{MAX_STIMULUS_BYTES / 2**30:.0f} GiB")
    cam = Camera(*view, n, path=path)
    cam.check_turn()
    geos = _geometries(objects, cam)
    video, visible = render(geos, cam, background, seed, ss, blur, noise)
    return ApproachStimulus(video, fps, _truths(geos, visible, fps, (w, h)), name, camera=cam.to_dict(),
                            background=background)


def _object_list(objects) -> list[ApproachObject]:
    """``objects`` (one :class:`ApproachObject` or a sequence of them) as a list."""
    if isinstance(objects, ApproachObject):
        objects = [objects]
    if isinstance(objects, (str, bytes)) or not hasattr(objects, "__iter__"):
        raise InputTypeError(f"objects must be a sequence of ApproachObject, got {type(objects).__name__}")
    objects = list(objects)
    for i, o in enumerate(objects):
        if not isinstance(o, ApproachObject):
            raise InputTypeError(f"objects[{i}] must be an ApproachObject, got {type(o).__name__}")
    return objects


def _check_camera(camera, camera_speed, camera_height_m, path=None) -> tuple[str, float, float]:
    """The camera's motion, speed and height above the ground, checked."""
    if path is not None:
        if camera_speed != 0:
            raise InputValueError("camera_speed must be 0 with a CameraPath (its speed_mps is the speed)")
        return "path", path.speed_mps, check_real(camera_height_m, "camera_height_m", positive=True)
    camera = check_choice(camera, "camera", CAMERA_MOTIONS)
    speed = check_real(camera_speed, "camera_speed")
    if camera == "static" and speed != 0:
        raise InputValueError(f"camera_speed must be 0 for a static camera, got {camera_speed!r}")
    height = check_real(camera_height_m, "camera_height_m", positive=True)
    return camera, speed, height


def _frame_count(frames, duration_s, fps: float, objects: list[ApproachObject], view: tuple, path=None) -> int:
    """The number of frames: ``frames``, or ``duration_s`` at ``fps``, or else until the last
    contact of an approaching object (``ceil(contact_frame) + 1``), or 150 without one."""
    if frames is not None and duration_s is not None:
        raise InputValueError("give frames or duration_s, not both")
    if frames is not None:
        return check_int(frames, "frames", minimum=1)
    if duration_s is not None:
        n = int(round(check_real(duration_s, "duration_s", positive=True) * fps))
        if n < 1:
            raise InputValueError(f"duration_s {duration_s!r} is shorter than one frame at {fps:g} fps")
        return n
    probe = Camera(*view, 1, path=path)
    contacts = [g.contact for g in (ObjectGeometry(o, probe) for o in objects) if g.contact is not None]
    return int(math.ceil(max(contacts))) + 1 if contacts else 150


def _geometries(objects: list[ApproachObject], cam: Camera) -> list[ObjectGeometry]:
    """Each object's path seen by ``cam``, its kind checked against its motion."""
    geos = [ObjectGeometry(o, cam) for o in objects]
    for i, g in enumerate(geos):
        g.check_kind(i)
        if g.obj.onset >= cam.n:
            raise InputValueError(f"objects[{i}].onset {g.obj.onset} is outside the video (0..{cam.n - 1})")
    return geos


def _truths(geos: list[ObjectGeometry], visible: list[np.ndarray], fps: float, size: tuple[int, int]) -> tuple:
    """The truth of every object (ids from 1); warns (for the caller of :func:`approach`) about an
    object never in view in the ``size`` frames."""
    w, h = size
    truths = []
    for i, (g, vis) in enumerate(zip(geos, visible)):
        if not vis.any():
            warnings.warn(f"objects[{i}] ({g.obj.kind}) is never in view in the {w}x{h} frames", stacklevel=3)
        truths.append(g.truth(i + 1, vis, fps))
    return tuple(truths)


# ---------------------------------------------------------------------------
# Ready-made scenes
# ---------------------------------------------------------------------------

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
    camera, cam_speed, ego = _preset_camera(camera, camera_speed)
    w, h = check_size(size)
    ttc = check_real(ttc_s, "ttc_s", positive=True)
    speed = check_real(speed_mps, "speed_mps", positive=True)
    seed = check_int(seed, "seed")
    rng = np.random.default_rng(sub_seed(seed, 5))
    order = ("collision", "pass", "translate", "recede", "static")
    objs = []
    for i in range(count):
        k = order[i % len(order)] if kind == "mixed" else kind
        if count == 1:
            at = ((w - 1) / 2.0, (h - 1) / 2.0)
        else:
            at = (float(rng.uniform(0.2, 0.8) * (w - 1)), float(rng.uniform(0.2, 0.8) * (h - 1)))
        objs.append(_preset_object(k, ttc, speed, miss_widths, rng, at=at, width_m=width_m, shape=shape,
                                   appearance=appearance, size=(w, h), hfov_deg=hfov_deg, ego_speed_mps=ego))
    frames = int(math.ceil(ttc * fps)) + 1 if duration_s is None else None
    return approach(objs, size=(w, h), fps=fps, hfov_deg=hfov_deg, frames=frames, duration_s=duration_s,
                    background=background, camera=camera, camera_speed=cam_speed,
                    camera_height_m=camera_height_m, noise_std=noise_std, blur_px=blur_px,
                    supersample=supersample, seed=seed, name="approach")


def _preset_camera(camera, camera_speed) -> tuple[str, float, float]:
    """The camera's motion, its speed (None: :data:`DEFAULT_CAMERA_SPEED`) and the forward speed
    the objects' velocities must make up for (0 unless ``"forward"``)."""
    camera = check_choice(camera, "camera", CAMERA_MOTIONS)
    cam_speed = DEFAULT_CAMERA_SPEED[camera] if camera_speed is None else check_real(camera_speed, "camera_speed")
    ego = cam_speed if camera == "forward" else 0.0
    return camera, cam_speed, ego


def _preset_object(kind: str, ttc: float, speed: float, miss_widths, rng, **common) -> ApproachObject:
    """One object of :func:`approach_scene` at ``common["at"]`` (a translation draws its direction
    from ``rng``)."""
    at, (w, h) = common["at"], common["size"]
    if kind == "collision":
        return ApproachObject.collision(ttc, speed_mps=speed, miss_widths=0.0 if miss_widths is None else miss_widths,
                                        **common)
    if kind == "pass":
        dx, dy = at[0] - (w - 1) / 2.0, at[1] - (h - 1) / 2.0
        side = math.degrees(math.atan2(dy, dx)) if (dx or dy) else "right"
        return ApproachObject.pass_by(ttc, speed_mps=speed, side=side,
                                      miss_widths=3.0 if miss_widths is None else miss_widths, **common)
    if kind == "recede":
        return ApproachObject.receding(distance_m=speed * ttc, speed_mps=speed, **common)
    if kind == "translate":
        return ApproachObject.translating(distance_m=speed * ttc, speed_mps=speed / 5.0,
                                          direction_deg=float(rng.uniform(0, 360)), **common)
    return ApproachObject.static(distance_m=speed * ttc, **common)


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
    With a turning camera (pan, tilt) the drawn position of a collision or
    pass holds at its anchor (its contact; for a pass halfway between its onset
    and when a still camera would lose it) in the camera's view then, not at its
    onset (:func:`~mlplc2.stimuli.world.geometry.turned`), so the camera does not
    turn away from it; one still out of view at its onset starts later on the same
    path. The draws are the same.

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
    camera, cam_speed, ego = _preset_camera(camera, camera_speed)
    w, h = check_size(size)
    fps = check_fps(fps)
    dur = check_real(duration_s, "duration_s", minimum=2.0)
    n = int(round(dur * fps))
    rng = np.random.default_rng(sub_seed(seed, 6))
    count, kinds = _random_count(rng, n_objects, kinds)
    check_hfov(hfov_deg, required=True)
    cam = Camera(w, h, float(hfov_deg), fps, camera, cam_speed, 1.0, n)
    objs = [_random_object(rng, i, None if kinds is None else kinds[i], cam, shape, appearance, ego)
            for i in range(count)]
    return approach(objs, size=(w, h), fps=fps, hfov_deg=hfov_deg, frames=n, background=background,
                    camera=camera, camera_speed=cam_speed, camera_height_m=camera_height_m,
                    noise_std=noise_std, blur_px=blur_px, supersample=supersample, seed=seed,
                    name=f"random_scene_{seed}")


def _random_count(rng, n_objects, kinds) -> tuple[int, list[str] | None]:
    """The number of objects of :func:`random_scene` (drawn 1-3 unless given) and their kinds, checked."""
    count = int(rng.integers(1, 4)) if n_objects is None else check_int(n_objects, "n_objects", minimum=1)
    if kinds is not None:
        kinds = [check_choice(k, "kinds", APPROACH_KINDS) for k in kinds]
        if not kinds or (n_objects is not None and len(kinds) != count):
            raise InputValueError(f"kinds must name one kind per object (n_objects={count}), got {kinds!r}")
        count = len(kinds)
    return count, kinds


def _random_object(rng, i: int, kind: str | None, cam: Camera, shape, appearance, ego: float) -> ApproachObject:
    """Object ``i`` of :func:`random_scene` seen by ``cam``: its kind (drawn even when ``kind`` is given,
    so the other draws stay the same), position, shape, appearance and onset, then its motion."""
    w, h, n, fps, f, hfov_deg = cam.w, cam.h, cam.n, cam.fps, cam.f, cam.hfov
    drawn = str(rng.choice(["collision", "pass"])) if i == 0 else \
        str(rng.choice(APPROACH_KINDS, p=[0.25, 0.25, 0.15, 0.2, 0.15]))
    kind = drawn if kind is None else kind
    common = dict(
        at=(float(rng.uniform(0.2, 0.8) * (w - 1)), float(rng.uniform(0.2, 0.8) * (h - 1))),
        shape=str(rng.choice(APPROACH_SHAPES)) if shape is None else shape,
        appearance=str(rng.choice(APPROACH_APPEARANCES)) if appearance is None else appearance,
        onset=int(rng.integers(0, max(1, n // 3))), size=(w, h), hfov_deg=hfov_deg, ego_speed_mps=ego)
    if kind in ("collision", "pass"):
        return _random_approaching(rng, kind, cam, common)
    return _random_distractor(rng, kind, fps, f, common)


def _random_approaching(rng, kind: str, cam: Camera, common: dict) -> ApproachObject:
    """A collision or pass of :func:`random_scene`: contact between 40 % of the time left after its
    onset and 5 frames before the end, closing at 2-8 m/s, 3-12 px wide at its onset. A turning
    camera (pan, tilt) sees it at ``at`` at its anchor (:func:`_anchor`) instead of its onset."""
    onset, n, fps = common["onset"], cam.n, cam.fps
    first = onset + 0.4 * (n - onset)
    contact = float(rng.uniform(first, n - 5))
    extra = dict(ttc_s=(contact - onset) / fps, speed_mps=float(rng.uniform(2.0, 8.0)),
                 width_px=float(rng.uniform(3.0, 12.0)), side=float(rng.uniform(0.0, 360.0)))
    if kind == "collision":
        obj = ApproachObject.collision(miss_widths=float(rng.uniform(0.0, COLLISION_AIM)), **extra, **common)
    else:
        obj = ApproachObject.pass_by(miss_widths=float(rng.uniform(*PASS_MISS_WIDTHS)), **extra, **common)
    return turned(obj, cam, _anchor(obj, cam, contact))


def _anchor(obj: ApproachObject, cam: Camera, contact: float) -> float:
    """The frame at which a turning camera sees a collision or pass of :func:`random_scene` (given
    along the axes of the camera then) where a still camera would: a collision's contact, so it is in
    view when it hits; a pass's frame halfway between its onset and the last frame in which a still
    camera sees its centre, so it crosses the view as a still camera's pass does."""
    if obj.kind == "collision" or cam.motion not in ("pan", "tilt"):
        return contact
    g = ObjectGeometry(obj, Camera(cam.w, cam.h, cam.hfov, cam.fps, "static", 0.0, 1.0, cam.n))
    inside = g.drawn & (g.x >= 0) & (g.x <= cam.w - 1) & (g.y >= 0) & (g.y <= cam.h - 1)
    last = g.frames[inside][-1] if inside.any() else obj.onset
    return 0.5 * (obj.onset + float(last))


def _random_distractor(rng, kind: str, fps: float, f: float, common: dict) -> ApproachObject:
    """A translating, receding or static object of :func:`random_scene`, 3-15 m away, 8-30 px wide
    (a translation at 1-4 px per frame, a recession at 1-4 m/s)."""
    z = float(rng.uniform(3.0, 15.0))
    extra = dict(distance_m=z, width_px=float(rng.uniform(8.0, 30.0)))
    if kind == "translate":
        px_per_frame = float(rng.uniform(1.0, 4.0))
        return ApproachObject.translating(speed_mps=px_per_frame * fps * z / f,
                                          direction_deg=float(rng.uniform(0.0, 360.0)), **extra, **common)
    if kind == "recede":
        return ApproachObject.receding(speed_mps=float(rng.uniform(1.0, 4.0)), **extra, **common)
    return ApproachObject.static(**extra, **common)
