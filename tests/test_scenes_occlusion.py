"""vmcl.scenes.occlusion: layered polygons and their exact junctions, checked against independent geometry
(OpenCV's rasteriser, scikit-image's point-in-polygon test, hand-worked scenes)."""

import math

import cv2
import numpy as np
import pytest
from skimage.measure import points_in_poly

from vmcl.errors import InputTypeError, InputValueError
from vmcl.scenes import Junction, OcclusionScene, occlusion, render_occlusion
from vmcl.scenes.occlusion import occlusion_scene

PI = math.pi


def square(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def wedge(centre, start_deg, stop_deg, radius=50.0):
    """A triangle with apex ``centre`` spanning directions start..stop (degrees, image coordinates)."""
    c = np.asarray(centre, float)
    ends = [c + radius * np.array([math.cos(math.radians(a)), math.sin(math.radians(a))])
            for a in (start_deg, stop_deg)]
    return np.array([c, *ends])


def visible(scene, x, y):
    """The visible polygon at points (x, y) by painter's order over scikit-image's point-in-polygon."""
    points = np.stack([np.ravel(x), np.ravel(y)], axis=1)
    labels = np.full(len(points), -1)
    for index, vertices in enumerate(scene.polygons):
        labels[points_in_poly(points, vertices)] = index
    return labels.reshape(np.shape(x))


def ring(scene, x, y, radius, samples=720):
    theta = 0.1234 + np.arange(samples) * 2 * PI / samples
    return visible(scene, x + radius * np.cos(theta), y + radius * np.sin(theta))


def find(scene, x, y, tol=1e-9):
    hits = [j for j in scene.junctions if abs(j.x - x) <= tol and abs(j.y - y) <= tol]
    assert len(hits) == 1, (x, y, scene.junctions)
    return hits[0]


def interior_angle(vertices, k):
    a, b, c = vertices[k - 1], vertices[k], vertices[(k + 1) % len(vertices)]
    u, v = a - b, c - b
    return math.degrees(math.acos(np.clip(np.dot(u, v) / np.linalg.norm(u) / np.linalg.norm(v), -1, 1)))


# ------------------------------------------------------------------------------------------ determinism


def test_same_seed_same_scene_and_different_seeds_differ():
    a, b = render_occlusion((96, 128), polygons=5, seed=11, noise=0.05), \
        render_occlusion((96, 128), polygons=5, seed=11, noise=0.05)
    assert np.array_equal(a.image, b.image) and np.array_equal(a.regions, b.regions)
    assert all(np.array_equal(p, q) for p, q in zip(a.polygons, b.polygons))
    assert a.greys == b.greys and a.background == b.background and a.junctions == b.junctions
    c = render_occlusion((96, 128), polygons=5, seed=12, noise=0.05)
    assert not np.array_equal(a.image, c.image)
    assert not all(p.shape == q.shape and np.array_equal(p, q) for p, q in zip(a.polygons, c.polygons))


def test_random_polygons_and_greys_follow_the_recipe():
    for seed in range(10):
        scene = render_occlusion((120, 160), polygons=6, seed=seed)
        assert len(scene.polygons) == 6 and len(scene.greys) == 6
        for vertices in scene.polygons:
            assert vertices.dtype == np.float64 and 3 <= len(vertices) <= 6
            edges = np.roll(vertices, -1, axis=0) - vertices
            turns = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
            assert (turns > 0).all()  # strictly convex, one orientation
        levels = np.array([scene.background, *scene.greys])
        gaps = np.abs(levels[:, None] - levels[None, :])[~np.eye(7, dtype=bool)]
        assert gaps.min() >= 0.12 and levels.min() >= 0.1 - 1e-12 and levels.max() <= 0.9 + 1e-12
    crowded = render_occlusion(polygons=8, seed=3)
    levels = np.array([crowded.background, *crowded.greys])
    assert np.abs(np.diff(np.sort(levels))).min() >= 0.1 - 1e-12


# -------------------------------------------------------------------------------------- regions, image


@pytest.mark.parametrize("seed", [0, 1, 2, 5])
def test_regions_agree_with_opencv_rasterisation(seed):
    scene = render_occlusion((160, 200), polygons=7, seed=seed)
    h, w = scene.regions.shape
    reference = np.full((h, w), -1, dtype=np.int32)
    for index, vertices in enumerate(scene.polygons):
        # A 16x canvas where image pixel centre c sits at the centre of fine pixel 16 c + 8: OpenCV's
        # fill rule then blurs the edges by 1/16 px only.
        mask = np.zeros((16 * h, 16 * w), np.uint8)
        cv2.fillPoly(mask, [np.round(vertices * 16 + 8).astype(np.int32).reshape(-1, 1, 2)], 1)
        reference[mask[8::16, 8::16] == 1] = index
    differ = reference != scene.regions
    assert differ.mean() <= 0.01
    # Disagreements are boundary pixels only: each has a 4-neighbour of another region (in either raster).
    pad = np.pad(scene.regions, 1, mode="edge")
    boundary = np.zeros_like(differ)
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        boundary |= pad[dy:dy + scene.regions.shape[0], dx:dx + scene.regions.shape[1]] != scene.regions
    pad_ref = np.pad(reference, 1, mode="edge")
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        boundary |= pad_ref[dy:dy + reference.shape[0], dx:dx + reference.shape[1]] != reference
    assert not (differ & ~boundary).any()


def test_regions_match_the_analytic_painter_at_pixel_centres():
    scene = render_occlusion((64, 80), polygons=6, seed=4)
    y, x = np.mgrid[0:64, 0:80].astype(float)
    # Offsets far below a pixel keep skimage off the edges, where the two tests' conventions may differ.
    reference = visible(scene, x + 1e-7, y + 1e-7)
    assert (reference == scene.regions).mean() >= 0.995


def test_image_without_antialias_is_the_grey_of_each_region():
    scene = render_occlusion((100, 90), polygons=6, seed=7, antialias=False)
    lookup = np.array([*scene.greys, scene.background], dtype=np.float32)
    assert scene.image.dtype == np.float32 and scene.regions.dtype == np.int32
    assert np.array_equal(scene.image, lookup[scene.regions])


@pytest.mark.parametrize("seed", [0, 3, 9, 11, 20])
def test_antialiased_interior_pixels_hold_their_region_grey(seed):
    scene = render_occlusion((128, 128), polygons=6, seed=seed)
    r = scene.regions
    h, w = r.shape
    # Interior: the 3 x 3 block around the pixel in one region, away from the image border (where the
    # block is cut off) and free of polygon vertices (a corner can poke into a pixel between the centres
    # of its neighbours: an edge line cannot, it would separate two of the 9 centres).
    interior = np.zeros(r.shape, bool)
    interior[1:-1, 1:-1] = True
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            interior[1:-1, 1:-1] &= r[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] == r[1:-1, 1:-1]
    for vertex in np.concatenate(scene.polygons):
        c, row = int(np.floor(vertex[0])), int(np.floor(vertex[1]))
        interior[max(row - 1, 0):max(row + 3, 0), max(c - 1, 0):max(c + 3, 0)] = False
    lookup = np.array([*scene.greys, scene.background])
    assert interior.mean() > 0.5
    for label in np.unique(r[interior]):
        assert scene.image[interior & (r == label)].mean() == pytest.approx(lookup[label], abs=1e-6)
    assert np.abs(scene.image[interior] - lookup[r[interior]]).max() <= 1e-6
    assert not np.array_equal(scene.image, lookup[r].astype(np.float32))  # edge pixels are mixed


def test_antialias_gives_exact_coverage_of_quarter_pixel_edges():
    # Edges at x = 60.25 and 140.25 cover a quarter and three quarters of their pixels' 4 sample columns;
    # y = 50.5 and 150.5 fall on pixel borders.
    scene = occlusion_scene([square(60.25, 50.5, 140.25, 150.5)], [0.9], shape=(200, 200), background=0.1)

    def mix(cover):
        return 0.1 + cover * (0.9 - 0.1)

    assert scene.image[100, 59] == pytest.approx(0.1, abs=1e-7)
    assert scene.image[100, 60] == pytest.approx(mix(0.25), abs=1e-6)
    assert scene.image[100, 140] == pytest.approx(mix(0.75), abs=1e-6)
    assert scene.image[100, 141] == pytest.approx(0.1, abs=1e-7)
    assert scene.image[50, 100] == pytest.approx(0.1, abs=1e-7)
    assert scene.image[51, 100] == pytest.approx(0.9, abs=1e-6)
    assert scene.image[150, 100] == pytest.approx(0.9, abs=1e-6)
    assert scene.image[151, 100] == pytest.approx(0.1, abs=1e-7)
    # Corner pixel (row 50.5 border, x 60.25): no coverage; row 51 gets the quarter column.
    assert scene.image[51, 60] == pytest.approx(mix(0.25), abs=1e-6)


def test_antialiased_image_integrates_to_the_polygon_area():
    triangle = np.array([[30.3, 20.7], [170.9, 60.2], [80.4, 175.1]])
    scene = occlusion_scene([triangle], [1.0], shape=(200, 200), background=0.0)
    x, y = triangle[:, 0], triangle[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    assert scene.image.astype(float).sum() == pytest.approx(area, rel=2e-3)


def test_noise_is_gaussian_seeded_and_not_clipped():
    def make(**noise):
        return occlusion_scene([square(20, 20, 60, 60)], [0.9], shape=(128, 128), background=0.1, **noise)

    clean, noisy, again = make(), make(noise=0.2, seed=3), make(noise=0.2, seed=3)
    residual = noisy.image.astype(float) - clean.image
    assert np.array_equal(noisy.image, again.image)
    assert residual.mean() == pytest.approx(0.0, abs=0.01) and residual.std() == pytest.approx(0.2, rel=0.03)
    assert noisy.image.min() < 0.0 and noisy.image.max() > 1.0
    assert np.array_equal(noisy.regions, clean.regions) and noisy.junctions == clean.junctions


# ---------------------------------------------------------------------------------- hand-built junctions


def test_outside_is_the_border_strip_without_known_junctions():
    scene = occlusion_scene([square(40, 40, 120, 120)], [0.5], shape=(200, 100), margin=8)
    assert scene.margin == 8
    points = np.array([[7.9, 50], [8, 50], [91, 50], [91.1, 50], [50, 7.5], [50, 191], [50, 191.5], [50, 100]])
    np.testing.assert_array_equal(scene.outside(points), [True, False, False, True, True, False, True, False])
    assert all(not scene.outside(np.array([[j.x, j.y]]))[0] for j in scene.junctions)
    assert scene.outside(np.zeros((0, 2))).shape == (0,)
    with pytest.raises(ValueError, match="points"):
        scene.outside(np.zeros((3, 3)))


def test_square_behind_square_gives_two_t_junctions_and_visible_corners():
    back, front = square(40, 40, 120, 120), square(80, 80, 160, 160)
    scene = occlusion_scene([back, front], [0.2, 0.8], shape=(200, 200))
    assert isinstance(scene, OcclusionScene)
    ts = scene.t_junctions()
    assert [(j.x, j.y) for j in ts] == [(120.0, 80.0), (80.0, 120.0)]
    right, bottom = ts
    # Back square edges: 0 top, 1 right (x = 120), 2 bottom (y = 120), 3 left.
    assert (right.occluder, right.occluded, right.edge) == (1, 0, 1)
    assert (bottom.occluder, bottom.occluded, bottom.edge) == (1, 0, 2)
    assert right.arms == pytest.approx((-PI, -PI / 2, 0.0), abs=1e-12)  # bar left-right, stem up
    assert bottom.arms == pytest.approx((-PI, -PI / 2, PI / 2), abs=1e-12)  # bar up-down, stem left
    corners = {(j.x, j.y) for j in scene.junctions if j.kind == "L"}
    # (120, 120) is under the front square.
    assert corners == {(40.0, 40.0), (120.0, 40.0), (40.0, 120.0), (80.0, 80.0), (160.0, 80.0),
                       (160.0, 160.0), (80.0, 160.0)}
    assert all((j.occluder, j.occluded, j.edge) == (-1, -1, -1) for j in scene.junctions if j.kind == "L")
    assert find(scene, 80, 80).arms == pytest.approx((0.0, PI / 2), abs=1e-12)
    assert find(scene, 160, 80).arms == pytest.approx((-PI, PI / 2), abs=1e-12)
    assert len(scene.junctions) == 9
    assert [(j.y, j.x) for j in scene.junctions] == sorted((j.y, j.x) for j in scene.junctions)
    # Each T cuts a different edge and the hidden stretches end at a hidden corner: no pairs.
    assert scene.t_pairs() == []


def test_bar_across_a_rectangle_gives_four_t_junctions_in_two_pairs():
    rect, band = square(60, 30, 100, 170), square(20, 80, 180, 120)
    scene = occlusion_scene([rect, band], [0.3, 0.7], shape=(200, 200), background=0.1)
    ts = scene.t_junctions()
    assert sorted((j.x, j.y) for j in ts) == [(60.0, 80.0), (60.0, 120.0), (100.0, 80.0), (100.0, 120.0)]
    for j in ts:
        # Rectangle edges: 1 is x = 100, 3 is x = 60.
        assert (j.occluder, j.occluded, j.edge) == (1, 0, 1 if j.x == 100 else 3)
        stem = -PI / 2 if j.y == 80 else PI / 2
        assert sorted(j.arms) == list(j.arms) and stem in j.arms
        assert sorted(j.arms) == pytest.approx(sorted([-PI, 0.0, stem]), abs=1e-12)
    pairs = scene.t_pairs()
    located = sorted(tuple(sorted((scene.junctions[i].x, scene.junctions[i].y) for i in pair))
                     for pair in pairs)
    assert located == [((60.0, 80.0), (60.0, 120.0)), ((100.0, 80.0), (100.0, 120.0))]
    assert all(i < k for i, k in pairs)
    assert sum(j.kind == "L" for j in scene.junctions) == 8 and len(scene.junctions) == 12


def test_a_pair_needs_both_ends_visible():
    rect, band, patch = square(60, 30, 100, 170), square(20, 80, 180, 120), square(50, 70, 70, 90)
    scene = occlusion_scene([rect, band, patch], [0.3, 0.7, 0.5], shape=(200, 200), background=0.1)
    assert all((j.x, j.y) != (60.0, 80.0) for j in scene.junctions)  # under the patch
    pairs = scene.t_pairs()
    # The rectangle's left edge reappears below the band but its upper cut is hidden: no pair there. The
    # patch cuts the band's top edge (edge 0) twice, both ends visible: a pair.
    assert [sorted((scene.junctions[i].x, scene.junctions[i].y) for i in pair) for pair in pairs] == \
        [[(50.0, 80.0), (70.0, 80.0)], [(100.0, 80.0), (100.0, 120.0)]]
    for x, y, roles in ((50, 80, (2, 1, 0)), (70, 80, (2, 1, 0)), (60, 70, (2, 0, 3))):
        j = find(scene, x, y)
        assert (j.kind, j.occluder, j.occluded, j.edge) == ("T", *roles)
    # The patch's bottom edge crosses the rectangle's edge where the band hides both: no junction.
    assert all((j.x, j.y) != (60.0, 90.0) for j in scene.junctions)


def test_a_concave_occluder_cuts_one_edge_into_two_pairs():
    back = square(20, 60, 180, 140)  # edge 0: the top, y = 60
    u_shape = np.array([[40, 40], [80, 40], [80, 100], [120, 100], [120, 40], [160, 40], [160, 120],
                        [40, 120]], float)
    scene = occlusion_scene([back, u_shape], [0.3, 0.7], shape=(200, 200), background=0.1)
    ts = scene.t_junctions()
    assert sorted((j.x, j.y) for j in ts) == [(40.0, 60.0), (80.0, 60.0), (120.0, 60.0), (160.0, 60.0)]
    assert all((j.occluder, j.occluded, j.edge) == (1, 0, 0) for j in ts)
    # One group of four T's, but the edge shows between the prongs: the pairs enclose the hidden parts.
    located = [sorted((scene.junctions[i].x, scene.junctions[i].y) for i in pair) for pair in scene.t_pairs()]
    assert sorted(located) == [[(40.0, 60.0), (80.0, 60.0)], [(120.0, 60.0), (160.0, 60.0)]]
    for x in (80.0, 120.0):  # reflex corners are L's too
        j = find(scene, x, 100.0)
        assert j.kind == "L"
        assert j.arms == pytest.approx(sorted([-PI / 2, 0.0 if x == 80 else -PI]), abs=1e-12)


def test_oblique_t_junction_is_exact():
    back = np.array([[30.0, 150.0], [150.0, 30.0], [170.0, 170.0]])  # hypotenuse y = 180 - x
    front = square(0, 100, 200, 200)
    scene = occlusion_scene([back, front], [0.2, 0.8], shape=(200, 200), margin=0)
    j = find(scene, 80.0, 100.0)
    assert (j.kind, j.occluder, j.occluded, j.edge) == ("T", 1, 0, 0)
    assert j.arms == pytest.approx(sorted([-PI, 0.0, math.atan2(-1, 1)]), abs=1e-12)


def test_general_classifier_y_arrow_and_x():
    centre = (100.0, 100.0)
    y_scene = occlusion_scene([wedge(centre, -90, 30), wedge(centre, 30, 150), wedge(centre, 150, 270)],
                              [0.2, 0.5, 0.8], shape=(200, 200), background=0.95)
    j = find(y_scene, *centre)
    assert j.kind == "Y" and (j.occluder, j.occluded, j.edge) == (-1, -1, -1)
    assert j.arms == pytest.approx((-PI / 2, PI / 6, 5 * PI / 6), abs=1e-9)
    # Outer corners shared by two wedges: arms 30, 30 and 300 degrees apart.
    tip = find(y_scene, 100.0, 50.0, tol=1e-6)
    assert tip.kind == "arrow" and len(tip.arms) == 3
    x_scene = occlusion_scene([wedge(centre, 0, 90), wedge(centre, 180, 270)], [0.3, 0.7], shape=(200, 200),
                              background=0.95)
    j = find(x_scene, *centre)
    assert j.kind == "X" and j.arms == pytest.approx((-PI, -PI / 2, 0.0, PI / 2), abs=1e-9)


def test_straight_vertices_hidden_vertices_and_invisible_boundaries_are_no_junctions():
    pentagon = np.array([[40, 40], [100, 40], [160, 40], [160, 160], [40, 160]], float)  # (100, 40): straight
    straight = occlusion_scene([pentagon], [0.8], shape=(200, 200))
    corners = {(40.0, 40.0), (160.0, 40.0), (160.0, 160.0), (40.0, 160.0)}
    assert {(j.x, j.y) for j in straight.junctions} == corners
    hidden = occlusion_scene([square(80, 80, 100, 100), square(40, 40, 160, 160)], [0.2, 0.8],
                             shape=(200, 200))
    assert {(j.x, j.y) for j in hidden.junctions} == corners
    # Equal greys: the boundary between the squares is invisible, so its junctions go.
    same = occlusion_scene([square(40, 40, 120, 120), square(80, 80, 160, 160)], [0.8, 0.8], shape=(200, 200),
                           background=0.2)
    assert same.t_junctions() == () and all((j.x, j.y) != (80.0, 80.0) for j in same.junctions)
    assert {(j.x, j.y) for j in same.junctions} == {(40.0, 40.0), (120.0, 40.0), (40.0, 120.0), (160.0, 80.0),
                                                     (160.0, 160.0), (80.0, 160.0)}


def test_margin_drops_junctions_near_the_border():
    scene = occlusion_scene([square(5, 5, 150, 150)], [0.8], shape=(200, 200), margin=8)
    assert {(j.x, j.y) for j in scene.junctions} == {(150.0, 150.0)}
    assert len(occlusion_scene([square(5, 5, 150, 150)], [0.8], shape=(200, 200), margin=0).junctions) == 4
    assert len(occlusion_scene([square(5, 5, 150, 150)], [0.8], shape=(200, 200), margin=5).junctions) == 4
    assert occlusion_scene([square(5, 5, 150, 150)], [0.8], shape=(200, 200), margin=49.5).junctions == ()


# ----------------------------------------------------------------------------- random scenes, checked


@pytest.mark.parametrize("seed,count", [(0, 6), (1, 6), (2, 8), (3, 7), (4, 3)])
def test_every_junction_separates_regions(seed, count):
    scene = render_occlusion((160, 160), polygons=count, seed=seed)
    assert scene.junctions
    for j in scene.junctions:
        assert isinstance(j, Junction) and j.kind in occlusion.KINDS
        assert 8 <= j.x <= 151 and 8 <= j.y <= 151
        assert len(np.unique(ring(scene, j.x, j.y, 2.0))) >= 2
        theta = 0.1 + np.arange(72) * 2 * PI / 72
        rows = np.round(j.y + 2 * np.sin(theta)).astype(int)
        rounded = scene.regions[rows, np.round(j.x + 2 * np.cos(theta)).astype(int)]
        assert len(np.unique(rounded)) >= 2
        assert list(j.arms) == sorted(j.arms) and all(-PI <= a < PI for a in j.arms)


@pytest.mark.parametrize("seed,count", [(0, 6), (1, 6), (2, 8), (5, 6), (7, 4), (8, 8)])
def test_junctions_match_an_independent_brute_force(seed, count):
    """Every visible crossing of two edges of different polygons is a T (occluder the nearer polygon),
    every visible non-straight vertex an L, and nothing else (random scenes are in general position)."""
    h, w, margin = 180, 200, 8
    scene = render_occlusion((h, w), polygons=count, seed=seed)
    expected_t, expected_l = {}, set()
    for p, vp in enumerate(scene.polygons):
        for k in range(len(vp)):
            x, y = vp[k]
            if (margin <= x <= w - 1 - margin and margin <= y <= h - 1 - margin
                    and len(np.unique(ring(scene, x, y, 0.01))) >= 2
                    and abs(interior_angle(vp, k) - 180) > 10):
                expected_l.add((round(x, 6), round(y, 6)))
        for q in range(p + 1, len(scene.polygons)):
            vq = scene.polygons[q]
            for i in range(len(vp)):
                a, b = vp[i], vp[(i + 1) % len(vp)]
                for k in range(len(vq)):
                    c, d = vq[k], vq[(k + 1) % len(vq)]
                    m = np.array([b - a, c - d]).T
                    if abs(np.linalg.det(m)) < 1e-9:
                        continue
                    t, u = np.linalg.solve(m, c - a)
                    if not (0 < t < 1 and 0 < u < 1):
                        continue
                    x, y = a + t * (b - a)
                    if (margin <= x <= w - 1 - margin and margin <= y <= h - 1 - margin
                            and len(np.unique(ring(scene, x, y, 0.01))) == 3):
                        expected_t[(round(x, 6), round(y, 6))] = (q, p, i)
    got_t = {(round(j.x, 6), round(j.y, 6)): (j.occluder, j.occluded, j.edge) for j in scene.t_junctions()}
    got_l = {(round(j.x, 6), round(j.y, 6)) for j in scene.junctions if j.kind == "L"}
    assert got_t == expected_t and expected_t
    assert got_l == expected_l
    assert len(scene.junctions) == len(got_t) + len(got_l)


@pytest.mark.parametrize("seed", range(6))
def test_t_pairs_are_the_two_ends_of_one_hidden_stretch(seed):
    scene = render_occlusion((200, 200), polygons=6, seed=seed)
    used = set()
    for i, k in scene.t_pairs():
        a, b = scene.junctions[i], scene.junctions[k]
        assert i < k and a.kind == b.kind == "T"
        assert (a.occluder, a.occluded, a.edge) == (b.occluder, b.occluded, b.edge)
        assert not used & {i, k}
        used |= {i, k}
        # Between them the edge is hidden by the occluder; both lie on the occluded edge's line.
        vertices = scene.polygons[a.occluded]
        p, q = vertices[a.edge], vertices[(a.edge + 1) % len(vertices)]
        for j in (a, b):
            d, e = q - p, np.array([j.x, j.y]) - p
            assert abs(d[0] * e[1] - d[1] * e[0]) / np.linalg.norm(q - p) < 1e-8
        middle = np.array([[(a.x + b.x) / 2, (a.y + b.y) / 2]])
        assert points_in_poly(middle, scene.polygons[a.occluder])[0]


def test_t_pairs_occur_in_random_scenes():
    assert sum(len(render_occlusion((200, 200), polygons=6, seed=s).t_pairs()) for s in range(6)) >= 2


def test_scene_is_read_only():
    scene = render_occlusion((64, 64), polygons=3, seed=0)
    with pytest.raises(ValueError):
        scene.image[0, 0] = 1.0
    with pytest.raises(ValueError):
        scene.polygons[0][0, 0] = 1.0


# ------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("kwargs,error,name", [
    ({"shape": (8, 64)}, ValueError, "shape"),
    ({"shape": (64,)}, TypeError, "shape"),
    ({"shape": "64x64"}, TypeError, "shape"),
    ({"shape": (64.0, 64)}, TypeError, "shape"),
    ({"polygons": 0}, ValueError, "polygons"),
    ({"polygons": 9}, ValueError, "polygons"),
    ({"polygons": 2.5}, TypeError, "polygons"),
    ({"seed": -1}, ValueError, "seed"),
    ({"seed": 1.5}, TypeError, "seed"),
    ({"noise": -0.1}, ValueError, "noise"),
    ({"noise": float("nan")}, ValueError, "noise"),
    ({"noise": float("inf")}, ValueError, "noise"),
    ({"noise": "0.1"}, TypeError, "noise"),
    ({"margin": -1}, ValueError, "margin"),
    ({"antialias": 1}, TypeError, "antialias"),
])
def test_render_occlusion_refuses_bad_arguments(kwargs, error, name):
    with pytest.raises(error, match=name) as caught:
        render_occlusion(**kwargs)
    assert isinstance(caught.value, (InputValueError, InputTypeError))


