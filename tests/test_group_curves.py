"""vmcl.group.curves: edge pixels linked into curves, against a plain tracer, and each curve's measures."""

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import STEPS, trace_curves

from vmcl.cm.doubling import principal
from vmcl.early.edges import canny
from vmcl.errors import InputError
from vmcl.group import BRANCH, link_edges
from vmcl.scenes import render_occlusion


def _partition(found):
    labels = np.asarray(found.labels)
    curves = {frozenset((int(x), int(y)) for y, x in zip(*np.nonzero(labels == i))) for i in range(len(found))}
    return curves, {(int(x), int(y)) for x, y in found.branches}


def _check_order(found):
    """Each curve's points are one linked step apart, in arc order, and the maps agree with them."""
    labels, position = np.asarray(found.labels), np.asarray(found.position)
    for i, curve in enumerate(found):
        steps = np.abs(np.diff(curve.points, axis=0))
        assert np.all(steps.max(axis=1) == 1) if len(steps) else True
        if curve.closed:
            assert np.abs(curve.points[0] - curve.points[-1]).max() == 1
        xs, ys = curve.points[:, 0], curve.points[:, 1]
        assert np.all(labels[ys, xs] == i)
        np.testing.assert_array_equal(position[ys, xs], np.arange(len(curve.points)))


