"""Deterministic mean-field annealing of the line-process MRF (Geiger and Girosi).

Seed section "Algorithms: Deterministic and stochastic": "Geiger and Girosi [1989] have shown that there
is a class of deterministic schemes that are the mean-field approximations of the MRF models. These
schemes have a much higher speed than the Montecarlo schemes". Each line site holds its expectation
m = sigma(-dE / T), dE being the mean-field energy difference of the site (the expected bond, central,
vertex and parallel terms under the neighbours' expectations); f is the fixed point of its conditional
mean with bonds weighted by 1 - m (the smooth kind), or, for the constant kind, each pixel holds a
distribution over the levels. T falls geometrically (continuation in temperature); at the end lines with
m > 1/2 are kept and ``schedule.quench`` ICM sweeps settle f and l on a local minimum of U.

References
----------
D. Geiger and F. Girosi, "Parallel and deterministic algorithms from MRFs: surface reconstruction",
IEEE PAMI 13(5):401-412, 1991.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vmcl.mrf.checks import check_cooling, check_count, check_fields, check_temperature
from vmcl.mrf.icm import quench
from vmcl.mrf.lattice import Lattice, philox_key
from vmcl.mrf.sampler import temperatures

__all__ = ["MeanFieldSchedule", "meanfield", "meanfield_buffers"]


@dataclass(frozen=True)
class MeanFieldSchedule:
    """Mean-field annealing: ``mf_steps`` temperatures mf_t0 * mf_factor**k, ``mf_iterations`` sweeps at
    each, then ``quench`` ICM sweeps.

    Parameters
    ----------
    mf_t0 : float
        The first temperature, > 0.
    mf_factor : float
        The cooling factor between temperatures, in (0, 1].
    mf_steps : int
        Temperatures.
    mf_iterations : int
        Sweeps at each temperature.
    quench : int
        ICM sweeps after the last temperature.
    """

    mf_t0: float = 4.0
    mf_factor: float = 0.8
    mf_steps: int = 15
    mf_iterations: int = 5
    quench: int = 10

    CHECKS: ClassVar = {"mf_t0": check_temperature, "mf_factor": check_cooling, "mf_steps": check_count,
                        "mf_iterations": check_count, "quench": check_count}

    def __post_init__(self) -> None:
        check_fields(self)


def meanfield_buffers(kind: str, ncomp: int, nlevels: int) -> tuple[int, ...]:
    """:func:`meanfield`'s own buffer (float32 words per site): the constant kind's level distributions."""
    return (nlevels,) if kind == "constant" else ()


def meanfield(lattice: Lattice, schedule: MeanFieldSchedule, seed: int) -> int:
    """Mean-field annealing from the lattice's state, then the quench; returns sweeps run.

    Deterministic: ``seed`` is taken, as every solver takes it, and not used.
    """
    machine = lattice.machine
    size = (lattice.n,)
    q = None
    if lattice.kind == "constant":
        q = machine.empty(lattice.n * lattice.nlevels, np.float32)
        machine.launch(lattice.kernel("q_init"), size, q, lattice.f, lattice.levels, np.int64(lattice.n))
    key = philox_key(0)
    steps = temperatures(schedule.mf_t0, schedule.mf_factor, schedule.mf_steps, schedule.mf_iterations)
    for k, temperature in enumerate(steps):
        lattice.sweep("mean", temperature, k, key, q=q)
    if q is not None:
        machine.launch(lattice.kernel("levels_mode"), size, q, lattice.f, lattice.levels, np.int64(lattice.n))
    machine.launch(lattice.kernel("scale_and_threshold"), size, lattice.f, lattice.lh, lattice.lv,
                   np.float32(1.0), np.int32(0), np.int64(lattice.n))
    return schedule.mf_steps * schedule.mf_iterations + quench(lattice, schedule.quench)
