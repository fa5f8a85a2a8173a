"""Front end, Eq. 1-12: stages in isolation and direction selectivity of every detector."""

from __future__ import annotations

import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2.neuropils.frontend import FrontEnd
from mlplc2.neuropils.lamina import gaussian_kernel_1d, on_off, vdog
from mlplc2.neuropils.medulla import contrast_normalise, shift
from mlplc2.neuropils.retina import photoreceptors

SIZE = 80


def moving_edge(direction: str, polarity: str, n: int = 24, speed: int = 1):
    """A half-plane edge sweeping in ``direction``; 'off' = dark advancing, 'on' = bright."""
    back, fore = (250.0, 0.0) if polarity == "off" else (0.0, 250.0)
    frames = []
    for t in range(n):
        img = np.full((SIZE, SIZE), back, np.float32)
        pos = 20 + speed * t
        if direction == "r":
            img[:, :pos] = fore
        elif direction == "l":
            img[:, SIZE - pos:] = fore
        elif direction == "d":
            img[:pos, :] = fore
        else:
            img[SIZE - pos:, :] = fore
        frames.append(img)
    return frames


def direction_energy(frames):
    fe = FrontEnd(mlplc2.Params(), fps=30.0)
    total = dict.fromkeys("rldu", 0.0)
    for i, frame in enumerate(frames):
        lm = fe.step(frame)
        if i >= 4:
            for k in total:
                total[k] += float(np.maximum(lm.direction(k), 0).sum())
    return total


OPPOSITE = {"r": "l", "l": "r", "d": "u", "u": "d"}


@pytest.mark.parametrize("polarity", ["on", "off"])
@pytest.mark.parametrize("direction", list("rldu"))
def test_detector_prefers_its_direction(direction, polarity):
    """Each of LM_r, LM_l, LM_d, LM_u, fed by T4 (ON) or T5 (OFF), answers its own
    direction more than the opposite one (NOTES 9)."""
    energy = direction_energy(moving_edge(direction, polarity))
    assert energy[direction] > 5 * energy[OPPOSITE[direction]]
    assert energy[direction] > 0


@pytest.mark.parametrize("direction", list("rldu"))
def test_channels_are_polarity_selective(direction):
    """A darkening edge drives only T5 (OFF), a brightening one only T4 (ON)."""
    fe = FrontEnd(mlplc2.Params(), fps=30.0)
    frames = moving_edge(direction, "off")
    l = photoreceptors(frames[5], frames[4])
    lv = vdog(l, fe.k_e, fe.k_i, fe.params.w_i)
    on, off = on_off(lv)
    assert off.max() > 1 and on.max() == 0


def test_retina_is_frame_difference():
    a = np.full((5, 6), 10, np.float32)
    b = a + 7
    assert np.array_equal(photoreceptors(b, a), np.full((5, 6), 7, np.float32))
    assert not photoreceptors(a, None).any()


def test_kernels_normalised_or_literal():
    k = gaussian_kernel_1d(5, 10.0, normalise=True)
    assert np.isclose(np.outer(k, k).sum(), 1.0, atol=1e-5)
    literal = gaussian_kernel_1d(5, 10.0, normalise=False)
    # Eq. 3 on the 11x11 window sums to ~0.175 (NOTES 3).
    assert np.isclose(np.outer(literal, literal).sum(), 0.175, atol=0.01)


def test_vdog_keeps_sign_of_excitation_and_never_amplifies():
    rng = np.random.default_rng(0)
    l = rng.normal(0, 30, (40, 40)).astype(np.float32)
    fe = FrontEnd(mlplc2.Params(), fps=30.0)
    from mlplc2.neuropils.lamina import gaussian_filter

    e = gaussian_filter(l, fe.k_e)
    out = vdog(l, fe.k_e, fe.k_i, 1.2)
    assert np.all(out * e >= 0)
    assert np.all(np.abs(out) <= np.abs(e) + 1e-5)


def test_contrast_normalisation_is_bounded():
    n = np.linspace(0, 1000, 400, dtype=np.float32).reshape(20, 20)
    k = gaussian_kernel_1d(5, 20.0)
    out = contrast_normalise(n, k, 25.0)
    assert out.min() >= 0 and out.max() < 1


