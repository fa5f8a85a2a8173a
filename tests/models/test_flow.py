"""The optical-flow baseline (``flow``, :mod:`mlplc2.models.flow`): time to contact, no
warning for what does not approach, the course of a pass-by, the camera's motion and the
tracker shared with the LPLC2 family, the stage functions, pickling and reset, and its
documentation.

The generic per-frame contract is in ``tests/test_testing.py`` (every registered model)."""

from __future__ import annotations

import doctest
import math
import pickle
from pathlib import Path

import cv2
import numpy as np
import pytest

import mlplc2
import mlplc2.models.flow as flow_module
from mlplc2.models.flow import FlowParams, FlowTTC, divergence, object_flow, regions
from mlplc2.stimuli import ApproachObject, approach
from mlplc2.targets import TargetParams, pyramid

DOCS = Path(__file__).resolve().parents[2] / "docs"


def _run(stim, model=None):
    model = FlowTTC(fps=stim.fps) if model is None else model
    return model, [model.step(f) for f in stim.frames]


def _on(out, row):
    """The targets of ``out`` whose centre lies on the object of truth row ``row``."""
    _, x, y, w, h, _, _ = row
    return [t for t in out.targets if abs(t.x - x) <= max(w / 2, 4) and abs(t.y - y) <= max(h / 2, 4)]


def _ttc_errors(stim, outs, lo=1.0, hi=3.0):
    """Relative errors of the estimates on object 1 in the frames whose true TTC is in [lo, hi)."""
    errs = []
    for row in stim.objects[0].track:
        frame, ttc = row[0], row[5]
        if ttc is None or not lo <= ttc < hi:
            continue
        est = [t.ttc_s for t in _on(outs[frame], row) if t.ttc_s is not None]
        if est:
            errs.append(abs(est[0] - ttc) / ttc)
    return errs


# -- time to contact -------------------------------------------------------------------
@pytest.mark.parametrize("appearance, noise", [("dark", 0.0), ("textured", 2.0)])
def test_ttc_within_15_percent_on_a_plain_background(appearance, noise):
    """A constant-speed approach on a plain background, true TTC 3.2 s down to 0.9 s: the
    median relative error over the frames of the 1-3 s bin is below 15 %, in most of them."""
    obj = ApproachObject.collision(ttc_s=3.2, at=(150, 110), width_px=8.0, speed_mps=4.0, appearance=appearance)
    stim = approach([obj], background="plain", duration_s=2.3, noise_std=noise, seed=1)
    _, outs = _run(stim)
    errs = _ttc_errors(stim, outs)
    in_bin = sum(1 for r in stim.objects[0].track if r[5] is not None and 1.0 <= r[5] < 3.0)
    assert len(errs) >= 0.6 * in_bin, (len(errs), in_bin)
    assert np.median(errs) < 0.15, np.median(errs)


def test_a_collision_on_a_textured_background_warns_in_time():
    """The still background around the object is left out of its expansion: the estimate is
    not pulled towards zero, and the warning comes before the horizon has half passed."""
    obj = ApproachObject.collision(ttc_s=2.5, at=(170, 100), width_px=10.0, speed_mps=4.0, appearance="dark")
    stim = approach([obj], background="texture", duration_s=2.4, seed=2)
    _, outs = _run(stim)
    assert np.median(_ttc_errors(stim, outs, 0.5, 3.0)) < 0.2
    first = next(r for r in stim.objects[0].track if any(t.warning for t in _on(outs[r[0]], r)))
    assert first[5] >= 0.5                     # true TTC at the first warning (horizon 1 s)


@pytest.mark.parametrize("background", ["plain", "texture"])
def test_one_object_is_one_target(background):
    """The regions of an approaching object are claimed by its target: one id follows it from
    its detection to its contact (the frames where it still fits in the view)."""
    obj = ApproachObject.collision(ttc_s=2.5, at=(150, 110), width_px=8.0, speed_mps=4.0, appearance="dark")
    stim = approach([obj], background=background, duration_s=2.4, noise_std=2.0, seed=9)
    _, outs = _run(stim)
    ids = {t.id for r in stim.objects[0].track if r[3] <= 240 for t in _on(outs[r[0]], r)}
    assert len(ids) == 1, ids


# -- what does not approach --------------------------------------------------------------
@pytest.mark.parametrize("kind", ["receding", "static"])
def test_receding_and_static_objects_give_no_warning(kind):
    make = ApproachObject.receding if kind == "receding" else ApproachObject.static
    obj = make(at=(160, 120), distance_m=3.0, width_px=40.0, appearance="dark")
    stim = approach([obj], background="texture", frames=60, noise_std=2.0, seed=3)
    _, outs = _run(stim)
    assert not any(o.warning or o.collision for o in outs)
    assert not any(t.ttc_s is not None for o in outs for t in o.targets)


