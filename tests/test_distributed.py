"""vmcl on Dask: a local cluster of 2 spawned workers gives, bit for bit, what one process gives alone.

The oracle is the serial run over the same items: :meth:`VisionMachine.run` in this process for the
library, ``vmcl run`` per item for ``vmcl batch`` (every array of fields.npz and every PNG compared byte
for byte; report.html holds the run's timings, so only its presence is checked). The cluster starts once
for the module and stops at its end; the kill test SIGKILLs one of its worker processes, which its nanny
restarts.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
import signal
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

# The dask extra (pip install 'vmcl[dask]'; the test extra brings it): without it these tests are skipped.
distributed = pytest.importorskip("distributed",
                                  reason="vmcl.distributed needs the dask extra: pip install 'vmcl[dask]'")

from vmcl import scenes
from vmcl.cli import SETTINGS_FILE, main, write_output
from vmcl.datasets import read_image, read_stereo_folder, stereo_views, write_stereo_folder
from vmcl.distributed import (
    MachinePlugin,
    batch_items,
    map_frames,
    map_sequence,
    run_batch,
    stitch,
    vmcl_stores,
    worker_machine,
    write_zarr,
)
from vmcl.errors import InputValueError
from vmcl.machine import Machine
from vmcl.output_folder import MARKER, output_folder
from vmcl.pipeline import Config, VisionMachine

# ICM restores in a few sweeps: the items stay cheap and every stage still runs.
FAST = {"mrf": {"method": "icm"}}


def _connected_once_more(connected):
    """``vmcl.distributed._connected``, tried once more after an AssertionError. With this module's Client
    open, each ``vmcl batch --scheduler`` of a test opens and closes another Client in this process, and
    distributed's loop runner asserts now and then that the event loop it started exists: a race with the
    loop a Client is closing, seen only here (it failed a test of CI once); a second attempt finds the loop.
    A user's process opens one Client, so the library connects once."""

    def connect(scheduler):
        try:
            return connected(scheduler)
        except AssertionError:
            time.sleep(0.5)
            return connected(scheduler)

    return connect


@pytest.fixture(scope="module")
def client():
    import vmcl.distributed

    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.CRITICAL)
    try:
        with distributed.Client(cluster) as c, pytest.MonkeyPatch.context() as patch:
            patch.setattr(vmcl.distributed, "_connected", _connected_once_more(vmcl.distributed._connected))
            c.register_plugin(MachinePlugin())
            yield c
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def serial():
    return VisionMachine(Config.from_dict(FAST), machine=Machine(profile=True))


def _scene(seed: int, size: int = 64):
    return scenes.render(scenes.preset("blocks", shape=(size, size)), seed=seed, noise=0.01)


def _same_result(a, b) -> None:
    for name, value in vars(a).items():
        other = getattr(b, name)
        if isinstance(value, np.ndarray):
            assert value.dtype == other.dtype and value.shape == other.shape, name
            assert value.tobytes() == other.tobytes(), f"{name} differs"
        elif value is None:
            assert other is None, name
    assert a.restored.keys() == b.restored.keys() and a.lines.keys() == b.lines.keys()
    for cue in a.restored:
        assert a.restored[cue].tobytes() == b.restored[cue].tobytes(), cue
    for cue in a.lines:
        assert all(x.tobytes() == y.tobytes() for x, y in zip(a.lines[cue], b.lines[cue])), cue
    assert a.notes == b.notes and a.config == b.config and list(a.stages) == list(b.stages)


def test_map_frames_equals_the_serial_run_and_each_worker_keeps_one_machine(client, serial):
    views = []
    for seed in range(3):
        s = _scene(seed)
        views += [(s.left, s.right, s.left_next), (s.left,), {"left": s.left[..., 0], "next": s.left_next[..., 0]}]
    futures = map_frames(client, views, FAST)
    for view, future in zip(views, futures):
        left, right, next_ = (view["left"], None, view["next"]) if isinstance(view, dict) else (*view, None, None)[:3]
        _same_result(future.result(), serial.run(left, right, next_))

    def machine_of_this_worker(_):
        return os.getpid(), id(worker_machine())

    seen = client.gather([client.submit(machine_of_this_worker, i, pure=False) for i in range(24)])
    per_process: dict[int, set[int]] = {}
    for pid, machine in seen:
        per_process.setdefault(pid, set()).add(machine)
    assert os.getpid() not in per_process  # spawned workers ran the tasks, not this process
    assert all(len(machines) == 1 for machines in per_process.values()), per_process


