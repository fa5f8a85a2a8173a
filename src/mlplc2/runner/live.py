"""The per-frame outputs of a run: a CSV file written a frame at a time (:class:`CsvFile`), and the
stream of results: one JSON object per frame (:func:`frame_record`, schema
:data:`SCHEMA`, documented in ``docs/robot.md``), written one line per frame and flushed
(:class:`JsonLines`: ``mlplc2 run --jsonl``), and the latency from a frame's decoding to its
line (:class:`Latency`).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import sys
from array import array
from collections.abc import Sequence
from pathlib import Path

__all__ = ["SCHEMA", "frame_record", "CsvFile", "JsonLines", "Latency"]

#: Version of the JSON lines' layout; raised when a field changes meaning or goes away
#: (a new field does not change it).
SCHEMA = 1

#: The cells of a ``targets.csv`` row a JSON line's target carries (besides ``model`` and ``id``).
_TARGET_KEYS = ("x", "y", "width", "height", "ttc_s", "miss", "azimuth_deg", "elevation_deg", "ttc_age_s",
               "ttc_sigma_s", "held_by")


def frame_record(index: int, time_s: float, skipped: int, models, outputs, target_rows, *,
                 wall_s: float | None = None, latency_ms: float | None = None) -> dict:
    """One frame's results as a JSON-able dict (schema :data:`SCHEMA`).

    ``models`` the run's models, ``outputs`` their :class:`~mlplc2.Output` s for the frame,
    ``target_rows`` the frame's ``targets.csv`` rows (input pixels). A model warns with its
    targets' warning, a model without targets with its alarm (``Output.collision``). ``wall_s`` (the computer's
    clock, Unix time in s, when the line was made) and ``latency_ms`` (from the frame's decoding to the line), when
    given, follow ``skipped``: a consumer can tell how old a line is on its own clock.
    """
    per_model = {}
    for m, out in zip(models, outputs):
        warns = bool(out.warning) if m.has_targets else bool(out.collision)
        per_model[m.name] = {"response": round(float(out.response), 6), "collision": bool(out.collision),
                             "warning": warns}
    targets = [{"model": r["model"], "id": r["target_id"], **{k: r[k] for k in _TARGET_KEYS},
                "warning": bool(r["warning"])} for r in target_rows]
    clock = {} if wall_s is None else {"wall_s": round(wall_s, 3)}
    if latency_ms is not None:
        clock["latency_ms"] = round(latency_ms, 1)
    return {"schema": SCHEMA, "frame": index, "time_s": time_s, "skipped": skipped, **clock,
            "warning": any(v["warning"] for v in per_model.values()), "models": per_model, "targets": targets}


class CsvFile:
    """A CSV file of dict rows, header first; :meth:`write` makes one ``write()`` per frame, then
    flushes: the file holds whole frames only."""

    def __init__(self, path: Path, columns: Sequence[str]):
        self.path = path
        self.file = open(path, "w", newline="", buffering=1, encoding="utf-8")
        self._buf = io.StringIO()
        self._writer = csv.DictWriter(self._buf, fieldnames=columns, lineterminator="\n")
        self._writer.writeheader()
        self.write([])

    def write(self, rows: list[dict]) -> None:
        self._writer.writerows(rows)
        self.file.write(self._buf.getvalue())
        self.file.flush()
        self._buf.seek(0)
        self._buf.truncate()


class JsonLines:
    """Where the JSON lines go: a path (``'-'``: standard output) or a text file object;
    :meth:`write` writes one line and flushes it."""

    def __init__(self, target):
        self._own = False
        self.gone = False
        if target == "-":
            self.file = sys.stdout
            self.name = "stdout"
        elif hasattr(target, "write"):
            self.file = target
            self.name = str(getattr(target, "name", "jsonl")).strip("<>")   # sys.stdout: "<stdout>"
        else:
            self.name = str(target)
            path = Path(target)
            path.parent.mkdir(parents=True, exist_ok=True)
            self.file = open(path, "w", encoding="utf-8")
            self._own = True

    def write(self, record: dict) -> bool:
        """Write one line; False when its reader has gone (a closed pipe: nothing more is written)."""
        if self.gone:
            return False
        try:
            self.file.write(json.dumps(record, separators=(",", ":")) + "\n")
            self.file.flush()
        except BrokenPipeError:
            self.gone = True
            try:  # so that the interpreter's last flush of the pipe does not fail again
                os.dup2(os.open(os.devnull, os.O_WRONLY), self.file.fileno())
            except (OSError, ValueError):
                pass
            return False
        return True

    def close(self) -> None:
        if self._own:
            self.file.close()
        else:
            try:
                self.file.flush()
            except (OSError, ValueError):  # a closed pipe: nothing more to say
                pass


class Latency:
    """Latencies (seconds) of the frames of a run; :meth:`stats` in milliseconds."""

    def __init__(self):
        self.values = array("d")

    def add(self, seconds: float) -> None:
        self.values.append(seconds)

    def stats(self) -> dict:
        """``{"median_ms", "p99_ms", "max_ms"}`` (empty without frames); p99: the nearest-rank 99th percentile."""
        v = sorted(self.values)
        if not v:
            return {}
        n = len(v)
        median = v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])
        p99 = v[min(n - 1, max(0, math.ceil(0.99 * n) - 1))]
        return {"median_ms": round(1e3 * median, 2), "p99_ms": round(1e3 * p99, 2), "max_ms": round(1e3 * v[-1], 2)}
