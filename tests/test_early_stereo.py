"""The stereo matcher: a NumPy oracle on random features, and quality on scenes with exact ground truth."""

import math

import numpy as np
import pytest
from oracles import box_sum as box_oracle
from scipy import ndimage

from vmcl import scenes
from vmcl.early.stereo import match, match_features
from vmcl.labels import Label
from vmcl.scenes import Body, Camera, Face, Light, Texture, World

DENSE_EDGES = {"low_threshold": 0.6, "high_threshold": 0.85, "use_quantiles": True}


def _direction_codes(direction):
    """Gradient directions as the matcher compares them: rounded to 1/65536 of a turn, mod 65536."""
    return np.rint(direction.astype(np.float32) * np.float32(65536 / (2 * np.pi))).astype(np.int64) % 65536


def _oracle(left, right, la, ra, d_min, d_max, patch, compatible, tolerance=0.35, min_score=0.3,
            bimodal=0.3, dip=0.8, min_votes=3.0):
    """The matcher written plainly: planes, window sums, the sequential selection, one suppression round."""
    _height, width = left.shape
    r, f32 = patch // 2, np.float32
    nl, nr = (box_oracle(m.astype(np.float32), r).astype(f32) for m in (left, right))
    best_s = np.full(left.shape, -np.inf, f32)
    best_d = np.full(left.shape, np.iinfo(np.int32).min)
    peak, valley, second = np.zeros(left.shape, f32), np.full(left.shape, np.inf, f32), np.zeros(left.shape, f32)
    for d in range(d_min, d_max + 1):
        plane = np.zeros(left.shape, bool)
        shifted = np.zeros(left.shape, bool)
        attr = np.zeros_like(ra)
        if d >= 0:
            shifted[:, d:], attr[:, d:] = right[:, :width - d], ra[:, :width - d]
        else:
            shifted[:, :d], attr[:, :d] = right[:, -d:], ra[:, -d:]
        if compatible == "direction":
            diff = (_direction_codes(la) - _direction_codes(attr)) % 65536
            ok = np.minimum(diff, 65536 - diff) <= math.floor(tolerance * 65536 / (2 * np.pi))
        else:
            ok = la == attr
        plane = left & shifted & ok
        votes = box_oracle(plane.astype(np.float32), r).astype(f32)
        nr_d = np.zeros(left.shape, f32)
        if d >= 0:
            nr_d[:, d:] = nr[:, :width - d]
        else:
            nr_d[:, :d] = nr[:, -d:]
        eligible = f32(0.5) * (nl + nr_d)
        with np.errstate(divide="ignore", invalid="ignore"):
            score = np.where(eligible > 0, votes / eligible, f32(0)).astype(f32)
        for y, x in zip(*np.nonzero(left)):
            if plane[y, x] and score[y, x] > best_s[y, x]:
                best_s[y, x], best_d[y, x] = score[y, x], d
            v = votes[y, x]
            if valley[y, x] <= f32(dip) * min(peak[y, x], v):
                second[y, x] = max(second[y, x], min(peak[y, x], v))
            if v > peak[y, x]:
                peak[y, x], valley[y, x] = v, np.inf
            else:
                valley[y, x] = min(valley[y, x], v)
    disparity = np.full(left.shape, np.nan, np.float32)
    out_of_range = np.zeros(left.shape, bool)
    discontinuity = left & (peak >= min_votes) & (second >= f32(bimodal) * peak)
    unset = np.iinfo(np.int32).min
    for y, x in zip(*np.nonzero(left)):
        s, d = best_s[y, x], best_d[y, x]
        matched = d != unset
        out_of_range[y, x] = not matched or s < min_score
        keep = matched and s >= min_score
        for xo in range(max(0, x - (d_max - d_min)), min(width - 1, x + d_max - d_min) + 1):
            if not keep:
                break
            if xo == x or not left[y, xo] or best_d[y, xo] == unset or best_s[y, xo] < min_score:
                continue
            here, there = x - d, xo - best_d[y, xo]
            stronger = best_s[y, xo] > s or (best_s[y, xo] == s and xo < x)
            if stronger and (there == here or (xo - x) * (there - here) < 0):
                keep = False
        if keep:
            disparity[y, x] = d
    return disparity, out_of_range, discontinuity


def _random_features(rng, shape, compatible):
    """Random left and right feature masks (30% of pixels) with random directions or signs."""
    left, right = rng.random(shape) < 0.3, rng.random(shape) < 0.3
    if compatible == "direction":
        la, ra = (rng.uniform(-np.pi, np.pi, shape).astype(np.float32) for _ in range(2))
    else:
        la, ra = (rng.choice(np.array([-1, 1], np.int8), shape) for _ in range(2))
    return left, right, la, ra


