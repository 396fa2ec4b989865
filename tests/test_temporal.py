"""Time: rendered sequences, the streaming machine and its temporal terms (seed section "Fast vision: The
role of time smoothness"), against the sequences' exact ground truth."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from vmcl import scenes
from vmcl.metrics import evaluate_flow
from vmcl.pipeline import (
    WARM_SCHEDULE,
    ColourConfig,
    Config,
    MotionConfig,
    MrfConfig,
    StereoConfig,
    TextureConfig,
    TimeConfig,
    VisionMachine,
)

# Depth and motion only: the cues whose fields the ground truth gives at every frame.
_DEPTH_AND_MOTION = {"colour": ColourConfig(enabled=False), "texture": TextureConfig(enabled=False)}


@pytest.mark.parametrize("name, wobble", [("blocks", 0.0), ("corridor", 0.0), ("cues", 0.0), ("blocks", 0.4),
                                          ("corridor", 0.4)])
def test_each_frame_of_a_sequence_continues_the_last(name, wobble):
    frames = scenes.render_sequence(scenes.preset(name, shape=(64, 80)), 3, seed=4, wobble=wobble)
    for before, after in itertools.pairwise(frames):
        seen = np.isfinite(before.left_next) & np.isfinite(after.left)
        assert (np.isfinite(before.left_next) == np.isfinite(after.left)).all()
        np.testing.assert_allclose(after.left[seen], before.left_next[seen], atol=1e-4)
    assert scenes.advance(frames[0].world, 0) is frames[0].world


def test_a_sequences_first_frame_is_the_single_render_and_frames_get_their_own_noise():
    world = scenes.preset("cues", shape=(64, 64))
    first, second = scenes.render_sequence(world, 2, seed=3, noise=0.05)
    np.testing.assert_array_equal(first.left, scenes.render(world, seed=3, noise=0.05).left)
    clean = scenes.render_sequence(world, 2, seed=3)
    # Same textures, different noise draws: the noise of frame 1 is not frame 0's again.
    assert not np.allclose(second.left - clean[1].left, first.left - clean[0].left)


def _errors(results, frames):
    """Per frame (from the second): mean |disparity error| and flow EPE, and the signed error fields."""
    rows = []
    for result, frame in zip(results, frames):
        visible = ~frame.occluded_stereo & np.isfinite(frame.disparity)
        moving = ~frame.occluded_motion & np.isfinite(frame.flow).all(axis=-1)
        rows.append((np.where(visible, result.disparity - frame.disparity, np.nan),
                     np.where(moving[..., None], result.flow - frame.flow, np.nan),
                     evaluate_flow(result.flow, frame.flow, mask=moving).epe))
    return rows


def _flicker(rows):
    """Mean change of the signed error between consecutive frames: disparity, flow."""
    d = [np.nanmean(np.abs(b[0] - a[0])) for a, b in itertools.pairwise(rows)]
    f = [np.nanmean(np.linalg.norm(b[1] - a[1], axis=-1)) for a, b in itertools.pairwise(rows)]
    return float(np.mean(d)), float(np.mean(f))


@pytest.fixture(scope="module")
def noisy_sequence():
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(96, 96)), 6, seed=2, noise=0.03)
    return frames, [f.left for f in frames], [f.right for f in frames]


# Strong temporal terms, for steady motion: the rendered sequences' velocities are constant. The gain is 2
# since the stereo MRF weighs its data by alpha 1 (it was 0.25, when a gain of 1 halved the disparity's
# flicker; with alpha 1 that gain takes off 43% of it, a gain of 2 57%).
STEADY = {"gain": 2.0, "memory": 2.0, "jump": 1.0}


@pytest.fixture(scope="module")
def streamed(noisy_sequence, machine):
    frames, lefts, rights = noisy_sequence
    out = {}
    for label, time in (("off", TimeConfig(enabled=False)), ("warm", TimeConfig(**STEADY)),
                        ("cold", TimeConfig(warm=False, **STEADY))):
        vm = VisionMachine(Config(time=time, **_DEPTH_AND_MOTION), machine=machine)
        # The last frame has no next, so no flow: scored up to the one before it.
        out[label] = _errors(list(vm.stream(lefts, rights))[1:-1], frames[1:-1])
    return out


def test_the_temporal_terms_halve_the_flicker_of_steady_motion(streamed):
    off, on = _flicker(streamed["off"]), _flicker(streamed["warm"])
    assert on[0] <= 0.5 * off[0], (on, off)
    assert on[1] <= 0.5 * off[1], (on, off)
    # ... and the fields themselves are no worse.
    assert np.mean([r[2] for r in streamed["warm"]]) <= np.mean([r[2] for r in streamed["off"]])


def test_a_warm_start_reaches_the_cold_starts_error_in_half_the_sweeps(streamed):
    fast = MrfConfig().settings("motion").schedule("meanfield")
    warm = MrfConfig().settings("motion", warm=True).schedule("meanfield")
    sweeps = [s.mf_steps * s.mf_iterations + s.quench for s in (fast, warm)]
    assert warm.mf_t0 == WARM_SCHEDULE["mf_t0"] and 2 * sweeps[1] <= sweeps[0], sweeps
    warm_epe = np.mean([r[2] for r in streamed["warm"]])
    cold_epe = np.mean([r[2] for r in streamed["cold"]])
    assert warm_epe <= 1.1 * cold_epe, (warm_epe, cold_epe)
    warm_d = np.mean([np.nanmean(np.abs(r[0])) for r in streamed["warm"]])
    cold_d = np.mean([np.nanmean(np.abs(r[0])) for r in streamed["cold"]])
    assert warm_d <= 1.1 * cold_d, (warm_d, cold_d)


def test_the_default_temporal_terms_cost_nothing_when_speeds_change(machine):
    # Speeds that change by about 30% per frame (the defaults were fitted on such sequences of other
    # scenes and seeds): the carried fields are worth little, and the defaults must not make the fields worse.
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(96, 96)), 5, seed=5, noise=0.02, wobble=0.3)
    lefts, rights = [f.left for f in frames], [f.right for f in frames]
    found = {}
    for label, time in (("off", TimeConfig(enabled=False)), ("default", TimeConfig())):
        vm = VisionMachine(Config(time=time, **_DEPTH_AND_MOTION), machine=machine)
        rows = _errors(list(vm.stream(lefts, rights))[1:-1], frames[1:-1])
        found[label] = (np.mean([r[2] for r in rows]), np.mean([np.nanmean(np.abs(r[0])) for r in rows]))
    assert found["default"][0] <= 1.03 * found["off"][0], found
    assert found["default"][1] <= 1.03 * found["off"][1], found


def test_without_the_temporal_terms_a_stream_is_run_on_each_frame(machine):
    frames = scenes.render_sequence(scenes.preset("cues", shape=(64, 64)), 3, seed=1, noise=0.02)
    lefts, rights = [f.left for f in frames], [f.right for f in frames]
    vm = VisionMachine(Config(time=TimeConfig(enabled=False)), machine=machine)
    streamed = list(vm.stream(iter(lefts), iter(rights)))
    assert len(streamed) == 3 and streamed[-1].flow is None
    for k, result in enumerate(streamed):
        alone = vm.run(lefts[k], rights[k], lefts[k + 1] if k + 1 < len(lefts) else None)
        for name in ("disparity", "flow", "labels", "boundary_strength"):
            expected = getattr(alone, name)
            if expected is None:
                assert getattr(result, name) is None
            else:
                np.testing.assert_array_equal(getattr(result, name), expected, err_msg=f"frame {k} {name}")


def test_the_previous_flow_predicts_the_motion_search(machine, monkeypatch):
    """With [time] predict_search, each frame but the first searches around the previous restored flow
    carried to it (the frame before's flow, moved along itself); without it, no prediction is given."""
    from vmcl.early import motion

    given = []
    real = motion.flow

    def recording(*args, **kwargs):
        prediction = kwargs.get("prediction")
        given.append(None if prediction is None else prediction.get())
        return real(*args, **kwargs)

    monkeypatch.setattr(motion, "flow", recording)
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 4, seed=1, noise=0.02)
    lefts, rights = [f.left for f in frames], [f.right for f in frames]
    for predict in (True, False):
        given.clear()
        vm = VisionMachine(Config(time=TimeConfig(predict_search=predict), **_DEPTH_AND_MOTION), machine=machine)
        streamed = list(vm.stream(iter(lefts), iter(rights)))
        assert len(given) == 3  # the last frame has no next one, so no flow
        assert given[0] is None
        if not predict:
            assert all(p is None for p in given)
            continue
        for k in (1, 2):
            prediction = given[k]
            assert prediction.shape == (64, 64, 2)
            carried = np.isfinite(prediction).all(axis=-1)
            assert carried.mean() > 0.5
            # The previous restored flow, moved along itself: the same motions, so the same median.
            previous = streamed[k - 1].flow
            truth = np.median(frames[k - 1].flow[np.isfinite(frames[k - 1].flow).all(axis=-1)], axis=0)
            assert np.abs(truth).max() > 0.3  # the scene moves (by 0.32 px)
            # and so does the restored flow (0.26 to 0.52 px on these tiny frames), or the comparison below
            # would compare two medians of a flow near 0
            assert np.abs(np.median(previous.reshape(-1, 2), axis=0)).max() > 0.15
            np.testing.assert_allclose(np.median(prediction[carried], axis=0),
                                       np.median(previous.reshape(-1, 2), axis=0), atol=0.1)


