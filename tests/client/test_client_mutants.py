"""Tests that kill the mutants mutmut made of src/dynevent/client/machine.py (see docs/testing.md).

They pin what tests/client/test_client.py left loose: the edge checks and their
errors, keyword-only construction, the ``KIND`` names that traces record, the
defaults of the state and output classes, the resolvable type hints, the
uint32 serial-number order of seqs, and the exact sentences of local
refusals and outcomes (users read them in simulated sessions' timelines and logs).
"""

from __future__ import annotations

import math
import typing
from collections.abc import Callable
from typing import Any

import pytest

from dynevent import client
from dynevent.client import (
    SECOND,
    AskResult,
    BackInContact,
    BeginReceived,
    ClientInput,
    ClientOutput,
    ClientState,
    ClientTransition,
    ContactLost,
    ContactMade,
    FeedbackReceived,
    GoalResponse,
    Ignored,
    OpenGoal,
    Outcome,
    OutcomeKind,
    OutOfContact,
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
from dynevent.server.inputs import NOW_RANGE
from dynevent.wire.messages import DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import EventType, GoalStatus, RejectReason
from support.client_scenario import (
    INACTIVE,
    PREFIX,
    RUNNING,
    U32,
    U64,
    WAITING,
    answer,
    begin,
    feed,
    running,
    sent,
    status,
    waiting,
)

UUID = "a" * 32


#: One nanosecond, in the seconds durations are given in: these tests count deadlines in nanoseconds.
NS = 1e-9


def refusal(transition: ClientTransition) -> outs.Rejected:
    (output,) = transition.outputs
    assert isinstance(output, Refused), output
    return output.rejection


def only(outputs: list[ClientOutput], cls: type[Any]) -> Any:
    found = [output for output in outputs if isinstance(output, cls)]
    assert len(found) == 1, outputs
    return found[0]


def next_a(state: ClientState, **kwargs: Any) -> ClientTransition:
    return client.request_next(state, "go_to_place", '"a"', now=0, **kwargs)


# --------------------------------------------------------------------------- constants and names


def test_second_is_one_billion_nanoseconds() -> None:
    assert SECOND == 1_000_000_000
    assert type(SECOND) is int


def test_outcome_kind_values() -> None:
    assert {kind.name: kind.value for kind in OutcomeKind} == {
        "COMPLETED": "completed",
        "CANCELED": "canceled",
        "KILLED": "killed",
        "SKIPPED": "skipped",
        "FAILED": "failed",
        "ERROR": "error",
        "EXECUTION_FAILURE": "execution_failure",
        "REJECTED": "rejected",
        "TIMEOUT": "timeout",
        "SUPERSEDED": "superseded",
    }
    for kind in OutcomeKind:
        assert str(kind) == kind.value
        assert OutcomeKind(kind.value) is kind


@pytest.mark.parametrize("final", ["completed", "canceled", "killed", "skipped", "failed", "error"])
def test_outcome_kind_of_a_final_status_has_its_name(final: str) -> None:
    state, uuid = running(child=6)
    goal_status = GoalStatus.SUCCEEDED if final in ("completed", "failed", "error") else GoalStatus.ABORTED
    _, outputs = feed(state, answer(uuid, goal_status, final, 6))
    outcome = only(outputs, Outcome)
    assert outcome.kind.value == final
    assert outcome.text == f"the event ended {final!r}"


_KINDS: list[tuple[type[Any], str]] = [
    (BeginReceived, "begin_received"),
    (StatusReceived, "status_received"),
    (GoalResponse, "goal_response"),
    (FeedbackReceived, "feedback_received"),
    (ResultReceived, "result_received"),
    (Tick, "tick"),
    (SendGoal, "send_goal"),
    (Refused, "refused"),
    (Outcome, "outcome"),
    (Progress, "progress"),
    (RunBegan, "run_began"),
    (ViewChanged, "view_changed"),
    (TimedOut, "timed_out"),
    (Ignored, "ignored"),
    (ContactMade, "contact_made"),
    (ContactLost, "contact_lost"),
    (AskResult, "ask_result"),
    (OutOfContact, "out_of_contact"),
    (BackInContact, "back_in_contact"),
]


@pytest.mark.parametrize(("cls", "kind"), _KINDS, ids=[kind for _, kind in _KINDS])
def test_kind_names_of_inputs_and_outputs(cls: type[Any], kind: str) -> None:
    # the names the simulated session's timeline and traces record
    assert kind == cls.KIND


def test_ignored_outputs_name_the_input_kind() -> None:
    state = waiting()
    for event in (
        GoalResponse(goal_uuid=UUID, accepted=True),
        FeedbackReceived(goal_uuid=UUID, feedback=Feedback()),
        answer(UUID, GoalStatus.SUCCEEDED),
        begin(1),
    ):
        (output,) = client.step(state, event).outputs
        assert isinstance(output, Ignored)
        assert output.input == type(event).KIND


# --------------------------------------------------------------------------- type hints


_PUBLIC_CLASSES = [
    BeginReceived,
    StatusReceived,
    GoalResponse,
    FeedbackReceived,
    ResultReceived,
    Tick,
    SendGoal,
    Refused,
    Outcome,
    Progress,
    RunBegan,
    ViewChanged,
    TimedOut,
    Ignored,
    ContactMade,
    ContactLost,
    AskResult,
    OutOfContact,
    BackInContact,
    OpenGoal,
    ClientState,
    ClientTransition,
]


@pytest.mark.parametrize("cls", _PUBLIC_CLASSES, ids=lambda cls: cls.__name__)
def test_type_hints_resolve(cls: type[Any]) -> None:
    # typing.get_type_hints evaluates the (string) annotations, as attrs/cattrs/sphinx do
    typing.get_type_hints(cls)


def test_optional_fields_are_typed_optional() -> None:
    assert typing.get_type_hints(GoalResponse)["rejection"] == outs.Rejected | None
    outcome = typing.get_type_hints(Outcome)
    assert outcome["reason"] == RejectReason | None
    assert outcome["goal_status"] == GoalStatus | None
    assert outcome["result"] == Result | None
    assert outcome["rejection"] == outs.Rejected | None
    opened = typing.get_type_hints(OpenGoal)
    assert opened["child_id"] == int | None
    assert opened["deadline"] == int | None
    state = typing.get_type_hints(ClientState)
    assert state["categories"] == frozenset[str] | None
    assert state["newest_seq"] == int | None
    assert state["ended_id"] == int | None


def test_input_and_output_unions() -> None:
    assert set(typing.get_args(ClientInput)) == {
        BeginReceived,
        StatusReceived,
        GoalResponse,
        FeedbackReceived,
        ResultReceived,
        Tick,
        ContactMade,
        ContactLost,
    }
    assert set(typing.get_args(ClientOutput)) == {
        SendGoal,
        Refused,
        Outcome,
        Progress,
        RunBegan,
        ViewChanged,
        TimedOut,
        Ignored,
        AskResult,
        OutOfContact,
        BackInContact,
    }


# --------------------------------------------------------------------------- construction


_POSITIONAL: list[Callable[[], object]] = [
    lambda: BeginReceived(begin(1).message),  # type: ignore[call-arg]
    lambda: StatusReceived(status(1, WAITING).message),  # type: ignore[call-arg]
    lambda: GoalResponse(UUID, True),  # type: ignore[call-arg]
    lambda: FeedbackReceived(UUID, Feedback()),  # type: ignore[call-arg]
    lambda: ResultReceived(UUID, GoalStatus.SUCCEEDED, Result()),  # type: ignore[call-arg]
    lambda: Tick(0),  # type: ignore[call-arg]
    lambda: SendGoal(UUID, Goal()),  # type: ignore[call-arg]
    lambda: Refused(EventType.NEXT, outs.Rejected(reason=RejectReason.BUSY, text=""), None),  # type: ignore[call-arg]
    lambda: Outcome(UUID, Goal(), OutcomeKind.COMPLETED, 0, "", ""),  # type: ignore[call-arg]
    lambda: Progress(UUID, "underway", 6, ()),  # type: ignore[call-arg]
    lambda: RunBegan(1, "{}"),  # type: ignore[call-arg]
    lambda: ViewChanged(WAITING, 1, 5, "standby"),  # type: ignore[call-arg]
    lambda: TimedOut(UUID, 6, 10),  # type: ignore[call-arg]
    lambda: Ignored("tick", "why"),  # type: ignore[call-arg]
    lambda: ContactMade(0),  # type: ignore[call-arg]
    lambda: ContactLost(0),  # type: ignore[call-arg]
    lambda: AskResult(UUID),  # type: ignore[call-arg]
    lambda: OutOfContact(0),  # type: ignore[call-arg]
    lambda: BackInContact(0, 1),  # type: ignore[call-arg]
    lambda: OpenGoal(UUID, Goal()),  # type: ignore[call-arg]
    lambda: ClientState(PREFIX),  # type: ignore[call-arg]
]


@pytest.mark.parametrize("build", _POSITIONAL, ids=[cls.__name__ for cls in _PUBLIC_CLASSES[:-1]])
def test_classes_are_keyword_only(build: Callable[[], object]) -> None:
    with pytest.raises(TypeError):
        build()


@pytest.mark.parametrize(
    "build",
    [
        BeginReceived,
        StatusReceived,
        lambda: GoalResponse(accepted=True),
        lambda: GoalResponse(goal_uuid=UUID),  # type: ignore[call-arg]
        lambda: FeedbackReceived(goal_uuid=UUID),
        lambda: FeedbackReceived(feedback=Feedback()),
        lambda: ResultReceived(status=GoalStatus.SUCCEEDED, result=Result()),
        lambda: ResultReceived(goal_uuid=UUID, result=Result()),
        lambda: ResultReceived(goal_uuid=UUID, status=GoalStatus.SUCCEEDED),
        Tick,
    ],
    ids=[
        "begin-message",
        "status-message",
        "response-uuid",
        "response-accepted",
        "feedback-uuid",
        "feedback-feedback",
        "result-uuid",
        "result-status",
        "result-result",
        "tick-now",
    ],
)
def test_input_fields_are_required(build: Callable[[], object]) -> None:
    with pytest.raises(TypeError):
        build()


def _invalid(build: Callable[[], object]) -> InvalidMessage:
    with pytest.raises(InvalidMessage) as caught:
        build()
    return caught.value


@pytest.mark.parametrize(
    ("build", "where", "field", "problem"),
    [
        (
            lambda: BeginReceived(message=Feedback()),  # type: ignore[arg-type]
            "BeginReceived",
            "message",
            "expected a DynamicEventDescription",
        ),
        (
            lambda: StatusReceived(message=begin(1).message),  # type: ignore[arg-type]
            "StatusReceived",
            "message",
            "expected a DynamicEventStatus",
        ),
        (
            lambda: FeedbackReceived(goal_uuid=UUID, feedback=Result()),  # type: ignore[arg-type]
            "FeedbackReceived",
            "feedback",
            "expected a Feedback",
        ),
        (
            lambda: ResultReceived(goal_uuid=UUID, status=GoalStatus.SUCCEEDED, result=Feedback()),  # type: ignore[arg-type]
            "ResultReceived",
            "result",
            "expected a Result",
        ),
        (
            lambda: GoalResponse(goal_uuid=UUID, accepted=False, rejection="busy"),  # type: ignore[arg-type]
            "GoalResponse",
            "rejection",
            "expected a Rejected or None",
        ),
        (
            lambda: GoalResponse(
                goal_uuid=UUID, accepted=True, rejection=outs.Rejected(reason=RejectReason.BUSY, text="")
            ),
            "GoalResponse",
            "rejection",
            "an accepted goal has none",
        ),
        (
            lambda: ResultReceived(goal_uuid=UUID, status=GoalStatus.EXECUTING, result=Result()),
            "ResultReceived",
            "status",
            "expected succeeded, canceled or aborted",
        ),
        (
            lambda: ResultReceived(goal_uuid=UUID, status="done", result=Result()),  # type: ignore[arg-type]
            "ResultReceived",
            "status",
            "expected succeeded, canceled or aborted",
        ),
        (lambda: Tick(now=1.0), "Tick", "now", "expected integer nanoseconds"),  # type: ignore[arg-type]
        (lambda: Tick(now=True), "Tick", "now", "expected integer nanoseconds"),
        (lambda: Tick(now=NOW_RANGE[1] + 1), "Tick", "now", "outside the range of builtin_interfaces/Time"),
        (lambda: Tick(now=NOW_RANGE[0] - 1), "Tick", "now", "outside the range of builtin_interfaces/Time"),
        (lambda: ClientState.new("X" * 16), "ClientState", "uuid_prefix", "expected 16 hexadecimal digits"),
        (lambda: ClientState.new("x" * 16), "ClientState", "uuid_prefix", "expected 16 hexadecimal digits"),
        (lambda: ClientState.new("0" * 15), "ClientState", "uuid_prefix", "expected 16 hexadecimal digits"),
        (
            lambda: ClientState.new(PREFIX, categories=["go_to_place", 1]),  # type: ignore[list-item]
            "ClientState",
            "categories",
            "expected category names (str)",
        ),
    ],
    ids=[
        "begin-type",
        "status-type",
        "feedback-type",
        "result-type",
        "rejection-type",
        "accepted-with-rejection",
        "non-terminal",
        "unknown-status",
        "float-now",
        "bool-now",
        "now-too-late",
        "now-too-early",
        "X-prefix",
        "x-prefix",
        "short-prefix",
        "category-names",
    ],
)
def test_edge_errors_name_message_field_and_problem(
    build: Callable[[], object], where: str, field: str, problem: str
) -> None:
    error = _invalid(build)
    assert (error.message_type, error.field, error.problem) == (where, field, problem)


def test_goal_uuids_are_checked_and_lowercased() -> None:
    assert GoalResponse(goal_uuid="A" * 32, accepted=True).goal_uuid == "a" * 32
    assert FeedbackReceived(goal_uuid="B" * 32, feedback=Feedback()).goal_uuid == "b" * 32
    assert ResultReceived(goal_uuid="C" * 32, status="succeeded", result=Result()).goal_uuid == "c" * 32  # type: ignore[arg-type]
    for build in (
        lambda: GoalResponse(goal_uuid="nope", accepted=True),
        lambda: FeedbackReceived(goal_uuid="nope", feedback=Feedback()),
        lambda: ResultReceived(goal_uuid="nope", status=GoalStatus.SUCCEEDED, result=Result()),
    ):
        assert _invalid(build).field == "goal_uuid"


@pytest.mark.parametrize("accepted", [1, 0, "yes", None])
def test_goal_response_accepted_is_a_bool(accepted: Any) -> None:
    with pytest.raises(TypeError):
        GoalResponse(goal_uuid=UUID, accepted=accepted)


def test_hexadecimal_prefixes_in_any_case() -> None:
    assert ClientState.new("0123456789ABCDEF").uuid_prefix == "0123456789abcdef"
    assert ClientState.new("abcdefABCDEF0000").uuid_prefix == "abcdefabcdef0000"


@pytest.mark.parametrize("now", [NOW_RANGE[0], NOW_RANGE[1], 0])
def test_now_range_is_inclusive(now: int) -> None:
    assert Tick(now=now).now == now
    state = waiting()
    assert isinstance(client.request_finish(state, now=now).outputs[0], SendGoal)
    assert isinstance(client.request_cancel(state, now=now).outputs[0], Refused)
    assert isinstance(client.request_next(state, "go_to_place", '"a"', now=now).outputs[0], SendGoal)


@pytest.mark.parametrize(
    ("command", "name"),
    [
        (lambda state, now: client.request_next(state, "go_to_place", '"a"', now=now), "request_next"),
        (lambda state, now: client.request_cancel(state, now=now), "request_cancel"),
        (lambda state, now: client.request_finish(state, now=now), "request_finish"),
    ],
    ids=["next", "cancel", "finish"],
)
@pytest.mark.parametrize(
    ("now", "problem"),
    [
        (1.0, "expected integer nanoseconds"),
        (NOW_RANGE[1] + 1, "outside the range of builtin_interfaces/Time"),
        (NOW_RANGE[0] - 1, "outside the range of builtin_interfaces/Time"),
    ],
)
def test_commands_name_themselves_in_now_errors(
    command: Callable[[ClientState, Any], ClientTransition], name: str, now: Any, problem: str
) -> None:
    error = _invalid(lambda: command(waiting(), now))
    assert (error.message_type, error.field, error.problem) == (name, "now", problem)


@pytest.mark.parametrize(
    ("timeout", "problem"),
    [
        (0, "expected a finite duration in seconds, above 0"),
        (-1, "expected a finite duration in seconds, above 0"),
        (float("nan"), "expected a finite duration in seconds, above 0"),
        (True, "expected a duration in seconds (an int or a float)"),
        ("1", "expected a duration in seconds (an int or a float)"),
        (60 * SECOND, "durations are in seconds, at most 604800 (a week): is this nanoseconds?"),
    ],
)
def test_timeout_error(timeout: Any, problem: str) -> None:
    error = _invalid(lambda: client.request_next(waiting(), "go_to_place", '"a"', timeout=timeout, now=0))
    assert (error.message_type, error.field, error.problem) == ("request_next", "timeout", problem)


# --------------------------------------------------------------------------- defaults


def test_new_client_state_fields() -> None:
    state = ClientState.new(PREFIX)
    assert (
        state.uuid_prefix,
        state.counter,
        state.categories,
        state.phase,
        state.seq,
        state.current_id,
        state.status,
        state.newest_seq,
        state.description,
        state.last_id,
        state.ended_id,
        state.finished,
        state.goals,
    ) == (PREFIX, 0, None, INACTIVE, 0, 0, "uninitialized", None, "", 0, None, False, ())
    assert ClientState(uuid_prefix=PREFIX) == state
    assert ClientState.new(PREFIX, categories=["b", "a"]).categories == frozenset({"a", "b"})


def test_open_goal_defaults() -> None:
    opened = OpenGoal(goal_uuid=UUID, goal=Goal())
    assert (opened.accepted, opened.child_id, opened.child_status, opened.deadline, opened.timed_out) == (
        False,
        None,
        "",
        None,
        False,
    )


def test_a_sent_goal_is_open_and_unanswered() -> None:
    state, send = sent(next_a(waiting()))
    assert state.goals == (OpenGoal(goal_uuid=send.goal_uuid, goal=send.goal),)
    opened = state.goals[0]
    assert opened.accepted is False
    assert opened.timed_out is False
    assert opened.child_status == ""
    assert opened.deadline is None
    assert client.next_deadline(state) is None
    state, send = sent(client.request_next(waiting(), "go_to_place", '"a"', timeout=7 * NS, now=3))
    assert state.goals[0].deadline == 10
    assert client.next_deadline(state) == 10


def test_outcome_defaults() -> None:
    outcome = Outcome(goal_uuid=UUID, goal=Goal(), kind=OutcomeKind.COMPLETED, id=0, status="", text="")
    assert (
        outcome.reason,
        outcome.execution_failure,
        outcome.goal_status,
        outcome.result,
        outcome.rejection,
    ) == (None, "", None, None, None)


def test_a_rejection_outcome_has_no_result() -> None:
    state, send = sent(next_a(waiting()))
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    outcome = only(outputs, Outcome)
    assert outcome == Outcome(
        goal_uuid=send.goal_uuid,
        goal=send.goal,
        kind=OutcomeKind.REJECTED,
        id=6,
        status="",
        text="refused by the server",
    )
    assert outcome.execution_failure == ""
    assert outcome.goal_status is None
    assert outcome.result is None
    assert outcome.reason is None


def test_an_answered_outcome_has_no_rejection() -> None:
    state, uuid = running(child=6)
    _, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6))
    outcome = only(outputs, Outcome)
    assert outcome.rejection is None
    assert outcome.execution_failure == ""


