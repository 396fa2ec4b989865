"""The sign-correlation theorem of the seed section "Motion": why cross-correlating the sign bit of a
Laplacian-filtered image is equivalent to cross-correlating the filtered image itself.

"If f(x, y) and g(x, y) are zero mean jointly normal processes, their cross-correlation is determined
fully by the correlation of the sign of f and of the sign of g (and determines it)":
R(sign f, sign g) = (2 / pi) arcsin R(f, g), the arcsine law (:func:`arcsine_law`).
:func:`sign_correlation` measures the left side on the machine; the "sign_log" features of
:func:`vmcl.early.motion.flow` score each patch by exactly this correlation.

References
----------
H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of optical
flow", Nature 337:549-553, 1989.
H. K. Nishihara, "Practical real-time imaging stereo matcher", Optical Engineering 23(5):536-545, 1984.
"""

from __future__ import annotations

import numpy as np

from vmcl.cm import reduce as _reduce
from vmcl.cm.core import ArrayLike, check_real, check_real_dtype, field, machine_for
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["arcsine_law", "sign_correlation"]


def sign_correlation(f: ArrayLike, g: ArrayLike, *, machine: Machine | None = None) -> float:
    """The correlation of the signs of two fields: the mean of sign(f) sign(g), with sign(0) = +1.

    Parameters
    ----------
    f, g : ndarray or pyopencl.array.Array, same shape, float32
        Fields (zero-mean ones for the arcsine law); host fields must not hold NaN (device fields are
        not checked, which would need a read back).
    machine : vmcl.Machine, optional

    Returns
    -------
    float
        In [-1, 1]; a scalar read back to the host for either kind of input.

    Notes
    -----
    For zero-mean jointly normal f and g with correlation R, the expectation is
    ``arcsine_law(R) = (2 / pi) arcsin R`` (the paper's theorem), so ``sin(pi / 2 * rho)`` recovers R
    from the sign bits alone.

    References
    ----------
    H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of
    optical flow", Nature 337:549-553, 1989.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> f, noise = rng.standard_normal((2, 256, 256)).astype(np.float32)
    >>> g = 0.6 * f + 0.8 * noise  # correlation 0.6
    >>> bool(abs(sign_correlation(f, g) - arcsine_law(0.6)) < 0.01)
    True
    """
    machine = machine_for(machine)
    for name, x in (("f", f), ("g", g)):
        if isinstance(x, np.ndarray) and x.dtype.kind == "f" and np.isnan(x).any():
            raise InputValueError(f"{name} must not contain NaN (it has no sign)")
    fd, _ = field(f, "f", machine, ndims=(1, 2, 3), dtypes=(np.float32,))
    gd, _ = field(g, "g", machine, ndims=(1, 2, 3), dtypes=(np.float32,))
    if fd.shape != gd.shape:
        raise InputValueError(f"f and g must have the same shape, got {fd.shape} and {gd.shape}")
    agreement = machine.empty(fd.shape, np.int32)
    machine.launch(machine.kernel("motion", "sign_agreement"), (fd.size,), fd, gd, agreement, np.int64(fd.size))
    total = _reduce.reduce(agreement, "sum", machine=machine)
    return int(total.get()) / fd.size


def arcsine_law(correlation: float | np.ndarray) -> float | np.ndarray:
    """``(2 / pi) arcsin(R)``: the correlation of the signs of zero-mean jointly normal fields of correlation R.

    Parameters
    ----------
    correlation : float or ndarray
        R in [-1, 1].

    Returns
    -------
    float or ndarray

    References
    ----------
    H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of
    optical flow", Nature 337:549-553, 1989 (the theorem in the seed paper's section "Motion").
    """
    if isinstance(correlation, np.ndarray):
        check_real_dtype(correlation, "correlation")
        if not (np.abs(correlation) <= 1).all():  # NaN fails too
            raise InputValueError("correlation must hold values in [-1, 1]")
    else:
        correlation = check_real(correlation, "correlation", minimum=-1, maximum=1)
    return 2.0 / np.pi * np.arcsin(correlation)
