"""Compressed recordings (dynevent.bags.unpack): every way rosbag2 and MCAP compress is read, and a
compressed bomb, a few kilobytes that unpack to gigabytes, is one line, its unpacking bounded before
it happens.

Time is not asserted (bench/bag_bombs.py measures each bomb's refusal in a process of its own): the
work is, as the memory the refusal takes (tracemalloc) and the bound the refusal names, past which
nothing is unpacked.  Unbounded, each bomb here took the reader to gigabytes.
"""

from __future__ import annotations

import contextlib
import subprocess
import sys
import tracemalloc
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from rosbags.rosbag2 import CompressionMode, StoragePlugin

from dynevent.bags import unpack
from dynevent.bags.reader import check_bag
from dynevent.errors import BagError
from support.bag_bombs import (
    BOMB,
    bag,
    lz4_zeros,
    mcap,
    packed_messages,
    status,
    storage_file,
    zstd_zeros,
)

STORAGES = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}
#: What a refused bomb is called.
BOMB_SAID = "a compressed bomb, not a recording"
#: The memory a refusal of a bomb that is not held at all may take (tracemalloc's peak): what a bag's
#: check takes anyway, and a piece of unpacking.
SMALL = 8_000_000


@contextlib.contextmanager
def peak() -> Iterator[list[int]]:
    """The peak of traced memory in the block, in bytes (in the list, once the block is over)."""
    found: list[int] = []
    tracemalloc.start()
    try:
        yield found
    finally:
        found.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()


def _refused(path: Path) -> tuple[str, int]:
    """check_bag's refusal of the bag at ``path`` and the memory it took."""
    with peak() as taken, pytest.raises(BagError) as refused:
        check_bag(path)
    return str(refused.value), taken[0]


@pytest.mark.parametrize(
    ("storage", "mode"),
    [
        (storage, mode)
        for storage in STORAGES
        for mode in CompressionMode
        if not (storage == "sqlite3" and mode is CompressionMode.STORAGE)  # SQLite has no chunks
    ],
)
def test_a_bag_compressed_in_each_way_is_read_as_it_was_written(
    tmp_path: Path, storage: str, mode: CompressionMode
) -> None:
    report = check_bag(bag(tmp_path / "bag", STORAGES[storage], mode, count=5))
    assert report.messages == 5 and report.clean
    assert [path.name for path in tmp_path.iterdir()] == ["bag"]  # what was unpacked is gone


@pytest.mark.parametrize("storage", list(STORAGES), ids=list(STORAGES))
def test_a_file_compressed_bomb_is_refused_at_the_bags_bound(tmp_path: Path, storage: str) -> None:
    recording = bag(tmp_path / "bomb", STORAGES[storage], CompressionMode.FILE)
    packed = storage_file(recording)
    packed.write_bytes(zstd_zeros(BOMB))  # 64 KiB, 2 GiB unpacked
    said, taken = _refused(recording)
    assert said == (
        f"{recording}: {packed.name} (compression_mode: file) unpacks to more than "
        f"{unpack.MAX_UNPACKED_BYTES:,} bytes: {BOMB_SAID}"
    )  # nothing past the bound unpacked: it unpacks to disk, a piece at a time
    assert taken < SMALL


def zstd(data: bytes) -> bytes:
    """``data`` compressed as rosbag2 compresses a message (zstd, the library rosbags uses)."""
    try:
        from compression import zstd as module  # type: ignore[import-not-found,unused-ignore]
    except ImportError:
        from backports import zstd as module  # type: ignore[import-not-found,no-redef,unused-ignore]
    packed: bytes = module.compress(data)
    return packed


@pytest.mark.parametrize("storage", list(STORAGES), ids=list(STORAGES))
def test_a_message_compressed_bomb_is_refused_at_the_bound_of_a_message(tmp_path: Path, storage: str) -> None:
    honest = [zstd(status(1, 0)), zstd(status(1, 0))]
    assert check_bag(packed_messages(tmp_path / "honest", STORAGES[storage], honest)).messages == 2
    bomb = [honest[0], zstd_zeros(BOMB), honest[1]]
    recording = packed_messages(tmp_path / "bomb", STORAGES[storage], bomb)
    said, taken = _refused(recording)
    assert said.startswith(f"{recording}: /rmf/dynamic_event/status/tinyRobot/r1 at ")
    assert said.endswith(f" unpacks to more than {unpack.MAX_UNPACKED_BYTES:,} bytes: {BOMB_SAID}")
    assert taken < unpack.MAX_UNPACKED_BYTES + SMALL  # the message is held, up to its bound only


