"""``vmcl-head``: drive the eye-head from the command line (the simulator unless --port says otherwise).

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system". Commands run in order, in one
session, so that a freshly powered head (or simulator) can be homed and moved in one call::

    vmcl-head home move 30 -10 point left 5 2 lens left zoom=50 focus=2 iris=4 status
    vmcl-head --port /dev/ttyUSB0 estop

Exit statuses: 0 done; 2 a usage or input error, one line: a command, number, gaze or lens setting
vmcl-head cannot run as written, and any target out of range, whether the host finds it beyond the travel
the head reports or a micro answers OUT_OF_RANGE (an argument the caller can correct, hardware.errors.
OutOfRange); 1 the head refused a command or failed, one line: a refusal by a micro for its state (an axis
not homed, a latched fault such as an emergency stop, busy), a reply that never came or came corrupted, a port that would not open (the
driver's HardwareError); 130 interrupted (Ctrl-C), the head told to stop. A refusal by the head is 1,
not 2: the line was valid, and it is the head's state (not homed, a fault latched) that must change,
with home, before the same line can run. A defect in vmcl-head itself ends with a Python traceback
(status 1 too). Every number, gaze and lens setting is checked before the head is opened (nothing
moved); a joint target beyond the travel the head reports is refused when that command comes (the
commands before it have run).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import TextIO

from .arguments import OneLineParser
from .errors import DeviceError, Fault, HardwareError, NotHomed
from .eye import focus_counts, iris_counts, mirror_angles, zoom_counts
from .head import Head

__all__ = ["UsageError", "main", "parse_commands"]

USAGE = """commands (run in order):
  status                          print every axis
  home                            clear faults, calibrate joints and lenses, centre the mirrors
  move PAN TILT                   joint angles, degrees (pan 0 ahead, + right; tilt 0 level, -90 down)
  point EYE AZIMUTH ELEVATION     EYE is left or right; gaze angles, degrees
  lens EYE [zoom=MM] [focus=M] [iris=F]   focal length mm, focus distance m (or inf), f-number
  estop                           emergency stop of every micro (clear with home)"""

# The driver's advice names its Python calls (Head.clear_faults); here it names the command that does it.
_ADVICE: tuple[tuple[type[DeviceError], str], ...] = (
    (Fault, "clear it with home (vmcl-head [--port URL] home ...)"),
    (NotHomed, "home it first (vmcl-head [--port URL] home ...)"),
)

Step = Callable[[Head, TextIO], None]


class UsageError(ValueError):
    """A command line that cannot be run as written."""


def _number(word: str, what: str, *, infinite: bool = False) -> float:
    """The number `word` (finite, unless `infinite` allows inf: a focus at infinity)."""
    try:
        value = float(word)
    except ValueError:
        raise UsageError(f"{what} must be a number, got {word!r}") from None
    if math.isnan(value) or (math.isinf(value) and not (infinite and value > 0)):
        raise UsageError(f"{what} must be a finite number{' or inf' if infinite else ''}, got {word!r}")
    return value


def _checked(check: Callable[..., object], *values: float) -> None:
    """Run a host-side conversion of the driver (gaze to mirror angles, lens settings to counts) on the
    command's values, so that one the head would refuse stops the command line before anything runs."""
    try:
        check(*values)
    except (ValueError, TypeError) as error:
        raise UsageError(str(error)) from None


def _said(error: HardwareError) -> str:
    """The error's message, with the advice the command line can follow in place of the driver's."""
    if not isinstance(error, DeviceError) or not error.args:
        return str(error)
    advice = next((text for kind, text in _ADVICE if isinstance(error, kind)), error.advice)
    return f"{error.args[0]}; {advice}" if advice else str(error.args[0])


def _eye(head: Head, name: str):
    return head.left if name == "left" else head.right


def _take(words: list[str], n: int, command: str, usage: str) -> list[str]:
    if len(words) < n:
        raise UsageError(f"{command} needs {usage}")
    taken = words[:n]
    del words[:n]
    return taken


