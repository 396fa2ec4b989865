"""The vmcl command: exit codes, the files it promises, and one clear line for bad input."""

import json
import os
import re
import signal
import subprocess
import sys
import time
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

import vmcl
from vmcl import scenes
from vmcl.cli import main
from vmcl.datasets import read_image
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.output_folder import is_whole, output_folder
from vmcl.pipeline import Config, VisionMachine


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    folder = tmp_path_factory.mktemp("images")
    s = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    paths = {}
    for name, image in (("left", s.left), ("right", s.right), ("next", s.left_next)):
        paths[name] = folder / f"{name}.png"
        cv2.imwrite(str(paths[name]), cv2.cvtColor(np.round(image * 255).clip(0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR))
    paths["small"] = folder / "small.png"
    cv2.imwrite(str(paths["small"]), np.zeros((32, 48), np.uint8))
    paths["junk"] = folder / "junk.png"
    paths["junk"].write_text("not an image")
    paths["fast"] = folder / "fast.toml"
    paths["fast"].write_text('[mrf]\nmethod = "icm"\n')
    return paths


def _float_image(path):
    """A float TIFF on the 0..255 scale, as some tools save brightness."""
    cv2.imwrite(str(path), np.linspace(0, 255, 32 * 32, dtype=np.float32).reshape(32, 32))
    return path


def _written(path, text):
    path.write_text(text)
    return path


def _leftovers(folder):
    return [p.name for p in folder.iterdir() if ".partial-" in p.name or ".old-" in p.name]


def test_demo_writes_the_report(tmp_path, images, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--size", "64", "--quiet", "--config", str(images["fast"])]) == 0
    assert {"report.html", "cartoon.png", "disparity.png", "flow.png"} <= {p.name for p in out.iterdir()}
    printed = capsys.readouterr().out
    assert "bad 1" in printed and "EPE" in printed and "albedo" in printed
    assert not _leftovers(tmp_path)


def test_demo_says_the_runs_notes_as_run_does(tmp_path, capsys):
    # The notes were only in the report: a table of recalls of 0 in the terminal had no word beside it.
    out = tmp_path / "demo"
    assert main(["demo", "--data", "cues", "--out", str(out), "--size", "64", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "vmcl: note: edges: Canny found no brightness edge" in err, err


def test_run_on_files_writes_report_and_fields(tmp_path, images):
    out = tmp_path / "run"
    code = main(["run", str(images["left"]), str(images["right"]), "--next", str(images["next"]),
                 "--config", str(images["fast"]), "--out", str(out), "--quiet"])
    assert code == 0
    fields = np.load(out / "fields.npz")
    assert fields["disparity"].shape == (64, 64) and fields["flow"].shape == (64, 64, 2)
    assert (out / "report.html").stat().st_size > 1000
    # The settings it ran with: the config file's over the defaults; given back as --config, the same run.
    settings = json.loads((out / "settings.json").read_text())
    assert settings == Config.from_toml(images["fast"]).to_dict() and settings != Config().to_dict()
    again = tmp_path / "again"
    assert main(["run", str(images["left"]), str(images["right"]), "--next", str(images["next"]),
                 "--config", str(out / "settings.json"), "--out", str(again), "--quiet"]) == 0
    assert json.loads((again / "settings.json").read_text()) == settings
    np.testing.assert_array_equal(np.load(again / "fields.npz")["disparity"], fields["disparity"])
    # Running again replaces the folder whole.
    assert main(["run", str(images["left"]), "--config", str(images["fast"]), "--out", str(out), "-q"]) == 0
    assert "disparity" not in np.load(out / "fields.npz")
    assert not _leftovers(tmp_path)


@pytest.mark.parametrize("case, message", [
    ("missing", "no such file"),
    ("junk", "cannot be read as an image"),
    ("sizes", "same size"),
    ("config", "unknown config key stereo.nope"),
    ("weights", "labels.weights"),
    ("tiny", "left must be at least 16 x 16 pixels, got shape (5, 7) (left is "),
    ("float255", "it holds floats up to 2"),
    ("json", "not valid JSON"),
    ("json_list", "a JSON object of sections expected, got list"),
    ("json_deep", "not valid JSON"),
    ("json_key", "unknown config key stereo.nope"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, images, capsys, case, message):
    cv2.imwrite(str(tmp_path / "tiny.png"), np.zeros((5, 7), np.uint8))
    bad_config = tmp_path / "bad.toml"
    bad_config.write_text("[stereo]\nnope = 1\n")
    bad_weights = tmp_path / "weights.toml"
    bad_weights.write_text(f'[labels]\nweights = "{tmp_path / "absent.json"}"\n')
    arguments = {
        "missing": [str(tmp_path / "absent.png")],
        "junk": [str(images["junk"])],
        "sizes": [str(images["left"]), str(images["small"])],
        "config": [str(images["left"]), "--config", str(bad_config)],
        "weights": [str(images["left"]), "--config", str(bad_weights)],
        "tiny": [str(tmp_path / "tiny.png")],
        "float255": [str(_float_image(tmp_path / "float255.tiff"))],
        "json": [str(images["left"]), "--config", str(_written(tmp_path / "bad.json", "{nope"))],
        "json_list": [str(images["left"]), "--config", str(_written(tmp_path / "list.json", "[1]"))],
        "json_deep": [str(images["left"]), "--config", str(_written(tmp_path / "deep.json", "[" * 100_000))],
        "json_key": [str(images["left"]), "--config", str(_written(tmp_path / "key.json", '{"stereo": {"nope": 1}}'))],
    }[case]
    out = tmp_path / "out"
    assert main(["run", *arguments, "--out", str(out), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and message in error and error.startswith("vmcl: error:")
    assert not out.exists() and not _leftovers(tmp_path)


def test_failed_run_leaves_the_previous_output_alone(tmp_path, images):
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.html").write_text("previous")
    assert main(["run", str(images["left"]), str(images["small"]), "--out", str(out), "-q"]) == 2
    assert (out / "report.html").read_text() == "previous"


def test_eval_without_data_is_exit_2(tmp_path, capsys):
    assert main(["eval", "stereo", "--data", str(tmp_path / "none"), "-q"]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_info_names_the_chosen_device(capsys):
    assert main(["info"]) == 0
    printed = capsys.readouterr().out
    assert " * " in printed and "kernel binary cache" in printed
    options = " ".join(vmcl.default_machine().build_options) or "none"
    assert f"build options: {options} (and each kernel's -D defines)" in printed


def test_info_lists_the_devices_when_vmcl_device_names_none(capsys, monkeypatch):
    # The error points the user to `vmcl info`, which stopped at the same error before listing anything.
    from vmcl.errors import InputValueError
    from vmcl.machine import list_devices

    def refused():
        raise InputValueError("the VMCL_DEVICE environment variable: index 99 is outside the OpenCL devices here")

    monkeypatch.setattr(vmcl, "default_machine", refused)
    assert main(["info"]) == 2
    captured = capsys.readouterr()
    assert all(f" {index}: " in captured.out for index in range(len(list_devices())))
    assert " * " not in captured.out and "index 99 is outside" in captured.err


def test_info_counts_what_the_kernel_cache_holds(tmp_path, capsys, monkeypatch):
    cache = tmp_path / "kcache"
    for group, program, size in (("AB", "ONE", 2**20), ("AB", "TWO", 2**20), ("CD", "THREE", 2 * 2**20)):
        (cache / group / program).mkdir(parents=True)
        (cache / group / program / "program.so").write_bytes(b"x" * size)
    monkeypatch.setenv("POCL_CACHE_DIR", str(cache))
    assert main(["info"]) == 0
    assert f"{cache} (PoCL's; other drivers keep their own): 3 programs built, 4 MiB" in capsys.readouterr().out


# -- --out: vmcl writes only its own files -------------------------------------------------------------

def _snapshot(folder):
    """Every file under ``folder`` with its bytes, and the folder's mode."""
    return ({p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()},
            folder.stat().st_mode & 0o777)


def _no_run(monkeypatch):
    """Fail the test if the machine runs: --out is to be refused before any work."""
    from vmcl.pipeline import VisionMachine

    monkeypatch.setattr(VisionMachine, "run", lambda *a, **k: pytest.fail("the machine ran before --out was checked"))


@pytest.mark.parametrize("command", ["run", "demo"])
def test_a_folder_of_other_files_is_refused_before_the_run_and_left_alone(tmp_path, images, capsys, monkeypatch,
                                                                          command):
    project = tmp_path / "project"
    (project / "imgs").mkdir(parents=True)
    (project / "main.py").write_text("print('mine')\n")
    (project / "imgs" / "left.png").write_bytes(images["left"].read_bytes())
    project.chmod(0o755)
    before = _snapshot(project)
    _no_run(monkeypatch)
    monkeypatch.chdir(project)
    argv = ["run", "imgs/left.png"] if command == "run" else ["demo", "--size", "64"]
    assert main([*argv, "--out", ".", "-q"]) == 2
    error = capsys.readouterr().err
    assert "not empty and is not a vmcl output" in error and len(error.strip().splitlines()) == 1
    assert _snapshot(project) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["project"]


@pytest.mark.parametrize("case, message", [("file", "exists and is not a folder"),
                                           ("foreign", "holds files vmcl did not write (notes.txt)"),
                                           ("bad marker", "which is not a file vmcl writes")])
def test_out_is_checked_before_the_run(tmp_path, images, capsys, monkeypatch, case, message):
    out = tmp_path / "out"
    if case == "file":
        out.write_text("a file")
    else:
        out.mkdir()
        (out / ".vmcl-output").write_text("report.html\n../elsewhere.txt\n" if case == "bad marker" else "report.html\n")
        (out / "report.html").write_text("previous")
        (out / "notes.txt").write_text("mine")
    before = out.read_bytes() if case == "file" else _snapshot(out)
    _no_run(monkeypatch)
    assert main(["run", str(images["left"]), "--out", str(out), "-q"]) == 2
    assert message in capsys.readouterr().err
    assert (out.read_bytes() if case == "file" else _snapshot(out)) == before
    assert not _leftovers(tmp_path)


def test_new_output_folders_get_the_umask_mode_and_existing_ones_keep_theirs(tmp_path, images):
    umask = os.umask(0o027)
    try:
        fresh = tmp_path / "a" / "b"
        assert main(["run", str(images["left"]), "--config", str(images["fast"]), "--out", str(fresh), "-q"]) == 0
    finally:
        os.umask(umask)
    assert fresh.stat().st_mode & 0o777 == 0o750 and (tmp_path / "a").stat().st_mode & 0o777 == 0o750
    existing = tmp_path / "existing"
    existing.mkdir()
    existing.chmod(0o711)
    for _ in range(2):  # into an empty folder, then over its own output
        assert main(["run", str(images["left"]), "--config", str(images["fast"]), "--out", str(existing), "-q"]) == 0
        assert existing.stat().st_mode & 0o777 == 0o711
    listed = (existing / ".vmcl-output").read_text().split("\n")
    assert {"report.html", "fields.npz", "cartoon.png"} <= set(listed)
    assert set(listed) - {""} - {line for line in listed if line.startswith("#")} == \
        {p.name for p in existing.iterdir()} - {".vmcl-output"}


@pytest.mark.parametrize("command", ["run", "demo"])
def test_a_failed_rename_keeps_the_previous_output(tmp_path, images, monkeypatch, capsys, command):
    out = tmp_path / "out"
    common = ["--config", str(images["fast"]), "--out", str(out), "-q"]
    first, second = {"run": (["run", str(images["left"])], ["run", str(images["left"]), str(images["right"])]),
                     "demo": (["demo", "--size", "64"], ["demo", "--size", "64", "--data", "corridor"])}[command]
    assert main([*first, *common]) == 0
    before = _snapshot(out)
    real_replace, calls = os.replace, []

    def failing_second_call(source, target):
        if Path(source).is_relative_to(tmp_path):  # the output's renames, not those of a cache
            calls.append(source)
            if len(calls) == 2:
                raise OSError(28, "No space left on device")
        return real_replace(source, target)

    monkeypatch.setattr(os, "replace", failing_second_call)
    assert main([*second, *common]) == 1
    assert "No space left on device" in capsys.readouterr().err
    assert _snapshot(out) == before
    assert not _leftovers(tmp_path)


@pytest.mark.parametrize("failure", [OSError, KeyboardInterrupt])
def test_every_interrupted_replacement_puts_the_previous_output_back(tmp_path, monkeypatch, failure):
    out = tmp_path / "out"
    with output_folder(out) as work:
        for name in ("report.html", "a.png", "fields.npz"):
            (work / name).write_text(f"previous {name}")
    before = _snapshot(out)
    real_replace = os.replace
    replaced = 0
    for fail_at in range(1, 20):
        calls = []

        def failing(source, target, fail_at=fail_at, calls=calls):
            calls.append(source)
            if len(calls) == fail_at:
                raise failure()
            return real_replace(source, target)

        monkeypatch.setattr(os, "replace", failing)
        try:
            with output_folder(out) as work:
                for name in ("report.html", "b.png"):
                    (work / name).write_text(f"new {name}")
        except failure:
            replaced += 1
            assert _snapshot(out) == before, f"rename {fail_at} failed"
            assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
        else:  # every rename went through
            break
    assert replaced >= 4
    assert {p.name: p.read_text() for p in out.iterdir()} == {
        "report.html": "new report.html", "b.png": "new b.png",
        ".vmcl-output": (out / ".vmcl-output").read_text()}
    assert (out / ".vmcl-output").read_text().splitlines()[1:] == ["b.png", "report.html"]


@pytest.mark.parametrize("damage", ["none", "cut short", "emptied", "deleted", "a member past the end"])
def test_an_output_is_whole_only_with_every_listed_archive_entire(tmp_path, damage):
    out = tmp_path / "out"
    with output_folder(out) as work:
        np.savez_compressed(work / "fields.npz", disparity=np.arange(20000.0).reshape(100, 200))
        (work / "report.html").write_text("report")
    fields = out / "fields.npz"
    data = fields.read_bytes()
    if damage == "cut short":
        fields.write_bytes(data[:len(data) // 2])
    elif damage == "emptied":
        fields.write_bytes(b"")
    elif damage == "deleted":
        fields.unlink()
    elif damage == "a member past the end":
        # The directory kept, the member's data cut from the middle: the directory points past the end.
        fields.write_bytes(data[:100] + data[len(data) // 2:])
    assert is_whole(out) == (damage == "none")


def test_run_says_the_runs_notes_on_stderr(tmp_path, images, capsys):
    # The notes (here: 12-bit data in a 16-bit file, which the machine reads on the 16-bit scale) were only
    # in the report.
    left = cv2.imread(str(images["left"]), cv2.IMREAD_UNCHANGED).astype(np.uint16) * 16
    cv2.imwrite(str(tmp_path / "dark.png"), left)
    assert main(["run", str(tmp_path / "dark.png"), "--out", str(tmp_path / "out"), "--config", str(images["fast"]),
                 "-q"]) == 0
    err = capsys.readouterr().err
    assert "vmcl: note:" in err and "very dark image" in err


def test_settings_name_files_absolute_and_record_arrays(tmp_path, images, monkeypatch):
    # A relative labels.weights was recorded as typed, so --config settings.json failed from elsewhere; an
    # array of levels (which the Config takes) broke the recording after the report was written.
    import json
    import shutil

    from vmcl import labelling
    from vmcl.cli import write_output

    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    shutil.copy(labelling.WEIGHTS_FILE, tmp_path / "sub" / "w.json")
    (tmp_path / "rel.toml").write_text('[labels]\nweights = "sub/w.json"\n[mrf]\nmethod = "icm"\n')
    assert main(["run", str(images["left"]), "--config", "rel.toml", "--out", "first", "-q"]) == 0
    recorded = json.loads((tmp_path / "first" / "settings.json").read_text())
    assert recorded["labels"]["weights"] == str(tmp_path / "sub" / "w.json")
    monkeypatch.chdir(tmp_path / "sub")
    assert main(["run", str(images["left"]), "--config", str(tmp_path / "first" / "settings.json"), "--out",
                 "again", "-q"]) == 0
    config = Config.from_dict({"mrf": {"method": "icm", "stereo": {"levels": np.linspace(0, 10, 11)}}})
    left = cv2.imread(str(images["left"]))[..., ::-1]
    right = cv2.imread(str(images["right"]))[..., ::-1]
    write_output(VisionMachine(config).run(left, right), tmp_path / "arrays", "t")
    assert json.loads((tmp_path / "arrays" / "settings.json").read_text())["mrf"]["stereo"]["levels"][-1] == 10.0


def test_demo_refuses_a_size_for_the_photographed_pair(tmp_path, capsys):
    # The motorcycle pair was run at its own 741 x 500, --size dropped in silence.
    assert main(["demo", "--data", "motorcycle", "--size", "64", "--out", str(tmp_path / "out"), "-q"]) == 2
    assert "--size sets a rendered scene's size" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("arguments, message", [
    (["--out", ""], "--out must name a folder"),
    (["--out", "{tmp}/out", "--fps", "-5"], "--fps sets a sequence"),
    # An unset shell variable as the right view or the next frame: the run went on without stereo or motion.
    (["", "--out", "{tmp}/out"], "right must name an image (or be left out), got an empty name"),
    (["--next", " ", "--out", "{tmp}/out"], "--next must name an image (or be left out), got an empty name"),
])
def test_run_refuses_an_empty_out_and_a_frame_rate_for_one_image(tmp_path, images, capsys, arguments, message):
    # --out "" wrote into the working folder; --fps was ignored for one image (and checked for a sequence).
    arguments = [a.format(tmp=tmp_path) for a in arguments]
    assert main(["run", str(images["left"]), *arguments, "-q"]) == 2
    assert message in capsys.readouterr().err


def test_eval_refuses_an_empty_data_folder(capsys):
    # Path("") is the working directory: an unset variable searched wherever the command ran.
    assert main(["eval", "flow", "--data", "", "-q"]) == 2
    assert "--data must name a folder, got an empty name" in capsys.readouterr().err


def test_a_killed_runs_partial_folder_is_removed_by_the_next_run_and_nothing_else(tmp_path):
    # SIGKILL runs no handler: the hidden partial folder stayed beside the output for good.
    import socket
    import subprocess
    import sys

    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                              check=True)
    dead = int(finished.stdout)
    host = "".join(c if c.isalnum() else "_" for c in socket.gethostname())
    out = tmp_path / "out"
    stale = tmp_path / f".out.partial-{host}.{dead}-0a1b2c3d"
    kept = [tmp_path / f".out.partial-{host}.{os.getpid()}-0a1b2c3d",  # a live process's (this one)
            tmp_path / f".out.partial-otherhost.{dead}-0a1b2c3d",  # another machine's, on a shared disk
            tmp_path / f".other.partial-{host}.{dead}-0a1b2c3d",  # beside another output
            tmp_path / ".out.partial-mine"]  # not a name vmcl gives
    for folder in (stale, *kept):
        folder.mkdir()
        (folder / "fields.npz").write_bytes(b"half")
    with output_folder(out) as work:
        (work / "report.html").write_text("new")
    assert not stale.exists() and all((folder / "fields.npz").exists() for folder in kept)


def test_a_changed_folder_is_not_replaced(tmp_path):
    out = tmp_path / "out"
    with output_folder(out) as work:
        (work / "report.html").write_text("previous")
    with pytest.raises(InputError, match="did not write"), output_folder(out) as work:
        (work / "report.html").write_text("new")
        (out / "added meanwhile.txt").write_text("mine")
    assert (out / "report.html").read_text() == "previous" and (out / "added meanwhile.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


# -- images vmcl cannot trust ---------------------------------------------------------------------------

def _jpeg(images):
    return cv2.imencode(".jpg", cv2.imread(str(images["left"])))[1].tobytes()


def _png_with_bad_text_crc(images):
    data = images["left"].read_bytes()
    chunk = b"tEXt" + b"Comment\x00made by the test"
    crc = (zlib.crc32(chunk) ^ 1).to_bytes(4, "big")
    return data[:33] + (len(chunk) - 4).to_bytes(4, "big") + chunk + crc + data[33:]  # after IHDR


def _huge_png():
    """A whole PNG of a few bytes whose header declares 100000 x 100000 pixels, over OpenCV's limit."""
    def chunk(kind, body):
        return len(body).to_bytes(4, "big") + kind + body + zlib.crc32(kind + body).to_bytes(4, "big")

    header = (100_000).to_bytes(4, "big") * 2 + bytes([8, 2, 0, 0, 0])
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(bytes(10)))
            + chunk(b"IEND", b""))


def _corrupt_scan(jpeg):
    data = bytearray(jpeg)
    scan = data.find(b"\xff\xda") + 40
    data[scan:scan + 20] = bytes(b ^ 0x5A for b in data[scan:scan + 20])
    return bytes(data)


@pytest.mark.parametrize("case, message", [
    ("truncated jpeg", "no end-of-image marker"),
    ("corrupt jpeg", "Corrupt JPEG data"),
    ("png with a bad crc", "tEXt chunk at byte 33 fails its CRC check"),
    ("truncated png", "before its IEND chunk"),
    ("folder", "is a folder, not an image file"),
    ("png over opencv's limit", "over its limit CV_IO_MAX_IMAGE_PIXELS"),
])
def test_damaged_images_are_refused(tmp_path, images, capsys, case, message):
    jpeg = _jpeg(images)
    data = {"truncated jpeg": jpeg[:len(jpeg) * 2 // 3],
            "corrupt jpeg": _corrupt_scan(jpeg),
            "png with a bad crc": _png_with_bad_text_crc(images),
            "truncated png": images["left"].read_bytes()[:-200],
            "png over opencv's limit": _huge_png()}.get(case)
    path = tmp_path / ("image.jpg" if "jpeg" in case else "image.png")
    if data is None:
        path.mkdir()
    else:
        path.write_bytes(data)
    with pytest.raises(InputError, match=re.escape(message)):
        read_image(path)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "-q"]) == 2
    error = capsys.readouterr().err.strip()
    named = "left image"
    if case == "folder":  # to vmcl run a folder is a sequence of frames, and this one holds none
        message, named = "the folder holds no images", "left: "
    assert len(error.splitlines()) == 1 and message in error and named in error
    assert not out.exists()


def test_write_output_never_overwrites_a_file_it_did_not_write(tmp_path):
    from vmcl.cli import write_output
    from vmcl.pipeline import VisionMachine

    result = VisionMachine(Config.from_dict({"mrf": {"method": "icm"}})).run(
        np.random.default_rng(0).random((64, 64)).astype(np.float32))
    for name in ("fields.npz", "settings.json"):
        folder = tmp_path / name.split(".")[0]
        folder.mkdir()
        (folder / name).write_bytes(b"the user's own")
        with pytest.raises(InputError, match=f"already holds {re.escape(name)}"):
            write_output(result, folder, "t")  # refused before anything is written: the report neither
        assert [p.name for p in folder.iterdir()] == [name] and (folder / name).read_bytes() == b"the user's own"
    # A link to nothing is a name taken too: writing through it made a file wherever it pointed.
    linked = tmp_path / "linked"
    linked.mkdir()
    elsewhere = tmp_path / "elsewhere.json"
    (linked / "settings.json").symlink_to(elsewhere)
    with pytest.raises(InputError, match="already holds settings.json"):
        write_output(result, linked, "t")
    assert not elsewhere.exists()
    write_output(result, tmp_path / "new", "t")  # a new folder takes them all
    assert {"fields.npz", "settings.json", "report.html"} <= {p.name for p in (tmp_path / "new").iterdir()}


def test_a_jpeg_ends_at_its_own_end_marker_not_at_a_thumbnails(tmp_path, images):
    jpeg = _jpeg(images)
    thumbnail = b"\xff\xe1" + (2 + 6).to_bytes(2, "big") + b"\x00\xff\xd9\x00\xff\xd9"  # an APP1 holding FFD9
    sound = tmp_path / "sound.jpg"
    sound.write_bytes(jpeg[:2] + thumbnail + jpeg[2:] + b"a camera's trailer")
    np.testing.assert_array_equal(read_image(sound), cv2.imread(str(sound), cv2.IMREAD_UNCHANGED)[..., ::-1])
    cut = tmp_path / "cut.jpg"
    cut.write_bytes(jpeg[:2] + thumbnail + jpeg[2:len(jpeg) * 2 // 3])
    with pytest.raises(InputError, match="no end-of-image marker"):
        read_image(cut)


# -- exit statuses ----------------------------------------------------------------------------------------

def test_a_defect_is_exit_1_with_its_traceback(images, tmp_path, capsys, monkeypatch):
    from vmcl.pipeline import VisionMachine

    def broken(*args, **kwargs):
        raise ValueError("a defect inside vmcl")

    monkeypatch.setattr(VisionMachine, "run", broken)
    assert main(["run", str(images["left"]), "--out", str(tmp_path / "out"), "-q"]) == 1
    error = capsys.readouterr().err
    assert "Traceback" in error and "a defect inside vmcl" in error and "broken" in error
    assert not _leftovers(tmp_path) and not (tmp_path / "out").exists()


def test_debug_shows_the_traceback_of_bad_input(tmp_path, capsys):
    assert main(["run", str(tmp_path / "absent.png"), "--out", str(tmp_path / "out"), "-q", "--debug"]) == 2
    error = capsys.readouterr().err
    assert "Traceback" in error and error.strip().endswith("no such file")


@pytest.mark.parametrize("text, message", [
    ('[stereo]\nenabled = "no"\n', "stereo.enabled must be true or false, got 'no' (str)"),
    ("[stereo]\nd_max = true\n", "stereo.d_max must be an integer or None, got True (bool)"),
    ("[texture]\nradius = 2.5\n", "texture.radius must be an integer, got 2.5 (float)"),
    ('[edges]\nsigma = "2"\n', "edges.sigma must be a number, got '2' (str)"),
    ('[colour]\nthreshold = [0.1]\n', "colour.threshold must be a number or None"),
    ("[mrf]\nstereo = 3\n", "mrf.stereo must be a table of keys"),
])
def test_config_types_are_checked_naming_the_key(tmp_path, images, capsys, monkeypatch, text, message):
    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(InputTypeError) as refused:
        Config.from_toml(path)
    assert message in str(refused.value)
    _no_run(monkeypatch)
    assert main(["run", str(images["left"]), "--config", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    assert message in capsys.readouterr().err


def test_a_binary_config_is_bad_input(tmp_path, images, capsys):
    path = tmp_path / "c.toml"
    path.write_bytes(b"\xff\xfe\x00binary")
    assert main(["run", str(images["left"]), "--config", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "not valid TOML" in err and err.count(str(path)) == 1, err  # the path once, not "config P: P: ..."


def _vmcl(*argv, env=None, cwd=None):
    return subprocess.Popen([sys.executable, "-m", "vmcl.cli", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=cwd)


@pytest.mark.parametrize("command", ["run", "demo", "info"])
def test_without_an_opencl_platform_the_hint_alone_and_exit_2(tmp_path, images, command):
    no_drivers = tmp_path / "no-icd"
    no_drivers.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "OCL_ICD_FILENAMES"} | {"OCL_ICD_VENDORS": str(no_drivers)}
    out = tmp_path / "out"
    argv = {"run": ["run", str(images["left"]), "--out", str(out), "-q"],
            "demo": ["demo", "--size", "64", "--out", str(out), "-q"], "info": ["info"]}[command]
    process = _vmcl(*argv, env=env)
    _, error = process.communicate(timeout=120)
    assert process.returncode == 2
    assert error.startswith("vmcl: No OpenCL platform found") and "Traceback" not in error
    assert "pocl-opencl-icd" in error and len(error.strip().splitlines()) <= 5
    assert sorted(p.name for p in tmp_path.iterdir()) == ["no-icd"]


def test_ctrl_c_is_one_line_exit_130_and_leaves_the_previous_output(tmp_path):
    s = scenes.render(scenes.preset("cues", shape=(512, 512)), seed=0, noise=0.01)
    paths = []
    for name, image in (("left", s.left), ("right", s.right), ("next", s.left_next)):
        paths.append(tmp_path / f"{name}.png")
        cv2.imwrite(str(paths[-1]), cv2.cvtColor(np.round(image * 255).astype(np.uint8), cv2.COLOR_RGB2BGR))
    out = tmp_path / "out"
    out.mkdir()
    (out / ".vmcl-output").write_text("report.html\n")
    (out / "report.html").write_text("previous")
    before = _snapshot(out)
    process = _vmcl("run", str(paths[0]), str(paths[1]), "--next", str(paths[2]), "--out", str(out), "-q")
    deadline = time.monotonic() + 120
    while not _leftovers(tmp_path) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # the hidden folder appears once --out is checked, as the run starts
    # 512 x 512 with every cue takes seconds: the signal lands mid-run even when this process was starved.
    assert process.poll() is None, "the run ended before it could be interrupted"
    process.send_signal(signal.SIGINT)
    _, error = process.communicate(timeout=300)
    # PoCL's in-process compiler may add its own "N errors generated." when the signal lands during a
    # kernel build (a first run); vmcl's own report is the one line, without a traceback.
    lines = error.strip().splitlines()
    assert process.returncode == 130 and lines and lines[-1] == "vmcl: interrupted", (process.returncode, error)
    assert "Traceback" not in error and len(lines) <= 2, error
    assert _snapshot(out) == before
    assert not _leftovers(tmp_path)


def test_settings_recorded_from_numpy_numbers_read_back_as_numbers():
    """A Config given NumPy scalars (np.float32 for a sigma) records them as plain numbers."""
    from vmcl.cli import settings_text

    config = Config.from_dict({"edges": {"sigma": np.float32(2.5)}, "motion": {"patch": np.int64(15)}})
    recorded = json.loads(settings_text(config.to_dict()))
    assert recorded["edges"]["sigma"] == 2.5 and recorded["motion"]["patch"] == 15
    assert Config.from_dict(recorded) == Config.from_dict({"edges": {"sigma": 2.5}, "motion": {"patch": 15}})


def test_names_present_are_refused_shown_at_most_three(tmp_path):
    from vmcl.output_folder import refuse_names_present

    refuse_names_present(tmp_path / "not yet", lambda name: True, "x")  # a folder not made yet holds nothing
    for k in range(5):
        (tmp_path / f"fields_{k:06d}.npz").write_bytes(b"")
    (tmp_path / "mine.txt").write_bytes(b"")
    refuse_names_present(tmp_path, lambda name: name == "other", "x")
    with pytest.raises(InputError, match=re.escape(f"folder {tmp_path} already holds fields_000000.npz, "
                                                   "fields_000001.npz, fields_000002.npz and 2 more; write the "
                                                   "sequence into a new")):
        refuse_names_present(tmp_path, lambda name: name.startswith("fields_"), "the sequence")
    # One of vmcl's names but for its case is that file where the file system ignores case: refused.
    (tmp_path / "Report.HTML").write_bytes(b"")
    with pytest.raises(InputError, match="already holds Report.HTML"):
        refuse_names_present(tmp_path, {"report.html"}.__contains__, "the report")
    with pytest.raises(InputError, match="folder must be a path"):
        refuse_names_present(3, {"report.html"}.__contains__, "the report")


def _grey_png(path, image):
    cv2.imwrite(str(path), np.round(np.clip(image, 0, 1) * 255).astype(np.uint8))
    return path


def test_learn_reads_a_mask_as_learn_does_and_names_one_that_marks_nothing(tmp_path, capsys):
    # A 0/1 mask PNG, which learn takes, was read as empty (cut at half of 255), and the image blamed ("the
    # example shows too little boundary ... 0 edge pixels").
    from vmcl.recognize import learn, load_model

    example = _grey_png(tmp_path / "ell.png", scenes.object_view("ell", shape=(160, 160))[0])
    inside = np.zeros((160, 160), bool)
    inside[20:140, 20:140] = True
    expected = learn("ell", [read_image(example)], masks=[inside]).views[0]  # the API, on the file's pixels
    on = inside.astype(np.uint8)
    for name, mask in (("01.png", on), ("0255.png", on * 255), ("01_16.png", on.astype(np.uint16)),
                       ("065535.png", on.astype(np.uint16) * 65535), ("colour.png", np.dstack([on * 255] * 3))):
        cv2.imwrite(str(tmp_path / name), mask)
        library = tmp_path / Path(name).stem
        assert main(["learn", "ell", str(example), "--library", str(library), "--mask", str(tmp_path / name),
                     "-q"]) == 0
        view = load_model(library / "ell.vmodel.npz").views[0]
        assert np.array_equal(view.points, expected.points) and np.array_equal(view.outline, expected.outline)
    grey = on * 200
    grey[20] = 100
    corner = np.zeros_like(on)
    corner[:4, :4] = 255
    capsys.readouterr()
    for name, mask, message in (
            ("empty.png", np.zeros_like(on), "mask {path} marks no pixel as the object: it holds only 0"),
            ("grey.png", grey, ("mask {path} must hold only 0 (off the object) and one other value (on it): 1 "
                                "or 255, its type's full scale; it holds 100, 200 where it is not 0")),
            ("red.png", np.dstack([np.zeros_like(on), np.zeros_like(on), on * 255]),
             "mask {path} is in colour: a mask must be black and white"),
            ("corner.png", corner, "images[0] (ell.png): the mask leaves 0 of the example's")):
        path = tmp_path / name
        cv2.imwrite(str(path), mask)
        assert main(["learn", "ell", str(example), "--library", str(tmp_path / "refused"), "--mask", str(path),
                     "-q"]) == 2
        err = capsys.readouterr().err
        assert message.format(path=path) in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "refused").exists()


def test_learn_names_a_library_that_is_a_file_before_learning(tmp_path, capsys, monkeypatch):
    # `--library afile` was refused only after the learning, as "folder must be a directory".
    import vmcl.recognize

    def learned(*args, **kwargs):
        raise AssertionError("learned a model that cannot be written")

    monkeypatch.setattr(vmcl.recognize, "learn", learned)
    example = _grey_png(tmp_path / "ell.png", scenes.object_view("ell", shape=(96, 96))[0])
    (tmp_path / "afile").write_bytes(b"")
    for library in (tmp_path / "afile", tmp_path / "afile" / "sub"):
        assert main(["learn", "ell", str(example), "--library", str(library), "-q"]) == 2
        assert capsys.readouterr().err == (f"vmcl: error: --library {library}: folder must be a directory (a library "
                                           f"of model files), but {tmp_path / 'afile'} is a file\n")


def test_model_path_names_a_refused_folder_as_its_caller_does(tmp_path):
    # vmcl learn told a refused --library from a refused name by the message's first word.
    from vmcl.recognize import model_path

    (tmp_path / "afile").write_bytes(b"")
    with pytest.raises(InputValueError, match=re.escape(f"--library {tmp_path / 'afile'}: folder must be a directory")):
        model_path(tmp_path / "afile", "box", folder_name="--library")
    with pytest.raises(InputValueError, match="^name must be"):  # the name is no folder's: no prefix
        model_path(tmp_path / "afile", "../box", folder_name="--library")
    with pytest.raises(InputValueError, match="^folder must be a directory"):
        model_path(tmp_path / "afile", "box")


def test_a_run_with_models_writes_what_it_recognised_for_programs(tmp_path, capsys):
    # `vmcl run --models` kept the poses in no file a program reads: fields.npz has none, the report a box.
    from vmcl.output_folder import MARKER
    from vmcl.recognize import carry, load_model

    examples = {name: scenes.object_view(name, shape=(160, 160)) for name in ("ell", "arrow")}
    library = tmp_path / "library"
    for name, (image, _) in examples.items():
        assert main(["learn", name, str(_grey_png(tmp_path / f"{name}.png", image)), "--library", str(library),
                     "-q"]) == 0
    scene = scenes.recognition_scene((300, 400), seed=6, library=("ell", "arrow"), objects=2, occlusion=(0.0, 0.1),
                                     clutter=2)
    left = _grey_png(tmp_path / "scene.png", scene.image)
    fast = _written(tmp_path / "fast.toml", '[mrf]\nmethod = "icm"\n')
    out = tmp_path / "run"
    assert main(["run", str(left), "--models", str(library), "--config", str(fast), "--out", str(out), "-q"]) == 0
    found = json.loads((out / "recognition.json").read_text(encoding="utf-8"))["detections"]
    assert sorted(d["name"] for d in found) == ["arrow", "ell"]
    for detection in found:
        # The oracle: the scene's exact corners, and the example's, of the same object.
        truth = next(p for p in scene.placements if p.name == detection["name"])
        example = examples[detection["name"]][1]
        ids = [int(i) for i in truth.corner_ids if i in example.corner_ids]
        at_example = example.corners[[list(example.corner_ids).index(i) for i in ids]]
        at_scene = truth.corners[[list(truth.corner_ids).index(i) for i in ids]]
        transform = np.array(detection["transform"])
        assert transform.shape == (3, 3) and np.abs(carry(transform, at_example) - at_scene).max() < 3
        view = load_model(library / f"{detection['name']}.vmodel.npz").views[detection["view"]]
        boundary = carry(transform, view.points)
        assert np.allclose(detection["box"], [*boundary.min(axis=0), *boundary.max(axis=0)])
        assert np.allclose(detection["corners"], carry(transform, view.corners))
        assert 0 < detection["score"] <= 1 and detection["significance"] >= 19
    assert "recognition.json" in (out / MARKER).read_text().splitlines() and is_whole(out)
    # Run again into the folder without models: the previous output's file goes with the rest of it.
    assert main(["run", str(left), "--config", str(fast), "--out", str(out), "-q"]) == 0
    assert not (out / "recognition.json").exists() and "recognition.json" not in (out / MARKER).read_text()
