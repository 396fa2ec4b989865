"""vmcl.group's saliency: the structural saliency network against a NumPy network, on shapes in clutter,
and local saliency against its formula."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import structural_saliency as numpy_network
from scipy import ndimage

from vmcl.errors import InputError
from vmcl.group import (
    link_edges,
    local_saliency,
    saliency_map,
    saliency_strength,
    salient_edges,
    structural_saliency,
)
from vmcl.scenes import clutter_display

TRIALS = range(20)  # the displays' test seeds; the defaults were chosen on seeds 100-119


def _random_field(seed, shape, density=0.25):
    rng = np.random.default_rng(seed)
    mask = rng.random(shape) < density
    tangent = np.where(mask & (rng.random(shape) < 0.9), rng.uniform(-math.pi, math.pi, shape), np.nan)
    strength = mask * rng.uniform(0.5, 2.0, shape)
    return mask, tangent.astype(np.float32), strength.astype(np.float32)


@given(st.integers(1, 30), st.integers(1, 30), st.integers(1, 15), st.floats(0.0, 1.0), st.floats(0.0, 3.0),
       st.integers(0, 2**31 - 1))
@settings(max_examples=20, deadline=None)
def test_network_matches_numpy(height, width, iterations, attenuation, curvature, seed):
    mask, tangent, strength = _random_field(seed, (height, width))
    want, elements = numpy_network(mask, tangent, strength, iterations, attenuation, curvature)
    got = structural_saliency(mask, tangent=tangent, strength=strength, iterations=iterations,
                              gap_attenuation=attenuation, curvature_scale=curvature)
    np.testing.assert_allclose(got.elements, elements, rtol=2e-5, atol=2e-5)
    np.testing.assert_allclose(got.saliency, want, rtol=2e-5, atol=2e-5)


def test_default_tangent_is_the_curves_own_and_device_in_device_out(machine):
    display = clutter_display((96, 96), segments=30, seed=3)
    tangent = link_edges(display.edges, machine=machine).tangent
    given_tangent = structural_saliency(display.edges, tangent=tangent, machine=machine).saliency
    own = structural_saliency(display.edges, machine=machine).saliency
    np.testing.assert_array_equal(own, given_tangent)
    on_device = structural_saliency(machine.to_device(display.edges.astype(np.uint8)), machine=machine)
    np.testing.assert_array_equal(on_device.saliency.get(), own)


def test_a_straight_line_scores_its_length():
    drawing = np.zeros((20, 60), bool)
    drawing[10, 5:45] = True  # 40 pixels, 39 elements
    # Ten iterations from the middle: ten elements of strength 1 ahead and ten behind, all straight.
    assert structural_saliency(drawing, iterations=10).saliency[10, 25] == pytest.approx(20.0, abs=1e-4)
    # Enough iterations to reach both ends: the line's 39 elements, plus what a path that turns round in
    # the empty space past an end may count again, which the turns' cost keeps small.
    saliency = structural_saliency(drawing, iterations=60).saliency
    assert 39.0 <= saliency[10, 25] <= 39.0 * 1.1
    assert 39.0 <= saliency[10, 5] <= 39.0 * 1.1


def _top_share(display, saliency):
    """The share of the K most salient edge pixels (K = the contour's size) within 1 pixel of the contour."""
    k = int(display.contour.sum())
    top = np.argsort(np.where(display.edges, saliency, -1).ravel(), kind="stable")[::-1][:k]
    near = ndimage.binary_dilation(display.contour, iterations=1)
    return near.ravel()[top].mean()


@pytest.mark.parametrize("gaps", [0, 8])
def test_contour_in_clutter_ranks_highest(gaps, machine):
    shares = [_top_share(display, structural_saliency(display.edges, machine=machine).saliency)
              for display in (clutter_display(segments=200, gaps=gaps, gap_length=3, seed=seed) for seed in TRIALS)]
    # In at least 90% of the displays, at least 90% of the most salient pixels are the contour's.
    assert np.mean(np.array(shares) >= 0.9) >= 0.9, shares


def test_clutter_display_is_what_it_says():
    display = clutter_display(segments=200, gaps=8, gap_length=3, seed=5)
    assert display.edges.dtype == bool and display.edges.shape == (256, 256)
    assert (display.contour <= display.edges).all()
    # An ellipse of these radii has about this perimeter (Ramanujan), less the 24 pixels of its gaps.
    a, b = display.radii
    perimeter = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))
    assert display.contour.sum() == pytest.approx(perimeter - 24, rel=0.25)
    np.testing.assert_array_equal(clutter_display(seed=5, gaps=8).edges, display.edges)


