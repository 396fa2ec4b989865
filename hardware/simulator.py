"""The simulated eye-head: three micros on a virtual UNET, with physics on a virtual clock.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system" describes the apparatus; this
module puts its three micros (hardware.firmware, with the mechanics of hardware.physics) behind the real
byte protocol (hardware.protocol), so the host code under test is exactly the code that drives hardware.

Time is virtual. It advances only when the host waits: reading the port (until the bytes it wants have
arrived, or its timeout has passed), flushing it, or sleeping through `World.sleep`. Every byte takes
10 bit times on the wire at the port's baud rate; a micro answers `turnaround` seconds after the last
byte of a request; each micro's control loop moves its axes on a 1 kHz tick. A run is therefore fast and, for a given seed,
repeats to the bit.

The wire is a 4-wire multi-drop line (RS-422/RS-485 full duplex), as pyserial sees it: every micro hears
the host, the host hears every micro, micros do not hear each other. Faults can be injected on it, in
both directions, from a seeded random generator (per byte: drop, corrupt = flip one bit, duplicate; per
transmission: truncate, delay by `lag` seconds), and a micro can be absent. `World.tamper` changes the
next transmission in one direction exactly, for tests that need one particular fault.

The URL form, for ``serial.serial_for_url`` (see hardware.protocol_sim) and ``python -m
hardware.ptyserver``::

    sim://?seed=1&drop=0.001&corrupt=0.001&truncate=0&delay=0&lag=0.1&duplicate=0&absent=3&pan=10&tilt=-45

Reference for the fault model: the Modbus RTU specification (a slave ignores a frame with a bad CRC and
the master retries on timeout) and Dynamixel Protocol 2.0 (status packets, broadcast without replies).
"""

from __future__ import annotations

import math
import random
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields
from urllib.parse import parse_qsl, urlsplit

from .commands import GALVO_ADDR, LENS_ADDR, STEPPER_ADDR
from .firmware import (
    GalvoEye,
    GalvoFirmware,
    LensAxis,
    LensFirmware,
    MicroFirmware,
    StepperAxis,
    StepperFirmware,
)
from .physics import COUNTS_PER_DEGREE, LENS_COUNTS, PAN, TILT, JointGeometry, LensMechanism, StepperMechanism
from .protocol import BROADCAST, MAX_ADDRESS, Parser

__all__ = ["Faults", "World"]
_TICK = 1e-3
_SWITCH_SCATTER = 20.0  # counts


@dataclass(frozen=True)
class Faults:
    """Fault rates on the wire. Per byte: `drop`, `corrupt` (one bit flipped), `duplicate`; per
    transmission (a host write or a micro's reply): `truncate` (the rest is lost), `delay` (sent `lag`
    seconds late)."""

    drop: float = 0.0
    corrupt: float = 0.0
    duplicate: float = 0.0
    truncate: float = 0.0
    delay: float = 0.0
    lag: float = 0.1

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{f.name} must be a finite number >= 0, got {value!r}")
            if f.name != "lag" and value > 1.0:
                raise ValueError(f"{f.name} is a probability and must be in [0, 1], got {value!r}")

    def apply(self, data: bytes, rng: random.Random) -> tuple[float, list[int | None]]:
        """What reaches the far end of the wire.

        Returns
        -------
        delay : float
            Seconds the whole transmission is held back.
        slots : list of int or None
            One entry per byte time on the wire: the byte received, or None for a byte lost (it still
            took its time on the wire).
        """
        if not (self.drop or self.corrupt or self.duplicate or self.truncate or self.delay):
            return 0.0, list(data)
        slots: list[int | None] = []
        for byte in data:
            if rng.random() < self.drop:
                slots.append(None)
                continue
            if rng.random() < self.corrupt:
                byte ^= 1 << rng.randrange(8)
            slots.append(byte)
            if rng.random() < self.duplicate:
                slots.append(byte)
        if slots and rng.random() < self.truncate:
            del slots[rng.randrange(len(slots)) :]
        return (self.lag if rng.random() < self.delay else 0.0), slots


