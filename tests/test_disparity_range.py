"""The disparity range found from the images: it holds the true range on rendered pairs with near objects,
the machine matches over it when the Config gives none and says so, and bad pairs are refused."""

import math

import numpy as np
import pytest

from vmcl import metrics, scenes
from vmcl.early.disparity_range import DisparityRange, estimate_range, fallback_range
from vmcl.errors import InputTypeError, InputValueError
from vmcl.pipeline import Config, VisionMachine
from vmcl.scenes import Body, Camera, Face, Light, Texture, World

SHAPE = (128, 192)


def _near_scene(plate_depth: float) -> scenes.Scene:
    """A dotted wall at depth 6 (d = 0.025 W) and a dotted plate in front of it at ``plate_depth`` (0.5:
    d = 0.3 W), seen by the presets' rig (focal length W, baseline 0.15); ambient light only."""
    focal = float(SHAPE[1])

    def dots(depth):
        return Texture("noise", 5 * depth / focal, 0.5)

    wall = Face((0.0, 0.0, 6.0), (1, 0, 0), (0, 1, 0), None, (0.6, 0.55, 0.5), dots(6.0))
    plate = Face((0.05, -0.15 * plate_depth, plate_depth), (1, 0, 0), (0, 1, 0),
                 (0.25 * plate_depth, 0.3 * plate_depth), (0.7, 0.5, 0.4), dots(plate_depth))
    world = World(Camera(SHAPE, focal, 0.15), Light(ambient=1.0), (Body((wall,)), Body((plate,))))
    return scenes.render(world, seed=0, noise=0.01)


def _visible(scene):
    return ~scene.occluded_stereo & np.isfinite(scene.disparity)


@pytest.fixture(scope="module")
def near_scene():
    return _near_scene(0.5)


@pytest.mark.parametrize("plate_depth", [0.5, 0.8])
def test_range_holds_the_visible_disparities_and_little_more(plate_depth, machine):
    scene = _near_scene(plate_depth)
    truth = scene.disparity[_visible(scene)]
    low, high = math.floor(truth.min()), math.ceil(truth.max())
    assert high > 0.18 * SHAPE[1]  # far beyond the old default of 5% of the width
    found = estimate_range(scene.left, scene.right, machine=machine)
    assert found.decided and found.confident > 0.3
    assert found.d_min <= low and found.d_max >= high
    # The margin is one pixel of the finest level searched (2 px here), the quantiles a few more, and the
    # range is widened by a quarter of its width on each side.
    allowance = 5 + math.ceil(0.25 * (high - low + 10))
    assert found.d_min >= low - allowance and found.d_max <= high + allowance


def test_negative_disparities_are_found(near_scene, machine):
    """Swapping the views negates every disparity: the estimate follows, below zero."""
    truth = near_scene.disparity[_visible(near_scene)]
    found = estimate_range(near_scene.right, near_scene.left, machine=machine)
    assert found.decided
    assert found.d_min <= -math.ceil(truth.max()) and found.d_max >= -math.floor(truth.min())
    assert found.found is not None and found.found[1] < 0  # before the margins: every match negative


def test_device_images_give_the_host_result(near_scene, machine):
    host = estimate_range(near_scene.left, near_scene.right, machine=machine)
    device = estimate_range(machine.to_device(near_scene.left), machine.to_device(near_scene.right),
                            machine=machine)
    assert host == device


@pytest.mark.parametrize("plate_depth", [0.5, 0.375])
def test_restored_disparity_with_the_range_found_is_as_good_as_with_the_true_range(plate_depth, machine):
    """Disparities from 0.025 W to 0.3 W (plate at 0.5) and to 0.4 W (plate at 0.375): no range given, the
    restored disparity is within a point of bad-1 of the run given the true range."""
    near_scene = _near_scene(plate_depth)
    visible = _visible(near_scene)
    truth = near_scene.disparity[visible]
    given = {"d_min": math.floor(truth.min()), "d_max": math.ceil(truth.max())}
    bad = {}
    for name, stereo in (("found", {}), ("true", given), ("old", {"d_min": 0, "d_max": math.ceil(0.05 * SHAPE[1])})):
        result = VisionMachine(Config.from_dict({"stereo": stereo}), machine=machine).run(near_scene.left,
                                                                                           near_scene.right)
        bad[name] = metrics.evaluate_disparity(result.disparity, near_scene.disparity, mask=visible).bad[1.0]
        notes = [n for n in result.notes if n.startswith("stereo: disparity range")]
        if name == "found":
            assert len(notes) == 1 and "from the images at 1/2 scale" in notes[0], result.notes
            assert result.half_occluded is not None and result.half_occluded.any()
        else:
            assert not notes  # the Config gave the range
    assert bad["found"] <= bad["true"] + 0.01, bad
    assert bad["old"] > bad["found"] + 0.1, bad  # what the range was for


