"""The per-frame contract every registered model honours: :func:`mlplc2.testing.check_model`
(step/reset, frame counting, run equals step, input never modified, bit-identical determinism
across runs, across ``reset()`` and after pickling/copying, immutable default parameters,
frame-size changes, channel handling and the input checks of ``Model.step``) run on every
model of :data:`mlplc2.models.REGISTRY`; what the registered models promise beyond it; the
registry and its names; and the contract suite itself (it fails broken models, the example of
docs/testing.md runs).

A model added to the registry is picked up here automatically.
"""

from __future__ import annotations

import copy
import importlib
import pickle
import sys
import types
import re
from pathlib import Path

import numpy as np
import pytest

import mlplc2
from mlplc2 import InputError, Output
from mlplc2.models import LPLC2, MLPLC2, REGISTRY, SLPLC2, Model, get_model, resolve_names
from mlplc2.params import ParameterSet
from mlplc2.testing import check_model, looming_frames, run_checks

NAMES = sorted(REGISTRY)


# -- the contract suite on every registered model --------------------------------------------
@pytest.mark.parametrize("check", [pytest.param(check, id=f"{name}-{check.__name__}")
                                   for name in NAMES for check in check_model(REGISTRY[name])])
def test_contract(check):
    check()


# -- what the registered models promise beyond the contract ---------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_registered_models_have_parameter_sets_and_min_size_3(name):
    """So ``check_construction`` checks their params (frozen, untouched, ``replace``, type) on every one."""
    cls = REGISTRY[name]
    assert isinstance(cls().params, ParameterSet)
    assert cls.min_size == 3


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
@pytest.mark.parametrize("name", NAMES)
def test_pickle_and_deepcopy_keep_a_non_default_fps(name, how):
    frames = looming_frames()
    model = REGISTRY[name](fps=25.0)
    [model.step(f) for f in frames[:10]]
    clone = pickle.loads(pickle.dumps(model)) if how == "pickle" else copy.deepcopy(model)
    assert type(clone) is type(model) and clone.fps == 25.0 and clone.frame_index == 10
    assert [clone.step(f) for f in frames[10:]] == [model.step(f) for f in frames[10:]]


def test_fields_and_localisation_are_class_attributes():
    """One truth for "has fields" and "localises": the model classes say it, evaluate asks them."""
    ev = importlib.import_module("mlplc2.evaluator")

    flags = {name: (cls.has_fields, cls.localises, cls.has_targets) for name, cls in REGISTRY.items()}
    assert flags["mlplc2"] == flags["slplc2"] == (True, True, True)
    assert flags["lplc2"] == (True, False, True)       # one frame-wide cell: fields, no positions
    assert flags["lgmd1"] == flags["lgmd2"] == (False, False, False)
    assert flags["flow"] == (False, False, True)
    for name, (fields, localises, targets) in flags.items():
        assert not localises or fields
        assert ev._model_says(name, "localises") is localises and ev._model_says(name, "has_targets") is targets
    assert ev._model_says("not-registered", "localises") is False
    assert MLPLC2.localises and SLPLC2.localises and not LPLC2.localises and not Model.localises


# -- the contract suite itself ------------------------------------------------------------------------
class Counter(Model):
    """A model without params whose response counts frames: it honours the contract."""

    def __init__(self, fps=30.0, params=None, **kwargs):
        super().__init__(fps=fps, params=None, **kwargs)
        self._n = 0

    def _reset(self):
        self._n = 0

    def _step(self, gray, index):
        self._n += 1
        return Output(frame=index, response=float(self._n % 7), collision=self._n > 5)


class ForgetsNothing(Counter):
    def _reset(self):
        pass


class Random(Counter):
    def _step(self, gray, index):
        return Output(frame=index, response=float(np.random.default_rng().random()), collision=True)


class Unpicklable(Counter):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._hook = lambda: None


class Silent(Counter):
    def _step(self, gray, index):
        return Output(frame=index, response=0.0)


class Mutable(Counter):
    """params a plain dict: not a frozen dataclass."""

    def __init__(self, fps=30.0, params=None, **kwargs):
        super().__init__(fps=fps, **kwargs)
        self.params = {"threshold": 1.0}


def test_a_model_honouring_the_contract_passes_every_check():
    names = run_checks(Counter)
    assert names == [c.__name__ for c in check_model(Counter)] and len(names) == 13
    assert all(n.startswith("check_") for n in names)


