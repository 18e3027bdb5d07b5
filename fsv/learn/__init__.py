"""Learning how humans share internal grip forces (the paper's §3.6): two small networks.

Modules: :mod:`fsv.learn.config` (what they learn from), :mod:`fsv.learn.nets` (the networks),
:mod:`fsv.learn.train`, :mod:`fsv.learn.model` (a trained model and its file) and
:mod:`fsv.learn.forces` (learned forces from a model). Beside the paper's networks, an end-to-end
one from the tracker's outputs to each finger's 3D force (a baseline of the learned family):
:mod:`fsv.learn.direct_inputs` (its inputs), :mod:`fsv.learn.direct` (the model and its file) and
:mod:`fsv.learn.direct_train` (its training).

* ``ANN_L2`` predicts the amount of internal force, ||f^(i)||_2 over the fingers in contact, [N].
* ``ANN_decomp`` predicts each finger's share, f_k^(i) / ||f^(i)||_2 (dimensionless).

Both take the features of :mod:`fsv.features` (eq. 10-13), are multilayer perceptrons with logistic
(sigmoid) hidden neurons and a linear output (like R's ``neuralnet`` with ``linear.output=TRUE``),
two hidden layers of (6, 7) and (8, 13) neurons as in the paper, and are trained full-batch with
resilient backpropagation (``torch.optim.Rprop``) on standardised inputs. ANN_L2's loss is the
paper's squared error or, with ``LearnConfig.amount_loss="relative"``, the mean relative error
|a_hat - a| / max(a, 1 N), the error the forces are scored by (the shipped model's): when people
who grip differently show the same motion, the first predicts their mean squeeze, the second a
median weighted by 1 / a.

Members. ``LearnConfig.members`` pairs of networks are trained from different initial weights
(one seeded generator, drawn in turn) and their outputs are averaged: the mean norm, and the mean
share vector renormalised. ``members=1`` is the paper's single pair; a few members average out
the dependence of a small network on its initial weights (``fsv-bench train`` and the Table 2
scorer say how many they used).

The person. The paper's features carry the motion and the contact geometry, nothing of who
squeezes, and people add very different amounts of internal force to the same motion. With
``LearnConfig.grip_inputs`` both networks also take the person's grip calibration
(:class:`fsv.grip.GripCalibration`: the amount of internal force against the load, fitted to a
short calibration recording with force sensors), two more inputs after the features. Such a model
assumes, for a person without a calibration, the mean calibration of its training samples.

Fingers not in contact. The hand has a fixed number K of finger slots (thumb first). The input is
``[p1, p3, p2_1..p2_K, p4_1..p4_K, active_1..active_K]`` (2 + 3K values) with p2_k = p4_k = 0 for
a finger not in contact, so the network sees which fingers touch. ``ANN_decomp`` has K outputs;
its loss counts only the fingers in contact, and at prediction time the shares of fingers not in
contact are set to 0 and the remaining shares are rescaled to unit L2 norm, so that the predicted
internal forces have exactly the norm ``ANN_L2`` predicts.

Determinism. Weights are drawn from a ``torch.Generator`` seeded with ``LearnConfig.seed``; the
global torch RNG is neither read nor advanced. Rprop on the full batch has no randomness, and
training runs single-threaded (the thread count is restored afterwards) so that floating-point
reductions happen in one order: the same data and config give bit-identical weights. Everything
is float64.

Forces. :func:`learned_forces` chains the features, the networks and the reconstruction SOCP
(eq. 14, :func:`fsv.forces.reconstruct_forces`): full contact forces that explain the motion and
whose internal normal components follow the predictions. Before the reconstruction, the predicted
amount of internal force (ANN_L2's output) is averaged over time with a Gaussian window of
:data:`AMOUNT_SMOOTHING_S` (:func:`smooth_over_time`); the shares stay per frame. The networks see
one frame's features, which tracked contacts and differentiated poses make noisy, while a person's
squeeze varies slowly; the window was chosen on the ``dev`` suite (docs/findings.md, "The amount
of internal force over time"). The paper's Table 2 protocol scores the networks per sample and
is not smoothed.

Files. :meth:`InternalForceModel.save` writes one NumPy ``.npz`` archive (weights and biases of
every layer, input and target normalisation; a JSON header with the config, finger names and
free-form metadata with the provenance of the environment that first wrote it,
:func:`fsv.provenance.provenance`) atomically, with a SHA-256 of all of that
(:func:`content_sha256`); :func:`load` reads it back without pickles, recomputes the digest and
refuses the file if it differs. Torch is needed to train, not to load or predict: the forward
pass is a few NumPy contractions (no BLAS, so the same bits on every BLAS kernel), which keeps the
~1.4 s import of torch out of every command that only applies a model.
"""

from fsv.learn.config import AMOUNT_LOSSES, GRIP_INPUTS, LearnConfig, TrainingSet
from fsv.learn.direct import DirectConfig, DirectForceModel, DirectPrediction, default_direct_path, load_direct
from fsv.learn.direct_inputs import direct_inputs, input_names
from fsv.learn.direct_train import DirectSamples, train_direct
from fsv.learn.forces import AMOUNT_SMOOTHING_S, learned_forces, smooth_over_time
from fsv.learn.model import FORMAT, VERSION, InternalForceModel, content_sha256, default_model, load, read_state
from fsv.learn.nets import forward
from fsv.learn.train import CrossValidation, cross_validate, relative_errors_pct, train

__all__ = ["AMOUNT_LOSSES", "AMOUNT_SMOOTHING_S", "FORMAT", "GRIP_INPUTS", "VERSION", "CrossValidation",
           "DirectConfig", "DirectForceModel", "DirectPrediction", "DirectSamples", "InternalForceModel", "LearnConfig",
           "TrainingSet", "content_sha256", "cross_validate", "default_direct_path", "default_model", "direct_inputs",
           "forward", "input_names", "learned_forces", "load", "load_direct", "read_state", "relative_errors_pct",
           "smooth_over_time", "train", "train_direct"]
