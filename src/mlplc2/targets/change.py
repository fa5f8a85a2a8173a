"""The box of the region that changed between two frames around a point (:func:`change_box`):
the window's own image motion undone by phase correlation, then the connected region of large
grey-level change nearest the point (a faint candidate's box; ``docs/targets.md``, step 2); a uniform
region's box (:func:`uniform_box`, :func:`uniform_region`) and spread (:func:`uniform_spread`); the extent of
the part of a box that moved as the box did (:func:`moving_extent`, ``TargetParams.onset_support``); and the region
that changed once the window's affine motion is undone (:func:`affine_change_box`, ``TargetParams.affine_reseat``).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import cv2
import numpy as np

__all__ = ["Support", "affine_change_box", "change_box", "moving_extent", "uniform_box", "uniform_region",
           "uniform_spread"]


@lru_cache(maxsize=None)
def _even_dft_size(n: int) -> int:
    """The largest m <= n that is even and its own optimal DFT size (``cv2.getOptimalDFTSize``)."""
    m = n
    while m > 2 and (m % 2 or cv2.getOptimalDFTSize(m) != m):
        m -= 1
    return m


@lru_cache(maxsize=64)
def _hanning(shape: tuple[int, int]) -> np.ndarray:
    """The phase correlation's Hanning window for windows of ``shape`` (h, w), made once per shape."""
    win = cv2.createHanningWindow(shape[::-1], cv2.CV_32F)
    win.flags.writeable = False
    return win


_DILATION = np.ones((3, 3), np.uint8)


