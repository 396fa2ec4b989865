"""Local filters on the mesh: the binomial Gaussian and the window maximum.

Seed section "Edge detection" (Zero-crossings): "An interesting and simple implementation of Gaussian
convolution relies on the binomial approximation to the Gaussian distribution. This algorithm requires
only integer addition, shifting, and local communication on the 2D mesh." The window maximum (grey-level
dilation by a square) is what the stereo matcher's shiftable windows need: the best of the windows that
hold a pixel.
"""

from __future__ import annotations

from typing import overload

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm.core import (
    WIDEST,
    ArrayLike,
    check_int,
    device_memory,
    field,
    machine_for,
    output_array,
    result,
    type_defines,
)
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["binomial", "max_passes", "window_max"]


def max_passes(height: int, width: int) -> int:
    """The most binomial passes an (height, width) image takes: those of a Gaussian of sigma
    max(height, width, WIDEST), since n passes have sigma sqrt(n / 2)."""
    height, width = check_int(height, "height", minimum=0), check_int(width, "width", minimum=0)
    return 2 * max(height, width, WIDEST) ** 2


@overload
def binomial(image: np.ndarray, passes: int, *, out: None = None, machine: Machine | None = None) -> np.ndarray: ...
@overload
def binomial(image: cl_array.Array, passes: int, *, out: cl_array.Array | None = None,
             machine: Machine | None = None) -> cl_array.Array: ...
def binomial(image: ArrayLike, passes: int, *, out: cl_array.Array | None = None,
             machine: Machine | None = None) -> ArrayLike:
    """Smooth ``image`` with ``passes`` passes of the 3 x 3 binomial mask [1 2 1]^T [1 2 1] / 16.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, 2-D (H, W) or a 3-D stack (planes, H, W)
        uint8 or int32 (integer add and shift: each pass rounds to nearest, ties up, exactly as
        ``(s + 8) >> 4``) or float32.
    passes : int
        0 <= n <= :func:`max_passes` (2 * max(H, W, WIDEST)**2). n passes approximate a Gaussian of
        standard deviation sqrt(n / 2) pixels (the binomial of order 2n); n = 0 returns a copy.
    out : pyopencl.array.Array, optional
        For device input: the array to write the result into (:func:`vmcl.cm.core.output_array`).
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``image`` (``out`` itself when given).

    Notes
    -----
    Borders repeat the edge pixel (clamp). Use ``passes = round(2 * sigma**2)`` for a target sigma.
    """
    machine = machine_for(machine)
    data, host = field(image, "image", machine, ndims=(2, 3), dtypes=(np.uint8, np.int32, np.float32))
    passes = check_int(passes, "passes", minimum=0)
    height, width = data.shape[-2:]
    if passes > max_passes(height, width):
        raise InputValueError(f"passes must be at most {max_passes(height, width)} for a {height} x {width} "
                              f"image (a Gaussian of sigma sqrt(passes / 2) no wider than max(H, W, {WIDEST})), "
                              f"got {passes}")
    machine.require_memory(f"{passes} binomial passes over shape {data.shape}", 3 * data.nbytes, data.nbytes)
    planes = data.size // (height * width)
    defines = type_defines(data.dtype)
    if data.dtype == np.uint8:
        defines["T_IS_UCHAR"] = 1
    kernel = machine.kernel("cm_filters", "binomial_pass", **defines)
    size = (-(-width // 16), height, planes)
    local = machine.row_local_size(size)
    # Ping-pong between two buffers, the last pass writing into the output; the input is never written.
    final = output_array(out, machine, data, host)
    spare = machine.empty(data.shape, data.dtype) if passes > 1 else final
    buffers = (final, spare) if passes % 2 else (spare, final)
    source = data
    for k in range(passes):
        target = buffers[k % 2]
        machine.launch(kernel, size, source, target, np.int64(width), np.int64(height), local_size=local)
        source = target
    if passes == 0:
        # pyopencl's overloads type a device copy's ends as Buffer; pooled buffers are memory objects too.
        cl.enqueue_copy(machine.queue, device_memory(final), data.base_data,  # type: ignore[call-overload]
                        byte_count=data.nbytes)
        source = final
    return result(source, host)


@overload
def window_max(x: np.ndarray, radius: int, *, machine: Machine | None = None) -> np.ndarray: ...
@overload
def window_max(x: cl_array.Array, radius: int, *, machine: Machine | None = None) -> cl_array.Array: ...
def window_max(x: ArrayLike, radius: int, *, machine: Machine | None = None) -> ArrayLike:
    """The maximum over the (2r+1) x (2r+1) window around every pixel (grey-level dilation by a square).

    Parameters
    ----------
    x : float32 ndarray or pyopencl.array.Array, 2-D (H, W) or a 3-D stack (planes, H, W)
        Planes are filtered one by one.
    radius : int
        r >= 0; windows reaching past the field are cut, so any r gives the result of the field's size.
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``x``.

    Notes
    -----
    Windows are cut at the borders (only pixels of the field count). NaN is passed over; a window of
    NaN only gives NaN. Two passes (rows, then columns) of 2r + 1 reads per pixel each: meant for small
    windows such as a matching patch.
    """
    machine = machine_for(machine)
    data, host = field(x, "x", machine, ndims=(2, 3), dtypes=(np.float32,))
    height, width = data.shape[-2:]
    # A window past the field holds only the field, so a larger radius changes nothing, and this bound
    # keeps x + r within the kernel's integers.
    radius = min(check_int(radius, "radius", minimum=0), max(height, width))
    machine.require_memory(f"a window maximum over shape {data.shape}", 3 * data.nbytes, data.nbytes)
    planes = data.size // (height * width)
    kernel = machine.kernel("cm_filters", "window_max_pass", **type_defines(data.dtype))
    rows, out = machine.empty(data.shape, data.dtype), machine.empty(data.shape, data.dtype)
    size = (width, height, planes)
    for source, target, along_rows in ((data, rows, 1), (rows, out, 0)):
        machine.launch(kernel, size, source, target, np.int64(width), np.int64(height), np.int64(radius),
                       np.int32(along_rows), local_size=machine.row_local_size(size))
    return result(out, host)
