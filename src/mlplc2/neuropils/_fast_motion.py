"""Compiled (Numba) medulla + lobula plate of the fast front end (Eq. 8-12), fused in one pass.

:func:`motion_rows` computes, row by row, what ``medulla.motion_detectors`` and
``lobula_plate.local_motion`` compute for the whole frame: the delays D_s = a_s N(t) + b_s N(t-1)
(Eq. 8), the correlators (Eq. 9), the mean over the distances and the two-tap filter with the
state M-hat (Eq. 10), the power ``T ** gamma`` (Eq. 11), opponency, Leaky ReLU, gain and the
magnitude LM (Eq. 11-12), with the float32 operations of the reference in the reference's
order (no fused multiply-add: ``fastmath=False``); every intermediate lives in row buffers,
only the state and the LM maps are planes. :class:`mlplc2.neuropils._fast_frontend.FastFrontEnd`
runs it as phase 3 of each band.

The only difference from the reference is ``x ** gamma`` for exponents other than 0.5, 1 and 2:
a vectorised float32 power (:func:`_power`, compiled with fused multiply-adds, relative error
~1e-6 like NumPy's own float32 power; :func:`pow_mode` picks the exact cases), so the LM maps
agree to ~1e-6 relative (``tests/test_fast.py``).
"""

from __future__ import annotations

import numpy as np

from ._fast import jit

__all__ = ["motion_rows", "pow_mode"]

_F32 = np.float32
U64 = np.uint64


# The fused pass is a loop over rows that calls one small kernel per row loop. Each takes whole
# arrays and unsigned offsets (no views: no reference counting; no negative-index wrap-around)
# and writes at most two arrays (LLVM's run-time alias checks stay within its limit), so LLVM
# vectorises every one; as one big function, register pressure made LLVM spill in the loops.
# Per row and channel: D_s of the row for every distance (:func:`_d_rows`), then two kernels
# (right/left, down/up) that loop over x with the distances unrolled inside (N_c is the length
# of a tuple, a compile-time constant), so the sums over s stay in registers and each pixel's
# D_s is formed once for the centre and the horizontal far points; Eq. 10 is applied in the
# same loop (:func:`_eq10`). Then the power (:func:`_power`) and Eq. 11-12 (:func:`_lobula_row`).
@jit(fastmath={"contract"})
def _power(t, base, n, g, mode, mb, kb, pb):
    """Eq. 11: t[base:base + n] = t ** g in place (t >= 0), vectorised.

    ``mode`` (:func:`pow_mode`): 1 sqrt (g = 0.5), 2 identity (g = 1), 3 square (g = 2), which
    is what NumPy does for these exponents (bit-identical); 0 any other g: log2/exp2 polynomials
    in float32 (fused multiply-adds allowed: ``fastmath={"contract"}``, which leaves the sqrt
    and the square exact), relative error ~1e-6 for normal results (NumPy's own float32
    power: ~2e-6; the rounding of g * log2(x) dominates for tiny x);
    subnormal inputs or results give 0. ``mb``, ``kb`` (int32), ``pb`` (float32): scratch.
    """
    if mode == 1:
        for j in range(n):
            t[base + j] = np.sqrt(t[base + j])
        return
    if mode == 2:
        return
    if mode == 3:
        for j in range(n):
            t[base + j] = t[base + j] * t[base + j]
        return
    one = _F32(1.0)
    ti = t.view(np.int32)
    mf = mb.view(np.float32)
    pbi = pb.view(np.int32)
    for j in range(n):
        mb[j] = (ti[base + j] & 0x007FFFFF) | 0x3F800000
    for j in range(n):
        xi = ti[base + j]
        e = _F32((xi >> 23) - 127)
        mm = mf[j]
        big = mm > _F32(1.4142135)
        mm = mm * _F32(0.5) if big else mm
        e = e + one if big else e
        z = (mm - one) / (mm + one)
        z2 = z * z
        # log2(m) = 2 atanh(z) / ln 2 with |z| <= 0.172
        l2 = _F32(2.8853900817779268) * z * (one + z2 * (_F32(0.3333333333333333) + z2 * (
            _F32(0.2) + z2 * _F32(0.14285714285714285))))
        yy = g * (e + l2)
        yk = np.floor(yy + _F32(0.5))
        f = (yy - yk) * _F32(0.6931471805599453)
        p = one + f * (one + f * (_F32(0.5) + f * (_F32(0.16666666666666666) + f * (
            _F32(0.041666666666666664) + f * (_F32(0.008333333333333333) + f * _F32(0.001388888888888889))))))
        pb[j] = p
        ki = np.int32(yk)
        kb[j] = ki if xi >= 0x00800000 else np.int32(-1000)
    for j in range(n):
        kk = kb[j]
        v = pbi[j] + (kk << 23)
        v = v if kk >= -125 else np.int32(0)
        v = v if kk <= 127 else np.int32(0x7F800000)
        ti[base + j] = v


