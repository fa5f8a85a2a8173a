"""Numba kernel of the image alignment of :mod:`mlplc2.targets.alignment`, chosen by :mod:`mlplc2.backend`.

:func:`align_patch` is :func:`mlplc2.targets.alignment.align` on one pyramid level: the patch sampled,
blurred and differentiated as OpenCV does it in float32: the warp's coordinates and ``fma``
interpolations, ``cv2.GaussianBlur``'s and ``cv2.Sobel``'s tap order. ``cv2.warpAffine`` computes
the source coordinates in float32 up to OpenCV 5.0 and in float64 from 5.1 (:data:`EXACT_COORDINATES`,
probed once at import, says which the installed OpenCV does). That is bit for bit on x86-64 with
AVX2 for a patch side that is a multiple of 16 (the default 32) inside the image, and within a
float32 ulp or so otherwise (OpenCV's scalar tail, and 5.1's replicated border, round differently).
Then the same float32 weights and Jacobian, the same float64 normal equations (the Gauss-Newton
Hessian of the template), iteration and stopping rules: the alignments agree to ~1e-12
(``tests/test_fast_targets.py``). Every kernel is ``nogil`` and cached on disk where possible (the
choice of coordinates is an argument, not a global: Numba's cache would keep a global's value
across an OpenCV upgrade); nothing here is public API.
"""

from __future__ import annotations

import math

import cv2
import numba
import numpy as np
from llvmlite import ir as llvm_ir
from numba.extending import intrinsic

from ..neuropils._fast import jit  # the same njit options and on-disk cache fallback as the front end

__all__ = ["align_patch"]


#: The blur of :func:`mlplc2.targets.alignment.align`, ``cv2.GaussianBlur(patch, (0, 0), 0.8)`` on float32:
#: OpenCV's kernel size for a float image, ``round(8 sigma + 1) | 1`` = 7, and its float32 taps.
_BLUR_SIGMA = 0.8
_TAPS = cv2.getGaussianKernel(int(round(8 * _BLUR_SIGMA + 1)) | 1, _BLUR_SIGMA, cv2.CV_32F).ravel().copy()

_F32 = np.float32


def _warp_coordinates_in_double() -> bool:
    """True when the installed ``cv2.warpAffine`` (``INTER_LINEAR | WARP_INVERSE_MAP``, float32)
    computes the source coordinates in float64 (OpenCV >= 5.1), False for float32 (<= 5.0).

    A row alternating 0 and 1000 sampled near column 1000, where a float32 coordinate is off by up
    to 3e-5 px: the interpolation magnifies that to up to 0.03 grey levels, against ~1e-4 for
    float64 coordinates (float32 rounding of the interpolation itself)."""
    row = np.tile(np.array([0.0, 1000.0], np.float32), (2, 1024))
    m = np.array([[0.0371, 0.0, 1000.3], [0.0, 1.0, 0.0]], np.float32)
    got = cv2.warpAffine(row, m, (64, 1), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                         borderMode=cv2.BORDER_REPLICATE)[0].astype(np.float64)
    xs = np.float64(m[0, 0]) * np.arange(64) + np.float64(m[0, 2])
    x0 = np.floor(xs).astype(np.int64)
    exact = row[0, x0] + (xs - x0) * (row[0, x0 + 1].astype(np.float64) - row[0, x0])
    return bool(np.abs(got - exact).max() < 1e-3)


#: The installed OpenCV's ``warpAffine`` coordinates: float64 (True, >= 5.1) or float32 (False).
EXACT_COORDINATES = _warp_coordinates_in_double()


@intrinsic
def _fma32(typingctx, a, b, c):
    """``a * b + c`` of three float32, rounded once (LLVM's ``llvm.fma``: one instruction where
    the CPU has FMA, like OpenCV's ``v_fma``; a correctly rounded library call otherwise)."""
    if not (a == b == c == numba.float32):
        return None
    sig = numba.float32(numba.float32, numba.float32, numba.float32)

    def codegen(context, builder, signature, args):
        f32 = llvm_ir.FloatType()
        fn = builder.module.declare_intrinsic("llvm.fma", [f32], llvm_ir.FunctionType(f32, [f32, f32, f32]))
        return builder.call(fn, args)

    return sig, codegen


