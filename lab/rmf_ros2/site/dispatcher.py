#!/usr/bin/env python3
"""Keeps a Dynamic Event open on one robot, so that a client always finds one soon.

It sends the robot a ``robot_task_request`` on ``task_api_requests``: a compose task whose
single phase is a ``dynamic_event`` activity (with an ``estimate``, so that the task
planner can cost it).  It watches the task's end, through the adapter's task state updates
(``task_state_update``) and, as a second witness, the Dynamic Event status topic
``rmf/dynamic_event/status/<fleet>/<robot>`` going INACTIVE for the run that began on
``rmf/dynamic_event/begin/<fleet>/<robot>``; when the task has ended it requests the next.

One-shot: ``--cancel-task`` publishes a ``cancel_task_request`` for the robot's current task
(or ``--task-id``), waits for the adapter's answer and exits (0 when the adapter accepted it).

Usage: dispatcher.py [--fleet tinyRobot] [--robot tinyRobot1] [--estimate-place hall]
       dispatcher.py --cancel-task [--task-id ID] [--timeout 10]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import uuid
from dataclasses import dataclass
from typing import Any

import rclpy
from rclpy.action import ActionClient
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rmf_task_msgs.action import DynamicEvent
from rmf_task_msgs.msg import ApiRequest, ApiResponse, DynamicEventDescription, DynamicEventStatus
from std_msgs.msg import String

# Task states after which the task will not run again (rmf_api_msgs task_state.json).
TERMINAL = frozenset({"completed", "canceled", "killed", "failed", "skipped", "error"})
RESPONSE_TIMEOUT = 15.0  # s without an answer to a request before it is sent again
RETRY_DELAY = 5.0  # s after a refused request before the next try
NEXT_DELAY = 0.5  # s between a task's end and the next request (lets the adapter settle)


def _qos(depth: int, durable: bool) -> QoSProfile:
    # The adapter's task API topics are reliable and transient local; a publisher must offer
    # transient local for its subscription to match, and a late subscriber gets recent answers.
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if durable else DurabilityPolicy.VOLATILE,
    )


def dynamic_event_task(fleet: str, estimate_place: str, now_millis: int) -> dict[str, Any]:
    """The task request: compose, one phase, whose activity is a dynamic_event."""
    activity = {
        "category": "dynamic_event",
        "description": {
            "category": "dynamic_event",
            "detail": "driven by a Dynamic Event client",
            "estimate": {"category": "go_to_place", "description": {"one_of": [estimate_place]}},
            "required": [],
        },
    }
    return {
        "category": "compose",
        "description": {"category": "dynamic_event", "phases": [{"activity": activity}]},
        "unix_millis_request_time": now_millis,
        "unix_millis_earliest_start_time": now_millis,
        "requester": "dynevent_site",
        "fleet_name": fleet,
    }


@dataclass
class Run:
    """The task this dispatcher last requested, and what it has seen of it."""

    task_id: str
    sent_at: float
    answered: bool = False
    begin_seq: int | None = None  # the Dynamic Event run that began for it
    status: str = "requested"
    ended_at: float | None = None


class Dispatcher:
    def __init__(self, node: Node, fleet: str, robot: str, estimate_place: str) -> None:
        self.node = node
        self.fleet = fleet
        self.robot = robot
        self.estimate_place = estimate_place
        self.log = node.get_logger()
        self.run: Run | None = None
        self.retry_at = 0.0
        self.robot_seen = False
        self.requests = node.create_publisher(ApiRequest, "task_api_requests", _qos(10, True))
        node.create_subscription(ApiResponse, "task_api_responses", self.on_response, _qos(100, True))
        node.create_subscription(String, "task_state_update", self.on_task_state, _qos(10, True))
        node.create_subscription(
            DynamicEventDescription, f"rmf/dynamic_event/begin/{fleet}/{robot}", self.on_begin, _qos(1, True)
        )
        node.create_subscription(
            DynamicEventStatus, f"rmf/dynamic_event/status/{fleet}/{robot}", self.on_status, _qos(1, True)
        )
        # The robot's Dynamic Event server exists once the adapter has added the robot, and its
        # task manager listens to task requests from then on: a request sent earlier is lost.
        self.action = ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/{fleet}/{robot}")
        node.create_timer(0.2, self.tick)

    # --- what the adapter says -------------------------------------------------------------
    def on_response(self, msg: ApiResponse) -> None:
        run = self.run
        if run is None or msg.request_id != run.task_id or run.answered:
            return
        run.answered = True
        answer = _json(msg.json_msg)
        if answer.get("success"):
            self.log.info(f"task {run.task_id} queued")
            return
        self.log.error(f"task {run.task_id} refused: {json.dumps(answer.get('errors', answer))}")
        self._ended(run, "refused", delay=RETRY_DELAY)

    def on_task_state(self, msg: String) -> None:
        run = self.run
        state = _json(msg.data).get("data", {})
        if run is None or state.get("booking", {}).get("id") != run.task_id:
            return
        status = str(state.get("status", ""))
        if status and status != run.status:
            self.log.info(f"task {run.task_id}: {status}")
            run.status = status
        if status in TERMINAL:
            self._ended(run, status)

    def on_begin(self, msg: DynamicEventDescription) -> None:
        self.log.info(f"dynamic event begins: seq {msg.dynamic_event_seq}")
        # The begin that follows our request is our task's; a transient-local replay of an
        # earlier run is not (its seq is the one we have already seen).
        run = self.run
        if run is not None and run.begin_seq is None and run.ended_at is None:
            run.begin_seq = msg.dynamic_event_seq

    def on_status(self, msg: DynamicEventStatus) -> None:
        run = self.run
        if (
            run is not None
            and run.begin_seq is not None
            and msg.dynamic_event_seq == run.begin_seq
            and msg.dynamic_state == DynamicEventStatus.DYNAMIC_STATE_INACTIVE
        ):
            # The adapter reports the run inactive when the dynamic event is over: the task
            # state update should say so too, but this witness does not depend on it.
            self._ended(run, f"dynamic event {run.begin_seq} inactive")

    # --- what the dispatcher does ------------------------------------------------------------
    def tick(self) -> None:
        now = time.monotonic()
        if not self.robot_seen:
            if not self.action.server_is_ready():
                return
            self.robot_seen = True
            self.retry_at = now + 1.0  # give the robot's task manager a moment to subscribe
            self.log.info(f"robot {self.fleet}/{self.robot} is up")
        run = self.run
        if run is not None and run.ended_at is None:
            if not run.answered and now - run.sent_at > RESPONSE_TIMEOUT:
                self.log.warn(f"no answer to task {run.task_id} in {RESPONSE_TIMEOUT:g} s: sending again")
                self._ended(run, "unanswered", delay=0.0)
            return
        if now >= self.retry_at:
            self.request()

    def request(self) -> None:
        task_id = f"dynevent_site_{uuid.uuid4()}"
        millis = int(time.time() * 1000)
        payload = {
            "type": "robot_task_request",
            "robot": self.robot,
            "fleet": self.fleet,
            "request": dynamic_event_task(self.fleet, self.estimate_place, millis),
        }
        # The adapter uses the request id as the task id (the booking id).
        self.requests.publish(ApiRequest(json_msg=json.dumps(payload), request_id=task_id))
        self.run = Run(task_id=task_id, sent_at=time.monotonic())
        self.log.info(f"requested task {task_id}")

    def _ended(self, run: Run, why: str, delay: float = NEXT_DELAY) -> None:
        if run.ended_at is not None:
            return
        run.ended_at = time.monotonic()
        self.retry_at = run.ended_at + delay
        self.log.info(f"task {run.task_id} ended ({why})")


def _json(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def cancel_task(node: Node, fleet: str, robot: str, task_id: str | None, timeout: float) -> int:
    """Publish a cancel_task_request for the robot's current task; 0 when the adapter accepted it."""
    deadline = time.monotonic() + timeout
    latest: dict[str, str] = {}  # task id -> status, for the robot's tasks, latest last
    answers: dict[str, dict[str, Any]] = {}

    def on_task_state(msg: String) -> None:
        state = _json(msg.data).get("data", {})
        assigned = state.get("assigned_to", {})
        if assigned.get("group") == fleet and assigned.get("name") == robot:
            task = str(state.get("booking", {}).get("id", ""))
            latest.pop(task, None)
            latest[task] = str(state.get("status", ""))

    def on_response(msg: ApiResponse) -> None:
        answers[msg.request_id] = _json(msg.json_msg)

    node.create_subscription(String, "task_state_update", on_task_state, _qos(10, True))
    node.create_subscription(ApiResponse, "task_api_responses", on_response, _qos(100, True))
    requests = node.create_publisher(ApiRequest, "task_api_requests", _qos(10, True))

    if task_id is None:
        # The adapter's recent task states arrive at once (transient local); wait a little for them.
        settle = time.monotonic() + 2.0
        while time.monotonic() < min(settle, deadline):
            rclpy.spin_once(node, timeout_sec=0.1)
        running = [task for task, status in latest.items() if status not in TERMINAL]
        if not running:
            print(f"no running task for {fleet}/{robot}", file=sys.stderr)
            return 1
        task_id = running[-1]

    request_id = f"dynevent_site_cancel_{uuid.uuid4()}"
    payload = {"type": "cancel_task_request", "task_id": task_id, "labels": ["dynevent_site"]}
    requests.publish(ApiRequest(json_msg=json.dumps(payload), request_id=request_id))
    print(f"cancel requested for task {task_id}")
    while time.monotonic() < deadline and request_id not in answers:
        rclpy.spin_once(node, timeout_sec=0.1)
    answer = answers.get(request_id)
    if answer is None:
        print(f"no answer from the adapter within {timeout:g} s", file=sys.stderr)
        return 1
    print(f"answer: {json.dumps(answer)}")
    return 0 if answer.get("success") else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fleet", default="tinyRobot")
    parser.add_argument("--robot", default="tinyRobot1")
    parser.add_argument(
        "--estimate-place", default="hall", help="the place of the go_to_place the task planner costs"
    )
    parser.add_argument("--cancel-task", action="store_true", help="cancel the robot's current task, once")
    parser.add_argument("--task-id", help="with --cancel-task: this task rather than the current one")
    parser.add_argument("--timeout", type=float, default=10.0, help="with --cancel-task: s to wait")
    args = parser.parse_args(argv)

    rclpy.init()
    node = Node("dynevent_site_dispatcher" if not args.cancel_task else "dynevent_site_cancel")
    try:
        if args.cancel_task:
            return cancel_task(node, args.fleet, args.robot, args.task_id, args.timeout)
        Dispatcher(node, args.fleet, args.robot, args.estimate_place)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
