"""Stereo: the Drumheller-Poggio matcher on the OpenCL machine, with the Vision Machine's improvements.

Seed section "Stereo": features of the two (registered) images are compared on potential match planes
p(x, y, d), one per disparity; each plane is summed over a patch (the local support) and the winner of
every left feature is chosen under the uniqueness and ordering constraints. The faithful "table"
variant builds every plane and sums it with grid-scans in time independent of the patch; the default
"running" variant uses that p is non-zero only at left features and only their support is ever
selected: it sums each left feature's support from the features of its window when it needs it (the
column sums of a band of rows slid down the image, as a box filter does) and folds it into the
winner at once, building no plane. The improvements the paper lists are here: Canny edges whose
gradient directions must agree (improvement 2), support normalised by the number of edges eligible to
match in the two patches (improvement 3), low normalised scores marking areas outside the disparity
range, bimodal vote histograms marking depth discontinuities, and support that stops at discontinuity
lines fed back from the integration stage. Matching brightness instead of edges ("we will explore
matching brightness values as well as edges") is the dense intensity variant.

References
----------
M. Drumheller and T. Poggio, "On parallel stereo", Proc. IEEE Int. Conf. Robotics and Automation, 1986.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 1988.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm import reduce as cm_reduce
from vmcl.cm import scan
from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_bool,
    check_choice,
    check_context,
    check_int,
    check_real,
    check_same_kind,
    check_same_scale,
    check_unmasked,
    machine_for,
)
from vmcl.cm.core import field as device_field
from vmcl.cm.filters import window_max
from vmcl.early.edges import canny, zero_crossings
from vmcl.early.filters import gaussian
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["Features", "Method", "StereoMatch", "check_pair", "check_range", "direction_code", "match", "match_features"]

Features = Literal["canny", "dog", "intensity"]
Method = Literal["running", "table"]
_METHODS: tuple[Method, ...] = ("running", "table")
_FEATURES: dict[Features, int] = {"canny": 0, "dog": 1, "intensity": 2}
# The intensity matcher's build of kernels/stereo.cl. Its helpers (moments, mean, sub-pixel fit) read no
# define, and are taken from this build too: one program for the whole intensity path on a first run.
_INTENSITY = {"FEATURES": _FEATURES["intensity"], "ATTR_T": "float"}
# On CPUs the intensity table's selection runs sixteen pixels per work-item (kernels/stereo.cl,
# select_table_lanes), bit for bit the scalar kernel's; a switch so that a test can hold the two equal.
_LANES_ON_CPU = True
_TABLE_BYTES = 256 << 20  # the largest table of match planes the default variant builds
_BAND = 32  # rows per work-item of match_edges (at least)
_MAX_RUNNING_PATCH = 181  # (2r + 1)^2 votes fit the running variant's int16 lanes
_SPAN = 16  # pixels of a row per work-item of match_edges_clipped and suppress (SPAN in kernels/stereo.cl)


@dataclass
class StereoMatch:
    """The matcher's output for the left view (host or device arrays, as the input was).

    disparity : float32 (H, W), d with I_left(x, y) = I_right(x - d, y); NaN where no match was kept. Whole
        pixels, but for intensity matches with ``subpixel``: the winner moved to its scores' parabola vertex.
    score : float32 (H, W), the winner's normalised score (before suppression); NaN off features.
    features : bool (H, W), the left features that took part (edges, zero crossings, or every pixel).
    out_of_range : bool (H, W), features whose best score stays below ``min_score``: the paper's sign of
        an area outside [d_min, d_max] (intensity matches, which take no ``min_score``: pixels no disparity
        could score).
    discontinuity : bool (H, W), features whose vote histogram over d has a second peak of at least
        ``bimodal`` times the first, 2 or more planes away: a depth discontinuity in the patch.
    d_min, d_max : int, the range searched (the one given, or the one found from the images).
    """

    disparity: ArrayLike
    score: ArrayLike
    features: ArrayLike
    out_of_range: ArrayLike
    discontinuity: ArrayLike
    d_min: int = 0
    d_max: int = 0




def check_pair(left: Any, right: Any, machine: Machine) -> None:
    """Refuse, naming ``left`` or ``right``, anything but a rectified pair of images the matcher takes: NumPy
    or device arrays of this machine (not one of each; device arrays whole and C-contiguous, not views),
    grey (H, W) or RGB (H, W, 3), of one shape, not empty, uint8, uint16, float32 or (on the host) another
    float, finite and within float32's range."""
    for name, image in (("left", left), ("right", right)):
        if not isinstance(image, (np.ndarray, cl_array.Array)):
            raise InputTypeError(f"{name} must be a NumPy array or a pyopencl.array.Array, got {type(image).__name__}")
        if isinstance(image, cl_array.Array):
            check_context(image, name, machine)
        check_unmasked(image, name)
        host_float = isinstance(image, np.ndarray) and image.dtype.kind == "f"
        # A big-endian uint16 is a uint16 (uploads convert it to the machine's byte order).
        if image.dtype.newbyteorder("=") not in IMAGE_TYPES and not host_float:
            raise InputTypeError(f"{name} must have dtype uint8, uint16 or float32 (or another float on the "
                                 f"host), got {image.dtype}")
        if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
            raise InputValueError(f"{name} must be grey (H, W) or RGB (H, W, 3), got shape {image.shape}")
        if isinstance(image, cl_array.Array):
            # Kernels take a device array's whole buffer: a view (strided, or with an offset) would be read as
            # something else, and refused deep inside by a helper's own name for it.
            device_field(image, name, machine, ndims=(2, 3), dtypes=tuple(IMAGE_TYPES))
    check_same_kind("left", isinstance(left, np.ndarray), "right", isinstance(right, np.ndarray))
    check_same_scale("left", left.dtype, "right", right.dtype)
    if left.shape != right.shape:
        raise InputValueError(f"left and right must have the same shape, got {left.shape} and {right.shape}")
    if 0 in left.shape[:2]:
        raise InputValueError(f"left and right must not be empty, got shape {left.shape}")
    for name, image in (("left", left), ("right", right)):
        # Device images are not checked: that would need a read back.
        if isinstance(image, np.ndarray) and image.dtype.kind == "f":
            if not np.isfinite(image).all():
                raise InputValueError(f"{name} has NaN or infinite pixels")
            if image.dtype.itemsize > 4 and np.abs(image).max() > np.finfo(np.float32).max:
                raise InputValueError(f"{name} has values beyond float32's range")


