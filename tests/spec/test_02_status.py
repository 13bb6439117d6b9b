"""§2. Phase and status: the tests of the rules of docs/spec.md §2.

The section's conformance vectors are src/dynevent/conformance/vectors/02-status.json.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    allowed_targets,
    status_message,
)
from dynevent.tools.diagram import render
from dynevent.wire.messages import DynamicEventStatus, Time
from dynevent.wire.vocab import DynamicState, RejectReason
from support.scenario import (
    INACTIVE,
    RUNNING,
    SUCCEEDED,
    WAITING,
    Run,
    answer,
    cancel_goal,
    deferred,
    feedback,
    finished_goal,
    next_goal,
    rejected,
    running,
    s,
    status,
    u,
    waiting,
)

SPEC = (Path(__file__).resolve().parents[2] / "docs" / "spec.md").read_text(encoding="utf-8")


def _all_kinds() -> list[str]:
    return sorted(machine.HANDLERS)


_EXPECTED_TARGETS: dict[tuple[DynamicState, str], set[DynamicState]] = {
    (DynamicState.INACTIVE, "begin"): {DynamicState.WAITING},
    (DynamicState.WAITING, "goal_started"): {DynamicState.RUNNING, DynamicState.INACTIVE},
    (DynamicState.WAITING, "goal_submitted"): {DynamicState.RUNNING, DynamicState.INACTIVE},
    (DynamicState.WAITING, "task_cancel"): {DynamicState.INACTIVE},
    (DynamicState.WAITING, "task_kill"): {DynamicState.INACTIVE},
    (DynamicState.WAITING, "shutdown"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "child_finished"): {DynamicState.WAITING, DynamicState.INACTIVE},
    (DynamicState.RUNNING, "goal_started"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "goal_submitted"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "cancel_requested"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "task_cancel"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "task_kill"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "shutdown"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "restart"): {DynamicState.WAITING, DynamicState.INACTIVE},
}


# --------------------------------------------------------------------------- the transition table


def test_every_edge_names_a_real_input_and_a_rule() -> None:
    rules = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC))
    for edge in machine.TRANSITIONS:
        assert edge.input in machine.HANDLERS, edge
        cited = re.findall(r"R\d+\.\d+", edge.rule)
        assert cited, edge
        assert set(cited) <= rules, edge
    assert len(machine.TRANSITIONS) == 18


def test_spec_diagram_is_the_transition_table() -> None:
    # Appendix A of docs/spec.md is generated from TRANSITIONS: inputs, guards and rules
    block = SPEC.split("<!-- diagram:start -->\n", 1)[1].split("<!-- diagram:end -->", 1)[0]
    assert block == f"```mermaid\n{render('mermaid')}```\n"
    for edge in machine.TRANSITIONS:
        label = edge.input if not edge.guard else f"{edge.input} [{edge.guard}]"
        assert f"    {edge.source.name} --> {edge.target.name}: {label} ({edge.rule})\n" in block


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


@pytest.mark.spec("R2.1")
@pytest.mark.parametrize("source", list(DynamicState), ids=lambda phase: phase.name)
def test_allowed_targets_per_phase_and_input(source: DynamicState) -> None:
    for kind in _all_kinds():
        expected = {source} | _EXPECTED_TARGETS.get((source, kind), set())
        assert allowed_targets(source, kind) == frozenset(expected), (source.name, kind)


@pytest.mark.spec("R2.1", "R11.1")
def test_a_finished_start_is_a_declared_edge() -> None:
    run = waiting()
    run.submit(u(1), finished_goal(1))
    assert run.phase in allowed_targets(DynamicState.WAITING, "goal_started")
    assert run.phase is DynamicState.INACTIVE


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
