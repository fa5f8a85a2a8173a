"""Run one or several models over a video, an image sequence or a camera.

:func:`run` decodes the frames once (streamed, in a background thread) and
steps every model on each frame, writing as it goes:

``responses.csv``
    one row per active field per frame (``frame,time_s,model,field_id,x,y,response,collision``),
    flushed after every frame: a run stopped by Ctrl-C leaves a valid file. A signal
    (Ctrl-C, SIGTERM) that arrives during a frame takes effect once the frame is written,
    so ``responses.csv``, ``targets.csv`` and ``fields.json`` always cover the same frames.
``fields.json``
    one summary per attention field (centre, birth, death, peak, first alarm) and, under
    ``"targets"``, one per target (life, first estimate, first warning and the estimates
    then, see ``docs/targets.md``).
``targets.csv``
    (models with targets) one row per target per frame:
    ``frame,model,target_id,x,y,width,height,ttc_s,miss,warning,fields,azimuth_deg,elevation_deg,ttc_age_s,ttc_sigma_s,held_by``
    (input pixels; time to contact in s, miss in object extents (widths across, heights up and down), empty while not estimable;
    the bearing in degrees only with ``hfov_deg``; ``fields`` the ids of its attention fields,
    space-separated; ``ttc_age_s`` the seconds since ``ttc_s`` was measured: 0 when this frame's fit
    gave it, more when it is the last one held and counted down, empty without ``ttc_s``; ``ttc_sigma_s``
    the standard error of ``ttc_s`` in s, that of the fit it came from; ``held_by`` the rule that held back a
    warning on that frame, :attr:`Target.held_by <mlplc2.targets.Target.held_by>`, else empty).
``responses.png``
    response against frame, one panel per model, and under a model with targets their time to
    contact with the warning frames marked (see :mod:`mlplc2.plots`).
``annotated.mp4``
    (``video=True``) the input with the targets (or fields) drawn, the warning target named in
    the header (:func:`mlplc2.plots.annotate_frame`).

The summary files are written under a hidden temporary name and renamed
when complete, so a file with its final name is never half-written.

Its options are one :class:`RunOptions` (keywords of :func:`run` build it); the models are
built from them. What a run gives, :class:`~mlplc2.runner.result.RunResult` and the columns of
its files, is in :mod:`mlplc2.runner.result` (re-exported here).

The modules: :mod:`~mlplc2.runner.options` (:class:`RunOptions`), :mod:`~mlplc2.runner.prepare` (the models
built, the source opened and checked, before the first frame), :mod:`~mlplc2.runner.frames` (the per-frame work),
:mod:`~mlplc2.runner.loop` (:func:`run`, :func:`stream`), :mod:`~mlplc2.runner.demonstration` (:func:`demo`);
:mod:`~mlplc2.runner.result` (what a run gives), :mod:`~mlplc2.runner.folders` (where it writes) and
:mod:`~mlplc2.runner.live` (the per-frame CSV and JSON lines, latency).
"""

from __future__ import annotations

from ..io import TruncatedInputWarning
from .demonstration import DEMO_MODELS, DemoResult, demo
from .folders import default_out_dir
from .loop import damaged_message, run, stream
from .options import RunOptions
from .prepare import ASPECT_TOLERANCE, PRESCAN_FRAMES
from .result import COLUMNS, TARGET_COLUMNS, RunInterrupted, RunResult

# Besides __all__, mlplc2.runner names DEMO_MODELS and damaged_message (the CLI's) and the constants ASPECT_TOLERANCE
# and PRESCAN_FRAMES (the docs').

__all__ = ["run", "stream", "RunOptions", "RunResult", "RunInterrupted", "TruncatedInputWarning", "COLUMNS", "TARGET_COLUMNS",
           "default_out_dir", "demo", "DemoResult"]
