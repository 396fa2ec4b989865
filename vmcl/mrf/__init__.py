"""Line-process Markov Random Fields: the integration stage of the Vision Machine.

Seed sections "The integration stage and MRF", "MRF models", "Organization of integration" and
"Algorithms: Deterministic and stochastic". :func:`restore` restores a cue (stereo disparity, motion
flow, colour, texture) as piecewise smooth or piecewise constant and finds its discontinuities at once,
helped by brightness edges; :func:`energy` evaluates the energy of any configuration on the host;
:func:`score_confidence`, :func:`mask_confidence` and :func:`backfill` make its data and confidence from the early modules'
measurements; :func:`sample` draws a configuration at a fixed temperature (the Gibbs sampler held there).

What a restoration is told comes in two halves: the energy (:class:`EnergyModel`, with its
:class:`LinePrior`) and the schedule of the chosen solver. :data:`SOLVERS` registers the solvers by
name, each with its schedule class (:class:`AnnealSchedule`, :class:`MpmSchedule`,
:class:`MeanFieldSchedule`, :class:`IcmSchedule`). :class:`Settings` holds a model and one schedule
per solver; :func:`preset` gives the measured Settings of each cue and :meth:`Settings.override` applies
a user's flat overrides to them::

    settings = preset("stereo").override({"beta": 3.0, "mf_steps": 6}, prefix="mrf.stereo")
    found = restore(data, method="meanfield", model=settings.model, schedule=settings.schedule("meanfield"))

:class:`NothingToRestore` is the refusal of data with no value to restore, caught by type.
"""

from vmcl.mrf.data import backfill, mask_confidence, score_confidence
from vmcl.mrf.draw import sample
from vmcl.mrf.energy import EnergyModel, LinePrior, energy
from vmcl.mrf.icm import IcmSchedule
from vmcl.mrf.meanfield import MeanFieldSchedule
from vmcl.mrf.presets import preset
from vmcl.mrf.restore import NothingToRestore, Restoration, boundary_map, restore
from vmcl.mrf.sampler import AnnealSchedule, MpmSchedule
from vmcl.mrf.settings import Settings
from vmcl.mrf.solvers import SOLVERS

__all__ = ["SOLVERS", "AnnealSchedule", "EnergyModel", "IcmSchedule", "LinePrior", "MeanFieldSchedule",
           "MpmSchedule", "NothingToRestore", "Restoration", "Settings", "backfill", "boundary_map", "energy",
           "mask_confidence", "preset", "restore", "sample", "score_confidence"]
