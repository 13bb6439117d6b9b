"""Conversions between dynevent's mirrors and the rosidl message classes of ``rmf_task_msgs``.

Incoming messages go through the mirrors' checks: a goal that a mirror
refuses raises :class:`~dynevent.errors.MalformedMessage` (an ``InvalidMessage``
that is the sender's fault) naming the field and the value, which the server
turns into a refusal instead of a traceback in a callback.  Outgoing messages
are built field by field from checked mirrors.
"""

from __future__ import annotations

import functools
from typing import Any

from builtin_interfaces.msg import Time as RosTime
from rmf_task_msgs.action import DynamicEvent
from rmf_task_msgs.msg import DynamicEventDescription as RosDescription
from rmf_task_msgs.msg import DynamicEventStatus as RosStatus
from rmf_task_msgs.msg import LogEntry as RosLogEntry
from unique_identifier_msgs.msg import UUID as RosUUID

from dynevent.conformance.received import (
    begin_from_ros,
    feedback_from_ros,
    goal_from_ros,
    result_from_ros,
    status_from_ros,
    uuid_from_ros,
)
from dynevent.server.inputs import goal_uuid
from dynevent.wire.messages import (
    DynamicEventDescription,
    DynamicEventStatus,
    Feedback,
    Goal,
    LogEntry,
    Result,
    Time,
)

__all__ = ["DynamicEvent", "RosDescription", "RosStatus", "begin_from_ros", "begin_to_ros",
    "describe_type", "feedback_from_ros", "feedback_to_ros", "goal_from_ros", "goal_to_ros",
    "log_entry_to_ros", "quiet_uuid", "result_from_ros", "result_to_ros", "status_from_ros",
    "status_to_ros", "time_to_ros", "uuid_from_ros", "uuid_to_ros"]  # fmt: skip


def describe_type() -> Any | None:
    """The description query's service type (R16), ``rmf_task_msgs/srv/DescribeDynamicEvent``, or
    None where the installed ``rmf_task_msgs`` has none (the deployed one has none: D17)."""
    try:
        from rmf_task_msgs.srv import DescribeDynamicEvent
    except ImportError:
        return None
    return DescribeDynamicEvent


def quiet_uuid(message: Any) -> Any:
    """``message`` (a ``unique_identifier_msgs/UUID``), its ``uuid`` viewed as an array that formats as
    32 hex digits: rclpy's action server formats a goal's UUID into five debug messages, logged or not,
    26 µs each for numpy (docs/performance.md).  The class has the name rosidl's C conversion asserts."""
    array = getattr(message, "_uuid", None)
    if array is not None and type(array).__name__ == "ndarray":
        message._uuid = array.view(_hex_array())
    return message


@functools.cache
def _hex_array() -> type:
    import numpy

    return type("numpy.ndarray", (numpy.ndarray,), {"__format__": lambda self, spec: bytes(self).hex()})


def uuid_to_ros(value: str) -> Any:
    """The ``unique_identifier_msgs/UUID`` of a goal UUID written as 32 hex digits."""
    return RosUUID(uuid=list(bytes.fromhex(goal_uuid(value))))


def time_to_ros(time: Time) -> Any:
    """A ``builtin_interfaces/Time``."""
    return RosTime(sec=time.sec, nanosec=time.nanosec)


def goal_to_ros(goal: Goal) -> Any:
    """A ``DynamicEvent.Goal``."""
    return DynamicEvent.Goal(
        dynamic_event_seq=goal.dynamic_event_seq,
        event_type=goal.event_type,
        category=goal.category,
        description=goal.description,
        id=goal.id,
        stubborn_period=goal.stubborn_period,
    )


def result_to_ros(result: Result) -> Any:
    """A ``DynamicEvent.Result``."""
    return DynamicEvent.Result(execution_failure=result.execution_failure, status=result.status, id=result.id)


def log_entry_to_ros(entry: LogEntry) -> Any:
    """A ``rmf_task_msgs/LogEntry``."""
    return RosLogEntry(
        seq=entry.seq, tier=entry.tier, unix_millis_time=entry.unix_millis_time, text=entry.text
    )


def feedback_to_ros(feedback: Feedback) -> Any:
    """A ``DynamicEvent.Feedback`` with its log entries."""
    return DynamicEvent.Feedback(
        status=feedback.status, id=feedback.id, logs=[log_entry_to_ros(entry) for entry in feedback.logs]
    )


def status_to_ros(status: DynamicEventStatus) -> Any:
    """A ``rmf_task_msgs/DynamicEventStatus``."""
    return RosStatus(
        dynamic_event_seq=status.dynamic_event_seq,
        dynamic_state=status.dynamic_state,
        status=status.status,
        id=status.id,
        time=time_to_ros(status.time),
    )


def begin_to_ros(begin: DynamicEventDescription) -> Any:
    """A ``rmf_task_msgs/DynamicEventDescription``."""
    return RosDescription(
        fleet=begin.fleet,
        robot=begin.robot,
        dynamic_event_seq=begin.dynamic_event_seq,
        description=begin.description,
        start_time=time_to_ros(begin.start_time),
    )
