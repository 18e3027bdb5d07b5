"""A frames dataset's card (``README.md``, Hugging Face form) and its Croissant 1.0 metadata (``croissant.json``).

Both are written by ``fsv-bench generate --frames`` from the dataset's index, after every shard:
the card's YAML header names the data's licence (:data:`DATA_LICENSE`), the task categories, the
size and the configs; ``croissant.json`` describes the index (a FileObject with its SHA-256 and a
RecordSet of its columns), the shards (a FileSet: HDF5, which Croissant's readers do not open, so
the index is the record set that lists them) and every array of a shard (a RecordSet with its
records inline), and fills the responsible-AI (RAI) fields. Neither
holds a date or a host name: the same dataset gives the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import os

from benchmark.atomic import write_text

DATA_LICENSE = ("cc-by-4.0", "https://creativecommons.org/licenses/by/4.0/", "CC BY 4.0")
"""The generated data's licence: (Hugging Face id, URL, name)."""
CODE_LICENSE = "MIT"
"""The licence of fsv-bench's code (pyproject.toml's ``license``), which generates the data."""
CROISSANT_CONTEXT = {
    "@language": "en", "@vocab": "https://schema.org/", "citeAs": "cr:citeAs", "column": "cr:column",
    "conformsTo": "dct:conformsTo", "cr": "http://mlcommons.org/croissant/", "rai": "http://mlcommons.org/croissant/RAI/",
    "data": {"@id": "cr:data", "@type": "@json"}, "dataType": {"@id": "cr:dataType", "@type": "@vocab"},
    "dct": "http://purl.org/dc/terms/", "equivalentProperty": "cr:equivalentProperty", "examples": {"@id": "cr:examples", "@type": "@json"}, "extract": "cr:extract",
    "field": "cr:field", "fileProperty": "cr:fileProperty", "fileObject": "cr:fileObject", "fileSet": "cr:fileSet",
    "format": "cr:format", "includes": "cr:includes", "isLiveDataset": "cr:isLiveDataset", "jsonPath": "cr:jsonPath",
    "key": "cr:key", "md5": "cr:md5", "parentField": "cr:parentField", "path": "cr:path", "recordSet": "cr:recordSet",
    "references": "cr:references", "regex": "cr:regex", "repeated": "cr:repeated", "replace": "cr:replace", "samplingRate": "cr:samplingRate",
    "sc": "https://schema.org/", "separator": "cr:separator", "source": "cr:source", "subField": "cr:subField",
    "transform": "cr:transform",
}
"""Croissant 1.0's JSON-LD context (the specification's)."""

_INDEX_FIELDS = (
    ("episode", "sc:Text", "the episode's name, <task>-u<user>-g<grasp>-m<mass>-s<seed>[-v<view>]"),
    ("file", "sc:Text", "the shard's path in the dataset, episodes/<episode>.h5"),
    ("split", "sc:Text", "the split of its person, grasp and view: cohort (the named ones) or train"),
    ("task", "sc:Text", "the task (lift, place, rotate, ...)"),
    ("user", "sc:Integer", "the person's index (0-4 named, >= 5 drawn; benchmark.world.people)"),
    ("grasp", "sc:Integer", "the grasp's index (0-3 named, >= 4 drawn; benchmark.world.grasp_families)"),
    ("view", "sc:Integer", "the camera view's index (0: the paper's set-up)"),
    ("mass", "sc:Integer", "the box's mass configuration (sim_assets/masses.yaml)"),
    ("seed", "sc:Integer", "the scenario's seed"),
    ("frames", "sc:Integer", "frames in the shard (0 for a failed episode)"),
    ("bytes", "sc:Integer", "the shard's size in bytes"),
    ("sha256", "sc:Text", "SHA-256 of the shard's bytes"),
    ("status", "sc:Text", "ok, or failed: the world's error (the shard then holds no frames)"),
    ("streams", "sc:Text", "the streams stored, comma-separated (depth, colour)"),
)

