"""Firmware of the three simulated UNET micros: galvanometers, motorized lenses, stepper motors.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": three 8051 micros on UNET, one
each for the galvanometers, the motorized lenses and the stepper motors, slaves that speak only when
spoken to. The behaviour each micro shows on the wire follows the proven protocols:

* Modbus RTU: a micro stays silent on a bad CRC and on a broadcast; a refused request gets an
  exception code.
* Dynamixel 2.0: every reply carries the error bits; a latched hardware fault shows in every status byte.
* FLIR/Directed Perception pan-tilt units: a command outside the limits is refused and not executed; a
  limit hit stops the axis and latches an error until reset; homing runs on the limit switch.

Each micro remembers its last (sequence, request, reply): a request that comes again with the same
sequence number (the host's retry after a lost reply) is answered from that memory and never executed
twice. `MicroFirmware.executed` counts the commands that ran, so tests can prove it.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from typing import cast

from .commands import (
    ACCEL_LIMIT,
    FAULT_BIT,
    FAULT_FLAGS,
    PROTOCOL_VERSION,
    VMAX_LIMIT,
    Cmd,
    Error,
    Flag,
    Kind,
    LayoutError,
    pack,
    unpack,
)
from .physics import (
    GALVO_RANGE_MDEG,
    LENS_COUNTS,
    GalvoMirror,
    LensMechanism,
    StepperMechanism,
    trapezoid_step,
)
from .protocol import BROADCAST, Frame, encode_reply

__all__ = [
    "STALL_COUNTS",
    "GalvoEye",
    "GalvoFirmware",
    "LensAxis",
    "LensFirmware",
    "MicroFirmware",
    "Refused",
    "StepperAxis",
    "StepperFirmware",
]

STALL_COUNTS = 100  # following error that counts as a stall (about 0.09 degree at the joint)
_SEEK_SPEED, _SEEK_ACCEL = 25_000.0, 200_000.0
_CREEP_SPEED = 2_000.0


class Refused(Exception):
    """Raised by a command handler to refuse a request with an error code; nothing was changed."""

    def __init__(self, code: Error) -> None:
        super().__init__(code.name)
        self.code = code


class _Axis:
    """What every axis of every micro shares: latched faults, stop, emergency stop."""

    def __init__(self) -> None:
        self.latched = Flag(0)

    @property
    def moving(self) -> bool:
        raise NotImplementedError

    @property
    def flags(self) -> Flag:
        raise NotImplementedError

    def step(self, dt: float) -> None:
        raise NotImplementedError

    def stop(self) -> None:
        """Come to rest (decelerating where the axis has inertia)."""
        raise NotImplementedError

    def halt(self) -> None:
        """Stop at once."""
        raise NotImplementedError

    def latch(self, fault: Flag, *, at_once: bool = True) -> None:
        if at_once:
            self.halt()
        else:
            self.stop()
        self.latched |= fault

    def clear_fault(self) -> None:
        self.latched = Flag(0)

    def require_no_fault(self) -> None:
        if self.latched:
            raise Refused(Error.FAULT)


class MicroFirmware:
    """What every micro does: framing replies, the (sequence, reply) memory, common commands, watchdog.

    Parameters
    ----------
    addr : int
        Its UNET address, 1..31.
    axes : sequence of axes
        The axes it drives; commands name them by index.
    """

    kind: Kind

    def __init__(self, addr: int, axes: Sequence[_Axis]) -> None:
        self.addr = addr
        self.axes = list(axes)
        self.executed: Counter[Cmd] = Counter()
        self.watchdog_period = 0.0
        self._last_heard = 0.0
        self._memory: tuple[int, int, bytes, bytes] | None = None
        self._handlers: dict[int, Callable[..., tuple[int, ...]]] = {
            Cmd.PING: lambda: (self.kind, PROTOCOL_VERSION),
            Cmd.STATUS: lambda: (int(self.flags),),
            Cmd.CLEAR_FAULT: self._each(lambda axis: axis.clear_fault()),
            Cmd.STOP: self._each(lambda axis: axis.stop()),
            Cmd.ESTOP: self._each(lambda axis: axis.latch(Flag.FAULT_ESTOP)),
            Cmd.WATCHDOG: self._watchdog,
        }
        self._handlers.update(self.commands())

    def commands(self) -> dict[int, Callable[..., tuple[int, ...]]]:
        """The micro kind's own command handlers."""
        raise NotImplementedError

    def _each(self, action: Callable[[_Axis], object]) -> Callable[[], tuple[int, ...]]:
        def handler() -> tuple[int, ...]:
            for axis in self.axes:
                action(axis)
            return ()

        return handler

    def _watchdog(self, period_ms: int) -> tuple[int, ...]:
        self.watchdog_period = period_ms / 1000.0
        return ()

    def axis(self, index: int) -> _Axis:
        if index >= len(self.axes):
            raise Refused(Error.OUT_OF_RANGE)
        return self.axes[index]

    @property
    def flags(self) -> Flag:
        """The OR of the flags of every axis."""
        flags = Flag(0)
        for axis in self.axes:
            flags |= axis.flags
        return flags

    @property
    def faulted(self) -> bool:
        return any(axis.latched & FAULT_FLAGS for axis in self.axes)

    def receive(self, frame: Frame, now: float) -> bytes | None:
        """Act on a request addressed to this micro (or broadcast); return the reply's bytes, if any."""
        self._last_heard = now
        broadcast = frame.addr == BROADCAST
        memory = self._memory
        if not broadcast and memory is not None and memory[:3] == (frame.seq, frame.cmd, frame.payload):
            return memory[3]
        data = b""
        handler = self._handlers.get(frame.cmd)
        if handler is None:
            code = Error.UNKNOWN_COMMAND
        else:
            try:
                args = unpack(frame.cmd, frame.payload)
            except LayoutError:
                code = Error.BAD_LENGTH
            else:
                self.executed[Cmd(frame.cmd)] += 1
                try:
                    data = pack(frame.cmd, *handler(*args), reply=True)
                    code = Error.OK
                except Refused as refusal:
                    code = refusal.code
        if broadcast:
            return None
        status = code | (FAULT_BIT if self.faulted else 0)
        reply = encode_reply(self.addr, frame.seq, status, frame.cmd, data)
        self._memory = (frame.seq, frame.cmd, frame.payload, reply)
        return reply

    @property
    def busy(self) -> bool:
        """True while anything needs fine time steps: an axis moving or a watchdog armed."""
        return self.watchdog_period > 0.0 or any(axis.moving for axis in self.axes)

    def tick(self, now: float, dt: float) -> None:
        """Advance every axis by `dt` seconds, ending at time `now`; trip the watchdog if the host fell
        silent."""
        for axis in self.axes:
            axis.step(dt)
        if self.watchdog_period and now - self._last_heard > self.watchdog_period:
            for axis in self.axes:
                if not axis.latched & Flag.FAULT_WATCHDOG:
                    axis.latch(Flag.FAULT_WATCHDOG, at_once=False)


