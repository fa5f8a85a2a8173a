"""Model parameters: Table I of the paper plus the documented extras.

Every field carries, in its dataclass metadata (:func:`param`), its Table I
symbol, unit, Table I value (or none: an *extra* the paper leaves implicit),
valid range and description. That one source gives the checks made when a
:class:`Params` is built, the table in ``help(mlplc2.Params)`` and the table in
``docs/model.md``, which ``mlplc2 params --markdown`` regenerates.
``docs/model.md`` explains each extra and why it has its value. One parameter
set serves every input: nothing here is tuned per video.
"""

from __future__ import annotations

import dataclasses
import inspect
import textwrap
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from ._validation import InputTypeError, InputValueError, Valid, check_fields, did_you_mean_hint

__all__ = ["Params", "ParameterSet", "GAMMA_MIN", "LM_SCALE_MAX", "param", "param_of", "parameter_table",
           "document_parameters"]

#: Smallest exponent gamma_on / gamma_off (Eq. 11). With tiny exponents T ** gamma lies within a
#: few float32 steps of 1 for every T > 0, the opponent difference r - l is rounding noise and the
#: reference and fast front ends disagree (measured on the looming stimuli: 6-17 % on the response
#: at gamma = 1e-7 and 3e-6, ~1e-8 from 1e-4 up); 0.01 leaves a margin.
GAMMA_MIN = 0.01
#: Largest lm_gain x max(1, leaky_slope): LM = lm_gain x f(r - l) with |r - l| <= 2, and Eq. 12
#: squares it, in float32 (largest 3.4e38): 1e15 leaves a wide margin.
LM_SCALE_MAX = 1e15