def _selection(min_score, bimodal, dip, min_votes, negative_evidence, direction_tolerance) -> dict:
    """The selection's numeric parameters, checked (the ranges in which they mean something)."""
    return {"min_score": check_real(min_score, "min_score"),
            "bimodal": check_real(bimodal, "bimodal", minimum=0, maximum=1),
            "dip": check_real(dip, "dip", minimum=0, maximum=1),
            "min_votes": check_real(min_votes, "min_votes", minimum=0),
            "negative_evidence": check_real(negative_evidence, "negative_evidence", minimum=0),
            "direction_tolerance": check_real(direction_tolerance, "direction_tolerance", minimum=0)}


def match(left: ArrayLike, right: ArrayLike, *, d_min: int | None = None, d_max: int | None = None, features: Features = "canny",
          patch: int = 11, sigma: float = 2.0, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False,
          direction_tolerance: float = math.radians(20),
          horizontal_tolerance: float = 10.0,
          min_score: float = 0.3, bimodal: float = 0.3, dip: float = 0.8, min_votes: float = 3.0,
          negative_evidence: float = 0.0, shiftable: bool = False, subpixel: bool = True,
          barriers: ArrayLike | None = None, method: Method | None = None,
          machine: Machine | None = None) -> StereoMatch:
    """Match a rectified (or registered) stereo pair over the disparity range [d_min, d_max].

    Parameters
    ----------
    left, right : (H, W) or (H, W, 3) arrays or device arrays; uint8, uint16 or float
        The pair, registered so that epipolar lines are rows (see :mod:`vmcl.early.registration`).
    d_min, d_max : int, optional
        The disparity range, d_min <= d_max, narrower than the image. Default: found from the images by
        :func:`vmcl.early.disparity_range.estimate_range`. An end given overrides that end, and the
        found other end moves to it if it would cross it (:func:`vmcl.early.disparity_range.range_to_search`):
        a given end beyond the range the images show leaves that one disparity to search, so give both.
    features : {"canny", "dog", "intensity"}
        "canny" (default): Canny edges, compatible when their gradient directions differ by at most
        ``direction_tolerance``. "dog": zero crossings of the difference of Gaussians, compatible when
        their signs agree (the original matcher). "intensity": every pixel, scored by the normalised
        cross-correlation of the smoothed brightness over the patch (dense). A disparity competes
        only where both patches lie inside the image: no match within ``patch // 2`` of the border, and
        near the left border (or, for negative disparities, the right) only the disparities whose right
        patch stays inside. Patches too flat for float32 to measure their variance do not match.
    patch : int
        Odd side of the support patch, >= 1.
    sigma : float
        Smoothing of the feature detector (Canny's Gaussian, the DoG's centre width, or the brightness
        smoothing for "intensity").
    low_threshold, high_threshold, use_quantiles
        Canny's thresholds (default: from its noise estimate, which assumes most of the image is not
        edge; on densely textured images give quantiles, e.g. 0.6 and 0.85 with ``use_quantiles``).
    direction_tolerance : float
        Radians, >= 0. Directions are compared as 16-bit codes, rounded to 1/65536 of a turn, and the
        tolerance is rounded down to whole codes.
    horizontal_tolerance : float
        Degrees: Canny edges closer than this to horizontal (their gradient direction's code closer to
        vertical) are not features, since along a scanline they cannot say where they match (the
        aperture problem). In [0, 90); 0 keeps every edge.
    min_score : float
        Edges and zero crossings whose best normalised score is below it are flagged out of range and left
        unmatched. Intensity matches ignore it and keep every score: a dense match's correlation is its
        weight downstream (:func:`vmcl.mrf.score_confidence`), not a cut-off, and the range estimate
        (:mod:`vmcl.early.disparity_range`) applies its own.
    bimodal, dip, min_votes : float
        Two peaks of the vote histogram over d count as separate when the votes between them fall to
        ``dip`` times the lower peak or less; when the lower of the strongest such pair reaches
        ``bimodal`` times the highest count (which needs ``min_votes`` votes), the feature is flagged
        as a discontinuity.
    negative_evidence : float
        >= 0; unmatched edges in the two patches, as a share of the patch area, times this, lower the
        score (the paper's planned negative evidence). 0 (default) is the plain normalised score.
    shiftable : bool
        Intensity only, without barriers: a pixel is scored at each d by the best of the (2r+1)^2
        patches that hold it, not only the one centred on it (shiftable windows, Bobick and Intille).
        Near a depth discontinuity some patch lies on the pixel's own side, so the nearer surface no
        longer spreads half a patch over the farther one; pixels within ``patch // 2`` of the border
        are then matched too, by patches further in. See the notes for how it compares.
    subpixel : bool
        Intensity only (edges and zero crossings ignore it: their support counts features, whose sums
        over neighbouring planes carry no peak to interpolate): refine each kept winner d to the vertex
        of the parabola through its scores at d - 1, d and d + 1 (see the notes). False keeps whole
        pixels. The winner itself, and so the uniqueness and ordering, are the same either way.
    barriers : bool (H, W), optional
        Discontinuity lines (from the integration stage, or ground truth): support windows stop at them,
        along rows and then along columns.
    method : {"table", "running"}, optional
        "table": the faithful version, every plane built (4 bytes per cell) and box-summed, then the
        selection walks the table. "running": no plane is stored. For edges and zero crossings, each
        left feature's support is summed from the features of its window, 16 disparities at a time,
        and folded into its winner at once (with barriers, over its clipped window directly); for
        intensity, each plane is summed and folded into the winners as it is made. Identical results.
        Default: running for edges and zero crossings (patch <= 181, the votes' 16-bit range); for
        intensity the table when it takes at most 256 MiB, else running.

    Returns
    -------
    StereoMatch

    Notes
    -----
    A pixel's winner is the disparity of highest score among the planes where it matches itself (ties:
    the smaller d). Uniqueness and ordering then run once over the winners: a winner is dropped when
    another winner on its row claims the same right pixel, or lies in its forbidden zone (reversing the
    left-right order), with a higher score.

    Shiftable windows (patch 11, sigma 1) lower the bad-1 rate of the dense intensity matches on
    Middlebury tsukuba, venus and teddy against centred windows, on the nonocc mask and most near
    discontinuities (disc mask); StereoSGBM, configured as OpenCV documents it, still does better on
    both masks. The match takes longer (benchmarks/results/stereo.md holds the rates and the times). Where the texture is sparse the best of many windows is more often a chance correlation:
    in the pipeline, dense bad-1 on the sparsely textured "cues" scene rose with shiftable windows.

    Sub-pixel refinement fits a parabola through the winner's normalised cross-correlations s-, s, s+ at
    d - 1, d, d + 1 and moves the disparity to its vertex, d + (s- - s+) / (2 (s- - 2 s + s+)), the offset
    clamped to [-0.5, 0.5] (it lies there already, the winner's score being the largest of the three).
    A parabola rather than the equiangular (V) fit: the correlation of smoothed brightness is smooth in d
    and close to quadratic around its peak, whereas the V shape suits costs with a kink at the minimum,
    such as sums of absolute differences. The neighbours' scores are those of the same windows as the
    winner's (shiftable: the best window at each d). A winner at d_min or d_max, or one whose neighbour
    did not compete (a window outside the image, a patch too flat to score), keeps its integer d.
    """
    machine = machine_for(machine)
    check_pair(left, right, machine)
    features = check_choice(features, "features", _FEATURES)
    if d_min is None or d_max is None:
        # Imported here: the range's estimate is itself made by this matcher (at a coarse scale, over a
        # given range), so its module imports this one.
        from vmcl.early.disparity_range import range_to_search

        d_min, d_max = range_to_search(left, right, d_min, d_max, machine=machine)
    _check_range(d_min, d_max, patch, left.shape[1])
    shiftable = check_bool(shiftable, "shiftable")
    subpixel = check_bool(subpixel, "subpixel")
    use_quantiles = check_bool(use_quantiles, "use_quantiles")
    sigma = check_real(sigma, "sigma", above=0)
    if shiftable and features != "intensity":
        raise InputValueError(f"shiftable windows score intensity patches: features must be 'intensity', got {features!r}")
    if shiftable and barriers is not None:
        raise InputValueError("shiftable windows take no barriers: a shifted patch already avoids the discontinuity")
    # From 90 degrees on no edge would be left.
    horizontal_tolerance = check_real(horizontal_tolerance, "horizontal_tolerance", minimum=0, below=90)
    selection = _selection(min_score, bimodal, dip, min_votes, negative_evidence, direction_tolerance)
    method = _plan(machine, features, left.shape[:2], d_min, d_max, patch, shiftable, barriers, method)
    maps = _feature_maps(machine, left, right, features, sigma, low_threshold, high_threshold, use_quantiles)
    min_angle = horizontal_tolerance * 65536 / 360 if features == "canny" else 0.0
    found = _match_maps(machine, maps, features, min_angle=min_angle, d_min=d_min, d_max=d_max, patch=patch,
                        **selection, shiftable=shiftable, subpixel=subpixel, barriers=barriers, method=method)
    return _deliver(found, isinstance(left, np.ndarray), d_min, d_max)


