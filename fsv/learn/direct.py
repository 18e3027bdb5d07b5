"""An end-to-end network from the tracker's outputs to each finger's 3D force: :class:`DirectForceModel`.

A careful baseline of the learned family (EgoPHI, PressureVision++ and their kin predict forces
end to end), given what the model-based reference is given after tracking
(:mod:`fsv.learn.direct_inputs`: the box's kinematics, its contacts, the lab's box) and none of
its physics beyond the required wrench as an input: no cone program, no Newton–Euler constraint.

Outputs, per frame, in the object frame: the 3D force of each of the K fingers on the box [N]
(3K values, finger-major, x, y, z), then the table's force [N] and torque about the centre of mass
[N m] on the box (6 values). A finger the contacts leave inactive gets zero force; the table's
wrench is zero when the box is clearly off the table: its lowest corner more than
:attr:`DirectConfig.off_table_m` above it (:func:`fsv.learn.direct_inputs.lowest_height`). A frame
without kinematics gets NaN.

The network is a multilayer perceptron with rectified hidden layers and a linear output on
standardised inputs and outputs, trained in torch (:mod:`fsv.learn.direct_train`) and applied in
NumPy (:func:`fsv.learn.nets.forward`: einsum contractions and max(h, 0), no BLAS and no
transcendental function, so the same bits on every machine).

Files. :meth:`DirectForceModel.save` writes one ``.npz`` (weights, normalisation, and a JSON
header with the config, finger names and metadata with the provenance), atomically, with the
SHA-256 of its content (:func:`fsv.learn.model.content_sha256`); :func:`load_direct` reads it back
without pickles and refuses it if the digest differs, as :func:`fsv.learn.load` does for the
internal-force networks.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import asdict, dataclass
from importlib.resources import files

import numpy as np

from fsv.errors import InputError, one_line
from fsv.learn.direct_inputs import check_window, direct_inputs, input_names, lowest_height
from fsv.learn.model import _holds_objects, checked_state, content_sha256, write_npz
from fsv.learn.nets import forward
from fsv.provenance import provenance

FORMAT = "fsv-direct-forces"
VERSION = 1
DEFAULT_FILE = "direct_forces.npz"
"""The shipped model's file name in ``fsv/data`` (made by ``fsv-bench train-direct``; see docs/methods.md)."""

ACTIVATION = "relu"
TABLE_OUTPUTS = 6


