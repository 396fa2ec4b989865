"""Host-side proxies of the three UNET micros, in the micros' own units (counts, millidegrees).

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": three micros on UNET, one each
for the galvanometers, the motorized lenses and the stepper motors. One class per kind, each a thin,
typed layer over `Bus.request` and the layouts of hardware.commands; physical units live one level up
(hardware.joint, hardware.eye). PING tells the kind of micro at an address, as Dynamixel's PING gives
the model number, so a wiring mistake shows up at start-up, not as a strange motion.
"""

from __future__ import annotations

from typing import NamedTuple

from .bus import Bus
from .commands import Cmd, Flag, Kind, LayoutError, pack, unpack
from .errors import BadLength, UnknownCommand

__all__ = ["AxisStatus", "GalvoMicro", "GalvoStatus", "LensMicro", "LensStatus", "Micro", "StepperMicro"]


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
        self.addr = addr
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
        ms = 0 if not period else round(period * 1000)
        if period and not 1 <= ms <= 0xFFFF:
            raise ValueError(f"period must be in [0.001, 65.535] seconds or None, got {period!r}")
        self.call(Cmd.WATCHDOG, ms)


class StepperMicro(Micro):
    """The stepper micro: axis 0 pan, axis 1 tilt; positions in encoder counts."""

    kind = Kind.STEPPER

    def home(self, axis: int) -> None:
        self.call(Cmd.HOME, axis)

    def move_to(self, axis: int, counts: int) -> None:
        self.call(Cmd.MOVE_TO, axis, counts)

    def set_profile(self, axis: int, vmax: int, accel: int) -> None:
        self.call(Cmd.SET_PROFILE, axis, vmax, accel)

    def axis_status(self, axis: int) -> AxisStatus:
        encoder, target, flags = self.call(Cmd.AXIS_STATUS, axis)
        return AxisStatus(encoder, target, Flag(flags))

    def limits(self, axis: int) -> tuple[int, int]:
        low, high = self.call(Cmd.GET_LIMITS, axis)
        return low, high


class GalvoMicro(Micro):
    """The galvanometer micro: eye 0 left, eye 1 right; mirror angles in millidegrees."""

    kind = Kind.GALVO

    def set_angles(self, eye: int, x: int, y: int) -> None:
        self.call(Cmd.GALVO_SET, eye, x, y)

    def get(self, eye: int) -> GalvoStatus:
        *angles, flags = self.call(Cmd.GALVO_GET, eye)
        return GalvoStatus(*angles, Flag(flags))


class LensMicro(Micro):
    """The lens micro: eye 0 left, eye 1 right; zoom, focus, iris in lens motor counts."""

    kind = Kind.LENS

    def home(self, eye: int) -> None:
        self.call(Cmd.LENS_HOME, eye)

    def set_counts(self, eye: int, zoom: int, focus: int, iris: int) -> None:
        self.call(Cmd.LENS_SET, eye, zoom, focus, iris)

    def get(self, eye: int) -> LensStatus:
        zoom, focus, iris, flags = self.call(Cmd.LENS_GET, eye)
        return LensStatus(zoom, focus, iris, Flag(flags))
