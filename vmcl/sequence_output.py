"""What ``vmcl run`` writes for a sequence: every frame's fields and videos of the cartoon, flow and disparity.

The folder (one that :func:`vmcl.output_folder.output_folder` prepared) receives

- ``fields_NNNNNN.npz``: each frame's fields, as ``fields.npz`` holds them for one run
  (:func:`vmcl.cli.result_fields`);
- ``cartoon.mp4``, ``flow.mp4``, ``disparity.mp4``: the labelled cartoon (:func:`vmcl.report.labels_image`),
  the restored flow in the Middlebury colour wheel and the restored disparity (turbo), one video frame per
  frame, for the fields the run made: flow.mp4 has one frame fewer than cartoon.mp4, since the last frame
  has no next frame to move to (a sequence of one frame has no flow.mp4), and a frame without the field
  (no flow from an all-black frame) is a black video frame, so that video frame k is sequence frame k. Colour scales are fixed by the
  first frame that has the field (its largest speed, at least :data:`LEAST_FLOW_SCALE` px per frame so that
  a clip that starts still is not drawn at full colour for its noise; its disparity range), so that colours
  mean the same speed or depth throughout. A frame of odd width or height is padded with a black row or column (MPEG-4 frames
  have even sides; the writer would crop the last row and column);
- ``sequence.md``: the videos with their frame rate and frame counts, the notes on the whole sequence (gaps
  in its numbering, the rate's source), then per frame (counted from 0), the file it came from, the time
  taken, the objects recognised (where the run has a model library) and the notes;
- ``settings.json`` (written by the command, :data:`vmcl.cli.SETTINGS_FILE`): the run's whole
  configuration, which ``--config`` reads back.

Videos are MPEG-4 (OpenCV's VideoWriter, fourcc mp4v). Files lie flat in the folder, as
:mod:`vmcl.output_folder` lists and replaces them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from vmcl.cm.core import check_real
from vmcl.output_folder import refuse_names_present
from vmcl.result import Result

__all__ = ["FOURCC", "FPS_RANGE", "LEAST_FLOW_SCALE", "SequenceWriter", "check_fps", "frame_count"]

LEAST_FLOW_SCALE = 1.0
"""The least speed (px per frame) the flow video's full colour stands for."""

FPS_RANGE = (0.01, 1000.0)
"""The frame rates the videos may be written at: OpenCV's mp4v writer refuses some beyond them (0.001 and
65536 fps fail only at the first frame, after the work) and hangs on an infinite one."""


def frame_count(frames: int) -> str:
    """"1 frame", "12 frames"."""
    return f"{frames} frame{'' if frames == 1 else 's'}"


def check_fps(fps: object, name: str) -> float:
    """``fps`` as a float within FPS_RANGE, else an InputError naming ``name``."""
    return check_real(fps, name, minimum=FPS_RANGE[0], maximum=FPS_RANGE[1])


_VIDEOS = ("cartoon", "flow", "disparity")  # the stems :meth:`SequenceWriter.pictures` makes
_FIELDS_FILE = re.compile(r"fields_\d{6,}\.npz")  # fields_{index:06d}.npz: six digits, more past a million

FOURCC = "mp4v"
"""The videos' codec, as OpenCV's VideoWriter names it."""


