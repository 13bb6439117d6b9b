"""Compressed recordings, unpacked within bounds before any reader unpacks them.

rosbag2 compresses in two ways, each with zstd: a whole storage file (``compression_mode: file``,
``x.mcap.zstd``) or each message (``compression_mode: message``); and an MCAP file compresses its
chunks (zstd or lz4) whatever the bag's mode.  A few kilobytes of zstd unpack to gigabytes, so a
recording from a stranger is unpacked here, piece by piece, against stated limits, and the sizes it
declares are checked against each other, before anything holds what it unpacks to:

- a chunk or a message unpacks to at most :data:`MAX_UNPACKED_BYTES` (a reader holds it whole);
- a whole bag, its storage files, chunks and messages together, unpacks to at most
  :data:`MAX_EXPANSION` times the bytes it stores (and to :data:`MAX_UNPACKED_BYTES` whatever its
  size), so that reading a compressed bag costs what reading an uncompressed bag of that many bytes
  does, and no more;
- an MCAP chunk unpacks to exactly the size it declares, its compressed bytes fill its record, and
  each chunk index in the summary (where the reader finds the chunks it unpacks) declares the very
  chunk the file holds at its offset.

:func:`readable` gives the storage library (rosbags) a bag it unpacks nothing of but the chunks
vetted here: a file-compressed storage file unpacked here, within bounds, into a temporary bag; a
message-compressed bag read as stored, each message then unpacked by :func:`unpack_message`.  A
bag over a bound is one :class:`~dynevent.errors.BagError` line.
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import struct
import tempfile
from collections.abc import Iterator
from pathlib import Path, PurePath
from typing import Any, BinaryIO, NamedTuple

from dynevent.errors import BagError

__all__ = [
    "MAGIC",
    "MAX_EXPANSION",
    "MAX_UNPACKED_BYTES",
    "Budget",
    "Readable",
    "pieces",
    "readable",
    "unpack_message",
    "vet_mcap",
]

#: The most bytes one MCAP chunk or one message unpacks to: a reader holds it whole (a chunk is
#: 768 KiB in rosbag2's MCAP by default, or one message larger than that, a camera's image say).
MAX_UNPACKED_BYTES = 64 * 1024 * 1024
#: A bag unpacks to at most this many times the bytes it stores (the recordings of the field
#: compress five to one; a bag of a map that is mostly unknown, more): beyond it, a bomb.
MAX_EXPANSION = 100
_BOMB = "a compressed bomb, not a recording"
#: How much is unpacked at a time: no more than this is held of what a bomb unpacks to.
_PIECE = 1024 * 1024

#: MCAP's magic, and the opcodes read here (the MCAP specification, as rosbags reads them).
MAGIC = b"\x89MCAP0\r\n"
_FOOTER, _CHUNK, _CHUNK_INDEX, _SUMMARY_OFFSET = 0x02, 0x06, 0x08, 0x0E
#: The footer record (opcode, length 20, summary start, summary offset start, CRC), then the magic.
_FOOTER_HEAD = struct.pack("<BQ", _FOOTER, 20)
_TAIL = len(_FOOTER_HEAD) + 20 + len(MAGIC)


class Budget:
    """What one bag may still unpack to: :data:`MAX_EXPANSION` times the ``stored`` bytes, and at
    least :data:`MAX_UNPACKED_BYTES`."""

    def __init__(self, source: str, stored: int) -> None:
        self.source = source
        self.left = max(MAX_UNPACKED_BYTES, MAX_EXPANSION * stored)
        self.limit = self.left

    def take(self, count: int, what: str) -> None:
        """Spend ``count`` unpacked bytes of ``what``; a :class:`BagError` past the bag's bound."""
        if count > self.left:
            raise BagError(
                self.source,
                f"{what} unpacks past the bag's bound, {self.limit:,} bytes ({MAX_EXPANSION} times "
                f"what it stores): {_BOMB}",
            )
        self.left -= count


