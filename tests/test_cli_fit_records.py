"""`vmcl fit`'s records and refusals: parameters the examples say nothing of kept, not fitted; the measuring
Config written with the fit; a fitted file's text (notes, comments, its record) never lost or edited
unnoticed; bad truth and bad roots refused by name; folders without truth named."""

import re
import shutil

import numpy as np
import pytest

from vmcl import datasets, fitted, scenes
from vmcl.cli import main
from vmcl.errors import InputTypeError, InputValueError
from vmcl.learn.cue_fit import cue_examples, fit_cue
from vmcl.mrf import preset
from vmcl.pipeline import Config, VisionMachine, tomllib


def _pair(folder, disparity=None):
    """The reviewer's 64 px blocks pair, in which Canny finds no brightness edge (Middlebury 2014 layout)."""
    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    left, right = (np.nan_to_num(np.clip(v, 0, 1)) for v in (scene.left, scene.right))
    datasets.write_stereo_folder(folder, left, right, scene.disparity)
    if disparity is not None:
        datasets.write_pfm(folder / "disp0.pfm", disparity(scene.disparity).astype(np.float32))
    return folder


@pytest.fixture(scope="module")
def edgeless(tmp_path_factory):
    return _pair(tmp_path_factory.mktemp("edgeless") / "a").parent


def _fit(capsys, *args):
    code = main(["fit", *map(str, args), "-q"])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_parameters_without_information_keep_the_configurations_values(edgeless, tmp_path, capsys):
    """No brightness edge and no crossing vertex in the examples: edge_gain and crossing were written as 0
    with the ridge's standard error and "fitted yes"; they keep the preset's values, said so."""
    out = tmp_path / "s.toml"
    code, printed, _ = _fit(capsys, "stereo", "--data", edgeless, "--out", out)
    assert code == 0
    written = tomllib.loads(out.read_text())
    hand = preset("stereo").model
    assert written["mrf"]["stereo"]["edge_gain"] == hand.edge_gain
    assert written["mrf"]["stereo"]["prior"]["crossing"] == hand.prior.crossing
    assert set(written["fitted"]["uninformed"]) == {"edge_gain", "crossing"}
    rows = {line.split()[0]: line for line in printed.splitlines() if line.startswith("  ")}
    assert rows["edge_gain"].split()[1:] == ["no", "information:", "kept"]
    assert rows["alpha"].split()[-1] == "yes"


def test_the_measuring_config_is_written_with_the_fit(edgeless, tmp_path, capsys):
    """A fit measured with [stereo] dense = "intensity" held [mrf.stereo] alone, so that the file ran the
    fitted MRF on the default matcher's measurements; it now holds the measuring settings and records them."""
    measuring = tmp_path / "meas.toml"
    measuring.write_text('[stereo]\ndense = "intensity"\n')
    out = tmp_path / "withcfg.toml"
    assert _fit(capsys, "stereo", "--data", edgeless, "--config", measuring, "--out", out)[0] == 0
    loaded = Config.from_toml(out)
    assert loaded.stereo.dense == "intensity"
    record = tomllib.loads(out.read_text())["fitted"]
    assert record["config"] == str(measuring)
    assert record["config_sha256"] == fitted.config_sha256(Config.from_toml(measuring).to_dict())
    # The fit is of the measuring machine's data: the same as fit_cue gives with it.
    again = fit_cue("stereo", [edgeless], vm=VisionMachine(Config.from_toml(measuring)))
    assert loaded.mrf.stereo["alpha"] == again.tables["mrf"]["stereo"]["alpha"]


@pytest.mark.parametrize("edit", [
    lambda text: text.replace("[fitted]\n", "[fitted]\nnote = \"mine\"\n"),
    lambda text: text + "# my comment\n",
    lambda text: text.replace("converged = true", "converged = false"),
    lambda text: re.sub(r'data_sha256 = "\w+"', 'data_sha256 = "0"', text),
])
def test_an_edited_fitted_file_is_never_replaced(edgeless, tmp_path, capsys, edit):
    """Only the parameters' hash was compared: a note or any edit of the record was overwritten in silence."""
    out = tmp_path / "s.toml"
    assert _fit(capsys, "stereo", "--data", edgeless, "--out", out)[0] == 0
    out.write_text(edit(out.read_text()))
    before = out.read_bytes()
    code, _, err = _fit(capsys, "stereo", "--data", edgeless, "--out", out)
    assert code == 2 and "edited since: vmcl would lose the edit" in err
    assert out.read_bytes() == before


