"""``dynevent record``: record a live system's Dynamic Event conversations into a rosbag2 bag.

The recorder looks at the ROS 2 graph once a second and subscribes to every
Dynamic Event name it finds for the robots asked for (``--fleet``,
``--robot``; every robot by default): each robot's status and begin topics,
the fleet-wide begin topic, the action's feedback and goal status topics and,
where introspection is on at a server or client, the action's service event
topics (send_goal, get_result, cancel_goal), which carry the goals and their
answers (docs/recordings.md).  Each message is written as it arrives,
serialised as received, with its receive time, into an MCAP bag in the
rosbag2 layout (``metadata.yaml`` beside it), which ``ros2 bag`` and other
rosbag2 readers open and ``dynevent check`` judges.

A progress line (messages, bytes) is shown on a terminal.  Ctrl-C (or
SIGTERM, or ``--seconds``) stops it cleanly: the bag is closed with its index
and metadata, and nothing received is lost.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import attrs
import rclpy
from action_msgs.msg import GoalStatusArray
from action_msgs.srv import CancelGoal
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from dynevent.bags import reader as bags
from dynevent.errors import InvalidName, RecordError
from dynevent.ros import spinning
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.ros.spinning import Spinner, bounded_close, close_down
from dynevent.wire.names import BEGIN_TOPIC, NameKind, action_name, begin_topic, parse_name, status_topic

__all__ = ["RecordOptions", "Recorder", "run"]

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
    every message into ``writer`` (rosbags' rosbag2 writer, open); :meth:`discover` finds new topics."""

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
            _CLASSES[msgtype], topic, lambda data, topic=topic: self._write(topic, data), qos, raw=True,
            event_callbacks=heard,
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
        if topic.lstrip("/") == BEGIN_TOPIC:
            return True
        name = topic
        for suffix in bags.HIDDEN_SUFFIXES:
            if topic.endswith(suffix):
                name = topic[: -len(suffix)]
        try:
            parsed = parse_name(name)
        except InvalidName:
            return False
        if (parsed.kind is NameKind.ACTION) == (name == topic):
            return False  # the action's own name is no topic; a hidden suffix on a topic is no name
        return self.wanted(parsed.fleet, parsed.robot)

    def _write(self, topic: str, data: bytes) -> None:
        now = time.time_ns()
        with self._lock:
            connection = self._connections.get(topic)
            if connection is None:  # after close
                return
            self.writer.write(connection, now, data)
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


@attrs.frozen(kw_only=True)
class RecordOptions:
    """What ``dynevent record`` is asked to do, its flags read and checked by the command line."""

    output: str | None = None  # the bag's directory; by default dynevent_<date>-<time>
    fleets: tuple[str, ...] = ()  # the fleets recorded (every fleet when none)
    robots: tuple[str, ...] = ()  # the robots recorded (every robot when none)
    seconds: float | None = None  # stop after this long (by default at Ctrl-C or SIGTERM)
    ros_args: tuple[str, ...] = ()  # ROS 2's own command-line arguments (``--ros-args ...``)


def run(args: RecordOptions, say: Callable[[str], None]) -> int:
    """Record until SIGINT, SIGTERM or ``--seconds``; 0, or 2 when the bag cannot be written."""
    try:
        from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
    except ImportError:
        from dynevent.errors import MissingExtra

        raise MissingExtra("bags", "rosbags", "writes rosbag2 recordings") from None
    output = Path(args.output or time.strftime("dynevent_%Y_%m_%d-%H_%M_%S"))
    if os.path.lexists(output):  # lexists: a path too long to stat is for the writer to name
        raise RecordError(f"--output {output}: exists already (a bag is a new directory)")
    fleets, robots = set(args.fleets), set(args.robots)

    def wanted(fleet: str, robot: str) -> bool:
        return (not fleets or fleet in fleets) and (not robots or robot in robots)

    try:
        writer = Writer(output, version=9, storage_plugin=StoragePlugin.MCAP)
        writer.open()
    except (OSError, WriterError) as exc:
        raise RecordError(f"--output {output}: cannot write: {exc}") from None
    spinning.init(args.ros_args)
    node = rclpy.create_node("dynevent_record")
    live = sys.stdout.isatty()

    def line(text: str) -> None:
        say(f"\r\033[K{text}" if live else text)

    recorder = Recorder(node, writer, wanted, line)

    def tick() -> None:
        recorder.discover()
        if live:
            sys.stdout.write(f"\r\033[Krecording {output}: {len(recorder.topics)} topics, "
                             f"{recorder.messages:,} messages, {recorder.bytes:,} bytes")  # fmt: skip
            sys.stdout.flush()

    timer = node.create_timer(DISCOVERY_PERIOD, tick)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = Spinner(executor, "dynevent-record")
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    for fleet in sorted(fleets) if robots else ():  # robots named in full: their names are known now
        for robot in sorted(robots):
            recorder.expect(fleet, robot)
    recorder.discover()
    spinner.start()
    say(f"recording into {output} (Ctrl-C to stop)")
    try:
        stop.wait(args.seconds)
    finally:
        # the bag is closed (its index and metadata.yaml written) before anything that could hang
        spinner.stop()
        recorder.close()  # a write in progress ends first; none follows
        writer.close()
        with bounded_close():
            node.destroy_timer(timer)
            close_down([node])
        if live:
            sys.stdout.write("\r\033[K")
    say(f"recorded {recorder.messages} messages ({recorder.bytes} bytes) on {len(recorder.topics)} topics "
        f"into {output}")  # fmt: skip
    return 0
