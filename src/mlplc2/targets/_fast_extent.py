"""Numba kernel of the edge scans of :mod:`mlplc2.targets.extent`, chosen by :mod:`mlplc2.backend`.

:func:`edges4` is :func:`mlplc2.targets.extent._strip_profiles` followed by
:func:`mlplc2.targets.extent._edge_distances` in one compiled pass: the same strip sums (float64,
rows / columns added in the same order as ``np.add.reduce``), the same order statistic for the
noise floor (the 75th percentile as ``np.partition``), the same threshold and the same scan over
the samples above it, so the four distances are bit-identical to the NumPy path. ``nogil`` and
cached on disk where possible; nothing here is public API.
"""

from __future__ import annotations

import numpy as np

from ..neuropils._fast import jit  # the same njit options and on-disk cache fallback as the front end

__all__ = ["edges4"]


@jit()
def _edge_of(prof, n, scale, min_peak, noise_k, rel_start, rel_edge, gap, local, cols, vals):
    """:func:`mlplc2.targets.extent._edge_distances` of one profile ``prof[:n]``; -1.0 for None.

    ``cols`` / ``vals``: scratch buffers of at least ``n`` entries. The comparisons and
    ``max`` / ``min`` follow Python's semantics (``max(a, b)`` is ``a`` unless ``b > a``).
    """
    floor = min_peak * scale
    if n > 0:
        # floor = max(floor, noise_k * max(q, 0)) with q the 75th percentile (order statistic
        # kq). q only matters when noise_k * q > floor; then the n - kq samples at or above q
        # in sorted order (NaN sorts last) all fail noise_k * v <= floor. Count those first
        # (one pass) and select q only when there are enough of them (a noisy profile).
        kq = int(0.75 * (n - 1))
        above = 0
        for c in range(n):
            if not noise_k * prof[c] <= floor:
                above += 1
        if above >= n - kq:
            q = np.partition(prof[:n], kq)[kq]
            if 0.0 > q:
                q = 0.0
            f2 = noise_k * q
            if f2 > floor:
                floor = f2
    sel = 0.5 * floor
    ns = 0
    for c in range(n):
        v = prof[c]
        if v >= sel:
            cols[ns] = c
            vals[ns] = v
            ns += 1
    i = 0
    while i < ns:
        j = i
        peak = vals[i]
        while j + 1 < ns and cols[j + 1] - cols[j] <= gap:
            j += 1
            if vals[j] > peak:
                peak = vals[j]
        if peak >= floor:
            near = peak
            k = j + 1
            lim = cols[i] + local
            while k < ns and cols[k] < lim:
                if vals[k] > near:
                    near = vals[k]
                k += 1
            if peak >= rel_start * near:
                level = rel_edge * peak
                k = j
                while vals[k] < level:      # stops at the peak (rel_edge <= 1, checked by the caller)
                    k -= 1
                ck = cols[k]
                if ck + 1 < n:
                    a = vals[k]
                    b = prof[ck + 1]
                    if 0.0 > b:
                        b = 0.0
                    den = a - b
                    tiny = 1e-12 * scale
                    if tiny > den:
                        den = tiny
                    frac = (a - level) / den
                    if 0.0 > frac:
                        frac = 0.0
                    if 1.0 < frac:
                        frac = 1.0
                    return (ck + 1) + frac
                return -1.0
        i = j + 1
    return -1.0


@jit()
def edges4(r, l, u, d, x, y, band, min_peak, noise_k, rel_start, rel_edge, gap, local):  # noqa: E741
    """The four edge distances (right, left, up, down; -1.0 for None) around (x, y).

    ``r, l, u, d``: the LM maps (H, W); ``x``, ``y`` inside the frame; ``rel_edge <= 1``.
    """
    h, w = r.shape
    r0 = max(y - band, 0)
    r1 = min(y + band + 1, h)
    c0 = max(x - band, 0)
    c1 = min(x + band + 1, w)
    nr = float(r1 - r0)
    nc = float(c1 - c0)
    m = max(w, h)
    prof = np.empty(m)
    cols = np.empty(m, np.int64)
    vals = np.empty(m)
    out = np.empty(4)
    # right: LM_r along the row, summed over the strip's rows (in order, like np.add.reduce)
    n = w - 1 - x
    for k in range(n):
        prof[k] = np.float64(r[r0, x + 1 + k])
    for row in range(r0 + 1, r1):
        for k in range(n):
            prof[k] += np.float64(r[row, x + 1 + k])
    out[0] = _edge_of(prof, n, nr, min_peak, noise_k, rel_start, rel_edge, gap, local, cols, vals)
    # left: LM_l, outwards from x - 1
    n = x
    for k in range(n):
        prof[k] = np.float64(l[r0, x - 1 - k])
    for row in range(r0 + 1, r1):
        for k in range(n):
            prof[k] += np.float64(l[row, x - 1 - k])
    out[1] = _edge_of(prof, n, nr, min_peak, noise_k, rel_start, rel_edge, gap, local, cols, vals)
    # up: LM_u along the column, upwards from y - 1, summed over the strip's columns
    n = y
    for k in range(n):
        s = np.float64(u[y - 1 - k, c0])
        for c in range(c0 + 1, c1):
            s += np.float64(u[y - 1 - k, c])
        prof[k] = s
    out[2] = _edge_of(prof, n, nc, min_peak, noise_k, rel_start, rel_edge, gap, local, cols, vals)
    # down: LM_d, downwards from y + 1
    n = h - 1 - y
    for k in range(n):
        s = np.float64(d[y + 1 + k, c0])
        for c in range(c0 + 1, c1):
            s += np.float64(d[y + 1 + k, c])
        prof[k] = s
    out[3] = _edge_of(prof, n, nc, min_peak, noise_k, rel_start, rel_edge, gap, local, cols, vals)
    return out[0], out[1], out[2], out[3]
