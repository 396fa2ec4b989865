"""Synthetic worlds seen by a rectified stereo pair over two frames, with ground truth at every pixel.

The seed paper's learning stage estimates parameters "from a set of examples in which data and desired
solution are given ... at least initially, synthetic images" (section "Learning and parameter
estimation"), and its labelling stage classifies each discontinuity as an occluding (depth),
orientation, albedo (mark), shadow or specular edge (section "Labeling the physical origin of edges",
"Physical discontinuities"). This module renders such examples: small worlds of textured, painted
planar faces under one light, ray cast per pixel in vectorised NumPy, with the physical cause of every
pixel known.

Image model (section "Color", after Hurlbert and Poggio): with the specular term off, every pixel obeys

    I^nu(x, y) = k^nu E(x, y) rho^nu(x, y)

exactly, where k^nu is the light's colour, rho^nu the surface albedo and E the effective illumination
``E = g(P) (ambient + (1 - ambient) (1 - shadow) max(0, n . L))``: Lambertian shading, a cast shadow,
an ambient term of the source's own colour (the single-source assumption) and a smooth illumination
gradient ``g(P) = exp(gradient . (P - gradient_origin))`` over world position P. With the specular term
on, ``I^nu = k^nu (E rho^nu + S)`` with the Blinn-Phong highlight S. Images are float32, not clipped:
noise stays exactly Gaussian.

Geometry and conventions (those of the whole package):

- world frame = the left camera's frame at time t: x right, y down, z forward; pinhole cameras with
  focal length ``focal`` in pixels and principal point ((W - 1) / 2, (H - 1) / 2), pixel centres at
  integer coordinates; the right camera sits at (baseline, 0, 0);
- disparity ``d = focal * baseline / depth >= 0`` with ``I_left(x, y) = I_right(x - d, y)``;
- flow (u, v) with ``I_t(x, y) = I_t+1(x + u, y + v)``, from the true 3-D motion of each point (bodies
  move rigidly, the stereo rig moves rigidly);
- NaN where there is no value (no surface).

Discontinuity labels (:class:`Label`) live on the dual lattice between 4-neighbours (``line_h`` between
(y, x) and (y, x + 1), ``line_v`` between (y, x) and (y + 1, x)) and on the pixel grid (``labels``). A
site's label is decided by the first of these that differs between its two pixels: the body (DEPTH),
the face of one body (ORIENTATION: faces of one body meet only along folds), the albedo region (ALBEDO
if the colour differs, TEXTURE if only the texture does), the cast shadow (SHADOW), the specular
highlight's half-maximum contour (SPECULAR). On the pixel grid, a DEPTH site labels its nearer pixel
(the occluding contour belongs to the occluder); every other site labels its left (``line_h``) or upper
(``line_v``) pixel; a pixel that receives several labels keeps the first in the order DEPTH,
ORIENTATION, ALBEDO, TEXTURE, SHADOW, SPECULAR. Texture elements (dots, stripes, blobs) modulate the
albedo of a region achromatically and are not labelled.

References
----------
T. Poggio, J. Little, E. Gamble, W. Gillett, D. Geiger, D. Weinshall et al., "The MIT Vision Machine",
Proc. DARPA Image Understanding Workshop, 1988.
A. Hurlbert and T. Poggio, "A network for image segmentation using color", NIPS 1988.
E. Gamble, D. Geiger, T. Poggio and D. Weinshall, "Integration of vision modules and labeling of surface
discontinuities", IEEE SMC 19(6), 1989.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vmcl.cm._arrays import check_bool, check_int, check_real
from vmcl.errors import InputTypeError, InputValueError
from vmcl.labels import Label

__all__ = [
    "PRESETS",
    "Body",
    "Camera",
    "Face",
    "Light",
    "Mark",
    "Motion",
    "Scene",
    "Texture",
    "World",
    "box",
    "fold",
    "preset",
    "render",
]

F32 = np.float32
_NEAR = 1e-3  # nearest depth a camera sees, world units
_EPS = 1e-5  # relative slack of segment tests, so a point never hides itself


_PRECEDENCE = (Label.DEPTH, Label.ORIENTATION, Label.ALBEDO, Label.TEXTURE, Label.SHADOW, Label.SPECULAR)


# --------------------------------------------------------------------------------------------- world


def _numbers(value, name: str, count: int) -> tuple[float, ...]:
    """``value`` as ``count`` finite floats: a tuple, list or array of real numbers."""
    if not isinstance(value, (tuple, list, np.ndarray)):
        raise InputTypeError(f"{name} must be {count} finite numbers, got {type(value).__name__}")
    if isinstance(value, np.ndarray):
        numbers = value.dtype.kind in "iuf"
    else:
        numbers = all(isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_))
                      for x in value)
    if not numbers:
        raise InputTypeError(f"{name} must be {count} finite numbers, got {value!r}")
    try:
        v = np.array([float(x) for x in np.ravel(value)], np.float64).reshape(np.shape(value))
    except OverflowError:  # an int beyond float's range
        raise InputValueError(f"{name} must be {count} finite numbers, got {value!r}") from None
    if v.shape != (count,) or not np.isfinite(v).all():
        raise InputValueError(f"{name} must be {count} finite numbers, got {value!r}")
    return tuple(float(x) for x in v)


def _vector(value, name: str) -> tuple[float, float, float]:
    return _numbers(value, name, 3)


def _instances(value, name: str, kind: type, *, empty: bool = True) -> tuple:
    """``value`` as a tuple of ``kind`` instances (a tuple or list of them)."""
    if not isinstance(value, (tuple, list)) or not all(isinstance(v, kind) for v in value):
        raise InputTypeError(f"{name} must be a tuple of {kind.__name__}, got {value!r:.80}")
    if not value and not empty:
        raise InputValueError(f"{name} must hold at least one {kind.__name__}")
    return tuple(value)


def _rotation(rvec) -> np.ndarray:
    """Rotation matrix of an axis-angle vector (Rodrigues)."""
    r = np.asarray(rvec, dtype=np.float64)
    angle = float(np.linalg.norm(r))
    if angle == 0.0:
        return np.eye(3)
    k = r / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


@dataclass(frozen=True)
class Texture:
    """An achromatic modulation of a region's albedo, with mean 1, fixed to the surface.

    Parameters
    ----------
    kind : {"flat", "noise", "stripes", "gradient", "blobs"}
        "noise": random dots (value noise on a lattice of cell ``scale``, smoothly interpolated);
        "stripes": a sinusoid of period ``scale``; "gradient": a smooth ramp ``tanh(a / scale)`` about
        the face origin; "blobs": dark Gaussian blobs of standard deviation ``size``, at most one per
        lattice cell of side ``scale``, present with probability ``fill`` (textons for the texture
        module: density is set by ``scale`` and ``fill``).
    scale : float
        Length in world units (cell side, period or ramp length).
    contrast : float
        Amplitude of the modulation, in [0, 1).
    angle : float
        Direction of stripes and gradient in the face's (u, v) coordinates, radians.
    size : float
        Blob standard deviation in world units (blobs only; ``6 * size <= scale``).
    fill : float
        Share of cells holding a blob (blobs only).
    """

    kind: str = "flat"
    scale: float = 1.0
    contrast: float = 0.0
    angle: float = 0.0
    size: float = 0.0
    fill: float = 1.0

    def __post_init__(self):
        if not isinstance(self.kind, str) or self.kind not in ("flat", "noise", "stripes", "gradient", "blobs"):
            raise InputValueError(f"texture kind must be flat, noise, stripes, gradient or blobs: {self.kind!r}")
        check_real(self.scale, "texture scale", above=0)
        check_real(self.contrast, "texture contrast", minimum=0, below=1)
        check_real(self.angle, "texture angle")
        check_real(self.size, "texture size", minimum=0)
        check_real(self.fill, "texture fill", minimum=0, maximum=1)
        # The relative slack admits 6 * size == scale computed in floating point (the presets use it).
        fits = self.size > 0 and 6 * self.size <= self.scale * (1 + 1e-9) and 0 <= self.fill <= 1
        if self.kind == "blobs" and not fits:
            raise InputValueError("blobs need size > 0, 6 * size <= scale and fill in [0, 1]")


@dataclass(frozen=True)
class Mark:
    """A painted region of a face: its own colour, and optionally its own texture.

    Parameters
    ----------
    shape : {"rect", "disc"}
    bounds : tuple of float
        In the face's (s, t) coordinates: (s0, t0, s1, t1) for a rect, (s, t, radius) for a disc.
    colour : (3,) floats
        Albedo rho (RGB, each in [0, 1]).
    texture : Texture, optional
        Default: the face's texture, continuing its pattern across the mark's edge.
    """

    shape: str
    bounds: tuple[float, ...]
    colour: tuple[float, float, float]
    texture: Texture | None = None

    def __post_init__(self):
        expected = {"rect": 4, "disc": 3}.get(self.shape) if isinstance(self.shape, str) else None
        if expected is None:
            raise InputValueError(f"mark shape must be 'rect' or 'disc', got {self.shape!r}")
        if not isinstance(self.bounds, (tuple, list, np.ndarray)) or len(self.bounds) != expected:
            raise InputValueError(f"a {self.shape} mark needs {expected} bounds, got {self.bounds!r}")
        _numbers(self.bounds, f"{self.shape} mark bounds", expected)
        _albedo(self.colour, "mark colour")
        if self.texture is not None and not isinstance(self.texture, Texture):
            raise InputTypeError(f"mark texture must be a Texture or None, got {type(self.texture).__name__}")

    def contains(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        if self.shape == "rect":
            s0, t0, s1, t1 = self.bounds
            return (s >= s0) & (s < s1) & (t >= t0) & (t < t1)
        cs, ct, r = self.bounds
        return (s - cs) ** 2 + (t - ct) ** 2 < r * r


def _albedo(colour, name: str) -> tuple[float, float, float]:
    c = _vector(colour, name)
    if min(c) < 0 or max(c) > 1:
        raise InputValueError(f"{name} must be in [0, 1], got {colour!r}")
    return c


@dataclass(frozen=True)
class Face:
    """A planar face: points ``origin + s u_axis + t v_axis``, 0 <= s <= size[0], 0 <= t <= size[1].

    Parameters
    ----------
    origin, u_axis, v_axis : (3,) floats
        The axes must be orthonormal. Faces are seen from both sides; shading uses the side facing
        the camera.
    size : (float, float) or None
        Extent along the axes; None for an unbounded plane (s, t anywhere).
    colour : (3,) floats
        Albedo of the face outside its marks.
    texture : Texture
    marks : tuple of Mark
        Painted regions; a later mark covers an earlier one.
    """

    origin: tuple[float, float, float]
    u_axis: tuple[float, float, float]
    v_axis: tuple[float, float, float]
    size: tuple[float, float] | None
    colour: tuple[float, float, float]
    texture: Texture = Texture()
    marks: tuple[Mark, ...] = ()

    def __post_init__(self):
        u = np.array(_vector(self.u_axis, "u_axis"))
        v = np.array(_vector(self.v_axis, "v_axis"))
        _vector(self.origin, "origin")
        if abs(u @ u - 1) > 1e-6 or abs(v @ v - 1) > 1e-6 or abs(u @ v) > 1e-6:
            raise InputValueError(f"u_axis and v_axis must be orthonormal, got {self.u_axis} and {self.v_axis}")
        if self.size is not None and min(_numbers(self.size, "size", 2)) <= 0:
            raise InputValueError(f"size must be two positive extents or None, got {self.size!r}")
        _albedo(self.colour, "colour")
        if not isinstance(self.texture, Texture):
            raise InputTypeError(f"texture must be a Texture, got {type(self.texture).__name__}")
        _instances(self.marks, "marks", Mark)


@dataclass(frozen=True)
class Motion:
    """A rigid motion from frame t to t + 1: rotate by ``rotation`` about ``centre``, then translate.

    Parameters
    ----------
    translation : (3,) floats
        World units.
    rotation : (3,) floats
        Axis-angle vector, radians.
    centre : (3,) floats
        Point the rotation turns about.
    """

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        for name in ("translation", "rotation", "centre"):
            _vector(getattr(self, name), name)

    def matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """(R, t) with ``p(t + 1) = R p(t) + t``."""
        rot = _rotation(_vector(self.rotation, "rotation"))
        c = np.array(_vector(self.centre, "centre"))
        return rot, c + np.array(_vector(self.translation, "translation")) - rot @ c


@dataclass(frozen=True)
class Body:
    """A rigid set of faces that moves as one. Faces of one body meet only along folds."""

    faces: tuple[Face, ...]
    motion: Motion = Motion()
    name: str = ""

    def __post_init__(self):
        _instances(self.faces, "faces", Face, empty=False)
        if not isinstance(self.motion, Motion):
            raise InputTypeError(f"motion must be a Motion, got {type(self.motion).__name__}")
        if not isinstance(self.name, str):
            raise InputTypeError(f"name must be a str, got {type(self.name).__name__}")


@dataclass(frozen=True)
class Light:
    """One distant source, its ambient share, an illumination gradient and an optional highlight.

    Parameters
    ----------
    direction : (3,) floats
        Towards the light (normalised here).
    colour : (3,) floats
        k^nu, the source's colour (ambient light has the same colour).
    ambient : float
        Share of the illumination that reaches every point, in [0, 1]; at 1 there is no shading.
    gradient, gradient_origin : (3,) floats
        ``g(P) = exp(gradient . (P - gradient_origin))``; gradient in log-intensity per world unit.
    specular : float
        Strength of the Blinn-Phong highlight (0: off, the image model holds exactly).
    shininess : float
        Blinn-Phong exponent.
    """

    direction: tuple[float, float, float] = (-0.4, -0.6, -0.7)
    colour: tuple[float, float, float] = (1.0, 1.0, 1.0)
    ambient: float = 0.3
    gradient: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gradient_origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    specular: float = 0.0
    shininess: float = 60.0

    def __post_init__(self):
        if np.linalg.norm(_vector(self.direction, "direction")) == 0:
            raise InputValueError("light direction must be non-zero")
        _albedo(self.colour, "light colour")
        _vector(self.gradient, "gradient")
        _vector(self.gradient_origin, "gradient_origin")
        check_real(self.ambient, "ambient", minimum=0, maximum=1)
        check_real(self.specular, "specular", minimum=0)
        check_real(self.shininess, "shininess", above=0)


@dataclass(frozen=True)
class Camera:
    """A rectified stereo rig.

    Parameters
    ----------
    shape : (int, int)
        Image height and width, each 64..1024.
    focal : float
        Focal length in pixels.
    baseline : float
        Distance from the left to the right camera, world units (the right camera is at +x).
    motion : Motion
        The rig's motion from t to t + 1 (about the left camera's centre unless ``centre`` says else).
    """

    shape: tuple[int, int]
    focal: float
    baseline: float
    motion: Motion = Motion()

    def __post_init__(self):
        if not isinstance(self.shape, (tuple, list)) or len(self.shape) != 2:
            raise InputValueError(f"shape must be (height, width) with each in 64..1024, got {self.shape!r}")
        for k, n in enumerate(self.shape):
            check_int(n, f"shape[{k}] (each side in 64..1024)", minimum=64, maximum=1024)
        check_real(self.focal, "focal", above=0)
        check_real(self.baseline, "baseline", above=0)
        if not isinstance(self.motion, Motion):
            raise InputTypeError(f"motion must be a Motion, got {type(self.motion).__name__}")


@dataclass(frozen=True)
class World:
    """Bodies, one light and a stereo rig."""

    camera: Camera
    light: Light
    bodies: tuple[Body, ...]

    def __post_init__(self):
        if not isinstance(self.camera, Camera):
            raise InputTypeError(f"camera must be a Camera, got {type(self.camera).__name__}")
        if not isinstance(self.light, Light):
            raise InputTypeError(f"light must be a Light, got {type(self.light).__name__}")
        _instances(self.bodies, "bodies (a world needs at least one body)", Body, empty=False)


def box(centre, size, *, colour, texture: Texture = Texture(), rotation=(0.0, 0.0, 0.0)) -> tuple[Face, ...]:
    """The six faces of a box.

    Parameters
    ----------
    centre : (3,) floats
    size : (3,) floats
        Side lengths along the box's own x, y, z axes.
    colour : (3,) floats
    texture : Texture
    rotation : (3,) floats
        Axis-angle rotation of the box about its centre, radians.

    Returns
    -------
    tuple of Face
    """
    rot = _rotation(_vector(rotation, "rotation"))
    half = np.asarray(_vector(size, "size"), dtype=np.float64) / 2
    if min(half) <= 0:
        raise InputValueError(f"size must be three positive side lengths, got {size!r}")
    c = np.asarray(_vector(centre, "centre"), dtype=np.float64)
    faces = []
    for axis in range(3):
        a, b = [(1, 2), (2, 0), (0, 1)][axis]
        for sign in (-1, 1):
            origin = c + rot[:, axis] * sign * half[axis] - rot[:, a] * half[a] - rot[:, b] * half[b]
            faces.append(Face(tuple(origin), tuple(rot[:, a]), tuple(rot[:, b]), (2 * half[a], 2 * half[b]),
                              colour, texture))
    return tuple(faces)


def fold(left, crease, right, height: float, *, colour, texture: Texture = Texture(),
         marks: tuple[tuple[Mark, ...], tuple[Mark, ...]] = ((), ())) -> tuple[Face, Face]:
    """Two vertical panels meeting along a vertical crease: an orientation discontinuity.

    Parameters
    ----------
    left, crease, right : (3,) floats
        Top ends of the left edge, the crease and the right edge (same y); the panels hang down
        (towards +y) by ``height``.
    height : float
    colour : (3,) floats
    texture : Texture
    marks : pair of tuples of Mark
        Marks of the left and right panels.

    Returns
    -------
    (Face, Face)
    """
    points = [np.asarray(_vector(p, name), dtype=np.float64)
              for p, name in ((left, "left"), (crease, "crease"), (right, "right"))]
    height = check_real(height, "height", above=0)
    if not (isinstance(marks, (tuple, list)) and len(marks) == 2):
        raise InputTypeError(f"marks must be a pair of tuples of Mark, got {marks!r:.80}")
    faces = []
    for (a, b), panel_marks in zip(((points[0], points[1]), (points[1], points[2])), marks):
        along = b - a
        if abs(along[1]) > 1e-9:
            raise InputValueError("left, crease and right must have the same y")
        width = float(np.linalg.norm(along))
        if width == 0:
            raise InputValueError("left, crease and right must be distinct points")
        faces.append(Face(tuple(a), tuple(along / width), (0.0, 1.0, 0.0), (width, height), colour, texture,
                          panel_marks))
    return faces[0], faces[1]


# --------------------------------------------------------------------------------------------- textures

# Points and directions are (3, N) float32 arrays (structure of arrays): NumPy's (N, 3) @ (3,) products
# measured 10 to 40 times slower than three scaled rows added.


def _dot(v, points: np.ndarray):
    """v . p for a 3-vector v and (3, N) points, or a float for one (3,) point."""
    if points.ndim == 1:
        return float(np.dot(v, points))
    return points[0] * F32(v[0]) + points[1] * F32(v[1]) + points[2] * F32(v[2])


def _apply(rot: np.ndarray, trans: np.ndarray, points: np.ndarray) -> np.ndarray:
    """rot @ p + trans for (3, N) points."""
    return np.stack([_dot(rot[k], points) + F32(trans[k]) for k in range(3)])


def _hash01(i: np.ndarray, j: np.ndarray, key: int) -> np.ndarray:
    """Uniform [0, 1) from integer lattice coordinates and a key (splitmix64 finaliser)."""
    with np.errstate(over="ignore"):
        x = (i.astype(np.int64).view(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
             ^ j.astype(np.int64).view(np.uint64) * np.uint64(0xC2B2AE3D27D4EB4F)
             ^ np.uint64(key & 0xFFFFFFFFFFFFFFFF))
        x ^= x >> np.uint64(30)
        x *= np.uint64(0xBF58476D1CE4E5B9)
        x ^= x >> np.uint64(27)
        x *= np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
    return ((x >> np.uint64(40)).astype(np.float32)) * F32(2.0**-24)


class _Lattice:
    """Random values of the lattice cells a set of pixels touches, hashed once per cell, not per pixel."""

    def __init__(self, i: np.ndarray, j: np.ndarray, key: int):
        self.i0, self.j0 = int(i.min()), int(j.min())
        shape = (int(i.max()) - self.i0 + 2, int(j.max()) - self.j0 + 2)
        self.key = key
        # A grazing plane can span more cells than there are pixels: then hash per pixel.
        self.table = None
        if shape[0] * shape[1] <= i.size:
            ii, jj = np.meshgrid(np.arange(shape[0]) + self.i0, np.arange(shape[1]) + self.j0, indexing="ij")
            self.table = ii, jj

    def __call__(self, i: np.ndarray, j: np.ndarray, offset: int = 0) -> np.ndarray:
        if self.table is None:
            return _hash01(i, j, self.key + offset)
        values = _hash01(*self.table, self.key + offset)
        return values[i - self.i0, j - self.j0]


def _modulation(texture: Texture, s: np.ndarray, t: np.ndarray, key: int) -> np.ndarray:
    c = F32(texture.contrast)
    if texture.kind == "flat" or c == 0:
        return np.ones_like(s)
    if texture.kind in ("stripes", "gradient"):
        a = s * F32(math.cos(texture.angle)) + t * F32(math.sin(texture.angle))
        if texture.kind == "stripes":
            return 1 + c * np.sin(a * F32(2 * math.pi / texture.scale))
        return 1 + c * np.tanh(a / F32(texture.scale))
    fs, ft = s / F32(texture.scale), t / F32(texture.scale)
    i, j = np.floor(fs), np.floor(ft)
    fx, fy = fs - i, ft - j
    i, j = i.astype(np.int64), j.astype(np.int64)
    cell = _Lattice(i, j, key)
    if texture.kind == "noise":
        wx, wy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
        top = cell(i, j) * (1 - wx) + cell(i + 1, j) * wx
        bottom = cell(i, j + 1) * (1 - wx) + cell(i + 1, j + 1) * wx
        return 1 + c * (2 * (top * (1 - wy) + bottom * wy) - 1)
    # Blobs: one per cell at most, kept 3 sigma inside it, so a pixel needs only its own cell.
    sigma = texture.size / texture.scale
    margin, span = 3 * sigma, 1 - 6 * sigma
    bx = margin + span * cell(i, j, 1)
    by = margin + span * cell(i, j, 2)
    present = cell(i, j) < texture.fill
    blob = np.exp(((fx - bx) ** 2 + (fy - by) ** 2) * F32(-0.5 / sigma**2)) * present
    mean = 1 - texture.contrast * texture.fill * 2 * math.pi * sigma**2
    return (1 - c * blob) / F32(mean)


# --------------------------------------------------------------------------------------------- views


@dataclass
class _Faces:
    """All faces as arrays, in one camera's frame at one time."""

    origin: np.ndarray  # (F, 3)
    u: np.ndarray
    v: np.ndarray
    normal: np.ndarray
    extent: np.ndarray  # (F, 2), inf for unbounded planes
    corners: np.ndarray  # (F, 4, 3), NaN for unbounded planes

    @classmethod
    def of(cls, faces: list[Face], rot: list[np.ndarray], trans: list[np.ndarray]) -> _Faces:
        origin = np.array([r @ f.origin + t for f, r, t in zip(faces, rot, trans)])
        u = np.array([r @ f.u_axis for f, r in zip(faces, rot)])
        v = np.array([r @ f.v_axis for f, r in zip(faces, rot)])
        extent = np.array([f.size or (np.inf, np.inf) for f in faces], dtype=np.float64)
        corners = np.full((len(faces), 4, 3), np.nan)
        for k, (a, b) in enumerate(extent):
            if np.isfinite(a):
                corners[k] = [origin[k] + x * u[k] + y * v[k] for x, y in ((0, 0), (a, 0), (a, b), (0, b))]
        return cls(origin, u, v, np.cross(u, v), extent, corners)


