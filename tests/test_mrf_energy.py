"""The kernel's energy equals the NumPy energy; the clique table; bad input is named."""

import numpy as np
import pytest

from vmcl import mrf
from vmcl.errors import InputError
from vmcl.mrf.energy import EnergyModel, LinePrior, line_costs
from vmcl.mrf.lattice import Lattice


def _padded(line, shape):
    out = np.zeros(shape, np.float32)
    out[:line.shape[0], :line.shape[1]] = line
    return out.ravel()


def _lattice(machine, data, confidence, edges, kind, model):
    to = machine.to_device
    return Lattice(machine, to(data.astype(np.float32)),
                   None if confidence is None else to(confidence.astype(np.float32)),
                   None if edges is None else to(edges.astype(np.uint8)), kind, model)


CASES = [  # (shape, kind, with confidence, with edges, require_edge)
    ((9, 13), "smooth", False, False, False),
    ((16, 11), "smooth", True, True, False),
    ((8, 8, 2), "smooth", True, True, True),
    ((12, 10), "constant", True, True, False),
    ((2, 2), "smooth", False, False, False),
]


@pytest.mark.parametrize("shape, kind, with_confidence, with_edges, require", CASES, ids=str)
def test_kernel_energy_equals_numpy(shape, kind, with_confidence, with_edges, require, machine):
    rng = np.random.default_rng(sum(shape))
    height, width = shape[:2]
    model = EnergyModel(alpha=0.7, beta=1.3, kappa=2.0, levels=(0.0, 1.0, 2.5),
                        prior=LinePrior(line=1.0, end=0.4, continuation=0.1, turn=0.3, junction=0.8, crossing=1.7,
                                        parallel=0.9),
                        edge_gain=0.6, require_edge=require, edge_radius=1)
    data = rng.normal(0, 2, shape).astype(np.float32)
    data[rng.random(shape[:2]) < 0.2] = np.nan
    confidence = rng.random((height, width)) if with_confidence else None
    edges = rng.random((height, width)) < (0.04 if require else 0.3) if with_edges else None
    lattice = _lattice(machine, data, confidence, edges, kind, model)
    b_h, b_v = line_costs((height, width), edges, model)
    for trial in range(5):
        if kind == "constant":
            f = rng.choice(np.float32([0.0, 1.0, 2.5]), shape)
        else:
            f = rng.normal(0, 2, shape).astype(np.float32)
        # Lines only where allowed: a forbidden line on gives +inf, checked below.
        line_h = (rng.random((height, width - 1)) < 0.4) & np.isfinite(b_h)
        line_v = (rng.random((height - 1, width)) < 0.4) & np.isfinite(b_v)
        lattice.f.set(f)
        lattice.lh.set(_padded(line_h, (height, width)))
        lattice.lv.set(_padded(line_v, (height, width)))
        expected = mrf.energy(f, line_h, line_v, data=data, confidence=confidence, edges=edges, kind=kind,
                              model=model)
        assert lattice.energy() == pytest.approx(expected, rel=2e-5, abs=1e-4), trial
    if require:
        forbidden = ~np.isfinite(b_h)
        assert forbidden.any()
        assert mrf.energy(f, line_h | forbidden, line_v, data=data, confidence=confidence, edges=edges,
                          model=model) == np.inf


def test_vertex_table_classes():
    prior = LinePrior(end=1, continuation=2, turn=3, junction=4, crossing=5)
    table = prior.table()
    up, down, left, right = 1, 2, 4, 8
    assert table[0] == 0
    assert [table[a] for a in (up, down, left, right)] == [1] * 4
    assert table[up | down] == table[left | right] == 2
    assert [table[a] for a in (up | left, up | right, down | left, down | right)] == [3] * 4
    assert [table[15 ^ a] for a in (up, down, left, right)] == [4] * 4
    assert table[15] == 5


def test_edges_lower_and_forbid_line_costs():
    edges = np.zeros((5, 6), bool)
    edges[2, 3] = True
    model = EnergyModel(beta=2.0, edge_gain=0.25, require_edge=True, edge_radius=1)
    b_h, b_v = line_costs((5, 6), edges, model)
    assert b_h[2, 2] == b_h[2, 3] == b_v[1, 3] == b_v[2, 3] == 2.0 * 0.75
    assert b_h[1, 1] == 2.0  # no edge on either side, one within the radius
    assert b_h[0, 0] == np.inf and b_v[4 - 1, 0] == np.inf


