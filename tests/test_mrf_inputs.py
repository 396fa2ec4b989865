"""What restore and sample make of their inputs: the constant kind's levels, warm starts with gaps, the value
checks of device arrays, values beyond float32's range, the device memory check, masked arrays and wide
edge radii (the user review of the MRF stage)."""

import time

import numpy as np
import pytest
from scipy import ndimage

from vmcl import mrf
from vmcl.errors import InputValueError
from vmcl.mrf.energy import EnergyModel, LinePrior, line_costs, resolve_levels
from vmcl.mrf.lattice import Lattice

RNG = np.random.default_rng(1)
CLEAN = np.zeros((64, 64))
CLEAN[:, 32:] = 4
CLEAN[10:30, 5:20] = 2
NOISY = CLEAN + RNG.normal(0, 0.3, CLEAN.shape)
STEP = (CLEAN > 0) * 1.0
STEP_NOISY = STEP + RNG.normal(0, 0.1, STEP.shape)


def _rmse(field, truth):
    return float(np.sqrt(np.mean((field - truth) ** 2)))


# ------------------------------------------------------------------------------- the constant kind's levels

def test_a_warm_start_does_not_move_the_levels_off_the_data(machine):
    model = EnergyModel(alpha=50, levels=8)
    cold = mrf.restore(STEP_NOISY, kind="constant", model=model, method="meanfield", machine=machine)
    warm = mrf.restore(STEP_NOISY, kind="constant", model=model, method="meanfield", machine=machine,
                       start=np.full(STEP.shape, 0.5))
    levels = resolve_levels(model, float(STEP_NOISY.astype(np.float32).min()),
                            float(STEP_NOISY.astype(np.float32).max()))
    for found in (cold, warm):
        assert set(np.unique(found.field)) <= set(levels.tolist())
        # The start's span (0.5 only) once gave levels 0.5 .. 1.36 and no level near the dark half.
        assert _rmse(found.field, STEP) < 0.15


def test_levels_span_the_weighted_data_then_all_data_then_the_start(machine):
    to = machine.to_device
    model = EnergyModel(levels=5)
    data = np.linspace(-2, 3, 64, dtype=np.float32).reshape(8, 8)
    start = np.full((8, 8), 10.0, np.float32)
    confidence = np.zeros((8, 8), np.float32)
    confidence[2:4, 2:4] = 1  # the data from -1.21 to -0.87 have a weight
    weighted = Lattice(machine, to(data), to(confidence), None, "constant", model, to(start))
    span = data[2:4, 2:4]
    np.testing.assert_array_equal(weighted.levels.get(), resolve_levels(model, float(span.min()), float(span.max())))
    # None with a weight (the prior): all of the data's finite values, still not the start's.
    prior = Lattice(machine, to(data), to(np.zeros((8, 8), np.float32)), None, "constant", model, to(start))
    np.testing.assert_array_equal(prior.levels.get(), resolve_levels(model, -2.0, 3.0))
    # No data at all: the start's span is all there is.
    ramp = np.linspace(0, 1, 64, dtype=np.float32).reshape(8, 8)
    empty = Lattice(machine, to(np.full((8, 8), np.nan, np.float32)), None, None, "constant", model, to(ramp))
    np.testing.assert_array_equal(empty.levels.get(), resolve_levels(model, 0.0, 1.0))


# ---------------------------------------------------------------------------------------- MPM's samples

@pytest.mark.parametrize("make", [lambda: mrf.MpmSchedule(samples=0),
                                  lambda: mrf.Settings().override({"samples": 0})])
def test_mpm_refuses_to_average_no_samples(make):
    with pytest.raises(InputValueError, match="samples must be >= 1"):
        make()


def test_mpm_of_one_sample_is_that_sample(machine):
    found = mrf.restore(NOISY, method="mpm", schedule=mrf.MpmSchedule(burn_in=5, samples=1), machine=machine)
    assert found.sweeps == 6 and np.isfinite(found.energy) and _rmse(found.field, CLEAN) < 1.0


