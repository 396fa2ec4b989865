"""Draw a configuration of the line-process MRF at a fixed temperature: the Gibbs sampler as a sampler.

Seed sections "MRF models" (sample distributions by Monte Carlo) and "Learning and parameter
estimation": parameters are learned from configurations whose distribution is known, and the ones this
module draws come from the same heat-bath sweep the solvers anneal with (kernels/mrf.cl), held at one
temperature. With no data (confidence 0 everywhere) it samples the prior itself: the constant kind with
two levels and no lines is the Ising model, with more levels the Potts model.
"""

from __future__ import annotations

from vmcl.cm.core import ArrayLike, check_bool, check_choice, check_int, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf.checks import check_temperature
from vmcl.mrf.energy import KINDS, EnergyModel
from vmcl.mrf.inputs import lattice_of
from vmcl.mrf.lattice import SWEEP_ORDER, philox_key
from vmcl.mrf.restore import Restoration

__all__ = ["MAX_SWEEPS", "sample"]

MAX_SWEEPS = 1_000_000
"""The most sweeps one draw runs (a million sweeps of a 128 x 128 lattice take hours on a CPU)."""


def sample(data: ArrayLike, *, confidence: ArrayLike | None = None, edges: ArrayLike | None = None,
           kind: str = "smooth", model: EnergyModel | None = None, temperature: float = 1.0, sweeps: int = 200,
           lines: bool = True, start: ArrayLike | None = None, seed: int = 0,
           machine: Machine | None = None) -> Restoration:
    """``sweeps`` heat-bath sweeps of the posterior exp(-U(f, l) / T) from a start: one draw of (f, l).

    Parameters
    ----------
    data : (H, W) or (H, W, C) array
        The data g, NaN where there is none, as for :func:`vmcl.mrf.restore`.
    confidence : (H, W) array, optional
        gamma >= 0; zero everywhere (with a ``start``) samples the prior alone.
    edges : (H, W) array, optional
        Brightness edges, non-zero at edge pixels.
    kind : {"smooth", "constant"}
    model : EnergyModel, optional
        The energy U; default ``EnergyModel()``. Unlike :func:`vmcl.mrf.restore`, alpha may be 0.
    temperature : float
        T > 0, in U's units, within float32's range.
    sweeps : int
        Sweeps, 1 .. :data:`MAX_SWEEPS`: every site once per sweep, lines first, then f (with
        ``lines``), f alone otherwise.
    lines : bool
        Sample the line process too; False keeps every line off (a field with no discontinuities).
    start : array of the data's shape, optional
        Where f starts wherever it is finite (else at the filled data; where no datum has a positive
        confidence, as when sampling the prior, the start's own values fill its gaps the same way, by a
        jump fill of neighbour means); the constant kind's start is taken to its nearest level.
        Infinities are refused.
    seed : int
        0 <= seed < 2**64: the same seed gives the same draw on any device.
    machine : vmcl.Machine, optional

    Returns
    -------
    Restoration
        The last state (f and l), its energy U and the sweeps run; NumPy for NumPy data.

    Raises
    ------
    InputValueError
        No datum has a positive confidence and no ``start`` is given, or one with no finite value
        (nothing says where f begins); the lattice does not fit the device's memory.

    Examples
    --------
    An Ising field at coupling J = 0.3 (the Potts cost kappa = 2 J at T = 1), from a random start:

    >>> import numpy as np
    >>> spins = np.random.default_rng(0).integers(0, 2, (32, 32)).astype(np.float32)
    >>> ising = EnergyModel(alpha=0.0, kappa=0.6, levels=(0.0, 1.0))
    >>> drawn = sample(spins, confidence=np.zeros((32, 32)), kind="constant", model=ising, lines=False,
    ...                start=spins, sweeps=50)
    >>> sorted(np.unique(drawn.field).tolist()), int(drawn.line_h.sum())
    ([0.0, 1.0], 0)
    """
    machine = machine_for(machine)
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    temperature = check_temperature(temperature, "temperature")
    check_int(sweeps, "sweeps", minimum=1, maximum=MAX_SWEEPS)
    check_bool(lines, "lines")
    check_int(seed, "seed", minimum=0, maximum=2**64 - 1)
    lattice, host = lattice_of(data, confidence, edges, start, kind, model, machine, "mrf.sample")
    if not lattice.begins:
        given = "no start is given" if start is None else "start holds no finite value"
        raise InputValueError(f"data has no value with a positive confidence and {given}: nothing says where "
                              "the field begins")
    order = SWEEP_ORDER if lines else tuple(step for step in SWEEP_ORDER if step[0] == "f")
    key = philox_key(int(seed))
    for k in range(int(sweeps)):
        lattice.sweep("sample", float(temperature), k, key, order)
    return Restoration.read(lattice, int(sweeps), host)
