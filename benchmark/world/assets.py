"""The simulated world of a scenario: table, box, hand and the palm's mocap target, as one MjModel.

:func:`build_world` composes ``sim_assets/world.xml`` (table and box) with the hand of the
scenario's user (``benchmark.world.hand``), the box mass of the scenario and a mocap body the palm is
welded to (a teleported palm cannot drag the box by friction; a welded free palm can). It returns
a :class:`World`: the compiled model plus every index the simulator, the renderer and the scorers
need. :func:`set_frame` poses a model from one frame of the truth so that every geom can be read.

The assets (``users.yaml``, ``grasps.yaml``, ``masses.yaml``, ``box.yaml``) are read here, and a
scenario index out of range fails with a :class:`~benchmark.errors.ScenarioError` that names the
accepted values.
"""

from __future__ import annotations

import functools
import importlib.resources
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mujoco
import numpy as np
import yaml

from benchmark.errors import ScenarioError
from benchmark.world.hand import hand_mjcf, pad_geoms
from benchmark.world.hand import hand_model as _hand_model_of
from benchmark.world.people import person, users  # noqa: F401 (users: re-exported)
from benchmark.world.scenario import Scenario
from benchmark.world.tasks import TASKS
from fsv import HandModel, ObjectModel
from fsv.hand import finger_of_segment

# Collision bits (see sim_assets/world.xml): the hand touches the box only, and only with its
# fingertip pads and its palm. The phalanx shafts are kinematic and visual only: every finger then
# touches the box at exactly one point (a sphere on a box gives one contact), where the paper's
# force sensors sit, so the per-finger truth (one force, one point) is exact and Newton-Euler
# holds; the grasp planner keeps the shafts clear of the box.
HAND_CONTYPE, HAND_CONAFFINITY = 2, 0


@functools.lru_cache(maxsize=None)
def _asset(name: str):
    return yaml.safe_load(importlib.resources.files("sim_assets").joinpath(name).read_text())


def box_spec() -> dict:
    """``sim_assets/box.yaml``: size, friction coefficients, start position."""
    return _asset("box.yaml")


def grasps() -> list[dict]:
    """``sim_assets/grasps.yaml``: the grasps (pad spots on the box faces, object frame)."""
    return _asset("grasps.yaml")


def masses() -> list[dict]:
    """``sim_assets/masses.yaml``: the box's mass configurations."""
    return _asset("masses.yaml")


def _pick(kind: str, items: list, index: int) -> dict:
    if not 0 <= index < len(items):
        names = ", ".join(f"{i} ({it['name']})" for i, it in enumerate(items))
        raise ScenarioError(f"{kind} {index} does not exist; accepted: {names}")
    return items[index]


def user_of(scenario: Scenario) -> dict:
    """The scenario's user: a named one of ``users.yaml`` (0-4) or a drawn person
    (``benchmark.world.people.person``), with its ``anatomy``."""
    return person(scenario.user)


def mass_of(scenario: Scenario) -> dict:
    """The scenario's mass entry; raises ScenarioError naming the accepted indices."""
    return _pick("mass", masses(), scenario.mass)


def validate(scenario: Scenario) -> None:
    """Checks that the scenario's task, user, grasp and mass exist and its duration suits the task.

    Raises:
        ScenarioError: Naming the bad value and the accepted ones.
    """

    if scenario.task not in TASKS:
        raise ScenarioError(f"unknown task {scenario.task!r}; accepted: {', '.join(TASKS)}")
    task = TASKS[scenario.task]
    if scenario.duration_s is not None and scenario.duration_s < task.min_duration_s:
        raise ScenarioError(f"duration {scenario.duration_s!r} s is too short for task {task.name!r}; "
                            f"accepted: >= {task.min_duration_s} s")
    mass_of(scenario)  # every user and grasp index exists: N beyond the named ones is drawn


def object_model(scenario: Scenario) -> ObjectModel:
    """The box as the method knows it: size, mass, inertia and friction of the scenario."""
    box = box_spec()
    m = float(mass_of(scenario)["mass_kg"])
    size = np.asarray(box["size_m"], dtype=float)
    return ObjectModel(size_m=size, mass_kg=m, inertia=ObjectModel.solid_box_inertia(size, m),
                       friction=float(box["finger_friction"]), table_friction=float(box["table_friction"]))


