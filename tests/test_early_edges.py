"""Canny and zero crossings: every stage against a NumPy oracle, localisation on synthetic step edges,
agreement with scikit-image, and BSDS500 boundaries where the data is present."""

import math

import numpy as np
import pytest
from scipy import ndimage

from vmcl import Machine
from vmcl.early import filters, noise
from vmcl.early.edges import CannyResult, canny, hysteresis_threshold, zero_crossings
from vmcl.metrics import detection_scores
from vmcl.patterns import spiral

skimage = pytest.importorskip("skimage")
from skimage import color, data, feature

EIGHT = np.ones((3, 3), bool)


# ------------------------------------------------------------------------------------------- oracles


def _smooth(image, sigma):
    return ndimage.gaussian_filter(np.asarray(image, np.float64), sigma, mode="nearest", truncate=4.0)


def _gradient(image, sigma):
    s = _smooth(image, sigma)
    gx, gy = ndimage.sobel(s, axis=1, mode="nearest"), ndimage.sobel(s, axis=0, mode="nearest")
    return np.hypot(gx, gy), gx, gy


def _nms(m, gx, gy, interpolate):
    """Maxima along the gradient, and how far each pixel is from the decision (ties are decided by
    rounding, so pixels within float32 rounding of it are left out of comparisons)."""
    h, w = m.shape
    padded = np.pad(m, 1, mode="edge")

    def at(dx, dy):
        return padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]

    ax, ay = np.abs(gx), np.abs(gy)
    same = (gy > 0) == (gx > 0)
    if interpolate:
        ymajor = np.where(same, ay > ax, ay >= ax)
        with np.errstate(divide="ignore", invalid="ignore"):
            weight = np.nan_to_num(np.where(ymajor, ax / ay, ay / ax))
        plus = np.where(same, at(1, 1), at(1, -1)) * weight + np.where(
            ymajor, np.where(same, at(0, 1), at(0, -1)), at(1, 0)) * (1 - weight)
        minus = np.where(same, at(-1, -1), at(-1, 1)) * weight + np.where(
            ymajor, np.where(same, at(0, -1), at(0, 1)), at(-1, 0)) * (1 - weight)
    else:
        tan22 = math.tan(math.pi / 8)
        horizontal = ay <= tan22 * ax
        vertical = ~horizontal & (ax <= tan22 * ay)
        plus = np.select([horizontal, vertical, same], [at(1, 0), at(0, 1), at(1, 1)], at(1, -1))
        minus = np.select([horizontal, vertical, same], [at(-1, 0), at(0, -1), at(-1, -1)], at(-1, 1))
    margin = np.minimum(m - plus, m - minus)
    inner = np.zeros(m.shape, bool)
    inner[1:-1, 1:-1] = True
    return (margin >= 0) & inner & (m > 0), np.abs(margin)


def _hysteresis(weak, strong):
    labels, _ = ndimage.label(weak, EIGHT)
    keep = np.zeros(labels.max() + 1, bool)
    keep[np.unique(labels[strong & weak])] = True
    keep[0] = False
    return keep[labels]


# ------------------------------------------------------------------------------------------- stages


@pytest.fixture(scope="module")
def camera():
    return data.camera()[100:260, 150:390]


def test_gradient_matches_sobel_of_the_gaussian(camera, machine):
    _, magnitude, direction = canny(camera, sigma=1.5, low_threshold=10, high_threshold=20, return_gradient=True,
                                    machine=machine)
    m, gx, gy = _gradient(camera, 1.5)
    np.testing.assert_allclose(magnitude, m, rtol=0, atol=2e-5 * 8 * 255)
    # An error e in the derivatives turns the direction by up to e / m.
    turn = np.angle(np.exp(1j * (direction - np.arctan2(gy, gx))))
    assert (np.abs(turn) * m).max() < 0.05