def _boxes(corners: np.ndarray, project) -> np.ndarray:
    """Per face (x0, x1, y0, y1) of the projected corners; infinite where a face cannot be bounded."""
    boxes = np.tile(np.array([-np.inf, np.inf, -np.inf, np.inf]), (len(corners), 1))
    for k, c in enumerate(corners):
        if np.isfinite(c).all():
            p = project(c)
            if p is not None:
                boxes[k] = (p[:, 0].min(), p[:, 0].max(), p[:, 1].min(), p[:, 1].max())
    return boxes


class _Camera:
    """Pinhole projection of one view."""

    def __init__(self, camera: Camera):
        self.h, self.w = camera.shape
        self.f = float(camera.focal)
        self.cx, self.cy = (self.w - 1) / 2, (self.h - 1) / 2
        self.rx = ((np.arange(self.w) - self.cx) / self.f).astype(F32)
        self.ry = ((np.arange(self.h) - self.cy) / self.f).astype(F32)

    def project(self, points: np.ndarray) -> np.ndarray | None:
        """Pixel coordinates of (K, 3) points all in front of the camera (else None)."""
        if (points[:, 2] <= _NEAR).any():
            return None
        return np.stack([self.f * points[:, 0] / points[:, 2] + self.cx,
                         self.f * points[:, 1] / points[:, 2] + self.cy], axis=-1)

    def pixel(self, points: np.ndarray) -> np.ndarray:
        """(2, N) pixel coordinates of (3, N) points (meaningless behind the camera)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.stack([F32(self.f) * points[0] / points[2] + F32(self.cx),
                             F32(self.f) * points[1] / points[2] + F32(self.cy)])

    def cast(self, faces: _Faces) -> tuple[np.ndarray, np.ndarray]:
        """Depth (inf: nothing) and face index (-1) of the nearest face along each pixel's ray."""
        depth = np.full((self.h, self.w), np.inf, F32)
        index = np.full((self.h, self.w), -1, np.int32)
        boxes = _boxes(faces.corners, self.project)
        for g in range(len(faces.origin)):
            x0, x1, y0, y1 = boxes[g]
            if np.isfinite(x0):
                xs = slice(max(0, math.floor(x0)), min(self.w, math.ceil(x1) + 1))
                ys = slice(max(0, math.floor(y0)), min(self.h, math.ceil(y1) + 1))
            else:
                xs, ys = slice(0, self.w), slice(0, self.h)
            if xs.start >= xs.stop or ys.start >= ys.stop:
                continue
            rx, ry = self.rx[xs][None, :], self.ry[ys][:, None]
            n, o = faces.normal[g], faces.origin[g]
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = F32(n @ o) / (F32(n[0]) * rx + F32(n[1]) * ry + F32(n[2]))
            window = depth[ys, xs]
            hit = (lam > _NEAR) & (lam < window)
            a, b = faces.extent[g]
            if np.isfinite(a):
                u, v = faces.u[g], faces.v[g]
                s = lam * (F32(u[0]) * rx + F32(u[1]) * ry + F32(u[2])) - F32(u @ o)
                t = lam * (F32(v[0]) * rx + F32(v[1]) * ry + F32(v[2])) - F32(v @ o)
                hit &= (s >= 0) & (s <= a) & (t >= 0) & (t <= b)
            window[hit] = lam[hit]
            index[ys, xs][hit] = g
        return depth, index


