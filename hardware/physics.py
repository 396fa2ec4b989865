"""Mechanics of the simulated eye-head: stepper joints, lens axes and galvanometer mirrors.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": pan (180 degrees) and tilt
(90 degrees) are each a stepper motor driving the joint through a harmonic drive (a large ratio, very
little backlash), closed-loop on an optical shaft encoder that also gives an index pulse once per motor
revolution; mechanical limit switches protect against over-travel and, with the index pulse, calibrate
the joint. Each eye has a motorized zoom lens (F1.4, 12.5 to 75 mm) and two galvanometer mirrors.

These classes hold what the micros cannot know directly: the true position of each part. The micros
(hardware.firmware) see it only through an encoder, a switch, an index pulse or a position sensor, as
real firmware would. Lengths are counts of the encoder (steppers) or of the lens motor (lenses).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

__all__ = [
    "COUNTS_PER_DEGREE",
    "COUNTS_PER_MOTOR_REV",
    "GALVO_RANGE_MDEG",
    "GEAR_RATIO",
    "LENS_COUNTS",
    "PAN",
    "TILT",
    "GalvoMirror",
    "JointGeometry",
    "LensMechanism",
    "StepperMechanism",
    "trapezoid_step",
]

COUNTS_PER_MOTOR_REV = 4096  # a 1024-line quadrature encoder on the motor shaft
GEAR_RATIO = 100  # the harmonic drive
COUNTS_PER_DEGREE = COUNTS_PER_MOTOR_REV * GEAR_RATIO / 360.0


def _deg(degrees: float) -> int:
    return round(degrees * COUNTS_PER_DEGREE)


@dataclass(frozen=True)
class JointGeometry:
    """Where things are along one joint, in encoder counts from the joint's zero.

    Attributes
    ----------
    soft_min, soft_max : int
        The travel the micro allows once homed.
    switch_neg, switch_pos : int
        Where each limit switch closes, moving towards it.
    hysteresis : int
        How far back the axis must go before a closed switch opens again.
    hard_min, hard_max : int
        The mechanical stops.
    index_phase : int
        Index pulses lie at ``k * COUNTS_PER_MOTOR_REV + index_phase``.
    home_index : int
        Factory calibration: the index pulse homing latches (the first one above the negative switch's
        release point), where the encoder is set on homing.
    """

    soft_min: int
    soft_max: int
    switch_neg: int
    switch_pos: int
    hysteresis: int
    hard_min: int
    hard_max: int
    index_phase: int
    home_index: int


def _joint(soft_min_deg: float, soft_max_deg: float) -> JointGeometry:
    hysteresis = _deg(0.2)
    switch_neg = _deg(soft_min_deg - 1.0)
    # The index homing uses sits half a motor turn above the switch's release point, so that the
    # switch's scatter (tens of counts) can never make homing pick a different index pulse.
    home_index = switch_neg + hysteresis + COUNTS_PER_MOTOR_REV // 2
    return JointGeometry(
        soft_min=_deg(soft_min_deg),
        soft_max=_deg(soft_max_deg),
        switch_neg=switch_neg,
        switch_pos=_deg(soft_max_deg + 1.0),
        hysteresis=hysteresis,
        hard_min=_deg(soft_min_deg - 3.0),
        hard_max=_deg(soft_max_deg + 3.0),
        index_phase=home_index % COUNTS_PER_MOTOR_REV,
        home_index=home_index,
    )


PAN = _joint(-90.0, 90.0)
TILT = _joint(-90.0, 0.0)


def trapezoid_step(
    pos: float, vel: float, target: float, vmax: float, accel: float, dt: float
) -> tuple[float, float]:
    """Advance a trapezoidal (accelerate, cruise, decelerate) profile by `dt`.

    The velocity moves by at most ``accel * dt`` towards the fastest speed from which the axis can still
    stop at `target` (about ``sqrt(2 * accel * distance)``, capped at `vmax`); a step on that braking
    curve that would reach or pass the target lands exactly on it, at rest, so an axis always ends on
    its target count.

    Returns
    -------
    pos, vel : float
        The new position and velocity.
    """
    remaining = target - pos
    change = accel * dt
    # The braking curve of the discrete profile: from speed n * change, braking by `change` a step
    # covers n (n + 1) / 2 * change * dt, the continuous sqrt(2 * accel * d) in the limit of small dt.
    braking = change * (math.sqrt(0.25 + 2.0 * abs(remaining) / (change * dt)) - 0.5)
    desired = math.copysign(min(vmax, braking), remaining)
    vel += max(-change, min(change, desired - vel))
    step = vel * dt
    # Land when this step reaches the target on the braking curve. A retarget closer than the stopping
    # distance is far above the curve, so it overshoots and comes back, as a real axis must.
    on_curve = abs(vel) <= abs(desired) + change
    if on_curve and (remaining == 0.0 or step / remaining >= 1.0):
        return float(target), 0.0
    return pos + step, vel


class StepperMechanism:
    """A stepper joint: motor, harmonic drive, encoder disc with index, limit switches, hard stops.

    Parameters
    ----------
    geometry : JointGeometry
    position : float
        Where the joint is at power-up, in counts from the joint's zero.
    jitter : callable
        ``jitter()`` returns the scatter, in counts, of a switch's closing (or opening) point, drawn
        anew each time the switch closes (or opens).

    Attributes
    ----------
    geometry : JointGeometry
        Replace it (``dataclasses.replace``) to move a switch, as a knocked switch or an obstacle would.
    position : float
        The joint's true position, counts from its zero.
    jammed : bool
        Set it to hold the joint still whatever the motor does (a stall).
    """

    def __init__(self, geometry: JointGeometry, position: float, jitter: Callable[[], float]) -> None:
        self.geometry = geometry
        self.position = float(position)
        self.jammed = False
        self._jitter = jitter
        self.switch_neg = position <= geometry.switch_neg
        self.switch_pos = position >= geometry.switch_pos
        # Each closing and opening point scatters a little about its nominal place, as a real switch's do.
        self._scatter = {edge: jitter() for edge in ("close_neg", "open_neg", "close_pos", "open_pos")}

    def _edge(self, edge: str) -> float:
        g = self.geometry
        nominal = {
            "close_neg": g.switch_neg,
            "open_neg": g.switch_neg + g.hysteresis,
            "close_pos": g.switch_pos,
            "open_pos": g.switch_pos - g.hysteresis,
        }[edge]
        return nominal + self._scatter[edge]

    def _crossed(self, edge: str, beyond: bool) -> bool:
        if beyond:
            self._scatter[edge] = self._jitter()
        return beyond

    def drive(self, commanded: float) -> tuple[float, float]:
        """The motor is stepped to `commanded` counts; the joint follows unless jammed or at a stop.

        Returns
        -------
        before, after : float
            The joint's true position before and after, for the encoder's index latch.
        """
        g = self.geometry
        before = self.position
        if not self.jammed:
            self.position = min(g.hard_max, max(g.hard_min, commanded))
        p = self.position
        if self.switch_neg:
            self.switch_neg = not self._crossed("open_neg", p >= self._edge("open_neg"))
        else:
            self.switch_neg = self._crossed("close_neg", p <= self._edge("close_neg"))
        if self.switch_pos:
            self.switch_pos = not self._crossed("open_pos", p <= self._edge("open_pos"))
        else:
            self.switch_pos = self._crossed("close_pos", p >= self._edge("close_pos"))
        return before, p

    def index_between(self, before: float, after: float) -> int | None:
        """The index pulse passed moving up from `before` to `after`, if any (the encoder latches it)."""
        if after <= before:
            return None
        k = math.floor((after - self.geometry.index_phase) / COUNTS_PER_MOTOR_REV)
        index = k * COUNTS_PER_MOTOR_REV + self.geometry.index_phase
        return index if before < index <= after else None


LENS_COUNTS = 4096  # each lens axis: a geared motor with a 12-bit range


class LensMechanism:
    """One lens axis (zoom, focus or iris): a motor turning a ring through gears with backlash.

    The motor's position is what the micro counts; the ring lags it by up to `backlash` counts after a
    reversal. A home sensor sees the ring below `home_edge`.
    """

    def __init__(
        self,
        motor: float,
        *,
        backlash: float = 12.0,
        home_edge: float = 0.0,
        travel: float = LENS_COUNTS + 100.0,
    ) -> None:
        self.motor = float(motor)
        self.ring = float(motor)
        self.backlash = backlash
        self.home_edge = home_edge
        self.travel = travel

    def drive(self, motor: float) -> None:
        """Turn the motor to `motor`; the ring moves only once the gear lash is taken up."""
        self.motor = min(self.travel, max(-self.travel, motor))
        self.ring = min(self.motor, max(self.ring, self.motor - self.backlash))

    @property
    def at_home(self) -> bool:
        """The home sensor's output."""
        return self.ring < self.home_edge


GALVO_RANGE_MDEG = 10_000  # +-10 degrees of mirror rotation


class GalvoMirror:
    """A galvanometer mirror: it turns towards its target at a limited slew rate (degrees/s)."""

    def __init__(self, *, slew: float = 500.0) -> None:
        self.angle = 0.0
        self.target = 0.0
        self.slew_mdeg = slew * 1000.0

    def step(self, dt: float) -> None:
        travel = self.slew_mdeg * dt
        self.angle += max(-travel, min(travel, self.target - self.angle))

    @property
    def moving(self) -> bool:
        return self.angle != self.target