@pytest.mark.parametrize("kwargs, error, match", [
    ({"data": np.zeros(5)}, ValueError, "data must have 2 or 3 dimensions"),
    ({"data": np.zeros((1, 5))}, ValueError, "at least 2 x 2"),
    ({"data": np.zeros((4, 4, 5))}, ValueError, "C in 1..4"),
    ({"data": np.zeros((4, 4), complex)}, TypeError, "data must be a real array"),
    ({"data": np.zeros((4, 4)), "confidence": np.ones((4, 5))}, ValueError, "confidence must have"),
    ({"data": np.zeros((4, 4)), "confidence": -np.ones((4, 4))}, ValueError, "confidence must be finite"),
    ({"data": np.zeros((4, 4)), "edges": np.ones((4, 4), np.float32)}, TypeError, "edges must be boolean"),
    ({"data": np.zeros((4, 4)), "kind": "plate"}, ValueError, "kind must be"),
    ({"data": np.zeros((4, 4)), "method": "sa"}, ValueError, "method must be one of .*'meanfield', 'icm'"),
    ({"data": np.zeros((4, 4)), "seed": -1}, ValueError, "seed must be"),
    ({"data": np.zeros((4, 4)), "model": {"alpha": 1}}, TypeError, "model must be"),
    ({"data": np.zeros((4, 4)), "method": "icm", "schedule": mrf.MpmSchedule()}, TypeError,
     "schedule must be a vmcl.mrf.IcmSchedule"),
    ({"data": np.zeros((4, 4)), "model": EnergyModel(alpha=0.0)}, ValueError, "model.alpha must be > 0"),
    ({"data": np.zeros((4, 4, 2)), "kind": "constant"}, ValueError, "scalar data"),
    ({"data": np.full((4, 4), np.nan)}, mrf.NothingToRestore, "no value"),
    ({"data": np.zeros((4, 4)), "confidence": np.zeros((4, 4))}, mrf.NothingToRestore, "no value"),
])
def test_bad_input_is_named(kwargs, error, match, machine):
    with pytest.raises(error, match=match):
        mrf.restore(machine=machine, **kwargs)


@pytest.mark.parametrize("settings, kwargs, error, match", [
    (EnergyModel, {"alpha": -1.0}, ValueError, "EnergyModel.alpha must be a finite number >= 0"),
    (mrf.AnnealSchedule, {"t0": 0.0}, ValueError, "AnnealSchedule.t0 must be a finite number > 0"),
    # Temperatures fall: a cooling factor above 1 is refused.
    (mrf.AnnealSchedule, {"t_factor": 1.5}, ValueError, "t_factor must be a finite number <= 1 and > 0"),
    (mrf.MeanFieldSchedule, {"mf_factor": 1.5}, ValueError, "mf_factor must be a finite number <= 1 and > 0"),
    (mrf.MpmSchedule, {"mpm_temperature": 0}, ValueError, "MpmSchedule.mpm_temperature must be a finite number > 0"),
    # A float where a count belongs is a wrong type, as everywhere in vmcl (vmcl.errors).
    (mrf.AnnealSchedule, {"sweeps": 2.5}, TypeError, "AnnealSchedule.sweeps must be an integer"),
    (mrf.AnnealSchedule, {"sweeps": 2**40}, ValueError, "sweeps must be <= 2147483647"),
    (mrf.IcmSchedule, {"icm_sweeps": -1}, ValueError, "IcmSchedule.icm_sweeps must be >= 0"),
    (EnergyModel, {"require_edge": 1}, TypeError, "require_edge must be a bool"),
    (EnergyModel, {"prior": {"line": 1.0}}, TypeError, "EnergyModel.prior must be a vmcl.mrf.LinePrior"),
    (EnergyModel, {"levels": 1}, ValueError, "levels must be a count"),
    (EnergyModel, {"levels": (1.0, 1.0)}, ValueError, "distinct"),
    (EnergyModel, {"levels": "32"}, ValueError, "levels must be a count"),
    (EnergyModel, {"levels": None}, ValueError, "levels must be a count"),
    (EnergyModel, {"beta": float("nan")}, ValueError, "beta must be a finite number"),
    (EnergyModel, {"beta": 10**400}, ValueError, "beta must be a finite number"),
    (LinePrior, {"end": float("inf")}, ValueError, "LinePrior.end must be a finite number"),
])
def test_bad_settings_are_named(settings, kwargs, error, match):
    with pytest.raises(error, match=match) as raised:
        settings(**kwargs)
    assert isinstance(raised.value, InputError)