SHARD_ARRAYS = (
    # (path, dtype, shape, units, description)
    ("labels/t", "float64", "T", "s", "frame times"),
    ("labels/contact_active", "bool", "T,K", "", "finger k touches the box (K = 5, thumb first)"),
    ("labels/contact_sliding", "bool", "T,K", "", "that contact slides"),
    ("labels/contact_force_world", "float64", "T,K,3", "N", "finger k's 3D force on the box, world frame"),
    ("labels/contact_force_object", "float64", "T,K,3", "N", "the same in the box's frame"),
    ("labels/contact_point_world", "float64", "T,K,3", "m", "centre of pressure, world frame"),
    ("labels/contact_point_object", "float64", "T,K,3", "m", "centre of pressure, box frame"),
    ("labels/contact_normal_world", "float64", "T,K,3", "", "unit normal into the box, world frame"),
    ("labels/contact_normal_object", "float64", "T,K,3", "", "unit normal into the box, box frame"),
    ("labels/box_pos", "float64", "T,3", "m", "box centre of mass"),
    ("labels/box_quat", "float64", "T,4", "", "box orientation world_q_object (w, x, y, z)"),
    ("labels/box_rot", "float64", "T,3,3", "", "box rotation world_R_object"),
    ("labels/box_vel", "float64", "T,3", "m/s", "box linear velocity"),
    ("labels/box_omega", "float64", "T,3", "rad/s", "box angular velocity, world frame"),
    ("labels/box_acc", "float64", "T,3", "m/s^2", "box linear acceleration"),
    ("labels/box_alpha", "float64", "T,3", "rad/s^2", "box angular acceleration, world frame"),
    ("labels/hand_qpos", "float64", "T,n", "rad", "hand joint angles"),
    ("labels/keypoints_world", "float64", "T,21,3", "m", "21 hand keypoints (OpenPose order), world frame"),
    ("labels/fingertip_pos", "float64", "T,K,3", "m", "fingertip centres, world frame"),
    ("labels/env_force", "float64", "T,3", "N", "the table's force on the box"),
    ("labels/env_torque", "float64", "T,3", "N m", "the table's torque on the box about its centre of mass"),
    ("<stream>/frames", "uint16 | uint8 | bytes", "T,H,W | T,H,W,3 | T",
     "mm | sRGB", "depth in 1 mm steps (lossless), or colour: raw uint8 or one JPEG per frame"),
    ("<stream>/labels", "uint8", "T,H,W", "", "label image: 0 none, 1 table, 2 box, 9 palm, 10 + k finger k"),
    ("<stream>/K", "float64", "3,3", "px", "OpenCV intrinsics"),
    ("<stream>/T_world_cam", "float64", "4,4", "m", "camera pose: maps camera points to world points"),
    ("<stream>/t_s", "float64", "T", "s", "the stream's frame timestamps"),
    ("<stream>/keypoints_uv", "float64", "T,21,2", "px", "keypoints in the stream's pixels"),
    ("<stream>/keypoints_z", "float64", "T,21", "m", "their depth along the optical axis"),
    ("<stream>/keypoint_visibility", "uint8", "T,21", "",
     "0 visible, 1 occluded by the box, 2 by the hand, 3 off the image, 4 by the table"),
    ("<stream>/cam_R_m2c", "float64", "T,3,3", "", "box rotation model-to-camera (BOP)"),
    ("<stream>/cam_t_m2c", "float64", "T,3", "mm", "box centre in the camera (BOP)"),
    ("<stream>/contact_point_cam", "float64", "T,K,3", "m", "centre of pressure, the stream's camera frame"),
    ("<stream>/contact_normal_cam", "float64", "T,K,3", "", "unit normal into the box, camera frame"),
    ("<stream>/contact_force_cam", "float64", "T,K,3", "N", "finger k's force on the box, camera frame"),
    ("privileged@person", "JSON", "", "", "PRIVILEGED: the person's anatomy and grip style (no method is given it)"),
    ("privileged@grasp", "JSON", "", "", "PRIVILEGED: the grasp's family and pad spots (no method is given it)"),
)
"""Every array of a shard (``<stream>``: depth, colour), as ``croissant.json`` lists them."""

