"""§8. Child end: the tests of the rules of docs/spec.md §8.

The section's conformance vectors are src/dynevent/conformance/vectors/08-child-end.json.
"""

from __future__ import annotations

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution, RobotServer
from dynevent.wire.vocab import GoalStatus, Status
from support.scenario import (
    ABORTED,
    CANCELED,
    CHILD_STATUSES,
    CONFIG,
    RUNNING,
    SERVER_CLASSES,
    SUCCEEDED,
    T0,
    WAITING,
    answer,
    cancel_goal,
    finished_goal,
    next_goal,
    running,
    running_server,
    s,
    status,
    u,
)

EARLY_END = ["canceled", "killed", "skipped"]


# --------------------------------------------------------------------------- R8.1


@pytest.mark.spec("R8.1", "R8.2", "R8.4")
@pytest.mark.parametrize("final", CHILD_STATUSES)
def test_child_end_answers_the_goal(final: str) -> None:
    run = running(child_id=5).at(s(300))
    goal_status = ABORTED if final in EARLY_END else SUCCEEDED
    assert run.child_end(final) == (
        answer(u(1), goal_status, "", final, 5),
        status(1, WAITING, "standby", 5, s(300)),
    )
    assert run.state.running is None
    assert run.state.status == "standby"
    assert run.state.stubborn is None
    assert run.phase is WAITING


@pytest.mark.spec("R8.1")
@pytest.mark.parametrize("cls", SERVER_CLASSES)
def test_snapshot_and_restore_continue_the_same_run(cls: type[RobotServer]) -> None:
    server = running_server(cls)
    restored = cls.restore(server.snapshot(), CONFIG)
    assert type(restored) is cls
    assert restored.state == server.state
    finished = ins.ChildFinished(status="completed", now=T0)
    assert restored.step(finished) == server.step(finished)


@pytest.mark.spec("R8.1", "R8.2")
def test_execution_finished() -> None:
    server = running_server()
    execution = Execution(server, 5)
    assert execution.finished(now=T0) == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5),
    )
    assert not execution.okay()


# --------------------------------------------------------------------------- R8.2


@pytest.mark.spec("R8.2", "R10.3")
@pytest.mark.parametrize("final", CHILD_STATUSES)
def test_child_end_after_an_action_level_cancel(final: str) -> None:
    run = running(child_id=5)
    run.cancel(u(1))
    goal_status = CANCELED if final in EARLY_END else SUCCEEDED
    assert run.child_end(final) == (
        answer(u(1), goal_status, "", final, 5),
        status(1, WAITING, "standby", 5),
    )


@pytest.mark.spec("R8.2")
def test_execution_finished_with_a_status() -> None:
    server = running_server()
    execution = Execution(server, 5)
    assert execution.finished(now=T0, status=Status.FAILED)[0] == answer(u(1), SUCCEEDED, "", "failed", 5)


# --------------------------------------------------------------------------- R8.3


@pytest.mark.spec("R8.3", "R8.2", "R9.3")
def test_waiting_cancels_succeed_in_start_order() -> None:
    run = running(child_id=5)
    run.request(u(3), cancel_goal(1, 5))
    run.request(u(2), cancel_goal(1, 5))
    run.start(u(2))
    run.start(u(3))
    assert run.state.cancels == (u(2), u(3))
    assert run.child_end("canceled") == (
        answer(u(1), ABORTED, "", "canceled", 5),
        answer(u(2), SUCCEEDED, "", "canceled", 5),
        answer(u(3), SUCCEEDED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )
    assert not run.state.cancels


@pytest.mark.spec("R8.3", "R8.2")
def test_a_cancel_that_came_too_late_shares_the_completed_result() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.child_end("completed") == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        answer(u(2), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5),
    )


@pytest.mark.spec("R8.3", "R8.2", "R10.3")
def test_cancel_goal_and_action_level_cancel_together() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    run.cancel(u(1))
    assert run.child_end("killed") == (
        answer(u(1), GoalStatus.CANCELED, "", "killed", 5),
        answer(u(2), SUCCEEDED, "", "killed", 5),
        status(1, WAITING, "standby", 5),
    )


# --------------------------------------------------------------------------- R8.4


@pytest.mark.spec("R8.4")
def test_after_the_child_the_run_goes_on() -> None:
    run = running(child_id=5)
    run.child_end("failed")
    assert run.request(u(2), next_goal(1, 6)) == (outs.GoalAccepted(goal_uuid=u(2)),)
    assert run.start(u(2))[-1] == status(1, RUNNING, "underway", 6)
    run.child_end("completed")
    assert run.submit(u(3), finished_goal(1))[1] == answer(u(3), SUCCEEDED, "", "completed", 1)


@pytest.mark.spec("R8.4", "R12.1")
def test_child_end_begins_stubbornness_when_asked() -> None:
    run = running(child_id=5, stubborn=2.5)
    run.tick("L2", 3.0, -4.0)
    assert run.child_end("completed", now=s(400)) == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        outs.StubbornBegin(period=2.5, since=s(400), map_name="L2", x=3.0, y=-4.0),
        status(1, WAITING, "standby", 5, s(400)),
    )
