"""Smoothing and second-derivative filters: the Gaussian (binomial or exact), its Laplacian, and the
difference of Gaussians.

Seed section "Edge detection" (Zero-crossings): differentiation is ill-posed, so the image is first
filtered "through an appropriate low-pass filter", a Gaussian, either by the binomial approximation
("only integer addition, shifting, and local communication on the 2D mesh", :func:`vmcl.cm.filters.binomial`)
or exactly; the Laplacian of a Gaussian is "a Gaussian followed by convolution with a discrete
Laplacian", and "is often approximated by the difference of Gaussians".

Every function takes a grey (H, W) or RGB (H, W, 3) image of uint8, uint16 or float values, NumPy or
device array, and computes in float32 on the grey image: RGB becomes ``0.2125 R + 0.7154 G + 0.0721 B``
(the ITU-R BT.709 luma weights, as ``skimage.color.rgb2gray``), and values keep the input's units (a
uint8 image stays on the 0-255 scale). NumPy in gives NumPy out, a device array in gives a device array
out. Borders repeat the edge pixel.

References
----------
D. Marr and E. Hildreth, "Theory of edge detection", Proc. R. Soc. Lond. B 207:187-217, 1980.
V. Torre and T. Poggio, "On edge detection", IEEE TPAMI 8(2):147-163, 1986.
"""

from __future__ import annotations

from typing import Literal, overload

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
from pyopencl import cltypes

from vmcl.cm import filters as _cm_filters
from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_sigma,
    image_field,
    launch_rows,
    machine_for,
    result,
    vector_kernel,
)
from vmcl.errors import InputValueError
from vmcl.machine import Machine, device_memory

__all__ = [
    "DEFAULT_SIGMA",
    "DOG_RATIO",
    "GREY_WEIGHTS",
    "LOG_SIGMA",
    "MAX_TAPS_SIGMA",
    "TRUNCATE",
    "Method",
    "binomial_passes",
    "channel_planes",
    "device_taps",
    "difference_of_gaussians",
    "discrete_laplacian",
    "gaussian",
    "gaussian_taps",
    "grey_field",
    "laplacian_of_gaussian",
    "separable_gaussian",
]

GREY_WEIGHTS = (0.2125, 0.7154, 0.0721)
"""Weights of R, G and B in the grey image (ITU-R BT.709 luma, scikit-image's ``rgb2gray``)."""

TRUNCATE = 4.0
"""The exact Gaussian's taps reach ``int(TRUNCATE * sigma + 0.5)`` pixels, as scipy's gaussian_filter."""

DOG_RATIO = 1.6
"""Marr and Hildreth's ratio of the two widths of a difference of Gaussians that best fits a LoG."""

DEFAULT_SIGMA = 1.0
"""Default width (pixels) of :func:`gaussian` and of :func:`difference_of_gaussians`' narrower Gaussian,
scikit-image's for its Gaussian filter."""

LOG_SIGMA = 2.0
"""Default width (pixels) of :func:`laplacian_of_gaussian`: the machine's for the Laplacian features it
matches (vmcl.early.motion's "log")."""

Method = Literal["binomial", "exact"]


def _grey_weights() -> np.ndarray:
    # pyopencl.cltypes makes its make_<type> functions at import; its type hints declare only the dtypes.
    return cltypes.make_float4(*GREY_WEIGHTS, 0.0)  # type: ignore[attr-defined]


MAX_TAPS_SIGMA = 2.0**18
"""The widest Gaussian :func:`gaussian_taps` tabulates (2 M taps); images bound their own widths lower."""


def gaussian_taps(sigma: float) -> np.ndarray:
    """The exact Gaussian's 1-D taps, normalised to sum 1 over ``int(4 sigma + 0.5)`` pixels each side."""
    sigma = check_sigma(sigma)
    if sigma > MAX_TAPS_SIGMA:
        raise InputValueError(f"sigma must be at most {MAX_TAPS_SIGMA} for a tap table, got {sigma}")
    radius = int(TRUNCATE * sigma + 0.5)
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    taps = np.exp(-0.5 * (x / sigma) ** 2)
    return (taps / taps.sum()).astype(np.float32)


