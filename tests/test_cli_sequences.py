"""`vmcl run` on sequences: folders, glob patterns and videos in; each frame's fields and the videos out."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from vmcl import scenes
from vmcl.cli import main
from vmcl.frame_sources import frame_order, is_sequence, open_frames
from vmcl.pipeline import Config
from vmcl.sequence_output import LEAST_FLOW_SCALE, SequenceWriter

FRAMES = 3


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """Left and right folders of a rendered stereo sequence, and the left frames as a video."""
    root = tmp_path_factory.mktemp("sequence")
    frames = scenes.render_sequence(scenes.preset("blocks", shape=(64, 64)), FRAMES, seed=0, noise=0.01)
    for side in ("left", "right"):
        (root / side).mkdir()
        for k, frame in enumerate(frames):
            image = np.round(getattr(frame, side) * 255).clip(0, 255).astype(np.uint8)
            cv2.imwrite(str(root / side / f"frame_{k:02d}.png"), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    (root / "left" / "notes.txt").write_text("not a frame")
    writer = cv2.VideoWriter(str(root / "clip.avi"), cv2.VideoWriter.fourcc(*"MJPG"), 5, (64, 64))
    for k in range(FRAMES):
        writer.write(cv2.imread(str(root / "left" / f"frame_{k:02d}.png")))
    writer.release()
    return root


def test_a_stereo_sequence_gives_each_frames_fields_and_the_videos(tmp_path, sequence):
    out = tmp_path / "out"
    assert main(["run", str(sequence / "left"), str(sequence / "right"), "--out", str(out), "-q"]) == 0
    fields = sorted(out.glob("fields_*.npz"))
    assert [p.name for p in fields] == [f"fields_{k:06d}.npz" for k in range(FRAMES)]
    with np.load(fields[0]) as first, np.load(fields[-1]) as last:
        assert first["disparity"].shape == (64, 64) and first["flow"].shape == (64, 64, 2)
        assert "flow" not in last  # the last frame has no next
    for stem, count in (("cartoon", FRAMES), ("disparity", FRAMES), ("flow", FRAMES - 1)):
        video = cv2.VideoCapture(str(out / f"{stem}.mp4"))
        assert video.isOpened(), stem
        assert int(video.get(cv2.CAP_PROP_FRAME_COUNT)) == count, stem
        video.release()
    assert "| 2 |" in (out / "sequence.md").read_text()


def test_a_glob_and_a_video_are_sequences_too(tmp_path, sequence):
    assert main(["run", str(sequence / "left" / "frame_0[01].png"), "--out", str(tmp_path / "glob"), "-q"]) == 0
    assert len(list((tmp_path / "glob").glob("fields_*.npz"))) == 2
    assert main(["run", str(sequence / "clip.avi"), "--out", str(tmp_path / "video"), "-q"]) == 0
    assert len(list((tmp_path / "video").glob("fields_*.npz"))) == FRAMES
    source = open_frames(sequence / "clip.avi")
    frame = next(source.frames())
    assert frame.shape == (64, 64, 3) and source.count == FRAMES


@pytest.mark.parametrize("case, message", [
    ("short_right", "left has 3 frames"),
    ("no_match", "matches no file"),
    ("missing_video", "no such video file"),
    ("next", "--next is for one image"),
    ("empty_folder", "holds no images"),
    # OpenCV's writer hangs on an infinite rate and refuses 65536 only at the first frame, after the work.
    ("fps_infinite", "--fps must be a finite number >= 0.01 and <= 1000.0, got inf"),
    ("fps_huge", "--fps must be a finite number >= 0.01 and <= 1000.0, got 65536.0"),
])
def test_bad_sequences_are_one_line_and_exit_2(tmp_path, sequence, capsys, case, message):
    (tmp_path / "empty").mkdir()
    right = tmp_path / "right"
    right.mkdir()
    (right / "a.png").write_bytes((sequence / "right" / "frame_00.png").read_bytes())
    argv = {"short_right": [str(sequence / "left"), str(right)],
            "no_match": [str(tmp_path / "*.png")],
            "missing_video": [str(tmp_path / "none.mp4")],
            "next": [str(sequence / "left"), "--next", str(sequence / "left" / "frame_01.png")],
            "empty_folder": [str(tmp_path / "empty")],
            "fps_infinite": [str(sequence / "left"), "--fps", "inf"],
            "fps_huge": [str(sequence / "left"), "--fps", "65536"]}[case]
    out = tmp_path / "out"
    assert main(["run", *argv, "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_open_frames_refuses_what_is_not_a_sequence(tmp_path, sequence):
    with pytest.raises(TypeError, match="spec must be a path"):
        open_frames(3)
    with pytest.raises(ValueError, match="not a folder, a glob pattern or a video"):
        open_frames(sequence / "left" / "frame_00.png")
    (tmp_path / "broken.mp4").write_bytes(b"not a video")
    with pytest.raises(ValueError, match="OpenCV cannot read this video"):
        open_frames(tmp_path / "broken.mp4")
    assert open_frames(sequence / "left").count == FRAMES  # notes.txt is not a frame


def test_numbered_frames_are_taken_in_numeric_order_and_the_summary_names_each(tmp_path, sequence):
    """frame8 ... frame11: by value, not by letter (frame10 would come first), in a folder and from a glob."""
    folder = tmp_path / "numbered"
    folder.mkdir()
    for k, number in enumerate((8, 9, 10)):
        (folder / f"f{number}.png").write_bytes((sequence / "left" / f"frame_{k:02d}.png").read_bytes())
    expected = ["f8.png", "f9.png", "f10.png"]
    assert [p.name for p in open_frames(folder).paths] == expected
    assert [p.name for p in open_frames(str(folder / "f*.png")).paths] == expected
    out = tmp_path / "out"
    assert main(["run", str(folder), "--out", str(out), "-q"]) == 0
    summary = (out / "sequence.md").read_text()
    assert [line.split("|")[2].strip() for line in summary.splitlines() if line.startswith("| ") and
            line.split("|")[1].strip().isdigit()] == expected


def test_frames_named_by_their_time_in_seconds_are_taken_in_time_order():
    # The decimals' digits compared as a whole number put 1.5 before 1.25.
    names = ["10.png", "1.5.png", "2.png", "1.25.png", "t_0.75_cam.png", "t_0.8_cam.png", "frame9.png", "frame10.png"]
    ordered = sorted((Path(name) for name in names), key=frame_order)
    assert [p.name for p in ordered] == ["1.25.png", "1.5.png", "2.png", "10.png", "frame9.png", "frame10.png",
                                         "t_0.75_cam.png", "t_0.8_cam.png"]


def test_an_image_file_whose_name_holds_glob_characters_is_one_image(tmp_path, sequence):
    for name in ("img[1].png", "a*b.png"):
        image = tmp_path / name
        image.write_bytes((sequence / "left" / "frame_00.png").read_bytes())
        assert not is_sequence(image)
        out = tmp_path / f"out{len(name)}"
        assert main(["run", str(image), "--out", str(out), "-q"]) == 0, name
        assert (out / "report.html").is_file() and not list(out.glob("fields_*.npz")), name


def test_a_frame_of_another_size_is_named_by_its_file(tmp_path, sequence, capsys):
    folder = tmp_path / "mixed"
    folder.mkdir()
    for k in range(2):
        (folder / f"frame{k}.png").write_bytes((sequence / "left" / f"frame_{k:02d}.png").read_bytes())
    cv2.imwrite(str(folder / "frame2.png"), np.zeros((48, 64, 3), np.uint8))
    assert main(["run", str(folder), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "frame 1: next has shape (48, 64, 3)" in err, err
    assert f"frame 1 is left {folder / 'frame1.png'}; the next frame is left {folder / 'frame2.png'}" in err, err


def test_a_page_of_another_size_is_named_by_its_file_and_page(tmp_path, sequence, capsys):
    # Frames of one file (a multi-page TIFF, a video) were named by neither: "frame 0: next has shape ...".
    first = cv2.imread(str(sequence / "left" / "frame_00.png"))
    stack = tmp_path / "stack.tif"
    assert cv2.imwritemulti(str(stack), [first, first[:-4], first])
    assert main(["run", str(stack), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "(frame 0 is left page 0 of stack.tif; the next frame is left page 1 of stack.tif)" in err, err


def _video(path, frames, size=(64, 48)):
    """An MJPG AVI of `frames` frames (a moving bright square)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 5, size)
    for k in range(frames):
        frame = np.full((size[1], size[0], 3), 40, np.uint8)
        frame[10:30, 5 + 2 * k:25 + 2 * k] = 220
        writer.write(frame)
    writer.release()
    return path


