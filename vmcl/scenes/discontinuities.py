"""Ground-truth discontinuity labels: a :class:`~vmcl.labels.Label` for every line site of the dual
lattice between 4-neighbours, and for the pixels (the rules are in the notes of :mod:`vmcl.scenes`), with
the tolerance each labelled pixel is matched within.

A texture-only boundary (TEXTURE) runs between two patterns of the same colour: between the texels on its
two sides the image is the same, so no method can place it closer than the texels allow. It is matched
within half the texel spacing of the coarser texture on its two sides (in pixels at the pixel's depth,
rounded up to half pixels); every other boundary within 1 pixel.
"""

from __future__ import annotations

import numpy as np

from vmcl.labels import Label

__all__ = ["discontinuity_labels"]

_PRECEDENCE = (Label.DEPTH, Label.ORIENTATION, Label.ALBEDO, Label.TEXTURE, Label.SHADOW, Label.SPECULAR)


def discontinuity_labels(depth, body, face, hue, look, region, shadow, highlight, texel=None):
    """Labels of the line sites between horizontal and vertical neighbours, of the pixels, and each
    labelled pixel's match tolerance (``texel``: the texel spacing in pixels at each pixel, 0 where its
    pattern has none; without it, every tolerance is 1)."""
    if texel is None:
        texel = np.zeros(depth.shape, np.float32)

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
    # A TEXTURE pixel's tolerance: half the coarser texel spacing of the two sides of its TEXTURE sites.
    half_spacing = np.zeros((h, w), np.float32)
    for code, step in ((line_h, (0, 1)), (line_v, (1, 0))):
        ys, xs = np.nonzero(code == Label.TEXTURE)
        coarser = np.maximum(texel[ys, xs], texel[ys + step[0], xs + step[1]])
        np.maximum.at(half_spacing, (ys, xs), 0.5 * coarser.astype(np.float32))
    tolerance = np.ones((h, w), np.float32)
    textured = labels == Label.TEXTURE
    # Rounded up to half pixels: a slanted face's spacing changes from pixel to pixel, and the metrics
    # match each distinct tolerance on its own (vmcl.metrics.within_tolerance).
    tolerance[textured] = np.maximum(1.0, np.ceil(2.0 * half_spacing[textured]) / 2.0)
    return labels, line_h, line_v, tolerance
