"""NEWS communication: every processor of the grid reads its neighbour (dx, dy) away, all at once.

Seed section "The Connection Machine": the NEWS network connects each processor to its neighbours in
the four cardinal directions of a grid; accesses are made in the same direction for all processors.
"""

from __future__ import annotations

from typing import Literal, overload

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    ArrayLike,
    check_choice,
    check_int,
    field,
    machine_for,
    output_array,
    result,
    type_defines,
)
from vmcl.machine import Machine

__all__ = ["BORDERS", "Border", "shift"]

Border = Literal["zero", "clamp", "wrap"]
BORDERS: dict[Border, int] = {"zero": 0, "clamp": 1, "wrap": 2}


@overload
def shift(x: np.ndarray, dx: int, dy: int, *, border: Border = "zero", out: None = None,
          machine: Machine | None = None) -> np.ndarray: ...
@overload
def shift(x: cl_array.Array, dx: int, dy: int, *, border: Border = "zero", out: cl_array.Array | None = None,
          machine: Machine | None = None) -> cl_array.Array: ...
def shift(x: ArrayLike, dx: int, dy: int, *, border: Border = "zero", out: cl_array.Array | None = None,
          machine: Machine | None = None) -> ArrayLike:
    """The field moved ``dx`` pixels to the right and ``dy`` down: ``out[y, x] = x[y - dy, x - dx]``.

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array, 2-D (H, W) or 3-D (planes, H, W); uint8, int32 or float32
        A 3-D stack is shifted along its last two axes, plane by plane.
    dx, dy : int
        The displacement; any integer (beyond the field's size, "zero" gives zeros and "wrap" wraps).
    border : {"zero", "clamp", "wrap"}
        What a pixel gets whose source lies outside the field: 0, the nearest edge pixel, or the pixel
        on the opposite side (``np.roll`` semantics).
    out : pyopencl.array.Array, optional
        For device input: the array to write the result into (:func:`vmcl.cm.core.output_array`).
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``x``.
    """
    machine = machine_for(machine)
    data, host = field(x, "x", machine, ndims=(2, 3), dtypes=(np.uint8, np.int32, np.float32))
    dx, dy = check_int(dx, "dx"), check_int(dy, "dy")
    border = check_choice(border, "border", BORDERS)
    height, width = data.shape[-2:]
    # Displacements reduced to the same result within the kernel's 64-bit arithmetic: a wrap repeats
    # every field size, and beyond one field size "zero" and "clamp" no longer change.
    if border == "wrap":
        dx, dy = dx % width, dy % height
    else:
        dx, dy = max(-width, min(width, dx)), max(-height, min(height, dy))
    planes = data.size // (height * width)
    out = output_array(out, machine, data, host)
    kernel = machine.kernel("news", "shift", BORDER=BORDERS[border], **type_defines(data.dtype))
    machine.launch(kernel, (width, height, planes), data, out, np.int64(width), np.int64(height),
                   np.int64(dx), np.int64(dy))
    return result(out, host)
