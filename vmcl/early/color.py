"""Colour: Hurlbert and Poggio's hue, and albedo-edge candidates from its gradient.

Seed section "Color". Under the single-source assumption the illumination separates into a spectral
part and a spatial one, and a Lambertian world images as

    I^nu(x, y) = k^nu E(x, y) rho^nu(x, y),    nu = red, green, blue,

with E the effective illumination (light gradients, shading and shadows). The hue

    H(x, y) = I^r / (I^r + I^g) = k^r rho^r / (k^r rho^r + k^g rho^g)

does not depend on E: it is piecewise constant, and changes only where the albedo rho^r or rho^g does.
:func:`hue` computes it at every pixel (one work-item each); :func:`albedo_edges` marks where its
gradient stands out of the noise, the candidates the MRF stage uses when it restores H as piecewise
constant. Specular reflections break the model (the paper's restriction).

Images are RGB (H, W, 3), uint8, uint16 or float, NumPy or device arrays; NumPy in gives NumPy out, a
device array in gives a device array out. Intensities are in the input's units; its *full scale* is 255
for uint8, 65535 for uint16 and 1 for float.

The edge rule
-------------
Where the albedo is constant, H varies only by noise. With independent noise of deviation s on each
channel, H has deviation ``s * sqrt(R^2 + G^2) / (R + G)^2``: dark pixels have noisier hues. Each
forward difference of H (towards the right and the lower neighbour, the dual-lattice sites a pixel owns
in :mod:`vmcl.scenes`) is divided by its own noise deviation in units of s, so its magnitude z follows a
Rayleigh law of scale s at every brightness. s is estimated as :mod:`vmcl.early.noise` does for Canny,
``s = median(z) / sqrt(2 ln 2)`` over the valid pixels, but never below :data:`NOISE_FLOOR` (the
quantisation noise of an 8-bit camera), and a pixel is a candidate when

    z > NOISE_HIGH * max(s, NOISE_FLOOR * full scale),

NOISE_HIGH = 4.1 (:data:`vmcl.early.noise.NOISE_HIGH`). The two differences share the centre pixel
(correlation 1/2), so z is not exactly Rayleigh: on pure noise s comes out a little low and more pixels
pass than an exact Rayleigh law would let through. Shadow and shading edges change E only, so H does
not step there.

The median comes from a histogram of z on the device, as in :mod:`vmcl.early.noise`, but with bins of
1/16 of an octave (:data:`HISTOGRAM_BINS`, by z's float exponent and leading mantissa bits) instead of
4096 linear bins over [0, max z]: they need no range, so nothing is read back to the host, and their
resolution follows the median rather than the largest edge. Within a bin the values are taken as spread
evenly, which puts the median close to ``np.median``'s on Gaussian noise; on 8-bit images, whose z
clusters on a few quantised values, the even spread is coarser and the median less exact.

References
----------
A. Hurlbert and T. Poggio, "A network for image segmentation using color", Advances in Neural
Information Processing Systems 1 (NIPS 1988), 297-304, 1989.
A. Hurlbert, "The computation of color", MIT AI Lab Technical Report 1154, 1989.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_bool,
    check_real,
    field,
    finite_float32,
    full_scale,
    launch_flat,
    launch_rows,
    machine_for,
    mask_result,
    result,
    vector_kernel,
)
from vmcl.early import noise as _noise
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["HISTOGRAM_BINS", "MIN_INTENSITY", "NOISE_FLOOR", "AlbedoEdges", "Hue", "albedo_edges", "hue"]

MIN_INTENSITY = 0.05
"""Default ``min_intensity`` as a share of the full scale: R + G below 5% of it is too dark for a hue."""

NOISE_FLOOR = 1.0 / (255.0 * math.sqrt(12.0))
"""Smallest noise deviation the edge rule assumes, as a share of the full scale: 8-bit quantisation."""

_THRESHOLD_ITEMS = 256
"""The work-group that totals the bands' histograms and finds the median (color.cl's THRESHOLD_ITEMS)."""
HISTOGRAM_BINS = (0x7F800000 >> 19) + 1
"""Bins of the noise estimate's histogram of z: 1/16 of an octave each, from 0 to infinity (color.cl)."""
_MEDIAN_OF_RAYLEIGH = math.sqrt(2.0 * math.log(2.0))



