"""Contacts the force stage sees: the truth's (an *oracle*) or a model of vision's contact errors.

``contacts_from_truth`` turns the simulator's per-finger contacts into :class:`fsv.Contacts`; a
sliding contact's direction is that of the truth's tangential force (kinetic friction on the object
points along it). Using them is the ``--contacts oracle`` ablation, and reports say so.

``vision_like_contacts`` stands in for the tracker's contacts where the tracker is not run (or to
isolate the effect of contact-point errors, the paper's §4.2 sensitivity study): each active
contact point is moved within its face of the box by Gaussian errors along the face's two in-plane
axes of the object frame, mean ``mean_m`` and standard deviation ``std_m`` per axis, independent
per frame and finger (the force programs are solved per frame, so only the per-frame error
distribution matters), then clipped to the face. The defaults are the paper's measured contact
error: mean -1.55 mm, std 6.13 mm (vision minus expected point, per axis). Normals stay the face
normals (a point that stays on its face keeps its normal); activity and sliding stay the truth's.
"""

from __future__ import annotations

import numpy as np

from benchmark.errors import BenchmarkError
from benchmark.world.truth import Truth
from fsv import Contacts, ObjectModel

PAPER_CONTACT_ERROR_MEAN_M = -1.55e-3
PAPER_CONTACT_ERROR_STD_M = 6.13e-3
PAPER_CONTACT_ERROR_MM = {"mean": round(PAPER_CONTACT_ERROR_MEAN_M * 1e3, 9), "std": round(PAPER_CONTACT_ERROR_STD_M * 1e3, 9)}
"""The paper's contact-point error per axis (vision minus expected point), [mm]: mean -1.55, std 6.13."""


def contacts_from_truth(truth: Truth) -> Contacts:
    """The truth's finger contacts as *oracle* :class:`fsv.Contacts` (object frame).

    Inactive fingers get zero points and normals; a sliding contact whose tangential force
    vanishes is treated as static (its kinetic direction is undefined).
    """
    F = np.asarray(truth.contact_force, float)
    n = np.asarray(truth.contact_normal, float)
    active = np.asarray(truth.contact_active, bool)
    tang = F - np.einsum("tki,tki->tk", F, n)[..., None] * n
    norm = np.linalg.norm(tang, axis=-1, keepdims=True)
    sliding = np.asarray(truth.contact_sliding, bool) & active & (norm[..., 0] > 1e-9)
    return Contacts(
        finger_names=tuple(str(s) for s in truth.finger_names),
        active=active,
        sliding=sliding,
        point=np.where(active[..., None], truth.contact_point, 0.0),
        normal=np.where(active[..., None], n, 0.0),
        slide_dir=np.where(sliding[..., None], tang / np.where(norm > 0, norm, 1.0), 0.0),
    )


def vision_like_contacts(
    contacts: Contacts,
    model: ObjectModel,
    rng: np.random.Generator,
    *,
    mean_m: float = PAPER_CONTACT_ERROR_MEAN_M,
    std_m: float = PAPER_CONTACT_ERROR_STD_M,
) -> Contacts:
    """Contacts with vision-like point errors (see the module docstring).

    Args:
        contacts: True contacts on the faces of the box (object frame).
        model: The box (its half extents bound the faces).
        rng: Source of the errors, e.g. ``scenario.rng("contact-error")``.
        mean_m: Mean error per in-plane axis [m].
        std_m: Standard deviation per in-plane axis [m], >= 0.

    Returns:
        The perturbed contacts.
    """
    if not (np.isfinite(mean_m) and np.isfinite(std_m) and std_m >= 0):
        raise BenchmarkError(f"contact error needs a finite mean and a std >= 0 in metres, got {mean_m!r}, {std_m!r}")
    h = model.half_extents
    normal_axis = np.argmax(np.abs(contacts.normal), axis=-1)  # (T, K): the face's axis
    in_plane = np.ones(contacts.point.shape, bool)
    np.put_along_axis(in_plane, normal_axis[..., None], False, axis=-1)
    err = rng.normal(mean_m, std_m, size=contacts.point.shape)
    moved = np.clip(contacts.point + np.where(in_plane & contacts.active[..., None], err, 0.0), -h, h)
    point = np.where(in_plane, moved, contacts.point)
    return Contacts(contacts.finger_names, contacts.active, contacts.sliding, point, contacts.normal,
                    contacts.slide_dir)
