"""The Head in physical units over the simulator: homing, travel, limits, faults, stops, the eyes."""

import dataclasses
import math

import pytest

from hardware.commands import FAULT_FLAGS, Cmd, Flag, pack
from hardware.errors import Fault, NotHomed, OutOfRange, PortError, UnknownCommand
from hardware.eye import line_of_sight, mirror_angles
from hardware.head import Head
from hardware.physics import COUNTS_PER_DEGREE, PAN, TILT
from hardware.protocol import FLAG, Parser


def open_head(url="sim://?seed=1", **kwargs):
    return Head(url, **kwargs)


@pytest.fixture(scope="module")
def homed():
    """One homed head for the tests that only move it (homing takes 11 s of virtual time)."""
    with open_head() as head:
        head.home()
        yield head


def world_of(head):
    return head.bus.port.world


def at_rest(world):
    return not any(axis.moving for micro in world.micros.values() for axis in micro.axes)


@pytest.mark.parametrize("seed", [1, 2])
def test_homing_finds_the_same_encoder_zero_from_any_start(seed):
    zeros = {"pan": set(), "tilt": set()}
    starts = [-92.5, -91.05, -90.9, -45.0, 0.0, 37.0, 89.9, 92.5]
    for start in starts:
        tilt = min(max(start, -92.5), 2.5)
        with open_head(f"sim://?seed={seed}&pan={start}&tilt={tilt}") as head:
            head.home()
            world = world_of(head)
            for name, axis in zip(("pan", "tilt"), world.stepper.axes):
                zeros[name].add(axis.zero)
                assert axis.encoder == 0
                assert abs(axis.mech.position) <= 1
            assert head.pan.position == 0.0
            assert head.tilt.position == 0.0
    # The encoder zero is where the joint's true zero is, to the count, whatever the start.
    for name, found in zeros.items():
        assert max(found) - min(found) <= 1, name
        assert abs(next(iter(found))) <= 1


def test_full_sweeps_reach_both_soft_limits_within_one_count(homed):
    world = world_of(homed)
    for joint, axis, geometry in zip(homed.joints, world.stepper.axes, (PAN, TILT)):
        low, high = joint.limits
        for angle, count in ((low, geometry.soft_min), (high, geometry.soft_max), (low, geometry.soft_min)):
            homed.move(**{joint.name: angle})
            assert abs(joint.status().encoder - count) <= 1
            assert abs(axis.mech.position - count) <= 1
            assert not axis.latched
    assert homed.pan.limits == (-90.0, 90.0)
    assert homed.tilt.limits == (-90.0, 0.0)
    homed.move(pan=0.0, tilt=0.0)


def test_move_reaches_angles_to_the_encoder_resolution(homed):
    homed.move(pan=33.3, tilt=-12.5)
    assert homed.pan.position == pytest.approx(33.3, abs=0.5 / COUNTS_PER_DEGREE)
    assert homed.tilt.position == pytest.approx(-12.5, abs=0.5 / COUNTS_PER_DEGREE)
    homed.move(pan=0.0, tilt=0.0)


def test_out_of_travel_move_is_refused_on_the_host_and_nothing_moves(homed):
    world = world_of(homed)
    before = [axis.mech.position for axis in world.stepper.axes]
    requests = homed.bus.stats.requests
    with pytest.raises(OutOfRange, match=r"tilt 5 deg is outside its travel \[-90, 0\] deg; nothing moved"):
        homed.move(pan=45.0, tilt=5.0)  # the pan target is fine, but neither joint may move
    assert homed.bus.stats.requests == requests
    world.sleep(1.0)
    assert [axis.mech.position for axis in world.stepper.axes] == before


def test_out_of_travel_move_in_counts_is_refused_on_the_host_against_the_limits_read():
    with open_head("sim://?seed=2") as head:
        requests = head.bus.stats.requests
        with pytest.raises(OutOfRange, match=r"pan: counts must be in -102400\.\.102400, got 102401"):
            head.pan.move_to_counts(PAN.soft_max + 1)
        assert head.bus.stats.requests == requests


