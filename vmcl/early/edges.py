"""Edges: zero crossings of the Laplacian of a Gaussian, and Canny's detector with hysteresis.

Seed section "Edge detection". Zero crossings: "To detect zero-crossings, the computation at each pixel
need only examine the sign bits of neighboring pixels" (:func:`zero_crossings`, with the sign and slope
the Drumheller-Poggio stereo matcher uses). Canny on the Connection Machine (:func:`canny`): Gaussian
smoothing, directional derivatives, non-maximum suppression "interpolating the gradient magnitude" (or
comparing the neighbours directly), and thresholding with hysteresis, a spreading activation taking O(m)
steps for a chain of m weak pixels that "can be reduced to O(log m), using distance doubling": the weak
mask is labelled by :func:`vmcl.cm.doubling.label` and components touching a strong pixel are kept.
Thresholds left out come from the noise estimate of :mod:`vmcl.early.noise`.

Images are grey or RGB, uint8, uint16 or float, converted as :mod:`vmcl.early.filters` describes;
magnitudes and thresholds are in the input's units (a uint8 image's gradients on the 0-255 scale).

References
----------
D. Marr and E. Hildreth, "Theory of edge detection", Proc. R. Soc. Lond. B 207:187-217, 1980.
J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.
V. Torre and T. Poggio, "On edge detection", IEEE TPAMI 8(2):147-163, 1986.
M. Drumheller and T. Poggio, "On parallel stereo", Proc. IEEE Conf. Robotics and Automation, 1986.
"""

from __future__ import annotations

import math
from typing import Literal, NamedTuple, overload

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import doubling as _doubling
from vmcl.cm.core import (
    ArrayLike,
    check_bool,
    check_choice,
    check_sigma,
    field,
    image_field,
    launch_flat,
    launch_rows,
    machine_for,
    mask_result,
    result,
    vector_kernel,
)
from vmcl.early import noise as _noise
from vmcl.early.filters import DOG_RATIO, discrete_laplacian, separable_gaussian
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = [
    "DEFAULT_SIGMA",
    "PLAIN_SCALE",
    "CannyResult",
    "Hysteresis",
    "ZeroCrossings",
    "canny",
    "hysteresis_threshold",
    "zero_crossings",
]

Hysteresis = Literal["doubling", "iterative"]

DEFAULT_SIGMA = 2.0
"""Default smoothing width (pixels) of :func:`canny` and :func:`zero_crossings`: the machine's own
(vmcl.pipeline.EdgesConfig.sigma)."""
_CHECK_EVERY = 16  # spreading-activation steps between reads of the "changed" flag
PLAIN_SCALE = 2.0**100
"""Host float images whose largest |value| lies within [1 / PLAIN_SCALE, PLAIN_SCALE] go to Canny as
they are; others are first scaled by a power of two (exactly) to bring it near 1."""
_CANNY_BYTES = 40  # device bytes per pixel canny keeps at once: fields, states, labels, with room to spare


class CannyResult(NamedTuple):
    """What :func:`canny` returns with ``return_gradient=True``: the edges and the gradient they came from.

    Attributes
    ----------
    edges : ndarray or pyopencl.array.Array, (H, W)
        bool for NumPy input; uint8 0/1 device array for device input.
    magnitude : ndarray or pyopencl.array.Array, float32 (H, W)
        sqrt(gx**2 + gy**2) of the Sobel derivatives of the smoothed image, in the input's units.
    direction : ndarray or pyopencl.array.Array, float32 (H, W)
        atan2(gy, gx) in radians, x to the right and y downwards (rows), in [-pi, pi].
    """

    edges: ArrayLike
    magnitude: ArrayLike
    direction: ArrayLike


class ZeroCrossings(NamedTuple):
    """What :func:`zero_crossings` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    mask : bool (H, W); uint8 0/1 on the device
        Crossing pixels whose slope is at least ``min_slope``.
    sign : int8 (H, W)
        Brightness polarity across the crossing along x, the sign the Drumheller-Poggio matcher requires
        two matched crossings to share: +1 dark to bright going right, -1 bright to dark, 0 off the
        crossings and at crossings with no x component.
    slope : float32 (H, W)
        Gradient magnitude of the filtered image at crossings (central differences), 0 elsewhere.
    response : float32 (H, W)
        The filtered image, with the Laplacian of a Gaussian's sign for both methods.
    """

    mask: ArrayLike
    sign: ArrayLike
    slope: ArrayLike
    response: ArrayLike