def test_a_frame_that_raises_is_reported_and_the_others_complete(client, serial):
    s = _scene(4)
    views = [(s.left, s.right), (s.left, s.right[:48, :48]), (s.left,)]
    futures = map_frames(client, views, FAST)
    distributed.wait(futures)
    assert [f.status for f in futures] == ["finished", "error", "finished"]
    error = futures[1].exception()
    assert isinstance(error, InputValueError) and "right" in str(error)
    _same_result(futures[0].result(), serial.run(s.left, s.right))
    _same_result(futures[2].result(), serial.run(s.left))


def test_map_frames_refuses_what_is_not_a_frame_by_name(client):
    s = _scene(0)
    with pytest.raises(TypeError, match=r"frames\[1\]"):
        map_frames(client, [s.left, "left.png"])
    with pytest.raises(TypeError, match=r"frames\[0\]\.right"):
        map_frames(client, [(s.left, "right.png")])
    with pytest.raises(ValueError, match="unknown config key"):
        map_frames(client, [s.left], {"mrf": {"nope": 1}})


def test_a_sequence_in_chunks_with_overlap_stitches_to_the_serial_run(client, serial):
    s = _scene(5)
    # A camera moving one pixel a frame over the rendered view: 6 frames, 5 pairs.
    frames = [np.ascontiguousarray(np.roll(s.left, shift, axis=1)) for shift in range(6)]
    futures = map_sequence(client, frames, FAST, chunk=2, overlap=1)
    assert len(futures) == 3
    chunks = client.gather(futures)
    assert [[t for t, _ in chunk] for chunk in chunks] == [[0, 1], [2, 3], [4]]
    results = stitch(chunks)
    assert len(results) == 5
    for t, result in enumerate(results):
        _same_result(result, serial.run(frames[t], next=frames[t + 1]))
    with pytest.raises(ValueError, match="pair"):
        stitch([chunks[0], chunks[2]])


def test_a_chunk_runs_only_the_pairs_it_returns(client, monkeypatch):
    """Each pair is run on its own, so a chunk's overlap (the pairs before its own) changes no Result; they
    were still sent and run, and their Results dropped. Every task of map_sequence is run here, in this
    process, on a machine that records the pairs it is given: each pair runs once, and only once."""
    from vmcl import distributed as vmcl_distributed

    ran = []

    class Recording:
        def run(self, left, right, next):
            ran.append((int(left[0, 0]), int(next[0, 0])))
            return ran[-1]

    monkeypatch.setattr(vmcl_distributed, "_vision_machine", lambda config: Recording())
    tasks = []
    monkeypatch.setattr(client, "submit", lambda task, *args, **kwargs: tasks.append((task, args)))
    frames = [np.full((16, 16), index, np.uint8) for index in range(6)]  # each frame known by its value
    map_sequence(client, frames, FAST, chunk=2, overlap=1)
    chunks = [task(*args) for task, args in tasks]
    assert chunks == [[(0, (0, 1)), (1, (1, 2))], [(2, (2, 3)), (3, (3, 4))], [(4, (4, 5))]]
    assert ran == [(t, t + 1) for t in range(5)]  # the overlap's pairs 1 and 3 were run twice, and dropped
    ran.clear()
    # run_chunk itself: its skipped leading pairs are not run either.
    assert vmcl_distributed.run_chunk(frames[2:], 2, 2, FAST) == [(4, (4, 5))]
    assert ran == [(4, 5)]
    for skip in (-1, 5, True, 1.5):  # clipped, or beyond the chunk's pairs, in silence before
        with pytest.raises((TypeError, ValueError), match="skip"):
            vmcl_distributed.run_chunk(frames[2:], 2, skip, FAST)


# ------------------------------------------------------------------------------------------------ vmcl batch

