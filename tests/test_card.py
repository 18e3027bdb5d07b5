import json
import logging

import pytest
import yaml
from frames_data import make_tiny

from benchmark.paper.dataset.card import RAI, SHARD_ARRAYS
from benchmark.paper.dataset.frames import read_index

pytestmark = pytest.mark.xdist_group("frames-data")  # one worker renders frames_data's episodes once


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("frames")
    make_tiny(out, streams=("depth",), seeds=(0,))
    return out


def test_the_card_has_a_hugging_face_header_naming_the_licences(tiny):
    text = (tiny / "README.md").read_text()
    head = yaml.safe_load(text.split("---\n")[1])
    assert head["license"] == "cc-by-4.0" and head["size_categories"] == ["n<1K"]
    assert "robotics" in head["task_categories"]
    assert head["configs"] == [{"config_name": "index", "data_files": [{"split": "train", "path": "index.parquet"}]}]
    assert "CC BY 4.0" in text and "fsv-bench: MIT" in text and "1 episodes, 31 frames" in text


def test_croissant_validates_with_mlcroissant_and_reads_the_index(tiny, caplog):
    mlc = pytest.importorskip("mlcroissant")
    doc = json.loads((tiny / "croissant.json").read_text())
    assert doc["conformsTo"] == "http://mlcommons.org/croissant/1.0" and doc["license"].endswith("/by/4.0/")
    assert all(doc[k] for k in RAI) and "Pheasant" in doc["rai:dataCollectionRawData"]
    with caplog.at_level(logging.WARNING):
        ds = mlc.Dataset(jsonld=str(tiny / "croissant.json"))
    issues = ds.metadata.ctx.issues
    assert not issues.errors
    assert [str(w) for w in issues.warnings] == [] or all("datePublished" in str(w) for w in issues.warnings)
    index = read_index(tiny)
    records = list(ds.records(record_set="index"))
    assert [r["index/episode"].decode() for r in records] == list(index["episode"])
    assert [r["index/sha256"].decode() for r in records] == list(index["sha256"])
    assert [r["index/frames"] for r in records] == [31]
    arrays = list(ds.records(record_set="shard_arrays"))
    assert len(arrays) == len(SHARD_ARRAYS) and arrays[3]["shard_arrays/path"] in ("labels/contact_force_world",
                                                                                    b"labels/contact_force_world")
