"""Fit an MRF's parameters to the errors of the machine's own restorations of the examples.

Seed section "Learning and parameter estimation", the second stage: "estimating [the parameters] from
examples where data and desired solution are given". Maximum pseudolikelihood
(:func:`vmcl.learn.fit_pseudolikelihood`) fits the model under which the desired solutions are likely
samples; but a desired solution (a true disparity map, whose lines are whole contours and whose surfaces
are exact planes) is no sample of a membrane, and the machine does not sample the model: it runs mean
field at its schedule. So the model pseudolikelihood prefers need not be the one whose restorations are
best. This learner scores what the machine delivers: each candidate setting restores every example's
data, and its error is counted against the desired solution, in pixels:

- a pixel whose restored value lies more than ``tolerance`` from the desired one (the field's bad-1 rate
  at the default tolerance of 1 px of disparity or flow),
- a desired line pixel with no restored line within 1 px (missed), and a restored line pixel with no
  desired line within 1 px (false),

over the example's valid pixels. The parameters move by a compass search (Kolda, Lewis and Torczon,
SIAM Review 45, 2003): each in turn a step up and down, the first that lowers the error taken, every step
halved when none does. The search needs no gradient (the restoration's error is piecewise constant in
the parameters), and the mean field is deterministic, so the same examples give the same fit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vmcl.cm.core import check_bool, check_choice, check_int, check_real, machine_for, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.integrate import restore_cue
from vmcl.learn.pseudolikelihood import PRIOR_PARAMETERS, Example, model_overrides
from vmcl.machine import Machine
from vmcl.metrics import detection_scores
from vmcl.mrf import SOLVERS, Settings, boundary_map
from vmcl.mrf.energy import KINDS, host_field
from vmcl.mrf.inputs import device_pixels

__all__ = ["SEARCHABLE", "SEARCHED", "RestorationFit", "fit_restoration", "restoration_error"]

SEARCHED = ("alpha", "beta", "edge_gain", *(name for name in PRIOR_PARAMETERS if name != "line"))
"""The parameters the search moves by default: the data weight, the line price, its lowering at
brightness edges and the line prior's vertex and parallel potentials (in units of beta; the prior's
``line``, the central clique, stays the unit beta multiplies)."""

SEARCHABLE = (*SEARCHED, "kappa")
"""Every parameter the search can move: also the constant kind's Potts cost."""

_SCALED = ("alpha", "beta", "kappa")
"""Positive parameters, searched on a log2 scale (a step of 1 doubles them); the others by addition."""

_FIRST_STEP = {"alpha": 1.0, "beta": 1.0, "kappa": 1.0}
"""Initial steps: a factor of 2 for the weights, a quarter of beta for the others."""
_OTHER_STEP = 0.25


@dataclass(frozen=True)
class RestorationFit:
    """What :func:`fit_restoration` found.

    Attributes
    ----------
    settings : vmcl.mrf.Settings
        The start's settings with the fitted parameters (restored as :func:`vmcl.integrate.restore_cue`
        restores them, which adds ``require_edge`` for ``candidates_only``).
    values : dict
        The fitted parameters by name (the prior's by their :class:`vmcl.mrf.LinePrior` names).
    error : float
        The examples' weighted mean error at ``settings``.
    start_error : float
        The same at the start.
    evaluations : int
        Settings scored (each restores every example once).
    converged : bool
        Whether every step shrank below ``step_floor`` before the evaluations ran out.
    """

    settings: Settings
    values: dict[str, float]
    error: float
    start_error: float
    evaluations: int
    converged: bool


