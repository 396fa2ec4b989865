"""Global reductions and histograms against NumPy."""

import numpy as np
import pytest

from vmcl.cm.reduce import extremes, histogram, histogram_to_top, reduce


@pytest.mark.parametrize("shape", [(1,), (7,), (1, 1), (31, 17), (3, 5, 7), (2048, 2048)], ids=str)
def test_reductions_match_numpy(shape, machine):
    rng = np.random.default_rng(0)
    ints = rng.integers(-10**6, 10**6, shape).astype(np.int32)
    assert reduce(ints, "sum", machine=machine) == ints.sum(dtype=np.int64)
    assert reduce(ints, "max", machine=machine) == ints.max()
    assert reduce(ints, "min", machine=machine) == ints.min()
    flags = ints > 0
    assert reduce(flags, "and", machine=machine) == flags.all()
    assert reduce(flags, "or", machine=machine) == flags.any()
    floats = rng.standard_normal(shape).astype(np.float32)
    exact = floats.astype(np.float64).sum()
    assert abs(float(reduce(floats, "sum", machine=machine)) - exact) <= 1e-6 * np.abs(floats).sum() + 1e-6
    assert reduce(floats, "max", machine=machine) == floats.max()
    assert reduce(floats, "min", machine=machine) == floats.min()


def test_float_sum_is_compensated(machine):
    # 2**24 followed by ones: a naive float32 loop stalls at 2**24 (adding 1 rounds back down); Kahan
    # summation gives the exact sum rounded to float32.
    x = np.ones(1 << 20, np.float32)
    x[0] = 2**24
    assert reduce(x, "sum", machine=machine) == np.float32(2**24 + (1 << 20) - 1)


def test_logical_results_and_empty_field(machine):
    assert reduce(np.ones((3, 3), bool), "and", machine=machine) == np.True_
    assert reduce(np.zeros(4, np.uint8), "or", machine=machine) == np.False_
    with pytest.raises(ValueError, match="x must not be empty"):
        reduce(np.zeros(0, np.float32), machine=machine)
    with pytest.raises(ValueError, match="op must be one of"):
        reduce(np.zeros(3, np.float32), "mean", machine=machine)


@pytest.mark.parametrize("shape", [(7,), (300, 301)])
def test_max_and_min_skip_nan_and_give_nan_only_for_nan_alone(shape, machine):
    """The same on every device: NaN elements are skipped (np.nanmax's rule), and a field of NaN alone gives
    NaN (NVIDIA's OpenCL gave infinity for it before max and min became fmax and fmin)."""
    x = np.full(shape, np.nan, np.float32)
    for op in ("max", "min"):
        assert np.isnan(float(reduce(x, op, machine=machine)))
    x.flat[::5] = np.arange(x.size)[::5] - 3.5
    assert float(reduce(x, "max", machine=machine)) == np.nanmax(x)
    assert float(reduce(x, "min", machine=machine)) == np.nanmin(x)


@pytest.mark.parametrize("device", [False, True])
def test_extremes_are_the_minimum_and_maximum(device, machine):
    """As floats, from a host or a device field (NaN skipped; NaN both for NaN alone)."""
    x = np.random.default_rng(3).standard_normal((37, 41)).astype(np.float32)
    x[5, 6] = np.nan
    field = machine.to_device(x) if device else x
    assert extremes(field, machine=machine) == (float(np.nanmin(x)), float(np.nanmax(x)))
    low, high = extremes(np.full(5, np.nan, np.float32), machine=machine)
    assert np.isnan(low) and np.isnan(high)


def test_device_result_stays_on_device(machine):
    out = reduce(machine.to_device(np.arange(10, dtype=np.int32)), "sum", machine=machine)
    assert not isinstance(out, np.ndarray) and out.get()[()] == 45


def test_same_bits_every_run_and_local_size(machine, machine_with_local_size):
    x = np.random.default_rng(1).standard_normal(300_001).astype(np.float32)
    first = reduce(x, machine=machine)
    assert reduce(x, machine=machine) == first and reduce(x, machine=machine_with_local_size) == first


