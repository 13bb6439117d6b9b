"""A fleet adapter's Dynamic Event servers, wired with dynevent.ros (the example of docs/ros.md).

Run it in a ROS 2 environment that has rmf_task_msgs::

    python docs/examples/ros_adapter.py --robot tinyRobot1 --robot tinyRobot2 --seconds 60

Each robot begins a dynamic event at once.  A ``go_to_place`` child drives
for three reports, 0.2 s apart, and fails on a place named ``nowhere``; a
cancel stops it at the next report.  The node runs until SIGINT or SIGTERM,
or ``--seconds`` have passed.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
import time
from typing import Any

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

from dynevent.ros import ChildExecution, DynamicEventServer
from dynevent.server.machine import ServerConfig

REPORTS = 3
PERIOD = 0.2  # seconds between two reports of a child


def go_to_place(category: str, description: Any) -> list[str]:
    """The description a go_to_place child accepts: a place name."""
    return [] if isinstance(description, str) and description else ["expected a place name"]


class DrivingChildren:
    """Child events simulated on the node's timers: underway, underway, then finished."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.timers: dict[int, Any] = {}

    def start(self, execution: ChildExecution) -> None:
        reports = [0]

        def report() -> None:
            if execution.done:
                return self._stop_timer(execution)
            if execution.stopping is not None:  # told to cancel or kill: stop at this report
                execution.finished()
            elif execution.parsed == "nowhere":
                execution.error("no such place")
                execution.finished("failed")
            elif reports[0] < REPORTS:
                reports[0] += 1
                execution.underway(f"driving to {execution.parsed}, {reports[0]} of {REPORTS}")
            else:
                execution.finished()
            if execution.done:
                self._stop_timer(execution)

        self.timers[execution.id] = self.node.create_timer(PERIOD, report)

    def _stop_timer(self, execution: ChildExecution) -> None:
        timer = self.timers.pop(execution.id, None)
        if timer is not None:
            self.node.destroy_timer(timer)

    def cancel(self, execution: ChildExecution) -> None:
        """Stops at the next report."""

    def kill(self, execution: ChildExecution) -> None:
        """Stops at the next report."""

    def interrupt(self, execution: ChildExecution) -> None:
        """This simulation does not pause."""

    def resume(self, execution: ChildExecution) -> None:
        """This simulation does not pause."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fleet", default="tinyRobot")
    parser.add_argument("--robot", action="append", dest="robots")
    parser.add_argument("--seconds", type=float, default=600.0, help="stop after this long")
    args = parser.parse_args(argv)

    rclpy.init()
    node = rclpy.create_node("dynevent_example_adapter")
    config = ServerConfig(categories={"go_to_place": go_to_place})
    begins = DynamicEventServer.fleet_begin_publisher(node)  # one fleet-wide begin topic for the node
    servers = [
        DynamicEventServer(node, args.fleet, robot, config, DrivingChildren(node), begin_publisher=begins)
        for robot in args.robots or ["tinyRobot1"]
    ]
    for event_id, server in enumerate(servers, start=1):
        server.begin('{"category": "patrol", "detail": "ward rounds"}', event_id)

    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    print("ready", flush=True)
    _spin_until(executor, stop, time.monotonic() + args.seconds)
    for server in servers:
        server.shutdown()  # every open goal is answered "shutting down"
    _spin_until(executor, threading.Event(), time.monotonic() + 0.2)  # the answers go out
    executor.shutdown(timeout_sec=5)
    node.destroy_node()
    rclpy.shutdown()
    return 0


def _spin_until(executor: Any, stop: threading.Event, deadline: float) -> None:
    """Spin on this thread until ``stop`` is set or ``deadline`` (``time.monotonic()``) passes.

    Spinning on the main thread, and not a daemon one, leaves no thread inside
    rclpy when the process tears ROS down.
    """
    with contextlib.suppress(ExternalShutdownException):
        while not stop.is_set() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)


if __name__ == "__main__":
    sys.exit(main())
