"""Integration: the cues' line processes, coupled to brightness edges, meet in one labelled map.

Seed sections "The Vision Machine System" (figure 1) and "Organization of integration". Each cue (depth
from stereo, motion, colour, texture) is restored by its own line-process MRF whose line sites cost less
at brightness edges (equation (12), :func:`vmcl.mrf.restore` with ``edges=``); this module puts their
line processes on the pixel grid and records, at every pixel, which cues support a discontinuity there
and whether a brightness edge lies on it (:class:`Cue` bits). The label of a supported pixel is its
physical reading (a :class:`vmcl.labels.Label` code): a jump of depth or motion is an occluding contour
(DEPTH), a change of hue an albedo edge (ALBEDO), a change of texture alone a texture boundary
(TEXTURE). The labelled pixels are the paper's "cartoon" of the scene. :func:`boundary` turns one line
process into a pixel map, the barriers that feed the integration back to the stereo matcher (the seed's
"feedback from the results of integration into the matching stage").

NumPy in gives NumPy out; device arrays in give device arrays out (uint8 0/1 maps), so the pipeline
keeps every field on the device.

References
----------
E. Gamble and T. Poggio, "Visual integration and detection of discontinuities: the key role of intensity
edges", MIT AI Memo 970, 1987.
E. Gamble, D. Geiger, T. Poggio and D. Weinshall, "Integration of vision modules and labeling of surface
discontinuities", IEEE SMC 19(6):1576-1581, 1989.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import NamedTuple, cast

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    ArrayLike,
    check_bool,
    check_choice,
    check_int,
    check_real_dtype,
    field,
    machine_for,
)
from vmcl.errors import InputTypeError, InputValueError
from vmcl.labels import RULE_PRECEDENCE, Cue, cue_bit, cue_names, rule_label
from vmcl.machine import Machine
from vmcl.mrf import SOLVERS, Restoration, Settings, restore

__all__ = ["Integration", "boundary", "integrate", "restore_cue"]


def _rule_defines() -> dict[str, object]:
    """The kernels' defines: the brightness bit, and each rule label's mask of cue bits in precedence order."""
    masks = {label: 0 for label in RULE_PRECEDENCE}
    for name in cue_names():
        masks[rule_label(name)] |= cue_bit(name)
    rules = [(mask, int(label)) for label, mask in masks.items() if mask]
    return {"BIT_BRIGHTNESS": int(Cue.BRIGHTNESS), "NRULES": len(rules),
            "RULE_MASKS": ",".join(str(mask) for mask, _ in rules),
            "RULE_CODES": ",".join(str(code) for _, code in rules)}


class Integration(NamedTuple):
    """What :func:`integrate` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    support : uint8 (H, W)
        OR of the :class:`Cue` bits of the cues marking each pixel (and BRIGHTNESS on edge pixels).
    labels : uint8 (H, W)
        :class:`vmcl.labels.Label` code of each discontinuity pixel (0 elsewhere): DEPTH where stereo or
        motion supports it, else ALBEDO where colour does, else TEXTURE where texture does.
    """

    support: ArrayLike
    labels: ArrayLike


def _pixel_map(array: ArrayLike, name: str, machine: Machine) -> cl_array.Array:
    """A 2-D 0/1 map on the device as uint8: bool or uint8 on the host (0/1), uint8 on the device."""
    if isinstance(array, np.ndarray) and array.dtype not in (np.bool_, np.uint8):
        raise InputTypeError(f"{name} must be a bool or uint8 array, got {array.dtype}")
    if isinstance(array, np.ndarray):
        array = array.view(np.uint8)
    return field(array, name, machine, ndims=(2,), dtypes=(np.uint8,))[0]


def _lines(line_h: ArrayLike, line_v: ArrayLike, prefix: str, machine: Machine,
           shape: tuple[int, int] | None) -> tuple[cl_array.Array, cl_array.Array, tuple[int, int]]:
    """Both line fields of one cue on the device as uint8, and the pixel shape they imply; ``prefix`` says
    where they came from in the caller's arguments."""
    h = _pixel_map(line_h, f"{prefix}line_h", machine)
    v = _pixel_map(line_v, f"{prefix}line_v", machine)
    implied = (h.shape[0], h.shape[1] + 1)
    if v.shape != (implied[0] - 1, implied[1]):
        raise InputValueError(f"{prefix}line_h {h.shape} and {prefix}line_v {v.shape} are not the two line fields "
                              f"of one image")
    if shape is not None and implied != shape:
        raise InputValueError(f"{prefix}line_h and line_v are the line fields of a {implied} image, but edges, "
                              f"shape or another cue says {shape}")
    return h, v, implied


