"""When each message of a bag was sent: MCAP's publish time, written by ``dynevent record`` and read
by ``dynevent check``.

An MCAP message record holds two times: its log time, when the recorder received the message, and its
publish time, when its publisher sent it (DDS's source timestamp, on the publisher's clock).  A
recorder on a lossy link receives a lost message when the publisher sends it again, seconds later,
after messages the publisher sent after it; only the publish time tells a feedback delivered late
from one sent late.  ``dynevent record`` writes the source timestamp rclpy gives each message as its
publish time (:func:`open_writer`); :func:`publish_times` reads them back where they differ from the log
time (a writer that knows no publish time writes the log time twice, as rosbags' own writer does).

A message record holds a sequence number too: ``dynevent record`` writes there the publisher's
publication sequence number (DDS numbers each message a writer sends, one by one), so that a gap in
a writer's numbers shows a message lost on the way for good, and says so in the bag's metadata
(:data:`SEQUENCE_KEY` in ``custom_data``): another recorder's sequence (a counter of its own, or 0)
is not read as one.
"""

from __future__ import annotations

import contextlib
import io
import struct
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple

from dynevent.bags import unpack

__all__ = ["SEQUENCE_KEY", "SEQUENCE_VALUE", "Sent", "open_writer", "publish_times"]

#: The key of a bag's ``custom_data`` whose value :data:`SEQUENCE_VALUE` says its MCAP message
#: records' sequence is the publisher's publication sequence number (``dynevent record``'s bags).
SEQUENCE_KEY = "dynevent.mcap_sequence"
SEQUENCE_VALUE = "publication_sequence_number"

#: The opcodes read here (the MCAP specification): a channel, a message, a chunk.
_CHANNEL, _MESSAGE, _CHUNK = 0x04, 0x05, 0x06
#: A message record's fields before its data: channel id, sequence, log time, publish time.
_MESSAGE_HEAD = struct.Struct("<HIQQ")
#: Where the sequence and the publish time sit in a message record, counted from its opcode.
_SEQUENCE_AT = 1 + 8 + 2
_PUBLISH_AT = _SEQUENCE_AT + 4 + 8


class Sent(NamedTuple):
    """What a bag says of one message's sending: when (ns, None where the bag does not say) and the
    publisher's number for it (0 where the bag does not say)."""

    time: int | None
    number: int


def open_writer(path: Path) -> Any:
    """A rosbags rosbag2 writer at ``path`` (version 9, MCAP storage; made, not opened) whose
    ``write_sent`` writes a message with its publish time beside its log time, and its publication
    sequence number as the record's sequence (:data:`SEQUENCE_KEY`)."""
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Rosbag2Writer
    from rosbags.rosbag2.storage_mcap import McapWriter

    class _McapWriter(McapWriter):  # type: ignore[misc]
        """rosbags' MCAP storage, with the publish time of the message being written put in its
        record before its chunk can be closed."""

        def __init__(self, *args: Any) -> None:
            super().__init__(*args)
            self.sent: int | None = None
            self.number = 0
            self._writing = self._due = False

        def write(self, connection: Any, timestamp: int, data: Any) -> None:
            chunk = getattr(self, "chunk", None)
            bio = getattr(chunk, "bio", None)
            if self.sent is None or not isinstance(bio, io.BytesIO):
                super().write(connection, timestamp, data)
                return
            at = bio.tell()
            self._writing = True
            try:
                super().write(connection, timestamp, data)
            finally:
                self._writing = False
            if bio.tell() > at and bio.getbuffer()[at] == _MESSAGE:
                bio.seek(at + _SEQUENCE_AT)
                bio.write(struct.pack("<I", self.number & 0xFFFFFFFF))
                bio.seek(at + _PUBLISH_AT)
                bio.write(struct.pack("<Q", self.sent))
                bio.seek(0, io.SEEK_END)
            if self._due:
                self._due = False
                super().close_chunk()

        def close_chunk(self) -> None:
            if self._writing:  # closed once the publish time is in
                self._due = True
            else:
                super().close_chunk()

    class _Writer(Rosbag2Writer):  # type: ignore[misc]
        STORAGE_PLUGINS = {**Rosbag2Writer.STORAGE_PLUGINS, StoragePlugin.MCAP: _McapWriter}

        def write_sent(
            self, connection: Any, timestamp: int, sent: int | None, data: bytes, number: int = 0
        ) -> None:
            """Write ``data`` received at ``timestamp``, sent at ``sent`` (ns; None: not known), the
            publisher's ``number``-th message (0: not known)."""
            storage = self.storage
            if isinstance(storage, _McapWriter):
                storage.sent, storage.number = (timestamp if sent is None else sent), number
            try:
                self.write(connection, timestamp, data)
            finally:
                if isinstance(storage, _McapWriter):
                    storage.sent, storage.number = None, 0

    writer = _Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_custom_data(SEQUENCE_KEY, SEQUENCE_VALUE)
    return writer


