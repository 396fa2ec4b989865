"""The line-process energy: its model, the clique table of the line prior, and the energy on the host.

Seed sections "MRF models" and "Organization of integration", equations (10) to (12). A field f (depth,
disparity, a flow vector, hue, texture density) on the pixel lattice is restored from data g while a
line process l on the dual lattice marks where the smoothness assumption breaks:

.. math::

    U(f, l) = \\sum_i \\alpha \\gamma_i |f_i - g_i|^2
            + \\sum_{<ij>} \\rho(f_i, f_j) (1 - l_{ij})
            + \\sum_{<ij>} l_{ij} b_{ij}
            + \\beta \\sum_{v} V(l_{up}, l_{down}, l_{left}, l_{right})
            + \\beta c_{par} \\sum_{\\parallel} l l'

- data: gamma_i is the confidence of g_i (0 where there is no data, as for sparse stereo);
- smoothness over 4-neighbours: rho = |f_i - f_j|^2 for the piecewise smooth kind (equation (11), the
  weak membrane), rho = kappa [f_i != f_j] for the piecewise constant kind (a Potts prior over discrete
  levels, as in Marroquin, Mitter and Poggio 1987);
- central cliques: a line site costs b_ij = beta (line - edge_gain e_ij), where e_ij = 1 when a
  brightness edge pixel lies on either side of the site (equation (12): V(l, e) = g(e, V_C(l)) lowers
  the cost of a line at a brightness edge); with ``require_edge`` a line with no edge pixel within
  ``edge_radius`` of either side is forbidden (b = +inf);
- vertex cliques: the four line sites meeting at a corner of four pixels, with potentials by
  configuration (empty 0, end, continuation, turn, T-junction, crossing: the :class:`LinePrior` table);
- parallel cliques: two parallel line sites one pixel apart (doubled lines).

The seed notes that "the assignment of zero energy values to the non-central cliques ... is wrong": every
clique that holds a line site (its central clique, both end vertices, both parallel pairs, the bond it
breaks) enters that site's conditional, which is derived from this one energy; the tests check the
sampler's conditionals against exact enumeration of it.

Line fields follow vmcl.scenes: ``line_h`` (H, W - 1) lies between (y, x) and (y, x + 1) (a vertical
segment of boundary), ``line_v`` (H - 1, W) between (y, x) and (y + 1, x). A corner (vertex) exists for
0 <= y < H - 1, 0 <= x < W - 1; lines leaving the image pay no end cost at the border.

References
----------
S. Geman and D. Geman, "Stochastic relaxation, Gibbs distributions, and the Bayesian restoration of
images", IEEE PAMI 6(6):721-741, 1984.
J. Marroquin, S. Mitter and T. Poggio, "Probabilistic solution of ill-posed problems in computational
vision", J. Amer. Statist. Assoc. 82(397):76-89, 1987.
E. Gamble and T. Poggio, "Visual integration and detection of discontinuities: the key role of intensity
edges", MIT AI Memo 970, 1987.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import check_bool, check_choice, check_unmasked, real_host_array, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.mrf.checks import FLOAT32_MAX, check_count, check_fields, check_number, check_weight

__all__ = [
    "KINDS",
    "EnergyModel",
    "LinePrior",
    "check_levels",
    "check_prior",
    "energy",
    "host_field",
    "line_costs",
    "resolve_levels",
]

KINDS = ("smooth", "constant")


def host_field(x, name: str, *, ndims: tuple[int, ...], empty: bool = False) -> np.ndarray:
    """``x``, a NumPy or device array, as a NumPy array of real numbers with one of ``ndims`` dimensions."""
    return real_host_array(to_host(x), name, ndims=ndims, empty=empty)


@dataclass(frozen=True)
class LinePrior:
    """Clique potentials of the line process, in units of ``EnergyModel.beta``.

    Parameters
    ----------
    line : float
        Central clique: the cost of one line site (before brightness edges lower it).
    end : float
        A vertex with one line: an end. An isolated segment pays ``line + 2 end``.
    continuation : float
        A vertex with two collinear lines (straight continuation): cheap.
    turn : float
        A vertex with two perpendicular lines (a corner).
    junction : float
        A vertex with three lines (a T-junction).
    crossing : float
        A vertex with four lines.
    parallel : float
        Two parallel line sites one pixel apart (a doubled line).

    Notes
    -----
    The defaults make continuation cheap and ends, isolated segments, doubled lines and crossings
    costly, the prior the seed describes ("continuous, non-intersecting, and rarely isolated"). They are
    the values the presets were measured with (see :mod:`vmcl.mrf.presets`).
    """

    line: float = 1.0
    end: float = 0.5
    continuation: float = 0.0
    turn: float = 0.25
    junction: float = 0.75
    crossing: float = 1.5
    parallel: float = 1.0

    CHECKS: ClassVar = dict.fromkeys(("line", "end", "continuation", "turn", "junction", "crossing", "parallel"),
                                     check_number)

    def __post_init__(self) -> None:
        check_fields(self)

    def table(self) -> np.ndarray:
        """The 16 vertex potentials (units of beta), indexed by up | down << 1 | left << 2 | right << 3."""
        table = np.zeros(16, np.float64)
        for arms in range(1, 16):
            up, down, left, right = (arms >> k & 1 for k in range(4))
            count = up + down + left + right
            if count == 1:
                table[arms] = self.end
            elif count == 2:
                table[arms] = self.continuation if (up and down) or (left and right) else self.turn
            elif count == 3:
                table[arms] = self.junction
            else:
                table[arms] = self.crossing
        return table


def check_prior(value: Any, label: str) -> None:
    if not isinstance(value, LinePrior):
        raise InputTypeError(f"{label} must be a vmcl.mrf.LinePrior, got {type(value).__name__}")


def check_levels(value: Any, label: str) -> int | tuple[float, ...]:
    """The constant kind's levels: a count in 2..64, or 2..64 distinct finite values within float32's range
    (a tuple, list or 1-D array), returned as an int or a tuple of floats."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        if not 2 <= value <= 64:
            raise InputValueError(f"{label} must be a count in 2..64 or a tuple of levels, got {value}")
        return int(value)
    check_unmasked(value, label)
    levels = np.asarray(value if isinstance(value, (tuple, list, np.ndarray)) else ())
    if levels.dtype.kind not in "iuf" or levels.ndim != 1 or not 2 <= levels.size <= 64 \
            or not np.all(np.isfinite(levels)) or np.unique(levels).size != levels.size:
        raise InputValueError(f"{label} must be a count in 2..64 or 2..64 distinct finite values, got {value!r}")
    if np.max(np.abs(levels)) > FLOAT32_MAX:
        raise InputValueError(f"{label} must lie within float32's range (the device holds the levels as float32), "
                              f"got {value!r}")
    # Distinct as float64 but equal as float32 would be one level twice on the device.
    if np.unique(levels.astype(np.float32)).size != levels.size:
        raise InputValueError(f"{label} must be distinct as float32 (the device holds the levels as float32), "
                              f"got {value!r}")
    return tuple(float(level) for level in levels)