def test_out_of_travel_move_is_refused_by_the_micro_too(homed):
    world = world_of(homed)
    before = world.stepper.axes[0].mech.position
    executed = world.stepper.executed[Cmd.MOVE_TO]
    # Sent raw, past the host's checks, as a host that skipped them would.
    with pytest.raises(OutOfRange, match="stepper micro refused MOVE_TO"):
        homed.bus.request(1, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 0, PAN.soft_max + 1), who="stepper micro")
    world.sleep(1.0)
    assert world.stepper.axes[0].mech.position == before
    assert world.stepper.executed[Cmd.MOVE_TO] == executed + 1  # it reached the micro, which refused it


def test_a_move_whose_sequence_number_is_the_flag_byte_arrives(homed):
    # Protocol version 1 found a false frame inside this request whenever SEQ was A5 (2 moves in 600).
    world = world_of(homed)
    seqs = []
    world.tamper("request", lambda frame: seqs.append(Parser().feed(frame)[0].seq) or frame)
    homed.stepper.ping()
    for _ in range((FLAG - 1 - seqs[0]) % 256):
        homed.stepper.ping()
    sent = []
    world.tamper("request", lambda frame: sent.append(Parser().feed(frame)[0]) or frame)
    retries = homed.bus.stats.retries
    homed.move(tilt=-30.52)
    assert (sent[0].seq, sent[0].cmd) == (FLAG, Cmd.MOVE_TO)
    assert homed.bus.stats.retries == retries
    assert homed.tilt.position == pytest.approx(-30.52, abs=0.5 / COUNTS_PER_DEGREE)
    homed.move(tilt=0.0)


def test_move_before_homing_raises_not_homed_and_nothing_moves():
    with open_head("sim://?seed=3&pan=10&tilt=-20") as head:
        world = world_of(head)
        with pytest.raises(NotHomed, match="pan: .*not homed"):
            head.move(pan=30.0)
        with pytest.raises(NotHomed, match="left lens: not homed"):
            head.left.set_lens(zoom=50.0)
        world.sleep(1.0)
        assert world.stepper.axes[0].mech.position == pytest.approx(10 * COUNTS_PER_DEGREE)
        assert at_rest(world)


def test_limit_hit_stops_the_axis_and_latches_until_cleared_or_homed():
    with open_head("sim://?seed=4") as head:
        head.home()
        world = world_of(head)
        pan = world.stepper.axes[0]
        # A limit switch knocked 60 degrees inwards, as an obstacle would be.
        pan.mech.geometry = dataclasses.replace(PAN, switch_pos=round(30 * COUNTS_PER_DEGREE))
        with pytest.raises(Fault, match=r"pan: .*FAULT: limit switch hit.*; clear it \(Head.clear_faults\) or home \(Head.home\)"):
            head.move(pan=60.0)
        stopped = pan.mech.position
        assert 30 * COUNTS_PER_DEGREE <= stopped < 31 * COUNTS_PER_DEGREE
        with pytest.raises(Fault, match=r"fault is latched; clear it \(Head.clear_faults\)"):
            head.move(pan=0.0)  # latched: even a move away is refused
        head.tilt.move_to(-10.0)  # the other joint is not affected
        head.clear_faults()
        with pytest.raises(Fault, match="limit switch hit"):
            head.move(pan=50.0)  # still on the switch, moving further in: latches again
        assert pan.mech.position == pytest.approx(stopped, abs=50)
        head.clear_faults()
        head.move(pan=0.0)  # moving away from the switch is fine once cleared
        assert head.pan.position == 0.0
        with pytest.raises(Fault, match="limit switch hit"):
            head.move(pan=45.0)
        pan.mech.geometry = PAN  # the obstacle removed
        head.home()  # homing clears the latch too
        assert not pan.latched
        head.move(pan=25.0)
        assert head.pan.position == pytest.approx(25.0, abs=1e-3)