def restoration_error(field: Any, line_h: Any, line_v: Any, example: Example, *, tolerance: float = 1.0) -> float:
    """The error of one restoration against an example's desired solution, as a share of its valid pixels.

    Parameters
    ----------
    field : array of the example's field's shape
        The restored field.
    line_h, line_v : (H, W - 1) and (H - 1, W) arrays
        The restored line process.
    example : vmcl.learn.Example
        Its ``field`` and ``valid`` give the desired values, its ``line_h`` and ``line_v`` the desired
        lines. Without them no line is desired and every restored line counts as false (where
        :func:`vmcl.learn.fit_pseudolikelihood` leaves such an example's line sites unscored: a
        restoration must still not draw lines the truth does not have).
    tolerance : float
        > 0: a restored value further than this from the desired one (Euclidean, for vector fields) is wrong.

    Returns
    -------
    float
        (wrong pixels + missed line pixels + false line pixels) / valid pixels, the line pixels matched
        within 1 px (:func:`vmcl.metrics.detection_scores`).
    """
    if not isinstance(example, Example):
        raise InputTypeError(f"example must be a vmcl.learn.Example, got {type(example).__name__}")
    check_real(tolerance, "tolerance", above=0)
    desired = host_field(example.field, "example.field", ndims=(2, 3)).astype(np.float64)
    found = host_field(to_host(field), "field", ndims=(2, 3)).astype(np.float64)
    if found.shape != desired.shape:
        raise InputValueError(f"field must have the example's shape {desired.shape}, got {found.shape}")
    shape = desired.shape[:2]
    valid = np.all(np.isfinite(desired.reshape(*shape, -1)), axis=2)
    if example.valid is not None:
        valid &= _sites(example.valid, "example.valid", shape)
    count = int(valid.sum())
    if count == 0:
        raise InputValueError("example has no valid pixel: nothing to score")
    # A NaN restored value is wrong wherever the truth is known: only the unknown truth is zeroed.
    distance = np.sqrt(np.sum((found - np.nan_to_num(desired)).reshape(*shape, -1) ** 2, axis=2))
    wrong = int(np.count_nonzero(valid & ~(distance <= tolerance)))
    h_shape, v_shape = (shape[0], shape[1] - 1), (shape[0] - 1, shape[1])
    restored_lines = boundary_map(_sites(line_h, "line_h", h_shape), _sites(line_v, "line_v", v_shape))
    if (example.line_h is None) != (example.line_v is None):
        raise InputValueError("example must give both line_h and line_v, or neither")
    if example.line_h is None:
        desired_lines = np.zeros(shape, bool)
    else:
        desired_lines = boundary_map(_sites(example.line_h, "example.line_h", h_shape),
                                     _sites(example.line_v, "example.line_v", v_shape))
    scores = detection_scores(restored_lines & valid, desired_lines & valid, tolerance=1.0)
    missed = scores.n_true * (1.0 - scores.recall) if scores.n_true else 0.0
    false = scores.n_predicted * (1.0 - scores.precision) if scores.n_predicted else 0.0
    return (wrong + missed + false) / count


def fit_restoration(examples: Sequence[Example], start: Settings, *, kind: str = "smooth",
                    candidates_only: bool = False, method: str = "meanfield",
                    parameters: Sequence[str] = SEARCHED, weights: Sequence[float] | None = None,
                    tolerance: float = 1.0, evaluations: int = 200, step_floor: float = 1.0 / 32,
                    machine: Machine | None = None) -> RestorationFit:
    """Fit an MRF's parameters to the error of its restorations of ``examples`` (see the module's text).

    Parameters
    ----------
    examples : sequence of vmcl.learn.Example
        Each with its data (and optionally confidence and edges) and its desired solution.
    start : vmcl.mrf.Settings
        Where the search starts (e.g. a pseudolikelihood fit's model in the cue's settings); every
        parameter not searched and the schedules stay as they are.
    kind : {"smooth", "constant"}
    candidates_only : bool
        Forbid lines with no edge within the model's ``edge_radius``, as the machine's colour and texture
        MRFs do.
    method : str
        The solver of :data:`vmcl.mrf.SOLVERS` that restores (deterministic ones give a deterministic fit).
    parameters : sequence of str
        Those searched, among :data:`SEARCHABLE` (default :data:`SEARCHED`; add ``"kappa"`` for the
        constant kind).
    weights : sequence of float, optional
        Each example's weight in the mean error (e.g. to weigh rendered and real examples as two equal
        groups); default equal.
    tolerance : float
        As :func:`restoration_error` takes it.
    evaluations : int
        The most settings scored.
    step_floor : float
        The search stops when every step is below this share of its first size.
    machine : vmcl.Machine, optional

    Returns
    -------
    RestorationFit

    Raises
    ------
    InputValueError
        No example, an example without data, an unknown or repeated parameter, a scaled parameter not
        above 0 at the start, or weights that do not fit.
    InputTypeError
        ``examples``, ``start`` or ``parameters`` of the wrong type.
    """
    machine = machine_for(machine)
    if not isinstance(start, Settings):
        raise InputTypeError(f"start must be a vmcl.mrf.Settings, got {type(start).__name__}")
    if isinstance(examples, (str, bytes)) or not isinstance(examples, Sequence):
        raise InputTypeError(f"examples must be a sequence of vmcl.learn.Example, got {type(examples).__name__}")
    examples = list(examples)
    if not examples:
        raise InputValueError("examples is empty: nothing to fit")
    for k, example in enumerate(examples):
        if not isinstance(example, Example):
            raise InputTypeError(f"examples[{k}] must be a vmcl.learn.Example, got {type(example).__name__}")
        if example.data is None:
            raise InputValueError(f"examples[{k}] has no data: a restoration needs the measurements")
    check_choice(kind, "kind", KINDS)
    check_bool(candidates_only, "candidates_only")
    check_choice(method, "method", SOLVERS)
    if isinstance(parameters, (str, bytes)) or not isinstance(parameters, Sequence):
        raise InputTypeError(f"parameters must be a sequence of names, got {type(parameters).__name__}")
    parameters = tuple(parameters)
    if not parameters:
        raise InputValueError("parameters is empty: nothing to search")
    for name in parameters:
        check_choice(name, "parameters", SEARCHABLE)
    if len(set(parameters)) != len(parameters):
        raise InputValueError(f"parameters names one more than once: {parameters}")
    share = _weights(weights, len(examples))
    check_real(tolerance, "tolerance", above=0)
    check_int(evaluations, "evaluations", minimum=1)
    check_real(step_floor, "step_floor", above=0)

    # Uploaded once: every candidate restores the same data on the device; only its results come back.
    inputs = [_uploaded(example, machine) for example in examples]

    def error(point: np.ndarray) -> float:
        settings = _settings(start, parameters, point)
        total = 0.0
        for example, (data, confidence, edges), w in zip(examples, inputs, share):
            found = restore_cue(data, confidence=confidence, coupling=edges, kind=kind,
                                candidates_only=candidates_only, settings=settings, method=method, machine=machine)
            total += w * restoration_error(found.field, found.line_h, found.line_v, example, tolerance=tolerance)
        return total

    point = _point(start, parameters)
    first = np.array([_FIRST_STEP.get(name, _OTHER_STEP) for name in parameters])
    steps = first.copy()
    best = start_error = error(point)
    count = 1
    converged = False
    while count < evaluations:
        moved, complete = False, True
        for k in range(len(parameters)):
            for sign in (1.0, -1.0):
                if count >= evaluations:
                    complete = False
                    break
                trial = point.copy()
                trial[k] += sign * steps[k]
                if not _allowed(parameters[k], trial[k]):
                    continue
                value = error(trial)
                count += 1
                if value < best:
                    best, point, moved = value, trial, True
                    break
        # Only a whole pass without a better setting shows the steps are too long for this point.
        if complete and not moved:
            steps /= 2
            if not np.any(steps >= step_floor * first):
                converged = True
                break
    settings = _settings(start, parameters, point)
    return RestorationFit(settings, _values(parameters, point), float(best), float(start_error), count, converged)