@pytest.mark.parametrize("compatible", ["direction", "sign"])
@pytest.mark.parametrize("variant", ["running", "table"])
@pytest.mark.parametrize("shape, d_min, d_max", [((23, 41), -2, 5), ((29, 97), -3, 37)])
def test_matches_numpy_oracle(compatible, variant, shape, d_min, d_max, machine):
    """Several groups of 16 disparities, a partial last one, and right pixels off both image borders."""
    rng = np.random.default_rng(0 if compatible == "sign" else 1)
    left, right, la, ra = _random_features(rng, shape, compatible)
    got = match_features(left, right, la, ra, d_min=d_min, d_max=d_max, compatible=compatible, patch=5,
                         direction_tolerance=math.radians(60), method=variant, machine=machine)
    disparity, out_of_range, discontinuity = _oracle(left, right, la, ra, d_min, d_max, 5, compatible,
                                                     tolerance=math.radians(60))
    np.testing.assert_array_equal(got.disparity, disparity)
    np.testing.assert_array_equal(got.out_of_range, out_of_range)
    np.testing.assert_array_equal(got.discontinuity, discontinuity)
    assert np.isfinite(disparity).sum() > 20 and discontinuity.sum() > 0


@pytest.mark.parametrize("compatible", ["direction", "sign"])
def test_variants_agree_with_barriers(compatible, machine):
    """The running variant sums clipped windows itself; the table sums its planes with _Support."""
    rng = np.random.default_rng(3)
    shape = (37, 61)
    left, right, la, ra = _random_features(rng, shape, compatible)
    barriers = rng.random(shape) < 0.08
    found = [match_features(left, right, la, ra, d_min=-3, d_max=20, compatible=compatible, patch=7,
                            barriers=barriers, direction_tolerance=math.radians(60), method=variant,
                            machine=machine) for variant in ("table", "running")]
    for name in ("disparity", "score", "out_of_range", "discontinuity"):
        np.testing.assert_array_equal(getattr(found[1], name), getattr(found[0], name))
    assert np.isfinite(found[0].disparity).sum() > 50


def test_features_drop_edges_near_horizontal(machine):
    """The left features are Canny's edges less those within horizontal_tolerance of horizontal,
    judged on the direction codes (the gradient's distance from vertical, in 1/65536 turns)."""
    from vmcl.early.edges import canny

    scene, d_min, d_max = _pair("corridor")
    edges, _, direction = canny(scene.left, sigma=2.0, return_gradient=True, machine=machine)
    from_vertical = np.abs((_direction_codes(direction) % 32768) - 16384)
    found = match(scene.left, scene.right, d_min=d_min, d_max=d_max, horizontal_tolerance=25.0, machine=machine)
    expected = edges & (from_vertical >= np.float32(25.0 * 65536 / 360))
    np.testing.assert_array_equal(found.features, expected)
    assert 0 < expected.sum() < edges.sum()
    # Matches lie on those features only, and agree with the scene's ground truth.
    matched = np.isfinite(found.disparity)
    assert not (matched & ~expected).any()
    visible = matched & ~scene.occluded_stereo & np.isfinite(scene.disparity)
    assert visible.sum() >= 0.5 * expected.sum()
    assert (np.abs(found.disparity - scene.disparity)[visible] <= 1).mean() >= 0.9


def _pair(name, noise=0.01):
    scene = scenes.render(scenes.preset(name, shape=(256, 256)), seed=0, noise=noise)
    return scene, int(np.floor(np.nanmin(scene.disparity))), int(np.ceil(np.nanmax(scene.disparity)))


@pytest.mark.parametrize("name", ["blocks", "corridor"])
def test_edge_matches_on_scenes(name, machine):
    scene, d_min, d_max = _pair(name)
    found = match(scene.left, scene.right, d_min=d_min, d_max=d_max, machine=machine)
    from vmcl.early.edges import canny

    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    edges = canny(scene.left, sigma=2.0, machine=machine) & visible
    matched = np.isfinite(found.disparity) & visible
    within = np.abs(found.disparity - scene.disparity)[matched] <= 1
    assert within.mean() >= 0.90
    assert matched.sum() / edges.sum() >= 0.70


def test_variants_and_local_sizes_agree(machine, machine_with_local_size):
    scene, d_min, d_max = _pair("blocks")
    left, right = scene.left[:96, :128], scene.right[:96, :128]
    reference = match(left, right, d_min=d_min, d_max=d_max, machine=machine)
    for variant, m in (("table", machine), ("running", machine_with_local_size)):
        other = match(left, right, d_min=d_min, d_max=d_max, method=variant, machine=m)
        np.testing.assert_array_equal(other.disparity, reference.disparity)
        np.testing.assert_array_equal(other.discontinuity, reference.discontinuity)


