"""§15. Shutdown: the tests of the rules of docs/spec.md §15.

The section's conformance vectors are src/dynevent/conformance/vectors/15-shutdown.json.
"""

from __future__ import annotations

import pytest

from dynevent.server import outputs as outs
from support.scenario import (
    INACTIVE,
    SHUTTING_DOWN,
    Run,
    aborted,
    cancel_goal,
    deferred,
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

# --------------------------------------------------------------------------- R15.1


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
        execute(u(5)),
        aborted(u(5), SHUTTING_DOWN),
        execute(u(4)),
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
        execute(u(2)),
        aborted(u(2), SHUTTING_DOWN),
        outs.StubbornEnd(),
        status(1, INACTIVE, "uninitialized", 0),
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R15.1", "R15.2")
def test_shutdown_after_the_run_answers_goals_left_queued() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.submit(u(1), finished_goal(1))
    assert run.shutdown() == (execute(u(2)), aborted(u(2), SHUTTING_DOWN))


# --------------------------------------------------------------------------- R15.2


@pytest.mark.spec("R15.2")
def test_shutdown_while_inactive_publishes_nothing() -> None:
    run = Run()
    assert run.shutdown() == ()
    assert run.state.shutdown


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