@pytest.mark.parametrize("cls, check, message", [
    (ForgetsNothing, "check_run_equals_step", r"run\(\) against step\(\): frame 0 differs"),
    (ForgetsNothing, "check_reset", r"after reset\(\): frame 0 differs"),
    (Random, "check_deterministic", "two models, frame 0: frame 0 differs"),
    (Unpicklable, "check_pickle", "(?i)pickle|lambda"),
    (Silent, "check_outputs", "the response does not change while the square looms"),
    (Mutable, "check_construction", "params dict is not a dataclass"),
])
def test_checks_fail_broken_models(cls, check, message):
    checks = {c.__name__: c for c in check_model(cls)}
    with pytest.raises(Exception, match=message):
        checks[check]()


@pytest.mark.parametrize("cls, message", [
    (ForgetsNothing, r"check_run_equals_step failed: AssertionError: run\(\) against step\(\): frame 0 differs"),
    (Unpicklable, "check_pickle failed: "),
    (Silent, "check_outputs failed: AssertionError: the response does not change while the square looms"),
])
def test_run_checks_names_the_first_failing_check(cls, message):
    with pytest.raises(AssertionError, match="^" + message) as info:
        run_checks(cls)
    assert "\n" not in str(info.value)


def test_responds_option_for_models_not_meant_to_answer_the_square():
    assert len(run_checks(Silent, responds=False)) == 13


@pytest.mark.parametrize("factory, message", [
    (5, "model_factory must be a callable returning a new model, got int"),
    (lambda: "model", "model_factory must return an mlplc2.models.Model, got str"),
    ((lambda m: lambda: m)(Counter()), "must return a new model at each call"),
])
def test_check_model_bad_factory_is_a_one_line_error(factory, message):
    with pytest.raises(InputError, match=re.escape(message)) as info:
        list(check_model(factory))
    assert isinstance(info.value, TypeError)


def test_testing_module_examples():
    import doctest

    import mlplc2.testing

    result = doctest.testmod(mlplc2.testing, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


def test_docs_testing_example_runs(capsys, monkeypatch):
    """docs/testing.md's example model, written from scratch, passes ``check_model`` (run as a
    module of its own: pickling finds its classes by module name)."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "testing.md").read_text(encoding="utf-8")
    code = re.findall(r"```python\n(.*?)```", text, re.S)[0]
    module = types.ModuleType("docs_testing_example")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    exec(compile(code, "docs/testing.md", "exec", dont_inherit=True), module.__dict__)
    assert capsys.readouterr().out.strip() == "13 checks passed"


def test_docs_testing_variant_of_mlplc2_runs(capsys, monkeypatch):
    """docs/testing.md's variant of mLPLC2 (an optical blur before the retina, a name of its own) passes the contract
    as the model does, answers otherwise than mLPLC2 on the same looming frames and is labelled by its name; two
    instances of one class told apart by ``name`` run side by side (a researcher's trial, session 51: none of this was
    documented). The block's ``mlplc2.run`` of a clip the test has not is left out."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "testing.md").read_text(encoding="utf-8")
    code = next(c for c in re.findall(r"```python\n(.*?)```", text, re.S) if "class BlurredMLPLC2(" in c)
    assert "class BlurredMLPLC2(mlplc2.MLPLC2)" in code
    script = next(c for c in re.findall(r"```python\n(.*?)```", text, re.S) if "mlplc2.cli.main" in c)
    assert 'if __name__ == "__main__":' in script      # Dask's workers import the script again (session 53)
    code = "\n".join(line for line in code.splitlines() if not line.startswith("result = mlplc2.run("))
    module = types.ModuleType("docs_testing_variant")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    try:
        exec(compile(code, "docs/testing.md", "exec", dont_inherit=True), module.__dict__)
    finally:
        REGISTRY.pop("mlplc2_blur", None)                              # the example registers its class
    assert capsys.readouterr().out.strip() == "13 checks passed"
    frames = looming_frames()
    plain, blurred = MLPLC2(fps=30.0), module.BlurredMLPLC2(fps=30.0)
    a, b = [o.response for o in plain.run(frames)], [o.response for o in blurred.run(frames)]
    assert blurred.name == "mlplc2_blur" and a != b
    other = MLPLC2(fps=30.0, params=mlplc2.Params(r_af=60))
    other.name = "mlplc2_r60"
    assert (other.name, MLPLC2.name, plain.name) == ("mlplc2_r60", "mlplc2", "mlplc2")


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
    ("mlplc2,nope", "unknown model 'nope'; choose from " + ", ".join(NAMES) + r" \(a model of your own: register it"),
    (",,", "models needs at least one"),
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
