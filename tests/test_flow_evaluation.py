"""Flow sequences read from any folder in the field's layouts, and `vmcl eval flow` on them."""

from __future__ import annotations

import shutil

import cv2
import numpy as np
import pytest

from vmcl import datasets, scenes
from vmcl.cli import main
from vmcl.flow_evaluation import baselines, evaluate_sequence, motion_only
from vmcl.metrics import evaluate_flow
from vmcl.pipeline import VisionMachine


def _png(path, image):
    cv2.imwrite(str(path), cv2.cvtColor(np.round(image * 255).clip(0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR))


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """A rendered 4-frame sequence in Middlebury's layout (flow for frame 12) and in this Sintel layout."""
    root = tmp_path_factory.mktemp("flows")
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 80)), 4, seed=0, noise=0.01)
    middlebury, sintel = root / "mine" / "Blocks", root / "clean" / "blocks"
    for folder in (middlebury, sintel / "gt" / "invalid"):
        folder.mkdir(parents=True)
    for k, frame in enumerate(frames):
        _png(middlebury / f"frame{10 + k}.png", frame.left)
        _png(sintel / f"frame_{k + 1:04d}.png", frame.left)
    _png(middlebury / "frame14.png", frames[-1].left_next)
    truth = frames[2].flow
    datasets.write_flo(middlebury / "flow12.flo", truth)
    datasets.write_flo(sintel / "gt" / "frame_0002.flo", frames[1].flow)
    invalid = np.zeros((64, 80), np.uint8)
    invalid[:, :4] = 255
    cv2.imwrite(str(sintel / "gt" / "invalid" / "frame_0002.png"), invalid)
    return root, frames


def test_a_middlebury_layout_folder_is_read_with_its_past(rendered):
    root, frames = rendered
    sequence = datasets.read_flow_folder(root / "mine" / "Blocks")
    assert [p.name for p in sequence.frames][:3] == ["frame10.png", "frame11.png", "frame12.png"]
    assert sequence.index == 2 and sequence.name == "Blocks" and sequence.occluded is None
    np.testing.assert_array_equal(sequence.mask, np.isfinite(frames[2].flow).all(axis=-1))


def test_a_sintel_layout_folder_is_read_with_its_invalid_pixels_left_out(rendered):
    root, _ = rendered
    assert datasets.find_flow_folders(root) == [root / "clean" / "blocks", root / "mine" / "Blocks"]
    sequence = datasets.read_flow_folder(root / "clean" / "blocks")
    assert sequence.index == 1 and sequence.name == "clean/blocks"
    assert not sequence.mask[:, :4].any() and sequence.mask[:, 4:].any()


def test_a_folder_given_as_dot_or_dotdot_is_named_by_its_own_name(rendered, monkeypatch):
    # The name was read from the path as given: "" for ".", "/.." for "..".
    root, _ = rendered
    monkeypatch.chdir(root / "mine" / "Blocks")
    assert datasets.read_flow_folder(".").name == "Blocks"
    monkeypatch.chdir(root / "clean" / "blocks" / "gt")
    assert datasets.read_flow_folder("..").name == "clean/blocks"


def test_folders_without_flow_or_frames_are_refused(tmp_path, rendered):
    root, _ = rendered
    with pytest.raises(ValueError, match="no ground-truth flow"):
        datasets.read_flow_folder(tmp_path)
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    shutil.copy(root / "mine" / "Blocks" / "flow12.flo", lonely / "flow12.flo")
    shutil.copy(root / "mine" / "Blocks" / "frame12.png", lonely / "frame12.png")
    with pytest.raises(ValueError, match="fewer than two numbered frames"):
        datasets.read_flow_folder(lonely)
    shutil.copy(root / "mine" / "Blocks" / "frame10.png", lonely / "frame10.png")
    with pytest.raises(ValueError, match="flow from frame 12 to 13, which the folder lacks"):
        datasets.read_flow_folder(lonely)
    with pytest.raises(FileNotFoundError):
        datasets.read_flow_folder(tmp_path / "none")


