"""Objects to recognise: a library of flat shapes and polyhedra, rendered alone (to learn from) and in
cluttered, occluded scenes with their exact identity and pose (to be recognised in).

Seed section "Recognition": the cartoon's labelled discontinuities feed a model-based recogniser (after
Huttenlocher and Cass), with models learned from examples. This module gives that recogniser its test
bench. :data:`OBJECTS` holds 2-D objects (polygons, and curved shapes sampled finely along their arcs) and
3-D objects (convex polyhedra with flat-shaded faces, seen in orthographic projection). :func:`object_view`
renders one object alone at a known pose, the example a model is learned from; :func:`recognition_scene`
places several library objects at random similarity poses (3-D ones also at a random view) among clutter,
each at least ``occlusion[0]`` hidden behind an occluder, and says where each object's corners are.

Coordinates are (x, y) in pixels, pixel centres at integers. An object lives in its own unit frame
(radius about 1); a placement maps it to the image by ``x = scale R(angle) p + centre`` after, for a 3-D
object, the rotation by ``yaw`` about the vertical axis and ``tilt`` about the horizontal one and the
orthographic projection onto (x, y).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import cv2
import numpy as np

from vmcl.cm.core import check_bool, check_int, check_real
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.recognize import Library, learn

__all__ = ["LAYER_DISPARITIES", "LEARNED_YAWS", "OBJECTS", "TILT", "Placement", "RecognitionScene", "SceneObject", "example_library",
           "example_views", "object_view", "recognition_scene"]

TILT = 25.0
"""The elevation (degrees) every 3-D object is seen from: the camera looks 25 degrees down on it."""

LEARNED_YAWS = (-40.0, -20.0, 0.0, 20.0, 40.0)
"""The views (yaw, degrees) a 3-D object is learned from by :func:`example_views`: five, 20 degrees apart,
spanning the range :func:`recognition_scene` draws views from, so a scene's view lies at most 10 degrees
from one of them."""
_SIZE = (45, 60)  # recognition_scene's default objects' scale (px)
_LEAST_EXTENT = 8  # px: an example's object is at least this wide or tall (smaller draws next to no edges)

_SUPERSAMPLE = 4  # each pixel is the mean of 4 x 4 samples, so edge pixels carry their coverage
_SHIFT = 4  # cv2.fillPoly's fractional bits: vertices placed to 1/16 of a fine pixel
_ARC = 24  # points per half turn of a curved outline
_LIGHT = np.array([-0.45, -0.55, -0.70])  # towards the light, camera frame (x right, y down, z away)


@dataclass(frozen=True, eq=False)
class SceneObject:
    """One object of :data:`OBJECTS`.

    Attributes
    ----------
    name : str
    outline : float64 (K, 2) or None
        A 2-D object's outline (a simple polygon, curves sampled finely), unit frame.
    vertices : float64 (V, 3) or None
        A 3-D object's vertices (x right, y down, z away from the camera at yaw 0).
    faces : tuple of tuple of int
        A 3-D object's faces, vertex indices counter-clockwise seen from outside; empty for 2-D.
    corners : float64 (C, 2) or (V, 3)
        The points a pose is scored at: a 2-D object's corners (vertices where the outline turns by more
        than 30 degrees), a 3-D object's vertices.
    curved : bool
        Its outline has curved parts.
    """

    name: str
    outline: np.ndarray | None
    vertices: np.ndarray | None
    faces: tuple[tuple[int, ...], ...]
    corners: np.ndarray
    curved: bool

    @property
    def solid(self) -> bool:
        """A 3-D object."""
        return self.vertices is not None

    def projected(self, yaw: float = 0.0) -> tuple[np.ndarray, list[np.ndarray]]:
        """The corners (C, 2) and the visible faces' polygons (each (k, 2), far to near) in the unit frame,
        seen at ``yaw`` degrees (3-D) or as drawn (2-D: the outline is the one face)."""
        if self.vertices is None:
            assert self.outline is not None
            return self.corners, [self.outline]
        rotated = _rotate(self.vertices, yaw)
        faces = []
        for face in self.faces:
            p = rotated[list(face)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            if normal[2] < -1e-9:  # faces the camera (z away from it)
                faces.append((float(p[:, 2].mean()), p[:, :2]))
        faces.sort(key=lambda f: -f[0])
        return rotated[:, :2], [f[1] for f in faces]

    def visible_corners(self, yaw: float = 0.0) -> np.ndarray:
        """The indices of the corners on a visible face at ``yaw`` (every corner of a 2-D object)."""
        if self.vertices is None:
            return np.arange(len(self.corners))
        rotated = _rotate(self.vertices, yaw)
        seen: set[int] = set()
        for face in self.faces:
            p = rotated[list(face)]
            if np.cross(p[1] - p[0], p[2] - p[0])[2] < -1e-9:
                seen.update(face)
        return np.array(sorted(seen), dtype=np.int64)

    def shades(self, yaw: float = 0.0, albedo: float = 0.7) -> list[float]:
        """Each visible face's grey (far to near, as :meth:`projected` orders them): Lambertian under one
        light with an ambient term; the 2-D object's one face is ``albedo``."""
        if self.vertices is None:
            return [albedo]
        rotated = _rotate(self.vertices, yaw)
        light = _LIGHT / np.linalg.norm(_LIGHT)
        shades = []
        for face in self.faces:
            p = rotated[list(face)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            if normal[2] < -1e-9:
                n = normal / np.linalg.norm(normal)
                shades.append((float(p[:, 2].mean()), albedo * (0.3 + 0.7 * max(0.0, float(n @ light)))))
        shades.sort(key=lambda f: -f[0])
        return [s for _, s in shades]


@dataclass(frozen=True)
class Placement:
    """Where one object lies in a scene.

    Attributes
    ----------
    name : str
    yaw : float
        The view (degrees) of a 3-D object; 0 for 2-D.
    scale, angle : float
        The similarity from the (projected) unit frame to the image: scale in pixels, angle in degrees.
    centre : (float, float)
    corners : float64 (C, 2)
        The object's corners in the image (every corner of a 2-D object; a 3-D object's visible
        vertices), exact.
    corner_ids : int64 (C,)
        Which of :attr:`SceneObject.corners` each row is.
    occluded : float
        The fraction of the object's area hidden by what lies in front of it (or outside the image).
    """

    name: str
    yaw: float
    scale: float
    angle: float
    centre: tuple[float, float]
    corners: np.ndarray
    corner_ids: np.ndarray
    occluded: float

    def matrix(self) -> np.ndarray:
        """The 2 x 3 affine map from the (projected) unit frame to the image."""
        return _similarity(self.scale, self.angle, self.centre)


@dataclass(frozen=True, eq=False)
class RecognitionScene:
    """What :func:`recognition_scene` returns.

    Attributes
    ----------
    image : float32 (H, W)
        Greys in [0, 1] plus noise: the left view of a stereo scene.
    placements : tuple of Placement
        The library objects in the scene (not the clutter or occluders).
    right : float32 (H, W) or None
        A stereo scene's right view (its own noise), rows being epipolar lines; None otherwise.
    disparity : float32 (H, W) or None
        A stereo scene's true disparity of the left view (x_right = x_left - d), each layer at its
        :data:`LAYER_DISPARITIES`' (a pixel on an outline holds the mean of the layers its samples show).
    """

    image: np.ndarray
    placements: tuple[Placement, ...]
    right: np.ndarray | None = None
    disparity: np.ndarray | None = None


LAYER_DISPARITIES = MappingProxyType({"back": 4.0, "object": 7.0, "occluder": 13.0, "front": 15.0})
"""A stereo recognition scene's disparity of each layer, in pixels, far to near as they are painted: the
background and the clutter behind everything, the library objects (the k-th at ``object + k``, nearer
than those placed before it, which it may overlap), their occluders, and the clutter in front. Each layer
is flat and parallel to the image: the right view is the same strokes moved left by their disparity.
Read-only: the scenes' ground truth is rendered from it."""


def _rotate(vertices: np.ndarray, yaw: float) -> np.ndarray:
    a, t = math.radians(yaw), math.radians(TILT)
    turn = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    # Tilt: the camera looks down, so the object's top (y < 0) leans away from it.
    tip = np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])
    return vertices @ (tip @ turn).T


