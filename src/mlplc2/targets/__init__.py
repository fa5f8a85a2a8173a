"""Targets: one per approaching object, with its time to contact, course and a collision warning.

The attention fields of the LPLC2 family (:mod:`mlplc2.neuropils.attention`, Eq. 13-16) say *where* the
local motion looms. A :class:`TargetLayer` turns them into what a robot acts on: one
:class:`Target` per object, with a stable id, its apparent size, the time to contact
``ttc_s``, the predicted ``miss`` distance at contact and a ``warning``. Nothing here changes
the fields: the paper's model is untouched. ``docs/targets.md`` gives the method step by step
and the measurements behind every choice, ``docs/benchmark.md`` the figures.

Per frame (:meth:`TargetLayer.step`): candidates from the attention fields and from the
strongest local motion or grey-level change outside every target; their box (:func:`change_box`,
else the edges of the outward local motion, :func:`measure_extent`); their growth d(log size)/dt,
measured in the image by aligning the object's patch between frames (:func:`align`); the time to
contact from the line through ``1 / S`` (:func:`fit_contact`); the lateral ``miss`` at contact
from the course (:func:`fit_course`); and the warning rule (:func:`estimate`,
:class:`TargetParams`), in which a field in collision alarm (``Field.collision``, the paper's
"fatal" field, itself unchanged) is evidence (:func:`alarm_warns`).

Bearings follow the convention of :mod:`mlplc2.camera`.

The layer's modules, bottom up: :mod:`.params` (:class:`TargetParams`); :mod:`.extent` (the
edges of the local motion), :mod:`.alignment` (the image alignment), :mod:`.change` (the changed
region), :mod:`.contact` (time to contact and course); :mod:`.track` (what is kept of each object and frame), :mod:`.warning` (the warning rule),
:mod:`.layer` (the tracker). The compiled kernels, :mod:`._fast_extent` and :mod:`._fast_align`, are chosen
by :mod:`mlplc2.backend`.
"""

from __future__ import annotations

from ..camera import bearing, check_hfov, focal_length
from .alignment import Alignment, align, pyramid
from .change import change_box
from .contact import ContactFit, fit_contact, fit_course
from .extent import Extent, edge_distance, measure_extent
from .layer import Observation, Target, TargetLayer, Track
from .warning import alarm_warns, count_down, estimate
from .params import TargetParams

__all__ = ["TargetParams", "Target", "TargetLayer", "Track", "Extent", "Alignment", "measure_extent", "edge_distance",
           "align", "change_box", "pyramid", "fit_contact", "fit_course", "estimate", "alarm_warns", "count_down",
           "bearing", "focal_length", "check_hfov", "Observation", "ContactFit"]
