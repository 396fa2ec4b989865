"""The Vision Machine: images in, the cartoon of labelled discontinuities and the dense fields out.

Seed sections "The Vision Machine System" (figure 1) and "Organization of integration". The images go
through the early modules independently: Canny's brightness edges (:mod:`vmcl.early.edges`), stereo
(:mod:`vmcl.early.stereo`), motion (:mod:`vmcl.early.motion`), colour (:mod:`vmcl.early.color`) and texture
(:mod:`vmcl.early.texture`). Each cue's measurements, noisy and for stereo sparse, are restored by a
line-process MRF coupled to the brightness edges (:func:`vmcl.mrf.restore`), which makes them dense and
finds their discontinuities at once; :mod:`vmcl.integrate` puts the line processes together into the
labelled map. The depth discontinuities of this first pass are fed back to the stereo matcher (the seed's
"feedback from the results of integration into the matching stage"): its support windows stop at them
in a second pass, which the stereo MRF restores again.

Any subset of inputs works: one image gives edges, colour (when RGB) and texture; a right image adds
stereo; a next frame adds motion. Over a sequence, :meth:`VisionMachine.stream` runs each frame with the
next one and carries each cue's restoration to the next frame (:mod:`vmcl.temporal`, the seed's "Fast
vision: The role of time smoothness"). Every field stays on the device from the one upload of each image to
the one download of each output; :class:`Result` holds the NumPy fields with the wall time of every stage
and, on a profiling Machine, the device time of every kernel.

References
----------
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
E. Gamble, D. Geiger, T. Poggio and D. Weinshall, "Integration of vision modules and labeling of surface
discontinuities", IEEE SMC 19(6):1576-1581, 1989.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import sys
import time
import typing
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence, Sized
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pyopencl.array as cl_array

from vmcl import fitted, labelling, learn, temporal
from vmcl import integrate as _integrate
from vmcl.cm import reduce as cm_reduce
from vmcl.cm.core import (
    UNIT_MARGIN,
    check_choice,
    check_int,
    check_real,
    check_unit_image,
    check_unmasked,
    full_scale,
)
from vmcl.cues import CueModule, Measurement, RunInputs, refine_stage_of, registered
from vmcl.early import (
    boundary_probability,
    disparity_range,
    edges,
    lucas_kanade,
    motion,
    motion_refine,
    semiglobal,
    stereo,
    texture,
    variational,
    weighted_median,
)
from vmcl.early.filters import GREY_WEIGHTS
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.group import Grouping, group, saliency_strength, structural_saliency
from vmcl.group.structural_saliency import MAX_ITERATIONS as MAX_SALIENCY_ITERATIONS
from vmcl.labels import CUES
from vmcl.machine import Machine, on_device
from vmcl.mrf import SOLVERS, NothingToRestore, Restoration, Settings, preset
from vmcl.mrf.checks import FLOAT32_MAX
from vmcl.mrf.data import check_unit_interval
from vmcl.recognize import SCALES, TRANSFORMS, Library, recognize
from vmcl.recognize.indexing import MAX_CANDIDATES
from vmcl.result import Result

__all__ = [
    "FILE_SETTINGS",
    "FLOAT_MARGIN",
    "SALIENCY",
    "SMALL_RANGE",
    "VIEW_RECHECK",
    "WARM_SCHEDULE",
    "ColourConfig",
    "Config",
    "CueData",
    "EdgesConfig",
    "GroupingConfig",
    "LabelsConfig",
    "MotionConfig",
    "MrfConfig",
    "Result",
    "StereoConfig",
    "TextureConfig",
    "TimeConfig",
    "VisionMachine",
    "as_image",
    "range_note",
]

if sys.version_info >= (3, 11):
    import tomllib
else:  # the same parser, before it joined the standard library
    import tomli as tomllib

# Full scale of each accepted integer dtype: images are computed as float32 in [0, 1].

# What each annotation of a Config section's fields takes; bool is not taken as an int (TOML's true is
# not 1), and an int is taken as a float (TOML's 2 is 2.0).
_FIELD_TYPES = {"bool": ((bool, np.bool_), "true or false"),
                "int": ((int, np.integer), "an integer"),
                "float": ((int, float, np.integer, np.floating), "a number"),
                "str": ((str,), "a string"),
                "Mapping[str, Any]": ((Mapping,), "a table of keys")}


VIEW_RECHECK = 30
"""In a stream that carries time, the frames at which the cameras' own state (the stereo rows' alignment) is
measured again: the stream's frames 0, 30, 60 ... (counted from its start), and the frame after a cut."""


def _check_field_types(section: str, values: Any) -> None:
    """Refuse a section field of the wrong type, naming ``section.key``, when the Config is made."""
    for spec in dataclasses.fields(values):
        value = getattr(values, spec.name)
        kinds = spec.type.split(" | ")  # the annotation as written (postponed annotations are strings)
        if value is None and "None" in kinds:
            continue
        if "str" in kinds and isinstance(value, os.PathLike) and isinstance(os.fspath(value), str):
            # A file setting given as a pathlib.Path, as the loaders it feeds take one: kept as its text.
            object.__setattr__(values, spec.name, os.fspath(value))
            continue
        is_bool = isinstance(value, (bool, np.bool_))
        if any(isinstance(value, _FIELD_TYPES[kind][0]) and (kind == "bool" or not is_bool)
               for kind in kinds if kind != "None"):
            # abs() before isfinite: an integer too large for a float (TOML holds any) compares exactly, where
            # math.isfinite would raise OverflowError on it.
            if ("float" in kinds and not is_bool and isinstance(value, (int, float, np.integer, np.floating))
                    and abs(value) > FLOAT32_MAX and not (isinstance(value, float) and math.isinf(value))):
                # Every real setting reaches the device as a float32 (or meets one there): beyond its range it
                # would become an infinity mid-run, with only NumPy's overflow warning.
                shown = repr(value) if len(repr(value)) <= 24 else f"an integer of {len(str(abs(value)))} digits"
                raise InputValueError(f"{section}.{spec.name} must lie within float32's range (magnitude at most "
                                      f"{FLOAT32_MAX:.4g}), in which the device computes, got {shown}")
            continue
        expected = " or ".join("None" if kind == "None" else _FIELD_TYPES[kind][1] for kind in kinds)
        raise InputTypeError(f"{section}.{spec.name} must be {expected}, got {value!r} ({type(value).__name__})")


def _check_thresholds(section: str, low: float | None, high: float | None, quantiles: bool) -> None:
    """Hysteresis thresholds: each None or >= 0 (a quantile in [0, 1] with ``use_quantiles``), low <= high."""
    top = 1.0 if quantiles else None
    for name, value in (("low_threshold", low), ("high_threshold", high)):
        if value is not None:
            check_real(value, f"{section}.{name}", minimum=0, maximum=top)
    if low is not None and high is not None and low > high:
        raise InputValueError(f"{section}.low_threshold ({low}) must not exceed {section}.high_threshold ({high})")


@dataclass(frozen=True)
class EdgesConfig:
    """Canny's brightness edges, the edges every cue's MRF is coupled to.

    Parameters
    ----------
    sigma : float
        Gaussian smoothing in pixels (the paper uses Canny "at a coarser resolution" for the MRFs).
    low_threshold, high_threshold : float, optional
        Hysteresis thresholds on the gradient magnitude (image in [0, 1]); None: the noise rule.
    use_quantiles : bool
        The thresholds are quantiles of the gradient magnitudes.
    saliency : {"none", "local", "structural"}
        Which edges the MRFs are coupled to (the seed's saliency operation before the MRF stage uses
        the intensity edges): "none" (default), all of Canny's; "local", those on curves of local
        saliency at least ``grouping.threshold``; "structural", those of structural saliency at least
        ``grouping.structural_threshold`` (:mod:`vmcl.group`).
    """

    sigma: float = edges.DEFAULT_SIGMA
    low_threshold: float | None = None
    high_threshold: float | None = None
    use_quantiles: bool = False
    saliency: str = "none"

    def __post_init__(self) -> None:
        _check_field_types("edges", self)
        check_real(self.sigma, "edges.sigma", above=0)
        _check_thresholds("edges", self.low_threshold, self.high_threshold, self.use_quantiles)
        if self.use_quantiles and self.low_threshold is None and self.high_threshold is None:
            # Without either the noise rule sets the thresholds and the switch changes nothing, in silence.
            raise InputValueError("edges.use_quantiles = true needs edges.low_threshold or edges.high_threshold (or "
                                  "both): quantiles of the gradient magnitudes, in [0, 1]")
        check_choice(self.saliency, "edges.saliency", SALIENCY)


SALIENCY = ("none", "local", "structural")
"""The choices of ``EdgesConfig.saliency``."""