def test_the_previous_flow_pulls_the_variational_refinement_only_when_asked(machine, monkeypatch):
    """[time] flow_prior gives the refinement the carried flow as its prior (frames but the first), with the
    refinement on; the motion search is then not predicted unless predict_search says so; with the
    refinement off, nothing is carried for it."""
    import vmcl.cues.motion as motion_cue
    from vmcl.early import motion

    searched, pulled = [], []
    real_flow, real_refine = motion.flow, motion_cue.variational_refine

    def recording_flow(*args, **kwargs):
        searched.append(kwargs.get("prediction") is not None)
        return real_flow(*args, **kwargs)

    def recording_refine(*args, **kwargs):
        prior = kwargs.get("prior")
        pulled.append((None if prior is None else prior.get(), kwargs.get("beta")))
        return real_refine(*args, **kwargs)

    monkeypatch.setattr(motion, "flow", recording_flow)
    monkeypatch.setattr(motion_cue, "variational_refine", recording_refine)
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 4, seed=1, noise=0.02)
    lefts, rights = [f.left for f in frames], [f.right for f in frames]
    refined = MotionConfig(variational_iterations=3)
    time = TimeConfig(predict_search=False, flow_prior=2.0)
    streamed = list(VisionMachine(Config(motion=refined, time=time, **_DEPTH_AND_MOTION),
                                  machine=machine).stream(iter(lefts), iter(rights)))
    assert searched == [False, False, False]
    assert pulled[0] == (None, 0.0)
    for k in (1, 2):
        prior, beta = pulled[k]
        assert beta == 2.0 and prior.shape == (64, 64, 2)
        carried = np.isfinite(prior).all(axis=-1)
        assert carried.mean() > 0.5
        np.testing.assert_allclose(np.median(prior[carried], axis=0),
                                   np.median(streamed[k - 1].flow.reshape(-1, 2), axis=0), atol=0.1)
    searched.clear()
    list(VisionMachine(Config(time=time, **_DEPTH_AND_MOTION), machine=machine).stream(iter(lefts), iter(rights)))
    assert searched == [False, False, False]  # the refinement off: no flow carried, none searched around