def change_box(prev: np.ndarray, cur: np.ndarray, x: int, y: int, radius: int, *, min_change: float = 3.0,
               rel: float = 0.2, kernel=None) -> tuple[float, float, float, float] | None:
    """Box ``(cx, cy, w, h)`` of the region that changed between two frames around (x, y).

    Within ``radius`` px of (x, y), the window's own image motion (a turning camera moves the
    background as a whole) is found by phase correlation and undone; then the pixels whose
    grey level, Hann-windowed about the window's centre, still changed by at least ``max(min_change, rel x`` the largest change``)`` are
    joined (3 x 3 dilation) and the connected region nearest to (x, y) is taken: for a small
    object growing against its background, the ring of its edge, hence its size to a pixel,
    long before its edges move a pixel per frame. None when nothing changed or the region
    reaches the window's border (a background that does not move as a whole: no compact
    object to box).

    ``kernel``: the compiled last steps (:func:`mlplc2.targets._fast_change.nearest_change`, the
    same box in every case; :mod:`mlplc2.backend` chooses it), or None (OpenCV and NumPy).
    """
    h, w = cur.shape
    x0, x1 = max(x - radius, 0), min(x + radius + 1, w)
    y0, y1 = max(y - radius, 0), min(y + radius + 1, h)
    if x1 - x0 < 8 or y1 - y0 < 8:
        return None
    # OpenCV's phase correlation reports a spurious half-pixel shift of identical windows whose
    # DFT size is odd (81 px: (0.5, 0.5)); an even DFT size has none
    x1, y1 = x0 + _even_dft_size(x1 - x0), y0 + _even_dft_size(y1 - y0)
    a = np.ascontiguousarray(prev[y0:y1, x0:x1], dtype=np.float32)
    b = np.ascontiguousarray(cur[y0:y1, x0:x1], dtype=np.float32)
    win = _hanning(a.shape)
    # the change is measured on the Hann-windowed windows (a change fades towards the window's
    # border). OpenCV up to 5.0 gave that by a side effect: its phaseCorrelate multiplies its
    # inputs by the window in place; 5.1 leaves them alone. So the window is applied here, and
    # phaseCorrelate gets arrays not used after it (docs/history.md, "Dependencies: OpenCV 5.1").
    # It is given the windowed windows and no window: it multiplies by the window first, the same
    # float32 products, so the same shift (on 3000 random windows with 5.1), without doing it twice
    a, b = a * win, b * win
    (sx, sy), _ = cv2.phaseCorrelate(a, b)     # without a window it leaves its inputs alone
    if abs(sx) > 0.5 or abs(sy) > 0.5:      # the background moved: compare it with itself
        m = np.array([[1.0, 0.0, -sx], [0.0, 1.0, -sy]], np.float32)
        b = cv2.warpAffine(b, m, (b.shape[1], b.shape[0]), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        border = int(math.ceil(max(abs(sx), abs(sy)))) + 1
    else:
        border = 0
    if kernel is not None:                   # the compiled last steps, the same box
        return _compiled(kernel, a, b, border, x, y, x0, y0, x1, y1, w, h, radius, min_change, rel)
    # the replicated margin (border) is not a change
    found = _changed(cv2.absdiff(b, a), border, x - x0, y - y0, min_change, rel)
    return None if found is None else _boxed(*found, x0, y0, x1, y1, w, h, radius)


def _changed(d: np.ndarray, margin: int, sx: int, sy: int, min_change: float, rel: float):
    """(box, distance) of the region of large change in ``d`` nearest (``sx``, ``sy``) (:func:`_nearest`): the
    pixels that changed by at least ``max(min_change, rel x`` the largest change``)``, joined by a 3 x 3 dilation, none
    within ``margin`` px of the border; None where nothing changed by ``min_change``."""
    if margin:
        d[:margin] = 0
        d[-margin:] = 0
        d[:, :margin] = 0
        d[:, -margin:] = 0
    top = float(d.max())
    if top < min_change:
        return None
    mask = cv2.dilate((d >= max(min_change, rel * top)).astype(np.uint8), _DILATION)
    return _nearest(mask, sx, sy)


# affine_change_box: the corners followed (Shi-Tomasi, at most AFFINE_CORNERS, at least AFFINE_SPACING px apart; at
# least AFFINE_FOLLOWED of them followed by pyramidal Lucas-Kanade, AFFINE_WINDOW px, 2 levels), their affine motion
# fitted with RANSAC (AFFINE_RANSAC px); the change within AFFINE_MARGIN px of the window's border is not counted
# (what the warp brought in from beyond it), and a region is an object's only at least AFFINE_MIN px across. The
# corners that fit the map span at least AFFINE_SPREAD of the window on each axis: over a plain background they lie
# on the object alone, and their map is its own growth.
AFFINE_SPREAD = 0.6
AFFINE_CORNERS = 60
AFFINE_SPACING = 4
AFFINE_FOLLOWED = 8
AFFINE_WINDOW = 9
AFFINE_RANSAC = 1.0
AFFINE_MARGIN = 4
AFFINE_MIN = 4


def affine_change_box(prev: np.ndarray, cur: np.ndarray, x: int, y: int, radius: int, *, min_change: float = 3.0,
                      rel: float = 0.2, inliers: float = 0.0) -> tuple[float, float, float, float] | None:
    """Box ``(cx, cy, w, h)`` of the region that changed between two frames around (x, y) once the window's affine
    motion is undone (``TargetParams.affine_reseat``).

    :func:`change_box` undoes a shift of its window: the background seen by a camera that moves forward (the
    ground under a drone) also grows and shears there, and its change fills the window. Here the background's
    motion is the affine map that most corners of the earlier window follow (corners of ``prev`` within
    ``radius`` px of (x, y), followed into ``cur`` by Lucas-Kanade, the map fitted by RANSAC: an object's own
    corners are its outliers); ``prev`` is warped by it, and the pixels that still changed by at least
    ``max(min_change, rel x`` the largest change``)`` are joined (3 x 3 dilation) and the connected region nearest
    (x, y) is taken, within a quarter of ``radius``. None where fewer than :data:`AFFINE_FOLLOWED` corners are
    followed, where fewer than ``inliers`` of them fit the map (a scene whose depth varies across the window: no
    one background motion), where those that fit span less than :data:`AFFINE_SPREAD` of the window on either
    axis (they lie on one thing: an object over a plain background), where nothing changed, where the region reaches within :data:`AFFINE_MARGIN` px of the
    window's border, or is under :data:`AFFINE_MIN` px across."""
    h, w = cur.shape
    x0, x1 = max(x - radius, 0), min(x + radius + 1, w)
    y0, y1 = max(y - radius, 0), min(y + radius + 1, h)
    if x1 - x0 < 16 or y1 - y0 < 16:
        return None
    a = np.ascontiguousarray(prev[y0:y1, x0:x1], dtype=np.float32)
    b = np.ascontiguousarray(cur[y0:y1, x0:x1], dtype=np.float32)
    pts = cv2.goodFeaturesToTrack(a, AFFINE_CORNERS, 0.01, AFFINE_SPACING)
    if pts is None or len(pts) < AFFINE_FOLLOWED:
        return None
    q, st, _ = cv2.calcOpticalFlowPyrLK(np.clip(a, 0, 255).astype(np.uint8), np.clip(b, 0, 255).astype(np.uint8),
                                        pts, None, winSize=(AFFINE_WINDOW, AFFINE_WINDOW), maxLevel=2)
    ok = st.ravel() == 1
    if ok.sum() < AFFINE_FOLLOWED:
        return None
    m, fit = cv2.estimateAffine2D(pts[ok], q[ok], ransacReprojThreshold=AFFINE_RANSAC)
    if m is None or fit.mean() < inliers:
        return None
    on = pts[ok][fit.ravel() == 1].reshape(-1, 2)
    if np.ptp(on[:, 0]) < AFFINE_SPREAD * (x1 - x0) or np.ptp(on[:, 1]) < AFFINE_SPREAD * (y1 - y0):
        return None                          # the corners that fit lie on one thing, not over the background
    d = cv2.absdiff(b, cv2.warpAffine(a, m, (a.shape[1], a.shape[0]), flags=cv2.INTER_LINEAR,
                                      borderMode=cv2.BORDER_REPLICATE))
    e = AFFINE_MARGIN
    found = _changed(d, e, x - x0, y - y0, min_change, rel)
    if found is None or found[1] > radius / 4.0:          # nothing changed, or no region near (x, y)
        return None
    bx, by, bw, bh = found[0]
    if bx < e or by < e or bx + bw > d.shape[1] - e or by + bh > d.shape[0] - e or min(bw, bh) - 2 < AFFINE_MIN:
        return None
    # the dilation added a pixel on each side
    return x0 + bx + bw / 2.0 - 0.5, y0 + by + bh / 2.0 - 0.5, float(bw - 2), float(bh - 2)


def _nearest(mask: np.ndarray, sx: int, sy: int):
    """(box (bx, by, bw, bh), distance) of the 8-connected region of ``mask`` whose bounding box
    lies nearest (``sx``, ``sy``), the first in ``cv2.connectedComponentsWithStats``' label order
    among equally near ones; (None, inf) without a region."""
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    best, best_d = None, math.inf
    for k in range(1, n):
        bx, by, bw, bh = (int(v) for v in stats[k, :4])
        dx = max(bx - sx, 0, sx - (bx + bw - 1))
        dy = max(by - sy, 0, sy - (by + bh - 1))
        dist = math.hypot(dx, dy)
        if dist < best_d:
            best, best_d = (bx, by, bw, bh), dist
    return best, best_d


def _compiled(kernel, a, b, border, x, y, x0, y0, x1, y1, w, h, radius, min_change, rel):
    """:func:`change_box`'s steps after the phase correlation with the compiled ``kernel``
    (:func:`mlplc2.targets._fast_change.nearest_change`); OpenCV's labels where it reports
    equally near regions with different boxes."""
    shape = a.shape
    d = np.empty(shape, np.float32)
    mask = np.empty(shape, np.uint8)
    labels = np.empty(shape, np.int32)
    stack = np.empty(2 * shape[0] * shape[1], np.int32)
    status, _, bx, by, bw, bh, dx, dy = kernel(a, b, int(border), float(min_change), float(rel), int(x - x0),
                                               int(y - y0), d, mask, labels, stack)
    if status == 0:
        return None
    if status == 1:
        best, best_d = (int(bx), int(by), int(bw), int(bh)), math.hypot(int(dx), int(dy))
    else:
        best, best_d = _nearest(mask, x - x0, y - y0)
    return _boxed(best, best_d, x0, y0, x1, y1, w, h, radius)


def _boxed(best, best_d, x0, y0, x1, y1, w, h, radius):
    """:func:`change_box`'s answer for the nearest region's box ``best`` (window px) at ``best_d``."""
    if best is None or best_d > radius / 4.0:
        return None
    bx, by, bw, bh = best
    inner_x = (x0 > 0 and bx == 0) or (x1 < w and bx + bw == x1 - x0)
    inner_y = (y0 > 0 and by == 0) or (y1 < h and by + bh == y1 - y0)
    if inner_x or inner_y:
        return None
    # the dilation added a pixel on each side
    return x0 + bx + bw / 2.0 - 0.5, y0 + by + bh / 2.0 - 0.5, max(bw - 2.0, 1.0), max(bh - 2.0, 1.0)


def _flood(img: np.ndarray, mask: np.ndarray, x: int, y: int, tol: float):
    """The 4-connected pixels within ``tol`` grey levels of the pixel (x, y) (a fixed-range flood fill
    into ``mask``, cleared first): (count, (bx, by, bw, bh))."""
    mask[:] = 0
    flags = 4 | cv2.FLOODFILL_MASK_ONLY | cv2.FLOODFILL_FIXED_RANGE | (1 << 8)
    n, _, _, rect = cv2.floodFill(img, mask, (int(x), int(y)), 0, tol, tol, flags)
    return n, rect


def _compact(n: int, rect, w: int, h: int, fill: float, aspect: float, min_px: float, cut: bool = False) -> bool:
    """Whether a region of ``n`` px with bounding box ``rect`` is a compact object in a frame of
    w x h px: it fills ``fill`` of its box, is at least ``min_px`` across, at most ``aspect``
    elongated and (unless ``cut``) does not touch the frame's border."""
    bx, by, bw, bh = rect
    inside = bx > 0 and by > 0 and bx + bw < w and by + bh < h
    return (min(bw, bh) >= min_px and max(bw, bh) <= aspect * min(bw, bh) and (cut or inside)
            and n >= fill * bw * bh)


def uniform_region(gray: np.ndarray, x: float, y: float, tol: float, *, fill: float = 0.7, aspect: float = 2.0,
                   min_px: float = 8.0, cut: bool = True) -> tuple[float, float, float, float] | None:
    """Box ``(cx, cy, w, h)`` of the uniform region at the point (x, y) (:func:`uniform_box`'s region
    from that one start, ``TargetParams.uniform_reseat``), None when it is not a compact object; with
    ``cut`` a region at the frame's border counts (the visible part of an object leaving the view)."""
    found = uniform_spread(gray, x, y, tol, fill=fill, aspect=aspect, min_px=min_px, cut=cut, spread=False)
    return None if found is None else found[0]


#: :func:`uniform_spread`: the width (px) of the ring outside a region's rim whose median grey level is the
#: background's, and the least contrast (grey levels) between the region and that background for its rim's pixels
#: to be weighted by their coverage (below it each counts half)
SPREAD_RING = 2
SPREAD_CONTRAST = 8.0


def _median(a: np.ndarray) -> float:
    """``np.median`` of a non-empty 1-D array, by one partial sort (a fraction of its cost on the few hundred pixels
    of a region's rim or ring)."""
    n = a.size
    k = n // 2
    if n % 2:
        return float(np.partition(a, k)[k])
    return float(np.partition(a, (k - 1, k))[k - 1:k + 1].mean())


def uniform_spread(gray: np.ndarray, x: float, y: float, tol: float, *, fill: float = 0.7, aspect: float = 2.0,
                   min_px: float = 8.0, cut: bool = True, spread: bool = True):
    """:func:`uniform_region`'s box and the region's spread ``(sx, sy)``: the standard deviations of its pixels'
    columns and rows, its 1-px rim (the pixels beside it, outside the flood fill's tolerance) weighted by their
    coverage, ``(I - b) / (v - b)`` clipped to [0, 1], from the region's median grey level ``v`` and the background's
    ``b`` (the median of the :data:`SPREAD_RING` px beyond the rim). ``TargetParams.uniform_spread``: a region counted
    in whole pixels grows by a ring of them at a time (a 20-px disc's box 19 -> 21 px in one frame), its rim's
    coverage grows smoothly; a disc of radius r has a spread of r / 2. ``(box, None)`` with ``spread`` False; None
    when the region is not a compact object."""
    h, w = gray.shape
    xi, yi = int(round(x)), int(round(y))
    if not (0 <= xi < w and 0 <= yi < h):
        return None
    mask = np.zeros((h + 2, w + 2), np.uint8)
    n, rect = _flood(np.ascontiguousarray(gray, dtype=np.float32), mask, xi, yi, tol)
    if not _compact(n, rect, w, h, fill, aspect, min_px, cut):
        return None
    bx, by, bw, bh = rect
    box = bx + bw / 2.0 - 0.5, by + bh / 2.0 - 0.5, float(bw), float(bh)
    if not spread:
        return box, None
    pad = 1 + SPREAD_RING
    x0, y0, x1, y1 = max(bx - pad, 0), max(by - pad, 0), min(bx + bw + pad, w), min(by + bh + pad, h)
    inside = mask[y0 + 1:y1 + 1, x0 + 1:x1 + 1]
    img = np.asarray(gray[y0:y1, x0:x1], np.float32)
    near = cv2.dilate(inside, _DILATION) > 0
    rim = near & (inside == 0)
    ring = (cv2.dilate(inside, _DILATION, iterations=pad) > 0) & ~near
    weights = inside.astype(np.float32)
    v = _median(img[inside > 0])
    b = _median(img[ring]) if ring.any() else v
    if abs(v - b) >= SPREAD_CONTRAST:
        weights[rim] = np.clip((img[rim] - b) / (v - b), 0.0, 1.0)
    else:
        weights[rim] = 0.5
    m = cv2.moments(weights)
    return box, (math.sqrt(max(m["mu20"], 1e-9) / m["m00"]), math.sqrt(max(m["mu02"], 1e-9) / m["m00"]))


def uniform_box(gray: np.ndarray, x: int, y: int, reach: float, tol: float, *, fill: float = 0.7,
                aspect: float = 2.0, min_px: float = 8.0) -> tuple[float, float, float, float] | None:
    """Box ``(cx, cy, w, h)`` of the uniform region beside the point (x, y), or None
    (``TargetParams.uniform_tol``): from start points ``reach`` / 3, 2 ``reach`` / 3 and ``reach``
    px from (x, y) in 8 directions, the 4-connected pixels within ``tol`` grey levels of the start's
    (a flood fill of fixed range); of the regions that fill at least ``fill`` of their bounding box,
    are at least ``min_px`` across, at most ``aspect`` elongated and do not touch the frame's border,
    the largest. A uniform object's seed lies on its outline (its only local motion and change):
    the region beside it is the object's whole extent."""
    h, w = gray.shape
    img = np.ascontiguousarray(gray, dtype=np.float32)
    done = np.zeros((h + 2, w + 2), np.uint8)
    best, best_area = None, 0
    mask = np.zeros((h + 2, w + 2), np.uint8)
    for k in (1, 2, 3):
        d = reach * k / 3.0
        for ux, uy in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)):
            sx, sy = int(round(x + ux * d)), int(round(y + uy * d))
            if not (0 <= sx < w and 0 <= sy < h) or done[sy + 1, sx + 1]:
                continue
            n, rect = _flood(img, mask, sx, sy, tol)
            done |= mask
            if not _compact(n, rect, w, h, fill, aspect, min_px) or n <= best_area:
                continue
            bx, by, bw, bh = rect
            best, best_area = (bx + bw / 2.0 - 0.5, by + bh / 2.0 - 0.5, float(bw), float(bh)), n
    return best


