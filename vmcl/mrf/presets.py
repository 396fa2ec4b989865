"""Measured parameters per cue (seed section "Organization of integration": depth, motion, colour and
texture are each restored by an MRF coupled to brightness edges).

How each was chosen (tests/test_mrf_quality.py holds the scenes; the figures are from one grid run):

- ``DEPTH`` (disparity in pixels, sparse matches): on a 96 x 96 piecewise-planar disparity map (three
  slanted planes, jumps of 3 to 8 px) with 10% of the pixels kept and noise sigma 0.3 px, mean field over
  alpha in {1, 2, 4}, beta in {1, 1.5, 2, 3}, edge_gain in {0.5, 0.75, 0.9, 1}, T0 in {2, 4, 8} and two
  schedules, on two to three noise seeds; kept the setting with the best worst-seed discontinuity F with
  brightness edges: recall 0.94 to 0.98 within 1 px, F 0.91 to 0.96 (0.65 to 0.84 without edges),
  bad-1 rate 1.0% to 1.4%. Annealing's schedule: T0 in {0.5, 1, 2, 4, 8} tried on the same data, lower
  final energy from T0 = 0.5 to 1 (from T0 >= 4 the sampler freezes in states with many lines, since a
  pixel with no data inside four lines has no restoring force); mean field reached lower energies.
- ``FLOW`` (flow in pixels, dense and noisy, both components sharing one line process): on the same map
  dense with noise sigma 1 px, alpha in {0.25, 0.5}, beta in {4, 8}, mean-field T0 in {0.5, 1, 2, 4}:
  alpha = 0.5, beta = 4, T0 = 2 found every discontinuity (precision and recall >= 0.99 within 1 px)
  with RMS error 0.22 px (input 1.0 px), and every edge of a moving square in a 48 x 48 flow field with
  noise sigma 0.7 px per component. T0 = 4 lost the square's edges (its soft lines let f blur the jump).
- ``COLOUR`` and ``TEXTURE`` (hue and texton density in [0, 1], piecewise constant): the constant kind
  measured on a 64 x 64 image of four levels one unit apart with noise sigma 0.5 (SNR 2: precision and
  recall >= 0.96, RMS error 0.07 to 0.11) with alpha = 2, beta = 1.5, kappa = 4; carried to [0, 1] units by
  alpha = 1 / (2 sigma^2) for a typical noise sigma of 0.05 (the energy's other terms do not depend on
  the data's units). Not yet measured on the colour and texture modules' own outputs (their issues).
"""

from __future__ import annotations

from vmcl.cm._arrays import check_choice
from vmcl.mrf.energy import Params

DEPTH = Params(alpha=1.0, beta=2.0, edge_gain=0.75, mf_t0=8.0, mf_factor=0.9, mf_steps=40, mf_iterations=5,
               t0=1.0, t_factor=0.99, sweeps=600)
FLOW = Params(alpha=0.5, beta=4.0, mf_t0=2.0, mf_factor=0.8, mf_steps=20, mf_iterations=5, t0=4.0,
              t_factor=0.98, sweeps=300)
COLOUR = Params(alpha=200.0, beta=1.5, kappa=4.0, levels=8, t0=2.0, t_factor=0.985, sweeps=400, mf_t0=2.0,
                mf_factor=0.9, mf_steps=30, mf_iterations=5)
TEXTURE = COLOUR

PRESETS = {"depth": DEPTH, "flow": FLOW, "colour": COLOUR, "texture": TEXTURE}


def preset(cue: str) -> Params:
    """The measured Params of a cue: "depth", "flow", "colour" or "texture"."""
    return PRESETS[check_choice(cue, "cue", PRESETS)]
