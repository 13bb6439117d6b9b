#!/usr/bin/env python3
"""Runs the headless Open-RMF site with one command, until SIGINT/SIGTERM or --seconds.

Starts, each as a child process with its own log file under --logs:

1. ``schedule``     rmf_traffic_schedule (rmf_traffic_ros2), the traffic schedule;
2. ``adapter``      full_control (rmf_fleet_adapter), Open-RMF's fleet adapter, with fleet tinyRobot;
3. ``fleet_driver`` fleet_driver.py, the robot tinyRobot1 that the adapter drives;
4. ``dispatcher``   dispatcher.py, which keeps a Dynamic Event task on the robot.

With ``--site easy`` the adapter is easy_adapter.py instead: the fleet made through EasyFullControl
(rmf_fleet_adapter_python), with the robot simulated in its process (no fleet_driver).

It waits for each to come up (bounded), then for the robot's Dynamic Event action server and
a Dynamic Event begin, and prints one line on stdout::

    READY fleet=tinyRobot robot=tinyRobot1 places=dock,hall,...

A child that does not come up in time, or dies, is named in one line on stderr; then every
child is stopped and the exit status is 1.  On SIGINT/SIGTERM or at --seconds it stops the
children (SIGINT, then SIGTERM, then SIGKILL, each bounded) and exits 0.

Needs an environment where Open-RMF's fleet adapter and its messages are sourced (lab/rmf_ros2/README.md)
and a ROS_DOMAIN_ID of the caller's.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

HERE = Path(__file__).resolve().parent
FLEET = "tinyRobot"
ROBOT = "tinyRobot1"
START = "dock"
# The adapter's model of the robot: what it plans with must match how fleet_driver.py moves
# (0.5 m/s), so that planned arrival times hold and a go_to_place takes the time it should.
ADAPTER_PARAMETERS = {
    "fleet_name": FLEET,
    "linear_velocity": 0.5,
    "angular_velocity": 0.6,
    "linear_acceleration": 0.5,
    "angular_acceleration": 1.5,
    "footprint_radius": 0.3,
    "vicinity_radius": 0.5,
    "reversible": True,
    "drain_battery": False,  # no battery model: tasks are never refused for charge
    "finishing_request": "nothing",  # stay put between tasks (no park/charge task of its own)
}
STOP_STEPS = ((signal.SIGINT, 5.0), (signal.SIGTERM, 3.0), (signal.SIGKILL, 2.0))


def say(text: str) -> None:
    print(f"site: {text}", file=sys.stderr, flush=True)


@dataclass
class Child:
    name: str
    argv: list[str]
    log_path: Path
    process: subprocess.Popen[bytes] | None = None
    log: IO[bytes] | None = None

    def start(self, env: dict[str, str]) -> None:
        # Held open for the child's lifetime, closed in stop().
        self.log = open(self.log_path, "ab")  # noqa: SIM115
        # Its own session: a Ctrl-C on the terminal reaches run_site only, which then stops the
        # children in order (the dispatcher and driver before the adapter and the schedule).
        self.process = subprocess.Popen(
            self.argv,
            stdin=subprocess.DEVNULL,
            stdout=self.log,
            stderr=subprocess.STDOUT,
            env=env,
            cwd=self.log_path.parent,  # whatever a child writes in its cwd lands with the logs
            start_new_session=True,
        )

    def exited(self) -> int | None:
        return None if self.process is None else self.process.poll()

    def stop(self) -> None:
        process = self.process
        if process is not None and process.poll() is None:
            for sig, bound in STOP_STEPS:
                try:
                    os.killpg(process.pid, sig)  # the child's own group: it and what it started
                except ProcessLookupError:
                    break
                try:
                    process.wait(timeout=bound)
                    break
                except subprocess.TimeoutExpired:
                    continue
        if self.log is not None:
            self.log.close()
            self.log = None


def place_names(nav_graph: Path) -> list[str]:
    import yaml

    graph = yaml.safe_load(nav_graph.read_text())
    names = []
    for level in graph["levels"].values():
        for vertex in level.get("vertices", []):
            options = vertex[2] if len(vertex) > 2 and vertex[2] else {}
            if options.get("name"):
                names.append(str(options["name"]))
    return names


def executable(package: str, name: str) -> str:
    from ament_index_python.packages import PackageNotFoundError, get_package_prefix

    try:
        path = Path(get_package_prefix(package)) / "lib" / package / name
    except PackageNotFoundError:
        raise SystemExit(f"site: package {package} not found: source the lab's env.sh first") from None
    if not os.access(path, os.X_OK):
        raise SystemExit(f"site: {path} is not an executable: is the lab's build finished?")
    return str(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=Path, required=True, help="directory for the children's logs")
    parser.add_argument("--seconds", type=float, help="stop by itself after this long (after READY)")
    parser.add_argument("--nav-graph", type=Path, default=HERE / "navgraph.yaml")
    parser.add_argument("--up-timeout", type=float, default=60.0, help="bound, in s, for each step")
    parser.add_argument(
        "--site",
        choices=("full_control", "easy"),
        default="full_control",
        help="how the robot is added: full_control's parameters (the default) or EasyFullControl",
    )
    args = parser.parse_args(argv)

    if not os.environ.get("ROS_DOMAIN_ID"):
        say("set ROS_DOMAIN_ID (the site does not pick one)")
        return 2
    # DDS stays on this machine, whatever the caller's environment says.
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_STATIC_PEERS", None)
    nav_graph = args.nav_graph.resolve()
    places = place_names(nav_graph)
    logs = args.logs.resolve()
    logs.mkdir(parents=True, exist_ok=True)
    # The schedule keeps its participant registry in a file and loads it again at start: a
    # fresh one per run keeps runs independent (and out of the source tree).
    registry = logs / "schedule_registry.yaml"
    registry.unlink(missing_ok=True)

    # Unbuffered output, so the logs show what happened up to the moment something went wrong.
    env = dict(os.environ, PYTHONUNBUFFERED="1", RCUTILS_LOGGING_BUFFERED_STREAM="0")
    line_buffered = ["stdbuf", "-oL", "-eL"] if shutil.which("stdbuf") else []
    adapter_args = ["--ros-args", "-p", f"nav_graph_file:={nav_graph}"]
    for key, value in ADAPTER_PARAMETERS.items():
        text = str(value).lower() if isinstance(value, bool) else str(value)
        adapter_args += ["-p", f"{key}:={text}"]
    python = sys.executable
    children = [
        Child(
            "schedule",
            [
                *line_buffered,
                executable("rmf_traffic_ros2", "rmf_traffic_schedule"),
                *["--ros-args", "-p", f"log_file_location:={registry}"],
            ],
            logs / "schedule.log",
        ),
        Child(
            "adapter",
            [*line_buffered, executable("rmf_fleet_adapter", "full_control"), *adapter_args],
            logs / "adapter.log",
        ),
        Child(
            "fleet_driver",
            [
                python,
                str(HERE / "fleet_driver.py"),
                "--nav-graph",
                str(nav_graph),
                "--fleet",
                FLEET,
                "--robot",
                ROBOT,
                "--start",
                START,
            ],
            logs / "fleet_driver.log",
        ),
        Child(
            "dispatcher",
            [python, str(HERE / "dispatcher.py"), "--fleet", FLEET, "--robot", ROBOT],
            logs / "dispatcher.log",
        ),
    ]
    if args.site == "easy":  # the fleet through EasyFullControl, the robot in the adapter's process
        children[1:3] = [
            Child(
                "adapter",
                [
                    python,
                    str(HERE / "easy_adapter.py"),
                    "--config",
                    str(HERE / "easy_config.yaml"),
                    "--nav-graph",
                    str(nav_graph),
                    "--robot",
                    ROBOT,
                    "--start",
                    START,
                ],
                logs / "adapter.log",
            )
        ]

    stop_reason: list[str] = []

    def on_signal(signum: int, _frame: object) -> None:
        stop_reason.append(signal.Signals(signum).name)

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)

    import rclpy
    from rclpy.action import ActionClient
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from rmf_task_msgs.action import DynamicEvent
    from rmf_task_msgs.msg import DynamicEventDescription

    # Our own signal handlers, not rclpy's: a signal must stop the children, not raise mid-wait.
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = Node("dynevent_site_watch")
    begins: list[int] = []
    node.create_subscription(
        DynamicEventDescription,
        f"rmf/dynamic_event/begin/{FLEET}/{ROBOT}",
        lambda msg: begins.append(msg.dynamic_event_seq),
        QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        ),
    )
    action = ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/{FLEET}/{ROBOT}")

    def node_named(prefix: str) -> Callable[[], bool]:
        return lambda: any(name.startswith(prefix) for name in node.get_node_names())

    def endpoint(topic: str, node_name: str, publisher: bool) -> Callable[[], bool]:
        def seen() -> bool:
            infos = (
                node.get_publishers_info_by_topic(topic)
                if publisher
                else node.get_subscriptions_info_by_topic(topic)
            )
            return any(info.node_name == node_name for info in infos)

        return seen

    def wait_for(what: str, ready: Callable[[], bool], culprit: Child) -> bool:
        """Wait, bounded, until ready(); False (with one line naming the culprit) if not."""
        started = time.monotonic()
        while time.monotonic() - started < args.up_timeout:
            if stop_reason:
                return False
            if ready():
                say(f"{what} ({time.monotonic() - started:.1f} s)")
                return True
            for child in children:
                code = child.exited()
                if code is not None:
                    say(f"{child.name} exited with status {code} before the site was up: {child.log_path}")
                    return False
            rclpy.spin_once(node, timeout_sec=0.1)
        say(f"{culprit.name} did not come up within {args.up_timeout:g} s ({what}): see {culprit.log_path}")
        return False

    schedule, adapter, dispatcher = children[0], children[1], children[-1]
    steps: list[tuple[Child | None, str, Callable[[], bool], Child]] = [
        (schedule, "schedule up", node_named("rmf_traffic_schedule_node"), schedule)
    ]
    if args.site == "easy":  # its node is up once it has found the schedule
        steps.append((adapter, "adapter up", node_named(f"{FLEET}_fleet_adapter"), adapter))
    else:
        driver = children[2]
        steps += [
            # The adapter subscribes to fleet states once it has found the schedule and made its fleet.
            (adapter, "adapter up", endpoint("/fleet_states", "fleet_adapter", publisher=False), adapter),
            (driver, "driver up", endpoint("/fleet_states", f"{FLEET}_fleet_driver", publisher=True), driver),
        ]
    steps += [
        # The robot's Dynamic Event server exists once the adapter has added the robot.
        (None, f"action server of {ROBOT} up", action.server_is_ready, adapter),
        (dispatcher, "dispatcher up", node_named("dynevent_site_dispatcher"), dispatcher),
        (None, "dynamic event begun", lambda: bool(begins), dispatcher),
    ]
    status = 0
    try:
        for child, what, ready, culprit in steps:
            if child is not None:
                child.start(env)
            if not wait_for(what, ready, culprit):
                status = 0 if stop_reason else 1  # a signal while starting is a clean stop
                return status
        print(f"READY fleet={FLEET} robot={ROBOT} places={','.join(places)} site={args.site}", flush=True)
        ready_at = time.monotonic()
        while not stop_reason:
            if args.seconds is not None and time.monotonic() - ready_at >= args.seconds:
                stop_reason.append(f"{args.seconds:g} s")
                break
            dead = [c for c in children if c.exited() is not None]
            if dead:
                say(f"{dead[0].name} exited with status {dead[0].exited()}: see {dead[0].log_path}")
                status = 1
                break
            rclpy.spin_once(node, timeout_sec=0.2)
        return status
    finally:
        say(f"stopping ({', '.join(stop_reason) or 'error'})")
        for child in reversed(children):
            child.stop()
        action.destroy()
        node.destroy_node()
        rclpy.try_shutdown()
        say("stopped")


if __name__ == "__main__":
    sys.exit(main())
