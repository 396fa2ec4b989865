"""Gaussian (exact and binomial), Laplacian of Gaussian and difference of Gaussians against NumPy/scipy."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from vmcl import Machine
from vmcl.early import filters
from vmcl.early.filters import GREY_WEIGHTS, difference_of_gaussians, gaussian, laplacian_of_gaussian

TOLERANCE = 2e-5  # float32 against float64, relative to the value range


def _grey(image):
    image = np.asarray(image, np.float64)
    return image @ np.array(GREY_WEIGHTS) if image.ndim == 3 else image


def _exact_oracle(image, sigma):
    return ndimage.gaussian_filter(_grey(image), sigma, mode="nearest", truncate=4.0)


def _binomial_oracle(image, passes):
    out = _grey(image)
    for _ in range(passes):
        for axis in (0, 1):
            out = ndimage.correlate1d(out, [0.25, 0.5, 0.25], axis=axis, mode="nearest")
    return out


def _laplacian_oracle(field):
    padded = np.pad(field, 1, mode="edge")
    c = padded[1:-1, 1:-1]
    return ((padded[1:-1, :-2] - c) + (padded[1:-1, 2:] - c)) + ((padded[:-2, 1:-1] - c) + (padded[2:, 1:-1] - c))


def _image(shape, dtype, seed=0):
    rng = np.random.default_rng(seed)
    if np.dtype(dtype).kind == "f":
        return rng.random(shape).astype(dtype)
    return rng.integers(0, np.iinfo(dtype).max, shape, endpoint=True).astype(dtype)


def _close(got, want, scale):
    np.testing.assert_allclose(got, want, rtol=0, atol=TOLERANCE * scale)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
@pytest.mark.parametrize("sigma", [0.5, 1.4, 3.0])
def test_exact_gaussian_matches_scipy(dtype, sigma, machine):
    image = _image((37, 53), dtype)
    got = gaussian(image, sigma=sigma, method="exact", machine=machine)
    assert got.dtype == np.float32 and got.shape == image.shape
    _close(got, _exact_oracle(image, sigma), float(image.max()))


def test_rgb_becomes_bt709_grey(machine):
    rgb = _image((23, 41, 3), np.uint8, seed=1)
    _close(gaussian(rgb, sigma=1.0, method="exact", machine=machine), _exact_oracle(rgb, 1.0), 255)
    _close(gaussian(rgb, sigma=1.0, machine=machine), _binomial_oracle(rgb, 2), 255)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_channel_planes_are_the_image_s_channels_in_its_levels(dtype, machine):
    rng = np.random.default_rng(4)
    top = 1.0 if dtype == np.float32 else np.iinfo(dtype).max
    rgb = (rng.uniform(0, 1, (9, 23, 3)) * top).astype(dtype)
    planes = filters.channel_planes(machine, machine.to_device(rgb)).get()
    np.testing.assert_array_equal(planes, np.moveaxis(rgb, -1, 0).astype(np.float32))
    grey = rgb[..., 1]
    np.testing.assert_array_equal(filters.channel_planes(machine, machine.to_device(grey)).get(),
                                  grey[None].astype(np.float32))


@settings(max_examples=25, deadline=None)
@given(height=st.integers(1, 40), width=st.integers(1, 70), sigma=st.floats(0.3, 4.0))
def test_exact_gaussian_any_shape(height, width, sigma, machine):
    image = _image((height, width), np.float32, seed=height * 100 + width)
    _close(gaussian(image, sigma=sigma, method="exact", machine=machine), _exact_oracle(image, sigma), 1.0)


@pytest.mark.parametrize("sigma, passes", [(0.3, 1), (1.0, 2), (1.4, 4), (2.0, 8)])
def test_binomial_gaussian_is_repeated_121_passes(sigma, passes, machine):
    assert filters.binomial_passes(sigma) == passes
    image = _image((29, 47), np.uint8, seed=2)
    _close(gaussian(image, sigma=sigma, machine=machine), _binomial_oracle(image, passes), 255)


def test_binomial_approaches_the_exact_gaussian(machine):
    # n passes have variance n / 2 exactly: at sigma = 2 (8 passes), the binomial of order 16 is within
    # 4% of the peak of the Gaussian's impulse response (measured 3.1%).
    impulse = np.zeros((41, 41), np.float32)
    impulse[20, 20] = 1.0
    binomial = gaussian(impulse, sigma=2.0, machine=machine)
    exact = gaussian(impulse, sigma=2.0, method="exact", machine=machine)
    assert np.abs(binomial - exact).max() < 0.04 * exact.max()
    x = np.arange(-20, 21)[None, :]
    assert abs((binomial * x**2).sum() - 4.0) < 1e-4  # variance sigma**2 along x


def test_constant_image_stays_constant_and_its_laplacian_zero(machine):
    flat = np.full((19, 35), 0.1, np.float32)
    for method in ("exact", "binomial"):
        smooth = gaussian(flat, sigma=1.7, method=method, machine=machine)
        assert np.ptp(smooth) == 0
    assert not laplacian_of_gaussian(flat, sigma=1.7, machine=machine).any()


@pytest.mark.parametrize("sigma", [1.0, 2.5])
def test_laplacian_of_gaussian_matches_oracle(sigma, machine):
    image = _image((31, 44), np.uint8, seed=3)
    got = laplacian_of_gaussian(image, sigma=sigma, machine=machine)
    _close(got, _laplacian_oracle(_exact_oracle(image, sigma)), 4 * 255)


def test_difference_of_gaussians_matches_oracle(machine):
    image = _image((33, 29), np.float32, seed=4)
    got = difference_of_gaussians(image, low_sigma=1.2, machine=machine)
    _close(got, _exact_oracle(image, 1.2) - _exact_oracle(image, 1.2 * 1.6), 1.0)
    got = difference_of_gaussians(image, low_sigma=0.8, high_sigma=3.0, machine=machine)
    _close(got, _exact_oracle(image, 0.8) - _exact_oracle(image, 3.0), 1.0)


def test_device_in_device_out(machine):
    image = _image((21, 34), np.uint8, seed=5)
    device = machine.to_device(image)
    for function, kwargs in ((gaussian, {"sigma": 1.0}), (gaussian, {"sigma": 1.0, "method": "exact"}),
                             (laplacian_of_gaussian, {"sigma": 1.5}),
                             (difference_of_gaussians, {"low_sigma": 1.0})):
        on_device = function(device, machine=machine, **kwargs)
        assert not isinstance(on_device, np.ndarray)
        np.testing.assert_array_equal(on_device.get(), function(image, machine=machine, **kwargs))


def test_results_do_not_depend_on_the_local_size(machine_with_local_size, machine):
    image = _image((45, 67, 3), np.uint8, seed=6)
    for function, kwargs in ((gaussian, {"sigma": 1.3, "method": "exact"}), (gaussian, {"sigma": 1.3}),
                             (laplacian_of_gaussian, {"sigma": 2.0}),
                             (difference_of_gaussians, {"low_sigma": 1.0})):
        np.testing.assert_array_equal(function(image, machine=machine_with_local_size, **kwargs),
                                      function(image, machine=machine, **kwargs))


def test_one_pixel_per_work_item_on_gpus_gives_the_same_values(machine):
    # GPUs run VEC = 1; forcing it here runs those kernels on this device.
    image = _image((26, 51), np.float32, seed=7)
    expected = laplacian_of_gaussian(image, sigma=1.5, machine=machine)
    scalar = Machine()
    scalar.vector_width = 1
    np.testing.assert_array_equal(laplacian_of_gaussian(image, sigma=1.5, machine=scalar), expected)


@pytest.mark.parametrize("sigma", [0, -1.0, float("nan"), float("inf")])
def test_bad_sigma_is_refused(sigma, machine):
    with pytest.raises(ValueError, match="sigma must be a finite number > 0"):
        gaussian(np.zeros((4, 4), np.float32), sigma=sigma, machine=machine)


def test_bad_input_is_refused(machine):
    image = np.zeros((6, 6), np.float32)
    with pytest.raises(ValueError, match="image must have 2 or 3 dimensions"):
        gaussian(np.zeros(8, np.float32), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="image must have 2 or 3 dimensions"):
        gaussian(np.zeros((2, 4, 4, 3), np.float32), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match=r"grey \(H, W\) or RGB \(H, W, 3\)"):
        gaussian(np.zeros((4, 4, 4), np.uint8), sigma=1.0, machine=machine)
    nan = image.copy()
    nan[2, 3] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        gaussian(nan, sigma=1.0, machine=machine)
    with pytest.raises(TypeError, match="image must have dtype"):
        gaussian(np.zeros((4, 4), np.int64), sigma=1.0, machine=machine)
    with pytest.raises(TypeError, match="image must have dtype"):
        gaussian(np.zeros((4, 4), bool), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="image must not be empty"):
        gaussian(np.zeros((0, 4), np.float32), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="method must be"):
        gaussian(image, sigma=1.0, method="box", machine=machine)
    with pytest.raises(TypeError, match="sigma must be a number"):
        gaussian(image, sigma="1", machine=machine)
    with pytest.raises(ValueError, match="high_sigma must exceed low_sigma"):
        difference_of_gaussians(image, low_sigma=2.0, high_sigma=1.0, machine=machine)


def test_widths_past_the_image_are_refused(machine):
    from vmcl.cm.filters import binomial

    image = np.zeros((30, 50), np.float32)
    for method in ("binomial", "exact"):
        with pytest.raises(ValueError, match="sigma must be at most 50 for a 30 x 50 image"):
            gaussian(image, sigma=1e4, method=method, machine=machine)
    with pytest.raises(ValueError, match="passes must be at most 5000"):
        binomial(image, 2**31, machine=machine)
    with pytest.raises(ValueError, match="high_sigma must be at most 50"):
        difference_of_gaussians(image, low_sigma=1.0, high_sigma=51.0, machine=machine)
    gaussian(np.zeros((2, 2), np.float32), sigma=4.0, machine=machine)  # small images take usual widths


def test_binomial_of_values_near_float32s_largest_does_not_overflow(machine):
    from vmcl.cm.filters import binomial

    image = np.random.default_rng(3).random((20, 37)).astype(np.float32) * np.float32(3e38)
    expected = ndimage.correlate(image.astype(np.float64), np.outer([1, 2, 1], [1, 2, 1]) / 16, mode="nearest")
    np.testing.assert_allclose(binomial(image, 1, machine=machine), expected, rtol=1e-6)
