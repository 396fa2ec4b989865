"""The energy model apart from the solvers' schedules: the registry, the presets and flat overrides."""

import dataclasses
from typing import ClassVar

import numpy as np
import pytest

from vmcl import mrf
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.labels import CUES
from vmcl.mrf import presets
from vmcl.mrf.checks import check_count, check_fields
from vmcl.mrf.icm import quench
from vmcl.mrf.solvers import Solver


def test_every_registered_solver_has_a_schedule_with_usable_defaults():
    assert tuple(mrf.SOLVERS) == ("anneal", "mpm", "meanfield", "icm")
    settings = mrf.Settings()
    assert tuple(settings.schedules) == tuple(mrf.SOLVERS)
    for method, solver in mrf.SOLVERS.items():
        assert settings.schedule(method) == solver.schedule()


def test_presets_are_keyed_by_cue_and_keep_their_measured_numbers():
    assert tuple(presets.PRESETS) == CUES == ("stereo", "motion", "colour", "texture")
    stereo, motion, colour = mrf.preset("stereo"), mrf.preset("motion"), mrf.preset("colour")
    assert stereo.model == mrf.EnergyModel(alpha=1.0, beta=2.0, edge_gain=0.75)
    assert stereo.schedule("anneal") == mrf.AnnealSchedule(t0=1.0, t_factor=0.99, sweeps=600, quench=10)
    assert stereo.schedule("meanfield") == mrf.MeanFieldSchedule(mf_t0=8.0, mf_factor=0.9, mf_steps=40,
                                                                 mf_iterations=5, quench=10)
    assert motion.model == mrf.EnergyModel(alpha=0.5, beta=4.0)
    assert motion.schedule("anneal") == mrf.AnnealSchedule(t0=4.0, t_factor=0.98, sweeps=300)
    assert motion.schedule("meanfield") == mrf.MeanFieldSchedule(mf_t0=2.0, mf_factor=0.8, mf_steps=20,
                                                                 mf_iterations=5)
    assert colour.model == mrf.EnergyModel(alpha=200.0, beta=1.5, kappa=4.0, levels=8)
    assert colour.schedule("anneal") == mrf.AnnealSchedule(t0=2.0, t_factor=0.985, sweeps=400)
    assert colour.schedule("meanfield") == mrf.MeanFieldSchedule(mf_t0=2.0, mf_factor=0.9, mf_steps=30,
                                                                 mf_iterations=5)
    assert mrf.preset("texture") == colour
    for settings in (stereo, motion, colour):  # not measured per cue: the classes' defaults
        assert settings.schedule("mpm") == mrf.MpmSchedule() and settings.schedule("icm") == mrf.IcmSchedule()


def test_override_sets_fields_by_flat_name_and_leaves_the_preset_alone():
    stereo = mrf.preset("stereo")
    changed = stereo.override({"beta": 3.0, "mf_steps": 6, "quench": 2, "icm_sweeps": 4, "burn_in": 1})
    assert changed.model == dataclasses.replace(stereo.model, beta=3.0)
    assert changed.schedule("meanfield") == dataclasses.replace(stereo.schedule("meanfield"), mf_steps=6, quench=2)
    # quench names a field of two schedules: it sets both.
    assert changed.schedule("anneal") == dataclasses.replace(stereo.schedule("anneal"), quench=2)
    assert changed.schedule("icm").icm_sweeps == 4 and changed.schedule("mpm").burn_in == 1
    assert mrf.preset("stereo") == stereo and stereo.model.beta == 2.0
    assert stereo.override({}) == stereo
    assert set(mrf.Settings.override_keys()) == {
        "alpha", "beta", "prior", "kappa", "levels", "edge_gain", "require_edge", "edge_radius", "t0", "t_factor",
        "sweeps", "quench", "mpm_temperature", "burn_in", "samples", "mf_t0", "mf_factor", "mf_steps",
        "mf_iterations", "icm_sweeps"}


