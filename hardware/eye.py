"""An eye: two galvanometer mirrors for pointing and a motorized zoom lens, in physical units.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": each eye is a CCD camera behind
a motorized zoom lens (F1.4, focal length 12.5 to 75 mm; iris, focus and focal length set by the host),
aimed through a pair of front-surface mirrors turned by galvanometers, "at the expense of a more
complicated imaging geometry". That geometry is here: the line of sight leaves the lens along +x, the
first mirror (turning about z) sends it along +y, the second (turning about x) sends it out along +z,
straight ahead. A mirror turned by theta deflects the beam by 2 theta, but the second mirror sees a beam
the first has already deflected, so the direction depends on both angles together; `mirror_angles`
inverts `line_of_sight` exactly rather than assuming the axes independent.

Lens units on the public API: focal length in millimetres, focus distance in metres, iris as an
f-number. Every lens move ends travelling the same way, so backlash does not shift the ring.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from .arguments import check_number, real_value
from .commands import FAULT_FLAGS, Flag, describe
from .errors import Fault, NotHomed, OutOfRange, naming
from .micros import GalvoMicro, LensMicro
from .physics import GALVO_RANGE_MDEG, LENS_COUNTS

__all__ = [
    "FOCUS_M",
    "F_NUMBER",
    "MIRROR_RANGE",
    "ZOOM_MM",
    "Eye",
    "EyeStatus",
    "line_of_sight",
    "mirror_angles",
]

ZOOM_MM = (12.5, 75.0)
FOCUS_M = (1.2, math.inf)  # nearest focus distance to infinity
F_NUMBER = (1.4, 16.0)
MIRROR_RANGE = GALVO_RANGE_MDEG / 1000.0
_TOP = LENS_COUNTS - 1
_ROOT2 = math.sqrt(0.5)


def _reflect(v: tuple[float, float, float], n: tuple[float, float, float]) -> tuple[float, float, float]:
    d = 2.0 * (v[0] * n[0] + v[1] * n[1] + v[2] * n[2])
    return v[0] - d * n[0], v[1] - d * n[1], v[2] - d * n[2]


def line_of_sight(x: float, y: float) -> tuple[float, float]:
    """Gaze direction for mirror angles `x` (first mirror) and `y` (second mirror), in degrees.

    Returns
    -------
    azimuth, elevation : float
        Degrees; azimuth positive to the right, elevation positive upwards, (0, 0) straight ahead.
    """
    a, b = math.radians(x), math.radians(y)
    # First mirror: normal (1, -1, 0)/sqrt 2 turned by -a about z; second: (0, 1, -1)/sqrt 2 turned by
    # -b about x. The signs make positive angles look right and up.
    n1 = (_ROOT2 * (math.cos(a) - math.sin(a)), _ROOT2 * (-math.sin(a) - math.cos(a)), 0.0)
    n2 = (0.0, _ROOT2 * (math.cos(b) - math.sin(b)), _ROOT2 * (-math.sin(b) - math.cos(b)))
    dx, dy, dz = _reflect(_reflect((1.0, 0.0, 0.0), n1), n2)
    return math.degrees(math.atan2(dx, dz)), math.degrees(math.atan2(dy, math.hypot(dx, dz)))


def mirror_angles(azimuth: float, elevation: float, *, tol: float = 1e-9) -> tuple[float, float]:
    """The mirror angles (degrees) that look along (`azimuth`, `elevation`): `line_of_sight` inverted
    by Newton's method from the small-angle guess (half of each).

    Raises
    ------
    OutOfRange
        No mirror angles within the galvanometers' range look that way.
    """
    for name, value in (("azimuth", azimuth), ("elevation", elevation)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"{name} must be a finite number of degrees, got {value!r}")
        if not math.isfinite(real_value(value)):
            raise ValueError(f"{name} must be a finite number of degrees, got {real_value(value):g}")
    beyond = OutOfRange(
        f"gaze (azimuth {azimuth:g}, elevation {elevation:g}) deg needs mirror angles beyond the mirror angle "
        f"limit of +-{MIRROR_RANGE:g} deg"
    )
    # Two mirrors within +-MIRROR_RANGE turn the gaze by well under 4 * MIRROR_RANGE either way; from
    # further out, Newton's method would start where the mirrors no longer reflect forwards.
    if max(abs(azimuth), abs(elevation)) > 4 * MIRROR_RANGE:
        raise beyond
    x, y = azimuth / 2.0, elevation / 2.0
    h = 1e-6
    for _ in range(30):
        az, el = line_of_sight(x, y)
        ea, ee = az - azimuth, el - elevation
        if abs(ea) < tol and abs(ee) < tol:
            break
        ax, ex = line_of_sight(x + h, y)
        ay, ey = line_of_sight(x, y + h)
        j11, j12, j21, j22 = (ax - az) / h, (ay - az) / h, (ex - el) / h, (ey - el) / h
        det = j11 * j22 - j12 * j21
        if not math.isfinite(det) or det == 0.0:
            raise beyond
        x -= (j22 * ea - j12 * ee) / det
        y -= (j11 * ee - j21 * ea) / det
    # Written so that a NaN anywhere refuses too.
    if not (max(abs(x), abs(y)) <= MIRROR_RANGE and abs(ea) <= 1e-6 and abs(ee) <= 1e-6):
        raise beyond
    return x, y


def zoom_counts(focal_length_mm: float) -> int:
    """Lens motor count of a focal length (linear in millimetres)."""
    check_number("zoom", focal_length_mm, *ZOOM_MM, "mm")
    low, high = ZOOM_MM
    return round((focal_length_mm - low) / (high - low) * _TOP)


def focus_counts(distance_m: float) -> int:
    """Lens motor count of a focus distance (linear in dioptres: 0 at infinity)."""
    check_number("focus", distance_m, *FOCUS_M, "m")
    return round(FOCUS_M[0] / distance_m * _TOP)


def iris_counts(f_number: float) -> int:
    """Lens motor count of an f-number (linear in stops)."""
    check_number("iris", f_number, *F_NUMBER, "(f-number)")
    low, high = F_NUMBER
    return round(math.log(f_number / low) / math.log(high / low) * _TOP)


class EyeStatus(NamedTuple):
    """An eye's state in physical units (angles in degrees); the lens values are NaN until the lens
    has been homed."""

    mirror_x: float
    mirror_y: float
    azimuth: float
    elevation: float
    zoom_mm: float
    focus_m: float
    f_number: float
    flags: Flag

    def __str__(self) -> str:
        lens = "lens not homed"
        if not math.isnan(self.zoom_mm):
            lens = f"zoom {self.zoom_mm:.1f} mm, focus {self.focus_m:.2f} m, F{self.f_number:.1f}"
        # Rounded first, and -0.0 made 0.0: a mirror a hair below zero would print as -0.000.
        azimuth, elevation, x, y = (round(v, 3) + 0.0 for v in (self.azimuth, self.elevation, self.mirror_x,
                                                                self.mirror_y))
        return f"gaze ({azimuth:+.3f}, {elevation:+.3f}) deg, mirrors ({x:+.3f}, {y:+.3f}) deg, {lens}, {describe(self.flags)}"


class Eye:
    """One eye: its mirror pair on the galvo micro and its lens on the lens micro.

    Parameters
    ----------
    galvo : GalvoMicro
    lens : LensMicro
    index : int
        0 left, 1 right.
    name : str
    """

    def __init__(self, galvo: GalvoMicro, lens: LensMicro, index: int, name: str) -> None:
        self.galvo = galvo
        self.lens = lens
        self.index = index
        self.name = name

    def __repr__(self) -> str:
        return f"Eye({self.name!r})"

    def set_mirrors(self, x: float, y: float) -> None:
        """Start turning the mirrors to `x`, `y` degrees."""
        for name, value in (("x", x), ("y", y)):
            check_number(f"{self.name} mirror {name}", value, -MIRROR_RANGE, MIRROR_RANGE, "degrees")
        with naming(f"{self.name} eye"):
            self.galvo.set_angles(self.index, round(x * 1000), round(y * 1000))

    def point(self, azimuth: float, elevation: float) -> None:
        """Start turning the line of sight to (`azimuth`, `elevation`) degrees."""
        self.set_mirrors(*mirror_angles(azimuth, elevation))

    def home_lens(self) -> None:
        """Start homing zoom, focus and iris on their home sensors."""
        with naming(f"{self.name} lens"):
            self.lens.home(self.index)

    def set_lens(
        self, *, zoom: float | None = None, focus: float | None = None, iris: float | None = None
    ) -> None:
        """Start moving the lens: `zoom` focal length in mm, `focus` distance in m (``math.inf`` for
        infinity), `iris` f-number. Settings left as None stay where they are."""
        if zoom is None and focus is None and iris is None:
            raise ValueError("give at least one of zoom (mm), focus (m), iris (f-number)")
        counts = (
            None if zoom is None else zoom_counts(zoom),
            None if focus is None else focus_counts(focus),
            None if iris is None else iris_counts(iris),
        )
        with naming(f"{self.name} lens"):
            current = self.lens.get(self.index)
            if not current.flags & Flag.HOMED:
                raise NotHomed("not homed", advice="home it first (Head.home or Eye.home_lens)")
            self.lens.set_counts(self.index, *(c if n is None else n for c, n in zip(current[:3], counts)))

    def status(self) -> EyeStatus:
        g = self.galvo.get(self.index)
        lens = self.lens.get(self.index)
        x, y = g.x / 1000.0, g.y / 1000.0
        if lens.flags & Flag.HOMED:
            zoom = ZOOM_MM[0] + lens.zoom / _TOP * (ZOOM_MM[1] - ZOOM_MM[0])
            focus = FOCUS_M[0] * _TOP / lens.focus if lens.focus > 0 else math.inf
            f_number = F_NUMBER[0] * (F_NUMBER[1] / F_NUMBER[0]) ** (lens.iris / _TOP)
        else:
            zoom = focus = f_number = math.nan
        # The mirrors never need homing, so the eye counts as homed when its lens is.
        flags = (g.flags & ~Flag.HOMED) | lens.flags
        return EyeStatus(x, y, *line_of_sight(x, y), zoom, focus, f_number, flags)

    def settled(self) -> bool:
        """True once mirrors and lens are at rest; raises Fault if a fault has latched."""
        flags = self.galvo.get(self.index).flags | self.lens.get(self.index).flags
        if flags & FAULT_FLAGS:
            raise Fault(f"{self.name} eye: {describe(flags)}", flags=int(flags))
        return not flags & (Flag.MOVING | Flag.HOMING)