def test_stall_stops_the_axis_and_latches_until_cleared():
    with open_head("sim://?seed=5") as head:
        head.home()
        world = world_of(head)
        tilt = world.stepper.axes[1]
        head.move(tilt=-80.0, wait=False)
        world.sleep(0.5)
        tilt.mech.jammed = True
        with pytest.raises(Fault, match="tilt: .*FAULT: stalled"):
            head.wait()
        jammed_at = tilt.mech.position
        assert tilt.latched == Flag.FAULT_STALL
        assert not tilt.moving
        with pytest.raises(Fault):
            head.move(tilt=-60.0)
        tilt.mech.jammed = False
        head.clear_faults()
        head.move(tilt=-60.0)
        assert head.tilt.position == pytest.approx(-60.0, abs=1e-3)
        assert jammed_at != tilt.mech.position


def start_everything(head):
    head.move(pan=80.0, tilt=-80.0, wait=False)
    head.left.point(20.0, 10.0)
    head.right.set_lens(zoom=75.0, focus=1.2, iris=16.0)


def test_exception_inside_with_head_stops_every_motor():
    head = open_head("sim://?seed=6")
    world = world_of(head)
    head.home()
    with pytest.raises(RuntimeError, match="vision crashed"), head:
        start_everything(head)
        world.sleep(0.005)
        assert not at_rest(world)
        raise RuntimeError("vision crashed")
    assert at_rest(world)
    world.sleep(1.0)
    assert at_rest(world)
    assert world.stepper.axes[0].mech.position < 80 * COUNTS_PER_DEGREE
    assert not any(axis.latched for micro in world.micros.values() for axis in micro.axes)
    assert not head.bus.port.is_open


def test_exception_with_silent_micros_falls_back_to_emergency_stop():
    head = open_head("sim://?seed=6")
    world = world_of(head)
    head.home()
    with pytest.raises(RuntimeError), head:
        start_everything(head)
        for _ in range(50):
            world.tamper("reply", lambda frame: b"")  # every reply lost from here on
        raise RuntimeError("boom")
    assert at_rest(world)
    assert all(axis.latched & Flag.FAULT_ESTOP for micro in world.micros.values() for axis in micro.axes)


def test_leaving_with_head_normally_stops_every_motor_too():
    with open_head("sim://?seed=6") as head:
        world = world_of(head)
        head.home()
        start_everything(head)
    assert at_rest(world)


def test_watchdog_stops_motion_when_the_host_goes_silent():
    with open_head("sim://?seed=7", watchdog=0.25) as head:
        head.home()
        world = world_of(head)
        head.move(pan=-85.0, wait=False)
        head.bus.sleep(1.0)  # the host does nothing for a second
        pan = world.stepper.axes[0]
        assert not pan.moving
        assert pan.mech.position > -80 * COUNTS_PER_DEGREE
        assert pan.latched & Flag.FAULT_WATCHDOG
        with pytest.raises(Fault, match="watchdog"):
            head.wait()
        head.clear_faults()
        head.move(pan=-85.0)  # polling while it waits keeps the watchdog fed
        assert head.pan.position == pytest.approx(-85.0, abs=1e-3)


def test_estop_stops_everything_at_once_and_home_recovers():
    with open_head("sim://?seed=8") as head:
        head.home()
        world = world_of(head)
        start_everything(head)
        world.sleep(0.2)
        head.estop()
        assert at_rest(world)
        status = head.status()
        assert status.pan.flags & Flag.FAULT_ESTOP and status.right.flags & Flag.FAULT_ESTOP
        head.home()
        assert not head.status().pan.flags & FAULT_FLAGS


def test_wrong_micro_at_an_address_is_reported_at_start_up():
    with pytest.raises(UnknownCommand, match="address 2: expected the stepper micro, found a galvo micro"):
        Head("sim://", stepper=2, galvo=1)


def test_mirror_geometry_is_coupled_and_inverted_exactly():
    assert line_of_sight(1.0, 0.0) == pytest.approx((2.0, 0.0))
    assert line_of_sight(0.0, 1.0) == pytest.approx((0.0, 2.0))
    azimuth, _ = line_of_sight(8.0, 8.0)
    assert abs(azimuth - 16.0) > 0.2  # the second mirror sees a beam the first has turned
    for azimuth in (-18.0, -5.0, 0.0, 7.5, 18.0):
        for elevation in (-18.0, 0.0, 3.0, 18.0):
            assert line_of_sight(*mirror_angles(azimuth, elevation)) == pytest.approx(
                (azimuth, elevation), abs=1e-9
            )
    with pytest.raises(OutOfRange, match="beyond"):
        mirror_angles(30.0, 0.0)