def test_a_pass_by_gives_no_warning_and_misses_by_more_than_a_width():
    obj = ApproachObject.pass_by(ttc_s=2.5, miss_widths=3.0, side="right", at=(150, 120), width_px=10.0,
                                 speed_mps=4.0, appearance="dark")
    stim = approach([obj], background="texture", duration_s=2.2, seed=4)
    _, outs = _run(stim)
    assert not any(o.warning for o in outs)
    misses = [t.miss for r in stim.objects[0].track for t in _on(outs[r[0]], r) if t.miss is not None]
    assert len(misses) >= 10
    assert np.median(misses) > 1.0, np.median(misses)


# -- the camera's own motion and the tracker: the LPLC2 family's ----------------------------
def test_the_heading_of_forward_ego_motion_is_near_the_principal_point():
    """The camera's motion is mlplc2.camera.MotionEstimator's (one estimate for every model;
    measured (151.3, 120.5) for (159.5, 119.5): the estimator works on a 160-px frame)."""
    stim = approach([], background="ground", camera="forward", camera_speed=3.0, frames=12, seed=5)
    model, _ = _run(stim)
    m = model.camera_motion
    assert isinstance(m, mlplc2.camera.CameraMotion) and m.heading is not None
    cx, cy = (320 - 1) / 2.0, (240 - 1) / 2.0
    assert math.hypot(m.heading[0] - cx, m.heading[1] - cy) < 12.0, m.heading


def test_a_pan_is_a_rotation_and_the_background_no_target():
    stim = approach([], background="texture", camera="pan", camera_speed=20.0, frames=8, seed=6)
    model, outs = _run(stim)
    assert abs(model.camera_motion.omega[1]) > 1e-3          # a pan: about the camera's y axis
    assert not any(o.targets for o in outs)                  # the background does not become a target


def test_the_tracker_is_the_target_layer_s():
    """The targets come from mlplc2.targets.TargetLayer, which obeys TargetParams' bound on
    simultaneous targets (0: none at all; the first version kept its own bound in FlowParams)."""
    stim = _looming()
    _, outs = _run(stim, FlowTTC(fps=stim.fps, target_params=TargetParams(max_targets=0)))
    assert not any(o.targets for o in outs)
    _, outs = _run(stim)
    assert any(o.targets for o in outs)


def test_a_pan_does_not_bend_the_course():
    """The camera's turn is taken out of the course: a collision seen from a panning camera
    slides across the image but is predicted to hit (miss within max_miss) and warns."""
    obj = ApproachObject.collision(ttc_s=2.5, at=(200, 120), width_px=10.0, speed_mps=4.0, appearance="dark")
    stim = approach([obj], background="texture", camera="pan", camera_speed=15.0, duration_s=2.4, seed=7)
    _, outs = _run(stim)
    late = [t for r in stim.objects[0].track if r[5] is not None and 0.3 <= r[5] < 1.0
            for t in _on(outs[r[0]], r) if t.miss is not None]
    assert late and np.median([t.miss for t in late]) <= 1.0
    assert any(t.warning for t in late)


# -- stage functions -------------------------------------------------------------------------
@pytest.mark.parametrize("background", ["plain", "texture"])
@pytest.mark.parametrize("width", [12.0, 20.0])
def test_object_flow_measures_a_small_disc_s_expansion(background, width):
    """Two frames of a dark disc 12 or 20 px wide growing 2.2 %: the patch's fit (the layer's
    growth evidence) finds kx and ky within 15 % of it, on a uniform background (only the edge
    has flow: the normal flow) and on a textured still one (left out by the layers), and the
    object's layer gives its box."""
    obj = ApproachObject.collision(ttc_s=1.5, at=(80.3, 60.6), width_px=width, speed_mps=4.0, appearance="dark",
                                   size=(160, 120))
    stim = approach([obj], size=(160, 120), background=background, frames=2, seed=0)
    (_, x, y, w0, _, _, _), (_, _, _, w1, _, _, _) = stim.objects[0].track[:2]
    k = math.log(w1 / w0)
    a, b = (pyramid(f.astype(np.float32)) for f in stim.frames)
    of = object_flow(a, b, x, y, 1.5 * w0 / 2 + 3.0)
    assert of is not None
    assert of.kx == pytest.approx(k, rel=0.15) and of.ky == pytest.approx(k, rel=0.15)
    assert abs(of.dx) < 0.1 and abs(of.dy) < 0.1
    assert of.box is not None and of.box[2] == pytest.approx(w1, rel=0.15)


def test_object_flow_of_two_equal_patches_is_exactly_still():
    img = np.random.default_rng(1).uniform(0, 255, (60, 80)).astype(np.float32)
    of = object_flow(pyramid(img), pyramid(img.copy()), 40.0, 30.0, 10.0)
    assert (of.kx, of.ky, of.dx, of.dy) == (0.0, 0.0, 0.0, 0.0)


def test_divergence_ignores_the_noise_flow_of_a_uniform_background():
    """DIS returns px-sized noise flow on a uniform background with sensor noise; the divergence
    is taken only where the image has structure, so it stays below the candidate threshold."""
    rng = np.random.default_rng(2)
    a = np.clip(128 + rng.normal(0, 2, (120, 160)), 0, 255).astype(np.uint8)
    b = np.clip(128 + rng.normal(0, 2, (120, 160)), 0, 255).astype(np.uint8)
    flow = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM).calc(a, b, None)
    assert np.abs(flow).max() > 0.5                                # DIS's flow there is noise ...
    div = divergence(flow, b.astype(np.float32), 8, FlowParams().min_gradient)
    assert np.abs(div).max() < FlowParams().min_divergence          # ... and no candidate
    assert regions(div, FlowParams()) == []