def _shape(shape) -> tuple[int, int]:
    if not isinstance(shape, (tuple, list)) or len(shape) != 2:
        raise InputTypeError(f"shape must be a (height, width) pair of integers, got {shape!r}")
    return check_int(shape[0], "shape[0]", minimum=1), check_int(shape[1], "shape[1]", minimum=1)


def restore_cue(data: ArrayLike, *, confidence: ArrayLike | None, coupling: ArrayLike, kind: str,
                candidates_only: bool, settings: Settings, method: str, seed: int = 0,
                start: ArrayLike | None = None, machine: Machine | None = None) -> Restoration:
    """Restore one cue's measurements by its line-process MRF, coupled to an edge field.

    The piecewise smooth cues (stereo, motion) are coupled to the brightness edges: a line site costs
    less next to one (equation (12)). The piecewise constant ones (colour, texture) are coupled to their
    own module's candidates with ``candidates_only``: lines are allowed only near them (the boundaries
    these cues exist for are the ones brightness misses).

    Parameters
    ----------
    data, confidence, coupling
        As :func:`vmcl.mrf.restore` takes ``data``, ``confidence`` and ``edges``.
    kind : {"smooth", "constant"}
    candidates_only : bool
        Forbid lines with no coupling edge within the model's ``edge_radius``.
    settings : vmcl.mrf.Settings
        The cue's energy model and solver schedules (e.g. ``Config().mrf.settings("stereo")``).
    method : str
        A solver of :data:`vmcl.mrf.SOLVERS`.
    seed : int
    start : array of the data's shape, optional
        A warm start, as :func:`vmcl.mrf.restore` takes it.
    machine : vmcl.Machine, optional

    Returns
    -------
    vmcl.mrf.Restoration

    Raises
    ------
    vmcl.mrf.NothingToRestore
        When no measurement has a positive confidence.
    """
    if not isinstance(settings, Settings):
        raise InputTypeError(f"settings must be a vmcl.mrf.Settings, got {type(settings).__name__}")
    model = settings.model
    if check_bool(candidates_only, "candidates_only"):
        model = dataclasses.replace(model, require_edge=True)
    check_choice(method, "method", SOLVERS)
    return restore(data, confidence=confidence, edges=coupling, kind=kind, method=method, model=model,
                   schedule=settings.schedule(method), seed=seed, start=start, machine=machine)


def boundary(line_h: ArrayLike, line_v: ArrayLike, *, machine: Machine | None = None) -> ArrayLike:
    """A line process as a pixel map: (y, x) is on when the site to its right or below it is on.

    Parameters
    ----------
    line_h, line_v : (H, W - 1) and (H - 1, W) arrays, bool or uint8 (device arrays: uint8)
        The line fields, as :func:`vmcl.mrf.restore` returns them.
    machine : vmcl.Machine, optional

    Returns
    -------
    (H, W) bool for NumPy input; uint8 0/1 device array for device input. The same map as
    :func:`vmcl.mrf.boundary_map`, computed on the device.
    """
    machine = machine_for(machine)
    host = isinstance(line_h, np.ndarray)
    h, v, (height, width) = _lines(line_h, line_v, "", machine, None)
    out = machine.empty((height, width), np.uint8)
    kernel = machine.kernel("integrate", "boundary", **_rule_defines())
    machine.launch(kernel, (width, height), h, v, out, np.int64(width), np.int64(height))
    return out.get().astype(bool) if host else out


