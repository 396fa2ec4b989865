"""`vmcl fit` and the fitted files it writes: learned from folders with ground truth, loaded by a Config,
checked against edits, and never written over a file vmcl did not write."""

import warnings

import numpy as np
import pytest

from vmcl import fitted, scenes
from vmcl.cli import main
from vmcl.datasets import write_stereo_folder
from vmcl.errors import InputValueError
from vmcl.learn.examples import jump_lines
from vmcl.mrf import LinePrior, preset
from vmcl.pipeline import Config, VisionMachine


@pytest.fixture(scope="module")
def stereo_data(tmp_path_factory):
    """Two rendered stereo scenes in a Middlebury layout (im2/im6/disp2, the 2001 venus layout)."""
    root = tmp_path_factory.mktemp("stereo_data")
    for name, seed in (("blocks", 0), ("cues", 1)):
        scene = scenes.render(scenes.preset(name, shape=(80, 96)), seed=seed, noise=0.01)
        truth = np.where(scene.occluded_stereo, np.nan, scene.disparity)
        write_stereo_folder(root / name, (scene.left * 255).astype(np.uint8), (scene.right * 255).astype(np.uint8),
                            truth)
    return root


def test_fit_writes_a_config_that_loads_and_runs(stereo_data, tmp_path, capsys):
    out = tmp_path / "stereo.toml"
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "-q"]) == 0
    printed = capsys.readouterr().out
    assert "2 example(s)" in printed and f"Wrote {out}" in printed
    config = Config.from_toml(out)
    table = config.mrf.stereo
    assert set(table) == {"alpha", "beta", "edge_gain", "prior"}
    assert set(table["prior"]) == {"line", "end", "continuation", "turn", "junction", "crossing", "parallel"}
    settings = config.mrf.settings("stereo", preset("stereo"))
    assert settings.model.alpha == table["alpha"] and settings.model.prior == LinePrior(**table["prior"])
    from vmcl.pipeline import tomllib

    provenance = tomllib.loads(out.read_text())["fitted"]
    assert provenance["data"] == ["blocks", "cues"] and provenance["what"] == "mrf.stereo"
    assert len(provenance["data_sha256"]) == 64 and provenance["written_by"] == fitted.FITTED_BY
    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=3)
    assert VisionMachine(config).run(scene.left, scene.right).disparity.shape == (64, 64)
    # a second fit replaces the file vmcl wrote; --fix holds a parameter
    assert "T = 1;" in printed  # the coupling held at 1 by default
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "--fix", "coupling=free", "-q"]) == 2
    assert "the fitted data weight is 0" in capsys.readouterr().err  # planar truth: see fit_cue


def test_fit_refined_by_the_restorations_error(stereo_data, tmp_path, capsys):
    """--refine: the pseudolikelihood fit, then the restorations' error on the same examples, which ends no
    higher than it starts; the file says so and loads."""
    out = tmp_path / "refined.toml"
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "--refine", "-q"]) == 0
    assert "Refined by the restorations' error" in capsys.readouterr().out
    values = __import__("vmcl.pipeline", fromlist=["tomllib"]).tomllib.loads(out.read_text())
    before, after = values["fitted"]["restoration_error"]
    assert after <= before and "fit_restoration" in values["fitted"]["method"]
    Config.from_toml(out)
    assert main(["fit", "colour", "--data", str(stereo_data), "--out", str(tmp_path / "c.toml"), "--refine", "-q"]) == 2
    assert "refine fits the piecewise smooth cues" in capsys.readouterr().err


def test_an_edited_fitted_file_is_refused(stereo_data, tmp_path, capsys):
    out = tmp_path / "stereo.toml"
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "-q"]) == 0
    text = out.read_text()
    edited = tmp_path / "edited.toml"
    edited.write_text(text.replace("alpha = ", "alpha = 1", 1))
    with pytest.raises(InputValueError, match="edited or damaged"):
        Config.from_toml(edited)
    # without its [fitted] table the same edit is the user's own configuration
    own = tmp_path / "own.toml"
    own.write_text(text.split("[fitted]")[0])
    Config.from_toml(own)


def test_another_version_warns(tmp_path, monkeypatch):
    # Written by another version (its record sealed by that version), not edited afterwards: the record's
    # entries_sha256 refuses an edited version entry as any other edit.
    monkeypatch.setattr("vmcl.__version__", "0.0.1")
    out = fitted.write_fitted(tmp_path / "a.toml", {"mrf": {"stereo": {"alpha": 0.5}}}, {"data": ["x"]})
    monkeypatch.undo()
    with pytest.warns(UserWarning, match="fitted by vmcl 0.0."):
        assert Config.from_toml(out).mrf.stereo == {"alpha": 0.5}


