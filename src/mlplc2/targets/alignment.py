"""The image measurement: horizontal and vertical scale and shift of an object's patch between
two frames (:func:`align`, :class:`Alignment`), by Gauss-Newton on
``cur(c + d + K (x - c)) = prev(x)``, ``K = diag(kx, ky)``, on image pyramids (:func:`pyramid`;
``docs/targets.md``, steps 3-4). The compiled twin of one alignment is
:func:`mlplc2.targets._fast_align.align_patch` (the same alignment to ~1e-12).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["Alignment", "pyramid", "align", "sample_patch"]


@dataclass(frozen=True)
class Alignment:
    """Scales and shift of a patch from the previous frame to this one (:func:`align`).

    ``kx``, ``ky``: the horizontal and vertical scale (size now / size before); ``dx``, ``dy``:
    shift (px) of the patch centre; ``residual``: rms grey-level difference left (weighted);
    ``sigma``: standard error of ``log scale`` from the Gauss-Newton normal equations.
    """

    kx: float
    ky: float
    dx: float
    dy: float
    residual: float
    sigma: float

    @property
    def scale(self) -> float:
        """The mean scale ``sqrt(kx ky)`` (an approaching object: its growth)."""
        return math.sqrt(self.kx * self.ky)

    @property
    def anisotropy(self) -> float:
        """``log(ky / kx)``: 0 for a fronto-parallel object; a ground plane grows twice as fast
        vertically as horizontally, a wall beside the path the other way round."""
        return math.log(self.ky / self.kx)


def pyramid(gray: np.ndarray, smallest: int = 16) -> list[np.ndarray]:
    """The frame and its successive halvings (``cv2.pyrDown``) down to ``smallest`` px."""
    levels = [gray]
    while min(levels[-1].shape) >= 2 * smallest:
        levels.append(cv2.pyrDown(levels[-1]))
    return levels


_GRIDS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _grid(n: int):
    """Patch coordinates (u, v) centred on the patch centre, and the index vector (cached)."""
    if n not in _GRIDS:
        u = np.arange(n, dtype=np.float32) - (n - 1) / 2.0
        uu, vv = np.meshgrid(u, u)
        _GRIDS[n] = (uu, vv, np.arange(n, dtype=np.float32))
    return _GRIDS[n]


def sample_patch(levels, level: int, cx: float, cy: float, step_x: float, step_y: float, n: int):
    """``n`` x ``n`` bilinear samples of pyramid ``level`` around (cx, cy) (level-0 px) every
    ``step_x`` / ``step_y`` level-0 px, and the mask of the samples that fall inside the frame."""
    img = levels[level]
    f = float(1 << level)
    sx, sy = step_x / f, step_y / f
    ox = (cx + 0.5) / f - 0.5 - (n - 1) / 2.0 * sx
    oy = (cy + 0.5) / f - 0.5 - (n - 1) / 2.0 * sy
    m = np.array([[sx, 0.0, ox], [0.0, sy, oy]], np.float32)
    patch = cv2.warpAffine(img, m, (n, n), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                           borderMode=cv2.BORDER_REPLICATE)
    idx = _grid(n)[2]
    h, w = img.shape
    xs, ys = ox + idx * sx, oy + idx * sy
    inside = ((ys >= 0) & (ys <= h - 1))[:, None] & ((xs >= 0) & (xs <= w - 1))[None, :]
    return patch, inside


def align(prev: list[np.ndarray], cur: list[np.ndarray], cx: float, cy: float, half: float,
          box: tuple[float, float], *, n: int = 32, iterations: int = 10, kernel=None,
          guess: tuple[float, float, float] | None = None) -> Alignment | None:
    """Scales and shift of the patch of half-side ``half`` px around (cx, cy) from ``prev`` to
    ``cur`` (two :func:`pyramid` s), weighted on the object's box (half-width, half-height px).

    Gauss-Newton on ``cur(c + d + K (x - c)) = prev(x)`` with ``K = diag(kx, ky)`` (the four
    parameters log kx, log ky, dx, dy), using the previous patch's gradients
    (forward-additive with a fixed Hessian); ``n`` x ``n`` samples are taken from the pyramid
    level whose pixel is at most 1.5 samples, so the cost does not depend on the object's size;
    samples outside the frame get no weight. None when the patch has too little texture or the
    iteration does not settle.

    ``guess``: (scale, dx, dy) where the iteration starts (a track's own motion carried over a long
    interval, ``TargetLayer._align_track``), else no motion; it always runs the NumPy version.
    ``kernel``: the compiled version (:func:`mlplc2.targets._fast_align.align_patch`, the same
    alignment to ~1e-12; :mod:`mlplc2.backend` chooses it) for float32 pyramids, or None.
    """
    step = 2.0 * half / n
    level = 0 if step <= 1.5 else min(int(math.ceil(math.log2(step / 1.5))), len(prev) - 1)
    if guess is None and kernel is not None and prev[level].dtype == cur[level].dtype == np.float32 \
            and prev[level].ndim == cur[level].ndim == 2:
        ok, *out = kernel(prev[level], cur[level], level, float(cx), float(cy), step, float(box[0]),
                          float(box[1]), int(n), int(iterations))
        return Alignment(*out) if ok else None
    uu, vv, _ = _grid(n)
    a, inside = sample_patch(prev, level, cx, cy, step, step, n)
    a = cv2.GaussianBlur(a, (0, 0), 0.8)
    gx = cv2.Sobel(a, cv2.CV_32F, 1, 0, ksize=3) * np.float32(0.125)
    gy = cv2.Sobel(a, cv2.CV_32F, 0, 1, ksize=3) * np.float32(0.125)
    # weights: 1 on the box, falling to 0 over a fifth of its half-size beyond it
    hw, hh = max(box[0], 1.0) / step, max(box[1], 1.0) / step
    wgt = (np.clip((1.2 * hw - np.abs(uu)) / (0.2 * hw), 0, 1) * np.clip((1.2 * hh - np.abs(vv)) / (0.2 * hh), 0, 1)
           * inside).astype(np.float32).ravel()
    jac = np.stack([(gx * uu).ravel(), (gy * vv).ravel(), gx.ravel(), gy.ravel()], 1)
    # the normal equations in float64: float32 sums would depend on the BLAS's summation order
    jw = (jac * wgt[:, None]).astype(np.float64)
    hess = jw.T @ jac
    if not np.all(np.isfinite(hess)) or np.linalg.cond(hess) > 1e7:
        return None
    hinv = np.linalg.inv(hess)
    px = py = tx = ty = 0.0
    if guess is not None:                # (scale, dx, dy): where the iteration starts
        px = py = math.log(guess[0])
        tx, ty = guess[1] / step, guess[2] / step
    r = None
    for _ in range(max(iterations, 1)):
        kx, ky = math.exp(px), math.exp(py)
        b, inside_b = sample_patch(cur, level, cx + tx * step, cy + ty * step, step * kx, step * ky, n)
        b = cv2.GaussianBlur(b, (0, 0), 0.8)
        r = (b - a).ravel()
        w_it = jw if inside_b.all() else jw * inside_b.ravel()[:, None]
        d0, d1, d2, d3 = hinv @ (w_it.T @ r)
        px -= d0
        py -= d1
        tx -= d2 * kx
        ty -= d3 * ky
        if not (abs(px) < 1.0 and abs(py) < 1.0 and abs(tx) < n and abs(ty) < n):
            return None
        if abs(d0) < 1e-5 and abs(d1) < 1e-5 and abs(d2) < 1e-3 and abs(d3) < 1e-3:
            break
    wsum = float(wgt.sum())
    res = math.sqrt(float(wgt @ (r * r)) / wsum) if wsum > 0 else math.inf
    var = 0.25 * (hinv[0, 0] + hinv[1, 1] + 2 * hinv[0, 1])     # of (log kx + log ky) / 2
    return Alignment(math.exp(px), math.exp(py), tx * step, ty * step, res, res * math.sqrt(max(float(var), 0.0)))

