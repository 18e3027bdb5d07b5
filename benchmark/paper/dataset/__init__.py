"""Training data for the internal-force networks without tactile hardware (the paper's §3.6).

Each episode of a grid of scenarios (tasks x users x grasps x masses x seeds) is simulated; per
frame we compute the features p1, p2_k, p3, p4_k (eq. 10-13, :mod:`fsv.features`) from the object's
kinematics and the contacts, and the targets from the decomposition SOCP (eq. 9,
:func:`fsv.forces.decompose_forces`) fed with the "tactile measurements": the truth's normal force of each
finger. As in the paper, samples whose vision and tactile net forces differ by more than
``max_gap_n`` (1.5 N) are dropped. The vision net force is F_c = m (a - g) from the kinematics the
features use; the tactile net force is the resultant of the truth's finger forces (so frames where
the table still carries the box are dropped too). Frames with fewer than ``min_fingers`` fingers in
contact (no internal force is possible) or invalid kinematics are dropped as well.

Sources. By default (``contacts="tracker"``) every episode goes through the method proper, as
``fsv-bench`` does: the depth video is rendered (``benchmark.camera.render``), the tracker
(``fsv.track.track``, with the benchmark's seeded first-frame initialisation and the same random
streams as ``fsv-bench``) estimates the box poses and the contacts, and the kinematics are the
algebraic differentiator of ``benchmark.world.motion`` on the tracked poses. Two cheaper, labelled
alternatives skip rendering and tracking: ``"error-model"``, the truth's contacts moved by the
paper's measured contact-point error (mean -1.55 mm, std 6.13 mm per axis, white in time,
``benchmark.world.contact_error``) with kinematics differentiated from tracker-like poses
(``benchmark.world.pose_error``); and ``"oracle"``, the truth's contacts (an ablation). ``kinematics=
"oracle"`` takes the true kinematics (an ablation). The dataset records its sources in
``dataset.json`` and in every file, and every report labels them.

Layout of a dataset folder::

    dataset.json              spec, sources, format version and the world's fingerprint (a resumed
                              run must match them), and the
                              provenance of the run that made it (``resumed_with``: of later runs)
    episodes/<id>.parquet     one table per episode (one row per kept frame), written atomically;
                              its bytes depend only on the episode (the same from a pool or Ray)
    episodes/<id>.seconds.json  how long it took to build (for the manifest's ``seconds``)
    manifest.parquet          one row per episode (counts, timing, status, SHA-256 of the file's
                              bytes), rebuilt from the files

Integrity. Every table (episodes and manifest) carries the SHA-256 of its own content in its
metadata (:mod:`benchmark.sealed_table`), and the manifest records the SHA-256 of each episode
file's bytes. :func:`load_dataset` checks both and that each file holds the episode its name says;
so does a resumed :func:`generate`, which reports a bad file on stderr and builds it again. Both
digests are needed: the content digest lets a file be checked on its own (an interrupted run has
no manifest yet), but about one in ten random 4-byte flips in a Parquet file hits bytes that no
reader uses (e.g. column statistics) and leaves the content as it was; the bytes' digest in the
manifest sees every flip.

Columns of an episode table: ``episode, task, user, grasp, mass, seed, frame, t``; the world-frame
kinematics ``pos_*, rot_00..rot_22, vel_*, acc_*, omega_*, alpha_*``; the features ``p1, p3,
p2_<finger>, p4_<finger>``; per finger ``active_, sliding_, point_{x,y,z}_, normal_{x,y,z}_,
slide_{x,y,z}_`` (object frame), ``f_meas_`` (tactile reading, [N], 0 off contact), ``f_true_`` (the
truth's normal force, the scoring reference), ``true_active_`` and ``true_point_{x,y,z}_`` (the
truth's contact, object frame: for scoring and for measuring contact errors only, never an input),
``F_true_{x,y,z}_`` (the truth's 3D force of the finger on the box, object frame, [N], 0 off
contact); ``f_nom_`` and ``f_int_`` (nominal and internal normal components from eq. 9, [N]; NaN on
rows the paper's rules do not keep); ``env_F_{x,y,z}``, ``env_T_{x,y,z}`` (the table's force [N]
and torque about the centre of mass [N m] on the box, object frame); ``paper_rule`` (the paper's
rules keep the row); ``net_gap_n``. Rows (``DatasetSpec.rows``): the frames the paper's rules keep
("paper"), or every frame with kinematics ("all", for the end-to-end network of
``fsv-bench train-direct``).
With the tracker, each file's metadata also holds the tracker's scores on the episode
(``benchmark.scores.tracking.score_tracking``). Read them with pandas
(``pd.read_parquet``) or :func:`load_dataset`.

Running. A local process pool over all cores by default, with a progress bar; or Ray
(``ray_address``; ``pip install 'fsv-bench[ray]'``), whose workers return tables to this process.
Either way only this process writes files: each episode goes to a temporary file that is renamed
into place, so an interrupted run (crash, Ctrl-C) leaves only complete episodes, and running the
same command again does the missing ones. A failed episode (e.g. the box was dropped) is written
as an empty table whose metadata holds the error, so it is neither lost nor retried forever.
"""

from benchmark.paper.dataset.build import build_episode, generate
from benchmark.paper.dataset.files import (
                                           finger_names_of,
                                           frames_of,
                                           load_dataset,
                                           read_episode_file,
                                           read_manifest,
                                           training_set,
                                           write_manifest,
)
from benchmark.paper.dataset.spec import CONTACTS, FORMAT, KINEMATICS, ROWS, VERSION, DatasetSpec

__all__ = ["CONTACTS", "FORMAT", "KINEMATICS", "ROWS", "VERSION", "DatasetSpec", "build_episode", "finger_names_of", "frames_of",
           "generate", "load_dataset", "read_episode_file", "read_manifest", "training_set", "write_manifest"]
