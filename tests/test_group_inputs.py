"""What the grouping stage makes of its inputs: device strengths checked as host ones, values beyond
float32's range, the image of the pairing test (its shape, size and mask), junction kinds by name, the
magnitudes behind the curves (the user review of the grouping stage), and the edges, tangents, strengths
and per-curve values of the second review."""

import re

import numpy as np
import pytest

from vmcl.errors import InputTypeError, InputValueError
from vmcl.group import (
    find_junctions,
    group,
    group_curves,
    link_edges,
    repair_edges,
    saliency_map,
    saliency_strength,
    salient_edges,
    structural_saliency,
)

DRAWING = np.zeros((32, 48), bool)
DRAWING[16, 4:44] = True


def _occlusion():
    """Two T-junction pairs: a rectangle's sides cut a line that passes behind it."""
    edges = np.zeros((60, 100), bool)
    edges[10:50, 40] = edges[10:50, 60] = True
    edges[10, 40:61] = edges[49, 40:61] = True
    edges[30, 5:40] = edges[30, 61:95] = True
    return edges


def _strength(value):
    strength = np.ones(DRAWING.shape, np.float32)
    strength[16, 10] = value
    return strength


# ------------------------------------------------------------------------------------------------ strength

@pytest.mark.parametrize("strength", [_strength(np.nan), _strength(np.inf), _strength(-1.0),
                                      np.full(DRAWING.shape, np.nan, np.float32)],
                         ids=["nan", "inf", "negative", "all nan"])
@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_strength_is_checked_on_the_device_as_on_the_host(strength, on_device, machine):
    given = machine.to_device(strength) if on_device else strength
    with pytest.raises(InputValueError, match="strength must"):
        structural_saliency(DRAWING, strength=given, machine=machine)


def test_a_curvature_scale_beyond_float32_is_refused():
    with pytest.raises(InputValueError, match="curvature_scale must lie within float32's range"):
        structural_saliency(DRAWING, curvature_scale=1e39)
    # The largest float32 itself is still a scale.
    assert np.isfinite(structural_saliency(DRAWING, curvature_scale=3e38).saliency).all()


# --------------------------------------------------------------------------------------------- magnitude

@pytest.mark.parametrize("value", [np.nan, np.inf, -1.0])
@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_link_edges_refuses_a_magnitude_that_is_no_magnitude(value, on_device, machine):
    magnitude = np.ones(DRAWING.shape, np.float32)
    magnitude[16, 20] = value
    given = machine.to_device(magnitude) if on_device else magnitude
    with pytest.raises(InputValueError, match="magnitude must"):
        link_edges(DRAWING, magnitude=given, machine=machine)
    with pytest.raises(InputValueError, match="magnitude must"):
        saliency_strength(DRAWING, given, machine=machine)


def test_saliency_strength_refuses_a_median_of_zero_on_the_edges():
    magnitude = np.zeros(DRAWING.shape, np.float32)
    magnitude[16, 4:10] = 5.0  # most edge pixels have no gradient
    with pytest.raises(InputValueError, match="magnitude is 0 on at least half of the edge pixels"):
        saliency_strength(DRAWING, magnitude)
    # No edges: nothing to scale, all 0.
    assert not saliency_strength(np.zeros_like(DRAWING), magnitude).any()


# ------------------------------------------------------------------------------------- the pairing image

def test_junctions_know_the_shape_of_their_edge_map():
    assert find_junctions(link_edges(_occlusion())).shape == (60, 100)


@pytest.mark.parametrize("shape", [(30, 50), (200, 300), (100, 60), (60, 101)])
def test_an_image_of_another_shape_is_refused(shape):
    edges = _occlusion()
    junctions = find_junctions(link_edges(edges))
    assert len(junctions.of_kind("T")) >= 2
    image = np.full(shape, 0.5, np.float32)
    with pytest.raises(InputValueError, match=r"image must have the edge map's height and width \(60, 100\)"):
        group_curves(junctions, image=image)
    with pytest.raises(InputValueError, match=r"image must have the edge map's height and width \(60, 100\)"):
        group(edges, image=image)


def test_the_image_is_checked_whatever_the_junctions():
    edges = np.zeros((60, 100), bool)
    edges[30, 10:90] = True  # one line: no T-junction to pair
    junctions = find_junctions(link_edges(edges))
    assert len(junctions.of_kind("T")) == 0
    for image, match in [(np.full((30, 50), 0.5, np.float32), "height and width"),
                         (np.full((12, 100), 0.5, np.float32), "at least 16 x 16 pixels"),
                         (np.ma.masked_less(np.full((60, 100), 0.5), 1.0), "masked array with masked values"),
                         (np.full((60, 100), 128.0), r"float images hold brightness in \[0, 1\]")]:
        with pytest.raises(InputValueError, match=match):
            group_curves(junctions, image=image)
        with pytest.raises(InputValueError, match=match):
            group(edges, image=image)