def hand_model(scenario: Scenario) -> HandModel:
    """The scenario's user's hand, exactly: the hand of the simulation (its anatomy's)."""
    return _hand_model_of(user_of(scenario)["anatomy"])


@dataclass(frozen=True)
class World:
    """A compiled world and its indices.

    Attributes:
        model: The MuJoCo model (1 ms step, elliptic cones, implicitfast).
        hand: The hand model the MJCF was written from.
        obj: The box's known model.
        box_body: Body id of the box.
        box_qadr: qpos address of the box's free joint (3 position + 4 quaternion).
        box_dadr: qvel address of the box's free joint (3 linear world-frame + 3 angular box-frame).
        box_geom: Geom id of the box.
        table_geom: Geom id of the table.
        hand_qadr: qpos addresses of the hand in ``Truth.hand_qpos`` order, (7 + n,).
        hand_dadr: qvel addresses of the hand: palm (6) then hinges, (6 + n,).
        joint_qadr: qpos addresses of the n hinges, (n,).
        joint_dadr: qvel addresses of the n hinges, (n,).
        finger_dofs: Per finger, the qvel addresses of its hinges, tuple of K arrays.
        palm_body: Body id of the palm.
        segment_body: Body id per hand segment, (B,).
        geom_segment: Hand segment of every MuJoCo geom, -1 for non-hand geoms, (ngeom,).
        geom_finger: Finger of every MuJoCo geom, -1 for the palm and non-hand geoms, (ngeom,).
        tip_site: Site id of each fingertip pad centre, (K,).
        mocap: Mocap index of the palm's target.
        actuator_joint: Hinge index (into the hand's joints) driven by each position actuator, (n,).
    """

    model: mujoco.MjModel
    hand: HandModel
    obj: ObjectModel
    box_body: int
    box_qadr: int
    box_dadr: int
    box_geom: int
    table_geom: int
    hand_qadr: np.ndarray
    hand_dadr: np.ndarray
    joint_qadr: np.ndarray
    joint_dadr: np.ndarray
    finger_dofs: tuple
    palm_body: int
    segment_body: np.ndarray
    geom_segment: np.ndarray
    geom_finger: np.ndarray
    tip_site: np.ndarray
    mocap: int
    actuator_joint: np.ndarray


@functools.lru_cache(maxsize=64)
def world_xml(user: int, mass: int, stiffness: float) -> str:
    """The MJCF text of a world (cached per user, mass and finger stiffness)."""
    sc = Scenario(user=user, mass=mass)
    hand = hand_model(sc)
    obj = object_model(sc)
    box = box_spec()
    root = ET.fromstring(importlib.resources.files("sim_assets").joinpath("world.xml").read_text())
    world = root.find("worldbody")
    body = world.find("body[@name='box']")
    body.set("pos", " ".join(repr(float(v)) for v in box["start_pos"]))
    inertial = body.find("inertial")
    inertial.set("mass", repr(obj.mass_kg))
    inertial.set("diaginertia", " ".join(repr(float(v)) for v in np.diag(obj.inertia)))
    geom = body.find("geom")
    geom.set("size", " ".join(repr(float(v)) for v in obj.half_extents))
    geom.set("friction", f"{obj.table_friction} 0.005 0.0001")
    world.find("geom[@name='table']").set("friction", f"{obj.table_friction} 0.005 0.0001")
    start = np.array([0.0, -0.25, 0.25])
    colliding = pad_geoms(hand) | (hand.geom_segment == 0)
    world.append(hand_mjcf(hand, pos=start, contype=HAND_CONTYPE, conaffinity=HAND_CONAFFINITY,
                           friction=obj.friction, colliding=colliding))
    target = ET.SubElement(world, "body", name="palm_target", mocap="true", pos=" ".join(repr(float(v)) for v in start))
    ET.SubElement(target, "site", name="palm_target", size="0.005", group="4")
    eq = ET.SubElement(root, "equality")
    ET.SubElement(eq, "weld", name="palm_weld", body1="hand_palm", body2="palm_target",
                  relpose="0 0 0 1 0 0 0", solref="0.01 1", solimp="0.95 0.99 0.001")
    act = ET.SubElement(root, "actuator")
    for name, rng in zip(hand.joint_names, hand.joint_range):
        ET.SubElement(act, "position", name=f"hand_{name}", joint=f"hand_{name}", kp=repr(float(stiffness)),
                      ctrlrange=f"{float(rng[0])!r} {float(rng[1])!r}", forcerange="-2 2")
    return ET.tostring(root, encoding="unicode")


