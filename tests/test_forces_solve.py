"""The cone programs: cones, Newton–Euler, the cvxpy oracle, eq. 8, kinetic contacts, infeasible frames."""

import clarabel
import numpy as np
import pytest
from forces_oracle import box_model, kinematics_for, oracle, random_grasp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fsv import Contacts, InputError, Kinematics
from fsv.forces import ForceSettings, FrameStatus, decompose_forces, nominal_forces, reconstruct_forces
from fsv.forces import program as program_module

REL = 1e-6


def _rel_residual(sol):
    scale = np.maximum(1.0, np.linalg.norm(sol.required, axis=1))
    return np.linalg.norm(sol.net_wrench - sol.required, axis=1) / scale


def _check_cones(sol, mu, tol=1e-6):
    f = np.einsum("tki,tki->tk", sol.force, sol.normal)
    tang = np.linalg.norm(sol.force - f[..., None] * sol.normal, axis=-1)
    scale = 1.0 + np.linalg.norm(sol.force, axis=-1)
    assert np.all(f[sol.active] >= -tol * scale[sol.active])
    assert np.all((tang - mu * f)[sol.active] <= tol * scale[sol.active])


def _check_kinetic(sol, contacts, mu, part, signed=False):
    """Sliding contacts: force = f (n + mu s) with f >= 0: on the cone surface along +slide_dir.

    The internal part of a sliding contact lies on the same line but may have either sign.
    """
    F = getattr(sol, part)
    f = np.einsum("tki,tki->tk", F, sol.normal)
    expected = f[..., None] * (sol.normal + mu * contacts.slide_dir)
    sl = sol.sliding
    assert np.allclose(F[sl], expected[sl], atol=1e-9)
    assert signed or np.all(f[sl] >= -1e-9)


@settings(max_examples=25, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), K=st.integers(1, 5), mu=st.floats(0.3, 1.2))
def test_nominal_is_feasible_minimal_and_matches_the_oracle(seed, K, mu):
    rng = np.random.default_rng(seed)
    model = box_model(mass_kg=rng.uniform(0.2, 1.5), friction=mu)
    contacts, force = random_grasp(rng, 2, K, model)
    kin = kinematics_for(rng, force, contacts.point, model)
    sol = nominal_forces(kin, contacts, model)
    assert np.all(sol.status == FrameStatus.OPTIMAL)
    assert np.all(_rel_residual(sol) <= REL)
    _check_cones(sol, mu)
    _check_kinetic(sol, contacts, mu, "force")
    tang = sol.tangential_force
    assert np.allclose(np.einsum("tki,tki->tk", tang, sol.normal), 0, atol=1e-12)
    assert np.allclose(tang + sol.normal_force[..., None] * sol.normal, sol.force)
    # The generating forces are feasible, so the nominal (minimal) sum of squares is not above theirs.
    assert np.all(sol.sum_of_squares <= np.einsum("tki,tki->t", force, force) * (1 + 1e-7) + 1e-7)
    assert np.allclose(sol.internal, 0.0)
    for t in range(len(sol)):
        nom, _, _ = oracle("nominal", sol.required[t], contacts, t, model)
        assert np.abs(sol.force[t] - nom).max() <= 1e-4


