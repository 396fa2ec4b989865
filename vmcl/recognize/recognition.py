"""Recognition in one call: selection, indexing, alignment and verification of a library's models.

Seed section "Recognition": "a three-stage recognition scheme": selection (:mod:`vmcl.recognize.selection`),
indexing (:mod:`vmcl.recognize.indexing`) and verification (:mod:`vmcl.recognize.verification`), on the
discontinuities the machine found. :func:`recognize` takes an image (its Canny edges), an edge map, the
machine's :class:`vmcl.result.Result` (its cartoon: the labelled discontinuities) or ready
:class:`vmcl.recognize.features.Features`, and returns the recognised objects, each with its model's name,
the view it was aligned from, its pose, its score and its boundary in the image.

Each verified candidate's significance is judged a contrario: -log10 of its number of false alarms, the
chance that its boundary support and its matched corners and arcs arise by accident among the image's edges
around it, times the candidates tested. Candidates are kept greedily, most significant first, each
scored again on the edge pixels no kept object explains yet (so a second reading of an object's edges
explains little), and one whose silhouette lies mostly on kept ones is dropped. A 3-D object's views are
aligned by an affine map near a similarity (a view near the one seen differs from it by a little
foreshortening in orthographic projection, Ullman and Basri's observation); a 2-D object's by
``transform``.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np
import pyopencl.array as cl_array
from scipy import special
from scipy.spatial import cKDTree

from vmcl.cm.core import check_bool, check_choice, check_int, check_real, machine_for
from vmcl.errors import InputTypeError
from vmcl.machine import Machine
from vmcl.recognize.arguments import real_map
from vmcl.recognize.features import Features, edge_features, features_of
from vmcl.recognize.indexing import MAX_CANDIDATES, Candidates, anchors_of, corner_pairs, index_for, vote
from vmcl.recognize.models import Library, View
from vmcl.recognize.selection import corner_regions, select_regions
from vmcl.recognize.verification import TRANSFORMS, Transform, carry, distance_transform, refine, support

__all__ = ["MIN_SIGNIFICANCE", "MIN_SIGNIFICANCE_DEPTH", "SCALES", "Detection", "recognize"]

MIN_SIGNIFICANCE = 19.0
""":func:`recognize`'s default ``min_significance`` on the image alone: the least that kept false detections to
at most 0.1 per image on rendered training scenes at the default ``tolerance`` (benchmarks/
recognition_fit.py, results/recognition_fit.md)."""

MIN_SIGNIFICANCE_DEPTH = 20.0
""":func:`recognize`'s default ``min_significance`` where a disparity map explains occlusion (``depth``, or a
Result's disparity): chosen by the same rule on the same training scenes rendered as stereo pairs, the
depth machine's disparity given (benchmarks/recognition_depth_fit.py, results/recognition_depth_fit.md).
Points a nearer surface hides leave an object's coverage, which raises every candidate's significance."""

SCALES = (0.5, 2.0)
""":func:`recognize`'s default ``scales``: objects half to twice their size in the examples they were learned
from."""

_CORNER_REACH = 3.0  # px: a view's corner and an image corner match this close,
_CORNER_TURN = np.radians(30)  # their bisectors this close in direction
_CORNER_OPENING = np.radians(25)  # and their openings this close
# A view's arc and an image arc match where their centres lie within this share of the radius (at least
# _CORNER_REACH px: a large circle's centre is placed less surely) and their radii within this factor.
_ARC_REACH = 0.1
_ARC_RADII = 1.15
_CORNER_ROUNDS = 3  # fits of a start from matched corners, each with the matches of the one before
_CORNER_STARTS = 16  # the candidates (best scored as refined so far) given a start from matched corners
_ANGLE = np.radians(25)  # the most a supporting edge's tangent may differ from the model's
_MARGIN = 10  # px around a pose over which the chance of support is measured
_SCREEN_POINTS = 96  # boundary points per candidate in the coarse test
_SCREEN_TOLERANCE = 4.0  # pixels
_NEARER = 1.0  # disparity: a surface this much nearer than an object hides it
_OVERLAP = 0.5  # a pose whose silhouette lies this much inside those kept already is dropped


@dataclass(frozen=True, eq=False)
class Detection:
    """One recognised object.

    Attributes
    ----------
    name : str
        Its model's name.
    view : int
        The model view it was aligned from.
    transform : float64 (3, 3)
        The pose: the homography taking the view's frame to the image (last row (0, 0, 1) for
        similarities and affine maps).
    score : float
        The fraction of the model's boundary (inside the image and not hidden by a nearer surface) that
        the image's edges support, each edge pixel counted once and none that an object kept before it
        explains: what ``min_score`` is tested against.
    votes : int
        The indexing votes of the candidate it came from.
    significance : float
        -log10 of its number of false alarms: how unlikely its support, and the corners and arcs it matches,
        are by chance, given how many candidates were tested and how crowded with edges the image is
        around it (kept where at least
        :func:`recognize`'s ``min_significance``).
    corners_found : float
        The fraction of the view's corners (those inside the image) that an image corner matches: within
        3 px, its bisector within 30 degrees and its opening within 25 (evidence the significance counts).
    corners : float64 (C, 2)
        The view's corners in the image, one per corner feature of the view: where more than two edges
        meet, each pair of them is a corner, so one point can appear more than once.
    boundary : float64 (N, 2)
        The view's boundary points in the image.
    supported : bool (N,)
        Which of them an image edge supports.
    inner_found : float
        The fraction of the view's inner markings (:attr:`vmcl.recognize.View.outline` False: a solid's
        edges between its faces, a flat object's print), of those inside the image and not hidden by a
        nearer surface (``depth``), that image edges support; NaN for a view with none there.
    """

    name: str
    view: int
    transform: np.ndarray
    score: float
    votes: int
    significance: float
    corners_found: float
    corners: np.ndarray
    boundary: np.ndarray
    supported: np.ndarray
    inner_found: float = float("nan")

    def locate(self, points: np.ndarray) -> np.ndarray:
        """Points (x, y) of the view's frame carried into the image by the pose."""
        return carry(self.transform, points)


def _depth(image: Any, depth: Any, shape: tuple[int, int]) -> np.ndarray | None:
    """The depth map occlusion is explained by: ``depth`` if given, else a Result's disparity, else None."""
    if depth is None and hasattr(image, "disparity") and hasattr(image, "config"):
        depth = image.disparity
    if depth is None:
        return None
    return real_map(depth, "depth", shape, "the image", unknown=True)


def _features(data: Any, sigma: float, machine: Machine) -> Features:
    if isinstance(data, Features):
        return data
    # A Result (duck-typed, so this layer does not import the pipeline): its cartoon's discontinuities.
    if hasattr(data, "labels") and hasattr(data, "edges") and hasattr(data, "config"):
        labels = np.asarray(data.labels) if data.labels is not None else None
        edges = labels != 0 if labels is not None and labels.any() else np.asarray(data.edges, bool)
        return edge_features(edges, machine=machine)
    if isinstance(data, (np.ndarray, cl_array.Array)):
        return features_of(data, sigma=sigma, machine=machine)
    raise InputTypeError("image must be an image or edge map (a NumPy or device array), a vmcl Result or "
                         "vmcl.recognize.Features, "
                         f"got {type(data).__name__}")


def recognize(image: Any, library: Library, *, transform: Transform = "similarity", sigma: float = 1.5,
              scales: tuple[float, float] = SCALES, min_score: float = 0.3, min_significance: float | None = None,
              min_support: int = 40, min_inner: float = 0.0,
              candidates: int = 1024, verify: int = 128, min_votes: int = 2, neighbours: int = 24, regions: int = 8,
              tolerance: float = 3.0, stretch: float = 1.1, arcs: bool = True, depth: np.ndarray | None = None,
              machine: Machine | None = None) -> list[Detection]:
    """Find a library's objects in an image.

    Parameters
    ----------
    image : array, Result or Features
        A grey or RGB image (its Canny edges at ``sigma``; a NumPy or device array), a bool edge map, a
        :class:`vmcl.result.Result` (its cartoon's discontinuities; the machine's own recognition stage reads
        the left image's edges instead, as models are learned from pictures, so the two can differ) or
        :class:`vmcl.recognize.features.Features`. The image side's corners are found at a turn of 45
        degrees, :func:`vmcl.recognize.learn`'s default ``corner``: a model learned at another finds other
        corners than the image shows.
    library : Library
    transform : {"similarity", "affine", "homography"}
        The pose a 2-D model is aligned by (3-D models' views: at least affine).
    sigma : float
        Canny's smoothing for an image, > 0.
    scales : (float, float)
        The sizes searched, as the object's size in the image over its size in the example it was learned
        from: by default half to twice (widen it for objects much nearer or farther than when learned; a
        wider range admits more small look-alikes among clutter).
    min_score : float
        The fraction of a model's boundary that must be supported, in (0, 1] (:attr:`Detection.score`:
        each edge pixel counted once, none that a detection kept before explains).
    min_significance : float, optional
        The least significance (-log10 of the number of false alarms, :attr:`Detection.significance`) a
        detection needs. The default is the least that kept false detections to at most 0.1 per image on
        rendered training scenes at the default ``tolerance``: :data:`MIN_SIGNIFICANCE` on the image alone,
        :data:`MIN_SIGNIFICANCE_DEPTH` where a disparity map explains occlusion (``depth``); it depends on the
        tolerance, so fit the two together; 0 is the a contrario criterion's own (one false alarm expected),
        which in clutter admits look-alikes.
    min_support : int
        The fewest distinct image edge pixels a detection explains, >= 1.
    min_inner : float
        In [0, 1]: the least fraction of a view's inner markings (:attr:`vmcl.recognize.View.outline`; a
        solid's edges between its faces) that image edges must support, where the view has some inside
        the image (and not hidden by a nearer surface, ``depth``). They are what tells a solid from a flat
        shape of its outline, which clutter often matches. 0: not required. The default was chosen on
        rendered training scenes (benchmarks/recognition_fit.py): no share required found as many objects
        there as any share tried, with no more false detections (benchmarks/results/recognition.md
        compares the test scenes with and without a share).
    candidates : int
        Pose bins kept from the vote, >= 1 (their hypotheses are pooled into candidate poses), shared
        between the model views: each keeps its own best up to an equal share, and a view with fewer
        leaves the rest to the others (:func:`vmcl.recognize.vote`), so that a large model, which gathers
        many votes by chance, cannot take a small one's share (each share shrinks as the library grows). The default was chosen on
        rendered training scenes with ``tolerance`` and ``neighbours`` (benchmarks/recognition_fit.py).
    verify : int
        Candidate poses refined and verified, >= 1: those a coarse test of each unrefined pose supports
        best.
    min_votes : int
        The fewest indexing votes a candidate needs, >= 1.
    neighbours : int
        Each of the image's features (a corner, or an arc's centre) is paired with this many nearest ones
        for indexing, >= 1 (a model view's with its 8 nearest, :func:`vmcl.recognize.index_for`). More
        pairs gather more chance votes, which compete for the same ``candidates``: raise the two together.
        The default was chosen on rendered training scenes (benchmarks/recognition_fit.py): two corners of
        one object may lie farther apart than a dozen of the clutter's.
    regions : int
        The most salient regions whose corners are also paired with their ``neighbours`` nearest of the
        same region (selection), >= 0.
    tolerance : float
        The distance (pixels) within which an edge supports a model point, > 0. The default is the one of
        those tried whose recognition rate at its own false-detection threshold was highest on rendered
        training scenes (benchmarks/recognition_fit.py): wide enough for a solid seen between its learned
        views.
    stretch : float
        The most a 3-D object's view alignment (an affine map near a similarity) may stretch one direction
        over the other, >= 1: a view near the one seen differs from it by a little foreshortening; more
        freedom fits clutter too. The default was chosen on rendered training scenes
        (benchmarks/recognition_fit.py).
    arcs : bool
        Index arcs (curve pieces on a circle) beside corners; without them a curved outline with fewer than
        two corners in view finds no candidate (benchmarks/results/recognition.md measures both).
    depth : (H, W) float array, optional
        A disparity map (larger nearer, NaN unknown; a Result's ``disparity`` by default): a model's points
        that find no edge where a surface nearer than the object lies are explained as occluded and left
        out of its coverage (the depth discontinuities explain the occlusion).
    machine : vmcl.Machine, optional

    Returns
    -------
    list of Detection
        In the order they were kept: most significant first.

    Notes
    -----
    The poses searched are rotations, scalings and shifts of the learned views (and their affine or
    projective maps): a mirror image of an object is none of them, and may be found as a rotation of the
    model that matches its outline but less of its markings (see :mod:`vmcl.recognize.models`). Learn the
    mirror image as a model of its own where the two must be told apart.
    """
    machine = machine_for(machine)
    if not isinstance(library, Library):
        raise InputTypeError(f"library must be a vmcl.recognize.Library, got {type(library).__name__}")
    transform = check_choice(transform, "transform", TRANSFORMS)
    sigma = check_real(sigma, "sigma", above=0)
    min_score = check_real(min_score, "min_score", above=0, maximum=1)
    if min_significance is not None:
        min_significance = check_real(min_significance, "min_significance")
    min_support = check_int(min_support, "min_support", minimum=1)
    min_inner = check_real(min_inner, "min_inner", minimum=0, maximum=1)
    candidates = check_int(candidates, "candidates", minimum=1, maximum=MAX_CANDIDATES)
    verify = check_int(verify, "verify", minimum=1)
    neighbours = check_int(neighbours, "neighbours", minimum=1)
    regions = check_int(regions, "regions", minimum=0)
    tolerance = check_real(tolerance, "tolerance", above=0)
    stretch = check_real(stretch, "stretch", minimum=1, maximum=1e6)
    arcs = check_bool(arcs, "arcs")
    features = _features(image, sigma, machine)
    if not arcs:
        features = replace(features, arcs=np.zeros((0, 2)), arc_radius=np.zeros(0), arc_middle=np.zeros((0, 2)))
    if not len(library) or len(features) + len(features.arcs) < 2:
        return []
    at, bisector, opening, radius = anchors_of(features)
    groups = None
    if regions:
        selected = select_regions(features.edges, features.saliency_map, machine=machine)
        # Arcs join no region's pairs: their centres need not lie in the region their curve bounds.
        groups = np.concatenate([corner_regions(selected, features.corners, features.bisector, top=regions),
                                 np.full(len(features.arcs), -1, np.int64)])
    pairs = corner_pairs(at, neighbours=neighbours, groups=groups)
    index = index_for(library)
    found = vote(index, at, bisector, opening, pairs, radius=radius, scales=scales, candidates=candidates,
                 min_votes=min_votes, machine=machine)
    depth = _depth(image, depth, features.shape)
    if min_significance is None:
        min_significance = MIN_SIGNIFICANCE if depth is None else MIN_SIGNIFICANCE_DEPTH
    return _verify(found, index.views, library, features, transform, min_score, min_significance, min_support,
                   min_inner, tolerance, verify, stretch, depth, machine)


def _gathered(found: Candidates, views: list[tuple[int, int, View]],
              most: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every candidate's view's boundary points and tangents, one after another (each thinned to about
    ``most`` when given), and each candidate's (start, stop) among them."""
    chosen = [views[row][2] for row in found.views]
    steps = [1 if most is None else max(1, len(v.points) // most) for v in chosen]
    points = [v.points[::k] for v, k in zip(chosen, steps)]
    tangents = [v.tangent[::k] for v, k in zip(chosen, steps)]
    sizes = np.array([len(p) for p in points], np.int64)
    stops = np.cumsum(sizes)
    return np.concatenate(points), np.concatenate(tangents), np.stack([stops - sizes, stops], axis=1)


def _screen(found: Candidates, views: list[tuple[int, int, View]], nearest: np.ndarray, tangent_map: np.ndarray,
            keep: int, machine: Machine) -> Candidates:
    """The ``keep`` candidates whose unrefined poses a coarse test supports best (a sample of each view's
    boundary, within _SCREEN_TOLERANCE px)."""
    if len(found) <= keep:
        return found
    points, tangents, ranges = _gathered(found, views, _SCREEN_POINTS)
    tested = refine(nearest, tangent_map, points, tangents, ranges, found.matrices(), tolerance=_SCREEN_TOLERANCE, start=_SCREEN_TOLERANCE, angle=30.0, iterations=0,
                    machine=machine)
    best = np.lexsort((-found.votes, -tested.score))[:keep]
    return Candidates(found.views[best], found.similarity[best], found.votes[best])


def _verify(found: Candidates, view_ids: np.ndarray, library: Library, features: Features, transform: Transform,
            min_score: float, min_significance: float, min_support: int, min_inner: float, tolerance: float, verify: int,
            stretch: float, depth: np.ndarray | None, machine: Machine) -> list[Detection]:
    if not len(found):
        return []
    views = library.views()
    nearest, distance = distance_transform(features.edges, machine=machine)
    tangent_map = features.tangent_map
    found = _screen(found, views, nearest, tangent_map, verify, machine)
    all_points, all_tangents, ranges_array = _gathered(found, views)
    solid = np.array([len(library.models[view_ids[row][0]].views) > 1 for row in found.views])

    def refined(rows: np.ndarray, starts: np.ndarray, kind: Transform, first: float = 8.0, steps: int = 6):
        # Each refinement narrows from ``first`` to the tolerance; a tolerance wider than ``first`` is held.
        return refine(nearest, tangent_map, all_points, all_tangents, ranges_array[rows], starts, transform=kind,
                      tolerance=tolerance, start=max(first, tolerance), iterations=steps, machine=machine)

    # Coarse to fine: every pose is fitted as a similarity first, then, where it may be more, as an affine map
    # and a homography from there (a similarity's few parameters reach a distant pose; the others refine it).
    everyone = np.arange(len(found))
    first = refined(everyone, found.matrices(), "similarity")
    score, inside, poses = first.score.copy(), first.inside.copy(), first.transforms.copy()
    affine = np.flatnonzero(solid | (transform != "similarity"))
    if len(affine):
        second = refined(affine, poses[affine], "affine", 4.0, 4)
        for k, row in enumerate(affine):
            stretched = np.linalg.svd(second.transforms[k][:2, :2], compute_uv=False)
            # A 3-D object's view is aligned by an affine map only where it stays near a similarity (a view
            # near the one seen differs from it by a little foreshortening, not by any affine map).
            if not solid[row] or stretched[0] <= stretch * stretched[1]:
                score[row], inside[row], poses[row] = second.score[k], second.inside[k], second.transforms[k]
    homography = np.flatnonzero(~solid) if transform == "homography" else np.zeros(0, int)
    if len(homography):
        third = refined(homography, poses[homography], "homography", 3.0, 4)
        score[homography], inside[homography], poses[homography] = third.score, third.inside, third.transforms
    tree = cKDTree(features.corners.reshape(-1, 2))
    if transform != "similarity" and len(features.corners):
        # A stretch or a perspective the similarity cannot follow leaves the far ends of the boundary beyond
        # the refinement's reach (a box stretched by 15% was 23 px off at its corners): the view's corners
        # matched to the image's near the pose give a start of the asked kind, kept where it scores higher.
        flat = np.flatnonzero(~solid)
        flat = flat[np.argsort(-score[flat], kind="stable")[:_CORNER_STARTS]]  # the likeliest poses: a fit costs
        starts = [_from_corners(poses[row], views[found.views[row]][2], features, tree, transform, tolerance)
                  for row in flat]
        again = np.array([row for row, start in zip(flat, starts) if start is not None], int)
        if len(again):
            fourth = refined(again, np.stack([start for start in starts if start is not None]), transform)
            better = fourth.score > score[again]
            rows = again[better]
            score[rows], inside[rows], poses[rows] = (fourth.score[better], fourth.inside[better],
                                                      fourth.transforms[better])
    h, w = features.shape
    # The final poses tested once more (all candidates in one launch): each candidate's distinct supported
    # image edge pixels are what it explains.
    final = support(nearest, tangent_map, all_points, all_tangents, ranges_array, poses, machine=machine)
    ok = final.inside & (final.distance <= tolerance) & (final.angle <= _ANGLE)
    address = np.round(final.edge[:, 1]).astype(np.int64) * w + np.round(final.edge[:, 0]).astype(np.int64)
    near_edges = _integral(distance <= tolerance)
    chance_angle = 2 * _ANGLE / np.pi
    explained, coverage, significance = [], np.zeros(len(found)), np.zeros(len(found))
    expected, trials, chance = np.zeros(len(found)), np.zeros(len(found)), np.zeros(len(found))
    feature_surprise = np.zeros(len(found))
    tests = np.log10(len(found))
    corners_found = np.zeros(len(found))
    inner_found = np.full(len(found), np.nan)
    for c in range(len(found)):
        view = views[found.views[c]][2]
        start, stop = ranges_array[c]
        pixels = np.unique(address[start:stop][ok[start:stop]])
        explained.append(pixels)
        # The most distinct pixels its points can reach: one each, or fewer where the pose shrinks them
        # closer than a pixel apart; its coverage is the share of those it explains.
        spread = view.length / max(len(view.points), 1) * _scale(poses[c])
        posed = carry(poses[c], view.points)
        hidden = (_hidden(posed, ok[start:stop], final.inside[start:stop], depth) if depth is not None
                  else np.zeros(stop - start, bool))
        expected[c] = max((inside[c] - np.count_nonzero(hidden)) * min(1.0, spread), 1.0)
        coverage[c] = min(len(pixels) / expected[c], 1.0)
        # A contrario: how unlikely that much support is by chance. Stretches of boundary 2 * tolerance
        # long are the independent trials; each is supported by chance with the probability that a point
        # near the pose lies within tolerance of some edge running its way.
        near, area = _box_count(near_edges, posed, (h, w))
        chance[c] = near / area * chance_angle if area else 1.0
        trials[c] = expected[c] / (2 * tolerance)
        matched, landed, corner_chance = _corner_matches(poses[c], view, features, tree)
        corners_found[c] = matched / max(landed, 1)
        # The corners and arcs it matches are further evidence, independent of the boundary's: a curved
        # outline has few corners, and its arcs are what indexing found it by.
        feature_surprise[c] = (_surprise(matched, landed, corner_chance)
                               + _surprise(*_arc_matches(poses[c], posed, view, features)))
        significance[c] = _surprise(coverage[c] * trials[c], trials[c], chance[c]) + feature_surprise[c] - tests
        inner = ~view.outline & final.inside[start:stop] & ~hidden  # a nearer surface explains hidden ones
        if inner.any():
            inner_found[c] = np.count_nonzero(inner & ok[start:stop]) / np.count_nonzero(inner)
    # Greedy explanation: the most significant candidate is kept, and every other is scored again on the
    # edge pixels no kept object explains yet (a second reading of an object's edges, or a part of it read
    # as a smaller object, explains little that is new); a candidate whose silhouette lies mostly on kept
    # ones is dropped (two objects do not lie in one place).
    claimed = np.zeros(h * w, bool)
    taken = np.zeros((h, w), bool)
    heap: list[tuple[float, int]] = [(-float(significance[c]), c) for c in range(len(found))
                                     if significance[c] >= min_significance and not inner_found[c] < min_inner]
    heapq.heapify(heap)
    kept: list[int] = []
    while heap:
        _, pick = heapq.heappop(heap)
        fresh = explained[pick][~claimed[explained[pick]]]
        cover = min(len(fresh) / expected[pick], 1.0)
        now = _surprise(cover * trials[pick], trials[pick], chance[pick]) + feature_surprise[pick] - tests
        if now < min_significance or cover < min_score or len(fresh) < min_support:
            continue
        if heap and now < -heap[0][0]:
            heapq.heappush(heap, (-now, pick))
            continue
        view = views[found.views[pick]][2]
        hull = _silhouette(carry(poses[pick], view.points), (h, w))
        area = int(hull.sum())
        if area == 0 or (hull & taken).sum() >= _OVERLAP * area:
            continue
        taken |= hull
        claimed[explained[pick]] = True
        significance[pick], coverage[pick] = now, cover
        kept.append(pick)
    detections: list[Detection] = []
    for c in kept:
        view = views[found.views[c]][2]
        model, view_index = (int(v) for v in view_ids[found.views[c]])
        boundary = carry(poses[c], view.points)
        start, stop = ranges_array[c]
        detections.append(Detection(library.models[model].name, view_index, poses[c], float(coverage[c]),
                                    int(found.votes[c]), float(significance[c]), float(corners_found[c]),
                                    carry(poses[c], view.corners), boundary, ok[start:stop].copy(),
                                    float(inner_found[c])))
    return detections


def _from_corners(pose: np.ndarray, view: View, features: Features, tree: cKDTree, transform: Transform,
                  tolerance: float) -> np.ndarray | None:
    """An affine map (or, for a homography, one more fit of that kind) from the view's corners to the
    image's matched near ``pose`` (within a quarter of the view's radius at first, then narrower as the fit
    follows them; bisectors and openings alike), by RANSAC; None where too few match or no fit is found
    (the last good fit where a later one fails)."""
    reach = max(0.25 * view.radius * _scale(pose), 4 * tolerance)
    current, fitted = pose, None
    # Affine fits first, whose six parameters the few matches of a rough pose hold; a homography last, from
    # the matches of the closest affine fit.
    kinds = ["affine"] * _CORNER_ROUNDS + (["homography"] if transform == "homography" else [])
    for kind in kinds:
        which, near = _alike_corners(current, view, features, tree, reach)
        if len(which) < (4 if kind == "homography" else 3):
            break
        src = view.corners[which].astype(np.float32)
        dst = features.corners[near].astype(np.float32)
        if kind == "homography":
            matrix, _ = cv2.findHomography(src, dst, cv2.RANSAC, 2 * tolerance)
        else:
            affine, _ = cv2.estimateAffine2D(src, dst, ransacReprojThreshold=2 * tolerance)
            matrix = None if affine is None else np.vstack([affine, [0.0, 0.0, 1.0]])
        if matrix is None or not np.all(np.isfinite(matrix)) or abs(matrix[2, 2]) < 1e-12:
            break
        if not _near_pose(matrix / matrix[2, 2], pose, view):
            break
        current = fitted = matrix / matrix[2, 2]
        reach = max(reach / 2, 2 * tolerance)
    return fitted


def _near_pose(fit: np.ndarray, pose: np.ndarray, view: View) -> bool:
    """Whether a fit from matched corners is a correction of ``pose``, not a new one: the view's bounding
    box stays a convex quadrilateral of between half and twice the pose's area, no corner of it moved by
    more than the view's radius at the pose's scale (a homography fitted to a few chance matches
    folded the box across the image and was then kept as a second detection)."""
    low, high = view.points.min(axis=0), view.points.max(axis=0)
    box = np.array([[low[0], low[1]], [high[0], low[1]], [high[0], high[1]], [low[0], high[1]]])
    moved, there = carry(fit, box), carry(pose, box)
    if not (np.all(np.isfinite(moved)) and np.all(np.isfinite(there))):
        return False
    edges = np.roll(moved, -1, axis=0) - moved
    turns = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    if not (np.all(turns > 0) or np.all(turns < 0)):
        return False

    def area(quad: np.ndarray) -> float:
        return 0.5 * abs(float(np.dot(quad[:, 0], np.roll(quad[:, 1], -1)) - np.dot(np.roll(quad[:, 0], -1), quad[:, 1])))

    ratio = area(moved) / max(area(there), 1e-9)
    shift = float(np.hypot(*(moved - there).T).max())
    return 0.5 <= ratio <= 2.0 and shift <= view.radius * _scale(pose)


def _alike_corners(pose: np.ndarray, view: View, features: Features, tree: cKDTree,
                   reach: float) -> tuple[np.ndarray, np.ndarray]:
    """The view's corners that an image corner matches at ``pose`` (within ``reach`` px, bisectors and
    openings alike), and for each the nearest such image corner: (view rows, image rows)."""
    at = carry(pose, view.corners)
    turned = np.stack([np.cos(view.bisector), np.sin(view.bisector)], 1) @ pose[:2, :2].T
    bisector = np.arctan2(turned[:, 1], turned[:, 0])
    # Every (view corner, image corner) pair within reach, flattened; of the alike, each view corner's nearest.
    lists = tree.query_ball_point(at, reach)
    which = np.repeat(np.arange(len(at)), [len(near) for near in lists])
    near = np.fromiter((k for found in lists for k in found), np.int64, count=len(which))
    alike = ((np.abs(np.angle(np.exp(1j * (bisector[which] - features.bisector[near])))) <= _CORNER_TURN)
             & (np.abs(view.opening[which] - features.opening[near]) <= _CORNER_OPENING))
    which, near = which[alike], near[alike]
    order = np.lexsort((np.hypot(*(features.corners[near] - at[which]).T), which))
    which, near = which[order], near[order]
    first = np.flatnonzero(np.concatenate([[True], which[1:] != which[:-1]])) if len(which) else which
    return which[first], near[first]


def _corner_matches(pose: np.ndarray, view: View, features: Features, tree: cKDTree) -> tuple[int, int, float]:
    """How many of the view's corners (of those that land in the image) an image corner matches, how many
    land there, and the chance that one is matched by accident (the image's corners around the pose,
    each covering a disc of _CORNER_REACH px and a share of the bisectors and openings)."""
    h, w = features.shape
    if not len(view.corners):
        return 0, 0, 0.0
    at = carry(pose, view.corners)
    inside = (at[:, 0] >= 0) & (at[:, 1] >= 0) & (at[:, 0] <= w - 1) & (at[:, 1] <= h - 1)
    if not inside.any() or not len(features.corners):
        return 0, int(inside.sum()), 0.0
    which, _ = _alike_corners(pose, view, features, tree, _CORNER_REACH)
    matched = int(np.count_nonzero(inside[which]))
    low = at[inside].min(axis=0) - _MARGIN
    high = at[inside].max(axis=0) + _MARGIN
    around = np.all((features.corners >= low) & (features.corners <= high), axis=1).sum()
    area = max(float(np.prod(high - low)), 1.0)
    chance = min(around * np.pi * _CORNER_REACH ** 2 / area, 1.0) * (_CORNER_TURN / np.pi) * (2 * _CORNER_OPENING / np.pi)
    return matched, int(inside.sum()), float(chance)


def _arc_matches(pose: np.ndarray, posed: np.ndarray, view: View, features: Features) -> tuple[int, int, float]:
    """How many of the view's arcs (of those whose centres land in the image) an image arc matches (centres
    within :data:`_ARC_REACH` of the radius, radii within a factor :data:`_ARC_RADII`), how many land there,
    and the chance that one is matched by accident (the image's arcs of a like radius around the pose, each
    covering a disc of the reach, over the area around ``posed``, the view's points at the pose), as
    :func:`_corner_matches` counts corners."""
    h, w = features.shape
    if not len(view.arcs) or not len(features.arcs):
        return 0, 0, 0.0
    at = carry(pose, view.arcs)
    radius = view.arc_radius * _scale(pose)
    # A pose that shrinks the view to a point leaves its arcs no radius to compare.
    inside = (at[:, 0] >= 0) & (at[:, 1] >= 0) & (at[:, 0] <= w - 1) & (at[:, 1] <= h - 1) & (radius > 0)
    if not inside.any():
        return 0, 0, 0.0
    reach = np.maximum(_CORNER_REACH, _ARC_REACH * radius)
    low, high = posed.min(axis=0) - _MARGIN, posed.max(axis=0) + _MARGIN
    area = max(float(np.prod(high - low)), 1.0)
    around = np.all((features.arcs >= low) & (features.arcs <= high), axis=1)
    matched, chances = 0, []
    for k in np.flatnonzero(inside):
        alike = np.abs(np.log(features.arc_radius / radius[k])) <= np.log(_ARC_RADII)
        matched += bool(np.any(alike & (np.hypot(*(features.arcs - at[k]).T) <= reach[k])))
        chances.append(min(np.count_nonzero(around & alike) * np.pi * reach[k] ** 2 / area, 1.0))
    return matched, int(inside.sum()), float(np.mean(chances))


def _hidden(posed: np.ndarray, supported: np.ndarray, inside: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Which of a candidate's unsupported points (those in the image) a nearer surface explains: the
    depth map (disparity, larger nearer) where they land exceeds the object's own there by more than
    _NEARER. The object's own disparity is the plane through its supported points (least squares), so
    that the far side of a slanted object is not taken for a surface in front of it; its median where
    the supported points cannot fix a plane (fewer than three, or along one line)."""
    h, w = depth.shape
    x = np.clip(np.round(posed[:, 0]).astype(np.int64), 0, w - 1)
    y = np.clip(np.round(posed[:, 1]).astype(np.int64), 0, h - 1)
    here = depth[y, x]
    known = supported & np.isfinite(here)
    if not known.any():
        return np.zeros(len(posed), bool)
    own = np.full(len(posed), np.median(here[known]))
    design = np.column_stack([x, y, np.ones(len(posed))]).astype(np.float64)
    plane, _, rank, _ = np.linalg.lstsq(design[known], here[known].astype(np.float64), rcond=None)
    if rank == 3:  # three points or more, not on one line
        own = design @ plane
    return inside & ~supported & (here > own + _NEARER)


def _silhouette(points: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The convex hull of points, as a bool mask of the image."""
    mask = np.zeros(shape, np.uint8)
    span = np.clip(points, -4 * max(shape), 4 * max(shape))
    hull = cv2.convexHull(np.round(span).astype(np.int32))
    cv2.fillConvexPoly(mask, hull, 1)
    return mask.astype(bool)


def _integral(mask: np.ndarray) -> np.ndarray:
    """The summed-area table of a mask, with a leading row and column of zeros."""
    table = np.zeros((mask.shape[0] + 1, mask.shape[1] + 1), np.float64)
    table[1:, 1:] = np.cumsum(np.cumsum(mask, axis=0), axis=1)
    return table


def _box_count(table: np.ndarray, points: np.ndarray, shape: tuple[int, int]) -> tuple[float, float]:
    """The mask's count over the bounding box of points (within the image), widened by _MARGIN px, and
    the box's area."""
    h, w = shape
    x0, y0 = (int(np.clip(np.floor(points[:, k].min()) - _MARGIN, 0, n - 1)) for k, n in ((0, w), (1, h)))
    x1, y1 = (int(np.clip(np.ceil(points[:, k].max()) + _MARGIN, 0, n - 1)) + 1 for k, n in ((0, w), (1, h)))
    if x1 <= x0 or y1 <= y0:
        return 0.0, 0.0
    total = table[y1, x1] - table[y0, x1] - table[y1, x0] + table[y0, x0]
    return float(total), float((x1 - x0) * (y1 - y0))


def _surprise(hits: float, trials: float, chance: float) -> float:
    """-log10 of the chance of at least ``hits`` successes in ``trials`` Bernoulli trials of probability
    ``chance`` (the binomial tail, continuous in its counts); 0 for no hits."""
    if hits <= 0 or trials <= 0:
        return 0.0
    chance = min(max(chance, 1e-6), 1 - 1e-6)
    tail = special.betainc(hits, max(trials - hits + 1, 1e-9), chance)
    return float(-np.log10(max(tail, 1e-300)))


def _scale(pose: np.ndarray) -> float:
    """The pose's linear scale: the square root of its linear part's determinant (at the origin)."""
    return float(np.sqrt(abs(np.linalg.det(pose[:2, :2] / pose[2, 2]))))
