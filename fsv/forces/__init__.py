"""Contact forces from cone programs (the paper's §3.3-3.5 and eq. 14), solved with Clarabel.

    nominal_forces      minimal sum-of-squares forces that explain the motion (eq. 4-6)
    decompose_forces    nominal + internal parts matching measured normal forces (eq. 7-9)
    reconstruct_forces  full forces whose internal normal parts follow predictions (eq. 14)

Each returns a :class:`ForceSolution` with a :class:`FrameStatus` per frame.
"""

from fsv.forces.environment import TableContacts, table_contacts
from fsv.forces.solution import FALLBACKS, SOLVED, ForceSolution, FrameStatus
from fsv.forces.solve import (
    BOUND_FACTOR,
    ForceSettings,
    decompose_forces,
    force_bound,
    nominal_forces,
    reconstruct_forces,
)
from fsv.forces.wrench import GRAVITY, required_wrench, tangent_basis, to_object_frame, to_world_frame

__all__ = [
    "BOUND_FACTOR",
    "FALLBACKS",
    "SOLVED",
    "force_bound",
    "GRAVITY",
    "ForceSettings",
    "ForceSolution",
    "FrameStatus",
    "TableContacts",
    "decompose_forces",
    "nominal_forces",
    "reconstruct_forces",
    "required_wrench",
    "table_contacts",
    "tangent_basis",
    "to_object_frame",
    "to_world_frame",
]