def _png(path: Path, image: np.ndarray) -> Path:
    cv2.imwrite(str(path), cv2.cvtColor(np.round(image * 255).clip(0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR))
    return path


def _scene_folders(root: Path, count: int, size: int) -> list[Path]:
    """Middlebury 2014-layout scene folders (im0, im1, disp0.pfm, calib.txt) of rendered pairs."""
    folders = []
    for seed in range(count):
        s = _scene(seed, size)
        folders.append(write_stereo_folder(root / f"scene{seed:02d}", s.left, s.right, s.disparity, ndisp=16))
    return folders


def _fast_toml(tmp_path: Path) -> Path:
    path = tmp_path / "fast.toml"
    path.write_text('[mrf]\nmethod = "icm"\n')
    return path


def _vmcl_run_outputs(folders: list[Path], config: Path, out: Path) -> None:
    """``vmcl run`` on each scene's pair (a new Machine each time: about 1 s of kernel builds per item)."""
    for folder in folders:
        assert main(["run", str(folder / "im0.png"), str(folder / "im1.png"), "--config", str(config),
                     "--out", str(out / folder.name), "--quiet"]) == 0


def _serial_outputs(folders: list[Path], serial: VisionMachine, out: Path) -> None:
    """What ``vmcl run`` writes for each scene, from one machine in this process (its kernels built once)."""
    for folder in folders:
        pair = read_stereo_folder(folder)
        with output_folder(out / folder.name) as work:
            write_output(serial.run(pair.left, pair.right), work, f"Vision Machine: {folder.name}")


def _assert_same_output(batch: Path, reference: Path) -> None:
    """The item's folder is whole and holds the serial run's arrays and pictures, bit for bit."""
    assert (batch / MARKER).is_file() and (batch / "report.html").is_file()
    # A batch item's folder also records what it was made from (item.json).
    assert sorted(p.name for p in batch.iterdir() if p.name != "item.json") == sorted(
        p.name for p in reference.iterdir())
    with np.load(batch / "fields.npz") as ours, np.load(reference / "fields.npz") as theirs:
        assert sorted(ours.files) == sorted(theirs.files)
        for name in ours.files:
            a, b = ours[name], theirs[name]
            assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), name
    for png in reference.glob("*.png"):
        assert (batch / png.name).read_bytes() == png.read_bytes(), png.name


def _no_partial_folders(out: Path) -> bool:
    return not [p for p in out.iterdir() if p.name.startswith(".")]


