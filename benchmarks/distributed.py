"""Items per second of `vmcl batch` on Dask: 1 and 2 workers, 1 and 2 threads each; a model for N nodes.

The items are ITEMS Middlebury-layout scene folders of rendered 256 x 256 stereo pairs (the 'blocks'
preset, one noise seed each), run with the default Config; each is a whole `vmcl batch` item: the
client reads the pair, a worker runs the machine and encodes the report and fields.npz, the client writes
the item's folder. Each cluster is started (spawned workers, MachinePlugin registered) and warmed with one
item per thread, whose kernels builds are not timed; the timed batch then runs into a new folder.

The serial row runs the same items in this process with one VisionMachine, reading and writing as the
batch does, without Dask. The scheduler's overhead per task is the wall time of TASKS empty tasks
through a 2-worker cluster, divided by their number. From these and the bytes each item sends and
receives, the model of throughput on N nodes (written under the tables) says where the scheduler or the
client's network becomes the limit. Writes benchmarks/results/distributed.md.
"""

from __future__ import annotations

import datetime
import logging
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

# Run as a script, this file's folder comes first on sys.path, and its name would hide Dask's package.
if sys.path and Path(sys.path[0]).resolve() == Path(__file__).resolve().parent:
    del sys.path[0]

from distributed import Client, LocalCluster

import vmcl
from vmcl import scenes
from vmcl.cli import write_output
from vmcl.datasets import read_stereo_folder, write_stereo_folder
from vmcl.distributed import MachinePlugin, batch_items, render_item, run_batch
from vmcl.output_folder import output_folder
from vmcl.pipeline import Config, VisionMachine

ITEMS = 12
SIZE = 256
TASKS = 2000
SETUPS = ((1, 1), (1, 2), (2, 1))  # (workers, threads per worker)
# The client's network in the model: 10 Gbit/s Ethernet, an assumption (this machine has no second node).
NETWORK_BYTES_PER_S = 1.25e9


def make_items(root: Path, count: int) -> None:
    for seed in range(count):
        s = scenes.render(scenes.preset("blocks", shape=(SIZE, SIZE)), seed=seed, noise=0.01)
        write_stereo_folder(root / f"scene{seed:03d}", s.left, s.right, s.disparity, ndisp=32)


def serial(data: Path, out: Path) -> tuple[float, float]:
    """(items per second, machine ms per item) in one process, reading and writing as a batch item does."""
    vm = VisionMachine(Config())
    items = batch_items([data])
    pair = read_stereo_folder(items[0].paths[0])
    vm.run(pair.left, pair.right)  # the kernels' builds
    machine_ms = 0.0
    start = time.perf_counter()
    for item in items:
        left, right, _ = item.load()
        t0 = time.perf_counter()
        result = vm.run(left, right)
        machine_ms += (time.perf_counter() - t0) * 1e3
        with output_folder(out / item.name) as work:
            write_output(result, work, f"Vision Machine: {item.name}")
    took = time.perf_counter() - start
    return len(items) / took, machine_ms / len(items)


def cluster_rate(data: Path, warm: Path, out: Path, workers: int, threads: int) -> float:
    with LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True, dashboard_address=None,
                      silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
        client.register_plugin(MachinePlugin())
        run_batch(client, batch_items([warm])[:workers * threads], out.with_name(out.name + "-warm"))
        items = batch_items([data])
        start = time.perf_counter()
        statuses = run_batch(client, items, out)
        took = time.perf_counter() - start
        assert all(s.state == "done" for s in statuses), [s.detail for s in statuses if s.state != "done"]
        return len(items) / took


def _noop(i: int) -> int:
    return i


def scheduler_overhead_ms() -> float:
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
        client.gather(client.map(_noop, range(100), pure=False))
        start = time.perf_counter()
        client.gather(client.map(_noop, range(TASKS), pure=False))
        return (time.perf_counter() - start) / TASKS * 1e3


def client_costs(data: Path, out: Path) -> tuple[int, int, float]:
    """(bytes sent to a worker, bytes sent back, the client's ms) per item.

    The client's work for an item in run_batch: reading its images, and writing the output files the
    worker encoded (timed with one item's output, written once per item).
    """
    items = batch_items([data])
    left, right, _ = items[0].load()
    output = render_item(left, right, None, Config().to_dict(), items[0].name)
    start = time.perf_counter()
    for item in items:
        item.load()
        with output_folder(out / item.name) as work:
            for name, content in output.files.items():
                (work / name).write_bytes(content)
    client_ms = (time.perf_counter() - start) / len(items) * 1e3
    return left.nbytes + right.nbytes, sum(len(b) for b in output.files.values()), client_ms


