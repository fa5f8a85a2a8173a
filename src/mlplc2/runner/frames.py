"""The per-frame work of a run (:class:`Frames`): every model steps on the frame, then the frame's share of every
output is written together (the JSON line, ``responses.csv``, ``targets.csv``, ``annotated.mp4``); at the end, the
summaries of the fields and targets. :class:`OutputFailed` and :class:`GyroEnded` stop a run at a frame."""

from __future__ import annotations

import time
from pathlib import Path

from .._validation import InputValueError
from ..evaluation.record import Recorder, response_rows
from ..io import FrameSource, VideoWriter
from ..models.base import Model
from .live import CsvFile, JsonLines, Latency, frame_record
from .options import RunOptions
from .result import COLUMNS, TARGET_COLUMNS, RunResult


class OutputFailed(Exception):
    """Writing one of the per-frame outputs failed (an OSError: a full disk, a device that refuses):
    the run stops at that frame, and :func:`_loop` still writes the summaries of the frames done.
    ``name`` is the output as ``fields.json``'s ``"error"`` names it (``annotated.mp4``,
    ``responses.csv``, ``targets.csv``, the JSON lines' path or ``stdout``), ``path`` the file's path
    for the one-line error; the OSError is its ``__cause__``."""

    def __init__(self, name: str, path: str):
        super().__init__(name)
        self.name, self.path = name, path


class GyroEnded(Exception):
    """The gyro's samples end before a frame's time (a source of unknown length, e.g. stdin, whose
    span could not be checked before the run), or a live gyro (:class:`~mlplc2.io.gyro.LiveGyro`) gave no rate:
    the run stops before that frame, :func:`_loop` writes the summaries of the frames done (``error``: the message;
    not complete), then raises it as an :class:`~mlplc2.InputError` (:func:`stream` too)."""


