"""Goals sent by dynevent's action clients all hear their responses (dynevent.ros.sending).

rclpy 9.1.2's ``send_goal_async`` registers a goal's response future under its lock, then registers a
second one in its place: a response handled between the two completes a future no one holds.  A
process that loses the processor at that moment (a loaded machine) loses the goal's response and its
result; here the sending thread is held there, for :data:`STALL` seconds, by the dictionary of feedback
callbacks that ``send_goal_async`` writes to in that moment.  The goals go to a plain rclpy action
server that refuses each one at once.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import pytest
from rclpy.action import ActionClient, ActionServer, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rmf_task_msgs.action import DynamicEvent
from ros_support import WAIT, Graph

from dynevent.errors import LocalError
from dynevent.ros import convert
from dynevent.ros.sending import GoalSender

GOALS = 10
STALL = 0.05
NAME = "sending/refused"


class _Stalling(dict[bytes, Any]):
    """Feedback callbacks, written to only after a goal's request is sent: the writer is held there."""

    def __setitem__(self, key: bytes, value: Any) -> None:
        time.sleep(STALL)
        super().__setitem__(key, value)


@pytest.fixture
def client(graph: Graph) -> tuple[Any, Any]:
    def serve(node: Any) -> Any:
        return ActionServer(
            node, DynamicEvent, NAME, execute_callback=lambda handle: DynamicEvent.Result(),
            goal_callback=lambda goal: GoalResponse.REJECT,
        )  # fmt: skip

    def make(node: Any) -> tuple[Any, Any]:
        action = ActionClient(node, DynamicEvent, NAME)
        action._feedback_callbacks = _Stalling()
        return node, action

    graph.node("refuser", serve)
    made: tuple[Any, Any] = graph.node("sender", make)
    assert made[1].wait_for_server(WAIT)
    return made


def _heard(send: Callable[[Any, Any, Callable[[Any], None]], None], within: float = WAIT) -> list[int]:
    """Send :data:`GOALS` goals one by one; the numbers of those whose response was heard (refused)
    ``within`` seconds of the last."""
    heard: list[int] = []
    lock = threading.Condition()

    def hear(number: int) -> Callable[[Any], None]:
        def on_response(future: Any) -> None:
            with lock:
                heard.append(number if not future.result().accepted else -1)
                lock.notify_all()

        return on_response

    for number in range(GOALS):
        send(
            DynamicEvent.Goal(event_type=1, id=number),
            convert.uuid_to_ros(f"{number + 1:032x}"),
            hear(number),
        )
    with lock:
        lock.wait_for(lambda: len(heard) == GOALS, within)
    time.sleep(STALL * 4)  # none heard twice
    return sorted(heard)


def test_rclpys_own_send_loses_the_response_of_a_goal_answered_while_it_registers_it(
    client: tuple[Any, Any],
) -> None:
    """The defect :class:`GoalSender` works around.  When this fails, the rclpy in use registers its
    futures once (rclpy pull request #1532), and dynevent.ros.sending's note may say so."""
    _, action = client

    def send(goal: Any, uuid: Any, on_response: Callable[[Any], None]) -> None:
        action.send_goal_async(
            goal, feedback_callback=lambda feedback: None, goal_uuid=uuid
        ).add_done_callback(on_response)

    assert _heard(send, within=1.0) == []  # a response lost is lost for good: a second shows it


def test_a_goal_sender_hears_the_response_of_every_goal(client: tuple[Any, Any]) -> None:
    node, action = client
    sender = GoalSender(node, action)
    try:
        assert _heard(
            lambda goal, uuid, on_response: sender.send(goal, uuid, lambda _: None, on_response)
        ) == list(range(GOALS))
    finally:
        sender.destroy()


def test_a_goal_sender_needs_a_mutually_exclusive_callback_group(graph: Graph) -> None:
    def make(node: Any) -> tuple[Any, Any]:
        return node, ActionClient(node, DynamicEvent, NAME, callback_group=ReentrantCallbackGroup())

    node, action = graph.node("reentrant", make)
    with pytest.raises(LocalError, match="ReentrantCallbackGroup: a goal sender needs"):
        GoalSender(node, action)
