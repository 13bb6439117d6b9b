"""The client machine: commands, local refusals, outcomes, the view, and docs/client.md's examples."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent import client
from dynevent.client import (
    SECOND,
    ClientInput,
    ClientState,
    FeedbackReceived,
    GoalResponse,
    Ignored,
    Outcome,
    OutcomeKind,
    Progress,
    Refused,
    ResultReceived,
    RunBegan,
    SendGoal,
    StatusReceived,
    Tick,
    TimedOut,
    ViewChanged,
)
from dynevent.errors import InvalidMessage
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.testing.strategies import messages
from dynevent.wire.messages import DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    ENDED_CHILD_STATUSES,
    DynamicState,
    EventType,
    GoalStatus,
    RejectReason,
    Status,
)
from support.client_scenario import (
    CONFIG,
    INACTIVE,
    PREFIX,
    RUNNING,
    U32,
    U64,
    WAITING,
    answer,
    begin,
    feed,
    only_outcome,
    refused,
    running,
    sent,
    status,
    waiting,
)

# --------------------------------------------------------------------------- construction


def test_new_client_has_a_fresh_servers_view() -> None:
    state = ClientState.new(PREFIX)
    fresh = machine.State.new("f", "r")
    assert (state.phase, state.seq, state.current_id) == (fresh.phase, fresh.seq, fresh.current_id)
    assert state.newest_seq is None and state.goals == ()


@pytest.mark.parametrize("prefix", ["", "0" * 15, "0" * 17, "0x" + "0" * 14, "g" * 16, "+" + "1" * 15, 16])
def test_bad_prefix_is_refused(prefix: Any) -> None:
    with pytest.raises(InvalidMessage, match="uuid_prefix"):
        ClientState.new(prefix)


def test_prefix_is_lowercased_and_uuids_count_up() -> None:
    assert ClientState.new("ABCDEF0123456789").uuid_prefix == "abcdef0123456789"
    state = waiting()
    state, first = sent(client.request_finish(state, now=0))
    assert first.goal_uuid == PREFIX + "0" * 16
    assert state.counter == 1
    assert ins.goal_uuid(first.goal_uuid) == first.goal_uuid


def test_bad_category_names_are_refused() -> None:
    with pytest.raises(InvalidMessage, match="categories"):
        ClientState.new(PREFIX, categories=[1])  # type: ignore[list-item]


# --------------------------------------------------------------------------- commands


def test_request_next_builds_the_goal() -> None:
    state, send = sent(
        client.request_next(
            waiting(seq=3, event_id=41), "go_to_place", '"pantry"', stubborn_period=3.5, now=0
        )
    )
    assert send.goal == Goal(
        dynamic_event_seq=3,
        event_type=EventType.NEXT,
        category="go_to_place",
        description='"pantry"',
        id=42,
        stubborn_period=3.5,
    )
    assert state.last_id == 42
    assert state.goal(send.goal_uuid) is not None


def test_next_ids_rise_and_are_unique_even_after_rejections() -> None:
    state, first = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    state, _ = feed(state, GoalResponse(goal_uuid=first.goal_uuid, accepted=False))
    state, second = sent(client.request_next(state, "go_to_place", '"a"', now=0))
    assert (first.goal.id, second.goal.id) == (6, 7)


def test_next_id_is_above_every_id_seen() -> None:
    state, _ = feed(waiting(), status(1, RUNNING, 90, "underway"), status(1, WAITING, 5))
    state, send = sent(client.request_next(state, "go_to_place", '"a"', now=0))
    assert send.goal.id == 91


def test_rejection_values_teach_the_last_id() -> None:
    state, first = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    stale = outs.Rejected(reason=RejectReason.STALE_ID, text="", current_id=500, requested_id=6)
    state, _ = feed(state, GoalResponse(goal_uuid=first.goal_uuid, accepted=False, rejection=stale))
    state, second = sent(client.request_next(state, "go_to_place", '"a"', now=0))
    assert second.goal.id == 501


def test_request_cancel_names_the_running_child() -> None:
    state, _ = running(child=6)
    state, send = sent(client.request_cancel(state, now=0))
    assert send.goal == Goal(dynamic_event_seq=1, event_type=EventType.CANCEL, id=6)


def test_request_cancel_uses_feedback_before_the_status_arrives() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    state, _ = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=6))
    )
    assert state.phase is WAITING
    state, cancel = sent(client.request_cancel(state, now=0))
    assert cancel.goal.id == 6


def test_request_cancel_names_its_own_child_when_a_status_names_another() -> None:
    state, _ = running(child=6)  # our NEXT's feedback named child 6; its answer has not arrived
    state, _ = feed(state, status(1, RUNNING, 9, "underway"))  # a status names another client's child
    state, cancel = sent(client.request_cancel(state, now=0))
    assert cancel.goal.id == 6


def test_request_cancel_may_target_another_clients_child_and_repeat() -> None:
    state, _ = feed(waiting(), status(1, RUNNING, 77, "underway"))
    state, first = sent(client.request_cancel(state, now=0))
    state, second = sent(client.request_cancel(state, now=0))
    assert first.goal.id == second.goal.id == 77
    assert first.goal_uuid != second.goal_uuid


def test_request_finish_builds_the_goal() -> None:
    _, send = sent(client.request_finish(waiting(seq=9), now=0))
    assert send.goal == Goal(dynamic_event_seq=9, event_type=EventType.FINISHED)


def test_commands_check_their_arguments_at_the_edge() -> None:
    state = waiting()
    with pytest.raises(InvalidMessage, match="timeout"):
        client.request_next(state, "go_to_place", '"a"', timeout=0, now=0)
    with pytest.raises(InvalidMessage, match=r"timeout.*is this nanoseconds"):
        client.request_next(state, "go_to_place", '"a"', timeout=60 * SECOND, now=0)  # a duration is seconds
    for huge in (-(10**400), 10**400):  # too large for a float: judged as an int, never converted
        with pytest.raises(InvalidMessage, match="timeout"):
            client.request_next(state, "go_to_place", '"a"', timeout=huge, now=0)
    with pytest.raises(InvalidMessage, match="now"):
        client.request_finish(state, now=1.0)  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match="now"):
        client.request_cancel(state, now=2**80)
    with pytest.raises(InvalidMessage, match="category"):
        client.request_next(state, "bad\x00", '"a"', now=0)
    with pytest.raises(InvalidMessage, match="stubborn_period"):
        client.request_next(state, "go_to_place", '"a"', stubborn_period=1e300, now=0)


# --------------------------------------------------------------------------- local refusals


def next_a(state: ClientState) -> client.ClientTransition:
    return client.request_next(state, "go_to_place", '"a"', now=0)


def cancel(state: ClientState) -> client.ClientTransition:
    return client.request_cancel(state, now=0)


def finish(state: ClientState) -> client.ClientTransition:
    return client.request_finish(state, now=0)


def test_inactive_before_anything_arrives() -> None:
    for command in (next_a, cancel, finish):
        result = refused(command(ClientState.new(PREFIX)))
        assert result.rejection.reason is RejectReason.INACTIVE


def test_inactive_after_the_run_ended() -> None:
    state, _ = feed(waiting(), status(1, INACTIVE))
    assert refused(client.request_finish(state, now=0)).rejection.reason is RejectReason.INACTIVE


def test_inactive_once_our_finished_succeeded_before_the_status_arrives() -> None:
    state, send = sent(client.request_finish(waiting(), now=0))
    state, outputs = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 5))
    assert only_outcome(outputs).kind is OutcomeKind.COMPLETED
    assert state.phase is WAITING  # the view waits for the status...
    reason = refused(client.request_next(state, "go_to_place", '"a"', now=0)).rejection.reason
    assert reason is RejectReason.INACTIVE  # ...but the client knows better


def test_stale_seq_when_a_newer_begin_arrived_first() -> None:
    state, outputs = feed(waiting(seq=1), begin(2))
    assert outputs == [RunBegan(seq=2, description="{}")]
    result = refused(client.request_finish(state, now=0))
    assert result.rejection.reason is RejectReason.SEQ_MISMATCH
    assert (result.rejection.expected_seq, result.rejection.received_seq) == (2, 1)


def test_busy_while_a_child_runs() -> None:
    state, _ = running(child=6)
    for command in (next_a, finish):
        result = refused(command(state))
        assert result.rejection.reason is RejectReason.BUSY
        assert result.rejection.current_id == 6


def test_busy_while_our_next_is_open() -> None:
    state, _ = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    assert state.phase is WAITING
    assert (
        refused(client.request_next(state, "go_to_place", '"b"', now=0)).rejection.reason is RejectReason.BUSY
    )
    assert refused(client.request_finish(state, now=0)).rejection.reason is RejectReason.BUSY


def test_busy_while_our_finished_is_open() -> None:
    state, _ = sent(client.request_finish(waiting(), now=0))
    assert (
        refused(client.request_next(state, "go_to_place", '"b"', now=0)).rejection.reason is RejectReason.BUSY
    )


def test_not_busy_once_the_answer_says_the_child_ended() -> None:
    state, uuid = running(child=6)
    state, _ = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6))
    assert state.phase is RUNNING and state.ended_id == 6  # the WAITING status has not arrived
    state, send = sent(client.request_next(state, "go_to_place", '"b"', now=0))
    assert send.goal.id == 7
    # child 6 has ended and child 7 is not known to run yet: nothing to cancel
    assert refused(client.request_cancel(state, now=0)).rejection.reason is RejectReason.CANCEL_IDLE


def test_unsupported_category_when_the_client_knows_the_categories() -> None:
    state = waiting(categories=["go_to_place"])
    result = refused(client.request_next(state, "teleport", '"a"', now=0))
    assert result.rejection.reason is RejectReason.UNSUPPORTED_CATEGORY
    assert result.rejection.categories == ("go_to_place",)
    sent(client.request_next(waiting(), "teleport", '"a"', now=0))  # unknown categories: the server decides


def test_description_not_json() -> None:
    result = refused(client.request_next(waiting(), "go_to_place", "{not json", now=0))
    assert result.rejection.reason is RejectReason.DESCRIPTION_NOT_JSON
    assert result.goal is not None and result.goal.description == "{not json"


@pytest.mark.parametrize("period", [math.nan, math.inf, -math.inf])
def test_non_finite_stubborn_period(period: float) -> None:
    result = refused(client.request_next(waiting(), "go_to_place", '"a"', stubborn_period=period, now=0))
    assert result.rejection.reason is RejectReason.NON_FINITE_STUBBORN_PERIOD


def test_stale_id_when_no_id_is_left() -> None:
    result = refused(client.request_next(waiting(event_id=U64), "go_to_place", '"a"', now=0))
    assert result.rejection.reason is RejectReason.STALE_ID
    assert result.rejection.current_id == U64
    _, send = sent(client.request_next(waiting(event_id=U64 - 1), "go_to_place", '"a"', now=0))
    assert send.goal.id == U64


def test_cancel_idle() -> None:
    result = refused(client.request_cancel(waiting(), now=0))
    assert result.rejection.reason is RejectReason.CANCEL_IDLE
    assert result.rejection.execution_failure == machine.EXECUTION_FAILURES["idle_cancel"]


def test_cancel_idle_once_the_child_is_known_to_have_ended() -> None:
    state, uuid = running(child=6)
    state, _ = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6))
    assert refused(client.request_cancel(state, now=0)).rejection.reason is RejectReason.CANCEL_IDLE


def test_refusals_change_nothing() -> None:
    state, _ = running()
    transition = client.request_finish(state, now=0)
    assert transition.state == state


def server_in(state_inputs: list[ins.Input], config: machine.ServerConfig = CONFIG) -> machine.State:
    server = machine.State.new("f", "r")
    for event in state_inputs:
        server = machine.step(server, event, config).state
    return server


@pytest.mark.parametrize(
    ("inputs", "command"),
    [
        ([], "next"),
        ([ins.Begin(description="{}", event_id=5, now=0)], "cancel"),
        ([ins.Begin(description="{}", event_id=U64, now=0)], "next"),
        ([ins.Begin(description="{}", event_id=5, now=0)], "nan"),
        ([ins.Begin(description="{}", event_id=5, now=0)], "json"),
        ([ins.Begin(description="{}", event_id=5, now=0)], "category"),
    ],
)
def test_local_refusals_give_the_servers_reason(inputs: list[ins.Input], command: str) -> None:
    server = server_in(inputs)
    state = ClientState.new(PREFIX, categories=CONFIG.categories)
    if server.active:
        state, _ = feed(state, status(server.seq, server.phase, server.current_id, server.status))
    transition = {
        "next": lambda: client.request_next(state, "go_to_place", '"a"', now=0),
        "cancel": lambda: client.request_cancel(state, now=0),
        "nan": lambda: client.request_next(state, "go_to_place", '"a"', stubborn_period=math.nan, now=0),
        "json": lambda: client.request_next(state, "go_to_place", "[", now=0),
        "category": lambda: client.request_next(state, "teleport", '"a"', now=0),
    }[command]()
    result = refused(transition)
    assert result.goal is not None
    decision = machine.accept(server, result.goal, CONFIG)
    assert isinstance(decision, outs.Rejected)
    assert decision.reason is result.rejection.reason


# --------------------------------------------------------------------------- the view


def test_status_messages_set_the_view() -> None:
    state, outputs = feed(ClientState.new(PREFIX), status(4, RUNNING, 12, "underway"))
    assert (state.phase, state.seq, state.current_id, state.status) == (RUNNING, 4, 12, "underway")
    assert outputs == [ViewChanged(phase=RUNNING, seq=4, current_id=12, status="underway")]
    assert state.newest_seq == 4 and state.last_id == 12


def test_an_unchanged_status_changes_nothing_visible() -> None:
    state = waiting()
    _, outputs = feed(state, status(1, WAITING, 5))
    assert outputs == []


def test_stale_status_and_begin_are_ignored() -> None:
    state, _ = feed(waiting(seq=1), begin(2))
    state, outputs = feed(state, status(1, INACTIVE), begin(1))
    assert all(isinstance(output, Ignored) for output in outputs) and len(outputs) == 2
    assert (state.phase, state.seq) == (WAITING, 1)
    state, outputs = feed(state, status(2, WAITING, 8))
    assert (state.phase, state.seq, state.current_id) == (WAITING, 2, 8)


def test_a_duplicate_begin_is_ignored_and_a_status_first_run_is_described_later() -> None:
    state, outputs = feed(
        ClientState.new(PREFIX), status(3, WAITING, 5), begin(3, '{"detail": "x"}'), begin(3)
    )
    assert isinstance(outputs[1], RunBegan) and isinstance(outputs[2], Ignored)
    assert state.description == '{"detail": "x"}'


def test_seq_wraps_as_a_serial_number() -> None:
    state, _ = feed(ClientState.new(PREFIX), status(U32, WAITING, 5))
    state, _ = feed(state, begin(0), status(0, WAITING, 7))
    assert (state.seq, state.current_id, state.newest_seq) == (0, 7, 0)
    state, outputs = feed(state, status(U32, INACTIVE))
    assert isinstance(outputs[0], Ignored)
    assert state.seq == 0


def test_an_unknown_dynamic_state_is_ignored() -> None:
    message = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=7, status="standby", id=5)
    state, outputs = feed(waiting(), StatusReceived(message=message))
    assert isinstance(outputs[0], Ignored)
    assert state == waiting()


def test_a_new_run_forgets_the_old_runs_knowledge() -> None:
    state, uuid = running(child=6)
    state, _ = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6), status(1, INACTIVE), begin(2))
    assert (state.newest_seq, state.last_id, state.ended_id, state.finished) == (2, 0, None, False)


# --------------------------------------------------------------------------- inputs without effect


def test_answers_for_unknown_goals_are_ignored() -> None:
    uuid = "f" * 32
    for event in (
        GoalResponse(goal_uuid=uuid, accepted=True),
        FeedbackReceived(goal_uuid=uuid, feedback=Feedback()),
        answer(uuid, GoalStatus.SUCCEEDED, "completed", 1),
    ):
        state, outputs = feed(waiting(), event)
        assert state == waiting() and len(outputs) == 1 and isinstance(outputs[0], Ignored)


def test_a_rejection_after_acceptance_is_ignored() -> None:
    state, send = sent(client.request_finish(waiting(), now=0))
    state, _ = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=True))
    state, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    assert isinstance(outputs[0], Ignored)
    assert state.goal(send.goal_uuid) is not None


def test_inputs_check_their_fields() -> None:
    with pytest.raises(InvalidMessage, match="rejection"):
        GoalResponse(
            goal_uuid="a" * 32, accepted=True, rejection=outs.Rejected(reason=RejectReason.BUSY, text="")
        )
    with pytest.raises(InvalidMessage, match="status"):
        ResultReceived(goal_uuid="a" * 32, status=GoalStatus.EXECUTING, result=Result())
    with pytest.raises(InvalidMessage, match="rejection"):
        GoalResponse(goal_uuid="a" * 32, accepted=False, rejection="busy")  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match="status"):
        ResultReceived(goal_uuid="a" * 32, status="done", result=Result())  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match="goal_uuid"):
        FeedbackReceived(goal_uuid="nope", feedback=Feedback())
    with pytest.raises(InvalidMessage, match="message"):
        StatusReceived(message=Feedback())  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match="now"):
        Tick(now=True)
    assert ResultReceived(goal_uuid="A" * 32, status="aborted", result=Result()).status is GoalStatus.ABORTED  # type: ignore[arg-type]


# --------------------------------------------------------------------------- outcomes


@pytest.mark.parametrize(
    ("goal_status", "final", "kind"),
    [
        (GoalStatus.SUCCEEDED, "completed", OutcomeKind.COMPLETED),
        (GoalStatus.ABORTED, "canceled", OutcomeKind.CANCELED),
        (GoalStatus.CANCELED, "canceled", OutcomeKind.CANCELED),
        (GoalStatus.ABORTED, "killed", OutcomeKind.KILLED),
        (GoalStatus.ABORTED, "skipped", OutcomeKind.SKIPPED),
        (GoalStatus.SUCCEEDED, "failed", OutcomeKind.FAILED),
        (GoalStatus.SUCCEEDED, "error", OutcomeKind.ERROR),
        (GoalStatus.SUCCEEDED, "underway", OutcomeKind.ERROR),
    ],
)
def test_outcome_by_final_status(goal_status: GoalStatus, final: str, kind: OutcomeKind) -> None:
    state, uuid = running(child=6)
    state, outputs = feed(state, answer(uuid, goal_status, final, 6))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.id, outcome.status, outcome.goal_status) == (kind, 6, final, goal_status)
    assert outcome.result == Result(status=final, id=6)
    assert state.goals == ()


def test_outcome_of_a_cancel_goal_is_how_its_target_ended() -> None:
    state, uuid = running(child=6)
    state, cancel = sent(client.request_cancel(state, now=0))
    state, outputs = feed(
        state,
        answer(uuid, GoalStatus.ABORTED, "canceled", 6),
        answer(cancel.goal_uuid, GoalStatus.SUCCEEDED, "canceled", 6),
    )
    kinds = [
        (output.goal.event_type, output.kind, output.id) for output in outputs if isinstance(output, Outcome)
    ]
    assert kinds == [(EventType.NEXT, OutcomeKind.CANCELED, 6), (EventType.CANCEL, OutcomeKind.CANCELED, 6)]


def test_outcome_of_finished_names_the_dynamic_event() -> None:
    state, send = sent(client.request_finish(waiting(event_id=5), now=0))
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 5))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.id) == (OutcomeKind.COMPLETED, 5)


def test_rejected_with_and_without_a_reason() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.reason, outcome.rejection) == (OutcomeKind.REJECTED, None, None)
    busy = outs.Rejected(reason=RejectReason.BUSY, text="event 9 is running", current_id=9)
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False, rejection=busy))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.reason, outcome.rejection) == (
        OutcomeKind.REJECTED,
        RejectReason.BUSY,
        busy,
    )
    assert "event 9 is running" in outcome.text


@pytest.mark.parametrize(
    ("failure", "reason"),
    [
        ("race condition", RejectReason.RACE),
        ("shutting down", RejectReason.SHUTTING_DOWN),
        ("ID for cancel request does not match current event", RejectReason.CANCEL_ID_MISMATCH),
        ("an idle dynamic event cannot be cancelled", RejectReason.CANCEL_IDLE),
        ("invalid event_type", RejectReason.UNKNOWN_EVENT_TYPE),
        ("Description parsing failure\n -- bad", RejectReason.DESCRIPTION_INVALID),
        ("something new", None),
    ],
)
def test_execution_failure_keeps_the_servers_string(failure: str, reason: RejectReason | None) -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, failure=failure))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.reason, outcome.execution_failure) == (
        OutcomeKind.EXECUTION_FAILURE,
        reason,
        failure,
    )
    assert outcome.id == send.goal.id


def test_cancelled_while_not_running_is_canceled() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    failure = machine.EXECUTION_FAILURES["not_running"]
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.CANCELED, failure=failure))
    assert only_outcome(outputs).kind is OutcomeKind.CANCELED


@pytest.mark.parametrize(
    "ending",
    [
        [status(1, INACTIVE)],
        [begin(2)],
        [status(2, WAITING, 3)],
        [status(1, INACTIVE), begin(2), status(2, WAITING, 3)],
    ],
)
def test_superseded_when_the_run_ended_before_the_answer(ending: list[ClientInput]) -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    state, _ = feed(state, *ending)
    mismatch = outs.Rejected(reason=RejectReason.SEQ_MISMATCH, text="Expected 2, received 1")
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False, rejection=mismatch))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.reason) == (OutcomeKind.SUPERSEDED, RejectReason.SEQ_MISMATCH)
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, failure="race condition"))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.reason) == (OutcomeKind.SUPERSEDED, RejectReason.RACE)


def test_a_real_end_is_not_superseded_even_when_it_arrives_late() -> None:
    state, uuid = running(child=6)
    state, _ = feed(state, status(1, INACTIVE))  # the INACTIVE status overtook the answer
    _, outputs = feed(state, answer(uuid, GoalStatus.ABORTED, "canceled", 6))
    assert only_outcome(outputs).kind is OutcomeKind.CANCELED


def test_a_result_before_the_response_closes_the_goal() -> None:
    state, send = sent(client.request_finish(waiting(), now=0))
    state, outputs = feed(
        state,
        answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 5),
        GoalResponse(goal_uuid=send.goal_uuid, accepted=True),
    )
    assert isinstance(outputs[0], Outcome) and isinstance(outputs[1], Ignored)


def test_feedback_is_progress() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    feedback = Feedback(status="delayed", id=6)
    state, outputs = feed(state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=feedback))
    assert outputs == [Progress(goal_uuid=send.goal_uuid, status="delayed", id=6, logs=())]
    opened = state.goal(send.goal_uuid)
    assert opened is not None and (opened.accepted, opened.child_id, opened.child_status) == (
        True,
        6,
        "delayed",
    )


# --------------------------------------------------------------------------- timeouts


def test_timeout_cancels_a_running_child_and_reports_timeout() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=10e-9, now=100))  # 10 ns
    assert client.next_deadline(state) == 110
    state, outputs = feed(
        state,
        FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=6)),
        Tick(now=109),
    )
    assert [type(output) for output in outputs] == [Progress]
    state, outputs = feed(state, Tick(now=110))
    assert outputs[0] == TimedOut(goal_uuid=send.goal_uuid, id=6, deadline=110)
    assert isinstance(outputs[1], SendGoal)
    assert outputs[1].goal == Goal(dynamic_event_seq=1, event_type=EventType.CANCEL, id=6)
    assert client.next_deadline(state) is None
    state, outputs = feed(state, Tick(now=200))
    assert outputs == []  # no second cancel
    state, outputs = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 6))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.status) == (OutcomeKind.TIMEOUT, "completed")


def test_timeout_waits_until_the_child_is_known_to_run() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state, outputs = feed(state, Tick(now=SECOND))
    assert [type(output) for output in outputs] == [TimedOut]
    state, outputs = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="queued", id=6))
    )
    assert [type(output) for output in outputs] == [Progress, SendGoal]


def test_timeout_uses_the_running_status_when_feedback_was_lost() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state, outputs = feed(state, Tick(now=SECOND), status(1, RUNNING, 6, "underway"))
    assert not any(isinstance(output, SendGoal) for output in outputs)  # not known to be ours yet
    state, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=True))
    cancels = [output for output in outputs if isinstance(output, SendGoal)]
    assert len(cancels) == 1 and cancels[0].goal.id == 6


def test_timeout_does_not_add_a_cancel_to_ours() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state, _ = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=6))
    )
    state, _ = sent(client.request_cancel(state, now=0))
    state, outputs = feed(state, Tick(now=SECOND))
    assert [type(output) for output in outputs] == [TimedOut]


def test_timeout_after_the_run_ended_sends_nothing() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state, _ = feed(state, status(1, INACTIVE), Tick(now=SECOND))
    state, outputs = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="queued", id=6))
    )
    assert not any(isinstance(output, SendGoal) for output in outputs)


def test_a_rejected_timed_out_goal_is_rejected() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state, _ = feed(state, Tick(now=5 * SECOND))
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    assert only_outcome(outputs).kind is OutcomeKind.REJECTED


# --------------------------------------------------------------------------- withdrawal


def test_withdrawing_a_running_next_cancels_its_child_at_once() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    state, _ = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=6))
    )
    state, cancel = sent(client.request_withdraw(state, send.goal_uuid, now=0))
    assert cancel.goal == Goal(dynamic_event_seq=1, event_type=EventType.CANCEL, id=6)
    state, outputs = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "canceled", 6))
    outcome = only_outcome(outputs)
    assert (outcome.kind, outcome.id) == (OutcomeKind.CANCELED, 6)  # not a timeout: the caller withdrew it


def test_a_withdrawn_next_is_cancelled_once_its_child_is_known() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    transition = client.request_withdraw(state, send.goal_uuid, now=0)
    assert transition.outputs == ()  # not accepted yet: the CANCEL would name nothing
    state, outputs = feed(
        transition.state,
        GoalResponse(goal_uuid=send.goal_uuid, accepted=True),
        FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="queued", id=9)),
    )
    cancels = [output for output in outputs if isinstance(output, SendGoal)]
    assert [cancel.goal.id for cancel in cancels] == [9]  # the server's number for the child (D10)
    state, outputs = feed(state, status(1, RUNNING, 9, "underway"))
    assert not any(isinstance(output, SendGoal) for output in outputs)  # one CANCEL, not two


def test_a_withdrawn_next_times_out_no_more_and_a_refused_one_sends_nothing() -> None:
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=1, now=0))
    state = client.request_withdraw(state, send.goal_uuid, now=0).state
    assert client.next_deadline(state) is None
    state, outputs = feed(state, Tick(now=5 * SECOND))
    assert outputs == []
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    assert only_outcome(outputs).kind is OutcomeKind.REJECTED


def test_withdrawing_what_is_not_an_open_next_is_ignored_with_why() -> None:
    state, send = sent(client.request_finish(waiting(), now=0))
    (ignored,) = client.request_withdraw(state, send.goal_uuid, now=0).outputs
    assert isinstance(ignored, Ignored) and "only a NEXT" in ignored.why
    (ignored,) = client.request_withdraw(state, "e" * 32, now=0).outputs
    assert isinstance(ignored, Ignored) and "not open" in ignored.why
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', now=0))
    state = client.request_withdraw(state, send.goal_uuid, now=0).state
    (ignored,) = client.request_withdraw(state, send.goal_uuid, now=0).outputs
    assert isinstance(ignored, Ignored) and "already withdrawn" in ignored.why


# --------------------------------------------------------------------------- purity


def _apply(state: ClientState, choice: int, seq: int) -> client.ClientTransition:
    if choice == 0:
        return client.request_next(state, "go_to_place", '"a"', timeout=3, now=0)
    if choice == 1:
        return client.request_cancel(state, now=0)
    if choice == 2:
        return client.request_finish(state, now=0)
    if choice == 3:
        return client.step(state, Tick(now=10))
    return client.step(state, status((seq + 1) & U32, WAITING, 1))


@given(st.lists(st.integers(0, 4), max_size=12), st.integers(0, 2**32 - 1))
def test_steps_are_pure_and_deterministic(choices: list[int], seq: int) -> None:
    def play() -> list[client.ClientTransition]:
        state = waiting(seq=seq)
        trace = []
        for choice in choices:
            before = repr(state)
            transition = _apply(state, choice, seq)
            assert repr(state) == before  # the old state is untouched
            state = transition.state
            trace.append(transition)
        return trace

    assert play() == play()


#: When a status or begin arrived, or None (a binding that gives no time: R21.6 is not watched).
ARRIVED = st.one_of(st.none(), st.integers(0, 10 * SECOND))


def _small_seq_status() -> st.SearchStrategy[StatusReceived]:
    message = st.builds(
        DynamicEventStatus,
        dynamic_event_seq=st.sampled_from((0, 1, 2, U32)),
        dynamic_state=st.integers(0, 3),
        status=st.sampled_from([status_.value for status_ in Status]),
        id=st.sampled_from((0, 5, 6, 7, U64)),
    )
    return st.builds(StatusReceived, message=message, now=ARRIVED)


TERMINAL = (GoalStatus.SUCCEEDED, GoalStatus.CANCELED, GoalStatus.ABORTED)
# Each item: (which goal UUID a goal-specific input names, what arrives or which command is given).
BOOK_ITEMS = st.tuples(
    st.integers(0, 3),
    st.one_of(
        _small_seq_status(),
        st.builds(StatusReceived, message=messages(DynamicEventStatus), now=ARRIVED),
        st.builds(
            lambda seq, now: attrs.evolve(begin(seq), now=now), st.sampled_from((0, 1, 2, U32)), ARRIVED
        ),
        st.integers(0, 10 * SECOND).map(lambda now: Tick(now=now)),
        st.integers(0, 10 * SECOND).map(lambda now: client.ContactMade(now=now)),
        st.integers(0, 10 * SECOND).map(lambda now: client.ContactLost(now=now)),
        st.tuples(st.just("response"), st.booleans()),
        st.tuples(
            st.just("feedback"), st.builds(Feedback, status=st.just("underway"), id=st.sampled_from((6, 7)))
        ),
        st.tuples(st.just("result"), st.sampled_from(TERMINAL), messages(Result)),
        st.sampled_from((("next",), ("next_timeout",), ("cancel",), ("finish",), ("withdraw",))),
    ),
)


def _book_step(state: ClientState, item: Any, uuid: str) -> client.ClientTransition:
    if not isinstance(item, tuple):
        return client.step(state, item)
    if item[0] == "response":
        return client.step(state, GoalResponse(goal_uuid=uuid, accepted=item[1]))
    if item[0] == "feedback":
        return client.step(state, FeedbackReceived(goal_uuid=uuid, feedback=item[1]))
    if item[0] == "result":
        return client.step(state, ResultReceived(goal_uuid=uuid, status=item[1], result=item[2]))
    if item[0] == "cancel":
        return client.request_cancel(state, now=0)
    if item[0] == "finish":
        return client.request_finish(state, now=0)
    if item[0] == "withdraw":
        return client.request_withdraw(state, uuid, now=0)
    timeout = 1 if item[0] == "next_timeout" else None
    return client.request_next(state, "go_to_place", '"a"', timeout=timeout, now=0)


@given(st.lists(BOOK_ITEMS, max_size=30))
def test_any_input_sequence_keeps_the_books(items: list[tuple[int, Any]]) -> None:
    """Total on any wire-valid input; one outcome per sent goal, none for others; UUIDs never repeat;
    a result is asked for again only for an open goal (R21.4)."""
    state = ClientState.new(PREFIX)
    sent_uuids: list[str] = []
    outcomes: list[str] = []
    for choice, item in items:
        uuid = sent_uuids[-1 - choice] if choice < len(sent_uuids) else "e" * 32
        transition = _book_step(state, item, uuid)
        state = transition.state
        for output in transition.outputs:
            if isinstance(output, SendGoal):
                assert output.goal_uuid not in sent_uuids
                sent_uuids.append(output.goal_uuid)
            elif isinstance(output, Outcome):
                assert output.goal_uuid in sent_uuids and output.goal_uuid not in outcomes
                outcomes.append(output.goal_uuid)
            elif isinstance(output, client.AskResult):
                assert state.goal(output.goal_uuid) is not None
        open_uuids = [goal.goal_uuid for goal in state.goals]
        assert sorted(open_uuids + outcomes) == sorted(sent_uuids)
        assert state.counter == len(sent_uuids)


# --------------------------------------------------------------------------- docs/client.md

DOC = Path(__file__).resolve().parents[2] / "docs" / "client.md"
BLOCKS = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.DOTALL)


def test_client_doc_has_examples() -> None:
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_client_doc_example_runs(index: int, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(BLOCKS[index], f"docs/client.md example {index + 1}", "exec"), {})
    out = capsys.readouterr().out
    for expected in re.findall(r"print\(.*?\)\s*# (.+)", BLOCKS[index]):
        assert expected in out


def test_every_status_has_an_outcome_kind() -> None:
    for status_ in Status:
        state, uuid = running()
        _, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, status_.value, 6))
        assert isinstance(only_outcome(outputs).kind, OutcomeKind)


# --------------------------------------------------------------------------- one projection


@pytest.mark.spec("R4.8", "R20.1")
def test_a_description_past_the_servers_limit_is_refused_locally() -> None:
    rejection = refused(client.request_next(waiting(), "go_to_place", '"' + "a" * 1_000_000 + '"', now=0))
    assert rejection.rejection.reason is RejectReason.DESCRIPTION_INVALID
    assert rejection.rejection.rule == "R4.8"


@pytest.mark.spec("R20.1")
def test_a_local_refusal_names_the_servers_rule() -> None:
    fresh = ClientState.new(PREFIX)
    assert refused(client.request_finish(fresh, now=0)).rejection.rule == "R4.3"
    state, _ = running()
    assert refused(client.request_finish(state, now=0)).rejection.rule == "R4.6"
    assert refused(client.request_cancel(waiting(), now=0)).rejection.rule == "R4.13"


@pytest.mark.spec("R20.1")
def test_dynamic_event_is_never_a_category_the_client_sends() -> None:
    rejection = refused(client.request_next(waiting(), "dynamic_event", "{}", now=0)).rejection
    assert rejection.reason is RejectReason.UNSUPPORTED_CATEGORY and rejection.categories == ()


@pytest.mark.spec("R2.2", "R20.1", "R20.2")
@given(
    st.sampled_from([INACTIVE, WAITING, RUNNING]),
    st.integers(1, 2**32 - 1),
    st.integers(0, 2**64 - 1),
    st.sampled_from(["standby", "underway", "queued", "error", *sorted(ENDED_CHILD_STATUSES)]),
    st.sampled_from([EventType.NEXT, EventType.CANCEL, EventType.FINISHED]),
    st.sampled_from(['"x"', "{", '"' + "a" * 1_000_001 + '"']),
    st.sampled_from([0.0, math.nan]),
)
def test_a_clients_refusal_is_the_servers_on_the_state_its_status_implies(
    phase: DynamicState,
    seq: int,
    event_id: int,
    text: str,
    event_type: EventType,
    description: str,
    period: float,
) -> None:
    """A client that knows only one status message refuses exactly what the server in that state would;
    a RUNNING status with a child's final status is the WAITING state of R20.2."""
    message = status(seq, phase, event_id, text)
    state, _ = feed(ClientState.new(PREFIX), message)
    if event_type == EventType.NEXT:
        transition = client.request_next(state, "go_to_place", description, stubborn_period=period, now=0)
    elif event_type == EventType.CANCEL:
        transition = client.request_cancel(state, now=0)
    else:
        transition = client.request_finish(state, now=0)
    (output,) = transition.outputs
    goal = output.goal
    implied = message.message
    if phase is RUNNING and text in ENDED_CHILD_STATUSES:
        implied = attrs.evolve(implied, dynamic_state=WAITING)
    server = machine.state_from_status(implied)
    decision = machine.accept(server, goal, CONFIG)
    if isinstance(output, Refused):
        assert isinstance(decision, outs.Rejected), (output, decision)
        assert (decision.reason, decision.rule) == (output.rejection.reason, output.rejection.rule)
    else:
        assert isinstance(decision, outs.Accepted), decision
