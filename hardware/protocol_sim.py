"""The ``sim://`` URL handler for pyserial: the simulated eye-head behind an ordinary serial port.

pyserial's ``serial.serial_for_url(url)`` looks for a module named ``protocol_<scheme>`` in each package
listed in ``serial.protocol_handler_packages``. `hardware.bus.register_sim_handler` adds ``"hardware"``
to that list, so that ``serial.serial_for_url("sim://?seed=1&drop=0.001", baudrate=115200)`` finds this
module and returns a `Serial` wrapped around a `hardware.simulator.World`. hardware.bus.open_port
registers it, so code that goes through the Bus never needs to.

The port is pyserial's own SerialBase, so the host code is exactly the code that drives a real port.
Its timeouts count virtual time (see hardware.simulator): a read returns as soon as the bytes it asked
for have arrived, or once its timeout has passed on the virtual clock, which `Serial.clock` exposes.

Reference: Poggio et al., "The MIT Vision Machine", section "The Eye-Head system"; the pyserial URL
handler documentation ("URL handlers", ``serial.protocol_handler_packages``).
"""

from __future__ import annotations

import random

import serial
from serial.serialutil import PortNotOpenError, SerialBase, SerialException

from .simulator import World

__all__ = ["Serial"]


class Serial(SerialBase):
    """A serial port whose far end is a simulated eye-head.

    Attributes
    ----------
    world : hardware.simulator.World
        The simulation, for tests and tools that inspect or disturb it.
    clock : hardware.simulator.World
        The virtual clock (``monotonic()`` and ``sleep()``) the port's timeouts count in.
    random : random.Random
        The seeded generator for the host's random choices.
    """

    # SerialBase (pyserial ships no types) sets is_open in its __init__; declared so that mypy knows its type.
    is_open: bool

    def open(self) -> None:
        if self.is_open:
            raise SerialException("port is already open")
        if self._port is None:
            raise SerialException("port must be configured before it can be used")
        self.world = World.from_url(self._port, baudrate=self._baudrate)
        self._unplugged = False
        self.is_open = True

    def unplug(self) -> None:
        """Pull the simulated USB-serial adapter out: from now on every read and write fails with the
        SerialException pyserial raises on Linux when that happens to a real one."""
        self._unplugged = True

    def close(self) -> None:
        self.is_open = False

    @property
    def clock(self) -> World:
        return self.world

    @property
    def random(self) -> random.Random:
        """The generator the host draws its random choices from (hardware.bus.Bus uses it for its
        first sequence number), seeded from the URL's seed so that a session repeats to the bit."""
        return self.world.host_random

    def _reconfigure_port(self) -> None:
        if self.is_open:
            # Changing the baud rate of an open port changes the byte time on the virtual wire.
            self.world.byte_time = 10.0 / self._baudrate

    def _require_open(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()
        if self._unplugged:
            raise SerialException(
                "device reports readiness to read but returned no data "
                "(device disconnected or multiple access on port?)"
            )

    @property
    def in_waiting(self) -> int:
        self._require_open()
        return self.world.host_waiting

    def read(self, size: int = 1) -> bytes:
        self._require_open()
        if self._timeout is None and not self.world.host_waiting:
            # pyserial would block for ever; nothing can arrive unless the host has sent something.
            data = self.world.host_read(size, None)
            if not data:
                raise SerialException(
                    "sim:// read with timeout=None and nothing on its way: it would block for ever"
                )
            return data
        return self.world.host_read(size, self._timeout)

    def write(self, data: bytes) -> int:
        self._require_open()
        data = serial.to_bytes(data)
        self.world.host_write(data)
        return len(data)

    def flush(self) -> None:
        self._require_open()
        self.world.host_flush()

    def reset_input_buffer(self) -> None:
        self._require_open()
        self.world.host_discard()

    def reset_output_buffer(self) -> None:
        self._require_open()

    def _update_rts_state(self) -> None:
        """RTS has no meaning on the simulated wire."""

    def _update_dtr_state(self) -> None:
        """DTR has no meaning on the simulated wire."""

    def _update_break_state(self) -> None:
        """A break has no meaning on the simulated wire."""
