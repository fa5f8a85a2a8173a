"""The finer front-end channel (``Params.fine_scale``, beyond the paper; docs/model.md, "A finer
channel for small objects"): its LM feeds the fields only where the coarse channel is silent."""

from __future__ import annotations

import numpy as np

import mlplc2

W, H = 160, 120


def looming_texture(n: int = 40, seed: int = 0):
    """A textured square whose mean grey is the background's (no outline), centred, looming:
    side 300 / (n + 3 - t) px (7 px -> 75 px). Yields (frame, side)."""
    rng = np.random.default_rng(seed)
    tex = np.where(rng.random((64, 64)) < 0.5, 80, 176).astype(np.uint8)
    ys, xs = np.mgrid[0:H, 0:W]
    for t in range(n):
        side = 300.0 / (n + 3 - t)
        f = np.full((H, W), 128, np.uint8)
        inside = (abs(xs - W / 2 + 0.5) <= side / 2) & (abs(ys - H / 2 + 0.5) <= side / 2)
        u = ((xs - W / 2) / side * 4).astype(int) % 64        # four texture cells across the object
        v = ((ys - H / 2) / side * 4).astype(int) % 64
        f[inside] = tex[v[inside], u[inside]]
        yield f, side


def first_answer(params: mlplc2.Params) -> float | None:
    """The object's side (px) when a field holding its centre first answers (Eq. 15 > 0)."""
    model = mlplc2.MLPLC2(30.0, params)
    for frame, side in looming_texture():
        out = model.step(frame)
        if any(f.response > 0 and abs(f.x - W // 2) <= f.radius and abs(f.y - H // 2) <= f.radius
               for f in out.fields):
            return side
    return None


def fields_over(params: mlplc2.Params):
    model = mlplc2.MLPLC2(30.0, params)
    return [tuple((f.id, f.x, f.y, round(f.response, 3)) for f in model.step(frame).fields)
            for frame, _ in looming_texture(24)]


def test_fine_channel_answers_a_small_textured_object_earlier():
    coarse = first_answer(mlplc2.Params())
    fine = first_answer(mlplc2.Params(fine_scale=0.5))
    assert fine is not None and coarse is not None
    assert fine < 40 <= coarse          # Table I's 23-px window averages the texture away until ~40 px


def test_fine_params_scale_the_windows_only():
    p = mlplc2.Params(fine_scale=0.5).fine_params()
    assert (p.r_e, p.sigma_e, p.r_i, p.sigma_i, p.r_c, p.sigma_c) == (3, 5.0, 6, 10.0, 3, 10.0)
    assert p.fine_scale == 0 and p.t_a == mlplc2.Params().t_a and p.lm_gain == mlplc2.Params().lm_gain


def test_silent_level_picks_the_channel():
    # nothing is below LM 0: the coarse channel everywhere, the paper's model
    assert fields_over(mlplc2.Params(fine_scale=0.5, fine_silent=0.0)) == fields_over(mlplc2.Params())
    # everything is below 1e30: the fine channel everywhere, a model with the fine windows
    fine = mlplc2.Params(fine_scale=0.5).fine_params()
    assert fields_over(mlplc2.Params(fine_scale=0.5, fine_silent=1e30)) == fields_over(fine)


def test_target_layer_sees_the_coarse_maps():
    coarse, both = mlplc2.MLPLC2(30.0), mlplc2.MLPLC2(30.0, mlplc2.Params(fine_scale=0.5))
    for frame, _ in looming_texture(20):
        coarse.step(frame)
        both.step(frame)
    np.testing.assert_array_equal(both.maps.magnitude, coarse.maps.magnitude)
