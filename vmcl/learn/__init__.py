"""Learning the machine's parameters from examples and from the data (seed section "Learning and
parameter estimation").

From examples whose desired solution is given: :func:`fit_pseudolikelihood` estimates the line-process
MRF's parameters by Besag's maximum pseudolikelihood, on the device. From the data alone:
:func:`cross_validate` chooses a cue's smoothing weight by held-out measurements, :func:`estimate_noise`
the measurements' noise by stochastic EM, and :func:`scan_temperature` the MPM temperature away from the
phase transition. :func:`fit_restoration` fits the same parameters to the error of the machine's own
restorations of the examples (discriminative, where pseudolikelihood fits the model to them).
"""

from vmcl.learn.cross_validation import CrossValidation, cross_validate
from vmcl.learn.noise import NoiseEstimate, estimate_noise
from vmcl.learn.pseudolikelihood import (
                                         PARAMETERS,
                                         Example,
                                         Pseudolikelihood,
                                         PseudolikelihoodFit,
                                         fit_pseudolikelihood,
                                         model_overrides,
)
from vmcl.learn.restoration_fit import RestorationFit, fit_restoration, restoration_error
from vmcl.learn.temperature import TemperatureScan, scan_temperature

__all__ = ["PARAMETERS", "CrossValidation", "Example", "NoiseEstimate", "Pseudolikelihood", "PseudolikelihoodFit",
           "RestorationFit", "TemperatureScan",
           "cross_validate", "estimate_noise", "fit_pseudolikelihood", "fit_restoration", "model_overrides",
           "restoration_error",
           "scan_temperature"]
