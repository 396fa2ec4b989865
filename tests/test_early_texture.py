"""Texture: texton density and texture-edge candidates against NumPy oracles, on the blob mosaic of
vmcl.scenes and on a mosaic of scikit-image's brick, grass and gravel."""

import importlib.util
from pathlib import Path

import numpy as np
import pyopencl.array as cl_array
import pytest
from scipy import ndimage

from vmcl import metrics, scenes
from vmcl.early import texture
from vmcl.early.filters import gaussian_taps
from vmcl.labels import Label

# benchmarks/ is a folder of scripts, not a package: its texture fit (which builds the photo mosaic and
# measures separations for its report) is loaded by its path.
_SPEC = importlib.util.spec_from_file_location(
    "texture_fit", Path(__file__).resolve().parents[1] / "benchmarks" / "texture_fit.py")
TEXTURE_FIT = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(TEXTURE_FIT)

PARAMS = {"fine_sigma": 1.0, "coarse_sigma": 4.0, "radius": 24}
PRESET_THRESHOLD = 0.08  # float images of the preset: blobs of depth about 0.3
MOSAIC_THRESHOLD = 20.0  # uint8 photographs


def _log_oracle(image, sigma):
    """Exact Gaussian (clamped borders) and the 5-point Laplacian, in float64."""
    taps = gaussian_taps(sigma).astype(np.float64)
    s = ndimage.correlate1d(image.astype(np.float64), taps, axis=1, mode="nearest")
    s = ndimage.correlate1d(s, taps, axis=0, mode="nearest")
    p = np.pad(s, 1, mode="edge")
    return (p[1:-1, :-2] - s) + (p[1:-1, 2:] - s) + (p[:-2, 1:-1] - s) + (p[2:, 1:-1] - s)


def _density_oracle(image, fine_sigma, coarse_sigma, threshold, radius):
    f = fine_sigma**2 * _log_oracle(image, fine_sigma)
    c = coarse_sigma**2 * _log_oracle(image, coarse_sigma)
    window = np.ones((3, 3), bool)
    near_bright = ndimage.binary_dilation(c > threshold, window)
    near_dark = ndimage.binary_dilation(c < -threshold, window)
    blobs = ((f > threshold) & ~near_bright) | ((f < -threshold) & ~near_dark)
    size = 2 * radius + 1
    sums = ndimage.uniform_filter(blobs.astype(np.float64), size, mode="constant") * size * size
    counts = ndimage.uniform_filter(np.ones(image.shape), size, mode="constant") * size * size
    ambiguous = np.minimum(np.abs(np.abs(f) - threshold), np.abs(np.abs(c) - threshold)) < 1e-4 * threshold
    return np.round(sums) / np.round(counts), ambiguous


def _edges_oracle(d, radius, edge_threshold):
    h, w = d.shape
    xs, ys = np.arange(w), np.arange(h)
    gx = d[:, np.minimum(xs + radius + 1, w - 1)] - d[:, np.maximum(xs - radius, 0)]
    gy = d[np.minimum(ys + radius + 1, h - 1)] - d[np.maximum(ys - radius, 0)]
    m = np.sqrt(gx * gx + gy * gy)  # float32, as the kernel
    p = np.pad(m, 1, mode="edge")
    along_x = np.abs(gx) >= np.abs(gy)
    before = np.where(along_x, p[1:-1, :-2], p[:-2, 1:-1])
    after = np.where(along_x, p[1:-1, 2:], p[2:, 1:-1])
    gap = np.minimum(np.abs(m - before), np.abs(m - after))
    ties = (gap <= 1e-5 * m) | (np.abs(m - edge_threshold) <= 1e-5 * m)  # fma or not decides ties
    return (m > before) & (m >= after) & (m > edge_threshold), ties


