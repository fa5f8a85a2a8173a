"""Fast front end of the LPLC2 family (Eq. 1-12): OpenCV Gaussians + fused Numba kernels.

:class:`FastFrontEnd` computes exactly what the reference :class:`mlplc2.frontend.FrontEnd`
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
   (Eq. 6-7);
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

from .frontend import set_coefficients
from .lobula_plate import LocalMotion
from .params import Params

__all__ = ["FastFrontEnd", "quadrant_sums", "quadrant_sums_all", "set_threads", "PLANES",
           "plane_traffic"]

_F32 = np.float32
U64 = np.uint64


def _jit(**options):
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
@_jit()
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


@_jit()
def _vdog_rows(e_band, e_off, i_band, i_off, on, off, y0, y1, w_i, after, use_prev):
    """Eq. 4-5 on rows [y0, y1): sign(E) max(|E| - w_i |I|, 0), split into ON and OFF.

    ``e_band[y - e_off]`` and ``i_band[y - i_off]`` are E and I of frame row y. With
    ``use_prev`` the after-image ``after`` times the previous ON/OFF (held in ``on``/``off``)
    is added, as in :func:`mlplc2.lamina.on_off`.
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


@_jit()
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


# ---------------------------------------------------------------------------
# Phase 3: the fused medulla + lobula-plate kernel (Eq. 8-12)
# ---------------------------------------------------------------------------
# The fused pass is a loop over rows that calls one small kernel per row loop. Each takes whole
# arrays and unsigned offsets (no views: no reference counting; no negative-index wrap-around)
# and writes at most two arrays (LLVM's run-time alias checks stay within its limit), so LLVM
# vectorises every one; as one big function, register pressure made LLVM spill in the loops.
@_jit()
def _corr_pair(o1, o2, flat_n, flat_p, base, o1_far, o2_far, a_s, b_s, beta, w, first):
    """Eq. 8-9 for one distance s and two opposite directions, accumulated (``first``: assigned).

    ``flat_n``/``flat_p``: N(t)/N(t-1) planes (padded), flattened. For x < w the centre is
    ``base + x``: o1[x] (+)= (N_f - beta N) D D_f with the far point at offset ``o1_far``
    (likewise o2), D = a_s N(t) + b_s N(t-1). Offsets are unsigned; a negative offset is
    its two's complement, which wraps back.
    """
    if first:
        for x in range(w):
            i = base + x
            nx = flat_n[i]
            bnx = beta * nx
            d = a_s * nx + b_s * flat_p[i]
            j = i + o1_far
            nf = flat_n[j]
            o1[x] = ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])
            j = i + o2_far
            nf = flat_n[j]
            o2[x] = ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])
    else:
        for x in range(w):
            i = base + x
            nx = flat_n[i]
            bnx = beta * nx
            d = a_s * nx + b_s * flat_p[i]
            j = i + o1_far
            nf = flat_n[j]
            o1[x] += ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])
            j = i + o2_far
            nf = flat_n[j]
            o2[x] += ((nf - bnx) * d) * (a_s * nf + b_s * flat_p[j])


@_jit()
def _output_dir(acc, m_flat, m_off, t, t_off, ao, bo, nc_div, average, w):
    """Eq. 10 for one direction on one row: mean over distances, two-tap filter with M-hat(t-1)
    (``m_flat[m_off + x]``, replaced by M-hat(t)), T rectified into ``t[t_off + x]``."""
    zero = _F32(0.0)
    for x in range(w):
        v = acc[x] / nc_div if average else acc[x]
        j = m_off + x
        tv = ao * v + bo * m_flat[j]
        m_flat[j] = v
        t[t_off + x] = tv if tv > zero else zero


@_jit(fastmath={"contract"})
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


@_jit()
def _opponency(t, w, hz, vt):
    """Eq. 11: r - l and d - u with r = T4_r^g1 + T5_r^g2 etc. (t: 8 rows of powered T)."""
    for x in range(w):
        hz[x] = (t[x] + t[U64(4) * w + x]) - (t[w + x] + t[U64(5) * w + x])
        vt[x] = (t[U64(2) * w + x] + t[U64(6) * w + x]) - (t[U64(3) * w + x] + t[U64(7) * w + x])


@_jit()
def _leaky_pair(src, out, o_pos, o_neg, gain, slope, w):
    """Eq. 11: out[o_pos + x] = g f(src), out[o_neg + x] = g f(-src), f the Leaky ReLU."""
    zero = _F32(0.0)
    for x in range(w):
        v = src[x]
        nv = -v
        out[o_pos + x] = gain * (v if v >= zero else slope * v)
        out[o_neg + x] = gain * (nv if nv >= zero else slope * nv)


@_jit()
def _magnitude(lm_flat, off, plane, w):
    """Eq. 12: LM = sqrt(max(LM_r, LM_l)^2 + max(LM_d, LM_u)^2) on one row."""
    for x in range(w):
        j = off + x
        vr = lm_flat[j]
        vl = lm_flat[j + plane]
        vd = lm_flat[j + U64(2) * plane]
        vu = lm_flat[j + U64(3) * plane]
        hh = vr if vr >= vl else vl
        vv = vd if vd >= vu else vu
        lm_flat[j + U64(4) * plane] = np.sqrt(hh * hh + vv * vv)


