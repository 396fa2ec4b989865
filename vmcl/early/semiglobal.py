"""Dense stereo by the census data term and min-sum message passing along scanlines (semi-global matching).

Seed sections "Stereo" and "Organization of integration": the stereo MRF's energy over a disparity per
pixel is a data term plus a smoothness term whose line process pays for discontinuities, and
discontinuities are cheaper where the brightness changes. Here the data term is the census transform's
Hamming distance (Zabih and Woodfill: each pixel described by which neighbours are darker, robust to the
two cameras' different gains and to the outliers a depth edge brings into a window); the smoothness term
charges ``p1`` for a change of one disparity and ``p2`` for a jump, ``p2`` lowered where the brightness
changes between the two pixels. The energy is minimised exactly along each scanline by min-sum
messages (a 1-D dynamic program), along 4 (or 8) directions, and the messages summed
(Hirschmueller's semi-global matching): the MRF's minimum approximated in a fixed number of sweeps,
one work-item per scanline (a few neighbouring ones on a CPU).

Both views' winners come from the one sum of messages. A left winner the right view does not confirm
(left-right consistency) has no value, and is told apart as half-occluded (no right pixel on its row
points back to it, and a nearer surface on its right can hide it: the right camera does not see it) or
mismatched (one does, or no nearer surface lies on its right). Kept winners are moved to
a fraction of a pixel by the equiangular (V) fit through their neighbours' sums.

References
----------
R. Zabih and J. Woodfill, "Non-parametric local transforms for computing visual correspondence", ECCV 1994.
J. Immerkaer, "Fast noise variance estimation", Computer Vision and Image Understanding 64(2), 1996.
H. Hirschmueller, "Stereo processing by semiglobal matching and mutual information", IEEE PAMI 30(2), 2008.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm.core import (
    ArrayLike,
    check_bool,
    check_int,
    check_real,
    check_unit_image,
    finite_float32,
    launch_rows,
    machine_for,
    mask_result,
    vector_kernel,
)
from vmcl.cm.reduce import reduce
from vmcl.cm.scan import box_sum
from vmcl.early.disparity_range import range_to_search
from vmcl.early.filters import channel_planes, grey_field
from vmcl.early.noise import threshold_field
from vmcl.early.stereo import check_pair
from vmcl.early.weighted_median import check_sigma_colour, weighted_median
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["AD_CAP", "AD_COLOUR", "AD_WEIGHT", "CENSUS_BITS", "CENSUS_THRESHOLD", "CPU_SCANLINES_PER_ITEM", "DIRECTIONS",
           "EDGE_GAIN", "JUMP", "MATCH_EXPOSURE", "OCCLUSION_GEOMETRY", "P1", "P2", "PATHS", "POOR_MATCH",
           "REFINE_COLOUR", "REFINE_RADIUS", "REFINE_STRIDE", "TONE_BINS", "TONE_STEPS", "SemiGlobalMatch",
           "check_paths", "match_semiglobal", "max_p2"]

CENSUS_SIZE = (9, 7)  # width, height of the census window: 62 neighbours in a 64-bit code
CENSUS_BITS = CENSUS_SIZE[0] * CENSUS_SIZE[1] - 1
"""Bits of a census code, the largest matching cost."""

DIRECTIONS = {8: ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1), (1, -1), (-1, 1)),
              4: ((1, 0), (-1, 0), (0, 1), (0, -1))}
"""The scanline directions (dx, dy) messages are passed along, for 8 and 4 paths, in opposite pairs (one launch
of the message kernel passes them along a pair's first direction and back)."""

# The defaults, fitted on the training pairs by the stereo machine's fit (benchmarks/stereo_fit.py, whose
# results/stereo_fit.md gives every combination tried): never on a pair a benchmark reports.
CENSUS_THRESHOLD = 3.0
"""Default census margin, in units of the noise's standard deviation."""
AD_WEIGHT = 4.0
"""Default weight of the pixels' absolute brightness difference in the data term, in census bits per noise
standard deviation (0: the census alone; benchmarks/results/stereo_fit.md, stage 2)."""
AD_COLOUR = False
"""Default: the brightness difference of a colour pair is the grey levels' (True: the mean of its channels')."""
AD_CAP = 8.0
"""The absolute difference counts up to this many noise standard deviations."""
P1 = 96
"""Default price of a change of one disparity between neighbours, in census bits (stage 6 of the fit)."""
P2 = 96.0
"""Default price of a jump where the brightness does not change, in census bits (stage 6 of the fit: on the
training pairs a larger jump price than P1 did not pay)."""
EDGE_GAIN = 0.0
"""Default lowering of the jump's price per unit of noise in the brightness change (stage 6 of the fit)."""
PATHS = 4
"""Default number of scanline directions the messages are passed along (:data:`DIRECTIONS`): with every other
setting fitted, 4 scored better on the training pairs than 8, at half the passes
(benchmarks/results/stereo_fit.md, stage 6)."""

REFINE_RADIUS = 9
"""Default radius of the weighted median's window at depth jumps, in pixels (its spatial scale too)."""
REFINE_COLOUR = 0.1
"""Default colour distance (in [0, 1] levels) at which a voter of the weighted median weighs 1/e."""
REFINE_STRIDE = 2
"""Default step between the weighted median's voters, in pixels (2: a quarter of the window votes)."""
JUMP = 1.5
"""Neighbours differing by more than this many pixels of disparity mark a jump the weighted median refines."""

POOR_MATCH = 0.25
"""A winner at an end of the range is out of range when its cost there exceeds this share of the largest
cost (every census bit differing, and the brightness difference at its cap): where the search stopped,
the match is poor; a good match at the end is kept, since a range may end right at a true disparity."""

MATCH_EXPOSURE = True
"""Default: the cameras' exposure difference is measured and taken out before the brightness difference
(benchmarks/results/stereo_fit.md, stage 2)."""
OCCLUSION_GEOMETRY = True
"""Default: an unconfirmed pixel is half-occluded only where a nearer surface on its right can hide it
(benchmarks/results/stereo_fit.md, stage 5)."""
TONE_BINS = 32
"""Bins of the pair's mean brightness, over the two views' joint span, in which the cameras' difference is
measured (TONE_BINS in kernels/semiglobal.cl)."""
TONE_STEPS = 2 * 128 + 1
"""Steps of the histogram of a bin's differences: 1/512 of the joint span each, 128 either way (TONE_STEPS in
kernels/semiglobal.cl)."""
# Not fitted (the training pairs say only that the measurement works): a sure match is one whose census
# differs in at most a quarter of its bits, with no other disparity, its neighbours apart, within 6 bits
# (a tenth of the code) of it; a bin's own median needs 64 votes, enough for the median of differences of
# two noisy pixels to settle within about a fifth of their spread.
_TONE_SURE = CENSUS_BITS // 4
_TONE_MARGIN = 6
_TONE_LEAST = 64

_NOISE_MEDIAN = 0.6745 * 6
"""The median magnitude of Immerkaer's mask on Gaussian noise, in units of the noise's standard deviation."""
_LINES_PER_GROUP = 16
"""Scanlines per work-group of the message kernel (its work-items: this over the lines a work-item takes,
at least one): left to the device, PoCL put a whole direction's lines in one work-group, which one CPU
thread runs; in groups of 16 lines every core takes a share."""
CPU_SCANLINES_PER_ITEM = 8
"""Scanlines a work-item of the message kernel steps along in turn on a CPU (LINES in kernels/semiglobal.cl):
a core waits on each step's minimum over the disparities, and other lines' steps fill the wait (each line
more holds its own private messages). A GPU hides the wait with other work-items and wants every line in a
work-item of its own."""
_LANES = 16  # disparities per vector in the message kernel (LANES in kernels/semiglobal.cl)
_PRIVATE_STEP = 64  # the private message arrays are sized in steps of this many disparities


@dataclass
class SemiGlobalMatch:
    """Dense disparities of the left view (host or device arrays, as the input was).

    disparity : float32 (H, W), d with I_left(x, y) = I_right(x - d, y), to a fraction of a pixel; NaN where
        the right view does not confirm the left winner.
    filled : float32 (H, W), ``disparity`` with the half-occluded pixels given their background's value
        (the smaller of the nearest kept disparities left and right on the row), or, where the frame hides
        them, the value of the surface on their right; with ``refine``, the pixels near depth jumps and
        the mismatched ones given the weighted median of the kept disparities around them (mismatched
        pixels without kept ones around stay NaN; without ``refine`` all do); out-of-range pixels NaN.
    occluded : bool (H, W) (uint8 0/1 on the device), half-occluded pixels: no disparity of the range is confirmed by the right view
        (and, with ``occlusion_geometry``, the nearest kept pixel on the row's right is nearer, by a pixel
        of disparity or more, than the nearest on its left, or one side has none); or the pixel is
        unconfirmed and the kept surface on its right, carried on to it, would be seen left of the right
        image (x < its disparity: the frame hides it).
    mismatched : bool (H, W) (uint8 0/1 on the device), unconfirmed pixels that are not half-occluded (the winner was wrong).
    out_of_range : bool (H, W) (uint8 0/1 on the device), pixels whose winner was an end of the range (d_min or d_max, where the
        image lets the range go on) with a poor cost there (above :data:`POOR_MATCH` of the largest
        cost): the search stopped there, so the match may lie beyond it (the seed's areas outside
        the matcher's disparity range). Unmatched, neither occluded nor mismatched.
    d_min, d_max : int, the range searched.
    """

    disparity: ArrayLike
    filled: ArrayLike
    occluded: ArrayLike
    mismatched: ArrayLike
    out_of_range: ArrayLike
    d_min: int
    d_max: int


def match_semiglobal(left: ArrayLike, right: ArrayLike, *, d_min: int | None = None, d_max: int | None = None,
                     census_threshold: float = CENSUS_THRESHOLD, ad_weight: float = AD_WEIGHT,
                     ad_colour: bool = AD_COLOUR, match_exposure: bool = MATCH_EXPOSURE, p1: int = P1, p2: float = P2,
                     edge_gain: float = EDGE_GAIN, paths: int = PATHS,
                     subpixel: bool = True, tolerance: int = 1, median: bool = True,
                     occlusion_geometry: bool = OCCLUSION_GEOMETRY, refine: bool = True,
                     refine_radius: int = REFINE_RADIUS, refine_colour: float = REFINE_COLOUR,
                     refine_stride: int = REFINE_STRIDE,
                     machine: Machine | None = None
                     ) -> SemiGlobalMatch:
    """Match a rectified pair densely: census costs, min-sum messages along scanlines, both views checked.

    Parameters
    ----------
    left, right : (H, W) or (H, W, 3) arrays or device arrays; uint8, uint16 or float
        The pair, rows being epipolar lines (as :func:`vmcl.early.stereo.match` takes it).
    d_min, d_max : int, optional
        The disparity range. Default: found from the images by
        :func:`vmcl.early.disparity_range.estimate_range`. An end given overrides that end, and the
        found other end moves to it if it would cross it (:func:`vmcl.early.disparity_range.range_to_search`):
        a given end beyond the range the images show leaves that one disparity to search, so give both.
    census_threshold : float
        >= 0: a neighbour sets its census bit when it is darker than the centre by more than this times the
        noise's standard deviation, estimated from the left view (J. Immerkaer's mask, with the median of
        its magnitude for the mean), so that noise on a flat patch leaves its bits unset rather than random.
    ad_weight : float
        In [0, 24]: the weight, in census bits per noise standard deviation, of the two pixels' absolute
        brightness difference (capped at :data:`AD_CAP` standard deviations) added to the census cost: a
        pixel's own evidence, which the census window's straddling of a depth edge does not blur (the
        AD-census cost of Mei et al., 2011, in the census's units). 0: the census alone.
    ad_colour : bool
        For a colour pair, take that difference as the mean of the R, G and B channels' absolute differences
        (as Mei et al. do), which tells apart surfaces of one grey but different hues; still in units of the
        grey's noise. False, or a grey pair: the grey levels' difference.
    match_exposure : bool
        Take that difference after moving the right view's brightness by the two cameras' difference,
        measured where the census match is sure (the median difference of such matches in each of
        :data:`TONE_BINS` brightness bins), so that differences of exposure and response between the
        cameras do not count as a mismatch (the census, which compares each pixel with its neighbours
        only, is blind to them). Differences up to a quarter of the two views' joint brightness span are
        measured. No effect when ``ad_weight`` is 0.
    p1 : int
        In [0, 255]: the price of a change of one disparity between neighbours (slanted surfaces), in
        census bits (a code has :data:`CENSUS_BITS`).
    p2 : float
        >= p1 and at most :func:`max_p2` of ``paths`` (7936 for 8 paths, 16128 for 4): the price of a larger
        jump (a depth discontinuity), where the brightness does not change.
    edge_gain : float
        >= 0: the jump's price between two pixels is ``max(p1, p2 / (1 + edge_gain * s))``, ``s`` their
        brightness difference in units of the noise's standard deviation (as for ``census_threshold``):
        discontinuities are cheaper at brightness edges. 0 keeps ``p2`` everywhere.
    paths : {8, 4}
        Directions the messages are passed along (:data:`DIRECTIONS`).
    subpixel : bool
        Move each kept winner to the vertex of the symmetric V through the summed costs at d - 1, d, d + 1
        (the equiangular fit: d + (s- - s+) / (2 (max(s-, s+) - s))), offsets within half a pixel; a
        winner at either end of the disparities that compete stays whole. Hamming costs grow linearly
        away from the match, which the V follows (on rendered slanted planes it came out closer than
        the parabola).
    tolerance : int
        >= 0: the most the right view's winner may differ from the left one's for the pixel to be kept.
    median : bool
        Replace each kept disparity by the median of the kept ones in its 3 x 3 neighbourhood (after the
        check, before the fill), which removes isolated wrong winners (Hirschmueller's filter);
        benchmarks/results/stereo.md gives the matcher with and without it.
    occlusion_geometry : bool
        Count an unconfirmed pixel as half-occluded only where the occlusion's geometry allows it: the kept
        surface on its right on the row is nearer, by a pixel of disparity or more, than the one on its left
        (only a nearer surface on its right hides a pixel of the left view from the right camera); other
        unconfirmed pixels are mismatched. False: every pixel no right pixel points back to is
        half-occluded (and takes its background's value). benchmarks/results/stereo_fit.md, stage 5.
    refine : bool
        Give every pixel within half a census window of a depth jump (neighbours of ``filled`` differing
        by more than :data:`JUMP`), and every mismatched pixel, the weighted median of the kept disparities
        around it, weighted by their likeness in colour to it (:func:`vmcl.early.weighted_median.weighted_median`):
        the census window carries the nearer surface's disparity up to half its width over the farther
        one, and the brightness edge between them says where each ends. Half-occluded pixels keep their
        background's value; out-of-range pixels stay without. A float pair on the host must hold
        brightness in [0, 1] (the colour scale's units).
    refine_radius : int
        >= 1: the weighted median's window radius, and its spatial scale, in pixels.
    refine_colour : float
        > 0: its colour scale (levels in [0, 1]).
    refine_stride : int
        >= 1: the step between its voters (its ``stride``).
    machine : vmcl.Machine, optional

    Returns
    -------
    SemiGlobalMatch

    Notes
    -----
    Where the pair has no texture (a patch, or the whole pair, of one brightness), every disparity costs the
    same and the messages decide: a patch takes the disparities of the textured surfaces around it, and a
    pair without any texture takes ``d_min`` (the frame's left edge, where a larger disparity's right pixel
    lies outside the image, tilts the messages towards it), confirmed by both views. The machine
    (:class:`vmcl.pipeline.VisionMachine`) notes a pair without texture and restores no disparity from it.

    The summed messages are 16-bit: ``paths`` messages of at most ``255 + p2`` each (a cost is a byte), so
    ``p2`` is at most ``65535 // paths - 255`` (:func:`max_p2`). The costs and sums take 3 bytes per pixel
    and disparity of device memory.

    Raises
    ------
    InputTypeError, InputValueError
        Not a pair of images of one shape and type; a range wider than the image or with |d| >= W; a
        parameter outside its range.
    """
    machine = machine_for(machine)
    check_pair(left, right, machine)
    left, right = (finite_float32(image, name) for name, image in (("left", left), ("right", right)))
    census_threshold = check_real(census_threshold, "census_threshold", minimum=0)
    # A cost must fit a byte: CENSUS_BITS + 24 * AD_CAP = 254.
    ad_weight = check_real(ad_weight, "ad_weight", minimum=0, maximum=24)
    ad_colour = check_bool(ad_colour, "ad_colour")
    match_exposure = check_bool(match_exposure, "match_exposure")
    p1 = check_int(p1, "p1", minimum=0, maximum=255)
    paths = check_paths(paths)  # before p2, whose largest value it sets
    p2 = check_real(p2, "p2", minimum=p1)
    if p2 > max_p2(paths):
        raise InputValueError(f"p2 must be at most {max_p2(paths)} with {paths} paths, got {p2}: the {paths} "
                              f"messages, up to 255 + p2 each, are summed in 16 bits (65535 at most)")
    edge_gain = check_real(edge_gain, "edge_gain", minimum=0)
    subpixel = check_bool(subpixel, "subpixel")
    tolerance = check_int(tolerance, "tolerance", minimum=0, maximum=2**31 - 1)
    median = check_bool(median, "median")
    occlusion_geometry = check_bool(occlusion_geometry, "occlusion_geometry")
    refine = check_bool(refine, "refine")
    for name, image in (("left", left), ("right", right)):
        if refine and isinstance(image, np.ndarray) and image.dtype == np.float32:
            # The weighted median's colour scale is in [0, 1] levels (the census is in units of the noise);
            # the pair shares one scale, so the right view is held to it too.
            check_unit_image(image, name)
    height, width = left.shape[:2]
    refine_radius = check_int(refine_radius, "refine_radius", minimum=1, maximum=2**31 - 1)
    # Checked here as the weighted median would, so that the error names this call's argument.
    refine_colour = check_sigma_colour(refine_colour, "refine_colour")
    refine_stride = check_int(refine_stride, "refine_stride", minimum=1, maximum=2**31 - 1)
    d_min, d_max = range_to_search(left, right, d_min, d_max, machine=machine)
    depth = d_max - d_min + 1
    cells = height * width * _LANES * math.ceil(depth / _LANES)
    machine.require_memory(f"semi-global matching of a {height} x {width} pair over {depth} disparities",
                           3 * cells + 40 * height * width, 2 * cells)
    host = isinstance(left, np.ndarray)
    images = [machine.to_device(image) if isinstance(image, np.ndarray) else image for image in (left, right)]
    views = [grey_field(machine, image) for image in images]
    if ad_colour and ad_weight > 0:
        levels = [channel_planes(machine, image) for image in images]
    else:
        levels = [view.reshape((1, height, width)) for view in views]
    dims = (np.int64(width), np.int64(height))
    costs, sums = _aggregate(machine, views, levels, d_min, depth, census_threshold, ad_weight, match_exposure, p1,
                             p2, edge_gain, paths)
    found = _select(machine, sums, costs, dims, d_min, depth, subpixel, tolerance, median, occlusion_geometry,
                    int(POOR_MATCH * (CENSUS_BITS + ad_weight * AD_CAP)))
    disparity, filled, occluded, mismatched, out_of_range = found
    if refine:
        filled = _refine(machine, filled, occluded, out_of_range, images[0], d_min, d_max, refine_radius,
                         refine_colour, refine_stride)
    return SemiGlobalMatch(disparity.get() if host else disparity, filled.get() if host else filled,
                           mask_result(occluded, host), mask_result(mismatched, host), mask_result(out_of_range, host),
                           d_min=d_min, d_max=d_max)


def max_p2(paths: int) -> int:
    """The largest ``p2`` :func:`match_semiglobal` takes with ``paths`` scanline directions: each of the
    ``paths`` messages summed in 16 bits is at most 255 + p2 (a cost is a byte), so ``paths * (255 + p2)``
    must not pass 65535 (7936 for 8 paths, 16128 for 4)."""
    return 65535 // check_paths(paths) - 255


def check_paths(paths: Any, name: str = "paths") -> int:
    """``paths``, a number of scanline directions :data:`DIRECTIONS` has (8 or 4); the errors name ``name``."""
    paths = check_int(paths, name)
    if paths not in DIRECTIONS:
        raise InputValueError(f"{name} must be 8 or 4, got {paths}")
    return paths


def _kernel(machine: Machine, name: str) -> cl.Kernel:
    """A kernel of kernels/semiglobal.cl but aggregate, all from one build: census's defines (the window,
    the vector width) are read by census alone, so the others take them too, one program on a first run
    where there were two. aggregate's message arrays are sized by the range, a build of its own."""
    return vector_kernel(machine, "semiglobal", name, CENSUS_W=CENSUS_SIZE[0], CENSUS_H=CENSUS_SIZE[1])


def _aggregate(machine: Machine, views: list[cl_array.Array], levels: list[cl_array.Array], d_min: int, depth: int,
               census_threshold: float, ad_weight: float, match_exposure: bool, p1: int, p2: float, edge_gain: float,
               paths: int) -> tuple[cl_array.Array, cl_array.Array]:
    """The (H, W, S) uint8 census costs and uint16 sum of the messages along every direction, S = D rounded
    up to whole vectors; ``views`` are the grey views (the census's), ``levels`` the (C, H, W) planes whose
    difference the costs add."""
    height, width = views[0].shape
    stride = _LANES * math.ceil(depth / _LANES)
    dims = (np.int64(width), np.int64(height))
    response = machine.empty((height, width), np.float32)
    machine.launch(_kernel(machine, "noise_response"), (width, height), views[0], response, *dims)
    # The noise's standard deviation from the median response of Immerkaer's mask (most pixels of most
    # images are smooth at its 3 x 3 scale; texture raises the median, which makes the census margin more
    # conservative, never less), kept on the device.
    to_sigma = 1 / _NOISE_MEDIAN
    noise, _ = threshold_field(machine, response, (0.5, 0.5, to_sigma, to_sigma), local=False)
    del response
    codes = [machine.empty((height, width), np.uint64) for _ in views]
    build = _kernel(machine, "census")
    for view, code in zip(views, codes):
        launch_rows(machine, build, width, height, view, code, *dims, np.float32(census_threshold), noise)
    levels = list(levels)
    if ad_weight > 0 and match_exposure:
        levels[1] = _exposure_matched(machine, codes, views, levels[1], d_min, depth)
    costs = machine.empty((height, width, stride), np.uint8)
    outside = CENSUS_BITS // 2 + round(ad_weight * AD_CAP / 2)
    machine.launch(_kernel(machine, "census_costs"), (width, height), *codes, *levels, np.int32(levels[0].shape[0]),
                   costs, *dims,
                   np.int32(depth), np.int32(stride), np.int32(d_min), np.uint8(outside), np.float32(ad_weight),
                   np.float32(AD_CAP), noise)
    del codes, levels
    sums = machine.empty((height, width, stride), np.uint16)
    per_item = CPU_SCANLINES_PER_ITEM if machine.is_cpu else 1
    aggregate = machine.kernel("semiglobal", "aggregate",
                               MAX_D=_PRIVATE_STEP * math.ceil(depth / _PRIVATE_STEP), LINES=per_item)
    # A launch passes messages along a direction and back (DIRECTIONS lists them in opposite pairs).
    for index, (dx, dy) in enumerate(DIRECTIONS[paths][::2]):
        lines = height if dy == 0 else width if dx == 0 else width + height - 1
        machine.launch(aggregate, (-(-lines // per_item),), costs, views[0], sums, *dims, np.int32(depth),
                       np.int32(stride), np.int32(dx), np.int32(dy), np.uint16(p1), np.float32(p2),
                       np.float32(edge_gain), noise,
                       np.int32(index == 0), local_size=(max(1, _LINES_PER_GROUP // per_item),))
    return costs, sums


def _exposure_matched(machine: Machine, codes: list[cl_array.Array], views: list[cl_array.Array],
                      levels: cl_array.Array, d_min: int, depth: int) -> cl_array.Array:
    """The right view's ``levels`` (its grey, or its colour planes) moved by the cameras' difference, per
    brightness bin, measured on the grey views' sure census matches (kernels/semiglobal.cl tone_votes); all
    on the device. Each colour channel takes the grey's move at its own level: one response curve for the
    three, which the grey's bins measure with three times the votes a channel's would have."""
    height, width = views[1].shape
    dims = (np.int64(width), np.int64(height))
    span = [reduce(view, op, machine=machine) for op in ("min", "max") for view in views]
    votes = machine.full((TONE_BINS, TONE_STEPS), np.int32, 0)
    machine.launch(_kernel(machine, "tone_votes"), (width, height), *codes, *views, votes, *dims,
                   np.int32(depth), np.int32(d_min), np.int32(_TONE_SURE), np.int32(_TONE_MARGIN), *span)
    offset = machine.empty((TONE_BINS,), np.float32)
    machine.launch(_kernel(machine, "tone_offsets"), (1,), votes, offset, np.int32(_TONE_LEAST), *span)
    moved = machine.empty(levels.shape, np.float32)
    machine.launch(_kernel(machine, "apply_tone"), (levels.size,), levels, moved, offset, np.int64(levels.size),
                   *span)
    return moved


def _refine(machine: Machine, filled: cl_array.Array, occluded: cl_array.Array, out_of_range: cl_array.Array,
            left: cl_array.Array, d_min: int, d_max: int, radius: int, colour: float, stride: int) -> cl_array.Array:
    """``filled`` with the pixels near its depth jumps, and the mismatched ones, given the weighted median of
    the kept disparities around them (half-occluded pixels keep theirs, out-of-range ones stay without)."""
    height, width = filled.shape
    dims = (np.int64(width), np.int64(height))
    flags = machine.empty((height, width), np.int32)
    machine.launch(_kernel(machine, "jump_flags"), (width, height), filled, flags, *dims, np.float32(JUMP))
    near = box_sum(flags, CENSUS_SIZE[0] // 2, machine=machine)
    where, voters = (machine.empty((height, width), np.uint8) for _ in range(2))
    machine.launch(_kernel(machine, "refine_targets"), (width, height), filled, occluded, out_of_range,
                   near, where, voters, *dims)
    refined = weighted_median(filled, left, low=d_min, high=d_max, where=where, voters=voters, radius=radius,
                              sigma_colour=colour, sigma_space=float(radius), stride=stride, machine=machine)
    assert isinstance(refined, cl_array.Array)  # device values in, device values out
    return refined


def _select(machine: Machine, sums: cl_array.Array, costs: cl_array.Array, dims, d_min: int, depth: int,
            subpixel: bool, tolerance: int, median: bool, geometry: bool, poor: int
            ) -> tuple[cl_array.Array, ...]:
    """Both views' winners, the check, and the filled disparity: (disparity, filled, occluded, mismatched,
    out_of_range)."""
    width, height = int(dims[0]), int(dims[1])
    stride = np.int32(sums.shape[2])
    disparity = machine.empty((height, width), np.float32)
    winners = [machine.empty((height, width), np.int32) for _ in range(2)]
    out_of_range = machine.empty((height, width), np.uint8)
    machine.launch(_kernel(machine, "select_left"), (width, height), sums, costs, disparity, winners[0],
                   out_of_range, *dims, np.int32(depth), stride, np.int32(d_min), np.int32(subpixel),
                   np.int32(poor))
    machine.launch(_kernel(machine, "select_right"), (width, height), sums, winners[1], *dims,
                   np.int32(depth), stride, np.int32(d_min))
    occluded, mismatched = (machine.empty((height, width), np.uint8) for _ in range(2))
    machine.launch(_kernel(machine, "check_views"), (width, height), disparity, *winners, out_of_range,
                   occluded, mismatched, *dims, np.int32(depth), np.int32(d_min), np.int32(tolerance))
    if median:
        smoothed = machine.empty((height, width), np.float32)
        launch_rows(machine, _kernel(machine, "median_kept"), width, height, disparity, smoothed, *dims)
        disparity = smoothed
    filled = machine.empty((height, width), np.float32)
    machine.launch(_kernel(machine, "fill_occluded"), (height,), disparity, occluded, mismatched, filled,
                   *dims, np.int32(geometry))
    return disparity, filled, occluded, mismatched, out_of_range