def _dotted(shape, seed):
    rng = np.random.default_rng(seed)
    image = np.full(shape, 0.7, np.float32)
    image[rng.random(shape) < 0.04] = 0.1
    image[:, shape[1] // 2:] += 0.25  # a contrast step across the dots
    return image


@pytest.mark.parametrize("shape", [(11, 9), (40, 71), (67, 33)], ids=str)
def test_density_matches_oracle(shape, machine):
    image = _dotted(shape, seed=shape[0])
    got = texture.density(image, threshold=0.1, machine=machine, **PARAMS | {"radius": 5})
    want, ambiguous = _density_oracle(image, 1.0, 4.0, 0.1, 5)
    assert not ambiguous.any()
    assert 0.02 < want.mean() < 0.5
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)


def test_texture_edges_match_oracle_with_a_fixed_threshold(machine):
    image = _dotted((64, 96), seed=2)
    image[:, 48:] = np.where(np.random.default_rng(3).random((64, 48)) < 0.15, 0.1, 0.7)
    got = texture.texture_edges(image, threshold=0.1, edge_threshold=0.02, machine=machine,
                                **PARAMS | {"radius": 6})
    want, ties = _edges_oracle(got.density, 6, np.float32(0.02))
    assert want.sum() > 20 and ties.mean() < 0.15
    np.testing.assert_array_equal(got.edges[~ties], want[~ties])
    # The edges' oracle starts from vmcl's density: that density must itself match its oracle.
    density, ambiguous = _density_oracle(image, 1.0, 4.0, 0.1, 6)
    assert not ambiguous.any()
    np.testing.assert_allclose(got.density, density, rtol=1e-6, atol=1e-7)


def test_device_in_device_out_and_local_sizes_agree(machine_with_local_size):
    m = machine_with_local_size
    image = _dotted((53, 77), seed=4)
    reference = texture.texture_edges(image, threshold=0.1, **PARAMS | {"radius": 6})
    got = texture.texture_edges(m.to_device(image), threshold=0.1, machine=m, **PARAMS | {"radius": 6})
    assert isinstance(got.edges, cl_array.Array) and isinstance(got.density, cl_array.Array)
    np.testing.assert_array_equal(got.density.get(), reference.density)
    np.testing.assert_array_equal(got.edges.get().view(bool), reference.edges)


def _boundaries(regions):
    """Left or upper pixel of every site between two regions (vmcl.scenes's convention)."""
    b = np.zeros(regions.shape, bool)
    b[:, :-1] |= regions[:, :-1] != regions[:, 1:]
    b[:-1] |= regions[:-1] != regions[1:]
    return b


@pytest.fixture(scope="module")
def blob_mosaic():
    return scenes.render(scenes.preset("textures", shape=(512, 512)), seed=0)


def test_blob_mosaic_densities_separate_and_edges_are_found(blob_mosaic, machine):
    s = blob_mosaic
    got = texture.texture_edges(s.left, threshold=PRESET_THRESHOLD, machine=machine, **PARAMS)
    regions = s.regions
    dense, wall, sparse, disc = regions[128, 128], regions[128, 384], regions[384, 384], regions[256, 256]
    # The disc (spacing 10, fill 0.3) and the sparse quadrant (spacing 16, fill 0.9) have nearly equal
    # expected densities by construction (0.3 / 10**2 against 0.9 / 16**2): that pair is not compared.
    pairs = [(dense, wall), (sparse, wall), (disc, wall), (disc, dense), (dense, sparse)]
    assert min(TEXTURE_FIT.separations(got.density, regions, pairs, PARAMS["radius"])) > 5
    truth = s.labels == Label.TEXTURE
    # Within the scene's tolerance, half the coarser texel spacing (the texture-only rule of Scene.tolerance):
    # measured 0.83 with the default noise factor; within 3 px, where the edges' placement shows, 0.74.
    assert metrics.detection_scores(got.edges, truth, tolerance=s.tolerance).recall >= 0.80
    assert metrics.detection_scores(got.edges, truth, tolerance=3).recall >= 0.70


def test_photo_mosaic_edges_are_found(machine):
    mosaic, regions = TEXTURE_FIT.photo_mosaic()
    got = texture.texture_edges(mosaic, threshold=MOSAIC_THRESHOLD, machine=machine, **PARAMS)
    assert metrics.detection_scores(got.edges, _boundaries(regions), tolerance=3).recall >= 0.80


