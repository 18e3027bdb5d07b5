"""The one way the benchmark enters a method: :func:`run_method` on an episode's camera inputs."""

from __future__ import annotations

import dataclasses

from benchmark.method.init import tracker_init
from benchmark.method.knowledge import DEFAULT_KNOWLEDGE, given, given_colour
from benchmark.method.protocol import DEFAULT_PROTOCOL, person_grip
from benchmark.method.spec import MethodSpec
from benchmark.world.contact_error import contacts_from_truth
from benchmark.world.motion import oracle_kinematics
from fsv.linalg import mm, mv, rigid_inverse
from fsv.method import CameraInput, Method, ReferenceTracker
from fsv.track.tracker import TrackInit


def camera_input(episode, init_scale: float = 1.0, knowledge: str = DEFAULT_KNOWLEDGE,
                 protocol: str = DEFAULT_PROTOCOL):
    """What the method is given of a rendered episode: no truth beyond the perturbed first frame,
    the hand, box and camera as ``knowledge`` says (:mod:`benchmark.method.knowledge`), and, under
    the ``calibrated`` protocol, the person's grip calibration measured in a recording of their own
    (:mod:`benchmark.method.protocol`).

    Args:
        episode: A rendered ``benchmark.world.episode.Episode``.
        init_scale: Scale of the seeded first-frame perturbation (``benchmark.method.init.INIT_PERTURBATION``).
        knowledge: "exact" (the simulation's own values, an ablation) or "lab" (measured, with errors).
        protocol: "blind" (nothing known of the person) or "calibrated".

    Returns:
        An ``fsv.method.CameraInput``.

    Raises:
        ProtocolError: Under ``calibrated``, if the person has no calibration recording.
    """
    return camera_input_and_knowledge(episode, init_scale, knowledge, protocol)[0]


def camera_input_and_knowledge(episode, init_scale: float = 1.0, knowledge: str = DEFAULT_KNOWLEDGE,
                               protocol: str = DEFAULT_PROTOCOL) -> tuple:
    """:func:`camera_input` and the :class:`benchmark.method.knowledge.Knowledge` record behind it."""

    hand, obj, calib, known = given(episode, knowledge)
    init = tracker_init(episode.truth, episode.scenario, hand, init_scale)
    if known.name != "exact":  # the first frame in the method's world (its calibration's)
        M = rigid_inverse(known.world_from_method)  # no BLAS: the same bits under every kernel
        R, t = M[:3, :3], M[:3, 3]
        init = TrackInit(box_pos=mv(R, init.box_pos) + t, box_rot=mm(R, init.box_rot),
                         palm_pos=mv(R, init.palm_pos) + t, palm_rot=mm(R, init.palm_rot), joints=init.joints)
    inputs = CameraInput(depth=episode.depth, calib=calib, object_model=obj, hand_model=hand, init=init,
                         gravity=episode.truth.gravity, grip=person_grip(episode.scenario.user, protocol),
                         colour=given_colour(episode, knowledge, known))
    return inputs, known


def oracle_inputs(episode, oracle: tuple) -> dict:
    """The truth's contacts and/or kinematics for a labelled oracle ablation (keyword arguments of a method call)."""
    out = {}
    if "contacts" in oracle:
        out["contacts"] = contacts_from_truth(episode.truth)
    if "kinematics" in oracle:
        out["kinematics"] = oracle_kinematics(episode.truth)
    return out


def run_method(spec: MethodSpec, episode, *, inputs=None, tracking=None, progress: bool = False):
    """Runs the method ``spec`` names on ``episode``'s camera inputs.

    Args:
        spec: Which method, and which inputs the truth replaces.
        episode: A rendered ``benchmark.world.episode.Episode``.
        inputs: Its camera inputs, if already made (:func:`camera_input`).
        tracking: The output of this method's tracker on this episode, if already computed by a
            method with the same tracker (methods differing only after tracking share it).
        progress: Show a per-frame progress bar while the reference tracker runs.

    Returns:
        The ``fsv.method.Estimate``; the tracker's searches draw from ``episode.scenario.rng("tracker")``.
    """
    method = spec.build()
    inputs = camera_input(episode, knowledge=spec.knowledge, protocol=spec.protocol) if inputs is None else inputs
    oracle = oracle_inputs(episode, spec.oracle)
    if tracking is not None:
        return method.after_tracking(inputs, tracking, **oracle)

    if progress and isinstance(method, Method) and isinstance(method.tracker, ReferenceTracker):
        from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench`'s start-up

        with tqdm(total=inputs.num_frames, desc="track", unit="frame", leave=False, disable=None) as bar:
            method = dataclasses.replace(method, tracker=dataclasses.replace(method.tracker, on_frame=bar.update))
            return method(inputs, episode.scenario.rng("tracker"), **oracle)
    return method(inputs, episode.scenario.rng("tracker"), **oracle)


def method_label(spec: MethodSpec) -> str:
    """One line naming the method and every stage (``oracle`` for inputs taken from the truth)."""
    method = spec.build()
    labels = dict(getattr(method, "labels", None) or {})
    if spec.knowledge != DEFAULT_KNOWLEDGE:
        labels["knowledge"] = spec.knowledge
    if spec.protocol != DEFAULT_PROTOCOL:
        labels["protocol"] = spec.protocol
    for o in spec.oracle:  # a whole method takes them too when make_method built it (--method direct)
        labels["differentiator" if o == "kinematics" else "contacts"] = "oracle"
    if spec.method:
        head = f"{spec.method}"
        return head + (f" ({'; '.join(f'{k}: {v}' for k, v in labels.items())})" if labels else "")
    return "; ".join(f"{k}: {v}" for k, v in labels.items())
