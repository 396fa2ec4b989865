"""box_sum: window sums by grid-scans, against prefix sums in float64 / int64."""

import numpy as np
import pytest
from oracles import box_sum as box_oracle

import vmcl
from vmcl.cm.scan import box_sum

SHAPES = [(1,), (23,), (1, 1), (1, 19), (19, 1), (31, 17), (40, 37), (3, 40, 37), (2, 1, 50)]


@pytest.mark.parametrize("shape", SHAPES, ids=str)
@pytest.mark.parametrize("radius", [0, 1, 4, 25])
def test_matches_prefix_sum_oracle(shape, radius, machine):
    _check_every_axis(shape, radius, machine, np.random.default_rng(len(shape) * 100 + radius))


def _check_every_axis(shape, radius, machine, rng):
    """box_sum of random int32 (exactly) and float32 fields over rows, columns and both, against the oracle."""
    full = (-1,) if len(shape) == 1 else (-2, -1)
    for axes in ([full] if len(shape) == 1 else [full, (-1,), (-2,)]):
        x = rng.integers(-1000, 1000, shape).astype(np.int32)
        np.testing.assert_array_equal(box_sum(x, radius, axes=axes, machine=machine),
                                      box_oracle(x, radius, axes).astype(np.int32))
        f = rng.random(shape).astype(np.float32)
        np.testing.assert_allclose(box_sum(f, radius, axes=axes, machine=machine), box_oracle(f, radius, axes),
                                   rtol=2e-6, atol=2e-5)


@pytest.fixture(scope="module")
def gpu_walks():
    """A Machine on this device that takes the GPU's path (short segments of each line, one work-item
    each): on PoCL it checks that path's sums, which a GPU runs."""
    machine = vmcl.Machine()
    machine.is_cpu = False
    return machine


@pytest.mark.parametrize("shape", SHAPES + [(3, 70, 53)], ids=str)
@pytest.mark.parametrize("radius", [0, 1, 4, 7, 25])
def test_segmented_walks_match_the_oracle(shape, radius, gpu_walks):
    """Lines shorter and longer than a segment, windows narrower and wider than one (it then grows), and
    stacks of planes: int32 exactly, float32 as closely as the one walk per line."""
    _check_every_axis(shape, radius, gpu_walks, np.random.default_rng(len(shape) * 100 + radius + 7))
    assert any(name.endswith("_segments") for name in gpu_walks.kernel_families())


def test_large_field_and_any_local_size(machine, machine_with_local_size):
    x = np.random.default_rng(3).integers(0, 256, (2048, 2048)).astype(np.int32)
    expected = box_oracle(x, 15).astype(np.int32)
    np.testing.assert_array_equal(box_sum(x, 15, machine=machine), expected)
    small = x[:300, :301]
    np.testing.assert_array_equal(box_sum(small, 7, machine=machine_with_local_size),
                                  box_oracle(small, 7).astype(np.int32))


def test_float_error_stays_small_on_long_lines(machine):
    # The running window adds and subtracts along 4096 pixels: the drift must stay at rounding level.
    x = np.random.default_rng(4).random((4, 4096)).astype(np.float32)
    got = box_sum(x, 30, machine=machine)
    assert np.max(np.abs(got - box_oracle(x, 30)) / box_oracle(x, 30)) < 1e-5


def test_window_counts_with_zero_border(machine):
    counts = box_sum(np.ones((5, 6), np.int32), 1, machine=machine)
    np.testing.assert_array_equal(counts[0], [4, 6, 6, 6, 6, 4])
    np.testing.assert_array_equal(counts[2], [6, 9, 9, 9, 9, 6])


@pytest.mark.parametrize("kwargs, error, match", [
    ({"radius": -1}, ValueError, "radius must be >= 0"),
    ({"radius": 1.5}, TypeError, "radius must be an integer"),
    ({"radius": 1, "axes": ()}, ValueError, "axes must be a non-empty tuple"),
    ({"radius": 1, "axes": (-1, -1)}, ValueError, "must not repeat"),
    ({"radius": 1, "axes": (0,)}, ValueError, "axes=0 is not supported"),
])
def test_bad_input_is_named(kwargs, error, match, machine):
    with pytest.raises(error, match=match):
        box_sum(np.zeros((2, 3, 4), np.float32), machine=machine, **kwargs)


@pytest.mark.parametrize("radius", [2**63, 10**30])
def test_radii_beyond_64_bits_sum_the_whole_line(radius, machine):
    """A window wider than the field sums all of it, at any radius (these used to raise OverflowError)."""
    x = np.random.default_rng(5).integers(-1000, 1000, (9, 14)).astype(np.int32)
    np.testing.assert_array_equal(box_sum(x, radius, machine=machine), np.full(x.shape, x.sum(), np.int32))
    np.testing.assert_array_equal(box_sum(x, radius, axes=(-1,), machine=machine),
                                  np.repeat(x.sum(axis=1, keepdims=True), 14, axis=1))


@pytest.mark.parametrize("axes, error, match", [([-1], TypeError, "axes must be a tuple"),
                                                ("-1", TypeError, "axes must be a tuple")])
def test_axes_of_the_wrong_type_are_a_type_error(axes, error, match, machine):
    with pytest.raises(error, match=match):
        box_sum(np.zeros((3, 3), np.int32), 1, axes=axes, machine=machine)


def test_the_default_axes_are_the_fields_own(machine):
    # A 1-D field's default is its only axis (the square window's (-2, -1) does not exist there); a
    # window longer than the field sums the field, so the overflow check counts no more than that.
    line = np.arange(6, dtype=np.int32)
    expected = np.convolve(line, np.ones(3, np.int32), mode="same")
    assert np.array_equal(box_sum(line, 1, machine=machine), expected)
    assert np.array_equal(box_sum(np.ones((3, 4), np.int32), 1, machine=machine),
                          box_sum(np.ones((3, 4), np.int32), 1, axes=(-2, -1), machine=machine))
    wide = box_sum(np.full((1, 1000), 1e32, np.float32), 1000, machine=machine)
    assert np.allclose(wide, 1e35, rtol=1e-5)


def test_window_sums_beyond_float32_are_refused_not_turned_into_nan(machine):
    # 25 values of 1e38 sum past float32's largest; the running sum's inf would become NaN downstream.
    x = np.full((8, 9), 1e38, np.float32)
    with pytest.raises(ValueError, match="x holds values up to 1e\\+38"):
        box_sum(x, 2, machine=machine)
    # One window's worth fits: the same values over a 1-pixel window are summed exactly.
    np.testing.assert_array_equal(box_sum(x, 0, machine=machine), x)
