"""Synthetic worlds seen by a rectified stereo pair over two frames, with ground truth at every pixel.

The seed paper's learning stage estimates parameters "from a set of examples in which data and desired
solution are given ... at least initially, synthetic images" (section "Learning and parameter
estimation"), and its labelling stage classifies each discontinuity as an occluding (depth),
orientation, albedo (mark), shadow or specular edge (section "Labeling the physical origin of edges",
"Physical discontinuities"). This package renders such examples: small worlds of textured, painted
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

Modules
-------
- :mod:`~vmcl.scenes.world`: the world model (Texture, Mark, Face, Motion, Body, Light, Camera, World, each
  checked when made) and the face builders :func:`box` and :func:`fold`;
- :mod:`~vmcl.scenes.points`: arithmetic on (3, N) float32 point arrays (dot products, rigid transforms);
- :mod:`~vmcl.scenes.textures`: the procedural textures that modulate a region's albedo;
- :mod:`~vmcl.scenes.raycast`: faces as arrays, pinhole projection, the nearest face along each ray and
  segment tests for shadows and occlusions;
- :mod:`~vmcl.scenes.shading`: albedo regions, effective illumination, shadows, highlights and the image;
- :mod:`~vmcl.scenes.discontinuities`: the ground-truth labels on the dual lattice and the pixel grid;
- :mod:`~vmcl.scenes.rendering`: :func:`render` and the :class:`Scene` it returns;
- :mod:`~vmcl.scenes.sequences`: :func:`render_sequence`, N frames of a moving world (:func:`advance`);
- :mod:`~vmcl.scenes.presets`: the ready-made worlds, :func:`preset` and :data:`PRESETS`;
- :mod:`~vmcl.scenes.clutter`: shapes in clutter, a closed smooth contour among random short segments
  (:func:`clutter_display`), for structural saliency;
- :mod:`~vmcl.scenes.occlusion`: 2-D occlusion scenes, opaque grey polygons stacked in depth
  (:func:`render_occlusion`, :func:`occlusion_scene`), with every junction (T, L, ...) exact.

References
----------
T. Poggio, J. Little, E. Gamble, W. Gillett, D. Geiger, D. Weinshall et al., "The MIT Vision Machine",
Proc. DARPA Image Understanding Workshop, 1988.
A. Hurlbert and T. Poggio, "A network for image segmentation using color", NIPS 1988.
E. Gamble, D. Geiger, T. Poggio and D. Weinshall, "Integration of vision modules and labeling of surface
discontinuities", IEEE SMC 19(6), 1989.
"""

# Label is not re-exported in __all__ (its home is vmcl.labels), but scenes.Label has always reached it and
# the render example and the README use that spelling.
from vmcl.labels import Label as Label
from vmcl.scenes.clutter import ClutterDisplay, clutter_display
from vmcl.scenes.occlusion import Junction, OcclusionScene, occlusion_scene, render_occlusion
from vmcl.scenes.presets import PRESETS, preset
from vmcl.scenes.recognition import (
                                     LAYER_DISPARITIES,
                                     LEARNED_YAWS,
                                     OBJECTS,
                                     TILT,
                                     Placement,
                                     RecognitionScene,
                                     SceneObject,
                                     example_library,
                                     example_views,
                                     object_view,
                                     recognition_scene,
)
from vmcl.scenes.rendering import Scene, render
from vmcl.scenes.sequences import advance, render_sequence
from vmcl.scenes.world import Body, Camera, Face, Light, Mark, Motion, Texture, World, box, fold

__all__ = [
                                     "LAYER_DISPARITIES",
                                     "LEARNED_YAWS",
                                     "OBJECTS",
                                     "PRESETS",
                                     "TILT",
                                     "Body",
                                     "Camera",
                                     "ClutterDisplay",
                                     "Face",
                                     "Junction",
                                     "Light",
                                     "Mark",
                                     "Motion",
                                     "OcclusionScene",
                                     "Placement",
                                     "RecognitionScene",
                                     "Scene",
                                     "SceneObject",
                                     "Texture",
                                     "World",
                                     "advance",
                                     "box",
                                     "clutter_display",
                                     "example_library",
                                     "example_views",
                                     "fold",
                                     "object_view",
                                     "occlusion_scene",
                                     "preset",
                                     "recognition_scene",
                                     "render",
                                     "render_occlusion",
                                     "render_sequence",
]
