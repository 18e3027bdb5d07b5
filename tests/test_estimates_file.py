"""Estimates files a hostile submitter writes: refused in one line (exit 2) naming the file, the entry and
what is accepted, before any array is read; the readers never read more than the format allows."""

import json
import os
import pathlib
import subprocess
import sys
import zipfile
import zlib

import h5py
import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.exchange import load_estimate
from benchmark.exchange.estimates_file import FORMAT, force_bound_n
from benchmark.suites import SUITES
from fsv.errors import InputError
from fsv.learn.model import load as load_model

ROOT = pathlib.Path(__file__).resolve().parents[1]
T, NAMES = 5, ("thumb", "index")
META = {"format": FORMAT, "version": 1, "episode": "lift-u0-g0-m0-s21", "finger_names": list(NAMES),
        "method": "a method", "stages": {"tracker": "a tracker"}}


def valid_arrays() -> dict:
    """A physical estimates file's arrays: the box at rest 10 cm above the origin, finger 0 in contact."""
    active = np.zeros((T, 2), bool)
    active[1:, 0] = True
    normal = np.zeros((T, 2, 3))
    normal[:, 0] = [0.0, 1.0, 0.0]
    return {"box/pos": np.tile([0.0, 0.0, 0.1], (T, 1)), "box/rot": np.repeat(np.eye(3)[None], T, 0),
            "contacts/active": active, "contacts/sliding": np.zeros((T, 2), bool),
            "contacts/point": np.zeros((T, 2, 3)), "contacts/normal": normal,
            **{f"kinematics/{f}": np.zeros((T, 3)) for f in ("vel", "acc", "omega", "alpha")},
            "kinematics/valid": np.ones(T, bool),
            "nominal/force": np.zeros((T, 2, 3)), "nominal/env_wrench": np.zeros((T, 6)),
            "nominal/status": np.zeros(T, np.int8)}


def write(path, arrays, meta=META):
    np.savez(path, **arrays, **{"meta.json": np.frombuffer(json.dumps(meta).encode(), np.uint8)})
    return path


