"""What models said, frame by frame: the one recorder of per-frame outputs.

One home for what every scorer and recorder needs (``mlplc2 run``, ``mlplc2 evaluate``,
``mlplc2 benchmark``, ``mlplc2 reproduce``, the tests):

:class:`Record` / :class:`Recorder`
    one model's outputs on one video: per frame the global alarm and response, the
    attention fields (id, centre, response, alarm) and the targets (id, centre, size, time
    to contact, miss, warning: :class:`TargetRow`); per field its life (birth, death, peak,
    first alarm: :class:`FieldHistory`) and per target its summary (:class:`TargetHistory`).
    A :class:`Recorder` fills Records from :class:`~mlplc2.Output` objects as a video is
    processed: its series may be switched off and the fields that died spilled to a
    temporary file for long runs (``mlplc2 run``, whose ``fields.json`` is
    :meth:`Recorder.summaries` and :meth:`Recorder.target_summaries`); :func:`record` runs a
    model over frames with every series (``mlplc2 reproduce``, the tests).
:func:`response_rows`
    the ``responses.csv`` rows of one output (the rounding of the output files).
:func:`read_responses`, :func:`read_targets`
    the rows of a ``responses.csv`` / ``targets.csv`` read back, as ``RunResult.rows`` / ``.targets`` hold
    them (``mlplc2 evaluate``, the plots).

Holding a Record against the ground truth is :mod:`mlplc2.evaluation.match`.
Coordinates are those of the video (its own pixels, the ground truth's).
"""

from __future__ import annotations

import csv
import json
import math
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validation import InputValueError

__all__ = ["FieldHistory", "TargetRow", "TargetHistory", "Record", "Recorder", "record", "response_rows",
           "read_responses", "read_targets"]


def _px(v: float | None) -> float | None:
    """A position or size in the output files: px, 2 decimals."""
    return None if v is None else round(float(v), 2)


def _sig(v: float) -> float:
    """A response in the output files: 7 significant digits."""
    v = float(v)
    return float(f"{v:.7g}") if math.isfinite(v) else v


def response_rows(index: int, time_s: float, name: str, out, to_input) -> list[dict]:
    """The ``responses.csv`` rows of one model's :class:`~mlplc2.models.Output` at frame ``index``:
    one per field (centre mapped to input pixels by ``to_input(x, y)``), or one frame-wide row."""
    if not out.fields:
        return [{"frame": index, "time_s": time_s, "model": name, "field_id": None, "x": None, "y": None,
                 "response": _sig(out.response), "collision": int(bool(out.collision))}]
    rows = []
    for f in out.fields:
        x, y = to_input(f.x, f.y)
        rows.append({"frame": index, "time_s": time_s, "model": name, "field_id": f.id, "x": _px(x),
                     "y": _px(y), "response": _sig(f.response), "collision": int(bool(f.collision))})
    return rows


def _num(v) -> float | None:
    """A number cell of the output files read back (empty: None)."""
    return None if v in (None, "") else float(v)


def _opt4(v: float | None) -> float | None:
    """A time to contact, miss or bearing in the output files: 4 decimals, empty when unknown."""
    return None if v is None else round(float(v), 4) + 0.0  # + 0.0: no "-0.0"


@dataclass
class FieldHistory:
    """One attention field over its life (frames are the video's frame indices).

    ``x``, ``y``: its centre at its peak response (the first frame of a plateau), in video
    pixels (mLPLC2 fields stay where they were born; sLPLC2's follows the motion);
    ``frames``, ``responses``, ``alarms``: its per-frame series (a :class:`Recorder` with
    ``series=True``)."""

    id: int
    x: float
    y: float
    radius: float
    born: int
    died: int | None = None
    peak_response: float = 0.0
    peak_frame: int | None = None
    first_alarm_frame: int | None = None
    frames: list[int] = field(default_factory=list)
    responses: list[float] = field(default_factory=list)
    alarms: list[int] = field(default_factory=list)

    @property
    def first_alarm(self) -> int | None:
        return self.first_alarm_frame

    @property
    def peak(self) -> float:
        return self.peak_response

    @property
    def last(self) -> int | None:
        return self.frames[-1] if self.frames else None

    def summary(self) -> dict:
        """The field's entry of ``fields.json`` (docs/cli.md): rounded as in ``responses.csv``."""
        return {"id": self.id, "x": _px(self.x), "y": _px(self.y), "born": self.born, "died": self.died,
                "peak_response": _sig(self.peak_response), "peak_frame": self.peak_frame,
                "first_alarm_frame": self.first_alarm_frame}


