"""The stereo cue: depth from a rectified pair, restored piecewise smooth, refined by feedback.

Seed sections "Stereo", "Feedback from the results of integration into the matching stage". The
Drumheller-Poggio matcher (:func:`vmcl.early.stereo.match`) gives sparse disparities at edge features;
with ``backfill``, a dense matcher fills the gaps between them, weighed less (:func:`vmcl.mrf.backfill`):
the semi-global matcher (:func:`vmcl.early.semiglobal.match_semiglobal`, whose half-occluded pixels it
reports and weighs least) or intensity correlation. The stereo MRF restores the disparity coupled to
the brightness edges; its first restoration's lines become the barriers of a second feature matching
pass (feedback), whose support windows stop at them, and the MRF restores again. Every pass matches over one disparity range: the
Config's ``d_min``/``d_max`` where given, else the range found from the images by
:func:`vmcl.early.disparity_range.estimate_range`, which the run's notes state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cl_array

from vmcl import integrate
from vmcl.cm import reduce as cm_reduce
from vmcl.cues.base import CueModule, Measurement, RunInputs
from vmcl.early import stereo
from vmcl.early.disparity_range import estimate_range, with_given_ends
from vmcl.early.filters import grey_field
from vmcl.early.rectification import ROW_OFFSET_NOTE, ROW_SPREAD_NOTE, row_alignment
from vmcl.early.semiglobal import SemiGlobalMatch, match_semiglobal
from vmcl.labels import Label
from vmcl.machine import on_device
from vmcl.mrf import backfill, mask_confidence, score_confidence
from vmcl.mrf import preset as mrf_preset
from vmcl.pictures import disparity_image

__all__ = ["StereoCue"]


DENSE_ALPHA = 1.0
"""The stereo MRF's data weight for the dense matches (the preset's is 1)."""
DENSE_BETA = 0.25
"""The stereo MRF's line weight for the dense matches (the preset's is 2)."""


class StereoCue(CueModule):
    """Depth from the left and right views (:class:`vmcl.pipeline.StereoConfig`)."""

    name = "stereo"
    needs = frozenset({"right"})
    kind = "smooth"
    label = Label.DEPTH
    fields = ("sparse_disparity", "stereo_discontinuity", "first_pass_disparity", "half_occluded", "out_of_range")
    # The stereo MRF's weights for the dense matches: the preset's, with the data weight alpha and the
    # line weight beta fitted on the training pairs (benchmarks/stereo_fit.py, stage 4: the best depth lines
    # among the settings whose disparity error is within a tolerance of the best). The preset itself was
    # measured on sparse edge matches.
    settings = mrf_preset("stereo").override({"alpha": DENSE_ALPHA, "beta": DENSE_BETA})
    restored_as = "disparity"

    def measure(self, run: RunInputs) -> Measurement:
        span, note = _disparity_range(run)
        dense = _dense_match(run, span)
        # The rows' alignment is the rig's: a stream measures it on its first frame, after a cut and every
        # VIEW_RECHECK frames (RunInputs.new_view).
        aligned = _alignment_note(run, span, dense) if run.new_view else None
        notes = tuple(n for n in (note, dense.note if dense else None, aligned) if n)
        fields = {} if dense is None else dense.fields
        if not run.config.stereo.feature_matches:
            assert dense is not None  # the Config refuses a stereo section with neither matcher
            return Measurement(dense.disparity, dense.confidence, run.brightness, state=_State(span, dense),
                               notes=notes, fields=fields)
        matched = _match(run, None, span)
        data, confidence = _disparity_data(run, matched, dense)
        fields.update({"sparse_disparity": on_device(matched.disparity),
                       "stereo_discontinuity": on_device(matched.discontinuity)})
        return Measurement(data, confidence, run.brightness, state=_State(span, dense), notes=notes, fields=fields)

    def refine_stage(self, config) -> str | None:
        s = config.stereo
        return "feedback" if s.feedback and s.feature_matches else None

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
        shown = {"disparity": (disparity_image(result.disparity, vmin=low, vmax=high),
                               "Dense disparity (the stereo MRF's restoration), pixels; near is red")}
        if result.half_occluded is not None and result.out_of_range is not None:
            marked = disparity_image(result.disparity, vmin=low, vmax=high)
            marked[:result.half_occluded.shape[0]][result.half_occluded] = (255, 0, 255)
            marked[:result.out_of_range.shape[0]][result.out_of_range] = (0, 255, 255)
            shown["half_occluded"] = (marked, ("Half-occluded pixels (magenta): the right camera does not see them; "
                                               "their disparity is the restoration's, from the background. "
                                               "Out of the searched range (cyan): best matched at its end"))
        if result.sparse_disparity is not None:
            shown["sparse_disparity"] = (disparity_image(result.sparse_disparity, vmin=low, vmax=high),
                                         "The feature matcher's sparse disparities, same scale")
        return shown


@dataclass(frozen=True)
class _Dense:
    """The dense matches as the stereo MRF's data: disparity (NaN where none), its confidence, the Result
    fields the matcher adds (the semi-global matcher's half-occluded and out-of-range pixels), and what
    the run's notes should say of them."""

    disparity: cl_array.Array
    confidence: cl_array.Array
    fields: dict[str, cl_array.Array]
    note: str | None = None


@dataclass(frozen=True)
class _State:
    """What the feedback pass reuses: the disparity range and the dense matches."""

    span: tuple[int, int]
    dense: _Dense | None


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
    span = with_given_ends(found, s.d_min, s.d_max)
    scale = f"1/{2**found.level} scale"
    if found.decided:
        source = f"from the images at {scale} ({100 * found.confident:.0f}% of its pixels matched confidently)"
    else:
        source = (f"a wide fallback, since too few confident matches ({100 * found.confident:.0f}% of the pixels "
                  f"at {scale}) were found to decide it from the images")
    given = [f"{name} = {value}" for name, value in (("d_min", s.d_min), ("d_max", s.d_max)) if value is not None]
    # Every confident match points the wrong way (each pixel lies further right in the right view than in the
    # left): what a pair given in the other order shows. Verging cameras give some negative disparities,
    # not all of them.
    swapped = found.found is not None and found.found[1] < 0
    # A given end beyond the other end found leaves one disparity to search: said, not left to the figures.
    crossed = ((s.d_min is not None and s.d_min > found.d_max) or (s.d_max is not None and s.d_max < found.d_min))
    return span, (f"stereo: disparity range {span[0]}..{span[1]} px, {source}"
                  + (f"; the Config gives {given[0]}" if given else "")
                  + (f", beyond the range {found.d_min}..{found.d_max} the images gave, so one disparity is searched: "
                     "give both d_min and d_max" if crossed else "")
                  + ("; every confident match has a negative disparity (the nearer, the more negative), as when "
                     "the views are given in the other order: is the left image the left camera's?" if swapped else ""))


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


def _dense_match(run: RunInputs, span: tuple[int, int]) -> _Dense | None:
    """The dense matches and their weights, or None without backfill.

    Matched once, without barriers: intensity matches made again with the first pass's lines as
    barriers, in the feedback pass, made the restored disparity worse (a higher dense bad-1 rate on the
    rendered "cues" and "blocks" scenes).
    """
    s = run.config.stereo
    if not s.backfill or (s.feature_matches and s.features == "intensity" and s.dense == "intensity"):
        return None
    if s.dense == "semiglobal":
        found = match_semiglobal(run.left, run.needed("right"), d_min=span[0], d_max=span[1],
                                 census_threshold=s.census_threshold, ad_weight=s.ad_weight,
                                 ad_colour=s.ad_colour, match_exposure=s.match_exposure, p1=s.p1, p2=s.p2,
                                 edge_gain=s.edge_gain, paths=s.paths,
                                 occlusion_geometry=s.occlusion_geometry,
                                 refine=s.refine, refine_radius=s.refine_radius,
                                 refine_colour=s.refine_colour, refine_stride=s.refine_stride, machine=run.machine)
        filled, occluded = on_device(found.filled), on_device(found.occluded)
        confidence = mask_confidence(filled, occluded, weight=s.backfill_weight, masked_weight=s.occluded_weight,
                                     machine=run.machine)
        fields = {"half_occluded": occluded, "out_of_range": on_device(found.out_of_range)}
        return _Dense(filled, on_device(confidence), fields, _matcher_notes(run, found))
    dense = _match(run, None, span, features="intensity")
    return _Dense(on_device(dense.disparity), on_device(score_confidence(
        dense.score, floor=s.backfill_floor, weight=s.backfill_weight, machine=run.machine)), {})


UNCONFIRMED_NOTE = 0.5
"""Share of the pixels the left-right check leaves unconfirmed above which the run's notes say so: well
above what the rectified training pairs leave (the untextured "shadows" scene leaves the most), and
below what a right view turned by 10 degrees leaves (tests/test_disparity_range.py)."""


OUT_OF_RANGE_NOTE = 0.01
"""Share of the pixels matched best, and poorly, at an end of the range above which the run's notes say
so (well above what the training pairs give with the range found from the images)."""


def _matcher_notes(run: RunInputs, found: SemiGlobalMatch) -> str | None:
    """What the run's notes should say of the semi-global matches: that most failed the left-right check
    (the pair is likely not rectified), and how many matched best at an end of the range."""
    counts = [cm_reduce.reduce(on_device(mask), "sum", machine=run.machine)
              for mask in (found.occluded, found.mismatched, found.out_of_range)]
    occluded, mismatched, outside = (int(count.get()) for count in counts)
    pixels = found.occluded.size
    said = []
    share = (occluded + mismatched) / pixels
    if share > UNCONFIRMED_NOTE:
        said.append(f"stereo: the right view confirmed only {100 * (1 - share):.0f}% of the left view's matches "
                    f"({100 * occluded / pixels:.0f}% half-occluded, {100 * mismatched / pixels:.0f}% mismatched): "
                    "the pair may not be rectified (its rows must be epipolar lines), or most of the scene is "
                    "untextured")
    if outside / pixels > OUT_OF_RANGE_NOTE:
        said.append(f"stereo: {100 * outside / pixels:.1f}% of the pixels matched best, and poorly, at an end of the "
                    f"range {found.d_min}..{found.d_max} px (Result.out_of_range): their disparity may lie outside it; "
                    "[stereo] d_min and d_max set the range")
    return "; ".join(said) or None


def _alignment_note(run: RunInputs, span: tuple[int, int], dense: _Dense | None) -> str | None:
    """A note when the views' rows are offset or turned against each other (vmcl.early.rectification): the
    matchers search along rows, and their disparities then fail where the left-right check sees little.
    Each tracked corner starts at the dense matches' disparity (else the middle of the range)."""
    start = dense.disparity.get() if dense is not None else (span[0] + span[1]) / 2
    # The views' grey read back, a third of their colour's bytes: the corners are tracked in grey.
    views = [grey_field(run.machine, view).get() for view in (run.left, run.needed("right"))]
    found = row_alignment(*views, disparity=start)
    if found is None or found.typical < ROW_OFFSET_NOTE:
        return None
    varies = (f"; the offset varies by {found.spread:.2f} px across the image (the views are turned or scaled "
              "against each other)") if found.spread >= ROW_SPREAD_NOTE else ""
    return (f"stereo: the right view's rows lie {found.offset:+.1f} px from the left's (the median over {found.tracks} "
            f"corners tracked between the views; half are off by {found.typical:.1f} px or more){varies}: the pair is "
            "not rectified, its rows are not epipolar lines and the disparity is unreliable; rectify it first "
            "(e.g. OpenCV's stereoRectify, or vmcl.early.registration's warp tables)")


def _disparity_data(run: RunInputs, matched: stereo.StereoMatch, dense: _Dense | None
                    ) -> tuple[cl_array.Array, cl_array.Array | None]:
    """The stereo MRF's data and confidence: the feature matches, backfilled by the dense matches."""
    if dense is None:
        return on_device(matched.disparity), None
    data, confidence = backfill(matched.disparity, dense.disparity, dense.confidence, machine=run.machine)
    return on_device(data), on_device(confidence)
