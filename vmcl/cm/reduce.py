"""Global reductions and histograms of a field.

Seed section "The Connection Machine": the machine returns to the host the global maximum, minimum,
sum, logical AND and logical OR of a field. Histograms, global or per tile, serve the noise estimate of
"Edge detection" (Noise Estimation), where the paper had "success with ... local histograms".
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm.core import (
    ArrayLike,
    bool_as_bytes,
    check_choice,
    check_int,
    check_real,
    field,
    machine_for,
    result,
    type_defines,
)
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["ReduceOp", "extremes", "histogram", "histogram_to_top", "reduce"]

ReduceOp = Literal["sum", "max", "min", "and", "or"]
_OPS = {"sum": 0, "max": 1, "min": 2, "and": 4, "or": 5}
_MIN_CHUNK = 1024
_DTYPES = (np.uint8, np.int32, np.float32)
_ANY_NDIM = tuple(range(33))


def reduce(x: ArrayLike, op: ReduceOp = "sum", *, machine: Machine | None = None):
    """Reduce a whole field to one value.

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array of any shape; bool, uint8, int32 or float32
        Narrower host integers are widened exactly (bool to uint8 values 0/1, others to int32).
    op : {"sum", "max", "min", "and", "or"}
        "and" and "or" are logical: non-zero counts as true.
    machine : vmcl.Machine, optional

    Returns
    -------
    For host input a NumPy scalar: sum gives int64 for integer fields (no overflow) and float32 for
    float32 fields; max and min keep the dtype; and/or give bool. For device input the same value as a
    0-d device array (int64, float32, the dtype, or uint8 0/1 for and/or), so it can stay on the device.

    Notes
    -----
    Deterministic on a given device: each chunk is reduced in sixteen lanes folded in lane order, then the
    chunk results in order (the chunk size follows the device's compute units, so a float sum may differ
    in the last bits between devices). Float sums use Kahan compensation throughout. NaN propagates through "sum" but is
    ignored by "max" and "min" (OpenCL's fmax/fmin rule): their result is NaN only where every element is.
    """
    machine = machine_for(machine)
    check_choice(op, "op", sorted(_OPS))
    data, host = field(bool_as_bytes(x), "x", machine, ndims=_ANY_NDIM, dtypes=_DTYPES)
    defines = type_defines(data.dtype)
    if op == "sum":
        accumulator: np.dtype = np.dtype(np.float32) if data.dtype == np.float32 else np.dtype(np.int64)
    elif op in ("and", "or"):
        accumulator = np.dtype(np.uint8)
    else:
        accumulator = data.dtype
    acc_name = {np.dtype(np.float32): "float", np.dtype(np.int64): "long", np.dtype(np.uint8): "uchar",
                np.dtype(np.int32): "int"}[accumulator]
    defines.update(OP=_OPS[op], ACC=acc_name)
    n = data.size
    # Enough chunks for every compute unit, each a multiple of 16 (the kernel's vector width).
    chunk = max(_MIN_CHUNK, -(-math.ceil(n / (machine.compute_units * 16)) // 16) * 16)
    count = math.ceil(n / chunk)
    partial = machine.empty(count, accumulator)
    compensation = machine.empty(count, accumulator)
    out = machine.empty((), accumulator)
    machine.launch(machine.kernel("reduce", "reduce_chunks", **defines), (count,), data, partial, compensation,
                   np.int64(n), np.int64(chunk))
    machine.launch(machine.kernel("reduce", "reduce_partials", **defines), (1,), partial, compensation, out,
                   np.int64(count))
    if not host:
        return out
    value = out.get()[()]
    return np.bool_(value) if op in ("and", "or") else value


def extremes(x: ArrayLike, *, machine: Machine | None = None) -> tuple[float, float]:
    """A field's minimum and maximum, as :func:`reduce` finds them ("min", "max"), read together.

    Both reductions are enqueued before either is read, so a device field costs one wait for the queue, not
    two (each wait leaves the device idle while the host goes on).

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array, as :func:`reduce` takes it
    machine : vmcl.Machine, optional

    Returns
    -------
    (float, float)
        The minimum and the maximum (NaN both where every element is NaN).
    """
    machine = machine_for(machine)
    found = [reduce(x, op, machine=machine) for op in ("min", "max")]
    low, high = (float(value.get() if isinstance(value, cl_array.Array) else value) for value in found)
    return low, high


def histogram(x: ArrayLike, bins: int, range: tuple[float, float], *, tile: tuple[int, int] | None = None,
              machine: Machine | None = None) -> ArrayLike:
    """Counts of values in ``bins`` equal bins over ``range``, for the whole field or per tile.

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array; uint8, int32 or float32
        Any shape for the global histogram; 2-D (H, W) when ``tile`` is given.
    bins : int
        Number of bins (1 to what the device's local memory holds, 4096 or more on every device seen).
    range : (lo, hi)
        lo < hi, finite. Bin of v: floor((v - lo) * bins / (hi - lo)) in float32, with v == hi in the last
        bin; values outside [lo, hi] and NaN are not counted. This is ``np.histogram``'s rule except that
        the bin index is computed in float32 (an integer field's values taken relative to floor(lo)
        exactly first), so a value within float32 rounding of an inner edge may land in the
        neighbouring bin. Ranges too narrow or too wide for float32's exponent (bins /
        (hi - lo) or hi - lo overflowing) are binned by the same rule as if the exponent were unbounded.
    tile : (th, tw), optional
        Per-tile histograms over tiles of th x tw pixels, row-major from the top left; tiles at the right
        and bottom edges hold what is left (smaller tiles).
    machine : vmcl.Machine, optional

    Returns
    -------
    int32 counts: shape (bins,), or (ceil(H/th), ceil(W/tw), bins) with ``tile``. Host in, host out.
    """
    machine = machine_for(machine)
    data, host = _histogram_field(x, bins, tile, machine)
    try:
        lo, hi = (float(v) for v in range)
    except (TypeError, ValueError):
        raise InputTypeError(f"range must be a pair of numbers (lo, hi), got {range!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise InputValueError(f"range must be finite with lo < hi, got {range!r}")
    return result(_count(machine, data, bins, lo, hi, None, tile), host)


def histogram_to_top(x: cl_array.Array, bins: int, top: cl_array.Array, *, lo: float = 0.0,
                     tile: tuple[int, int] | None = None, machine: Machine | None = None) -> cl_array.Array:
    """:func:`histogram` over [lo, top], where ``top`` is a float32 device scalar (a field's maximum from
    :func:`reduce`, say), read on the device: the host never waits for it.

    Parameters
    ----------
    x : pyopencl.array.Array; uint8, int32 or float32
        As for :func:`histogram`.
    bins : int
    top : 0-d or 1-element float32 pyopencl.array.Array
        The upper end of the range; when it is not above ``lo`` (a field of zeros) or is NaN, the range
        is [lo, lo + 1]. For an integer ``x`` (whose maximum float32 may round down past 2^24), values up
        to the next float32 above ``top`` are counted. An infinite ``top`` makes the bins infinitely
        wide: every value from ``lo`` on is counted in bin 0 (the device's value is not read on the
        host, so it cannot be refused there).
    lo : float
        Finite.
    tile, machine
        As for :func:`histogram`.

    Returns
    -------
    int32 device counts, as :func:`histogram` returns them; the bins are those :func:`histogram` gives
    for the range (lo, hi) with hi the value of ``top``.
    """
    machine = machine_for(machine)
    if not isinstance(x, cl_array.Array):
        raise InputTypeError(f"x must be a pyopencl.array.Array, got {type(x).__name__}")
    if not isinstance(top, cl_array.Array) or top.dtype != np.float32 or top.size != 1:
        raise InputTypeError("top must be a one-element float32 pyopencl.array.Array")
    lo = check_real(lo, "lo")
    data, _ = _histogram_field(x, bins, tile, machine)
    return _count(machine, data, bins, lo, lo + 1.0, top, tile)


def _histogram_field(x, bins, tile, machine: Machine) -> tuple[cl_array.Array, bool]:
    data, host = field(bool_as_bytes(x), "x", machine, ndims=(2,) if tile is not None else _ANY_NDIM,
                       dtypes=_DTYPES)
    check_int(bins, "bins")
    local_bins = machine.device.local_mem_size // 4 - 16
    if not 1 <= bins <= local_bins:
        raise InputValueError(f"bins must be between 1 and {local_bins} on this device, got {bins}")
    if tile is not None and (not isinstance(tile, tuple) or len(tile) != 2
                             or not all(isinstance(t, (int, np.integer)) and t >= 1 for t in tile)):
        raise InputValueError(f"tile must be a pair of positive integers (th, tw), got {tile!r}")
    return data, host


def _count(machine: Machine, data: cl_array.Array, bins: int, lo: float, hi: float,
           top: cl_array.Array | None, tile) -> cl_array.Array:
    """The histogram kernel over [lo, hi], or over [lo, top] read on the device when ``top`` is given."""
    if tile is None:
        width = data.shape[-1]
        height = data.size // width
        # Bands of rows, each counted by one work-group and added into the single histogram; on a CPU
        # two per core, since each band also clears and adds a whole histogram.
        band = max(1, math.ceil(height / (machine.compute_units * (2 if machine.is_cpu else 8))))
        th, tw, accumulate = band, width, True
    else:
        height, width = data.shape
        th, tw, accumulate = int(tile[0]), int(tile[1]), False
    tiles_y, tiles_x = math.ceil(height / th), math.ceil(width / tw)
    shape = (bins,) if accumulate else (tiles_y, tiles_x, bins)
    counts_bytes = 4 * math.prod(shape)
    machine.require_memory(f"{tiles_y * tiles_x} histograms of {bins} bins", data.nbytes + counts_bytes,
                           max(data.nbytes, counts_bytes))
    out = machine.full(shape, np.int32, 0) if accumulate else machine.empty(shape, np.int32)
    local = 1 if machine.is_cpu else min(256, machine.device.max_work_group_size)
    # A one-work-item group counts without atomics (a CPU runs each group on one thread anyway).
    defines = dict(OP=0, ACC="int", SHARED_COUNTS=int(local > 1), TO_TOP=int(top is not None),
                   **type_defines(data.dtype))
    # Integers are binned relative to the range's start, taken exactly (kernels/reduce.cl, RELATIVE).
    base = 0 if data.dtype.kind == "f" else int(np.clip(math.floor(lo), -2**31, 2**31 - 1))
    lo, hi = lo - base, hi - base
    # A range too narrow or too wide for float32 overflows here; the kernel rescales such ranges.
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        scale = np.float32(bins) / (np.float32(hi) - np.float32(lo))
    kernel = machine.kernel("reduce", "histogram_tiles", **defines)
    machine.launch(kernel, (tiles_y * tiles_x * local,), data, out, cl.LocalMemory(4 * bins),
                   top if top is not None else out, np.int64(width), np.int64(height), np.int64(th),
                   np.int64(tw), np.int64(tiles_x), np.float32(lo), np.float32(hi), np.float32(scale),
                   np.int32(bins), np.int32(accumulate), np.int64(base), local_size=(local,))
    return out