def binomial_passes(sigma: float) -> int:
    """Passes of the 3 x 3 binomial mask for a Gaussian of ``sigma``: n passes have variance n / 2."""
    sigma = check_sigma(sigma)
    return max(1, round(2.0 * sigma * sigma))


def device_taps(machine: Machine, sigmas: tuple[float, ...]) -> tuple[cl_array.Array, int]:
    """The packed taps of one or two widths on the device (:meth:`vmcl.Machine.constant`: uploaded once
    per machine and widths), and their common radius."""
    radius = max(int(TRUNCATE * s + 0.5) for s in sigmas)

    def packed() -> np.ndarray:
        taps = np.zeros((len(sigmas), 2 * radius + 1), np.float32)
        for plane, s in enumerate(sigmas):
            t = gaussian_taps(s)
            pad = radius - len(t) // 2
            taps[plane, pad:pad + len(t)] = t
        return taps

    return machine.constant(("vmcl.early.filters", "taps", sigmas), packed), radius


def separable_gaussian(machine: Machine, data: cl_array.Array, sigmas: tuple[float, ...]) -> cl_array.Array:
    """The exact separable Gaussian of the grey image of a device image checked by
    :func:`vmcl.cm.core.image_field`.

    With one width in ``sigmas``, the smoothed float32 (H, W) image; with two, the first smoothing minus
    the second, in one fused pair of passes. The edge detectors smooth with it on the device.
    """
    height, width = data.shape[:2]
    planes = len(sigmas)
    taps_device, radius = device_taps(machine, sigmas)
    if data.ndim == 3:
        data = grey_field(machine, data)
    rows = machine.empty((planes, height, width), np.float32)
    out = machine.empty((height, width), np.float32)
    dims = (np.int64(width), np.int64(height))
    # Both passes from one build (the column pass reads no IN_T): one program on a first run, not two.
    defines = {"PLANES": planes, "IN_T": IMAGE_TYPES[data.dtype]}
    along_rows = vector_kernel(machine, "early_filters", "gauss_rows", **defines)
    launch_rows(machine, along_rows, width, height, data, rows, taps_device, np.int32(radius), *dims)
    along_columns = vector_kernel(machine, "early_filters", "gauss_cols", **defines)
    launch_rows(machine, along_columns, width, height, rows, out, taps_device, np.int32(radius), *dims)
    return out


def grey_field(machine: Machine, data: cl_array.Array) -> cl_array.Array:
    """The float32 (H, W) grey image of a device image (uint8, uint16 or float32; grey or RGB, weighed by
    :data:`GREY_WEIGHTS`), in grey levels of its own type; a float32 grey image is returned as it is."""
    if data.dtype == np.float32 and data.ndim == 2:
        return data
    height, width = data.shape[:2]
    out = machine.empty((height, width), np.float32)
    to_grey = vector_kernel(machine, "early_filters", "to_grey", IN_T=IMAGE_TYPES[data.dtype],
                            CHANNELS=3 if data.ndim == 3 else 1)
    launch_rows(machine, to_grey, width, height, data, out, _grey_weights(), *map(np.int64, (width, height)))
    return out


