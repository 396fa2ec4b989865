"""Maximum pseudolikelihood (Besag) for the line-process MRF's parameters, from examples.

Seed section "Learning and parameter estimation": the second stage, "estimating the parameters from
examples where data and desired solution are given", by Besag's pseudolikelihood. An example is a
desired solution (the field f and its line process l), with the data g and its confidence gamma the
early module gave, and the brightness edges the lines are coupled to. The energy U(f, l) of
:mod:`vmcl.mrf.energy` divided by the temperature T is linear in its natural parameters

    theta = (alpha, coupling, line, edge_gain, end, continuation, turn, junction, crossing, parallel) / T

(:data:`PARAMETERS`; ``coupling`` is 1 for the smooth kind's membrane and kappa for the constant
kind's Potts cost; the line prior's entries and edge_gain are multiplied by beta). Every site's
conditional given all the others is then an exponential family in theta:

- a pixel of the smooth kind: Gaussian, precision 2 (a gamma + c n), mean (a gamma g + c s) / (a gamma + c n)
  over its n bonded neighbours of sum s;
- a pixel of the constant kind: softmax over the levels of -(a gamma (level - g)^2 + kappa (bonded
  neighbours at another level));
- a line site: logistic in dE / T, the change of every clique that holds it (the broken bond, its central
  cost lowered at brightness edges, both end vertices, both parallel pairs), the conditional the Gibbs
  sampler draws from (kernels/mrf.cl).

The negative log pseudolikelihood, the sum of -log p(site | rest) over every scored site, is convex in
theta; Newton's method with a backtracking line search minimises it. Its value, gradient and Hessian are
sums over sites computed by kernels/pseudolikelihood.cl on the device, one work-item per chunk of sites,
so a step costs one pass over the lattice whatever the number of parameters.

A small ridge (``ridge`` times the number of sites, times |theta|^2 / 2) keeps the estimate finite where
the examples separate the two states of a line site perfectly (a desired line exactly where the field
jumps, as with ground truth), where the unpenalised estimate runs off to infinity along a direction that
only sharpens the threshold.

References
----------
J. Besag, "Statistical analysis of non-lattice data", The Statistician 24(3):179-195, 1975.
J. Besag, "On the statistical analysis of dirty pictures", J. Roy. Statist. Soc. B 48(3):259-302, 1986.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from vmcl.cm.core import check_choice, check_int, check_real, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf.checks import MAX_COUNT
from vmcl.mrf.energy import KINDS, EnergyModel, LinePrior, host_field, line_costs

__all__ = ["LINE_PARAMETERS", "PARAMETERS", "PRIOR_PARAMETERS", "Example", "Pseudolikelihood", "PseudolikelihoodFit",
           "check_fixed", "fit_pseudolikelihood"]

PARAMETERS = ("alpha", "coupling", "line", "edge_gain", "end", "continuation", "turn", "junction", "crossing",
              "parallel")
"""The natural parameters, in theta's order (each is the energy's weight divided by T)."""
LINE_PARAMETERS = PARAMETERS[1:]
"""Those a line site's conditional depends on, in the order of its features (kernels/pseudolikelihood.cl)."""
PRIOR_PARAMETERS = ("line", "end", "continuation", "turn", "junction", "crossing", "parallel")
"""The :class:`vmcl.mrf.LinePrior` entries among them."""
CHUNK = 64
"""Sites summed by one work-item before the host adds the partial sums in float64."""
SITES = ("all", "pixels", "lines")
"""Which conditionals a pseudolikelihood scores: every site's, the pixels' (the field given its
neighbours, its data and the lines) or the line sites' (each line given the field and the other lines)."""


@dataclass(frozen=True)
class Example:
    """One example: a desired solution, the data it was to be restored from and the edges.

    Parameters
    ----------
    field : (H, W) or (H, W, C) array
        The desired field f (disparity, flow, a level map). NaN where it is unknown (e.g. Middlebury's
        unknown disparities): those pixels are left out, with every conditional that reads them. Infinite
        values are refused (NaN marks an unknown value).
    line_h, line_v : (H, W - 1) and (H - 1, W) arrays, optional
        The desired line process (non-zero: a line), both or neither. Without them there are no lines
        and the line sites are not scored.
    data : array of the field's shape, optional
        The measurements g the field restores, NaN where there is none (infinite values are refused).
    confidence : (H, W) array, optional
        gamma >= 0 of the data (default 1 wherever the data is finite).
    edges : (H, W) array, optional
        Brightness edge pixels (non-zero), which lower a line's cost (``edge_gain``).
    valid : (H, W) bool array, optional
        Where the example holds (default everywhere the field is finite).
    levels : sequence of float, optional
        The constant kind's levels in this example (e.g. spread over its own data's range, as
        :func:`vmcl.mrf.restore` spreads a count of levels); default those the fit is given.
    """

    field: Any
    line_h: Any = None
    line_v: Any = None
    data: Any = None
    confidence: Any = None
    edges: Any = None
    valid: Any = None
    levels: Any = None


