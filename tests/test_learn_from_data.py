"""Parameters chosen from the data alone (vmcl.learn): the smoothing weight by cross-validation, the
noise by stochastic EM, the MPM temperature away from the phase transition; each against a truth the
test knows and the method never reads."""

import numpy as np
import pytest

from vmcl import mrf
from vmcl.errors import InputTypeError, InputValueError
from vmcl.learn import cross_validate, estimate_noise, scan_temperature

ISING_CRITICAL = 0.5 * np.log(1 + np.sqrt(2))  # Onsager's J_c of the square lattice


@pytest.mark.parametrize("sigma", [0.3, 1.0])
def test_cross_validated_weight_restores_nearly_as_well_as_the_best(machine, sigma):
    """A smooth surface with a jump, noisy: the weight chosen from held-out measurements gives a restored
    RMS error (against the noiseless surface, which the choice never sees) within 5% of the best weight
    of the same candidates."""
    y, x = np.mgrid[0:96, 0:96] / 96.0
    truth = 3 * np.sin(2 * np.pi * x) * np.cos(np.pi * y) + 4 * (x > 0.6)
    noisy = truth + np.random.default_rng(1).normal(0, sigma, truth.shape)
    settings = mrf.preset("stereo")
    schedule = settings.schedule("meanfield")
    found = cross_validate(noisy, model=settings.model, schedule=schedule, machine=machine)
    errors = []
    for alpha in found.candidates:
        model = mrf.EnergyModel(**{**settings.model.__dict__, "alpha": alpha})
        restored = mrf.restore(noisy, model=model, method="meanfield", schedule=schedule, machine=machine).field
        errors.append(float(np.sqrt(np.mean((restored - truth) ** 2))))
    assert errors[found.candidates.index(found.alpha)] <= 1.05 * min(errors)
    assert found.model.alpha == found.alpha and found.model.beta == settings.model.beta


def test_cross_validation_refusals(machine):
    with pytest.raises(InputValueError, match="too few to hold out"):
        cross_validate(np.zeros((4, 4)), machine=machine)
    with pytest.raises(InputValueError, match="folds"):
        cross_validate(np.zeros((32, 32)), holdout=0.25, folds=5, machine=machine)
    with pytest.raises(InputTypeError, match="candidates"):
        cross_validate(np.zeros((32, 32)), candidates=2.0, machine=machine)


@pytest.mark.parametrize("sigma", [0.2, 0.5, 1.0])
def test_noise_found_by_stochastic_em(machine, sigma):
    """Data drawn from the model itself (a membrane field drawn from the prior, plus noise of known sigma):
    the estimate within 5%."""
    model = mrf.EnergyModel(alpha=0.005, beta=4.0)  # the prior, anchored only weakly at 0
    field = mrf.sample(np.zeros((128, 128), np.float32), model=model, sweeps=500, seed=1, machine=machine).field
    data = field + np.random.default_rng(2).normal(0, sigma, field.shape).astype(np.float32)
    found = estimate_noise(data, model=model, machine=machine)
    assert found.sigma == pytest.approx(sigma, rel=0.05)
    assert found.alpha == pytest.approx(1 / (2 * found.sigma**2))


def test_scan_finds_the_ising_transition(machine):
    """The Ising model (Potts cost kappa = 1, no lines, no data) has its transition at T_c = kappa / (2 J_c)
    = 1.135: the density of domain walls changes fastest within 10% of it, and the MPM temperature is
    kept a factor 1.5 below."""
    spins = np.ones((96, 96), np.float32)
    ising = mrf.EnergyModel(alpha=0.0, kappa=1.0, levels=(0.0, 1.0))
    scan = scan_temperature(spins, confidence=np.zeros((96, 96)), kind="constant", model=ising, lines=False,
                            start=spins, temperatures=np.geomspace(0.7, 1.8, 15).tolist(), sweeps=600,
                            machine=machine)
    critical = 1.0 / (2 * ISING_CRITICAL)
    assert scan.transition == pytest.approx(critical, rel=0.1)
    assert scan.chosen == pytest.approx(scan.transition / 1.5)
    assert np.all(np.diff(scan.density) > -0.02)  # more walls when hotter, within a draw's noise


def test_the_machine_cross_validates_each_cues_weight_when_asked(machine):
    """[mrf] cross_validate: each cue's alpha chosen on the image (a note names it, one of the candidates
    around the cue's own alpha); without it no such note."""
    from vmcl import scenes
    from vmcl.cues.stereo import StereoCue
    from vmcl.learn.cross_validation import DEFAULT_FACTORS
    from vmcl.pipeline import Config, VisionMachine

    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    only = {"motion": {"enabled": False}, "colour": {"enabled": False}, "texture": {"enabled": False}}
    found = VisionMachine(Config.from_dict({**only, "mrf": {"cross_validate": True}}), machine=machine).run(
        scene.left, scene.right)
    notes = [n for n in found.notes if "chosen by cross-validation" in n]
    assert len(notes) == 1 and notes[0].startswith("stereo: data weight alpha ")
    chosen = float(notes[0].split("alpha ")[1].split(" ")[0])
    own = StereoCue.settings.model.alpha
    assert any(chosen == pytest.approx(own * factor) for factor in DEFAULT_FACTORS)
    plain = VisionMachine(Config.from_dict(only), machine=machine).run(scene.left, scene.right)
    assert not [n for n in plain.notes if "cross-validation" in n]