@functools.cache
def _zstd() -> Any:
    """The zstd module of PEP 784 (Python 3.14's, or its backport, which rosbags unpacks with), or
    None where rosbags (before 0.11) unpacks with zstandard."""
    try:
        from compression import zstd  # type: ignore[import-not-found,unused-ignore]
    except ImportError:
        try:
            from backports import zstd  # type: ignore[import-not-found,no-redef,unused-ignore]
        except ImportError:
            return None
    return zstd


def _unpacking(stream: BinaryIO, compression: str) -> BinaryIO:
    """A reader of what ``stream`` unpacks to (``compression``: ``zstd`` or ``lz4``), read across
    frames as the storage library reads it; the decompressors come with rosbags."""
    reader: BinaryIO
    if compression == "lz4":
        import lz4.frame

        reader = lz4.frame.open(stream, "rb")
    elif (zstd := _zstd()) is not None:
        reader = zstd.open(stream, "rb")
    else:
        import zstandard

        reader = zstandard.ZstdDecompressor().stream_reader(stream, read_across_frames=True)
    return reader


def pieces(source: str, stream: BinaryIO, compression: str, limit: int, what: str) -> Iterator[bytes]:
    """What ``stream`` unpacks to, piece by piece; a :class:`BagError` once it passes ``limit`` bytes
    (nothing past the limit is unpacked) or when it is not what ``compression`` says."""
    unpacked = 0
    try:
        with _unpacking(stream, compression) as reader:
            while piece := reader.read(min(_PIECE, limit - unpacked + 1)):
                unpacked += len(piece)
                if unpacked > limit:
                    raise BagError(source, f"{what} unpacks to more than {limit:,} bytes: {_BOMB}")
                yield piece
    except (BagError, GeneratorExit):
        raise
    except Exception as exc:  # each decompressor's own: a corrupt or truncated frame
        problem = " ".join(str(exc).split()) or type(exc).__name__
        raise BagError(source, f"{what}: cannot be unpacked ({compression}): {problem}") from None


def unpack_message(source: str, data: bytes, what: str, budget: Budget) -> bytes:
    """One message of a bag whose messages are compressed (zstd), unpacked within bounds."""
    zstd = _zstd()
    if zstd is not None:  # a message of up to a piece, at once: as fast as the library unpacks it
        decompressor = zstd.ZstdDecompressor()
        with contextlib.suppress(zstd.ZstdError):  # said by the pieces below
            unpacked: bytes = decompressor.decompress(data, _PIECE)
            if decompressor.eof and not decompressor.unused_data:
                budget.take(len(unpacked), what)
                return unpacked
    # a larger message, frames after the first, a frame that breaks off: piece by piece
    unpacked = b"".join(pieces(source, io.BytesIO(data), "zstd", MAX_UNPACKED_BYTES, what))
    budget.take(len(unpacked), what)
    return unpacked


