"""NEWS shifts against an explicit loop oracle and np.roll."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vmcl.cm.news import shift


def _oracle(x, dx, dy, border):
    height, width = x.shape[-2:]
    ys, xs = np.arange(height) - dy, np.arange(width) - dx
    if border == "wrap":
        return np.roll(x, (dy, dx), axis=(-2, -1))
    if border == "clamp":
        return x[..., np.clip(ys, 0, height - 1)[:, None], np.clip(xs, 0, width - 1)[None, :]]
    out = np.zeros_like(x)
    inside_y, inside_x = (ys >= 0) & (ys < height), (xs >= 0) & (xs < width)
    out[..., np.flatnonzero(inside_y)[:, None], np.flatnonzero(inside_x)[None, :]] = \
        x[..., ys[inside_y][:, None], xs[inside_x][None, :]]
    return out


@settings(max_examples=60, deadline=None)
@given(shape=st.sampled_from([(1, 1), (1, 9), (9, 1), (7, 13), (3, 11, 5), (64, 61)]),
       dx=st.integers(-70, 70), dy=st.integers(-70, 70), border=st.sampled_from(["zero", "clamp", "wrap"]),
       dtype=st.sampled_from([np.uint8, np.int32, np.float32]))
def test_shift_matches_oracle(shape, dx, dy, border, dtype, machine):
    x = (np.arange(np.prod(shape)) % 251).astype(dtype).reshape(shape)
    np.testing.assert_array_equal(shift(x, dx, dy, border=border, machine=machine), _oracle(x, dx, dy, border))


def test_large_field_any_local_size(machine, machine_with_local_size):
    x = np.random.default_rng(0).random((2048, 2048)).astype(np.float32)
    np.testing.assert_array_equal(shift(x, 3, -2, machine=machine), _oracle(x, 3, -2, "zero"))
    np.testing.assert_array_equal(shift(x[:100, :77], -1, 1, border="wrap", machine=machine_with_local_size),
                                  np.roll(x[:100, :77], (1, -1), axis=(0, 1)))


@pytest.mark.parametrize("args, kwargs, error, match", [
    ((np.zeros(5, np.float32), 1, 0), {}, ValueError, "x must have 2 or 3 dimensions"),
    ((np.zeros((2, 2), np.float32), 1.0, 0), {}, TypeError, "dx must be an integer"),
    ((np.zeros((2, 2), np.float32), 1, 0), {"border": "mirror"}, ValueError, "border must be one of"),
    ((np.zeros((2, 2), np.float64), 1, 0), {}, TypeError, "x must have dtype"),
])
def test_bad_input_is_named(args, kwargs, error, match, machine):
    with pytest.raises(error, match=match):
        shift(*args, machine=machine, **kwargs)


def test_copy_yardstick_copies_every_element(machine):
    # benchmarks/primitives.py measures bandwidth with this kernel; it must copy tails too.
    source = np.arange(1000003, dtype=np.float32)
    target = machine.empty(source.shape, np.float32)
    kernel = machine.kernel("news", "copy", T="float", BORDER=0, VEC=16)
    machine.launch(kernel, (-(-source.size // 16),), machine.to_device(source), target, np.int64(source.size))
    np.testing.assert_array_equal(target.get(), source)


@pytest.mark.parametrize("border", ["zero", "clamp", "wrap"])
@pytest.mark.parametrize("dx, dy", [(2**63, 0), (0, -2**63 - 1), (10**30 + 3, -(10**30) - 2)])
def test_displacements_beyond_64_bits_match_oracle(dx, dy, border, machine):
    """Any integer is a displacement; these used to raise OverflowError converting to the kernel's long."""
    x = (np.arange(7 * 13) % 251).astype(np.float32).reshape(7, 13)

    def same_result(d, size):
        # The oracle's NumPy integers cannot hold these: a wrap repeats every size, and a zero or clamp
        # border shifted by the whole field or more is all zeros or all edge.
        return d % size if border == "wrap" else int(np.sign(d)) * min(abs(d), size)

    want = _oracle(x, same_result(dx, 13), same_result(dy, 7), border)
    np.testing.assert_array_equal(shift(x, dx, dy, border=border, machine=machine), want)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"border": ["zero"]}, TypeError, "border must be one of"),
    ({"border": None}, TypeError, "border must be one of"),
])
def test_bad_border_type_is_named(kwargs, error, match, machine):
    from vmcl.errors import InputError

    with pytest.raises(error, match=match) as raised:
        shift(np.zeros((2, 2), np.float32), 1, 0, machine=machine, **kwargs)
    assert isinstance(raised.value, InputError)
