"""The features recognition works on: corners with their two edges, and the boundary as oriented points.

Seed section "Recognition": indexing uses "simple viewpoint-invariant combinations of features (two lines
forming a corner, ...)". A corner is where two edges meet: an L-junction on one curve, or two adjacent
arms of a T, Y, arrow or X junction (:func:`vmcl.group.junctions.find_junctions`). Each corner is kept
as its position, the direction of the bisector of the angle its two edges make (into the angle) and the
angle's opening; under a similarity the opening is unchanged and the bisector turns with the image, so
pairs of corners give the invariant keys of :mod:`vmcl.recognize.indexing`. A curved outline may show
too few corners for that (a half disc has two; with one hidden, none pair), so its curve pieces are
features too: an arc is a stretch of a curve that a circle fits, kept as the circle's centre and radius
(a similarity moves the centre with the image and scales the radius with it). The boundary, every curve
pixel with its tangent, is what :mod:`vmcl.recognize.verification` tests a pose against.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from vmcl.cm.core import ArrayLike, check_real, machine_for, to_host
from vmcl.early.edges import canny
from vmcl.errors import InputTypeError, InputValueError
from vmcl.group.curves import Curves, link_edges
from vmcl.group.junctions import Junctions, find_junctions
from vmcl.group.local_saliency import local_saliency, saliency_map
from vmcl.machine import Machine

__all__ = ["ARC_LENGTH", "MIN_OPENING", "Features", "arcs_of", "edge_features", "features_of", "image_features"]

MIN_OPENING = math.radians(15)
"""Corners sharper than this (degrees: 15) are not kept: their two edges' directions are not separable."""

_MAX_OPENING = math.radians(165)  # wider than this, the two edges are one straight edge

ARC_LENGTH = 20
"""The fewest curve pixels an arc spans."""

_ARC_RESIDUAL = 0.6  # px: the most a circle's rms distance from a stretch's pixels may be for it to be an arc
_ARC_TURN = math.radians(30)  # the least an arc turns (its length over its radius): straighter is a line
_ARC_REACH = 10  # pixels either side over which the tangent's turning gives a pixel's bending (the pixel grid's
# staircase makes the turning over fewer noisy by more than half of a 100 px radius's)
_ARC_STRAIGHT = 1 / 300  # bending (1/px) below which a pixel is on a line, not an arc
_CORNER_REACH = 3  # pixels either side over which the tangent's turning finds a corner,
_CORNER_TURN = math.radians(30)  # at least this much of it
_ARC_MIN_RADIUS = 12.0  # px: a tighter bend is a corner rounded by the edges' smoothing (its radius is the blur's)
_ARC_SAME = 0.2  # neighbouring arcs of a curve are one where centres and radii agree within this share of the radius


@dataclass(frozen=True, eq=False)
class Features:
    """An image's (or a model view's) features.

    Attributes
    ----------
    shape : (int, int)
        The image's (H, W).
    corners : float64 (F, 2)
        Corner positions (x, y).
    bisector : float64 (F,)
        The direction (radians, atan2(dy, dx)) halfway between each corner's two edges, pointing into the
        angle they make.
    opening : float64 (F,)
        The angle between each corner's two edges, in (0, pi).
    points : float64 (N, 2)
        The boundary: every curve pixel (x, y).
    tangent : float64 (N,)
        The boundary's tangent direction at each point (radians, modulo pi; NaN where unknown).
    edges : bool (H, W)
        The edge map the features came from.
    tangent_map : float32 (H, W)
        The tangent at each edge pixel (NaN elsewhere and where unknown).
    saliency_map : float32 (H, W)
        The local saliency of the curve each edge pixel lies on (:mod:`vmcl.group.local_saliency`; 0
        elsewhere and at branch pixels).
    arcs : float64 (A, 2)
        The centres (x, y) of the circles the curves' arcs lie on (:func:`arcs_of`).
    arc_radius : float64 (A,)
        Their radii in pixels.
    arc_middle : float64 (A, 2)
        The middle pixel (x, y) of each arc.
    """

    shape: tuple[int, int]
    corners: np.ndarray
    bisector: np.ndarray
    opening: np.ndarray
    points: np.ndarray
    tangent: np.ndarray
    edges: np.ndarray
    tangent_map: np.ndarray
    saliency_map: np.ndarray
    arcs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    arc_radius: np.ndarray = field(default_factory=lambda: np.zeros(0))
    arc_middle: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def __len__(self) -> int:
        return len(self.corners)


