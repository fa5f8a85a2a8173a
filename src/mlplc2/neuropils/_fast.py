"""Fast front end of the LPLC2 family (Eq. 1-12): OpenCV Gaussians + fused Numba kernels.

:class:`FastFrontEnd` computes exactly what the reference :class:`mlplc2.neuropils.frontend.FrontEnd`
computes, with the same float32 arithmetic in the same order, so that everything up to the
T4/T5 outputs is bit-identical to it:

* the Gaussians of Eq. 2, 3 and 7 are the same ``cv2.sepFilter2D`` calls (zero outside the
  frame), and the tanh of Eq. 6 is the same ``numpy.tanh``. This matters: the square root of
  Eq. 11 (gamma_2 = 0.5) amplifies a rounding difference of 1e-7 in a T5 value near zero into a
  relative LM difference of up to ~1e-4, so a Gaussian that merely rounds differently (another
  summation order, float64) would already use up the whole tolerance;
* the delays, correlators, two-tap filters, opponency, Leaky ReLU, gain and magnitude
  (Eq. 8-12) run in one fused Numba pass over the rows (:func:`_motion_rows`: every
  intermediate lives in row buffers, only the state and the LM maps are planes), with the
  operations of the reference in the reference's order (no fused multiply-add:
  ``fastmath=False``);
* the only difference is ``x ** gamma`` for exponents other than 0.5, 1 and 2: a vectorised
  float32 power (:func:`_power`, compiled with fused multiply-adds, relative error ~1e-6 like
  NumPy's own float32 power), so the LM maps agree to ~1e-6 relative (``tests/test_fast.py``).

Work is split into horizontal bands, one per thread (``numba.get_num_threads()``, so
``numba.set_num_threads`` and ``mlplc2 bench --threads`` set it). Each band runs three
phases; a barrier separates them because each needs a few rows of its neighbours:

1. L = P(t) - P(t-1) on the band plus r_i rows of context, E and I (``sepFilter2D``), vDoG and
   ON/OFF for the band's rows (Eq. 1-5);
2. K_c * ON and K_c * OFF on the band plus r_c rows, N = tanh(ON / (epsilon + K_c * ON))
   (Eq. 6-7); with the relative floor of ``Params.n_floor`` (on by default) N is formed on
   ``n_floor_radius`` more rows of context and set to 0 where it is below ``n_floor`` times
   its local maximum (the reference's own ``medulla.local_max``, an OpenCV dilation), so no
   extra barrier is needed;
3. the fused kernel :func:`_motion_rows` (Eq. 8-12) for the band's rows.

OpenCV and NumPy release the GIL and every kernel is ``nogil``, so the bands run in parallel
in a small thread pool: band 0 on the calling thread, each other band on a pool thread that
runs all three phases. The barriers spin without the GIL (:func:`_spin_wait`, ~1 us per poll):
waking a sleeping thread costs ~35 us here, and three wake-ups per frame used to cost 10-15 %
of a 320x240 frame. All state is float32; the planes per stream are listed in
:data:`PLANES`.
"""

from __future__ import annotations

import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import cv2
import numba
import numpy as np

from .._validation import check_int
from .frontend import set_coefficients
from .lobula_plate import LocalMotion
from .medulla import local_max
from ..params import Params

__all__ = ["FastFrontEnd", "quadrant_sums", "quadrant_sums_all", "set_threads", "jit", "PLANES",
           "plane_traffic"]

_F32 = np.float32
U64 = np.uint64


def jit(**options):
    """``numba.njit`` with an on-disk cache when one can be written, without one otherwise.

    Numba caches next to the source (``__pycache__``) or, when that is read-only (a
    system-wide install), in ``NUMBA_CACHE_DIR`` / the user's cache folder. Where no
    location is writable ``cache=True`` raises at decoration time; compile without it.
    """
    base = dict(fastmath=False, nogil=True, error_model="numpy")
    base.update(options)

    def deco(func):
        try:
            return numba.njit(cache=True, **base)(func)
        except (RuntimeError, OSError):  # pragma: no cover - depends on the file system
            return numba.njit(cache=False, **base)(func)

    return deco


