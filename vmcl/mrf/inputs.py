"""The checked inputs of a restoration or a draw of the line-process MRF, on the device.

:func:`vmcl.mrf.restore` and :func:`vmcl.mrf.sample` take the same arguments (the data, its confidence,
the brightness edges, a start) from NumPy or the device; one check here names each argument the same
way in both.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import field
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf.energy import EnergyModel
from vmcl.mrf.lattice import Lattice

__all__ = ["device_data", "device_pixels", "lattice_of"]


def device_data(data: Any, machine: Machine, name: str = "data") -> tuple[cl_array.Array, bool]:
    """``data`` (a cue, or a warm start named ``name``) as a float32 device array, (H, W) or (H, W, C)
    with C in 1..4 and H, W >= 2, and whether it came from the host."""
    if isinstance(data, np.ndarray):
        if data.dtype.kind not in "iuf":
            raise InputTypeError(f"{name} must be a real array (integer or float), got dtype {data.dtype}")
        data = data.astype(np.float32)
    g, host = field(data, name, machine, ndims=(2, 3), dtypes=(np.float32,))
    if g.ndim == 3 and not 1 <= g.shape[2] <= 4:
        raise InputValueError(f"{name} must be (H, W) or (H, W, C) with C in 1..4, got shape {g.shape}")
    if min(g.shape[:2]) < 2:
        raise InputValueError(f"{name} must be at least 2 x 2 pixels, got shape {g.shape}")
    return g, host


def device_pixels(x: Any, name: str, shape: tuple[int, int], dtype: type, machine: Machine) -> cl_array.Array | None:
    """An optional (H, W) per-pixel input on the device: confidence (float32) or edges (uint8)."""
    if x is None:
        return None
    if isinstance(x, np.ndarray):
        if x.shape != shape:
            raise InputValueError(f"{name} must have the data's shape {shape}, got {x.shape}")
        if dtype is np.uint8:
            if x.dtype != np.bool_ and x.dtype.kind not in "iu":
                raise InputTypeError(f"{name} must be boolean or integer (non-zero: an edge), got {x.dtype}")
            return machine.to_device((x != 0).astype(np.uint8))
        if x.dtype.kind not in "iuf":
            raise InputTypeError(f"{name} must be real, got dtype {x.dtype}")
        if not np.all(np.isfinite(x)) or np.any(x < 0):
            raise InputValueError(f"{name} must be finite and >= 0")
        return machine.to_device(x.astype(np.float32))
    device, _ = field(x, name, machine, ndims=(2,), dtypes=(dtype,))
    if device.shape != shape:
        raise InputValueError(f"{name} must have the data's shape {shape}, got {device.shape}")
    return device


def lattice_of(data: Any, confidence: Any, edges: Any, start: Any, kind: str, model: EnergyModel,
               machine: Machine) -> tuple[Lattice, bool]:
    """The checked arguments on the device as a :class:`Lattice`, and whether the data came from the host.

    The data as :func:`device_data` takes it (scalar for the constant kind), the confidence and edges as
    :func:`device_pixels` takes them, the start of the data's shape.
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
    return Lattice(machine, g, gamma, e, kind, model, first), host
