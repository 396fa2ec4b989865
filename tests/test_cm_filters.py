"""Local filters: the binomial Gaussian (exact integer add-and-shift against an oracle, and its variance) and
the window maximum against scipy."""

import numpy as np
import pytest
from scipy import ndimage

from vmcl.cm.filters import binomial, window_max


def _oracle(x, passes):
    acc = x.astype(np.float64 if x.dtype.kind == "f" else np.int64)
    weights = np.array([1, 2, 1])
    for _ in range(passes):
        pad = [(0, 0)] * (acc.ndim - 2) + [(1, 1), (1, 1)]
        p = np.pad(acc, pad, mode="edge")
        h, w = acc.shape[-2:]
        s = sum(weights[i] * weights[j] * p[..., i:i + h, j:j + w] for i in range(3) for j in range(3))
        acc = s / 16.0 if acc.dtype.kind == "f" else (s + 8) >> 4
    return acc


@pytest.mark.parametrize("shape", [(1, 1), (1, 17), (17, 1), (37, 53), (2, 19, 23)], ids=str)
@pytest.mark.parametrize("passes", [0, 1, 4])
def test_integer_passes_are_exact(shape, passes, machine):
    rng = np.random.default_rng(passes)
    u8 = rng.integers(0, 256, shape).astype(np.uint8)
    np.testing.assert_array_equal(binomial(u8, passes, machine=machine), _oracle(u8, passes).astype(np.uint8))
    i32 = rng.integers(-10**6, 10**6, shape).astype(np.int32)
    np.testing.assert_array_equal(binomial(i32, passes, machine=machine), _oracle(i32, passes).astype(np.int32))
    f32 = rng.random(shape).astype(np.float32)
    np.testing.assert_allclose(binomial(f32, passes, machine=machine), _oracle(f32, passes), rtol=1e-5, atol=1e-6)


def test_impulse_response_has_variance_n_over_2(machine):
    impulse = np.zeros((65, 65), np.float32)
    impulse[32, 32] = 1
    response = binomial(impulse, 6, machine=machine).astype(np.float64)
    assert abs(response.sum() - 1) < 1e-5
    offsets = np.arange(65) - 32
    assert abs((response.sum(axis=0) * offsets**2).sum() - 3.0) < 1e-4
    assert abs((response.sum(axis=1) * offsets**2).sum() - 3.0) < 1e-4


def test_large_image_any_local_size(machine, machine_with_local_size):
    x = np.random.default_rng(1).integers(0, 256, (2048, 2048)).astype(np.uint8)
    np.testing.assert_array_equal(binomial(x, 2, machine=machine), _oracle(x, 2).astype(np.uint8))
    np.testing.assert_array_equal(binomial(x[:50, :61], 3, machine=machine_with_local_size),
                                  _oracle(x[:50, :61], 3).astype(np.uint8))


@pytest.mark.parametrize("image, passes, error, match", [
    (np.zeros((4, 4), np.uint8), -1, ValueError, "passes must be >= 0"),
    (np.zeros((4, 4), np.uint8), 1.0, TypeError, "passes must be an integer"),
    (np.zeros(4, np.uint8), 1, ValueError, "image must have 2 or 3 dimensions"),
    (np.zeros((4, 4), np.float64), 1, TypeError, "image must have dtype"),
])
def test_bad_input_is_named(image, passes, error, match, machine):
    with pytest.raises(error, match=match):
        binomial(image, passes, machine=machine)


@pytest.mark.parametrize("shape", [(1, 1), (1, 17), (17, 1), (37, 53), (3, 19, 23)], ids=str)
@pytest.mark.parametrize("radius", [0, 1, 5, 30])
def test_window_max_matches_scipy(shape, radius, machine):
    rng = np.random.default_rng(radius)
    x = rng.normal(size=shape).astype(np.float32)
    x.flat[rng.integers(0, x.size, max(1, x.size // 10))] = -np.inf  # the matcher's unscorable cells
    size = (1,) * (x.ndim - 2) + (2 * radius + 1,) * 2
    expected = ndimage.maximum_filter(x, size=size, mode="constant", cval=-np.inf)
    np.testing.assert_array_equal(window_max(x, radius, machine=machine), expected)


def test_window_max_passes_over_nan_and_keeps_device_arrays(machine):
    x = np.zeros((5, 7), np.float32)
    x[2, 3] = np.nan
    x[0, 0] = 4.0
    got = window_max(machine.to_device(x), 1, machine=machine)
    assert not isinstance(got, np.ndarray)
    host = got.get()
    assert not np.isnan(host).any() and host[1, 1] == 4.0 and host[2, 3] == 0.0
    assert np.isnan(window_max(np.full((3, 3), np.nan, np.float32), 1, machine=machine)).all()


@pytest.mark.parametrize("x, radius, error, pattern", [
    (np.zeros((4, 4), np.float32), -1, ValueError, "radius must be >= 0"),
    (np.zeros((4, 4), np.float32), 1.5, TypeError, "radius must be an integer"),
    (np.zeros((4, 4), np.int32), 1, TypeError, "x must have dtype float32"),
    (np.zeros(4, np.float32), 1, ValueError, "x must have 2 or 3 dimensions"),
])
def test_window_max_bad_input_is_named(x, radius, error, pattern, machine):
    with pytest.raises(error, match=pattern):
        window_max(x, radius, machine=machine)