class Hue(NamedTuple):
    """What :func:`hue` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    hue : float32 (H, W), or (H, W, 2) for the chromaticity pair
        NaN where the pixel is not valid.
    valid : bool (H, W); uint8 0/1 on the device
        Pixels whose channels and denominator are finite (its sum overflows float32 only for channels near
        its largest value) and whose denominator reaches ``min_intensity``.
    """

    hue: ArrayLike
    valid: ArrayLike


class AlbedoEdges(NamedTuple):
    """What :func:`albedo_edges` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    edges : bool (H, W); uint8 0/1 on the device
        Candidates: pixels whose hue differs from their right or lower neighbour's beyond the noise.
    hue : float32 (H, W)
        H = R / (R + G), NaN where not valid (as :func:`hue`).
    valid : bool (H, W); uint8 0/1 on the device
    """

    edges: ArrayLike
    hue: ArrayLike
    valid: ArrayLike


def _rgb(rgb, machine: Machine) -> tuple[cl_array.Array, bool]:
    """Check an RGB image and return it on the device (uint8, uint16 or float32) with its origin."""
    if isinstance(rgb, (np.ndarray, cl_array.Array)) and (rgb.ndim != 3 or rgb.shape[2] != 3):
        raise InputValueError(f"rgb must be an RGB image of shape (H, W, 3), got shape {rgb.shape}: a grey image "
                         f"has no hue")
    return field(finite_float32(rgb, "rgb"), "rgb", machine, ndims=(3,), dtypes=tuple(IMAGE_TYPES))


def _min_intensity(value, dtype: np.dtype) -> float:
    if value is None:
        return MIN_INTENSITY * full_scale(dtype)
    return check_real(value, "min_intensity", above=0)


def hue(rgb: ArrayLike, *, min_intensity: float | None = None, chromaticity: bool = False,
        machine: Machine | None = None) -> Hue:
    """Hurlbert and Poggio's hue H = R / (R + G) at every pixel, with where it is defined.

    Parameters
    ----------
    rgb : ndarray or pyopencl.array.Array, (H, W, 3)
        uint8, uint16 or float (float64 is converted to float32; device arrays must be uint8, uint16 or
        float32). NumPy input must be finite.
    min_intensity : float, optional
        Smallest denominator (R + G, or R + G + B for the pair) of a valid pixel, in the input's units,
        > 0. Default: :data:`MIN_INTENSITY` of the full scale (12.75 for uint8, 0.05 for float). With
        channel noise s, H's deviation is at most ``s / min_intensity`` on valid pixels.
    chromaticity : bool
        Return the chromaticity pair (R / (R + G + B), G / (R + G + B)) instead of H, shape (H, W, 2).
        It is as independent of E as H, and sees changes of rho^b that H misses.
    machine : vmcl.Machine, optional

    Returns
    -------
    Hue
        (hue, valid). Pixels with a non-finite channel (possible in device input) are not valid.

    References
    ----------
    A. Hurlbert and T. Poggio, "A network for image segmentation using color", NIPS 1988.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.color import hue
    >>> rgb = np.array([[[0.6, 0.2, 0.1], [0.06, 0.02, 0.01], [0.01, 0.01, 0.3]]], np.float32)
    >>> h, valid = hue(rgb)
    >>> [round(float(v), 6) for v in h[0, :2]], valid.tolist()
    ([0.75, 0.75], [[True, True, False]])
    """
    machine = machine_for(machine)
    data, host = _rgb(rgb, machine)
    threshold = _min_intensity(min_intensity, data.dtype)
    height, width = data.shape[:2]
    chroma = check_bool(chromaticity, "chromaticity")
    out = machine.empty((height, width, 2) if chroma else (height, width), np.float32)
    valid = machine.empty((height, width), np.uint8)
    kernel = machine.kernel("color", "hue", IN_T=IMAGE_TYPES[data.dtype], CHROMA=int(chroma))
    machine.launch(kernel, (width, height), data, out, valid, np.float32(threshold), np.int64(width),
                   np.int64(height))
    return Hue(result(out, host), mask_result(valid, host))