@dataclass(frozen=True)
class EnergyModel:
    """The energy U(f, l): its weights, the line prior and the coupling to brightness edges.

    What the energy is, not how a solver minimises or samples it (each solver's schedule is its own
    class, :data:`vmcl.mrf.SOLVERS`). Temperatures of the schedules are in this energy's units.

    Parameters
    ----------
    alpha : float
        Weight of the data term, >= 0 (:func:`vmcl.mrf.restore` needs > 0). With Gaussian noise of
        standard deviation sigma at T = 1 the posterior is exact for alpha = 1 / (2 sigma^2).
    beta : float
        Scale of the line prior, >= 0: a line site costs ``beta * prior.line`` and breaks a bond whose
        smoothness cost exceeds about that.
    prior : LinePrior
        The clique table.
    kappa : float
        Potts cost of two different neighbouring levels (constant kind), >= 0.
    levels : int or tuple of float
        The constant kind's levels: a count in 2..64, spread evenly over the range of the data (of its
        values with a positive confidence; where none has one, as when :func:`vmcl.mrf.sample` draws
        from the prior, of all its finite values; only where it holds none at all, of the start's), so a
        warm start never moves them; or 2..64 distinct levels (a list or 1-D array is taken as a tuple
        of floats, so the model stays hashable).
    edge_gain : float
        How much a brightness edge lowers a line site's cost, in units of beta (equation (12)).
    require_edge : bool
        Forbid lines with no brightness edge pixel within ``edge_radius`` pixels (only with edges).
    edge_radius : int
        Chebyshev radius for ``require_edge``, 0 .. 2**31 - 1. Its cost does not grow with it (the
        neighbourhood is found in two passes, along the rows and then the columns); a radius at or beyond
        the field's larger side reaches every pixel from every other, as that side itself does.

    Notes
    -----
    Every real number here reaches the device as a float32, so each must lie within float32's range, and
    so must ``beta`` times each entry of the prior and ``edge_gain`` (the line costs the device holds).
    """

    alpha: float = 1.0
    beta: float = 1.0
    prior: LinePrior = field(default_factory=LinePrior)
    kappa: float = 1.0
    levels: int | tuple[float, ...] = 32
    edge_gain: float = 0.5
    require_edge: bool = False
    edge_radius: int = 1

    CHECKS: ClassVar = {"alpha": check_weight, "beta": check_weight, "prior": check_prior, "kappa": check_weight,
                        "levels": check_levels, "edge_gain": check_number, "require_edge": check_bool,
                        "edge_radius": check_count}

    def __post_init__(self) -> None:
        check_fields(self)
        # A list or array of levels would leave the frozen model unhashable: kept as a tuple of floats.
        object.__setattr__(self, "levels", check_levels(self.levels, "EnergyModel.levels"))
        scaled = {f"prior.{item.name}": getattr(self.prior, item.name) for item in fields(self.prior)}
        for name, value in {**scaled, "edge_gain": self.edge_gain}.items():
            if abs(self.beta * value) > FLOAT32_MAX:
                raise InputValueError(f"EnergyModel.beta * EnergyModel.{name} = {self.beta * value:.3g} is beyond "
                                      "float32's range, in which the device holds the line costs")

    def check_anchored(self, label: str) -> None:
        """Refuse a model without a data term (alpha not > 0), which restoring needs; ``label`` names its
        alpha in the error."""
        if not self.alpha > 0:
            raise InputValueError(f"{label} must be > 0, got {self.alpha}: without the data term nothing anchors "
                                  "the field")

    def vertex_table(self) -> np.ndarray:
        """beta times the vertex potentials, float64 (16,)."""
        return self.beta * self.prior.table()


