"""Ray casting: the faces as arrays in one view's frame, pinhole projection, the nearest face along each
pixel's ray, and exact segment tests against the faces (for shadows and occlusions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vmcl.scenes.points import F32, dot
from vmcl.scenes.world import Camera, Face

__all__ = ["EPS", "NEAR", "FaceArrays", "Pinhole", "camera_blocked", "projected_boxes", "segment_blocked"]

NEAR = 1e-3
"""Nearest depth a camera sees, world units."""
EPS = 1e-5
"""Relative slack of segment tests, so a point never hides itself."""


@dataclass
class FaceArrays:
    """All faces as arrays, in one camera's frame at one time."""

    origin: np.ndarray  # (F, 3)
    u: np.ndarray
    v: np.ndarray
    normal: np.ndarray
    extent: np.ndarray  # (F, 2), inf for unbounded planes
    corners: np.ndarray  # (F, 4, 3), NaN for unbounded planes

    @classmethod
    def of(cls, faces: list[Face], rot: list[np.ndarray], trans: list[np.ndarray]) -> FaceArrays:
        origin = np.array([r @ f.origin + t for f, r, t in zip(faces, rot, trans)])
        u = np.array([r @ f.u_axis for f, r in zip(faces, rot)])
        v = np.array([r @ f.v_axis for f, r in zip(faces, rot)])
        extent = np.array([f.size or (np.inf, np.inf) for f in faces], dtype=np.float64)
        corners = np.full((len(faces), 4, 3), np.nan)
        for k, (a, b) in enumerate(extent):
            if np.isfinite(a):
                corners[k] = [origin[k] + x * u[k] + y * v[k] for x, y in ((0, 0), (a, 0), (a, b), (0, b))]
        return cls(origin, u, v, np.cross(u, v), extent, corners)


def projected_boxes(corners: np.ndarray, project) -> np.ndarray:
    """Per face (x0, x1, y0, y1) of the projected corners; infinite where a face cannot be bounded."""
    boxes = np.tile(np.array([-np.inf, np.inf, -np.inf, np.inf]), (len(corners), 1))
    for k, c in enumerate(corners):
        if np.isfinite(c).all():
            p = project(c)
            if p is not None:
                boxes[k] = (p[:, 0].min(), p[:, 0].max(), p[:, 1].min(), p[:, 1].max())
    return boxes


class Pinhole:
    """Pinhole projection of one view."""

    def __init__(self, camera: Camera):
        self.h, self.w = camera.shape
        self.f = float(camera.focal)
        self.cx, self.cy = (self.w - 1) / 2, (self.h - 1) / 2
        self.rx = ((np.arange(self.w) - self.cx) / self.f).astype(F32)
        self.ry = ((np.arange(self.h) - self.cy) / self.f).astype(F32)

    def project(self, points: np.ndarray) -> np.ndarray | None:
        """Pixel coordinates of (K, 3) points all in front of the camera (else None)."""
        if (points[:, 2] <= NEAR).any():
            return None
        return np.stack([self.f * points[:, 0] / points[:, 2] + self.cx,
                         self.f * points[:, 1] / points[:, 2] + self.cy], axis=-1)

    def pixel(self, points: np.ndarray) -> np.ndarray:
        """(2, N) pixel coordinates of (3, N) points (meaningless behind the camera)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.stack([F32(self.f) * points[0] / points[2] + F32(self.cx),
                             F32(self.f) * points[1] / points[2] + F32(self.cy)])

    def cast(self, faces: FaceArrays) -> tuple[np.ndarray, np.ndarray]:
        """Depth (inf: nothing) and face index (-1) of the nearest face along each pixel's ray."""
        depth = np.full((self.h, self.w), np.inf, F32)
        index = np.full((self.h, self.w), -1, np.int32)
        boxes = projected_boxes(faces.corners, self.project)
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
            hit = (lam > NEAR) & (lam < window)
            a, b = faces.extent[g]
            if np.isfinite(a):
                u, v = faces.u[g], faces.v[g]
                s = lam * (F32(u[0]) * rx + F32(u[1]) * ry + F32(u[2])) - F32(u @ o)
                t = lam * (F32(v[0]) * rx + F32(v[1]) * ry + F32(v[2])) - F32(v @ o)
                hit &= (s >= 0) & (s <= a) & (t >= 0) & (t <= b)
            window[hit] = lam[hit]
            index[ys, xs][hit] = g
        return depth, index


def segment_blocked(faces: FaceArrays, start: np.ndarray, direction: np.ndarray, far: float,
                    own: np.ndarray, keys: np.ndarray, boxes: np.ndarray, eps: float) -> np.ndarray:
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
            mu = (F32(n @ o) - dot(n, p)) / dot(n, d)
        hit = (mu > eps) & (mu < far)
        a, b = faces.extent[g]
        if np.isfinite(a):
            u, v = faces.u[g], faces.v[g]
            s = dot(u, p) + mu * dot(u, d) - F32(u @ o)
            t = dot(v, p) + mu * dot(v, d) - F32(v @ o)
            hit &= (s >= 0) & (s <= a) & (t >= 0) & (t <= b)
        blocked[idx[hit]] = True
    return blocked


def camera_blocked(cam: Pinhole, faces: FaceArrays, points: np.ndarray, own: np.ndarray) -> np.ndarray:
    """Whether the segment from this camera's centre to each (3, N) point meets another face (or the
    point is behind the camera)."""
    behind = points[2] <= NEAR
    keys = cam.pixel(points)
    keys[:, behind] = np.nan
    boxes = projected_boxes(faces.corners, cam.project)
    return behind | segment_blocked(faces, np.zeros(3), points, 1 - EPS, own, keys, boxes, EPS)
