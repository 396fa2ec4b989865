"""Field checks of the MRF's frozen settings (the energy model and the solvers' schedules).

Each settings class lists one check per field in ``CHECKS``; a check takes the value and the label to
name it by. The classes check themselves as ``ClassName.field``; :meth:`vmcl.mrf.Settings.override`
checks a user's value first under the label the user wrote (``mrf.<cue>.<key>`` in a Config), so a
refusal names the key in the user's own file.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from vmcl.cm.core import check_int, check_real

__all__ = [
    "MAX_COUNT",
    "check_cooling",
    "check_count",
    "check_fields",
    "check_number",
    "check_temperature",
    "check_weight",
]

# Counts of sweeps, levels and radii: far above any schedule that ends, and within the kernels' int32.
MAX_COUNT = 2**31 - 1


def check_fields(settings: Any) -> None:
    """Check every field of a settings dataclass with its class's ``CHECKS``, naming it ``Class.field``."""
    owner = type(settings)
    for item in fields(settings):
        owner.CHECKS[item.name](getattr(settings, item.name), f"{owner.__name__}.{item.name}")


def check_count(value: Any, label: str) -> None:
    """A number of sweeps, steps or pixels: an integer in 0 .. MAX_COUNT."""
    check_int(value, label, minimum=0, maximum=MAX_COUNT)


def check_number(value: Any, label: str) -> None:
    """Any finite real number."""
    check_real(value, label)


def check_weight(value: Any, label: str) -> None:
    """A finite real number >= 0 (a weight of a term of the energy)."""
    check_real(value, label, minimum=0)


def check_temperature(value: Any, label: str) -> None:
    """A finite temperature > 0, in the energy's units."""
    check_real(value, label, above=0)


def check_cooling(value: Any, label: str) -> None:
    """A factor in (0, 1] between successive temperatures: annealing never heats up."""
    check_real(value, label, above=0, maximum=1)
