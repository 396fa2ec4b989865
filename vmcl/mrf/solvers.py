"""The solvers :func:`vmcl.mrf.restore` runs, registered by name.

Seed section "Algorithms: Deterministic and stochastic". A solver is a function
``solve(lattice, schedule, seed) -> sweeps run`` that leaves its estimate in the lattice's field and line
process, and the frozen dataclass of its schedule, which checks its fields when made and whose defaults
are a usable schedule. Adding a solver is one module holding both and one entry in :data:`SOLVERS`;
:class:`vmcl.mrf.Settings` and the presets then give it its default schedule until one is measured.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from vmcl.mrf.icm import IcmSchedule, icm
from vmcl.mrf.lattice import Lattice
from vmcl.mrf.meanfield import MeanFieldSchedule, meanfield
from vmcl.mrf.sampler import AnnealSchedule, MpmSchedule, anneal, mpm

__all__ = ["SOLVERS", "Solver"]


class Solver(NamedTuple):
    """One registered solver: the function that runs it and the class of its schedule."""

    solve: Callable[[Lattice, Any, int], int]
    schedule: type


SOLVERS: dict[str, Solver] = {
    "anneal": Solver(anneal, AnnealSchedule),
    "mpm": Solver(mpm, MpmSchedule),
    "meanfield": Solver(meanfield, MeanFieldSchedule),
    "icm": Solver(icm, IcmSchedule),
}
"""Method name -> :class:`Solver`: simulated annealing (MAP; stochastic), Marroquin's MPM estimator
(stochastic), Geiger-Girosi mean-field annealing and ICM (both deterministic)."""
