"""FSV: force sensing from vision (Pham, Kyriazis, Argyros, Kheddar, CVPR 2015).

The method sees depth frames, the camera calibration and known models of the object and the
hand; it never imports the simulator, the renderer or the benchmark.
"""

from fsv.errors import FsvError, InputError, SolverError, TrackingError
from fsv.models import HandModel, ObjectModel
from fsv.types import Calibration, Contacts, DepthVideo, Kinematics, Poses

__all__ = [
    "Calibration",
    "Contacts",
    "DepthVideo",
    "FsvError",
    "HandModel",
    "InputError",
    "Kinematics",
    "ObjectModel",
    "Poses",
    "SolverError",
    "TrackingError",
]