RAI = {
    "rai:dataCollection": (
        "No data was collected from people. Every episode is simulated: MuJoCo simulates a model hand grasping and "
        "moving a box on a table; a CPU rasteriser renders what an RGB-D camera (a DS325-like depth sensor and a "
        "colour camera) would record, with a simulated sensor's noise."),
    "rai:dataCollectionType": "Synthetic data (physics simulation and rendering)",
    "rai:dataCollectionRawData": (
        "The synthetic people are drawn from published distributions: hand length and breadth from Pheasant & "
        "Haslegrave (2006, Bodyspace, British adults 19-65), digit proportions after Manning et al. (1998) and "
        "Vergara et al. (2018), the grip's safety margin after Johansson & Westling (1984) and Cole (1991), the "
        "fingers' shares of the force after Radwin et al. (1992); ranges without a citation are stated choices "
        "(benchmark.world.people, benchmark.world.anatomy). The named users 0-4 are fictional."),
    "rai:dataAnnotationProtocol": (
        "Labels are the simulator's ground truth, not human annotations: contact forces, points and normals, box "
        "pose and its derivatives, hand joint angles and keypoints; per stream the keypoints' pixels and "
        "visibility, the box pose in BOP's convention and label images from the noise-free render."),
    "rai:annotationsPerItem": "Every frame carries every label; no item is annotated by a person.",
    "rai:dataPreprocessingProtocol": (
        "Depth is stored losslessly (the sensor's 1 mm steps as uint16). Colour is stored lossless (raw) or, when "
        "asked, as JPEG of quality 90 (lossy); the encoding is recorded in each shard and in dataset.json."),
    "rai:personalSensitiveInformation": (
        "None: no real person is recorded. The people's descriptors (sex, hand anatomy, grip style) are synthetic "
        "and stored under the shards' privileged group."),
    "rai:dataBiases": (
        "The drawn hands follow one population's anthropometry (British adults, Pheasant & Haslegrave 2006); "
        "grip styles span the named cohort's; one box, one table, three grasp families (thumb against two to four "
        "fingers across the box's width). Skin albedo is one RGB per person."),
    "rai:dataLimitations": (
        "Simulated world and sensors: MuJoCo's soft contact model, a rigid box of known size, no shadows, "
        "specular light or inter-reflection in the colour, a depth sensor model rather than a real one's "
        "artefacts, a model hand of capsules or a smooth skin rather than a scanned one. Networks trained on it "
        "meet a domain gap on real recordings. The privileged descriptors must not be network inputs when "
        "results are compared with vision-only methods."),
    "rai:dataUseCases": (
        "Training and validating networks that estimate hand-object contact forces, hand pose, object pose and "
        "segmentation from RGB-D video; fsv-bench's dev and test people are never in a generated frames dataset, "
        "so its benchmark scores stay unbiased."),
    "rai:dataSocialImpact": (
        "Force sensing from vision without tactile hardware (ergonomics, rehabilitation, robot learning from "
        "demonstration). Synthetic people avoid recording real participants; conclusions about real people "
        "need real data."),
    "rai:dataReleaseMaintenancePlan": (
        "Regenerated bit-identically from the fsv-bench release named in dataset.json's provenance with the "
        "command recorded there; nothing needs to be maintained beyond the code."),
}
"""The responsible-AI fields of ``croissant.json`` (Croissant RAI 1.0 vocabulary)."""


def _sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _name(spec) -> str:
    return "fsv-bench-frames-" + "-".join(spec.streams)


def croissant(out, spec, index) -> dict:
    """The Croissant 1.0 JSON-LD of a frames dataset folder (its ``index.parquet`` must be written)."""
    out = os.fspath(out)
    g = spec.grid
    lic = DATA_LICENSE
    fields = [{"@type": "cr:Field", "@id": f"index/{name}", "name": name, "description": desc, "dataType": dtype,
               "source": {"fileObject": {"@id": "index-file"}, "extract": {"column": name}}}
              for name, dtype, desc in _INDEX_FIELDS]
    arrays = [{"shard_arrays/path": p, "shard_arrays/dtype": d, "shard_arrays/shape": s, "shard_arrays/units": u,
               "shard_arrays/description": desc} for p, d, s, u, desc in SHARD_ARRAYS]
    return {
        "@context": CROISSANT_CONTEXT,
        "@type": "sc:Dataset",
        "conformsTo": "http://mlcommons.org/croissant/1.0",
        "name": _name(spec),
        "description": (f"Synthetic RGB-D frames of a hand grasping and moving a box, with each finger's 3D contact "
                        f"force and the hand's and box's state per frame: {len(index)} episodes "
                        f"({int(index['frames'].sum())} frames, streams {', '.join(spec.streams)}) generated by "
                        f"fsv-bench (tasks {', '.join(g.tasks)})."),
        "license": lic[1],
        "version": "1.0.0",
        "citeAs": "fsv-bench: a physics-simulator-backed benchmark for force sensing from vision (software, "
                  f"code licence {CODE_LICENSE})",
        "keywords": ["force from vision", "hand-object interaction", "RGB-D", "synthetic", "contact force"],
        "isLiveDataset": False,
        **RAI,
        "distribution": [
            {"@type": "cr:FileObject", "@id": "index-file", "name": "index.parquet", "contentUrl": "index.parquet",
             "encodingFormat": "application/x-parquet", "sha256": _sha256(os.path.join(out, "index.parquet")),
             "description": "one row per shard (episode): scenario, split, frames, bytes, SHA-256"},
            {"@type": "cr:FileSet", "@id": "shards", "name": "shards", "encodingFormat": "application/x-hdf5",
             "includes": "episodes/*.h5", "description": "one HDF5 shard per episode (benchmark.paper.dataset.shards)"},
        ],
        "recordSet": [
            {"@type": "cr:RecordSet", "@id": "index", "name": "index", "key": {"@id": "index/episode"},
             "description": "the shards of the dataset", "field": fields},
            {"@type": "cr:RecordSet", "@id": "shard_arrays", "name": "shard_arrays",
             "description": "every array of a shard: its HDF5 path, type, shape (T frames, K = 5 fingers, H x W "
                            "pixels), units and meaning",
             "field": [{"@type": "cr:Field", "@id": f"shard_arrays/{n}", "name": n, "dataType": "sc:Text"}
                       for n in ("path", "dtype", "shape", "units", "description")],
             "data": arrays},
        ],
    }


