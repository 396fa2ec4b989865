"""Measured settings per cue: the energy model and every solver's schedule (seed section "Organization
of integration": depth, motion, colour and texture are each restored by an MRF coupled to brightness
edges). The cues are named as :data:`vmcl.labels.CUES` names them: "stereo" restores the disparity,
"motion" the optical flow, "colour" the hue and "texture" the texton density.

Which schedule each solver gets:

- "meanfield" and "anneal": the measured schedules below. They are long: the anneal schedules are 600
  (stereo), 300 (motion) and 400 (colour, texture) heat-bath sweeps plus 10 ICM sweeps, the mean-field
  ones 40 x 5, 20 x 5 and 30 x 5 sweeps plus 10. Choosing method "anneal" runs exactly these 610, 310 or
  410 sweeps unless the caller overrides ``sweeps``, ``t0``, ``t_factor`` or ``quench``. A pipeline's
  shorter "fast" schedule (vmcl.pipeline) is a set of overrides applied on top of these: it shortens
  mean field, and its ``quench`` also sets annealing's (the one key the two share, see
  :meth:`Settings.override`), so "anneal" keeps its long schedule under it, less 8 quench sweeps.
- "mpm" and "icm": the schedule classes' defaults (50 + 100 sweeps at T = 1; 30 ICM sweeps), not
  measured per cue.

How each was chosen (tests/test_mrf_quality.py holds the scenes; the choices come from one grid run):

- ``STEREO`` (disparity in pixels, sparse matches): on a 96 x 96 piecewise-planar disparity map (three
  slanted planes, jumps of 3 to 8 px) with 10% of the pixels kept and noise sigma 0.3 px, mean field over
  alpha in {1, 2, 4}, beta in {1, 1.5, 2, 3}, edge_gain in {0.5, 0.75, 0.9, 1}, T0 in {2, 4, 8} and two
  schedules, on two to three noise seeds; kept the setting with the best worst-seed discontinuity F
  (within 1 px) with brightness edges, which found nearly all discontinuities and kept the disparity's bad-1
  rate low; without the edges its F was clearly lower. Annealing's schedule: T0 in {0.5, 1, 2, 4, 8}
  tried on the same data, lower final energy from T0 = 0.5 to 1 (from T0 >= 4 the sampler freezes in
  states with many lines, since a pixel with no data inside four lines has no restoring force); mean
  field reached lower energies.
- ``MOTION`` (flow in pixels, dense and noisy, both components sharing one line process): on the same map
  dense with noise sigma 1 px, alpha in {0.25, 0.5}, beta in {4, 8}, mean-field T0 in {0.5, 1, 2, 4}:
  alpha = 0.5, beta = 4, T0 = 2 found the discontinuities (nearly every one, and nearly nothing else,
  within 1 px) with the RMS error a fraction of the input noise's, and every edge of a moving square in
  a 48 x 48 flow field with noise sigma 0.7 px per component. T0 = 4 lost the square's edges (its soft
  lines let f blur the jump).
- ``COLOUR`` and ``TEXTURE`` (hue and texton density in [0, 1], piecewise constant): the constant kind
  tried on a 64 x 64 image of four levels one unit apart with noise sigma 0.5 (SNR 2), where alpha = 2,
  beta = 1.5, kappa = 4 found nearly every level boundary and little else and restored the levels to
  well within the noise; carried to [0, 1] units by alpha = 1 / (2 sigma^2) for a typical noise sigma of
  0.05 (the energy's other terms do not depend on the data's units). Not yet measured on the colour and
  texture modules' own outputs (their issues).
"""

from __future__ import annotations

from vmcl.cm.core import check_choice
from vmcl.mrf.energy import EnergyModel
from vmcl.mrf.icm import IcmSchedule
from vmcl.mrf.meanfield import MeanFieldSchedule
from vmcl.mrf.sampler import AnnealSchedule, MpmSchedule
from vmcl.mrf.settings import Settings

__all__ = ["COLOUR", "MOTION", "PRESETS", "STEREO", "TEXTURE", "preset"]

STEREO = Settings(EnergyModel(alpha=1.0, beta=2.0, edge_gain=0.75),
                  {"anneal": AnnealSchedule(t0=1.0, t_factor=0.99, sweeps=600, quench=10),
                   "mpm": MpmSchedule(),
                   "meanfield": MeanFieldSchedule(mf_t0=8.0, mf_factor=0.9, mf_steps=40, mf_iterations=5, quench=10),
                   "icm": IcmSchedule()})
MOTION = Settings(EnergyModel(alpha=0.5, beta=4.0),
                  {"anneal": AnnealSchedule(t0=4.0, t_factor=0.98, sweeps=300, quench=10),
                   "mpm": MpmSchedule(),
                   "meanfield": MeanFieldSchedule(mf_t0=2.0, mf_factor=0.8, mf_steps=20, mf_iterations=5, quench=10),
                   "icm": IcmSchedule()})
COLOUR = Settings(EnergyModel(alpha=200.0, beta=1.5, kappa=4.0, levels=8),
                  {"anneal": AnnealSchedule(t0=2.0, t_factor=0.985, sweeps=400, quench=10),
                   "mpm": MpmSchedule(),
                   "meanfield": MeanFieldSchedule(mf_t0=2.0, mf_factor=0.9, mf_steps=30, mf_iterations=5, quench=10),
                   "icm": IcmSchedule()})
TEXTURE = COLOUR

PRESETS = {"stereo": STEREO, "motion": MOTION, "colour": COLOUR, "texture": TEXTURE}


def preset(cue: str) -> Settings:
    """The measured :class:`Settings` of a cue: "stereo", "motion", "colour" or "texture".

    Apply a user's flat overrides with :meth:`Settings.override`, e.g.
    ``preset("stereo").override({"beta": 3.0}, prefix="mrf.stereo")``.
    """
    return PRESETS[check_choice(cue, "cue", PRESETS)]
