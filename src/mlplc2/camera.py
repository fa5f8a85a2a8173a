"""The camera: pinhole geometry (focal length, bearing), in one place for the models and the stimuli.

Bearing convention: azimuth positive to the right, elevation positive up,
``azimuth = atan((x - cx) / f)``, ``elevation = atan((cy - y) / f)`` with
``(cx, cy) = ((W - 1) / 2, (H - 1) / 2)`` in pixel-index coordinates (the centre
of pixel column ``i`` is at ``x = i``) and ``f = (W / 2) / tan(hfov / 2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ._validation import check_real

#: A rotation that moves no point of the frame by more than this (px, at the model's working size)
#: is not compensated: a still camera's frames are never resampled (its estimate is ~0.01 px).
STILL_PX = 0.1
#: Least share of the tracked points that must agree with the rotation for it to be compensated.
MIN_ROTATION_CONFIDENCE = 0.5
#: When no heading is measured, a translation alone whose heading lies out of the joint fit's reach (3 focal
#: lengths from the principal point: sideways, e.g. over near ground) that explains this much larger a share
#: of the points than the rotation does is taken instead: no rotation.
TRANSLATION_MARGIN = 0.15
#: When the flow since the previous frame shows too little expansion to tell a heading (a slow translation: the
#: ground of a walk or a slow drive moves ~0.6 px a frame at the reduced size, near the tracking precision), the
#: heading alone is fitted again on the flow from this many frames back, where the same translation moves the
#: points this many times as far; the rotation stays the frame's own. 1 = off (the default: 3 measured in session 14,
#: ground_forward's heading in 0.07-0.09 -> 0.92-0.97 of the frames, but drone_3's collider and a real clip's lead
#: lost to the target layer's rules that a heading enables; docs/history.md, "The heading of a slow translation").
HEADING_FRAMES = 1
#: The least share of the followed points whose expansion must be measured (a radial flow over twice the tracking
#: precision, 0.6 px at the reduced size) for a frame to give a heading ...
MIN_EXPANDING_SHARE = 0.3
#: ... or this share, where their median expansion rate is at least :data:`FAST_EXPANSION` a frame. The far scene
#: (the sky, a backdrop) and the ground nearest the camera, which a wide lens or a fast drive moves too far for the
#: forward-backward check, say nothing about the heading: through a 90-degree lens the drive at 20 m/s had a share
#: of 0.13-0.27 expanding (every point about the principal point, at 0.07-0.16 a frame) and gave a heading in 0-4 %
#: of the frames of three of the five standard drive scenes, so the target layer's rules for a translating camera
#: never applied there (docs/history.md, "The heading through a wide lens", session 40).
FAST_EXPANDING_SHARE = 0.15
#: The expansion rate (1 / frame, the median of the expanding points) above which :data:`FAST_EXPANDING_SHARE` is
#: enough: the static world measured is within about 25 frames of contact. The slow translations of the benchmark
#: (ground_forward's walk, 0.019-0.021 a frame; the drone's flight, 0.011-0.018) keep the larger share: their
#: heading from fewer points was right to 6-9 px, but with it the target layer's rules lost 12 of their colliders over
#: the thirty-nine sets (session 40).
FAST_EXPANSION = 0.04
#: ... and where their rates differ by at least this factor (the 90th percentile over the 10th): the static world
#: lies at many depths and expands at as many rates (a drive's ground and roadside: 2.4-3.5 at the 10th percentile of
#: the frames, 3.0-3.9 at the median), one approaching object at one depth (a still or hand-held camera's collider near
#: its contact: 1.2-2.0; it gave a hand-held camera a heading at its own centre, kept from then on, and a still
#: camera one too; session 40).
FAST_DEPTHS = 2.0

__all__ = ["check_hfov", "focal_length", "bearing", "CameraMotion", "MotionEstimator", "rotation_matrix", "warp",
           "compensation"]


def check_hfov(hfov_deg, *, required: bool = False) -> float | None:
    """Validate a horizontal field of view in degrees, in (0, 180); None (unknown) unless ``required``."""
    if hfov_deg is None and not required:
        return None
    return check_real(hfov_deg, "hfov_deg", positive=True, below=180)


def focal_length(width: int, hfov_deg: float | None) -> float | None:
    """Pinhole focal length in px, ``(W / 2) / tan(hfov / 2)``; None when ``hfov_deg`` is None (unknown)."""
    hfov = check_hfov(hfov_deg)
    if hfov is None:
        return None
    return (width / 2.0) / math.tan(math.radians(hfov) / 2.0)


def bearing(x: float, y: float, shape: tuple[int, int], focal: float | None) -> tuple[float, float]:
    """(azimuth, elevation) of pixel (x, y): degrees given ``focal`` (px), else px offsets.

    Azimuth positive right, elevation positive up; the optical axis passes
    through ((W - 1) / 2, (H - 1) / 2).
    """
    h, w = shape
    dx = x - (w - 1) / 2.0
    dy = (h - 1) / 2.0 - y
    if focal is None:
        return float(dx), float(dy)
    return math.degrees(math.atan2(dx, focal)), math.degrees(math.atan2(dy, focal))


# ---------------------------------------------------------------------------
# Camera motion: the rotation (the homography of the far scene) and the heading (FOE), per frame
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class CameraMotion:
    """The camera's motion between the previous frame and this one, in this frame's pixels.

    ``omega``: the camera's rotation since the previous frame (rad per frame, right-handed, about its
    x (right), y (down) and z (forward) axes: a pan to the right is ``+y``, a tilt up ``+x``), so that a
    point of the far scene seen at ``p`` in the previous frame is seen at ``homography(...) @ p`` now
    (the homography ``K R^T K^-1`` of a pure rotation ``R``).
    ``heading``: the focus of expansion (x, y) in pixels (where the camera is going), None when no
    translation is measured. ``rotation_confidence``: the share of the grid's points that were
    followed and agree with the fitted motion (0: nothing measured); ``heading_confidence``: the share
    of the points whose expansion is measured that expand about the heading.
    ``given``: True when the rotation came from the user (a gyro), not from the images.
    """

    omega: tuple[float, float, float] = (0.0, 0.0, 0.0)
    heading: tuple[float, float] | None = None
    rotation_confidence: float = 0.0
    heading_confidence: float = 0.0
    expansion: float = 0.0
    points: int = 0
    given: bool = False

    def homography(self, shape: tuple[int, int], focal: float) -> np.ndarray:
        """The 3x3 homography that maps the previous frame's far scene onto this frame."""
        h, w = shape
        k = np.array([[focal, 0.0, (w - 1) / 2.0], [0.0, focal, (h - 1) / 2.0], [0.0, 0.0, 1.0]])
        return k @ rotation_matrix(self.omega).T @ np.linalg.inv(k)

    @property
    def still(self) -> bool:
        """No rotation to compensate: exactly zero (the first frame, no texture, or given so)."""
        return self.omega == (0.0, 0.0, 0.0)

    @property
    def trusted(self) -> bool:
        """A rotation to compensate: given (a gyro), or estimated with at least
        :data:`MIN_ROTATION_CONFIDENCE` of the grid's points agreeing; not :attr:`still`."""
        return not self.still and (self.given or self.rotation_confidence >= MIN_ROTATION_CONFIDENCE)

    def shift_px(self, shape: tuple[int, int], focal: float) -> float:
        """The largest image motion (px) the rotation gives at the frame's centre and corners."""
        return _shift_px(self.homography(shape, focal), shape)