def _blocked(faces: _Faces, start: np.ndarray, direction: np.ndarray, far: float, own: np.ndarray,
             keys: np.ndarray, boxes: np.ndarray, eps: float) -> np.ndarray:
    """Whether ``start + mu direction`` meets a face other than ``own`` for mu in (eps, far).

    ``start`` and ``direction`` are (3, N) or one (3,) vector. ``keys`` (2, N) are coordinates constant
    along each segment (its image point, or its position across the light), and ``boxes`` each face's
    range of them, so a face is tested only where it can block.
    """
    blocked = np.zeros(own.shape, dtype=bool)
    for g in range(len(faces.origin)):
        x0, x1, y0, y1 = boxes[g]
        candidate = own != g
        if np.isfinite(x0):
            candidate &= (keys[0] >= x0) & (keys[0] <= x1) & (keys[1] >= y0) & (keys[1] <= y1)
        idx = np.flatnonzero(candidate & ~blocked)
        if idx.size == 0:
            continue
        p = start[:, idx] if start.ndim == 2 else start
        d = direction[:, idx] if direction.ndim == 2 else direction
        n, o = faces.normal[g], faces.origin[g]
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = (F32(n @ o) - _dot(n, p)) / _dot(n, d)
        hit = (mu > eps) & (mu < far)
        a, b = faces.extent[g]
        if np.isfinite(a):
            u, v = faces.u[g], faces.v[g]
            s = _dot(u, p) + mu * _dot(u, d) - F32(u @ o)
            t = _dot(v, p) + mu * _dot(v, d) - F32(v @ o)
            hit &= (s >= 0) & (s <= a) & (t >= 0) & (t <= b)
        blocked[idx[hit]] = True
    return blocked


