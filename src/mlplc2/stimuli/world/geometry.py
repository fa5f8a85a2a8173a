"""Where the 3-D approaches' objects are: positions, sizes and paths in 3-D and in the image.

* An object's ``start`` and ``velocity`` are given along the axes of the
  camera at the object's onset frame, ``start`` relative to the camera's
  position then (:func:`place` puts it on the ray through an image point). The
  velocity is the object's own (in the world); a forward-moving camera adds
  ``-speed`` to its relative Z velocity. Objects are fronto-parallel to the
  camera at their onset (their plane keeps its orientation in the world, so a
  panning camera sees it in perspective): the plane maps to the image by the
  homography ``H = K [e1 e2 P]`` (object axes ``e1``, ``e2`` and centre ``P`` in
  the camera frame).
* Contact and miss are properties of the motion relative to the camera
  centre, which rotation does not change: in the object's frame (the camera
  axes at its onset, moving with the camera) the relative position is
  ``D(t) = start + v_rel (t - t_onset)``; contact is when ``D_z`` reaches 0
  (``contact_frame``, fractional), the miss is ``|D_xy| / width`` then, and
  the true time to contact at frame ``k`` is ``(contact_frame - k) / fps``.
* Kinds (:meth:`ObjectGeometry.check_kind`): ``collision``: relative Z velocity
  < 0 and miss < :data:`COLLISION_MISS`; ``pass``: approaching with a miss of at
  least :data:`PASS_MIN_MISS`; ``recede``: relative Z velocity > 0;
  ``translate``: relative Z velocity 0, lateral velocity not 0; ``static``: no
  relative motion.
* A :class:`~mlplc2.stimuli.world.camera.CameraPath` camera (``"path"``): ``start`` and
  ``velocity`` are along the *vehicle's* axes at the onset (the camera's without its pitch,
  roll and shake) and ``start`` relative to the vehicle's position then; the velocity is the
  object's own, constant in the world. ``D(t)`` is then the object's centre relative to the
  vehicle's position in the vehicle's axes at ``t`` (no longer linear when the path turns):
  contact is where ``D_z`` first reaches 0 (found on a grid of 1/64 frame, linear between),
  the miss ``|D_xy| / width`` then, and the kinds are checked with ``dD/dt`` at the onset.
  The camera's pitch, roll and shake (rotations about its centre, and a shake of its
  centre by at most a few cm) are left out of contact and miss; the track (the projection)
  has them. The object stays fronto-parallel to the vehicle's axes at its onset.
* The extent of the projected outline is exact: the projected corners of a
  square, the dual conic of a disc. The truth (:meth:`ObjectGeometry.truth`) is
  one :class:`mlplc2.evaluation.truth.ObjectTruth` per object with a per-frame
  ``track`` of :class:`mlplc2.evaluation.truth.TrackPoint`.
"""

from __future__ import annotations

import math

import numpy as np

from ..._validation import InputValueError, check_real, check_reals
from ...camera import check_hfov, focal_length
from ...evaluation.truth import ObjectTruth, TrackPoint
from .._common import check_size
from .camera import Camera

__all__ = ["ObjectGeometry", "ObjectTrack", "place", "side_angle", "COLLISION_MISS", "PASS_MIN_MISS", "FAR_M",
           "DEFAULT_WIDTH_M", "MAX_TURN_DEG",
           "ENTRY_LEAD_S", "turned"]

#: A collision's centre reaches the camera plane closer than this to the camera centre (widths).
COLLISION_MISS = 0.5
#: A pass misses the camera centre by at least this (widths): a disc's edge (0.5) and a square's
#: corner (0.71) stay clear of the camera.
PASS_MIN_MISS = 1.0
#: Objects whose centre is farther than this (m) are not drawn.
FAR_M = 1000.0
#: Default physical width of an object (m).
DEFAULT_WIDTH_M = 0.5
#: Largest turn (deg) of a turning camera between an object's onset and its anchor (:func:`turned`).
MAX_TURN_DEG = 60.0
#: A turning camera's object starts this long (s) before it first comes into view (:func:`turned`).
ENTRY_LEAD_S = 0.5


_SIDES = {"right": 0.0, "below": 90.0, "left": 180.0, "above": 270.0}


def side_angle(side) -> float:
    """The image-plane angle (rad) of ``side``: "right", "below", "left", "above" or
    degrees (0 right, 90 below, 180 left, 270 above)."""
    if isinstance(side, str):
        if side not in _SIDES:
            raise InputValueError(f"side must be one of {', '.join(_SIDES)} or an angle in degrees, got {side!r}")
        return math.radians(_SIDES[side])
    return math.radians(check_real(side, "side"))


def place(at, distance, width_m, width_px, size, hfov_deg):
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


#: The older name of the 3-D truth: one :class:`mlplc2.evaluation.truth.ObjectTruth` per object, with its
#: ``kind``, ``approach`` (the frames in view while approaching), ``contact_frame``, ``miss``,
#: a ``track`` of :class:`mlplc2.evaluation.truth.TrackPoint` (one row per frame in which the object is at
#: least partly in view: the projection of its centre, the extent of its outline, None while
#: part of it is behind the camera, the true time to contact and the predicted miss) and the
#: object as given in ``extra`` (``shape``, ``width_m``, ``onset``, ``start_m``,
#: ``velocity_mps``); its ``polarity`` is the object's appearance. docs/stimuli.md "Ground truth".
ObjectTrack = ObjectTruth