def _shift_px(homography: np.ndarray, shape: tuple[int, int]) -> float:
    """The largest image motion (px) ``homography`` gives at the frame's centre and corners."""
    h, w = shape
    pts = np.array([[0.0, 0.0, 1.0], [w - 1.0, 0.0, 1.0], [0.0, h - 1.0, 1.0], [w - 1.0, h - 1.0, 1.0],
                    [(w - 1) / 2.0, (h - 1) / 2.0, 1.0]]).T
    q = homography @ pts
    return float(np.max(np.hypot(q[0] / q[2] - pts[0], q[1] / q[2] - pts[1])))


def compensation(motion: CameraMotion, shape: tuple[int, int], focal: float) -> np.ndarray | None:
    """The homography that carries a model's state into this frame's pixels (gaze stabilisation,
    docs/model.md, "Camera motion"), or None when there is nothing to compensate: no rotation, an
    estimated one with a confidence below :data:`MIN_ROTATION_CONFIDENCE` (a given one, a gyro's, is
    always trusted: :attr:`CameraMotion.trusted`) or a shift below :data:`STILL_PX` (a still camera
    is never resampled). The one test of every model that stabilises."""
    if not motion.trusted:
        return None
    hom = motion.homography(shape, focal)                  # once: CameraMotion.shift_px's own
    return None if _shift_px(hom, shape) < STILL_PX else hom


