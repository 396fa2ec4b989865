"""What a cue declares to the machine, and what the machine hands it.

Seed sections "The Vision Machine System" (figure 1) and "Organization of integration": each cue is an
early module whose measurements a line-process MRF restores, coupled to edges; the integration stage
reads its line process. A :class:`CueModule` says everything the run needs to know about one cue: which
inputs it needs, how its module is called, what its MRF restores and is coupled to, which Result
fields it fills, whether it refines itself after integration (stereo's feedback), its rule label and
its pictures in the report. :mod:`vmcl.pipeline` loops over the registered cues (:mod:`vmcl.cues`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pyopencl.array as cl_array

from vmcl.labels import Label
from vmcl.machine import Machine
from vmcl.mrf import Settings

__all__ = ["CueModule", "Measurement", "RunInputs"]


@dataclass(frozen=True)
class RunInputs:
    """What every cue of one run may read: the device images, the brightness edges and the Config.

    Attributes
    ----------
    machine : vmcl.Machine
    config : vmcl.pipeline.Config
    left : device float32 (H, W) or (H, W, 3)
        The left view at t, in [0, 1].
    right, next : device arrays like ``left``, or None
        The right view at t, and the left view at t + 1.
    brightness : device uint8 (H, W)
        Canny's brightness edges (0/1), the coupling of the piecewise smooth cues.
    motion_prediction : device float32 (H, W, 2), or None
        In a stream, the previous frame's flow carried to this one (NaN where time is broken), which
        predicts where the motion search looks (:attr:`vmcl.pipeline.TimeConfig.predict_search`) and
        pulls the variational refinement (:attr:`vmcl.pipeline.TimeConfig.flow_prior`).
    new_view : bool
        False in a stream whose frame carries the previous one's (one rig, the same view): what belongs to
        the cameras rather than the scene (the stereo rows' alignment) was measured on an earlier frame. A
        stream measures it on its first frame, after a cut, and every
        :data:`vmcl.pipeline.VIEW_RECHECK` frames.
    """

    machine: Machine
    config: Any
    left: cl_array.Array
    right: cl_array.Array | None
    next: cl_array.Array | None
    brightness: cl_array.Array
    motion_prediction: cl_array.Array | None = None
    new_view: bool = True

    @property
    def width(self) -> int:
        return int(self.left.shape[1])

    def needed(self, name: Literal["right", "next"]) -> cl_array.Array:
        """The right view or the next frame, which a cue reads only when it lists ``name`` in its needs.

        The pipeline runs a cue only when its needs are given, so for such a cue the image is there; a
        cue that reads an input it did not declare fails here, by name, rather than in its module.
        """
        array = self.right if name == "right" else self.next
        if array is None:
            raise RuntimeError(f"this run has no {name!r} image: a cue that reads it must list it in its needs")
        return array


@dataclass
class Measurement:
    """What a cue's early module gave, on the device.

    Attributes
    ----------
    data : device array
        The MRF's data: (H, W) or (H, W, 2) float32, NaN where there is no measurement.
    confidence : device float32 (H, W) or None
        The data term's weight at each pixel (None: 1 wherever there is data).
    coupling : device uint8 (H, W)
        The edges the cue's line sites are coupled to (equation (12)).
    fields : dict of str to device array
        Fields for the Result, by :class:`vmcl.result.Result` attribute name (the cue declares them in
        :attr:`CueModule.fields`).
    state : any
        What the cue keeps for :meth:`CueModule.refine` (e.g. stereo's intensity matches).
    notes : tuple of str
        Lines for ``Result.notes``: what the module decided from the data that the user should know
        (e.g. the disparity range stereo found).
    """

    data: cl_array.Array
    confidence: cl_array.Array | None
    coupling: cl_array.Array
    fields: dict[str, cl_array.Array] = field(default_factory=dict)
    state: Any = None
    notes: tuple[str, ...] = ()


class CueModule:
    """One cue of the machine. Subclass it, set the class attributes, implement :meth:`measure`, and
    register an instance with :func:`vmcl.cues.register`.

    A cue added at run time runs whenever it is registered and its needs are given: Config sections (and
    their ``enabled`` switch) and ``[mrf.<cue>]`` overrides exist for the built-in cues
    (:data:`vmcl.labels.CUES`) only.

    Attributes
    ----------
    name : str
        The cue's one name: its key in ``Result.restored`` and ``Result.lines``, its stage names (``name``,
        ``"mrf <name>"``), and for a built-in cue its Config section, MRF preset and ``[mrf.<name>]``
        overrides. A Python identifier that no stage or Config attribute has (:data:`vmcl.cues.RESERVED`).
    needs : frozenset of {"right", "next", "rgb"}
        The inputs without which the cue does not run.
    kind : {"smooth", "constant"}
        What its MRF restores (:func:`vmcl.mrf.restore`).
    candidates_only : bool
        Its lines are allowed only near its coupling's edges (the cue is coupled to its own module's
        candidates rather than to the brightness edges).
    label : vmcl.labels.Label
        The physical cause its lines stand for in the rule labelling.
    fields : tuple of str
        The Result attributes its measurement (and refinement) fill.
    restored_as : str or None
        The Result attribute that holds its restored field besides ``Result.restored[name]``. Neither it
        nor ``fields`` may name an attribute the machine fills itself (:data:`vmcl.cues.MACHINE_FIELDS`) or
        another registered cue declares.
    settings : vmcl.mrf.Settings or None
        Its MRF's energy model and schedules (``model.alpha`` > 0). None: :func:`vmcl.mrf.preset`'s for a
        built-in cue, else ``Settings()``. The Config's ``[mrf] schedule`` applies on top, and for a
        built-in cue its ``[mrf.<cue>]`` overrides.
    """

    name: str = ""
    needs: frozenset[str] = frozenset()
    kind: str = "smooth"
    candidates_only: bool = False
    label: Label = Label.NONE
    fields: tuple[str, ...] = ()
    restored_as: str | None = None
    settings: Settings | None = None

    def result_attributes(self) -> list[str]:
        """The Result attributes the cue fills: its ``fields``, then its ``restored_as``."""
        return [*self.fields, *([self.restored_as] if self.restored_as is not None else [])]

    def enabled(self, config: Any) -> bool:
        """Whether the Config switches the cue on: a built-in cue's section's ``enabled``; a cue added at
        run time has no section (nothing of its name with an ``enabled`` field) and is always on."""
        return bool(getattr(getattr(config, self.name, None), "enabled", True))

    def measure(self, run: RunInputs) -> Measurement:
        """Run the cue's early module on this run's images."""
        raise NotImplementedError

    def refine_stage(self, config: Any) -> str | None:
        """The name of the stage in which :meth:`refine` runs, or None when the cue does not refine; no
        other stage's name (:func:`vmcl.cues.register` checks the default Config's, and
        :class:`vmcl.pipeline.VisionMachine` the one it is given)."""
        return None

    def refine(self, run: RunInputs, measurement: Measurement,
               lines: tuple[cl_array.Array, cl_array.Array]) -> Measurement:
        """Measure again knowing the first restoration's lines (the seed's feedback from integration)."""
        raise NotImplementedError

    def pictures(self, result: Any) -> dict[str, tuple[np.ndarray, str]]:
        """The report's pictures of this cue in a Result: stem -> (uint8 RGB image, caption)."""
        return {}
