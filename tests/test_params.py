"""Validation of ``mlplc2.Params``: every value that passes runs; every value that fails
raises a one-line ``mlplc2.InputError`` at construction (and in ``replace``)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import mlplc2
from mlplc2 import stimuli
from mlplc2._validation import FLOAT32_TINY, InputError, InputTypeError, InputValueError
from mlplc2.params import GAMMA_MIN, LM_SCALE_MAX
from mlplc2.targets import TargetParams


def _raises(exc, **kwargs):
    with pytest.raises(exc) as info:
        mlplc2.Params(**kwargs)
    assert "\n" not in str(info.value)
    return str(info.value)


# Values that passed validation, then crashed in model.step() or gave NaN / backend-dependent
# output (exclusion=inf: OverflowError; lm_gain=1e39: inf gain, all-zero output; epsilon and
# gamma below float32's smallest normal: 0 in float32, NaN maps or 0 vs 42240 between backends).
@pytest.mark.parametrize("kwargs", [
    dict(exclusion=float("inf")), dict(t_a=float("nan")), dict(t_d=-float("inf")), dict(beta=float("nan")),
    dict(lm_gain=1e39), dict(alarm_threshold=1e39), dict(q_min=10**400),
    dict(lm_gain=3e38), dict(leaky_slope=1e14), dict(lm_gain=2 * LM_SCALE_MAX),
    dict(epsilon=1e-50), dict(epsilon=1e-40), dict(sigma_e=1e-50), dict(tau_1=1e-45),
    dict(gamma_on=1e-50, gamma_off=1e-50), dict(gamma_on=1e-7), dict(gamma_off=0.0),
    dict(r_af=2**40), dict(d=10**30),
])
def test_values_that_break_the_model_later_are_rejected(kwargs):
    msg = _raises(InputValueError, **kwargs)
    assert msg.startswith("Params.") and next(iter(kwargs)) in msg


def test_values_at_the_bounds_run():
    """The smallest and largest accepted values give finite output, the same on both front ends."""
    frames = stimuli.looming(half_size=0.5, speed=5.0, contact_time=2.0).frames[20:40]
    cases = [dict(epsilon=FLOAT32_TINY, sigma_c=FLOAT32_TINY, tau_1=FLOAT32_TINY),
             dict(gamma_on=GAMMA_MIN, gamma_off=GAMMA_MIN),
             dict(lm_gain=LM_SCALE_MAX, exclusion=3.4e38, t_d=3.4e38),
             dict(lm_gain=1.0, leaky_slope=LM_SCALE_MAX)]
    for kwargs in cases:
        params = mlplc2.Params(**kwargs)
        runs = []
        for backend in ("reference", "numba"):
            model = mlplc2.MLPLC2(fps=30.0, params=params, backend=backend)
            outs = [model.step(f) for f in frames]
            assert all(math.isfinite(o.response) for o in outs), kwargs
            assert np.isfinite(model.maps.magnitude).all(), kwargs
            runs.append([o.response for o in outs])
        assert runs[0] == pytest.approx(runs[1], rel=1e-5, abs=1e-3), kwargs


@pytest.mark.parametrize("value", ["10", None, np.array([5.0]), np.array(5.0), [5.0], True, np.bool_(True),
                                   1 + 2j, object()])
def test_non_numbers_raise_input_type_error(value):
    # '>=' not supported ... (a plain TypeError) before; an array or a bool was accepted
    msg = _raises(InputTypeError, t_a=value)
    assert msg.startswith("Params.t_a must be a number")


def test_numpy_scalars_are_accepted_and_stored_as_python_numbers():
    p = mlplc2.Params(r_af=np.int64(40), n_c=np.int32(3), d=np.uint8(10), t_a=np.float32(5.5),
                      beta=np.float64(1.5), average_distances=np.bool_(False))
    assert (type(p.r_af), type(p.n_c), type(p.d)) == (int, int, int)
    assert (type(p.t_a), type(p.beta), type(p.average_distances)) == (float, float, bool)
    assert p == mlplc2.Params(n_c=3, t_a=5.5, average_distances=False)
    assert hash(p) == hash(mlplc2.Params(n_c=3, t_a=5.5, average_distances=False))
    assert [mlplc2.Params(r_af=r).r_af for r in np.arange(20, 61, 20)] == [20, 40, 60]   # a sweep
    assert type(mlplc2.Params(t_a=12).t_a) is float
    out = mlplc2.MLPLC2(fps=30.0, params=p).step(np.zeros((30, 40), np.uint8))
    assert out.response == 0.0


@pytest.mark.parametrize("kwargs", [dict(grace=True), dict(r_af=True), dict(r_af=40.0), dict(n_c=2.5),
                                    dict(grace=-1), dict(max_fields=np.int64(0))])
def test_integer_fields_are_strict(kwargs):
    msg = _raises(InputValueError, **kwargs)
    assert "must be an integer" in msg


@pytest.mark.parametrize("name", ["normalise_kernels", "average_distances"])
@pytest.mark.parametrize("value", ["no", "False", 0, 1, None])
def test_bool_fields_need_real_bools(name, value):
    # "no" was accepted and taken as true
    _raises(InputTypeError, **{name: value})


def test_replace_validates_like_the_constructor():
    p = mlplc2.Params()
    with pytest.raises(InputTypeError, match="Params.t_a"):
        p.replace(t_a="12")
    with pytest.raises(InputValueError, match="Params.exclusion"):
        p.replace(exclusion=float("inf"))
    with pytest.raises(InputValueError, match="unknown parameter"):
        p.replace(no_such_parameter=1)
    q = p.replace(r_af=np.int64(30), t_a=np.float32(12))
    assert (q.r_af, q.t_a) == (30, 12.0) and type(q.r_af) is int and type(q.t_a) is float


@pytest.mark.parametrize("make, message", [
    (lambda: mlplc2.Params(R_AF=60), r"^Params\(\) has no parameter 'R_AF'; did you mean 'r_af'\?$"),
    (lambda: mlplc2.Params().replace(T_a=12), r"^unknown parameter\(s\) T_a; did you mean 't_a'\?$"),
    (lambda: mlplc2.targets.TargetParams(horizon=2.0), r"did you mean 'horizon_s'\?$"),
    (lambda: mlplc2.Params(no_such_thing=1), r"has no parameter 'no_such_thing'; known: after_image, "),
])
def test_a_mistyped_parameter_names_the_one_meant(make, message):
    # a researcher's trial (session 51): Params(R_AF=60) gave Python's "unexpected keyword argument", while the
    # command line's --params file named the field meant; still a TypeError (and an InputError)
    with pytest.raises(InputError, match=message) as info:
        make()
    assert isinstance(info.value, (TypeError, ValueError))


def test_every_error_is_an_input_error():
    """InputValueError / InputTypeError are ValueError / TypeError, so older callers still catch them."""
    for kwargs in (dict(t_a="x"), dict(t_a=-1), dict(grace=True), dict(field_shape="hexagon"),
                   dict(normalise_kernels="yes")):
        with pytest.raises(InputError):
            mlplc2.Params(**kwargs)
    assert issubclass(InputValueError, ValueError) and issubclass(InputTypeError, TypeError)


def _bounds_cases(cls):
    """(field, value, passes) at the edges of every numeric field's valid range as the table
    states it (``Valid`` in the field metadata)."""
    for f in dataclasses.fields(cls):
        v = f.metadata["valid"]
        step = 1 if v.kind == "int" else 1e-6
        if v.kind not in ("int", "real"):
            continue
        if v.positive:
            yield f.name, 0.0, False
            yield f.name, FLOAT32_TINY, True
        if v.minimum is not None:
            yield f.name, v.minimum, True
            yield f.name, v.minimum - step, False
        if v.below is not None:
            yield f.name, v.below, False
            yield f.name, v.below - step, True
        if v.maximum is not None:
            yield f.name, v.maximum, True
            yield f.name, v.maximum + step, False


@pytest.mark.parametrize("cls, prefix", [(mlplc2.Params, "Params"), (TargetParams, "TargetParams")])
def test_the_ranges_shown_are_the_ranges_enforced(cls, prefix):
    """The valid values of help() and the docs' tables are the metadata the checks use."""
    cases = list(_bounds_cases(cls))
    numeric = [f for f in dataclasses.fields(cls) if f.metadata["valid"].kind in ("int", "real")]
    assert len(cases) >= 2 * len(numeric) - 8       # every numeric field's range (a switch has none)
    for name, value, passes in cases:
        extra = {"min_frames": {"window": 1000}, "window": {"min_frames": 3}}.get(name, {}) if cls is TargetParams else {}
        if passes:
            assert getattr(cls(**{name: value, **extra}), name) == value, (name, value)
        else:
            with pytest.raises(InputValueError, match=f"^{prefix}.{name} must be"):
                cls(**{name: value, **extra})