def parse_commands(words: list[str]) -> list[Step]:
    """Turn the command words into steps, checking everything that can be checked without the head.

    Raises
    ------
    UsageError
        Unknown command, missing or malformed argument.
    """
    words = list(words)
    steps: list[Step] = []
    if not words:
        raise UsageError("no command given")
    while words:
        command = words.pop(0)
        if command == "status":
            steps.append(lambda head, out: print(head.status(), file=out))
        elif command == "home":

            def home(head: Head, out: TextIO) -> None:
                head.home()
                print("homed", file=out)

            steps.append(home)
        elif command == "move":
            pan, tilt = (_number(w, a) for w, a in zip(_take(words, 2, "move", "PAN TILT"), ("PAN", "TILT")))

            # Defaults bind this command's angles (a closure would see the loop's last ones).
            def move(head: Head, out: TextIO, p: float = pan, t: float = tilt) -> None:
                head.move(pan=p, tilt=t)

            steps.append(move)
        elif command == "point":
            eye, az, el = _take(words, 3, "point", "EYE AZIMUTH ELEVATION")
            if eye not in ("left", "right"):
                raise UsageError(f"EYE must be left or right, got {eye!r}")
            azimuth, elevation = _number(az, "AZIMUTH"), _number(el, "ELEVATION")
            _checked(mirror_angles, azimuth, elevation)

            def point(head: Head, out: TextIO, e=eye, a=azimuth, b=elevation) -> None:
                _eye(head, e).point(a, b)
                head.wait()

            steps.append(point)
        elif command == "lens":
            (eye,) = _take(words, 1, "lens", "EYE and at least one of zoom=MM focus=M iris=F")
            if eye not in ("left", "right"):
                raise UsageError(f"EYE must be left or right, got {eye!r}")
            settings: dict[str, float] = {}
            while words and "=" in words[0]:
                key, _, value = words.pop(0).partition("=")
                if key not in ("zoom", "focus", "iris") or key in settings:
                    raise UsageError(f"lens takes zoom=MM, focus=M and iris=F once each, got {key!r}")
                settings[key] = _number(value, key, infinite=key == "focus")
                _checked({"zoom": zoom_counts, "focus": focus_counts, "iris": iris_counts}[key], settings[key])
            if not settings:
                raise UsageError("lens needs at least one of zoom=MM focus=M iris=F")

            def lens(head: Head, out: TextIO, e=eye, kw=settings) -> None:
                _eye(head, e).set_lens(**kw)
                head.wait()

            steps.append(lens)
        elif command == "estop":

            def estop(head: Head, out: TextIO) -> None:
                head.estop()
                print("emergency stop sent to every micro (home clears it)", file=out)

            steps.append(estop)
        elif command.startswith("-"):
            raise UsageError(f"options go before the commands (vmcl-head --port URL home ...), got {command!r} after them")
        else:
            raise UsageError(f"unknown command {command!r}")
    return steps


def main(argv: list[str] | None = None, *, out: TextIO | None = None) -> int:
    """Run ``vmcl-head``; returns the exit status."""
    out = out or sys.stdout
    parser = OneLineParser(
        prog="vmcl-head",
        description="Drive the Vision Machine eye-head (default: the simulator).",
        epilog=USAGE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--port", default="sim://", help="serial device or URL (default: sim://)")
    parser.add_argument("--baud", type=int, default=115200, help="baud rate (default: 115200)")
    parser.add_argument("--timeout", type=float, default=0.05, help="reply timeout, seconds (default: 0.05)")
    parser.add_argument("commands", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)

    def fail(message: str, status: int) -> int:
        print(f"vmcl-head: error: {message}", file=sys.stderr)
        return status

    try:
        steps = parse_commands(args.commands)
    except UsageError as exc:
        return fail(f"{exc} (see vmcl-head --help)", 2)
    opened = False
    try:
        with Head(args.port, baudrate=args.baud, timeout=args.timeout) as head:
            opened = True
            for step in steps:
                step(head, out)
    except (ValueError, TypeError) as exc:
        return fail(str(exc), 2)
    except HardwareError as exc:
        return fail(_said(exc), 1)
    except KeyboardInterrupt:  # leaving the Head's block has stopped every motor, if the head was open
        return fail("interrupted; the head was told to stop" if opened else "interrupted before the head was open",
                    130)
    return 0