def test_an_empty_or_truncated_video_is_refused_and_the_earlier_output_kept(tmp_path, sequence, capsys):
    # A video of no frames "succeeded" and replaced a finished output with an empty one; a truncated one
    # was run on the frames before its damage as if they were the whole video.
    out = tmp_path / "out"
    assert main(["run", str(sequence / "clip.avi"), "--out", str(out), "-q"]) == 0
    before = sorted(p.name for p in out.iterdir())
    whole = _video(tmp_path / "whole.avi", 12)
    data = whole.read_bytes()
    (tmp_path / "truncated.avi").write_bytes(data[:len(data) // 2])
    for name, message in (("empty.avi", "holds no frames"), ("truncated.avi", "frames its header declares")):
        if name == "empty.avi":
            _video(tmp_path / name, 0)
        capsys.readouterr()
        assert main(["run", str(tmp_path / name), "--out", str(out), "-q"]) == 2
        err = capsys.readouterr().err
        assert message in err and name in err, err
        assert sorted(p.name for p in out.iterdir()) == before
    with pytest.raises(ValueError, match=r"ended after \d+ of the 12 frames"):
        list(open_frames(tmp_path / "truncated.avi").frames())
    assert len(list(open_frames(whole).frames())) == 12


def test_a_sequence_records_its_settings_for_config_to_run_again(tmp_path, sequence):
    # A sequence's output recorded no settings: --config had nothing to read back.
    (tmp_path / "mine.toml").write_text('[mrf]\nmethod = "icm"\n[time]\ngain = 2.0\n')
    out = tmp_path / "out"
    assert main(["run", str(sequence / "left"), "--config", str(tmp_path / "mine.toml"), "--out", str(out), "-q"]) == 0
    recorded = Config.from_dict(json.loads((out / "settings.json").read_text()))
    assert recorded.mrf.method == "icm" and recorded.time.gain == 2.0
    assert main(["run", str(sequence / "left"), "--config", str(out / "settings.json"), "--out", str(tmp_path / "again"),
                 "-q"]) == 0


def test_an_unquoted_glob_is_told_to_be_quoted(tmp_path, sequence, capsys):
    # The shell gives vmcl the glob's files: argparse said only "unrecognized arguments".
    frames = sorted(str(p) for p in (sequence / "left").glob("frame_*.png"))
    with pytest.raises(SystemExit) as stop:
        main(["run", *frames, "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert "a glob of frames must be quoted" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["run", frames[0], "--out", str(tmp_path / "out"), "--no-such-option"])
    assert "a glob" not in capsys.readouterr().err


def test_a_video_that_ends_before_its_declared_count_is_noted(tmp_path, capsys):
    # Two frames short of its header's count (within what a container's estimate may be off by), a video
    # was run in silence.
    data = _video(tmp_path / "whole.avi", 12).read_bytes()
    (tmp_path / "short.avi").write_bytes(data[:len(data) - 1200])
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "short.avi"), "--out", str(out), "-q"]) == 0
    note = "its header declares 12 frames; 10 were read"
    assert note in capsys.readouterr().err and note in (out / "sequence.md").read_text()
    # As the right view beside a whole left one, the short video's end was said in Python's terms, no file named.
    assert main(["run", str(tmp_path / "whole.avi"), str(tmp_path / "short.avi"), "--out", str(tmp_path / "o2"),
                 "-q"]) == 2
    err = capsys.readouterr().err
    assert "rights ended at frame 10" in err and f"right: video {tmp_path / 'short.avi'}" in err, err


@pytest.mark.parametrize("stop, status", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_a_run_stopped_by_a_signal_cleans_up_and_says_so(tmp_path, stop, status):
    # SIGTERM (kill, timeout, a CI cancelling) and SIGHUP (a closed terminal) killed the process where it
    # stood, leaving hidden half-written folders behind.
    clip = _video(tmp_path / "long.avi", 200)
    out = tmp_path / "out"
    code = "import sys; from vmcl.cli import main; sys.exit(main(sys.argv[1:]))"
    process = subprocess.Popen([sys.executable, "-c", code, "run", str(clip), "--out", str(out), "-q"],
                               stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob(".out.partial-*")) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert process.poll() is None, "the run ended before it could be stopped"
    time.sleep(0.5)  # well inside the run: frames are being written
    process.send_signal(stop)
    _, err = process.communicate(timeout=120)
    assert process.returncode == status, err
    assert f"stopped by {stop.name}" in err
    assert not out.exists() and not list(tmp_path.glob(".out*"))


def test_odd_sized_frames_are_whole_in_the_videos_and_a_still_start_is_not_full_colour(tmp_path, sequence):
    # MPEG-4 frames have even sides: the writer cropped an odd frame's last row and column. The flow video's
    # scale came from the first frame alone, so a clip starting still drew its noise at full colour.
    folder = tmp_path / "odd"
    folder.mkdir()
    for k, name in enumerate(["frame_00.png", "frame_00.png", "frame_01.png"]):
        cv2.imwrite(str(folder / f"f{k}.png"), cv2.imread(str(sequence / "left" / name))[:47, :63])
    out = tmp_path / "out"
    assert main(["run", str(folder), "--out", str(out), "-q"]) == 0
    cartoon = cv2.VideoCapture(str(out / "cartoon.mp4"))
    ok, frame = cartoon.read()
    cartoon.release()
    assert ok and frame.shape[:2] == (48, 64)
    # The frame's last row and column are drawn (a cartoon is mostly light), the padding beyond them black.
    assert frame[46, :63].mean() > 60 and frame[:47, 62].mean() > 60
    assert frame[47, :].mean() < 30 and frame[:, 63].mean() < 30
    still = SimpleNamespace(image=np.zeros((8, 8)), labels=np.zeros((8, 8), np.uint8), disparity=None,
                            flow=np.full((8, 8, 2), 0.02, np.float32))
    writer = SequenceWriter(tmp_path, fps=5.0, title="still")
    picture = writer.pictures(still)["flow"]
    assert writer.scales["flow"][1] == LEAST_FLOW_SCALE
    assert picture.min() > 240  # near white: next to no motion, drawn as next to none


def test_hidden_and_other_files_are_not_frames(tmp_path, sequence):
    # macOS leaves ._name resource files beside each frame on other disks; a glob such as frames/* also
    # meets a folder's Thumbs.db: neither is a frame, where both ended the run as undecodable images.
    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(2):
        (folder / f"f{k}.png").write_bytes((sequence / "left" / f"frame_0{k}.png").read_bytes())
        (folder / f"._f{k}.png").write_bytes(b"\x00\x05\x16\x07 AppleDouble")
    (folder / "Thumbs.db").write_bytes(b"not an image")
    for spec in (folder, folder / "*"):
        source = open_frames(spec)
        assert [p.name for p in source.paths] == ["f0.png", "f1.png"] and source.count == 2
    with pytest.raises(ValueError, match="matches no image"):
        open_frames(folder / "*.db")
    with pytest.raises(ValueError, match="spec is empty"):
        open_frames("")



def test_a_signal_the_caller_ignores_stays_ignored(tmp_path):
    # Under nohup SIGHUP is ignored: vmcl took it over, and a closed terminal stopped the run.
    clip = _video(tmp_path / "long.avi", 200)
    out = tmp_path / "out"
    code = ("import signal, sys; signal.signal(signal.SIGHUP, signal.SIG_IGN); "
            "from vmcl.cli import main; sys.exit(main(sys.argv[1:]))")
    process = subprocess.Popen([sys.executable, "-c", code, "run", str(clip), "--out", str(out), "-q"],
                               stderr=subprocess.PIPE, text=True)
    # Sent once frames are being written: during a kernel's first build, LLVM's own handler in PoCL removes
    # its temporary files on SIGHUP even when the signal is ignored, and that build fails.
    deadline = time.monotonic() + 120
    while (len(list(tmp_path.glob(".out.partial-*/fields_*.npz"))) < 3 and process.poll() is None
           and time.monotonic() < deadline):
        time.sleep(0.05)
    assert process.poll() is None, "the run ended before the signal could be sent"
    process.send_signal(signal.SIGHUP)
    _, err = process.communicate(timeout=600)
    assert process.returncode == 0, err
    assert len(list(out.glob("fields_*.npz"))) == 200


def _copies(folder, sequence, names):
    """``folder`` holding the rendered left frames 0, 1, ... under ``names``."""
    folder.mkdir()
    for k, name in enumerate(names):
        image = cv2.imread(str(sequence / "left" / f"frame_{k % FRAMES:02d}.png"))
        assert cv2.imwrite(str(folder / name), image)
    return folder


@pytest.mark.parametrize("names, first, second", [
    (["frame07.png", "frame08.png", "frame8.png"], "frame08.png", "frame8.png"),
    (["frame09.png", "frame10.jpg", "frame10.png"], "frame10.jpg", "frame10.png"),
])
def test_two_files_of_one_frame_are_refused_naming_both(tmp_path, sequence, capsys, names, first, second):
    # Both copies were run as frames, with no motion between them, and nothing said.
    folder = _copies(tmp_path / "dup", sequence, names)
    expected = f"{folder / first} and {folder / second} are two files of one frame"
    for spec in (folder, folder / "frame*"):
        with pytest.raises(ValueError, match=re.escape(expected)):
            open_frames(spec)
    out = tmp_path / "out"
    assert main(["run", str(folder), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert expected in err and len(err.strip().splitlines()) == 1 and not out.exists(), err
    if first.endswith(".jpg"):  # a glob that takes one kind of the two takes one file a frame
        assert [p.name for p in open_frames(folder / "*.png").paths] == ["frame09.png", "frame10.png"]


def test_a_gap_in_the_numbering_is_said_naming_the_frames_either_side(tmp_path, sequence, capsys):
    # frame09 followed by frame12 was run as one step, with nothing said.
    gapped = _copies(tmp_path / "gap", sequence, ["frame08.png", "frame09.png", "frame12.png"])
    note = ("1 gap in the frames' numbering, where it otherwise steps by 1: frame 1 (frame09.png) to frame12.png, "
            "3 apart; frames are missing there")
    out = tmp_path / "out"
    assert main(["run", str(gapped), "--out", str(out), "-q"]) == 0
    assert note in capsys.readouterr().err and note in (out / "sequence.md").read_text()
    (said,) = open_frames(gapped).notes
    assert said.startswith(f"3 images in {gapped}: ") and note in said
    # No gap: frames numbered by tens, a time stamp's jitter, times in seconds.
    for k, names in enumerate([["f00.png", "f10.png", "f20.png", "f30.png"],
                               ["t0.png", "t33.png", "t67.png", "t100.png"],
                               ["1.25.png", "1.5.png", "2.png", "4.png"]]):
        assert open_frames(_copies(tmp_path / f"even{k}", sequence, names)).notes == (), names
    # Two series in one folder: no gap between them, but a note that they are two.
    (series,) = open_frames(_copies(tmp_path / "series", sequence, ["a1.png", "a2.png", "b7.png", "b8.png"])).notes
    assert "2 series of numbered names (aNN.png: 2, bNN.png: 2)" in series and "frames' numbering" not in series
    # Two gaps of a series that steps by 2: both named.
    notes = open_frames(_copies(tmp_path / "two", sequence, ["s0.png", "s2.png", "s8.png", "s10.png", "s14.png"])).notes
    assert "2 gaps" in notes[0] and "steps by 2: frame 1 (s2.png) to s8.png, 6 apart; frame 3 (s10.png) to s14.png, 4 apart" \
        in notes[0], notes


def test_a_multi_page_tiff_and_an_animated_gif_are_sequences_of_their_pages(tmp_path, sequence, capsys):
    # Only a TIFF's first page was run, with no word of the others; an animated GIF was refused as having
    # an alpha channel.
    pages = [cv2.cvtColor(cv2.imread(str(sequence / "left" / f"frame_{k:02d}.png")), cv2.COLOR_BGR2RGB)
             for k in range(FRAMES)]
    stack = tmp_path / "stack.tif"
    assert cv2.imwritemulti(str(stack), [page[..., ::-1] for page in pages])
    assert is_sequence(stack)
    source = open_frames(stack)
    assert source.count == FRAMES and source.description == f"the {FRAMES} pages of {stack}"
    read = list(source.frames())
    assert len(read) == FRAMES and all(np.array_equal(a, b) for a, b in zip(read, pages))
    out = tmp_path / "out"
    assert main(["run", str(stack), "--out", str(out), "-q"]) == 0
    assert len(list(out.glob("fields_*.npz"))) == FRAMES
    assert f"| {FRAMES - 1} | page {FRAMES - 1} of stack.tif |" in (out / "sequence.md").read_text()
    # GIF frames in colours of OpenCV's GIF palette (3-3-2 bits: red and green by 36, blue by 85), so that the
    # file holds them exactly; returned as RGB, without the alpha channel OpenCV gives them.
    flat = [np.full((40, 48, 3), (36 * k, 216 - 36 * k, 85), np.uint8) for k in range(4)]
    for k, frame in enumerate(flat):
        frame[10:20, 5 + 4 * k:15 + 4 * k] = (252, 252, 255)
    animation = cv2.Animation()
    animation.frames, animation.durations = [f[..., ::-1] for f in flat], [100] * len(flat)
    gif = tmp_path / "moving.gif"
    assert cv2.imwriteanimation(str(gif), animation)
    source = open_frames(gif)
    assert source.description == f"the 4 frames of the animation {gif}" and source.name(2) == "frame 2 of moving.gif"
    read = list(source.frames())
    assert [f.shape for f in read] == [(40, 48, 3)] * 4
    assert all(np.array_equal(a, b) for a, b in zip(read, flat))
    # A file of one page is one image, as before; a file of pages among a folder's frames is refused.
    assert not is_sequence(sequence / "left" / "frame_00.png")
    folder = tmp_path / "frames"
    folder.mkdir()
    (folder / "a0.tif").write_bytes(stack.read_bytes())
    with pytest.raises(ValueError, match=re.escape(f"{folder / 'a0.tif'} holds {FRAMES} pages")):
        list(open_frames(folder).frames())


def test_the_videos_take_the_input_videos_frame_rate_unless_fps_is_given(tmp_path, capsys):
    # The videos were written at 10 fps whatever the input video's rate: a 5 fps clip played twice as fast.
    clip = _video(tmp_path / "clip.avi", 3)  # 5 fps
    for argv, rate in (([], 5.0), (["--fps", "7"], 7.0)):
        out = tmp_path / f"out{rate:g}"
        assert main(["run", str(clip), *argv, "--out", str(out), "-q"]) == 0
        err = capsys.readouterr().err
        video = cv2.VideoCapture(str(out / "cartoon.mp4"))
        assert video.get(cv2.CAP_PROP_FPS) == pytest.approx(rate)
        video.release()
        summary = (out / "sequence.md").read_text()
        assert (f"3 frames; videos at {rate:g} fps: cartoon.mp4 (3 frames), flow.mp4 (2 frames: the last frame "
                "has no next frame to move to)") in summary, summary
        said = f"videos written at 5 fps, the frame rate of {clip}"
        assert (said in err and said in summary) == (not argv), err
    assert open_frames(clip).fps == 5.0


def test_progress_counts_frames_from_0_as_the_summary_and_the_errors_do(tmp_path, sequence, monkeypatch):
    # The bar said frame 1 ... frame 3 for the summary's frames 0 ... 2.
    import tqdm

    said = []

    class Bar:
        def __init__(self, **kwargs):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def set_postfix_str(self, text):
            said.append(text)

        def update(self):
            pass

    monkeypatch.setattr(tqdm, "tqdm", Bar)
    out = tmp_path / "out"
    assert main(["run", str(sequence / "left"), "--out", str(out)]) == 0
    rows = [line.split("|")[1].strip() for line in (out / "sequence.md").read_text().splitlines()
            if line.startswith("| ") and line.split("|")[1].strip().isdigit()]
    assert said == [f"frame {row}" for row in rows] == ["frame 0", "frame 1", "frame 2"]


def test_frames_too_small_for_motion_are_refused_naming_the_frame_and_its_file(tmp_path, capsys):
    # The machine's refusal had no "frame k:" and no file, unlike the other errors of a frame.
    folder = tmp_path / "small"
    folder.mkdir()
    for k in range(3):
        cv2.imwrite(str(folder / f"f{k}.png"), np.tile(np.arange(20, dtype=np.uint8) * 10 + k, (20, 1)))
    assert main(["run", str(folder), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "frame 0: motion" in err and "patch (21) is larger than the image" in err, err
    assert f"(frame 0 is left {folder / 'f0.png'}; the next frame is left {folder / 'f1.png'})" in err, err


def test_a_one_frame_sequence_says_it_has_no_flow(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(_video(tmp_path / "one.avi", 1)), "--out", str(out), "-q"]) == 0
    summary = (out / "sequence.md").read_text()
    assert "1 frame; videos at 5 fps: cartoon.mp4 (1 frame)\n" in summary, summary
    assert "| 0 | video frame 0 |" in summary and "motion needs a next frame: no flow |" in summary, summary
    assert not (out / "flow.mp4").exists()
