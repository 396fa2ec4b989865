"""vmcl.sequence_output: the sequence writer writes only its own files."""

import re

import pytest

from vmcl.errors import InputError
from vmcl.sequence_output import SequenceWriter


@pytest.mark.parametrize("name", ["fields_000000.npz", "fields_000041.npz", "sequence.md", "cartoon.mp4"])
def test_a_folder_holding_a_name_it_writes_is_refused_before_anything_is_written(tmp_path, name):
    (tmp_path / name).write_bytes(b"the user's own")
    with pytest.raises(InputError, match=re.escape(f"folder {tmp_path} already holds {name}")):
        SequenceWriter(tmp_path, fps=5.0, title="t")
    assert [p.name for p in tmp_path.iterdir()] == [name] and (tmp_path / name).read_bytes() == b"the user's own"


def test_a_link_to_nothing_is_a_name_taken_and_other_files_are_left_to_be(tmp_path):
    elsewhere = tmp_path.parent / f"{tmp_path.name}-elsewhere.md"
    (tmp_path / "sequence.md").symlink_to(elsewhere)
    with pytest.raises(InputError, match="already holds sequence.md"):
        SequenceWriter(tmp_path, fps=5.0, title="t")
    (tmp_path / "sequence.md").unlink()
    for name in ("fields.npz", "fields_1.npz", "notes.md", "holiday.mp4"):  # none of them its own
        (tmp_path / name).write_bytes(b"the user's own")
    writer = SequenceWriter(tmp_path, fps=5.0, title="t")
    writer.close()  # no frame: only the summary
    assert (tmp_path / "sequence.md").read_text(encoding="utf-8").startswith("# t\n")
    assert not elsewhere.exists()


def test_a_frame_without_flow_is_a_black_video_frame_and_the_videos_stay_in_step(tmp_path):
    # flow.mp4 left out a frame with no flow (an all-black one): from there on its frame k was frame k + 1.
    import cv2
    import numpy as np

    from vmcl.flow_evaluation import motion_only
    from vmcl.pipeline import VisionMachine

    rng = np.random.default_rng(0)
    texture = cv2.GaussianBlur(rng.random((64, 64)).astype(np.float32), (0, 0), 1.5)
    vm = VisionMachine(motion_only())
    moving = vm.run(texture, next=np.roll(texture, 2, axis=1))
    still = vm.run(texture)  # no next frame: no flow
    assert moving.flow is not None and still.flow is None
    writer = SequenceWriter(tmp_path, fps=5.0, title="t")
    for result in (moving, still, moving, still):
        writer.add(result)
    writer.close()
    frames = []
    video = cv2.VideoCapture(str(tmp_path / "flow.mp4"))
    while True:
        ok, picture = video.read()
        if not ok:
            break
        frames.append(picture)
    video.release()
    assert len(frames) == 3  # frames 0, 1 (black) and 2; the last has no next frame to move to
    assert frames[1].max() < 20 < frames[0].max() and frames[2].max() > 20
    summary = (tmp_path / "sequence.md").read_text(encoding="utf-8")
    assert ("flow.mp4 (3 frames: the last frame has no next frame to move to; 1 black, for the frames without its "
            "field: 1)") in summary
