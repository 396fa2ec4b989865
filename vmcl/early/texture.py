"""Texture: the density of blob textons, and texture-edge candidates from its gradient.

Seed section "Texture", "a greatly simplified parallel version of the texture algorithm developed by
Voorhees and Poggio": the image is filtered by the Laplacian of a Gaussian at a fine scale, which
selects the textural elements, and "thresholded at a non-zero value to find the regions which comprise
the blobs". Contrast boundaries also give blobs at the fine scale; they persist at a coarser scale,
where the texture's blobs fade, so "blobs at the coarser scale are removed from the fine scale image".
A summation then "counts the density of blobs (the portion of the summation region covered by blobs)"
around each point: here the Connection Machine's window sum by scans, :func:`vmcl.cm.scan.box_sum`.
Discontinuities of the density mark occlusion boundaries and changes of surface orientation.

The blob rule
-------------
Both Laplacians are the exact Gaussian followed by the 5-point Laplacian
(:func:`vmcl.early.filters.laplacian_of_gaussian`), scale-normalised by sigma**2 so that a contrast
step gives the same peak response (0.24 times its contrast) at every scale while a blob's response
fades above its own size. A pixel is a fine blob when ``|fine_sigma**2 * LoG_fine| > threshold``; it is
removed when the coarse map ``coarse_sigma**2 * LoG_coarse`` exceeds the threshold with the same sign at
the pixel or one of its 8 neighbours. Dark and bright blobs both count.

The edge rule
-------------
At each pixel, the densities of the two adjacent (2r+1)-wide windows on either side of its right site
are differenced (and likewise below), giving a gradient whose magnitude peaks on a boundary between
two textures. Candidates are the maxima of the magnitude along its dominant axis that exceed
``max(noise_factor * s, MIN_DENSITY_STEP)``, s estimated from the median magnitude as
:mod:`vmcl.early.noise` does (``s = median / sqrt(2 ln 2)``). The default factor,
:data:`NOISE_FACTOR`, was fitted on rendered scenes (benchmarks/texture_fit.py): the texture MRF, whose
lines are allowed only near these candidates, draws about as many lines whatever its data weight (the
same results file), so the candidates' own threshold decides how many false texture lines the cartoon
gets. The floor keeps untextured images (density 0 everywhere) free of candidates.

Images are grey or RGB, uint8, uint16 or float, NumPy or device arrays, converted to grey as
:mod:`vmcl.early.filters` describes; ``threshold`` is in the input's units. NumPy in gives NumPy out, a
device array in gives a device array out.

References
----------
H. Voorhees and T. Poggio, "Detecting textons and texture boundaries in natural images", Proc. First
International Conference on Computer Vision (ICCV), 250-258, 1987.
H. Voorhees and T. Poggio, "Computing texture boundaries from images", Nature 333:364-367, 1988.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
"""

from __future__ import annotations

from typing import NamedTuple, overload

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import scan as _scan
from vmcl.cm.core import (
    ArrayLike,
    check_int,
    check_real,
    check_sigma,
    full_scale,
    image_field,
    machine_for,
    result,
)
from vmcl.early import noise as _noise
from vmcl.early.filters import laplacian_of_gaussian
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["COARSE_SIGMA", "FINE_SIGMA", "MIN_DENSITY_STEP", "NOISE_FACTOR", "RADIUS", "THRESHOLD", "TextureEdges",
           "density", "texture_edges"]

FINE_SIGMA = 1.0
"""Default ``fine_sigma``: the machine's (vmcl.pipeline.TextureConfig)."""

COARSE_SIGMA = 4.0
"""Default ``coarse_sigma``: the machine's."""

THRESHOLD = 0.08
"""Default blob threshold, as a share of the input's full scale: the machine's for images in [0, 1]."""

RADIUS = 24
"""Default window radius (a 49-pixel window): the machine's."""

MIN_DENSITY_STEP = 0.01
"""Smallest density difference (share of a window covered by blobs) that can be a texture edge."""

NOISE_FACTOR = 3.5
"""Default of :func:`texture_edges`'s ``noise_factor``: candidates exceed this many noise deviations of the
density's gradient (fitted by benchmarks/texture_fit.py on rendered scenes)."""