def _xy(array: cl_array.Array) -> tuple[int, int]:
    height, width = array.shape
    return width, height


def zero_crossings(image: ArrayLike, *, sigma: float = DEFAULT_SIGMA, method: Literal["log", "dog"] = "log",
                   min_slope: float = 0.0, machine: Machine | None = None) -> ZeroCrossings:
    """Zero crossings of the Laplacian of a Gaussian (or its difference-of-Gaussians approximation).

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3); uint8, uint16 or float
    sigma : float
        Width of the Gaussian in pixels, > 0; default :data:`DEFAULT_SIGMA`.
    method : {"log", "dog"}
        "log": the exact Gaussian, then the 5-point Laplacian. "dog": G(sigma * sqrt(1.6)) minus
        G(sigma / sqrt(1.6)), Marr and Hildreth's approximation, computed in one fused pair of passes.
    min_slope : float
        Crossings whose slope (the response's gradient magnitude) is below this are dropped; >= 0.
    machine : vmcl.Machine, optional

    Returns
    -------
    ZeroCrossings
        (mask, sign, slope, response).

    Notes
    -----
    A crossing lies between 4-neighbours of strictly opposite signs; the one of the two nearer zero is
    marked (the positive one on a tie), so lines are one pixel thick and within half a pixel of the
    interpolated crossing. A pixel that is exactly 0 is marked when its neighbours on either side along
    x or along y have opposite signs; runs of exact zeros mark nothing. The Laplacian of a Gaussian is
    exactly 0 where the image is flat; the difference of Gaussians is not (its two smoothings round
    differently, leaving a residue at float32's rounding level), so on synthetic images with flat
    regions a ``min_slope`` of a small fraction of the contrast keeps that residue from crossing zero.

    References
    ----------
    D. Marr and E. Hildreth, "Theory of edge detection", Proc. R. Soc. Lond. B 207:187-217, 1980.
    M. Drumheller and T. Poggio, "On parallel stereo", Proc. IEEE Conf. Robotics and Automation, 1986.
    """
    machine = machine_for(machine)
    sigma = check_sigma(sigma)
    if method not in ("log", "dog"):
        raise InputValueError(f"method must be 'log' or 'dog', got {method!r}")
    min_slope = _non_negative(min_slope, "min_slope")
    data, host = image_field(image, machine, what="zero crossings", footprint=22, largest=8,
                             widths={"sigma": sigma})
    if method == "log":
        response = discrete_laplacian(machine, separable_gaussian(machine, data, (sigma,)))
    else:
        ratio = math.sqrt(DOG_RATIO)
        response = separable_gaussian(machine, data, (sigma * ratio, sigma / ratio))
    size = _xy(response)
    mask = machine.empty(response.shape, np.uint8)
    sign = machine.empty(response.shape, np.int8)
    slope = machine.empty(response.shape, np.float32)
    launch_rows(machine, vector_kernel(machine, "edges", "zero_crossings"), *size, response, mask, sign,
                slope, np.float32(min_slope), *map(np.int64, size))
    return ZeroCrossings(mask_result(mask, host), result(sign, host), result(slope, host), result(response, host))


