"""The MRF stage's data and confidence from measurements (vmcl.mrf.data) against NumPy."""

import numpy as np
import pyopencl.array as cl_array
import pytest

from vmcl.mrf import backfill, score_confidence


def ramp_oracle(score, floor, weight=1.0):
    return weight * np.nan_to_num(np.clip((score.astype(np.float64) - floor) / (1 - floor), 0, 1))


@pytest.fixture(scope="module")
def scores():
    rng = np.random.default_rng(3)
    score = rng.uniform(-0.5, 1.0, (37, 53)).astype(np.float32)
    score[rng.random(score.shape) < 0.2] = np.nan
    score[0, :4] = [0.7, 1.0, -1.0, 0.85]
    return score


@pytest.mark.parametrize("floor, weight", [(0.0, 1.0), (0.7, 1.0), (0.9, 0.2), (0.5, 0.0)])
def test_score_confidence_is_the_clamped_ramp(scores, machine, floor, weight):
    got = score_confidence(scores, floor=floor, weight=weight, machine=machine)
    assert got.dtype == np.float32 and got.shape == scores.shape
    np.testing.assert_allclose(got, ramp_oracle(scores, floor, weight), atol=1e-6)


def test_score_confidence_on_the_device_and_at_any_local_size(scores, machine, machine_with_local_size):
    expected = score_confidence(scores, floor=0.7, machine=machine)
    on_device = score_confidence(machine.to_device(scores), floor=0.7, machine=machine)
    assert isinstance(on_device, cl_array.Array)
    np.testing.assert_array_equal(on_device.get(), expected)
    np.testing.assert_array_equal(score_confidence(scores, floor=0.7, machine=machine_with_local_size), expected)


@pytest.mark.parametrize("components", [1, 2])
def test_backfill_keeps_the_primary_and_fills_its_gaps(machine, components):
    rng = np.random.default_rng(4)
    shape = (29, 31) + ((components,) if components > 1 else ())
    primary = rng.normal(size=shape).astype(np.float32)
    secondary = rng.normal(size=shape).astype(np.float32)
    gaps = rng.random((29, 31)) < 0.7
    primary[gaps] = np.nan
    if components > 1:  # one NaN component makes the whole pixel a gap
        primary[~gaps & (rng.random((29, 31)) < 0.1), 1] = np.nan
    secondary[rng.random(shape) < 0.1] = np.nan
    gamma2 = rng.random((29, 31)).astype(np.float32)
    gamma2[rng.random(gamma2.shape) < 0.05] = np.nan
    data, gamma = backfill(primary, secondary, gamma2, machine=machine)
    def measured(field):
        return np.isfinite(field).all(axis=-1) if components > 1 else np.isfinite(field)
    has, second_has = measured(primary), measured(secondary)
    where = has[..., None] if components > 1 else has
    np.testing.assert_array_equal(data, np.where(where, primary, secondary))
    fill = np.where(second_has & np.isfinite(gamma2), gamma2, np.float32(0))
    np.testing.assert_array_equal(gamma, np.where(has, np.float32(1), fill))
    device = backfill(machine.to_device(primary), secondary, gamma2, machine=machine)
    assert all(isinstance(a, cl_array.Array) for a in device)
    np.testing.assert_array_equal(device[0].get(), data)


def test_bad_input_names_the_argument(scores, machine):
    for floor, error in ((1.0, ValueError), (-0.1, ValueError), (float("nan"), ValueError), ("0.5", TypeError)):
        with pytest.raises(error, match="floor"):
            score_confidence(scores, floor=floor, machine=machine)
    with pytest.raises(ValueError, match="weight"):
        score_confidence(scores, floor=0.5, weight=1.5, machine=machine)
    with pytest.raises(TypeError, match="score"):
        score_confidence(np.zeros((2, 4), np.int32), floor=0.5, machine=machine)
    with pytest.raises(ValueError, match="score"):
        score_confidence(scores[0], floor=0.5, machine=machine)
    field = np.zeros((4, 5), np.float32)
    with pytest.raises(ValueError, match="secondary has shape"):
        backfill(field, field[:, :4], field, machine=machine)
    with pytest.raises(ValueError, match="secondary_confidence"):
        backfill(field, field, field[:3], machine=machine)
    with pytest.raises(TypeError, match="primary"):
        backfill(field.astype(np.float64), field, field, machine=machine)
