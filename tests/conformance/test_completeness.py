"""Completeness, measured: every check of the machine, switched off one at a time by the test kit
(:mod:`dynevent.testing.switched_off`), must be caught by the vectors and by the probe.

The checks are enrolled from the machine itself (its request checks' table, and every rule its
source names as a value), so that a check added to the machine is measured without a word written
here."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from dynevent.conformance import vectors
from dynevent.conformance.probe.cases import LIVE_CANNOT_SHOW, Verdict
from dynevent.conformance.records import config_from_json, input_from_json
from dynevent.conformance.vectors.driver import state_from_json
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.testing import switched_off as kit
from dynevent.wire.messages import Goal
from support.completeness import (
    DDS_ADDED,
    DDS_CANNOT_SHOW,
    LINKS,
    OVER_DDS,
    dds_cases,
    measure,
    probe_published_at_start,
    table,
)


def _rules_the_vectors_meet() -> set[str]:
    """The rule of every output and refusal the machine gives over every vector."""
    met: set[str] = set()
    for vector in vectors.load_vectors():
        config = config_from_json(vector.config)
        state = state_from_json(vector.fleet, vector.robot, vector.state)
        for step in vector.steps:
            state, outputs = machine.step(state, input_from_json(step.input), config)
            for output in outputs:
                met.add(output.rule)
                if isinstance(output, outs.GoalRejected):
                    met.add(output.rejection.rule)
    return met


def test_every_check_of_the_machine_is_switched_off_by_the_kit() -> None:
    assert kit.check_rules() == tuple(check.rule for check in machine.REQUEST_CHECKS)
    enrolled = [item.rule for item in kit.switches()]
    assert enrolled == [*kit.check_rules(), *kit.step_rules()]
    assert len(set(enrolled)) == len(enrolled)
    # every rule an output of the machine names is enrolled (what reading the source must not miss)
    assert _rules_the_vectors_meet() - set(enrolled) == set()
    assert {"R2.3", "R5.2", "R8.4", "R18.4"} <= set(kit.step_rules())  # an output's, a decision's, an edge's


def test_a_check_added_to_the_machines_table_is_enrolled(monkeypatch: pytest.MonkeyPatch) -> None:
    added = machine.RequestCheck("R4.99", machine.REQUEST_CHECKS[0].reason, frozenset({1}), lambda *_: None)
    monkeypatch.setattr(machine, "REQUEST_CHECKS", (*machine.REQUEST_CHECKS, added))
    assert kit.check_rules()[-1] == "R4.99"
    assert "R4.99" in [item.rule for item in kit.switches()]


def test_a_switch_holds_only_while_the_server_steps() -> None:
    names = ("step", "REQUEST_CHECKS", "_STANDARD_WALKS", "_RMF_ROS2_WALKS", "_DEFERRED", "_BY_CLASS",
             "_DESCRIPTION_CHECKS", "_ACCEPTANCES", "race_lost", "next_seq")  # fmt: skip
    before = {name: getattr(machine, name) for name in names}
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    state = machine.State.new("fleet", "robot")
    stale = Goal(dynamic_event_seq=7, event_type=3)
    begin = ins.Begin(description="{}", event_id=1, now=0)
    with kit.switched_off("R4.2"):
        assert machine.accept(state, stale, config).rule == "R4.3"  # the next check refuses it
    with kit.switched_off("R2.3"):
        assert [output.KIND for output in machine.step(state, begin, config).outputs] == ["publish_begin"]
    assert {name: getattr(machine, name) for name in names} == before
    assert machine.accept(state, stale, config).rule == "R4.2"
    assert [output.KIND for output in machine.step(state, begin, config).outputs][-1] == "publish_status"


def test_the_unwarned_clamp_holds_for_a_goal_a_binding_submits_as_for_one_started() -> None:
    """R12.2 switched off: no warning in the start feedback, whether the goal starts in its own step or
    in the step that submits it (request and start in one, as the ROS binding steps it)."""
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description}, stubborn_minimum=2.0)
    state = machine.step(machine.State.new("fleet", "robot"), ins.Begin(description="{}", event_id=1, now=0),
                         config).state  # fmt: skip
    goal = Goal(dynamic_event_seq=state.seq, event_type=1, category="go_to_place", description="{}", id=2,
                stubborn_period=0.01)  # fmt: skip
    submitted = ins.GoalSubmitted(goal_uuid="a" * 32, goal=goal, now=1)

    def warned() -> list[str]:
        outputs = machine.step(state, submitted, config).outputs
        return [
            entry.text
            for out in outputs
            if isinstance(out, outs.PublishFeedback)
            for entry in out.feedback.logs
        ]

    assert len(warned()) == 1
    with kit.switched_off("R12.2"):
        assert warned() == []


def test_each_switch_says_what_the_server_does_instead() -> None:
    for item in kit.switches():
        assert item.how and item.kind in ("request check", "step"), item
        assert (item.rule in kit.DECISIONS) == (item.kind == "step" and "dropped" not in item.how), item


# ------------------------------------------------------------------ what catches each


def test_every_check_switched_off_is_caught_by_the_vectors_and_by_the_probe_on_each_link_or_said_why() -> (
    None
):
    """The vectors catch every check switched off; the probe catches it on the in-process link and over
    the driver protocol, or the case list says why no live exchange shows it (and says so of no
    check it catches)."""
    measured = measure()
    assert [item.rule for item in measured] == [item.rule for item in kit.switches()]
    assert [item.rule for item in measured if item.vector is None] == []
    unexplained = [
        item.rule
        for item in measured
        if not all(item.probe[link][1] for link in LINKS) and item.rule not in LIVE_CANNOT_SHOW
    ]
    assert unexplained == [], "caught by no case on some link, and no reason in cases.LIVE_CANNOT_SHOW"
    stale = [item.rule for item in measured if item.rule in LIVE_CANNOT_SHOW and item.probe["in process"][1]]
    assert stale == [], "caught by the probe, yet cases.LIVE_CANNOT_SHOW says no live exchange shows it"
    assert set(LIVE_CANNOT_SHOW) <= {item.rule for item in measured}


def test_r8_4_switched_off_fails_the_case_of_its_rule_rather_than_leaving_cases_not_run() -> None:
    """A server that publishes no status at a child's end: the case of R8.4 fails, naming it."""
    (item,) = [item for item in measure() if item.rule == "R8.4"]
    assert item.probe["in process"] == ("standard", ("next.status_after_child",))


