"""What ``dynevent check`` takes to refuse a compressed bomb, each in a process of its own.

Run ``python bench/bag_bombs.py`` from a virtual environment with the ``bags`` extra (and the test
extra's helpers: it builds the bombs with ``tests/support/bag_bombs.py``).  Each row is one recording whose
compressed bytes unpack to 2 GiB (a storage file, a message, an MCAP chunk), checked by
``python -m dynevent check`` in a fresh process: its wall time, its peak resident memory (the
process's ``ru_maxrss``, the interpreter and rosbags included), its exit status and its one line.
The bound is the issue's: each in under 2 s and under 200 MB (#52).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sqlite3
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # run as a script: bench and the tests' bombs

from rosbags.rosbag2 import CompressionMode, StoragePlugin  # noqa: E402

from bench.check_bags import run_check  # noqa: E402
from support.bag_bombs import BOMB, bag, lz4_zeros, mcap, packed_messages, storage_file, zstd_zeros  # noqa: E402


def _file_bomb(storage: StoragePlugin) -> Callable[[Path], Path]:
    def make(folder: Path) -> Path:
        recording = bag(folder / "bomb", storage, CompressionMode.FILE)
        storage_file(recording).write_bytes(zstd_zeros(BOMB))
        return recording

    return make


def _message_bomb(storage: StoragePlugin) -> Callable[[Path], Path]:
    def make(folder: Path) -> Path:
        return packed_messages(folder / "bomb", storage, [zstd_zeros(BOMB)])

    return make


def _sqlite_message_bomb(folder: Path) -> Path:
    """The issue's: a SQLite bag whose messages are zstd, one of them a bomb."""
    recording = bag(folder / "bomb", StoragePlugin.SQLITE3, CompressionMode.MESSAGE)
    with contextlib.closing(sqlite3.connect(storage_file(recording))) as connection:
        connection.execute("UPDATE messages SET data = ? WHERE id = 2", (zstd_zeros(BOMB),))
        connection.commit()
    return recording


BOMBS: dict[str, Callable[[Path], Path]] = {
    "SQLite, messages compressed, one a bomb": _sqlite_message_bomb,
    "MCAP, messages compressed, one a bomb": _message_bomb(StoragePlugin.MCAP),
    "SQLite, file compressed: a bomb": _file_bomb(StoragePlugin.SQLITE3),
    "MCAP, file compressed: a bomb": _file_bomb(StoragePlugin.MCAP),
    "MCAP, a zstd chunk declared 2 GiB": lambda f: mcap(f / "bomb.mcap", zstd_zeros(BOMB), "zstd", BOMB),
    "MCAP, a zstd chunk declared 1 kB": lambda f: mcap(f / "bomb.mcap", zstd_zeros(BOMB), "zstd", 1000),
    "MCAP, an lz4 chunk declared 1 kB (1 GiB)": lambda f: mcap(f / "b.mcap", lz4_zeros(2**30), "lz4", 1000),
}  # fmt: skip


def measure(path: Path) -> tuple[float, float, int, str]:
    """``dynevent check PATH`` in a process of its own: seconds, peak resident MB, status, its line."""
    seconds, done, kilobytes = run_check(path)
    status = next(line for line in done.stdout.splitlines() if line.startswith("status ")).split()[1]
    line = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ""
    return seconds, kilobytes / 1024, int(status), line


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    print("| bomb (2 GiB unpacked, unless said) | stored | time | peak RSS | exit | the line |")
    print("|---|---|---|---|---|---|")
    for name, make in BOMBS.items():
        with tempfile.TemporaryDirectory() as folder:
            path = make(Path(folder))
            stored = sum(file.stat().st_size for file in ([path] if path.is_file() else path.iterdir()))
            seconds, megabytes, status, line = measure(path)
            said = line.replace(str(path), "BAG")
            size, rss = f"{stored / 1024:.0f} KiB", f"{megabytes:.0f} MB"
            cells = (name, size, f"{seconds:.2f} s", rss, status, said)
            print("| " + " | ".join(str(cell) for cell in cells) + " |")
    print(f"\n(python {sys.version.split()[0]}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