def test_one_bound_given_overrides_its_end(near_scene, machine, monkeypatch):
    from vmcl.cues import stereo

    spans = []
    real = stereo.match_semiglobal

    def spy(*args, **kwargs):
        spans.append((kwargs["d_min"], kwargs["d_max"]))
        return real(*args, **kwargs)

    monkeypatch.setattr(stereo, "match_semiglobal", spy)
    config = Config.from_dict({"stereo": {"d_min": -3}, "mrf": {"method": "icm"}})
    result = VisionMachine(config, machine=machine).run(near_scene.left, near_scene.right)
    found = estimate_range(near_scene.left, near_scene.right, machine=machine)
    assert set(spans) == {(-3, found.d_max)}
    assert any(n.startswith(f"stereo: disparity range -3..{found.d_max} px") and "d_min = -3" in n
               for n in result.notes), result.notes
    assert not any("one disparity is searched" in n for n in result.notes)
    # A bound beyond the other end found leaves one disparity to search, which the note says.
    beyond = found.d_max + 5
    config = Config.from_dict({"stereo": {"d_min": beyond}, "mrf": {"method": "icm"}})
    result = VisionMachine(config, machine=machine).run(near_scene.left, near_scene.right)
    assert spans[-1] == (beyond, beyond)
    assert any(f"beyond the range {found.d_min}..{found.d_max} the images gave, so one disparity is searched" in n
               for n in result.notes), result.notes


def test_flat_images_do_not_decide_and_fall_back_with_a_note(machine):
    flat = np.full((64, 96), 0.5, np.float32)
    found = estimate_range(flat, flat, machine=machine)
    assert found == DisparityRange(*fallback_range(96), decided=False, level=found.level, confident=0.0,
                                   searched=found.searched, found=None)
    assert (found.d_min, found.d_max) == (0, 48)
    result = VisionMachine(machine=machine).run(flat, flat)
    assert any(n.startswith("stereo: disparity range 0..48 px, a wide fallback") for n in result.notes), result.notes


def test_tiny_images_are_matched_at_full_resolution_or_refused(machine):
    rng = np.random.default_rng(0)
    image = rng.random((16, 40), np.float32)
    found = estimate_range(image, np.roll(image, -3, axis=1), machine=machine)  # d = 3 everywhere
    assert found.level == 0 and found.decided and found.d_min <= 3 <= found.d_max
    with pytest.raises(InputValueError, match="patch .*or give the range: d_min and d_max"):
        estimate_range(image[:5], image[:5], machine=machine)


@pytest.mark.parametrize("left, right, error, name", [
    (np.zeros((64, 64)), np.zeros((64, 80)), InputValueError, "same shape"),
    (np.zeros((64, 64)), [[0.0]], InputTypeError, "right"),
    (np.zeros((64, 64, 4)), np.zeros((64, 64, 4)), InputValueError, "left"),
    (np.full((64, 64), np.nan), np.zeros((64, 64)), InputValueError, "left"),
])
def test_bad_pairs_are_refused_naming_the_argument(left, right, error, name, machine):
    with pytest.raises(error, match=name):
        estimate_range(left, right, machine=machine)


@pytest.mark.parametrize("key, value", [("max_disparity", 0.0), ("max_disparity", 1.5), ("coarse_side", 0),
                                        ("patch", 6), ("min_score", 2.0), ("quantile", 0.5), ("margin", -1),
                                        ("min_share", 0.0)])
