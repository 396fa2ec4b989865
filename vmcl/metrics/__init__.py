"""The field's own error measures: stereo bad pixels, flow endpoint and angular error, BSDS boundaries.

Every module of the Vision Machine is measured against ground truth (seed paper, "Learning and parameter
estimation": parameters are estimated "from a set of examples in which data and desired solution are
given"). The figures computed here are the ones the literature reports, computed the way it computes
them, so that vmcl's numbers can be set beside published ones (device arrays are accepted and copied
to the host):

- :mod:`~vmcl.metrics.stereo`: Middlebury "bad pixels" at 0.5, 1, 2 and 4 px, pixels without an output
  counted as bad and the output density reported beside, plus mean absolute and RMS error on the pixels
  that have an output (Scharstein and Szeliski 2002);
- :mod:`~vmcl.metrics.flow`: average endpoint error and Barron's average angular error (Barron, Fleet and
  Beauchemin 1994; Baker et al. 2011);
- :mod:`~vmcl.metrics.boundaries`: the BSDS benchmark's precision, recall and F-measure at the optimal
  dataset scale (ODS) and the optimal image scale (OIS), with the benchmark's one-to-one pixel matching
  (``correspondPixels``, taken from the maintained ``pyEdgeEval`` port of the official C++ code) and its
  thinning;
- :mod:`~vmcl.metrics.detections`: labelled discontinuities, per physical label (depth, orientation,
  albedo, shadow, specular, texture), precision and recall of predicted discontinuity pixels within a
  tolerance of t pixels, the measure the seed paper's labelling stage needs;
- :mod:`~vmcl.metrics.points`: detected points (junctions, corners) matched one to one within a
  tolerance, and the junctions of human segmentations (where three or more segments meet);
- :mod:`~vmcl.metrics.recognition`: recognised objects against a scene's, the recognition rate, false
  detections per image and the pose's error at the model's corners.

Two private modules serve them all: ``_inputs`` (argument checks and the copy of device arrays to the
host) and ``_rates`` (ratios and the F-measure, 0 where nothing is counted).
"""

from vmcl.metrics.boundaries import BoundaryCounts, BoundaryScores, boundary_counts, evaluate_boundaries
from vmcl.metrics.detections import DetectionScores, detection_scores, label_scores, within_tolerance
from vmcl.metrics.flow import FlowScores, angular_error, endpoint_error, evaluate_flow
from vmcl.metrics.points import match_points, point_scores, segmentation_junctions
from vmcl.metrics.recognition import RecognitionScores, recognition_scores
from vmcl.metrics.stereo import BAD_PIXEL_THRESHOLDS, DisparityScores, evaluate_disparity

__all__ = [
    "BAD_PIXEL_THRESHOLDS",
    "BoundaryCounts",
    "BoundaryScores",
    "DetectionScores",
    "DisparityScores",
    "FlowScores",
    "RecognitionScores",
    "angular_error",
    "boundary_counts",
    "detection_scores",
    "endpoint_error",
    "evaluate_boundaries",
    "evaluate_disparity",
    "evaluate_flow",
    "label_scores",
    "match_points",
    "point_scores",
    "recognition_scores",
    "segmentation_junctions",
    "within_tolerance",
]
