"""The shared core under the primitives (:mod:`vmcl.cm`) and the early layer (:mod:`vmcl.early`):
argument checks, host/device dispatch and the launches of vectorised row and flat kernels.

NumPy in gives NumPy out; a device array in gives a device array out, so a pipeline keeps its fields on
the device between stages. Inputs are checked at the door with errors that name the argument. Every
module above takes its checks and launches from here, so one piece of code serves every caller.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Iterable
from typing import Any, TypeVar, cast

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
from numpy.typing import DTypeLike

from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine, default_machine, device_memory

__all__ = [
    "IMAGE_TYPES",
    "UNIT_MARGIN",
    "WIDEST",
    "ArrayLike",
    "bool_as_bytes",
    "check_bool",
    "check_choice",
    "check_context",
    "check_int",
    "check_real",
    "check_real_dtype",
    "check_same_kind",
    "check_same_scale",
    "check_sigma",
    "check_unit_image",
    "check_unmasked",
    "check_widths",
    "device_memory",
    "field",
    "finite_float32",
    "flags_field",
    "full_scale",
    "image_field",
    "launch_flat",
    "launch_rows",
    "machine_for",
    "mask_result",
    "normalise_axis",
    "output_array",
    "real_host_array",
    "result",
    "to_host",
    "type_defines",
    "vector_kernel",
]

ArrayLike = np.ndarray | cl_array.Array
"""What the public functions take and return: a NumPy array or a device array."""

WIDEST = 32
"""Gaussian width (sigma, in pixels) any image may be smoothed with; wider ones only up to the image's
larger side, past which a Gaussian only blurs the repeated border while its work keeps growing."""

IMAGE_TYPES: dict[np.dtype, str] = {np.dtype(np.uint8): "uchar", np.dtype(np.uint16): "ushort",
                                    np.dtype(np.float32): "float"}
"""The image dtypes the early layer's kernels read, with their OpenCL type names (the ``IN_T`` define)."""

# Host dtypes that convert to int32 or float32 without changing any value.
_EXACT_TO_INT32 = {np.dtype(t) for t in (np.bool_, np.int8, np.uint8, np.int16, np.uint16, np.int32)}
_EXACT_TO_FLOAT32 = {np.dtype(np.float16), np.dtype(np.float32)}


def machine_for(machine: Machine | None) -> Machine:
    """The Machine a call runs on: ``machine`` itself, or :func:`vmcl.default_machine` for None.

    Raises
    ------
    InputTypeError
        For anything but a Machine or None.
    """
    if machine is not None and not isinstance(machine, Machine):
        raise InputTypeError(f"machine must be a vmcl.Machine or None, got {type(machine).__name__}")
    return machine if machine is not None else default_machine()


@functools.cache
def _dtypes(dtypes: tuple[DTypeLike, ...]) -> tuple[np.dtype, ...]:
    return tuple(np.dtype(t) for t in dtypes)


class _DtypeNames:
    """The accepted dtypes as text, formatted only when an error message needs them."""

    def __init__(self, accepted: tuple[np.dtype, ...]) -> None:
        self.accepted = accepted

    def __str__(self) -> str:
        return " or ".join(str(d) for d in self.accepted)


def field(x: Any, name: str, machine: Machine, *, ndims: tuple[int, ...],
          dtypes: tuple[DTypeLike, ...] = (np.int32, np.float32)) -> tuple[cl_array.Array, bool]:
    """Check ``x`` and return it as a device array with whether it came from the host.

    Host arrays of a narrower integer (or float16) dtype are widened exactly to int32 (float32) when
    that dtype is accepted; device arrays must already have an accepted dtype, since converting them
    would hide a copy.
    """
    accepted = _dtypes(dtypes)
    names = _DtypeNames(accepted)
    if isinstance(x, cl_array.Array):
        check_context(x, name, machine)
        if x.dtype not in accepted:
            raise InputTypeError(f"{name} must have dtype {names}, got {x.dtype}")
        if not x.flags.c_contiguous:
            raise InputValueError(f"{name} must be a C-contiguous device array")
        if x.offset:
            # Kernels get the buffer itself, which starts before a view's first element.
            raise InputValueError(f"{name} must not be a device view with an offset (copy it: {name}.copy())")
        host = False
        device = x
    elif isinstance(x, np.ndarray):
        check_unmasked(x, name)
        host = True
        dtype = x.dtype.newbyteorder("=")  # a big-endian uint16 is a uint16: its values are uploaded natively
        if dtype not in accepted:
            if np.dtype(np.int32) in accepted and dtype in _EXACT_TO_INT32:
                dtype = np.dtype(np.int32)
            elif np.dtype(np.float32) in accepted and dtype in _EXACT_TO_FLOAT32:
                dtype = np.dtype(np.float32)
            else:
                raise InputTypeError(f"{name} must have dtype {names} (convert with .astype), got {x.dtype}")
        device = None
    else:
        raise InputTypeError(f"{name} must be a NumPy array or a pyopencl.array.Array, got {type(x).__name__}")
    if x.ndim not in ndims:
        raise InputValueError(f"{name} must have {_dimensions(ndims)} dimensions, got shape {x.shape}")
    if x.size == 0:
        raise InputValueError(f"{name} must not be empty, got shape {x.shape}")
    if device is None:
        device = machine.to_device(np.asarray(x, dtype=dtype))
    return device, host


