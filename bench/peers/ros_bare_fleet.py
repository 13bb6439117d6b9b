"""The bare rclpy peer of ``dynevent serve`` for bench/ros_fleet.py: the same exchanges, no protocol.

Per robot one rclpy ``ActionServer`` of ``rmf_task_msgs/action/DynamicEvent`` and a transient-local
status publisher (and the begin publishers serve makes), on one node spun by a single-threaded
executor, as serve's are.  Each goal is accepted, publishes RUNNING and one ``underway`` feedback,
runs a simulated child of ``DURATION`` seconds on a one-shot timer, then publishes WAITING and
succeeds with ``completed``.  Nothing is checked: it is the least a server doing the same exchange
does, the floor dynevent's binding is measured against.

    python ros_bare_fleet.py CONFIG [--introspection] [--ignore-own]

CONFIG is the JSON file serve reads (fleet, robots, categories).  ``--introspection`` turns on each
action server's service events as serve's judge does; ``--ignore-own`` gives the process's DDS
participant the property serve gives its own (dynevent.ros.participant), so that a start measured
beside serve's makes the same entities the same way.
"""

from __future__ import annotations

import contextlib
import json
import signal
import sys
import threading
from pathlib import Path
from typing import Any

import rclpy
from rclpy.action import ActionServer
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.task import Future
from rmf_task_msgs.action import DynamicEvent
from rmf_task_msgs.msg import DynamicEventDescription, DynamicEventStatus

from dynevent.ros.participant import ignore_own_endpoints
from dynevent.ros.qos import EVENTS_KEPT, introspect
from dynevent.ros.server import latched as _latched  # the same QoS as serve's topics


class Robot:
    def __init__(self, node: Any, fleet: str, robot: str, duration: float, introspection: bool) -> None:
        self.node, self.duration, self.last = node, duration, 1
        self.status = node.create_publisher(
            DynamicEventStatus, f"rmf/dynamic_event/status/{fleet}/{robot}", _latched(1)
        )
        self.begin = node.create_publisher(
            DynamicEventDescription, f"rmf/dynamic_event/begin/{fleet}/{robot}", _latched(1)
        )
        self.action = ActionServer(
            node, DynamicEvent, f"rmf/dynamic_event/command/{fleet}/{robot}", self.execute
        )
        if introspection:
            introspect(self.action, node, _latched(EVENTS_KEPT))
        self.status.publish(DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=1))

    async def execute(self, goal_handle: Any) -> Any:
        self.last += 1
        child = self.last
        self.status.publish(
            DynamicEventStatus(dynamic_event_seq=1, dynamic_state=2, status="underway", id=child)
        )
        goal_handle.publish_feedback(DynamicEvent.Feedback(status="underway", id=child))
        ended: Future[None] = Future()
        timer = None

        def end() -> None:
            self.node.destroy_timer(timer)
            ended.set_result(None)

        timer = self.node.create_timer(self.duration, end)
        await ended
        self.status.publish(
            DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=child)
        )
        goal_handle.succeed()
        return DynamicEvent.Result(status="completed", id=child)


def main() -> None:
    config = json.loads(Path(sys.argv[1]).read_text(encoding="utf-8"))
    duration = float(config["categories"]["go_to_place"]["duration"])
    if "--ignore-own" in sys.argv[2:]:
        ignore_own_endpoints()
    introspection = "--introspection" in sys.argv[2:]
    rclpy.init()
    node = rclpy.create_node("bench_bare_fleet")
    robots = [Robot(node, config["fleet"], robot, duration, introspection) for robot in config["robots"]]
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())

    def spin() -> None:
        with contextlib.suppress(ExternalShutdownException):
            executor.spin()

    threading.Thread(target=spin, daemon=True).start()
    print(f"serving {len(robots)} robot(s)", flush=True)
    stop.wait()
    executor.shutdown(timeout_sec=5)


if __name__ == "__main__":
    main()
