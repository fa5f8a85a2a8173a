"""The contract every model honours, as checks anyone can run on a model of their own.

In the spirit of scikit-learn's and river's ``check_estimator``: :func:`check_model` yields the
checks (zero-argument callables named ``check_...``; each raises :class:`AssertionError` with a
one-line message when the model breaks the contract), so a test suite can parametrise over them;
:func:`run_checks` runs them all and names the first that fails. The checks make their own frames
(a dark square looming on a blurred texture, 64x48 RGB), so a model needs no data. The test suite
runs them on every registered model (``tests/test_testing.py``); ``docs/testing.md`` shows a model
written from scratch and checked. Plain Python: pytest is not needed.

Examples
--------
>>> import mlplc2
>>> from mlplc2.testing import check_model, run_checks
>>> [check.__name__ for check in check_model(mlplc2.LGMD1)][:3]
['check_outputs', 'check_run_equals_step', 'check_reset']
>>> len(run_checks(lambda: mlplc2.LGMD1(fps=30.0)))
13
"""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle
import re
import warnings
from collections.abc import Callable, Iterator

import cv2
import numpy as np

from ._validation import InputError, InputTypeError, InputWarning
from .neuropils.attention import Field
from .models.base import Model, Output

__all__ = ["check_model", "run_checks", "looming_frames", "CHECKS", "BAD_FRAMES"]

H, W = 48, 64     # size of the checks' frames
N = 24            # frames of the looming square

#: Frames every model rejects with an :class:`~mlplc2.InputError` (``Model.step``).
BAD_FRAMES = {
    "nan": lambda: np.full((H, W), np.nan),
    "inf": lambda: np.where(np.eye(H, W, dtype=bool), np.inf, 100.0),
    "bool": lambda: np.ones((H, W), bool),
    "object": lambda: np.zeros((H, W), object),
    "ndim1": lambda: np.zeros(H * W, np.uint8),
    "channels2": lambda: np.zeros((H, W, 2), np.uint8),
    "too_small": lambda: np.zeros((2, 2), np.uint8),
}
BAD_FPS = (0, -30, float("nan"), float("inf"), "fast", None, True, "30")


