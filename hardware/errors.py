"""The exceptions of the eye-head driver.

Two families, after the split every proven servo protocol makes (Dynamixel 2.0 status packets, Modbus RTU
exception replies, the FLIR pan-tilt units' error replies): a CommError means the bytes did not make it
(nothing is known about whether a command ran), a DeviceError means a micro answered and refused or
reported a fault (the command did not run). Every message says what to do next.

Reference: Poggio et al., "The MIT Vision Machine", section "The Eye-Head system".
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = [
    "FAULT_ADVICE",
    "BadLength",
    "Busy",
    "CommError",
    "CorruptFrame",
    "DeviceError",
    "Fault",
    "HardwareError",
    "MotionTimeout",
    "NotHomed",
    "OutOfRange",
    "PortError",
    "Timeout",
    "UnknownCommand",
]


class HardwareError(Exception):
    """Base class of every error the eye-head driver raises (apart from ValueError/TypeError for bad
    arguments)."""


class CommError(HardwareError):
    """No valid reply came back: the micro may or may not have acted on the request."""


class Timeout(CommError):
    """A micro did not answer within the reply timeout, after every retry."""


class CorruptFrame(CommError):
    """Replies came back, but every one failed its CRC or was cut short, after every retry."""


class PortError(CommError):
    """The serial port itself failed: it would not open, or a read or write on it failed (a USB-serial
    adapter unplugged, the device powered off, the pty's far end gone). The original
    ``serial.SerialException`` or OSError is its ``__cause__``."""


class DeviceError(HardwareError):
    """A micro answered and refused the command, or reports a latched fault.

    Attributes
    ----------
    code : int
        The error code from the reply's STATUS byte (bits 0..6).
    fault_latched : bool
        Bit 7 of the STATUS byte: the micro has a latched fault.
    advice : str
        What to do next, in the driver's own terms (``Head.home``), appended to the message by ``str``.
        Kept apart so that a front end with other means words its own: vmcl-head names its commands.
    """

    def __init__(self, message: str, *, code: int = 0, fault_latched: bool = False, advice: str = "") -> None:
        super().__init__(message)
        self.code = code
        self.fault_latched = fault_latched
        self.advice = advice

    def __str__(self) -> str:
        said = super().__str__()
        return f"{said}; {self.advice}" if self.advice else said


class Busy(DeviceError):
    """The axis is homing; wait for it to finish or send STOP."""


class UnknownCommand(DeviceError):
    """The micro does not implement the command: the wrong kind of micro is at that address."""


class BadLength(DeviceError):
    """The payload length does not match the command: host and firmware disagree on the protocol."""


class OutOfRange(DeviceError, ValueError):
    """A target outside the soft limits (checked on the host, and again in the micro); nothing moved.

    It is also a ValueError, since it is an argument the caller can correct.
    """


class NotHomed(DeviceError):
    """The axis has not been calibrated since power-up: home it first."""


FAULT_ADVICE = "clear it (Head.clear_faults) or home (Head.home)"
"""What clears a latched fault, in the driver's terms: CLEAR_FAULT to its micro, or homing."""


class Fault(DeviceError):
    """A latched fault (limit switch, stall, emergency stop, watchdog) refuses motion until cleared.

    Attributes
    ----------
    flags : int
        The axis flags (see hardware.commands.Flag) that describe the fault, 0 when not known.
    """

    def __init__(self, message: str, *, code: int = 0, fault_latched: bool = True, flags: int = 0,
                 advice: str = FAULT_ADVICE) -> None:
        super().__init__(message, code=code, fault_latched=fault_latched, advice=advice)
        self.flags = flags


class MotionTimeout(HardwareError):
    """An axis was still moving when the host stopped waiting for it."""


@contextmanager
def naming(what: str) -> Iterator[None]:
    """Prefix the message of a DeviceError raised inside the block with `what` (an axis or eye name),
    keeping its class and attributes."""
    try:
        yield
    except DeviceError as exc:
        # The message alone: str() would fold the advice into it, where a front end could not replace it.
        exc.args = (f"{what}: {exc.args[0] if exc.args else ''}", *exc.args[1:])
        raise
