"""A joint of the head (pan or tilt) in degrees: soft limits, homing, moves, waiting for rest.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": pan 180 degrees left to right,
tilt 90 degrees from vertical-down to horizontal, stepper motors through harmonic drives, calibrated by
a limit switch and the encoder's index pulse. As in the ROS driver of the FLIR/Directed Perception
pan-tilt units, the host reads the soft limits from the micro at start-up and refuses an out-of-travel
target before sending anything; the micro checks again.

Angles: pan 0 is straight ahead, positive to the right; tilt 0 is horizontal, -90 is vertical-down.
"""

from __future__ import annotations

import math
import numbers
from typing import NamedTuple

from .arguments import check_number, real_value
from .commands import ACCEL_LIMIT, FAULT_FLAGS, VMAX_LIMIT, Flag, describe
from .errors import Fault, OutOfRange, naming
from .micros import StepperMicro
from .physics import COUNTS_PER_DEGREE

__all__ = ["COUNTS_PER_DEGREE", "Joint", "JointStatus"]


class JointStatus(NamedTuple):
    """A joint's state: position and target in degrees, encoder count, flags."""

    position: float
    target: float
    encoder: int
    flags: Flag

    def __str__(self) -> str:
        where = f"{self.position:+8.3f} deg (target {self.target:+8.3f})"
        if not self.flags & Flag.HOMED:
            where = f"not homed, {self.encoder:+d} counts from power-up"
        return f"{where}, {describe(self.flags)}"


class Joint:
    """One joint of the head.

    Parameters
    ----------
    micro : StepperMicro
    axis : int
        0 pan, 1 tilt.
    name : str

    Attributes
    ----------
    limits : tuple of float
        The soft limits in degrees, as read from the micro.
    """

    def __init__(self, micro: StepperMicro, axis: int, name: str) -> None:
        self.micro = micro
        self.axis = axis
        self.name = name
        low, high = micro.limits(axis)
        self._count_limits = (low, high)
        self.limits = (low / COUNTS_PER_DEGREE, high / COUNTS_PER_DEGREE)

    def __repr__(self) -> str:
        return f"Joint({self.name!r}, limits={self.limits})"

    def counts(self, degrees: float) -> int:
        """The encoder count of `degrees`, refused (OutOfRange) beyond the soft limits."""
        if not isinstance(degrees, numbers.Real) or isinstance(degrees, bool):
            raise TypeError(f"{self.name} must be a number of degrees, got {type(degrees).__name__}")
        value = real_value(degrees)  # an int too large for a float: infinite, beyond the travel
        if math.isnan(value) or (math.isinf(value) and isinstance(degrees, float)):
            raise ValueError(f"{self.name} must be finite, got {degrees!r}")
        low, high = self._count_limits
        # Compared before rounding: a huge angle (1e308) would overflow to inf counts, which round refuses.
        scaled = value * COUNTS_PER_DEGREE
        counts = round(scaled) if low - 1 <= scaled <= high + 1 else None
        if counts is None or not low <= counts <= high:
            raise OutOfRange(
                f"{self.name} {value:g} deg is outside its travel [{self.limits[0]:g}, {self.limits[1]:g}] deg;"
                " nothing moved"
            )
        return counts

    def status(self) -> JointStatus:
        s = self.micro.axis_status(self.axis)
        return JointStatus(s.encoder / COUNTS_PER_DEGREE, s.target / COUNTS_PER_DEGREE, s.encoder, s.flags)

    @property
    def position(self) -> float:
        """Where the joint is now, degrees (from the encoder)."""
        return self.status().position

    def home(self) -> None:
        """Start homing (seek the limit switch, then the index pulse, then go to 0); clears faults."""
        with naming(self.name):
            self.micro.home(self.axis)

    def move_to(self, degrees: float) -> None:
        """Start a move to `degrees`; `settled` or Head.wait tells when it has arrived."""
        self.move_to_counts(self.counts(degrees))

    def move_to_counts(self, counts: int) -> None:
        """Start a move to encoder count `counts` (the micro checks its soft limits)."""
        with naming(self.name):
            self.micro.move_to(self.axis, counts)

    def set_profile(self, speed: float, acceleration: float) -> None:
        """Set the top speed (degrees/s) and acceleration (degrees/s^2) of later moves, within what the
        stepper micro accepts (1..VMAX_LIMIT counts/s, 1..ACCEL_LIMIT counts/s^2)."""
        counts = []
        for name, value, limit, unit in (
            ("speed", speed, VMAX_LIMIT, "degrees/s"),
            ("acceleration", acceleration, ACCEL_LIMIT, "degrees/s^2"),
        ):
            low, high = 1 / COUNTS_PER_DEGREE, limit / COUNTS_PER_DEGREE
            counts.append(round(check_number(name, value, low, high, unit) * COUNTS_PER_DEGREE))
        with naming(self.name):
            self.micro.set_profile(self.axis, *counts)

    def settled(self) -> bool:
        """True once the joint is at rest and not homing; raises Fault if a fault has latched."""
        flags = self.micro.axis_status(self.axis).flags
        if flags & FAULT_FLAGS:
            raise Fault(f"{self.name}: {describe(flags)}", flags=int(flags))
        return not flags & (Flag.MOVING | Flag.HOMING)