@settings(max_examples=15, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), K=st.integers(2, 5))
def test_decomposition_has_zero_internal_wrench_and_matches_the_oracle(seed, K):
    rng = np.random.default_rng(seed)
    model = box_model(friction=rng.uniform(0.4, 1.0))
    contacts, force = random_grasp(rng, 2, K, model)
    kin = kinematics_for(rng, force, contacts.point, model)
    measured = np.einsum("tki,tki->tk", force, contacts.normal) + rng.normal(scale=0.5, size=(2, K))
    measured[0, 0] = np.nan  # one finger without a sensor
    sol = decompose_forces(kin, contacts, model, measured)
    assert np.all(sol.status == FrameStatus.OPTIMAL)
    assert np.all(_rel_residual(sol) <= REL)
    assert np.abs(sol.internal_wrench).max() <= 1e-8 * (1 + np.abs(sol.internal).max())
    _check_cones(sol, model.friction)  # the total force
    nominal_only = nominal_forces(kin, contacts, model)
    assert np.isfinite(sol.force).all() and np.isfinite(sol.objective).all()
    for part in ("nominal", "internal", "force"):
        _check_kinetic(sol, contacts, model.friction, part, signed=part == "internal")
    f_n = np.einsum("tki,tki->tk", sol.nominal, sol.normal)
    assert np.all(f_n[sol.active] >= -1e-7)
    for t in range(2):
        nom, inner, _ = oracle("decomposition", sol.required[t], contacts, t, model, target=measured)
        assert np.abs(sol.nominal[t] - nom).max() <= 1e-4
        assert np.abs(sol.internal[t] - inner).max() <= 1e-4
    # Its nominal part explains the motion at least as expensively as the nominal solution.
    nominal_sos = np.einsum("tki,tki->t", sol.nominal, sol.nominal)
    assert np.all(nominal_sos >= nominal_only.sum_of_squares * (1 - 1e-6) - 1e-7)


def test_decomposition_of_consistent_measurements_recovers_them_and_the_nominal_forces():
    """With noise-free measurements of feasible forces, eq. 9 can fit them exactly at no extra nominal cost."""
    rng = np.random.default_rng(7)
    model = box_model()
    contacts, force = random_grasp(rng, 5, 4, model, p_sliding=0.0)
    kin = kinematics_for(rng, force, contacts.point, model)
    measured = np.einsum("tki,tki->tk", force, contacts.normal)
    nominal = nominal_forces(kin, contacts, model)
    # The regularisation of the internal tangential parts biases the fit by O(regularization * F).
    for eps, tol in ((1e-3, 1e-2), (1e-5, 2e-4)):
        sol = decompose_forces(kin, contacts, model, measured, settings=ForceSettings(regularization=eps))
        assert np.abs(sol.normal_force - measured).max() < tol
        assert np.abs(sol.nominal - nominal.force).max() < tol


@settings(max_examples=15, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), K=st.integers(2, 5))
def test_reconstruction_follows_the_predictions_and_matches_the_oracle(seed, K):
    rng = np.random.default_rng(seed)
    model = box_model()
    contacts, force = random_grasp(rng, 2, K, model)
    kin = kinematics_for(rng, force, contacts.point, model)
    predicted = rng.uniform(0.0, 5.0, size=(2, K))
    sol = reconstruct_forces(kin, contacts, model, predicted)
    assert np.all(sol.status == FrameStatus.OPTIMAL)
    assert np.all(_rel_residual(sol) <= REL)
    assert np.abs(sol.internal_wrench).max() <= 1e-8 * (1 + np.abs(sol.internal).max())
    _check_cones(sol, model.friction)
    for t in range(2):
        nom, inner, _ = oracle("reconstruction", sol.required[t], contacts, t, model, target=predicted)
        assert np.abs(sol.nominal[t] - nom).max() <= 1e-4
        assert np.abs(sol.internal[t] - inner).max() <= 1e-4


def test_reconstruction_reproduces_internal_forces_that_are_achievable():
    rng = np.random.default_rng(3)
    model = box_model()
    contacts, force = random_grasp(rng, 4, 4, model, p_sliding=0.0)
    kin = kinematics_for(rng, force, contacts.point, model)
    measured = np.einsum("tki,tki->tk", force, contacts.normal)
    fine = ForceSettings(regularization=1e-5)
    internal = decompose_forces(kin, contacts, model, measured, settings=fine).internal_normal
    sol = reconstruct_forces(kin, contacts, model, internal, settings=fine)
    assert np.abs(sol.internal_normal - internal).max() < 5e-4
    assert np.abs(sol.normal_force - measured).max() < 5e-4
    sol = reconstruct_forces(kin, contacts, model, internal)
    assert np.abs(sol.internal_normal - internal).max() < 2e-2


