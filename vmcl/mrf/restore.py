"""Restore a cue as piecewise smooth or piecewise constant while finding its discontinuities.

Seed sections "The integration stage and MRF" ("detect discontinuities in each cue, for instance depth,
simultaneously with the approximation of the depth data"), "MRF models", "Organization of integration"
(coupling to brightness edges, equation (12)) and "Algorithms: Deterministic and stochastic". The energy
is :mod:`vmcl.mrf.energy`'s; the solvers are those :data:`vmcl.mrf.SOLVERS` registers by name
(:mod:`vmcl.mrf.sampler`: annealing, MPM; :mod:`vmcl.mrf.meanfield`; :mod:`vmcl.mrf.icm`).

References
----------
S. Geman and D. Geman, IEEE PAMI 6(6):721-741, 1984.
J. Marroquin, S. Mitter and T. Poggio, J. Amer. Statist. Assoc. 82(397):76-89, 1987.
D. Geiger and F. Girosi, IEEE PAMI 13(5):401-412, 1991.
J. Besag, J. Roy. Statist. Soc. B 48(3):259-302, 1986.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vmcl.cm.core import ArrayLike, check_choice, check_int, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.mrf.energy import KINDS, EnergyModel, host_field
from vmcl.mrf.inputs import lattice_of
from vmcl.mrf.lattice import Lattice
from vmcl.mrf.solvers import SOLVERS

__all__ = ["NothingToRestore", "Restoration", "boundary_map", "restore"]


class NothingToRestore(InputValueError):
    """The data hold no value with a positive confidence, so there is nothing to restore.

    The one refusal of :func:`restore` that a good run can meet (an early module that found no match,
    no flow, no valid hue); callers that then leave the cue out catch it by this type.
    """


@dataclass
class Restoration:
    """The result of :func:`restore`.

    Attributes
    ----------
    field : array of the data's shape, float32
        The restored field.
    line_h : (H, W - 1) array
        Line sites between (y, x) and (y, x + 1) (bool on the host, uint8 0/1 on the device).
    line_v : (H - 1, W) array
        Line sites between (y, x) and (y + 1, x).
    energy : float
        U(field, lines) of the returned configuration.
    sweeps : int
        Sweeps run (every site once per sweep).
    """

    field: ArrayLike
    line_h: ArrayLike
    line_v: ArrayLike
    energy: float
    sweeps: int

    @classmethod
    def read(cls, lattice: Lattice, sweeps: int, host: bool) -> Restoration:
        """The lattice's state after ``sweeps`` sweeps: NumPy arrays (lines as bool) when the data came
        from the host, the device arrays otherwise."""
        total = lattice.energy()
        line_h, line_v = lattice.lines()
        if host:
            return cls(lattice.f.get(), line_h.get().astype(bool), line_v.get().astype(bool), total, sweeps)
        return cls(lattice.f, line_h, line_v, total, sweeps)


def restore(data: ArrayLike, *, confidence: ArrayLike | None = None, edges: ArrayLike | None = None,
            kind: str = "smooth", method: str = "meanfield", model: EnergyModel | None = None,
            schedule: Any = None, seed: int = 0, start: ArrayLike | None = None,
            machine: Machine | None = None) -> Restoration:
    """Restore ``data`` under the line-process MRF prior and find its discontinuities.

    Parameters
    ----------
    data : ndarray or pyopencl.array.Array, (H, W) or (H, W, C) with C in 1..4
        The cue: depth, disparity, hue, texture density (scalar) or flow (C = 2, one line process for
        all components). NaN where there is no value; infinities are refused. Host arrays of any real
        dtype are computed in float32 (values beyond its range are refused); device arrays must be
        float32. H, W >= 2.
    confidence : (H, W) array, optional
        gamma_i >= 0 and finite, the weight of each datum (0 where there is none, e.g. sparse stereo
        matches); ``model.alpha * gamma_i`` must stay within float32's range. Default 1 wherever the
        data is finite. Device arrays: float32, checked on the device as host arrays are.
    edges : (H, W) array, optional
        Brightness edges (e.g. Canny), non-zero at edge pixels; they lower the cost of a line between
        two pixels when either is an edge pixel (``model.edge_gain``), and with ``model.require_edge``
        lines far from every edge are forbidden. Device arrays: uint8.
    kind : {"smooth", "constant"}
        Piecewise smooth (quadratic membrane) or piecewise constant (Potts over ``model.levels``;
        scalar data only).
    method : str
        A solver of :data:`vmcl.mrf.SOLVERS`: "anneal" (simulated annealing, MAP), "mpm" (Marroquin's
        MPM estimator: posterior mean of f, marginal modes of l), "meanfield" (Geiger-Girosi mean field
        with continuation in temperature) or "icm" (ICM from the data). The default is mean field: it
        reached lower energies than annealing on the rendered disparity maps the presets were measured on
        (:mod:`vmcl.mrf.presets`), in a fraction of the sweeps, and on data with many missing values a
        short annealing schedule can freeze lines around pixels that no datum pulls back.
    model : EnergyModel, optional
        The energy; default ``EnergyModel()``. alpha must be > 0.
    schedule : optional
        The method's schedule, an instance of ``SOLVERS[method].schedule`` (:class:`AnnealSchedule`,
        :class:`MpmSchedule`, :class:`MeanFieldSchedule`, :class:`IcmSchedule`); default that class's
        defaults. :func:`vmcl.mrf.preset` gives measured models and schedules per cue:
        ``s = preset("stereo"); restore(..., model=s.model, schedule=s.schedule(method))``.
    seed : int
        0 <= seed < 2**64, keys the random numbers of "anneal" and "mpm" (ignored by the deterministic
        methods). The same seed gives the same bits at any local size.
    start : array of the data's shape, optional
        A warm start: the field begins here wherever all its components are finite (NaN elsewhere: there
        it begins at the filled data; infinities are refused, as in the data), e.g. the previous frame's
        restoration carried along the flow (:mod:`vmcl.temporal`), with a schedule that starts cold
        enough to keep it. It does not move the constant kind's levels, which span the data's values.
        Device arrays: float32.
    machine : vmcl.Machine, optional

    Returns
    -------
    Restoration
        NumPy fields for NumPy data, device arrays for device data.

    Raises
    ------
    NothingToRestore
        No datum has a positive confidence (an InputValueError, caught by type where a cue may be empty).
    InputValueError
        Among others: the lattice and the solver's buffers do not fit the device's memory (checked with
        :meth:`vmcl.Machine.require_memory` before any is allocated).

    Notes
    -----
    The start is the data with its gaps filled (a jump fill of neighbour means), or ``start`` where it
    holds values, and no lines; the constant kind starts from the nearest levels. The sweeps are enqueued back to back and read back once.

    Examples
    --------
    >>> import numpy as np
    >>> step = np.where(np.arange(16) < 8, 0.0, 4.0) * np.ones((16, 1))
    >>> noisy = step + np.random.default_rng(0).normal(0, 0.3, step.shape)
    >>> r = restore(noisy, method="icm")
    >>> int(r.line_h[:, 7].sum()), int(r.line_h.sum() + r.line_v.sum())
    (16, 16)

    References
    ----------
    S. Geman and D. Geman, "Stochastic relaxation, Gibbs distributions, and the Bayesian restoration
    of images", IEEE PAMI 6(6):721-741, 1984.
    J. Marroquin, S. Mitter and T. Poggio, "Probabilistic solution of ill-posed problems in
    computational vision", J. Amer. Statist. Assoc. 82(397):76-89, 1987.
    D. Geiger and F. Girosi, "Parallel and deterministic algorithms from MRFs: surface reconstruction",
    IEEE PAMI 13(5):401-412, 1991.
    J. Besag, "On the statistical analysis of dirty pictures", J. Roy. Statist. Soc. B 48:259-302, 1986.
    """
    machine = machine_for(machine)
    model = EnergyModel() if model is None else model
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel or None, got {type(model).__name__}")
    check_choice(kind, "kind", KINDS)
    solver = SOLVERS[check_choice(method, "method", SOLVERS)]
    schedule = solver.schedule() if schedule is None else schedule
    if not isinstance(schedule, solver.schedule):
        raise InputTypeError(f"schedule must be a vmcl.mrf.{solver.schedule.__name__} (method {method!r}) or None, "
                             f"got {type(schedule).__name__}")
    check_int(seed, "seed", minimum=0, maximum=2**64 - 1)
    model.check_anchored("model.alpha")
    lattice, host = lattice_of(data, confidence, edges, start, kind, model, machine,
                               f"mrf.restore (method {method!r})", solver.buffers)
    if not lattice.strongest > 0:
        raise NothingToRestore("data has no value with a positive confidence: nothing to restore")
    return Restoration.read(lattice, solver.solve(lattice, schedule, int(seed)), host)


def boundary_map(line_h: np.ndarray, line_v: np.ndarray) -> np.ndarray:
    """Pixels next to a line: (y, x) is marked when the site to its right or below it is on.

    Parameters
    ----------
    line_h, line_v : (H, W - 1) and (H - 1, W) arrays (NumPy or device), non-zero where a line is on

    Returns
    -------
    (H, W) bool array
        The left/upper pixel of each line site, the convention of vmcl.scenes' labels for non-depth
        discontinuities; compare within a tolerance of 1 px with :func:`vmcl.metrics.detection_scores`.
    """
    line_h = host_field(line_h, "line_h", ndims=(2,), empty=True) != 0
    line_v = host_field(line_v, "line_v", ndims=(2,), empty=True) != 0
    height, width = line_h.shape[0], line_v.shape[1]
    if line_h.shape != (height, width - 1) or line_v.shape != (height - 1, width):
        raise InputValueError(f"line_h must have shape (H, W - 1) and line_v (H - 1, W), got {line_h.shape} and "
                              f"{line_v.shape}")
    out = np.zeros((height, width), bool)
    out[:, :-1] |= line_h
    out[:-1, :] |= line_v
    return out