def bool_as_bytes(x: Any) -> Any:
    """A boolean array, host or device, as the uint8 array of its bytes (0 and 1), which the kernels read;
    anything else as it is."""
    if isinstance(x, (np.ndarray, cl_array.Array)) and x.dtype == np.bool_:
        return x.view(np.uint8)
    return x


def flags_field(segments: Any, shape: tuple[int, ...], name: str, machine: Machine) -> cl_array.Array:
    """Segment-start flags as a uint8 device array of the given shape (non-zero marks a start)."""
    if isinstance(segments, np.ndarray):
        if segments.shape != shape:
            raise InputValueError(f"{name} must have the data's shape {shape}, got {segments.shape}")
        if segments.dtype != np.bool_ and not np.issubdtype(segments.dtype, np.integer):
            raise InputTypeError(f"{name} must be boolean or integer flags, got {segments.dtype}")
        return machine.to_device((segments != 0).astype(np.uint8))
    if isinstance(segments, cl_array.Array):
        check_context(segments, name, machine)
        if segments.shape != shape:
            raise InputValueError(f"{name} must have the data's shape {shape}, got {segments.shape}")
        if segments.dtype not in (np.dtype(np.uint8), np.dtype(np.bool_)):
            raise InputTypeError(f"{name} on the device must be uint8 or bool, got {segments.dtype}")
        return segments
    raise InputTypeError(f"{name} must be a NumPy array, a pyopencl.array.Array or None, got {type(segments).__name__}")


def output_array(out: Any, machine: Machine, like: cl_array.Array, host: bool, name: str = "out") -> cl_array.Array:
    """The device array a call writes its result into: ``out`` when the caller gives one, else a new one
    from the Machine's pool, with ``like``'s shape and dtype.

    ``out`` lets a caller that keeps its fields on the device reuse one buffer across calls (a stream of
    frames). It must be a C-contiguous device array of this Machine's context with the result's shape and
    dtype, and not the input itself: the kernels read neighbours of what they write.
    """
    if out is None:
        return machine.empty(like.shape, like.dtype)
    if host:
        raise InputTypeError(f"{name} is for device input (it is a device array the result is written to); "
                             "with NumPy input the result is a new NumPy array")
    if not isinstance(out, cl_array.Array):
        raise InputTypeError(f"{name} must be a pyopencl.array.Array or None, got {type(out).__name__}")
    check_context(out, name, machine)
    if out.shape != like.shape or out.dtype != like.dtype:
        raise InputValueError(f"{name} must have the result's shape {like.shape} and dtype {like.dtype}, "
                              f"got {out.shape} {out.dtype}")
    if not out.flags.c_contiguous or out.offset:
        raise InputValueError(f"{name} must be a C-contiguous device array without an offset (not a view)")
    if out.base_data is like.base_data:
        raise InputValueError(f"{name} must not be the input array: the kernels read it while writing")
    return out


def result(device: cl_array.Array, host: bool) -> ArrayLike:
    """A call's output as its input came: copied to NumPy when ``host``, else the device array itself."""
    return device.get() if host else device


def mask_result(mask: cl_array.Array, host: bool) -> ArrayLike:
    """A call's 0/1 uint8 device mask as its input came: a bool NumPy array for host input (a view of the
    copied bytes), else the device array itself."""
    return mask.get().view(np.bool_) if host else mask


def type_defines(dtype: np.dtype) -> dict[str, Any]:
    """The -D defines that specialise a kernel family for int32 or float32."""
    if dtype == np.float32:
        return {"T": "float", "T_IS_FLOAT": 1}
    if dtype == np.int32:
        return {"T": "int", "T_IS_FLOAT": 0}
    if dtype == np.uint8:
        return {"T": "uchar", "T_IS_FLOAT": 0}
    raise InputTypeError(f"no kernel type for dtype {dtype}")