@dataclass(frozen=True)
class GroupingConfig:
    """The grouping stage (:func:`vmcl.group.group`): curves, their saliency, junctions and T-junction pairs.

    The thresholds were fitted on BSDS500 training images (benchmarks/grouping_fit.py,
    results/grouping_fit.md): each is the one that gave the best F-measure (ODS) of the edges it keeps
    there. The local saliency's exponent and scale won there too; the network's 30 iterations were chosen
    on shapes-in-clutter training displays (15, 30 and 60 scored within 0.003 of each other on BSDS).

    Parameters
    ----------
    enabled : bool
        Run the stage; the Result's ``grouping`` is None without it (``edges.saliency`` other than
        "none" runs what it needs either way).
    threshold : float
        The local saliency (gradient magnitude times pixels**length_exponent, image in [0, 1]) a curve
        needs to stay among the salient edges, >= 0.
    length_exponent, curvature_scale : float
        The local saliency's (:func:`vmcl.group.local_saliency.local_saliency`); length_exponent at most 4.
    gap : float
        The longest gap, in pixels, a broken T-junction's stem is followed across (>= 0).
    alignment : float
        How far (degrees) two T-junctions' stems may point off the line between them and still be paired.
    structural_threshold : float
        What an edge pixel's structural saliency times its strength (:func:`vmcl.group.saliency_strength`)
        must reach for it to stay among the structurally salient edges, >= 0.
    iterations : int
        The structural saliency network's iterations (>= 1).
    gap_attenuation : float
        Its attenuation per pixel of gap, in [0, 1].
    """

    enabled: bool = True
    threshold: float = 0.892
    length_exponent: float = 0.5
    curvature_scale: float = 0.5
    gap: float = 6.0
    alignment: float = 20.0
    structural_threshold: float = 93.8
    iterations: int = 30
    gap_attenuation: float = 0.85

    def __post_init__(self) -> None:
        _check_field_types("grouping", self)
        check_real(self.threshold, "grouping.threshold", minimum=0)
        # At most 4: a curve of a million pixels then still has a saliency float32 holds.
        check_real(self.length_exponent, "grouping.length_exponent", minimum=0, maximum=4)
        check_real(self.curvature_scale, "grouping.curvature_scale", above=0)
        check_real(self.gap, "grouping.gap", minimum=0)
        check_real(self.alignment, "grouping.alignment", above=0, below=90)
        check_real(self.structural_threshold, "grouping.structural_threshold", minimum=0)
        check_int(self.iterations, "grouping.iterations", minimum=1, maximum=MAX_SALIENCY_ITERATIONS)
        check_real(self.gap_attenuation, "grouping.gap_attenuation", minimum=0, maximum=1)


DENSE_MATCHERS = ("semiglobal", "intensity")
"""The stereo cue's dense matchers (``StereoConfig.dense``)."""


@dataclass(frozen=True)
class StereoConfig:
    """The Drumheller-Poggio matcher (:func:`vmcl.early.stereo.match`) and the feedback pass.

    Parameters
    ----------
    enabled : bool
    d_min, d_max : int, optional
        The disparity range every matching pass searches. None (the default): found from the images
        (:func:`vmcl.early.disparity_range.estimate_range`; ``Result.notes`` states the range and
        what it was based on); a bound given overrides that end of the range found.
    max_disparity : float
        In (0, 1]: the widest disparity, of either sign, the range estimate searches, as a share of the
        image width; where the images do not decide the range, the matching falls back to 0 ..
        ``floor(max_disparity * W)``.
    features, patch, sigma, low_threshold, high_threshold, use_quantiles
        As :func:`vmcl.early.stereo.match` takes them, ``sigma`` for edge and zero-crossing features
        (intensity matches smooth with ``intensity_sigma``). The defaults match Canny edges chosen by
        quantile (60% and 85%), which keeps textured surfaces matched where the noise rule sees none.
    feature_matches : bool
        Run the feature matcher (:func:`vmcl.early.stereo.match` with ``features``); False leaves the
        stereo MRF the dense matches alone (``backfill`` must then be on).
    feedback : bool
        Match the features again with support windows stopped at the first pass's depth discontinuities.
    backfill : bool
        Also match every pixel (``dense``) and let those matches fill the gaps between the feature
        matches in the stereo MRF's data (:func:`vmcl.mrf.backfill`); without feature matches, they are
        the data.
    dense : {"semiglobal", "intensity"}
        The dense matcher. "semiglobal": census costs with min-sum messages along scanlines, both views
        checked (:func:`vmcl.early.semiglobal.match_semiglobal`); its confirmed disparities weigh
        ``backfill_weight``, its half-occluded pixels, given their background's disparity,
        ``occluded_weight``; ``Result.half_occluded`` marks them. "intensity": normalised
        cross-correlation (``features="intensity"``, the same patch, sub-pixel), weighed by
        :func:`vmcl.mrf.score_confidence` of the correlation with ``backfill_floor`` and
        ``backfill_weight``.
    backfill_floor, backfill_weight : float
        Intensity matches whose correlation is at or below the floor weigh 0; a perfect one (or a
        confirmed semi-global match) weighs ``backfill_weight`` (the feature matches weigh 1). The
        default, 1, was fitted with the semi-global matcher (benchmarks/stereo_fit.py); intensity
        matches beside edge matches were fitted at 0.2, the earlier default.
    occluded_weight : float
        In [0, 1]: the weight of the semi-global matcher's half-occluded pixels.
    census_threshold, ad_weight, ad_colour, match_exposure, p1, p2, edge_gain, paths
        The semi-global matcher's census margin, the weight of the pixels' brightness difference beside the
        census, whether a colour pair's difference is its channels' mean (else its grey's), whether that
        difference is taken after the cameras' exposure difference, measured on the
        surest census matches, is taken out, the smoothness prices, and the number of scanline directions
        (8 or 4), as :func:`vmcl.early.semiglobal.match_semiglobal` takes them.
    occlusion_geometry : bool
        The semi-global matcher counts an unconfirmed pixel as half-occluded only where a nearer surface on
        its right can hide it (:func:`vmcl.early.semiglobal.match_semiglobal`'s ``occlusion_geometry``).
    refine, refine_radius, refine_colour, refine_stride
        The semi-global matcher's weighted median at depth jumps (pixels near a jump take the median of
        the confirmed disparities of their own colour around them), as
        :func:`vmcl.early.semiglobal.match_semiglobal` takes them.
    shiftable : bool
        Intensity matches (the backfill, or ``features = "intensity"``) score each pixel by the best
        patch that holds it (:func:`vmcl.early.stereo.match`'s ``shiftable``), so that the nearer
        surface does not spread over the farther one at depth discontinuities. An intensity matcher's
        feedback pass has barriers instead, which stop its windows at the lines.
    intensity_sigma : float
        The brightness smoothing of intensity matches (``sigma`` is the edge detector's).
    """

    enabled: bool = True
    d_min: int | None = None
    d_max: int | None = None
    max_disparity: float = disparity_range.MAX_DISPARITY
    features: str = "canny"
    patch: int = 11
    sigma: float = 2.0
    low_threshold: float | None = 0.6
    high_threshold: float | None = 0.85
    use_quantiles: bool = True
    feature_matches: bool = False
    feedback: bool = True
    backfill: bool = True
    dense: str = "semiglobal"
    backfill_floor: float = 0.9
    backfill_weight: float = 1.0
    occluded_weight: float = 0.1
    census_threshold: float = semiglobal.CENSUS_THRESHOLD
    ad_weight: float = semiglobal.AD_WEIGHT
    ad_colour: bool = semiglobal.AD_COLOUR
    match_exposure: bool = semiglobal.MATCH_EXPOSURE
    p1: int = semiglobal.P1
    p2: float = semiglobal.P2
    edge_gain: float = semiglobal.EDGE_GAIN
    paths: int = semiglobal.PATHS
    occlusion_geometry: bool = semiglobal.OCCLUSION_GEOMETRY
    refine: bool = True
    refine_radius: int = semiglobal.REFINE_RADIUS
    refine_colour: float = semiglobal.REFINE_COLOUR
    refine_stride: int = semiglobal.REFINE_STRIDE
    shiftable: bool = True
    intensity_sigma: float = 1.0

    def __post_init__(self) -> None:
        # Checked when the Config is made, naming the key, not mid-run.
        _check_field_types("stereo", self)
        check_choice(self.features, "stereo.features", typing.get_args(stereo.Features))
        check_int(self.patch, "stereo.patch", minimum=1)
        if self.patch % 2 == 0:
            raise InputValueError(f"stereo.patch must be odd (a window centred on the pixel), got {self.patch}")
        if self.d_min is not None and self.d_max is not None and self.d_min > self.d_max:
            raise InputValueError(f"stereo.d_min ({self.d_min}) must not exceed stereo.d_max ({self.d_max})")
        check_real(self.max_disparity, "stereo.max_disparity", above=0, maximum=1)
        check_real(self.sigma, "stereo.sigma", above=0)
        _check_thresholds("stereo", self.low_threshold, self.high_threshold, self.use_quantiles)
        check_unit_interval(self.backfill_floor, "stereo.backfill_floor", closed_above=False)
        check_unit_interval(self.backfill_weight, "stereo.backfill_weight", closed_above=True)
        check_unit_interval(self.occluded_weight, "stereo.occluded_weight", closed_above=True)
        check_choice(self.dense, "stereo.dense", DENSE_MATCHERS)
        check_real(self.census_threshold, "stereo.census_threshold", minimum=0)
        check_real(self.ad_weight, "stereo.ad_weight", minimum=0, maximum=24)
        check_int(self.p1, "stereo.p1", minimum=0, maximum=255)
        # The messages' sums are 16-bit: their largest price depends on how many directions add up.
        paths = semiglobal.check_paths(self.paths, "stereo.paths")
        check_real(self.p2, "stereo.p2", minimum=self.p1, maximum=semiglobal.max_p2(paths))
        check_real(self.edge_gain, "stereo.edge_gain", minimum=0)
        check_int(self.refine_radius, "stereo.refine_radius", minimum=1, maximum=2**31 - 1)
        weighted_median.check_sigma_colour(self.refine_colour, "stereo.refine_colour")
        check_int(self.refine_stride, "stereo.refine_stride", minimum=1, maximum=2**31 - 1)
        if not self.feature_matches and not self.backfill:
            raise InputValueError("stereo: feature_matches and backfill are both off, which leaves no matcher")
        if not self.feature_matches and self.backfill_weight == 0:
            # The dense matches are then the only data: weighing them 0 leaves the half-occluded pixels alone.
            raise InputValueError("stereo.backfill_weight must be > 0 without feature matches (the dense matches "
                                  "are the stereo MRF's only data)")
        if not 0 < self.intensity_sigma < math.inf:
            raise InputValueError(f"stereo.intensity_sigma must be > 0 and finite, got {self.intensity_sigma!r}")