@dataclass(frozen=True)
class PseudolikelihoodFit:
    """What :func:`fit_pseudolikelihood` found.

    Attributes
    ----------
    theta : dict of str to float
        Every natural parameter of :data:`PARAMETERS` (energy weight / T), fitted or held.
    standard_error : dict of str to float
        For each fitted parameter, the square root of the diagonal of the inverse Hessian of the objective
        minimised at theta: the negative log pseudolikelihood plus the ridge, whose curvature
        ``ridge * sites`` it adds to each diagonal entry (negligible beside an informed parameter's own; the
        parameters the examples say nothing of are not fitted, see ``uninformed``). The curvature, not the
        sandwich estimate: it understates the spread, since neighbouring conditionals are not independent.
    fitted : tuple of str
        The parameters that were fitted; the others were held.
    kind : {"smooth", "constant"}
    scored : {"all", "pixels", "lines"}
        The conditionals scored.
    levels : tuple of float or None
        The constant kind's levels.
    value : float
        The mean negative log pseudolikelihood per scored site at theta (ridge excluded).
    sites : dict of str to int
        Scored sites: "pixels" and "lines".
    iterations : int
        Newton steps taken.
    converged : bool
        Whether the Newton decrement fell below the tolerance.
    history : list of float
        The objective per scored site (ridge included) at the start and after each Newton step.
    uninformed : tuple of str
        The held parameters the examples carry no information on (:attr:`Pseudolikelihood.uninformed`: no
        data for alpha; no scored line site whose conditional depends on a line parameter, e.g. no brightness
        edge for edge_gain, no vertex of the kind for a prior entry). Their theta is 0, which the
        pseudolikelihood does not depend on; :meth:`model` takes them from its base.
    """

    theta: dict[str, float]
    standard_error: dict[str, float]
    fitted: tuple[str, ...]
    kind: str
    scored: str
    levels: tuple[float, ...] | None
    value: float
    sites: dict[str, int]
    iterations: int
    converged: bool
    history: list[float] = field(default_factory=list)
    uninformed: tuple[str, ...] = ()

    @property
    def temperature(self) -> float:
        """T of the examples in the energy's units: 1 / coupling for the smooth kind (whose bond weight
        is 1), 1 for the constant kind (whose Potts cost kappa is a parameter)."""
        return 1.0 / self.theta["coupling"] if self.kind == "smooth" else 1.0

    def model(self, base: EnergyModel | None = None, *, held_coupling: str = "fixed={'coupling': 1.0}") -> EnergyModel:
        """The fitted energy as an :class:`vmcl.mrf.EnergyModel`, in the units of ``temperature``.

        beta is the line's cost (so the prior's ``line`` is 1), or 1 where the fitted line cost is not
        positive; the prior's other entries and ``edge_gain`` are in units of it. Fields the fit does
        not touch (levels, require_edge, edge_radius, and kappa for the smooth kind) come from ``base``
        (default ``EnergyModel()``);
        the constant kind's levels are the fitted ones. A fit of the line sites alone takes alpha from
        ``base``; one of the pixel sites alone takes beta, the prior and edge_gain from it; and every fit takes
        from it the parameters it has no information on (``uninformed``: edge_gain without brightness edges,
        a prior entry without a vertex of its kind), so that they keep their values rather than become 0.
        ``held_coupling`` is how the caller holds the coupling at 1, which the advice of a refused fit names
        (a command's option, e.g. "--fix coupling=1").

        Raises
        ------
        InputValueError
            The fit gives no usable energy: a data weight of 0 (at its bound) or a coupling that is not
            positive.
        """
        base = EnergyModel() if base is None else base
        if not isinstance(base, EnergyModel):
            raise InputTypeError(f"base must be a vmcl.mrf.EnergyModel or None, got {type(base).__name__}")
        if not isinstance(held_coupling, str):
            raise InputTypeError(f"held_coupling must be a str, got {type(held_coupling).__name__}")
        scale = self.theta["coupling"] if self.kind == "smooth" else 1.0
        if not self.theta["coupling"] > 0:
            raise InputValueError(f"the fitted coupling is {self.theta['coupling']:.4g}, not > 0: the examples are "
                                  "rougher inside regions than across their lines, so no MRF of this kind fits them")
        kept = set(self.uninformed)
        if self.scored != "lines" and "alpha" not in kept and not self.theta["alpha"] > 0:
            raise InputValueError(f"the fitted data weight is {self.theta['alpha']:.4g}: the desired fields are "
                                  "predicted by their neighbours better than by any share of the data (e.g. exactly "
                                  "planar ground truth, whose fitted coupling then grows without bound); hold the "
                                  f"coupling ({held_coupling}) to fit the data weight in the energy's units")
        line = self.theta["line"] / scale
        beta = base.beta if "line" in kept else line if line > 0 else 1.0
        prior = LinePrior(**{name: getattr(base.prior, name) if name in kept else self.theta[name] / scale / beta
                             for name in PRIOR_PARAMETERS})
        changes: dict[str, Any] = {}
        if self.scored != "lines" and "alpha" not in kept:
            changes["alpha"] = self.theta["alpha"] / scale
        if self.scored != "pixels":
            changes.update(beta=beta, prior=prior, edge_gain=base.edge_gain if "edge_gain" in kept else
                           self.theta["edge_gain"] / scale / beta)
        if self.kind == "constant":
            changes["kappa"] = self.theta["coupling"]
            if self.levels is not None:  # one set for every example (else each had its own: base's stay)
                changes["levels"] = self.levels
        return replace(base, **changes)


