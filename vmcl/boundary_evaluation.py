"""The boundary evaluation: the cartoon's soft map beside Canny's detectors on human boundaries (BSDS500).

One harness, used by ``vmcl eval edges`` and by benchmarks/boundaries.py, so that every boundary figure
vmcl reports comes from the same reading of the data and the same sweeps:

- the data: any BSDS-layout folder (:func:`vmcl.datasets.read_bsds_folder`);
- the maps (:func:`boundary_maps`): the monocular machine's soft map at its defaults
  (:attr:`vmcl.result.Result.boundary_strength`), swept; its cartoon (labels != 0), binary; vmcl's
  Canny and OpenCV's Canny, each swept over the same number of hysteresis thresholds (:func:`canny_sweep`);
- the figures (:func:`score_maps`): the BSDS benchmark's ODS and OIS F-measures and average precision,
  its one-to-one matching at 0.0075 of the image diagonal and its thinning
  (:func:`vmcl.metrics.evaluate_boundaries`). The matching (the benchmark's correspondPixels, through
  pyEdgeEval) joins random outlier edges to its assignment graph from a generator seeded by the clock, as
  the BSDS benchmark's own code does, so the same maps can score a little differently from run to run; the
  maps themselves are the same bit for bit.

A Canny sweep: Gaussian smoothing of width 2 (the machine's own, :class:`vmcl.pipeline.EdgesConfig`),
high thresholds spaced geometrically over the range a photograph's contrasts span, the low threshold 0.4
of the high (Canny's 2:1 to 3:1 advice). Raising both thresholds together can only remove edges, so each
pixel is given the last level at which it is an edge, and the sweep is scored at the levels.

References
----------
D. Martin, C. Fowlkes and J. Malik, "Learning to detect natural image boundaries using local brightness,
color, and texture cues", IEEE TPAMI 26(5):530-549, 2004. P. Arbelaez, M. Maire, C. Fowlkes and
J. Malik, "Contour detection and hierarchical image segmentation", IEEE TPAMI 33(5):898-916, 2011.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from vmcl.cm.core import check_int, machine_for, to_host
from vmcl.datasets import BSDSImage
from vmcl.early.edges import canny
from vmcl.errors import InputValueError
from vmcl.machine import Machine
from vmcl.metrics import BoundaryScores, evaluate_boundaries

__all__ = ["CANNY_SIGMA", "LOCAL_SPAN", "LOW_RATIO", "STRUCTURAL_SPAN", "MapSet", "boundary_maps", "canny_sweep",
           "local_saliency_sweep", "opencv_canny_sweep", "score_maps", "structural_saliency_sweep", "sweep_thresholds"]

CANNY_SIGMA = 2.0
"""The Canny sweeps' Gaussian width, the machine's own (EdgesConfig.sigma)."""

LOW_RATIO = 0.4
"""The low hysteresis threshold over the high one."""

MAX_LEVELS = 1000
"""The most levels a sweep takes (each is a detector run, and each threshold a matching per annotator)."""

_VMCL_LEVELS = (0.004, 0.4)  # Gaussian-smoothed gradient magnitudes of an image in [0, 1]
_OPENCV_LEVELS = (4.0, 800.0)  # cv2.Canny's L2 Sobel magnitudes of an 8-bit image


@dataclass(frozen=True)
class MapSet:
    """One method's maps over a set of images.

    Attributes
    ----------
    name : str
    maps : list of float32 (H, W) arrays
        Values in [0, 1]; a pixel is a boundary at threshold t where its value is >= t.
    thresholds : int
        The thresholds to sweep (1: the map is binary, scored at 0.5).
    ms_per_image : float
        Wall time of making one map, the mean over the images.
    """

    name: str
    maps: list
    thresholds: int
    ms_per_image: float


def _levels(span: tuple[float, float], count: int) -> np.ndarray:
    return np.geomspace(span[0], span[1], count)


def _nested(edge_sets: Sequence[np.ndarray]) -> np.ndarray:
    """Each pixel's value: the last level's threshold (:func:`sweep_thresholds`) where it is an edge, 0 if none."""
    out = np.zeros(edge_sets[0].shape, np.float32)
    for edges, level in zip(edge_sets, sweep_thresholds(len(edge_sets))):
        out[edges] = level
    return out


def _count(count) -> int:
    return check_int(count, "count", minimum=1, maximum=MAX_LEVELS)


def sweep_thresholds(count: int) -> np.ndarray:
    """The thresholds at which a sweep of ``count`` levels is scored: (k + 1) / (count + 1), rounded to
    float32 as the sweeps' maps hold them (5 / 6 in float32 is below 5 / 6, and would fail its own level)."""
    levels = (np.arange(_count(count)) + 1.0) / (count + 1)
    return levels.astype(np.float32).astype(np.float64)


