"""The router: get against fancy indexing, send against np.ufunc.at and a sequential loop."""

import numpy as np
import pytest

from vmcl.cm.router import get, send
from vmcl.errors import InputError

UFUNC_AT = {"sum": np.add, "max": np.maximum, "min": np.minimum, "and": np.bitwise_and, "or": np.bitwise_or}


def _send_oracle(values, address, size, combine, fill=0):
    """A sequential loop over the senders in index order: the definition of the result."""
    out = np.full(size, fill, values.dtype)
    seen = np.zeros(size, bool)
    for v, a in zip(values.ravel(), address.ravel()):
        if combine == "overwrite" or not seen[a]:
            out[a] = v
        else:
            out[a] = UFUNC_AT[combine](out[a], v)
        seen[a] = True
    return out


@pytest.mark.parametrize("dtype", [np.uint8, np.int32, np.float32])
def test_get_matches_fancy_indexing(dtype, machine, machine_with_local_size):
    rng = np.random.default_rng(0)
    field = (rng.random((37, 41)) * 200).astype(dtype)
    address = rng.integers(0, field.size, (13, 17)).astype(np.int32)
    np.testing.assert_array_equal(get(field, address, machine=machine), field.ravel()[address])
    np.testing.assert_array_equal(get(field, address, machine=machine_with_local_size), field.ravel()[address])


CASES = [(c, d) for c in ("overwrite", "sum", "max", "min", "and", "or") for d in (np.uint8, np.int32, np.float32)
         if not (c in ("and", "or") and d == np.float32)]


@pytest.mark.parametrize("combine, dtype", CASES)
def test_send_matches_sequential_loop(combine, dtype, machine):
    rng = np.random.default_rng(1)
    values = (rng.standard_normal(3000) * 50).astype(dtype) if dtype == np.float32 \
        else rng.integers(0, 200, 3000).astype(dtype)
    address = rng.integers(0, 500, 3000).astype(np.int32)
    np.testing.assert_array_equal(send(values, address, size=500, combine=combine, fill=7, machine=machine),
                                  _send_oracle(values, address, 500, combine, fill=7))


def test_float_sum_equals_np_add_at_bit_for_bit(machine, machine_with_local_size):
    rng = np.random.default_rng(2)
    values = rng.standard_normal(200_000).astype(np.float32)
    address = rng.integers(0, 1000, 200_000).astype(np.int32)
    expected = np.zeros(1000, np.float32)
    np.add.at(expected, address, values)
    np.testing.assert_array_equal(send(values, address, size=1000, combine="sum", machine=machine), expected)
    np.testing.assert_array_equal(send(values, address, size=1000, combine="sum", machine=machine_with_local_size),
                                  expected)


def test_every_sender_to_one_destination(machine):
    values = np.random.default_rng(3).standard_normal(100_000).astype(np.float32)
    expected = np.zeros(1, np.float32)
    np.add.at(expected, np.zeros(100_000, np.intp), values)
    np.testing.assert_array_equal(send(values, np.zeros(100_000, np.int32), size=1, combine="sum", machine=machine),
                                  expected)


def test_permutation_round_trip_and_shape(machine):
    rng = np.random.default_rng(4)
    field = rng.random((64, 48)).astype(np.float32)
    permutation = rng.permutation(field.size).astype(np.int32)
    scattered = send(field.ravel(), permutation, size=field.shape, machine=machine)
    assert scattered.shape == field.shape
    np.testing.assert_array_equal(get(scattered, permutation, machine=machine), field.ravel())


@pytest.mark.parametrize("call, error, match", [
    (lambda m: get(np.zeros(5, np.float32), np.array([5], np.int32), machine=m), ValueError, r"address must lie in \[0, 4\]"),
    (lambda m: get(np.zeros(5, np.float32), np.array([-1], np.int32), machine=m), ValueError, "address must lie"),
    (lambda m: get(np.zeros(5, np.float32), np.array([1.0]), machine=m), TypeError, "address must have dtype"),
    (lambda m: get(np.zeros(0, np.float32), np.array([0], np.int32), machine=m), ValueError, "field must not be empty"),
    (lambda m: send(np.zeros(3, np.float32), np.zeros(4, np.int32), size=2, machine=m), ValueError, "shape of values"),
    (lambda m: send(np.zeros(3, np.float32), np.zeros(3, np.int32), size=0, machine=m), ValueError, "size must be"),
    (lambda m: send(np.zeros(3, np.float32), np.zeros(3, np.int32), size=2, combine="and", machine=m), TypeError,
     "needs integer values"),
    (lambda m: send(np.zeros(3, np.float32), np.zeros(3, np.int32), size=2, combine="mean", machine=m), ValueError,
     "combine must be one of"),
])
def test_bad_input_is_named(call, error, match, machine):
    with pytest.raises(error, match=match):
        call(machine)


