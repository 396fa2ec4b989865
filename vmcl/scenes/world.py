"""The world model: textures, marks, faces, motions, bodies, the light, the stereo rig and the world
that holds them, each checked when it is made, and :func:`box` and :func:`fold`, which build faces.

Points are in the world frame (the left camera's frame at time t: x right, y down, z forward).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_int, check_real
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["TEXEL_KINDS", "Body", "Camera", "Face", "Light", "Mark", "Motion", "Texture", "World", "box", "fold"]


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
    x, y, z = _numbers(value, name, 3)  # exactly three: _numbers checks the count
    return x, y, z


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


TEXEL_KINDS = ("noise", "stripes", "blobs")
"""The :class:`Texture` kinds made of repeated elements (texels), whose ``scale`` is their spacing."""


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
