"""Frame sequences from disk: a folder or glob of images, a video or a file of pages, read lazily in order.

What ``vmcl run`` and :meth:`vmcl.pipeline.VisionMachine.stream` take as a sequence. Images are read with
:func:`vmcl.datasets.read_image` (so damaged files are refused by name); videos with OpenCV's
VideoCapture, and the pages of one file that holds several images (a multi-page TIFF, an animated GIF, PNG
or WebP) with OpenCV's imreadmulti; BGR frames are returned as RGB.

A folder's or pattern's files are one frame each, in :func:`frame_order`: two files of one frame (frame8.png
and frame08.png, frame10.png and frame10.jpg) are refused, and a gap in their numbering (frame09.png
followed by frame12.png) is stated in :attr:`FrameSource.notes`, since the motion from the frame before it
spans the missing frames.
"""

from __future__ import annotations

import contextlib
import glob
import itertools
import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

import numpy as np

from vmcl.datasets import IMAGE_SUFFIXES, PNG_SIGNATURE, from_opencv, read_image
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["ANIMATION_BYTES", "IMAGE_SUFFIXES", "VIDEO_SUFFIXES", "FrameSource", "frame_order", "is_sequence", "open_frames"]

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv")
"""The file suffixes (any case) read as videos."""

_INDEXED_VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".m4v")  # containers that record their frame count
_GLOB_CHARACTERS = set("*?[")
_NUMBERS = re.compile(r"(\d+(?:\.\d+)?)")  # a run of digits, with its decimals where a point and digits follow
# Formats that may hold several images in one file: TIFF pages, GIF, PNG (APNG) and WebP animations.
_PAGED_SUFFIXES = (".tif", ".tiff", ".gif", ".png", ".webp")
_PAGES_READ = 16  # a TIFF's pages read per imreadmulti call, so that a long stack is not held whole
ANIMATION_BYTES = 2**31
"""The most an animation's frames may take decoded: OpenCV decodes an animation's frames in one call (each
is drawn over the ones before it, so a call from a later frame decodes from the first again), and a longer
or larger one is refused, naming its size, rather than exhaust the memory."""


def _by_value(text: str) -> tuple:
    """``text`` with each number (decimals included) as its value, comparable with any other such key."""
    parts = _NUMBERS.split(text)
    return tuple((1, Decimal(part), "") if index % 2 else (0, Decimal(0), part) for index, part in enumerate(parts))