def test_at_a_scene_cut_time_breaks_and_the_frame_starts_cold(machine):
    first = scenes.render_sequence(scenes.preset("blocks", shape=(80, 80)), 3, seed=1, noise=0.02)
    second = scenes.render_sequence(scenes.preset("corridor", shape=(80, 80)), 2, seed=1, noise=0.02)
    lefts = [f.left for f in first] + [f.left for f in second]
    vm = VisionMachine(Config(time=TimeConfig(**STEADY), **_DEPTH_AND_MOTION), machine=machine)
    results = list(vm.stream(lefts))
    cut = results[3]  # the corridor's first frame, after three of the blocks
    assert any("scene cut" in note for note in cut.notes), cut.notes
    alone = VisionMachine(Config(**_DEPTH_AND_MOTION), machine=machine).run(lefts[3], next=lefts[4])
    truth = second[0]
    moving = ~truth.occluded_motion & np.isfinite(truth.flow).all(axis=-1)
    ghosted = evaluate_flow(cut.flow, truth.flow, mask=moving).epe
    cold = evaluate_flow(alone.flow, truth.flow, mask=moving).epe
    assert ghosted <= 1.1 * cold, (ghosted, cold)
    assert not any("scene cut" in note for r in results[:3] for note in r.notes)


def test_where_an_object_appears_time_breaks_and_nothing_ghosts(machine):
    world = scenes.preset("blocks", shape=(96, 96))
    # A crate that appears at frame 3 in front of the scene, moving to the right.
    crate = scenes.Body(scenes.box((0.9, -0.2, 3.0), (0.9, 0.9, 0.9), colour=(0.8, 0.35, 0.3),
                                   texture=scenes.Texture("noise", 0.05, 0.4)),
                        scenes.Motion((0.08, 0.0, 0.0)), name="crate")
    with_crate = dataclasses.replace(world, bodies=(*world.bodies, crate))
    before = scenes.render_sequence(world, 3, seed=2, noise=0.01)
    after = [scenes.render(scenes.advance(with_crate, k), seed=2, noise=0.01, frame=k) for k in (3, 4)]
    lefts = [f.left for f in before] + [f.left for f in after]
    vm = VisionMachine(Config(time=TimeConfig(**STEADY), **_DEPTH_AND_MOTION), machine=machine)
    appeared = list(vm.stream(lefts))[3]
    alone = VisionMachine(Config(**_DEPTH_AND_MOTION), machine=machine).run(lefts[3], next=lefts[4])
    truth = after[0]
    crate_pixels = (truth.bodies == len(world.bodies)) & ~truth.occluded_motion
    assert crate_pixels.sum() > 200
    ghosted = evaluate_flow(appeared.flow, truth.flow, mask=crate_pixels).epe
    cold = evaluate_flow(alone.flow, truth.flow, mask=crate_pixels).epe
    assert ghosted <= 1.1 * cold + 0.05, (ghosted, cold)


