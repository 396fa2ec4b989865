"""The argument checks the recognition modules share: corner lists, angle lists, pairs and maps.

Every refusal is a :class:`vmcl.errors.InputError` naming the argument; nothing is converted lossily.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vmcl.cm.core import check_unmasked, full_scale, to_host
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["angles", "edge_map", "index_pairs", "object_mask", "points", "real_map"]


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


def object_mask(x: Any, name: str) -> np.ndarray:
    """``x``: an object mask, an (H, W) array of at least 2 x 2 pixels, NumPy or device: bool, or numbers (a
    picture's uint8 or uint16, an integer or float map) holding 0 off the object and one other value on it,
    1 or the type's full scale (255 for uint8, 65535 for uint16); not all 0. Returns bool.

    Any other value is refused rather than thresholded: a grey or blurred edge, a JPEG's ringing, or a
    mask of another scale has no one cut that is right for all of them."""
    x = to_host(x, name)
    if not isinstance(x, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy or device array, got {type(x).__name__}")
    check_unmasked(x, name)
    if x.dtype.kind not in "biuf":
        raise InputTypeError(f"{name} must be bool, integer or float, got dtype {x.dtype}")
    if x.dtype != np.bool_:
        on = x[x != 0]  # NaN among them: it is no value a mask may hold
        full = full_scale(x.dtype)
        if on.size and (on[0] not in (1, full) or not (on == on[0]).all()):
            seen = np.unique(on)
            raise InputValueError(
                f"{name} must hold only 0 (off the object) and one other value (on it): 1"
                + ("" if full == 1 else f" or {full:g}, its type's full scale")
                + f"; it holds {', '.join(f'{v:g}' for v in seen[:4])}{' ...' if len(seen) > 4 else ''} where it is not 0")
    mask = edge_map(x != 0, name)
    if not mask.any():
        raise InputValueError(f"{name} marks no pixel as the object: it holds only 0")
    return mask


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
