"""The motion cue: optical flow from the next frame, restored piecewise smooth.

Seed section "Motion": patchwise correlation over a displacement range (:func:`vmcl.early.motion.flow`),
its weighted median at brightness edges (:func:`vmcl.early.motion_refine.refine_flow`), and the motion MRF
restores the flow coupled to the brightness edges, each estimate weighed by its match
score (:func:`vmcl.mrf.score_confidence`). Between the two, Lucas-Kanade steps
(:func:`vmcl.early.lucas_kanade.lucas_kanade`) carry the flow below the discrete search's precision, and a
variational refinement (:func:`vmcl.early.variational.variational_refine`) lets each pixel's flow answer to
its own brightness and its neighbours' flow at once.
"""

from __future__ import annotations

import numpy as np

from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import motion
from vmcl.early.lucas_kanade import lucas_kanade
from vmcl.early.motion_refine import refine_flow
from vmcl.early.sign_correlation import arcsine_law
from vmcl.early.variational import variational_refine
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.mrf import score_confidence
from vmcl.pictures import flow_image

__all__ = ["FOUND_SHARE", "LIMIT_SHARE", "MotionCue"]

LIMIT_SHARE = 0.005
"""The share of the coarsest level's estimates at the edge of its range from which the run notes it."""
FOUND_SHARE = 0.2
"""The share of the coarsest level's pixels with an estimate below which the run notes that the motion MRF
restores the flow from little data."""


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
        levels = mc.levels
        if levels is None:
            levels = motion.pyramid_levels(tuple(run.left.shape), patch=mc.patch, delta=mc.delta)
        found = motion.flow(run.left, run.needed("next"), delta=mc.delta, patch=mc.patch, levels=levels,
                            features=mc.features,
                            prediction=run.motion_prediction if run.config.time.predict_search else None,
                            machine=run.machine)
        confidence = (on_device(score_confidence(found.score, floor=self.floor(mc.confidence_floor, mc.features),
                                                 machine=run.machine))
                      if mc.weigh_by_score else None)
        flow = on_device(found.flow)  # device input, device output
        measured = (on_device(refine_flow(flow, run.left, radius=mc.refine_radius, sigma_colour=mc.refine_colour,
                                          stride=mc.refine_stride, machine=run.machine))
                    if mc.refine else flow)
        if mc.lucas_kanade_iterations:
            measured = on_device(lucas_kanade(measured, run.left, run.needed("next"), window=mc.lucas_kanade_window,
                                              iterations=mc.lucas_kanade_iterations,
                                              highpass=mc.lucas_kanade_highpass, machine=run.machine))
        if mc.variational_iterations:
            pull = run.config.time.flow_prior if run.motion_prediction is not None else 0.0
            measured = on_device(variational_refine(measured, run.left, run.needed("next"),
                                                    alpha=mc.variational_alpha,
                                                    iterations=mc.variational_iterations,
                                                    prior=run.motion_prediction if pull else None, beta=pull,
                                                    machine=run.machine))
        return Measurement(measured, confidence, run.brightness, fields={"raw_flow": flow},
                           notes=(self.limit_note(found.limit_share, motion.reach(mc.delta, levels), levels)
                                  + self.sparse_note(found.found_share, mc.features, mc.patch)))

    @staticmethod
    def floor(correlation: float, features: str) -> float:
        """The confidence floor in the features' score units, from a floor on the correlation of the
        brightness (the squared-difference scores' units): the sign of the LoG scores the arcsine law of
        the correlation (:mod:`vmcl.early.sign_correlation`); edges' Dice scores take it as it is."""
        return float(arcsine_law(correlation)) if features == "sign_log" else correlation

    @staticmethod
    def limit_note(share: float, limit: int, levels: int) -> tuple[str, ...]:
        """A note when a noticeable share of the coarsest level's flow lies at the edge of its range: the
        motion there may be larger than the search reaches."""
        if share < LIMIT_SHARE:
            return ()
        # A next frame of another scene (a cut) also drives the winners to the range's edge: said beside the
        # advice, which would not help there.
        return ((f"motion: {share:.1%} of the coarsest level's flow lies at the edge of its range, so motion "
                f"may exceed the search's limit of {limit} px ({levels} pyramid levels): raise [motion] levels "
                "or delta; or the next frame shows another scene (a cut), and this frame's flow means nothing"),)

    @staticmethod
    def sparse_note(share: float, features: str, patch: int) -> tuple[str, ...]:
        """A note when the matcher found an estimate at few pixels: the restored flow then rests on little."""
        if share >= FOUND_SHARE:
            return ()
        return ((f"motion: the matcher found flow at only {share:.1%} of the coarsest level's pixels (features "
                 f"{features!r}, patch {patch}), so the restored flow rests on little data; a wider [motion] patch "
                 "or other features may find more"),)

    def pictures(self, result) -> dict[str, tuple[np.ndarray, str]]:
        if result.flow is None:
            return {}
        finite = np.isfinite(result.flow).all(axis=-1)
        fastest = float(np.hypot(*result.flow[finite].T).max()) if finite.any() else 0.0
        caption = ("Optical flow (the motion MRF's restoration), Middlebury colour wheel; key top left; "
                   f"full colour is its largest speed, {fastest:.2f} px per frame")
        # The picture's scale is the caption's speed: one maximum for both.
        return {"flow": (flow_image(result.flow, max_flow=fastest if fastest > 0 else None), caption)}
