"""docs/spec.md sections 2 (phase and status) and 3 (begin)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.server import outputs as outs
from dynevent.server.machine import State, status_message
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Time
from dynevent.wire.vocab import RejectReason
from scenario import (
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
    deferred,
    feedback,
    finished_goal,
    ignored,
    next_goal,
    rejected,
    running,
    s,
    status,
    time,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R2.1


@pytest.mark.spec("R2.1")
def test_phase_follows_a_whole_run() -> None:
    run = Run()
    assert run.phase is INACTIVE
    run.begin(event_id=1)
    assert run.phase is WAITING
    run.submit(u(1), next_goal(1, 5))
    assert run.phase is RUNNING
    run.child_end("completed")
    assert run.phase is WAITING
    run.submit(u(2), finished_goal(1))
    assert run.phase is INACTIVE


@pytest.mark.spec("R2.1", "R9.3")
def test_the_running_slot_is_held_while_a_cancel_is_in_progress() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.phase is RUNNING
    assert run.state.running is not None
    assert run.state.running.goal_uuid == u(1)
    run.child_end("canceled")
    assert run.phase is WAITING


@pytest.mark.spec("R2.1", "R6.3")
def test_a_deferred_child_holds_the_running_slot() -> None:
    run = deferred(child_id=5)
    assert run.phase is RUNNING


@pytest.mark.spec("R2.1")
def test_phase_numbers() -> None:
    assert (INACTIVE.value, WAITING.value, RUNNING.value) == (0, 1, 2)


# --------------------------------------------------------------------------- R2.2


@pytest.mark.spec("R2.2")
def test_status_message_of_each_phase() -> None:
    now = s(12.5) + 7
    run = Run()
    assert status_message(run.state, now) == DynamicEventStatus(
        dynamic_event_seq=0,
        dynamic_state=0,
        status="uninitialized",
        id=0,
        time=Time(sec=12, nanosec=500_000_007),
    )
    run.begin(event_id=40)
    assert status_message(run.state, now) == status(1, WAITING, "standby", 40, now).message
    run.submit(u(1), next_goal(1, 41))
    run.progress("delayed")
    assert status_message(run.state, now) == status(1, RUNNING, "delayed", 41, now).message
    run.child_end("completed")
    assert status_message(run.state, now) == status(1, WAITING, "standby", 41, now).message  # R2.2
    run.submit(u(2), finished_goal(1))
    # INACTIVE keeps the seq but reports uninitialized and id 0, whatever the stored status.
    assert run.state.status == "completed"
    assert status_message(run.state, now) == status(1, INACTIVE, "uninitialized", 0, now).message


@pytest.mark.spec("R2.2")
def test_status_message_time_is_the_inputs_now_even_before_1970() -> None:
    run = Run().at(-1)
    outputs = run.begin(event_id=3)
    assert outputs[-1] == status(1, WAITING, "standby", 3, -1)
    assert outputs[-1].message.time == Time(sec=-1, nanosec=999_999_999)


# --------------------------------------------------------------------------- R2.3


@pytest.mark.spec("R2.3")
def test_steps_that_keep_the_status_message_publish_none() -> None:
    run = running(child_id=5)
    assert run.progress("underway") == (feedback(u(1), "underway", 5),)
    assert run.request(u(9), next_goal(1, 6)) == (rejected(u(9), RejectReason.BUSY, current_id=5),)
    assert run.tick() == ()
    assert run.interrupt() == (outs.InterruptChild(id=5),)
    assert run.resume() == (outs.ResumeChild(id=5),)
    assert run.submit(u(2), cancel_goal(1, 5)) == (outs.ExecuteGoal(goal_uuid=u(2)), outs.CancelChild(id=5))
    assert not any(isinstance(output, outs.PublishStatus) for output in run.query())


@pytest.mark.spec("R2.3")
def test_status_message_is_last_and_describes_the_state_after_the_whole_step() -> None:
    run = running(child_id=5)
    run.at(s(200))
    outputs = run.child_end("completed")
    # the goal is answered first; the message already says WAITING, standby, the event's own id
    assert outputs == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5, s(200)),
    )
    assert outputs[-1].message == status_message(run.state, s(200))


@pytest.mark.spec("R2.3")
def test_a_changed_status_alone_publishes() -> None:
    run = running(child_id=5)
    assert run.progress("blocked") == (feedback(u(1), "blocked", 5), status(1, RUNNING, "blocked", 5))
    assert run.progress("blocked") == (feedback(u(1), "blocked", 5),)


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