def _image(image) -> np.ndarray:
    from vmcl.pipeline import as_image

    return as_image(image, "image")


def canny_sweep(image: np.ndarray, count: int, *, machine: Machine | None = None) -> np.ndarray:
    """vmcl Canny swept over ``count`` high thresholds: float32 (H, W) of each pixel's last level
    (:func:`sweep_thresholds`), 0 where it is never an edge. ``image``: grey or RGB, as the machine takes it."""
    count = _count(count)
    machine = machine_for(machine)
    # Thresholds are in units of an image in [0, 1] (as_image's); canny makes RGB grey itself. The image
    # goes to the device once for all the levels.
    scaled = machine.to_device(_image(image))
    return _nested([canny(scaled, sigma=CANNY_SIGMA, low_threshold=LOW_RATIO * level, high_threshold=level,
                          machine=machine).get().astype(bool) for level in _levels(_VMCL_LEVELS, count)])


def opencv_canny_sweep(image: np.ndarray, count: int) -> np.ndarray:
    """OpenCV's Canny (L2 gradient, after a Gaussian of :data:`CANNY_SIGMA`) swept as :func:`canny_sweep`."""
    count = _count(count)
    image = np.round(_image(image) * 255).astype(np.uint8)  # OpenCV's Canny takes 8-bit images
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
    smoothed = cv2.GaussianBlur(grey, (0, 0), CANNY_SIGMA)
    return _nested([cv2.Canny(smoothed, LOW_RATIO * level, level, L2gradient=True) > 0
                    for level in _levels(_OPENCV_LEVELS, count)])


LOCAL_SPAN = (0.005, 20.0)
"""Local saliencies (gradient magnitude times pixels**0.5, image in [0, 1]) that :func:`local_saliency_sweep`
maps to 0 and 1, log-spaced between: the range the BSDS500 training images' curves span."""
STRUCTURAL_SPAN = (0.05, 5000.0)
"""Structural saliencies times relative strength that :func:`structural_saliency_sweep` maps to 0 and 1."""


def _log_levels(values: np.ndarray, span: tuple[float, float]) -> np.ndarray:
    """Values mapped to [0, 1] on a log scale over ``span`` (0 where a value is 0)."""
    low, high = span
    with np.errstate(divide="ignore"):
        levels = np.log(np.maximum(values, 0) / low) / np.log(high / low)
    return np.where(values > 0, np.clip(levels, 1e-6, 1), 0).astype(np.float32)


def _all_edges(image: np.ndarray, machine: Machine):
    """Canny at the sweeps' lowest level, with its gradient: every edge a sweep can keep."""
    return canny(machine.to_device(_image(image)), sigma=CANNY_SIGMA, low_threshold=LOW_RATIO * _VMCL_LEVELS[0],
                 high_threshold=_VMCL_LEVELS[0], return_gradient=True, machine=machine)


def local_saliency_sweep(image: np.ndarray, *, length_exponent: float | None = None,
                         curvature_scale: float | None = None, machine: Machine | None = None) -> np.ndarray:
    """Canny pruned by local saliency, as a sweep: every edge of vmcl Canny at the sweep's lowest level,
    each pixel given its curve's local saliency (:func:`vmcl.group.local_saliency`, the ``[grouping]``
    defaults unless given), mapped to [0, 1] by :data:`LOCAL_SPAN`."""
    from vmcl.group import link_edges, local_saliency, saliency_map
    from vmcl.pipeline import GroupingConfig

    machine = machine_for(machine)
    defaults = GroupingConfig()
    found = _all_edges(image, machine)
    curves = link_edges(found.edges, magnitude=found.magnitude, machine=machine)
    values = local_saliency(curves, length_exponent=defaults.length_exponent if length_exponent is None
                            else length_exponent,
                            curvature_scale=defaults.curvature_scale if curvature_scale is None else curvature_scale)
    return _log_levels(saliency_map(curves, values), LOCAL_SPAN)


