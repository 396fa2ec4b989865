"""The colour cue: hue from an RGB image, restored piecewise constant near its own albedo edges.

Seed section "Color": the Hurlbert-Poggio hue H = R / (R + G) and its albedo-edge candidates
(:func:`vmcl.early.color.albedo_edges`). The colour MRF is coupled to those candidates, with lines
allowed only near them: the boundaries colour exists for are the ones brightness misses (isoluminant
colour), and the brightness coupling would license lines at every shadow and texton (on the "cues"
scene, with mean field, the hue lines coupled to brightness were far less precise than those coupled to
the candidates, most of them false).
"""

from __future__ import annotations

import numpy as np

from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import color
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.pictures import field_image

__all__ = ["ColourCue"]


class ColourCue(CueModule):
    """Hue from the left view when it is RGB (:class:`vmcl.pipeline.ColourConfig`)."""

    name = "colour"
    needs = frozenset({"rgb"})
    kind = "constant"
    candidates_only = True
    label = Label.ALBEDO
    fields = ("hue", "colour_edges")

    def measure(self, run: RunInputs) -> Measurement:
        found = color.albedo_edges(run.left, threshold=run.config.colour.threshold, machine=run.machine)
        hue, edges = on_device(found.hue), on_device(found.edges)  # device input, device output
        return Measurement(hue, None, edges, fields={"hue": hue, "colour_edges": edges})

    def pictures(self, result) -> dict[str, tuple[np.ndarray, str]]:
        if result.hue is None:
            return {}
        return {"hue": (field_image(result.restored.get("colour", result.hue)),
                        "Hue H = R / (R + G), restored as piecewise constant")}
