"""Depth coherence of a box: whether it scales as one fronto-parallel object or as a surface
slanted in depth (the ground ahead, a wall beside the path) (:func:`slant`; ``docs/targets.md``,
step 7, issue 22).

An object on a collision course that is small against its distance scales uniformly about one
centre: the image motion of its points is ``d + s (x - c)``, one scale rate ``s`` everywhere. The
static world seen from a camera moving forward is not: a ground point at image row ``y`` below the
horizon ``y_h`` has the inverse depth ``1 / Z = (y - y_h) / (f h_c)``, so its scale rate
``T_z / Z`` grows linearly with the row, from 0 at the horizon; a wall beside the path likewise
with the column. The planar flow of a slanted plane (the 8-parameter model of Adiv, 1985, with
the rotation removed by the gaze stabilisation) adds the terms ``(a u_n + b v_n) (u, v)`` to the
scaling ``diag(s_x, s_y)`` (``u_n``, ``v_n``: the coordinates over the box's half-sides):
``b / s_x`` is how much the horizontal scale rate changes from the box's centre to its bottom edge
(0 for a fronto-parallel object, 1 for a ground patch reaching up to the horizon: at ``d`` px below
it the ground's horizontal scale rate is ``c d``), ``a / s_y`` how much the vertical one changes
from its centre to its right edge (a wall beside the path).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["slant"]


def _patch(img: np.ndarray, level: int, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Bilinear samples of pyramid level ``level`` at the level-0 coordinates ``xs``, ``ys``."""
    f = float(1 << level)
    mx = ((xs + 0.5) / f - 0.5).astype(np.float32)
    my = ((ys + 0.5) / f - 0.5).astype(np.float32)
    return cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def slant(prev: list[np.ndarray], cur: list[np.ndarray], old: tuple[float, float, float, float],
          new: tuple[float, float, float, float], *, n: int = 32, margin: float = 1.5,
          iterations: int = 10) -> tuple[float, float] | None:
    """The depth gradient across a box between two :func:`~.alignment.pyramid` s: ``(across, down)``,
    the change of its vertical scale rate from its centre to its right edge over its value
    (``a / s_y``), and of its horizontal scale rate from its centre to its bottom edge (``b / s_x``):
    0, 0 for a fronto-parallel object; ``down`` = 1 for a ground patch reaching up to the horizon. ``old``, ``new``: the box (cx, cy, w, h, px) in ``prev`` and in
    ``cur``, which start the fit (shift and scale). Gauss-Newton on the planar flow
    ``cur(c + step (u + t + S u + (a u_n + b v_n) u)) = prev(c + step u)`` (``u`` = (u, v) patch
    samples about the old centre ``c``, ``u_n``, ``v_n`` them over the box's half-sides, ``S`` =
    diag(sx, sy)), weighted on the box. None when the box did not grow on both axes, the patch has too little
    texture or the iteration does not settle."""
    cx, cy, w, h = old
    half = margin * max(w, h) / 2.0 + 3.0
    step = 2.0 * half / n
    level = 0 if step <= 1.5 else min(int(math.ceil(math.log2(step / 1.5))), len(prev) - 1)
    u = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
    uu, vv = np.meshgrid(u, u)
    hw, hh = max(w / 2.0, 1.0) / step, max(h / 2.0, 1.0) / step
    un, vn = uu / hw, vv / hh
    a = cv2.GaussianBlur(_patch(prev[level], level, cx + step * uu, cy + step * vv), (0, 0), 0.8)
    gx = cv2.Sobel(a, cv2.CV_32F, 1, 0, ksize=3).astype(np.float64) * 0.125
    gy = cv2.Sobel(a, cv2.CV_32F, 0, 1, ksize=3).astype(np.float64) * 0.125
    wgt = (np.clip((1.2 * hw - np.abs(uu)) / (0.2 * hw), 0, 1) * np.clip((1.2 * hh - np.abs(vv)) / (0.2 * hh), 0, 1)).ravel()
    radial = gx * uu + gy * vv
    jac = np.stack([(gx * uu).ravel(), (gy * vv).ravel(), gx.ravel(), gy.ravel(), (radial * un).ravel(),
                    (radial * vn).ravel()], 1)
    jw = jac * wgt[:, None]
    hess = jw.T @ jac
    if not np.all(np.isfinite(hess)) or np.linalg.cond(hess) > 1e8:
        return None
    hinv = np.linalg.inv(hess)
    p = np.array([new[2] / w - 1.0, new[3] / h - 1.0, (new[0] - cx) / step, (new[1] - cy) / step, 0.0, 0.0])
    for _ in range(max(iterations, 1)):
        sx, sy, tx, ty, ga, gb = p
        rad = ga * un + gb * vn
        b = _patch(cur[level], level, cx + step * (uu + tx + sx * uu + rad * uu),
                   cy + step * (vv + ty + sy * vv + rad * vv))
        r = (cv2.GaussianBlur(b, (0, 0), 0.8).astype(np.float64) - a).ravel()
        d = hinv @ (jw.T @ r)
        p = p - d
        if not (np.all(np.abs(p[[0, 1, 4, 5]]) < 1.0) and abs(p[2]) < n and abs(p[3]) < n):
            return None
        if np.all(np.abs(d[[0, 1, 4, 5]]) < 1e-4) and np.all(np.abs(d[2:4]) < 1e-3):
            break
    if not (p[0] > 0 and p[1] > 0):
        return None
    return float(p[4] / p[1]), float(p[5] / p[0])
