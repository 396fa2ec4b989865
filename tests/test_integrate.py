"""vmcl.integrate refuses bad line fields, edges and shapes by name."""

import numpy as np
import pytest

from vmcl.errors import InputError
from vmcl.integrate import boundary, integrate


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
])
def test_bad_arguments_are_refused_by_name(call, error, match, machine):
    with pytest.raises(error, match=match) as raised:
        call(machine)
    assert isinstance(raised.value, InputError)