@jit()
def _lobula_row(t, lm_flat, row, plane, gain, slope, w):
    """Eq. 11-12 on one row, fused: r - l and d - u with r = T4_r^g1 + T5_r^g2 etc. (``t``: the
    8 rows of powered T), LM_r = g f(r - l), LM_l = g f(l - r), LM_d, LM_u likewise (f the
    Leaky ReLU), LM = sqrt(max(LM_r, LM_l)^2 + max(LM_d, LM_u)^2), written to the five planes
    of ``lm_flat`` at ``row + k * plane``."""
    zero = _F32(0.0)
    for x in range(w):
        hz = (t[x] + t[U64(4) * w + x]) - (t[w + x] + t[U64(5) * w + x])
        vt = (t[U64(2) * w + x] + t[U64(6) * w + x]) - (t[U64(3) * w + x] + t[U64(7) * w + x])
        nh = -hz
        nv = -vt
        vr = gain * (hz if hz >= zero else slope * hz)
        vl = gain * (nh if nh >= zero else slope * nh)
        vd = gain * (vt if vt >= zero else slope * vt)
        vu = gain * (nv if nv >= zero else slope * nv)
        j = row + x
        lm_flat[j] = vr
        lm_flat[j + plane] = vl
        lm_flat[j + U64(2) * plane] = vd
        lm_flat[j + U64(3) * plane] = vu
        hh = vr if vr >= vl else vl
        vv = vd if vd >= vu else vu
        lm_flat[j + U64(4) * plane] = np.sqrt(hh * hh + vv * vv)


@jit()
def _d_rows(flat_n, flat_p, row, a, b, drow, wp):
    """Eq. 8 on one padded row: drow[s * wp + x] = a_s N(t) + b_s N(t-1) at ``row + x``, every
    distance s, the whole padded width (zero in the border)."""
    for s in range(len(a)):
        a_s = a[s]
        b_s = b[s]
        o = U64(s) * wp
        for x in range(wp):
            drow[o + x] = a_s * flat_n[row + x] + b_s * flat_p[row + x]


@jit(inline="always")
def _eq10(total, m_flat, j, t, k, ao, bo, nc_div, average):
    """Eq. 10 for one pixel and direction: mean over the distances, two-tap filter with
    M-hat(t-1) = ``m_flat[j]`` (replaced by M-hat(t)), rectified T into ``t[k]``."""
    v = total / nc_div if average else total
    tv = ao * v + bo * m_flat[j]
    m_flat[j] = v
    t[k] = tv if tv > _F32(0.0) else _F32(0.0)


@jit()
def _corr_h(flat_n, centre, wp, drow, pad, a, beta, m_flat, m1, m2, t, t1, t2, ao, bo, nc_div, average, w):
    """Eq. 8-9 for one row of one channel, directions right (``o1``) and left (``o2``), all
    distances at once.

    ``centre + x`` (x < w) is the pixel in the padded, flattened N(t) planes; ``drow`` holds
    D_s of this row (:func:`_d_rows`). ``a`` is a tuple: its length N_c is a compile-time
    constant, so the loop over the distances is unrolled and the sums stay in registers
    (two written arrays per kernel: LLVM's run-time alias checks stay within its limit). The
    sums are formed in the reference's order (0, then s = 1..N_c). Then Eq. 10 as in
    :func:`_eq10`: M-hat(t-1) at ``m_flat[m1 + x]`` (right; ``m2``: left) is replaced by
    M-hat(t) and the rectified T goes to ``t[t1 + x]`` (``t2``).
    """
    nc = len(a)
    zero = _F32(0.0)
    for x in range(w):
        i = centre + x
        bnx = beta * flat_n[i]
        sr = zero
        sl = zero
        for s in range(nc):
            sd = U64(s + 1)
            jd = U64(s) * wp + pad + x
            d = drow[jd]
            nf = flat_n[i + sd]
            sr += ((nf - bnx) * d) * drow[jd + sd]
            nf = flat_n[i - sd]
            sl += ((nf - bnx) * d) * drow[jd - sd]
        _eq10(sr, m_flat, m1 + x, t, t1 + x, ao, bo, nc_div, average)
        _eq10(sl, m_flat, m2 + x, t, t2 + x, ao, bo, nc_div, average)


