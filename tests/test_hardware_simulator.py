"""The simulated eye-head: wire timing, fault injection, URL parsing, and the mechanics of each axis."""

import itertools
import math
import random

import pytest
import serial

from hardware.bus import open_port
from hardware.commands import PROTOCOL_VERSION, Cmd, Flag, pack
from hardware.firmware import LensAxis
from hardware.physics import (
    COUNTS_PER_MOTOR_REV,
    PAN,
    TILT,
    LensMechanism,
    StepperMechanism,
    trapezoid_step,
)
from hardware.protocol import encode_reply, encode_request
from hardware.simulator import Faults, World

PING_TO_STEPPER = encode_request(1, 1, Cmd.PING)


def run_profile(target, vmax, accel, *, pos=0.0, vel=0.0, dt=1e-3, steps=100_000):
    trace = [(pos, vel)]
    for _ in range(steps):
        pos, vel = trapezoid_step(pos, vel, target, vmax, accel, dt)
        trace.append((pos, vel))
        if pos == target and vel == 0.0:
            return trace
    raise AssertionError("profile never arrived")


def test_trapezoid_respects_limits_and_lands_exactly():
    vmax, accel, dt = 50_000.0, 100_000.0, 1e-3
    trace = run_profile(102_400, vmax, accel, dt=dt)
    velocities = [v for _, v in trace]
    assert max(velocities) == pytest.approx(vmax)
    assert max(abs(b - a) for a, b in itertools.pairwise(velocities)) <= accel * dt + 1e-6
    assert trace[-1] == (102_400.0, 0.0)
    # Accelerate, cruise, decelerate: distance / vmax + vmax / accel, to the tick; no overshoot.
    assert (len(trace) - 1) * dt == pytest.approx(102_400 / vmax + vmax / accel, abs=dt)
    assert max(p for p, _ in trace) == 102_400


def test_retarget_inside_the_stopping_distance_overshoots_and_returns():
    pos, vel = 0.0, 50_000.0
    trace = run_profile(1000, 50_000.0, 100_000.0, pos=pos, vel=vel)
    assert max(p for p, _ in trace) > 1000 + 5000  # v^2 / 2a = 12500 counts to stop
    assert trace[-1] == (1000.0, 0.0)


def test_index_pulses_come_once_per_motor_revolution():
    mech = StepperMechanism(PAN, 0.0, lambda: 0.0)
    found = [
        i
        for start in range(-3 * COUNTS_PER_MOTOR_REV, 3 * COUNTS_PER_MOTOR_REV, 100)
        if (i := mech.index_between(start, start + 100)) is not None
    ]
    assert len(found) == 6
    assert {b - a for a, b in itertools.pairwise(found)} == {COUNTS_PER_MOTOR_REV}
    assert PAN.home_index in {i + k * COUNTS_PER_MOTOR_REV for i in found for k in range(-30, 30)}
    assert mech.index_between(found[0] + 10, found[0] - 10) is None  # latched moving up only


def test_limit_switch_closes_and_opens_with_hysteresis():
    mech = StepperMechanism(TILT, -80.0 * 1137.0, lambda: 0.0)
    p = mech.position
    while not mech.switch_neg:
        p -= 1
        mech.drive(p)
    closed = p
    while mech.switch_neg:
        p += 1
        mech.drive(p)
    assert closed == math.floor(TILT.switch_neg)
    assert p - closed == pytest.approx(TILT.hysteresis, abs=1)


def test_hard_stop_holds_the_joint():
    mech = StepperMechanism(PAN, 0.0, lambda: 0.0)
    mech.drive(PAN.hard_max + 5000)
    assert mech.position == PAN.hard_max
    assert mech.switch_pos


def test_lens_backlash_and_the_firmware_approach_from_below():
    mech = LensMechanism(2000.0, backlash=12.0)
    mech.drive(2100.0)
    from_below = mech.ring
    mech.drive(2200.0)
    mech.drive(2100.0)
    assert mech.ring - from_below == pytest.approx(12.0)  # the raw gears land 12 counts apart
    rings = []
    for start in (1500, 2600):
        axis = LensAxis(LensMechanism(float(start), backlash=12.0))
        axis.homed = True
        axis.go_to(2100 - start + axis.pos)
        while axis.moving:
            axis.step(1e-3)
        rings.append(axis.mech.ring)
    assert rings[0] == pytest.approx(rings[1])


def test_ping_round_trip_takes_exactly_the_bytes_and_the_turnaround():
    world = World(baudrate=115200, turnaround=3e-4)
    world.host_write(PING_TO_STEPPER)
    expected = encode_reply(1, 1, 0, Cmd.PING, bytes((1, PROTOCOL_VERSION)))
    reply = world.host_read(len(expected), 1.0)
    assert reply == expected
    assert world.now == pytest.approx((len(PING_TO_STEPPER) + len(reply)) * 10 / 115200 + 3e-4)