def albedo_edges(rgb: ArrayLike, *, min_intensity: float | None = None, threshold: float | None = None,
                 machine: Machine | None = None) -> AlbedoEdges:
    """Albedo-edge candidates: pixels where the hue's gradient stands out of the noise.

    Parameters
    ----------
    rgb : ndarray or pyopencl.array.Array, (H, W, 3); uint8, uint16 or float
        As for :func:`hue`.
    min_intensity : float, optional
        As for :func:`hue`.
    threshold : float, optional
        Threshold on the noise-normalised hue gradient z (in the input's intensity units, see the
        module's edge rule), >= 0. Default: ``NOISE_HIGH * max(s, NOISE_FLOOR * full scale)`` with s
        estimated from the median of z.
    machine : vmcl.Machine, optional

    Returns
    -------
    AlbedoEdges
        (edges, hue, valid).

    Notes
    -----
    A candidate marks the pixel on the left of (or above) the step, the pixel :mod:`vmcl.scenes`
    labels. Pixels next to a non-valid one are never candidates. The kernels are enqueued back to back
    with no wait (the noise estimate stays on the device).

    References
    ----------
    A. Hurlbert and T. Poggio, "A network for image segmentation using color", NIPS 1988.
    J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.color import albedo_edges
    >>> rgb = np.ones((8, 8, 3), np.float32) * np.array([0.2, 0.6, 0.3], np.float32)
    >>> rgb[:, 4:, 0] = 0.6
    >>> rgb *= np.linspace(0.5, 1.0, 8, dtype=np.float32)[:, None, None]  # shading changes E only
    >>> np.flatnonzero(albedo_edges(rgb).edges[0]).tolist()
    [3]
    """
    machine = machine_for(machine)
    data, host = _rgb(rgb, machine)
    least = _min_intensity(min_intensity, data.dtype)
    if threshold is not None:
        threshold = check_real(threshold, "threshold", minimum=0)
    height, width = data.shape[:2]
    shape = (height, width)
    hue_field, valid, z = (machine.empty(shape, np.float32), machine.empty(shape, np.uint8),
                           machine.empty(shape, np.float32))
    # The four kernels below take one define set, though only hue_gradient reads it: one program on a
    # first run, not three.
    defines = {"IN_T": IMAGE_TYPES[data.dtype]}
    gradient = vector_kernel(machine, "color", "hue_gradient", **defines)
    launch_rows(machine, gradient, width, height, data, hue_field, valid, z, np.float32(least),
                np.int64(width), np.int64(height))
    if threshold is None:
        # Bands of rows, each histogrammed by one work-item: enough of them to keep every core busy.
        bands = min(height, 8 * machine.compute_units)
        rows = -(-height // bands)
        bands = -(-height // rows)
        counts = machine.empty((bands, HISTOGRAM_BINS), np.int32)
        machine.launch(vector_kernel(machine, "color", "hue_histogram", **defines), (bands,), z, counts, np.int64(rows),
                       np.int64(width), np.int64(height))
        estimated = machine.empty((1,), np.float32)
        machine.launch(vector_kernel(machine, "color", "hue_threshold", **defines), (_THRESHOLD_ITEMS,), counts,
                       estimated, np.int64(bands), np.float32(_noise.NOISE_HIGH / _MEDIAN_OF_RAYLEIGH),
                       np.float32(_noise.NOISE_HIGH * NOISE_FLOOR * full_scale(data.dtype)),
                       local_size=(_THRESHOLD_ITEMS,))
        fixed = 0.0
    else:
        estimated, fixed = z, float(threshold)
    edges = machine.empty(shape, np.uint8)
    n = height * width
    launch_flat(machine, vector_kernel(machine, "color", "hue_edges", **defines), n, z,
                estimated, edges, np.float32(fixed), np.int64(n), np.int32(threshold is not None))
    return AlbedoEdges(mask_result(edges, host), result(hue_field, host), mask_result(valid, host))
