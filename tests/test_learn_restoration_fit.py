"""Fitting an MRF to the errors of its own restorations (vmcl.learn.fit_restoration): the error counted
against a hand count, the search against an exhaustive grid of the same restorations, and its refusals."""

import numpy as np
import pytest

from vmcl import mrf
from vmcl.errors import InputTypeError, InputValueError
from vmcl.learn import Example, fit_restoration, restoration_error
from vmcl.learn.examples import truth_example


def test_error_counts_wrong_pixels_and_missed_and_false_lines():
    """A 10 x 10 field with a vertical jump between columns 4 and 5 (lines there). The restoration is
    wrong at 3 pixels (by 2 or 3, more than the tolerance; a fourth pixel off by 0.5 is within it), draws
    the jump's upper 5 rows (row 5 lies within 1 px of them; rows 6 to 9 are missed: 4 line pixels) and a
    false line 4 columns away (2 pixels): (3 + 4 + 2) / 100."""
    truth = np.zeros((10, 10), np.float32)
    truth[:, 5:] = 5.0
    example = truth_example(truth, truth, None, np.zeros((10, 10), bool))
    found = truth.copy()
    found[0, 0] = found[1, 1] = found[2, 8] = 2.0
    found[3, 3] = 0.5
    line_h = np.zeros((10, 9), bool)
    line_h[:5, 4] = True
    line_h[8:, 8] = True  # pixels (8, 8) and (9, 8): more than 1 px from the jump's pixels in column 4
    line_v = np.zeros((9, 10), bool)
    assert restoration_error(found, line_h, line_v, example) == pytest.approx(9 / 100)
    assert restoration_error(truth, *(np.asarray(x) for x in (example.line_h, example.line_v)), example) == 0.0


def test_error_leaves_out_invalid_pixels():
    truth = np.zeros((8, 8), np.float32)
    valid = np.ones((8, 8), bool)
    valid[:4] = False
    example = Example(truth, valid=valid, data=truth)
    found = truth.copy()
    found[:4] = 9.0  # wrong only where the truth is not known
    found[7, 7] = 9.0
    none_h, none_v = np.zeros((8, 7), bool), np.zeros((7, 8), bool)
    assert restoration_error(found, none_h, none_v, example) == pytest.approx(1 / 32)
    found[6, 0] = np.nan  # no value where the truth (0) is known: wrong, not read as 0
    assert restoration_error(found, none_h, none_v, example) == pytest.approx(2 / 32)
    with pytest.raises(InputValueError, match="example.valid"):
        restoration_error(found, none_h, none_v, Example(truth, valid=valid[:4], data=truth))
    with pytest.raises(InputValueError, match="both line_h and line_v"):
        restoration_error(found, none_h, none_v, Example(truth, line_h=none_h, data=truth))


def _stepped_example(seed):
    """A slanted surface with a 4 px step, measured with noise of 0.7 px; brightness edges on the step."""
    y, x = np.mgrid[0:64, 0:64]
    truth = (0.05 * x + 0.02 * y + 4.0 * (x >= 32)).astype(np.float32)
    data = truth + np.random.default_rng(seed).normal(0, 0.7, truth.shape).astype(np.float32)
    edges = np.zeros(truth.shape, bool)
    edges[:, 31:33] = True
    return truth_example(truth, data, None, edges)


def test_search_finds_the_grid_best_data_weight(machine):
    """Only the data weight searched, from a start 64 times too small (the surface smoothed flat): the
    fitted weight's error within 5% of the best of an exhaustive grid of the same restorations (2^-8 to
    2^4 in half steps), and below the start's."""
    examples = [_stepped_example(seed) for seed in (0, 1)]
    start = mrf.preset("stereo").override({"alpha": 2.0 ** -7})
    fit = fit_restoration(examples, start, parameters=("alpha",), machine=machine)
    schedule = start.schedule("meanfield")

    def grid_error(alpha):
        model = start.override({"alpha": alpha}).model
        total = 0.0
        for example in examples:
            found = mrf.restore(example.data, edges=example.edges, method="meanfield", model=model,
                                schedule=schedule, machine=machine)
            total += restoration_error(found.field, found.line_h, found.line_v, example) / len(examples)
        return total

    best = min(grid_error(2.0 ** k) for k in np.arange(-8.0, 4.5, 0.5))
    assert fit.error <= 1.05 * best + 1e-9
    assert fit.error < fit.start_error
    assert fit.error == pytest.approx(grid_error(fit.values["alpha"]))
    assert fit.settings.model.alpha == pytest.approx(fit.values["alpha"])
    assert fit.settings.model.beta == start.model.beta and fit.settings.schedules == start.schedules


def test_search_is_deterministic_and_moves_only_what_it_is_given(machine):
    examples = [_stepped_example(2)]
    start = mrf.preset("stereo")
    first = fit_restoration(examples, start, parameters=("beta", "end"), evaluations=12, machine=machine)
    second = fit_restoration(examples, start, parameters=("beta", "end"), evaluations=12, machine=machine)
    assert first.values == second.values and first.error == second.error
    assert first.evaluations <= 12 and sorted(first.values) == ["beta", "end"]
    model, before = first.settings.model, start.model
    assert (model.alpha, model.edge_gain, model.prior.turn) == (before.alpha, before.edge_gain, before.prior.turn)


def test_refusals(machine):
    example = _stepped_example(0)
    start = mrf.preset("stereo")
    with pytest.raises(InputValueError, match="examples is empty"):
        fit_restoration([], start, machine=machine)
    with pytest.raises(InputValueError, match=r"examples\[0\] has no data"):
        fit_restoration([Example(example.field)], start, machine=machine)
    with pytest.raises(InputTypeError, match=r"examples\[0\]"):
        fit_restoration([np.zeros((4, 4))], start, machine=machine)
    with pytest.raises(InputTypeError, match="start"):
        fit_restoration([example], start.model, machine=machine)
    with pytest.raises(InputValueError, match="parameter"):
        fit_restoration([example], start, parameters=("line",), machine=machine)
    with pytest.raises(InputValueError, match="more than once"):
        fit_restoration([example], start, parameters=("alpha", "alpha"), machine=machine)
    with pytest.raises(InputValueError, match="kappa > 0"):
        fit_restoration([example], start.override({"kappa": 0.0}), parameters=("kappa",), machine=machine)
    with pytest.raises(InputValueError, match="weights"):
        fit_restoration([example], start, weights=[1.0, 1.0], machine=machine)
    with pytest.raises(InputValueError, match="weights"):
        fit_restoration([example], start, weights=[-1.0], machine=machine)
    with pytest.raises(InputValueError, match="evaluations"):
        fit_restoration([example], start, evaluations=0, machine=machine)
    with pytest.raises(InputValueError, match="tolerance"):
        restoration_error(example.field, example.line_h, example.line_v, example, tolerance=0.0)
    with pytest.raises(InputValueError, match="field must have the example's shape"):
        restoration_error(np.zeros((3, 3)), example.line_h, example.line_v, example)