def _camera_blocked(cam: _Camera, faces: _Faces, points: np.ndarray, own: np.ndarray) -> np.ndarray:
    """Whether the segment from this camera's centre to each (3, N) point meets another face (or the
    point is behind the camera)."""
    behind = points[2] <= _NEAR
    keys = cam.pixel(points)
    keys[:, behind] = np.nan
    boxes = _boxes(faces.corners, cam.project)
    return behind | _blocked(faces, np.zeros(3), points, 1 - _EPS, own, keys, boxes, _EPS)


# --------------------------------------------------------------------------------------------- shading


@dataclass
class _Surface:
    """What one view sees: per-pixel geometry and the physical terms of the image model."""

    depth: np.ndarray  # (H, W), inf where nothing
    index: np.ndarray  # (H, W) face index, -1
    points: np.ndarray  # (3, N) view-frame points of the pixels with a face (raster order)
    pixels: np.ndarray  # (N,) flat pixel indices
    face: np.ndarray  # (N,) face index
    region: np.ndarray  # (N,) global region id
    albedo: np.ndarray  # (N, 3)
    illumination: np.ndarray  # (N,)
    specular: np.ndarray  # (N,)
    shadow: np.ndarray  # (N,) bool
    highlight: np.ndarray  # (N,) bool


@dataclass
class _Regions:
    """Every albedo region of the world: its colour, texture and texture key."""

    first: list[int]  # first region id of each face
    colour: np.ndarray  # (R, 3)
    hue: np.ndarray  # (R,) id of the colour; equal colours, equal ids
    look: np.ndarray  # (R,) id of (texture, key); equal looks continue one pattern
    textures: list[tuple[Texture, int]]

    @classmethod
    def of(cls, faces: list[Face], seed: int) -> _Regions:
        first, colours, looks, textures, seen = [], [], [], [], {}
        for k, face in enumerate(faces):
            first.append(len(colours))
            looks_of_face = [(face.colour, None)] + [(mk.colour, mk.texture) for mk in face.marks]
            for m, (colour, texture) in enumerate(looks_of_face):
                # A mark without its own texture continues its face's pattern: same texture, same key.
                own = texture is not None
                item = (texture if own else face.texture, _seed_key(seed, k, m if own else 0))
                look = seen.setdefault(item, len(seen))
                if look == len(textures):
                    textures.append(item)
                colours.append(colour)
                looks.append(look)
        colour = np.array(colours, F32)
        hue = np.unique(colour, axis=0, return_inverse=True)[1].ravel()
        return cls(first, colour, hue, np.array(looks), textures)