def _sites(value: Any, name: str, shape: tuple[int, int]) -> np.ndarray:
    """A map of sites (pixels or line sites) as bool, if it is a real or boolean array of ``shape``."""
    host = np.asarray(to_host(value, name)) if isinstance(value, np.ndarray) or hasattr(value, "get") else None
    if host is None or host.shape != shape or host.dtype.kind not in "biuf":
        raise InputValueError(f"{name} must be a real or boolean array of shape {shape}, got {type(value).__name__} "
                              f"{getattr(host, 'dtype', '')} {getattr(host, 'shape', '')}")
    return host != 0


def _weights(weights: Sequence[float] | None, n: int) -> np.ndarray:
    if weights is None:
        return np.full(n, 1.0 / n)
    try:
        w = np.asarray(weights, np.float64)
    except (TypeError, ValueError):
        w = np.full(0, np.nan)
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
        raise InputValueError(f"weights must be {n} finite numbers >= 0, one per example, not all 0")
    return w / w.sum()


def _uploaded(example: Example, machine: Machine) -> tuple[Any, Any, Any]:
    data = machine.to_device(host_field(example.data, "example.data", ndims=(2, 3)).astype(np.float32))
    shape = (int(data.shape[0]), int(data.shape[1]))
    confidence = None if example.confidence is None else machine.to_device(
        host_field(example.confidence, "example.confidence", ndims=(2,)).astype(np.float32))
    edges = None if example.edges is None else device_pixels(example.edges, "example.edges", shape, np.uint8,
                                                             machine)
    return data, confidence, edges


def _point(settings: Settings, parameters: tuple[str, ...]) -> np.ndarray:
    values = _values_of(settings)
    for name in parameters:
        if name in _SCALED and not values[name] > 0:
            raise InputValueError(f"start must have {name} > 0 to search it (on a log scale), got {values[name]}")
    return np.array([math.log2(values[name]) if name in _SCALED else values[name] for name in parameters])


def _values_of(settings: Settings) -> dict[str, float]:
    values = model_overrides(settings.model, kappa=True)
    return {**{k: v for k, v in values.items() if k != "prior"}, **values["prior"]}


def _values(parameters: tuple[str, ...], point: np.ndarray) -> dict[str, float]:
    return {name: float(2.0 ** x if name in _SCALED else x) for name, x in zip(parameters, point)}


def _allowed(name: str, x: float) -> bool:
    # The energy takes any real potential; only the weights' log2 is kept where float32 holds them well.
    return name not in _SCALED or -20.0 <= x <= 20.0


def _settings(start: Settings, parameters: tuple[str, ...], point: np.ndarray) -> Settings:
    values = _values(parameters, point)
    prior = {name: values.pop(name) for name in PRIOR_PARAMETERS if name in values}
    overrides: dict[str, Any] = dict(values)
    if prior:
        overrides["prior"] = {**{name: getattr(start.model.prior, name) for name in PRIOR_PARAMETERS}, **prior}
    return start.override(overrides)
