"""The binomial Gaussian: smoothing by repeated [1 2 1]/4 passes on the mesh.

Seed section "Edge detection" (Zero-crossings): "An interesting and simple implementation of Gaussian
convolution relies on the binomial approximation to the Gaussian distribution. This algorithm requires
only integer addition, shifting, and local communication on the 2D mesh."
"""

from __future__ import annotations

import numpy as np

from vmcl.cm._arrays import ArrayLike, field, machine_for, result, type_defines
from vmcl.machine import Machine


def binomial(image: ArrayLike, passes: int, *, machine: Machine | None = None) -> ArrayLike:
    """Smooth ``image`` with ``passes`` passes of the 3 x 3 binomial mask [1 2 1]^T [1 2 1] / 16.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, 2-D (H, W) or a 3-D stack (planes, H, W)
        uint8 or int32 (integer add and shift: each pass rounds to nearest, ties up, exactly as
        ``(s + 8) >> 4``) or float32.
    passes : int
        n >= 0. n passes approximate a Gaussian of standard deviation sqrt(n / 2) pixels (the binomial
        of order 2n); n = 0 returns a copy.
    machine : vmcl.Machine, optional

    Returns
    -------
    Same type, shape and dtype as ``image``.

    Notes
    -----
    Borders repeat the edge pixel (clamp). Use ``passes = round(2 * sigma**2)`` for a target sigma.
    """
    machine = machine_for(machine)
    data, host = field(image, "image", machine, ndims=(2, 3), dtypes=(np.uint8, np.int32, np.float32))
    if not isinstance(passes, (int, np.integer)) or isinstance(passes, bool):
        raise TypeError(f"passes must be an integer, got {type(passes).__name__}")
    if passes < 0:
        raise ValueError(f"passes must be >= 0, got {passes}")
    height, width = data.shape[-2:]
    planes = data.size // (height * width)
    defines = type_defines(data.dtype)
    if data.dtype == np.uint8:
        defines["T_IS_UCHAR"] = 1
    kernel = machine.kernel("filters", "binomial_pass", **defines)
    size = (-(-width // 16), height, planes)
    local = machine.row_local_size(size)
    # Ping-pong between two pooled buffers; the input is never written.
    buffers = (machine.empty(data.shape, data.dtype), machine.empty(data.shape, data.dtype))
    source = data
    for k in range(passes):
        target = buffers[k % 2]
        machine.launch(kernel, size, source, target, np.int64(width), np.int64(height), local_size=local)
        source = target
    if passes == 0:
        source = data.copy(queue=machine.queue)
    return result(source, host)
