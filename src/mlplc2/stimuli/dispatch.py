"""The stimuli by name (the CLI's ``mlplc2 stimulus NAME``): :data:`NAMES`, each name's options
(:func:`parameters`), :func:`generate` and :func:`write` (a video and its ground-truth JSON).

The names are the six basic stimuli of Sec. IV-A (:func:`mlplc2.stimuli.paper.basic`), the
scenes of Sec. IV-B (``four_phase``, ``six_objects``), a physical ``looming`` approach
(:mod:`mlplc2.stimuli.paper`) and the 3-D ``approach`` scenes
(:func:`mlplc2.stimuli.world.approach_scene`, docs/stimuli.md).
"""

from __future__ import annotations

import inspect
import typing
from pathlib import Path
from typing import Any, Callable

from .._validation import InputValueError
from ._common import Stimulus
from .paper import BASIC_NAMES, basic, four_phase, looming, six_objects
from .world import approach_scene

__all__ = ["NAMES", "GENERATORS", "parameters", "generate", "write"]

#: Every name :func:`generate` accepts.
NAMES: tuple[str, ...] = BASIC_NAMES + ("four_phase", "six_objects", "looming", "approach")


def _basic_factory(name: str) -> Callable[..., Stimulus]:
    def make(*, size: int = 100, frames: int = 50, fps: float = 30.0) -> Stimulus:
        return basic(name, size=size, frames=frames, fps=fps)
    make.__name__ = name
    return make


#: The generator of each name of :data:`NAMES` (``mlplc2 stimulus NAME``).
GENERATORS: dict[str, Callable[..., Stimulus]] = {name: _basic_factory(name) for name in BASIC_NAMES}
GENERATORS.update(four_phase=four_phase, six_objects=six_objects, looming=looming, approach=approach_scene)


def parameters(name: str) -> dict[str, inspect.Parameter]:
    """The keyword options of stimulus ``name``: its generator's parameters (from
    ``inspect.signature``, annotations resolved to types where they can be), in order.

    ``mlplc2 stimulus`` builds its ``--option`` list from these (docs/cli.md), so a
    generator added to ``GENERATORS`` gets its command-line options without CLI code.
    """
    if name not in GENERATORS:
        raise InputValueError(f"unknown stimulus {name!r}; valid names: {', '.join(NAMES)}")
    func = GENERATORS[name]
    try:
        hints = typing.get_type_hints(func)
    except Exception:  # noqa: BLE001 - an annotation that does not resolve stays as written
        hints = {}
    return {p.name: p.replace(annotation=hints.get(p.name, p.annotation))
            for p in inspect.signature(func).parameters.values()
            if p.kind not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)}


def generate(name: str, **options: Any) -> Stimulus:
    """Generate the stimulus ``name`` (one of :data:`NAMES`) with keyword ``options``.

    Parameters
    ----------
    name : str
        Stimulus name; see :data:`NAMES`.
    **options
        Keyword arguments of the generator: :func:`basic` (``size``,
        ``frames``, ``fps``) for the six basic stimuli, else those of
        :func:`four_phase`, :func:`six_objects`, :func:`looming` or, for
        ``"approach"``, :func:`approach_scene` (:func:`parameters` lists them).

    Returns
    -------
    Stimulus

    Raises
    ------
    mlplc2._validation.InputValueError
        Unknown name, unknown option or invalid option value.
    """
    valid = list(parameters(name))
    unknown = [k for k in options if k not in valid]
    if unknown:
        flags = ", ".join("--" + k.replace("_", "-") for k in valid)
        raise InputValueError(f"unknown option(s) {', '.join(map(repr, unknown))} for stimulus {name!r}; "
                              f"valid options: {', '.join(valid) or 'none'} (command line: {flags or 'none'}; "
                              f"see 'mlplc2 stimulus --help')")
    return GENERATORS[name](**options)


def write(name: str, out, *, gt=None, **options) -> tuple[Path, Path]:
    """Generate stimulus ``name`` (:func:`generate`) and write it (``mlplc2 stimulus``).

    Writes the video to ``out`` (``.mp4`` H.264, or ``.avi`` MJPG) and its
    ground truth to ``gt`` (default: ``<out stem>_gt.json`` beside it).
    ``options`` go to the generator (e.g. ``seed``, ``background``).
    Returns ``(video_path, gt_path)``.
    """
    from .._files import check_output_file, write_json
    from ..io import check_video_output, write_video

    out = check_video_output(out)
    gt_path = check_output_file(gt if gt is not None else out.with_name(f"{out.stem}_gt.json"),
                                what="ground truth")
    if gt_path.resolve() == out.resolve():
        raise InputValueError(f"the video and its ground truth would both be written to {out}")
    stim = generate(name, **options)
    gt_path.parent.mkdir(parents=True, exist_ok=True)
    write_video(out, stim.frames, stim.fps, stim.size)
    write_json(gt_path, {"name": name, "video": out.name, **stim.to_ground_truth()})
    return out, gt_path
