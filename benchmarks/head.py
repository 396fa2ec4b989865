"""Round-trip latency and command throughput of the eye-head protocol (hardware/), written to
benchmarks/results/head.md.

Poggio et al., "The MIT Vision Machine", section "The Eye-Head system": the host drives three micros
over UNET. Two kinds of figures, kept apart:

* Virtual clock (the simulator behind ``sim://``): what the protocol itself costs on the wire at a baud
  rate (bytes x 10 bit times + the micro's 0.3 ms turnaround; host code takes no virtual time). These
  are exact and repeatable, and say what a real line at that rate would give with an ideal host.
* Wall clock over a pty, the simulator in another process (``python -m hardware.ptyserver``, its clock
  following the wall clock, replies paced at 115200 baud): what this Python host achieves end to end,
  including the operating system and both processes.

Run: ``python benchmarks/head.py``.
"""

from __future__ import annotations

import platform
import statistics
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from hardware.bus import Bus
from hardware.commands import Cmd, pack
from hardware.errors import CommError
from hardware.head import Head
from hardware.protocol import encode_reply, encode_request

RESULTS = ROOT / "benchmarks" / "results" / "head.md"
COMMANDS = [
    ("PING", 1, Cmd.PING, ()),
    ("STATUS", 1, Cmd.STATUS, ()),
    ("AXIS_STATUS", 1, Cmd.AXIS_STATUS, (0,)),
    ("GALVO_SET", 2, Cmd.GALVO_SET, (0, 1000, -1000)),
    ("GALVO_GET", 2, Cmd.GALVO_GET, (0,)),
    ("LENS_GET", 3, Cmd.LENS_GET, (0,)),
]


def virtual_round_trips(baudrate: int, n: int = 200) -> list[tuple[str, int, float]]:
    """(command, bytes on the wire both ways, virtual seconds per round trip)."""
    rows = []
    with Bus("sim://?seed=1", baudrate=baudrate) as bus:
        world = bus.port.world
        for name, addr, cmd, args in COMMANDS:
            payload = pack(cmd, *args)
            start = world.now
            for _ in range(n):
                reply = bus.request(addr, cmd, payload)
            # The frames as sent (byte stuffing makes their length depend on their content).
            wire = (len(encode_request(addr, reply.seq, cmd, payload))
                    + len(encode_reply(addr, reply.seq, reply.status, cmd, reply.payload)))
            rows.append((name, wire, (world.now - start) / n))
    return rows


def virtual_with_faults(url: str, n: int = 2000) -> tuple[float, float, int, int]:
    """(mean virtual seconds per request, retries per 1000 requests, failures, requests executed more
    than once) under injected faults, with the Bus's default timeout (50 ms) and retries (3)."""
    with Bus(url) as bus:
        world = bus.port.world
        runs: Counter[tuple[int, ...]] = Counter()
        handler = world.galvo._handlers[Cmd.GALVO_SET]

        def logged(*args: int) -> tuple[int, ...]:
            runs[args] += 1
            return handler(*args)

        world.galvo._handlers[Cmd.GALVO_SET] = logged
        start = world.now
        for i in range(n):
            try:
                bus.request(2, Cmd.GALVO_SET, pack(Cmd.GALVO_SET, i % 2, i - 1000, 0))  # every one distinct
            except CommError:
                pass  # counted in bus.stats.failures
        world.sleep(1.0)  # let any late frame arrive
        twice = sum(1 for count in runs.values() if count > 1)
        return (world.now - start - 1.0) / n, 1000 * bus.stats.retries / n, bus.stats.failures, twice


def virtual_motion() -> tuple[float, float]:
    """(virtual seconds to home the whole head, to sweep pan from -90 to +90 degrees)."""
    with Head("sim://?seed=1&pan=45&tilt=-45") as head:
        world = head.bus.port.world
        start = world.now
        head.home()
        homing = world.now - start
        head.move(pan=-90.0)
        start = world.now
        head.move(pan=90.0)
        return homing, world.now - start


def host_cost(n: int = 3000) -> float:
    """Wall-clock seconds this process spends per simulated PING (host code and simulator together)."""
    with Bus("sim://?seed=1") as bus:
        start = time.perf_counter()
        for _ in range(n):
            bus.request(1, Cmd.PING)
        return (time.perf_counter() - start) / n