def channel_planes(machine: Machine, data: cl_array.Array) -> cl_array.Array:
    """The float32 (C, H, W) planes of a device image's channels (C = 3 for RGB, 1 for grey), in levels of its
    own type, as :func:`grey_field` gives the grey image: each plane is to_grey's sum with one channel
    weighing 1, so no program is built beyond the grey conversion's."""
    if data.ndim == 2:
        return grey_field(machine, data).reshape((1, *data.shape))
    height, width = data.shape[:2]
    planes = machine.empty((3, height, width), np.float32)
    plane = machine.empty((height, width), np.float32)
    to_grey = vector_kernel(machine, "early_filters", "to_grey", IN_T=IMAGE_TYPES[data.dtype], CHANNELS=3)
    for channel in range(3):
        weights = [0.0] * 4
        weights[channel] = 1.0
        launch_rows(machine, to_grey, width, height, data, plane,
                    cltypes.make_float4(*weights),  # type: ignore[attr-defined]
                    *map(np.int64, (width, height)))
        # pyopencl's overloads type a device copy's ends as Buffer, but enqueue_copy dispatches on
        # memory objects.
        cl.enqueue_copy(machine.queue, device_memory(planes), device_memory(plane),  # type: ignore[call-overload]
                        byte_count=plane.nbytes, dst_offset=channel * plane.nbytes)
    return planes


def _smooth(machine: Machine, data: cl_array.Array, sigma: float, method: str) -> cl_array.Array:
    if method == "exact":
        return separable_gaussian(machine, data, (sigma,))
    if method == "binomial":
        return _cm_filters.binomial(grey_field(machine, data), binomial_passes(sigma), machine=machine)
    raise InputValueError(f"method must be 'binomial' or 'exact', got {method!r}")


def discrete_laplacian(machine: Machine, smoothed: cl_array.Array) -> cl_array.Array:
    """The 5-point discrete Laplacian of a float32 (H, W) device field, borders repeating the edge pixel."""
    height, width = smoothed.shape
    out = machine.empty((height, width), np.float32)
    # laplacian reads no define: taken with a float field's single smoothing's, it shares that build.
    laplacian = vector_kernel(machine, "early_filters", "laplacian", PLANES=1, IN_T="float")
    launch_rows(machine, laplacian, width, height, smoothed, out,
                np.int64(width), np.int64(height))
    return out


@overload
def gaussian(image: np.ndarray, *, sigma: float = DEFAULT_SIGMA, method: Method = "binomial",
             machine: Machine | None = None) -> np.ndarray: ...
@overload
def gaussian(image: cl_array.Array, *, sigma: float = DEFAULT_SIGMA, method: Method = "binomial",
             machine: Machine | None = None) -> cl_array.Array: ...
def gaussian(image: ArrayLike, *, sigma: float = DEFAULT_SIGMA, method: Method = "binomial",
             machine: Machine | None = None) -> ArrayLike:
    """Smooth the grey image with a Gaussian of standard deviation ``sigma`` pixels.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        uint8, uint16 or float (float64 is converted to float32; device arrays must be uint8, uint16 or
        float32). RGB is converted to grey with :data:`GREY_WEIGHTS`.
    sigma : float
        Standard deviation in pixels, > 0 and at most the image's larger side (or
        :data:`vmcl.cm.core.WIDEST` for smaller images); default :data:`DEFAULT_SIGMA`.
    method : {"binomial", "exact"}
        "binomial" (the paper's): n = max(1, round(2 sigma**2)) passes of the 3 x 3 mask
        [1 2 1]^T [1 2 1] / 16 (:func:`vmcl.cm.filters.binomial`), a Gaussian of standard deviation
        sqrt(n / 2), so sigma is rounded to the nearest such value (1.4 gives sqrt(2)). "exact": separable
        convolution with sampled Gaussian taps normalised to sum 1, reaching ``int(4 sigma + 0.5)``
        pixels each side (scipy's ``gaussian_filter`` with ``mode="nearest"``).
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W): NumPy for NumPy input, a device array for device input.

    Notes
    -----
    Borders repeat the edge pixel. The binomial passes run in float32; on 8-bit input their sums are
    the integer add-and-shift arithmetic exactly for up to 4 passes (8 + 4n bits fit float32's 24).

    References
    ----------
    V. Torre and T. Poggio, "On edge detection", IEEE TPAMI 8(2):147-163, 1986.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.filters import gaussian
    >>> step = np.zeros((8, 8), np.uint8); step[:, 4:] = 255
    >>> smooth = gaussian(step, sigma=1.0, method="exact")
    >>> bool(0 < smooth[0, 3] < smooth[0, 4] < 255)
    True
    """
    machine = machine_for(machine)
    sigma = check_sigma(sigma)
    if method not in ("binomial", "exact"):
        raise InputValueError(f"method must be 'binomial' or 'exact', got {method!r}")
    data, host = image_field(image, machine, what="a Gaussian", footprint=12, widths={"sigma": sigma})
    return result(_smooth(machine, data, sigma, method), host)


