"""Test helpers for the force programs: random feasible grasps and a cvxpy oracle.

Not a test module (no ``test_`` prefix): ``tests/test_forces_*.py`` import it. cvxpy is a test
dependency only; the method never imports it.
"""

from __future__ import annotations

import numpy as np

from fsv import Contacts, Kinematics, ObjectModel
from fsv.forces import GRAVITY, tangent_basis

SIZE = np.array([0.171, 0.111, 0.060])
FACES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)


def box_model(mass_kg=0.5, friction=0.8, table_friction=0.5) -> ObjectModel:
    return ObjectModel(
        size_m=SIZE,
        mass_kg=mass_kg,
        inertia=ObjectModel.solid_box_inertia(SIZE, mass_kg),
        friction=friction,
        table_friction=table_friction,
    )


def random_rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def random_grasp(rng, T: int, K: int, model: ObjectModel, p_sliding=0.3, p_active=1.0):
    """Random contacts on the box faces and random forces inside (or on) their cones.

    Returns:
        ``(contacts, forces)``: forces (T, K, 3) in the object frame, zero where inactive;
        sliding contacts' forces lie on the cone surface along +slide_dir.
    """
    h = model.half_extents
    mu = model.friction
    point = np.zeros((T, K, 3))
    normal = np.zeros((T, K, 3))
    slide = np.zeros((T, K, 3))
    force = np.zeros((T, K, 3))
    active = rng.random((T, K)) < p_active
    sliding = active & (rng.random((T, K)) < p_sliding)
    for t in range(T):
        for k in range(K):
            face = FACES[rng.integers(6)]
            p = rng.uniform(-h, h)
            axis = np.argmax(np.abs(face))
            p[axis] = face[axis] * h[axis]
            n = -face
            tx, ty = tangent_basis(n)
            a = rng.uniform(0, 2 * np.pi)
            tdir = np.cos(a) * tx + np.sin(a) * ty
            f = rng.uniform(0.5, 6.0)
            point[t, k], normal[t, k] = p, n
            if sliding[t, k]:
                slide[t, k] = tdir
                force[t, k] = f * (n + mu * tdir)
            elif active[t, k]:
                force[t, k] = f * n + rng.uniform(0, 0.95) * mu * f * tdir
    contacts = Contacts(
        finger_names=[f"f{k}" for k in range(K)],
        active=active,
        sliding=sliding,
        point=point,
        normal=normal,
        slide_dir=slide,
    )
    return contacts, force


def kinematics_for(rng, force, point, model: ObjectModel, env_wrench=None, pos=None, rot=None) -> Kinematics:
    """Kinematics whose eq. 1 wrench equals the wrench of the given object-frame forces.

    Orientation and angular velocity are random (unless given); acceleration and angular
    acceleration are solved from Newton–Euler.
    """
    T = force.shape[0]
    w_obj = np.concatenate([force.sum(1), np.cross(point, force).sum(1)], axis=1)
    if env_wrench is not None:
        w_obj = w_obj + env_wrench
    R = np.stack([random_rotation(rng) for _ in range(T)]) if rot is None else rot
    pos = np.tile([0.0, 0.0, 0.5], (T, 1)) if pos is None else pos
    omega = rng.normal(scale=2.0, size=(T, 3))
    F = np.einsum("tij,tj->ti", R, w_obj[:, :3])
    tau = np.einsum("tij,tj->ti", R, w_obj[:, 3:])
    J = R @ model.inertia @ np.swapaxes(R, 1, 2)
    acc = F / model.mass_kg + GRAVITY
    rhs = tau - np.cross(omega, np.einsum("tij,tj->ti", J, omega))
    alpha = np.linalg.solve(J, rhs[..., None])[..., 0]
    return Kinematics(
        t=np.arange(T) / 30.0, pos=pos, rot=R, vel=np.zeros((T, 3)), acc=acc, omega=omega, alpha=alpha,
        valid=np.ones(T, bool),
    )


