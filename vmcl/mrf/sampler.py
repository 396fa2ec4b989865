"""Stochastic solvers: Gibbs-Metropolis simulated annealing for the MAP, and Marroquin's MPM estimator.

Seed sections "MRF models" ("sample distributions can be obtained using Monte Carlo techniques such as the
Metropolis algorithm ... simulated annealing is one of the possible techniques"; "Marroquin [1985] has
shown that the average surface f under the posterior distribution is often a better estimate") and
"Algorithms: Deterministic and stochastic". Each sweep is a heat-bath (Gibbs) update of every site by
colours (kernels/mrf.cl): f from its Gaussian (smooth) or discrete (constant) conditional, each line
site from its exact two-state conditional. Random numbers come from Philox keyed by (seed, sweep, site),
so a seed gives the same bits at any local size.

References
----------
S. Geman and D. Geman, "Stochastic relaxation, Gibbs distributions, and the Bayesian restoration of
images", IEEE PAMI 6(6):721-741, 1984.
J. Marroquin, S. Mitter and T. Poggio, "Probabilistic solution of ill-posed problems in computational
vision", J. Amer. Statist. Assoc. 82(397):76-89, 1987.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vmcl.mrf.checks import check_cooling, check_count, check_fields, check_positive_count, check_temperature
from vmcl.mrf.icm import quench
from vmcl.mrf.lattice import Lattice, philox_key

__all__ = ["AnnealSchedule", "MpmSchedule", "anneal", "mpm", "mpm_buffers", "temperatures"]


_BLOCK = 4096  # temperatures found at once


def temperatures(t0: float, factor: float, count: int, repeat: int = 1) -> Iterator[float]:
    """The geometric schedule t0 * factor**k, k = 0 .. count - 1, each temperature ``repeat`` times.

    A generator: a schedule's counts may be as large as its checks allow (MAX_COUNT), and a list of them
    would take gigabytes before the first sweep. Blocks of them are found as NumPy finds a whole schedule,
    so a temperature is the same to the bit whatever the count."""
    for first in range(0, count, _BLOCK):
        for temperature in t0 * factor ** np.arange(first, min(first + _BLOCK, count), dtype=np.float64):
            for _ in range(repeat):
                yield float(temperature)


@dataclass(frozen=True)
class AnnealSchedule:
    """Simulated annealing: ``sweeps`` heat-bath sweeps at T = t0 * t_factor**k, then ``quench`` ICM sweeps.

    Parameters
    ----------
    t0 : float
        The first temperature, > 0.
    t_factor : float
        The cooling factor between sweeps, in (0, 1].
    sweeps : int
        Heat-bath sweeps.
    quench : int
        ICM sweeps after the last one, so the result is a local minimum of U.

    Notes
    -----
    The defaults are a short generic schedule; the presets' own (:mod:`vmcl.mrf.presets`) are the
    measured ones, of 300 to 600 sweeps. The first temperature is the one those measurements favour (on
    the rendered disparity maps of :mod:`vmcl.mrf.presets`, lower final energies from T0 = 0.5 to 1):
    from T0 >= 4 the sampler freezes in states with many lines, since a pixel without data inside four
    lines has no restoring force, and a field with many missing values came back worse than its data.
    """

    t0: float = 1.0
    t_factor: float = 0.95
    sweeps: int = 100
    quench: int = 10

    CHECKS: ClassVar = {"t0": check_temperature, "t_factor": check_cooling, "sweeps": check_count,
                        "quench": check_count}

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class MpmSchedule:
    """Marroquin's MPM estimator: ``burn_in`` sweeps, then ``samples`` sweeps averaged, all at one T.

    Parameters
    ----------
    mpm_temperature : float
        The sampling temperature, > 0 (1: the posterior itself).
    burn_in : int
        Sweeps before the first sample.
    samples : int
        Sweeps averaged, >= 1 (the estimate is their mean).
    """

    mpm_temperature: float = 1.0
    burn_in: int = 50
    samples: int = 100

    CHECKS: ClassVar = {"mpm_temperature": check_temperature, "burn_in": check_count,
                        "samples": check_positive_count}

    def __post_init__(self) -> None:
        check_fields(self)


def anneal(lattice: Lattice, schedule: AnnealSchedule, seed: int) -> int:
    """Simulated annealing from the lattice's state, then a zero-temperature quench; returns sweeps run."""
    key = philox_key(seed)
    for k, temperature in enumerate(temperatures(schedule.t0, schedule.t_factor, schedule.sweeps)):
        lattice.sweep("sample", temperature, k, key)
    return schedule.sweeps + quench(lattice, schedule.quench)


def mpm_buffers(kind: str, ncomp: int, nlevels: int) -> tuple[int, ...]:
    """:func:`mpm`'s sums per site (float32 words): of f (its components, or a count per level for the
    constant kind) and of each line field."""
    return (ncomp if kind == "smooth" else nlevels, 1, 1)


def mpm(lattice: Lattice, schedule: MpmSchedule, seed: int) -> int:
    """Marroquin's estimator at T = schedule.mpm_temperature; returns sweeps run.

    After ``burn_in`` sweeps, ``samples`` sweeps are accumulated: the smooth kind's f becomes the sample
    mean (the posterior mean), the constant kind's the most frequent level of each pixel (the maximiser
    of the posterior marginals), and a line site is on where it was on in more than half the samples.
    """
    machine = lattice.machine
    key = philox_key(seed)
    per_site = lattice.ncomp if lattice.kind == "smooth" else lattice.nlevels
    sum_f = machine.empty(lattice.n * per_site, np.float32)
    sum_h, sum_v = machine.empty(lattice.n, np.float32), machine.empty(lattice.n, np.float32)
    for array in (sum_f, sum_h, sum_v):
        lattice.set_value(array, 0.0)
    accumulate = lattice.kernel("accumulate")
    size = (lattice.n,)
    for k in range(schedule.burn_in + schedule.samples):
        lattice.sweep("sample", schedule.mpm_temperature, k, key)
        if k >= schedule.burn_in:
            machine.launch(accumulate, size, lattice.f, lattice.lh, lattice.lv, sum_f, sum_h, sum_v,
                           lattice.levels, np.int64(lattice.n))
    count = np.float32(schedule.samples)
    smooth = lattice.kind == "smooth"
    machine.launch(lattice.kernel("scale_and_threshold"), size, sum_f, sum_h, sum_v, count, np.int32(smooth),
                   np.int64(lattice.n))
    if smooth:
        lattice.copy(lattice.f, sum_f)
    else:
        machine.launch(lattice.kernel("levels_mode"), size, sum_f, lattice.f, lattice.levels, np.int64(lattice.n))
    lattice.copy(lattice.lh, sum_h)
    lattice.copy(lattice.lv, sum_v)
    return schedule.burn_in + schedule.samples
