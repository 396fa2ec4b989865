"""Colour: hue and albedo-edge candidates against NumPy oracles, and against the ground truth of a
scene with an illumination gradient, shading and a cast shadow."""

import math

import numpy as np
import pyopencl.array as cl_array
import pytest

from vmcl import metrics, scenes
from vmcl.early import color, noise
from vmcl.early.edges import canny
from vmcl.labels import Label

FULL_SCALE = {np.uint8: 255.0, np.uint16: 65535.0, np.float32: 1.0}


def _hue_oracle(rgb, min_intensity, chromaticity=False):
    c = rgb.astype(np.float32)
    den = c.sum(axis=2) if chromaticity else c[..., 0] + c[..., 1]
    valid = np.isfinite(c).all(axis=2) & (den >= np.float32(min_intensity))
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.stack([c[..., 0] / den, c[..., 1] / den], axis=2) if chromaticity else c[..., 0] / den
    out[~valid] = np.nan
    return out, valid


def _z_oracle(rgb, min_intensity):
    """The noise-normalised hue gradient of the module's edge rule, in float64."""
    c = rgb.astype(np.float64)
    r, g = c[..., 0], c[..., 1]
    valid = (r + g) >= min_intensity
    with np.errstate(divide="ignore", invalid="ignore"):
        h = r / (r + g)
        gain = np.sqrt(r * r + g * g) / (r + g) ** 2
    right = np.concatenate([np.arange(1, rgb.shape[1]), [rgb.shape[1] - 1]])
    down = np.concatenate([np.arange(1, rgb.shape[0]), [rgb.shape[0] - 1]])
    with np.errstate(divide="ignore", invalid="ignore"):
        zx = (h[:, right] - h) / np.hypot(gain, gain[:, right])
        zy = (h[down] - h) / np.hypot(gain, gain[down])
    z = np.hypot(zx, zy)
    z[~(valid & valid[:, right] & valid[down])] = np.nan
    return z


def _random_rgb(shape, dtype, seed):
    rng = np.random.default_rng(seed)
    top = FULL_SCALE[dtype]
    x = rng.random(shape + (3,)) ** 2 * top  # squared: many dark pixels, so the mask matters
    return x.astype(dtype)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
@pytest.mark.parametrize("shape", [(1, 1), (1, 13), (13, 1), (37, 53)], ids=str)
@pytest.mark.parametrize("chromaticity", [False, True])
def test_hue_matches_oracle(dtype, shape, chromaticity, machine):
    rgb = _random_rgb(shape, dtype, seed=shape[0] * 100 + shape[1])
    threshold = 0.2 * FULL_SCALE[dtype]
    out, valid = color.hue(rgb, min_intensity=threshold, chromaticity=chromaticity, machine=machine)
    want, want_valid = _hue_oracle(rgb, threshold, chromaticity)
    assert valid.dtype == bool and out.dtype == np.float32
    np.testing.assert_array_equal(valid, want_valid)
    np.testing.assert_allclose(out, want, rtol=1e-6, equal_nan=True)


def test_default_min_intensity_is_five_percent_of_full_scale(machine):
    rgb = np.zeros((1, 4, 3), np.uint8)
    rgb[0, :, 0] = [6, 7, 12, 13]
    rgb[0, :, 1] = 0  # R + G = 6, 7, 12, 13 against 0.05 * 255 = 12.75
    assert color.hue(rgb, machine=machine).valid.tolist() == [[False, False, False, True]]


def test_device_in_device_out_and_local_sizes_agree(machine_with_local_size):
    m = machine_with_local_size
    rgb = _random_rgb((29, 67), np.float32, seed=3)
    reference = color.albedo_edges(rgb, min_intensity=0.1)
    got = color.albedo_edges(m.to_device(rgb), min_intensity=0.1, machine=m)
    assert all(isinstance(a, cl_array.Array) for a in got)
    np.testing.assert_array_equal(got.edges.get().view(bool), reference.edges)
    np.testing.assert_array_equal(got.hue.get(), reference.hue)
    np.testing.assert_array_equal(got.valid.get().view(bool), reference.valid)
    h = color.hue(m.to_device(rgb), chromaticity=True, machine=m)
    np.testing.assert_array_equal(h.hue.get(), color.hue(rgb, chromaticity=True).hue)


def test_device_input_marks_non_finite_pixels_invalid(machine):
    rgb = np.full((2, 3, 3), 0.5, np.float32)
    rgb[0, 0, 2], rgb[1, 2, 0] = np.nan, np.inf
    h, valid = color.hue(machine.to_device(rgb), machine=machine)
    assert valid.get().tolist() == [[0, 1, 1], [1, 1, 0]]
    assert np.isnan(h.get()[[0, 1], [0, 2]]).all()


@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_albedo_edges_match_oracle_with_a_fixed_threshold(dtype, machine):
    rgb = _random_rgb((41, 59), dtype, seed=7)
    least = 0.3 * FULL_SCALE[dtype]
    z = _z_oracle(rgb, least)
    threshold = float(np.nanmedian(z))
    got = color.albedo_edges(rgb, min_intensity=least, threshold=threshold, machine=machine)
    want = z > threshold
    close = np.abs(z - threshold) <= 1e-5 * threshold  # float32 rounding decides these
    assert 0.1 < want.mean() < 0.5  # both outcomes are well represented
    assert close.mean() < 0.01  # so the comparison below covers nearly every pixel
    np.testing.assert_array_equal(got.edges[~close], want[~close])
    hue, valid = _hue_oracle(rgb, least)
    np.testing.assert_array_equal(got.valid, valid)
    np.testing.assert_allclose(got.hue, hue, rtol=1e-6, equal_nan=True)