_G = np.zeros((4, 5))
_LH, _LV = np.zeros((4, 4), bool), np.zeros((3, 5), bool)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"f": _G.astype(complex)}, TypeError, "f must hold real numbers"),
    ({"data": _G.astype(object)}, TypeError, "data must hold real numbers"),
    ({"line_h": _LH.astype("<U1")}, TypeError, "line_h must hold real numbers"),
    ({"f": [[0.0] * 5] * 4}, TypeError, "f must be a NumPy array"),
    ({"f": np.full((4, 5), np.nan)}, ValueError, "f must be finite"),
    ({"f": np.zeros(5), "data": np.zeros(5)}, ValueError, "data must have 2 or 3 dimensions"),
    ({"f": np.zeros((0, 5)), "data": np.zeros((0, 5))}, ValueError, "data must not be empty"),
    ({"confidence": np.ones((0, 5))}, ValueError, "confidence must not be empty"),
    ({"confidence": np.ones((4, 4))}, ValueError, "confidence must have the field's shape"),
    ({"confidence": -np.ones((4, 5))}, ValueError, "confidence must be finite and >= 0"),
    ({"edges": np.ones((4, 5), complex)}, TypeError, "edges must hold real numbers"),
    ({"edges": np.ones((5, 4))}, ValueError, "edges must have the field's shape"),
    ({"kind": ["smooth"]}, TypeError, "kind must be one of"),
    ({"model": {"alpha": 1}}, TypeError, "model must be"),
])
def test_energy_refuses_bad_input_by_name(kwargs, error, match):
    call = {"f": _G, "line_h": _LH, "line_v": _LV, "data": _G, **kwargs}
    with pytest.raises(error, match=match) as raised:
        mrf.energy(call.pop("f"), call.pop("line_h"), call.pop("line_v"), **call)
    assert isinstance(raised.value, InputError)


def test_energy_of_device_arrays_and_of_a_radius_beyond_the_image(machine):
    rng = np.random.default_rng(3)
    f, data = rng.random((5, 6)), rng.random((5, 6))
    line_h, line_v = rng.random((5, 5)) < 0.3, rng.random((4, 6)) < 0.3
    edges = np.zeros((5, 6), bool)
    edges[2, 3] = True
    wide = EnergyModel(require_edge=True, edge_radius=6)
    expected = mrf.energy(f, line_h, line_v, data=data, edges=edges, model=wide)
    on_device = [machine.to_device(a.astype(np.float32)) for a in (f, data)]
    lines = [machine.to_device(a.astype(np.uint8)) for a in (line_h, line_v)]
    got = mrf.energy(on_device[0], *lines, data=on_device[1], edges=machine.to_device(edges.astype(np.uint8)),
                     model=wide)
    assert got == pytest.approx(expected, rel=1e-6)
    # A radius wider than the image marks the same pixels (it once allocated a (2r + H) x (2r + W) mask).
    huge = EnergyModel(require_edge=True, edge_radius=2**31 - 1)
    assert mrf.energy(f, line_h, line_v, data=data, edges=edges, model=huge) == expected


def test_boundary_map_takes_device_lines_and_names_bad_ones(machine):
    line_h = np.zeros((3, 3), bool)
    line_h[1, 0] = True
    line_v = np.zeros((2, 4), bool)
    line_v[0, 3] = True
    expected = np.zeros((3, 4), bool)
    expected[1, 0] = expected[0, 3] = True
    assert np.array_equal(mrf.boundary_map(line_h, line_v), expected)
    device = mrf.boundary_map(machine.to_device(line_h.view(np.uint8)), machine.to_device(line_v.view(np.uint8)))
    assert np.array_equal(device, expected)
    for bad, error, match in ((line_h.astype(complex), TypeError, "line_h must hold real numbers"),
                              (None, TypeError, "line_h must be a NumPy array"),
                              (np.zeros(3, bool), ValueError, "line_h must have 2 dimensions"),
                              (np.zeros((2, 3), bool), ValueError, "line_h must have shape"),
                              (np.zeros((3, 1), bool), ValueError, "line_h must have shape")):
        with pytest.raises(error, match=match) as raised:
            mrf.boundary_map(bad, line_v)
        assert isinstance(raised.value, InputError)


# The cues are named as vmcl.labels names them: the old "depth" and "flow" are refused.
@pytest.mark.parametrize("cue, error", [(["stereo"], TypeError), (None, TypeError), ("depth", ValueError),
                                        ("flow", ValueError)])
def test_preset_names_a_bad_cue(cue, error):
    with pytest.raises(error, match="cue must be one of") as raised:
        mrf.preset(cue)
    assert isinstance(raised.value, InputError)
