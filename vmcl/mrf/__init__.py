"""Line-process Markov Random Fields: the integration stage of the Vision Machine.

Seed sections "The integration stage and MRF", "MRF models", "Organization of integration" and
"Algorithms: Deterministic and stochastic". :func:`restore` restores a cue (depth, flow, colour, texture)
as piecewise smooth or piecewise constant and finds its discontinuities at once, helped by brightness
edges; :func:`energy` evaluates the energy of any configuration on the host; :func:`score_confidence`
and :func:`backfill` make its data and confidence from the early modules' measurements.
"""

from vmcl.mrf.data import backfill, score_confidence
from vmcl.mrf.energy import LinePrior, Params, energy
from vmcl.mrf.presets import preset
from vmcl.mrf.restore import Restoration, boundary_map, restore

__all__ = ["LinePrior", "Params", "Restoration", "backfill", "boundary_map", "energy", "preset", "restore",
           "score_confidence"]