def test_next_has_no_stubbornness_by_default() -> None:
    _, send = sent(next_a(waiting()))
    assert send.goal.stubborn_period == 0.0


# --------------------------------------------------------------------------- seqs as uint32 serial numbers


@pytest.mark.parametrize(
    ("current", "arriving", "adopted"),
    [
        (1, 2, True),
        (1, 100, True),
        (1, 1000, True),
        (0, 2**31 - 1, True),  # the farthest seq that is still newer
        (0, 2**31, False),  # exactly half way round: not newer
        (0, 2**31 + 1, False),
        (5, 4, False),
        (0, U32, False),
        (U32, 0, True),
        (U32 - 10, 20, True),
    ],
)
def test_seq_order_is_rfc_1982(current: int, arriving: int, adopted: bool) -> None:
    state = waiting(seq=current)
    after, outputs = feed(state, status(arriving, WAITING, 9))
    if adopted:
        assert (after.seq, after.newest_seq) == (arriving, arriving)
        assert outputs == [ViewChanged(phase=WAITING, seq=arriving, current_id=9, status="standby")]
    else:
        assert after == state
        assert outputs == [
            Ignored(input="status_received", why=f"status of run {arriving}, older than run {current}")
        ]
    after, outputs = feed(state, begin(arriving, '{"detail": "x"}'))
    if adopted:
        assert outputs == [RunBegan(seq=arriving, description='{"detail": "x"}')]
    else:
        assert outputs == [
            Ignored(input="begin_received", why=f"begin of run {arriving}, older than run {current}")
        ]


