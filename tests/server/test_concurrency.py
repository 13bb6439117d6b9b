"""LockedRobotServer under several threads: no update lost, every accepted goal answered once.

A validator that sleeps widens the read-step-write window, as rclpy callbacks
on a MultiThreadedExecutor would; the same hammer on the unlocked server
loses updates, which shows the hammer can fail.
"""

from __future__ import annotations

import threading
import time
from collections import Counter
from collections.abc import Sequence
from typing import Any

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import LockedRobotServer, RobotServer
from dynevent.server.machine import ServerConfig
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType

THREADS = 6
GOALS_PER_THREAD = 25
SECOND = 1_000_000_000


def _slow_validator(category: str, description: Any) -> Sequence[str]:
    time.sleep(0.0002)  # releases the GIL inside the step, like real work would
    return ()


CONFIG = ServerConfig(categories={"go_to_place": _slow_validator})


def _hammer(server: RobotServer) -> list[outs.Output]:
    """Threads race NEXT goals (and CANCELs of what they see running); an adapter thread ends children."""
    collected: list[outs.Output] = []
    collected_lock = threading.Lock()
    stop = threading.Event()

    def record(produced: Sequence[outs.Output]) -> None:
        with collected_lock:
            collected.extend(produced)

    record(server.step(ins.Begin(description="{}", event_id=1, now=SECOND)))

    def client(index: int) -> None:
        for number in range(GOALS_PER_THREAD):
            uuid = f"{index:016x}{number:016x}"
            state = server.state
            if state.running is not None and number % 3 == 0:
                goal = Goal(
                    dynamic_event_seq=state.seq, event_type=EventType.CANCEL, id=state.running.child_id
                )
            else:
                goal = Goal(
                    dynamic_event_seq=state.seq,
                    event_type=EventType.NEXT,
                    category="go_to_place",
                    description='"a"',
                    id=state.last_id + 1 + index,
                )
            produced = server.step(ins.GoalRequested(goal_uuid=uuid, goal=goal, now=2 * SECOND))
            record(produced)
            if any(isinstance(output, outs.GoalAccepted) for output in produced):
                record(server.step(ins.GoalStarted(goal_uuid=uuid, now=2 * SECOND)))

    def adapter() -> None:
        while not stop.is_set():
            record(server.step(ins.ChildProgress(status="underway", log_text="moving", now=3 * SECOND)))
            record(server.step(ins.ChildFinished(status="completed", now=3 * SECOND)))
            time.sleep(0.0005)

    workers = [threading.Thread(target=client, args=(index,)) for index in range(THREADS)]
    ender = threading.Thread(target=adapter)
    ender.start()
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    stop.set()
    ender.join()
    record(server.step(ins.Shutdown(now=9 * SECOND)))  # answers whatever is still open
    return collected


def _violations(collected: list[outs.Output]) -> list[str]:
    accepted = {output.goal_uuid for output in collected if isinstance(output, outs.GoalAccepted)}
    answers = Counter(output.goal_uuid for output in collected if isinstance(output, outs.AnswerGoal))
    problems = [f"{uuid} accepted, never answered" for uuid in accepted if answers[uuid] == 0]
    problems += [f"{uuid} answered {count} times" for uuid, count in answers.items() if count > 1]
    problems += [f"{uuid} answered, never accepted" for uuid in answers if uuid not in accepted]
    started = [output.id for output in collected if isinstance(output, outs.StartChild)]
    if len(started) != len(set(started)):
        problems.append(f"a child id started twice: {sorted(started)}")
    ended = {
        output.result.id for output in collected if isinstance(output, outs.AnswerGoal) and output.result.id
    }
    unended = set(started) - ended
    if len(unended) > 1:  # only the child running at shutdown may end unanswered by its own result
        problems.append(f"children {sorted(unended)} started and never ended: two ran at once")
    return problems


@pytest.mark.spec("R19.1", "R19.2")
def test_locked_server_keeps_every_invariant_under_threads() -> None:
    collected = _hammer(LockedRobotServer("tinyRobot", "r1", CONFIG))
    assert sum(isinstance(output, outs.GoalAccepted) for output in collected) > THREADS
    assert sum(isinstance(output, outs.StartChild) for output in collected) > 1
    assert _violations(collected) == []


def test_the_hammer_catches_an_unlocked_server() -> None:
    # Without the lock, concurrent read-step-write loses updates: some accepted goal is never answered.
    found: list[str] = []
    for _ in range(5):
        found = _violations(_hammer(RobotServer("tinyRobot", "r1", CONFIG)))
        if found:
            break
    assert found, "the unlocked server showed no violation: the hammer has no teeth"
