"""Host-side proxies of the three UNET micros, in the micros' own units (counts, millidegrees).

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": three micros on UNET, one each
for the galvanometers, the motorized lenses and the stepper motors. One class per kind, each a thin,
typed layer over `Bus.request` and the layouts of hardware.commands; physical units live one level up
(hardware.joint, hardware.eye). PING tells the kind of micro at an address, as Dynamixel's PING gives
the model number, so a wiring mistake shows up at start-up, not as a strange motion.
"""

from __future__ import annotations

from typing import NamedTuple

from .arguments import check_int, check_number
from .bus import Bus
from .commands import ACCEL_LIMIT, VMAX_LIMIT, Cmd, Flag, Kind, LayoutError, pack, unpack
from .errors import BadLength, UnknownCommand
from .physics import GALVO_RANGE_MDEG, LENS_COUNTS
from .protocol import MAX_ADDRESS

__all__ = [
    "WATCHDOG_RANGE",
    "AxisStatus",
    "GalvoMicro",
    "GalvoStatus",
    "LensMicro",
    "LensStatus",
    "Micro",
    "StepperMicro",
]

# Every micro drives two of something: the stepper axes 0 pan and 1 tilt, the galvo and lens micros
# eyes 0 left and 1 right (PROTOCOL.md).
_LAST_INDEX = 1
_INT32 = (-(2**31), 2**31 - 1)
WATCHDOG_RANGE = (0.001, 65.535)  # seconds: WATCHDOG takes 1..65535 ms (0 disarms)


class AxisStatus(NamedTuple):
    """A stepper axis: encoder count, target count, flags."""

    encoder: int
    target: int
    flags: Flag


class GalvoStatus(NamedTuple):
    """A mirror pair: angles and target angles in millidegrees, flags."""

    x: int
    y: int
    target_x: int
    target_y: int
    flags: Flag


class LensStatus(NamedTuple):
    """A lens: zoom, focus and iris motor counts, flags (OR of the three axes)."""

    zoom: int
    focus: int
    iris: int
    flags: Flag


class Micro:
    """One micro on the bus.

    Parameters
    ----------
    bus : Bus
    addr : int
        Its address, 1..31.
    name : str, optional
        For messages; by default the kind and address.
    """

    kind: Kind

    def __init__(self, bus: Bus, addr: int, name: str | None = None) -> None:
        if not isinstance(bus, Bus):
            raise TypeError(f"bus must be a hardware.bus.Bus, got {type(bus).__name__}")
        self.bus = bus
        self.addr = check_int("addr", addr, 1, MAX_ADDRESS)
        self.name = name or f"{self.kind.name.lower()} micro"

    def __repr__(self) -> str:
        return f"{type(self).__name__}(addr={self.addr})"

    def call(self, cmd: Cmd, *args: int) -> tuple[int, ...]:
        """Send `cmd` with `args` and return the reply's values."""
        reply = self.bus.request(self.addr, cmd, pack(cmd, *args), who=self.name)
        try:
            return unpack(cmd, reply.payload, reply=True)
        except LayoutError as exc:
            raise BadLength(
                f"{self.name} sent a malformed {cmd.name} reply ({exc}); firmware version mismatch?"
            )

    def ping(self) -> tuple[Kind | int, int]:
        """The micro's kind and protocol version."""
        kind, version = self.call(Cmd.PING)
        return (Kind(kind) if kind in Kind._value2member_map_ else kind), version

    def check_kind(self) -> None:
        """Raise UnknownCommand unless the micro at this address is of this class's kind."""
        kind, _ = self.ping()
        if kind != self.kind:
            found = kind.name.lower() if isinstance(kind, Kind) else f"kind {kind}"
            raise UnknownCommand(
                f"address {self.addr}: expected the {self.kind.name.lower()} micro, found a {found} micro; "
                "check the addresses given to Head"
            )

    def status(self) -> Flag:
        """The OR of the flags of every axis of the micro."""
        return Flag(self.call(Cmd.STATUS)[0])

    def clear_fault(self) -> None:
        """Clear every latched fault (the cause must be gone, or it latches again)."""
        self.call(Cmd.CLEAR_FAULT)

    def stop(self) -> None:
        """Bring every axis to rest, decelerating."""
        self.call(Cmd.STOP)

    def estop(self) -> None:
        """Stop every axis at once and latch FAULT_ESTOP."""
        self.call(Cmd.ESTOP)

    def set_watchdog(self, period: float | None) -> None:
        """Stop every axis and latch FAULT_WATCHDOG if the host is silent for `period` seconds.

        Parameters
        ----------
        period : float or None
            0.001 to 65.535 seconds; None (or 0) disarms the watchdog.
        """
        disarm = period is None or (not isinstance(period, bool) and period == 0)
        ms = (
            0
            if disarm
            else round(check_number("period", period, *WATCHDOG_RANGE, "seconds (or None)") * 1000)
        )
        self.call(Cmd.WATCHDOG, ms)