def test_an_edited_record_is_refused_when_loaded(edgeless, tmp_path, capsys):
    out = tmp_path / "s.toml"
    assert _fit(capsys, "stereo", "--data", edgeless, "--out", out)[0] == 0
    Config.from_toml(out)  # unedited, and with a comment added (not an entry), it loads
    out.write_text(out.read_text() + "# a comment\n")
    Config.from_toml(out)
    out.write_text(out.read_text().replace("converged = true", "converged = false"))
    with pytest.raises(InputValueError, match="edited or damaged"):
        Config.from_toml(out)


def test_negative_truth_and_truth_with_nothing_known_are_refused_by_folder(tmp_path, capsys):
    negative = _pair(tmp_path / "neg" / "a", disparity=lambda d: -d)
    code, _, err = _fit(capsys, "stereo", "--data", negative.parent, "--out", tmp_path / "n.toml")
    assert code == 2 and f"{negative}: its ground-truth disparity goes down to -" in err
    # A flow of NaN alone was met as the library's "examples: no site to score (sites='all')", naming no folder.
    import cv2

    unknown = tmp_path / "nan" / "a"
    unknown.mkdir(parents=True)
    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    for name, frame in (("frame10.png", scene.left), ("frame11.png", scene.left_next)):
        cv2.imwrite(str(unknown / name), (np.clip(np.nan_to_num(frame), 0, 1)[..., ::-1] * 255).astype(np.uint8))
    datasets.write_flo(unknown / "flow10.flo", np.full_like(scene.flow, np.nan))
    code, _, err = _fit(capsys, "motion", "--data", unknown.parent, "--out", tmp_path / "u.toml")
    assert code == 2 and f"{unknown}: its ground-truth flow has no known value" in err, err
    assert not (tmp_path / "n.toml").exists() and not (tmp_path / "u.toml").exists()


def test_folders_without_truth_are_named(edgeless, tmp_path, capsys):
    root = tmp_path / "data"
    shutil.copytree(edgeless / "a", root / "a")
    shutil.copytree(edgeless / "a", root / "nogt")
    (root / "nogt" / "disp0.pfm").unlink()
    code, _, err = _fit(capsys, "stereo", "--data", root, "--out", tmp_path / "s.toml")
    assert code == 0
    assert f"vmcl: note: left out {root / 'nogt'}: " in err and "disp0.pfm" in err


def test_the_walk_that_finds_the_examples_names_the_folders_left_out(edgeless, tmp_path):
    # cue_examples gave the examples alone, and fit_cue walked the roots again to name the rest.
    root = tmp_path / "data"
    shutil.copytree(edgeless / "a", root / "a")
    shutil.copytree(edgeless / "a", root / "nogt")
    (root / "nogt" / "disp0.pfm").unlink()
    _, names, _, left_out = cue_examples("stereo", [root, root / "nogt"], VisionMachine())
    assert names == ["a"]
    assert len(left_out) == 1 and left_out[0].startswith(f"left out {root / 'nogt'}: ") and "disp0.pfm" in left_out[0]


def test_fit_cue_names_a_refused_held_value_as_its_caller_does(tmp_path):
    # The command matched the library's text to say which --fix was refused; the caller now gives the name.
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputValueError, match=re.escape("--fix coupling=0: fixed['coupling'] must be > 0")):
        fit_cue("colour", tmp_path / "empty", fixed={"alpha": 1.0, "coupling": 0.0}, fixed_name="--fix")
    with pytest.raises(InputValueError, match=r"^fixed\['alpha'\] must be > 0"):  # no name: the library's own
        fit_cue("stereo", tmp_path / "empty", fixed={"alpha": -1.0})
    with pytest.raises(InputTypeError, match="fixed_name must be a str"):
        fit_cue("stereo", tmp_path / "empty", fixed_name=3)


def test_fit_cue_refuses_bad_roots_and_machines_by_name(edgeless):
    one = fit_cue("stereo", str(edgeless))  # a single path is one root, not a string of them
    assert one.provenance["data"] == ["a"]
    for roots, kind, message in (([], InputValueError, "roots is empty"),
                                 (["nope"], InputValueError, "roots: nope is not a folder"),
                                 (3, InputTypeError, "roots must be a folder's path")):
        for cue in ("stereo", "motion", "colour"):
            with pytest.raises(kind, match=message):
                fit_cue(cue, roots)
    with pytest.raises(InputTypeError, match="vm must be a vmcl.pipeline.VisionMachine"):
        fit_cue("stereo", [edgeless], vm=3)


