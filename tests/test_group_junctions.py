"""vmcl.group.junctions: junctions found and classified, broken T-junctions repaired, curves grouped across
pairs of T-junctions; scored against the exact junctions of vmcl.scenes' occlusion scenes.

Evaluated T-junctions: those whose type is defined at the detector's scale (OcclusionScene.resolvable):
no other junction of the scene within 6 pixels (the arms are measured 2 to 12 pixels out) and every angle
between arms at least 30 degrees (Canny at sigma 1 merges edges closer than that). Detections near the
T-junctions left out are neither right nor wrong. The scenes' seeds 0-39 are the test set; the detector was tuned on seeds
1000-1039.
"""

import math

import cv2
import numpy as np
import pytest

from vmcl.early.edges import canny
from vmcl.errors import InputError
from vmcl.group import find_junctions, group, group_curves, link_edges, repair_edges
from vmcl.metrics import match_points, point_scores
from vmcl.scenes import occlusion_scene, render_occlusion

SEEDS = range(40)


def _truth(scene):
    """The scene's T-junction points, split into those evaluated and those left out."""
    points = np.array([[j.x, j.y] for j in scene.t_junctions()]).reshape(-1, 2)
    keep = scene.resolvable()
    return points[keep], points[~keep]


@pytest.fixture(scope="module")
def scenes(machine):
    out = []
    for seed in SEEDS:
        scene = render_occlusion((256, 256), polygons=6, seed=seed, noise=0.01)
        edges = canny(scene.image, sigma=1.0, machine=machine)
        curves = link_edges(edges, machine=machine)
        out.append((scene, edges, curves, find_junctions(curves)))
    return out


def test_t_junction_recall_and_precision_within_3_px(scenes):
    hits = truths = counted = 0
    for scene, _, _, junctions in scenes:
        evaluated, left_out = _truth(scene)
        found = junctions.points[junctions.of_kind("T")]
        hits += len(match_points(evaluated, found, tolerance=3.0))
        truths += len(evaluated)
        # Detections in the border strip where the scene knows no junctions count neither way.
        counted += point_scores(evaluated, found, tolerance=3.0, ignore=left_out,
                                exclude=scene.outside(found)).n_predicted
    assert truths > 100
    recall, precision = hits / truths, hits / counted
    assert recall >= 0.8, recall
    assert precision >= 0.8, precision


def test_each_t_says_which_side_occludes(scenes):
    right = total = 0
    for scene, _, _, junctions in scenes:
        truth = [j for j, keep in zip(scene.t_junctions(), scene.resolvable()) if keep]
        points = np.array([[j.x, j.y] for j in truth]).reshape(-1, 2)
        ts = junctions.of_kind("T")
        for r, c in match_points(points, junctions.points[ts], tolerance=3.0):
            # A point a few pixels into the side the T says occludes lies on the occluder.
            x, y = np.rint(junctions.points[ts[c]] + 4 * junctions.occluder[ts[c]]).astype(int)
            right += scene.regions[min(max(y, 0), 255), min(max(x, 0), 255)] == truth[r].occluder
            total += 1
    assert total > 100
    assert right / total >= 0.85, right / total


def test_broken_t_junctions_are_repaired_within_2_px(scenes, machine):
    broken = repaired = 0
    for scene, edges, curves, junctions in scenes:
        fixed = link_edges(repair_edges(edges, junctions), machine=machine)
        for j, keep in zip(scene.t_junctions(), scene.resolvable()):
            point = np.array([j.x, j.y])
            if not keep or (len(curves.branches) and np.linalg.norm(curves.branches - point, axis=1).min() <= 2):
                continue  # Canny joined this one itself
            broken += 1
            repaired += bool(len(fixed.branches)) and np.linalg.norm(fixed.branches - point, axis=1).min() <= 2
    assert broken > 50
    assert repaired / broken >= 0.7, repaired / broken


def _drawing(arms_degrees, size=64, length=24):
    """A line drawing of straight arms from the centre."""
    drawing = np.zeros((size, size), np.uint8)
    centre = size // 2
    for angle in np.radians(arms_degrees):
        end = (round(centre + length * math.cos(angle)), round(centre + length * math.sin(angle)))
        cv2.line(drawing, (centre, centre), end, 1, 1)
    return drawing.astype(bool)


@pytest.mark.parametrize("arms, kind", [
    ((0, 180, 90), "T"), ((0, 180, -60), "T"), ((90, 210, 330), "Y"), ((0, 150, 210), "Y"), ((0, 50, 100), "arrow"),
    ((0, 90), "L"), ((0, 90, 180, 270), "X"), ((30, 100, 200, 300), "X"),
])
def test_drawn_junctions_are_classified(arms, kind):
    found = find_junctions(link_edges(_drawing(arms)))
    near = np.linalg.norm(found.points - 32, axis=1) <= 3
    assert list(found.kinds[near]) == [kind]
    got = found.arms[near][0][:len(arms)]
    off = np.abs(np.angle(np.exp(1j * (np.radians(arms)[:, None] - got[None]))))
    assert np.all(off.min(axis=1) <= math.radians(8))