def rotation_matrix(omega) -> np.ndarray:
    """The camera's rotation ``R`` for the rotation vector ``omega`` (rad; Rodrigues' formula)."""
    r, _ = cv2.Rodrigues(np.asarray(omega, dtype=np.float64).reshape(3, 1))
    return r


def _rotational_flow(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per point, the 2x3 matrix A with flow = A @ omega for a small rotation (normalised coordinates).

    The image motion of the far scene under a small camera rotation ``omega`` (Longuet-Higgins &
    Prazdny 1980, with x right, y down, z forward): a pan to the right moves the scene left.
    """
    a = np.empty((x.size, 2, 3))
    a[:, 0, 0] = x * y
    a[:, 0, 1] = -(1.0 + x * x)
    a[:, 0, 2] = y
    a[:, 1, 0] = 1.0 + y * y
    a[:, 1, 1] = -x * y
    a[:, 1, 2] = -x
    return a


_LK_WINDOW = 11          # px, the Lucas-Kanade window at the reduced size
_LK_LEVELS = 2           # pyramid levels above the reduced frame: motions up to ~30 px there
_LK_STOP = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03)
_MIN_TEXTURE = 100.0     # mean squared Sobel gradient (grey levels^2) for a grid point to be followed


class MotionEstimator:
    """Estimates :class:`CameraMotion` once per frame from the grey images (``apply(gray)``).

    Sparse pyramidal Lucas-Kanade (OpenCV) on a regular grid of a reduced frame, a forward-backward
    check, then a robust fit (iteratively reweighted least squares) of the flow field of a moving
    camera: a small rotation ``omega`` plus an expansion about the focus of expansion (the heading),
    whose magnitude varies from point to point with the depth. Objects that move on their own and
    frames without texture fall out as outliers (low confidence, no motion assumed).

    ``hfov_deg``: the horizontal field of view (needed to turn pixels into angles; 60 deg when
    unknown, documented). ``apply(gray, omega=...)``: the rotation given by the caller (rad since the
    last frame, the camera's axes: a gyro's, ``Model.step(gyro=)``); only the heading is then estimated,
    and ``rotation_confidence`` says how much of the images agrees with it. ``heading``: a fixed
    heading (x, y) in pixels of the frames given, when the robot knows it (``TargetParams.heading``).
    """

    def __init__(self, *, hfov_deg: float | None = None, grid: tuple[int, int] = (12, 9), work_width: int = 160,
                 heading: tuple[float, float] | None = None, min_expansion: float = 0.002,
                 heading_frames: int = HEADING_FRAMES):
        self.hfov_deg = 60.0 if hfov_deg is None else check_hfov(hfov_deg)
        self.heading_frames = max(int(heading_frames), 1)
        self.grid = grid
        self.work_width = work_width
        self.fixed_heading = heading
        self.min_expansion = min_expansion
        self.reset()

    def configure(self, hfov_deg: float | None, heading: tuple[float, float] | None) -> None:
        """The model's field of view (None: 60 degrees) and fixed heading (px of the frames given to
        :meth:`apply`; None: estimated), set before each frame (a model's may change after it was built)."""
        self.hfov_deg = 60.0 if hfov_deg is None else check_hfov(hfov_deg)
        self.fixed_heading = heading

    def reset(self) -> None:
        self._prev: np.ndarray | None = None
        self._older: list[np.ndarray] = []     # the reduced frames before the previous one (HEADING_FRAMES)

    def turn(self, image: np.ndarray, shape: tuple[int, int], *, hfov_deg: float | None,
             heading: tuple[float, float] | None = None, omega=None) -> tuple[CameraMotion, np.ndarray | None]:
        """One frame of gaze stabilisation, the same for every model that stabilises: the camera's
        motion to ``image`` (:meth:`apply`, with the model's current field of view and fixed heading,
        and the rotation ``omega`` when a gyro gives it) and the homography that carries a state of
        ``shape`` into this frame's pixels (:func:`compensation`; None: nothing to carry)."""
        self.configure(hfov_deg, heading)
        motion = self.apply(image, omega=omega)
        return motion, compensation(motion, shape, focal_length(shape[1], self.hfov_deg))

    def _reduce(self, gray: np.ndarray) -> tuple[np.ndarray, float]:
        h, w = gray.shape
        fast = _fast_camera()
        if gray.dtype == np.uint8:
            img = gray
        elif fast is not None and gray.ndim == 2:           # one compiled pass, the same values
            img = np.empty(gray.shape, np.uint8)
            fast.to_uint8(gray, img)
        else:
            img = np.clip(gray, 0, 255).astype(np.uint8)
        scale = 1.0
        while img.shape[1] >= 2 * self.work_width:
            img = cv2.pyrDown(img)
            scale *= 2.0
        return img, scale

    def _grid_points(self, shape: tuple[int, int]):
        """The grid's points ((N, 1, 2) float32 x, y) and their integer rows and columns for a frame
        of ``shape``: made once per shape and grid (the same every frame)."""
        key = (tuple(shape), tuple(self.grid))
        if getattr(self, "_points_key", None) != key:
            h, w = shape
            nx, ny = self.grid
            xs = (np.arange(nx) + 0.5) * w / nx
            ys = (np.arange(ny) + 0.5) * h / ny
            p0 = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 1, 2).astype(np.float32)
            p0.setflags(write=False)
            rows, cols = p0[:, 0, 1].astype(int), p0[:, 0, 0].astype(int)
            # the texture test at the points alone (_fast_camera.grid_texture) needs 4 px around each
            inside = bool(rows.min() >= 4 and rows.max() <= h - 5 and cols.min() >= 4 and cols.max() <= w - 5)
            self._points = (p0, rows, cols, inside)
            self._points_key = key
        return self._points

    def _track(self, prev_img: np.ndarray, cur_img: np.ndarray):
        """Grid points of the previous frame followed into this one (pyramidal Lucas-Kanade on the
        images), kept where the forward-backward error is under 0.5 px and the previous
        frame has texture (a flat patch "tracks" onto itself and says nothing)."""
        p0, rows, cols, inside = self._grid_points(prev_img.shape)
        fast = _fast_camera()
        if fast is not None and inside:                     # at the points only: the same values
            texture = fast.grid_texture(prev_img, rows, cols)
        else:
            gx = cv2.Sobel(prev_img, cv2.CV_32F, 1, 0, ksize=3)
            gy = cv2.Sobel(prev_img, cv2.CV_32F, 0, 1, ksize=3)
            texture = cv2.blur(gx * gx + gy * gy, (7, 7))[rows, cols]
        p0 = p0[texture > _MIN_TEXTURE]
        if len(p0) < 8:
            return np.empty((0, 2)), np.empty((0, 2))
        win = (_LK_WINDOW, _LK_WINDOW)
        p1, st, _ = cv2.calcOpticalFlowPyrLK(prev_img, cur_img, p0, None, winSize=win, maxLevel=_LK_LEVELS,
                                             criteria=_LK_STOP)
        pb, st2, _ = cv2.calcOpticalFlowPyrLK(cur_img, prev_img, p1, None, winSize=win, maxLevel=_LK_LEVELS,
                                              criteria=_LK_STOP)
        ok = (st.ravel() == 1) & (st2.ravel() == 1) & (np.abs(pb - p0).reshape(-1, 2).max(axis=1) < 0.5)
        return p0.reshape(-1, 2)[ok].astype(np.float64), p1.reshape(-1, 2)[ok].astype(np.float64)

    def apply(self, gray: np.ndarray, *, omega=None) -> CameraMotion:
        """The camera's motion from the previous frame to ``gray`` (the first frame: none)."""
        img, scale = self._reduce(gray)
        prev, self._prev = self._prev, img
        older = self._older
        if prev is not None:                                 # the frames back, oldest first, for the heading
            self._older = (older + [prev])[-max(self.heading_frames - 1, 0):] if self.heading_frames > 1 else []
        given = omega is not None
        if prev is None or prev.shape != img.shape:
            return CameraMotion(omega=tuple(float(v) for v in omega) if given else (0.0, 0.0, 0.0), given=given)
        h, w = img.shape
        f = focal_length(w, self.hfov_deg)
        cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
        p0, p1 = self._track(prev, img)
        if len(p0) < 8:
            return CameraMotion(omega=tuple(float(v) for v in omega) if given else (0.0, 0.0, 0.0), points=len(p0),
                                given=given)
        x0, y0 = (p0[:, 0] - cx) / f, (p0[:, 1] - cy) / f
        d = np.stack([(p1[:, 0] - p0[:, 0]) / f, (p1[:, 1] - p0[:, 1]) / f], -1)
        heading = None if self.fixed_heading is None else (
            (self.fixed_heading[0] / scale - cx) / f, (self.fixed_heading[1] / scale - cy) / f)
        fit = _fit_motion(x0, y0, d, None if omega is None else np.asarray(omega, float), heading, 1.0 / f)
        w_est, e, rot_ok, exp, exp_ok = fit
        # no heading measured: a rotation, or a sideways translation over near ground (parallax)? A share
        # (at most 1) can exceed the rotation's by TRANSLATION_MARGIN only when that is below 1 - the margin.
        if e is None and omega is None and rot_ok + TRANSLATION_MARGIN < 1.0:
            moved, t = _translation_share(x0, y0, d, 1.0 / f)
            sideways = abs(t[2]) < np.hypot(t[0], t[1]) / 3.0          # a heading beyond the joint fit's reach
            if sideways and moved > rot_ok + TRANSLATION_MARGIN:
                w_est, rot_ok = np.zeros(3), moved
        rot_ok *= len(p0) / float(self.grid[0] * self.grid[1])   # a share of the whole grid: a few points
                                                                  # on a flat or overexposed frame are no evidence
        n_back = self.heading_frames
        if (e is None and omega is None and heading is None and n_back > 1 and len(older) >= n_back - 1
                and older[0].shape == img.shape):
            e, exp, exp_ok = self._slow_heading(older[0], img, f, cx, cy, n_back)
        head_px = None
        if e is not None and exp > self.min_expansion:
            head_px = (float((e[0] * f + cx) * scale), float((e[1] * f + cy) * scale))
        return CameraMotion(omega=tuple(float(v) for v in w_est), heading=head_px,
                            rotation_confidence=float(rot_ok), heading_confidence=float(exp_ok if head_px else 0.0),
                            expansion=float(exp), points=len(p0), given=given)


    def _slow_heading(self, old: np.ndarray, img: np.ndarray, f: float, cx: float, cy: float, n: int):
        """The heading (normalised), expansion rate (1 / frame) and its share fitted on the flow from
        ``old``, ``n`` frames back, to ``img`` (:data:`HEADING_FRAMES`); (None, 0, 0) when that flow too
        shows too little expansion."""
        p0, p1 = self._track(old, img)
        if len(p0) < 8:
            return None, 0.0, 0.0
        x0, y0 = (p0[:, 0] - cx) / f, (p0[:, 1] - cy) / f
        d = np.stack([(p1[:, 0] - p0[:, 0]) / f, (p1[:, 1] - p0[:, 1]) / f], -1)
        _, e, _, exp, exp_ok = _fit_motion(x0, y0, d, None, None, 1.0 / f)
        return (None, 0.0, 0.0) if e is None else (e, exp / n, exp_ok)