@pytest.mark.parametrize("interpolate", [True, False])
def test_non_maximum_suppression_matches_oracle(camera, interpolate, machine):
    # With low == high every weak pixel is strong, so the edges are the maxima above the threshold.
    threshold = 4.0
    edges = canny(camera, sigma=1.0, low_threshold=threshold, high_threshold=threshold, interpolate=interpolate,
                  machine=machine)
    m, gx, gy = _gradient(camera, 1.0)
    maxima, margin = _nms(m, gx, gy, interpolate)
    want = maxima & (m >= threshold)
    decided = (margin > 1e-3) & (np.abs(m - threshold) > 1e-3)
    assert decided.mean() > 0.99
    np.testing.assert_array_equal(edges[decided], want[decided])


@pytest.mark.parametrize("method", ["doubling", "iterative"])
@pytest.mark.parametrize("shape, seed", [((1, 1), 0), ((1, 57), 1), ((64, 1), 2), ((97, 131), 3), ((256, 256), 4)])
def test_hysteresis_matches_labelling_oracle(shape, seed, method, machine):
    field = ndimage.gaussian_filter(np.random.default_rng(seed).random(shape), 1.0).astype(np.float32)
    low, high = np.quantile(field, [0.5, 0.9])
    got = hysteresis_threshold(field, low_threshold=float(low), high_threshold=float(high), method=method,
                               machine=machine)
    np.testing.assert_array_equal(got, _hysteresis(field >= np.float32(low), field >= np.float32(high)))


def test_hysteresis_follows_a_spiral_to_its_end(machine):
    # One chain of ~2000 weak pixels with a strong pixel at its outer end, and a copy with none.
    wall = spiral(64)
    field = np.zeros((64, 130), np.float32)
    field[:, :64] = 0.5 * wall
    field[:, 66:] = 0.5 * wall
    field[0, 0] = 1.0
    want = np.zeros(field.shape, bool)
    want[:, :64] = wall
    for method in ("doubling", "iterative"):
        got = hysteresis_threshold(field, low_threshold=0.4, high_threshold=0.9, method=method, machine=machine)
        np.testing.assert_array_equal(got, want)


def test_canny_is_the_composition_of_its_stages(camera, machine):
    low, high = 6.0, 15.0
    edges = canny(camera, sigma=1.4, low_threshold=low, high_threshold=high, machine=machine)
    m, gx, gy = _gradient(camera, 1.4)
    maxima, margin = _nms(m, gx, gy, True)
    want = _hysteresis(maxima & (m >= low), m >= high)
    # Rounding may flip a tie, and with it the fate of the chain it links: compare where it cannot.
    near = ndimage.binary_dilation((margin < 1e-3) | (np.abs(m - low) < 1e-3) | (np.abs(m - high) < 1e-3),
                                   EIGHT, iterations=2)
    unsure = ndimage.label(want | edges, EIGHT)[0]
    unsure = np.isin(unsure, np.unique(unsure[near & (want | edges)])) & (unsure > 0)
    assert (~unsure).mean() > 0.95
    np.testing.assert_array_equal(edges[~unsure], want[~unsure])


# ------------------------------------------------------------------------------------------- noise


def test_noise_estimate_on_pure_noise(machine):
    # The smoothed Sobel derivative of white noise of deviation sn has deviation sn * ||k|| (k: the
    # filter's impulse response); the estimate must recover it.
    sn, sigma = 0.05, 1.5
    image = np.random.default_rng(8).normal(0.5, sn, (384, 384)).astype(np.float32)
    _, magnitude, _ = canny(image, sigma=sigma, low_threshold=1, high_threshold=1, return_gradient=True,
                            machine=machine)
    impulse = np.zeros((41, 41))
    impulse[20, 20] = 1.0
    response = ndimage.sobel(ndimage.gaussian_filter(impulse, sigma, mode="constant"), axis=1, mode="constant")
    s = sn * np.sqrt((response**2).sum())
    low, high = noise.noise_thresholds(magnitude, machine=machine)
    assert abs(high / (noise.CANNY_HIGH * s) - 1) < 0.05
    assert low == pytest.approx(high * noise.CANNY_LOW / noise.CANNY_HIGH, rel=1e-6)


