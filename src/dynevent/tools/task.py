"""``dynevent task``: its flags checked without ROS 2, then a running ``dynevent serve`` told what
happens to a robot's task (:mod:`dynevent.tools.live.task`)."""

from __future__ import annotations

import argparse
from typing import Any

from dynevent.errors import TaskError
from dynevent.tools.live import run_over_ros, say
from dynevent.wire import _json

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent task``: 0 once the serve took it, 1 when it did not, 2 for bad usage or no serve
    of the robot."""

    def check() -> str:
        if not 0 < args.timeout < 1e6:
            raise TaskError(f"--timeout: expected positive seconds (got {args.timeout})")
        if args.description is not None and args.what != "begin":
            raise TaskError(f"--description: only a begin takes one (got {args.what})")
        if args.description is None:
            return ""
        try:
            _json.parse(args.description)
        except _json.JsonProblem as exc:
            raise TaskError(f"--description: not JSON dynevent reads: {exc}") from None
        return str(args.description).strip()

    def tell(live: Any, description: str) -> int:
        options = live.TaskOptions(
            fleet=args.fleet, robot=args.robot, what=args.what, description=description,
            timeout=args.timeout, ros_args=tuple(args.ros_args),
        )  # fmt: skip
        return int(live.run(options, say))

    return run_over_ros("task", check, tell)
