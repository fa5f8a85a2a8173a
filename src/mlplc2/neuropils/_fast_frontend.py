"""Fast front end of the LPLC2 family (Eq. 1-12): OpenCV Gaussians + fused Numba kernels.

:class:`FastFrontEnd` computes exactly what the reference :class:`mlplc2.neuropils.frontend.FrontEnd`
computes, with the same float32 arithmetic in the same order, so that everything up to the
T4/T5 outputs is bit-identical to it:

* the Gaussians of Eq. 2, 3 and 7 are the same ``cv2.sepFilter2D`` calls (zero outside the
  frame), and the tanh of Eq. 6 is the same ``numpy.tanh``. This matters: the square root of
  Eq. 11 (gamma_2 = 0.5) amplifies a rounding difference of 1e-7 in a T5 value near zero into a
  relative LM difference of up to ~1e-4, so a Gaussian that merely rounds differently (another
  summation order, float64) would already use up the whole tolerance;
* the retina and lamina (Eq. 1-5) and the contrast normalisation (Eq. 6-7) run as small
  Numba row kernels (:func:`_retina_rows`, :func:`_vdog_rows`, :func:`_ratio_rows`, ...) in
  this module, with the operations of the reference in the reference's order (no fused
  multiply-add: ``fastmath=False``, :func:`mlplc2.neuropils._fast.jit`);
* the delays, correlators, two-tap filters, opponency, Leaky ReLU, gain and magnitude
  (Eq. 8-12) run in one fused Numba pass over the rows
  (:func:`mlplc2.neuropils._fast_motion.motion_rows`: every intermediate lives in row
  buffers, only the state and the LM maps are planes), same operations in the same order;
* the only difference is ``x ** gamma`` for exponents other than 0.5, 1 and 2: a vectorised
  float32 power (in :mod:`mlplc2.neuropils._fast_motion`, relative error ~1e-6 like NumPy's
  own float32 power), so the LM maps agree to ~1e-6 relative (``tests/test_fast.py``).

Work is split into horizontal bands, one per thread (``numba.get_num_threads()``, so
``numba.set_num_threads`` and ``mlplc2 bench --threads`` set it). Each band runs three
phases; a barrier separates them because each needs a few rows of its neighbours:

1. L = P(t) - P(t-1) on the band plus r_i rows of context, E and I (``sepFilter2D``), vDoG and
   ON/OFF for the band's rows (Eq. 1-5);
2. K_c * ON and K_c * OFF on the band plus r_c rows, N = tanh(ON / (epsilon + K_c * ON))
   (Eq. 6-7); with the relative floor of ``Params.n_floor`` (off by default: 0) N is formed on
   ``n_floor_radius`` more rows of context and set to 0 where it is below ``n_floor`` times
   its local maximum (the reference's own ``medulla.local_max``, an OpenCV dilation), so no
   extra barrier is needed;
3. the fused kernel :func:`mlplc2.neuropils._fast_motion.motion_rows` (Eq. 8-12) for the band's rows.

OpenCV and NumPy release the GIL and every kernel is ``nogil``, so the bands run in parallel
in a small thread pool: band 0 on the calling thread, each other band on a pool thread that
runs all three phases (the pool: :func:`mlplc2.neuropils._fast.pool`). The barriers spin
without the GIL (:func:`mlplc2.neuropils._fast.spin_wait`, ~1 us per poll):
waking a sleeping thread costs ~35 us here, and three wake-ups per frame used to cost 10-15 %
of a 320x240 frame. All state is float32; the planes per stream are listed in
:data:`PLANES`.
"""

from __future__ import annotations

import math

import cv2
import numba
import numpy as np

from . import _fast
from ._fast import jit
from ._fast_motion import motion_rows, pow_mode
from .frontend import set_coefficients, use_interval
from .lobula_plate import LocalMotion
from .medulla import local_max
from ..camera import warp
from ..params import Params

__all__ = ["FastFrontEnd", "PLANES", "MIN_BAND_PIXELS", "plane_count", "plane_traffic"]

_F32 = np.float32
U64 = np.uint64


def _carry(jobs, homography: np.ndarray) -> None:
    """Warp each job of ``jobs`` into its output (:func:`mlplc2.camera.warp`): ``(plane, out, fill)``
    (``out`` None: in place, through a new plane), or ``(planes, outs, packed, warped)``: four
    planes warped as one four-channel image (:func:`_warp4`)."""
    for job in jobs:
        if len(job) == 4:
            _warp4(homography, *job)
        elif job[1] is None:
            job[0][...] = warp(job[0], homography, fill=job[2])
        else:
            warp(job[0], homography, fill=job[2], out=job[1])


