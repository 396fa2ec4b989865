"""The probability of boundary: its colour space, filter bank and gradients against NumPy oracles, what a
probability must do (bounds, monotone in contrast, thin), the shipped model, and the fit's refusal of the
test images."""

import importlib.util
import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from skimage import color

import vmcl
from tests import oracles
from vmcl.early import boundary_probability as bp

FIT_SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "boundary_fit.py"


def _smooth_rgb(seed=0, shape=(40, 56)):
    rng = np.random.default_rng(seed)
    noise = rng.random(shape + (3,))
    return np.clip(oracles._smoothed(noise[..., 0], 1.5)[..., None] * 0.5 + noise * 0.5, 0, 1).astype(np.float32)


def _lab_oracle(rgb):
    return np.moveaxis(color.rgb2lab(rgb.astype(np.float64)), -1, 0) / 100.0


def test_filter_bank_on_the_lightness_matches_the_oracle():
    rgb = _smooth_rgb()
    model = bp.BoundaryModel.load()
    found = bp.oriented_gradients(rgb, model=model)
    assert found.shape == (bp.ORIENTATIONS, 40, 56, len(model.features))
    # The bank rests on L* alone, so this also checks the colour space against scikit-image's rgb2lab.
    responses = bp.bank_responses(rgb)
    expected = oracles.texton_bank(_lab_oracle(rgb)[0])
    np.testing.assert_allclose(responses, expected, atol=2e-4)
    # One pixel per work-item (VEC = 1, as on a GPU), forced here (on a CPU the 56 columns are three chunks
    # of 16 and a partial one).
    scalar = vmcl.Machine()
    scalar.vector_width = 1
    np.testing.assert_allclose(bp.bank_responses(rgb, machine=scalar), expected, atol=2e-4)


def _small_scales_model():
    """The shipped textons at scales whose texture smoothing is partly exact (step 1) and partly sampled."""
    shipped = bp.BoundaryModel.load()
    scales = (0.75, 3.0)
    assert [bp.sample_step(bp.TEXTURE_RATIO * s) for s in scales] == [1, 6]
    return bp.BoundaryModel(scales, shipped.centres, np.zeros(1 + len(bp.feature_names(scales)), np.float32))


@pytest.mark.parametrize("small_scales", [False, True])
def test_oriented_gradients_match_the_oracle(small_scales):
    rgb = _smooth_rgb(1)
    model = _small_scales_model() if small_scales else bp.BoundaryModel.load()
    found = bp.oriented_gradients(rgb, model=model)
    lab = _lab_oracle(rgb)
    responses = oracles.texton_bank(lab[0])
    distances = ((responses[..., None, :] - model.centres[None, None].astype(np.float64)) ** 2).sum(-1)
    labels = distances.argmin(-1)
    expected = oracles.oriented_gradients(lab, labels, len(model.centres), model.scales)
    # A pixel whose two nearest textons are within rounding of each other may take either.
    ordered = np.sort(distances, axis=-1)
    assert (ordered[..., 1] - ordered[..., 0] > 1e-4).mean() > 0.99
    close = np.isclose(found, expected, atol=2e-4, rtol=1e-3)
    assert close.mean() > 0.995, f"{(~close).sum()} of {close.size} features differ"


def test_sampled_smoothings_stay_near_the_exact_gaussian():
    """The wide smoothings (textons' histograms and their tensors on a grid of every sample_step-th pixel,
    the surround at every sample_step-th row) stay near the exact Gaussians' features: on average within 4%
    of each feature's range, and within 8% two samples of the widest step or more inside the image."""
    model = bp.BoundaryModel.load()
    # One sample per sigma: the step is the width's whole pixels (the oracle reads sample_step too).
    assert [bp.sample_step(sigma) for sigma in (0.5, 1.9, 3.0, 10.0, 12.0)] == [1, 1, 3, 10, 12]
    steps = [bp.sample_step(bp.TEXTURE_RATIO * s) for s in model.scales] + [bp.sample_step(bp.SURROUND_SIGMA)]
    margin = 2 * max(steps)
    rgb = _smooth_rgb(2, shape=(96, 128))
    found = bp.oriented_gradients(rgb, model=model)
    lab = _lab_oracle(rgb)
    responses = oracles.texton_bank(lab[0])
    labels = ((responses[..., None, :] - model.centres[None, None].astype(np.float64)) ** 2).sum(-1).argmin(-1)
    exact = oracles.oriented_gradients(lab, labels, len(model.centres), model.scales, sampled=False)
    for j, name in enumerate(model.features):
        error = np.abs(found[..., j] - exact[..., j]) / np.abs(exact[..., j]).max()
        assert error.mean() <= 0.04, name  # measured at most 2.1% (1 sample per sigma)
        assert error[:, margin:-margin, margin:-margin].max() <= 0.08, name  # measured at most 5.0%


def test_a_grey_image_has_no_colour_gradient():
    step = np.zeros((32, 32), np.float32)
    step[:, 16:] = 0.5
    found = bp.oriented_gradients(step)
    names = bp.BoundaryModel.load().features
    colour = [j for j, name in enumerate(names) if name.split()[-2] in ("a", "b")]
    assert colour and np.all(found[..., colour] == 0)
    lightness = names.index("L 1.5")
    assert found[0, 16, 15, lightness] > 0.05  # across the step (normal along x) ...
    assert found[4, 16, 15, lightness] < 1e-6  # ... and nothing along it


