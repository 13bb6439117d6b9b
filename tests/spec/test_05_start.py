"""§5. Goal start: the tests of the rules of docs/spec.md §5.

The section's conformance vectors are src/dynevent/conformance/vectors/05-start.json.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.wire.messages import Goal
from support.scenario import (
    ADAPTER,
    RACE,
    RUNNING,
    T0,
    WAITING,
    Run,
    aborted,
    execute,
    feedback,
    finished_goal,
    next_goal,
    running,
    start_child,
    status,
    u,
    waiting,
)


def _finished() -> Run:
    run = waiting()
    run.request(u(2), finished_goal(1))
    run.start(u(2))
    return run


def _id_taken() -> Run:
    run = waiting()
    run.request(u(2), next_goal(1, 6))
    run.start(u(2))
    run.child_end()
    return run


# --------------------------------------------------------------------------- R5.1


@pytest.mark.spec("R5.1", "R6.4")
def test_start_executes_first_and_leaves_the_queue() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.request(u(2), finished_goal(1))
    outputs = run.start(u(1))
    assert outputs[0] == execute(u(1))
    assert [queued.goal_uuid for queued in run.state.queued] == [u(2)]


@pytest.mark.spec("R5.1")
def test_goals_start_in_any_order() -> None:
    run = waiting()
    run.request(u(1), finished_goal(1))
    run.request(u(2), next_goal(1, 5))
    assert run.start(u(2))[0] == execute(u(2))
    assert [queued.goal_uuid for queued in run.state.queued] == [u(1)]


# --------------------------------------------------------------------------- R5.2


@pytest.mark.spec("R5.2", "R11.2")
def test_race_a_new_run_began() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.submit(u(1), finished_goal(1))
    run.begin(event_id=1)
    assert run.seq == 2
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), RACE))
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.phase is WAITING


@pytest.mark.spec("R5.2", "R11.2")
def test_race_the_run_ended() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.submit(u(1), finished_goal(1))
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), RACE))
    assert run.state.queued == ()


@pytest.mark.spec("R5.2")
def test_race_another_next_took_the_running_slot() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.request(u(2), next_goal(1, 6))
    run.start(u(1))
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), RACE))
    assert run.state.running is not None
    assert run.state.running.goal_uuid == u(1)
    assert run.state.last_id == 5


@pytest.mark.spec("R5.2")
def test_race_a_finished_while_a_child_runs() -> None:
    run = waiting()
    run.request(u(1), finished_goal(1))
    run.submit(u(2), next_goal(1, 5))
    assert run.start(u(1)) == (execute(u(1)), aborted(u(1), RACE))
    assert run.phase is RUNNING
    assert run.state.active


@pytest.mark.spec("R5.2", "R4.12")
@pytest.mark.parametrize("second_id", [5, 6])
def test_race_the_id_is_no_longer_greater_than_last_id(second_id: int) -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 6))
    run.request(u(2), next_goal(1, second_id))
    run.start(u(1))
    run.child_end("completed")
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), RACE))
    assert run.state.last_id == 6


@pytest.mark.spec("R5.2", "R6.2", "R17.3")
def test_no_id_race_under_the_adapter_policy() -> None:
    run = waiting(event_id=10, config=ADAPTER)
    run.request(u(1), next_goal(1, 0))
    run.request(u(2), next_goal(1, 0))
    run.start(u(1))
    run.child_end("completed")
    assert run.start(u(2)) == (
        execute(u(2)),
        start_child(12),
        feedback(u(2), "underway", 12),
        status(1, RUNNING, "underway", 12),
    )


@pytest.mark.spec("R5.2")
@pytest.mark.parametrize(
    ("build", "sent", "text"),
    [
        (lambda: waiting(seq=1), next_goal(1, 6), "its seq 1 is no longer the run's seq 2"),
        (_finished, next_goal(1, 6), "no dynamic event is active any more"),
        (running, next_goal(1, 6), "event 5 holds the running slot"),
        (_id_taken, next_goal(1, 6), "its id 6 is no longer above 6, the highest id used"),
        (waiting, next_goal(1, 6), ""),
    ],
    ids=["seq", "inactive", "running", "id", "not_lost"],
)
def test_race_lost_sentences(build: Callable[[], Run], sent: Goal, text: str) -> None:
    run = build()
    assert machine.race_lost(run.state, sent, run.config) == text


# --------------------------------------------------------------------------- R5.3


@pytest.mark.spec("R5.3")
def test_a_submitted_goal_that_lost_a_race_is_aborted_with_the_refusal_under_the_failure() -> None:
    assert waiting().step(ins.GoalSubmitted(goal_uuid=u(2), goal=next_goal(7, 6), now=T0)) == (
        outs.ExecuteGoal(goal_uuid=u(2)),
        aborted(u(2), "race condition\n -- Expected 1, received 7"),
    )