class SequenceWriter:
    """Writes a stream's Results into a folder, frame by frame; :meth:`close` finishes the videos.

    Parameters
    ----------
    folder : Path
        An existing folder vmcl may write into, holding no file of the names the writer writes (it is
        refused, before anything is written, rather than overwritten).
    fps : float
        The videos' frame rate, within FPS_RANGE (0.01 to 1000).
    title : str
        The summary's heading.
    """

    def __init__(self, folder: Path, *, fps: float, title: str) -> None:
        check_fps(fps, "fps")
        self.folder, self.fps, self.title = Path(folder), float(fps), title
        # How many frames come is not known yet, so any fields_NNNNNN.npz is taken.
        ours = {"sequence.md", *(f"{stem}.mp4" for stem in _VIDEOS)}
        refuse_names_present(self.folder, lambda name: name in ours or bool(_FIELDS_FILE.fullmatch(name)),
                             "the sequence")
        self.writers: dict[str, object] = {}
        self.scales: dict[str, tuple[float, float]] = {}
        self.rows: list[tuple[str, str, str]] = []  # a row's cells before, in and after the recognised column
        self.recognising = False  # whether any frame was searched for the library's objects
        self.noted = 0  # the frames with notes
        self.notes: list[str] = []  # notes on the whole sequence, written under the summary's first line
        self.frames = 0
        self.written: dict[str, int] = {}  # the frames written to each video, by its stem
        self.blank: dict[str, list[int]] = {}  # the frames each video shows black, having no field for them

    def add(self, result: Result, source: str = "") -> None:
        """Write the next frame's Result; ``source`` names where its frame came from (a file) in the summary."""
        from vmcl.cli import recognised_text, result_fields

        index = self.frames
        np.savez_compressed(self.folder / f"fields_{index:06d}.npz", allow_pickle=True,
                            **result_fields(result))
        for stem, picture in self.pictures(result).items():
            # Video frame k is sequence frame k: a frame without this field (a black frame has no flow) is
            # shown black, once a later frame has one, so that the videos stay in step.
            missing = list(range(self.written.get(stem, 0), index))
            for _ in missing:
                self.write(stem, np.zeros_like(picture))
            self.blank.setdefault(stem, []).extend(missing)
            self.write(stem, picture)
        notes = "; ".join(result.notes) if result.notes else ""
        found = "" if result.recognition is None else recognised_text(result.recognition)
        self.recognising = self.recognising or result.recognition is not None
        self.noted += bool(result.notes)
        self.rows.append((f"| {index} | {source} | {result.total_ms:.0f} | ", found, f"{notes} |"))
        self.frames += 1

    def pictures(self, result: Result) -> dict[str, np.ndarray]:
        """This frame's video pictures (uint8 RGB) by video name."""
        from vmcl.pictures import disparity_image, flow_image
        from vmcl.report import labels_image

        out = {"cartoon": labels_image(result.image, result.labels)}
        if result.flow is not None:
            if "flow" not in self.scales:
                speed = np.hypot(result.flow[..., 0], result.flow[..., 1])
                finite = speed[np.isfinite(speed)]
                self.scales["flow"] = (0.0, max(float(finite.max()) if finite.size else 0.0, LEAST_FLOW_SCALE))
            out["flow"] = flow_image(result.flow, max_flow=self.scales["flow"][1])
        if result.disparity is not None:
            if "disparity" not in self.scales:
                finite = result.disparity[np.isfinite(result.disparity)]
                low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
                self.scales["disparity"] = (low, max(high, low + 1e-3))
            low, high = self.scales["disparity"]
            out["disparity"] = disparity_image(result.disparity, vmin=low, vmax=high)
        return out

    def _videos(self) -> str:
        """The summary's line of videos: their rate and each one's frames (flow's one fewer, said why)."""
        if not self.written:
            return "videos: none"
        why = {"flow": ": the last frame has no next frame to move to"} if self.written.get("flow") == self.frames - 1 else {}
        for stem, frames in self.blank.items():
            if frames:
                shown = ", ".join(map(str, frames[:10])) + (" ..." if len(frames) > 10 else "")
                why[stem] = why.get(stem, "") + f"; {len(frames)} black, for the frames without its field: {shown}"
        return f"videos at {self.fps:.4g} fps: " + ", ".join(
            f"{stem}.mp4 ({frame_count(count)}{why.get(stem, '')})" for stem, count in sorted(self.written.items()))

    def _table(self) -> list[str]:
        """The summary's table: a column of each frame's recognised objects where the run recognised."""
        if not self.recognising:
            return ["| frame | source | ms | notes |", "|---|---|---|---|", *(a + c for a, _, c in self.rows)]
        return ["| frame | source | ms | recognised | notes |", "|---|---|---|---|---|",
                *(f"{a}{b} | {c}" for a, b, c in self.rows)]

    def write(self, stem: str, picture: np.ndarray) -> None:
        import cv2

        height, width = picture.shape[:2]
        picture = np.pad(picture, ((0, height % 2), (0, width % 2), (0, 0)))  # even sides, nothing cropped
        writer = self.writers.get(stem)
        if writer is None:
            height, width = picture.shape[:2]
            writer = cv2.VideoWriter(str(self.folder / f"{stem}.mp4"), cv2.VideoWriter.fourcc(*FOURCC), self.fps,
                                     (width, height))
            if not writer.isOpened():
                raise OSError(f"OpenCV cannot write the video {self.folder / f'{stem}.mp4'} (codec {FOURCC})")
            self.writers[stem] = writer
        writer.write(cv2.cvtColor(picture, cv2.COLOR_RGB2BGR))  # type: ignore[attr-defined]
        self.written[stem] = self.written.get(stem, 0) + 1

    def close(self) -> None:
        """Finish the videos and write the summary."""
        for writer in self.writers.values():
            writer.release()  # type: ignore[attr-defined]
        self.writers = {}
        lines = [f"# {self.title}", "", f"{frame_count(self.frames)}; {self._videos()}",
                 *(line for note in self.notes for line in ("", f"Note: {note}")), "", *self._table(), ""]
        (self.folder / "sequence.md").write_text("\n".join(lines), encoding="utf-8")
