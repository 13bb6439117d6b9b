"""A Dynamic Event server that is there and says nothing: its action server is on the graph, it never
publishes a status or a begin, and it never answers a goal request (``python silent_server.py ROBOT``).
The probe must end against it within the bound docs/probe.md gives (tests/ros/test_ros_probe.py)."""

from __future__ import annotations

import signal
import sys
from typing import Any

import rclpy
from rclpy.action import ActionServer
from rclpy.executors import SingleThreadedExecutor
from rclpy.task import Future
from rmf_task_msgs.action import DynamicEvent

from dynevent.wire.names import action_name


async def never_answers(goal: Any) -> Any:
    await Future()  # no one completes it: the goal request stays unanswered
    raise AssertionError("unreachable")


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("silent_server")
    server = ActionServer(
        node, DynamicEvent, action_name("tinyRobot", sys.argv[1]), lambda handle: None,
        goal_callback=never_answers,
    )  # fmt: skip
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    stopped: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, _: stopped.append(signum))
    signal.signal(signal.SIGTERM, lambda signum, _: stopped.append(signum))
    print("serving silently", flush=True)
    while not stopped:
        executor.spin_once(timeout_sec=0.2)
    server.destroy()
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()
