"""Which method the benchmark runs: :class:`MethodSpec`, named by text so worker processes can rebuild it."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import lru_cache

from benchmark.method.knowledge import DEFAULT_KNOWLEDGE, check_knowledge
from benchmark.method.load import load_object
from benchmark.method.protocol import DEFAULT_PROTOCOL, check_protocol
from benchmark.world.motion import DECLARED
from fsv.errors import FsvError, InputError
from fsv.learn import default_direct_path, load, load_direct
from fsv.method import DirectForces, LearnedInternalForces, Method, StencilDifferentiator, make_method, method_streams
from fsv.method.baselines import BASELINE_STAGE, BASELINES

ORACLE_STAGES = ("contacts", "kinematics")
"""The method's inputs the truth may replace (a labelled *oracle* ablation)."""

DIFFERENTIATORS = ("algebraic", "central", "gaussian")
"""Built-in names ``--differentiator`` accepts besides ``module:attribute``: the benchmark's
calibrated stencil differentiators (``benchmark.world.motion.DECLARED``)."""


@dataclass(frozen=True)
class MethodSpec:
    """A method: the reference, with stages replaced by ``module:attribute`` specs, or a whole method.

    Attributes:
        method: A whole method replacing every stage: an ``fsv.method.Method`` (or a factory of one),
            or any callable ``(inputs: fsv.method.CameraInput, rng) -> fsv.method.Estimate``; or the
            name of a baseline (:data:`fsv.method.baselines.BASELINES`: ``static``,
            ``zero-kinematics``, ``gravity-forces``, ``no-internal``, ``grip-line``); or
            :data:`DIRECT`, the end-to-end network on the reference tracker's outputs
            (:class:`fsv.method.direct.DirectForces`, its model from ``direct_model``).
        tracker: Replaces the reference tracker.
        differentiator: Replaces the algebraic differentiator; or one of :data:`DIFFERENTIATORS`.
        forces: Replaces the nominal-force programs.
        internal: Replaces the learned internal forces; "none" for nominal forces only.
        internal_model: A model file of ``fsv-bench train`` for the reference internal-force stage
            (default: the shipped model).
        direct_model: The model file of ``fsv-bench train-direct`` for ``method="direct"``
            (default: the shipped ``fsv/data/direct_forces.npz``).
        oracle: Inputs replaced by the truth, a subset of :data:`ORACLE_STAGES`.
        knowledge: What the method is told of the hand, the box and the camera
            (:data:`benchmark.method.knowledge.KNOWLEDGE`: "exact" or "lab").
        protocol: What it is told of the person (:data:`benchmark.method.protocol.PROTOCOLS`:
            "blind", nothing, or "calibrated", the person's grip calibration).
    """

    method: str | None = None
    tracker: str | None = None
    differentiator: str | None = None
    forces: str | None = None
    internal: str | None = None
    internal_model: str | None = None
    direct_model: str | None = None
    oracle: tuple = field(default_factory=tuple)
    knowledge: str = DEFAULT_KNOWLEDGE
    protocol: str = DEFAULT_PROTOCOL

    def __post_init__(self):
        check_knowledge(self.knowledge)
        check_protocol(self.protocol)
        object.__setattr__(self, "oracle", tuple(sorted(set(self.oracle))))
        bad = [o for o in self.oracle if o not in ORACLE_STAGES]
        if bad:
            raise ValueError(f"--oracle {bad[0]!r}: accepted: {', '.join(ORACLE_STAGES)} (comma-separated)")
        if self.internal and self.internal_model:
            raise ValueError("--internal-model is a model for the reference internal-force stage; --internal replaces "
                             "that stage: give one of them")
        if self.direct_model and self.method != DIRECT:
            raise ValueError(f"--direct-model is the model of --method {DIRECT}; give both, or neither")
        if self.method and any((self.tracker, self.differentiator, self.forces, self.internal, self.internal_model)):
            raise ValueError("--method replaces every stage; give it alone, or replace single stages with "
                             "--tracker/--differentiator/--forces/--internal")

    @property
    def tracking_key(self):
        """Methods with equal keys run the same tracker (an episode's tracking is run once for them);
        None: a whole method of its own, never shared."""

        if not self.method:
            return ("tracker", self.tracker, self.knowledge)
        if self.method == DIRECT:  # the reference tracker, its output shared with the reference
            return ("tracker", None, self.knowledge)
        if self.method in BASELINE_STAGE:
            return (("tracker", None, self.knowledge) if BASELINE_STAGE[self.method] != "tracker"
                    else ("baseline", self.method, self.knowledge))
        return None

    @property
    def streams(self) -> tuple:
        """The camera streams the method reads (:func:`fsv.method.method_streams`)."""

        return method_streams(self.build())

    @property
    def stage_specs(self) -> dict:
        return {"tracker": self.tracker, "differentiator": self.differentiator, "forces": self.forces,
                "internal": self.internal}

    def build(self):
        """The runnable method (cached per process): loads and checks every named stage.

        Raises:
            ValueError: One line naming a spec that cannot be loaded.
        """
        return _build(self)

    def check(self) -> None:
        """Loads every named stage now (bad specs fail before any expensive work)."""
        self.build()