class World:
    """The three micros, their mechanics, the wire between them and the host, and the virtual clock.

    Parameters
    ----------
    seed : int
        Seeds the fault injection and the mechanics (start positions, switch scatter) separately.
    baudrate : int
        Bits per second on the wire (8N1: 10 bits per byte).
    faults : Faults
        Fault rates on the wire.
    absent : iterable of int
        Addresses of micros that are not on the bus (unpowered, unplugged).
    turnaround : float
        Seconds a micro takes to start its reply after the last byte of a request.
    pan, tilt : float, optional
        Where the joints are at power-up, degrees; by default drawn from the seed within the travel.

    Attributes
    ----------
    now : float
        The virtual time, seconds.
    stepper, galvo, lens : MicroFirmware
        The micros at addresses 1, 2 and 3 (present on the bus or not).
    micros : dict
        The micros present on the bus, by address.
    host_random : random.Random
        Seeded from `seed`, for the host's random choices, so that a run repeats to the bit.
    """

    def __init__(
        self,
        *,
        seed: int = 0,
        baudrate: int = 115200,
        faults: Faults | None = None,
        absent: Iterable[int] = (),
        turnaround: float = 3e-4,
        pan: float | None = None,
        tilt: float | None = None,
    ) -> None:
        if not isinstance(baudrate, int) or baudrate <= 0:
            raise ValueError(f"baudrate must be a positive int, got {baudrate!r}")
        if not 0.0 <= turnaround < math.inf:
            raise ValueError(f"turnaround must be a finite number >= 0 seconds, got {turnaround!r}")
        self.faults = faults or Faults()
        self.byte_time = 10.0 / baudrate
        self.turnaround = turnaround
        self.now = 0.0
        self._ticks = 0
        self._fault_rng = random.Random(f"{seed}/faults")
        mech_rng = random.Random(f"{seed}/mechanics")
        # The host's own random choices (its first sequence number) come from the seed too: frames are
        # byte-stuffed, so their lengths, and with them the timing and the faults that hit them, depend
        # on their content.
        self.host_random = random.Random(f"{seed}/host")

        def scatter() -> float:
            return mech_rng.uniform(-_SWITCH_SCATTER, _SWITCH_SCATTER)

        def joint(geometry: JointGeometry, start: float | None) -> StepperAxis:
            if start is None:
                position = mech_rng.uniform(geometry.soft_min, geometry.soft_max)
            else:
                position = start * COUNTS_PER_DEGREE
                if not geometry.hard_min <= position <= geometry.hard_max:
                    raise ValueError(f"start angle {start!r} is beyond the joint's mechanical stops")
            return StepperAxis(StepperMechanism(geometry, position, scatter))

        self.stepper = StepperFirmware(STEPPER_ADDR, [joint(PAN, pan), joint(TILT, tilt)])
        self.galvo = GalvoFirmware(GALVO_ADDR, [GalvoEye(), GalvoEye()])
        self.lens = LensFirmware(
            LENS_ADDR, [LensAxis(LensMechanism(mech_rng.uniform(100, LENS_COUNTS - 100))) for _ in range(6)]
        )
        absent = set(absent)
        for addr in absent:
            if not isinstance(addr, int) or not 1 <= addr <= MAX_ADDRESS:
                raise ValueError(f"absent addresses must be ints in 1..{MAX_ADDRESS}, got {addr!r}")
        self.micros: dict[int, MicroFirmware] = {
            m.addr: m for m in (self.stepper, self.galvo, self.lens) if m.addr not in absent
        }
        # Every micro's UART sees the same bytes, so one parser stands for all of them.
        self._parser = Parser()
        self._to_micros: deque[tuple[float, int]] = deque()
        self._to_host: deque[tuple[float, int]] = deque()
        self._tx_free = 0.0
        self._rx_free = 0.0
        self._tamper: dict[str, deque[Callable[[bytes], bytes]]] = {"request": deque(), "reply": deque()}

    @classmethod
    def from_url(cls, url: str, *, baudrate: int = 115200) -> World:
        """Build a world from a ``sim://?key=value&...`` URL (see the module docstring for the keys)."""
        parts = urlsplit(url)
        if parts.scheme.lower() != "sim" or parts.netloc or parts.path not in ("", "/"):
            raise ValueError(f"url must look like 'sim://?seed=1&drop=0.01', got {url!r}")
        fault_names = {f.name for f in fields(Faults)}
        known = sorted(fault_names | {"seed", "absent", "turnaround", "pan", "tilt"})
        kwargs: dict = {}
        faults: dict[str, float] = {}
        for key, value in parse_qsl(parts.query, keep_blank_values=True, strict_parsing=bool(parts.query)):
            if key not in known:
                raise ValueError(f"unknown sim:// parameter {key!r}; known: {', '.join(known)}")
            try:
                if key == "seed":
                    kwargs[key] = int(value)
                elif key == "absent":
                    kwargs[key] = [int(a) for a in value.split(",") if a]
                elif key in fault_names:
                    faults[key] = float(value)
                else:
                    kwargs[key] = float(value)
            except ValueError:
                raise ValueError(f"sim:// parameter {key!r} has a bad value {value!r}") from None
        return cls(baudrate=baudrate, faults=Faults(**faults), **kwargs)

    # --- the clock -------------------------------------------------------------------------------

    def monotonic(self) -> float:
        """The virtual time, seconds (the same interface as the wall clock's ``time.monotonic``)."""
        return self.now

    def sleep(self, seconds: float) -> None:
        """Let `seconds` of virtual time pass."""
        self.advance_to(self.now + max(0.0, seconds))

    def advance_to(self, t: float) -> None:
        """Run the micros and the wire up to virtual time `t`."""
        while self._to_micros and self._to_micros[0][0] <= t:
            arrival, byte = self._to_micros.popleft()
            self._deliver(byte, arrival)
        self._run_physics(t)

    def _run_physics(self, until: float) -> None:
        # Each micro runs its control loop on a 1 kHz timer, as real firmware does: the axes move on
        # that fixed grid of ticks, and a request is served with the state of the last tick before it.
        # Ticks run lazily, when a request arrives or an advance ends.
        last = math.floor(until / _TICK + 1e-9)
        if last > self._ticks:
            for micro in self.micros.values():
                if micro.busy:
                    for k in range(self._ticks + 1, last + 1):
                        micro.tick(k * _TICK, _TICK)
            self._ticks = last
        self.now = max(self.now, until)

    def _deliver(self, byte: int, arrival: float) -> None:
        for frame in self._parser.feed(bytes((byte,))):
            if frame.is_reply:
                continue
            self._run_physics(arrival)
            if frame.addr == BROADCAST:
                targets = list(self.micros.values())
            else:
                targets = [self.micros[frame.addr]] if frame.addr in self.micros else []
            for micro in targets:
                reply = micro.receive(frame, self.now)
                if reply is not None:
                    self._transmit(reply, "reply", self.now + self.turnaround)

    def _transmit(self, data: bytes, direction: str, ready: float) -> float:
        tamper = self._tamper[direction]
        if tamper:
            data = tamper.popleft()(data)
        delay, slots = self.faults.apply(data, self._fault_rng)
        line, free = (
            (self._to_host, self._rx_free) if direction == "reply" else (self._to_micros, self._tx_free)
        )
        start = max(ready, free) + delay
        for i, byte in enumerate(slots):
            if byte is not None:
                line.append((start + (i + 1) * self.byte_time, byte))
        end = start + len(slots) * self.byte_time
        if direction == "reply":
            self._rx_free = end
        else:
            self._tx_free = end
        return end

    def tamper(self, direction: str, change: Callable[[bytes], bytes]) -> None:
        """Pass the next transmission in `direction` ("request": host to micros, "reply": micro to host)
        through `change` before the random faults."""
        if direction not in self._tamper:
            raise ValueError(f"direction must be 'request' or 'reply', got {direction!r}")
        self._tamper[direction].append(change)

    # --- the host's end of the wire ------------------------------------------------------------------

    def host_write(self, data: bytes) -> None:
        """The host transmits `data` (it is on the wire from now on)."""
        self._transmit(bytes(data), "request", self.now)

    def host_flush(self) -> None:
        """Wait until everything the host wrote has been delivered."""
        self.advance_to(max(self.now, self._tx_free))

    @property
    def host_waiting(self) -> int:
        """Bytes that have reached the host and not been read."""
        n = 0
        for t, _ in self._to_host:
            if t > self.now:
                break
            n += 1
        return n

    def host_read(self, size: int, timeout: float | None) -> bytes:
        """Wait (in virtual time) until `size` bytes have reached the host or `timeout` has passed, and
        return what has arrived, at most `size` bytes."""
        deadline = math.inf if timeout is None else self.now + timeout
        while self.host_waiting < size:
            # The bytes the host already has on their way decide when it can next have more; until all
            # it sent has been delivered, replies may still be added.
            if len(self._to_host) >= size:
                upcoming = self._to_host[size - 1][0]
            elif self._to_micros:
                upcoming = self._to_micros[-1][0]
            else:
                upcoming = math.inf
            if upcoming > deadline or upcoming == math.inf:
                if deadline < math.inf:
                    self.advance_to(deadline)
                break
            self.advance_to(upcoming)
        count = min(size, self.host_waiting)
        return bytes(self._to_host.popleft()[1] for _ in range(count))

    def host_discard(self) -> None:
        """Drop what has reached the host and not been read."""
        for _ in range(self.host_waiting):
            self._to_host.popleft()