def test_fit_never_writes_over_a_file_it_did_not_write(stereo_data, tmp_path, capsys):
    mine = tmp_path / "mine.toml"
    mine.write_text("[edges]\nsigma = 2.0\n")
    before = mine.read_bytes()
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(mine), "-q"]) == 2
    assert "not a file `vmcl fit` wrote" in capsys.readouterr().err
    assert mine.read_bytes() == before
    with pytest.raises(InputValueError, match="not a file `vmcl fit` wrote"):
        fitted.write_fitted(mine, {"mrf": {}}, {})
    assert mine.read_bytes() == before


def test_fit_keeps_an_edited_fit_a_link_and_a_read_only_fit_and_refuses_a_missing_folder_first(stereo_data, tmp_path,
                                                                                               capsys):
    """A fitted file edited since (the user's lines would be lost), a link, a read-only fit and a path in a
    missing folder are refused before any fitting, in one line, and nothing is written; an unedited fit
    is replaced."""
    out = tmp_path / "stereo.toml"
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "-q"]) == 0
    assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(out), "-q"]) == 0  # its own, unedited
    edited = tmp_path / "edited.toml"
    edited.write_text(out.read_text() + "\n[stereo]\npaths = 8\n")
    link = tmp_path / "link.toml"
    link.symlink_to(out)
    locked = tmp_path / "locked.toml"
    locked.write_text(out.read_text())
    locked.chmod(0o444)
    capsys.readouterr()
    for target, message in ((edited, "edited since: vmcl would lose the edit"), (link, "is a link"),
                            (locked, "is read-only"), (tmp_path / "missing" / "f.toml", "does not exist")):
        before = target.read_bytes() if target.exists() else None
        assert main(["fit", "stereo", "--data", str(stereo_data), "--out", str(target), "-q"]) == 2, target
        errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("vmcl: error:")]
        assert len(errors) == 1 and message in errors[0], errors
        assert (target.read_bytes() if target.exists() else None) == before
    assert link.is_symlink()