# --------------------------------------------------------------------------- local refusal sentences


def test_refusal_sentences() -> None:
    # seq_mismatch
    state, _ = feed(waiting(seq=1), begin(2))
    assert refusal(client.request_finish(state, now=0)).text == (
        "run 2 has begun and its status has not arrived; a goal for run 1 would be refused"
    )
    # inactive
    assert refusal(client.request_finish(ClientState.new(PREFIX), now=0)).text == (
        "no dynamic event is active for this robot"
    )
    # busy: a child runs
    state, _ = running(child=6)
    assert refusal(next_a(state)).text == "event 6 is running: only a CANCEL with its id is accepted"
    # busy: our own goals
    state, send = sent(next_a(waiting()))
    rejection = refusal(client.request_finish(state, now=0))
    assert rejection.text == f"this client's NEXT goal {send.goal_uuid} is still open; another would race it"
    assert rejection.current_id is None
    state, send = sent(client.request_finish(waiting(), now=0))
    assert refusal(next_a(state)).text == (
        f"this client's FINISHED goal {send.goal_uuid} is still open; another would race it"
    )
    # cancel_idle
    assert refusal(client.request_cancel(waiting(), now=0)).text == "no event is running to cancel"


def test_busy_with_our_open_next_names_its_child_once_known() -> None:
    state, uuid = running(child=6)
    state, _ = feed(state, status(1, WAITING, 6))  # the view lost the RUNNING; our NEXT is still open
    rejection = refusal(client.request_finish(state, now=0))
    assert rejection.reason is RejectReason.BUSY
    assert rejection.current_id == 6
    assert rejection.text == f"this client's NEXT goal {uuid} is still open; another would race it"


