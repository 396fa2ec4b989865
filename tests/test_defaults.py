"""Every early-vision function runs with its defaults (as scikit-image's do), the machine's own settings,
so that a library user needs no parameter taken from elsewhere; and the defaults are the Config's."""

import numpy as np

from vmcl import scenes
from vmcl.early import edges, filters, motion, stereo, texture
from vmcl.pipeline import Config


def test_the_early_functions_run_with_their_defaults_and_share_the_machines(machine):
    s = scenes.render(scenes.preset("blocks", shape=(96, 96)), seed=0, noise=0.01)
    grey = s.left.mean(axis=2).astype(np.float32)
    assert filters.gaussian(grey, machine=machine).shape == grey.shape
    assert filters.laplacian_of_gaussian(grey, machine=machine).shape == grey.shape
    assert filters.difference_of_gaussians(grey, machine=machine).shape == grey.shape
    assert edges.canny(grey, machine=machine).any()
    assert edges.zero_crossings(grey, machine=machine).mask.any()
    # The default blob threshold is a share of the input's full scale: uint8 and float images agree.
    as_uint8 = np.round(grey * 255).astype(np.uint8)
    np.testing.assert_allclose(texture.density(as_uint8, machine=machine),
                               texture.density(as_uint8.astype(np.float32) / 255, machine=machine), atol=1e-6)
    assert motion.flow(s.left, s.left_next, machine=machine).flow.shape == (96, 96, 2)
    # No range given: found from the images; the edge matches then land near the truth (measured: 263
    # matches, median error 0.2 px, on this 256 x 256 scene).
    wide = scenes.render(scenes.preset("blocks", shape=(256, 256)), seed=0, noise=0.01)
    matched = stereo.match(wide.left, wide.right, machine=machine)
    found = matched.disparity
    assert matched.d_min <= np.nanmin(wide.disparity) and np.nanmax(wide.disparity) <= matched.d_max  # the range found
    known = np.isfinite(found) & np.isfinite(wide.disparity) & ~wide.occluded_stereo
    assert known.sum() > 150 and np.median(np.abs(found - wide.disparity)[known]) < 0.5
    config = Config()
    assert (config.edges.sigma, config.motion.delta, config.motion.patch) == (edges.DEFAULT_SIGMA, motion.DELTA,
                                                                              motion.PATCH)
    assert (config.texture.fine_sigma, config.texture.coarse_sigma, config.texture.threshold,
            config.texture.radius) == (texture.FINE_SIGMA, texture.COARSE_SIGMA, texture.THRESHOLD, texture.RADIUS)
