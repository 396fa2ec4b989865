"""The sampling temperature of Marroquin's MPM estimator, chosen from the model: away from the phase
transition.

Seed section "Learning and parameter estimation": the MPM estimator must be run at a temperature "away
from phase transition", where the posterior's samples (and so their marginals) change abruptly with
the temperature and a chain mixes slowly. The scan draws the MRF (:func:`vmcl.mrf.sample`) at a range
of temperatures and measures the density of discontinuities in each draw: the share of line sites on
(the constant kind with no lines: the share of neighbour pairs at different levels, its domain walls).
The transition is where that density changes fastest against log T (the peak of the specific heat's
analogue); the chosen temperature is 1 (the posterior itself) unless the transition lies within a
factor ``margin`` of it, and then a factor ``margin`` below the transition (the ordered side, where MPM
approaches the MAP estimate and stays stable).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import ArrayLike, check_bool, check_choice, check_int, check_real, machine_for, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf import EnergyModel, sample
from vmcl.mrf.energy import KINDS

__all__ = ["DEFAULT_TEMPERATURES", "TemperatureScan", "scan_temperature"]

DEFAULT_TEMPERATURES = tuple(float(t) for t in np.geomspace(0.25, 4.0, 13))
"""1/4 to 4 in steps of sqrt(2)."""


@dataclass(frozen=True)
class TemperatureScan:
    """What :func:`scan_temperature` measured.

    Attributes
    ----------
    temperatures : tuple of float
        Ascending.
    density : tuple of float
        The discontinuities' density in the draw at each temperature.
    transition : float
        The geometric middle of the interval where the density changes fastest against log T.
    chosen : float
        The MPM temperature: 1, or ``transition / margin`` where 1 is within a factor ``margin`` of it.
    """

    temperatures: tuple[float, ...]
    density: tuple[float, ...]
    transition: float
    chosen: float


def scan_temperature(data: ArrayLike, *, confidence: ArrayLike | None = None, edges: ArrayLike | None = None,
                     kind: str = "smooth", model: EnergyModel | None = None,
                     temperatures: Sequence[float] | None = None, sweeps: int = 300, lines: bool = True,
                     start: ArrayLike | None = None, margin: float = 1.5, seed: int = 0,
                     machine: Machine | None = None) -> TemperatureScan:
    """Draw the MRF at each temperature, measure its discontinuities, and find the transition.

    Parameters
    ----------
    data, confidence, edges, kind, model, lines, start, seed, machine
        As for :func:`vmcl.mrf.sample`.
    temperatures : sequence of float, optional
        At least 3 temperatures > 0; default :data:`DEFAULT_TEMPERATURES`.
    sweeps : int
        Sweeps per draw (each draw starts afresh from ``start`` or the data).
    margin : float
        >= 1: how far (as a factor) the MPM temperature keeps from the transition.

    Returns
    -------
    TemperatureScan
    """
    machine = machine_for(machine)
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    check_bool(lines, "lines")
    check_real(margin, "margin", minimum=1)
    check_int(sweeps, "sweeps", minimum=1, maximum=1_000_000)
    check_int(seed, "seed", minimum=0, maximum=2**64 - 1 - 1000)
    if temperatures is None:
        temperatures = DEFAULT_TEMPERATURES
    if isinstance(temperatures, (str, bytes)) or not isinstance(temperatures, Sequence):
        raise InputTypeError("temperatures must be a sequence of temperatures")
    scale = sorted({check_real(t, "temperatures", above=0) for t in temperatures})
    if len(scale) < 3:
        raise InputValueError(f"temperatures must hold at least 3 distinct values, got {len(scale)}")
    density = []
    for k, temperature in enumerate(scale):
        drawn = sample(data, confidence=confidence, edges=edges, kind=kind, model=model, temperature=temperature,
                       sweeps=sweeps, lines=lines, start=start, seed=seed + k, machine=machine)
        density.append(_density(drawn, kind, lines))
    slopes = np.abs(np.diff(density) / np.diff(np.log(scale)))
    fastest = int(np.argmax(slopes))
    transition = float(np.sqrt(scale[fastest] * scale[fastest + 1]))
    chosen = 1.0 if not 1.0 / margin < transition < margin else transition / margin
    return TemperatureScan(temperatures=tuple(scale), density=tuple(density), transition=transition, chosen=chosen)


def _density(drawn, kind: str, lines: bool) -> float:
    line_h, line_v = to_host(drawn.line_h), to_host(drawn.line_v)
    if lines or kind == "smooth":
        return float((line_h.sum() + line_v.sum()) / (line_h.size + line_v.size))
    f = to_host(drawn.field)
    walls = np.count_nonzero(f[:, 1:] != f[:, :-1]) + np.count_nonzero(f[1:] != f[:-1])
    return float(walls / (f[:, 1:].size + f[1:].size))
