"""Batches and sequences on Dask: one Machine per worker process, NumPy arrays in and Results out.

A data set, a long video or a parameter sweep outgrows one machine; :mod:`dask.distributed` runs the
same code on a laptop (a ``LocalCluster``), on SSH hosts, Kubernetes, SLURM (dask-jobqueue) or a cloud
service. An OpenCL context, queue or kernel cannot be pickled, and a forked child reusing its parent's
PoCL context hangs, so nothing of OpenCL ever travels: each worker process (spawned, Dask's default
start method) makes its own :class:`vmcl.Machine` once, through :class:`MachinePlugin`, and keeps it in
this module's per-process cache (:func:`worker_machine`); tasks carry NumPy arrays and the Config as a
dict, and return :class:`vmcl.result.Result` (NumPy fields and a Config dataclass, both picklable).

- :func:`map_frames` runs the machine on each frame, pair or triple: futures of Results.
- :func:`map_sequence` splits a video into chunks of frame pairs (t, t + 1), one task each, and
  :func:`stitch` puts the chunks' Results back in order. Every pair is run on its own, as
  :meth:`vmcl.pipeline.VisionMachine.run` runs it: the Results are those of
  :meth:`~vmcl.pipeline.VisionMachine.stream` with ``[time] enabled = false``, one per pair. The temporal
  terms (each cue's restoration carried from frame to frame, :mod:`vmcl.temporal`) need every earlier
  frame's Result, so they come only from the sequential stream (``vmcl run`` on a sequence).
- :func:`batch_items` and :func:`run_batch` are the ``vmcl batch`` command: every item an output folder
  written whole or not at all (:func:`vmcl.output_folder.output_folder`), finished items skipped on a
  rerun, failed items reported by name with their error while the rest complete.
- :func:`check_zarr` and :func:`write_zarr` are ``vmcl batch --zarr FIELD``: one field of every item stacked
  into a Zarr array ``out``/<FIELD>.zarr of shape (items, H, W[, C]), rewritten from the items' fields.npz
  after each run (the ``zarr`` package, in the ``dask`` extra).

Dask reruns the tasks of a worker that died on another worker (``distributed.scheduler.allowed-failures``,
3 by default, bounds how many deaths one task may witness); a task that raises is run once more
(``retries=1``) before its error is reported.

Examples
--------
>>> from distributed import Client, LocalCluster  # doctest: +SKIP
>>> with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:  # doctest: +SKIP
...     client.register_plugin(MachinePlugin())
...     results = client.gather(map_frames(client, [(left, right), (left2, right2)]))
"""

from __future__ import annotations

import contextlib
import importlib.util
import itertools
import json
import math
import os
import re
import secrets
import shutil
import tempfile
import threading
import uuid
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

try:
    from distributed import Client, Future, LocalCluster, WorkerPlugin, as_completed
except ImportError as _missing:  # an optional extra: say which one
    raise ImportError("vmcl.distributed needs Dask's distributed scheduler: pip install 'vmcl[dask]'") from _missing

from vmcl.cm.core import check_int
from vmcl.datasets import IMAGE_SUFFIXES
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.output_folder import MARKER, is_whole, output_folder
from vmcl.pipeline import Config, VisionMachine
from vmcl.result import Result

__all__ = [
    "IMAGE_SUFFIXES",
    "ZARR_WRITER",
    "BatchItem",
    "ItemOutput",
    "ItemStatus",
    "LocalClusterSize",
    "MachinePlugin",
    "ZarrStore",
    "batch_items",
    "check_zarr",
    "cluster_client",
    "local_cluster_size",
    "map_frames",
    "map_sequence",
    "render_item",
    "run_batch",
    "run_chunk",
    "run_frame",
    "stitch",
    "vmcl_stores",
    "worker_machine",
    "write_zarr",
]

# ----------------------------------------------------------------------------------- the worker's side

_lock = threading.Lock()
_machine: Machine | None = None
_machine_device: str | int | None = None
_machines: dict[str, VisionMachine] = {}
_MAX_CONFIGS = 8  # VisionMachines kept per process, one per Config seen (a sweep's configs)


def _make_machine(device: str | int | None) -> Machine:
    if isinstance(device, int) and device < 0:
        raise InputValueError(f"device: index {device} is negative; vmcl info lists the devices from 0")
    # Profiling, as a VisionMachine's own Machine: the report's kernel table is that of `vmcl run`. An index
    # is given as its digits, which Machine takes as one.
    return Machine(str(device) if isinstance(device, int) else device, profile=True)


def worker_machine() -> Machine:
    """This process's Machine: the one :class:`MachinePlugin` made, else one on the default device.

    Made once per process and kept: every task a worker runs shares it (and so its built kernels).
    The default device is ``VMCL_DEVICE`` of the worker's environment, else the first (GPUs first).
    """
    global _machine
    with _lock:
        if _machine is None:
            _machine = _make_machine(None)
        return _machine


def _install_machine(device: str | int | None) -> Machine:
    """Make this process's Machine on ``device``, unless the one it has was made for the same device."""
    global _machine, _machine_device
    with _lock:
        if _machine is None or _machine_device != device:
            _machine, _machine_device = _make_machine(device), device
            _machines.clear()  # their Machine is gone
        return _machine


class MachinePlugin(WorkerPlugin):
    """Makes each worker process's Machine when the worker starts (and when the nanny restarts it).

    Register it once per cluster: ``client.register_plugin(MachinePlugin())``; workers that join later
    get it too. A device that cannot be opened fails the registration on that worker.

    Parameters
    ----------
    device : str or int, optional
        A case-insensitive substring of the OpenCL platform or device name, or an index into
        :func:`vmcl.machine.list_devices` as the worker sees it. Default: the worker's ``VMCL_DEVICE``,
        else its first device (GPUs first). Several devices on one node: one worker per device, each
        started with its own ``VMCL_DEVICE`` (or its own plugin).
    """

    name = "vmcl-machine"

    def __init__(self, device: str | int | None = None) -> None:
        if isinstance(device, bool) or not isinstance(device, (str, int, type(None))):
            raise InputTypeError(f"device must be a device name substring, a device index or None, "
                                 f"got {type(device).__name__}")
        if isinstance(device, int) and device < 0:
            raise InputValueError(f"device must be a device index >= 0, got {device}")
        self.device = device

    def setup(self, worker: Any = None) -> None:
        """Make the worker's Machine (a registration again for the same device keeps the one it has)."""
        _install_machine(self.device)


