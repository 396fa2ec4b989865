"""The vmcl-head command line, against the simulator."""

import io
import re

import pytest

from hardware.cli import main


def run(argv):
    out = io.StringIO()
    return main(argv, out=out), out.getvalue()


def test_a_sequence_of_commands_runs_in_one_session(capsys):
    status, out = run(
        [
            "home",
            "move",
            "30",
            "-10",
            "point",
            "left",
            "5",
            "2",
            "lens",
            "right",
            "zoom=50",
            "focus=inf",
            "iris=4",
            "status",
        ]
    )
    assert status == 0
    assert out.startswith("homed\n")
    assert "pan    +30.000 deg" in out
    assert "tilt   -10.000 deg" in out
    assert re.search(r"left  gaze \(\+(4\.99\d|5\.00\d), \+(1\.99\d|2\.00\d)\) deg", out)
    assert "zoom 50.0 mm, focus inf m, F4.0" in out
    assert capsys.readouterr().err == ""


def test_status_of_a_fresh_head_says_not_homed():
    status, out = run(["--port", "sim://?seed=2", "status"])
    assert status == 0
    assert out.startswith("pan   not homed, +0 counts from power-up, idle\ntilt  not homed")
    assert out.count("lens not homed") == 2


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "no command given"),
        (["frob"], "unknown command 'frob'"),
        (["move", "30"], "move needs PAN TILT"),
        (["move", "x", "1"], "PAN must be a number, got 'x'"),
        (["move", "nan", "1"], "PAN must be a finite number, got 'nan'"),
        (["home", "--port", "sim://", "status"], r"options go before the commands .*got '--port' after them"),
        (["lens", "left", "focus=-inf"], "focus must be a finite number or inf, got '-inf'"),
        (["point", "middle", "1", "2"], "EYE must be left or right"),
        (["lens", "left"], "lens needs at least one of"),
        (["lens", "left", "zoom=20", "zoom=30"], "once each"),
        (["lens", "left", "aperture=2"], "got 'aperture'"),
        (["home", "move", "100", "0"], "pan 100 deg is outside its travel"),
        (["home", "lens", "left", "zoom=5"], r"zoom must be in \[12.5, 75\] mm"),
        (["--port", "sim://?nope=1", "status"], "unknown sim:// parameter 'nope'"),
        (["move", "1e308", "0"], r"pan 1e\+308 deg is outside its travel \[-90, 90\] deg; nothing moved"),
        (["move", "0", "-1e308"], r"tilt -1e\+308 deg is outside its travel"),
        (
            ["point", "left", "1e308", "0"],
            r"gaze \(azimuth 1e\+308, elevation 0\) deg needs mirror angles beyond",
        ),
        (["--baud", "fast", "status"], "argument --baud: invalid int value: 'fast'"),
    ],
)
def test_usage_and_input_errors_exit_2_with_one_line(capsys, argv, message):
    status, _ = run(argv)
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith("vmcl-head: error: ")
    assert err.count("\n") == 1
    assert re.search(message, err)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["move", "10", "0"], "pan: stepper micro refused MOVE_TO: the axis is not homed"),
        (["--port", "sim://?absent=2", "status"], "galvo micro (address 2) gave no valid reply to PING"),
        (["--port", "/dev/does-not-exist", "status"], "cannot use port '/dev/does-not-exist'"),
    ],
)
def test_hardware_errors_exit_1_with_one_line(capsys, argv, message):
    status, _ = run(argv)
    err = capsys.readouterr().err
    assert status == 1
    assert message in err
    assert err.count("\n") == 1


def test_estop_latches_a_fault_everywhere_and_home_clears_it():
    status, out = run(["home", "estop", "status"])
    assert status == 0
    assert "emergency stop sent" in out
    assert out.count("FAULT: emergency stop") == 4
    status, out = run(["estop", "home", "status"])
    assert status == 0
    assert "FAULT" not in out


def test_help_exits_0(capsys):
    assert main(["--help"]) == 0
    assert "move PAN TILT" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["home", "move", "inf", "0"], "PAN must be a finite number, got 'inf'"),
    (["home", "move", "0", "1e400"], "TILT must be a finite number, got '1e400'"),
    (["home", "point", "left", "30", "0"], "needs mirror angles beyond"),
    (["home", "lens", "left", "zoom=5"], r"zoom must be in \[12.5, 75\] mm"),
    (["home", "lens", "right", "iris=0.5"], "iris"),
])
def test_what_can_be_checked_without_the_head_stops_the_line_before_anything_runs(capsys, argv, message):
    """A bad number, gaze or lens setting anywhere in the line: exit 2 and nothing ran (no homing first)."""
    status, out = run(argv)
    err = capsys.readouterr().err
    assert status == 2 and re.search(message, err), err
    assert "homed" not in out


def test_an_interrupt_stops_the_head_and_exits_130_with_one_line(capsys, monkeypatch):
    """Ctrl-C during a command: leaving the session stops the motors, and the command line says so in one
    line with the shell's status for an interrupt, not a traceback."""
    from hardware.head import Head

    stopped = []
    monkeypatch.setattr(Head, "home", lambda self, **kwargs: (_ for _ in ()).throw(KeyboardInterrupt()))
    real_stop = Head.stop
    monkeypatch.setattr(Head, "stop", lambda self: (stopped.append(True), real_stop(self))[1])
    status, _ = run(["home"])
    err = capsys.readouterr().err
    assert status == 130 and err == "vmcl-head: error: interrupted; the head was told to stop\n", err
    assert stopped


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["home", "estop", "move", "10", "0"],
         "pan: stepper micro refused MOVE_TO: a fault is latched; clear it with home (vmcl-head [--port URL] home ...)"),
        (["home", "estop", "point", "left", "1", "1"],
         ("left eye: galvo micro refused GALVO_SET: a fault is latched; clear it with home (vmcl-head [--port URL] "
          "home ...)")),
        (["move", "10", "0"],
         "pan: stepper micro refused MOVE_TO: the axis is not homed; home it first (vmcl-head [--port URL] home ...)"),
        (["lens", "left", "zoom=50"], "left lens: not homed; home it first (vmcl-head [--port URL] home ...)"),
    ],
)
def test_a_refusal_by_the_head_names_the_command_that_clears_it_and_exits_1(capsys, argv, message):
    """After estop the advice named Head.clear_faults, which the command line does not offer: it names home,
    as its help does. A refusal by the head is exit status 1, as documented (the line itself was valid)."""
    status, _ = run(argv)
    err = capsys.readouterr().err
    assert status == 1
    assert err == f"vmcl-head: error: {message}\n"
    assert "Head." not in err and "clear_faults" not in err


def test_the_documented_exit_statuses_say_a_refusal_by_the_head_is_1():
    import hardware.cli

    doc = " ".join(hardware.cli.__doc__.split())
    assert "1 the head refused a command or failed" in doc and "A refusal by the head is 1, not 2" in doc
