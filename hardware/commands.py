"""The UNET command set of the three eye-head micros: codes, payload layouts, status codes and flags.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": one micro each for the
galvanometers, the motorized lenses and the stepper motors. The command set borrows from the proven
protocols: PING/STATUS and error bits in every status packet (Dynamixel 2.0), exception codes for a
refused request (Modbus RTU), refusal of out-of-limit commands, limits read back by the host at start-up
and latched limit errors (the FLIR/Directed Perception pan-tilt units).

The host (hardware.micros) and the simulated firmware (hardware.firmware) both pack and unpack payloads
through `pack` and `unpack`, so the two sides cannot disagree about a layout.
"""

from __future__ import annotations

import struct
from enum import IntEnum, IntFlag

__all__ = [
    "ACCEL_LIMIT",
    "FAULT_BIT",
    "FAULT_FLAGS",
    "GALVO_ADDR",
    "LENS_ADDR",
    "PROTOCOL_VERSION",
    "STEPPER_ADDR",
    "VMAX_LIMIT",
    "Cmd",
    "Error",
    "Flag",
    "Kind",
    "LayoutError",
    "describe",
    "pack",
    "unpack",
]

# Version 2: frames between A5 flags with byte stuffing (version 1 had a sync byte only).
PROTOCOL_VERSION = 2
FAULT_BIT = 0x80
# The factory addresses of the three micros.
STEPPER_ADDR, GALVO_ADDR, LENS_ADDR = 1, 2, 3
# The ranges SET_PROFILE accepts; the host checks them before sending, the stepper micro again.
VMAX_LIMIT = 60_000  # counts/s: about 53 degrees/s at the joint
ACCEL_LIMIT = 400_000  # counts/s^2


class Cmd(IntEnum):
    """Command codes. 0x0_: every micro; 0x1_: steppers; 0x2_: galvanometers; 0x3_: lenses."""

    PING = 0x01
    STATUS = 0x02
    CLEAR_FAULT = 0x03
    STOP = 0x04
    ESTOP = 0x05
    WATCHDOG = 0x06
    HOME = 0x10
    MOVE_TO = 0x11
    SET_PROFILE = 0x12
    AXIS_STATUS = 0x13
    GET_LIMITS = 0x14
    GALVO_SET = 0x20
    GALVO_GET = 0x21
    LENS_HOME = 0x30
    LENS_SET = 0x31
    LENS_GET = 0x32


class Kind(IntEnum):
    """The kind of micro, returned by PING."""

    STEPPER = 1
    GALVO = 2
    LENS = 3


class Error(IntEnum):
    """Error codes, bits 0..6 of a reply's STATUS byte."""

    OK = 0
    BUSY = 1
    UNKNOWN_COMMAND = 2
    BAD_LENGTH = 3
    OUT_OF_RANGE = 4
    NOT_HOMED = 5
    FAULT = 6


class Flag(IntFlag):
    """Axis flags. The FAULT_* flags are latched until CLEAR_FAULT (or HOME, for a stepper axis)."""

    MOVING = 0x0001
    HOMED = 0x0002
    HOMING = 0x0004
    LIMIT_NEG = 0x0008
    LIMIT_POS = 0x0010
    FAULT_LIMIT = 0x0020
    FAULT_STALL = 0x0040
    FAULT_ESTOP = 0x0080
    FAULT_WATCHDOG = 0x0100


FAULT_FLAGS = Flag.FAULT_LIMIT | Flag.FAULT_STALL | Flag.FAULT_ESTOP | Flag.FAULT_WATCHDOG

_WORDS = {
    Flag.MOVING: "moving",
    Flag.HOMED: "homed",
    Flag.HOMING: "homing",
    Flag.LIMIT_NEG: "on the negative limit switch",
    Flag.LIMIT_POS: "on the positive limit switch",
    Flag.FAULT_LIMIT: "FAULT: limit switch hit",
    Flag.FAULT_STALL: "FAULT: stalled",
    Flag.FAULT_ESTOP: "FAULT: emergency stop",
    Flag.FAULT_WATCHDOG: "FAULT: watchdog (the host fell silent)",
}


def describe(flags: int) -> str:
    """Flags in words, e.g. ``"homed, FAULT: stalled"``; ``"idle"`` when none is set."""
    return ", ".join(word for flag, word in _WORDS.items() if flags & flag) or "idle"


# (request layout, reply layout) as little-endian struct formats.
_LAYOUTS: dict[Cmd, tuple[str, str]] = {
    Cmd.PING: ("<", "<BB"),  # -> kind, protocol version
    Cmd.STATUS: ("<", "<H"),  # -> OR of the flags of every axis
    Cmd.CLEAR_FAULT: ("<", "<"),
    Cmd.STOP: ("<", "<"),
    Cmd.ESTOP: ("<", "<"),
    Cmd.WATCHDOG: ("<H", "<"),  # period in ms, 0 disarms
    Cmd.HOME: ("<B", "<"),  # axis
    Cmd.MOVE_TO: ("<Bi", "<"),  # axis, target in encoder counts
    Cmd.SET_PROFILE: ("<BII", "<"),  # axis, max velocity counts/s, acceleration counts/s^2
    Cmd.AXIS_STATUS: ("<B", "<iiH"),  # axis -> encoder count, target, flags
    Cmd.GET_LIMITS: ("<B", "<ii"),  # axis -> soft limits, counts
    Cmd.GALVO_SET: ("<Bhh", "<"),  # eye, mirror angles in millidegrees
    Cmd.GALVO_GET: ("<B", "<hhhhH"),  # eye -> angles, target angles (millidegrees), flags
    Cmd.LENS_HOME: ("<B", "<"),  # eye
    Cmd.LENS_SET: ("<BHHH", "<"),  # eye, zoom, focus, iris in lens counts
    Cmd.LENS_GET: ("<B", "<hhhH"),  # eye -> zoom, focus, iris counts (negative before homing), flags
}
_STRUCTS = {cmd: (struct.Struct(req), struct.Struct(rep)) for cmd, (req, rep) in _LAYOUTS.items()}


class LayoutError(ValueError):
    """A payload whose length does not fit its command's layout, or an unknown command."""


def _struct(cmd: int, reply: bool) -> struct.Struct:
    try:
        return _STRUCTS[Cmd(cmd)][reply]
    except ValueError:
        raise LayoutError(f"unknown command 0x{cmd:02x}") from None


def pack(cmd: int, *values: int, reply: bool = False) -> bytes:
    """Pack the arguments of a request (or, with ``reply=True``, the data of a reply) to `cmd`."""
    try:
        return _struct(cmd, reply).pack(*values)
    except struct.error as exc:
        raise LayoutError(f"{Cmd(cmd).name}: {exc}") from None


def unpack(cmd: int, payload: bytes, *, reply: bool = False) -> tuple[int, ...]:
    """Unpack a request's (or, with ``reply=True``, a reply's) payload to `cmd`."""
    layout = _struct(cmd, reply)
    if len(payload) != layout.size:
        raise LayoutError(f"{Cmd(cmd).name} expects {layout.size} payload bytes, got {len(payload)}")
    return layout.unpack(payload)
