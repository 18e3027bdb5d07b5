"""Environment contacts: the box resting on the table, seen from the estimated pose.

The table is the plane z = 0 of the world frame (docs/design.md). The method does not observe the
table's force, so it models the contact from geometry alone, as point contacts at box corners,
each with a Coulomb friction cone of coefficient ``ObjectModel.table_friction`` about the table's
normal (world +z, which pushes into the box):

* a box lying nearly flat (its lowest face tilted by at most ``max_tilt_deg``) whose lowest corner
  is within ``height_tol_m`` of the table rests on that face: its four corners touch. Their cones
  span every wrench a flat face contact can transmit (any centre of pressure inside the face), and
  the tilt allowance keeps an orientation error of the estimated pose (1 degree lifts the far end
  of the 171 mm box by 3 mm; tracker-like pose errors reach 6 degrees) from turning a resting box
  into one balanced on an edge, which could not hold it;
* a box tilted further touches with the corners within ``height_tol_m`` of the table (an edge's
  two corners when it is tipped, one when it stands on a corner).

Corner contacts are always static: a box sliding on the table has its kinetic friction on the
surface of these cones, so the static model contains it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv._check import as_array, same_length
from fsv.errors import InputError
from fsv.models import ObjectModel
from fsv.types import Kinematics

#: Corners of a box with unit half extents, shape (8, 3); scaled by ObjectModel.half_extents.
UNIT_CORNERS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


@dataclass(frozen=True)
class TableContacts:
    """Corner contacts of the box with the table.

    Attributes:
        active: Corner j touches the table at frame i, shape (T, 8).
        point: Corner positions in the object frame, shape (8, 3), [m].
        normal: Table normal (world +z) in the object frame, shape (T, 3): the direction in which
            the table pushes the box.
        friction: Coulomb coefficient between the box and the table.
    """

    active: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    friction: float

    def __post_init__(self):
        active = as_array("TableContacts.active", self.active, (None, 8), bool)
        point = as_array("TableContacts.point", self.point, (8, 3))
        normal = as_array("TableContacts.normal", self.normal, (None, 3))
        same_length("TableContacts", active=active, normal=normal)
        if not (np.isfinite(self.friction) and self.friction >= 0):
            raise InputError(f"TableContacts.friction must be >= 0, got {self.friction!r}")
        object.__setattr__(self, "active", active)
        object.__setattr__(self, "point", point)
        object.__setattr__(self, "normal", normal)
        object.__setattr__(self, "friction", float(self.friction))

    def __len__(self) -> int:
        return self.active.shape[0]

    @staticmethod
    def none(num_frames: int, model: ObjectModel) -> "TableContacts":
        """No table contact at any of ``num_frames`` frames."""
        return TableContacts(
            active=np.zeros((num_frames, 8), bool),
            point=UNIT_CORNERS * model.half_extents,
            normal=np.tile([0.0, 0.0, 1.0], (num_frames, 1)),
            friction=model.table_friction,
        )


def table_contacts(
    kinematics: Kinematics, model: ObjectModel, *, height_tol_m: float = 0.003, max_tilt_deg: float = 10.0
) -> TableContacts:
    """Detects the box's corners on the table from the estimated pose.

    Args:
        kinematics: Estimated pose (``pos``, ``rot``) of the object, T frames.
        model: The box (its half extents and table friction).
        height_tol_m: A corner within this height [m] of the table plane z = 0 (or below it)
            touches the table. It absorbs the pose's error and the contact's compliance.
        max_tilt_deg: A lowest face tilted by at most this angle [deg] counts as flat.

    Returns:
        The corner contacts per frame; frames whose pose is not finite have none.
    """
    if not (np.isfinite(height_tol_m) and height_tol_m >= 0):
        raise InputError(f"height_tol_m must be a height >= 0 in metres, got {height_tol_m!r}")
    if not (np.isfinite(max_tilt_deg) and 0 <= max_tilt_deg < 45):
        raise InputError(f"max_tilt_deg must be an angle in [0, 45) degrees, got {max_tilt_deg!r}")
    corners = UNIT_CORNERS * model.half_extents
    up = kinematics.rot[:, 2, :]  # world z in the object frame, (T, 3)
    with np.errstate(invalid="ignore"):
        z = kinematics.pos[:, 2:3] + np.einsum("tj,cj->tc", up, corners)
        active = np.isfinite(z) & (z <= height_tol_m)
        # The lowest face: the box axis closest to the vertical, on the side pointing down.
        axis = np.argmax(np.abs(np.nan_to_num(up)), axis=1)
        down = -np.sign(np.take_along_axis(up, axis[:, None], axis=1))  # (T, 1)
        on_face = UNIT_CORNERS.T[axis] == down  # (T, 8)
        cos_tilt = np.abs(np.take_along_axis(up, axis[:, None], axis=1))[:, 0]
        flat = cos_tilt >= np.cos(np.radians(max_tilt_deg))
        resting = flat & (np.where(on_face, z, np.inf).min(axis=1) <= height_tol_m)
    active = np.where(resting[:, None], on_face, active)
    normal = np.where(np.isfinite(kinematics.rot[:, 2, :]), kinematics.rot[:, 2, :], 0.0)
    normal[~active.any(axis=1)] = (0.0, 0.0, 1.0)
    return TableContacts(active=active, point=corners, normal=normal, friction=model.table_friction)
