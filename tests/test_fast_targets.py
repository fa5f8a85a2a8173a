"""The compiled image alignment (mlplc2.targets._fast_align.align_patch) against mlplc2.targets.alignment.

The NumPy ``align`` is the oracle. The kernel samples, blurs and differentiates the patch in
OpenCV's float32 order (bit for bit here; asserted to a few float32 ulps, the order of
OpenCV's own SIMD paths) and solves the same float64 normal equations, so the alignments agree
to ~1e-12 and the targets of a whole scene to ~1e-10 px. No timings here: see ``mlplc2 bench``.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2 import targets as T
from mlplc2.targets import _fast_align
from mlplc2.targets.alignment import sample_patch
from mlplc2.backend import resolve

W, H = 200, 150


def texture(seed: int = 0, w: int = W, h: int = H) -> np.ndarray:
    """A smooth procedural texture (0-255, float32): blurred, upsampled noise."""
    rng = np.random.default_rng(seed)
    small = rng.random((h // 6 + 2, w // 6 + 2)).astype(np.float32) * 255.0
    img = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    return cv2.GaussianBlur(img, (0, 0), 1.0)


def zoomed(img: np.ndarray, cx: float, cy: float, kx: float, ky: float, dx: float, dy: float) -> np.ndarray:
    """``img`` grown by (kx, ky) about (cx, cy) and shifted by (dx, dy): ``cur(c + d + K (x - c)) = img(x)``."""
    m = np.array([[1 / kx, 0.0, cx - (cx + dx) / kx], [0.0, 1 / ky, cy - (cy + dy) / ky]], np.float32)
    return cv2.warpAffine(img, m, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def both(prev, cur, cx, cy, half, box, n=32, iterations=10):
    pa, pc = T.pyramid(prev), T.pyramid(cur)
    ref = T.align(pa, pc, cx, cy, half, box, n=n, iterations=iterations)
    fast = T.align(pa, pc, cx, cy, half, box, n=n, iterations=iterations, kernel=_fast_align.align_patch)
    return ref, fast


def assert_same(ref: T.Alignment, fast: T.Alignment) -> None:
    for name in ("kx", "ky", "dx", "dy"):
        a, b = getattr(ref, name), getattr(fast, name)
        assert b == pytest.approx(a, rel=1e-6, abs=1e-6), name
    # the rms residual and its sigma: the reference sums them in float32
    assert fast.residual == pytest.approx(ref.residual, rel=1e-5, abs=1e-6)
    assert fast.sigma == pytest.approx(ref.sigma, rel=1e-5, abs=1e-9)


# --- the pieces: sampling and blur ----------------------------------------------------------
@pytest.mark.parametrize("n", [16, 32, 64])
def test_sampling_and_inside_mask_match_opencv(n):
    rng = np.random.default_rng(n)
    levels = T.pyramid(texture(1) + rng.normal(0, 3, (H, W)).astype(np.float32))
    out = np.empty((n, n), np.float32)
    in_x, in_y = np.empty(n, np.bool_), np.empty(n, np.bool_)
    partial = 0
    for _ in range(60):
        level = int(rng.integers(0, len(levels)))
        cx, cy = rng.uniform(-40, W + 40), rng.uniform(-40, H + 40)     # some patches cross the border
        sx, sy = rng.uniform(0.3, 4.0, 2)
        ref, inside = sample_patch(levels, level, cx, cy, sx, sy, n)
        everywhere = _fast_align._sample(levels[level], level, cx, cy, sx, sy, n, out, in_x, in_y,
                                         _fast_align.EXACT_COORDINATES)
        np.testing.assert_array_equal(in_y[:, None] & in_x[None, :], inside)
        assert everywhere == inside.all()
        partial += 0 < inside.sum() < inside.size
        np.testing.assert_allclose(out, ref, rtol=1e-6, atol=1e-4)   # bilinear, replicated border
    assert partial >= 10


@pytest.mark.parametrize("n", [8, 32])
def test_blur_matches_opencv(n):
    rng = np.random.default_rng(n)
    taps = _fast_align._TAPS
    np.testing.assert_array_equal(taps, cv2.getGaussianKernel(7, 0.8, cv2.CV_32F).ravel())
    pad, tmp, out = np.empty(n + taps.size - 1, np.float32), np.empty((n, n), np.float32), np.empty((n, n), np.float32)
    for _ in range(10):
        a = (rng.random((n, n)) * 255).astype(np.float32)
        _fast_align._blur(a, pad, tmp, out, taps)
        np.testing.assert_allclose(out, cv2.GaussianBlur(a, (0, 0), 0.8), rtol=1e-6, atol=1e-4)


# --- whole alignments ---------------------------------------------------------------------------
@pytest.mark.parametrize("kx, ky, dx, dy, half", [
    (1.0, 1.0, 0.0, 0.0, 20.0),
    (1.04, 1.04, 0.7, -0.4, 20.0),       # an approaching object: growth and a sub-pixel shift
    (0.96, 0.96, -1.2, 0.3, 16.0),       # receding
    (1.03, 1.06, 0.2, 0.5, 24.0),        # anisotropic growth
    (1.05, 1.05, 1.5, -2.0, 70.0),       # a large patch: pyramid level 2
])
def test_kernel_matches_reference_on_known_zooms(kx, ky, dx, dy, half):
    prev = texture(2)
    cx, cy = 97.3, 71.8
    cur = zoomed(prev, cx, cy, kx, ky, dx, dy)
    ref, fast = both(prev, cur, cx, cy, half, (half / 1.5, half / 1.5))
    assert ref is not None and fast is not None
    # the reference measures the known warp (the test is not about two wrong answers agreeing)
    assert ref.kx == pytest.approx(kx, abs=3e-3) and ref.ky == pytest.approx(ky, abs=3e-3)
    tol = 0.05 * max(1.0, half / 16.0)           # 0.05 samples, or px at level 0
    assert ref.dx == pytest.approx(dx, abs=tol) and ref.dy == pytest.approx(dy, abs=tol)
    assert_same(ref, fast)


@pytest.mark.parametrize("cx, cy", [(3.0, 70.0), (W - 2.0, 5.0), (-6.0, H + 4.0), (100.0, H - 8.0)])
def test_kernel_matches_reference_at_the_frame_border(cx, cy):
    """Patches partly outside the frame (the inside masks of the template and of every
    resampled patch: samples outside get no weight)."""
    prev = texture(3)
    cur = zoomed(prev, cx, cy, 1.04, 1.04, 0.4, -0.3)
    levels = T.pyramid(prev)
    _, inside = sample_patch(levels, 0, cx, cy, 30.0 / 16, 30.0 / 16, 32)
    assert 0 < inside.sum() < inside.size
    ref, fast = both(prev, cur, cx, cy, 30.0, (20.0, 20.0))
    assert ref is not None and fast is not None
    assert ref.scale == pytest.approx(1.04, abs=0.01)
    assert_same(ref, fast)


def test_flat_or_one_dimensional_patches_give_none():
    flat = np.full((H, W), 90.0, np.float32)
    assert both(flat, flat, 100.0, 75.0, 20.0, (12.0, 12.0)) == (None, None)
    # vertical stripes: the vertical scale and shift are not observable (singular Hessian)
    stripes = np.tile((128 + 60 * np.sin(np.arange(W) / 3.0)).astype(np.float32), (H, 1))
    assert both(stripes, stripes, 100.0, 75.0, 20.0, (12.0, 12.0)) == (None, None)


def test_kernel_matches_reference_when_the_iteration_fails():
    """Unrelated images: the iteration runs away (None) or settles on a poor fit (a large
    residual, rejected by the layer's ``max_residual``), the same in both; and the iteration
    limit is the same (stopped after 1, 2, 3 iterations)."""
    outcomes = set()
    for s in range(4):
        for half in (10.0, 20.0):
            ref, fast = both(texture(10 + s), texture(20 + s), 100.0, 75.0, half, (0.6 * half, 0.6 * half))
            assert (ref is None) == (fast is None)
            if ref is not None:
                assert ref.residual > 25.0
                assert_same(ref, fast)
            outcomes.add(ref is None)
    assert outcomes == {True, False}
    prev = texture(6)
    cur = zoomed(prev, 100.0, 75.0, 1.05, 1.05, 1.0, 0.5)
    last = None
    for iterations in (1, 2, 3):
        ref, fast = both(prev, cur, 100.0, 75.0, 20.0, (13.0, 13.0), iterations=iterations)
        assert ref is not None and fast is not None and ref != last
        assert_same(ref, fast)
        last = ref


def test_dispatch_and_backend():
    assert resolve("numba").align_kernel is _fast_align.align_patch
    assert resolve("reference").align_kernel is None
    for backend, kernel in (("numba", _fast_align.align_patch), ("reference", None)):
        model = mlplc2.MLPLC2(fps=30.0, backend=backend)
        model.step(np.zeros((48, 64), np.uint8))
        assert model._layer.align_kernel is kernel


# --- the targets of a whole scene -----------------------------------------------------------------
@pytest.mark.parametrize("seed, background, duration", [(1, "texture", 2.0), (0, "plain", 3.0)])
def test_targets_agree_with_the_reference_backend(seed, background, duration):
    """mLPLC2's targets with the compiled and the reference backend: the same ids, boxes within
    1e-3 px, times to contact within 1e-3 s (the plain background is the hard case: little
    texture, so a float32 rounding difference used to change which targets were kept)."""
    scene = stimuli.random_scene(seed, kinds=["collision", "pass"], background=background,
                                 duration_s=duration, noise_std=2.0)
    fast, ref = mlplc2.MLPLC2(fps=30.0, backend="numba"), mlplc2.MLPLC2(fps=30.0, backend="reference")
    estimates = 0
    for i, frame in enumerate(scene.frames):
        a, b = fast.step(frame).targets, ref.step(frame).targets
        assert [t.id for t in a] == [t.id for t in b], f"frame {i}"
        for ta, tb in zip(a, b):
            for name in ("x", "y", "width", "height"):
                assert getattr(ta, name) == pytest.approx(getattr(tb, name), abs=1e-3), f"frame {i} {name}"
            assert (ta.ttc_s is None) == (tb.ttc_s is None), f"frame {i}"
            if ta.ttc_s is not None:
                estimates += 1
                assert ta.ttc_s == pytest.approx(tb.ttc_s, abs=1e-3), f"frame {i}"
            assert ta.warning == tb.warning
    assert estimates >= 10


# --- the change box's compiled last steps (mlplc2.targets._fast_change) ---------------------------
def _change_scene(rng):
    """Two frames with a turn of a few px, blobs and rings drawn in one and noise added: regions of
    every shape, often several near a seed, some equally near."""
    prev = cv2.GaussianBlur((rng.random((120, 160)) * 255).astype(np.float32), (0, 0), rng.uniform(0.5, 4))
    cur = np.roll(prev, (int(rng.integers(-3, 4)), int(rng.integers(-3, 4))), axis=(0, 1)).copy()
    for _ in range(int(rng.integers(1, 6))):
        x, y, r = (int(v) for v in (rng.integers(0, 160), rng.integers(0, 120), rng.integers(2, 25)))
        target = cur if rng.random() < 0.5 else prev
        cv2.circle(target, (x, y), r, float(rng.uniform(0, 255)), int(rng.choice([-1, 1, 2, 3])))
    cur += (rng.random(cur.shape) * rng.uniform(0, 8)).astype(np.float32)
    return prev, cur


def test_change_kernel_gives_the_boxes_of_opencv():
    """The kernel's box is the OpenCV path's in every case (the NumPy / OpenCV ``change_box`` is the
    oracle), equally near regions with different boxes included (the kernel then defers to
    OpenCV's label order; at least a few such seeds occur here)."""
    from mlplc2.targets import _fast_change

    calls = {0: 0, 1: 0, 2: 0}

    def counted(*args):
        out = _fast_change.nearest_change(*args)
        calls[out[0]] += 1
        return out

    rng = np.random.default_rng(3)
    boxes = 0
    for _ in range(60):
        prev, cur = _change_scene(rng)
        for _ in range(5):
            x, y = int(rng.integers(-5, 165)), int(rng.integers(-5, 125))
            radius = int(rng.choice([40, 20, 12, 6]))
            kw = dict(min_change=float(rng.choice([3.0, 0.5, 10.0])), rel=float(rng.choice([0.2, 0.05, 0.5])))
            ref = T.change_box(prev, cur, x, y, radius, **kw)
            assert T.change_box(prev, cur, x, y, radius, kernel=counted, **kw) == ref, (x, y, radius, kw)
            boxes += ref is not None
    assert boxes >= 100 and calls[1] >= 100 and calls[2] >= 3, (boxes, calls)


def test_change_kernel_reports_equally_near_regions():
    """Two changed squares on either side of the seed, equally far from it: the kernel does not pick
    one by its own labelling but says TIE; a third region nearer wins outright."""
    from mlplc2.targets import _fast_change

    a = np.zeros((40, 40), np.float32)
    b = a.copy()
    b[18:22, 5:9] = 100.0                 # 11 px left of the seed (20, 20), dilated
    b[18:22, 32:36] = 100.0               # 11 px right of it (the dilation adds a pixel)
    scratch = (np.empty((40, 40), np.float32), np.empty((40, 40), np.uint8), np.empty((40, 40), np.int32),
               np.empty(3200, np.int32))
    out = _fast_change.nearest_change(a, b, 0, 3.0, 0.2, 20, 20, *scratch)
    assert out[0] == _fast_change.TIE and out[1] == 100.0
    b[19:21, 14:16] = 100.0               # 4 px left of it
    status, top, bx, by, bw, bh, dx, dy = _fast_change.nearest_change(a, b, 0, 3.0, 0.2, 20, 20, *scratch)
    assert (status, bx, by, bw, bh, dx, dy) == (_fast_change.FOUND, 13, 18, 4, 4, 4, 0)   # the dilation's pixel
    assert _fast_change.nearest_change(a, a, 0, 3.0, 0.2, 20, 20, *scratch)[0] == _fast_change.NONE


def test_change_kernel_dispatch():
    from mlplc2.targets import _fast_change

    assert resolve("numba").change_kernel is _fast_change.nearest_change
    assert resolve("reference").change_kernel is None
    models = [(mlplc2.MLPLC2(fps=30.0, backend="numba"), _fast_change.nearest_change),
              (mlplc2.MLPLC2(fps=30.0, backend="reference"), None),
              (mlplc2.get_model("flow")(fps=30.0), _fast_change.nearest_change)]   # the flow baseline: always compiled
    for model, kernel in models:
        model.step(np.zeros((48, 64), np.uint8))
        assert model._layer.change_kernel is kernel
