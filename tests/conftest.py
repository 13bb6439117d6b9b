"""Shared test configuration: hypothesis profiles.

``ci`` (the default) keeps ``bash .ci/run`` well under ten minutes on two
cores; ``deep`` runs many more and longer examples.  Choose with the
``DYNEVENT_HYPOTHESIS_PROFILE`` environment variable.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=100,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.register_profile(
    "deep",
    max_examples=5_000,
    deadline=None,
    stateful_step_count=200,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    print_blob=True,
)
settings.register_profile("dev", max_examples=20, deadline=None)
settings.load_profile(os.environ.get("DYNEVENT_HYPOTHESIS_PROFILE", "ci"))


def pytest_report_header() -> str:
    """Whether the ROS 2 tests run here, and if not, why (they are then not collected)."""
    folder = str(Path(__file__).resolve().parent / "ros")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    from ros_support import ROS, WHY

    if not ROS:
        return (
            f"ros: the ROS 2 tests over DDS (tests/ros/test_ros_*.py) are not collected: {WHY}; "
            "tests/ros's others run (the newcomer's path sets ROS 2 up itself)"
        )
    import rclpy

    return f"ros: the ROS 2 tests run over DDS on loopback (rclpy from {Path(rclpy.__file__).parent})"


#: The environment variable naming the folder where a test process ended at its deadline leaves every
#: thread's stack (tests/ros/conftest.py): faulthandler cannot write them to standard error, which
#: pytest captures, and which is lost with a worker that ends.
STACKS = "DYNEVENT_TEST_STACKS"


def pytest_configure(config: pytest.Config) -> None:
    """The run's stacks folder, chosen once: pytest-xdist's workers inherit it."""
    if not os.environ.get(STACKS):
        os.environ[STACKS] = tempfile.mkdtemp(prefix="dynevent-stacks-")


@pytest.hookimpl(optionalhook=True)
def pytest_handlecrashitem(crashitem: str, report: pytest.TestReport, sched: Any) -> None:
    """A pytest-xdist worker ended under a test: its report says where every thread was, if the
    deadline ended it (rather than only that the worker went down)."""
    worker = getattr(getattr(getattr(report, "node", None), "gateway", None), "id", "")
    stacks = Path(os.environ.get(STACKS, "")) / f"{worker}.txt"
    try:
        text = stacks.read_text("utf-8", errors="replace").strip()
    except OSError:
        return
    if text:
        report.longrepr = f"{report.longrepr}\n\nthe worker's stacks when it ended ({stacks}):\n{text}"
