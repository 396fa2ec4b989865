"""Learning the machine's parameters from examples and from the data (seed section "Learning and
parameter estimation").

:func:`fit_pseudolikelihood` estimates the line-process MRF's parameters from examples whose desired
solution is given (Besag's maximum pseudolikelihood, on the device).
"""

from vmcl.learn.pseudolikelihood import PARAMETERS, Example, PseudolikelihoodFit, fit_pseudolikelihood

__all__ = ["PARAMETERS", "Example", "PseudolikelihoodFit", "fit_pseudolikelihood"]