def test_pointing_and_lens_in_physical_units(homed):
    homed.left.point(12.0, -6.0)
    homed.left.set_lens(zoom=50.0, focus=2.0, iris=5.6)
    homed.wait()
    status = homed.left.status()
    assert (status.azimuth, status.elevation) == pytest.approx((12.0, -6.0), abs=0.003)
    assert status.zoom_mm == pytest.approx(50.0, abs=62.5 / 4095)
    assert status.focus_m == pytest.approx(2.0, rel=2e-3)
    assert status.f_number == pytest.approx(5.6, rel=2e-3)
    homed.left.set_lens(focus=math.inf)
    homed.wait()
    assert homed.left.status().focus_m == math.inf
    assert homed.left.status().zoom_mm == pytest.approx(50.0, abs=62.5 / 4095)


def test_lens_lands_on_the_same_ring_position_from_either_side(homed):
    ring = world_of(homed).lens.axes[4].mech  # right eye, focus
    rings = []
    for start in (1.3, 100.0):
        homed.right.set_lens(focus=start)
        homed.wait()
        homed.right.set_lens(focus=3.0)
        homed.wait()
        rings.append(ring.ring)
    assert rings[0] == rings[1]


def test_fixate_sets_the_vergence(homed):
    homed.fixate(1.0, baseline=0.3)
    assert homed.vergence() == pytest.approx(2 * math.degrees(math.atan(0.15)), abs=0.005)
    homed.fixate(1e9)
    assert homed.vergence() == pytest.approx(0.0, abs=0.005)
    # Nearer than the mirrors turn the eyes: the refusal spoke of a gaze of 26.6 deg the caller never gave.
    before = homed.vergence()
    with pytest.raises(OutOfRange, match=r"distance 0.3 m is nearer .*: the nearest is 0.412 m; nothing moved"):
        homed.fixate(0.3)
    assert homed.vergence() == before
    homed.fixate(0.413)
    assert homed.vergence() == pytest.approx(2 * math.degrees(math.atan(0.15 / 0.413)), abs=0.005)


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda h: h.move(pan="10"), TypeError, "pan must be a number"),
        (lambda h: h.move(tilt=math.nan), ValueError, "tilt must be finite"),
        (lambda h: h.left.set_lens(), ValueError, "at least one of zoom"),
        (lambda h: h.left.set_lens(zoom=100.0), OutOfRange, r"zoom must be in \[12.5, 75\] mm"),
        (lambda h: h.left.set_lens(iris=1.0), OutOfRange, "iris"),
        (lambda h: h.right.set_mirrors(0.0, 11.0), OutOfRange, "right mirror y"),
        (lambda h: h.left.point(40.0, 0.0), OutOfRange, "beyond"),
        (lambda h: h.fixate(-1.0), ValueError, "distance"),
        (lambda h: h.pan.set_profile(0.0, 10.0), ValueError, "speed"),
        (lambda h: h.stepper.set_watchdog(100.0), ValueError, "period"),
        (lambda h: h.move(pan=1e308), OutOfRange, r"pan 1e\+308 deg is outside its travel \[-90, 90\]"),
        (lambda h: h.left.point(1e308, 0.0), OutOfRange, r"azimuth 1e\+308, elevation 0\) deg needs"),
        (lambda h: h.left.point(0.0, True), TypeError, "elevation must be a finite number"),
        (lambda h: h.right.set_mirrors(math.nan, 0.0), OutOfRange, r"right mirror x must be in \[-10, 10\]"),
        (lambda h: h.pan.set_profile(100.0, 10.0), OutOfRange, r"speed must be in \[0.000878906, 52.7344\]"),
        (lambda h: h.pan.set_profile(10.0, math.inf), OutOfRange, "acceleration must be in .* got inf"),
        (lambda h: h.pan.set_profile(math.nan, 10.0), OutOfRange, "speed .* got nan"),
        (lambda h: h.tilt.set_profile(1e308, 10.0), OutOfRange, r"speed .* got 1e\+308"),
        (lambda h: h.tilt.set_profile(True, 10.0), TypeError, "speed must be a number"),
        (lambda h: h.stepper.set_profile(0, 16974053, 5), OutOfRange, r"vmax must be in 1\.\.60000"),
        (lambda h: h.stepper.set_profile(0, 100, 0), OutOfRange, r"accel must be in 1\.\.400000, got 0"),
        (lambda h: h.stepper.set_profile(0, 100.0, 5), TypeError, "vmax must be an int"),
        (lambda h: h.stepper.set_profile(2, 100, 5), OutOfRange, r"axis must be in 0\.\.1, got 2"),
        (lambda h: h.stepper.move_to(True, 0), TypeError, "axis must be an int"),
        (lambda h: h.stepper.move_to(1, 2**40), OutOfRange, r"counts must be in -102400\.\.0"),
        (lambda h: h.stepper.home("0"), TypeError, "axis"),
        (lambda h: h.galvo.set_angles(0, 10_001, 0), OutOfRange, r"x must be in -10000\.\.10000"),
        (lambda h: h.galvo.set_angles(0, 0, 1.5), TypeError, "y must be an int"),
        (lambda h: h.lens.set_counts(1, 0, 4096, 0), OutOfRange, r"focus must be in 0\.\.4095, got 4096"),
        (lambda h: h.lens.set_counts(2, 0, 0, 0), OutOfRange, "eye must be in 0..1"),
        (lambda h: h.lens.get(-1), OutOfRange, "eye"),
        (lambda h: h.stepper.set_watchdog(math.inf), OutOfRange, r"period must be in \[0.001, 65.535\]"),
        (lambda h: h.stepper.set_watchdog(math.nan), OutOfRange, "period .* got nan"),
        (lambda h: h.stepper.set_watchdog(True), TypeError, "period"),
        (lambda h: h.fixate(True), ValueError, "distance must be a positive number of metres"),
        # An int too large for a float is out of range, never an OverflowError.
        (lambda h: h.move(pan=10**400), OutOfRange, "pan inf deg is outside its travel"),
        (lambda h: h.left.point(10**400, 0), ValueError, "azimuth must be a finite number of degrees, got inf"),
        (lambda h: h.left.point("1", 0), TypeError, "azimuth must be a finite number of degrees, got '1'"),
        (lambda h: h.fixate(-(10**400)), ValueError, "distance must be a positive number of metres .*, got -inf"),
        (lambda h: h.wait(timeout=math.nan), OutOfRange, r"timeout must be in \[0, 86400\] seconds, got nan"),
        (lambda h: h.bus.sleep(math.inf), OutOfRange, "seconds must be in .* got inf"),
    ],
)
def test_bad_arguments_are_refused_by_name_before_anything_is_sent(homed, call, error, message):
    requests = homed.bus.stats.requests
    with pytest.raises(error, match=message):
        call(homed)
    assert homed.bus.stats.requests == requests