class Frames:
    """The per-frame work of :func:`run`: step every model, record, write each output's share."""

    def __init__(self, src: FrameSource, built: list[Model], result: RunResult, options: RunOptions):
        self.src, self.built, self.result, self.options = src, built, result, options
        self.names = result.models
        self.recorder = Recorder(built, fps=src.fps, source=str(src.name), size=src.size, offset=src.start,
                                 to_input=src.to_input, series=False, spill=not options.keep_rows)
        self.primary = next((i for i, m in enumerate(built) if m.has_fields), None)  # the model drawn on the video
        self.field_shape = (getattr(built[self.primary].params, "field_shape", "square")
                            if self.primary is not None else "square")
        self.responses = self.targets = self.vw = self.lines = None
        self.latency = Latency()

    def open(self, out_dir: Path | None) -> None:
        """The per-frame outputs: the JSON lines, ``responses.csv``, ``targets.csv`` and ``annotated.mp4``."""
        if self.options.jsonl is not None:
            self.lines = JsonLines(self.options.jsonl)
        if out_dir is None:
            return
        self.responses = CsvFile(out_dir / "responses.csv", COLUMNS)
        self.result.files["responses.csv"] = self.responses.path
        if any(m.has_targets for m in self.built):
            self.targets = CsvFile(out_dir / "targets.csv", TARGET_COLUMNS)
            self.result.files["targets.csv"] = self.targets.path
        if self.options.video:
            self.vw = VideoWriter(out_dir / "annotated.mp4", self.src.fps, self.src.size)

    def step(self, item: tuple) -> dict:
        """One frame: the models step, then the frame's share of every output, together; returns
        the frame's JSON line (:func:`~mlplc2.runner.live.frame_record`). Its latency runs from the
        frame's decoding to its JSON line, written before its CSV rows (without ``jsonl``: to where it would be)."""
        index, frame = item[0], item[1]
        names, result, src = self.names, self.result, self.src
        time_s = round(index / src.fps if src.time_s is None else src.time_s, 6)
        try:
            rate = None if self.options.gyro is None else self.options.gyro.at(time_s, src.fps)
        except InputValueError as exc:  # a source of unknown length outran the gyro: stop, keep the frames done
            raise GyroEnded(str(exc)) from None
        # the gyro only to the models that take it (a model of the user's may not know the keyword)
        outputs = [m.step(frame, src.time_s) if rate is None or m.gyro_refusal() else
                   m.step(frame, src.time_s, gyro=rate) for m in self.built]
        if self.vw is not None:
            from ..plots import annotate_frame

            img = annotate_frame(item[2], outputs, names, src.scale_x, src.scale_y, primary=self.primary,
                                 index=index, field_shape=self.field_shape, draw_fields=self.options.draw_fields)
            try:
                self.vw.write(img)
            except OSError as exc:  # a full disk: this frame goes nowhere, the others' outputs are kept
                raise OutputFailed("annotated.mp4", str(self.vw.path)) from exc
        # The frame's share of every output, together: the JSON line first (its latency ends there), the CSV rows after.
        target_rows = []
        for name, out in zip(names, outputs):
            if out.repeated:
                result.repeated[name] += 1
            target_rows.extend({"frame": index, "model": name, "target_id": t.id, **t.values()}
                               for t in self.recorder.update(index, name, out))
        record = frame_record(index, time_s, src.skipped, self.built, outputs, target_rows, wall_s=time.time(),
                              latency_ms=1e3 * (time.perf_counter() - src.decoded_at))
        if self.lines is not None:
            try:
                delivered = self.lines.write(record)
            except OSError as exc:  # not a reader that went away (that is False): a full disk, /dev/full
                raise OutputFailed(self.lines.name, self.lines.name) from exc
            if not delivered:
                self.result.reader_gone = True
            if not delivered and self.result.message is None:
                self.result.message = (f"the reader of the JSON lines went away (frame {index} not delivered); "
                                       f"stopped there")
        line_at = time.perf_counter()
        frame_rows = [row for name, out in zip(names, outputs)
                      for row in response_rows(index, time_s, name, out, src.to_input)]
        for csv_file, rows in ((self.targets, target_rows), (self.responses, frame_rows)):
            if csv_file is not None and (rows or csv_file is self.responses):
                try:
                    csv_file.write(rows)
                except OSError as exc:
                    raise OutputFailed(csv_file.path.name, str(csv_file.path)) from exc
        result.n_frames += 1
        if result.n_frames > 1:  # the first frame's step builds the models' state (and compiles): not latency
            self.latency.add(line_at - src.decoded_at)
        if self.options.keep_rows:
            result.targets.extend(target_rows)
            result.rows.extend(frame_rows)
        result.skipped += src.skipped
        return record

    def close_csv(self, failed: bool = False) -> None:
        """Close the CSV files and the JSON lines; after a failed write (``failed``) closing the file
        that failed would fail again (its unwritten rest): that is not a second error."""
        closes = [f.file.close for f in (self.responses, self.targets) if f is not None]
        closes += [self.lines.close] if self.lines is not None else []
        for close in closes:
            try:
                close()
            except OSError:
                if not failed:
                    raise

    def summarise(self, interrupted: bool, failed: OutputFailed | None = None) -> None:
        """The run's end state and the summaries of its fields and targets into ``result``."""
        result, recorder, names = self.result, self.recorder, self.names
        result.interrupted = interrupted
        if failed is not None:
            cause = failed.__cause__
            result.error = f"{failed.name}: {getattr(cause, 'strerror', None) or cause}"
        result.truncated = self.src.truncated
        result.dropped, result.damaged = self.src.dropped, self.src.damaged
        result.message = self.src.message or result.message
        result.latency = self.latency.stats()
        # One decision on duplicated frames: the pre-scan's, or a model left to find out held frames.
        if result.duplicated is False and any(result.repeated[m.name] for m in self.built
                                              if m.repeat_threshold == "auto"):
            result.duplicated = True
        # Fields still alive at the end keep died = None.
        with recorder:
            result.fields = {name: recorder.summaries(name) for name in names}
            result.target_summaries = {name: recorder.target_summaries(name) for name in names
                                       if recorder.records[name].has_targets}
            result.alarms = {name: {"count": r.alarm_count, "first": r.first_alarm_frame, "peak": r.peak_response,
                                    "peak_frame": r.peak_frame}
                             for name, r in recorder.records.items()}
