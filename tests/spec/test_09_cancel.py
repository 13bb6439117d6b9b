"""§9. CANCEL: the tests of the rules of docs/spec.md §9.

The section's conformance vectors are src/dynevent/conformance/vectors/09-cancel.json.
"""

from __future__ import annotations

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution
from support.scenario import (
    ABORTED,
    CANCEL_ID,
    CANCELED,
    IDLE_CANCEL,
    RUNNING,
    SUCCEEDED,
    T0,
    WAITING,
    aborted,
    answer,
    cancel_goal,
    deferred,
    entry,
    execute,
    feedback,
    next_goal,
    running,
    running_server,
    s,
    status,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R9.1


@pytest.mark.spec("R9.1")
def test_cancel_starting_after_the_child_ended_is_idle() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    run.child_end("completed")
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), IDLE_CANCEL))
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.phase is WAITING


# --------------------------------------------------------------------------- R9.2


@pytest.mark.spec("R9.2")
def test_cancel_starting_while_another_child_runs_is_a_mismatch() -> None:
    run = running(child_id=5)
    run.request(u(2), cancel_goal(1, 5))
    run.child_end("completed")
    run.submit(u(3), next_goal(1, 6))
    assert run.start(u(2)) == (execute(u(2)), aborted(u(2), CANCEL_ID))
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.state.running is not None
    assert not run.state.running.canceling


# --------------------------------------------------------------------------- R9.3


@pytest.mark.spec("R9.3")
def test_cancel_of_a_started_child_waits_for_its_end() -> None:
    run = running(child_id=5)
    assert run.submit(u(2), cancel_goal(1, 5)) == (execute(u(2)), outs.CancelChild(id=5))
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
    assert run.submit(u(3), cancel_goal(1, 5)) == (execute(u(3)),)
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
    assert run.submit(u(2), cancel_goal(1, 5)) == (execute(u(2)),)
    assert run.state.cancels == (u(2),)


@pytest.mark.spec("R9.3", "R8.2", "R8.3")
def test_automatic_kill_finishes_the_child_killed() -> None:
    server = running_server()
    execution = Execution(server, 5)
    server.step(ins.GoalRequested(goal_uuid=u(2), goal=cancel_goal(1, 5), now=T0))
    server.step(ins.GoalStarted(goal_uuid=u(2), now=T0))
    assert execution.kill(now=T0) == (
        answer(u(1), ABORTED, "", "killed", 5),
        answer(u(2), SUCCEEDED, "", "killed", 5),
        status(1, WAITING, "standby", 5),
    )


@pytest.mark.spec("R9.3", "R8.2")
def test_without_automatic_cancel_the_adapter_winds_down() -> None:
    server = running_server()
    execution = Execution(server, 5, automatic_cancel=False)
    server.step(ins.CancelRequested(goal_uuid=u(1), now=T0))
    assert execution.cancel(now=T0) == ()
    assert not execution.okay()
    assert (execution.stopping, execution.done) == ("canceled", False)  # stopping, not finished
    assert server.state.running is not None
    # still winding down: reports still reach the goal
    assert execution.underway("parking", now=T0)[1] == feedback(
        u(1), "underway", 5, entry(0, "info", T0, "parking")
    )
    # a plain finished() after a cancel ends canceled
    assert execution.finished(now=s(101)) == (
        answer(u(1), CANCELED, "", "canceled", 5),
        status(1, WAITING, "standby", 5, s(101)),
    )
    assert execution.done and not execution.okay()


# --------------------------------------------------------------------------- R9.4


@pytest.mark.spec("R9.4", "R8.2", "R8.3")
def test_cancel_of_a_deferred_child_cancels_it_at_once() -> None:
    run = deferred(child_id=5)
    assert run.submit(u(2), cancel_goal(1, 5)) == (
        execute(u(2)),
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
