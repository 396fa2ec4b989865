"""Frame sequences from disk: a folder of images, a glob pattern, or a video file, read lazily in order.

What ``vmcl run`` and :meth:`vmcl.pipeline.VisionMachine.stream` take as a sequence. Images are read with
:func:`vmcl.datasets.read_image` (so damaged files are refused by name); videos with OpenCV's
VideoCapture, whose BGR frames are returned as RGB.
"""

from __future__ import annotations

import glob
import re
from collections.abc import Iterator
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

import numpy as np

from vmcl.datasets import IMAGE_SUFFIXES, read_image
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["IMAGE_SUFFIXES", "VIDEO_SUFFIXES", "FrameSource", "frame_order", "is_sequence", "open_frames"]

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv")
"""The file suffixes (any case) read as videos."""

_INDEXED_VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".m4v")  # containers that record their frame count
_GLOB_CHARACTERS = set("*?[")
_NUMBERS = re.compile(r"(\d+(?:\.\d+)?)")  # a run of digits, with its decimals where a point and digits follow


def frame_order(path: Path) -> tuple:
    """The sort key of a frame's file: its path with each number compared by value, so that frame9 comes
    before frame10 (as numbered frames are meant) and a timestamp 1.25 before 1.5 (a decimal point followed
    by digits is read as one: frames named by their time in seconds), then the path's own text (which
    settles 01 and 1)."""
    parts = _NUMBERS.split(str(path))
    return (tuple((1, Decimal(part), "") if index % 2 else (0, Decimal(0), part) for index, part in enumerate(parts)),
            str(path))


@dataclass(frozen=True)
class FrameSource:
    """A sequence of frames on disk.

    Attributes
    ----------
    description : str
        What it is, for messages ("12 images in frames/", "video clip.mp4").
    count : int or None
        The number of frames (a video's own count may be an estimate), None when unknown. Reading a video
        that holds no frames, or ends before the count its header declares (truncated or damaged: more
        than two frames short, or for containers that do not record the count, than a twentieth),
        raises ValueError naming it, after the frames it did read.
    paths : tuple of Path
        The image files in order (empty for a video).
    video : Path or None
    """

    description: str
    count: int | None
    paths: tuple[Path, ...] = ()
    video: Path | None = None

    def frames(self) -> Iterator[np.ndarray]:
        """The frames in order, read one at a time: uint8 or uint16, (H, W) grey or (H, W, 3) RGB."""
        if self.video is None:
            for path in self.paths:
                yield read_image(path, picture=True)
            return
        import cv2

        capture = cv2.VideoCapture(str(self.video))
        read = 0
        try:
            while True:
                ok, frame = capture.read()
                if not ok:
                    break
                read += 1
                yield cv2.cvtColor(frame, cv2.COLOR_BGR2RGB) if frame.ndim == 3 else frame
        finally:
            capture.release()
        # A video that ends before the count its header declares is truncated or damaged: a run on the
        # frames before the damage would stand for the whole video. OpenCV's count can be a frame or two
        # high for a whole video (edit lists, B-frames), and containers whose count it only estimates
        # from the duration are let off a twentieth.
        indexed = self.video.suffix.lower() in _INDEXED_VIDEO_SUFFIXES
        slack = 0 if not self.count else 2 if indexed else max(2, self.count // 20)
        if self.count and read < self.count - slack:
            raise InputValueError(f"{self.video}: the video ended after {read} of the {self.count} frames its header "
                                  "declares: it is truncated or damaged")
        if not read:
            raise InputValueError(f"{self.video}: the video holds no frames OpenCV can read")


def _is_frame(path: Path) -> bool:
    """Whether a file found in a folder or by a pattern is a frame: an image file by its suffix, not a
    hidden one (a macOS ``._frame.png`` resource file)."""
    return path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES and not path.name.startswith(".")


def is_sequence(spec: str | Path) -> bool:
    """Whether ``spec`` names a sequence (a folder, a glob pattern or a video file), not one image. An image
    file that exists is one image, whatever characters its name holds (``img[1].png``)."""
    text = str(spec)
    path = Path(text)
    if path.is_file() and path.suffix.lower() not in VIDEO_SUFFIXES:
        return False
    return path.is_dir() or bool(_GLOB_CHARACTERS & set(text)) or path.suffix.lower() in VIDEO_SUFFIXES


def open_frames(spec: str | Path) -> FrameSource:
    """The frames ``spec`` names.

    Parameters
    ----------
    spec : str or Path
        A folder (its files with :data:`IMAGE_SUFFIXES`), a glob pattern (``frames/*.png``: the files with
        those suffixes it matches) or a video file (:data:`VIDEO_SUFFIXES`); hidden files (names starting
        with a dot, such as macOS's ``._frame.png``) are not frames. Files are taken in the order of their
        names, numbers in them by value (:func:`frame_order`: frame9 before frame10).

    Returns
    -------
    FrameSource

    Raises
    ------
    FileNotFoundError
        The folder or video does not exist, or the pattern matches nothing.
    ValueError
        The folder holds no images, or OpenCV cannot open the video.
    """
    if not isinstance(spec, (str, Path)):
        raise InputTypeError(f"spec must be a path or pattern, got {type(spec).__name__}")
    text = str(spec)
    if not text.strip():
        raise InputValueError("spec is empty: name a folder of frames, a glob pattern or a video file")
    path = Path(text)
    if path.is_dir():
        paths = tuple(sorted((p for p in path.iterdir() if _is_frame(p)), key=frame_order))
        if not paths:
            raise InputValueError(f"{path}: the folder holds no images ({', '.join(IMAGE_SUFFIXES)})")
        return FrameSource(f"{len(paths)} images in {path}", len(paths), paths)
    if path.suffix.lower() in VIDEO_SUFFIXES and (path.is_file() or not _GLOB_CHARACTERS & set(text)):
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such video file")
        import cv2

        capture = cv2.VideoCapture(str(path))
        try:
            if not capture.isOpened():
                raise InputValueError(f"{path}: OpenCV cannot read this video")
            count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
        finally:
            capture.release()
        return FrameSource(f"video {path}", count if count > 0 else None, video=path)
    if _GLOB_CHARACTERS & set(text) and not path.is_file():  # an image file named img[1].png is one image
        matches = [Path(p) for p in glob.glob(text)]
        paths = tuple(sorted((p for p in matches if _is_frame(p)), key=frame_order))
        if not paths:
            if any(p.is_file() for p in matches):
                raise InputValueError(f"{text}: the pattern matches no image ({', '.join(IMAGE_SUFFIXES)})")
            raise FileNotFoundError(f"{text}: the pattern matches no file")
        return FrameSource(f"{len(paths)} images matching {text}", len(paths), paths)
    raise InputValueError(f"{text}: not a folder, a glob pattern or a video file ({', '.join(VIDEO_SUFFIXES)})")