def test_an_open_goal_of_an_older_run_does_not_make_the_new_run_busy() -> None:
    state, first = sent(next_a(waiting(seq=1)))
    state, _ = feed(state, status(1, INACTIVE), begin(2), status(2, WAITING, 3))
    assert state.goal(first.goal_uuid) is not None  # its answer has not arrived
    state, second = sent(next_a(state))
    assert (second.goal.dynamic_event_seq, second.goal.id) == (2, 4)
    _, finish = sent(
        client.request_finish(
            client.step(state, answer(second.goal_uuid, GoalStatus.SUCCEEDED, "completed", 4)).state, now=0
        )
    )
    assert finish.goal.dynamic_event_seq == 2


def test_an_open_cancel_does_not_make_a_next_busy() -> None:
    state, uuid = running(child=6)
    state, cancel = sent(client.request_cancel(state, now=0))
    # the NEXT's answer says child 6 has ended; the CANCEL's answer and the status have not arrived
    state, _ = feed(state, answer(uuid, GoalStatus.ABORTED, "canceled", 6))
    assert state.goal(cancel.goal_uuid) is not None
    _, send = sent(next_a(state))
    assert send.goal.id == 7
    _, finish = sent(client.request_finish(state, now=0))
    assert finish.goal.event_type == EventType.FINISHED