def test_only_the_frames_run_is_read_and_every_file_has_the_frames_size(tmp_path, rendered):
    # Any numbered PNG was a frame: Middlebury's colour picture flow10.png sorted before frame10.png and
    # was scored as frame t. A next frame or a mask of another size was accepted.
    root, _ = rendered
    folder = tmp_path / "Blocks"
    shutil.copytree(root / "mine" / "Blocks", folder)
    picture = cv2.imread(str(folder / "frame10.png"))
    cv2.imwrite(str(folder / "flow12.png"), picture)
    sequence = datasets.read_flow_folder(folder)
    assert [p.name for p in sequence.frames][sequence.index:sequence.index + 2] == ["frame12.png", "frame13.png"]
    assert not any(p.name.startswith("flow") for p in sequence.frames)
    for number in range(10, 15):  # as many as the frames: which run is the sequence cannot be told
        cv2.imwrite(str(folder / f"img{number}.png"), picture)
    with pytest.raises(ValueError, match="which are the frames cannot be told"):
        datasets.read_flow_folder(folder)
    for path in folder.glob("img*.png"):
        path.unlink()
    # A longer run of other numbered PNGs (masks) beside the frames: the run that holds the flow's frame
    # and its next is the sequence.
    for number in range(1, 8):
        cv2.imwrite(str(folder / f"mask{number:02d}.png"), picture)
    assert datasets.read_flow_folder(folder).frames[0].name.startswith("frame")
    cv2.imwrite(str(folder / "frame13.png"), cv2.resize(picture, None, fx=2, fy=2))
    with pytest.raises(ValueError, match="frame13.png is"):
        datasets.read_flow_folder(folder)


def test_a_gap_or_a_frame_of_another_size_ends_the_sequence_there(tmp_path, rendered):
    # frame10 was streamed as the frame before frame12 where frame11 was missing; a past frame of another size
    # stopped the whole sequence's scoring.
    root, _ = rendered
    folder = tmp_path / "Blocks"
    shutil.copytree(root / "mine" / "Blocks", folder)
    (folder / "frame11.png").unlink()
    sequence = datasets.read_flow_folder(folder)
    assert [p.name for p in sequence.frames] == ["frame12.png", "frame13.png", "frame14.png"] and sequence.index == 0
    shutil.copy(root / "mine" / "Blocks" / "frame11.png", folder / "frame11.png")
    cv2.imwrite(str(folder / "frame10.png"), cv2.imread(str(folder / "frame10.png"))[:32])
    sequence = datasets.read_flow_folder(folder)
    assert [p.name for p in sequence.frames][:2] == ["frame11.png", "frame12.png"] and sequence.index == 1


def test_frames_of_another_image_type_are_read_and_a_second_flow_is_reported(tmp_path, rendered):
    root, _ = rendered
    folder = tmp_path / "data" / "Blocks"
    folder.mkdir(parents=True)
    for path in (root / "mine" / "Blocks").glob("frame*.png"):
        cv2.imwrite(str(folder / (path.stem + ".jpg")), cv2.imread(str(path)), [cv2.IMWRITE_JPEG_QUALITY, 100])
    shutil.copy(root / "mine" / "Blocks" / "flow12.flo", folder / "flow12.flo")
    sequence = datasets.read_flow_folder(folder)
    assert sequence.frames[sequence.index].name == "frame12.jpg"
    # A user's estimate beside the truth: the folder was passed over without a word.
    shutil.copy(folder / "flow12.flo", folder / "my_estimate.flo")
    assert datasets.find_flow_folders(tmp_path / "data") == []
    [(lacking, why)] = datasets.flow_folders_lacking(tmp_path / "data")
    assert lacking == folder and "2 flows (flow12.flo, my_estimate.flo)" in why


def test_frames_without_ground_truth_are_named_not_passed_over(tmp_path, rendered):
    # Middlebury's download holds eval-data/ without ground truth: eval flow left it out without a word,
    # where the README promises a note. Other numbered pictures (a folder of photographs) are no sequence.
    root, _ = rendered
    army = tmp_path / "eval-data" / "Army"
    army.mkdir(parents=True)
    for path in (root / "mine" / "Blocks").glob("frame*.png"):
        shutil.copy(path, army / path.name)
    photos = tmp_path / "photos"
    photos.mkdir()
    for k in (1, 2, 3):
        shutil.copy(root / "mine" / "Blocks" / "frame10.png", photos / f"IMG_{k:04d}.png")
    [(lacking, why)] = datasets.flow_folders_lacking(tmp_path)
    assert lacking == army and why.startswith("it holds 5 numbered frames (frame10.png ...) but no ground-truth flow")


