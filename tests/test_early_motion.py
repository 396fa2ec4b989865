"""Motion: votes and winners against NumPy oracles, translations, scenes with ground truth, the arcsine
law, and real sequences where ../shared/datasets is present."""

import cv2
import numpy as np
import pyopencl.array as cl_array
import pytest
from oracles import box_sum as box_oracle
from scipy import ndimage

from vmcl import scenes
from vmcl.datasets import FLOW_SCENES, load_flow
from vmcl.early import edges, filters, motion
from vmcl.early.sign_correlation import arcsine_law, sign_correlation
from vmcl.metrics import endpoint_error, evaluate_flow


def texture(shape, shift=(0.0, 0.0), seed=0, waves=40):
    """A smooth random texture, sums of sinusoids (wavelengths 5-16 px), sampled at (x - u, y - v): the
    frame that follows ``texture(shape)`` under the flow (u, v), exactly, for any sub-pixel shift."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0, np.pi, waves)
    k = 2 * np.pi / rng.uniform(5, 16, waves)
    phase = rng.uniform(0, 2 * np.pi, waves)
    y, x = np.mgrid[: shape[0], : shape[1]].astype(np.float64)
    x, y = x - shift[0], y - shift[1]
    arg = k[:, None, None] * (np.cos(angle)[:, None, None] * x + np.sin(angle)[:, None, None] * y) + phase[:, None, None]
    image = np.cos(arg).sum(axis=0)
    return (128 + 20 * image).astype(np.float32)


def oracle_features(frame, features):
    sigma = motion.DEFAULT_SIGMA[features]
    if features == "brightness":
        return filters.gaussian(frame, sigma=sigma, method="exact")
    if features == "edges":
        low, high = motion.EDGE_QUANTILES
        return edges.canny(frame, sigma=sigma, low_threshold=low, high_threshold=high, use_quantiles=True)
    return filters.laplacian_of_gaussian(frame, sigma=sigma)


def oracle_votes(f0, f1, delta, radius, features):
    """Every displacement's comparison (frame 1 clamped at the border), summed over the patch."""
    height, width = f0.shape
    ys, xs = np.mgrid[:height, :width]
    planes = []
    for vy in range(-delta, delta + 1):
        for vx in range(-delta, delta + 1):
            g = f1[np.clip(ys + vy, 0, height - 1), np.clip(xs + vx, 0, width - 1)]
            if features in ("brightness", "log"):
                cost = (f0.astype(np.float64) - g) ** 2
            elif features == "sign_log":
                cost = ((f0 >= 0) != (g >= 0)).astype(np.int64)
            else:
                cost = ((f0 != 0) != (g != 0)).astype(np.int64)
            planes.append(box_oracle(cost, radius))
    return np.stack(planes)


def oracle_winner(table, delta):
    """The smallest vote; ties to the smaller |v|^2, then to the first visited: rows of fixed vy in the
    order 0, -1, +1, -2, +2, ..., vx ascending (the rule for binary votes; textures' float votes do not
    tie)."""
    n = 2 * delta + 1
    d = np.arange(n * n)
    vy, vx = d // n - delta, d % n - delta
    visit = (2 * np.abs(vy) - (vy < 0)) * n + vx
    order = np.lexsort((visit, vx**2 + vy**2))
    return order[np.argmin(table[order], axis=0)]


def winner_index(flow, delta):
    """Displacement index of an integer flow (0 where there is none)."""
    n = 2 * delta + 1
    flow = np.nan_to_num(flow)
    return (np.rint(flow[..., 1]).astype(int) + delta) * n + np.rint(flow[..., 0]).astype(int) + delta


def interior(shape, border):
    mask = np.zeros(shape, bool)
    mask[border:-border, border:-border] = True
    return mask


@pytest.fixture(scope="module")
def pair():
    return texture((40, 52)), texture((40, 52), shift=(1.6, -0.7))


@pytest.mark.parametrize("features", motion.FEATURES)
def test_votes_match_oracle(pair, features):
    frame0, frame1 = pair
    table = motion.votes(frame0, frame1, delta=2, patch=5, features=features)
    expected = oracle_votes(oracle_features(frame0, features), oracle_features(frame1, features), 2, 2, features)
    assert table.shape == (25, 40, 52)
    if table.dtype == np.int32:
        np.testing.assert_array_equal(table, expected)
    else:
        np.testing.assert_allclose(table, expected, rtol=1e-4, atol=1e-2)


