"""The main command's stages, in pipeline order: each a :class:`benchmark.commands.stage.Stage`.

A new stage is a module here with a ``STAGE`` and one entry in :data:`STAGES`.
"""

from benchmark.commands.stages import (
    forces,
    kinematics,
    learn,
    render,
    simulate,
    track,
    verdict,
)

STAGES = (simulate.STAGE, render.STAGE, track.STAGE, kinematics.STAGE, forces.STAGE, learn.STAGE, verdict.STAGE)
"""The stages of ``fsv-bench``, in order."""
