"""The Connection Machine primitives as OpenCL kernel families.

Seed section "Powerful primitive operations": NEWS communication (:mod:`news`), the router (:mod:`router`),
scans and grid-scans (:mod:`scan`), distance doubling (:mod:`doubling`), global reductions and histograms
(:mod:`reduce`) and the binomial Gaussian of "Zero-crossings" (:mod:`filters`). :mod:`core` holds the
argument checks and kernel launches that these and the early layer (:mod:`vmcl.early`) share.
"""

from vmcl.cm import core, doubling, filters, news, reduce, router, scan

__all__ = ["core", "doubling", "filters", "news", "reduce", "router", "scan"]
