"""Edge pixels linked into curves on the machine, with each curve's length, curvature and strength.

Seed section "Saliency, grouping, and segmentation": the saliency operation works on curves, not pixels.
Each edge pixel finds its neighbours among the edge pixels (mixed adjacency: a diagonal neighbour only
where no 4-neighbour shares the corner, so a one-pixel-thin staircase is a chain, not a string of
triangles). Pixels with three or more links are branch pixels, where curves meet: they split the curves
and are where the junctions are (:mod:`vmcl.group.junctions`). Every other edge pixel has at most two
links, so the curve pixels form paths and closed loops. Each curve is walked both ways as a ring of
"tour" nodes, and distance doubling over the rings (:func:`vmcl.cm.doubling.principal_from_predecessors`,
the paper's use of it, on the rings the tour writes backwards) gives every pixel its curve (the ring's
principal) and its arc position in O(log n) steps.

Each curve's size (its largest arc position + 1, gathered at its key: its principal's, made dense) and an
exclusive sum of the sizes put every pixel in its slot, curve after curve in arc order, on the device, and
draw the maps; the tangents and turns are then read from neighbouring slots. The host reads the pixels in
that order and measures each curve: its length (steps of 1 and sqrt 2), its curvature (the turning of the
tangent of the positions smoothed along the arc), its mean gradient magnitude and its end tangents.

Coordinates are (x, y): x the column, y the row, as image pixels are addressed.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm import doubling
from vmcl.cm.core import WIDEST, ArrayLike, check_real, field, machine_for
from vmcl.cm.scan import exclusive_sum_into
from vmcl.errors import InputValueError
from vmcl.machine import Machine
from vmcl.mrf.checks import check_weights

__all__ = ["BRANCH", "Curve", "Curves", "link_edges"]

BRANCH = -2
"""The value :attr:`Curves.labels` holds at branch pixels (off the edges: -1)."""

_TANGENT_SPAN = 5  # pixels back from an end along which its tangent is measured
_FIELDS = 10  # int32 words per curve pixel in the packed answer (kernels/curves.cl's OUT_ fields)
_EARLY_FIELDS = 7  # of which the first seven are written before the tangents (OUT_TURN)
RUN = 16  # pixels per work-item of kernels/curves.cl's whole-image passes (its RUN)


@dataclass(frozen=True)
class Curve:
    """One curve of :class:`Curves`.

    Attributes
    ----------
    points : int32 (n, 2)
        Its pixels (x, y) in arc order.
    closed : bool
        A loop (its last pixel links back to its first).
    length : float
        Arc length in pixels (steps of 1 along the axes, sqrt 2 on diagonals; a loop's closing step counted).
    mean_curvature : float
        Mean |curvature| in radians per pixel (the tangent's total turning over the length).
    total_curvature : float
        The tangent's total turning, in radians.
    magnitude : float
        Mean gradient magnitude over the pixels (NaN when no magnitude was given).
    tangents : float64 (2, 2)
        Unit tangents pointing out of the curve at its first and last pixel (NaN for loops and single pixels).
    """

    points: np.ndarray
    closed: bool
    length: float
    mean_curvature: float
    total_curvature: float
    magnitude: float
    tangents: np.ndarray


@dataclass(frozen=True)
class Curves:
    """What :func:`link_edges` returns: the curves as per-pixel maps and as a host sequence of :class:`Curve`.

    Attributes
    ----------
    labels : int32 (H, W)
        The curve index of each curve pixel, :data:`BRANCH` (-2) at branch pixels, -1 off the edges;
        NumPy for NumPy input, a device array for device input.
    position : int32 (H, W)
        Each curve pixel's arc position (0 at its curve's first pixel), -1 elsewhere; like ``labels``.
    tangent : float32 (H, W)
        Each curve pixel's tangent direction in radians (atan2(dy, dx), pointing along increasing arc
        position), from the positions smoothed along the arc; NaN at single-pixel curves (no direction)
        and elsewhere; like ``labels``.
    points : int32 (N, 2)
        Every curve pixel (x, y), curve after curve, each in arc order; curve i holds
        ``points[offsets[i]:offsets[i + 1]]``.
    offsets : int64 (C + 1,)
    closed, length, mean_curvature, total_curvature, magnitude : arrays (C,)
        Per curve, as :class:`Curve` describes.
    tangents : float64 (C, 2, 2)
        Out-pointing unit tangents at each curve's first and last pixel.
    branches : int32 (B, 2)
        The branch pixels (x, y), in raster order.

    Curves are numbered closed curves first, then open ones, each in the raster order of its principal
    (for an open curve, the end it starts at: of its two ends, the one later in raster order).
    """

    labels: ArrayLike
    position: ArrayLike
    tangent: ArrayLike
    points: np.ndarray
    offsets: np.ndarray
    closed: np.ndarray
    length: np.ndarray
    mean_curvature: np.ndarray
    total_curvature: np.ndarray
    magnitude: np.ndarray
    tangents: np.ndarray
    branches: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def __getitem__(self, i: int) -> Curve:
        if not -len(self) <= i < len(self):
            raise IndexError(f"curve {i} out of range for {len(self)} curves")
        i %= len(self)
        return Curve(self.points[self.offsets[i]:self.offsets[i + 1]], bool(self.closed[i]), float(self.length[i]),
                     float(self.mean_curvature[i]), float(self.total_curvature[i]), float(self.magnitude[i]),
                     self.tangents[i])

    def __iter__(self) -> Iterator[Curve]:
        return (self[i] for i in range(len(self)))

    @property
    def sizes(self) -> np.ndarray:
        """The number of pixels of each curve."""
        return np.diff(self.offsets)

    def curve_of_points(self) -> np.ndarray:
        """The curve index of each row of :attr:`points`."""
        return np.repeat(np.arange(len(self)), self.sizes)


def link_edges(edges: ArrayLike, *, magnitude: ArrayLike | None = None, smoothing: float = 2.0,
               machine: Machine | None = None) -> Curves:
    """Link the pixels of an edge map into curves, split at branch pixels.

    Parameters
    ----------
    edges : (H, W) bool or uint8 array (non-zero is an edge), NumPy or device
        E.g. :func:`vmcl.early.edges.canny`'s output.
    magnitude : (H, W) float32 array, optional
        The gradient magnitude the edges came from (``canny(..., return_gradient=True)``): each curve's
        mean is its strength. Finite and >= 0 (NaN, infinities and negative values are refused, on the
        host and on the device).
    smoothing : float
        Width (Gaussian sigma, in pixels along the arc) of the smoothing of the positions before the
        tangent and curvature are measured, in [0, 32]; 0 takes the pixels as they are.
    machine : vmcl.Machine, optional

    Returns
    -------
    Curves
        Maps (NumPy or device, as ``edges`` came) and per-curve arrays on the host.

    Examples
    --------
    >>> import numpy as np
    >>> ring = np.zeros((16, 16), bool); ring[4, 4:12] = ring[11, 4:12] = ring[4:12, 4] = ring[4:12, 11] = True
    >>> found = link_edges(ring)
    >>> len(found), bool(found.closed[0]), int(found.sizes[0])
    (1, True, 28)
    """
    machine = machine_for(machine)
    if isinstance(edges, np.ndarray) and edges.dtype == np.bool_:
        edges = edges.view(np.uint8)
    mask, host = field(edges, "edges", machine, ndims=(2,), dtypes=(np.uint8,))
    smoothing = check_real(smoothing, "smoothing", minimum=0, maximum=WIDEST)
    strength = None
    if magnitude is not None:
        strength, _ = field(magnitude, "magnitude", machine, ndims=(2,), dtypes=(np.float32,))
        if strength.shape != mask.shape:
            raise InputValueError(f"magnitude has shape {strength.shape}, edges {mask.shape}: they must match")
        # A NaN would make its curve's strength NaN, which local_saliency reads as "no magnitude" (1).
        check_weights(strength if isinstance(magnitude, cl_array.Array) else magnitude, "magnitude", machine)
    found = _link_on_device(machine, mask, strength, smoothing, draw_maps=not host)
    shape = (int(mask.shape[0]), int(mask.shape[1]))
    curves = _measure(found, shape)
    maps = _host_maps(found, curves.sizes, shape) if found.maps is None else found.maps
    _without_direction(maps[2], found.pixel[found.size == 1], machine)
    return dataclasses.replace(curves, labels=maps[0], position=maps[1], tangent=maps[2])


def _without_direction(tangent: ArrayLike, pixels: np.ndarray, machine: Machine) -> None:
    """NaN written into the tangent map (host or device) at ``pixels`` (flat addresses): the pixels of
    single-pixel curves. Their arc gives the tangent kernel a zero vector, whose angle comes out 0 (east),
    but a single pixel has no direction, and structural_saliency reads NaN as unknown, 0 as horizontal."""
    if not len(pixels):
        return
    flat = tangent.reshape(-1)
    if isinstance(flat, cl_array.Array):
        flat.setitem(machine.to_device(pixels.astype(np.int32)), machine.full(len(pixels), np.float32, np.nan),
                     queue=machine.queue)
    else:
        flat[pixels] = np.nan


class _Linked(NamedTuple):
    """The device's answer, every curve pixel in arc order (curve after curve, in the order of their
    keys): its flat address and (column, row), its curve's size, arc position, loop flag and gradient
    magnitude (NaN without one); the branch pixels' flat addresses; the labels, position and tangent
    maps on the device, where they were drawn; and the read of the fields written last (see
    :meth:`arc_fields`)."""

    pixel: np.ndarray
    points: np.ndarray
    size: np.ndarray
    position: np.ndarray
    closed: np.ndarray
    magnitude: np.ndarray
    branches: np.ndarray
    maps: tuple[cl_array.Array, cl_array.Array, cl_array.Array] | None
    late: tuple[np.ndarray, cl.Event | None]

    def arc_fields(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tangent's turn to the next pixel, the step's length and the tangent's direction, once
        their read is done (float32 (N,) each)."""
        values, reading = self.late
        if reading is not None:
            reading.wait()
        return values[0], values[1], values[2]


