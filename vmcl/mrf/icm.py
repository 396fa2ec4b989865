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

from vmcl.mrf.lattice import Lattice, philox_key


def icm(lattice: Lattice, sweeps: int) -> int:
    """Enqueue ``sweeps`` ICM sweeps on the lattice's state; returns ``sweeps``."""
    key = philox_key(0)
    for k in range(sweeps):
        lattice.sweep("icm", 0.0, k, key)
    return sweeps
