"""The blind and calibrated protocols (benchmark.method.protocol): what the method is told of the person."""

import pytest

from benchmark.method import MethodSpec
from benchmark.method.grip_file import calibrated_users, read_calibration
from benchmark.method.protocol import (
    DEFAULT_PROTOCOL,
    PROTOCOLS,
    ProtocolError,
    check_protocol,
    person_grip,
)


def test_blind_is_the_default_and_tells_nothing():
    assert DEFAULT_PROTOCOL == "blind" and PROTOCOLS == ("blind", "calibrated")
    assert MethodSpec().protocol == "blind"
    for user in (0, 3, 123, 5000):
        assert person_grip(user, "blind") is None


def test_calibrated_gives_the_persons_own_line_from_the_shipped_calibration():
    shipped = read_calibration()
    for user in (0, 4):
        grip = person_grip(user, "calibrated")
        assert grip == shipped[user] and grip.samples > 0
    assert person_grip(0, "calibrated") != person_grip(4, "calibrated")


def test_calibrated_without_a_recording_is_refused_naming_the_person_and_the_calibrated_ones():
    with pytest.raises(ProtocolError, match=r"user 5000 has no calibration recording; accepted: --protocol blind") as e:
        person_grip(5000, "calibrated")
    assert calibrated_users() in str(e.value) and calibrated_users().startswith("0-4")


def test_a_bad_protocol_is_refused_naming_the_accepted_ones():
    with pytest.raises(ValueError, match=r"--protocol 'sighted': accepted: blind, calibrated"):
        check_protocol("sighted")
    with pytest.raises(ValueError, match="accepted: blind, calibrated"):
        MethodSpec(protocol="sighted")


def test_camera_input_follows_the_protocol(rendered_lift_episode):
    from benchmark.method import camera_input

    assert camera_input(rendered_lift_episode).grip is None
    assert camera_input(rendered_lift_episode, protocol="calibrated").grip == read_calibration()[0]


def test_the_main_command_records_the_protocols_model_and_only_the_line_it_told(tmp_path):
    import json

    from benchmark.commands.cli import main
    from benchmark.method.grip_file import read_calibration

    learned = {}
    for protocol in PROTOCOLS:
        out = tmp_path / protocol
        assert main(["--task", "lift", "--duration", "2", "--quiet", "--no-pictures", "--protocol", protocol,
                     "--out", str(out)]) in (0, 1)
        learned[protocol] = json.loads((out / "summary.json").read_text())["learning"]
    blind, calibrated = learned["blind"], learned["calibrated"]
    assert blind["internal_model"] == "fsv/data/internal_forces_blind.npz" and not blind["model"]["grip_inputs"]
    assert "grip_calibration" not in blind  # nothing was told of the person
    line = read_calibration()[0]
    assert calibrated["internal_model"] == "fsv/data/internal_forces.npz" and calibrated["model"]["grip_inputs"]
    assert calibrated["grip_calibration"] == {"baseline_n": line.baseline_n, "gain": line.gain}
