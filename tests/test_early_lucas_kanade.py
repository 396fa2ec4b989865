"""Lucas-Kanade steps: a flow off by up to half a pixel brought to the true sub-pixel translation, pixels
without flow or without texture left as they are, and bad input refused naming it."""

import dataclasses

import cv2
import numpy as np
import pytest

from vmcl.early.lucas_kanade import LIMIT, lucas_kanade
from vmcl.errors import InputTypeError, InputValueError
from vmcl.pipeline import ColourConfig, Config, MotionConfig, StereoConfig, TextureConfig, VisionMachine

TRUE = (1.3, -0.7)


def translated(shape=(120, 140), seed=0):
    """A smooth random texture in [0, 1] and the same texture moved by TRUE (frame1(x + TRUE) = frame0(x)),
    resampled bicubically."""
    rng = np.random.default_rng(seed)
    frame0 = cv2.GaussianBlur(rng.random(shape).astype(np.float32), (0, 0), 2.0)
    frame0 = (frame0 - frame0.min()) / (frame0.max() - frame0.min())
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float32)
    frame1 = cv2.remap(frame0, xs - TRUE[0], ys - TRUE[1], cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return frame0, np.clip(frame1, 0, 1)


def rough_start(shape, seed=1):
    """The true flow off by up to 0.45 px per component, in smooth waves (the steps refine a smooth flow,
    as the MRF leaves it)."""
    rng = np.random.default_rng(seed)
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float32)
    flow = np.empty((*shape, 2), np.float32)
    flow[..., 0] = TRUE[0] + 0.45 * np.sin(xs / 17 + rng.uniform(0, 6))
    flow[..., 1] = TRUE[1] + 0.45 * np.cos(ys / 13 + xs / 29 + rng.uniform(0, 6))
    return flow


def translation_error(flow, margin=12):
    inner = flow[margin:-margin, margin:-margin]
    return np.abs(inner - np.array(TRUE, np.float32)).mean(axis=(0, 1))


def test_steps_bring_a_rough_flow_to_the_true_translation(machine):
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    assert (translation_error(start) > 0.2).all()
    found = lucas_kanade(start, frame0, frame1, machine=machine)
    assert (translation_error(found) < 0.06).all()  # measured 0.039 and 0.039 from 0.29 and 0.28


def test_a_high_pass_keeps_the_steps_true_when_the_exposure_changes(machine):
    """Frame 1's levels raised to 1.15 (a camera's exposure changing between the frames): brightness
    constancy fails and the plain steps go astray; with the frames' smoothing at 4 px taken off first, they
    still find the translation."""
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    darker = frame1 ** 1.15
    assert (translation_error(lucas_kanade(start, frame0, darker, highpass=0.0, machine=machine)) > 0.2).all()  # 0.35, 0.36
    assert (translation_error(lucas_kanade(start, frame0, darker, highpass=4.0, machine=machine)) < 0.06).all()  # 0.038


def test_one_step_moves_at_most_the_limit(machine):
    frame0, frame1 = translated()
    start = np.zeros((*frame0.shape, 2), np.float32)  # 1.3 and 0.7 px off
    found = lucas_kanade(start, frame0, frame1, iterations=1, machine=machine)
    assert np.abs(found).max() <= LIMIT + 1e-6
    assert np.abs(found[..., 0]).max() == pytest.approx(LIMIT)


def test_uint8_frames_give_the_float_frames_result(machine):
    frame0, frame1 = translated()
    start = rough_start(frame0.shape)
    as_float = lucas_kanade(start, np.round(frame0 * 255) / 255, np.round(frame1 * 255) / 255, machine=machine)
    as_bytes = lucas_kanade(start, np.round(frame0 * 255).astype(np.uint8), np.round(frame1 * 255).astype(np.uint8),
                            machine=machine)
    np.testing.assert_allclose(as_bytes, as_float, atol=1e-4)


