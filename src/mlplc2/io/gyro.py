"""A gyro's angular velocity over time (``mlplc2 run --gyro FILE.csv``), read and interpolated
at each frame's timestamp (docs/robot.md, "Frame rate, field of view and a gyro").

The file: a CSV with a header naming the columns ``t`` (seconds, on the video's clock: the time
of frame ``i`` is its container timestamp, or ``i / fps``) and ``wx``, ``wy``, ``wz`` (rad/s about
the camera's x (right), y (down) and z (forward) axes; other columns are ignored), one sample a
row, ``t`` increasing. Between samples the rate is interpolated linearly; the samples must span
the run's frames (up to :data:`SLACK` of a frame interval beyond the first and last sample, the
end sample's rate is held).
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np

from .._validation import InputTypeError, InputValueError, InputWarning

__all__ = ["Gyro", "LiveGyro", "SLACK"]

#: How far (in frame intervals) beyond its first or last sample a gyro's rate is held.
SLACK = 1.0
#: A gyro (ten samples or more) whose samples lie further apart than this many frame intervals at the median
#: is warned of (:meth:`Gyro.check_covers`).
SPARSE = 10.0
_COLUMNS = ("t", "wx", "wy", "wz")


class Gyro:
    """Angular-velocity samples: ``t`` (N,) seconds, increasing; ``rates`` (N, 3) rad/s, camera axes."""

    def __init__(self, t, rates, name: str = "gyro"):
        self.t = np.asarray(t, dtype=np.float64)
        self.rates = np.asarray(rates, dtype=np.float64)
        self.name = name
        self._spacing_checked = False
        if len(self.t) < 2:
            raise InputValueError(f"{name}: needs at least 2 samples (t, wx, wy, wz), got {len(self.t)}")
        if not (np.all(np.isfinite(self.t)) and np.all(np.isfinite(self.rates))):
            raise InputValueError(f"{name}: every t, wx, wy, wz must be a finite number")
        bad = np.flatnonzero(np.diff(self.t) <= 0)
        if bad.size:
            raise InputValueError(f"{name}: t must increase, but sample {bad[0] + 1} (t = {self.t[bad[0] + 1]:g} s) "
                                  f"follows t = {self.t[bad[0]]:g} s")

    @classmethod
    def load(cls, value) -> "Gyro | LiveGyro":
        """A :class:`Gyro` from a CSV path (module docstring), an (N, 4) array of rows ``t, wx, wy, wz``,
        or a :class:`Gyro` (returned as is); a callable ``rate(t)`` gives a :class:`LiveGyro` (a robot's IMU read as
        the frames come)."""
        if isinstance(value, (Gyro, LiveGyro)):
            return value
        if isinstance(value, (str, Path)):
            return cls._read_csv(Path(value))
        if callable(value):
            return LiveGyro(value)
        try:
            a = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputTypeError(f"gyro must be a CSV file or an (N, 4) array of t, wx, wy, wz, "
                                 f"got {type(value).__name__}") from None
        if a.ndim != 2 or a.shape[1] != 4:
            raise InputValueError(f"gyro: an array must have shape (N, 4) (t, wx, wy, wz), got {a.shape}")
        return cls(a[:, 0], a[:, 1:], "gyro")

    @classmethod
    def _read_csv(cls, path: Path) -> "Gyro":
        try:
            with open(path, newline="", encoding="utf-8") as f:
                rows = list(csv.reader(f))
        except (OSError, UnicodeDecodeError) as exc:
            raise InputValueError(f"{path}: cannot read the gyro file ({getattr(exc, 'strerror', None) or exc})") \
                from None
        rows = [r for r in rows if r and any(c.strip() for c in r)]
        header = [c.strip().lower() for c in rows[0]] if rows else []
        missing = [c for c in _COLUMNS if c not in header]
        if missing:
            first = ",".join(rows[0]) if rows else ""
            seen = f"; its first line: {first[:60]!r}" if first else ""
            raise InputValueError(f"{path}: the gyro file needs a header line with the comma-separated columns "
                                  f"t, wx, wy, wz (missing: {', '.join(missing)}{seen})")
        cols = [header.index(c) for c in _COLUMNS]
        values = np.empty((len(rows) - 1, 4))
        for i, row in enumerate(rows[1:]):
            try:
                values[i] = [float(row[c]) for c in cols]
            except (IndexError, ValueError):
                raise InputValueError(f"{path}: line {i + 2}: expected numbers in columns t, wx, wy, wz, "
                                      f"got {','.join(row)!r}") from None
        return cls(values[:, 0], values[:, 1:], str(path))

    def check_covers(self, first_s: float, last_s: float | None, fps: float) -> None:
        """Raise :class:`~mlplc2.InputError` unless the samples span ``first_s`` to ``last_s`` (None: unknown).
        The first time, warn (:class:`~mlplc2.InputWarning`) when many samples lie further apart than
        :data:`SPARSE` frame intervals at the median: a gyro samples faster than a camera, so its times are
        probably not in seconds (milliseconds: its span then covers the frames, with the wrong rates)."""
        if not self._spacing_checked:
            self._spacing_checked = True
            gap = float(np.median(np.diff(self.t)))
            if len(self.t) >= 10 and gap > SPARSE / fps:
                warnings.warn(f"{self.name}: its samples are {gap:g} s apart at the median, {gap * fps:.0f} frame "
                              f"intervals: is t in seconds? (milliseconds: divide it by 1000)", InputWarning,
                              stacklevel=2)
        slack = SLACK / fps
        if first_s < self.t[0] - slack or (last_s is not None and last_s > self.t[-1] + slack):
            frames = (f"a frame is at {_s(first_s)} s" if last_s == first_s else
                      f"the run's frames start at {_s(first_s)} s" if last_s is None else
                      f"the run's frames are at {_s(first_s)} to {_s(last_s)} s")
            raise InputValueError(f"{self.name}: the gyro covers t = {_s(self.t[0])} to {_s(self.t[-1])} s "
                                  f"but {frames} "
                                  f"(t is on the video's clock: frame i at i / fps, or its timestamp)")

    def at(self, t: float, fps: float) -> tuple[float, float, float]:
        """The rate (rad/s) at ``t`` seconds, interpolated linearly; outside the samples (beyond :data:`SLACK`),
        :class:`~mlplc2.InputError`."""
        self.check_covers(t, t, fps)
        return tuple(float(np.interp(t, self.t, self.rates[:, k])) for k in range(3))


class LiveGyro:
    """A gyro read as the frames come (``stream(source, gyro=rate)``, ``run(..., gyro=rate)``): ``rate(t)`` is called
    once per frame with the frame's time (seconds, on the source's clock, as ``time_s`` of the JSON lines) and gives
    the camera's angular velocity then, ``(wx, wy, wz)`` rad/s about its x (right), y (down) and z (forward) axes (the
    robot's latest IMU reading, or one interpolated at ``t``), or None for a frame without one (its rotation is then
    the images' estimate)."""

    def __init__(self, rate, name: str | None = None):
        self.rate = rate
        self.name = name or f"gyro {getattr(rate, '__name__', type(rate).__name__)}"

    def check_covers(self, first_s: float, last_s: float | None, fps: float) -> None:
        """Nothing to check before the run: each frame asks for its own rate."""

    def at(self, t: float, fps: float) -> tuple[float, float, float] | None:
        """``rate(t)`` as three floats; :class:`~mlplc2.InputError` for anything else than three finite numbers or
        None."""
        value = self.rate(t)
        if value is None:
            return None
        try:
            if isinstance(value, (str, bytes)):
                raise TypeError(value)
            w = tuple(float(v) for v in value)
        except (TypeError, ValueError):
            raise InputTypeError(f"{self.name}: gave {value!r} at t = {_s(t)} s; expected (wx, wy, wz) in rad/s "
                                 f"or None") from None
        if len(w) != 3 or not all(np.isfinite(w)):
            raise InputValueError(f"{self.name}: gave {value!r} at t = {_s(t)} s; expected three finite numbers "
                                  f"(wx, wy, wz) in rad/s or None")
        return w


def _s(t: float) -> str:
    """Seconds for a message: 6 significant digits, and the milliseconds of a clock past 10^5 s (a robot's
    epoch time, 1.7e9 s, showed its first and last sample alike as 1.73325e+09)."""
    return f"{t:g}" if abs(t) < 1e5 else f"{t:.3f}"