def test_out_of_range_flag_catches_edges_beyond_the_range(machine):
    scene, d_min, d_max = _pair("corridor")
    middle = (d_min + d_max) // 2
    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    for low, high in ((d_min, middle), (middle, d_max)):
        found = match(scene.left, scene.right, d_min=low, d_max=high, machine=machine)
        outside = found.features & visible & ((scene.disparity < low - 0.5) | (scene.disparity > high + 0.5))
        inside = found.features & visible & (scene.disparity >= low) & (scene.disparity <= high)
        assert outside.sum() > 100
        assert found.out_of_range[outside].mean() >= 0.80
        assert found.out_of_range[inside].mean() < 0.10


def two_planes(size=256):
    """A textured plate 3 m away in front of a textured wall at 8 m: disparities 12.8 and 4.8 px."""
    def px(pixels, depth):
        return pixels * depth / size
    wall = Face((-3.0, -3.0, 8.0), (1, 0, 0), (0, 1, 0), None, (0.6, 0.55, 0.5), Texture("noise", px(4, 8), 0.4))
    plate = Face((-0.6, -0.6, 3.0), (1, 0, 0), (0, 1, 0), (1.2, 1.2), (0.5, 0.6, 0.55), Texture("noise", px(4, 3), 0.4))
    world = World(Camera((size, size), float(size), 0.15), Light(), (Body((wall,)), Body((plate,))))
    return scenes.render(world, seed=1, noise=0.01)


def test_bimodal_votes_flag_depth_discontinuities(machine):
    scene = two_planes()
    found = match(scene.left, scene.right, d_min=2, d_max=16, patch=15, machine=machine, **DENSE_EDGES)
    depth_edges = scene.labels == Label.DEPTH
    reachable = depth_edges & ndimage.binary_dilation(found.features, iterations=2)
    flagged = ndimage.binary_dilation(found.discontinuity, iterations=2)
    assert flagged[reachable].mean() >= 0.60
    near_edges = ndimage.binary_dilation(depth_edges, iterations=7)
    assert near_edges[found.discontinuity].mean() >= 0.80


def test_barriers_keep_support_on_one_surface(machine):
    scene = two_planes()
    depth_edges = scene.labels == Label.DEPTH
    near = ndimage.binary_dilation(depth_edges, iterations=6) & ~scene.occluded_stereo
    accuracy, flags = [], []
    for barriers in (None, ndimage.binary_dilation(depth_edges)):
        found = match(scene.left, scene.right, d_min=2, d_max=16, barriers=barriers, machine=machine, **DENSE_EDGES)
        matched = np.isfinite(found.disparity) & near
        accuracy.append(np.mean(np.abs(found.disparity - scene.disparity)[matched] <= 1))
        flags.append(found.discontinuity.sum())
    assert accuracy[1] > accuracy[0] + 0.01 and accuracy[1] >= 0.97
    assert flags[1] < flags[0]


def test_barrier_windows_match_oracle(machine):
    from vmcl.early.stereo import _Support

    rng = np.random.default_rng(5)
    planes = (rng.random((3, 17, 29)) < 0.5).astype(np.float32)
    barrier = rng.random((17, 29)) < 0.1
    support = _Support(machine, 2, machine.to_device(barrier.astype(np.uint8)), (17, 29))
    got = support.sum(machine.to_device(planes)).get()
    expected = np.zeros_like(planes)
    for axis_rows in (True, False):
        source = planes if axis_rows else expected.copy()
        out = np.zeros_like(planes)
        lines = barrier if axis_rows else barrier.T
        data = source if axis_rows else np.swapaxes(source, 1, 2)
        result = np.zeros_like(data)
        for line in range(lines.shape[0]):
            walls = lines[line]
            run = np.cumsum(np.r_[True, walls[1:] | walls[:-1]])  # run id: a wall is a run of its own
            for t in range(len(walls)):
                same = np.flatnonzero(run == run[t])
                lo, hi = max(t - 2, same[0]), min(t + 2, same[-1])
                result[:, line, t] = data[:, line, lo:hi + 1].sum(axis=1)
        out = result if axis_rows else np.swapaxes(result, 1, 2)
        expected = out
    np.testing.assert_allclose(got, expected)


def test_intensity_variant_is_dense_and_accurate(machine):
    scene, d_min, d_max = _pair("blocks")
    found = match(scene.left, scene.right, d_min=d_min, d_max=d_max, features="intensity", machine=machine)
    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    matched = np.isfinite(found.disparity) & visible
    assert matched.sum() / visible.sum() >= 0.85
    assert np.mean(np.abs(found.disparity - scene.disparity)[matched] <= 1) >= 0.90



