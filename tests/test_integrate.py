"""vmcl.integrate: the cues' line processes and the brightness edges meet in one labelled map; bad
arguments are refused by name."""

import numpy as np
import pytest

from vmcl.errors import InputError
from vmcl.integrate import Cue, boundary, integrate
from vmcl.mrf import boundary_map
from vmcl.scenes import Label


def _lines(height=4, width=5):
    line_h = np.zeros((height, width - 1), bool)
    line_h[:, 1] = True  # a vertical boundary between x = 1 and x = 2
    return line_h, np.zeros((height - 1, width), bool)


def test_labels_and_support_hand_computed(machine):
    line_h, line_v = _lines()
    edges = np.zeros((4, 5), bool)
    edges[0, 1] = True
    out = integrate({"depth": (line_h, line_v), "colour": (line_h, line_v)}, edges=edges, machine=machine)
    expected_support = np.zeros((4, 5), np.uint8)
    expected_support[:, 1] = Cue.DEPTH | Cue.COLOUR
    expected_support[0, 1] |= Cue.BRIGHTNESS
    np.testing.assert_array_equal(out.support, expected_support)
    expected_labels = np.where(expected_support != 0, np.uint8(Label.DEPTH), np.uint8(0))
    np.testing.assert_array_equal(out.labels, expected_labels)


def test_shape_alone_gives_an_empty_cartoon(machine):
    out = integrate({}, shape=(3, 2), machine=machine)
    assert out.support.shape == (3, 2) and not out.support.any() and not out.labels.any()


def test_boundary_equals_the_host_map_for_uint8_and_device_input(machine):
    rng = np.random.default_rng(1)
    line_h, line_v = rng.random((6, 7)) < 0.3, rng.random((5, 8)) < 0.3
    expected = boundary_map(line_h, line_v)
    np.testing.assert_array_equal(boundary(line_h, line_v, machine=machine), expected)
    np.testing.assert_array_equal(boundary(line_h.view(np.uint8), line_v.view(np.uint8), machine=machine), expected)
    device = boundary(machine.to_device(line_h.view(np.uint8)), machine.to_device(line_v.view(np.uint8)),
                      machine=machine)
    np.testing.assert_array_equal(device.get(), expected.view(np.uint8))


LINE_H, LINE_V = _lines()


@pytest.mark.parametrize("call, error, match", [
    # Empty line fields once reached the device allocator (RuntimeError from pyopencl).
    (lambda m: boundary(np.zeros((0, 4), bool), LINE_V, machine=m), ValueError, "line_h must not be empty"),
    (lambda m: boundary(LINE_H.astype(np.float32), LINE_V, machine=m), TypeError, "line_h must be a bool or uint8"),
    (lambda m: boundary(LINE_H, LINE_V.astype(complex), machine=m), TypeError, "line_v must be a bool or uint8"),
    (lambda m: boundary(LINE_H, None, machine=m), TypeError, "line_v must be a NumPy array"),
    (lambda m: boundary(LINE_H[0], LINE_V, machine=m), ValueError, "line_h must have 2 dimensions"),
    (lambda m: boundary(LINE_H, LINE_V[:2], machine=m), ValueError, "line_h .* and line_v .* are not the two"),
    (lambda m: integrate(None, machine=m), TypeError, "lines must be a mapping"),
    (lambda m: integrate({"depth": LINE_H}, machine=m), TypeError, r"lines\['depth'\] must be a \(line_h, line_v\)"),
    (lambda m: integrate({"sky": (LINE_H, LINE_V)}, machine=m), ValueError, "lines has unknown cues"),
    (lambda m: integrate({"depth": (LINE_H[:, :0], LINE_V)}, machine=m), ValueError,
     r"lines\['depth'\] line_h must not be empty"),
    (lambda m: integrate({}, edges=np.zeros((0, 5)), machine=m), ValueError, "edges must not be empty"),
    (lambda m: integrate({}, edges=np.zeros((4, 5), complex), machine=m), TypeError, "edges must hold real numbers"),
    (lambda m: integrate({}, edges=np.zeros((4, 5), object), machine=m), TypeError, "edges must hold real numbers"),
    (lambda m: integrate({"depth": (LINE_H, LINE_V)}, edges=np.zeros((4, 6)), machine=m), ValueError,
     r"edges must have the lines' shape \(4, 5\)"),
    (lambda m: integrate({"depth": (LINE_H, LINE_V)}, shape=(4, 6), machine=m), ValueError,
     r"line fields of a \(4, 5\) image, but edges, shape"),
    (lambda m: integrate({}, shape=None, machine=m), ValueError, "needs lines, edges or a shape"),
    (lambda m: integrate({}, shape=(0, 5), machine=m), ValueError, r"shape\[0\] must be >= 1"),
    (lambda m: integrate({}, shape=(4.0, 5), machine=m), TypeError, r"shape\[0\] must be an integer"),
    (lambda m: integrate({}, shape=3, machine=m), TypeError, "shape must be a"),
])
def test_bad_arguments_are_refused_by_name(call, error, match, machine):
    with pytest.raises(error, match=match) as raised:
        call(machine)
    assert isinstance(raised.value, InputError)
