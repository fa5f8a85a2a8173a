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
from mlplc2.plots import ALARM_RGB, CALM_RGB, FIELD_ALARM_RGB, PANEL_RGB, WARN_RGB, annotate_frame

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
    assert _is(img, 80 + 10, 100, FIELD_ALARM_RGB)  # in alarm: the field alarm's violet
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


def test_a_header_wider_than_the_frame_is_written_smaller_to_fit_it():
    """A 160x120 frame is narrower than the header of a warning model in alarm at the frame's own font size: the
    header is written smaller, so its box ends inside the frame with its padding clear (the text not cut by the
    edge), still with text in it; a header that fits keeps its size."""
    from mlplc2.targets import Target

    def header_box(size, targets):
        w, h = size
        frame = np.full((h, w, 3), 255, np.uint8)
        out = Output(0, 9.0, (_field(collision=True),), collision=True, targets=targets)
        img = annotate_frame(frame, [out], ["mlplc2"], draw_fields="none")
        red = np.all(img[: h // 4] == ALARM_RGB, axis=2)
        rows = np.nonzero(red.sum(axis=1) > 5)[0]
        cols = np.nonzero(red[rows].any(axis=0))[0]
        return img[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1], cols[-1], w

    long = (Target(12, 20.0, 100.0, 8.0, 8.0, ttc_s=0.53, miss=0.4, warning=True),
            Target(13, 140.0, 100.0, 8.0, 8.0, ttc_s=0.61, miss=0.2, warning=True))
    box, right, w = header_box((160, 120), long)
    assert right < w - 1                                   # the box ends inside the frame ...
    assert np.all(box[:, -2:] == ALARM_RGB)                # ... and no letter runs into its right edge
    assert (~np.all(box == ALARM_RGB, axis=2)).sum() > 50  # the text is there
    small_h = box.shape[0]
    box, _, _ = header_box((320, 120), long)               # the same height, room for the whole header
    assert box.shape[0] > small_h


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


# -- issue 24 item 4: which target warns, boxes inside the frame, the header, the timeline ------------

def _target(tid=1, x=216.0, y=120.0, width=510.0, height=150.0, ttc_s=0.8, miss=0.3, warning=True):
    from mlplc2.targets import Target

    return Target(tid, x, y, width, height, ttc_s=ttc_s, miss=miss, warning=warning)


def test_header_says_which_target_warns_and_what_is_a_field_alarm():
    from mlplc2.plots import header_text

    calm = _target(1, ttc_s=2.0, warning=False)
    soon, later = _target(3, ttc_s=0.8), _target(5, ttc_s=1.4)
    assert header_text("mlplc2", Output(0, 0.0, targets=(calm, later, soon))) == "mlplc2 WARNING T3 0.80 s +1"
    f = _field(collision=True, response=1926.0)
    assert header_text("mlplc2", Output(0, 1926.0, (f,), collision=True, targets=(soon,))) == \
        "mlplc2 WARNING T3 0.80 s, field alarm"
    assert header_text("mlplc2", Output(0, 1926.0, (f,), collision=True, targets=(calm,))) == \
        "mlplc2 field alarm (paper), response 1926"
    assert header_text("lgmd2", Output(0, 0.9, collision=True)) == "lgmd2 ALARM, response 0.9"
    assert header_text("mlplc2", Output(0, 0.0, targets=(calm,))) == "mlplc2 response 0"



def test_a_field_alarm_without_a_warning_is_not_shown_as_one():
    """The paper's field alarm while no target warns is a row of its own colour, saying which signal it is:
    only a warning (a target's, or an LGMD model's alarm, its only signal) is on red. The header of a field
    alarm was red too, with ``field ALARM``, and read as the collision warning."""
    frame = np.full((240, 320, 3), 255, np.uint8)
    f = _field(collision=True, response=1926.0)
    calm, warning = _target(1, ttc_s=2.0, warning=False), _target(3, ttc_s=0.8)

    def header_colours(out):
        img = annotate_frame(frame, [out], [("mlplc2" if out.fields else "lgmd2")], draw_fields="none")
        left = img[:30, :6].reshape(-1, 3)   # the header row's left end, left of any target
        return {name for name, rgb in (("red", ALARM_RGB), ("violet", FIELD_ALARM_RGB), ("grey", PANEL_RGB))
                if np.all(left == rgb, axis=1).any()}

    assert header_colours(Output(0, 1926.0, (f,), collision=True, targets=(calm,))) == {"violet"}
    assert header_colours(Output(0, 1926.0, (f,), collision=True, targets=(warning,))) == {"red"}
    assert header_colours(Output(0, 0.0, targets=(warning,))) == {"red"}
    assert header_colours(Output(0, 0.9, collision=True)) == {"red"}   # an LGMD model's alarm is its warning
    assert header_colours(Output(0, 5.0, (_field(),), targets=(calm,))) == {"grey"}


def test_a_field_in_alarm_is_drawn_in_the_field_alarm_colour_not_the_warning_red():
    """A field in collision alarm is outlined, crossed and labelled in violet (``FIELD_ALARM_RGB``), as the
    header of its model: red is a warning's alone. With no target warning no pixel is warning red; a warning
    target beside the field is red, its field still violet."""
    frame = np.full((240, 320, 3), 255, np.uint8)
    f = _field(x=200, y=150, radius=30, response=1926.0, collision=True)
    calm = _target(1, x=60, y=150, width=40, height=40, ttc_s=2.0, warning=False)
    img = annotate_frame(frame, [Output(0, 1926.0, (f,), collision=True, targets=(calm,))], ["mlplc2"],
                         draw_fields="all")
    assert not np.all(img == ALARM_RGB, axis=2).any()       # nothing says "warning"
    for x, y in [(170, 150), (230, 150), (200, 180), (200, 150)]:  # the outline's sides and the centre cross
        assert _is(img, x, y, FIELD_ALARM_RGB), (x, y)
    warning = _target(3, x=60, y=150, width=40, height=40, ttc_s=0.8)
    img = annotate_frame(frame, [Output(0, 1926.0, (f,), collision=True, targets=(warning,))], ["mlplc2"],
                         draw_fields="all")
    assert _is(img, 230, 150, FIELD_ALARM_RGB) and _is(img, 40, 150, WARN_RGB)


def test_target_box_wider_than_the_frame_is_clipped_inside_it():
    """A warning target 510 px wide on a 432-px frame: its left and right sides are drawn at
    the frame's edges, its top and bottom across the frame."""
    frame = np.full((240, 432, 3), GREY, np.uint8)
    img = annotate_frame(frame, [Output(0, 0.0, targets=(_target(),))], ["mlplc2"])
    red = np.all(img == WARN_RGB, axis=2)
    rows = slice(120 - 30, 120 + 30)  # the middle of the box's height, away from every label
    assert red[rows, :4].any(axis=1).all() and red[rows, -4:].any(axis=1).all()  # left and right sides
    for y in (120 - 75, 120 + 75):  # top and bottom sides
        assert red[y - 2:y + 3, 100:330].any(axis=0).all(), y


def test_warning_label_keeps_clear_of_the_header():
    """A warning target filling the frame: its label goes where it hides no header row."""
    frame = np.full((240, 320, 3), 255, np.uint8)
    t = _target(x=160, y=120, width=330, height=250)
    outs = [Output(0, 0.0, targets=(t,)), Output(0, 0.5)]
    img = annotate_frame(frame, outs, ["mlplc2", "lgmd2"], index=7)
    header_only = annotate_frame(frame, outs, ["mlplc2", "lgmd2"], primary=None)
    header = np.any(header_only != frame, axis=2)
    header[80:] = False
    assert header.sum() > 500 and (img[header] == header_only[header]).all()
    assert np.all(img == WARN_RGB, axis=2)[100:].sum() > 300  # the label went below the header



def test_labels_take_less_of_a_small_frame():
    """At 160x120 three target labels covered about a quarter of the picture (the targets' overlay, boxes
    and labels, changed 25.0 % of its pixels, the whole overlay 37.5 %): below 320 px wide the text is
    smaller and a target's label short (``T1 WARN 0.62 s``, no miss), so the targets' overlay changes
    12.0 %, the whole 20.9 %. Frames 320 px wide and wider keep their labels (the tests above)."""
    frame = np.full((120, 160, 3), GREY, np.uint8)
    targets = (_target(1, 40.0, 70.0, 20.0, 20.0, ttc_s=0.62, miss=0.3, warning=True),
               _target(2, 110.0, 50.0, 16.0, 16.0, ttc_s=1.84, miss=0.7, warning=False),
               _target(3, 90.0, 95.0, 12.0, 12.0, ttc_s=3.05, miss=2.4, warning=False))
    outs = [Output(0, 0.0, targets=targets)]
    img = annotate_frame(frame, outs, ["mlplc2"], index=7)
    header = annotate_frame(frame, outs, ["mlplc2"], index=7, primary=None)
    by_targets = np.any(img != header, axis=2).mean()
    overall = np.any(img != frame, axis=2).mean()
    assert by_targets < 0.16, by_targets
    assert overall < 0.25, overall
    assert np.all(img == WARN_RGB, axis=2).sum() > 150   # the warning target's box and label are still drawn


def _timeline_rows():
    rows = [{"frame": k, "model": "mlplc2", "target_id": 1, "ttc_s": 1.0 - 0.1 * k, "miss": 0.2,
             "warning": int(k >= 6)} for k in range(10)]
    rows += [{"frame": k, "model": "mlplc2", "target_id": 2, "ttc_s": None, "miss": None, "warning": 0}
             for k in range(3, 8)]
    return rows


def test_timeline_draws_time_to_contact_and_marks_the_warning_frames():
    from mlplc2.plots import figure, plot_timeline

    ax = figure(6, 3).subplots()
    plot_timeline(ax, _timeline_rows(), "mlplc2")
    line, dots = ax.lines  # target 2 never had a time to contact: no line
    assert list(line.get_xdata()) == list(range(10))
    assert np.allclose(line.get_ydata(), [1.0 - 0.1 * k for k in range(10)])
    assert list(dots.get_xdata()) == [6, 7, 8, 9] and np.allclose(dots.get_ydata(), [0.4, 0.3, 0.2, 0.1])
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["T1 warns 6-9"]


def test_responses_png_gets_a_timeline_panel_from_targets_csv(tmp_path):
    import csv

    import matplotlib.image

    from mlplc2.plots import plot_responses, read_targets

    rows = [{"frame": k, "time_s": k / 30, "model": "mlplc2", "field_id": 1, "x": 10.0, "y": 10.0,
             "response": float(k), "collision": 0} for k in range(10)]
    path = tmp_path / "targets.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["frame", "model", "target_id", "x", "y", "width", "height", "ttc_s",
                                          "miss", "warning", "fields", "azimuth_deg", "elevation_deg"])
        w.writeheader()
        for r in _timeline_rows():
            w.writerow({**r, "ttc_s": "" if r["ttc_s"] is None else r["ttc_s"], "miss": r["miss"] or "",
                        "x": 1, "y": 1, "width": 2, "height": 2, "fields": "", "azimuth_deg": "", "elevation_deg": ""})
    read = read_targets(path)      # the rows as RunResult.targets holds them: the keys plot_timeline uses, and more
    assert [{k: r[k] for k in _timeline_rows()[0]} for r in read[:2]] == _timeline_rows()[:2]
    assert read[-1]["ttc_s"] is None and read[0]["fields"] == "" and read[0]["ttc_age_s"] is None
    one = plot_responses(rows, tmp_path / "one.png")
    two = plot_responses(rows, tmp_path / "two.png", targets=path)
    h1, h2 = (matplotlib.image.imread(p).shape[0] for p in (one, two))
    assert h2 > 1.5 * h1  # a second panel