def test_read_waits_for_its_timeout_in_virtual_time_only():
    world = World()
    assert world.host_read(5, 0.25) == b""
    assert world.now == pytest.approx(0.25)
    port = open_port("sim://")
    with pytest.raises(serial.SerialException, match="block for ever"):
        port.timeout = None
        port.read(1)


def test_same_seed_same_faults_same_bytes():
    def session(seed):
        world = World(
            seed=seed, faults=Faults(drop=0.05, corrupt=0.05, duplicate=0.05, truncate=0.1, delay=0.1)
        )
        received = []
        for _ in range(50):
            world.host_write(PING_TO_STEPPER)
            received.append((world.host_read(11, 0.2), world.now))
        return received

    assert session(3) == session(3)
    assert session(3) != session(4)


@pytest.mark.parametrize("kind", ["drop", "corrupt", "duplicate", "truncate", "delay"])
def test_each_fault_comes_at_its_rate_and_does_what_it_says(kind):
    rng = random.Random(0)
    faults = Faults(**{kind: 0.1}, lag=0.3)
    data = bytes(range(20))
    hits = 0
    for _ in range(2000):
        delay, slots = faults.apply(data, rng)
        if kind == "drop":
            assert len(slots) == 20
            assert all(s in (b, None) for s, b in zip(slots, data))
            hits += slots.count(None)
        elif kind == "corrupt":
            flips = [(s ^ b).bit_count() for s, b in zip(slots, data)]
            assert set(flips) <= {0, 1}
            hits += sum(flips)
        elif kind == "duplicate":
            hits += len(slots) - 20
        elif kind == "truncate":
            assert slots == list(data[: len(slots)])
            hits += len(slots) < 20
        else:
            assert delay in (0.0, 0.3)
            hits += delay > 0
    trials = 2000 if kind in ("truncate", "delay") else 40_000
    assert hits / trials == pytest.approx(0.1, rel=0.15)


def test_galvo_slews_at_its_rate():
    world = World()
    world.host_write(encode_request(2, 1, Cmd.GALVO_SET, pack(Cmd.GALVO_SET, 0, 10_000, 0)))
    world.host_flush()
    start = world.now
    mirror = world.galvo.axes[0].mirrors[0]
    while mirror.moving:
        world.sleep(1e-3)
    assert world.now - start == pytest.approx(10.0 / 500.0, abs=2e-3)


def test_watchdog_stops_motion_when_the_host_falls_silent():
    world = World(seed=1)
    world.host_write(encode_request(2, 1, Cmd.WATCHDOG, pack(Cmd.WATCHDOG, 8)))
    world.host_write(encode_request(2, 2, Cmd.GALVO_SET, pack(Cmd.GALVO_SET, 1, 10_000, 10_000)))
    world.host_flush()
    pair = world.galvo.axes[1]
    world.sleep(0.005)
    assert pair.moving
    assert not pair.latched
    world.sleep(0.1)  # a 10 degree slew takes 20 ms: the watchdog (8 ms) stops it half way
    assert not pair.moving
    assert 3_000 < pair.mirrors[0].angle < 6_000
    assert pair.latched == Flag.FAULT_WATCHDOG


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("loop://", "must look like"),
        ("sim://host?seed=1", "must look like"),
        ("sim://?sede=1", "unknown sim:// parameter 'sede'"),
        ("sim://?seed=x", "'seed' has a bad value"),
        ("sim://?drop=1.5", "drop is a probability"),
        ("sim://?corrupt=-0.1", "corrupt must be a finite number >= 0"),
        ("sim://?lag=inf", "lag must be a finite number >= 0"),
        ("sim://?turnaround=inf", "turnaround must be a finite number"),
        ("sim://?absent=40", "absent addresses"),
        ("sim://?pan=120", "beyond the joint's mechanical stops"),
        ("sim://?turnaround=-1", "turnaround"),
    ],
)
def test_bad_urls_say_what_is_wrong(url, message):
    with pytest.raises(ValueError, match=message):
        World.from_url(url)


def test_url_sets_the_world_up():
    world = World.from_url("sim://?seed=5&absent=2,3&pan=12.5&tilt=-45&drop=0.01&lag=0.2")
    assert sorted(world.micros) == [1]
    assert world.faults == Faults(drop=0.01, lag=0.2)
    assert world.stepper.axes[0].mech.position == pytest.approx(12.5 * 409600 / 360)
    assert world.stepper.axes[1].mech.position == pytest.approx(-45 * 409600 / 360)