def test_the_evaluation_scores_every_method_against_the_truth(rendered, machine):
    root, frames = rendered
    sequence = datasets.read_flow_folder(root / "mine" / "Blocks")
    rows = {row.method: row for row in evaluate_sequence(sequence, machine=machine)}
    assert set(rows) == {"vmcl two frames", "vmcl sequence", *baselines()}
    # Every method finds the motion: each lands below a zero flow's error.
    zero = float(np.nanmean(np.linalg.norm(frames[2].flow, axis=-1)))
    for row in rows.values():
        assert 0 < row.epe < 0.8 * zero, (row.method, row.epe, zero)
        assert row.epe_matched is None and row.ms > 0
    # The machine's row is its flow scored over the mask, as the metrics score it directly.
    images = [datasets.read_image(path) for path in sequence.frames[2:4]]
    direct = VisionMachine(motion_only(), machine=machine).run(images[0], next=images[1])
    expected = evaluate_flow(direct.flow, sequence.flow, mask=sequence.mask)
    assert rows["vmcl two frames"].epe == pytest.approx(expected.epe, rel=1e-6)


def test_eval_flow_prints_each_sequence_and_method(rendered, capsys):
    root, _ = rendered
    assert main(["eval", "flow", "--data", str(root / "mine"), "-q"]) == 0
    out = capsys.readouterr().out
    assert "Blocks" in out and "vmcl sequence" in out and "OpenCV DIS medium" in out
    assert main(["eval", "flow", "--data", str(root / "mine" / "Blocks" / "flow12.flo"), "-q"]) == 2


def test_eval_flow_tells_sequences_of_one_name_apart_by_their_path(rendered, tmp_path, capsys):
    # Two folders named Blocks in different places were both printed as "Blocks".
    root, _ = rendered
    for place in ("a", "b"):
        shutil.copytree(root / "mine" / "Blocks", tmp_path / place / "Blocks")
    assert main(["eval", "flow", "--data", str(tmp_path), "-q"]) == 0
    out = capsys.readouterr().out
    names = {line.split()[0] for line in out.splitlines() if "vmcl two frames" in line}
    assert names == {"a/Blocks", "b/Blocks"}, out


def test_middleburys_download_layout_is_read_and_a_bad_sequence_is_left_out_by_name(rendered, tmp_path, capsys):
    """other-data/<scene> beside other-gt-flow/<scene>/flowNN.flo, as Middlebury's download lays them out, is a
    sequence named other-data/<scene>; a truncated .flo and a flow with one frame are left out, each named on
    stderr, while the good sequence is scored (status 2)."""
    root, _ = rendered
    source = root / "mine" / "Blocks"
    data, truths = tmp_path / "other-data" / "Blocks", tmp_path / "other-gt-flow" / "Blocks"
    shutil.copytree(source, data)
    (data / "flow12.flo").unlink()
    truths.mkdir(parents=True)
    shutil.copy(source / "flow12.flo", truths / "flow12.flo")
    sequence = datasets.read_flow_folder(data)
    assert sequence.name == "other-data/Blocks" and sequence.index == 2
    np.testing.assert_array_equal(sequence.flow, datasets.read_flo(source / "flow12.flo"))
    broken = tmp_path / "broken"
    shutil.copytree(source, broken)
    (broken / "flow12.flo").write_bytes((source / "flow12.flo").read_bytes()[:100])
    one = tmp_path / "one"
    one.mkdir()
    shutil.copy(source / "flow12.flo", one / "flow12.flo")
    shutil.copy(source / "frame12.png", one / "frame12.png")
    lack = "it holds the flow flow12.flo but one numbered frame (*NN.png), not the two it joins"
    assert datasets.flow_folders_lacking(tmp_path) == [(one, lack)]
    assert main(["eval", "flow", "--data", str(tmp_path), "-q"]) == 2
    captured = capsys.readouterr()
    assert "other-data/Blocks" in captured.out
    err = captured.err.splitlines()
    assert len(err) == 2 and any(line.startswith(f"vmcl: left out {broken}") for line in err), err
    assert any(line.startswith(f"vmcl: note: left out {one}: it holds the flow") for line in err), err


