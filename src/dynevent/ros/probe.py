"""The probe's link over DDS (:class:`RosLink`): the probe's cases (:mod:`dynevent.conformance.probe.runner`)
carried to a live Dynamic Event server through its action, status and begin topics, with nothing of
the server's process imported.  ``dynevent probe`` (:mod:`dynevent.tools.live.probe`) runs them."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from action_msgs.msg import GoalStatus as RosGoalStatus
from rclpy.action import ActionClient
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, QoSPolicyKind, QoSProfile

from dynevent.conformance.judge.trace import TraceWriter
from dynevent.conformance.probe.runner import Exchange, Link
from dynevent.errors import InvalidMessage
from dynevent.ros import convert
from dynevent.ros.client import introspect
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.ros.qos import latched
from dynevent.ros.sending import GoalSender
from dynevent.wire.messages import Goal
from dynevent.wire.names import (
    STATUS_TOPIC_DEPTH,
    action_name,
    begin_topic,
    description_service,
    status_topic,
)
from dynevent.wire.vocab import CANCEL_GOAL_TERMINATED, GoalStatus

__all__ = ["VOLATILE", "RosLink"]

_TERMINAL = {
    RosGoalStatus.STATUS_SUCCEEDED: GoalStatus.SUCCEEDED,
    RosGoalStatus.STATUS_CANCELED: GoalStatus.CANCELED,
    RosGoalStatus.STATUS_ABORTED: GoalStatus.ABORTED,
}
#: How long the description case looks for the service, which a server need not offer (D17).
_SERVICE_WAIT = 2.0
#: How a topic offered volatile is said.
VOLATILE = "offered volatile, not transient-local: a late subscriber gets nothing (R1.4)"
#: The history depth of the probe's own subscriptions.
_READER_DEPTH = 100


class RosLink(Link):
    """The probe's :class:`~dynevent.conformance.probe.runner.Link` over DDS: the robot's status and begin
    topics, and an action client without a client machine."""

    channels_lag = True  # each reliable DDS channel delivers in order, held back by a message lost

    def __init__(self, node: Any, fleet: str, robot: str, trace: TraceWriter | None = None) -> None:
        super().__init__(fleet, robot, trace)
        self._node = node
        self._last_number = 0  # the status writer's last publication sequence number heard
        # a deep reader history: the writer keeps the last message for late subscribers (R1.4), and
        # the probe, subscribed all along, must miss none of those that follow (an INACTIVE status
        # followed at once by the next run's)
        self._topics = {
            "status": (RosStatus, status_topic(fleet, robot), self._on_status),
            "begin": (RosDescription, begin_topic(fleet, robot), self._on_begin),
        }
        self._subscriptions = [self._subscribe(name, latched(_READER_DEPTH)) for name in self._topics]
        self._action = ActionClient(node, DynamicEvent, action_name(fleet, robot))
        self._sender = GoalSender(node, self._action)
        self._describer: Any = None  # the description query's client, made at its first use

    def _subscribe(self, name: str, qos: QoSProfile) -> Any:
        kind, topic, callback = self._topics[name]
        events = SubscriptionEventCallbacks(incompatible_qos=lambda info: self._incompatible(name, info))
        return self._node.create_subscription(kind, topic, callback, qos, event_callbacks=events)

    def _incompatible(self, name: str, info: Any) -> None:
        """A writer on the topic offers a QoS the probe's transient-local reader cannot match: said
        (:attr:`~dynevent.conformance.probe.runner.Link.offered`), and, for a volatile writer, a volatile
        reader too, so that what it publishes from now on is still heard."""
        policy = QoSPolicyKind(info.last_policy_kind)
        if name in self.offered:
            return
        if policy is QoSPolicyKind.DURABILITY:
            self.offered[name] = VOLATILE
            volatile = latched(_READER_DEPTH)
            volatile.durability = DurabilityPolicy.VOLATILE
            self._subscriptions.append(self._subscribe(name, volatile))
        else:
            self.offered[name] = f"offered a QoS the probe's reader cannot match ({policy.name.lower()})"

    def clock(self) -> float:
        return time.monotonic()

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        with self._changed:
            return self._changed.wait_for(condition, timeout)

    def _on_status(self, message: Any, info: Any) -> None:
        # a gap in the writer's numbers is a status published and never delivered (its topic keeps one)
        number = int(info.get("publication_sequence_number") or 0)
        if number and self._last_number and number > self._last_number + 1:
            self.statuses_missed += number - self._last_number - 1
        self._last_number = max(number, self._last_number)
        try:
            status = convert.status_from_ros(message)
        except InvalidMessage:
            return
        self.hear_status(status)

    def _on_begin(self, message: Any) -> None:
        try:
            begin = convert.begin_from_ros(message)
        except InvalidMessage:
            return
        self.hear_begin(begin)

    def wait_for_server(self, timeout: float) -> bool:
        """The action server found, and then the robot's status publisher matched by the probe's
        reader (or found to offer what it cannot match), within ``timeout`` in all: over a lossy link
        the two are discovered apart, seconds apart, and a status the reader is not yet matched to
        cannot come (R1.4 is judged once it can).  A server without a status publisher is still found."""
        deadline = time.monotonic() + timeout
        if not self._action.wait_for_server(timeout_sec=timeout):
            return False
        reader = self._subscriptions[0]  # the status topic's, made first
        while reader.get_publisher_count() == 0 and "status" not in self.offered:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            time.sleep(min(left, 0.05))
        return True

    def late_subscriber(self) -> threading.Event:
        heard = threading.Event()

        def hear(_: Any) -> None:
            with self._changed:  # a wait of the link looks again
                heard.set()
                self._changed.notify_all()

        topic = status_topic(self.fleet, self.robot)
        self._subscriptions.append(
            self._node.create_subscription(RosStatus, topic, hear, latched(STATUS_TOPIC_DEPTH))
        )
        return heard

    def send(self, goal: Goal) -> Exchange:
        exchange = Exchange(goal, self)
        self.sent("goal", goal_uuid=exchange.uuid, message=goal)
        self._sender.send(
            convert.goal_to_ros(goal),
            convert.uuid_to_ros(exchange.uuid),
            lambda message: self._on_feedback(exchange, message),
            lambda done: self._on_response(exchange, done),
        )
        return exchange

    def _on_response(self, exchange: Exchange, future: Any) -> None:
        handle = future.result()
        accepted = bool(handle is not None and handle.accepted)
        if accepted:
            exchange.handle = handle
            exchange.accepted_at = handle.stamp.sec * 1_000_000_000 + handle.stamp.nanosec
        self.hear_response(exchange, accepted)
        if accepted:
            handle.get_result_async().add_done_callback(lambda done: self._on_result(exchange, done))

    def _on_result(self, exchange: Exchange, future: Any) -> None:
        response = future.result()
        status = _TERMINAL.get(response.status, GoalStatus.ABORTED)
        self.hear_answer(exchange, status, convert.result_from_ros(response.result))

    def _on_feedback(self, exchange: Exchange, message: Any) -> None:
        try:
            feedback = convert.feedback_from_ros(message.feedback)
        except InvalidMessage:
            return
        self.hear_feedback(exchange, feedback)

    def cancel(self, exchange: Exchange, timeout: float) -> bool | None:
        answered = threading.Event()
        accepted: list[bool] = []

        def on_response(future: Any) -> None:
            response = future.result()
            canceling = [] if response is None else response.goals_canceling
            accepted.append(any(convert.uuid_from_ros(info.goal_id) == exchange.uuid for info in canceling))
            ended = response is not None and int(response.return_code) == CANCEL_GOAL_TERMINATED
            self.hear_cancel_response(exchange, accepted[0], terminated=ended and not accepted[0])
            answered.set()

        self.sent("cancel_request", goal_uuid=exchange.uuid)
        exchange.handle.cancel_goal_async().add_done_callback(on_response)
        return accepted[0] if answered.wait(timeout) else None

    def describe(self, timeout: float) -> tuple[Any, str]:
        """The description query's answer (R16), or None and why there is none: no service type in
        this installation, no service for the robot, or no answer within ``timeout`` (the service's
        discovery included)."""
        service = convert.describe_type()
        if service is None:
            return None, "this installation's rmf_task_msgs has no DescribeDynamicEvent service type"
        if self._describer is None:  # one client for the run: a query after the first needs no discovery
            self._describer = self._node.create_client(service, description_service(self.fleet, self.robot))
        client = self._describer
        deadline = time.monotonic() + timeout  # the service found and its answer, within ``timeout`` in all
        if not client.wait_for_service(timeout_sec=min(timeout, _SERVICE_WAIT)):
            return None, f"no description service {description_service(self.fleet, self.robot)}"
        answered = threading.Event()
        future = client.call_async(service.Request())
        future.add_done_callback(lambda _: answered.set())
        if not answered.wait(max(deadline - time.monotonic(), 0.0)):
            return None, f"the description service did not answer within {timeout:g} s"
        return future.result(), ""

    def introspect(self) -> bool:
        """Publish the probe's action service events (ROS 2 introspection, with contents)."""
        return introspect(self._action, self._node)

    def destroy(self) -> None:
        if self._describer is not None:
            self._node.destroy_client(self._describer)
        self._sender.destroy()
        self._action.destroy()