class TextureEdges(NamedTuple):
    """What :func:`texture_edges` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    edges : bool (H, W); uint8 0/1 on the device
        Candidates, one pixel thick, on the left of (or above) the boundary between two densities.
    density : float32 (H, W)
        As :func:`density` returns it.
    """

    edges: ArrayLike
    density: ArrayLike


def _check(fine_sigma, coarse_sigma, threshold, radius, image) -> tuple[float, float, float, int]:
    fine = check_sigma(fine_sigma, "fine_sigma")
    coarse = check_sigma(coarse_sigma, "coarse_sigma")
    if coarse <= fine:
        raise InputValueError(f"coarse_sigma must exceed fine_sigma, got coarse_sigma={coarse} <= fine_sigma={fine}")
    # Blobs are thresholded at a non-zero value.
    if threshold is None:
        threshold = THRESHOLD * full_scale(getattr(image, "dtype", np.float32))
    threshold = check_real(threshold, "threshold", above=0)
    return fine, coarse, threshold, check_int(radius, "radius", minimum=1)


def _image_and_radius(image, radius: int, fine: float, coarse: float,
                      machine: Machine) -> tuple[cl_array.Array, bool, int]:
    """The image on the device, whether it came from the host, and the radius cut to the image: windows
    are cut at the border, so a radius beyond the image's longer side gives the same windows (and the
    kernels' 64-bit index arithmetic never sees a larger one)."""
    # Per pixel: two Laplacians and their smoothing passes, the blobs and their window sums, the
    # density, and the gradient's magnitude, axis and edges.
    data, host = image_field(image, machine, what="texture density", footprint=56,
                             widths={"fine_sigma": fine, "coarse_sigma": coarse})
    return data, host, min(radius, max(data.shape[:2]))


def _density(machine: Machine, data: cl_array.Array, fine: float, coarse: float, threshold: float,
             radius: int) -> cl_array.Array:
    height, width = data.shape[:2]
    size, dims = (width, height), (np.int64(width), np.int64(height))
    fine_log = laplacian_of_gaussian(data, sigma=fine, machine=machine)
    coarse_log = laplacian_of_gaussian(data, sigma=coarse, machine=machine)
    blobs = machine.empty((height, width), np.int32)
    machine.launch(machine.kernel("texture", "textons"), size, fine_log, coarse_log, blobs,
                   np.float32(fine * fine), np.float32(coarse * coarse), np.float32(threshold), *dims)
    sums = _scan.box_sum(blobs, radius, machine=machine)
    out = machine.empty((height, width), np.float32)
    machine.launch(machine.kernel("texture", "window_mean"), size, sums, out, np.int64(radius), *dims)
    return out


@overload
def density(image: np.ndarray, *, fine_sigma: float = FINE_SIGMA, coarse_sigma: float = COARSE_SIGMA,
            threshold: float | None = None, radius: int = RADIUS,
            machine: Machine | None = None) -> np.ndarray: ...
@overload
def density(image: cl_array.Array, *, fine_sigma: float = FINE_SIGMA, coarse_sigma: float = COARSE_SIGMA,
            threshold: float | None = None, radius: int = RADIUS,
            machine: Machine | None = None) -> cl_array.Array: ...
