"""Scans and grid-scans: the Connection Machine's plus-, max-, min- and copy-scan, segmented.

Seed section "Powerful primitive operations" (Scanning): a scan with a binary associative operator
returns [a0, a0+a1, ..., a0+...+a(n-1)]; segment bits restart it; grid-scans run along the rows or the
columns of the NEWS grid, and ``box_sum`` is the paper's window sum built from them.

References
----------
G. E. Blelloch, "Scans as primitive parallel operations", ICPP 1987.
W. D. Hillis and G. L. Steele, "Data parallel algorithms", CACM 29(12), 1986.
"""

from __future__ import annotations

import math
from typing import Literal, overload

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
from pyopencl import cltypes

from vmcl.cm.core import (
    ArrayLike,
    check_bool,
    check_choice,
    check_int,
    device_memory,
    field,
    flags_field,
    machine_for,
    normalise_axis,
    output_array,
    result,
    type_defines,
)
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = [
    "BOX_SEGMENT",
    "COLUMN_VEC",
    "METHODS",
    "OPS",
    "ROW_ILP",
    "Method",
    "Op",
    "box_sum",
    "column_groups",
    "exclusive_sum_into",
    "scan",
    "scan_rows_into",
]

Op = Literal["plus", "max", "min", "copy"]
Method = Literal["work_efficient", "hillis_steele"]

OPS: dict[Op, int] = {"plus": 0, "max": 1, "min": 2, "copy": 3}
METHODS: tuple[Method, ...] = ("work_efficient", "hillis_steele")
COLUMN_VEC = 16
BOX_SEGMENT = 16
"""On a GPU, box_sum's work-items each walk this many outputs of a line (at least the window's width)."""
ROW_ILP = 4  # chunks per work-item in the row kernels (ILP in kernels/scan.cl)
_MIN_CHUNK = 4096
# On a CPU one work-item sums a short line faster than two more launches let two share it. Measured on
# PoCL (2 cores), an exclusive sum waited for: 16 Ki elements 227 us in one chunk, 268 us in chunks;
# 32 Ki 274 against 301; 64 Ki 382 against 328. Lines under 64 Ki elements are not cut.
_MIN_CHUNK_CPU = 32768


@overload
def scan(x: np.ndarray, *, op: Op = "plus", axis: int = -1, exclusive: bool = False,
         segments: ArrayLike | None = None, method: Method = "work_efficient",
         machine: Machine | None = None) -> np.ndarray: ...
@overload
def scan(x: cl_array.Array, *, op: Op = "plus", axis: int = -1, exclusive: bool = False,
         segments: ArrayLike | None = None, method: Method = "work_efficient",
         machine: Machine | None = None) -> cl_array.Array: ...