@pytest.mark.parametrize("args, message", [
    (["colour", "--fix", "coupling=0"], "--fix coupling=0: fixed['coupling'] must be > 0"),
    (["texture", "--fix", "coupling=-1"], "--fix coupling=-1: fixed['coupling'] must be > 0"),
    (["colour", "--jump", "2"], "--jump is an option of the stereo and motion fits"),
    (["stereo", "--fix", "line=1e400"], "--fix line=1e400: '1e400' is not a finite number"),
])
def test_fit_options_refused_before_any_work(tmp_path, capsys, args, message):
    # An empty folder: a refusal that waited for the examples would say there are none.
    (tmp_path / "empty").mkdir()
    code, _, err = _fit(capsys, *args, "--data", tmp_path / "empty", "--out", tmp_path / "x.toml")
    assert code == 2 and message in err, err


def test_free_coupling_advice_names_the_option(edgeless, tmp_path, capsys):
    code, _, err = _fit(capsys, "stereo", "--data", edgeless, "--fix", "coupling=free", "--out", tmp_path / "x.toml")
    assert code == 2 and "--fix coupling=1" in err and "fixed={" not in err


def test_the_version_warning_is_a_vmcl_line(tmp_path, capsys, monkeypatch, recwarn):
    monkeypatch.setattr("vmcl.__version__", "0.0.1")
    other = fitted.write_fitted(tmp_path / "other.toml", {"mrf": {"stereo": {"alpha": 0.5}}}, {"data": ["x"]})
    monkeypatch.undo()
    # One written before the record was sealed, its vmcl entry gone: a version it does not say.
    unsaid = tmp_path / "unsaid.toml"
    unsaid.write_text(re.sub(r'\n(vmcl|entries_sha256) = "[^"]*"', "", other.read_text()))
    (tmp_path / "empty").mkdir()
    for config, message in ((other, "other.toml was fitted by vmcl 0.0.1, this is vmcl"),
                            (unsaid, "unsaid.toml does not say which vmcl version fitted it")):
        code, _, err = _fit(capsys, "stereo", "--data", tmp_path / "empty", "--config", config, "--out",
                            tmp_path / "x.toml")
        assert code == 2 and f"vmcl: warning: {tmp_path / message}" in err, err
        assert "UserWarning" not in err
    assert not [w for w in recwarn if issubclass(w.category, fitted.FittedVersionWarning)]




def test_a_fitted_file_with_its_entries_reordered_still_loads():
    # The record's hash covered the text as written: two entries swapped were refused as an edit.
    import tempfile
    from pathlib import Path

    from vmcl.fitted import check_fitted, write_fitted
    from vmcl.pipeline import tomllib

    with tempfile.TemporaryDirectory() as folder:
        path = write_fitted(Path(folder) / "f.toml", {"mrf": {"stereo": {"alpha": 2.0, "beta": 0.5}}},
                            {"data": ["x"], "what": "mrf.stereo"})
        text = path.read_text()
        swapped = text.replace("alpha = 2.0\nbeta = 0.5", "beta = 0.5\nalpha = 2.0")
        assert swapped != text
        check_fitted(tomllib.loads(swapped), "f.toml")  # loads: the same entries
        with pytest.raises(ValueError, match="edited or damaged since"):
            check_fitted(tomllib.loads(swapped.replace("beta = 0.5", "beta = 0.6")), "f.toml")


def test_the_users_warning_filters_decide_the_version_warning(tmp_path, capsys, monkeypatch):
    # The command forced its "always" ahead of every filter: `python -W ignore::...` still printed the line.
    import warnings

    monkeypatch.setattr("vmcl.__version__", "0.0.1")
    other = fitted.write_fitted(tmp_path / "other.toml", {"mrf": {"stereo": {"alpha": 0.5}}}, {"data": ["x"]})
    monkeypatch.undo()
    (tmp_path / "empty").mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fitted.FittedVersionWarning)
        code, _, err = _fit(capsys, "stereo", "--data", tmp_path / "empty", "--config", other, "--out",
                            tmp_path / "x.toml")
    assert code == 2 and "vmcl: warning" not in err, err