def _similarity(scale: float, angle: float, centre: tuple[float, float]) -> np.ndarray:
    a = math.radians(angle)
    c, s = scale * math.cos(a), scale * math.sin(a)
    return np.array([[c, -s, centre[0]], [s, c, centre[1]]])


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:, :2].T + matrix[:, 2]


def _arc(cx: float, cy: float, r: float, start: float, stop: float, ry: float | None = None) -> np.ndarray:
    """Points along an arc (degrees, counter-clockwise in the maths sense; y down flips it on screen),
    both ends included."""
    n = max(2, round(abs(stop - start) / 180 * _ARC) + 1)
    t = np.radians(np.linspace(start, stop, n))
    return np.stack([cx + r * np.cos(t), cy + (r if ry is None else ry) * np.sin(t)], axis=1)


def _polygon_corners(outline: np.ndarray, turn: float = 30.0) -> np.ndarray:
    prev = outline - np.roll(outline, 1, axis=0)
    nxt = np.roll(outline, -1, axis=0) - outline
    angle = np.abs(np.angle((nxt[:, 0] + 1j * nxt[:, 1]) / (prev[:, 0] + 1j * prev[:, 1])))
    return outline[np.degrees(angle) > turn]


def _flat(name: str, outline: list | np.ndarray, curved: bool = False) -> SceneObject:
    points = np.asarray(outline, dtype=np.float64)
    # Drop repeated points where arcs meet straight parts.
    keep = np.hypot(*(points - np.roll(points, 1, axis=0)).T) > 1e-9
    points = points[keep]
    # The unit frame: the area's centroid at 0, the area that of the unit disc (vertices sample arcs
    # densely, so their own mean and spread would lean towards the curved parts).
    x, y = points[:, 0], points[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = cross.sum() / 2
    centroid = np.array([((x + np.roll(x, -1)) * cross).sum(), ((y + np.roll(y, -1)) * cross).sum()]) / (6 * area)
    points = (points - centroid) / math.sqrt(abs(area) / math.pi)
    return SceneObject(name, points, None, (), _polygon_corners(points), curved)


def _solid(name: str, vertices: list, faces: list) -> SceneObject:
    v = np.asarray(vertices, dtype=np.float64)
    v = v - v.mean(axis=0)
    v /= np.sqrt((v ** 2).sum(axis=1).mean())
    return SceneObject(name, None, v, tuple(tuple(f) for f in faces), v, False)


def _prism(base: list, height: float) -> tuple[list, list]:
    """A right prism over a convex base (x, z) counter-clockwise seen from above (y < 0 is up)."""
    k = len(base)
    top = [(x, -height / 2, z) for x, z in base]
    bottom = [(x, height / 2, z) for x, z in base]
    faces = [list(range(k)), list(range(2 * k - 1, k - 1, -1))]
    faces += [[i, (i + 1) % k, k + (i + 1) % k, k + i][::-1] for i in range(k)]
    return top + bottom, faces


def _oriented(vertices: list, faces: list) -> list:
    """The faces ordered so their normals point away from the centroid."""
    v = np.asarray(vertices, float)
    centre = v.mean(axis=0)
    out = []
    for f in faces:
        p = v[list(f)]
        if np.cross(p[1] - p[0], p[2] - p[0]) @ (p.mean(axis=0) - centre) < 0:
            f = list(f)[::-1]
        out.append(list(f))
    return out


def _library() -> tuple[SceneObject, ...]:
    objects = [
        _flat("ell", [(0, 0), (3, 0), (3, 1), (1, 1), (1, 4), (0, 4)]),
        _flat("tee", [(0, 0), (5, 0), (5, 1.2), (3.1, 1.2), (3.1, 4.5), (1.9, 4.5), (1.9, 1.2), (0, 1.2)]),
        _flat("cross", [(1, 0), (2, 0), (2, 1), (3, 1), (3, 2), (2, 2), (2, 3.4), (1, 3.4), (1, 2), (0, 2),
                        (0, 1), (1, 1)]),
        _flat("arrow", [(0, 1), (3, 1), (3, 0), (5, 1.75), (3, 3.5), (3, 2.5), (0, 2.5)]),
        _flat("house", [(0, 1.6), (1.5, 0), (3, 1.6), (3, 4), (0, 4)]),
        _flat("star", [(math.cos(math.radians(90 + 36 * i)) * (1 if i % 2 == 0 else 0.45),
                        -math.sin(math.radians(90 + 36 * i)) * (1 if i % 2 == 0 else 0.45)) for i in range(10)]),
        _flat("trapezoid", [(0, 2), (1, 0), (3.2, 0), (4, 2)]),
        _flat("chevron", [(0, 0), (2, 1.5), (4, 0), (4, 1.4), (2, 2.9), (0, 1.4)]),
        _flat("hexagon", [(0, 1), (1.2, 0), (3, 0.3), (3.6, 1.6), (2.4, 3), (0.6, 2.6)]),
        _flat("comb", [(0, 0), (4, 0), (4, 3), (3, 3), (3, 1), (2.5, 1), (2.5, 3), (1.5, 3), (1.5, 1), (1, 1),
                       (1, 3), (0, 3)]),
        _flat("flag", [(0, 0), (3, 0), (2.2, 1), (3, 2), (0.8, 2), (0.8, 4), (0, 4)]),
        _flat("notched triangle", [(0, 3), (1.5, 0), (3.6, 3), (2.3, 3), (1.8, 2.2), (1.3, 3)]),
        _flat("half disc", _arc(0, 0, 2, 180, 360), curved=True),
        _flat("crescent", np.concatenate([_arc(0, 0, 2, 90, 270), _arc(0.9, 0, 1.75, 235, 125)[1:-1]]), curved=True),
        _flat("pac", np.concatenate([[(0, 0)], _arc(0, 0, 2, 35, 325)]), curved=True),
        _flat("tab", np.concatenate([[(0, 2.5), (0, 0)], _arc(2.5, 1.25, 1.25, 270, 450)[:-1], [(2.5, 2.5)]]),
              curved=True),
        _flat("keyhole", np.concatenate([_arc(0, 0, 1, 120, 420)[:-1], [(0.5, 0.866), (1.1, 3), (-1.1, 3),
                                                                         (-0.5, 0.866)]]), curved=True),
        _flat("quarter", np.concatenate([[(0, 0)], _arc(0, 0, 2.4, -90, 0)]), curved=True),
        _flat("bitten square", np.concatenate([[(0, 0), (3, 0), (3, 3)], _arc(1.5, 3, 0.9, 0, -180)[:-1],
                                               [(0, 3)]]), curved=True),
        _flat("lens", np.concatenate([_arc(0, 1.2, 2, -125, -55), _arc(0, -1.2, 2, 55, 125)[1:-1]]),
              curved=True),
        _flat("shield", np.concatenate([[(-1.5, 0), (1.5, 0)], _arc(-1.5, 0, 3, 0, 60)[:-1],
                                        _arc(1.5, 0, 3, 120, 180)[:-1]]), curved=True),
    ]
    box_v, box_f = _prism([(-1.4, -0.8), (1.4, -0.8), (1.4, 0.8), (-1.4, 0.8)], 1.6)
    wedge_v, wedge_f = _prism([(-1.3, -1), (1.3, -1), (0, 1.2)], 1.3)
    hexa_v, hexa_f = _prism([(math.cos(math.radians(60 * i)), math.sin(math.radians(60 * i))) for i in range(6)], 1.5)
    pyramid_v = [(-1, 0.6, -1), (1, 0.6, -1), (1, 0.6, 1), (-1, 0.6, 1), (0, -1.0, 0)]
    pyramid_f = [[0, 1, 2, 3], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    frustum_v = [(-1.2, 0.6, -1.2), (1.2, 0.6, -1.2), (1.2, 0.6, 1.2), (-1.2, 0.6, 1.2),
                 (-0.6, -0.6, -0.6), (0.6, -0.6, -0.6), (0.6, -0.6, 0.6), (-0.6, -0.6, 0.6)]
    frustum_f = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    ramp_v = [(-1.4, 0.7, -0.8), (1.4, 0.7, -0.8), (1.4, 0.7, 0.8), (-1.4, 0.7, 0.8), (1.4, -0.9, -0.8),
              (1.4, -0.9, 0.8)]
    ramp_f = [[0, 1, 2, 3], [1, 4, 5, 2], [0, 4, 1], [3, 2, 5], [0, 3, 5, 4]]
    objects += [_solid("block", box_v, _oriented(box_v, box_f)),
                _solid("prism", wedge_v, _oriented(wedge_v, wedge_f)),
                _solid("hexagonal prism", hexa_v, _oriented(hexa_v, hexa_f)),
                _solid("pyramid", pyramid_v, _oriented(pyramid_v, pyramid_f)),
                _solid("frustum", frustum_v, _oriented(frustum_v, frustum_f)),
                _solid("ramp", ramp_v, _oriented(ramp_v, ramp_f))]
    return tuple(objects)


OBJECTS: tuple[SceneObject, ...] = _library()
"""The library: 21 2-D objects (12 polygons, 9 with curved outlines) and 6 convex polyhedra."""

_BY_NAME = {o.name: o for o in OBJECTS}


def _object(name: str, what: str = "name") -> SceneObject:
    if not isinstance(name, str):
        raise InputTypeError(f"{what} must be the name of one of vmcl.scenes.OBJECTS, got {type(name).__name__}")
    if name not in _BY_NAME:
        raise InputValueError(f"{what} must be one of {sorted(_BY_NAME)}, got {name!r}")
    return _BY_NAME[name]


class _Canvas:
    """Polygons painted far to near at 4 x 4 samples per pixel, with the id of what each sample shows."""

    def __init__(self, h: int, w: int, background: float) -> None:
        self.h, self.w = h, w
        self.background = background
        self.grey = np.full((h * _SUPERSAMPLE, w * _SUPERSAMPLE), background, np.float32)
        self.owner = np.full(self.grey.shape, -1, np.int32)
        self.strokes: list[tuple[np.ndarray, float, int]] = []  # (polygon, grey, owner), far to near

    def paint(self, polygon: np.ndarray, grey: float, owner: int) -> None:
        fine = (polygon + 0.5) * _SUPERSAMPLE - 0.5
        pts = np.round(fine * (1 << _SHIFT)).astype(np.int64)
        if np.abs(pts).max() > 2**30:
            raise InputValueError("a polygon lies too far outside the image to draw")
        mask = np.zeros(self.grey.shape, np.uint8)
        cv2.fillPoly(mask, [pts.astype(np.int32)], 1, lineType=cv2.LINE_8, shift=_SHIFT)
        on = mask.astype(bool)
        self.grey[on] = grey
        self.owner[on] = owner
        self.strokes.append((polygon, grey, owner))

    @staticmethod
    def whole_area(polygons: list[np.ndarray]) -> int:
        """The samples the polygons cover together, inside the image or beyond it: drawn on a canvas of their
        own box, moved by whole pixels (so the samples fall as on the image's)."""
        corners = np.concatenate(polygons)
        low = np.floor(corners.min(axis=0)) - 1
        high = np.ceil(corners.max(axis=0)) + 1
        box = _Canvas(int(high[1] - low[1]) + 1, int(high[0] - low[0]) + 1, 0.0)
        covered = np.zeros(box.grey.shape, bool)
        for polygon in polygons:
            covered |= box.area(polygon - low)
        return int(covered.sum())

    def area(self, polygon: np.ndarray) -> np.ndarray:
        """The samples inside a polygon (whatever is painted there)."""
        mask = np.zeros(self.grey.shape, np.uint8)
        fine = (polygon + 0.5) * _SUPERSAMPLE - 0.5
        cv2.fillPoly(mask, [np.round(fine * (1 << _SHIFT)).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=_SHIFT)
        return mask.astype(bool)

    def image(self) -> np.ndarray:
        return self._pixels(self.grey)

    def _pixels(self, samples: np.ndarray) -> np.ndarray:
        """A sample plane averaged over each pixel's samples."""
        return samples.reshape(self.h, _SUPERSAMPLE, self.w, _SUPERSAMPLE).mean(axis=(1, 3)).astype(np.float32)

    def stereo(self) -> tuple[np.ndarray, np.ndarray]:
        """The right view of the strokes painted so far, each moved left by its layer's disparity
        (:data:`LAYER_DISPARITIES`), and the left view's disparity."""
        right = _Canvas(self.h, self.w, self.background)
        disparity = np.full(self.grey.shape, LAYER_DISPARITIES["back"], np.float32)
        for (polygon, grey, owner), d in zip(self.strokes, _layer_disparities(self.strokes)):
            right.paint(polygon - np.array([d, 0.0]), grey, owner)
            disparity[self.area(polygon)] = d
        return right.image(), self._pixels(disparity)


def _layer_disparities(strokes: list[tuple[np.ndarray, float, int]]) -> list[float]:
    """Each stroke's disparity, by the layer :func:`_draw_scene` paints it in: clutter (owner -2) before the
    occluders (-3) lies behind everything, after them in front; object k's faces are at ``object + k``."""
    found, occluders_painted = [], False
    for _, _, owner in strokes:
        occluders_painted |= owner == -3
        if owner >= 0:
            found.append(LAYER_DISPARITIES["object"] + owner)
        elif owner == -3:
            found.append(LAYER_DISPARITIES["occluder"])
        else:
            found.append(LAYER_DISPARITIES["front" if occluders_painted else "back"])
    return found


def _check_shape(shape: object) -> tuple[int, int]:
    if not isinstance(shape, (tuple, list)) or len(shape) != 2:
        raise InputTypeError(f"shape must be a pair (height, width) of ints, got {shape!r}")
    h, w = (check_int(n, "shape", minimum=32, maximum=8192) for n in shape)
    return h, w


def object_view(name: str, *, yaw: float = 0.0, shape: tuple[int, int] = (200, 200), scale: float | None = None,
                background: float = 0.2, albedo: float = 0.8, noise: float = 0.0,
                seed: int = 0) -> tuple[np.ndarray, Placement]:
    """One object alone, upright and centred: the example a model is learned from.

    Parameters
    ----------
    name : str
        One of :data:`OBJECTS`' names.
    yaw : float
        A 3-D object's view in degrees (ignored for 2-D objects).
    shape : (int, int)
        (H, W), each 32 to 8192.
    scale : float, optional
        Pixels per unit of the object's frame (> 0); default 0.22 min(H, W). The object must lie inside the
        image, at least 8 px across.
    background, albedo : float
        The background's grey and the object's (a 3-D object's faces are shaded from it), in [0, 1].
    noise : float
        Standard deviation of the Gaussian noise added, >= 0.
    seed : int
        Seeds the noise.

    Returns
    -------
    image : float32 (H, W)
    placement : Placement
    """
    obj = _object(name)
    h, w = _check_shape(shape)
    yaw = check_real(yaw, "yaw", minimum=-180, maximum=180)
    scale = 0.22 * min(h, w) if scale is None else check_real(scale, "scale", above=0)
    background = check_real(background, "background", minimum=0, maximum=1)
    albedo = check_real(albedo, "albedo", minimum=0, maximum=1)
    noise = check_real(noise, "noise", minimum=0)
    seed = check_int(seed, "seed", minimum=0)
    centre = ((w - 1) / 2, (h - 1) / 2)
    _, faces = obj.projected(yaw if obj.solid else 0.0)
    drawn = _apply(_similarity(scale, 0.0, centre), np.concatenate(faces))
    low, high = drawn.min(axis=0), drawn.max(axis=0)
    # An example shows the whole object: one cut by the image's border (its placement said nothing was
    # hidden) or too small to draw an edge teaches a model of something else.
    if (low < 0).any() or high[0] > w - 1 or high[1] > h - 1:
        largest = scale * min((w - 1) / 2 / np.abs(drawn[:, 0] - centre[0]).max(),
                              (h - 1) / 2 / np.abs(drawn[:, 1] - centre[1]).max())
        raise InputValueError(f"scale must keep the {name!r} inside the {h} x {w} image (at most {largest:.4g} "
                              f"here), got {scale:.4g}")
    if (high - low).max() < _LEAST_EXTENT:
        raise InputValueError(f"scale must draw the {name!r} at least {_LEAST_EXTENT} px across, got {scale:.4g} "
                              f"({(high - low).max():.3g} px)")
    canvas = _Canvas(h, w, background)
    placement = _draw(canvas, obj, 0, yaw if obj.solid else 0.0, scale, 0.0, centre, albedo)
    image = canvas.image()
    if noise > 0:
        image += np.random.default_rng(seed).normal(0, noise, image.shape).astype(np.float32)
    return image, placement


def example_views(name: str, *, shape: tuple[int, int] = (200, 200)) -> list[tuple[np.ndarray, Placement]]:
    """The examples a model of the object is learned from: one view of a 2-D object, the views at
    :data:`LEARNED_YAWS` of a 3-D one (:func:`object_view`'s defaults otherwise).

    Returns
    -------
    list of (image, Placement)
    """
    obj = _object(name)
    return [object_view(name, yaw=yaw, shape=shape) for yaw in (LEARNED_YAWS if obj.solid else (0.0,))]


def example_library(names: tuple[str, ...] | None = None, *,
                    machine: Machine | None = None) -> tuple[Library, dict[str, list[Placement]]]:
    """The library learned from :func:`example_views` of the objects (default: all of :data:`OBJECTS`),
    with the placements of each model's views (which put its corners in its frame, for
    :func:`vmcl.metrics.recognition_scores`).

    Returns
    -------
    library : vmcl.recognize.Library
    learned : dict of str to list of Placement
    """
    if names is not None and (isinstance(names, str) or not isinstance(names, (tuple, list))):
        raise InputTypeError(f"names must be a tuple of object names, got {type(names).__name__}")
    chosen = [o.name for o in OBJECTS] if names is None else [_object(n, "names").name for n in names]
    if not chosen:
        raise InputValueError("names must name at least one object (None: all of OBJECTS)")
    repeated = sorted({name for name in chosen if chosen.count(name) > 1})
    if repeated:  # else refused by the Library, as "models", which the caller never gave
        raise InputValueError(f"names must name each object once, got {', '.join(map(repr, repeated))} more than once")
    models, learned = [], {}
    for name in chosen:
        views = example_views(name)
        models.append(learn(name, [image for image, _ in views], machine=machine))
        learned[name] = [placement for _, placement in views]
    return Library(models), learned


def _draw(canvas: _Canvas, obj: SceneObject, owner: int, yaw: float, scale: float, angle: float,
          centre: tuple[float, float], albedo: float) -> Placement:
    matrix = _similarity(scale, angle, centre)
    corners, faces = obj.projected(yaw)
    for face, grey in zip(faces, obj.shades(yaw, albedo)):
        canvas.paint(_apply(matrix, face), grey, owner)
    ids = obj.visible_corners(yaw)
    return Placement(obj.name, yaw, scale, angle, centre, _apply(matrix, corners[ids]), ids, 0.0)


def _random_blob(rng: np.random.Generator, centre: np.ndarray, radius: float) -> np.ndarray:
    k = int(rng.integers(3, 8))
    angles = np.sort(rng.uniform(0, 2 * math.pi, k))
    radii = radius * rng.uniform(0.6, 1.0, k)
    if rng.uniform() < 0.3:  # an ellipse
        t = np.linspace(0, 2 * math.pi, 48, endpoint=False)
        a, b, phi = radius, radius * rng.uniform(0.4, 1.0), rng.uniform(0, math.pi)
        x, y = a * np.cos(t), b * np.sin(t)
        return centre + np.stack([x * math.cos(phi) - y * math.sin(phi), x * math.sin(phi) + y * math.cos(phi)], 1)
    return centre + np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


def _bar(rng: np.random.Generator, centre: np.ndarray, length: float) -> np.ndarray:
    a = rng.uniform(0, math.pi)
    d = np.array([math.cos(a), math.sin(a)]) * length / 2
    n = np.array([-d[1], d[0]]) / np.linalg.norm(d) * rng.uniform(1.0, 2.5)
    return np.array([centre - d - n, centre + d - n, centre + d + n, centre - d + n])


def _albedo(rng: np.random.Generator, obj: SceneObject, yaw: float, background: float) -> float:
    """An albedo whose faces (a 3-D object's, shaded) all stand 0.15 off the background, drawn brighter for
    3-D objects (shading darkens them)."""
    for _ in range(100):
        albedo = float(rng.uniform(0.55, 1.0) if obj.solid else rng.uniform(0.08, 0.92))
        if all(abs(s - background) >= 0.15 for s in obj.shades(yaw, albedo)):
            return albedo
    return albedo


def _grey(rng: np.random.Generator, avoid: list[float], contrast: float = 0.15) -> float:
    for _ in range(100):
        g = float(rng.uniform(0.08, 0.92))
        if all(abs(g - a) >= contrast for a in avoid):
            return g
    return float(rng.uniform(0.08, 0.92))


def recognition_scene(shape: tuple[int, int] = (384, 512), *, objects: int = 2, library: tuple[str, ...] | None = None,
                      occlusion: tuple[float, float] = (0.3, 0.5), clutter: int = 8, views: tuple[float, float] = (-40, 40),
                      size: tuple[float, float] = _SIZE, noise: float = 0.01, stereo: bool = False,
                      seed: int = 0) -> RecognitionScene:
    """Library objects at random poses among clutter, each partly hidden behind an occluder.

    Parameters
    ----------
    shape : (int, int)
        (H, W), each 32 to 8192.
    objects : int
        How many library objects (distinct), 1 to 6.
    library : tuple of str, optional
        The names to draw them from; default every object of :data:`OBJECTS`.
    occlusion : (float, float)
        The fraction of each object's area hidden (by its occluder, the other objects and clutter in front
        of it and the image border) lies within this range, 0 <= low <= high <= 0.95: the occluder is placed
        again until it is, and the whole scene drawn again (from the same seed's stream) where clutter or
        another object's occluder took an object out of it. A range no arrangement meets in
        _SCENE_ATTEMPTS draws (objects too large for the shape, say) raises ValueError.
    clutter : int
        Shapes and bars not in the library scattered behind and among the objects, >= 0.
    views : (float, float)
        A 3-D object's yaw is uniform in this range (degrees).
    size : (float, float)
        Each object's scale (pixels per unit of its frame, its rms radius) is uniform in this range.
    noise : float
        Standard deviation of the Gaussian noise, >= 0.
    stereo : bool
        Also render the right view of a stereo pair and the true disparity: each layer flat at its
        :data:`LAYER_DISPARITIES`', nearer as it is painted later, so that a stereo machine can tell what
        hides each object. The left view and the placements are those of ``stereo=False``.
    seed : int
        >= 0; the same seed gives the same scene.

    Returns
    -------
    RecognitionScene

    Examples
    --------
    >>> from vmcl.scenes import recognition_scene
    >>> scene = recognition_scene(seed=1)
    >>> len(scene.placements), all(p.occluded >= 0.3 for p in scene.placements)
    (2, True)
    """
    h, w = _check_shape(shape)
    count = check_int(objects, "objects", minimum=1, maximum=6)
    if library is not None and (isinstance(library, str) or not isinstance(library, (tuple, list))):
        raise InputTypeError(f"library must be a tuple of object names, got {type(library).__name__}")
    names = tuple(o.name for o in OBJECTS) if library is None else tuple(_object(n, "library").name for n in library)
    if len(set(names)) < count:
        raise InputValueError(f"library must hold at least objects={count} distinct names, got {len(set(names))}")
    low, high = _pair(occlusion, "occlusion", 0.0, 0.95)
    clutter = check_int(clutter, "clutter", minimum=0, maximum=1000)
    yaw_low, yaw_high = _pair(views, "views", -180.0, 180.0)
    if size == _SIZE and _SIZE[1] > min(h, w):  # refused as "size", which the caller never gave
        raise InputValueError(f"shape {h} x {w} is too small for the default size {_SIZE} (the objects' scale in px, "
                              "at most the shape's smaller side): give a size within it")
    small, large = _pair(size, "size", 1.0, float(min(h, w)))
    noise = check_real(noise, "noise", minimum=0)
    stereo = check_bool(stereo, "stereo")
    seed = check_int(seed, "seed", minimum=0)
    rng = np.random.default_rng(seed)
    for _ in range(_SCENE_ATTEMPTS):  # the first draw is the scene unless an object left the range
        drawn = _draw_scene(rng, (h, w), count, names, (low, high), clutter, (yaw_low, yaw_high), (small, large))
        if drawn is None:
            continue
        canvas, placements = drawn
        if all(low <= p.occluded <= high for p in placements):
            right, disparity = canvas.stereo() if stereo else (None, None)
            # The left view's noise is drawn first, so that a stereo scene's left view is the plain scene's.
            images = [canvas.image()] + ([] if right is None else [right])
            if noise > 0:
                for image in images:
                    image += rng.normal(0, noise, image.shape).astype(np.float32)
            return RecognitionScene(images[0], placements, right, disparity)
    raise InputValueError(f"occlusion: no arrangement of {count} object(s) of size {small:g}..{large:g} px in "
                          f"{w} x {h} hid each within {low:g}..{high:g} in {_SCENE_ATTEMPTS} draws; widen the range, "
                          "enlarge the shape or place fewer or smaller objects")


_SCENE_ATTEMPTS = 20


def _draw_scene(rng: np.random.Generator, shape: tuple[int, int], count: int, names: tuple[str, ...],
                occlusion: tuple[float, float], clutter: int, views: tuple[float, float],
                size: tuple[float, float]) -> tuple[_Canvas, tuple[Placement, ...]] | None:
    """One draw of :func:`recognition_scene` (its arguments checked), before noise: the canvas and the
    placements, each with the share of it hidden in the end; None where an occluder found no place."""
    (h, w), (low, high), (yaw_low, yaw_high), (small, large) = shape, occlusion, views, size
    background = float(rng.uniform(0.35, 0.65))
    canvas = _Canvas(h, w, background)
    for _ in range(clutter):  # behind everything
        at = rng.uniform([0, 0], [w, h])
        if rng.uniform() < 0.5:
            canvas.paint(_bar(rng, at, rng.uniform(20, 80)), _grey(rng, [background]), -2)
        else:
            canvas.paint(_random_blob(rng, at, rng.uniform(10, 35)), _grey(rng, [background]), -2)
    chosen = [str(n) for n in rng.choice(names, size=count, replace=False)]
    placed: list[tuple[SceneObject, float, float, float, tuple[float, float], float]] = []
    centres: list[np.ndarray] = []
    for name in chosen:
        obj = _BY_NAME[name]
        scale = float(rng.uniform(small, large))
        for _ in range(200):
            centre = rng.uniform([1.3 * scale, 1.3 * scale], [w - 1.3 * scale, h - 1.3 * scale]) \
                if w > 2.6 * scale and h > 2.6 * scale else np.array([(w - 1) / 2, (h - 1) / 2])
            if all(np.hypot(*(centre - c)) >= 2.6 * scale for c in centres):
                break
        centres.append(centre)
        yaw = float(rng.uniform(yaw_low, yaw_high)) if obj.solid else 0.0
        placed.append((obj, yaw, scale, float(rng.uniform(-180, 180)), (float(centre[0]), float(centre[1])),
                       _albedo(rng, obj, yaw, background)))
    placements = []
    for k, (obj, yaw, scale, angle, where, albedo) in enumerate(placed):
        placements.append(_draw(canvas, obj, k, yaw, scale, angle, where, albedo))
    # One occluder per object, placed again until each object is hidden within the range. What lies beyond the
    # image is hidden too: the shares are of the whole object (counted on the image alone, an object half
    # outside it passed as a little hidden).
    for k, (obj, yaw, scale, angle, where, albedo) in enumerate(placed):
        faces = [_apply(_similarity(scale, angle, where), face) for face in obj.projected(yaw)[1]]
        own = np.zeros(canvas.grey.shape, bool)
        for face in faces:
            own |= canvas.area(face)
        total = max(_Canvas.whole_area(faces), 1)
        beyond = total - int(own.sum())
        for _ in range(400):
            at = np.array(where) + rng.normal(0, scale, 2)
            blob = _random_blob(rng, at, scale * rng.uniform(0.6, 1.1))
            hidden = own & (canvas.area(blob) | (canvas.owner != k))
            if low <= (hidden.sum() + beyond) / total <= high:
                canvas.paint(blob, _grey(rng, [background, *obj.shades(yaw, albedo)]), -3)
                break
        else:
            return None  # no place for this occluder: the draw fails
    for _ in range(clutter // 2):  # some clutter in front too, away from the objects' middles
        at = rng.uniform([0, 0], [w, h])
        if all(np.hypot(*(at - c)) > 2.2 * s for c, s in zip(centres, (p[2] for p in placed))):
            canvas.paint(_bar(rng, at, rng.uniform(15, 50)), _grey(rng, [background]), -2)
    for k, (obj, yaw, scale, angle, where, albedo) in enumerate(placed):
        faces = [_apply(_similarity(scale, angle, where), face) for face in obj.projected(yaw)[1]]
        own = np.zeros(canvas.grey.shape, bool)
        for face in faces:
            own |= canvas.area(face)
        total = max(_Canvas.whole_area(faces), 1)
        hidden = float(((own & (canvas.owner != k)).sum() + total - int(own.sum())) / total)
        p = placements[k]
        placements[k] = Placement(p.name, p.yaw, p.scale, p.angle, p.centre, p.corners, p.corner_ids, hidden)
    return canvas, tuple(placements)


def _pair(value: object, name: str, lowest: float, highest: float) -> tuple[float, float]:
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise InputTypeError(f"{name} must be a pair (low, high), got {value!r}")
    low, high = (check_real(v, name, minimum=lowest, maximum=highest) for v in value)
    if low > high:
        raise InputValueError(f"{name} must be (low, high) with low <= high, got {value!r}")
    return low, high