@dataclass(frozen=True)
class TargetRow:
    """One target in one frame (video pixels)."""

    id: int
    x: float
    y: float
    width: float | None = None
    height: float | None = None
    ttc_s: float | None = None
    miss: float | None = None
    warning: bool = False
    fields: tuple[int, ...] = ()
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    ttc_age_s: float | None = None
    ttc_sigma_s: float | None = None
    held_by: str | None = None

    @classmethod
    def from_row(cls, r) -> "TargetRow":
        """A ``targets.csv`` row (dict of strings or numbers) as a TargetRow (``mlplc2 evaluate``): every cell
        :meth:`values` writes; a file written before ``ttc_age_s``, ``ttc_sigma_s`` or ``held_by`` (no such column)
        reads as None."""
        fields = r.get("fields") or ""
        return cls(int(r["target_id"]), float(r["x"]), float(r["y"]), _num(r.get("width")), _num(r.get("height")),
                   _num(r.get("ttc_s")), _num(r.get("miss")), bool(int(float(r.get("warning") or 0))),
                   tuple(int(v) for v in str(fields).split()), azimuth_deg=_num(r.get("azimuth_deg")),
                   elevation_deg=_num(r.get("elevation_deg")), ttc_age_s=_num(r.get("ttc_age_s")),
                   ttc_sigma_s=_num(r.get("ttc_sigma_s")), held_by=r.get("held_by") or None)

    def values(self) -> dict:
        """Its cells of ``targets.csv`` after ``frame, model, target_id`` (rounded; None: empty)."""
        return {"x": _px(self.x), "y": _px(self.y), "width": _px(self.width), "height": _px(self.height),
                "ttc_s": _opt4(self.ttc_s), "miss": _opt4(self.miss), "warning": int(bool(self.warning)),
                "fields": " ".join(map(str, self.fields)), "azimuth_deg": _opt4(self.azimuth_deg),
                "elevation_deg": _opt4(self.elevation_deg), "ttc_age_s": _opt4(self.ttc_age_s),
                "ttc_sigma_s": _opt4(self.ttc_sigma_s), "held_by": self.held_by}