def main() -> int:
    machine = vmcl.default_machine()
    load = os.getloadavg()[0]
    root = Path(tempfile.mkdtemp(prefix="vmcl-bench-distributed-"))
    try:
        make_items(root / "data", ITEMS)
        make_items(root / "warm", 2)
        rate_serial, machine_ms = serial(root / "data", root / "serial")
        print(f"serial: {rate_serial:.2f} items/s", file=sys.stderr)
        rates = {}
        for workers, threads in SETUPS:
            rates[(workers, threads)] = cluster_rate(root / "data", root / "warm", root / f"out-{workers}-{threads}",
                                                     workers, threads)
            print(f"{workers} x {threads}: {rates[(workers, threads)]:.2f} items/s", file=sys.stderr)
        overhead = scheduler_overhead_ms()
        sent, received, client_ms = client_costs(root / "data", root / "client")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    best = max(rates, key=lambda k: rates[k])
    per_node = rates[best]
    network_ms = (sent + received) / NETWORK_BYTES_PER_S * 1e3
    scheduler_limit, network_limit, client_limit = 1e3 / overhead, 1e3 / network_ms, 1e3 / client_ms
    limits = {"the scheduler": scheduler_limit, "the client's network": network_limit,
              "the client's reading and writing": client_limit}
    lines = [
        "# Batches on Dask (vmcl.distributed, `vmcl batch`)", "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}. Device: {machine.device.platform.name} / "
         f"{machine.device.name}, {os.cpu_count()} cores, shared with other work (load average before: {load:.1f}); "
         f"distributed {__import__('distributed').__version__}. {ITEMS} items, each a {SIZE} x {SIZE} stereo "
         "pair's `vmcl batch` item (default Config: stereo, colour, texture, mean-field MRFs, the report and "
         "fields.npz written); each cluster warmed with one item per thread first."), "",
        "## Throughput", "",
        "| setup | workers | threads per worker | items per second | x serial |",
        "|---|---|---|---|---|",
        f"| serial (one process, no Dask) | - | - | {rate_serial:.2f} | 1.00 |",
        *(f"| local cluster | {w} | {t} | {r:.2f} | {r / rate_serial:.2f} |" for (w, t), r in rates.items()),
        "",
        "## Costs per item", "",
        "| cost | value |",
        "|---|---|",
        f"| machine's run per item (serial, ms) | {machine_ms:.0f} |",
        f"| client's reading and writing per item (ms; the worker encodes the files) | {client_ms:.1f} |",
        f"| input sent to a worker per item (bytes) | {sent} |",
        f"| output sent back per item (bytes) | {received} |",
        f"| scheduler overhead per task (ms, {TASKS} empty tasks, 2 workers) | {overhead:.2f} |",
        "",
        "## A model of N nodes", "",
        (f"Each node runs items at the best rate measured here ({per_node:.2f} items per second: "
         f"{best[0]} worker(s) x {best[1]} thread(s)); N nodes give N times that until a shared resource "
         "saturates. The shared resources, each a ceiling in items per second: the scheduler "
         f"(1 / {overhead:.2f} ms = {scheduler_limit:.0f}), the client's network (input and output, "
         f"{(sent + received) / 1e6:.2f} MB per item, at {NETWORK_BYTES_PER_S * 8 / 1e9:.0f} Gbit/s, an assumption: "
         f"{network_limit:.0f}) and the client's own reading of the images and "
         f"writing of the outputs ({client_ms:.1f} ms per item on one core here: "
         f"{client_limit:.0f})."),
        "",
        "| nodes | items per second (model) | limited by |",
        "|---|---|---|",
    ]
    for nodes in (1, 2, 4, 8, 16, 32, 64, 128, 256):
        ceiling_name, ceiling = min(limits.items(), key=lambda kv: kv[1])
        rate = min(nodes * per_node, ceiling)
        lines.append(f"| {nodes} | {rate:.1f} | {'the nodes' if nodes * per_node <= ceiling else ceiling_name} |")
    ceiling_name, ceiling = min(limits.items(), key=lambda kv: kv[1])
    spread = (max(rates.values()) - min(rates.values())) / min(rates.values())
    lines[lines.index("## Costs per item") - 1:lines.index("## Costs per item") - 1] = [
        "",
        (f"Load average after the runs: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores. The setups differ by "
         f"{100 * spread:.0f}% (best {best[0]} x {best[1]}); the same script run minutes apart on this shared "
         "machine has ranked them differently, so such differences are noise here. One process already has "
         "every core (PoCL's threads); `vmcl batch` starts 1 worker x 1 thread."),
    ]
    lines += [
        "",
        (f"The first limit is {ceiling_name}, at about {ceiling / per_node:.0f} nodes of this kind "
         f"({ceiling:.0f} items per second). Faster nodes (a GPU) reach it with fewer; larger images move the "
         "network's limit down in proportion to their pixels and leave the scheduler's where it is; a "
         "client that cannot keep up can run several batches, each over part of the items, into one --out."),
        "",
        "## One worker on a GPU", "",
        "Not measured: no GPU machine was lent for this run.",
    ]
    out = Path(__file__).resolve().parent / "results" / "distributed.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