class _MotorAxis(_Axis):
    """An axis driven to a target count with homing: what the stepper and lens controllers share."""

    def __init__(self, position: float) -> None:
        super().__init__()
        # The counter powers up at 0 wherever the axis happens to be.
        self.zero = math.floor(position)
        self.pos = position - self.zero
        self.vel = 0.0
        self.target = self.pos
        self.homed = False
        self.phase: str | None = None

    @property
    def moving(self) -> bool:
        return self.vel != 0.0 or self.pos != self.target

    def _braking_target(self, accel: float) -> float:
        """Where a stop brings the axis to rest: its stopping distance at `accel` from the current speed,
        on to a whole count (where every move ends), but never past the target it was already braking
        onto: a stop cannot carry the axis further than the move would have (past a soft limit)."""
        reach = self.pos + math.copysign(self.vel * self.vel / (2.0 * accel), self.vel)
        whole = float(math.ceil(reach) if self.vel > 0.0 else math.floor(reach))
        if self.vel > 0.0 and self.target >= self.pos:
            return min(whole, self.target)
        if self.vel < 0.0 and self.target <= self.pos:
            return max(whole, self.target)
        return whole

    @property
    def flags(self) -> Flag:
        flags = self.latched
        if self.moving:
            flags |= Flag.MOVING
        if self.homed:
            flags |= Flag.HOMED
        if self.phase:
            flags |= Flag.HOMING
        return flags