def test_noise_thresholds_are_histogram_medians(camera, machine):
    _, m, _ = canny(camera, sigma=1.0, low_threshold=1, high_threshold=1, return_gradient=True, machine=machine)
    width = m.max() / noise.BINS  # the estimate's resolution
    scale = np.array([noise.CANNY_LOW, noise.CANNY_HIGH]) / math.sqrt(2 * math.log(2))
    np.testing.assert_allclose(noise.noise_thresholds(m, machine=machine), np.median(m) * scale,
                               atol=width * scale[1])
    tiles = noise.noise_thresholds(m, noise="local", machine=machine)
    t = noise.TILE
    assert tiles.shape == (math.ceil(m.shape[0] / t), math.ceil(m.shape[1] / t), 2)
    for ty in range(tiles.shape[0]):
        for tx in range(tiles.shape[1]):
            median = np.median(m[ty * t:(ty + 1) * t, tx * t:(tx + 1) * t])
            np.testing.assert_allclose(tiles[ty, tx], median * scale, atol=width * scale[1])


def test_quantile_thresholds_match_percentiles(camera, machine):
    _, m, _ = canny(camera, sigma=1.0, low_threshold=1, high_threshold=1, return_gradient=True, machine=machine)
    pairs, _ = noise.threshold_field(machine, machine.to_device(m), (0.6, 0.9, 1.0, 1.0), local=False)
    np.testing.assert_allclose(pairs.get().ravel(), np.percentile(m, [60, 90]), atol=m.max() / noise.BINS)
    # canny with quantiles: the edges of the exact percentiles, except pixels within a bin of them.
    edges = canny(camera, sigma=1.0, low_threshold=0.6, high_threshold=0.9, use_quantiles=True, machine=machine)
    low, high = np.percentile(m, [60, 90])
    exact = canny(camera, sigma=1.0, low_threshold=float(low), high_threshold=float(high), machine=machine)
    assert (edges != exact).mean() < 1e-3


def test_one_threshold_given_keeps_the_rules_ratio(camera, machine):
    ratio = noise.CANNY_LOW / noise.CANNY_HIGH
    both = canny(camera, sigma=1.0, low_threshold=10 * ratio, high_threshold=10, machine=machine)
    np.testing.assert_array_equal(canny(camera, sigma=1.0, high_threshold=10, machine=machine), both)
    np.testing.assert_array_equal(canny(camera, sigma=1.0, low_threshold=10 * ratio, machine=machine), both)


# ------------------------------------------------------------------------------------------- localisation


def _step_scene(kind, noise_level, seed, n=192):
    """A unit step along a straight, slanted or circular boundary (anti-aliased) plus Gaussian noise,
    and the signed distance of every pixel centre to the boundary."""
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    if kind == "straight":
        d = x - 80.3
    elif kind == "slanted":
        angle = np.deg2rad(27)
        d = (x - 96.2) * np.cos(angle) + (y - 95.7) * np.sin(angle)
    else:
        d = 50.4 - np.hypot(x - 95.3, y - 97.8)
    image = np.clip(0.5 + d, 0, 1) + np.random.default_rng(seed).normal(0, noise_level, (n, n))
    return image.astype(np.float32), d


@pytest.mark.parametrize("kind", ["straight", "slanted", "circle"])
@pytest.mark.parametrize("thresholds, options", [
    ({"low_threshold": 0.3, "high_threshold": 0.6}, {}),
    ({"low_threshold": 0.3, "high_threshold": 0.6}, {"method": "iterative", "interpolate": False}),
    ({}, {"noise": "global"}),
    ({}, {"noise": "local", "method": "iterative"}),
])
@pytest.mark.parametrize("sigma", [1.0, 2.0])
def test_localisation_on_step_edges(kind, thresholds, options, sigma, machine):
    image, d = _step_scene(kind, 0.05, seed=int(sigma * 10))
    edges = canny(image, sigma=sigma, machine=machine, **thresholds, **options)
    inner = np.zeros(edges.shape, bool)
    inner[4:-4, 4:-4] = True  # the outermost ring is never an edge
    edges &= inner
    truth = (np.abs(d) <= 0.5) & inner
    distance = np.abs(d[edges])
    assert distance.mean() <= 0.5
    assert detection_scores(edges, truth, tolerance=1.0).recall >= 0.95
    assert (distance > 1.0).mean() <= 0.05


