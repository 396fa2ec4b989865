"""The solvers :func:`vmcl.mrf.restore` runs, registered by name.

Seed section "Algorithms: Deterministic and stochastic". A solver is a function
``solve(lattice, schedule, seed) -> sweeps run`` that leaves its estimate in the lattice's field and line
process, the class of its schedule, and what buffers it allocates (for the memory check). Adding a solver
is one module holding both and one entry in :data:`SOLVERS`; :class:`vmcl.mrf.Settings` and the presets
then give it its default schedule until one is measured.

A schedule class is a dataclass (frozen, as the others) whose every field has a default, the defaults
together a usable schedule: ``Settings`` makes one with no arguments, and a Config's ``[mrf]`` schedule
and ``[mrf.<cue>]`` overrides set its fields by name (:meth:`vmcl.mrf.Settings.override`), a name it
shares with another schedule or the energy model (e.g. ``quench``) in each of them. It should check its
fields when made, refusing a bad value with a :class:`vmcl.errors.InputError`; with a ``CHECKS`` class
attribute (field name -> ``check(value, label)``, run by :func:`vmcl.mrf.checks.check_fields` in its
``__post_init__``, as :class:`vmcl.mrf.IcmSchedule` does) an override is also refused under the key the
user wrote (``mrf.<cue>.<field>``). A class without ``CHECKS`` is taken, with only its own checks.
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