# --------------------------------------------------------------------------- a warm start with gaps, no data

def test_gaps_of_a_start_are_filled_from_it_where_no_datum_has_a_weight(machine):
    start = NOISY.copy()
    start[:8] = np.nan
    drawn = mrf.sample(NOISY, confidence=np.zeros(NOISY.shape), start=start, sweeps=5, machine=machine)
    assert np.isfinite(drawn.field).all() and np.isfinite(drawn.energy)
    to = machine.to_device
    lattice = Lattice(machine, to(NOISY.astype(np.float32)), to(np.zeros(NOISY.shape, np.float32)), None,
                      "smooth", EnergyModel(), to(start.astype(np.float32)))
    began = lattice.f_start.get()
    np.testing.assert_array_equal(began[8:], start[8:].astype(np.float32))
    # The gap begins at the start's neighbours (row 8, which the jump fill reaches first).
    assert np.isfinite(began).all() and began[:8].min() >= start[8:].min() and began[:8].max() <= start[8:].max()


def test_a_start_with_no_value_and_no_weighted_data_is_refused(machine):
    with pytest.raises(InputValueError, match="start holds no finite value"):
        mrf.sample(NOISY, confidence=np.zeros(NOISY.shape), start=np.full(NOISY.shape, np.nan), sweeps=5,
                   machine=machine)


# ------------------------------------------------------------------------------ device arrays' values

def _device(machine, array):
    return machine.to_device(np.asarray(array, np.float32))


def _confidence(value):
    gamma = np.ones(NOISY.shape, np.float32)
    gamma[4:8, 4:8] = value
    return gamma


@pytest.mark.parametrize("gamma", [_confidence(np.nan), _confidence(-5.0), _confidence(np.inf),
                                   np.full(NOISY.shape, np.nan, np.float32), -np.ones(NOISY.shape, np.float32)],
                         ids=["nan", "negative", "inf", "all nan", "all negative"])
@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_confidence_is_checked_on_the_device_as_on_the_host(gamma, on_device, machine):
    confidence = _device(machine, gamma) if on_device else gamma
    with pytest.raises(InputValueError, match="confidence must") as raised:
        mrf.restore(_device(machine, NOISY), confidence=confidence, method="icm", machine=machine)
    assert not isinstance(raised.value, mrf.NothingToRestore)
    with pytest.raises(InputValueError, match="confidence must"):
        mrf.sample(_device(machine, NOISY), confidence=confidence, sweeps=1, machine=machine)


@pytest.mark.parametrize("name", ["data", "start"])
@pytest.mark.parametrize("value", [np.inf, -np.inf])
@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_infinities_are_refused_in_the_data_and_the_start(name, value, on_device, machine):
    bad = NOISY.astype(np.float32)
    bad[3, 3] = value
    bad = _device(machine, bad) if on_device else bad
    good = _device(machine, NOISY) if on_device else NOISY.astype(np.float32)
    args = {"data": good, "start": good, name: bad}
    with pytest.raises(InputValueError, match=f"{name} must not hold infinities"):
        mrf.restore(args["data"], start=args["start"], method="icm", machine=machine)


@pytest.mark.parametrize("on_device", [False, True], ids=["host", "device"])
def test_backfill_refuses_a_negative_secondary_confidence(on_device, machine):
    field = NOISY.astype(np.float32)
    gamma = np.ones(field.shape, np.float32)
    gamma[0, 0] = -0.5
    args = [_device(machine, a) if on_device else a for a in (field, field, gamma)]
    with pytest.raises(InputValueError, match="secondary_confidence must be >= 0"):
        mrf.backfill(*args, machine=machine)
    # NaN still means no confidence, as documented.
    gamma[0, 0] = np.nan
    args[2] = _device(machine, gamma) if on_device else gamma
    primary = field.copy()
    primary[0, 0] = np.nan
    args[0] = _device(machine, primary) if on_device else primary
    _, weight = mrf.backfill(*args, machine=machine)
    assert (weight.get() if on_device else weight)[0, 0] == 0


