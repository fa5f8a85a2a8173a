"""The neuropils of the fly's visual system that the LPLC2 family models (the paper's Fig. 2, Eq. 1-16).

``retina`` (photoreceptors, Eq. 1) -> ``lamina`` (vDoG, ON/OFF, Eq. 2-5) -> ``medulla`` (contrast
normalisation and T4/T5 motion detectors, Eq. 6-10) -> ``lobula_plate`` (the local-motion maps,
Eq. 11-12); ``frontend`` chains them frame by frame; ``attention`` holds the attention fields
(Eq. 13-16). The compiled (Numba) kernels sit beside the stages they mirror: ``_fast_frontend``,
``_fast_motion``, ``_fast_attention``: the models run those by default (``backend="numba"``); an edit to a
stage here changes a model built with ``backend="reference"`` (docs/testing.md, "A variant of mLPLC2").

Equation numbers follow ``shared/paper/NOTES.md`` and docs/model.md, which count the vDoG subtraction as Eq. 4:
from Eq. 5 on they are one above the compiled paper's own (Eq. 15 here is the paper's Eq. 14).
"""
