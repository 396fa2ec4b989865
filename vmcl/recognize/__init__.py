"""Recognition: objects found in the machine's discontinuities by selection, indexing and verification.

Seed sections "Recognition" and "Learning in a three-stage recognition scheme". Models are learned from
example images (:func:`learn`, a :class:`Library` folder); :func:`recognize` finds them in an image, an
edge map or a Result's cartoon: regions ranked by saliency (:mod:`vmcl.recognize.selection`), candidate
poses from invariant keys of corner and arc pairs by geometric hashing (:mod:`vmcl.recognize.indexing`), each
candidate aligned and verified against the image's edges (:mod:`vmcl.recognize.verification`).
"""

from vmcl.recognize.features import Features, arcs_of, edge_features, features_of, image_features
from vmcl.recognize.indexing import (
                                         Candidates,
                                         Index,
                                         anchors_of,
                                         corner_pairs,
                                         index_for,
                                         pair_keys,
                                         vote,
                                         vote_numpy,
)
from vmcl.recognize.models import (
                                         MODEL_SUFFIX,
                                         Library,
                                         Model,
                                         View,
                                         learn,
                                         load_model,
                                         model_path,
                                         save_model,
                                         view_of,
)
from vmcl.recognize.recognition import SCALES, Detection, recognize
from vmcl.recognize.selection import Regions, corner_regions, select_regions
from vmcl.recognize.verification import (
                                         TRANSFORMS,
                                         NearestEdge,
                                         Support,
                                         Verified,
                                         carry,
                                         distance_transform,
                                         distance_transform_numpy,
                                         refine,
                                         support,
                                         support_numpy,
)

__all__ = ["MODEL_SUFFIX", "SCALES", "TRANSFORMS", "Candidates", "Detection", "Features", "Index", "Library", "Model",
           "NearestEdge", "Regions", "Support", "Verified", "View", "anchors_of", "arcs_of", "carry", "corner_pairs",
           "corner_regions", "distance_transform", "distance_transform_numpy", "edge_features", "features_of",
           "image_features", "index_for", "learn", "load_model", "model_path", "pair_keys", "recognize", "refine", "save_model", "select_regions", "support",
           "support_numpy", "view_of", "vote", "vote_numpy"]