def _float32_rule(x, bins, lo, hi):
    v = x.astype(np.float32).ravel()
    v = v[(v >= np.float32(lo)) & (v <= np.float32(hi))]
    scale = np.float32(bins) / (np.float32(hi) - np.float32(lo))
    index = np.minimum(np.floor((v - np.float32(lo)) * scale).astype(np.int64), bins - 1)
    return np.bincount(index, minlength=bins)


def test_histogram_matches_numpy_on_integers(machine):
    image = np.random.default_rng(2).integers(0, 256, (512, 300)).astype(np.uint8)
    np.testing.assert_array_equal(histogram(image, 256, (0, 256), machine=machine),
                                  np.histogram(image, 256, (0, 256))[0])



@pytest.mark.parametrize("values, bins, low, high", [([100000001, 100000002, 100000003], 3, 100000001, 100000004),
                                                     ([2**31 - 1, 2**31 - 2], 2, 2**31 - 2, 2**31 - 1),
                                                     ([-2**31, -1500000000, -500000000, 500000000, 2**31 - 1], 4, -2**31, 2**31 - 1)])
def test_histogram_bins_large_integers_as_numpy_does(values, bins, low, high, machine, machine_with_local_size):
    # int32 values past 2**24 are not float32's: taken as floats, neighbouring ones shared a bin.
    x = np.array(values * 40, np.int32)
    np.testing.assert_array_equal(histogram(x, bins, (low, high), machine=machine_with_local_size),
                                  np.histogram(x.astype(np.float64), bins, (low, high))[0])


def test_a_float_sum_that_reaches_an_infinity_is_that_infinity(machine):
    # Kahan's compensation of an infinite sum is inf - inf: carried on, it made the sum NaN.
    for n in (1, 20, 100001):
        assert reduce(np.array([np.inf, 1.0] * n, np.float32), machine=machine) == np.inf
        assert reduce(np.array([-np.inf, 2.0] * n, np.float32), machine=machine) == -np.inf
    assert reduce(np.full(1000, 1e36, np.float32), machine=machine) == np.inf  # past float32's largest
    assert np.isnan(reduce(np.array([np.inf, -np.inf] * 20, np.float32), machine=machine))


def test_histogram_float_rule_nan_and_outside(machine, machine_with_local_size):
    x = np.random.default_rng(3).standard_normal((300, 401)).astype(np.float32)
    x[0, :10] = np.nan
    expected = _float32_rule(x, 37, -2.0, 2.5)
    counts = histogram(x, 37, (-2.0, 2.5), machine=machine)
    np.testing.assert_array_equal(counts, expected)
    np.testing.assert_array_equal(histogram(x, 37, (-2.0, 2.5), machine=machine_with_local_size), expected)
    # Every finite value inside the closed range is counted once (the last bin holds hi), NaN never.
    assert counts.sum() == np.sum((x >= -2) & (x <= 2.5))


def test_tiled_histograms(machine):
    image = np.random.default_rng(4).integers(0, 256, (250, 130)).astype(np.uint8)
    tiles = histogram(image, 16, (0, 256), tile=(64, 50), machine=machine)
    assert tiles.shape == (4, 3, 16)
    for ty in range(4):
        for tx in range(3):
            block = image[ty * 64:(ty + 1) * 64, tx * 50:(tx + 1) * 50]
            np.testing.assert_array_equal(tiles[ty, tx], np.histogram(block, 16, (0, 256))[0])


@pytest.mark.parametrize("tile", [None, (64, 50)])
def test_histogram_to_a_top_on_the_device_matches_the_host_range(tile, machine):
    """The range [0, max] read on the device gives the bins of the host range (0, max), and [0, 1] for a
    field of zeros (the noise estimate's rule)."""
    x = np.random.default_rng(5).gamma(2.0, 3.0, (250, 130)).astype(np.float32)
    for field in (x, np.zeros_like(x)):
        device = machine.to_device(field)
        top = reduce(device, "max", machine=machine)
        hi = float(field.max()) if field.max() > 0 else 1.0
        got = histogram_to_top(device, 4096, top, tile=tile, machine=machine).get()
        np.testing.assert_array_equal(got, histogram(field, 4096, (0.0, hi), tile=tile, machine=machine))
        assert got.sum() == field.size


