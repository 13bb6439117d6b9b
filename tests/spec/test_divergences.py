"""Regression tests for docs/divergences.md: where dynevent departs from rmf_ros2, and why.

Each test builds the exact situation in which rmf_ros2 misbehaves (or
behaves otherwise by design) and asserts dynevent's behaviour; where a
compatibility option exists, a second test asserts that the option
reproduces rmf_ros2.  The last tests keep docs/divergences.md and this file
in step: every test the document names exists here, every test here is named
there, and every rule the document cites is a rule of docs/spec.md that the
section's tests cite too.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State, status_message
from dynevent.wire.messages import DescriptionResponse
from dynevent.wire.vocab import Compatibility, IdPolicy, RejectReason
from support.scenario import (
    ABORTED,
    ANY_TEXT,
    CANCEL_ID,
    CANCELED,
    CATEGORIES,
    CONFIG,
    DESC,
    FLEET,
    IDLE_CANCEL,
    INACTIVE,
    INVALID_EVENT_TYPE,
    NOT_RUNNING,
    PARSE_FAILURE,
    RACE,
    RMF_ROS2,
    ROBOT,
    RUNNING,
    SHUTTING_DOWN,
    SUCCEEDED,
    T0,
    WAITING,
    Run,
    aborted,
    answer,
    cancel_goal,
    entry,
    feedback,
    finished_goal,
    goal,
    next_goal,
    rejected,
    running,
    start_child,
    status,
    u,
    waiting,
)

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "divergences.md"
SPEC = ROOT / "docs" / "spec.md"

U32_MAX = 2**32 - 1


def accepted(uuid: str) -> tuple[outs.GoalAccepted]:
    return (outs.GoalAccepted(goal_uuid=uuid),)


# --------------------------------------------------------------------------- D1


@pytest.mark.spec("R9.3", "R2.1", "R4.6", "R8.3", "R19.2")
def test_a_cancel_keeps_the_robot_running_until_the_child_ends() -> None:
    run = running(child_id=5, uuid=u(1))
    assert run.request(u(2), cancel_goal(run.seq, 5)) == accepted(u(2))
    # the CANCEL starts: the child is told to stop, nothing else changes (no status message)
    assert run.start(u(2)) == (outs.ExecuteGoal(goal_uuid=u(2)), outs.CancelChild(id=5))
    assert run.phase is RUNNING
    # rmf_ros2 would now count the robot as idle and accept this NEXT
    assert run.request(u(3), next_goal(run.seq, 6)) == (rejected(u(3), RejectReason.BUSY, current_id=5),)
    assert run.request(u(4), finished_goal(run.seq)) == (rejected(u(4), RejectReason.BUSY, current_id=5),)
    # the child really ends: both goals are answered, then the robot is free
    assert run.child_end("canceled") == (
        answer(u(1), ABORTED, text="canceled", id=5),
        answer(u(2), SUCCEEDED, text="canceled", id=5),
        status(run.seq, WAITING, "standby", 5),  # the highest id used (R2.2)
    )
    assert run.request(u(3), next_goal(run.seq, 6)) == accepted(u(3))


# --------------------------------------------------------------------------- D2


@pytest.mark.spec("R2.3", "R8.4", "R19.5")
def test_the_status_after_a_child_ends_says_waiting() -> None:
    run = running(child_id=5, uuid=u(1))
    outputs = run.child_end("completed")
    # rmf_ros2 publishes (RUNNING, completed, 5) here and nothing after it
    assert outputs == (
        answer(u(1), SUCCEEDED, text="completed", id=5),
        status(run.seq, WAITING, "standby", 5),  # WAITING, and the highest id used (R2.2)
    )
    assert run.phase is WAITING
    assert run.state.running is None


# --------------------------------------------------------------------------- D3, D4


@pytest.mark.spec("R14.1", "R14.3", "R14.4", "R6.4")
def test_a_resume_clears_an_interruption_handed_to_the_child() -> None:
    run = running(child_id=5, uuid=u(1))
    assert run.interrupt() == (outs.InterruptChild(id=5),)
    assert run.resume() == (outs.ResumeChild(id=5),)
    assert not run.state.interrupted
    run.child_end("completed")
    # rmf_ros2 never cleared the interruption: this child would be deferred forever
    assert run.submit(u(2), next_goal(run.seq, 6)) == (
        outs.ExecuteGoal(goal_uuid=u(2)),
        start_child(6),
        feedback(u(2), "underway", 6),
        status(run.seq, RUNNING, "underway", 6),
    )


@pytest.mark.spec("R14.2", "R6.3", "R14.5")
def test_an_interruption_without_a_child_is_confirmed_at_once() -> None:
    run = waiting()
    # rmf_ros2 returns a resume handle and never confirms
    assert run.interrupt() == (outs.InterruptConfirmed(),)
    assert run.submit(u(1), next_goal(run.seq, 5)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        feedback(u(1), "queued", 5),
        status(run.seq, RUNNING, "queued", 5),
    )
    assert run.resume() == (
        start_child(5),
        feedback(u(1), "underway", 5),
        status(run.seq, RUNNING, "underway", 5),
    )


# --------------------------------------------------------------------------- D5


@pytest.mark.spec("R5.2", "R3.1")
def test_a_goal_accepted_for_one_run_cannot_start_in_the_next() -> None:
    run = waiting(event_id=1)
    assert run.request(u(1), next_goal(1, 5)) == accepted(u(1))
    assert run.request(u(2), finished_goal(1)) == accepted(u(2))
    run.task_cancel()  # run 1 ends before its goals start
    run.begin(event_id=1)  # run 2
    assert run.seq == 2
    # rmf_ros2 does not look at the seq again: the NEXT would run and the FINISHED end run 2
    assert run.start(u(1)) == (outs.ExecuteGoal(goal_uuid=u(1)), aborted(u(1), RACE))
    assert run.start(u(2)) == (outs.ExecuteGoal(goal_uuid=u(2)), aborted(u(2), RACE))
    assert run.phase is WAITING
    assert run.state.seq == 2


# --------------------------------------------------------------------------- D6


@pytest.mark.spec("R4.15", "R4.2", "R4.7", "R4.9", "R4.12")
def test_every_rejection_carries_a_reason_and_its_values() -> None:
    run = waiting(event_id=1)
    assert run.request(u(1), next_goal(run.seq + 1, 5)) == (
        rejected(
            u(1), RejectReason.SEQ_MISMATCH, text="Expected 1, received 2", expected_seq=1, received_seq=2
        ),
    )
    assert run.request(u(2), next_goal(run.seq, 5, category="fly")) == (
        rejected(u(2), RejectReason.UNSUPPORTED_CATEGORY, categories=("go_to_place", "perform_action")),
    )
    (not_json,) = run.request(u(3), next_goal(run.seq, 5, description="{"))
    assert isinstance(not_json, outs.GoalRejected)
    assert not_json.rejection.reason is RejectReason.DESCRIPTION_NOT_JSON
    assert len(not_json.rejection.errors) == 1
    assert not_json.rejection.execution_failure == f"{PARSE_FAILURE}\n -- {not_json.rejection.errors[0]}"
    assert run.request(u(4), next_goal(run.seq, 1)) == (
        rejected(u(4), RejectReason.STALE_ID, current_id=1, requested_id=1),
    )
    assert run.state == run.before  # a refusal changes nothing


# --------------------------------------------------------------------------- D7


@pytest.mark.spec("R4.4", "R4.5")
def test_undefined_event_types_are_rejected_at_request_time() -> None:
    run = waiting()
    for number, (event_type, reason) in enumerate(
        (
            (0, RejectReason.UNINITIALIZED_EVENT_TYPE),
            (4, RejectReason.UNKNOWN_EVENT_TYPE),
            (U32_MAX, RejectReason.UNKNOWN_EVENT_TYPE),
        ),
        start=1,
    ):
        assert run.request(u(number), goal(run.seq, event_type)) == (
            rejected(u(number), reason, execution_failure=INVALID_EVENT_TYPE),
        )
    assert run.state.queued == ()


@pytest.mark.spec("R17.1", "R17.2")
def test_rmf_ros2_mode_accepts_then_aborts_undefined_event_types() -> None:
    run = waiting(config=RMF_ROS2)
    for number, event_type in enumerate((0, 4, U32_MAX), start=1):
        assert run.request(u(number), goal(run.seq, event_type)) == accepted(u(number))
        assert run.start(u(number)) == (
            outs.ExecuteGoal(goal_uuid=u(number)),
            aborted(u(number), INVALID_EVENT_TYPE),
        )
    assert run.phase is WAITING


# --------------------------------------------------------------------------- D8


@pytest.mark.spec("R4.13", "R4.14")
def test_bad_cancels_are_rejected_at_request_time() -> None:
    run = waiting()
    assert run.request(u(1), cancel_goal(run.seq, 1)) == (
        rejected(u(1), RejectReason.CANCEL_IDLE, execution_failure=IDLE_CANCEL),
    )
    run.submit(u(2), next_goal(run.seq, 5))
    assert run.request(u(3), cancel_goal(run.seq, 4)) == (
        rejected(
            u(3), RejectReason.CANCEL_ID_MISMATCH, current_id=5, requested_id=4, execution_failure=CANCEL_ID
        ),
    )
    assert run.state.queued == ()


@pytest.mark.spec("R17.1", "R17.2", "R9.1", "R9.2")
def test_rmf_ros2_mode_accepts_then_aborts_bad_cancels() -> None:
    run = waiting(event_id=1, config=RMF_ROS2)
    assert run.request(u(1), cancel_goal(run.seq, 1)) == accepted(u(1))
    assert run.start(u(1)) == (outs.ExecuteGoal(goal_uuid=u(1)), aborted(u(1), IDLE_CANCEL))
    run.submit(u(2), next_goal(run.seq, 99))
    assert run.state.running is not None
    child = run.state.running.child_id
    assert run.request(u(3), cancel_goal(run.seq, child + 1)) == accepted(u(3))
    assert run.start(u(3)) == (outs.ExecuteGoal(goal_uuid=u(3)), aborted(u(3), CANCEL_ID))
    assert run.phase is RUNNING


# --------------------------------------------------------------------------- D9


@pytest.mark.spec("R7.2", "R7.3")
def test_log_entries_are_numbered_one_by_one_per_robot() -> None:
    run = running(child_id=5, uuid=u(1))
    first = entry(0, "info", T0, "first")
    second = entry(1, "warning", T0, "second")
    assert run.progress("underway", log="first") == (
        outs.Log(entry=first),
        feedback(u(1), "underway", 5, first),
    )
    assert run.progress("delayed", log="second", tier="warning") == (
        outs.Log(entry=second),
        feedback(u(1), "delayed", 5, second),
        status(run.seq, RUNNING, "delayed", 5),
    )
    run.child_end("completed")
    run.task_cancel()  # log entry 2, "Received signal to cancel"; the run ends
    run.begin(event_id=1)
    run.submit(u(2), next_goal(run.seq, 6))
    # rmf_ros2 would number this entry with the dynamic event seq (2)
    assert run.progress("underway", log="third")[0] == outs.Log(entry=entry(3, "info", T0, "third"))
    run.evolve(log_seq=U32_MAX)
    wrapped = [run.progress("underway", log=text)[0] for text in ("last", "wrapped")]
    assert [output.entry.seq for output in wrapped if isinstance(output, outs.Log)] == [U32_MAX, 0]


# --------------------------------------------------------------------------- D10


@pytest.mark.spec("R6.2", "R4.12", "R5.2")
def test_the_next_goal_names_its_child() -> None:
    run = waiting(event_id=1)
    assert run.submit(u(1), next_goal(run.seq, 40)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        start_child(40),
        feedback(u(1), "underway", 40),
        status(run.seq, RUNNING, "underway", 40),
    )
    run.child_end("completed")
    assert run.request(u(2), next_goal(run.seq, 40)) == (
        rejected(u(2), RejectReason.STALE_ID, current_id=40, requested_id=40),
    )
    # two NEXTs accepted together: the first to start uses its id, the other has gone stale
    assert run.request(u(3), next_goal(run.seq, 42)) == accepted(u(3))
    assert run.request(u(4), next_goal(run.seq, 41)) == accepted(u(4))
    assert run.start(u(3))[1] == start_child(42)
    run.child_end("completed")
    assert run.start(u(4)) == (outs.ExecuteGoal(goal_uuid=u(4)), aborted(u(4), RACE))


@pytest.mark.spec("R17.3", "R6.2")
def test_the_adapter_id_policy_numbers_children_itself() -> None:
    assert RMF_ROS2.id_policy is IdPolicy.ADAPTER
    assert RMF_ROS2.compatibility is Compatibility.RMF_ROS2
    config = ServerConfig(categories=CATEGORIES, id_policy=IdPolicy.ADAPTER)
    run = waiting(event_id=1, config=config)
    assert run.submit(u(1), next_goal(run.seq, 40))[1] == start_child(2)
    run.child_end("completed")
    assert run.submit(u(2), next_goal(run.seq, 0))[1] == start_child(3)  # any id will do


# --------------------------------------------------------------------------- D11, D12


@pytest.mark.spec("R12.2", "R12.1", "R19.4")
def test_a_clamped_stubborn_period_is_reported() -> None:
    run = waiting()
    warning = entry(0, "warning", T0, ANY_TEXT)
    assert run.submit(u(1), next_goal(run.seq, 5, stubborn=0.5)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        outs.StubbornClamped(requested=0.5, applied=2.0),
        outs.Log(entry=warning),
        start_child(5),
        feedback(u(1), "underway", 5, warning),
        status(run.seq, RUNNING, "underway", 5),
    )
    assert run.child_end("completed") == (
        answer(u(1), SUCCEEDED, text="completed", id=5),
        outs.StubbornBegin(period=2.0, since=T0, map_name=None, x=0.0, y=0.0),
        status(run.seq, WAITING, "standby", 5),
    )


@pytest.mark.spec("R4.11")
def test_a_non_finite_stubborn_period_is_rejected() -> None:
    run = waiting()
    for number, period in enumerate((math.nan, math.inf, -math.inf), start=1):
        assert run.request(u(number), next_goal(run.seq, 5, stubborn=period)) == (
            rejected(u(number), RejectReason.NON_FINITE_STUBBORN_PERIOD),
        )
    # CANCEL and FINISHED do not use the period: it is not checked
    run.submit(u(4), next_goal(run.seq, 5))
    nan_cancel = goal(run.seq, 2, id=5, stubborn=math.nan)
    assert run.request(u(5), nan_cancel) == accepted(u(5))


# --------------------------------------------------------------------------- D13


@pytest.mark.spec("R3.2", "R3.1")
def test_a_seq_wrap_is_reported() -> None:
    run = Run(CONFIG, attrs.evolve(State.new(FLEET, ROBOT), seq=U32_MAX))
    outputs = run.begin(event_id=1)
    assert outputs[0] == outs.SeqWrapped(previous=U32_MAX, seq=0)
    begin = outputs[1]
    assert isinstance(begin, outs.PublishBegin)
    assert begin.message.dynamic_event_seq == 0
    assert outputs[2:] == (status(0, WAITING, "standby", 1),)
    assert run.request(u(1), next_goal(0, 5)) == accepted(u(1))


# --------------------------------------------------------------------------- D14


@pytest.mark.spec("R15.1", "R15.2", "R4.1", "R19.1")
def test_shutdown_answers_every_open_goal_once() -> None:
    run = running(child_id=5, uuid=u(1))
    run.submit(u(2), cancel_goal(run.seq, 5))  # a CANCEL waiting for the child
    assert run.request(u(3), cancel_goal(run.seq, 5)) == accepted(u(3))  # accepted, not started
    assert run.shutdown() == (
        aborted(u(1), SHUTTING_DOWN),
        aborted(u(2), SHUTTING_DOWN),
        outs.ExecuteGoal(goal_uuid=u(3)),
        aborted(u(3), SHUTTING_DOWN),
        status(run.seq, INACTIVE, "uninitialized", 0),
    )
    assert run.request(u(4), next_goal(run.seq, 6)) == (
        rejected(u(4), RejectReason.SHUTTING_DOWN, execution_failure=SHUTTING_DOWN),
    )
    run.assert_ignored(run.begin(), "begin")
    run.assert_ignored(run.start(u(3)), "goal_started")


# --------------------------------------------------------------------------- D15


@pytest.mark.spec("R10.5", "R10.1", "R10.3", "R8.2")
def test_an_action_level_cancel_is_accepted_only_for_an_open_goal() -> None:
    run = running(child_id=5, uuid=u(1))
    # rmf_ros2 accepts every cancel request
    assert run.cancel(u(9)) == (outs.CancelResponse(goal_uuid=u(9), accepted=False),)
    run.child_end("completed")
    assert run.cancel(u(1)) == (outs.CancelResponse(goal_uuid=u(1), accepted=False),)
    # a goal not started yet: answered at once
    assert run.request(u(2), next_goal(run.seq, 6)) == accepted(u(2))
    assert run.cancel(u(2)) == (
        outs.CancelResponse(goal_uuid=u(2), accepted=True),
        answer(u(2), CANCELED, NOT_RUNNING),
    )
    # the running goal: the child is told to stop and the goal ends canceled when it does
    run.submit(u(3), next_goal(run.seq, 7))
    assert run.cancel(u(3)) == (outs.CancelResponse(goal_uuid=u(3), accepted=True), outs.CancelChild(id=7))
    assert run.child_end("canceled")[0] == answer(u(3), CANCELED, text="canceled", id=7)


# --------------------------------------------------------------------------- D16


@pytest.mark.spec("R7.4", "R13.1")
def test_only_a_task_signal_freezes_the_status_mirror() -> None:
    run = running(child_id=5, uuid=u(1))
    assert run.progress("skipped")[-1] == status(run.seq, RUNNING, "skipped", 5)
    # rmf_ros2 keeps `skipped` until the next child starts or this one ends
    assert run.progress("underway")[-1] == status(run.seq, RUNNING, "underway", 5)
    assert run.task_cancel()[-1] == status(run.seq, RUNNING, "canceled", 5)
    assert run.progress("underway") == (feedback(u(1), "underway", 5),)
    assert run.state.status == "canceled"


# --------------------------------------------------------------------------- D17


@pytest.mark.spec("R16.1", "R16.2")
def test_the_description_service_answers_from_the_state() -> None:
    run = Run()
    assert run.query() == (outs.DescriptionAnswer(response=DescriptionResponse()),)
    run.begin(event_id=1)
    assert run.query() == (
        outs.DescriptionAnswer(
            response=DescriptionResponse(running=True, status="standby", description=DESC, id=1)
        ),
    )
    run.submit(u(1), next_goal(run.seq, 5))
    assert run.query() == (
        outs.DescriptionAnswer(
            response=DescriptionResponse(running=True, status="underway", description=DESC, id=5)
        ),
    )


# --------------------------------------------------------------------------- D2 (compatibility), D10, D16


@pytest.mark.spec("R17.4", "R2.3")
def test_rmf_ros2_mode_publishes_running_at_a_childs_end() -> None:
    run = running(config=RMF_ROS2, uuid=u(1))  # child 2, numbered by the adapter
    assert run.child_end("completed")[-1] == status(run.seq, RUNNING, "completed", 2)
    assert run.phase is WAITING  # the stuck robot is not reproduced: the next NEXT is accepted
    assert run.request(u(2), next_goal(run.seq, 0)) == accepted(u(2))


@pytest.mark.spec("R17.4", "R9.3")
def test_rmf_ros2_mode_publishes_waiting_at_the_end_of_a_cancelled_child() -> None:
    """After a CANCEL goal the message says WAITING with the child's final status, as the deployed
    adapter's does once its CANCEL has freed the slot (D28); the machine itself kept the robot RUNNING
    until the end, and answers both goals then (D1 is not reproduced)."""
    run = running(config=RMF_ROS2, uuid=u(1))
    run.request(u(2), cancel_goal(run.seq, 2))
    run.start(u(2))
    assert run.phase is RUNNING
    outputs = run.child_end("canceled")
    assert outputs[-1] == status(run.seq, WAITING, "canceled", 2)
    assert answer(u(2), SUCCEEDED, text="canceled", id=2) in outputs


@pytest.mark.spec("R20.2", "R17.4")
def test_dynevents_client_reads_rmf_ros2s_running_after_a_childs_end_as_waiting() -> None:
    from dynevent import client

    run = running(config=RMF_ROS2, uuid=u(1))
    seen = run.child_end("completed")[-1]
    assert isinstance(seen, outs.PublishStatus)
    view = client.step(
        client.ClientState.new("00000000000000cd"), client.StatusReceived(message=seen.message)
    )
    (send,) = client.request_next(view.state, "go_to_place", '"b"', now=T0).outputs
    assert isinstance(send, client.SendGoal), send  # not refused locally as busy
    assert run.request(u(2), send.goal) == accepted(u(2))


@pytest.mark.spec("R20.1", "R2.2", "R6.2")
def test_a_client_that_keeps_no_state_works_in_standard_mode() -> None:
    run = waiting(event_id=7)
    for child in (8, 9):
        seen = status_message(run.state, T0)  # all a one-shot client knows
        run.submit(u(child), next_goal(seen.dynamic_event_seq, seen.id + 1))
        run.child_end("completed")
        assert status_message(run.state, T0).id == child
    run.submit(u(10), next_goal(run.seq, 0))  # id 0: the server numbers the child
    assert run.state.running is not None and run.state.running.child_id == 10


@pytest.mark.spec("R17.5", "R7.4")
def test_rmf_ros2_mode_shows_the_childs_status_after_a_task_signal() -> None:
    run = running(config=RMF_ROS2, uuid=u(1))
    run.task_cancel()
    assert run.progress("underway")[-1] == status(run.seq, RUNNING, "underway", 2)
    assert run.state.status == "canceled"


# --------------------------------------------------------------------------- D18, D19, D20, D21


@pytest.mark.spec("R2.3", "R7.1", "R17.5")
def test_a_status_message_is_published_only_when_it_changes() -> None:
    run = running(child_id=5, uuid=u(1))
    assert run.progress("underway") == (feedback(u(1), "underway", 5),)  # rmf_ros2 adds a status
    compat = running(config=RMF_ROS2, uuid=u(1))
    assert compat.progress("underway")[-1] == status(compat.seq, RUNNING, "underway", 2)


@pytest.mark.spec("R3.3", "R17.6")
def test_the_begin_description_is_published_as_given() -> None:
    text = '{"estimate": {"category": "go_to_place", "description": "pantry"},  "category": "patrol"}'
    begin = Run().begin(event_id=1, description=text)[0]
    assert isinstance(begin, outs.PublishBegin) and begin.message.description == text
    compat = Run(RMF_ROS2).begin(event_id=1, description=text)[0]
    assert isinstance(compat, outs.PublishBegin)
    assert compat.message.description == (
        '{"category":"patrol","estimate":{"category":"go_to_place","description":"pantry"}}'
    )


@pytest.mark.spec("R1.4", "R2.2")
def test_a_fresh_server_has_a_status_to_publish_and_the_topics_their_depths() -> None:
    from dynevent.wire.names import BEGIN_TOPIC_DEPTH, ROBOT_BEGIN_TOPIC_DEPTH, STATUS_TOPIC_DEPTH

    message = status_message(State.new(FLEET, ROBOT), T0)
    assert (message.dynamic_event_seq, message.dynamic_state, message.status, message.id) == (
        0,
        0,
        "uninitialized",
        0,
    )
    assert (BEGIN_TOPIC_DEPTH, ROBOT_BEGIN_TOPIC_DEPTH, STATUS_TOPIC_DEPTH) == (100, 1, 1)


@pytest.mark.spec("R5.3", "R5.1", "R19.1")
def test_a_lost_race_is_executed_once_then_answered() -> None:
    from dynevent.server import inputs as ins

    run = running(child_id=5, uuid=u(1))
    outputs = run.step(ins.GoalSubmitted(goal_uuid=u(2), goal=next_goal(run.seq, 6), now=T0))
    assert outputs[0] == outs.ExecuteGoal(goal_uuid=u(2))
    assert len(outputs) == 2 and isinstance(outputs[1], outs.AnswerGoal)
    assert outputs[1].result.execution_failure.startswith(RACE)


# --------------------------------------------------------------------------- D22 to D25


@pytest.mark.spec("R4.17", "R4.7")
def test_a_dynamic_event_is_never_a_child_category() -> None:
    from dynevent.errors import InvalidConfig

    with pytest.raises(InvalidConfig):
        ServerConfig(categories={**CATEGORIES, "dynamic_event": CATEGORIES["go_to_place"]})
    run = waiting()
    nested = next_goal(run.seq, 5, category="dynamic_event", description="{}")
    assert run.request(u(1), nested)[0].rejection.reason is RejectReason.UNSUPPORTED_CATEGORY  # type: ignore[union-attr]


@pytest.mark.spec("R13.1", "R13.3", "R13.5", "R18.7")
def test_a_task_signal_is_told_and_a_kill_stays_a_kill() -> None:
    run = running(child_id=5, uuid=u(1))
    told = run.task_kill()
    assert any(isinstance(output, outs.PublishFeedback) for output in told)  # rmf_ros2 publishes nothing
    run.assert_ignored(run.task_cancel(), "task_cancel")  # rmf_ros2 overwrites killed with canceled
    assert run.child_end("killed")[-2] == outs.DynamicEventFinished(status="killed")
    deferred = waiting()
    deferred.interrupt()
    deferred.submit(u(2), next_goal(deferred.seq, 5))
    assert deferred.task_cancel()[1] == answer(u(2), ABORTED, text="canceled", id=5)  # answered at once


@pytest.mark.spec("R12.5", "R21.2")
def test_stubbornness_always_ends_with_stubborn_end() -> None:
    from dynevent.server import inputs as ins

    for end in ("next", "finished", "signal", "shutdown", "restart"):
        run = running(child_id=5, uuid=u(1), stubborn=3.0)
        run.child_end("canceled")  # a cancelled child asked for it too: stubborn, as in rmf_ros2
        assert run.state.stubborn is not None
        if end == "next":
            outputs = run.submit(u(2), next_goal(run.seq, 6))
        elif end == "finished":
            outputs = run.submit(u(2), finished_goal(run.seq))
        elif end == "signal":
            outputs = run.task_cancel()
        elif end == "shutdown":
            outputs = run.shutdown()
        else:
            outputs = run.step(ins.Restart(now=T0))
        assert outs.StubbornEnd() in outputs, end
        assert run.state.stubborn is None


@pytest.mark.spec("R21.1", "R21.3")
def test_a_restored_state_goes_on_with_its_run() -> None:
    from dynevent.server import inputs as ins
    from dynevent.server import snapshot

    run = running(child_id=5, uuid=u(1))
    restored = Run(CONFIG, snapshot.loads(snapshot.dumps(run.state)))
    outputs = restored.step(ins.Restart(now=T0))
    assert outputs[0] == aborted(u(1), "server restarted")
    assert outputs[-1] == status(run.seq, WAITING, "standby", 5)
    assert restored.request(u(2), next_goal(run.seq, 6)) == accepted(u(2))


# --------------------------------------------------------------------------- the document and this file


# --------------------------------------------------------------------------- D26


@pytest.mark.spec("R3.1", "R2.2")
def test_a_run_begins_waiting_standby() -> None:
    """The status a run's begin publishes, and the one a late client reads, says WAITING ``standby``
    (the deployed adapter's latched status then says WAITING ``uninitialized``)."""
    run = Run()
    published = [output for output in run.begin(event_id=1) if isinstance(output, outs.PublishStatus)]
    assert published == [status(run.seq, WAITING, "standby", 1)]
    assert status_message(run.state, T0) == published[0].message


# --------------------------------------------------------------------------- D27


@pytest.mark.spec("R12.1", "R12.3")
def test_a_stubborn_hold_refreshes_whatever_the_robot_reported() -> None:
    """A NEXT with a stubborn period, its child's end, then ticks: the hold begins where the robot was
    last seen (nowhere, here) and each refresh is a value (the deployed full_control adapter crashes
    at the first refresh, reading navigation parameters its robots lack)."""
    run = running(child_id=5, stubborn=3.0)
    assert run.child_end("completed")[1] == outs.StubbornBegin(
        period=3.0, since=T0, map_name=None, x=0.0, y=0.0
    )
    refreshed = run.tick("L1", 1.0, 2.0, now=T0 + 10**9)
    assert refreshed == (outs.StubbornHold(period=3.0, since=T0 + 10**9, map_name="L1", x=1.0, y=2.0),)
    assert run.state.stubborn is not None


# --------------------------------------------------------------------------- D28


@pytest.mark.spec("R8.4", "R9.3")
def test_the_status_after_a_cancelled_child_says_waiting_standby() -> None:
    """A CANCEL ends the child; the status then says WAITING ``standby`` with the child's id (the
    deployed adapter says WAITING ``canceled``; after a completed child, RUNNING ``completed``, D2)."""
    run = running(child_id=5)
    run.request(u(2), cancel_goal(run.seq, 5))
    run.start(u(2))
    outputs = run.child_end("canceled")
    assert outputs[-1] == status(run.seq, WAITING, "standby", 5)


# --------------------------------------------------------------------------- D29


@pytest.mark.spec("R13.1", "R9.3")
def test_a_cancel_goal_logs_nothing_of_a_task_signal() -> None:
    """``Received signal to cancel`` is a task signal's log line (R13.1); a CANCEL goal's child end
    writes none (the deployed adapter's go_to_place child writes it on any cancel)."""
    run = running(child_id=5)
    run.request(u(2), cancel_goal(run.seq, 5))
    outputs = run.start(u(2)) + run.child_end("canceled")
    logs = [output.entry.text for output in outputs if isinstance(output, outs.Log)]
    assert "Received signal to cancel" not in logs
    assert run.state.task_signal == ""


# --------------------------------------------------------------------------- D30


@pytest.mark.spec("R4.6", "R11.1")
def test_a_finished_while_a_child_runs_is_refused_busy() -> None:
    run = running(child_id=5)
    assert run.request(u(2), finished_goal(run.seq)) == (rejected(u(2), RejectReason.BUSY, current_id=5),)
    assert run.phase is RUNNING and run.state.active


# --------------------------------------------------------------------------- D31


@pytest.mark.spec("R10.3", "R8.2")
def test_an_action_level_cancel_of_the_running_next_stops_its_child() -> None:
    run = running(child_id=5)
    outputs = run.cancel(u(1))
    assert outs.CancelResponse(goal_uuid=u(1), accepted=True) in outputs
    assert outs.CancelChild(id=5) in outputs
    assert run.child_end("canceled")[0] == answer(u(1), CANCELED, text="canceled", id=5)


# --------------------------------------------------------------------------- D32


@pytest.mark.spec("R8.2", "R7.1")
def test_a_childs_end_is_in_its_goals_answer_not_its_feedback() -> None:
    """The child's final status reaches the client in its goal's answer; the machine publishes no
    feedback at the end (the deployed adapter sends one more feedback with the final status first)."""
    run = running(child_id=5)
    outputs = run.child_end("completed")
    assert not [output for output in outputs if isinstance(output, outs.PublishFeedback)]
    assert outputs[0] == answer(u(1), SUCCEEDED, text="completed", id=5)


@pytest.mark.spec("R17.7", "R8.2")
def test_rmf_ros2_mode_sends_a_childs_end_as_feedback_before_its_answer() -> None:
    run = running(config=RMF_ROS2, uuid=u(1))  # child 2, numbered by the adapter
    outputs = run.child_end("completed")
    assert outputs[0] == feedback(u(1), "completed", 2)
    assert outputs[1] == answer(u(1), SUCCEEDED, text="completed", id=2)


@pytest.mark.spec("R17.7", "R13.4")
def test_rmf_ros2_mode_sends_the_end_as_feedback_under_a_task_cancel_too() -> None:
    run = running(config=RMF_ROS2, uuid=u(1))
    run.step(ins.TaskCancel(now=T0))
    outputs = run.child_end("canceled")
    assert outputs[0] == feedback(u(1), "canceled", 2)
    assert outputs[1] == answer(u(1), ABORTED, text="canceled", id=2)


_META = {
    "test_the_document_and_this_file_name_the_same_tests",
    "test_the_document_cites_rules_of_the_spec_that_its_tests_cite",
}


def _sections() -> dict[str, tuple[set[str], list[str]]]:
    """Each ``## D<n>.`` section of docs/divergences.md: the rules it cites, the tests it names."""
    text = DOC.read_text(encoding="utf-8")
    sections: dict[str, tuple[set[str], list[str]]] = {}
    for block in re.split(r"^(?=## D\d+\.)", text, flags=re.MULTILINE)[1:]:
        title = block.splitlines()[0]
        # an item runs to the next item or the end of the section
        rules_line = re.search(r"^- \*\*Rules\*\*: (.*?)(?=^- |\Z)", block, flags=re.MULTILINE | re.DOTALL)
        tests_line = re.search(
            r"^- \*\*Regression tests?\*\*: (.*?)(?=^- |\Z)", block, flags=re.MULTILINE | re.DOTALL
        )
        assert rules_line and tests_line, f"{title}: needs a **Rules** and a **Regression test** line"
        rules = set(re.findall(r"R\d+\.\d+", rules_line.group(1)))
        tests = re.findall(r"`(test_\w+)`", tests_line.group(1))
        assert rules and tests, f"{title}: names no rule or no test"
        sections[title] = (rules, tests)
    return sections


def _tests_here() -> dict[str, set[str]]:
    """The regression tests of this file and the rules each cites."""
    module = sys.modules[__name__]
    found: dict[str, set[str]] = {}
    for name in dir(module):
        function = getattr(module, name)
        if name.startswith("test_") and callable(function) and name not in _META:
            marks = getattr(function, "pytestmark", [])
            found[name] = {rule for mark in marks if mark.name == "spec" for rule in mark.args}
    return found


def test_the_document_and_this_file_name_the_same_tests() -> None:
    named = [test for _, tests in _sections().values() for test in tests]
    assert len(named) == len(set(named)), "a regression test is named by two sections"
    here = set(_tests_here())
    assert sorted(set(named) - here) == [], "docs/divergences.md names tests that do not exist"
    assert sorted(here - set(named)) == [], "tests/test_divergences.py has tests the document does not name"


def test_the_document_cites_rules_of_the_spec_that_its_tests_cite() -> None:
    spec_rules = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC.read_text(encoding="utf-8")))
    cited = _tests_here()
    for title, (rules, tests) in _sections().items():
        assert rules <= spec_rules, f"{title}: cites rules docs/spec.md does not define: {rules - spec_rules}"
        for test in tests:
            assert cited.get(test), f"{test} cites no spec rule"
            assert cited[test] & rules, f"{test} cites none of the rules of {title!r}"
