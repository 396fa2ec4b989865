"""Models learned from example images, and the library folder they are kept in.

Seed section "Learning in a three-stage recognition scheme": models are learned from examples. A model is
its boundary features in its own frame, as seen in each example: a 2-D object has one view, a 3-D object
a few views around it (recognised at viewpoints between them by aligning the nearest, section
"Recognition"'s alignment, after Ullman and Basri). :func:`learn` builds a model from images of the
object alone (or with a mask saying which pixels are the object's); a :class:`Library` is a folder of
model files (``NAME.vmodel.npz``) any user can add to with ``vmcl learn``.

A model is the object as its examples show it, not its mirror image: recognition searches rotations,
scalings and shifts of its views, so a mirrored object (a print seen from behind, a left-handed part for
a right-handed one's model) is not one of its poses, and may be matched as a rotation of it (box.png
mirrored as box.png turned 180 degrees, its print matching less). Learn the mirror image as a model of its
own where the two must be told apart.
"""

from __future__ import annotations

import json
import math
import re
import zipfile
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from vmcl.cm.core import check_bool, check_int, machine_for
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.output_folder import replace_file
from vmcl.recognize.arguments import angles, object_mask
from vmcl.recognize.arguments import points as point_array
from vmcl.recognize.features import Features, features_of

__all__ = ["MODEL_SUFFIX", "Library", "Model", "View", "learn", "load_model", "model_path", "save_model", "view_of"]

MODEL_SUFFIX = ".vmodel.npz"
"""The suffix of a model file in a library folder."""

_FORMAT = "vmcl-model"
_VERSION = 3  # 2: views keep their arcs; 3: which points are the outline's. Older files: no arcs (1), all outline
_OUTLINE_REACH = 3.0  # px: a boundary point this near the object's outer border is the outline's
_NAME = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9 _.+-]{0,62}[A-Za-z0-9_.+-])?")  # no space at the end: a name
# "box " would list as "box"
_MAX_POINTS = 1500  # boundary points kept per view: enough to verify a pose, few enough to test many
_LEAST_POINTS = 8  # boundary pixels an example needs to be learned from
_TURN = 2 * math.pi  # radians: a view's directions (atan2's within pi of 0, a float32 tangent's a rounding past
# it) lie within a turn of 0; one beyond is damage, and far beyond its cosine is noise
_FARTHEST = 1e9  # px: no length in a view exceeds the coordinates recognition takes (arguments.points')
_SLACK = 1e-6  # px: a centroid's rounding beyond its points' box
_RADIUS_SLACK = 2.0  # a radius this far off its boundary's spread is not the view's (a damaged file)


