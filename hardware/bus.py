"""The host's end of UNET: one master, up to 31 micros, over any pyserial port.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": the micros on UNET are slaves
that "speak when spoken to"; the host is the single master. The Bus sends one request at a time (a
lock makes it safe to share between threads), waits for the matching reply, and retries a bounded
number of times with the same sequence number, as a Modbus RTU master does after a timeout. The micro
answers a retry from its memory of its last (sequence, reply), so a command never runs twice
(hardware/PROTOCOL.md). A broadcast (address 0) is sent and never waited for, as in Dynamixel 2.0.

Ports come from ``serial.serial_for_url``, so a device path (``/dev/ttyUSB0``), a pty, any pyserial
URL (``rfc2217://``, ``socket://``) and the simulator (``sim://``, hardware.protocol_sim) all work.
"""

from __future__ import annotations

import random
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import serial

from .arguments import check_number
from .commands import FAULT_BIT, Cmd, Error
from .errors import (
    FAULT_ADVICE,
    BadLength,
    Busy,
    CorruptFrame,
    DeviceError,
    Fault,
    MotionTimeout,
    NotHomed,
    OutOfRange,
    PortError,
    Timeout,
    UnknownCommand,
)
from .protocol import BROADCAST, LONGEST_FRAME, MAX_ADDRESS, Frame, Parser, encode_request

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = ["POLL_FAILURES", "Bus", "BusStats", "Clock", "WallClock", "open_port", "register_sim_handler"]

# The longest sleep or wait the Bus accepts, seconds: a day. Longer ones (inf, 1e308) are mistakes that
# would hang the host, or overflow the simulator's clock.
_LONGEST_WAIT = 86_400.0

POLL_FAILURES = 3
"""Polls in a row whose every retry failed (Timeout, CorruptFrame) before :meth:`Bus.wait_for` gives up: on a
noisy line one such poll is bad luck that a long wait meets (a homing polls thousands of times); several in a
row, a micro or line that is gone."""