@pytest.mark.parametrize("overrides, prefix, error, match", [
    ({"betta": 1.0}, "mrf.stereo", InputValueError, r"unknown key mrf\.stereo\.betta; the keys are alpha, beta"),
    ({"betta": 1.0}, None, InputValueError, "unknown key betta; the keys are"),
    ({"beta": "3"}, "mrf.stereo", InputTypeError, r"mrf\.stereo\.beta must be a real number"),
    ({"sweeps": 2.5}, "mrf.motion", InputTypeError, r"mrf\.motion\.sweeps must be an integer"),
    ({"quench": -1}, "mrf.colour", InputValueError, r"mrf\.colour\.quench must be >= 0"),
    ({"levels": 1}, "mrf.colour", InputValueError, r"mrf\.colour\.levels must be a count"),
    ({"require_edge": "yes"}, "mrf.texture", InputTypeError, r"mrf\.texture\.require_edge must be a bool"),
    ({"t_factor": 1.5}, None, InputValueError, r"AnnealSchedule\.t_factor must be a finite number <= 1"),
    ({"mf_t0": 0.0}, None, InputValueError, r"MeanFieldSchedule\.mf_t0 must be a finite number > 0"),
    ({1: 2}, "mrf.stereo", InputTypeError, "mrf.stereo must have str keys"),
    ([("beta", 1.0)], "mrf.stereo", InputTypeError, "mrf.stereo must be a mapping"),
])
def test_override_names_a_bad_key_or_value(overrides, prefix, error, match):
    with pytest.raises(error, match=match):
        mrf.preset("stereo").override(overrides, prefix=prefix)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"model": {"alpha": 1.0}}, InputTypeError, "Settings.model must be a vmcl.mrf.EnergyModel"),
    ({"schedules": [mrf.IcmSchedule()]}, InputTypeError, "Settings.schedules must be a mapping"),
    ({"schedules": {"gibbs": mrf.AnnealSchedule()}}, InputValueError, "a key of Settings.schedules must be one of"),
    ({"schedules": {"icm": mrf.MpmSchedule()}}, InputTypeError,
     r"Settings.schedules\['icm'\] must be a vmcl.mrf.IcmSchedule"),
])
def test_settings_refuse_a_schedule_of_another_solver(kwargs, error, match):
    with pytest.raises(error, match=match):
        mrf.Settings(**kwargs)


def test_restore_runs_the_schedule_it_is_given(machine):
    noisy = np.where(np.arange(12) < 6, 0.0, 4.0) * np.ones((10, 1))
    noisy = noisy + np.random.default_rng(0).normal(0, 0.3, noisy.shape)
    settings = mrf.preset("stereo").override({"sweeps": 5, "quench": 1, "mf_steps": 2, "mf_iterations": 3,
                                              "burn_in": 2, "samples": 3, "icm_sweeps": 4})
    sweeps = {method: mrf.restore(noisy, method=method, model=settings.model, schedule=settings.schedule(method),
                                  machine=machine).sweeps for method in mrf.SOLVERS}
    assert sweeps == {"anneal": 6, "mpm": 5, "meanfield": 7, "icm": 4}
    # Without a schedule, the method's defaults: never a preset's long anneal.
    assert mrf.restore(noisy, method="anneal", machine=machine).sweeps == 110
    with pytest.raises(InputValueError, match="method must be one of .*'anneal', 'mpm', 'meanfield', 'icm'"):
        mrf.restore(noisy, method="gibbs", machine=machine)


def test_nothing_to_restore_is_caught_by_type(machine):
    with pytest.raises(mrf.NothingToRestore, match="nothing to restore") as raised:
        mrf.restore(np.full((4, 4), np.nan), method="icm", machine=machine)
    assert isinstance(raised.value, InputValueError) and isinstance(raised.value, InputError)


@dataclasses.dataclass(frozen=True)
class _TwiceIcm:
    rounds: int = 2

    CHECKS: ClassVar = {"rounds": check_count}

    def __post_init__(self):
        check_fields(self)


def test_a_solver_is_one_registry_entry(machine, monkeypatch):
    monkeypatch.setitem(mrf.SOLVERS, "twice", Solver(lambda lattice, schedule, seed: quench(lattice, 2 * schedule.rounds),
                                                    _TwiceIcm))
    settings = mrf.preset("stereo").override({"rounds": 3}, prefix="mrf.stereo")
    assert settings.schedule("twice") == _TwiceIcm(3) and settings.model == mrf.preset("stereo").model
    noisy = np.random.default_rng(1).normal(0, 1, (8, 8))
    found = mrf.restore(noisy, method="twice", schedule=settings.schedule("twice"), machine=machine)
    assert found.sweeps == 6
    np.testing.assert_array_equal(found.field, mrf.restore(noisy, method="icm", schedule=mrf.IcmSchedule(6),
                                                          machine=machine).field)
    with pytest.raises(InputValueError, match=r"mrf\.stereo\.rounds must be >= 0"):
        mrf.preset("stereo").override({"rounds": -1}, prefix="mrf.stereo")


@dataclasses.dataclass(frozen=True)
class _UncheckedSchedule:
    quench: int = 3


def test_a_schedule_class_without_checks_is_taken(machine):
    # Built as vmcl.mrf.solvers describes, with no CHECKS: every Config() failed with an AttributeError once
    # it shared a field (quench) with the "fast" schedule's overrides.
    from vmcl.pipeline import Config

    mrf.SOLVERS["mine"] = Solver(lambda lattice, schedule, seed: quench(lattice, schedule.quench), _UncheckedSchedule)
    try:
        settings = Config().mrf.settings("stereo")
        assert settings.schedule("mine") == _UncheckedSchedule(2)  # the "fast" schedule's quench
        assert mrf.preset("stereo").override({"quench": 5}, prefix="mrf.stereo").schedule("mine").quench == 5
        noisy = np.random.default_rng(1).normal(0, 1, (8, 8))
        assert mrf.restore(noisy, method="mine", schedule=settings.schedule("mine"), machine=machine).sweeps == 2
    finally:
        del mrf.SOLVERS["mine"]
