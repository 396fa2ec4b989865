"""The checked inputs of a restoration or a draw of the line-process MRF, on the device.

:func:`vmcl.mrf.restore` and :func:`vmcl.mrf.sample` take the same arguments (the data, its confidence,
the brightness edges, a start) from NumPy or the device; one check here names each argument the same
way in both, and checks the values of device arrays as it checks those of host arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import reduce as cm_reduce
from vmcl.cm.core import check_unmasked, field
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf.checks import check_weights
from vmcl.mrf.energy import EnergyModel
from vmcl.mrf.lattice import Lattice

__all__ = ["device_data", "device_pixels", "lattice_of"]


def device_data(data: Any, machine: Machine, name: str = "data") -> tuple[cl_array.Array, bool]:
    """``data`` (a cue, or a warm start named ``name``) as a float32 device array, (H, W) or (H, W, C)
    with C in 1..4 and H, W >= 2, and whether it came from the host.

    NaN marks a missing value; an infinity is refused (it is no value, and no missing one either), and so
    is a host value beyond float32's range, which the device would hold as one."""
    if isinstance(data, np.ndarray):
        check_unmasked(data, name)
        if data.dtype.kind not in "iuf":
            raise InputTypeError(f"{name} must be a real array (integer or float), got dtype {data.dtype}")
        source = data
        with np.errstate(over="ignore"):  # a value beyond float32's range is refused just below
            data = data.astype(np.float32)
        if source.dtype.kind == "f" and np.isinf(data).any():
            if np.isinf(source).any():
                raise InputValueError(f"{name} must not hold infinities (NaN marks a missing value)")
            raise InputValueError(f"{name} has values beyond float32's range, in which the restoration computes")
    g, host = field(data, name, machine, ndims=(2, 3), dtypes=(np.float32,))
    if g.ndim == 3 and not 1 <= g.shape[2] <= 4:
        raise InputValueError(f"{name} must be (H, W) or (H, W, C) with C in 1..4, got shape {g.shape}")
    if min(g.shape[:2]) < 2:
        raise InputValueError(f"{name} must be at least 2 x 2 pixels, got shape {g.shape}")
    if not host:
        # min and max skip NaN (a missing value), so they find an infinity anywhere.
        low, high = cm_reduce.extremes(g, machine=machine)
        if math.isinf(low) or math.isinf(high):
            raise InputValueError(f"{name} must not hold infinities (NaN marks a missing value)")
    return g, host


def device_pixels(x: Any, name: str, shape: tuple[int, int], dtype: type, machine: Machine) -> cl_array.Array | None:
    """An optional (H, W) per-pixel input on the device: confidence (float32, finite and >= 0, whether it
    comes from the host or the device) or edges (uint8)."""
    if x is None:
        return None
    if isinstance(x, np.ndarray):
        check_unmasked(x, name)
        if x.shape != shape:
            raise InputValueError(f"{name} must have the data's shape {shape}, got {x.shape}")
        if dtype is np.uint8:
            if x.dtype != np.bool_ and x.dtype.kind not in "iu":
                raise InputTypeError(f"{name} must be boolean or integer (non-zero: an edge), got {x.dtype}")
            return machine.to_device((x != 0).astype(np.uint8))
        if x.dtype.kind not in "iuf":
            raise InputTypeError(f"{name} must be real, got dtype {x.dtype}")
        return machine.to_device(np.asarray(check_weights(x, name, machine), np.float32))
    device, _ = field(x, name, machine, ndims=(2,), dtypes=(dtype,))
    if device.shape != shape:
        raise InputValueError(f"{name} must have the data's shape {shape}, got {device.shape}")
    if dtype is np.float32:
        check_weights(device, name, machine)
    return device


def lattice_of(data: Any, confidence: Any, edges: Any, start: Any, kind: str, model: EnergyModel,
               machine: Machine, what: str,
               solver_buffers: Callable[[str, int, int], tuple[int, ...]] | None = None) -> tuple[Lattice, bool]:
    """The checked arguments on the device as a :class:`Lattice`, and whether the data came from the host.

    The data as :func:`device_data` takes it (scalar for the constant kind), the confidence and edges as
    :func:`device_pixels` takes them, the start of the data's shape. Before the lattice is made, the
    device memory it and the solver need (``solver_buffers(kind, ncomp, nlevels)``: float32 words per site
    of each of the solver's own buffers) is checked with :meth:`vmcl.Machine.require_memory`, naming
    ``what``. Refuses a weight ``model.alpha * confidence`` beyond float32's range.
    """
    g, host = device_data(data, machine)
    height, width = g.shape[:2]
    if kind == "constant" and g.ndim == 3 and g.shape[2] != 1:
        raise InputValueError(f"kind='constant' takes scalar data (H, W), got shape {g.shape}")
    gamma = device_pixels(confidence, "confidence", (height, width), np.float32, machine)
    e = device_pixels(edges, "edges", (height, width), np.uint8, machine)
    first = None
    if start is not None:
        first, _ = device_data(start, machine, "start")
        if first.shape != g.shape:
            raise InputValueError(f"start must have the data's shape {g.shape}, got {first.shape}")
    ncomp = 1 if g.ndim == 2 else g.shape[2]
    nlevels = 1
    if kind == "constant":
        nlevels = model.levels if isinstance(model.levels, int) else len(model.levels)
    words = () if solver_buffers is None else solver_buffers(kind, ncomp, nlevels)
    total, largest = Lattice.memory(g.shape, kind, model, confidence=gamma is not None, edges=e is not None,
                                    start=first is not None, solver_words=words)
    detail = f" with {nlevels} levels" if kind == "constant" else ""
    machine.require_memory(f"{what} of a {height} x {width} x {ncomp} field ({kind}{detail})", total, largest)
    lattice = Lattice(machine, g, gamma, e, kind, model, first)
    if math.isinf(lattice.strongest):
        raise InputValueError(f"model.alpha ({model.alpha:g}) times the confidence exceeds float32's range, in "
                              "which the restoration weighs its data: lower one of them")
    return lattice, host
