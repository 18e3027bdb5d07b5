"""What two model files trained by the same code on the same data must share, bit for bit."""

from __future__ import annotations

from fsv.learn.direct import read_direct_state
from fsv.learn.model import content_sha256


def trained_bits(path) -> str:
    """The SHA-256 of a direct model file's content but the list of BLAS libraries in its provenance.

    That list names the libraries the training process had loaded (``fsv.provenance``): two trainings
    in one test process differ there when a test between them loaded another (cvxpy's solvers bring
    their own OpenBLAS, measured). The weights, the normalisation and the rest of the metadata count.
    """
    state = read_direct_state(path)
    state["metadata"]["provenance"].pop("blas")
    return content_sha256(state)
