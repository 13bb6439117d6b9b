"""Vocabularies: the enums and their wire values (foundation issue)."""

from __future__ import annotations

import json
from pathlib import Path

from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, Status, Tier

SHARED = Path(__file__).resolve().parents[2] / "shared" / "reference" / "schemas" / "task_state.json"

TASK_STATE_STATUSES = [
    "uninitialized", "blocked", "error", "failed", "queued", "standby",
    "underway", "delayed", "skipped", "canceled", "killed", "completed",
]  # fmt: skip


def test_event_type_values() -> None:
    assert {e.name: e.value for e in EventType} == {"UNINITIALIZED": 0, "NEXT": 1, "CANCEL": 2, "FINISHED": 3}


def test_dynamic_state_values() -> None:
    assert {e.name: e.value for e in DynamicState} == {"INACTIVE": 0, "WAITING": 1, "RUNNING": 2}


def test_tier_values() -> None:
    assert [t.value for t in Tier] == ["uninitialized", "info", "warning", "error"]
    assert str(Tier.INFO) == "info" and Tier("warning") is Tier.WARNING


def test_status_is_exactly_the_task_state_enum() -> None:
    assert [s.value for s in Status] == TASK_STATE_STATUSES
    if SHARED.exists():  # the upstream schema, when the reference material is beside the checkout
        schema = json.loads(SHARED.read_text())
        assert schema["$defs"]["status"]["enum"] == TASK_STATE_STATUSES


def test_goal_status_lifecycle() -> None:
    assert [g.value for g in GoalStatus] == [
        "accepted",
        "executing",
        "canceling",
        "succeeded",
        "canceled",
        "aborted",
    ]
    assert {g for g in GoalStatus if g.is_terminal} == {
        GoalStatus.SUCCEEDED,
        GoalStatus.CANCELED,
        GoalStatus.ABORTED,
    }
