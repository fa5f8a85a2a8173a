"""One fused pass that carries the fast front end's state through a camera turn (gaze stabilisation).

:meth:`mlplc2.neuropils._fast_frontend.FastFrontEnd.compensate` resamples P(t-1), N(t-1) of both
channels and M-hat(t-1) of both channels and four directions (and the after-image's ON/OFF when
``Params.after_image`` is set): 11 (13) float32 planes under one homography. Warping each plane with
``cv2.warpPerspective`` (as the NumPy reference does, :func:`mlplc2.camera.warp`) recomputes every
pixel's source coordinate once per plane; :func:`carry_rows` computes it once and interpolates all
the planes there.

It is :func:`mlplc2.camera.warp` for every plane: bilinear, the source coordinate of an output
pixel (x, y) being ``inv(H) @ (x, y, 1)`` (``H``: previous frame -> this one), pixel centres at
integer coordinates. Where one of the four taps lies outside the previous frame, P(t-1) takes this
frame's grey value (``fill``: no change where nothing was seen before) and the other planes take 0
for that tap (OpenCV's constant border of 0), as OpenCV does. The one difference: OpenCV rounds the
source coordinate to 1/32 px (its fixed-point interpolation table); here it is exact (float64), so
values differ by up to ~1/64 px of the image's local gradient (docs/model.md, "Camera motion").
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

from ._fast import jit

__all__ = ["carry_rows"]


@intrinsic
def _fma32(typingctx, a, b, c):
    """LLVM's ``llvm.fma.f32``: float32 ``a * b + c`` rounded once (a fused multiply-add, one
    instruction where the CPU has FMA, as OpenCV's ``v_fma``)."""
    sig = types.float32(types.float32, types.float32, types.float32)

    def codegen(context, builder, signature, args):
        flt = ir.FloatType()
        fn = builder.module.declare_intrinsic("llvm.fma", [flt], ir.FunctionType(flt, [flt, flt, flt]))
        return builder.call(fn, args)

    return sig, codegen


@jit()
def _fma(a, b, c):
    """float32 ``a * b + c`` rounded once."""
    return _fma32(np.float32(a), np.float32(b), np.float32(c))


@jit()
def _lerp(src, i, dj, a, b):
    """Bilinear value of flat ``src`` at the tap ``i`` (top left), ``dj`` to the next row, weights
    ``a`` (x) and ``b`` (y), in OpenCV's order of operations (its warp kernels: along x, then y)."""
    one = np.uint64(1)
    p00 = src[i]
    p10 = src[i + dj]
    v0 = _fma(a, src[i + one] - p00, p00)
    v1 = _fma(a, src[i + dj + one] - p10, p10)
    return _fma(b, v1 - v0, v0)


@jit()
def _tap(src, r, c, h, w, a, b):
    """As :func:`_lerp` at top-left tap (r, c) of a 2-D ``src`` (h, w), taps outside read as 0."""
    zero = np.float32(0.0)
    p00 = src[r, c] if (0 <= r < h and 0 <= c < w) else zero
    p01 = src[r, c + 1] if (0 <= r < h and 0 <= c + 1 < w) else zero
    p10 = src[r + 1, c] if (0 <= r + 1 < h and 0 <= c < w) else zero
    p11 = src[r + 1, c + 1] if (0 <= r + 1 < h and 0 <= c + 1 < w) else zero
    v0 = _fma(a, p01 - p00, p00)
    v1 = _fma(a, p11 - p10, p10)
    return _fma(b, v1 - v0, v0)


