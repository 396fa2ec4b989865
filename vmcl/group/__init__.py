"""Grouping (seed section "Saliency, grouping, and segmentation"): edge pixels linked into curves on the
machine (:mod:`~vmcl.group.curves`), local saliency (:mod:`~vmcl.group.local_saliency`, after Beymer) and
structural saliency (:mod:`~vmcl.group.structural_saliency`, Sha'ashua and Ullman), junctions found,
classified and repaired, and curves grouped across pairs of T-junctions (:mod:`~vmcl.group.junctions`);
:func:`group` runs them all (:mod:`~vmcl.group.grouping`).
"""

from vmcl.group.curves import BRANCH, Curve, Curves, link_edges
from vmcl.group.grouping import Grouping, group
from vmcl.group.junctions import KINDS, Junctions, find_junctions, group_curves, repair_edges
from vmcl.group.local_saliency import local_saliency, saliency_map, salient_edges
from vmcl.group.structural_saliency import StructuralSaliency, saliency_strength, structural_saliency

__all__ = ["BRANCH", "KINDS", "Curve", "Curves", "Grouping", "Junctions", "StructuralSaliency", "find_junctions",
           "group", "group_curves", "link_edges", "local_saliency", "repair_edges", "saliency_map", "saliency_strength",
           "salient_edges", "structural_saliency"]