@dataclass(frozen=True)
class MotionConfig:
    """Patchwise optical flow (:func:`vmcl.early.motion.flow`) and its weight in the MRF stage.

    Parameters
    ----------
    enabled : bool
    delta, patch, features
        As :func:`vmcl.early.motion.flow` takes them.
    levels : int or None
        The pyramid's levels, as :func:`vmcl.early.motion.flow` takes them; None (default): found
        from the image's size (:func:`vmcl.early.motion.pyramid_levels`), so that the search reaches a
        fixed share of the image. The run's notes say when much of the flow lies at the search's limit.
    weigh_by_score : bool
        The motion MRF weighs each estimate by :func:`vmcl.mrf.score_confidence` of its score; off,
        every estimate weighs 1.
    confidence_floor : float
        In [0, 1): that weighting's floor (:func:`vmcl.mrf.score_confidence`) as a correlation of the
        brightness, the squared-difference features' score; for "sign_log" it is carried to the sign
        correlation's units by the arcsine law.
    refine, refine_radius, refine_colour, refine_stride
        Each flow component is replaced by its weighted median over the pixels of the window of like colour
        (:func:`vmcl.early.weighted_median.weighted_median`: the window's radius and spatial scale in
        pixels, its colour scale in [0, 1] levels, the step between voters) before the motion MRF restores
        it: the matcher's windows straddle motion boundaries and its estimates scatter, which a median
        whose support stops at brightness edges mends (Sun, Roth and Black's weighted median of flow).
        Pixels the matcher left without flow take their neighbours' median (weighed 0 by the score when
        ``weigh_by_score``). ``Result.raw_flow`` stays the matcher's own. Defaults fitted on rendered scenes
        (benchmarks/motion_refine_fit.py).
    lucas_kanade_iterations, lucas_kanade_window, lucas_kanade_highpass
        Lucas-Kanade steps (:func:`vmcl.early.lucas_kanade.lucas_kanade`: their number, >= 0, their
        Gaussian window's scale in pixels, > 0, and the scale of the Gaussian taken from the frames first,
        0 for none or > 1) refine the flow on the two frames, below the discrete
        search's precision, after the weighted median and before the motion MRF restores it (which keeps
        a stream's temporal terms on the refined flow); 0 steps: none. Defaults fitted on rendered scenes
        (benchmarks/motion_lucas_kanade_fit.py).
    variational_iterations, variational_alpha
        The variational refinement (:func:`vmcl.early.variational.variational_refine`: its fixed-point
        iterations, >= 0, 0 for none, and its smoothness weight, >= 0) after the Lucas-Kanade steps and
        before the motion MRF: every pixel's flow answers to its own brightness and gradient and to its
        neighbours' flow at once. Off by default (0 iterations) for its cost. Set it to
        :data:`vmcl.early.variational.ITERATIONS` for the setting fitted on rendered scenes
        (benchmarks/motion_variational_fit.py; the alpha default is that fit's);
        benchmarks/results/motion.md gives its time and its gain on the real sequences.
    """

    enabled: bool = True
    delta: int = motion.DELTA
    patch: int = motion.PATCH
    levels: int | None = None
    features: str = "sign_log"
    weigh_by_score: bool = True
    confidence_floor: float = 0.7
    refine: bool = motion_refine.REFINE
    refine_radius: int = motion_refine.REFINE_RADIUS
    refine_colour: float = motion_refine.REFINE_COLOUR
    refine_stride: int = motion_refine.REFINE_STRIDE
    lucas_kanade_iterations: int = lucas_kanade.ITERATIONS
    lucas_kanade_window: float = lucas_kanade.WINDOW
    lucas_kanade_highpass: float = lucas_kanade.HIGHPASS
    variational_iterations: int = 0
    variational_alpha: float = variational.ALPHA

    def __post_init__(self) -> None:
        _check_field_types("motion", self)
        check_int(self.delta, "motion.delta", minimum=1)
        check_int(self.patch, "motion.patch", minimum=1)
        if self.patch % 2 == 0:
            raise InputValueError(f"motion.patch must be odd (a window centred on the pixel), got {self.patch}")
        if self.levels is not None:
            check_int(self.levels, "motion.levels", minimum=1)
        check_choice(self.features, "motion.features", motion.FEATURES)
        check_unit_interval(self.confidence_floor, "motion.confidence_floor", closed_above=False)
        check_int(self.refine_radius, "motion.refine_radius", minimum=1, maximum=2**31 - 1)
        check_real(self.refine_colour, "motion.refine_colour", above=0)
        check_int(self.refine_stride, "motion.refine_stride", minimum=1, maximum=2**31 - 1)
        check_int(self.lucas_kanade_iterations, "motion.lucas_kanade_iterations", minimum=0, maximum=1000)
        check_real(self.lucas_kanade_window, "motion.lucas_kanade_window", above=0)
        check_real(self.lucas_kanade_highpass, "motion.lucas_kanade_highpass", minimum=0)
        if 0 < self.lucas_kanade_highpass <= lucas_kanade.PRESMOOTH:
            raise InputValueError(f"motion.lucas_kanade_highpass must be 0 or exceed {lucas_kanade.PRESMOOTH:g}, got "
                                  f"{self.lucas_kanade_highpass}")
        check_int(self.variational_iterations, "motion.variational_iterations", minimum=0, maximum=1000)
        check_real(self.variational_alpha, "motion.variational_alpha", minimum=0, maximum=1e6)


@dataclass(frozen=True)
class ColourConfig:
    """Hurlbert-Poggio hue (:func:`vmcl.early.color.albedo_edges`); used when the left image is RGB.

    Parameters
    ----------
    enabled : bool
    threshold : float, optional
        On the noise-normalised hue gradient; None: the noise rule.
    """

    enabled: bool = True
    threshold: float | None = None

    def __post_init__(self) -> None:
        _check_field_types("colour", self)
        if self.threshold is not None:
            check_real(self.threshold, "colour.threshold", minimum=0)


@dataclass(frozen=True)
class TextureConfig:
    """Blob-texton density (:func:`vmcl.early.texture.texture_edges`); parameters as it takes them.

    ``threshold`` is in the units of images scaled to [0, 1].
    """

    enabled: bool = True
    fine_sigma: float = texture.FINE_SIGMA
    coarse_sigma: float = texture.COARSE_SIGMA
    threshold: float = texture.THRESHOLD
    radius: int = texture.RADIUS
    noise_factor: float = texture.NOISE_FACTOR

    def __post_init__(self) -> None:
        _check_field_types("texture", self)
        check_real(self.fine_sigma, "texture.fine_sigma", above=0)
        check_real(self.coarse_sigma, "texture.coarse_sigma", above=0)
        if self.fine_sigma >= self.coarse_sigma:
            raise InputValueError(f"texture.fine_sigma ({self.fine_sigma}) must be below texture.coarse_sigma "
                                  f"({self.coarse_sigma})")
        check_real(self.threshold, "texture.threshold", above=0)  # texture.density refuses 0 at run time
        check_int(self.radius, "texture.radius", minimum=1)
        check_real(self.noise_factor, "texture.noise_factor", above=0)


@dataclass(frozen=True)
class MrfConfig:
    """The line-process MRF restoring each cue (:func:`vmcl.mrf.restore`).

    Parameters
    ----------
    method : {"meanfield", "icm", "mpm", "anneal"}
        The solver for every cue. "meanfield" (Geiger and Girosi, the default) finds the
        discontinuities; "icm" is faster but leaves many spurious lines in the piecewise-constant
        cues (benchmarks/results/pipeline.md).
    seed : int
        Keys the random numbers of "anneal" and "mpm".
    schedule : {"fast", "preset"}
        "fast" (default): mean field at 6 temperatures falling from 2 by a factor 0.6, two sweeps each,
        then 2 ICM sweeps (14 sweeps). It runs a frame many times faster than the presets' own
        110-sweep schedules with the same quality within noise (dense disparity, flow and integrated
        discontinuities on the "cues" scene, compared before the flow's confidence weights); on a
        disparity map alone, benchmarks/results/mrf.md compares the two schedules' time, energy and
        error.
        "preset": each cue's preset schedule.
    cross_validate : bool
        Choose each cue's data weight alpha per image, by held-out measurements
        (:func:`vmcl.learn.cross_validate`: 9 candidates from 1/16 to 16 times the cue's own alpha, 3 folds
        of 10%), instead of the fixed one. 27 more restorations per cue; off by default.
        benchmarks/results/learn.md measures it on the stereo pairs.
    stereo, motion, colour, texture : mapping of str to value
        Overrides of :func:`vmcl.mrf.preset`'s measured settings per cue (any field of
        :class:`vmcl.mrf.EnergyModel` or of a solver's schedule, e.g. ``{"beta": 3.0}``; see
        :meth:`vmcl.mrf.Settings.override`), one table per cue of :data:`vmcl.labels.CUES`.
    """

    method: str = "meanfield"
    seed: int = 0
    schedule: str = "fast"
    cross_validate: bool = False
    stereo: Mapping[str, Any] = field(default_factory=dict)
    motion: Mapping[str, Any] = field(default_factory=dict)
    colour: Mapping[str, Any] = field(default_factory=dict)
    texture: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _check_field_types("mrf", self)
        check_choice(self.method, "mrf.method", SOLVERS)
        check_choice(self.schedule, "mrf.schedule", _SCHEDULES)
        check_int(self.seed, "mrf.seed", minimum=0, maximum=2**64 - 1)
        # Copied: a frozen Config must not change when the caller's mappings do later.
        for cue in CUES:
            object.__setattr__(self, cue, copy.deepcopy(dict(getattr(self, cue))))

    def __hash__(self) -> int:
        # The overrides are mappings, which do not hash: their keys do, and equal mappings have equal keys
        # (their values may be equal and of different types, 3 and 3.0, which a text of them tells apart).
        keys = tuple(tuple(sorted(map(str, getattr(self, cue)))) for cue in CUES)
        return hash((self.method, self.seed, self.schedule, self.cross_validate, keys))

    def settings(self, cue: str, default: Settings | None = None, *, warm: bool = False) -> Settings:
        """The MRF settings of ``cue``: ``default`` (the cue's own, :attr:`vmcl.cues.CueModule.settings`),
        else its preset (for :data:`vmcl.labels.CUES`) or ``Settings()``, with the schedule (with
        ``warm``, :data:`WARM_SCHEDULE`) and this configuration's overrides."""
        schedule = WARM_SCHEDULE if warm else _SCHEDULES[self.schedule]
        if cue in CUES:
            base = default if default is not None else preset(cue)
            return base.override({**schedule, **getattr(self, cue)}, prefix=f"mrf.{cue}")
        return (default or Settings()).override(schedule, prefix=f"mrf.{cue}")