DIRECT = "direct"
"""``--method direct``: the reference tracker and differentiator, then the end-to-end network
(:class:`fsv.method.direct.DirectForces`) as the force stage whose forces are the final ones."""

DIRECT_COMMAND = ("fsv-bench generate --split train --rows all ... --out DIR, then "
                  "fsv-bench train-direct --data DIR --out {path}")
"""How a missing direct model is made (the one line of its refusal)."""


def direct_method(path: str | None = None):
    """The method of ``--method direct``: the model at ``path`` (default the shipped one) as the
    force stage, no internal-force stage. ValueError (one line, naming the file and the command
    that makes it) when it is missing or unreadable."""
    shipped = path is None
    path = default_direct_path() if shipped else path
    if not os.path.isfile(path):
        where = "fsv/data/direct_forces.npz" if shipped else path
        raise ValueError(f"--method {DIRECT}: no model at {where}; make one with "
                         + DIRECT_COMMAND.format(path=where) + ("" if not shipped else " (or pass --direct-model FILE)"))
    try:
        model = load_direct(path)
    except (FsvError, OSError) as e:
        raise ValueError(f"--direct-model {path}: {e}") from e
    source = "shipped model" if shipped else f"model {path}"
    return make_method(forces=DirectForces(model, source=source), internal=False)


@lru_cache(maxsize=16)
def _build(spec: MethodSpec):
    if spec.method == DIRECT:
        return direct_method(spec.direct_model)
    if spec.method in BASELINES:
        return BASELINES[spec.method]()
    if spec.method:
        method = load_object(spec.method, "--method")
        if spec.oracle and not isinstance(method, Method):
            raise ValueError(f"--oracle needs a method built by fsv.method.make_method; --method {spec.method} is not")
        return method
    stages = {}
    if spec.internal_model:
        try:
            stages["internal"] = LearnedInternalForces(load(spec.internal_model), source=f"model {spec.internal_model}")
        except (FsvError, OSError) as e:
            raise ValueError(f"--internal-model {spec.internal_model}: {e}") from e
    for name, text in spec.stage_specs.items():
        if text is None:
            continue
        if name == "differentiator" and ":" not in text and text not in DIFFERENTIATORS:
            raise ValueError(f"--differentiator {text!r}: accepted: {', '.join(DIFFERENTIATORS)}, "
                             "module:attribute or path/to/file.py:attribute")
        if name == "differentiator" and text in DIFFERENTIATORS:
            stages[name] = StencilDifferentiator(DECLARED[text])
        elif name == "internal" and text == "none":
            stages[name] = False
        else:
            stage = load_object(text, f"--{name}")
            stages[name] = _Named(stage, text) if not isinstance(getattr(stage, "name", None), str) else stage
    try:
        return make_method(**stages)
    except InputError as e:
        raise ValueError(str(e)) from e


class _Named:
    """A user's stage labelled with the spec that named it (when it has no ``name`` of its own)."""

    def __init__(self, stage, name: str):
        self.stage, self.name = stage, name

    def __call__(self, *args, **kwargs):
        return self.stage(*args, **kwargs)

    def __reduce__(self):
        return (_Named, (self.stage, self.name))