def density(image: ArrayLike, *, fine_sigma: float = FINE_SIGMA, coarse_sigma: float = COARSE_SIGMA,
            threshold: float | None = None, radius: int = RADIUS,
            machine: Machine | None = None) -> ArrayLike:
    """Share of the (2r+1) x (2r+1) window around every pixel covered by fine-scale blobs (textons).

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        uint8, uint16 or float (float64 is converted to float32; device arrays must be uint8, uint16 or
        float32); NumPy input must be finite. RGB is converted to grey.
    fine_sigma : float
        Scale of the textural elements, in pixels, > 0: about the blobs' own standard deviation; default
        :data:`FINE_SIGMA`.
    coarse_sigma : float
        Scale at which the texture's blobs have faded but contrast boundaries remain, > fine_sigma.
        Three to four times fine_sigma separates them (the scale-normalised response of a blob of
        deviation b falls as ``sigma**2 b**2 / (b**2 + sigma**2)**2``, only 18% from b to 1.6 b); default
        :data:`COARSE_SIGMA`.
    threshold : float, optional
        Blob threshold on the scale-normalised Laplacians, in the input's units, > 0. A step of
        contrast c responds with 0.24 c. Default: :data:`THRESHOLD` of the input's full scale (255 for
        uint8, 65535 for uint16, 1 for floats).
    radius : int
        r >= 1: the window is 2r+1 pixels wide; windows are cut at the image's border; default
        :data:`RADIUS`.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W) in [0, 1]: NumPy for NumPy input, a device array for device input.

    Notes
    -----
    See the module's blob rule. Time does not depend on ``radius`` (the window sums are scans); it
    grows with the Gaussians' widths, ``int(4 sigma + 0.5)`` taps each side.

    References
    ----------
    H. Voorhees and T. Poggio, "Detecting textons and texture boundaries in natural images", ICCV 1987.
    H. Voorhees and T. Poggio, "Computing texture boundaries from images", Nature 333:364-367, 1988.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.texture import density
    >>> dots = np.full((64, 64), 0.8, np.float32); dots[4::8, 4::8] = 0.0
    >>> d = density(dots, fine_sigma=1.0, coarse_sigma=4.0, threshold=0.05, radius=8)
    >>> bool(d[32, 32] > 0.05), float(density(np.ones((64, 64)), fine_sigma=1.0, coarse_sigma=4.0,
    ...                                               threshold=0.05, radius=8).max())
    (True, 0.0)
    """
    machine = machine_for(machine)
    fine, coarse, threshold, radius = _check(fine_sigma, coarse_sigma, threshold, radius, image)
    data, host, radius = _image_and_radius(image, radius, fine, coarse, machine)
    return result(_density(machine, data, fine, coarse, threshold, radius), host)


def texture_edges(image: ArrayLike, *, fine_sigma: float = FINE_SIGMA, coarse_sigma: float = COARSE_SIGMA,
                  threshold: float | None = None, radius: int = RADIUS, edge_threshold: float | None = None, noise_factor: float = NOISE_FACTOR,
                  machine: Machine | None = None) -> TextureEdges:
    """Texture-edge candidates: maxima of the texton density's gradient across the boundary.

    Parameters
    ----------
    image, fine_sigma, coarse_sigma, threshold, radius
        As for :func:`density`.
    edge_threshold : float, optional
        Smallest density difference between the two adjacent windows of a candidate, >= 0. Default:
        ``max(noise_factor * s, MIN_DENSITY_STEP)`` (the module's edge rule).
    noise_factor : float
        > 0: the edge rule's multiple of the gradient's noise deviation s (ignored with
        ``edge_threshold``).
    machine : vmcl.Machine, optional

    Returns
    -------
    TextureEdges
        (edges, density).

    Notes
    -----
    The outermost ring of pixels is never a candidate. Without ``edge_threshold``, the histogram's range
    (the gradient's maximum) stays on the device.

    References
    ----------
    H. Voorhees and T. Poggio, "Computing texture boundaries from images", Nature 333:364-367, 1988.
    J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.
    """
    machine = machine_for(machine)
    fine, coarse, threshold, radius = _check(fine_sigma, coarse_sigma, threshold, radius, image)
    if edge_threshold is not None:
        edge_threshold = check_real(edge_threshold, "edge_threshold", minimum=0)
    # Bounded by float32's range: the device multiplies the noise deviation by it.
    noise_factor = check_real(noise_factor, "noise_factor", above=0, maximum=float(np.finfo(np.float32).max))
    data, host, radius = _image_and_radius(image, radius, fine, coarse, machine)
    dens = _density(machine, data, fine, coarse, threshold, radius)
    height, width = dens.shape
    size, dims = (width, height), (np.int64(width), np.int64(height))
    magnitude, axis = machine.empty(dens.shape, np.float32), machine.empty(dens.shape, np.uint8)
    machine.launch(machine.kernel("texture", "density_gradient"), size, dens, magnitude, axis,
                   np.int64(radius), *dims)
    if edge_threshold is None:
        # The kernel reads the rule's low threshold only.
        rule = _noise.noise_rule(noise_factor, noise_factor)
        pairs, _ = _noise.threshold_field(machine, magnitude, rule, local=False)
        floor = MIN_DENSITY_STEP
    else:
        pairs, floor = magnitude, float(edge_threshold)
    edges = machine.empty(dens.shape, np.uint8)
    machine.launch(machine.kernel("texture", "texture_edges"), size,
                   magnitude, axis, pairs, edges, np.float32(floor), *dims, np.int32(edge_threshold is not None))
    return TextureEdges(edges.get().view(np.bool_) if host else edges, result(dens, host))
