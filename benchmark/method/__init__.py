"""The benchmark's side of the method: which method to run (:class:`MethodSpec`) and the one
function that runs it on an episode (:func:`run_method`)."""

from benchmark.method.run import camera_input, method_label, oracle_inputs, run_method
from benchmark.method.spec import DIFFERENTIATORS, ORACLE_STAGES, MethodSpec

__all__ = ["DIFFERENTIATORS", "ORACLE_STAGES", "MethodSpec", "camera_input", "method_label", "oracle_inputs",
           "run_method"]