def _single_contact(required_dir):
    """One finger at the centre of the +y face (normal -y, into the box), box at rest in free space."""
    model = box_model()
    h = model.half_extents
    contacts = Contacts(
        finger_names=["thumb"],
        active=[[True]],
        sliding=[[False]],
        point=[[[0.0, h[1], 0.0]]],
        normal=[[[0.0, -1.0, 0.0]]],
        slide_dir=np.zeros((1, 1, 3)),
    )
    force = np.array([[[*required_dir]]], float)
    kin = kinematics_for(np.random.default_rng(0), force, contacts.point, model, rot=np.eye(3)[None])
    return model, contacts, kin


def test_a_contact_pushing_the_wrong_way_is_infeasible_with_a_least_violation_answer():
    # The motion needs +y force at the +y face: the finger would have to pull.
    model, contacts, kin = _single_contact((0.0, 3.0, 0.0))
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.LEAST_VIOLATION
    # Best possible: no force; the violation is the whole required wrench.
    assert np.abs(sol.force).max() < 1e-4
    assert np.allclose(sol.residual[0], sol.required[0], atol=1e-4)
    nom, _, _ = oracle("nominal", sol.required[0], contacts, 0, model, slack_weight=1e6)
    assert np.abs(sol.force[0] - nom).max() <= 1e-4


def test_a_partly_infeasible_frame_explains_what_it_can():
    # Required: 1 N of push (-y, into the box) with 2 N of friction along +x; mu = 0.8 allows
    # 0.8 N: the least violation leans on the cone's surface and reports the rest.
    model, contacts, kin = _single_contact((2.0, -1.0, 0.0))
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.LEAST_VIOLATION
    nom, _, _ = oracle("nominal", sol.required[0], contacts, 0, model, slack_weight=1e6)
    assert np.abs(sol.force[0] - nom).max() <= 1e-4
    assert np.linalg.norm(sol.residual[0]) > 0.1
    _check_cones(sol, model.friction)
    F = sol.force[0, 0]
    assert F[1] < -0.5 and np.hypot(F[0], F[2]) == pytest.approx(model.friction * -F[1], rel=1e-4)


def test_frames_without_contacts_or_kinematics_do_not_crash():
    rng = np.random.default_rng(1)
    model = box_model()
    contacts, force = random_grasp(rng, 3, 3, model)
    kin = kinematics_for(rng, force, contacts.point, model)
    active = contacts.active.copy()
    active[1] = False
    contacts = Contacts(contacts.finger_names, active, contacts.sliding & active, contacts.point, contacts.normal,
                        contacts.slide_dir)
    valid = np.array([True, True, False])
    kin = Kinematics(kin.t, kin.pos, kin.rot, kin.vel, kin.acc, kin.omega, kin.alpha, valid)
    sol = nominal_forces(kin, contacts, model)
    assert list(sol.status) == [FrameStatus.OPTIMAL, FrameStatus.NO_CONTACTS, FrameStatus.NO_KINEMATICS]
    assert np.all(sol.force[1] == 0) and np.allclose(sol.residual[1], sol.required[1])
    assert np.isnan(sol.force[2]).all()
    assert sol.count(FrameStatus.NO_CONTACTS) == 1


