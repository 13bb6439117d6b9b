"""Smoke test of the ROS 2 environment that tests/ros/setup-ros-env.sh builds.

Run, after ``. build/ros/env.sh``, with the venv's Python::

    .venv-ros/bin/python tests/ros/smoke.py

One node holds a DynamicEvent ActionServer on
``rmf/dynamic_event/command/f/r`` and an ActionClient: one goal is sent, one
feedback with one LogEntry and the result come back. Then a DynamicEventStatus
published on a transient-local, reliable, depth-1 topic reaches a subscriber
created after the publication (a late joiner), which gets the last sample only.

Exit 0 on success, 1 on a failed check, 3 when the 30 s deadline passes.
ROS_DOMAIN_ID is chosen at random when unset, so parallel runs do not meet.
Not collected by pytest (no ``test_`` prefix).
"""

from __future__ import annotations

import faulthandler
import os
import random
import signal
import sys
import threading
import time

DEADLINE_S = 30
STEP_TIMEOUT_S = 10.0
ACTION_NAME = "rmf/dynamic_event/command/f/r"
STATUS_TOPIC = "rmf/dynamic_event/status/f/r"


def _on_deadline(signum: int, frame: object) -> None:
    print(f"smoke: FAILED: deadline of {DEADLINE_S} s passed", file=sys.stderr, flush=True)
    os._exit(3)


def _check(cond: bool, what: str) -> None:
    if not cond:
        raise AssertionError(what)


