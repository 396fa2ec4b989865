"""The argument checks the recognition modules share: corner lists, angle lists, pairs and maps.

Every refusal is a :class:`vmcl.errors.InputError` naming the argument; nothing is converted lossily.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vmcl.cm.core import check_unmasked
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["angles", "edge_map", "index_pairs", "points", "real_map"]


def _host(x: Any, name: str) -> np.ndarray:
    if not isinstance(x, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy array, got {type(x).__name__}")
    check_unmasked(x, name)
    if x.dtype.kind not in "iuf":
        raise InputTypeError(f"{name} must hold real numbers (integer or float), got dtype {x.dtype}")
    return x


def points(x: Any, name: str) -> np.ndarray:
    """``x``: finite (N, 2) coordinates (x, y), N >= 0; float64."""
    x = _host(x, name)
    if x.ndim != 2 or x.shape[1] != 2:
        raise InputValueError(f"{name} must be an (N, 2) array of (x, y), got shape {x.shape}")
    x = x.astype(np.float64)
    if not np.isfinite(x).all() or np.abs(x).max(initial=0) > 1e9:
        raise InputValueError(f"{name} must be finite coordinates within 1e9 pixels")
    return x


def angles(x: Any, name: str, count: int, of: str, *, low: float = -np.inf, high: float = np.inf,
           unknown: bool = False) -> np.ndarray:
    """``x``: ``count`` angles (radians), one per row of the argument ``of``, in [low, high]; NaN (unknown)
    allowed with ``unknown``; float64."""
    x = _host(x, name)
    if x.shape != (count,):
        raise InputValueError(f"{name} must be a ({count},) array, one value per row of {of}, got shape {x.shape}")
    x = x.astype(np.float64)
    known = np.isfinite(x)
    if not unknown and not known.all() or np.isinf(x).any():
        raise InputValueError(f"{name} must be finite{' or NaN' if unknown else ''}")
    if ((x[known] < low) | (x[known] > high)).any():
        raise InputValueError(f"{name} must lie within [{low:.4g}, {high:.4g}]")
    return x


def index_pairs(x: Any, name: str, count: int) -> np.ndarray:
    """``x``: an integer (P, 2) array of indices into ``count`` items; int64."""
    if not isinstance(x, np.ndarray) or x.dtype.kind not in "iu":
        raise InputTypeError(f"{name} must be an integer NumPy array, got "
                             f"{type(x).__name__ if not isinstance(x, np.ndarray) else x.dtype}")
    check_unmasked(x, name)
    if x.ndim != 2 or x.shape[1] != 2:
        raise InputValueError(f"{name} must be a (P, 2) array, got shape {x.shape}")
    if x.size and (x.min() < 0 or x.max() >= count):
        raise InputValueError(f"{name} must index the {count} items (0 to {count - 1})")
    return x.astype(np.int64)


def edge_map(x: Any, name: str) -> np.ndarray:
    """``x``: a bool, or uint8 0/1, (H, W) host array of at least 2 x 2 pixels; bool."""
    if not isinstance(x, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy array, got {type(x).__name__}")
    check_unmasked(x, name)
    if x.dtype not in (np.bool_, np.uint8):
        raise InputTypeError(f"{name} must be bool or uint8 0/1, got dtype {x.dtype}")
    if x.ndim != 2 or min(x.shape) < 2:
        raise InputValueError(f"{name} must be an (H, W) array of at least 2 x 2 pixels, got shape {x.shape}")
    if x.size >= 2**31:
        raise InputValueError(f"{name} must have fewer than 2**31 pixels, got {x.size}")
    if x.dtype == np.uint8 and x.max() > 1:
        raise InputValueError(f"{name} must hold 0 and 1 only")
    return x.astype(bool)


def real_map(x: Any, name: str, shape: tuple[int, ...], of: str, *, unknown: bool = False) -> np.ndarray:
    """``x``: a real host array of ``shape`` (that of the argument ``of``), finite (NaN allowed with
    ``unknown``); float64."""
    x = _host(x, name)
    if x.shape != shape:
        raise InputValueError(f"{name} must have the shape of {of}, {shape}, got {x.shape}")
    x = x.astype(np.float64)
    if np.isinf(x).any() or (not unknown and np.isnan(x).any()):
        raise InputValueError(f"{name} must be finite{' or NaN' if unknown else ''}")
    return x
