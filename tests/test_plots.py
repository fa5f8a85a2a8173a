"""mlplc2.plots: the overlay of ``annotated.mp4`` (``annotate_frame``, issue 14 item 2): fields
in their real shape, only those that respond unless asked, labels on boxes that scale with
the frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mlplc2._validation import InputValueError
from mlplc2.neuropils.attention import Field
from mlplc2.models.base import Output
from mlplc2.plots import ALARM_RGB, CALM_RGB, PANEL_RGB, annotate_frame

GREY = 128


def _field(fid=1, x=80.0, y=60.0, radius=30.0, response=5.0, collision=False):
    return Field(fid, x, y, radius, response, collision, 0)


def _draw(fields, *, size=(160, 120), level=GREY, **kw):
    w, h = size
    frame = np.full((h, w, 3), level, np.uint8)
    out = Output(frame=0, response=max((f.response for f in fields), default=0.0), fields=tuple(fields),
                 collision=any(f.collision for f in fields))
    return frame, annotate_frame(frame, [out], ["mlplc2"], **kw)


def _is(img, x, y, rgb) -> bool:
    return tuple(int(v) for v in img[y, x]) == tuple(rgb)


def test_square_field_is_drawn_as_a_square():
    """The default field is the 2 R_AF square (Params.field_shape): its outline passes
    through the corners, not through the circle of radius R_AF."""
    f = _field(x=80, y=60, radius=30)
    _, img = _draw([f])
    for x, y in [(50, 30 + 12), (110, 90), (50, 90), (110, 60), (80, 90), (50, 60)]:  # on the square
        assert _is(img, x, y, CALM_RGB), (x, y)
    d = round(30 / math.sqrt(2))  # on the circle of radius 30, inside the square: untouched
    for x, y in [(80 + d, 60 + d), (80 - d, 60 + d), (80 + d, 60 - d + 4)]:
        assert _is(img, x, y, (GREY,) * 3), (x, y)


def test_disc_field_is_drawn_as_a_disc():
    f = _field(x=80, y=60, radius=30)
    _, img = _draw([f], field_shape="disc")
    d = round(30 / math.sqrt(2))
    assert (img[60 + d - 1:60 + d + 2, 80 + d - 1:80 + d + 2] != GREY).any()  # on the circle
    assert _is(img, 110, 90, (GREY,) * 3) and _is(img, 50, 90, (GREY,) * 3)  # the corners are not


def test_anisotropic_resize_stretches_the_square():
    _, img = _draw([_field(x=40, y=30, radius=15)], scale_x=2.0, scale_y=2.0 * 0.75)
    assert _is(img, 80 + 30, 45 + 22, CALM_RGB) and _is(img, 80 - 30, 45 + 22, CALM_RGB)


def test_only_responding_or_alarmed_fields_by_default():
    quiet = _field(1, x=40, y=60, radius=15, response=0.0)
    loud = _field(2, x=120, y=60, radius=15, response=7.0)
    alarm = _field(3, x=80, y=100, radius=10, response=0.0, collision=True)
    _, img = _draw([quiet, loud, alarm])
    assert _is(img, 40 + 15, 60, (GREY,) * 3) and _is(img, 40 - 15, 65, (GREY,) * 3)  # not drawn
    assert _is(img, 120 + 15, 60, CALM_RGB)
    assert _is(img, 80 + 10, 100, ALARM_RGB)
    _, everything = _draw([quiet, loud, alarm], draw_fields="all")
    assert _is(everything, 40 + 15, 60, CALM_RGB) and _is(everything, 40 - 15, 65, CALM_RGB)
    with pytest.raises(InputValueError, match="draw_fields"):
        _draw([quiet], draw_fields="some")


def _changed_box(before, after, region):
    """Bounding box (x0, y0, x1, y1) of the pixels that changed within ``region`` (y, x slices)."""
    diff = (before[region] != after[region]).any(axis=2)
    ys, xs = np.nonzero(diff)
    return xs.min(), ys.min(), xs.max() + 1, ys.max() + 1


@pytest.mark.parametrize("level", [255, 0, 128])
def test_header_is_on_a_box_and_scales_with_the_frame(level):
    """On white, black or grey frames the header label is a filled dark box (readable on
    anything), about 3x higher at 1280x720 than at 320x240, and at least 14 px there."""
    heights = {}
    for size in [(320, 240), (1280, 720)]:
        frame, img = _draw([], size=size, level=level)
        w, h = size
        region = (slice(0, h // 3), slice(0, w // 2))  # the header, top left
        x0, y0, x1, y1 = _changed_box(frame, img, region)
        box = img[y0:y1, x0:x1].reshape(-1, 3)
        filled = np.mean(np.all(box == PANEL_RGB, axis=1))
        assert filled > 0.6, (size, filled)  # a box with text, not outlined letters
        assert x0 > 0 and y0 > 0  # a margin from the frame edge
        heights[size] = y1 - y0
    assert heights[(320, 240)] >= 14
    assert 2.5 <= heights[(1280, 720)] / heights[(320, 240)] <= 3.5, heights


def test_header_rows_do_not_overlap_and_field_labels_avoid_them():
    frame = np.full((240, 320, 3), 255, np.uint8)
    f = _field(x=40, y=40, radius=20, response=9.0)  # its label would sit on the header
    outs = [Output(0, 9.0, (f,)), Output(0, 0.5), Output(0, 0.7, collision=True)]
    img = annotate_frame(frame, outs, ["mlplc2", "lgmd2", "lgmd1"])
    left = img[:120, :12]  # the left end of the header rows, left of any field

    def kind(row):
        for name, rgb in (("panel", PANEL_RGB), ("alarm", ALARM_RGB)):
            if np.all(row == rgb, axis=1).any():
                return name
        return "white" if np.all(row == 255) else "other"

    kinds = [kind(row) for row in left]
    runs = [k for i, k in enumerate(kinds) if i == 0 or k != kinds[i - 1]]
    assert runs[:6] == ["white", "panel", "white", "panel", "white", "alarm"], runs  # three separate rows
    assert (np.all(img == CALM_RGB, axis=2)).sum() > 200  # the field's green label box is drawn whole
    green = np.nonzero(np.all(img == CALM_RGB, axis=2).sum(axis=1) > 30)[0]  # rows of the label box
    dark = np.nonzero((np.all(img == PANEL_RGB, axis=2) | np.all(img == ALARM_RGB, axis=2))[:, :40].any(axis=1))[0]
    assert not set(green) & set(dark)  # the label is not under (or over) the header
