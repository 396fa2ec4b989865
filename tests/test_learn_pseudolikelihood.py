"""Maximum pseudolikelihood (vmcl.learn): the device's sums against the energy's own conditionals, and
parameters found again in fields drawn by vmcl's Gibbs sampler at known parameters."""

import dataclasses
import re

import numpy as np
import pytest
from oracles import pseudolikelihood as oracle_pseudolikelihood

from vmcl import mrf
from vmcl.errors import InputTypeError, InputValueError
from vmcl.learn import PARAMETERS, Example, fit_pseudolikelihood
from vmcl.learn.pseudolikelihood import Pseudolikelihood

THETA = dict(zip(PARAMETERS, (0.8, 1.3, 2.0, 0.7, 0.6, 0.3, 1.1, 1.7, 2.2, 0.9)))


def _configuration(rng, shape, kind):
    height, width = shape[:2]
    if kind == "smooth":
        f = rng.normal(0, 1, shape)
    else:
        f = rng.choice([0.0, 0.5, 1.0], size=shape)
    return (f, rng.random((height, width - 1)) < 0.4, rng.random((height - 1, width)) < 0.4,
            rng.random((height, width)) < 0.3)


@pytest.mark.parametrize("kind, shape", [("smooth", (5, 6)), ("smooth", (4, 5, 2)), ("constant", (5, 6))])
def test_value_and_gradient_match_the_energy(machine, kind, shape):
    rng = np.random.default_rng(7)
    f, lh, lv, edges = _configuration(rng, shape, kind)
    data = f + rng.normal(0, 0.3, shape)
    gamma = rng.uniform(0.2, 1.0, shape[:2])
    levels = (0.0, 0.5, 1.0) if kind == "constant" else None
    example = Example(f, lh, lv, data=data, confidence=gamma, edges=edges)
    value, grad, hess = Pseudolikelihood([example], kind=kind, levels=levels, machine=machine).terms(THETA)

    def oracle(theta):
        return oracle_pseudolikelihood(f, lh, lv, theta, data=data, confidence=gamma, edges=edges, kind=kind,
                                       levels=levels)

    assert value == pytest.approx(oracle(THETA), rel=1e-4)
    step = 1e-4
    for k, name in enumerate(PARAMETERS):
        up, down = dict(THETA), dict(THETA)
        up[name] += step
        down[name] -= step
        assert grad[k] == pytest.approx((oracle(up) - oracle(down)) / (2 * step), rel=2e-3, abs=2e-3), name
    assert np.allclose(hess, hess.T)
    assert np.all(np.linalg.eigvalsh(hess) > -1e-4)  # convex


@pytest.mark.parametrize("coupling", [0.1, 0.2, 0.3, 0.44, 0.5])
def test_ising_coupling_recovered(machine, coupling):
    """Ising fields (two levels, no lines, no data) of 128 x 128 drawn by vmcl.mrf.sample at J, Potts cost
    kappa = 2 J at T = 1; four independent fields pooled. Above the critical J = 0.4407 the chain starts
    ordered (from a random start it would coarsen for far longer than the test runs)."""
    ising = mrf.EnergyModel(alpha=0.0, kappa=2 * coupling, levels=(0.0, 1.0))
    examples = []
    for seed in range(4):
        start = np.random.default_rng(seed).integers(0, 2, (128, 128)).astype(np.float32)
        if coupling > 0.44:
            start[:] = 1.0
        drawn = mrf.sample(start, confidence=np.zeros((128, 128)), kind="constant", model=ising, lines=False,
                           start=start, sweeps=1000, seed=seed, machine=machine)
        examples.append(Example(drawn.field))
    fit = fit_pseudolikelihood(examples, kind="constant", levels=(0.0, 1.0), machine=machine)
    assert fit.converged and fit.fitted == ("coupling",)
    assert abs(fit.theta["coupling"] / 2 - coupling) < 0.01