# ----------------------------------------------------------------------------- beyond float32's range

@pytest.mark.parametrize("make, match", [
    (lambda: EnergyModel(alpha=1e39), "EnergyModel.alpha must lie within float32's range"),
    (lambda: EnergyModel(beta=1e39), "EnergyModel.beta must lie within float32's range"),
    (lambda: EnergyModel(kappa=-1e39), "EnergyModel.kappa must be a finite number >= 0"),
    (lambda: EnergyModel(kappa=1e39), "EnergyModel.kappa must lie within float32's range"),
    (lambda: EnergyModel(edge_gain=-1e39), "EnergyModel.edge_gain must lie within float32's range"),
    (lambda: EnergyModel(levels=(0.0, 1e39)), "EnergyModel.levels must lie within float32's range"),
    (lambda: EnergyModel(levels=(1.0, 1.0 + 1e-12)), "EnergyModel.levels must be distinct as float32"),
    (lambda: EnergyModel(beta=1e20, prior=LinePrior(crossing=1e20)), r"beta \* EnergyModel.prior.crossing"),
    (lambda: EnergyModel(beta=1e20, edge_gain=1e20), r"beta \* EnergyModel.edge_gain"),
    (lambda: LinePrior(line=1e39), "LinePrior.line must lie within float32's range"),
    (lambda: mrf.AnnealSchedule(t0=1e39), "AnnealSchedule.t0 must lie within float32's range"),
    (lambda: mrf.MeanFieldSchedule(mf_t0=1e39), "MeanFieldSchedule.mf_t0 must lie within float32's range"),
    (lambda: mrf.MpmSchedule(mpm_temperature=1e39), "MpmSchedule.mpm_temperature must lie within float32's"),
    (lambda: mrf.preset("stereo").override({"alpha": 1e39}, prefix="mrf.stereo"), "mrf.stereo.alpha must lie"),
    (lambda: mrf.sample(NOISY, temperature=1e39, sweeps=1), "temperature must lie within float32's range"),
])
def test_settings_beyond_float32_are_refused_by_name(make, match):
    with pytest.raises(InputValueError, match=match):
        make()


def test_data_and_weights_beyond_float32_are_refused_by_name(machine):
    data = NOISY.copy()
    data[5, 5] = 1e39
    with pytest.raises(InputValueError, match="data has values beyond float32's range"):
        mrf.restore(data, method="icm", machine=machine)
    with pytest.raises(InputValueError, match="start has values beyond float32's range"):
        mrf.restore(NOISY, start=data, method="icm", machine=machine)
    confidence = np.ones(NOISY.shape)
    confidence[3, 3] = 1e39
    with pytest.raises(InputValueError, match="confidence has values beyond float32's range"):
        mrf.restore(NOISY, confidence=confidence, method="meanfield", machine=machine)
    # Each within range, their product not: alpha * confidence is the weight the device holds.
    with pytest.raises(InputValueError, match=r"model.alpha \(100\) times the confidence exceeds float32's range"):
        mrf.restore(NOISY, confidence=np.full(NOISY.shape, 1e37), model=EnergyModel(alpha=100), method="icm",
                    machine=machine)


# --------------------------------------------------------------------------------------- device memory

def test_a_lattice_too_large_for_the_device_is_refused_before_it_is_made(machine):
    levels = 64
    side = int(np.ceil(np.sqrt(machine.device.max_mem_alloc_size / (4 * levels)))) + 1
    if side * side * 4 > 2**30:
        pytest.skip(f"this device allocates {machine.device.max_mem_alloc_size} bytes at once: the data to "
                    "outgrow it would not fit this test")
    model = EnergyModel(levels=levels)
    began = time.perf_counter()
    with pytest.raises(InputValueError, match=r"mrf.restore \(method 'meanfield'\) .* needs .* MiB of device memory"):
        mrf.restore(np.zeros((side, side), np.float32), kind="constant", model=model, method="meanfield",
                    machine=machine)
    assert time.perf_counter() - began < 10  # once a LogicError (INVALID_BUFFER_SIZE) after the preparation