def _read_rows(path, row: Callable[[dict], dict], needs: Sequence[str], what: str | None) -> list[dict] | None:
    """``row(cells)`` of every row of the CSV file ``path`` with a frame. Without a column of ``needs``: None,
    or InputValueError ``<path>: not a <what> ...`` when ``what`` is given; a cell that does not parse:
    InputValueError ``<path>: malformed row``."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        missing = set(needs) - set(reader.fieldnames or ())
        if missing and what is None:
            return None
        if missing:
            raise InputValueError(f"{path}: not a {what} (missing columns {', '.join(sorted(missing))})")
        try:
            return [row(r) for r in reader if r["frame"] not in (None, "")]
        except (TypeError, ValueError, KeyError):
            raise InputValueError(f"{path}: malformed row") from None


def _response(r: dict) -> dict:
    return {"frame": int(r["frame"]), "time_s": _num(r.get("time_s")), "model": r["model"],
            "field_id": None if r["field_id"] in (None, "") else int(r["field_id"]), "x": _num(r["x"]),
            "y": _num(r["y"]), "response": _num(r.get("response")), "collision": int(r["collision"])}


def _target(r: dict) -> dict:
    t = dict(vars(TargetRow.from_row(r)))          # its fields in the order of the columns
    return {"frame": int(r["frame"]), "model": r["model"], "target_id": t.pop("id"),
            **t, "warning": int(t["warning"]), "fields": " ".join(map(str, t["fields"]))}


def read_responses(path) -> list[dict]:
    """The rows of a ``responses.csv`` written by :func:`mlplc2.run`, as ``RunResult.rows`` holds them (numbers
    parsed, an empty cell None; so is ``time_s`` or ``response`` of a file without that column); rows without a
    frame are skipped. One-line InputValueError for a file without the columns ``mlplc2 evaluate`` needs
    (``not a responses.csv``) or with a cell that does not parse (``malformed row``)."""
    return _read_rows(path, _response, ("frame", "model", "field_id", "x", "y", "collision"), "responses.csv")


def read_targets(path) -> list[dict] | None:
    """The rows of a ``targets.csv`` written by :func:`mlplc2.run`, as ``RunResult.targets`` holds them (cells
    parsed as :meth:`TargetRow.from_row` parses them, not rounded again); rows without a frame are skipped.
    None for a file without ``target_id`` (written before the target layer). One-line InputValueError for a
    cell that does not parse (``malformed row``)."""
    return _read_rows(path, _target, ("target_id",), None)


@dataclass
class TargetHistory:
    """One target over its life: the summary ``fields.json`` writes under ``"targets"``
    (docs/targets.md): life, frames, first estimate, first warning and the estimates then."""

    id: int
    born: int
    died: int | None = None
    frames: int = 0
    first_ttc_frame: int | None = None
    first_warning_frame: int | None = None
    warning_frames: int = 0
    warning_runs: list[list[int]] = field(default_factory=list)   # [first, last] frame of each run of warnings
    at_first_warning: TargetRow | None = None
    fields: set[int] = field(default_factory=set)
    last_frame: int | None = None
    last: TargetRow | None = None

    def summary(self) -> dict:
        return {"id": self.id, "born": self.born, "died": self.died, "frames": self.frames,
                "first_ttc_frame": self.first_ttc_frame, "first_warning_frame": self.first_warning_frame,
                "warning_frames": self.warning_frames, "warning_runs": [list(r) for r in self.warning_runs],
                "at_first_warning": None if self.at_first_warning is None else _listed(self.at_first_warning),
                "fields": sorted(self.fields), "last": {"frame": self.last_frame, **_listed(self.last)}}


def _listed(row: TargetRow) -> dict:
    """A ``targets.csv`` row for ``fields.json``: its ``fields`` a list of ids, as the target's own ``fields``
    (the CSV's cell is the ids separated by spaces)."""
    return {**row.values(), "fields": list(row.fields)}


@dataclass
class Record:
    """One model's outputs on one video.

    Always: ``fields`` (id -> :class:`FieldHistory`, their summaries; with ``spill`` only the
    live ones), ``targets`` (id -> :class:`TargetHistory`), ``alarm_count`` and
    ``first_alarm_frame`` (frames with ``Output.collision``), ``peak_response`` and ``peak_frame``. With ``series`` (the default)
    also per frame: ``alarm[frame]`` (``Output.collision``), ``response_at[frame]``
    (``Output.response``), ``fields_at[frame]``: ``(field_id, x, y, response, collision)`` of
    every field, ``targets_at[frame]``: its :class:`TargetRow` s; and each field's series.
    ``has_targets``: the model makes targets (its warning is then the targets' warnings; else
    its alarm). ``localises``: its fields have meaningful positions.
    """

    model: str
    source: str = ""
    fps: float = 30.0
    size: tuple[int, int] | None = None
    start: int = 0
    n_frames: int = 0
    alarm: dict[int, bool] = field(default_factory=dict)
    response_at: dict[int, float] = field(default_factory=dict)
    fields_at: dict[int, list[tuple[int, float, float, float, bool]]] = field(default_factory=dict)
    targets_at: dict[int, list[TargetRow]] = field(default_factory=dict)
    fields: dict[int, FieldHistory] = field(default_factory=dict)
    targets: dict[int, TargetHistory] = field(default_factory=dict)
    alarm_count: int = 0
    first_alarm_frame: int | None = None
    peak_response: float | None = None
    """The largest ``Output.response`` of any frame (None before the first), and its frame: ``peak_frame``."""
    peak_frame: int | None = None
    has_targets: bool = False
    localises: bool = False
    label: str = ""

    @property
    def frames(self) -> range:
        """The processed frames."""
        return range(self.start, self.start + self.n_frames)

    @property
    def response(self) -> np.ndarray:
        """``Output.response`` of every processed frame (series), as an array."""
        return np.array([self.response_at.get(f, 0.0) for f in self.frames], dtype=float)

    @property
    def collision(self) -> np.ndarray:
        """``Output.collision`` of every processed frame (series), as an array."""
        return np.array([bool(self.alarm.get(f)) for f in self.frames], dtype=bool)

    def alarmed(self) -> list[FieldHistory]:
        """The fields that raised an alarm, in order of birth."""
        return [f for f in self.fields.values() if f.first_alarm_frame is not None]


class Recorder:
    """Fills one :class:`Record` per model from the models' outputs, frame by frame: the one
    recorder of ``mlplc2 run`` (``fields.json``), ``mlplc2 reproduce`` and the tests.

    ``offset``: the video frame index of model frame 0 (``--start``); ``to_input``: maps model
    pixels to video pixels (``--resize``); ``series``: keep the per-frame rows and each field's
    per-frame responses (False keeps only the summaries: flat memory in the frames);
    ``spill``: a field that died leaves memory for an anonymous temporary file (flat memory
    in the fields too: long or live runs); :meth:`summaries` still lists it. :meth:`close`
    the recorder (or use it in a ``with`` block) to delete that file.
    """

    def __init__(self, models: Sequence, *, fps: float = 30.0, source: str = "", size=None, offset: int = 0,
                 to_input=None, series: bool = True, spill: bool = False):
        self.offset = offset
        self.to_input = to_input or (lambda x, y: (x, y))
        self.series = series
        self.records: dict[str, Record] = {}
        self._alive: dict[str, set[int]] = {}
        self._alive_targets: dict[str, set[int]] = {}
        self._spill: dict[str, Any] | None = {} if spill else None
        for m in models:
            name = m if isinstance(m, str) else m.name
            self.records[name] = Record(model=name, source=source, fps=fps, size=size, start=offset,
                                        has_targets=bool(getattr(m, "has_targets", False)),
                                        localises=bool(getattr(m, "localises", False)), label=name)
            self._alive[name] = set()
            self._alive_targets[name] = set()

    def update(self, index: int, name: str, out) -> list[TargetRow]:
        """Add ``out`` (an :class:`~mlplc2.Output`) of model ``name`` at video frame ``index``.
        Returns the frame's targets as :class:`TargetRow` s (video pixels: ``targets.csv``)."""
        rec = self.records[name]
        rec.n_frames = index - rec.start + 1
        if out.collision:
            rec.alarm_count += 1
            if rec.first_alarm_frame is None:
                rec.first_alarm_frame = index
        if rec.peak_response is None or out.response > rec.peak_response:
            rec.peak_response, rec.peak_frame = float(out.response), index
        if self.series:
            rec.alarm[index] = bool(out.collision)
            rec.response_at[index] = float(out.response)
        present = set()
        rows = []
        for f in out.fields:
            present.add(f.id)
            x, y = self.to_input(f.x, f.y)
            ft = rec.fields.get(f.id)
            if ft is None:
                ft = rec.fields[f.id] = FieldHistory(f.id, float(x), float(y), float(f.radius), f.born + self.offset,
                                                   peak_response=float(f.response), peak_frame=index)
            elif f.response > ft.peak_response:      # the first frame of a plateau stays the peak
                ft.peak_response, ft.peak_frame = float(f.response), index
                ft.x, ft.y = float(x), float(y)
            if f.collision and ft.first_alarm_frame is None:
                ft.first_alarm_frame = index
            if self.series:
                ft.frames.append(index)
                ft.responses.append(float(f.response))
                if f.collision:
                    ft.alarms.append(index)
                rows.append((f.id, float(x), float(y), float(f.response), bool(f.collision)))
        for fid in self._alive[name] - present:
            ft = rec.fields[fid]
            ft.died = index
            if self._spill is not None:
                spill = self._spill.get(name)
                if spill is None:
                    spill = self._spill[name] = tempfile.TemporaryFile("w+", encoding="utf-8")
                spill.write(json.dumps(ft.summary()) + "\n")
                del rec.fields[fid]
        self._alive[name] = present
        targets = [self._target_row(t) for t in getattr(out, "targets", ())]
        self._update_targets(index, rec, name, targets)
        if self.series:
            if rows:
                rec.fields_at[index] = rows
            if targets:
                rec.targets_at[index] = targets
        return targets

    def _target_row(self, t) -> TargetRow:
        x, y = self.to_input(t.x, t.y)
        x1, y1 = self.to_input(t.x + t.width, t.y + t.height)
        return TargetRow(t.id, float(x), float(y), float(x1 - x), float(y1 - y), t.ttc_s, t.miss, bool(t.warning),
                         tuple(t.fields), getattr(t, "azimuth_deg", None), getattr(t, "elevation_deg", None),
                         getattr(t, "ttc_age_s", None), getattr(t, "ttc_sigma_s", None), getattr(t, "held_by", None))

    def _update_targets(self, index: int, rec: Record, name: str, rows: list[TargetRow]) -> None:
        """Per target: life, frames, first estimate and first warning (with the estimate then)."""
        seen = set()
        for t in rows:
            seen.add(t.id)
            tt = rec.targets.get(t.id)
            if tt is None:
                tt = rec.targets[t.id] = TargetHistory(t.id, born=index)
            tt.frames += 1
            tt.fields.update(t.fields)
            if t.ttc_s is not None and tt.first_ttc_frame is None:
                tt.first_ttc_frame = index
            if t.warning:
                tt.warning_frames += 1
                if tt.last is not None and tt.last.warning and tt.warning_runs:   # its last frame warned too
                    tt.warning_runs[-1][1] = index
                else:
                    tt.warning_runs.append([index, index])
                if tt.first_warning_frame is None:
                    tt.first_warning_frame, tt.at_first_warning = index, t
            tt.last_frame, tt.last = index, t
        for tid in self._alive_targets[name] - seen:
            if rec.targets[tid].died is None:
                rec.targets[tid].died = index
        self._alive_targets[name] = seen

    def summaries(self, name: str) -> list[dict]:
        """The field summaries of model ``name`` (``fields.json`` ``"models"``), by id, spilled ones too."""
        out = [ft.summary() for ft in self.records[name].fields.values()]
        spill = None if self._spill is None else self._spill.get(name)
        if spill is not None:
            spill.seek(0)
            out += [json.loads(line) for line in spill]
            spill.seek(0, 2)
        return sorted(out, key=lambda d: d["id"])

    def target_summaries(self, name: str) -> list[dict]:
        """The target summaries of model ``name`` (``fields.json`` ``"targets"``), by id."""
        targets = self.records[name].targets
        return [targets[k].summary() for k in sorted(targets)]

    def close(self) -> None:
        """Delete the spill files (the summaries of the fields that died are then lost)."""
        for f in (self._spill or {}).values():
            f.close()
        if self._spill:
            self._spill.clear()

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def record(model, frames, *, progress=None) -> Record:
    """Run ``model`` (a :class:`~mlplc2.models.Model`) over ``frames`` and record every output
    with its series (frame indices: ``Output.frame``). ``progress``: an object with
    ``update(1)`` (a tqdm bar), called once per frame."""
    rec = Recorder([model], fps=model.fps)
    for frame in frames:
        out = model.step(frame)
        rec.update(out.frame, model.name, out)
        if progress is not None:
            progress.update(1)
    return rec.records[model.name]
