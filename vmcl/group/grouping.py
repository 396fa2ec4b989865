"""The grouping stage in one call: curves, their local saliency, junctions, repairs and groups.

:func:`group` is what :class:`vmcl.pipeline.VisionMachine` runs after Canny (its ``[grouping]`` settings)
and what a user calls on any edge map: it links the edges into curves
(:func:`vmcl.group.curves.link_edges`), scores them (:func:`vmcl.group.local_saliency.local_saliency`),
finds and classifies the junctions and repairs the T-junctions Canny broke
(:func:`vmcl.group.junctions.find_junctions`), and groups curves across pairs of T-junctions
(:func:`vmcl.group.junctions.group_curves`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import ArrayLike, check_real, machine_for, to_host
from vmcl.group.curves import Curves, link_edges
from vmcl.group.junctions import Junctions, find_junctions, group_curves, pairing_image, repair_edges
from vmcl.group.local_saliency import local_saliency, salient_edges
from vmcl.machine import Machine

__all__ = ["Grouping", "group"]


@dataclass(frozen=True)
class Grouping:
    """What :func:`group` returns (host arrays).

    Attributes
    ----------
    curves : Curves
        The edges linked into curves (host maps).
    saliency : float64 (C,)
        Each curve's local saliency.
    salient : bool (H, W)
        The edges pruned to the curves of local saliency >= the threshold.
    junctions : Junctions
    repaired : bool (H, W)
        The edges with the gaps of broken T-junctions filled.
    pairs : int32 (P, 2)
        T-junctions paired across an occluder (indices into ``junctions``).
    groups : list of int32 arrays
        The curves the pairs join, each a sorted array of curve indices.
    """

    curves: Curves
    saliency: np.ndarray
    salient: np.ndarray
    junctions: Junctions
    repaired: np.ndarray
    pairs: np.ndarray
    groups: list[np.ndarray]


def group(edges: ArrayLike, *, magnitude: ArrayLike | None = None, image: ArrayLike | None = None,
          threshold: float = 0.0, length_exponent: float = 0.5, curvature_scale: float = 0.5, gap: float = 6.0,
          alignment: float = 20.0, machine: Machine | None = None) -> Grouping:
    """Group an edge map: curves, local saliency, junctions, repairs and T-junction pairs.

    Parameters
    ----------
    edges : (H, W) bool or uint8 array, NumPy or device
    magnitude : (H, W) float32 array, NumPy or device, optional
        The gradient magnitude behind the edges (each curve's strength; 1 without it); finite and >= 0, and
        small enough that a curve's saliency (its mean magnitude times its length**length_exponent) stays
        within float32's range.
    image : (H, W) or (H, W, 3) array, NumPy or device, optional
        The image, for the pairing test of :func:`vmcl.group.junctions.group_curves`: of the edge map's
        (H, W), at least 16 x 16 pixels, as :func:`vmcl.pipeline.as_image` reads it; checked before the
        edges are linked.
    threshold : float
        The local saliency a curve needs to stay in ``salient``, >= 0 (0 keeps every curve).
    length_exponent, curvature_scale : float
        As :func:`vmcl.group.local_saliency.local_saliency` takes them.
    gap : float
        As :func:`vmcl.group.junctions.find_junctions` takes it.
    alignment : float
        As :func:`vmcl.group.junctions.group_curves` takes it.
    machine : vmcl.Machine, optional

    Returns
    -------
    Grouping
    """
    machine = machine_for(machine)
    threshold = check_real(threshold, "threshold", minimum=0)
    if image is not None and isinstance(edges, (np.ndarray, cl_array.Array)) and edges.ndim == 2:
        # Refused now, not after the linking and the junctions, and with the edge map's shape: group_curves
        # checks it against the junctions' (the same) too. Other edges are link_edges' to refuse.
        image = pairing_image(image, (int(edges.shape[0]), int(edges.shape[1])))
    linked = link_edges(edges, magnitude=magnitude, machine=machine)
    labels, position, tangent = (np.asarray(to_host(m)) for m in (linked.labels, linked.position, linked.tangent))
    curves = Curves(labels, position, tangent, linked.points, linked.offsets, linked.closed, linked.length, linked.mean_curvature,
                    linked.total_curvature, linked.magnitude, linked.tangents, linked.branches)
    saliency = local_saliency(curves, length_exponent=length_exponent, curvature_scale=curvature_scale)
    junctions = find_junctions(curves, gap=gap)
    pairs, groups = group_curves(junctions, image=image, alignment=alignment)
    mask = curves.labels != -1
    return Grouping(curves, saliency, salient_edges(curves, saliency, threshold), junctions,
                    repair_edges(mask, junctions), pairs, groups)