@pytest.mark.parametrize(
    ("categories", "text"),
    [
        (["go_to_place", "dock"], "category 'teleport' is not supported; supported: dock, go_to_place"),
        (["go_to_place"], "category 'teleport' is not supported; supported: go_to_place"),
        ([], "category 'teleport' is not supported; supported: none"),
    ],
)
def test_unsupported_category_sentence(categories: list[str], text: str) -> None:
    rejection = refusal(client.request_next(waiting(categories=categories), "teleport", '"a"', now=0))
    assert rejection.reason is RejectReason.UNSUPPORTED_CATEGORY
    assert rejection.text == text
    assert rejection.categories == tuple(sorted(categories))


def test_not_json_sentence_matches_the_server() -> None:
    rejection = refusal(client.request_next(waiting(), "go_to_place", "[1,", now=0))
    server = machine.State.new("f", "r")
    server = machine.step(
        server, ins.Begin(description="{}", event_id=5, now=0), machine.ServerConfig()
    ).state
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    decision = machine.accept(
        server,
        Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description="[1,", id=6),
        config,
    )
    assert isinstance(decision, outs.Rejected)
    assert (rejection.reason, rejection.text, rejection.errors) == (
        decision.reason,
        decision.text,
        decision.errors,
    )


@pytest.mark.parametrize("period", [math.nan, math.inf, -math.inf])
def test_non_finite_period_sentence(period: float) -> None:
    rejection = refusal(client.request_next(waiting(), "go_to_place", '"a"', stubborn_period=period, now=0))
    assert rejection.text == f"stubborn_period {period} is not a finite number"