def _size_category(n: int) -> str:
    for bound, name in ((1_000, "n<1K"), (10_000, "1K<n<10K"), (100_000, "10K<n<100K"), (1_000_000, "100K<n<1M")):
        if n < bound:
            return name
    return "1M<n<10M"


def card(spec, index) -> str:
    """The dataset card (``README.md``): a YAML header for the Hugging Face hub, then the text."""
    g = spec.grid
    frames, mb = int(index["frames"].sum()), index["bytes"].sum() / 1e6
    colour = ("" if "colour" not in spec.streams else
              f" Colour is stored {'losslessly (raw uint8, gzip)' if spec.colour_encoding == 'raw' else 'as JPEG (quality 90, lossy)'}.")
    lines = [
        "---",
        f"license: {DATA_LICENSE[0]}",
        f"pretty_name: fsv-bench frames ({', '.join(spec.streams)})",
        "task_categories:", "- robotics", "- keypoint-detection", "- image-segmentation", "- depth-estimation",
        "tags:", "- synthetic", "- force-estimation", "- hand-object-interaction", "- rgb-d", "- simulation",
        "size_categories:", f"- {_size_category(frames)}",
        "configs:", "- config_name: index", "  data_files:", "  - split: train", "    path: index.parquet",
        "---", "",
        f"# fsv-bench frames: {', '.join(spec.streams)}", "",
        f"Synthetic RGB-D frames of a simulated hand grasping and moving a box, with every finger's 3D contact force "
        f"and the hand's and the box's state at every frame. {len(index)} episodes, {frames} frames, {mb:.1f} MB; "
        f"tasks {', '.join(g.tasks)}; made by `fsv-bench generate --frames` (the spec and the command's provenance "
        f"are in `dataset.json`).{colour}", "",
        "## Licence", "",
        f"The data: {DATA_LICENSE[2]} ({DATA_LICENSE[1]}). The code that generates it, fsv-bench: {CODE_LICENSE}.", "",
        "## Layout", "",
        "- `index.parquet`: one row per episode (episode, file, split, task, user, grasp, view, mass, seed, frames, "
        "bytes, sha256, status, streams).",
        "- `episodes/<episode>.h5`: one HDF5 shard per episode: `<stream>/frames` and `<stream>/labels` (label "
        "images), the stream's calibration and per-stream labels (keypoints' pixels and visibility, box pose in "
        "BOP's convention, contacts and forces in its camera frame); `labels/` the world- and object-frame labels "
        "(contact forces, points, normals, activity, box pose, velocity and acceleration, hand joint angles, "
        "keypoints); `privileged/` the person's and the grasp's descriptors.",
        "- `croissant.json`: Croissant 1.0 metadata with the responsible-AI fields; every array is listed there.", "",
        "Read it in windows of frames with PyTorch: `benchmark.paper.dataset.windows.FrameWindows` (fsv-bench's "
        "docs/data.md).", "",
        "## Privileged fields", "",
        "`privileged/` holds who squeezes (anatomy, grip style) and how (the grasp's family and pad spots). No "
        "method in fsv-bench is given them; a network that takes them as inputs is not a vision method.", "",
        "## Splits", "",
        "Only the named cohort and fsv-bench's training split (people, grasps and views 1000 and above) are ever in "
        "a frames dataset; the dev (100-499) and test (500-999) people are refused, so a network trained here can "
        "be scored on fsv-bench's suites.", "",
        "## Responsible AI", "",
        *[f"- **{k[4:]}**: {v}" for k, v in RAI.items()], "",
    ]
    return "\n".join(lines)


def write_card(out, spec, index) -> None:
    """Writes ``out/README.md`` and ``out/croissant.json`` (atomically)."""
    out = os.fspath(out)
    write_text(os.path.join(out, "README.md"), card(spec, index))
    write_text(os.path.join(out, "croissant.json"), json.dumps(croissant(out, spec, index), indent=1) + "\n")
