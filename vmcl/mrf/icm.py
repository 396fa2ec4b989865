"""Iterated conditional modes, the deterministic baseline (seed section "Algorithms: Deterministic and
stochastic").

Each sweep sets every site, colour by colour, to the mode of its conditional given the rest: f to the
weighted mean of its data and unbroken neighbours (smooth) or the cheapest level (constant), a line site
on exactly when that lowers U. U never increases, so ICM stops in the local minimum nearest its start.

References
----------
J. Besag, "On the statistical analysis of dirty pictures", J. Roy. Statist. Soc. B 48(3):259-302, 1986.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vmcl.mrf.checks import check_count, check_fields
from vmcl.mrf.lattice import Lattice, philox_key

__all__ = ["IcmSchedule", "icm", "quench"]


@dataclass(frozen=True)
class IcmSchedule:
    """ICM from the data: ``icm_sweeps`` sweeps of conditional modes.

    Parameters
    ----------
    icm_sweeps : int
        Sweeps (0: the start itself, the data with its gaps filled).
    """

    icm_sweeps: int = 30

    CHECKS: ClassVar = {"icm_sweeps": check_count}

    def __post_init__(self) -> None:
        check_fields(self)


def quench(lattice: Lattice, sweeps: int) -> int:
    """Enqueue ``sweeps`` ICM sweeps on the lattice's state; returns ``sweeps``.

    Also the zero-temperature end of the annealing solvers, which settle on a local minimum of U with it.
    """
    key = philox_key(0)
    for k in range(sweeps):
        lattice.sweep("icm", 0.0, k, key)
    return sweeps


def icm(lattice: Lattice, schedule: IcmSchedule, seed: int) -> int:
    """ICM from the lattice's state; returns sweeps run. Deterministic: ``seed`` is not used."""
    return quench(lattice, schedule.icm_sweeps)
