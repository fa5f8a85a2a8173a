"""Numba kernel of the camera-motion fit of :mod:`mlplc2.camera` (``_fit_motion``'s iterations).

The same robust fit, in the same order of operations, as :func:`mlplc2.camera._fit_motion` does with
NumPy, in one compiled loop: the NumPy version spends ~1.7 ms per frame in the overhead of ~30
small array operations per round; this one ~0.05 ms. The camera uses it when Numba imports.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["fit_rounds"]


@numba.njit(cache=True, nogil=True)
def fit_rounds(x, y, dx, dy, w0, e0, fit_omega, fit_heading, sigma, iterations):
    """``iterations`` rounds of the fit; returns omega (3), e (2), the Tukey scale, the residual
    ``err``, the expansion rates ``s`` and the squared radial distances ``rr`` of the last round."""
    n = x.size
    a0 = np.empty((n, 3))
    a1 = np.empty((n, 3))
    for i in range(n):
        a0[i, 0] = x[i] * y[i]
        a0[i, 1] = -(1.0 + x[i] * x[i])
        a0[i, 2] = y[i]
        a1[i, 0] = 1.0 + y[i] * y[i]
        a1[i, 1] = -x[i] * y[i]
        a1[i, 2] = -x[i]
    wts = np.ones(n)
    w = w0.copy()
    e = e0.copy()
    err = np.zeros(n)
    s = np.zeros(n)
    rr = np.zeros(n)
    scale = sigma
    for _ in range(iterations):
        for i in range(n):
            rx, ry = x[i] - e[0], y[i] - e[1]
            rr[i] = max(rx * rx + ry * ry, 1e-12)
        if fit_omega:
            m = np.zeros((3, 3))
            b = np.zeros(3)
            for i in range(n):
                inv = 1.0 / np.sqrt(rr[i])
                nx = -(y[i] - e[1]) * inv
                ny = (x[i] - e[0]) * inv
                r0 = nx * a0[i, 0] + ny * a1[i, 0]
                r1 = nx * a0[i, 1] + ny * a1[i, 1]
                r2 = nx * a0[i, 2] + ny * a1[i, 2]
                rhs = nx * dx[i] + ny * dy[i]
                wi = wts[i]
                m[0, 0] += wi * r0 * r0
                m[0, 1] += wi * r0 * r1
                m[0, 2] += wi * r0 * r2
                m[1, 1] += wi * r1 * r1
                m[1, 2] += wi * r1 * r2
                m[2, 2] += wi * r2 * r2
                b[0] += wi * r0 * rhs
                b[1] += wi * r1 * rhs
                b[2] += wi * r2 * rhs
            m[1, 0], m[2, 0], m[2, 1] = m[0, 1], m[0, 2], m[1, 2]
            for k in range(3):
                m[k, k] += 1e-12
            w = np.linalg.solve(m, b)
        resx = np.empty(n)
        resy = np.empty(n)
        for i in range(n):
            resx[i] = dx[i] - (a0[i, 0] * w[0] + a0[i, 1] * w[1] + a0[i, 2] * w[2])
            resy[i] = dy[i] - (a1[i, 0] * w[0] + a1[i, 1] * w[1] + a1[i, 2] * w[2])
            s[i] = (resx[i] * (x[i] - e[0]) + resy[i] * (y[i] - e[1])) / rr[i]
        if fit_heading:
            m00 = m01 = m11 = b0 = b1 = 0.0
            count = 0
            for i in range(n):
                wi = wts[i] if s[i] > 0 else 0.0
                if wi != 0.0:
                    count += 1
                rhs = -resy[i] * x[i] + resx[i] * y[i]
                m00 += wi * resy[i] * resy[i]
                m01 -= wi * resy[i] * resx[i]
                m11 += wi * resx[i] * resx[i]
                b0 -= wi * resy[i] * rhs
                b1 += wi * resx[i] * rhs
            det = m00 * m11 - m01 * m01
            if count >= 3 and abs(det) > 1e-18:
                ex = (m11 * b0 - m01 * b1) / det
                ey = (m00 * b1 - m01 * b0) / det
                if np.isfinite(ex) and np.isfinite(ey) and np.hypot(ex, ey) < 3.0:
                    e[0], e[1] = ex, ey
        for i in range(n):
            err[i] = np.hypot(resx[i] - s[i] * (x[i] - e[0]), resy[i] - s[i] * (y[i] - e[1]))
        scale = max(1.4826 * np.median(err), sigma)
        for i in range(n):
            u = err[i] / (4.685 * scale)
            wts[i] = (1.0 - u * u) ** 2 if u < 1.0 else 0.0
    return w, e, scale, err, s, rr


@numba.njit(cache=True, nogil=True)
def to_uint8(gray, out):
    """``out[...] = np.clip(gray, 0, 255).astype(np.uint8)`` in one pass (truncation toward zero, as
    NumPy's cast); ``gray`` a 2-D float array, ``out`` uint8 of its shape."""
    h, w = gray.shape
    for y in range(h):
        g = gray[y]
        o = out[y]
        for x in range(w):
            v = g[x]
            v = 0.0 if v < 0.0 else v
            v = 255.0 if v > 255.0 else v
            o[x] = np.uint8(v)


@numba.njit(cache=True, nogil=True)
def grid_texture(img, rows, cols):
    """At each point (rows[k], cols[k]) of the uint8 image ``img`` (each at least 4 px inside it),
    what ``cv2.blur(gx * gx + gy * gy, (7, 7))`` gives there, ``gx``, ``gy`` the 3x3 Sobel
    derivatives (``cv2.Sobel(img, cv2.CV_32F, ...)``): those are integers, their squares' sums
    exact in float32, and OpenCV's box filter sums float32 in float64 (exact for these integers)
    and scales by 1/49 in float64 before rounding to float32, as done here."""
    n = rows.size
    out = np.empty(n, np.float32)
    scale = 1.0 / 49.0
    for k in range(n):
        r0 = rows[k]
        c0 = cols[k]
        total = 0
        for r in range(r0 - 3, r0 + 4):
            up = img[r - 1]
            mid = img[r]
            dn = img[r + 1]
            for c in range(c0 - 3, c0 + 4):
                gx = (np.int64(up[c + 1]) - np.int64(up[c - 1]) + 2 * (np.int64(mid[c + 1]) - np.int64(mid[c - 1]))
                      + np.int64(dn[c + 1]) - np.int64(dn[c - 1]))
                gy = (np.int64(dn[c - 1]) - np.int64(up[c - 1]) + 2 * (np.int64(dn[c]) - np.int64(up[c]))
                      + np.int64(dn[c + 1]) - np.int64(up[c + 1]))
                total += gx * gx + gy * gy
        out[k] = np.float32(np.float64(total) * scale)
    return out