@pytest.mark.parametrize(
    ("watchdog", "error", "message"),
    [
        (math.inf, ValueError, r"watchdog must be in \[0.001, 65.535\] seconds, got inf"),
        (math.nan, ValueError, "watchdog .* got nan"),
        (1e308, ValueError, "watchdog"),
        (0.0, ValueError, "watchdog"),
        (True, TypeError, "watchdog must be a number"),
        ("1", TypeError, "watchdog must be a number"),
    ],
)
def test_head_refuses_a_bad_watchdog_by_name(watchdog, error, message):
    with pytest.raises(error, match=message):
        Head("sim://?seed=1", watchdog=watchdog)


def test_a_dead_port_raises_port_error_and_not_serial_exception():
    head = open_head("sim://?seed=2")
    head.status()
    head.bus.port.unplug()
    with pytest.raises(PortError, match="disconnected") as info, head:
        head.status()
    assert info.value.__cause__ is not None
    assert not head.bus.port.is_open


def test_the_blocks_own_error_is_the_one_seen_when_the_stop_on_leaving_fails_too():
    """The port lost inside a `with`: stopping, the emergency stop and closing on the way out fail as well,
    and the caller sees the block's own error, not theirs; without an error in the block, theirs."""
    head = open_head("sim://?seed=2")
    with pytest.raises(RuntimeError, match="the caller's own"), head:
        head.bus.port.unplug()
        raise RuntimeError("the caller's own")
    head = open_head("sim://?seed=2")
    with pytest.raises(PortError), head:
        head.bus.port.unplug()