def looming_frames(n: int = N, h: int = H, w: int = W, seed: int = 0) -> list[np.ndarray]:
    """A dark square growing by 2 px a frame on a blurred random texture (RGB uint8, unequal
    channels so that the luma weights matter)."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 3)
    bg = cv2.normalize(bg, None, 120, 220, cv2.NORM_MINMAX).astype(np.uint8)
    frames = []
    for i in range(n):
        f = bg.copy()
        side = 2 * i + 2
        y0, x0 = max(h // 2 - side // 2, 0), max(w // 2 - side // 2, 0)
        f[y0:y0 + side, x0:x0 + side] = 10
        frames.append(np.stack([f, f - f // 8, f // 2 + 100], axis=-1))
    return frames


# -- helpers -------------------------------------------------------------------------------------
def _expect(condition, message: str) -> None:
    """``assert`` that survives ``python -O``."""
    if not condition:
        raise AssertionError(message)


def _raises(kind, call, match: str | None = None) -> BaseException:
    """The exception of type ``kind`` that ``call()`` raises (its message searched for ``match``)."""
    try:
        call()
    except kind as e:
        _expect(match is None or re.search(match, str(e)), f"{type(e).__name__} {str(e)!r} does not match {match!r}")
        return e
    raise AssertionError(f"did not raise {kind.__name__}" + (f" matching {match!r}" if match else ""))


def _outputs(model: Model, frames) -> list[Output]:
    return [model.step(f) for f in frames]


def _same_outputs(a: list[Output], b: list[Output], what: str) -> None:
    """Bit-identical outputs (floats compared with ==, the response also bit for bit)."""
    _expect(len(a) == len(b), f"{what}: {len(a)} outputs against {len(b)}")
    for i, (oa, ob) in enumerate(zip(a, b)):
        if oa != ob:
            raise AssertionError(f"{what}: frame {i} differs: {oa} != {ob}")
        if np.float64(oa.response).tobytes() != np.float64(ob.response).tobytes():
            raise AssertionError(f"{what}: frame {i}: response {oa.response!r} is not bit-identical to {ob.response!r}")


def _same_state(a, b) -> bool:
    """Arrays bit for bit (shape and dtype too), dataclasses, dicts and sequences item by item, the rest by ==."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
    if dataclasses.is_dataclass(a) and not isinstance(a, type) and type(a) is type(b):
        return all(_same_state(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same_state(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same_state(x, y) for x, y in zip(a, b))
    return bool(a == b)


# -- the checks ----------------------------------------------------------------------------------
def check_outputs(make, frames, *, responds=True, **_):
    """Every step returns an :class:`~mlplc2.Output`: its frame index counted, a finite float
    response, bool alarm and spike, a tuple of :class:`~mlplc2.Field` and of targets sorted by
    urgency (``most_urgent`` the first, ``warning`` any target's); ``responds``: the looming
    square moves the response and raises the alarm at least once."""
    model = make()
    _expect(model.frame_index == 0, f"a new model's frame_index is {model.frame_index}, not 0")
    outs = []
    for i, f in enumerate(frames):
        out = model.step(f)
        _expect(isinstance(out, Output), f"step() returned {type(out).__name__}, not mlplc2.Output")
        _expect(out.frame == i and model.frame_index == i + 1,
                f"frame {i}: Output.frame {out.frame}, frame_index {model.frame_index}")
        _expect(isinstance(out.response, float) and math.isfinite(out.response),
                f"frame {i}: response {out.response!r} is not a finite float")
        _expect(isinstance(out.collision, bool) and isinstance(out.spike, bool),
                f"frame {i}: collision {out.collision!r} and spike {out.spike!r} must be bool")
        _expect(isinstance(out.fields, tuple) and all(isinstance(fl, Field) for fl in out.fields),
                f"frame {i}: fields must be a tuple of mlplc2.Field")
        _expect(isinstance(out.targets, tuple), f"frame {i}: targets must be a tuple")
        _expect(out.most_urgent is (out.targets[0] if out.targets else None),
                f"frame {i}: most_urgent is not the first target")
        _expect(list(out.targets) == sorted(out.targets, key=lambda t: t.urgency()),
                f"frame {i}: targets are not sorted by urgency (warnings first, then the shortest ttc_s)")
        _expect(out.warning == any(t.warning for t in out.targets), f"frame {i}: warning is not any target's")
        outs.append(out)
    if responds:
        _expect(max(o.response for o in outs) > min(o.response for o in outs),
                "the response does not change while the square looms")
        _expect(any(o.collision for o in outs), "no collision alarm while the square looms")
    _expect(repr(model).startswith(f"{type(model).__name__}(fps={model.fps:g}"),
            f"repr {model!r} does not start with {type(model).__name__}(fps={model.fps:g}")


def check_run_equals_step(make, frames, **_):
    """``run(frames)`` (batch) yields lazily what ``step`` gives frame by frame (streaming)."""
    model = make()
    outs = _outputs(model, frames)
    model.reset()
    gen = model.run(iter(frames))
    _expect(model.frame_index == 0, "run() consumed frames before it was iterated")
    _same_outputs(list(gen), outs, "run() against step()")


def check_reset(make, frames, **_):
    """``reset()`` restores the initial state: the same outputs again (field ids from 1 again), and
    a model reset mid-run answers like a new one."""
    model = make()
    first = _outputs(model, frames)
    model.reset()
    _expect(model.frame_index == 0, f"frame_index is {model.frame_index} after reset(), not 0")
    second = _outputs(model, frames)
    _same_outputs(first, second, "after reset()")
    if any(o.fields for o in first):
        ids = sorted({fl.id for o in second for fl in o.fields})
        _expect(ids[0] == 1, f"field ids start at {ids[0]} after reset(), not 1")
    model = make()
    _outputs(model, looming_frames(seed=5)[: N // 2])
    model.reset()
    _same_outputs(_outputs(model, frames), _outputs(make(), frames), "reset mid-run against a new model")


def check_deterministic(make, frames, *, state_attrs=("maps", "state"), **_):
    """Two models answer bit-identically, and so do their inspection attributes (``state_attrs``
    present on the model, compared after every frame)."""
    a, b = make(), make()
    for i, f in enumerate(frames):
        _same_outputs([a.step(f)], [b.step(f)], f"two models, frame {i}")
        for attr in state_attrs:
            if hasattr(a, attr):
                _expect(_same_state(getattr(a, attr), getattr(b, attr)), f"two models, frame {i}: {attr} differs")


def check_pickle(make, frames, **_):
    """A model pickled or deep-copied mid-run goes on exactly like the original, independently of
    it; a new model pickled answers like a new one."""
    for how, clone_of in (("pickle", lambda m: pickle.loads(pickle.dumps(m))), ("deepcopy", copy.deepcopy)):
        model = make()
        _outputs(model, frames[:10])
        clone = clone_of(model)
        _expect(type(clone) is type(model) and clone.fps == model.fps and clone.frame_index == 10,
                f"{how}: the copy is {clone!r} at frame {clone.frame_index}, not {model!r} at frame 10")
        rest = _outputs(clone, frames[10:])
        _expect(model.frame_index == 10, f"{how}: stepping the copy stepped the original")
        _same_outputs(rest, _outputs(model, frames[10:]), f"{how}: the copy against the original")
    clone = pickle.loads(pickle.dumps(make()))
    _same_outputs(_outputs(clone, frames[:6]), _outputs(make(), frames[:6]), "a new model pickled")


def check_construction(make, frames, **_):
    """``type(model)(fps=...)`` rejects a bad fps (one-line :class:`~mlplc2.InputError`). A model with
    ``params``: they are a frozen, hashable dataclass that a run leaves alone (their ``replace``
    rejects an unknown name), and ``params`` of another type is a ``TypeError``."""
    cls = type(make())
    for fps in BAD_FPS:
        _raises(InputError, lambda: cls(fps=fps), "fps must be")
    model = make()
    params = model.params
    if params is None:
        return
    _expect(dataclasses.is_dataclass(params), f"params {type(params).__name__} is not a dataclass")
    before = dataclasses.asdict(params)
    field0 = dataclasses.fields(params)[0].name
    _raises(dataclasses.FrozenInstanceError, lambda: setattr(params, field0, getattr(params, field0)))
    hash(params)   # frozen and hashable: safe to share between models
    _outputs(model, frames)
    _expect(dataclasses.asdict(model.params) == before, "a run changed the model's params")
    _expect(make().params == params, "a run changed the default params")
    if hasattr(params, "replace"):
        _raises(ValueError, lambda: params.replace(no_such_parameter=1), "unknown parameter")
    _raises(TypeError, lambda: cls(params={"t_a": 1.0}), "params must be")


def check_input_not_modified(make, frames, **_):
    """``step`` never modifies its frame (values, writeable flag, layout), a float frame out of range
    either."""
    model = make()
    for i, f in enumerate(frames):
        g = f.copy()
        flags = (f.flags.writeable, f.flags.c_contiguous)
        model.step(f)
        _expect(np.array_equal(f, g) and (f.flags.writeable, f.flags.c_contiguous) == flags,
                f"step() modified frame {i}")
    f = frames[3].astype(np.float64) * 1.5 - 20   # out of range on both sides: clipped in a copy
    g = f.copy()
    model.step(f)
    _expect(np.array_equal(f, g), "step() modified a float frame")


def check_memory_layouts(make, frames, **_):
    """Read-only, non-contiguous, Fortran-ordered and negative-stride frames answer like C-ordered ones."""
    ref = _outputs(make(), frames[:12])
    views = []
    for f in frames[:12]:
        big = np.zeros((H * 2, W * 2, 3), np.uint8)
        big[::2, ::2] = f
        v = big[::2, ::2]                       # non-contiguous view
        _expect(not v.flags.c_contiguous, "the view is contiguous")
        v.flags.writeable = False
        views.append(v)
    _same_outputs(_outputs(make(), views), ref, "read-only non-contiguous frames")
    _same_outputs(_outputs(make(), [np.asfortranarray(f) for f in frames[:12]]), ref, "Fortran-ordered frames")
    flipped = [np.ascontiguousarray(f[::-1, ::-1])[::-1, ::-1] for f in frames[:12]]
    _same_outputs(_outputs(make(), flipped), ref, "negative-stride frames")


def check_channels(make, frames, **_):
    """RGBA answers like RGB (alpha ignored), (H, W, 1) like (H, W), and equal RGB channels like
    that grey level (response within 1e-4 relative or 1e-6 absolute)."""
    rng = np.random.default_rng(1)
    ref = _outputs(make(), frames[:12])
    rgba = [np.concatenate([f, rng.integers(0, 256, (H, W, 1), dtype=np.uint8)], axis=-1) for f in frames[:12]]
    _same_outputs(_outputs(make(), rgba), ref, "RGBA against RGB")
    grey = [f[:, :, 0] for f in frames[:12]]
    _same_outputs(_outputs(make(), [g[:, :, None] for g in grey]), _outputs(make(), grey), "(H, W, 1) against (H, W)")
    a = _outputs(make(), [np.repeat(g[:, :, None], 3, axis=2) for g in grey])
    b = _outputs(make(), grey)
    for i, (oa, ob) in enumerate(zip(a, b)):
        _expect(abs(oa.response - ob.response) <= max(1e-4 * abs(ob.response), 1e-6),
                f"frame {i}: grey RGB response {oa.response!r} against grey {ob.response!r}")


def check_bad_input(make, frames, **_):
    """Bad frames (2 or 5 channels, NaN, inf, bool, object, 1-D, too small) raise a one-line
    :class:`~mlplc2.InputError` and leave no trace: the run goes on as without them, and a
    rejected first frame fixes no size."""
    for channels in (2, 5):
        model = make()
        e = _raises(InputError, lambda: model.step(np.zeros((H, W, channels), np.uint8)),
                    f"must have 1, 3 \\(RGB\\) or 4 \\(RGBA\\) channels, got {channels}")
        _expect(isinstance(e, ValueError), f"{channels} channels: {type(e).__name__} is not a ValueError")
        _expect(model.frame_index == 0, f"{channels} channels: a rejected frame was counted")
    for bad, frame in BAD_FRAMES.items():
        model, ref = make(), make()
        for f in frames[:8]:
            model.step(f)
            ref.step(f)
        e = _raises(InputError, lambda: model.step(frame()))
        _expect("\n" not in str(e), f"{bad}: the message is not one line")
        _expect(model.frame_index == 8, f"{bad}: a rejected frame was counted")
        _same_outputs(_outputs(model, frames[8:]), _outputs(ref, frames[8:]), f"{bad}: after a rejected frame")
        first = make()
        _raises(InputError, lambda: first.step(frame()))
        first.step(np.zeros((20, 30), np.uint8))
        _expect(first.frame_index == 1, f"{bad}: a rejected first frame was counted")


def check_frame_size(make, frames, **_):
    """A frame of another size raises a one-line :class:`~mlplc2.InputError` naming both sizes,
    the frame and ``reset()``, and leaves no trace; after ``reset()`` a new size is fine (fields inside it)."""
    model, ref = make(), make()
    for f in frames[:5]:
        model.step(f)
        ref.step(f)
    e = _raises(InputError, lambda: model.step(np.zeros((H + 2, W - 4, 3), np.uint8)))
    msg = str(e)
    _expect(isinstance(e, ValueError) and "\n" not in msg, f"{msg!r} is not a one-line ValueError")
    _expect(f"{W - 4}x{H + 2}" in msg and f"{W}x{H}" in msg and "reset()" in msg and "frame 5" in msg,
            f"{msg!r} does not name both sizes, the frame and reset()")
    _expect(model.frame_index == 5, "a rejected frame was counted")
    _same_outputs(_outputs(model, frames[5:]), _outputs(ref, frames[5:]), "after a frame of another size")
    model.reset()
    small = [f[: H // 2, : W // 2] for f in frames]
    _same_outputs(_outputs(model, small), _outputs(make(), small), "a new size after reset()")
    for o in _outputs(make(), small):
        for fl in o.fields:
            _expect(0 <= fl.x < W // 2 and 0 <= fl.y < H // 2, f"field {fl} outside the {W // 2}x{H // 2} frame")


def check_minimum_size(make, frames, **_):
    """Frames of ``min_size`` pixels a side give finite outputs (fields inside); smaller ones raise
    a :class:`~mlplc2.InputError` naming the minimum and the size."""
    n = type(make()).min_size
    rng = np.random.default_rng(0)
    for shape in [(n, n), (n, 40), (40, n)]:
        model = make()
        for i in range(12):
            frame = rng.integers(0, 256, shape, dtype=np.uint8) if i % 3 else np.zeros(shape, np.uint8)
            out = model.step(frame)
            _expect(math.isfinite(out.response), f"{shape}: response {out.response!r} is not finite")
            for fl in out.fields:
                _expect(0 <= fl.x < shape[1] and 0 <= fl.y < shape[0], f"{shape}: field {fl} outside the frame")
    for shape in [(n - 1, 40), (40, n - 1), (1, 1), (0, 10)]:
        e = _raises(InputError, lambda: make().step(np.zeros(shape, np.uint8)), f"needs at least {n}x{n}")
        _expect(isinstance(e, ValueError), f"{shape}: {type(e).__name__} is not a ValueError")
        _expect(f"is {shape[1]}x{shape[0]} pixels" in str(e), f"{shape}: {str(e)!r} does not name the size")


def check_unit_scale_warning(make, frames, **_):
    """A float frame on a 0-1 scale warns (:class:`~mlplc2.InputWarning`) once per model; black
    float, 0-255 float and integer frames do not."""
    model = make()
    frame = np.random.default_rng(0).random((60, 80)).astype(np.float32)   # a 0-1 image
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model.step(frame)
    _expect(any(issubclass(w.category, InputWarning) and "0-255" in str(w.message) for w in caught),
            "a 0-1 float frame did not warn (mlplc2.InputWarning)")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.step(frame)                                           # once per model
        fresh = make()
        fresh.step(np.zeros((60, 80), np.float32))                  # black: no warning
        fresh.step(frame * 255)                                     # 0-255 floats: none
        fresh.step((frame * 255).astype(np.uint8) // 255)           # integers: none


CHECKS = (check_outputs, check_run_equals_step, check_reset, check_deterministic, check_pickle,
          check_construction, check_input_not_modified, check_memory_layouts, check_channels,
          check_bad_input, check_frame_size, check_minimum_size, check_unit_scale_warning)


def check_model(model_factory: Callable[[], Model], *, responds: bool = True,
                state_attrs: tuple[str, ...] = ("maps", "state")) -> Iterator[Callable[[], None]]:
    """Yield the checks every model must pass, as zero-argument callables named ``check_...``.

    Parameters
    ----------
    model_factory : callable
        Returns a new model at each call, e.g. ``lambda: MLPLC2(fps=30)`` or a model class.
        ``type(model)(fps=...)`` must build one too (the bad-fps check).
    responds : bool
        The looming square must change the response and raise ``Output.collision`` at least
        once (``check_outputs``). False for a model that is not meant to answer it.
    state_attrs : tuple of str
        Attributes compared between two models after every frame (``check_deterministic``),
        where the model has them: arrays bit for bit, dataclasses and dicts item by item.

    Each check raises :class:`AssertionError` (one line) when the model breaks the contract:
    see each ``mlplc2.testing.check_*`` function's docstring. Run them all with :func:`run_checks`.
    """
    if not callable(model_factory):
        raise InputTypeError(f"model_factory must be a callable returning a new model, got {type(model_factory).__name__}")
    first, second = model_factory(), model_factory()
    if not isinstance(first, Model):
        raise InputTypeError(f"model_factory must return an mlplc2.models.Model, got {type(first).__name__}")
    if first is second:
        raise InputTypeError("model_factory must return a new model at each call, got the same one twice")
    frames = looming_frames()
    options = {"responds": responds, "state_attrs": tuple(state_attrs)}
    for fn in CHECKS:
        def check(fn=fn):
            fn(model_factory, frames, **options)

        check.__name__ = check.__qualname__ = fn.__name__
        check.__doc__ = fn.__doc__
        yield check


def run_checks(model_factory: Callable[[], Model], **options) -> list[str]:
    """Run every check of :func:`check_model` (same arguments); return their names, or raise
    :class:`AssertionError` naming the first failing check and why."""
    names = []
    for check in check_model(model_factory, **options):
        try:
            check()
        except Exception as e:
            raise AssertionError(f"{check.__name__} failed: {type(e).__name__}: {e}") from e
        names.append(check.__name__)
    return names