def test_intensity_matches_only_with_windows_inside_the_image(machine):
    """A disparity competes only where both patches lie inside the image (scored with the full area, cut
    windows were wrong): no match within r of the border; every pixel where the true disparity's windows
    fit is matched, exactly."""
    texture = np.random.default_rng(5).random((40, 67)).astype(np.float32)
    left, right = texture[:, :64], texture[:, 3:]  # left(x) = right(x - 3)
    found = match(left, right, d_min=-1, d_max=8, patch=5, sigma=0.3, features="intensity", subpixel=False,
                  machine=machine)
    inside = np.zeros(left.shape, bool)
    inside[2:38, 2:62] = True  # r = 2 from every border
    matched = np.isfinite(found.disparity)
    assert not (matched & ~inside).any()
    assert np.all(found.disparity[2:38, 3 + 2:62] == 3)  # where x - 3 - r >= 0
    # Nearer the left border only disparities that keep the right patch inside compete (the winners
    # there then lose to the true matches in the suppression).
    assert np.all(found.disparity[2:38, 2:5][matched[2:38, 2:5]] <= 2)

def test_intensity_matches_keep_every_score_whatever_min_score(machine):
    """min_score cuts edge matches only (the docstring): an intensity match's correlation is its weight
    downstream, so the weak ones stay matched, none flagged out of range, at any min_score."""
    rng = np.random.default_rng(3)
    texture = rng.random((40, 68)).astype(np.float32)
    left, right = texture[:, :64], texture[:, 4:] + 0.5 * rng.random((40, 64)).astype(np.float32)
    found = {score: match(left, right, d_min=0, d_max=8, patch=5, sigma=0.5, features="intensity",
                          min_score=score, machine=machine) for score in (-1.0, 0.99)}
    weak = np.isfinite(found[-1.0].disparity) & (found[-1.0].score < 0.99)
    assert weak.sum() > 100  # the noise leaves many matches below the higher min_score
    for name in ("disparity", "score", "out_of_range"):
        np.testing.assert_array_equal(getattr(found[0.99], name), getattr(found[-1.0], name))
    assert not (found[0.99].out_of_range & np.isfinite(found[0.99].score)).any()


def test_a_device_view_is_refused_naming_it(machine):
    """A view's buffer starts elsewhere than its first element: refused by the pair's names, where it was
    refused as "image" (a helper's name) or by the kernel launch, naming nothing."""
    host = np.random.default_rng(0).random((32, 48)).astype(np.float32)
    whole = machine.to_device(host)
    with pytest.raises(ValueError, match="^left must be a C-contiguous device array"):
        match(whole[:, :40], machine.to_device(host[:, :40].copy()), d_min=0, d_max=4, machine=machine)
    with pytest.raises(ValueError, match="^right must not be a device view with an offset"):
        match(machine.to_device(host[4:].copy()), whole[4:], d_min=0, d_max=4, machine=machine)


def test_intensity_score_does_not_depend_on_the_brightness_level(machine):
    """A correlation ignores an added constant; float32 patch moments of raw uint8 brightness near 220
    lost the variance of a low-contrast texture (scores up to 4.6, half the matches wrong)."""
    texture = np.random.default_rng(1).normal(0, 2, (48, 84)).astype(np.float32)
    found = {}
    for level in (30, 220):
        pair = [np.clip(level + texture[:, k:k + 80], 0, 255).astype(np.uint8) for k in (0, 4)]
        found[level] = match(*pair, d_min=0, d_max=8, patch=7, features="intensity", subpixel=False,
                             machine=machine)
        assert np.nanmax(found[level].score) <= 1
    matched = np.isfinite(found[30].disparity)
    assert matched.mean() > 0.7 and np.mean(found[30].disparity[matched] == 4) > 0.95
    same = (found[220].disparity == found[30].disparity) | ~(matched | np.isfinite(found[220].disparity))
    assert same.mean() > 0.99
    flat = np.full((32, 48), 100, np.uint8)
    assert not np.isfinite(match(flat, flat, d_min=0, d_max=4, patch=5, features="intensity",
                                 machine=machine).disparity).any()