def test_the_baselines_take_frames_sliced_from_larger_arrays():
    # DIS raised cv2.error (I0.isContinuous()) on a crop of a larger frame.
    frame = np.random.default_rng(0).integers(0, 255, (100, 140)).astype(np.uint8)
    for name, method in baselines().items():
        assert method(frame[10:90, 10:130], frame[11:91, 10:130]).shape == (80, 120, 2), name


def test_evaluate_sequence_refuses_what_is_not_a_sequence_by_name():
    # A path or None met an AttributeError; a truthy string was taken for others=True.
    from vmcl.errors import InputError

    with pytest.raises(InputError, match="sequence must be a vmcl.datasets.FlowSequence"):
        evaluate_sequence("yosemite")
    with pytest.raises(InputError, match="others"):
        evaluate_sequence(datasets.FlowSequence("x", (), 0, np.zeros((2, 2, 2)), np.ones((2, 2), bool), None),
                          others="no")


def test_two_frames_of_one_number_are_never_paired(tmp_path, rendered):
    # frame012.png beside frame12.png: both were frame 12, and the pair scored was frame012 -> frame12, a frame
    # against its copy. In the scored pair it is refused naming both; in the past it ends the past, as a gap does.
    root, _ = rendered
    folder = tmp_path / "Blocks"
    shutil.copytree(root / "mine" / "Blocks", folder)
    shutil.copy(folder / "frame12.png", folder / "frame012.png")
    with pytest.raises(ValueError, match=r"holds 2 frames numbered 12 \(frame012.png, frame12.png\)"):
        datasets.read_flow_folder(folder)
    (folder / "frame012.png").unlink()
    shutil.copy(folder / "frame10.png", folder / "frame010.png")
    sequence = datasets.read_flow_folder(folder)
    assert [p.name for p in sequence.frames] == ["frame11.png", "frame12.png", "frame13.png", "frame14.png"]
    assert sequence.index == 1


