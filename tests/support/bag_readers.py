"""Readers of a rosbag2 recording other than ``dynevent check``'s, which take each message's type
from the definitions the bag itself holds (``message_definition``), as a tool that has never seen
the protocol's interface files does.

- rosbags with an empty type store: every type from the bag's ``ros2msg`` texts alone;
- Foxglove's ROS 2 decoder (``mcap`` with ``mcap-ros2-support``), which parses the texts with ROS's
  own parser (rosidl_adapter).  That parser takes only ``.msg`` names (no ``_``): the types an
  action derives (``DynamicEvent_FeedbackMessage``, the service events) are beyond any ``ros2msg``
  text, rosbag2's own included, so it reads the status, begin and goal status topics.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any


def read_with_rosbags(bag: Path) -> dict[str, list[Any]]:
    """Each topic's messages, decoded by rosbags from the bag's own message definitions alone."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    messages: dict[str, list[Any]] = {}
    with Reader(bag) as reader:
        for connection in reader.connections:
            store = get_typestore(Stores.EMPTY)
            store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
            decoded = messages.setdefault(connection.topic, [])
            for _, _, raw in reader.messages(connections=[connection]):
                decoded.append(store.deserialize_cdr(raw, connection.msgtype))
    return messages


def read_with_foxglove(bag: Path) -> tuple[dict[str, list[Any]], Counter[str]]:
    """The messages of each topic whose type ROS's parser names, decoded by Foxglove's ROS 2 decoder
    from the bag's own message definitions; and how many messages of each other topic it skipped."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    messages: dict[str, list[Any]] = {}
    skipped: Counter[str] = Counter()
    for path in sorted(bag.glob("*.mcap")):
        with path.open("rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            assert summary is not None, f"{path}: no summary (the bag was not closed)"
            readable = [
                channel.topic
                for channel in summary.channels.values()
                if "_" not in summary.schemas[channel.schema_id].name.rsplit("/", 1)[-1]
            ]
            for channel in summary.channels.values():
                if channel.topic not in readable:
                    skipped[channel.topic] += summary.statistics.channel_message_counts.get(channel.id, 0)
            for _, channel, _, decoded in reader.iter_decoded_messages(topics=readable):
                messages.setdefault(channel.topic, []).append(decoded)
    return messages, skipped