@_jit()
def _motion_rows(n_cur, n_prev, pad, m, lm, y0, y1, a, b, ao, bo, beta, nc_div, average,
                 g_on, g_off, mode_on, mode_off, gain, slope):
    """Eq. 8-12 for rows [y0, y1), both channels, all directions and distances, fused.

    n_cur, n_prev : (2, H + 2 pad, W + 2 pad) contrast-normalised N(t), N(t-1) of the ON and
        OFF channels, frame pixel (y, x) at (y + pad, x + pad), zero in the border of width
        ``pad`` >= N_c: a correlator whose far point is outside the frame then adds
        (0 - beta N) D * 0 = 0, the reference's zero padding, without a bounds test.
    m : (2, 4, H, W) M-hat(t-1) per channel and direction (r, l, d, u); overwritten with
        M-hat(t) (the state of Eq. 10).
    lm : (5, H, W) output LM_r, LM_l, LM_d, LM_u, LM.
    a, b : (N_c,) float32 delay coefficients a_s and 1 - a_s of Eq. 8.
    mode_on, mode_off : how ``T ** gamma`` is computed (:func:`_power`).

    The float32 operations are those of ``medulla.motion_detectors`` and
    ``lobula_plate.local_motion`` in the same order (the reference), row by row; only row-sized
    scratch buffers are allocated.
    """
    h = m.shape[2]
    w = m.shape[3]
    wu = U64(w)
    wp = U64(w + 2 * pad)
    plane = U64(h * w)
    nc = a.shape[0]
    tr = np.empty(w, np.float32)
    tl = np.empty(w, np.float32)
    td = np.empty(w, np.float32)
    tu = np.empty(w, np.float32)
    tots = (tr, tl, td, tu)
    hz = np.empty(w, np.float32)
    vt = np.empty(w, np.float32)
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
            for s in range(nc):
                sd = U64(s + 1)
                first = s == 0
                # right (far x + s) and left (x - s); down (far y + s) and up (y - s)
                centre = cu * plane_p + yp * wp + pu
                _corr_pair(tr, tl, flat_n, flat_p, centre, sd, U64(0) - sd, a[s], b[s], beta, wu, first)
                _corr_pair(td, tu, flat_n, flat_p, centre, sd * wp, U64(0) - sd * wp, a[s], b[s], beta,
                           wu, first)
            base = cu * U64(4) * wu
            for k in range(4):
                _output_dir(tots[k], m_flat, ((cu * U64(4) + U64(k)) * U64(h) + yu) * wu, t,
                            base + U64(k) * wu, ao, bo, nc_div, average, wu)
            if c == 0:
                _power(t, base, U64(4) * wu, g_on, mode_on, mb, kb, pb)
            else:
                _power(t, base, U64(4) * wu, g_off, mode_off, mb, kb, pb)
        _opponency(t, wu, hz, vt)
        row = yu * wu
        _leaky_pair(hz, lm_flat, row, row + plane, gain, slope, wu)
        _leaky_pair(vt, lm_flat, row + U64(2) * plane, row + U64(3) * plane, gain, slope, wu)
        _magnitude(lm_flat, row, plane, wu)


# ---------------------------------------------------------------------------
# Attention-field helper (Eq. 14). Eq. 13 stays mlplc2.attention.argmax_outside: its copy and
# NumPy's SIMD argmax measured 2-3x faster than a masked argmax kernel here.
# ---------------------------------------------------------------------------
@_jit()
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
    """Same as :func:`mlplc2.attention.quadrant_sums` (to float64 rounding), in one pass."""
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


@_jit()
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
    """Use ``n`` threads for the fast front end (Numba's thread count) and OpenCV."""
    numba.set_num_threads(int(n))
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
    ("M-hat", 8, "correlator state per channel and direction (Eq. 10)"),
    ("LM", 5, "LM_r, LM_l, LM_d, LM_u, LM (the output)"),
)


def plane_traffic() -> dict[str, int]:
    """Plane-sized reads and writes per frame of :class:`FastFrontEnd` (counted from the kernels).

    Phase 1: read gray, P(t-1), write L, write P(t) (4); E and I read L and write (4); vDoG
    reads E, I and writes ON, OFF (4). Phase 2: the K_c filters read ON/OFF and write (4); the
    ratio reads ON, OFF, K_c ON, K_c OFF and writes N (6); tanh reads and writes N (4).
    Phase 3: reads N(t), N(t-1) (4), reads and writes M-hat (16), writes LM (5).
    Attention: Eq. 13 copies LM and reads the copy (3; the quadrant sums touch only the fields).
    """
    return {"phase1": 12, "phase2": 14, "phase3": 25, "attention": 3}


# ---------------------------------------------------------------------------
# The front end
# ---------------------------------------------------------------------------
def _pow_mode(g: float) -> int:
    return {0.5: 1, 1.0: 2, 2.0: 3}.get(float(np.float32(g)), 0)


class FastFrontEnd:
    """Eq. 1-12 like :class:`mlplc2.frontend.FrontEnd`, fast (see the module docstring).

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
        self._ao = np.float32(self.alpha_out)
        self._bo = np.float32(1) - self._ao
        self._beta = np.float32(p.beta)
        self._nc_div = np.float32(len(self.alphas))
        self._w_i = np.float32(p.w_i)
        self._after = np.float32(p.after_image)
        self._eps = np.float32(p.epsilon)
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
        self._m = np.zeros((2, 4, h, w), np.float32)
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
            cs, ce = max(y0 - p.r_c, 0), min(y1 + p.r_c, h)
            bands.append(dict(
                y0=y0, y1=y1, ys=ys, ye=ye, es=es, ee=ee, cs=cs, ce=ce,
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
            _ratio_rows(sig, kb, cs, self._n, c, pad, y0, y1, self._eps)
            rows = self._n[c, y0 + pad:y1 + pad, pad:-pad]
            np.tanh(rows, out=rows)

    def _phase3(self, bd, lm) -> None:
        _motion_rows(self._n, self._n_prev, self._pad, self._m, lm, bd["y0"], bd["y1"], self._a, self._b,
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