@pytest.mark.parametrize("kind, method, largest_words", [
    ("constant", "meanfield", 64), ("constant", "mpm", 64), ("smooth", "mpm", 2), ("smooth", "meanfield", 2),
    ("constant", "icm", 1), ("smooth", "anneal", 2)])
def test_the_memory_asked_for_holds_the_solvers_buffers(kind, method, largest_words, machine, monkeypatch):
    asked = []
    monkeypatch.setattr(machine, "require_memory", lambda what, total, largest=None: asked.append((what, total,
                                                                                                  largest)))
    shape = (16, 24) if kind == "constant" else (16, 24, 2)
    data = np.zeros(shape, np.float32)
    schedule = mrf.SOLVERS[method].schedule(**({"mf_steps": 1} if method == "meanfield" else {}))
    mrf.restore(data, kind=kind, method=method, model=EnergyModel(levels=64), schedule=schedule, machine=machine)
    ((what, total, largest),) = asked
    n = 16 * 24
    assert what.startswith(f"mrf.restore (method {method!r})")
    assert largest == 4 * n * largest_words
    solver = sum(mrf.SOLVERS[method].buffers(kind, 1 if kind == "constant" else 2, 64))
    assert total >= 4 * n * (solver + 5 * (1 if kind == "constant" else 2) + 6)
    asked.clear()
    mrf.sample(data, kind=kind, model=EnergyModel(levels=64), sweeps=1, machine=machine)
    assert [entry[0].split(" of ")[0] for entry in asked] == ["mrf.sample"]


# -------------------------------------------------------------------------------------------- masked arrays

@pytest.mark.parametrize("name", ["confidence", "edges", "data", "start"])
def test_masked_arrays_with_masked_values_are_refused(name, machine):
    masked = np.ma.masked_greater(np.ones(NOISY.shape), 0.5)
    args = {"data": NOISY, "start": None, name: masked}
    data = args.pop("data")
    with pytest.raises(InputValueError, match=f"{name} is a masked array with masked values"):
        mrf.restore(data, method="icm", machine=machine, **args)


# ----------------------------------------------------------------------------------------- edge radius

def _near_oracle(edges, radius):
    if radius >= max(edges.shape):
        return np.full(edges.shape, edges.any())
    return ndimage.maximum_filter(edges.astype(np.uint8), size=2 * radius + 1, mode="constant") > 0


@pytest.mark.parametrize("radius", [0, 1, 3, 17, 399, 400, 2**31 - 1])
def test_line_costs_of_any_radius_are_the_squares(radius, machine):
    rng = np.random.default_rng(radius % 97)
    shape = (400, 400)
    edges = rng.random(shape) < 2e-4
    model = EnergyModel(require_edge=True, edge_radius=radius)
    lattice = Lattice(machine, machine.to_device(np.zeros(shape, np.float32)), None,
                      machine.to_device(edges.astype(np.uint8)), "smooth", model)
    b_h, b_v = line_costs(shape, edges, model)
    near = _near_oracle(edges, radius)
    allowed_h, allowed_v = near[:, :-1] | near[:, 1:], near[:-1] | near[1:]
    np.testing.assert_array_equal(np.isfinite(b_h), allowed_h)
    np.testing.assert_array_equal(np.isfinite(b_v), allowed_v)
    device_h = lattice.bh.get().reshape(shape)[:, :-1]
    device_v = lattice.bv.get().reshape(shape)[:-1, :]
    np.testing.assert_array_equal(device_h, b_h.astype(np.float32))
    np.testing.assert_array_equal(device_v, b_v.astype(np.float32))