@contextlib.contextmanager
def readable(source: str, path: Path, metadata: Any) -> Iterator[Readable]:
    """The bag at ``path`` (``metadata``: its metadata.yaml, parsed; None for a storage file alone) as
    the storage library may read it, every chunk it will unpack vetted; for a bag whose messages are
    compressed, the budget :func:`unpack_message` unpacks them within (None: they are not); and its
    MCAP files, each vetted."""
    information = metadata.get("rosbag2_bagfile_information") if isinstance(metadata, dict) else None
    if not isinstance(information, dict):  # a storage file alone, or a bag the library refuses
        if path.suffix == ".mcap" and path.is_file():
            vet_mcap(source, path, Budget(source, path.stat().st_size))
            yield Readable(path, None, (path,))
            return
        yield Readable(path, None, ())
        return
    names = information.get("relative_file_paths")
    names = names if isinstance(names, list) else []
    stored = [path / PurePath(name).name for name in names if isinstance(name, str)]
    mode = str(information.get("compression_mode") or "").lower()
    packed = mode in ("file", "message") and information.get("compression_format") == "zstd"
    mcap = information.get("storage_identifier") == "mcap"
    if not all(os.path.isfile(file) for file in stored):  # the library names the files missing
        yield Readable(path, None, ())
        return
    budget = Budget(source, sum(file.stat().st_size for file in stored))
    if not packed:
        for file in stored if mcap else ():
            vet_mcap(source, file, budget)
        yield Readable(path, None, tuple(stored) if mcap else ())
        return
    with tempfile.TemporaryDirectory(prefix="dynevent-bag-") as folder:
        view = Path(folder)
        unpacked = dict(information, compression_mode="", compression_format="")
        targets = []
        for file in stored:
            if mode == "file":  # x.mcap.zstd unpacks to x.mcap, as rosbag2 names it
                target = view / file.stem
                _unpack_file(source, file, target, budget)
            else:
                target = view / file.name
                target.symlink_to(file.resolve())
            if mcap:
                vet_mcap(source, target, budget)
                targets.append(target)
        if mode == "file":
            unpacked["relative_file_paths"] = [
                PurePath(name).stem if isinstance(name, str) else name for name in names
            ]
        _write_metadata(view / "metadata.yaml", dict(metadata, rosbag2_bagfile_information=unpacked))
        yield Readable(view, budget if mode == "message" else None, tuple(targets))


class Readable(NamedTuple):
    """A bag as the storage library may read it (:func:`readable`)."""

    #: the bag (a folder with metadata.yaml, or a storage file alone)
    path: Path
    #: what its compressed messages may still unpack to (None: its messages are not compressed)
    budget: Budget | None
    #: its MCAP storage files, each vetted (MCAP's own records are read there: dynevent.bags.sent)
    mcap: tuple[Path, ...]


def _unpack_file(source: str, packed: Path, target: Path, budget: Budget) -> None:
    """A file-compressed storage file unpacked into ``target``, within the bag's budget."""
    what = f"{packed.name} (compression_mode: file)"
    try:
        with packed.open("rb") as stream, target.open("xb") as out:
            unpacked = 0
            for piece in pieces(source, stream, "zstd", budget.left, what):
                out.write(piece)
                unpacked += len(piece)
    except OSError as exc:
        raise BagError(source, f"{packed.name}: cannot read: {exc.strerror or exc}") from None
    budget.take(unpacked, what)


def _write_metadata(path: Path, document: Any) -> None:
    from ruamel.yaml import YAML

    with path.open("w", encoding="utf-8") as stream:
        YAML(typ="safe").dump(document, stream)


def vet_mcap(source: str, path: Path, budget: Budget) -> None:
    """Every chunk of the MCAP file at ``path`` that rosbags may unpack, unpacked first within
    bounds (counted, not kept): each record of its data section, as the library walks it when the
    file has no summary, and each chunk index of its summary, as the library reads them otherwise.
    A file that is not MCAP, or that breaks off, is left to the library to refuse."""
    with path.open("rb") as stream:
        size = os.fstat(stream.fileno()).st_size
        if size < len(MAGIC) + _TAIL or stream.read(len(MAGIC)) != MAGIC:
            return
        footer_start = size - _TAIL
        stream.seek(footer_start)
        tail = stream.read(_TAIL)
        if not tail.startswith(_FOOTER_HEAD) or not tail.endswith(MAGIC):
            return
        (summary_start,) = struct.unpack_from("<Q", tail, len(_FOOTER_HEAD))
        chunks: dict[int, _Declared] = {}
        for offset, opcode, length in _records(stream, len(MAGIC), summary_start or footer_start, size):
            if opcode == _CHUNK:
                chunks[offset] = _vet_chunk(source, stream, offset, length, budget)
        for offset, opcode, length in _records(stream, summary_start or size, size, size):
            if opcode in (_FOOTER, _SUMMARY_OFFSET):
                break
            if opcode == _CHUNK_INDEX:
                stream.seek(offset + 9)
                _vet_index(source, offset, stream.read(length), chunks)