def pty_figures(n: int = 1000, seconds: float = 3.0) -> tuple[list[float], float]:
    """(PING round trips in wall-clock seconds, STATUS requests per second) over a pty."""
    server = subprocess.Popen(
        [sys.executable, "-m", "hardware.ptyserver", "sim://?seed=1"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        path = server.stdout.readline().strip()
        with Bus(path, timeout=0.1) as bus:
            for _ in range(50):
                bus.request(1, Cmd.PING)
            trips = []
            for _ in range(n):
                start = time.perf_counter()
                bus.request(1, Cmd.PING)
                trips.append(time.perf_counter() - start)
            count, start = 0, time.perf_counter()
            while time.perf_counter() - start < seconds:
                bus.request(1, Cmd.STATUS)
                count += 1
            rate = count / (time.perf_counter() - start)
            assert bus.stats.failures == 0
        return trips, rate
    finally:
        server.terminate()
        server.wait(timeout=5)
        server.stdout.close()


def main() -> None:
    lines = [
        "# Eye-head protocol: latency and throughput",
        "",
        (
            f"Measured by `python benchmarks/head.py` on {platform.node() or 'this machine'}"
            f" ({platform.machine()}, Python {platform.python_version()}, {time.strftime('%Y-%m-%d')})."
        ),
        "",
        "## Virtual clock (simulator), 115200 baud",
        "",
        "Exact wire time: bytes x 10 bit times + 0.3 ms micro turnaround; the host takes no virtual time.",
        "",
        "| command | bytes (both ways) | round trip, ms | commands/s |",
        "|---|---:|---:|---:|",
    ]
    for name, wire, seconds in virtual_round_trips(115200):
        lines.append(f"| {name} | {wire} | {seconds * 1e3:.3f} | {1 / seconds:.0f} |")
    lines += [
        "",
        "PING at other baud rates:",
        "",
        "| baud | round trip, ms | commands/s |",
        "|---:|---:|---:|",
    ]
    for baud in (9600, 57600, 115200, 1_000_000):
        _, _, seconds = virtual_round_trips(baud, n=50)[0]
        lines.append(f"| {baud} | {seconds * 1e3:.3f} | {1 / seconds:.0f} |")
    lines += [
        "",
        (
            "GALVO_SET under injected faults (115200 baud, reply timeout 50 ms, 3 retries, 2000 requests;"
            " rates per byte, delay per transmission):"
        ),
        "",
        "| faults | mean per request, ms | commands/s | retries per 1000 | failures | executed twice |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    fault_sets = (
        "none",
        "drop=0.001&corrupt=0.001",
        "drop=0.01&corrupt=0.01",
        "drop=0.01&corrupt=0.01&delay=0.01&lag=0.1",
    )
    for faults in fault_sets:
        url = "sim://?seed=1" + ("" if faults == "none" else "&" + faults)
        mean, retries, failures, twice = virtual_with_faults(url)
        lines.append(
            f"| {faults} | {mean * 1e3:.3f} | {1 / mean:.0f} | {retries:.1f} | {failures} | {twice} |"
        )
    homing, sweep = virtual_motion()
    lines += [
        "",
        (
            f"Motion (virtual): homing the whole head from pan 45, tilt -45 took {homing:.2f} s; a pan sweep"
            f" from -90 to +90 degrees {sweep:.2f} s (default profile 50000 counts/s, 100000 counts/s^2)."
        ),
        "",
        "## Wall clock",
        "",
        (
            f"Host and simulator in one process: {host_cost() * 1e6:.0f} us of CPU-bound Python per simulated"
            " PING (what a test pays per command)."
        ),
        "",
    ]
    trips, rate = pty_figures()
    trips_ms = sorted(t * 1e3 for t in trips)
    lines += [
        (
            "Over a pty, simulator in another process, its clock following the wall clock, replies paced at"
            " 115200 baud (wire time of a PING alone: 1.776 ms):"
        ),
        "",
        (
            f"- PING round trip over {len(trips)} requests: median {statistics.median(trips_ms):.3f} ms,"
            f" 95th percentile {trips_ms[int(0.95 * len(trips_ms))]:.3f} ms, max {trips_ms[-1]:.3f} ms"
        ),
        f"- STATUS throughput: {rate:.0f} commands/s",
        "",
    ]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
