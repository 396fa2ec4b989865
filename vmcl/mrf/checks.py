"""Field checks of the MRF's frozen settings (the energy model and the solvers' schedules), and the value
check of per-pixel weights, on the host or the device.

Each settings class lists one check per field in ``CHECKS``; a check takes the value and the label to
name it by. The classes check themselves as ``ClassName.field``; :meth:`vmcl.mrf.Settings.override`
checks a user's value first under the label the user wrote (``mrf.<cue>.<key>`` in a Config), so a
refusal names the key in the user's own file.

Every number a setting holds reaches the device as a float32, so the real-valued ones must lie within
float32's range: a finite float64 beyond it would become an infinity there and every result NaN.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import reduce as cm_reduce
from vmcl.cm.core import ArrayLike, check_int, check_real, finite_float32
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = [
    "FLOAT32_MAX",
    "MAX_COUNT",
    "check_cooling",
    "check_count",
    "check_fields",
    "check_number",
    "check_positive_count",
    "check_temperature",
    "check_weight",
    "check_weights",
    "within_float32",
]

# Counts of sweeps, levels and radii: far above any schedule that ends, and within the kernels' int32.
MAX_COUNT = 2**31 - 1

FLOAT32_MAX = float(np.finfo(np.float32).max)
"""The largest magnitude a real setting may have: the kernels compute in float32."""


def check_fields(settings: Any) -> None:
    """Check every field of a settings dataclass with its class's ``CHECKS``, naming it ``Class.field``."""
    owner = type(settings)
    for item in fields(settings):
        owner.CHECKS[item.name](getattr(settings, item.name), f"{owner.__name__}.{item.name}")


def within_float32(number: float, label: str) -> float:
    """``number`` (a checked finite real) refused, naming ``label``, where its magnitude exceeds float32's
    largest: the device would hold it as an infinity."""
    if abs(number) > FLOAT32_MAX:
        raise InputValueError(f"{label} must lie within float32's range (magnitude at most {FLOAT32_MAX:.4g}), "
                              f"in which the device computes, got {number:g}")
    return number


def check_count(value: Any, label: str) -> int:
    """A number of sweeps, steps or pixels: an integer in 0 .. MAX_COUNT."""
    return check_int(value, label, minimum=0, maximum=MAX_COUNT)


def check_positive_count(value: Any, label: str) -> int:
    """A count that must not be 0 (what a solver divides by, such as the samples it averages): 1 .. MAX_COUNT."""
    return check_int(value, label, minimum=1, maximum=MAX_COUNT)


def check_number(value: Any, label: str) -> float:
    """Any finite real number within float32's range."""
    return within_float32(check_real(value, label), label)


def check_weight(value: Any, label: str) -> float:
    """A finite real number >= 0 within float32's range (a weight of a term of the energy)."""
    return within_float32(check_real(value, label, minimum=0), label)


def check_temperature(value: Any, label: str) -> float:
    """A finite temperature > 0 within float32's range, in the energy's units."""
    return within_float32(check_real(value, label, above=0), label)


def check_cooling(value: Any, label: str) -> float:
    """A factor in (0, 1] between successive temperatures: annealing never heats up."""
    return check_real(value, label, above=0, maximum=1)


def check_weights(x: ArrayLike, name: str, machine: Machine) -> ArrayLike:
    """``x``, per-pixel weights (a NumPy array of real numbers or a float32 device array), refused unless
    every value is finite and >= 0; host floats are returned as float32, refused beyond its range.

    A device array is checked where it lies, by three reductions read back together
    (:func:`vmcl.cm.reduce.reduce`): "min" and "max" skip NaN, so they find negative values and
    infinities, and "sum" carries NaN (an overflowing sum of finite values gives an infinity, never NaN).

    Raises
    ------
    InputValueError
        Naming ``name``: NaN, an infinity, a negative value, or (host) a value beyond float32's range.
    """
    if isinstance(x, cl_array.Array):
        found = [cm_reduce.reduce(x, op, machine=machine) for op in ("min", "max", "sum")]
        low, high, total = (float(value.get()) for value in found)
        if math.isnan(total) or not (math.isfinite(low) and math.isfinite(high)):
            raise InputValueError(f"{name} must be finite and >= 0: it holds NaN or an infinity")
    else:
        with np.errstate(over="ignore"):  # finite_float32 refuses what overflows its cast, with a message
            checked: np.ndarray = finite_float32(x, name)
        low = float(np.min(checked)) if checked.size else 0.0
        x = checked
    if low < 0:
        raise InputValueError(f"{name} must be finite and >= 0, got a value of {low:g}")
    return x