def _seed_key(seed: int, face: int, mark: int) -> int:
    return int(np.random.SeedSequence([seed, face, mark]).generate_state(1, np.uint64)[0])


def _shade(cam: _Camera, faces: _Faces, world: World, spec: list[Face], regions: _Regions,
           world_to_view: tuple[np.ndarray, np.ndarray]) -> _Surface:
    """Ray cast one view and evaluate albedo, effective illumination, shadow and highlight."""
    depth, index = cam.cast(faces)
    pixels = np.flatnonzero(index.ravel() >= 0)
    ys, xs = np.divmod(pixels, cam.w)
    z = depth.ravel()[pixels]
    points = np.stack([cam.rx[xs] * z, cam.ry[ys] * z, z])
    face = index.ravel()[pixels]
    n = len(pixels)
    light = world.light
    rot, trans = world_to_view
    to_light = (rot @ (np.asarray(light.direction) / np.linalg.norm(light.direction))).astype(F32)
    region, albedo = np.zeros(n, np.int32), np.zeros((n, 3), F32)
    cosine = np.zeros(n, F32)
    normals = np.zeros((len(spec), 3))
    for g, f in enumerate(spec):
        sel = np.flatnonzero(face == g)
        if sel.size == 0:
            continue
        p = points[:, sel]
        s = _dot(faces.u[g], p) - F32(faces.u[g] @ faces.origin[g])
        t = _dot(faces.v[g], p) - F32(faces.v[g] @ faces.origin[g])
        local = np.zeros(sel.size, np.int32)
        for m, mark in enumerate(f.marks):
            local[mark.contains(s, t)] = m + 1
        region[sel] = regions.first[g] + local
        for r in np.flatnonzero(np.bincount(local)):
            inside = local == r
            rid = regions.first[g] + r
            texture, key = regions.textures[regions.look[rid]]
            modulation = _modulation(texture, s[inside], t[inside], key)
            albedo[sel[inside]] = regions.colour[rid] * modulation[:, None]
        # Shade the side of the face that looks at the camera (the view's centre is its origin).
        normals[g] = faces.normal[g] if faces.normal[g] @ faces.origin[g] < 0 else -faces.normal[g]
        cosine[sel] = normals[g] @ to_light

    lit = cosine > 0
    shadow = np.zeros(n, dtype=bool)
    if light.ambient < 1 and lit.any():
        # Coordinates across the light are constant along a shadow ray: cull faces by them.
        across = np.linalg.svd(to_light[None, :])[2][1:]
        idx = np.flatnonzero(lit)
        p = points[:, idx]
        keys = np.stack([_dot(across[0], p), _dot(across[1], p)])
        eps = _EPS * float(np.abs(z).max())
        shadow[idx] = _blocked(faces, p, to_light, np.inf, face[idx], keys,
                               _boxes(faces.corners, lambda c: c @ across.T), eps)
    # gradient . world point = (rot gradient) . (view point - trans)
    gradient = rot @ np.asarray(light.gradient)
    offset = gradient @ trans + np.dot(light.gradient, light.gradient_origin)
    gain = np.exp(_dot(gradient, points) - F32(offset)) if gradient.any() else np.ones(n, F32)
    direct = np.where(shadow, F32(0), np.maximum(cosine, 0))
    illumination = gain * (F32(light.ambient) + F32(1 - light.ambient) * direct)
    specular = np.zeros(n, F32)
    highlight = np.zeros(n, dtype=bool)
    if light.specular > 0:
        half = to_light[:, None] - points / np.sqrt(_dot(points, points))
        facing = np.maximum(np.einsum("ij,ij->j", normals[face].T.astype(F32), half), 0)
        lobe = np.where(lit & ~shadow, facing / np.sqrt(_dot(half, half)), 0) ** F32(light.shininess)
        specular = (F32(light.specular) * gain * lobe).astype(F32)
        highlight = lobe >= 0.5
    return _Surface(depth, index, points, pixels, face, region, albedo, illumination.astype(F32), specular,
                    shadow, highlight)


def _image(surface: _Surface, cam: _Camera, colour: np.ndarray, noise: float,
           rng: np.random.Generator) -> np.ndarray:
    image = np.full((cam.h * cam.w, 3), np.nan, F32)
    radiance = surface.illumination[:, None] * surface.albedo + surface.specular[:, None]
    image[surface.pixels] = colour * radiance
    image = image.reshape(cam.h, cam.w, 3)
    if noise > 0:
        image += rng.standard_normal(image.shape, dtype=F32) * F32(noise)
    return image


