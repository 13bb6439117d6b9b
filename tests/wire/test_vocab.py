"""Vocabularies: the enums and their wire values (foundation issue)."""

from __future__ import annotations

import json
import re
from pathlib import Path

from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, Status, Tier, Violation

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


SPEC = (Path(__file__).resolve().parents[2] / "docs" / "spec.md").read_text(encoding="utf-8")
TRACE_FORMAT = (Path(__file__).resolve().parents[2] / "docs" / "trace-format.md").read_text(encoding="utf-8")


def test_every_violation_names_a_rule_of_the_spec() -> None:
    rules = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC))
    assert {violation.rule for violation in Violation} <= rules
    assert len({(violation.code, violation.rule) for violation in Violation}) == len(Violation)


def test_the_finding_codes_documented_for_check_carry_the_vocabulary_rules() -> None:
    """docs/trace-format.md's table of finding codes agrees with the vocabulary it documents."""
    rows = re.findall(r"^\| (`[a-z_<>]+`(?:, `[a-z_<>]+`)*) \| ([^|]+) \|", TRACE_FORMAT, re.MULTILINE)
    documented: dict[str, str] = {}
    for codes, rules in rows:
        for code in re.findall(r"`([a-z_<>]+)`", codes):
            documented[code] = rules
    checked = 0
    for violation in Violation:
        if violation.code in documented:
            assert violation.rule in documented[violation.code], violation
            checked += 1
    assert checked >= 15  # the table is read