def test_stream_refuses_frames_that_do_not_fit(machine):
    frames = scenes.render_sequence(scenes.preset("cues", shape=(64, 64)), 2, seed=1)
    vm = VisionMachine(Config(time=TimeConfig(enabled=False), **_DEPTH_AND_MOTION), machine=machine)
    # Lists: their lengths are compared before any work; iterators: when one ends before the other.
    with pytest.raises(ValueError, match=r"frames and rights must be as long .*, got 2 and 1"):
        list(vm.stream([f.left for f in frames], [frames[0].right]))
    with pytest.raises(ValueError, match=r"frames and rights must be as long .*, got 1 and 2"):
        list(vm.stream([frames[0].left], [frames[0].right, frames[1].right]))
    with pytest.raises(ValueError, match="rights ended at frame 1"):
        list(vm.stream(iter([f.left for f in frames]), iter([frames[0].right])))
    with pytest.raises(ValueError, match="rights holds more frames"):
        list(vm.stream(iter([frames[0].left]), iter([frames[0].right, frames[1].right])))
    with pytest.raises(ValueError, match="frame 0: next has shape"):
        list(vm.stream([frames[0].left, frames[1].left[:32]]))
    assert list(vm.stream([])) == []
    # One image is not a sequence: its rows were read as frames, refused as too small.
    for image in (frames[0].left, frames[0].left.mean(axis=2)):
        with pytest.raises(TypeError, match="got one image of shape"):
            list(vm.stream(image))