@jit()
def carry_rows(hinv, gray, p_src, p_out, n_src, n_out, pad, m_src, m_out, on_src, on_out, off_src, off_out,
               after, y0, y1):
    """Rows [y0, y1) of every carried plane, interpolated at one source coordinate per pixel.

    ``hinv``: (3, 3) float64, this frame's pixels -> the previous frame's. ``p_src`` / ``p_out``:
    P(t-1) (H, W), its uncovered taps filled from ``gray``; ``n_src`` / ``n_out``: N(t-1) of both
    channels with a zero border of ``pad`` pixels, (2, H + 2 pad, W + 2 pad), only the inside
    written; ``m_src`` / ``m_out``: M-hat, row-interleaved (H, 2, 4, W); with ``after`` the ON and
    OFF planes too (else they are not touched). All C-contiguous; outputs must not share memory
    with the sources.
    """
    h, w = p_src.shape
    wp = w + 2 * pad
    n_plane = (h + 2 * pad) * wp
    pf = p_src.reshape(h * w)
    nf = n_src.reshape(2 * n_plane)
    mf = m_src.reshape(h * 8 * w)
    onf = on_src.reshape(h * w)
    offf = off_src.reshape(h * w)
    pof = p_out.reshape(h * w)
    nof = n_out.reshape(2 * n_plane)
    mof = m_out.reshape(h * 8 * w)
    onof = on_out.reshape(h * w)
    offof = off_out.reshape(h * w)
    m8 = m_src.reshape(h, 8, w)
    zero = np.float32(0.0)
    uw = np.uint64(w)
    uw8 = np.uint64(8 * w)
    uwp = np.uint64(wp)
    un_plane = np.uint64(n_plane)
    m0 = np.float32(hinv[0, 0])
    m3 = np.float32(hinv[1, 0])
    m6 = np.float32(hinv[2, 0])
    for y in range(y0, y1):
        # as OpenCV's warpPerspective (float32 coordinates, fused multiply-adds)
        mx = np.float32(y) * np.float32(hinv[0, 1]) + np.float32(hinv[0, 2])
        my = np.float32(y) * np.float32(hinv[1, 1]) + np.float32(hinv[1, 2])
        mw = np.float32(y) * np.float32(hinv[2, 1]) + np.float32(hinv[2, 2])
        for x in range(w):
            xf = np.float32(x)
            q = _fma(m6, xf, mw)
            sx = _fma(m0, xf, mx) / q
            sy = _fma(m3, xf, my) / q
            o = np.uint64(y * w + x)
            on_ = np.uint64((y + pad) * wp + x + pad)
            o8 = np.uint64(y * 8 * w + x)
            if not (sx >= -1.0 and sx < w and sy >= -1.0 and sy < h):   # all four taps outside (or NaN)
                pof[o] = gray[y, x]
                nof[on_] = zero
                nof[on_ + un_plane] = zero
                for k in range(8):
                    mof[o8 + np.uint64(k) * uw] = zero
                if after:
                    onof[o] = zero
                    offof[o] = zero
                continue
            c0 = int(sx)          # floor (sx > -1, so truncation is off by one only below 0)
            r0 = int(sy)
            if c0 > sx:
                c0 -= 1
            if r0 > sy:
                r0 -= 1
            fx = np.float32(c0)
            fy = np.float32(r0)
            a = sx - fx
            b = sy - fy
            if c0 >= 0 and c0 < w - 1 and r0 >= 0 and r0 < h - 1:   # all four taps inside
                # unsigned flat indices: no negative-index wraparound test on each of the 44 reads
                i = np.uint64(r0 * w + c0)
                pof[o] = _lerp(pf, i, uw, a, b)
                j = np.uint64((r0 + pad) * wp + c0 + pad)
                nof[on_] = _lerp(nf, j, uwp, a, b)
                nof[on_ + un_plane] = _lerp(nf, j + un_plane, uwp, a, b)
                i8 = np.uint64(r0 * 8 * w + c0)
                for k in range(8):
                    uk = np.uint64(k) * uw
                    mof[o8 + uk] = _lerp(mf, i8 + uk, uw8, a, b)
                if after:
                    onof[o] = _lerp(onf, i, uw, a, b)
                    offof[o] = _lerp(offf, i, uw, a, b)
            else:   # some taps outside: P(t-1) filled from this frame, the others read 0 there
                pof[o] = gray[y, x]
                for c in range(2):
                    nof[on_ + np.uint64(c) * un_plane] = _tap(n_src[c, pad:pad + h, pad:pad + w], r0, c0, h, w, a, b)
                for k in range(8):
                    mof[o8 + np.uint64(k) * uw] = _tap(m8[:, k, :], r0, c0, h, w, a, b)
                if after:
                    onof[o] = _tap(on_src, r0, c0, h, w, a, b)
                    offof[o] = _tap(off_src, r0, c0, h, w, a, b)
