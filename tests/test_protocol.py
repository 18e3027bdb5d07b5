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