@pytest.mark.parametrize("polygons,greys,kwargs,error,name", [
    ([np.zeros((3, 3))], [0.5], {}, ValueError, r"polygons\[0\]"),
    ([square(10, 10, 50, 50), np.array([[0.0, 0.0], [1.0, 1.0]])], [0.5, 0.6], {}, ValueError,
     r"polygons\[1\]"),
    ([np.array([[0.0, 0.0], [10.0, np.nan], [0.0, 10.0]])], [0.5], {}, ValueError, r"polygons\[0\]"),
    ([np.array([[0.0, 0.0], [10.0, 10.0], [20.0, 20.0]])], [0.5], {}, ValueError, r"polygons\[0\]"),
    ([np.array([["a", "b"], ["c", "d"], ["e", "f"]])], [0.5], {}, TypeError, r"polygons\[0\]"),
    ([[[0, 0], [10, 0, 3], [0, 10]]], [0.5], {}, ValueError, r"polygons\[0\]"),
    ("abc", [0.5], {}, TypeError, "polygons"),
    (None, [0.5], {}, TypeError, "polygons"),
    ([square(10, 10, 50, 50)], [0.5, 0.6], {}, ValueError, "greys"),
    ([square(10, 10, 50, 50)], [1.5], {}, ValueError, r"greys\[0\]"),
    ([square(10, 10, 50, 50)], 0.5, {}, TypeError, "greys"),
    ([square(10, 10, 50, 50)], [0.5], {"background": 2.0}, ValueError, "background"),
    ([square(10, 10, 50, 50)], [0.5], {"shape": (15, 64)}, ValueError, "shape"),
    ([square(10, 10, 50, 50)], [0.5], {"margin": float("nan")}, ValueError, "margin"),
])
def test_occlusion_scene_refuses_bad_arguments(polygons, greys, kwargs, error, name):
    kwargs = {"shape": (64, 64), **kwargs}
    with pytest.raises(error, match=name):
        occlusion_scene(polygons, greys, **kwargs)
