"""The variational refinement: a flow off by up to half a pixel brought to the true sub-pixel translation,
against brightness constancy and against gradient constancy alone (an exposure change), its energy lowered
(a NumPy oracle of the functional), the multigrid carrying the flow across a region without texture, pixels
without flow kept, the motion cue's use of it, and bad input refused naming it."""

import dataclasses

import cv2
import numpy as np
import pytest
from test_early_lucas_kanade import TRUE, rough_start, translated, translation_error

from vmcl.early.variational import ALPHA, DELTA, EPSILON, GAMMA, variational_refine
from vmcl.errors import InputTypeError, InputValueError
from vmcl.pipeline import ColourConfig, Config, MotionConfig, StereoConfig, TextureConfig, VisionMachine


def _psi(s):
    return np.sqrt(s + EPSILON ** 2)


def _energy(flow, frame0, frame1, alpha=ALPHA, delta=DELTA, gamma=GAMMA, margin=4):
    """The functional the refinement lowers, in NumPy (cv2's bilinear warp; central differences; the frames
    in grey levels of 255, as the refinement counts them), over the pixels ``margin`` from the border."""
    f0, f1 = (cv2.GaussianBlur(frame * np.float32(255), (0, 0), 1.0) for frame in (frame0, frame1))
    ys, xs = np.mgrid[0:f0.shape[0], 0:f0.shape[1]].astype(np.float32)
    warped = cv2.remap(f1, xs + flow[..., 0], ys + flow[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    gy0, gx0 = np.gradient(f0)
    gy1, gx1 = np.gradient(warped)
    data = delta * _psi((warped - f0) ** 2) + gamma * _psi((gx1 - gx0) ** 2 + (gy1 - gy0) ** 2)
    du = np.diff(flow, axis=1, append=flow[:, -1:])
    dv = np.diff(flow, axis=0, append=flow[-1:])
    smooth = alpha * _psi((du ** 2).sum(-1) + (dv ** 2).sum(-1))
    inner = (slice(margin, -margin), slice(margin, -margin))
    return float((data + smooth)[inner].sum())


def test_the_refinement_brings_a_rough_flow_to_the_true_translation_and_lowers_its_energy(machine):
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    assert (translation_error(start) > 0.2).all()
    found = variational_refine(start, frame0, frame1, iterations=10, machine=machine)
    assert (translation_error(found) < 0.06).all()
    assert _energy(found, frame0, frame1) < 0.5 * _energy(start, frame0, frame1)


def test_gradient_constancy_alone_holds_when_the_exposure_changes(machine):
    """Frame 1's levels raised to 1.15: brightness constancy fails, the gradient's constancy much less. Both
    run to convergence (40 iterations), so each error is its functional's optimum's."""
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    darker = frame1 ** 1.15
    brightness = variational_refine(start, frame0, darker, gamma=0.0, iterations=40, machine=machine)
    gradient = variational_refine(start, frame0, darker, delta=0.0, iterations=40, machine=machine)
    # measured 0.031 and 0.032 against 0.094 and 0.093
    assert (translation_error(gradient) < 0.5 * translation_error(brightness)).all()


def test_a_true_flow_stays_true(machine):
    frame0, frame1 = translated(seed=4)
    exact = np.broadcast_to(np.array(TRUE, np.float32), (*frame0.shape, 2)).copy()
    found = variational_refine(exact, frame0, frame1, machine=machine)
    # Frame 1 read bilinearly between its pixels is a little smoother than frame 0: the refinement's
    # optimum lies that far off (measured 0.043; the Lucas-Kanade steps' floor is the same, 0.039).
    assert (translation_error(found) < 0.06).all()


def test_the_multigrid_carries_the_flow_across_a_region_without_texture(machine):
    """A flat disk of radius 35 px in both frames: no data inside it, so its flow must come from the textured
    ring around it (the true translation), across up to 35 pixels. Relaxation on the pixel grid alone moves
    a correction about a pixel per sweep; the multigrid's coarser levels carry it across at once."""
    frame0, frame1 = translated()
    ys, xs = np.mgrid[0:frame0.shape[0], 0:frame0.shape[1]]
    frame0 = np.where((xs - 70) ** 2 + (ys - 60) ** 2 < 35 ** 2, 0.5, frame0).astype(np.float32)
    frame1 = np.where((xs - 70 - TRUE[0]) ** 2 + (ys - 60 - TRUE[1]) ** 2 < 35 ** 2, 0.5, frame1).astype(np.float32)
    start = rough_start(frame0.shape)
    inside = (xs - 70) ** 2 + (ys - 60) ** 2 < 25 ** 2

    def error(flow):
        return np.abs(flow[inside] - np.array(TRUE, np.float32)).mean(axis=0)

    assert (error(start) > 0.25).all()
    grid = variational_refine(start, frame0, frame1, iterations=5, machine=machine)
    pixels = variational_refine(start, frame0, frame1, iterations=5, levels=1, machine=machine)
    assert (error(grid) < 0.06).all()  # measured 0.029 and 0.039
    assert (error(pixels) > 0.2).all()  # measured 0.28 and 0.26


def test_the_multigrid_and_relaxation_on_the_pixel_grid_reach_the_same_solution(machine):
    """Odd sides at every level, pixels without flow in a block at the corner and inside: once both have
    converged, the multigrid's flow is relaxation's on the pixel grid alone (its oracle), which needs far more
    sweeps to get there."""
    frame0, frame1 = translated(shape=(37, 53), seed=6)
    start = rough_start(frame0.shape)
    start[33:, 49:] = np.nan
    start[10:14, 20:24] = np.nan
    found = variational_refine(start, frame0, frame1, iterations=60, machine=machine)
    oracle = variational_refine(start, frame0, frame1, iterations=60, levels=1, sweeps=30, machine=machine)
    known = np.isfinite(start).all(axis=-1)
    assert np.isnan(found[~known]).all()
    np.testing.assert_allclose(found[known], oracle[known], atol=1e-4)  # measured 8e-6
    # ... and it is not the start: after 5 iterations the multigrid is still 0.02 px away.
    assert np.abs(variational_refine(start, frame0, frame1, iterations=5, machine=machine)[known]
                  - oracle[known]).max() > 1e-3


def test_a_prior_pulls_the_flow_where_it_has_a_value(machine):
    """A prior 0.3 px off the truth over the right half of the frame, NaN (no pull) over the left: a heavy pull
    holds the right half at the prior; the left half's flow answers to its frames."""
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    prior = np.broadcast_to(np.array(TRUE, np.float32) + np.float32(0.3), start.shape).copy()
    prior[:, :70] = np.nan
    found = variational_refine(start, frame0, frame1, prior=prior, beta=1e4, machine=machine)
    truth = np.array(TRUE, np.float32)
    assert np.abs(found[20:100, 85:125] - truth).mean() == pytest.approx(0.3, abs=0.01)  # the prior's offset
    assert np.abs(found[20:100, 15:55] - truth).mean() < 0.06  # measured 0.038
    np.testing.assert_array_equal(variational_refine(start, frame0, frame1, prior=prior, beta=0.0, machine=machine),
                                  variational_refine(start, frame0, frame1, machine=machine))


def test_pixels_without_flow_keep_it_and_pass_nothing_on(machine):
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    start[60, 70] = np.nan
    start[10, 100] = (500.0, 0.0)  # carried out of frame 1: no data, its neighbours' flow
    found = variational_refine(start, frame0, frame1, iterations=10, machine=machine)
    assert np.isnan(found[60, 70]).all()
    assert np.isfinite(np.delete(found.reshape(-1, 2), 60 * 140 + 70, axis=0)).all()
    # No data where it points, so the smoothness alone gives it its neighbours' flow.
    assert np.abs(found[10, 100] - np.array(TRUE, np.float32)).max() < 0.2


def test_device_flow_gives_device_output_equal_to_host_and_leaves_the_input(machine):
    frame0, frame1 = translated(seed=2)
    start = rough_start(frame0.shape)
    host = variational_refine(start, frame0, frame1, machine=machine)
    device_start = machine.to_device(start)
    device = variational_refine(device_start, machine.to_device(frame0), machine.to_device(frame1), machine=machine)
    np.testing.assert_array_equal(device.get(), host)
    np.testing.assert_array_equal(device_start.get(), start)
    np.testing.assert_array_equal(variational_refine(start, frame0, frame1, iterations=0, machine=machine), start)
    as_bytes = variational_refine(start, np.round(frame0 * 255).astype(np.uint8),
                                  np.round(frame1 * 255).astype(np.uint8), machine=machine)
    as_float = variational_refine(start, np.round(frame0 * 255) / 255, np.round(frame1 * 255) / 255, machine=machine)
    # The robust weights, 1 / sqrt(r^2 + eps^2), magnify the last bits where a residual r nears 0.
    np.testing.assert_allclose(as_bytes, as_float, atol=0.01)


def test_the_motion_cue_takes_the_refinement(machine):
    frame0, frame1 = translated(shape=(96, 112), seed=3)
    off = {"stereo": StereoConfig(enabled=False), "colour": ColourConfig(enabled=False),
           "texture": TextureConfig(enabled=False)}
    motions = [dataclasses.replace(MotionConfig(), variational_iterations=n) for n in (5, 0)]
    flows = [VisionMachine(Config(motion=m, **off), machine=machine).run(frame0, next=frame1).flow for m in motions]
    inner = (slice(16, -16), slice(16, -16))
    refined, plain = (np.linalg.norm(f[inner] - np.array(TRUE, np.float32), axis=-1).mean() for f in flows)
    assert refined < 0.97 * plain


@pytest.mark.parametrize(("kwargs", "error", "pattern"), [
    ({"flow": np.zeros((6, 6, 3), np.float32)}, InputValueError, "two components"),
    ({"frame0": np.zeros((5, 6), np.float32)}, InputValueError, "frame0"),
    ({"frame1": np.zeros((6, 6), np.uint8)}, InputValueError, "same type"),
    ({"frame1": "frame"}, InputTypeError, "frame1"),
    ({"frame1": np.full((6, 6), 255.0, np.float32)}, InputValueError, "frame1: float images hold brightness in"),
    ({"frame0": np.zeros((6, 6, 3), np.uint8), "frame1": np.zeros((6, 6), np.uint8)}, InputValueError,
     "frame0 and frame1 must have the same shape"),
    ({"alpha": -1.0}, InputValueError, "alpha"),
    ({"delta": -1.0}, InputValueError, "delta"),
    ({"gamma": float("nan")}, InputValueError, "gamma"),
    ({"delta": 0.0, "gamma": 0.0}, InputValueError, "delta and gamma must not both be 0"),
    ({"iterations": -1}, InputValueError, "iterations"),
    ({"sweeps": 0}, InputValueError, "sweeps"),
    ({"levels": 0}, InputValueError, "levels"),
    ({"levels": 2.5}, InputTypeError, "levels"),
    ({"prior": np.zeros((6, 5, 2), np.float32)}, InputValueError, "prior must have the flow's shape"),
    ({"prior": np.zeros((6, 6, 2), np.float64)}, InputTypeError, "prior must have dtype float32"),
    ({"beta": -1.0}, InputValueError, "beta"),
])
def test_bad_input_is_refused_naming_it(kwargs, error, pattern, machine):
    call = {"flow": np.zeros((6, 6, 2), np.float32), "frame0": np.zeros((6, 6), np.float32),
            "frame1": np.zeros((6, 6), np.float32)}
    with pytest.raises(error, match=pattern):
        variational_refine(**{**call, **kwargs}, machine=machine)


def test_an_odd_width_and_any_work_group_size_give_the_same_refinement(machine, machine_with_local_size):
    """Red-black relaxation over an odd width (the last column's colour alternates by row), and the kernels'
    results whatever the work-group size."""
    frame0, frame1 = translated(shape=(121, 141), seed=5)
    start = rough_start(frame0.shape)
    found = variational_refine(start, frame0, frame1, iterations=10, machine=machine)
    assert (translation_error(found) < 0.06).all()
    np.testing.assert_array_equal(variational_refine(start, frame0, frame1, iterations=10,
                                                     machine=machine_with_local_size), found)
