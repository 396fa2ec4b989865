"""Rendering: :func:`render` turns a world into a :class:`Scene`, the stereo pair at t, the left view at
t + 1 and the left view's ground truth (depth, disparity, flow, albedo, illumination, shadows,
occlusions, discontinuity labels).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_int, check_real
from vmcl.errors import InputTypeError
from vmcl.scenes.discontinuities import discontinuity_labels
from vmcl.scenes.points import F32, transform
from vmcl.scenes.raycast import NEAR, FaceArrays, Pinhole, camera_blocked
from vmcl.scenes.shading import Regions, form_image, shade
from vmcl.scenes.world import TEXEL_KINDS, World

__all__ = ["Scene", "render"]


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
        :class:`~vmcl.labels.Label` codes on the pixel grid (see the notes of :mod:`vmcl.scenes` for which
        pixel carries a label).
    tolerance : (H, W) float32
        The distance in pixels within which each labelled pixel counts as found (the ``tolerance`` of
        :func:`vmcl.metrics.label_scores`): 1, except on texture-only boundaries (TEXTURE), half the
        texel spacing of the coarser texture on their two sides, rounded up to half pixels
        (:mod:`vmcl.scenes.discontinuities`).
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
    tolerance: np.ndarray
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


def _grid(cam: Pinhole, values: np.ndarray, pixels: np.ndarray, fill) -> np.ndarray:
    out = np.full((cam.h * cam.w, *values.shape[1:]), fill, dtype=values.dtype)
    out[pixels] = values
    return out.reshape(cam.h, cam.w, *values.shape[1:])


def render(world: World, *, seed: int = 0, noise: float = 0.0, frame: int = 0) -> Scene:
    """Render the left and right views at t, the left view at t + 1, and the ground truth.

    Parameters
    ----------
    world : World
        Geometry, light and cameras (see :func:`preset` for ready-made ones).
    seed : int
        Seeds the random textures and the noise; the same seed gives the same bits.
    noise : float
        Standard deviation of Gaussian noise added independently to every pixel, channel and image.
    frame : int
        The frame's index in a sequence (:func:`vmcl.scenes.render_sequence`), >= 0: it keys the noise
        with the seed, so that each frame of a sequence gets its own noise while the textures (keyed by
        the seed alone) stay attached to their faces.

    Returns
    -------
    Scene

    Notes
    -----
    Each pixel's ray is cast against every face (culled by the face's projected bounding box); shadows
    and occlusions are exact segment tests against the faces (benchmarks/results/ground_truth.md times
    each preset's rendering at 512 x 512).

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
    check_int(frame, "frame", minimum=0)
    cam = Pinhole(world.camera)
    spec = [f for b in world.bodies for f in b.faces]
    owner = np.array([k for k, b in enumerate(world.bodies) for _ in b.faces])
    regions = Regions.of(spec, int(seed))
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

    faces_left = FaceArrays.of(spec, [eye] * len(spec), [zero] * len(spec))
    faces_right = FaceArrays.of(spec, [eye] * len(spec), [-baseline] * len(spec))
    faces_next = FaceArrays.of(spec, next_rot, next_trans)
    left = shade(cam, faces_left, world, spec, regions, (eye, zero))
    right = shade(cam, faces_right, world, spec, regions, (eye, -baseline))
    # The rig at t + 1 maps world points q to rig_rot.T (q - rig_t).
    nxt = shade(cam, faces_next, world, spec, regions, (rig_rot.T, -rig_rot.T @ rig_t))

    colour = np.asarray(world.light.colour, F32)
    # Frame 0 keeps the key of a single render, so a sequence's first frame is that render bit for bit.
    rngs = [np.random.default_rng([int(seed), view] + ([int(frame)] if frame else [])) for view in range(3)]
    images = [form_image(s, cam, colour, float(noise), g) for s, g in zip((left, right, nxt), rngs)]

    face, p = left.face, left.points
    right_points = p - np.array([[world.camera.baseline], [0.0], [0.0]], F32)
    moved = np.empty_like(p)
    for g in range(len(spec)):
        sel = np.flatnonzero(face == g)
        moved[:, sel] = transform(next_rot[g], next_trans[g], p[:, sel])
    target = cam.pixel(moved)
    ys, xs = np.divmod(left.pixels, cam.w)
    flow = (target - np.stack([xs, ys]).astype(F32)).T
    flow[moved[2] <= NEAR] = np.nan
    x_right = cam.pixel(right_points)[0]
    occluded_stereo = ((x_right < 0) | (x_right > cam.w - 1)
                       | camera_blocked(cam, faces_right, right_points, face))
    inside = (target[0] >= 0) & (target[0] <= cam.w - 1) & (target[1] >= 0) & (target[1] <= cam.h - 1)
    occluded_motion = ~inside | camera_blocked(cam, faces_next, moved, face)

    depth = np.where(np.isfinite(left.depth), left.depth, np.nan).astype(F32)
    surfaces = left.index
    bodies = np.where(surfaces >= 0, owner[np.maximum(surfaces, 0)], -1).astype(np.int32)
    region = _grid(cam, left.region, left.pixels, -1)
    shadow = _grid(cam, left.shadow, left.pixels, False)
    highlight = _grid(cam, left.highlight, left.pixels, False)
    look = _grid(cam, regions.look[left.region], left.pixels, -1)
    # Each pattern's texel spacing (cell or period; none for flat and gradient patterns) in pixels at the
    # pixel's depth; the appended 0 is read by pixels with no surface (look -1).
    spacing = np.array([t.scale if t.kind in TEXEL_KINDS else 0.0 for t, _ in regions.textures] + [0.0], F32)
    with np.errstate(invalid="ignore", divide="ignore"):
        texel = np.where(np.isfinite(depth), spacing[look] * F32(cam.f) / depth, 0.0).astype(F32)
    labels, line_h, line_v, tolerance = discontinuity_labels(
        np.where(np.isfinite(depth), depth, np.inf), bodies, surfaces,
        _grid(cam, regions.hue[left.region], left.pixels, -1), look, region, shadow, highlight, texel)
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
        tolerance=tolerance,
        line_h=line_h,
        line_v=line_v,
        regions=region,
        surfaces=surfaces,
        bodies=bodies,
    )