def test_stale_id_sentence() -> None:
    rejection = refusal(next_a(waiting(event_id=U64)))
    assert rejection.text == f"no id above {U64}, the highest id seen in this run, is left"
    assert (rejection.current_id, rejection.requested_id) == (U64, U64)


def test_cancel_idle_carries_the_servers_failure_string() -> None:
    rejection = refusal(client.request_cancel(waiting(), now=0))
    assert rejection.execution_failure == "an idle dynamic event cannot be cancelled"


# --------------------------------------------------------------------------- notices and outcome sentences


def test_ignored_sentences() -> None:
    state = waiting()
    unknown = "f" * 32
    for event in (
        GoalResponse(goal_uuid=unknown, accepted=True),
        FeedbackReceived(goal_uuid=unknown, feedback=Feedback()),
        answer(unknown, GoalStatus.SUCCEEDED),
    ):
        assert client.step(state, event).outputs == (
            Ignored(input=event.KIND, why=f"no open goal {unknown}"),
        )
    assert client.step(state, begin(1)).outputs == (
        Ignored(input="begin_received", why="run 1 was already described"),
    )
    message = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=7, status="standby", id=5)
    assert client.step(state, StatusReceived(message=message)).outputs == (
        Ignored(input="status_received", why="dynamic_state 7 is none of INACTIVE, WAITING, RUNNING"),
    )
    state, send = sent(client.request_finish(state, now=0))
    state, _ = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=True))
    assert client.step(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False)).outputs == (
        Ignored(input="goal_response", why=f"goal {send.goal_uuid} was accepted"),
    )


def test_rejection_outcome_sentences() -> None:
    state, send = sent(next_a(waiting()))
    busy = outs.Rejected(reason=RejectReason.BUSY, text="event 9 is running", current_id=9)
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False, rejection=busy))
    assert only(outputs, Outcome).text == "refused by the server: event 9 is running"
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    assert only(outputs, Outcome).text == "refused by the server"
    ended, _ = feed(state, status(1, INACTIVE))
    _, outputs = feed(ended, GoalResponse(goal_uuid=send.goal_uuid, accepted=False, rejection=busy))
    outcome = only(outputs, Outcome)
    assert (outcome.kind, outcome.text, outcome.status) == (
        OutcomeKind.SUPERSEDED,
        "refused after run 1 ended",
        "",
    )


def test_failure_outcome_sentences() -> None:
    state, send = sent(next_a(waiting()))
    uuid = send.goal_uuid
    _, outputs = feed(state, answer(uuid, GoalStatus.CANCELED, failure="cancelled while not running"))
    assert only(outputs, Outcome).text == "cancelled before it began: cancelled while not running"
    _, outputs = feed(state, answer(uuid, GoalStatus.ABORTED, failure="race condition"))
    assert only(outputs, Outcome).text == "could not begin: race condition"
    ended, _ = feed(state, status(1, INACTIVE))
    _, outputs = feed(ended, answer(uuid, GoalStatus.ABORTED, failure="race condition"))
    assert only(outputs, Outcome).text == "could not begin after run 1 ended: race condition"


