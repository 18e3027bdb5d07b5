"""The articulated hand fitted to the depth the box and the table leave unexplained.

Articulated ICP with Levenberg-Marquardt, as in model-based hand trackers: the hand is the known
capsule model (`fsv.HandModel`, palm pose plus n >= 20 hinge angles). The data are the pixels near
the predicted hand that lie ``scene_k`` noise sigmas in front of the predicted box-and-table depth:

* where the camera ray of such a pixel hits a capsule, the residual is observed minus predicted
  depth along the ray (ray-capsule casting: only the visible front surface explains a pixel, so
  depth noise cannot pull points onto the far side of a thin finger);
* elsewhere it is the signed distance of the observed point to its nearest capsule surface;
* free space: the other pixels of the region, which see the box or the table, are compared with
  the model's depth wherever the model puts a capsule on their ray (render and compare, as in the
  paper's tracker). A capsule predicted where the camera sees the farther box face is wrong, so a
  finger hovering in front of a face is not fitted onto it, and a finger lying on a face is
  pulled back to it by the pixels whose noise hid it among the face's.

Both use robust Cauchy weights and analytic Jacobians: a surface point x on segment s moves by
dt + dw x (x - palm) + sum_j dq_j a_j x (x - pivot_j) over the hinges j of s and its ancestors.
Extra residual rows keep the fit physical and coherent in time:

* temporal smoothness: palm and joints stay near a constant-velocity prediction (a finger that
  cannot be seen keeps its last pose: the paper's occlusion prior at the level of the hand);
* no hand-box interpenetration: capsule samples are pushed out of the tracked box;
* grasp closure: a finger hidden from the camera whose pad is near the box flexes until the pad
  meets the surface (fingers wrap the object they hold);
* grasp rigidity: while the box is held (at least two digits have touched it for a few frames),
  each such digit's pad stays where it was on the box's surface, in the box's frame and along the
  face, unless the depth says otherwise (established contacts do not slide without evidence);
* joint limits: every step is projected onto the model's joint ranges.

A step is taken only if it lowers the robust cost (Levenberg-Marquardt). When the hand moves, a
second start from the last pose competes with the constant-velocity prediction, and when few
observed points agree with the fit a small particle search over the palm's pose re-initialises it
(the paper's tracker is a particle swarm over the whole configuration).

A local fit cannot leave some wrong configurations that the render-and-compare cost does tell
apart: a finger fitted where its neighbour is while the neighbour hovers, two neighbours swapped,
a finger lost while hidden. So in every frame a few alternative finger configurations (a digit
back at its first-frame configuration, a neighbour's configuration copied onto a finger, two
neighbours swapped; taken in turn) are refined from the fitted palm, and the lowest cost wins."""

from __future__ import annotations

import numpy as np

from fsv.errors import InputError
from fsv.linalg import dot, mm, norm, rows_mt, solve
from fsv.models import HandModel, ObjectModel
from fsv.rotation import exp_so3, log_so3
from fsv.track.articulation import mirror_upper
from fsv.track.camera import CameraRays
from fsv.track.capsules import ray_capsules
from fsv.track.hand import lm
from fsv.track.hand.config import HandTrackerConfig
from fsv.track.hand.kinematics import HandKinematics
from fsv.track.hand.state import HandFit, HandState
from fsv.track.hand_system import (
    box_signed_distance,
    hand_normal_equations,
    rigidity_rows,
)
from fsv.track.kernel_args import readonly
from fsv.types import Calibration