def test_an_expanding_patch_is_one_region_at_its_centre():
    """A synthetic flow that expands 2 % per frame about (100, 60) inside a 40-px square and is
    still elsewhere, over a textured image: one region, centred on the square."""
    h, w = 120, 160
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    inside = (np.abs(xs - 100) < 20) & (np.abs(ys - 60) < 20)
    flow = np.stack([0.02 * (xs - 100) * inside, 0.02 * (ys - 60) * inside], -1).astype(np.float32)
    gray = np.random.default_rng(3).uniform(0, 255, (h, w)).astype(np.float32)
    found = regions(divergence(flow, gray, 8, 3.0), FlowParams())
    assert len(found) == 1
    assert abs(found[0].x - 100) <= 8 and abs(found[0].y - 60) <= 8 
    assert found[0].divergence == pytest.approx(0.04, rel=0.1)       # twice the expansion rate


# -- state -----------------------------------------------------------------------------------
def _looming():
    obj = ApproachObject.collision(ttc_s=2.0, at=(140, 100), width_px=10.0, speed_mps=4.0, appearance="textured")
    return approach([obj], background="texture", duration_s=1.8, noise_std=2.0, seed=8)


def test_pickled_mid_track_continues_identically_and_reset_starts_afresh():
    stim = _looming()
    half = len(stim.frames) // 2
    model = FlowTTC(fps=stim.fps)
    first = [model.step(f) for f in stim.frames[:half]]
    assert first[-1].targets                                        # a target is being tracked
    copy = pickle.loads(pickle.dumps(model))
    rest = [model.step(f) for f in stim.frames[half:]]
    assert [copy.step(f) for f in stim.frames[half:]] == rest
    model.reset()
    assert model.camera_motion is None and model.flow is None
    assert [model.step(f) for f in stim.frames] == first + rest


def test_bad_parameters_are_one_line_errors():
    from mlplc2 import InputError

    with pytest.raises(InputError, match="FlowParams.cell"):
        FlowParams(cell=1)
    with pytest.raises(InputError, match="FlowParams.preset"):
        FlowParams(preset="slow")
    with pytest.raises(InputError, match="params must be mlplc2.models.flow.FlowParams"):
        FlowTTC(params={"cell": 5})


# -- documentation -----------------------------------------------------------------------------
def test_docstring_examples():
    result = doctest.testmod(flow_module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


def test_the_readme_points_to_the_flow_docs():
    """docs/flow.md's parameter table is checked with the others (tests/test_docs.py, `mlplc2 params --flow`)."""
    readme = (DOCS.parent / "README.md").read_text(encoding="utf-8")
    assert "(docs/flow.md)" in readme


@pytest.mark.parametrize("name", ["flow", "mlplc2"])
def test_a_heading_given_in_the_frames_pixels_holds_on_frames_wider_than_the_working_width(name):
    """``TargetParams.heading`` is in the pixels of the frames given: the principal point of a
    640 x 480 video given explicitly is the working frame's principal point, and predicts the same course
    (miss) as no heading at all (the principal point by default) while the model measures none itself,
    although the models work on 320 x 240 frames."""
    from mlplc2 import stimuli
    from mlplc2.targets import TargetParams

    st = stimuli.approach_scene(kind="collision", size=(640, 480), ttc_s=1.5, seed=4)
    misses, measured = [], []
    for heading in (None, (319.5, 239.5)):
        model = mlplc2.get_model(name)(fps=st.fps, target_params=TargetParams(heading=heading))
        rows = []
        for f in st.frames:
            out = model.step(f)
            rows += [(t.miss, model._layer.heading) for t in out.targets]
        misses.append([m for m, _ in rows])
        measured.append([h for _, h in rows])
        if heading is not None:
            assert model._work_heading() == (159.5, 119.5)
    assert any(m is not None for m in misses[0])
    assert [m is None for m in misses[0]] == [m is None for m in misses[1]]
    # the same course to rounding while no heading is measured (the fit's miss is the centre's offset from its own
    # expansion centre at contact: the heading drops out but for the rounding of the subtraction) ...
    alike = [(a, b) for a, b, h in zip(*misses, measured[0]) if a is not None and h is None]
    assert alike and [a for a, _ in alike] == pytest.approx([b for _, b in alike], abs=1e-6)
    # ... and to 1e-3 of the object's extent where the run without one measures its own (the flow baseline's focus of
    # expansion, 2 px from the principal point from frame 35 on: with the disc's uniform region re-seated it no longer
    # drops out exactly). A heading 160 px off (the frame's pixels taken for the working frame's) moves it by up to
    # 1.5 extents.
    assert [m for m in misses[0] if m is not None] == pytest.approx([m for m in misses[1] if m is not None], abs=1e-3)