def frame_order(path: Path) -> tuple:
    """The sort key of a frame's file: its path with each number compared by value, so that frame9 comes
    before frame10 (as numbered frames are meant) and a timestamp 1.25 before 1.5 (a decimal point followed
    by digits is read as one: frames named by their time in seconds), then the path's own text (which
    settles 01 and 1)."""
    return _by_value(str(path)), str(path)


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
        The image files in order (empty for a video or a file of pages).
    video : Path or None
    pages : Path or None
        The one file whose pages (a multi-page TIFF) or animation frames (GIF, PNG, WebP) are the frames.
    fps : float or None
        The frame rate the video declares (OpenCV's CAP_PROP_FPS), None for images or where it declares
        none (0, not finite).
    notes : tuple of str
        What a run should say about the frames: the gaps in a folder's or pattern's numbering.
    """

    description: str
    count: int | None
    paths: tuple[Path, ...] = ()
    video: Path | None = None
    pages: Path | None = None
    fps: float | None = None
    notes: tuple[str, ...] = ()

    def name(self, index: int) -> str:
        """Where frame ``index`` comes from, for a summary's rows: its file's name, its page of the file, or
        its frame of the video."""
        if self.paths:
            return self.paths[index].name
        if self.pages is not None:
            return f"{_page_word(self.pages)} {index} of {self.pages.name}"
        return f"video frame {index}"

    def frames(self) -> Iterator[np.ndarray]:
        """The frames in order, read one at a time: uint8 or uint16, (H, W) grey or (H, W, 3) RGB."""
        if self.pages is not None:
            yield from _read_pages(self.pages, self.count or 0)
            return
        if self.video is None:
            for path in self.paths:
                yield read_image(path, picture=True, check=_refuse_pages)
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


@contextlib.contextmanager
def _opencv_quiet() -> Iterator[None]:
    """OpenCV's log silenced: it prints its decoders' complaints about a damaged file, which the caller
    reports in one line of its own."""
    import cv2

    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        yield
    finally:
        cv2.utils.logging.setLogLevel(level)


def _page_count(path: Path) -> int:
    """How many images the file holds (a TIFF's pages, an animation's frames); 1 for a format that holds
    one, and where OpenCV counts none (a damaged file: reading it says why)."""
    if path.suffix.lower() not in _PAGED_SUFFIXES:
        return 1
    import cv2

    with _opencv_quiet():
        return max(int(cv2.imcount(str(path))), 1)


def _refuse_pages(path: Path, data: bytes) -> None:
    """Refuse a frame file of a folder or pattern that holds several images (read_image would take its first
    alone, in silence), from the bytes read for its image: OpenCV counts them only from the file, which is
    opened again just where its bytes say it may hold several."""
    if _may_hold_several(path, data) and (pages := _page_count(path)) > 1:
        raise InputValueError(f"{path} holds {pages} {_page_word(path)}s, and a frame of a folder or pattern must be "
                              "one image: run the file alone to take them as a sequence")


def _may_hold_several(path: Path, data: bytes) -> bool:
    """Whether a file's bytes may hold several images: False where their header shows one (a PNG without an
    animation control chunk before its image data, a TIFF whose first page links to no other, a WebP without
    the animation flag), True where they do not tell."""
    if path.suffix.lower() not in _PAGED_SUFFIXES:
        return False
    if data.startswith(PNG_SIGNATURE):
        at = 8
        while at + 8 <= len(data):
            kind = data[at + 4:at + 8]
            if kind in (b"acTL", b"IDAT"):  # an APNG declares its frames before the image data
                return kind == b"acTL"
            at += 12 + int.from_bytes(data[at:at + 4], "big")
        return True
    if data[:4] in (b"II*\x00", b"MM\x00*"):
        def number(at: int, size: int) -> int | None:
            field = data[at:at + size]
            return int.from_bytes(field, "little" if data[:2] == b"II" else "big") if len(field) == size else None

        first = number(4, 4) or 0
        entries = number(first, 2) or 0
        return number(first + 2 + 12 * entries, 4) != 0  # the offset of the first page's next page: 0 if none
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        # A simple WebP (VP8, VP8L) is one image; an extended one (VP8X) says in its flags whether it is animated.
        return data[12:16] == b"VP8X" and (len(data) < 21 or bool(data[20] & 0x02))
    return True


def _page_word(path: Path) -> str:
    """What one image of a file of several is called: a TIFF's page, an animation's frame."""
    return "page" if path.suffix.lower() in (".tif", ".tiff") else "frame"


def _read_pages(path: Path, count: int) -> Iterator[np.ndarray]:
    """The ``count`` pages of ``path`` in order, as :func:`vmcl.datasets.read_image` returns an image (an alpha
    channel dropped where it is opaque). A TIFF's pages are read a few at a time, so that a long stack is not
    held whole: OpenCV finds a page by its offset. An animation's frames are read in one call: each is drawn
    over the ones before it, so OpenCV decodes from the first frame on every call."""
    import cv2

    batch = _PAGES_READ if _page_word(path) == "page" else max(count, 1)
    if batch > _PAGES_READ:
        with _opencv_quiet():
            ok, first = cv2.imreadmulti(str(path), 0, 1, flags=cv2.IMREAD_UNCHANGED)
        if ok and first and count * first[0].nbytes > ANIMATION_BYTES:
            raise InputValueError(f"{path}: its {count} frames of {first[0].shape[1]} x {first[0].shape[0]} take "
                                  f"{count * first[0].nbytes / 2**30:.1f} GiB decoded at once (OpenCV decodes an "
                                  f"animation whole), over {ANIMATION_BYTES / 2**30:g} GiB: convert it to a video "
                                  "or a folder of frames")
    for start in range(0, count, batch):
        wanted = min(batch, count - start)
        with _opencv_quiet():
            ok, pages = cv2.imreadmulti(str(path), start, wanted, flags=cv2.IMREAD_UNCHANGED)
        if not ok or len(pages) < wanted:  # damaged after the count was taken: the rest would be lost in silence
            raise InputValueError(f"{path}: OpenCV cannot read {_page_word(path)} {start + len(pages or ())} of its "
                                  f"{count} (damaged?)")
        for index, page in enumerate(pages, start):
            # OpenCV gives an animated GIF's frames an alpha channel, opaque but where a pixel is transparent.
            yield from_opencv(page, name=f"{path}: {_page_word(path)} {index}", opaque_alpha=True)


def _refuse_duplicates(paths: Sequence[Path]) -> None:
    """Refuse two files of one frame: the same name in one folder but for its suffix or the zeros before
    a number (frame10.png and frame10.jpg, frame8.png and frame08.png), which would run as two frames with
    no motion between them."""
    seen: dict[tuple, Path] = {}
    for path in paths:
        key = (path.parent, _by_value(path.stem))
        if key in seen:
            raise InputValueError(f"{seen[key]} and {path} are two files of one frame (their names differ only in "
                                  "their suffix or in zeros before a number): keep one, or name the files to take "
                                  "with a glob pattern")
        seen[key] = path


def _numbered(path: Path) -> tuple[tuple, int] | None:
    """A frame file's series (its folder and name but for its last number) and that number, when the name
    ends in a whole number; None otherwise (a time in seconds: its steps need not be even)."""
    parts = _NUMBERS.split(path.stem)
    if len(parts) < 3 or "." in parts[-2]:
        return None
    return (path.parent, _by_value("".join(parts[:-2]) + "#" + parts[-1])), int(parts[-2])


_GAPS_LISTED = 10  # the gaps a note lists by name; more are counted


def _numbering_gaps(paths: Sequence[Path]) -> tuple[str, ...]:
    """A note on the gaps in the frames' numbering: where a number follows the one before by at least twice
    the series' step (its least step, so frames numbered by tens have no gap every frame; a missing frame
    doubles it, where a jitter in a time stamp does not), the frames between are missing and the motion
    from the frame before the gap spans them. Refusing would be too strict: footage drops frames."""
    numbered = [_numbered(path) for path in paths]
    pairs = [(index, a[0], b[1] - a[1]) for index, (a, b) in enumerate(itertools.pairwise(numbered))
             if a is not None and b is not None and a[0] == b[0]]
    steps: dict[tuple, int] = {}
    for _, series, apart in pairs:
        steps[series] = min(steps.get(series, apart), apart)
    gaps = [f"frame {index} ({paths[index].name}) to {paths[index + 1].name}, {apart} apart"
            for index, series, apart in pairs if apart >= 2 * steps[series]]
    if not gaps:
        return ()
    step = " or ".join(str(step) for step in sorted(set(steps.values())))
    more = f"; and {len(gaps) - _GAPS_LISTED} more" if len(gaps) > _GAPS_LISTED else ""
    return (f"{len(gaps)} gap{'s' if len(gaps) > 1 else ''} in the frames' numbering, where it otherwise steps by "
            f"{step}: {'; '.join(gaps[:_GAPS_LISTED])}{more}; frames are missing there, and the motion of the frame "
            "before each gap spans them"),


def _several_series(paths: Sequence[Path]) -> tuple[str, ...]:
    """A note when the frames are several series of numbered names (left_07.png ... beside right_07.png ...):
    they are run one after another, and the motion between two series' frames means nothing."""
    series: dict[tuple, list[Path]] = {}
    for path in paths:
        numbered = _numbered(path)
        if numbered is not None:
            series.setdefault(numbered[0], []).append(path)
    if len(series) < 2:
        return ()
    named = [f"{_series_name(run[0])}: {len(run)}" for run in series.values()]
    return (f"the frames are {len(series)} series of numbered names ({', '.join(named[:4])}"
            f"{' ...' if len(named) > 4 else ''}), run one after another, so the motion from one series' last frame "
            "to the next one's first means nothing: name one series with a glob pattern (e.g. left_*.png)"),


