"""Ready-made worlds: :func:`preset` builds each of :data:`PRESETS` at any image size."""

from __future__ import annotations

import math

from vmcl.cm.core import check_bool
from vmcl.errors import InputValueError
from vmcl.scenes.world import Body, Camera, Face, Light, Mark, Motion, Texture, World, box, fold

__all__ = ["PRESETS", "preset"]

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
    camera = Camera((int(shape[0]), int(shape[1])), float(shape[1]), _BASELINE)
    f = camera.focal

    def px(pixels: float, depth: float) -> float:
        return pixels * depth / f

    light = Light(specular=0.5 if specular else 0.0)
    bodies, light, rig = builders[name](px, light)
    return World(Camera(camera.shape, camera.focal, camera.baseline, rig), light, bodies)