def test_batch_equals_vmcl_run_per_item(client, tmp_path, capsys):
    folders = _scene_folders(tmp_path / "data", 4, 64)
    config = _fast_toml(tmp_path)
    _vmcl_run_outputs(folders, config, tmp_path / "serial")
    out = tmp_path / "batch"
    code = main(["batch", str(tmp_path / "data"), "--config", str(config), "--out", str(out),
                 "--scheduler", client.scheduler_info()["address"], "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "4 done, 0 skipped (already there), 0 failed" in printed
    for folder in folders:
        _assert_same_output(out / folder.name, tmp_path / "serial" / folder.name)
    assert _no_partial_folders(out)


def test_a_worker_killed_mid_batch_loses_nothing(client, serial, tmp_path):
    folders = _scene_folders(tmp_path / "data", 20, 128)
    config = _fast_toml(tmp_path)
    out = tmp_path / "batch"
    killed: dict[str, object] = {}

    def kill_a_busy_worker() -> None:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            finished = sum((folder / MARKER).is_file() for folder in out.glob("*")) if out.exists() else 0
            busy = [address for address, keys in client.processing().items() if keys]
            if finished >= 3 and busy:
                pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, signal.SIGKILL)
                killed.update(pid=pid, finished=finished)
                return
            time.sleep(0.005)

    killer = threading.Thread(target=kill_a_busy_worker)
    killer.start()
    try:
        code = main(["batch", str(tmp_path / "data"), "--config", str(config), "--out", str(out),
                     "--scheduler", client.scheduler_info()["address"], "--quiet"])
    finally:
        killer.join()
    assert killed, "no worker was killed"
    assert killed["finished"] < 20, "the batch ended before the kill: the items are too small to test this"
    assert code == 0
    _serial_outputs(folders, serial, tmp_path / "serial")
    for folder in folders:
        _assert_same_output(out / folder.name, tmp_path / "serial" / folder.name)
    assert _no_partial_folders(out)
    client.wait_for_workers(2, timeout=60)  # the nanny brings the worker back for the tests after this one
    assert killed["pid"] not in client.run(os.getpid).values()


def test_an_interrupted_batch_resumes_with_only_the_missing_items(client, serial, tmp_path, capsys):
    folders = _scene_folders(tmp_path / "data", 6, 64)
    items = batch_items([tmp_path / "data"])
    out = tmp_path / "batch"
    ended = []

    def interrupt_after_two(name: str) -> None:
        ended.append(name)
        if len(ended) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(client, items, out, FAST, progress=interrupt_after_two)
    first = {p.name: (p / MARKER).stat().st_mtime_ns for p in out.iterdir() if (p / MARKER).is_file()}
    assert sorted(first) == sorted(ended) and _no_partial_folders(out)

    config = _fast_toml(tmp_path)
    code = main(["batch", str(tmp_path / "data"), "--config", str(config), "--out", str(out),
                 "--scheduler", client.scheduler_info()["address"], "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "4 done, 2 skipped (already there), 0 failed" in printed
    for name, mtime in first.items():  # the finished items were not written again
        assert (out / name / MARKER).stat().st_mtime_ns == mtime
        assert f"{name}  skipped" in printed
    _serial_outputs(folders, serial, tmp_path / "serial")
    for folder in folders:
        _assert_same_output(out / folder.name, tmp_path / "serial" / folder.name)


def test_a_batch_with_other_settings_runs_the_items_again_and_one_with_the_same_skips_them(client, tmp_path):
    """A resumed batch never mixes settings: each output records its own (settings.json), and an item whose
    folder was made with others runs again, its output replaced."""
    _scene_folders(tmp_path / "data", 2, 64)
    items = batch_items([tmp_path / "data"])
    out = tmp_path / "batch"
    other = {"mrf": {"method": "icm"}, "edges": {"sigma": 2.5}}
    assert [s.state for s in run_batch(client, items, out, FAST)] == ["done", "done"]
    recorded = {item.name: json.loads((out / item.name / SETTINGS_FILE).read_text()) for item in items}
    assert all(values == Config.from_dict(FAST).to_dict() for values in recorded.values())
    again = run_batch(client, items, out, other)
    assert [(s.state, s.detail) for s in again] == [
        ("done", "run again: the output there was made with other settings or inputs, or is damaged")] * 2
    for item in items:
        assert json.loads((out / item.name / SETTINGS_FILE).read_text())["edges"]["sigma"] == 2.5
    assert [s.state for s in run_batch(client, items, out, other)] == ["skipped", "skipped"]
    # The same settings written otherwise (an int where the recorded value is a float) are the same settings.
    threshold = Config().stereo.census_threshold
    assert threshold == int(threshold)
    same = {**other, "stereo": {"census_threshold": int(threshold)}}
    assert [s.state for s in run_batch(client, items, out, same)] == ["skipped", "skipped"]



def test_a_batch_runs_again_an_item_whose_inputs_changed_or_whose_output_is_damaged(client, tmp_path):
    # A rerun knew an item by its folder's name and the settings only: an image replaced under the same
    # name kept its old results, and a fields.npz cut short was trusted (and broke --zarr with a traceback).
    _scene_folders(tmp_path / "data", 2, 64)
    items = batch_items([tmp_path / "data"])
    out = tmp_path / "batch"
    assert [s.state for s in run_batch(client, items, out, FAST)] == ["done", "done"]
    changed, damaged = items
    left = changed.paths[0] / "im0.png"
    picture = cv2.imread(str(left))
    cv2.imwrite(str(left), np.ascontiguousarray(picture[:, ::-1]))  # another picture under the same name
    fields = out / damaged.name / "fields.npz"
    fields.write_bytes(fields.read_bytes()[:1000])
    assert write_zarr(out, items, "disparity").filled == (damaged.name,)  # not stacked, and no traceback
    again = run_batch(client, items, out, FAST)
    assert [s.state for s in again] == ["done", "done"], again
    with np.load(fields) as restored:
        assert "disparity" in restored.files
    assert [s.state for s in run_batch(client, items, out, FAST)] == ["skipped", "skipped"]


def test_a_failing_item_is_reported_by_name_and_the_others_complete(client, serial, tmp_path, capsys):
    data = tmp_path / "data"
    data.mkdir()
    for seed in range(3):
        _png(data / f"frame{seed}.png", _scene(seed).left)
    cv2.imwrite(str(data / "tiny.png"), np.zeros((8, 8), np.uint8))  # the machine refuses it on the worker
    (data / "broken.png").write_text("not an image")  # refused when read, before it is sent
    out = tmp_path / "batch"
    code = main(["batch", str(data), "--out", str(out), "--config", str(_fast_toml(tmp_path)),
                 "--scheduler", client.scheduler_info()["address"], "--quiet"])
    assert code == 2  # what failed was bad input
    printed = capsys.readouterr().out
    assert "3 done, 0 skipped (already there), 2 failed" in printed
    lines = {line.split()[0]: line for line in printed.splitlines()[2:]}
    assert "failed" in lines["tiny"] and "InputValueError: left must be at least 16 x 16" in lines["tiny"]
    assert "failed" in lines["broken"] and "broken.png" in lines["broken"]
    assert sorted(p.name for p in out.iterdir()) == ["frame0", "frame1", "frame2"]
    for seed in range(3):
        reference = tmp_path / "serial" / f"frame{seed}"
        with output_folder(reference) as work:
            write_output(serial.run(read_image(data / f"frame{seed}.png")), work, f"Vision Machine: frame{seed}")
        _assert_same_output(out / f"frame{seed}", reference)


def test_batch_refuses_an_item_folder_it_did_not_write(client, tmp_path, capsys):
    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0).left)
    (tmp_path / "batch" / "a").mkdir(parents=True)
    (tmp_path / "batch" / "a" / "notes.txt").write_text("mine")
    code = main(["batch", str(data), "--out", str(tmp_path / "batch"), "--scheduler", client.scheduler_info()["address"],
                 "--quiet"])
    assert code == 2
    assert "is not a vmcl output" in capsys.readouterr().err
    assert (tmp_path / "batch" / "a" / "notes.txt").read_text() == "mine"


def test_batch_items_are_named_uniquely_and_safely(tmp_path):
    for folder in ("x", "y"):
        (tmp_path / folder).mkdir()
        for name in ("a b.png", "A.PNG", ".hidden.png", "c.txt"):
            (tmp_path / folder / name).write_bytes(b"")
    items = batch_items([tmp_path / "x", tmp_path / "y"])
    assert [(i.name, i.paths[0].name) for i in items] == [
        ("A", "A.PNG"), ("a_b", "a b.png"), ("A-2", "A.PNG"), ("a_b-2", "a b.png")]
    frames = batch_items([tmp_path / "x"], frames=True)
    assert [(i.name, i.kind, [p.name for p in i.paths]) for i in frames] == [("A", "motion", ["A.PNG", "a b.png"])]
    with pytest.raises(ValueError, match="inputs: no such file or folder"):
        batch_items([tmp_path / "missing"])
    with pytest.raises(ValueError, match="at least 2 frames"):
        batch_items([tmp_path / "x" / "A.PNG"], frames=True)


def test_a_stereo_pair_without_ground_truth_is_one_pair_item(tmp_path):
    # A folder holding a layout's two views but no ground truth (a benchmark's test pair, a user's own
    # im0.png and im1.png) was taken for a folder of images: two items, each run alone, without depth.
    folders = _scene_folders(tmp_path / "data", 2, 64)
    (folders[1] / "disp0.pfm").unlink()
    items = batch_items([tmp_path / "data"])
    assert [(i.name, i.kind) for i in items] == [("scene00", "scene"), ("scene01", "pair")]
    assert [p.name for p in items[1].paths] == ["im0.png", "im1.png"]
    left, right, following = items[1].load()
    assert right is not None and following is None
    np.testing.assert_array_equal(left, read_image(folders[1] / "im0.png"))
    assert stereo_views(folders[1]) == (folders[1] / "im0.png", folders[1] / "im1.png")
    assert stereo_views(tmp_path) is None
    # A folder of numbered images that happens to hold im0.png and im1.png is images, each an item; and a
    # folder's own images stay items beside a pair in a subfolder.
    photos = tmp_path / "photos"
    photos.mkdir()
    for name in ("im0.png", "im1.png", "im2.png", "im3.png", "a.png"):
        cv2.imwrite(str(photos / name), np.zeros((64, 64), np.uint8))
    assert [(i.name, i.kind) for i in batch_items([photos])] == [
        ("a", "image"), ("im0", "image"), ("im1", "image"), ("im2", "image"), ("im3", "image")]
    for name in ("im2.png", "im3.png"):
        (photos / name).unlink()
    (photos / "sub").mkdir()
    for name in ("im0.png", "im1.png"):
        (photos / name).rename(photos / "sub" / name)
    assert [(i.name, i.kind) for i in batch_items([photos])] == [("sub", "pair"), ("a", "image")]


# ------------------------------------------------------------------------------------------------ vmcl batch --zarr

def _zarr_rows(store: Path) -> tuple[np.ndarray, dict]:
    zarr = pytest.importorskip("zarr")
    array = zarr.open_array(str(store), mode="r")
    return array[...], dict(array.attrs)


def test_batch_zarr_stacks_each_items_field_in_order_and_fills_the_failed(client, tmp_path, capsys):
    pytest.importorskip("zarr")
    folders = _scene_folders(tmp_path / "data", 3, 64)
    broken = tmp_path / "broken.png"
    broken.write_text("not an image")  # fails when read: its rows are the fill value
    single = _png(tmp_path / "single.png", _scene(7).left)  # runs, but a single image has no disparity
    out = tmp_path / "batch"
    argv = ["batch", str(tmp_path / "data"), str(broken), str(single), "--out", str(out), "--config",
            str(_fast_toml(tmp_path)), "--zarr", "disparity", "--zarr", "labels",
            "--scheduler", client.scheduler_info()["address"], "--quiet"]
    names = [folder.name for folder in folders] + ["broken", "single"]
    for run in ("first", "resumed"):
        assert main(argv) == 2, run  # the broken item is bad input
        printed = capsys.readouterr().out
        assert ("4 done, 0 skipped" if run == "first" else "0 done, 4 skipped") in printed, run
        assert "disparity: " in printed and "2 item(s) filled with NaN (failed, or no disparity): broken, single" in printed
        assert "1 item(s) filled with 0 (failed, or no labels): broken" in printed
        for field in ("disparity", "labels"):
            rows, attrs = _zarr_rows(out / f"{field}.zarr")
            assert attrs["written_by"] == "vmcl" and attrs["items"] == names, field
            present = [name for name in names if name != "broken" and (field == "labels" or name != "single")]
            for index, name in enumerate(names):
                if name in present:
                    with np.load(out / name / "fields.npz") as fields:
                        want = fields[field]
                    assert rows[index].dtype == want.dtype and rows[index].tobytes() == want.tobytes(), (field, name)
                elif field == "disparity":
                    assert np.isnan(rows[index]).all(), name
                else:
                    assert not rows[index].any(), name
            stacked = np.stack([np.load(out / name / "fields.npz")[field] for name in present])
            assert rows[[names.index(name) for name in present]].tobytes() == stacked.tobytes(), field
        assert _no_partial_folders(out)
        # Spoil a row: the resumed run rewrites the store from the folders, not from what it held.
        __import__("zarr").open_array(str(out / "disparity.zarr"), mode="r+")[0] = -1.0


def test_a_store_an_earlier_batch_built_is_named_when_a_later_one_adds_items_without_it(client, tmp_path, capsys):
    """A store built by one run lacks the items a later run without --zarr writes: that run says so."""
    pytest.importorskip("zarr")
    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0, 64).left)
    out = tmp_path / "batch"
    common = ["--out", str(out), "--config", str(_fast_toml(tmp_path)), "--scheduler",
              client.scheduler_info()["address"], "--quiet"]
    assert main(["batch", str(data), "--zarr", "labels", *common]) == 0
    assert vmcl_stores(out) == ["labels"] and vmcl_stores(tmp_path / "absent") == []
    capsys.readouterr()
    assert main(["batch", str(data), *common]) == 0  # nothing new: nothing to say
    assert "was built by an earlier run" not in capsys.readouterr().err
    _png(data / "b.png", _scene(1, 64).left)
    assert main(["batch", str(data), *common]) == 0
    err = capsys.readouterr().err
    assert f"{out / 'labels.zarr'} was built by an earlier run and is out of date for the 1 item(s) this one wrote: " \
           "rerun with --zarr labels to rebuild it" in err, err


