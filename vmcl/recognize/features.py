"""The features recognition works on: corners with their two edges, and the boundary as oriented points.

Seed section "Recognition": indexing uses "simple viewpoint-invariant combinations of features (two lines
forming a corner, ...)". A corner is where two edges meet: an L-junction on one curve, or two adjacent
arms of a T, Y, arrow or X junction (:func:`vmcl.group.junctions.find_junctions`). Each corner is kept
as its position, the direction of the bisector of the angle its two edges make (into the angle) and the
angle's opening; under a similarity the opening is unchanged and the bisector turns with the image, so
pairs of corners give the invariant keys of :mod:`vmcl.recognize.indexing`. The boundary, every curve
pixel with its tangent, is what :mod:`vmcl.recognize.verification` tests a pose against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import ArrayLike, check_real, machine_for, to_host
from vmcl.early.edges import canny
from vmcl.errors import InputTypeError, InputValueError
from vmcl.group.curves import Curves, link_edges
from vmcl.group.junctions import Junctions, find_junctions
from vmcl.group.local_saliency import local_saliency, saliency_map
from vmcl.machine import Machine

__all__ = ["MIN_OPENING", "Features", "edge_features", "image_features"]

MIN_OPENING = math.radians(15)
"""Corners sharper than this (degrees: 15) are not kept: their two edges' directions are not separable."""

_MAX_OPENING = math.radians(165)  # wider than this, the two edges are one straight edge


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


def _from_curves(curves: Curves, corner: float, gap: float) -> Features:
    labels = np.asarray(to_host(curves.labels))
    tangent_map = np.asarray(to_host(curves.tangent), np.float32)
    junctions = find_junctions(curves, corner=corner, gap=gap)
    positions, bisectors, openings = corners_of(junctions)
    edges = labels != -1
    ys, xs = np.nonzero(edges)
    return Features(labels.shape, positions, bisectors, openings, np.stack([xs, ys], axis=1).astype(np.float64),
                    tangent_map[ys, xs].astype(np.float64), edges, tangent_map,
                    saliency_map(curves, local_saliency(curves)))


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
    if min(image.shape[:2]) < 8:
        raise InputValueError(f"image must be at least 8 x 8 pixels, got {tuple(image.shape)}")
    sigma = check_real(sigma, "sigma", above=0)
    found = canny(image, sigma=sigma, return_gradient=True, machine=machine)
    return edge_features(found.edges, magnitude=found.magnitude, corner=corner, gap=gap, machine=machine)