def main() -> int:
    # The alarm covers the Python side; faulthandler is the backstop that ends
    # the process even if a C call never returns.
    signal.signal(signal.SIGALRM, _on_deadline)
    signal.alarm(DEADLINE_S)
    faulthandler.dump_traceback_later(DEADLINE_S + 5, exit=True)

    if not os.environ.get("ROS_DOMAIN_ID"):
        os.environ["ROS_DOMAIN_ID"] = str(random.randint(1, 101))
    started = time.monotonic()

    import rclpy
    from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse
    from rclpy.callback_groups import ReentrantCallbackGroup
    from rclpy.executors import MultiThreadedExecutor
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rmf_task_msgs.action import DynamicEvent
    from rmf_task_msgs.msg import DynamicEventDescription, DynamicEventStatus, LogEntry

    _check(DynamicEvent.Goal.EVENT_TYPE_NEXT == 1, "EVENT_TYPE_NEXT")
    _check(DynamicEventStatus.DYNAMIC_STATE_WAITING == 1, "DYNAMIC_STATE_WAITING")
    _check(LogEntry.TIER_INFO == "info", "TIER_INFO")
    _check(hasattr(DynamicEventDescription(), "start_time"), "DynamicEventDescription.start_time")

    rclpy.init()
    node = rclpy.create_node("dynevent_smoke")
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    group = ReentrantCallbackGroup()
    feedback_seen = threading.Event()
    feedbacks: list = []
    published = [0]

    def goal_callback(goal: DynamicEvent.Goal) -> GoalResponse:
        ok = goal.event_type == DynamicEvent.Goal.EVENT_TYPE_NEXT
        return GoalResponse.ACCEPT if ok else GoalResponse.REJECT

    def execute_callback(goal_handle):  # type: ignore[no-untyped-def]
        goal = goal_handle.request
        entry = LogEntry(
            seq=0,
            tier=LogEntry.TIER_INFO,
            unix_millis_time=int(time.time() * 1000),
            text=f"started {goal.category}",
        )
        # Feedback is a volatile topic: the client's feedback subscription may
        # not be matched yet, so publish until it has seen one (bounded).
        until = time.monotonic() + STEP_TIMEOUT_S
        while not feedback_seen.is_set() and time.monotonic() < until:
            goal_handle.publish_feedback(DynamicEvent.Feedback(status="underway", id=goal.id, logs=[entry]))
            published[0] += 1
            feedback_seen.wait(0.05)
        goal_handle.succeed()
        return DynamicEvent.Result(execution_failure="", status="completed", id=goal.id)

    server = ActionServer(
        node,
        DynamicEvent,
        ACTION_NAME,
        execute_callback=execute_callback,
        goal_callback=goal_callback,
        cancel_callback=lambda _gh: CancelResponse.ACCEPT,
        callback_group=group,
    )
    client = ActionClient(node, DynamicEvent, ACTION_NAME, callback_group=group)

    def on_feedback(msg) -> None:  # type: ignore[no-untyped-def]
        feedbacks.append(msg.feedback)
        feedback_seen.set()

    def spin_until(future, what: str):  # type: ignore[no-untyped-def]
        executor.spin_until_future_complete(future, timeout_sec=STEP_TIMEOUT_S)
        _check(future.done(), f"timed out waiting for {what}")
        return future.result()

    try:
        # 1. action round trip
        _check(client.wait_for_server(timeout_sec=STEP_TIMEOUT_S), "action server not discovered")
        goal = DynamicEvent.Goal(
            dynamic_event_seq=7,
            event_type=DynamicEvent.Goal.EVENT_TYPE_NEXT,
            category="go_to_place",
            description='{"waypoint": "A"}',
            id=42,
            stubborn_period=0.0,
        )
        handle = spin_until(client.send_goal_async(goal, feedback_callback=on_feedback), "goal response")
        _check(handle.accepted, "goal rejected")
        result = spin_until(handle.get_result_async(), "result").result
        _check(
            (result.execution_failure, result.status, result.id) == ("", "completed", 42),
            f"unexpected result {result}",
        )
        until = time.monotonic() + STEP_TIMEOUT_S
        while not feedbacks and time.monotonic() < until:
            executor.spin_once(timeout_sec=0.05)
        _check(bool(feedbacks), "no feedback received")
        fb = feedbacks[0]
        _check(fb.id == 42 and fb.status == "underway", f"unexpected feedback {fb}")
        _check(
            len(fb.logs) == 1 and fb.logs[0].tier == "info" and fb.logs[0].text == "started go_to_place",
            f"unexpected feedback logs {fb.logs}",
        )

        # 2. transient-local status topic, late joiner gets the last sample only
        qos = QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        pub = node.create_publisher(DynamicEventStatus, STATUS_TOPIC, qos)
        for state in (DynamicEventStatus.DYNAMIC_STATE_INACTIVE, DynamicEventStatus.DYNAMIC_STATE_WAITING):
            pub.publish(
                DynamicEventStatus(
                    dynamic_event_seq=7,
                    dynamic_state=state,
                    status="",
                    id=0,
                    time=node.get_clock().now().to_msg(),
                )
            )
        received: list = []
        node.create_subscription(DynamicEventStatus, STATUS_TOPIC, received.append, qos)
        until = time.monotonic() + STEP_TIMEOUT_S
        while not received and time.monotonic() < until:
            executor.spin_once(timeout_sec=0.05)
        _check(bool(received), "late joiner got no status")
        settle = time.monotonic() + 0.3
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.05)
        _check(len(received) == 1, f"late joiner got {len(received)} statuses, expected 1")
        _check(
            received[0].dynamic_state == DynamicEventStatus.DYNAMIC_STATE_WAITING
            and received[0].dynamic_event_seq == 7,
            f"unexpected status {received[0]}",
        )
    except AssertionError as exc:
        print(f"smoke: FAILED: {exc}", file=sys.stderr)
        return 1
    finally:
        client.destroy()
        server.destroy()
        executor.shutdown(timeout_sec=2.0)
        node.destroy_node()
        rclpy.try_shutdown()

    print(
        f"smoke: ok (domain {os.environ['ROS_DOMAIN_ID']}, feedback published {published[0]}x, "
        f"{time.monotonic() - started:.2f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