# moving_extent: a pixel belongs to the box's object where it changed since the reference frame by at least
# SUPPORT_CHANGE grey levels and the box's own motion explains the change to within SUPPORT_EXPLAINED of it; it is
# seen to stay still where the box's motion would have changed it by that much and the still scene explains that
# to within SUPPORT_EXPLAINED; both differences are smoothed over SUPPORT_BLUR px (the grain of a codec's or a
# sensor's noise, not an object's edge). The box put on the moving part (TargetParams.support_reseat) spans
# SUPPORT_PAD times its 5th-95th percentile span (which leaves out a tenth of it).
SUPPORT_CHANGE = 6.0
SUPPORT_EXPLAINED = 0.5
SUPPORT_BLUR = 1.5
SUPPORT_PAD = 1.1


class Support(NamedTuple):
    """:func:`moving_extent`'s answer: the part of a box that moves with it, and what lies beyond that part."""

    width: float        #: the part's 5th-95th percentile span on x (px)
    height: float       #: ... on y
    pixels: int         #: how many pixels it counts
    x: float            #: the centre of that span on x
    y: float            #: ... on y
    beyond: tuple[int, int]   #: the box's pixels more than 1 px beyond the part's own box (SUPPORT_PAD times its span) on x, on y
    still: tuple[int, int]    #: of those, the ones seen to stay still (the still scene, not the box's motion, explains them)


