"""Ground truth: one model of what happens in a video, and the JSON format that stores it.

Every part of mlplc2 that knows the truth about a video uses these types: the stimulus
generators emit them, ``mlplc2 evaluate`` / ``mlplc2 benchmark`` score against them and
``mlplc2 reproduce`` reads the paper's objects through them. The format is documented in
``docs/evaluation.md`` ("Ground truth"); three flavours share it:

object level (the paper's ``ground_truth.json``, ``mlplc2 stimulus``)
    per video the objects with a centre (or a per-frame track) and the frame intervals of
    their phases (``approach``, ``hold``, ``recede``, ``translate``);
3-D approaches (:func:`mlplc2.stimuli.approach`)
    the same, plus per object a ``kind`` (``collision``, ``pass``, ``recede``,
    ``translate``, ``static``), a ``contact_frame`` and a ``miss`` distance, and a track
    with the apparent size, the true time to contact and the predicted miss per frame;
clip level (real clips, ``../shared/data/real/ground_truth.json``)
    ``"label": "collision" | "no_collision"`` with the ``contact_frame``, the
    ``danger_onset_frame`` (when a person would judge a collision likely), and the track of
    the colliding object (:attr:`VideoTruth.collider`); ``events`` describe the rest.

Coordinates are pixels of the video the truth describes (``size``), ``x`` = column,
``y`` = row, origin top-left; frames are 0-based; intervals are half-open ``[start, end)``.
Every malformed field raises :class:`~mlplc2.InputValueError` naming it.
"""

from __future__ import annotations

import bisect
import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any, NamedTuple

from .._validation import InputValueError

__all__ = ["TrackPoint", "ObjectTruth", "VideoTruth", "GroundTruth", "load", "parse", "read_json", "save",
           "PHASES", "KINDS", "LEGACY_KINDS", "LABELS", "TRACK_COLUMNS", "APPEARANCES", "OBJECT_LAYOUTS"]

#: Phase intervals an object may have, ``[start, end)`` in frames.
PHASES = ("approach", "hold", "recede", "translate")
#: What a 3-D object does relative to the camera (:func:`mlplc2.stimuli.approach`): reaches the
#: camera (``collision``), crosses the camera plane beside it (``pass``), or does not approach.
KINDS = ("collision", "pass", "recede", "translate", "static")
#: The older ``"kind"`` + ``"interval"`` shorthand of one phase (``{"kind": "approaching",
#: "interval": [0, 40]}`` is ``{"approach": [0, 40]}``).
LEGACY_KINDS = {"approaching": "approach", "static": "hold", "receding": "recede", "translating": "translate"}
#: Clip-level labels.
LABELS = ("collision", "no_collision")
#: Columns of a track row, in the default order (``"track_columns"`` may name a prefix of them).
TRACK_COLUMNS = ("frame", "x", "y", "width", "height", "ttc_s", "miss")
#: Appearance of an object against its background.
APPEARANCES = ("dark", "bright", "textured")
#: Key order of an object's JSON (:meth:`ObjectTruth.to_dict`), per flavour: "2d" the paper's
#: ``ground_truth.json`` and :mod:`mlplc2.stimuli` (``half_size``, ``speed``, ``note`` are
#: extras of its generators), "3d" (a ``kind``) the entries of :func:`mlplc2.stimuli.approach`
#: (docs/stimuli.md; ``shape`` ... ``velocity_mps`` are extras). Other keys follow, then
#: ``track_columns``, ``track`` and ``sizes``.
OBJECT_LAYOUTS = {
    "2d": ("id", "kind", "center", "polarity", *PHASES, "contact_frame", "miss", "half_size", "speed", "velocity",
           "note"),
    "3d": ("id", "kind", "shape", "appearance", "width_m", "onset", "start_m", "velocity_mps", "contact_frame",
           "miss", "approach", "hold", "recede", "translate"),
}


# ---------------------------------------------------------------------------
# types
# ---------------------------------------------------------------------------
class TrackPoint(NamedTuple):
    """One frame of an object's track: centre, apparent size (px) and, for 3-D truth, the true
    time to contact (s; None when the object is not approaching) and the predicted miss at
    contact (object widths; None without a contact). A row of :data:`TRACK_COLUMNS`."""

    frame: int
    x: float
    y: float
    width: float | None = None
    height: float | None = None
    ttc_s: float | None = None
    miss: float | None = None