def model_overrides(model: EnergyModel, *, kappa: bool = False) -> dict[str, Any]:
    """The parameters a fit learns, of ``model``, as plain numbers: what :meth:`vmcl.mrf.Settings.override`
    and a Config's ``[mrf.<cue>]`` table take (alpha, beta, edge_gain, the prior's entries as a table, and
    with ``kappa`` the constant kind's Potts cost)."""
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel, got {type(model).__name__}")
    found: dict[str, Any] = {"alpha": float(model.alpha), "beta": float(model.beta),
                             "edge_gain": float(model.edge_gain),
                             "prior": {name: float(getattr(model.prior, name)) for name in PRIOR_PARAMETERS}}
    if kappa:
        found["kappa"] = float(model.kappa)
    return found


class _Lattice:
    """One example on the device: its fields, and the features that do not depend on theta."""

    def __init__(self, example: Example, kind: str, levels: np.ndarray | None, edge_radius: int | None,
                 machine: Machine) -> None:
        self.machine = machine
        with np.errstate(over="ignore"):  # a value beyond float32's range is refused below, as the infinity it becomes
            f = host_field(example.field, "field", ndims=(2, 3)).astype(np.float32)
        if f.ndim == 3 and not 1 <= f.shape[2] <= 4:
            raise InputValueError(f"field must be (H, W) or (H, W, C) with C in 1..4, got shape {f.shape}")
        if f.ndim == 3 and kind == "constant" and f.shape[2] != 1:
            raise InputValueError(f"kind='constant' takes scalar fields (H, W), got shape {f.shape}")
        self.height, self.width = f.shape[:2]
        if min(self.height, self.width) < 2:
            raise InputValueError(f"field must be at least 2 x 2 pixels, got shape {f.shape}")
        self.ncomp = 1 if f.ndim == 2 else f.shape[2]
        shape = (self.height, self.width)
        known = np.all(np.isfinite(f.reshape(*shape, -1)), axis=2)
        valid = known if example.valid is None else known & (_pixels(example.valid, "valid", shape) != 0)
        self.f = np.where(known.reshape(*shape, *([1] if f.ndim == 3 else [])), f, 0).astype(np.float32)
        self.data = example.data is not None
        g = np.zeros_like(self.f) if example.data is None else host_field(example.data, "data", ndims=(2, 3))
        if g.shape != f.shape:
            raise InputValueError(f"data must have the field's shape {f.shape}, got {g.shape}")
        for name, values in (("field", f), ("data", g)):
            # An infinity is no value, and no unknown one either (NaN is), as vmcl.mrf.restore holds; a value
            # beyond float32's range becomes one in the float32 sums.
            with np.errstate(over="ignore"):
                if np.isinf(values.astype(np.float32)).any():
                    raise InputValueError(f"{name} must not hold infinities or values beyond float32's range "
                                          "(NaN marks an unknown value)")
        measured = np.all(np.isfinite(g.reshape(*shape, -1)), axis=2) & self.data
        gamma = np.ones(shape) if example.confidence is None else _pixels(example.confidence, "confidence", shape)
        if not np.all(np.isfinite(gamma)) or np.any(gamma < 0):
            raise InputValueError("confidence must be finite and >= 0")
        gamma = np.where(measured, gamma, 0).astype(np.float32)
        g = np.where(measured.reshape(*shape, *([1] if f.ndim == 3 else [])), g, 0).astype(np.float32)
        self.lines = example.line_h is not None or example.line_v is not None
        lh, lv = np.zeros(shape, np.uint8), np.zeros(shape, np.uint8)
        if self.lines:
            given_h = _pixels(example.line_h, "line_h", (self.height, self.width - 1))
            given_v = _pixels(example.line_v, "line_v", (self.height - 1, self.width))
            lh[:, :-1], lv[:-1, :] = given_h != 0, given_v != 0
        self.edges = example.edges is not None
        edges = np.zeros(shape, np.uint8) if example.edges is None else _pixels(example.edges, "edges", shape) != 0
        put = machine.to_device
        self.d_f, self.d_g, self.d_gamma = put(self.f), put(g), put(gamma)
        self.d_lh, self.d_lv, self.d_valid = put(lh), put(lv), put(valid.astype(np.uint8))
        dims = (np.int64(self.width), np.int64(self.height))
        self.dims = dims
        n = self.height * self.width
        kind_define = int(kind == "constant")
        self.kind = kind
        self.line_features = self.line_observed = None
        if self.lines:
            self.line_features = machine.empty(2 * n * 2 * len(LINE_PARAMETERS), np.float32)
            self.line_observed = machine.empty(2 * n, np.int32)
            usable = np.ones((2, *shape), np.uint8)
            if edge_radius is not None:
                # the sites the model forbids (b = +inf): line_costs decides them as the restoration does
                forbid = EnergyModel(require_edge=True, edge_radius=edge_radius)
                cost_h, cost_v = line_costs(shape, edges if self.edges else None, forbid)
                usable[0, :, :-1], usable[1, :-1, :] = np.isfinite(cost_h), np.isfinite(cost_v)
            program = machine.kernel("pseudolikelihood", "line_features", NCOMP=self.ncomp, KIND=kind_define)
            machine.launch(program, (self.width, self.height, 2), self.d_f, self.d_lh, self.d_lv,
                           put(edges.astype(np.uint8)), np.int32(self.edges), self.d_valid, put(usable),
                           self.line_features, self.line_observed, *dims)
        self.potts_features = self.potts_observed = None
        self.nlevels = 0
        if kind == "constant":
            if example.levels is not None:
                levels = _levels(example.levels, [])
            assert levels is not None
            self.nlevels = int(levels.size)
            self.potts_features = machine.empty(n * self.nlevels * 2, np.float32)
            self.potts_observed = machine.empty(n, np.int32)
            program = machine.kernel("pseudolikelihood", "potts_features", NCOMP=1, KIND=1, NLEVELS=self.nlevels)
            machine.launch(program, (self.width, self.height), self.d_f, self.d_g, self.d_gamma, self.d_lh, self.d_lv,
                           put(levels), self.d_valid, self.potts_features, self.potts_observed, *dims)
            if np.any(valid & ~np.isin(self.f.reshape(shape), levels)):
                raise InputValueError("field holds values that are not among the levels; give levels= or a field "
                                      "of levels")
        self.counts = {"pixels": self._scored_pixels(valid, lh, lv, gamma),
                       "lines": 0 if self.line_observed is None else int(np.count_nonzero(self.line_observed.get() >= 0))}

    def _scored_pixels(self, valid: np.ndarray, lh: np.ndarray, lv: np.ndarray, gamma: np.ndarray) -> int:
        """Pixels whose conditional is scored: valid, every bonded neighbour valid, and (smooth kind)
        anchored by data or a bond; the constant kind's count comes from its features kernel."""
        if self.potts_observed is not None:
            return int(np.count_nonzero(self.potts_observed.get() >= 0))
        ok = valid.copy()
        bonded = np.zeros(valid.shape, int)
        pad = np.pad(valid, 1, constant_values=True)
        for keep, neighbour in ((np.pad(~lh[:, :-1].astype(bool), ((0, 0), (1, 0))), pad[1:-1, :-2]),
                                (np.pad(~lh[:, :-1].astype(bool), ((0, 0), (0, 1))), pad[1:-1, 2:]),
                                (np.pad(~lv[:-1, :].astype(bool), ((1, 0), (0, 0))), pad[:-2, 1:-1]),
                                (np.pad(~lv[:-1, :].astype(bool), ((0, 1), (0, 0))), pad[2:, 1:-1])):
            ok &= ~keep | neighbour
            bonded += keep
        return int(np.count_nonzero(ok & ((bonded > 0) | (gamma > 0))))

    def terms(self, theta: np.ndarray, pixels: bool, lines: bool) -> tuple[float, np.ndarray, np.ndarray]:
        """The negative log pseudolikelihood over this example's scored sites, its gradient and Hessian in
        all of :data:`PARAMETERS` (the pixel sites with ``pixels``, the line sites with ``lines``)."""
        size = len(PARAMETERS)
        value, grad, hess = 0.0, np.zeros(size), np.zeros((size, size))
        parts: list[tuple[tuple[int, ...], tuple[float, np.ndarray, np.ndarray]]] = []
        n = self.height * self.width
        if pixels and self.kind == "smooth":
            kernel = self.machine.kernel("pseudolikelihood", "gaussian_terms", NCOMP=self.ncomp, KIND=0, CHUNK=CHUNK)
            rows = self._sum_rows(kernel, 2, (n + CHUNK - 1) // CHUNK, self.d_f, self.d_g, self.d_gamma,
                                  self.d_lh, self.d_lv, self.d_valid, np.float32(theta[0]), np.float32(theta[1]),
                                  *self.dims)
            parts.append(((0, 1), rows))
        elif pixels:
            rows = self._softmax(self.potts_features, self.potts_observed, n, self.nlevels, theta[:2])
            parts.append(((0, 1), rows))
        if lines and self.line_features is not None:
            rows = self._softmax(self.line_features, self.line_observed, 2 * n, 2, theta[1:])
            parts.append((tuple(range(1, size)), rows))
        for index, (v, g, h) in parts:
            value += v
            grad[list(index)] += g
            hess[np.ix_(index, index)] += h
        return value, grad, hess

    def _softmax(self, features: Any, observed: Any, sites: int, options: int, theta: np.ndarray) -> tuple:
        k = theta.size
        kernel = self.machine.kernel("pseudolikelihood", "softmax_terms", NOPT=options, K=k, CHUNK=CHUNK)
        items = (sites + CHUNK - 1) // CHUNK
        return self._sum_rows(kernel, k, items, features, observed, self.machine.to_device(theta.astype(np.float32)),
                              np.int64(sites))

    def _sum_rows(self, kernel: Any, k: int, items: int, *args: Any) -> tuple[float, np.ndarray, np.ndarray]:
        """Launch ``kernel`` over ``items`` chunks and add its rows (value, gradient, Hessian's upper
        triangle) in float64; the output comes from the machine's buffer pool."""
        width = 1 + k + k * (k + 1) // 2
        out = self.machine.empty(items * width, np.float32)
        self.machine.launch(kernel, (items,), *args, out)
        total = out.get().reshape(items, width).astype(np.float64).sum(axis=0)
        hess = np.zeros((k, k))
        hess[np.triu_indices(k)] = total[1 + k:]
        hess = hess + np.triu(hess, 1).T
        return float(total[0]), total[1:1 + k], hess