@pytest.mark.parametrize("args, message", [
    (["--data", "{empty}"], "nothing to fit stereo to"),
    (["--data", "{missing}"], "no such folder"),
    (["--data", "{data}", "--fix", "beta=1"], "the parameters are alpha"),
    (["--data", "{data}", "--fix", "alpha=x"], "is not a number"),
    # A held value outside the model's domain was blamed on the examples' fields; a second --fix won in silence.
    (["--data", "{data}", "--fix", "alpha=-5"], "--fix alpha=-5: fixed['alpha'] must be > 0"),
    (["--data", "{data}", "--fix", "alpha=0"], "--fix alpha=0: fixed['alpha'] must be > 0"),
    (["--data", "{data}", "--fix", "coupling=-1"], "--fix coupling=-1: fixed['coupling'] must be > 0"),
    (["--data", "{data}", "--fix", "alpha=1", "--fix", "alpha=2"], "--fix alpha given twice"),
])
def test_fit_refusals_are_one_line(stereo_data, tmp_path, capsys, args, message):
    (tmp_path / "empty").mkdir()
    filled = [a.format(empty=tmp_path / "empty", missing=tmp_path / "missing", data=stereo_data) for a in args]
    out = tmp_path / "x.toml"
    assert main(["fit", "stereo", *filled, "--out", str(out), "-q"]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_overlapping_data_folders_count_each_example_once(stereo_data, tmp_path, capsys):
    # The same scene under two --data roots was two examples: the standard errors fell by the square root of 2.
    out = tmp_path / "x.toml"
    assert main(["fit", "stereo", "--data", str(stereo_data), "--data", str(stereo_data / "blocks"), "--data",
                 str(stereo_data), "--out", str(out), "-q"]) == 0
    assert "2 example(s)" in capsys.readouterr().out


def test_hash_survives_the_toml_round_trip(tmp_path):
    tables = {"mrf": {"motion": {"alpha": 1e-05, "beta": 0.1 + 0.2, "prior": {"end": -0.0, "line": 1.0}}}}
    out = fitted.write_fitted(tmp_path / "m.toml", tables, {"data": ['quote " and \\ back']})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        config = Config.from_toml(out)
    assert config.mrf.motion["beta"] == 0.1 + 0.2


def test_measure_gives_each_cue_its_mrf_data():
    scene = scenes.render(scenes.preset("cues", shape=(64, 64)), seed=0)
    vm = VisionMachine()
    measured = vm.measure(scene.left, scene.right, scene.left_next)
    assert set(measured) == {"stereo", "motion", "colour", "texture"}
    stereo = measured["stereo"]
    assert stereo.data.shape == (64, 64) and stereo.data.dtype == np.float32
    assert measured["motion"].data.shape == (64, 64, 2)
    # the piecewise smooth cues are coupled to the run's brightness edges
    result = vm.run(scene.left, scene.right, scene.left_next)
    assert np.array_equal(stereo.coupling, result.edges)
    finite = np.isfinite(stereo.data) & ~scene.occluded_stereo
    assert np.mean(np.abs(stereo.data[finite] - scene.disparity[finite]) <= 1) > 0.8


def test_jump_lines_mark_the_jumps_between_known_pixels():
    field = np.zeros((4, 5))
    field[:, 3:] = 2.0
    field[0, 0] = np.nan
    line_h, line_v = jump_lines(field)
    assert line_h[:, 2].all() and line_h.sum() == 4 and not line_v.any()
    vector = np.zeros((3, 3, 2))
    vector[2, :, 1] = 1.5
    assert jump_lines(vector)[1][1].all() and jump_lines(vector, jump=2.0)[1].sum() == 0


def test_prior_tables_in_a_config(tmp_path):
    config = Config.from_dict({"mrf": {"stereo": {"prior": {"end": 2.0}}}})
    prior = config.mrf.settings("stereo").model.prior
    assert prior == LinePrior(end=2.0)
    with pytest.raises(InputValueError, match=r"unknown key mrf.stereo.prior.ends"):
        Config.from_dict({"mrf": {"stereo": {"prior": {"ends": 2.0}}}}).mrf.settings("stereo")


def test_fit_colour_from_a_bsds_folder(datasets_root, tmp_path, capsys):
    """Two BSDS training images in the distribution's layout (images/train, groundTruth/train, beside a
    test split the fit must not read): the colour MRF fitted to their first annotators' segmentations."""
    source = datasets_root / "bsds500" / "train"
    names = sorted(p.name for p in source.iterdir() if p.is_dir())[:2]
    for split, chosen in (("train", names), ("test", sorted(p.name for p in source.iterdir() if p.is_dir())[2:3])):
        for kind, suffix in (("images", "jpg"), ("groundTruth", "mat")):
            folder = tmp_path / "data" / kind / split
            folder.mkdir(parents=True)
            for name in chosen:
                (folder / f"{name}.{suffix}").write_bytes((source / name / f"{name}.{suffix}").read_bytes())
    out = tmp_path / "colour.toml"
    assert main(["fit", "colour", "--data", str(tmp_path / "data"), "--out", str(out), "-q"]) == 0
    assert "colour: 2 example(s)" in capsys.readouterr().out
    from vmcl.pipeline import tomllib

    written = tomllib.loads(out.read_text())
    assert written["fitted"]["data"] == names
    table = Config.from_toml(out).mrf.colour
    assert {"alpha", "beta", "kappa", "edge_gain", "prior"} <= set(table) and table["kappa"] > 0
    # The data's hash is of the files read (the training split's images and annotations), links followed: the
    # same data through a linked folder records the same hash, and it is not the hash of nothing.
    read = [tmp_path / "data" / kind / "train" / f"{name}.{suffix}" for name in names
            for kind, suffix in (("images", "jpg"), ("groundTruth", "mat"))]
    assert written["fitted"]["data_sha256"] == fitted.files_sha256(read)
    (tmp_path / "linked").mkdir()
    for kind in ("images", "groundTruth"):  # linked folders inside, which a plain walk would not enter
        (tmp_path / "linked" / kind).symlink_to(tmp_path / "data" / kind, target_is_directory=True)
    again = tmp_path / "linked.toml"
    assert main(["fit", "colour", "--data", str(tmp_path / "linked"), "--out", str(again), "-q"]) == 0
    assert tomllib.loads(again.read_text())["fitted"]["data_sha256"] == written["fitted"]["data_sha256"]


def test_fitting_a_cue_the_machine_does_not_run_is_refused_by_name(stereo_data, tmp_path):
    # Stereo and motion raised a bare KeyError where colour and texture named the cue.
    import cv2

    from vmcl.datasets import write_flo
    from vmcl.learn.cue_fit import fit_cue

    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    folder = tmp_path / "flow" / "Blocks"
    folder.mkdir(parents=True)
    for name, frame in (("frame10.png", scene.left), ("frame11.png", scene.left_next)):
        cv2.imwrite(str(folder / name), (frame[..., ::-1] * 255).astype(np.uint8))
    write_flo(folder / "flow10.flo", scene.flow)
    for cue, root, example in (("stereo", stereo_data, "blocks"), ("motion", tmp_path / "flow", "Blocks")):
        off = VisionMachine(Config.from_dict({cue: {"enabled": False}}))
        with pytest.raises(InputValueError, match=f"{example}: the {cue} cue does not run on this image "
                                                  rf"\(\[{cue}\] enabled = false\)"):
            fit_cue(cue, [root], vm=off)