class ParameterSet:
    """What every frozen parameter dataclass offers (:class:`Params`, ``TargetParams``, the LGMD
    and flow parameters): a validated :meth:`replace`, :meth:`to_dict` and :meth:`coerce`; a keyword that is no
    field is refused with the field it most likely meant (``Params(R_AF=60)``: did you mean 'r_af'?)."""

    def __new__(cls, *args, **kwargs):
        if kwargs and dataclasses.is_dataclass(cls):
            names = {f.name for f in dataclasses.fields(cls) if f.init}
            unknown = [k for k in kwargs if k not in names]
            if unknown:
                raise InputTypeError(f"{cls.__name__}() has no parameter {unknown[0]!r}"
                                     f"{_did_you_mean(unknown[0], sorted(names))}")
        return super().__new__(cls)

    @classmethod
    def coerce(cls, value, name: str):
        """``value`` as this parameter set: None stays None, an instance is returned as it is,
        a mapping gives the defaults with those fields replaced; anything else raises
        InputValueError naming the argument ``name``."""
        if value is None or isinstance(value, cls):
            return value
        if isinstance(value, Mapping):
            return cls().replace(**{str(k): v for k, v in value.items()})
        raise InputValueError(f"{name} must be {cls.__module__}.{cls.__qualname__} or a dict of its fields, "
                              f"got {type(value).__name__}")

    def replace(self, **changes):
        """Return a copy with ``changes`` applied (validated like the constructor)."""
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            hint = _did_you_mean(unknown[0], sorted(names)) if len(unknown) == 1 else ""
            raise InputValueError(f"unknown parameter(s) {', '.join(unknown)}{hint or '; known: ' + ', '.join(sorted(names))}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _did_you_mean(word: str, names: list[str]) -> str:
    """``"; did you mean 'X'?"`` for the field name closest to a mistyped ``word`` (case aside), else the names."""
    return "; " + did_you_mean_hint(str(word).lower(), names, otherwise=f"known: {', '.join(names)}")


def param(default, doc: str, *, valid: Valid, symbol: str = "", unit: str = "", table: str | None = None):
    """A dataclass field with its documentation as metadata: ``symbol`` (the paper's, or ""),
    ``unit`` ("" for none), ``table`` (the value Table I gives, as printed there; None for an
    extra), ``valid`` (a :class:`~mlplc2._validation.Valid`, checked by ``check_fields``) and
    ``doc`` (one paragraph)."""
    return dataclasses.field(default=default, metadata={"symbol": symbol, "unit": unit, "table": table,
                                                        "valid": valid, "doc": " ".join(doc.split())})


def param_of(cls, name: str):
    """A new field with the default and the :func:`param` metadata of field ``name`` of the
    parameter set ``cls``: one definition for a parameter that two parameter sets share."""
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    return dataclasses.field(default=f.default, metadata=f.metadata)


def _show_default(value, markdown: bool) -> str:
    if isinstance(value, str):
        return f'`"{value}"`' if markdown else f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _fields(cls) -> tuple[dataclasses.Field, ...]:
    fields = dataclasses.fields(cls)
    for f in fields:
        if "doc" not in f.metadata:   # every field is documented and checked (fails at import)
            raise TypeError(f"{cls.__name__}.{f.name} has no param() metadata (symbol, unit, Table I, "
                            f"valid values, description)")
    return fields


def parameter_table(cls, *, markdown: bool = False) -> str:
    """The parameter table of the dataclass ``cls`` (:class:`Params`, ``TargetParams``), built
    from its fields' metadata (:func:`param`): name, symbol, unit, default, Table I value or
    "extra", valid values and description. ``markdown=True``: the table of docs/model.md (one
    row per field, description in the last column); otherwise plain text for the docstring
    (aligned columns, then the descriptions in numpydoc ``Attributes`` form). The Table I
    column is left out when no field has a Table I value, the symbol column when no field has a
    Table I value or a symbol."""
    fields = _fields(cls)
    paper = any(f.metadata["table"] is not None for f in fields)
    symbols = paper or any(f.metadata["symbol"] for f in fields)
    keep = [0, *([1] if symbols else []), 2, 3, *([4] if paper else []), 5]
    head = [["field", "symbol", "unit", "default", "Table I", "valid values"][i] for i in keep]
    rows = []
    for f in fields:
        m = f.metadata
        name = f"`{f.name}`" if markdown else f.name
        cells = [name, m["symbol"] or "-", m["unit"] or "-", _show_default(f.default, markdown),
                 "extra" if m["table"] is None else m["table"], str(m["valid"])]
        rows.append([cells[i] for i in keep])
    if markdown:
        def cell(text):
            return text.replace("|", "\\|")

        lines = ["| " + " | ".join(head + ["description"]) + " |", "|" + "---|" * (len(head) + 1)]
        lines += ["| " + " | ".join(cell(c) for c in r + [f.metadata["doc"]]) + " |" for r, f in zip(rows, fields)]
        return "\n".join(lines) + "\n"
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in [head, *rows]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    lines += ["", "Attributes", "----------"]
    for f in fields:
        kind = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        lines.append(f"{f.name} : {kind}")
        lines += textwrap.wrap(f.metadata["doc"], 88, initial_indent="    ", subsequent_indent="    ")
    return "\n".join(lines) + "\n"


def document_parameters(title: str):
    """Class decorator: insert :func:`parameter_table` of the class, under ``title``, into its
    docstring (before its Examples section, if any), so that ``help()`` shows the table."""
    def deco(cls):
        doc = inspect.cleandoc(cls.__doc__ or "") + "\n"
        table = f"{title}\n{'-' * len(title)}\n{parameter_table(cls)}\n"
        at = doc.find("\nExamples\n--------\n") + 1
        cls.__doc__ = doc[:at] + table + doc[at:] if at else doc + "\n" + table
        return cls
    return deco


@document_parameters("Parameters (Table I and extras)")
@dataclass(frozen=True)
class Params(ParameterSet):
    """Parameters of the LPLC2 model family (LPLC2, sLPLC2, mLPLC2).

    Defaults are Table I of Liu & Fu (the mLPLC2 paper) where Table I gives a
    value, except ``epsilon`` (25 grey levels for Table I's 0.2: docs/model.md, "Deviations from
    the paper, in one list"); the remaining fields are the extras ``docs/model.md`` documents.
    Time constants are in milliseconds and turned into filter coefficients
    from the frame rate the model is built with (``tau_i = 1000 / fps``).
    Equation numbers (here, in ``mlplc2 params`` and in the code) follow NOTES.md and docs/model.md, which count
    the vDoG subtraction as Eq. 4: from Eq. 5 on they are one above the compiled paper's own.

    Valid values (the table below; checked at construction and by
    :meth:`replace`; one-line :class:`mlplc2.InputError` otherwise, a
    ``ValueError`` or ``TypeError``): numbers are finite Python or NumPy
    scalars (not bools, strings, None or arrays) within float32's range
    (magnitude <= 3.4e38), stored as Python floats; "> 0" means at least
    1.18e-38 (float32's smallest normal number); integers are Python or NumPy
    integers (not bools or floats) up to 2**31 - 1, stored as Python ints;
    True or False accepts NumPy bools too.

    Examples
    --------
    >>> p = Params(t_a=12.0)
    >>> p.r_af
    40
    >>> Params(beta=-1)
    Traceback (most recent call last):
    ...
    mlplc2._validation.InputValueError: Params.beta must be >= 0, got -1
    """

    # --- Lamina, Eq. 2-4 ---------------------------------------------------
    r_e: int = param(5, "Radius of the excitatory window of K_e, Eq. 2.",
                     symbol="r_De", unit="px", table="5", valid=Valid.integer(1))
    r_i: int = param(11, "Radius of the inhibitory window of K_i, Eq. 2.",
                     symbol="r_Di", unit="px", table="11", valid=Valid.integer(1))
    sigma_e: float = param(10.0, "Standard deviation of the excitatory Gaussian K_e, Eq. 3.",
                           symbol="sigma_e", unit="px", table="10", valid=Valid.real(positive=True))
    sigma_i: float = param(20.0, "Standard deviation of the inhibitory Gaussian K_i, Eq. 3.",
                           symbol="sigma_i", unit="px", table="20", valid=Valid.real(positive=True))
    w_i: float = param(1.2, """Weight of the inhibition in the vDoG with polarity selectivity (Eq. 4),
                       L_vDoG = sign(E) max(|E| - w_i |I|, 0) (authors' code: 1.2; docs/model.md).""",
                       symbol="w_i", valid=Valid.real(minimum=0))
    normalise_kernels: bool = param(True, """Scale K_e, K_i, K_c to unit sum on their truncated windows
                                    (authors' code). Eq. 3 taken literally sums to ~0.17 (K_e), ~0.19 (K_i)
                                    and ~0.05 (K_c) on these windows (NOTES 3).""", valid=Valid.boolean())
    after_image: float = param(0.0, """Fraction of the previous ON/OFF value added to the current one
                               (Eq. 5). The paper has none (0); the authors' code uses 0.1.""",
                               valid=Valid.real(minimum=0, below=1))

    # --- Medulla, Eq. 6-10 -------------------------------------------------
    r_c: int = param(5, "Radius of the contrast-normalisation window of K_c, Eq. 7.",
                     symbol="r_Dc", unit="px", table="5", valid=Valid.integer(1))
    sigma_c: float = param(20.0, "Standard deviation of K_c, Eq. 7.",
                           symbol="sigma_c", unit="px", table="20", valid=Valid.real(positive=True))
    n_floor: float = param(0.0, """Relative floor on the contrast-normalised signal (after Eq. 6): N is
                           set to 0 where it is below n_floor times the largest N within ``n_floor_radius``
                           px. 0 (the default) = the paper, no floor. 0.3-0.5 removes the low tails of each
                           moving band, where the triple correlator of Eq. 9 answers the shape of the band
                           (a square's corners) rather than its motion, and with it the ~20 % answer of
                           LPLC2 and sLPLC2 to a bright receding square; it is not the default because it
                           costs field creation, alarms and speed on textured scenes (docs/model.md, "Open
                           problems"). The authors' code zeroes N below an absolute 0.67-0.75 tuned per
                           video (NOTES 6).""", valid=Valid.real(minimum=0, below=1))
    n_floor_radius: int = param(10, """Radius of the square window of the local maximum used by
                                ``n_floor`` (21 x 21: about one band of the inhibitory vDoG window,
                                r_Di = 11).""", unit="px", valid=Valid.integer(1))
    epsilon: float = param(25.0, """Constant of the contrast normalisation, Eq. 6, on the 0-255 scale of
                           the input. Table I gives 0.2; that value makes every change, however faint,
                           saturate the tanh (background texture as strong as a looming object). 25 keeps
                           weak changes weak (see docs/model.md).""",
                           symbol="epsilon", unit="grey level", table="0.2", valid=Valid.real(positive=True))
    n_c: int = param(5, "Number of sampling distances (connected neurons) per T4/T5 cell, Eq. 10.",
                     symbol="N_c", table="5", valid=Valid.integer(1))
    tau_1: float = param(80.0, "Delay of the correlator at sampling distance 1, Eq. 8.",
                         symbol="tau_1", unit="ms", table="80", valid=Valid.real(positive=True))
    tau_nc: float = param(40.0, """Delay at sampling distance N_c; the dynamic delays run linearly from
                          tau_1 to tau_Nc ("80~40" in Table I).""", symbol="tau_Nc", unit="ms", table="80~40",
                          valid=Valid.real(positive=True))
    tau_out: float = param(40.0, """Delay of the T4/T5 output filter, M-hat(t-1) in Eq. 10 (the paper's Eq. 9).
                           Table I gives no value of its own: the paper's tau_Nc is read as this delay too
                           (40 ms); the authors' code uses a recursive 30 ms low-pass (NOTES 8). A parameter of
                           its own so that either delay changes alone.""", unit="ms",
                           valid=Valid.real(positive=True))
    beta: float = param(1.5, "Bias coefficient of the null-direction term of the correlator, Eq. 9.",
                        symbol="beta", table="1.5", valid=Valid.real(minimum=0))
    average_distances: bool = param(True, """Divide the sum over the N_c sampling distances of Eq. 10 by
                                    N_c, which keeps T4/T5 in [0, 1] where the exponents gamma_1 = 0.9 >
                                    gamma_2 = 0.5 favour OFF (dark) edges.""", valid=Valid.boolean())

    # --- Lobula plate, Eq. 11-12 -------------------------------------------
    gamma_on: float = param(0.9, "Exponent on the ON (T4) signal, Eq. 11.",
                            symbol="gamma_1", table="0.9", valid=Valid.real(minimum=GAMMA_MIN))
    gamma_off: float = param(0.5, "Exponent on the OFF (T5) signal, Eq. 11.",
                             symbol="gamma_2", table="0.5", valid=Valid.real(minimum=GAMMA_MIN))
    leaky_slope: float = param(0.5, """Slope of the Leaky-ReLU f of Eq. 11 for negative input. The paper
                               gives none (authors' code: 0.01); 0.5 lets inward (null-direction) motion
                               inhibit a quadrant, as the LPLC2 literature describes, so a translating
                               background does not open the gate.""",
                               valid=Valid.real(minimum=0, also=f"lm_gain x max(1, leaky_slope) <= {LM_SCALE_MAX:g}"))
    lm_gain: float = param(160.0, """Gain applied to the local-motion maps LM_v after Eq. 11, which puts LM
                           on the scale of the Table I thresholds T_a and T_d (authors' code multiplies the
                           fused signal by 10). 160 lets the weaker bright (ON) approach reach T_a = 10, as
                           Sec. IV-A reports.""", symbol="g",
                           valid=Valid.real(minimum=0, also=f"lm_gain x max(1, leaky_slope) <= {LM_SCALE_MAX:g}"))

    # --- Attention fields, Eq. 13-16 ---------------------------------------
    r_af: int = param(40, "Radius (half-side for square fields) of an attention field.",
                      symbol="R_AF", unit="px", table="40", valid=Valid.integer(1))
    field_shape: Literal["square", "disc"] = param("square", """Shape of an attention field: a 2 R_AF
                                                   square or a disc of radius R_AF.""",
                                                   valid=Valid.choice("square", "disc"))
    exclusion: float = param(1.25, """Eq. 13 searches for a new field outside every existing field; the
                             excluded zone around a field that answered in the previous frame (the search
                             comes before this frame's Eq. 14-15, Algorithm 1) is this many times R_AF, so
                             that the blurred edges of an object that has outgrown its field do not seed a
                             second field beside it (1.0 = the paper's literal rule).""",
                             unit="x R_AF", valid=Valid.real(minimum=0))
    t_a: float = param(10.0, "LM must exceed this to create an attention field, Eq. 13.",
                       symbol="T_a", table="10", valid=Valid.real(minimum=0))
    t_d: float = param(5000.0, """A field whose responses summed over the last d frames fall below this
                       is removed, Eq. 16.""", symbol="T_d", table="5000", valid=Valid.real(minimum=0))
    d: int = param(10, "Window of the removal rule, Eq. 16.",
                   symbol="d", unit="frames", table="10 tau_i", valid=Valid.integer(1))
    grace: int = param(15, """Frames a new field lives before Eq. 16 may remove it (NOTES 16; authors: 5; frames
                       given, held repeats included: a time).
                       A field is created when the expansion starts (2-3 frames after onset with the
                       default gain) but answers only once the expansion is wider than the lamina filters
                       (several frames later); 15 frames give it a full window of d responses before it is
                       judged where every frame is processed (on a clip whose images are each held four
                       times, 4-5 responses: docs/model.md, "Time").""", unit="frames", valid=Valid.integer(0))
    q_min: float = param(0.05, """Arbour threshold: the all-four-arbours gate of Eq. 15 opens when every
                         quadrant sum Q_i exceeds q_min times the quadrant's area in pixels (the paper's
                         bool(prod Q_i), which with a leaky f would open on any faint net outward motion).
                         0.05 = 80 over a 40 x 40 quadrant; the area is that of the pixels the quadrant
                         integrates (inside the frame, and inside the disc with ``field_shape="disc"``).
                         Quadrants larger than R_AF^2 (the frame-wide LPLC2) count as sqrt(area * R_AF^2)
                         pixels (``attention.gate_area``).""", unit="per px", valid=Valid.real(minimum=0))
    alarm_threshold: float = param(10000.0, """A field is in collision alarm when its responses summed over
                                   the last ``alarm_window`` frames reach this (the paper's "fatal" fields;
                                   NOTES 17).""", valid=Valid.real(minimum=0))
    alarm_window: int = param(5, "Frames summed for the collision alarm.", unit="frames",
                              valid=Valid.integer(1))
    max_fields: int = param(16, """Upper bound on simultaneous attention fields (keeps work and memory
                            bounded); no new field is created while this many exist.""",
                            valid=Valid.integer(1))

    def __post_init__(self) -> None:
        check_fields(self, "Params")
        scale = self.lm_gain * max(1.0, self.leaky_slope)
        if scale > LM_SCALE_MAX:
            raise InputValueError(f"Params.lm_gain x max(1, leaky_slope) must be <= {LM_SCALE_MAX:g} (LM stays "
                                  f"finite in float32), got {scale:g}")

    def delays_ms(self) -> tuple[float, ...]:
        """Dynamic delays tau_s (ms) for sampling distances s = 1..N_c (Eq. 8, Table I)."""
        if self.n_c == 1:
            return (self.tau_1,)
        step = (self.tau_nc - self.tau_1) / (self.n_c - 1)
        return tuple(self.tau_1 + k * step for k in range(self.n_c))