@jit()
def _reflect101(i, n):
    """``cv2.BORDER_REFLECT_101`` index (``n >= 2``, ``-n < i < 2 n - 1``)."""
    if i < 0:
        return -i
    if i >= n:
        return 2 * (n - 1) - i
    return i


@jit()
def _sample(img, level, cx, cy, step_x, step_y, n, out, in_x, in_y, exact):
    """:func:`mlplc2.targets.alignment.sample_patch` into ``out`` (n, n) float32; ``in_x`` / ``in_y``: the
    inside mask per column / row (the mask is their outer product). True when all inside.

    ``cv2.warpAffine(INTER_LINEAR | WARP_INVERSE_MAP, BORDER_REPLICATE)`` with the float32
    matrix ``[[sx, 0, ox], [0, sy, oy]]`` as OpenCV computes it for float32 images: the source
    column and row, their floor and fraction (float32), and two linear interpolations by ``fma``
    (along the row, then between the rows), the four neighbours clamped to the image (replicated
    border). The coordinates: with ``exact`` (OpenCV >= 5.1, :data:`EXACT_COORDINATES`)
    ``sx x + ox`` and ``sy y + oy`` in float64; without (4.11-5.0) ``fma(sx, x, ox)`` and
    ``sy y + oy`` (two roundings) in float32. The mask follows NumPy's float32 ``ox + idx * sx``
    of the reference.
    """
    h, w = img.shape
    f = float(1 << level)
    sx = step_x / f
    sy = step_y / f
    ox = (cx + 0.5) / f - 0.5 - (n - 1) / 2.0 * sx
    oy = (cy + 0.5) / f - 0.5 - (n - 1) / 2.0 * sy
    m0, m2, m4, m5 = _F32(sx), _F32(ox), _F32(sy), _F32(oy)
    x0 = np.empty(n, np.int64)
    x1 = np.empty(n, np.int64)
    ax = np.empty(n, np.float32)
    wlim = _F32(w - 1)
    hlim = _F32(h - 1)
    zero = _F32(0.0)
    everywhere = True
    for j in range(n):
        fj = _F32(j)
        if exact:
            xd = np.float64(m0) * j + np.float64(m2)
            ix = int(math.floor(xd))
            ax[j] = _F32(xd - ix)
        else:
            xs = _fma32(m0, fj, m2)
            ix = int(math.floor(xs))
            ax[j] = xs - _F32(ix)
        x0[j] = min(max(ix, 0), w - 1)
        x1[j] = min(max(ix + 1, 0), w - 1)
        xm = m2 + fj * m0
        in_x[j] = xm >= zero and xm <= wlim
        everywhere = everywhere and in_x[j]
    for i in range(n):
        fi = _F32(i)
        if exact:
            yd = np.float64(m4) * i + np.float64(m5)
            iy = int(math.floor(yd))
            by = _F32(yd - iy)
        else:
            ys = fi * m4 + m5
            iy = int(math.floor(ys))
            by = ys - _F32(iy)
        y0 = min(max(iy, 0), h - 1)
        y1 = min(max(iy + 1, 0), h - 1)
        ym = m5 + fi * m4
        in_y[i] = ym >= zero and ym <= hlim
        everywhere = everywhere and in_y[i]
        for j in range(n):
            a = ax[j]
            p00 = img[y0, x0[j]]
            p10 = img[y1, x0[j]]
            v0 = _fma32(a, img[y0, x1[j]] - p00, p00)
            v1 = _fma32(a, img[y1, x1[j]] - p10, p10)
            out[i, j] = _fma32(by, v1 - v0, v0)
    return everywhere


