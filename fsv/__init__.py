"""FSV: force sensing from vision (Pham, Kyriazis, Argyros, Kheddar, CVPR 2015).

The method sees depth frames, the camera calibration and known models of the object and the
hand; it never imports the simulator, the renderer or the benchmark.
"""

from fsv.errors import FsvError, InputError, SolverError, TrackingError
from fsv.grip import GripCalibration
from fsv.method import CameraInput, Method, make_method
from fsv.models import HandModel, ObjectModel

# The whole method: depth -> tracking -> contacts -> kinematics -> forces.
from fsv.pipeline import Estimate, run_pipeline
from fsv.track.tracker import TrackInit
from fsv.types import STREAMS, Calibration, ColourVideo, Contacts, DepthVideo, Kinematics, Poses

__all__ = [
    "STREAMS",
    "Calibration",
    "CameraInput",
    "ColourVideo",
    "Contacts",
    "DepthVideo",
    "Estimate",
    "FsvError",
    "GripCalibration",
    "HandModel",
    "InputError",
    "Kinematics",
    "Method",
    "ObjectModel",
    "Poses",
    "SolverError",
    "TrackInit",
    "TrackingError",
    "make_method",
    "run_pipeline",
]
