"""fsv.linalg: fixed-order products and solves equal NumPy's to rounding, and are kernel-independent."""

import numpy as np
import pytest
from openblas_kernels import runnable_kernels

from fsv import linalg


@pytest.fixture
def rng():
    return np.random.default_rng(7)


def test_products_equal_numpy_to_rounding(rng):
    A, B = rng.normal(size=(5, 3, 4)), rng.normal(size=(5, 4, 2))
    x, M = rng.normal(size=(6, 3)), rng.normal(size=(3, 3))
    np.testing.assert_allclose(linalg.mm(A, B), A @ B, rtol=0, atol=1e-14)
    np.testing.assert_allclose(linalg.mv(A, B[..., 0]), np.einsum("nij,nj->ni", A, B[..., 0]), atol=1e-14)
    np.testing.assert_allclose(linalg.vm(x, M), x @ M, atol=1e-14)
    np.testing.assert_allclose(linalg.rows_mt(x, M), x @ M.T, atol=1e-14)
    np.testing.assert_allclose(linalg.dot(x, x), np.sum(x * x, axis=1), atol=1e-14)
    assert linalg.norm(x) == pytest.approx(np.sqrt(np.sum(x * x)), rel=1e-15)


def test_gram_and_transposed_product(rng):
    J, w, r = rng.normal(size=(200, 7)), rng.uniform(0.5, 2.0, 200), rng.normal(size=200)
    G = linalg.gram(J, w)
    np.testing.assert_allclose(G, (J * w[:, None]).T @ J, rtol=1e-13, atol=1e-12)
    assert np.array_equal(G, G.T)  # symmetric by construction, bit for bit
    np.testing.assert_allclose(linalg.gram(J), J.T @ J, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(linalg.tmv(J, r), J.T @ r, atol=1e-12)


def test_correlation_and_convolution_equal_numpys(rng):
    x, w = rng.normal(size=50), rng.normal(size=7)
    np.testing.assert_allclose(linalg.correlate_valid(x, w), np.correlate(x, w, "valid"), atol=1e-13)
    np.testing.assert_allclose(linalg.convolve_full(x, w), np.convolve(x, w), atol=1e-13)
    assert linalg.convolve_full([1.0, 2.0], [0.5, 0.0, -0.5]).tolist() == [0.5, 1.0, -0.5, -1.0]


def test_solve_and_inverse(rng):
    A = rng.normal(size=(9, 9)) + 3 * np.eye(9)
    b = rng.normal(size=9)
    x = linalg.solve(A, b)
    np.testing.assert_allclose(A @ x, b, atol=1e-12)
    np.testing.assert_allclose(linalg.solve(A, np.stack([b, 2 * b], 1))[:, 1], 2 * x, atol=1e-12)
    np.testing.assert_allclose(linalg.inv(A) @ A, np.eye(9), atol=1e-12)
    P = np.array([[0.0, 1.0], [1.0, 0.0]])  # needs a row swap (zero first pivot)
    np.testing.assert_allclose(linalg.solve(P, [2.0, 3.0]), [3.0, 2.0])
    with pytest.raises(np.linalg.LinAlgError):
        linalg.solve(np.zeros((3, 3)), np.ones(3))
    with pytest.raises(ValueError, match="solve needs"):
        linalg.solve(np.zeros((3, 2)), np.ones(3))


def test_rigid_inverse_inverts_a_rigid_transform(rng):
    from fsv.rotation import exp_so3

    T = np.eye(4)
    T[:3, :3], T[:3, 3] = exp_so3(rng.normal(size=3)), rng.normal(size=3)
    inv = linalg.rigid_inverse(T)
    np.testing.assert_allclose(inv @ T, np.eye(4), atol=1e-15)
    np.testing.assert_allclose(inv, np.linalg.inv(T), atol=1e-15)
    assert np.all(inv[3] == [0.0, 0.0, 0.0, 1.0])


_PROBE = """
import hashlib, numpy as np
from fsv import linalg
rng = np.random.default_rng(3)
A = rng.normal(size=(40, 3, 3)); J = rng.normal(size=(500, 26)); b = rng.normal(size=26)
G = linalg.gram(J) + np.eye(26)
out = [linalg.mm(A, A), linalg.vm(J[:, :3], A[0]), linalg.gram(J), linalg.solve(G, b), linalg.inv(G[:6, :6]),
       np.array(linalg.norm(J)), linalg.tmv(J, J[:, 0]),
       linalg.correlate_valid(J[:, 0], b[:9]), linalg.convolve_full(b, J[:5, 1]),
       linalg.rigid_inverse(np.vstack([np.hstack([A[1], b[:3, None]]), [0, 0, 0, 1]]))]
print(hashlib.sha256(b"".join(np.ascontiguousarray(o).tobytes() for o in out)).hexdigest())
"""


def test_same_bits_under_every_openblas_kernel(kernel_python):
    """The point of the module: OPENBLAS_CORETYPE changes NumPy's BLAS products, not these."""
    digests = set()
    for kernel in ("Haswell", "Sandybridge", "Nehalem", "Prescott", *(["SkylakeX"] if "SkylakeX" in runnable_kernels() else [])):
        digests.add(kernel_python(_PROBE, env={"OPENBLAS_CORETYPE": kernel}).strip())
    assert len(digests) == 1