def _index(name: str, value: object) -> int:
    return check_int(name, value, 0, _LAST_INDEX)


class StepperMicro(Micro):
    """The stepper micro: axis 0 pan, axis 1 tilt; positions in encoder counts."""

    kind = Kind.STEPPER

    def __init__(self, bus: Bus, addr: int, name: str | None = None) -> None:
        super().__init__(bus, addr, name)
        # The soft limits of each axis once read from the micro: later moves are checked against them.
        self._limits: dict[int, tuple[int, int]] = {}

    def home(self, axis: int) -> None:
        self.call(Cmd.HOME, _index("axis", axis))

    def move_to(self, axis: int, counts: int) -> None:
        """Start a move to `counts`, checked against the soft limits when `limits` has read them."""
        axis = _index("axis", axis)
        counts = check_int("counts", counts, *self._limits.get(axis, _INT32))
        self.call(Cmd.MOVE_TO, axis, counts)

    def set_profile(self, axis: int, vmax: int, accel: int) -> None:
        """Top speed `vmax` (counts/s, 1..VMAX_LIMIT) and acceleration `accel` (counts/s^2,
        1..ACCEL_LIMIT) of later moves."""
        axis = _index("axis", axis)
        vmax = check_int("vmax", vmax, 1, VMAX_LIMIT)
        accel = check_int("accel", accel, 1, ACCEL_LIMIT)
        self.call(Cmd.SET_PROFILE, axis, vmax, accel)

    def axis_status(self, axis: int) -> AxisStatus:
        encoder, target, flags = self.call(Cmd.AXIS_STATUS, _index("axis", axis))
        return AxisStatus(encoder, target, Flag(flags))

    def limits(self, axis: int) -> tuple[int, int]:
        axis = _index("axis", axis)
        low, high = self.call(Cmd.GET_LIMITS, axis)
        self._limits[axis] = (low, high)
        return low, high


class GalvoMicro(Micro):
    """The galvanometer micro: eye 0 left, eye 1 right; mirror angles in millidegrees."""

    kind = Kind.GALVO

    def set_angles(self, eye: int, x: int, y: int) -> None:
        """Turn the mirrors to `x`, `y` millidegrees (each within +-GALVO_RANGE_MDEG)."""
        eye = _index("eye", eye)
        angles = [
            check_int(name, value, -GALVO_RANGE_MDEG, GALVO_RANGE_MDEG)
            for name, value in (("x", x), ("y", y))
        ]
        self.call(Cmd.GALVO_SET, eye, *angles)

    def get(self, eye: int) -> GalvoStatus:
        x, y, target_x, target_y, flags = self.call(Cmd.GALVO_GET, _index("eye", eye))
        return GalvoStatus(x, y, target_x, target_y, Flag(flags))


class LensMicro(Micro):
    """The lens micro: eye 0 left, eye 1 right; zoom, focus, iris in lens motor counts."""

    kind = Kind.LENS

    def home(self, eye: int) -> None:
        self.call(Cmd.LENS_HOME, _index("eye", eye))

    def set_counts(self, eye: int, zoom: int, focus: int, iris: int) -> None:
        """Move the lens motors to `zoom`, `focus`, `iris` counts (each 0..LENS_COUNTS - 1)."""
        eye = _index("eye", eye)
        counts = [
            check_int(name, value, 0, LENS_COUNTS - 1)
            for name, value in (("zoom", zoom), ("focus", focus), ("iris", iris))
        ]
        self.call(Cmd.LENS_SET, eye, *counts)

    def get(self, eye: int) -> LensStatus:
        zoom, focus, iris, flags = self.call(Cmd.LENS_GET, _index("eye", eye))
        return LensStatus(zoom, focus, iris, Flag(flags))