def test_batch_zarr_refuses_items_of_different_sizes_before_any_work(tmp_path, capsys):
    pytest.importorskip("zarr")
    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0, 64).left)
    _png(data / "b.png", _scene(1, 64).left[:48, :40])
    out = tmp_path / "batch"
    # No scheduler is named and none is needed: the refusal comes before the cluster starts.
    assert main(["batch", str(data), "--out", str(out), "--zarr", "labels", "--quiet"]) == 2
    error = capsys.readouterr().err
    assert "--zarr labels" in error and "64 x 64 (a)" in error and "48 x 40 (b)" in error
    assert not out.exists()


@pytest.mark.parametrize("field, message", [
    ("flow", "--zarr flow: no item of the batch has a next frame (--frames), which flow needs"),
    ("disparity", "--zarr disparity: no item of the batch has a right view"),
    ("bogus", "--zarr: 'bogus' is not a field of fields.npz"),
])
def test_batch_zarr_refuses_a_field_no_item_can_make_before_any_work(tmp_path, capsys, field, message):
    # Flow without --frames was refused after the whole batch ran; an unknown field was named fields[0].
    pytest.importorskip("zarr")
    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0, 64).left)
    out = tmp_path / "batch"
    assert main(["batch", str(data), "--out", str(out), "--zarr", "labels", "--zarr", field, "--quiet"]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_batch_zarr_knows_the_fields_of_a_cue_registered_at_run_time(tmp_path, capsys):
    # The fields that need a right view were a hand-kept list of the built-in cues'; a cue added at run time
    # that needs one was refused only after the whole batch ran.
    pytest.importorskip("zarr")
    from vmcl import cues
    from vmcl.cues import CueModule
    from vmcl.labels import Label

    class Paired(CueModule):
        name = "paired_cue"
        needs = frozenset({"right"})
        label = Label.DEPTH

    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0, 64).left)
    out = tmp_path / "batch"
    cues.register(Paired())
    try:
        assert main(["batch", str(data), "--out", str(out), "--zarr", "paired_cue_line_h", "--quiet"]) == 2
    finally:
        cues.unregister("paired_cue")
    assert "--zarr paired_cue_line_h: no item of the batch has a right view" in capsys.readouterr().err
    assert not out.exists()


