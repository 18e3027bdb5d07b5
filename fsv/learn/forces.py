"""Learned forces: features, the networks' predictions (the amount averaged over time) and the reconstruction SOCP (eq. 14)."""

from __future__ import annotations

import numpy as np

from fsv._check import positive
from fsv.errors import InputError
from fsv.features import GRAVITY, grasp_features
from fsv.forces import ForceSettings, ForceSolution, reconstruct_forces
from fsv.learn.model import InternalForceModel
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics

AMOUNT_SMOOTHING_S = 1.0
"""Standard deviation of the Gaussian window over which :func:`learned_forces` averages the predicted
amount of internal force, [s]; 0 turns it off. Chosen on ``dev`` with tracked inputs (median error
of the final forces over its 48 episodes: 20.7 % per frame, 19.0 % at 0.1 s, 18.1 % at 0.25 s, 17.3 % at 0.5 s,
17.1 % at 1 s and at 2 s; the middle of the plateau)."""

def learned_forces(
    model: InternalForceModel,
    kinematics: Kinematics,
    contacts: Contacts,
    object_model: ObjectModel,
    *,
    gravity=GRAVITY,
    settings: ForceSettings | None = None,
    smoothing_s: float = AMOUNT_SMOOTHING_S,
    grip=None,
) -> tuple[ForceSolution, np.ndarray]:
    """Full contact forces from vision with human-like internal forces (the paper's Fig. 2b).

    Args:
        model: Trained networks whose finger slots match ``contacts.finger_names``.
        kinematics: Object kinematics (world frame), T frames.
        contacts: Finger contacts (object frame), T frames.
        object_model: The known object (mass, inertia, friction).
        gravity: Gravity, world frame, shape (3,), [m/s^2].
        settings: Settings of the cone program.
        smoothing_s: Standard deviation of the Gaussian window over which the predicted amount of
            internal force is averaged, [s] (:func:`smooth_over_time`); 0: per frame.
        grip: The person's :class:`fsv.grip.GripCalibration`, for a model with grip inputs (None:
            the training samples' mean, see :meth:`InternalForceModel.predict`).

    Returns:
        ``(solution, predicted)``: the reconstruction (eq. 14) and the predicted internal normal
        forces fed to it, shape (T, K), [N] (0 for fingers not in contact).
    """
    if tuple(contacts.finger_names) != model.finger_names:
        raise InputError(f"contacts have fingers {contacts.finger_names}, the model {model.finger_names}")
    if not (np.isfinite(smoothing_s) and smoothing_s >= 0):
        raise InputError(f"smoothing_s must be a finite number of seconds >= 0, got {smoothing_s!r}")
    features = grasp_features(kinematics, contacts, object_model, gravity=gravity)
    ok = kinematics.valid[:, None] & contacts.active
    x = features.matrix()
    x = np.where(np.isfinite(x), x, 0.0)
    amount, shares, _ = model.predict(x, contacts.active, grip)
    if smoothing_s > 0:
        amount = smooth_over_time(amount, kinematics.t, ok.any(axis=1), smoothing_s)
    predicted = np.where(ok, amount[:, None] * shares, 0.0)
    target = np.where(ok, predicted, np.nan)
    solution = reconstruct_forces(kinematics, contacts, object_model, target, gravity=gravity, settings=settings)
    return solution, predicted


def smooth_over_time(values: np.ndarray, t: np.ndarray, defined: np.ndarray, sigma_s: float) -> np.ndarray:
    """Gaussian-weighted average of a per-frame signal over the frames where it is defined.

    At frame i the result is sum_j w_ij v_j / sum_j w_ij over the defined frames j, with
    w_ij = exp(-(t_i - t_j)^2 / (2 sigma^2)) truncated at 4 sigma: a window that ends at the video's
    edges or at undefined frames is renormalised rather than padded. Frames are taken as evenly
    spaced (the window in frames is ``sigma_s`` over the mean frame interval). The sums run in
    SciPy's own loops (no BLAS), so the result has the same bits under every BLAS kernel.

    Args:
        values: The signal, shape (T,).
        t: Frame times, shape (T,), [s].
        defined: Frames where the signal is defined, shape (T,).
        sigma_s: The window's standard deviation, [s]; > 0.

    Returns:
        The averaged signal, shape (T,); 0 where no defined frame lies within the window or where
        ``defined`` is False.
    """
    from scipy.ndimage import gaussian_filter1d  # lazy: scipy.ndimage (40 ms) off `import fsv`

    v = np.asarray(values, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    d = np.asarray(defined, dtype=bool)
    if not (v.ndim == 1 and t.shape == v.shape == d.shape):
        raise InputError(f"values, t and defined must be (T,) arrays of one length, got {v.shape}, {t.shape}, {d.shape}")
    positive("sigma_s", sigma_s, "a finite number of seconds > 0")
    if v.size < 2:
        return np.where(d, v, 0.0)
    sigma = sigma_s / float(np.mean(np.diff(t)))
    weight = gaussian_filter1d(d.astype(np.float64), sigma, mode="constant", truncate=4.0)
    total = gaussian_filter1d(np.where(d, v, 0.0), sigma, mode="constant", truncate=4.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / weight
    return np.where(d & (weight > 0), out, 0.0)
