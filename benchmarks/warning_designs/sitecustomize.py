"""Designs of the target layer's warning decision measured in session 13 against issue 22's item 7 (the same
first warning whatever the encoding); a measurement aid, not part of the package (docs/history.md, "Encoding and
size", session 13).

Python imports this module at start-up when its folder is on ``PYTHONPATH``; with ``MLPLC2_WARNING_DESIGN`` set
(a JSON object) it wraps ``mlplc2.targets.warning.alarm_warns``, ``.off_path`` and ``mlplc2.targets.layer.estimate`` in that
process and in every process it starts with the same environment (the benchmark's workers), so the same design
runs in ``benchmarks/encoding_invariance.py``, ``mlplc2 run`` and ``mlplc2 benchmark``::

    MLPLC2_WARNING_DESIGN='{"kind": "alarm_iso"}' PYTHONPATH=src:benchmarks/warning_designs \\
        python benchmarks/encoding_invariance.py --data ../shared/data --model mlplc2 --cache /tmp/x/cache

Kinds (``kind``, several joined by ``+``; everything else is ``mlplc2.targets.warning`` as it is):

``alarm_iso``  the target's own fit vetoes a field alarm by its time to contact, not by its box's anisotropy: a
               fit with a significant growth (``min_tstat``) whose growth is anisotropic (``max_anisotropy``)
               gives the alarm its time to contact instead of a "no"; the alarm is vetoed when that time
               to contact lies beyond ``horizon_s`` by more than ``k`` (default 1) of its standard errors
               (the veto measured against the fit's own noise, not at a single crossing);
``recent``     with ``alarm_iso``: the fit's time to contact stands in for the alarm only when the box grew
               isotropically (``max_anisotropy``) over the last ``min_frames`` span (an older track's box may
               have changed its shape long before the field's alarm);
``sustain``    a warning that the fit begins (no field of the track in collision alarm this frame) begins only
               when every time to contact the track had over the last ``s`` seconds (default 0.1) lay within
               ``horizon_s`` (a time to contact under the horizon for a duration, not one frame's crossing);
``contact``    a warning that the fit begins needs the track's predicted contact instants (clock + ttc) over the
               last ``s`` seconds (default 0.2; at least ``n``, default 3) to agree within ``tol`` s (default
               0.2) and their median to lie within ``horizon_s`` of now: the contact instant, which a steady
               approach keeps, rather than one frame's time to contact;
``path_pp``    ``path_drift`` (a warning begun without a field alarm only on a box that keeps its bearing) also
               where no heading was measured this run, against ``TargetParams.heading`` or the principal point:
               whether the camera-motion estimate found a heading is itself a decision on the codec's noise.
"""

import json
import os

_SPEC = os.environ.get("MLPLC2_WARNING_DESIGN")
if _SPEC:
    from dataclasses import replace

    import mlplc2.targets.layer as _layer
    import mlplc2.targets.warning as _warning
    from mlplc2.targets.contact import fit_contact

    D = json.loads(_SPEC)
    KINDS = set(D["kind"].split("+"))       # designs may be combined: "alarm_iso+sustain"
    _alarm_warns, _estimate = _warning.alarm_warns, _warning.estimate
    _FPS = {}

    def alarm_warns(t, p, index, ttc, miss, heading=None, shape=None):
        if "alarm_iso" in KINDS and p.alarm_warns and t.last_alarm == index and ttc is None \
                and _warning.fits(t.history, t.fit_span):
            fit = fit_contact([q.frame for q in t.history], [q.log_scale for q in t.history])
            fps = _FPS.get("fps", 30.0)
            ago = index - t.history[-1].frame
            if fit is None or fit.ttc is None or fit.tstat < p.min_tstat or fit.ttc <= ago:
                return False
            growth = t.history[-1].log_scale - t.history[0].log_scale
            if growth <= 0:
                return False
            if "recent" in KINDS:                  # isotropy over the last min_frames span only
                recent = [q for q in t.history if q.frame >= t.history[-1].frame - t.fit_span - 1e-6]
                g = recent[-1].log_scale - recent[0].log_scale
                if not (g > 0 and abs(recent[-1].anisotropy - recent[0].anisotropy) <= p.max_anisotropy * g):
                    return False
            ttc, sigma = (fit.ttc - ago) / fps, fit.sigma / fps
            if ttc - D.get("k", 1.0) * sigma > p.horizon_s:
                return False
            ttc = min(ttc, p.horizon_s)            # within the horizon by its noise: not the horizon's veto
        elif "alarm_iso" in KINDS and ttc is not None and ttc > p.horizon_s and t.last_alarm == index:
            sigma = t.held[2] if t.held is not None and t.held[0] == index else None
            if sigma is not None and ttc - D.get("k", 1.0) * sigma <= p.horizon_s:
                ttc = p.horizon_s
        return _alarm_warns(t, p, index, ttc, miss, heading, shape)

    def estimate(t, p, fps, index, shape, focal=None, heading=None, **kw):
        _FPS["fps"], _FPS["shape"] = fps, shape
        before = t.warned
        o = _estimate(t, p, fps, index, shape, focal, heading=heading, **kw)
        if not o.warning or before or t.last_alarm == index or not KINDS & {"sustain", "contact"}:
            return o
        s = D.get("s", 0.1 if "sustain" in KINDS else 0.2) * fps
        past = [(c, v) for c, v in list(t.ttcs)[:-1] if c >= index - s - 1e-6]
        if "sustain" in KINDS:
            ok = bool(past) and all(v is not None and v <= p.horizon_s for _, v in past)
        else:
            pts = [c / fps + v for c, v in list(t.ttcs) if c >= index - s - 1e-6 and v is not None]
            pts.sort()
            ok = len(pts) >= D.get("n", 3) and pts[-1] - pts[0] <= D.get("tol", 0.2) \
                and pts[len(pts) // 2] - index / fps <= p.horizon_s
        if ok:
            return o
        t.warned, t.onset_cut = False, False
        return replace(o, warning=False)

    _off_path = _warning.off_path

    def off_path(t, p, index, heading):
        if "path_pp" in KINDS and heading is None and "shape" in _FPS:
            h, w = _FPS["shape"]
            heading = p.heading if p.heading is not None else ((w - 1) / 2.0, (h - 1) / 2.0)
        return _off_path(t, p, index, heading)

    _warning.off_path = off_path
    _warning.alarm_warns = alarm_warns
    _layer.estimate = estimate
