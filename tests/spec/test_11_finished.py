"""§11. FINISHED and the end of a run: the tests of the rules of docs/spec.md §11.

The section's conformance vectors are src/dynevent/conformance/vectors/11-finished.json.
"""

from __future__ import annotations

import pytest

from dynevent.server import outputs as outs
from support.scenario import (
    INACTIVE,
    RACE,
    SUCCEEDED,
    WAITING,
    aborted,
    answer,
    execute,
    finished_goal,
    next_goal,
    running,
    s,
    status,
    stubborn,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R11.1


@pytest.mark.spec("R11.1", "R11.2")
def test_finished_ends_the_run() -> None:
    run = waiting(event_id=40).at(s(500))
    assert run.submit(u(1), finished_goal(1)) == (
        execute(u(1)),
        answer(u(1), SUCCEEDED, "", "completed", 40),
        outs.DynamicEventFinished(status="completed"),
        status(1, INACTIVE, "uninitialized", 0, s(500)),
    )
    assert (run.state.active, run.state.status, run.phase) == (False, "completed", INACTIVE)


@pytest.mark.spec("R11.1", "R12.5")
def test_finished_ends_stubbornness_first() -> None:
    run = stubborn(3.0)
    assert run.submit(u(2), finished_goal(1)) == (
        execute(u(2)),
        outs.StubbornEnd(),
        answer(u(2), SUCCEEDED, "", "completed", 1),
        outs.DynamicEventFinished(status="completed"),
        status(1, INACTIVE, "uninitialized", 0),
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R11.1")
def test_finished_after_children_answers_with_the_events_own_id() -> None:
    run = running(child_id=5, event_id=3)
    run.child_end("completed")
    assert run.submit(u(2), finished_goal(1))[1] == answer(u(2), SUCCEEDED, "", "completed", 3)


# --------------------------------------------------------------------------- R11.2


@pytest.mark.spec("R11.2", "R5.2")
def test_goals_still_queued_stay_queued_and_lose_the_race() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.request(u(3), finished_goal(1))
    run.submit(u(1), finished_goal(1))
    assert [queued.goal_uuid for queued in run.state.queued] == [u(2), u(3)]
    assert run.start(u(3)) == (execute(u(3)), aborted(u(3), RACE))
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), RACE))
    assert run.state.queued == ()


@pytest.mark.spec("R11.2", "R3.1")
def test_a_new_run_may_begin_after_the_end() -> None:
    run = waiting(event_id=1)
    run.submit(u(1), finished_goal(1))
    assert run.begin(event_id=2)[-1] == status(2, WAITING, "standby", 2)
