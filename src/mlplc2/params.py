"""Model parameters: Table I of the paper plus the documented extras.

Every field maps to a Table I symbol (its docstring names it) or is an extra
parameter that the paper leaves implicit; ``docs/model.md`` explains each extra
and why it has its value. One parameter set serves every input: nothing here
is tuned per video.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal

from ._validation import InputValueError, check_bool, check_int, check_real

__all__ = ["Params", "GAMMA_MIN", "LM_SCALE_MAX"]

#: Smallest exponent gamma_on / gamma_off (Eq. 11). With tiny exponents T ** gamma lies within a
#: few float32 steps of 1 for every T > 0, the opponent difference r - l is rounding noise and the
#: reference and fast front ends disagree (measured on the looming stimuli: 6-17 % on the response
#: at gamma = 1e-7 and 3e-6, ~1e-8 from 1e-4 up); 0.01 leaves a margin.
GAMMA_MIN = 0.01
#: Largest lm_gain x max(1, leaky_slope): LM = lm_gain x f(r - l) with |r - l| <= 2, and Eq. 12
#: squares it, in float32 (largest 3.4e38): 1e15 leaves a wide margin.
LM_SCALE_MAX = 1e15


@dataclass(frozen=True)
class Params:
    """Parameters of the LPLC2 model family (LPLC2, sLPLC2, mLPLC2).

    Defaults are Table I of Liu & Fu (the mLPLC2 paper) where Table I gives a
    value; the remaining fields are the extras ``docs/model.md`` documents.
    Time constants are in milliseconds and turned into filter coefficients
    from the frame rate the model is built with (``tau_i = 1000 / fps``).

    Valid values (checked at construction and by :meth:`replace`; one-line
    :class:`mlplc2.InputError` otherwise, a ``ValueError`` or ``TypeError``):

    * numbers: finite Python or NumPy scalars (not bools, strings, None or arrays),
      within float32's range (magnitude <= 3.4e38), stored as Python floats;
      ``sigma_*``, ``tau_*`` and ``epsilon`` > 0 and at least 1.18e-38 (float32's
      smallest normal number), ``gamma_on``/``gamma_off`` >= 0.01 (``GAMMA_MIN``),
      the others >= 0; ``n_floor`` and ``after_image`` < 1; ``lm_gain x max(1,
      leaky_slope)`` <= 1e15 (``LM_SCALE_MAX``: LM stays finite in float32);
    * integers: Python or NumPy integers (not bools or floats) up to 2**31 - 1,
      stored as Python ints; >= 1, except ``grace`` >= 0;
    * ``normalise_kernels``, ``average_distances``: True or False (NumPy bools too);
    * ``field_shape``: "square" or "disc".

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
    r_e: int = 5
    """r_De (px): radius of the excitatory window of K_e, Eq. 2 (Table I)."""
    r_i: int = 11
    """r_Di (px): radius of the inhibitory window of K_i (Table I)."""
    sigma_e: float = 10.0
    """sigma_e (px): standard deviation of the excitatory Gaussian K_e, Eq. 3 (Table I)."""
    sigma_i: float = 20.0
    """sigma_i (px): standard deviation of the inhibitory Gaussian K_i (Table I)."""
    w_i: float = 1.2
    """Extra. Weight of the inhibition in the vDoG with polarity selectivity (Eq. 4),
    L_vDoG = sign(E) max(|E| - w_i |I|, 0) (authors' code: 1.2; docs/model.md)."""
    normalise_kernels: bool = True
    """Extra. Scale K_e, K_i, K_c to unit sum on their truncated windows (authors' code).
    Eq. 3 taken literally sums to ~0.17 (K_e), ~0.19 (K_i) and ~0.05 (K_c) on these windows
    (NOTES 3)."""
    after_image: float = 0.0
    """Extra. Fraction of the previous ON/OFF value added to the current one (Eq. 5).
    The paper has none (0); the authors' code uses 0.1."""

    # --- Medulla, Eq. 6-10 -------------------------------------------------
    r_c: int = 5
    """r_Dc (px): radius of the contrast-normalisation window of K_c, Eq. 7 (Table I)."""
    sigma_c: float = 20.0
    """sigma_c (px): standard deviation of K_c (Table I)."""
    n_floor: float = 0.0
    """Extra. Relative floor on the contrast-normalised signal (after Eq. 6): N is set to 0
    where it is below n_floor times the largest N within ``n_floor_radius`` px. 0 (the
    default) = the paper, no floor. 0.3-0.5 removes the low tails of each moving band, where
    the triple correlator of Eq. 9 answers the shape of the band (a square's corners) rather
    than its motion, and with it the ~20 % answer of LPLC2 and sLPLC2 to a bright receding
    square; it is not the default because it costs field creation, alarms and speed on
    textured scenes (docs/model.md, "Open problems"). The authors' code zeroes N below an
    absolute 0.67-0.75 tuned per video (NOTES 6)."""
    n_floor_radius: int = 10
    """Extra. Radius (px) of the square window of the local maximum used by ``n_floor``
    (21 x 21: about one band of the inhibitory vDoG window, r_Di = 11)."""
    epsilon: float = 25.0
    """epsilon: constant of the contrast normalisation, Eq. 6, on the 0-255 scale of the input.
    Table I gives 0.2; that value makes every change, however faint, saturate the tanh
    (background texture as strong as a looming object). 25 keeps weak changes weak
    (see docs/model.md)."""
    n_c: int = 5
    """N_c: number of sampling distances (connected neurons) per T4/T5 cell, Eq. 10 (Table I)."""
    tau_1: float = 80.0
    """tau_1 (ms): delay of the correlator at sampling distance 1, Eq. 8 (Table I)."""
    tau_nc: float = 40.0
    """tau_Nc (ms): delay at sampling distance N_c; the dynamic delays run linearly from
    tau_1 to tau_Nc ("80~40" in Table I). Also the delay of the T4/T5 output filter, Eq. 10."""
    beta: float = 1.5
    """beta: bias coefficient of the null-direction term of the correlator, Eq. 9 (Table I)."""
    average_distances: bool = True
    """Extra. Divide the sum over the N_c sampling distances of Eq. 10 by N_c, which keeps
    T4/T5 in [0, 1] where the exponents gamma_1 = 0.9 > gamma_2 = 0.5 favour OFF (dark) edges."""

    # --- Lobula plate, Eq. 11-12 -------------------------------------------
    gamma_on: float = 0.9
    """gamma_1: exponent on the ON (T4) signal, Eq. 11 (Table I)."""
    gamma_off: float = 0.5
    """gamma_2: exponent on the OFF (T5) signal, Eq. 11 (Table I)."""
    leaky_slope: float = 0.5
    """Extra. Slope of the Leaky-ReLU f of Eq. 11 for negative input. The paper gives none
    (authors' code: 0.01); 0.5 lets inward (null-direction) motion inhibit a quadrant, as the
    LPLC2 literature describes, so a translating background does not open the gate."""
    lm_gain: float = 160.0
    """Extra. Gain applied to the local-motion maps LM_v after Eq. 11, which puts LM on the
    scale of the Table I thresholds T_a and T_d (authors' code multiplies the fused signal by
    10). 160 lets the weaker bright (ON) approach reach T_a = 10, as Sec. IV-A reports."""

    # --- Attention fields, Eq. 13-16 ---------------------------------------
    r_af: int = 40
    """R_AF (px): radius (half-side for square fields) of an attention field (Table I)."""
    field_shape: Literal["square", "disc"] = "square"
    """Extra. Shape of an attention field: a 2 R_AF square or a disc of radius R_AF."""
    exclusion: float = 1.25
    """Extra. Eq. 13 searches for a new field outside every existing field; the excluded zone
    around a field that answered in the previous frame (the search comes before this frame's
    Eq. 14-15, Algorithm 1) is this many times R_AF, so that the blurred edges of an object that
    has outgrown its field do not seed a second field beside it (1.0 = the paper's literal rule)."""
    t_a: float = 10.0
    """T_a: LM must exceed this to create an attention field, Eq. 13 (Table I)."""
    t_d: float = 5000.0
    """T_d: a field whose responses summed over the last d frames fall below this is
    removed, Eq. 16 (Table I)."""
    d: int = 10
    """d (frames): window of the removal rule, Eq. 16 ("10 tau_i" in Table I)."""
    grace: int = 15
    """Extra. Frames a new field lives before Eq. 16 may remove it (NOTES 16; authors: 5).
    A field is created when the expansion starts (2-3 frames after onset with the default
    gain) but answers only once the expansion is wider than the lamina filters (several frames
    later); 15 frames give it a full window of d responses before it is judged."""
    q_min: float = 0.05
    """Extra. Arbour threshold: the all-four-arbours gate of Eq. 15 opens when every quadrant
    sum Q_i exceeds q_min times the quadrant's area in pixels (the paper's bool(prod Q_i),
    which with a leaky f would open on any faint net outward motion). 0.05 = 80 over a
    40 x 40 quadrant; the area is that of the pixels the quadrant integrates (inside the frame,
    and inside the disc with ``field_shape="disc"``). Quadrants larger than R_AF^2 (the
    frame-wide LPLC2) count as sqrt(area * R_AF^2) pixels (``attention.gate_area``)."""
    alarm_threshold: float = 10000.0
    """Extra. A field is in collision alarm when its responses summed over the last
    ``alarm_window`` frames reach this (the paper's "fatal" fields; NOTES 17)."""
    alarm_window: int = 5
    """Extra. Frames summed for the collision alarm."""
    max_fields: int = 16
    """Extra. Upper bound on simultaneous attention fields (keeps work and memory bounded);
    no new field is created while this many exist."""

    def __post_init__(self) -> None:
        def put(name, value):
            object.__setattr__(self, name, value)

        def real(name, **bounds):
            put(name, check_real(getattr(self, name), f"Params.{name}", **bounds))

        for name in ("sigma_e", "sigma_i", "sigma_c", "tau_1", "tau_nc", "epsilon"):
            real(name, positive=True)
        for name in ("gamma_on", "gamma_off"):
            real(name, minimum=GAMMA_MIN)
        for name in ("exclusion", "w_i", "beta", "leaky_slope", "lm_gain", "t_a", "t_d", "q_min",
                     "alarm_threshold"):
            real(name, minimum=0)
        real("n_floor", minimum=0, below=1)
        real("after_image", minimum=0, below=1)
        for name in ("r_e", "r_i", "r_c", "n_c", "r_af", "d", "alarm_window", "max_fields", "n_floor_radius"):
            put(name, check_int(getattr(self, name), f"Params.{name}", minimum=1))
        put("grace", check_int(self.grace, "Params.grace", minimum=0))
        for name in ("normalise_kernels", "average_distances"):
            put(name, check_bool(getattr(self, name), f"Params.{name}"))
        if not isinstance(self.field_shape, str) or self.field_shape not in ("square", "disc"):
            raise InputValueError(f"Params.field_shape must be 'square' or 'disc', got {self.field_shape!r}")
        put("field_shape", str(self.field_shape))
        scale = self.lm_gain * max(1.0, self.leaky_slope)
        if scale > LM_SCALE_MAX:
            raise InputValueError(f"Params.lm_gain x max(1, leaky_slope) must be <= {LM_SCALE_MAX:g} (LM stays "
                                  f"finite in float32), got {scale:g}")

    def replace(self, **changes) -> "Params":
        """Return a copy with ``changes`` applied (validated like the constructor)."""
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise InputValueError(f"unknown parameter(s) {', '.join(unknown)}; known: {', '.join(sorted(names))}")
        return dataclasses.replace(self, **changes)

    def delays_ms(self) -> tuple[float, ...]:
        """Dynamic delays tau_s (ms) for sampling distances s = 1..N_c (Eq. 8, Table I)."""
        if self.n_c == 1:
            return (self.tau_1,)
        step = (self.tau_nc - self.tau_1) / (self.n_c - 1)
        return tuple(self.tau_1 + k * step for k in range(self.n_c))

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)
