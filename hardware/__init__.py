"""The eye-head of the MIT Vision Machine: a driver over pyserial and a faithful simulator.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": two eyes (a motorized zoom lens
and two galvanometer mirrors each) on a pan/tilt head driven by stepper motors through harmonic drives,
controlled over UNET, a multi-drop network of micros that speak only when spoken to. The wire protocol
(hardware/PROTOCOL.md) follows Dynamixel Protocol 2.0, Modbus RTU and the FLIR/Directed Perception
pan-tilt units.

Modules, one job each: protocol (byte-stuffed framing, CRC-16, parser), commands (command set), bus (the
master over pyserial), micros (one proxy class per micro kind), joint and eye (axes in physical units),
head (the whole head), arguments (argument checks before sending), errors; physics, firmware and
simulator (the simulated head on a virtual clock), protocol_sim (the ``sim://`` pyserial URL handler),
ptyserver (the simulator on a pty), cli (``vmcl-head``).

Example
-------
>>> from hardware import Head
>>> with Head("sim://?seed=1") as head:
...     head.home()
...     head.move(pan=-20.0, tilt=-45.0)
...     round(head.tilt.position, 2)
-45.0
"""

from .bus import Bus, open_port, register_sim_handler
from .errors import (
    BadLength,
    Busy,
    CommError,
    CorruptFrame,
    DeviceError,
    Fault,
    HardwareError,
    MotionTimeout,
    NotHomed,
    OutOfRange,
    PortError,
    Timeout,
    UnknownCommand,
)
from .eye import Eye, EyeStatus
from .head import Head, HeadStatus
from .joint import Joint, JointStatus

__all__ = [
    "BadLength",
    "Bus",
    "Busy",
    "CommError",
    "CorruptFrame",
    "DeviceError",
    "Eye",
    "EyeStatus",
    "Fault",
    "HardwareError",
    "Head",
    "HeadStatus",
    "Joint",
    "JointStatus",
    "MotionTimeout",
    "NotHomed",
    "OutOfRange",
    "PortError",
    "Timeout",
    "UnknownCommand",
    "open_port",
    "register_sim_handler",
]