def _intensity_scores_oracle(left, right, d_min, d_max, patch, sigma):
    """Intensity scores in float64, a (D, H, W) table: each cell's centred correlation of the smoothed,
    mean-centred brightness (-inf where a window leaves either image or is flat)."""
    from vmcl.early.filters import gaussian

    r = patch // 2
    smooth = [gaussian(image, sigma=sigma, method="exact").astype(np.float64) for image in (left, right)]
    lb, rb = (b - b.mean() for b in smooth)
    height, width = lb.shape
    scores = np.full((d_max - d_min + 1, height, width), -np.inf)
    box = np.ones((patch, patch))
    for k, d in enumerate(range(d_min, d_max + 1)):
        shifted = np.zeros_like(rb)
        lo, hi = max(d, 0), min(width, width + d)
        shifted[:, lo:hi] = rb[:, lo - d:hi - d]
        n = patch * patch
        sums = [ndimage.convolve(a, box, mode="constant") for a in (lb, shifted, lb * lb, shifted * shifted,
                                                                   lb * shifted)]
        var_l, var_r = sums[2] - sums[0] ** 2 / n, sums[3] - sums[1] ** 2 / n
        with np.errstate(invalid="ignore", divide="ignore"):
            ncc = (sums[4] - sums[0] * sums[1] / n) / np.sqrt(var_l * var_r)
        ys, xs = np.mgrid[:height, :width]
        inside = (ys >= r) & (ys + r < height) & (xs - r >= 0) & (xs + r < width) & (xs - d - r >= 0) & (
            xs - d + r < width)
        scores[k] = np.where(inside & (var_l > 1e-9) & (var_r > 1e-9), np.clip(ncc, -1, 1), -np.inf)
    return scores


def _shifted_scores_oracle(left, right, d_min, d_max, patch, sigma):
    """Shiftable-window scores in float64: the centred scores' maximum over the windows holding the pixel."""
    scores = _intensity_scores_oracle(left, right, d_min, d_max, patch, sigma)
    return ndimage.maximum_filter(scores, size=(1, patch, patch), mode="constant", cval=-np.inf)


def _shifted_oracle(left, right, d_min, d_max, patch, sigma):
    """Winners of shiftable-window intensity matching in float64: the best d of the shiftable scores
    (ties: the smaller), and its score."""
    widened = _shifted_scores_oracle(left, right, d_min, d_max, patch, sigma)
    return d_min + widened.argmax(axis=0), widened.max(axis=0)


@pytest.mark.parametrize("variant", ["table", "running"])
def test_shiftable_windows_match_oracle(variant, machine):
    rng = np.random.default_rng(7)
    texture = ndimage.gaussian_filter(rng.random((48, 90)), 1.0).astype(np.float32)
    # A textured square at disparity 6 in front of a background at disparity 0.
    left, right = texture[:, 10:74].copy(), texture[:, 10:74].copy()
    left[12:36, 20:44] = texture[12:36, 4:28]
    right[12:36, 14:38] = texture[12:36, 4:28]
    found = match(left, right, d_min=-2, d_max=9, patch=7, sigma=0.7, features="intensity", shiftable=True,
                  subpixel=False, method=variant, machine=machine)
    best_d, best_score = _shifted_oracle(left, right, -2, 9, 7, 0.7)
    kept = np.isfinite(found.disparity)
    assert kept.mean() > 0.85  # shifted windows reach the border; suppression drops few
    assert np.mean(found.disparity[kept] == best_d[kept]) > 0.995  # float32 against float64: near-ties
    scored = np.isfinite(found.score)
    np.testing.assert_allclose(found.score[scored], best_score[scored], atol=2e-4)


def test_shiftable_variants_agree(machine):
    scene, d_min, d_max = _pair("blocks")
    found = [match(scene.left, scene.right, d_min=d_min, d_max=d_max, features="intensity", shiftable=True,
                   method=variant, machine=machine) for variant in ("table", "running")]
    for name in ("disparity", "score", "discontinuity"):
        np.testing.assert_array_equal(getattr(found[0], name), getattr(found[1], name))


def test_shiftable_windows_keep_the_nearer_surface_off_the_farther(machine):
    """Near a depth edge a centred patch straddles both surfaces and the nearer one wins half a patch
    beyond its outline; a shifted patch lies on the pixel's own side."""
    scene = two_planes()
    near = ndimage.binary_dilation(scene.labels == Label.DEPTH, iterations=5) & ~scene.occluded_stereo
    accuracy = []
    for shiftable in (False, True):
        found = match(scene.left, scene.right, d_min=2, d_max=16, features="intensity", patch=11, sigma=1.0,
                      shiftable=shiftable, machine=machine)
        matched = np.isfinite(found.disparity) & near
        accuracy.append(np.mean(np.abs(found.disparity - scene.disparity)[matched] <= 1))
    assert accuracy[1] >= 0.9 and accuracy[1] > accuracy[0] + 0.1