def build_world(scenario: Scenario) -> World:
    """Compiles the world of a scenario.

    Args:
        scenario: Which user (hand scale, finger stiffness) and mass to build.

    Returns:
        A fresh :class:`World` (its MjModel may be modified by the caller).

    Raises:
        ScenarioError: If the user or mass index does not exist.
    """
    user = user_of(scenario)
    mass_of(scenario)
    xml = world_xml(scenario.user, scenario.mass, float(user["stiffness_nm_per_rad"]))
    m = mujoco.MjModel.from_xml_string(xml)
    hand = hand_model(scenario)
    obj = object_model(scenario)
    jid = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)  # noqa: E731
    bid = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)  # noqa: E731
    palm_j = jid("hand_palm")
    hinge = np.array([jid(f"hand_{n}") for n in hand.joint_names])
    joint_qadr = m.jnt_qposadr[hinge]
    joint_dadr = m.jnt_dofadr[hinge]
    qa = m.jnt_qposadr[palm_j]
    da = m.jnt_dofadr[palm_j]
    seg_body = np.array([bid(f"hand_{s}") for s in hand.segment_names])
    body_seg = {b: i for i, b in enumerate(seg_body)}
    finger_of_seg = finger_of_segment(hand)
    geom_segment = np.array([body_seg.get(int(b), -1) for b in m.geom_bodyid], dtype=np.int64)
    geom_finger = np.where(geom_segment >= 0, finger_of_seg[np.maximum(geom_segment, 0)], -1)
    finger_dofs = tuple(
        joint_dadr[np.isin(hand.joint_segment, np.flatnonzero(finger_of_seg == k))] for k in range(len(hand.finger_names))
    )
    act_joint = np.array([list(hinge).index(m.actuator_trnid[a, 0]) for a in range(m.nu)])
    box_j = jid("box")
    return World(
        model=m, hand=hand, obj=obj, box_body=bid("box"), box_qadr=int(m.jnt_qposadr[box_j]),
        box_dadr=int(m.jnt_dofadr[box_j]), box_geom=mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "box"),
        table_geom=mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "table"),
        hand_qadr=np.concatenate([np.arange(qa, qa + 7), joint_qadr]),
        hand_dadr=np.concatenate([np.arange(da, da + 6), joint_dadr]), joint_qadr=joint_qadr, joint_dadr=joint_dadr,
        finger_dofs=finger_dofs, palm_body=bid("hand_palm"), segment_body=seg_body, geom_segment=geom_segment,
        geom_finger=geom_finger,
        tip_site=np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"hand_{f}_tip") for f in hand.finger_names]),
        mocap=int(m.body_mocapid[bid("palm_target")]), actuator_joint=act_joint,
    )


def set_frame(world: World, data: mujoco.MjData, box_pos, box_quat, hand_qpos) -> None:
    """Poses the world from one frame of the truth and runs ``mj_kinematics``.

    Afterwards ``data.geom_xpos``/``geom_xmat``, ``xpos``/``xquat`` and ``site_xpos`` hold the
    poses of that frame (the palm's mocap target is moved onto the palm).

    Args:
        world: The world of the episode's scenario.
        data: An MjData of ``world.model``.
        box_pos: Box centre of mass, (3,), [m].
        box_quat: Box orientation (w, x, y, z), (4,).
        hand_qpos: Palm free joint (7) then hinges in ``HandModel.joint_names`` order, (7 + n,).
    """
    hand_qpos = np.asarray(hand_qpos, dtype=float)
    if hand_qpos.shape != (len(world.hand_qadr),):
        raise ScenarioError(f"hand_qpos must have {len(world.hand_qadr)} entries, got {hand_qpos.shape}")
    data.qpos[world.box_qadr : world.box_qadr + 3] = box_pos
    data.qpos[world.box_qadr + 3 : world.box_qadr + 7] = box_quat
    data.qpos[world.hand_qadr] = hand_qpos
    data.mocap_pos[world.mocap] = hand_qpos[:3]
    data.mocap_quat[world.mocap] = hand_qpos[3:7]
    mujoco.mj_kinematics(world.model, data)
