"""docs/spec.md sections 11 (FINISHED, end of a run), 15 (shutdown) and 16 (description query)."""

from __future__ import annotations

import pytest

from dynevent.server import outputs as outs
from dynevent.wire.messages import DescriptionResponse
from scenario import (
    DESC,
    INACTIVE,
    RACE,
    SHUTTING_DOWN,
    SUCCEEDED,
    WAITING,
    Run,
    aborted,
    answer,
    cancel_goal,
    deferred,
    finished_goal,
    next_goal,
    running,
    s,
    status,
    stubborn,
    u,
    waiting,
)


def _execute(uuid: str) -> outs.ExecuteGoal:
    return outs.ExecuteGoal(goal_uuid=uuid)


def _described(running: bool = False, text: str = "", description: str = "", id: int = 0) -> tuple[object]:
    return (
        outs.DescriptionAnswer(
            response=DescriptionResponse(running=running, status=text, description=description, id=id)
        ),
    )


# --------------------------------------------------------------------------- R11.1, R11.2


@pytest.mark.spec("R11.1", "R11.2")
def test_finished_ends_the_run() -> None:
    run = waiting(event_id=40).at(s(500))
    assert run.submit(u(1), finished_goal(1)) == (
        _execute(u(1)),
        answer(u(1), SUCCEEDED, "", "completed", 40),
        outs.DynamicEventFinished(status="completed"),
        status(1, INACTIVE, "uninitialized", 0, s(500)),
    )
    assert (run.state.active, run.state.status, run.phase) == (False, "completed", INACTIVE)


@pytest.mark.spec("R11.1", "R12.5")
def test_finished_ends_stubbornness_first() -> None:
    run = stubborn(3.0)
    assert run.submit(u(2), finished_goal(1)) == (
        _execute(u(2)),
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


@pytest.mark.spec("R11.2", "R5.2")
def test_goals_still_queued_stay_queued_and_lose_the_race() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.request(u(3), finished_goal(1))
    run.submit(u(1), finished_goal(1))
    assert [queued.goal_uuid for queued in run.state.queued] == [u(2), u(3)]
    assert run.start(u(3)) == (_execute(u(3)), aborted(u(3), RACE))
    assert run.start(u(2)) == (_execute(u(2)), aborted(u(2), RACE))
    assert run.state.queued == ()


@pytest.mark.spec("R11.2", "R3.1")
def test_a_new_run_may_begin_after_the_end() -> None:
    run = waiting(event_id=1)
    run.submit(u(1), finished_goal(1))
    assert run.begin(event_id=2)[-1] == status(2, WAITING, "standby", 2)


# --------------------------------------------------------------------------- R15.1, R15.2


@pytest.mark.spec("R15.1", "R15.2")
def test_shutdown_answers_every_open_goal_in_order() -> None:
    run = running(child_id=5)
    run.submit(u(3), cancel_goal(1, 5))
    run.submit(u(2), cancel_goal(1, 5))
    run.request(u(5), cancel_goal(1, 5))
    run.request(u(4), cancel_goal(1, 5))
    assert run.shutdown(now=s(600)) == (
        aborted(u(1), SHUTTING_DOWN),
        aborted(u(3), SHUTTING_DOWN),
        aborted(u(2), SHUTTING_DOWN),
        _execute(u(5)),
        aborted(u(5), SHUTTING_DOWN),
        _execute(u(4)),
        aborted(u(4), SHUTTING_DOWN),
        status(1, INACTIVE, "uninitialized", 0, s(600)),
    )
    state = run.state
    assert (state.shutdown, state.active, state.running, state.queued, state.cancels) == (
        True,
        False,
        None,
        (),
        (),
    )


@pytest.mark.spec("R15.1")
def test_shutdown_aborts_a_deferred_childs_goal() -> None:
    run = deferred(child_id=5)
    assert run.shutdown() == (aborted(u(1), SHUTTING_DOWN), status(1, INACTIVE, "uninitialized", 0))


@pytest.mark.spec("R15.1", "R15.2", "R12.5")
def test_shutdown_while_stubborn_with_a_queued_goal() -> None:
    run = stubborn(3.0)
    run.request(u(2), next_goal(1, 6))
    assert run.shutdown() == (
        _execute(u(2)),
        aborted(u(2), SHUTTING_DOWN),
        outs.StubbornEnd(),
        status(1, INACTIVE, "uninitialized", 0),
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R15.2")
def test_shutdown_while_inactive_publishes_nothing() -> None:
    run = Run()
    assert run.shutdown() == ()
    assert run.state.shutdown


@pytest.mark.spec("R15.1", "R15.2")
def test_shutdown_after_the_run_answers_goals_left_queued() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.submit(u(1), finished_goal(1))
    assert run.shutdown() == (_execute(u(2)), aborted(u(2), SHUTTING_DOWN))


@pytest.mark.spec("R15.2", "R18.1", "R4.1")
def test_after_shutdown_begins_are_ignored_and_requests_refused() -> None:
    run = waiting()
    run.shutdown()
    run.assert_ignored(run.begin(event_id=2), "begin")
    run.assert_ignored(run.shutdown(), "shutdown")
    outputs = run.request(u(9), next_goal(1, 5))
    assert isinstance(outputs[0], outs.GoalRejected)
    assert outputs[0].rejection.reason == "shutting_down"


@pytest.mark.spec("R15.2", "R18.4")
def test_a_child_report_after_shutdown_is_ignored() -> None:
    run = running(child_id=5)
    run.shutdown()
    run.assert_ignored(run.child_end("completed"), "child_finished")
    run.assert_ignored(run.progress("underway"), "child_progress")


# --------------------------------------------------------------------------- R16.1, R16.2


@pytest.mark.spec("R16.1")
def test_description_query_while_inactive() -> None:
    run = Run()
    assert run.query() == _described()
    run = waiting()
    run.submit(u(1), finished_goal(1))
    assert run.query() == _described()
    assert run.state == run.before
    run = running()
    run.shutdown()
    assert run.query() == _described()


@pytest.mark.spec("R16.2")
def test_description_query_while_waiting() -> None:
    run = waiting(event_id=40)
    assert run.query() == _described(True, "standby", DESC, 40)
    assert run.state == run.before


@pytest.mark.spec("R16.2")
def test_description_query_while_running() -> None:
    run = running(child_id=41, event_id=40)
    run.progress("delayed")
    assert run.query() == _described(True, "delayed", DESC, 41)
    run.task_cancel()
    assert run.query() == _described(True, "canceled", DESC, 41)


@pytest.mark.spec("R16.2", "R6.3")
def test_description_query_with_a_deferred_child() -> None:
    run = deferred(child_id=5)
    assert run.query() == _described(True, "queued", DESC, 5)
