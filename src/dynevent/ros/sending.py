"""Goals sent so that their responses are not lost: from a callback of the action client's own group.

rclpy 9.1.2 (Kilted) registers the future of a goal's response in ``ActionClient.send_goal_async``
under its lock, then registers a second future in its place (a merge left both; rclpy's pull request
#1532 removed the second, after these wheels were built).  A response the executor handles between
the two completes the first future, which no one holds: the returned one never completes, and the
goal's acceptance and its result are lost to its sender while the server runs it (a probe's two
NEXTs sent at once, across hosts; 123 of 500 goals sent with a thread switch interval of 1 µs).
rclpy 7.1 (Jazzy) takes such a response before any future is registered (rclpy issue #1123).

:class:`GoalSender` sends from a guard condition's callback in the action client's mutually
exclusive callback group: no response, feedback or result of that client is taken until the send is
whole, on any executor.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from typing import Any

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup

from dynevent.errors import LocalError

__all__ = ["GoalSender"]

_Call = Callable[[Any], None]


class GoalSender:
    """Sends the goals of ``action`` (an rclpy ``ActionClient`` of ``node``, in a mutually exclusive
    callback group), in the order given, from its group's turn on the node's executor."""

    def __init__(self, node: Any, action: Any) -> None:
        if not isinstance(action.callback_group, MutuallyExclusiveCallbackGroup):
            raise LocalError(f"{type(action.callback_group).__name__}: a goal sender needs the action "
                             "client in a mutually exclusive callback group")  # fmt: skip
        self._node = node
        self._action = action
        self._queue: collections.deque[tuple[Any, Any, _Call, _Call]] = collections.deque()
        self._guard = node.create_guard_condition(self._send_queued, callback_group=action.callback_group)

    def send(self, goal: Any, goal_uuid: Any, on_feedback: _Call, on_response: _Call) -> None:
        """Send ``goal`` (a ROS goal message) as ``goal_uuid`` (a ROS UUID) on the executor's next
        turn: ``on_feedback`` is called with each feedback message of it, ``on_response`` with the
        future of its response (an rclpy ``ClientGoalHandle``) once it is done."""
        self._queue.append((goal, goal_uuid, on_feedback, on_response))
        self._guard.trigger()

    def _send_queued(self) -> None:
        while self._queue:
            goal, goal_uuid, on_feedback, on_response = self._queue.popleft()
            future = self._action.send_goal_async(goal, feedback_callback=on_feedback, goal_uuid=goal_uuid)
            future.add_done_callback(on_response)

    def destroy(self) -> None:
        """Release the guard condition (goals still queued are not sent)."""
        self._queue.clear()
        self._node.destroy_guard_condition(self._guard)