def corners_of(junctions: Junctions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pair of angularly adjacent arms of each junction whose angle is between 15 and 165 degrees, as
    (positions (F, 2), bisectors (F,), openings (F,))."""
    positions, bisectors, openings = [], [], []
    for point, arms in zip(junctions.points, junctions.arms):
        arms = np.sort(arms[np.isfinite(arms)])
        if len(arms) < 2:
            continue
        following = np.roll(arms, -1)
        following[-1] += 2 * math.pi
        gaps = following - arms
        take = (gaps >= MIN_OPENING) & (gaps <= _MAX_OPENING)
        positions.extend([point] * int(take.sum()))
        bisectors.extend(np.angle(np.exp(1j * (arms[take] + gaps[take] / 2))))
        openings.extend(gaps[take])
    return (np.array(positions, np.float64).reshape(-1, 2), np.array(bisectors, np.float64),
            np.array(openings, np.float64))


def _circle(points: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The circle fitted to points (algebraic least squares: x^2 + y^2 + D x + E y + F = 0): its centre,
    radius and rms distance from the points (inf where they are collinear)."""
    x, y = points[:, 0], points[:, 1]
    system = np.stack([x, y, np.ones_like(x)], axis=1)
    solution, *_ = np.linalg.lstsq(system, -(x * x + y * y), rcond=None)
    centre = -0.5 * solution[:2]
    squared = centre @ centre - solution[2]
    if not np.isfinite(squared) or squared <= 0:
        return centre, math.inf, math.inf
    radius = math.sqrt(squared)
    residual = float(np.sqrt(np.mean((np.hypot(x - centre[0], y - centre[1]) - radius) ** 2)))
    return centre, radius, residual


def _same_circle(a: np.ndarray, ra: float, b: np.ndarray, rb: float) -> bool:
    scale = max(ra, rb)
    return bool(np.hypot(*(a - b)) <= _ARC_SAME * scale and abs(ra - rb) <= _ARC_SAME * scale)


def _bridged(bend: np.ndarray) -> np.ndarray:
    """Bending signs with each gap of straight pixels (0) shorter than an arc between two runs of one sign
    given that sign: on a wide circle the measured bending dips below the straight level here and there."""
    out = bend.copy()
    for start, stop in _runs((bend == 0).astype(np.int64)):
        if 0 < start and stop < len(bend) and stop - start < ARC_LENGTH and bend[start - 1] == bend[stop]:
            out[start:stop] = bend[stop]
    return out


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The (start, stop) of each run of equal non-zero values."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flags, [0]])) != 0)
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges) if flags[a] != 0]


