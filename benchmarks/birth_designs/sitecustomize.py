"""Designs of Eq. 13 (where and when mLPLC2 makes an attention field) measured in session 12 against issue 22's
item 7 (the same first warning whatever the encoding); a measurement aid, not part of the package: none was taken
(docs/history.md, "Encoding and size", session 12).

Python imports this module at start-up when its folder is on ``PYTHONPATH``; with ``MLPLC2_BIRTH_DESIGN`` set (a JSON
object) it replaces ``MLPLC2._step`` in that process and in every process it starts with the same environment (the
benchmark's workers), so the same design runs in ``benchmarks/encoding_invariance.py``, ``mlplc2 run`` and
``mlplc2 benchmark``::

    MLPLC2_BIRTH_DESIGN='{"kind": "persist"}' PYTHONPATH=src:benchmarks/birth_designs \\
        python benchmarks/encoding_invariance.py --data ../shared/data --model mlplc2 --cache /tmp/x/cache

Kinds (``kind``; everything else is Eq. 13-16 as in ``mlplc2.models.lplc2.MLPLC2._step``):

``persist``   a field is born only where the LM also exceeded ``frac`` (default 1) x T_a within ``r`` (default 5)
              working px on the previous processed frame (a birth confirmed over two frames), unless its LM is
              above ``strong`` x T_a (default: none is);
``tavg``      the new field is sought (and T_a applied) on the mean LM of this and the previous processed frame;
``smooth``    the new field is placed at the largest LM after a Gaussian blur (``sigma``, default 3 px), born when
              the raw LM within ``r`` (default 5) px of it exceeds T_a;
``rel``       ... and also exceeds ``k`` x the frame's ``q``-th percentile of LM (default 99): a noise floor
              relative to the frame;
``warm``      no field before frame ``n`` (the front end's start);
``evidence``  fields are born as in the paper, but the target layer sees only those whose birth LM was at least
              ``t`` (a field threshold for the targets' evidence only; the reported fields are all of them).
"""

import json
import os

_SPEC = os.environ.get("MLPLC2_BIRTH_DESIGN")
if _SPEC:
    from dataclasses import replace

    import cv2
    import numpy as np

    from mlplc2.models.lplc2 import MLPLC2
    from mlplc2.neuropils.attention import argmax_outside

    D = json.loads(_SPEC)
    KIND = D["kind"]

    def _peak(m, x, y, r):
        return float(m[max(y - r, 0):y + r + 1, max(x - r, 0):x + r + 1].max())

    def _step(self, gray, index):
        p = self.params
        lm = self._front(gray)
        m = lm.magnitude
        prev = getattr(self, "_design_prev", None)
        if len(self._fields) < p.max_fields:
            zones = [(f.x, f.y, round(p.exclusion * f.radius) if f.response > 0 else f.radius) for f in self._fields]
            if KIND == "smooth":
                cand = argmax_outside(cv2.GaussianBlur(m, (0, 0), D.get("sigma", 3.0)), zones, p.field_shape)
                if cand is not None:
                    cand = (cand[0], cand[1], _peak(m, cand[0], cand[1], D.get("r", 5)))
            elif KIND == "tavg":
                cand = argmax_outside(m if prev is None else 0.5 * (m + prev), zones, p.field_shape)
            else:
                cand = argmax_outside(m, zones, p.field_shape)
            ok = cand is not None and cand[2] > p.t_a
            if ok and KIND == "persist" and cand[2] <= D.get("strong", np.inf) * p.t_a:
                ok = prev is not None and _peak(prev, cand[0], cand[1], D.get("r", 5)) > D.get("frac", 1.0) * p.t_a
            if ok and KIND == "warm":
                ok = index >= D["n"]
            if ok and KIND == "rel":
                ok = cand[2] > D["k"] * float(np.percentile(m, D.get("q", 99)))
            if ok:
                self._new_field(cand[0], cand[1], index, p.r_af).birth_lm = cand[2]
        for f in self._fields:
            self._integrate(f, lm)
        self._fields = self._survivors(index)
        self._design_prev = m.copy()
        return self._output(gray, index)

    MLPLC2._step = _step

    if KIND == "evidence":
        _output = MLPLC2._output

        def _evidence_output(self, gray, index):
            every = self._fields
            self._fields = [f for f in every if getattr(f, "birth_lm", np.inf) >= D["t"]]
            try:
                out = _output(self, gray, index)
            finally:
                self._fields = every
            fields = tuple(f.snapshot() for f in every)
            alarm = any(f.collision for f in fields)
            return replace(out, fields=fields, response=max((f.response for f in fields), default=0.0),
                           collision=alarm, spike=alarm)

        MLPLC2._output = _evidence_output

    _reset = MLPLC2._reset

    def _design_reset(self):
        _reset(self)
        self._design_prev = None

    MLPLC2._reset = _design_reset
