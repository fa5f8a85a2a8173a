"""The neuropils of the fly's visual system that the LPLC2 family models (the paper's Fig. 2, Eq. 1-16).

``retina`` (photoreceptors, Eq. 1) -> ``lamina`` (vDoG, ON/OFF, Eq. 2-5) -> ``medulla`` (contrast
normalisation and T4/T5 motion detectors, Eq. 6-10) -> ``lobula_plate`` (the local-motion maps,
Eq. 11-12); ``frontend`` chains them frame by frame; ``attention`` holds the attention fields
(Eq. 13-16). The compiled (Numba) kernels sit beside the stages they mirror: ``_fast_frontend``,
``_fast_motion``, ``_fast_attention``.
"""
