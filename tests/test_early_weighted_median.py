"""The weighted median whose support stops at brightness edges: exact against a NumPy oracle, a fattened step
given back its edge, the voters and chosen pixels honoured, bad input refused naming the argument."""

import numpy as np
import pytest

from vmcl.early.weighted_median import MAX_BINS, MAX_KEPT_VOTERS, weighted_median
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine


def _oracle(values, image, where, voters, low, high, radius, sigma_colour, sigma_space, stride=1, bin_width=1.0):
    """The definition, pixel by pixel in float64."""
    if values.ndim == 3:
        return np.stack([_oracle(values[..., c], image, where, voters, low, high, radius, sigma_colour, sigma_space,
                                 stride, bin_width) for c in range(values.shape[2])], axis=-1)
    height, width = values.shape
    levels = image.astype(np.float64) / {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}.get(image.dtype, 1.0)
    levels = levels.reshape(height, width, -1)
    span = (high - low) / bin_width + 1
    widening = max(1, int(np.ceil(span / MAX_BINS)))
    step = bin_width * widening
    bins = min(MAX_BINS, int(np.ceil(span / widening)) + 1)
    want = values.astype(np.float64).copy()
    for y, x in zip(*np.nonzero(where)):
        ws, vs = [], []
        for yy in range(max(0, y - radius), min(height, y + radius + 1)):
            for xx in range(max(0, x - radius), min(width, x + radius + 1)):
                if (yy - y) % stride or (xx - x) % stride or not voters[yy, xx] or np.isnan(values[yy, xx]):
                    continue
                ws.append(np.exp(-np.linalg.norm(levels[yy, xx] - levels[y, x]) / sigma_colour
                                 - np.hypot(xx - x, yy - y) / sigma_space))
                vs.append(values[yy, xx])
        if not ws:
            continue
        ws, vs = np.array(ws), np.array(vs, np.float64)
        b = np.clip(np.floor((vs - (low - 0.5 * step)) / step).astype(int), 0, bins - 1)
        cum = np.cumsum(np.bincount(b, weights=ws, minlength=bins))
        k = int(np.argmax(cum >= cum[-1] / 2))
        want[y, x] = (ws[b == k] * vs[b == k]).sum() / ws[b == k].sum()
    return want


def _random_case(channels, low, high, dtype, components, shape=(30, 41)):
    rng = np.random.default_rng(channels)
    values = rng.uniform(low, high, (*shape, components) if components else shape).astype(np.float32)
    values[rng.uniform(size=values.shape) < 0.05] = np.nan
    image_shape = (*shape, 3) if channels == 3 else shape
    image = (rng.uniform(0, 1, image_shape).astype(np.float32) if dtype == np.float32
             else rng.integers(0, np.iinfo(dtype).max + 1, image_shape).astype(dtype))
    where = rng.uniform(size=shape) < 0.4
    voters = rng.uniform(size=shape) < 0.8
    return values, image, where, voters


# Radius 3 at strides 1, 2 and 3 keeps at most 49 voters (the kept voters' bisection); radius 5 at stride 1,
# 121 (the histogram).
@pytest.mark.parametrize(("channels", "low", "high", "radius", "stride", "dtype", "bin_width", "components"), [
    (3, 0.0, 10.0, 3, 1, np.uint8, 1.0, 0), (1, -3.0, 40.0, 3, 1, np.uint8, 1.0, 0),
    (3, 0.0, 10.0, 3, 2, np.uint16, 1.0, 0), (1, -3.0, 40.0, 3, 3, np.uint8, 1.0, 0),
    (3, 0.0, 10.0, 3, 1, np.float32, 1.0, 0), (3, -2.5, 3.0, 3, 2, np.uint8, 0.125, 2),
    (1, -3.0, 40.0, 3, 1, np.uint8, 0.01, 1), (1, -3.0, 4.0, 3, 1, np.float32, 0.5, 2),
    (3, 0.0, 10.0, 5, 1, np.uint8, 1.0, 0), (1, -2.5, 3.0, 5, 1, np.float32, 0.125, 2)])
def test_matches_numpy_oracle(channels, low, high, radius, stride, dtype, bin_width, components, machine):
    """Grey and RGB weights, strides, sub-unit bins (0.01 over 43 units: widened to fit MAX_BINS), fields
    of several components (0: an (H, W) field), and windows of both forms: voters kept, or a histogram."""
    values, image, where, voters = _random_case(channels, low, high, dtype, components)
    found = weighted_median(values, image, low=low, high=high, where=where, voters=voters, radius=radius,
                            sigma_colour=0.2, sigma_space=3.0, stride=stride, bin_width=bin_width, machine=machine)
    want = _oracle(values, image, where, voters, low, high, radius, 0.2, 3.0, stride, bin_width)
    np.testing.assert_array_equal(np.isnan(found), np.isnan(want))
    np.testing.assert_allclose(found[~np.isnan(want)], want[~np.isnan(want)], atol=2e-5)
    np.testing.assert_array_equal(found[~where], values[~where])


def test_the_two_forms_meet_at_the_kept_voters_limit():
    """The largest window whose voters are kept (radius 4: 81 voters) and the smallest histogrammed one
    (radius 5: 121) both match the oracle, in the one-pixel-per-work-item form a GPU runs (VEC = 1)."""
    assert (2 * 4 + 1) ** 2 == MAX_KEPT_VOTERS
    scalar = Machine()
    scalar.vector_width = 1
    values, image, where, voters = _random_case(3, -2.5, 3.0, np.uint8, 2, shape=(19, 23))
    for radius in (4, 5):
        found = weighted_median(values, image, low=-2.5, high=3.0, where=where, voters=voters, radius=radius,
                                sigma_colour=0.2, sigma_space=3.0, bin_width=0.125, machine=scalar)
        want = _oracle(values, image, where, voters, -2.5, 3.0, radius, 0.2, 3.0, 1, 0.125)
        np.testing.assert_array_equal(np.isnan(found), np.isnan(want))
        np.testing.assert_allclose(found[~np.isnan(want)], want[~np.isnan(want)], atol=2e-5)