# --------------------------------------------------------------------------------------------- labels


def _labels(depth, body, face, hue, look, region, shadow, highlight):
    """Labels of the line sites between horizontal and vertical neighbours, and of the pixels."""

    def sites(a, b):
        code = np.zeros(body[a].shape, np.uint8)
        code[highlight[a] != highlight[b]] = Label.SPECULAR
        code[shadow[a] != shadow[b]] = Label.SHADOW
        other = region[a] != region[b]
        same_colour = hue[a] == hue[b]
        code[other & same_colour & (look[a] != look[b])] = Label.TEXTURE
        code[other & ~same_colour] = Label.ALBEDO
        code[face[a] != face[b]] = Label.ORIENTATION
        code[body[a] != body[b]] = Label.DEPTH
        return code

    h, w = depth.shape
    line_h = sites((slice(None), slice(0, -1)), (slice(None), slice(1, None)))
    line_v = sites((slice(0, -1), slice(None)), (slice(1, None), slice(None)))
    rank = np.full(len(Label), len(_PRECEDENCE), np.int64)
    rank[list(_PRECEDENCE)] = np.arange(len(_PRECEDENCE))
    best = np.full((h, w), len(_PRECEDENCE), np.int64)
    for code, step in ((line_h, (0, 1)), (line_v, (1, 0))):
        ys, xs = np.nonzero(code)
        ys2, xs2 = ys + step[0], xs + step[1]
        # A DEPTH site labels its nearer pixel: the occluding contour belongs to the occluder.
        far = (code[ys, xs] == Label.DEPTH) & (depth[ys2, xs2] < depth[ys, xs])
        np.minimum.at(best, (np.where(far, ys2, ys), np.where(far, xs2, xs)), rank[code[ys, xs]])
    labels = np.zeros((h, w), np.uint8)
    has = best < len(_PRECEDENCE)
    labels[has] = np.array(_PRECEDENCE, np.uint8)[best[has]]
    return labels, line_h, line_v


# --------------------------------------------------------------------------------------------- render


@dataclass(frozen=True)
class Scene:
    """A rendered stereo pair, the left view's next frame, and the left view's ground truth at t.

    Attributes
    ----------
    world : World
    seed : int
    noise : float
        Standard deviation of the Gaussian noise added to each image.
    left, right, left_next : (H, W, 3) float32 arrays
        RGB images (left and right at t, left at t + 1); NaN where no surface is seen.
    depth : (H, W) float32
        z of the surface point (not the distance along the ray); NaN where no surface.
    disparity : (H, W) float32
        ``focal * baseline / depth``.
    flow : (H, W, 2) float32
        (u, v) from t to t + 1; NaN where no surface, or the point is behind the camera at t + 1.
    albedo : (H, W, 3) float32
        rho^nu.
    illumination : (H, W) float32
        Effective illumination E.
    specular : (H, W) float32
        Specular term S (zero when the light's specular strength is 0).
    light_colour : (3,) float32
        k^nu: ``left = light_colour * (illumination * albedo + specular)`` before noise.
    shadow : (H, W) bool
        Lit-facing points in a cast shadow.
    occluded_stereo : (H, W) bool
        Points the right camera does not see (hidden, or outside its image).
    occluded_motion : (H, W) bool
        Points the left camera does not see at t + 1 (hidden, or outside the image).
    labels : (H, W) uint8
        :class:`Label` codes on the pixel grid (see the module notes for which pixel carries a label).
    line_h : (H, W - 1) uint8
        Labels of the sites between (y, x) and (y, x + 1).
    line_v : (H - 1, W) uint8
        Labels of the sites between (y, x) and (y + 1, x).
    regions, surfaces, bodies : (H, W) int32
        Albedo region, face and body of each pixel (-1: none); region ids are unique in the world.
    """

    world: World
    seed: int
    noise: float
    left: np.ndarray
    right: np.ndarray
    left_next: np.ndarray
    depth: np.ndarray
    disparity: np.ndarray
    flow: np.ndarray
    albedo: np.ndarray
    illumination: np.ndarray
    specular: np.ndarray
    light_colour: np.ndarray
    shadow: np.ndarray
    occluded_stereo: np.ndarray
    occluded_motion: np.ndarray
    labels: np.ndarray
    line_h: np.ndarray
    line_v: np.ndarray
    regions: np.ndarray
    surfaces: np.ndarray
    bodies: np.ndarray

    @property
    def focal(self) -> float:
        return self.world.camera.focal

    @property
    def baseline(self) -> float:
        return self.world.camera.baseline


def _grid(cam: _Camera, values: np.ndarray, pixels: np.ndarray, fill) -> np.ndarray:
    out = np.full((cam.h * cam.w, *values.shape[1:]), fill, dtype=values.dtype)
    out[pixels] = values
    return out.reshape(cam.h, cam.w, *values.shape[1:])


