"""The motion cue: optical flow from the next frame, restored piecewise smooth.

Seed section "Motion": patchwise correlation over a displacement range (:func:`vmcl.early.motion.flow`);
the motion MRF restores the flow coupled to the brightness edges, each estimate weighed by its match
score (:func:`vmcl.mrf.score_confidence`).
"""

from __future__ import annotations

import numpy as np

from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import motion
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.mrf import score_confidence
from vmcl.pictures import flow_image

__all__ = ["MotionCue"]


class MotionCue(CueModule):
    """Flow from the left view at t and t + 1 (:class:`vmcl.pipeline.MotionConfig`)."""

    name = "motion"
    needs = frozenset({"next"})
    kind = "smooth"
    label = Label.DEPTH
    fields = ("raw_flow",)
    restored_as = "flow"

    def measure(self, run: RunInputs) -> Measurement:
        mc = run.config.motion
        found = motion.flow(run.left, run.needed("next"), delta=mc.delta, patch=mc.patch, levels=mc.levels,
                            features=mc.features, machine=run.machine)
        confidence = (on_device(score_confidence(found.score, floor=mc.confidence_floor, machine=run.machine))
                      if mc.weigh_by_score else None)
        flow = on_device(found.flow)  # device input, device output
        return Measurement(flow, confidence, run.brightness, fields={"raw_flow": flow})

    def pictures(self, result) -> dict[str, tuple[np.ndarray, str]]:
        if result.flow is None:
            return {}
        return {"flow": (flow_image(result.flow),
                         "Optical flow (the motion MRF's restoration), Middlebury colour wheel; key top left")}