def resolve_levels(model: EnergyModel, low: float, high: float) -> np.ndarray:
    """The constant kind's levels as float32: the given ones, or a count spread over [low, high]."""
    if isinstance(model.levels, (int, np.integer)):
        if not high > low:
            high = low + 1.0
        return np.linspace(low, high, int(model.levels)).astype(np.float32)
    return np.asarray(model.levels, np.float32)


def line_costs(shape: tuple[int, int], edges: np.ndarray | None, model: EnergyModel) -> tuple[np.ndarray, np.ndarray]:
    """Central clique costs b of every line site: ((H, W - 1), (H - 1, W)) float64, +inf where forbidden.

    Parameters
    ----------
    shape : (int, int)
        (H, W) of the pixel lattice.
    edges : (H, W) array or None
        Brightness edge pixels (non-zero: an edge), e.g. from Canny.
    model : EnergyModel

    Returns
    -------
    (b_h, b_v)
    """
    height, width = shape
    base = model.beta * model.prior.line
    b_h = np.full((height, width - 1), base)
    b_v = np.full((height - 1, width), base)
    if edges is None:
        return b_h, b_v
    e = (edges.get() if isinstance(edges, cl_array.Array) else np.asarray(edges)) != 0
    gain = model.beta * model.edge_gain
    at_h = e[:, :-1] | e[:, 1:]
    at_v = e[:-1, :] | e[1:, :]
    b_h -= gain * at_h
    b_v -= gain * at_v
    if model.require_edge:
        near = _dilate(e, model.edge_radius)
        b_h[~(near[:, :-1] | near[:, 1:])] = np.inf
        b_v[~(near[:-1, :] | near[1:, :])] = np.inf
    return b_h, b_v


def _dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    """True within Chebyshev distance ``radius`` of a True pixel (the image does not wrap).

    The square neighbourhood is separable: within ``radius`` along the row, then along the column, each
    pass O(H W) whatever the radius (kernels/mrf.cl's near_rows and near_columns do the same)."""
    return _within(_within(mask, radius, axis=1), radius, axis=0)


def _within(mask: np.ndarray, radius: int, axis: int) -> np.ndarray:
    """True where a True lies within ``radius`` along ``axis``: the nearest one before and after each
    pixel, found by running maxima of their indices."""
    size = mask.shape[axis]
    index = np.arange(size, dtype=np.int64).reshape((-1, 1) if axis == 0 else (1, -1))
    never = np.int64(-2**62)  # before any pixel by more than any radius, and no overflow below
    before = np.maximum.accumulate(np.where(mask, index, never), axis=axis)
    flipped = np.flip(mask, axis=axis)
    after = size - 1 - np.flip(np.maximum.accumulate(np.where(flipped, index, never), axis=axis), axis=axis)
    return (index - before <= radius) | (after - index <= radius)