def test_a_fattened_step_goes_back_to_the_brightness_edge(machine):
    """A disparity step carried 3 px past the brightness edge (a census window's fattening) returns to the
    edge; pixels far from the edge keep their fractions of a pixel."""
    image = np.zeros((24, 40), np.float32)
    image[:, 20:] = 0.8
    truth = np.where(np.arange(40) < 20, 12.25, 3.5).astype(np.float32)[None].repeat(24, 0)
    fattened = truth.copy()
    fattened[:, 20:23] = 12.25
    near = np.zeros(truth.shape, bool)
    near[:, 16:27] = True
    found = weighted_median(fattened, image, low=0, high=20, where=near, machine=machine)
    np.testing.assert_allclose(found, truth, atol=1e-5)


def test_device_input_gives_device_output_equal_to_host(machine):
    rng = np.random.default_rng(5)
    values = rng.uniform(0, 9, (12, 15)).astype(np.float32)
    image = rng.uniform(0, 1, (12, 15)).astype(np.float32)
    host = weighted_median(values, image, low=0, high=9, radius=2, machine=machine)
    device = weighted_median(machine.to_device(values), machine.to_device(image), low=0, high=9, radius=2,
                             machine=machine)
    np.testing.assert_array_equal(device.get(), host)


def test_a_pixel_without_voters_keeps_its_value(machine):
    values = np.arange(20, dtype=np.float32).reshape(4, 5)
    found = weighted_median(values, np.zeros((4, 5), np.float32), low=0, high=19,
                            voters=np.zeros((4, 5), bool), machine=machine)
    np.testing.assert_array_equal(found, values)


@pytest.mark.parametrize(("kwargs", "error", "pattern"), [
    ({"low": 5.0, "high": 1.0}, InputValueError, "low must not exceed high"),
    ({"radius": 0}, InputValueError, "radius"),
    ({"sigma_colour": 0.0}, InputValueError, "sigma_colour"),
    ({"sigma_space": -1.0}, InputValueError, "sigma_space"),
    ({"stride": 0}, InputValueError, "stride"),
    ({"bin_width": 0.0}, InputValueError, "bin_width"),
    ({"bin_width": 1e-300, "low": 2.0, "high": 2.0}, InputValueError, "bin_width must be at least"),
    ({"values": np.zeros((6, 6, 3), np.float32)}, InputValueError, "one or two components"),
    ({"bin_width": 1e-300, "low": -1e37, "high": 1e37}, InputValueError, "bin_width .* is too narrow"),
    ({"sigma_colour": 1e-40}, InputValueError, "sigma_colour must be at least"),
    ({"image": np.full((6, 6), 255.0, np.float32)}, InputValueError, "image: float images hold brightness in"),
    ({"where": np.zeros((3, 3), bool)}, InputValueError, "where"),
    ({"voters": "all"}, InputTypeError, "voters"),
    ({"image": np.zeros((6, 5), np.float32)}, InputValueError, "image"),
    ({"values": np.zeros((6, 6), np.int64)}, InputTypeError, "values"),
])
def test_bad_input_is_refused_naming_it(kwargs, error, pattern, machine):
    call = {"values": np.zeros((6, 6), np.float32), "image": np.zeros((6, 6), np.float32), "low": 0.0, "high": 4.0}
    with pytest.raises(error, match=pattern):
        weighted_median(**{**call, **kwargs}, machine=machine)


@pytest.mark.parametrize("lanes", ["device", 1])
def test_a_value_that_does_not_vote_does_not_reach_the_result(lanes, machine):
    """An infinite value at a pixel that is not a voter (and the border's values, which the vector form reads
    for positions outside the image) weighs nothing: the chosen pixels take their voters' median, never NaN.
    Also in the one-pixel-per-work-item form a GPU runs (VEC = 1), forced here."""
    if lanes != "device":
        machine = Machine()
        machine.vector_width = lanes
    values = np.zeros((3, 21), np.float32)
    values[1, 3] = np.inf
    voters = np.ones((3, 21), bool)
    voters[1, 3] = False
    found = weighted_median(values, np.zeros((3, 21), np.float32), low=0, high=4, voters=voters, radius=1,
                            machine=machine)
    np.testing.assert_array_equal(found, 0)  # the infinite pixel itself too: its voters are its neighbours


@pytest.mark.parametrize("value", [1e37, 1e39])
def test_values_whose_weighted_sums_overflow_float32_are_refused(value, machine):
    # A constant field of 1e37 came out as infinity everywhere (its weighted sums overflowed float32), and a
    # float64 one beyond float32's range was cast to infinity with only NumPy's warning.
    image = np.full((9, 12), 0.5, np.float32)
    with pytest.raises(InputValueError, match="values reach .* they must stay within"):
        weighted_median(np.full((9, 12), value), image, low=0, high=1, radius=3, machine=machine)
    found = weighted_median(np.full((9, 12), 1e30), image, low=0, high=1, radius=3, machine=machine)
    np.testing.assert_allclose(found, 1e30, rtol=1e-6)
