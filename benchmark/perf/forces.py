"""Speed of the nominal force program: ours (Clarabel, direct API) against cvxpy with parameters.

    python -m benchmark.perf.forces [--frames N] [--repeats R] [--seed S] [--grasp G]

Frames: a simulated lift with the truth's contacts and kinematics (an oracle input: speed does not
depend on where the contacts come from), restricted to the frames where 4-5 fingers touch, none
slides and the box is off the table, and to the most frequent set of touching fingers, so cvxpy
compiles one parametrised problem (DPP: the wrench matrix and the required wrench are parameters)
and then only re-solves. Both sides solve the same frames with Clarabel; ours includes validation,
assembly of the cone program and unpacking of the forces, cvxpy only ``problem.solve``.

Ours is timed per frame (``ForceSolution.solve_time_s``: assembly, solver update, solve and
unpacking; median over frames and runs) and as whole calls (validation and per-sequence geometry
included; call time over frames, median of ``repeats`` runs). cvxpy is timed per frame
(``problem.solve``), its runs interleaved with ours; median over frames. The ratio is the median
over runs of cvxpy's median frame time over ours. Both wall-clock and process CPU time are printed: the machine is shared, so the CPU times
and the ratios are the steadier numbers.
Targets: <= 0.15 ms per frame and >= 10x faster than cvxpy.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from benchmark.world.contact_error import contacts_from_truth
from benchmark.world.motion import oracle_kinematics
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from fsv import Contacts, Kinematics
from fsv.forces import FrameStatus, nominal_forces, required_wrench, table_contacts, tangent_basis, to_object_frame

TARGET_MS = 0.15
TARGET_RATIO = 10.0


def _frames(seed: int, grasp: int = 0):
    ep = simulate(Scenario(task="lift", seed=seed, grasp=grasp))
    tr = ep.truth
    kin, con = oracle_kinematics(tr), contacts_from_truth(tr)
    n = con.active.sum(axis=1)
    ok = (n >= 4) & (n <= 5) & ~con.sliding.any(axis=1) & ~table_contacts(kin, ep.object_model).active.any(axis=1)
    keys = [row.tobytes() for row in con.active]
    counts = {}
    for t in np.flatnonzero(ok):
        counts[keys[t]] = counts.get(keys[t], 0) + 1
    if not counts:
        raise SystemExit("perf_forces: the lift has no frame with 4-5 static fingers off the table")
    best = max(counts, key=counts.get)
    idx = np.array([t for t in np.flatnonzero(ok) if keys[t] == best])
    return ep, kin, con, idx


def _subset(kin, con, idx):
    k = Kinematics(kin.t[idx], kin.pos[idx], kin.rot[idx], kin.vel[idx], kin.acc[idx], kin.omega[idx],
                   kin.alpha[idx], kin.valid[idx], kin.method)
    c = Contacts(con.finger_names, con.active[idx], con.sliding[idx], con.point[idx], con.normal[idx],
                 con.slide_dir[idx])
    return k, c


def _cvxpy_solver(K: int, mu: float):
    import cvxpy as cp  # lazy: optional cvxpy (0.7 s)

    W = cp.Parameter((6, 3 * K))
    w = cp.Parameter(6)
    x = cp.Variable(3 * K)
    cons = [W @ x == w] + [cp.SOC(mu * x[3 * k], x[3 * k + 1 : 3 * k + 3]) for k in range(K)]
    prob = cp.Problem(cp.Minimize(cp.sum_squares(x)), cons)
    assert prob.is_dpp()
    return prob, W, w, x


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmark.perf.forces", description=__doc__.split("\n")[0])
    p.add_argument("--frames", type=int, default=200, help="at most this many frames")
    p.add_argument("--repeats", type=int, default=7, help="timed repetitions of our sequence solve")
    p.add_argument("--seed", type=int, default=0, help="scenario seed of the lift")
    p.add_argument("--grasp", type=int, default=0, help="grasp of the lift (2: five fingers, see sim_assets/grasps.yaml)")
    args = p.parse_args(argv)
    import cvxpy as cp  # lazy: optional cvxpy (0.7 s)

    ep, kin, con, idx = _frames(args.seed, args.grasp)
    idx = idx[: args.frames]
    k, c = _subset(kin, con, idx)
    model = ep.object_model
    g = ep.truth.gravity
    fingers = np.flatnonzero(c.active[0])
    K = len(fingers)

    prob, W, w, x = _cvxpy_solver(K, model.friction)
    req = to_object_frame(k.rot, required_wrench(k, model, g))
    n = c.normal[:, fingers]
    tx, ty = tangent_basis(n)
    dirs = np.stack([n, tx, ty], axis=2)  # (T, K, 3, 3)
    cols = np.concatenate([dirs, np.cross(c.point[:, fingers, None, :], dirs)], axis=-1)  # (T, K, 3, 6)
    Wall = cols.reshape(len(idx), 3 * K, 6).transpose(0, 2, 1)

    sol = nominal_forces(k, c, model, gravity=g)  # warm-up (imports, first solver build)
    W.value, w.value = Wall[0], req[0]
    prob.solve(solver=cp.CLARABEL)  # the first solve compiles the problem
    # Interleave the two so that the shared machine's load hits both alike.
    ours, ours_frame, ours_cpu, times, cpu, its, ratios, diff = [], [], [], [], [], [], [], 0.0
    for _ in range(args.repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        sol = nominal_forces(k, c, model, gravity=g)
        ours.append((time.perf_counter() - t0) / len(idx))
        ours_cpu.append((time.process_time() - c0) / len(idx))
        ours_frame.append(sol.solve_time_s)
        run_times = []
        for j in range(len(idx)):
            W.value, w.value = Wall[j], req[j]
            t0, c0 = time.perf_counter(), time.process_time()
            prob.solve(solver=cp.CLARABEL)
            run_times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            its.append(prob.solver_stats.num_iters)
            F = np.einsum("kd,kdi->ki", x.value.reshape(K, 3), dirs[j])
            diff = max(diff, float(np.abs(F - sol.force[j, fingers]).max()))
        times += run_times
        ratios.append(np.median(run_times) / np.median(sol.solve_time_s))
    ours_ms, ours_cpu_ms = float(np.median(ours) * 1e3), float(np.median(ours_cpu) * 1e3)
    frame_ms = float(np.median(np.concatenate(ours_frame)) * 1e3)
    cvx_ms, cvx_cpu_ms = float(np.median(times) * 1e3), float(np.median(cpu) * 1e3)
    ratio = float(np.median(ratios))
    print(f"frames: {len(idx)} of a simulated lift, {K} static finger contacts each (oracle contacts and kinematics)")
    print(f"ours  (Clarabel direct, updated per frame): {frame_ms:.3f} ms/frame wall (median over frames of "
          f"assembly + update + solve + unpacking); whole call incl. validation {ours_ms:.3f} ms/frame wall, "
          f"{ours_cpu_ms:.3f} ms CPU (median of {args.repeats} runs); median {np.median(sol.iterations):.0f} "
          f"iterations, {sol.count(FrameStatus.OPTIMAL)} optimal")
    print(f"cvxpy (DPP parameters, Clarabel):           {cvx_ms:.3f} ms/frame wall, {cvx_cpu_ms:.3f} ms CPU "
          f"(median over frames), median {np.median(its):.0f} iterations")
    print(f"ratio cvxpy / ours: {ratio:.1f}x wall (median over interleaved runs), {cvx_cpu_ms / ours_cpu_ms:.1f}x CPU   "
          f"max force difference: {diff:.2e} N")
    print(f"targets (median frame, wall): <= {TARGET_MS} ms/frame: {'met' if frame_ms <= TARGET_MS else 'NOT met'}; "
          f">= {TARGET_RATIO:.0f}x: {'met' if ratio >= TARGET_RATIO else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