@dataclass(frozen=True)
class RecognitionConfig:
    """The recognition stage (:func:`vmcl.recognize.recognize`): a library's objects found in the left image.

    Parameters
    ----------
    models : str
        A library folder of model files (``vmcl learn``; relative to the working directory, in a TOML file
        to its folder: :meth:`Config.from_toml`); "" (the default) runs no recognition.
    transform : {"similarity", "affine", "homography"}
        The pose a 2-D model is aligned by, as :func:`vmcl.recognize.recognize` takes it.
    candidates : int
        The pose bins kept by the indexing, shared between the library's views (``recognize``'s
        ``candidates``): each view's share shrinks as the library grows, so an object in a cluttered
        photograph that a small library finds may need more beside a large one.
    min_scale, max_scale : float
        The sizes searched, as an object's size in the image over its size in the example it was learned
        from (``recognize``'s ``scales``): half to twice by default. An object farther or nearer than that
        is not found; widen the range for it (a wider one admits more small look-alikes among clutter).
    """

    models: str = ""
    transform: str = "similarity"
    candidates: int = 1024
    min_scale: float = SCALES[0]
    max_scale: float = SCALES[1]

    def __post_init__(self) -> None:
        _check_field_types("recognition", self)
        check_choice(self.transform, "recognition.transform", TRANSFORMS)
        check_int(self.candidates, "recognition.candidates", minimum=1, maximum=MAX_CANDIDATES)
        check_real(self.min_scale, "recognition.min_scale", above=0, maximum=1e6)
        check_real(self.max_scale, "recognition.max_scale", minimum=self.min_scale, maximum=1e6)


@dataclass(frozen=True)
class LabelsConfig:
    """How the integration stage labels the discontinuities (:mod:`vmcl.labelling`).

    Parameters
    ----------
    method : {"linear", "rule"}
        "linear" (default): the paper's linear classifier at every pixel with a brightness edge or a
        cue's line, fitted to rendered scenes; it also drops candidates it reads as no discontinuity and
        gives ORIENTATION, SHADOW and SPECULAR labels. "rule": every pixel a cue's line marks, labelled
        DEPTH (depth or motion), else ALBEDO (colour), else TEXTURE (:func:`vmcl.integrate.integrate`).
        benchmarks/results/labelling.md compares them.
    weights : str or None
        A JSON file of :class:`vmcl.labelling.LinearLabeller` weights (relative to the working
        directory; in a TOML file, to its folder: :meth:`Config.from_toml`), read and checked when the
        Config is made; None: the fitted ones shipped. Only
        "linear" uses them.
    boundary_probability : bool
        Run the stage "boundaries": the left image's probability of boundary
        (:func:`vmcl.early.boundary_probability.boundary_probability`), which the soft map
        ``Result.boundary_strength`` follows (True, the default). False leaves it out (a run that wants
        no soft map, e.g. depth alone, saves its time): the strength is then the linear classifier's
        support at the candidates and 0 elsewhere (the "rule" method's: 1 where it labels a
        discontinuity). The labels do not depend on it.
    """

    method: str = "linear"
    weights: str | None = None
    boundary_probability: bool = True

    def __post_init__(self):
        _check_field_types("labels", self)
        if self.method not in ("linear", "rule"):
            raise InputValueError(f"labels.method must be 'linear' or 'rule', got {self.method!r}")
        if self.weights is not None:
            if not isinstance(self.weights, str) or not self.weights:
                raise InputTypeError(f"labels.weights must be a file name or None, got {self.weights!r}")
            try:
                labelling.LinearLabeller.load(self.weights)
            except ValueError as error:
                raise InputValueError(f"labels.weights: {error}") from None

    def labeller(self) -> labelling.LinearLabeller:
        """The weights this section names."""
        return labelling.LinearLabeller.load(self.weights) if self.weights else labelling.default_labeller()


@dataclass(frozen=True)
class TimeConfig:
    """What :meth:`VisionMachine.stream` carries from frame to frame (:mod:`vmcl.temporal`).

    The defaults of gain, memory and jump were chosen by benchmarks/time_fit.py on rendered sequences
    whose speeds change from frame to frame: there the carried fields are worth little against each new
    measurement, so time breaks at a small change (jump) and the carried information stays modest. Sequences of steadier motion gain more from a
    larger gain and memory (benchmarks/results/time_fit.md).

    Parameters
    ----------
    enabled : bool
        Temporal terms on (the stream then differs from independent runs); off, each frame of a stream
        is exactly :meth:`VisionMachine.run` on that frame and the next.
    gain : float
        >= 0, the weight of the carried field's information against the new measurement's.
    memory : float
        > 0, the most information the past can carry, in frames' worth of a unit-confidence measurement
        (the Kalman prediction's process noise is its inverse).
    tolerance : float
        > 0, the largest change of smoothed brightness (images in [0, 1]) along the flow that keeps
        time unbroken at a pixel.
    jump : float
        > 0, the largest change (pixels) between a piecewise smooth cue's carried value and its new
        measurement (disparity; flow, as a vector) that keeps time unbroken for that cue at a pixel: a
        larger one says the surface or its motion changed, and the measurement stands alone.
    scene_cut : float
        In (0, 1]: when a larger share of the pixels is broken, the frame starts cold.
    warm : bool
        Start each MRF from the carried field with :data:`WARM_SCHEDULE` (mean field); off, the full
        schedule from the data.
    predict_search : bool
        The previous flow, carried to the frame, predicts where the motion search looks: the finest level
        is searched around it as well as around the coarse-to-fine prediction, and each pixel keeps the
        better match (:func:`vmcl.early.motion.flow`'s ``prediction``). On by default: its error ratio
        to time off on the training sequences was the lower (benchmarks/time_fit.py).
    flow_prior : float
        >= 0: the weight of the motion cue's variational refinement's pull towards the previous frame's
        flow carried to this one (``beta`` of :func:`vmcl.early.variational.variational_refine`; none where
        time is broken); 0, none. It acts only when ``[motion] variational_iterations`` > 0. Default 0:
        fitted on rendered sequences with the refinement on (benchmarks/time_variational_fit.py), every
        weight scored worse than none, the sequences' speeds changing from frame to frame.
    """

    enabled: bool = True
    gain: float = 0.5
    memory: float = 4.0
    tolerance: float = 0.05
    jump: float = 0.25
    scene_cut: float = 0.5
    warm: bool = True
    predict_search: bool = True
    flow_prior: float = 0.0

    def __post_init__(self) -> None:
        _check_field_types("time", self)
        # Bounded as flow_prior is: beyond float32 the carried weights overflow mid-stream.
        check_real(self.gain, "time.gain", minimum=0, maximum=1e6)
        check_real(self.memory, "time.memory", above=0, maximum=1e6)
        check_real(self.tolerance, "time.tolerance", above=0)
        check_real(self.jump, "time.jump", above=0)
        check_real(self.scene_cut, "time.scene_cut", above=0, maximum=1)
        check_real(self.flow_prior, "time.flow_prior", minimum=0, maximum=1e6)

    def memory_of(self, machine: Machine) -> temporal.Memory:
        """A new stream's :class:`vmcl.temporal.Memory` with these settings."""
        return temporal.Memory(machine, tolerance=self.tolerance, memory=self.memory, gain=self.gain,
                               scene_cut=self.scene_cut)


_SCHEDULES = {
    "fast": {"mf_t0": 2.0, "mf_factor": 0.6, "mf_steps": 6, "mf_iterations": 2, "quench": 2},
    "preset": {},
}

WARM_SCHEDULE = {"mf_t0": 0.43, "mf_factor": 0.6, "mf_steps": 3, "mf_iterations": 1, "quench": 2}
"""The mean-field schedule of a warm start (:attr:`TimeConfig.warm`): the last three temperatures of the
"fast" schedule, one sweep each, then 2 ICM sweeps (5 sweeps against its 14). Its first temperature is
cold enough that the carried field's lines form at once where its jumps are, and the field keeps them."""