# ------------------------------------------------------------------------------------------- skimage


@pytest.mark.parametrize("name", ["camera", "coins", "astronaut"])
@pytest.mark.parametrize("sigma, low, high", [(1.0, 20.0, 40.0), (2.0, 10.0, 25.0)])
def test_agreement_with_skimage(name, sigma, low, high, machine):
    image = getattr(data, name)()
    grey = color.rgb2gray(image) if image.ndim == 3 else image
    # skimage scales integer images to [0, 1] and divides thresholds by the dtype's maximum; its rgb2gray
    # output is already in [0, 1], so the thresholds are given in those units.
    scale = 255.0 if image.ndim == 3 else 1.0
    theirs = feature.canny(grey, sigma=sigma, low_threshold=low / scale, high_threshold=high / scale,
                           mode="nearest")
    ours = canny(image, sigma=sigma, low_threshold=low, high_threshold=high, machine=machine)
    assert detection_scores(ours, theirs, tolerance=1.0).f >= 0.95


# ------------------------------------------------------------------------------------------- zero crossings


def _zero_crossing_oracle(f, min_slope):
    p = np.pad(f, 1, mode="edge")
    c, left, right, up, down = p[1:-1, 1:-1], p[1:-1, :-2], p[1:-1, 2:], p[:-2, 1:-1], p[2:, 1:-1]

    def opposite(a, b):
        return ((a > 0) & (b < 0)) | ((a < 0) & (b > 0))

    def nearer(q):
        return opposite(c, q) & ((np.abs(c) < np.abs(q)) | ((np.abs(c) == np.abs(q)) & (c > 0)))

    crossing = np.where(c == 0, opposite(left, right) | opposite(up, down),
                        nearer(left) | nearer(right) | nearer(up) | nearer(down))
    dx, dy = 0.5 * (right - left), 0.5 * (down - up)
    slope = np.sqrt(dx * dx + dy * dy)
    keep = crossing & (slope >= min_slope)
    return keep, np.where(keep, -np.sign(dx), 0).astype(np.int8), np.where(keep, slope, 0)


@pytest.mark.parametrize("method", ["log", "dog"])
@pytest.mark.parametrize("min_slope", [0.0, 0.5])
def test_zero_crossings_match_oracle(camera, method, min_slope, machine):
    z = zero_crossings(camera, sigma=2.0, method=method, min_slope=min_slope, machine=machine)
    mask, sign, slope = _zero_crossing_oracle(z.response, min_slope)
    np.testing.assert_array_equal(z.mask, mask)
    np.testing.assert_array_equal(z.sign, sign)
    np.testing.assert_allclose(z.slope, slope, rtol=1e-6)
    want = (filters.laplacian_of_gaussian(camera, sigma=2.0, machine=machine) if method == "log" else
            -filters.difference_of_gaussians(camera, low_sigma=2.0 / math.sqrt(1.6), machine=machine))
    np.testing.assert_allclose(z.response, want, rtol=0, atol=1e-5 * 255)


@pytest.mark.parametrize("method", ["log", "dog"])
@pytest.mark.parametrize("sigma", [1.5, 3.0])
def test_zero_crossings_of_a_disc_lie_on_its_circle(method, sigma, machine):
    n, radius = 160, 47.3
    y, x = np.mgrid[0:n, 0:n]
    d = radius - np.hypot(x - 79.6, y - 81.2)
    disc = np.clip(0.5 + d, 0, 1).astype(np.float32)
    # The two smoothings of a DoG round differently, leaving ~1e-7 where the image is flat; the real
    # crossings have slopes above 1e-2.
    z = zero_crossings(disc, sigma=sigma, method=method, min_slope=1e-4 if method == "dog" else 0.0,
                       machine=machine)
    assert np.abs(d[z.mask]).max() <= 1.0
    assert detection_scores(z.mask, np.abs(d) <= 0.5, tolerance=1.0).recall >= 0.95