def scan(x: ArrayLike, *, op: Op = "plus", axis: int = -1, exclusive: bool = False,
         segments: ArrayLike | None = None, method: Method = "work_efficient",
         machine: Machine | None = None) -> ArrayLike:
    """Inclusive or exclusive scan of ``x`` along rows (axis -1) or columns (axis -2).

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array, 1-D, 2-D or 3-D, int32 or float32
        The field; a 3-D array is a stack of planes scanned plane by plane. Narrower host integer
        dtypes (bool, int8, uint8, int16, uint16) are widened exactly to int32.
    op : {"plus", "max", "min", "copy"}
        The associative operator. "copy" broadcasts the first value of each segment.
    axis : int
        -1 (along rows, the only choice for 1-D) or -2 (along columns).
    exclusive : bool
        Each element gets the scan of the elements before it in its segment; the first element of a
        segment gets the identity (0 for plus, -inf / INT_MIN for max, +inf / INT_MAX for min, 0 for
        copy).
    segments : array of bool or int, same shape as ``x``, optional
        Non-zero marks the first element of a segment; the scan restarts there. Every line starts a
        segment anyway.
    method : {"work_efficient", "hillis_steele"}
        "work_efficient" (default, faster): each line is cut into chunks scanned serially by one
        work-item each, after a pass over chunk totals gives each chunk its carry; O(n) work. Column
        scans take 16 columns per work-item so each row step is one contiguous vector access.
        "hillis_steele": the per-processor algorithm, ceil(log2 n) steps each combining with the
        element 2^k before; O(n log n) work.
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``x`` (after the exact widening above).

    Notes
    -----
    Float max and min pass over NaN, as NumPy's fmax and fmin do: an inclusive scan is
    ``np.fmax.accumulate`` (``fmin``) within each segment, NaN only where every element so far is NaN, with
    either method and along either axis; an exclusive scan's element after only NaNs is NaN.

    Float sums accumulate in float32 serially within each chunk, and chunk totals are added as carries,
    so the rounding differs from a serial loop's; it is no worse than ``np.cumsum``'s in float32
    (relative error against a float64 sum, on uniform values). Integer plus-scans wrap
    on int32 overflow, as the hardware does.
    """
    machine = machine_for(machine)
    data, host = field(x, "x", machine, ndims=(1, 2, 3))
    axis = normalise_axis(axis, data.ndim, (-1,) if data.ndim == 1 else (-1, -2))
    op = check_choice(op, "op", OPS)
    method = check_choice(method, "method", METHODS)
    exclusive = check_bool(exclusive, "exclusive")
    flags = None if segments is None else flags_field(segments, data.shape, "segments", machine)
    out = machine.empty(data.shape, data.dtype)
    defines = dict(type_defines(data.dtype), OP=OPS[op], SEGMENTED=int(flags is not None),
                   EXCLUSIVE=int(bool(exclusive)))
    if method == "hillis_steele":
        _hillis_steele(machine, data, flags, out, axis, defines)
    elif axis == -1:
        scan_rows_into(machine, data, flags, out, defines)
    else:
        _scan_cols(machine, data, flags, out, defines)
    return result(out, host)


