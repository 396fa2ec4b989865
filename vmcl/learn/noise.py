"""The noise of a cue's measurements, estimated with its restoration: stochastic EM.

Seed section "Learning and parameter estimation", the third stage: a parameter estimated "with
incomplete data" by EM. The measurements g are the field f plus Gaussian noise of variance
sigma^2 / gamma (gamma the confidence), which is the data term alpha gamma |f - g|^2 at T = 1 with
alpha = 1 / (2 sigma^2). f is not observed; EM alternates the field given the data and the noise given
the field. The expectation over the posterior of (f, l) is taken by drawing from it (the Gibbs sampler
of :func:`vmcl.mrf.sample`, at T = 1, carried on from the previous draw): stochastic EM (Celeux and
Diebolt), whose estimate is the mean of the M-steps after a burn-in. The prior (beta, the line costs)
is the model's, taken as the probability law it defines at T = 1.

References
----------
G. Celeux and J. Diebolt, "The SEM algorithm: a probabilistic teacher algorithm derived from the EM
algorithm for the mixture problem", Computational Statistics Quarterly 2:73-82, 1985.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from vmcl.cm.core import ArrayLike, check_choice, check_int, check_real, machine_for, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf import EnergyModel, sample
from vmcl.mrf.energy import KINDS, host_field
from vmcl.mrf.inputs import device_pixels

__all__ = ["NoiseEstimate", "estimate_noise"]


@dataclass(frozen=True)
class NoiseEstimate:
    """What :func:`estimate_noise` found.

    Attributes
    ----------
    sigma : float
        The noise's standard deviation at confidence 1, in the data's units.
    alpha : float
        The data weight it makes at T = 1: 1 / (2 sigma^2).
    history : tuple of float
        sigma after each iteration (the estimate averages the variances after the burn-in).
    """

    sigma: float
    alpha: float
    history: tuple[float, ...]


def estimate_noise(data: ArrayLike, *, confidence: ArrayLike | None = None, edges: ArrayLike | None = None,
                   kind: str = "smooth", model: EnergyModel | None = None, sigma: float | None = None,
                   iterations: int = 80, burn_in: int = 40, sweeps: int = 10, seed: int = 0,
                   machine: Machine | None = None) -> NoiseEstimate:
    """Estimate the measurements' noise under the line-process MRF by stochastic EM.

    Parameters
    ----------
    data, confidence, edges, kind
        As for :func:`vmcl.mrf.restore`.
    model : EnergyModel, optional
        The prior (its alpha is replaced at every iteration); default ``EnergyModel()``.
    sigma : float, optional
        Where to start, in 1e-6 .. 1e6 (the data's units); default the spread of the data about their 4-neighbour mean.
    iterations : int
        EM iterations, 2 .. 10000.
    burn_in : int
        Iterations left out of the estimate, 0 .. iterations - 1.
    sweeps : int
        Gibbs sweeps per E-step, 1 .. 10000.
    seed : int
    machine : vmcl.Machine, optional

    Returns
    -------
    NoiseEstimate
    """
    machine = machine_for(machine)
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    check_int(iterations, "iterations", minimum=2, maximum=10000)
    check_int(burn_in, "burn_in", minimum=0, maximum=iterations - 1)
    check_int(sweeps, "sweeps", minimum=1, maximum=10000)
    check_int(seed, "seed", minimum=0, maximum=2**32 - 1)
    g = host_field(data, "data", ndims=(2, 3)).astype(np.float64)
    shape = g.shape[:2]
    gamma = np.ones(shape) if confidence is None else host_field(confidence, "confidence", ndims=(2,))
    if gamma.shape != shape:
        raise InputValueError(f"confidence must have the data's shape {shape}, got {gamma.shape}")
    if not np.all(np.isfinite(gamma)) or np.any(gamma < 0):
        raise InputValueError("confidence must be finite and >= 0")
    measured = np.all(np.isfinite(g.reshape(*shape, -1)), axis=2) & (gamma > 0)
    if np.count_nonzero(measured) < 2:
        raise InputValueError("data has fewer than 2 measurements with a positive confidence")
    ncomp = 1 if g.ndim == 2 else g.shape[2]
    current = _initial_sigma(g, measured) if sigma is None else check_real(sigma, "sigma", minimum=1e-6, maximum=1e6)
    # On the device once; each draw starts from the last, which stays there (only its field comes back).
    device_g, device_gamma = machine.to_device(g.astype(np.float32)), machine.to_device(gamma.astype(np.float32))
    edge_map = device_pixels(edges, "edges", shape, np.uint8, machine)
    start = None
    variances, history = [], []
    for k in range(int(iterations)):
        trial = replace(model, alpha=1.0 / (2.0 * current**2))
        drawn = sample(device_g, confidence=device_gamma, edges=edge_map, kind=kind, model=trial,
                       sweeps=int(sweeps), start=start, seed=seed * 100003 + k, machine=machine)
        start = drawn.field
        field = to_host(drawn.field)
        residual = np.sum((field.reshape(*shape, -1) - g.reshape(*shape, -1)) ** 2, axis=2)
        variance = float(np.sum(gamma[measured] * residual[measured]) / (ncomp * np.count_nonzero(measured)))
        current = max(float(np.sqrt(variance)), 1e-6)
        history.append(current)
        if k >= burn_in:
            variances.append(variance)
    found = float(np.sqrt(np.mean(variances)))
    return NoiseEstimate(sigma=found, alpha=1.0 / (2.0 * found**2), history=tuple(history))


def _initial_sigma(g: np.ndarray, measured: np.ndarray) -> float:
    """The spread of the measurements about their neighbours: a start that is the noise's order."""
    values = g.reshape(*measured.shape, -1)
    right = measured[:, 1:] & measured[:, :-1]
    diffs = (values[:, 1:] - values[:, :-1])[right]
    spread = float(np.median(np.abs(diffs))) / 0.954 if diffs.size else 1.0  # MAD of a difference of two
    return spread if spread > 0 else 1.0