def render(world: World, *, seed: int = 0, noise: float = 0.0) -> Scene:
    """Render the left and right views at t, the left view at t + 1, and the ground truth.

    Parameters
    ----------
    world : World
        Geometry, light and cameras (see :func:`preset` for ready-made ones).
    seed : int
        Seeds the random textures and the noise; the same seed gives the same bits.
    noise : float
        Standard deviation of Gaussian noise added independently to every pixel, channel and image.

    Returns
    -------
    Scene

    Notes
    -----
    Each pixel's ray is cast against every face (culled by the face's projected bounding box); shadows
    and occlusions are exact segment tests against the faces. A 512 x 512 scene with ten faces
    renders in about 0.3 s on two cores (benchmarks/results/ground_truth.md).

    Examples
    --------
    >>> from vmcl import scenes
    >>> scene = scenes.render(scenes.preset("blocks", shape=(128, 128)), seed=0)
    >>> scene.left.shape, scene.disparity.dtype
    ((128, 128, 3), dtype('float32'))
    >>> bool((scene.labels == scenes.Label.SHADOW).any())
    True
    """
    if not isinstance(world, World):
        raise InputTypeError(f"world must be a World (see vmcl.scenes.preset), got {type(world).__name__}")
    check_int(seed, "seed", minimum=0)
    check_real(noise, "noise (a standard deviation)", minimum=0)
    cam = _Camera(world.camera)
    spec = [f for b in world.bodies for f in b.faces]
    owner = np.array([k for k, b in enumerate(world.bodies) for _ in b.faces])
    regions = _Regions.of(spec, int(seed))
    eye, zero = np.eye(3), np.zeros(3)
    baseline = np.array([world.camera.baseline, 0.0, 0.0])
    # Frame t + 1: each body's motion, then into the moved rig's frame.
    rig_rot, rig_t = world.camera.motion.matrix()
    to_next = []
    for b in world.bodies:
        r, t = b.motion.matrix()
        to_next.append((rig_rot.T @ r, rig_rot.T @ (t - rig_t)))
    next_rot = [to_next[k][0] for k in owner]
    next_trans = [to_next[k][1] for k in owner]

    faces_left = _Faces.of(spec, [eye] * len(spec), [zero] * len(spec))
    faces_right = _Faces.of(spec, [eye] * len(spec), [-baseline] * len(spec))
    faces_next = _Faces.of(spec, next_rot, next_trans)
    left = _shade(cam, faces_left, world, spec, regions, (eye, zero))
    right = _shade(cam, faces_right, world, spec, regions, (eye, -baseline))
    # The rig at t + 1 maps world points q to rig_rot.T (q - rig_t).
    nxt = _shade(cam, faces_next, world, spec, regions, (rig_rot.T, -rig_rot.T @ rig_t))

    colour = np.asarray(world.light.colour, F32)
    rngs = [np.random.default_rng([int(seed), view]) for view in range(3)]
    images = [_image(s, cam, colour, float(noise), g) for s, g in zip((left, right, nxt), rngs)]

    face, p = left.face, left.points
    right_points = p - np.array([[world.camera.baseline], [0.0], [0.0]], F32)
    moved = np.empty_like(p)
    for g in range(len(spec)):
        sel = np.flatnonzero(face == g)
        moved[:, sel] = _apply(next_rot[g], next_trans[g], p[:, sel])
    target = cam.pixel(moved)
    ys, xs = np.divmod(left.pixels, cam.w)
    flow = (target - np.stack([xs, ys]).astype(F32)).T
    flow[moved[2] <= _NEAR] = np.nan
    x_right = cam.pixel(right_points)[0]
    occluded_stereo = ((x_right < 0) | (x_right > cam.w - 1)
                       | _camera_blocked(cam, faces_right, right_points, face))
    inside = (target[0] >= 0) & (target[0] <= cam.w - 1) & (target[1] >= 0) & (target[1] <= cam.h - 1)
    occluded_motion = ~inside | _camera_blocked(cam, faces_next, moved, face)

    depth = np.where(np.isfinite(left.depth), left.depth, np.nan).astype(F32)
    surfaces = left.index
    bodies = np.where(surfaces >= 0, owner[np.maximum(surfaces, 0)], -1).astype(np.int32)
    region = _grid(cam, left.region, left.pixels, -1)
    shadow = _grid(cam, left.shadow, left.pixels, False)
    highlight = _grid(cam, left.highlight, left.pixels, False)
    labels, line_h, line_v = _labels(np.where(np.isfinite(depth), depth, np.inf), bodies, surfaces,
                                     _grid(cam, regions.hue[left.region], left.pixels, -1),
                                     _grid(cam, regions.look[left.region], left.pixels, -1),
                                     region, shadow, highlight)
    return Scene(
        world=world,
        seed=int(seed),
        noise=float(noise),
        left=images[0],
        right=images[1],
        left_next=images[2],
        depth=depth,
        disparity=(F32(cam.f * world.camera.baseline) / depth).astype(F32),
        flow=_grid(cam, flow.astype(F32), left.pixels, np.nan),
        albedo=_grid(cam, left.albedo, left.pixels, np.nan),
        illumination=_grid(cam, left.illumination, left.pixels, np.nan),
        specular=_grid(cam, left.specular, left.pixels, np.nan),
        light_colour=colour,
        shadow=shadow,
        occluded_stereo=_grid(cam, occluded_stereo, left.pixels, False),
        occluded_motion=_grid(cam, occluded_motion, left.pixels, False),
        labels=labels,
        line_h=line_h,
        line_v=line_v,
        regions=region,
        surfaces=surfaces,
        bodies=bodies,
    )


# --------------------------------------------------------------------------------------------- presets

PRESETS = ("blocks", "corridor", "shadows", "textures", "cues")
"""Names accepted by :func:`preset`."""

_BASELINE = 0.15


def _blocks(px, light: Light) -> tuple[tuple[Body, ...], Light, Motion]:
    wall = Face((0.0, 0.0, 8.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), None, (0.62, 0.56, 0.48),
                Texture("noise", px(6, 8), 0.35),
                (Mark("rect", (0.6, -3.2, 3.2, -1.4), (0.25, 0.45, 0.7)),
                 Mark("disc", (-2.3, -2.2, 0.9), (0.75, 0.3, 0.25),
                      Texture("gradient", 0.6, 0.4, angle=0.5))))
    c, s = math.cos(0.7), math.sin(0.7)
    slanted = Face((-2.3, -1.5, 5.0), (c, 0.0, s), (0.0, 1.0, 0.0), (1.6, 3.0), (0.55, 0.6, 0.7),
                   Texture("stripes", px(12, 5.5), 0.3),
                   (Mark("rect", (0.0, 1.9, 1.6, 2.4), (0.8, 0.7, 0.3)),))
    panels = fold((1.0, -1.3, 6.4), (1.8, -1.3, 5.6), (2.6, -1.3, 6.4), 2.6, colour=(0.7, 0.65, 0.55),
                  texture=Texture("noise", px(5, 6), 0.3),
                  marks=((), (Mark("rect", (0.2, 1.6, 0.9, 2.2), (0.3, 0.6, 0.35)),)))
    centre = (-0.3, 0.55, 4.2)
    cube = box(centre, (1.1, 0.9, 1.0), colour=(0.35, 0.62, 0.4), rotation=(0.0, 0.5, 0.0),
               texture=Texture("blobs", px(9, 4.2), 0.5, size=px(1.5, 4.2), fill=0.8))
    bodies = (Body((wall,), name="wall"), Body((slanted,), name="slanted plane"), Body(panels, name="fold"),
              Body(cube, Motion((0.12, -0.03, -0.1), (0.0, 0.04, 0.0), centre), name="box"))
    return bodies, light, Motion((0.04, 0.0, 0.0))


def _corridor(px, light: Light) -> tuple[tuple[Body, ...], Light, Motion]:
    # Open to the sky: under a distant light a roof would put the whole corridor in its shadow.
    x, top, floor, near, far = 1.5, -3.5, 1.1, -1.0, 16.0
    length, height = far - near, floor - top
    noise = Texture("noise", px(10, 6), 0.3)
    faces = (
        Face((-x, floor, near), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (2 * x, length), (0.55, 0.5, 0.45),
             Texture("noise", px(8, 6), 0.4), (Mark("rect", (1.1, 0.0, 1.9, length), (0.6, 0.2, 0.2)),)),
        Face((-x, top, near), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (length, height), (0.7, 0.68, 0.6), noise,
             (Mark("rect", (5.0, 2.5, 6.0, height), (0.45, 0.3, 0.2)),
              Mark("rect", (10.0, 2.5, 10.8, height), (0.45, 0.3, 0.2)))),
        Face((x, top, near), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (length, height), (0.66, 0.7, 0.62), noise,
             (Mark("rect", (7.0, 2.8, 8.2, 3.6), (0.3, 0.5, 0.75)),
              Mark("rect", (12.0, 2.7, 13.0, 3.7), (0.8, 0.65, 0.3)))),
        Face((-x, top, far), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (2 * x, height), (0.6, 0.6, 0.7),
             Texture("blobs", px(8, far), 0.5, size=px(1.2, far), fill=0.9)),
    )
    sky = Face((0.0, 0.0, 60.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), None, (0.75, 0.85, 0.95))
    crate = box((0.7, 0.5, 6.0), (0.8, 0.6, 0.8), colour=(0.75, 0.55, 0.3), rotation=(0.0, 0.3, 0.0),
                texture=Texture("noise", px(5, 6), 0.35))
    light = Light((0.2, -1.0, -0.35), light.colour, 0.35, specular=light.specular, shininess=light.shininess)
    bodies = (Body(faces, name="corridor"), Body((sky,), name="sky"),
              Body(crate, name="crate hovering above the floor"))
    return bodies, light, Motion((0.0, 0.0, 0.2), (0.0, 0.01, 0.0))


