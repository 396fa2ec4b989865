"""The router: reads and writes at arbitrary addresses, with combining at the destination.

Seed section "Powerful primitive operations" (Routing): the router "provides parallel reads and writes
among processor memory at arbitrary distances and with arbitrary patterns", and "can combine messages at
a destination by various operations, such as logical AND, inclusive OR, summation, and maximum or
minimum". Addresses are flat indices (the CM's linear processor order: y * W + x for a field).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pyopencl as cl

from vmcl.cm import _arrays
from vmcl.cm import reduce as _reduce
from vmcl.cm._arrays import ArrayLike, machine_for, result, type_defines
from vmcl.cm.scan import exclusive_sum_into
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

Combine = Literal["overwrite", "sum", "max", "min", "and", "or"]
_COMBINE = {"overwrite": 100, "sum": 0, "max": 1, "min": 2, "and": 4, "or": 5}
_DTYPES = (np.uint8, np.int32, np.float32)
_ANY_NDIM = tuple(range(1, 33))


def _addresses(address: ArrayLike, size: int, machine: Machine) -> tuple:
    data, host = _arrays.field(address, "address", machine, ndims=_ANY_NDIM, dtypes=(np.int32,))
    if host:
        low, high = int(np.min(address)), int(np.max(address))
    else:
        low, high = (int(_reduce.reduce(data, op, machine=machine).get()) for op in ("min", "max"))
    if low < 0 or high >= size:
        raise InputValueError(f"address must lie in [0, {size - 1}], got values in [{low}, {high}]")
    return data, host


def get(field: ArrayLike, address: ArrayLike, *, machine: Machine | None = None) -> ArrayLike:
    """Every processor reads the field at its address: ``out[i] = field.flat[address[i]]``.

    Parameters
    ----------
    field : array of any shape; uint8, int32 or float32
    address : int32 array of any shape, values in [0, field.size)

    Returns
    -------
    Values of ``field``'s dtype, in ``address``'s shape.
    """
    machine = machine_for(machine)
    data, host = _arrays.field(field, "field", machine, ndims=_ANY_NDIM, dtypes=_DTYPES)
    where, _ = _addresses(address, data.size, machine)
    out = machine.empty(where.shape, data.dtype)
    machine.launch(machine.kernel("router", "gather", COMBINE_OP=100, **type_defines(data.dtype)), (where.size,),
                   data, where, out, np.int64(where.size))
    return result(out, host)


def send(values: ArrayLike, address: ArrayLike, *, size: int | tuple[int, ...], combine: Combine = "overwrite",
         fill: float = 0, machine: Machine | None = None) -> ArrayLike:
    """Every processor sends its value to a destination; messages to one destination are combined.

    Parameters
    ----------
    values : array of any shape; uint8, int32 or float32
    address : int32 array of ``values``' shape, values in [0, prod(size))
    size : int or tuple of int
        The destination field's size (1-D) or shape.
    combine : {"overwrite", "sum", "max", "min", "and", "or"}
        How messages to one destination combine. "overwrite": the sender with the highest index wins.
        "and" / "or": bitwise, integer types only (logical on 0/1 fields).
    fill : scalar
        What destinations that receive no message hold.

    Returns
    -------
    The destination field, of ``values``' dtype and shape ``size``.

    Notes
    -----
    Deterministic whatever the device and its scheduling, floats included, with no float atomics:
    senders are bucketed by destination with integer atomics, each bucket is sorted by sender index
    (heapsort, O(k log k) for a bucket of k), and each destination folds its messages in sender order.
    A float32 "sum" therefore equals the sequential ``np.add.at`` bit for bit.
    """
    machine = machine_for(machine)
    data, host = _arrays.field(values, "values", machine, ndims=_ANY_NDIM, dtypes=_DTYPES)
    shape = (size,) if isinstance(size, (int, np.integer)) else tuple(size)
    if not shape or not all(isinstance(s, (int, np.integer)) and s >= 1 for s in shape):
        raise InputValueError(f"size must be a positive integer or a shape of positive integers, got {size!r}")
    if combine not in _COMBINE:
        raise InputValueError(f"combine must be one of {sorted(_COMBINE)}, got {combine!r}")
    if combine in ("and", "or") and data.dtype == np.float32:
        raise InputTypeError(f"combine={combine!r} needs integer values, got float32")
    destinations = int(np.prod(shape))
    where, _ = _addresses(address, destinations, machine)
    if where.shape != data.shape:
        raise InputValueError(f"address must have the shape of values {data.shape}, got {where.shape}")
    n = data.size
    defines = dict(COMBINE_OP=_COMBINE[combine], **type_defines(data.dtype))
    counts = machine.empty(destinations, np.int32)
    offsets = machine.empty(destinations, np.int32)
    cursor = machine.empty(destinations, np.int32)
    slots = machine.empty(n, np.int32)
    out = machine.empty(shape, data.dtype)
    queue = machine.queue
    cl.enqueue_fill_buffer(queue, counts.base_data, np.int32(0), 0, counts.nbytes)
    machine.launch(machine.kernel("router", "count_senders", **defines), (n,), where, counts, np.int64(n))
    exclusive_sum_into(machine, counts, offsets)
    cl.enqueue_copy(queue, cursor.base_data, offsets.base_data, byte_count=offsets.nbytes)
    machine.launch(machine.kernel("router", "place_senders", **defines), (n,), where, cursor, slots, np.int64(n))
    machine.launch(machine.kernel("router", "sort_buckets", **defines), (destinations,), offsets, counts, slots,
                   np.int64(destinations))
    machine.launch(machine.kernel("router", "combine_buckets", **defines), (destinations,), data, offsets, counts,
                   slots, out, data.dtype.type(fill), np.int64(destinations))
    return result(out, host)