def test_batch_zarr_refuses_a_store_it_did_not_write_and_leaves_it(tmp_path, capsys, monkeypatch):
    zarr = pytest.importorskip("zarr")
    data = tmp_path / "data"
    data.mkdir()
    _png(data / "a.png", _scene(0, 64).left)
    out = tmp_path / "batch"
    (out / "disparity.zarr").mkdir(parents=True)
    (out / "disparity.zarr" / "notes.txt").write_text("mine")
    foreign = zarr.open_array(str(out / "labels.zarr"), mode="w", shape=(2, 2), dtype="uint8")
    foreign[...] = 7
    before = sorted((p.relative_to(out), p.read_bytes()) for p in out.rglob("*") if p.is_file())
    for field in ("disparity", "labels"):
        assert main(["batch", str(data), "--out", str(out), "--zarr", field, "--quiet"]) == 2
        assert f"--zarr {field}: {out / field}.zarr is there and vmcl did not write it" in capsys.readouterr().err
    assert sorted((p.relative_to(out), p.read_bytes()) for p in out.rglob("*") if p.is_file()) == before
    assert sorted(p.name for p in out.iterdir()) == ["disparity.zarr", "labels.zarr"]  # no item ran
    items = batch_items([data])
    with pytest.raises(ValueError, match="did not write it"):
        write_zarr(out, items, "labels")
    with pytest.raises(ValueError, match="field: 'nope' is not a field"):
        write_zarr(out, items, "nope")
    with pytest.raises(TypeError, match="items"):
        write_zarr(out, "a.png", "disparity")
    monkeypatch.setitem(__import__("sys").modules, "zarr", None)  # as if zarr were not installed
    assert main(["batch", str(data), "--out", str(tmp_path / "other"), "--zarr", "disparity", "--quiet"]) == 2
    assert "pip install 'vmcl[dask]'" in capsys.readouterr().err