def test_messages_each_within_their_bound_are_refused_at_the_bags(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bag as a whole unpacks to at most MAX_EXPANSION times what it stores (here made 1, and a
    message's bound 100 kB, so that a few small messages pass it)."""
    monkeypatch.setattr(unpack, "MAX_EXPANSION", 1)
    monkeypatch.setattr(unpack, "MAX_UNPACKED_BYTES", 100_000)
    long = zstd(status(1, 0, "x" * 90_000))  # a status the mirrors refuse, and the check goes on
    recording = packed_messages(tmp_path / "bag", StoragePlugin.MCAP, [long] * 3)
    stored = storage_file(recording).stat().st_size
    assert stored < 100_000 < 3 * 90_000
    said, _ = _refused(recording)
    assert said.endswith(
        f" unpacks past the bag's bound, 100,000 bytes (1 times what it stores): {BOMB_SAID}"
    ), said


#: MCAP chunks that lie: (compression, the chunk's compressed bytes, the size it declares, what is said).
CHUNKS: dict[str, tuple[str, Callable[[], bytes], int, str]] = {
    "zstd, declared as large as it is": (
        "zstd", lambda: zstd_zeros(BOMB), BOMB,
        f"declares {BOMB:,} bytes unpacked, more than {unpack.MAX_UNPACKED_BYTES:,}: {BOMB_SAID}",
    ),
    "zstd, declared small": (
        "zstd", lambda: zstd_zeros(BOMB), 1_000, f"unpacks to more than 1,000 bytes: {BOMB_SAID}"
    ),
    "lz4, declared small": (
        "lz4", lambda: lz4_zeros(2**28), 1_000, f"unpacks to more than 1,000 bytes: {BOMB_SAID}"
    ),
    "zstd, declared larger than it is": (
        "zstd", lambda: zstd_zeros(1_000), 2_000, "unpacks to 1,000 bytes, not the 2,000 it declares"
    ),
}  # fmt: skip


@pytest.mark.parametrize("chunk", list(CHUNKS))
@pytest.mark.parametrize("summary", [False, True], ids=["walked", "indexed"])
def test_an_mcap_chunk_bomb_is_refused_before_it_is_unpacked(
    tmp_path: Path, chunk: str, summary: bool
) -> None:
    """Without a summary the reader walks every chunk as it opens the file; with one, it unpacks the
    chunks the summary's indexes declare (here declaring what the chunk does)."""
    compression, packed, declared, problem = CHUNKS[chunk]
    data = packed()
    index = (compression, len(data), declared) if summary else None
    said, taken = _refused(mcap(tmp_path / "bomb.mcap", data, compression, declared, index=index))
    assert said == f"{tmp_path / 'bomb.mcap'}: the MCAP chunk at offset 175 {problem}"
    assert taken < SMALL


def test_a_chunk_index_that_declares_another_chunk_than_the_file_holds_is_refused(tmp_path: Path) -> None:
    """The reader unpacks what an index declares: an index that makes a small chunk large, or names
    an offset where no chunk is, is refused before anything is unpacked."""
    data = zstd_zeros(5_000)
    for index, declared in (
        (("zstd", len(data), 4_000), "a chunk of 10 bytes (zstd) unpacking to 4,000 at offset 175"),
        (("lz4", len(data), 5_000), "a chunk of 10 bytes (lz4) unpacking to 5,000 at offset 175"),
        (("zstd", len(data) + 1, 5_000), "a chunk of 11 bytes (zstd) unpacking to 5,000 at offset 175"),
    ):
        said, _ = _refused(mcap(tmp_path / "lies.mcap", data, "zstd", 5_000, index=index))
        assert said.endswith(f"declares {declared}, which is not the chunk the file holds there"), said


def test_a_chunk_whose_record_does_not_hold_its_declared_bytes_is_refused(tmp_path: Path) -> None:
    path = mcap(tmp_path / "short.mcap", zstd_zeros(5_000), "zstd", 5_000)
    data = bytearray(path.read_bytes())
    at = 175 + 9 + 32 + len("zstd")  # the chunk's compressed length
    data[at : at + 8] = (5).to_bytes(8, "little")
    path.write_bytes(bytes(data))
    said, _ = _refused(path)
    assert said.endswith("declares 5 compressed bytes in a record that holds 10"), said


@pytest.mark.parametrize("storage", list(STORAGES), ids=list(STORAGES))
def test_dynevent_check_says_a_bomb_in_one_line(tmp_path: Path, storage: str) -> None:
    recording = packed_messages(tmp_path / "bomb", STORAGES[storage], [zstd_zeros(BOMB)])
    done = subprocess.run(
        [sys.executable, "-m", "dynevent", "check", str(recording)],
        capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 2 and done.stdout == "" and "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.rstrip().endswith(BOMB_SAID), done.stderr
