"""Memory-based registration of the stereo pair: warp tables learnt from a dot pattern.

Seed section "Stereo" (Memory-based registration and calibration): the system is shown "a pattern of
dots, roughly on a sparse grid, at the distance around which stereo has to operate"; matching the dots
of the two images gives a warping vector per dot, bilinear interpolation gives it everywhere else, and
the table mapping the right image onto the left is stored. Prior to matching, the right image is warped
by the stored addresses. Tables are kept per vergence angle, and a table for an angle between stored
ones is interpolated ("the system can generalize by interpolating between warping tables").

The dots are found with the Connection Machine primitives: a threshold, connected components by
distance doubling (:func:`vmcl.cm.doubling.label`) and weighted centroids summed by the router
(:func:`vmcl.cm.router.send`). Matching the few dots and interpolating their vectors run on the host
(SciPy's k-d tree and Delaunay-based linear interpolation); the warp itself is a kernel.
"""

from __future__ import annotations

import bisect
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, overload

import numpy as np
import pyopencl.array as cl_array
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator
from scipy.spatial import QhullError, cKDTree

from vmcl.cm import doubling, reduce, router
from vmcl.cm.core import (
    ArrayLike,
    check_choice,
    check_int,
    check_real,
    check_real_dtype,
    machine_for,
    real_host_array,
    result,
)
from vmcl.cm.core import field as device_field
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["TableStore", "WarpTable", "find_dots", "match_dots", "warp"]


def _grey(image: np.ndarray, name: str) -> np.ndarray:
    check_real_dtype(image, name)
    if image.ndim != 2 or image.size == 0:
        raise InputValueError(f"{name} must be a non-empty grey image (H, W), got shape {image.shape}")
    with np.errstate(over="ignore"):
        grey = image.astype(np.float32)
    if not np.all(np.isfinite(grey)):
        raise InputValueError(f"{name} must be finite (and within float32's range)")
    return grey


def _dots(dots, name: str) -> np.ndarray:
    """Centroids checked as a finite (k, 2) array of reals (k may be 0)."""
    real_host_array(dots, name, ndims=(2,), empty=True)
    if dots.shape[1] != 2:
        raise InputValueError(f"{name} must be an array of (x, y) centroids of shape (k, 2), got shape {dots.shape}")
    if not np.isfinite(dots).all():
        raise InputValueError(f"{name} must hold finite centroids")
    return dots