@pytest.mark.parametrize("address", ["nonsense", "http://127.0.0.1:9"])
def test_a_scheduler_address_that_is_none_is_one_line(tmp_path, capsys, address):
    # Dask's ValueError on the address ended the command with a traceback as an internal error.
    (tmp_path / "data").mkdir()
    cv2.imwrite(str(tmp_path / "data" / "a.png"), np.zeros((32, 32), np.uint8))
    assert main(["batch", str(tmp_path / "data"), "--out", str(tmp_path / "out"), "--scheduler", address, "-q"]) == 2
    err = capsys.readouterr().err
    assert f"--scheduler {address} is not a scheduler address" in err and len(err.strip().splitlines()) == 1, err


def test_workers_beside_a_scheduler_are_refused(tmp_path, capsys):
    # --workers and --threads size a local cluster: beside --scheduler they were dropped without a word.
    (tmp_path / "data").mkdir()
    cv2.imwrite(str(tmp_path / "data" / "a.png"), np.zeros((32, 32), np.uint8))
    assert main(["batch", str(tmp_path / "data"), "--out", str(tmp_path / "out"), "--scheduler", "tcp://127.0.0.1:9",
                 "--workers", "4", "-q"]) == 2
    assert "--workers and --threads size a local cluster" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_port_that_answers_but_not_as_a_scheduler_ends_in_one_line(tmp_path, capsys, monkeypatch):
    # A port where a server accepts and waits for a request of its own (a web server, the dashboard) hung
    # vmcl batch for ever: Dask's timeout covers the connection, not the handshake after it.
    import socket
    import threading

    from vmcl import distributed

    monkeypatch.setattr(distributed, "_CONNECT_SECONDS", 1)
    server = socket.create_server(("127.0.0.1", 0))
    held = []
    threading.Thread(target=lambda: held.append(server.accept()), daemon=True).start()
    (tmp_path / "data").mkdir()
    cv2.imwrite(str(tmp_path / "data" / "a.png"), np.zeros((32, 32), np.uint8))
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        assert main(["batch", str(tmp_path / "data"), "--out", str(tmp_path / "out"), "--scheduler", address,
                     "-q"]) == 2
    finally:
        server.close()
    err = capsys.readouterr().err
    assert "nothing answered as a Dask scheduler" in err and len(err.strip().splitlines()) == 1, err