def slanted_plane(size=96, angle=0.5):
    """A textured plane turned 0.5 rad about the vertical, 4 m away at the image centre: its disparity
    falls linearly along x (1/Z of a plane is linear in the image), from 9.1 to 5.3 px."""
    turned = (math.cos(angle), 0.0, math.sin(angle))
    plane = Face((0.0, 0.0, 4.0), turned, (0, 1, 0), None, (0.55, 0.55, 0.5), Texture("noise", 16 / size, 0.4))
    world = World(Camera((size, size), float(size), 0.3), Light(), (Body((plane,)),))
    return scenes.render(world, seed=2, noise=0.01)


@pytest.mark.parametrize("shiftable", [False, True])
def test_subpixel_disparity_follows_a_slanted_plane(shiftable, machine):
    """Whole-pixel winners on a plane whose disparity varies continuously are off by a quarter pixel on
    average; the parabola through the neighbouring scores brings them within a tenth. The winners stay
    the same (the refinement moves each by at most half a pixel), and both variants agree."""
    scene = slanted_plane()
    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    errors, found = {}, {}
    for subpixel in (False, True):
        for method in ("table", "running"):
            found[subpixel, method] = match(scene.left, scene.right, d_min=3, d_max=11, features="intensity",
                                            shiftable=shiftable, subpixel=subpixel, method=method,
                                            machine=machine)
        np.testing.assert_array_equal(found[subpixel, "table"].disparity, found[subpixel, "running"].disparity)
        disparity = found[subpixel, "table"].disparity
        matched = np.isfinite(disparity) & visible
        assert matched.sum() > 0.6 * visible.sum()
        errors[subpixel] = np.mean(np.abs(disparity - scene.disparity)[matched])
    # Measured: 0.269 and 0.073 (centred windows), 0.289 and 0.099 (shiftable).
    assert 0.2 < errors[False] < 0.32
    assert errors[True] < 0.15
    whole, refined = found[False, "table"].disparity, found[True, "table"].disparity
    np.testing.assert_array_equal(np.isfinite(whole), np.isfinite(refined))
    kept = np.isfinite(whole)
    assert np.abs(refined - whole)[kept].max() <= 0.5
    assert np.mean(refined[kept] != whole[kept]) > 0.9


@pytest.mark.parametrize("shiftable", [False, True])
def test_subpixel_offset_matches_oracle(shiftable, machine):
    """The refined disparity is d + (s- - s+) / (2 (s- - 2 s + s+)) with NumPy's float64 scores at the
    winner d and its neighbours; winners at the range's ends, or with a neighbour that did not compete,
    keep d."""
    rng = np.random.default_rng(11)
    texture = ndimage.gaussian_filter(rng.random((40, 80)), 1.5).astype(np.float32)
    # left(x) = right(x - 3.7): the right view is the texture 4 px on, moved back by 0.3 px.
    left = texture[:, :64]
    right = ndimage.shift(texture[:, 4:68], (0, 0.3), order=3, mode="nearest").astype(np.float32)
    d_min, d_max, patch, sigma = 2, 9, 7, 0.7
    whole = match(left, right, d_min=d_min, d_max=d_max, patch=patch, sigma=sigma, features="intensity",
                  shiftable=shiftable, subpixel=False, machine=machine).disparity
    refined = match(left, right, d_min=d_min, d_max=d_max, patch=patch, sigma=sigma, features="intensity",
                    shiftable=shiftable, machine=machine).disparity
    oracle = _shifted_scores_oracle if shiftable else _intensity_scores_oracle
    scores = oracle(left, right, d_min, d_max, patch, sigma)
    ys, xs = np.nonzero(np.isfinite(whole))
    k = whole[ys, xs].astype(np.int64) - d_min
    at_end = (k == 0) | (k == d_max - d_min)
    below = scores[np.clip(k - 1, 0, None), ys, xs]
    centre = scores[k, ys, xs]
    above = scores[np.clip(k + 1, None, d_max - d_min), ys, xs]
    missing = at_end | ~np.isfinite(below) | ~np.isfinite(above)
    np.testing.assert_array_equal(refined[ys[missing], xs[missing]], whole[ys[missing], xs[missing]])
    curvature = below - 2 * centre + above
    # Where the peak is flat the float32 scores' rounding (1e-4) moves the vertex by more than 1e-3.
    sharp = ~missing & (curvature < -0.02)
    assert sharp.sum() > 500
    offset = np.clip((below - above)[sharp] / (2 * curvature[sharp]), -0.5, 0.5)
    np.testing.assert_allclose(refined[ys[sharp], xs[sharp]], whole[ys[sharp], xs[sharp]] + offset, atol=1e-3)


