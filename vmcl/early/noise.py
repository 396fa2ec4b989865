"""Noise estimation from histograms of gradient magnitudes, for Canny's thresholds.

Seed section "Edge detection" (Noise Estimation): "Estimating noise in the image can be done by
analyzing a histogram of the gradient magnitudes. Most computational implementations of this step
perform a global analysis ...; we have had success with a Connection Machine implementation using local
histograms." Both are here: one histogram of the whole field, or one per tile
(:func:`vmcl.cm.reduce.histogram`), turned into thresholds on the device, one work-item per histogram.

The rule
--------
Where the image is smooth, the smoothed gradient is noise: its two components are Gaussian with some
standard deviation s, so its magnitude follows a Rayleigh law of scale s, whose median is
s * sqrt(2 ln 2). Most pixels of most images are smooth, so

    s = median(|grad|) / sqrt(2 ln 2),

and a noise pixel exceeds k s with probability exp(-k**2 / 2). Texture raises the median, which makes
every threshold below more conservative, never less. A detector that tests each pixel once uses
NOISE_HIGH = 4.1 (2e-4 of noise pixels pass; :mod:`vmcl.early.color`). Canny's hysteresis needs more:
the maxima of smoothed noise above its low threshold form chains that grow from every strong edge, and
every chain holding a noise pixel above high survives, so Canny takes

    low = CANNY_LOW * s = 3 s,   high = CANNY_HIGH * s = 6 s

(1.1% and 1.5e-8 of noise pixels pass). With 2 s and 4.1 s, chains of noise hung on the step edges of
the localisation tests; 3 s and 6 s kept all of them clean at noise up to a fifth of the contrast and
sigma from 1 to 3.

References
----------
J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.
"""

from __future__ import annotations

import math
from typing import Literal, overload

import numpy as np
import pyopencl.array as cl_array
from pyopencl import cltypes

from vmcl.cm import reduce as _reduce
from vmcl.cm.core import ArrayLike, check_real, field, machine_for, result, vector_kernel
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = [
    "BINS",
    "CANNY_HIGH",
    "CANNY_LOW",
    "NOISE_HIGH",
    "NOISE_LOW",
    "TILE",
    "Noise",
    "noise_rule",
    "noise_thresholds",
    "threshold_field",
]

NOISE_LOW = 2.0
"""Low threshold of the plain rule, in units of the estimated noise scale s."""
NOISE_HIGH = 4.1
"""High threshold of the plain rule (a detector testing each pixel once), in units of s."""
CANNY_LOW = 3.0
"""Canny's low threshold, in units of s."""
CANNY_HIGH = 6.0
"""Canny's high threshold, in units of s."""
TILE = 64
"""Side of the square tiles of the local estimate, in pixels."""
BINS = 4096
"""Histogram bins over [0, max |grad|]; quantiles are interpolated within a bin."""

Noise = Literal["global", "local"]
_MEDIAN_OF_RAYLEIGH = math.sqrt(2.0 * math.log(2.0))


def noise_rule(low: float = NOISE_LOW, high: float = NOISE_HIGH) -> tuple[float, float, float, float]:
    """(quantile, quantile, factor, factor) for :func:`threshold_field`: thresholds ``low * s`` and
    ``high * s``, both scaling the median."""
    low, high = check_real(low, "low", minimum=0), check_real(high, "high", minimum=0)
    if low > high:
        raise InputValueError(f"low must be at most high, got low={low}, high={high}")
    return 0.5, 0.5, low / _MEDIAN_OF_RAYLEIGH, high / _MEDIAN_OF_RAYLEIGH


def threshold_field(machine: Machine, magnitude: cl_array.Array, rule: tuple[float, float, float, float],
                    *, local: bool) -> tuple[cl_array.Array, tuple[int, int]]:
    """Device thresholds (low, high) from histograms of ``magnitude``: ``rule = (f_low, f_high, k_low,
    k_high)`` gives ``k * quantile(f)``. Returns the pairs, shape (tiles_y, tiles_x, 2), and the tiles.

    The histograms span [0, max] with the field's maximum kept on the device, so the host never waits.
    """
    top = _reduce.reduce(magnitude, "max", machine=machine)
    tile = (TILE, TILE) if local else None
    hist = _reduce.histogram_to_top(magnitude, BINS, top, tile=tile, machine=machine)
    height, width = magnitude.shape
    tiles = (math.ceil(height / TILE), math.ceil(width / TILE)) if local else (1, 1)
    out = machine.empty(tiles + (2,), np.float32)
    count = tiles[0] * tiles[1]
    thresholds = vector_kernel(machine, "edges", "histogram_thresholds")
    # pyopencl.cltypes makes its make_<type> functions at import; its type hints declare only the dtypes.
    rule4 = cltypes.make_float4(*rule)  # type: ignore[attr-defined]
    machine.launch(thresholds, (count,), hist, out, np.int32(BINS), top, rule4, np.int64(count))
    return out, tiles