def test_shift_convention():
    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    b = shift(a, 1, 0)  # b[y, x] = a[y, x + 1]
    assert b[0, 0] == a[0, 1] and b[0, 3] == 0
    c = shift(a, 0, -1)  # c[y, x] = a[y - 1, x]
    assert c[1, 2] == a[0, 2] and not c[0].any()


def test_frame_interval_comes_from_fps():
    p = mlplc2.Params()
    slow, fast = FrontEnd(p, fps=10.0), FrontEnd(p, fps=100.0)
    assert slow.alphas[0] > fast.alphas[0]
    tau_i = 1000.0 / 10.0
    assert np.isclose(slow.alphas[0], tau_i / (tau_i + p.tau_1))
    assert np.allclose(p.delays_ms(), (80, 70, 60, 50, 40))


def test_the_output_delay_and_the_last_correlator_delay_are_set_apart():
    """Eq. 10's output filter takes its delay from ``tau_out`` (read as Table I's tau_Nc, 40 ms), the correlators'
    last distance from ``tau_nc``: each changes alone, on both front ends alike."""
    from mlplc2.backend import make_frontend

    tau_i = 1000.0 / 30.0
    p = mlplc2.Params()
    assert p.tau_out == p.tau_nc == 40.0
    for tau_out, tau_nc in ((30.0, 40.0), (40.0, 60.0)):
        q = p.replace(tau_out=tau_out, tau_nc=tau_nc)
        fe = FrontEnd(q, fps=30.0)
        assert np.isclose(fe.alpha_out, tau_i / (tau_i + tau_out))
        assert np.isclose(fe.alphas[-1], tau_i / (tau_i + tau_nc))
    frames = moving_edge("r", "off", n=8)
    maps = {}
    for backend in ("reference", "numba"):
        for tau_out in (40.0, 30.0):
            fe = make_frontend(p.replace(tau_out=tau_out), 30.0, backend)
            for f in frames:
                lm = fe.step(f)
            maps[backend, tau_out] = lm.magnitude.copy()
    assert not np.allclose(maps["reference", 40.0], maps["reference", 30.0])   # the output delay matters
    for tau_out in (40.0, 30.0):
        assert np.allclose(maps["reference", tau_out], maps["numba", tau_out], atol=1e-4)


def test_maps_are_reachable_after_step():
    model = mlplc2.MLPLC2(fps=30.0)
    frames = moving_edge("r", "off", n=6)
    for f in frames:
        model.step(f)
    lm = model.maps
    assert lm.magnitude.shape == (SIZE, SIZE)
    assert np.allclose(lm.magnitude, np.sqrt(np.maximum(lm.r, lm.l) ** 2 + np.maximum(lm.d, lm.u) ** 2))


def test_relative_floor_zeroes_the_tails_of_each_band():
    """Params.n_floor: N below n_floor x its local maximum (radius n_floor_radius) is 0, the
    rest unchanged; the fast path does the same."""
    rng = np.random.default_rng(1)
    sig = rng.uniform(0, 60, (40, 50)).astype(np.float32)
    k_c = gaussian_kernel_1d(5, 20.0)
    plain = contrast_normalise(sig, k_c, 25.0)
    floored = contrast_normalise(sig, k_c, 25.0, floor=0.8, floor_radius=3)
    # the local maximum, by brute force
    pad = np.pad(plain, 3)
    lmax = np.max([pad[dy:dy + 40, dx:dx + 50] for dy in range(7) for dx in range(7)], axis=0)
    cut = plain < 0.8 * lmax
    assert cut.any() and (~cut).any()
    assert np.all(floored[cut] == 0)
    np.testing.assert_array_equal(floored[~cut], plain[~cut])
    pytest.importorskip("numba")
    st = stimuli.basic("bright_recede")
    params = mlplc2.Params(n_floor=0.35)
    ref = mlplc2.LPLC2(fps=30.0, params=params, backend="reference")
    fast = mlplc2.LPLC2(fps=30.0, params=params, backend="numba")
    for frame in st.frames[:12]:
        ref.step(frame)
        fast.step(frame)
        np.testing.assert_allclose(fast.maps.magnitude, ref.maps.magnitude, rtol=1e-4, atol=1e-4)