def test_subpixel_is_ignored_for_edges(machine):
    scene, d_min, d_max = _pair("blocks")
    found = [match(scene.left, scene.right, d_min=d_min, d_max=d_max, subpixel=subpixel, machine=machine)
             for subpixel in (False, True)]
    np.testing.assert_array_equal(found[0].disparity, found[1].disparity)
    kept = np.isfinite(found[1].disparity)
    assert np.array_equal(found[1].disparity[kept], np.rint(found[1].disparity[kept]))


def test_negative_evidence_is_measured_against_the_plain_score(machine):
    scene, d_min, d_max = _pair("blocks")
    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    plain = match(scene.left, scene.right, d_min=d_min, d_max=d_max, machine=machine)
    negative = match(scene.left, scene.right, d_min=d_min, d_max=d_max, negative_evidence=1.0, machine=machine)
    assert not np.array_equal(plain.score, negative.score, equal_nan=True)
    for found in (plain, negative):
        matched = np.isfinite(found.disparity) & visible
        assert np.mean(np.abs(found.disparity - scene.disparity)[matched] <= 1) >= 0.90


@pytest.mark.parametrize("kwargs, error, pattern", [
    ({"right": np.zeros((32, 30), np.float32)}, ValueError, "same shape"),
    ({"d_min": 5, "d_max": 2}, ValueError, "must not exceed"),
    ({"d_min": 0, "d_max": 40}, ValueError, "wider than the image"),
    ({"right": np.zeros((32, 32, 3), np.float32)}, ValueError, "same shape"),
    ({"patch": 4}, ValueError, "odd integer"),
    ({"features": "sift"}, ValueError, "features must be one of"),
    ({"method": "fast"}, ValueError, "method must be"),
    ({"d_min": 1.5}, TypeError, "d_min must be an integer"),
    ({"patch": 183, "method": "running"}, ValueError, "16 bits"),
    ({"direction_tolerance": -0.1}, ValueError, "direction_tolerance"),
    ({"horizontal_tolerance": 90.0}, ValueError, "horizontal_tolerance"),
    ({"horizontal_tolerance": float("nan")}, ValueError, "horizontal_tolerance"),
    ({"left": np.zeros((0, 32), np.float32), "right": np.zeros((0, 32), np.float32)}, ValueError, "empty"),
    ({"left": np.full((32, 32), np.nan, np.float32)}, ValueError, "left has NaN"),
    ({"right": np.full((32, 32), np.inf, np.float32), "features": "intensity"}, ValueError, "right has NaN"),
    ({"shiftable": True}, ValueError, "features must be 'intensity'"),
    ({"shiftable": True, "features": "intensity", "barriers": np.zeros((32, 32), bool)}, ValueError, "no barriers"),
    ({"shiftable": 1, "features": "intensity"}, TypeError, "shiftable must be a bool"),
    ({"subpixel": 1, "features": "intensity"}, TypeError, "subpixel must be a bool"),
    ({"subpixel": None}, TypeError, "subpixel must be a bool"),
])
def test_bad_input_is_named(kwargs, error, pattern, machine):
    arguments = {"left": np.zeros((32, 32), np.float32), "right": np.zeros((32, 32), np.float32),
                 "d_min": 0, "d_max": 8}
    arguments.update(kwargs)
    with pytest.raises(error, match=pattern):
        match(arguments.pop("left"), arguments.pop("right"), machine=machine, **arguments)


def test_grey_and_colour_mix_is_refused(machine):
    with pytest.raises(ValueError, match="both be grey or both be colour|same shape"):
        match(np.zeros((32, 32), np.float32), np.zeros((32, 32, 3), np.float32), d_min=0, d_max=4, machine=machine)


