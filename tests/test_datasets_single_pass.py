"""The flow readers do each piece of work once: one walk of a data tree, no decoding of frames nobody reads."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import cv2
import numpy as np
import pytest

from vmcl import datasets


def _sequence(folder: Path, numbers, flow: int) -> None:
    """Empty numbered frames and a flow: enough for the searches, which open no file."""
    folder.mkdir(parents=True)
    for number in numbers:
        (folder / f"frame{number}.png").touch()
    (folder / f"flow{flow}.flo").touch()


def test_flow_folders_lacking_walks_the_tree_once(tmp_path, monkeypatch):
    # It walked the tree three times: once for the folders that lack a part, once again for the sequences (as
    # find_flow_folders does), and a third time below the depth searched; each sequence was tried twice.
    near, lacking = tmp_path / "a" / "near", tmp_path / "b" / "lacking"
    deep = tmp_path / "c" / "d" / "e" / "f" / "deep"
    _sequence(near, (10, 11), 10)
    _sequence(lacking, (10,), 10)
    _sequence(deep, (10, 11), 10)
    tried: Counter = Counter()
    is_sequence = datasets._is_flow_sequence

    def counted(folder: Path) -> bool:
        tried[folder] += 1
        return is_sequence(folder)

    listed: Counter = Counter()
    iterdir = Path.iterdir

    def counted_listing(self: Path):
        listed[self] += 1
        return iterdir(self)

    monkeypatch.setattr(datasets, "_is_flow_sequence", counted)
    monkeypatch.setattr(Path, "iterdir", counted_listing)
    found = datasets.flow_folders_lacking(tmp_path)
    assert [folder for folder, _ in found] == [lacking, deep]
    assert "one numbered frame" in found[0][1] and "5 levels below" in found[1][1]
    assert deep in tried and near in tried and max(tried.values()) == 1
    # The folders that hold no flow are listed by the walk alone: each once.
    walked = [tmp_path, tmp_path / "a", tmp_path / "b", tmp_path / "c", tmp_path / "c" / "d", deep.parent]
    assert [listed[folder] for folder in walked] == [1] * len(walked)
    monkeypatch.undo()
    assert datasets.find_flow_folders(tmp_path) == [near]
    assert datasets.find_flow_folders(tmp_path, depth=5) == [near, deep]


def test_the_deeper_search_follows_no_link(tmp_path):
    # Below the depth searched the walk only looks for what to mention: a link there is not followed.
    (tmp_path / "a" / "b" / "c").mkdir(parents=True)
    _sequence(tmp_path / "elsewhere" / "seq", (10, 11), 10)
    (tmp_path / "a" / "b" / "c" / "link").symlink_to(tmp_path / "elsewhere", target_is_directory=True)
    assert datasets.flow_folders_lacking(tmp_path, depth=2) == []
    assert datasets.find_flow_folders(tmp_path, depth=5) == [tmp_path / "a" / "b" / "c" / "link" / "seq",
                                                            tmp_path / "elsewhere" / "seq"]


def _frames(folder: Path, count: int = 5) -> list[Path]:
    folder.mkdir(parents=True)
    rng = np.random.default_rng(0)
    paths = [folder / f"frame{10 + k}.png" for k in range(count)]
    for path in paths:
        cv2.imwrite(str(path), rng.integers(0, 256, (8, 10, 3), dtype=np.uint8))
    datasets.write_flo(folder / "flow12.flo", np.zeros((8, 10, 2), np.float32))
    return paths


def test_frames_after_the_scored_pair_are_not_decoded(tmp_path, monkeypatch):
    # Every frame after the scored pair (12 -> 13) was decoded, though nothing reads it.
    paths = _frames(tmp_path / "seq")
    names = {path.read_bytes(): path.name for path in paths}
    decoded = []
    decode = datasets._decode

    def recorded(data: bytes):
        decoded.append(names[data])
        return decode(data)

    monkeypatch.setattr(datasets, "_decode", recorded)
    sequence = datasets.read_flow_folder(tmp_path / "seq")
    assert [path.name for path in sequence.frames] == [path.name for path in paths] and sequence.index == 2
    assert sorted(decoded) == ["frame10.png", "frame11.png", "frame12.png", "frame13.png"]


def test_the_masks_are_applied_and_each_must_have_the_frames_size(tmp_path):
    folder = tmp_path / "clean" / "scene"
    _frames(folder, 2)
    (folder / "flow12.flo").unlink()
    for part in ("invalid", "occlusions"):
        (folder / "gt" / part).mkdir(parents=True)
    datasets.write_flo(folder / "gt" / "frame_0010.flo", np.zeros((8, 10, 2), np.float32))
    invalid, occluded = np.zeros((8, 10), np.uint8), np.zeros((8, 10), np.uint8)
    invalid[:, :2], occluded[:3] = 255, 255
    cv2.imwrite(str(folder / "gt" / "invalid" / "frame_0010.png"), invalid)
    cv2.imwrite(str(folder / "gt" / "occlusions" / "frame_0010.png"), occluded)
    sequence = datasets.read_flow_folder(folder)
    np.testing.assert_array_equal(sequence.mask, invalid == 0)
    np.testing.assert_array_equal(sequence.occluded, occluded == 255)
    cv2.imwrite(str(folder / "gt" / "occlusions" / "frame_0010.png"), occluded[:4])
    with pytest.raises(ValueError, match=r"occlusions/frame_0010.png is 10 x 4, the frame frame10.png 10 x 8"):
        datasets.read_flow_folder(folder)


def test_a_check_refuses_by_raising_not_by_returning(tmp_path):
    # A predicate's False refused nothing: the image was read as if the check had passed.
    path = tmp_path / "one.png"
    assert cv2.imwrite(str(path), np.zeros((4, 4), np.uint8))
    with pytest.raises(TypeError, match="check must refuse by raising and return None, got False"):
        datasets.read_image(path, check=lambda where, data: False)
    assert datasets.read_image(path, check=lambda where, data: None).shape == (4, 4)


def test_sintels_own_folders_of_fields_are_not_read_as_passes(tmp_path):
    # flow_viz, occlusions, invalid and disparities sit beside the passes, numbered as frames are: eval flow
    # scored the masks as frames, and counted the folders of one picture fewer as failures.
    training = tmp_path / "training"
    frame = np.zeros((8, 10), np.uint8)
    for part, count in (("clean", 4), ("final", 4), ("flow_viz", 3), ("occlusions", 3), ("invalid", 4),
                        ("disparities", 4)):
        (training / part / "alley_1").mkdir(parents=True)
        for k in range(1, count + 1):
            assert cv2.imwrite(str(training / part / "alley_1" / f"frame_{k:04d}.png"), frame + 40 * k)
    (training / "flow" / "alley_1").mkdir(parents=True)
    for k in range(1, 4):
        datasets.write_flo(training / "flow" / "alley_1" / f"frame_{k:04d}.flo", np.zeros((8, 10, 2), np.float32))
    assert datasets.find_flow_folders(tmp_path) == [training / "clean" / "alley_1", training / "final" / "alley_1"]
    assert datasets.flow_folders_lacking(tmp_path) == []
    assert datasets.read_flow_folder(training / "clean" / "alley_1").index == 2
