"""mlplc2: the attention-driven LPLC2 neural ensemble model (mLPLC2) and its baselines.

>>> import mlplc2
>>> model = mlplc2.MLPLC2(fps=30.0)
"""

from ._validation import InputError, InputWarning
from .neuropils.attention import Field
from .models import LGMD1, LGMD2, LPLC2, MLPLC2, SLPLC2, Output, available_models, get_model
from .params import Params
from .runner import RunResult, run, stream
from .evaluator import evaluate  # light: stdlib only at import time

__all__ = ["Params", "MLPLC2", "SLPLC2", "LPLC2", "LGMD2", "LGMD1", "Output", "Field", "InputError", "InputWarning",
           "available_models", "get_model", "run", "stream", "RunResult", "evaluate"]
__version__ = "0.1.0"