@pytest.mark.parametrize("name", ["tsukuba", "venus", "teddy"])
def test_edge_matches_beat_stereobm_on_middlebury(name, datasets_root, machine):
    import cv2

    from vmcl.datasets import load_stereo

    pair = load_stereo(name, datasets_root)
    d_max = int(np.ceil(pair.disparity_range[1])) + 2
    found = match(pair.left, pair.right, d_min=0, d_max=d_max, machine=machine)
    grey = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in (pair.left, pair.right)]
    block = cv2.StereoBM_create(numDisparities=-(-(d_max + 1) // 16) * 16, blockSize=15).compute(*grey) / 16.0
    block[block < 0] = np.nan
    at = np.isfinite(found.disparity) & pair.masks["nonocc"]
    ours = np.mean(np.abs(found.disparity - pair.disparity)[at] > 1)
    theirs = np.mean(~(np.abs(block - pair.disparity)[at] <= 1))
    assert at.sum() > 1000 and ours <= theirs


@pytest.mark.parametrize("name", ["min_score", "bimodal", "dip", "min_votes"])
@pytest.mark.parametrize("value, error", [(None, TypeError), (float("nan"), ValueError), ("0.3", TypeError),
                                          ([0.3], TypeError), (True, TypeError), (float("inf"), ValueError)])
def test_selection_parameters_are_checked_by_type_and_range(name, value, error, machine):
    """These used to be taken as they came: None became NaN in the kernel, "0.3" and [0.3] were converted."""
    image = np.zeros((32, 32), np.float32)
    with pytest.raises(error, match=name):
        match(image, image, d_min=0, d_max=4, machine=machine, **{name: value})


@pytest.mark.parametrize("kwargs, error, pattern", [
    ({"bimodal": 1.5}, ValueError, "bimodal must be a finite number >= 0 and <= 1"),
    ({"dip": -0.1}, ValueError, "dip must be a finite number >= 0 and <= 1"),
    ({"min_votes": -1.0}, ValueError, "min_votes must be a finite number >= 0"),
    ({"use_quantiles": "no"}, TypeError, "use_quantiles must be a bool"),
    ({"features": ["canny"]}, TypeError, "features must be one of"),
    ({"direction_tolerance": float("inf")}, ValueError, "direction_tolerance"),
    ({"horizontal_tolerance": None}, TypeError, "horizontal_tolerance"),
    ({"patch": 33}, ValueError, "patch must be at most the image's smaller side, 32"),
    ({"left": np.ones(32, np.float32), "right": np.ones(32, np.float32)}, ValueError, "left must be grey"),
])
def test_more_bad_input_is_named(kwargs, error, pattern, machine):
    from vmcl.errors import InputError

    arguments = {"left": np.zeros((32, 32), np.float32), "right": np.zeros((32, 32), np.float32),
                 "d_min": 0, "d_max": 8} | kwargs
    with pytest.raises(error, match=pattern) as raised:
        match(arguments.pop("left"), arguments.pop("right"), machine=machine, **arguments)
    assert isinstance(raised.value, InputError)


def test_match_features_refuses_a_host_and_a_device_mask(machine):
    mask, direction = np.zeros((32, 32), np.uint8), np.zeros((32, 32), np.float32)
    with pytest.raises(TypeError, match="both be NumPy arrays or both device arrays"):
        match_features(mask, machine.to_device(mask), direction, direction, d_min=0, d_max=4, machine=machine)


def test_a_table_beyond_the_device_memory_is_refused_before_any_work(machine):
    """8192 x 8192 pixels over 8192 disparities: the check comes before the features are computed (it used
    to fail in pyopencl's create_buffer after them). The images are never read."""
    side = 8192
    left, right = (machine.empty((side, side), np.float32) for _ in range(2))
    with pytest.raises(ValueError, match="device memory"):
        match(left, right, d_min=0, d_max=side - 1, features="intensity", method="table", machine=machine)


@pytest.mark.parametrize("angle, error", [(float("nan"), ValueError), (float("inf"), ValueError),
                                          (None, TypeError), ("1", TypeError)])
def test_direction_code_refuses_what_is_not_an_angle(angle, error):
    from vmcl.early.stereo import direction_code

    with pytest.raises(error, match="angle"):
        direction_code(angle)


@pytest.mark.parametrize("width", [61, 64])
def test_the_intensity_table_in_sixteen_lanes_is_the_scalar_selection_bit_for_bit(monkeypatch, machine, width):
    # On a CPU the table's selection runs sixteen pixels per work-item, the row's tail (61 = 3 * 16 + 13)
    # through the scalar kernel; with the lanes off, the scalar kernel takes every pixel. Every field
    # (winner, score, sub-pixel offset from the neighbours, range and bimodality flags) must agree.
    from vmcl.early import stereo as stereo_module

    if machine.vector_width == 1:
        pytest.skip("the lanes run on CPU devices only")
    rng = np.random.default_rng(7)
    left = ndimage.gaussian_filter(rng.random((40, width)), 1.0).astype(np.float32)
    right = np.roll(left, -5, axis=1) + 0.01 * rng.standard_normal(left.shape).astype(np.float32)
    found = {}
    for lanes in (True, False):
        monkeypatch.setattr(stereo_module, "_LANES_ON_CPU", lanes)
        found[lanes] = match(left, right, d_min=-3, d_max=12, features="intensity", method="table",
                             subpixel=True, machine=machine)
    for name in ("disparity", "score", "features", "out_of_range", "discontinuity"):
        np.testing.assert_array_equal(getattr(found[True], name), getattr(found[False], name), err_msg=name)
    assert np.isfinite(found[True].disparity).mean() > 0.5
