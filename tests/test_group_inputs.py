"""What the grouping stage makes of its inputs: device strengths checked as host ones, values beyond
float32's range, the image of the pairing test (its shape, size and mask), junction kinds by name, and the
magnitudes behind the curves (the user review of the grouping stage)."""

import numpy as np
import pytest

from vmcl.errors import InputTypeError, InputValueError
from vmcl.group import (
    find_junctions,
    group,
    group_curves,
    link_edges,
    saliency_strength,
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
