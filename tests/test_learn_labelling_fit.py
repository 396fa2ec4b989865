"""The labelling classifier's fit (vmcl.learn.labelling_fit, `vmcl fit labelling`): it regenerates the shipped
weights from the renderings they name, writes a checked file a Config loads, and refuses what it cannot use."""

import numpy as np
import pytest

from vmcl import labelling
from vmcl.cli import main
from vmcl.errors import InputError
from vmcl.learn.labelling_fit import fit_labeller, labeller_provenance, labelling_fields, rendered_runs
from vmcl.pipeline import Config, VisionMachine

ALL_INPUTS = "+".join(labelling.INPUTS)


def test_the_shipped_weights_are_regenerated_from_what_they_name(machine):
    """The renderings and seeds the shipped file names give, refitted, the shipped weights' class probabilities
    at every candidate they were fitted on, and the same description and renderer hash as its record."""
    vm = VisionMachine(Config.from_dict({"labels": {"method": "rule"}}), machine=machine)
    shipped = labelling.default_labeller()
    fitted_on, provenance = labeller_provenance()
    assert shipped.fitted_on == fitted_on
    assert {k: shipped.record[k] for k in ("data_sha256", "config_sha256")} == \
        {k: provenance[k] for k in ("data_sha256", "config_sha256")}
    runs = rendered_runs(vm)
    assert len(runs) == 20  # five presets, with and without highlights, two seeds
    again = fit_labeller(runs.values(), input_sets=[labelling.INPUTS], machine=machine)
    # Compared by what they say, not weight by weight: the logistic fit is nearly flat along some directions
    # (a constant added to every class's bias; the bias of a class no candidate has), and L-BFGS stops
    # along them where the host's arithmetic leads it. Fitted on PoCL on two CPUs (an AMD EPYC and an Intel
    # Xeon), the bias row moved by up to 0.7 while no probability moved by 2e-4. Another OpenCL implementation
    # rounds the machine's fields differently in their last bits, and the fit follows (NVIDIA's moved the
    # weights by up to about 0.01).
    exact = "Portable Computing Language" in machine.device.platform.name
    np.testing.assert_allclose(_probabilities(again, runs, machine), _probabilities(shipped, runs, machine),
                               atol=1e-3 if exact else 0.02)


def _probabilities(labeller, runs, machine):
    """Each class's probability at every candidate of the runs, by ``labeller``'s weights for all inputs."""
    weights = labeller.weights[ALL_INPUTS].astype(np.float64)
    found = []
    for result, _, _ in runs.values():
        features = labelling.features(result.support, result.image, machine=machine, **labelling_fields(result))
        rows = np.moveaxis(features, 0, -1)[(result.support & labelling.CANDIDATE_BITS) != 0].astype(np.float64)
        z = np.concatenate([np.ones((len(rows), 1)), rows], axis=1) @ weights
        z -= z.max(axis=1, keepdims=True)
        found.append(np.exp(z) / np.exp(z).sum(axis=1, keepdims=True))
    return np.concatenate(found)


def test_rendered_runs_refusals(machine):
    linear = VisionMachine(machine=machine)
    with pytest.raises(InputError, match="rule"):
        rendered_runs(linear, presets=["blocks"])
    rule = VisionMachine(Config.from_dict({"labels": {"method": "rule"}}), machine=machine)
    with pytest.raises(InputError, match="presets"):
        rendered_runs(rule, presets=["nowhere"])
    with pytest.raises(InputError, match="presets"):
        rendered_runs(rule, presets="blocks")
    with pytest.raises(InputError, match="seeds"):
        rendered_runs(rule, presets=["blocks"], seeds=[-1])
    with pytest.raises(InputError, match="shape"):
        rendered_runs(rule, presets=["blocks"], shape=(32, 32))
    with pytest.raises(InputError, match="vm"):
        rendered_runs(None)
    with pytest.raises(InputError, match="runs is empty"):
        fit_labeller([])
    with pytest.raises(InputError, match=r"runs\[0\]"):
        fit_labeller([(None, None, None)])
    with pytest.raises(InputError, match="result"):
        labelling_fields(None)


def test_fit_labelling_writes_weights_a_config_loads(tmp_path, capsys):
    out = tmp_path / "weights.json"
    assert main(["fit", "labelling", "--out", str(out), "--seeds", "3", "--size", "96", "-q"]) == 0
    assert "Wrote" in capsys.readouterr().out
    loaded = Config.from_dict({"labels": {"weights": str(out)}}).labels.labeller()
    assert "seeds (3,)" in loaded.fitted_on and loaded.record["code"] == "vmcl.learn.labelling_fit"
    assert sorted(loaded.weights) == sorted(labelling.default_labeller().weights)
    assert main(["fit", "labelling", "--out", str(out), "--seeds", "3", "--size", "96", "-q"]) == 0  # its own: replaced


@pytest.mark.parametrize("args, message", [
    (["labelling", "--out", "{tmp}/w.toml"], "name it *.json"),
    (["labelling", "--out", "{tmp}/w.json", "--data", "{tmp}"], "takes no --data"),
    (["labelling", "--out", "{tmp}/w.json", "--size", "16"], "at least 64"),
    (["labelling", "--out", "{tmp}/mine.json"], "not a file `vmcl fit` wrote"),
    (["stereo", "--out", "{tmp}/s.toml"], "needs --data"),
    (["stereo", "--out", "{tmp}/s.toml", "--data", "{tmp}", "--seeds", "3"], "an option of vmcl fit labelling"),
    (["labelling", "--out", "{tmp}/w.json", "--refine"], "not of vmcl fit labelling"),
    (["labelling", "--out", "{tmp}/w.json", "--jump", "2"], "not of vmcl fit labelling"),
])
def test_fit_labelling_refusals_are_one_line(tmp_path, capsys, args, message):
    (tmp_path / "mine.json").write_text("{}")
    assert main(["fit", *[a.format(tmp=tmp_path) for a in args], "-q"]) == 2
    assert message in capsys.readouterr().err
    assert (tmp_path / "mine.json").read_text() == "{}"
    assert not (tmp_path / "w.json").exists() and not (tmp_path / "w.toml").exists()