def _lerp(a, b, w):
    if a is None or b is None:
        return a if w < 0.5 else b
    return a + w * (b - a)


@dataclass(frozen=True, eq=True)
class ObjectTruth:
    """One object of a video.

    Attributes
    ----------
    id : int or str
        Object number (1-based in generated truth).
    kind : str or None
        One of :data:`KINDS` for 3-D truth; None for the paper's 2-D objects (their phases say
        what they do).
    center : (x, y) or None
        Fixed centre (2-D stimuli; for a translating object, the centre at the first frame of
        its ``translate`` interval); None for a full-field pattern or when ``track`` is given.
    track : tuple of TrackPoint
        Per-frame positions (3-D truth: every frame in view; real clips: a few labelled frames,
        linearly interpolated).
    polarity : {"dark", "bright", "textured"} or None
        Appearance against the background.
    approach, hold, recede, translate : (start, end) or None
        Phase intervals.
    velocity : (vx, vy) or None
        Px per frame during ``translate`` (2-D stimuli).
    sizes : tuple of float
        Nominal side per frame of the video (2-D stimuli), 0 when absent.
    contact_frame : float or None
        Fractional frame at which the object reaches the camera plane (3-D truth, physical
        looming), None if never.
    miss : float or None
        Lateral miss distance at contact in object widths (0 = dead centre), None without contact.
    extra : dict
        Everything else the JSON object holds, kept on save: the paper stimuli's ``note`` and,
        for physical looming, ``half_size`` (m) and ``speed`` (m/s); the 3-D generator's
        ``shape``, ``width_m``, ``onset``, ``start_m`` and ``velocity_mps`` (docs/stimuli.md).
    """

    id: Any
    kind: str | None = None
    center: tuple[float, float] | None = None
    track: tuple[TrackPoint, ...] = ()
    polarity: str | None = None
    approach: tuple[int, int] | None = None
    hold: tuple[int, int] | None = None
    recede: tuple[int, int] | None = None
    translate: tuple[int, int] | None = None
    velocity: tuple[float, float] | None = None
    sizes: tuple[float, ...] = ()
    contact_frame: float | None = None
    miss: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def approaching(self) -> bool:
        """Whether the object approaches at some point (an ``approach`` phase, or a 3-D
        collision or pass-by): the objects the paper's detection metrics score."""
        return self.approach is not None or self.kind in ("collision", "pass")

    @property
    def collides(self) -> bool:
        """Whether the object is on a collision course (3-D ``kind == "collision"``, or the
        colliding object of a real clip)."""
        return self.kind == "collision"

    @property
    def span(self) -> tuple[int, int] | None:
        """``[start, end)`` from the start of its first phase to the end of its last (the frames
        a 2-D object is on screen); None without phases."""
        spans = [getattr(self, p) for p in PHASES if getattr(self, p) is not None]
        return (min(a for a, _ in spans), max(b for _, b in spans)) if spans else None

    def life_end(self) -> int:
        """End of approach + the hold that directly follows it (exclusive)."""
        end = self.approach[1]
        if self.hold is not None and self.hold[0] <= end:
            end = max(end, self.hold[1])
        return end

    def point_at(self, frame: float) -> TrackPoint | None:
        """The track at ``frame``: exact on a tracked frame, linearly interpolated between two,
        held before the first and after the last; None without a track."""
        t = self.track
        if not t:
            return None
        if frame <= t[0].frame:
            return t[0]
        if frame >= t[-1].frame:
            return t[-1]
        hi = bisect.bisect_right(t, frame, key=lambda p: p.frame)
        a, b = t[hi - 1], t[hi]
        if a.frame == frame:
            return a
        w = (frame - a.frame) / (b.frame - a.frame)
        return TrackPoint(int(frame), *(_lerp(u, v, w) for u, v in zip(a[1:], b[1:])))

    def center_at(self, frame: float) -> tuple[float, float] | None:
        """Centre ``(x, y)`` at ``frame``: the track (interpolated) if there is one, else
        ``center`` (moved by ``velocity`` during ``translate``)."""
        p = self.point_at(frame)
        if p is not None:
            return (p.x, p.y)
        if self.center is None:
            return None
        if self.velocity is None or self.translate is None:
            return self.center
        start, end = self.translate
        dt = min(max(frame, start), end - 1) - start
        return (self.center[0] + self.velocity[0] * dt, self.center[1] + self.velocity[1] * dt)

    def width_at(self, frame: int) -> float | None:
        """Apparent width (px) at ``frame``: the track's, else the nominal side (2-D stimuli)."""
        p = self.point_at(frame)
        if p is not None and p.width is not None:
            return p.width
        if self.sizes and 0 <= frame < len(self.sizes):
            return float(self.sizes[int(frame)])
        return None

    def in_track(self, frame: int) -> bool:
        """Whether ``frame`` lies within the tracked frames (3-D truth: the object is in view)."""
        return bool(self.track) and self.track[0].frame <= frame <= self.track[-1].frame

    def ttc_at(self, frame: int, fps: float) -> float | None:
        """True time to contact (s) at ``frame``: the track's, else from ``contact_frame``;
        None when unknown or after contact."""
        p = self.point_at(frame) if self.in_track(frame) else None
        if p is not None and p.ttc_s is not None:
            return p.ttc_s
        if self.contact_frame is not None and frame < self.contact_frame:
            return (self.contact_frame - frame) / fps
        return None

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of this truth, in the layout of its flavour (:data:`OBJECT_LAYOUTS`).

        2-D objects (no ``kind``: the paper's ``ground_truth.json``, :mod:`mlplc2.stimuli`)
        write the keys that are set. 3-D objects (a ``kind``: :func:`mlplc2.stimuli.approach`,
        docs/stimuli.md "Ground truth") name the polarity ``appearance``, always write
        ``contact_frame``, ``miss`` and ``approach`` (``null``: none) and every track column.
        Numbers are written as they are, except that integral centres, velocities and sizes
        are written as integers.
        """
        three_d = self.kind is not None
        out: dict[str, Any] = {"id": self.id}
        if self.kind is not None:
            out["kind"] = self.kind
        if self.center is not None:
            out["center"] = [_num(self.center[0]), _num(self.center[1])]
        if self.polarity is not None:
            out["appearance" if three_d else "polarity"] = self.polarity
        for phase in PHASES:
            interval = getattr(self, phase)
            if interval is not None or (three_d and phase == "approach"):
                out[phase] = None if interval is None else [int(interval[0]), int(interval[1])]
        for name in ("contact_frame", "miss"):
            v = getattr(self, name)
            if v is not None or three_d:
                out[name] = None if v is None else float(v)
        if self.velocity is not None:
            out["velocity"] = [_num(self.velocity[0]), _num(self.velocity[1])]
        for k, v in self.extra.items():
            out.setdefault(k, v)
        if self.track:
            n = len(TRACK_COLUMNS) if three_d else max(_used_columns(p) for p in self.track)
            out["track_columns"] = list(TRACK_COLUMNS[:n])
            out["track"] = [[_opt(v) for v in p[:n]] for p in self.track]
        if self.sizes:
            out["sizes"] = [_num(s) for s in self.sizes]
        head = [k for k in OBJECT_LAYOUTS["3d" if three_d else "2d"] if k in out]
        last = [k for k in ("track_columns", "track", "sizes") if k in out]
        rest = [k for k in out if k not in head and k not in last]
        return {k: out[k] for k in head + rest + last}


def _used_columns(p: TrackPoint) -> int:
    n = len(p)
    while n > 3 and p[n - 1] is None:
        n -= 1
    return n


@dataclass(frozen=True)
class VideoTruth:
    """Ground truth of one video: its objects and/or a clip-level label.

    ``contact_frame``: the first frame the colliding object touches the camera (clip level),
    with ``danger_onset_frame`` (when a person would judge a collision likely) and
    ``first_visible_frame``; ``ranges`` their plausible intervals (``{"contact_frame": (a, b),
    ...}``). ``collider``: the colliding object of a labelled clip (its ``track`` has
    ``width``), scored by the warning metrics but not by the paper's object metrics.
    ``camera`` / ``background``: the 3-D generator's description. ``extra``: every other key.
    """

    key: str
    size: tuple[int, int] | None = None
    frames: int | None = None
    fps: float | None = None
    objects: tuple[ObjectTruth, ...] = ()
    label: str | None = None
    contact_frame: float | None = None
    danger_onset_frame: float | None = None
    first_visible_frame: float | None = None
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    collider: ObjectTruth | None = None
    events: tuple[Mapping[str, Any], ...] = ()
    camera: Mapping[str, Any] | None = None
    background: str | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def collision_frame(self) -> float | None:
        """The older name of ``contact_frame`` (clip-level truth)."""
        return self.contact_frame

    @property
    def object_level(self) -> bool:
        """Whether the truth lists the objects (False for a clip-level label only)."""
        return bool(self.objects) or self.label is None

    def to_dict(self) -> dict[str, Any]:
        """The JSON entry of this video (the keys that are set)."""
        out: dict[str, Any] = {}
        for name, as_json in (("size", list), ("frames", int), ("fps", float), ("camera", dict), ("background", str),
                              ("label", str)):
            if getattr(self, name) is not None:
                out[name] = as_json(getattr(self, name))
        for name in ("contact_frame", "danger_onset_frame", "first_visible_frame"):
            v = getattr(self, name)
            if v is not None or (self.label is not None and name == "contact_frame"):
                out[name] = None if v is None else _num(v)
            r = self.ranges.get(name)
            if r is not None:
                out[_RANGE_NAMES[name]] = [_num(r[0]), _num(r[1])]
        if self.collider is not None:
            out["track"] = [[p.frame, _num(p.x), _num(p.y)] + ([] if p.width is None else [_num(p.width)])
                            for p in self.collider.track]
            for k, v in self.collider.extra.items():
                out.setdefault(k, v)
        if self.events:
            out["events"] = [dict(e) for e in self.events]
        for k, v in self.extra.items():
            out.setdefault(k, v)
        if self.object_level:
            out["objects"] = [o.to_dict() for o in self.objects]
        return out


#: Range keys of the clip-level format and the frame each bounds.
_RANGE_KEYS = {"contact_frame_range": "contact_frame", "danger_onset_range": "danger_onset_frame",
               "first_visible_range": "first_visible_frame"}
_RANGE_NAMES = {v: k for k, v in _RANGE_KEYS.items()}


class GroundTruth(Mapping):
    """Video key -> :class:`VideoTruth`, with :meth:`match` to find a video's truth."""

    def __init__(self, videos: Mapping[str, VideoTruth], source: str = "<dict>"):
        self._videos = dict(videos)
        self.source = source

    def __getitem__(self, key):
        return self._videos[key]

    def __iter__(self):
        return iter(self._videos)

    def __len__(self):
        return len(self._videos)

    def match(self, video) -> VideoTruth | None:
        """The truth of ``video`` (a path): the key that is the longest suffix of its path
        (``scenes/a.avi`` matches ``/data/paper/scenes/a.avi``), else the key with the same
        basename; ``None`` if none. Ambiguous basenames raise."""
        parts = PurePosixPath(str(video).replace("\\", "/")).parts
        best, best_len = None, 0
        for key in self._videos:
            kparts = tuple(p for p in PurePosixPath(key.replace("\\", "/")).parts if p not in (".", ""))
            if kparts and len(kparts) <= len(parts) and tuple(parts[-len(kparts):]) == kparts:
                if len(kparts) > best_len:
                    best, best_len = key, len(kparts)
        if best is not None:
            return self._videos[best]
        name = parts[-1] if parts else ""
        same = [k for k in self._videos if PurePosixPath(k.replace("\\", "/")).name == name]
        if len(same) > 1:
            raise InputValueError(f"{video}: ambiguous ground truth, several keys have its name: {', '.join(same)}")
        if same:
            return self._videos[same[0]]
        if len(self._videos) == 1:
            only = next(iter(self._videos.values()))
            if only.key == "*":
                return only
        return None

    def merged(self, other: "GroundTruth") -> "GroundTruth":
        """The videos of both (``other`` wins on a key both have)."""
        return GroundTruth({**self._videos, **dict(other)}, f"{self.source} + {other.source}")

    def to_dict(self) -> dict[str, Any]:
        """``{"videos": {key: entry}}`` (object level) and ``{"clips": {...}}`` (clip level)."""
        out: dict[str, Any] = {}
        for top, object_level in (("videos", True), ("clips", False)):
            entries = {k: v.to_dict() for k, v in self._videos.items() if v.object_level == object_level}
            if entries:
                out[top] = entries
        return out


# ---------------------------------------------------------------------------
# parsing
# ---------------------------------------------------------------------------
def _bad(where: str, message: str) -> InputValueError:
    return InputValueError(f"{where}: {message}")


def _num(value) -> float | int:
    """Integral floats as int (tidy JSON), others as float."""
    value = float(value)
    return int(value) if value.is_integer() else value


def _opt(value):
    """A track value: None, an int (frame) or a float, as it is."""
    return None if value is None else (int(value) if isinstance(value, int) else float(value))


def _int(value, where: str, minimum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)) \
            or not float(value).is_integer():
        raise _bad(where, f"expected an integer, got {value!r}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise _bad(where, f"expected an integer >= {minimum}, got {value}")
    return value


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
        raise _bad(where, f"expected a finite number, got {value!r}")
    return float(value)


def _opt_number(value, where: str) -> float | None:
    return None if value is None else _number(value, where)


def _interval(value, where: str) -> tuple[int, int]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _bad(where, f"expected an interval [start, end), got {value!r}")
    start, end = _int(value[0], where, 0), _int(value[1], where, 0)
    if end <= start:
        raise _bad(where, f"interval [start, end) must have end > start, got {list(value)}")
    return start, end


def _point(value, where: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _bad(where, f"expected [x, y], got {value!r}")
    return _number(value[0], where), _number(value[1], where)


def _track(raw, columns, where: str) -> tuple[TrackPoint, ...]:
    """Track rows ``[frame, x, y, ...]`` named by ``columns`` (a prefix of :data:`TRACK_COLUMNS`;
    default: as many as each row has)."""
    if columns is not None:
        if not isinstance(columns, (list, tuple)) or tuple(columns) != TRACK_COLUMNS[:len(columns)] \
                or len(columns) < 3:
            raise _bad(f"{where}_columns", f"expected a prefix of {list(TRACK_COLUMNS)} (at least frame, x, y), "
                                           f"got {columns!r}")
    if not isinstance(raw, (list, tuple)):
        raise _bad(where, "expected a list of [frame, x, y, ...]")
    points = []
    for k, row in enumerate(raw):
        n = len(columns) if columns is not None else (len(row) if isinstance(row, (list, tuple)) else 0)
        if not isinstance(row, (list, tuple)) or len(row) != n or not 3 <= n <= len(TRACK_COLUMNS):
            what = f"[{', '.join(columns)}]" if columns is not None else "[frame, x, y] (+ width, height, ttc_s, miss)"
            raise _bad(f"{where}[{k}]", f"expected {what}, got {row!r}")
        w = f"{where}[{k}]"
        vals = [_int(row[0], w, 0), _number(row[1], w), _number(row[2], w)]
        vals += [_opt_number(v, w) for v in row[3:]]
        if len(vals) > 3 and vals[3] is not None and vals[3] < 0:
            raise _bad(w, f"width must be >= 0, got {vals[3]}")
        points.append(TrackPoint(*vals))
    points.sort(key=lambda p: p.frame)
    if len({p.frame for p in points}) != len(points):
        raise _bad(where, "a frame appears twice")
    return tuple(points)


#: Keys of an object that the parser reads itself (the rest goes to ``ObjectTruth.extra``).
_OBJECT_KEYS = {"id", "kind", "interval", "center", "track", "track_columns", "polarity", "appearance",
                "contact_frame", "miss", "velocity", "sizes", *PHASES}


def parse_object(obj, where: str, index: int) -> ObjectTruth:
    """One object of a video entry (see the module docstring)."""
    if not isinstance(obj, Mapping):
        raise _bad(where, f"expected an object (JSON dict), got {type(obj).__name__}")
    oid = obj.get("id", index + 1)
    center = _point(obj["center"], f"{where}.center") if obj.get("center") is not None else None
    track = _track(obj["track"], obj.get("track_columns"), f"{where}.track") if obj.get("track") is not None else ()
    if obj.get("track") is not None and not track:
        raise _bad(f"{where}.track", "expected a non-empty list of [frame, x, y, ...]")
    phases = {p: _interval(obj[p], f"{where}.{p}") for p in PHASES if obj.get(p) is not None}
    kind = obj.get("kind")
    if kind is not None:
        if not isinstance(kind, str) or kind not in KINDS + tuple(LEGACY_KINDS):
            raise _bad(f"{where}.kind", f"expected one of {', '.join(KINDS + tuple(LEGACY_KINDS))}, got {kind!r}")
        # "approaching" / "receding" / "translating" (and "static" with an "interval") are the older
        # shorthand of one phase; "static" alone is the 3-D kind.
        if kind not in KINDS or obj.get("interval") is not None:
            phase = LEGACY_KINDS[kind]
            if obj.get("interval") is not None:
                phases.setdefault(phase, _interval(obj["interval"], f"{where}.interval"))
            elif phase not in phases:
                raise _bad(where, f"kind {kind!r} needs an 'interval' [start, end) or a {phase!r} interval")
            kind = None
    polarity = obj.get("polarity", obj.get("appearance"))
    if polarity is not None and polarity not in APPEARANCES:
        raise _bad(f"{where}.polarity", f"expected one of {', '.join(APPEARANCES)}, got {polarity!r}")
    if "approach" in phases and center is None and not track:
        raise _bad(where, "an approaching object needs a 'center' [x, y] or a 'track'")
    velocity = _point(obj["velocity"], f"{where}.velocity") if obj.get("velocity") is not None else None
    sizes = ()
    if obj.get("sizes") is not None:
        raw = obj["sizes"]
        if not isinstance(raw, (list, tuple)):
            raise _bad(f"{where}.sizes", f"expected a list of numbers (side per frame), got {raw!r}")
        sizes = tuple(_number(v, f"{where}.sizes") for v in raw)
    contact = _opt_number(obj.get("contact_frame"), f"{where}.contact_frame")
    miss = _opt_number(obj.get("miss"), f"{where}.miss")
    extra = {k: v for k, v in obj.items() if k not in _OBJECT_KEYS}
    if "appearance" in obj and "polarity" in obj:
        extra["appearance"] = obj["appearance"]
    return ObjectTruth(id=oid, kind=kind, center=center, track=track, polarity=polarity, velocity=velocity,
                       sizes=sizes, contact_frame=contact, miss=miss, extra=extra, **phases)


#: Keys of a video entry that the parser reads itself.
_ENTRY_KEYS = {"size", "frames", "fps", "objects", "label", "contact_frame", "collision_frame",
               "danger_onset_frame", "first_visible_frame", "track", "events", "camera", "background",
               *_RANGE_KEYS}


def parse_entry(key: str, entry, where: str) -> VideoTruth:
    """One video entry (object level, 3-D or clip level)."""
    if not isinstance(entry, Mapping):
        raise _bad(where, f"expected a JSON object, got {type(entry).__name__}")
    if "objects" not in entry and "label" not in entry:
        raise _bad(where, "a video entry needs 'objects' (object level) or 'label' (clip level)")
    size = None
    if entry.get("size") is not None:
        s = entry["size"]
        if not isinstance(s, (list, tuple)) or len(s) != 2:
            raise _bad(f"{where}.size", f"expected [W, H], got {s!r}")
        size = (_int(s[0], f"{where}.size", 1), _int(s[1], f"{where}.size", 1))
    frames = _int(entry["frames"], f"{where}.frames", 1) if entry.get("frames") is not None else None
    fps = None
    if entry.get("fps") is not None:
        fps = _number(entry["fps"], f"{where}.fps")
        if fps <= 0:
            raise _bad(f"{where}.fps", f"expected a positive number, got {fps}")
    objects = entry.get("objects", [])
    if not isinstance(objects, (list, tuple)):
        raise _bad(f"{where}.objects", f"expected a list, got {type(objects).__name__}")
    objs = tuple(parse_object(o, f"{where}.objects[{i}]", i) for i, o in enumerate(objects))
    label = entry.get("label")
    if label is not None and label not in LABELS:
        raise _bad(f"{where}.label", f"expected 'collision' or 'no_collision', got {label!r}")
    contact = entry.get("contact_frame")
    old = entry.get("collision_frame")
    if old is not None and contact is not None and old != contact:
        raise _bad(f"{where}.collision_frame", f"differs from contact_frame ({old!r} vs {contact!r}); give one")
    given = "contact_frame" if contact is not None else "collision_frame"
    contact = contact if contact is not None else old
    if contact is not None:
        if label != "collision":
            raise _bad(f"{where}.{given}", f"only a clip labelled 'collision' has a {given.replace('_', ' ')}")
        contact = _int(contact, f"{where}.{given}", 0)
    marks = {k: None if entry.get(k) is None else float(_int(entry[k], f"{where}.{k}", 0))
             for k in ("danger_onset_frame", "first_visible_frame")}
    ranges = {}
    for rk, fk in _RANGE_KEYS.items():
        if entry.get(rk) is not None:
            r = entry[rk]
            if not isinstance(r, (list, tuple)) or len(r) != 2:
                raise _bad(f"{where}.{rk}", f"expected [first, last], got {r!r}")
            a, b = _int(r[0], f"{where}.{rk}", 0), _int(r[1], f"{where}.{rk}", 0)
            if b < a:
                raise _bad(f"{where}.{rk}", f"expected first <= last, got {list(r)}")
            ranges[fk] = (a, b)
    collider = None
    if entry.get("track"):
        if label != "collision":
            raise _bad(f"{where}.track", "only a clip labelled 'collision' has the track of a colliding object")
        collider = ObjectTruth(id="collider", kind="collision", track=_track(entry["track"], None, f"{where}.track"),
                               contact_frame=None if contact is None else float(contact),
                               extra={k: entry[k] for k in ("object",) if k in entry})
    events = entry.get("events", [])
    if not isinstance(events, (list, tuple)) or not all(isinstance(e, Mapping) for e in events):
        raise _bad(f"{where}.events", "expected a list of objects")
    camera = entry.get("camera")
    if camera is not None and not isinstance(camera, Mapping):
        raise _bad(f"{where}.camera", f"expected an object, got {camera!r}")
    background = entry.get("background")
    if background is not None and not isinstance(background, str):
        raise _bad(f"{where}.background", f"expected a string, got {background!r}")
    extra = {k: v for k, v in entry.items() if k not in _ENTRY_KEYS and not (collider is not None and k == "object")}
    return VideoTruth(key=key, size=size, frames=frames, fps=fps, objects=objs, label=label,
                      contact_frame=None if contact is None else float(contact),
                      ranges=ranges, **marks,
                      collider=collider, events=tuple(dict(e) for e in events),
                      camera=None if camera is None else dict(camera), background=background, extra=extra)


def read_json(path):
    """The parsed content of the ground-truth (or other JSON) file ``path`` (one-line errors)."""
    path = Path(path)
    if path.is_dir():
        hint = " (did you mean its ground_truth.json?)" if (path / "ground_truth.json").is_file() else ""
        raise InputValueError(f"{path}: is a folder, not a ground truth JSON file{hint}")
    if not path.is_file():
        raise InputValueError(f"{path}: ground truth file not found")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputValueError(f"{path}: not valid JSON ({exc})") from None


def parse(data, source: str = "<dict>") -> GroundTruth:
    """A :class:`GroundTruth` from parsed JSON (see :func:`load`)."""
    if not isinstance(data, Mapping):
        raise InputValueError(f"{source}: ground truth must be a JSON object, got {type(data).__name__}")
    parsed: dict[str, VideoTruth] = {}
    tops = [top for top in ("videos", "clips") if top in data]
    for top in tops:
        videos = data[top]
        if not isinstance(videos, Mapping) or not videos:
            raise InputValueError(f"{source}: '{top}' must be a non-empty object {{name: entry}}")
        for k, v in videos.items():
            if str(k) in parsed:
                raise InputValueError(f"{source}: {k!r} is both in 'videos' and in 'clips'")
            parsed[str(k)] = parse_entry(str(k), v, f"{source}: {top}[{k!r}]")
    if not tops:
        key = str(data.get("video") or "*")
        parsed = {key: parse_entry(key, data, f"{source}: entry")}
    return GroundTruth(parsed, source)


def load(gt) -> GroundTruth:
    """Read ground truth: a path to a JSON file, the parsed JSON, or a :class:`GroundTruth`.

    Accepted: ``{"videos": {KEY: ENTRY}}`` (the paper's ``ground_truth.json``),
    ``{"clips": {KEY: ENTRY}}`` (clip labels, ``../shared/data/real/ground_truth.json``), both
    at once, or a single ``ENTRY`` (as written by ``mlplc2 stimulus``) whose key is its
    ``"video"`` field (matched by basename), else ``"*"`` (any video). Other top-level keys are
    ignored. A list of paths (or of parsed files) is read into one truth.
    """
    if isinstance(gt, GroundTruth):
        return gt
    if isinstance(gt, (list, tuple)):
        if not gt:
            raise InputValueError("no ground truth given")
        return functools.reduce(GroundTruth.merged, [load(g) for g in gt])
    if isinstance(gt, (str, Path)):
        return parse(read_json(gt), str(gt))
    return parse(gt)


def save(truth: GroundTruth | VideoTruth, path) -> Path:
    """Write ``truth`` as JSON to ``path`` (atomically: a file with its final name is complete)."""
    from .._files import write_json

    path = Path(path)
    write_json(path, truth.to_dict())
    return path
