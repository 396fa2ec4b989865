"""The stereo cue: depth from a rectified pair, restored piecewise smooth, refined by feedback.

Seed sections "Stereo", "Feedback from the results of integration into the matching stage". The
Drumheller-Poggio matcher (:func:`vmcl.early.stereo.match`) gives sparse disparities at edge features;
with ``backfill``, intensity matches of high correlation fill the gaps between them, weighed less
(:func:`vmcl.mrf.backfill`). The stereo MRF restores the disparity coupled to the brightness edges; its
first restoration's lines become the barriers of a second matching pass (feedback), whose support
windows stop at them, and the MRF restores again. Every pass matches over one disparity range: the
Config's ``d_min``/``d_max`` where given, else the range found from the images by
:func:`vmcl.early.disparity_range.estimate_range`, which the run's notes state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cl_array

from vmcl import integrate
from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import stereo
from vmcl.early.disparity_range import estimate_range
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.mrf import backfill, score_confidence
from vmcl.pictures import disparity_image

__all__ = ["StereoCue"]


class StereoCue(CueModule):
    """Depth from the left and right views (:class:`vmcl.pipeline.StereoConfig`)."""

    name = "stereo"
    needs = frozenset({"right"})
    kind = "smooth"
    label = Label.DEPTH
    fields = ("sparse_disparity", "stereo_discontinuity", "first_pass_disparity")
    restored_as = "disparity"

    def measure(self, run: RunInputs) -> Measurement:
        span, note = _disparity_range(run)
        matched = _match(run, None, span)
        dense = _dense_match(run, span)
        data, confidence = _disparity_data(run, matched, dense)
        return Measurement(data, confidence, run.brightness, state=_State(span, dense), notes=(note,) if note else (),
                           fields={"sparse_disparity": on_device(matched.disparity),
                                   "stereo_discontinuity": on_device(matched.discontinuity)})

    def refine_stage(self, config) -> str | None:
        return "feedback" if config.stereo.feedback else None

    def refine(self, run: RunInputs, measurement: Measurement, lines) -> Measurement:
        barriers = integrate.boundary(*lines, machine=run.machine)
        state = measurement.state
        matched = _match(run, barriers, state.span)
        data, confidence = _disparity_data(run, matched, state.dense)
        return Measurement(data, confidence, run.brightness, state=measurement.state,
                           fields={"first_pass_disparity": measurement.fields["sparse_disparity"],
                                   "sparse_disparity": on_device(matched.disparity),
                                   "stereo_discontinuity": on_device(matched.discontinuity)})

    def pictures(self, result) -> dict[str, tuple[np.ndarray, str]]:
        if result.disparity is None:
            return {}
        finite = result.disparity[np.isfinite(result.disparity)]
        low, high = (float(finite.min()), float(finite.max())) if finite.size else (None, None)
        return {"disparity": (disparity_image(result.disparity, vmin=low, vmax=high),
                              "Dense disparity (the stereo MRF's restoration), pixels; near is red"),
                "sparse_disparity": (disparity_image(result.sparse_disparity, vmin=low, vmax=high),
                                     "The matcher's sparse disparities, same scale")}


@dataclass(frozen=True)
class _State:
    """What the feedback pass reuses: the disparity range and the intensity matches."""

    span: tuple[int, int]
    dense: tuple[cl_array.Array, cl_array.Array] | None


def _disparity_range(run: RunInputs) -> tuple[tuple[int, int], str | None]:
    """The range every matching pass searches, and the note saying where it came from (None when the
    Config gives both ends).

    A bound the Config gives overrides that end of the range found from the images; the other end is
    the estimate's, moved to the given bound if it would cross it.
    """
    s = run.config.stereo
    if s.d_min is not None and s.d_max is not None:
        return (s.d_min, s.d_max), None
    found = estimate_range(run.left, run.needed("right"), max_disparity=s.max_disparity, machine=run.machine)
    if s.d_min is not None:
        span = (s.d_min, max(found.d_max, s.d_min))
    elif s.d_max is not None:
        span = (min(found.d_min, s.d_max), s.d_max)
    else:
        span = (found.d_min, found.d_max)
    scale = f"1/{2**found.level} scale"
    if found.decided:
        source = f"from the images at {scale} ({100 * found.confident:.0f}% of its pixels matched confidently)"
    else:
        source = (f"a wide fallback, since too few confident matches ({100 * found.confident:.0f}% of the pixels "
                  f"at {scale}) were found to decide it from the images")
    given = [f"{name} = {value}" for name, value in (("d_min", s.d_min), ("d_max", s.d_max)) if value is not None]
    return span, (f"stereo: disparity range {span[0]}..{span[1]} px, {source}"
                  + (f"; the Config gives {given[0]}" if given else ""))


def _match(run: RunInputs, barriers, span: tuple[int, int], *, features: stereo.Features | None = None
           ) -> stereo.StereoMatch:
    s = run.config.stereo
    features = features or s.features
    # Canny's thresholds mean nothing to the intensity matcher, which matches every pixel; shiftable
    # windows are its own.
    options = {"shiftable": s.shiftable and barriers is None} if features == "intensity" else {
        "low_threshold": s.low_threshold, "high_threshold": s.high_threshold, "use_quantiles": s.use_quantiles}
    return stereo.match(run.left, run.needed("right"), d_min=span[0], d_max=span[1], features=features,
                        patch=s.patch, sigma=s.intensity_sigma if features == "intensity" else s.sigma,
                        barriers=barriers, machine=run.machine, **options)


def _dense_match(run: RunInputs, span: tuple[int, int]) -> tuple[cl_array.Array, cl_array.Array] | None:
    """The intensity matches and their weights for :func:`_disparity_data`, or None without backfill.

    Matched once, without barriers: matched again with the first pass's lines as barriers, in the
    feedback pass, it made the restored disparity worse (a higher dense bad-1 rate on the rendered
    "cues" and "blocks" scenes).
    """
    s = run.config.stereo
    if not s.backfill or s.features == "intensity":
        return None
    dense = _match(run, None, span, features="intensity")
    return on_device(dense.disparity), on_device(score_confidence(dense.score, floor=s.backfill_floor,
                                                                   weight=s.backfill_weight, machine=run.machine))


def _disparity_data(run: RunInputs, matched: stereo.StereoMatch, dense: tuple[cl_array.Array, cl_array.Array] | None
                ) -> tuple[cl_array.Array, cl_array.Array | None]:
    """The stereo MRF's data and confidence: the feature matches, backfilled by intensity matches."""
    if dense is None:
        return on_device(matched.disparity), None
    data, confidence = backfill(matched.disparity, *dense, machine=run.machine)
    return on_device(data), on_device(confidence)
