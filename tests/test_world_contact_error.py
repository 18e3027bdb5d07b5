"""Contacts from the truth (oracle) and the vision contact-error model of the paper's §4.2."""

import numpy as np
import pytest
from forces_oracle import grasp_truth

from benchmark.errors import BenchmarkError
from benchmark.world.contact_error import contacts_from_truth, vision_like_contacts


def test_contacts_from_truth_keep_points_normals_and_the_kinetic_direction():
    truth, model = grasp_truth(0, T=30, K=4, p_sliding=0.4)
    c = contacts_from_truth(truth)
    assert np.array_equal(c.active, truth.contact_active)
    assert np.array_equal(c.sliding, truth.contact_sliding)
    assert np.allclose(c.point, truth.contact_point) and np.allclose(c.normal, truth.contact_normal)
    # The sliding forces of grasp_truth lie on the cone surface along +slide_dir: recover it.
    F, n = truth.contact_force, truth.contact_normal
    f = np.einsum("tki,tki->tk", F, n)
    expected = (F - f[..., None] * n) / (model.friction * f[..., None])
    assert c.sliding.any()
    assert np.allclose(c.slide_dir[c.sliding], expected[c.sliding])
    assert np.all(c.slide_dir[~c.sliding] == 0)


def test_vision_errors_have_the_requested_statistics_and_stay_on_the_faces():
    truth, model = grasp_truth(1, T=400, K=5)
    c = contacts_from_truth(truth)
    v = vision_like_contacts(c, model, np.random.default_rng(0))
    axis = np.argmax(np.abs(c.normal), axis=-1)
    in_plane = np.ones(c.point.shape, bool)
    np.put_along_axis(in_plane, axis[..., None], False, axis=-1)
    d = (v.point - c.point)[in_plane & c.active[..., None]]
    # Clipping at the face edges trims the tails a little: allow for it.
    assert d.mean() == pytest.approx(-1.55e-3, abs=4e-4)
    assert d.std() == pytest.approx(6.13e-3, rel=0.12)
    assert np.all((v.point - c.point)[~in_plane] == 0)  # the normal coordinate stays on the face
    assert np.all(np.abs(v.point) <= model.half_extents + 1e-12)
    assert np.array_equal(v.normal, c.normal)
    same = vision_like_contacts(c, model, np.random.default_rng(0))
    assert np.array_equal(same.point, v.point)
    with pytest.raises(BenchmarkError, match="std >= 0"):
        vision_like_contacts(c, model, np.random.default_rng(0), std_m=-1.0)