# ---------------------------------------------------------------------------
# Phase 1: retina and lamina (Eq. 1-5)
# ---------------------------------------------------------------------------
@jit()
def _retina_rows(gray, p_prev, p_next, l_band, ys, ye, y0, y1):
    """L = P(t) - P(t-1) on rows [ys, ye) into ``l_band``; P(t) rows [y0, y1) into ``p_next``."""
    w = gray.shape[1]
    for y in range(ys, ye):
        g = gray[y]
        p = p_prev[y]
        out = l_band[y - ys]
        for x in range(w):
            out[x] = g[x] - p[x]
    for y in range(y0, y1):
        g = gray[y]
        q = p_next[y]
        for x in range(w):
            q[x] = g[x]


@jit()
def _vdog_rows(e_band, e_off, i_band, i_off, on, off, y0, y1, w_i, after, use_prev):
    """Eq. 4-5 on rows [y0, y1): sign(E) max(|E| - w_i |I|, 0), split into ON and OFF.

    ``e_band[y - e_off]`` and ``i_band[y - i_off]`` are E and I of frame row y. With
    ``use_prev`` the after-image ``after`` times the previous ON/OFF (held in ``on``/``off``)
    is added, as in :func:`mlplc2.neuropils.lamina.on_off`.
    """
    zero = _F32(0.0)
    w = on.shape[1]
    for y in range(y0, y1):
        er = e_band[y - e_off]
        ir = i_band[y - i_off]
        onr = on[y]
        offr = off[y]
        for x in range(w):
            e = er[x]
            mag = abs(e) - w_i * abs(ir[x])
            mag = mag if mag > zero else zero
            lv = math.copysign(mag, e)
            a = lv if lv > zero else zero
            b = -lv if -lv > zero else zero
            if use_prev:
                a = a + after * onr[x]
                b = b + after * offr[x]
            onr[x] = a
            offr[x] = b


@jit()
def _ratio_rows(sig, k_band, k_off, n_pad, c, pad, y0, y1, eps):
    """Eq. 6 before the tanh: N = sig / (epsilon + K_c * sig) on rows [y0, y1), written to
    channel ``c`` of the zero-padded planes ``n_pad`` (frame pixel (y, x) at (y + pad, x + pad))."""
    U = np.uint64
    wu = U(sig.shape[1])
    pu = U(pad)
    cu = U(c)
    for y in range(y0, y1):
        yu = U(y)
        yk = U(y - k_off)
        yo = U(y + pad)
        for x in range(wu):
            n_pad[cu, yo, x + pu] = sig[yu, x] / (eps + k_band[yk, x])


@jit()
def _ratio_band(sig, k_band, k_off, out, o_off, y0, y1, eps):
    """Eq. 6 before the tanh on rows [y0, y1) into ``out[y - o_off]`` (a band's scratch, for
    the relative floor of ``Params.n_floor``); same operation as :func:`_ratio_rows`."""
    w = sig.shape[1]
    for y in range(y0, y1):
        s = sig[y]
        k = k_band[y - k_off]
        o = out[y - o_off]
        for x in range(w):
            o[x] = s[x] / (eps + k[x])


@jit()
def _floor_rows(nb, lmax, off, n_pad, c, pad, y0, y1, floor):
    """The relative floor of ``Params.n_floor`` (``medulla.contrast_normalise``) on rows
    [y0, y1): N = 0 where N < floor * (local maximum of N), else N; from ``nb[y - off]`` (with
    ``lmax[y - off]``) into channel ``c`` of the padded planes ``n_pad``."""
    zero = _F32(0.0)
    w = U64(nb.shape[1])
    wp = U64(n_pad.shape[2])
    src = nb.reshape(nb.size)
    mx = lmax.reshape(lmax.size)
    dst = n_pad.reshape(n_pad.size)
    for y in range(y0, y1):
        i0 = U64(y - off) * w
        o0 = (U64(c) * U64(n_pad.shape[1]) + U64(y + pad)) * wp + U64(pad)
        for x in range(w):
            v = src[i0 + x]
            dst[o0 + x] = zero if v < floor * mx[i0 + x] else v