PRIOR = mrf.LinePrior(line=1.0, end=0.4, continuation=0.5, turn=0.7, junction=1.0, crossing=1.2, parallel=0.6)
TRUTH = {"alpha": 1.0, "coupling": 1.0, "line": 2.0, "edge_gain": 1.0, "end": 0.8, "continuation": 1.0, "turn": 1.4,
         "junction": 2.0, "crossing": 2.4, "parallel": 1.2}  # EnergyModel(alpha 1, beta 2, PRIOR, edge_gain 0.5) at T = 1


@pytest.fixture(scope="module")
def line_process_draws(machine):
    """A smooth field with its line process drawn at T = 1 from the posterior given noisy blocks and
    edges (the true block boundaries and 5% random pixels): 16 draws of 192 x 192."""
    model = mrf.EnergyModel(alpha=1.0, beta=2.0, prior=PRIOR, edge_gain=0.5)
    examples = []
    for seed in range(16):
        rng = np.random.default_rng(seed)
        truth = np.zeros((192, 192), np.float32)
        for _ in range(12):
            y, x = rng.integers(0, 152, 2)
            h, w = rng.integers(20, 60, 2)
            truth[y:y + h, x:x + w] = rng.uniform(-3, 3)
        noisy = truth + rng.normal(0, 0.5, truth.shape).astype(np.float32)
        gy, gx = np.gradient(truth)
        edges = (np.hypot(gx, gy) > 0) | (rng.random(truth.shape) < 0.05)
        drawn = mrf.sample(noisy, edges=edges, model=model, sweeps=300, seed=seed, machine=machine)
        examples.append(Example(drawn.field, drawn.line_h, drawn.line_v, data=noisy, edges=edges))
    return examples


def test_line_process_potentials_recovered(machine, line_process_draws):
    """Every potential, the data weight and the edge coupling within 10%, and the model they make within
    10% of the truth."""
    fit = fit_pseudolikelihood(line_process_draws, machine=machine)
    assert fit.converged and set(fit.fitted) == set(PARAMETERS)
    for name, value in TRUTH.items():
        assert fit.theta[name] == pytest.approx(value, rel=0.1), name
    found = fit.model()
    assert fit.temperature == pytest.approx(1.0, rel=0.01)
    assert (found.alpha, found.beta, found.edge_gain) == pytest.approx((1.0, 2.0, 0.5), rel=0.1)
    for name in ("end", "continuation", "turn", "junction", "crossing", "parallel"):
        assert getattr(found.prior, name) == pytest.approx(getattr(PRIOR, name), rel=0.1), name


def test_a_refused_fit_advises_holding_the_coupling_as_its_caller_does(machine, line_process_draws):
    # The advice named the library's fixed= mapping, which vmcl fit rewrote by matching its text.
    fit = fit_pseudolikelihood(line_process_draws, machine=machine)
    flat = dataclasses.replace(fit, theta={**fit.theta, "alpha": 0.0})
    with pytest.raises(InputValueError, match=re.escape("hold the coupling (fixed={'coupling': 1.0})")):
        flat.model()
    with pytest.raises(InputValueError, match=re.escape("hold the coupling (--fix coupling=1)")):
        flat.model(held_coupling="--fix coupling=1")
    with pytest.raises(InputTypeError, match="held_coupling"):
        fit.model(held_coupling=1)


def test_one_kind_of_site_alone(machine, line_process_draws):
    """The pixels' conditionals alone give the data weight and the coupling; the lines' alone give the
    line potentials and the coupling; each model takes what its sites do not inform from the base."""
    pixels = fit_pseudolikelihood(line_process_draws, sites="pixels", machine=machine)
    assert set(pixels.fitted) == {"alpha", "coupling"} and pixels.sites["lines"] == 0
    assert (pixels.theta["alpha"], pixels.theta["coupling"]) == pytest.approx((1.0, 1.0), rel=0.05)
    base = mrf.EnergyModel(alpha=3.0, beta=7.0)
    assert pixels.model(base).beta == 7.0 and pixels.model(base).alpha == pytest.approx(1.0, rel=0.05)
    lines = fit_pseudolikelihood(line_process_draws, sites="lines", machine=machine)
    assert "alpha" not in lines.fitted and lines.sites["pixels"] == 0
    for name in ("coupling", "line", "edge_gain", "end", "parallel"):
        assert lines.theta[name] == pytest.approx(TRUTH[name], rel=0.1), name
    assert lines.model(base).alpha == 3.0 and lines.model(base).beta == pytest.approx(2.0, rel=0.1)


