"""End to end: the host drives a simulated head served on a pty by another process."""

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import hardware
from hardware.commands import FAULT_FLAGS, Flag
from hardware.errors import OutOfRange, PortError, Timeout
from hardware.head import Head

# The package's parent directory, so the server imports this checkout of `hardware` installed or not.
_ROOT = str(Path(hardware.__file__).resolve().parent.parent)


def _server_env() -> dict[str, str]:
    """This environment with the checkout first on the path, the paths it had kept after it (packages
    installed through PYTHONPATH, pyserial say, must stay importable in the server)."""
    return dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [_ROOT, os.environ.get("PYTHONPATH")])))


def start_server(url: str, rate: float) -> tuple[subprocess.Popen, str]:
    env = _server_env()
    proc = subprocess.Popen(
        [sys.executable, "-m", "hardware.ptyserver", url, "--rate", str(rate)],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    path = proc.stdout.readline().strip()
    if not path.startswith("/dev/"):
        proc.kill()
        proc.wait()
        pytest.fail(f"pty server did not start: {path!r}")
    return proc, path


def stop_server(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    proc.stdout.close()


@pytest.fixture
def served():
    """A server whose virtual clock runs 20 times faster than the wall clock, so homing takes ~0.6 s."""
    proc, path = start_server("sim://?seed=11&absent=9", rate=20.0)
    try:
        yield proc, path
    finally:
        stop_server(proc)
    assert proc.returncode is not None


def test_head_over_a_pty_homes_moves_points_and_refuses(served):
    proc, path = served
    with Head(path, timeout=0.1) as head:
        head.home()
        head.move(pan=-60.0, tilt=-30.0)
        head.right.point(-4.0, 3.0)
        head.right.set_lens(zoom=40.0, focus=1.5, iris=2.8)
        head.wait()
        status = head.status()
        assert status.pan.position == pytest.approx(-60.0, abs=1e-3)
        assert status.tilt.position == pytest.approx(-30.0, abs=1e-3)
        assert (status.right.azimuth, status.right.elevation) == pytest.approx((-4.0, 3.0), abs=0.003)
        assert status.right.zoom_mm == pytest.approx(40.0, abs=0.02)
        with pytest.raises(OutOfRange):
            head.move(pan=-100.0)
        head.estop()
        assert head.status().pan.flags & Flag.FAULT_ESTOP
        head.clear_faults()
        assert not head.status().pan.flags & FAULT_FLAGS
        assert head.bus.stats.failures == 0
    # A second session on the same running server finds it where the first left it.
    with Head(path, timeout=0.1) as head:
        assert head.pan.position == pytest.approx(-60.0, abs=1e-3)
        with pytest.raises(Timeout):
            head.bus.request(9, 0x01)
    assert proc.poll() is None


def test_a_port_held_by_one_host_is_refused_to_a_second(served):
    """Two hosts on one line would interleave their frames: the port opens for one at a time."""
    _, path = served
    with Head(path, timeout=0.1) as head:
        with pytest.raises(PortError, match=f"cannot use port '{path}'"):
            Head(path, timeout=0.1)
        assert head.pan.position is not None  # the first host still has it
    with Head(path, timeout=0.1) as head:  # free again once closed
        head.status()


def test_server_exits_when_its_parent_dies():
    # A parent shell starts the server and exits at once; the orphaned server must not linger.
    script = (
        "import subprocess, sys; p = subprocess.Popen([sys.executable, '-m', 'hardware.ptyserver'], "
        "stdout=subprocess.PIPE, text=True); print(p.pid, p.stdout.readline().strip(), flush=True)"
    )
    env = _server_env()
    out = subprocess.run(
        [sys.executable, "-c", script], check=True, capture_output=True, text=True, env=env, timeout=30
    )
    pid = int(out.stdout.split()[0])
    for _ in range(100):
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return
        subprocess.run(["sleep", "0.05"], check=True)
    os.kill(pid, signal.SIGKILL)
    pytest.fail("the pty server outlived its parent")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sim://?drop=2"], "drop is a probability"),
        (["--rate", "inf"], r"--rate must be in \[0.001, 1000\] virtual seconds per second, got inf"),
        (["--rate", "1e308"], r"--rate must be in .* got 1e\+308"),
        (["--rate", "nan"], "--rate must be in .* got nan"),
        (["--rate", "0"], "--rate must be in .* got 0"),
        (["--rate", "fast"], "argument --rate: invalid float value: 'fast'"),
        (["--baud", "0"], "baudrate must be a positive int, got 0"),
    ],
)
def test_bad_server_options_exit_2_with_one_line_naming_them(args, message):
    env = _server_env()
    done = subprocess.run(
        [sys.executable, "-m", "hardware.ptyserver", *args],
        check=False,
        capture_output=True,
        text=True,
        env=env,
        timeout=30,
    )
    assert done.returncode == 2
    assert done.stderr.startswith("python -m hardware.ptyserver: error: ")
    assert done.stderr.count("\n") == 1
    assert re.search(message, done.stderr)


def test_a_server_that_dies_under_the_host_raises_port_error():
    proc, path = start_server("sim://?seed=12", rate=20.0)
    try:
        head = Head(path, timeout=0.1)
        head.status()
        proc.kill()
        proc.wait()
        with pytest.raises(PortError, match=repr(path)) as info, head:
            head.status()
        assert info.value.__cause__ is not None
    finally:
        stop_server(proc)