def match_features(left: ArrayLike, right: ArrayLike, left_attribute: ArrayLike, right_attribute: ArrayLike, *,
                   d_min: int, d_max: int, compatible: Literal["direction", "sign"] = "direction",
                   patch: int = 11, direction_tolerance: float = math.radians(20), min_score: float = 0.3,
                   bimodal: float = 0.3, dip: float = 0.8, min_votes: float = 3.0, negative_evidence: float = 0.0,
                   barriers: ArrayLike | None = None, method: Method | None = None,
                   machine: Machine | None = None) -> StereoMatch:
    """The matcher on feature maps computed elsewhere (the second half of :func:`match`).

    Parameters
    ----------
    left, right : bool or uint8 (H, W)
        Feature masks.
    left_attribute, right_attribute : (H, W)
        float32 gradient directions in radians (``compatible="direction"``), or int8 signs
        (``compatible="sign"``).
    The other parameters are :func:`match`'s.
    """
    machine = machine_for(machine)
    compatible = check_choice(compatible, "compatible", ("direction", "sign"))
    selection = _selection(min_score, bimodal, dip, min_votes, negative_evidence, direction_tolerance)
    hosts = {}
    features: Features = "canny" if compatible == "direction" else "dog"
    attr_type = np.float32 if compatible == "direction" else np.int8
    maps = {}
    for name, mask, attribute in (("left", left, left_attribute), ("right", right, right_attribute)):
        if isinstance(mask, np.ndarray) and mask.dtype == np.bool_:
            mask = mask.view(np.uint8)
        maps[name], host = device_field(mask, name, machine, ndims=(2,), dtypes=(np.uint8,))
        hosts[name] = host
        maps[name + "_attr"], _ = device_field(attribute, f"{name}_attribute", machine, ndims=(2,),
                                               dtypes=(attr_type,))
        if maps[name + "_attr"].shape != maps[name].shape:
            raise InputValueError(f"{name}_attribute must have the shape of {name}")
    check_same_kind("left", hosts["left"], "right", hosts["right"])
    check_pair(maps["left"], maps["right"], machine)
    shape = maps["left"].shape
    _check_range(d_min, d_max, patch, shape[1])
    method = _plan(machine, features, shape, d_min, d_max, patch, False, barriers, method)
    found = _match_maps(machine, maps, features, min_angle=0.0, d_min=d_min, d_max=d_max, patch=patch,
                        **selection, barriers=barriers, method=method)
    return _deliver(found, host, d_min, d_max)


