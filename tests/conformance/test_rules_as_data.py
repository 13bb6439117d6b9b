"""Rules as data: every output, and every refusal, names the docs/spec.md rule that produced it.

The rule is an annotation: it takes no part in equality and is not encoded, so
the conformance vectors are unchanged by it.  These tests run the machine over
every conformance vector and check that each output's rule is a rule of the
spec, that a refusal's rule is the row of the spec's R4 table whose reason it
gives, and that a vector's outputs are attributed to rules it was written for.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from dynevent.conformance import vectors
from dynevent.conformance.records import config_from_json, input_from_json, output_to_json
from dynevent.conformance.vectors.driver import state_from_json
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.wire.messages import Goal, Result
from dynevent.wire.vocab import Failure, GoalStatus, RejectReason

ROOT = Path(__file__).resolve().parents[2]
SPEC = (ROOT / "docs" / "spec.md").read_text(encoding="utf-8")
RULES = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC))
#: Rules the spec marks "(bindings)": what a binding does around the machine, which no output names.
BINDING_RULES = set(re.findall(r"\*\*(R\d+\.\d+)\*\* \(bindings\)", SPEC))
#: The R4 table of the spec: rule -> the reason code its row gives.
REFUSALS = dict(re.findall(r"^\| \*\*(R4\.\d+)\*\* \|[^|]*\| `([a-z_]+)` \|", SPEC, re.MULTILINE))
SERVER_VECTORS = vectors.load_vectors()


def _run(vector: vectors.Vector) -> list[tuple[object, outs.Output]]:
    config = config_from_json(vector.config, "$.config")
    state = state_from_json(vector.fleet, vector.robot, vector.state)
    emitted: list[tuple[object, outs.Output]] = []
    for step in vector.steps:
        if not isinstance(step.input, dict) or step.input.get("type") not in machine_kinds():
            return emitted
        transition = machine.step(state, input_from_json(step.input), config)
        emitted.extend((step.input.get("type"), output) for output in transition.outputs)
        state = transition.state
    return emitted


def machine_kinds() -> set[str]:
    from dynevent.server import inputs

    return set(inputs.INPUT_TYPES)


def test_the_spec_table_of_refusals_is_read() -> None:
    assert len(REFUSALS) == 14
    assert REFUSALS["R4.8"] == REFUSALS["R4.10"] == RejectReason.DESCRIPTION_INVALID.value


@pytest.mark.parametrize("vector", SERVER_VECTORS, ids=lambda vector: vector.name)
def test_every_output_of_every_vector_names_a_spec_rule(vector: vectors.Vector) -> None:
    emitted = _run(vector)
    for kind, output in emitted:
        assert output.rule in RULES, f"{kind}: {output!r} names no rule of docs/spec.md"
        if isinstance(output, outs.GoalRejected):
            rejection = output.rejection
            assert REFUSALS[rejection.rule] == rejection.reason.value, rejection


def _attributed(vector: vectors.Vector) -> set[str]:
    rules: set[str] = set()
    for _, output in _run(vector):
        rules.add(output.rule)
        if isinstance(output, outs.GoalRejected):
            rules.add(output.rejection.rule)
    return rules


#: Rules of sections 3 to 18 and 21 that shape state or the values inside outputs, and decide no output
#: (R4.18 says what a field category's validator finds, R4.19 how much is listed; R4.10 refuses with it).
STATE_RULES = {
    "R3.1", "R4.17", "R4.18", "R4.19", "R6.2", "R7.3", "R7.4", "R8.1", "R8.4", "R12.3",
    "R13.4", "R13.5", "R13.6", "R14.3", "R15.2", "R17.1", "R17.3", "R17.6", "R17.8",
}  # fmt: skip


def _section(rule: str) -> int:
    return int(rule[1:].split(".", maxsplit=1)[0])


def test_every_rule_that_decides_an_output_is_attributed_by_some_vector() -> None:
    attributed = set().union(*(_attributed(vector) for vector in SERVER_VECTORS))
    deciding = {rule for rule in RULES if 3 <= _section(rule) <= 18 or _section(rule) == 21}
    deciding -= STATE_RULES | BINDING_RULES
    assert {"R21.4", "R21.5", "R21.6"} == BINDING_RULES
    assert attributed == deciding | {"R2.3"}


@pytest.mark.spec("R19.6")
def test_the_rule_is_an_annotation_not_part_of_the_value() -> None:
    one = outs.AnswerGoal(goal_uuid="1" * 32, status=GoalStatus.ABORTED, result=Result(), rule="R5.2")
    other = outs.AnswerGoal(goal_uuid="1" * 32, status=GoalStatus.ABORTED, result=Result(), rule="R15.1")
    assert one == other and hash(one) == hash(other)
    assert "rule" not in output_to_json(one)
    assert one.rule == "R5.2" and other.rule == "R15.1"


def _running(config: machine.ServerConfig) -> machine.State:
    state = machine.State.new("fleet", "robot")
    from dynevent.server import inputs as ins

    state = machine.step(state, ins.Begin(description="{}", event_id=1, now=1), config).state
    goal = Goal(dynamic_event_seq=1, event_type=1, category="go", description="{}", id=2)
    state = machine.step(state, ins.GoalRequested(goal_uuid="a" * 32, goal=goal, now=2), config).state
    return machine.step(state, ins.GoalStarted(goal_uuid="a" * 32, now=3), config).state


@pytest.mark.spec("R8.2", "R8.3", "R9.3")
def test_the_running_goal_and_the_waiting_cancels_are_answered_under_their_own_rules() -> None:
    from dynevent.server import inputs as ins

    config = machine.ServerConfig(categories={"go": machine.any_description})
    state = _running(config)
    cancel = Goal(dynamic_event_seq=1, event_type=2, id=2)
    state = machine.step(state, ins.GoalSubmitted(goal_uuid="b" * 32, goal=cancel, now=4), config).state
    ended = machine.step(state, ins.ChildFinished(status="canceled", now=5), config)
    answers = {out.goal_uuid: out.rule for out in ended.outputs if isinstance(out, outs.AnswerGoal)}
    assert answers == {"a" * 32: "R8.2", "b" * 32: "R8.3"}


@pytest.mark.spec("R5.2", "R9.1", "R9.2")
def test_an_execution_failure_is_read_back_with_its_reason() -> None:
    assert Failure.of("race condition\n -- its seq 3 is no longer the run's seq 4") is Failure.RACE
    assert Failure.of("an idle dynamic event cannot be cancelled").reason is RejectReason.CANCEL_IDLE
    assert Failure.CANCEL_ID.reason is RejectReason.CANCEL_ID_MISMATCH
    assert Failure.NOT_RUNNING.reason is None
    assert Failure.of("") is None and Failure.of("race condition, almost") is None
    assert machine.EXECUTION_FAILURES["idle_cancel"] == Failure.IDLE_CANCEL.value


@pytest.mark.spec("R5.2")
def test_race_lost_says_how() -> None:
    config = machine.ServerConfig(categories={"go": machine.any_description})
    state = _running(config)
    stale = Goal(dynamic_event_seq=0, event_type=3)
    assert machine.race_lost(state, stale, config) == "its seq 0 is no longer the run's seq 1"
    busy = Goal(dynamic_event_seq=1, event_type=3)
    assert machine.race_lost(state, busy, config) == "event 2 holds the running slot"
    assert machine.race_lost(state, Goal(dynamic_event_seq=1, event_type=2, id=2), config) == ""
    # the same as a value, for a reader that sorts races by why they were lost (never by the words)
    assert machine.race_loss(state, stale, config) is machine.RaceLoss.SEQ
    assert machine.race_loss(state, busy, config) is machine.RaceLoss.SLOT
    assert machine.race_loss(state, Goal(dynamic_event_seq=1, event_type=2, id=2), config) is None


@pytest.mark.parametrize("name", sorted(name for name in machine.__all__ if name.endswith("_RULE")))
def test_every_rule_the_machine_names_for_its_readers_is_a_spec_rule(name: str) -> None:
    """The constants check and the client read (the rule of a child's start, end, result...) are rules."""
    assert getattr(machine, name) in RULES
