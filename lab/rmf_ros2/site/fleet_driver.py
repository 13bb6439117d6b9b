#!/usr/bin/env python3
"""A headless fleet driver: one robot that the full_control fleet adapter drives over ROS 2.

It stands where a simulator's slotcar or a real robot's driver would be:

- it publishes rmf_fleet_msgs/FleetState on ``/fleet_states`` at 10 Hz (the robot's
  name, the ``task_id`` of the latest request, its mode, location and remaining path);
- it follows each PathRequest on ``robot_path_requests`` addressed to its fleet and robot,
  moving along the path at a realistic speed, so that a go_to_place takes time; a new
  request replaces the one being followed (that is how the adapter stops or re-routes
  a robot, e.g. when a go_to_place is cancelled);
- it honours ModeRequest on ``robot_mode_requests``: pause, resume, stop, and docking.

Usage: fleet_driver.py --nav-graph navgraph.yaml [--fleet tinyRobot] [--robot tinyRobot1]
       [--start dock] [--speed 0.5]
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import yaml

# How long the robot may wait at a waypoint it reached ahead of the waypoint's scheduled time.
# The adapter plans timed paths (and idle "responsive waits" as a path that stays put until a
# time); a robot that honours the times keeps to the traffic schedule, and the cap keeps a
# far-off time from freezing the robot.
MAX_EARLY_WAIT = 30.0
# How long a docking ModeRequest keeps the robot in MODE_DOCKING: this site has no docks, so
# the robot only has to report docking for a while and then be done.
DOCKING_SECONDS = 2.0
PERIOD = 0.1  # s between state reports, and the motion step


@dataclass
class Waypoint:
    """One point of a requested path: where, facing where, by when (s since the epoch)."""

    x: float
    y: float
    yaw: float
    t: float
    speed_limit: float | None = None  # the approach lane's limit, when the adapter sets one
    level: str = ""


@dataclass
class Robot:
    """The robot's motion and the state it reports, with no ROS in it."""

    name: str
    level: str
    x: float
    y: float
    yaw: float = 0.0
    speed: float = 0.5
    task_id: str = ""
    path: list[Waypoint] = field(default_factory=list)
    paused: bool = False
    docking_until: float | None = None
    arrived_at: float | None = None  # when the robot reached path[0] (to cap an early wait)

    def follow(self, task_id: str, path: list[Waypoint]) -> None:
        """Replace whatever the robot was doing by this path."""
        self.task_id = task_id
        self.path = list(path)
        self.paused = False
        self.docking_until = None
        self.arrived_at = None

    def stop(self, task_id: str) -> None:
        self.task_id = task_id
        self.path = []
        self.paused = False
        self.docking_until = None
        self.arrived_at = None

    def dock(self, task_id: str, now: float) -> None:
        self.stop(task_id)
        self.docking_until = now + DOCKING_SECONDS

    def moving(self) -> bool:
        return bool(self.path) and not self.paused

    def step(self, dt: float, now: float) -> None:
        """Advance the robot by dt seconds of travel along its path."""
        if self.docking_until is not None and now >= self.docking_until:
            self.docking_until = None
        if self.paused:
            return
        budget = dt  # seconds of motion left in this step
        while self.path and budget > 1e-9:
            target = self.path[0]
            speed = self.speed
            if target.speed_limit is not None and target.speed_limit > 0.0:
                speed = min(speed, target.speed_limit)
            dx, dy = target.x - self.x, target.y - self.y
            distance = math.hypot(dx, dy)
            if distance > 1e-6:
                travel = min(distance, speed * budget)
                self.x += dx / distance * travel
                self.y += dy / distance * travel
                self.yaw = math.atan2(dy, dx)
                budget -= travel / speed
                if travel < distance:
                    return  # still on the way; the rest next step
            # On the waypoint: face its heading, and leave it when its time has come.
            self.x, self.y, self.yaw = target.x, target.y, target.yaw
            if target.level:
                self.level = target.level
            if self.arrived_at is None:
                self.arrived_at = now
            if now < target.t and now - self.arrived_at < MAX_EARLY_WAIT:
                return
            self.path.pop(0)
            self.arrived_at = None