def _non_negative(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputTypeError(f"{name} must be a number, got {type(value).__name__}")
    if not math.isfinite(value) or value < 0:
        raise InputValueError(f"{name} must be a finite number >= 0, got {value}")
    return float(value)


def _hysteresis(machine: Machine, state: cl_array.Array, marks: cl_array.Array | None,
                method: str) -> cl_array.Array:
    """Edges (uint8 0/1) from a state field (0 none, 1 weak, 3 strong): strong pixels and the weak ones
    8-connected to them through weak pixels. ``marks`` must be zeroed and of the field's size for
    "doubling"."""
    n = state.size
    edges = machine.empty(state.shape, np.uint8)
    if method == "doubling":
        labels = _doubling.label(state, connectivity=8, method="doubling", machine=machine)
        mark_strong = vector_kernel(machine, "edges", "mark_strong")
        launch_flat(machine, mark_strong, n, state, labels, marks, np.int64(n))
        launch_flat(machine, vector_kernel(machine, "edges", "keep_marked"), n, labels, marks, edges,
                    np.int64(n))
        return edges
    size = _xy(state)
    step = vector_kernel(machine, "edges", "grow_step")
    spare = machine.empty(state.shape, np.uint8)
    changed = machine.empty(1, np.int32)
    current = state
    while True:
        machine.fill(changed, 0)
        for _ in range(_CHECK_EVERY):
            launch_rows(machine, step, *size, current, spare, changed, *map(np.int64, size))
            current, spare = spare, current
        if not changed.get(queue=machine.queue)[0]:
            break
    launch_flat(machine, vector_kernel(machine, "edges", "strong_pixels"), n, current, edges, np.int64(n))
    return edges


def _check_hysteresis(method, name: str) -> None:
    check_choice(method, name, ("doubling", "iterative"))


def hysteresis_threshold(image: ArrayLike, *, low_threshold: float, high_threshold: float,
                         method: Hysteresis = "doubling", machine: Machine | None = None) -> ArrayLike:
    """Thresholding with hysteresis: pixels >= high, and pixels >= low 8-connected to them through
    pixels >= low.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, float32 (H, W)
        E.g. non-maximum-suppressed gradient magnitudes.
    low_threshold, high_threshold : float
        0 <= low <= high. Comparisons are ``>=`` (Canny's; scikit-image's ``apply_hysteresis_threshold``
        uses ``>``).
    method : {"doubling", "iterative"}
        "doubling": label the ``>= low`` mask (:func:`vmcl.cm.doubling.label`, the paper's O(log m)
        distance doubling in its union-find form), mark every component holding a pixel >= high at its
        principal, and read the marks back. "iterative": the paper's spreading activation, each step
        turning weak pixels next to edge pixels into edge pixels until none changes, O(m) steps for a
        chain of m weak pixels (the "changed" flag is read every 16 steps). Both give identical edges.
    machine : vmcl.Machine, optional

    Returns
    -------
    bool (H, W) for NumPy input; uint8 0/1 device array for device input.
    """
    machine = machine_for(machine)
    _check_hysteresis(method, "method")
    low, high = (_non_negative(v, name) for v, name in ((low_threshold, "low_threshold"),
                                                         (high_threshold, "high_threshold")))
    if low > high:
        raise InputValueError(f"low_threshold ({low}) must not exceed high_threshold ({high})")
    data, host = field(image, "image", machine, ndims=(2,), dtypes=(np.float32,))
    size = _xy(data)
    state, marks = machine.empty(data.shape, np.uint8), machine.empty(data.shape, np.uint8)
    launch_rows(machine, vector_kernel(machine, "edges", "double_threshold"), *size, data, state, marks,
                np.float32(low), np.float32(high), *map(np.int64, size))
    return mask_result(_hysteresis(machine, state, marks, method), host)


def _threshold_value(value, name: str, use_quantiles: bool) -> float | None:
    if value is None:
        return None
    value = _non_negative(value, name)
    if use_quantiles and value > 1:
        raise InputValueError(f"{name} must be a quantile in [0, 1] when use_quantiles=True, got {value}")
    return value


def _thresholds(machine: Machine, magnitude: cl_array.Array, low: float | None, high: float | None,
                use_quantiles: bool, noise: str) -> tuple[cl_array.Array, tuple[int, int], bool]:
    """Device (low, high) pairs for nms_classify, their tile grid, and whether they vary by tile."""
    ratio = _noise.CANNY_LOW / _noise.CANNY_HIGH
    if low is None and high is None:
        local = noise == "local"
        rule = _noise.noise_rule(_noise.CANNY_LOW, _noise.CANNY_HIGH)
        pairs, tiles = _noise.threshold_field(machine, magnitude, rule, local=local)
        return pairs, tiles, local
    given_low = low if low is not None else high
    given_high = high if high is not None else low
    # At least one threshold was given (both None returned above), so each stands in for a missing one.
    assert given_low is not None and given_high is not None
    if use_quantiles:
        rule = (given_low, given_high, 1.0 if low is not None else ratio,
                1.0 if high is not None else 1.0 / ratio)
        pairs, tiles = _noise.threshold_field(machine, magnitude, rule, local=False)
        return pairs, tiles, False
    low = given_high * ratio if low is None else low
    high = low / ratio if high is None else high
    pairs = machine.empty((1, 1, 2), np.float32)
    machine.launch(vector_kernel(machine, "edges", "set_thresholds"), (1,), pairs, np.float32(low),
                   np.float32(high))
    return pairs, (1, 1), False


def _scale_exponent(image) -> int:
    """e such that ``image * 2**-e`` has its largest |value| in [1, 2), for a host float image outside
    :data:`PLAIN_SCALE`'s range; 0 for all others (device arrays, integers, ordinary images, and
    images with NaN or infinity, which :func:`vmcl.cm.core.image_field` refuses)."""
    if not isinstance(image, np.ndarray) or image.dtype.kind != "f" or image.size == 0:
        return 0
    with np.errstate(invalid="ignore"):
        largest = float(np.max(np.abs(image)))
    if not math.isfinite(largest) or largest == 0 or 1 / PLAIN_SCALE <= largest <= PLAIN_SCALE:
        return 0
    return math.frexp(largest)[1] - 1


@overload
def canny(image: np.ndarray, *, sigma: float = DEFAULT_SIGMA, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False, interpolate: bool = True,
          method: Hysteresis = "doubling", noise: _noise.Noise = "global",
          return_gradient: Literal[False] = False, machine: Machine | None = None) -> np.ndarray: ...
@overload
def canny(image: cl_array.Array, *, sigma: float = DEFAULT_SIGMA, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False, interpolate: bool = True,
          method: Hysteresis = "doubling", noise: _noise.Noise = "global",
          return_gradient: Literal[False] = False, machine: Machine | None = None) -> cl_array.Array: ...
@overload
def canny(image: ArrayLike, *, sigma: float = DEFAULT_SIGMA, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False, interpolate: bool = True,
          method: Hysteresis = "doubling", noise: _noise.Noise = "global",
          return_gradient: Literal[True], machine: Machine | None = None) -> CannyResult: ...
@overload
def canny(image: ArrayLike, *, sigma: float = DEFAULT_SIGMA, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False, interpolate: bool = True,
          method: Hysteresis = "doubling", noise: _noise.Noise = "global",
          return_gradient: bool = False, machine: Machine | None = None) -> ArrayLike | CannyResult: ...
def canny(image: ArrayLike, *, sigma: float = DEFAULT_SIGMA, low_threshold: float | None = None,
          high_threshold: float | None = None, use_quantiles: bool = False, interpolate: bool = True,
          method: Hysteresis = "doubling", noise: _noise.Noise = "global", return_gradient: bool = False,
          machine: Machine | None = None) -> ArrayLike | CannyResult:
    """Canny's edge detector, as the Vision Machine ran it on the Connection Machine.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        uint8, uint16 or float (float64 is converted to float32; device arrays must be uint8, uint16 or
        float32); RGB is converted to grey with :data:`vmcl.early.filters.GREY_WEIGHTS`.
    sigma : float
        Standard deviation of the Gaussian smoothing in pixels, > 0 (the exact separable Gaussian); default
        :data:`DEFAULT_SIGMA`.
    low_threshold, high_threshold : float, optional
        Hysteresis thresholds on the gradient magnitude, in the input's units (see Notes), with
        low <= high. Both None: from the noise estimate (:mod:`vmcl.early.noise`): with s the noise
        scale, median(|grad|) / sqrt(2 ln 2), low = 3 s and high = 6 s. One None: it keeps that
        rule's ratio (low = high / 2) to the one given.
    use_quantiles : bool
        Thresholds given are quantiles in [0, 1] of the gradient magnitudes of the whole image (from a
        4096-bin histogram, within max / 4096 of ``np.percentile``).
    interpolate : bool
        Non-maximum suppression against the gradient magnitude interpolated between the two neighbours
        on each side along the gradient (scikit-image's bilinear rule, ties kept); False compares the
        two neighbours of the nearest of the 4 axes and diagonals.
    method : {"doubling", "iterative"}
        The hysteresis: "doubling" (default): label the weak-or-strong mask with
        :func:`vmcl.cm.doubling.label` and keep the components holding a strong pixel. "iterative": the
        paper's O(m) spreading activation.
        Identical edges; see :func:`hysteresis_threshold`.
    noise : {"global", "local"}
        Used when both thresholds are None: one histogram for the whole image, or one per 64 x 64 tile
        with the thresholds interpolated bilinearly between tile centres.
    return_gradient : bool
        Also return the gradient magnitude and direction (for the stereo matcher), as a
        :class:`CannyResult`.
    machine : vmcl.Machine, optional

    Returns
    -------
    edges : bool (H, W) for NumPy input; uint8 0/1 device array for device input
        Without ``return_gradient``, the edges alone.
    CannyResult
        With ``return_gradient``, the named tuple ``(edges, magnitude, direction)``.

    Notes
    -----
    The gradient is the Sobel operator's ([-1 0 1] along the derivative, [1 2 1] across) on the
    smoothed image, so magnitudes are 8 times the brightness slope per pixel: a step of contrast c
    smoothed with sigma peaks near 8 c / (sqrt(2 pi) sigma). These are scikit-image's units: given the
    same sigma and the same thresholds (in the input's own units, for integer images too), the edges agree
    with ``skimage.feature.canny(..., mode="nearest")``. Borders repeat the edge pixel; the outermost
    ring of pixels is never an edge. Weak pixels are maxima >= low and > 0, strong ones maxima >= high.

    The noise-estimated thresholds scale with the image, so ``canny(k * image)`` finds the edges of
    ``image`` for any k that float32 holds, up to the rounding of ``k * image`` itself: the gradient
    magnitude is computed without overflow or underflow, and a host float image whose largest |value|
    lies outside [2**-100, 2**100] (subnormal, or near float32's largest) is filtered scaled by a power
    of two (exact), with given thresholds scaled alike. Magnitudes returned with ``return_gradient``
    are in the input's units; where those overflow float32 the call is refused. Device images are
    taken as they are (checking them would make the host wait): NaN or infinity there, or values
    beyond 2**124, give meaningless edges.

    When thresholds come from histograms, their range (the magnitude's maximum) stays on the device: the
    host does not wait for the device anywhere in a call with device input.

    References
    ----------
    J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.
    V. Torre and T. Poggio, "On edge detection", IEEE TPAMI 8(2):147-163, 1986.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.edges import canny
    >>> square = np.zeros((32, 32), np.float32); square[8:24, 8:24] = 1
    >>> edges = canny(square, sigma=1.0, low_threshold=0.5, high_threshold=1.0)
    >>> bool(edges[16, 7] or edges[16, 8]), bool(edges[16, 16])
    (True, False)
    """
    machine = machine_for(machine)
    sigma = check_sigma(sigma)
    _check_hysteresis(method, "method")
    check_choice(noise, "noise", ("global", "local"))
    return_gradient = check_bool(return_gradient, "return_gradient")
    use_quantiles = check_bool(use_quantiles, "use_quantiles")
    interpolate = check_bool(interpolate, "interpolate")
    low = _threshold_value(low_threshold, "low_threshold", use_quantiles)
    high = _threshold_value(high_threshold, "high_threshold", use_quantiles)
    if low is not None and high is not None and low > high:
        raise InputValueError(f"low_threshold ({low}) must not exceed high_threshold ({high})")
    exponent = _scale_exponent(image)
    if exponent:
        assert isinstance(image, np.ndarray)  # _scale_exponent scales host float images only
        image = np.ldexp(image, -exponent)
        if not use_quantiles:
            low, high = (None if t is None else math.ldexp(t, -exponent) for t in (low, high))
    data, host = image_field(image, machine, what="canny", footprint=_CANNY_BYTES, widths={"sigma": sigma})
    smoothed = separable_gaussian(machine, data, (sigma,))
    size = _xy(smoothed)
    dims = tuple(map(np.int64, size))
    magnitude = machine.empty(smoothed.shape, np.float32)
    direction = machine.empty(smoothed.shape, np.float32) if return_gradient else magnitude
    launch_rows(machine, vector_kernel(machine, "edges", "gradient"), *size, smoothed, magnitude, direction, *dims,
                np.int32(return_gradient))
    pairs, tiles, local = _thresholds(machine, magnitude, low, high, use_quantiles, noise)
    state = machine.empty(smoothed.shape, np.uint8)
    doubling = method == "doubling"
    # Spreading activation needs no marks; without clear_marks the kernel never touches its marks argument.
    marks = machine.empty(smoothed.shape, np.uint8) if doubling else state
    launch_rows(machine, vector_kernel(machine, "edges", "nms_classify"), *size, smoothed, magnitude, pairs, state,
                marks, np.int64(_noise.TILE), np.int64(tiles[1]), np.int64(tiles[0]), *dims,
                np.int32(bool(interpolate)), np.int32(local), np.int32(doubling))
    edges = mask_result(_hysteresis(machine, state, marks if doubling else None, method), host)
    if not return_gradient:
        return edges
    magnitude_out = result(magnitude, host)
    if exponent:
        assert isinstance(magnitude_out, np.ndarray)  # scaled images are host images (above)
        with np.errstate(over="ignore"):
            magnitude_out = np.ldexp(magnitude_out, exponent)
        if not np.isfinite(magnitude_out).all():
            raise InputValueError(f"image values of about {2.0 ** exponent:.3g} give gradient magnitudes beyond "
                                  "float32's range: scale the image down to return them (return_gradient)")
    return CannyResult(edges, magnitude_out, result(direction, host))
