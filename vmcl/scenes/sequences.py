"""Sequences: a world's bodies and rig moving on for N frames, each frame rendered with its ground truth.

Seed section "Fast vision: The role of time smoothness": surfaces and the brightness array change little
from frame to frame, which the machine's temporal terms exploit; testing them needs frames whose flow,
disparity and labels are exact at every t. Each body repeats its :class:`~vmcl.scenes.Motion` at every
step (a constant world-frame velocity) and the rig repeats its own in its own frame (a camera that keeps
walking and turning as it did in the first step). Frame k is the world re-expressed in the rig's frame
at k and rendered by :func:`~vmcl.scenes.render`, so its ``left_next`` and flow look one step further,
and frame k + 1's ``left`` is frame k's ``left_next`` up to noise.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from vmcl.cm.core import check_int, check_real, real_host_array
from vmcl.errors import InputTypeError, InputValueError
from vmcl.scenes.rendering import Scene, render
from vmcl.scenes.world import Body, Face, Motion, World

__all__ = ["MAX_FRAMES", "advance", "render_sequence"]

MAX_FRAMES = 1000
"""The most frames :func:`render_sequence` renders into one tuple (and steps :func:`advance` takes)."""


def _matrix(motion: Motion) -> np.ndarray:
    """A motion as a 4 x 4 homogeneous transform."""
    rot, trans = motion.matrix()
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rot, trans
    return out


def _motion(transform: np.ndarray) -> Motion:
    """A 4 x 4 rigid transform as a Motion about the origin."""
    rvec = cv2.Rodrigues(np.ascontiguousarray(transform[:3, :3]))[0].ravel()
    return Motion(translation=_triple(transform[:3, 3]), rotation=_triple(rvec))


def _triple(values: np.ndarray) -> tuple[float, float, float]:
    return float(values[0]), float(values[1]), float(values[2])


def _moved(face: Face, transform: np.ndarray) -> Face:
    """The face carried by a rigid transform; its (s, t) coordinates, and so its texture and marks,
    move with it."""
    rot, trans = transform[:3, :3], transform[:3, 3]
    return dataclasses.replace(face, origin=_triple(rot @ np.asarray(face.origin, float) + trans),
                               u_axis=_triple(rot @ np.asarray(face.u_axis, float)),
                               v_axis=_triple(rot @ np.asarray(face.v_axis, float)))


def _scaled(motion: Motion, speed: float) -> Motion:
    """The motion at ``speed`` times its size: translation and rotation angle scaled, same centre."""
    return Motion(translation=_triple(speed * np.asarray(motion.translation, float)),
                  rotation=_triple(speed * np.asarray(motion.rotation, float)), centre=motion.centre)


def _speeds(speeds, steps: int, bodies: int) -> np.ndarray:
    if speeds is None:
        return np.ones((steps + 1, bodies + 1))
    table = real_host_array(speeds, "speeds", ndims=(2,)).astype(float)
    if table.shape != (steps + 1, bodies + 1):
        raise InputValueError(f"speeds must have shape (steps + 1, bodies + 1) = {(steps + 1, bodies + 1)}, "
                              f"got {table.shape}")
    if not np.isfinite(table).all() or (table < 0).any():
        raise InputValueError("speeds must be finite and >= 0")
    return table


def advance(world: World, steps: int, *, speeds=None) -> World:
    """The world ``steps`` frames on, expressed in the rig's frame at that time.

    Parameters
    ----------
    world : World
        At frame 0; each body's and the rig's motion is the step from one frame to the next.
    steps : int
        0 .. :data:`MAX_FRAMES`; 0 returns the world as given.
    speeds : (steps + 1, bodies + 1) NumPy array of real numbers >= 0, optional
        ``speeds[j, b]`` scales body b's motion in the step from frame j to j + 1 (its translation and
        its rotation angle), ``speeds[j, -1]`` the rig's; row ``steps`` sets the motions the returned
        world holds (its next step). Default all 1: every step is the world's own motion.

    Returns
    -------
    World
        Bodies moved ``steps`` times, everything (faces, each body's motion, the light's direction and
        illumination gradient) re-expressed in the rig's frame at frame ``steps``; the rig's motion is
        its own (a motion in the rig's frame) at that step's speed.
    """
    if not isinstance(world, World):
        raise InputTypeError(f"world must be a World (see vmcl.scenes.preset), got {type(world).__name__}")
    steps = check_int(steps, "steps", minimum=0, maximum=MAX_FRAMES)
    table = _speeds(speeds, steps, len(world.bodies))
    if steps == 0 and speeds is None:
        return world
    rig = np.eye(4)  # rig frame at k -> world frame at 0: the rig's steps composed in its own frame
    for j in range(steps):
        rig = rig @ _matrix(_scaled(world.camera.motion, table[j, -1]))
    to_rig = np.linalg.inv(rig)
    bodies = []
    for b, body in enumerate(world.bodies):
        pose = np.eye(4)  # the body's steps composed in the world frame at 0
        for j in range(steps):
            pose = _matrix(_scaled(body.motion, table[j, b])) @ pose
        step = _matrix(_scaled(body.motion, table[steps, b]))
        bodies.append(Body(faces=tuple(_moved(f, to_rig @ pose) for f in body.faces),
                           motion=_motion(to_rig @ step @ rig), name=body.name))
    rot, trans = to_rig[:3, :3], to_rig[:3, 3]
    light = world.light
    light = dataclasses.replace(
        light, direction=_triple(rot @ np.asarray(light.direction, float)),
        gradient=_triple(rot @ np.asarray(light.gradient, float)),
        gradient_origin=_triple(rot @ np.asarray(light.gradient_origin, float) + trans))
    camera = dataclasses.replace(world.camera, motion=_scaled(world.camera.motion, table[steps, -1]))
    return World(camera=camera, light=light, bodies=tuple(bodies))


def render_sequence(world: World, frames: int, *, seed: int = 0, noise: float = 0.0,
                    wobble: float = 0.0) -> tuple[Scene, ...]:
    """Render ``frames`` consecutive frames of a moving world.

    Parameters
    ----------
    world : World
        Frame 0 (:func:`vmcl.scenes.preset` gives ready-made ones, each with moving bodies or rig).
    frames : int
        1 .. :data:`MAX_FRAMES` (a longer sequence: :func:`advance` and :func:`vmcl.scenes.render` frame by
        frame).
    seed : int
        Seeds the textures (the same at every frame) and, with the frame's index, each frame's noise.
    noise : float
        Standard deviation of the Gaussian noise of every image.
    wobble : float
        >= 0: each step's speed of every body and of the rig is ``max(0, 1 + wobble z)``, z standard
        normal, drawn per step from the seed (motions that change from frame to frame, as real ones
        do; :func:`advance`'s ``speeds``). 0: constant velocities.

    Returns
    -------
    tuple of Scene
        Scene k holds frame k's stereo pair, its next left view and the ground truth from k to k + 1
        (flow, disparity, labels at k); the last scene's ``left_next`` is frame ``frames``.

    Examples
    --------
    >>> from vmcl import scenes
    >>> frames = scenes.render_sequence(scenes.preset("cues", shape=(64, 64)), 3, seed=0)
    >>> len(frames), bool(abs(frames[1].left - frames[0].left_next).max() < 1e-4)
    (3, True)
    """
    frames = check_int(frames, "frames", minimum=1, maximum=MAX_FRAMES)
    check_int(seed, "seed", minimum=0)
    wobble = check_real(wobble, "wobble", minimum=0)
    if not isinstance(world, World):
        raise InputTypeError(f"world must be a World (see vmcl.scenes.preset), got {type(world).__name__}")
    shape = (frames, len(world.bodies) + 1)
    table = np.maximum(0.0, 1.0 + wobble * np.random.default_rng([int(seed), 1]).standard_normal(shape))
    if wobble == 0:
        table = np.ones(shape)
    return tuple(render(advance(world, k, speeds=table[:k + 1] if wobble else None), seed=seed, noise=noise, frame=k)
                 for k in range(frames))