def test_a_t_broken_by_a_gap_is_found_repaired_and_oriented():
    drawing = np.zeros((64, 64), bool)
    drawing[40, 8:56] = True   # the bar
    drawing[10:36, 32] = True  # the stem, ending 5 pixels above the bar
    found = find_junctions(link_edges(drawing))
    (t,) = found.of_kind("T")
    np.testing.assert_allclose(found.points[t], [32, 40], atol=1)
    assert found.gap[t] == pytest.approx(5.0)
    # The stem comes from above, so the occluding surface is below the bar.
    np.testing.assert_allclose(found.occluder[t], [0, 1], atol=1e-6)
    repaired = repair_edges(drawing, found)
    assert repaired[36:40, 32].all() and repaired.sum() == drawing.sum() + 4


@pytest.mark.parametrize("hit, kind", [(31, "L"), (32, "L"), (33, "T"), (45, "T")])
def test_a_gap_reaching_a_curve_by_its_end_makes_a_corner_not_a_t(hit, kind):
    """A bar needs at least three pixels on each side of where the stem's gap meets it: met one or two
    pixels from its end, the two curves make a corner (Canny breaks corners as it breaks T's)."""
    drawing = np.zeros((80, 80), bool)
    drawing[50, 30:61] = True  # the bar, from x = 30
    drawing[20:47, hit] = True  # the stem, ending 3 pixels above the bar
    found = find_junctions(link_edges(drawing))
    assert list(found.kinds) == [kind]
    np.testing.assert_allclose(found.points[0], [hit, 50], atol=1)


def test_curves_are_grouped_across_an_occluder(machine):
    # A vertical rectangle behind a horizontal band: its two long edges are cut twice each, making two
    # pairs of T-junctions whose stems point at each other across the band.
    back = np.array([[100, 20], [150, 20], [150, 236], [100, 236]], float)
    band = np.array([[20, 110], [236, 110], [236, 150], [20, 150]], float)
    scene = occlusion_scene([back, band], [0.25, 0.75], shape=(256, 256), background=0.5, noise=0.01)
    result = canny(scene.image, sigma=1.0, return_gradient=True, machine=machine)
    found = group(result.edges, magnitude=result.magnitude, image=scene.image, machine=machine)
    truth = {tuple(sorted(pair)) for pair in scene.t_pairs()}
    assert len(truth) == 2
    points = np.array([[j.x, j.y] for j in scene.junctions])
    got = set()
    for a, b in found.pairs:
        ia = int(np.argmin(np.linalg.norm(points - found.junctions.points[a], axis=1)))
        ib = int(np.argmin(np.linalg.norm(points - found.junctions.points[b], axis=1)))
        got.add(tuple(sorted((ia, ib))))
    assert got == truth
    # Canny draws the rectangle above the band as one curve and below it as another; the pairs join them.
    (members,) = found.groups
    heights = sorted(found.curves[int(c)].points[:, 1].mean() for c in members)
    assert len(members) == 2 and heights[0] < 110 and heights[1] > 150


def test_pairs_need_alike_brightness_when_the_image_is_given(machine):
    back = np.array([[100, 20], [150, 20], [150, 236], [100, 236]], float)
    band = np.array([[20, 110], [236, 110], [236, 150], [20, 150]], float)
    scene = occlusion_scene([back, band], [0.25, 0.75], shape=(256, 256), background=0.5, noise=0.01)
    junctions = find_junctions(link_edges(canny(scene.image, sigma=1.0, machine=machine), machine=machine))
    pairs, _ = group_curves(junctions, image=scene.image)
    assert len(pairs) == 2
    # The same junctions against an image where the two sides of the band differ: no pairs.
    other = scene.image.copy()
    other[150:] = np.where(np.abs(other[150:] - 0.25) < 0.05, 0.9, other[150:])
    assert len(group_curves(junctions, image=other)[0]) == 0


@pytest.mark.parametrize("call, match", [
    (lambda: find_junctions(np.zeros((4, 4))), "curves"),
    (lambda: find_junctions(link_edges(np.zeros((8, 8), bool)), gap=-1), "gap"),
    (lambda: find_junctions(link_edges(np.zeros((8, 8), bool)), straight=95), "straight"),
    (lambda: find_junctions(link_edges(np.zeros((8, 8), bool)), min_length=1), "min_length"),
    (lambda: group_curves("junctions"), "junctions"),
    (lambda: group_curves(find_junctions(link_edges(np.zeros((8, 8), bool))), alignment=0), "alignment"),
])
def test_bad_input_is_refused_by_name(call, match):
    with pytest.raises(InputError, match=match):
        call()


@pytest.mark.parametrize("extra", [[], [(30, 23)], [(29, 26), (30, 23), (30, 24)]])
def test_a_t_junction_survives_the_fragments_canny_leaves_in_its_gap(extra):
    # A one-pixel fragment between a stem and its bar stopped the stem's search (it "joined" a junction
    # that was not there), and a spur with a stub made the stem's end touch a cluster with no junction.
    edges = np.zeros((60, 60), bool)
    edges[20, 5:55] = True
    edges[26:55, 30] = True
    for x, y in extra:
        edges[y, x] = True
    found = find_junctions(link_edges(edges))
    assert list(found.kinds) == ["T"]
    np.testing.assert_allclose(found.points, [[30.0, 20.0]], atol=1.0)