def _random_drawing(rng, shape, lines):
    drawing = np.zeros(shape, np.uint8)
    for _ in range(lines):
        x0, x1 = rng.integers(0, shape[1], 2)
        y0, y1 = rng.integers(0, shape[0], 2)
        cv2.line(drawing, (int(x0), int(y0)), (int(x1), int(y1)), 1, 1)
    for _ in range(lines // 3):
        cv2.circle(drawing, (int(rng.integers(0, shape[1])), int(rng.integers(0, shape[0]))),
                   int(rng.integers(2, max(3, min(shape) // 3))), 1, 1)
    return drawing.astype(bool)


@pytest.mark.parametrize("seed", range(4))
def test_partition_matches_a_plain_tracer_on_drawings(seed, machine):
    mask = _random_drawing(np.random.default_rng(seed), (97, 131), 14)
    found = link_edges(mask, machine=machine)
    assert _partition(found) == trace_curves(mask)
    _check_order(found)


@given(st.integers(1, 40), st.integers(1, 40), st.floats(0.05, 0.6), st.integers(0, 2**31 - 1))
@settings(max_examples=25, deadline=None)
def test_partition_matches_a_plain_tracer_on_random_masks(height, width, density, seed):
    mask = np.random.default_rng(seed).random((height, width)) < density
    found = link_edges(mask)
    assert _partition(found) == trace_curves(mask)
    _check_order(found)


def test_partition_on_canny_of_a_rendered_scene(machine):
    scene = render_occlusion((200, 240), polygons=7, seed=4, noise=0.02)
    edges = canny(scene.image, sigma=1.0, machine=machine)
    found = link_edges(edges, machine=machine)
    assert _partition(found) == trace_curves(edges)
    assert len(found) > 5
    _check_order(found)


def test_partition_on_canny_of_a_photograph(machine, datasets_root):
    from vmcl.datasets import load_bsds

    image = load_bsds(datasets_root, split="test").images[0].image
    edges = canny(image, sigma=2.0, machine=machine)
    found = link_edges(edges, machine=machine)
    assert _partition(found) == trace_curves(edges)
    _check_order(found)


def test_square_loop_and_its_measures():
    ring = np.zeros((20, 20), bool)
    ring[4, 4:14] = ring[13, 4:14] = ring[4:14, 4] = ring[4:14, 13] = True
    found = link_edges(ring, smoothing=0.0)
    assert len(found) == 1 and found.closed[0]
    assert found.length[0] == pytest.approx(36.0)
    # A closed curve's tangent turns once round: 2 pi in all.
    assert found.total_curvature[0] == pytest.approx(2 * math.pi, abs=1e-5)
    assert found.mean_curvature[0] == pytest.approx(2 * math.pi / 36, abs=1e-6)
    assert np.isnan(found.tangents[0]).all()


def test_open_line_measures_and_magnitude():
    line = np.zeros((12, 30), bool)
    line[5, 3:25] = True
    magnitude = np.zeros((12, 30), np.float32)
    magnitude[5, 3:25] = np.linspace(1, 2, 22)
    found = link_edges(line, magnitude=magnitude)
    assert len(found) == 1 and not found.closed[0]
    assert found.length[0] == pytest.approx(21.0)
    assert found.total_curvature[0] == pytest.approx(0.0, abs=1e-6)
    assert found.magnitude[0] == pytest.approx(1.5, rel=1e-6)
    ends = {tuple(found.points[0]), tuple(found.points[-1])}
    assert ends == {(3, 5), (24, 5)}
    # Out-pointing end tangents: along -x at x = 3, along +x at x = 24.
    out = {tuple(found.points[0]): found.tangents[0, 0], tuple(found.points[-1]): found.tangents[0, 1]}
    np.testing.assert_allclose(out[(3, 5)], [-1, 0], atol=1e-12)
    np.testing.assert_allclose(out[(24, 5)], [1, 0], atol=1e-12)
    tangent = np.asarray(found.tangent)
    along = tangent[5, 3:25]
    assert np.all(np.isclose(np.abs(along), 0, atol=1e-6) | np.isclose(np.abs(along), math.pi, atol=1e-6))
    assert np.isnan(tangent[0]).all()


def test_circle_curvature_is_one_over_its_radius():
    drawing = np.zeros((120, 120), np.uint8)
    cv2.circle(drawing, (60, 60), 40, 1, 1)
    found = link_edges(drawing.astype(bool), smoothing=3.0)
    assert len(found) == 1 and found.closed[0]
    assert found.length[0] == pytest.approx(2 * math.pi * 40, rel=0.1)
    assert found.mean_curvature[0] == pytest.approx(1 / 40, rel=0.1)


def test_branch_pixels_split_curves_and_are_labelled():
    tee = np.zeros((20, 21), bool)
    tee[10, 2:19] = True
    tee[3:10, 10] = True
    found = link_edges(tee)
    assert [tuple(b) for b in found.branches] == [(10, 10)]
    assert found.labels[10, 10] == BRANCH and found.labels[0, 0] == -1
    assert sorted(found.sizes.tolist()) == [7, 8, 8]


def test_device_in_device_out(machine):
    mask = _random_drawing(np.random.default_rng(9), (50, 60), 6)
    host = link_edges(mask, machine=machine)
    device = link_edges(machine.to_device(mask.astype(np.uint8)), machine=machine)
    for name in ("labels", "position", "tangent"):
        np.testing.assert_array_equal(getattr(device, name).get(), getattr(host, name))
    np.testing.assert_array_equal(device.points, host.points)


def _masks():
    rng = np.random.default_rng(21)
    yield "empty", np.zeros((7, 20), bool)
    yield "one pixel", np.pad(np.ones((1, 1), bool), 3)
    yield "solid block", np.pad(np.ones((6, 6), bool), 2)  # branch pixels inside, curve pixels at the corners
    for width in (1, 5, 15, 16, 17, 33):  # narrower than a run, a run, one pixel into the next
        for density in (0.1, 0.4):
            yield f"random {width} wide, {density}", rng.random((23, width)) < density


@pytest.mark.parametrize("name, mask", list(_masks()), ids=[name for name, _ in _masks()])
def test_maps_drawn_on_the_device_equal_the_host_s(name, mask, machine):
    # A host edge map has its maps drawn on the host from the device's fields; a device one on the device,
    # cleared by the first pass and drawn as the curves are put in order.
    host = link_edges(mask, machine=machine)
    device = link_edges(machine.to_device(mask.astype(np.uint8)), machine=machine)
    for field in ("labels", "position", "tangent"):
        np.testing.assert_array_equal(getattr(device, field).get(), getattr(host, field), err_msg=field)
    for field in ("points", "offsets", "closed", "length", "total_curvature", "magnitude", "tangents", "branches"):
        np.testing.assert_array_equal(getattr(device, field), getattr(host, field), err_msg=field)
    branches = np.zeros(mask.shape, bool)
    branches[host.branches[:, 1], host.branches[:, 0]] = True
    np.testing.assert_array_equal(host.labels == BRANCH, branches)
    np.testing.assert_array_equal(host.labels != -1, mask)  # every edge pixel is a curve's or a branch


def test_empty_map_gives_no_curves():
    found = link_edges(np.zeros((8, 9), bool))
    assert len(found) == 0 and found.points.shape == (0, 2) and (np.asarray(found.labels) == -1).all()


@pytest.mark.parametrize("call, match", [
    (lambda: link_edges(np.zeros((4, 4, 2), bool)), "edges"),
    (lambda: link_edges(np.zeros((4, 4), np.float64)), "edges"),
    (lambda: link_edges([[1, 0]]), "edges"),
    (lambda: link_edges(np.zeros((4, 4), bool), smoothing=-1), "smoothing"),
    (lambda: link_edges(np.zeros((4, 4), bool), magnitude=np.zeros((3, 4), np.float32)), "magnitude"),
])
def test_bad_input_is_refused_by_name(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_principal_with_keys_picks_the_largest_key(machine):
    # Two rings: 0 -> 1 -> 2 -> 0 and 3 -> 4 -> 3; keys make node 1 and node 3 the principals.
    nxt = np.array([1, 2, 0, 4, 3], np.int32)
    keys = np.array([5, 9, 2, 8, 1], np.int32)
    top, distance = principal(nxt, keys=keys, machine=machine)
    np.testing.assert_array_equal(top, [9, 9, 9, 8, 8])
    np.testing.assert_array_equal(distance, [2, 0, 1, 0, 1])
    with pytest.raises(InputError, match="distinct"):
        principal(nxt, keys=np.array([1, 1, 2, 3, 4], np.int32), machine=machine)


def test_steps_are_the_kernels_directions():
    # The oracle's step order is the kernels' (E, NE, N, NW, W, SW, S, SE on screen).
    assert STEPS[1] == (1, -1) and STEPS[6] == (0, 1)
