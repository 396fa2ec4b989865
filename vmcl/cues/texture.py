"""The texture cue: texton density, restored piecewise constant near its own texture edges.

Seed section "Texture": the density of blob textons (:func:`vmcl.early.texture.texture_edges`). Like
colour, the texture MRF is coupled to its own module's candidates with lines allowed only near them:
inside a texture, brightness edges are everywhere.
"""

from __future__ import annotations

import numpy as np

from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import texture
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.pictures import field_image

__all__ = ["TextureCue"]


class TextureCue(CueModule):
    """Texton density of the left view (:class:`vmcl.pipeline.TextureConfig`)."""

    name = "texture"
    kind = "constant"
    candidates_only = True
    label = Label.TEXTURE
    fields = ("density", "texture_edges")

    def measure(self, run: RunInputs) -> Measurement:
        t = run.config.texture
        found = texture.texture_edges(run.left, fine_sigma=t.fine_sigma, coarse_sigma=t.coarse_sigma,
                                      threshold=t.threshold, radius=t.radius, noise_factor=t.noise_factor,
                                      machine=run.machine)
        density, edges = on_device(found.density), on_device(found.edges)  # device input, device output
        return Measurement(density, None, edges, fields={"density": density, "texture_edges": edges})

    def pictures(self, result) -> dict[str, tuple[np.ndarray, str]]:
        if result.density is None:
            return {}
        return {"texture": (field_image(result.restored.get("texture", result.density)),
                            "Texton density, restored as piecewise constant")}