def test_zero_crossing_sign_is_the_brightness_polarity(machine):
    step = np.zeros((24, 40), np.float32)
    step[:, 20:] = 1.0
    for image, polarity in ((step, 1), (1.0 - step, -1)):
        z = zero_crossings(image, sigma=1.5, machine=machine)
        assert z.mask.sum() == 24 and set(np.unique(z.sign[z.mask])) == {polarity}
        assert (z.sign[~z.mask] == 0).all()


# ------------------------------------------------------------------------------------------- machines


CANNY_CASES = [
    {"low_threshold": 8.0, "high_threshold": 20.0},
    {"noise": "local", "method": "iterative"},
    {"low_threshold": 0.7, "high_threshold": 0.95, "use_quantiles": True, "interpolate": False},
]


def test_results_do_not_depend_on_the_local_size(camera, machine_with_local_size, machine):
    rgb = data.astronaut()[:150, 100:317]
    for kwargs in CANNY_CASES:
        np.testing.assert_array_equal(canny(rgb, sigma=1.2, machine=machine_with_local_size, **kwargs),
                                      canny(rgb, sigma=1.2, machine=machine, **kwargs))
    for got, want in zip(zero_crossings(camera, sigma=2.0, method="dog", machine=machine_with_local_size),
                         zero_crossings(camera, sigma=2.0, method="dog", machine=machine)):
        np.testing.assert_array_equal(got, want)


def test_one_pixel_per_work_item_on_gpus_gives_the_same_values(camera, machine):
    expected = [canny(camera, sigma=1.2, machine=machine, **kwargs) for kwargs in CANNY_CASES]
    crossings = zero_crossings(camera, sigma=2.0, machine=machine)
    scalar = Machine()
    scalar.vector_width = 1
    for kwargs, want in zip(CANNY_CASES, expected):
        np.testing.assert_array_equal(canny(camera, sigma=1.2, machine=scalar, **kwargs), want)
    for got, want in zip(zero_crossings(camera, sigma=2.0, machine=scalar), crossings):
        np.testing.assert_array_equal(got, want)


def test_device_in_device_out(camera, machine):
    device = machine.to_device(camera)
    edges, magnitude, direction = canny(device, sigma=1.0, return_gradient=True, machine=machine)
    host = canny(camera, sigma=1.0, return_gradient=True, machine=machine)
    assert isinstance(host, CannyResult)
    assert edges.dtype == np.uint8 and host.edges.dtype == np.bool_
    np.testing.assert_array_equal(edges.get().astype(bool), host.edges)
    np.testing.assert_array_equal(magnitude.get(), host.magnitude)
    np.testing.assert_array_equal(direction.get(), host.direction)
    z = zero_crossings(device, sigma=2.0, machine=machine)
    assert not isinstance(z.mask, np.ndarray)
    np.testing.assert_array_equal(z.mask.get().astype(bool), zero_crossings(camera, sigma=2.0, machine=machine).mask)


# ------------------------------------------------------------------------------------------- bad input


def test_bad_input_is_refused(machine):
    image = np.zeros((8, 8), np.float32)
    for sigma in (0, -0.5):
        with pytest.raises(ValueError, match="sigma must be a finite number > 0"):
            canny(image, sigma=sigma, machine=machine)
        with pytest.raises(ValueError, match="sigma must be a finite number > 0"):
            zero_crossings(image, sigma=sigma, machine=machine)
    with pytest.raises(ValueError, match=r"low_threshold \(5.0\) must not exceed high_threshold \(2.0\)"):
        canny(image, sigma=1.0, low_threshold=5, high_threshold=2, machine=machine)
    with pytest.raises(ValueError, match="high_threshold must be a quantile in"):
        canny(image, sigma=1.0, low_threshold=0.5, high_threshold=1.5, use_quantiles=True, machine=machine)
    with pytest.raises(ValueError, match="low_threshold must be a finite number >= 0"):
        canny(image, sigma=1.0, low_threshold=-0.1, high_threshold=0.5, use_quantiles=True, machine=machine)
    with pytest.raises(ValueError, match="low_threshold must be a finite number >= 0"):
        canny(image, sigma=1.0, low_threshold=float("nan"), machine=machine)
    with pytest.raises(ValueError, match="image must have 2 or 3 dimensions"):
        canny(np.zeros(16, np.float32), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="image must have 2 or 3 dimensions"):
        canny(np.zeros((2, 8, 8, 3), np.uint8), sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="image must have 2 or 3 dimensions"):
        zero_crossings(np.zeros(16, np.float32), sigma=1.0, machine=machine)
    nan = image.copy()
    nan[3, 3] = np.nan
    with pytest.raises(ValueError, match="image must not contain NaN"):
        canny(nan, sigma=1.0, machine=machine)
    with pytest.raises(ValueError, match="method must be"):
        canny(image, sigma=1.0, method="recursive", machine=machine)
    with pytest.raises(ValueError, match="noise must be"):
        canny(image, sigma=1.0, noise="tiled", machine=machine)
    with pytest.raises(ValueError, match="method must be 'log' or 'dog'"):
        zero_crossings(image, sigma=1.0, method="canny", machine=machine)
    with pytest.raises(ValueError, match="min_slope must be a finite number >= 0"):
        zero_crossings(image, sigma=1.0, min_slope=-1, machine=machine)
    with pytest.raises(TypeError, match="image must have dtype float32"):
        hysteresis_threshold(np.zeros((4, 4)), low_threshold=0, high_threshold=1, machine=machine)


