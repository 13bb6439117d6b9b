"""docs/spec.md sections 9 (CANCEL goals) and 10 (action-level cancel)."""

from __future__ import annotations

import attrs
import pytest

from dynevent.server import outputs as outs
from dynevent.server.machine import QueuedGoal
from scenario import (
    ABORTED,
    CANCEL_ID,
    CANCELED,
    IDLE_CANCEL,
    NOT_RUNNING,
    RUNNING,
    SUCCEEDED,
    WAITING,
    aborted,
    answer,
    cancel_goal,
    deferred,
    feedback,
    finished_goal,
    next_goal,
    running,
    start_child,
    status,
    u,
    waiting,
)


def _execute(uuid: str) -> outs.ExecuteGoal:
    return outs.ExecuteGoal(goal_uuid=uuid)


def _response(uuid: str, accepted: bool = True) -> outs.CancelResponse:
    return outs.CancelResponse(goal_uuid=uuid, accepted=accepted)


# --------------------------------------------------------------------------- R9.1, R9.2


@pytest.mark.spec("R9.1")
def test_cancel_starting_after_the_child_ended_is_idle() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    run.child_end("completed")
    assert run.start(u(2)) == (_execute(u(2)), aborted(u(2), IDLE_CANCEL))
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.phase is WAITING


@pytest.mark.spec("R9.2")
def test_cancel_starting_while_another_child_runs_is_a_mismatch() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    run.child_end("completed")
    run.submit(u(3), next_goal(1, 6))
    assert run.start(u(2)) == (_execute(u(2)), aborted(u(2), CANCEL_ID))
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.state.running is not None
    assert not run.state.running.canceling


# --------------------------------------------------------------------------- R9.3


@pytest.mark.spec("R9.3")
def test_cancel_of_a_started_child_waits_for_its_end() -> None:
    run = running(child_id=5)
    assert run.submit(u(2), cancel_goal(1, 5)) == (_execute(u(2)), outs.CancelChild(id=5))
    assert run.state.cancels == (u(2),)
    assert run.state.running is not None
    assert run.state.running.canceling
    assert not run.state.running.cancel_requested
    assert (run.phase, run.state.status) == (RUNNING, "underway")
    # the child still reports; the goal still holds the slot
    assert run.progress("underway") == (feedback(u(1), "underway", 5),)


@pytest.mark.spec("R9.3")
def test_a_second_cancel_does_not_tell_the_child_again() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.submit(u(3), cancel_goal(1, 5)) == (_execute(u(3)),)
    assert run.state.cancels == (u(2), u(3))


@pytest.mark.spec("R9.3", "R10.3", "R13.2")
@pytest.mark.parametrize("stop", ["action_cancel", "task_cancel", "task_kill"])
def test_cancel_after_the_child_was_told_to_stop(stop: str) -> None:
    run = running(child_id=5)
    if stop == "action_cancel":
        run.cancel(u(1))
    elif stop == "task_cancel":
        run.task_cancel()
    else:
        run.task_kill()
    assert run.submit(u(2), cancel_goal(1, 5)) == (_execute(u(2)),)
    assert run.state.cancels == (u(2),)


# --------------------------------------------------------------------------- R9.4