def structural_saliency_sweep(image: np.ndarray, *, iterations: int | None = None,
                              gap_attenuation: float | None = None, machine: Machine | None = None) -> np.ndarray:
    """Canny pruned by structural saliency, as a sweep: every edge of vmcl Canny at the sweep's lowest level,
    each given its structural saliency (:func:`vmcl.group.structural_saliency`, elements of strength
    :func:`vmcl.group.saliency_strength`) times that strength, mapped to [0, 1] by :data:`STRUCTURAL_SPAN`:
    the measure ``edges.saliency = "structural"`` prunes by."""
    from vmcl.group import saliency_strength, structural_saliency
    from vmcl.pipeline import GroupingConfig

    machine = machine_for(machine)
    defaults = GroupingConfig()
    found = _all_edges(image, machine)
    strength = saliency_strength(found.edges, found.magnitude, machine=machine)
    network = structural_saliency(found.edges, strength=strength,
                                  iterations=defaults.iterations if iterations is None else iterations,
                                  gap_attenuation=defaults.gap_attenuation if gap_attenuation is None
                                  else gap_attenuation, machine=machine)
    values = to_host(network.saliency) * to_host(strength) * to_host(found.edges)
    return _log_levels(values, STRUCTURAL_SPAN)


def _timed(make: Callable[[BSDSImage], np.ndarray], images: Sequence[BSDSImage]) -> tuple[list, float]:
    maps, total = [], 0.0
    for item in images:
        start = time.perf_counter()
        maps.append(make(item))
        total += time.perf_counter() - start
    return maps, 1e3 * total / max(len(images), 1)


def boundary_maps(images: Sequence[BSDSImage], *, thresholds: int = 30, machine: Machine | None = None,
                  progress: Callable[[str], None] | None = None) -> list[MapSet]:
    """The maps of every method on ``images``: the soft map, the cartoon, vmcl's and OpenCV's Canny.

    The machine runs as a user runs it on one image: its defaults (the monocular machine with all its cues).
    """
    from vmcl.pipeline import VisionMachine

    thresholds = check_int(thresholds, "thresholds", minimum=2, maximum=MAX_LEVELS)
    vm = VisionMachine(machine=machine)
    results, soft_ms, cartoons = [], 0.0, []
    for item in images:
        start = time.perf_counter()
        result = vm.run(item.image)
        soft_ms += (time.perf_counter() - start) * 1e3
        results.append(result.boundary_strength)
        cartoons.append(result.discontinuities.astype(np.float32))
        if progress is not None:
            progress(item.name)
    vmcl_canny, canny_ms = _timed(lambda item: canny_sweep(item.image, thresholds, machine=vm.machine), images)
    cv_canny, cv_ms = _timed(lambda item: opencv_canny_sweep(item.image, thresholds), images)
    run_ms = soft_ms / max(len(images), 1)
    return [MapSet("vmcl cartoon, soft map (boundary_strength), swept", results, thresholds, run_ms),
            MapSet("vmcl cartoon, labels != 0 (binary)", cartoons, 1, run_ms),
            MapSet("vmcl Canny, threshold sweep", vmcl_canny, thresholds, canny_ms),
            MapSet("OpenCV Canny, threshold sweep", cv_canny, thresholds, cv_ms)]


def score_maps(maps: MapSet, images: Sequence[BSDSImage], *, workers: int = 1) -> BoundaryScores:
    """The BSDS benchmark's scores of one method's maps against the images' human boundaries."""
    if len(maps.maps) != len(images):
        raise InputValueError(f"{maps.name}: {len(maps.maps)} maps for {len(images)} images")
    # A swept map is scored at the benchmark's own evenly spaced thresholds, which are the sweeps' levels.
    levels = [0.5] if maps.thresholds == 1 else sweep_thresholds(maps.thresholds)
    return evaluate_boundaries(maps.maps, [item.boundaries for item in images], thresholds=levels, workers=workers)
