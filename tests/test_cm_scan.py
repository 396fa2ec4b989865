"""Scans and grid-scans against a NumPy oracle: every operator, both variants, segments, exclusive."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import scan as scan_oracle

from vmcl.cm.core import check_sigma, check_unit_image
from vmcl.cm.scan import exclusive_sum_into, scan
from vmcl.errors import InputTypeError, InputValueError

OPS = ["plus", "max", "min", "copy"]
METHODS = ["work_efficient", "hillis_steele"]
# 1 x 1, 1 x N, N x 1, primes and non-powers of two, and lines long enough to be cut into chunks (on
# a GPU from 8 Ki elements, on a CPU from 64 Ki).
SHAPES = [(1,), (2,), (97,), (20011,), (200003,), (1, 1), (1, 257), (257, 1), (13, 31), (3, 5, 17), (2, 9001), (9001, 2),
          (70001, 3),
          (5, 48, 33)]


def _data(shape, dtype, rng):
    if dtype == np.int32:
        return rng.integers(-50, 50, shape).astype(np.int32)
    return rng.standard_normal(shape).astype(np.float32)


def _check(got, expected, x, op, axis):
    assert got.dtype == expected.dtype and got.shape == expected.shape
    if op == "plus" and x.dtype == np.float32:
        # Chunked float sums round differently from a serial loop: bound by the running magnitude.
        magnitude = np.cumsum(np.abs(x.astype(np.float64)), axis=axis)
        np.testing.assert_array_less(np.abs(got - expected), 1e-6 * magnitude + 1e-6)
    else:
        np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("shape", SHAPES, ids=str)
@pytest.mark.parametrize("dtype", [np.int32, np.float32], ids=["int32", "float32"])
@pytest.mark.parametrize("method", METHODS)
def test_scan_matches_oracle(shape, dtype, method, machine):
    rng = np.random.default_rng(hash((shape, method)) % 2**32)
    x = _data(shape, dtype, rng)
    segments = rng.random(shape) < 0.05
    for axis in ([-1] if len(shape) == 1 else [-1, -2]):
        for op in OPS:
            for exclusive in (False, True):
                for seg in (None, segments):
                    got = scan(x, op=op, axis=axis, exclusive=exclusive, segments=seg, method=method,
                               machine=machine)
                    expected = scan_oracle(x, op, axis, exclusive, seg)
                    _check(got, expected, x, op, axis)


@settings(max_examples=40, deadline=None)
@given(height=st.integers(1, 70), width=st.integers(1, 70), axis=st.sampled_from([-1, -2]),
       op=st.sampled_from(OPS), exclusive=st.booleans(), method=st.sampled_from(METHODS),
       density=st.sampled_from([0.0, 0.1, 0.5]), seed=st.integers(0, 2**31))
def test_scan_hypothesis(height, width, axis, op, exclusive, method, density, seed, machine):
    rng = np.random.default_rng(seed)
    x = rng.integers(-1000, 1000, (height, width)).astype(np.int32)
    segments = rng.random(x.shape) < density
    got = scan(x, op=op, axis=axis, exclusive=exclusive, segments=segments, method=method, machine=machine)
    np.testing.assert_array_equal(got, scan_oracle(x, op, axis, exclusive, segments))


@pytest.mark.parametrize("axis", [-1, -2])
def test_large_field_2048(axis, machine):
    rng = np.random.default_rng(5)
    x = rng.integers(-100, 100, (2048, 2048)).astype(np.int32)
    np.testing.assert_array_equal(scan(x, axis=axis, machine=machine), np.cumsum(x, axis=axis, dtype=np.int32))
    np.testing.assert_array_equal(scan(x, op="max", axis=axis, machine=machine), np.maximum.accumulate(x, axis=axis))


def test_long_1d_float_scan_is_no_less_accurate_than_numpy(machine):
    x = np.random.default_rng(2).random(1 << 22).astype(np.float32)
    exact = np.cumsum(x.astype(np.float64))
    ours = np.max(np.abs(scan(x, machine=machine) - exact) / exact)
    numpys = np.max(np.abs(np.cumsum(x) - exact) / exact)
    assert ours <= numpys and ours < 5e-5


def test_variants_agree_and_repeat_bit_for_bit(machine, machine_with_local_size):
    rng = np.random.default_rng(9)
    x = rng.standard_normal((301, 517)).astype(np.float32)
    segments = rng.random(x.shape) < 0.01
    for axis in (-1, -2):
        reference = scan(x, axis=axis, segments=segments, machine=machine)
        np.testing.assert_array_equal(scan(x, axis=axis, segments=segments, machine=machine), reference)
        np.testing.assert_array_equal(
            scan(x, axis=axis, segments=segments, machine=machine_with_local_size), reference)
        exact = scan(x, op="max", axis=axis, segments=segments, machine=machine)
        np.testing.assert_array_equal(
            scan(x, op="max", axis=axis, segments=segments, method="hillis_steele", machine=machine), exact)


def test_device_in_device_out(machine):
    x = np.arange(20, dtype=np.int32).reshape(4, 5)
    device = machine.to_device(x)
    out = scan(device, machine=machine)
    assert not isinstance(out, np.ndarray)
    np.testing.assert_array_equal(out.get(), np.cumsum(x, axis=1))


def test_narrow_integers_are_widened_exactly(machine):
    x = np.array([[250, 10, 3]], np.uint8)
    got = scan(x, machine=machine)
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, [[250, 260, 263]])


@pytest.mark.parametrize("kwargs, error, match", [
    ({"x": np.zeros((2, 2, 2, 2), np.float32)}, ValueError, "x must have"),
    ({"x": np.zeros(5, np.float64)}, TypeError, "x must have dtype"),
    ({"x": np.zeros((0, 3), np.float32)}, ValueError, "x must not be empty"),
    ({"x": [1, 2, 3]}, TypeError, "x must be a NumPy array"),
    ({"x": np.zeros(5, np.float32), "axis": -2}, ValueError, "axis=-2 is out of range"),
    ({"x": np.zeros((3, 3), np.float32), "axis": 2}, ValueError, "axis=2 is out of range"),
    ({"x": np.zeros(5, np.float32), "op": "times"}, ValueError, "op must be one of"),
    ({"x": np.zeros(5, np.float32), "method": "fast"}, ValueError, "method must be one of"),
    ({"x": np.zeros(5, np.float32), "segments": np.zeros(4, bool)}, ValueError, "segments must have the data's shape"),
    ({"x": np.zeros(5, np.float32), "segments": np.zeros(5, np.float32)}, TypeError, "segments must be boolean"),
    ({"x": np.zeros(5, np.float32), "exclusive": 1}, TypeError, "exclusive must be a bool"),
])
def test_bad_input_is_named(kwargs, error, match, machine):
    x = kwargs.pop("x")
    with pytest.raises(error, match=match):
        scan(x, machine=machine, **kwargs)


def test_segments_of_another_machine_are_refused(machine):
    """A device array of another OpenCL context used to be handed to this machine's kernels."""
    from vmcl import Machine

    other = Machine()
    x = machine.to_device(np.ones((4, 5), np.float32))
    with pytest.raises(ValueError, match="segments lives on another OpenCL context"):
        scan(x, segments=other.to_device(np.zeros((4, 5), np.uint8)), machine=machine)