def test_one_solver_per_contact_layout_updated_in_place(monkeypatch):
    """Frames sharing a layout re-use one solver; the updated solves equal fresh ones."""
    rng = np.random.default_rng(5)
    model = box_model()
    contacts, force = random_grasp(rng, 12, 4, model, p_sliding=0.0)
    # Two layouts: all four fingers, then the last finger lifted for the second half.
    active = np.ones((12, 4), bool)
    active[6:, 3] = False
    force[6:, 3] = 0.0
    contacts = Contacts(contacts.finger_names, active, np.zeros_like(active), contacts.point, contacts.normal,
                        contacts.slide_dir)
    kin = kinematics_for(rng, force, contacts.point, model)
    built = []
    real = clarabel.DefaultSolver

    def counting(*args):
        built.append(1)
        return real(*args)

    monkeypatch.setattr(program_module.clarabel, "DefaultSolver", counting)
    seq = nominal_forces(kin, contacts, model)
    assert len(built) == 2
    for t in (0, 5, 6, 11):
        one = nominal_forces(
            Kinematics(kin.t[t : t + 1], kin.pos[t : t + 1], kin.rot[t : t + 1], kin.vel[t : t + 1],
                       kin.acc[t : t + 1], kin.omega[t : t + 1], kin.alpha[t : t + 1], kin.valid[t : t + 1]),
            Contacts(contacts.finger_names, active[t : t + 1], contacts.sliding[t : t + 1], contacts.point[t : t + 1],
                     contacts.normal[t : t + 1], contacts.slide_dir[t : t + 1]),
            model,
        )
        assert np.abs(one.force[0] - seq.force[t]).max() < 1e-7


def test_bad_inputs_name_the_value():
    rng = np.random.default_rng(2)
    model = box_model()
    contacts, force = random_grasp(rng, 2, 3, model, p_sliding=0.0)
    kin = kinematics_for(rng, force, contacts.point, model)
    with pytest.raises(InputError, match="measured_normal"):
        decompose_forces(kin, contacts, model, np.ones((2, 4)))
    with pytest.raises(InputError, match="internal_normal"):
        reconstruct_forces(kin, contacts, model, np.full((2, 3), np.inf))
    sliding = contacts.active.copy()
    bad = Contacts(contacts.finger_names, contacts.active, sliding, contacts.point, contacts.normal,
                   np.zeros_like(contacts.point))
    with pytest.raises(InputError, match="slide_dir of sliding finger 0 at frame 0"):
        nominal_forces(kin, bad, model)
    with pytest.raises(InputError, match="slack_weight"):
        ForceSettings(slack_weight=0.0)
    with pytest.raises(InputError, match="contacts must be fsv.Contacts"):
        nominal_forces(kin, force, model)


def test_a_solver_that_gives_up_is_reported_failed_with_nan_forces():
    rng = np.random.default_rng(8)
    model = box_model()
    contacts, force = random_grasp(rng, 2, 4, model)
    kin = kinematics_for(rng, force, contacts.point, model)
    sol = nominal_forces(kin, contacts, model, settings=ForceSettings(max_iter=1))
    assert list(sol.status) == [FrameStatus.FAILED] * 2
    assert np.isnan(sol.force).all() and np.isnan(sol.objective).all()


def _sliding_single_contact(required_dir):
    """``_single_contact`` with the finger flagged sliding along +x (kinetic friction along +x)."""
    model, contacts, kin = _single_contact(required_dir)
    sliding = Contacts(finger_names=["thumb"], active=[[True]], sliding=[[True]], point=contacts.point,
                       normal=contacts.normal, slide_dir=[[[1.0, 0.0, 0.0]]])
    return model, sliding, kin


def test_a_sliding_flag_that_makes_the_frame_infeasible_is_retried_with_static_friction():
    # A pure push (-y) cannot come from kinetic friction along +x (force along -y + 0.8 x) but lies
    # inside the static cone: the retry solves it exactly and reports the contact as held.
    model, contacts, kin = _sliding_single_contact((0.0, -3.0, 0.0))
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.STATIC_FRICTION and not sol.sliding[0, 0]
    assert np.allclose(sol.force[0, 0], [0.0, -3.0, 0.0], atol=1e-6) and _rel_residual(sol)[0] <= REL
    kinetic_only = nominal_forces(kin, contacts, model, settings=ForceSettings(static_retry=False))
    assert kinetic_only.status[0] == FrameStatus.LEAST_VIOLATION and kinetic_only.sliding[0, 0]
    assert np.linalg.norm(kinetic_only.residual[0]) > 0.5