def test_a_device_image_pairs_as_its_host_copy(machine):
    # group took device edges and magnitude but refused a device image ("must be a NumPy array").
    edges = _occlusion()
    image = np.zeros(edges.shape, np.float32)
    image[:30], image[30:] = 0.2, 0.8
    image[10:50, 40:61] = 0.5
    swapped = image.copy()  # the line's sides swapped on the rectangle's right: not one edge behind it
    swapped[:30, 61:], swapped[30:, 61:] = 0.8, 0.2
    for given, pairs in ((image, 1), (swapped, 0), ((image * 255).astype(np.uint8), 1)):
        host = group(edges, image=given, machine=machine)
        found = group(machine.to_device(edges.view(np.uint8)), image=machine.to_device(given), machine=machine)
        assert found.pairs.tolist() == host.pairs.tolist() and len(host.pairs) == pairs
        assert group_curves(host.junctions, image=machine.to_device(given))[0].tolist() == host.pairs.tolist()
    with pytest.raises(InputValueError, match=r"image must have the edge map's height and width \(60, 100\)"):
        group(edges, image=machine.to_device(image[:30]), machine=machine)


@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_a_magnitude_that_overflows_the_saliency_is_named(on_device, machine):
    # A magnitude of 3e38 was blamed on the default length_exponent 0.5 ("makes the longest curves' saliency
    # overflow"): the magnitude, 3e38 times the 40 px line's 40**0.5, is what overflows.
    magnitude = np.full(DRAWING.shape, 3e38, np.float32)
    given = machine.to_device(magnitude) if on_device else magnitude
    length = float(link_edges(DRAWING).length.max())
    with pytest.raises(InputValueError, match=rf"^magnitude \(link_edges'\) up to 3e\+38 makes the curves' saliency "
                                              rf"\(magnitude times length\*\*length_exponent, here up to "
                                              rf"{length ** 0.5:.3g}\) overflow float32"):
        group(DRAWING, magnitude=given, machine=machine)
    # Where the length alone overflows, at a magnitude of 1, the exponent is to blame, as before.
    with pytest.raises(InputValueError, match="^length_exponent 30 makes the longest curves' saliency overflow"):
        group(DRAWING, magnitude=np.ones(DRAWING.shape, np.float32), length_exponent=30, machine=machine)
    # A magnitude within range keeps its saliency: the mean magnitude times length**0.5.
    largest = np.float32(np.finfo(np.float32).max / 2 / length ** 0.5)
    saliency = group(DRAWING, magnitude=np.full(DRAWING.shape, largest, np.float32), machine=machine).saliency
    assert np.allclose(saliency, float(largest) * length ** 0.5, rtol=1e-5)


def test_an_image_of_the_edge_maps_shape_still_pairs(machine):
    edges = _occlusion()
    image = np.zeros(edges.shape, np.float32)
    image[:30], image[30:] = 0.2, 0.8
    image[10:50, 40:61] = 0.5
    found = group(edges, image=image, machine=machine)
    assert found.pairs.tolist() == group_curves(found.junctions, image=image)[0].tolist()
    assert len(found.pairs) == 1
    assert len(group(edges, image=np.dstack([image] * 3), machine=machine).pairs) == 1


# ------------------------------------------------------------------------------------------ junction kinds

def test_a_junction_kind_is_named_by_a_known_string():
    junctions = find_junctions(link_edges(_occlusion()))
    assert junctions.of_kind("T").size == 2  # where the line meets the rectangle; the corners are L
    with pytest.raises(InputValueError, match="kind must be one of"):
        junctions.of_kind("Z")
    with pytest.raises(InputTypeError, match="kind must be one of"):
        junctions.of_kind(3)


# ------------------------------------------------------------------------------------------- repair_edges

def _broken_t():
    """A T whose stem stops three pixels short of its bar: one junction with a fill."""
    edges = np.zeros((60, 60), bool)
    edges[20, 5:55] = True
    edges[24:51, 30] = True
    return edges, find_junctions(link_edges(edges))


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_repair_edges_refuses_an_edge_map_that_is_not_finite(value):
    edges, junctions = _broken_t()
    given = edges.astype(np.float64)
    given[0, 0] = value  # non-zero: cast to bool it would be an edge
    with pytest.raises(InputValueError, match="edges must not contain NaN or infinite values"):
        repair_edges(given, junctions)


