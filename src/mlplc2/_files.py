"""Atomic file writes: the one place an output file is created.

Every output (CSV, JSON, PNG, video, Parquet) is written to a hidden temporary file in the
target folder (:func:`tempfile.mkstemp`, so two threads or processes writing one path never
share a temporary name) and moved into place with :func:`os.replace` once the write
succeeded; on failure the temporary file is deleted and the old output, if any, is kept.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from ._validation import InputValueError

__all__ = ["atomic_path", "temporary_path", "replace", "write_text", "write_json", "write_csv",
           "check_output_file"]

_UMASK: int | None = None
_UMASK_LOCK = threading.Lock()


def _file_mode() -> int:
    """0o666 less the process umask: the mode :func:`open` would have given a new file."""
    global _UMASK
    with _UMASK_LOCK:
        if _UMASK is None:
            _UMASK = os.umask(0)
            os.umask(_UMASK)
    return 0o666 & ~_UMASK


def temporary_path(path) -> Path:
    """A new, empty, hidden file next to ``path`` (same suffix, the usual file mode), for a
    writer that needs a file name; :func:`replace` moves it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(suffix=path.suffix, prefix=f".{path.stem}.partial-", dir=path.parent)
    os.close(fd)
    os.chmod(name, _file_mode())
    return Path(name)


def replace(tmp: Path, path: Path) -> None:
    """``os.replace(tmp, path)``; on failure delete ``tmp`` and raise an OSError that names
    ``path`` (not the hidden temporary name)."""
    try:
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None


@contextmanager
def atomic_path(path):
    """``with atomic_path('out/fields.json') as tmp: write(tmp)``: the final name appears
    only once the write succeeded; on an exception the temporary file is deleted."""
    tmp = temporary_path(path)
    try:
        yield tmp
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    replace(tmp, Path(path))


def write_text(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _numpy_default(obj):
    """NumPy scalars and arrays as JSON (their Python values)."""
    if hasattr(obj, "tolist"):          # numpy.generic, numpy.ndarray
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def write_json(path, data, *, indent: int | None = 1, end: str = "\n") -> None:
    """Write ``data`` as JSON (``indent`` as :func:`json.dumps`; NumPy values as their Python
    values; ``end`` after the last line) to ``path`` atomically."""
    write_text(path, json.dumps(data, indent=indent, default=_numpy_default) + end)


def write_csv(path, rows, columns, *, extrasaction: str = "raise") -> None:
    """Write ``rows`` (dicts) as CSV with header ``columns`` (``\\n`` line ends, UTF-8) to
    ``path`` atomically; ``extrasaction`` as :class:`csv.DictWriter`."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=list(columns), lineterminator="\n", extrasaction=extrasaction)
        w.writeheader()
        w.writerows(rows)


def check_output_file(path, *, what: str = "output") -> Path:
    """Return ``path`` as a Path, or raise if it names an existing directory."""
    path = Path(path)
    if path.is_dir():
        raise InputValueError(f"{path}: is a directory, expected a file name for the {what}")
    return path