@jit()
def _corr_v(flat_n, flat_p, centre, wp, drow, pad, a, b, beta, m_flat, m1, m2, t, t1, t2, ao, bo, nc_div,
            average, w):
    """Like :func:`_corr_h` for directions down (``m1``, ``t1``) and up (``m2``, ``t2``): the
    far points' D_s = a_s N(t) + b_s N(t-1) is formed from the rows s above and below (same
    operations)."""
    nc = len(a)
    zero = _F32(0.0)
    for x in range(w):
        i = centre + x
        bnx = beta * flat_n[i]
        sd_ = zero
        su = zero
        for s in range(nc):
            sd = U64(s + 1)
            a_s = a[s]
            b_s = b[s]
            d = drow[U64(s) * wp + pad + x]
            j = i + sd * wp
            nf = flat_n[j]
            sd_ += ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])
            j = i - sd * wp
            nf = flat_n[j]
            su += ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])
        _eq10(sd_, m_flat, m1 + x, t, t1 + x, ao, bo, nc_div, average)
        _eq10(su, m_flat, m2 + x, t, t2 + x, ao, bo, nc_div, average)


@jit()
def motion_rows(n_cur, n_prev, pad, m, lm, y0, y1, a, b, ao, bo, beta, nc_div, average,
                 g_on, g_off, mode_on, mode_off, gain, slope):
    """Eq. 8-12 for rows [y0, y1), both channels, all directions and distances, fused.

    n_cur, n_prev : (2, H + 2 pad, W + 2 pad) contrast-normalised N(t), N(t-1) of the ON and
        OFF channels, frame pixel (y, x) at (y + pad, x + pad), zero in the border of width
        ``pad`` >= N_c: a correlator whose far point is outside the frame then adds
        (0 - beta N) D * 0 = 0, the reference's zero padding, without a bounds test.
    m : (H, 2, 4, W) M-hat(t-1) per row, channel and direction (r, l, d, u), the eight rows
        of a frame row next to each other (one memory stream instead of eight); overwritten
        with M-hat(t) (the state of Eq. 10).
    lm : (5, H, W) output LM_r, LM_l, LM_d, LM_u, LM.
    a, b : tuples of N_c float32 delay coefficients a_s and 1 - a_s of Eq. 8.
    mode_on, mode_off : how ``T ** gamma`` is computed (:func:`_power`).

    The float32 operations are those of ``medulla.motion_detectors`` and
    ``lobula_plate.local_motion`` in the same order (the reference), row by row; only row-sized
    scratch buffers are allocated.
    """
    h = m.shape[0]
    w = m.shape[3]
    wu = U64(w)
    wp = U64(w + 2 * pad)
    plane = U64(h * w)
    nc = len(a)
    drow = np.empty(nc * (w + 2 * pad), np.float32)
    t = np.empty(8 * w, np.float32)  # T of channel c, direction k at (c * 4 + k) * w + x
    mb = np.empty(4 * w, np.int32)
    kb = np.empty(4 * w, np.int32)
    pb = np.empty(4 * w, np.float32)
    m_flat = m.reshape(m.size)
    lm_flat = lm.reshape(lm.size)
    flat_n = n_cur.reshape(n_cur.size)
    flat_p = n_prev.reshape(n_prev.size)
    plane_p = U64(n_cur.shape[1]) * wp
    pu = U64(pad)
    for y in range(y0, y1):
        yu = U64(y)
        yp = yu + pu
        for c in range(2):
            cu = U64(c)
            row = cu * plane_p + yp * wp
            _d_rows(flat_n, flat_p, row, a, b, drow, wp)
            base = cu * U64(4) * wu  # T of this channel in t
            mo = (yu * U64(2) + cu) * U64(4) * wu  # its M-hat rows (r, l, d, u)
            _corr_h(flat_n, row + pu, wp, drow, pu, a, beta, m_flat, mo, mo + wu, t, base, base + wu,
                    ao, bo, nc_div, average, wu)
            _corr_v(flat_n, flat_p, row + pu, wp, drow, pu, a, b, beta, m_flat, mo + U64(2) * wu,
                    mo + U64(3) * wu, t, base + U64(2) * wu, base + U64(3) * wu, ao, bo, nc_div, average, wu)
            if c == 0:
                _power(t, base, U64(4) * wu, g_on, mode_on, mb, kb, pb)
            else:
                _power(t, base, U64(4) * wu, g_off, mode_off, mb, kb, pb)
        _lobula_row(t, lm_flat, yu * wu, plane, gain, slope, wu)


def pow_mode(g: float) -> int:
    """How :func:`_power` computes ``T ** g``: 1 sqrt (g = 0.5), 2 identity (g = 1), 3 square
    (g = 2), 0 any other g (the float32 polynomials)."""
    return {0.5: 1, 1.0: 2, 2.0: 3}.get(float(np.float32(g)), 0)