def integrate(lines: Mapping[str, tuple[ArrayLike, ArrayLike]], *, edges: ArrayLike | None = None,
              owners: Mapping[str, ArrayLike] | None = None, shape: tuple[int, int] | None = None,
              machine: Machine | None = None) -> Integration:
    """Combine the cues' line processes and the brightness edges into the labelled discontinuity map.

    Parameters
    ----------
    lines : mapping of cue name to (line_h, line_v)
        Any subset of :data:`vmcl.labels.CUES` ("stereo", "motion", "colour", "texture"); each value as
        :func:`boundary` takes it. Cues left out support nothing.
    edges : (H, W) array, optional
        Brightness edges, non-zero on edge pixels (device arrays: uint8); they set the BRIGHTNESS bit.
    owners : mapping of cue name to (H, W) array, optional
        For a cue of ``lines``, a field that says which of a line site's two pixels the line marks: the
        one whose value is larger (a disparity: the nearer surface, which owns an occluding contour, as
        :mod:`vmcl.scenes` labels it). Equal or NaN values keep the left or upper pixel, the mark of a
        cue without an owner. Device arrays: float32.
    shape : (int, int), optional
        The image's (H, W); required when neither lines nor edges are given.
    machine : vmcl.Machine, optional

    Returns
    -------
    Integration
        (support, labels): NumPy for NumPy input, device arrays when any input is a device array.

    Examples
    --------
    >>> import numpy as np
    >>> line_h = np.zeros((4, 3), bool); line_h[:, 1] = True    # a vertical line between x = 1 and 2
    >>> out = integrate({"colour": (line_h, np.zeros((3, 4), bool))})
    >>> out.labels[0].tolist(), int(out.support[0, 1])
    ([0, 3, 0, 0], 4)
    """
    machine = machine_for(machine)
    if not isinstance(lines, Mapping):
        raise InputTypeError(f"lines must be a mapping of cue name to (line_h, line_v), got {type(lines).__name__}")
    unknown = set(lines) - set(cue_names())
    if unknown:
        raise InputValueError(f"lines has unknown cues {sorted(unknown, key=str)}; cues are {', '.join(cue_names())}")
    for name, pair in lines.items():
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise InputTypeError(f"lines[{name!r}] must be a (line_h, line_v) pair, got {type(pair).__name__}")
    owners = {} if owners is None else owners
    if not isinstance(owners, Mapping):
        raise InputTypeError(f"owners must be a mapping of cue name to a field, got {type(owners).__name__}")
    unowned = set(owners) - set(lines)
    if unowned:
        raise InputValueError(f"owners has cues without lines: {sorted(unowned, key=str)}")
    if shape is not None:
        shape = _shape(shape)
    inputs = ([a for pair in lines.values() for a in pair] + list(owners.values())
              + ([edges] if edges is not None else []))
    host = all(isinstance(a, np.ndarray) for a in inputs)
    marks = []
    for name in cue_names():
        if name in lines:
            h, v, shape = _lines(*lines[name], f"lines[{name!r}] ", machine, shape)
            owner = None
            if name in owners:
                given = owners[name]
                if isinstance(given, np.ndarray):  # any real host dtype, compared as float32 on the device
                    given = check_real_dtype(given, f"owners[{name!r}]").astype(np.float32, copy=False)
                owner = field(given, f"owners[{name!r}]", machine, ndims=(2,), dtypes=(np.float32,))[0]
                if owner.shape != shape:
                    raise InputValueError(f"owners[{name!r}] must have the lines' shape {shape}, got {owner.shape}")
            marks.append((h, v, cue_bit(name), owner))
    if edges is not None:
        if isinstance(edges, np.ndarray):
            edges = (check_real_dtype(edges, "edges") != 0).view(np.uint8)
        edges = field(edges, "edges", machine, ndims=(2,), dtypes=(np.uint8,))[0]
        if shape is not None and edges.shape != shape:
            raise InputValueError(f"edges must have the lines' shape {shape}, got {edges.shape}")
        shape = cast("tuple[int, int]", edges.shape)  # field() above checked that edges is 2-D
    if shape is None:
        raise InputValueError("integrate needs lines, edges or a shape")
    height, width = shape
    support, labels = machine.empty(shape, np.uint8), machine.empty(shape, np.uint8)
    defines = _rule_defines()
    size, extent = (width, height), (np.int64(width), np.int64(height))
    machine.launch(machine.kernel("integrate", "start_support", **defines), size,
                   support if edges is None else edges, np.int32(edges is not None), support, *extent)
    for h, v, bit, owner in marks:
        if owner is None:
            machine.launch(machine.kernel("integrate", "mark_cue", **defines), size, h, v, np.int32(bit), support,
                           *extent)
        else:
            machine.launch(machine.kernel("integrate", "mark_cue_owned", **defines), size, h, v, np.int32(bit),
                           owner, support, *extent)
    machine.launch(machine.kernel("integrate", "rule_labels", **defines), size, support, labels, *extent)
    if host:
        return Integration(support.get(), labels.get())
    return Integration(support, labels)
