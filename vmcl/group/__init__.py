"""Grouping (seed section "Saliency, grouping, and segmentation"): edge pixels linked into curves on the
machine (:mod:`~vmcl.group.curves`), local saliency (:mod:`~vmcl.group.local_saliency`, Beymer) and
structural saliency (:mod:`~vmcl.group.structural_saliency`, Sha'ashua and Ullman), T-junctions found,
classified and repaired (:mod:`~vmcl.group.junctions`), and curves grouped across pairs of T-junctions.
"""

from vmcl.group.curves import BRANCH, Curve, Curves, link_edges

__all__ = ["BRANCH", "Curve", "Curves", "link_edges"]