def _shadows(px, light: Light) -> tuple[tuple[Body, ...], Light, Motion]:
    columns, rows = (-3.0, -1.0, 0.8, 3.0), (-2.6, -0.2, 2.6)
    colours = ((0.8, 0.3, 0.25), (0.3, 0.6, 0.3), (0.25, 0.35, 0.75), (0.85, 0.75, 0.3), (0.6, 0.35, 0.65),
               (0.45, 0.7, 0.5))
    mondrian = tuple(Mark("rect", (columns[i], rows[j], columns[i + 1], rows[j + 1]), colours[3 * j + i])
                     for j in range(2) for i in range(3))
    wall = Face((0.0, 0.0, 7.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), None, (0.7, 0.7, 0.7), marks=mondrian)
    panels = fold((1.0, 0.2, 5.0), (1.6, 0.2, 4.5), (2.2, 0.2, 5.0), 1.6, colour=(0.4, 0.5, 0.8),
                  marks=((Mark("rect", (0.0, 0.0, 0.79, 0.8), (0.8, 0.5, 0.2)),),
                         (Mark("rect", (0.0, 0.8, 0.79, 1.6), (0.75, 0.3, 0.5)),)))
    plate = Face((-1.5, -1.1, 4.2), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0), (0.9, 0.85, 0.6))
    # A warm light: k^nu is not white, and H = R / (R + G) is still constant in each region.
    light = Light((-0.35, -0.45, -0.82), (1.0, 0.92, 0.8), 0.3, (-0.22, 0.05, 0.0), (-3.5, 0.0, 0.0),
                  light.specular, light.shininess)
    bodies = (Body((wall,), name="mondrian wall"), Body(panels, name="fold"),
              Body((plate,), Motion((0.05, 0.02, 0.0)), name="shadow caster"))
    return bodies, light, Motion()


def _textures(px, light: Light) -> tuple[tuple[Body, ...], Light, Motion]:
    z = 6.0

    def blobs(spacing, fill=0.9):
        return Texture("blobs", px(spacing, z), 0.6, size=px(1.0, z), fill=fill)

    grey = (0.6, 0.6, 0.6)
    wall = Face((0.0, 0.0, z), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), None, grey, blobs(10),
                (Mark("rect", (-3.0, -3.0, 0.0, 0.0), grey, blobs(6.5)),
                 Mark("rect", (0.0, 0.0, 3.0, 3.0), grey, blobs(16)),
                 Mark("disc", (0.0, 0.0, 0.9), grey, blobs(10, fill=0.3))))
    light = Light((0.0, -0.3, -1.0), light.colour, 0.5, specular=light.specular, shininess=light.shininess)
    return (Body((wall,), name="blob mosaic"),), light, Motion((0.05, 0.02, 0.0))


def _cues(px, light: Light) -> tuple[tuple[Body, ...], Light, Motion]:
    grey = (0.5, 0.5, 0.5)
    # Same luminance (Rec. 601 weights) as the grey, different hue: a boundary only colour can see.
    red, blue = 0.65, 0.55
    tint = (red, (0.5 - 0.299 * red - 0.114 * blue) / 0.587, blue)

    def blobs(spacing, z):
        return Texture("blobs", px(spacing, z), 0.6, size=px(1.2, z), fill=0.85)

    wall = Face((0.0, 0.0, 6.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), None, grey, blobs(9, 6.0),
                (Mark("rect", (-2.6, -2.0, -1.0, 2.0), tint),
                 Mark("rect", (-0.6, -2.0, 0.9, 2.0), grey, blobs(18, 6.0))))
    plate = Face((0.9, -1.2, 4.5), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.2, 2.4), grey, blobs(9, 4.5))
    # Ambient only: no shading and no shadow, so the plate's outline is seen by depth (and motion) alone.
    light = Light(light.direction, light.colour, 1.0, specular=light.specular, shininess=light.shininess)
    bodies = (Body((wall,), name="wall: colour-only and texture-only regions"),
              Body((plate,), Motion((0.1, 0.0, 0.0)), name="plate: depth-only"))
    return bodies, light, Motion()


def preset(name: str, *, shape: tuple[int, int] = (256, 256), specular: bool = False) -> World:
    """A named world, ready for :func:`render`.

    Parameters
    ----------
    name : str
        - "blocks": a back wall of random dots with painted marks (one with a smooth gradient), a
          slanted striped plane, a fold, and a box (blob texture) in front that occludes the plane and
          casts a shadow; the box moves and turns, the rig pans. Every label but TEXTURE occurs
          (SPECULAR with ``specular=True``).
        - "corridor": floor, walls and end wall of one corridor open to the sky (orientation edges at
          its corners), doors and posters as marks, a crate hovering above the floor, the shadows of
          the crate and of a wall on the floor; the rig walks forward (expanding flow) and turns.
        - "shadows": for colour: a Mondrian of flat colours on a wall and on a fold under a warm
          light, a strong illumination gradient (brightness varies by more than 30% inside every wall
          region), shading, and a plate casting a shadow across several colours; no texture.
        - "textures": a mosaic of blob textures of different densities (one colour, mean albedo
          equal), on a fronto-parallel wall; region edges are TEXTURE.
        - "cues": boundaries seen by one cue each: an isoluminant colour region (ALBEDO), a region of
          sparser blobs (TEXTURE), and a plate in front with the wall's colour and texture statistics
          (DEPTH; it also moves); ambient light only.
    shape : (int, int)
        Image height and width, each 64..1024. The geometry is the same at every size (the focal
        length is the width in pixels), while texture elements keep their size in pixels at a
        reference depth, so their pixel statistics do not change with the size.
    specular : bool
        Add a Blinn-Phong highlight (strength 0.5, shininess 60); off, the image model holds exactly.

    Returns
    -------
    World

    Notes
    -----
    World units are metres for intuition; the stereo baseline is 0.15. As fractions of the image
    width W, disparities span 0.019-0.043 W (blocks), 0.003-0.068 W (corridor), 0.021-0.036 W
    (shadows), 0.025 W (textures) and 0.025-0.033 W (cues); the largest flow is about 0.08 W
    (corridor) and at most 0.025 W elsewhere.
    """
    builders = {"blocks": _blocks, "corridor": _corridor, "shadows": _shadows, "textures": _textures,
                "cues": _cues}
    if not isinstance(name, str) or name not in builders:
        raise InputValueError(f"unknown preset {name!r}; name must be one of {', '.join(PRESETS)}")
    specular = check_bool(specular, "specular")
    shape = Camera(shape, 1.0, _BASELINE).shape  # checked before its width becomes the focal length
    camera = Camera(tuple(int(n) for n in shape), float(shape[1]), _BASELINE)
    f = camera.focal

    def px(pixels: float, depth: float) -> float:
        return pixels * depth / f

    light = Light(specular=0.5 if specular else 0.0)
    bodies, light, rig = builders[name](px, light)
    return World(Camera(camera.shape, camera.focal, camera.baseline, rig), light, bodies)
