"""What the method knows of the person: the ``blind`` and ``calibrated`` protocols.

- ``blind`` (the paper's protocol, the default): nothing is known about the person; the method
  gets no grip calibration (``CameraInput.grip`` is None; a model trained with grip inputs then
  assumes its training people's mean grip).
- ``calibrated``: the person was recorded once beforehand with force sensors (the benchmark's
  calibration recording, never scored: ``benchmark.paper.calibration``), and the method gets that
  person's grip line (:func:`benchmark.method.grip_file.user_grip`).

The two are reported side by side: a calibrated number never stands alone.
"""

from __future__ import annotations

from benchmark.errors import BenchmarkError
from benchmark.method.grip_file import calibrated_users, user_grip

PROTOCOLS = ("blind", "calibrated")
"""The protocols a method may be run under."""
DEFAULT_PROTOCOL = "blind"
"""The paper's: nothing is known about the person."""


class ProtocolError(BenchmarkError, ValueError):
    """A calibrated run of a person without a calibration recording (bad input: exit status 2)."""


def check_protocol(name: str) -> str:
    """``name`` if it is one of :data:`PROTOCOLS`; ValueError naming the accepted ones otherwise."""
    if name not in PROTOCOLS:
        raise ValueError(f"--protocol {name!r}: accepted: {', '.join(PROTOCOLS)}")
    return name


def person_grip(user: int, protocol: str):
    """The grip calibration the method gets for ``user`` under ``protocol``.

    Returns:
        None under ``blind``; the person's :class:`fsv.grip.GripCalibration` under ``calibrated``.

    Raises:
        ProtocolError: Under ``calibrated``, if the person has no calibration recording.
    """

    check_protocol(protocol)
    if protocol == "blind":
        return None
    grip = user_grip(user)
    if grip is None:
        raise ProtocolError(f"--protocol calibrated: user {user} has no calibration recording; accepted: "
                            f"--protocol blind, or a calibrated person ({calibrated_users()})")
    return grip


def check_people(users, protocol: str) -> None:
    """Raises before any work if ``protocol`` is unknown, or ``calibrated`` and one of ``users`` has
    no calibration recording (:func:`person_grip`'s errors)."""
    check_protocol(protocol)
    for user in dict.fromkeys(int(u) for u in users):
        person_grip(user, protocol)