def test_pixels_without_flow_or_texture_keep_their_flow(machine):
    frame0, frame1 = translated()
    frame0[:, :40] = frame1[:, :40] = 0.5  # a flat band: no gradient, so no step
    start = rough_start(frame0.shape)
    start[60, 70] = np.nan
    start[10, 100] = (500.0, 0.0)  # carried out of frame 1
    # The smoothed brightness: a flat band stays flat (a high-pass would reach into it from its edge).
    found = lucas_kanade(start, frame0, frame1, window=2.0, highpass=0.0, machine=machine)
    assert np.isnan(found[60, 70]).all()
    np.testing.assert_array_equal(found[:, :25], start[:, :25])  # farther than the window's reach from texture
    assert found[10, 100, 0] == pytest.approx(500.0, abs=LIMIT)  # its neighbours' sums move it, at most a step
    assert np.isfinite(np.delete(found.reshape(-1, 2), 60 * 140 + 70, axis=0)).all()


def test_device_flow_gives_device_output_equal_to_host_and_leaves_the_input(machine):
    frame0, frame1 = translated(seed=2)
    start = rough_start(frame0.shape)
    host = lucas_kanade(start, frame0, frame1, machine=machine)
    device_start = machine.to_device(start)
    device = lucas_kanade(device_start, machine.to_device(frame0), machine.to_device(frame1), machine=machine)
    np.testing.assert_array_equal(device.get(), host)
    np.testing.assert_array_equal(device_start.get(), start)
    np.testing.assert_array_equal(lucas_kanade(start, frame0, frame1, iterations=0, machine=machine), start)


def test_the_motion_cue_takes_the_steps_and_its_restored_flow_gains(machine):
    frame0, frame1 = translated(shape=(96, 112), seed=3)
    off = {"stereo": StereoConfig(enabled=False), "colour": ColourConfig(enabled=False),
           "texture": TextureConfig(enabled=False)}
    # The variational refinement, which would take the flow on from either, is left out.
    alone = dataclasses.replace(MotionConfig(), variational_iterations=0)
    with_steps = VisionMachine(Config(motion=alone, **off), machine=machine).run(frame0, next=frame1)
    without = VisionMachine(Config(motion=dataclasses.replace(alone, lucas_kanade_iterations=0), **off),
                            machine=machine).run(frame0, next=frame1)
    inner = (slice(16, -16), slice(16, -16))
    epe = [np.linalg.norm(flow[inner] - np.array(TRUE, np.float32), axis=-1).mean() for flow in (with_steps.flow,
                                                                                                   without.flow)]
    assert epe[0] < 0.7 * epe[1]  # measured 0.061 against 0.108


@pytest.mark.parametrize(("kwargs", "error", "pattern"), [
    ({"flow": np.zeros((6, 6, 3), np.float32)}, InputValueError, "two components"),
    ({"flow": np.zeros((6, 6), np.float32)}, InputValueError, "flow"),
    ({"frame0": np.zeros((5, 6), np.float32)}, InputValueError, "frame0"),
    ({"frame1": np.zeros((6, 6, 4), np.float32)}, InputValueError, "frame1"),
    ({"frame1": np.zeros((6, 6), np.uint8)}, InputValueError, "same type"),
    ({"frame0": np.full((6, 6), np.nan, np.float32)}, InputValueError, "frame0"),
    ({"frame1": "frame"}, InputTypeError, "frame1"),
    ({"frame0": np.full((6, 6), 2.0, np.float32)}, InputValueError, "frame0: float images hold brightness in"),
    ({"frame1": np.zeros((6, 6, 3), np.float32)}, InputValueError, "frame0 and frame1 must have the same shape"),
    ({"window": 0.0}, InputValueError, "window"),
    ({"window": 1e9}, InputValueError, "window"),
    ({"iterations": -1}, InputValueError, "iterations"),
    ({"highpass": 0.5}, InputValueError, "highpass must be 0 or exceed"),
    ({"highpass": -2.0}, InputValueError, "highpass"),
    ({"highpass": 1e9}, InputValueError, "highpass"),
])
def test_bad_input_is_refused_naming_it(kwargs, error, pattern, machine):
    call = {"flow": np.zeros((6, 6, 2), np.float32), "frame0": np.zeros((6, 6), np.float32),
            "frame1": np.zeros((6, 6), np.float32)}
    with pytest.raises(error, match=pattern):
        lucas_kanade(**{**call, **kwargs}, machine=machine)


def test_mixed_host_and_device_inputs_are_refused(machine):
    frame = np.zeros((6, 6), np.float32)
    with pytest.raises(InputTypeError, match="frame0"):
        lucas_kanade(np.zeros((6, 6, 2), np.float32), machine.to_device(frame), frame, machine=machine)