class ObjectGeometry:
    """Per-frame camera-frame pose, homography and image extent of one object (an
    :class:`~mlplc2.stimuli.world.ApproachObject`), its contact and miss, and its truth."""

    def __init__(self, obj, cam: Camera):
        self.obj = obj
        self.r = obj.width_m / 2.0
        k0 = obj.onset
        self.frames = np.arange(k0, cam.n)
        tau = (self.frames - k0) / cam.fps
        if cam.motion == "path":
            rel, M, self.P = self._path_pose(cam, tau)
        else:
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
        if cam.motion == "path":
            return                                          # contact and miss: _path_pose
        self.contact = None
        self.miss = None
        if self.v_rel[2] < 0:
            tc = -obj.start[2] / self.v_rel[2]
            self.contact = float(obj.onset + tc * cam.fps)
            at = np.array(obj.start) + tc * self.v_rel
            self.miss = float(math.hypot(at[0], at[1]) / obj.width_m)

    def _path_pose(self, cam: Camera, tau: np.ndarray):
        """A :class:`~mlplc2.stimuli.world.camera.CameraPath` camera: the object's position relative
        to the vehicle (its axes), its rotation and centre in the camera frame per frame; sets
        ``v_rel`` (d/dt of the first at the onset), ``contact`` and ``miss`` (where the first's Z
        first reaches 0, to 1/64 frame, linear between samples)."""
        obj, path, fps = self.obj, cam.path, cam.fps
        t0 = obj.onset / fps
        c0, v0 = path.vehicle(t0)
        start, vel = np.array(obj.start), np.array(obj.velocity)

        def world(t):                                        # the object's centre in the world
            return c0[None, :] + (start[None, :] + (t - t0)[:, None] * vel[None, :]) @ v0.T

        def relative(t):                                     # ... in the vehicle's axes at t
            c, v = path.vehicle(t)
            return np.einsum("kji,kj->ki", v, world(t) - c)

        t = t0 + tau
        rel = relative(t)
        pos, R = cam.position[self.frames], cam.R[self.frames]
        P = np.einsum("kji,kj->ki", R, world(t) - pos)
        M = np.einsum("kji,jl->kil", R, v0)
        d = relative(np.array([t0, t0 + 1e-4]))
        self.v_rel = (d[1] - d[0]) / 1e-4
        self.contact = self.miss = None
        ts = t0 + np.arange(0.0, cam.n / fps + 60.0, 1.0 / (64 * fps))
        z = relative(ts)
        hit = np.flatnonzero((z[:-1, 2] > 0) & (z[1:, 2] <= 0))
        if self.v_rel[2] < 0 and hit.size:
            j = hit[0]
            a = z[j, 2] / (z[j, 2] - z[j + 1, 2])
            at = z[j] + a * (z[j + 1] - z[j])
            self.contact = float((ts[j] + a * (ts[j + 1] - ts[j])) * fps)
            self.miss = float(math.hypot(at[0], at[1]) / obj.width_m)
        return rel, M, P

    def check_kind(self, i: int) -> None:
        """Raise unless the declared kind matches the relative motion."""
        kind, vz = self.obj.kind, self.v_rel[2]
        speed = float(np.linalg.norm(self.v_rel))
        tol = 1e-9 * max(1.0, speed)
        where = f"objects[{i}] (kind {kind!r})"
        if kind in ("collision", "pass"):
            if not vz < -tol:
                raise InputValueError(f"{where} does not approach the camera (relative vz = {vz:g} m/s)")
            if self.miss is None:
                raise InputValueError(f"{where} never reaches the camera plane")
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


def turned(obj, cam: Camera, anchor: float, limit_deg: float = MAX_TURN_DEG, lead_s: float = ENTRY_LEAD_S):
    """``obj`` (an :class:`~mlplc2.stimuli.world.ApproachObject` whose ``start`` and ``velocity`` are
    given along the axes of the camera at frame ``anchor`` instead of at its onset) as an object of
    ``cam``'s turning (``"pan"`` or ``"tilt"``) scene: the same path in the world, seen at the
    anchor where a still camera would see it. ``start`` and ``velocity`` are rotated by
    ``R(onset)^T R(anchor)``. The onset is put off, on the same path, to ``lead_s`` before the
    object first comes into view (its bounding box in the image), and to at most ``limit_deg`` of
    turn before the anchor (so it never starts behind the camera): its plane, fronto-parallel to the
    camera at its onset, then faces the camera nearly as it does when it comes into view. Any
    other camera: ``obj`` unchanged."""
    if cam.motion not in ("pan", "tilt") or cam.speed == 0:
        return obj
    rate = math.radians(cam.speed) / cam.fps                     # rad per frame
    onset = obj.onset
    if abs(rate * (anchor - onset)) > math.radians(limit_deg):
        onset = int(math.ceil(anchor - math.radians(limit_deg) / abs(rate)))
    g = ObjectGeometry(_rotated(obj, cam, anchor, onset), cam)
    x0, x1, y0, y1 = g.box.T
    seen = g.drawn & (~g.whole | ((x1 >= -0.5) & (x0 <= cam.w - 0.5) & (y1 >= -0.5) & (y0 <= cam.h - 0.5)))
    if seen.any():
        onset = max(onset, int(g.frames[np.argmax(seen)]) - int(round(lead_s * cam.fps)))
    return _rotated(obj, cam, anchor, onset)


def _rotated(obj, cam: Camera, anchor: float, onset: int):
    """:func:`turned`'s object with its onset at ``onset`` (>= ``obj.onset``), on the same path."""
    from dataclasses import replace

    start = np.array(obj.start) + (onset - obj.onset) / cam.fps * np.array(obj.velocity)
    M = cam.rotation(math.radians(cam.speed) / cam.fps * (anchor - onset))   # R(onset)^T R(anchor)
    return replace(obj, start=tuple(float(v) for v in M @ start),
                   velocity=tuple(float(v) for v in M @ np.array(obj.velocity)), onset=onset)