@pytest.mark.parametrize("kwargs, match", [({"op": ["plus"]}, "op must be one of"),
                                           ({"method": ["hillis_steele"]}, "method must be one of"),
                                           ({"op": None}, "op must be one of")])
def test_choices_of_the_wrong_type_are_a_type_error(kwargs, match, machine):
    from vmcl.errors import InputTypeError

    with pytest.raises(InputTypeError, match=match):
        scan(np.zeros(5, np.float32), machine=machine, **kwargs)


@pytest.mark.parametrize("pairs", [1, 2, 97, 20011, 150001])
def test_exclusive_sums_of_pairs_scan_each_component(pairs, machine):
    # Long enough inputs are cut into chunks, whose carries must hold both components.
    counts = np.random.default_rng(pairs).integers(0, 1000, (pairs, 2)).astype(np.int32)
    out = machine.empty(2 * pairs, np.int32)
    exclusive_sum_into(machine, machine.to_device(counts.ravel()), out, pairs=True)
    np.testing.assert_array_equal(out.get().reshape(pairs, 2), np.cumsum(counts, axis=0) - counts)


def test_exclusive_sums_of_pairs_refuse_an_odd_length(machine):
    with pytest.raises(InputValueError, match="even number"):
        exclusive_sum_into(machine, machine.to_device(np.ones(3, np.int32)), machine.empty(3, np.int32), pairs=True)


def test_exclusive_sums_refuse_what_is_not_an_int32_device_array(machine):
    # A host array reached the kernel as a pyopencl size error; float32 ones came back as garbage.
    out = machine.empty(3, np.int32)
    with pytest.raises(InputTypeError, match="counts must be an int32 pyopencl array, got ndarray"):
        exclusive_sum_into(machine, np.ones(3, np.int32), out)
    with pytest.raises(InputTypeError, match="counts must be an int32 pyopencl array, got dtype float32"):
        exclusive_sum_into(machine, machine.to_device(np.ones(3, np.float32)), out)
    with pytest.raises(InputValueError, match="out must have counts' 4 elements"):
        exclusive_sum_into(machine, machine.to_device(np.ones(4, np.int32)), out)


def test_the_shared_checks_refuse_huge_numbers_and_pass_empty_images():
    with pytest.raises(InputValueError, match="sigma must be a finite number > 0"):
        check_sigma(10**400)
    check_unit_image(np.zeros((0, 4), np.float32), "image")  # nothing to be on the wrong scale
    with pytest.raises(InputValueError, match="image: float images hold brightness in"):
        check_unit_image(np.full((2, 2), 255.0, np.float32), "image")


@pytest.mark.parametrize("method", ["work_efficient", "hillis_steele"])
def test_float_max_and_min_pass_over_nan_as_numpy_fmax_and_fmin(method, machine):
    # A line's leading NaN came out -inf (the running state's start), a value not in the input, and the two
    # methods disagreed.
    rng = np.random.default_rng(5)
    x = rng.random((6, 300)).astype(np.float32)
    x[rng.random(x.shape) < 0.4] = np.nan
    x[2] = np.nan
    for op, accumulate in (("max", np.fmax.accumulate), ("min", np.fmin.accumulate)):
        got = scan(x, op=op, method=method, machine=machine)
        np.testing.assert_array_equal(got, accumulate(x, axis=1))
        if method == "work_efficient":
            np.testing.assert_array_equal(scan(x.T.copy(), op=op, axis=-2, machine=machine), accumulate(x.T, axis=0))
        shifted = scan(x, op=op, exclusive=True, method=method, machine=machine)
        assert (shifted[:, 0] == (-np.inf if op == "max" else np.inf)).all()
        np.testing.assert_array_equal(shifted[:, 1:], accumulate(x, axis=1)[:, :-1])
