"""mlplc2: the attention-driven LPLC2 neural ensemble model (mLPLC2) and its baselines.

>>> import mlplc2
>>> model = mlplc2.MLPLC2(fps=30.0)

The public names are imported when first used (PEP 562 ``__getattr__``): ``import mlplc2`` itself
loads nothing heavy, so that the ``mlplc2`` command sets up its Ctrl-C handling before NumPy, OpenCV
and Numba load (``mlplc2.cli.main``: one ``interrupted`` line, never a traceback).
"""

from __future__ import annotations

import importlib

#: Each public name and the submodule that defines it.
_PUBLIC = {"Params": "params", "MLPLC2": "models", "SLPLC2": "models", "LPLC2": "models", "LGMD2": "models",
           "LGMD1": "models", "Output": "models", "Field": "neuropils.attention", "InputError": "_validation",
           "InputWarning": "_validation", "available_models": "models", "get_model": "models", "run": "runner",
           "stream": "runner", "RunResult": "runner", "evaluate": "evaluator"}

__all__ = list(_PUBLIC)
__version__ = "0.1.0"


def __getattr__(name: str):
    import importlib.util   # here: the module itself loads nothing the command does not need first

    if name in _PUBLIC:
        value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    elif not name.startswith("__") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        # a subpackage (mlplc2.targets, ...) after a plain `import mlplc2`, as when they were imported here
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