def test_held_parameters_and_defaults(machine):
    f = np.random.default_rng(0).normal(size=(16, 16))
    fit = fit_pseudolikelihood([Example(f)], machine=machine)
    assert fit.fitted == ("coupling",)  # no data, no lines: only the membrane's 1 / T
    assert fit.theta["alpha"] == 0.0 and fit.sites == {"pixels": 256, "lines": 0}
    # White noise of variance 1 read as a membrane: f_i given its n neighbours is N(mean, 1 / (2 c n)),
    # off by 1 + 1 / n from the noise's own spread about the neighbours' mean, so c is near 1 / (2 n (1 + 1 / n)).
    assert 0.05 < fit.theta["coupling"] < 0.2
    held = fit_pseudolikelihood([Example(f, np.zeros((16, 15)), np.zeros((15, 16)))], fixed={"continuation": 0.0},
                                machine=machine)
    assert held.theta["continuation"] == 0.0 and "continuation" not in held.fitted and "edge_gain" not in held.fitted


def test_unknown_pixels_are_left_out(machine):
    f = np.random.default_rng(0).normal(size=(12, 12))
    holes = f.copy()
    holes[3:6, 3:6] = np.nan
    whole = fit_pseudolikelihood([Example(f)], machine=machine)
    with_holes = fit_pseudolikelihood([Example(holes)], machine=machine)
    # 9 unknown pixels, and their 12 bonded neighbours whose conditionals read them
    assert with_holes.sites["pixels"] == whole.sites["pixels"] - 9 - 12


def test_refusals(machine):
    f = np.zeros((8, 8))
    with pytest.raises(InputTypeError, match="examples"):
        fit_pseudolikelihood([], machine=machine)
    with pytest.raises(InputTypeError, match="examples"):
        fit_pseudolikelihood([f], machine=machine)
    with pytest.raises(InputValueError, match="line_h must have shape"):
        fit_pseudolikelihood([Example(f, np.zeros((8, 8)), np.zeros((7, 8)))], machine=machine)
    with pytest.raises(InputValueError, match="unknown parameter 'beta'"):
        fit_pseudolikelihood([Example(f)], fixed={"beta": 1.0}, machine=machine)
    with pytest.raises(InputValueError, match="not among the levels"):
        fit_pseudolikelihood([Example(np.eye(8) * 0.5)], kind="constant", levels=(0.0, 1.0), machine=machine)
    with pytest.raises(InputValueError, match="2..64 distinct levels"):
        fit_pseudolikelihood([Example(np.arange(100.0).reshape(10, 10))], kind="constant", machine=machine)
    with pytest.raises(InputValueError, match="data must have the field's shape"):
        fit_pseudolikelihood([Example(f, data=np.zeros((8, 9)))], machine=machine)


def test_each_example_may_bring_its_own_levels(machine):
    """The constant kind's levels spread over each image's own range: the pooled terms are the sum of each
    example's terms with its levels."""
    rng = np.random.default_rng(3)
    first = Example(rng.choice([0.0, 0.5, 1.0], (8, 9)), data=rng.random((8, 9)), levels=(0.0, 0.5, 1.0))
    second = Example(rng.choice([0.2, 0.3], (7, 6)), data=rng.random((7, 6)), levels=(0.2, 0.3))
    pooled = Pseudolikelihood([first, second], kind="constant", machine=machine).terms(THETA)
    alone = [Pseudolikelihood([e], kind="constant", machine=machine).terms(THETA) for e in (first, second)]
    assert pooled[0] == pytest.approx(alone[0][0] + alone[1][0], rel=1e-6)
    assert np.allclose(pooled[1], alone[0][1] + alone[1][1], rtol=1e-5, atol=1e-6)


