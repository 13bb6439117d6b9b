"""Robots' states in an embedded SQLite database, so that a server survives its own end.

:class:`StateStore` keeps one snapshot (:mod:`dynevent.server.snapshot`) per robot
in a SQLite file (stdlib ``sqlite3``, write-ahead log): :meth:`~StateStore.save`
writes one robot's state in one transaction, :meth:`~StateStore.load`
restores every robot's, each validated as a snapshot is.  A process killed
at any moment leaves the last committed state of every robot; restore it and
step :class:`~dynevent.server.inputs.Restart` (R21).

It also keeps each goal's answer (:meth:`~StateStore.keep_answers`), for
:data:`~dynevent.server.answers.ANSWER_RETENTION` seconds, as long as the
binding keeps it in memory (:mod:`dynevent.server.answers`): a server
restarted on the file gives a client that asks again the answer its goal
got, even when the process died before the answer went out, and ``server
restarted`` for a goal that was open when it died (R21.1).  A goal's first
answer is the one kept.  A store of version 1 (no answers) is
brought to version 2 when it is opened.

A file that is not a SQLite database, a database of something else, a
store of another format or version, or a snapshot that does not validate is
refused with :class:`InvalidStore`, naming the file and what is wrong, and
nothing is written to it.
"""

from __future__ import annotations

import os
import sqlite3
import threading
import time
from collections.abc import Sequence
from pathlib import Path

from dynevent.errors import (
    InvalidMessage,
    InvalidSnapshot,
    InvalidStore,  # defined there with every error; importable here too
)
from dynevent.server import snapshot
from dynevent.server.answers import ANSWER_RETENTION
from dynevent.server.inputs import goal_uuid
from dynevent.server.machine import State
from dynevent.server.outputs import AnswerGoal
from dynevent.wire.messages import Result
from dynevent.wire.vocab import TERMINAL_GOAL_STATUSES, GoalStatus

__all__ = ["ANSWER_RETENTION", "FORMAT", "VERSION", "InvalidStore", "StateStore"]

#: The ``format`` of a dynevent store, in its ``meta`` table.
FORMAT = "dynevent.server.store"
#: The store's layout version: 2 adds the answers table.
VERSION = 2

_ANSWERS = (
    "CREATE TABLE answers (fleet TEXT NOT NULL, robot TEXT NOT NULL, goal_uuid TEXT NOT NULL, "
    "status TEXT NOT NULL, result TEXT NOT NULL, answered INTEGER NOT NULL, "
    "PRIMARY KEY (fleet, robot, goal_uuid))"
)
_SCHEMA = (
    "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
    "CREATE TABLE robots (fleet TEXT NOT NULL, robot TEXT NOT NULL, snapshot TEXT NOT NULL, "
    "PRIMARY KEY (fleet, robot))",
    _ANSWERS,
)


class StateStore:
    """One SQLite file holding the state of every robot of a server; safe to share between threads."""

    def __init__(self, path: str | os.PathLike[str], *, answer_retention: float = ANSWER_RETENTION) -> None:
        self.path = str(path)
        self.answer_retention = answer_retention
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
        if tables not in ({"meta", "robots"}, {"meta", "robots", "answers"}):
            raise InvalidStore(self.path, f"is not a dynevent state store (tables {sorted(tables)})")
        meta = dict(self._db.execute("SELECT key, value FROM meta").fetchall())
        if meta.get("format") != FORMAT:
            raise InvalidStore(self.path, f"has format {meta.get('format')!r}, not {FORMAT!r}")
        version = meta.get("version")
        if (version, "answers" in tables) not in (("1", False), (str(VERSION), True)):
            raise InvalidStore(self.path, f"has version {version!r}; this dynevent reads 1 and {VERSION}")
        self._db.execute("PRAGMA journal_mode=WAL")
        if version == "1":  # version 2 only adds the answers
            with self._transaction():
                self._db.execute(_ANSWERS)
                self._db.execute("UPDATE meta SET value = ? WHERE key = 'version'", (str(VERSION),))

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

    def keep_answers(self, fleet: str, robot: str, answers: Sequence[AnswerGoal]) -> None:
        """Keep these answers of one robot's goals, in one transaction (durable once this returns);
        a goal's first answer is kept, and answers older than the retention are dropped."""
        now = time.time_ns()
        rows = [
            (fleet, robot, answer.goal_uuid, answer.status.value, answer.result.to_json(), now)
            for answer in answers
        ]
        expired = now - round(self.answer_retention * 1e9)
        with self._lock, self._transaction():
            self._db.executemany(
                "INSERT OR IGNORE INTO answers (fleet, robot, goal_uuid, status, result, answered) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                rows,
            )
            self._db.execute("DELETE FROM answers WHERE answered < ?", (expired,))

    def answers(self, fleet: str, robot: str) -> dict[str, AnswerGoal]:
        """The kept answers of one robot's goals (within the retention), by goal UUID; each validated."""
        expired = time.time_ns() - round(self.answer_retention * 1e9)
        try:
            with self._lock:
                rows = self._db.execute(
                    "SELECT goal_uuid, status, result FROM answers "
                    "WHERE fleet = ? AND robot = ? AND answered >= ? ORDER BY answered",
                    (fleet, robot, expired),
                ).fetchall()
        except (sqlite3.DatabaseError, UnicodeDecodeError) as exc:
            raise InvalidStore(self.path, f"cannot be read ({exc})") from None
        kept: dict[str, AnswerGoal] = {}
        for uuid, status, result in rows:
            try:
                answer = AnswerGoal(
                    goal_uuid=goal_uuid(uuid), status=GoalStatus(status), result=Result.from_json(result)
                )
            except (InvalidMessage, ValueError, TypeError) as exc:
                raise InvalidStore(self.path, f"robot {fleet}/{robot}: answer {uuid!r}: {exc}") from None
            if answer.status not in TERMINAL_GOAL_STATUSES:
                raise InvalidStore(self.path, f"robot {fleet}/{robot}: answer {uuid!r}: status {status!r}")
            kept[answer.goal_uuid] = answer
        return kept

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
