"""What the method is told of the hand, the box and the camera: the truth, or what a lab measures.

``lab`` (the default) hands the method what a lab would measure, each quantity with an error drawn
from the scenario's ``"knowledge"`` stream (the same scenario, the same errors). ``exact`` hands it
the simulation's own values (the hand that rendered the depth, the box's true mass and friction,
the camera's true calibration): a labelled ablation, like the oracles. What ``lab`` gives:

- **the hand**: the method's generic hand (the template, ``sim_assets/hand.yaml``, with none of the
  person's proportions) stretched along the hand to the person's hand length and across it to
  their hand breadth, both read off a ruler (:data:`RULER_SD_M`; the template is 190 mm long and
  85 mm broad, ``benchmark.world.anatomy``);
- **the box**: its mass from a kitchen scale (:data:`SCALE_SD_KG`), its finger friction from a
  tilt test, mu = tan(theta) at the angle theta where the box starts to slide on a finger-pad
  material (:data:`TILT_SD_RAD`);
- **the camera**: intrinsics from a checkerboard calibration (:data:`FOCAL_SD_REL`,
  :data:`PRINCIPAL_SD_PX`) and the camera's pose in the world from a board laid on the table
  (:data:`EXTRINSIC_ROT_SD_RAD`, :data:`EXTRINSIC_POS_SD_M`), which also gives the method the
  direction of gravity (vertical in its world). The colour camera, when the method reads it: its
  intrinsics from its own checkerboard calibration (the same error sizes, drawn from the scenario's
  ``"knowledge-colour"`` stream, so the depth's errors do not move) and its offset from the depth
  camera as the maker's calibration gives it (exact: a stated choice), so its pose is the depth
  camera's calibrated pose carried by that offset.

The sizes are choices, stated here and in docs/scenarios.md. ``lab-hand``, ``lab-box`` and
``lab-camera`` apply one source's errors alone (the same draws as ``lab``), to measure what each costs.
``NAME:FACTOR`` (e.g. ``lab:2``, ``lab-camera:0.5``) scales every error of ``NAME`` by ``FACTOR``:
the same draws times the factor (a worse or a better lab), for ``fsv-bench sweep --axis knowledge``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from benchmark.world.anatomy import TEMPLATE_HAND_BREADTH_M, TEMPLATE_HAND_LENGTH_M, Anatomy
from benchmark.world.hand import hand_model as hand_of
from fsv import Calibration, ColourVideo
from fsv.linalg import mm, norm, rigid_inverse

SOURCES = ("hand", "box", "camera")
"""The sources of a lab's errors; ``lab-<source>`` applies that source's alone (an ablation)."""

KNOWLEDGE = ("exact", "lab") + tuple(f"lab-{s}" for s in SOURCES)
"""The accepted values of ``--knowledge``: "exact", "lab" (every source's errors) or one source's,
each ``lab`` one optionally with ``:FACTOR`` (:func:`parse_knowledge`)."""

DEFAULT_KNOWLEDGE = "lab"
"""What the method is told unless the command says otherwise: what a lab would measure."""

RULER_SD_M = 0.002
"""A hand length or breadth read off a ruler by a person: 2 mm (a choice; the inter-observer error
of trained anthropometrists is about 1-2 mm for these two dimensions)."""
SCALE_SD_KG = 0.001
"""A kitchen scale's error: 1 g (a choice: its resolution)."""
TILT_SD_RAD = math.radians(1.5)
"""The slip angle of a tilt test read with an inclinometer: 1.5 degrees (a choice)."""
FOCAL_SD_REL = 0.003
"""Relative error of each focal length of a checkerboard calibration: 0.3 % (a choice, of the order
of the parameter uncertainties a calibration with sub-pixel residuals leaves)."""
PRINCIPAL_SD_PX = 1.5
"""Error of each principal-point coordinate: 1.5 px (a choice, as above)."""
EXTRINSIC_ROT_SD_RAD = math.radians(0.2)
"""Error of the camera's orientation in the world per axis: 0.2 degrees (a choice: a board on the
table seen at 0.55 m); its tilt is the error of the gravity direction the method assumes."""
EXTRINSIC_POS_SD_M = 0.0015
"""Error of the camera's position in the world per axis: 1.5 mm (a choice, as above)."""


@dataclass(frozen=True)
class Knowledge:
    """What a method was told, with the error of each given quantity.

    Attributes:
        name: A ``--knowledge`` value (:func:`parse_knowledge`): "exact", "lab", "lab-<source>",
            a lab one optionally with ":FACTOR".
        hand_scale_true: The person's hand scale (the simulated hand's; for a drawn person the
            geometric mean of its length and breadth scales).
        hand_scale_given: The given hand model's (the geometric mean of its length and breadth scales).
        hand_length_m: True and measured hand length, (2,), [m].
        hand_breadth_m: True and measured hand breadth, (2,), [m].
        mass_kg: True and given box mass, (2,), [kg].
        friction: True and given finger friction coefficient, (2,).
        focal_px: True and given (fx, fy), (2, 2), [px].
        principal_px: True and given (cx, cy), (2, 2), [px].
        camera_rot_err_deg: Angle of the given camera orientation's error, [deg].
        camera_pos_err_m: Norm of the given camera position's error, [m].
        world_from_method: Maps the method's world frame into the true one through the camera,
            (4, 4): ``T_world_cam_true @ inv(T_world_cam_given)``; the identity for "exact".
    """

    name: str
    hand_scale_true: float
    hand_scale_given: float
    hand_length_m: tuple
    hand_breadth_m: tuple
    mass_kg: tuple
    friction: tuple
    focal_px: tuple
    principal_px: tuple
    camera_rot_err_deg: float
    camera_pos_err_m: float
    world_from_method: np.ndarray

    def record(self) -> dict:
        """JSON of every given quantity beside its true value and its error."""
        def pair(values):
            true, given = (float(v) for v in values)
            return {"true": true, "given": given, "error": given - true}

        return {
            "knowledge": self.name,
            "hand_scale": pair((self.hand_scale_true, self.hand_scale_given)),
            "hand_length_m": pair(self.hand_length_m), "hand_breadth_m": pair(self.hand_breadth_m),
            "mass_kg": pair(self.mass_kg), "friction": pair(self.friction),
            "fx_px": pair((self.focal_px[0][0], self.focal_px[1][0])),
            "fy_px": pair((self.focal_px[0][1], self.focal_px[1][1])),
            "cx_px": pair((self.principal_px[0][0], self.principal_px[1][0])),
            "cy_px": pair((self.principal_px[0][1], self.principal_px[1][1])),
            "camera_rot_err_deg": float(self.camera_rot_err_deg), "camera_pos_err_m": float(self.camera_pos_err_m),
        }

    def given_record(self) -> dict:
        """What the method may read of it (camera-input files): the knowledge, each given quantity
        and the standard deviation of its measurement (0 where it was given exactly); never the
        truth or the error."""
        on = _error_scales(self.name)
        sd = {"hand_length_m": RULER_SD_M * on["hand"], "hand_breadth_m": RULER_SD_M * on["hand"],
              "mass_kg": SCALE_SD_KG * on["box"], "tilt_angle_rad": TILT_SD_RAD * on["box"],
              "focal_rel": FOCAL_SD_REL * on["camera"], "principal_px": PRINCIPAL_SD_PX * on["camera"],
              "camera_rot_rad": EXTRINSIC_ROT_SD_RAD * on["camera"], "camera_pos_m": EXTRINSIC_POS_SD_M * on["camera"]}
        return {"knowledge": self.name, "hand_length_m": float(self.hand_length_m[1]),
                "hand_breadth_m": float(self.hand_breadth_m[1]), "hand_scale": float(self.hand_scale_given),
                "mass_kg": float(self.mass_kg[1]), "friction": float(self.friction[1]),
                "measurement_sd": {k: float(v) for k, v in sd.items()}}

    @property
    def camera_from_lab(self) -> bool:
        """Whether the camera's calibration came from a lab (with errors, unless scaled to 0)."""
        return _sources(self.name)["camera"]

    def line(self) -> str:
        """One line: what the method was given and its errors."""
        r = self.record()
        if self.name == "exact":
            return "knowledge [exact]: the simulated hand, the true box and the true camera (an ablation)"
        return (f"knowledge [{self.name}]: hand scale {r['hand_scale']['given']:.3f} from a ruler (true "
                f"{r['hand_scale']['true']:.3f}), mass {1e3 * r['mass_kg']['given']:.0f} g "
                f"({1e3 * r['mass_kg']['error']:+.1f} g), friction {r['friction']['given']:.3f} "
                f"({r['friction']['error']:+.3f}), focal {r['fx_px']['error']:+.2f}/{r['fy_px']['error']:+.2f} px, "
                f"principal point {r['cx_px']['error']:+.2f}/{r['cy_px']['error']:+.2f} px, camera "
                f"{r['camera_rot_err_deg']:.2f} deg and {1e3 * r['camera_pos_err_m']:.1f} mm off")


MAX_ERROR_FACTOR = 100.0
"""The largest accepted ``:FACTOR`` (a hundred times a lab's errors is no lab)."""


def parse_knowledge(name: str) -> tuple:
    """``(base, factor)`` of a knowledge name: ``"lab:2"`` is ``("lab", 2.0)``, ``"lab"`` is
    ``("lab", 1.0)``, ``"exact"`` is ``("exact", 0.0)``.

    Raises:
        ValueError: Naming the bad value and what is accepted: a base of :data:`KNOWLEDGE`, and for
            a ``lab`` one a factor that is a finite number in [0, :data:`MAX_ERROR_FACTOR`].
    """
    accepted = (f"accepted: {', '.join(KNOWLEDGE)}, each lab one optionally with :FACTOR scaling its errors "
                f"(0 to {MAX_ERROR_FACTOR:g}, e.g. lab:2)")
    if not isinstance(name, str):
        raise ValueError(f"--knowledge {name!r}: {accepted}")
    base, sep, text = name.partition(":")
    if base not in KNOWLEDGE or (sep and base == "exact"):
        raise ValueError(f"--knowledge {name!r}: {accepted}")
    if base == "exact":
        return base, 0.0
    if not sep:
        return base, 1.0
    try:
        factor = float(text)
    except ValueError:
        raise ValueError(f"--knowledge {name!r}: {text!r} is not a number; {accepted}") from None
    if not (math.isfinite(factor) and 0.0 <= factor <= MAX_ERROR_FACTOR):
        raise ValueError(f"--knowledge {name!r}: factor {text} is out of range; {accepted}")
    return base, factor


def _sources(name: str) -> dict:
    """Which sources (:data:`SOURCES`) a knowledge ``name`` takes from a lab (True) or exactly."""
    base = parse_knowledge(name)[0]
    return {src: base in ("lab", f"lab-{src}") for src in SOURCES}


def _error_scales(name: str) -> dict:
    """The factor on each source's lab errors under ``name`` (0 for a source given exactly; a lab
    source with factor 0 is measured perfectly, but still the lab's way: the generic hand)."""
    factor = parse_knowledge(name)[1]
    return {src: factor if on else 0.0 for src, on in _sources(name).items()}


def check_knowledge(name: str) -> str:
    """``name`` if :func:`parse_knowledge` accepts it; its ValueError otherwise."""
    parse_knowledge(name)
    return name


def _rotation(rotvec) -> np.ndarray:
    """Rotation matrix of a rotation vector (Rodrigues), (3, 3)."""
    v = np.asarray(rotvec, dtype=float)
    angle = norm(v)
    if angle == 0.0:
        return np.eye(3)
    k = v / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * mm(K, K)


def given(episode, name: str = DEFAULT_KNOWLEDGE) -> tuple:
    """What the method is told of ``episode`` under knowledge ``name``.

    Args:
        episode: A rendered ``benchmark.world.episode.Episode``.
        name: One of :data:`KNOWLEDGE`, optionally with ``:FACTOR`` (:func:`parse_knowledge`).

    Returns:
        ``(hand_model, object_model, calib, knowledge)``: the method's models and calibration and
        the :class:`Knowledge` record.
    """
    from benchmark.world.assets import user_of  # lazy: MuJoCo (0.25 s) off `fsv-bench calibrate`'s start-up

    check_knowledge(name)
    person = user_of(episode.scenario)
    scale, anatomy = float(person["hand_scale"]), person["anatomy"]
    om, calib = episode.object_model, episode.calib
    length, breadth = anatomy.hand_length_m, anatomy.hand_breadth_m
    K = np.asarray(calib.K, dtype=float)
    focal, principal = (K[0, 0], K[1, 1]), (K[0, 2], K[1, 2])
    if parse_knowledge(name)[0] == "exact":
        knowledge = Knowledge(name, scale, scale, (length, length), (breadth, breadth), (om.mass_kg, om.mass_kg),
                              (om.friction, om.friction), (focal, focal), (principal, principal), 0.0, 0.0, np.eye(4))
        return episode.hand_model, om, calib, knowledge
    rng = episode.scenario.rng("knowledge")
    # every draw, in a fixed order (a source left exact still draws: the others' errors stay the same)
    on, scale_of = _sources(name), _error_scales(name)
    length_m = length + RULER_SD_M * rng.standard_normal() * scale_of["hand"]
    breadth_m = breadth + RULER_SD_M * rng.standard_normal() * scale_of["hand"]
    mass = om.mass_kg + SCALE_SD_KG * rng.standard_normal() * scale_of["box"]
    theta = math.atan(om.friction) + TILT_SD_RAD * rng.standard_normal() * scale_of["box"]
    df = FOCAL_SD_REL * rng.standard_normal(2) * scale_of["camera"]
    dc = PRINCIPAL_SD_PX * rng.standard_normal(2) * scale_of["camera"]
    drot = EXTRINSIC_ROT_SD_RAD * rng.standard_normal(3) * scale_of["camera"]
    dpos = EXTRINSIC_POS_SD_M * rng.standard_normal(3) * scale_of["camera"]
    generic = Anatomy(length_scale=float(length_m / TEMPLATE_HAND_LENGTH_M),
                      breadth_scale=float(breadth_m / TEMPLATE_HAND_BREADTH_M))
    scale_given = math.sqrt(generic.length_scale * generic.breadth_scale) if on["hand"] else scale
    friction = math.tan(theta) if on["box"] else om.friction
    K_given = K.copy()
    K_given[0, 0], K_given[1, 1] = K[0, 0] * (1 + df[0]), K[1, 1] * (1 + df[1])
    K_given[0, 2], K_given[1, 2] = K[0, 2] + dc[0], K[1, 2] + dc[1]
    T = np.asarray(calib.T_world_cam, dtype=float)
    T_given = T.copy()
    T_given[:3, :3] = mm(_rotation(drot), T[:3, :3])
    T_given[:3, 3] = T[:3, 3] + dpos
    calib_given = (Calibration(K=K_given, T_world_cam=T_given, width=calib.width, height=calib.height)
                   if on["camera"] else calib)
    om_given = (replace(om, mass_kg=mass, inertia=type(om).solid_box_inertia(om.size_m, mass), friction=friction)
                if on["box"] else om)
    knowledge = Knowledge(
        name, scale, scale_given, (length, length_m), (breadth, breadth_m), (om.mass_kg, mass), (om.friction, friction),
        (focal, (K_given[0, 0], K_given[1, 1])), (principal, (K_given[0, 2], K_given[1, 2])),
        math.degrees(norm(drot)), norm(dpos),
        mm(T, rigid_inverse(T_given)) if on["camera"] else np.eye(4))
    return (hand_of(generic) if on["hand"] else episode.hand_model), om_given, calib_given, knowledge


def given_colour(episode, name: str, known: "Knowledge"):
    """The colour stream as the method is told it under knowledge ``name``, or None without colour.

    Under ``exact`` (or a ``lab`` variant without the camera's errors) the episode's own stream;
    otherwise its intrinsics carry a checkerboard calibration's errors (:data:`FOCAL_SD_REL`,
    :data:`PRINCIPAL_SD_PX`, from the ``"knowledge-colour"`` stream) and its pose is expressed in
    the method's world (``known.world_from_method``): the depth-to-colour offset is exact.
    """

    colour = episode.colour
    if colour is None:
        return None
    check_knowledge(name)
    if parse_knowledge(name)[0] == "exact" or not _sources(name)["camera"]:
        return colour
    rng = episode.scenario.rng("knowledge-colour")
    scale = _error_scales(name)["camera"]
    df = FOCAL_SD_REL * rng.standard_normal(2) * scale
    dc = PRINCIPAL_SD_PX * rng.standard_normal(2) * scale
    c = colour.calib
    K = np.asarray(c.K, dtype=float).copy()
    K[0, 0], K[1, 1] = K[0, 0] * (1 + df[0]), K[1, 1] * (1 + df[1])
    K[0, 2], K[1, 2] = K[0, 2] + dc[0], K[1, 2] + dc[1]
    T = mm(rigid_inverse(known.world_from_method), np.asarray(c.T_world_cam, dtype=float))
    calib = Calibration(K=K, T_world_cam=T, width=c.width, height=c.height)
    return ColourVideo(rgb=colour.rgb, fps=colour.fps, calib=calib, t_s=colour.t_s, exposure_s=colour.exposure_s)
