"""The mirrors of received messages, from any object with the ROS field names: rclpy's message
objects (:mod:`dynevent.ros.convert`), or a bag reader's (:mod:`dynevent.bags.reader`).

A value a mirror refuses is the sender's fault: :class:`~dynevent.errors.MalformedMessage` (an
``InvalidMessage``) naming the field and the value.  Nothing here imports ROS.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

from dynevent.errors import InvalidMessage, MalformedMessage
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

__all__ = [
    "begin_from_ros",
    "feedback_from_ros",
    "goal_from_ros",
    "result_from_ros",
    "status_from_ros",
    "time_from_ros",
    "uuid_from_ros",
]

_F = TypeVar("_F", bound=Callable[..., Any])


def _received(convert: _F) -> _F:
    """A conversion of a message received: a value the mirror refuses is the sender's fault
    (:class:`~dynevent.errors.MalformedMessage`), not a misuse of dynevent here."""

    @functools.wraps(convert)
    def received(*args: Any) -> Any:
        try:
            return convert(*args)
        except MalformedMessage:
            raise
        except InvalidMessage as exc:
            raise MalformedMessage.of(exc) from None

    return received  # type: ignore[return-value]


@_received
def uuid_from_ros(value: Any) -> str:
    """A goal UUID (``unique_identifier_msgs/UUID`` or its 16 uint8 values) as 32 hex digits."""
    raw = getattr(value, "uuid", value)
    try:
        return goal_uuid(bytes(bytearray(raw)))
    except (TypeError, ValueError) as exc:
        raise MalformedMessage("UUID", "uuid", raw, str(exc)) from None


@_received
def time_from_ros(message: Any) -> Time:
    """A ``builtin_interfaces/Time``."""
    return Time(sec=message.sec, nanosec=message.nanosec)


@_received
def goal_from_ros(message: Any) -> Goal:
    """The mirror of a received goal; raises :class:`InvalidMessage` for a value the mirror refuses."""
    return Goal(
        dynamic_event_seq=message.dynamic_event_seq,
        event_type=message.event_type,
        category=message.category,
        description=message.description,
        id=message.id,
        stubborn_period=float(message.stubborn_period),
    )


@_received
def result_from_ros(message: Any) -> Result:
    """The mirror of a received result."""
    return Result(execution_failure=message.execution_failure, status=message.status, id=message.id)


@_received
def feedback_from_ros(message: Any) -> Feedback:
    """The mirror of received feedback."""
    logs = tuple(
        LogEntry(seq=entry.seq, tier=entry.tier, unix_millis_time=entry.unix_millis_time, text=entry.text)
        for entry in message.logs
    )
    return Feedback(status=message.status, id=message.id, logs=logs)


@_received
def status_from_ros(message: Any) -> DynamicEventStatus:
    """The mirror of a received status message."""
    return DynamicEventStatus(
        dynamic_event_seq=message.dynamic_event_seq,
        dynamic_state=message.dynamic_state,
        status=message.status,
        id=message.id,
        time=time_from_ros(message.time),
    )


@_received
def begin_from_ros(message: Any) -> DynamicEventDescription:
    """The mirror of a received begin message."""
    return DynamicEventDescription(
        fleet=message.fleet,
        robot=message.robot,
        dynamic_event_seq=message.dynamic_event_seq,
        description=message.description,
        start_time=time_from_ros(message.start_time),
    )