def _fit_motion(x, y, d, omega, heading, px, iterations: int = 6, min_share: float = MIN_EXPANDING_SHARE):
    """Robust fit of ``d = A(x, y) omega + s_i (p_i - e)`` (rotation + expansion about the FOE e).

    Alternates: omega given e (linear: the flow across the radial direction p - e is the rotation's
    alone), then e given omega (linear in e: what the rotation leaves is parallel to p - e).
    Tukey weights on the residual, its scale from the median. Returns omega, e (normalised; None
    when too little expands to tell), the share of inliers, the median expansion rate of the points
    whose expansion is measured (1 / frames) and the share of those that expand about e.
    """
    n = len(x)
    fast = _fast_rounds()
    if fast is not None:                                    # the compiled rounds (mlplc2._fast_camera)
        w0 = np.zeros(3) if omega is None else np.asarray(omega, float)
        e0 = np.zeros(2) if heading is None else np.asarray(heading, float)
        w_est, e, scale, err, s, rr = fast(np.ascontiguousarray(x, float), np.ascontiguousarray(y, float),
                                           np.ascontiguousarray(d[:, 0]), np.ascontiguousarray(d[:, 1]), w0, e0,
                                           omega is None, heading is None, 0.3 * px, iterations)
        return _fit_result(w_est, e, scale, err, s, rr, 0.3 * px, min_share)
    a = _rotational_flow(x, y)
    a0, a1 = a[:, 0, :], a[:, 1, :]
    wts = np.ones(n)
    w_est = np.zeros(3) if omega is None else np.asarray(omega, float)
    e = np.zeros(2) if heading is None else np.asarray(heading, float)
    sigma = 0.3 * px
    dx, dy = d[:, 0], d[:, 1]
    for _ in range(iterations):
        rx, ry = x - e[0], y - e[1]
        rr = np.maximum(rx * rx + ry * ry, 1e-12)
        if omega is None:
            inv = 1.0 / np.sqrt(rr)
            nx_, ny_ = -ry * inv, rx * inv                   # across the radial direction
            rows = nx_[:, None] * a0 + ny_[:, None] * a1
            rw = rows * wts[:, None]
            w_est = np.linalg.solve(rw.T @ rows + 1e-12 * np.eye(3), rw.T @ (nx_ * dx + ny_ * dy))
        resx, resy = dx - a0 @ w_est, dy - a1 @ w_est       # what the rotation leaves: the expansion
        s = (resx * rx + resy * ry) / rr
        if heading is None:
            ww = wts * (s > 0)
            if np.count_nonzero(ww) >= 3:
                m = np.array([[ww @ (resy * resy), -(ww @ (resy * resx))], [-(ww @ (resx * resy)), ww @ (resx * resx)]])
                rhs = -resy * x + resx * y
                b = np.array([-(ww @ (resy * rhs)), ww @ (resx * rhs)])
                if abs(np.linalg.det(m)) > 1e-18:
                    e_new = np.linalg.solve(m, b)
                    if np.all(np.isfinite(e_new)) and np.hypot(*e_new) < 3.0:
                        e = e_new
        err = np.hypot(resx - s * (x - e[0]), resy - s * (y - e[1]))
        scale = max(1.4826 * float(np.median(err)), sigma)
        u = err / (4.685 * scale)
        wts = np.where(u < 1.0, (1.0 - u * u) ** 2, 0.0)
    return _fit_result(w_est, e, scale, err, s, rr, sigma, min_share)


