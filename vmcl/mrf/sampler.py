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

import numpy as np

from vmcl.mrf.icm import icm
from vmcl.mrf.lattice import Lattice, philox_key


def temperatures(t0: float, factor: float, count: int) -> np.ndarray:
    """The geometric schedule t0 * factor**k, k = 0 .. count - 1."""
    return t0 * factor ** np.arange(count, dtype=np.float64)


def anneal(lattice: Lattice, seed: int) -> int:
    """Simulated annealing from the lattice's state, then a zero-temperature quench; returns sweeps run.

    ``params.sweeps`` heat-bath sweeps at T = t0 * t_factor**k, then ``params.quench`` ICM sweeps so the
    result is a local minimum of U.
    """
    params = lattice.params
    key = philox_key(seed)
    for k, temperature in enumerate(temperatures(params.t0, params.t_factor, params.sweeps)):
        lattice.sweep("sample", temperature, k, key)
    return params.sweeps + icm(lattice, params.quench)


def mpm(lattice: Lattice, seed: int) -> int:
    """Marroquin's estimator at T = params.mpm_temperature; returns sweeps run.

    After ``burn_in`` sweeps, ``samples`` sweeps are accumulated: the smooth kind's f becomes the sample
    mean (the posterior mean), the constant kind's the most frequent level of each pixel (the maximiser
    of the posterior marginals), and a line site is on where it was on in more than half the samples.
    """
    params = lattice.params
    machine = lattice.machine
    key = philox_key(seed)
    per_site = lattice.ncomp if lattice.kind == "smooth" else lattice.nlevels
    sum_f = machine.empty(lattice.n * per_site, np.float32)
    sum_h, sum_v = machine.empty(lattice.n, np.float32), machine.empty(lattice.n, np.float32)
    for array in (sum_f, sum_h, sum_v):
        lattice.set_value(array, 0.0)
    accumulate = lattice.kernel("accumulate")
    size = (lattice.n,)
    for k in range(params.burn_in + params.samples):
        lattice.sweep("sample", params.mpm_temperature, k, key)
        if k >= params.burn_in:
            machine.launch(accumulate, size, lattice.f, lattice.lh, lattice.lv, sum_f, sum_h, sum_v,
                           lattice.levels, np.int64(lattice.n))
    count = np.float32(max(params.samples, 1))
    smooth = lattice.kind == "smooth"
    machine.launch(lattice.kernel("scale_and_threshold"), size, sum_f, sum_h, sum_v, count, np.int32(smooth),
                   np.int64(lattice.n))
    if smooth:
        lattice.copy(lattice.f, sum_f)
    else:
        machine.launch(lattice.kernel("levels_mode"), size, sum_f, lattice.f, lattice.levels, np.int64(lattice.n))
    lattice.copy(lattice.lh, sum_h)
    lattice.copy(lattice.lv, sum_v)
    return params.burn_in + params.samples