def test_the_physical_bound_follows_the_grasp_mechanics():
    from fsv.forces import force_bound

    required = np.array([[0.0, 0.0, 2.94, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.03, 0.0, 0.0]])
    bound = force_bound(required, friction=0.8, lever_m=0.03, factor=5.0)
    assert bound == pytest.approx([5 * 2.25 * 2.94, 5 * 2.25 * 0.03 / 0.03])  # 33.1 N and 11.25 N


def test_forces_above_the_physical_bound_are_flagged_and_never_passed_on():
    model, contacts, kin = _single_contact((0.0, -3.0, 0.0))
    assert nominal_forces(kin, contacts, model).status[0] == FrameStatus.OPTIMAL  # 3 N against a bound of 34 N
    tight = nominal_forces(kin, contacts, model, settings=ForceSettings(bound_factor=0.05))  # bound 0.34 N
    assert tight.status[0] == FrameStatus.IMPLAUSIBLE and np.isnan(tight.force).all()
    unbounded = nominal_forces(kin, contacts, model, settings=ForceSettings(bound_factor=np.inf))
    assert unbounded.status[0] == FrameStatus.OPTIMAL


def test_a_violation_within_the_solvers_precision_counts_as_solved():
    # Friction needed 2e-7 beyond the cone (mu = 0.8 of a 1 N push): infeasible by a hair, as when the
    # box slides on the table with its force exactly on the cone; the least-violation answer then
    # explains the motion to 1.3e-6 N (mostly the slack weight's own trade-off) and is reported
    # solved, unless the tolerance is 0.
    model, contacts, kin = _single_contact((0.8 * (1 + 2e-7), -1.0, 0.0))
    strict = nominal_forces(kin, contacts, model, settings=ForceSettings(feasibility_tol=0.0))
    assert strict.status[0] == FrameStatus.LEAST_VIOLATION and 0 < np.linalg.norm(strict.residual[0]) < 1e-5
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.OPTIMAL and np.allclose(sol.force, strict.force)
    model, contacts, kin = _single_contact((0.8 * 1.01, -1.0, 0.0))  # 1 % outside: a real violation
    assert nominal_forces(kin, contacts, model).status[0] == FrameStatus.LEAST_VIOLATION


