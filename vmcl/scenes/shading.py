"""Shading: what one view sees of the world (albedo regions and their textures, effective illumination,
cast shadows, the specular highlight) and the image it forms, ``I^nu = k^nu (E rho^nu + S)`` plus noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vmcl.scenes.points import F32, dot
from vmcl.scenes.raycast import EPS, FaceArrays, Pinhole, projected_boxes, segment_blocked
from vmcl.scenes.textures import texture_modulation
from vmcl.scenes.world import Face, Texture, World

__all__ = ["Regions", "Surface", "form_image", "shade"]


@dataclass
class Surface:
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
class Regions:
    """Every albedo region of the world: its colour, texture and texture key."""

    first: list[int]  # first region id of each face
    colour: np.ndarray  # (R, 3)
    hue: np.ndarray  # (R,) id of the colour; equal colours, equal ids
    look: np.ndarray  # (R,) id of (texture, key); equal looks continue one pattern
    textures: list[tuple[Texture, int]]

    @classmethod
    def of(cls, faces: list[Face], seed: int) -> Regions:
        first: list[int] = []
        colours: list[tuple[float, float, float]] = []
        looks: list[int] = []
        textures: list[tuple[Texture, int]] = []
        seen: dict[tuple[Texture, int], int] = {}
        for k, face in enumerate(faces):
            first.append(len(colours))
            looks_of_face = [(face.colour, None)] + [(mk.colour, mk.texture) for mk in face.marks]
            for m, (look_colour, texture) in enumerate(looks_of_face):
                # A mark without its own texture continues its face's pattern: same texture, same key.
                own = texture is not None
                item = (texture if texture is not None else face.texture, _seed_key(seed, k, m if own else 0))
                look = seen.setdefault(item, len(seen))
                if look == len(textures):
                    textures.append(item)
                colours.append(look_colour)
                looks.append(look)
        colour = np.array(colours, F32)
        hue = np.unique(colour, axis=0, return_inverse=True)[1].ravel()
        return cls(first, colour, hue, np.array(looks), textures)


def _seed_key(seed: int, face: int, mark: int) -> int:
    return int(np.random.SeedSequence([seed, face, mark]).generate_state(1, np.uint64)[0])


def shade(cam: Pinhole, faces: FaceArrays, world: World, spec: list[Face], regions: Regions,
          world_to_view: tuple[np.ndarray, np.ndarray]) -> Surface:
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
        s = dot(faces.u[g], p) - F32(faces.u[g] @ faces.origin[g])
        t = dot(faces.v[g], p) - F32(faces.v[g] @ faces.origin[g])
        local = np.zeros(sel.size, np.int32)
        for m, mark in enumerate(f.marks):
            local[mark.contains(s, t)] = m + 1
        region[sel] = regions.first[g] + local
        for r in np.flatnonzero(np.bincount(local)):
            inside = local == r
            rid = regions.first[g] + r
            texture, key = regions.textures[regions.look[rid]]
            modulation = texture_modulation(texture, s[inside], t[inside], key)
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
        keys = np.stack([dot(across[0], p), dot(across[1], p)])
        eps = EPS * float(np.abs(z).max())
        shadow[idx] = segment_blocked(faces, p, to_light, np.inf, face[idx], keys,
                                      projected_boxes(faces.corners, lambda c: c @ across.T), eps)
    # gradient . world point = (rot gradient) . (view point - trans)
    gradient = rot @ np.asarray(light.gradient)
    offset = gradient @ trans + np.dot(light.gradient, light.gradient_origin)
    gain = np.exp(dot(gradient, points) - F32(offset)) if gradient.any() else np.ones(n, F32)
    direct = np.where(shadow, F32(0), np.maximum(cosine, 0))
    illumination = gain * (F32(light.ambient) + F32(1 - light.ambient) * direct)
    specular = np.zeros(n, F32)
    highlight = np.zeros(n, dtype=bool)
    if light.specular > 0:
        half = to_light[:, None] - points / np.sqrt(dot(points, points))
        facing = np.maximum(np.einsum("ij,ij->j", normals[face].T.astype(F32), half), 0)
        lobe = np.where(lit & ~shadow, facing / np.sqrt(dot(half, half)), 0) ** F32(light.shininess)
        specular = (F32(light.specular) * gain * lobe).astype(F32)
        highlight = lobe >= 0.5
    return Surface(depth, index, points, pixels, face, region, albedo, illumination.astype(F32), specular,
                    shadow, highlight)


def form_image(surface: Surface, cam: Pinhole, colour: np.ndarray, noise: float,
               rng: np.random.Generator) -> np.ndarray:
    """(H, W, 3) float32 image ``colour * (illumination * albedo + specular)`` of what a view sees,
    plus Gaussian noise of standard deviation ``noise`` drawn from ``rng``; NaN where nothing is seen."""
    flat = np.full((cam.h * cam.w, 3), np.nan, F32)
    radiance = surface.illumination[:, None] * surface.albedo + surface.specular[:, None]
    flat[surface.pixels] = colour * radiance
    image = flat.reshape(cam.h, cam.w, 3)
    if noise > 0:
        image += rng.standard_normal(image.shape, dtype=F32) * F32(noise)
    return image