@pytest.mark.spec("R9.4", "R8.2", "R8.3")
def test_cancel_of_a_deferred_child_cancels_it_at_once() -> None:
    run = deferred(child_id=5)
    assert run.submit(u(2), cancel_goal(1, 5)) == (
        _execute(u(2)),
        answer(u(1), ABORTED, "", "canceled", 5),
        answer(u(2), SUCCEEDED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )
    assert (run.state.running, run.state.cancels, run.state.status) == (None, (), "standby")
    assert run.phase is WAITING


@pytest.mark.spec("R9.4")
def test_no_stubbornness_after_a_deferred_child_is_cancelled() -> None:
    run = waiting()
    run.interrupt()
    run.submit(u(1), next_goal(1, 5, stubborn=3.0))
    outputs = run.submit(u(2), cancel_goal(1, 5))
    assert not any(isinstance(output, outs.StubbornBegin) for output in outputs)
    assert run.state.stubborn is None


# --------------------------------------------------------------------------- R10.1


@pytest.mark.spec("R10.1")
def test_cancel_of_a_queued_goal() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.request(u(2), finished_goal(1))
    assert run.cancel(u(1)) == (_response(u(1)), answer(u(1), CANCELED, NOT_RUNNING))
    assert run.state == attrs.evolve(run.before, queued=(QueuedGoal(goal_uuid=u(2), goal=finished_goal(1)),))


@pytest.mark.spec("R10.1", "R18.3")
def test_a_cancelled_queued_goal_cannot_start() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.cancel(u(1))
    outputs = run.start(u(1))
    run.assert_ignored(outputs, "goal_started")


@pytest.mark.spec("R10.1")
def test_cancel_of_a_queued_cancel_goal_while_running() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    assert run.cancel(u(2)) == (_response(u(2)), answer(u(2), CANCELED, NOT_RUNNING))
    assert run.state == attrs.evolve(run.before, queued=())


@pytest.mark.spec("R10.1", "R11.2")
def test_cancel_of_a_goal_queued_past_the_end_of_its_run() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.submit(u(1), finished_goal(1))
    assert run.cancel(u(2)) == (_response(u(2)), answer(u(2), CANCELED, NOT_RUNNING))
    assert run.state.queued == ()


# --------------------------------------------------------------------------- R10.2


@pytest.mark.spec("R10.2")
def test_cancel_of_a_waiting_cancel_goal() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    run.submit(u(3), cancel_goal(1, 5))
    assert run.cancel(u(2)) == (_response(u(2)), answer(u(2), CANCELED, NOT_RUNNING))
    assert run.state == attrs.evolve(run.before, cancels=(u(3),))
    # the child's cancellation goes on; only the remaining goals are answered at its end
    assert run.state.running is not None
    assert run.state.running.canceling
    assert run.child_end("canceled") == (
        answer(u(1), ABORTED, "", "canceled", 5),
        answer(u(3), SUCCEEDED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )


# --------------------------------------------------------------------------- R10.3


@pytest.mark.spec("R10.3")
def test_cancel_of_the_running_goal_tells_the_child() -> None:
    run = running(child_id=5)
    assert run.cancel(u(1)) == (_response(u(1)), outs.CancelChild(id=5))
    assert run.state.running is not None
    assert (run.state.running.cancel_requested, run.state.running.canceling) == (True, True)
    assert (run.phase, run.state.status) == (RUNNING, "underway")


@pytest.mark.spec("R10.3")
def test_a_repeated_cancel_of_the_running_goal_does_not_tell_the_child_again() -> None:
    run = running(child_id=5)
    run.cancel(u(1))
    assert run.cancel(u(1)) == (_response(u(1)),)
    assert run.state == run.before


@pytest.mark.spec("R10.3", "R9.3", "R8.2")
def test_cancel_of_the_running_goal_after_a_cancel_goal_is_recorded() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.cancel(u(1)) == (_response(u(1)),)
    assert run.state.running is not None
    assert run.state.running.cancel_requested
    assert run.child_end("canceled")[0] == answer(u(1), CANCELED, "", "canceled", 5)


# --------------------------------------------------------------------------- R10.4


@pytest.mark.spec("R10.4")
def test_cancel_of_the_running_goal_with_a_deferred_child() -> None:
    run = deferred(child_id=5)
    assert run.cancel(u(1)) == (
        _response(u(1)),
        answer(u(1), CANCELED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )
    assert (run.state.running, run.state.status, run.phase) == (None, "standby", WAITING)
    # the child never starts
    assert run.resume() == ()
    assert run.submit(u(2), next_goal(1, 6))[1] == start_child(6)


# --------------------------------------------------------------------------- R10.5


@pytest.mark.spec("R10.5")
def test_cancel_of_an_unknown_goal_is_rejected() -> None:
    run = running(child_id=5)
    assert run.cancel(u(77)) == (_response(u(77), accepted=False),)
    assert run.state == run.before


@pytest.mark.spec("R10.5")
def test_cancel_of_an_answered_goal_is_rejected() -> None:
    run = running(child_id=5)
    run.child_end("completed")
    assert run.cancel(u(1)) == (_response(u(1), accepted=False),)
    assert run.state == run.before
    run.request(u(2), next_goal(1, 6))
    run.cancel(u(2))
    assert run.cancel(u(2)) == (_response(u(2), accepted=False),)


@pytest.mark.spec("R10.5", "R15.1")
def test_cancel_after_shutdown_is_rejected() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    run.shutdown()
    for uuid in (u(1), u(2)):
        assert run.cancel(uuid) == (_response(uuid, accepted=False),)