def test_noise_rule_estimates_the_channel_noise(machine):
    # Constant albedo, a strong shading ramp and Gaussian noise of deviation s on every channel:
    # the rule's threshold is NOISE_HIGH * s, and few pixels pass.
    rng = np.random.default_rng(11)
    s = 0.01
    ramp = np.linspace(0.3, 1.0, 512, dtype=np.float32)[None, :, None]
    rgb = (np.array([0.7, 0.5, 0.3], np.float32) * ramp * np.ones((512, 1, 1), np.float32)
           + rng.normal(0, s, (512, 512, 3)).astype(np.float32))
    edges = color.albedo_edges(rgb, machine=machine).edges
    z = _z_oracle(rgb, 0.05)
    estimated = np.nanmedian(z) / math.sqrt(2 * math.log(2))
    assert abs(estimated / s - 1) < 0.08  # zx and zy share the centre pixel: not quite Rayleigh
    threshold = noise.NOISE_HIGH * estimated
    decided = np.abs(z - threshold) > 0.01 * threshold  # the device median comes from a histogram
    np.testing.assert_array_equal(edges[decided], (z > threshold)[decided])
    assert edges.mean() < 3e-3


@pytest.fixture(scope="module")
def shadows():
    return scenes.render(scenes.preset("shadows", shape=(256, 256)), seed=1)


def test_hue_is_constant_in_each_albedo_region_where_intensity_is_not(shadows, machine):
    h, valid = color.hue(shadows.left, machine=machine)
    assert valid.all()
    intensity = shadows.left.mean(axis=2)
    wall_regions = 0
    for region in np.unique(shadows.regions):
        inside = shadows.regions == region
        hues, values = h[inside], intensity[inside]
        assert (hues.max() - hues.min()) / hues.mean() < 0.02
        if (shadows.bodies[inside] == 0).all():  # the wall: its light gradient is strong
            wall_regions += 1
            assert (values.max() - values.min()) / values.max() > 0.30
    assert wall_regions == 7  # the grey wall and its six colours


def test_albedo_edges_find_albedo_edges_and_not_shadows(shadows, machine):
    # An 8-bit camera with noise of half a grey level.
    rng = np.random.default_rng(5)
    noisy = shadows.left + rng.normal(0, 0.5 / 255, shadows.left.shape).astype(np.float32)
    rgb = np.clip(np.round(noisy * 255), 0, 255).astype(np.uint8)
    albedo = shadows.labels == Label.ALBEDO
    shadow = shadows.labels == Label.SHADOW
    assert albedo.sum() > 500 and shadow.sum() > 100
    edges = color.albedo_edges(rgb, machine=machine).edges
    assert metrics.detection_scores(edges, albedo, tolerance=1).recall >= 0.90
    assert metrics.detection_scores(edges, shadow, tolerance=1).recall < 0.10
    brightness = canny(rgb, sigma=1.0, machine=machine)
    assert metrics.detection_scores(brightness, shadow, tolerance=1).recall == 1.0


def test_bad_input_is_refused(machine):
    with pytest.raises(ValueError, match="rgb must be an RGB image"):
        color.hue(np.zeros((8, 8), np.float32), machine=machine)
    with pytest.raises(ValueError, match="rgb must be an RGB image"):
        color.albedo_edges(np.zeros((8, 8, 1), np.uint8), machine=machine)
    bad = np.ones((4, 4, 3))
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match="rgb must not contain NaN"):
        color.hue(bad, machine=machine)
    with pytest.raises(ValueError, match="min_intensity"):
        color.hue(np.ones((4, 4, 3), np.float32), min_intensity=0, machine=machine)
    with pytest.raises(TypeError, match="rgb must have dtype"):
        color.hue(np.ones((4, 4, 3), np.int64), machine=machine)
    with pytest.raises(ValueError, match="threshold"):
        color.albedo_edges(np.ones((4, 4, 3), np.float32), threshold=-1.0, machine=machine)


@pytest.mark.parametrize("call, error, match", [
    (lambda m: color.hue(np.ones((4, 4, 3), np.float32), chromaticity="no", machine=m), TypeError, "chromaticity"),
    (lambda m: color.hue(np.ones((4, 4, 3), np.float32), chromaticity=None, machine=m), TypeError, "chromaticity"),
    (lambda m: color.hue(np.ones((4, 4, 3), np.float32), chromaticity=1, machine=m), TypeError, "chromaticity"),
])
def test_chromaticity_must_be_a_bool(call, error, match, machine):
    """chromaticity="no" used to return the chromaticity pair (a non-empty string is true)."""
    with pytest.raises(error, match=match):
        call(machine)


@pytest.mark.parametrize("shape", [(2, 2, 3), (8, 48, 3)])  # the scalar kernel and the 16-pixel one
def test_a_sum_that_overflows_float32_gives_no_hue(shape, machine):
    # R + G = inf gave a hue of 0 (R / inf), marked valid.
    image = np.full(shape, 3e38, np.float32)
    found = color.hue(image, machine=machine)
    assert not found.valid.any() and np.isnan(found.hue).all()
    assert not color.hue(image, chromaticity=True, machine=machine).valid.any()
    assert np.isnan(color.albedo_edges(image, machine=machine).hue).all()