#: A chunk as its record declares it: (compression, compressed bytes, unpacked bytes).
_Declared = tuple[str, int, int]


def _records(stream: BinaryIO, start: int, end: int, size: int) -> Iterator[tuple[int, int, int]]:
    """(offset, opcode, length) of each record from ``start`` while one begins before ``end``, as the
    library walks them (a record may run past ``end``, not past the file's ``size``)."""
    offset = start
    while offset < end and offset + 9 <= size:
        stream.seek(offset)
        opcode, length = struct.unpack("<BQ", stream.read(9))
        if length > size - offset - 9:
            return  # a record that breaks off: the library says so
        yield offset, opcode, length
        offset += 9 + length


def _vet_chunk(source: str, stream: BinaryIO, offset: int, length: int, budget: Budget) -> _Declared:
    """A chunk record's declared sizes checked against each other and against the bounds, then its
    records unpacked (counted) to see that they unpack to what it declares."""
    what = f"the MCAP chunk at offset {offset}"
    end = offset + 9 + length
    stream.seek(offset + 9)
    head = stream.read(32)
    if len(head) < 32:
        raise BagError(source, f"{what}: a record of {length} bytes is too short for a chunk's header")
    _, _, unpacked, _, named = struct.unpack("<qqQII", head)
    records_at = offset + 9 + 32 + named + 8
    if records_at > end:
        raise BagError(source, f"{what}: its compression's name does not fit its record")
    compression = stream.read(named).decode("utf-8", "replace")
    (packed,) = struct.unpack("<Q", stream.read(8))
    if records_at + packed != end:
        raise BagError(
            source, f"{what} declares {packed:,} compressed bytes in a record that holds {end - records_at:,}"
        )
    if compression not in ("zstd", "lz4"):
        return compression, packed, unpacked  # stored as it is (or a compression the library refuses)
    if unpacked > MAX_UNPACKED_BYTES:
        raise BagError(
            source,
            f"{what} declares {unpacked:,} bytes unpacked, more than {MAX_UNPACKED_BYTES:,}: {_BOMB}",
        )
    budget.take(unpacked, what)
    unpacking = pieces(source, io.BytesIO(stream.read(packed)), compression, unpacked, what)
    found = sum(len(piece) for piece in unpacking)
    if found != unpacked:
        raise BagError(source, f"{what} unpacks to {found:,} bytes, not the {unpacked:,} it declares")
    return compression, packed, unpacked


def _vet_index(source: str, offset: int, body: bytes, chunks: dict[int, _Declared]) -> None:
    """A chunk index of the summary names a chunk vetted by :func:`_vet_chunk`, declared alike: the
    library unpacks what the index declares."""
    declared, at = _chunk_index(body)
    if declared is not None and chunks.get(at) != declared:
        compression, packed, unpacked = declared
        raise BagError(
            source,
            f"the MCAP chunk index at offset {offset} declares a chunk of {packed:,} bytes "
            f"({compression or 'not compressed'}) unpacking to {unpacked:,} at offset {at}, "
            "which is not the chunk the file holds there",
        )


def _chunk_index(body: bytes) -> tuple[_Declared | None, int]:
    """A chunk index record's chunk, as it declares it, and the offset it names (None: too short for
    the library to read either)."""
    try:
        (at,) = struct.unpack_from("<Q", body, 16)
        (index_bytes,) = struct.unpack_from("<I", body, 32)
        position = 36 + index_bytes + 8
        (named,) = struct.unpack_from("<I", body, position)
        compression = body[position + 4 : position + 4 + named].decode("utf-8", "replace")
        packed, unpacked = struct.unpack_from("<QQ", body, position + 4 + named)
    except struct.error:
        return None, 0
    return (compression, packed, unpacked), at
