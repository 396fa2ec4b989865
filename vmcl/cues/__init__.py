"""The cues the machine integrates: one module each, and the registry the pipeline loops over.

Seed section "Organization of integration": stereo, motion, colour and texture are each measured by an
early module, restored by a line-process MRF coupled to edges, and integrated through their line
processes. Each cue is a :class:`CueModule` (:mod:`vmcl.cues.base`) that declares what it needs, how it
is measured, what its MRF restores and is coupled to, the Result fields it fills and its pictures;
:class:`vmcl.pipeline.VisionMachine` runs the registered cues in registration order.

Adding a cue: a module with a :class:`CueModule` subclass (and the kernel of its early module), an MRF
preset (:mod:`vmcl.mrf.presets`) or the default settings, and :func:`register`. The built-in cues are
:data:`vmcl.labels.CUES`; a cue added at run time gets the next free support bit
(:func:`vmcl.labels.add_cue`) and joins the rule labelling; the linear classifier's inputs are fitted to
the built-in cues only (:mod:`vmcl.labelling`).

A cue added at run time runs whenever it is registered (and its needs are given): Config sections (with
their ``enabled`` switch) and ``[mrf.<cue>]`` overrides exist for the built-in cues only. Its MRF runs on
its own :attr:`CueModule.settings` with the Config's ``[mrf]`` method and schedule.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from vmcl.cm.core import check_bool
from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.cues.colour import ColourCue
from vmcl.cues.motion import MotionCue
from vmcl.cues.stereo import StereoCue
from vmcl.cues.texture import TextureCue
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.labels import CUES, add_cue, remove_cue
from vmcl.mrf import Settings
from vmcl.result import Result

_REGISTRY: dict[str, CueModule] = {}

INPUTS = frozenset({"right", "next", "rgb"})
"""What a cue may need beyond the left image."""

RESERVED = frozenset({"upload", "time", "edges", "grouping", "boundaries", "feedback", "integrate", "download",
                      "recognition", "mrf", "labels"})
"""Names no cue may take: the run's own stages (``mrf`` prefixes each cue's restoration) and the Config
sections that are not a cue's. :func:`register` also refuses every field and attribute name of
:class:`vmcl.pipeline.Config` (its sections, ``to_dict``, ``from_dict``, ``from_toml`` ...), read from the
class when it is called."""

MACHINE_FIELDS = frozenset({"image", "edges", "grouping", "recognition", "support", "labels", "boundary_strength",
                            "config", "restored", "lines", "stages", "kernels", "notes"})
"""The :class:`vmcl.result.Result` attributes the run fills itself, which no cue may declare; the others
are the cues' (:attr:`CueModule.fields`, :attr:`CueModule.restored_as`)."""


def _reserved() -> frozenset[str]:
    """:data:`RESERVED` and every name a :class:`vmcl.pipeline.Config` has: a cue of such a name would be
    read as its section (``enabled``) or collide with its attributes."""
    from vmcl.pipeline import Config  # here, not at the top: vmcl.pipeline imports this module

    return RESERVED | {item.name for item in dataclasses.fields(Config)} | {
        name for name in dir(Config) if not name.startswith("_")}


