"""A field's weighted median over windows whose support stops at brightness edges.

Seed sections "Stereo" and "Organization of integration": depth discontinuities coincide with brightness
edges. A matcher's window straddles a depth edge and carries the nearer surface's disparity a few pixels
over the farther one's (the foreground "fattens"); a pixel near a jump can be given back its own
surface's value by letting only the neighbours of its own colour vote. Each chosen pixel takes the weighted
median of the voters' values in its window, a voter q weighing

    exp(-|I(q) - I(p)| / sigma_colour - |q - p| / sigma_space),

so that neighbours across a brightness edge hardly count (the joint weighted median of Ma, Li, Ma, Zhang,
"Constant time weighted median filtering for stereo matching and beyond", ICCV 2013, and of the occlusion
filling of Hosni, Rhemann, Bleyer, Rother, Gelautz, "Fast cost-volume filtering for visual correspondence
and beyond", PAMI 35(2), 2013). The median is taken over bins of ``step`` units; the pixel takes the
weighted mean of the voters in the median's bin, so that a value keeps its fraction of a bin.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_int,
    check_real,
    check_same_kind,
    check_unit_image,
    field,
    flags_field,
    image_field,
    launch_rows,
    machine_for,
    result,
    vector_kernel,
)
from vmcl.early.filters import channel_planes
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["MAX_BINS", "MAX_KEPT_VOTERS", "check_sigma_colour", "weighted_median"]

MAX_BINS = 1024
"""The most bins a pixel's histogram holds; a wider span of values gets bins of several units."""
MAX_KEPT_VOTERS = 81
"""Windows of at most this many voters (a reach of 4 steps of ``stride`` each way) are computed with every
voter kept and the median's bin found by bisection, several pixels per work-item (the pipeline's stereo
and flow refinements); wider ones with a histogram per pixel. Both take the same rule; they can differ only
where a bin's cumulative weight lies within rounding of half the total."""

_BIN_STEP = 64  # the private histograms are sized in steps of this many bins (one program per size)
_HALF_RANGE = float(np.finfo(np.float32).max) / 4
_LEVELS = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0, np.dtype(np.float32): 1.0}


def check_sigma_colour(sigma_colour: Any, name: str = "sigma_colour") -> float:
    """``sigma_colour`` as :func:`weighted_median` takes it, a float > 0 whose inverse fits float32 (the
    kernels multiply by it); the errors name ``name`` (a caller's own name for the weighted median's scale)."""
    sigma_colour = check_real(sigma_colour, name, above=0)
    if 1 / sigma_colour > float(np.finfo(np.float32).max):  # compared in float64: no overflowing cast
        raise InputValueError(f"{name} must be at least {1 / float(np.finfo(np.float32).max):.1e} (its "
                              f"inverse must fit float32), got {sigma_colour}")
    return sigma_colour


