"""``dynevent explain``: a state rebuilt from a status message, the verdict, why, what to send instead."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.conformance.explain import UNKNOWN_GOAL, explain, format_explanation, state_from_status
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.testing.strategies import messages
from dynevent.tools import cli
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, RejectReason

INACTIVE = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=0, status="uninitialized", id=0)
WAITING = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=1, status="standby", id=5)
RUNNING = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=2, status="underway", id=8)
NON_FINITE = RejectReason.NON_FINITE_STUBBORN_PERIOD
CANCEL_7 = Goal(dynamic_event_seq=3, event_type=EventType.CANCEL, id=7)
CANCEL_8 = Goal(dynamic_event_seq=3, event_type=EventType.CANCEL, id=8)
NEXT = Goal(
    dynamic_event_seq=3, event_type=EventType.NEXT, category="go_to_place", description='"lobby"', id=9
)


def next_goal(**fields: object) -> Goal:
    values: dict[str, object] = {
        "dynamic_event_seq": 3,
        "event_type": EventType.NEXT,
        "category": "go_to_place",
        "description": '"lobby"',
        "id": 9,
    }
    values.update(fields)
    return Goal(**values)  # type: ignore[arg-type]


def test_state_from_status_gives_back_the_message() -> None:
    for message in (INACTIVE, WAITING, RUNNING):
        state = state_from_status(message)
        assert machine.status_message(state, 0) == message
    running = state_from_status(RUNNING).running
    assert running is not None and running.goal_uuid == UNKNOWN_GOAL and running.started
    deferred = state_from_status(
        DynamicEventStatus(dynamic_event_seq=3, dynamic_state=2, status="queued", id=8)
    )
    assert deferred.interrupted and deferred.running is not None and not deferred.running.started
    with pytest.raises(ValueError, match="dynamic_state 9"):
        state_from_status(DynamicEventStatus(dynamic_state=9))


@pytest.mark.parametrize(
    ("status", "goal", "reason", "rule", "instead"),
    [
        (RUNNING, next_goal(dynamic_event_seq=2), RejectReason.SEQ_MISMATCH, "R4.2", CANCEL_8),
        (INACTIVE, next_goal(), RejectReason.INACTIVE, "R4.3", None),
        (WAITING, next_goal(event_type=0), RejectReason.UNINITIALIZED_EVENT_TYPE, "R4.4", None),
        (WAITING, next_goal(event_type=9), RejectReason.UNKNOWN_EVENT_TYPE, "R4.5", None),
        (RUNNING, next_goal(), RejectReason.BUSY, "R4.6", CANCEL_8),
        (WAITING, next_goal(description="lobby"), RejectReason.DESCRIPTION_NOT_JSON, "R4.9", next_goal()),
        (WAITING, next_goal(stubborn_period=math.nan), NON_FINITE, "R4.11", NEXT),
        (WAITING, next_goal(id=5), RejectReason.STALE_ID, "R4.12", next_goal(id=6)),
        (WAITING, Goal(dynamic_event_seq=3, event_type=2, id=5), RejectReason.CANCEL_IDLE, "R4.13", None),
        (RUNNING, CANCEL_7, RejectReason.CANCEL_ID_MISMATCH, "R4.14", CANCEL_8),
    ],
)  # fmt: skip
def test_each_refusal_says_why_and_what_to_send(
    status: DynamicEventStatus, goal: Goal, reason: RejectReason, rule: str, instead: Goal | None
) -> None:
    explanation = explain(status, goal)
    assert isinstance(explanation.decision, outs.Rejected)
    assert (explanation.decision.reason, explanation.rule) == (reason, rule)
    assert explanation.instead == instead
    assert explanation.advice and not explanation.accepted
    text = format_explanation(explanation)
    assert f"verdict:  rejected: {reason.value} ({rule})" in text


def test_every_correction_is_reported_in_order() -> None:
    goal = next_goal(dynamic_event_seq=1, description="lobby", stubborn_period=float("nan"), id=2)
    explanation = explain(WAITING, goal)
    assert [later.reason for later in explanation.then] == [
        RejectReason.DESCRIPTION_NOT_JSON,
        RejectReason.NON_FINITE_STUBBORN_PERIOD,
        RejectReason.STALE_ID,
    ]
    assert explanation.instead == next_goal(id=6)


def test_known_categories_are_checked() -> None:
    explanation = explain(WAITING, next_goal(category="dance"), categories=("go_to_place", "patrol"))
    assert isinstance(explanation.decision, outs.Rejected)
    assert explanation.decision.reason is RejectReason.UNSUPPORTED_CATEGORY
    assert "go_to_place, patrol" in explanation.advice
    assert not any("categories" in item for item in explanation.unknown)


def test_unknown_categories_are_said_to_be_unknown() -> None:
    explanation = explain(WAITING, next_goal(category="dance"))
    assert explanation.accepted
    assert any("'dance' was taken as supported" in item for item in explanation.unknown)
    # a status names the highest id used (R2.2): that is no longer unknown
    assert not any("highest id used" in item for item in explanation.unknown)


def test_accepted_goals_say_what_happens_at_their_start() -> None:
    assert explain(WAITING, next_goal(stubborn_period=0.5)).at_start == (
        "child 9 starts (R6.4); its stubborn period of 0.5 s will be raised to 2 s, with a warning (R12.2)"
    )
    assert "told to cancel" in explain(RUNNING, Goal(dynamic_event_seq=3, event_type=2, id=8)).at_start
    finished = explain(WAITING, Goal(dynamic_event_seq=3, event_type=3))
    assert finished.accepted and "'completed' and id 5 (R11.1)" in finished.at_start


def test_a_status_cannot_tell_a_deferred_child_from_one_that_reported_queued() -> None:
    queued = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=2, status="queued", id=8)
    explanation = explain(queued, CANCEL_8)
    assert "deferred child 8 is cancelled at once" in explanation.at_start
    assert any("reported 'queued'" in item for item in explanation.unknown)


def test_rmf_ros2_accepts_and_then_aborts() -> None:
    explanation = explain(RUNNING, Goal(dynamic_event_seq=3, event_type=2, id=7), compatibility="rmf_ros2")
    assert isinstance(explanation.decision, outs.Accepted)
    assert explanation.aborted_at_start and not explanation.accepted and explanation.rule == "R17.1"
    assert "'ID for cancel request does not match current event' (R9.2)" in explanation.at_start
    assert explanation.instead == Goal(dynamic_event_seq=3, event_type=2, id=8)
    bad_type = explain(WAITING, Goal(dynamic_event_seq=3, event_type=0), compatibility="rmf_ros2")
    assert bad_type.aborted_at_start and "'invalid event_type' (R17.2)" in bad_type.at_start


def test_an_inconsistent_status_is_said_so() -> None:
    odd = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=0, status="underway", id=4)
    assert "INACTIVE status message always says" in explain(odd, next_goal()).inconsistency
    assert "none of INACTIVE" in explain(DynamicEventStatus(dynamic_state=7), next_goal()).inconsistency


def test_json_form() -> None:
    data = explain(RUNNING, next_goal(dynamic_event_seq=2)).to_dict()
    assert data["verdict"] == "rejected" and data["reason"] == "seq_mismatch" and data["rule"] == "R4.2"
    assert data["values"] == {"expected_seq": 3, "received_seq": 2}
    assert data["then"] == [
        {
            "reason": "busy",
            "rule": "R4.6",
            "text": "event 8 is running: only a CANCEL with its id is accepted",
        }
    ]
    assert Goal.from_dict(data["instead"]) == Goal(dynamic_event_seq=3, event_type=2, id=8)
    assert json.loads(json.dumps(data)) == data


def test_the_command_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    status, goal = RUNNING.to_json(), next_goal().to_json()
    assert cli.main(["explain", "--status", status, "--goal", goal]) == 1
    assert "busy (R4.6)" in capsys.readouterr().out
    cancel = Goal(dynamic_event_seq=3, event_type=2, id=8).to_json()
    assert cli.main(["explain", "--json", "--status", status, "--goal", cancel]) == 0
    assert json.loads(capsys.readouterr().out)["verdict"] == "accepted"
    assert cli.main(["explain", "--status", status, "--goal", '{"event_type": 4294967296}']) == 2
    error = capsys.readouterr().err
    assert (
        error.startswith("dynevent explain: --goal: Goal.event_type: out of range")
        and "Traceback" not in error
    )


@given(messages(DynamicEventStatus), messages(Goal), st.sampled_from(["standard", "rmf_ros2"]))
def test_explain_never_raises_and_its_advice_is_accepted(
    status: DynamicEventStatus, goal: Goal, compatibility: str
) -> None:
    explanation = explain(status, goal, compatibility=compatibility)
    format_explanation(explanation)
    json.dumps(explanation.to_dict())
    if explanation.instead is not None and not explanation.inconsistency:
        state = state_from_status(status)
        strict = machine.ServerConfig(categories=dict.fromkeys([goal.category], machine.any_description))
        assert isinstance(machine.accept(state, explanation.instead, strict), outs.Accepted)
    assert explanation.accepted == (
        isinstance(explanation.decision, outs.Accepted) and not explanation.aborted_at_start
    )
    if status.dynamic_state == DynamicState.INACTIVE and not explanation.inconsistency:
        assert not explanation.accepted


@pytest.mark.spec("R4.7")
def test_a_json_quoted_category_is_recognised_and_unquoted() -> None:
    """What a client's --file sends by mistake: the category written as a JSON string."""
    explanation = explain(WAITING, next_goal(category='"go_to_place"'), categories=("go_to_place", "patrol"))
    assert isinstance(explanation.decision, outs.Rejected)
    assert explanation.decision.reason is RejectReason.UNSUPPORTED_CATEGORY
    assert "JSON-quoted" in explanation.advice
    assert explanation.instead is not None and explanation.instead.category == "go_to_place"
    unknown = explain(WAITING, next_goal(category='"fly"'), categories=("go_to_place",))
    assert unknown.instead is None and "JSON-quoted" not in unknown.advice


@pytest.mark.parametrize("state", [DynamicState.WAITING, DynamicState.RUNNING])
def test_the_highest_id_never_suggests_an_id_past_the_wire(state: DynamicState) -> None:
    """A status id of 2**64 - 1 once made explain suggest 2**64 (and raise building that goal)."""
    top = 2**64 - 1
    status = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=state, status="standby", id=top)
    goal = Goal(
        dynamic_event_seq=3, event_type=EventType.NEXT, category="go_to_place", description='"a"', id=5
    )
    explanation = explain(status, goal)
    text = format_explanation(explanation)
    assert str(2**64) not in text
    if explanation.instead is not None:
        assert 0 <= explanation.instead.id <= top