@dataclass(frozen=True, eq=False)
class View:
    """One view of a model: its features in the frame of the image it was learned from.

    Attributes
    ----------
    corners : float64 (F, 2)
    bisector, opening : float64 (F,)
        As :class:`vmcl.recognize.features.Features` holds them (the bisector in radians within
        [-2 pi, 2 pi], the opening within [0, pi]).
    points : float64 (N, 2)
        The boundary, thinned to one point per ``spacing`` x ``spacing`` cell; N >= 1. Coordinates (these,
        the corners' and the arcs') lie within 1e9 pixels, as :func:`vmcl.recognize.recognize` takes them.
    tangent : float64 (N,)
        The boundary's tangent at each point (radians modulo pi, within [-2 pi, 2 pi]; NaN where unknown).
        Verification counts an edge in any direction as supporting a point of unknown tangent, so at
        least one must be known: with none, a pose would be tested by position alone.
    centre : float64 (2,)
        The boundary's centroid (within its points' box).
    radius : float
        The boundary's rms distance from its centroid, at least 1 (the scale the pose search measures in;
        within a factor of 2 of it).
    shape : (int, int)
        The example image's (H, W).
    length : float
        The boundary's length in pixels (its edge pixels, before thinning).
    arcs : float64 (A, 2)
    arc_radius : float64 (A,)
        Its arcs' circles (:func:`vmcl.recognize.features.arcs_of`): centres and radii.
    outline : bool (N,)
        Which boundary points lie on the object's outline (its outer border in the example); the others
        are its inner markings: a solid's edges between its faces, a flat object's print. A view learned
        without a closed outline holds every point as the outline's.
    """

    corners: np.ndarray
    bisector: np.ndarray
    opening: np.ndarray
    points: np.ndarray
    tangent: np.ndarray
    centre: np.ndarray
    radius: float
    shape: tuple[int, int]
    length: float
    arcs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    arc_radius: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outline: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    def __post_init__(self) -> None:
        # Checked whole, with the ranges recognition's own checks apply: a view read from a damaged file, or
        # made by hand, failed later in recognise naming an argument the user never gave, or (a NaN radius,
        # tangents all unknown) matched at a wrong pose.
        corners = point_array(np.asarray(self.corners), "a view's corners")
        angles(np.asarray(self.bisector), "a view's bisector", len(corners), "its corners", low=-_TURN, high=_TURN)
        angles(np.asarray(self.opening), "a view's opening", len(corners), "its corners", low=0.0, high=math.pi)
        boundary = point_array(np.asarray(self.points), "a view's points")
        if not len(boundary):
            raise InputValueError("a view must hold at least one boundary point")
        tangent = angles(np.asarray(self.tangent), "a view's tangent", len(boundary), "its points", low=-_TURN,
                         high=_TURN, unknown=True)
        if np.isnan(tangent).all():
            # Verification counts a point of unknown tangent as supported by an edge in any direction: with
            # none known, a pose is tested by position alone, and clutter fits one.
            raise InputValueError("a view's tangent must be known (not NaN) at one boundary point at least")
        arcs = point_array(np.asarray(self.arcs), "a view's arcs")
        # (a radius, not an angle; checked for its shape and range as recognition's indexing checks it)
        arc_radius = angles(np.asarray(self.arc_radius), "a view's arc_radius", len(arcs), "its arcs",
                            low=0.0, high=_FARTHEST)
        if (arc_radius <= 0).any():
            raise InputValueError("a view's arc_radius must be > 0")
        if np.shape(self.centre) != (2,):
            raise InputValueError(f"a view's centre must be one point (x, y), got shape {np.shape(self.centre)}")
        centre = point_array(np.asarray(self.centre).reshape(1, 2), "a view's centre")[0]
        low, high = boundary.min(axis=0), boundary.max(axis=0)
        if ((centre < low - _SLACK) | (centre > high + _SLACK)).any():
            # The pose search measures in the frame the centre and radius give; one off the boundary (a
            # damaged file) was searched in and found nothing, silently.
            raise InputValueError("a view's centre must be its boundary's centroid, within its points' box "
                                  f"({low[0]:.4g}, {low[1]:.4g}) to ({high[0]:.4g}, {high[1]:.4g}), got "
                                  f"({centre[0]:.4g}, {centre[1]:.4g})")
        if not (isinstance(self.radius, Real) and math.isfinite(self.radius) and self.radius > 0):
            raise InputValueError(f"a view's radius must be a finite number > 0, got {self.radius!r}")
        spread = max(float(np.sqrt(((boundary - centre) ** 2).sum(axis=1).mean())), 1.0)
        if not spread / _RADIUS_SLACK <= self.radius <= spread * _RADIUS_SLACK:
            raise InputValueError(f"a view's radius must be its boundary's rms distance from its centre (at least "
                                  f"1 px), {spread:.4g}, within a factor of {_RADIUS_SLACK:g}, got {self.radius!r}")
        if not (isinstance(self.length, Real) and math.isfinite(self.length) and self.length >= 0):
            raise InputValueError(f"a view's length must be a finite number >= 0, got {self.length!r}")
        if (not isinstance(self.shape, tuple) or len(self.shape) != 2
                or not all(isinstance(n, Integral) and n >= 1 for n in self.shape)):
            raise InputValueError(f"a view's shape must be (H, W), two ints >= 1, got {self.shape!r}")
        if not len(self.outline):  # not given (a file of an older format): every point the outline's
            object.__setattr__(self, "outline", np.ones(len(self.points), bool))
        elif np.asarray(self.outline).dtype != np.bool_:
            raise InputValueError(f"outline must be a bool array, got {np.asarray(self.outline).dtype}")
        elif np.shape(self.outline) != (len(self.points),):
            raise InputValueError(f"outline must hold one bool per boundary point ({len(self.points)}), "
                                  f"got shape {np.shape(self.outline)}")


