"""FSV: force sensing from vision (Pham, Kyriazis, Argyros, Kheddar, CVPR 2015).

The method sees depth frames, the camera calibration and known models of the object and the
hand; it never imports the simulator, the renderer or the benchmark.
"""

from fsv.errors import FsvError, InputError, SolverError, TrackingError
from fsv.models import HandModel, ObjectModel
from fsv.types import Calibration, Contacts, DepthVideo, Kinematics, Poses

# The whole method (issue 6): depth -> tracking -> contacts -> kinematics -> forces.
from fsv.pipeline import Estimate, run_pipeline
from fsv.track.tracker import TrackInit

__all__ = [
    "Calibration",
    "Contacts",
    "DepthVideo",
    "Estimate",
    "FsvError",
    "HandModel",
    "InputError",
    "Kinematics",
    "ObjectModel",
    "Poses",
    "SolverError",
    "TrackInit",
    "TrackingError",
    "run_pipeline",
]
