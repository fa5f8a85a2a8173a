"""Numba kernel of the change box's last steps (:func:`mlplc2.targets.change.change_box`), chosen
by :mod:`mlplc2.backend`.

:func:`nearest_change` takes the two Hann-windowed windows (the newer one already moved back by
the phase correlation's shift) and does in one compiled pass what ``change_box`` does after the
correlation with five OpenCV calls and a Python loop: the absolute difference (float32, as
``cv2.absdiff``), the replicated margin zeroed, its largest value, the threshold (compared in
float32, as NumPy compares a float32 array with a Python float), the 3 x 3 dilation (nothing
beyond the window, as ``cv2.dilate``'s default border), the 8-connected regions and, among their
bounding boxes, the one nearest the seed. ``change_box`` took the first nearest in
``cv2.connectedComponentsWithStats``' label order; the kernel labels the regions in its own order,
so when two regions with different boxes lie equally near it says so, and ``change_box`` then asks
OpenCV (the same answer in every case; docs/history.md, "The seeding frames' cost"). ``nogil`` and cached on disk
where possible; nothing here is public API.
"""

from __future__ import annotations

import numpy as np

from ..neuropils._fast import jit  # the same njit options and on-disk cache fallback as the front end

__all__ = ["nearest_change"]

#: :func:`nearest_change` statuses
NONE, FOUND, TIE = 0, 1, 2


@jit()
def nearest_change(a, b, border, min_change, rel, sx, sy, d, mask, labels, stack):
    """The region of large change nearest (``sx``, ``sy``) (window pixels) between windows ``a``
    and ``b`` (float32, the same shape); ``border``: the margin (px) that is no change.

    ``d`` (float32), ``mask`` (uint8), ``labels`` (int32) of the windows' shape and ``stack``
    (int32, 2 x its size): scratch, ``d`` and ``mask`` left as ``change_box`` makes them
    (``mask`` only when the largest change reaches ``min_change``). Returns ``(status, top, bx,
    by, bw, bh, dx, dy)``: status :data:`NONE` (the largest change ``top`` is under
    ``min_change``, or no region), :data:`FOUND` (the nearest region's box, its distance ``dx``,
    ``dy`` from the seed in px along each axis) or :data:`TIE` (regions with different boxes
    equally near: the caller picks by OpenCV's label order).
    """
    h, w = a.shape
    top = np.float32(0.0)
    nan = False
    for i in range(h):
        for j in range(w):
            if i < border or i >= h - border or j < border or j >= w - border:
                v = np.float32(0.0)
            else:
                v = abs(b[i, j] - a[i, j])
            d[i, j] = v
            if v != v:
                nan = True
            elif v > top:
                top = v
    topf = np.nan if nan else float(top)
    if topf < min_change:
        return NONE, topf, 0, 0, 0, 0, 0, 0
    thr = min_change
    if rel * topf > thr:                 # Python's max(min_change, rel * top)
        thr = rel * topf
    thr32 = np.float32(thr)
    for i in range(h):                  # the threshold, dilated along the rows ...
        for j in range(w):
            labels[i, j] = 0
        for j in range(w):
            if d[i, j] >= thr32:
                labels[i, j] = 1
                if j > 0:
                    labels[i, j - 1] = 1
                if j + 1 < w:
                    labels[i, j + 1] = 1
    for i in range(h):                  # ... then down the columns (3 x 3, nothing beyond the window)
        for j in range(w):
            mask[i, j] = labels[i, j]
        if i > 0:
            for j in range(w):
                mask[i, j] |= labels[i - 1, j]
        if i + 1 < h:
            for j in range(w):
                mask[i, j] |= labels[i + 1, j]
    for i in range(h):
        for j in range(w):
            labels[i, j] = 0
    status = NONE
    best = 1 << 60
    bx0 = by0 = bw0 = bh0 = ddx = ddy = 0
    n = 0
    for i in range(h):
        for j in range(w):
            if mask[i, j] == 0 or labels[i, j] != 0:
                continue
            n += 1
            labels[i, j] = n
            top_s = 0
            stack[0] = i
            stack[1] = j
            top_s = 1
            x0 = x1 = j
            y0 = y1 = i
            while top_s > 0:
                top_s -= 1
                ci = stack[2 * top_s]
                cj = stack[2 * top_s + 1]
                if ci < y0:
                    y0 = ci
                if ci > y1:
                    y1 = ci
                if cj < x0:
                    x0 = cj
                if cj > x1:
                    x1 = cj
                for u in range(max(ci - 1, 0), min(ci + 2, h)):
                    for v in range(max(cj - 1, 0), min(cj + 2, w)):
                        if mask[u, v] != 0 and labels[u, v] == 0:
                            labels[u, v] = n
                            stack[2 * top_s] = u
                            stack[2 * top_s + 1] = v
                            top_s += 1
            bw = x1 - x0 + 1
            bh = y1 - y0 + 1
            dx = max(x0 - sx, 0, sx - (x0 + bw - 1))
            dy = max(y0 - sy, 0, sy - (y0 + bh - 1))
            s = dx * dx + dy * dy
            if s < best:
                best = s
                status = FOUND
                bx0, by0, bw0, bh0, ddx, ddy = x0, y0, bw, bh, dx, dy
            elif s == best and (x0 != bx0 or y0 != by0 or bw != bw0 or bh != bh0):
                status = TIE
    return status, topf, bx0, by0, bw0, bh0, ddx, ddy
