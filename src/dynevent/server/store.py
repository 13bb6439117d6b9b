"""Robots' states in an embedded SQLite database, so that a server survives its own end.

:class:`StateStore` keeps one snapshot (:mod:`dynevent.server.snapshot`) per robot
in a SQLite file (stdlib ``sqlite3``, write-ahead log): :meth:`~StateStore.save`
writes one robot's state in one transaction, :meth:`~StateStore.load`
restores every robot's, each validated as a snapshot is.  A process killed
at any moment leaves the last committed state of every robot; restore it and
step :class:`~dynevent.server.inputs.Restart` (R21).

A file that is not a SQLite database, a database of something else, a
store of another format or version, or a snapshot that does not validate is
refused with :class:`InvalidStore`, naming the file and what is wrong, and
nothing is written to it.
"""

from __future__ import annotations

import os
import sqlite3
import threading
from pathlib import Path

from dynevent.errors import (
    InvalidSnapshot,
    InvalidStore,  # defined there with every error; importable here too
)
from dynevent.server import snapshot
from dynevent.server.machine import State

__all__ = ["FORMAT", "VERSION", "InvalidStore", "StateStore"]

#: The ``format`` of a dynevent store, in its ``meta`` table.
FORMAT = "dynevent.server.store"
#: The store's layout version.
VERSION = 1

_SCHEMA = (
    "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
    "CREATE TABLE robots (fleet TEXT NOT NULL, robot TEXT NOT NULL, snapshot TEXT NOT NULL, "
    "PRIMARY KEY (fleet, robot))",
)


class StateStore:
    """One SQLite file holding the state of every robot of a server; safe to share between threads."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        self._lock = threading.Lock()
        existed = Path(self.path).exists() and Path(self.path).stat().st_size > 0
        try:
            self._db = sqlite3.connect(self.path, timeout=5.0, isolation_level=None, check_same_thread=False)
        except sqlite3.Error as exc:
            raise InvalidStore(self.path, f"cannot be opened: {exc}") from None
        try:
            if existed:
                self._check()
            else:
                self._create()
        except (sqlite3.DatabaseError, UnicodeDecodeError) as exc:  # text that is not UTF-8: not ours
            self._db.close()
            raise InvalidStore(self.path, f"is not a dynevent state store ({exc})") from None
        except InvalidStore:
            self._db.close()
            raise

    def _create(self) -> None:
        self._db.execute("PRAGMA journal_mode=WAL")
        with self._transaction():
            for statement in _SCHEMA:
                self._db.execute(statement)
            self._db.executemany(
                "INSERT INTO meta (key, value) VALUES (?, ?)", [("format", FORMAT), ("version", str(VERSION))]
            )

    def _check(self) -> None:
        tables = {row[0] for row in self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        if tables != {"meta", "robots"}:
            raise InvalidStore(self.path, f"is not a dynevent state store (tables {sorted(tables)})")
        meta = dict(self._db.execute("SELECT key, value FROM meta").fetchall())
        if meta.get("format") != FORMAT:
            raise InvalidStore(self.path, f"has format {meta.get('format')!r}, not {FORMAT!r}")
        if meta.get("version") != str(VERSION):
            raise InvalidStore(
                self.path, f"has version {meta.get('version')!r}; this dynevent reads {VERSION}"
            )
        self._db.execute("PRAGMA journal_mode=WAL")

    def _transaction(self) -> _Committing:
        self._db.execute("BEGIN IMMEDIATE")
        return _Committing(self._db)

    def load(self) -> dict[tuple[str, str], State]:
        """Every robot's stored state, by (fleet, robot); each snapshot validated."""
        states: dict[tuple[str, str], State] = {}
        try:
            with self._lock:
                rows = self._db.execute(
                    "SELECT fleet, robot, snapshot FROM robots ORDER BY fleet, robot"
                ).fetchall()
        except (sqlite3.DatabaseError, UnicodeDecodeError) as exc:
            raise InvalidStore(self.path, f"cannot be read ({exc})") from None
        for fleet, robot, text in rows:
            try:
                state = snapshot.loads(text)
            except InvalidSnapshot as exc:
                raise InvalidStore(self.path, f"robot {fleet}/{robot}: {exc}") from None
            if (state.fleet, state.robot) != (fleet, robot):
                raise InvalidStore(
                    self.path, f"robot {fleet}/{robot} holds the state of {state.fleet}/{state.robot}"
                )
            states[(fleet, robot)] = state
        return states

    def save(self, state: State) -> None:
        """Write one robot's state, in one transaction (durable once this returns)."""
        text = snapshot.dumps(state)
        with self._lock, self._transaction():
            self._db.execute(
                "INSERT INTO robots (fleet, robot, snapshot) VALUES (?, ?, ?) "
                "ON CONFLICT (fleet, robot) DO UPDATE SET snapshot = excluded.snapshot",
                (state.fleet, state.robot, text),
            )

    def close(self) -> None:
        """Close the database."""
        self._db.close()


class _Committing:
    """Commit at the end of a ``with`` block, roll back on an exception."""

    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db

    def __enter__(self) -> sqlite3.Connection:
        return self._db

    def __exit__(self, kind: object, value: object, traceback: object) -> None:
        self._db.execute("COMMIT" if kind is None else "ROLLBACK")