def test_ctrl_c_in_a_terminal_ends_a_local_batch_in_one_line(tmp_path):
    # A terminal's Ctrl-C reaches the whole process group: each local worker process printed its traceback.
    import subprocess
    import sys

    _scene_folders(tmp_path / "data", 12, 96)
    out = tmp_path / "batch"
    code = "import sys; from vmcl.cli import main; sys.exit(main(sys.argv[1:]))"
    process = subprocess.Popen([sys.executable, "-c", code, "batch", str(tmp_path / "data"), "--out", str(out),
                                "--workers", "1", "--threads", "1", "-q"], stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    deadline = time.monotonic() + 180
    while not (out.is_dir() and any(p.name.startswith("scene") for p in out.iterdir())) \
            and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert process.poll() is None, "the batch ended before it could be interrupted"
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "vmcl: interrupted", err


def test_zarr_leaves_out_an_item_that_failed_whatever_its_folder_still_holds(client, tmp_path, capsys):
    # An item that fails in a run keeps its earlier output (vmcl does not delete it), made with other
    # settings: --zarr stacked that old output beside the new ones.
    pytest.importorskip("zarr")
    folders = _scene_folders(tmp_path / "data", 2, 64)
    out = tmp_path / "batch"
    base = ["batch", str(tmp_path / "data"), "--out", str(out), "--scheduler", client.scheduler_info()["address"],
            "--quiet", "--zarr", "disparity"]
    assert main([*base, "--config", str(_fast_toml(tmp_path))]) == 0
    (out / folders[1].name / "notes.txt").write_text("mine")  # its folder now refuses to be replaced
    other = tmp_path / "other.toml"
    other.write_text('[mrf]\nmethod = "icm"\n[edges]\nsigma = 2.5\n')
    capsys.readouterr()
    assert main([*base, "--config", str(other)]) == 2
    printed = capsys.readouterr().out
    assert f"1 item(s) filled with NaN (failed, or no disparity): {folders[1].name}" in printed, printed
    rows, _ = _zarr_rows(out / "disparity.zarr")
    assert np.isnan(rows[1]).all() and not np.isnan(rows[0]).all()
    assert (out / folders[1].name / "notes.txt").read_text() == "mine"


def test_map_sequence_equals_the_stream_with_time_disabled_one_result_per_pair(client):
    """map_sequence runs each pair on its own: its Results are stream's with [time] enabled = false, frame
    for frame, one per pair (n - 1 for n frames; stream adds the last frame's, without motion)."""
    s = _scene(6)
    frames = [np.ascontiguousarray(np.roll(s.left, shift, axis=1)) for shift in range(4)]
    untimed = {**FAST, "time": {"enabled": False}}
    streamed = list(VisionMachine(Config.from_dict(untimed), machine=Machine(profile=True)).stream(frames))
    assert len(streamed) == 4 and streamed[-1].flow is None
    for config in (untimed, FAST):  # the config's own [time] section is not used
        results = stitch(client.gather(map_sequence(client, frames, config, chunk=2)))
        assert len(results) == 3
        for t, result in enumerate(results):
            assert result.flow is not None
            assert result.config.time.enabled == (config is FAST)  # the Config it was given, recorded
            _same_result(dataclasses.replace(result, config=streamed[t].config), streamed[t])


def test_a_local_cluster_leaves_no_scratch_space_in_the_temporary_folder(tmp_path):
    """Dask's scheduler and workers put dask-scratch-space (global.lock, purge.lock) in the temporary
    folder and left it there after every local batch; vmcl gives the cluster a folder of its own and removes
    it when the cluster closes, after a batch and after an error inside the block alike. Run in a process of
    its own, with TMPDIR its own too: a second local cluster in this process (beside the module's) left
    distributed's loop in a state that failed a later test's connection now and then."""
    import subprocess
    import sys

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    (tmp_path / "data").mkdir()
    _png(tmp_path / "data" / "a.png", _scene(0).left)
    code = (
        "import sys, tempfile\n"
        "from pathlib import Path\n"
        "from vmcl.cli import main\n"
        "from vmcl.distributed import cluster_client\n"
        "scratch = Path(sys.argv[1])\n"
        "assert tempfile.gettempdir() == str(scratch)\n"
        "assert main(sys.argv[2:]) == 0\n"
        "print('after the batch:', sorted(p.name for p in scratch.rglob('*')))\n"
        "used = []\n"
        "try:\n"
        "    with cluster_client(workers=1, threads=1):\n"
        "        used += [p.parent.name for p in scratch.rglob('dask-scratch-space')]\n"
        "        raise RuntimeError('inside the block')\n"
        "except RuntimeError:\n"
        "    pass\n"
        "print('while the cluster ran:', used)\n"
        "print('after the error:', sorted(p.name for p in scratch.rglob('*')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code, str(scratch), "batch", str(tmp_path / "data"), "--config",
                           str(_fast_toml(tmp_path)), "--out", str(tmp_path / "out"), "--workers", "1", "--threads",
                           "1", "--quiet"], check=False, env={**os.environ, "TMPDIR": str(scratch)},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert "after the batch: []" in lines and "after the error: []" in lines, done.stdout
    assert (tmp_path / "out" / "a" / "fields.npz").is_file()
    used = next(line for line in lines if line.startswith("while the cluster ran:"))
    assert "vmcl-dask-" in used, used  # the scratch space lay under the cluster's own folder
