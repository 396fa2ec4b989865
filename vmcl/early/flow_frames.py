"""The flow and the two frames a flow refinement reads (:mod:`vmcl.early.lucas_kanade`,
:mod:`vmcl.early.variational`): checked against each other, and the frames made grey and smoothed on the
device.

Differentiation is ill-posed (the seed's "Edge detection"), so a refinement that linearises brightness
constancy takes its gradients on frames smoothed by a Gaussian first; optionally less a wider Gaussian
(a difference of Gaussians, the seed's approximation of the Laplacian of a Gaussian), so that brightness
changes slower than it, such as an exposure change between the frames, break constancy less.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_same_kind,
    check_same_scale,
    check_unit_image,
    field,
    finite_float32,
)
from vmcl.early.filters import separable_gaussian
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["check_flow_frames", "smoothed_frames"]

_GAIN = {np.dtype(np.uint8): 1 / 255, np.dtype(np.uint16): 1 / 65535, np.dtype(np.float32): 1.0}
"""Brightness of each image type to [0, 1]."""


def check_flow_frames(flow: ArrayLike, frame0: ArrayLike, frame1: ArrayLike,
                      machine: Machine) -> tuple[cl_array.Array, bool]:
    """The flow (float32 (H, W, 2)) on the device and whether it came as a NumPy array, checked with its two
    frames: NumPy arrays with a NumPy flow, device arrays with a device flow, of the flow's height and
    width, and of one shape (channels too: a grey frame with an RGB one is refused). Errors name
    ``flow``, ``frame0`` and ``frame1``."""
    data, host = field(flow, "flow", machine, ndims=(3,), dtypes=(np.float32,))
    if data.shape[2] != 2:
        raise InputValueError(f"flow must have two components (H, W, 2), got shape {data.shape}")
    for name, frame in (("frame0", frame0), ("frame1", frame1)):
        if not isinstance(frame, (np.ndarray, cl_array.Array)):
            raise InputTypeError(f"{name} must be a NumPy array or a device array, got {type(frame).__name__}")
        check_same_kind("flow", host, name, not isinstance(frame, cl_array.Array))
        if frame.shape[:2] != data.shape[:2]:
            raise InputValueError(f"flow and {name} must have the same height and width, got flow {data.shape} "
                                  f"and {name} {frame.shape}")
    if frame0.shape != frame1.shape:
        raise InputValueError(f"frame0 and frame1 must have the same shape, got {frame0.shape} and {frame1.shape}")
    return data, host


def smoothed_frames(frame0: ArrayLike, frame1: ArrayLike, sigmas: tuple[float, ...],
                    machine: Machine) -> tuple[cl_array.Array, cl_array.Array, float]:
    """The two frames' grey images on the device, smoothed by the Gaussian of ``sigmas[0]`` (less that of
    ``sigmas[1]`` when given), and what carries their brightness to [0, 1] (1/255 for uint8, 1 for float).
    The frames are grey or RGB, of one type (NumPy floats in [0, 1]); errors name ``frame0`` and
    ``frame1``."""
    smoothed, types = [], []
    for name, frame in (("frame0", frame0), ("frame1", frame1)):
        checked = finite_float32(frame, name)
        if isinstance(checked, np.ndarray) and checked.dtype.kind == "f":
            check_unit_image(checked, name)  # the refinements' weights are set for brightness in [0, 1]
        grey, _ = field(checked, name, machine, ndims=(2, 3), dtypes=tuple(IMAGE_TYPES))
        if grey.ndim == 3 and grey.shape[2] != 3:
            raise InputValueError(f"{name} must be grey (H, W) or RGB (H, W, 3), got shape {grey.shape}")
        smoothed.append(separable_gaussian(machine, grey, sigmas))
        types.append(grey.dtype)
    check_same_scale("frame0", types[0], "frame1", types[1])
    return smoothed[0], smoothed[1], _GAIN[types[0]]
