"""The eye-head: pan and tilt joints carrying two eyes, one object, stopped safely on any exit.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": "the head moves the eyes as a
unit, while allowing the eyes to point independently"; three micros on UNET drive it (steppers,
galvanometers, lenses). Head opens the bus, checks with PING that each micro is of the expected kind
(Dynamixel 2.0 style), reads the joints' soft limits (as the ROS driver of the FLIR pan-tilt units
does), and can arm each micro's watchdog. As a context manager it stops every motor however the block
ends, an exception included: a decelerating STOP to each micro, confirmed by polling until nothing
moves; if the micros do not answer, an emergency stop by broadcast, which needs no reply.

Example
-------
>>> with Head("sim://?seed=1") as head:
...     head.home()
...     head.move(pan=30.0, tilt=-10.0)
...     round(head.pan.position, 3)
30.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .arguments import check_number, real_value
from .bus import Bus
from .commands import GALVO_ADDR, LENS_ADDR, STEPPER_ADDR, Cmd, Flag
from .errors import HardwareError, OutOfRange
from .eye import MIRROR_RANGE, Eye, EyeStatus, line_of_sight
from .joint import Joint, JointStatus
from .micros import WATCHDOG_RANGE, GalvoMicro, LensMicro, Micro, StepperMicro

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = ["Head", "HeadStatus"]

_HOME_TIMEOUT = 60.0  # seconds: a sweep of both joints to the switch, the creep, and back to 0
_MOVE_TIMEOUT = 20.0


@dataclass(frozen=True)
class HeadStatus:
    """Every axis of the head, in physical units."""

    pan: JointStatus
    tilt: JointStatus
    left: EyeStatus
    right: EyeStatus

    def __str__(self) -> str:
        return f"pan   {self.pan}\ntilt  {self.tilt}\nleft  {self.left}\nright {self.right}"


class Head:
    """The pan/tilt head with its two eyes.

    Parameters
    ----------
    port : str or Bus
        A serial device, pyserial URL or ``sim://`` URL (default: the simulator), or an open Bus
        (then Head does not close it).
    baudrate, timeout, retries : optional
        Passed to the Bus when `port` is a string.
    stepper, galvo, lens : int
        The micros' addresses.
    watchdog : float, optional
        Arm every micro's watchdog: if the host is silent this many seconds (0.001 to 65.535), motion
        stops and a fault latches.

    Attributes
    ----------
    bus : Bus
    pan, tilt : Joint
    left, right : Eye
    micros : tuple of Micro
    """

    def __init__(
        self,
        port: str | Bus = "sim://",
        *,
        baudrate: int = 115200,
        timeout: float = 0.05,
        retries: int = 3,
        stepper: int = STEPPER_ADDR,
        galvo: int = GALVO_ADDR,
        lens: int = LENS_ADDR,
        watchdog: float | None = None,
    ) -> None:
        if watchdog is not None:
            # Checked before the port opens, so a bad value sends nothing.
            check_number("watchdog", watchdog, *WATCHDOG_RANGE, "seconds")
        self._owns_bus = not isinstance(port, Bus)
        self.bus = (
            port if isinstance(port, Bus) else Bus(port, baudrate=baudrate, timeout=timeout, retries=retries)
        )
        try:
            self.stepper = StepperMicro(self.bus, stepper)
            self.galvo = GalvoMicro(self.bus, galvo)
            self.lens = LensMicro(self.bus, lens)
            self.micros: tuple[Micro, ...] = (self.stepper, self.galvo, self.lens)
            for micro in self.micros:
                micro.check_kind()
            self.pan = Joint(self.stepper, 0, "pan")
            self.tilt = Joint(self.stepper, 1, "tilt")
            self.left = Eye(self.galvo, self.lens, 0, "left")
            self.right = Eye(self.galvo, self.lens, 1, "right")
            if watchdog is not None:
                for micro in self.micros:
                    micro.set_watchdog(watchdog)
        except BaseException:
            self.close()
            raise

    def __repr__(self) -> str:
        return f"Head(port={self.bus.port.port!r})"

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object) -> None:
        # Leaving the block stops every motor. When the block itself failed, its error is the one the caller
        # sees: a stop, emergency stop or close that fails after it (on the port the first error lost)
        # would otherwise take its place.
        failure: HardwareError | None = None
        try:
            self.stop()
        except HardwareError as error:
            failure = error
            try:
                self.estop()  # the micros did not confirm the stop; an emergency stop needs no reply
            except HardwareError as also:
                failure = also  # its context is the stop's error
        try:
            self.close()
        except HardwareError as error:
            failure = failure or error
        if failure is not None and exc_type is None:
            raise failure

    def close(self) -> None:
        """Close the bus, if Head opened it."""
        if self._owns_bus:
            self.bus.close()

    @property
    def joints(self) -> tuple[Joint, Joint]:
        return self.pan, self.tilt

    @property
    def eyes(self) -> tuple[Eye, Eye]:
        return self.left, self.right

    def wait(self, *, timeout: float = _MOVE_TIMEOUT) -> None:
        """Wait until every joint, mirror and lens is at rest.

        Raises
        ------
        Fault
            A fault latched on the way (limit, stall, estop, watchdog).
        MotionTimeout
            Still moving after `timeout` seconds.
        """
        parts = (*self.joints, *self.eyes)

        def settled() -> bool:
            # Ask every part each time: a fault anywhere shows at once, and every micro's watchdog is fed.
            states = [part.settled() for part in parts]
            return all(states)

        self.bus.wait_for(settled, timeout=timeout, what="the head")

    def home(self, *, wait: bool = True) -> None:
        """Clear every latched fault and calibrate everything: each joint on its limit switch and index
        pulse (ending at 0 degrees), each lens on its home sensors; centre the mirrors."""
        self.clear_faults()
        for joint in self.joints:
            joint.home()
        for eye in self.eyes:
            eye.home_lens()
            eye.set_mirrors(0.0, 0.0)
        if wait:
            self.wait(timeout=_HOME_TIMEOUT)

    def move(self, pan: float | None = None, tilt: float | None = None, *, wait: bool = True) -> None:
        """Move the joints to `pan` and `tilt` degrees (None leaves a joint where it is).

        Both targets are checked against the soft limits before either joint is told to move, so an
        out-of-travel request moves nothing.
        """
        moves = [
            (joint, joint.counts(angle))
            for joint, angle in zip(self.joints, (pan, tilt))
            if angle is not None
        ]
        for joint, counts in moves:
            joint.move_to_counts(counts)
        if wait:
            self.wait()

    def stop(self, *, wait: bool = True) -> None:
        """Bring every motor to rest, decelerating; no fault latches."""
        for micro in self.micros:
            micro.stop()
        if wait:
            self.bus.wait_for(
                lambda: not any(m.status() & Flag.MOVING for m in self.micros),
                timeout=_MOVE_TIMEOUT,
                what="stop",
            )

    def estop(self) -> None:
        """Emergency stop: broadcast ESTOP (every micro stops every axis at once and latches
        FAULT_ESTOP; `clear_faults` or `home` to go on). Sent twice, since nobody answers a broadcast."""
        for _ in range(2):
            self.bus.broadcast(Cmd.ESTOP)

    def clear_faults(self) -> None:
        """Clear the latched faults of every micro."""
        for micro in self.micros:
            micro.clear_fault()

    def status(self) -> HeadStatus:
        return HeadStatus(self.pan.status(), self.tilt.status(), self.left.status(), self.right.status())

    def vergence(self) -> float:
        """The angle between the eyes' lines of sight in the horizontal plane, degrees: the left eye's
        azimuth minus the right eye's (positive when they converge)."""
        left, right = self.left.status(), self.right.status()
        return left.azimuth - right.azimuth

    def fixate(self, distance: float, *, baseline: float = 0.3, wait: bool = True) -> None:
        """Converge both eyes symmetrically on a point straight ahead at `distance` metres, with the
        eyes `baseline` metres apart; ``math.inf`` looks at infinity: parallel gaze, vergence 0 (as a lens
        focuses at inf). Nearer than the gaze limit lets each eye turn (about 0.41 m at the default
        baseline) is refused (OutOfRange, naming the nearest distance) before anything moves."""
        for name, value in (("distance", distance), ("baseline", baseline)):
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            # An int too large for a float is as far as inf; only the distance may be infinite.
            far = number and real_value(value) == math.inf and name == "distance"
            if not number or not (math.isfinite(real_value(value)) or far) or value <= 0:
                shown = f"{real_value(value):g}" if number else repr(value)
                also = " (or inf, parallel gaze)" if name == "distance" else ""
                raise ValueError(f"{name} must be a positive number of metres{also}, got {shown}")
        half = math.degrees(math.atan2(baseline / 2.0, real_value(distance)))
        # The widest sideways gaze the mirrors give, at elevation 0 (the gaze limit; the mirror angle limit is
        # MIRROR_RANGE): nearer than that, a refusal in mirror angles would speak of a gaze the caller never gave.
        widest = min(abs(line_of_sight(sign * MIRROR_RANGE, 0.0)[0]) for sign in (1.0, -1.0))
        if half > widest:
            nearest = baseline / 2.0 / math.tan(math.radians(widest))
            raise OutOfRange(f"distance {distance:g} m is nearer than the eyes can converge with a baseline of "
                             f"{baseline:g} m (each gaze would turn {half:.3g} deg; the gaze limit is {widest:.3g} "
                             f"deg, the mirror angles at their limit of +-{MIRROR_RANGE:g} deg): the nearest is "
                             f"{nearest:.3g} m; nothing moved")
        self.left.point(half, 0.0)
        self.right.point(-half, 0.0)
        if wait:
            self.wait()