@dataclass(frozen=True, eq=False)
class Model:
    """A named object: one view (2-D) or several (3-D, in the order they were learned).

    Attributes
    ----------
    name : str
    views : tuple of View
    sources : tuple of str
        Where each view was learned from (file names, or "array").
    """

    name: str
    views: tuple[View, ...]
    sources: tuple[str, ...]

    def __post_init__(self) -> None:
        _check_name(self.name)
        if not isinstance(self.views, tuple) or not self.views or not all(isinstance(v, View) for v in self.views):
            raise InputTypeError("views must be a non-empty tuple of vmcl.recognize.View")
        if (not isinstance(self.sources, tuple) or len(self.sources) != len(self.views)
                or not all(isinstance(x, str) for x in self.sources)):
            raise InputTypeError(f"sources must be a tuple of one str per view ({len(self.views)})")


def _check_name(name: Any) -> str:
    if not isinstance(name, str):
        raise InputTypeError(f"name must be a str, got {type(name).__name__}")
    if not _NAME.fullmatch(name):  # match's $ also matches before a final newline
        raise InputValueError("name must be 1 to 64 ASCII letters (A to Z, a to z), digits, spaces or _ . + - "
                              f"(starting with a letter or digit, not ending with a space), got {name!r}")
    return name


def view_of(features: Features, *, mask: np.ndarray | None = None, spacing: int = 2) -> View:
    """A model view from an example's features.

    Parameters
    ----------
    features : Features
    mask : (H, W) array, optional
        The object's pixels, as :func:`learn` takes a mask (bool, or 0 and 1 or the type's full scale;
        NumPy or device); features outside it (dilated by 2 px) are left out, and its outer border is
        the object's outline. Default: every feature, and the outline is the outer border of the region
        the edges enclose (with no closed outline, every point is the outline's).
    spacing : int
        The boundary is thinned to one point per ``spacing`` x ``spacing`` cell (>= 1), and further (a
        coarser grid) where that leaves more than 1500 points.

    Returns
    -------
    View
    """
    if not isinstance(features, Features):
        raise InputTypeError(f"features must be vmcl.recognize.Features, got {type(features).__name__}")
    spacing = check_int(spacing, "spacing", minimum=1)
    corners, bisector, opening = features.corners, features.bisector, features.opening
    points, tangent = features.points, features.tangent
    arcs, arc_radius = features.arcs, features.arc_radius
    if mask is not None:
        mask = object_mask(mask, "mask")
        if mask.shape != features.shape:
            raise InputValueError(f"mask must have the image's shape {features.shape}, got {mask.shape}")
        grown = _dilate(mask, 2)
        keep_c = grown[corners[:, 1].round().astype(int), corners[:, 0].round().astype(int)] if len(corners) else \
            np.zeros(0, bool)
        corners, bisector, opening = corners[keep_c], bisector[keep_c], opening[keep_c]
        keep_p = grown[points[:, 1].astype(int), points[:, 0].astype(int)]
        points, tangent = points[keep_p], tangent[keep_p]
        middle = features.arc_middle.round().astype(int)
        keep_a = grown[middle[:, 1], middle[:, 0]] if len(arcs) else np.zeros(0, bool)
        arcs, arc_radius = arcs[keep_a], arc_radius[keep_a]
    length = float(len(points))
    if len(points) < _LEAST_POINTS:
        if mask is not None and len(features.points) >= _LEAST_POINTS:  # the mask's doing, not the example's
            raise InputValueError(f"the mask leaves {len(points)} of the example's {len(features.points)} edge "
                                  f"pixels, too few to learn from ({_LEAST_POINTS} at least): it must cover the "
                                  "object, edges included")
        raise InputValueError(f"the example shows too little boundary to learn from ({len(points)} edge pixels)")
    while True:
        cells = np.unique((points // spacing).astype(np.int64) @ np.array([1, 1 << 32]), return_index=True)[1]
        if len(cells) <= _MAX_POINTS:
            break
        spacing += 1
    kept = np.sort(cells)
    points, tangent = points[kept], tangent[kept]
    centre = points.mean(axis=0)
    radius = float(np.sqrt(((points - centre) ** 2).sum(axis=1).mean()))
    outline = _on_outline(points, mask if mask is not None else _enclosed(features.edges))
    return View(corners.copy(), bisector.copy(), opening.copy(), points.copy(), tangent.copy(), centre,
                max(radius, 1.0), features.shape, length, arcs.copy(), arc_radius.copy(), outline)


def _enclosed(edges: np.ndarray) -> np.ndarray:
    """The region the edges' outermost closed curves enclose (the edges themselves where none closes)."""
    grown = cv2.dilate(edges.astype(np.uint8), np.ones((3, 3), np.uint8))  # closes one-pixel gaps
    contours, _ = cv2.findContours(grown, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    region = np.zeros_like(grown)
    cv2.drawContours(region, contours, -1, 1, thickness=cv2.FILLED)
    return region.astype(bool)


def _on_outline(points: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Which points lie within _OUTLINE_REACH px of the region's outer border (its holes' borders are inner)."""
    region = region.astype(np.uint8)
    contours, _ = cv2.findContours(region, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    border = np.ones_like(region)
    cv2.drawContours(border, contours, -1, 0, thickness=1)
    reach = cv2.distanceTransform(border, cv2.DIST_L2, 5)
    h, w = region.shape
    x = np.clip(np.round(points[:, 0]).astype(np.int64), 0, w - 1)
    y = np.clip(np.round(points[:, 1]).astype(np.int64), 0, h - 1)
    return reach[y, x] <= _OUTLINE_REACH


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    out = mask.copy()
    h, w = mask.shape
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            src = mask[max(0, -dy):h - max(0, dy), max(0, -dx):w - max(0, dx)]
            out[max(0, dy):h - max(0, -dy), max(0, dx):w - max(0, -dx)] |= src
    return out


def learn(name: str, images: Sequence[Any], *, masks: Sequence[Any] | None = None, sigma: float = 1.5,
          corner: float = 45.0, sources: Sequence[str] | None = None, machine: Machine | None = None) -> Model:
    """A model from example images: one view per image.

    Parameters
    ----------
    name : str
        1 to 64 ASCII letters, digits, spaces or ``_ . + -``.
    images : sequence of (H, W) or (H, W, 3) arrays, NumPy or device
        The examples: one image of a 2-D object, or views around a 3-D object (at most a few degrees
        apart for the views between them to be recognised; 20 degrees apart is tested). Each shows the
        object alone, or with ``masks``. A 2-D bool array is an edge map (a line drawing), as
        :func:`vmcl.recognize.recognize` takes one (:func:`vmcl.recognize.features_of`).
    masks : sequence of (H, W) arrays, optional
        The object's pixels in each image, NumPy or device: bool, or numbers holding 0 off the object and one
        other value on it, 1 or the type's full scale (uint8 0 and 1 or 0 and 255, uint16 0 and 1 or 0 and
        65535, float 0 and 1), as ``vmcl learn --mask`` reads a mask image; any other value (a grey edge) is
        refused, not thresholded, and so is a mask of 0 alone.
    sigma, corner : float
        Canny's smoothing and the corner turn, as :func:`vmcl.recognize.image_features` takes them.
    sources : sequence of str, optional
        Where each image came from, kept in the model.
    machine : vmcl.Machine, optional

    Returns
    -------
    Model
    """
    name = _check_name(name)
    machine = machine_for(machine)
    if isinstance(images, (np.ndarray, str)) or not isinstance(images, Sequence) or not images:
        raise InputTypeError("images must be a non-empty sequence (a list) of images")
    if masks is not None and (isinstance(masks, (np.ndarray, str)) or not isinstance(masks, Sequence)
                              or len(masks) != len(images)):
        raise InputValueError(f"masks must be a list of one mask per image ({len(images)})")
    if sources is not None and (isinstance(sources, str) or not isinstance(sources, Sequence)
                                or len(sources) != len(images) or not all(isinstance(x, str) for x in sources)):
        raise InputValueError(f"sources must be a list of one str per image ({len(images)})")
    if masks is not None:  # named as masks, not as their images
        masks = [object_mask(mask, f"masks[{i}]") for i, mask in enumerate(masks)]
    views = []
    for i, image in enumerate(images):
        which = f"images[{i}]" + (f" ({sources[i]})" if sources is not None else "")
        try:
            features = features_of(image, sigma=sigma, corner=corner, machine=machine)
            if len(features.points) < _LEAST_POINTS and not (isinstance(image, np.ndarray) and image.dtype == np.bool_):
                # A picture's Canny thresholds come from its noise, estimated from its median gradient: a
                # textured picture raises them over its edges (a 160 x 120 crop of fur kept 11 pixels); a
                # blank, faint or tiny one has no edges to find.
                raise InputValueError(
                    f"the example shows too little boundary to learn from ({len(features.points)} edge pixels at "
                    "the Canny thresholds its noise estimate gives): a blank, faint or tiny picture shows too few "
                    "edges, and texture raises the thresholds over an object's; give its edge map instead (a bool "
                    "array, e.g. vmcl.early.canny(image, low_threshold=..., high_threshold=...)), or a picture that "
                    "shows the object")
            view = view_of(features, mask=None if masks is None else masks[i])
            if len(view.corners) + len(view.arcs) < 2:
                # Indexing looks pairs of them up: with fewer the view is never a candidate, in any image.
                raise InputValueError(
                    f"the example shows {len(view.corners)} corners and {len(view.arcs)} arcs, and recognition "
                    "needs two of them to index a view by (an ellipse or a disc alone has none or one): it "
                    "would never be found")
            views.append(view)
        except InputError as error:
            # Which of several examples failed is what the user needs to mend it.
            raise type(error)(f"{which}: {error}") from None
    return Model(name, tuple(views), tuple(sources) if sources is not None else ("array",) * len(views))


def model_path(folder: str | Path, name: str, *, folder_name: str | None = None) -> Path:
    """The file :func:`save_model` writes a model of this name to in a library folder: ``NAME.vmodel.npz``
    (the name checked as a model's is, and the folder as one it can write into: a directory, or none yet
    and no file in its place or above it).

    ``folder_name`` is what the caller calls ``folder`` (a command's option, e.g. "--library"): a refused
    folder is then said as the caller's user gave it (``--library PATH: folder must be ...``)."""
    if folder_name is not None and not isinstance(folder_name, str):
        raise InputTypeError(f"folder_name must be a str or None, got {type(folder_name).__name__}")
    if not isinstance(folder, (str, Path)):
        raise InputTypeError(f"folder must be a str or Path, got {type(folder).__name__}")
    name = _check_name(name)
    given = "" if folder_name is None else f"{folder_name} {folder}: "
    folder = Path(folder)
    for above in (folder, *folder.parents):
        if above.exists() and not above.is_dir():
            raise InputValueError(f"{given}folder must be a directory (a library of model files), but {above} is a "
                                  "file")
    return folder / f"{name}{MODEL_SUFFIX}"


def save_model(model: Model, folder: str | Path, *, replace: bool = False) -> Path:
    """Write a model into a library folder (created if missing) as ``NAME.vmodel.npz``.

    Parameters
    ----------
    model : Model
    folder : str or Path
    replace : bool
        Replace a model file of the same name. Without it an existing file is an error; a file that is
        not a vmcl model, or holds a model of another name, is never replaced. Another file of the
        folder that holds a model of this name (one renamed by hand) is an error either way, since
        :meth:`Library.load` would refuse the folder.

    Returns
    -------
    Path
        The file written.
    """
    if not isinstance(model, Model):
        raise InputTypeError(f"model must be a vmcl.recognize.Model, got {type(model).__name__}")
    replace = check_bool(replace, "replace")
    path = model_path(folder, model.name)
    folder = path.parent
    if path.exists():
        if not replace:
            raise InputValueError(f"{path} exists; pass replace=True (vmcl learn --replace) to replace it")
        held = load_model(path).name  # refuses a file that is not a vmcl model
        if held != model.name:
            raise InputValueError(f"{path} holds the model {held!r}, not {model.name!r}: it is not replaced")
    if folder.is_dir():
        others = [p.name for p in sorted(folder.glob(f"*{MODEL_SUFFIX}")) if p != path and _name_in(p) == model.name]
        if others:
            raise InputValueError(f"{', '.join(others)} in {folder} already hold(s) the model {model.name!r} (a file "
                                  "renamed by hand keeps the name it was learned under); remove or rename it first")
    folder.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, np.ndarray] = {}
    for i, view in enumerate(model.views):
        arrays.update({f"v{i}_corners": view.corners, f"v{i}_bisector": view.bisector, f"v{i}_opening": view.opening,
                       f"v{i}_points": view.points, f"v{i}_tangent": view.tangent,
                       f"v{i}_centre": view.centre,
                       f"v{i}_arcs": np.column_stack([view.arcs.reshape(-1, 2), view.arc_radius]),
                       f"v{i}_outline": view.outline,
                       f"v{i}_frame": np.array([view.radius, *view.shape, view.length], np.float64)})
    meta = {"format": _FORMAT, "version": _VERSION, "name": model.name, "views": len(model.views),
            "sources": list(model.sources)}
    # Under a new hidden name of its own, then moved over: a user's NAME.vmodel.npz.partial was overwritten.
    replace_file(path, lambda stream: np.savez_compressed(stream, allow_pickle=False, meta=np.array(json.dumps(meta)),
                                                          **arrays))
    return path


def _name_in(path: Path) -> str | None:
    """The name of the model a file holds, from its header alone; None for a file that is not one."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
        return meta.get("name") if isinstance(meta, dict) and meta.get("format") == _FORMAT else None
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, KeyError, TypeError):
        return None


def load_model(path: str | Path) -> Model:
    """Read a model file written by :func:`save_model`.

    Raises
    ------
    vmcl.errors.InputValueError
        The file is missing or not a vmcl model, or (damaged or edited by hand) holds a header or a view that
        is not one: a count of views that is not a whole number, or a view's array of the wrong shape or out
        of the ranges :class:`View` states, named with the file and the view's arrays (``v0_*``), so that
        it is refused here and not later in :func:`vmcl.recognize.recognize`.
    """
    if not isinstance(path, (str, Path)):
        raise InputTypeError(f"path must be a str or Path, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise InputValueError(f"path must be a model file, {path} is not a file")
    if not zipfile.is_zipfile(path):  # np.load would read another file as a pickle or a bare array
        raise InputValueError(f"{path} is not a vmcl model file (it is not a NumPy .npz archive)")
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if not isinstance(meta, dict) or meta.get("format") != _FORMAT:
                raise ValueError("not a model")
            if type(meta.get("version")) is not int or meta["version"] not in range(1, _VERSION + 1):
                raise InputValueError(f"{path} is a vmcl model of format version {meta.get('version')}; this vmcl "
                                      f"reads versions 1 to {_VERSION}")
            # Counts and names as save_model writes them: int("1") or int(1.7) read a hand-edited header as
            # something it does not say.
            if type(meta.get("views")) is not int or meta["views"] < 1:
                raise ValueError(f"its header's views must be a whole number >= 1, got {meta.get('views')!r}")
            sources = meta.get("sources")
            if not isinstance(sources, list) or not all(isinstance(x, str) for x in sources):
                raise ValueError(f"its header's sources must be a list of str, got {sources!r}")
            views = [_view_in(data, i, meta["version"]) for i in range(meta["views"])]
            return Model(_check_name(meta["name"]), tuple(views), tuple(sources))
    except InputError as error:  # the file's version, or a view or model it holds that is not one
        raise error if str(path) in str(error) else InputValueError(f"{path}: {error}") from None
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError):
        # Not a whole .npz archive: damaged (a flipped byte inside a compressed member fails in zlib), cut
        # short, or another kind of file.
        raise InputValueError(f"{path} is not a vmcl model file (it is not a whole NumPy .npz archive: damaged, "
                              "cut short or another kind of file)") from None
    except RecursionError:  # a header nested deeper than JSON's reader goes
        raise InputValueError(f"{path} is not a vmcl model file (its header is nested too deeply)") from None
    except (ValueError, KeyError, IndexError, TypeError, OverflowError) as error:
        reason = "it holds Python objects" if "allow_pickle" in str(error) else str(error)
        raise InputValueError(f"{path} is not a vmcl model file ({reason})") from None


def _view_in(data: Any, i: int, version: int) -> View:
    """View ``i`` of an open model file (its arrays ``v{i}_*``), checked as a :class:`View` is."""
    frame = data[f"v{i}_frame"]
    if frame.dtype.kind not in "iuf" or frame.shape != (4,) or not np.isfinite(frame).all():
        raise ValueError(f"v{i}_frame is not the 4 finite numbers (radius, H, W, length) of view {i}")
    arcs = data[f"v{i}_arcs"] if version >= 2 else np.zeros((0, 3))
    if arcs.ndim != 2 or arcs.shape[1] != 3:
        raise ValueError(f"v{i}_arcs is not (A, 3) rows of a circle's centre and radius, shape {arcs.shape}")
    # An older format holds no outline, which the View reads as every point the outline's; a file of this one
    # whose outline is empty would be read so too.
    outline = data[f"v{i}_outline"] if version >= 3 else np.zeros(0, bool)
    if version >= 3 and not outline.size:
        raise ValueError(f"v{i}_outline is empty")
    try:
        return View(data[f"v{i}_corners"], data[f"v{i}_bisector"], data[f"v{i}_opening"], data[f"v{i}_points"],
                    data[f"v{i}_tangent"], data[f"v{i}_centre"], float(frame[0]), (int(frame[1]), int(frame[2])),
                    float(frame[3]), arcs[:, :2].copy(), arcs[:, 2].copy(), outline)
    except InputError as error:  # the View names its field; the file names it v{i}_<field>
        raise type(error)(f"view {i} (its arrays v{i}_*): {error}") from None


class Library:
    """Models to recognise: given as a sequence, or read from a folder of ``*.vmodel.npz`` files.

    Parameters
    ----------
    models : sequence of Model
        Distinct names.
    """

    def __init__(self, models: Sequence[Model]) -> None:
        if isinstance(models, (str, Model)) or not isinstance(models, Sequence):
            raise InputTypeError(f"models must be a sequence (a list) of vmcl.recognize.Model, got {type(models).__name__}")
        models = tuple(models)
        for m in models:
            if not isinstance(m, Model):
                raise InputTypeError(f"models must hold vmcl.recognize.Model, got {type(m).__name__}")
        names = [m.name for m in models]
        if len(set(names)) != len(names):
            raise InputValueError(f"models must have distinct names, got {sorted(names)}")
        self.models = models
        self._indices: dict[Any, Any] = {}

    @classmethod
    def load(cls, folder: str | Path) -> Library:
        """Every model file in a folder (sorted by name), each read by :func:`load_model` (which names a file
        that is not a whole, valid model)."""
        if not isinstance(folder, (str, Path)):
            raise InputTypeError(f"folder must be a str or Path, got {type(folder).__name__}")
        folder = Path(folder)
        if not folder.is_dir():
            raise InputValueError(f"folder must be a directory of model files, got {folder}")
        files = sorted(folder.glob(f"*{MODEL_SUFFIX}"))
        models = [load_model(p) for p in files]
        owners: dict[str, list[str]] = {}
        for path, model in zip(files, models):
            owners.setdefault(model.name, []).append(path.name)
        shared = {name: paths for name, paths in owners.items() if len(paths) > 1}
        if shared:  # a file renamed by hand keeps the name it was learned under
            raise InputValueError(f"{folder}: models must have distinct names, but " + "; ".join(
                f"{', '.join(paths)} all hold the model {name!r}" for name, paths in shared.items()))
        return cls(models)

    def __len__(self) -> int:
        return len(self.models)

    def __iter__(self) -> Iterator[Model]:
        return iter(self.models)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.models)

    def views(self) -> list[tuple[int, int, View]]:
        """Every (model index, view index, view), model after model."""
        return [(m, v, view) for m, model in enumerate(self.models) for v, view in enumerate(model.views)]

    def cached(self, key: Any, build: Any) -> Any:
        """What ``build()`` gives, made once per ``key`` (the index per Machine and settings)."""
        if key not in self._indices:
            self._indices[key] = build()
        return self._indices[key]

