"""The router: reads and writes at arbitrary addresses, with combining at the destination.

Seed section "Powerful primitive operations" (Routing): the router "provides parallel reads and writes
among processor memory at arbitrary distances and with arbitrary patterns", and "can combine messages at
a destination by various operations, such as logical AND, inclusive OR, summation, and maximum or
minimum". Addresses are flat indices (the CM's linear processor order: y * W + x for a field).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import pyopencl as cl

from vmcl.cm import core
from vmcl.cm import reduce as _reduce
from vmcl.cm.core import (
    ArrayLike,
    check_choice,
    check_int,
    check_real,
    device_memory,
    machine_for,
    result,
    type_defines,
)
from vmcl.cm.scan import exclusive_sum_into
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["Combine", "get", "send"]

Combine = Literal["overwrite", "sum", "max", "min", "and", "or"]
_COMBINE: dict[Combine, int] = {"overwrite": 100, "sum": 0, "max": 1, "min": 2, "and": 4, "or": 5}
_DTYPES = (np.uint8, np.int32, np.float32)
_ANY_NDIM = tuple(range(1, 33))
_MAX_DESTINATIONS = 2**31 - 1  # addresses, counts and offsets are int32


def _addresses(address: ArrayLike, size: int, machine: Machine, bound: str) -> tuple:
    data, host = core.field(address, "address", machine, ndims=_ANY_NDIM, dtypes=(np.int32,))
    if host:
        assert isinstance(address, np.ndarray)  # field() reports host for NumPy input only
        low, high = int(np.min(address)), int(np.max(address))
    else:
        low, high = (int(_reduce.reduce(data, op, machine=machine).get()) for op in ("min", "max"))
    if low < 0 or high >= size:
        raise InputValueError(f"address must lie in [0, {size - 1}] ({bound}), got values in [{low}, {high}]")
    return data, host


def _shape(size) -> tuple[int, ...]:
    """The destination shape from an int or a sequence of ints, each >= 1."""
    if isinstance(size, (list, tuple)):
        if not size:
            raise InputValueError("size must be a positive integer or a non-empty shape, got ()")
        return tuple(check_int(s, "size", minimum=1) for s in size)
    return (check_int(size, "size", minimum=1),)


def _fill(fill, dtype: np.dtype):
    """``fill`` as a scalar of ``dtype``, refused where the conversion would change it."""
    if dtype.kind == "f":
        # NaN and infinities are float32 values (a "no message" marker); finite values must not overflow.
        if isinstance(fill, (float, np.floating)) and not math.isfinite(fill):
            return dtype.type(fill)
        largest = float(np.finfo(dtype).max)
        if not isinstance(fill, (bool, np.bool_)) and isinstance(fill, (int, float, np.number)) and abs(fill) > largest:
            raise InputValueError(f"fill must lie within float32's range (+-{largest:.3g}), or be NaN or an infinity, "
                                  f"got {fill}")
        return dtype.type(check_real(fill, "fill", minimum=-largest, maximum=largest))
    limits = np.iinfo(dtype)
    return dtype.type(check_int(fill, f"fill (for {dtype} values)", minimum=int(limits.min),
                                maximum=int(limits.max)))


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
    data, host = core.field(field, "field", machine, ndims=_ANY_NDIM, dtypes=_DTYPES)
    where, address_host = _addresses(address, data.size, machine, f"field has {data.size} elements")
    core.check_same_kind("field", host, "address", address_host)  # what comes back follows what went in
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
        The destination field's size (1-D) or shape; at most 2**31 - 1 destinations (int32 addresses),
        and as many as the device's memory holds.
    combine : {"overwrite", "sum", "max", "min", "and", "or"}
        How messages to one destination combine. "overwrite": the sender with the highest index wins.
        "sum": in ``values``' dtype, so integer sums wrap on overflow as the hardware's adds do (give wider
        values, int32 for uint8 messages, where they may). "max" / "min" of floats pass over NaN, as
        NumPy's fmax and fmin (and :func:`vmcl.cm.reduce.reduce`) do: NaN only where every message is NaN.
        "and" / "or": bitwise, integer types only (logical on 0/1 fields).
    fill : scalar
        What destinations that receive no message hold: an integer within the range of integer
        ``values``, a real number (or NaN, or an infinity) within float32's range for float32 ones.

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
    data, host = core.field(values, "values", machine, ndims=_ANY_NDIM, dtypes=_DTYPES)
    shape = _shape(size)
    combine = check_choice(combine, "combine", _COMBINE)
    if combine in ("and", "or") and data.dtype == np.float32:
        raise InputTypeError(f"combine={combine!r} needs integer values, got float32")
    fill_value = _fill(fill, data.dtype)
    destinations = math.prod(shape)
    if destinations > _MAX_DESTINATIONS:
        raise InputValueError(f"size must hold at most {_MAX_DESTINATIONS} destinations (int32 addresses), "
                              f"got {size!r}")
    int32 = np.dtype(np.int32).itemsize
    # counts, offsets and cursor per destination, the output, and one slot per sender.
    machine.require_memory(f"router.send to {destinations} destinations",
                           destinations * (3 * int32 + data.dtype.itemsize) + data.size * int32,
                           max(destinations, data.size) * max(int32, data.dtype.itemsize))
    where, address_host = _addresses(address, destinations, machine, f"size gives {destinations} destinations")
    core.check_same_kind("values", host, "address", address_host)  # what comes back follows what went in
    if where.shape != data.shape:
        raise InputValueError(f"address must have the shape of values {data.shape}, got {where.shape}")
    n = data.size
    defines = dict(COMBINE_OP=_COMBINE[combine], **type_defines(data.dtype))
    counts = machine.full(destinations, np.int32, 0)
    offsets = machine.empty(destinations, np.int32)
    cursor = machine.empty(destinations, np.int32)
    slots = machine.empty(n, np.int32)
    out = machine.empty(shape, data.dtype)
    queue = machine.queue
    machine.launch(machine.kernel("router", "count_senders", **defines), (n,), where, counts, np.int64(n))
    exclusive_sum_into(machine, counts, offsets)
    # pyopencl's overloads type a device copy's ends as Buffer, but enqueue_copy dispatches on
    # MemoryObjectHolder, so the pool's PooledBuffers (not Buffer subclasses) are copied alike.
    cl.enqueue_copy(queue, device_memory(cursor), device_memory(offsets),  # type: ignore[call-overload]
                    byte_count=offsets.nbytes)
    machine.launch(machine.kernel("router", "place_senders", **defines), (n,), where, cursor, slots, np.int64(n))
    machine.launch(machine.kernel("router", "sort_buckets", **defines), (destinations,), offsets, counts, slots,
                   np.int64(destinations))
    machine.launch(machine.kernel("router", "combine_buckets", **defines), (destinations,), data, offsets, counts,
                   slots, out, fill_value, np.int64(destinations))
    return result(out, host)