def test_lines_the_model_forbids_are_not_scored(machine):
    """With edge_radius (the model's require_edge) only line sites with an edge pixel within the radius
    of either pixel are scored."""
    rng = np.random.default_rng(4)
    f = rng.normal(size=(10, 12))
    edges = np.zeros((10, 12), bool)
    edges[:, 3] = True
    example = Example(f, rng.random((10, 11)) < 0.3, rng.random((9, 12)) < 0.3, edges=edges)
    everywhere = Pseudolikelihood([example], machine=machine).sites["lines"]
    assert everywhere == 10 * 11 + 9 * 12
    near = Pseudolikelihood([example], edge_radius=0, machine=machine).sites["lines"]
    # radius 0: an edge pixel at either end; lh sites (y, 2) and (y, 3), lv sites (y, 3)
    assert near == 10 * 2 + 9
    assert Pseudolikelihood([example], edge_radius=1, machine=machine).sites["lines"] == 10 * 4 + 9 * 3


def test_a_fit_with_nothing_to_score_is_refused(machine):
    # It "converged" at its start, and the fitted model then blamed the examples' roughness.
    data = np.random.default_rng(0).normal(size=(16, 16)).astype(np.float32)
    with pytest.raises(InputValueError, match="no site to score"):
        fit_pseudolikelihood([Example(np.full((16, 16), np.nan, np.float32), data=data)], machine=machine)
    with pytest.raises(InputValueError, match="no site to score"):
        fit_pseudolikelihood([Example(data, valid=np.zeros((16, 16), bool))], machine=machine)


@pytest.mark.parametrize("where", ["field", "data"])
def test_infinite_values_are_refused_not_taken_as_unknown(machine, where):
    values = np.random.default_rng(0).normal(size=(16, 16)).astype(np.float32)
    infinite = values.copy()
    infinite[3, 4] = np.inf
    example = Example(infinite, data=values) if where == "field" else Example(values, data=infinite)
    with pytest.raises(InputValueError, match=f"{where} must not hold infinities"):
        fit_pseudolikelihood([example], machine=machine)
    beyond = values.astype(np.float64)
    beyond[0, 0] = 1e300  # an infinity in float32, where the sums are computed
    with pytest.raises(InputValueError, match="field must not hold infinities or values beyond float32's range"):
        fit_pseudolikelihood([Example(beyond)], machine=machine)


def test_parameters_the_examples_say_nothing_of_are_not_fitted(machine):
    """Edges given but none set, and lines that make no crossing or turn: edge_gain, crossing and turn were
    "fitted" at 0 with the ridge's standard error (1 / sqrt(ridge * sites)); they are held, listed as
    uninformed, and the model keeps its base's values. The fitted parameters are those of a fit that holds the
    three itself (the pseudolikelihood does not depend on them)."""
    rng = np.random.default_rng(0)
    f = np.zeros((32, 32), np.float32)
    f[:, 16:] = 5
    g = f + 0.3 * rng.normal(size=f.shape).astype(np.float32)
    example = Example(f, np.abs(np.diff(f, axis=1)) > 1, np.abs(np.diff(f, axis=0)) > 1, data=g,
                      edges=np.zeros(f.shape))
    fit = fit_pseudolikelihood([example], machine=machine)
    assert set(fit.uninformed) == {"edge_gain", "turn", "crossing"}
    assert not set(fit.uninformed) & (set(fit.fitted) | set(fit.standard_error))
    held = fit_pseudolikelihood([example], fixed=dict.fromkeys(fit.uninformed, 0.0), machine=machine)
    for name in held.fitted:
        assert fit.theta[name] == pytest.approx(held.theta[name], rel=1e-6, abs=1e-9), name
    base = mrf.EnergyModel(edge_gain=0.3, prior=mrf.LinePrior(turn=0.4, crossing=2.5))
    model = fit.model(base)
    assert (model.edge_gain, model.prior.turn, model.prior.crossing) == (0.3, 0.4, 2.5)
    assert model.prior.end == pytest.approx(fit.theta["end"] / fit.theta["coupling"] / model.beta)