@pytest.mark.parametrize("features", ["brightness", "sign_log", "edges"])
def test_winner_and_subpixel_match_oracle(pair, features):
    frame0, frame1 = pair
    table = motion.votes(frame0, frame1, delta=2, patch=5, features=features)
    result = motion.flow(frame0, frame1, delta=2, patch=5, features=features, speed_penalty=0.0)
    integer = motion.flow(frame0, frame1, delta=2, patch=5, features=features, speed_penalty=0.0, subpixel=False)
    known = np.isfinite(result.flow[..., 0])
    assert known.sum() > (50 if features == "edges" else 0.9 * known.size)
    winner = oracle_winner(table, 2)
    np.testing.assert_array_equal(winner_index(integer.flow, 2)[known], winner[known])
    # The parabola through the winner and its neighbours along x (u) and y (v); none at the range's edge.
    votes = table.astype(np.float64)

    def vote_at(d, valid):
        return np.where(valid, np.take_along_axis(votes, np.clip(d, 0, 24)[None], axis=0)[0], np.inf)

    best = vote_at(winner, True)
    for axis, step, position in ((0, 1, winner % 5), (1, 5, winner // 5)):
        lo, hi = vote_at(winner - step, position > 0), vote_at(winner + step, position < 4)
        curvature = lo - 2 * best + hi
        with np.errstate(invalid="ignore"):
            offset = np.where(np.isfinite(curvature) & (curvature > 0),
                              np.clip(0.5 * (lo - hi) / curvature, -0.5, 0.5), 0.0)
        np.testing.assert_allclose(result.flow[..., axis][known] - integer.flow[..., axis][known], offset[known],
                                   atol=2e-3)


def test_penalised_winner_is_the_penalised_minimum(pair):
    frame0, frame1 = pair
    penalty = 0.02
    table = motion.votes(frame0, frame1, delta=3, patch=7).astype(np.float64)
    f0 = oracle_features(frame0, "brightness").astype(np.float64)
    count = box_oracle(np.ones_like(f0), 3)
    contrast = box_oracle(f0 * f0, 3) - box_oracle(f0, 3) ** 2 / count
    d = np.arange(49)
    norm = ((d % 7 - 3) ** 2 + (d // 7 - 3) ** 2)[:, None, None]
    key = table + penalty * contrast * norm
    result = motion.flow(frame0, frame1, delta=3, patch=7, speed_penalty=penalty, subpixel=False)
    chosen = np.take_along_axis(key, winner_index(result.flow, 3)[None], axis=0)[0]
    assert np.all(chosen <= key.min(axis=0) + 1e-4 * contrast)
    assert np.any(winner_index(result.flow, 3) != oracle_winner(table, 3))  # the prior does act


def test_scores_match_their_definitions(pair):
    frame0, frame1 = pair
    signs = motion.flow(frame0, frame1, delta=2, patch=5, features="sign_log", subpixel=False)
    table = motion.votes(frame0, frame1, delta=2, patch=5, features="sign_log")
    vote = np.take_along_axis(table, winner_index(signs.flow, 2)[None], axis=0)[0]
    count = box_oracle(np.ones(frame0.shape), 2)
    np.testing.assert_allclose(signs.score, 1 - 2 * vote / count, atol=1e-6)

    bright = motion.flow(frame0, frame1, delta=2, patch=5, subpixel=False, speed_penalty=0.0)
    f0, f1 = (oracle_features(f, "brightness").astype(np.float64) for f in (frame0, frame1))
    contrast0 = box_oracle(f0 * f0, 2) - box_oracle(f0, 2) ** 2 / count
    contrast1 = box_oracle(f1 * f1, 2) - box_oracle(f1, 2) ** 2 / count
    u, v = (np.rint(bright.flow[..., k]).astype(int) for k in (0, 1))
    ys, xs = np.mgrid[: f0.shape[0], : f0.shape[1]]
    ys1, xs1 = np.clip(ys + v, 0, f0.shape[0] - 1), np.clip(xs + u, 0, f0.shape[1] - 1)
    vote = np.take_along_axis(motion.votes(frame0, frame1, delta=2, patch=5), winner_index(bright.flow, 2)[None], 0)[0]
    expected = 1 - vote / (contrast0 + contrast1[ys1, xs1])
    np.testing.assert_allclose(bright.score, expected, atol=2e-3)
    assert np.nanmin(bright.score) < 0.99 < np.nanmax(bright.score) <= 1.0


@pytest.mark.parametrize("method", motion.METHODS)
def test_same_bits_at_any_local_size(pair, machine, machine_with_local_size, method):
    frame0, frame1 = pair
    kwargs = {"delta": 3, "patch": 5, "method": method, "levels": 2}
    reference = motion.flow(frame0, frame1, machine=machine, **kwargs)
    for result in (motion.flow(frame0, frame1, machine=machine_with_local_size, **kwargs),
                   motion.flow(frame0, frame1, machine=machine, **kwargs)):
        for got, want in zip((result.flow, result.score, result.boundaries),
                             (reference.flow, reference.score, reference.boundaries)):
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("features", motion.FEATURES)
def test_running_maximum_equals_full_table(features):
    frame0 = np.asarray(scenes.render(scenes.preset("textures", shape=(64, 64)), seed=2).left)
    frame1 = np.roll(frame0, (1, -2), axis=(0, 1))
    running = motion.flow(frame0, frame1, delta=3, patch=7, features=features, method="running")
    table = motion.flow(frame0, frame1, delta=3, patch=7, features=features, method="table")
    np.testing.assert_array_equal(running.flow, table.flow)
    np.testing.assert_array_equal(running.score, table.score)


@pytest.mark.parametrize("shift", [(3, -2), (-4, 1), (0, 4)])
def test_integer_translation(shift):
    frame0, frame1 = texture((64, 80)), texture((64, 80), shift=shift)
    result = motion.flow(frame0, frame1, delta=4, patch=7)
    truth = np.broadcast_to(np.array(shift, np.float32), frame0.shape + (2,))
    error = endpoint_error(result.flow, truth)[interior(frame0.shape, 8)]
    assert np.isfinite(error).all()
    assert error.mean() < 0.1


@pytest.mark.parametrize("shift", [(1.3, -0.6), (-2.5, 0.25), (0.4, 3.3)])
def test_subpixel_translation(shift):
    frame0, frame1 = texture((64, 80), seed=1), texture((64, 80), shift=shift, seed=1)
    result = motion.flow(frame0, frame1, delta=4, patch=9)
    truth = np.broadcast_to(np.array(shift, np.float32), frame0.shape + (2,))
    error = endpoint_error(result.flow, truth)[interior(frame0.shape, 9)]
    assert error.mean() < 0.25


def test_limit_share_is_a_share_of_pixels():
    """A motion of (8, 8) searched over delta 4 (the default) puts both components of most estimates at the
    limit: each such pixel counts once (counting components gave 1.87), so the share stays in [0, 1]."""
    smooth = ndimage.gaussian_filter(np.random.default_rng(1).random((140, 180)), 3)
    image = ((smooth - smooth.min()) / np.ptp(smooth) * 255).astype(np.uint8)
    frame0, frame1 = image[10:-10, 10:-10], np.roll(image, (8, 8), (0, 1))[10:-10, 10:-10]
    result = motion.flow(frame0, frame1)
    at_limit = np.abs(result.flow) >= 4 - 1e-3
    assert at_limit.all(axis=-1).mean() > 0.5  # both components, at most pixels
    assert 0.5 < result.limit_share <= 1
    assert result.limit_share == pytest.approx(at_limit.any(axis=-1).mean())


def test_the_speed_penalty_is_bounded_where_float32_holds_it(machine):
    """The device computes speed_penalty * C0 in float32: at 1e34 it overflowed on uint8 frames, every
    displacement's key was infinite or NaN, and every pixel got the flow (-5, -4), outside the range, with
    a NaN score. Above 1 is refused by name; at 1 the flow stays in range, and a NaN score has no flow."""
    frame0 = (np.random.default_rng(0).random((60, 80)) * 255).astype(np.uint8)
    frame1 = np.roll(frame0, 2, 1)
    with pytest.raises(ValueError, match="speed_penalty must be a finite number >= 0 and <= 1"):
        motion.flow(frame0, frame1, speed_penalty=1e34, machine=machine)
    result = motion.flow(frame0, frame1, speed_penalty=1.0, machine=machine)
    known = np.isfinite(result.score)
    assert known.mean() > 0.9
    np.testing.assert_array_equal(np.isfinite(result.flow).all(axis=-1), known)
    assert np.abs(result.flow[known]).max() <= motion.DELTA


def test_pyramid_finds_motion_beyond_delta():
    shift = (9.4, -6.7)
    frame0, frame1 = texture((112, 160), seed=3), texture((112, 160), shift=shift, seed=3)
    truth = np.broadcast_to(np.array(shift, np.float32), frame0.shape + (2,))
    # The coarsest level's patch spans 36 pixels, and its errors where the match leaves the frame (10 px
    # from the border) spread that far inwards.
    inside = interior(frame0.shape, 40)
    flat = endpoint_error(motion.flow(frame0, frame1, delta=3, patch=9).flow, truth)[inside]
    pyramid = endpoint_error(motion.flow(frame0, frame1, delta=3, patch=9, levels=3).flow, truth)[inside]
    assert flat.mean() > 3
    assert pyramid.mean() < 0.25


def _fast_square(shape=(96, 128), speed=9, corner=(40, 30), side=20):
    """A static textured background and a square of another texture moving ``speed`` px to the right:
    frames 0 and 1, and the true flow."""
    background = texture(shape, seed=5)
    frames = []
    for shift in (0, speed):
        frame, moved = background.copy(), texture(shape, shift=(shift, 0.0), seed=6)
        (y, x) = corner
        frame[y:y + side, x + shift:x + shift + side] = moved[y:y + side, x + shift:x + shift + side]
        frames.append(frame)
    truth = np.zeros(shape + (2,), np.float32)
    truth[corner[0]:corner[0] + side, corner[1]:corner[1] + side, 0] = speed
    return frames[0], frames[1], truth


def test_a_prediction_finds_a_motion_the_search_cannot_reach():
    """The previous flow, carried along (here the truth, 0.4 px off on the square), points the search at a
    fast square beyond delta; the background, predicted at rest, keeps the estimate of the search
    without a prediction (the same search, through the warp: equal to float rounding)."""
    frame0, frame1, truth = _fast_square()
    prediction = truth.copy()
    prediction[truth[..., 0] > 0, 0] -= 0.4
    alone = motion.flow(frame0, frame1, delta=3, patch=7)
    predicted = motion.flow(frame0, frame1, delta=3, patch=7, prediction=prediction)
    core = np.zeros(truth.shape[:2], bool)
    core[44:56, 34:46] = True  # the square's pixels whose patch lies inside it
    assert endpoint_error(alone.flow, truth)[core].mean() > 3
    assert endpoint_error(predicted.flow, truth)[core].mean() < 0.25
    far = interior(truth.shape[:2], 8) & ~ndimage.binary_dilation(truth[..., 0] > 0, iterations=12)
    np.testing.assert_allclose(predicted.flow[far], alone.flow[far], atol=1e-4)


def test_a_prediction_that_holds_nowhere_changes_nothing(pair, machine):
    nowhere = np.full(pair[0].shape + (2,), np.nan, np.float32)
    alone = motion.flow(*pair, delta=3, patch=5, machine=machine)
    predicted = motion.flow(*pair, delta=3, patch=5, prediction=nowhere, machine=machine)
    for a, b in ((alone.flow, predicted.flow), (alone.score, predicted.score), (alone.boundaries, predicted.boundaries)):
        np.testing.assert_array_equal(a, b)


def test_a_prediction_of_another_size_is_refused(pair, machine):
    with pytest.raises(ValueError, match="prediction must have 3 dimensions"):
        motion.flow(*pair, delta=2, patch=5, prediction=np.zeros((40, 52), np.float32), machine=machine)
    with pytest.raises(ValueError, match=r"prediction must be a flow of the frames' size, \(40, 52, 2\)"):
        motion.flow(*pair, delta=2, patch=5, prediction=np.zeros((40, 51, 2), np.float32), machine=machine)


@pytest.fixture(scope="module")
def blocks():
    return scenes.render(scenes.preset("blocks", shape=(128, 192)), seed=1)


def test_scene_flow_and_motion_boundaries(blocks):
    scene = blocks
    result = motion.flow(scene.left, scene.left_next, delta=4, patch=11)
    truth = scene.flow
    evaluated = ~scene.occluded_motion & np.isfinite(truth).all(axis=-1) & interior(truth.shape[:2], 6)
    scores = evaluate_flow(result.flow, truth, mask=evaluated)
    assert scores.density > 0.99
    assert scores.epe < 0.5
    # True motion boundaries: 4-neighbours whose flows differ by more than a pixel (or one has none).
    filled = np.nan_to_num(truth, nan=1e3)
    jump_x = np.hypot(*(filled[:, 1:] - filled[:, :-1]).transpose(2, 0, 1)) > 1
    jump_y = np.hypot(*(filled[1:] - filled[:-1]).transpose(2, 0, 1)) > 1
    boundary = np.zeros(truth.shape[:2], bool)
    boundary[:, 1:] |= jump_x
    boundary[:, :-1] |= jump_x
    boundary[1:] |= jump_y
    boundary[:-1] |= jump_y
    boundary &= interior(boundary.shape, 6)
    near_mask = ndimage.binary_dilation(result.boundaries, np.ones((5, 5), bool))
    recall = (near_mask & boundary).sum() / boundary.sum()
    assert recall >= 0.6
    assert result.boundaries.mean() < 0.25  # evidence, not everything


@pytest.fixture(scope="module")
def textures():
    scene = scenes.render(scenes.preset("textures", shape=(128, 128)), seed=3)
    return scene, motion.flow(scene.left, scene.left_next, delta=3, patch=11)


@pytest.mark.parametrize(("features", "density"), [("sign_log", 0.8), ("log", 0.8), ("edges", 0.05)])
def test_feature_variants_agree(textures, features, density):
    """The seed's observation: edge- and intensity-based variants give similar flow (edges: sparse)."""
    scene, bright = textures
    other = motion.flow(scene.left, scene.left_next, delta=3, patch=11, features=features)
    inside = interior((128, 128), 8)
    both = inside & np.isfinite(bright.flow[..., 0]) & np.isfinite(other.flow[..., 0])
    assert both.sum() > density * inside.sum()
    close = endpoint_error(bright.flow, other.flow)[both] <= 0.5
    assert close.mean() >= 0.9


@pytest.mark.parametrize("correlation", [-0.9, -0.5, 0.0, 0.3, 0.7, 0.95])
def test_sign_correlation_follows_arcsine_law(correlation):
    rng = np.random.default_rng(7)
    f, h = (ndimage.gaussian_filter(rng.standard_normal((512, 512)), 1.0) for _ in range(2))
    f, h = f / f.std(), h / h.std()
    g = correlation * f + np.sqrt(1 - correlation**2) * h
    measured = sign_correlation(f.astype(np.float32), g.astype(np.float32))
    assert abs(measured - arcsine_law(correlation)) < 0.02


def test_sign_correlation_of_known_signs(machine):
    f = np.array([1.0, -2.0, 0.0, 3.0], np.float32)
    g = np.array([2.0, 1.0, 0.5, -1.0], np.float32)
    assert sign_correlation(f, g) == 0.0  # agree, disagree, agree (0 counts as +), disagree
    assert sign_correlation(machine.to_device(f), machine.to_device(f)) == 1.0


def test_dtypes_and_device_arrays(pair, machine):
    frame0, frame1 = (np.clip(f, 0, 255).astype(np.uint8) for f in pair)
    reference = motion.flow(frame0, frame1, delta=2, patch=5)
    as_float = motion.flow(frame0.astype(np.float64), frame1.astype(np.float32), delta=2, patch=5)
    rgb = motion.flow(np.repeat(frame0[..., None], 3, -1), np.repeat(frame1[..., None], 3, -1), delta=2, patch=5)
    on_device = motion.flow(machine.to_device(frame0), machine.to_device(frame1), delta=2, patch=5)
    assert isinstance(on_device.flow, cl_array.Array) and on_device.boundaries.dtype == np.uint8
    np.testing.assert_array_equal(as_float.flow, reference.flow)
    np.testing.assert_array_equal(on_device.flow.get(), reference.flow)
    np.testing.assert_allclose(rgb.flow, reference.flow, atol=0.02)
    assert reference.flow.shape == frame0.shape + (2,) and reference.boundaries.dtype == np.bool_


def test_bad_input(pair, machine):
    frame0, frame1 = pair
    with pytest.raises(ValueError, match="same shape"):
        motion.flow(frame0, frame1[:, :-1], delta=2, patch=5)
    with pytest.raises(ValueError, match="delta"):
        motion.flow(frame0, frame1, delta=0, patch=5)
    with pytest.raises(ValueError, match="delta"):
        motion.flow(frame0, frame1, delta=40, patch=5)
    with pytest.raises(ValueError, match="patch"):
        motion.flow(frame0, frame1, delta=2, patch=0)
    with pytest.raises(ValueError, match="patch"):
        motion.flow(frame0, frame1, delta=2, patch=4)
    with pytest.raises(ValueError, match="patch"):
        motion.flow(frame0, frame1, delta=2, patch=41)
    with pytest.raises(ValueError, match="levels"):
        motion.flow(frame0, frame1, delta=2, patch=5, levels=5)
    with pytest.raises(TypeError, match="delta"):
        motion.flow(frame0, frame1, delta=2.0, patch=5)
    bad = frame0.copy()
    bad[3, 3] = np.nan
    with pytest.raises(ValueError, match="frame1"):
        motion.flow(frame0, bad, delta=2, patch=5)
    with pytest.raises(TypeError, match="frame0"):
        motion.flow(frame0.tolist(), frame1, delta=2, patch=5)
    with pytest.raises(TypeError, match="both"):
        motion.flow(frame0, machine.to_device(frame1), delta=2, patch=5)
    with pytest.raises(ValueError, match="features"):
        motion.flow(frame0, frame1, delta=2, patch=5, features="colour")
    with pytest.raises(ValueError, match="method"):
        motion.flow(frame0, frame1, delta=2, patch=5, method="fast")
    with pytest.raises(ValueError, match="speed_penalty"):
        motion.flow(frame0, frame1, delta=2, patch=5, speed_penalty=-1.0)
    with pytest.raises(ValueError, match="frame0"):
        motion.flow(frame0[..., None].repeat(2, -1), frame1[..., None].repeat(2, -1), delta=2, patch=5)
    with pytest.raises(ValueError, match="same shape"):
        sign_correlation(frame0, frame1[:, :-1])
    with pytest.raises(ValueError, match="g must not contain NaN"):
        sign_correlation(frame0, bad)


BEST = {"delta": 4, "patch": 21, "levels": 2, "features": "sign_log"}
"""vmcl's best configuration on the real sequences (benchmarks/results/motion.md)."""


def test_real_sequences_beat_farneback(datasets_root):
    ours, farneback = [], []
    for name in FLOW_SCENES:
        pair = load_flow(name, datasets_root)
        ours.append(evaluate_flow(motion.flow(pair.frame0, pair.frame1, **BEST).flow, pair.flow, mask=pair.mask).epe)
        theirs = cv2.calcOpticalFlowFarneback(pair.frame0, pair.frame1, None, 0.5, 3, 15, 3, 5, 1.2, 0)
        farneback.append(evaluate_flow(theirs, pair.flow, mask=pair.mask).epe)
    assert np.mean(ours) < np.mean(farneback)


def test_levels_are_bounded_by_the_image(pair, machine):
    """levels=10**12 used to grow memory without end (2 ** (levels - 1)); the refusal names the maximum."""
    frame0, frame1 = pair
    height, width = frame0.shape
    most, side = 1, min(height, width)
    while -(-side // 2) >= 5:  # the coarsest level must hold the patch (5) and delta + 1 (3)
        most, side = most + 1, -(-side // 2)
    for levels in (most + 1, 10**12):
        with pytest.raises(ValueError, match=f"levels must be at most {most} "):
            motion.flow(frame0, frame1, delta=2, patch=5, levels=levels, machine=machine)
    assert motion.flow(frame0, frame1, delta=2, patch=5, levels=most, machine=machine).flow.shape == (height, width, 2)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"subpixel": "no"}, TypeError, "subpixel must be a bool"),
    ({"subpixel": None}, TypeError, "subpixel must be a bool"),
    ({"features": ["log"]}, TypeError, "features must be one of"),
    ({"method": ["table"]}, TypeError, "method must be one of"),
])
def test_flags_and_choices_are_checked_by_type(pair, kwargs, error, match, machine):
    frame0, frame1 = pair
    with pytest.raises(error, match=match):
        motion.flow(frame0, frame1, delta=2, patch=5, machine=machine, **kwargs)


def test_a_vote_table_beyond_the_device_memory_is_refused(machine):
    """(2 * 1000 + 1)**2 planes of 1024 x 1024 pixels: refused before anything is allocated (it used to fail
    in pyopencl's create_buffer)."""
    frame = np.zeros((1024, 1024), np.float32)
    with pytest.raises(ValueError, match="device memory"):
        motion.votes(frame, frame, delta=1000, patch=3, machine=machine)
    with pytest.raises(ValueError, match="device memory"):
        motion.flow(frame, frame, delta=1000, patch=3, method="table", machine=machine)


@pytest.mark.parametrize("value, error", [(2.0, ValueError), (float("nan"), ValueError), ("0.5", TypeError),
                                          (None, TypeError), (True, TypeError), (np.array([0.5, 1.5]), ValueError)])
def test_arcsine_law_takes_correlations_only(value, error):
    with pytest.raises(error, match="correlation"):
        arcsine_law(value)