@jit()
def _blur(src, pad, tmp, dst, taps):
    """``cv2.GaussianBlur(src, (0, 0), 0.8)`` of a float32 patch (``BORDER_REFLECT_101``), in
    OpenCV's order: along the rows tap by tap (``fma``), then along the columns with the
    symmetric taps paired (centre tap first, then ``fma`` of the pair sums outwards).
    ``pad``: scratch of ``n1 + len(taps) - 1`` float32; each inner loop runs along a row."""
    n0, n1 = src.shape
    k = taps.shape[0]
    r = k // 2
    for i in range(n0):
        for j in range(n1):
            pad[j + r] = src[i, j]
        for t in range(r):
            pad[r - 1 - t] = src[i, t + 1]
            pad[n1 + r + t] = src[i, n1 - 2 - t]
        c = taps[0]
        for j in range(n1):
            tmp[i, j] = c * pad[j]
        for t in range(1, k):
            c = taps[t]
            for j in range(n1):
                tmp[i, j] = _fma32(c, pad[j + t], tmp[i, j])
    for i in range(n0):
        c = taps[r]
        for j in range(n1):
            dst[i, j] = c * tmp[i, j]
        for t in range(1, r + 1):
            c = taps[r - t]
            im, ip = _reflect101(i - t, n0), _reflect101(i + t, n0)
            for j in range(n1):
                dst[i, j] = _fma32(c, tmp[im, j] + tmp[ip, j], dst[i, j])


@jit()
def _support(wts):
    """``(first, last + 1)`` of the nonzero entries of a weight profile that is positive on one
    interval (``(0, 0)`` when all are zero)."""
    lo = 0
    while lo < wts.shape[0] and not wts[lo] > 0:
        lo += 1
    hi = wts.shape[0]
    while hi > lo and not wts[hi - 1] > 0:
        hi -= 1
    return lo, hi


@jit()
def _weights(n, step, box_w, box_h):
    """The patch coordinate ``u`` of each column (row) and the float32 weights per column ``wx``
    and per row ``wy``: 1 on the box, falling to 0 over a fifth of its half-size beyond it."""
    hw = max(box_w, 1.0) / step
    hh = max(box_h, 1.0) / step
    cw1, cw2 = _F32(1.2 * hw), _F32(0.2 * hw)
    ch1, ch2 = _F32(1.2 * hh), _F32(0.2 * hh)
    half_n = _F32((n - 1) / 2.0)
    u = np.empty(n, np.float32)
    wx = np.empty(n, np.float32)
    wy = np.empty(n, np.float32)
    one = _F32(1.0)
    zero = _F32(0.0)
    for j in range(n):
        u[j] = _F32(j) - half_n
        au = abs(u[j])
        wx[j] = min(max((cw1 - au) / cw2, zero), one)
        wy[j] = min(max((ch1 - au) / ch2, zero), one)
    return u, wx, wy