# ------------------------------------------------------------------------------------------- BSDS500

BSDS_SIGMA = 2.0
BSDS_LEVELS = np.geomspace(0.5, 2.0, 4)
"""The sweep: high thresholds from half to twice the noise rule's 6 s, low = high / 2."""


def _soft_map(shape, detect):
    """Boundary strength from a sweep: a pixel holds (i + 1) / (K + 1) for the highest level i whose
    edges hold it (Canny's edges shrink as the thresholds grow)."""
    strength = np.zeros(shape)
    for i, level in enumerate(BSDS_LEVELS):
        strength[detect(level)] = (i + 1) / (len(BSDS_LEVELS) + 1)
    return strength


def test_bsds500_boundaries_at_least_as_good_as_skimage(datasets_root, machine):
    # vmcl's sweep is placed at multiples of each image's noise estimate (the paper's noise estimation);
    # skimage's canny gets the same multiples of the data set's mean estimate, fixed thresholds as it is
    # used. Given the same thresholds both give the same edges (test_agreement_with_skimage).
    from vmcl.datasets import load_bsds
    from vmcl.metrics import evaluate_boundaries

    images = load_bsds(datasets_root).images
    assert len(images) == 10
    noise_scales = []
    for im in images:
        _, magnitude, _ = canny(im.image, sigma=BSDS_SIGMA, low_threshold=0, high_threshold=0,
                                return_gradient=True, machine=machine)
        noise_scales.append(float(noise.noise_thresholds(magnitude, machine=machine)[1]) / noise.CANNY_HIGH)
    mean_scale = float(np.mean(noise_scales))
    ratio = noise.CANNY_LOW / noise.CANNY_HIGH
    ours, theirs = [], []
    for im, s in zip(images, noise_scales):
        grey = color.rgb2gray(im.image)
        ours.append(_soft_map(grey.shape, lambda k, image=im.image, s=s: canny(
            image, sigma=BSDS_SIGMA, low_threshold=k * ratio * noise.CANNY_HIGH * s,
            high_threshold=k * noise.CANNY_HIGH * s, machine=machine)))
        theirs.append(_soft_map(grey.shape, lambda k, grey=grey: feature.canny(
            grey, sigma=BSDS_SIGMA, low_threshold=k * ratio * noise.CANNY_HIGH * mean_scale / 255,
            high_threshold=k * noise.CANNY_HIGH * mean_scale / 255, mode="nearest")))
    truths = [list(im.boundaries) for im in images]
    levels = np.arange(1, len(BSDS_LEVELS) + 1) / (len(BSDS_LEVELS) + 1)
    vmcl_scores = evaluate_boundaries(ours, truths, thresholds=levels, workers=2)
    skimage_scores = evaluate_boundaries(theirs, truths, thresholds=levels, workers=2)
    print(f"BSDS500 test (10 images): vmcl ODS {vmcl_scores.ods_f:.4f} OIS {vmcl_scores.ois_f:.4f}; "
          f"skimage ODS {skimage_scores.ods_f:.4f} OIS {skimage_scores.ois_f:.4f}")
    assert vmcl_scores.ods_f >= skimage_scores.ods_f
    assert vmcl_scores.ois_f >= skimage_scores.ois_f