def load_places(nav_graph: Path) -> dict[str, tuple[str, float, float]]:
    """Named waypoints of the graph: name -> (level, x, y)."""
    graph = yaml.safe_load(nav_graph.read_text())
    places: dict[str, tuple[str, float, float]] = {}
    for level, content in graph["levels"].items():
        for vertex in content.get("vertices", []):
            options = vertex[2] if len(vertex) > 2 and vertex[2] else {}
            if options.get("name"):
                places[str(options["name"])] = (str(level), float(vertex[0]), float(vertex[1]))
    return places


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nav-graph", type=Path, required=True)
    parser.add_argument("--fleet", default="tinyRobot")
    parser.add_argument("--robot", default="tinyRobot1")
    parser.add_argument("--start", default="dock", help="the named waypoint the robot starts on")
    parser.add_argument("--speed", type=float, default=0.5, help="m/s along a path")
    args = parser.parse_args(argv)

    places = load_places(args.nav_graph)
    if args.start not in places:
        print(f"fleet_driver: no waypoint named {args.start!r} in {args.nav_graph}", file=sys.stderr)
        return 2
    level, x, y = places[args.start]
    robot = Robot(name=args.robot, level=level, x=x, y=y, speed=args.speed)
    return _run(args.fleet, robot)


def _run(fleet: str, robot: Robot) -> int:
    # ROS imports here, so that the motion model above can be used and tested without ROS.
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node
    from rclpy.time import Time
    from rmf_fleet_msgs.msg import FleetState, Location, ModeRequest, PathRequest, RobotMode, RobotState

    rclpy.init()
    node = Node(f"{fleet}_fleet_driver")
    log = node.get_logger()
    clock = node.get_clock()
    seq = 0

    def now() -> float:
        return float(clock.now().nanoseconds) * 1e-9

    def location(x: float, y: float, yaw: float, t: float, level: str) -> Location:
        msg = Location()
        msg.t = Time(nanoseconds=int(t * 1e9)).to_msg()
        msg.x, msg.y, msg.yaw = float(x), float(y), float(yaw)
        msg.level_name = level
        return msg

    def on_path(request: PathRequest) -> None:
        if request.fleet_name != fleet or request.robot_name != robot.name:
            return
        # The adapter sends a request again while our state does not show its task_id yet.
        if request.task_id == robot.task_id:
            return
        path = [
            Waypoint(
                x=p.x,
                y=p.y,
                yaw=p.yaw,
                t=Time.from_msg(p.t).nanoseconds * 1e-9,
                speed_limit=p.approach_speed_limit if p.obey_approach_speed_limit else None,
                level=p.level_name,
            )
            for p in request.path
        ]
        robot.follow(request.task_id, path)
        end = f"({path[-1].x:.2f}, {path[-1].y:.2f})" if path else "nowhere"
        log.info(f"path request {request.task_id}: {len(path)} waypoint(s) to {end}")

    def on_mode(request: ModeRequest) -> None:
        if request.fleet_name != fleet or request.robot_name != robot.name:
            return
        mode = request.mode.mode
        if mode == RobotMode.MODE_PAUSED:
            robot.task_id = request.task_id
            robot.paused = True
        elif mode == RobotMode.MODE_MOVING:
            robot.task_id = request.task_id
            robot.paused = False
        elif mode == RobotMode.MODE_DOCKING:
            robot.dock(request.task_id, now())
        elif mode in (RobotMode.MODE_IDLE, RobotMode.MODE_EMERGENCY):
            robot.stop(request.task_id)
        else:
            log.warn(f"mode request {mode} ignored (task {request.task_id})")
            return
        log.info(f"mode request {mode} (task {request.task_id})")

    def tick() -> None:
        nonlocal seq
        t = now()
        was_moving = robot.moving()
        robot.step(PERIOD, t)
        if was_moving and not robot.path:
            log.info(f"path {robot.task_id} done at ({robot.x:.2f}, {robot.y:.2f})")
        state = RobotState()
        state.name = robot.name
        state.model = fleet
        state.task_id = robot.task_id
        seq += 1
        state.seq = seq
        if robot.docking_until is not None:
            state.mode.mode = RobotMode.MODE_DOCKING
        elif robot.paused:
            state.mode.mode = RobotMode.MODE_PAUSED
        elif robot.path:
            state.mode.mode = RobotMode.MODE_MOVING
        else:
            state.mode.mode = RobotMode.MODE_IDLE
        state.battery_percent = 100.0  # the site does not drain batteries (drain_battery is off)
        state.location = location(robot.x, robot.y, robot.yaw, t, robot.level)
        state.path = [location(w.x, w.y, w.yaw, w.t, w.level or robot.level) for w in robot.path]
        fleet_state = FleetState()
        fleet_state.name = fleet
        fleet_state.robots = [state]
        publisher.publish(fleet_state)

    publisher = node.create_publisher(FleetState, "/fleet_states", 10)
    node.create_subscription(PathRequest, "robot_path_requests", on_path, 10)
    node.create_subscription(ModeRequest, "robot_mode_requests", on_mode, 10)
    node.create_timer(PERIOD, tick)
    log.info(f"robot {fleet}/{robot.name} on {robot.level} at ({robot.x:.2f}, {robot.y:.2f})")
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