def register(cue: CueModule) -> None:
    """Add a cue to the machine (after the ones registered before it).

    Its declarations are checked here, not mid-run: a name no other cue, stage or Config attribute has
    (:data:`RESERVED`), needs a set among :data:`INPUTS`, an MRF kind, ``candidates_only`` a bool,
    settings a :class:`vmcl.mrf.Settings` (or None) whose ``model.alpha`` is > 0, Result fields that
    :class:`vmcl.result.Result` has and that neither the machine (:data:`MACHINE_FIELDS`) nor another
    registered cue fills, a refinement stage (:meth:`CueModule.refine_stage` of the default Config; a
    :class:`vmcl.pipeline.VisionMachine` checks its own Config's) of a name no stage has, and a rule label.
    """

    if not isinstance(cue, CueModule):
        raise InputTypeError(f"cue must be a vmcl.cues.CueModule, got {type(cue).__name__}")
    if not isinstance(cue.name, str):
        raise InputTypeError(f"a cue's name must be a str, got {type(cue.name).__name__} ({type(cue).__name__})")
    if not cue.name.isidentifier():
        raise InputValueError(f"a cue's name must be a Python identifier, got {cue.name!r} ({type(cue).__name__})")
    if cue.name in _REGISTRY:
        raise InputValueError(f"a cue named {cue.name!r} is already registered")
    reserved = _reserved()
    if cue.name in reserved:
        raise InputValueError(f"a cue cannot be named {cue.name!r}: the run has a stage or Config section or "
                              f"attribute of that name ({', '.join(sorted(reserved))})")
    if not isinstance(cue.needs, (set, frozenset)):
        raise InputTypeError(f"cue {cue.name!r}: needs must be a set or frozenset among {sorted(INPUTS)}, got "
                             f"{type(cue.needs).__name__}")
    if not cue.needs <= INPUTS:
        raise InputValueError(f"cue {cue.name!r} needs {sorted(cue.needs - INPUTS, key=repr)}, which no run "
                              f"gives; needs are among {sorted(INPUTS)}")
    if cue.kind not in ("smooth", "constant"):
        raise InputValueError(f"cue {cue.name!r} has kind {cue.kind!r}; kinds are 'smooth' and 'constant'")
    check_bool(cue.candidates_only, f"cue {cue.name!r}: candidates_only")
    if cue.settings is not None:
        if not isinstance(cue.settings, Settings):
            raise InputTypeError(f"cue {cue.name!r}: settings must be a vmcl.mrf.Settings or None, got "
                                 f"{type(cue.settings).__name__}")
        cue.settings.model.check_anchored(f"cue {cue.name!r}: settings.model.alpha")  # restore would, mid-run
    if not isinstance(cue.fields, (tuple, list)) or not all(isinstance(name, str) for name in cue.fields):
        raise InputTypeError(f"cue {cue.name!r}: fields must be a tuple of Result attribute names, got "
                             f"{cue.fields!r}")
    if cue.restored_as is not None and not isinstance(cue.restored_as, str):
        raise InputTypeError(f"cue {cue.name!r}: restored_as must be a Result attribute name or None, got "
                             f"{type(cue.restored_as).__name__}")
    filled = cue.result_attributes()
    known = {f.name for f in dataclasses.fields(Result)}
    unknown = [name for name in filled if name not in known]
    if unknown:
        raise InputValueError(f"cue {cue.name!r} declares Result fields {unknown} that Result does not have")
    owners = {name: other.name for other in _REGISTRY.values() for name in other.result_attributes()}
    for index, name in enumerate(filled):
        # Two fills of one attribute: the pipeline would pass it to Result twice (a TypeError mid-run) or
        # let the later one overwrite the earlier in silence.
        if name in MACHINE_FIELDS:
            raise InputValueError(f"cue {cue.name!r} declares the Result attribute {name!r}, which the machine "
                                  "fills itself")
        if name in owners:
            raise InputValueError(f"cue {cue.name!r} declares the Result attribute {name!r}, which the "
                                  f"{owners[name]!r} cue fills")
        if name in filled[:index]:
            raise InputValueError(f"cue {cue.name!r} declares the Result attribute {name!r} twice")
    _check_refine_stage(cue, reserved)
    if cue.name not in CUES:
        try:
            add_cue(cue.name, cue.label)
        except InputError as error:  # the label, or no support bit left: said of this cue
            raise type(error)(f"cue {cue.name!r}: {error}") from None
    _REGISTRY[cue.name] = cue


def _check_refine_stage(cue: CueModule, reserved: frozenset[str]) -> None:
    """Refuse a refinement stage that would share its name, and so its timing and progress, with another
    stage. It is asked of the default Config: the one a Config of the run's gives is not known here."""
    from vmcl.pipeline import Config  # here, not at the top: vmcl.pipeline imports this module

    config = Config()
    stage = refine_stage_of(cue, config)
    if stage is None:
        return
    names = [*_REGISTRY, cue.name]
    taken = reserved | set(names) | {f"mrf {name}" for name in names} | {
        other.refine_stage(config) for other in _REGISTRY.values()}
    if stage in taken:
        raise InputValueError(f"cue {cue.name!r}: refine_stage() is {stage!r}, the name of another stage of the run")


def refine_stage_of(cue: CueModule, config: Any) -> str | None:
    """``cue``'s refinement stage under ``config`` (:meth:`CueModule.refine_stage`), refused unless it is a
    stage name (a str) or None. Whether the name is free is the caller's to check: :func:`register` knows
    the registry, a :class:`vmcl.pipeline.VisionMachine` its own run's stages."""
    if not isinstance(cue, CueModule):
        raise InputTypeError(f"cue must be a vmcl.cues.CueModule, got {type(cue).__name__}")
    stage = cue.refine_stage(config)
    if stage is not None and not isinstance(stage, str):
        raise InputTypeError(f"cue {cue.name!r}: refine_stage() must return a stage name (str) or None, got "
                             f"{type(stage).__name__}")
    return stage


def unregister(name: str) -> None:
    """Remove the cue registered under ``name``, which must be the last one registered of the cues added at
    run time (each holds a support bit, and the bits stay packed: unregister them in the reverse order of
    registration). The built-in cues stay."""
    if not isinstance(name, str):
        raise InputTypeError(f"name must be a cue's name (str), got {type(name).__name__}")
    if name in CUES:
        raise InputValueError(f"{name!r} is a built-in cue")
    if name not in _REGISTRY:
        raise InputValueError(f"no cue named {name!r} is registered")
    last = list(_REGISTRY)[-1]
    if name != last:
        raise InputValueError(f"cue {name!r} cannot be unregistered while {last!r}, registered after it, is: "
                              "unregister the cues in the reverse order of registration")
    remove_cue(name)
    del _REGISTRY[name]


def registered() -> tuple[CueModule, ...]:
    """The registered cues, in the order the pipeline runs them."""
    return tuple(_REGISTRY.values())


for _builtin in (StereoCue(), MotionCue(), ColourCue(), TextureCue()):
    _REGISTRY[_builtin.name] = _builtin

__all__ = ["INPUTS", "MACHINE_FIELDS", "RESERVED", "CueModule", "Measurement", "RunInputs", "refine_stage_of", "register",
           "registered", "unregister"]
