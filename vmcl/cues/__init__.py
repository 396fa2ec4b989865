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
"""

from __future__ import annotations

import dataclasses

from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.cues.colour import ColourCue
from vmcl.cues.motion import MotionCue
from vmcl.cues.stereo import StereoCue
from vmcl.cues.texture import TextureCue
from vmcl.errors import InputTypeError, InputValueError
from vmcl.labels import CUES, add_cue, remove_cue
from vmcl.result import Result

_REGISTRY: dict[str, CueModule] = {}

INPUTS = frozenset({"right", "next", "rgb"})
"""What a cue may need beyond the left image."""

RESERVED = frozenset({"upload", "edges", "feedback", "integrate", "download", "mrf", "labels"})
"""Names no cue may take: the run's own stages and the Config sections that are not a cue's."""


def register(cue: CueModule) -> None:
    """Add a cue to the machine (after the ones registered before it).

    Its declarations are checked here, not mid-run: a name no other cue has, needs among
    :data:`INPUTS`, an MRF kind, and Result fields that :class:`vmcl.result.Result` has.
    """

    if not isinstance(cue, CueModule):
        raise InputTypeError(f"cue must be a vmcl.cues.CueModule, got {type(cue).__name__}")
    if cue.name in _REGISTRY:
        raise InputValueError(f"a cue named {cue.name!r} is already registered")
    if cue.name in RESERVED:
        raise InputValueError(f"a cue cannot be named {cue.name!r}: the run has a stage or Config section of "
                              f"that name ({', '.join(sorted(RESERVED))})")
    if not cue.needs <= INPUTS:
        raise InputValueError(f"cue {cue.name!r} needs {sorted(cue.needs - INPUTS)}, which no run gives; "
                              f"needs are among {sorted(INPUTS)}")
    if cue.kind not in ("smooth", "constant"):
        raise InputValueError(f"cue {cue.name!r} has kind {cue.kind!r}; kinds are 'smooth' and 'constant'")
    known = {f.name for f in dataclasses.fields(Result)}
    unknown = [name for name in (*cue.fields, *([cue.restored_as] if cue.restored_as else [])) if name not in known]
    if unknown:
        raise InputValueError(f"cue {cue.name!r} declares Result fields {unknown} that Result does not have")
    if cue.name not in CUES:
        add_cue(cue.name, cue.label)
    _REGISTRY[cue.name] = cue


def unregister(name: str) -> None:
    """Remove the cue registered last under ``name`` (a cue added at run time; the built-ins stay)."""
    if name in CUES:
        raise InputValueError(f"{name!r} is a built-in cue")
    if name not in _REGISTRY:
        raise InputValueError(f"no cue named {name!r} is registered")
    remove_cue(name)
    del _REGISTRY[name]


def registered() -> tuple[CueModule, ...]:
    """The registered cues, in the order the pipeline runs them."""
    return tuple(_REGISTRY.values())


for _builtin in (StereoCue(), MotionCue(), ColourCue(), TextureCue()):
    _REGISTRY[_builtin.name] = _builtin

__all__ = ["INPUTS", "RESERVED", "CueModule", "Measurement", "RunInputs", "register", "registered", "unregister"]