class StepperAxis(_MotorAxis):
    """One joint's controller: trapezoidal profiles closed on the encoder, homing, limits, stalls.

    Homing (HOME): seek the negative limit switch fast, back off slowly until it opens, creep on to the
    next index pulse, where the encoder is set to the factory-calibrated count; then move to count 0.
    The index pulse, not the switch, fixes the zero, which is why homing repeats to the count.
    """

    def __init__(self, mech: StepperMechanism, *, vmax: float = 50_000.0, accel: float = 100_000.0) -> None:
        super().__init__(mech.position)
        self.mech = mech
        self.vmax = vmax
        self.accel = accel

    @property
    def encoder(self) -> int:
        return math.floor(self.mech.position) - self.zero

    @property
    def flags(self) -> Flag:
        flags = super().flags
        if self.mech.switch_neg:
            flags |= Flag.LIMIT_NEG
        if self.mech.switch_pos:
            flags |= Flag.LIMIT_POS
        return flags

    def _profile(self) -> tuple[float, float]:
        if self.phase == "seek":
            return _SEEK_SPEED, _SEEK_ACCEL
        if self.phase in ("backoff", "index"):
            return _CREEP_SPEED, _SEEK_ACCEL
        return self.vmax, self.accel

    def step(self, dt: float) -> None:
        if not self.moving:
            return
        vmax, accel = self._profile()
        self.pos, self.vel = trapezoid_step(self.pos, self.vel, self.target, vmax, accel, dt)
        before, after = self.mech.drive(self.pos + self.zero)
        if self.phase == "index":
            index = self.mech.index_between(before, after)
            if index is not None:
                self._set_zero(index - self.mech.geometry.home_index)
                self.homed = True
                self.phase = "center"
                self.target = 0
        if abs(self.pos + self.zero - self.mech.position) > STALL_COUNTS:
            self.latch(Flag.FAULT_STALL)
            return
        # Homing drives onto the negative switch on purpose; anything else that reaches a switch is a fault.
        if (self.mech.switch_pos and self.vel > 0.0) or (
            self.mech.switch_neg and self.vel < 0.0 and not self.phase
        ):
            self.latch(Flag.FAULT_LIMIT)
            return
        if self.phase == "seek" and self.mech.switch_neg:
            self.phase = "backoff"
            self.target = self.pos + self._span
        elif self.phase == "backoff" and not self.mech.switch_neg:
            self.phase = "index"
        elif self.phase == "center" and not self.moving:
            self.phase = None

    @property
    def _span(self) -> int:
        g = self.mech.geometry
        return 2 * (g.hard_max - g.hard_min)

    def _set_zero(self, zero: int) -> None:
        shift = self.zero - zero
        self.zero = zero
        self.pos += shift
        self.target += shift

    def stop(self) -> None:
        self.phase = None
        if self.moving:
            self.target = self._braking_target(self._profile()[1])

    def halt(self) -> None:
        self.phase = None
        self.vel = 0.0
        self.pos = self.mech.position - self.zero
        self.target = self.pos

    def home(self) -> None:
        self.latched = Flag(0)
        self.homed = False
        if self.mech.switch_neg:
            self.phase = "backoff"
            self.target = self.pos + self._span
        else:
            self.phase = "seek"
            self.target = self.pos - self._span

    def move_to(self, target: int) -> None:
        self.require_no_fault()
        if self.phase:
            raise Refused(Error.BUSY)
        if not self.homed:
            raise Refused(Error.NOT_HOMED)
        g = self.mech.geometry
        if not g.soft_min <= target <= g.soft_max:
            raise Refused(Error.OUT_OF_RANGE)
        self.target = target


class StepperFirmware(MicroFirmware):
    """The stepper micro: axis 0 is pan, axis 1 is tilt."""

    kind = Kind.STEPPER

    def commands(self) -> dict[int, Callable[..., tuple[int, ...]]]:
        return {
            Cmd.HOME: self._home,
            Cmd.MOVE_TO: self._move_to,
            Cmd.SET_PROFILE: self._set_profile,
            Cmd.AXIS_STATUS: self._axis_status,
            Cmd.GET_LIMITS: self._limits,
        }

    def axis(self, index: int) -> StepperAxis:
        return cast(StepperAxis, super().axis(index))

    def _home(self, index: int) -> tuple[int, ...]:
        self.axis(index).home()
        return ()

    def _move_to(self, index: int, target: int) -> tuple[int, ...]:
        self.axis(index).move_to(target)
        return ()

    def _set_profile(self, index: int, vmax: int, accel: int) -> tuple[int, ...]:
        axis = self.axis(index)
        if not (1 <= vmax <= VMAX_LIMIT and 1 <= accel <= ACCEL_LIMIT):
            raise Refused(Error.OUT_OF_RANGE)
        axis.vmax, axis.accel = float(vmax), float(accel)
        return ()

    def _axis_status(self, index: int) -> tuple[int, ...]:
        axis = self.axis(index)
        return axis.encoder, round(axis.target), int(axis.flags)

    def _limits(self, index: int) -> tuple[int, ...]:
        g = self.axis(index).mech.geometry
        return g.soft_min, g.soft_max