@dataclass(frozen=True)
class DirectConfig:
    """Architecture, inputs and training of the end-to-end network.

    Attributes:
        hidden: Hidden layer sizes.
        window: Frames of kinematics on either side among the inputs (0: the frame alone; the
            reference's differentiator already spans 7 frames).
        off_table_m: The box is clearly off the table, and the table's wrench zero, when its lowest
            corner is higher than this above it, [m] (four times the tracker's median position
            error of about 5 mm under lab knowledge).
        epochs: Passes over the training samples.
        batch: Samples per Adam step.
        lr: Adam's step size.
        weight_decay: Adam's L2 penalty on the weights.
        val_fraction: Share of the training episodes held out to choose the epoch (the weights of
            the epoch with the least validation loss are kept); 0: the last epoch's.
        seed: Seed of the initial weights, the order of the samples and the held-out episodes.
    """

    hidden: tuple = (128, 128)
    window: int = 0
    off_table_m: float = 0.02
    epochs: int = 60
    batch: int = 256
    lr: float = 1e-3
    weight_decay: float = 0.0
    val_fraction: float = 0.1
    seed: int = 0

    def __post_init__(self):
        h = tuple(self.hidden)
        if not h or any(isinstance(v, bool) or int(v) != v or v < 1 for v in h):
            raise InputError(f"DirectConfig.hidden must be a non-empty tuple of positive sizes, got {self.hidden!r}")
        object.__setattr__(self, "hidden", tuple(int(v) for v in h))
        object.__setattr__(self, "window", check_window(self.window))
        for name, low in (("epochs", 1), ("batch", 1), ("seed", 0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise InputError(f"DirectConfig.{name} must be an integer >= {low}, got {v!r}")
            object.__setattr__(self, name, int(v))
        for name, ok, what in (("off_table_m", lambda v: v > 0, "> 0 m"), ("lr", lambda v: v > 0, "> 0"),
                               ("weight_decay", lambda v: v >= 0, ">= 0"),
                               ("val_fraction", lambda v: 0 <= v < 1, "in [0, 1)")):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or not ok(v):
                raise InputError(f"DirectConfig.{name} must be a number {what}, got {v!r}")
            object.__setattr__(self, name, float(v))


@dataclass(frozen=True)
class DirectPrediction:
    """What :meth:`DirectForceModel.predict` returns for T frames and K fingers.

    Attributes:
        force: Each finger's force on the box, object frame, shape (T, K, 3), [N]; 0 where the
            finger is not in contact, NaN on frames without kinematics.
        table: The table's force [N] and torque about the centre of mass [N m] on the box, object
            frame, shape (T, 6); 0 where the box is clearly off the table, NaN without kinematics.
        valid: Frames with kinematics, shape (T,).
        on_table: Frames where the table's wrench is predicted (not clearly off it), shape (T,).
    """

    force: np.ndarray
    table: np.ndarray
    valid: np.ndarray
    on_table: np.ndarray


def on_table(height: np.ndarray, off_table_m: float) -> np.ndarray:
    """Frames whose box is not clearly off the table: lowest corner at most ``off_table_m`` [m]
    above it, shape (T,) (False where the height is NaN)."""
    with np.errstate(invalid="ignore"):
        return np.asarray(height, float) <= off_table_m


class DirectForceModel:
    """The trained network with its normalisation.

    Attributes:
        config: How it was built and trained (:class:`DirectConfig`).
        finger_names: The K finger slots, thumb first.
        x_mean, x_std: Input standardisation, shape (n_in,) (:func:`fsv.learn.direct_inputs.input_names`).
        y_mean, y_std: Output standardisation, shape (3K + 6,), [N and N m].
        layers: (weight (out, in), bias (out,)) float64 per layer.
        metadata: Free-form description (dataset, command, losses, timing); JSON-like values only.
    """

    def __init__(self, config: DirectConfig, finger_names, x_mean, x_std, y_mean, y_std, layers, metadata=None):
        if not isinstance(config, DirectConfig):
            raise InputError(f"config must be an fsv.learn.DirectConfig, got {type(config).__name__}")
        self.config = config
        self.finger_names = tuple(str(n) for n in finger_names)
        self.x_mean, self.x_std = np.asarray(x_mean, np.float64), np.asarray(x_std, np.float64)
        self.y_mean, self.y_std = np.asarray(y_mean, np.float64), np.asarray(y_std, np.float64)
        self.layers = [(np.asarray(W, np.float64), np.asarray(b, np.float64)) for W, b in layers]
        self.metadata = dict(metadata or {})
        sizes = [self.num_inputs, *config.hidden, self.num_outputs]
        got = [(W.shape, b.shape) for W, b in self.layers]
        want = [((o, i), (o,)) for i, o in zip(sizes[:-1], sizes[1:])]
        if got != want:
            raise InputError(f"the layers have shapes {got}, the config and {len(self.finger_names)} fingers need {want}")
        for name, n in (("x_mean", self.num_inputs), ("x_std", self.num_inputs), ("y_mean", self.num_outputs),
                        ("y_std", self.num_outputs)):
            v = getattr(self, name)
            if v.shape != (n,) or not np.all(np.isfinite(v)) or (name.endswith("std") and np.any(v <= 0)):
                raise InputError(f"{name} must hold {n} finite values{' > 0' if name.endswith('std') else ''}, "
                                 f"got shape {v.shape}")

    @property
    def num_fingers(self) -> int:
        return len(self.finger_names)

    @property
    def num_inputs(self) -> int:
        return len(input_names(self.finger_names, self.config.window))

    @property
    def num_outputs(self) -> int:
        """3K finger force components and the table's 6."""
        return 3 * self.num_fingers + TABLE_OUTPUTS

    @property
    def num_parameters(self) -> int:
        """Weights and biases."""
        return int(sum(W.size + b.size for W, b in self.layers))

    def predict_inputs(self, x: np.ndarray) -> np.ndarray:
        """The network's raw outputs (before any zeroing) of inputs ``x``, shape (N, n_in) -> (N, 3K + 6),
        [N, N m]; NaN rows stay NaN."""
        x = np.asarray(x, np.float64)
        if x.ndim != 2 or x.shape[1] != self.num_inputs:
            raise InputError(f"predict_inputs expects inputs of shape (N, {self.num_inputs}), got {x.shape}")
        z = (x - self.x_mean) / self.x_std
        return forward(self.layers, z, ACTIVATION) * self.y_std + self.y_mean

    def predict(self, kinematics, contacts, object_model, gravity) -> DirectPrediction:
        """Each finger's force and the table's wrench on every frame (see the module docstring).

        Args:
            kinematics: The box's kinematics in the table's frame (the table at z = 0), T frames.
            contacts: The contacts (object frame), T frames, the model's K fingers in its order.
            object_model: The box as the method knows it.
            gravity: Gravity in the kinematics' frame, shape (3,), [m/s^2].
        """
        if tuple(contacts.finger_names) != self.finger_names:
            raise InputError(f"the contacts have fingers {tuple(contacts.finger_names)}, the model {self.finger_names}")
        x, valid = direct_inputs(kinematics, contacts, object_model, gravity, window=self.config.window)
        K, T = self.num_fingers, len(x)
        out = np.full((T, self.num_outputs), np.nan)
        if valid.any():
            out[valid] = self.predict_inputs(x[valid])
        active = np.asarray(contacts.active, bool)
        force = np.where(active[..., None], out[:, :3 * K].reshape(T, K, 3), 0.0)
        table_on = on_table(lowest_height(kinematics, object_model), self.config.off_table_m) & valid
        table = np.where(table_on[:, None], out[:, 3 * K:], 0.0)
        force[~valid], table[~valid] = np.nan, np.nan
        return DirectPrediction(force=force, table=table, valid=valid, on_table=table_on)

    def state(self) -> dict:
        """What :meth:`save` writes: the model, its metadata (with ``provenance`` unless it has one)
        and ``sha256``, the digest of the rest."""
        metadata = dict(self.metadata)
        metadata.setdefault("provenance", provenance())
        st = {
            "format": FORMAT, "version": VERSION, "config": asdict(self.config), "finger_names": list(self.finger_names),
            "x_mean": self.x_mean.copy(), "x_std": self.x_std.copy(), "y_mean": self.y_mean.copy(),
            "y_std": self.y_std.copy(),
            "layers": [{"weight": W.copy(), "bias": b.copy()} for W, b in self.layers], "metadata": metadata,
        }
        st["sha256"] = content_sha256(st)
        return st

    def save(self, path) -> None:
        """Writes the model to ``path`` atomically (see the module docstring)."""
        write_npz(path, _to_arrays(self.state()))


_ARRAYS = ("x_mean", "x_std", "y_mean", "y_std")


def _to_arrays(state: dict) -> dict:
    arrays = {k: state[k] for k in _ARRAYS}
    for i, layer in enumerate(state["layers"]):
        arrays[f"layer.{i}.weight"], arrays[f"layer.{i}.bias"] = layer["weight"], layer["bias"]
    header = {k: v for k, v in state.items() if k not in (*_ARRAYS, "layers")}
    header["num_layers"] = len(state["layers"])
    arrays["header"] = np.array(json.dumps(header, allow_nan=False))
    return arrays


def read_direct_state(path) -> dict:
    """The raw content of a direct model file (what :meth:`DirectForceModel.state` wrote), unchecked.

    Raises:
        InputError: If the file is not an ``.npz`` archive or a member holds Python objects.
    """
    if not zipfile.is_zipfile(path):
        raise InputError(f"{os.fspath(path)!r} is not a .npz archive (a direct force model is one, written by "
                         "fsv-bench train-direct)")
    with np.load(path, allow_pickle=False) as npz:
        for name in npz.files:
            if _holds_objects(npz.zip, name + ".npy"):
                raise InputError(f"{os.fspath(path)!r}: member {name!r} holds Python objects; a model holds "
                                 "numeric arrays only")
        state = json.loads(str(npz["header"][()]))
        n = state.pop("num_layers")
        for k in _ARRAYS:
            state[k] = npz[k]
        state["layers"] = [{"weight": npz[f"layer.{i}.weight"], "bias": npz[f"layer.{i}.bias"]} for i in range(n)]
    return state


def load_direct(path) -> DirectForceModel:
    """Reads a model written by :meth:`DirectForceModel.save` and checks its digest.

    Raises:
        InputError: If the file is missing, not a direct force model of this version, or its
            content does not match the digest stored in it; the message names the file.
    """
    path = os.fspath(path)
    st = checked_state(path, read_direct_state, what="direct force model", file_format=FORMAT, version=VERSION)
    try:
        config = DirectConfig(**{k: tuple(v) if k == "hidden" else v for k, v in dict(st["config"]).items()})
        return DirectForceModel(config, st["finger_names"], st["x_mean"], st["x_std"], st["y_mean"], st["y_std"],
                                [(layer["weight"], layer["bias"]) for layer in st["layers"]], st["metadata"])
    except (KeyError, TypeError, AttributeError, ValueError, InputError) as e:
        raise InputError(f"{path!r} has inconsistent direct force model data: {one_line(e)}") from e


def default_direct_path() -> str:
    """Where the shipped direct model lives: ``fsv/data/direct_forces.npz`` (it may be absent)."""
    return os.fspath(files("fsv").joinpath("data", DEFAULT_FILE))