def _otsu(grey: np.ndarray, machine: Machine) -> float:
    """Otsu's threshold from a 256-bin histogram of the image (computed on the device)."""
    lo, hi = float(grey.min()), float(grey.max())
    if hi <= lo:
        raise InputValueError("image is constant: there are no dots to find")
    counts = reduce.histogram(grey, 256, (lo, hi), machine=machine).astype(np.float64)
    centres = lo + (np.arange(256) + 0.5) * (hi - lo) / 256
    weight = np.cumsum(counts)
    mean = np.cumsum(counts * centres)
    total, grand = weight[-1], mean[-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        between = (grand * weight - mean * total) ** 2 / (weight * (total - weight))
    return float(centres[np.nanargmax(between[:-1])] + 0.5 * (hi - lo) / 256)


def find_dots(image: np.ndarray, *, polarity: Literal["dark", "bright"] = "dark", threshold: float | None = None,
              min_area: int = 4, machine: Machine | None = None) -> np.ndarray:
    """Centroids of the dots of a calibration pattern.

    Parameters
    ----------
    image : ndarray (H, W)
        Grey image of the dot pattern.
    polarity : {"dark", "bright"}
        Dots darker or brighter than the background.
    threshold : float, optional
        Grey level separating dots from background; default Otsu's threshold.
    min_area : int
        Blobs of fewer pixels are noise and dropped.

    Returns
    -------
    float64 array (k, 2) of (x, y) centroids, weighted by each pixel's contrast to the threshold, in
    the order of the blobs' largest addresses (row-major).
    """
    machine = machine_for(machine)
    grey = _grey(image, "image")
    polarity = check_choice(polarity, "polarity", ("dark", "bright"))
    min_area = check_int(min_area, "min_area", minimum=0)
    if threshold is None:
        threshold = _otsu(grey, machine)
    else:
        threshold = check_real(threshold, "threshold")
    contrast = (threshold - grey) if polarity == "dark" else (grey - threshold)
    mask = contrast > 0
    labels = doubling.label(mask, connectivity=8, relabel=True, machine=machine)
    count = int(labels.max())
    if count == 0:
        return np.zeros((0, 2))
    weight = np.where(mask, contrast, 0).astype(np.float32)
    ys, xs = np.indices(grey.shape, dtype=np.float32)
    sums = [router.send(values, labels, size=count + 1, combine="sum", machine=machine)
            for values in (weight * xs, weight * ys, weight)]
    area = router.send(mask.view(np.uint8), labels, size=count + 1, combine="sum", machine=machine)
    keep = area[1:].astype(np.int64) >= min_area
    total = sums[2][1:].astype(np.float64)
    centroids = np.stack([sums[0][1:] / total, sums[1][1:] / total], axis=1)
    return centroids[keep]


def match_dots(left: np.ndarray, right: np.ndarray, *, max_shift: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of dots that are each other's nearest neighbour within ``max_shift`` pixels.

    The pattern must be sparse enough that matching is unambiguous (dot spacing above 2 * max_shift),
    as the paper requires. Returns the matched left and right centroids, (m, 2) each, in left order.
    """
    left, right = _dots(left, "left"), _dots(right, "right")
    # An infinite shift is a query without a distance bound.
    if not (isinstance(max_shift, (float, np.floating)) and max_shift == np.inf):
        max_shift = check_real(max_shift, "max_shift", above=0)
    if len(left) == 0 or len(right) == 0:
        return np.zeros((0, 2)), np.zeros((0, 2))
    distance, nearest = cKDTree(right).query(left, distance_upper_bound=max_shift)
    _, back = cKDTree(left).query(right, distance_upper_bound=max_shift)
    found = np.isfinite(distance)
    mutual = found & (back[np.minimum(nearest, len(right) - 1)] == np.arange(len(left)))
    return left[mutual], right[nearest[mutual]]


@dataclass
class WarpTable:
    """Where to read the right image for every pixel of the left view, learnt at one vergence angle.

    ``source[y, x] = (x', y')``: the registered right image at (x, y) is the right image sampled at
    (x', y'). Inside the convex hull of the matched dots the warping vectors are interpolated linearly
    (over their Delaunay triangulation); outside it, the nearest dot's vector is used.
    """

    source: np.ndarray
    vergence: float = 0.0
    dots: int = 0

    @classmethod
    def from_dots(cls, left: np.ndarray, right: np.ndarray, shape: tuple[int, int], *,
                  vergence: float = 0.0) -> WarpTable:
        """The table from matched dot centroids (see :func:`match_dots`) for images of ``shape``."""
        left, right = _dots(left, "left"), _dots(right, "right")
        if left.shape != right.shape:
            raise InputValueError(f"left and right must hold the same number of matched dots, got {len(left)} "
                                  f"and {len(right)}")
        if len(left) < 3:
            raise InputValueError(f"need at least 3 matched dots to interpolate a warp table, got {len(left)}")
        if not isinstance(shape, (tuple, list)) or len(shape) != 2:
            raise InputTypeError(f"shape must be a tuple (H, W), got {shape!r}")
        height, width = (check_int(n, "shape", minimum=1) for n in shape)
        shape = (height, width)
        vergence = check_real(vergence, "vergence")
        vectors = right - left
        try:
            ys, xs = np.indices(shape, dtype=np.float64)
            points = np.stack([xs.ravel(), ys.ravel()], axis=1)
            linear = LinearNDInterpolator(left, vectors)(points)
        except (MemoryError, ValueError) as error:  # NumPy's "array is too big" is a ValueError
            raise InputValueError(f"shape {shape}: a warp table that large needs more host memory than there "
                                  f"is ({error})") from error
        except QhullError as error:
            raise InputValueError(f"the matched dots do not span an area (all on one line?): {error}") from error
        outside = ~np.isfinite(linear[:, 0])
        linear[outside] = NearestNDInterpolator(left, vectors)(points[outside])
        source = (points + linear).reshape(*shape, 2).astype(np.float32)
        return cls(source=source, vergence=vergence, dots=len(left))

    @classmethod
    def calibrate(cls, left_image: np.ndarray, right_image: np.ndarray, *, max_shift: float,
                  vergence: float = 0.0, polarity: Literal["dark", "bright"] = "dark",
                  machine: Machine | None = None) -> WarpTable:
        """Find, match and interpolate the dots of a calibration pair in one call."""
        _grey(left_image, "left_image")
        _grey(right_image, "right_image")
        if left_image.shape != right_image.shape:
            raise InputValueError(f"left_image and right_image differ in shape: {left_image.shape} and "
                                  f"{right_image.shape}")
        left = find_dots(left_image, polarity=polarity, machine=machine)
        right = find_dots(right_image, polarity=polarity, machine=machine)
        matched_left, matched_right = match_dots(left, right, max_shift=max_shift)
        return cls.from_dots(matched_left, matched_right, left_image.shape, vergence=vergence)


@dataclass
class TableStore:
    """Warp tables for a few vergence angles; tables for angles between them are interpolated."""

    tables: list[WarpTable] = field(default_factory=list)

    def __post_init__(self) -> None:
        # The tables given pass add's checks and order, as load's do: table_for bisects them by vergence.
        if isinstance(self.tables, (str, bytes)) or not isinstance(self.tables, (list, tuple)):
            raise InputTypeError(f"tables must be a list of WarpTable, got {type(self.tables).__name__}")
        given, self.tables = list(self.tables), []
        for table in given:
            self.add(table)

    def add(self, table: WarpTable) -> None:
        """Store ``table``, in order of vergence (which :meth:`table_for` bisects): its source must be an
        (H, W, 2) array of reals, of the stored tables' shape, and its vergence a finite number not stored
        yet."""
        if not isinstance(table, WarpTable):
            raise InputTypeError(f"table must be a WarpTable, got {type(table).__name__}")
        source = check_real_dtype(table.source, "table.source")
        if source.ndim != 3 or source.shape[2] != 2 or 0 in source.shape:
            raise InputValueError(f"table.source must be the (x, y) source positions of shape (H, W, 2), got shape "
                                  f"{source.shape}")
        check_real(table.vergence, "table.vergence")
        if self.tables and table.source.shape != self.tables[0].source.shape:
            raise InputValueError(f"table shape {table.source.shape} differs from the store's "
                             f"{self.tables[0].source.shape}")
        if any(t.vergence == table.vergence for t in self.tables):
            raise InputValueError(f"a table for vergence {table.vergence} is already stored")
        bisect.insort(self.tables, table, key=lambda t: t.vergence)

    def table_for(self, vergence: float) -> WarpTable:
        """The stored table for this angle, or the linear interpolation of the two around it."""
        vergence = check_real(vergence, "vergence")
        if not self.tables:
            raise InputValueError("the store holds no tables")
        angles = [t.vergence for t in self.tables]
        if not angles[0] <= vergence <= angles[-1]:
            raise InputValueError(f"vergence {vergence} lies outside the stored range [{angles[0]}, {angles[-1]}]; "
                             "tables are interpolated, never extrapolated")
        upper = bisect.bisect_left(angles, vergence)
        if angles[upper] == vergence:
            return self.tables[upper]
        below, above = self.tables[upper - 1], self.tables[upper]
        t = (vergence - below.vergence) / (above.vergence - below.vergence)
        source = ((1 - t) * below.source + t * above.source).astype(np.float32)
        return WarpTable(source=source, vergence=float(vergence), dots=0)

    def save(self, path: str | Path) -> None:
        """Write the store to the file ``path`` itself (an .npz archive, whatever the name's suffix: NumPy
        would add ".npz" to a name without it), which :meth:`load` reads back from the same ``path``."""
        if not isinstance(path, (str, Path)):
            raise InputTypeError(f"path must be a str or a pathlib.Path, got {type(path).__name__}")
        if not self.tables:
            raise InputValueError("the store holds no tables to save")
        with open(path, "wb") as file:  # a file object: NumPy writes it under no other name
            np.savez_compressed(file, vergence=np.array([t.vergence for t in self.tables]),
                                dots=np.array([t.dots for t in self.tables]),
                                source=np.stack([t.source for t in self.tables]))

    @classmethod
    def load(cls, path: str | Path) -> TableStore:
        """The store :meth:`save` wrote to the file ``path`` (the same path, no suffix added), its tables
        checked and ordered as :meth:`add` checks and orders them."""
        if not isinstance(path, (str, Path)):
            raise InputTypeError(f"path must be a str or a pathlib.Path, got {type(path).__name__}")
        try:
            with np.load(path, allow_pickle=False) as data:
                tables = [WarpTable(source=s, vergence=float(v), dots=int(d))
                          for s, v, d in zip(data["source"], data["vergence"], data["dots"], strict=True)]
        except (ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as error:
            raise InputValueError(f"path {str(path)!r} is not a table store saved by TableStore.save: "
                                  f"{error}") from error
        store = cls()
        for table in tables:
            try:
                store.add(table)
            except InputError as error:
                raise InputValueError(f"path {str(path)!r} holds a table the store refuses: {error}") from error
        return store


@overload
def warp(image: np.ndarray, table: WarpTable | ArrayLike, *,
         machine: Machine | None = None) -> np.ndarray: ...
@overload
def warp(image: cl_array.Array, table: WarpTable | ArrayLike, *,
         machine: Machine | None = None) -> cl_array.Array: ...
def warp(image: ArrayLike, table: WarpTable | ArrayLike, *, machine: Machine | None = None) -> ArrayLike:
    """Warp ``image`` by a table: ``out[y, x] = image`` sampled bilinearly at ``table[y, x]``.

    Parameters
    ----------
    image : (H, W) or (H, W, C) array or device array, float32 (other real dtypes are converted; values
        beyond float32's range are refused)
    table : WarpTable, or its (H, W, 2) float32 source positions
        The table's (H, W) must equal the image's.

    Returns
    -------
    float32 of the image's shape; NaN where the table points outside the image.
    """
    machine = machine_for(machine)
    source = table.source if isinstance(table, WarpTable) else table
    if isinstance(image, np.ndarray) and image.dtype != np.float32:
        if not np.issubdtype(image.dtype, np.number) or np.iscomplexobj(image):
            raise InputTypeError(f"image must be real-valued, got {image.dtype}")
        with np.errstate(over="ignore"):  # refused just below
            converted = image.astype(np.float32)
        # NaN and infinities carry over as they are (a float32 image may hold them too); a finite value
        # beyond float32's range would become an infinity the image never held.
        if (np.isinf(converted) & np.isfinite(image)).any():
            raise InputValueError("image has values beyond float32's range, in which the warp computes")
        image = converted
    data, host = device_field(image, "image", machine, ndims=(2, 3), dtypes=(np.float32,))
    positions, _ = device_field(source, "table", machine, ndims=(3,), dtypes=(np.float32,))
    height, width = data.shape[:2]
    if positions.shape != (height, width, 2):
        raise InputValueError(f"table must have shape {(height, width, 2)} for this image, got {positions.shape}")
    channels = data.shape[2] if data.ndim == 3 else 1
    out = machine.empty(data.shape, np.float32)
    machine.launch(machine.kernel("registration", "warp_bilinear"), (width, height), data, positions, out,
                   np.int64(width), np.int64(height), np.int64(channels))
    return result(out, host)
