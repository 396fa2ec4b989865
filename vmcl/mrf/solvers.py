"""The solvers :func:`vmcl.mrf.restore` runs, registered by name.

Seed section "Algorithms: Deterministic and stochastic". A solver is a function
``solve(lattice, schedule, seed) -> sweeps run`` that leaves its estimate in the lattice's field and line
process, the frozen dataclass of its schedule, and what buffers it allocates (for the memory check), which checks its fields when made and whose defaults
are a usable schedule. Adding a solver is one module holding both and one entry in :data:`SOLVERS`;
:class:`vmcl.mrf.Settings` and the presets then give it its default schedule until one is measured.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from vmcl.mrf.icm import IcmSchedule, icm
from vmcl.mrf.lattice import Lattice
from vmcl.mrf.meanfield import MeanFieldSchedule, meanfield, meanfield_buffers
from vmcl.mrf.sampler import AnnealSchedule, MpmSchedule, anneal, mpm, mpm_buffers

__all__ = ["SOLVERS", "Solver", "no_buffers"]


def no_buffers(kind: str, ncomp: int, nlevels: int) -> tuple[int, ...]:
    """The buffers of a solver that allocates none beyond the lattice's."""
    return ()


class Solver(NamedTuple):
    """One registered solver: the function that runs it, the class of its schedule, and the buffers it
    allocates beyond the lattice's: ``buffers(kind, ncomp, nlevels)`` gives float32 words per site of
    each, so :func:`vmcl.mrf.restore` can check the device's memory before anything is allocated."""

    solve: Callable[[Lattice, Any, int], int]
    schedule: type
    buffers: Callable[[str, int, int], tuple[int, ...]] = no_buffers


SOLVERS: dict[str, Solver] = {
    "anneal": Solver(anneal, AnnealSchedule),
    "mpm": Solver(mpm, MpmSchedule, mpm_buffers),
    "meanfield": Solver(meanfield, MeanFieldSchedule, meanfield_buffers),
    "icm": Solver(icm, IcmSchedule),
}
"""Method name -> :class:`Solver`: simulated annealing (MAP; stochastic), Marroquin's MPM estimator
(stochastic), Geiger-Girosi mean-field annealing and ICM (both deterministic)."""