def _vision_machine(config: Mapping[str, Any] | None) -> VisionMachine:
    """The process's VisionMachine for this Config (as a dict), on :func:`worker_machine`."""
    key = json.dumps(config or {}, sort_keys=True, default=str)
    machine = worker_machine()
    with _lock:
        vm = _machines.get(key)
        if vm is None or vm.machine is not machine:
            if len(_machines) >= _MAX_CONFIGS:
                _machines.pop(next(iter(_machines)))
            vm = _machines[key] = VisionMachine(Config.from_dict(config or {}), machine=machine)
        return vm


def run_frame(left: np.ndarray, right: np.ndarray | None = None, next: np.ndarray | None = None,
              config: Mapping[str, Any] | None = None) -> Result:
    """One run of the machine on this worker's Machine (the task :func:`map_frames` submits).

    Parameters
    ----------
    left, right, next : ndarray
        As :meth:`vmcl.pipeline.VisionMachine.run` takes them.
    config : mapping, optional
        :meth:`vmcl.pipeline.Config.to_dict`'s nested values (default: ``Config()``).

    Returns
    -------
    Result
    """
    return _vision_machine(config).run(left, right, next)


def run_chunk(frames: Sequence[np.ndarray], first: int, skip: int, config: Mapping[str, Any] | None = None,
              rights: Sequence[np.ndarray] | None = None) -> list[tuple[int, Result]]:
    """Run the pairs (frames[k], frames[k + 1]) of one chunk, each on its own; the task of :func:`map_sequence`.

    Each pair's Result is ``VisionMachine.run(frames[k], rights[k], frames[k + 1])``: nothing is carried
    from one pair to the next (no temporal terms), so the skipped pairs are not run at all.

    Parameters
    ----------
    frames : sequence of ndarray
        The chunk's frames: frame ``first`` of the video onwards.
    first : int
        The video index of ``frames[0]``.
    skip : int
        Leading pairs not run and not returned (>= 0): no other pair's Result depends on them.
    config : mapping, optional
        :meth:`vmcl.pipeline.Config.to_dict`'s nested values.
    rights : sequence of ndarray, optional
        The right view of each frame (stereo video): pair k is also matched in stereo.

    Returns
    -------
    list of (int, Result)
        Each returned pair's video index t (the pair t, t + 1) and its Result.
    """
    skip = check_int(skip, "skip", minimum=0, maximum=max(len(frames) - 1, 0))
    vm = _vision_machine(config)
    # Only the returned pairs run: a skipped pair's Result would be thrown away, and no pair reads another's.
    return [(first + k, vm.run(frames[k], None if rights is None else rights[k], frames[k + 1]))
            for k in range(skip, len(frames) - 1)]


@dataclass(frozen=True)
class ItemOutput:
    """What a batch item's task sends back: its output files' bytes (encoded on the worker) and its time.

    Attributes
    ----------
    files : dict of str to bytes
        The files ``vmcl run`` writes (report.html, the report's PNGs, fields.npz), by name.
    total_ms : float
        The machine's wall time for the item.
    notes : list of str
        :attr:`vmcl.result.Result.notes`.
    """

    files: dict[str, bytes]
    total_ms: float
    notes: list[str] = field(default_factory=list)


def render_item(left: np.ndarray, right: np.ndarray | None, next: np.ndarray | None,
                config: Mapping[str, Any] | None, title: str) -> ItemOutput:
    """Run the machine on one batch item and encode its output as ``vmcl run`` would write it.

    The PNGs and the compressed fields are made on the worker, so the client only writes bytes and no
    file system is shared between them.
    """
    from vmcl.cli import write_output  # the command's own writer: a batch item is a `vmcl run`

    result = run_frame(left, right, next, config)
    with tempfile.TemporaryDirectory(prefix="vmcl-item-") as folder:
        write_output(result, Path(folder), f"Vision Machine: {title}")
        files = {path.name: path.read_bytes() for path in sorted(Path(folder).iterdir())}
    return ItemOutput(files, result.total_ms, list(result.notes))


# ----------------------------------------------------------------------------------- the client's side

def _check_client(client: Any) -> Client:
    if not isinstance(client, Client):
        raise InputTypeError(f"client must be a distributed.Client, got {type(client).__name__}")
    return client


def _config_dict(config: Any) -> dict[str, Any]:
    if config is None:
        return Config().to_dict()
    if isinstance(config, Config):
        return config.to_dict()
    if isinstance(config, Mapping):
        return Config.from_dict(config).to_dict()  # checked here, not on every worker
    raise InputTypeError(f"config must be a vmcl.pipeline.Config, a mapping of its sections or None, "
                         f"got {type(config).__name__}")


def _check_retries(retries: Any) -> int:
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise InputValueError(f"retries must be an integer >= 0, got {retries!r}")
    return retries


def _frame(frame: Any, where: str) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """(left, right, next) of one item of ``frames``; the arrays' values are the machine's to check."""
    if isinstance(frame, np.ndarray):
        views: tuple[Any, ...] = (frame, None, None)
    elif isinstance(frame, Mapping):
        unknown = sorted(set(map(str, frame)) - {"left", "right", "next"})
        if unknown or "left" not in frame:
            raise InputValueError(f"{where} must map 'left' (and optionally 'right', 'next') to images, "
                                  f"got the keys {sorted(map(str, frame))}")
        views = (frame["left"], frame.get("right"), frame.get("next"))
    elif isinstance(frame, (tuple, list)) and 1 <= len(frame) <= 3:
        views = (*frame, *(None,) * (3 - len(frame)))
    elif hasattr(frame, "left") and hasattr(frame, "right"):  # vmcl.datasets.StereoPair
        views = (frame.left, frame.right, None)
    else:
        raise InputTypeError(f"{where} must be an image, a (left, right[, next]) tuple, a mapping of 'left', "
                             f"'right', 'next' or a StereoPair, got {type(frame).__name__}")
    for name, view in zip(("left", "right", "next"), views):
        if not (view is None and name != "left") and not isinstance(view, np.ndarray):
            raise InputTypeError(f"{where}.{name} must be a NumPy array{'' if name == 'left' else ' or None'}, "
                                 f"got {type(view).__name__}")
    return views[0], views[1], views[2]


