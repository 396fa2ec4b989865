"""vmcl.integrate refuses bad line fields, edges and shapes by name."""

import numpy as np
import pytest

from vmcl.errors import InputError
from vmcl.integrate import boundary, integrate
from vmcl.labels import Cue


def _lines(height=4, width=5):
    line_h = np.zeros((height, width - 1), bool)
    line_h[:, 1] = True  # a vertical boundary between x = 1 and x = 2
    return line_h, np.zeros((height - 1, width), bool)


LINE_H, LINE_V = _lines()


@pytest.mark.parametrize("call, error, match", [
    # Empty line fields once reached the device allocator (RuntimeError from pyopencl).
    (lambda m: boundary(np.zeros((0, 4), bool), LINE_V, machine=m), ValueError, "line_h must not be empty"),
    (lambda m: boundary(LINE_H.astype(np.float32), LINE_V, machine=m), TypeError, "line_h must be a bool or uint8"),
    (lambda m: boundary(LINE_H, LINE_V.astype(complex), machine=m), TypeError, "line_v must be a bool or uint8"),
    (lambda m: boundary(LINE_H, None, machine=m), TypeError, "line_v must be a NumPy array"),
    (lambda m: boundary(LINE_H[0], LINE_V, machine=m), ValueError, "line_h must have 2 dimensions"),
    (lambda m: integrate(None, machine=m), TypeError, "lines must be a mapping"),
    (lambda m: integrate({"stereo": LINE_H}, machine=m), TypeError, r"lines\['stereo'\] must be a \(line_h, line_v\)"),
    (lambda m: integrate({"stereo": (LINE_H[:, :0], LINE_V)}, machine=m), ValueError,
     r"lines\['stereo'\] line_h must not be empty"),
    (lambda m: integrate({}, edges=np.zeros((0, 5)), machine=m), ValueError, "edges must not be empty"),
    (lambda m: integrate({}, edges=np.zeros((4, 5), complex), machine=m), TypeError, "edges must hold real numbers"),
    (lambda m: integrate({}, edges=np.zeros((4, 5), object), machine=m), TypeError, "edges must hold real numbers"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, edges=np.zeros((4, 6)), machine=m), ValueError,
     r"edges must have the lines' shape \(4, 5\)"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, shape=(4, 6), machine=m), ValueError,
     r"line fields of a \(4, 5\) image, but edges, shape"),
    (lambda m: integrate({}, shape=(0, 5), machine=m), ValueError, r"shape\[0\] must be >= 1"),
    (lambda m: integrate({}, shape=(4.0, 5), machine=m), TypeError, r"shape\[0\] must be an integer"),
    (lambda m: integrate({}, shape=3, machine=m), TypeError, "shape must be a"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, owners=[], machine=m), TypeError, "owners must be a mapping"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, owners={"motion": np.zeros((4, 5))}, machine=m), ValueError,
     r"owners has cues without lines: \['motion'\]"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, owners={"stereo": np.zeros((4, 6))}, machine=m), ValueError,
     r"owners\['stereo'\] must have the lines' shape \(4, 5\)"),
    (lambda m: integrate({"stereo": (LINE_H, LINE_V)}, owners={"stereo": np.zeros((4, 5), complex)}, machine=m),
     TypeError, r"owners\['stereo'\] must hold real numbers"),
])
def test_bad_arguments_are_refused_by_name(call, error, match, machine):
    with pytest.raises(error, match=match) as raised:
        call(machine)
    assert isinstance(raised.value, InputError)


def _owned_marks_oracle(line_h, line_v, owner):
    """Each on site's mark on the pixel whose owner is larger; ties and NaN on the left or upper pixel."""
    marks = np.zeros(owner.shape, bool)
    for y, x in zip(*np.nonzero(line_h)):
        marks[y, x + 1 if owner[y, x + 1] > owner[y, x] else x] = True
    for y, x in zip(*np.nonzero(line_v)):
        marks[y + 1 if owner[y + 1, x] > owner[y, x] else y, x] = True
    return marks


def test_owned_lines_mark_the_side_their_owner_picks(machine):
    """A depth line marks its nearer pixel (the larger disparity), on both sides of a plate and across
    rows; equal and NaN owners keep the left or upper pixel, as unowned lines do."""
    rng = np.random.default_rng(3)
    height, width = 9, 11
    line_h, line_v = rng.random((height, width - 1)) < 0.3, rng.random((height - 1, width)) < 0.3
    owner = rng.integers(0, 3, (height, width)).astype(np.float64)  # many ties
    owner[rng.random(owner.shape) < 0.1] = np.nan
    found = integrate({"stereo": (line_h, line_v)}, owners={"stereo": owner}, machine=machine)
    stereo = (found.support & Cue.STEREO) != 0
    np.testing.assert_array_equal(stereo, _owned_marks_oracle(line_h, line_v, owner))
    plain = integrate({"stereo": (line_h, line_v)}, owners={"stereo": np.zeros(owner.shape)}, machine=machine)
    unowned = integrate({"stereo": (line_h, line_v)}, machine=machine)
    np.testing.assert_array_equal(plain.support, unowned.support)
