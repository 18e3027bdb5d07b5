"""Rotation helpers shared by the hand model, the kinematics and the trackers."""

import numpy as np
import pytest

from fsv.rotation import cross


@pytest.mark.parametrize("shape_a, shape_b", [((50, 3), (50, 3)), ((40, 20, 3), (40, 1, 3)), ((30, 3), (3,)),
                                              ((3,), (25, 3))])
def test_cross_equals_numpys_cross_bit_for_bit(shape_a, shape_b):
    rng = np.random.default_rng(0)
    a = rng.normal(size=shape_a) * 10.0 ** rng.integers(-6, 3, size=shape_a)
    b = rng.normal(size=shape_b)
    c = cross(a, b)
    ref = np.cross(a, b)
    assert c.shape == ref.shape and c.flags.c_contiguous
    assert c.tobytes() == ref.tobytes()
    # and it is the cross product: orthogonal to both, e_x x e_y = e_z
    np.testing.assert_allclose(np.einsum("...i,...i->...", c, np.broadcast_to(b, c.shape)), 0.0,
                               atol=1e-9 * np.abs(a).max())
    np.testing.assert_array_equal(cross(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])), [0.0, 0.0, 1.0])