def publish_times(
    source: str, paths: Iterable[Path], *, numbered: bool = False
) -> dict[tuple[str, int, int], Sent]:
    """When each message of the MCAP files at ``paths`` was sent, where its publish time is not its log
    time (else None), and, ``numbered`` (the bag's metadata says so: :data:`SEQUENCE_KEY`), its
    publication number, where not 0: by (topic, log time, hash of its data as stored), each message
    that has either; a file that is not MCAP gives none,
    and one that breaks off or declares what it does not hold gives what came before (the storage
    library says what is wrong with it).  Its chunks were vetted before
    (:func:`dynevent.bags.unpack.vet_mcap`); each is unpacked here within the bound of one chunk."""
    found: dict[tuple[str, int, int], Sent] = {}
    for path in paths:
        if path.suffix != ".mcap":
            continue
        with path.open("rb") as stream:
            if stream.read(len(unpack.MAGIC)) != unpack.MAGIC:
                continue
            stream.seek(0, io.SEEK_END)
            size = stream.tell()
            topics: dict[int, str] = {}
            for body in _bodies(source, _walk(stream, len(unpack.MAGIC), size), topics):
                channel, sequence, logged, published = _MESSAGE_HEAD.unpack_from(body)
                number = sequence if numbered else 0
                if (published != logged or number) and channel in topics:
                    key = (topics[channel], logged, hash(bytes(body[_MESSAGE_HEAD.size :])))
                    found[key] = Sent(published if published != logged else None, number)
    return found


def _bodies(
    source: str, records: Iterator[tuple[int, memoryview]], topics: dict[int, str]
) -> Iterator[memoryview]:
    """The body of each message record of ``records``, inside chunks or out; each channel record's
    topic put in ``topics`` on the way."""
    for opcode, body in records:
        if opcode == _CHANNEL and len(body) >= 8:  # its id, its schema's id, its topic
            channel, _, named = struct.unpack_from("<HHI", body)
            if 8 + named <= len(body):
                topics[channel] = bytes(body[8 : 8 + named]).decode("utf-8", "replace")
        elif opcode == _MESSAGE and len(body) >= _MESSAGE_HEAD.size:
            yield body
        elif opcode == _CHUNK:
            held = _chunk_records(source, body)
            if held is not None:
                yield from _bodies(source, _walk(io.BytesIO(held), 0, len(held)), topics)


def _walk(stream: BinaryIO, start: int, size: int) -> Iterator[tuple[int, memoryview]]:
    """(opcode, body) of each record from ``start`` of the ``size`` bytes of ``stream``, until one
    does not fit."""
    offset = start
    while offset + 9 <= size:
        stream.seek(offset)
        opcode, length = struct.unpack("<BQ", stream.read(9))
        if length > size - offset - 9:
            return
        yield opcode, memoryview(stream.read(length))
        offset += 9 + length


def _chunk_records(source: str, body: memoryview) -> bytes | None:
    """What a chunk record holds, unpacked within the bound of one chunk (None: a chunk that declares
    what it does not hold, or a compression this does not know, which the storage library refuses)."""
    if len(body) < 32:
        return None
    _, _, unpacked, _, named = struct.unpack_from("<qqQII", body)
    if 32 + named + 8 > len(body):
        return None
    compression = bytes(body[32 : 32 + named]).decode("utf-8", "replace")
    (packed,) = struct.unpack_from("<Q", body, 32 + named)
    records = body[32 + named + 8 :]
    if packed != len(records):
        return None
    if not compression:
        return bytes(records)
    if compression not in ("zstd", "lz4") or unpacked > unpack.MAX_UNPACKED_BYTES:
        return None
    with contextlib.closing(io.BytesIO(bytes(records))) as stream:
        return b"".join(unpack.pieces(source, stream, compression, unpacked, "an MCAP chunk"))
