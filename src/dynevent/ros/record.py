"""What ``dynevent record`` (:mod:`dynevent.tools.live.record`) records: the subscriptions.

The recorder looks at the ROS 2 graph (each :meth:`Recorder.discover`) and subscribes to every
Dynamic Event name it finds for the robots asked for (``--fleet``,
``--robot``; every robot by default): each robot's status and begin topics,
the fleet-wide begin topic, the action's feedback and goal status topics and,
where introspection is on at a server or client, the action's service event
topics (send_goal, get_result, cancel_goal), which carry the goals and their
answers (docs/recordings.md).  Each message is written as it arrives,
serialised as received, with its receive time and the time its publisher sent it, into an MCAP bag in the
rosbag2 layout (``metadata.yaml`` beside it), which ``ros2 bag`` and other
rosbag2 readers open and ``dynevent check`` judges.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from action_msgs.msg import GoalStatusArray
from action_msgs.srv import CancelGoal
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from dynevent.bags import reader as bags
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.wire.names import action_name, begin_topic, status_topic

__all__ = ["DISCOVERY_PERIOD", "Recorder"]

#: The message class of each type a Dynamic Event conversation uses.
_CLASSES: dict[str, Any] = {
    "rmf_task_msgs/msg/DynamicEventStatus": RosStatus,
    "rmf_task_msgs/msg/DynamicEventDescription": RosDescription,
    "rmf_task_msgs/action/DynamicEvent_FeedbackMessage": DynamicEvent.Impl.FeedbackMessage,
    "action_msgs/msg/GoalStatusArray": GoalStatusArray,
    "rmf_task_msgs/action/DynamicEvent_SendGoal_Event": DynamicEvent.Impl.SendGoalService.Event,
    "rmf_task_msgs/action/DynamicEvent_GetResult_Event": DynamicEvent.Impl.GetResultService.Event,
    "action_msgs/srv/CancelGoal_Event": CancelGoal.Event,
}
#: How often the graph is looked at for new topics, and the progress line redrawn, in seconds.
DISCOVERY_PERIOD = 1.0
#: The depth of the recorder's subscriptions.
DEPTH = 1000
_UNHASHED = "RIHS01_" + "0" * 64


class Recorder:
    """Subscribes to the Dynamic Event topics of the robots ``wanted(fleet, robot)`` names and writes
    every message into ``writer`` (:func:`dynevent.bags.sent.open_writer`'s, open); :meth:`discover`
    finds new topics."""

    def __init__(
        self, node: Any, writer: Any, wanted: Callable[[str, str], bool], say: Callable[[str], None] = print
    ) -> None:
        self.node = node
        self.say = say
        self.writer = writer
        self.wanted = wanted
        self.messages = 0
        self.bytes = 0
        self.topics: dict[str, Any] = {}  # topic: its subscription
        self.heard: set[str] = set()  # the topics whose subscription has matched a publisher
        self._connections: dict[str, Any] = {}
        self._lock = threading.Lock()

    def discover(self) -> None:
        """Subscribe to every Dynamic Event topic on the graph not yet recorded."""
        for topic, types in self.node.get_topic_names_and_types():
            if topic in self.topics:
                continue
            msgtype = next((name for name in types if name in _CLASSES), None)
            if msgtype is None or not self._named(topic):
                continue
            infos = self.node.get_publishers_info_by_topic(topic)
            if not infos:
                continue  # no publisher yet: its QoS (a latched topic?) is learned when one comes
            rihs01 = next((str(info.topic_type_hash) for info in infos if info.topic_type_hash), "")
            self._subscribe(topic, msgtype, _qos_for(infos), rihs01)

    def keep_discovering(self, then: Callable[[], None], period: float = DISCOVERY_PERIOD) -> None:
        """:meth:`discover` every ``period`` seconds from now on, on the node's executor, and ``then()``
        after each look (a progress line)."""

        def tick() -> None:
            self.discover()
            then()

        self.node.create_timer(period, tick)

    def expect(self, fleet: str, robot: str) -> None:
        """Subscribe now to every name of this robot, before any publisher is there: a short-lived
        client's introspection (its first goal) is recorded too."""
        action = "/" + action_name(fleet, robot)
        names = {"/" + status_topic(fleet, robot): "status", "/" + begin_topic(fleet, robot): "begin"}
        names.update({action + suffix: channel for suffix, channel in bags.HIDDEN.items()})
        for topic, channel in names.items():
            if topic not in self.topics:
                msgtype = bags.TYPES[channel]
                latched_topic = channel in ("status", "begin", bags.GOAL_STATUS)  # transient-local (R1.4)
                durability = DurabilityPolicy.TRANSIENT_LOCAL if latched_topic else DurabilityPolicy.VOLATILE
                qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=DEPTH,
                                 reliability=ReliabilityPolicy.RELIABLE, durability=durability)  # fmt: skip
                self._subscribe(topic, msgtype, qos, "")

    def _subscribe(self, topic: str, msgtype: str, qos: QoSProfile, rihs01: str) -> None:
        with self._lock:
            self._connections[topic] = self.writer.add_connection(
                topic, msgtype, msgdef=bags.message_definition(msgtype),
                rihs01=rihs01 if rihs01.startswith("RIHS01_") else _UNHASHED,
            )  # fmt: skip
        heard = SubscriptionEventCallbacks(matched=lambda info, topic=topic: self._matched(topic, info))
        self.topics[topic] = self.node.create_subscription(
            _CLASSES[msgtype], topic, lambda data, info, topic=topic: self._write(topic, data, info), qos,
            raw=True, event_callbacks=heard,
        )  # fmt: skip
        self.say(f"recording {topic} ({msgtype})")

    def _matched(self, topic: str, info: Any) -> None:
        """Say when a topic is first heard: its subscription has matched a publisher, whose messages
        are recorded from then on (a subscription made is not yet one matched: DDS discovery between
        two processes can take seconds, and what a volatile topic carried before is not recorded)."""
        if info.current_count > 0 and topic not in self.heard:
            self.heard.add(topic)
            self.say(f"hearing {topic}")

    def _named(self, topic: str) -> bool:
        """Whether ``topic`` is a Dynamic Event name of a robot asked for (the fleet-wide begin topic
        always is: it carries every robot's begins)."""
        found = bags.channel_of(topic)
        return found is not None and (not found.robot or self.wanted(found.fleet, found.robot))

    def _write(self, topic: str, data: bytes, info: Any) -> None:
        # when the middleware received it, not when the executor got to it: a recorder that falls
        # behind (a busy machine) takes messages in bursts, and the bag's order must still be theirs
        now = info.get("received_timestamp") or time.time_ns()
        # and when its publisher sent it (DDS's source timestamp): the bag's publish time, which tells
        # a message a lossy link delivered late from one sent late (dynevent.bags.sent)
        sent = info.get("source_timestamp") or None
        # and its publisher's number for it: a gap in a writer's numbers is a message lost for good
        number = int(info.get("publication_sequence_number") or 0)
        with self._lock:
            connection = self._connections.get(topic)
            if connection is None:  # after close
                return
            self.writer.write_sent(connection, now, sent, data, number)
            self.messages += 1
            self.bytes += len(data)

    def close(self) -> None:
        """Write nothing more; the caller closes the writer."""
        with self._lock:
            self._connections.clear()


def _qos_for(infos: Any) -> QoSProfile:
    """Reliable and transient-local when any publisher offers it (a latched topic: its last messages
    are recorded too), else what the publishers offer; a deep history."""
    transient = any(info.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for info in infos)
    reliable = all(info.qos_profile.reliability == ReliabilityPolicy.RELIABLE for info in infos) and infos
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=DEPTH,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE,
    )