@jit()
def _normal_equations(a, in_x, in_y, u, wx, wy, i0, i1, j0, j1, jw, wgt):
    """The template's Sobel gradients (``ksize=3`` x 1/8, ``BORDER_REFLECT_101``), weights and
    Jacobian (float32) on rows ``i0:i1``, columns ``j0:j1`` of the blurred patch ``a`` (n, n):
    the weighted Jacobian into ``jw`` (n n, 4) and the weights into ``wgt`` (n n); returns the
    Hessian ``jw.T @ jac`` (4, 4) float64, each of the 16 entries summed over the samples in order."""
    n = a.shape[0]
    zero = _F32(0.0)
    eighth = _F32(0.125)
    two = _F32(2.0)
    h00 = h01 = h02 = h03 = h10 = h11 = h12 = h13 = 0.0
    h20 = h21 = h22 = h23 = h30 = h31 = h32 = h33 = 0.0
    for i in range(i0, i1):
        im, ip = _reflect101(i - 1, n), _reflect101(i + 1, n)
        for j in range(j0, j1):
            jm, jp = _reflect101(j - 1, n), _reflect101(j + 1, n)
            # Sobel x: the row difference, then [1 2 1] down the column (centre first)
            d = a[i, jp] - a[i, jm]
            gx = (two * d + ((a[im, jp] - a[im, jm]) + (a[ip, jp] - a[ip, jm]))) * eighth
            # Sobel y: [1 2 1] along the row (centre first), then the column difference
            em = two * a[im, j] + (a[im, jm] + a[im, jp])
            ep = two * a[ip, j] + (a[ip, jm] + a[ip, jp])
            gy = (ep - em) * eighth
            k = i * n + j
            wk = wx[j] * wy[i]
            if not (in_x[j] and in_y[i]):
                wk = zero
            wgt[k] = wk
            jx, jy = gx * u[j], gy * u[i]      # the Jacobian: d/dlog kx, d/dlog ky, d/dx, d/dy
            w0, w1, w2, w3 = jx * wk, jy * wk, gx * wk, gy * wk
            jw[k, 0] = w0
            jw[k, 1] = w1
            jw[k, 2] = w2
            jw[k, 3] = w3
            f0, f1, f2, f3 = np.float64(jx), np.float64(jy), np.float64(gx), np.float64(gy)
            e0, e1, e2, e3 = np.float64(w0), np.float64(w1), np.float64(w2), np.float64(w3)
            h00 += e0 * f0
            h01 += e0 * f1
            h02 += e0 * f2
            h03 += e0 * f3
            h10 += e1 * f0
            h11 += e1 * f1
            h12 += e1 * f2
            h13 += e1 * f3
            h20 += e2 * f0
            h21 += e2 * f1
            h22 += e2 * f2
            h23 += e2 * f3
            h30 += e3 * f0
            h31 += e3 * f1
            h32 += e3 * f2
            h33 += e3 * f3
    hess = np.empty((4, 4))
    hess[0, 0], hess[0, 1], hess[0, 2], hess[0, 3] = h00, h01, h02, h03
    hess[1, 0], hess[1, 1], hess[1, 2], hess[1, 3] = h10, h11, h12, h13
    hess[2, 0], hess[2, 1], hess[2, 2], hess[2, 3] = h20, h21, h22, h23
    hess[3, 0], hess[3, 1], hess[3, 2], hess[3, 3] = h30, h31, h32, h33
    return hess


@jit()
def _iterate(cur, level, cx, cy, step, n, iterations, a, jw, hinv, i0, i1, j0, j1, pad, tmp, taps, r, exact):
    """The Gauss-Newton iteration (forward-additive, fixed Hessian ``hinv``) of the patch of
    ``cur`` against the template ``a``: the residuals of the last round into ``r`` (n n).
    Returns ``(ok, px, py, tx, ty)`` (log kx, log ky, shift in samples); ``ok`` False when
    the iteration ran away."""
    b0 = np.empty((n, n), np.float32)
    b = np.empty((n, n), np.float32)
    bx = np.empty(n, np.bool_)
    by = np.empty(n, np.bool_)
    zero = _F32(0.0)
    px = py = tx = ty = 0.0
    for _ in range(max(iterations, 1)):
        kx, ky = math.exp(px), math.exp(py)
        _sample(cur, level, cx + tx * step, cy + ty * step, step * kx, step * ky, n, b0, bx, by, exact)
        _blur(b0, pad, tmp, b, taps)
        g0 = g1 = g2 = g3 = 0.0
        for i in range(i0, i1):
            for j in range(j0, j1):
                k = i * n + j
                rk = b[i, j] - a[i, j]
                r[k] = rk
                if not (bx[j] and by[i]):      # outside the frame now: no weight (rk stays for the residual)
                    rk = zero
                fr = np.float64(rk)
                g0 += np.float64(jw[k, 0]) * fr
                g1 += np.float64(jw[k, 1]) * fr
                g2 += np.float64(jw[k, 2]) * fr
                g3 += np.float64(jw[k, 3]) * fr
        d0 = hinv[0, 0] * g0 + hinv[0, 1] * g1 + hinv[0, 2] * g2 + hinv[0, 3] * g3
        d1 = hinv[1, 0] * g0 + hinv[1, 1] * g1 + hinv[1, 2] * g2 + hinv[1, 3] * g3
        d2 = hinv[2, 0] * g0 + hinv[2, 1] * g1 + hinv[2, 2] * g2 + hinv[2, 3] * g3
        d3 = hinv[3, 0] * g0 + hinv[3, 1] * g1 + hinv[3, 2] * g2 + hinv[3, 3] * g3
        px -= d0
        py -= d1
        tx -= d2 * kx
        ty -= d3 * ky
        if not (abs(px) < 1.0 and abs(py) < 1.0 and abs(tx) < n and abs(ty) < n):
            return False, px, py, tx, ty
        if abs(d0) < 1e-5 and abs(d1) < 1e-5 and abs(d2) < 1e-3 and abs(d3) < 1e-3:
            break
    return True, px, py, tx, ty


