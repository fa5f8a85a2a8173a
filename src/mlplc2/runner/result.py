"""What :func:`mlplc2.run` gives: :class:`RunResult` (the rows of ``responses.csv`` and
``targets.csv``, the summaries of ``fields.json``), the columns of those files
(:data:`COLUMNS`, :data:`TARGET_COLUMNS`), and :class:`RunInterrupted` (Ctrl-C during a run,
carrying the result of the frames done).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._validation import InputValueError
from ..evaluation.record import read_responses

__all__ = ["RunResult", "RunInterrupted", "COLUMNS", "TARGET_COLUMNS"]

#: Columns of ``responses.csv``, in order.
COLUMNS = ("frame", "time_s", "model", "field_id", "x", "y", "response", "collision")
#: Columns of ``targets.csv``, in order (``docs/targets.md``): positions and sizes in input pixels,
#: the bearing in degrees (empty without a field of view), the age of ``ttc_s`` in s (0: measured this frame),
#: its standard error in s.
TARGET_COLUMNS = ("frame", "model", "target_id", "x", "y", "width", "height", "ttc_s", "miss", "warning", "fields",
                  "azimuth_deg", "elevation_deg", "ttc_age_s", "ttc_sigma_s", "held_by")


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run`; the outputs for the frames done were written.

    ``.result`` is the :class:`RunResult` of the frames processed.
    """

    def __init__(self, result: "RunResult"):
        super().__init__(f"interrupted after {result.n_frames} frames")
        self.result = result


