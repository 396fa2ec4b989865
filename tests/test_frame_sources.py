"""Frame files read once, animations decoded once, and pages held to read_image's colour rules."""

from __future__ import annotations

import re

import cv2
import numpy as np
import pytest

from vmcl import datasets, frame_sources
from vmcl.frame_sources import _PAGES_READ, open_frames


def _rgb_frames(count: int, shape=(8, 10)) -> list[np.ndarray]:
    """Frames in colours of OpenCV's GIF palette (red and green by 36, blue by 85), so that a GIF holds them
    exactly."""
    return [np.full((*shape, 3), (36 * (k % 8), 36 * (k // 8 % 8), 85 * (k % 4)), np.uint8) for k in range(count)]


def _calls(monkeypatch, name: str) -> list:
    """The calls made to OpenCV's function ``name``, which still does its work."""
    calls: list = []
    function = getattr(cv2, name)
    monkeypatch.setattr(cv2, name, lambda *args, **kwargs: calls.append(args) or function(*args, **kwargs))
    return calls


def test_a_folders_frame_files_are_opened_once(tmp_path, monkeypatch):
    # Each frame file was opened twice: by OpenCV to count its pages, then to read its image.
    frames = _rgb_frames(3)
    for k, frame in enumerate(frames):
        assert cv2.imwrite(str(tmp_path / f"frame{k}{('.png', '.tif', '.webp')[k]}"), frame[..., ::-1],
                           [cv2.IMWRITE_WEBP_QUALITY, 101])
    counted = _calls(monkeypatch, "imcount")
    read = list(open_frames(tmp_path).frames())
    assert counted == [] and len(read) == 3 and all(np.array_equal(a, b) for a, b in zip(read, frames))
    # A file of several pages among them is still refused, naming its count.
    monkeypatch.undo()
    assert cv2.imwritemulti(str(tmp_path / "frame1.tif"), [frame[..., ::-1] for frame in frames])
    with pytest.raises(ValueError, match=re.escape(f"{tmp_path / 'frame1.tif'} holds 3 pages")):
        list(open_frames(tmp_path).frames())


@pytest.mark.parametrize("suffix", [".png", ".gif"])
def test_an_animation_is_decoded_once_per_read(tmp_path, monkeypatch, suffix):
    # An animation was read a batch of frames at a time, each batch decoded again from its first frame (and
    # OpenCV reads no APNG from a frame past its first: a longer one was refused as damaged).
    frames = _rgb_frames(_PAGES_READ + 2)
    animation = cv2.Animation()
    animation.frames, animation.durations = [frame[..., ::-1] for frame in frames], [100] * len(frames)
    path = tmp_path / f"moving{suffix}"
    assert cv2.imwriteanimation(str(path), animation)
    calls = _calls(monkeypatch, "imreadmulti")
    read = list(open_frames(path).frames())
    # One call for all the frames, after one for the first alone (its size, against ANIMATION_BYTES).
    assert len(calls) == 2 and len(read) == len(frames)
    assert all(np.array_equal(a, b) for a, b in zip(read, frames))
    # One too large to decode at once is refused, naming its size, before it is decoded.
    monkeypatch.setattr(frame_sources, "ANIMATION_BYTES", 1000)
    with pytest.raises(ValueError, match=re.escape(f"{path}: its {len(frames)} frames of")):
        next(open_frames(path).frames())
    assert len(calls) == 3


def test_a_tiffs_pages_are_read_a_few_at_a_time_as_read_image_reads_an_image(tmp_path, monkeypatch):
    frames = _rgb_frames(_PAGES_READ + 1)
    stack = tmp_path / "stack.tif"
    assert cv2.imwritemulti(str(stack), [frame[..., ::-1] for frame in frames])
    calls = _calls(monkeypatch, "imreadmulti")
    read = list(open_frames(stack).frames())
    assert len(calls) == 2 and len(read) == len(frames) and all(np.array_equal(a, b) for a, b in zip(read, frames))
    np.testing.assert_array_equal(read[0], datasets.read_image(stack))  # its first page, as read_image reads it
    # An opaque alpha channel is dropped from a page, a transparent pixel refused; read_image refuses any alpha.
    rgba = [np.dstack([frame[..., ::-1], np.full(frame.shape[:2], 255, np.uint8)]) for frame in frames[:2]]
    rgba[1][0, 0, 3] = 0
    assert cv2.imwritemulti(str(stack), rgba)
    pages = open_frames(stack).frames()
    np.testing.assert_array_equal(next(pages), frames[0])
    with pytest.raises(ValueError, match=re.escape(f"{stack}: page 1 has transparent pixels; expected grey or RGB")):
        next(pages)
    with pytest.raises(ValueError, match="has an alpha channel; expected grey or RGB"):
        datasets.read_image(stack)


def test_several_series_of_frames_in_one_folder_are_noted(tmp_path):
    # left_07..09 and right_07..09 in one folder ran as six frames, the motion from left_09 to right_07
    # among them, without a word.
    for side in ("left", "right"):
        for k in (7, 8, 9):
            assert cv2.imwrite(str(tmp_path / f"{side}_{k:02d}.png"), np.zeros((8, 8), np.uint8))
    source = open_frames(tmp_path)
    assert source.count == 6
    [note] = source.notes
    assert "the frames are 2 series of numbered names (left_NN.png: 3, right_NN.png: 3)" in note
    assert open_frames(str(tmp_path / "left_*.png")).notes == ()