class HandTracker:
    """Tracks the articulated hand frame by frame.

    Args:
        calib: Camera calibration.
        hand_model: The known hand.
        object_model: The known box (for the no-interpenetration rows).
        init: First-frame configuration estimate.
        config: Tracker parameters.
        rng: Generator of the re-initialisation search.
        table_z: Height of the table plane, [m].
    """

    def __init__(self, calib: Calibration, hand_model: HandModel, object_model: ObjectModel, init: HandState, *,
                 config: HandTrackerConfig | None = None, rng: np.random.Generator | None = None,
                 table_z: float = 0.0):
        if not isinstance(init, HandState):
            raise InputError(f"init must be a HandState, got {type(init).__name__}")
        if init.joints.shape != (hand_model.num_joints,):
            raise InputError(f"init.joints must have {hand_model.num_joints} angles, got {init.joints.shape}")
        self.calib = calib
        self.kin = HandKinematics(hand_model)
        self.model = hand_model
        self.half = object_model.half_extents
        self.rays = CameraRays.from_calibration(calib, table_z=table_z)
        self.config = config or HandTrackerConfig()
        self.rng = rng if rng is not None else np.random.default_rng(0)
        lo, hi = (np.ascontiguousarray(hand_model.joint_range[:, i], dtype=np.float64) for i in (0, 1))
        self.lo, self.hi = lo, hi
        self.history = [HandState(init.palm_pos, init.palm_rot, np.clip(init.joints, lo, hi))]
        K = len(hand_model.finger_names)
        self.hidden = np.zeros(K, dtype=bool)  # unseen in the last frame
        # Grasp rigidity: frames each digit has touched the box; the digits with an established
        # contact (indices) and every pad in the box's frame with its face's normal axis (the rows
        # of the next frame).
        self.touching = np.zeros(K, dtype=np.int64)
        self.rigid = np.zeros(0, dtype=np.int64)
        self.anchor = np.zeros((K, 3))
        self.anchor_axis = np.zeros(K, dtype=np.int64)
        self.frame = 0
        # Every finger's hinges, proximal first, and the first-frame configuration (the re-seed of
        # the finger search).
        self.finger_joints = [np.flatnonzero(self.kin.moves[int(tip)] & (self.kin.finger_of_segment[hand_model.joint_segment] == k))
                              for k, tip in enumerate(hand_model.fingertip_segment)]
        self.init_joints = self.history[0].joints.copy()
        # Flexion hinges turn about the segment's x axis (abduction about its z axis).
        self.flexion = (np.abs(hand_model.joint_axis[:, 0]) > 0.9).astype(float)
        # Capsule samples for the no-interpenetration rows: ends and middle of every capsule.
        fromto = hand_model.geom_fromto
        s = np.array([0.0, 0.5, 1.0])
        self.pen_local = readonly(
            (fromto[:, None, :3] * (1 - s)[None, :, None] + fromto[:, None, 3:] * s[None, :, None]).reshape(-1, 3))
        self.pen_segment = readonly(np.repeat(hand_model.geom_segment, 3), np.int64)
        self.pen_radius = readonly(np.repeat(hand_model.geom_radius, 3))
        # The model's arrays as the compiled normal equations take them (read-only, whatever the
        # model's origin: one compiled specialisation, fsv.track.kernel_args).
        self._geom_segment = readonly(hand_model.geom_segment, np.int64)
        self._geom_fromto = readonly(hand_model.geom_fromto)
        self._geom_radius = readonly(hand_model.geom_radius)
        self._tip_segment = readonly(hand_model.fingertip_segment, np.int64)
        self._tip_offset = readonly(hand_model.fingertip_offset)
        self._tip_radius = readonly(hand_model.fingertip_radius)
        kin = self.kin  # ... and the kinematics as the compiled fit takes them (fsv.track.hand.lm.system)
        self._kin_arrays = (kin.hinge_K, kin.hinge_KK, kin.parent, kin.offset_pos, kin.offset_rot_c, kin.joint_start,
                            kin.joint_ids, kin.joint_axis, kin.moves)

    def predict(self) -> HandState:
        """Constant-velocity prediction of the palm; joints keep their last values."""
        last = self.history[-1]
        if len(self.history) < 2:
            return last
        prev = self.history[-2]
        rot = mm(exp_so3(log_so3(mm(last.palm_rot, prev.palm_rot.T))), last.palm_rot)
        return HandState._from_fit(2 * last.palm_pos - prev.palm_pos, rot, last.joints)

    def _candidates(self, depth_m, scene_depth, state: HandState, sigma: float):
        """Flat indices of the pixels near the predicted hand that lie in front of the scene, and
        of (a subsample of) the other valid pixels near it, which see the scene."""
        pose = self.kin.pose(state)
        a, b = self.kin.capsules(pose[0], pose[1])
        uvz = self.rays.project(self.calib, np.concatenate([a, b]))
        uvz = uvz[uvz[:, 2] > 0.05]
        W, H = self.rays.width, self.rays.height
        if uvz.shape[0] == 0:
            return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
        m = self.config.roi_margin_px
        u0, v0 = np.maximum(np.floor(uvz[:, :2].min(0)).astype(int) - m, 0)
        u1, v1 = np.minimum(np.ceil(uvz[:, :2].max(0)).astype(int) + m, [W - 1, H - 1])
        if u1 <= u0 or v1 <= v0:
            return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
        vv, uu = np.mgrid[v0 : v1 + 1, u0 : u1 + 1]
        idx = (vv * W + uu).reshape(-1)
        z = depth_m.reshape(-1)[idx].astype(float)
        zs = np.asarray(scene_depth(idx), dtype=float)
        keep = (z > 0) & (z < zs - self.config.scene_k * sigma)
        scene = idx[(z > 0) & ~keep]
        n_free = int(self.config.free_space_points)
        scene = scene[:: int(np.ceil(scene.size / n_free))] if n_free and scene.size > n_free else scene[: n_free]
        if scene.size:  # only the rays that pass near the predicted hand can meet it this frame
            inflated = self.model.geom_radius + self.config.free_space_margin_m
            scene = scene[ray_capsules(self.rays.origin, self.rays.ray[scene], a, b, inflated, surface=False)[1] >= 0]
        idx = idx[keep]
        if idx.size > self.config.max_points:
            idx = idx[:: int(np.ceil(idx.size / self.config.max_points))]
        return idx, scene

    def _system(self, st: HandState, rays, z_obs, free, prior: HandState, box_pos, box_rot, sigma: float):
        """Normal equations (A, g), robust cost and explained fraction of a configuration.

        The residuals (see the module docstring and :func:`fsv.track.hand_system.hand_normal_equations`):

        * hand candidates: where the camera ray hits a capsule (in front of the observation by less
          than 3 sigma) observed minus predicted depth along the ray, else the signed distance of
          the observed point to its nearest capsule (candidates farther than ``assign_max_m`` pull
          nothing); Cauchy weights;
        * free space: pixels that see the box or the table where the model puts a capsule on
          their ray, observed minus predicted depth;
        * no interpenetration with the box, grasp closure of hidden fingers near it;
        * grasp rigidity of the established contacts (:func:`fsv.track.hand_system.rigidity_rows`);
        * temporal smoothness about the prediction (the occlusion prior for unseen fingers).

        ``rays`` (N, 3) and ``z_obs`` (N,) are the candidates' rays and depths; ``free`` is
        ``(rays (M, 3), depth (M,))`` of the pixels that see the scene."""
        c = self.config
        n = self.model.num_joints
        pos, rot, axis, pivot = self.kin.pose(st)
        box_pos = np.ascontiguousarray(box_pos, dtype=np.float64)
        box_rot = np.ascontiguousarray(box_rot, dtype=np.float64)
        A, g, cost, explained = hand_normal_equations(
            pos, rot, axis, pivot, self.kin.moves, self._geom_segment, self._geom_fromto, self._geom_radius,
            self.rays.origin, rays, z_obs, free[0], free[1], float(sigma), float(c.cauchy_k), float(c.assign_max_m),
            self.pen_local, self.pen_segment, self.pen_radius, float(c.penetration_m), box_pos, box_rot,
            self.half, self.hidden, self._tip_segment, self._tip_offset, self._tip_radius, self.flexion,
            float(c.closure_m), float(c.closure_range_m))
        if self.rigid.size:
            cost += rigidity_rows(A, g, pos, rot, axis, pivot, self.kin.moves, self._tip_segment, self._tip_offset,
                                  self.rigid, self.anchor, self.anchor_axis, box_pos, box_rot,
                                  (sigma / c.rigidity_m) ** 2)
        # Temporal smoothness about the prediction (the occlusion prior for unseen fingers).
        for sl, sd_, res in ((slice(0, 3), c.smooth_pos_m, st.palm_pos - prior.palm_pos),
                             (slice(3, 6), c.smooth_rot_rad, log_so3(mm(st.palm_rot, prior.palm_rot.T))),
                             (slice(6, 6 + n), c.smooth_joint_rad, st.joints - prior.joints)):
            ws = (sigma / sd_) ** 2
            idx = np.arange(sl.start, sl.stop)
            A[idx, idx] += ws
            g[sl] -= ws * res
            cost += 0.5 * ws * float(dot(res, res))
        mirror_upper(A)
        return A, g, cost, explained

    def _update_rigidity(self, tips: np.ndarray, box_pos: np.ndarray, box_rot: np.ndarray) -> None:
        """Which digits touch the box after this frame's fit (pad centres ``tips`` (K, 3), [m]), and
        the anchors of the next frame's grasp-rigidity rows."""
        c = self.config
        if not c.rigidity_frames:
            return
        u = rows_mt(tips - box_pos[None, :], box_rot.T)  # box frame
        dist, _ = box_signed_distance(u, self.half)
        touch = dist - self.model.fingertip_radius <= c.rigidity_gap_m
        self.touching = np.where(touch, self.touching + 1, 0)
        established = np.flatnonzero(self.touching >= c.rigidity_frames)
        self.rigid = established if established.size >= 2 else established[:0]
        self.anchor = u
        self.anchor_axis = np.argmax(np.abs(u) - self.half[None, :], axis=1)

    def _solve(self, idx, z_obs, free, state: HandState, prior: HandState, box_pos, box_rot, sigma: float):
        """Levenberg-Marquardt from ``state``: a step is taken only if it lowers the robust cost."""
        c = self.config
        rays = self.rays.ray[idx]
        if lm.AVAILABLE:
            fitted = self._solve_compiled(rays, z_obs, free, state, prior, box_pos, box_rot, sigma)
            if fitted is not None:
                return fitted
        n = self.model.num_joints
        args = (rays, z_obs, free, prior, box_pos, box_rot, sigma)
        A, g, cost, explained = self._system(state, *args)
        lam = 1e-3
        for _ in range(c.iterations):
            step = solve(A + lam * np.diag(np.diag(A)) + 1e-12 * np.eye(6 + n), g)
            step[:3] = np.clip(step[:3], -0.02, 0.02)
            step[3:] = np.clip(step[3:], -0.3, 0.3)
            cand = HandState._from_fit(state.palm_pos + step[:3], mm(exp_so3(step[3:6]), state.palm_rot),
                                       np.clip(state.joints + step[6:], self.lo, self.hi))
            A2, g2, cost2, expl2 = self._system(cand, *args)
            if cost2 < cost:
                state, A, g, cost, explained = cand, A2, g2, cost2, expl2
                lam = max(lam / 3, 1e-6)
                if np.max(np.abs(step)) < 1e-5:
                    break
            else:
                lam *= 8
        return state, explained, cost

    def _solve_compiled(self, rays, z_obs, free, state: HandState, prior: HandState, box_pos, box_rot, sigma: float):
        """:meth:`_solve` in one compiled call (:func:`fsv.track.hand.lm.solve`, the same bits), or
        None where a rotation update left SO(3) (the NumPy loop takes its singular-value branch)."""
        c = self.config
        data = (self._geom_segment, self._geom_fromto, self._geom_radius, self.rays.origin,
                readonly(rays), readonly(z_obs), readonly(free[0]), readonly(free[1]), float(sigma),
                float(c.cauchy_k), float(c.assign_max_m), self.pen_local, self.pen_segment, self.pen_radius,
                float(c.penetration_m), self.half, self.hidden, self._tip_segment, self._tip_offset, self._tip_radius,
                self.flexion, float(c.closure_m), float(c.closure_range_m))
        status, moved, pos, rot, joints, explained, cost = lm.solve(
            *(readonly(v) for v in (state.palm_pos, state.palm_rot, state.joints,
                                        prior.palm_pos, prior.palm_rot, prior.joints)),
            (sigma / c.smooth_pos_m) ** 2, (sigma / c.smooth_rot_rad) ** 2, (sigma / c.smooth_joint_rad) ** 2,
            self._kin_arrays, data, self.rigid, self.anchor, self.anchor_axis, (sigma / c.rigidity_m) ** 2,
            readonly(box_pos), readonly(box_rot), self.lo, self.hi,
            int(c.iterations))
        if status == lm.SINGULAR:
            raise np.linalg.LinAlgError("singular matrix")
        if status == lm.FALLBACK:
            return None
        return (HandState._fitted(pos, rot, joints) if moved else state), explained, cost

    def predicted_depth(self, index: np.ndarray, inflate_m: float = 0.004) -> np.ndarray:
        """Depth of the predicted hand (capsules inflated by ``inflate_m``) at flat pixel indices,
        (N,) -> (N,) in [m], +inf where it is absent: the occluder the box tracker leaves out."""
        st = self.predict()
        pos, rot, _, _ = self.kin.pose(st)
        a, b = self.kin.capsules(pos, rot)
        return ray_capsules(self.rays.origin, self.rays.ray[index], a, b, self.model.geom_radius + inflate_m,
                            surface=False)[0]

    def update(self, depth_m: np.ndarray, scene_depth, box_pos, box_rot, sigma: float) -> HandFit:
        """Tracks one frame.

        Args:
            depth_m: Observed depth image, shape (H, W), [m].
            scene_depth: Depth of the tracked box in front of the table: a function of flat
                pixel indices (N,) returning depths (N,) in [m] (+inf where nothing is predicted).
            box_pos: Tracked box centre, shape (3,), [m].
            box_rot: Tracked world_R_object, shape (3, 3).
            sigma: Depth noise scale, [m].
        """
        depth_m = np.asarray(depth_m)
        if depth_m.shape != (self.rays.height, self.rays.width):
            raise InputError(f"depth must have shape ({self.rays.height}, {self.rays.width}), got {depth_m.shape}")
        if not callable(scene_depth):
            raise InputError(f"scene_depth must be a function of pixel indices, got {type(scene_depth).__name__}")
        c = self.config
        prior = self.predict()
        idx, scene = self._candidates(depth_m, scene_depth, prior, sigma)
        z_obs = depth_m.reshape(-1)[idx].astype(float)
        free = (self.rays.ray[scene], depth_m.reshape(-1)[scene].astype(float))
        # Two starts when the hand moves: the constant-velocity prediction and the last pose (the
        # hand may have stopped); the lower robust cost wins.
        state, explained, cost = self._solve(idx, z_obs, free, prior, prior, box_pos, box_rot, sigma)
        last = self.history[-1]
        if norm(prior.palm_pos - last.palm_pos) > 0.004:
            alt = self._solve(idx, z_obs, free, last, prior, box_pos, box_rot, sigma)
            if alt[2] < cost:
                state, explained, cost = alt
        if c.finger_hypotheses and idx.size:
            state, explained, cost = self._finger_search(idx, z_obs, free, state, explained, cost, prior, box_pos,
                                                         box_rot, sigma)
        self.frame += 1
        reinit = False
        if explained < c.lost_fraction and idx.size >= 50:
            state, explained, reinit = self._search(idx, z_obs, free, state, explained, cost, prior, box_pos, box_rot,
                                                    sigma)
        self.history = (self.history + [state])[-2:]
        pose = self.kin.pose(state)
        tips = self.kin.fingertips(pose[0], pose[1])
        observed = self._observed(idx, z_obs, pose, sigma)
        self.hidden = ~observed
        self._update_rigidity(tips, np.asarray(box_pos, dtype=float), np.asarray(box_rot, dtype=float))
        return HandFit(state=state, fingertips=tips, observed=observed, explained=explained, reinitialised=reinit)

    def _observed(self, idx, z_obs, pose, sigma) -> np.ndarray:
        """Fingers whose two distal segments are the first surface hit, at the observed depth,
        on at least ``visible_min_points`` candidate pixels."""
        K = len(self.model.finger_names)
        if idx.size == 0:
            return np.zeros(K, dtype=bool)
        a, b = self.kin.capsules(pose[0], pose[1])
        zh, geom, _, _ = ray_capsules(self.rays.origin, self.rays.ray[idx], a, b, self.model.geom_radius, surface=False)
        seen = (geom >= 0) & (np.abs(z_obs - zh) < 2 * sigma)
        seg = np.where(seen, self.model.geom_segment[np.maximum(geom, 0)], -1)
        counts = np.zeros(K, dtype=int)
        for k, tip in enumerate(self.model.fingertip_segment):
            counts[k] = int(np.sum((seg == tip) | (seg == self.model.parent[tip])))
        return counts >= self.config.visible_min_points

    def _search(self, idx, z_obs, free, state, explained, cost, prior, box_pos, box_rot, sigma):
        """Particle search over the palm pose when the fit explains too few points."""
        best, best_e, best_cost, reinit = state, explained, cost, False
        for _ in range(self.config.particles):
            cand = HandState._from_fit(state.palm_pos + self.rng.normal(0.0, 0.02, 3),
                                       mm(exp_so3(self.rng.normal(0.0, 0.2, 3)), state.palm_rot), state.joints)
            fit, e, cst = self._solve(idx, z_obs, free, cand, prior, box_pos, box_rot, sigma)
            if cst < best_cost:
                best, best_e, best_cost, reinit = fit, e, cst, True
        return best, best_e, reinit

    def finger_hypotheses(self, joints: np.ndarray) -> list[tuple[str, np.ndarray]]:
        """Alternative hinge angles for a fit, each with a name: every digit back at its
        first-frame configuration (``"init:<finger>"``); for the fingers (the digits after the
        thumb), each neighbour's configuration copied onto a finger (``"copy:<from>-><to>"``) and
        every pair of neighbours swapped (``"swap:<a>-<b>"``). Hypotheses equal to ``joints`` are
        left out.

        Args:
            joints: The fitted hinge angles, shape (n,), [rad].

        Returns:
            ``(name, hinge angles (n,))`` pairs, angles clipped to the joint ranges.
        """
        fj, names, out = self.finger_joints, self.model.finger_names, []
        K = len(fj)
        for k in range(K):
            q = joints.copy()
            q[fj[k]] = self.init_joints[fj[k]]
            out.append((f"init:{names[k]}", q))
        for k in range(1, K):
            for src in (k - 1, k + 1):
                if 1 <= src < K and len(fj[src]) == len(fj[k]):
                    q = joints.copy()
                    q[fj[k]] = joints[fj[src]]
                    out.append((f"copy:{names[src]}->{names[k]}", q))
        for k in range(1, K - 1):
            if len(fj[k]) == len(fj[k + 1]):
                q = joints.copy()
                q[fj[k]], q[fj[k + 1]] = joints[fj[k + 1]], joints[fj[k]]
                out.append((f"swap:{names[k]}-{names[k + 1]}", q))
        out = [(name, np.clip(q, self.lo, self.hi)) for name, q in out]
        return [(name, q) for name, q in out if np.max(np.abs(q - joints)) > 1e-9]

    def _finger_search(self, idx, z_obs, free, state, explained, cost, prior, box_pos, box_rot, sigma):
        """Finger configurations that a local fit cannot reach (a finger fitted onto its
        neighbour's place, one that hovers where its neighbour lies, one lost while hidden) compete
        with the fit: each of :meth:`finger_hypotheses` is refined from the fitted palm and the
        lowest robust cost wins (render and compare, as the paper's particle swarm scores its
        hypotheses)."""
        best = (state, explained, cost)
        hyps = self.finger_hypotheses(state.joints)
        m = int(self.config.finger_hypotheses)
        if m < len(hyps):  # in turn: frame i tries hypotheses i*m ... i*m + m - 1 (cyclically)
            hyps = [hyps[(self.frame * m + j) % len(hyps)] for j in range(m)]
        for _, q in hyps:
            fit = self._solve(idx, z_obs, free, HandState._from_fit(state.palm_pos, state.palm_rot, q), prior,
                              box_pos, box_rot, sigma)
            if fit[2] < best[2]:
                best = fit
        return best