@dataclass
class RunResult:
    """What :func:`run` computed.

    Attributes
    ----------
    rows : list of dict
        The rows of ``responses.csv`` (keys :data:`COLUMNS`; ``None`` where the
        CSV cell is empty; ``collision`` is 0 or 1). Empty when the run was made
        with ``keep_rows=False`` (the rows are then only in the CSV).
    alarms : dict
        Per model name, the frames with the collision flag set: ``{"count": n,
        "first": frame or None}``, and the largest ``Output.response`` with its frame (``"peak"``,
        ``"peak_frame"``; None without frames); kept whatever ``keep_rows`` says.
    fields : dict
        Per model name, the list of field summaries written to ``fields.json``.
    fps : float
        Frame rate used (``time_s = frame / fps``).
    n_frames : int
        Frames processed.
    truncated : bool
        The input stopped decoding early (see ``message``).
    interrupted : bool
        The run was stopped by Ctrl-C (or SIGTERM under ``mlplc2 run``).
    error : str, optional
        Why an output stopped the run (``annotated.mp4`` on a full disk): the other outputs
        were written for the frames done, then :func:`run` raised the OSError. Or why the gyro
        stopped it (its samples ended before a frame of a source of unknown length): the
        outputs were written for the frames done, then :func:`run` raised an InputError.
    seconds : float
        Wall time of the frame loop (decoding, models, writing the per-frame outputs),
        in seconds; ``n_frames / seconds`` is the processing rate.
    files : dict
        Output name -> path of the files written (empty with ``out=False``).
    """

    source: str
    models: list[str]
    fps: float
    size: tuple[int, int]
    model_size: tuple[int, int]
    start: int = 0
    n_frames: int = 0
    rows: list[dict] = field(default_factory=list)
    fields: dict[str, list[dict]] = field(default_factory=dict)
    truncated: bool = False
    interrupted: bool = False
    error: str | None = None
    message: str | None = None
    out: Path | None = None
    files: dict[str, Path] = field(default_factory=dict)
    targets: list[dict] = field(default_factory=list)
    """The rows of ``targets.csv`` (keys :data:`TARGET_COLUMNS`; empty with ``keep_rows=False``)."""
    alarms: dict[str, dict] = field(default_factory=dict)
    hfov_deg: float | None = None
    stabilise: dict[str, bool] = field(default_factory=dict)
    """Per model, whether it compensated the camera's rotation before its front end (gaze stabilisation,
    ``Model.stabilise``): the paper's model does not (``--no-stabilise``); ``fields.json`` ``"stabilise"``."""
    seconds: float = 0.0
    target_summaries: dict[str, list[dict]] = field(default_factory=dict)
    """Per model with targets, one summary per target (``fields.json`` ``"targets"``)."""
    repeated: dict[str, int] = field(default_factory=dict)
    """Per model (every model of the run, 0 when none), the frames it held as repeats of the
    previous one (``Output.repeated``)."""
    skipped: int = 0
    """Frames of a live source skipped because the models were behind (the newest frame was taken)."""
    damaged: list[int] = field(default_factory=list)
    """Frames of the input that could not be decoded (a damaged packet), skipped: decoding went on after them."""
    dropped: bool = False
    """A stream or camera stopped with an error (``message`` says which); the results cover the frames before."""
    reader_gone: bool = False
    """The reader of the JSON lines went away (a closed pipe): the run stopped at the first frame it could not
    deliver, whose rows the CSV files still hold (``n_frames`` counts it); not :attr:`complete`."""
    latency: dict[str, float] = field(default_factory=dict)
    """From a frame's decoding to the end of its outputs (its JSON line): ``median_ms``, ``p99_ms``, ``max_ms``."""
    params: dict[str, dict] = field(default_factory=dict)
    """Per model, the parameters it ran with that differ from its defaults (``{}``: the defaults): the fields of its
    own parameter set (``Params`` for the LPLC2 family); a model with targets adds those of its ``TargetParams`` under
    ``"targets"``."""
    duplicated: bool | None = False
    """The video repeats its frames: its first frames looked duplicated (so the models with
    ``repeat_threshold="auto"`` held the copies from the start, :data:`mlplc2.runner.PRESCAN_FRAMES`),
    or such a model found out later and held frames. None when no model was left to find out
    (every model's ``repeat_threshold`` set: ``--skip-repeats``, ``--every-frame``). The
    ``note:`` line of ``mlplc2 run`` is printed exactly when it is True."""

    def __repr__(self) -> str:
        """A few lines, not the rows (a notebook shows this): the source, the frames, each model's alarms and first
        warning, the files; ``rows``, ``targets`` and :meth:`summary` hold the rest."""
        status = "complete" if self.complete else "incomplete: " + (self.message or self.error or "stopped early")
        lines = [f"RunResult({self.source!r}: {self.n_frames} frames from {self.start} at {self.fps:g} fps, "
                 f"{self.size[0]}x{self.size[1]}, {status})"]
        for m in self.models:
            a = self.alarms.get(m, {})
            line = f"  {m}: collision alarm on {a.get('count', 0)} frames (first {a.get('first')})"
            if m in self.target_summaries:
                warned = [s["first_warning_frame"] for s in self.target_summaries[m]
                          if s.get("first_warning_frame") is not None]
                line += (f"; {len(self.target_summaries[m])} targets, first warning "
                         f"{'at frame %d' % min(warned) if warned else 'none'}")
            lines.append(line)
        lines.append(f"  rows: {len(self.rows)}, target rows: {len(self.targets)}"
                     + (f"; files in {self.out}" if self.files else "; no files written"))
        return "\n".join(lines)

    @property
    def complete(self) -> bool:
        """The whole input was processed and every output written (``fields.json`` ``"complete"``)."""
        return not (self.truncated or self.interrupted or self.error or self.dropped or self.reader_gone)

    def to_dataframe(self):
        """``rows`` as a pandas DataFrame; after a
        run with ``keep_rows=False`` the rows are read back from ``responses.csv``."""
        import pandas as pd
        rows = self.rows
        if not rows and self.n_frames:
            path = self.files.get("responses.csv")
            if path is None or not Path(path).is_file():
                raise InputValueError("this run kept no rows (keep_rows=False) and wrote no responses.csv")
            rows = read_responses(path)
        df = pd.DataFrame(rows, columns=list(COLUMNS))
        return df.astype({"field_id": "Int64", "x": "float64", "y": "float64", "collision": bool})

    def summary(self) -> dict[str, Any]:
        """The content of ``fields.json``."""
        return {
            "video": self.source,
            "fps": self.fps,
            "size": list(self.size),
            "model_size": list(self.model_size),
            "start": self.start,
            "n_frames": self.n_frames,
            "seconds": round(self.seconds, 3),
            "complete": self.complete,
            "truncated": self.truncated,
            "interrupted": self.interrupted,
            "error": self.error,
            "hfov_deg": self.hfov_deg,
            "stabilise": self.stabilise,
            "models": self.fields,
            "targets": self.target_summaries,
            "duplicated": self.duplicated,
            "frames_held": self.repeated,
            "frames_skipped": self.skipped,
            "frames_damaged": self.damaged,
            "dropped": self.dropped,
            "reader_gone": self.reader_gone,
            "latency_ms": self.latency,
            "params": self.params,
        }
