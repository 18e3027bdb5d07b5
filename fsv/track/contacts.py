"""Contacts from tracking: proximity of the tracked fingertips to the box surface (the paper's §3.1).

Finger k touches the box at frame i when its fingertip pad (a sphere of known radius) comes within
``on_m`` of the box surface, and lets go when the gap exceeds ``off_m`` (hysteresis against tracking
jitter). The contact point is the pad centre projected onto the surface, the normal is the inward
normal of the face it lies on, both in the object frame. A contact slides when its point moves over
the surface faster than ``slide_speed_m_s`` (a centred difference over ``slide_window`` frames on
each side); the sliding direction is that motion's direction (kinetic friction on the object acts
along it).

Occlusion prior (the paper's modification of its tracker): a finger that cannot be seen keeps its
contact, and its contact point stays at its last observed position on the object.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.models import ObjectModel
from fsv.track.hand import box_signed_distance
from fsv.types import Contacts, Poses


@dataclass(frozen=True)
class ContactConfig:
    """Parameters of contact detection (fixed in advance).

    Attributes:
        on_m: A contact starts when the pad's gap to the surface falls below this, [m].
        off_m: It ends when the gap exceeds this, [m] (>= on_m).
        slide_speed_m_s: Contact point speed over the surface above which a contact slides, [m/s].
        slide_window: Frames on each side of the centred difference for the sliding speed.
        occlusion_prior: Keep an unseen finger's contact and its last observed point.
    """

    on_m: float = 0.006
    off_m: float = 0.012
    slide_speed_m_s: float = 0.05
    slide_window: int = 3
    occlusion_prior: bool = True

    def __post_init__(self):
        if not (np.isfinite(self.on_m) and np.isfinite(self.off_m) and self.off_m >= self.on_m):
            raise InputError(f"ContactConfig needs finite on_m <= off_m, got {self.on_m!r}, {self.off_m!r}")
        if not (np.isfinite(self.slide_speed_m_s) and self.slide_speed_m_s > 0):
            raise InputError(f"slide_speed_m_s must be > 0, got {self.slide_speed_m_s!r}")
        if int(self.slide_window) < 1:
            raise InputError(f"slide_window must be >= 1 frame, got {self.slide_window!r}")


def surface_contact(points_obj: np.ndarray, half: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest box-surface point, inward face normal and signed distance of object-frame points.

    Args:
        points_obj: Points in the object frame, shape (P, 3), [m].
        half: Half edge lengths, shape (3,), [m].

    Returns:
        ``(point (P, 3), normal (P, 3), distance (P,))``: the closest point on the surface, the
        inward unit normal of the face it lies on, and the signed distance (negative inside).
    """
    dist, grad = box_signed_distance(points_obj, half)
    point = points_obj - dist[:, None] * grad
    point = np.clip(point, -half, half)
    face = np.argmax(np.abs(point) / half, axis=1)
    rows = np.arange(points_obj.shape[0])
    normal = np.zeros_like(point)
    normal[rows, face] = -np.sign(point[rows, face])
    return point, normal, dist


def detect_contacts(fingertips: np.ndarray, radius: np.ndarray, observed: np.ndarray, box: Poses,
                    object_model: ObjectModel, finger_names, config: ContactConfig | None = None) -> Contacts:
    """Contacts of every finger in every frame.

    Args:
        fingertips: Tracked fingertip pad centres in the world, shape (T, K, 3), [m].
        radius: Pad radii, shape (K,), [m].
        observed: Whether each finger was seen in each frame, shape (T, K).
        box: Tracked box poses, T frames.
        object_model: The known box.
        finger_names: K names, thumb first.
        config: Detection parameters.

    Returns:
        The contacts (object frame).
    """
    c = config or ContactConfig()
    tips = np.asarray(fingertips, dtype=float)
    radius = np.asarray(radius, dtype=float)
    observed = np.asarray(observed, dtype=bool)
    T = len(box)
    if tips.ndim != 3 or tips.shape[0] != T or tips.shape[2] != 3:
        raise InputError(f"fingertips must have shape ({T}, K, 3), got {tips.shape}")
    K = tips.shape[1]
    if radius.shape != (K,) or observed.shape != (T, K) or len(tuple(finger_names)) != K:
        raise InputError(f"radius must be ({K},), observed ({T}, {K}) and {K} finger names; got "
                         f"{radius.shape}, {observed.shape}, {len(tuple(finger_names))}")
    half = object_model.half_extents
    q = np.einsum("tji,tkj->tki", box.rot, tips - box.pos[:, None, :])
    point, normal, dist = surface_contact(q.reshape(-1, 3), half)
    point, normal = point.reshape(T, K, 3), normal.reshape(T, K, 3)
    gap = dist.reshape(T, K) - radius[None]
    active = np.zeros((T, K), dtype=bool)
    for i in range(T):
        prev = active[i - 1] if i else np.zeros(K, dtype=bool)
        active[i] = np.where(prev, gap[i] <= c.off_m, gap[i] <= c.on_m)
        if c.occlusion_prior and i:
            hidden = ~observed[i] & prev
            active[i] |= hidden
            point[i, hidden] = point[i - 1, hidden]
            normal[i, hidden] = normal[i - 1, hidden]
    sliding = np.zeros((T, K), dtype=bool)
    slide_dir = np.zeros((T, K, 3))
    dt = float(np.median(np.diff(box.t))) if T > 1 else 1.0
    w = int(c.slide_window)
    for i in range(w, T - w):
        span = active[i - w : i + w + 1].all(axis=0)
        v = (point[i + w] - point[i - w]) / (2 * w * dt)
        v -= np.einsum("ki,ki->k", v, normal[i])[:, None] * normal[i]
        speed = np.linalg.norm(v, axis=1)
        s = span & (speed > c.slide_speed_m_s)
        sliding[i] = s
        slide_dir[i, s] = v[s] / speed[s, None]
    return Contacts(finger_names=tuple(finger_names), active=active, sliding=sliding, point=point,
                    normal=normal, slide_dir=slide_dir)