def _pixels(x: Any, name: str, shape: tuple[int, ...]) -> np.ndarray:
    array = host_field(np.asarray(x) if isinstance(x, (list, tuple)) else x, name, ndims=(2,), empty=True)
    if array.shape != shape:
        raise InputValueError(f"{name} must have shape {shape}, got {array.shape}")
    return array


def _levels(given: Any, fields: list[np.ndarray]) -> np.ndarray:
    if given is not None:
        try:
            levels = np.asarray(given, np.float32)
        except (TypeError, ValueError):
            raise InputValueError(f"levels must be 2..64 distinct finite values, got {given!r}") from None
        if levels.ndim != 1 or not 2 <= levels.size <= 64 or not np.all(np.isfinite(levels)) \
                or np.unique(levels).size != levels.size:
            raise InputValueError(f"levels must be 2..64 distinct finite values, got {given!r}")
        return levels
    values = np.unique(np.concatenate([f[np.isfinite(f)].ravel() for f in fields]).astype(np.float32))
    if not 2 <= values.size <= 64:
        raise InputValueError(f"the constant kind's fields must hold 2..64 distinct levels, got {values.size}; "
                              "give levels=")
    return values


class Pseudolikelihood:
    """The negative log pseudolikelihood of examples, prepared on the device.

    The examples' fields and each site's features (which do not depend on theta) are computed once, when
    it is made; each :meth:`terms` is then one pass over every site.

    Parameters
    ----------
    examples : sequence of Example
    kind : {"smooth", "constant"}
    levels : sequence of float, optional
        The constant kind's levels (default: the distinct values of the fields, 2 to 64).
    sites : {"all", "pixels", "lines"}
        The conditionals scored (:data:`SITES`).
    edge_radius : int, optional
        The model's ``require_edge``: line sites with no edge pixel within this Chebyshev radius of either
        pixel are forbidden, so not scored (as the constant cues' MRFs run, coupled to their candidates).
    machine : vmcl.Machine, optional

    Attributes
    ----------
    levels : tuple of float or None
    sites : dict of str to int
        Scored "pixels" and "lines".
    has_data, has_lines, has_edges : bool
        Whether any example gives data, a line process, brightness edges.
    uninformed : tuple of str
        The parameters the scored conditionals do not depend on, so the examples carry no information
        on: alpha when no example gives data (pixels scored), and each line parameter but the coupling
        (line, edge_gain, the prior's entries; lines scored) whose feature is 0 at every scored line site
        (no brightness edge at any for edge_gain, no vertex that a line would make or unmake of the kind
        for a prior entry; every one when no line site is scored).
    """

    def __init__(self, examples: Sequence[Example], *, kind: str = "smooth", levels: Sequence[float] | None = None,
                 sites: str = "all", edge_radius: int | None = None, machine: Machine | None = None) -> None:
        machine = machine_for(machine)
        check_choice(kind, "kind", KINDS)
        self.scored = check_choice(sites, "sites", SITES)
        if isinstance(examples, Example):
            examples = [examples]
        if not isinstance(examples, Sequence) or not examples or not all(isinstance(e, Example) for e in examples):
            raise InputTypeError("examples must be a non-empty sequence of vmcl.learn.Example")
        if edge_radius is not None:
            check_int(edge_radius, "edge_radius", minimum=0, maximum=MAX_COUNT)
        found = None
        if kind == "constant" and (levels is not None or any(e.levels is None for e in examples)):
            found = _levels(levels, [host_field(e.field, "field", ndims=(2, 3)) for e in examples if e.levels is None])
        self.kind = kind
        self._lattices = [_Lattice(e, kind, found, edge_radius, machine) for e in examples]
        self.levels = None if found is None else tuple(float(v) for v in found)
        self.sites = {"pixels": sum(lat.counts["pixels"] for lat in self._lattices) if sites != "lines" else 0,
                      "lines": sum(lat.counts["lines"] for lat in self._lattices) if sites != "pixels" else 0}
        self.has_data = any(lat.data for lat in self._lattices)
        self.has_lines = any(lat.lines for lat in self._lattices)
        self.has_edges = any(lat.edges for lat in self._lattices)
        self.uninformed = self._uninformed()

    def _uninformed(self) -> tuple[str, ...]:
        found = ["alpha"] if self.scored != "lines" and not self.has_data else []
        if self.scored == "pixels":
            return tuple(found)
        # At theta = 0 every line site's two states are equally likely, so each parameter's curvature is a
        # quarter of the sum of its feature's squares over the scored sites: 0 exactly where the feature is
        # 0 at every one (the features are small whole numbers, so one site that has it gives at least 1/4).
        hess = np.zeros((len(PARAMETERS), len(PARAMETERS)))
        for lattice in self._lattices:
            hess += lattice.terms(np.zeros(len(PARAMETERS)), pixels=False, lines=True)[2]
        return tuple(found + [name for k, name in enumerate(PARAMETERS)
                              if name in LINE_PARAMETERS[1:] and not hess[k, k] > 0.125])

    def terms(self, theta: Mapping[str, float] | np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """The value at ``theta`` (a mapping with every name of :data:`PARAMETERS`, or their vector in
        that order), its gradient (10,) and Hessian (10, 10): sums over every scored site, no ridge."""
        if isinstance(theta, Mapping):
            missing = [name for name in PARAMETERS if name not in theta]
            if missing:
                raise InputValueError(f"theta needs a value for {', '.join(missing)}")
            vector = np.array([check_real(theta[name], f"theta[{name!r}]") for name in PARAMETERS], np.float64)
        else:
            if not isinstance(theta, np.ndarray) or theta.dtype.kind not in "iuf":
                raise InputTypeError(f"theta must be a mapping of {', '.join(PARAMETERS)} to numbers, or their "
                                     f"real vector, got {type(theta).__name__}")
            vector = theta.astype(np.float64)
            if vector.shape != (len(PARAMETERS),) or not np.all(np.isfinite(vector)):
                raise InputValueError(f"theta must hold {len(PARAMETERS)} finite values, got shape {vector.shape}")
        size = len(PARAMETERS)
        value, grad, hess = 0.0, np.zeros(size), np.zeros((size, size))
        for lattice in self._lattices:
            v, g, h = lattice.terms(vector, pixels=self.scored in ("all", "pixels"),
                                    lines=self.scored in ("all", "lines"))
            value, grad, hess = value + v, grad + g, hess + h
        return value, grad, hess


def fit_pseudolikelihood(examples: Sequence[Example], *, kind: str = "smooth",
                         levels: Sequence[float] | None = None, fixed: Mapping[str, float] | None = None,
                         sites: str = "all", edge_radius: int | None = None, ridge: float = 1e-6, tolerance: float = 1e-9, max_iterations: int = 100,
                         machine: Machine | None = None) -> PseudolikelihoodFit:
    """Fit the line-process MRF's natural parameters to examples by maximum pseudolikelihood.

    Parameters
    ----------
    examples : sequence of Example
        Desired solutions with their data and edges (one or many; their sites are pooled).
    kind : {"smooth", "constant"}
        Piecewise smooth (the membrane) or piecewise constant (Potts).
    levels : sequence of float, optional
        The constant kind's levels; default the distinct values of the fields (2 to 64).
    fixed : mapping of str to float, optional
        Parameters of :data:`PARAMETERS` held at these natural values instead of fitted. Held by
        default, at 0: those the examples carry no information on (:attr:`Pseudolikelihood.uninformed`:
        ``alpha`` when no example has data, ``edge_gain`` when no scored line site has a brightness edge, a
        prior entry when none has a vertex of its kind, every line parameter when none has lines), listed
        in the fit's ``uninformed``; and those the scored ``sites`` do not depend on.
    sites : {"all", "pixels", "lines"}
        The conditionals scored (:data:`SITES`). "lines" fits the line process given the examples'
        fields: give the fields the lines are to be decided on (e.g. the measurements themselves);
        the data weight is then not fitted, and :meth:`PseudolikelihoodFit.model` takes it from its base.
    edge_radius : int, optional
        Fit the model with ``require_edge`` at this radius (see :class:`Pseudolikelihood`).
    ridge : float
        >= 0: the penalty ridge * sites * |theta|^2 / 2 on the fitted parameters (see the module notes).
    tolerance : float
        > 0: stop when the Newton decrement per scored site falls below it.
    max_iterations : int
        Newton steps at most (1 .. 1000).
    machine : vmcl.Machine, optional

    Returns
    -------
    PseudolikelihoodFit

    Examples
    --------
    An Ising field drawn at coupling J = 0.25 (kappa = 0.5) by the Gibbs sampler, and J found again:

    >>> import numpy as np
    >>> from vmcl import mrf
    >>> spins = np.random.default_rng(1).integers(0, 2, (64, 64)).astype(np.float32)
    >>> ising = mrf.EnergyModel(alpha=0.0, kappa=0.5, levels=(0.0, 1.0))
    >>> drawn = mrf.sample(spins, confidence=np.zeros((64, 64)), kind="constant", model=ising, lines=False,
    ...                    start=spins, sweeps=200, seed=3)
    >>> fit = fit_pseudolikelihood([Example(drawn.field)], kind="constant")
    >>> abs(fit.theta["coupling"] / 2 - 0.25) < 0.03
    True
    """
    machine = machine_for(machine)
    check_choice(kind, "kind", KINDS)
    check_real(ridge, "ridge", minimum=0)
    check_real(tolerance, "tolerance", above=0)
    check_int(max_iterations, "max_iterations", minimum=1, maximum=1000)
    fixed = check_fixed(fixed, kind=kind, sites=sites)
    problem = Pseudolikelihood(examples, kind=kind, levels=levels, sites=sites, edge_radius=edge_radius,
                               machine=machine)
    held = dict(fixed)
    if sites == "lines":
        held.setdefault("alpha", 0.0)
    if sites == "pixels":
        held.update({name: fixed.get(name, 0.0) for name in LINE_PARAMETERS if name != "coupling"})
    # Fitted, such a parameter would take the value the ridge alone gives it (0), with a standard error of
    # the ridge's own curvature: a number the examples never said.
    uninformed = tuple(name for name in problem.uninformed if name not in fixed)
    held.update({name: 0.0 for name in uninformed})
    free = [i for i, name in enumerate(PARAMETERS) if name not in held]
    if not free:
        raise InputValueError("every parameter is held: nothing to fit")
    counts = dict(problem.sites)
    scored = counts["pixels"] + counts["lines"]
    if not scored:  # else Newton "converges" at once on a zero objective and theta is its start
        raise InputValueError(f"examples: no site to score (sites={sites!r}): every pixel is unknown (NaN) or not "
                              "valid, or lacks the valid neighbours and data its conditional reads, and no line "
                              "site is scored")
    weight = ridge * scored
    theta = np.array([held.get(name, _START[name]) for name in PARAMETERS], np.float64)

    def objective(point: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        value, grad, hess = problem.terms(point)
        sub = point[free]
        return (value + 0.5 * weight * float(sub @ sub), grad[free] + weight * sub,
                hess[np.ix_(free, free)] + weight * np.eye(len(free)))

    value, grad, hess = objective(theta)
    if not math.isfinite(value):
        raise InputValueError("the pseudolikelihood is not finite at the start; check the examples' fields")
    history, converged, iterations = [value / scored], False, 0
    bounded = [k for k, i in enumerate(free) if PARAMETERS[i] in LOWER_BOUNDS]
    for iterations in range(1, max_iterations + 1):
        step = _bounded_step(theta[free], grad, hess, bounded, [LOWER_BOUNDS.get(PARAMETERS[i], 0.0) for i in free])
        decrement = float(-grad @ step)
        if decrement / scored < tolerance:
            converged = True
            iterations -= 1
            break
        t = 1.0
        while True:  # a projected line search: the bounded parameters are clamped to their domain
            trial = theta.copy()
            trial[free] += t * step
            for k in bounded:
                trial[free[k]] = max(trial[free[k]], LOWER_BOUNDS[PARAMETERS[free[k]]])
            new = objective(trial)
            # Armijo's condition on the step actually taken (the clamped one)
            if math.isfinite(new[0]) and new[0] <= value + 1e-4 * float(grad @ (trial[free] - theta[free])):
                break
            t *= 0.5
            if t < 1e-10:
                break
        if t < 1e-10:
            converged = decrement / scored < 1e3 * tolerance
            break
        theta, (value, grad, hess) = trial, new
        history.append(value / scored)
    covariance = np.linalg.pinv(hess)
    errors = {PARAMETERS[i]: float(math.sqrt(max(covariance[k, k], 0.0))) for k, i in enumerate(free)}
    plain = problem.terms(theta)[0]
    return PseudolikelihoodFit(theta={name: float(v) for name, v in zip(PARAMETERS, theta)}, standard_error=errors,
                               fitted=tuple(PARAMETERS[i] for i in free), kind=kind, scored=sites,
                               levels=problem.levels,
                               value=plain / scored, sites=counts, iterations=iterations, converged=converged,
                               history=history, uninformed=uninformed)


# Where Newton starts: the hand-set presets' shape at T = 1 (any start converges; the objective is convex).
_START = {"alpha": 1.0, "coupling": 1.0, "line": 1.0, "edge_gain": 0.5, "end": 0.5, "continuation": 0.0,
          "turn": 0.25, "junction": 0.75, "crossing": 1.5, "parallel": 1.0}


def check_fixed(fixed: Mapping[str, float] | None, *, kind: str = "smooth", sites: str = "all") -> dict[str, float]:
    """:func:`fit_pseudolikelihood`'s ``fixed`` checked: names among :data:`PARAMETERS`, real values, each in
    the model's domain (``alpha`` > 0, or 0 where only the lines are scored; ``coupling`` > 0, which
    :meth:`PseudolikelihoodFit.model` needs of either kind and the smooth kind's pixels' conditionals too). A held value outside it was met as a pseudolikelihood "not finite at the start", blamed on the
    examples, or as a "fitted" data weight of 0. Callers that measure examples first check here before."""
    check_choice(kind, "kind", KINDS)
    check_choice(sites, "sites", SITES)
    if fixed is not None and not isinstance(fixed, Mapping):
        raise InputTypeError(f"fixed must be a mapping of parameter names to values, got {type(fixed).__name__}")
    fixed = dict(fixed or {})
    for name, value in fixed.items():
        if name not in PARAMETERS:
            raise InputValueError(f"fixed: unknown parameter {name!r}; the parameters are {', '.join(PARAMETERS)}")
        check_real(value, f"fixed[{name!r}]")
    if "alpha" in fixed and not (fixed["alpha"] > 0 or (fixed["alpha"] == 0 and sites == "lines")):
        raise InputValueError(f"fixed['alpha'] must be > 0 (the data term's weight: the model's fields answer to "
                              f"their data), got {fixed['alpha']}")
    if "coupling" in fixed and not fixed["coupling"] > 0:
        why = ("the pixels' conditionals are not finite without it" if kind == "smooth" else
               "the Potts cost kappa: an energy that does not favour equal neighbours makes no model")
        raise InputValueError(f"fixed['coupling'] must be > 0 for the {kind} kind ({why}), got {fixed['coupling']}")
    return fixed


LOWER_BOUNDS = {"alpha": 0.0}
"""The fitted parameters' domain: a data term that rewards disagreeing with the data is no energy of the
model (the coupling needs no bound: the pixels' conditionals are not finite without it)."""


def _bounded_step(point: np.ndarray, grad: np.ndarray, hess: np.ndarray, bounded: list[int],
                  lows: list[float]) -> np.ndarray:
    """The projected Newton step: the bounded parameters that sit on their bound with a gradient that
    points out of the domain are held there (the binding set), the others take the Newton step of the
    problem reduced to them."""
    held = [k for k in bounded if point[k] <= lows[k] and grad[k] > 0]
    if not held:
        return -_solve(hess, grad)
    moving = [k for k in range(point.size) if k not in held]
    step = np.zeros_like(point)
    if moving:
        step[moving] = -_solve(hess[np.ix_(moving, moving)], grad[moving])
    return step


def _solve(hess: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """H^-1 g, by least squares where H is singular (a parameter no site informs)."""
    try:
        return np.linalg.solve(hess, grad)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(hess, grad, rcond=None)[0]

