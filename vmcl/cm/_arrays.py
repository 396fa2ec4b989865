"""Argument checking and host/device dispatch shared by the primitives.

NumPy in gives NumPy out; a device array in gives a device array out, so a pipeline keeps its fields on
the device between stages. Inputs are checked at the door with errors that name the argument.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import pyopencl.array as cl_array

from vmcl.machine import Machine, default_machine

ArrayLike = np.ndarray | cl_array.Array

# Host dtypes that convert to int32 or float32 without changing any value.
_EXACT_TO_INT32 = {np.dtype(t) for t in (np.bool_, np.int8, np.uint8, np.int16, np.uint16, np.int32)}
_EXACT_TO_FLOAT32 = {np.dtype(np.float16), np.dtype(np.float32)}


def machine_for(machine: Machine | None) -> Machine:
    if machine is not None and not isinstance(machine, Machine):
        raise TypeError(f"machine must be a vmcl.Machine or None, got {type(machine).__name__}")
    return machine if machine is not None else default_machine()


@functools.cache
def _dtypes(dtypes: tuple) -> tuple[np.dtype, ...]:
    return tuple(np.dtype(t) for t in dtypes)


class _DtypeNames:
    """The accepted dtypes as text, formatted only when an error message needs them."""

    def __init__(self, accepted: tuple[np.dtype, ...]) -> None:
        self.accepted = accepted

    def __str__(self) -> str:
        return " or ".join(str(d) for d in self.accepted)


def field(x: Any, name: str, machine: Machine, *, ndims: tuple[int, ...],
          dtypes: tuple[type, ...] = (np.int32, np.float32)) -> tuple[cl_array.Array, bool]:
    """Check ``x`` and return it as a device array with whether it came from the host.

    Host arrays of a narrower integer (or float16) dtype are widened exactly to int32 (float32) when
    that dtype is accepted; device arrays must already have an accepted dtype, since converting them
    would hide a copy.
    """
    accepted = _dtypes(dtypes)
    names = _DtypeNames(accepted)
    if isinstance(x, cl_array.Array):
        if x.context != machine.context:
            raise ValueError(f"{name} lives on another OpenCL context than the machine's ({machine!r})")
        if x.dtype not in accepted:
            raise TypeError(f"{name} must have dtype {names}, got {x.dtype}")
        if not x.flags.c_contiguous:
            raise ValueError(f"{name} must be a C-contiguous device array")
        if x.offset:
            # Kernels get the buffer itself, which starts before a view's first element.
            raise ValueError(f"{name} must not be a device view with an offset (copy it: {name}.copy())")
        host = False
        device = x
    elif isinstance(x, np.ndarray):
        host = True
        dtype = x.dtype
        if dtype not in accepted:
            if np.dtype(np.int32) in accepted and dtype in _EXACT_TO_INT32:
                dtype = np.dtype(np.int32)
            elif np.dtype(np.float32) in accepted and dtype in _EXACT_TO_FLOAT32:
                dtype = np.dtype(np.float32)
            else:
                raise TypeError(f"{name} must have dtype {names} (convert with .astype), got {x.dtype}")
        device = None
    else:
        raise TypeError(f"{name} must be a NumPy array or a pyopencl.array.Array, got {type(x).__name__}")
    if x.ndim not in ndims:
        wanted = " or ".join(str(n) for n in ndims)
        raise ValueError(f"{name} must have {wanted} dimensions, got shape {x.shape}")
    if x.size == 0:
        raise ValueError(f"{name} must not be empty, got shape {x.shape}")
    if device is None:
        device = machine.to_device(np.asarray(x, dtype=dtype))
    return device, host


def flags_field(segments: Any, shape: tuple[int, ...], name: str, machine: Machine) -> cl_array.Array:
    """Segment-start flags as a uint8 device array of the given shape (non-zero marks a start)."""
    if isinstance(segments, np.ndarray):
        if segments.shape != shape:
            raise ValueError(f"{name} must have the data's shape {shape}, got {segments.shape}")
        if segments.dtype != np.bool_ and not np.issubdtype(segments.dtype, np.integer):
            raise TypeError(f"{name} must be boolean or integer flags, got {segments.dtype}")
        return machine.to_device((segments != 0).astype(np.uint8))
    if isinstance(segments, cl_array.Array):
        if segments.shape != shape:
            raise ValueError(f"{name} must have the data's shape {shape}, got {segments.shape}")
        if segments.dtype not in (np.dtype(np.uint8), np.dtype(np.bool_)):
            raise TypeError(f"{name} on the device must be uint8 or bool, got {segments.dtype}")
        return segments
    raise TypeError(f"{name} must be a NumPy array, a pyopencl.array.Array or None, got {type(segments).__name__}")


def result(device: cl_array.Array, host: bool) -> ArrayLike:
    return device.get() if host else device


def type_defines(dtype: np.dtype) -> dict[str, Any]:
    """The -D defines that specialise a kernel family for int32 or float32."""
    if dtype == np.float32:
        return {"T": "float", "T_IS_FLOAT": 1}
    if dtype == np.int32:
        return {"T": "int", "T_IS_FLOAT": 0}
    if dtype == np.uint8:
        return {"T": "uchar", "T_IS_FLOAT": 0}
    raise TypeError(f"no kernel type for dtype {dtype}")


def check_int(value: Any, name: str, *, minimum: int | None = None) -> int:
    """``value`` as an int; TypeError naming ``name`` for a non-integer (bool included), ValueError below
    ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return int(value)


def normalise_axis(axis: int, ndim: int, allowed: tuple[int, ...], name: str = "axis") -> int:
    """``axis`` as a negative index, checked against the allowed (negative) axes."""
    check_int(axis, name)
    if not -ndim <= axis < ndim:
        raise ValueError(f"{name}={axis} is out of range for an array of {ndim} dimensions")
    negative = int(axis) - ndim if axis >= 0 else int(axis)
    if negative not in allowed:
        raise ValueError(f"{name}={axis} is not supported: scans run along the last axis (rows) or, for "
                         f"2-D and 3-D fields, the second to last (columns)")
    return negative