# ---------------------------------------------------------------------------
# Phase 3: the fused medulla + lobula-plate kernel (Eq. 8-12)
# ---------------------------------------------------------------------------
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

    ``mode`` (:func:`_pow_mode`): 1 sqrt (g = 0.5), 2 identity (g = 1), 3 square (g = 2), which
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
def _motion_rows(n_cur, n_prev, pad, m, lm, y0, y1, a, b, ao, bo, beta, nc_div, average,
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


# ---------------------------------------------------------------------------
# Attention-field helper (Eq. 14). Eq. 13 stays mlplc2.neuropils.attention.argmax_outside: its copy and
# NumPy's SIMD argmax measured 2-3x faster than a masked argmax kernel here.
# ---------------------------------------------------------------------------
@jit()
def _quadrant_sums_kernel(a_r, a_l, a_d, a_u, fields, disc, out):
    """Eq. 14 for every field (x, y, r): Q1..Q4 in float64 (square or disc quadrants)."""
    h, w = a_r.shape
    for k in range(fields.shape[0]):
        cx = fields[k, 0]
        cy = fields[k, 1]
        r = fields[k, 2]
        q1 = 0.0
        q2 = 0.0
        q3 = 0.0
        q4 = 0.0
        for y in range(max(cy - r, 0), min(cy + r + 1, h)):
            if y == cy:
                continue
            dy = y - cy
            if disc:
                rem = r * r - dy * dy
                half = int(math.sqrt(rem))
                while half * half > rem:
                    half -= 1
                while (half + 1) * (half + 1) <= rem:
                    half += 1
            else:
                half = r
            up = y < cy
            vrow = a_u[y] if up else a_d[y]
            rr = a_r[y]
            lr = a_l[y]
            sr = 0.0
            for x in range(max(cx + 1, 0), min(cx + half + 1, w)):
                sr += np.float64(rr[x]) + np.float64(vrow[x])
            sl = 0.0
            for x in range(max(cx - half, 0), min(cx, w)):
                sl += np.float64(lr[x]) + np.float64(vrow[x])
            if up:
                q1 += sr
                q2 += sl
            else:
                q4 += sr
                q3 += sl
        out[k, 0] = q1
        out[k, 1] = q2
        out[k, 2] = q3
        out[k, 3] = q4


def quadrant_sums(lm: LocalMotion, cx: int, cy: int, r: int, shape: str = "square"
                  ) -> tuple[float, float, float, float]:
    """Same as :func:`mlplc2.neuropils.attention.quadrant_sums` (to float64 rounding), in one pass."""
    out = np.zeros((1, 4), np.float64)
    _quadrant_sums_kernel(lm.r, lm.l, lm.d, lm.u, np.array([[cx, cy, r]], np.int64), shape == "disc", out)
    return (float(out[0, 0]), float(out[0, 1]), float(out[0, 2]), float(out[0, 3]))


def quadrant_sums_all(lm: LocalMotion, fields, shape: str = "square") -> np.ndarray:
    """Eq. 14 for several fields at once: (n, 4) array of Q1..Q4 (``fields``: (x, y, r) rows)."""
    f = np.asarray(fields, dtype=np.int64).reshape(-1, 3)
    out = np.zeros((f.shape[0], 4), np.float64)
    _quadrant_sums_kernel(lm.r, lm.l, lm.d, lm.u, f, shape == "disc", out)
    return out


# ---------------------------------------------------------------------------
# Threads
# ---------------------------------------------------------------------------
_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0
_POOL_LOCK = threading.Lock()

#: Held while one frame's bands run on the shared pool. The bands of a frame wait for each
#: other (spin barriers); without it, two streams stepping in two threads could interleave
#: their band tasks in the pool's queue so that every worker waits for a sibling still
#: queued behind the other stream's tasks: a deadlock (3 or more bands).
_BANDS_LOCK = threading.Lock()


def _pool(n: int) -> ThreadPoolExecutor:
    global _POOL, _POOL_SIZE
    with _POOL_LOCK:
        if _POOL is None or _POOL_SIZE < n:
            old = _POOL
            _POOL = ThreadPoolExecutor(max_workers=n, thread_name_prefix="mlplc2-band")
            _POOL_SIZE = n
            if old is not None:
                old.shutdown(wait=False)
        return _POOL


def _copy_slice(stack: np.ndarray, lo: int, hi: int) -> None:
    for k in range(stack.shape[0] - 1):
        np.copyto(stack[k + 1, lo:hi], stack[k, lo:hi])


def copy_chain(stack: np.ndarray, threads: int | None = None) -> None:
    """Memory-bandwidth probe of ``mlplc2 bench``: copy plane k into plane k + 1 of the
    (N + 1, H * W) ``stack`` for k = 0..N-1 with ``np.copyto`` (memcpy), split like the front
    end's bands: one slice per thread (default ``numba.get_num_threads()``), same thread pool."""
    size = stack.shape[1]
    n = max(1, int(numba.get_num_threads() if threads is None else threads))
    cuts = [size * k // n for k in range(n + 1)]
    if n == 1:
        _copy_slice(stack, 0, size)
        return
    futs = [_pool(n - 1).submit(_copy_slice, stack, lo, hi) for lo, hi in zip(cuts[1:-1], cuts[2:])]
    _copy_slice(stack, cuts[0], cuts[1])
    for f in futs:
        f.result()


#: ``arrive`` value of a band that finished the frame (or failed).
_DONE = 1 << 30

#: Polls (~0.5 us each) before the spin barrier falls back to sleeping.
_POLLS = 20000

# libc's sched_yield, called by symbol (resolved in the process at link time; unlike a ctypes
# pointer, this keeps the kernel cacheable).
_sched_yield = numba.types.ExternalFunction("sched_yield", numba.types.int32())


@jit()
def _spin(arrive, stage, polls):
    """Poll (``sched_yield`` between polls, which also keeps LLVM from hoisting the loads) until
    every entry of ``arrive`` is at least ``stage``, at most ``polls`` times; True when reached."""
    n = arrive.shape[0]
    for _ in range(polls):
        lo = arrive[0]
        for k in range(1, n):
            v = arrive[k]
            lo = v if v < lo else lo
        if lo >= stage:
            return True
        _sched_yield()
    return False


_SPIN_OK: bool | None = None


def _spin_ok() -> bool:
    """Whether :func:`_spin` compiles here (``sched_yield`` is a POSIX symbol); checked once."""
    global _SPIN_OK
    if _SPIN_OK is None:
        try:
            _spin(np.zeros(1, np.int64), 0, 1)
            _SPIN_OK = True
        except Exception:  # pragma: no cover - platforms without sched_yield
            _SPIN_OK = False
    return _SPIN_OK


def _spin_wait(arrive: np.ndarray, stage: int) -> None:
    """Spin barrier: wait, without the GIL, until every band's ``arrive`` entry is >= ``stage``.

    Waking a sleeping thread (a future, a lock) costs ~35 us here, as much as a phase of a
    small frame; a poll costs ~1 us. After ~20000 polls (a band held up: a busy machine) it
    sleeps 50 us between rounds of polls instead of keeping a shared core busy.
    """
    if _spin(arrive, stage, _POLLS):
        return
    while not _spin(arrive, stage, 20):
        time.sleep(5e-5)


def set_threads(n: int) -> None:
    """Use ``n`` threads for the fast front end (Numba's thread count) and OpenCV.

    ``n`` must be between 1 and Numba's ``NUMBA_NUM_THREADS`` (by default the number of cores).
    """
    limit = int(numba.config.NUMBA_NUM_THREADS)
    n = check_int(n, f"threads (1 to {limit} on this machine: the number of cores, or NUMBA_NUM_THREADS)",
                  minimum=1, maximum=limit)
    numba.set_num_threads(n)
    cv2.setNumThreads(int(n))


#: Smallest number of pixels per band: below it, threads cost more than they save.
MIN_BAND_PIXELS = 24_000

#: The float32 planes of one stream (name, count) and what they hold.
PLANES: tuple[tuple[str, int, str], ...] = (
    ("P(t-1), P(t)", 2, "previous / next grey frame (double buffer)"),
    ("L band", 1, "photoreceptor change, per band with r_i rows of context"),
    ("E, I bands", 2, "excitatory and inhibitory Gaussians, per band"),
    ("ON, OFF", 2, "lamina outputs (Eq. 5)"),
    ("K_c ON, K_c OFF bands", 2, "contrast-normalisation Gaussians, per band"),
    ("N(t), N(t-1)", 4, "contrast-normalised ON/OFF, now and one frame ago"),
    ("N band, local max", 2, "only with Params.n_floor > 0: N of a band with n_floor_radius rows "
                             "of context, and its local maximum"),
    ("M-hat", 8, "correlator state per channel and direction (Eq. 10)"),
    ("LM", 5, "LM_r, LM_l, LM_d, LM_u, LM (the output)"),
)


def plane_count(floor: bool = False) -> int:
    """Float32 planes one stream touches (:data:`PLANES`; the floor's two only with ``floor``)."""
    return sum(count for name, count, _ in PLANES if floor or not name.startswith("N band"))


def plane_traffic(floor: bool = False) -> dict[str, int]:
    """Plane-sized reads and writes per frame of :class:`FastFrontEnd` (counted from the kernels).

    Phase 1: read gray, P(t-1), write L, write P(t) (4); E and I read L and write (4); vDoG
    reads E, I and writes ON, OFF (4). Phase 2: the K_c filters read ON/OFF and write (4); the
    ratio reads ON, OFF, K_c ON, K_c OFF and writes N (6); tanh reads and writes N (4); with
    the relative floor of ``Params.n_floor`` (``floor``; off by default) the local maximum reads N
    and writes its result (4) and the floor reads both and writes N (6).
    Phase 3: reads N(t), N(t-1) (4), reads and writes M-hat (16), writes LM (5).
    Attention: Eq. 13 copies LM and reads the copy (3; the quadrant sums touch only the fields).
    """
    return {"phase1": 12, "phase2": 24 if floor else 14, "phase3": 25, "attention": 3}


# ---------------------------------------------------------------------------
# The front end
# ---------------------------------------------------------------------------
def _pow_mode(g: float) -> int:
    return {0.5: 1, 1.0: 2, 2.0: 3}.get(float(np.float32(g)), 0)


class FastFrontEnd:
    """Eq. 1-12 like :class:`mlplc2.neuropils.frontend.FrontEnd`, fast (see the module docstring).

    Same constructor, attributes (``params``, ``fps``, ``alphas``, ``alpha_out``, ``k_e``,
    ``k_i``, ``k_c``), :meth:`step` and :meth:`reset`. The returned maps are new arrays
    every frame (a caller may keep them).
    """

    backend = "numba"

    def __init__(self, params: Params, fps: float):
        set_coefficients(self, params, fps)
        p = params
        # float32 coefficients exactly as the reference forms them
        a = np.array([np.float32(x) for x in self.alphas], np.float32)
        self._a = a
        self._b = (np.float32(1) - a).astype(np.float32)
        # tuples for the kernels: N_c becomes a compile-time constant (unrolled distance loop)
        self._a_t = tuple(np.float32(v) for v in a)
        self._b_t = tuple(np.float32(v) for v in self._b)
        self._ao = np.float32(self.alpha_out)
        self._bo = np.float32(1) - self._ao
        self._beta = np.float32(p.beta)
        self._nc_div = np.float32(len(self.alphas))
        self._w_i = np.float32(p.w_i)
        self._after = np.float32(p.after_image)
        self._eps = np.float32(p.epsilon)
        self._floor = np.float32(p.n_floor)
        # relative floor (Params.n_floor > 0): N is compared with its local maximum within
        # n_floor_radius px, so phase 2 forms N on that many rows of context as well
        self._floor_r = int(p.n_floor_radius) if p.n_floor else 0
        self._g_on = np.float32(p.gamma_on)
        self._g_off = np.float32(p.gamma_off)
        self._mode_on = _pow_mode(p.gamma_on)
        self._mode_off = _pow_mode(p.gamma_off)
        self._gain = np.float32(p.lm_gain)
        self._slope = np.float32(p.leaky_slope)
        self.reset()

    def reset(self) -> None:
        self._shape = None
        self._first = True
        self._bands = None

    # -- buffers ----------------------------------------------------------------
    def _allocate(self, h: int, w: int, nbands: int) -> None:
        p = self.params
        self._shape = (h, w)
        self._p = [np.empty((h, w), np.float32), np.empty((h, w), np.float32)]
        self._on = np.zeros((h, w), np.float32)
        self._off = np.zeros((h, w), np.float32)
        pad = self._pad = p.n_c  # zero border: correlator far points outside the frame read 0
        self._n = np.zeros((2, h + 2 * pad, w + 2 * pad), np.float32)
        self._n_prev = np.zeros((2, h + 2 * pad, w + 2 * pad), np.float32)
        self._m_rows = np.zeros((h, 2, 4, w), np.float32)  # what the kernel uses
        self._m = self._m_rows.transpose(1, 2, 0, 3)  # (2, 4, H, W) view: channel, direction
        self._plan(nbands)

    def _plan(self, nbands: int) -> None:
        """Split rows into ``nbands`` bands and allocate each band's scratch planes."""
        h, w = self._shape
        p = self.params
        edges = [round(k * h / nbands) for k in range(nbands + 1)]
        bands = []
        for y0, y1 in zip(edges[:-1], edges[1:]):
            ys, ye = max(y0 - p.r_i, 0), min(y1 + p.r_i, h)
            es, ee = max(y0 - p.r_e, 0), min(y1 + p.r_e, h)
            fr = self._floor_r
            ns, ne = max(y0 - fr, 0), min(y1 + fr, h)  # rows of N the floor needs
            cs, ce = max(ns - p.r_c, 0), min(ne + p.r_c, h)
            bands.append(dict(
                y0=y0, y1=y1, ys=ys, ye=ye, es=es, ee=ee, cs=cs, ce=ce, ns=ns, ne=ne,
                nb=np.empty((ne - ns, w), np.float32) if fr else None,
                l=np.empty((ye - ys, w), np.float32),
                e=np.empty((ee - es, w), np.float32),
                i=np.empty((ye - ys, w), np.float32),
                kon=np.empty((ce - cs, w), np.float32),
                koff=np.empty((ce - cs, w), np.float32)))
        self._bands = bands

    # -- the three phases, per band ---------------------------------------------
    def _phase1(self, bd, gray, p_prev, p_next) -> None:
        ys, ye, es, ee, y0, y1 = bd["ys"], bd["ye"], bd["es"], bd["ee"], bd["y0"], bd["y1"]
        lb = bd["l"]
        _retina_rows(gray, p_prev, p_next, lb, ys, ye, y0, y1)
        cv2.sepFilter2D(lb[es - ys:ee - ys], cv2.CV_32F, self.k_e, self.k_e, dst=bd["e"],
                        borderType=cv2.BORDER_CONSTANT)
        cv2.sepFilter2D(lb, cv2.CV_32F, self.k_i, self.k_i, dst=bd["i"], borderType=cv2.BORDER_CONSTANT)
        use_prev = bool(self.params.after_image) and not self._first
        _vdog_rows(bd["e"], es, bd["i"], ys, self._on, self._off, y0, y1, self._w_i, self._after, use_prev)

    def _phase2(self, bd) -> None:
        cs, ce, y0, y1 = bd["cs"], bd["ce"], bd["y0"], bd["y1"]
        for sig, kb, c in ((self._on, bd["kon"], 0), (self._off, bd["koff"], 1)):
            cv2.sepFilter2D(sig[cs:ce], cv2.CV_32F, self.k_c, self.k_c, dst=kb,
                            borderType=cv2.BORDER_CONSTANT)
            pad = self._pad
            if self._floor_r:  # Params.n_floor: N on the band and n_floor_radius rows of context
                nb, ns = bd["nb"], bd["ns"]
                _ratio_band(sig, kb, cs, nb, ns, ns, bd["ne"], self._eps)
                np.tanh(nb, out=nb)
                _floor_rows(nb, local_max(nb, self._floor_r), ns, self._n, c, pad, y0, y1, self._floor)
                continue
            _ratio_rows(sig, kb, cs, self._n, c, pad, y0, y1, self._eps)
            rows = self._n[c, y0 + pad:y1 + pad, pad:-pad]
            np.tanh(rows, out=rows)

    def _phase3(self, bd, lm) -> None:
        _motion_rows(self._n, self._n_prev, self._pad, self._m_rows, lm, bd["y0"], bd["y1"], self._a_t, self._b_t,
                     self._ao, self._bo, self._beta, self._nc_div, bool(self.params.average_distances),
                     self._g_on, self._g_off, self._mode_on, self._mode_off, self._gain, self._slope)

    def _nbands(self, h: int, w: int) -> int:
        n = max(1, int(numba.get_num_threads()))
        n = min(n, max(1, (h * w) // MIN_BAND_PIXELS), max(1, h // 16))
        return n

    def _band_task(self, k, bd, gray, p_prev, p_next, lm, arrive) -> None:
        """Band ``k``: the three phases, with a spin barrier (:func:`_spin_wait`) between them."""
        try:
            self._phase1(bd, gray, p_prev, p_next)
            arrive[k] = 1
            _spin_wait(arrive, 1)
            self._phase2(bd)
            arrive[k] = 2
            _spin_wait(arrive, 2)
            self._phase3(bd, lm)
        finally:
            arrive[k] = _DONE

    def _run_bands(self, bands, gray, p_prev, p_next, lm) -> None:
        """All bands in parallel: band 0 on this thread, the others on the pool's threads.

        The phases are separated by spin barriers on ``arrive`` (one entry per band, the last
        stage it reached): waking a sleeping thread costs tens of microseconds per barrier
        here, as much as a phase of a small frame. A band that fails marks itself done so
        that the others never wait forever; its exception is raised here.
        """
        n = len(bands)
        arrive = np.zeros(n, np.int64)
        with _BANDS_LOCK:  # one frame's bands at a time on the shared pool (see _BANDS_LOCK)
            futs = [_pool(n - 1).submit(self._band_task, k, bd, gray, p_prev, p_next, lm, arrive)
                    for k, bd in enumerate(bands) if k]
            try:
                self._band_task(0, bands[0], gray, p_prev, p_next, lm, arrive)
            finally:
                _spin_wait(arrive, _DONE)
                for f in futs:
                    f.result()

    def step(self, gray: np.ndarray) -> LocalMotion:
        gray = np.ascontiguousarray(gray, dtype=np.float32)
        h, w = gray.shape
        nb = self._nbands(h, w)
        if self._shape != (h, w):
            self._allocate(h, w, nb)
            self._first = True
        elif len(self._bands) != nb:
            self._plan(nb)
        if self._first:
            self._p[0][...] = gray  # frame 0: L = 0 (no change yet)
        p_prev, p_next = self._p
        lm = np.empty((5, h, w), np.float32)
        bands = self._bands
        if len(bands) == 1:
            bd = bands[0]
            self._phase1(bd, gray, p_prev, p_next)
            self._phase2(bd)
            self._phase3(bd, lm)
        elif _spin_ok():
            self._run_bands(bands, gray, p_prev, p_next, lm)
        else:  # pragma: no cover - no spin barrier: one thread-pool round trip per phase
            with _BANDS_LOCK:
                pool = _pool(len(bands) - 1)
                for phase, args in ((self._phase1, (gray, p_prev, p_next)), (self._phase2, ()),
                                    (self._phase3, (lm,))):
                    futs = [pool.submit(phase, bd, *args) for bd in bands[1:]]
                    phase(bands[0], *args)
                    for f in futs:
                        f.result()
        self._p = [p_next, p_prev]
        self._n, self._n_prev = self._n_prev, self._n
        self._first = False
        return LocalMotion(lm[0], lm[1], lm[2], lm[3], lm[4])
