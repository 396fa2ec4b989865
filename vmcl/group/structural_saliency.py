"""Structural saliency: Sha'ashua and Ullman's locally connected network that finds long, smooth curves
through gaps and clutter.

Seed section "Saliency, grouping, and segmentation": a saliency operation on the edge detector's output,
before the MRF stage uses the intensity edges. Every pixel holds eight orientation elements, one per
neighbour step; an element is *actual* where the edge map links the pixel to that neighbour, *virtual*
(a gap) elsewhere. Each iteration every element takes the best of the three continuations leaving its
far end within 45 degrees:

    E'(i) = sigma(i) + rho(i) max_j f(i, j) E(j)

with sigma the element's strength (0 in a gap), rho 1 on the curve and ``gap_attenuation`` in a gap, and
f(i, j) = exp(-c 2 alpha tan(alpha / 2) / ds) for a turn alpha over a step of length ds (the discrete
integral of squared curvature, scaled by ``curvature_scale`` = c; a virtual element's direction is only
known to its 45-degree sector, so a turn into or out of a gap is counted from the sector's edge; within
a gap turns cost in full, lest a curve loop back through empty space and count its own pixels again). After n iterations E(i) is the
saliency of the best curve of n elements that starts with i, so long smooth curves win over short or
wiggly ones, and a curve broken by short gaps keeps most of its saliency. An actual element's direction
is the curve's own tangent (:attr:`vmcl.group.curves.Curves.tangent`, smoothed along the arc) rather than
its grid step, so a smooth curve at any angle turns little from pixel to pixel; a virtual element's
direction is its step.

A pixel's saliency is the best curve through it: its best element ahead plus the best leaving it the
other way.

References
----------
A. Sha'ashua and S. Ullman, "Structural saliency: the detection of globally salient structures using a
locally connected network", Proc. ICCV, 321-327, 1988.
T. D. Alter and R. Basri, "Extracting salient curves from images: an analysis of the saliency network",
IJCV 27(1):51-69, 1998.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import reduce as cm_reduce
from vmcl.cm.core import ArrayLike, check_int, check_real, field, machine_for, result
from vmcl.errors import InputValueError
from vmcl.group.curves import RUN, link_edges
from vmcl.machine import Machine
from vmcl.mrf.checks import FLOAT32_MAX, check_weights, within_float32

__all__ = ["MAX_ITERATIONS", "StructuralSaliency", "saliency_strength", "structural_saliency"]

MAX_ITERATIONS = 10_000
"""The most iterations :func:`structural_saliency` runs: curves longer than any image's perimeter."""


class StructuralSaliency(NamedTuple):
    """What :func:`structural_saliency` returns (NumPy, or device arrays for device input).

    Attributes
    ----------
    saliency : float32 (H, W)
        Each pixel's saliency: the best curve through it (in elements of strength 1: about its length in
        pixels for a straight curve of unit strength that the iterations could follow to its ends).
        Gap pixels on a salient completion get values too.
    elements : float32 (8, H, W)
        Each element's saliency, plane k for the step towards neighbour k (E, NE, N, NW, W, SW, S, SE).
    """

    saliency: ArrayLike
    elements: ArrayLike