def _chunks(machine: Machine, lines: int, length: int) -> tuple[int, int]:
    """How many chunks to cut each line into, and their length, so every compute unit has work."""
    wanted = machine.compute_units * ROW_ILP * (8 if machine.is_cpu else 256)
    per_line = 1
    if lines < wanted:
        per_line = max(1, min(math.ceil(wanted / lines), length // (_MIN_CHUNK_CPU if machine.is_cpu else _MIN_CHUNK)))
    chunk = math.ceil(length / per_line)
    return math.ceil(length / chunk), chunk


def scan_rows_into(machine: Machine, data: cl_array.Array, flags: cl_array.Array | None,
                   out: cl_array.Array, defines: dict) -> None:
    """Work-efficient scan along the last axis of ``data`` into ``out`` (both C-contiguous)."""
    n = data.shape[-1]
    lines = data.size // n
    per_line, chunk = _chunks(machine, lines, n)
    n_chunks = lines * per_line
    work_items = math.ceil(n_chunks / ROW_ILP)
    flag_arg = flags if flags is not None else data
    dtype = data.dtype
    carry = carry_have = None
    if per_line > 1:
        total = machine.empty(n_chunks, dtype)
        restarts = machine.empty(n_chunks, np.uint8)
        carry = machine.empty(n_chunks, dtype)
        carry_have = machine.empty(n_chunks, np.uint8)
        machine.launch(machine.kernel("scan", "chunk_totals_rows", **defines), (work_items,),
                       data, flag_arg, total, restarts, np.int64(n), np.int64(chunk), np.int32(per_line),
                       np.int64(n_chunks))
        machine.launch(machine.kernel("scan", "chunk_carries", **defines), (lines,),
                       total, restarts, carry, carry_have, np.int32(per_line), np.int64(lines))
    machine.launch(machine.kernel("scan", "scan_rows", **defines), (work_items,),
                   data, flag_arg, out, carry if carry is not None else data,
                   carry_have if carry_have is not None else flag_arg,
                   np.int64(n), np.int64(chunk), np.int32(per_line), np.int32(per_line > 1), np.int64(n_chunks))


def column_groups(width: int) -> list[tuple[int, int, int]]:
    """(VEC, first column, work-items) per launch of a column kernel: full groups of 16 columns take
    the vector build, the remaining width % 16 columns the scalar one."""
    width = check_int(width, "width", minimum=0)
    n_vec = width // COLUMN_VEC
    groups = ((COLUMN_VEC, 0, n_vec), (1, n_vec * COLUMN_VEC, width - n_vec * COLUMN_VEC))
    return [group for group in groups if group[2]]


def exclusive_sum_into(machine: Machine, counts: cl_array.Array, out: cl_array.Array, *, pairs: bool = False) -> None:
    """Exclusive plus-scan of a flat int32 device array into ``out``: offsets from counts.

    With ``pairs``, the arrays hold (a, b) pairs in consecutive elements, and the a's and the b's are
    summed each on their own in the same passes: two scans for the launches of one.
    """
    for name, array in (("counts", counts), ("out", out)):
        if not isinstance(array, cl_array.Array):
            raise InputTypeError(f"{name} must be an int32 pyopencl array, got {type(array).__name__}")
        if array.dtype != np.int32:
            raise InputTypeError(f"{name} must be an int32 pyopencl array, got dtype {array.dtype}")
    if out.size != counts.size:
        raise InputValueError(f"out must have counts' {counts.size} elements, got {out.size}")
    if not pairs:
        scan_rows_into(machine, counts.reshape(counts.size), None, out.reshape(out.size),
                       dict(type_defines(np.dtype(np.int32)), OP=OPS["plus"], SEGMENTED=0, EXCLUSIVE=1))
        return
    if counts.size % 2 or out.size % 2:
        raise InputValueError(f"pairs need an even number of elements, got {counts.size} and {out.size}")
    # OpenCL's int2 adds componentwise, so the scan's kernels need nothing but the type.
    defines = {"T": "int2", "T_IS_FLOAT": 0, "T_IS_PAIR": 1, "OP": OPS["plus"], "SEGMENTED": 0, "EXCLUSIVE": 1}
    scan_rows_into(machine, counts.reshape(counts.size).view(cltypes.int2), None,
                   out.reshape(out.size).view(cltypes.int2), defines)


def _scan_cols(machine: Machine, data: cl_array.Array, flags: cl_array.Array | None,
               out: cl_array.Array, defines: dict) -> None:
    height, width = data.shape[-2], data.shape[-1]
    planes = data.size // (height * width)
    per_line, chunk = _chunks(machine, planes * width, height)
    flag_arg = flags if flags is not None else data
    dtype = data.dtype
    groups = column_groups(width)
    carry = carry_have = None
    if per_line > 1:
        n_chunks = planes * width * per_line
        total = machine.empty(n_chunks, dtype)
        restarts = machine.empty(n_chunks, np.uint8)
        carry = machine.empty(n_chunks, dtype)
        carry_have = machine.empty(n_chunks, np.uint8)
        for vec, col0, count in groups:
            machine.launch(machine.kernel("scan", "chunk_totals_cols", VEC=vec, **defines),
                           (count, per_line, planes), data, flag_arg, total, restarts,
                           np.int64(width), np.int64(height), np.int64(col0), np.int64(count),
                           np.int64(chunk), np.int32(per_line))
        machine.launch(machine.kernel("scan", "chunk_carries", **defines), (planes * width,),
                       total, restarts, carry, carry_have, np.int32(per_line), np.int64(planes * width))
    for vec, col0, count in groups:
        machine.launch(machine.kernel("scan", "scan_cols", VEC=vec, **defines), (count, per_line, planes),
                       data, flag_arg, out, carry if carry is not None else data,
                       carry_have if carry_have is not None else flag_arg,
                       np.int64(width), np.int64(height), np.int64(col0), np.int64(count), np.int64(chunk),
                       np.int32(per_line), np.int32(per_line > 1))


def _hillis_steele(machine: Machine, data: cl_array.Array, flags: cl_array.Array | None,
                   out: cl_array.Array, axis: int, defines: dict) -> None:
    n = data.shape[axis]
    stride = 1 if axis == -1 else data.shape[-1]
    size = data.size
    segmented = flags is not None
    step = machine.kernel("scan", "hillis_steele_step", **defines)
    exclusive = defines["EXCLUSIVE"]
    steps = max(1, math.ceil(math.log2(n))) if n > 1 else 0
    # Ping-pong between two buffers; the last step must land in `out` (or in the buffer the exclusive
    # shift reads from), so the first target is chosen by the parity of the step count.
    final = machine.empty(data.shape, data.dtype) if exclusive else out
    spare = machine.empty(data.shape, data.dtype)
    buffers = (final, spare) if steps % 2 == 1 else (spare, final)
    flag_buffers = ((machine.empty(data.shape, np.uint8), machine.empty(data.shape, np.uint8))
                    if segmented else (data, data))
    source, source_flags = data, flags if segmented else data
    if steps == 0:
        # pyopencl's overloads type a device copy's ends as Buffer, but enqueue_copy dispatches on
        # MemoryObjectHolder, so the pool's PooledBuffers (not Buffer subclasses) are copied alike. ``data``
        # may be the caller's array, from any allocator: its memory is passed on as it is.
        cl.enqueue_copy(machine.queue, device_memory(final), data.base_data,  # type: ignore[call-overload]
                        byte_count=data.nbytes)
    for k in range(steps):
        target, target_flags = buffers[k % 2], flag_buffers[k % 2]
        machine.launch(step, (size,), source, source_flags, target, target_flags,
                       np.int64(stride), np.int64(n), np.int64(1 << k), np.int64(size))
        source, source_flags = target, target_flags
    if exclusive:
        machine.launch(machine.kernel("scan", "shift_exclusive", **defines), (size,),
                       final, flags if segmented else data, out, np.int64(stride), np.int64(n), np.int64(size))


def _check_window_sums_fit(x: np.ndarray, window: int) -> None:
    """Refuse a host field whose window sums could overflow float32.

    The running sum that overflows to inf does not come back when the large values leave the window
    (inf - inf is NaN), so later, finite, sums would be lost; the bound is checked on the host, where
    it costs one pass over memory the upload reads anyway.
    """
    largest = float(np.max(np.abs(x), initial=0.0, where=np.isfinite(x)))
    if largest * window > float(np.finfo(np.float32).max):
        raise InputValueError(f"x holds values up to {largest:.3g}, whose sums over a {window}-pixel window "
                              "overflow float32; scale x down first")


@overload
def box_sum(x: np.ndarray, radius: int, *, axes: tuple[int, ...] | None = None, out: None = None,
            machine: Machine | None = None) -> np.ndarray: ...
@overload
def box_sum(x: cl_array.Array, radius: int, *, axes: tuple[int, ...] | None = None,
            out: cl_array.Array | None = None, machine: Machine | None = None) -> cl_array.Array: ...
def box_sum(x: ArrayLike, radius: int, *, axes: tuple[int, ...] | None = None,
            out: cl_array.Array | None = None, machine: Machine | None = None) -> ArrayLike:
    """Sum over the (2r+1) x (2r+1) window around every pixel, by grid-scans, in time independent of r.

    Parameters
    ----------
    x : ndarray or pyopencl.array.Array, 1-D, 2-D or 3-D, int32 or float32
        The field, or a stack of planes (d, y, x) summed plane by plane (stereo and motion sum every
        disparity plane at once).
    radius : int
        r >= 0; the window is 2r+1 wide along each summed axis.
    axes : tuple of int, optional
        The axes to sum along: (-2, -1) (the square window), (-1,) (rows only) or (-2,) (columns only).
        Default: (-2, -1), or (-1,) for a 1-D field (its only axis).
    out : pyopencl.array.Array, optional
        For device input: the array to write the sums into (:func:`vmcl.cm.core.output_array`).
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``x``.

    Notes
    -----
    Outside the field counts as zero, so windows that reach over a border sum fewer pixels (divide by
    ``box_sum`` of ones to get a mean). Each pass adds the element entering the window and subtracts
    the one leaving as it scans, which is the paper's difference of two scan values P[x+r] - P[x-r-1]
    fused into one pass: exact for int32 (wrapping on overflow), and for float32 within a relative
    error of about sqrt(n) * 2**-24 of the largest partial sum. A host float field whose window sums
    could overflow float32 is refused. For the same reason a NaN or infinity
    does not leave the window with its element: it spoils every later output of its row (and, in the
    column pass, of the columns below it). Replace non-finite values first; they are not checked here,
    since that would cost a pass of its own.

    On a CPU each work-item walks whole lines. On any other device each walks :data:`BOX_SEGMENT` outputs
    of a line (or the window's width, if wider), starting from its first window summed whole: a walk per
    line leaves most of a GPU idle. A NaN or infinity then spoils the later outputs of its segment, not
    of the whole line.
    """
    machine = machine_for(machine)
    data, host = field(x, "x", machine, ndims=(1, 2, 3))
    # A window as long as the line already sums all of it, so wider ones are cut to that (the same
    # sums) before the kernels' 64-bit index arithmetic sees them.
    radius = min(check_int(radius, "radius", minimum=0), max(data.shape))
    if axes is None:
        axes = (-1,) if data.ndim == 1 else (-2, -1)
    if not isinstance(axes, tuple):
        raise InputTypeError(f"axes must be a tuple such as (-2, -1), got {type(axes).__name__}")
    if not axes:
        raise InputValueError("axes must be a non-empty tuple such as (-2, -1), got ()")
    allowed = (-1,) if data.ndim == 1 else (-1, -2)
    wanted = {normalise_axis(a, data.ndim, allowed, "axes") for a in axes}
    if len(wanted) != len(axes):
        raise InputValueError(f"axes must not repeat an axis, got {axes!r}")
    if host and data.dtype.kind == "f" and data.size:
        assert isinstance(x, np.ndarray)  # field() reports host for NumPy input only
        # A window longer than the field sums the field's length, no more.
        _check_window_sums_fit(x, int(np.prod([min(2 * radius + 1, data.shape[a]) for a in wanted])))
    final = output_array(out, machine, data, host)
    defines = type_defines(data.dtype)
    width = data.shape[-1]
    r = np.int64(radius)
    source = data
    # A CPU walks each line whole (its cores are few, and a walk keeps its SIMD lanes busy); a GPU walks
    # short segments of the lines, many thousands at once (kernels/scan_box.cl, box_rows_segments).
    segment = np.int64(max(BOX_SEGMENT, 2 * radius + 1))
    if -1 in wanted:
        lines = data.size // width
        rows = final if -2 not in wanted else machine.empty(data.shape, data.dtype)
        if machine.is_cpu:
            # box_rows reads no VEC: built with the column pass's vector width it shares that pass's program
            # where both run (a window sum over rows and columns), one build fewer on a first run.
            machine.launch(machine.kernel("scan_box", "box_rows", VEC=COLUMN_VEC, **defines),
                           (math.ceil(lines / 4),), source, rows, np.int64(width), np.int64(lines), r)
        else:
            machine.launch(machine.kernel("scan_box", "box_rows_segments", VEC=1, **defines),
                           (math.ceil(width / segment), lines), source, rows, np.int64(width), np.int64(lines), r,
                           segment)
        source = rows
    if -2 in wanted:
        height = data.shape[-2]
        planes = data.size // (height * width)
        cols = final
        if machine.is_cpu:
            for vec, col0, count in column_groups(width):
                machine.launch(machine.kernel("scan_box", "box_cols", VEC=vec, **defines), (count, planes),
                               source, cols, np.int64(width), np.int64(height), np.int64(col0), np.int64(count), r)
        else:
            machine.launch(machine.kernel("scan_box", "box_cols_segments", VEC=1, **defines),
                           (width, math.ceil(height / segment), planes), source, cols, np.int64(width),
                           np.int64(height), r, segment)
        source = cols
    return result(source, host)
