"""The vmcl command: exit codes, the files it promises, and one clear line for bad input."""

import cv2
import numpy as np
import pytest

from vmcl import scenes
from vmcl.cli import main


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


def _leftovers(folder):
    return [p.name for p in folder.iterdir() if ".partial-" in p.name or ".old-" in p.name]


def test_demo_writes_the_report(tmp_path, images, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--size", "64", "--quiet", "--config", str(images["fast"])]) == 0
    assert {"report.html", "cartoon.png", "disparity.png", "flow.png"} <= {p.name for p in out.iterdir()}
    printed = capsys.readouterr().out
    assert "bad 1" in printed and "EPE" in printed and "albedo" in printed
    assert not _leftovers(tmp_path)


def test_run_on_files_writes_report_and_fields(tmp_path, images):
    out = tmp_path / "run"
    code = main(["run", str(images["left"]), str(images["right"]), "--next", str(images["next"]),
                 "--config", str(images["fast"]), "--out", str(out), "--quiet"])
    assert code == 0
    fields = np.load(out / "fields.npz")
    assert fields["disparity"].shape == (64, 64) and fields["flow"].shape == (64, 64, 2)
    assert (out / "report.html").stat().st_size > 1000
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
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, images, capsys, case, message):
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
