"""Serve the simulated eye-head on a pseudo-terminal, so that a host in another process can drive it.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": the host talks to the head's
micros over a serial line. Here the far end of that line is a pty whose other side plays the three
micros (hardware.simulator), so a host program opens an ordinary serial device, exactly as it would
open the USB-serial adapter of the real head, and nothing in it knows the difference.

Usage::

    python -m hardware.ptyserver ['sim://?seed=1&drop=0.001'] [--rate 20]

prints the device path (e.g. ``/dev/pts/7``) on the first line of standard output, then serves until
it is terminated or its parent process exits. The virtual clock follows the wall clock, `rate` times
faster (to home the head in less than its real 11 s, say); replies go out when their bytes would have
reached the host at the line's baud rate (115200 unless the URL's owner says otherwise: a pty has no
baud rate of its own).
"""

from __future__ import annotations

import os
import select
import sys
import time
import tty

from .arguments import OneLineParser, check_number
from .simulator import World

__all__ = ["RATE_RANGE", "main", "serve"]

_POLL = 0.001  # seconds between looks at the wire: the pty's own latency is of this order
# Virtual seconds per wall-clock second. Beyond a thousand, one poll of the wire lets a whole reply
# timeout pass in virtual time, so no host could keep up.
RATE_RANGE = (0.001, 1000.0)


def serve(world: World, master: int, *, rate: float = 1.0, parent: int | None = None) -> None:
    """Play `world` on the master side `master` of a pty until `parent` (a pid) is no longer our
    parent process, or for ever.

    Parameters
    ----------
    world : World
    master : int
        File descriptor of the pty's master side.
    rate : float
        Virtual seconds per wall-clock second.
    parent : int, optional
        Stop when our parent process is no longer this one (it exited).
    """
    check_number("rate", rate, *RATE_RANGE, "virtual seconds per second")
    start = time.monotonic()
    while parent is None or os.getppid() == parent:
        readable, _, _ = select.select([master], [], [], _POLL)
        world.advance_to((time.monotonic() - start) * rate)
        if readable:
            world.host_write(os.read(master, 4096))
        arrived = world.host_read(world.host_waiting, 0.0)
        if arrived:
            os.write(master, arrived)


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m hardware.ptyserver``."""
    parser = OneLineParser(prog="python -m hardware.ptyserver", description=__doc__.split("\n\n")[0])
    parser.add_argument("url", nargs="?", default="sim://", help="sim:// URL with fault and start options")
    parser.add_argument("--rate", type=float, default=1.0, help="virtual seconds per wall-clock second")
    parser.add_argument("--baud", type=int, default=115200, help="baud rate of the simulated line")
    # The parent is read before the port's name is printed: a parent that exits once it has read the name
    # could otherwise be gone already, and the server would take its adopter for its parent and never stop.
    parent = os.getppid()
    args = parser.parse_args(argv)
    try:
        check_number("--rate", args.rate, *RATE_RANGE, "virtual seconds per second")
        world = World.from_url(args.url, baudrate=args.baud)
    except ValueError as exc:
        parser.error(str(exc))
    master, slave = os.openpty()
    # Raw mode, so the line discipline neither echoes nor translates bytes. The slave stays open here
    # so that reads on the master do not fail between host sessions.
    tty.setraw(slave)
    print(os.ttyname(slave), flush=True)
    try:
        serve(world, master, rate=args.rate, parent=parent)
    except KeyboardInterrupt:
        pass
    finally:
        os.close(master)
        os.close(slave)
    return 0


if __name__ == "__main__":
    sys.exit(main())
