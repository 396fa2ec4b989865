"""Cross-validation of a cue's smoothing weight from its data alone.

Seed section "Learning and parameter estimation", the third stage: "tuning the parameters from the
data", by cross-validation. The data weight alpha of the line-process MRF (the smoothness weight is the
energy's unit, so alpha is the inverse of the smoothing) is chosen per image: a random share of the
measurements is held out, the rest restored with each candidate weight, and the candidate whose
restoration predicts the held-out measurements best (confidence-weighted mean squared error, over
``folds`` disjoint held-out shares) wins. No ground truth is read.

Generalised cross-validation needs the restoration to be linear in the data (the influence matrix's
trace); the line process makes it non-linear, so only the held-out kind is offered.

References
----------
G. Wahba, Spline Models for Observational Data, SIAM, 1990 (chapter 4: cross-validation).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from vmcl.cm.core import ArrayLike, check_choice, check_int, check_real, machine_for, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf import SOLVERS, EnergyModel, NothingToRestore, restore
from vmcl.mrf.energy import KINDS, host_field
from vmcl.mrf.inputs import device_pixels

__all__ = ["DEFAULT_FACTORS", "CrossValidation", "cross_validate"]

DEFAULT_FACTORS = tuple(2.0 ** k for k in range(-4, 5))
"""The candidates, as factors of the model's alpha: 1/16 to 16 in steps of 2."""


@dataclass(frozen=True)
class CrossValidation:
    """What :func:`cross_validate` found.

    Attributes
    ----------
    alpha : float
        The chosen data weight.
    candidates : tuple of float
        The weights tried, ascending.
    scores : tuple of float
        Each candidate's held-out error (confidence-weighted mean squared error, in the data's units
        squared), mean over the folds.
    model : EnergyModel
        The given model with the chosen alpha.
    """

    alpha: float
    candidates: tuple[float, ...]
    scores: tuple[float, ...]
    model: EnergyModel


def cross_validate(data: ArrayLike, *, confidence: ArrayLike | None = None, edges: ArrayLike | None = None,
                   kind: str = "smooth", model: EnergyModel | None = None, method: str = "meanfield",
                   schedule: Any = None, candidates: Sequence[float] | None = None, holdout: float = 0.1,
                   folds: int = 3, seed: int = 0, machine: Machine | None = None) -> CrossValidation:
    """Choose the data weight alpha of :func:`vmcl.mrf.restore` by held-out measurements.

    Parameters
    ----------
    data, confidence, edges, kind, method, schedule
        As for :func:`vmcl.mrf.restore` (NumPy or device arrays).
    model : EnergyModel, optional
        Everything but alpha (default ``EnergyModel()``).
    candidates : sequence of float, optional
        The weights to try, each > 0; default the model's alpha times :data:`DEFAULT_FACTORS`.
    holdout : float
        The share of the measurements held out per fold, in (0, 0.5].
    folds : int
        How many disjoint shares are held out in turn, 1 .. floor(1 / holdout).
    seed : int
        Draws the held-out shares (and keys the stochastic solvers).
    machine : vmcl.Machine, optional

    Returns
    -------
    CrossValidation

    Raises
    ------
    InputValueError
        Fewer than 10 measurements per fold to hold out.

    Examples
    --------
    >>> import numpy as np
    >>> ramp = np.linspace(0, 4, 48)[None, :] * np.ones((48, 1))
    >>> noisy = ramp + np.random.default_rng(0).normal(0, 0.5, ramp.shape)
    >>> found = cross_validate(noisy, method="icm")
    >>> found.alpha < 1.0  # noisy data: smooth more than the default weight does
    True
    """
    machine = machine_for(machine)
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    check_choice(method, "method", SOLVERS)
    check_real(holdout, "holdout", above=0, maximum=0.5)
    check_int(folds, "folds", minimum=1, maximum=int(1 / holdout))
    check_int(seed, "seed", minimum=0, maximum=2**64 - 1)
    if candidates is None:
        if model.alpha <= 0:
            raise InputValueError("model.alpha must be > 0 for the default candidates (factors of it)")
        candidates = [model.alpha * factor for factor in DEFAULT_FACTORS]
    if isinstance(candidates, (str, bytes)) or not isinstance(candidates, Sequence) or not candidates:
        raise InputTypeError("candidates must be a non-empty sequence of weights")
    weights = sorted({check_real(c, "candidates", above=0) for c in candidates})
    g = host_field(data, "data", ndims=(2, 3)).astype(np.float32)
    shape = g.shape[:2]
    gamma = np.ones(shape, np.float32) if confidence is None else \
        host_field(confidence, "confidence", ndims=(2,)).astype(np.float32)
    if gamma.shape != shape:
        raise InputValueError(f"confidence must have the data's shape {shape}, got {gamma.shape}")
    if not np.all(np.isfinite(gamma)) or np.any(gamma < 0):
        raise InputValueError("confidence must be finite and >= 0")
    measured = np.all(np.isfinite(g.reshape(*shape, -1)), axis=2) & (gamma > 0)
    where = np.flatnonzero(measured)
    per_fold = int(holdout * where.size)
    if per_fold < 10:
        raise InputValueError(f"data has {where.size} measurements with a positive confidence: too few to hold "
                              f"out a share holdout={holdout:g} of them per fold (at least 10 each)")
    order = np.random.default_rng(seed).permutation(where)
    # On the device once: each restoration below reads them there, and only its field comes back.
    device_g = machine.to_device(g)
    edge_map = device_pixels(edges, "edges", shape, np.uint8, machine)
    errors = np.zeros((len(weights), folds))
    for fold in range(folds):
        held = order[fold * per_fold:(fold + 1) * per_fold]
        kept = gamma.copy().ravel()
        kept[held] = 0.0
        device_kept = machine.to_device(kept.reshape(shape))
        truth = g.reshape(shape[0] * shape[1], -1)[held]
        w = gamma.ravel()[held]
        for k, alpha in enumerate(weights):
            trial = replace(model, alpha=alpha)
            try:
                found = restore(device_g, confidence=device_kept, edges=edge_map, kind=kind, method=method,
                                model=trial, schedule=schedule, seed=seed, machine=machine)
            except NothingToRestore:
                raise InputValueError("data has nothing left to restore once a share is held out") from None
            guess = to_host(found.field).astype(np.float64).reshape(shape[0] * shape[1], -1)[held]
            errors[k, fold] = float(np.sum(w * np.sum((guess - truth) ** 2, axis=1)) / np.sum(w))
    scores = errors.mean(axis=1)
    best = int(np.argmin(scores))
    return CrossValidation(alpha=weights[best], candidates=tuple(weights),
                           scores=tuple(float(s) for s in scores), model=replace(model, alpha=weights[best]))
