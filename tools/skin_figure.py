"""Writes docs/pictures/skin.png and prints the skin's numbers for docs/scenarios.md.

    python tools/skin_figure.py [--out docs/pictures/skin.png]

Panels: the default lift's skin in depth beside the primitives a method is given under exact
knowledge and beside the lab's generic hand (``--knowledge lab``: the template stretched to a
ruler's length and breadth), both at the true pose; the skin's depth difference to the lab's hand;
a close-up of the thumb's pulp flattened on the box, seen from inside the box (the box not drawn);
the pulp's patch area against its normal force. Printed: the depth difference over hand pixels
(median and 90th percentile) against both models on four episodes, the collision gap and the patch
areas.
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _shade(depth, K):
    """Lambertian shading of a depth image lit from the camera, NaN where empty."""
    H, W = depth.shape
    u, v = np.meshgrid(np.arange(W), np.arange(H))
    z = np.where(depth > 0, depth, np.nan)
    P = np.stack([(u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z, z], axis=-1)
    n = np.cross(np.gradient(P, axis=1), np.gradient(P, axis=0))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.abs(n[..., 2])


def _model_render(skin_episode, hand_model):
    """Depth and labels of the table, the box and ``hand_model``'s capsules at the truth's hand pose,
    from the episode's camera, every frame (the model's joints set to the true angles)."""
    import mujoco

    from benchmark.camera import raster_kernels as rk
    from benchmark.camera.depth import DepthRenderer
    from benchmark.camera.scene import LABEL_FINGER0, LABEL_PALM, world_labels
    from benchmark.camera.views import camera_of
    from benchmark.world.assets import build_world, set_frame
    from fsv.hand import capsule_endpoints, finger_of_segment, forward_kinematics_qpos

    sc, tr = skin_episode.scenario, skin_episode.truth
    world = build_world(sc)
    camera = camera_of(sc.view)
    labels = world_labels(world)
    labels[labels >= LABEL_PALM] = 0
    scene = DepthRenderer(world.model, camera, labels)
    data = mujoco.MjData(world.model)
    cam_from_world = np.linalg.inv(camera.T_world_cam)
    K = camera.K
    finger_of = finger_of_segment(hand_model)
    seg = np.asarray(hand_model.geom_segment)
    cap_label = np.where(finger_of[seg] >= 0, LABEL_FINGER0 + finger_of[seg], LABEL_PALM).astype(np.uint8)
    radius = np.ascontiguousarray(hand_model.geom_radius, dtype=np.float64)
    T = len(tr.t)
    depth = np.zeros((T, camera.height, camera.width), np.float32)
    lab = np.zeros((T, camera.height, camera.width), np.uint8)
    for k in range(T):
        set_frame(world, data, tr.box_pos[k], tr.box_quat[k], tr.hand_qpos[k])
        d0, l0 = scene.render(data.xpos, data.xmat)
        ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, tr.hand_qpos[k]))
        ends = np.ascontiguousarray(ends @ cam_from_world[:3, :3].T + cam_from_world[:3, 3])
        zbuf = np.where(d0 > 0, d0, np.inf).astype(np.float64)
        lbuf = l0.copy()
        rk.draw_capsules(ends, radius, cap_label, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
                         camera.znear, camera.zfar, zbuf, lbuf)
        rk.finish(zbuf, lbuf, depth[k], lab[k])
    return depth, lab


def _render_pair(sc):
    from benchmark.camera.render import render
    from benchmark.world.simulate import simulate

    return render(simulate(dataclasses.replace(sc, hand_surface="skin"))), render(simulate(sc))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "docs" / "pictures" / "skin.png")
    args = p.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from benchmark.camera.camera import Camera
    from benchmark.camera.depth import DepthRenderer, pulp_presses
    from benchmark.camera.pulp_patch import patch_area_m2
    from benchmark.camera.render import hand_skin
    from benchmark.camera.scene import world_labels
    from benchmark.camera.skin_stats import collision_gap, hand_depth_difference
    from benchmark.method.knowledge import given
    from benchmark.world.assets import build_world, hand_model, set_frame
    from benchmark.world.scenario import Scenario

    exact = dict(noise_m=0.0, sensor="ideal")
    scenarios = [Scenario(task="lift", seed=0, duration_s=3.0, **exact),
                 Scenario(task="rotate", user=1, grasp=1, seed=11, duration_s=3.0, **exact),
                 Scenario(task="place", user=3, grasp=2, seed=12, duration_s=3.0, **exact),
                 Scenario(task="lift", user=123, grasp=17, seed=13, duration_s=3.0, **exact)]
    for sc in scenarios:
        skin, prim = _render_pair(sc)
        lab_depth, lab_labels = _model_render(skin, given(skin, "lab-hand")[0])
        for name, (d, lb) in (("primitives", (prim.depth.depth_m, prim.labels)), ("lab's hand", (lab_depth, lab_labels))):
            stats = hand_depth_difference(skin.depth.depth_m, skin.labels, d, lb)
            print(f"{sc.task} u{sc.user} g{sc.grasp}: skin - {name} over hand pixels: median {stats['median_mm']:+.2f} mm, "
                  f"|median| {stats['median_abs_mm']:.2f} mm, 90th percentile {stats['p90_abs_mm']:.2f} mm; "
                  f"silhouettes differ on {100 * stats['silhouette_frac']:.1f} % of hand pixels")
        if sc is scenarios[0]:
            first = (skin, prim, lab_depth, lab_labels)
    hand = hand_model(scenarios[0])
    gap = collision_gap(hand)
    print(f"collision gap (user 0): pulp median {gap['pulp_mm'][0]:.2f} mm, max {gap['pulp_mm'][1]:.2f} mm; palm's palmar "
          f"line median {gap['palm_mm'][0]:.2f} mm, max {gap['palm_mm'][1]:.2f} mm (the hypothenar eminence); every "
          f"vertex from its segment's primitives: median {gap['skin_mm'][0]:.2f} mm, 90th percentile {gap['skin_mm'][1]:.2f} mm")
    forces = np.array([0.0, 0.25, 0.5, 1, 2, 3, 5, 7.5, 10, 15, 20])
    areas = np.array([[patch_area_m2(hand, k, f) * 1e6 for f in forces] for k in range(5)])
    for f, a in zip(forces, areas.T):
        print(f"patch at {f:g} N: thumb {a[0]:.0f} mm^2, index {a[1]:.0f} mm^2")

    skin, prim, lab_depth, lab_labels = first
    tr = skin.truth
    held = np.flatnonzero(tr.held & tr.contact_active[:, 0])
    k = int(held[len(held) // 2])
    K = skin.calib.K
    hand_px = (skin.labels[k] >= 9) | (prim.labels[k] >= 9)
    vv, uu = np.nonzero(hand_px | (skin.labels[k] == 2))
    v0, v1, u0, u1 = max(vv.min() - 6, 0), vv.max() + 6, max(uu.min() - 6, 0), uu.max() + 6
    fig, ax = plt.subplots(1, 6, figsize=(23, 4))
    for i, (d, title) in enumerate([(skin.depth.depth_m[k], "the skin (rendered)"),
                                    (prim.depth.depth_m[k], "the primitives (exact knowledge)"),
                                    (lab_depth[k], "the lab's generic hand (lab knowledge)")]):
        ax[i].imshow(_shade(d.astype(float), K)[v0:v1, u0:u1], cmap="gray", vmin=0, vmax=1)
        ax[i].set_title(title)
    diff = (skin.depth.depth_m[k].astype(float) - lab_depth[k]) * 1e3
    diff[~((skin.labels[k] >= 9) | (lab_labels[k] >= 9))] = np.nan
    im = ax[3].imshow(diff[v0:v1, u0:u1], cmap="RdBu", vmin=-10, vmax=10)
    ax[3].set_title("skin - lab's hand, depth [mm]")
    fig.colorbar(im, ax=ax[3], fraction=0.046)

    # the thumb's pulp seen from inside the box, looking back along the contact normal
    sc = dataclasses.replace(scenarios[0], hand_surface="skin")
    world = build_world(sc)
    import mujoco

    data = mujoco.MjData(world.model)
    set_frame(world, data, tr.box_pos[k], tr.box_quat[k], tr.hand_qpos[k])
    centre, push = pulp_presses(tr)
    n = push[k, 0] / np.linalg.norm(push[k, 0])
    c = centre[k, 0]
    zc = -n
    xc = np.cross(zc, [0.0, 0.0, 1.0])
    xc /= np.linalg.norm(xc)
    T = np.eye(4)
    T[:3, :3] = np.stack([xc, np.cross(zc, xc), zc], axis=1)
    dist = 0.10
    T[:3, 3] = c + n * dist
    cam = Camera(width=120, height=120, K=np.array([[350.0, 0, 59.5], [0, 350.0, 59.5], [0, 0, 1]]),
                 T_world_cam=T, fps=30.0, znear=0.01, zfar=1.0)
    labels = world_labels(world)
    labels[[world.box_geom, world.table_geom]] = 0
    r = DepthRenderer(world.model, cam, labels, skin=hand_skin(world))
    depth, lab = r.render(data.xpos, data.xmat, centre[k], push[k])
    height = (depth.astype(float) - dist) * 1e3
    height[lab < 9] = np.nan
    im = ax[4].imshow(height, cmap="magma", vmin=0, vmax=6)
    f_n = float(tr.contact_force[k, 0] @ tr.contact_normal[k, 0])
    ax[4].set_title(f"thumb pulp from inside the box, {f_n:.1f} N\n(height above the face [mm]; 0 = flat patch)")
    fig.colorbar(im, ax=ax[4], fraction=0.046)
    ax[5].plot(forces, areas[0], "o-", label="thumb")
    ax[5].plot(forces, areas[1], "s-", label="index")
    ax[5].set_xlabel("normal force [N]")
    ax[5].set_ylabel("flat patch area [mm$^2$]")
    ax[5].set_title("patch area against force")
    ax[5].grid(alpha=0.3)
    ax[5].legend()
    for a in ax[:5]:
        a.set_xticks([])
        a.set_yticks([])
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=90)
    tmp.replace(args.out)
    print(f"wrote {args.out} (frame {k}, thumb normal force {f_n:.1f} N)")


if __name__ == "__main__":
    main()
