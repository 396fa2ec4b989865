"""Local saliency (after Beymer): each curve scored by its length, its smoothness and its strength, and the
edge map pruned to the salient curves.

Seed section "Saliency, grouping, and segmentation": "a saliency operation on the output of the edge
detector", favouring long, smooth, strong curves, before the MRF stage uses the edges. A curve's saliency
is

    S = m * L**length_exponent * exp(-kappa / curvature_scale)

with m its mean gradient magnitude, L its length in pixels and kappa its mean |curvature| (radians per
pixel), all from :func:`vmcl.group.curves.link_edges`. A curve linked without a magnitude counts m = 1.
"""

from __future__ import annotations

import itertools

import numpy as np

from vmcl.cm.core import check_real, finite_float32, real_host_array, to_host
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.group.curves import BRANCH, Curves

__all__ = ["local_saliency", "saliency_map", "salient_edges"]


def _curves(curves) -> Curves:
    if not isinstance(curves, Curves):
        raise InputTypeError(f"curves must be a vmcl.group.Curves (from link_edges), got {type(curves).__name__}")
    return curves


def local_saliency(curves: Curves, *, length_exponent: float = 0.5, curvature_scale: float = 0.5) -> np.ndarray:
    """Each curve's local saliency.

    Parameters
    ----------
    curves : Curves
    length_exponent : float
        How strongly length counts, >= 0 (0: not at all; 1: saliency grows with length).
    curvature_scale : float
        The mean |curvature| (radians per pixel) that divides a curve's saliency by e, > 0 (a circle of
        radius r has curvature 1 / r).

    Returns
    -------
    float64 (C,)
        One value per curve, in the units of the magnitude (gradient magnitude times pixels**length_exponent).
    """
    curves = _curves(curves)
    length_exponent = check_real(length_exponent, "length_exponent", minimum=0)
    curvature_scale = check_real(curvature_scale, "curvature_scale", above=0)
    strength = np.where(np.isnan(curves.magnitude), 1.0, curves.magnitude)
    # A single pixel has length 0; it counts as one pixel long.
    with np.errstate(over="ignore"):
        saliency = (strength * np.maximum(curves.length, 1.0) ** length_exponent
                    * np.exp(-curves.mean_curvature / curvature_scale))
    largest = np.finfo(np.float32).max
    if saliency.size and not np.all(np.abs(saliency) <= largest):
        # Blamed on the length alone where it overflows at a strength of 1 (the saliency without a
        # magnitude), else on the magnitude the curves were linked with.
        with np.errstate(over="ignore"):
            by_length = np.maximum(curves.length, 1.0) ** length_exponent
        if not np.all(by_length <= largest):
            raise InputValueError(f"length_exponent {length_exponent:g} makes the longest curves' saliency overflow "
                                  f"float32 (curves up to {float(np.max(curves.length)):.0f} px long); use a smaller one")
        raise InputValueError(f"magnitude (link_edges') up to {float(np.max(strength)):.3g} makes the curves' saliency "
                              f"(magnitude times length**length_exponent, here up to {float(np.max(by_length)):.3g}) "
                              "overflow float32; scale the magnitude down")
    return saliency


def saliency_map(curves: Curves, values: np.ndarray) -> np.ndarray:
    """Per-curve values (finite, within float32's range) painted onto the curves' pixels: float32 (H, W), 0
    off the curves and on branch pixels (which belong to no one curve)."""
    curves = _curves(curves)
    # Painted into a float32 map: NaN, infinities and values beyond float32's range would be painted as
    # they are or become infinities, and compare false (or true) against any threshold (finite_float32
    # refuses what overflows its cast, with a message).
    with np.errstate(over="ignore"):
        values = finite_float32(real_host_array(values, "values", ndims=(1,), empty=True), "values")
    values = values.astype(np.float64)
    if values.shape != (len(curves),):
        raise InputValueError(f"values must hold one value per curve ({len(curves)}), got shape {values.shape}")
    labels = np.asarray(to_host(curves.labels))
    painted = np.zeros(labels.shape, np.float32)
    on = labels >= 0
    painted[on] = values[labels[on]]
    return painted


def salient_edges(curves: Curves, saliency: np.ndarray, threshold: float) -> np.ndarray:
    """The edge map pruned to the curves whose saliency is at least ``threshold`` (bool (H, W)); branch
    pixels stay where a kept curve touches them."""
    threshold = check_real(threshold, "threshold", minimum=0)
    curves = _curves(curves)
    try:
        painted = saliency_map(curves, saliency)
    except InputError as error:
        raise type(error)(str(error).replace("values", "saliency", 1)) from None
    labels = np.asarray(to_host(curves.labels))
    keep = (painted >= threshold) & (labels >= 0)
    # A branch pixel stays where one of its 8 neighbours is kept: looked up at the branch pixels alone, the
    # few pixels it decides, not by dilating the whole map.
    ys, xs = np.nonzero(labels == BRANCH)
    if len(ys):
        height, width = keep.shape
        touched = np.zeros(len(ys), bool)
        for dy, dx in itertools.product((-1, 0, 1), repeat=2):
            if dy or dx:
                y, x = ys + dy, xs + dx
                inside = (y >= 0) & (y < height) & (x >= 0) & (x < width)
                touched[inside] |= keep[y[inside], x[inside]]
        keep[ys[touched], xs[touched]] = True
    return keep