@overload
def noise_thresholds(magnitude: np.ndarray, *, noise: Noise = "global",
                     machine: Machine | None = None) -> np.ndarray: ...
@overload
def noise_thresholds(magnitude: cl_array.Array, *, noise: Noise = "global",
                     machine: Machine | None = None) -> cl_array.Array: ...
def noise_thresholds(magnitude: ArrayLike, *, noise: Noise = "global", machine: Machine | None = None) -> ArrayLike:
    """Canny's (low, high) thresholds from the noise estimated in a field of gradient magnitudes.

    Parameters
    ----------
    magnitude : ndarray or pyopencl.array.Array, float32 (H, W)
        Gradient magnitudes, e.g. the second output of ``canny(..., return_gradient=True)``; >= 0 and
        finite, and small enough for the high threshold (about 5 times the median) to be a float32: at most
        ``float32 max * sqrt(2 ln 2) / CANNY_HIGH`` (6.68e37). A host array outside these is refused; a
        device array is not checked, because that would make the host wait (NaN or infinity there gives
        thresholds of infinity or 0).
    noise : {"global", "local"}
        "global": one histogram of the whole field. "local": one per tile of :data:`TILE` x :data:`TILE`
        pixels (tiles at the right and bottom hold what is left); :func:`vmcl.early.edges.canny`
        interpolates them bilinearly between tile centres.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 array: (2,) for "global", (ceil(H / TILE), ceil(W / TILE), 2) for "local"; each pair is
    (low, high) by the rule of this module's docstring. NumPy for NumPy input, else a device array.

    Notes
    -----
    Medians come from :data:`BINS`-bin histograms over [0, max], with the values of a bin taken as
    spread evenly across it: within one bin width (max / 4096) of ``np.median``. Any finite scale works,
    subnormal magnitudes included: the thresholds keep float32's precision at that scale. A field (or a
    tile) that is 0 everywhere has no scale of its own: its histogram spans [0, 1]
    (:func:`vmcl.cm.reduce.histogram_to_top`'s fallback), so its thresholds are those of a median half a
    bin of that span wide, small and positive, and no pixel of it is an edge.

    References
    ----------
    J. Canny, "A computational approach to edge detection", IEEE TPAMI 8(6):679-698, 1986.
    """
    machine = machine_for(machine)
    if noise not in ("global", "local"):
        raise InputValueError(f"noise must be 'global' or 'local', got {noise!r}")
    if isinstance(magnitude, np.ndarray) and magnitude.dtype.kind == "f" and magnitude.size:
        if not np.isfinite(magnitude).all():
            raise InputValueError("magnitude must not contain NaN or infinite values")
        # Thresholds are a quantile times up to CANNY_HIGH / sqrt(2 ln 2), in float32: beyond this they overflow.
        largest = float(np.finfo(np.float32).max) * _MEDIAN_OF_RAYLEIGH / CANNY_HIGH
        low, high = float(magnitude.min()), float(magnitude.max())
        if low < 0:
            raise InputValueError(f"magnitude must be >= 0 (gradient magnitudes), got a minimum of {low:g}")
        if high > largest:
            raise InputValueError(f"magnitude must be at most {largest:.3g}, so that Canny's high threshold "
                                  f"({CANNY_HIGH:g} s) fits float32, got a maximum of {high:g}")
    data, host = field(magnitude, "magnitude", machine, ndims=(2,), dtypes=(np.float32,))
    out, _ = threshold_field(machine, data, noise_rule(CANNY_LOW, CANNY_HIGH), local=noise == "local")
    return result(out.reshape(2) if noise == "global" else out, host)