def _translation_share(x, y, d, px, iterations: int = 3):
    """The share of the points whose flow ``d`` a translation alone explains (any direction, each
    point at its own depth, all in front of the camera; no rotation), and the direction ``t``.

    Robust (Tukey-weighted) total least squares of ``c_i . t = 0``, ``c_i = (d_y, -d_x, d_x y - d_y x)``:
    the flow at each point lies along ``(x t_z - t_x, y t_z - t_y)``.
    """
    sigma = 0.3 * px
    dx, dy = d[:, 0], d[:, 1]
    c = np.stack([dy, -dx, dx * y - dy * x], -1)
    wts = np.ones(len(x))
    for _ in range(iterations):
        t = np.linalg.eigh((c * wts[:, None]).T @ c)[1][:, 0]
        rx, ry = x * t[2] - t[0], y * t[2] - t[1]
        rr = np.maximum(rx * rx + ry * ry, 1e-12)
        s = (dx * rx + dy * ry) / rr
        err = np.hypot(dx - s * rx, dy - s * ry)
        scale = max(1.4826 * float(np.median(err)), sigma)
        u = err / (4.685 * scale)
        wts = np.where(u < 1.0, (1.0 - u * u) ** 2, 0.0)
    ahead = s * np.sign(wts @ s) > -2.0 * sigma / np.sqrt(rr)   # one sign of depth for the whole scene
    return float(np.mean((err < 3.0 * sigma) & ahead)), t


