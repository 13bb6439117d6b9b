"""The ROS 2 binding: dynevent behind a real rclpy action server and client.

Nothing else in dynevent imports this package, and this package imports
``rclpy`` and the ``rmf_task_msgs`` message types from the environment: a ROS
install (apt or source, Jazzy or newer) or the registry's ROS wheels.
``pip install dynevent`` never installs a second rclpy.  See docs/ros.md.

- :class:`~dynevent.ros.server.DynamicEventServer`: one robot's server on a
  node (several on one node make a fleet);
- :class:`~dynevent.ros.client.DynamicEventClient`: the client machine over an
  rclpy action client and the status and begin subscriptions, on a node you spin;
- :class:`~dynevent.ros.robot.RobotClient` and :class:`~dynevent.ros.robot.AsyncRobotClient`: the
  same with a node, a context and a spinning thread of their own (blocking, or asyncio);
- :mod:`dynevent.ros.convert`: the mirrors to and from the rosidl classes.
"""

from __future__ import annotations

try:
    import rclpy  # noqa: F401
    import rmf_task_msgs.action  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the environment
    raise ImportError(
        f"dynevent.ros needs ROS 2 (rclpy) and the rmf_task_msgs interfaces: {exc}. "
        "Source a ROS 2 environment (Jazzy or newer) that provides both; "
        "dynevent/ros/setup/setup-ros-env.sh (in this package) builds one from the registry's wheels.",
        name=exc.name,
    ) from exc

from dynevent.ros.client import DynamicEventClient, GoalRun
from dynevent.ros.robot import AsyncRobotClient, RobotClient
from dynevent.ros.server import ChildEvents, ChildExecution, DynamicEventServer, StubbornHolds

__all__ = [
    "AsyncRobotClient",
    "ChildEvents",
    "ChildExecution",
    "DynamicEventClient",
    "DynamicEventServer",
    "GoalRun",
    "RobotClient",
    "StubbornHolds",
]