@pytest.mark.parametrize(
    ("failure", "reason"),
    [
        ("Description parsing failure\n -- first\n -- second", RejectReason.DESCRIPTION_INVALID),
        ("race condition\nmore\nlines", RejectReason.RACE),
        ("race condition ", None),
    ],
)
def test_failure_reason_reads_the_first_line(failure: str, reason: RejectReason | None) -> None:
    state, send = sent(next_a(waiting()))
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, failure=failure))
    outcome = only(outputs, Outcome)
    assert (outcome.reason, outcome.execution_failure) == (reason, failure)


def test_result_sentences() -> None:
    state, uuid = running(child=6)
    _, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "underway", 6))
    outcome = only(outputs, Outcome)
    assert (outcome.kind, outcome.text) == (
        OutcomeKind.ERROR,
        "the event ended 'underway', which is not a final status",
    )
    _, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6))
    assert only(outputs, Outcome).text == "the event ended 'completed'"


def test_timeout_sentence() -> None:
    state, send = sent(next_a(waiting(), timeout=10 * NS))
    state, _ = feed(state, Tick(now=10))
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, "canceled", 6))
    outcome = only(outputs, Outcome)
    assert (outcome.kind, outcome.text) == (
        OutcomeKind.TIMEOUT,
        "outran its timeout; the event ended 'canceled'",
    )


# --------------------------------------------------------------------------- knowledge from answers


def test_an_execution_failure_teaches_no_end() -> None:
    state, send = sent(next_a(waiting()))
    state, _ = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, failure="race condition"))
    assert (state.ended_id, state.last_id, state.finished) == (None, 6, False)


def test_an_older_runs_finished_does_not_end_the_new_run() -> None:
    state, send = sent(client.request_finish(waiting(seq=1), now=0))
    state, _ = feed(state, begin(2), status(2, WAITING, 3))
    state, _ = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 5))
    assert state.finished is False
    assert state.last_id == 3
    _, next_goal = sent(next_a(state))
    assert (next_goal.goal.dynamic_event_seq, next_goal.goal.id) == (2, 4)


def test_an_older_runs_result_teaches_nothing_about_the_new_run() -> None:
    state, send = sent(next_a(waiting(seq=1)))
    state, _ = feed(state, begin(2), status(2, WAITING, 3))
    state, _ = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 40))
    assert (state.ended_id, state.last_id) == (None, 3)


# --------------------------------------------------------------------------- timeouts


def test_a_running_status_sends_the_timeout_cancel() -> None:
    state, send = sent(next_a(waiting(), timeout=10 * NS))
    state, _ = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=True))
    state, outputs = feed(state, Tick(now=10))
    assert outputs == [TimedOut(goal_uuid=send.goal_uuid, id=6, deadline=10)]  # no child known yet
    state, outputs = feed(state, status(1, RUNNING, 6, "underway"))
    cancel = only(outputs, SendGoal)
    assert cancel.goal == Goal(dynamic_event_seq=1, event_type=EventType.CANCEL, id=6)


def test_timed_out_names_the_child_feedback_named() -> None:
    # under id policy "adapter" the server numbers the child itself
    state, send = sent(next_a(waiting(), timeout=10 * NS))
    assert send.goal.id == 6
    state, _ = feed(
        state, FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=9))
    )
    _, outputs = feed(state, Tick(now=10))
    assert outputs[0] == TimedOut(goal_uuid=send.goal_uuid, id=9, deadline=10)
    assert only(outputs, SendGoal).goal.id == 9


def test_a_goal_without_deadline_does_not_stop_the_tick() -> None:
    state, first = sent(next_a(waiting(seq=1)))  # no timeout; its answer never arrives
    state, _ = feed(state, status(1, INACTIVE), begin(2), status(2, WAITING, 3))
    state, second = sent(next_a(state, timeout=10 * NS))
    assert [goal.goal_uuid for goal in state.goals] == [first.goal_uuid, second.goal_uuid]
    assert client.next_deadline(state) == 10
    _, outputs = feed(state, Tick(now=10))
    assert outputs[0] == TimedOut(goal_uuid=second.goal_uuid, id=4, deadline=10)


def test_an_already_timed_out_goal_does_not_stop_the_tick() -> None:
    state, first = sent(next_a(waiting(seq=1), timeout=5 * NS))
    state, _ = feed(state, Tick(now=5), status(1, INACTIVE), begin(2), status(2, WAITING, 3))
    state, second = sent(next_a(state, timeout=10 * NS))
    _, outputs = feed(state, Tick(now=10))
    assert outputs == [TimedOut(goal_uuid=second.goal_uuid, id=4, deadline=10)]
    assert first.goal_uuid != second.goal_uuid


# --------------------------------------------------------------------------- hand-built states