def check_range(d_min: int, d_max: int, width: int) -> None:
    """Refuse, naming ``d_min`` or ``d_max``, a disparity range a matcher cannot search in an image
    ``width`` pixels wide: ends that are not integers, ``d_min > d_max``, more than ``width`` disparities,
    or a disparity of ``width`` or more either way (no pixel of the other view lies that far)."""
    width = check_int(width, "width", minimum=1)
    for name, value in (("d_min", d_min), ("d_max", d_max)):
        check_int(value, name)
    if d_min > d_max:
        raise InputValueError(f"d_min ({d_min}) must not exceed d_max ({d_max})")
    if d_max - d_min + 1 > width or max(abs(d_min), abs(d_max)) >= width:
        raise InputValueError(f"d_min and d_max: the disparity range [{d_min}, {d_max}] is wider than the image "
                              f"(width {width} pixels)")


def _check_range(d_min, d_max, patch, width: int) -> None:
    check_range(d_min, d_max, width)
    check_int(patch, "patch")
    if patch < 1 or patch % 2 == 0:
        raise InputValueError(f"patch must be an odd integer >= 1, got {patch}")


def _plan(machine: Machine, features: Features, shape: tuple[int, ...], d_min: int, d_max: int, patch: int,
          shiftable: bool, barriers, method: Method | None) -> Method:
    """The variant to run (the given one, checked, or the default), after checking that the device holds
    the tables it builds; before any work is done."""
    height, width = shape
    depth = d_max - d_min + 1
    table_bytes = depth * height * width * np.dtype(np.float32).itemsize
    if method is None:
        if features == "intensity":
            # Shiftable windows hold three tables at once: scores and the window maximum's two passes.
            tables = 3 if shiftable else 1
            method = "table" if tables * table_bytes <= _TABLE_BYTES else "running"
        else:
            method = "running" if patch <= _MAX_RUNNING_PATCH else "table"
    method = check_choice(method, "method", _METHODS)
    if method == "running" and features != "intensity" and patch > _MAX_RUNNING_PATCH:
        raise InputValueError(f"the running variant counts votes in 16 bits: patch must be <= {_MAX_RUNNING_PATCH}, "
                              f"got {patch} (use method='table')")
    if patch > min(height, width):
        # No patch would lie inside the image, so nothing could match.
        raise InputValueError(f"patch must be at most the image's smaller side, {min(height, width)} for this "
                              f"{height} x {width} image, got {patch}")
    # Tables alive at once: the planes and the box sum's two passes (the clipped sums' prefix and pass
    # with barriers; the shiftable scores and window maximum): the running variants hold at most one
    # plane, or _TABLE_BYTES of column sums.
    tables = (4 if barriers is not None or shiftable else 3) if method == "table" else 0
    per_pixel = 172  # feature maps, codes, counts, moments and their sums, selection, neighbours, outputs
    machine.require_memory(f"stereo matching of {height} x {width} pixels over {depth} disparities "
                           f"(method {method!r})",
                           tables * table_bytes + per_pixel * height * width + (_TABLE_BYTES if not tables else 0),
                           max(table_bytes if tables else 0, 16 * height * width))
    return method


