"""The Gibbs sampler against the exact posterior on a 3 x 3 lattice at T = 1.

Lines given f: the sampled configurations of all 12 line sites against exact enumeration of the 4096
configurations (chi-square). f given the lines: sample mean and covariance against the Gaussian
posterior solved on the host (within 3 standard errors, estimated by batch means since successive
sweeps are correlated). Each in two colour orders: the coding must leave the posterior invariant.
"""

import itertools

import numpy as np
import pyopencl as cl
import pytest
from scipy import stats

from vmcl import mrf
from vmcl.mrf.energy import EnergyModel, LinePrior
from vmcl.mrf.lattice import Lattice, philox_key

H = W = 3
MODEL = EnergyModel(alpha=1.0, beta=1.0, prior=LinePrior(line=1.0, end=0.5, continuation=0.1, turn=0.3,
                                                         junction=0.8, crossing=1.5, parallel=0.7), edge_gain=0.5)
F = np.float32([[0.0, 1.1, 1.0], [0.1, 0.9, 1.2], [0.0, 0.2, 1.0]])
EDGES = np.array([[0, 1, 0], [0, 1, 0], [0, 0, 0]], bool)


def _chain(machine, lattice, order, sweeps, arrays, seed, thin):
    """Run ``sweeps`` sweeps; copy ``arrays`` after every ``thin``-th into one device buffer; read once."""
    per = sum(a.size for a in arrays)
    out = machine.empty((sweeps // thin, per), np.float32)
    key = philox_key(seed)
    for k in range(sweeps):
        lattice.sweep("sample", 1.0, k, key, order=order)
        if (k + 1) % thin == 0:
            offset = (k // thin) * per * 4
            for a in arrays:
                cl.enqueue_copy(machine.queue, out.data, a.data, byte_count=a.nbytes, dst_offset=offset)
                offset += a.nbytes
    return out.get()


def _exact_line_distribution():
    probabilities = np.empty(1 << 12)
    for index, bits in enumerate(itertools.product((0, 1), repeat=12)):
        line_h = np.array(bits[:6], bool).reshape(H, W - 1)
        line_v = np.array(bits[6:], bool).reshape(H - 1, W)
        probabilities[index] = -mrf.energy(F, line_h, line_v, data=F, edges=EDGES, model=MODEL)
    probabilities = np.exp(probabilities - probabilities.max())
    return probabilities / probabilities.sum()


@pytest.mark.parametrize("order", [(0, 1, 2, 3), (3, 0, 2, 1)], ids=str)
def test_lines_given_f_match_exact_enumeration(order, machine):
    to = machine.to_device
    lattice = Lattice(machine, to(F), None, to(EDGES.astype(np.uint8)), "smooth", MODEL)
    samples = _chain(machine, lattice, tuple(("lines", c) for c in order), 10000, (lattice.lh, lattice.lv),
                     seed=11, thin=1)
    lh = samples[:, :H * W].reshape(-1, H, W)[:, :, :W - 1].reshape(-1, 6)
    lv = samples[:, H * W:].reshape(-1, H, W)[:, :H - 1, :].reshape(-1, 6)
    bits = np.concatenate([lh, lv], axis=1).astype(np.int64)
    index = bits @ (1 << np.arange(11, -1, -1))
    observed = np.bincount(index, minlength=1 << 12)
    expected = _exact_line_distribution() * len(index)
    big = expected >= 5
    assert big.sum() > 50  # the test has power: many configurations are likely
    obs = np.append(observed[big], observed[~big].sum())
    exp = np.append(expected[big], expected[~big].sum())
    p = stats.chisquare(obs, exp, ddof=0).pvalue
    assert p > 0.001, p


def _gaussian_posterior(data, w, line_h, line_v):
    """Precision 2A and mean A^-1 b of exp(-U(f)) for U = sum w (f - g)^2 + sum (1 - l)(f_i - f_j)^2."""
    n = H * W
    a = np.diag(w.ravel().astype(np.float64))
    index = np.arange(n).reshape(H, W)
    bonds = [(index[y, x], index[y, x + 1], line_h[y, x]) for y in range(H) for x in range(W - 1)]
    bonds += [(index[y, x], index[y + 1, x], line_v[y, x]) for y in range(H - 1) for x in range(W)]
    for i, j, broken in bonds:
        if not broken:
            a[i, i] += 1
            a[j, j] += 1
            a[i, j] -= 1
            a[j, i] -= 1
    mean = np.linalg.solve(a, w.ravel()[:, None] * data.reshape(n, -1))
    return mean, np.linalg.inv(2 * a)


@pytest.mark.parametrize("components, order", [(1, (0, 1)), (2, (1, 0))], ids=str)
def test_f_given_lines_matches_gaussian_posterior(components, order, machine):
    rng = np.random.default_rng(components)
    data = rng.normal(0, 1, (H, W, components)).astype(np.float32)
    confidence = np.float32([[1.0, 0.0, 0.5], [0.0, 0.0, 2.0], [0.3, 0.0, 1.0]])
    line_h = np.array([[0, 1], [0, 1], [0, 0]], bool)
    line_v = np.array([[1, 0, 0], [0, 0, 1]], bool)
    to = machine.to_device
    lattice = Lattice(machine, to(data), to(confidence), None, "smooth", MODEL)
    for line, padded in ((line_h, lattice.lh), (line_v, lattice.lv)):
        full = np.zeros((H, W), np.float32)
        full[:line.shape[0], :line.shape[1]] = line
        padded.set(full.ravel())
    sweeps, batches = 12500, 50
    samples = _chain(machine, lattice, tuple(("f", c) for c in order), sweeps, (lattice.f,), seed=5, thin=1)
    samples = samples[500:].reshape(-1, H * W, components)
    mean, covariance = _gaussian_posterior(data, confidence, line_h, line_v)
    for c in range(components):
        x = samples[:, :, c].astype(np.float64)
        centred = x - mean[:, c]
        products = centred[:, :, None] * centred[:, None, :]
        for estimate, exact in ((x, mean[:, c]), (products, covariance)):
            per_batch = estimate.reshape(batches, -1, *estimate.shape[1:]).mean(axis=1)
            error = np.abs(per_batch.mean(axis=0) - exact)
            standard_error = per_batch.std(axis=0, ddof=1) / np.sqrt(batches)
            assert np.all(error < 3 * standard_error), (error / standard_error).max()
    if components == 2:  # components are independent given the lines
        cross = np.mean((samples[:, :, 0] - mean[:, 0]) * (samples[:, :, 1] - mean[:, 1]), axis=0)
        assert np.all(np.abs(cross) < 0.05)


POTTS = EnergyModel(alpha=2.0, beta=1.0, kappa=1.5, levels=(0.0, 0.5, 1.0))
LINE_H = np.array([[0, 1], [0, 1], [0, 0]], bool)
LINE_V = np.array([[1, 0, 0], [0, 0, 1]], bool)


def _potts_lattice(machine, data):
    """A constant-kind lattice of ``data`` with the lines LINE_H, LINE_V set (and kept: only f is swept)."""
    to = machine.to_device
    lattice = Lattice(machine, to(data), None, None, "constant", POTTS)
    for line, padded in ((LINE_H, lattice.lh), (LINE_V, lattice.lv)):
        full = np.zeros((H, W), np.float32)
        full[:line.shape[0], :line.shape[1]] = line
        padded.set(full.ravel())
    return lattice


def _potts_bonds():
    """(i, j, kept) of every bond of the 3 x 3 lattice under LINE_H, LINE_V."""
    index = np.arange(H * W).reshape(H, W)
    bonds = [(index[y, x], index[y, x + 1], not LINE_H[y, x]) for y in range(H) for x in range(W - 1)]
    return bonds + [(index[y, x], index[y + 1, x], not LINE_V[y, x]) for y in range(H - 1) for x in range(W)]


@pytest.mark.parametrize("order", [(0, 1), (1, 0)], ids=str)
def test_levels_given_lines_match_exact_enumeration(order, machine):
    """The constant kind's heat bath: each pixel's level marginals against the exact ones of
    exp(-U), U = sum alpha (f - g)^2 + kappa sum over kept bonds [f_i != f_j], over all 3^9 fields."""
    data = np.float32([[0.1, 0.6, 0.9], [0.4, 0.5, 1.0], [0.0, 0.3, 0.7]])
    lattice = _potts_lattice(machine, data)
    levels = np.float32(POTTS.levels)
    fields = np.array(list(itertools.product(range(3), repeat=H * W)))
    values = levels[fields]
    energy = (POTTS.alpha * (values - data.ravel()) ** 2).sum(axis=1)
    for i, j, kept in _potts_bonds():
        energy += POTTS.kappa * kept * (fields[:, i] != fields[:, j])
    weight = np.exp(-(energy - energy.min()))
    exact = np.stack([(weight[:, None] * (fields == k)).sum(axis=0) for k in range(3)], axis=1) / weight.sum()
    sweeps, batches = 20000, 50
    samples = _chain(machine, lattice, tuple(("f", c) for c in order), sweeps, (lattice.f,), seed=9, thin=1)
    samples = samples[500:][: (sweeps - 500) // batches * batches]
    for k, level in enumerate(levels):
        per_batch = (samples == level).reshape(batches, -1, H * W).mean(axis=1)
        error = np.abs(per_batch.mean(axis=0) - exact[:, k])
        standard_error = per_batch.std(axis=0, ddof=1) / np.sqrt(batches)
        assert np.all(error < 3 * standard_error + 1e-3), (error / np.maximum(standard_error, 1e-9)).max()


def test_an_icm_sweep_of_levels_takes_each_conditional_mode(machine):
    """One ICM sweep of the constant kind, colour 0 then colour 1, against the same on the host."""
    data = np.float32([[0.12, 0.61, 0.93], [0.38, 0.52, 0.97], [0.04, 0.33, 0.71]])
    lattice = _potts_lattice(machine, data)
    levels = np.float32(POTTS.levels)
    f = levels[np.abs(data.ravel()[:, None] - levels).argmin(axis=1)]  # the start: the nearest level
    np.testing.assert_array_equal(lattice.f.get().ravel(), f)
    neighbours = {i: [] for i in range(H * W)}
    for i, j, kept in _potts_bonds():
        neighbours[i].append((j, kept))
        neighbours[j].append((i, kept))
    for colour in (0, 1):
        new = f.copy()
        for i in range(H * W):
            if (i // W + i % W) % 2 != colour:
                continue
            energy = [POTTS.alpha * (level - data.ravel()[i]) ** 2
                      + sum(POTTS.kappa * kept * (level != f[j]) for j, kept in neighbours[i]) for level in levels]
            new[i] = levels[int(np.argmin(energy))]
        f = new
    lattice.sweep("icm", 1.0, 0, philox_key(0), order=(("f", 0), ("f", 1)))
    np.testing.assert_array_equal(lattice.f.get().ravel(), f)
    assert len(set(f.tolist())) > 1  # the modes are not all one level


def test_a_schedule_of_the_largest_count_allowed_starts_without_listing_its_temperatures():
    # Counts up to MAX_COUNT pass the schedules' checks; a list of 2**31 temperatures would take 16 GiB
    # before the first sweep, so the schedule is a generator.
    from vmcl.mrf.checks import MAX_COUNT
    from vmcl.mrf.sampler import temperatures

    huge = temperatures(2.0, 0.5, MAX_COUNT, 3)
    assert list(itertools.islice(huge, 4)) == [2.0, 2.0, 2.0, 1.0]
    np.testing.assert_allclose(list(temperatures(4.0, 0.8, 5)), 4.0 * 0.8 ** np.arange(5), rtol=0, atol=0)