def test_bad_options_are_refused_naming_them(key, value, machine):
    image = np.zeros((64, 64), np.float32)
    with pytest.raises((InputValueError, InputTypeError), match=key):
        estimate_range(image, image, machine=machine, **{key: value})


def test_a_wide_margin_is_cut_at_the_matcher_s_limits_never_past_what_was_found():
    rng = np.random.default_rng(0)
    left = rng.random((64, 96)).astype(np.float32)
    right = np.roll(left, -5, axis=1)
    found = estimate_range(left, right, margin=10**9)
    assert found.found == (5, 5) and found.d_min <= 5 <= found.d_max
    assert found.d_max - found.d_min <= 95


@pytest.mark.parametrize(("stereo", "name"), [({"d_min": 0, "d_max": SHAPE[1]}, "d_max"),
                                             ({"d_min": -SHAPE[1], "d_max": 4}, "d_min")])
def test_a_range_override_outside_the_image_is_refused(stereo, name, near_scene, machine):
    with pytest.raises(InputValueError, match=name):
        VisionMachine(Config.from_dict({"stereo": stereo}), machine=machine).run(near_scene.left, near_scene.right)


def test_a_pair_that_is_not_rectified_gets_a_note(near_scene, machine):
    """The right view turned by 10 degrees: most matches fail the left-right check, and the notes say the
    pair may not be rectified; the upright pair gets no such note."""
    import cv2

    height, width = SHAPE
    turn = cv2.getRotationMatrix2D((width / 2, height / 2), 10, 1.0)
    turned = cv2.warpAffine(near_scene.right, turn, (width, height), borderMode=cv2.BORDER_REFLECT)
    notes = {}
    for label, right in (("turned", turned), ("upright", near_scene.right)):
        result = VisionMachine(machine=machine).run(near_scene.left, right)
        notes[label] = [n for n in result.notes if "may not be rectified" in n]
    assert len(notes["turned"]) == 1 and not notes["upright"], notes


def test_a_range_too_narrow_is_reported(near_scene, machine):
    """Given 0..12 where the plate lies at 0.3 W (about 58 px), pixels that matched best at the range's end
    are marked in Result.out_of_range and the notes say so; with the range found from the images, neither."""
    narrow = VisionMachine(Config.from_dict({"stereo": {"d_min": 0, "d_max": 12}}), machine=machine).run(
        near_scene.left, near_scene.right)
    found = VisionMachine(machine=machine).run(near_scene.left, near_scene.right)
    visible = _visible(near_scene)
    plate, wall = visible & (near_scene.disparity > 12), visible & (near_scene.disparity <= 12)
    # Measured: 27% of the plate, 0.01% of the wall.
    assert narrow.out_of_range[plate].mean() > 0.2 and narrow.out_of_range[wall].mean() < 0.02
    assert any("at an end of the range 0..12 px" in n for n in narrow.notes), narrow.notes
    assert not any("end of the range" in n for n in found.notes), found.notes
    assert found.out_of_range.mean() < 0.01


def test_a_pair_given_in_the_other_order_gets_a_note(near_scene, machine):
    """Left and right swapped: every disparity is negative, and the range's note asks whether the views are
    in order; the pair in order gets no such note."""
    notes = {}
    for label, (left, right) in (("swapped", (near_scene.right, near_scene.left)),
                                 ("in order", (near_scene.left, near_scene.right))):
        result = VisionMachine(machine=machine).run(left, right)
        notes[label] = [n for n in result.notes if "given in the other order" in n]
    assert len(notes["swapped"]) == 1 and not notes["in order"], notes


def test_given_ends_take_the_place_of_the_found_ones_and_the_other_end_never_crosses():
    from vmcl.early.disparity_range import with_given_ends

    found = DisparityRange(5, 40, decided=True, level=2, confident=0.5, searched=(-100, 100), found=(8, 36))
    assert with_given_ends(found, None, None) == (5, 40)
    assert with_given_ends(found, 10, None) == (10, 40) and with_given_ends(found, 50, None) == (50, 50)
    assert with_given_ends(found, None, 30) == (5, 30) and with_given_ends(found, None, 2) == (2, 2)
    assert with_given_ends(found, 0, 60) == (0, 60)
