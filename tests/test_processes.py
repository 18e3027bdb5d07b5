"""tests/processes.py: a process that has ended is not running, zombie or gone."""

import os
import sys
import time

import pytest
from processes import group_running, running, state

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")


def test_a_live_process_runs_and_an_ended_child_is_a_zombie_until_reaped():
    assert running(os.getpid()) and state(os.getpid()) == "R"
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    deadline = time.monotonic() + 10
    while state(pid) != "Z" and time.monotonic() < deadline:
        time.sleep(0.01)
    assert state(pid) == "Z" and not running(pid)  # ended, not yet reaped
    os.waitpid(pid, 0)
    assert state(pid) == "gone" and not running(pid)


def test_a_group_runs_while_a_member_runs_and_not_once_its_members_are_zombies():
    pid = os.fork()
    if pid == 0:
        os.setpgid(0, 0)
        time.sleep(0.3)
        os._exit(0)
    deadline = time.monotonic() + 10
    while not group_running(pid) and time.monotonic() < deadline:  # until the child has its own group
        time.sleep(0.01)
    assert group_running(pid) == [pid]
    while state(pid) != "Z" and time.monotonic() < deadline:
        time.sleep(0.01)
    os.killpg(pid, 0)  # the zombie still answers as a member of its group
    assert group_running(pid) == []
    os.waitpid(pid, 0)
    assert group_running(pid) == []