def refused(capsys, path, *needles):
    """``fsv-bench check`` exits 2 with one line naming the file and every needle, no traceback."""
    code = main(["check", str(path)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert str(path) in err and "Traceback" not in err and "pickle" not in err.lower(), err
    for needle in needles:
        assert needle in err, err
    return err


def with_(name, value):
    arrays = valid_arrays()
    arrays[name] = value
    return arrays


@pytest.mark.parametrize("arrays, needles", [
    (with_("box/pos", np.full((T, 3), "0.1")), ("box/pos holds strings", "expected float64 or float32")),
    (with_("box/pos", np.zeros((T, 3), complex)), ("box/pos holds complex numbers", "expected float64 or float32")),
    (with_("box/pos", np.zeros((T, 3), bool)), ("box/pos holds booleans (|b1)", "expected float64 or float32")),
    (with_("box/pos", np.zeros((T, 3), np.float16)), ("box/pos holds float16", "expected float64 or float32")),
    (with_("box/pos", np.zeros((T, 3), np.int64)), ("box/pos holds integers (<i8)",)),
    (with_("nominal/status", np.full(T, 300, np.int16)), ("nominal/status at frame 0 is 300", "accepted: 0, 1")),
    (with_("nominal/status", np.full(T, 99, np.int8)), ("nominal/status at frame 0 is 99",)),
    (with_("nominal/status", np.full(T, -1, np.int8)), ("nominal/status at frame 0 is -1",)),
    (with_("nominal/status", np.full(T, 0.5)), ("nominal/status holds float64", "an integer type")),
    (with_("contacts/active", np.full((T, 2), 0.5)), ("contacts/active holds float64", "expected bool")),
    (with_("box/pos", np.full((T, 3), 1e300)), ("box/pos at frame 0 has a coordinate beyond 5 m",)),
    (with_("box/pos", np.full((T, 3), 6.0)), ("box/pos at frame 0 has a coordinate beyond 5 m",)),
    (with_("contacts/point", np.full((T, 2, 3), 2.0)), ("contacts/point at frame 1 has a coordinate beyond 1 m",)),
    (with_("kinematics/acc", np.full((T, 3), 1e300)), ("kinematics/acc at frame 0 has a component above 1e+06",)),
    (with_("nominal/force", np.full((T, 2, 3), 1e7)), ("nominal/force at frame 0 has a component above 6475",)),
    (with_("forces/secret", np.zeros(3)), ("array 'forces/secret' is not in the estimates format",)),
    (with_("box/pos", np.zeros((T, 3, 1))), ("box/pos has shape (5, 3, 1); expected (T, 3) with T <= 28801",)),
])
def test_wrong_types_and_absurd_values_are_refused_naming_the_array(tmp_path, capsys, arrays, needles):
    refused(capsys, write(tmp_path / "e.npz", arrays), *needles)


def test_the_valid_file_is_accepted_and_the_bound_is_the_heaviest_box(tmp_path, capsys):
    assert main(["check", str(write(tmp_path / "e.npz", valid_arrays()))]) == 0
    assert force_bound_n() == pytest.approx(1000 * 0.66 * 9.81)
    arrays = valid_arrays()
    arrays["contacts/active"] = arrays["contacts/active"].astype(np.uint8)  # writers without a bool type
    arrays["box/pos"] = arrays["box/pos"].astype(np.float32)
    arrays["nominal/status"] = np.full(T, 7, np.int64)
    est = load_estimate(write(tmp_path / "f.npz", arrays), t=np.arange(T) / 30.0, finger_names=NAMES)
    assert est.contacts.active.dtype == bool and est.nominal.status.dtype == np.int8


@pytest.mark.parametrize("change, needles", [
    ({"version": True}, ("version True;", "reads version 1 (an integer)")),
    ({"version": 1.0}, ("version 1.0;",)),
    ({"stages": "x"}, ('"stages" must be an object',)),
    ({"stages": {"tracker": 3}}, ('"stages" \'tracker\' must be a string, got int',)),
    ({"finger_names": "thumb"}, ('"finger_names" must be a list',)),
    ({"finger_names": "line\nbreak"}, ("\"finger_names\" must be a list of 1 to 10 names, got 'line\\nbreak'",)),
    ({"method": "m" * 10_000_000}, ("'meta.json' holds 10000165 bytes, above the 1048576",)),  # above the 1 MiB bound of meta.json
    ({"method": "m" * 5000}, ('"method" has 5000 characters; at most 1000',)),
    ({"method": "line one\nline two"}, ('"method" holds a line break',)),
    ({"episode": ["x"]}, ('"episode" must be a string, got list',)),
    ({"suite": {"name": "tiny", "version": True}}, ('"suite" must be {"name": string, "version": integer}',)),
    ({"notes": "hello"}, ("key 'notes' is not in the format",)),
])
def test_malformed_meta_json_is_one_line_naming_the_key(tmp_path, capsys, change, needles):
    refused(capsys, write(tmp_path / "e.npz", valid_arrays(), {**META, **change}), *needles)


def test_score_refuses_a_malformed_meta_json_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    (tmp_path / "est").mkdir()
    write(tmp_path / "est" / "lift-u0-g0-m0-s21.npz", valid_arrays(), {**META, "stages": "x"})
    code = main(["score", "--suite", "tiny", "--estimates", str(tmp_path / "est"), "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "cache"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and '"stages" must be an object' in err and "Traceback" not in err
    assert not (tmp_path / "o").exists() and not (tmp_path / "cache").exists()


@pytest.mark.parametrize("content", [b'{"format": "fsv-bench-estimates"}', b"hello\n", bytes(range(256)) * 8])
def test_a_file_that_is_not_an_archive_never_mentions_pickles(tmp_path, capsys, content):
    path = tmp_path / "e.npz"
    path.write_bytes(content)
    refused(capsys, path, "not a zip archive of .npy arrays (.npz)")


def test_a_model_that_is_not_an_archive_never_mentions_pickles(tmp_path):
    path = tmp_path / "model.npz"
    path.write_text('{"format": "fsv-internal-forces"}')
    with pytest.raises(InputError) as e:
        load_model(path)
    assert "pickle" not in str(e.value).lower() and "not a .npz archive" in str(e.value)
    np.savez(path, header=np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(InputError) as e:
        load_model(path)
    assert "pickle" not in str(e.value).lower() and "holds Python objects" in str(e.value)


class _FlushedDeflate:
    """A raw deflate compressor that ends every piece it is given with a full flush, which resets
    it: a valid stream, in which every piece equal to ``block`` deflates to the same bytes, made
    once (deflating a GiB of zeros piece by piece takes 1.9 s of CPU; a full flush costs 16 bytes
    a 16 MiB piece)."""

    def __init__(self, block: bytes):
        self._deflate = zlib.compressobj(6, zlib.DEFLATED, -15)
        self._block = block
        self._block_out = self._piece(block)

    def _piece(self, data) -> bytes:
        return self._deflate.compress(data) + self._deflate.flush(zlib.Z_FULL_FLUSH)

    def compress(self, data) -> bytes:
        return self._block_out if data == self._block else self._piece(data)

    def flush(self) -> bytes:
        return self._deflate.flush()


def declared_zip(path, name: str, shape: tuple):
    """A valid estimates file plus an entry ``name`` whose .npy header declares ``shape`` float64,
    zeros deflated: about 1 MB on disk for a GiB declared."""
    write(path, valid_arrays())
    header = {"descr": "<f8", "fortran_order": False, "shape": shape}
    info = zipfile.ZipInfo(name + ".npy")
    info.compress_type = zipfile.ZIP_DEFLATED
    block = bytes(1 << 24)
    with pytest.MonkeyPatch.context() as mp:  # zipfile's deflate, for this entry: the same format
        mp.setattr(zipfile, "_get_compressor", lambda *_: _FlushedDeflate(block))
        with zipfile.ZipFile(path, "a") as z, z.open(info, "w", force_zip64=True) as out:
            np.lib.format.write_array_header_1_0(out, header)
            left = int(np.prod(shape)) * 8
            while left:
                out.write(block if left >= len(block) else block[:left])
                left -= min(left, len(block))
    return path


@pytest.fixture(scope="module")
def gib_file(tmp_path_factory):
    """1.1 MB on disk: a valid estimates file with an extra, unlisted array declaring 1 GiB."""
    return declared_zip(tmp_path_factory.mktemp("hostile") / "e.npz", "extra/x", (1 << 27,))


def test_an_unlisted_gib_array_is_refused_by_name(gib_file, capsys):
    assert gib_file.stat().st_size < 2_000_000
    refused(capsys, gib_file, "array 'extra/x' is not in the estimates format")


def test_a_listed_array_declaring_too_many_frames_is_refused_from_its_header(tmp_path, capsys):
    path = tmp_path / "e.npz"
    arrays = valid_arrays()
    del arrays["box/pos"]
    write(path, arrays)
    with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_DEFLATED) as z, \
            z.open(zipfile.ZipInfo("box/pos.npy"), "w", force_zip64=True) as out:
        np.lib.format.write_array_header_1_0(out, {"descr": "<f8", "fortran_order": False, "shape": (1 << 26, 3)})
        out.write(bytes(1 << 20))  # the data need not be there: nothing is read past the header
    refused(capsys, path, "box/pos has shape (67108864, 3); expected (T, 3) with T <= 28801 frames")


def test_an_entry_of_another_compression_or_expanding_beyond_deflate_is_refused(tmp_path, capsys):
    path = write(tmp_path / "e.npz", valid_arrays())
    with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_BZIP2) as z:
        z.writestr("hand/fingertips.npy", bytes(1 << 22))
    refused(capsys, path, "entry 'hand/fingertips.npy' uses compression method 12")
    path = write(tmp_path / "f.npz", valid_arrays())
    with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("hand/fingertips.npy", bytes(1 << 20))
    data = bytearray(path.read_bytes())  # the central directory says the entry expands 4 GiB
    info = zipfile.ZipFile(path).getinfo("hand/fingertips.npy")
    at = bytes(data).rfind(b"hand/fingertips.npy") - 46
    assert data[at:at + 4] == b"PK\x01\x02" and int.from_bytes(data[at + 24:at + 28], "little") == info.file_size
    data[at + 24:at + 28] = (0xFFFFFFF0).to_bytes(4, "little")
    path.write_bytes(bytes(data))
    refused(capsys, path, "entry 'hand/fingertips.npy' expands", "above 1100")


def h5_file(path, extra=None, arrays=None, meta=META):
    with h5py.File(path, "w") as f:
        for name, value in (valid_arrays() if arrays is None else arrays).items():
            f.create_dataset(name, data=value)
        f.create_dataset("meta.json", data=np.frombuffer(json.dumps(meta).encode(), np.uint8))
        if extra is not None:
            extra(f)
    return path


def test_hdf5_external_storage_links_and_virtual_datasets_are_refused(tmp_path, capsys):
    secret = tmp_path / "secret.bin"
    secret.write_bytes(np.arange(T * 3, dtype="<f8").tobytes())
    assert main(["check", str(h5_file(tmp_path / "ok.h5"))]) == 0
    arrays = valid_arrays()
    del arrays["box/pos"]

    def external(f):
        f.create_dataset("box/pos", shape=(T, 3), dtype="<f8", external=[(str(secret), 0, T * 3 * 8)])

    refused(capsys, h5_file(tmp_path / "a.h5", external, arrays), "dataset 'box/pos' has external raw storage")

    def external_link(f):
        f["box/pos"] = h5py.ExternalLink(str(tmp_path / "ok.h5"), "box/pos")

    refused(capsys, h5_file(tmp_path / "b.h5", external_link, arrays), "entry 'box/pos' is an external link")

    def soft_link(f):
        f["box/pos"] = h5py.SoftLink("/kinematics/vel")

    refused(capsys, h5_file(tmp_path / "c.h5", soft_link, arrays), "entry 'box/pos' is a soft link")

    def virtual(f):
        layout = h5py.VirtualLayout(shape=(T, 3), dtype="<f8")
        layout[:] = h5py.VirtualSource(str(tmp_path / "ok.h5"), "box/pos", shape=(T, 3))
        f.create_virtual_dataset("box/pos", layout)

    refused(capsys, h5_file(tmp_path / "d.h5", virtual, arrays), "dataset 'box/pos' is virtual")

    def unallocated(f):  # declares 1 GiB, stores nothing: every byte would come from the fill value
        f.create_dataset("hand/fingertips", shape=(1 << 25, 2, 2), dtype="<f8")

    refused(capsys, h5_file(tmp_path / "e.h5", unallocated), "dataset 'hand/fingertips' expands")


def test_hdf5_string_data_names_the_file_and_the_array(tmp_path, capsys):
    arrays = valid_arrays()
    arrays["box/pos"] = np.full((T, 3), "0.1", dtype=object)
    with h5py.File(tmp_path / "s.h5", "w") as f:
        for name, value in arrays.items():
            if value.dtype == object:
                f.create_dataset(name, data=value.astype(str).tolist(), dtype=h5py.string_dtype())
            else:
                f.create_dataset(name, data=value)
        f.create_dataset("meta.json", data=np.frombuffer(json.dumps(META).encode(), np.uint8))
    refused(capsys, tmp_path / "s.h5", "array 'box/pos' holds objects or variable-length strings")


PEAK = """
import resource, subprocess, sys
subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
"""


def peak_kib(*args, env=None) -> int:
    """Peak resident memory of a command in a fresh process, [KiB] (ru_maxrss of the children)."""
    run = subprocess.run([sys.executable, "-c", PEAK, sys.executable, *args], capture_output=True, text=True,
                         cwd=ROOT, env=env, timeout=300)
    return int(run.stdout.split()[-1])


def test_check_and_score_on_a_hostile_file_use_at_most_twice_a_valid_files_memory(gib_file, tmp_path):
    """Peaks measured (ru_maxrss, this machine): on 067b7e0, check read the unlisted 1 GiB array twice:
    valid file 195 MB, hostile 2294 MB. Now: check 195 MB valid, 195 MB hostile; score refuses the
    hostile file before any episode is made at 315 MB (its imports), against 374 MB scoring a valid
    file of the same suite from a warm cache (not run here: it needs the episode rendered and a
    method's estimates; a valid score reads at least what check reads, so 2x check's bounds it)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    valid = write(tmp_path / "valid.npz", valid_arrays())
    check = ["-m", "benchmark.commands.entry", "check"]
    base, hostile = peak_kib(*check, str(valid), env=env), peak_kib(*check, str(gib_file), env=env)
    assert hostile <= 2 * base, (base, hostile)
    score = ("import sys; from benchmark.suites import SUITES; from tiny_suite import TINY; "
             "SUITES['tiny'] = TINY; from benchmark.commands.cli import main; sys.exit(main(sys.argv[1:]))")
    env["PYTHONPATH"] = f"{ROOT}{os.pathsep}{ROOT / 'tests'}"
    (tmp_path / "est").mkdir()
    (tmp_path / "est" / "lift-u0-g0-m0-s21.npz").write_bytes(gib_file.read_bytes())
    args = ["score", "--suite", "tiny", "--estimates", str(tmp_path / "est"), "--cache", str(tmp_path / "cache"),
            "--quiet", "--no-baselines"]
    hostile_score = peak_kib("-c", score, *args, "--out", str(tmp_path / "o1"), env=env)
    assert not (tmp_path / "o1").exists() and not (tmp_path / "cache").exists()  # refused before any work
    # a valid file's score reads what check reads and renders the episode: at least check's memory
    assert hostile_score <= 2 * base, (base, hostile_score)
