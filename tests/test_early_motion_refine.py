"""The flow's weighted median: each component the weighted median of its own values, a scattered flow mended
up to its brightness edge, and bad input refused naming it."""

import numpy as np
import pytest

from vmcl.early.motion_refine import FLOW_BIN, refine_flow
from vmcl.early.weighted_median import weighted_median
from vmcl.errors import InputTypeError, InputValueError


def _two_surfaces(seed=0):
    """A 40 x 48 frame, dark on the left half and bright on the right, moving by (1.25, -0.5) and (-2.0, 0.75);
    a fifth of the pixels' flow replaced by scatter of up to 2 px (the span stays under 62 bins of FLOW_BIN), and
    a few pixels without flow."""
    rng = np.random.default_rng(seed)
    image = np.full((40, 48), 0.2, np.float32)
    image[:, 24:] = 0.8
    truth = np.empty((40, 48, 2), np.float32)
    truth[:, :24] = (1.25, -0.5)
    truth[:, 24:] = (-2.0, 0.75)
    flow = truth.copy()
    scattered = rng.uniform(size=(40, 48)) < 0.2
    flow[scattered] += rng.uniform(-2, 2, (int(scattered.sum()), 2)).astype(np.float32)
    flow[rng.uniform(size=(40, 48)) < 0.02] = np.nan
    return image, flow, truth


def test_each_component_is_the_weighted_median_of_its_own_values(machine):
    image, flow, _ = _two_surfaces()
    found = refine_flow(flow, image, radius=4, sigma_colour=0.1, stride=1, machine=machine)
    low, high = float(np.nanmin(flow)), float(np.nanmax(flow))
    assert (high - low) / FLOW_BIN < 62  # bins of FLOW_BIN
    for c in range(2):
        want = weighted_median(np.ascontiguousarray(flow[..., c]), image, low=low, high=high, radius=4,
                               sigma_colour=0.1, sigma_space=4.0, bin_width=FLOW_BIN, machine=machine)
        np.testing.assert_array_equal(found[..., c], want)


def test_scattered_flow_is_mended_up_to_the_brightness_edge(machine):
    """Before: a fifth of the pixels off by up to 2 px. After: within a bin of the truth everywhere, the
    columns either side of the edge included (their voters across it weigh exp(-6))."""
    image, flow, truth = _two_surfaces()
    before = np.linalg.norm(np.nan_to_num(flow - truth, nan=10.0), axis=-1)
    assert np.mean(before > 0.5) > 0.15
    found = refine_flow(flow, image, radius=5, sigma_colour=0.1, stride=1, machine=machine)
    error = np.linalg.norm(found - truth, axis=-1)
    assert np.isfinite(found).all()
    assert error.max() < 2 * FLOW_BIN


def test_device_flow_gives_device_output_equal_to_host(machine):
    image, flow, _ = _two_surfaces(seed=1)
    host = refine_flow(flow, image, radius=3, stride=1, machine=machine)
    device = refine_flow(machine.to_device(flow), machine.to_device(image), radius=3, stride=1, machine=machine)
    np.testing.assert_array_equal(device.get(), host)


def test_a_flow_without_values_comes_back_unchanged(machine):
    flow = np.full((6, 7, 2), np.nan, np.float32)
    np.testing.assert_array_equal(refine_flow(flow, np.zeros((6, 7), np.float32), machine=machine), flow)


@pytest.mark.parametrize(("kwargs", "error", "pattern"), [
    ({"flow": np.zeros((6, 6, 3), np.float32)}, InputValueError, "two components"),
    ({"flow": np.zeros((6, 6), np.float32)}, InputValueError, "flow"),
    ({"flow": np.full((6, 6, 2), np.inf, np.float32)}, InputValueError, "infinite"),
    # Finite but past float32's binning: the error names the flow, not the weighted median's low/high.
    ({"flow": np.full((6, 6, 2), -3e38, np.float32)}, InputValueError, "flow must lie within"),
    ({"radius": 0}, InputValueError, "radius"),
    ({"sigma_colour": 0.0}, InputValueError, "sigma_colour"),
    ({"stride": 0}, InputValueError, "stride"),
    ({"image": np.zeros((5, 6), np.float32)}, InputValueError, "image"),
    ({"image": "frame"}, InputTypeError, "image"),
])
def test_bad_input_is_refused_naming_it(kwargs, error, pattern, machine):
    call = {"flow": np.zeros((6, 6, 2), np.float32), "image": np.zeros((6, 6), np.float32)}
    with pytest.raises(error, match=pattern):
        refine_flow(**{**call, **kwargs}, machine=machine)