def arcs_of(curves: Curves) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arcs of curves: stretches that bend one way, evenly, and that a circle fits.

    Along each curve, a pixel's bending is its tangent's turning over the 10 pixels either side (per
    pixel of arc), and a corner is where the tangent turns 30 degrees over 3 pixels either side. Pixels
    bending less than 1/300 per pixel lie on lines, unless fewer than :data:`ARC_LENGTH` of them lie
    between pixels bending one way (a wide circle's measured bending dips); each run of the others,
    bending one way and more than 10 pixels from a corner, less 5 pixels at either end (where an arc runs
    on into a line, its bending leaks into the line's first pixels), is fitted where it spans
    :data:`ARC_LENGTH` pixels with a circle, and is an arc where its pixels lie within 0.6 px (rms) of the
    circle, it turns at least 30 degrees, and its radius is at least 12 px (a tighter bend is a corner the
    edges' smoothing rounded) and within a factor of 2 of the run's median bending. Neighbouring arcs of
    one curve on one circle are joined.

    Parameters
    ----------
    curves : vmcl.group.curves.Curves

    Returns
    -------
    centres : float64 (A, 2)
        Each arc's circle's centre (x, y).
    radii : float64 (A,)
    middles : float64 (A, 2)
        Each arc's middle pixel (x, y).
    """
    if not isinstance(curves, Curves):
        raise InputTypeError(f"curves must be vmcl.group.curves.Curves, got {type(curves).__name__}")
    tangent_map = np.asarray(to_host(curves.tangent))
    centres: list[np.ndarray] = []
    radii: list[float] = []
    middles: list[np.ndarray] = []
    k, j = _ARC_REACH, _CORNER_REACH
    # An open curve's first and last reach have no bending measured: it needs an arc's length beside them.
    for c in np.flatnonzero(np.diff(curves.offsets) >= ARC_LENGTH + 2 * k):
        points = curves.points[curves.offsets[c]:curves.offsets[c + 1]]
        theta = tangent_map[points[:, 1], points[:, 0]].astype(np.float64)
        known = np.isfinite(theta)
        if known.sum() < ARC_LENGTH:
            continue
        theta = np.unwrap(np.interp(np.arange(len(theta)), np.flatnonzero(known), theta[known]))
        if curves.closed[c]:
            # A loop is read from its sharpest turn, or where it bends least if it has no corner (so that no
            # arc is cut at the seam), with a reach's overlap at each end so the turning is measured across it.
            turned = np.angle(np.exp(1j * (np.roll(theta, -j) - np.roll(theta, j))))
            if np.abs(turned).max() >= _CORNER_TURN:
                first = int(np.argmax(np.abs(turned)))
            else:
                # (the turning over three reaches either side: over one, a circle's measured bending dips)
                wide = 3 * k
                first = int(np.argmin(np.abs(np.angle(np.exp(1j * (np.roll(theta, -wide) - np.roll(theta, wide)))))))
            order = np.arange(first - k, first + len(points) + k) % len(points)
            points = points[order]
            theta = np.unwrap(theta[order])
        steps = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
        bending = np.zeros(len(points))
        bending[k:-k] = (theta[2 * k:] - theta[:-2 * k]) / np.maximum(steps[2 * k:] - steps[:-2 * k], 1e-9)
        corner = np.zeros(len(points), bool)
        corner[j:-j] = np.abs(theta[2 * j:] - theta[:-2 * j]) >= _CORNER_TURN
        corner[:k] = corner[-k:] = True  # no bending measured there
        # A corner's turn leaks into the bending up to a reach away: those pixels are no arc's.
        near_corner = np.convolve(corner, np.ones(2 * k + 1), mode="same") > 0
        bend = np.where(np.abs(bending) >= _ARC_STRAIGHT, np.sign(bending), 0).astype(np.int64)
        bend = np.where(near_corner, 0, _bridged(bend))
        found: list[tuple[int, int, np.ndarray, float]] = []
        for start, stop in _runs(bend):
            # Where an arc runs on into a line without a corner, the bending measured over a reach leaks half
            # a reach into the line: the run's ends are left out.
            start, stop = start + k // 2, stop - k // 2
            if stop - start < ARC_LENGTH:
                continue
            centre, radius, residual = _circle(points[start:stop].astype(np.float64))
            if residual > _ARC_RESIDUAL or radius < _ARC_MIN_RADIUS or steps[stop - 1] - steps[start] < _ARC_TURN * radius:
                continue
            # A short piece can fit a circle of another radius within the residual: its radius must agree with
            # how much the piece bends.
            if not 0.5 <= np.median(np.abs(bending[start:stop])) * radius <= 2.0:
                continue
            if found and _same_circle(found[-1][2], found[-1][3], centre, radius):
                # A dip in the measured bending split one arc: fitted again as a whole.
                joined = _circle(points[found[-1][0]:stop].astype(np.float64))
                if joined[2] <= _ARC_RESIDUAL:
                    found[-1] = (found[-1][0], stop, joined[0], joined[1])
                    continue
            found.append((start, stop, centre, radius))
        centres.extend(f[2] for f in found)
        radii.extend(f[3] for f in found)
        middles.extend(points[(f[0] + f[1] - 1) // 2] for f in found)
    return (np.array(centres, np.float64).reshape(-1, 2), np.array(radii, np.float64),
            np.array(middles, np.float64).reshape(-1, 2))


def _from_curves(curves: Curves, corner: float, gap: float) -> Features:
    labels = np.asarray(to_host(curves.labels))
    tangent_map = np.asarray(to_host(curves.tangent), np.float32)
    junctions = find_junctions(curves, corner=corner, gap=gap)
    positions, bisectors, openings = corners_of(junctions)
    edges = labels != -1
    ys, xs = np.nonzero(edges)
    return Features(labels.shape, positions, bisectors, openings, np.stack([xs, ys], axis=1).astype(np.float64),
                    tangent_map[ys, xs].astype(np.float64), edges, tangent_map,
                    saliency_map(curves, local_saliency(curves)), *arcs_of(curves))


def edge_features(edges: ArrayLike, *, magnitude: ArrayLike | None = None, corner: float = 45.0, gap: float = 6.0,
                  machine: Machine | None = None) -> Features:
    """The corners and oriented boundary of an edge map.

    Parameters
    ----------
    edges : (H, W) bool or uint8 array, NumPy or device
        An edge map: Canny's, or the cartoon's labelled discontinuities.
    magnitude : (H, W) float32 array, optional
        The gradient magnitude behind the edges (passed to :func:`vmcl.group.curves.link_edges`).
    corner : float
        The turn (degrees) along one curve that makes a corner, in (0, 180]
        (:func:`vmcl.group.junctions.find_junctions`' ``corner``).
    gap : float
        The gap (pixels) a broken junction is followed across, >= 0.
    machine : vmcl.Machine, optional

    Returns
    -------
    Features
    """
    machine = machine_for(machine)
    corner = check_real(corner, "corner", above=0, maximum=180)
    gap = check_real(gap, "gap", minimum=0)
    return _from_curves(link_edges(edges, magnitude=magnitude, machine=machine), corner, gap)


def image_features(image: ArrayLike, *, sigma: float = 1.5, corner: float = 45.0, gap: float = 6.0,
                   machine: Machine | None = None) -> Features:
    """The corners and oriented boundary of an image's Canny edges (thresholds from its noise).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) array
        As :func:`vmcl.early.edges.canny` takes it.
    sigma : float
        Canny's smoothing in pixels, > 0.
    corner, gap : float
        As :func:`edge_features` takes them.
    machine : vmcl.Machine, optional

    Returns
    -------
    Features
    """
    machine = machine_for(machine)
    if not hasattr(image, "shape"):
        raise InputTypeError(f"image must be an array, got {type(image).__name__}")
    if len(image.shape) not in (2, 3):
        raise InputValueError(f"image must be (H, W) or (H, W, 3), got shape {tuple(image.shape)}")
    if min(image.shape[:2]) < 8:
        raise InputValueError(f"image must be at least 8 x 8 pixels, got {tuple(image.shape)}")
    sigma = check_real(sigma, "sigma", above=0)
    found = canny(image, sigma=sigma, return_gradient=True, machine=machine)
    return edge_features(found.edges, magnitude=found.magnitude, corner=corner, gap=gap, machine=machine)


def features_of(image: ArrayLike, *, sigma: float = 1.5, corner: float = 45.0,
                machine: Machine | None = None) -> Features:
    """The features of an image or an edge map, as :func:`vmcl.recognize.learn` and
    :func:`vmcl.recognize.recognize` take them: a 2-D bool array is an edge map (:func:`edge_features`),
    anything else an image (:func:`image_features`, with ``sigma``): a uint8 edge map of 0 and 255 (as
    ``cv2.Canny`` gives one) too, whose strokes then have edges of their own; give ``edges > 0``.

    Raises
    ------
    vmcl.errors.InputValueError
        A 2-D integer array of 0 and 1 (both): an edge map or mask in an integer type, which as a picture is
        black, and whose Canny edges would be each edge pixel's outline (poses off by a pixel or more).
    """
    if isinstance(image, np.ndarray) and image.ndim == 2 and image.dtype == np.bool_:
        return edge_features(image, corner=corner, machine=machine)
    if (isinstance(image, np.ndarray) and image.ndim == 2 and image.dtype.kind in "ui" and image.size
            and int(np.max(image)) == 1 and int(np.min(image)) == 0):  # (a black picture is none)
        raise InputValueError(f"image holds only the values 0 and 1 ({image.dtype}): an edge map must be a bool "
                              "array (image.astype(bool)); an image, its brightness")
    return image_features(image, sigma=sigma, corner=corner, machine=machine)