def _fit_result(w_est, e, scale, err, s, rr, sigma, min_share):
    """What the fit's last round tells: omega, e (None when under ``min_share`` of the points
    show a measurable expansion, and under :data:`FAST_EXPANDING_SHARE`, slower than :data:`FAST_EXPANSION` or
    at rates as alike as one object's, :data:`FAST_DEPTHS`), the share of inliers, the median expansion rate and
    the share of expanding points."""
    inliers = err < 3.0 * sigma
    radial = s * np.sqrt(rr)                                # the expansion's own flow at each point
    moving = inliers & (np.abs(radial) > 2.0 * sigma)       # points whose expansion is measured
    count = int(moving.sum())
    rate = float(np.median(s[moving])) if count else 0.0
    fast = count >= max(3, FAST_EXPANDING_SHARE * len(err)) and rate >= FAST_EXPANSION \
        and np.percentile(s[moving], 90) >= FAST_DEPTHS * np.percentile(s[moving], 10)
    if count < max(3, min_share * len(err)) and not fast:
        still = np.hypot(err, radial) < 3.0 * sigma         # too little expands to tell a heading: then the
        return w_est, None, float(np.mean(still)), 0.0, 0.0  # rotation alone must explain the flow
    return w_est, e, float(np.mean(inliers)), rate, float(np.mean(s[moving] > 0))