def map_frames(client: Client, frames: Iterable[Any], config: Config | Mapping[str, Any] | None = None, *,
               retries: int = 1) -> list[Future]:
    """Run the machine on every frame on the client's cluster: one task per frame.

    Parameters
    ----------
    client : distributed.Client
    frames : iterable
        Each an image (edges, colour, texture), a tuple ``(left, right)`` or ``(left, right, next)``
        (None for a view not given), a mapping with keys ``left``, ``right``, ``next``, or a
        :class:`vmcl.datasets.StereoPair`.
    config : Config or mapping, optional
        Sent to the workers as :meth:`vmcl.pipeline.Config.to_dict`'s dict. Default: ``Config()``.
    retries : int
        Reruns of a task that raised before its future holds the error (a task whose worker died is
        rerun elsewhere regardless).

    Returns
    -------
    list of distributed.Future
        One per frame, in order, each of a :class:`vmcl.result.Result`; a frame the machine refuses
        (shape, dtype, sizes that differ) gives a future holding its error, and the others complete.
    """
    client = _check_client(client)
    values = _config_dict(config)
    retries = _check_retries(retries)
    if isinstance(frames, (np.ndarray, str, bytes)) or not isinstance(frames, Iterable):
        raise InputTypeError(f"frames must be an iterable of frames (a list), got {type(frames).__name__}")
    views = [_frame(frame, f"frames[{index}]") for index, frame in enumerate(frames)]
    batch = uuid.uuid4().hex[:8]
    # pure=False: hashing every image for a key costs a pass over the data and finds nothing to share.
    return [client.submit(run_frame, *view, values, key=f"vmcl-frame-{batch}-{index}", retries=retries, pure=False)
            for index, view in enumerate(views)]