def _link_on_device(machine: Machine, mask: cl_array.Array, strength: cl_array.Array | None,
                    smoothing: float, *, draw_maps: bool) -> _Linked:
    """The curves' fields in arc order, read back, and with ``draw_maps`` the labels, position and tangent
    maps drawn on the device as the curves are put in order (cleared by the first pass)."""
    height, width = mask.shape
    n = mask.size
    size = (-(-width // RUN), height)  # work-items of RUN pixels along each row
    sizes = (np.int32(width), np.int32(height))
    # Uploaded once per machine and smoothing: the launches are most of the curves' host time already.
    weights = machine.constant(("vmcl.group.curves", "tangent weights", smoothing), lambda: _tangent_weights(smoothing))
    curve_links, branch_list = machine.empty(mask.shape, np.uint8), machine.empty(n, np.int32)
    runs = size[0] * size[1]
    run_bits = machine.empty(runs, np.uint16)
    run_count, run_offset = machine.empty(runs, np.int32), machine.empty(runs, np.int32)
    counts = machine.full(2, np.int32, 0)  # curve pixels, branch pixels
    if draw_maps:
        maps = (machine.empty(mask.shape, np.int32), machine.empty(mask.shape, np.int32),
                machine.empty(mask.shape, np.float32))
    # Without maps the kernels write none, and any buffer stands in for them.
    drawn = maps if draw_maps else (run_count, run_count, run_count)
    draw = np.int32(draw_maps)
    machine.launch(machine.kernel("curves", "split_branches"), size, mask, curve_links, run_bits, run_count,
                   branch_list, counts, *drawn, draw, *sizes)
    # Curve pixels are numbered in raster order: by their runs' offsets, then within each run.
    exclusive_sum_into(machine, run_count, run_offset)
    machine.launch(machine.kernel("curves", "count_curve_pixels"), (1,), run_offset, run_count, counts,
                   np.int64(runs))
    count, branch_count = (int(c) for c in counts.get())
    # Read back with the curves' fields below: the read waits on nothing of its own.
    listed = np.empty(branch_count, np.int32)
    listed_event = machine.read_into(listed, branch_list)
    if count == 0:
        if listed_event is not None:
            listed_event.wait()
        empty = np.zeros(0, np.int32)
        nothing = np.zeros(0, np.float32)
        return _Linked(empty, np.zeros((0, 2), np.int32), empty, empty, np.zeros(0, bool), nothing,
                       np.sort(listed), maps if draw_maps else None, (np.zeros((3, 0), np.float32), None))
    if _FIELDS * count >= 2**31:  # the packed fields' addresses are int32
        raise InputValueError(f"edges holds {count} curve pixels; at most {(2**31 - 1) // _FIELDS} can be linked")
    prev_node, key = machine.empty(2 * count, np.int32), machine.empty(2 * count, np.int32)
    pixel = machine.empty(count, np.int32)
    # (size, 1) pairs per key: their exclusive sums are each curve's first slot and its number.
    size_of_key, offset_of_key = machine.empty(4 * count, np.int32), machine.empty(4 * count, np.int32)
    machine.launch(machine.kernel("curves", "tour"), size, curve_links, run_bits, run_offset, prev_node, key, pixel,
                   size_of_key, *sizes, np.int32(count))
    top, distance = doubling.principal_from_predecessors(prev_node, keys=key, check=False, machine=machine)
    curve_key, position, closed = (machine.empty(count, np.int32) for _ in range(3))
    machine.launch(machine.kernel("curves", "arc_positions"), (count,), top, distance, curve_key, position, closed,
                   size_of_key, np.int32(count))
    # Curves are put in the order of their keys (see Curves) by the offsets of their sizes, summed over the
    # key range, so the host reads them in arc order and sorts nothing.
    exclusive_sum_into(machine, size_of_key, offset_of_key, pairs=True)
    packed = machine.empty(_FIELDS * count, np.int32)
    machine.launch(machine.kernel("curves", "arrange"), (count,), curve_key, position, closed, pixel,
                   mask if strength is None else strength, np.int32(strength is not None), size_of_key,
                   offset_of_key, packed, drawn[0], drawn[1], draw, np.int32(width), np.int32(count))
    # The fields arrange wrote are read while the tangents are found: the host measures the curves
    # meanwhile, and waits only for the last three fields.
    early = np.empty(_EARLY_FIELDS * count, np.int32)
    early_read = machine.read_into(early, packed)
    machine.launch(machine.kernel("curves", "arc_tangents"), (count,), packed, weights, np.int32(weights.size),
                   drawn[2], draw, np.int32(count))
    machine.launch(machine.kernel("curves", "arc_turns"), (count,), packed, np.int32(count))
    late = np.empty((_FIELDS - _EARLY_FIELDS, count), np.float32)
    late_read = machine.read_into(late, packed, offset=_EARLY_FIELDS * count)
    if early_read is not None:
        early_read.wait()  # and with it the branch list's read, queued before it
    fields = early[:5 * count].reshape(5, count)
    return _Linked(fields[0], early[5 * count:].reshape(count, 2), fields[1], fields[2], fields[3].astype(bool),
                   fields[4].view(np.float32), np.sort(listed), maps if draw_maps else None,
                   (late, late_read))


def _tangent_weights(smoothing: float) -> np.ndarray:
    """The derivative of a Gaussian of width ``smoothing`` at 1, 2, ... 3 sigma along the arc (its
    positive half; the kernel negates it behind); 0: the central difference."""
    if smoothing == 0:
        return np.ones(1, np.float32)
    t = np.arange(1, math.ceil(3 * smoothing) + 1)
    return (t * np.exp(-0.5 * (t / smoothing) ** 2)).astype(np.float32)


def _measure(found: _Linked, shape: tuple[int, int]) -> Curves:
    """The curves and their measures (maps left empty): what needs no tangent first, while the device
    finds them, then the rest."""
    width = shape[1]
    starts = np.flatnonzero(found.position == 0)
    sizes = found.size[starts].astype(np.int64)
    offsets = np.append(starts, found.pixel.size).astype(np.int64)
    closed = found.closed[starts]
    branch_points = np.stack([found.branches % width, found.branches // width], axis=1).astype(np.int32)
    end_tangents = _end_tangents(found.points, offsets, closed)
    magnitude = np.add.reduceat(found.magnitude, starts, dtype=np.float64) / sizes if len(starts) else np.zeros(0)
    turn, step, _ = found.arc_fields()
    if len(starts):
        # Summed in float64 as they are read (no converted copies): the host's share of the time counts.
        length, total = (np.add.reduceat(values, starts, dtype=np.float64) for values in (step, turn))
    else:
        length = total = np.zeros(0)
    mean = np.divide(total, length, out=np.zeros(len(starts)), where=length > 0)
    nothing = np.zeros(0)
    return Curves(nothing, nothing, nothing, found.points, offsets, closed, length, mean, total, magnitude,
                  end_tangents, branch_points)


def _host_maps(found: _Linked, sizes: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The labels, position and tangent maps, on the host (``sizes``: the curves' numbers of pixels)."""
    size = shape[0] * shape[1]
    ids = np.repeat(np.arange(len(sizes), dtype=np.int32), sizes)
    labels, position = np.full(size, -1, np.int32), np.full(size, -1, np.int32)
    tangent = np.full(size, np.nan, np.float32)
    labels[found.pixel] = ids
    labels[found.branches] = BRANCH
    position[found.pixel] = found.position
    tangent[found.pixel] = found.arc_fields()[2]
    return labels.reshape(shape), position.reshape(shape), tangent.reshape(shape)


def _end_tangents(points: np.ndarray, offsets: np.ndarray, closed: np.ndarray) -> np.ndarray:
    """Unit tangents pointing out of each curve at its first and last pixel, along the chord to the pixel
    a few steps in (NaN for loops and single pixels)."""
    first, last = offsets[:-1], offsets[1:] - 1
    span = np.minimum(_TANGENT_SPAN, last - first)
    # One gather of the four pixels per curve: each NumPy call costs more than its few hundred rows.
    ends = points[np.concatenate([first, first + span, last, last - span])].reshape(4, -1, 2)
    chords = (ends[0::2] - ends[1::2]).transpose(1, 0, 2)
    norm = np.hypot(chords[..., :1], chords[..., 1:])
    norm[norm == 0] = np.nan  # a single pixel has no chord: NaN, as a loop
    tangents = chords / norm
    tangents[closed] = np.nan
    return tangents