@pytest.mark.parametrize("radius", [399, 2**31 - 1])
def test_the_cost_of_a_wide_radius_does_not_grow_with_it(radius, machine):
    # One edge pixel, in the corner where a scan of each site's square reaches it last.
    shape = (400, 400)
    edges = np.zeros(shape, bool)
    edges[-1, -1] = True
    model = EnergyModel(require_edge=True, edge_radius=radius)
    to = machine.to_device
    Lattice(machine, to(np.zeros((4, 4), np.float32)), None, to(np.ones((4, 4), np.uint8)), "smooth", model)
    began = time.perf_counter()  # the kernels are built: what is left is the work
    lattice = Lattice(machine, to(np.zeros(shape, np.float32)), None, to(edges.astype(np.uint8)), "smooth", model)
    lattice.bh.get()
    on_device = time.perf_counter() - began
    began = time.perf_counter()
    b_h, _ = line_costs(shape, edges, model)
    on_host = time.perf_counter() - began
    # Scanning each site's square took (2 r + 1)^2 looks per site (tens of seconds here, the device and
    # the host alike); the two passes take milliseconds.
    assert on_device < 3 and on_host < 3
    assert np.isfinite(b_h).all()


@pytest.mark.parametrize("shape, edge", [((40, 6), (20, 3)), ((6, 40), (3, 20)), ((6, 6), None)])
@pytest.mark.parametrize("radius", [5, 6, 8, 39, 40, 100])
def test_the_device_agrees_with_the_host_on_rectangles_and_fields_without_edges(shape, edge, radius, machine):
    # A row without an edge pixel took the row's width for its distance, which a radius of that width or
    # more accepted: the device then allowed lines the host forbids.
    edges = np.zeros(shape, bool)
    if edge is not None:
        edges[edge] = True
    model = EnergyModel(require_edge=True, edge_radius=radius)
    lattice = Lattice(machine, machine.to_device(np.zeros(shape, np.float32)), None,
                      machine.to_device(edges.astype(np.uint8)), "smooth", model)
    b_h, b_v = line_costs(shape, edges, model)
    np.testing.assert_array_equal(lattice.bh.get().reshape(shape)[:, :-1], b_h.astype(np.float32))
    np.testing.assert_array_equal(lattice.bv.get().reshape(shape)[:-1, :], b_v.astype(np.float32))


def test_a_radius_beyond_the_field_reaches_every_pixel():
    edges = np.zeros((30, 50), bool)
    edges[0, 0] = True
    for radius in (49, 50, 10**6):
        b_h, b_v = line_costs(edges.shape, edges, EnergyModel(require_edge=True, edge_radius=radius))
        assert np.isfinite(b_h).all() and np.isfinite(b_v).all()
    # A site is forbidden only where both its pixels lie beyond the radius: the last column's, at 48 and 49.
    b_h, _ = line_costs(edges.shape, edges, EnergyModel(require_edge=True, edge_radius=47))
    assert np.flatnonzero(~np.isfinite(b_h).all(axis=0)).tolist() == [48]


# ------------------------------------------------------------------------------------------------ levels

@pytest.mark.parametrize("given", [np.array([0.0, 1.0]), [0, 1], (0.0, 1.0), np.array([0, 1], np.int64)])
def test_levels_given_as_any_sequence_are_a_hashable_tuple_of_floats(given):
    model = EnergyModel(levels=given)
    assert model.levels == (0.0, 1.0) and all(type(level) is float for level in model.levels)
    assert hash(model) == hash(EnergyModel(levels=(0.0, 1.0)))
    assert mrf.Settings().override({"levels": given}).model == model


@pytest.mark.parametrize("given, error", [(np.ma.masked_equal([0.0, 1.0, 2.0], 1.0), InputValueError),
                                          (np.array([[0.0, 1.0]]), InputValueError),
                                          (np.array(["a", "b"]), InputValueError)])
def test_bad_level_sequences_are_refused(given, error):
    with pytest.raises(error, match="levels"):
        EnergyModel(levels=given)


def test_levels_as_a_count_stay_an_int():
    assert EnergyModel(levels=np.int64(8)).levels == 8 and type(EnergyModel(levels=np.int64(8)).levels) is int
