"""Parameter sets of a batch: the overrides given (a dict, a Params or a JSON file), the
sweeps (``NAME=V1,V2,...``: their Cartesian product), the overrides that apply to each model
(:func:`restrict`, :func:`model_overrides`, :func:`model_params`), and a set's id
(:func:`param_set_id`, a hash of its JSON) and label (:func:`param_label`).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import itertools
import json
from collections.abc import Mapping, Sequence
from pathlib import Path

from .._validation import InputTypeError, InputValueError, did_you_mean_hint

__all__ = ["param_sets", "model_params", "parse_sweep", "param_set_id", "param_label", "restrict",
           "model_overrides"]


def _parse_value(text: str):
    text = text.strip()
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def parse_sweep(specs) -> dict[str, list]:
    """``["t_a=8,10,12", "beta=1.5"]`` (or a dict name -> values) -> ``{name: [values]}``.

    Values are parsed as JSON scalars (``10`` int, ``1.5`` float, ``true``,
    else a string). ``MODEL.NAME=...`` sweeps a parameter of one model only
    (e.g. ``lgmd2.some_param``)."""
    if specs is None:
        return {}
    if isinstance(specs, Mapping):
        return {str(k): list(v) if isinstance(v, (list, tuple)) else [v] for k, v in specs.items()}
    if isinstance(specs, str):
        specs = [specs]
    sweep: dict[str, list] = {}
    for spec in specs:
        name, sep, values = str(spec).partition("=")
        name = name.strip()
        if not sep or not name or not values.strip():
            raise InputValueError(f"--sweep {spec!r}: expected PARAM=V1,V2,...")
        if any(not v.strip() for v in values.split(",")):
            raise InputValueError(f"--sweep {spec!r}: an empty value (expected PARAM=V1,V2,...)")
        vals = [_parse_value(v) for v in values.split(",")]
        if name in sweep:
            raise InputValueError(f"--sweep: parameter {name!r} given twice")
        sweep[name] = vals
    return sweep


@functools.lru_cache(maxsize=None)
def _param_class(model: str):
    from ..models.base import get_model

    cls = type(get_model(model)(fps=30.0).params)
    if not dataclasses.is_dataclass(cls):
        raise InputValueError(f"parameters for {model}: its params ({cls.__name__}) are no dataclass, so none can be "
                              "set (docs/testing.md: a model's parameters are a frozen dataclass)")
    return cls


def _replaced(cls, over: Mapping):
    """``cls()`` with ``over`` applied: a :class:`~mlplc2.params.ParameterSet`'s ``replace`` (validated), or
    ``dataclasses.replace`` after a check of the names (a model of your own)."""
    if hasattr(cls, "replace"):
        return cls().replace(**over)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = [k for k in over if k not in names]
    if unknown:
        hint = did_you_mean_hint(str(unknown[0]), sorted(names))
        raise TypeError(f"{cls.__name__} has no parameter {unknown[0]!r}" + (f" ({hint})" if hint else ""))
    return dataclasses.replace(cls(), **over)


def _lplc2_family(model: str) -> bool:
    """Whether ``model`` takes :class:`~mlplc2.params.Params` (the LPLC2 family): the flat overrides apply to it."""
    from ..params import Params

    return _param_class(model) is Params


def model_overrides(pset: Mapping, model: str) -> dict:
    """The parameter overrides of ``pset`` that apply to ``model``: flat keys
    (``Params`` fields) for the LPLC2 family, plus a ``{model: {...}}`` section."""
    flat = {k: v for k, v in pset.items() if not isinstance(v, Mapping)}
    section = pset.get(model) if isinstance(pset.get(model), Mapping) else {}
    return {**(flat if _lplc2_family(model) else {}), **section}


def model_params(pset: Mapping, model: str):
    """The parameter object of ``model`` for parameter set ``pset`` (one of :func:`param_sets`),
    or None where ``pset`` changes none of its parameters (the model's defaults)."""
    over = model_overrides(pset, model)
    if not over:
        return None
    cls = _param_class(model)
    try:
        return _replaced(cls, over)
    except (TypeError, ValueError) as exc:
        raise InputValueError(f"parameters for {model}: {exc}") from None


def _target_fields() -> set:
    """The target layer's parameter names (:class:`~mlplc2.targets.TargetParams`)."""
    from ..targets import TargetParams

    return set(TargetParams().to_dict())


def _target_layer(name: str) -> str:
    """The one-line error for a target-layer parameter (or section) in a parameter file: those are not set there."""
    return (f"parameters: {name!r} belongs to the target layer (TargetParams), which a parameter file does not set: "
            "use --horizon, --max-miss, --alarm-warns / --no-alarm-warns and --heading, or target_params= in Python "
            "(docs/cli.md, 'mlplc2 params')")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_types(cls, over: Mapping, prefix: str = "") -> None:
    """A one-line error naming the parameter for an override of the wrong type
    (``t_a="abc"``), before the parameter class's own range checks."""
    defaults = {f.name: f.default for f in dataclasses.fields(cls)}
    for name, value in over.items():
        default = defaults.get(name, dataclasses.MISSING)
        if isinstance(default, bool):
            ok, want = isinstance(value, bool), "true or false"
        elif _is_number(default):
            ok, want = _is_number(value), "a number"
        elif isinstance(default, str):
            ok, want = isinstance(value, str), "a string"
        elif isinstance(default, tuple):
            ok = isinstance(value, (list, tuple)) and len(value) == len(default) and all(map(_is_number, value))
            want = f"a list of {len(default)} numbers"
        else:  # unknown names are reported by replace(); other types are left to the class
            continue
        if not ok:
            raise InputTypeError(f"parameters: {prefix}{name} must be {want}, got {value!r}")


def _is_default(value, default) -> bool:
    if isinstance(default, tuple) and isinstance(value, (list, tuple)):
        value, default = list(value), list(default)
    return isinstance(value, bool) == isinstance(default, bool) and value == default


def _drop_defaults(pset: Mapping) -> dict:
    """``pset`` without the overrides equal to the default value (``t_a=10`` is no
    override), so that a parameter set of default values has the id ``default``."""
    from ..models.base import param_defaults
    from ..params import Params

    flat = {k: v for k, v in pset.items() if not isinstance(v, Mapping)}
    base = Params().to_dict()
    out = {k: v for k, v in flat.items() if not _is_default(v, base[k])}
    for model, section in pset.items():
        if not isinstance(section, Mapping):
            continue
        own = param_defaults(model)
        if _lplc2_family(model):  # its section overrides the flat values for it
            own.update(flat)
        keep = {k: v for k, v in section.items() if not _is_default(v, own[k])}
        if keep:
            out[model] = keep
    return out


def restrict(pset: Mapping, model: str) -> dict:
    """The part of parameter set ``pset`` that ``model`` uses (flat Params fields
    for the LPLC2 family, plus its own section)."""
    own = {k: v for k, v in pset.items() if not isinstance(v, Mapping)} if _lplc2_family(model) else {}
    if isinstance(pset.get(model), Mapping) and pset[model]:
        own[model] = dict(pset[model])
    return own


def param_set_id(pset: Mapping) -> str:
    """Stable id: ``default`` for no overrides, else ``p`` + 8 hex digits of a hash of the sorted JSON."""
    if not pset:
        return "default"
    text = json.dumps(pset, sort_keys=True, separators=(",", ":"))
    return "p" + hashlib.sha1(text.encode()).hexdigest()[:8]


def param_label(model: str, overrides: Mapping | None = None, *, shared: Mapping | None = None,
                width: int | None = None, tag: str = "") -> str:
    """What people read for ``model`` run with parameter ``overrides``: ``mlplc2`` without
    overrides, else ``mlplc2[r_af=30,t_a=8]`` (names sorted; values as JSON, text bare; a
    section ``{"lgmd2": {...}}`` as ``lgmd2.NAME=...``). Unlike the id of :func:`param_set_id`
    (the folder names), it names the parameters.

    For tables: the overrides in ``shared`` (common to every label shown next to this one) are
    left out, as a leading ``…``; with ``width``, a label still longer is cut at a parameter
    boundary, ``…`` for the rest, and ends with `` tag`` (a parameter set id keeps cut labels apart).
    """
    def items(over) -> list[str]:
        out = []
        for name, value in sorted((over or {}).items()):
            pairs = sorted(value.items()) if isinstance(value, Mapping) else [(None, value)]
            for sub, v in pairs:
                text = v if isinstance(v, str) else json.dumps(v, separators=(",", ":"))
                out.append(f"{name if sub is None else f'{name}.{sub}'}={text}")
        return out

    left_out = set(items(shared))
    kept = [i for i in items(overrides) if i not in left_out]
    if left_out and len(kept) < len(items(overrides)):
        kept.insert(0, "…")
    label = f"{model}[{','.join(kept)}]" if kept else model
    if width is None or len(label) <= width:
        return label
    cut: list[str] = []
    for item in kept:
        if cut and len(model) + sum(len(c) + 1 for c in cut) + len(item) + 4 > width:
            break
        cut.append(item)
    return f"{model}[{','.join(cut)},…]" + (f" {tag}" if tag else "")


def param_sets(params=None, sweep=None, models: Sequence[str] = ("mlplc2",)) -> list[dict]:
    """Parameter sets: the overrides in ``params`` (a dict, or a JSON file of
    ``Params`` fields, with optional ``{"lgmd2": {...}}`` sections per model)
    combined with every point of the Cartesian product of ``sweep``.

    Every override is checked (name, type, value) against its parameter class,
    whether or not its model is in ``models``; each set is also checked by
    building the parameters of every model in ``models``. Overrides equal to
    the default value are dropped (a set of defaults is ``{}``, id ``default``).
    """
    from ..models.base import available_models, param_defaults
    from ..params import Params

    base: dict = {}
    if params is not None:
        if isinstance(params, (str, Path)):
            path = Path(params)
            if not path.is_file():
                raise InputValueError(f"{path}: parameter file not found")
            try:
                base = json.loads(path.read_text(encoding="utf-8"))
            except json.JSONDecodeError as exc:
                raise InputValueError(f"{path}: not valid JSON ({exc})") from None
        elif hasattr(params, "to_dict"):
            default = Params().to_dict()
            base = {k: v for k, v in params.to_dict().items() if default.get(k) != v}
        else:
            base = dict(params)
        if not isinstance(base, Mapping):
            raise InputValueError("--params: expected a JSON object {name: value}")
        base = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in base.items()}
    sweeping = sweep is not None
    sweep = parse_sweep(sweep)
    names = list(sweep)
    for name in names:      # a swept value that no model run reads would only repeat the same runs
        model, dot, _ = name.partition(".")
        if dot and model in available_models() and model not in models:
            raise InputValueError(f"--sweep {name}: {model} is not among the models run ({', '.join(models)})")
        if not dot and name in Params().to_dict() and models \
                and not any(_lplc2_family(m) for m in models if m in available_models()):
            raise InputValueError(f"--sweep {name}: a Params field, read only by the LPLC2 family, which none of "
                                  f"the models run is ({', '.join(models)}); another model's parameter: "
                                  "--sweep MODEL.NAME=...")
    sets = []
    for combo in itertools.product(*(sweep[n] for n in names)) if names else [()]:
        pset = json.loads(json.dumps(base))
        for name, value in zip(names, combo):
            model, dot, pname = name.partition(".")
            if dot:
                pset.setdefault(model, {})[pname] = value
            else:
                pset[name] = value
        sets.append(pset)
    pnames = set(Params().to_dict())
    for pset in sets:
        for k, v in pset.items():
            if isinstance(v, Mapping):
                if k not in available_models():
                    raise InputValueError(_target_layer(k) if k in ("targets", "target_params") else
                                          f"parameters: {k!r} is not a model name ({', '.join(available_models())})")
                named = next((n for n in v if (n in _target_fields() or n == "targets")
                              and n not in param_defaults(k)), None)
                if named is not None:
                    raise InputValueError(_target_layer(f"{k}.{named}"))
            elif k not in pnames and k in _target_fields():
                raise InputValueError(_target_layer(k))
            elif k not in pnames:
                hint = did_you_mean_hint(str(k).lower(), sorted(pnames))
                raise InputValueError(f"parameters: unknown parameter {k!r}"
                                      + (f" ({hint})" if hint else "")
                                      + "; Params fields: 'mlplc2 params' or help(mlplc2.Params); other models' "
                                      "parameters go in a section {\"lgmd2\": {...}}"
                                      + (" or --sweep lgmd2.NAME=..." if sweeping else ""))
        flat = {k: v for k, v in pset.items() if not isinstance(v, Mapping)}
        _check_types(Params, flat)
        if flat:  # Params fields are checked even when no LPLC2-family model runs
            try:
                Params().replace(**flat)
            except (TypeError, ValueError) as exc:
                raise InputValueError(f"parameters: {exc}") from None
        sections = [k for k, v in pset.items() if isinstance(v, Mapping)]
        for m in sections:
            _check_types(_param_class(m), pset[m], f"{m}.")
        for m in dict.fromkeys([*models, *sections]):  # every model given a section, run or not
            model_params(pset, m)
    unique = {}
    for pset in map(_drop_defaults, sets):  # t_a=10,10.0 is one set
        unique.setdefault(param_set_id(pset), pset)
    return list(unique.values())