def _series_name(path: Path) -> str:
    """A frame file's name with its frame number (the stem's last number) shown as NN: left_NN.png."""
    last = list(_NUMBERS.finditer(path.stem))[-1]
    return f"{path.stem[:last.start()]}NN{path.stem[last.end():]}{path.suffix}"


def _image_frames(paths: Sequence[Path], where: str) -> FrameSource:
    """The frame source of the image files of a folder or pattern (``where``: "in frames/"), in frame order."""
    ordered = tuple(sorted(paths, key=frame_order))
    _refuse_duplicates(ordered)
    description = f"{len(ordered)} images {where}"
    return FrameSource(description, len(ordered), ordered,
                       notes=tuple(f"{description}: {note}"
                                   for note in (*_several_series(ordered), *_numbering_gaps(ordered))))


def _is_frame(path: Path) -> bool:
    """Whether a file found in a folder or by a pattern is a frame: an image file by its suffix, not a
    hidden one (a macOS ``._frame.png`` resource file)."""
    return path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES and not path.name.startswith(".")


def is_sequence(spec: str | Path) -> bool:
    """Whether ``spec`` names a sequence (a folder, a glob pattern, a video file or an image file of several
    pages: a multi-page TIFF, an animated GIF), not one image. An image file of one page that exists is one
    image, whatever characters its name holds (``img[1].png``)."""
    text = str(spec)
    path = Path(text)
    if path.is_file() and path.suffix.lower() not in VIDEO_SUFFIXES:
        return _page_count(path) > 1  # a multi-page TIFF, an animation: its pages are the frames
    return path.is_dir() or bool(_GLOB_CHARACTERS & set(text)) or path.suffix.lower() in VIDEO_SUFFIXES


