"""The per-frame contract every registered model honours (one suite, parametrised
over :data:`mlplc2.models.REGISTRY`): step/reset, frame counting, input never
modified, bit-identical determinism across runs, across ``reset()`` and after
pickling/copying, immutable default parameters, frame-size changes, channel
handling and the input checks of ``Model.step``.

A model added to the registry is picked up here automatically.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import cv2
import numpy as np
import pytest

import mlplc2
from mlplc2 import Field, InputError, Output
from mlplc2.models import REGISTRY, get_model, resolve_names

NAMES = sorted(REGISTRY)
H, W = 48, 64
N = 24


def _looming_rgb(n: int = N, h: int = H, w: int = W, seed: int = 0) -> list[np.ndarray]:
    """A dark square growing on a textured background (RGB uint8): every model responds."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 3)
    bg = cv2.normalize(bg, None, 120, 220, cv2.NORM_MINMAX).astype(np.uint8)
    frames = []
    for i in range(n):
        f = bg.copy()
        side = 2 * i + 2
        y0, x0 = max(h // 2 - side // 2, 0), max(w // 2 - side // 2, 0)
        f[y0:y0 + side, x0:x0 + side] = 10
        f = np.stack([f, f - f // 8, f // 2 + 100], axis=-1)  # unequal channels: luma matters
        frames.append(f)
    return frames


@pytest.fixture(scope="module")
def frames():
    return _looming_rgb()


def _all_outputs(model, frames) -> list[Output]:
    return [model.step(f) for f in frames]


def _state_of(model):
    """Everything observable after a frame: outputs are compared separately, this adds the maps."""
    maps = getattr(model, "maps", None)
    if maps is None:
        return None
    return [getattr(maps, k).copy() for k in ("r", "l", "d", "u", "magnitude")]


def _assert_identical(a: list[Output], b: list[Output]) -> None:
    """Bit-identical outputs (floats compared with ==, including the field quadrants)."""
    assert len(a) == len(b)
    for oa, ob in zip(a, b):
        assert oa == ob, (oa, ob)
        # == on floats is exact, but spell out the bit-level check for the response
        assert np.float64(oa.response).tobytes() == np.float64(ob.response).tobytes()


# -- registry ------------------------------------------------------------------------
def test_registry_has_every_model():
    assert set(NAMES) >= {"mlplc2", "slplc2", "lplc2", "lgmd2", "lgmd1"}
    assert mlplc2.available_models() == NAMES
    for name in NAMES:
        assert REGISTRY[name].name == name
        assert get_model(name.upper()) is REGISTRY[name]
    with pytest.raises(InputError, match="unknown model 'nope'; choose from") as info:
        get_model("nope")
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("value, names", [
    ("mlplc2", ["mlplc2"]), (" MLPLC2 , lgmd2,", ["mlplc2", "lgmd2"]), (["lgmd2", "mlplc2,LGMD2"], ["lgmd2", "mlplc2"]),
    (("slplc2",), ["slplc2"]),
])
def test_resolve_names_one_parser_of_model_names(value, names):
    assert resolve_names(value) == names


@pytest.mark.parametrize("value, message", [
    ("mlplc2,nope", "unknown model 'nope'; choose from " + ", ".join(NAMES)), (",,", "models needs at least one"),
    ([], "models needs at least one"), (5, "models must be a model name or a list"), ([None], r"model names \(str\)"),
])
def test_resolve_names_bad_values_are_one_line_errors(value, message):
    with pytest.raises(InputError, match=message) as info:
        resolve_names(value)
    assert "\n" not in str(info.value)


def test_every_entry_point_reads_model_names_alike(tmp_path, monkeypatch):
    """run, batch, evaluate and benchmark take the same spellings (benchmark and run used to
    reject upper case or a comma-separated list item)."""
    from mlplc2 import batch, benchmark

    video = tmp_path / "v.avi"
    from mlplc2.io import write_video

    write_video(video, np.full((3, 48, 64), 128, np.uint8), 30.0)
    assert mlplc2.run(video, ["MLPLC2, lgmd2", "mlplc2"], out=False, quiet=True).models == ["mlplc2", "lgmd2"]

    class Reached(Exception):
        pass

    def stop(*args, **kwargs):
        raise Reached

    monkeypatch.setattr(benchmark, "suite", stop)
    with pytest.raises(Reached):   # past the model names
        benchmark.benchmark(tmp_path / "b", quick=True, models="MLPLC2,Flow")
    for call in (lambda m: benchmark.benchmark(tmp_path / "b", quick=True, models=m),
                 lambda m: batch.batch([video], tmp_path / "o", models=m, workers=0),
                 lambda m: mlplc2.evaluate(video, {"videos": {"v.avi": {"objects": []}}}, models=m),
                 lambda m: mlplc2.run(video, m, out=False)):
        with pytest.raises(InputError, match="unknown model 'nope'; choose from"):
            call("mlplc2, NOPE")


# -- step / reset / run ---------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_step_returns_outputs_and_counts_frames(name, frames):
    model = REGISTRY[name](fps=30.0)
    assert model.frame_index == 0
    outs = []
    for i, f in enumerate(frames):
        out = model.step(f)
        assert isinstance(out, Output)
        assert out.frame == i and model.frame_index == i + 1
        assert isinstance(out.response, float) and math.isfinite(out.response)
        assert isinstance(out.collision, bool) and isinstance(out.spike, bool)
        assert isinstance(out.fields, tuple) and all(isinstance(fl, Field) for fl in out.fields)
        assert isinstance(out.targets, tuple)
        # the most urgent target: warnings first, then the shortest time to contact
        assert out.most_urgent is (out.targets[0] if out.targets else None)
        assert list(out.targets) == sorted(out.targets, key=lambda t: t.urgency())
        assert out.warning == any(t.warning for t in out.targets)
        outs.append(out)
    # it saw the square: a response and a collision alarm (the state the other tests compare is not trivial)
    assert max(o.response for o in outs) > min(o.response for o in outs)
    assert any(o.collision for o in outs)
    # run() is step() over an iterable, lazily
    model.reset()
    gen = model.run(iter(frames))
    assert model.frame_index == 0  # nothing consumed yet
    _assert_identical(list(gen), outs)
    assert repr(model).startswith(type(model).__name__ + "(fps=30")


@pytest.mark.parametrize("name", NAMES)
def test_reset_restores_initial_state(name, frames):
    model = REGISTRY[name]()
    first = _all_outputs(model, frames)
    model.reset()
    assert model.frame_index == 0
    second = _all_outputs(model, frames)
    _assert_identical(first, second)
    if first and any(o.fields for o in first):
        ids = sorted({fl.id for o in second for fl in o.fields})
        assert ids[0] == 1  # field ids start again at 1 after reset


@pytest.mark.parametrize("name", NAMES)
def test_reset_mid_run_equals_fresh_model(name, frames):
    other = _looming_rgb(seed=5)
    model = REGISTRY[name]()
    _all_outputs(model, other[: N // 2])
    model.reset()
    _assert_identical(_all_outputs(model, frames), _all_outputs(REGISTRY[name](), frames))


# -- determinism ------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_bit_identical_across_instances(name, frames):
    a, b = REGISTRY[name](), REGISTRY[name]()
    for f in frames:
        oa, ob = a.step(f), b.step(f)
        _assert_identical([oa], [ob])
        sa, sb = _state_of(a), _state_of(b)
        if sa is not None:
            for xa, xb in zip(sa, sb):
                assert xa.tobytes() == xb.tobytes()
    if hasattr(a, "state"):
        assert a.state == b.state


# -- pickling / copying -------------------------------------------------------------------
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
@pytest.mark.parametrize("name", NAMES)
def test_pickle_and_deepcopy_mid_run(name, how, frames):
    model = REGISTRY[name](fps=25.0)
    _all_outputs(model, frames[:10])
    clone = pickle.loads(pickle.dumps(model)) if how == "pickle" else copy.deepcopy(model)
    assert type(clone) is type(model) and clone.fps == 25.0 and clone.frame_index == 10
    rest_clone = _all_outputs(clone, frames[10:])
    assert model.frame_index == 10  # the copy is independent
    _assert_identical(rest_clone, _all_outputs(model, frames[10:]))


@pytest.mark.parametrize("name", NAMES)
def test_pickle_fresh_model(name, frames):
    clone = pickle.loads(pickle.dumps(REGISTRY[name]()))
    _assert_identical(_all_outputs(clone, frames[:6]), _all_outputs(REGISTRY[name](), frames[:6]))


# -- parameters ----------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_default_params_immutable_and_untouched(name, frames):
    model = REGISTRY[name]()
    params = model.params
    assert dataclasses.is_dataclass(params)
    before = dataclasses.asdict(params)
    field0 = dataclasses.fields(params)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(params, field0, getattr(params, field0))
    hash(params)  # frozen and hashable: safe to share between models
    _all_outputs(model, frames)
    assert dataclasses.asdict(model.params) == before
    assert REGISTRY[name]().params == params  # defaults not changed by a run
    with pytest.raises(ValueError, match="unknown parameter"):
        params.replace(no_such_parameter=1)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("fps", [0, -30, float("nan"), float("inf"), "fast", None, True, "30"])
def test_bad_fps_rejected(name, fps):
    with pytest.raises(InputError, match="fps must be"):
        REGISTRY[name](fps=fps)


@pytest.mark.parametrize("name", NAMES)
def test_wrong_params_type_rejected(name):
    with pytest.raises(TypeError, match="params must be"):
        REGISTRY[name](params={"t_a": 1.0})


# -- input is never modified; any memory layout works ---------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_input_not_modified(name, frames):
    model = REGISTRY[name]()
    for f in frames:
        g = f.copy()
        flags = (f.flags.writeable, f.flags.c_contiguous)
        model.step(f)
        assert np.array_equal(f, g) and (f.flags.writeable, f.flags.c_contiguous) == flags
    # float input too (converted, never scaled or clipped in place)
    f = frames[3].astype(np.float64) * 1.5 - 20  # out of range on both sides: clipped in a copy
    g = f.copy()
    model.step(f)
    assert np.array_equal(f, g)


@pytest.mark.parametrize("name", NAMES)
def test_readonly_noncontiguous_fortran_accepted(name, frames):
    ref = _all_outputs(REGISTRY[name](), frames[:12])
    views = []
    for f in frames[:12]:
        big = np.zeros((H * 2, W * 2, 3), np.uint8)
        big[::2, ::2] = f
        v = big[::2, ::2]  # non-contiguous view
        assert not v.flags.c_contiguous
        v.flags.writeable = False
        views.append(v)
    _assert_identical(_all_outputs(REGISTRY[name](), views), ref)
    fortran = [np.asfortranarray(f) for f in frames[:12]]
    _assert_identical(_all_outputs(REGISTRY[name](), fortran), ref)
    flipped = [np.ascontiguousarray(f[::-1, ::-1])[::-1, ::-1] for f in frames[:12]]  # negative strides
    _assert_identical(_all_outputs(REGISTRY[name](), flipped), ref)


# -- channels --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_rgba_alpha_ignored_and_single_channel(name, frames):
    rng = np.random.default_rng(1)
    ref = _all_outputs(REGISTRY[name](), frames[:12])
    rgba = [np.concatenate([f, rng.integers(0, 256, (H, W, 1), dtype=np.uint8)], axis=-1) for f in frames[:12]]
    _assert_identical(_all_outputs(REGISTRY[name](), rgba), ref)
    grey = [f[:, :, 0] for f in frames[:12]]
    _assert_identical(_all_outputs(REGISTRY[name](), [g[:, :, None] for g in grey]),
                      _all_outputs(REGISTRY[name](), grey))
    # equal channels = that grey level (Rec. 601 weights sum to 1)
    grey_rgb = [np.repeat(g[:, :, None], 3, axis=2) for g in grey]
    a = _all_outputs(REGISTRY[name](), grey_rgb)
    b = _all_outputs(REGISTRY[name](), grey)
    for oa, ob in zip(a, b):
        assert oa.response == pytest.approx(ob.response, rel=1e-4, abs=1e-6)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("channels", [2, 5])
def test_2_and_5_channels_rejected(name, channels):
    model = REGISTRY[name]()
    with pytest.raises(InputError, match=f"must have 1, 3 \\(RGB\\) or 4 \\(RGBA\\) channels, got {channels}"
                       ) as info:
        model.step(np.zeros((H, W, channels), np.uint8))
    assert isinstance(info.value, ValueError)
    assert model.frame_index == 0


# -- frame size ---------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_frame_size_change_names_both_sizes_then_reset_allows_it(name, frames):
    model = REGISTRY[name]()
    ref_model = REGISTRY[name]()
    for f in frames[:5]:
        model.step(f)
        ref_model.step(f)
    with pytest.raises(InputError) as info:
        model.step(np.zeros((H + 2, W - 4, 3), np.uint8))
    msg = str(info.value)
    assert isinstance(info.value, ValueError) and "\n" not in msg
    assert f"{W - 4}x{H + 2}" in msg and f"{W}x{H}" in msg and "reset()" in msg and "frame 5" in msg
    assert model.frame_index == 5
    # the rejected frame left no trace: the run goes on exactly as without it
    _assert_identical(_all_outputs(model, frames[5:]), _all_outputs(ref_model, frames[5:]))
    # after reset() a new size is fine, and the model behaves like a fresh one
    model.reset()
    small = [f[: H // 2, : W // 2] for f in frames]
    _assert_identical(_all_outputs(model, small), _all_outputs(REGISTRY[name](), small))
    for o in _all_outputs(REGISTRY[name](), small):
        for fl in o.fields:
            assert 0 <= fl.x < W // 2 and 0 <= fl.y < H // 2


@pytest.mark.parametrize("name", NAMES)
def test_minimum_size(name):
    cls = REGISTRY[name]
    n = cls.min_size
    assert n == 3
    rng = np.random.default_rng(0)
    for shape in [(n, n), (n, 40), (40, n)]:
        model = cls()
        for i in range(12):
            frame = rng.integers(0, 256, shape, dtype=np.uint8) if i % 3 else np.zeros(shape, np.uint8)
            out = model.step(frame)
            assert math.isfinite(out.response)
            for fl in out.fields:
                assert 0 <= fl.x < shape[1] and 0 <= fl.y < shape[0]
    for shape in [(n - 1, 40), (40, n - 1), (1, 1), (0, 10)]:
        with pytest.raises(InputError, match=f"needs at least {n}x{n}") as info:
            cls().step(np.zeros(shape, np.uint8))
        assert isinstance(info.value, ValueError)
        assert f"is {shape[1]}x{shape[0]} pixels" in str(info.value)


# -- a rejected frame never changes the model -------------------------------------------------
BAD = {
    "nan": lambda: np.full((H, W), np.nan),
    "inf": lambda: np.where(np.eye(H, W, dtype=bool), np.inf, 100.0),
    "bool": lambda: np.ones((H, W), bool),
    "object": lambda: np.zeros((H, W), object),
    "ndim1": lambda: np.zeros(H * W, np.uint8),
    "channels2": lambda: np.zeros((H, W, 2), np.uint8),
    "too_small": lambda: np.zeros((2, 2), np.uint8),
}


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("bad", sorted(BAD))
def test_rejected_frame_leaves_state_untouched(name, bad, frames):
    model, ref = REGISTRY[name](), REGISTRY[name]()
    for f in frames[:8]:
        model.step(f)
        ref.step(f)
    with pytest.raises(InputError):
        model.step(BAD[bad]())
    assert model.frame_index == 8
    _assert_identical(_all_outputs(model, frames[8:]), _all_outputs(ref, frames[8:]))
    # and as the very first frame: the size is not fixed by a rejected frame
    first = REGISTRY[name]()
    with pytest.raises(InputError):
        first.step(BAD[bad]())
    first.step(np.zeros((20, 30), np.uint8))
    assert first.frame_index == 1


# --- a 0-1 float frame warns once (issue 14) -----------------------------------------------------
@pytest.mark.parametrize("name", ["mlplc2", "lgmd2"])
def test_unit_scale_float_frames_warn_once(name):
    import warnings

    model = mlplc2.get_model(name)(fps=30.0)
    frame = np.random.default_rng(0).random((60, 80)).astype(np.float32)   # a 0-1 image
    with pytest.warns(mlplc2.InputWarning, match="0-255"):
        model.step(frame)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.step(frame)                                                # once per model
        fresh = mlplc2.get_model(name)(fps=30.0)
        fresh.step(np.zeros((60, 80), np.float32))                        # black: no warning
        fresh.step(frame * 255)                                           # 0-255 floats: none
        fresh.step((frame * 255).astype(np.uint8) // 255)                 # integers: none
