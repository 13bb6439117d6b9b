"""Compressed rosbag2 recordings, honest and hostile, made by the tests (no binary blob is kept):
bags compressed by rosbags' writer in each of rosbag2's ways, and compressed bombs, a few kilobytes
that unpack to gigabytes, put where a bag's compressed bytes go.

- :func:`zstd_zeros`: a zstd frame of ``size`` zero bytes, written block by block (run-length
  blocks of 128 KiB, four bytes each): 2 GiB in 64 KiB, made at once;
- :func:`lz4_zeros`: an lz4 frame of ``size`` zero bytes (lz4 packs about 250 to one);
- :func:`bag`: a recording of a robot's statuses, compressed as asked;
- :func:`packed_messages`: a bag whose messages are compressed, each given as it is stored;
- :func:`mcap`: an MCAP file of one chunk, its compressed bytes and declared sizes as given.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

from dynevent.bags.reader import message_definition, typestore

STATUS_TOPIC = "/rmf/dynamic_event/status/tinyRobot/r1"
STATUS_TYPE = "rmf_task_msgs/msg/DynamicEventStatus"
SECOND = 10**9
T0 = 1_700_000_000 * SECOND
#: A bomb's size: what the issue's recordings unpacked to.
BOMB = 2**31


def zstd_zeros(size: int) -> bytes:
    """A zstd frame (no declared content size) of ``size`` zero bytes."""
    frame = bytearray(struct.pack("<I", 0xFD2FB528)) + bytes([0x00, 0x38])  # no size; a 128 KiB window
    block = 128 * 1024
    while True:
        count = min(size, block)
        size -= count
        frame += ((size == 0) | (1 << 1) | (count << 3)).to_bytes(3, "little") + b"\0"  # a run of zeros
        if size == 0:
            return bytes(frame)


def lz4_zeros(size: int) -> bytes:
    """An lz4 frame of ``size`` zero bytes, packed a mebibyte at a time."""
    import lz4.frame

    piece = bytes(1024 * 1024)
    with lz4.frame.LZ4FrameCompressor() as packer:
        parts = [packer.begin()]
        while size > 0:
            parts.append(packer.compress(piece[: min(size, len(piece))]))
            size -= len(piece)
        parts.append(packer.flush())
    return b"".join(parts)


def status(seq: int, time: int, text: str = "standby") -> bytes:
    """A robot's status message, serialized as a bag holds it (``text`` its status)."""
    store = typestore()
    message = store.types[STATUS_TYPE](
        dynamic_event_seq=seq,
        dynamic_state=1,
        status=text,
        id=0,
        time=store.types["builtin_interfaces/msg/Time"](sec=time // SECOND, nanosec=time % SECOND),
    )
    data: bytes = store.serialize_cdr(message, STATUS_TYPE)
    return data


def bag(
    path: Path, storage: StoragePlugin, mode: CompressionMode = CompressionMode.NONE, count: int = 3
) -> Path:
    """A recording of ``count`` statuses of one robot, compressed as rosbags compresses in ``mode``
    (``STORAGE``: MCAP's chunks, zstd)."""
    writer = Writer(path, version=9, storage_plugin=storage)
    if mode is not CompressionMode.NONE:
        writer.set_compression(mode, CompressionFormat.ZSTD)
    with writer:
        connection = writer.add_connection(
            STATUS_TOPIC, STATUS_TYPE, msgdef=message_definition(STATUS_TYPE), rihs01="RIHS01_" + "0" * 64
        )
        for number in range(count):
            time = T0 + number * SECOND
            writer.write(connection, time, status(1, time))
    return path


def packed_messages(path: Path, storage: StoragePlugin, packed: list[bytes]) -> Path:
    """A bag whose messages are compressed (``compression_mode: message``, zstd), each given as it is
    stored: one status a message, a second apart."""
    from ruamel.yaml import YAML

    writer = Writer(path, version=9, storage_plugin=storage)
    with writer:
        connection = writer.add_connection(
            STATUS_TOPIC, STATUS_TYPE, msgdef=message_definition(STATUS_TYPE), rihs01="RIHS01_" + "0" * 64
        )
        for number, data in enumerate(packed):
            writer.write(connection, T0 + number * SECOND, data)
    document = metadata(path)
    document["rosbag2_bagfile_information"].update(compression_mode="message", compression_format="zstd")
    with (path / "metadata.yaml").open("w", encoding="utf-8") as stream:
        YAML(typ="safe").dump(document, stream)
    return path


def storage_file(path: Path) -> Path:
    """The bag's one storage file."""
    (found,) = (file for file in path.iterdir() if file.name != "metadata.yaml")
    return found


def _record(opcode: int, body: bytes) -> bytes:
    return struct.pack("<BQ", opcode, len(body)) + body


def _text(value: str) -> bytes:
    data = value.encode()
    return struct.pack("<I", len(data)) + data


def mcap(
    path: Path,
    packed: bytes,
    compression: str,
    declared: int,
    *,
    index: tuple[str, int, int] | None = None,
) -> Path:
    """An MCAP file (profile ros2) with a status channel and one chunk of ``packed`` bytes in
    ``compression`` that declares it unpacks to ``declared``.  With ``index`` (compression, packed
    bytes, unpacked bytes), a summary whose chunk index declares the chunk so; without it, no
    summary (the reader then walks every chunk as it opens the file)."""
    header = _record(0x01, _text("ros2") + _text("dynevent tests"))
    schema = _record(0x03, struct.pack("<H", 1) + _text(STATUS_TYPE) + _text("ros2msg") + _text(""))
    channel = _record(
        0x04, struct.pack("<HH", 1, 1) + _text(STATUS_TOPIC) + _text("cdr") + struct.pack("<I", 0)
    )
    magic = b"\x89MCAP0\r\n"
    chunk_at = len(magic) + len(header) + len(schema) + len(channel)
    chunk = _record(
        0x06,
        struct.pack("<qqQI", T0, T0, declared, 0) + _text(compression) + struct.pack("<Q", len(packed))
        + packed,
    )  # fmt: skip
    data = magic + header + schema + channel + chunk + _record(0x0F, struct.pack("<I", 0))
    summary = b""
    if index is not None:
        named, size, unpacked = index
        offsets = struct.pack("<HQ", 1, len(data))  # where the chunk's message index would be
        summary = schema + channel + _record(
            0x08,
            struct.pack("<qqQQ", T0, T0, chunk_at, len(chunk)) + struct.pack("<I", len(offsets)) + offsets
            + struct.pack("<Q", 0) + _text(named) + struct.pack("<QQ", size, unpacked),
        )  # fmt: skip
    summary_start = len(data) if summary else 0
    footer = _record(0x02, struct.pack("<QQI", summary_start, 0, 0))
    path.write_bytes(data + summary + footer + magic)
    return path


def metadata(path: Path) -> Any:
    """A bag's metadata.yaml, parsed."""
    from ruamel.yaml import YAML

    return YAML(typ="safe").load((path / "metadata.yaml").read_text(encoding="utf-8"))