def open_frames(spec: str | Path) -> FrameSource:
    """The frames ``spec`` names.

    Parameters
    ----------
    spec : str or Path
        A folder (its files with :data:`IMAGE_SUFFIXES`), a glob pattern (``frames/*.png``: the files with
        those suffixes it matches), a video file (:data:`VIDEO_SUFFIXES`) or one image file that holds
        several (a multi-page TIFF, an animated GIF, PNG or WebP: its pages in order); hidden files (names
        starting with a dot, such as macOS's ``._frame.png``) are not frames. Files are taken in the order
        of their names, numbers in them by value (:func:`frame_order`: frame9 before frame10); a gap in
        their numbering is stated in the source's ``notes``.

    Returns
    -------
    FrameSource

    Raises
    ------
    FileNotFoundError
        The folder or video does not exist, or the pattern matches nothing.
    ValueError
        The folder holds no images, two of its files are one frame (frame8.png and frame08.png, frame10.png
        and frame10.jpg: the same name but for the suffix or a number's leading zeros), OpenCV cannot open
        the video, or ``spec`` is an image file of one page.
    """
    if not isinstance(spec, (str, Path)):
        raise InputTypeError(f"spec must be a path or pattern, got {type(spec).__name__}")
    text = str(spec)
    if not text.strip():
        raise InputValueError("spec is empty: name a folder of frames, a glob pattern or a video file")
    path = Path(text)
    if path.is_dir():
        paths = [p for p in path.iterdir() if _is_frame(p)]
        if not paths:
            raise InputValueError(f"{path}: the folder holds no images ({', '.join(IMAGE_SUFFIXES)})")
        return _image_frames(paths, f"in {path}")
    if path.is_file() and path.suffix.lower() not in VIDEO_SUFFIXES and (pages := _page_count(path)) > 1:
        animation = "" if _page_word(path) == "page" else "the animation "
        return FrameSource(f"the {pages} {_page_word(path)}s of {animation}{path}", pages, pages=path)
    if path.suffix.lower() in VIDEO_SUFFIXES and (path.is_file() or not _GLOB_CHARACTERS & set(text)):
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such video file")
        import cv2

        capture = cv2.VideoCapture(str(path))
        try:
            if not capture.isOpened():
                raise InputValueError(f"{path}: OpenCV cannot read this video")
            count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
            fps = float(capture.get(cv2.CAP_PROP_FPS))
        finally:
            capture.release()
        return FrameSource(f"video {path}", count if count > 0 else None, video=path,
                           fps=fps if math.isfinite(fps) and fps > 0 else None)
    if _GLOB_CHARACTERS & set(text) and not path.is_file():  # an image file named img[1].png is one image
        matches = [Path(p) for p in glob.glob(text)]
        paths = [p for p in matches if _is_frame(p)]
        if not paths:
            if any(p.is_file() for p in matches):
                raise InputValueError(f"{text}: the pattern matches no image ({', '.join(IMAGE_SUFFIXES)})")
            raise FileNotFoundError(f"{text}: the pattern matches no file")
        return _image_frames(paths, f"matching {text}")
    raise InputValueError(f"{text}: not a folder, a glob pattern or a video file ({', '.join(VIDEO_SUFFIXES)}), "
                          "nor an image file of several pages")