class LensAxis(_MotorAxis):
    """One lens axis's controller. Every move ends travelling upwards, so the gear lash is always taken
    up the same way and a count means the same ring position whichever side it was approached from."""

    _SPEED, _ACCEL, _HOME_SPEED = 3000.0, 30_000.0, 800.0
    _OVERSHOOT = 40  # more than the backlash

    def __init__(self, mech: LensMechanism) -> None:
        super().__init__(mech.motor)
        self.mech = mech
        self._final: int | None = None

    @property
    def count(self) -> int:
        return round(self.mech.motor - self.zero)

    def step(self, dt: float) -> None:
        if not self.moving:
            return
        speed = self._HOME_SPEED if self.phase else self._SPEED
        self.pos, self.vel = trapezoid_step(self.pos, self.vel, self.target, speed, self._ACCEL, dt)
        self.mech.drive(self.pos + self.zero)
        if self.phase == "seek" and self.mech.at_home:
            self.phase = "release"
            self.target = self.pos + 2 * self.mech.travel
        elif self.phase == "release" and not self.mech.at_home:
            # The sensor edge, reached travelling upwards, is count 0.
            shift = self.zero - math.floor(self.mech.motor)
            self.zero -= shift
            self.pos += shift
            self.phase = None
            self.homed = True
            self.go_to(0)
        elif self._final is not None and not self.moving:
            self.target, self._final = self._final, None

    def go_to(self, target: int) -> None:
        if target < self.pos:
            self.target, self._final = target - self._OVERSHOOT, target
        else:
            self.target, self._final = target, None

    def home(self) -> None:
        self.latched = Flag(0)
        self.homed = False
        self._final = None
        self.phase = "seek"
        self.target = self.pos - 2 * self.mech.travel

    def stop(self) -> None:
        self.phase = None
        self._final = None
        if self.moving:
            self.target = self._braking_target(self._ACCEL)

    def halt(self) -> None:
        self.phase = None
        self._final = None
        self.vel = 0.0
        self.target = self.pos


class LensFirmware(MicroFirmware):
    """The lens micro: axes 0-2 are the left eye's zoom, focus, iris; axes 3-5 the right eye's."""

    kind = Kind.LENS

    def commands(self) -> dict[int, Callable[..., tuple[int, ...]]]:
        return {Cmd.LENS_HOME: self._home, Cmd.LENS_SET: self._set, Cmd.LENS_GET: self._get}

    def _lens(self, eye: int) -> list[LensAxis]:
        if eye > 1:
            raise Refused(Error.OUT_OF_RANGE)
        return cast(list[LensAxis], self.axes[3 * eye : 3 * eye + 3])

    def _home(self, eye: int) -> tuple[int, ...]:
        for axis in self._lens(eye):
            axis.home()
        return ()

    def _set(self, eye: int, *counts: int) -> tuple[int, ...]:
        axes = self._lens(eye)
        for axis in axes:
            axis.require_no_fault()
            if axis.phase:
                raise Refused(Error.BUSY)
            if not axis.homed:
                raise Refused(Error.NOT_HOMED)
        if any(count >= LENS_COUNTS for count in counts):
            raise Refused(Error.OUT_OF_RANGE)
        for axis, count in zip(axes, counts):
            axis.go_to(count)
        return ()

    def _get(self, eye: int) -> tuple[int, ...]:
        axes = self._lens(eye)
        flags = Flag(0)
        for axis in axes:
            flags |= axis.flags
        return (*(axis.count for axis in axes), int(flags))


class GalvoEye(_Axis):
    """The two galvanometer mirrors in front of one eye, driven together."""

    def __init__(self, slew: float = 500.0) -> None:
        super().__init__()
        self.mirrors = (GalvoMirror(slew=slew), GalvoMirror(slew=slew))

    @property
    def moving(self) -> bool:
        return any(m.moving for m in self.mirrors)

    @property
    def flags(self) -> Flag:
        # A galvo reads its angle from an absolute position sensor: it never needs homing.
        flags = self.latched | Flag.HOMED
        return flags | Flag.MOVING if self.moving else flags

    def step(self, dt: float) -> None:
        for mirror in self.mirrors:
            mirror.step(dt)

    def stop(self) -> None:
        for mirror in self.mirrors:
            mirror.target = mirror.angle

    halt = stop


class GalvoFirmware(MicroFirmware):
    """The galvanometer micro: axis 0 is the left eye's mirror pair, axis 1 the right eye's."""

    kind = Kind.GALVO

    def commands(self) -> dict[int, Callable[..., tuple[int, ...]]]:
        return {Cmd.GALVO_SET: self._set, Cmd.GALVO_GET: self._get}

    def axis(self, index: int) -> GalvoEye:
        return cast(GalvoEye, super().axis(index))

    def _set(self, eye: int, x: int, y: int) -> tuple[int, ...]:
        pair = self.axis(eye)
        pair.require_no_fault()
        if max(abs(x), abs(y)) > GALVO_RANGE_MDEG:
            raise Refused(Error.OUT_OF_RANGE)
        for mirror, angle in zip(pair.mirrors, (x, y)):
            mirror.target = float(angle)
        return ()

    def _get(self, eye: int) -> tuple[int, ...]:
        pair = self.axis(eye)
        angles = tuple(round(m.angle) for m in pair.mirrors)
        targets = tuple(round(m.target) for m in pair.mirrors)
        return (*angles, *targets, int(pair.flags))
