"""Argument checks and host conversion shared by the metric families.

Every measure accepts NumPy or device (pyopencl) arrays and refuses bad input at the door with an error
that names the argument; these checks are the one copy that the stereo, flow, boundary and detection
measures use.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vmcl.cm.core import to_host
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["as_float_field", "as_mask", "check_sequence", "evaluated_pixels"]


def as_float_field(array, name: str, *, ndim: int) -> np.ndarray:
    """``array`` as a non-empty float64 field of ``ndim`` dimensions; NaN allowed (no value), infinity not."""
    array = np.asarray(to_host(array, name))
    if array.dtype.kind not in "iuf":
        raise InputTypeError(f"{name} must be a numeric array of real numbers, got dtype {array.dtype}")
    if array.ndim != ndim:
        raise InputValueError(f"{name} must have {ndim} dimensions, got shape {array.shape}")
    if array.size == 0:
        raise InputValueError(f"{name} is empty")
    array = array.astype(np.float64, copy=False)
    if np.isinf(array).any():
        raise InputValueError(f"{name} contains infinite values; use NaN for 'no value'")
    return array


def as_mask(mask, name: str, shape: tuple[int, ...], against: str) -> np.ndarray:
    """``mask`` as a boolean array of ``against``'s shape."""
    mask = np.asarray(to_host(mask, name))
    if mask.dtype != bool:
        raise InputTypeError(f"{name} must be a boolean array, got dtype {mask.dtype}")
    if mask.shape != shape:
        raise InputValueError(f"{name} has shape {mask.shape}, {against} has shape {shape}")
    return mask


def check_sequence(value, name: str) -> Sequence | np.ndarray:
    """``value`` checked as a list, tuple or NumPy array of at least one dimension (a stack of maps)."""
    if not isinstance(value, (list, tuple, np.ndarray)) or (isinstance(value, np.ndarray) and value.ndim == 0):
        raise InputTypeError(f"{name} must be a list, tuple or array, got {type(value).__name__}")
    return value


def evaluated_pixels(truth: np.ndarray, mask, truth_known: np.ndarray) -> np.ndarray:
    """Pixels to score: the mask where one is given (the truth must be known there), else the known truth."""
    if mask is None:
        evaluated = truth_known
    else:
        evaluated = as_mask(mask, "mask", truth_known.shape, "ground_truth's pixels")
        unknown = int(np.count_nonzero(evaluated & ~truth_known))
        if unknown:
            raise InputValueError(f"ground_truth has no value (NaN) at {unknown} pixels inside mask")
    if not evaluated.any():
        raise InputValueError("no pixel to evaluate: the mask is empty, or the ground_truth has no value (NaN) "
                              "anywhere")
    return evaluated
