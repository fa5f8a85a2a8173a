"""Where :func:`mlplc2.run` writes: the default output folder of a source
(:func:`default_out_dir`) and the folder made ready for a run (:func:`prepare_out_dir`,
:data:`RUN_OUTPUTS`)."""

from __future__ import annotations

from pathlib import Path

from .._validation import InputValueError
from ..io import FrameSource, is_camera
from ..io.formats import STDIN, is_url

__all__ = ["RUN_OUTPUTS", "default_out_dir", "is_the_input", "prepare_out_dir"]

#: The files a run writes into its output folder (all of them, whatever the options). :func:`run`
#: deletes those of an earlier run first, so that the folder never mixes two runs (e.g. an old
#: ``annotated.mp4`` beside new results).
RUN_OUTPUTS = ("responses.csv", "targets.csv", "fields.json", "responses.png", "annotated.mp4")


def is_the_input(source, path) -> bool:
    """Whether ``path`` is the input file ``source`` itself (an output that would overwrite it)."""
    try:
        return (isinstance(source, (str, Path)) and Path(source).is_file() and Path(path).exists()
                and Path(source).samefile(path))
    except (OSError, ValueError):
        return False


def default_out_dir(source) -> Path:
    """``<stem>_mlplc2/`` next to the input (camera N: ``./cameraN_mlplc2``; a URL:
    ``./<last part of its path or host>_mlplc2``; stdin: ``./stdin_mlplc2``)."""
    if isinstance(source, FrameSource):
        source = source.name
    if is_camera(source):
        return Path.cwd() / f"camera{int(source)}_mlplc2"
    if (isinstance(source, str) and source == STDIN) or is_url(source):
        rest = "" if source == STDIN else str(source).split("://", 1)[1].split("?")[0]
        netloc = rest.split("/", 1)[0]
        if "@" in netloc:                   # user:password@host: never in a folder's name
            rest = rest[netloc.rindex("@") + 1:]
        name = "stdin" if source == STDIN else Path(rest).stem
        return Path.cwd() / f"{''.join(c if c.isalnum() or c in '-_.' else '_' for c in name) or 'stream'}_mlplc2"
    p = Path(source)
    if p.is_dir():
        p = p.resolve()
        return p.parent / f"{p.name}_mlplc2"
    if any(ch in str(source) for ch in "*?[") and not p.exists():
        parent = p.parent
        while any(ch in str(parent) for ch in "*?["):
            parent = parent.parent
        parent = parent.resolve()
        return parent.parent / f"{parent.name}_mlplc2"
    return p.parent / f"{p.stem}_mlplc2"


def prepare_out_dir(source, src: FrameSource, out) -> Path:
    """The output folder, created, without the outputs of an earlier run (:data:`RUN_OUTPUTS`)."""
    out_dir = Path(out) if out is not None else default_out_dir(source)
    if src.kind == "images" and out_dir.is_dir() and isinstance(source, (str, Path)) \
            and Path(source).is_dir() and out_dir.resolve() == Path(source).resolve():
        raise InputValueError(f"{out_dir}: the output folder is the folder of input frames; "
                              f"choose another --out")
    if out_dir.exists() and not out_dir.is_dir():
        raise InputValueError(f"{out_dir}: is a file, expected a folder for the outputs")
    for p in (out_dir / name for name in RUN_OUTPUTS):   # the run would delete it first, then write over it
        if is_the_input(source, p):
            raise InputValueError(f"{source}: the input is {p.name} of the output folder {out_dir}, which the "
                                  f"run deletes and writes anew: choose another --out")
    out_dir.mkdir(parents=True, exist_ok=True)
    for p in (out_dir / name for name in RUN_OUTPUTS):  # an earlier run's: never mix two runs
        if p.is_file() or p.is_symlink():
            p.unlink()
    return out_dir