def test_frames_the_evaluation_does_not_use_do_not_spoil_it(tmp_path, rendered):
    # A cut-short or RGBA frame after the scored pair (12 -> 13) made the whole folder "left out"; a grey past
    # frame among RGB ones was kept, and the stream then refused "frame 1: next has shape ..." naming no file.
    root, _ = rendered
    folder = tmp_path / "Blocks"
    shutil.copytree(root / "mine" / "Blocks", folder)
    source = root / "mine" / "Blocks"
    whole = (source / "frame14.png").read_bytes()
    (folder / "frame14.png").write_bytes(whole[:len(whole) // 2])
    names = [p.name for p in datasets.read_flow_folder(folder).frames]
    assert names == ["frame10.png", "frame11.png", "frame12.png", "frame13.png"]
    rgba = cv2.cvtColor(cv2.imread(str(source / "frame14.png")), cv2.COLOR_BGR2BGRA)
    cv2.imwrite(str(folder / "frame14.png"), rgba)
    assert [p.name for p in datasets.read_flow_folder(folder).frames] == names
    # A past frame of another colour kind ends the past there, as one of another size does.
    cv2.imwrite(str(folder / "frame11.png"), cv2.imread(str(source / "frame11.png"), cv2.IMREAD_GRAYSCALE))
    sequence = datasets.read_flow_folder(folder)
    assert [p.name for p in sequence.frames] == ["frame12.png", "frame13.png"] and sequence.index == 0
    # The past is streamed: one that cannot be read is refused by name.
    (folder / "frame11.png").write_bytes((source / "frame11.png").read_bytes()[:200])
    with pytest.raises(ValueError, match="frame11.png is damaged"):
        datasets.read_flow_folder(folder)
    # The next frame is scored: another colour kind is refused naming it.
    shutil.copy(source / "frame11.png", folder / "frame11.png")
    cv2.imwrite(str(folder / "frame13.png"), cv2.imread(str(source / "frame13.png"), cv2.IMREAD_GRAYSCALE))
    with pytest.raises(ValueError, match="frame13.png is 80 x 64 grey, the frame frame12.png 80 x 64 RGB"):
        datasets.read_flow_folder(folder)


def test_a_hand_made_sequence_with_a_frame_of_another_kind_is_refused_naming_the_file(tmp_path, rendered, machine):
    root, _ = rendered
    source = root / "mine" / "Blocks"
    grey = tmp_path / "frame11.png"
    cv2.imwrite(str(grey), cv2.imread(str(source / "frame11.png"), cv2.IMREAD_GRAYSCALE))
    read = datasets.read_flow_folder(source)
    frames = (source / "frame10.png", grey, source / "frame12.png", source / "frame13.png")
    sequence = datasets.FlowSequence("mixed", frames, 2, read.flow, read.mask)
    with pytest.raises(ValueError, match=r"frame11.png has shape \(64, 80\), the scored frame frame12.png"):
        evaluate_sequence(sequence, machine=machine, others=False)


def test_frames_are_read_as_vmcl_run_reads_them(tmp_path, rendered, machine):
    # A PPM of maxval 1020 holding 4 x the 8-bit frame is that frame at full scale (4 * 65535 / 1020 = 257):
    # read as stored it was dark, and the baselines' 8-bit frames had 5 grey levels. The same pair stored as
    # 8-bit PNGs is the oracle: the baselines see the same 8-bit frames, the machine the same brightness.
    root, _ = rendered
    source = root / "mine" / "Blocks"
    png, ppm = tmp_path / "png", tmp_path / "ppm"
    for folder in (png, ppm):
        folder.mkdir()
        shutil.copy(source / "flow12.flo", folder / "flow12.flo")
    for number in (12, 13):
        shutil.copy(source / f"frame{number}.png", png / f"frame{number}.png")
        rgb = (datasets.read_image(source / f"frame{number}.png").astype(np.uint16) * 4).astype(">u2")
        header = f"P6\n{rgb.shape[1]} {rgb.shape[0]}\n1020\n".encode()
        (ppm / f"frame{number}.ppm").write_bytes(header + rgb.tobytes())
    assert np.array_equal(datasets.read_image(ppm / "frame12.ppm", picture=True),
                          datasets.read_image(source / "frame12.png").astype(np.uint16) * 257)
    expected = {row.method: row for row in evaluate_sequence(datasets.read_flow_folder(png), machine=machine)}
    found = {row.method: row for row in evaluate_sequence(datasets.read_flow_folder(ppm), machine=machine)}
    assert set(found) == set(expected) == {"vmcl two frames", *baselines()}
    for method in baselines():
        assert (found[method].epe, found[method].aae) == (expected[method].epe, expected[method].aae), method
    assert found["vmcl two frames"].epe == pytest.approx(expected["vmcl two frames"].epe, rel=1e-3)


def test_sequences_deeper_than_the_search_are_named(tmp_path, rendered, capsys):
    # A sequence five folders down was passed over in silence by `vmcl eval flow` (find_flow_folders searches 4).
    root, _ = rendered
    shallow, deep = tmp_path / "shallow", tmp_path / "a" / "b" / "c" / "d" / "Blocks"
    shutil.copytree(root / "mine" / "Blocks", shallow)
    shutil.copytree(root / "mine" / "Blocks", deep)
    assert datasets.find_flow_folders(tmp_path) == [shallow]
    assert datasets.find_flow_folders(tmp_path, depth=5) == [deep, shallow]
    why = (f"it is a flow sequence 5 levels below {tmp_path}, deeper than the 4 levels searched (search from a "
           "folder nearer to it)")
    assert datasets.flow_folders_lacking(tmp_path) == [(deep, why)]
    assert datasets.flow_folders_lacking(tmp_path, depth=5) == []
    assert main(["eval", "flow", "--data", str(tmp_path), "-q"]) == 0
    assert f"vmcl: note: left out {deep}: {why}" in capsys.readouterr().err.splitlines()