_SECTIONS = {"edges": EdgesConfig, "grouping": GroupingConfig, "stereo": StereoConfig, "motion": MotionConfig,
             "colour": ColourConfig, "texture": TextureConfig, "mrf": MrfConfig, "labels": LabelsConfig,
             "time": TimeConfig, "recognition": RecognitionConfig}


@dataclass(frozen=True)
class Config:
    """Everything the machine can be told, with documented defaults; see each section's class.

    Load one from TOML with :meth:`from_toml` (sections ``[edges]``, ``[grouping]``, ``[stereo]``, ``[motion]``,
    ``[colour]``, ``[texture]``, ``[mrf]`` and ``[mrf.stereo]`` ... for the MRF settings' overrides, ``[labels]``); unknown keys
    are refused with a ValueError naming them, and values of the wrong type (each field's annotation: bool,
    int, float, str, None where allowed; true is not an integer) with a TypeError naming ``section.key``.

    Examples
    --------
    >>> Config.from_dict({"stereo": {"d_max": 16}, "mrf": {"method": "icm"}}).stereo.d_max
    16
    """

    edges: EdgesConfig = field(default_factory=EdgesConfig)
    grouping: GroupingConfig = field(default_factory=GroupingConfig)
    stereo: StereoConfig = field(default_factory=StereoConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    colour: ColourConfig = field(default_factory=ColourConfig)
    texture: TextureConfig = field(default_factory=TextureConfig)
    mrf: MrfConfig = field(default_factory=MrfConfig)
    labels: LabelsConfig = field(default_factory=LabelsConfig)
    time: TimeConfig = field(default_factory=TimeConfig)
    recognition: RecognitionConfig = field(default_factory=RecognitionConfig)

    def __post_init__(self) -> None:
        # A Config made in Python is checked like one read from TOML: each section of its own class
        # (whose values checked themselves), and every cue's MRF overrides applied once.
        for name, kind in _SECTIONS.items():
            section = getattr(self, name)
            if not isinstance(section, kind):
                raise InputTypeError(f"config section {name} must be a vmcl.pipeline.{kind.__name__}, "
                                     f"got {type(section).__name__}")
        for cue in CUES:
            self.mrf.settings(cue).model.check_anchored(f"mrf.{cue}.alpha")  # restore would, but only mid-run

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> Config:
        """A Config from nested mappings; a key that names nothing raises ValueError, a mistyped value TypeError."""
        if not isinstance(values, Mapping):
            raise InputTypeError(f"config values must be a mapping of section to keys, got {type(values).__name__}")
        sections = {}
        for name, entries in values.items():
            if name not in _SECTIONS:
                raise InputValueError(f"unknown config section {name!r}; sections are {', '.join(_SECTIONS)}")
            if not isinstance(entries, Mapping):
                raise InputTypeError(f"config section {name!r} must be a table of keys")
            known = {f.name for f in dataclasses.fields(_SECTIONS[name])}
            for key in entries:
                if key not in known:
                    raise InputValueError(f"unknown config key {name}.{key}; {name} has {', '.join(sorted(known))}")
            sections[name] = _SECTIONS[name](**dict(entries))  # MrfConfig copies its own mappings
        return cls(**sections)

    @classmethod
    def from_toml(cls, path: str | Path) -> Config:
        """Read a Config from a TOML file.

        The file settings it names (``[labels] weights``, ``[recognition] models``) are read relative to the
        TOML file's folder where they are relative paths, as a configuration that travels with its files
        means them.

        A file ``vmcl fit`` wrote carries a ``[fitted]`` table: its parameters, and its entries the record's
        included, are checked against the hashes recorded there (:func:`vmcl.fitted.check_fitted`), and a
        warning (:class:`vmcl.fitted.FittedVersionWarning`) says when another vmcl version fitted them.

        Raises InputValueError (a ValueError) on a folder, bad TOML (or text that is not UTF-8), keys, or
        a fitted file edited since it was fitted; InputTypeError (a TypeError) on a ``path`` that is
        not a str or an os.PathLike, or mistyped values; FileNotFoundError if the file does not exist, and
        another OSError if it cannot be read. A refusal about the file starts with its path.
        """
        if not isinstance(path, (str, os.PathLike)):
            raise InputTypeError(f"path must be a str or an os.PathLike, got {type(path).__name__}")
        path = Path(path)
        if path.is_dir():
            raise InputValueError(f"{path}: a folder, not a TOML file")
        try:
            # utf-8-sig: a byte-order mark (as Windows' Notepad saves UTF-8) is not part of the TOML.
            values = tomllib.loads(path.read_text(encoding="utf-8-sig"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
            raise InputValueError(f"{path}: not valid TOML ({error})") from None
        except RecursionError:
            raise InputValueError(f"{path}: not a configuration (its tables or arrays are nested too deeply)") from None
        return cls.from_dict(_files_beside(fitted.check_fitted(values, str(path)), path.parent))

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """The configuration as nested plain values (for the report)."""
        return {name: {k: (dict(v) if isinstance(v, Mapping) else v)
                       for k, v in dataclasses.asdict(getattr(self, name)).items()} for name in _SECTIONS}


FLOAT_MARGIN = UNIT_MARGIN
"""How far outside [0, 1] a float image's pixels may lie (noise) before :func:`as_image` refuses it
(:data:`vmcl.cm.core.UNIT_MARGIN`)."""


FILE_SETTINGS = (("labels", "weights"), ("recognition", "models"))
"""The (section, key) of each setting that names a file or folder: :meth:`Config.from_toml` reads a relative
one from the TOML file's folder."""


def _files_beside(values: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``values`` with each relative file setting (:data:`FILE_SETTINGS`) joined to ``folder``."""
    for section, key in FILE_SETTINGS:
        entries = values.get(section)
        if (isinstance(entries, dict) and isinstance(entries.get(key), str) and entries[key]
                and not Path(entries[key]).is_absolute()):
            values = {**values, section: {**entries, key: str(folder / entries[key])}}
    return values


def as_image(array: Any, name: str) -> np.ndarray:
    """An input image as float32 in [0, 1]: (H, W) grey or (H, W, 3) RGB; uint8, uint16 or float.

    Float images must already be in [0, 1] (within :data:`FLOAT_MARGIN`); float64 is converted to
    float32. Raises ValueError or TypeError naming ``name`` for anything else (wrong shape, NaN or
    infinite pixels, values off the [0, 1] scale, too small).
    """
    if isinstance(array, (str, os.PathLike)):
        raise InputTypeError(f"{name} must be a NumPy array, got the path {str(array)!r}: read it first "
                             "(vmcl.datasets.read_image)")
    if not isinstance(array, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy array, got {type(array).__name__}")
    check_unmasked(array, name)
    if array.ndim not in (2, 3) or (array.ndim == 3 and array.shape[2] != 3):
        raise InputValueError(f"{name} must be (H, W) grey or (H, W, 3) RGB, got shape {array.shape}")
    if min(array.shape[:2]) < 16:
        raise InputValueError(f"{name} must be at least 16 x 16 pixels, got shape {array.shape}")
    if array.dtype.kind == "u" and array.dtype.itemsize in (1, 2):  # uint8 and uint16, in either byte order
        return (array.astype(np.float32) / np.float32(full_scale(array.dtype)))
    if array.dtype.kind != "f":
        raise InputTypeError(f"{name} must be uint8, uint16 or float, got {array.dtype}")
    if not np.isfinite(array).all():
        raise InputValueError(f"{name} has NaN or infinite pixels")
    check_unit_image(array, name)
    image = np.ascontiguousarray(array, np.float32)
    # Never the caller's own array: a Result holds its image, which the caller may change after the run.
    return image.copy() if np.shares_memory(image, array) else image


class CueData(NamedTuple):
    """One cue's measurement as its MRF receives it (:meth:`VisionMachine.measure`), on the host.

    Attributes
    ----------
    data : (H, W) or (H, W, 2) float32 array
        NaN where the module gave no value.
    confidence : (H, W) float32 array or None
        The data term's weight (None: 1 wherever there is data).
    coupling : (H, W) bool array
        The edges the cue's line sites are coupled to.
    """

    data: np.ndarray
    confidence: np.ndarray | None
    coupling: np.ndarray


class VisionMachine:
    """The integrated machine of figure 1: early modules, MRF restoration per cue, integration.

    Parameters
    ----------
    config : Config, optional
        Default: ``Config()``.
    machine : vmcl.Machine, optional
        Default: a new profiling Machine (per-kernel timings in every Result).

    Examples
    --------
    >>> from vmcl import scenes
    >>> scene = scenes.render(scenes.preset("cues", shape=(64, 64)), seed=0)
    >>> result = VisionMachine().run(scene.left, scene.right)  # doctest: +SKIP
    >>> result.disparity.shape, sorted(result.lines)  # doctest: +SKIP
    ((64, 64), ['colour', 'stereo', 'texture'])
    """

    def __init__(self, config: Config | None = None, *, machine: Machine | None = None) -> None:
        if config is not None and not isinstance(config, Config):
            raise InputTypeError(f"config must be a vmcl.pipeline.Config, got {type(config).__name__}")
        if machine is not None and not isinstance(machine, Machine):
            raise InputTypeError(f"machine must be a vmcl.Machine, got {type(machine).__name__}")
        self.config = config or Config()
        self.machine = machine or Machine(profile=True)
        # Read once per machine; None with the rule labels.
        self.labeller = self.config.labels.labeller() if self.config.labels.method == "linear" else None
        # The model library, read once (its index is built at the first run); None without recognition.
        try:
            self.library = Library.load(self.config.recognition.models) if self.config.recognition.models else None
        except InputError as error:
            raise type(error)(f"recognition.models: {error}") from None
        self._check_refine_stages()

    def _check_refine_stages(self) -> None:
        """Refuse a Config under which a cue's refinement stage (:meth:`vmcl.cues.CueModule.refine_stage`) is
        not a name or None, or is the name of another stage of the run, whose timing and progress it would
        take: :func:`vmcl.cues.register` can ask the default Config only."""
        everything = {"right": True, "next": True, "rgb": True}
        refining = [(cue, refine_stage_of(cue, self.config)) for cue in self.cues(**everything)]
        names = self.stages(**everything, streaming=True)
        for cue, stage in reversed(refining):  # the later cue of two that share a stage is the one said
            if stage and names.count(stage) > 1:
                raise InputValueError(f"cue {cue.name!r}: under this Config refine_stage() is {stage!r}, the name "
                                      "of another stage of the run")

    def cues(self, *, right: bool, next: bool, rgb: bool) -> list[CueModule]:
        """The registered cues (:func:`vmcl.cues.registered`) that run for these inputs, in order."""
        given = {name for name, present in (("right", right), ("next", next), ("rgb", rgb)) if present}
        return [cue for cue in registered() if cue.needs <= given and cue.enabled(self.config)]

    def stages(self, *, right: bool, next: bool, rgb: bool, streaming: bool = False) -> list[str]:
        """The names of the stages :meth:`run` (or, with ``streaming``, a frame of :meth:`stream` with
        the temporal terms on) goes through for these inputs, in order."""
        active = self.cues(right=right, next=next, rgb=rgb)
        carried = ["time"] if streaming and self.config.time.enabled else []
        grouping = ["grouping"] if self.config.grouping.enabled or self.config.edges.saliency != "none" else []
        boundaries = ["boundaries"] if self.config.labels.boundary_probability else []
        names = ["upload", *carried, "edges", *grouping, *boundaries, *(cue.name for cue in active)]
        for cue in active:
            names += [f"mrf {cue.name}"] + [stage for stage in [cue.refine_stage(self.config)] if stage]
        return names + ["integrate", "download"] + (["recognition"] if self.library is not None else [])

    def run(self, left: np.ndarray, right: np.ndarray | None = None, next: np.ndarray | None = None, *,
            progress: Callable[[str], None] | None = None) -> Result:
        """Run the machine on one image, a stereo pair, and/or the next frame of the left view.

        Parameters
        ----------
        left : (H, W) or (H, W, 3) array, uint8, uint16 or float
            The left view at t: integers on their type's full scale, floats in [0, 1] (floats on another
            scale, such as 0..255, are refused: divide them by their full scale first).
        right : array of left's shape, optional
            The right view at t, rectified (rows are epipolar lines): adds stereo. Its type may differ from
            left's (each is read on its own type's scale, as ``left`` is).
        next : array of left's shape, optional
            The left view at t + 1: adds motion (its type may differ, as ``right``'s may).
        progress : callable, optional
            Called with each stage's name (see :meth:`stages`) when the stage ends.

        Returns
        -------
        Result

        Raises
        ------
        ValueError, TypeError
            Bad images (shape, dtype, NaN, sizes that differ) or a configuration the modules refuse.
        """
        _check_progress(progress)
        image, others, notes = _inputs(left, right, next)
        return _Run(self, image, others, progress, None, notes=notes).result

    def measure(self, left: np.ndarray, right: np.ndarray | None = None,
                next: np.ndarray | None = None) -> dict[str, CueData]:
        """What each cue's early module gives its MRF, before any restoration: the data to learn from.

        Parameters
        ----------
        left, right, next
            As for :meth:`run`.

        Returns
        -------
        dict of str to CueData
            By cue name (the cues :meth:`run` would run for these inputs): the MRF's data (NaN where
            none), its confidence and the edges its lines are coupled to, on the host. Stereo's are
            those of its first pass (before the feedback pass re-matches along the restored lines).
        """
        image, others, notes = _inputs(left, right, next)
        return _Run(self, image, others, None, None, notes=notes, measure_only=True).measured

    def stream(self, frames: Iterable[np.ndarray], rights: Iterable[np.ndarray] | None = None, *,
               progress: Callable[[str], None] | None = None) -> Iterator[Result]:
        """Run the machine over a sequence: one Result per frame, the temporal terms carried between them.

        Parameters
        ----------
        frames : iterable of arrays
            The left view's frames in order, each as :meth:`run` takes ``left`` (all of one size and
            channels). Read lazily, one frame ahead: frame t's Result comes once frame t + 1 is read.
        rights : iterable of arrays, optional
            The right view's frames (a stereo sequence), as many as ``frames``; a None among them is refused,
            as among ``frames``, not read as a frame without stereo.
        progress : callable, optional
            Called with each stage's name, as :meth:`run` calls it (the stages of :meth:`stages` with
            ``streaming=True``).

        Yields
        ------
        Result
            Frame t's, with motion from t to t + 1 (the last frame has none; a sequence of one frame has a
            note that motion needs a next frame). With ``config.time``
            enabled (the default), each cue's MRF also holds the previous frame's restoration carried
            along the flow (:mod:`vmcl.temporal`), and ``notes`` says where time was broken; disabled,
            each Result is ``run(frame t, right t, frame t + 1)``.

        Raises
        ------
        ValueError, TypeError
            As :meth:`run`, each prefixed "frame k: " (k counted from 0); also when ``rights`` ends before or
            after ``frames``.
        """
        for name, given in (("frames", frames), ("rights", rights)):
            if isinstance(given, (str, os.PathLike)):
                raise InputTypeError(f"{name} must be an iterable of images, got the path {str(given)!r}: read a "
                                     "folder, glob or video with vmcl.frame_sources.open_frames(path).frames()")
            if given is not None and not isinstance(given, Iterable):
                raise InputTypeError(f"{name} must be an iterable of images, got {type(given).__name__}")
            if isinstance(given, np.ndarray) and (given.ndim == 2 or (given.ndim == 3 and given.shape[2] == 3)):
                # Its rows would be read as frames, and refused as too small with no word of why.
                raise InputTypeError(f"{name} must be an iterable of images, got one image of shape {given.shape}: "
                                     "give a list of frames (or run() for one image)")
        if rights is not None and isinstance(frames, Sized) and isinstance(rights, Sized) and len(frames) != len(rights):
            raise InputValueError(f"frames and rights must be as long (a stereo sequence needs a right view per "
                                  f"frame), got {len(frames)} and {len(rights)}")  # before any work, counts known
        _check_progress(progress)
        memory = self.config.time.memory_of(self.machine) if self.config.time.enabled else None
        # Each frame is copied as it is read: frames are read one ahead, and a camera or video reader that
        # fills one buffer per frame would otherwise change the frame being run under it (no motion).
        lefts = (_held(frame) for frame in frames)
        seconds = (_held(frame) for frame in rights) if rights is not None else None
        # The following frame is each frame's next where a cue reads one (motion); given where none does, it
        # would earn every frame the note that it was not used, though the user gave none.
        reads_next = any("next" in cue.needs for cue in self.cues(right=True, next=True, rgb=True))
        index, current = 0, next(lefts, _ENDED)  # a None among the frames is a bad frame, not the end
        if current is _ENDED:
            return
        right = self._stream_right(seconds, index)
        while current is not _ENDED:
            following = next(lefts, _ENDED)
            if following is None:  # named now: as "no next frame" it would run this frame without motion first
                raise InputTypeError(f"frame {index + 1}: left must be a NumPy array, got NoneType")
            try:
                image, others, notes = _inputs(current, right, None if following is _ENDED or not reads_next
                                               else following)
                if index == 0 and following is _ENDED and reads_next:  # said, or no flow looks like no motion
                    notes.append("motion: the sequence has one frame, and motion needs a next frame: no flow")
                # The machine's own refusals (a frame smaller than the motion patch) name the frame too.
                result = _Run(self, image, others, progress, memory, notes=notes).result
            except InputError as error:
                raise type(error)(f"frame {index}: {error}") from None
            yield result
            index, current = index + 1, following
            right = self._stream_right(seconds, index) if current is not _ENDED else None
        if seconds is not None and next(seconds, _ENDED) is not _ENDED:
            raise InputValueError(f"rights holds more frames than frames, which ended after {index}")

    @staticmethod
    def _stream_right(rights: Iterator[Any] | None, index: int) -> Any:
        """The right view of frame ``index`` as read (checked with the frame), None for a monocular stream."""
        if rights is None:
            return None
        right = next(rights, _ENDED)
        if right is _ENDED:
            raise InputValueError(f"rights ended at frame {index}: a stereo sequence needs a right view per frame")
        if right is None:  # as a missing right it would run the frame without stereo, in silence
            raise InputTypeError(f"frame {index}: right must be a NumPy array, got NoneType")
        return right


_ENDED = object()  # the end of a stream's frames (None is a frame, a bad one)


def _check_progress(progress: Any) -> None:
    if progress is not None and not callable(progress):
        raise InputTypeError(f"progress must be a callable taking a stage's name, or None, got {type(progress).__name__}")


def _held(frame: Any) -> Any:
    """A stream's frame as read: a NumPy array copied (its source may fill the same buffer next), the
    rest as given, for the checks to name."""
    return frame.copy() if isinstance(frame, np.ndarray) else frame  # a masked array stays one, for the checks


def _inputs(left: Any, right: Any, next: Any) -> tuple[np.ndarray, dict[str, np.ndarray], list[str]]:
    """The images of one run, checked: left and the others present, each of left's shape; and the notes on
    them (:func:`range_note`)."""
    image = as_image(left, "left")
    others = {}
    for name, array in (("right", right), ("next", next)):
        if array is not None:
            others[name] = as_image(array, name)
            if others[name].shape != image.shape:
                raise InputValueError(f"{name} has shape {others[name].shape}, left has {image.shape}: "
                                      "the images must have the same size and channels")
    notes = [note for name, array in (("left", left), ("right", right), ("next", next))
             if array is not None and (note := range_note(array, name))]
    return image, others, notes


SMALL_RANGE = 1 / 8
"""An image whose brightest pixel is below this share of its type's full scale (of 1 for a float image) gets
a note (:func:`range_note`): 13-bit data or less stored in uint16, or an 8-bit image darker than 32."""


def range_note(array: np.ndarray, name: str) -> str | None:
    """A note when an image uses only the bottom of its range: an integer one (uint8, uint16) of its type's,
    a float one of [0, 1]. The machine reads integers on their full scale and floats as they are
    (:func:`as_image`), so such an image is very dark to it, and the stages that read contrast in absolute
    terms (the probability of boundary, the texture's blobs, the colour and MRF thresholds) see little;
    nothing is rescaled without being asked. None otherwise."""
    if array.size == 0:
        return None
    if array.dtype.kind == "f":
        top_value = float(np.max(array))  # as_image has refused what is not finite
        if top_value >= SMALL_RANGE:
            return None
        if top_value <= 0:
            return f"{name}: no pixel is above 0 (a black image): the machine sees nothing in it"
        return (f"{name}: its brightest pixel is {top_value:.4g}, and the machine reads a float image on [0, 1], "
                f"so it sees a very dark image and its contrast-based stages find little; scale it to [0, 1] first "
                f"(x {1 / top_value:.4g} takes its brightest pixel to 1)")
    if array.dtype.kind != "u" or array.dtype.itemsize not in (1, 2):
        return None
    scale = full_scale(array.dtype)
    top = int(array.max())
    if top >= SMALL_RANGE * scale:
        return None
    if top == 0:
        return f"{name}: every pixel is 0 (a black image): the machine sees nothing in it"
    bits = top.bit_length()
    # b-bit data reaches 2^b - 1; the factor that takes that to the type's full scale (255 for 1-bit data).
    factor = scale / (2**bits - 1)
    return (f"{name}: its brightest pixel is {top} of {array.dtype.newbyteorder('=')}'s {scale:.0f} ({100 * top / scale:.1f}% of "
            f"the range), and the machine reads images on their type's full scale, so it sees a very dark image "
            f"and its contrast-based stages find little; if the data has {bits} bit{'s' if bits > 1 else ''}, "
            f"scale it to the full range first (x {factor:.6g})")


def _checked_measurement(cue: CueModule, found: Any) -> Measurement:
    """What a cue's measure returned, if it is a Measurement of device arrays: a cue of the user's that
    returns something else is refused by name, not met later as a bare TypeError."""
    if not isinstance(found, Measurement):
        raise InputTypeError(f"measure() must return a vmcl.cues.Measurement, got {type(found).__name__}")
    for name in ("data", "confidence", "coupling"):
        value = getattr(found, name)
        if not (isinstance(value, cl_array.Array) or (name == "confidence" and value is None)):
            raise InputTypeError(f"its Measurement's {name} must be a device array (pyopencl.array.Array, e.g. "
                                 f"run.machine.to_device(x)), got {type(value).__name__}")
    undeclared = sorted(set(found.fields) - set(cue.fields))
    if undeclared:  # passed on to Result, they would crash it or overwrite what another fills
        raise InputValueError(f"its Measurement holds fields {undeclared} that the cue does not declare in its "
                              f"fields {tuple(cue.fields)}")
    return found


def _device_lines(found: Restoration) -> tuple[cl_array.Array, cl_array.Array]:
    """A restoration's line fields (line_h, line_v), on the device where the run's restorations are."""
    return on_device(found.line_h), on_device(found.line_v)


class _Run:
    """One run of the machine: the stages in order, each timed, the fields kept on the device."""

    def __init__(self, vm: VisionMachine, image: np.ndarray, others: dict[str, np.ndarray],
                 progress: Callable[[str], None] | None, memory: temporal.Memory | None, *,
                 notes: Sequence[str] = (), measure_only: bool = False) -> None:
        self.m, self.c = vm.machine, vm.config
        self.progress = progress
        self.memory, self.carries = memory, False
        self.stages: dict[str, float] = {}
        self.notes: list[str] = list(notes)
        if self.m.profile:
            self.m.timings(reset=True)  # only this run's kernels
        active = vm.cues(right="right" in others, next="next" in others, rgb=image.ndim == 3)
        for given in ("right", "next"):  # an image given and read by nothing: said, not dropped in silence
            if given in others and not any(given in cue.needs for cue in active):
                self.notes.append(f"{given}: given but not used: no cue that reads it is enabled")
        if vm.labeller is not None:  # before any stage runs: a weights file without this run's inputs
            try:
                vm.labeller.for_inputs([cue.name for cue in active if cue.name in CUES])
            except InputError as error:
                raise type(error)(f"labels.weights ({self.c.labels.weights or 'the shipped ones'}): {error}") from None
        with self.stage("upload"):
            left = self.m.to_device(image)
            others_d = {name: self.m.to_device(array) for name, array in others.items()}
        if memory is not None:
            with self.stage("time"):
                self.carries = memory.begin(left)
            if memory.broken is not None and memory.broken_share > self.c.time.scene_cut:
                self.notes.append(f"time: {memory.broken_share:.0%} of the pixels changed since the previous "
                                  "frame (a scene cut): this frame starts cold")
        with self.stage("edges"):
            e = self.c.edges
            try:
                canny = edges.canny(left, sigma=e.sigma, low_threshold=e.low_threshold,
                                    high_threshold=e.high_threshold, use_quantiles=e.use_quantiles,
                                    return_gradient=True, machine=self.m)
            except InputError as error:  # a limit that depends on the image (sigma's, by its size)
                raise type(error)(f"edges (the [edges] settings on this image): {error}") from None
            brightness = on_device(canny.edges)
            if e.low_threshold is None and e.high_threshold is None and not e.use_quantiles:
                self._note_no_edges(image, brightness)
        self.grouping = None
        if self.c.grouping.enabled or e.saliency != "none":
            with self.stage("grouping"):
                self.grouping, brightness = self.group(image, canny)
        image_boundaries = None
        if self.c.labels.boundary_probability:
            with self.stage("boundaries"):
                image_boundaries = on_device(boundary_probability.boundary_probability(left,
                                                                                       machine=self.m).probability)
        prediction = None
        # The previous flow carried to this frame: for the motion search, and for the refinement's prior.
        wants_prior = self.c.time.flow_prior > 0 and self.c.motion.variational_iterations > 0
        if self.carries and (self.c.time.predict_search or wants_prior) and "next" in others:
            carried = memory.carry("motion") if memory is not None else None
            prediction = carried.prediction if carried is not None else None
        # A stream's frames come from one rig: what belongs to the cameras is measured again every
        # VIEW_RECHECK frames (a first frame too dark or blank to measure is not the stream's last word).
        new_view = not self.carries or memory is None or memory.frame % VIEW_RECHECK == 0
        run = RunInputs(self.m, self.c, left, others_d.get("right"), others_d.get("next"), brightness, prediction,
                        new_view=new_view)
        measured = {}
        # A left image of one brightness holds nothing to match: the matchers' winners there are their scans'
        # first disparity or motion, confirmed by equally blind checks, which the MRF took as sure data.
        blank = bool(np.all(np.ptp(image.reshape(-1, image.shape[2] if image.ndim == 3 else 1), axis=0) == 0))
        for cue in active:
            with self.stage(cue.name):
                try:
                    measured[cue.name] = _checked_measurement(cue, cue.measure(run))
                except InputError as error:
                    # A built-in cue's module's own argument names (patch, levels) are its Config keys; a
                    # cue of the user's has no section.
                    where = f"the [{cue.name}] settings on this image" if cue.name in CUES else "a registered cue"
                    raise type(error)(f"{cue.name} ({where}): {error}") from None
                if blank and cue.needs & {"right", "next"}:
                    blind = measured[cue.name]
                    # Its raw fields too: a float field without values, a mask without pixels.
                    fields = {name: self.m.full(array.shape, array.dtype, np.nan if array.dtype.kind == "f" else 0)
                              for name, array in blind.fields.items()}
                    measured[cue.name] = dataclasses.replace(
                        blind, data=self.m.full(blind.data.shape, np.float32, np.nan), confidence=None,
                        fields=fields)
                    self.notes.append(f"{cue.name}: the left image has one brightness everywhere, so there is "
                                      "nothing to match: no data")
            self.notes.extend(measured[cue.name].notes)
        if measure_only:
            self.measured = {name: CueData(m.data.get(), None if m.confidence is None else m.confidence.get(),
                                           m.coupling.get().astype(bool)) for name, m in measured.items()}
            return
        fields = {name: array for m in measured.values() for name, array in m.fields.items()}
        lines, restored = {}, {}
        for cue in active:
            with self.stage(f"mrf {cue.name}"):
                found = self.restore(cue, measured[cue.name])
            refine = cue.refine_stage(self.c)
            if refine:
                # Run through (empty where nothing was restored), so that progress and Result.stages see
                # every stage VisionMachine.stages lists.
                with self.stage(refine):
                    if found is not None:
                        again = _checked_measurement(cue, cue.refine(run, measured[cue.name], _device_lines(found)))
                        fields.update(again.fields)
                        found = self.restore(cue, again) or found
            if found is not None:
                lines[cue.name], restored[cue.name] = _device_lines(found), on_device(found.field)
        if memory is not None:
            memory.end(restored.get("motion"))
        with self.stage("integrate"):
            # A depth line marks its nearer pixel: the occluding contour belongs to the occluder.
            owners = {"stereo": restored["stereo"]} if "stereo" in lines else None
            integration = _integrate.integrate(lines, edges=brightness, owners=owners, machine=self.m)
            support, labels = on_device(integration.support), on_device(integration.labels)
            strength = image_boundaries
            if vm.labeller is not None:
                found_labels = labelling.classify(
                    support, left, disparity=restored.get("stereo"), flow=restored.get("motion"),
                    hue=restored.get("colour"), texture="texture" in lines, labeller=vm.labeller,
                    probability=image_boundaries, machine=self.m)
                labels, strength = on_device(found_labels.labels), on_device(found_labels.strength)
        with self.stage("download"):
            host: dict[str, Any] = {name: array.get() for name, array in fields.items()}
            host_restored = {cue: array.get() for cue, array in restored.items()}
            host_lines = {cue: (h.get().astype(bool), v.get().astype(bool)) for cue, (h, v) in lines.items()}
            edge_map, host_support, host_labels = brightness.get(), support.get(), labels.get()
            # Without the image's probability the "rule" labels leave no strength: the labelled pixels are
            # it (not every support bit: a brightness edge no cue marks is labelled none).
            host_strength = (strength.get() if strength is not None
                             else (host_labels != 0).astype(np.float32))
        as_bool = ("colour_edges", "texture_edges", "stereo_discontinuity", "half_occluded", "out_of_range")
        host = {name: (value.astype(bool) if name in as_bool else value) for name, value in host.items()}
        for cue in active:
            if cue.restored_as and cue.name in host_restored:
                host[cue.restored_as] = host_restored[cue.name]
        self.result = Result(image=image, edges=edge_map.astype(bool), grouping=self.grouping,
                             support=host_support, labels=host_labels,
                             boundary_strength=host_strength, config=self.c, restored=host_restored, lines=host_lines, stages=self.stages,
                             kernels=self.m.timings(reset=True) if self.m.profile else {}, notes=self.notes,
                             **host)
        if vm.library is not None:
            with self.stage("recognition"):
                # On the left image's own edges, at the scale the models were learned at; a stereo run's
                # disparity explains the boundary its nearer surfaces hide.
                settings = self.c.recognition
                # transform: a str the Config checked against TRANSFORMS (a Config field cannot be a Literal).
                self.result.recognition = recognize(image, vm.library,
                                                    transform=settings.transform,  # type: ignore[arg-type]
                                                    candidates=settings.candidates,
                                                    scales=(settings.min_scale, settings.max_scale),
                                                    depth=self.result.disparity,
                                                    machine=self.m)
                if not self.result.recognition:
                    # An object nearer or farther than when learned lies outside the sizes searched.
                    self.result.notes.append(
                        f"recognition: no object found at the sizes searched, {settings.min_scale:g} to "
                        f"{settings.max_scale:g} times the learned examples' ([recognition] min_scale and "
                        "max_scale widen them)")

    def group(self, image: np.ndarray, canny: edges.CannyResult) -> tuple[Grouping, cl_array.Array]:
        """The grouping of Canny's edges, and the edges the MRFs are coupled to (``edges.saliency``)."""
        g = self.c.grouping
        canny_edges = on_device(canny.edges)
        found = group(canny_edges, magnitude=canny.magnitude, image=image, threshold=g.threshold,
                      length_exponent=g.length_exponent, curvature_scale=g.curvature_scale, gap=g.gap,
                      alignment=g.alignment, machine=self.m)
        saliency = self.c.edges.saliency
        if saliency == "local":
            self._note_pruned_away(found.salient, canny_edges, "local")
            return found, self.m.to_device(found.salient.astype(np.uint8))
        if saliency == "structural":
            strength = on_device(saliency_strength(canny_edges, canny.magnitude, machine=self.m))
            network = structural_saliency(canny_edges, tangent=self.m.to_device(np.asarray(found.curves.tangent)),
                                          strength=strength,
                                          iterations=g.iterations, gap_attenuation=g.gap_attenuation, machine=self.m)
            # The measure the threshold was fitted to (vmcl.boundary_evaluation.structural_saliency_sweep):
            # the network's saliency times the edge's own strength.
            measure = on_device(network.saliency).get() * strength.get()
            kept = (measure >= g.structural_threshold) & canny_edges.get().astype(bool)
            self._note_pruned_away(kept, canny_edges, "structural")
            return found, self.m.to_device(kept.astype(np.uint8))
        return found, canny_edges

    def _note_no_edges(self, image: np.ndarray, found: cl_array.Array) -> None:
        """A note when the noise rule's thresholds left no edge in an image that is not of one brightness:
        they come from the median gradient, which a texture filling the image raises above every edge, and
        every MRF is then coupled to no brightness edge."""
        # The grey the edges are found in: an image of one colour, or whose colour changes at one brightness,
        # has no brightness edge to find, and no threshold is to blame.
        grey = image @ np.asarray(GREY_WEIGHTS, np.float32) if image.ndim == 3 else image
        if np.ptp(grey) < 1e-6 * full_scale(image.dtype) or int(cm_reduce.reduce(found, "sum", machine=self.m).get()):
            return
        self.notes.append("edges: Canny found no brightness edge: the noise rule's thresholds (from the median "
                          "gradient, which a texture filling the image raises) lie above every gradient, so the "
                          "cues' MRFs are coupled to no brightness edge; set [edges] low_threshold and "
                          "high_threshold (gradient magnitudes, the image in [0, 1]; or, with use_quantiles = "
                          "true, quantiles of the gradient magnitudes, e.g. 0.7 and 0.9)")

    def _note_pruned_away(self, kept: np.ndarray, canny_edges: cl_array.Array, kind: str) -> None:
        """A note when the saliency pruning kept none of Canny's edges, which leaves the MRFs coupled to none."""
        if not np.any(kept) and (found := int(np.count_nonzero(canny_edges.get()))):
            threshold = self.c.grouping.structural_threshold if kind == "structural" else self.c.grouping.threshold
            self.notes.append(f"edges: the {kind} saliency pruning kept none of the {found} edge pixels (its "
                              f"threshold {threshold:g} was fitted on photographs, whose edges differ in contrast "
                              "and length; an image whose edges are all alike can fall below it): the MRFs are "
                              "coupled to no brightness edge; lower grouping's threshold or set edges.saliency = "
                              '"none"')

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        start = time.perf_counter()
        yield
        self.m.finish()  # a stage's time includes its device work
        self.stages[name] = (time.perf_counter() - start) * 1e3
        if self.progress is not None:
            self.progress(name)

    def restore(self, cue: CueModule, measured: Measurement) -> Restoration | None:
        """Restore one cue's measurement coupled to its edges (None, with a note, when it holds no data).

        In a stream with the temporal terms on, the measurement is first fused with the cue's previous
        restoration carried to this frame, which is also the MRF's warm start (:mod:`vmcl.temporal`).
        """
        data, confidence, start, warm = measured.data, measured.confidence, None, False
        if self.memory is not None:
            carried = self.memory.carry(cue.name) if self.carries else None
            jump = self.c.time.jump if cue.kind == "smooth" else math.inf
            data, confidence, fused_start = self.memory.fuse(data, confidence, carried, jump)
            if carried is not None and self.c.time.warm:
                start, warm = fused_start, True
        settings = self.c.mrf.settings(cue.name, cue.settings, warm=warm)
        try:
            if self.c.mrf.cross_validate:
                settings = self.cross_validated(cue, settings, data, confidence, measured.coupling)
            found = _integrate.restore_cue(data, confidence=confidence, coupling=measured.coupling,
                                           kind=cue.kind, candidates_only=cue.candidates_only,
                                           settings=settings, method=self.c.mrf.method, seed=self.c.mrf.seed,
                                           start=start, machine=self.m)
        except NothingToRestore:
            # The one refusal a good run can meet: the module found nothing (no match, no flow, no
            # valid hue) for the MRF to restore. The cue is then absent from the result.
            self.notes.append(f"{cue.name}: the early module gave no data, so no {cue.name} field or "
                              "discontinuities")
            return None
        if self.memory is not None and confidence is not None:
            self.memory.remember(cue.name, on_device(found.field), confidence, nearest=cue.kind == "constant")
        return found

    def cross_validated(self, cue: CueModule, settings: Settings, data: Any, confidence: Any, coupling: Any) -> Settings:
        """``settings`` with the data weight chosen on this image by held-out measurements (a note says which)."""
        model = settings.model
        if cue.candidates_only:
            model = dataclasses.replace(model, require_edge=True)
        try:
            chosen = learn.cross_validate(data, confidence=confidence, edges=coupling, kind=cue.kind, model=model,
                                          method=self.c.mrf.method, schedule=settings.schedule(self.c.mrf.method),
                                          seed=self.c.mrf.seed, machine=self.m)
        except InputValueError as error:
            # Too few measurements to hold any out: the cue keeps its own weight.
            self.notes.append(f"{cue.name}: no cross-validation ({error}); alpha {model.alpha:g} kept")
            return settings
        self.notes.append(f"{cue.name}: data weight alpha {chosen.alpha:g} chosen by cross-validation "
                          f"({model.alpha:g} without)")
        return settings.override({"alpha": chosen.alpha})
