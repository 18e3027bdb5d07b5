"""The method as composed stages: :class:`Method` and the one function that builds it, :func:`make_method`.

>>> method = make_method(differentiator=my_differentiator)   # the reference with one stage replaced
>>> estimate = method(CameraInput(depth, calib, object_model, hand_model, init), rng)
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.forces import ForceSolution
from fsv.kinematics import kinematics_in_frame
from fsv.method.estimate import Estimate
from fsv.method.inputs import CameraInput
from fsv.method.reference import LearnedInternalForces, NominalForces, ReferenceTracker, StencilDifferentiator
from fsv.method.stages import ORACLE, accepts_grip, is_final, stage_label
from fsv.types import Contacts, Kinematics, Poses, check_streams


@dataclass(frozen=True)
class Method:
    """A tracker, a differentiator, a force estimator and an optional internal-force stage.

    Build one with :func:`make_method`. Calling it runs the stages in order on a
    :class:`CameraInput`; each stage sees only the previous stages' outputs and the inputs.

    Attributes:
        tracker: ``(inputs, rng) -> tracking`` (``.box``, ``.contacts``).
        differentiator: ``(poses) -> Kinematics``.
        forces: ``(kinematics, contacts, object_model, gravity) -> ForceSolution`` (nominal forces), or None.
            A stage whose ``final`` attribute is True (:func:`fsv.method.stages.is_final`, e.g.
            :class:`fsv.method.direct.DirectForces`) returns the method's final forces: without an
            internal-force stage they are the estimate's ``forces`` too.
        internal: ``(kinematics, contacts, object_model, gravity) -> (ForceSolution, predicted)``, or None.
        labels: The name of each stage (``tracker``, ``differentiator``, ``forces``, ``internal``).
    """

    tracker: object
    differentiator: object
    forces: object
    internal: object
    labels: dict

    @property
    def streams(self) -> tuple:
        """The camera streams the method reads: its tracker's (the only stage that sees images)."""
        return method_streams(self.tracker)

    @property
    def name(self) -> str:
        """One line naming every stage."""
        return "; ".join(f"{k}: {v}" for k, v in self.labels.items())

    def __call__(self, inputs: CameraInput, rng: np.random.Generator | None = None, *,
                 contacts: Contacts | None = None, kinematics: Kinematics | None = None) -> Estimate:
        """Runs every stage on ``inputs``.

        Args:
            inputs: The camera inputs of one episode.
            rng: Generator of the tracker's searches (default: seeded with 0).
            contacts: Oracle ablation: contacts replacing the tracked ones (labelled "oracle").
            kinematics: Oracle ablation: kinematics replacing the differentiated ones.

        Returns:
            The estimate, with per-stage timings and labels.
        """
        t0 = time.perf_counter()
        tracking = self.track(inputs, rng)
        return self.after_tracking(inputs, tracking, contacts=contacts, kinematics=kinematics,
                                   track_s=time.perf_counter() - t0)

    def track(self, inputs: CameraInput, rng: np.random.Generator | None = None):
        """The tracker stage alone (methods sharing a tracker may share its output)."""
        if not isinstance(inputs, CameraInput):
            raise InputError(f"inputs must be an fsv.method.CameraInput, got {type(inputs).__name__}")
        tracking = self.tracker(inputs, rng if rng is not None else np.random.default_rng(0))
        _check_output("tracker", self.labels["tracker"], tracking, "box", Poses, inputs.num_frames)
        _check_output("tracker", self.labels["tracker"], tracking, "contacts", Contacts, inputs.num_frames)
        return tracking

    def after_tracking(self, inputs: CameraInput, tracking, *, contacts: Contacts | None = None,
                       kinematics: Kinematics | None = None, track_s: float = 0.0) -> Estimate:
        """The stages after the tracker, on a tracker's output (see :meth:`__call__`)."""
        T = inputs.num_frames
        for name, value, kind in (("contacts", contacts, Contacts), ("kinematics", kinematics, Kinematics)):
            if value is not None and (not isinstance(value, kind) or len(value) != T):
                raise InputError(f"{name} must be None or an fsv.{kind.__name__} of {T} frames, got {value!r:.80}")
        labels, oracle = dict(self.labels), []
        timing = {"track": track_s, **{f"track_{k}": v for k, v in (getattr(tracking, "timing_s", None) or {}).items()}}
        t_start = time.perf_counter()
        if contacts is None:
            contacts = tracking.contacts
        else:
            oracle.append("contacts")
            labels["contacts"] = ORACLE
        t0 = time.perf_counter()
        if kinematics is None:
            kinematics = self.differentiator(tracking.box)
            _check_value("differentiator", labels["differentiator"], kinematics, Kinematics, T)
        else:
            oracle.append("kinematics")
            labels["differentiator"] = ORACLE
        timing["kinematics"] = time.perf_counter() - t0
        nominal = full = predicted = learned_model = None
        timing["forces"] = timing["learn"] = 0.0
        # The force stages work in the table's frame (the table the tracker found at z = 0, gravity
        # along -z); the kinematics of the estimate stay in the calibration's world. Oracle
        # kinematics are the truth's, whose table is at z = 0 already.
        table_from_world = getattr(tracking, "table_from_world", None)
        on_table = kinematics
        if table_from_world is not None and "kinematics" not in oracle:
            on_table = kinematics_in_frame(kinematics, table_from_world)
        if self.forces is not None:
            t0 = time.perf_counter()
            nominal = self.forces(on_table, contacts, inputs.object_model, inputs.gravity)
            _check_value("forces", labels["forces"], nominal, ForceSolution, T)
            contacts = nominal.contacts_used(contacts)  # with any contact the force stage added
            timing["forces"] = time.perf_counter() - t0
        if self.internal is not None:
            t0 = time.perf_counter()
            grip = {"grip": inputs.grip} if accepts_grip(self.internal) else {}
            out = self.internal(on_table, contacts, inputs.object_model, inputs.gravity, **grip)
            if not (isinstance(out, tuple) and len(out) == 2):
                raise InputError(f"the internal-force stage {labels['internal']!r} must return "
                                 f"(ForceSolution, predicted), got {type(out).__name__}")
            full, predicted = out
            _check_value("internal", labels["internal"], full, ForceSolution, T)
            if isinstance(self.internal, LearnedInternalForces):
                learned_model = self.internal.model_for(inputs.grip)
            timing["learn"] = time.perf_counter() - t0
        elif nominal is not None and is_final(self.forces):  # its forces are the final ones already
            full = nominal
        timing["total"] = track_s + time.perf_counter() - t_start
        return Estimate(tracking=tracking, contacts=contacts, kinematics=kinematics, nominal=nominal, forces=full,
                        internal_pred=predicted, oracle=tuple(oracle), timing_s=timing, labels=labels,
                        learned_model=learned_model)