def energy(f: np.ndarray, line_h: np.ndarray, line_v: np.ndarray, *, data: np.ndarray,
           confidence: np.ndarray | None = None, edges: np.ndarray | None = None, kind: str = "smooth",
           model: EnergyModel | None = None) -> float:
    """U(f, l) of any configuration, in float64 on the host (the oracle of the kernels).

    Parameters
    ----------
    f : (H, W) or (H, W, C) array
        The field.
    line_h, line_v : (H, W - 1) and (H - 1, W) arrays
        The line process (non-zero: a line).
    data : array of f's shape
        The data g; NaN where there is none (weight 0).
    confidence : (H, W) array, optional
        gamma, >= 0; default 1 wherever the data is finite.
    edges : (H, W) array, optional
        Brightness edge pixels.
    kind : {"smooth", "constant"}
    model : EnergyModel, optional
        Default ``EnergyModel()``.

    Returns
    -------
    float
        +inf when a forbidden line is on.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.zeros((2, 3)); g[:, 2] = 2.0
    >>> lh = np.zeros((2, 2), bool); lv = np.zeros((1, 3), bool)
    >>> energy(g, lh, lv, data=g)  # two bonds of (2 - 0)^2, no lines
    8.0
    >>> lh[0, 1] = True  # one line site (cost 1) instead of a bond, ending at the corner (0, 1)
    >>> energy(g, lh, lv, data=g)
    5.5

    References
    ----------
    S. Geman and D. Geman, IEEE PAMI 6(6):721-741, 1984 (line processes).
    """
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    g = host_field(data, "data", ndims=(2, 3)).astype(np.float64)
    f = host_field(f, "f", ndims=(2, 3)).astype(np.float64)
    if f.shape != g.shape:
        raise InputValueError(f"f must have the data's shape (H, W) or (H, W, C), got {f.shape} and {g.shape}")
    if not np.all(np.isfinite(f)):
        raise InputValueError("f must be finite (NaN marks missing data, never a missing field value)")
    if f.ndim == 2:
        f, g = f[..., None], g[..., None]
    height, width = f.shape[:2]
    lh = host_field(line_h, "line_h", ndims=(2,), empty=True) != 0
    lv = host_field(line_v, "line_v", ndims=(2,), empty=True) != 0
    if lh.shape != (height, width - 1) or lv.shape != (height - 1, width):
        raise InputValueError(f"line_h and line_v must have shapes {(height, width - 1)} and {(height - 1, width)}, "
                              f"got {lh.shape} and {lv.shape}")
    for name, pixels in (("confidence", confidence), ("edges", edges)):
        if pixels is not None and host_field(pixels, name, ndims=(2,)).shape != (height, width):
            raise InputValueError(f"{name} must have the field's shape {(height, width)}, got {np.shape(pixels)}")
    finite = np.all(np.isfinite(g), axis=2)
    gamma = np.ones((height, width)) if confidence is None else host_field(confidence, "confidence", ndims=(2,))
    if not np.all(np.isfinite(gamma)) or np.any(gamma < 0):
        raise InputValueError("confidence must be finite and >= 0")
    gamma = gamma.astype(np.float64)
    w = model.alpha * np.where(finite, gamma, 0.0)
    total = float(np.sum(w * np.sum((f - np.where(finite[..., None], g, 0.0)) ** 2, axis=2)))
    if kind == "smooth":
        bond_h = np.sum((f[:, 1:] - f[:, :-1]) ** 2, axis=2)
        bond_v = np.sum((f[1:] - f[:-1]) ** 2, axis=2)
    else:
        bond_h = model.kappa * np.any(f[:, 1:] != f[:, :-1], axis=2)
        bond_v = model.kappa * np.any(f[1:] != f[:-1], axis=2)
    b_h, b_v = line_costs((height, width), edges, model)
    total += float(np.sum(np.where(lh, b_h, bond_h)) + np.sum(np.where(lv, b_v, bond_v)))
    arms = (lh[:-1, :].astype(int) | lh[1:, :] << 1 | lv[:, :-1] << 2 | lv[:, 1:] << 3)
    total += float(np.sum(model.vertex_table()[arms]))
    doubled = np.sum(lh[:, :-1] & lh[:, 1:]) + np.sum(lv[:-1, :] & lv[1:, :])
    total += float(model.beta * model.prior.parallel * doubled)
    return total