def _pinch_with_a_candidate(gap_m):
    """A finger at the +y face and a second one 'near' the -y face (inactive, its pad ``gap_m`` away);
    the motion needs a squeeze's friction: 3 N along +z with no net y force."""
    model = box_model()
    h = model.half_extents
    point = np.array([[[0.0, h[1], 0.0], [0.0, -h[1], 0.0]]])
    normal = np.array([[[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]])
    contacts = Contacts(finger_names=["index", "thumb"], active=[[True, False]], sliding=[[False, False]],
                        point=point, normal=normal, slide_dir=np.zeros((1, 2, 3)), gap=[[0.0, gap_m]])
    force = np.array([[[0.0, -3.0, 1.5], [0.0, 3.0, 1.5]]])
    kin = kinematics_for(np.random.default_rng(0), force, point, model, rot=np.eye(3)[None])
    return model, contacts, kin


def test_an_infeasible_frame_takes_a_finger_near_the_surface_as_a_contact():
    # One finger cannot lift the box (it would need friction without pressing); the finger the
    # tracker saw 20 mm from the opposite face can: the frame is solved exactly with it added.
    model, contacts, kin = _pinch_with_a_candidate(0.02)
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.CONTACTS_ADDED and sol.active[0].tolist() == [True, True]
    assert _rel_residual(sol)[0] <= REL
    _check_cones(sol, model.friction)
    nom, _, _ = oracle("nominal", sol.required[0], sol.contacts_used(contacts), 0, model)
    assert np.abs(sol.force[0] - nom).max() <= 1e-4
    used = sol.contacts_used(contacts)
    assert used.active[0].tolist() == [True, True] and np.allclose(used.point[0, 1], contacts.point[0, 1])
    # The same frame with the candidate beyond the repair distance, with the repair off, or with
    # an unknown gap: least violation, and the given contacts are passed on unchanged.
    for c, settings_ in ((_pinch_with_a_candidate(0.05)[1], None), (contacts, ForceSettings(repair_gap_m=0.0)),
                         (Contacts(contacts.finger_names, contacts.active, contacts.sliding, contacts.point,
                                   contacts.normal, contacts.slide_dir), None)):
        far = nominal_forces(kin, c, model, settings=settings_)
        assert far.status[0] == FrameStatus.LEAST_VIOLATION and far.active[0].tolist() == [True, False]
        assert far.contacts_used(c) is c


def test_the_learned_stage_sees_the_contacts_the_force_stage_added():
    # reconstruction with the contacts passed on is exact; with the tracked ones it is not
    model, contacts, kin = _pinch_with_a_candidate(0.02)
    used = nominal_forces(kin, contacts, model).contacts_used(contacts)
    target = np.array([[2.0, 2.0]])
    assert reconstruct_forces(kin, used, model, target).status[0] == FrameStatus.OPTIMAL
    no_repair = ForceSettings(repair_gap_m=0.0)
    assert reconstruct_forces(kin, contacts, model, target, settings=no_repair).status[0] == FrameStatus.LEAST_VIOLATION


def test_contacts_used_checks_the_fingers():
    model, contacts, kin = _pinch_with_a_candidate(0.02)
    sol = nominal_forces(kin, contacts, model)
    other = Contacts(["a", "b"], contacts.active, contacts.sliding, contacts.point, contacts.normal, contacts.slide_dir)
    with pytest.raises(InputError, match="fingers"):
        sol.contacts_used(other)


def test_a_frame_that_lost_every_contact_takes_the_fingers_near_the_surface():
    # Both fingers of the pinch off the box's surface by the tracker's error (8 mm and 20 mm, beyond
    # the detector's hysteresis): nothing touches the box, yet it moves as held. The two pads near
    # the surface carry it exactly, rather than no force at all.
    model, contacts, kin = _pinch_with_a_candidate(0.02)
    lost = Contacts(contacts.finger_names, [[False, False]], contacts.sliding, contacts.point, contacts.normal,
                    contacts.slide_dir, gap=[[0.008, 0.02]])
    sol = nominal_forces(kin, lost, model)
    assert sol.status[0] == FrameStatus.CONTACTS_ADDED and sol.active[0].tolist() == [True, True]
    assert _rel_residual(sol)[0] <= REL
    nom, _, _ = oracle("nominal", sol.required[0], sol.contacts_used(lost), 0, model)
    assert np.abs(sol.force[0] - nom).max() <= 1e-4
    # one pad near: it cannot lift the box alone; the least-violation answer with it, not zero force
    one = Contacts(contacts.finger_names, [[False, False]], contacts.sliding, contacts.point, contacts.normal,
                   contacts.slide_dir, gap=[[0.008, 0.05]])
    sol = nominal_forces(kin, one, model)
    assert sol.status[0] == FrameStatus.LEAST_VIOLATION and sol.active[0].tolist() == [True, False]
    assert np.linalg.norm(sol.force[0, 0]) > 0.5
    assert _rel_residual(sol)[0] < 1.0  # explains part of the motion
    # no pad near (or an unknown gap): no contacts, as before
    for gap in ([[0.05, 0.05]], None):
        none = Contacts(contacts.finger_names, [[False, False]], contacts.sliding, contacts.point, contacts.normal,
                        contacts.slide_dir, gap=gap)
        sol = nominal_forces(kin, none, model)
        assert sol.status[0] == FrameStatus.NO_CONTACTS and np.all(sol.force[0] == 0)