def test_a_state_with_a_view_but_no_run_heard_of() -> None:
    # ClientState is public: a caller may build one from a saved view.  Without a
    # newest run, no run is known to be over, so a refusal is a plain rejection.
    state = ClientState(uuid_prefix=PREFIX, phase=WAITING, seq=1, current_id=5, status="standby")
    state, send = sent(client.request_finish(state, now=0))
    _, outputs = feed(state, GoalResponse(goal_uuid=send.goal_uuid, accepted=False))
    assert only(outputs, Outcome).kind is OutcomeKind.REJECTED
    _, outputs = feed(state, answer(send.goal_uuid, GoalStatus.ABORTED, failure="race condition"))
    outcome = only(outputs, Outcome)
    assert (outcome.kind, outcome.reason) == (OutcomeKind.EXECUTION_FAILURE, RejectReason.RACE)


# --------------------------------------------------------------------------- a bug found on the way


def _wrapped_adapter_run() -> tuple[ClientState, machine.State, machine.ServerConfig]:
    """rmf_ros2 ids: our NEXT took child 2**64 - 1 and ended; a foreign NEXT then got child 0 (R6.2)."""
    config = machine.ServerConfig.rmf_ros2({"go_to_place": machine.any_description})
    server = machine.step(
        machine.State.new("f", "r"), ins.Begin(description="{}", event_id=U64 - 1, now=0), config
    ).state
    state, _ = feed(ClientState.new(PREFIX), StatusReceived(message=machine.status_message(server, 0)))
    state, send = sent(next_a(state))
    for event in (
        ins.GoalRequested(goal_uuid=send.goal_uuid, goal=send.goal, now=0),
        ins.GoalStarted(goal_uuid=send.goal_uuid, now=0),
        ins.ChildFinished(status="completed", now=0),
    ):
        server = machine.step(server, event, config).state
    state, _ = feed(
        state,
        GoalResponse(goal_uuid=send.goal_uuid, accepted=True),
        answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", U64),
    )
    foreign = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description='"b"')
    for event in (
        ins.GoalRequested(goal_uuid="f" * 32, goal=foreign, now=0),
        ins.GoalStarted(goal_uuid="f" * 32, now=0),
    ):
        server = machine.step(server, event, config).state
    assert server.phase is RUNNING
    assert server.current_id == 0  # last_id + 1 modulo 2**64
    state, _ = feed(state, StatusReceived(message=machine.status_message(server, 0)))
    assert (state.phase, state.current_id, state.ended_id) == (RUNNING, 0, U64)
    return state, server, config


def test_client_knows_the_child_runs_after_an_adapter_id_wrap() -> None:
    # Found by tests/tools/demo/test_simulated_session.py::test_client_and_server_agree (config adapter_ids,
    # begin event_id 2**64 - 2), which fails on this example once Hypothesis draws it.
    state, server, config = _wrapped_adapter_run()
    cancel = client.request_cancel(state, now=0)
    assert isinstance(cancel.outputs[0], SendGoal)  # the server would accept a CANCEL of child 0
    finish = refusal(client.request_finish(state, now=0))
    decision = machine.accept(server, Goal(dynamic_event_seq=1, event_type=EventType.FINISHED), config)
    assert isinstance(decision, outs.Rejected)
    assert finish.reason is decision.reason  # busy


# --------------------------------------------------------------------------- survivors of the split layout


@pytest.mark.spec("R4.2", "R4.6")
def test_the_clients_own_refusals_carry_the_rules_of_their_reasons() -> None:
    """A newer run's missing status is the server's R4.2; an own open NEXT is the server's R4.6."""
    state = waiting(1)
    state, _ = feed(state, begin(2))  # run 2 has begun, its status has not arrived
    newer = refusal(next_a(state))
    assert (newer.reason, newer.rule) == (RejectReason.SEQ_MISMATCH, "R4.2")
    state, _ = sent(next_a(waiting(1)))
    own = refusal(client.request_finish(state, now=0))
    assert (own.reason, own.rule) == (RejectReason.BUSY, "R4.6")


@pytest.mark.spec("R9.1")
def test_an_own_next_without_a_child_yet_leaves_the_cancel_to_the_viewed_child() -> None:
    """Our NEXT is accepted and has no child yet; another client's child 8 runs: a CANCEL names 8."""
    state, send = sent(next_a(waiting(1)))
    state, _ = feed(
        state, GoalResponse(goal_uuid=send.goal_uuid, accepted=True), status(1, RUNNING, 8, "underway")
    )
    cancel = client.request_cancel(state, now=0)
    (output,) = cancel.outputs
    assert isinstance(output, SendGoal) and output.goal.id == 8


@pytest.mark.spec("R8.1")
def test_a_second_childs_end_is_known_before_its_status() -> None:
    """Child 6 ended, then child 7: its answer arrives before the status; a NEXT is not refused as busy."""
    state, uuid = running(1, 6)
    state, _ = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", 6), status(1, WAITING, 6))
    state, send = sent(next_a(state))
    state, _ = feed(
        state,
        GoalResponse(goal_uuid=send.goal_uuid, accepted=True),
        FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=7)),
        status(1, RUNNING, 7, "underway"),
        answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", 7),
    )
    assert state.ended_id == 7
    (output,) = next_a(state).outputs
    assert isinstance(output, SendGoal), output
