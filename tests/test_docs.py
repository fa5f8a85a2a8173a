"""The docstring examples run (numpydoc Examples are doctests)."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["mlplc2", "mlplc2.params", "mlplc2.models.lplc2", "mlplc2.models.lgmd", "mlplc2._signals"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