def check_int(value: Any, name: str, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as an int; TypeError naming ``name`` for a non-integer (bool included), ValueError below
    ``minimum`` or above ``maximum``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InputTypeError(f"{name} must be an integer, got {type(value).__name__}")
    if minimum is not None and value < minimum:
        raise InputValueError(f"{name} must be >= {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise InputValueError(f"{name} must be <= {maximum}, got {value}")
    return int(value)


def check_real(value: Any, name: str, *, minimum: float | None = None, maximum: float | None = None,
               above: float | None = None, below: float | None = None) -> float:
    """``value`` as a finite float in range; TypeError naming ``name`` for anything but a real number (bool,
    str, None, arrays and complex included), ValueError for NaN, infinity or a value out of range.

    ``minimum`` / ``maximum`` are inclusive bounds, ``above`` / ``below`` exclusive ones.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputTypeError(f"{name} must be a real number, got {type(value).__name__}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond float's range
        number = math.inf if value > 0 else -math.inf
    limits = [(bound, sign, test) for bound, sign, test in ((minimum, ">=", operator.ge), (maximum, "<=", operator.le),
                                                            (above, ">", operator.gt), (below, "<", operator.lt))
              if bound is not None]
    if not math.isfinite(number) or not all(test(number, bound) for bound, _, test in limits):
        wanted = "".join(f"{' and' if i else ''} {sign} {bound}" for i, (bound, sign, _) in enumerate(limits))
        raise InputValueError(f"{name} must be a finite number{wanted}, got {value}")
    return number


def check_bool(value: Any, name: str) -> bool:
    """``value`` as a bool; TypeError naming ``name`` for anything else (0, 1, "no" and None included)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputTypeError(f"{name} must be a bool (True or False), got {type(value).__name__}")
    return bool(value)


_Choice = TypeVar("_Choice", bound=str)


def check_choice(value: Any, name: str, choices: Iterable[_Choice]) -> _Choice:
    """``value``, one of the strings ``choices``; TypeError for a non-string, ValueError for another string.

    Typed as the choices' type, so choices of a ``Literal`` type (``OPS: dict[Op, int]``) give that type.
    """
    choices = tuple(choices)
    if not isinstance(value, str):
        raise InputTypeError(f"{name} must be one of {choices}, got {type(value).__name__}")
    if value not in choices:
        raise InputValueError(f"{name} must be one of {choices}, got {value!r}")
    # Equal to one of the choices, so of their type (a Literal's values are plain strs).
    return cast(_Choice, value)


def check_context(x: cl_array.Array, name: str, machine: Machine) -> None:
    """Refuse a device array made in another OpenCL context (another Machine): its buffers mean nothing to
    this machine's kernels."""
    if x.context != machine.context:
        raise InputValueError(f"{name} lives on another OpenCL context than the machine's ({machine!r}); "
                              f"copy it through the host")


def check_same_kind(first: str, first_host: bool, second: str, second_host: bool) -> None:
    """Refuse two arrays of one call that are not both NumPy arrays or both device arrays (``*_host``: whether
    each is a NumPy array): a call returns what it was given, and mixed kinds leave that undecided."""
    if first_host != second_host:
        raise InputTypeError(f"{first} and {second} must both be NumPy arrays or both device arrays")


def full_scale(dtype: DTypeLike) -> float:
    """The brightness an image type's largest value stands for, in the units of float images (which hold
    brightness in [0, 1]): 255 for uint8, 65535 for uint16, 1 for floats, whatever the byte order."""
    return {"u1": 255.0, "u2": 65535.0}.get(np.dtype(dtype).newbyteorder("=").str[1:], 1.0)


def check_same_scale(first: str, first_dtype: DTypeLike, second: str, second_dtype: DTypeLike) -> None:
    """Refuse two images of one call whose values are on different scales: vmcl compares their values as they
    are, in their type's units (uint8 0..255, uint16 0..65535, floats 0..1), so a uint8 frame beside a float
    one, or beside a uint16 one, would be matched against numbers of another meaning. Floats of any width
    go together; the byte order does not matter."""
    a, b = np.dtype(first_dtype).newbyteorder("="), np.dtype(second_dtype).newbyteorder("=")
    if a == b or (a.kind == "f" and b.kind == "f"):
        return
    raise InputValueError(f"{first} and {second} must have the same type (their values are compared in their "
                          f"type's units: 0..255, 0..65535, or 0..1 for floats), got {first_dtype} and {second_dtype}")


def check_unmasked(x: Any, name: str) -> None:
    """Refuse a NumPy masked array with masked values: vmcl reads every value of an array, so its mask
    would be silently lost (one with nothing masked is read as its data)."""
    if isinstance(x, np.ma.MaskedArray) and np.ma.getmaskarray(x).any():
        raise InputValueError(f"{name} is a masked array with masked values, and vmcl reads every value: fill "
                              f"them ({name}.filled(...), NaN where the function takes NaN for a missing value) "
                              "or pass its data")


def _dimensions(ndims: tuple[int, ...]) -> str:
    """The dimension counts allowed, as a message says them: "2 or 3", or "1 to 32" for a longer run."""
    if len(ndims) > 3 and list(ndims) == list(range(ndims[0], ndims[-1] + 1)):
        return f"{ndims[0]} to {ndims[-1]}"
    return " or ".join(str(n) for n in ndims)


def check_real_dtype(x: Any, name: str) -> np.ndarray:
    """``x`` checked as a NumPy array of real numbers (bool, integer or float); complex, object, string
    and other dtypes are refused, never converted."""
    if not isinstance(x, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy array, got {type(x).__name__}")
    check_unmasked(x, name)
    if x.dtype.kind not in "biuf":
        raise InputTypeError(f"{name} must hold real numbers (bool, integer or float), got dtype {x.dtype}")
    return x


def to_host(x: Any, name: str | None = None) -> Any:
    """``x`` as it is, or a device array (pyopencl) copied to a NumPy array, for host-side arithmetic; given
    the argument's ``name``, a masked array with masked values is refused (:func:`check_unmasked`)."""
    if name is not None:
        check_unmasked(x, name)
    return x.get() if isinstance(x, cl_array.Array) else x


def real_host_array(x: Any, name: str, *, ndims: tuple[int, ...], empty: bool = False) -> np.ndarray:
    """``x`` checked as a NumPy array of real numbers (:func:`check_real_dtype`) with one of ``ndims``
    dimensions, and not empty unless ``empty``."""
    check_real_dtype(x, name)
    if x.ndim not in ndims:
        raise InputValueError(f"{name} must have {_dimensions(ndims)} dimensions, got shape {x.shape}")
    if x.size == 0 and not empty:
        raise InputValueError(f"{name} must not be empty, got shape {x.shape}")
    return x


def normalise_axis(axis: int, ndim: int, allowed: tuple[int, ...], name: str = "axis") -> int:
    """``axis`` as a negative index, checked against the allowed (negative) axes."""
    check_int(axis, name)
    if not -ndim <= axis < ndim:
        raise InputValueError(f"{name}={axis} is out of range for an array of {ndim} dimensions")
    negative = int(axis) - ndim if axis >= 0 else int(axis)
    if negative not in allowed:
        raise InputValueError(f"{name}={axis} is not supported: scans run along the last axis (rows) or, for "
                         f"2-D and 3-D fields, the second to last (columns)")
    return negative


def check_sigma(sigma: Any, name: str = "sigma") -> float:
    """``sigma`` as a float; TypeError naming ``name`` for anything but a real number (bool included),
    ValueError for NaN, infinity or a value <= 0."""
    if isinstance(sigma, bool) or not isinstance(sigma, (int, float, np.integer, np.floating)):
        raise InputTypeError(f"{name} must be a number, got {type(sigma).__name__}")
    try:
        value = float(sigma)
    except OverflowError:  # an int past float's range
        raise InputValueError(f"{name} must be a finite number > 0, got an integer past float's range") from None
    if not math.isfinite(value) or value <= 0:
        raise InputValueError(f"{name} must be a finite number > 0, got {sigma}")
    return value


def check_widths(widths: dict[str, float], height: int, width: int) -> None:
    """Refuse Gaussians (name: sigma) wider than a ``height`` x ``width`` image allows.

    The work of a pass grows with the width (taps or binomial passes), and past the image's larger side
    (or :data:`WIDEST` for smaller images) a Gaussian only blurs the repeated border.
    """
    limit = max(height, width, WIDEST)
    for name, sigma in widths.items():
        if sigma > limit:
            raise InputValueError(f"{name} must be at most {limit} for a {height} x {width} image (its larger "
                                  f"side, or {WIDEST} for smaller images), got {sigma}")


def finite_float32(x: Any, name: str) -> Any:
    """A host float array ``x`` checked finite and converted to float32; anything else unchanged.

    Raises
    ------
    InputValueError
        Naming ``name``, for NaN or infinity, and for values beyond float32's range.
    """
    check_unmasked(x, name)
    if isinstance(x, np.ndarray) and x.dtype.kind == "f":
        if not np.isfinite(x).all():
            raise InputValueError(f"{name} must not contain NaN or infinite values")
        if x.dtype != np.float32:
            x = x.astype(np.float32)
            if not np.isfinite(x).all():
                raise InputValueError(f"{name} has values beyond float32's range")
    return x


UNIT_MARGIN = 0.25
"""How far outside [0, 1] a float image's brightness may reach and still be read on the [0, 1] scale (noisy
renderings overshoot; an image in 0..255 is far outside, and one centred on 0, in [-0.5, 0.5], is outside
too: with a margin of 0.5 it was read as a dark image on the wrong scale)."""


def check_unit_image(image: np.ndarray, name: str) -> None:
    """Refuse, naming ``name``, a host float image whose brightness is not on the [0, 1] scale (within
    :data:`UNIT_MARGIN`): the thresholds and weights it meets are set for that scale, and an image on
    another (0..255 floats) would be processed as something else. Dividing by the full scale is the
    caller's knowledge, so it is refused, not rescaled."""
    if not image.size:
        return  # no brightness to be on the wrong scale (the callers refuse empty images by their shape)
    low, high = float(np.min(image)), float(np.max(image))
    if low < -UNIT_MARGIN or high > 1 + UNIT_MARGIN:
        raise InputValueError(f"{name}: float images hold brightness in [0, 1], got values in [{low:.3g}, "
                              f"{high:.3g}]; divide by the image's full scale (e.g. 255) first")


def image_field(image: Any, machine: Machine, *, what: str, footprint: int, largest: int = 4,
                widths: dict[str, float] | None = None) -> tuple[cl_array.Array, bool]:
    """Check a grey or RGB image and return it on the device with whether it came from the host.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        Of a dtype in :data:`IMAGE_TYPES`; host floats of other widths are converted to float32, after
        refusing NaN, infinity and values beyond float32's range (:func:`finite_float32`).
    machine : vmcl.Machine
    what : str
        The computation, as the memory error names it ("a Gaussian").
    footprint : int
        Device bytes per pixel the call needs besides the input.
    largest : int
        Bytes per pixel of the largest buffer the call allocates.
    widths : dict of str to float, optional
        Gaussian widths (name: sigma) checked against the image (:func:`check_widths`).

    Returns
    -------
    (pyopencl.array.Array, bool)
        The image on the device (uint8, uint16 or float32) and whether it came from the host.

    Notes
    -----
    Widths and device memory (:meth:`vmcl.Machine.require_memory`) are checked before anything is
    uploaded.
    """
    image = finite_float32(image, "image")
    if isinstance(image, (np.ndarray, cl_array.Array)) and image.ndim in (2, 3) and image.size:
        height, width = image.shape[:2]
        check_widths(widths or {}, height, width)
        pixels, input_bytes = height * width, image.size * min(image.dtype.itemsize, 4)
        machine.require_memory(f"{what} of a {height} x {width} image", input_bytes + footprint * pixels,
                               max(input_bytes, largest * pixels))
    data, host = field(image, "image", machine, ndims=(2, 3), dtypes=tuple(IMAGE_TYPES))
    if data.ndim == 3 and data.shape[2] != 3:
        raise InputValueError(f"image must be grey (H, W) or RGB (H, W, 3), got shape {data.shape}")
    return data, host


def vector_kernel(machine: Machine, family: str, name: str, **defines: Any) -> cl.Kernel:
    """Kernel ``name`` of ``family`` built for the Machine's :attr:`~vmcl.Machine.vector_width` (the
    ``VEC`` define: elements per work-item), for :func:`launch_rows` and :func:`launch_flat`."""
    return machine.kernel(family, name, VEC=machine.vector_width, **defines)


def launch_rows(machine: Machine, kernel: cl.Kernel, width: int, height: int, *args: Any) -> None:
    """Launch a :func:`vector_kernel` over (row chunks of ``vector_width`` pixels, rows) of a ``height`` x
    ``width`` field, in the Machine's work-groups for row kernels (:meth:`vmcl.Machine.row_local_size`)."""
    size = (-(-width // machine.vector_width), height)
    machine.launch(kernel, size, *args, local_size=machine.row_local_size(size))


def launch_flat(machine: Machine, kernel: cl.Kernel, n: int, *args: Any) -> None:
    """Launch a :func:`vector_kernel` over chunks of ``vector_width`` elements of a flat field of ``n``."""
    machine.launch(kernel, (-(-n // machine.vector_width),), *args)