# The photographs' densities drift across each photo (light, focus), so PARAMS leaves them 2 to 4
# within-region deviations apart. What separates them (measured 2026-11-22 with this module): a coarse
# scale twice the fine one ("slightly coarser", as the seed paper puts it), a threshold of 10 grey levels
# and a radius of 48, which averages the drift out. Separations (brick/grass, brick/gravel,
# grass/gravel): 12.9, 10.0, 7.0 here; 3.9, 4.2, 2.0 with PARAMS and threshold 20. Around this setting
# the smallest of the three is 6.0 (threshold 8), 5.5 (12), 6.0 (coarse_sigma 3), 4.9 (coarse_sigma 4),
# 6.2 (radius 40) and 4.98 (radius 32). The edge candidates of this setting recall 99.9% of the boundaries.
PHOTO_PARAMS = {"fine_sigma": 1.0, "coarse_sigma": 2.0, "threshold": 10.0, "radius": 48}


def test_photo_mosaic_densities_separate(machine):
    mosaic, regions = TEXTURE_FIT.photo_mosaic()
    d = texture.density(mosaic, machine=machine, **PHOTO_PARAMS)
    separations = TEXTURE_FIT.separations(d, regions, TEXTURE_FIT.MOSAIC_PAIRS, PHOTO_PARAMS["radius"])
    assert min(separations) > 5


def test_plain_contrast_step_is_no_texture(machine):
    step = np.full((256, 256), 0.2, np.float32)
    step[:, 128:] = 0.6  # its LoG response (0.24 * 0.4) passes the threshold at both scales
    got = texture.texture_edges(step, threshold=PRESET_THRESHOLD, machine=machine, **PARAMS)
    assert got.density.max() == 0
    assert not got.edges.any()


def test_bad_input_is_refused(machine):
    image = np.ones((16, 16), np.float32)
    with pytest.raises(ValueError, match="coarse_sigma must exceed fine_sigma"):
        texture.density(image, fine_sigma=2.0, coarse_sigma=1.0, threshold=0.1, radius=3, machine=machine)
    bad = image.astype(np.float64)
    bad[3, 4] = np.inf
    with pytest.raises(ValueError, match="image must not contain NaN"):
        texture.density(bad, threshold=0.1, machine=machine, **PARAMS)
    with pytest.raises(ValueError, match="threshold must be a finite number > 0"):
        texture.density(image, threshold=0.0, machine=machine, **PARAMS)
    with pytest.raises(ValueError, match="radius"):
        texture.density(image, threshold=0.1, fine_sigma=1.0, coarse_sigma=4.0, radius=0, machine=machine)
    with pytest.raises(ValueError, match="fine_sigma"):
        texture.density(image, threshold=0.1, fine_sigma=-1.0, coarse_sigma=4.0, radius=3, machine=machine)
    with pytest.raises(ValueError, match="edge_threshold"):
        texture.texture_edges(image, threshold=0.1, edge_threshold=-0.5, machine=machine, **PARAMS)


@pytest.mark.parametrize("radius", [2**63, 10**30])
def test_radii_beyond_the_image_take_the_whole_image(radius, machine):
    """Windows are cut at the border, so any radius past the image is the whole image (these radii used
    to raise OverflowError)."""
    image = _dotted((40, 71), seed=40)  # no pixel near the threshold (as in test_density_matches_oracle)
    got = texture.texture_edges(image, threshold=0.1, radius=radius, edge_threshold=0.02, machine=machine,
                                fine_sigma=1.0, coarse_sigma=4.0)
    want, ambiguous = _density_oracle(image, 1.0, 4.0, 0.1, 71)
    assert not ambiguous.any()
    np.testing.assert_allclose(got.density, want, rtol=1e-6, atol=1e-7)
    assert not got.edges.any()  # one window, one density: no gradient anywhere