def moving_extent(prev: np.ndarray, cur: np.ndarray, box: tuple[float, float, float, float],
                  then: tuple[float, float, float, float]) -> Support | None:
    """The part of ``box`` (centre x, y, width, height in ``cur``) that moves as the box moved since ``prev`` (the
    same camera's earlier frame, compensated into ``cur``'s pixels: a still scene stays put), where it was ``then``
    (centre x, y, width, height in those pixels): a point of the box at ``c + u`` now was at
    ``c_then + u * (w_then / w, h_then / h)``.

    A pixel of the box counts where its grey level changed since ``prev`` by at least :data:`SUPPORT_CHANGE`
    (it moved) and the box's motion undoes that change to within :data:`SUPPORT_EXPLAINED` of it (it moved with
    the box), both differences smoothed over :data:`SUPPORT_BLUR` px: the object's texture and edges, not the
    still background beside it, which changed nowhere, nor a background moving otherwise. The extent is the span
    of those pixels' coordinates from the 5th to the 95th percentile on each axis (the edge ring of a uniform
    object spans it too). A pixel is seen to stay still where the box's motion would change it by at least
    :data:`SUPPORT_CHANGE` and the still scene explains it to within :data:`SUPPORT_EXPLAINED`: textured
    background, not a plain one (nor a uniform object's plain inside), which says nothing either way
    (:class:`Support`, ``still``). None when the box lies outside the frames or has no size."""
    cx, cy, w, h = box
    tx, ty, tw, th = then
    hh, ww = cur.shape
    x0, x1 = int(max(math.floor(cx - w / 2.0), 0)), int(min(math.ceil(cx + w / 2.0) + 1, ww))
    y0, y1 = int(max(math.floor(cy - h / 2.0), 0)), int(min(math.ceil(cy + h / 2.0) + 1, hh))
    if x1 - x0 < 2 or y1 - y0 < 2 or min(w, h, tw, th) <= 0:
        return None
    # the window with a margin for the smoothing, then the box's pixels of it
    m = int(math.ceil(3 * SUPPORT_BLUR))
    a0, a1, b0, b1 = max(x0 - m, 0), min(x1 + m, ww), max(y0 - m, 0), min(y1 + m, hh)
    yy, xx = np.mgrid[b0:b1, a0:a1].astype(np.float32)
    mx = (tx + (xx - cx) * (tw / w)).astype(np.float32)      # where each pixel was, moving with the box
    my = (ty + (yy - cy) * (th / h)).astype(np.float32)
    before = np.ascontiguousarray(prev, dtype=np.float32)
    now = np.asarray(cur[b0:b1, a0:a1], dtype=np.float32)
    moved = cv2.remap(before, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    e_box = cv2.GaussianBlur(np.abs(now - moved), (0, 0), SUPPORT_BLUR)
    e_still = cv2.GaussianBlur(np.abs(now - before[b0:b1, a0:a1]), (0, 0), SUPPORT_BLUR)
    inside = (np.abs(xx - cx) <= w / 2.0) & (np.abs(yy - cy) <= h / 2.0)
    on = inside & (e_still >= SUPPORT_CHANGE) & (e_box <= SUPPORT_EXPLAINED * e_still)
    n = int(on.sum())
    if n == 0:
        return Support(0.0, 0.0, 0, cx, cy, (0, 0), (0, 0))
    xs, ys = xx[on], yy[on]
    (xa, xb), (ya, yb) = np.percentile(xs, [5, 95]), np.percentile(ys, [5, 95])
    still = inside & (e_box >= SUPPORT_CHANGE) & (e_still <= SUPPORT_EXPLAINED * e_box)
    half = (SUPPORT_PAD - 1.0) / 2.0              # the part's box reaches this share of its span beyond it
    px, py = half * (xb - xa) + 1.0, half * (yb - ya) + 1.0
    bx, by = inside & ((xx < xa - px) | (xx > xb + px)), inside & ((yy < ya - py) | (yy > yb + py))
    return Support(float(xb - xa), float(yb - ya), n, float(xa + xb) / 2.0, float(ya + yb) / 2.0,
                   (int(bx.sum()), int(by.sum())), (int((still & bx).sum()), int((still & by).sum())))


def ground_matrix(kappa: float, heading: tuple[float, float]) -> np.ndarray:
    """The homography (this frame's pixels -> an earlier frame's) of the ground plane under a camera that
    translates parallel to it towards ``heading`` (px; its row is the horizon, the ground plane's vanishing
    line): a ground point at ``p`` now was at ``h + (p - h) / (1 + kappa (y - y_h))``, ``kappa`` the distance
    driven over the camera's height and focal length (1/px). Above the horizon it is not the ground's."""
    hx, hy = heading
    k = float(kappa)
    return np.array([[1.0, k * hx, -k * hx * hy], [0.0, 1.0 + k * hy, -k * hy * hy], [0.0, k, 1.0 - k * hy]])


#: :func:`ground_kappa`: the ground's scaling searched (the most over the frame's bottom row, ``kappa (H - y_h)``)
GROUND_MAX_SCALE = 1.5
#: :func:`ground_kappa`: how much the ground warp must lower the ground's mean change to be taken
GROUND_GAIN = 0.8
#: :func:`ground_kappa`: the horizon's rows searched about the heading's (px of the frame searched)
GROUND_ROWS = (-3, -2, -1, 0, 1, 2, 3)
#: :func:`ground_kappa`: a change counts up to this many grey levels (an object on the ground is not the ground)
GROUND_CLIP = 40.0


def ground_kappa(prev: np.ndarray, cur: np.ndarray, heading: tuple[float, float], *, steps: int = 12,
                 margin: int = 2) -> tuple[float, tuple[float, float]]:
    """The ground's ``kappa`` and horizon (:func:`ground_matrix`) between ``prev`` and ``cur`` (same size;
    ``heading`` in their pixels): the pair that makes the mean absolute change (clipped at ``GROUND_CLIP``: an
    object on the ground is not the ground) ``margin`` px and more below the horizon least, searched over
    ``steps`` values in ``(0, GROUND_MAX_SCALE / (H - y_h)]`` on the heading's row, then the rows
    ``GROUND_ROWS`` about it at the best value and a step either side, then half a step either side of the
    best value and half a row either side of the best row; ``(0, heading)`` where the best lowers the change by
    less than ``GROUND_GAIN`` times (no ground, or one that does not move as the plane)."""
    h, w = cur.shape
    top = int(math.ceil(heading[1] + max(GROUND_ROWS))) + margin
    if top >= h - 4 or top < 0:
        return 0.0, heading
    below = np.asarray(cur, np.float32)[top:]
    src = np.asarray(prev, np.float32)
    shift = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, float(top)], [0.0, 0.0, 1.0]])   # only the rows below

    def cost(k: float, hy: float) -> float:
        back = cv2.warpPerspective(src, ground_matrix(k, (heading[0], hy)) @ shift, (w, h - top),
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)
        return float(np.minimum(cv2.absdiff(back, below), GROUND_CLIP).mean())

    step = GROUND_MAX_SCALE / max(h - heading[1], 1.0) / steps
    still = cost(0.0, heading[1])
    best, best_cost = (0.0, heading[1]), still

    def tries(pairs):
        nonlocal best, best_cost
        for k, hy in pairs:
            if k > 0:
                c = cost(k, hy)
                if c < best_cost:
                    best, best_cost = (k, hy), c

    tries((i * step, heading[1]) for i in range(1, steps + 1))
    k0 = best[0]
    tries((k, heading[1] + r) for r in GROUND_ROWS if r for k in (k0 - step, k0, k0 + step))
    tries((best[0] + d, best[1]) for d in (-step / 2, step / 2))
    tries((best[0], best[1] + d) for d in (-0.5, 0.5))
    if best_cost > GROUND_GAIN * still:
        return 0.0, heading
    return float(best[0]), (heading[0], float(best[1]))


def ground_reference(prev: np.ndarray, kappa: float, heading: tuple[float, float]) -> np.ndarray:
    """``prev`` with its ground (below the horizon, ``heading``'s row) carried into the later frame's pixels
    (:func:`ground_matrix`), the rest as it was. Only the rows below the horizon are warped (as
    :func:`ground_kappa` does): above it the plane's homography sends the rows near the horizon to the
    vanishing line at infinity, where ``cv2.warpPerspective`` (OpenCV 5.1) can crash the process
    (``tests/test_targets.py``)."""
    h, w = prev.shape
    src = np.asarray(prev, np.float32)
    if kappa <= 0:
        return src
    top = min(max(int(math.ceil(heading[1])), 0), h)
    out = src.copy()
    if top < h:
        shift = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, float(top)], [0.0, 0.0, 1.0]])   # only the rows below
        out[top:] = cv2.warpPerspective(src, ground_matrix(kappa, heading) @ shift, (w, h - top),
                                        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)
    return out