def _warp4(homography: np.ndarray, planes, outs, packed: np.ndarray, warped: np.ndarray) -> None:
    """Four planes of one shape warped at once, with zeros where the turn uncovers: interleaved into
    ``packed`` (H, W, 4), one ``cv2.warpPerspective`` of that four-channel image into ``warped``,
    split into ``outs``. OpenCV computes each pixel's source coordinates once for the four channels
    and interpolates each channel as it does a single plane: the values are those of four
    single-plane warps bit for bit with OpenCV 5.0; with 5.1 up to a float32 unit in the last place on
    a few pixels next to the uncovered border (``tests/test_fast.py``), at about half the CPU time
    (docs/model.md, "Camera motion")."""
    _pack4(planes[0], planes[1], planes[2], planes[3], packed)
    h, w = planes[0].shape
    cv2.warpPerspective(packed, homography, (w, h), dst=warped, flags=cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_CONSTANT, borderValue=(0.0, 0.0, 0.0, 0.0))
    _unpack4(warped, outs[0], outs[1], outs[2], outs[3])


@jit()
def _pack4(a, b, c, d, out):
    """``out[y, x] = (a, b, c, d)[y, x]``."""
    for y in range(out.shape[0]):
        ar, br, cr, dr, o = a[y], b[y], c[y], d[y], out[y]
        for x in range(out.shape[1]):
            o[x, 0] = ar[x]
            o[x, 1] = br[x]
            o[x, 2] = cr[x]
            o[x, 3] = dr[x]


@jit()
def _unpack4(src, a, b, c, d):
    """``(a, b, c, d)[y, x] = src[y, x]``, one output row after the other (contiguous writes: ~25 %
    less time than the four written together, docs/history.md, "The stabilised pipeline's speed")."""
    for y in range(src.shape[0]):
        s = src[y]
        o = a[y]
        for x in range(src.shape[1]):
            o[x] = s[x, 0]
        o = b[y]
        for x in range(src.shape[1]):
            o[x] = s[x, 1]
        o = c[y]
        for x in range(src.shape[1]):
            o[x] = s[x, 2]
        o = d[y]
        for x in range(src.shape[1]):
            o[x] = s[x, 3]