def test_a_stream_without_motion_gives_no_note_of_an_unused_next_frame(machine):
    # The stream gives each frame its next; with no cue reading it, every frame said it was not used.
    frames = scenes.render_sequence(scenes.preset("cues", shape=(64, 64)), 3, seed=1)
    vm = VisionMachine(Config(time=TimeConfig(enabled=False), motion=MotionConfig(enabled=False), **_DEPTH_AND_MOTION),
                       machine=machine)
    results = list(vm.stream([f.left for f in frames], [f.right for f in frames]))
    assert len(results) == 3 and not any("next" in note for r in results for note in r.notes)
    assert all(r.flow is None and r.disparity is not None for r in results)


@pytest.mark.parametrize("key, value, message", [("gain", -1.0, "time.gain"), ("memory", 0.0, "time.memory"),
                                                  # beyond float32 they failed mid-stream, naming neither
                                                  ("gain", 1e39, "time.gain"), ("memory", 1e39, "time.memory"),
                                                  ("tolerance", 0.0, "time.tolerance"), ("jump", -1.0, "time.jump"),
                                                  ("scene_cut", 1.5, "time.scene_cut"), ("warm", 1, "time.warm")])
def test_time_settings_are_checked_naming_the_key(key, value, message):
    with pytest.raises((ValueError, TypeError), match=message):
        Config.from_dict({"time": {key: value}})


def test_the_warm_schedule_keeps_a_users_overrides():
    mine = MrfConfig(motion={"beta": 3.0}).settings("motion", warm=True)
    assert mine.model.beta == 3.0
    assert dataclasses.asdict(mine.schedule("meanfield"))["mf_steps"] == WARM_SCHEDULE["mf_steps"]


def test_render_sequence_refuses_bad_counts_and_worlds():
    world = scenes.preset("cues", shape=(64, 64))
    for frames in (0, scenes.sequences.MAX_FRAMES + 1):
        with pytest.raises(ValueError, match="frames"):
            scenes.render_sequence(world, frames)
    with pytest.raises(TypeError, match="world must be a World"):
        scenes.render_sequence("cues", 2)
    with pytest.raises(ValueError, match="wobble"):
        scenes.render_sequence(world, 2, wobble=-0.1)
    with pytest.raises(ValueError, match="speeds must have shape"):
        scenes.advance(world, 2, speeds=np.ones((2, 2)))
    assert len(scenes.render_sequence(world, 1)) == 1


def _panning(name: str, speed: float) -> scenes.Scene:
    """The preset with still bodies and the rig sliding sideways by ``speed`` world units per frame."""
    world = scenes.preset(name, shape=(256, 256))
    bodies = tuple(dataclasses.replace(b, motion=scenes.Motion()) for b in world.bodies)
    camera = dataclasses.replace(world.camera, motion=scenes.Motion((speed, 0.0, 0.0)))
    return scenes.render(dataclasses.replace(world, bodies=bodies, camera=camera), seed=1, noise=0.01)


