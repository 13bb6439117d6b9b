"""The ROS tests: real rclpy, real DDS, on loopback only, in a domain of their own.

They need ROS 2 and the ``rmf_task_msgs`` interfaces importable (source
``build/ros/env.sh``, made by ``tests/ros/setup-ros-env.sh``).  Without them
the ROS tests over DDS (test_ros_*.py) are not collected and the run's header says why (see
tests/conftest.py), except under ``CI=true``, where the run fails instead: CI
must run them.  Every test has a deadline (faulthandler ends a hung
process) and every wait in them a bound.
"""

from __future__ import annotations

import faulthandler
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import pytest
from ros_support import ROS, TEST_DEADLINE, WHY, Graph, keep_dds_local

if ROS:
    keep_dds_local()
    collect_ignore_glob: list[str] = []
else:
    collect_ignore_glob = ["test_ros_*.py"]


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if not ROS and os.environ.get("CI") == "true":
        raise pytest.UsageError(f"CI=true and the ROS tests cannot run: {WHY}")


_stacks: list[IO[str]] = []  # this process's stacks file, opened once (faulthandler keeps its descriptor)


def _stacks_file() -> IO[str]:
    """Where this process writes every thread's stack if a test passes its deadline: a file of the run's
    stacks folder (tests/conftest.py reports it when a pytest-xdist worker ends)."""
    if not _stacks:
        folder = Path(os.environ.get("DYNEVENT_TEST_STACKS") or ".")
        name = os.environ.get("PYTEST_XDIST_WORKER", "main")
        _stacks.append(open(folder / f"{name}.txt", "w", encoding="utf-8"))  # noqa: SIM115
    return _stacks[0]


@pytest.fixture(autouse=True)
def _deadline(request: pytest.FixtureRequest) -> Iterator[None]:
    # a test that builds an environment (the newcomer's path) is bounded by its steps' own bounds,
    # not by the deadline of a test that only talks to a server
    marker = request.node.get_closest_marker("deadline")
    seconds = marker.args[0] if marker else TEST_DEADLINE
    faulthandler.dump_traceback_later(seconds, exit=True, file=_stacks_file())
    yield
    faulthandler.cancel_dump_traceback_later()


@pytest.fixture
def graph() -> Iterator[Graph]:
    made = Graph()
    yield made
    made.close()
