"""mlplc2._validation: the input errors (a value and a type error, both importable from the
package) and ``as_gray``, which makes every accepted frame a new float32 array of grey levels
0-255. (The full table of bad frames given to ``Model.step``: ``tests/models/test_base.py``.)"""

from __future__ import annotations

import numpy as np
import pytest

import mlplc2
from mlplc2 import InputError
from mlplc2._validation import InputTypeError, InputValueError, as_gray

H, W = 48, 64


def test_bad_frame_errors_are_importable_from_the_package():
    assert mlplc2.InputError is InputError
    assert issubclass(InputValueError, InputError) and issubclass(InputValueError, ValueError)
    assert issubclass(InputTypeError, InputError) and issubclass(InputTypeError, TypeError)


# -- accepted dtypes and their scaling to 0-255 ---------------------------------------
def _gradient():
    x = np.linspace(0, 255, W)
    y = np.linspace(0, 1, H)[:, None]
    return np.round(x[None, :] * y).astype(np.uint8)  # every value 0..255 occurs somewhere


def test_as_gray_scaling():
    g8 = _gradient()
    ref = g8.astype(np.float32)
    out = as_gray(g8)
    assert out.dtype == np.float32 and out.flags.c_contiguous and np.array_equal(out, ref)
    # uint16: / 257 (65535 -> 255; 8-bit values v * 257 map back exactly)
    assert np.allclose(as_gray(g8.astype(np.uint16) * 257), ref, atol=1e-4)
    assert as_gray(np.full((3, 3), 65535, np.uint16)).max() == pytest.approx(255.0)
    # float: taken as 0-255 (not 0-1), clipped to [0, 255], any float width
    for dt in (np.float16, np.float32, np.float64, np.longdouble):
        assert np.array_equal(as_gray(g8.astype(dt)), ref), dt
    wild = np.array([[-1e300, -1.0, 0.0], [128.5, 255.0, 256.0], [1e30, 1e300, 3e38]])
    assert as_gray(wild).tolist() == [[0, 0, 0], [128.5, 255, 255], [255, 255, 255]]
    # other integers: taken as 0-255 and clipped
    for dt in (np.int8, np.int16, np.int32, np.int64, np.uint32, np.uint64):
        v = np.array([[-128 if np.dtype(dt).kind == "i" else 0, 0, 100], [127, 255, 1000], [2, 3, 4]])
        v = np.clip(v, np.iinfo(dt).min, np.iinfo(dt).max).astype(dt)
        assert as_gray(v).tolist() == np.clip(v.astype(np.float64), 0, 255).tolist(), dt
    # nested lists of numbers and masked arrays without masked pixels are fine
    assert np.array_equal(as_gray([[0, 128, 255]] * 3), np.array([[0, 128, 255]] * 3, np.float32))
    assert np.array_equal(as_gray(np.ma.masked_array(g8, mask=False)), ref)
    # RGB -> Rec. 601 luma; alpha ignored; (H, W, 1) is grey
    rgb = np.zeros((3, 3, 3), np.uint8)
    rgb[..., 0] = 255
    assert as_gray(rgb)[0, 0] == pytest.approx(0.299 * 255, rel=1e-6)
    rgba = np.concatenate([rgb, np.full((3, 3, 1), 7, np.uint8)], axis=-1)
    assert np.array_equal(as_gray(rgba), as_gray(rgb))
    assert np.array_equal(as_gray(g8[:, :, None]), ref)


def test_as_gray_returns_a_new_array():
    f = np.full((5, 5), 10.0, np.float32)
    g = as_gray(f)
    g += 1
    assert f[0, 0] == 10.0  # never a view of the input
    ro = np.full((5, 5, 3), 300.0)
    ro.flags.writeable = False
    assert as_gray(ro).max() == 255.0 and ro.max() == 300.0


# -- the one "did you mean" helper ------------------------------------------------------
def test_did_you_mean_names_the_closest_name_or_none():
    from mlplc2._validation import did_you_mean, did_you_mean_hint

    assert did_you_mean("treshold", ["threshold", "fps", "horizon_s"]) == "threshold"
    assert did_you_mean("zzzzzz", ["threshold", "fps"]) is None
    assert did_you_mean("R_AF", ["r_af", "t_a"]) is None          # case counts: callers lower-case
    assert did_you_mean("fsp", ["fps"]) == "fps"                   # ratio 0.67
    assert did_you_mean("fsp", ["fps"], cutoff=0.7) is None        # the CLI's cutoff for options
    assert did_you_mean_hint("treshold", ("threshold",)) == "did you mean 'threshold'?"
    assert did_you_mean_hint("zzzzzz", ("threshold",), otherwise="known: threshold") == "known: threshold"


def test_check_int_without_an_upper_bound():
    from mlplc2._validation import INT_MAX, check_int

    assert check_int(10**12, "n", maximum=None) == 10**12
    with pytest.raises(InputValueError, match=rf"^n must be an integer in \[0, {INT_MAX}\], got 1000000000000$"):
        check_int(10**12, "n")
    with pytest.raises(InputValueError, match=r"^n must be an integer >= 1, got 0$"):
        check_int(0, "n", minimum=1, maximum=None)