@jit()
def _rms(wgt, r, n, i0, i1, j0, j1):
    """The weighted rms residual (summed in float64); inf without weight."""
    wsum = 0.0
    rr = 0.0
    for i in range(i0, i1):
        for k in range(i * n + j0, i * n + j1):
            wsum += np.float64(wgt[k])
            rr += np.float64(wgt[k]) * (np.float64(r[k]) * np.float64(r[k]))
    return math.sqrt(rr / wsum) if wsum > 0 else math.inf


def align_patch(prev, cur, level, cx, cy, step, box_w, box_h, n, iterations):
    """:func:`_align_patch` with the installed OpenCV's coordinates (:data:`EXACT_COORDINATES`)."""
    return _align_patch(prev, cur, level, cx, cy, step, box_w, box_h, n, iterations, EXACT_COORDINATES)


@jit()
def _align_patch(prev, cur, level, cx, cy, step, box_w, box_h, n, iterations, exact):
    """:func:`mlplc2.targets.alignment.align` on pyramid level ``level`` (``prev`` and ``cur``: that level
    of the two pyramids, float32), patch ``n`` x ``n`` every ``step`` level-0 px.

    Returns ``(ok, kx, ky, dx, dy, residual, sigma)``; ``ok`` False for None. The samples, the
    blur, the Sobel gradients (``ksize=3`` x 1/8, ``BORDER_REFLECT_101``), the weights and the
    Jacobian are the reference's float32 values; the Hessian, its inverse and the sums of the
    updates are float64 like the reference's (summed in sample order here, by BLAS there), with
    the same iteration and stopping rules. The rms residual is summed in float64 (float32
    there: ~1e-7 relative).
    """
    taps = _TAPS
    a0 = np.empty((n, n), np.float32)
    a = np.empty((n, n), np.float32)
    tmp = np.empty((n, n), np.float32)
    pad = np.empty(n + taps.shape[0] - 1, np.float32)
    in_x = np.empty(n, np.bool_)
    in_y = np.empty(n, np.bool_)
    _sample(prev, level, cx, cy, step, step, n, a0, in_x, in_y, exact)
    _blur(a0, pad, tmp, a, taps)
    u, wx, wy = _weights(n, step, box_w, box_h)
    # the samples of zero weight add exact zeros to every sum below: only the rows i0:i1 and
    # columns j0:j1 of nonzero weight are visited
    j0, j1 = _support(wx)
    i0, i1 = _support(wy)
    m = n * n
    jw = np.empty((m, 4), np.float32)
    wgt = np.empty(m, np.float32)
    hess = _normal_equations(a, in_x, in_y, u, wx, wy, i0, i1, j0, j1, jw, wgt)
    fail = (False, 1.0, 1.0, 0.0, 0.0, math.inf, math.inf)
    if not np.all(np.isfinite(hess)) or np.linalg.cond(hess) > 1e7:
        return fail
    hinv = np.linalg.inv(hess)
    r = np.empty(m, np.float32)
    ok, px, py, tx, ty = _iterate(cur, level, cx, cy, step, n, iterations, a, jw, hinv, i0, i1, j0, j1, pad, tmp,
                                  taps, r, exact)
    if not ok:
        return fail
    res = _rms(wgt, r, n, i0, i1, j0, j1)
    var = 0.25 * (hinv[0, 0] + hinv[1, 1] + 2 * hinv[0, 1])     # of (log kx + log ky) / 2
    return (True, math.exp(px), math.exp(py), tx * step, ty * step, res, res * math.sqrt(max(var, 0.0)))