# ---------------------------------------------------------------------------
# Phases 1 and 2: retina, lamina (Eq. 1-5) and contrast normalisation (Eq. 6-7)
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
        self._set_alphas()
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
        self._mode_on = pow_mode(p.gamma_on)
        self._mode_off = pow_mode(p.gamma_off)
        self._gain = np.float32(p.lm_gain)
        self._slope = np.float32(p.leaky_slope)
        self.reset()

    def _set_alphas(self) -> None:
        """The kernels' float32 forms of ``alphas`` and ``alpha_out``, exactly as the reference forms them."""
        a = np.array([np.float32(x) for x in self.alphas], np.float32)
        self._a = a
        self._b = (np.float32(1) - a).astype(np.float32)
        # tuples for the kernels: N_c becomes a compile-time constant (unrolled distance loop)
        self._a_t = tuple(np.float32(v) for v in a)
        self._b_t = tuple(np.float32(v) for v in self._b)
        self._ao = np.float32(self.alpha_out)
        self._bo = np.float32(1) - self._ao

    def reset(self) -> None:
        self._shape = None
        self._first = True
        self._bands = None

    def compensate(self, homography: np.ndarray, gray: np.ndarray) -> None:
        """Gaze stabilisation, as :meth:`mlplc2.neuropils.frontend.FrontEnd.compensate`: P(t-1),
        N(t-1), M-hat(t-1) (and the after-image) carried into this frame's pixels. Each plane is
        warped straight into its spare buffer (the one :meth:`step` overwrites next: P(t), N(t), or
        the M-hat double buffer), then the buffers swap. Each channel's four M-hat(t-1) planes go
        through one four-channel ``warpPerspective`` (:func:`_warp4`), the values of the reference's
        one warp per plane bit for bit; the five jobs (two of them four-channel) are shared out over
        the front end's threads (OpenCV runs a 320 x 240 warp on one thread), so the
        values do not depend on the threads."""
        if self._shape is None or self._first or np.shape(gray) != self._shape:
            return
        gray = np.asarray(gray, dtype=np.float32)
        pad = self._pad
        inner = (slice(pad, -pad), slice(pad, -pad)) if pad else (slice(None), slice(None))
        if self._packed is None:                            # per channel: packed, warped
            self._packed = np.empty((2, 2) + self._shape + (4,), np.float32)
        # each channel's four M-hat(t-1) directions through _m_rows (what the kernel reads) as one
        # warp; P(t-1) into P(t)'s buffer (the frame where uncovered), N(t-1) with its zero border kept
        jobs = [([self._m_rows[:, c, d, :] for d in range(4)], [self._m_spare[:, c, d, :] for d in range(4)],
                 *self._packed[c]) for c in range(2)]
        jobs += [(self._p[0], self._p[1], gray)]
        jobs += [(self._n_prev[c][inner], self._n[c][inner], 0.0) for c in range(2)]
        if self.params.after_image:
            jobs += [(self._on, None, 0.0), (self._off, None, 0.0)]
        n = len(self._bands) if self._bands else 1
        if n > 1:
            with _fast.BANDS_LOCK:                          # the shared pool, one frame at a time
                futs = [_fast.pool(n - 1).submit(_carry, jobs[k::n], homography) for k in range(1, n)]
                _carry(jobs[0::n], homography)
                for f in futs:
                    f.result()
        else:
            _carry(jobs, homography)
        self._p = self._p[::-1]
        self._n, self._n_prev = self._n_prev, self._n
        self._m_rows, self._m_spare = self._m_spare, self._m_rows
        self._m = self._m_rows.transpose(1, 2, 0, 3)

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
        self._m_spare = np.empty_like(self._m_rows)        # what compensate warps _m_rows into
        self._packed = None                                # compensate's four-channel images, made at its first turn
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
        motion_rows(self._n, self._n_prev, self._pad, self._m_rows, lm, bd["y0"], bd["y1"], self._a_t, self._b_t,
                     self._ao, self._bo, self._beta, self._nc_div, bool(self.params.average_distances),
                     self._g_on, self._g_off, self._mode_on, self._mode_off, self._gain, self._slope)

    def _nbands(self, h: int, w: int) -> int:
        n = max(1, int(numba.get_num_threads()))
        n = min(n, max(1, (h * w) // MIN_BAND_PIXELS), max(1, h // 16))
        return n

    def _band_task(self, k, bd, gray, p_prev, p_next, lm, arrive) -> None:
        """Band ``k``: the three phases, with a spin barrier (:func:`_fast.spin_wait`) between them."""
        try:
            self._phase1(bd, gray, p_prev, p_next)
            arrive[k] = 1
            _fast.spin_wait(arrive, 1)
            self._phase2(bd)
            arrive[k] = 2
            _fast.spin_wait(arrive, 2)
            self._phase3(bd, lm)
        finally:
            arrive[k] = _fast.DONE

    def _run_bands(self, bands, gray, p_prev, p_next, lm) -> None:
        """All bands in parallel: band 0 on this thread, the others on the pool's threads.

        The phases are separated by spin barriers on ``arrive`` (one entry per band, the last
        stage it reached): waking a sleeping thread costs tens of microseconds per barrier
        here, as much as a phase of a small frame. A band that fails marks itself done so
        that the others never wait forever; its exception is raised here.
        """
        n = len(bands)
        arrive = np.zeros(n, np.int64)
        with _fast.BANDS_LOCK:  # one frame's bands at a time on the shared pool (see _fast.BANDS_LOCK)
            futs = [_fast.pool(n - 1).submit(self._band_task, k, bd, gray, p_prev, p_next, lm, arrive)
                    for k, bd in enumerate(bands) if k]
            try:
                self._band_task(0, bands[0], gray, p_prev, p_next, lm, arrive)
            finally:
                _fast.spin_wait(arrive, _fast.DONE)
                for f in futs:
                    f.result()

    def step(self, gray: np.ndarray, interval: float = 1) -> LocalMotion:
        """Eq. 1-12 on ``gray``, ``interval`` frame intervals after the last frame (:func:`use_interval`)."""
        if use_interval(self, interval):
            self._set_alphas()
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
        elif _fast.spin_ok():
            self._run_bands(bands, gray, p_prev, p_next, lm)
        else:  # pragma: no cover - no spin barrier: one thread-pool round trip per phase
            with _fast.BANDS_LOCK:
                pool = _fast.pool(len(bands) - 1)
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
