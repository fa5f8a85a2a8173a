"""Sec. IV-A: the selectivity matrix of the LPLC2 family on the six basic stimuli.

A cross-cutting suite of the paper's results: the LPLC2 family (mlplc2.models.lplc2, with the
front end and attention beneath it) on the stimuli of mlplc2.stimuli and, when present, the
paper's own videos."""

from __future__ import annotations

import pytest

import mlplc2
from mlplc2 import stimuli

from .conftest import read_gray

FAMILY = ["lplc2", "slplc2", "mlplc2"]
NON_LOOMING = ["dark_recede", "bright_recede", "translating", "grating"]
PAPER_FILES = {"dark_approach": "test_black_approach.avi", "bright_approach": "test_white_approach.avi",
               "dark_recede": "test_black_recede.avi", "bright_recede": "test_white_recede.avi",
               "translating": "test_translating.avi", "grating": "test_grating.avi"}
# Known deviation (docs/model.md, "Open problems"): with the default parameters the
# frame-wide LPLC2 and the roaming sLPLC2 give a brief response (~20 % of the dark approach)
# to the bright receding square; Params(n_floor=0.35) removes it
# (test_relative_floor_gives_the_paper_matrix).
KNOWN = {("lplc2", "bright_recede"), ("slplc2", "bright_recede")}


def peaks(model_name, source):
    out = {}
    for name in stimuli.BASIC_NAMES:
        model = mlplc2.get_model(model_name)(fps=30.0)
        out[name] = max(model.step(f).response for f in source(name))
    return out


def generated(name):
    return stimuli.basic(name).frames


def check_matrix(model_name, pk):
    dark = pk["dark_approach"]
    assert dark > 0
    assert 0 < pk["bright_approach"] < 0.5 * dark, "bright approach: weaker than dark, but answered"
    for name in NON_LOOMING:
        if (model_name, name) in KNOWN:
            continue
        assert pk[name] < 0.05 * dark, f"{model_name} answers {name}: {pk[name]:.0f} vs {dark:.0f}"


@pytest.mark.parametrize("model_name", FAMILY)
def test_selectivity_on_generated_stimuli(model_name):
    check_matrix(model_name, peaks(model_name, generated))


@pytest.mark.paper
@pytest.mark.parametrize("model_name", FAMILY)
def test_selectivity_on_paper_videos(model_name, paper_dir):
    def source(name):
        return read_gray(paper_dir / "basic" / PAPER_FILES[name])

    check_matrix(model_name, peaks(model_name, source))


@pytest.mark.parametrize("model_name", FAMILY)
def test_dark_approach_response_grows(model_name):
    """The response builds up while the square expands (Fig. 3, column 1)."""
    model = mlplc2.get_model(model_name)(fps=30.0)
    resp = [model.step(f).response for f in generated("dark_approach")]
    assert max(resp[:8]) < max(resp[20:])


@pytest.mark.parametrize("model_name", FAMILY)
def test_relative_floor_gives_the_paper_matrix(model_name):
    """The documented remedy for the known deviation: the relative floor on N
    (Params(n_floor=0.35)) gives every model the paper's matrix, bright recede included."""
    params = mlplc2.Params(n_floor=0.35)
    pk = {}
    for name in stimuli.BASIC_NAMES:
        model = mlplc2.get_model(model_name)(fps=30.0, params=params)
        pk[name] = max(model.step(f).response for f in generated(name))
    dark = pk["dark_approach"]
    assert 0 < pk["bright_approach"] < 0.5 * dark
    for name in NON_LOOMING:
        assert pk[name] < 0.05 * dark, f"{model_name} answers {name} with n_floor=0.35"