@pytest.mark.parametrize("link", LINKS)
def test_r2_3_switched_off_after_the_first_status_fails_the_case_of_its_rule(link: str) -> None:
    """A server that publishes its status when it starts (as dynevent's ROS binding does) and no change
    of it after, R2.3 switched off: the child's end it never publishes fails the case of R8.4 and R2.3,
    naming them, rather than leaving that case and the rest not run (exit 3)."""
    code, findings = probe_published_at_start("R2.3", link)
    verdicts = {finding.case.id: finding for finding in findings}
    assert verdicts["status.latched"].verdict is Verdict.PASS  # the first status came
    assert code == 1
    after = verdicts["next.status_after_child"]
    assert after.verdict is Verdict.FAIL and {"R2.3", "R8.4"} <= set(after.case.rules)
    assert "the status still says WAITING" in after.seen and "R8.4" in after.expected


def test_the_record_of_the_probe_over_dds_holds_every_check_the_probe_catches_in_process() -> None:
    """tests/ros/test_ros_completeness.py holds OVER_DDS to what DDS shows; here it is held to the
    in-process measurement: a row per check caught in process, each caught by cases it runs (or the
    judge) or said why not, and every reason and added case for such a check only."""
    measured = {item.rule: item for item in measure() if item.probe["in process"][1]}
    assert list(OVER_DDS) == list(measured), "OVER_DDS: a row per check caught in process, in order"
    for rule, caught in OVER_DDS.items():
        assert (not caught) == (rule in DDS_CANNOT_SHOW), rule
        ran = dds_cases(measured[rule])
        assert caught == ("the judge",) or set(caught) <= set(ran), (rule, caught, ran)
    assert set(DDS_CANNOT_SHOW) | set(DDS_ADDED) <= set(OVER_DDS)
    assert all(cases and why for cases, why in DDS_ADDED.values())


DOC = Path(__file__).resolve().parents[2] / "docs" / "conformance.md"
BEGIN, END = "<!-- the table of completeness: begin -->", "<!-- the table of completeness: end -->"


def test_docs_conformance_prints_the_table_of_completeness() -> None:
    """docs/conformance.md's table is :func:`completeness.table`; ``DYNEVENT_UPDATE_COMPLETENESS=1``
    rewrites it."""
    text = DOC.read_text(encoding="utf-8")
    before, _, rest = text.partition(BEGIN + "\n")
    _, _, after = rest.partition(END)
    fresh = before + BEGIN + "\n" + table(LIVE_CANNOT_SHOW) + END + after
    if os.environ.get("DYNEVENT_UPDATE_COMPLETENESS") == "1":
        DOC.write_text(fresh, encoding="utf-8")
    how = "DYNEVENT_UPDATE_COMPLETENESS=1 pytest tests/conformance/test_completeness.py"
    assert BEGIN in text and END in text and text == fresh, f"docs/conformance.md's table is stale: {how}"