class Clock(Protocol):
    """What the Bus needs of a clock: the wall clock for real ports, the virtual one for ``sim://``."""

    def monotonic(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class WallClock:
    """The wall clock."""

    monotonic = staticmethod(time.monotonic)
    sleep = staticmethod(time.sleep)


def register_sim_handler() -> None:
    """Make ``sim://`` URLs known to ``serial.serial_for_url``: add this package to
    ``serial.protocol_handler_packages``, where pyserial looks for the module ``protocol_sim``
    (hardware.protocol_sim). Idempotent; `open_port` calls it."""
    if "hardware" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("hardware")


def open_port(url: str, *, baudrate: int = 115200) -> serial.SerialBase:
    """Open a serial port or pyserial URL, ``sim://`` included (registered here, explicitly).

    Parameters
    ----------
    url : str
        A device (``/dev/ttyUSB0``, ``COM3``, a pty path) or a URL (``sim://?seed=1``, ``socket://...``).
    baudrate : int
        Bits per second; the eye-head runs at 115200 by default.

    The port is opened for this process alone (pyserial's ``exclusive``: a lock on POSIX, the system's own
    rule on Windows): two hosts on one line would interleave their frames.

    Raises
    ------
    PortError
        The port would not open (no such device, no permission, busy or held by another program).
    """
    if not isinstance(url, str) or not url:
        raise TypeError(f"url must be a non-empty str, got {url!r}")
    if isinstance(baudrate, bool) or not isinstance(baudrate, int) or baudrate <= 0:
        raise ValueError(f"baudrate must be a positive int, got {baudrate!r}")
    register_sim_handler()
    try:
        return serial.serial_for_url(url, baudrate=baudrate, timeout=0, exclusive=True)
    except (serial.SerialException, OSError) as exc:
        raise PortError(f"cannot use port {url!r}: {exc}") from exc


@contextmanager
def _port_failures(port: serial.SerialBase) -> Iterator[None]:
    """Turn a failing port (pyserial raises SerialException, an OSError, when a device vanishes) into
    the driver's own PortError, so a caller needs to catch only HardwareError."""
    try:
        yield
    except (serial.SerialException, OSError) as exc:
        raise PortError(
            f"the serial port {getattr(port, 'port', None)!r} failed ({exc}); "
            "is the head still plugged in and powered?"
        ) from exc


# Each refusal: its class, what happened, and what to do next (the error's advice).
_DEVICE_ERRORS: dict[int, tuple[type[DeviceError], str, str]] = {
    Error.BUSY: (Busy, "the axis is busy homing", "wait for it, or stop it first"),
    Error.UNKNOWN_COMMAND: (UnknownCommand, "unknown command", "is the right kind of micro at this address?"),
    Error.BAD_LENGTH: (BadLength, "bad payload length", "host and firmware disagree on the protocol version"),
    Error.OUT_OF_RANGE: (OutOfRange, "argument out of range (beyond the soft limits?); nothing moved", ""),
    Error.NOT_HOMED: (NotHomed, "the axis is not homed", "home it first (Head.home)"),
    Error.FAULT: (Fault, "a fault is latched", FAULT_ADVICE),
}


@dataclass
class BusStats:
    """Counters of what happened on the bus since it was opened."""

    requests: int = 0
    broadcasts: int = 0
    retries: int = 0
    failures: int = 0
    stale_replies: int = 0


class Bus:
    """The UNET master.

    Parameters
    ----------
    port : str or serial.SerialBase
        A URL or device for `open_port`, or a port already open (then the Bus does not close it).
    baudrate : int
        Used when `port` is a URL or device.
    timeout : float
        Seconds to wait for each reply.
    retries : int
        How many times to resend a request that got no valid reply.
    clock : Clock, optional
        The clock timeouts are measured on; by default the port's own ``clock`` attribute when it has
        one (the simulator's virtual clock), else the wall clock.

    Attributes
    ----------
    port : serial.SerialBase
    stats : BusStats
    """

    def __init__(
        self,
        port: str | serial.SerialBase = "sim://",
        *,
        baudrate: int = 115200,
        timeout: float = 0.05,
        retries: int = 3,
        clock: Clock | None = None,
    ) -> None:
        if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0.0 < timeout < 60.0:
            raise ValueError(f"timeout must be a number of seconds in (0, 60), got {timeout!r}")
        if not isinstance(retries, int) or isinstance(retries, bool) or not 0 <= retries <= 100:
            raise ValueError(f"retries must be an int in 0..100, got {retries!r}")
        if not isinstance(port, str) and not (hasattr(port, "read") and hasattr(port, "write")):
            raise TypeError(f"port must be a serial device or URL (str) or an open pyserial port, got {port!r}")
        self._owns_port = isinstance(port, str)
        self._closed = False
        self.port = open_port(port, baudrate=baudrate) if isinstance(port, str) else port
        self.clock: Clock = clock or getattr(self.port, "clock", None) or WallClock()
        self.timeout = float(timeout)
        self.retries = retries
        self.stats = BusStats()
        self._parser = Parser()
        self._lock = threading.RLock()
        # A fresh host starts its sequence numbers at random, so a micro's memory of the last request
        # of a previous host session is not mistaken for a retry of this session's first request. The
        # simulator's port offers a seeded generator, so that a simulated session repeats to the bit.
        start = (getattr(self.port, "random", None) or random.SystemRandom()).randrange(256)
        self._seq = dict.fromkeys(range(MAX_ADDRESS + 1), start)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the port, if the Bus opened it; the Bus (and a Head on it) then refuses every request."""
        self._closed = True
        if self._owns_port:
            with _port_failures(self.port):
                self.port.close()

    def _silence_advice(self) -> str:
        """Why a micro may not have answered: where the longest reply takes much of the reply timeout on the
        wire at the port's baud rate (10 bits a byte, every byte stuffed), the timeout is the likely cause;
        else the micro itself."""
        baudrate = getattr(self.port, "baudrate", None)
        if isinstance(baudrate, (int, float)) and baudrate > 0:
            longest = 10 * 2 * LONGEST_FRAME / baudrate
            if longest > self.timeout / 2:
                return (f"at {baudrate:g} baud the longest reply takes up to {longest * 1000:.0f} ms on the wire: "
                        "raise the reply timeout (timeout; vmcl-head --timeout)")
        return "is it powered, wired, at that address?"

    def sleep(self, seconds: float) -> None:
        """Sleep on the bus's clock (virtual time on the simulator), 0 to a day."""
        self.clock.sleep(check_number("seconds", seconds, 0.0, _LONGEST_WAIT, "seconds"))

    def request(self, addr: int, cmd: int, payload: bytes = b"", *, who: str | None = None) -> Frame:
        """Send a request to micro `addr` and return its reply.

        Parameters
        ----------
        addr : int
            1..31.
        cmd : int
            Command code (hardware.commands.Cmd).
        payload : bytes
            Packed arguments.
        who : str, optional
            How to name the micro in error messages.

        Returns
        -------
        Frame
            The reply, whose status reports success.

        Raises
        ------
        Timeout
            No reply after ``retries + 1`` attempts.
        CorruptFrame
            Only corrupted replies after ``retries + 1`` attempts.
        PortError
            The port failed (the device is gone).
        DeviceError
            The micro refused the command (a subclass per error code).
        """
        if not isinstance(addr, int) or isinstance(addr, bool) or not 1 <= addr <= MAX_ADDRESS:
            raise ValueError(f"addr must be an int in 1..{MAX_ADDRESS} (0 is broadcast), got {addr!r}")
        who = who or f"micro {addr}"
        if self._closed:
            raise PortError(f"this Bus (or the Head on it) was closed; open a new one to reach {who}")
        with self._lock, _port_failures(self.port):
            seq = self._seq[addr] = (self._seq[addr] + 1) & 0xFF
            frame = encode_request(addr, seq, cmd, payload)
            self.stats.requests += 1
            corrupt_before = self._parser.crc_errors + self._parser.dropped
            for attempt in range(self.retries + 1):
                if attempt:
                    self.stats.retries += 1
                self.port.write(frame)
                reply = self._await(addr, seq, cmd)
                if reply is not None:
                    break
            else:
                self.stats.failures += 1
                what = (
                    f"{who} (address {addr}) gave no valid reply to {_name(cmd)} in {self.retries + 1} tries"
                )
                if self._parser.crc_errors + self._parser.dropped > corrupt_before:
                    raise CorruptFrame(f"{what}: replies came back corrupted; check wiring, baud rate, noise")
                raise Timeout(f"{what} ({self.timeout * 1000:.0f} ms each); {self._silence_advice()}")
        status = reply.status
        assert status is not None  # _await returns only replies, and every reply carries a status
        code = status & ~FAULT_BIT
        if code != Error.OK:
            kind, what, advice = _DEVICE_ERRORS.get(code, (DeviceError, f"error code {code}", ""))
            raise kind(
                f"{who} refused {_name(cmd)}: {what}",
                code=code,
                fault_latched=bool(status & FAULT_BIT),
                advice=advice,
            )
        return reply

    def _await(self, addr: int, seq: int, cmd: int) -> Frame | None:
        deadline = self.clock.monotonic() + self.timeout
        port, parser = self.port, self._parser
        while (remaining := deadline - self.clock.monotonic()) > 0.0:
            port.timeout = remaining
            chunk = port.read(max(parser.bytes_needed(), port.in_waiting))
            found = None
            for frame in parser.feed(chunk):
                if (
                    found is None
                    and frame.is_reply
                    and (frame.addr, frame.seq, frame.cmd) == (addr, seq, cmd)
                ):
                    found = frame
                else:
                    self.stats.stale_replies += 1
            if found is not None:
                return found
        return None

    def broadcast(self, cmd: int, payload: bytes = b"") -> None:
        """Send `cmd` to every micro at once. No micro answers a broadcast, so this returns as soon as
        the frame is on the wire; it cannot report whether anyone heard it."""
        with self._lock, _port_failures(self.port):
            seq = self._seq[BROADCAST] = (self._seq[BROADCAST] + 1) & 0xFF
            self.port.write(encode_request(BROADCAST, seq, cmd, payload))
            self.port.flush()
            self.stats.broadcasts += 1

    def wait_for(
        self, done: Callable[[], bool], *, timeout: float, what: str, interval: float = 0.02
    ) -> None:
        """Poll `done` every `interval` seconds (on the bus's clock) until it returns True.

        Raises
        ------
        MotionTimeout
            `done` was still False after `timeout` seconds (0 to a day).
        """
        check_number("timeout", timeout, 0.0, _LONGEST_WAIT, "seconds")
        check_number("interval", interval, 1e-6, _LONGEST_WAIT, "seconds")
        deadline = self.clock.monotonic() + timeout
        failed = 0
        while True:
            # A poll only reads state, so one whose every retry was lost on a noisy line is asked again: a
            # long wait (homing sends thousands of polls) would otherwise end at the first unlucky one.
            # Several in a row mean the line or the micro is gone; a failed port is never retried.
            try:
                if done():
                    return
                failed = 0
            except (Timeout, CorruptFrame):
                failed += 1
                if failed >= POLL_FAILURES:
                    raise
            if self.clock.monotonic() >= deadline:
                raise MotionTimeout(f"{what} did not finish within {timeout:g} s; it may be obstructed")
            self.clock.sleep(interval)


def _name(cmd: int) -> str:
    try:
        return Cmd(cmd).name
    except ValueError:
        return f"command 0x{cmd:02x}"
