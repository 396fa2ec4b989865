"""Everything a restoration is told: the energy model and one schedule per registered solver.

:class:`Settings` is what :mod:`vmcl.mrf.presets` measures per cue and what a user's flat overrides (a
Config's ``[mrf.<cue>]`` table) change, through :meth:`Settings.override`. :func:`vmcl.mrf.restore`
takes its two halves: ``model=settings.model, schedule=settings.schedule(method)``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from vmcl.cm.core import check_choice
from vmcl.errors import InputTypeError, InputValueError
from vmcl.mrf.energy import EnergyModel, LinePrior
from vmcl.mrf.solvers import SOLVERS

__all__ = ["Settings"]


@dataclass(frozen=True)
class Settings:
    """The energy model and every registered solver's schedule.

    Parameters
    ----------
    model : EnergyModel
        The energy U(f, l).
    schedules : mapping of str to schedule, optional
        Method name (a key of :data:`vmcl.mrf.SOLVERS`) -> that solver's schedule (e.g.
        ``{"meanfield": MeanFieldSchedule(mf_steps=6)}``). A solver left out gets its schedule class's
        defaults, so ``schedules`` always holds one schedule per registered solver.

    Examples
    --------
    >>> settings = Settings().override({"beta": 3.0, "mf_steps": 6})
    >>> settings.model.beta, settings.schedule("meanfield").mf_steps
    (3.0, 6)
    """

    model: EnergyModel = field(default_factory=EnergyModel)
    schedules: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.model, EnergyModel):
            raise InputTypeError(f"Settings.model must be a vmcl.mrf.EnergyModel, got {type(self.model).__name__}")
        if not isinstance(self.schedules, Mapping):
            raise InputTypeError(f"Settings.schedules must be a mapping of method names to schedules, got "
                                 f"{type(self.schedules).__name__}")
        for method, schedule in self.schedules.items():
            check_choice(method, "a key of Settings.schedules", SOLVERS)
            wanted = SOLVERS[method].schedule
            if not isinstance(schedule, wanted):
                raise InputTypeError(f"Settings.schedules[{method!r}] must be a vmcl.mrf.{wanted.__name__}, got "
                                     f"{type(schedule).__name__}")
        # A plain dict in registry order, so that the repr (what a Config prints) lists every solver.
        complete = {method: self.schedules.get(method, solver.schedule()) for method, solver in SOLVERS.items()}
        object.__setattr__(self, "schedules", complete)

    def schedule(self, method: str) -> Any:
        """The schedule of ``method``, one of :data:`vmcl.mrf.SOLVERS`."""
        check_choice(method, "method", SOLVERS)
        # A solver registered after these settings were made runs on its schedule's defaults.
        return self.schedules[method] if method in self.schedules else SOLVERS[method].schedule()

    @staticmethod
    def override_keys() -> tuple[str, ...]:
        """The keys :meth:`override` takes: every field of the model and of every schedule, sorted."""
        owners = (EnergyModel, *(solver.schedule for solver in SOLVERS.values()))
        return tuple(sorted({item.name for owner in owners for item in dataclasses.fields(owner)}))

    def override(self, overrides: Mapping[str, Any], *, prefix: str | None = None) -> Settings:
        """These settings with some fields replaced, by their flat names; ``self`` is unchanged.

        Parameters
        ----------
        overrides : mapping of str to value
            Field name -> new value. A name is any field of :class:`EnergyModel` (alpha, beta, prior
            (a :class:`LinePrior`, or a mapping of some of its entries, the others its defaults), kappa, levels, edge_gain, require_edge, edge_radius) or of any registered schedule (t0,
            t_factor, sweeps, quench; mpm_temperature, burn_in, samples; mf_t0, mf_factor, mf_steps,
            mf_iterations, quench; icm_sweeps): :meth:`override_keys`. A name that several schedules
            share sets it in each: ``quench`` is both annealing's and mean field's.
        prefix : str, optional
            How the caller's user names these keys, e.g. ``"mrf.stereo"`` for a Config's
            ``[mrf.stereo]`` table: refusals then name ``mrf.stereo.<key>``. Without it they name
            ``EnergyModel.<key>``, ``AnnealSchedule.<key>`` ...

        Returns
        -------
        Settings

        Raises
        ------
        InputValueError
            An unknown key (named, with the known ones listed), or a value out of range.
        InputTypeError
            ``overrides`` not a mapping, a key not a string, or a value of the wrong type.
        """
        where = "overrides" if prefix is None else prefix
        if not isinstance(overrides, Mapping):
            raise InputTypeError(f"{where} must be a mapping of keys to values, got {type(overrides).__name__}")
        known = self.override_keys()
        for key in overrides:
            if not isinstance(key, str):
                raise InputTypeError(f"{where} must have str keys, got {key!r}")
            if key not in known:
                label = key if prefix is None else f"{prefix}.{key}"
                raise InputValueError(f"unknown key {label}; the keys are {', '.join(known)}")
        model = self._replaced(self.model, overrides, prefix)
        schedules = {method: self._replaced(self.schedule(method), overrides, prefix) for method in SOLVERS}
        return Settings(model, schedules)

    @staticmethod
    def _prior(table: Mapping[str, Any], label: str) -> LinePrior:
        """A line prior given as a table of its entries (a TOML ``[mrf.<cue>.prior]`` table); the entries
        left out keep :class:`LinePrior`'s defaults."""
        known = [item.name for item in dataclasses.fields(LinePrior)]
        for key in table:
            if key not in known:
                raise InputValueError(f"unknown key {label}.{key}; the keys are {', '.join(known)}")
            LinePrior.CHECKS[key](table[key], f"{label}.{key}")
        return LinePrior(**table)

    @staticmethod
    def _replaced(settings: Any, overrides: Mapping[str, Any], prefix: str | None) -> Any:
        """``settings`` (the model or a schedule) with the overrides of its own fields, checked by the
        label the user knows before the dataclass checks them again as ``Class.field``."""
        own = {item.name: overrides[item.name] for item in dataclasses.fields(settings) if item.name in overrides}
        if isinstance(own.get("prior"), Mapping):
            own["prior"] = Settings._prior(own["prior"], "prior" if prefix is None else f"{prefix}.prior")
        if prefix is not None:
            # A schedule class without CHECKS (vmcl.mrf.solvers) checks its fields itself, if at all.
            checks = getattr(type(settings), "CHECKS", {})
            for name, value in own.items():
                if name in checks:
                    checks[name](value, f"{prefix}.{name}")
        return dataclasses.replace(settings, **own) if own else settings