def weighted_median(values: ArrayLike, image: ArrayLike, *, low: float, high: float, where: ArrayLike | None = None,
                    voters: ArrayLike | None = None, radius: int = 9, sigma_colour: float = 0.1,
                    sigma_space: float = 9.0, stride: int = 1, bin_width: float = 1.0,
                    machine: Machine | None = None) -> ArrayLike:
    """Replace each chosen pixel's value by the weighted median of its voters' values around it.

    Parameters
    ----------
    values : float32 (H, W) or (H, W, 2) array or device array
        The field (e.g. a disparity map, or a flow's two components), NaN where it has no value; its values
        times the voters a pixel must stay within float32's range (the kernels sum them in float32; a host
        field is checked); each
        component takes its own median, with the same weights (found once for both).
    image : (H, W) or (H, W, 3) array or device array; uint8, uint16 or float
        The brightness the weights follow, grey or RGB, its levels scaled to [0, 1] by its type's range
        (uint8 by 255, uint16 by 65535; a float image must be in [0, 1] already: a NumPy one outside it is
        refused, a device one is not read back to be checked).
    low, high : float
        The span of the voters' values (e.g. a disparity range), low <= high, each within a quarter of
        float32's range; values outside it count in the first or last bin.
    where : bool or uint8 (H, W), optional
        The pixels to replace (default every pixel); the others keep their value.
    voters : bool or uint8 (H, W), optional
        The pixels whose values vote (default every pixel with a value); NaN values never vote.
    radius : int
        >= 1: the window is (2 radius + 1) pixels square (clipped by the image's borders).
    sigma_colour : float
        > 0: the colour distance (Euclidean, in the [0, 1] scale) at which a voter's weight falls by e.
    sigma_space : float
        > 0: the distance in pixels at which a voter's weight falls by e.
    stride : int
        >= 1: only the window's rows and columns at multiples of ``stride`` from the pixel's own vote
        (1, the default: every pixel of the window; 2 visits a quarter of them, over the same reach).
    bin_width : float
        > 0: the width of the median's bins in the values' units (1, the default, for whole disparities;
        a fraction for a flow's sub-pixel values), widened where the span would need more than MAX_BINS.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 of the values' shape, as the input came (NumPy for NumPy ``values``, else a device array): the
    field with the chosen pixels replaced; a chosen pixel without any voter in its window keeps its own value.

    Notes
    -----
    The median is taken over bins ``step = bin_width * max(1, ceil(((high - low) / bin_width + 1) / MAX_BINS))``
    units wide, starting half a bin below ``low`` (multiples of ``bin_width`` from ``low`` sit mid-bin when
    ``step`` is ``bin_width``); the result is the weighted mean of the voters in the median's bin. Each
    chosen pixel visits up to ``(2 (radius // stride) + 1)^2`` neighbours (fewer at the image's border).
    Where that is at most :data:`MAX_KEPT_VOTERS`, the voters are kept and the median's bin found by
    bisection over them, for several adjacent pixels at once on a CPU's vector lanes; the weights'
    exponential may then differ from the one-pixel form's in its last bit.

    Raises
    ------
    InputTypeError, InputValueError
        Naming the argument: a field that is not float32 (H, W) or (H, W, 2), an image or mask of another shape,
        ``low > high``, a parameter outside its range.
    """
    machine = machine_for(machine)
    largest = None  # a host field's largest magnitude, checked once the window's voters are known
    if isinstance(values, np.ndarray) and values.dtype.kind == "f":
        finite = np.isfinite(values)
        largest = float(np.abs(values[finite]).max()) if finite.any() else 0.0
        with np.errstate(over="ignore"):
            values = values.astype(np.float32, copy=False)
    data, host = field(values, "values", machine, ndims=(2, 3), dtypes=(np.float32,))
    height, width = data.shape[:2]
    components = data.shape[2] if data.ndim == 3 else 1
    if components > 2:
        raise InputValueError(f"values must have one or two components ((H, W) or (H, W, 2)), got shape {data.shape}")
    # 6 bytes a pixel for the flags and the field's copy, 12 for the image's float planes (RGB).
    picture, image_host = image_field(image, machine, what="a weighted median", footprint=18)
    check_same_kind("values", host, "image", image_host)
    if isinstance(image, np.ndarray) and picture.dtype == np.float32:
        check_unit_image(image, "image")
    if picture.shape[:2] != (height, width):
        raise InputValueError(f"image must have values' height and width {(height, width)}, got shape {picture.shape}")
    # A quarter of float32's range each way, so that the span and the bins' edges stay finite in float32.
    low = check_real(low, "low", minimum=-_HALF_RANGE, maximum=_HALF_RANGE)
    high = check_real(high, "high", minimum=-_HALF_RANGE, maximum=_HALF_RANGE)
    if low > high:
        raise InputValueError(f"low must not exceed high, got low {low} and high {high}")
    radius = check_int(radius, "radius", minimum=1, maximum=2**31 - 1)
    sigma_colour = check_sigma_colour(sigma_colour)
    sigma_space = check_real(sigma_space, "sigma_space", above=0)
    stride = check_int(stride, "stride", minimum=1, maximum=2**31 - 1)
    bin_width = check_real(bin_width, "bin_width", above=0, maximum=_HALF_RANGE)
    span = (high - low) / bin_width + 1  # in bins of bin_width
    if not math.isfinite(span):
        raise InputValueError(f"bin_width {bin_width} is too narrow for the span from low {low} to high {high}")
    widening = max(1, math.ceil(span / MAX_BINS))
    step = bin_width * widening
    bins = min(MAX_BINS, math.ceil(span / widening) + 1)
    if not np.float32(step) >= np.finfo(np.float32).tiny:  # the kernel divides by the bins' width in float32
        raise InputValueError(f"bin_width must be at least {float(np.finfo(np.float32).tiny):.1e} (a float32), "
                              f"got {bin_width}")
    chosen = flags_field(np.ones((height, width), np.uint8) if where is None else where, (height, width), "where",
                         machine)
    voting = flags_field(np.ones((height, width), np.uint8) if voters is None else voters, (height, width), "voters",
                         machine)
    reach = min(radius, max(height, width) - 1)  # no window reaches further than the image
    side = 2 * reach + 1
    stride = min(stride, side)
    spatial = _spatial_weights(machine, reach, sigma_space)
    out = machine.empty(data.shape, np.float32)
    channels = 3 if picture.ndim == 3 else 1
    common = (np.int64(width), np.int64(height), np.int32(reach), np.float32(1 / sigma_colour), spatial,
              np.float32(1 / _LEVELS[picture.dtype]), np.float32(low - 0.5 * step), np.float32(step), np.int32(bins),
              np.int32(stride))
    steps = reach // stride
    # The kernels sum each voter's weight (at most 1) times its value in float32: a field whose values times
    # the voters overflow it came out as an infinity (a float64 one beyond float32 too).
    limit = float(np.finfo(np.float32).max) / (2 * steps + 1) ** 2 / 2
    if largest is not None and largest > limit:
        raise InputValueError(f"values reach {largest:.3g}: with {(2 * steps + 1) ** 2} voters a pixel (radius "
                              f"{radius}, stride {stride}) they must stay within {limit:.3g}, as their weighted sums "
                              "are float32")
    if (2 * steps + 1) ** 2 <= MAX_KEPT_VOTERS:
        kernel = vector_kernel(machine, "weighted_median", "weighted_median_bisect", CHANNELS=channels,
                               COMPS=components, MAX_VOTERS=MAX_KEPT_VOTERS)
        launch_rows(machine, kernel, width, height, data, voting, chosen, channel_planes(machine, picture), out,
                    *common, np.int32(steps), np.int32(max(1, math.ceil(math.log2(bins)))))
    else:
        kernel = machine.kernel("weighted_median", "weighted_median", IN_T=IMAGE_TYPES[picture.dtype],
                                CHANNELS=channels, COMPS=components, NBINS=_BIN_STEP * math.ceil(bins / _BIN_STEP))
        machine.launch(kernel, (width, height), data, voting, chosen, picture, out, *common)
    return result(out, host)


def _spatial_weights(machine: Machine, reach: int, sigma_space: float) -> cl_array.Array:
    """The (2 reach + 1)^2 table of exp(-|q - p| / sigma_space) on the device, uploaded once per machine
    and window (:meth:`vmcl.Machine.constant`): the matcher's fields stay on the device, and an upload on
    every call would wait for its queue to drain."""
    def table() -> np.ndarray:
        side = 2 * reach + 1
        machine.require_memory(f"a weighted median's table of {side} x {side} spatial weights", 4 * side * side,
                               4 * side * side)
        offsets = np.arange(-reach, reach + 1, dtype=np.float64)
        return np.exp(-np.hypot(offsets[:, None], offsets[None, :]) / sigma_space).astype(np.float32)

    return machine.constant(("vmcl.early.weighted_median", "spatial", reach, sigma_space), table)