def _check_value(stage: str, label: str, value, kind, T: int) -> None:
    if not isinstance(value, kind) or len(value) != T:
        got = type(value).__name__ if not isinstance(value, kind) else f"{len(value)} frames"
        raise InputError(f"the {stage} stage {label!r} must return an {kind.__module__}.{kind.__name__} "
                         f"of {T} frames, got {got}")


def _check_output(stage: str, label: str, output, attribute: str, kind, T: int) -> None:
    value = getattr(output, attribute, None)
    if not isinstance(value, kind) or len(value) != T:
        got = type(value).__name__ if not isinstance(value, kind) else f"{len(value)} frames"
        raise InputError(f"the {stage} stage {label!r} must return an object whose .{attribute} is an "
                         f"{kind.__module__}.{kind.__name__} of {T} frames, got {got}")


def method_streams(method) -> tuple:
    """The camera streams a method (or a tracker) declares it reads: its ``streams`` attribute, a
    tuple of names of :data:`fsv.types.STREAMS` (``("depth",)`` when it declares none). The
    benchmark renders those and no more, so a depth-only method pays nothing for colour.

    Raises:
        InputError: For a declared name that is not a stream.
    """
    return check_streams(getattr(method, "streams", ("depth",)))


def make_method(*, tracker=None, differentiator=None, forces=None, internal=None) -> Method:
    """Composes the method from its stages; a stage left as None is the reference's.

    Args:
        tracker: Replaces :class:`fsv.method.ReferenceTracker`.
        differentiator: Replaces the algebraic :class:`fsv.method.StencilDifferentiator`.
        forces: Replaces :class:`fsv.method.NominalForces`; False: no force stage.
        internal: Replaces :class:`fsv.method.LearnedInternalForces` with the shipped model; False:
            no internal-force stage (the estimate then has nominal forces only).

    Returns:
        The method. Its ``labels`` name every stage (a stage's ``name`` attribute or its qualified name).

    Raises:
        InputError: If a stage is not callable or is named "oracle".
    """
    stages = {
        "tracker": ReferenceTracker() if tracker is None else tracker,
        "differentiator": StencilDifferentiator() if differentiator is None else differentiator,
        "forces": NominalForces() if forces is None else (None if forces is False else forces),
        "internal": LearnedInternalForces() if internal is None else (None if internal is False else internal),
    }
    labels = {}
    for name, stage in stages.items():
        if stage is None:
            labels[name] = "none"
            continue
        if not callable(stage):
            raise InputError(f"the {name} stage must be callable, got {type(stage).__name__} {stage!r:.60}")
        labels[name] = stage_label(stage)
    return Method(labels=labels, **stages)
