"""Selection: the image cut into regions bounded by its discontinuities, ranked by saliency.

Seed section "Recognition": selection is "segmentation into regions likely to be one object", and the
recogniser looks first at features that lie together in one region. The regions are the connected
components of the pixels off the discontinuities (4-connected, so an 8-connected one-pixel contour
closes them), labelled on the machine (:func:`vmcl.cm.doubling.label`); each is ranked by the mean local
saliency of the curves that bound it (:func:`vmcl.group.local_saliency.local_saliency`: long, smooth,
strong curves first). A corner belongs to the region its angle opens into.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vmcl.cm import doubling
from vmcl.cm.core import check_int, check_real, machine_for
from vmcl.errors import InputTypeError
from vmcl.machine import Machine
from vmcl.recognize.arguments import angles, edge_map, points, real_map

__all__ = ["Regions", "corner_regions", "select_regions"]


@dataclass(frozen=True)
class Regions:
    """What :func:`select_regions` returns.

    Attributes
    ----------
    labels : int32 (H, W)
        Each pixel's region (0, 1, ...), -1 on the discontinuities.
    saliency : float64 (R,)
        Each region's mean boundary saliency (0 for a region without boundary).
    area : int64 (R,)
        Each region's pixels.
    ranked : int64 (K,)
        The regions recognition looks at first, most salient first: those of at least ``min_area``
        pixels and at most ``max_fraction`` of the image.
    """

    labels: np.ndarray
    saliency: np.ndarray
    area: np.ndarray
    ranked: np.ndarray


def select_regions(edges: np.ndarray, saliency_map: np.ndarray, *, min_area: int = 64, max_fraction: float = 0.5,
                   machine: Machine | None = None) -> Regions:
    """Regions bounded by an edge map, ranked by the saliency of their boundaries.

    Parameters
    ----------
    edges : bool (H, W)
        The discontinuities.
    saliency_map : float (H, W)
        Each edge pixel's saliency (its curve's); ignored off the edges.
    min_area : int
        The fewest pixels a ranked region has, >= 1.
    max_fraction : float
        The largest fraction of the image a ranked region covers (the background), in (0, 1].
    machine : vmcl.Machine, optional

    Returns
    -------
    Regions
    """
    machine = machine_for(machine)
    edges = edge_map(edges, "edges")
    saliency_map = real_map(saliency_map, "saliency_map", edges.shape, "edges")
    min_area = check_int(min_area, "min_area", minimum=1)
    max_fraction = check_real(max_fraction, "max_fraction", above=0, maximum=1)
    labels = np.asarray(doubling.label(~edges, connectivity=4, relabel=True, machine=machine)).astype(np.int32) - 1
    count = int(labels.max()) + 1 if labels.size else 0
    area = np.bincount(labels[labels >= 0], minlength=count).astype(np.int64)
    # Each edge pixel's saliency credited to the regions 4-adjacent to it.
    h, w = edges.shape
    ys, xs = np.nonzero(edges)
    value = np.nan_to_num(saliency_map[ys, xs])
    total, touches = np.zeros(count), np.zeros(count)
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        ny, nx = ys + dy, xs + dx
        ok = (ny >= 0) & (ny < h) & (nx >= 0) & (nx < w)
        region = labels[ny[ok], nx[ok]]
        on = region >= 0
        np.add.at(total, region[on], value[ok][on])
        np.add.at(touches, region[on], 1)
    saliency = np.where(touches > 0, total / np.maximum(touches, 1), 0.0)
    eligible = np.flatnonzero((area >= min_area) & (area <= max_fraction * h * w))
    ranked = eligible[np.argsort(-saliency[eligible], kind="stable")]
    return Regions(labels, saliency, area, ranked.astype(np.int64))


def corner_regions(regions: Regions, corners: np.ndarray, bisector: np.ndarray, *, reach: float = 3.0,
                   top: int = 8) -> np.ndarray:
    """The region each corner opens into (``reach`` px along its bisector), among the ``top`` ranked
    regions; -1 for a corner whose region is not among them."""
    if not isinstance(regions, Regions):
        raise InputTypeError(f"regions must be vmcl.recognize.Regions (select_regions'), got {type(regions).__name__}")
    corners = points(corners, "corners")
    bisector = angles(bisector, "bisector", len(corners), "corners")
    reach = check_real(reach, "reach", minimum=0, maximum=1e6)
    top = check_int(top, "top", minimum=0)
    h, w = regions.labels.shape
    at = corners + reach * np.stack([np.cos(bisector), np.sin(bisector)], 1)
    x = np.clip(np.round(at[:, 0]).astype(np.int64), 0, w - 1)
    y = np.clip(np.round(at[:, 1]).astype(np.int64), 0, h - 1)
    region = regions.labels[y, x]
    keep = np.isin(region, regions.ranked[:top])
    return np.where(keep, region, -1).astype(np.int64)


