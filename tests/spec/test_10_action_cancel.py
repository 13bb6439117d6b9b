"""§10. Action-level cancel: the tests of the rules of docs/spec.md §10.

The section's conformance vectors are src/dynevent/conformance/vectors/10-action-cancel.json.
"""

from __future__ import annotations

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution
from dynevent.server.machine import QueuedGoal
from support.scenario import (
    ABORTED,
    CANCELED,
    NOT_RUNNING,
    RUNNING,
    SUCCEEDED,
    T0,
    WAITING,
    answer,
    cancel_goal,
    deferred,
    finished_goal,
    next_goal,
    running,
    running_server,
    start_child,
    status,
    u,
    waiting,
)


def _response(uuid: str, accepted: bool = True) -> outs.CancelResponse:
    return outs.CancelResponse(goal_uuid=uuid, accepted=accepted)


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


@pytest.mark.spec("R10.3", "R8.2")
def test_automatic_cancel_finishes_the_child_at_once() -> None:
    server = running_server()
    execution = Execution(server, 5)
    assert execution.automatic_cancel
    assert server.step(ins.CancelRequested(goal_uuid=u(1), now=T0)) == (
        outs.CancelResponse(goal_uuid=u(1), accepted=True),
        outs.CancelChild(id=5),
    )
    assert execution.cancel(now=T0) == (
        answer(u(1), CANCELED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )
    assert not execution.okay()
    assert server.state.running is None


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
