"""The client machine (:mod:`dynevent.client`) over an rclpy action client and the robot's topics.

:class:`DynamicEventClient` subscribes to the robot's status and begin
topics, keeps a :class:`~dynevent.client.ClientState` from them, and turns
:meth:`~DynamicEventClient.next`, :meth:`~DynamicEventClient.cancel` and
:meth:`~DynamicEventClient.finish` into goals, each followed by a
:class:`GoalRun`: its feedback as it arrives, then one typed
:class:`~dynevent.client.Outcome`, or at once a
:class:`~dynevent.client.Refused` when the robot, as the client knows it,
would refuse the goal.  A run is awaitable inside the node's executor
(``outcome = await run``) and can be waited on from another thread with a
bound (:meth:`GoalRun.wait`).

A server's restart (R21), or a partition longer than DDS's lease, loses what was in flight to the
client.  The client hands the robot's status publisher matched and no longer matched to the
client machine (:class:`~dynevent.client.ContactMade`, :class:`~dynevent.client.ContactLost`), which
asks again for the result of every open goal (R21.4, R21.5): a server that kept the answer gives it,
one that does not know the goal ends it ``goal lost: unknown to the server``; ``on_contact`` hears
of contact lost and found, and a wait that ends at its bound names the cause.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from typing import Any

from action_msgs.msg import GoalStatus as RosGoalStatus
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.task import Future

from dynevent import client as cl
from dynevent.client.run import GoalRun
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.errors import (
    GoalWaitTimeout,  # defined there with every error; importable here too
    InvalidMessage,
    NotSpinning,
)
from dynevent.ros import convert
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.ros.qos import introspect, latched
from dynevent.ros.sending import GoalSender
from dynevent.server.inputs import NOW_RANGE
from dynevent.wire.messages import Result
from dynevent.wire.names import (
    ROBOT_BEGIN_TOPIC_DEPTH,
    STATUS_TOPIC_DEPTH,
    action_name,
    begin_topic,
    status_topic,
)
from dynevent.wire.units import SECOND
from dynevent.wire.vocab import Failure, GoalStatus

__all__ = ["DynamicEventClient", "GoalRun", "GoalWaitTimeout", "introspect"]

_TERMINAL = {
    RosGoalStatus.STATUS_SUCCEEDED: GoalStatus.SUCCEEDED,
    RosGoalStatus.STATUS_CANCELED: GoalStatus.CANCELED,
    RosGoalStatus.STATUS_ABORTED: GoalStatus.ABORTED,
}

#: The shortest wait the client's one timer is armed for (seconds): a deadline already past is
#: ticked at once, and a clock that moves back cannot set a wait of no length.
SHORTEST_WAIT = 0.001


class DynamicEventClient:
    """A Dynamic Event client of one robot on ``node``, which an executor must spin.

    ``categories`` (the robot's, when known) and ``validators`` (e.g.
    ``dynevent.descriptions.Robot().validators()``) let the client refuse, without
    sending it, a goal the server would refuse (:class:`dynevent.client.ClientState`).
    ``trace`` records every message the client sends and receives, as a tap at a client
    (docs/trace-format.md), for ``dynevent check``.  ``on_contact`` is called (on the executor's
    thread) with each :class:`~dynevent.client.OutOfContact` and
    :class:`~dynevent.client.BackInContact` (R21.5).
    """

    def __init__(
        self,
        node: Any,
        fleet: str,
        robot: str,
        *,
        categories: Any = None,
        validators: Any = None,
        uuid_prefix: str | None = None,
        trace: TraceWriter | None = None,
        on_contact: Callable[[cl.OutOfContact | cl.BackInContact], None] | None = None,
    ) -> None:
        self._node = node
        self._trace = trace
        self._on_contact = on_contact
        self._name = f"{fleet}/{robot}"
        self._lock = threading.Lock()
        prefix = uuid_prefix if uuid_prefix is not None else os.urandom(8).hex()
        self._state = cl.ClientState.new(prefix, categories=categories, validators=validators)
        self._runs: dict[str, GoalRun] = {}
        self._views = threading.Condition(self._lock)
        self._status_seen = False
        self._contact_taken = False  # a matched event of the status topic was taken
        # every attribute above, the timer and the action client before the subscriptions: an executor
        # that already spins the node (a shared one) may call back as soon as a subscription exists
        group = MutuallyExclusiveCallbackGroup()
        # one timer, armed only for the next moment something can be due (a NEXT's timeout, asking a
        # server again for a result): a client that waits costs nothing between (_arm)
        self._timer = node.create_timer(1.0, self._on_tick, callback_group=group)
        self._timer.cancel()
        self._action = ActionClient(node, DynamicEvent, action_name(fleet, robot), callback_group=group)
        self._sender = GoalSender(node, self._action)
        self._begin = node.create_subscription(
            RosDescription,
            begin_topic(fleet, robot),
            self._on_begin,
            latched(ROBOT_BEGIN_TOPIC_DEPTH),
            callback_group=group,
        )
        # a status publisher matched is a server process in contact (a new one, R21.4, or one lost
        # and found again, R21.5), and none matched is contact lost: the graph's events, no clock
        self._status = node.create_subscription(
            RosStatus,
            status_topic(fleet, robot),
            self._on_status,
            latched(STATUS_TOPIC_DEPTH),
            callback_group=group,
            event_callbacks=SubscriptionEventCallbacks(matched=self._on_contact_event),
        )

    # ---------------------------------------------------------------- views

    @property
    def state(self) -> cl.ClientState:
        """The client machine's state: the view of the robot and the open goals."""
        with self._lock:
            return self._state

    def now(self) -> int:
        """The node's clock, in integer nanoseconds."""
        nanoseconds: int = self._node.get_clock().now().nanoseconds
        return min(max(nanoseconds, NOW_RANGE[0]), NOW_RANGE[1])

    def contact_text(self) -> str | None:
        """One line saying since when the client has been out of contact with the robot's server
        (R21.5), or None while it is in contact."""
        since = self.state.contact_lost_at
        if since is None:
            return None
        clock = time.strftime("%H:%M:%S", time.localtime(since / SECOND))
        return f"out of contact with {self._name} since {clock} ({(self.now() - since) / SECOND:.0f} s)"

    def wait_for_server(self, timeout: float) -> bool:
        """Wait (at most ``timeout`` seconds) until the robot's action server is there."""
        return bool(self._action.wait_for_server(timeout_sec=timeout))

    def wait_for_status(self, timeout: float) -> bool:
        """Wait (at most ``timeout`` seconds, from another thread than the executor's) for a status.
        Raises :class:`~dynevent.errors.NotSpinning` at once when the node is in no executor.

        The status must be of the newest run the client has heard of: a begin
        can arrive before its run's status, and a goal built from the older
        status would only be refused.
        """
        if getattr(self._node, "executor", None) is None:
            raise NotSpinning(
                f"nothing spins node {self._node.get_name()!r}: add it to an executor that spins in "
                "another thread (its callbacks bring the status), or use dynevent.ros.RobotClient, "
                "which spins its own node"
            )
        with self._views:
            return self._views.wait_for(
                lambda: self._status_seen and self._state.seq == self._state.newest_seq, timeout
            )

    # ---------------------------------------------------------------- commands

    def next(
        self,
        category: str,
        description: str,
        *,
        stubborn_period: float = 0.0,
        timeout: float | None = None,
        on_progress: Callable[[cl.Progress], None] | None = None,
    ) -> GoalRun:
        """Ask the robot to run the next event (a NEXT goal); ``timeout`` seconds cancels it when due."""
        return self._command(
            lambda state, now: cl.request_next(
                state, category, description, stubborn_period=stubborn_period, timeout=timeout, now=now
            ),
            on_progress,
        )

    def cancel(self, on_progress: Callable[[cl.Progress], None] | None = None) -> GoalRun:
        """Ask the robot to cancel the running event (a CANCEL goal naming it)."""
        return self._command(lambda state, now: cl.request_cancel(state, now=now), on_progress)

    def finish(self) -> GoalRun:
        """Tell the robot that the dynamic event is over (a FINISHED goal)."""
        return self._command(lambda state, now: cl.request_finish(state, now=now), None)

    def withdraw(self, run: GoalRun) -> None:
        """No longer want this NEXT: its child is cancelled (a CANCEL naming it) as soon as it is known
        to run, at once if it is (:func:`dynevent.client.request_withdraw`); ``run`` then ends with how
        the child ended.  Nothing is sent for a run already over or never sent."""
        uuid = run.goal_uuid
        if uuid is None or run.done():
            return
        with self._lock:
            transition = cl.request_withdraw(self._state, uuid, now=self.now())
            self._state = transition.state
        self._carry_out(transition.outputs)

    def introspect(self) -> bool:
        """Publish this client's action service events (ROS 2 introspection, with contents), so that
        a recording holds its goals and answers; False where rclpy cannot."""
        return introspect(self._action, self._node)

    def destroy(self) -> None:
        """Release the action client, subscriptions and timer."""
        self._sender.destroy()
        self._action.destroy()
        self._node.destroy_subscription(self._status)
        self._node.destroy_subscription(self._begin)
        self._node.destroy_timer(self._timer)

    # ---------------------------------------------------------------- plumbing

    def _command(
        self,
        command: Callable[[cl.ClientState, int], cl.ClientTransition],
        on_progress: Callable[[cl.Progress], None] | None,
    ) -> GoalRun:
        run = GoalRun(on_progress, Future(), why_open=self.contact_text)
        with self._lock:
            transition = command(self._state, self.now())
            self._state = transition.state
            for output in transition.outputs:
                if isinstance(output, cl.SendGoal):
                    run.goal_uuid = output.goal_uuid
                    self._runs[output.goal_uuid] = run
        for output in transition.outputs:
            if isinstance(output, cl.Refused):
                run.end(output)
        self._carry_out(transition.outputs)
        return run

    def _step(self, event: cl.ClientInput) -> None:
        with self._lock:
            transition = cl.step(self._state, event)
            self._state = transition.state
            self._views.notify_all()
        self._carry_out(transition.outputs)

    def _carry_out(self, outputs: tuple[cl.ClientOutput, ...]) -> None:
        for output in outputs:
            if isinstance(output, cl.SendGoal):
                self._send(output)
            elif isinstance(output, cl.Progress):
                run = self._runs.get(output.goal_uuid)
                if run is not None:
                    run.report(output)
            elif isinstance(output, cl.Outcome):
                ended = self._runs.pop(output.goal_uuid, None)
                if ended is not None:
                    ended.end(output)
            elif isinstance(output, cl.AskResult):
                self._ask_result(output.goal_uuid, contact=output.contact)
            elif isinstance(output, (cl.OutOfContact, cl.BackInContact)) and self._on_contact is not None:
                self._on_contact(output)
        self._arm()

    def _send(self, send: cl.SendGoal) -> None:
        uuid = send.goal_uuid
        if self._trace is not None:
            self._trace.observe("goal", goal_uuid=uuid, message=send.goal)
        self._sender.send(
            convert.goal_to_ros(send.goal), convert.uuid_to_ros(uuid),
            lambda message: self._on_feedback(uuid, message), lambda future: self._on_response(uuid, future),
        )  # fmt: skip

    def _on_response(self, uuid: str, future: Any) -> None:
        handle = future.result()
        accepted = bool(handle is not None and handle.accepted)
        if self._trace is not None:
            self._trace.observe("goal_response", goal_uuid=uuid, accepted=accepted)
        self._step(cl.GoalResponse(goal_uuid=uuid, accepted=accepted))
        if accepted:
            handle.get_result_async().add_done_callback(lambda done: self._on_result(uuid, done))

    def _ask_result(self, uuid: str, *, contact: bool) -> None:
        """Ask the server again for a goal's result (R21.4, R21.5, R21.6: :class:`~dynevent.client.AskResult`
        says what an unknown goal means); a request sent while the action server is not matched
        would go nowhere, and the machine asks again later."""
        if not self._action.server_is_ready():
            return
        response = DynamicEvent.Impl.SendGoalService.Response(accepted=True)
        handle = ClientGoalHandle(self._action, convert.uuid_to_ros(uuid), response)
        handle.get_result_async().add_done_callback(lambda done: self._on_result(uuid, done, contact=contact))

    def _on_result(self, uuid: str, future: Any, *, contact: bool = True) -> None:
        response = future.result()
        if self.state.goal(uuid) is None:
            return  # answered already: a goal asked for again hears its answer once per request
        if response.status == RosGoalStatus.STATUS_UNKNOWN:  # a server that does not know the goal
            if not contact:
                return  # R21.6: not received yet; the machine asks again
            status, result = GoalStatus.ABORTED, Result(execution_failure=Failure.LOST.value)  # R21.4
        else:
            status = _TERMINAL.get(response.status, GoalStatus.ABORTED)
            result = convert.result_from_ros(response.result)
            if self._trace is not None:
                self._trace.observe("result", goal_uuid=uuid, status=status, message=result)
        self._step(cl.ResultReceived(goal_uuid=uuid, status=status, result=result))

    def _heard(self, kind: str, read: Callable[[Any], Any], message: Any, **fields: Any) -> Any:
        """``message`` read as dynevent's mirror (None, after a warning, when it is not valid), and
        written to the trace as a ``kind`` record."""
        try:
            mirror = read(message)
        except InvalidMessage as exc:
            goal = f" for goal {fields['goal_uuid']}" if fields else ""
            self._node.get_logger().warning(f"{kind}{goal} refused: {exc}")
            return None
        if self._trace is not None:
            self._trace.observe(kind, message=mirror, **fields)
        return mirror

    def _on_feedback(self, uuid: str, message: Any) -> None:
        feedback = self._heard("feedback", convert.feedback_from_ros, message.feedback, goal_uuid=uuid)
        if feedback is not None:
            self._step(cl.FeedbackReceived(goal_uuid=uuid, feedback=feedback))

    def _on_status(self, message: Any) -> None:
        status = self._heard("status", convert.status_from_ros, message)
        if status is not None:
            with self._lock:
                self._status_seen = True
            self._step(cl.StatusReceived(message=status, now=self.now()))

    def _on_begin(self, message: Any) -> None:
        begin = self._heard("begin", convert.begin_from_ros, message)
        if begin is not None:
            self._step(cl.BeginReceived(message=begin, now=self.now()))

    def _on_tick(self) -> None:
        if self.state.goals:
            self._step(cl.Tick(now=self.now()))
        else:
            self._arm()

    def _on_contact_event(self, info: Any) -> None:
        """A status publisher of the robot matched (a server process in contact: R21.4, R21.5), or
        the last one is no longer matched (contact lost: R21.5).

        ``info`` sums every change since the last event taken: a process killed and its successor
        matched before the executor took the event read as no change of the current count (one
        gone, one come), and the goal the dead process never saw waited for good (found in CI,
        under load).  The total count says a publisher matched whatever left meanwhile.

        The first event, of one publisher whose status was heard already, is the match of the process
        the client heard, taken late (after the executor ran the status's callback, and a goal sent
        since): no new process, and a result request sent then could reach it before the goal's
        request and be answered as unknown (found with ``dynevent send``: a goal ended lost)."""
        with self._lock:
            taken_late = not self._contact_taken and self._status_seen and info.total_count_change == 1
            self._contact_taken = True
        if info.total_count_change > 0 and not taken_late:
            self._step(cl.ContactMade(now=self.now()))
        if info.current_count == 0 and (info.current_count_change < 0 or info.total_count_change > 0):
            self._step(cl.ContactLost(now=self.now()))

    def _arm(self) -> None:
        """Set the timer for the next moment something can be due (the client machine's next
        deadline, :func:`dynevent.client.next_deadline`: a NEXT's timeout, asking a server again for
        a result), or stop it when nothing can be."""
        with self._lock:
            deadline = cl.next_deadline(self._state)
        if deadline is None:
            self._timer.cancel()
            return
        wait = (deadline - self.now()) / SECOND
        self._timer.timer_period_ns = round(max(wait, SHORTEST_WAIT) * SECOND)
        self._timer.reset()
