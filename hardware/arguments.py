"""Checks of the arguments the driver and its two command lines take, before anything is sent.

As the ROS driver of the FLIR/Directed Perception pan-tilt units does, the host refuses an argument
outside the device's limits before it goes on the wire (the micro checks again): a refusal then names
the argument and its allowed range, instead of surfacing as an OverflowError from ``round(inf)``, a
``struct.error`` from packing, or a refusal code from a micro. NaN, infinities, bools and strings are
refused like any other value out of range or of the wrong type.
"""

from __future__ import annotations

import argparse
import math
import numbers
from typing import NoReturn

from .errors import OutOfRange

__all__ = ["OneLineParser", "check_int", "check_number", "real_value"]


def check_int(name: str, value: object, low: int, high: int) -> int:
    """`value` as an int, if it is an integer (not a bool) in ``low..high``.

    Raises
    ------
    TypeError
        Not an integer.
    OutOfRange
        Outside ``low..high`` (it is a ValueError too).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int in {low}..{high}, got {value!r}")
    number = int(value)
    if not low <= number <= high:
        raise OutOfRange(f"{name} must be in {low}..{high}, got {number}")
    return number


def real_value(value: float) -> float:
    """A real number as a float, an int too large for one as the infinity of its sign (beyond every range
    here), so that a check compares it instead of failing with OverflowError."""
    try:
        return float(value)
    except OverflowError:  # copysign would convert it too
        return math.inf if value > 0 else -math.inf


def check_number(name: str, value: object, low: float, high: float, unit: str) -> float:
    """`value` as a float, if it is a real number (not a bool) in ``[low, high]``.

    Raises
    ------
    TypeError
        Not a real number.
    OutOfRange
        NaN, or outside ``[low, high]`` (it is a ValueError too).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number of {unit}, got {value!r}")
    number = real_value(value)  # type: ignore[arg-type]  # a numbers.Real, which the checker cannot convert
    if not low <= number <= high:  # NaN fails this too
        raise OutOfRange(f"{name} must be in [{low:g}, {high:g}] {unit}, got {number:g}")
    return number


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line on stderr (``prog: error: message``) and exit
    status 2, so that a script or a person sees the one thing that is wrong."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")
