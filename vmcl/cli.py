"""The ``vmcl`` command: run the Vision Machine, write its report, measure it on the field's data sets.

Seed section "The Vision Machine System": images in, the cartoon of labelled discontinuities and the
dense fields out (:mod:`vmcl.pipeline`, :mod:`vmcl.report`).

    vmcl demo [--out DIR] [--data SCENE|motorcycle] [--size N]
    vmcl run LEFT [RIGHT] [--next NEXT] [--config C.toml] --out DIR
    vmcl run FRAMES [RIGHT_FRAMES] [--fps N] [--config C.toml] --out DIR
    vmcl eval stereo|flow|edges --data DIR
    vmcl fit stereo|motion|colour|texture --data DIR [--data DIR ...] --out FITTED.toml [--config C.toml] [--jump PX]
             [--fix NAME=VALUE] [--refine]
    vmcl fit labelling --out WEIGHTS.json [--config C.toml] [--seeds N ...] [--size PX]
    vmcl info
    vmcl batch INPUTS... --out DIR [--frames] [--config C.toml] [--scheduler ADDRESS] [--workers N] [--threads N]
               [--zarr FIELD ...]
    (each takes --quiet / -q, no progress bars, and --debug, tracebacks for every error)

Exit statuses: 0 done; 2 bad input (a missing, unreadable, truncated or corrupt file, images of
different sizes, a bad configuration key or type, an ``--out`` vmcl may not write into) or no OpenCL
platform, reported as one line (the install hint for the latter); 1 a defect in vmcl or a library under
it, reported with its traceback; 130 interrupted (Ctrl-C), 143 stopped (SIGTERM: ``kill``, ``timeout``, a CI
cancelling) and 129 hung up (SIGHUP: the terminal closed), each reported as one line, with what the run
had begun to write removed as on any failure. ``--debug`` shows the traceback for every error, bad input
included.

vmcl writes only its own files. ``--out`` must be a new folder, an empty one, or a previous vmcl output,
which vmcl knows by the file :data:`vmcl.output_folder.MARKER` listing the files it wrote there; anything else is refused
before the run. The files are written into a hidden folder beside ``--out`` and moved into place only
when all are written; replacing a previous output touches only the files it lists, and puts them back
if the move fails or is interrupted part way. A new folder gets the mode the umask gives; an existing one
keeps its own.

Images must be at least 16 x 16 pixels. Motion (``--next``) compares patches of ``[motion] patch``
pixels (21 by default), so its frames must be at least that wide and high; its pyramid's levels follow
the frames' size unless ``[motion] levels`` sets them.

``vmcl batch`` (the ``dask`` extra) runs every item, an image, a Middlebury-layout scene folder's pair or
with ``--frames`` a frame and the next, as one task on a Dask cluster (:mod:`vmcl.distributed`), and writes
what ``vmcl run`` writes into ``--out``/<item>/ as each finishes, each folder whole or absent. Items
already there with the same settings are skipped (a rerun resumes; each output records its settings in
settings.json), those made with other settings run again; an item that fails is listed with its error in the table at
the end while the others complete, and the exit status is then 2 if every failure was bad input, else 1.
``--zarr FIELD`` also stacks that field of every item into the Zarr array ``--out``/FIELD.zarr, rewritten
from the items' fields.npz after each run (:func:`vmcl.distributed.write_zarr`); items of different sizes
are refused before any work.

``vmcl run`` on a sequence (a folder of frames, a quoted glob pattern, a video file or one file of several
images, a multi-page TIFF or an animated GIF; for a stereo sequence the right view's likewise) streams it
through the machine with the temporal terms (:meth:`vmcl.pipeline.VisionMachine.stream`, the ``[time]``
settings) and writes what :mod:`vmcl.sequence_output` describes: each frame's fields and videos of the
cartoon, flow and disparity, at ``--fps`` or else the input video's own rate. Frames are counted from 0 in
the progress bar, the summary and the errors. Two files of one frame (frame8.png and frame08.png) are
refused; a gap in the files' numbering is noted (:func:`vmcl.frame_sources.open_frames`).

``vmcl fit`` learns a cue's MRF parameters from every example with ground truth below ``--data`` (stereo
pairs with their disparity, frame pairs with their flow): the machine's own measurements beside the truth,
by maximum pseudolikelihood (:mod:`vmcl.learn.cue_fit`). It writes a TOML file that ``--config`` loads, with
a ``[fitted]`` table naming the data, the code and a hash of the parameters, checked when loaded
(:mod:`vmcl.fitted`); it replaces only a file an earlier ``vmcl fit`` wrote.

Stages that take time show a progress bar on stderr (tqdm); ``--quiet`` keeps only the results.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import signal
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from vmcl.errors import InputError, InputTypeError
from vmcl.machine import NoOpenCLPlatformError
from vmcl.output_folder import output_folder, refuse_names_present

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_DEFECT",
    "EXIT_INTERRUPTED",
    "FIELD_NAMES",
    "SCENES",
    "BadInput",
    "cue_fields",
    "evaluation_tables",
    "main",
    "parser",
    "result_fields",
    "write_output",
]

EXIT_DEFECT = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report a command stopped by Ctrl-C


class _Stopped(BaseException):
    """A stop signal (SIGTERM, SIGHUP) raised where the command is, so that what a run has begun to write
    is cleaned up as for Ctrl-C (the output folder's writer removes it on any BaseException)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def _raise_stopped(signum: int, frame: object) -> None:
    raise _Stopped(signum)


@contextlib.contextmanager
def _stop_signals_raise() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`_Stopped` while the command runs (their default kills the process
    where it stands, leaving a half-written output behind); the handlers before are put back after."""
    kinds = [getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)]
    # Only a signal left at its default: one the caller set aside (nohup ignores SIGHUP) stays theirs.
    kinds = [kind for kind in kinds if signal.getsignal(kind) is signal.SIG_DFL]
    try:
        before = {kind: signal.signal(kind, _raise_stopped) for kind in kinds}
    except ValueError:  # not the main thread (vmcl.cli.main called from a worker): signals are not ours
        yield
        return
    try:
        yield
    finally:
        for kind, handler in before.items():
            signal.signal(kind, handler)

SCENES = ("blocks", "corridor", "shadows", "textures", "cues")

class BadInput(InputError):
    """Input the command refuses: reported as one line, exit status 2."""


@contextlib.contextmanager
def _progress(args: argparse.Namespace, total: int, what: str, unit: str = "stage") -> Iterator[Callable[[str], None]]:
    """A tqdm bar of ``total`` steps on stderr (none with --quiet); yields the step callback."""
    if args.quiet:
        yield lambda name: None
        return
    from tqdm import tqdm

    with tqdm(total=total, desc=what, unit=unit, file=sys.stderr, leave=False) as bar:
        def step(name: str) -> None:
            bar.set_postfix_str(name)
            bar.update()
        yield step


def _read(path: str, what: str) -> np.ndarray:
    from vmcl.cm.core import UNIT_MARGIN
    from vmcl.datasets import read_image

    try:
        image = read_image(path, picture=True)
    except FileNotFoundError:
        raise BadInput(f"{what} image {path}: no such file") from None
    except (InputError, OSError) as error:
        raise BadInput(f"{what} image {path}: cannot be read as an image ({error})") from None
    if image.dtype.kind == "f" and image.size and np.isfinite(image).all() and float(image.max()) > 1 + UNIT_MARGIN:
        # The machine reads float brightness in [0, 1]; a file of floats on another scale (0..255) is the
        # file's to fix: the command line cannot know its full scale.
        raise BadInput(f"{what} image {path}: it holds floats up to {float(image.max()):.4g}, and vmcl reads float "
                       "images as brightness in [0, 1]: save it as an 8- or 16-bit image, or with its values "
                       "divided by its full scale")
    return image


def _config(path: str | None):
    import warnings

    from vmcl.fitted import FittedVersionWarning

    # A fitted file's version warning is the command's word to its user, not Python's with a source line.
    # Appended, the "always" comes after the user's own filters (-W, PYTHONWARNINGS): one that ignores it or
    # makes it an error still decides.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", FittedVersionWarning, append=True)
        config = _loaded_config(path)
    for warning in caught:
        if issubclass(warning.category, FittedVersionWarning):
            print(f"vmcl: warning: {warning.message}", file=sys.stderr)
        else:
            warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)
    return config


def _loaded_config(path: str | None):
    from vmcl.pipeline import Config

    if path is None:
        return Config()
    try:
        if path.lower().endswith(".json"):  # an output's settings.json: the run it records, again
            import json

            try:
                values = json.loads(Path(path).read_text(encoding="utf-8"))
            except (ValueError, RecursionError) as error:  # JSONDecodeError and UnicodeDecodeError among them
                raise BadInput(f"config {path}: not valid JSON ({str(error)[:200]})") from None
            if not isinstance(values, dict):
                raise BadInput(f"config {path}: a JSON object of sections expected, got {type(values).__name__}")
            return Config.from_dict(values)
        return Config.from_toml(path)
    except FileNotFoundError:
        raise BadInput(f"config {path}: no such file") from None
    except (InputError, OSError) as error:
        # The Config's own refusals start with the file's path, which this line has already said.
        raise BadInput(f"config {path}: {str(error).removeprefix(f'{Path(path)}: ')}") from None


def _run_machine(vm, args, left, right=None, next_=None):
    from vmcl.pipeline import as_image

    rgb = as_image(left, "left").ndim == 3
    total = len(vm.stages(right=right is not None, next=next_ is not None, rgb=rgb))
    with _progress(args, total, "vision machine") as step:
        return vm.run(left, right, next_, progress=step)


def _table_lines(rows: Sequence[Sequence[object]]) -> list[str]:
    """Rows (the header first) as lines of columns aligned by spaces."""
    widths = [max(len(str(row[i])) for row in rows) for i in range(len(rows[0]))]
    return ["  " + "  ".join(str(c).ljust(w) for c, w in zip(row, widths)) for row in rows]


def _print_table(title: str, rows: Sequence[Sequence[object]]) -> None:
    print(title)
    print("\n".join(_table_lines(rows)))


def _fmt(value: float, digits: int = 3) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.{digits}f}"


# -- demo ----------------------------------------------------------------------------------------------

def _demo_inputs(args) -> tuple[str, dict, dict]:
    """(title, images, ground truth) for the demo's data."""
    if args.data == "motorcycle":
        if args.size is not None:  # it would be run at its own size, the option dropped in silence
            raise BadInput("--size sets a rendered scene's size; --data motorcycle is a photographed pair of its "
                           "own size (741 x 500)")
        try:
            from skimage import data
        except ImportError:
            raise BadInput("--data motorcycle needs scikit-image (pip install scikit-image)") from None
        left, right, disparity = data.stereo_motorcycle()
        truth = {"disparity": np.where(np.isfinite(disparity), disparity, np.nan).astype(np.float32)}
        return "Middlebury Motorcycle (scikit-image)", {"left": left, "right": right}, truth
    from vmcl import scenes

    # Seed 2: the shipped labelling weights were fitted to seeds 0 and 1 (benchmarks/labelling.py), so the
    # label scores printed are on an image they did not see.
    size = DEMO_SIZE if args.size is None else args.size
    scene = scenes.render(scenes.preset(args.data, shape=(size, size)), seed=2, noise=0.01)
    visible = ~scene.occluded_stereo & np.isfinite(scene.disparity)
    moving = ~scene.occluded_motion & np.isfinite(scene.flow).all(axis=-1)
    truth = {"disparity": np.where(visible, scene.disparity, np.nan), "flow": np.where(moving[..., None], scene.flow, np.nan),
             "labels": scene.labels, "tolerance": scene.tolerance}
    return (f"vmcl.scenes '{args.data}' at {size} x {size}",
            {"left": scene.left, "right": scene.right, "next": scene.left_next}, truth)


def evaluation_tables(result, truth: dict) -> dict[str, list[tuple]]:
    """Tables of the run's scores against whatever ground truth there is (for the terminal and report):
    ``truth`` may hold "labels" (with "tolerance", a rendered scene's per-pixel match tolerance), "disparity"
    and "flow"."""
    from vmcl import metrics
    from vmcl.labels import Label

    tables = {}
    if "labels" in truth:
        rows: list[tuple[object, ...]] = [("discontinuities", "precision", "recall", "F", "true px")]
        # A rendered scene's tolerance: 1 px, texture-only boundaries half their texel spacing (Scene.tolerance).
        tolerance = truth.get("tolerance", 1.0)
        overall = metrics.detection_scores(result.discontinuities, truth["labels"] > 0, tolerance=tolerance)
        rows.append(("all (integrated)", _fmt(overall.precision), _fmt(overall.recall), _fmt(overall.f), overall.n_true))
        for label, score in metrics.label_scores(result.labels, truth["labels"], tolerance=tolerance).items():
            rows.append((Label(label).name.lower(), _fmt(score.precision), _fmt(score.recall), _fmt(score.f),
                         score.n_true))
        within = "1 px" if "tolerance" not in truth else "1 px (texture-only: half their texel spacing)"
        tables[f"Discontinuities within {within}"] = rows
    if "disparity" in truth and result.disparity is not None:
        rows = [("disparity", "bad 0.5", "bad 1", "bad 2", "density")]
        known = np.isfinite(truth["disparity"])
        for name, field in (("dense (MRF)", result.disparity), ("sparse (feature matcher)", result.sparse_disparity)):
            if field is None:  # the feature matcher is off by default
                continue
            s = metrics.evaluate_disparity(field, truth["disparity"], mask=known)
            rows.append((name, _fmt(s.bad[0.5]), _fmt(s.bad[1.0]), _fmt(s.bad[2.0]), _fmt(s.density)))
        tables["Disparity (share of bad pixels)"] = rows
    if "flow" in truth and result.flow is not None:
        rows = [("flow", "EPE px", "AAE deg", "density")]
        known = np.isfinite(truth["flow"]).all(axis=-1)
        for name, field in (("restored (MRF)", result.flow), ("raw (motion module)", result.raw_flow)):
            scores = metrics.evaluate_flow(field, truth["flow"], mask=known)
            rows.append((name, _fmt(scores.epe), _fmt(scores.aae, 2), _fmt(scores.density)))
        tables["Optical flow"] = rows
    return tables


def _demo(args) -> int:
    from vmcl.pipeline import VisionMachine
    from vmcl.report import write_report

    config = _config(args.config)
    with output_folder(Path(args.out)) as work:
        title, inputs, truth = _demo_inputs(args)
        vm = VisionMachine(config)
        result = _run_machine(vm, args, inputs["left"], inputs.get("right"), inputs.get("next"))
        tables = evaluation_tables(result, truth)
        print(f"{title}: {result.total_ms:.0f} ms")
        for name, rows in tables.items():
            _print_table(name, rows)
        write_report(result, work, title=f"Vision Machine demo: {title}", evaluation=tables)
    for note in result.notes:  # as vmcl run says them: what the scores above may owe to the inputs
        print(f"vmcl: note: {note}", file=sys.stderr)
    print(f"report: {Path(args.out) / 'report.html'}")
    return 0


# -- run -----------------------------------------------------------------------------------------------

def _with_models(config, models: str | None):
    """The configuration with ``vmcl run --models`` as its recognition library (checked to be one)."""
    import dataclasses

    if models is None:
        return config
    from vmcl.recognize import MODEL_SUFFIX

    if not Path(models).is_dir() or not any(Path(models).glob(f"*{MODEL_SUFFIX}")):
        # A file is no folder to learn into (learn refuses it): the advice names a folder only where it can be one.
        folder = "DIR" if Path(models).is_file() or not str(models).strip() else models
        raise BadInput(f"--models {models}: not a folder of models (make one with vmcl learn NAME IMAGES... "
                       f"--library {folder})")
    # The section's other keys (--config's transform, candidates) are kept: only the library is the option's.
    return dataclasses.replace(config, recognition=dataclasses.replace(config.recognition, models=str(models)))


def _run(args) -> int:
    from vmcl.frame_sources import is_sequence
    from vmcl.pipeline import VisionMachine

    if not str(args.out).strip():
        raise BadInput("--out must name a folder, got an empty name")
    for name, given in (("right", args.right), ("--next", args.next)):
        if given is not None and not str(given).strip():  # an unset variable: the run dropped that view
            raise BadInput(f"{name} must name an image (or be left out), got an empty name")
    if is_sequence(args.left):
        return _run_sequence(args)
    if args.fps is not None:
        raise BadInput("--fps sets a sequence's video frame rate; left is one image")
    if args.right and is_sequence(args.right):
        raise BadInput(f"right {args.right} is a sequence but left {args.left} is one image")
    config = _with_models(_config(args.config), args.models)
    left = _read(args.left, "left")
    right = _read(args.right, "right") if args.right else None
    next_ = _read(args.next, "next") if args.next else None
    for name, image in (("right", right), ("next", next_)):
        if image is not None and image.shape != left.shape:
            raise BadInput(f"{name} image is {image.shape[1]} x {image.shape[0]}"
                           f"{'' if image.ndim == left.ndim else ' ' + ('RGB' if image.ndim == 3 else 'grey')}, "
                           f"left is {left.shape[1]} x {left.shape[0]}{' RGB' if left.ndim == 3 else ' grey'}: "
                           "the images must have the same size and channels")
    with output_folder(Path(args.out)) as work:
        vm = VisionMachine(config)
        try:
            result = _run_machine(vm, args, left, right, next_)
        except InputError as error:  # the machine names its images left, right, next: say which files they are
            files = "; ".join(f"{name} is {path}" for name, path in (("left", args.left), ("right", args.right),
                                                                      ("next", args.next)) if path)
            raise BadInput(f"{error} ({files})") from None
        write_output(result, work, f"Vision Machine: {Path(args.left).name}")
    for note in result.notes:  # what the run found out about its inputs: not only in the report
        print(f"vmcl: note: {note}", file=sys.stderr)
    if result.recognition is not None:
        print(f"recognised: {recognised_text(result.recognition)}")
    print(f"{result.total_ms:.0f} ms; report: {Path(args.out) / 'report.html'}")
    return 0


def _learn(args) -> int:
    from vmcl.recognize import learn, model_path, save_model
    from vmcl.recognize.arguments import object_mask

    # Said before the learning, not after it, of the option the user typed.
    target = model_path(args.library, args.name, folder_name="--library")
    if target.exists() and not args.replace:
        raise BadInput(f"{target} exists: give --replace to replace it with the model learned now")
    images = [_read(path, "example") for path in args.images]
    masks = None
    if args.mask:
        if len(args.mask) != len(images):
            raise BadInput(f"--mask given {len(args.mask)} times for {len(images)} images: give one mask per image")
        masks = [_mask(path, image) for path, image in zip(args.mask, images)]
        # Read as learn reads a mask (0 off the object, 1 or the full scale on it), named by its file.
        masks = [object_mask(mask, f"mask {path}") for path, mask in zip(args.mask, masks)]
    model = learn(args.name, images, masks=masks, sources=[Path(p).name for p in args.images])
    path = save_model(model, args.library, replace=args.replace)
    corners = sum(len(v.corners) for v in model.views)
    # The inner markings (a solid's edges between its faces) are what tells a solid from a flat shape of its
    # outline (recognize's min_inner can require them); a user learning a solid should see they were found.
    inner = 1 - np.concatenate([v.outline for v in model.views]).mean()
    print(f"{model.name}: {len(model.views)} view{'s' * (len(model.views) != 1)}, {corners} corners, "
          f"{inner:.0%} of its boundary inner markings; wrote {path}")
    return 0


def _mask(path: str, image: np.ndarray) -> np.ndarray:
    """``vmcl learn --mask``'s image at ``path``, grey, of its example's size."""
    mask = _read(path, "mask")
    if mask.shape[:2] != image.shape[:2]:
        raise BadInput(f"mask {path} is {mask.shape[1]} x {mask.shape[0]}, its image "
                       f"{image.shape[1]} x {image.shape[0]}: a mask must have its image's size")
    if mask.ndim == 3:  # a black and white mask saved in colour; a coloured one has no one reading
        if not (mask == mask[..., :1]).all():
            raise BadInput(f"mask {path} is in colour: a mask must be black and white (0 off the object)")
        mask = mask[..., 0]
    return mask


def _frames(spec: str, what: str):
    from vmcl.frame_sources import open_frames

    try:
        return open_frames(spec)
    except FileNotFoundError as error:
        raise BadInput(f"{what}: {error}") from None
    except (InputError, OSError) as error:
        raise BadInput(f"{what}: {error}") from None


def _run_sequence(args) -> int:
    from vmcl.pipeline import VisionMachine
    from vmcl.sequence_output import SequenceWriter, frame_count

    if args.next:
        raise BadInput("--next is for one image; a sequence's next frames are its own")
    config = _with_models(_config(args.config), args.models)
    lefts = _frames(args.left, "left")
    rights = _frames(args.right, "right") if args.right else None
    if rights is not None and None not in (lefts.count, rights.count) and lefts.count != rights.count:
        raise BadInput(f"left has {lefts.count} frames ({lefts.description}), right {rights.count} "
                       f"({rights.description}): a stereo sequence needs a right view per frame")
    fps, rate_note = _sequence_fps(args.fps, lefts, rights)  # before the output folder is made: OpenCV's writer
    # would fail after the work
    vm = VisionMachine(config)
    settings = settings_text(config.to_dict())  # recorded, as a single run's are, for --config to run it again
    frames = 0
    with output_folder(Path(args.out)) as work:
        (work / SETTINGS_FILE).write_text(settings, encoding="utf-8")
        writer = SequenceWriter(work, fps=fps, title=f"Vision Machine: {lefts.description}")
        writer.notes += [note for source in (lefts, rights) if source is not None for note in source.notes]
        writer.notes += [rate_note] if rate_note else []
        with _progress(args, lefts.count or 0, "frames", unit="frame") as step:
            results = vm.stream(_reading(lefts, "left"), _reading(rights, "right") if rights else None)
            try:
                for result in results:
                    writer.add(result, lefts.name(frames))
                    step(f"frame {frames}")  # counted from 0, as sequence.md and the errors count them
                    frames += 1
                for source in (lefts, rights):
                    # A video may end a frame or two before the count its header declares (an estimate in some
                    # containers); fewer than declared is said, not left to be noticed.
                    if source is not None and source.video is not None and source.count and frames < source.count:
                        writer.notes.append(f"{source.description}: its header declares {source.count} frames; "
                                            f"{frames} were read")
            except InputError as error:
                raise BadInput(_naming_files(str(error), lefts, rights)) from None
            finally:
                writer.close()
    for note in writer.notes:
        print(f"vmcl: note: {note}", file=sys.stderr)
    if writer.noted:
        print(f"vmcl: note: {writer.noted} of the frames have notes; see {Path(args.out) / 'sequence.md'}",
              file=sys.stderr)
    print(f"{frame_count(frames)}; videos and fields in {args.out}")
    return 0


def _sequence_fps(given: float | None, lefts, rights) -> tuple[float, str | None]:
    """The videos' frame rate: ``--fps`` when given, else the rate the input video declares, else
    :data:`DEFAULT_FPS`; and a note saying where a rate not given came from (None for ``--fps``)."""
    from vmcl.sequence_output import FPS_RANGE, check_fps

    if given is not None:
        return check_fps(given, "--fps"), None
    video = next((source for source in (lefts, rights) if source is not None and source.video is not None), None)
    if video is None:
        return DEFAULT_FPS, None
    if video.fps is not None and FPS_RANGE[0] <= video.fps <= FPS_RANGE[1]:
        return video.fps, f"videos written at {video.fps:.4g} fps, the frame rate of {video.video} (--fps sets another)"
    declared = ("no frame rate" if video.fps is None
                else f"{video.fps:.4g} fps, outside {FPS_RANGE[0]:g} to {FPS_RANGE[1]:g}")
    return DEFAULT_FPS, f"{video.video} declares {declared}: videos written at {DEFAULT_FPS:g} fps (--fps sets another)"


def _naming_files(message: str, lefts, rights) -> str:
    """A stream's error about frame k ("frame k: ...", :meth:`VisionMachine.stream`) with the files of
    frame k and of the next frame, which its "next" is; one about the two views' lengths with the two
    sources."""
    if message.startswith(("rights ended", "rights holds more")):  # the views' lengths: say which sources
        return (f"{message} (left: {lefts.description}; right: {rights.description})" if rights is not None
                else message)
    found = re.match(r"frame (\d+): ", message)
    if found is None:
        return message
    index = int(found.group(1))

    def where(source, k: int) -> list[str]:
        """Frame k's file, or its page of the file or frame of the video (none past a folder's last)."""
        if source.paths:
            return [str(path) for path in source.paths[k:k + 1]]
        return [source.name(k) + (f" of {source.video}" if source.video is not None else "")]

    here = [f"left {place}" for place in where(lefts, index)]
    if rights is not None:
        here += [f"right {place}" for place in where(rights, index)]
    named = [f"frame {index} is {', '.join(here)}"] if here else []
    named += [f"the next frame is left {place}" for place in where(lefts, index + 1)]
    return f"{message} ({'; '.join(named)})" if named else message


def _reading(source, what: str):
    """The source's frames, a read failure reported as bad input naming the file."""
    try:
        yield from source.frames()
    except FileNotFoundError as error:
        raise BadInput(f"{what}: {error}") from None
    except (InputError, OSError) as error:
        raise BadInput(f"{what}: {error}") from None


def write_output(result, folder: str | os.PathLike, title: str) -> None:
    """Write what ``vmcl run`` writes for a run into ``folder``: the report (HTML and PNGs), fields.npz,
    the settings it ran with (:data:`SETTINGS_FILE`) and, where it recognised (``--models``), the objects
    found (:data:`RECOGNITION_FILE`). Files of those names already in ``folder`` are never overwritten: the
    call is refused (InputValueError) before anything is written.

    ``vmcl batch`` writes the same files for every item (on the worker that ran it), and runs an item again
    when the settings recorded in its folder are not the batch's.
    """
    from vmcl.report import write_report

    if not isinstance(folder, (str, os.PathLike)):
        raise InputTypeError(f"folder must be a path, got {type(folder).__name__}")
    folder = Path(folder)
    # write_report refuses its own names; these are refused before it writes anything.
    refuse_names_present(folder, {"fields.npz", SETTINGS_FILE, RECOGNITION_FILE}.__contains__, "the output")
    settings = settings_text(result.config.to_dict())  # before anything is written: a failure leaves nothing
    found = None if result.recognition is None else recognition_text(result.recognition)
    write_report(result, folder, title=title)
    # allow_pickle is NumPy's default; naming it tells the type checker that no field of the ** binds it.
    np.savez_compressed(folder / "fields.npz", allow_pickle=True, **result_fields(result))
    (folder / SETTINGS_FILE).write_text(settings, encoding="utf-8")
    if found is not None:
        (folder / RECOGNITION_FILE).write_text(found, encoding="utf-8")


def recognised_text(detections) -> str:
    """A run's recognised objects as the command reports them: each name with its score and the mean of
    its boundary points in the image, or "nothing"."""
    return ", ".join(f"{d.name} ({d.score:.2f}) at ({d.boundary[:, 0].mean():.0f}, {d.boundary[:, 1].mean():.0f})"
                     for d in detections) or "nothing"


RECOGNITION_FILE = "recognition.json"
"""The file of an output folder that holds the objects a run with ``--models`` recognised, for programs to read
(:func:`recognition_text`), written by a run with models (``--models``, ``[recognition] models``) alone: one
without them recognises nothing, and leaves none (a previous output's is removed with the rest of it)."""


def recognition_text(detections) -> str:
    """A run's recognised objects (:class:`vmcl.recognize.Detection`, best first) as the JSON text of
    :data:`RECOGNITION_FILE`: ``{"detections": [...]}``, each an object of its model's ``name``, the model
    ``view`` it was aligned from, its pose ``transform`` (the 3 x 3 homography, rows, taking the view's frame,
    the pixels of the example it was learned from, to the image's), ``score``, ``significance``, ``votes``,
    ``corners_found``, ``inner_found`` (null for a view with no inner markings in sight), ``corners`` (the
    view's corners in the image, [x, y] each) and ``box`` (its boundary's box in the image, [x0, y0, x1, y1]);
    ``[]`` where the run found none."""
    import json

    def box(points: np.ndarray) -> list[float] | None:
        return [*map(float, points.min(axis=0)), *map(float, points.max(axis=0))] if len(points) else None

    found = [{"name": d.name, "view": int(d.view), "transform": np.asarray(d.transform, float).tolist(),
              "score": float(d.score), "significance": float(d.significance), "votes": int(d.votes),
              "corners_found": float(d.corners_found),
              "inner_found": None if np.isnan(d.inner_found) else float(d.inner_found),
              "corners": np.asarray(d.corners, float).reshape(-1, 2).tolist(), "box": box(np.asarray(d.boundary))}
             for d in detections]
    # Strict JSON (no NaN or Infinity, which other readers refuse: a detection's numbers are finite), one
    # detection a line.
    lines = ",\n".join(f"  {json.dumps(one, allow_nan=False)}" for one in found)
    return '{"detections": [\n' + lines + "\n]}\n" if found else '{"detections": []}\n'


DEMO_SIZE = 256
"""The side of the scene ``vmcl demo`` renders when ``--size`` is not given."""

DEFAULT_FPS = 10.0
"""The frame rate of a sequence's videos when ``--fps`` is not given and no input video declares its own."""

SETTINGS_FILE = "settings.json"
"""The file of an output folder that records the run's whole configuration (:meth:`Config.to_dict`, as JSON);
``--config`` reads it back (a .json file) to run the same settings again."""


def settings_text(values: dict) -> str:
    """A configuration's values (:meth:`vmcl.pipeline.Config.to_dict`) as the JSON text of :data:`SETTINGS_FILE`:
    keys sorted, so that two runs with the same settings write the same text; the files it names
    (``labels.weights``, ``recognition.models``) absolute, so that ``--config`` reads it from anywhere."""
    import json

    def plain(value):  # a Config holds NumPy values as it was given them (np.float32(2.0) for a sigma)
        if isinstance(value, (np.generic, np.ndarray)):
            return value.tolist()
        raise InputTypeError(f"a setting of type {type(value).__name__} cannot be recorded")

    values = {section: dict(entries) for section, entries in values.items()}
    for section, key in _FILE_SETTINGS:
        named = values.get(section, {}).get(key)
        if isinstance(named, str) and named:
            values[section][key] = str(Path(named).resolve())
    return json.dumps(values, indent=1, sort_keys=True, default=plain) + "\n"


_FILE_SETTINGS = (("labels", "weights"), ("recognition", "models"))  # settings that name a file or folder


FIELD_NAMES = ("edges", "support", "labels", "boundary_strength", "hue", "colour_edges", "density", "texture_edges",
               "sparse_disparity", "first_pass_disparity", "stereo_discontinuity", "half_occluded", "out_of_range", "disparity",
               "raw_flow", "flow")
"""The Result fields fields.npz holds when the run made them; with ``restored_<cue>``, ``<cue>_line_h`` and
``<cue>_line_v`` for each cue restored (:func:`result_fields`)."""


def cue_fields(cue) -> list[str]:
    """The names of fields.npz that a registered cue's run fills (:func:`result_fields` names them)."""
    return [*cue.result_attributes(), f"restored_{cue.name}", f"{cue.name}_line_h", f"{cue.name}_line_v"]


def result_fields(result) -> dict[str, np.ndarray]:
    """The run's fields as named arrays for fields.npz."""
    out = {name: getattr(result, name) for name in FIELD_NAMES if getattr(result, name) is not None}
    for cue, restored in result.restored.items():
        out[f"restored_{cue}"] = restored
    for cue, (line_h, line_v) in result.lines.items():
        out[f"{cue}_line_h"], out[f"{cue}_line_v"] = line_h, line_v
    return out


# -- eval ----------------------------------------------------------------------------------------------

def _eval(args) -> int:
    if not str(args.data).strip():  # Path("") is the working directory: an unset variable searched it
        raise BadInput("--data must name a folder, got an empty name")
    root = Path(args.data)
    if not root.is_dir():
        raise BadInput(f"--data {root}: no such folder (the layout of ../shared/datasets)")
    return {"stereo": _eval_stereo, "flow": _eval_flow, "edges": _eval_edges}[args.benchmark](args, root)


def _fit(args) -> int:
    from vmcl.fitted import check_writable, write_fitted
    from vmcl.learn.cue_fit import fit_cue
    from vmcl.learn.pseudolikelihood import PARAMETERS
    from vmcl.pipeline import VisionMachine

    if args.cue == "labelling":
        return _fit_labelling(args)
    if not args.data:
        raise BadInput(f"vmcl fit {args.cue} needs --data: a folder of examples with ground truth")
    for option, value in (("--seeds", args.seeds), ("--size", args.size)):
        if value is not None:
            raise BadInput(f"{option} is an option of vmcl fit labelling (its renderings); {args.cue} fits --data")
    if args.jump is not None and args.cue not in ("stereo", "motion"):
        raise BadInput(f"--jump is an option of the stereo and motion fits (their truth's discontinuities); "
                       f"{args.cue}'s desired lines are its segmentation's boundaries")
    args.jump = 1.0 if args.jump is None else args.jump
    for root in args.data:
        if not Path(root).is_dir():
            raise BadInput(f"--data {root}: no such folder")
    out = Path(args.out)
    if out.suffix != ".toml":
        raise BadInput(f"--out {out}: the fitted parameters are a TOML file; name it *.toml")
    check_writable(out)  # before the long fit, not after it
    fixed = {"coupling": 1.0} if args.cue in ("stereo", "motion") else {}
    given: set[str] = set()
    for item in args.fix:
        name, _, value = item.partition("=")
        if name not in PARAMETERS:
            raise BadInput(f"--fix {item}: the parameters are {', '.join(PARAMETERS)}")
        if name in given:  # the last would win in silence
            raise BadInput(f"--fix {name} given twice: give each parameter once")
        given.add(name)
        if value == "free":
            fixed.pop(name, None)
            continue
        try:
            fixed[name] = float(value)
        except ValueError:
            raise BadInput(f"--fix {item}: {value!r} is not a number") from None
        if not math.isfinite(fixed[name]):  # 1e400 reads as inf, which the refusal would echo instead
            raise BadInput(f"--fix {item}: {value!r} is not a finite number")
    vm = VisionMachine(_config(args.config))
    print(f"Fitting the {args.cue} MRF to the examples under {', '.join(args.data)} ...", file=sys.stderr)
    found = fit_cue(args.cue, args.data, vm=vm, jump=args.jump, fixed=fixed, fixed_name="--fix", refine=args.refine)
    for line in found.left_out:
        print(f"vmcl: note: {line}", file=sys.stderr)
    provenance = {**found.provenance, **({"config": args.config} if args.config else {})}
    written = write_fitted(out, found.tables, provenance)
    fit = found.fit
    rows: list[tuple[object, ...]] = [("parameter", "natural (per T)", "standard error", "fitted")]
    rows += [(name, f"{fit.theta[name]:.4g}" if name not in fit.uninformed else "",
              f"{fit.standard_error[name]:.2g}" if name in fit.standard_error else "",
              "yes" if name in fit.fitted else "no information: kept" if name in fit.uninformed else "held")
             for name in PARAMETERS]
    _print_table(f"{args.cue}: {len(found.provenance['data'])} example(s), {fit.sites['pixels']} pixel and "
                 f"{fit.sites['lines']} line sites, {fit.iterations} Newton steps"
                 f"{'' if fit.converged else ' (not converged)'}", rows)
    if args.refine:
        before, after = found.provenance["restoration_error"]
        values = found.tables["mrf"][args.cue]
        print(f"Refined by the restorations' error: {before:.4f} -> {after:.4f} of the examples' pixels wrong "
              f"(values, missed and false lines) after {found.provenance['restoration_settings_scored']} settings"
              f"{'' if found.provenance['restoration_converged'] else ' (not converged: the evaluations ran out)'}"
              f"; written: alpha {values['alpha']:.4g}, beta {values['beta']:.4g}, edge_gain "
              f"{values['edge_gain']:.4g}, prior " + ", ".join(f"{k} {v:.3g}" for k, v in values["prior"].items()))
    if fit.uninformed:
        values = found.tables["mrf"][args.cue]
        kept = [f"{name} {values[name] if name in values else values['prior'][name]:.4g}" for name in fit.uninformed
                if name in values or name in values.get("prior", {})]
        # With --refine the restorations' error searches them further, from the configuration's values.
        how = ("the restorations' error searched them from the configuration's values" if args.refine else
               "written as the configuration gave them")
        print(f"No information in the examples on {', '.join(fit.uninformed)} (no brightness edge at a scored line "
              f"site, no vertex of that kind, or no data): {how}{': ' + ', '.join(kept) if kept else ''}")
    print(f"Wrote {written}: [mrf.{args.cue}] at T = {fit.temperature:.4g}"
          f"{' with the measuring settings of ' + args.config if args.config else ''}; load it with "
          f"--config {written}")
    return 0


def _fit_labelling(args) -> int:
    """``vmcl fit labelling``: the linear classifier fitted to rendered scenes, written as JSON."""
    import dataclasses

    from vmcl.fitted import check_writable
    from vmcl.learn.labelling_fit import fit_labeller, labeller_provenance, rendered_runs
    from vmcl.pipeline import VisionMachine

    if args.data:
        raise BadInput("vmcl fit labelling takes no --data: it renders its examples (vmcl.scenes presets), "
                       "whose labels are exact")
    for option, given in (("--refine", args.refine), ("--jump", args.jump is not None), ("--fix", bool(args.fix))):
        if given:
            raise BadInput(f"{option} is an option of the cues' MRF fits, not of vmcl fit labelling")
    args.seeds = [0, 1] if args.seeds is None else args.seeds
    args.size = 256 if args.size is None else args.size
    out = Path(args.out)
    if out.suffix != ".json":
        raise BadInput(f"--out {out}: the labelling weights are a JSON file; name it *.json")
    if args.size < 64:
        raise BadInput(f"--size {args.size}: the renderings must be at least 64 px")
    if not args.seeds or min(args.seeds) < 0:
        raise BadInput("--seeds: one or more noise seeds >= 0")
    check_writable(out)  # before the long fit, not after it
    config = _config(args.config)
    # The rule labels: the classifier is fitted to the candidates, not to an earlier classifier's labels.
    vm = VisionMachine(dataclasses.replace(config, labels=dataclasses.replace(config.labels, method="rule")))
    shape, seeds = (args.size, args.size), tuple(args.seeds)
    print(f"Running the machine on the rendered presets at {args.size} x {args.size}, seeds {seeds} ...",
          file=sys.stderr)
    runs = rendered_runs(vm, seeds=seeds, shape=shape)
    fitted_on, provenance = labeller_provenance(seeds=seeds, shape=shape, config=vm.config)
    labeller = fit_labeller(runs.values(), fitted_on=fitted_on, machine=vm.machine)
    written = labeller.save(out, provenance)
    print(f"Wrote {written}: weights for {len(labeller.weights)} sets of inputs, fitted to {len(runs)} renderings; "
          f"use it with [labels] weights = \"{written}\"")
    return 0


def _only(**sections):
    """A Config with the cues not named switched off (an evaluation runs what it measures)."""
    from vmcl.pipeline import ColourConfig, Config, MotionConfig, StereoConfig, TextureConfig

    return Config(stereo=sections.get("stereo", StereoConfig(enabled=False)),
                  motion=sections.get("motion", MotionConfig(enabled=False)),
                  colour=ColourConfig(enabled=False), texture=TextureConfig(enabled=False))


def _timed(function, *args, **kwargs):
    """``function(*args, **kwargs)`` and its wall time in ms."""
    start = time.perf_counter()
    value = function(*args, **kwargs)
    return value, (time.perf_counter() - start) * 1e3


def _eval_stereo(args, root: Path) -> int:
    from dataclasses import replace

    from vmcl.datasets import find_stereo_folders, read_stereo_folder, stereo_folders_lacking
    from vmcl.stereo_evaluation import evaluate_pair, markdown_tables, opencv_baselines, vmcl_method

    folders = find_stereo_folders(root)
    # Folders without ground truth (a benchmark's own test scenes, MiddEval3's testF) are named, not failures.
    passed_over = [_left_out(folder, lack) for folder, lack in stereo_folders_lacking(root)]
    left_out: list[str] = []
    if not folders:
        raise BadInput(f"--data {root}: no stereo scene in a Middlebury layout found (a scene's folder, or a "
                       "folder holding such folders)" + "".join(f"; {line}" for line in passed_over))
    ours = vmcl_method()  # one machine for every scene: its kernels are built once
    evaluations = []
    with _progress(args, len(folders), "stereo") as step:
        for folder in folders:
            # Named by the path under --data, so that two copies of a scene (2001 and v2) stay apart.
            name = folder.name if folder == root else folder.relative_to(root).as_posix()
            try:  # one scene that cannot be read or matched is reported, and the others are still scored
                pair = replace(read_stereo_folder(folder), name=name)
                evaluations.append(evaluate_pair(pair, [ours, *opencv_baselines(pair)]))
            except (InputError, OSError) as error:
                left_out.append(_left_out(folder, str(error)))
            step(name)
    return _scored_and_left_out(f"Stereo on {len(evaluations)} Middlebury scene(s) under {root}",
                                ["", *markdown_tables(evaluations)] if evaluations else [], left_out, passed_over)


def _left_out(folder: Path, reason: str) -> str:
    """One line saying an evaluation left ``folder`` out, and why (a reason that names the folder already
    is not prefixed with it again)."""
    prefix = f"{folder}: "
    return f"left out {folder}: {reason.removeprefix(prefix)}"


def _scored_and_left_out(heading: str, lines: Sequence[str], left_out: Sequence[str],
                         passed_over: Sequence[str] = ()) -> int:
    """Print what an evaluation scored, then each folder it passed over (holding no ground truth) and each it
    left out because it failed to read or run, and why (on stderr, one line each); the exit status is 2 (bad
    input) when any failed or nothing was scored, else 0."""
    if lines:
        print(heading)
        print("\n".join(lines))
    for line in passed_over:
        print(f"vmcl: note: {line}", file=sys.stderr)
    for line in left_out:
        print(f"vmcl: {line}", file=sys.stderr)
    if not lines:
        raise BadInput(f"{heading}: every folder was left out")
    return EXIT_BAD_INPUT if left_out else 0


def _eval_flow(args, root: Path) -> int:
    from vmcl.datasets import find_flow_folders, flow_folders_lacking, read_flow_folder
    from vmcl.flow_evaluation import evaluate_sequence
    from vmcl.machine import default_machine

    folders = find_flow_folders(root)
    passed_over = [_left_out(folder, lack) for folder, lack in flow_folders_lacking(root)]
    left_out: list[str] = []
    if not folders:
        raise BadInput(f"--data {root}: no flow sequence found (numbered frames with flowNN.flo, gt/*.flo, "
                       "Sintel's flow/ or Middlebury's other-gt-flow/)" + "".join(f"; {line}" for line in passed_over))
    rows: list[tuple[object, ...]] = [("sequence", "method", "EPE px", "matched", "unmatched", "AAE deg", "ms")]
    machine = default_machine()
    scored = 0
    # Sequences of one name in different places (a/Grove2 and b/Grove2) are told apart by their path below
    # the data's root; the others keep the name their folder gives them.
    shared = {name for name, count in Counter(folder.name for folder in folders).items() if count > 1}
    with _progress(args, len(folders), "flow", unit="sequence") as step:
        for folder in folders:
            try:  # one sequence that cannot be read or run is reported, and the others are still scored
                sequence = read_flow_folder(folder)
                if folder.name in shared:
                    sequence = replace(sequence, name=folder.relative_to(root).as_posix())
                found = evaluate_sequence(sequence, machine=machine)
            except (InputError, OSError) as error:
                left_out.append(_left_out(folder, str(error)))
                step(folder.name)
                continue
            for row in found:
                rows.append((sequence.name, row.method, _fmt(row.epe), _fmt_optional(row.epe_matched),
                             _fmt_optional(row.epe_unmatched), _fmt(row.aae, 2), f"{row.ms:.0f}"))
            scored += 1
            step(sequence.name)
    heading = ("Optical flow (average endpoint error over the valid pixels; matched / unmatched where the data "
               "marks occlusions; vmcl sequence: the frames before the scored one streamed with the temporal terms)")
    return _scored_and_left_out(heading, _table_lines(rows) if scored else [], left_out, passed_over)


def _fmt_optional(value: float | None) -> str:
    return "-" if value is None else _fmt(value)


def _eval_edges(args, root: Path) -> int:
    from vmcl.boundary_evaluation import boundary_maps, score_maps
    from vmcl.datasets import find_bsds_folders, load_bsds, read_bsds_folder

    unscorable: list[tuple[Path, str]] = []  # images that cannot be scored, and why: named, the others scored
    try:
        if (root / "bsds500" / "test").is_dir():  # the shared data sets' folder
            images = load_bsds(root).images
        else:
            # The folder itself, else the distribution's images/ and groundTruth/ below it (BSR/BSDS500/data).
            below = [] if (root / "images").is_dir() else find_bsds_folders(root)
            # BSR/ holds the benchmark's own small example beside the data (bench/data): the folders with a
            # test split are the data set.
            split = [folder for folder in below if (folder / "images" / "test").is_dir()]
            below = split or below
            if len(below) > 1:
                raise BadInput(f"--data {root}: BSDS500 layouts in {len(below)} folders below it "
                               f"({', '.join(map(str, below[:3]))}{' ...' if len(below) > 3 else ''}): give one")
            images = read_bsds_folder(below[0] if below else root, left_out=unscorable)
    except FileNotFoundError as error:
        raise BadInput(f"--data {root}: {str(error).removeprefix(f'{root}: ')}") from None
    left_out = [_left_out(image, why) for image, why in unscorable]
    if not images:
        return _scored_and_left_out(f"Boundaries under {root}", [], left_out)
    with _progress(args, len(images), "images") as step:
        sets = boundary_maps(images, thresholds=args.thresholds, progress=step)
    rows = [("method", "ODS F", "OIS F", "AP", "ms per image")]
    for maps in sets:
        s = score_maps(maps, images, workers=args.workers)
        swept = maps.thresholds > 1
        rows.append((maps.name, _fmt(s.ods_f), _fmt(s.ois_f) if swept else "-",
                     _fmt(s.average_precision) if swept else "-", f"{maps.ms_per_image:.0f}"))
    return _scored_and_left_out(f"Boundaries (BSDS500 benchmark, {len(images)} images, {args.thresholds} thresholds; "
                                "match distance 0.0075 of the diagonal)", _table_lines(rows), left_out)


# -- info ----------------------------------------------------------------------------------------------

def _info(args) -> int:
    import pyopencl as cl

    import vmcl
    from vmcl.machine import kernels_dir, list_devices

    print(f"vmcl {vmcl.__version__}; pyopencl {cl.VERSION_TEXT}")
    try:
        devices = list_devices()
    except NoOpenCLPlatformError as error:
        print(f"vmcl: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        machine = vmcl.default_machine()
    except InputError as error:
        # A VMCL_DEVICE that names no device here: the list it points the user to is printed all the same.
        machine = None
        print(f"vmcl: error: {error}", file=sys.stderr)
    chosen = machine.device if machine is not None else None
    for index, device in enumerate(devices):
        mark = "*" if device == chosen else " "
        # pyopencl's stub declares to_string in the enum's body, so mypy takes it for a member, not a method.
        kind = cl.device_type.to_string(device.type)  # type: ignore[operator]
        print(f" {mark} {index}: {device.platform.name} / {device.name} ({kind}, {device.max_compute_units} "
                   f"compute units, {device.global_mem_size // 2**20} MiB)")
    print(f"chosen (*): VMCL_DEVICE={os.environ.get('VMCL_DEVICE', '')!r} (a device's index or a part of its name), "
          "else the first (GPUs first)" + ("" if machine is not None else "; none: VMCL_DEVICE names no device here"))
    if machine is not None:
        print(f"build options: {' '.join(machine.build_options) or 'none'} (and each kernel's -D defines)")
    print(f"kernel sources: {kernels_dir()}")
    cache = os.environ.get("POCL_CACHE_DIR") or Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "pocl" / "kcache"
    print(f"kernel binary cache: {cache} (PoCL's; other drivers keep their own){_cache_contents(Path(cache))}")
    return 0 if machine is not None else EXIT_BAD_INPUT


def _cache_contents(cache: Path) -> str:
    """What PoCL's cache holds: its programs (one folder each, under two-letter folders) and their size."""
    if not cache.is_dir():
        return ": empty (the first run builds every kernel)"
    programs = [p for group in cache.iterdir() if group.is_dir() for p in group.iterdir() if p.is_dir()]
    size = sum(f.stat().st_size for p in programs for f in p.rglob("*") if f.is_file())
    return f": {len(programs)} programs built, {size / 2**20:.0f} MiB"


# -- batch ---------------------------------------------------------------------------------------------

def _batch(args) -> int:
    try:
        from vmcl import distributed
    except ImportError as error:
        raise BadInput(f"vmcl batch runs on Dask: {error}") from None

    config = _config(args.config)
    items = distributed.batch_items(args.inputs, frames=args.frames)
    fields = list(dict.fromkeys(args.zarr))
    if fields:
        try:  # before any work: the stores' names and places, and one image size over the items
            distributed.check_zarr(Path(args.out), items, fields)
        except ImportError as error:
            raise BadInput(str(error)) from None
        except InputError as error:  # said of the option the user typed, not of the function's argument
            raise BadInput(re.sub(r"^fields\[\d+\]:", "--zarr:", str(error))) from None
    with distributed.cluster_client(args.scheduler, workers=args.workers, threads=args.threads,
                                    worker_logs=args.debug) as (client, where):
        print(f"{len(items)} item(s) on the {where}", file=sys.stderr)
        with _progress(args, len(items), "batch", unit="item") as step:
            statuses = distributed.run_batch(client, items, Path(args.out), config, progress=step)
    # A done item's run notes are in its report, as a single run's are; the table says why an item failed or
    # ran again.
    rows: list[tuple[object, ...]] = [("item", "status", "ms", "error, or why it ran again")]
    rows += [(s.name, s.state, _fmt(s.total_ms, 0), s.detail) for s in statuses]
    counts = {state: sum(s.state == state for s in statuses) for state in ("done", "skipped", "failed")}
    _print_table(f"Batch into {args.out}: {counts['done']} done, {counts['skipped']} skipped (already there), "
                 f"{counts['failed']} failed", rows)
    if counts["done"]:  # the stores an earlier run built and this one did not: they lack what it wrote
        for field in (f for f in distributed.vmcl_stores(Path(args.out)) if f not in fields):
            print(f"{Path(args.out) / (field + '.zarr')} was built by an earlier run and is out of date for the "
                  f"{counts['done']} item(s) this one wrote: rerun with --zarr {field} to rebuild it", file=sys.stderr)
    for field in fields:  # from the folders on disk: a resumed batch's store holds every finished item
        store = distributed.write_zarr(Path(args.out), items, field,
                                       failed=[s.name for s in statuses if s.state == "failed"])
        line = f"{field}: {store.path} ({' x '.join(map(str, store.shape))} {store.dtype})"
        if store.filled:
            fill = "NaN" if store.dtype.kind in "fc" else "0"
            shown = ", ".join(store.filled[:5]) + (f" and {len(store.filled) - 5} more" if len(store.filled) > 5 else "")
            line += f"; {len(store.filled)} item(s) filled with {fill} (failed, or no {field}): {shown}"
        print(line)
    failed = [s for s in statuses if s.state == "failed"]
    if not failed:
        return 0
    # Every item ran or was tried: the status says whether what failed was bad input or a defect.
    return EXIT_BAD_INPUT if all(isinstance(s.error, InputError) for s in failed) else EXIT_DEFECT


# -- the parser ----------------------------------------------------------------------------------------

def parser() -> argparse.ArgumentParser:
    """The command's argument parser."""
    top = argparse.ArgumentParser(prog="vmcl", description="The MIT Vision Machine on OpenCL.")
    commands = top.add_subparsers(dest="command", required=True)
    quiet = argparse.ArgumentParser(add_help=False)
    quiet.add_argument("--quiet", "-q", action="store_true", help="no progress bars")
    quiet.add_argument("--debug", action="store_true",
                       help="show the traceback of every error, bad input and interrupts included")

    demo = commands.add_parser("demo", parents=[quiet], help="run the machine on a scene and write the report")
    demo.add_argument("--out", default="vmcl-demo",
                      help="output folder: new, empty or a previous vmcl output (default: vmcl-demo)")
    demo.add_argument("--data", default="blocks", choices=(*SCENES, "motorcycle"),
                      help="a vmcl.scenes preset (default: blocks) or scikit-image's Middlebury Motorcycle pair")
    demo.add_argument("--size", type=int, help=f"a rendered scene's size in pixels (64..1024, default {DEMO_SIZE})")
    demo.add_argument("--config", help="TOML configuration (see vmcl.pipeline.Config), or an output's settings.json")

    run = commands.add_parser("run", parents=[quiet], help="run the machine on image files or a sequence")
    run.add_argument("left", help="left image (any file OpenCV reads), or a sequence: a folder of frames, a glob "
                                  "pattern (quoted) or a video file")
    run.add_argument("right", nargs="?", help="right image of a rectified pair (adds stereo), or the right "
                                              "view's sequence")
    run.add_argument("--next", help="the left view's next frame: adds motion (one image only)")
    run.add_argument("--fps", type=float, help="a sequence's videos' frame rate, 0.01 to 1000 (default: the input "
                     f"video's, else {DEFAULT_FPS:g})")
    run.add_argument("--config", help="TOML configuration (see vmcl.pipeline.Config), or an output's settings.json")
    run.add_argument("--out", required=True, help="output folder: new, empty or a previous vmcl output")
    run.add_argument("--models", help="a library folder of models (vmcl learn): recognise them in the left image")

    learn = commands.add_parser("learn", parents=[quiet],
                                help="learn an object's model from example images into a library folder")
    learn.add_argument("name", help="the model's name (letters, digits, spaces, _ . + -)")
    learn.add_argument("images", nargs="+", metavar="IMAGE",
                       help="the examples: one image of a flat object, or a few views around a 3-D one, in order")
    learn.add_argument("--library", required=True, help="the library folder (created if missing)")
    learn.add_argument("--mask", action="append", default=[], metavar="MASK",
                       help="an image, white where the object is, per example (default: the whole image is the "
                            "object); repeat once per example")
    learn.add_argument("--replace", action="store_true", help="replace the library's model of this name")

    evaluate = commands.add_parser("eval", parents=[quiet], help="benchmarks beside OpenCV's baselines")
    evaluate.add_argument("benchmark", choices=("stereo", "flow", "edges"))
    evaluate.add_argument("--data", required=True,
                          help="stereo: a scene folder in a Middlebury layout (2001, 2003, v2, 2005/2006, "
                               "2014/2021) or any folder holding such folders; flow: a folder of numbered frames "
                               "with ground truth (Middlebury, Sintel or Yosemite layout) or any folder holding "
                               "such folders; edges: that folder (its bsds500/test images) or "
                               "any BSDS-layout folder (<id>/<id>.jpg + .mat, or images/ and groundTruth/)")
    evaluate.add_argument("--thresholds", type=int, default=30,
                          help="edges: thresholds of each sweep (default 30; the BSDS benchmark's own count is "
                               "99; each costs one matching per image and annotator)")
    evaluate.add_argument("--workers", type=int, default=1, help="edges: processes for the matching (default 1)")

    fit = commands.add_parser("fit", parents=[quiet],
                              help="learn a cue's MRF parameters from a data set with ground truth, or the "
                                   "labelling classifier's weights from rendered scenes")
    fit.add_argument("cue", choices=("stereo", "motion", "colour", "texture", "labelling"))
    fit.add_argument("--data", action="append", default=[],
                     help="a folder of examples with ground truth, searched as `vmcl eval` searches it (stereo: "
                          "Middlebury-layout scenes; motion: frames with flow; colour, texture: a BSDS-layout "
                          "folder of training images, their first annotator's segmentation); repeatable; "
                          "needed by every cue, not by labelling (it renders its own)")
    fit.add_argument("--out", required=True, help="the file to write (a cue: TOML; labelling: JSON): new, or one "
                                                  "`vmcl fit` wrote")
    fit.add_argument("--refine", action="store_true",
                     help="stereo, motion: then move the fitted parameters to lower the errors of the machine's "
                          "own restorations of the examples (vmcl.learn.fit_restoration)")
    fit.add_argument("--seeds", type=int, nargs="+", default=None,
                     help="labelling: the renderings' noise seeds (default 0 1, the shipped fit's)")
    fit.add_argument("--size", type=int, default=None,
                     help="labelling: the renderings' size in px (default 256, the shipped fit's)")
    fit.add_argument("--config", help="TOML configuration of the machine whose measurements are fitted")
    fit.add_argument("--jump", type=float, default=None,
                     help="a true discontinuity: neighbours more than this many pixels apart (default 1)")
    fit.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                     help="hold a natural parameter instead of fitting it; repeatable (stereo and motion hold "
                          "coupling=1, the energy's units, unless --fix coupling=free)")

    commands.add_parser("info", parents=[quiet], help="OpenCL platforms and devices, the kernel cache")

    batch = commands.add_parser("batch", parents=[quiet],
                                help="run the machine on many items over a Dask cluster, one output folder each")
    batch.add_argument("inputs", nargs="+", metavar="INPUT",
                       help="image files (one item each), folders of Middlebury-layout scenes (a stereo pair "
                            "each) or folders of images (one item each)")
    batch.add_argument("--out", required=True,
                       help="the batch's folder: each item's output goes to OUT/<item>/; items already there "
                            "with the same settings are skipped (a rerun resumes), those made with other settings "
                            "run again")
    batch.add_argument("--frames", action="store_true",
                       help="the images are the frames of one sequence, in order: each item is a frame and the "
                            "next (motion)")
    batch.add_argument("--config", help="TOML configuration (see vmcl.pipeline.Config), or an output's settings.json")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="a Dask scheduler (tcp://host:8786); default: a local cluster on this computer")
    batch.add_argument("--workers", type=int, help="the local cluster's worker processes (default 1)")
    batch.add_argument("--threads", type=int, help="threads per local worker (default 1)")
    batch.add_argument("--zarr", action="append", default=[], metavar="FIELD",
                       help="also stack this field of fields.npz (disparity, labels, flow, ...) over the items into "
                            "the Zarr array OUT/FIELD.zarr (items x H x W[ x C], the items' order; failed items "
                            "filled with NaN or 0); repeatable; needs the zarr package")
    return top


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``vmcl`` console script; returns the exit status."""
    top = parser()
    args, extra = top.parse_known_args(argv)
    if extra:
        hint = ""
        if args.command == "run" and all(Path(word).exists() for word in extra):
            # The shell expanded an unquoted glob into its files, which argparse meets as surplus arguments.
            hint = "; a glob of frames must be quoted, or the shell gives vmcl its files one by one ('frames/*.png')"
        top.error(f"unrecognized arguments: {' '.join(extra)}{hint}")
    if args.command == "demo" and args.size is not None and not 64 <= args.size <= 1024:
        print("vmcl: error: --size must be within 64..1024", file=sys.stderr)
        return EXIT_BAD_INPUT
    handler = {"demo": _demo, "run": _run, "eval": _eval, "fit": _fit, "info": _info, "batch": _batch,
               "learn": _learn}[args.command]
    try:
        with _stop_signals_raise():
            return handler(args)
    except KeyboardInterrupt:
        _traceback_if(args.debug)
        print("vmcl: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except _Stopped as stop:
        _traceback_if(args.debug)
        print(f"vmcl: stopped by {signal.Signals(stop.signum).name}", file=sys.stderr)
        return 128 + stop.signum
    except NoOpenCLPlatformError as error:
        _traceback_if(args.debug)
        print(f"vmcl: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except InputError as error:
        # vmcl refuses bad input with a sentence naming the argument; anything else is a defect.
        _traceback_if(args.debug)
        print(f"vmcl: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as error:  # noqa: BLE001 - the command's top: any defect is shown whole, then exit 1
        traceback.print_exc()
        print(f"vmcl: internal error: {type(error).__name__}: {error} (a defect, not bad input: please "
              "report it with the traceback above)", file=sys.stderr)
        return EXIT_DEFECT


def _traceback_if(debug: bool) -> None:
    if debug:
        traceback.print_exc()


def console() -> None:
    """The ``vmcl`` console script: :func:`main`, then the process's exit.

    After Ctrl-C the process ends at once (``os._exit``), once its output is flushed: an interrupt that
    landed inside a library's constructor (pyopencl's on-disk kernel cache, for one) leaves objects whose
    finalisers would print tracebacks at interpreter shutdown, after the one line the user was promised.
    Everything vmcl owns was already cleaned up when the interrupt unwound (:mod:`vmcl.output_folder`).
    """
    code = main()
    if code == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    console()