def oracle(kind, required, contacts: Contacts, t: int, model: ObjectModel, target=None, corners=(), table_normal=None,
           table_weight=0.01, eps=1e-3, slack_weight=None):
    """Solves one frame with cvxpy, formulated on 3-D force vectors (not on eq. 2's coordinates).

    Returns:
        ``(nominal (K, 3), internal (K, 3), corner forces (len(corners), 3))``; the corner forces
        are the totals (nominal + internal).
    """
    import cvxpy as cp  # lazy: cvxpy (0.25 s) off every xdist worker's collection of the modules that import this one

    K = len(contacts.finger_names)
    mu, mut = model.friction, model.table_friction
    cons, cost = [], 0
    Fn, Fi = {}, {}
    internal = kind != "nominal"
    for k in np.flatnonzero(contacts.active[t]):
        n = contacts.normal[t, k]
        if contacts.sliding[t, k]:
            s = contacts.slide_dir[t, k]
            d = n + mu * s
            a = cp.Variable()
            Fn[k] = a * d
            cons.append(a >= 0)
            if internal:
                b = cp.Variable()
                Fi[k] = b * d
                cons.append(a + b >= 0)
        else:
            Fn[k] = cp.Variable(3)
            cons.append(cp.norm(Fn[k] - (n @ Fn[k]) * n) <= mu * (n @ Fn[k]))
            if internal:
                Fi[k] = cp.Variable(3)
                tot = Fn[k] + Fi[k]
                cons.append(cp.norm(tot - (n @ tot) * n) <= mu * (n @ tot))
                cost += eps * cp.sum_squares(Fi[k] - (n @ Fi[k]) * n)
        cost += cp.sum_squares(Fn[k])
        if internal:
            if target is None or not np.isfinite(target[t, k]):
                cost += eps * cp.square(n @ Fi[k])
            elif kind == "decomposition":
                cost += cp.square(n @ (Fn[k] + Fi[k]) - target[t, k])
            else:
                cost += cp.square(n @ Fi[k] - target[t, k])
    Fc = []
    half = model.half_extents
    from fsv.forces.environment import UNIT_CORNERS

    Fci = []
    for j in corners:
        F = cp.Variable(3)
        nz = table_normal
        cons.append(cp.norm(F - (nz @ F) * nz) <= mut * (nz @ F))
        cost += table_weight * cp.sum_squares(F)
        Fc.append((UNIT_CORNERS[j] * half, F))
        if internal:
            G = cp.Variable(3)
            tot = F + G
            cons.append(cp.norm(tot - (nz @ tot) * nz) <= mut * (nz @ tot))
            cost += eps * cp.sum_squares(G - (nz @ G) * nz) + eps * table_weight * cp.square(nz @ G)
            Fci.append((UNIT_CORNERS[j] * half, G))
    pts = contacts.point[t]
    net_f = sum(Fn.values()) + sum(F for _, F in Fc) if (Fn or Fc) else np.zeros(3)
    net_m = sum(cp.hstack(_cross(pts[k], Fn[k])) for k in Fn) + sum(cp.hstack(_cross(p, F)) for p, F in Fc)
    residual = cp.hstack([required[:3] - net_f, required[3:] - net_m])
    if slack_weight is None:
        cons.append(residual == 0)
    else:
        cost += slack_weight * cp.sum_squares(residual)
    if internal:
        cons.append(sum(Fi.values()) + sum(G for _, G in Fci) == 0)
        cons.append(sum(cp.hstack(_cross(pts[k], Fi[k])) for k in Fi) + sum(cp.hstack(_cross(p, G)) for p, G in Fci) == 0)
    prob = cp.Problem(cp.Minimize(cost), cons)
    prob.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-12, tol_feas=1e-10)
    assert prob.status in ("optimal", "optimal_inaccurate"), prob.status
    nominal = np.zeros((K, 3))
    inner = np.zeros((K, 3))
    for k in Fn:
        nominal[k] = np.asarray(Fn[k].value).reshape(3)
        if internal:
            inner[k] = np.asarray(Fi[k].value).reshape(3)
    corner = np.array([np.asarray(F.value).reshape(3) for _, F in Fc]).reshape(-1, 3)
    if Fci:
        corner = corner + np.array([np.asarray(G.value).reshape(3) for _, G in Fci])
    return nominal, inner, corner


def _cross(p, F):
    return [p[1] * F[2] - p[2] * F[1], p[2] * F[0] - p[0] * F[2], p[0] * F[1] - p[1] * F[0]]


def grasp_truth(seed: int, T: int = 20, K: int = 4, model: ObjectModel | None = None, p_sliding: float = 0.0):
    """A self-consistent benchmark Truth of a box held in the air by a random grasp.

    Contact forces are random inside their cones; the box's acceleration and angular acceleration
    are those Newton–Euler gives for them (no table force). Returns ``(truth, model)``.
    """
    from benchmark.world.truth import Truth

    rng = np.random.default_rng(seed)
    model = box_model() if model is None else model
    contacts, force = random_grasp(rng, T, K, model, p_sliding=p_sliding)
    q = rng.normal(size=(T, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    R = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )
    kin = kinematics_for(rng, force, contacts.point, model, rot=R)
    zk = np.zeros((T, K, 3))
    truth = Truth(
        t=kin.t, box_pos=kin.pos, box_quat=q, box_vel=kin.vel, box_omega=kin.omega, box_acc=kin.acc,
        box_alpha=kin.alpha, imu_acc=np.einsum("tji,tj->ti", R, kin.acc - GRAVITY),
        imu_gyro=np.einsum("tji,tj->ti", R, kin.omega), finger_names=np.array(contacts.finger_names),
        contact_active=contacts.active, contact_sliding=contacts.sliding, contact_point=contacts.point,
        contact_normal=contacts.normal, contact_force=force, env_force=np.zeros((T, 3)),
        env_torque=np.zeros((T, 3)), fingertip_pos=zk, hand_qpos=np.zeros((T, 12)), mass=model.mass_kg,
        inertia=model.inertia, gravity=GRAVITY, net_wrench_mean=_resultant(R, contacts.point, force),
    )
    return truth, model


def _resultant(R: np.ndarray, point: np.ndarray, force: np.ndarray) -> np.ndarray:
    """The fingers' resultant wrench in the world frame, (T, 6): the frame mean of a truth made without time steps."""
    f = np.einsum("tij,tkj->tki", R, force)
    r = np.einsum("tij,tkj->tki", R, point)
    return np.concatenate([f.sum(axis=1), np.cross(r, f).sum(axis=1)], axis=1)
