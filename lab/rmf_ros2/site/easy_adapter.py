#!/usr/bin/env python3
"""The site's robot added through EasyFullControl, as most deployments add theirs (rmf_demos' fleet
adapters do): Open-RMF's fleet adapter made by ``rmf_adapter`` (rmf_fleet_adapter_python) in this
process, with the robot tinyRobot1 simulated beside it.

The robot is fleet_driver.py's motion model (0.5 m/s along straight lanes) driven by EasyFullControl's
callbacks: ``navigate`` sends it to a destination and the command finishes when it is there;
``stop`` stops it; ``action_executor`` runs a performed action for 2 s.  Its state goes to the
adapter at 10 Hz (``EasyRobotUpdateHandle.update``).  run_site.py starts it with ``--site easy``.

Usage: easy_adapter.py --config easy_config.yaml --nav-graph navgraph.yaml [--robot tinyRobot1]
       [--start dock]
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from pathlib import Path
from typing import Any

from fleet_driver import Robot, Waypoint, load_places

PERIOD = 0.1  # s between state updates, and the motion step
ACTION_SECONDS = 2.0  # how long a performed action takes


class SimulatedRobot:
    """The robot, and the one command EasyFullControl has it carry out at a time."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.execution: Any = None
        self.action_ends: float | None = None
        self.lock = threading.Lock()

    def navigate(self, destination: Any, execution: Any) -> None:
        x, y, yaw = (float(value) for value in destination.position)
        with self.lock:
            self.execution, self.action_ends = execution, None
            target = Waypoint(x=x, y=y, yaw=yaw, t=0.0, level=destination.map or self.robot.level)
            self.robot.follow("", [target])

    def stop(self, activity: Any) -> None:
        with self.lock:
            if self.execution is not None and self.execution.identifier.is_same(activity):
                self.execution, self.action_ends = None, None
                self.robot.stop("")

    def act(self, category: str, description: Any, execution: Any) -> None:
        with self.lock:
            self.execution, self.action_ends = execution, time.monotonic() + ACTION_SECONDS
            self.robot.stop("")

    def step(self, dt: float) -> tuple[Any, Any]:
        """Move ``dt`` seconds; finish the command once it is done; the robot's state and the
        activity of the command it carries out (None when it has none)."""
        from rmf_adapter import easy_full_control as easy

        finished = None
        with self.lock:
            robot = self.robot
            robot.step(dt, time.time())
            if self.execution is not None:
                ends = self.action_ends
                if (not robot.moving()) if ends is None else time.monotonic() >= ends:
                    finished, self.execution, self.action_ends = self.execution, None, None
            state = easy.RobotState(robot.level, [robot.x, robot.y, robot.yaw], 1.0)
            activity = None if self.execution is None else self.execution.identifier
        if finished is not None:
            finished.finished()  # outside the lock: the adapter may call back at once
        return state, activity


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, required=True)
    parser.add_argument("--nav-graph", type=Path, required=True)
    parser.add_argument("--robot", default="tinyRobot1")
    parser.add_argument("--start", default="dock")
    args = parser.parse_args(argv)
    places = load_places(args.nav_graph)
    if args.start not in places:
        print(f"easy_adapter: no waypoint named {args.start!r} in {args.nav_graph}", file=sys.stderr)
        return 2

    import rclpy
    import rmf_adapter
    from rmf_adapter import Adapter
    from rmf_adapter import easy_full_control as easy

    rclpy.init()
    rmf_adapter.init_rclcpp()
    config = easy.FleetConfiguration.from_config_files(str(args.config), str(args.nav_graph))
    if config is None:
        print(f"easy_adapter: {args.config} is not a fleet configuration", file=sys.stderr)
        return 2
    adapter = Adapter.make(f"{config.fleet_name}_fleet_adapter")
    if adapter is None:
        print("easy_adapter: no adapter (is the traffic schedule running?)", file=sys.stderr)
        return 1
    adapter.start()
    fleet = adapter.add_easy_fleet(config)
    level, x, y = places[args.start]
    robot = SimulatedRobot(Robot(name=args.robot, level=level, x=x, y=y, speed=0.5))
    callbacks = easy.RobotCallbacks(robot.navigate, robot.stop, robot.act)
    state, _ = robot.step(0.0)
    handle = fleet.add_robot(args.robot, state, config.get_known_robot_configuration(args.robot), callbacks)
    print(f"easy_adapter: {config.fleet_name}/{args.robot} added at {args.start}", flush=True)
    last = time.monotonic()
    try:
        while rclpy.ok():
            time.sleep(PERIOD)
            now = time.monotonic()
            state, activity = robot.step(now - last)
            last = now
            handle.update(state, activity)
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