def test_large_field_2048(machine):
    rng = np.random.default_rng(5)
    field = rng.random((2048, 2048)).astype(np.float32)
    address = rng.integers(0, field.size, field.size).astype(np.int32)
    np.testing.assert_array_equal(get(field, address, machine=machine), field.ravel()[address])
    expected = np.zeros(field.size, np.float32)
    np.add.at(expected, address, field.ravel())
    np.testing.assert_array_equal(send(field.ravel(), address, size=field.size, combine="sum", machine=machine),
                                  expected)


@pytest.mark.parametrize("fill, error", [(0.5, TypeError), ("7", TypeError), (None, TypeError), (True, TypeError),
                                         ([0], TypeError), (float("nan"), TypeError), (2**40, ValueError)])
def test_send_refuses_an_integer_fill_it_would_change(fill, error, machine):
    """0.5 used to become 0, "7" become 7 and True become 1: a fill is a value of the values' dtype."""
    from vmcl.errors import InputError

    with pytest.raises(error, match="fill") as raised:
        send(np.ones(3, np.int32), np.zeros(3, np.int32), size=4, fill=fill, machine=machine)
    assert isinstance(raised.value, InputError)


@pytest.mark.parametrize("dtype, fill", [(np.uint8, 300), (np.uint8, -1), (np.float32, 1e39)])
def test_send_refuses_a_fill_beyond_the_dtype(dtype, fill, machine):
    with pytest.raises(ValueError, match="fill"):
        send(np.ones(3, dtype), np.zeros(3, np.int32), size=4, fill=fill, machine=machine)


@pytest.mark.parametrize("size, error, match", [
    (2**31, ValueError, "at most 2147483647 destinations"),
    ((2**16, 2**16), ValueError, "at most 2147483647 destinations"),
    (None, TypeError, "size must be an integer"),
    (16.0, TypeError, "size must be an integer"),
    ((4, True), TypeError, "size must be an integer"),
    ((), ValueError, "non-empty shape"),
])
def test_send_refuses_sizes_by_type_and_range(size, error, match, machine):
    with pytest.raises(error, match=match):
        send(np.ones(3, np.float32), np.zeros(3, np.int32), size=size, machine=machine)


def test_send_refuses_destinations_beyond_the_device_memory(machine):
    """Checked before anything is allocated (it used to fail in pyopencl's create_buffer)."""
    destinations = 2**31 - 1
    if destinations * 16 <= machine.device.global_mem_size and destinations * 4 <= machine.device.max_mem_alloc_size:
        pytest.skip("this device holds the largest addressable send")
    with pytest.raises(ValueError, match="device memory"):
        send(np.ones(3, np.float32), np.zeros(3, np.int32), size=destinations, machine=machine)


def test_send_refuses_a_combine_of_the_wrong_type(machine):
    with pytest.raises(TypeError, match="combine must be one of"):
        send(np.ones(3, np.float32), np.zeros(3, np.int32), size=2, combine=["sum"], machine=machine)


def test_a_float_fill_beyond_float32_names_what_may_be_given():
    # "fill must be a finite number" was said of a fill that may be NaN or an infinity.
    with pytest.raises(InputError, match="within float32's range .* or be NaN or an infinity, got -1e"):
        send(np.array([3.0], np.float32), np.array([0], np.int32), size=2, fill=-1e39)
    assert np.isinf(send(np.array([3.0], np.float32), np.array([0], np.int32), size=2, fill=np.inf)[1])


@pytest.mark.parametrize("values, largest, smallest", [([1, np.nan, 2], 2, 1), ([2, np.nan, 1], 2, 1),
                                                       ([5, 3, np.nan], 5, 3), ([np.nan, 5, 3], 5, 3),
                                                       ([np.nan, np.nan], np.nan, np.nan)])
def test_float_max_and_min_pass_over_nan_whatever_the_senders_order(values, largest, smallest, machine):
    # A NaN reset the fold: [1, nan, 2] gave min 2, and the answer hung on the senders' order.
    values = np.array(values, np.float32)
    to_one = np.zeros(len(values), np.int32)
    np.testing.assert_array_equal(send(values, to_one, size=1, combine="max", machine=machine), [largest])
    np.testing.assert_array_equal(send(values, to_one, size=1, combine="min", machine=machine), [smallest])


def test_numpy_and_device_arrays_are_not_mixed(machine):
    # The result's kind silently followed the first argument's.
    field = np.arange(4, dtype=np.float32)
    address = np.array([3, 0], np.int32)
    with pytest.raises(InputError, match="field and address must both be NumPy arrays or both device arrays"):
        get(field, machine.to_device(address), machine=machine)
    with pytest.raises(InputError, match="values and address must both be NumPy arrays or both device arrays"):
        send(machine.to_device(field[:2]), address, size=4, machine=machine)


def test_a_run_of_dimension_counts_is_said_as_a_range(machine):
    # The message listed "1 or 2 or 3 or ... or 32".
    with pytest.raises(InputError, match=r"field must have 1 to 32 dimensions, got shape \(1, 1"):
        get(np.zeros((1,) * 33, np.float32), np.zeros(1, np.int32), machine=machine)
