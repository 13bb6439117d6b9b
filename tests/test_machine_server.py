"""The mutable conveniences of dynevent.server.holder: RobotServer, LockedRobotServer and Execution."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution, LockedRobotServer, RobotServer
from dynevent.server.machine import State
from dynevent.wire.vocab import RejectReason, Status
from scenario import (
    ABORTED,
    CANCELED,
    CONFIG,
    DESC,
    FLEET,
    INACTIVE,
    ROBOT,
    RUNNING,
    SUCCEEDED,
    T0,
    WAITING,
    Run,
    answer,
    cancel_goal,
    entry,
    feedback,
    next_goal,
    s,
    start_child,
    status,
    u,
)

SERVERS = [RobotServer, LockedRobotServer]


def _running(cls: type[RobotServer] = RobotServer, child_id: int = 5) -> RobotServer:
    server = cls(FLEET, ROBOT, CONFIG)
    server.step(ins.Begin(description=DESC, event_id=1, now=T0))
    server.step(ins.GoalRequested(goal_uuid=u(1), goal=next_goal(1, child_id), now=T0))
    server.step(ins.GoalStarted(goal_uuid=u(1), now=T0))
    return server


# --------------------------------------------------------------------------- RobotServer, LockedRobotServer


@pytest.mark.spec("R3.1", "R4.16", "R6.4", "R2.2")
@pytest.mark.parametrize("cls", SERVERS)
def test_the_server_holds_the_state_across_steps(cls: type[RobotServer]) -> None:
    server = cls(FLEET, ROBOT, CONFIG)
    assert server.state == State.new(FLEET, ROBOT)
    assert server.config is CONFIG
    assert server.status_message(T0) == status(0, INACTIVE, "uninitialized", 0).message
    server.step(ins.Begin(description=DESC, event_id=1, now=T0))
    assert server.accept(next_goal(1, 5)) == outs.Accepted(event_type=1)
    assert server.step(ins.GoalRequested(goal_uuid=u(1), goal=next_goal(1, 5), now=T0)) == (
        outs.GoalAccepted(goal_uuid=u(1)),
    )
    assert server.step(ins.GoalStarted(goal_uuid=u(1), now=T0)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        start_child(5),
        feedback(u(1), "underway", 5),
        status(1, RUNNING, "underway", 5),
    )
    assert server.status_message(s(7)) == status(1, RUNNING, "underway", 5, s(7)).message
    decision = server.accept(next_goal(1, 6))
    assert isinstance(decision, outs.Rejected)
    assert decision.reason is RejectReason.BUSY


@pytest.mark.spec("R3.1", "R8.4")
@pytest.mark.parametrize("cls", SERVERS)
def test_the_server_agrees_with_the_pure_machine(cls: type[RobotServer]) -> None:
    server = _running(cls)
    run = Run()
    run.begin(event_id=1)
    run.submit(u(1), next_goal(1, 5))
    assert server.state == run.state
    assert server.step(ins.ChildFinished(status="completed", now=T0)) == run.child_end("completed")
    assert server.state == run.state


@pytest.mark.spec("R8.1")
@pytest.mark.parametrize("cls", SERVERS)
def test_snapshot_and_restore_continue_the_same_run(cls: type[RobotServer]) -> None:
    server = _running(cls)
    restored = cls.restore(server.snapshot(), CONFIG)
    assert type(restored) is cls
    assert restored.state == server.state
    finished = ins.ChildFinished(status="completed", now=T0)
    assert restored.step(finished) == server.step(finished)


@pytest.mark.spec("R3.3")
def test_a_state_of_another_robot_is_refused() -> None:
    with pytest.raises(ValueError, match="r1"):
        RobotServer(FLEET, "r2", CONFIG, State.new(FLEET, ROBOT))


# --------------------------------------------------------------------------- Execution: reports


@pytest.mark.spec("R7.1", "R7.2", "R7.4")
@pytest.mark.parametrize(
    ("method", "reported", "tier"),
    [
        (Execution.underway, "underway", "info"),
        (Execution.delayed, "delayed", "warning"),
        (Execution.blocked, "blocked", "warning"),
        (Execution.error, "error", "error"),
    ],
)
def test_execution_reports_with_their_tiers(
    method: Callable[..., tuple[object, ...]], reported: str, tier: str
) -> None:
    server = _running()
    execution = Execution(server, 5)
    log = entry(0, tier, T0, "note")
    expected: tuple[object, ...] = (outs.Log(entry=log), feedback(u(1), reported, 5, log))
    if reported != "underway":
        expected += (status(1, RUNNING, reported, 5),)
    assert method(execution, "note", now=T0) == expected
    assert method(execution, now=T0) == (feedback(u(1), reported, 5),)
    assert execution.okay()


@pytest.mark.spec("R8.1", "R8.2")
def test_execution_finished() -> None:
    server = _running()
    execution = Execution(server, 5)
    assert execution.finished(now=T0) == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5),
    )
    assert not execution.okay()


@pytest.mark.spec("R8.2")
def test_execution_finished_with_a_status() -> None:
    server = _running()
    execution = Execution(server, 5)
    assert execution.finished(now=T0, status=Status.FAILED)[0] == answer(u(1), SUCCEEDED, "", "failed", 5)


# --------------------------------------------------------------------------- Execution: cancel and kill


@pytest.mark.spec("R10.3", "R8.2")
def test_automatic_cancel_finishes_the_child_at_once() -> None:
    server = _running()
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


@pytest.mark.spec("R9.3", "R8.2", "R8.3")
def test_automatic_kill_finishes_the_child_killed() -> None:
    server = _running()
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
    server = _running()
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


@pytest.mark.spec("R13.2", "R13.4")
def test_without_automatic_cancel_a_kill_ends_killed() -> None:
    server = _running()
    execution = Execution(server, 5, automatic_cancel=False)
    server.step(ins.TaskKill(now=T0))
    assert execution.kill(now=T0) == ()
    assert execution.finished(now=T0) == (
        answer(u(1), ABORTED, "", "killed", 5),
        outs.DynamicEventFinished(status="killed"),
        status(1, INACTIVE, "uninitialized", 0),
    )


# --------------------------------------------------------------------------- Execution: after the end


@pytest.mark.spec("R18.4")
@pytest.mark.parametrize("automatic", [True, False])
def test_after_finishing_every_method_returns_nothing(automatic: bool) -> None:
    server = _running()
    execution = Execution(server, 5, automatic_cancel=automatic)
    if automatic:
        execution.cancel(now=T0)
    else:
        execution.finished(now=T0)
    state = server.state
    calls: list[Callable[[], tuple[object, ...]]] = [
        lambda: execution.underway("x", now=T0),
        lambda: execution.delayed("x", now=T0),
        lambda: execution.blocked("x", now=T0),
        lambda: execution.error("x", now=T0),
        lambda: execution.finished(now=T0),
        lambda: execution.cancel(now=T0),
        lambda: execution.kill(now=T0),
    ]
    for call in calls:
        assert call() == ()
    assert server.state == state
    assert not execution.okay()
    execution.update_remaining_time(12.5)
    assert execution.remaining_time == 12.5
    assert "finished" in repr(execution)