@pytest.mark.parametrize("values", [np.arange(5, dtype=np.int64), 2**25 + np.arange(6), -7 - np.arange(4),
                                    2**30 + np.array([0, 1, 2, 63, 64, 65])])
def test_histogram_to_an_integer_fields_top_counts_every_value(values, machine):
    # An int32 field's maximum in float32 rounds, past 2^24 sometimes down (2^25 + 5 to 2^25 + 4): the
    # largest values lay above the range read on the device and were left out.
    field = np.tile(values.astype(np.int32), (3, 1))
    device = machine.to_device(field)
    top = machine.to_device(np.array([np.float32(values.max())], np.float32))
    got = histogram_to_top(device, 16, top, lo=float(values.min()), machine=machine).get()
    assert got.sum() == field.size
    if values.max() - values.min() < 2**24 and np.float32(values.max()) == values.max():
        # Where float32 holds the top exactly, the bins are the host range's.
        np.testing.assert_array_equal(
            got, histogram(field, 16, (float(values.min()), float(values.max())), machine=machine))


def test_histogram_to_a_nan_or_infinite_top(machine):
    field = machine.to_device(np.array([[0.5, 2.0, 7.0]], np.float32))
    nan, inf = (machine.to_device(np.array([v], np.float32)) for v in (np.nan, np.inf))
    assert histogram_to_top(field, 4, nan, machine=machine).get().tolist() == [0, 0, 1, 0]  # [0, 1]
    assert histogram_to_top(field, 4, inf, machine=machine).get().tolist() == [3, 0, 0, 0]


@pytest.mark.parametrize("kwargs, error, match", [
    ({"bins": 0, "range": (0, 1)}, ValueError, "bins must be between"),
    ({"bins": 4, "range": (1, 1)}, ValueError, "lo < hi"),
    ({"bins": 4, "range": (0, np.inf)}, ValueError, "finite"),
    ({"bins": 4, "range": "ab"}, TypeError, "range must be a pair"),
    ({"bins": 4, "range": (0, 1), "tile": (0, 4)}, ValueError, "tile must be a pair"),
    ({"bins": 2.5, "range": (0, 1)}, TypeError, "bins must be an integer"),
])
def test_histogram_bad_input_is_named(kwargs, error, match, machine):
    with pytest.raises(error, match=match):
        histogram(np.zeros((4, 4), np.float32), machine=machine, **kwargs)


@pytest.mark.parametrize("width", [16, 17])
@pytest.mark.parametrize("value_range", [(0.0, 1e-38), (0.0, 2.0**-140), (-3e38, 3e38)])
def test_histogram_of_a_range_beyond_float32s_exponent_is_numpys(width, value_range, machine):
    # bins / (hi - lo) or hi - lo overflows float32 here: the bins were garbage indices (a crash at
    # width 17, where the scalar path runs) and are now np.histogram's.
    value_range = lo, hi = tuple(float(np.float32(v)) for v in value_range)  # ends that float32 holds
    x = np.linspace(lo, hi, 4 * width, dtype=np.float32).reshape(4, width)
    x[0, 0] = 0.0
    expected, _ = np.histogram(x.astype(np.float64), 16, value_range)
    np.testing.assert_array_equal(histogram(x, 16, value_range, machine=machine), expected)


def test_histogram_counts_too_many_tiles_are_refused_before_allocating(machine):
    with pytest.raises(ValueError, match="histograms of 4096 bins needs"):
        histogram(np.zeros((2048, 2048), np.uint8), 4096, (0, 1), tile=(1, 1), machine=machine)


def test_a_device_bool_array_is_taken_as_a_host_one_is(machine):
    # A bool field on the device was refused ("must have dtype uint8, int32 or float32") where the same
    # field on the host was counted.
    from vmcl.cm.doubling import label

    mask = np.random.default_rng(2).random((19, 23)) < 0.4
    device = machine.to_device(mask)
    assert reduce(device, "sum", machine=machine) == reduce(mask, "sum", machine=machine) == mask.sum()
    np.testing.assert_array_equal(histogram(device, 2, (0, 1), machine=machine).get(), [(~mask).sum(), mask.sum()])
    np.testing.assert_array_equal(label(device, machine=machine).get(), label(mask, machine=machine))