def test_motion_finds_a_large_motion_with_no_range_given(machine):
    scene = _panning("cues", 0.5)  # flow from 14 to 28 px across the scene's depths
    known = ~scene.occluded_motion & np.isfinite(scene.flow).all(axis=-1)
    assert np.nanmax(np.abs(scene.flow[known])) > 25
    config = Config(stereo=StereoConfig(enabled=False), **_DEPTH_AND_MOTION)
    result = VisionMachine(config, machine=machine).run(scene.left, next=scene.left_next)
    assert evaluate_flow(result.flow, scene.flow, mask=known).epe < 0.5
    assert not any("limit" in note for note in result.notes)
    # With the pyramid cut to 2 levels the search reaches 12 px, and the run says so.
    short = Config(stereo=StereoConfig(enabled=False), motion=MotionConfig(levels=2), **_DEPTH_AND_MOTION)
    notes = VisionMachine(short, machine=machine).run(scene.left, next=scene.left_next).notes
    assert any("search's limit of 12 px" in note for note in notes), notes


def test_a_matcher_that_finds_little_is_noted(machine):
    """One-pixel brightness patches match almost nowhere: the MRF still gives a dense flow, and the run
    says it rests on little data; the default matcher finds flow nearly everywhere and says nothing."""
    scene = _panning("cues", 0.1)
    off = {"stereo": StereoConfig(enabled=False), **_DEPTH_AND_MOTION}
    for section, sparse in ((MotionConfig(patch=1, features="brightness"), True), (MotionConfig(), False)):
        result = VisionMachine(Config(motion=section, **off), machine=machine).run(scene.left, next=scene.left_next)
        noted = [note for note in result.notes if "rests on little data" in note]
        assert bool(noted) == sparse, result.notes
        assert np.isfinite(result.flow).all()


def test_a_field_is_carried_only_between_a_frames_begin_and_end(machine):
    """vmcl.temporal.Memory: a restoration carried along the flow to the next frame, NaN and weightless where
    its source lies outside the image (a 6-px shift right: the first 6 columns), the rest the source pixel's
    value; nothing carried once the frame has ended and before the next begins (its brightness test is gone)."""
    from vmcl.temporal import Memory

    memory = Memory(machine, tolerance=0.05, memory=4.0, gain=0.5, scene_cut=0.5)
    height, width, shift = 8, 24, 6
    frame = machine.to_device(np.full((height, width), 0.5, np.float32))
    field = np.tile(np.arange(width, dtype=np.float32), (height, 1))
    memory.begin(frame)
    memory.remember("stereo", machine.to_device(field), machine.to_device(np.ones((height, width), np.float32)),
                    True)
    flow = np.zeros((height, width, 2), np.float32)
    flow[..., 0] = shift
    memory.end(machine.to_device(flow))
    assert memory.carry("stereo") is None  # the frame ended, the next has not begun
    assert memory.begin(frame)
    carried = memory.carry("stereo")
    prediction, weight = carried.prediction.get(), carried.weight.get()
    assert np.isnan(prediction[:, :shift]).all() and (weight[:, :shift] == 0).all()
    np.testing.assert_array_equal(prediction[:, shift:], field[:, :-shift])
    assert (weight[:, shift:] > 0).all()


def test_a_path_where_images_belong_is_refused_with_the_way_to_read_it(machine, tmp_path):
    vm = VisionMachine(machine=machine)
    with pytest.raises(TypeError, match=r"frames must be an iterable of images, got the path .*open_frames"):
        list(vm.stream(str(tmp_path)))
    with pytest.raises(TypeError, match=r"rights must be an iterable of images, got the path"):
        list(vm.stream([np.zeros((32, 32), np.float32)], tmp_path))
    with pytest.raises(TypeError, match=r"left must be a NumPy array, got the path .*read_image"):
        vm.run(str(tmp_path / "left.png"))


