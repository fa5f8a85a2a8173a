"""Models: the LPLC2 family (MLPLC2, SLPLC2, LPLC2) and the LGMD baselines."""

from .base import REGISTRY, Model, Output, available_models, get_model, register, resolve_names
from .flow import FlowParams, FlowTTC
from .lgmd import LGMD1, LGMD2
from .lplc2 import LPLC2, MLPLC2, SLPLC2

__all__ = ["Model", "Output", "REGISTRY", "register", "get_model", "available_models", "resolve_names",
           "MLPLC2", "SLPLC2", "LPLC2", "LGMD2", "LGMD1", "FlowTTC", "FlowParams"]
