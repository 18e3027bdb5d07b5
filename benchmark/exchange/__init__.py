"""Files exchanged with a method in any language: camera inputs out (``fsv-bench export``),
per-frame estimates in (``fsv-bench score``)."""

from benchmark.exchange.camera_file import CameraFileError, load_camera_input, rng_generator, save_camera_input
from benchmark.exchange.estimates_file import EstimatesFileError, load_estimate, save_estimate

__all__ = ["CameraFileError", "EstimatesFileError", "load_camera_input", "load_estimate", "rng_generator",
           "save_camera_input", "save_estimate"]