def test_probability_is_bounded_thin_and_monotone_in_contrast():
    peaks = []
    for contrast in (0.02, 0.05, 0.1, 0.2, 0.4):
        step = np.full((48, 48), 0.3, np.float32)
        step[:, 24:] += contrast
        found = bp.boundary_probability(step)
        for field in (found.probability, found.dense):
            assert field.dtype == np.float32 and field.min() >= 0 and field.max() <= 1
        row = found.probability[24]
        assert np.argmax(row) in (23, 24)
        # Thin: beside the step's contour, nothing survives suppression.
        assert row[21] == 0 and row[26] == 0
        assert abs(found.orientation[24, 23]) < 1e-6  # the normal points along x
        peaks.append(float(row.max()))
    assert all(b > a for a, b in itertools.pairwise(peaks)), peaks
    assert peaks[-1] > 0.7 and peaks[0] < 0.5


def test_orientation_is_the_winning_normal_angle():
    # A step across rows has its normal along y: pi / 2. Every pixel's angle is one of the eight o pi / 8.
    step = np.full((48, 48), 0.3, np.float32)
    step[24:] += 0.4
    found = bp.boundary_probability(step)
    assert found.orientation.dtype == np.float32
    column = found.probability[:, 24]
    assert np.argmax(column) in (23, 24)
    assert found.orientation[np.argmax(column), 24] == pytest.approx(np.pi / 2, abs=1e-6)
    steps = found.orientation / np.float32(np.pi / bp.ORIENTATIONS)
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-5)
    assert steps.min() >= 0 and steps.max() <= bp.ORIENTATIONS - 1


def test_device_in_device_out(machine):
    rgb = _smooth_rgb(2)
    host = bp.boundary_probability(rgb, machine=machine)
    device = bp.boundary_probability(machine.to_device(rgb), machine=machine)
    assert not isinstance(device.probability, np.ndarray)
    np.testing.assert_array_equal(device.probability.get(), host.probability)


def test_model_round_trip_and_refusals(tmp_path):
    model = bp.BoundaryModel.load()
    assert "BSDS500 train" in model.fitted_on and model.features == bp.FEATURES
    assert model.record["images"] == 190 and len(model.record["data_sha256"]) == 64  # checked as it loaded
    model.save(tmp_path / "m.json")
    again = bp.BoundaryModel.load(tmp_path / "m.json")
    np.testing.assert_allclose(again.weights, model.weights, atol=1e-5)
    edited = json.loads((tmp_path / "m.json").read_text())
    edited["weights"][0] += 0.5
    (tmp_path / "m.json").write_text(json.dumps(edited))
    with pytest.raises(ValueError, match="differ from those fitted"):
        bp.BoundaryModel.load(tmp_path / "m.json")
    (tmp_path / "notes.json").write_text("{}")
    with pytest.raises(ValueError, match="not a file `vmcl fit` wrote"):
        model.save(tmp_path / "notes.json")
    assert (tmp_path / "notes.json").read_text() == "{}"
    (tmp_path / "bad.json").write_text(json.dumps({"scales": [1.0]}))
    with pytest.raises(ValueError, match="bad.json"):
        bp.BoundaryModel.load(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="weights"):
        bp.BoundaryModel((1.0,), model.centres, np.zeros(3, np.float32))
    with pytest.raises(TypeError, match="model"):
        bp.boundary_probability(np.zeros((8, 8), np.float32), model="shipped")
    with pytest.raises(ValueError, match="image"):
        bp.boundary_probability(np.zeros((8, 8, 4), np.float32))


@pytest.mark.parametrize("call", [bp.boundary_probability, bp.oriented_gradients, bp.bank_responses])
def test_a_float_image_off_the_unit_scale_is_refused(call, machine):
    """Float images hold brightness in [0, 1] (sRGB): one in 0..255 was taken and read as another image."""
    with pytest.raises(ValueError, match="image: float images hold brightness in"):
        call(255 * _smooth_rgb(1), machine=machine)


def test_a_flat_image_has_no_gradient_even_at_its_borders():
    found = bp.oriented_gradients(np.full((24, 40), 0.25, np.float32))
    assert np.all(found == 0)


def test_thinning_leaves_a_flat_image_empty_and_a_wide_ridge_one_pixel_wide():
    # Equal neighbours along the normal both survived: a flat image's floor probability (0.001) stayed at every
    # pixel, so the soft map called the whole of a blank frame boundary at any threshold below it.
    flat = bp.boundary_probability(np.full((40, 40), 0.5, np.float32))
    assert not flat.probability.any()
    step = np.full((40, 40), 0.3, np.float32)
    step[:, 20:] = 0.7
    thin = bp.boundary_probability(step).probability
    assert all(np.count_nonzero(row > 0.1) == 1 for row in thin[5:35])


def test_the_fit_refuses_the_test_split():
    spec = importlib.util.spec_from_file_location("boundary_fit", FIT_SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    with pytest.raises(SystemExit, match="train split only"):
        module.training_images(Path("/nonexistent"), "test")


def test_a_map_builds_two_programs_of_its_file(monkeypatch):
    # Every kernel but lab takes the model's one define set (its groups read only their own defines), so a
    # first run builds the file twice, not once per kernel group; the map is the same either way (above).
    built = set()
    real = vmcl.Machine.program

    def program(self, family, **defines):
        if family == "boundary_probability":
            built.add(tuple(sorted(defines.items())))
        return real(self, family, **defines)

    monkeypatch.setattr(vmcl.Machine, "program", program)
    bp.boundary_probability(_smooth_rgb(3), machine=vmcl.Machine())
    assert len(built) == 2, built