@pytest.mark.parametrize("shape", [(100, 100), (61, 60), (60, 61)])
def test_repair_edges_refuses_an_edge_map_of_another_shape(shape):
    edges, junctions = _broken_t()
    assert junctions.shape == (60, 60) and sum(len(fill) for fill in junctions.fills) > 0
    with pytest.raises(InputValueError, match=re.escape(f"the junctions were found in (60, 60), got shape {shape}")):
        repair_edges(np.zeros(shape, bool), junctions)
    # The edge map itself is repaired: the stem reaches the bar.
    assert repair_edges(edges, junctions)[20:24, 30].all()


# ------------------------------------------------------------------------------ tangents and strengths

@pytest.mark.parametrize("value", [np.inf, -np.inf])
@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_an_infinite_tangent_is_refused(value, on_device, machine):
    tangent = np.zeros(DRAWING.shape, np.float32)
    tangent[16, 10] = value  # on the line
    given = machine.to_device(tangent) if on_device else tangent
    with pytest.raises(InputValueError, match="tangent must be finite where known"):
        structural_saliency(DRAWING, tangent=given, machine=machine)
    # NaN is an unknown tangent, and taken.
    tangent[16, 10] = np.nan
    given = machine.to_device(tangent) if on_device else tangent
    assert np.isfinite(structural_saliency(DRAWING, tangent=given, machine=machine).saliency).all()


@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_a_strength_that_would_overflow_the_saliency_is_refused(on_device, machine):
    iterations = 30
    limit = float(np.finfo(np.float32).max) / (4 * iterations)
    largest = np.float32(limit)
    if largest > limit:  # the float32 nearest the limit may lie just above it
        largest = np.nextafter(largest, np.float32(0))
    for value in [3e38, np.nextafter(largest, np.float32(np.inf))]:
        strength = _strength(value)
        given = machine.to_device(strength) if on_device else strength
        with pytest.raises(InputValueError, match=r"strength must be at most .* for iterations=30"):
            structural_saliency(DRAWING, strength=given, iterations=iterations, machine=machine)
    # At the limit, even everywhere, the saliency stays finite.
    strength = np.full(DRAWING.shape, largest, np.float32)
    given = machine.to_device(strength) if on_device else strength
    saliency = structural_saliency(DRAWING, strength=given, iterations=iterations, machine=machine).saliency
    assert np.isfinite(saliency).all()


# ---------------------------------------------------------------------------------------- per-curve values

@pytest.mark.parametrize("value, match", [(np.nan, "must not contain NaN or infinite values"),
                                          (np.inf, "must not contain NaN or infinite values"),
                                          (1e39, "has values beyond float32's range")])
def test_per_curve_values_must_be_finite(value, match):
    curves = link_edges(DRAWING)
    values = np.full(len(curves), value)
    with pytest.raises(InputValueError, match=f"values {match}"):
        saliency_map(curves, values)
    with pytest.raises(InputValueError, match=f"saliency {match}"):
        salient_edges(curves, values, 1.0)


# ---------------------------------------------------------------------------------- single-pixel curves

def _crossing():
    """A vertical line across two horizontal ones two rows apart: the pixel between the crossings (the
    branch pixels) is a curve of its own, one pixel long."""
    edges = np.zeros((32, 40), bool)
    edges[10, 4:36] = edges[12, 4:36] = True
    edges[2:30, 20] = True
    return edges


@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_a_single_pixel_has_no_tangent(on_device, machine):
    edges = _crossing()
    curves = link_edges(machine.to_device(edges.view(np.uint8)) if on_device else edges, machine=machine)
    labels, tangent = (m.get() if on_device else m for m in (curves.labels, curves.tangent))
    single = curves.sizes[labels[11, 20]] == 1
    assert single and np.isnan(curves.tangents[labels[11, 20]]).all()
    assert np.isnan(tangent[11, 20])
    # Other curve pixels keep theirs.
    assert np.isfinite(tangent[labels >= 0][curves.sizes[labels[labels >= 0]] > 1]).all()


def test_structural_saliency_takes_a_single_pixel_tangent_as_unknown(machine):
    edges = _crossing()
    unknown = np.asarray(link_edges(edges, machine=machine).tangent).copy()
    unknown[11, 20] = np.nan
    default = structural_saliency(edges, machine=machine).saliency
    assert np.array_equal(default, structural_saliency(edges, tangent=unknown, machine=machine).saliency)
    # As the pixel were horizontal, the vertical line would turn there, and lose saliency.
    horizontal = unknown.copy()
    horizontal[11, 20] = 0.0
    assert structural_saliency(edges, tangent=horizontal, machine=machine).saliency[11, 20] < default[11, 20]