def test_profile_changes_the_speed(homed):
    world = world_of(homed)
    homed.pan.set_profile(10.0, 100.0)
    start = world.now
    homed.move(pan=20.0)
    slow = world.now - start
    homed.pan.set_profile(44.0, 88.0)
    start = world.now
    homed.move(pan=0.0)
    assert slow > 2.0 > world.now - start


def test_a_stop_during_the_final_braking_never_carries_a_joint_past_its_target():
    """Stopped while braking onto the pan's soft limit (+90 degrees), the joint comes to rest on the limit or
    short of it, never past (a stop cannot take it further than the move would have), and on a whole count:
    its encoder reads its target. Stopped while cruising, it ends short of the limit, on a whole count too."""
    head = open_head()
    world = world_of(head)
    head.home()
    for dt in [3.0 + 0.05 * k for k in range(34)]:  # cruising, then the last deceleration onto +90
        head.move(pan=-90, wait=True)
        head.move(pan=90, wait=False)
        world.sleep(dt)
        head.stop()
        head.wait()
        status = head.pan.status()
        assert status.encoder <= 90 * COUNTS_PER_DEGREE + 1e-6, (dt, status)
        assert status.encoder == round(status.target * COUNTS_PER_DEGREE), (dt, status)
    head.close()


@pytest.mark.parametrize("far", [math.inf, 10**400], ids=["inf", "an int beyond float"])
def test_fixating_at_infinity_is_parallel_gaze(homed, far):
    """A fixation at infinity is meaningful (parallel eyes, vergence 0), as a lens focused at inf is: it was
    refused as not a positive number of metres. An int too large for a float is as far."""
    homed.fixate(1.0)
    assert homed.vergence() > 10.0
    homed.fixate(far)
    assert homed.vergence() == pytest.approx(0.0, abs=1e-9)
    for eye in homed.eyes:
        status = eye.status()
        assert (status.azimuth, status.elevation) == pytest.approx((0.0, 0.0), abs=1e-9)
    for bad, shown in ((-math.inf, "-inf"), (math.nan, "nan"), (0.0, "0")):
        with pytest.raises(ValueError, match=rf"distance must be a positive number of metres \(or inf, parallel "
                                             rf"gaze\), got {shown}$"):
            homed.fixate(bad)
    with pytest.raises(ValueError, match="baseline must be a positive number of metres, got inf"):
        homed.fixate(1.0, baseline=math.inf)


def test_a_refused_fixation_names_the_gaze_limit_and_a_refused_gaze_the_mirror_angle_limit(homed):
    """fixate said "the mirrors reach 20" (a gaze angle) where point said "mirror angles beyond +-10 deg" (a
    mirror angle): each now says which limit it means, and gives its value."""
    widest = min(abs(line_of_sight(sign * 10.0, 0.0)[0]) for sign in (1.0, -1.0))
    with pytest.raises(OutOfRange) as fixation:
        homed.fixate(0.01)
    assert f"(each gaze would turn 86.2 deg; the gaze limit is {widest:.3g} deg, the mirror angles at their limit " \
           "of +-10 deg): the nearest is 0.412 m" in str(fixation.value)
    assert "mirrors reach" not in str(fixation.value)
    with pytest.raises(OutOfRange) as gaze:
        homed.left.point(20.0, 20.0)
    assert str(gaze.value) == ("gaze (azimuth 20, elevation 20) deg needs mirror angles beyond the mirror angle limit "
                               "of +-10 deg")