def test_a_stream_copies_each_frame_and_names_a_frame_that_is_none(machine, tmp_path):
    # A None frame was taken for the end of the stream (fewer Results, no error); a source that fills one
    # buffer per frame (a camera, a video reader) gave no motion, since frames are read one ahead; and a
    # Result's image was the caller's own float32 array.
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 3, seed=1, noise=0.01)
    lefts = [np.ascontiguousarray(f.left.mean(axis=2), np.float32) for f in frames]
    vm = VisionMachine(Config(time=TimeConfig(enabled=False), **_DEPTH_AND_MOTION), machine=machine)
    stream = vm.stream([lefts[0], None, lefts[2]])
    with pytest.raises(TypeError, match="frame 1: left must be a NumPy array, got NoneType"):
        next(stream)  # frame 0 is not run as a last frame, without motion, before the error
    with pytest.raises(TypeError, match="frames must be an iterable of images, got int"):
        list(vm.stream(5))

    def camera():
        buffer = np.empty_like(lefts[0])
        for frame in lefts:
            buffer[:] = frame
            yield buffer

    from_camera = list(vm.stream(camera()))
    from_copies = list(vm.stream(lefts))
    assert len(from_camera) == len(from_copies) == 3
    for ours, theirs in zip(from_camera, from_copies):
        assert ours.flow is None and theirs.flow is None or np.array_equal(ours.flow, theirs.flow)
        np.testing.assert_array_equal(ours.image, theirs.image)
    assert np.abs(from_copies[0].flow).mean() > 0.1  # the blocks move: the copies see it (a buffer saw none)
    image = lefts[0].copy()
    result = vm.run(image)
    image[:] = 0
    assert result.image.max() > 0


def test_a_none_among_the_right_frames_is_refused_as_among_the_left(machine):
    # A None right view ran its frame without stereo, in silence (disparity None, no note), where a None
    # left frame was refused.
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 3, seed=1, noise=0.01)
    vm = VisionMachine(Config(time=TimeConfig(enabled=False), motion=MotionConfig(enabled=False), **_DEPTH_AND_MOTION),
                       machine=machine)
    stream = vm.stream([f.left for f in frames], [frames[0].right, None, frames[2].right])
    assert next(stream).disparity is not None  # frame 0 has its right view
    with pytest.raises(TypeError, match="^frame 1: right must be a NumPy array, got NoneType$"):
        next(stream)
    with pytest.raises(TypeError, match="^frame 0: right must be a NumPy array, got NoneType$"):
        list(vm.stream(iter([frames[0].left]), iter([None])))


def test_a_sequence_of_one_frame_says_motion_needs_a_next_frame(machine):
    # One frame gave no flow and no word of why.
    frame = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 1, seed=1, noise=0.01)[0]
    note = "motion: the sequence has one frame, and motion needs a next frame: no flow"
    (alone,) = VisionMachine(Config(time=TimeConfig(enabled=False), **_DEPTH_AND_MOTION), machine=machine).stream(
        [frame.left])
    assert alone.flow is None and note in alone.notes
    # Not where motion is off (nothing reads a next frame), nor on a longer sequence's last frame.
    (still,) = VisionMachine(Config(motion=MotionConfig(enabled=False), **_DEPTH_AND_MOTION),
                             machine=machine).stream([frame.left])
    assert still.flow is None and not any("next frame" in n for n in still.notes)
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), 2, seed=1, noise=0.01)
    results = list(VisionMachine(Config(time=TimeConfig(enabled=False), **_DEPTH_AND_MOTION),
                                 machine=machine).stream([f.left for f in frames]))
    assert results[0].flow is not None and results[1].flow is None
    assert not any("next frame" in n for r in results for n in r.notes)


def test_a_frame_the_machine_refuses_is_named_as_the_checks_name_it(machine):
    # Frames smaller than the motion patch were refused without "frame k:", unlike every other frame error.
    ramp = np.tile(np.arange(20, dtype=np.uint8) * 10, (20, 1))
    vm = VisionMachine(Config(time=TimeConfig(enabled=False), **_DEPTH_AND_MOTION), machine=machine)
    with pytest.raises(ValueError, match=r"^frame 0: motion .*patch \(21\) is larger than the image \(20 x 20"):
        list(vm.stream([ramp, ramp, ramp]))