def test_local_saliency_is_its_formula():
    drawing = np.zeros((40, 60), bool)
    drawing[10, 5:45] = True
    drawing[25:30, 20] = True
    magnitude = np.where(drawing, 2.0, 0).astype(np.float32)
    curves = link_edges(drawing, magnitude=magnitude)
    values = local_saliency(curves, length_exponent=0.5, curvature_scale=0.25)
    want = 2.0 * np.maximum(curves.length, 1) ** 0.5 * np.exp(-curves.mean_curvature / 0.25)
    np.testing.assert_allclose(values, want)
    assert sorted(values.round(6)) == sorted([round(2 * math.sqrt(4), 6), round(2 * math.sqrt(39), 6)])
    painted = saliency_map(curves, values)
    assert painted[10, 20] == pytest.approx(2 * math.sqrt(39)) and painted[0, 0] == 0
    kept = salient_edges(curves, values, 5.0)
    assert kept[10, 5:45].all() and not kept[25:30, 20].any()


def test_a_junction_pixel_stays_where_a_kept_curve_touches_it():
    """A T: the bar is split at the junction into two curves, the junction pixel is a branch pixel of none.
    Kept with the one curve that passes the threshold, dropped when none does."""
    drawing = np.zeros((40, 60), bool)
    drawing[10, 5:45] = True
    drawing[11:30, 20] = True
    curves = link_edges(drawing, magnitude=np.where(drawing, 2.0, 0).astype(np.float32))
    values = local_saliency(curves, length_exponent=0.5, curvature_scale=0.25)
    longest = float(values.max())  # the bar's right part, 24 px
    kept = salient_edges(curves, values, longest - 1e-3)
    assert kept[10, 20] and kept[10, 21:45].all()
    assert not kept[10, 5:20].any() and not kept[11:30, 20].any()
    assert not salient_edges(curves, values, longest + 1e-3).any()


def test_saliency_strength_is_relative_to_the_median():
    edges = np.zeros((10, 10), bool)
    edges[2, 2:8] = True
    magnitude = np.zeros((10, 10), np.float32)
    magnitude[2, 2:8] = [1, 2, 3, 4, 5, 6]
    strength = saliency_strength(edges, magnitude)
    np.testing.assert_allclose(strength[2, 2:8], np.array([1, 2, 3, 4, 5, 6]) / 3.5, rtol=1e-6)
    assert strength[~edges].max() == 0


@pytest.mark.parametrize("call, match", [
    (lambda: structural_saliency(np.zeros((8, 8), bool), iterations=0), "iterations"),
    (lambda: structural_saliency(np.zeros((8, 8), bool), gap_attenuation=1.5), "gap_attenuation"),
    (lambda: structural_saliency(np.zeros((8, 8), bool), curvature_scale=-1), "curvature_scale"),
    (lambda: structural_saliency(np.zeros((8, 8), bool), tangent=np.zeros((7, 8), np.float32)), "tangent"),
    (lambda: structural_saliency(np.zeros((8, 8), bool), strength=-np.ones((8, 8), np.float32)), "strength"),
    (lambda: local_saliency(np.zeros((8, 8))), "curves"),
    (lambda: local_saliency(link_edges(np.eye(8, dtype=bool)), curvature_scale=0), "curvature_scale"),
    (lambda: saliency_map(link_edges(np.eye(8, dtype=bool)), np.zeros(3)), "values"),
    (lambda: clutter_display((32, 32)), "shape"),
    (lambda: clutter_display(length=(5, 2)), "length"),
])
def test_bad_input_is_refused_by_name(call, match):
    with pytest.raises(InputError, match=match):
        call()
