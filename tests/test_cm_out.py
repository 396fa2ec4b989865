"""``out=``: a caller that keeps its fields on the device writes a primitive's result into its own buffer."""

import numpy as np
import pytest

import vmcl
from vmcl.cm import filters, news, scan


@pytest.mark.parametrize(("call", "dtype"), [
    (lambda x, **k: news.shift(x, 2, -1, border="clamp", **k), np.float32),
    (lambda x, **k: scan.box_sum(x, 3, **k), np.float32),
    (lambda x, **k: scan.box_sum(x, 2, axes=(-1,), **k), np.int32),
    (lambda x, **k: scan.box_sum(x, 2, axes=(-2,), **k), np.float32),
    (lambda x, **k: filters.binomial(x, 0, **k), np.float32),
    (lambda x, **k: filters.binomial(x, 1, **k), np.float32),
    (lambda x, **k: filters.binomial(x, 4, **k), np.uint8),
    (lambda x, **k: filters.binomial(x, 5, **k), np.int32),
])
def test_out_receives_the_same_result_and_is_returned(machine, call, dtype):
    host = (np.random.default_rng(0).random((23, 37)) * 200).astype(dtype)
    data = machine.to_device(host)
    expected = call(host, machine=machine)
    out = machine.empty(host.shape, host.dtype)
    returned = call(data, out=out, machine=machine)
    assert returned is out
    np.testing.assert_array_equal(out.get(), expected)
    np.testing.assert_array_equal(data.get(), host)  # the input is never written


def test_bad_out_is_refused_by_name(machine):
    host = np.zeros((8, 9), np.float32)
    data = machine.to_device(host)
    with pytest.raises(TypeError, match="out is for device input"):
        news.shift(host, 1, 0, out=machine.empty((8, 9), np.float32), machine=machine)
    with pytest.raises(ValueError, match=r"out must have the result's shape \(8, 9\)"):
        scan.box_sum(data, 1, out=machine.empty((9, 8), np.float32), machine=machine)
    with pytest.raises(ValueError, match="dtype float32"):
        filters.binomial(data, 2, out=machine.empty((8, 9), np.int32), machine=machine)
    with pytest.raises(ValueError, match="must not be the input"):
        news.shift(data, 1, 0, out=data, machine=machine)
    with pytest.raises(TypeError, match="out must be a pyopencl.array.Array"):
        filters.binomial(data, 1, out=np.zeros((8, 9), np.float32), machine=machine)
    with pytest.raises(ValueError, match="another OpenCL context"):
        scan.box_sum(data, 1, out=vmcl.Machine().empty((8, 9), np.float32), machine=machine)