def _deliver(found: list, host: bool, d_min: int, d_max: int) -> StereoMatch:
    if not host:
        disparity, score, features, out_of_range, discontinuity = found
        return StereoMatch(disparity, score, features, out_of_range, discontinuity, d_min, d_max)
    # All five copies queued at once, one wait: the first would otherwise wait for the whole match and
    # each further one for its own round trip.
    copies = [f.get_async() for f in found]
    cl.wait_for_events([event for _, event in copies])
    disparity, score, features, out_of_range, discontinuity = (array for array, _ in copies)
    return StereoMatch(disparity, score, features.view(np.bool_), out_of_range.view(np.bool_),
                       discontinuity.view(np.bool_), d_min, d_max)


def _match_maps(machine: Machine, maps: dict, features: Features, *, min_angle, d_min, d_max, patch,
                direction_tolerance, min_score, bimodal, dip, min_votes, negative_evidence, barriers, method,
                shiftable=False, subpixel=False) -> list:
    """Planes, support, selection and suppression on device feature maps, and for intensity with
    ``subpixel`` the refinement of the kept winners; returns the device outputs."""
    height, width = maps["left"].shape
    depth = d_max - d_min + 1
    radius = patch // 2
    if barriers is not None:
        if isinstance(barriers, np.ndarray) and barriers.dtype == np.bool_:
            barriers = barriers.view(np.uint8)
        barrier, _ = device_field(barriers, "barriers", machine, ndims=(2,), dtypes=(np.uint8,))
        if barrier.shape != (height, width):
            raise InputValueError(f"barriers must have the images' shape {(height, width)}, got {barrier.shape}")
    else:
        barrier = None
    support = _Support(machine, radius, barrier, (height, width))
    # The square windows of the running edge matcher count eligible features themselves.
    sliding = method == "running" and features != "intensity" and barrier is None
    if features == "intensity":
        common: Sequence[cl_array.Array] = (maps["left"], maps["right"], maps["left_attr"],
                                            maps["right_attr"])
        stats: cl_array.Array | None = support.sum(_moments(machine, maps))
        tolerance = np.int32(0)
    else:
        *common, counts = _codes(machine, maps, features, min_angle, counts=not sliding)
        stats = None if sliding else support.sum(counts)
        tolerance = np.int32(direction_code(direction_tolerance) if features == "canny" else 0)
    selection = [machine.empty((height, width), np.float32), machine.empty((height, width), np.int32),
                 machine.empty((height, width, 3), np.float32)]
    # The winners' neighbouring scores (kernels/stereo.cl, Around); the edge table's selection takes a
    # placeholder it never writes.
    around = machine.empty((height, width, 3) if features == "intensity" else (1,), np.float32)
    defines = _INTENSITY if features == "intensity" else {"FEATURES": _FEATURES[features], "ATTR_T": "ushort"}
    area = np.float32(patch * patch)
    dims = (np.int64(width), np.int64(height))
    build = machine.kernel("stereo", "match_planes", **defines)
    if method == "running" and features != "intensity" and not sliding:
        machine.launch(machine.kernel("stereo", "match_edges_clipped", **defines), (-(-width // _SPAN), height),
                       *common, stats, *support.window_bounds(), *selection, *dims,
                       np.int32(d_min), np.int32(d_max), np.int64(radius), tolerance, area,
                       np.float32(negative_evidence), np.float32(dip))
    elif sliding:
        # Each band keeps a short16 column sum per column and group of 16 disparities; taller bands
        # when many of them would need more than _TABLE_BYTES.
        band_bytes = width * (-(-depth // 16)) * 32
        band = max(_BAND, -(-height // max(1, _TABLE_BYTES // band_bytes)))
        bands = -(-height // band)
        scratch = machine.empty(bands * band_bytes // 2, np.int16)
        tallies = machine.empty(bands * 2 * width, np.int32)
        machine.launch(machine.kernel("stereo", "match_edges", **defines), (bands,), *common, scratch, tallies,
                       *selection, *dims, np.int64(band), np.int32(d_min), np.int32(d_max), np.int64(radius),
                       tolerance, area, np.float32(negative_evidence), np.float32(dip))
    elif shiftable:
        _select_shifted(machine, support, common, stats, [*selection, around], defines, method, d_min=d_min,
                        depth=depth, area=area, dip=dip, radius=radius)
    elif method == "table":
        planes = machine.empty((depth, height, width), np.float32)
        machine.launch(build, (width, height, depth), *common, planes, *dims, np.int64(depth), np.int32(d_min),
                       tolerance)
        arguments = (support.sum(planes), planes, common[0], stats, *selection, around, *dims, np.int64(depth),
                     np.int32(d_min), area, np.float32(negative_evidence), np.float32(dip), np.int64(radius))
        first_x = 0
        if features == "intensity" and machine.vector_width > 1 and _LANES_ON_CPU:
            # Sixteen pixels per work-item as SIMD lanes; select_table takes each row's tail.
            first_x = width // 16 * 16
            machine.launch(machine.kernel("stereo", "select_table_lanes", **defines), (width // 16, height),
                           *arguments, local_size=machine.row_local_size((width // 16, height)))
        machine.launch(machine.kernel("stereo", "select_table", **defines), (width - first_x, height), *arguments,
                       np.int64(first_x))
    else:
        plane = machine.empty((1, height, width), np.float32)
        fold = machine.kernel("stereo", "select_running", **defines)
        for k in range(depth):
            machine.launch(build, (width, height, 1), *common, plane, *dims, np.int64(1), np.int32(d_min + k),
                           tolerance)
            machine.launch(fold, (width, height), support.sum(plane), plane, common[0], stats, *selection,
                           around, *dims, np.int32(d_min + k), np.int32(k == 0), area, np.float32(negative_evidence),
                           np.float32(dip), np.int64(radius))
    outputs = [machine.empty((height, width), np.float32), machine.empty((height, width), np.float32),
               machine.empty((height, width), np.uint8), machine.empty((height, width), np.uint8)]
    machine.launch(machine.kernel("stereo", "suppress", **defines), (-(-width // _SPAN), height), common[0],
                   selection[0],
                   selection[1], selection[2], *outputs, *dims, np.int32(d_min), np.int32(d_max),
                   # Intensity matches keep every score (the docstring's min_score): their correlation weighs
                   # them downstream (vmcl.mrf.score_confidence, above its own floor), so no cut is made here.
                   np.float32(min_score if features != "intensity" else -np.inf), np.float32(bimodal),
                   np.float32(min_votes))
    disparity, score, out_of_range, discontinuity = outputs
    if features == "intensity" and subpixel:
        machine.launch(machine.kernel("stereo", "refine_subpixel", **_INTENSITY), (height * width,), disparity, selection[0],
                       around, np.int64(height * width))
    return [disparity, score, common[0], out_of_range, discontinuity]


def _select_shifted(machine: Machine, support: _Support, common, stats, selection, defines, method, *, d_min,
                    depth, area, dip, radius) -> None:
    """Intensity winners over shiftable windows: each plane's centred scores, their window maximum, folded
    (``selection``: best scores, winners, peaks and the winners' neighbouring scores).

    The table does it for all planes in one go; the running variant plane by plane (three planes' worth
    of memory instead of three tables).
    """
    height, width = selection[0].shape
    build = machine.kernel("stereo", "match_planes", **defines)
    score = machine.kernel("stereo", "intensity_scores", **defines)
    fold = machine.kernel("stereo", "select_scores", **defines)
    dims = (np.int64(width), np.int64(height))
    step = depth if method == "table" else 1
    for start in range(0, depth, step):
        count, d = min(step, depth - start), np.int32(d_min + start)
        planes = machine.empty((count, height, width), np.float32)
        machine.launch(build, (width, height, count), *common, planes, *dims, np.int64(count), d, np.int32(0))
        votes = support.sum(planes)
        del planes  # back to the pool before the scores and their maximum need theirs
        scores = machine.empty((count, height, width), np.float32)
        machine.launch(score, (width, height, count), votes, stats, scores, *dims, np.int64(count), d, area,
                       np.int64(radius))
        del votes
        machine.launch(fold, (width, height), window_max(scores, radius, machine=machine), common[0], *selection,
                       *dims, np.int64(count), d, np.int32(start == 0), np.float32(dip))


def direction_code(angle: float) -> int:
    """An angle in radians (>= 0) as a count of 1/65536 turns, the unit feature codes compare directions
    in (the tolerance: rounded down, so a code distance within it is an angle within it, up to the codes'
    own rounding of half a step, 0.0027 degrees); half a turn and more is 32768."""
    angle = check_real(angle, "angle", minimum=0)
    return min(math.floor(min(angle, math.pi) * 65536 / (2 * math.pi)), 32768)


def _codes(machine: Machine, maps: dict, features: Features, min_angle: float, *, counts: bool) -> list:
    """The left and right feature masks and 16-bit codes both matchers compare, and with ``counts`` the
    masks as a (2, H, W) float32 stack of counts, else None (kernels/stereo.cl, feature_codes); edges whose
    gradient lies within ``min_angle`` (in 1/65536 turns) of vertical are dropped."""
    height, width = maps["left"].shape
    n = height * width
    out = [machine.empty((height, width), np.uint8), machine.empty((height, width), np.uint8),
           machine.empty((height, width), np.uint16), machine.empty((height, width), np.uint16)]
    stack = machine.empty((2, height, width), np.float32) if counts else None
    source = {"SOURCE_T": "char", "SOURCE_T_IS_FLOAT": 0} if features == "dog" else {"SOURCE_T": "float",
                                                                                    "SOURCE_T_IS_FLOAT": 1}
    machine.launch(machine.kernel("stereo", "feature_codes", WITH_COUNTS=int(counts), **source), (-(-n // 16),),
                   maps["left"], maps["right"], maps["left_attr"], maps["right_attr"], *out,
                   stack if counts else out[0], np.float32(min_angle), np.int64(n))
    return [*out, stack]


def _moments(machine: Machine, maps: dict) -> cl_array.Array:
    """The planes whose patch sums the intensity score needs: L, L^2, R and R^2 as one (4, H, W) stack."""
    height, width = maps["left"].shape
    n = height * width
    stack = machine.empty((4, height, width), np.float32)
    machine.launch(machine.kernel("stereo", "intensity_moments", **_INTENSITY), (n,), maps["left_attr"], maps["right_attr"],
                   stack, np.int64(n))
    return stack


def _feature_maps(machine: Machine, left, right, features: Features, sigma: float, low, high,
                  quantiles: bool) -> dict:
    """Left and right feature masks (uint8) and attributes (direction, sign, or brightness) on the device."""
    maps = {}
    for side, image in (("left", left), ("right", right)):
        if isinstance(image, np.ndarray):
            image = machine.to_device(image.astype(np.float32) if image.dtype.kind == "f" else image)
        if features == "canny":
            found = canny(image, sigma=sigma, low_threshold=low, high_threshold=high, use_quantiles=quantiles,
                          return_gradient=True, machine=machine)
            maps[side], maps[side + "_attr"] = found.edges, found.direction
        elif features == "dog":
            crossings = zero_crossings(image, sigma=sigma, method="dog", machine=machine)
            maps[side], maps[side + "_attr"] = crossings.mask, crossings.sign
        else:
            brightness = gaussian(image, sigma=sigma, method="exact", machine=machine)
            # Centred on its mean, so the patch moments stay near the variances they are differenced
            # into: with uint8 brightness around 200, float32 rounding of the raw sums swamped a patch's
            # variance and the correlation left [-1, 1] (its value then depended on the mean level).
            total = cm_reduce.reduce(brightness, "sum", machine=machine)
            machine.launch(machine.kernel("stereo", "subtract_mean", **_INTENSITY), (brightness.size,), brightness, total,
                           np.int64(brightness.size))
            maps[side] = machine.full(brightness.shape, np.uint8, 1)
            maps[side + "_attr"] = brightness
    return maps


class _Support:
    """Window sums over the patch: plain box sums, or sums that stop at barrier lines."""

    def __init__(self, machine: Machine, radius: int, barrier: cl_array.Array | None, shape) -> None:
        self.machine, self.radius, self.barrier = machine, radius, barrier
        if barrier is not None:
            height, width = shape
            self.bounds = {}
            for along_rows in (1, 0):
                first, last = machine.empty(shape, np.int32), machine.empty(shape, np.int32)
                machine.launch(machine.kernel("stereo", "run_bounds"), (height if along_rows else width,),
                               barrier, first, last, np.int64(width), np.int64(height), np.int32(along_rows))
                self.bounds[along_rows] = (first, last)

    def window_bounds(self) -> tuple[cl_array.Array, ...]:
        """(first, last) of every pixel's barrier-free run along its row, then along its column, for
        kernels that clip windows themselves (only with barriers)."""
        return (*self.bounds[1], *self.bounds[0])

    def sum(self, planes: cl_array.Array) -> cl_array.Array:
        """Sum every plane of a (D, H, W) float32 stack over the support window."""
        if self.barrier is None:
            return scan.box_sum(planes, self.radius, machine=self.machine)
        machine = self.machine
        height, width = planes.shape[-2:]
        depth = planes.size // (height * width)
        data = planes
        for along_rows in (1, 0):
            prefix = scan.scan(data, axis=-1 if along_rows else -2, machine=machine)
            out = machine.empty(planes.shape, np.float32)
            first, last = self.bounds[along_rows]
            machine.launch(machine.kernel("stereo", "clipped_window"), (width, height, depth), prefix, first, last,
                           out, np.int64(width), np.int64(height), np.int64(self.radius), np.int32(along_rows))
            data = out
        return data