@overload
def laplacian_of_gaussian(image: np.ndarray, *, sigma: float = LOG_SIGMA,
                          machine: Machine | None = None) -> np.ndarray: ...
@overload
def laplacian_of_gaussian(image: cl_array.Array, *, sigma: float = LOG_SIGMA,
                          machine: Machine | None = None) -> cl_array.Array: ...
def laplacian_of_gaussian(image: ArrayLike, *, sigma: float = LOG_SIGMA, machine: Machine | None = None) -> ArrayLike:
    """The exact Gaussian of ``sigma`` followed by the 5-point discrete Laplacian.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3); uint8, uint16 or float
    sigma : float
        Standard deviation of the Gaussian in pixels, > 0 and at most the image's larger side (or
        :data:`vmcl.cm.core.WIDEST` for smaller images); default :data:`LOG_SIGMA`.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W): sum of the four differences ``smooth[neighbour] - smooth[centre]``; positive on
    the dark side of a step, negative on the bright side.

    References
    ----------
    D. Marr and E. Hildreth, "Theory of edge detection", Proc. R. Soc. Lond. B 207:187-217, 1980.
    """
    machine = machine_for(machine)
    sigma = check_sigma(sigma)
    data, host = image_field(image, machine, what="a Laplacian of a Gaussian", footprint=16,
                             widths={"sigma": sigma})
    return result(discrete_laplacian(machine, separable_gaussian(machine, data, (sigma,))), host)


@overload
def difference_of_gaussians(image: np.ndarray, *, low_sigma: float = DEFAULT_SIGMA, high_sigma: float | None = None,
                            machine: Machine | None = None) -> np.ndarray: ...
@overload
def difference_of_gaussians(image: cl_array.Array, *, low_sigma: float = DEFAULT_SIGMA, high_sigma: float | None = None,
                            machine: Machine | None = None) -> cl_array.Array: ...
def difference_of_gaussians(image: ArrayLike, *, low_sigma: float = DEFAULT_SIGMA, high_sigma: float | None = None,
                            machine: Machine | None = None) -> ArrayLike:
    """The narrower Gaussian minus the wider one (scikit-image's convention), in one fused pair of passes.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3); uint8, uint16 or float
    low_sigma : float
        Standard deviation of the narrower Gaussian, > 0; default :data:`DEFAULT_SIGMA`.
    high_sigma : float, optional
        Of the wider one, > low_sigma. Default: 1.6 * low_sigma (Marr and Hildreth's best fit to the
        Laplacian of a Gaussian of width about sqrt(low_sigma * high_sigma)). Both at most the image's
        larger side (or :data:`vmcl.cm.core.WIDEST` for smaller images).
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W). Its sign is the opposite of the Laplacian of a Gaussian's (negative on the dark
    side of a step).

    References
    ----------
    D. Marr and E. Hildreth, "Theory of edge detection", Proc. R. Soc. Lond. B 207:187-217, 1980.
    """
    machine = machine_for(machine)
    low_sigma = check_sigma(low_sigma, "low_sigma")
    high_sigma = DOG_RATIO * low_sigma if high_sigma is None else check_sigma(high_sigma, "high_sigma")
    if high_sigma <= low_sigma:
        raise InputValueError(f"high_sigma must exceed low_sigma, got {high_sigma} <= {low_sigma}")
    data, host = image_field(image, machine, what="a difference of Gaussians", footprint=16, largest=8,
                             widths={"low_sigma": low_sigma, "high_sigma": high_sigma})
    return result(separable_gaussian(machine, data, (low_sigma, high_sigma)), host)
