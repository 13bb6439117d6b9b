"""The ROS 2 binding: dynevent behind a real rclpy action server and client.

Nothing else in dynevent imports this package (behaviour trees name a client's
type), and its modules import ``rclpy`` and the ``rmf_task_msgs`` message types
from the environment: a ROS install (apt or source, Jazzy or newer) or the
registry's ROS wheels.  ``pip install dynevent`` never installs a second rclpy.
``import dynevent.ros`` itself is quick and needs no ROS: each name below is
imported on first use, and says what is missing when ROS 2 is.  See docs/ros.md.

- :class:`~dynevent.ros.server.DynamicEventServer`: one robot's server on a
  node (several on one node make a fleet);
- :class:`~dynevent.ros.client.DynamicEventClient`: the client machine over an
  rclpy action client and the status and begin subscriptions, on a node you spin;
- :class:`~dynevent.ros.robot.RobotClient` and :class:`~dynevent.ros.robot.AsyncRobotClient`: the
  same with a node, a context and a spinning thread of their own (blocking, or asyncio), or on a
  :class:`~dynevent.ros.robot.RobotClients` hub that many robots' clients share;
- :mod:`dynevent.ros.convert`: the mirrors to and from the rosidl classes.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

#: Each public name, and the module of this package it is defined in: imported on first use, so
#: ``import dynevent.ros`` is quick and works without ROS 2 (a name that needs it says what is missing).
_HOMES = {
    "AsyncRobotClient": "robot",
    "ChildEvents": "server",
    "ChildExecution": "server",
    "DynamicEventClient": "client",
    "DynamicEventServer": "server",
    "GoalRun": "client",
    "RobotClient": "robot",
    "RobotClients": "robot",
    "StubbornHolds": "server",
}

__all__ = [
    "AsyncRobotClient", "ChildEvents", "ChildExecution", "DynamicEventClient", "DynamicEventServer",
    "GoalRun", "RobotClient", "RobotClients", "StubbornHolds",
]  # fmt: skip


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use (PEP 562), saying what is missing without ROS 2."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        module = importlib.import_module(f"{__name__}.{home}")
    except ImportError as exc:
        if (exc.name or "").split(".")[0] not in _ROS_PACKAGES:
            raise
        raise ImportError(
            f"dynevent.ros.{name} needs ROS 2 (rclpy) and the rmf_task_msgs interfaces: {exc}. "
            "Source a ROS 2 environment (Jazzy or newer) that provides both; "
            "dynevent/ros/setup/setup-ros-env.sh (in this package) builds one from the registry's wheels.",
            name=exc.name,
        ) from exc
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


#: The top-level packages of a ROS 2 environment whose absence the message above explains.
_ROS_PACKAGES = frozenset(
    {"rclpy", "rmf_task_msgs", "action_msgs", "builtin_interfaces", "unique_identifier_msgs", "service_msgs",
     "rosidl_runtime_py", "rpyutils"}
)  # fmt: skip

if TYPE_CHECKING:  # what type checkers and editors see, without importing anything at run time
    from dynevent.ros.client import DynamicEventClient, GoalRun
    from dynevent.ros.robot import AsyncRobotClient, RobotClient, RobotClients
    from dynevent.ros.server import ChildEvents, ChildExecution, DynamicEventServer, StubbornHolds
