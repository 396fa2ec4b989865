"""The grouping stage in the machine: Result.grouping, salient edges as the MRFs' coupling, the report."""

import numpy as np
import pytest

from vmcl.early.edges import canny
from vmcl.errors import InputError
from vmcl.group import link_edges, structural_saliency
from vmcl.pipeline import Config, VisionMachine, as_image
from vmcl.report import images, write_report
from vmcl.scenes import render_occlusion


@pytest.fixture(scope="module")
def scene():
    return render_occlusion((128, 160), polygons=5, seed=2, noise=0.01)


def _canny(image, machine):
    config = Config()
    return canny(as_image(image, "image"), sigma=config.edges.sigma, machine=machine)


def test_result_holds_the_grouping_of_the_edges(scene, machine):
    result = VisionMachine(machine=machine).run(scene.image)
    assert "grouping" in result.stages
    grouping = result.grouping
    assert grouping is not None
    # The curves are those of the edges the run found: every edge pixel on a curve or a branch.
    np.testing.assert_array_equal(grouping.curves.labels != -1, result.edges)
    again = link_edges(result.edges)
    np.testing.assert_array_equal(grouping.curves.points, again.points)
    assert grouping.junctions.counts()["T"] >= 1
    # The repairs only add pixels.
    assert (grouping.repaired >= result.edges).all()


def test_grouping_can_be_turned_off(scene, machine):
    result = VisionMachine(Config.from_dict({"grouping": {"enabled": False}}), machine=machine).run(scene.image)
    assert result.grouping is None and "grouping" not in result.stages
    assert "grouping" not in VisionMachine(Config.from_dict({"grouping": {"enabled": False}})).stages(
        right=False, next=False, rgb=False)


def test_locally_salient_edges_couple_the_mrfs(scene, machine):
    canny_edges = _canny(scene.image, machine)
    config = Config.from_dict({"edges": {"saliency": "local"}, "grouping": {"threshold": 2.0}})
    result = VisionMachine(config, machine=machine).run(scene.image)
    assert result.grouping is not None
    np.testing.assert_array_equal(result.edges, result.grouping.salient)
    assert result.edges.sum() < canny_edges.sum() and (result.edges <= canny_edges).all()
    # Every kept curve pixel is on a curve of saliency >= 2; every dropped one on a curve below it.
    labels = np.asarray(result.grouping.curves.labels)
    on = labels >= 0
    assert (result.grouping.saliency[labels[on & result.edges]] >= 2.0).all()
    assert (result.grouping.saliency[labels[on & ~result.edges]] < 2.0).all()


def test_structurally_salient_edges_couple_the_mrfs(scene, machine):
    canny_edges = _canny(scene.image, machine)
    config = Config.from_dict({"edges": {"saliency": "structural"},
                               "grouping": {"enabled": False, "structural_threshold": 20.0, "iterations": 20}})
    result = VisionMachine(config, machine=machine).run(scene.image)
    from vmcl.group import saliency_strength

    grey = as_image(scene.image, "image")
    gradient = canny(grey, sigma=2.0, return_gradient=True, machine=machine)
    strength = saliency_strength(gradient.edges, gradient.magnitude)
    network = structural_saliency(gradient.edges, tangent=link_edges(gradient.edges).tangent, strength=strength,
                                  iterations=20, gap_attenuation=0.85, machine=machine).saliency
    np.testing.assert_array_equal(result.edges, canny_edges & (network * strength >= 20.0))
    assert 0 < result.edges.sum() < canny_edges.sum()


@pytest.mark.parametrize("saliency", ["structural", "local"])
def test_a_pruning_that_keeps_no_edge_says_so(machine, saliency):
    # A clean step: its edges are all alike in contrast, and the structural threshold fitted on photographs
    # pruned every one of them with no word.
    image = np.full((64, 64), 0.2, np.float32)
    image[:, 32:] = 0.8
    config = Config.from_dict({"edges": {"saliency": saliency},
                               "grouping": {"structural_threshold": 1e6, "threshold": 1e6}})
    result = VisionMachine(config, machine=machine).run(image)
    assert not result.edges.any()
    assert any(n.startswith(f"edges: the {saliency} saliency pruning kept none of the") for n in result.notes)
    kept = VisionMachine(Config.from_dict({"edges": {"saliency": saliency}, "grouping": {"structural_threshold": 0.0,
                                                                                       "threshold": 0.0}}),
                         machine=machine).run(image)
    assert kept.edges.any() and not any("pruning kept none" in n for n in kept.notes)


def test_report_shows_the_grouping(scene, machine, tmp_path):
    result = VisionMachine(machine=machine).run(scene.image)
    pictures = images(result)
    assert pictures["grouping"].shape == (*scene.image.shape, 3)
    written = write_report(result, tmp_path / "report")
    page = written["report"].read_text(encoding="utf-8")
    assert "<h2>Grouping</h2>" in page and "T junctions" in page


@pytest.mark.parametrize("values, match", [
    ({"edges": {"saliency": "salient"}}, "edges.saliency"),
    ({"grouping": {"threshold": -1.0}}, "grouping.threshold"),
    ({"grouping": {"iterations": 0}}, "grouping.iterations"),
    ({"grouping": {"gap_attenuation": 2.0}}, "grouping.gap_attenuation"),
    ({"grouping": {"bogus": 1}}, "grouping.bogus"),
])
def test_bad_grouping_settings_are_refused_by_name(values, match):
    with pytest.raises(InputError, match=match):
        Config.from_dict(values)
