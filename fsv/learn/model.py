"""A trained pair of networks (:class:`InternalForceModel`) and its file: saved, read and checked."""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from dataclasses import asdict
from importlib.resources import files

import numpy as np

from fsv.digest import tree_sha256
from fsv.errors import InputError, one_line
from fsv.features import Features
from fsv.learn.config import GRIP_INPUTS, LearnConfig
from fsv.learn.nets import forward
from fsv.provenance import provenance

FORMAT = "fsv-internal-forces"
VERSION = 4  # versions 1 and 2 carried no digest; 3 was a torch archive. None of them is read


class InternalForceModel:
    """The trained pair of networks with their normalisation.

    Attributes:
        config: How they were built and trained.
        finger_names: The K finger slots, thumb first.
        x_mean, x_std: Input standardisation, shape (2 + 3K,), or (2 + 3K + 2,) with grip inputs.
        l2_mean, l2_std: Standardisation of ANN_L2's target, [N].
        net_l2, net_decomp: The networks, one per member (lists of ``config.members``); each is its
            list of (weight (out, in), bias (out,)) float64 layers (see :func:`forward`).
        metadata: Free-form description (dataset, command, losses); JSON-like values only.
        grip_mean: With grip inputs, the mean grip calibration of the training samples, shape (2,):
            what :meth:`predict` assumes for a person without one; None otherwise.
    """

    def __init__(self, config, finger_names, x_mean, x_std, l2_mean, l2_std, net_l2, net_decomp, metadata=None,
                 grip_mean=None):
        self.config = config
        self.finger_names = tuple(str(n) for n in finger_names)
        self.x_mean = np.asarray(x_mean, dtype=np.float64)
        self.x_std = np.asarray(x_std, dtype=np.float64)
        self.l2_mean = float(l2_mean)
        self.l2_std = float(l2_std)
        self.net_l2 = [[(np.asarray(W, np.float64), np.asarray(b, np.float64)) for W, b in net] for net in net_l2]
        self.net_decomp = [[(np.asarray(W, np.float64), np.asarray(b, np.float64)) for W, b in net] for net in net_decomp]
        if len(self.net_l2) != len(self.net_decomp) or not self.net_l2:
            raise InputError(f"a model needs as many ANN_L2 as ANN_decomp networks (>= 1), got {len(self.net_l2)}, "
                             f"{len(self.net_decomp)}")
        self.metadata = dict(metadata or {})
        if config.grip_inputs:
            g = np.asarray(grip_mean if grip_mean is not None else np.full(GRIP_INPUTS, np.nan), dtype=np.float64)
            if g.shape != (GRIP_INPUTS,) or not np.all(np.isfinite(g)):
                raise InputError(f"a model with grip inputs needs a finite grip_mean of shape ({GRIP_INPUTS},), got {grip_mean!r}")
            self.grip_mean = g
        else:
            self.grip_mean = None

    @property
    def num_fingers(self) -> int:
        return len(self.finger_names)

    @property
    def num_inputs(self) -> int:
        """Network inputs: 2 + 3K features, and 2 more with grip inputs."""
        return 2 + 3 * self.num_fingers + (GRIP_INPUTS if self.config.grip_inputs else 0)

    def grip_columns(self, grip, n: int) -> np.ndarray:
        """The grip inputs of ``n`` samples, shape (n, 2): ``grip`` ((2,), (n, 2), a
        :class:`fsv.grip.GripCalibration`, or None for :attr:`grip_mean`)."""
        if grip is None:
            g = self.grip_mean
        elif hasattr(grip, "vector"):
            g = grip.vector()
        else:
            g = np.asarray(grip, dtype=np.float64)
        g = np.broadcast_to(g, (n, GRIP_INPUTS)) if np.shape(g) in ((GRIP_INPUTS,), (n, GRIP_INPUTS)) else None
        if g is None or not np.all(np.isfinite(g)):
            raise InputError(f"grip must be a GripCalibration, or finite values of shape ({GRIP_INPUTS},) or "
                             f"({n}, {GRIP_INPUTS}), got {grip!r:.80}")
        return g

    def predict(self, x: np.ndarray, active: np.ndarray, grip=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Predicts the internal forces of each finger in contact.

        Args:
            x: The paper's features, shape (N, 2 + 3K) (see :meth:`fsv.features.Features.matrix`).
            active: Finger in contact, shape (N, K).
            grip: With grip inputs, the person's grip calibration (see :meth:`grip_columns`);
                None assumes the training samples' mean. Ignored by a model without grip inputs.

        Returns:
            ``(l2, shares, internal)``: the internal-force norm, shape (N,), [N] (clipped at 0);
            the per-finger shares, shape (N, K), unit L2 norm over the active fingers and 0
            elsewhere; and the internal normal forces l2 * shares, shape (N, K), [N]. With several
            members, the norm is their mean and the shares their mean, renormalised.
        """
        x = np.asarray(x, dtype=np.float64)
        a = np.asarray(active, dtype=bool)
        K = self.num_fingers
        if x.ndim != 2 or x.shape[1] != 2 + 3 * K or a.shape != (x.shape[0], K):
            raise InputError(f"predict expects x of shape (N, {2 + 3 * K}) and active of shape (N, {K}), got {x.shape}, {a.shape}")
        if self.config.grip_inputs:
            x = np.concatenate([x, self.grip_columns(grip, x.shape[0])], axis=1)
        z = (x - self.x_mean) / self.x_std
        l2 = np.mean([forward(net, z)[:, 0] for net in self.net_l2], axis=0) * self.l2_std + self.l2_mean
        s = np.zeros((x.shape[0], K))
        for net in self.net_decomp:
            out = np.where(a, forward(net, z), 0.0)
            n = np.linalg.norm(out, axis=1)
            s += out / np.where(n > 0, n, 1.0)[:, None]
        norm = np.linalg.norm(s, axis=1)
        s = s / np.where(norm > 0, norm, 1.0)[:, None]
        l2 = np.maximum(l2, 0.0)
        return l2, s, l2[:, None] * s

    def predict_features(self, features: Features, grip=None) -> np.ndarray:
        """Internal normal forces per finger, shape (T, K), [N], from :class:`Features` (and the
        person's grip calibration, see :meth:`predict`)."""
        if features.num_fingers != self.num_fingers:
            raise InputError(f"features have {features.num_fingers} fingers, the model {self.num_fingers} ({self.finger_names})")
        return self.predict(features.matrix(), features.active, grip)[2]

    def state(self) -> dict:
        """What :meth:`save` writes: the model, its metadata and ``sha256``, the digest of the rest.

        The metadata gains ``provenance`` (:func:`fsv.provenance.provenance`) unless it has one
        already (a model read from a file keeps the provenance of the environment that wrote it).
        """

        metadata = dict(self.metadata)
        if "provenance" not in metadata:
            metadata["provenance"] = provenance()
        st = {
            "format": FORMAT,
            "version": VERSION,
            "config": asdict(self.config),
            "finger_names": list(self.finger_names),
            "x_mean": self.x_mean.copy(),
            "x_std": self.x_std.copy(),
            "l2_mean": self.l2_mean,
            "l2_std": self.l2_std,
            "net_l2": [[{"weight": W.copy(), "bias": b.copy()} for W, b in net] for net in self.net_l2],
            "net_decomp": [[{"weight": W.copy(), "bias": b.copy()} for W, b in net] for net in self.net_decomp],
            "metadata": metadata,
        }
        if self.grip_mean is not None:
            st["grip_mean"] = [float(v) for v in self.grip_mean]
        st["sha256"] = content_sha256(st)
        return st

    def save(self, path) -> None:
        """Writes the model to ``path`` atomically (temporary file in the same folder, then rename)."""
        write_npz(path, _to_arrays(self.state()))


def write_npz(path, arrays: dict) -> None:
    """Writes ``arrays`` as an ``.npz`` archive to ``path`` atomically (a temporary file in the same
    folder, then a rename), readable by everyone like any data file."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".npz")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)  # mkstemp makes it private; a model is shared like any data file
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def content_sha256(state: dict) -> str:
    """SHA-256 of a model file's content: every entry of ``state`` but ``sha256`` (format, config,
    finger names, normalisation, every weight array's dtype, shape and bytes, metadata), in a
    canonical order (:func:`fsv.digest.tree_sha256`)."""
    return tree_sha256({k: v for k, v in state.items() if k != "sha256"})


_NETS = ("net_l2", "net_decomp")


def _to_arrays(state: dict) -> dict:
    """The ``.npz`` members of a state: its arrays by name, and the rest as a JSON ``header``."""
    arrays = {"x_mean": state["x_mean"], "x_std": state["x_std"]}
    header = {k: v for k, v in state.items() if k not in ("x_mean", "x_std", *_NETS)}
    header["layers"] = {}
    for key in _NETS:
        header["layers"][key] = [len(net) for net in state[key]]
        for m, net in enumerate(state[key]):
            for i, layer in enumerate(net):
                arrays[f"{key}.{m}.{i}.weight"] = layer["weight"]
                arrays[f"{key}.{m}.{i}.bias"] = layer["bias"]
    arrays["header"] = np.array(json.dumps(header, allow_nan=False))
    return arrays


def _from_arrays(npz) -> dict:
    """The state of a model file's ``.npz`` members (the inverse of :func:`_to_arrays`)."""
    state = json.loads(str(npz["header"][()]))
    layers = state.pop("layers")
    state["x_mean"], state["x_std"] = npz["x_mean"], npz["x_std"]
    for key in _NETS:
        state[key] = [[{"weight": npz[f"{key}.{m}.{i}.weight"], "bias": npz[f"{key}.{m}.{i}.bias"]} for i in range(n)]
                      for m, n in enumerate(layers[key])]
    return state


def read_state(path) -> dict:
    """The raw content of a model file (what :meth:`InternalForceModel.state` wrote), unchecked.

    Raises:
        InputError: If the file is not a ``.npz`` archive or a member holds Python objects (never
            loaded).
    """
    if not zipfile.is_zipfile(path):
        raise InputError(f"{os.fspath(path)!r} is not a .npz archive (an internal-force model is one, written by "
                         "fsv-bench train)")
    with np.load(path, allow_pickle=False) as npz:
        for name in npz.files:
            if _holds_objects(npz.zip, name + ".npy"):
                raise InputError(f"{os.fspath(path)!r}: member {name!r} holds Python objects; a model holds "
                                 "numeric arrays only")
        return _from_arrays(npz)


def _holds_objects(archive, member: str) -> bool:
    """Whether a ``.npy`` member of a zip archive declares an object dtype (from its header alone)."""
    if member not in archive.namelist():
        return False
    with archive.open(member) as fp:
        major, _ = np.lib.format.read_magic(fp)
        read = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
        return read(fp)[2].hasobject


def checked_state(path: str, read, *, what: str, file_format: str, version: int) -> dict:
    """A model file's state read by ``read(path)`` and checked: it exists, reads, has the format
    ``file_format`` and ``version``, and its content matches the SHA-256 stored in it.

    Raises:
        InputError: Naming the file and what is wrong (``what`` names the kind of model).
    """
    if not os.path.isfile(path):
        raise InputError(f"no {what} at {path!r}")
    try:
        st = read(path)
    except Exception as e:  # a truncated, corrupt or foreign file: report it as bad input
        raise InputError(f"{path!r} is not a readable {what}: {one_line(e)}") from e
    if not isinstance(st, dict) or st.get("format") != file_format:
        raise InputError(f"{path!r} is not an {file_format} file")
    if st.get("version") != version:
        raise InputError(f"{path!r} is an {file_format} file of version {st.get('version')!r}; this fsv reads version "
                         f"{version} (train the model again)")
    try:
        digest = content_sha256(st)
    except InputError as e:
        raise InputError(f"{path!r} is corrupt: {e}") from e
    if st.get("sha256") != digest:
        raise InputError(f"{path!r} is corrupt: its content has SHA-256 {digest[:16]}..., the file records "
                         f"{str(st.get('sha256'))[:16]}...")
    return st


def load(path) -> InternalForceModel:
    """Reads a model written by :meth:`InternalForceModel.save` and checks its digest.

    Raises:
        InputError: If the file is missing, is not an internal-force model of this version, or its
            content does not match the digest stored in it (flipped bytes, a truncated or edited
            file); the message names the file.
    """
    path = os.fspath(path)
    st = checked_state(path, read_state, what="internal-force model", file_format=FORMAT, version=VERSION)
    try:
        config = LearnConfig(**dict(st["config"]))
        K = len(st["finger_names"])
        nets = {key: [[(layer["weight"], layer["bias"]) for layer in net] for net in st[key]] for key in _NETS}
        for key, hidden, n_out in (("net_l2", config.hidden_l2, 1), ("net_decomp", config.hidden_decomp, K)):
            sizes = [2 + 3 * K + (GRIP_INPUTS if config.grip_inputs else 0), *hidden, n_out]
            for net in nets[key]:
                if [W.shape for W, _ in net] != list(zip(sizes[1:], sizes[:-1])) or \
                        [b.shape for _, b in net] != [(n,) for n in sizes[1:]]:
                    raise InputError(f"{key} layers do not have the config's sizes {sizes}")
        return InternalForceModel(config, st["finger_names"], st["x_mean"], st["x_std"], st["l2_mean"], st["l2_std"],
                                  nets["net_l2"], nets["net_decomp"], st["metadata"], st.get("grip_mean"))
    except (KeyError, TypeError, AttributeError, ValueError, InputError) as e:
        raise InputError(f"{path!r} has inconsistent internal-force model data: {one_line(e)}") from e


SHIPPED_MODELS = {False: "internal_forces.npz", True: "internal_forces_blind.npz"}
"""The two models shipped in ``fsv/data``, by ``blind``: trained on the same samples of the same
training people with the same recipe, one with the person's grip calibration among its inputs
(``LearnConfig.grip_inputs``), one user-blind (the paper's networks)."""


def default_model(*, blind: bool = False) -> InternalForceModel:
    """A model shipped with the package; see docs/data.md for the commands that trained them and
    the data they were trained on.

    Args:
        blind: False: the model with grip inputs (``fsv/data/internal_forces.npz``), for a person
            whose grip calibration is known. True: the user-blind model
            (``fsv/data/internal_forces_blind.npz``), for a person of whom nothing is known.
            Fed no calibration, the first assumes its training people's mean line, which errs far
            more on a new person than a network trained without one (docs/findings.md).
    """
    if not isinstance(blind, bool):
        raise InputError(f"default_model: blind must be True or False, got {blind!r}")

    return load(files("fsv").joinpath("data", SHIPPED_MODELS[blind]))
