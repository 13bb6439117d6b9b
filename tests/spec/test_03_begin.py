"""§3. Begin: the tests of the rules of docs/spec.md §3.

The section's conformance vectors are src/dynevent/conformance/vectors/03-begin.json.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import RobotServer
from dynevent.server.machine import State
from dynevent.wire.messages import DynamicEventDescription, Time
from dynevent.wire.vocab import RejectReason
from support.scenario import (
    CONFIG,
    DESC,
    FLEET,
    INACTIVE,
    ROBOT,
    RUNNING,
    SERVER_CLASSES,
    T0,
    WAITING,
    Run,
    feedback,
    ignored,
    next_goal,
    running,
    running_server,
    s,
    start_child,
    status,
    time,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R3.1


@pytest.mark.spec("R3.1")
def test_begin_activates_the_dynamic_event() -> None:
    run = Run()
    run.begin(event_id=17, description=DESC)
    state = run.state
    assert (state.seq, state.active, state.event_id, state.description, state.status, state.last_id) == (
        1,
        True,
        17,
        DESC,
        "standby",
        17,
    )
    assert state.task_signal == ""
    assert state.running is None


@pytest.mark.spec("R3.1")
def test_each_begin_numbers_a_new_run_and_clears_the_task_signal() -> None:
    run = waiting(event_id=1)
    run.task_cancel()
    assert run.state.task_signal == "canceled"
    assert not run.state.active
    run.begin(event_id=2)
    assert (run.state.seq, run.state.task_signal, run.state.status, run.state.last_id) == (
        2,
        "",
        "standby",
        2,
    )


@pytest.mark.spec("R3.1", "R3.3")
@given(seq=st.integers(0, 2**32 - 2), event_id=st.integers(0, 2**64 - 1))
def test_begin_outputs_for_any_seq_and_event_id(seq: int, event_id: int) -> None:
    run = Run(state=State(fleet=FLEET, robot=ROBOT, seq=seq))
    assert run.begin(event_id=event_id) == (
        outs.PublishBegin(
            message=DynamicEventDescription(
                fleet=FLEET, robot=ROBOT, dynamic_event_seq=seq + 1, description=DESC, start_time=time(T0)
            )
        ),
        status(seq + 1, WAITING, "standby", event_id),
    )
    assert run.state.seq == seq + 1
    assert run.state.last_id == event_id


@pytest.mark.spec("R3.1", "R4.16", "R6.4", "R2.2")
@pytest.mark.parametrize("cls", SERVER_CLASSES)
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
@pytest.mark.parametrize("cls", SERVER_CLASSES)
def test_the_server_agrees_with_the_pure_machine(cls: type[RobotServer]) -> None:
    server = running_server(cls)
    run = Run()
    run.begin(event_id=1)
    run.submit(u(1), next_goal(1, 5))
    assert server.state == run.state
    assert server.step(ins.ChildFinished(status="completed", now=T0)) == run.child_end("completed")
    assert server.state == run.state


# --------------------------------------------------------------------------- R3.2


@pytest.mark.spec("R3.2", "R3.1")
def test_seq_wraps_and_the_wrap_is_reported_first() -> None:
    run = Run().evolve(seq=2**32 - 1)
    assert run.begin(event_id=4) == (
        outs.SeqWrapped(previous=4294967295, seq=0),
        outs.PublishBegin(
            message=DynamicEventDescription(
                fleet=FLEET, robot=ROBOT, dynamic_event_seq=0, description=DESC, start_time=time(T0)
            )
        ),
        status(0, WAITING, "standby", 4),
    )
    assert run.state.seq == 0
    # goals name the new seq; the old one is now a mismatch
    assert run.request(u(1), next_goal(0, 5)) == (outs.GoalAccepted(goal_uuid=u(1)),)


@pytest.mark.spec("R3.2")
def test_no_wrap_notice_before_the_wrap() -> None:
    run = Run().evolve(seq=2**32 - 2)
    outputs = run.begin()
    assert not any(isinstance(output, outs.SeqWrapped) for output in outputs)
    assert run.state.seq == 2**32 - 1


# --------------------------------------------------------------------------- R3.3


@pytest.mark.spec("R3.3")
def test_publish_begin_carries_the_full_description_and_start_time() -> None:
    description = '{"estimate":{"category":"go_to_place","description":"lobby"},"x-custom":{"k":[null]}}'
    run = Run().at(s(1_700_000_000.25))
    outputs = run.begin(event_id=9, description=description)
    assert outputs[0] == outs.PublishBegin(
        message=DynamicEventDescription(
            fleet="tinyRobot",
            robot="r1",
            dynamic_event_seq=1,
            description=description,
            start_time=Time(sec=1_700_000_000, nanosec=250_000_000),
        )
    )


@pytest.mark.spec("R3.3")
def test_a_state_of_another_robot_is_refused() -> None:
    with pytest.raises(ValueError, match="r1"):
        RobotServer(FLEET, "r2", CONFIG, State.new(FLEET, ROBOT))


# --------------------------------------------------------------------------- R3.4


@pytest.mark.spec("R3.4", "R18.1")
def test_begin_while_waiting_is_ignored() -> None:
    run = waiting(event_id=1)
    outputs = run.begin(event_id=2)
    run.assert_ignored(outputs, "begin")


@pytest.mark.spec("R3.4", "R18.1")
def test_begin_while_running_is_ignored() -> None:
    run = running(child_id=5)
    outputs = run.begin(event_id=2)
    assert outputs == ignored("begin")
    assert run.state == run.before