def structural_saliency(edges: ArrayLike, *, tangent: ArrayLike | None = None, strength: ArrayLike | None = None,
                        iterations: int = 30, gap_attenuation: float = 0.85, curvature_scale: float = 1.0,
                        machine: Machine | None = None) -> StructuralSaliency:
    """Sha'ashua and Ullman's structural saliency of an edge map.

    Parameters
    ----------
    edges : (H, W) bool or uint8 array, NumPy or device
        The edge map (e.g. Canny's, or a line drawing one pixel thin).
    tangent : (H, W) float32 array, optional
        Each edge pixel's tangent direction in radians (its sense does not matter); NaN where unknown
        (the pixel's elements then follow their grid steps); infinities are refused. Default: the curves'
        own (:func:`vmcl.group.curves.link_edges`; NaN at single-pixel curves).
    strength : (H, W) float32 array, optional
        Each edge pixel's local strength, the elements' sigma (e.g. the gradient magnitude over its
        median on the edges); finite and >= 0, NumPy or device arrays alike, and at most float32's
        largest / (4 * ``iterations``), so that the saliency (a sum of up to 2 * ``iterations`` strengths)
        stays within float32. Default: 1 on every edge pixel.
    iterations : int
        Network iterations, in [1, :data:`MAX_ITERATIONS`]: the length (in elements) of the curves the
        measure looks along.
    gap_attenuation : float
        rho of a virtual element, in [0, 1]: a gap of g pixels keeps gap_attenuation**g of what lies beyond.
        The defaults (30 iterations, 0.85) were chosen on shapes-in-clutter displays of training seeds
        (:func:`vmcl.scenes.clutter_display`, benchmarks/grouping_fit.py).
    curvature_scale : float
        c in the coupling, >= 0 and within float32's range: 0 ignores curvature.
    machine : vmcl.Machine, optional

    Returns
    -------
    StructuralSaliency
        (saliency, elements).

    Examples
    --------
    >>> import numpy as np
    >>> drawing = np.zeros((32, 48), bool); drawing[16, 4:44] = True; drawing[5, 10:14] = True
    >>> s = structural_saliency(drawing, iterations=40).saliency
    >>> bool(s[16, 24] > 3 * s[5, 11])
    True
    """
    machine = machine_for(machine)
    if isinstance(edges, np.ndarray) and edges.dtype == np.bool_:
        edges = edges.view(np.uint8)
    mask, host = field(edges, "edges", machine, ndims=(2,), dtypes=(np.uint8,))
    iterations = check_int(iterations, "iterations", minimum=1, maximum=MAX_ITERATIONS)
    gap_attenuation = check_real(gap_attenuation, "gap_attenuation", minimum=0, maximum=1)
    # The device holds c as a float32: a larger finite value would become an infinity there.
    curvature_scale = within_float32(check_real(curvature_scale, "curvature_scale", minimum=0), "curvature_scale")
    height, width = mask.shape
    if tangent is None:
        tangents = link_edges(mask, machine=machine).tangent
        assert isinstance(tangents, cl_array.Array)  # device edges give device maps
    else:
        tangents = _matching(tangent, "tangent", mask, machine)
        # NaN means unknown (the elements follow their steps); an infinity is no direction either, but the
        # device does not read it as unknown: its turns come out NaN, which cuts every curve through the
        # pixel. cm_reduce.extremes skips NaN, so only infinities show in it.
        low, high = cm_reduce.extremes(tangents, machine=machine)
        if math.isinf(low) or math.isinf(high):
            raise InputValueError("tangent must be finite where known (NaN where unknown): it holds an infinity")
    if strength is None:
        weights = machine.empty(mask.shape, np.float32)
        machine.launch(machine.kernel("structural_saliency", "unit_strength"), (mask.size,), mask, weights,
                       np.int64(mask.size))
    else:
        weights = _matching(strength, "strength", mask, machine)
        # A device strength is checked on the device, as a host one on the host.
        check_weights(weights if isinstance(strength, cl_array.Array) else strength, "strength", machine)
        # A pixel's saliency sums up to 2 * iterations strengths in float32: the limit keeps it finite, with
        # a factor of 2 to spare for the sums' rounding.
        largest = float(cm_reduce.reduce(weights, "max", machine=machine).get())
        limit = FLOAT32_MAX / (4 * iterations)
        if largest > limit:
            raise InputValueError(f"strength must be at most float32's largest / (4 * iterations) = {limit:.4g} "
                                  f"for iterations={iterations}, lest the saliency overflow float32; got {largest:.4g}")
    machine.require_memory("structural_saliency", 8 * 6 * 4 * mask.size, 8 * 3 * 4 * mask.size)
    sizes = (np.int32(width), np.int32(height))
    links = machine.empty(mask.shape, np.uint8)
    machine.launch(machine.kernel("curves", "link_pixels"), (-(-width // RUN), height), mask, links, *sizes)
    elements = (8, height, width)
    sigma, rho = machine.empty(elements, np.float32), machine.empty(elements, np.float32)
    coupling = machine.empty((3, *elements), np.float32)
    machine.launch(machine.kernel("structural_saliency", "prepare"), (width, height, 8), links, tangents, weights,
                   sigma, rho, coupling, np.float32(gap_attenuation), np.float32(curvature_scale), *sizes)
    current, spare = sigma.copy(queue=machine.queue), machine.empty(elements, np.float32)
    step = machine.kernel("structural_saliency", "iterate")
    # The first iteration is E = sigma itself: n - 1 more make curves of n elements.
    for _ in range(iterations - 1):
        machine.launch(step, (width, height, 8), current, sigma, rho, coupling, spare, *sizes)
        current, spare = spare, current
    saliency = machine.empty(mask.shape, np.float32)
    machine.launch(machine.kernel("structural_saliency", "pixel_saliency"), (width, height), current, saliency, *sizes)
    return StructuralSaliency(result(saliency, host), result(current, host))


def saliency_strength(edges: ArrayLike, magnitude: ArrayLike, *, machine: Machine | None = None) -> ArrayLike:
    """Each edge pixel's gradient magnitude over the median magnitude on the edges (0 off the edges): a
    ``strength`` for :func:`structural_saliency` that does not depend on the image's contrast.

    Parameters
    ----------
    edges : (H, W) bool or uint8 array, NumPy or device
    magnitude : (H, W) float32 array
        Finite and >= 0 (a gradient magnitude), with a median above 0 on the edges.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W), NumPy or device as ``edges`` came; all 0 where there are no edges.

    Raises
    ------
    InputValueError
        ``magnitude`` holds NaN, an infinity or a negative value, or is 0 on at least half of the edge
        pixels (a median of 0 leaves no contrast to divide by).
    """
    machine = machine_for(machine)
    if isinstance(edges, np.ndarray) and edges.dtype == np.bool_:
        edges = edges.view(np.uint8)
    mask, host = field(edges, "edges", machine, ndims=(2,), dtypes=(np.uint8,))
    strength = _matching(magnitude, "magnitude", mask, machine).get()
    check_weights(strength, "magnitude", machine)  # read back already: checked on the host
    on = mask.get().astype(bool)
    if not on.any():
        return np.zeros(mask.shape, np.float32) if host else machine.to_device(np.zeros(mask.shape, np.float32))
    median = float(np.median(strength[on]))
    if not median > 0:
        raise InputValueError("magnitude is 0 on at least half of the edge pixels (its median there): there is no "
                              "contrast to scale the strength by")
    scaled = np.where(on, strength / median, 0).astype(np.float32)
    return scaled if host else machine.to_device(scaled)


def _matching(x: ArrayLike, name: str, mask: cl_array.Array, machine: Machine) -> cl_array.Array:
    data, _ = field(x, name, machine, ndims=(2,), dtypes=(np.float32,))
    if data.shape != mask.shape:
        raise InputValueError(f"{name} has shape {data.shape}, edges {mask.shape}: they must match")
    return data