def _scene_grey() -> np.ndarray:
    from vmcl import scenes

    return np.asarray(scenes.render(scenes.preset("cues", shape=(96, 128)), seed=0, noise=0.01).left, np.float32)


@pytest.mark.parametrize("scale", [1e-42, 1e-30, 1e-10, 1e10, 1e20, 1e30, 1e38])
def test_canny_with_estimated_thresholds_is_scale_invariant(scale, machine):
    image = _scene_grey()
    expected = canny(image, sigma=1.0, machine=machine)
    assert expected.sum() > 500
    np.testing.assert_array_equal(canny(image * np.float32(scale), sigma=1.0, machine=machine), expected)


def test_canny_with_one_huge_pixel_marks_only_around_it(machine):
    image = _scene_grey().mean(axis=2)
    image[40, 123] = 1e30  # in the last 8 columns: the scalar path of the histogram
    edges = canny(image, sigma=1.0, machine=machine)
    rows, cols = np.nonzero(edges)
    assert len(rows) and np.abs(rows - 40).max() <= 4 and np.abs(cols - 123).max() <= 4


def test_noise_thresholds_of_subnormal_and_non_finite_magnitudes(machine):
    tiny = np.float32(1e-42)
    got = noise.noise_thresholds(np.full((40, 56), tiny, np.float32), machine=machine)
    expected = np.array([noise.CANNY_LOW, noise.CANNY_HIGH]) * float(tiny) / math.sqrt(2 * math.log(2))
    np.testing.assert_allclose(got, expected, rtol=2e-3)
    for bad in (np.inf, np.nan):
        magnitude = np.ones((40, 56), np.float32)
        magnitude[3, 3] = bad
        with pytest.raises(ValueError, match="magnitude must not contain NaN or infinite values"):
            noise.noise_thresholds(magnitude, machine=machine)


def test_noise_thresholds_refuse_negative_magnitudes_and_thresholds_beyond_float32(machine):
    """Magnitudes are >= 0 (negative ones were taken as they came); a field of 3e38 gave thresholds of
    infinity, its high threshold about 5 times its median. The largest magnitude taken gives finite ones."""
    magnitude = np.ones((40, 56), np.float32)
    magnitude[3, 3] = -1
    with pytest.raises(ValueError, match="magnitude must be >= 0"):
        noise.noise_thresholds(magnitude, machine=machine)
    with pytest.raises(ValueError, match="magnitude must be at most 6.68e\\+37"):
        noise.noise_thresholds(np.full((40, 56), 3e38, np.float32), machine=machine)
    largest = np.float32(float(np.finfo(np.float32).max) * math.sqrt(2 * math.log(2)) / noise.CANNY_HIGH)
    for kind in ("global", "local"):
        assert np.isfinite(noise.noise_thresholds(np.full((40, 56), largest), noise=kind, machine=machine)).all()


def test_canny_refuses_what_float32_or_the_device_cannot_hold(machine):
    with pytest.raises(ValueError, match="gradient magnitudes beyond float32's range"):
        canny(np.kron(np.eye(2, dtype=np.float32), np.full((16, 16), 3e38, np.float32)), sigma=1.0,
              return_gradient=True, machine=machine)
    # np.zeros does not touch its pages: the refusal comes before anything is read or uploaded. The side is
    # past what the device holds in one float32 buffer (a GPU with 139 GiB holds a 32768 x 32768 canny).
    side = max(32768, math.isqrt(machine.device.max_mem_alloc_size // 4) + 1)
    with pytest.raises(ValueError, match=f"canny of a {side} x {side} image needs"):
        canny(np.zeros((side, side), np.uint8), sigma=1.0, machine=machine)


def test_interpolate_must_be_a_bool(machine):
    # "no" was taken as True.
    with pytest.raises(TypeError, match="interpolate"):
        canny(np.zeros((16, 16), np.float32), interpolate="no", machine=machine)
