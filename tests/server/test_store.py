"""The SQLite state store: real files, a real process killed with SIGKILL, refusals that write nothing."""

from __future__ import annotations

import hashlib
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.machine import State
from dynevent.server.outputs import AnswerGoal
from dynevent.server.store import InvalidStore, StateStore
from dynevent.wire.messages import Result
from dynevent.wire.vocab import GoalStatus
from support.scenario import CONFIG, next_goal, running, u, waiting


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.spec("R21.3")
def test_states_survive_a_reopen(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    store = StateStore(path)
    first, second = running(child_id=8).state, waiting(event_id=3).state
    store.save(first)
    store.save(attrs_replace(second, robot="r2"))
    store.save(first)  # the same robot again: one row
    store.close()
    loaded = StateStore(path).load()
    assert loaded == {
        (first.fleet, first.robot): first,
        (first.fleet, "r2"): attrs_replace(second, robot="r2"),
    }
    assert sqlite3.connect(path).execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def attrs_replace(state: State, **changes: object) -> State:
    return attrs.evolve(state, **changes)


WRITER = """
import sys
from dynevent.server import inputs as ins, machine
from dynevent.server.machine import ServerConfig, State, any_description
from dynevent.server.store import StateStore
store = StateStore(sys.argv[1])
config = ServerConfig(categories={"go_to_place": any_description})
state = State.new("fleet", "robot")
state = machine.step(state, ins.Begin(description="{}", event_id=0, now=0), config).state
n = 0
while True:  # killed by the test
    n += 1
    state = machine.step(state, ins.Tick(now=n, map_name="L1", x=float(n), y=0.0), config).state
    store.save(state)
    if n == 50:
        print("saving", flush=True)
"""


@pytest.mark.spec("R21.3", "R19.6")
def test_a_writer_killed_with_sigkill_leaves_its_last_committed_state(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    writer = subprocess.Popen([sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert writer.stdout is not None
        assert writer.stdout.readline().strip() == "saving"
        time.sleep(0.2)
        os.kill(writer.pid, signal.SIGKILL)
        writer.wait(timeout=10)
    finally:
        if writer.poll() is None:
            writer.kill()
    assert writer.returncode == -signal.SIGKILL
    (state,) = StateStore(path).load().values()
    assert state.position is not None and state.position.x >= 50  # every save before the kill is there
    assert state.seq == 1 and state.active
    assert machine.step(state, ins.Restart(now=0), CONFIG).state.active  # and it restarts


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        (b"this is not a database, just text" * 100, "is not a dynevent state store"),
        (None, "is not a dynevent state store (tables ['other'])"),
    ],
)
def test_foreign_files_are_refused_and_left_untouched(
    tmp_path: Path, content: bytes | None, problem: str
) -> None:
    path = tmp_path / "foreign.db"
    if content is not None:
        path.write_bytes(content)
    else:
        db = sqlite3.connect(path)
        db.execute("CREATE TABLE other (x)")
        db.execute("INSERT INTO other VALUES (1)")
        db.commit()
        db.close()
    before = _digest(path)
    with pytest.raises(InvalidStore) as caught:
        StateStore(path)
    assert problem in str(caught.value) and str(path) in str(caught.value)
    assert _digest(path) == before


def test_another_format_or_version_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    StateStore(path).close()
    db = sqlite3.connect(path)
    db.execute("UPDATE meta SET value = '3' WHERE key = 'version'")
    db.commit()
    db.close()
    before = _digest(path)
    with pytest.raises(InvalidStore, match="has version '3'; this dynevent reads 1 and 2"):
        StateStore(path)
    assert _digest(path) == before


def _answer(n: int, status: GoalStatus = GoalStatus.SUCCEEDED, failure: str = "") -> AnswerGoal:
    return AnswerGoal(
        goal_uuid=u(n), status=status, result=Result(execution_failure=failure, status="completed", id=n)
    )


@pytest.mark.spec("R21.1")
def test_answers_are_kept_per_robot_and_the_first_answer_of_a_goal_wins(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    store = StateStore(path)
    store.keep_answers("f", "r1", [_answer(1), _answer(2, GoalStatus.CANCELED)])
    store.keep_answers("f", "r2", [_answer(3)])
    store.keep_answers("f", "r1", [_answer(1, GoalStatus.ABORTED, "server restarted")])  # not kept
    store.close()
    reopened = StateStore(path)
    assert reopened.answers("f", "r1") == {u(1): _answer(1), u(2): _answer(2, GoalStatus.CANCELED)}
    assert reopened.answers("f", "r2") == {u(3): _answer(3)}
    assert reopened.answers("f", "nobody") == {}


def test_answers_older_than_the_retention_are_dropped(tmp_path: Path) -> None:
    store = StateStore(tmp_path / "state.db", answer_retention=0.2)
    store.keep_answers("f", "r", [_answer(1)])
    assert list(store.answers("f", "r")) == [u(1)]
    time.sleep(0.3)
    assert store.answers("f", "r") == {}
    store.keep_answers("f", "r", [_answer(2)])
    rows = sqlite3.connect(tmp_path / "state.db").execute("SELECT goal_uuid FROM answers").fetchall()
    assert rows == [(u(2),)]  # the old row is deleted, not only hidden


def test_a_version_1_store_is_brought_to_version_2_and_keeps_its_states(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    state = running(child_id=8).state
    store = StateStore(path)
    store.save(state)
    store.close()
    db = sqlite3.connect(path)
    db.execute("DROP TABLE answers")
    db.execute("UPDATE meta SET value = '1' WHERE key = 'version'")
    db.commit()
    db.close()
    upgraded = StateStore(path)
    assert upgraded.load() == {(state.fleet, state.robot): state}
    upgraded.keep_answers(state.fleet, state.robot, [_answer(1)])
    assert list(upgraded.answers(state.fleet, state.robot)) == [u(1)]
    version = sqlite3.connect(path).execute("SELECT value FROM meta WHERE key = 'version'").fetchone()
    assert version == ("2",)


@pytest.mark.parametrize(
    ("column", "value", "problem"),
    [("status", "executing", "status 'executing'"), ("result", "{", "answer"), ("goal_uuid", "x", "'x'")],
)
def test_a_damaged_answer_is_refused_naming_the_robot(
    tmp_path: Path, column: str, value: str, problem: str
) -> None:
    path = tmp_path / "state.db"
    store = StateStore(path)
    store.keep_answers("f", "r", [_answer(1)])
    store.close()
    db = sqlite3.connect(path)
    db.execute(f"UPDATE answers SET {column} = ?", (value,))
    db.commit()
    db.close()
    with pytest.raises(InvalidStore, match=r"robot f/r: ") as caught:
        StateStore(path).answers("f", "r")
    assert problem in str(caught.value)


def test_a_corrupt_snapshot_is_refused_naming_the_robot(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    store = StateStore(path)
    store.save(waiting().state)
    store.close()
    db = sqlite3.connect(path)
    db.execute('UPDATE robots SET snapshot = \'{"format": "dynevent.state", "version": 1, "state": {}}\'')
    db.commit()
    db.close()
    before = _digest(path)
    with pytest.raises(InvalidStore, match=r"robot tinyRobot/r1: "):
        StateStore(path).load()
    assert _digest(path) == before


def test_a_restored_state_restarts_and_continues(tmp_path: Path) -> None:
    path = tmp_path / "state.db"
    run = running(child_id=8)
    StateStore(path).save(run.state)
    (state,) = StateStore(path).load().values()
    assert snapshot.dumps(state) == snapshot.dumps(run.state)
    after = machine.step(state, ins.Restart(now=0), CONFIG).state
    accepted = machine.step(after, ins.GoalRequested(goal_uuid=u(9), goal=next_goal(1, 9), now=0), CONFIG)
    assert accepted.outputs[0].KIND == "goal_accepted"
