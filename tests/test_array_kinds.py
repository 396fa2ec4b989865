"""The arrays of one call must go together. A call returns the kind of arrays it was given (NumPy in, NumPy
out; device in, device out), so one that mixes a NumPy array with a device array is refused with a TypeError
naming both arguments (vmcl.cm.core.check_same_kind), whichever of the two is on the device. Two images
compared value for value must be on one scale (vmcl.cm.core.check_same_scale); a big-endian image is its
type, read by value."""

import numpy as np
import pytest

from vmcl.early.lucas_kanade import lucas_kanade
from vmcl.early.motion import flow
from vmcl.early.motion_refine import refine_flow
from vmcl.early.stereo import match, match_features
from vmcl.early.variational import variational_refine
from vmcl.early.weighted_median import weighted_median
from vmcl.errors import InputTypeError, InputValueError

SHAPE = (24, 32)


def _image():
    return np.random.default_rng(0).random(SHAPE, np.float32)


def _flow():
    return np.zeros((*SHAPE, 2), np.float32)


def _frames_like(flow_array, machine):
    """Two frames of the flow's kind, so that the prior is the one argument of the other kind."""
    frames = (_image(), _image())
    return frames if isinstance(flow_array, np.ndarray) else tuple(machine.to_device(f) for f in frames)


CALLS = {
    "motion.flow": (("frame0", "frame1"), lambda a, b, m: flow(a, b, delta=2, patch=5, machine=m),
                    (_image, _image)),
    "refine_flow": (("flow", "image"), lambda a, b, m: refine_flow(a, b, machine=m), (_flow, _image)),
    "lucas_kanade": (("flow", "frame0"), lambda a, b, m: lucas_kanade(a, b, _image(), machine=m), (_flow, _image)),
    "variational_refine": (("flow", "prior"),
                           lambda a, b, m: variational_refine(a, *_frames_like(a, m), prior=b, beta=1.0, machine=m),
                           (_flow, _flow)),
    "weighted_median": (("values", "image"), lambda a, b, m: weighted_median(a, b, low=0.0, high=1.0, machine=m),
                        (_image, _image)),
    "stereo.match": (("left", "right"), lambda a, b, m: match(a, b, d_min=0, d_max=4, machine=m), (_image, _image)),
    "match_features": (("left", "right"),
                       lambda a, b, m: match_features(a, b, _image(), _image(), d_min=0, d_max=4, machine=m),
                       (lambda: np.zeros(SHAPE, np.uint8), lambda: np.zeros(SHAPE, np.uint8))),
}


@pytest.mark.parametrize("device_side", [0, 1], ids=["first on the device", "second on the device"])
@pytest.mark.parametrize("call", sorted(CALLS))
def test_a_numpy_and_a_device_array_together_are_refused_by_name(call, device_side, machine):
    names, run, makers = CALLS[call]
    arrays = [make() for make in makers]
    arrays[device_side] = machine.to_device(arrays[device_side])
    with pytest.raises(InputTypeError) as raised:
        run(*arrays, machine)
    message = str(raised.value)
    assert f"{names[0]} and {names[1]} must both be NumPy arrays or both device arrays" in message


@pytest.mark.parametrize("second", [np.float32, np.uint16], ids=["float beside uint8", "uint16 beside uint8"])
@pytest.mark.parametrize("call", ["match_semiglobal", "estimate_range", "stereo.match", "motion.flow"])
def test_two_images_on_different_scales_are_refused_by_name(call, second, machine):
    """uint8 0..255 beside float 0..1 (or uint16 0..65535) would be compared number for number: refused."""
    from vmcl.early.disparity_range import estimate_range
    from vmcl.early.semiglobal import match_semiglobal

    first = (np.random.default_rng(1).random((48, 64)) * 255).astype(np.uint8)
    other = first.astype(second) / (255 if second == np.float32 else 1)
    other = other.astype(second)
    names = ("frame0", "frame1") if call == "motion.flow" else ("left", "right")
    run = {"match_semiglobal": lambda: match_semiglobal(first, other, machine=machine),
           "estimate_range": lambda: estimate_range(first, other, machine=machine),
           "stereo.match": lambda: match(first, other, d_min=0, d_max=4, machine=machine),
           "motion.flow": lambda: flow(first, other, delta=2, patch=5, machine=machine)}[call]
    with pytest.raises(InputValueError, match=f"{names[0]} and {names[1]} must have the same type"):
        run()


def test_floats_of_two_widths_go_together_and_a_big_endian_image_is_read_by_value(machine):
    from vmcl.early.semiglobal import match_semiglobal

    rng = np.random.default_rng(2)
    left = (rng.random((48, 64)) * 65535).astype(np.uint16)
    right = np.roll(left, -3, axis=1)
    native = match_semiglobal(left, right, d_min=0, d_max=8, machine=machine).filled
    swapped = match_semiglobal(left.astype(">u2"), right.astype(">u2"), d_min=0, d_max=8, machine=machine).filled
    np.testing.assert_array_equal(native, swapped)
    moved = flow(left.astype(">u2"), right.astype(">u2"), delta=4, patch=9, machine=machine).flow
    np.testing.assert_array_equal(moved, flow(left, right, delta=4, patch=9, machine=machine).flow)
    grey = (left / np.float32(65535)).astype(np.float32)
    shifted = np.roll(grey, -3, axis=1)
    np.testing.assert_array_equal(flow(grey, shifted.astype(np.float64), delta=4, patch=9, machine=machine).flow,
                                  flow(grey, shifted, delta=4, patch=9, machine=machine).flow)


def test_a_big_endian_image_is_read_on_its_types_scale_by_the_machine_and_the_texture(machine):
    """Beyond the matchers: the machine's own reading of images (on the type's full scale) and the texture's
    default threshold (a share of it) take a big-endian uint16 as the uint16 it is."""
    from vmcl.early.texture import density
    from vmcl.pipeline import VisionMachine, range_note

    image = (np.random.default_rng(3).random((48, 64)) * 65535).astype(np.uint16)
    swapped = image.astype(">u2")
    np.testing.assert_array_equal(density(swapped, machine=machine), density(image, machine=machine))
    vm = VisionMachine(machine=machine)
    np.testing.assert_array_equal(vm.run(swapped).labels, vm.run(image).labels)
    assert "of uint16's 65535" in range_note((image // 16).astype(">u2"), "left")