def map_sequence(client: Client, frames: Sequence[np.ndarray], config: Config | Mapping[str, Any] | None = None,
                 *, chunk: int = 16, overlap: int = 0, rights: Sequence[np.ndarray] | None = None,
                 retries: int = 1) -> list[Future]:
    """Run the machine on a video's frame pairs (t, t + 1), each pair on its own, ``chunk`` pairs per task.

    Pair t's Result is ``VisionMachine.run(frames[t], rights[t], frames[t + 1])``: nothing is carried from
    one pair to the next, so the Results equal, frame for frame, those of
    :meth:`vmcl.pipeline.VisionMachine.stream` over the same frames with ``[time] enabled = false``
    (``config``'s own ``[time]`` section is not used). With the temporal terms on (the default), stream
    carries each cue's restoration along the flow from every earlier frame, which chunks run apart
    cannot: for them run the sequence in one process (``vmcl run`` on a sequence, or ``stream``).

    A video of n frames gives n - 1 Results, one per pair: a Result here is the machine on a frame and
    the next, and the last frame has no next (stream also yields a last Result for it, without motion;
    run it with :func:`map_frames` if it is wanted). :func:`stitch` of the gathered chunks puts them in
    the video's order.

    Parameters
    ----------
    client : distributed.Client
    frames : sequence of ndarray
        The video's frames (the left view), at least 2.
    config : Config or mapping, optional
    chunk : int
        Pairs each task returns (>= 1).
    overlap : int
        Ignored (>= 0), kept so that calls which give it still run: a chunk once also ran this many pairs
        before its own and dropped them, but no pair depends on another, so a chunk is now sent and runs
        its own pairs only, whatever the overlap.
    rights : sequence of ndarray, optional
        The right view of every frame (as many as ``frames``): each pair adds stereo.
    retries : int

    Returns
    -------
    list of distributed.Future
        One per chunk, in order, each of a list of (t, Result): n - 1 Results in all for n frames.
    """
    client = _check_client(client)
    values = _config_dict(config)
    retries = _check_retries(retries)
    for name, value, minimum in (("chunk", chunk, 1), ("overlap", overlap, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise InputValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if isinstance(frames, np.ndarray) or not isinstance(frames, Sequence):
        raise InputTypeError(f"frames must be a sequence of images (a list), got {type(frames).__name__}")
    if len(frames) < 2:
        raise InputValueError(f"frames must hold at least 2 frames (one pair), got {len(frames)}")
    for index, frame in enumerate(frames):
        if not isinstance(frame, np.ndarray):
            raise InputTypeError(f"frames[{index}] must be a NumPy array, got {type(frame).__name__}")
    if rights is not None:
        if isinstance(rights, np.ndarray) or not isinstance(rights, Sequence) or len(rights) != len(frames):
            raise InputValueError(f"rights must be a sequence of {len(frames)} right views (one per frame), "
                                  f"got {type(rights).__name__}")
        for index, view in enumerate(rights):
            if not isinstance(view, np.ndarray):
                raise InputTypeError(f"rights[{index}] must be a NumPy array, got {type(view).__name__}")
    pairs = len(frames) - 1
    batch = uuid.uuid4().hex[:8]
    futures = []
    for start in range(0, pairs, chunk):
        stop = min(start + chunk, pairs)
        # The chunk's own frames only: its overlap's pairs would be run and dropped (no pair reads another's),
        # so they are neither sent nor run.
        chunk_rights = None if rights is None else list(rights[start:stop + 1])
        futures.append(client.submit(run_chunk, list(frames[start:stop + 1]), start, 0, values,
                                     chunk_rights, key=f"vmcl-chunk-{batch}-{start}", retries=retries,
                                     pure=False))
    return futures


def stitch(chunks: Iterable[Sequence[tuple[int, Result]]]) -> list[Result]:
    """The Results of :func:`map_sequence`'s gathered chunks in the video's order, each pair once.

    Raises
    ------
    ValueError
        If a pair is missing or given twice (chunks of different calls mixed).
    """
    if isinstance(chunks, (str, bytes, Mapping)) or not isinstance(chunks, Iterable):
        raise InputTypeError(f"chunks must be an iterable of map_sequence's chunks, got {type(chunks).__name__}")
    found: dict[int, Result] = {}
    for index, chunk in enumerate(chunks):
        if isinstance(chunk, (str, bytes)) or not isinstance(chunk, Sequence):
            raise InputTypeError(f"chunks[{index}] must be a list of (t, Result), got {type(chunk).__name__}")
        for entry in chunk:
            if not (isinstance(entry, Sequence) and len(entry) == 2 and isinstance(entry[0], int)
                    and not isinstance(entry[0], bool) and entry[0] >= 0 and isinstance(entry[1], Result)):
                raise InputTypeError(f"chunks[{index}] must hold (t, Result) pairs with t >= 0, got {entry!r:.80}")
            t, result = entry
            if t in found:
                raise InputValueError(f"chunks[{index}] holds the pair {t} again: chunks of different sequences?")
            found[t] = result
    missing = sorted(set(range(len(found))) - set(found))
    if missing:
        raise InputValueError(f"chunks lack the pair(s) {missing[:5]}: every chunk of the sequence is needed")
    return [found[t] for t in range(len(found))]


# ----------------------------------------------------------------------------------- batches (vmcl batch)

@dataclass(frozen=True)
class BatchItem:
    """One item of a batch: a name (its output folder's) and where its images are.

    Attributes
    ----------
    name : str
        Unique in the batch, safe as a folder name.
    kind : str
        "image" (one image), "scene" (a Middlebury-layout scene folder: a stereo pair), "pair" (a
        stereo pair without the rest of its layout: its left and right views) or "motion" (a frame and
        the next one).
    paths : tuple of Path
        The image, the scene folder, the left and right views, or the frame and the next frame.
    """

    name: str
    kind: str
    paths: tuple[Path, ...]

    def load(self) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """(left, right, next) as the files hold them."""
        from vmcl.datasets import read_image, read_stereo_folder

        if self.kind == "scene":
            pair = read_stereo_folder(self.paths[0])
            return pair.left, pair.right, None
        if self.kind == "pair":
            return read_image(self.paths[0]), read_image(self.paths[1]), None
        if self.kind == "motion":
            return read_image(self.paths[0]), None, read_image(self.paths[1])
        return read_image(self.paths[0]), None, None


def _safe_name(text: str) -> str:
    # A folder name on every file system; a leading dot would hide it beside output_folder's own hidden folders.
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("_.") or "item"
    return name


def _images_in(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
                  and not p.name.startswith("."))


def batch_items(inputs: Sequence[str | os.PathLike[str]], *, frames: bool = False) -> list[BatchItem]:
    """The items of a batch over these inputs, named uniquely after their files and folders.

    Parameters
    ----------
    inputs : sequence of str or Path
        Image files (each an item), folders holding Middlebury-layout scenes (each scene an item, a
        stereo pair; :func:`vmcl.datasets.find_stereo_folders`), folders whose only images are a layout's
        two views (a pair without ground truth, such as a data set's test pair or a user's own im0.png and
        im1.png: :func:`vmcl.datasets.stereo_views`), or folders of image files (each image an item).
    frames : bool
        The images, in the order given (a folder's sorted by name), are the frames of one sequence: item t
        is frame t with frame t + 1 (motion), named after frame t.

    Returns
    -------
    list of BatchItem
        In the inputs' order. Names repeated are told apart by "-2", "-3" ... in that order, so the same
        inputs give the same names (what a rerun's resume goes by).

    Raises
    ------
    ValueError
        An input that does not exist, a folder with nothing to run, fewer than 2 frames.
    """
    from vmcl.datasets import find_stereo_folders, stereo_folders_lacking, stereo_views

    if isinstance(inputs, (str, os.PathLike)) or not isinstance(inputs, Sequence):
        raise InputTypeError(f"inputs must be a sequence of paths, got {type(inputs).__name__}")
    if not isinstance(frames, (bool, np.bool_)):
        raise InputTypeError(f"frames must be true or false, got {type(frames).__name__}")
    if not inputs:
        raise InputValueError("inputs: no input given (image files or folders)")
    for index, entry in enumerate(inputs):
        if not isinstance(entry, (str, os.PathLike)):
            raise InputTypeError(f"inputs[{index}] must be a path (str or os.PathLike), got {type(entry).__name__}")
    raw: list[tuple[str, str, tuple[Path, ...]]] = []  # (name, kind, paths)
    images: list[Path] = []
    for entry in inputs:
        path = Path(entry)
        if path.is_file():
            images.append(path)
        elif path.is_dir():
            # Scenes with their ground truth; and folders whose images are a layout's two views and nothing
            # else, pairs without it (a data set's test pair, a user's im0.png and im1.png), which were taken
            # for two images.
            scenes: list[tuple[Path, str, tuple[Path, ...]]] = [] if frames else sorted(
                [(scene, "scene", (scene,)) for scene in find_stereo_folders(path)]
                + [(pair, "pair", views) for pair, _ in stereo_folders_lacking(path)
                   if (views := stereo_views(pair)) is not None and set(_images_in(pair)) == set(views)])
            raw += [(path.name if scene == path else scene.relative_to(path).as_posix(), kind, paths)
                    for scene, kind, paths in scenes]
            if any(kind == "scene" or scene == path for scene, kind, _ in scenes):
                continue  # a data set's folder, or a pair itself: its other images are not items
            found = _images_in(path)
            if not found and not scenes:
                raise InputValueError(f"inputs: the folder {entry} holds no Middlebury-layout scene and no image "
                                      f"file ({', '.join(IMAGE_SUFFIXES)})")
            images += found
        else:
            raise InputValueError(f"inputs: no such file or folder: {entry}")
    if frames:
        if len(images) < 2:
            raise InputValueError(f"inputs: --frames needs at least 2 frames, got {len(images)}")
        raw += [(a.stem, "motion", (a, b)) for a, b in itertools.pairwise(images)]
    else:
        raw += [(image.stem, "image", (image,)) for image in images]
    items, taken = [], set()
    for name, kind, paths in raw:
        base = _safe_name(name)
        unique, n = base, 1
        while unique.lower() in taken:  # lower: case-insensitive file systems would merge the folders
            n += 1
            unique = f"{base}-{n}"
        taken.add(unique.lower())
        items.append(BatchItem(unique, kind, paths))
    return items


@dataclass(frozen=True)
class ItemStatus:
    """How a batch item ended.

    Attributes
    ----------
    name : str
    state : str
        "done", "skipped" (a complete output was already there) or "failed".
    detail : str
        The error of a failed item (its type and message); for an item run again, why; else "".
    total_ms : float
        The machine's wall time (NaN unless done).
    error : BaseException or None
        The failed item's exception.
    """

    name: str
    state: str
    detail: str = ""
    total_ms: float = math.nan
    error: BaseException | None = None


def _finished(folder: Path) -> bool:
    """Whether ``folder`` holds a vmcl output: output_folder moves the marker in with the last file."""
    return (folder / MARKER).is_file()


_ITEM_FILE = "item.json"
"""The file in each item's output that records what it was made from: the item's kind and its input files
(path, size and modification time), so that a rerun knows an item whose inputs changed under the same
name."""


def _item_record(item: BatchItem) -> str:
    """The item's kind and inputs as _ITEM_FILE holds them (a scene folder by its files)."""
    # A scene by its files, hidden ones left out (a file browser rewrites its .DS_Store at will).
    files = (sorted(p for p in item.paths[0].iterdir() if p.is_file() and not p.name.startswith("."))
             if item.kind == "scene" else list(item.paths))
    inputs = []
    for path in files:
        stat = path.stat()
        inputs.append({"path": str(path.resolve()), "size": stat.st_size, "modified_ns": stat.st_mtime_ns})
    return json.dumps({"kind": item.kind, "inputs": inputs}, indent=1, sort_keys=True) + "\n"


def _made_with(folder: Path, values: dict[str, Any], item: BatchItem) -> bool:
    """Whether the output in ``folder`` is whole and was made from this item's inputs, as they are now,
    with these settings (one written before outputs recorded them, or whose record is unreadable, was
    not)."""
    from vmcl.cli import SETTINGS_FILE, settings_text

    try:
        # Compared as values, not text: a setting given as 2 is the same as the default's 2.0.
        recorded = json.loads((folder / SETTINGS_FILE).read_text(encoding="utf-8"))
        return (is_whole(folder) and recorded == json.loads(settings_text(values))
                and (folder / _ITEM_FILE).read_text(encoding="utf-8") == _item_record(item))
    except (OSError, UnicodeDecodeError, ValueError):
        return False


def run_batch(client: Client, items: Sequence[BatchItem], out: str | os.PathLike[str],
              config: Config | Mapping[str, Any] | None = None, *, retries: int = 1,
              progress: Callable[[str], None] | None = None) -> list[ItemStatus]:
    """Run every item on the client's cluster and write each one's output into ``out``/<name>/.

    Items whose folder already holds a whole vmcl output made from the same inputs with the same settings
    are skipped (a rerun resumes); one made with other settings (the file vmcl.cli.SETTINGS_FILE in it
    records them) or from inputs that changed since (item.json records their paths, sizes and times), or
    one that is damaged (a file missing or cut short), is run again and its output replaced, so that a
    batch's folders never mix settings. The images are
    read here, a few tasks ahead of the workers (twice the cluster's threads), so that a batch of any
    length holds only those in memory; each output is written, whole or not at all, as its task ends.

    Parameters
    ----------
    client : distributed.Client
    items : sequence of BatchItem
    out : str or Path
        The batch's folder: vmcl writes only the items' folders in it.
    config : Config or mapping, optional
    retries : int
        Reruns of a task that raised before the item is reported failed.
    progress : callable, optional
        Called with each item's name as it ends (done, skipped or failed).

    Returns
    -------
    list of ItemStatus
        One per item, in the items' order.

    Raises
    ------
    ValueError
        Before anything runs: ``out`` is not a folder, or an item's folder is there and is not a vmcl
        output (vmcl writes only its own files).
    """
    client = _check_client(client)
    values = _config_dict(config)
    retries = _check_retries(retries)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputValueError(f"--out {out} exists and is not a folder")
    step = progress or (lambda name: None)
    statuses: dict[str, ItemStatus] = {}
    todo: list[BatchItem] = []
    again: set[str] = set()
    for item in items:
        folder = out / item.name
        if _finished(folder) and _made_with(folder, values, item):
            statuses[item.name] = ItemStatus(item.name, "skipped", "already there")
            step(item.name)
        elif _finished(folder):
            again.add(item.name)
            todo.append(item)
        elif folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
            raise InputValueError(f"--out {out}: {folder} is there and is not a vmcl output; vmcl writes only its "
                                  "own files: move it away or name another folder")
        else:
            todo.append(item)
    batch = uuid.uuid4().hex[:8]
    waiting = iter(todo)
    running: dict[Future, BatchItem] = {}
    records: dict[str, str] = {}
    ended = as_completed()

    def fail(item: BatchItem, error: BaseException) -> None:
        statuses[item.name] = ItemStatus(item.name, "failed", f"{type(error).__name__}: {error}", error=error)
        step(item.name)

    def refill() -> None:
        # Workers may join or leave while the batch runs: the lookahead follows the threads there are.
        ahead = max(2, 2 * sum(client.nthreads().values()))
        while len(running) < ahead:
            item = next(waiting, None)
            if item is None:
                return
            try:
                # What the output is made from, taken before the inputs are read: an input changed while
                # its item runs then fails the next run's comparison, and the item runs again.
                records[item.name] = _item_record(item)
                views = item.load()
            except (InputError, OSError) as error:
                fail(item, error)
                continue
            future = client.submit(render_item, *views, values, item.name, key=f"vmcl-batch-{batch}-{item.name}",
                                   retries=retries, pure=False)
            running[future] = item
            ended.add(future)

    refill()
    for future in ended:
        item = running.pop(future)
        try:
            if future.status == "finished":
                output = future.result()
                with output_folder(out / item.name) as work:
                    for name, data in output.files.items():
                        (work / name).write_bytes(data)
                    (work / _ITEM_FILE).write_text(records[item.name], encoding="utf-8")
                detail = ("run again: the output there was made with other settings or inputs, or is damaged"
                          if item.name in again else "")
                statuses[item.name] = ItemStatus(item.name, "done", detail, total_ms=output.total_ms)
                step(item.name)
            else:
                fail(item, future.exception())
        except (InputError, OSError) as error:  # its folder became unwritable or foreign meanwhile
            fail(item, error)
        finally:
            future.release()
        refill()
    return [statuses[item.name] for item in items]


# ----------------------------------------------------------------------------------- one field over the batch (Zarr)

ZARR_WRITER = "vmcl"
"""The value of the attribute ``written_by`` of every Zarr store vmcl writes: it replaces only those."""

_ZARR_INSTALL = "vmcl batch --zarr needs the zarr package: pip install 'vmcl[dask]'"
_CUE_FIELD = re.compile(r"restored_[a-z][a-z0-9_]*|[a-z][a-z0-9_]*_line_[hv]")


@dataclass(frozen=True)
class ZarrStore:
    """A Zarr array :func:`write_zarr` wrote: one field of every item of a batch.

    Attributes
    ----------
    path : Path
        ``out``/<field>.zarr.
    field : str
        The name of the field in each item's fields.npz.
    shape : tuple of int
        (items, H, W[, C]), the items in the batch's order.
    dtype : numpy.dtype
    filled : tuple of str
        The items whose row holds the fill value (NaN for floats, 0 for integers, False for booleans):
        those without a finished output (failed, or not run yet) or whose result lacks the field.
    """

    path: Path
    field: str
    shape: tuple[int, ...]
    dtype: np.dtype
    filled: tuple[str, ...]


def _zarr() -> Any:
    """The zarr module, or the ImportError that says how to install it."""
    try:
        import zarr
    except ImportError:
        raise ImportError(_ZARR_INSTALL) from None
    return zarr


def _check_field(field: Any, argument: str = "field") -> str:
    from vmcl.cli import FIELD_NAMES

    if not isinstance(field, str):
        raise InputTypeError(f"{argument} must be the name of a field of fields.npz (a str), got {type(field).__name__}")
    if field not in FIELD_NAMES and not _CUE_FIELD.fullmatch(field):
        raise InputValueError(f"{argument}: {field!r} is not a field of fields.npz; the fields are "
                              f"{', '.join(FIELD_NAMES)}, restored_<cue>, <cue>_line_h and <cue>_line_v")
    return field


def _check_items(items: Any) -> list[BatchItem]:
    if isinstance(items, (str, bytes, os.PathLike, Mapping)) or not isinstance(items, Sequence):
        raise InputTypeError(f"items must be a sequence of BatchItem (batch_items' list), got {type(items).__name__}")
    if not items:
        raise InputValueError("items: no item given (a Zarr array over the batch needs at least one)")
    names: set[str] = set()
    for index, item in enumerate(items):
        if not isinstance(item, BatchItem):
            raise InputTypeError(f"items[{index}] must be a BatchItem, got {type(item).__name__}")
        if item.name in names:
            raise InputValueError(f"items[{index}]: the name {item.name!r} is there twice (batch_items names them "
                                  "uniquely)")
        names.add(item.name)
    return list(items)


def _check_out(out: Any) -> Path:
    if not isinstance(out, (str, os.PathLike)):
        raise InputTypeError(f"out must be a path (str or os.PathLike), got {type(out).__name__}")
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise InputValueError(f"out: {path} exists and is not a folder")
    return path


def _written_by_vmcl(path: Path, zarr: Any) -> bool:
    """Whether ``path`` is a Zarr store vmcl wrote (its attribute written_by)."""
    if not path.is_dir() or path.is_symlink():
        return False
    try:
        return zarr.open_array(store=str(path), mode="r").attrs.get("written_by") == ZARR_WRITER
    except Exception:  # noqa: BLE001 - anything zarr cannot open as an array is not vmcl's store
        return False


def vmcl_stores(out: str | os.PathLike[str]) -> list[str]:
    """The fields of the Zarr stores vmcl wrote in ``out`` (``out``/<field>.zarr), sorted; none when the zarr
    package is missing (then vmcl wrote none)."""
    try:
        zarr = _zarr()
    except ImportError:
        return []
    folder = Path(out)
    return sorted(p.name[:-len(".zarr")] for p in folder.glob("*.zarr") if _written_by_vmcl(p, zarr)) \
        if folder.is_dir() else []


def _zarr_target(out: Path, field: str) -> Path:
    """``out``/<field>.zarr, refused unless it is absent or a store vmcl wrote."""
    target = out / f"{field}.zarr"
    if not target.exists() and not target.is_symlink():
        return target
    if not _written_by_vmcl(target, _zarr()):
        raise InputValueError(f"--zarr {field}: {target} is there and vmcl did not write it (a vmcl store has the "
                              f"attribute written_by: {ZARR_WRITER}); vmcl writes only its own files: move it away "
                              "or name another --out")
    return target


def _size_text(size: tuple[int, ...], names: list[str]) -> str:
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    return f"{' x '.join(map(str, size))} ({shown})"


def _fields_needing(needed: str) -> set[str]:
    """The fields of fields.npz that a run makes only with the input ``needed`` ("right" or "next"): those of
    the registered cues that need it."""
    from vmcl.cli import cue_fields
    from vmcl.cues import registered

    return {name for cue in registered() if needed in cue.needs for name in cue_fields(cue)}


def check_zarr(out: str | os.PathLike[str], items: Sequence[BatchItem], fields: Sequence[str]) -> None:
    """Refuse, before a batch runs, the ``--zarr`` stores :func:`write_zarr` could not write after it.

    Every item's images are read here, once (their size only is kept), so with ``--zarr`` a batch reads
    its images twice; an item whose images cannot be read is left to fail in the batch (its row filled).

    Parameters
    ----------
    out : str or Path
        The batch's folder (it need not exist yet).
    items : sequence of BatchItem
    fields : sequence of str
        The fields of fields.npz to stack (:data:`vmcl.cli.FIELD_NAMES`, ``restored_<cue>``,
        ``<cue>_line_h``, ``<cue>_line_v``).

    Raises
    ------
    ImportError
        The zarr package is missing (it comes with ``pip install 'vmcl[dask]'``).
    ValueError
        A name that is not a field, a field that no item has the input for (flow without a next frame,
        disparity without a right view), items whose images differ in size (one array cannot hold them; the
        sizes found are named), or a ``out``/<field>.zarr that vmcl did not write.
    """
    out = _check_out(out)
    items = _check_items(items)
    if isinstance(fields, (str, bytes)) or not isinstance(fields, Sequence):
        raise InputTypeError(f"fields must be a sequence of field names, got {type(fields).__name__}")
    names = [_check_field(field, f"fields[{index}]") for index, field in enumerate(fields)]
    if not names:
        return
    _zarr()
    for name in dict.fromkeys(names):
        _zarr_target(out, name)
        # A field only an input no item has can make (flow: a next frame; disparity: a right view) would be
        # refused after the whole batch ran.
        for needed, kinds, how in (("next", ("motion",), "a next frame (--frames)"),
                                   ("right", ("scene", "pair"), "a right view (a stereo scene or pair)")):
            if name in _fields_needing(needed) and not any(item.kind in kinds for item in items):
                raise InputValueError(f"--zarr {name}: no item of the batch has {how}, which {name} needs")
    sizes: dict[tuple[int, ...], list[str]] = {}
    for item in items:
        try:
            left = item.load()[0]
        except (InputError, OSError):
            continue  # the batch reports it (and its row is filled)
        sizes.setdefault(tuple(left.shape[:2]), []).append(item.name)
    if len(sizes) > 1:
        found = "; ".join(_size_text(size, found) for size, found in sizes.items())
        raise InputValueError(f"--zarr {' '.join(dict.fromkeys(names))}: one array over the batch needs the items' "
                              f"images of one size, and they have {len(sizes)}: {found}; run the sizes as "
                              "separate batches, or leave out --zarr")


def _fill_value(dtype: np.dtype) -> Any:
    if dtype.kind == "b":
        return False
    if dtype.kind in "iu":
        return 0
    if dtype.kind in "fc":
        return np.nan
    raise InputValueError(f"field: fields.npz holds it as {dtype}, which vmcl does not put into a Zarr array")


def _item_field(folder: Path, field: str) -> np.ndarray | None:
    """The field from the item's fields.npz, if the item's output is whole (every file it lists there and
    readable) and holds it."""
    if not is_whole(folder) or not (folder / "fields.npz").is_file():
        return None
    try:
        with np.load(folder / "fields.npz", allow_pickle=False) as fields:
            return fields[field] if field in fields.files else None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise InputValueError(f"out: {folder / 'fields.npz'} cannot be read ({error}); remove the item's folder "
                              "to run it again") from None


def _new_array(zarr: Any, path: Path, shape: tuple[int, ...], dtype: np.dtype) -> Any:
    # One chunk per item: a row is written as its item is read. Rows that are the fill value are stored
    # too, so that a NaN's bits read back as written.
    options: dict[str, Any] = {"shape": shape, "chunks": (1, *shape[1:]), "dtype": dtype,
                               "fill_value": _fill_value(dtype)}
    if int(zarr.__version__.split(".")[0]) >= 3:
        options["config"] = {"write_empty_chunks": True}
    else:
        options["write_empty_chunks"] = True
    return zarr.open_array(store=str(path), mode="w-", **options)


def _replace(work: Path, target: Path) -> None:
    """Move the whole store ``work`` to ``target``, the previous store there going only once it is in."""
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old-{secrets.token_hex(4)}")
        os.replace(target, old)
    try:
        os.replace(work, target)
    except BaseException:
        if old is not None:
            os.replace(old, target)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def write_zarr(out: str | os.PathLike[str], items: Sequence[BatchItem], field: str, *,
               failed: Sequence[str] = ()) -> ZarrStore:
    """Stack one field of every item's output in ``out`` into the Zarr array ``out``/<field>.zarr.

    The rows follow the items' order and come from the items' fields.npz on disk, so the store is always
    that of the folders, whichever run wrote them (``vmcl batch`` calls this after every run, a resumed one
    too). It is written into a hidden store beside its place and moved there when whole: a previous vmcl
    store is replaced only then, and a store vmcl did not write is refused. The array has one chunk per
    item and the attributes ``written_by`` ("vmcl"), ``field``, ``items`` (the names, in order) and
    ``filled``.

    Parameters
    ----------
    out : str or Path
        The batch's folder (:func:`run_batch`'s ``out``).
    items : sequence of BatchItem
        The batch's items, in order.
    field : str
        A name of fields.npz (:data:`vmcl.cli.FIELD_NAMES`, ``restored_<cue>``, ``<cue>_line_h``,
        ``<cue>_line_v``).
    failed : sequence of str
        The names of items that failed in the run that built their folders (:func:`run_batch`'s statuses):
        their rows are filled, whatever their folders still hold (an earlier output, made with other
        settings or inputs, which the failed run did not replace).

    Returns
    -------
    ZarrStore
        Its path, shape (items, H, W[, C]), dtype and the items whose row is the fill value (NaN for
        floats, 0 for integers, False for booleans): items without a whole output (failed) or without
        the field (disparity of a single image).

    Raises
    ------
    ImportError
        The zarr package is missing (it comes with ``pip install 'vmcl[dask]'``).
    ValueError
        No item's output holds the field, the items' fields differ in shape or dtype, an unreadable
        fields.npz, or a ``out``/<field>.zarr that vmcl did not write.

    Examples
    --------
    >>> store = write_zarr("results", batch_items(["data"]), "disparity")  # doctest: +SKIP
    >>> zarr.open_array(str(store.path), mode="r")[0]  # the first item's disparity  # doctest: +SKIP
    """
    out = _check_out(out)
    items = _check_items(items)
    field = _check_field(field)
    if isinstance(failed, str) or not isinstance(failed, Sequence) or not all(isinstance(n, str) for n in failed):
        raise InputTypeError(f"failed must be a sequence of item names, got {failed!r}")
    left_out = set(failed)
    zarr = _zarr()
    target = _zarr_target(out, field)
    work = out / f".{field}.zarr.partial-{secrets.token_hex(4)}"
    array: Any = None
    first = ""
    filled: list[str] = []
    try:
        for index, item in enumerate(items):
            values = None if item.name in left_out else _item_field(out / item.name, field)
            if values is None:
                filled.append(item.name)
                continue
            if array is None:
                array = _new_array(zarr, work, (len(items), *values.shape), values.dtype)
                first = item.name
            elif values.shape != array.shape[1:] or values.dtype != array.dtype:
                raise InputValueError(
                    f"--zarr {field}: the items' {field} in {out} differ: {first}'s is {np.dtype(array.dtype)} "
                    f"{tuple(array.shape[1:])}, {item.name}'s {values.dtype} {values.shape}; one array cannot hold "
                    "both")
            array[index] = values
        if array is None:
            raise InputValueError(f"--zarr {field}: no item in {out} holds {field!r} (failed, not run yet, or a "
                                  f"result without it: disparity needs a stereo pair, flow a next frame)")
        array.attrs.update({"written_by": ZARR_WRITER, "field": field, "items": [item.name for item in items],
                            "filled": filled})
        _replace(work, target)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return ZarrStore(target, field, tuple(array.shape), np.dtype(array.dtype), tuple(filled))


# ----------------------------------------------------------------------------------- a local cluster

@dataclass(frozen=True)
class LocalClusterSize:
    """Workers and threads for a LocalCluster on this computer, and why."""

    workers: int
    threads: int
    reason: str


def local_cluster_size(workers: int | None = None, threads: int | None = None) -> LocalClusterSize:
    """The LocalCluster ``vmcl batch`` starts without a scheduler: 1 worker of 1 thread unless told.

    PoCL runs every kernel on all of the CPU's cores from one process, and a GPU runs one queue's kernels
    one after the other, so one worker already keeps the device busy. A second worker process or thread
    could overlap one item's host work (the Python between kernels, PNG and npz encoding, pickling) with
    another's kernels; on a shared 2-core CPU that overlap measured within the run-to-run noise
    (benchmarks/results/distributed.md), while each worker costs a context, its kernel builds and its
    memory. For several devices, start one ``dask worker`` per device, each with its ``VMCL_DEVICE``, and
    name their scheduler with ``--scheduler``.
    """
    for name, value in (("workers", workers), ("threads", threads)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise InputValueError(f"--{name} must be an integer >= 1, got {value!r}")
    if workers is not None and threads is not None:
        return LocalClusterSize(workers, threads, "as asked")
    return LocalClusterSize(workers or 1, threads or 1,
                            "one worker keeps the device busy: PoCL's kernels use every core")


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """SIGINT ignored while the block runs (in the main thread; elsewhere signals are not this code's)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


_CONNECT_SECONDS = 20


def _connected(scheduler: str) -> Client:
    """A Client of ``scheduler``, or TimeoutError. Dask's own timeout covers the connection but not the
    handshake after it: a port where something else answers (a web server, the scheduler's dashboard)
    waited forever. The Client is made in a thread, left behind if it never returns (a daemon, which the
    process's exit ends)."""
    made: dict[str, Any] = {}

    def connect() -> None:
        try:
            made["client"] = Client(scheduler, timeout=f"{_CONNECT_SECONDS}s")
        except BaseException as error:  # noqa: BLE001 (handed to the caller's thread, whatever it is)
            made["error"] = error

    thread = threading.Thread(target=connect, name="vmcl-scheduler-connect", daemon=True)
    thread.start()
    thread.join(1.5 * _CONNECT_SECONDS)  # Dask's own timeout first, where it applies
    if thread.is_alive():
        raise TimeoutError(f"nothing answered as a Dask scheduler within {1.5 * _CONNECT_SECONDS:g} s (a scheduler "
                           "listens on its own port, 8786 by default, not its dashboard's)")
    if "error" in made:
        raise made["error"]
    return made["client"]


@contextlib.contextmanager
def cluster_client(scheduler: str | None = None, *, workers: int | None = None, threads: int | None = None,
                   device: str | int | None = None, worker_logs: bool = False) -> Iterator[tuple[Client, str]]:
    """A Client of ``scheduler``, else of a new LocalCluster (closed after), with MachinePlugin registered.

    Yields the client and a line saying what it runs on (the workers, threads and dashboard). A local
    cluster's own log lines are kept from the terminal unless ``worker_logs``: a task's error is reported
    with its item, and a worker that dies is restarted by its nanny and its tasks rerun elsewhere. A local
    cluster keeps Dask's scratch space in a temporary folder of its own, removed when the cluster closes
    (on an error or an interrupt too), where Dask would leave it in the system's temporary folder.
    """
    import logging

    if scheduler is not None and (workers is not None or threads is not None):
        raise InputValueError("--workers and --threads size a local cluster; with --scheduler the scheduler's "
                              "own workers run the items")
    plugin = MachinePlugin(device)
    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            try:
                client = stack.enter_context(_connected(scheduler))
            except (OSError, TimeoutError) as error:
                raise InputValueError(f"--scheduler {scheduler}: cannot connect ({error})") from None
            except ValueError as error:  # Dask's reading of the address: no port, an unknown scheme
                raise InputValueError(f"--scheduler {scheduler} is not a scheduler address such as "
                                      f"tcp://host:8786 ({error})") from None
            except MemoryError:  # something answered that does not speak Dask's protocol
                raise InputValueError(f"--scheduler {scheduler}: what answers there is not a Dask scheduler") from None
            threads_there = client.nthreads()
            where = (f"Dask scheduler {scheduler}: {len(threads_there)} worker(s), "
                     f"{sum(threads_there.values())} thread(s)")
        else:
            size = local_cluster_size(workers, threads)
            # Dask's scheduler and workers keep their scratch (dask-scratch-space, its lock files) in the
            # temporary folder itself, and leave it there when they close. The cluster gets a folder of its
            # own, entered first so that it is removed after the cluster has closed, however the block ends.
            scratch = stack.enter_context(tempfile.TemporaryDirectory(prefix="vmcl-dask-"))
            # The worker processes start with Ctrl-C ignored (the disposition carries over into them): a
            # terminal's Ctrl-C reaches the whole process group, and each worker printed its traceback.
            # This process stops on it and closes the cluster, which ends them.
            with _sigint_ignored():
                cluster = stack.enter_context(LocalCluster(
                    n_workers=size.workers, threads_per_worker=size.threads, processes=True,
                    local_directory=scratch, scheduler_kwargs={"local_directory": scratch},
                    silence_logs=logging.WARNING if worker_logs else logging.CRITICAL))
            client = stack.enter_context(Client(cluster))
            where = f"local Dask cluster: {size.workers} worker(s) x {size.threads} thread(s) ({size.reason})"
        if "dashboard" in client.scheduler_info().get("services", {}):
            # A local scheduler serves the dashboard's pages only with bokeh installed (a remote one: its own).
            missing = scheduler is None and importlib.util.find_spec("bokeh") is None
            where += f"; dashboard {client.dashboard_link}{' (pip install bokeh to see it)' if missing else ''}"
        client.register_plugin(plugin)
        yield client, where