_FAST: list = []


def _fast_camera():
    """The compiled kernels of the estimate (:mod:`mlplc2._fast_camera`), or None without Numba."""
    if not _FAST:
        try:
            from . import _fast_camera as module
            _FAST.append(module)
        except Exception:  # noqa: BLE001 - ImportError, or Numba failing to initialise: NumPy then
            _FAST.append(None)
    return _FAST[0]


def _fast_rounds():
    """The compiled rounds of the fit (:mod:`mlplc2._fast_camera`), or None without Numba."""
    fast = _fast_camera()
    return None if fast is None else fast.fit_rounds


def warp(image: np.ndarray, homography: np.ndarray, *, fill: np.ndarray | float = 0.0,
         out: np.ndarray | None = None) -> np.ndarray:
    """``image`` of the previous frame seen in this frame's pixels (``homography``: previous -> this).

    Bilinear (``cv2.warpPerspective``); where this frame sees what the previous one did not (the
    border the rotation uncovers), ``fill``: a number, or an image of this frame whose values are
    taken there (the current grey frame for the previous frame: no change where nothing was seen).
    ``out``: a float32 array of the image's shape to write into (a view with rows apart in memory
    will do; not ``image`` itself), else a new one; the values are the same either way.
    """
    h, w = image.shape
    if np.isscalar(fill):
        return cv2.warpPerspective(image, homography, (w, h), dst=out, flags=cv2.INTER_LINEAR,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=float(fill))
    out = cv2.warpPerspective(image, homography, (w, h), dst=out, flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
    np.copyto(out, fill, where=np.isnan(out))           # in place: no third image
    return out
