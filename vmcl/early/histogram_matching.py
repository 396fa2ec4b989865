"""Histogram matching: one field's values moved so that their distribution follows another's.

Two cameras rarely agree on brightness: exposure, gain, vignetting and their response curves differ,
so the same surface point has different grey levels in the two views of a stereo pair (Hirschmueller
and Scharstein, "Evaluation of stereo matching costs on images with radiometric differences", PAMI
31(9), 2009). A matching cost that compares the levels themselves (the semi-global matcher's brightness
difference beside the census) then prices the right match as a poor one. Wherever the two views' tone
curves differ by one monotonic function over the image (a global exposure or response difference), giving
each value of one view the value of the same rank in the other undoes it exactly; most of the pixels of a
pair see the same surfaces, so their distributions differ little otherwise.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import ArrayLike, check_int, field, machine_for, result
from vmcl.cm.reduce import histogram, reduce
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["match_histogram"]


def match_histogram(image: ArrayLike, reference: ArrayLike, *, bins: int = 1024,
                    machine: Machine | None = None) -> ArrayLike:
    """``image`` with each value replaced by the value of the same rank in ``reference``.

    Parameters
    ----------
    image : float32 (H, W) array or device array
        The field to move (a host array of another real dtype is converted to float32); NaN stays NaN
        and takes no part.
    reference : float32 (H2, W2) array or device array
        The field whose distribution ``image`` takes on; any size (another view of the scene).
    bins : int
        >= 2: both fields are binned over their joint span (the lesser minimum to the greater maximum) in
        this many equal bins; a value's rank and the reference's value of that rank are each interpolated
        linearly within their bin.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W), as ``image`` came (NumPy for NumPy, else a device array). A field matched to itself
    comes back unchanged; one whose values are a monotonic function of the reference's comes back as
    the reference's values, to within a bin's width (the span / ``bins``).

    Raises
    ------
    InputTypeError, InputValueError
        Naming the argument: not a real 2-D field, an infinite value in a host field, host and device
        fields mixed, ``bins`` outside [2, what the device's local memory holds].
    """
    machine = machine_for(machine)
    fields = []
    for name, x in (("image", image), ("reference", reference)):
        if isinstance(x, np.ndarray):
            if x.dtype.kind not in "uif":
                raise InputTypeError(f"{name} must hold real numbers, got dtype {x.dtype}")
            x = x.astype(np.float32, copy=False)
            if np.isinf(x).any():
                raise InputValueError(f"{name} must not hold an infinite value")
        fields.append(field(x, name, machine, ndims=(2,), dtypes=(np.float32,)))
    (data, host), (ref, reference_host) = fields
    if host != reference_host:
        raise InputTypeError("image and reference must both be NumPy arrays or both device arrays")
    bins = check_int(bins, "bins", minimum=2)
    ends = [reduce(x, op, machine=machine) for op in ("min", "max") for x in (data, ref)]
    cdfs = []
    places = []
    for x in (data, ref):
        place = machine.empty(x.shape, np.float32)
        machine.launch(machine.kernel("histogram_matching", "unit_levels"), (x.size,), x, place,
                       np.int64(x.size), *ends)
        counts = histogram(place, bins, (0.0, 1.0), machine=machine)
        assert isinstance(counts, cl_array.Array)  # device field in, device counts out
        cdf = machine.empty((bins + 1,), np.float32)
        machine.launch(machine.kernel("histogram_matching", "cumulate"), (1,), counts, cdf, np.int32(bins))
        cdfs.append(cdf)
        places.append(place)
    out = machine.empty(data.shape, np.float32)
    machine.launch(machine.kernel("histogram_matching", "match_levels"), (data.size,), data, places[0], *cdfs, out,
                   np.int64(data.size), np.int32(bins), *ends)
    return result(out, host)
