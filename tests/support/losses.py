"""Messages a lossy link can lose for good, and a recording without them.

A reliable DDS writer sends a lost message again until the reader has it, while the message is still
in the writer's history: it is lost for good only when the writer let it go first, having sent as many
newer messages as its history keeps (:func:`kept`), or when the recording stopped before it came.
:func:`losable` takes that model, with a message's own writer told by its topic and, for a service's
introspection events, by the side that sent it (the server's request-received and response-sent
events, or a client's request-sent and response-received ones): a message is losable when its
writer sent ``kept`` newer ones within :data:`REPAIR` seconds after it, or when it was received within
:data:`REPAIR` of the recording's end.  :func:`without` writes a recording with some left out, every
other message as it was (its log time, publish time and publication number).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import attrs
from mcap.reader import make_reader
from mcap.writer import Writer

from dynevent.bags.reader import _stored_name, typestore
from dynevent.wire.names import (
    BEGIN_TOPIC,
    BEGIN_TOPIC_DEPTH,
    EVENTS_KEPT,
    ROBOT_BEGIN_TOPIC_DEPTH,
    STATUS_TOPIC_DEPTH,
)

#: How long a lossy link may take to repair a lost message (seconds): one let go later than this
#: after it was sent was sent again before (at 30% loss across hosts, most repairs take under 3 s).
REPAIR = 5.0
#: The feedback topic's history (rclpy's action server: the default QoS, 10).
FEEDBACK_KEPT = 10
#: The action's goal status topic's history (rcl_action: 1, transient-local).
GOAL_STATUS_KEPT = 1

_STORE = typestore()


@attrs.frozen
class Message:
    """One message of a recording, as the MCAP file holds it."""

    topic: str
    writer: str  # the topic, and for introspection events the side that sent them
    log_time: int
    publish_time: int
    schema: Any
    channel: Any
    record: Any


def kept(topic: str) -> int:
    """How many messages the writer of ``topic`` keeps to send again."""
    if topic.endswith("/_action/feedback"):
        return FEEDBACK_KEPT
    if topic.endswith("/_action/status"):
        return GOAL_STATUS_KEPT
    if topic.endswith("/_service_event"):
        return EVENTS_KEPT
    if topic.startswith(f"/{BEGIN_TOPIC}/"):
        return ROBOT_BEGIN_TOPIC_DEPTH
    if topic == f"/{BEGIN_TOPIC}":
        return BEGIN_TOPIC_DEPTH
    return STATUS_TOPIC_DEPTH


def read(bag: Path) -> list[Message]:
    """The messages of the recording in ``bag`` (a folder holding one MCAP file), in file order."""
    (path,) = bag.glob("*.mcap")
    messages = []
    with path.open("rb") as file:
        for schema, channel, record in make_reader(file).iter_messages(log_time_order=False):
            writer = channel.topic
            if writer.endswith("/_service_event"):
                event = _STORE.deserialize_cdr(record.data, _stored_name(_STORE, schema.name))
                writer += " server" if int(event.info.event_type) in (1, 2) else " client"
            messages.append(
                Message(channel.topic, writer, record.log_time, record.publish_time, schema, channel, record)
            )
    return messages


def losable(messages: list[Message]) -> list[Message]:
    """The Dynamic Event messages a lossy link could have lost for good (see the module docs)."""
    end = max(message.log_time for message in messages)
    repair = round(REPAIR * 1e9)
    found = []
    for message in messages:
        if "/dynamic_event/" not in message.topic:
            continue
        newer = sum(
            1
            for other in messages
            if other.writer == message.writer
            and message.publish_time < other.publish_time <= message.publish_time + repair
        )
        if newer >= kept(message.topic) or message.log_time >= end - repair:
            found.append(message)
    return found


def without(bag: Path, messages: list[Message], left_out: set[int], target: Path) -> Path:
    """A copy of the recording ``bag`` (its ``messages``, :func:`read`) in folder ``target``, without
    the messages whose log times are ``left_out``; its metadata is the original's."""
    (path,) = bag.glob("*.mcap")
    with path.open("rb") as file:
        reader = make_reader(file)
        header = reader.get_header()
        metadata = list(reader.iter_metadata())
    target.mkdir(parents=True, exist_ok=True)
    shutil.copy(bag / "metadata.yaml", target / "metadata.yaml")
    with (target / path.name).open("wb") as file:
        writer = Writer(file)
        writer.start(profile=header.profile, library=header.library)
        for item in metadata:
            writer.add_metadata(item.name, item.metadata)
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for message in messages:
            schema, channel, record = message.schema, message.channel, message.record
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas.get(channel.schema_id, 0),
                    channel.metadata,
                )
            if message.log_time in left_out:
                continue
            writer.add_message(
                channels[channel.id], record.log_time, record.data, record.publish_time, record.sequence
            )
        writer.finish()
    return target
