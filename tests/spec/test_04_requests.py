"""§4. Goal requests: the tests of the rules of docs/spec.md §4.

The section's conformance vectors are src/dynevent/conformance/vectors/04-requests.json.

Every reject reason, its values and the check order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import attrs
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from dynevent.errors import InvalidConfig, InvalidDescription
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    QueuedGoal,
    ServerConfig,
    any_description,
)
from dynevent.wire.description import MAX_DESCRIPTION_BYTES, EventDescription
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType, IdPolicy, RejectReason
from support.scenario import (
    ANY_TEXT,
    CANCEL_ID,
    CATEGORIES,
    CONFIG,
    IDLE_CANCEL,
    INVALID_EVENT_TYPE,
    PARSE_FAILURE,
    PLACE,
    RUNNING,
    SHUTTING_DOWN,
    WAITING,
    Run,
    cancel_goal,
    deferred,
    finished_goal,
    goal,
    next_goal,
    rejected,
    running,
    shut_down,
    u,
    waiting,
)

U64_MAX = 2**64 - 1


def _rejection(outputs: tuple[Any, ...]) -> outs.Rejected:
    assert len(outputs) == 1
    assert isinstance(outputs[0], outs.GoalRejected)
    return outputs[0].rejection


R = RejectReason
ACCEPTED = (outs.GoalAccepted(goal_uuid=u(9)),)


def _only_rejection(outputs: tuple[Any, ...]) -> outs.Rejected:
    assert len(outputs) == 1
    assert isinstance(outputs[0], outs.GoalRejected)
    assert outputs[0].goal_uuid == u(9)
    return outputs[0].rejection


def _assert_description_rejection(
    outputs: tuple[Any, ...], reason: RejectReason, errors: Sequence[str] | None = None
) -> outs.Rejected:
    """A description rejection: its errors, and the rmf_ros2 string with one `\\n -- ` line per error."""
    rejection = _only_rejection(outputs)
    assert rejection.reason is reason
    assert rejection.text
    if errors is None:
        assert len(rejection.errors) == 1
        assert rejection.errors[0]
    else:
        assert rejection.errors == tuple(errors)
    assert rejection.execution_failure == PARSE_FAILURE + "".join(f"\n -- {e}" for e in rejection.errors)
    assert (rejection.expected_seq, rejection.received_seq, rejection.current_id, rejection.requested_id) == (
        None,
        None,
        None,
        None,
    )
    assert rejection.categories == ()
    return rejection


# --------------------------------------------------------------------------- R4.1


@pytest.mark.spec("R4.1")
def test_shutting_down_is_checked_first() -> None:
    run = running(child_id=5)
    run.shutdown()
    for number, request in enumerate(
        (next_goal(1, 6), next_goal(7, 6), goal(1, 7), cancel_goal(1, 99), finished_goal(0)), start=10
    ):
        assert run.request(u(number), request) == (
            rejected(u(number), R.SHUTTING_DOWN, execution_failure=SHUTTING_DOWN),
        )


# --------------------------------------------------------------------------- R4.2


@pytest.mark.spec("R4.2")
@given(current=st.integers(0, 2**32 - 1), received=st.integers(0, 2**32 - 1), event_type=st.integers(0, 9))
def test_seq_mismatch_for_any_seq_pair(current: int, received: int, event_type: int) -> None:
    run = Run().evolve(seq=(current - 1) % 2**32)
    run.begin()
    assert run.seq == current
    assume(received != current)
    request = goal(received, event_type, id=2, category="go_to_place", description=PLACE)
    assert run.request(u(9), request) == (
        rejected(
            u(9),
            R.SEQ_MISMATCH,
            text=f"Expected {current}, received {received}",
            expected_seq=current,
            received_seq=received,
        ),
    )


@pytest.mark.spec("R4.2", "R4.3")
def test_stale_seq_while_inactive_is_a_seq_mismatch() -> None:
    run = waiting(event_id=1)
    run.submit(u(1), finished_goal(1))
    # inactive and stale: the seq decides
    assert run.request(u(9), next_goal(0, 5)) == (
        rejected(u(9), R.SEQ_MISMATCH, text="Expected 1, received 0", expected_seq=1, received_seq=0),
    )


@pytest.mark.spec("R4.2", "R3.2")
def test_seq_mismatch_after_the_wrap() -> None:
    run = waiting(seq=2**32 - 1)
    assert run.seq == 0
    assert run.request(u(9), next_goal(2**32 - 1, 5)) == (
        rejected(
            u(9),
            R.SEQ_MISMATCH,
            text="Expected 0, received 4294967295",
            expected_seq=0,
            received_seq=4294967295,
        ),
    )


# --------------------------------------------------------------------------- R4.3


@pytest.mark.spec("R4.3")
def test_inactive_before_the_first_begin() -> None:
    run = Run()
    assert run.request(u(9), next_goal(0, 5)) == (rejected(u(9), R.INACTIVE),)


@pytest.mark.spec("R4.3", "R4.4", "R4.5")
def test_inactive_after_the_run_ended_beats_event_type_checks() -> None:
    run = waiting(event_id=1)
    run.submit(u(1), finished_goal(1))
    for request in (next_goal(1, 5), goal(1, 0), goal(1, 4), cancel_goal(1, 5), finished_goal(1)):
        assert run.request(u(9), request) == (rejected(u(9), R.INACTIVE),)


# --------------------------------------------------------------------------- R4.4, R4.5


@pytest.mark.spec("R4.4")
def test_event_type_zero_is_uninitialized() -> None:
    run = waiting()
    assert run.request(u(9), goal(1, 0, id=2, category="go_to_place", description=PLACE)) == (
        rejected(u(9), R.UNINITIALIZED_EVENT_TYPE, execution_failure=INVALID_EVENT_TYPE),
    )


@pytest.mark.spec("R4.5")
@pytest.mark.parametrize("event_type", [4, 7, 2**32 - 1])
def test_event_type_above_three_is_unknown(event_type: int) -> None:
    run = waiting()
    assert run.request(u(9), goal(1, event_type, id=2)) == (
        rejected(u(9), R.UNKNOWN_EVENT_TYPE, execution_failure=INVALID_EVENT_TYPE),
    )


@pytest.mark.spec("R4.4", "R4.5", "R4.6")
@pytest.mark.parametrize(
    ("event_type", "reason"), [(0, R.UNINITIALIZED_EVENT_TYPE), (7, R.UNKNOWN_EVENT_TYPE)]
)
def test_bad_event_type_while_busy_is_not_busy(event_type: int, reason: RejectReason) -> None:
    run = running(child_id=5)
    assert run.request(u(9), goal(1, event_type, id=5)) == (
        rejected(u(9), reason, execution_failure=INVALID_EVENT_TYPE),
    )


# --------------------------------------------------------------------------- R4.6


@pytest.mark.spec("R4.6")
@pytest.mark.parametrize("request_goal", [next_goal(1, 6), finished_goal(1)], ids=["NEXT", "FINISHED"])
def test_busy_while_a_child_runs(request_goal: Goal) -> None:
    run = running(child_id=5)
    assert run.request(u(9), request_goal) == (rejected(u(9), R.BUSY, current_id=5),)


@pytest.mark.spec("R4.6", "R6.3")
def test_busy_while_a_deferred_child_holds_the_slot() -> None:
    run = deferred(child_id=5)
    assert run.request(u(9), next_goal(1, 6)) == (rejected(u(9), R.BUSY, current_id=5),)


@pytest.mark.spec("R4.6", "R9.3")
def test_busy_while_a_cancel_is_in_progress() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.request(u(9), next_goal(1, 6)) == (rejected(u(9), R.BUSY, current_id=5),)


@pytest.mark.spec("R4.6", "R4.7", "R4.9", "R4.11", "R4.12")
def test_busy_comes_before_the_next_checks() -> None:
    run = running(child_id=5)
    request = next_goal(1, 0, category="nope", description="{", stubborn=math.nan)
    assert run.request(u(9), request) == (rejected(u(9), R.BUSY, current_id=5),)


# --------------------------------------------------------------------------- R4.7


@pytest.mark.spec("R4.7")
def test_unsupported_category_lists_the_supported_ones_sorted() -> None:
    config = ServerConfig(
        categories={"zeta": any_description, "alpha": any_description, "mid": any_description}
    )
    run = waiting(config=config)
    assert run.request(u(9), next_goal(1, 2, category="go_to_place")) == (
        rejected(u(9), R.UNSUPPORTED_CATEGORY, categories=("alpha", "mid", "zeta")),
    )


@pytest.mark.spec("R4.7")
def test_unsupported_category_with_no_category_configured() -> None:
    run = waiting(config=ServerConfig())
    assert run.request(u(9), next_goal(1, 2)) == (rejected(u(9), R.UNSUPPORTED_CATEGORY, categories=()),)


@pytest.mark.spec("R4.7", "R4.9")
def test_unsupported_category_comes_before_the_description() -> None:
    run = waiting()
    assert run.request(u(9), next_goal(1, 2, category="dock", description="{")) == (
        rejected(u(9), R.UNSUPPORTED_CATEGORY, categories=("go_to_place", "perform_action")),
    )


# --------------------------------------------------------------------------- R4.8


@pytest.mark.spec("R4.8")
def test_description_longer_than_the_default_limit() -> None:
    run = waiting()
    at_limit = '"' + "a" * 999_998 + '"'
    assert len(at_limit) == 1_000_000
    assert run.request(u(8), next_goal(1, 2, description=at_limit)) == (outs.GoalAccepted(goal_uuid=u(8)),)
    above = '"' + "a" * 999_999 + '"'
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 3, description=above)), R.DESCRIPTION_INVALID
    )


@pytest.mark.spec("R4.8", "R1.5")
def test_description_limit_counts_utf8_bytes_as_the_begin_limit_does() -> None:
    run = waiting(config=attrs.evolve(CONFIG, max_description_length=6))
    # four characters, six UTF-8 bytes: at the limit
    assert run.request(u(8), next_goal(1, 2, description='"éé"')) == (outs.GoalAccepted(goal_uuid=u(8)),)
    # five characters, seven bytes: above it, although a count of characters would accept it
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 3, description='"ééa"')), R.DESCRIPTION_INVALID
    )


@pytest.mark.spec("R4.8", "R1.5")
def test_a_next_description_never_exceeds_what_a_begin_accepts() -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories={"dance": any_description}, max_description_length=MAX_DESCRIPTION_BYTES + 1)
    assert caught.value.field == "max_description_length"
    run = waiting()
    at_limit = '"' + "é" * ((MAX_DESCRIPTION_BYTES - 2) // 2) + '"'
    assert len(at_limit.encode()) == MAX_DESCRIPTION_BYTES
    assert run.request(u(8), next_goal(1, 2, description=at_limit)) == (outs.GoalAccepted(goal_uuid=u(8)),)
    above = at_limit[:-1] + 'a"'
    refused = run.request(u(9), next_goal(1, 3, description=above))
    _assert_description_rejection(refused, R.DESCRIPTION_INVALID)
    with pytest.raises(InvalidDescription):
        EventDescription.from_json('{"detail": ' + above + "}")


@pytest.mark.spec("R4.8", "R4.9")
def test_length_is_checked_before_json() -> None:
    run = waiting(config=attrs.evolve(CONFIG, max_description_length=3))
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, description="{{{{")), R.DESCRIPTION_INVALID
    )


# --------------------------------------------------------------------------- R4.9


@pytest.mark.spec("R4.9")
@pytest.mark.parametrize(
    "description",
    [
        "",
        "{",
        "lobby",
        '{"place": "a", "place": "b"}',
        "[" * 65 + "]" * 65,
        '{"place": "a"} trailing',
    ],
    ids=["empty", "unclosed", "bare-word", "duplicate-key", "nested-65", "trailing"],
)
def test_description_not_json(description: str) -> None:
    run = waiting()
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, category="perform_action", description=description)),
        R.DESCRIPTION_NOT_JSON,
    )


@pytest.mark.spec("R4.9")
@pytest.mark.parametrize(
    ("category", "description"),
    [
        ("perform_action", "NaN"),
        ("perform_action", "[Infinity, -Infinity]"),
        ("go_to_place", '{"place": "a", "speed": NaN}'),
        ("perform_action", "[" * 64 + "]" * 64),
    ],
    ids=["NaN", "infinities", "NaN-inside", "nested-64"],
)
def test_description_json_edge_cases_accepted(category: str, description: str) -> None:
    run = waiting()
    assert run.request(u(9), next_goal(1, 2, category=category, description=description)) == ACCEPTED


@pytest.mark.spec("R4.9", "R4.11")
def test_not_json_comes_before_the_stubborn_period() -> None:
    run = waiting()
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, description="{", stubborn=math.nan)), R.DESCRIPTION_NOT_JSON
    )


# --------------------------------------------------------------------------- R4.10


@pytest.mark.spec("R4.10")
def test_validator_errors() -> None:
    run = waiting()
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, description='{"place": 3}')),
        R.DESCRIPTION_INVALID,
        ["expected a place name or an object with a string 'place'"],
    )


@pytest.mark.spec("R4.10")
def test_one_failure_line_per_validator_error() -> None:
    seen: list[tuple[str, Any]] = []

    def two_errors(category: str, description: Any) -> Sequence[str]:
        seen.append((category, description))
        return ["first problem", "second problem"]

    run = waiting(config=ServerConfig(categories={"dock": two_errors}))
    rejection = _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, category="dock", description='{"at": [1, 2.5]}')),
        R.DESCRIPTION_INVALID,
        ["first problem", "second problem"],
    )
    assert rejection.execution_failure == "Description parsing failure\n -- first problem\n -- second problem"
    # the validator gets the category and the parsed description
    assert seen == [("dock", {"at": [1, 2.5]})]


@pytest.mark.spec("R4.10")
def test_a_validator_that_raises_is_one_error() -> None:
    def broken(category: str, description: Any) -> Sequence[str]:
        raise KeyError("schema")

    run = waiting(config=ServerConfig(categories={"dock": broken}))
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, category="dock", description="{}")), R.DESCRIPTION_INVALID
    )


@pytest.mark.spec("R4.10", "R4.11")
def test_validator_errors_come_before_the_stubborn_period() -> None:
    run = waiting()
    _assert_description_rejection(
        run.request(u(9), next_goal(1, 2, description="[]", stubborn=math.inf)), R.DESCRIPTION_INVALID
    )


# --------------------------------------------------------------------------- R4.11


@pytest.mark.spec("R4.11")
@pytest.mark.parametrize("period", [math.nan, math.inf, -math.inf])
def test_non_finite_stubborn_period(period: float) -> None:
    run = waiting()
    assert run.request(u(9), next_goal(1, 2, stubborn=period)) == (
        rejected(u(9), R.NON_FINITE_STUBBORN_PERIOD),
    )


@pytest.mark.spec("R4.11", "R4.12")
def test_non_finite_period_comes_before_a_stale_id() -> None:
    run = waiting(event_id=10)
    assert run.request(u(9), next_goal(1, 3, stubborn=math.nan)) == (
        rejected(u(9), R.NON_FINITE_STUBBORN_PERIOD),
    )


@pytest.mark.spec("R4.11")
@pytest.mark.parametrize("period", [3.4028234663852886e38, -1.0, 0.0, 1e-45])
def test_finite_stubborn_periods_accepted(period: float) -> None:
    run = waiting()
    assert run.request(u(9), next_goal(1, 2, stubborn=period)) == ACCEPTED


# --------------------------------------------------------------------------- R4.12


@pytest.mark.spec("R4.12")
@pytest.mark.parametrize("requested", [9, 10])
def test_stale_id(requested: int) -> None:
    run = waiting(event_id=10)
    assert run.request(u(9), next_goal(1, requested)) == (
        rejected(u(9), R.STALE_ID, current_id=10, requested_id=requested),
    )


@pytest.mark.spec("R4.12", "R6.2")
def test_stale_id_follows_the_last_child() -> None:
    run = waiting(event_id=10)
    assert run.request(u(8), next_goal(1, 11)) == (outs.GoalAccepted(goal_uuid=u(8)),)
    run.start(u(8))
    run.child_end("completed")
    assert run.request(u(9), next_goal(1, 11)) == (
        rejected(u(9), R.STALE_ID, current_id=11, requested_id=11),
    )
    assert run.request(u(7), next_goal(1, 2**64 - 1)) == (outs.GoalAccepted(goal_uuid=u(7)),)


@pytest.mark.spec("R4.12", "R17.3")
def test_no_stale_id_under_the_adapter_policy() -> None:
    run = waiting(event_id=10, config=attrs.evolve(CONFIG, id_policy=IdPolicy.ADAPTER))
    assert run.request(u(9), next_goal(1, 0)) == ACCEPTED


# --------------------------------------------------------------------------- R4.13, R4.14


@pytest.mark.spec("R4.13")
def test_cancel_idle() -> None:
    run = waiting()
    assert run.request(u(9), cancel_goal(1, 1)) == (
        rejected(u(9), R.CANCEL_IDLE, execution_failure=IDLE_CANCEL),
    )


@pytest.mark.spec("R4.13")
def test_cancel_idle_ignores_the_unused_fields() -> None:
    run = waiting()
    request = goal(1, EventType.CANCEL, id=3, category="nope", description="{", stubborn=math.nan)
    assert run.request(u(9), request) == (rejected(u(9), R.CANCEL_IDLE, execution_failure=IDLE_CANCEL),)


@pytest.mark.spec("R4.14")
@pytest.mark.parametrize("requested", [0, 4, 6, 2**64 - 1])
def test_cancel_id_mismatch(requested: int) -> None:
    run = running(child_id=5)
    assert run.request(u(9), cancel_goal(1, requested)) == (
        rejected(
            u(9), R.CANCEL_ID_MISMATCH, current_id=5, requested_id=requested, execution_failure=CANCEL_ID
        ),
    )


@pytest.mark.spec("R4.14", "R4.16")
def test_cancel_of_the_running_child_is_accepted_started_or_deferred() -> None:
    run = running(child_id=5)
    assert run.request(u(9), cancel_goal(1, 5)) == ACCEPTED
    run = deferred(child_id=5)
    assert run.request(u(9), cancel_goal(1, 5)) == ACCEPTED


# --------------------------------------------------------------------------- unused fields


@pytest.mark.spec("R4.7", "R4.9", "R4.11", "R4.12")
def test_fields_a_goal_type_does_not_use_are_not_checked() -> None:
    run = waiting(event_id=10)
    finished = goal(1, EventType.FINISHED, id=0, category="nope", description="{", stubborn=math.nan)
    assert run.request(u(9), finished) == ACCEPTED
    run = running(child_id=5, event_id=1)
    cancel = goal(1, EventType.CANCEL, id=5, category="nope", description="{", stubborn=-math.inf)
    assert run.request(u(9), cancel) == ACCEPTED


# --------------------------------------------------------------------------- R4.15, R4.16


@pytest.mark.spec("R4.15")
def test_a_rejection_changes_nothing() -> None:
    run = running(child_id=5)
    run.request(u(3), cancel_goal(1, 5))
    for number, request in enumerate(
        (next_goal(1, 6), cancel_goal(1, 6), goal(1, 0), next_goal(2, 6)), start=10
    ):
        outputs = run.request(u(number), request)
        assert len(outputs) == 1
        assert isinstance(outputs[0], outs.GoalRejected)
        assert run.state == run.before


@pytest.mark.spec("R4.15")
def test_accept_is_the_pure_query_behind_the_rejection() -> None:
    run = running(child_id=5)
    decision = run.accept(cancel_goal(1, 4))
    assert decision == outs.Rejected(
        reason=R.CANCEL_ID_MISMATCH,
        text=ANY_TEXT,
        current_id=5,
        requested_id=4,
        execution_failure=CANCEL_ID,
    )
    assert run.request(u(9), cancel_goal(1, 4)) == (outs.GoalRejected(goal_uuid=u(9), rejection=decision),)
    assert run.accept(cancel_goal(1, 5)) == outs.Accepted(event_type=EventType.CANCEL)


@pytest.mark.spec("R4.16")
def test_accepted_goals_queue_in_acceptance_order_and_nothing_else_changes() -> None:
    run = waiting(event_id=1)
    first, second, third = next_goal(1, 7), next_goal(1, 6), finished_goal(1)
    assert run.request(u(3), first) == (outs.GoalAccepted(goal_uuid=u(3)),)
    before = run.before
    assert run.state == attrs.evolve(before, queued=(QueuedGoal(goal_uuid=u(3), goal=first),))
    assert run.request(u(1), second) == (outs.GoalAccepted(goal_uuid=u(1)),)
    assert run.request(u(2), third) == (outs.GoalAccepted(goal_uuid=u(2)),)
    assert run.state == attrs.evolve(
        before,
        queued=(
            QueuedGoal(goal_uuid=u(3), goal=first),
            QueuedGoal(goal_uuid=u(1), goal=second),
            QueuedGoal(goal_uuid=u(2), goal=third),
        ),
    )
    assert run.phase is WAITING


@pytest.mark.spec("R4.16", "R9.3")
def test_a_cancel_is_queued_while_running() -> None:
    run = running(child_id=5)
    assert run.request(u(9), cancel_goal(1, 5)) == ACCEPTED
    assert run.state.queued == (QueuedGoal(goal_uuid=u(9), goal=cancel_goal(1, 5)),)
    assert run.phase is RUNNING


# --------------------------------------------------------------------------- the whole table, as an oracle

_SITUATIONS = ("fresh", "waiting", "running", "ended", "shutdown")
_DESCRIPTIONS = (PLACE, '{"place": 3}', "{", '{"place": "a"}', "[" * 70 + "]" * 70)


def _expected_reason(
    situation: str, request: Goal, config: ServerConfig, last_id: int
) -> RejectReason | None:
    """The §4 table, read top to bottom (standard mode, id policy `goal`)."""
    seq = 0 if situation == "fresh" else 1
    if situation == "shutdown":
        return R.SHUTTING_DOWN
    if request.dynamic_event_seq != seq:
        return R.SEQ_MISMATCH
    if situation in ("fresh", "ended"):
        return R.INACTIVE
    if request.event_type == 0:
        return R.UNINITIALIZED_EVENT_TYPE
    if request.event_type > 3:
        return R.UNKNOWN_EVENT_TYPE
    if situation == "running" and request.event_type != EventType.CANCEL:
        return R.BUSY
    if request.event_type == EventType.NEXT:
        if request.category not in config.categories:
            return R.UNSUPPORTED_CATEGORY
        if request.description == "{" or request.description.startswith("[" * 65):
            return R.DESCRIPTION_NOT_JSON
        if request.category == "go_to_place" and request.description == '{"place": 3}':
            return R.DESCRIPTION_INVALID
        if not math.isfinite(request.stubborn_period):
            return R.NON_FINITE_STUBBORN_PERIOD
        if request.id <= last_id if request.id != 0 else last_id == 2**64 - 1:  # id 0: the server assigns
            return R.STALE_ID
    if request.event_type == EventType.CANCEL:
        if situation != "running":
            return R.CANCEL_IDLE
        if request.id != 5:
            return R.CANCEL_ID_MISMATCH
    return None


@pytest.mark.spec(
    "R4.1",
    "R4.2",
    "R4.3",
    "R4.4",
    "R4.5",
    "R4.6",
    "R4.7",
    "R4.9",
    "R4.10",
    "R4.11",
    "R4.12",
    "R4.13",
    "R4.14",
)
@given(
    situation=st.sampled_from(_SITUATIONS),
    seq=st.sampled_from([0, 1, 2]),
    event_type=st.sampled_from([0, 1, 2, 3, 4, 2**32 - 1]),
    category=st.sampled_from([*CATEGORIES, "dock"]),
    description=st.sampled_from(_DESCRIPTIONS),
    id=st.sampled_from([0, 4, 5, 6, 2**64 - 1]),
    stubborn=st.sampled_from([0.0, 1.5, math.nan, math.inf]),
)
def test_the_first_failing_check_decides(
    situation: str, seq: int, event_type: int, category: str, description: str, id: int, stubborn: float
) -> None:
    if situation == "running":
        run = running(child_id=5, event_id=4)
    else:
        run = Run() if situation == "fresh" else waiting(event_id=4)
        if situation == "ended":
            run.submit(u(1), finished_goal(1))
        elif situation == "shutdown":
            run.shutdown()
    request = goal(seq, event_type, id, category, description, stubborn)
    expected = _expected_reason(situation, request, run.config, run.state.last_id)
    outputs = run.request(u(9), request)
    if expected is None:
        assert outputs == ACCEPTED
    else:
        assert _only_rejection(outputs).reason is expected
        assert run.state == run.before


# --------------------------------------------------------------------------- R4.8


@pytest.mark.spec("R4.8")
def test_too_long_errors_and_failure_string() -> None:
    run = waiting(config=attrs.evolve(CONFIG, max_description_length=4))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, description='"abc"')))
    problem = "description is 5 bytes, above the limit of 4"
    assert rejection.errors == (problem,)
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {problem}"


# --------------------------------------------------------------------------- R4.9


@pytest.mark.spec("R4.9")
def test_not_json_sentence_names_the_category() -> None:
    run = waiting()
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="perform_action", description="{")))
    assert rejection.reason is R.DESCRIPTION_NOT_JSON
    (error,) = rejection.errors
    assert error.startswith("not valid JSON: ")
    assert rejection.text == f"the description of the 'perform_action' event is {error}"
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {error}"


# --------------------------------------------------------------------------- R4.10


@pytest.mark.spec("R4.10")
def test_several_validator_errors_are_joined_in_the_sentence() -> None:
    def two_errors(category: str, description: Any) -> Sequence[str]:
        return ["first problem", "second problem"]

    run = waiting(config=ServerConfig(categories={"dock": two_errors}))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="dock", description="{}")))
    assert rejection.text == "the description does not fit the 'dock' category: first problem; second problem"


@pytest.mark.spec("R4.10")
def test_a_raising_validator_is_one_error_naming_the_exception() -> None:
    def broken(category: str, description: Any) -> Sequence[str]:
        raise KeyError("schema")

    run = waiting(config=ServerConfig(categories={"dock": broken}))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="dock", description="{}")))
    error = "the validator raised KeyError: 'schema'"
    assert rejection.errors == (error,)
    assert rejection.text == f"the description does not fit the 'dock' category: {error}"
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {error}"


# --------------------------------------------------------------------------- R4.15


@pytest.mark.spec("R4.15")
@pytest.mark.parametrize(
    ("build", "sent", "reason", "text"),
    [
        (shut_down, next_goal(1, 2), R.SHUTTING_DOWN, "the server is shutting down"),
        (waiting, next_goal(7, 2), R.SEQ_MISMATCH, "Expected 1, received 7"),
        (Run, next_goal(0, 2), R.INACTIVE, "no dynamic event is active for this robot"),
        (
            waiting,
            goal(1, 0),
            R.UNINITIALIZED_EVENT_TYPE,
            "event_type is 0 (UNINITIALIZED): the goal was default-initialized",
        ),
        (
            waiting,
            goal(1, 4),
            R.UNKNOWN_EVENT_TYPE,
            "event_type 4 is none of NEXT (1), CANCEL (2), FINISHED (3)",
        ),
        (running, next_goal(1, 6), R.BUSY, "event 5 is running: only a CANCEL with its id is accepted"),
        (
            waiting,
            next_goal(1, 2, category="dock"),
            R.UNSUPPORTED_CATEGORY,
            "category 'dock' is not supported; supported: go_to_place, perform_action",
        ),
        (
            lambda: waiting(config=ServerConfig()),
            next_goal(1, 2),
            R.UNSUPPORTED_CATEGORY,
            "category 'go_to_place' is not supported; supported: none",
        ),
        (
            lambda: waiting(config=attrs.evolve(CONFIG, max_description_length=4)),
            next_goal(1, 2, description='"abc"'),
            R.DESCRIPTION_INVALID,
            "description is 5 bytes, above the limit of 4",
        ),
        (
            waiting,
            next_goal(1, 2, description='{"place": 3}'),
            R.DESCRIPTION_INVALID,
            "the description does not fit the 'go_to_place' category: "
            "expected a place name or an object with a string 'place'",
        ),
        (
            waiting,
            next_goal(1, 2, stubborn=math.nan),
            R.NON_FINITE_STUBBORN_PERIOD,
            "stubborn_period nan is not a finite number",
        ),
        (
            waiting,
            next_goal(1, 2, stubborn=-math.inf),
            R.NON_FINITE_STUBBORN_PERIOD,
            "stubborn_period -inf is not a finite number",
        ),
        (waiting, next_goal(1, 1), R.STALE_ID, "id 1 is not greater than 1, the highest id used in this run"),
        (
            lambda: waiting().evolve(last_id=U64_MAX),
            next_goal(1, 0),
            R.STALE_ID,
            f"id 0 asks the server for the next id, and none is left above {U64_MAX}",
        ),
        (waiting, cancel_goal(1, 5), R.CANCEL_IDLE, "no event is running to cancel"),
        (running, cancel_goal(1, 6), R.CANCEL_ID_MISMATCH, "the running event is 5, the CANCEL names 6"),
    ],
    ids=[
        "shutting_down",
        "seq_mismatch",
        "inactive",
        "uninitialized_event_type",
        "unknown_event_type",
        "busy",
        "unsupported_category",
        "unsupported_category_none",
        "too_long",
        "validator",
        "nan_period",
        "infinite_period",
        "stale_id",
        "stale_id_none_left",
        "cancel_idle",
        "cancel_id_mismatch",
    ],
)
def test_rejection_sentences(build: Callable[[], Run], sent: Any, reason: RejectReason, text: str) -> None:
    rejection = _rejection(build().request(u(9), sent))
    assert rejection.reason is reason
    assert rejection.text == text
