"""§6. NEXT: the tests of the rules of docs/spec.md §6.

The section's conformance vectors are src/dynevent/conformance/vectors/06-next.json.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import attrs
import pytest

from dynevent import client
from dynevent.conformance.explain import explain
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    RunningGoal,
    ServerConfig,
    any_description,
)
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, RejectReason
from support.scenario import (
    ADAPTER,
    ANY_TEXT,
    CONFIG,
    PARSE_FAILURE,
    RUNNING,
    T0,
    WAITING,
    aborted,
    entry,
    execute,
    feedback,
    next_goal,
    s,
    start_child,
    status,
    stubborn,
    u,
    waiting,
)


def _clamp_log(seq: int, now: int = T0) -> outs.Log:
    return outs.Log(entry=entry(seq, "warning", now, ANY_TEXT))


def _rejecting(*errors: str) -> ServerConfig:
    def validator(category: str, description: Any) -> Sequence[str]:
        return errors

    return ServerConfig(categories={"go_to_place": validator})


# --------------------------------------------------------------------------- R6.1


@pytest.mark.spec("R6.1")
def test_description_is_checked_again_at_start() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = _rejecting("the map changed")
    assert run.start(u(1)) == (
        execute(u(1)),
        aborted(u(1), "Description parsing failure\n -- the map changed"),
    )
    assert run.state == attrs.evolve(run.before, queued=())
    assert run.state.last_id == 1


@pytest.mark.spec("R6.1")
def test_description_recheck_one_line_per_error() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = _rejecting("first", "second")
    assert run.start(u(1)) == (
        execute(u(1)),
        aborted(u(1), "Description parsing failure\n -- first\n -- second"),
    )


@pytest.mark.spec("R6.1", "R4.8")
def test_description_length_is_checked_again_at_start() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = attrs.evolve(CONFIG, max_description_length=3)
    outputs = run.start(u(1))
    assert outputs == (execute(u(1)), aborted(u(1), ANY_TEXT))
    failure = outputs[1].result.execution_failure
    assert failure.startswith(PARSE_FAILURE + "\n -- ")
    assert failure.count("\n -- ") == 1
    assert run.phase is WAITING


@pytest.mark.spec("R6.1")
def test_a_next_whose_category_is_no_longer_configured_is_answered() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = ServerConfig(categories={"perform_action": any_description})
    outputs = run.start(u(1))  # the machine never raises (R19.7)
    assert outputs == (execute(u(1)), aborted(u(1), ANY_TEXT))
    assert run.phase is WAITING


@pytest.mark.spec("R6.1")
def test_a_category_dropped_before_the_start_aborts_with_one_error_line() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = ServerConfig(categories={"perform_action": any_description, "dock": any_description})
    assert run.start(u(1)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        aborted(
            u(1),
            f"{PARSE_FAILURE}\n -- category 'go_to_place' is not supported; supported: dock, perform_action",
        ),
    )


def _counting() -> tuple[ServerConfig, list[str]]:
    calls: list[str] = []

    def validator(category: str, description: Any) -> Sequence[str]:
        calls.append(description)
        return ()

    return ServerConfig(categories={"go_to_place": validator}), calls


@pytest.mark.spec("R6.1")
def test_under_the_configuration_that_accepted_it_the_check_is_kept() -> None:
    config, calls = _counting()
    run = waiting(config=config)
    run.request(u(1), next_goal(1, 5))
    assert calls == ["lobby"]
    outputs = run.start(u(1))
    assert calls == ["lobby"]  # not checked again
    started = next(output for output in outputs if isinstance(output, outs.StartChild))
    assert started.parsed == "lobby"


@pytest.mark.spec("R6.1")
def test_under_an_equal_but_other_configuration_the_check_runs_again() -> None:
    config, calls = _counting()
    run = waiting(config=config)
    run.request(u(1), next_goal(1, 5))
    run.config = attrs.evolve(config)
    run.start(u(1))
    assert calls == ["lobby", "lobby"]


@pytest.mark.spec("R6.1")
def test_a_kept_check_of_another_shape_is_checked_again() -> None:
    config, calls = _counting()
    run = waiting(config=config)
    run.request(u(1), next_goal(1, 5))
    queued = attrs.evolve(run.state.queued[0], checked=())  # a state built by hand
    run.state = attrs.evolve(run.state, queued=(queued,))
    run.start(u(1))  # the machine never raises (R19.7)
    assert calls == ["lobby", "lobby"]
    assert run.phase is RUNNING


@pytest.mark.spec("R6.1")
def test_a_restored_queued_goal_is_checked_again() -> None:
    config, calls = _counting()
    run = waiting(config=config)
    run.request(u(1), next_goal(1, 5))
    run.state = snapshot.loads(snapshot.dumps(run.state))
    assert run.state.queued[0].checked is None
    run.start(u(1))
    assert calls == ["lobby", "lobby"]
    assert run.phase is RUNNING


# --------------------------------------------------------------------------- R6.2


@pytest.mark.spec("R6.2")
def test_the_goal_names_its_child() -> None:
    run = waiting(event_id=3)
    run.submit(u(1), next_goal(1, 2**64 - 1))
    assert run.state.running is not None
    assert run.state.running.child_id == 2**64 - 1
    assert run.state.last_id == 2**64 - 1


@pytest.mark.spec("R6.2")
def test_the_adapter_numbers_children_and_wraps_at_2_64() -> None:
    run = waiting(event_id=2**64 - 1, config=ADAPTER)
    assert run.submit(u(1), next_goal(1, 77)) == (
        execute(u(1)),
        start_child(0),
        feedback(u(1), "underway", 0),
        status(1, RUNNING, "underway", 0),
    )
    assert run.state.last_id == 0
    run.child_end("completed")
    run.submit(u(2), next_goal(1, 77))
    assert run.state.running is not None
    assert run.state.running.child_id == 1


@pytest.mark.spec("R6.2", "R17.3")
@pytest.mark.parametrize(
    ("last_id", "child_id"),
    [(200, 201), (2**63, 2**63 + 1), (2**64 - 2, 2**64 - 1), (2**64 - 1, 0)],
)
def test_adapter_ids_count_modulo_2_64(last_id: int, child_id: int) -> None:
    run = waiting(event_id=last_id, config=ADAPTER)
    outputs = run.submit(u(1), next_goal(1, 0))
    assert start_child(child_id) in outputs
    assert run.state.last_id == child_id
    assert run.state.running is not None
    assert run.state.running.child_id == child_id


# --------------------------------------------------------------------------- R6.3


@pytest.mark.spec("R6.3", "R14.2")
def test_interrupted_start_is_deferred() -> None:
    run = waiting()
    run.interrupt()
    request = next_goal(1, 5)
    assert run.submit(u(1), request) == (
        execute(u(1)),
        feedback(u(1), "queued", 5),
        status(1, RUNNING, "queued", 5),
    )
    assert run.state.running == RunningGoal(
        goal_uuid=u(1), goal=request, child_id=5, child_status="queued", started=False
    )
    assert (run.state.status, run.state.last_id) == ("queued", 5)


@pytest.mark.spec("R6.3", "R12.2", "R7.3")
def test_deferred_start_carries_the_clamp_notice() -> None:
    run = waiting().evolve(log_seq=41)
    run.interrupt()
    assert run.submit(u(1), next_goal(1, 5, stubborn=0.5)) == (
        execute(u(1)),
        outs.StubbornClamped(requested=0.5, applied=2.0),
        _clamp_log(41),
        feedback(u(1), "queued", 5, entry(41, "warning", T0, ANY_TEXT)),
        status(1, RUNNING, "queued", 5),
    )
    assert run.state.log_seq == 42


@pytest.mark.spec("R6.3", "R12.5")
def test_deferred_start_keeps_stubbornness_until_the_child_starts() -> None:
    run = stubborn(3.0, child_id=5)
    run.interrupt()
    assert run.submit(u(2), next_goal(1, 6)) == (
        execute(u(2)),
        feedback(u(2), "queued", 6),
        status(1, RUNNING, "queued", 6),
    )
    assert run.state.stubborn is not None


# --------------------------------------------------------------------------- R6.4


@pytest.mark.spec("R6.4")
def test_next_starts_the_child() -> None:
    run = waiting(event_id=1).at(s(150))
    request = next_goal(1, 5, category="perform_action", description='{"action": "clean", "zones": [1, 2]}')
    assert run.submit(u(1), request) == (
        execute(u(1)),
        outs.StartChild(
            category="perform_action",
            description='{"action": "clean", "zones": [1, 2]}',
            id=5,
            parsed={"action": "clean", "zones": [1, 2]},
        ),
        feedback(u(1), "underway", 5),
        status(1, RUNNING, "underway", 5, s(150)),
    )
    assert run.state.running == RunningGoal(
        goal_uuid=u(1), goal=request, child_id=5, child_status="underway", started=True
    )
    assert run.state.status == "underway"


@pytest.mark.spec("R6.4", "R12.2")
@pytest.mark.parametrize("period", [1e-45, 0.5, 1.5, 1.99])
def test_clamp_notice_at_start(period: float) -> None:
    run = waiting()
    request = next_goal(1, 5, stubborn=period)
    requested = request.stubborn_period  # as float32 carries it
    assert run.submit(u(1), request) == (
        execute(u(1)),
        outs.StubbornClamped(requested=requested, applied=2.0),
        _clamp_log(0),
        start_child(5),
        feedback(u(1), "underway", 5, entry(0, "warning", T0, ANY_TEXT)),
        status(1, RUNNING, "underway", 5),
    )


@pytest.mark.spec("R6.4", "R12.2")
@pytest.mark.parametrize("period", [-3.0, 0.0, 2.0, 30.0])
def test_no_clamp_notice_at_or_above_the_minimum_or_without_stubbornness(period: float) -> None:
    run = waiting()
    assert run.submit(u(1), next_goal(1, 5, stubborn=period)) == (
        execute(u(1)),
        start_child(5),
        feedback(u(1), "underway", 5),
        status(1, RUNNING, "underway", 5),
    )
    assert run.state.log_seq == 0


@pytest.mark.spec("R6.4", "R12.2")
def test_clamp_uses_the_configured_minimum() -> None:
    run = waiting(config=attrs.evolve(CONFIG, stubborn_minimum=5.0))
    outputs = run.submit(u(1), next_goal(1, 5, stubborn=3.0))
    assert outputs[1] == outs.StubbornClamped(requested=3.0, applied=5.0)


@pytest.mark.spec("R6.4", "R12.5")
def test_next_start_ends_stubbornness() -> None:
    run = stubborn(3.0, child_id=5)
    assert run.submit(u(2), next_goal(1, 6)) == (
        execute(u(2)),
        outs.StubbornEnd(),
        start_child(6),
        feedback(u(2), "underway", 6),
        status(1, RUNNING, "underway", 6),
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R6.4", "R12.2", "R12.5")
def test_output_order_with_clamp_and_stubborn_end() -> None:
    run = stubborn(3.0, child_id=5)
    log_seq = run.state.log_seq
    assert run.submit(u(2), next_goal(1, 6, stubborn=1.0)) == (
        execute(u(2)),
        outs.StubbornClamped(requested=1.0, applied=2.0),
        _clamp_log(log_seq),
        outs.StubbornEnd(),
        start_child(6),
        feedback(u(2), "underway", 6, entry(log_seq, "warning", T0, ANY_TEXT)),
        status(1, RUNNING, "underway", 6),
    )


# --------------------------------------------------------------------------- the id above the highest, once


@pytest.mark.spec("R4.12", "R6.2")
def test_the_fresh_id_is_one_function_and_none_is_left_at_the_top() -> None:
    """One rule for the id above a run's highest, asked by every side at 2**64 - 1: the machine
    refuses id 0 (goal policy) and wraps its own counter (adapter policy), the client machine sends
    no id it would have to invent, and explain says none is left."""
    top = 2**64 - 1
    assert machine.fresh_id(5) == 6 and machine.fresh_id(top - 1) == top and machine.fresh_id(top) is None
    goal_zero = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go", description="{}", id=0)
    assert machine.next_child_id(goal_zero, top, machine.ServerConfig(id_policy="adapter")) == 0
    config = machine.ServerConfig(categories={"go": machine.any_description})
    state = machine.step(
        machine.State.new("f", "r"), ins.Begin(description="{}", event_id=top, now=1), config
    ).state
    refused = machine.accept(state, goal_zero, config)
    assert isinstance(refused, outs.Rejected) and refused.reason is RejectReason.STALE_ID
    at_top = DynamicEventStatus(
        dynamic_event_seq=1, dynamic_state=DynamicState.WAITING, status="standby", id=top
    )
    held = client.step(
        client.ClientState.new("0" * 16, categories=["go"]), client.StatusReceived(message=at_top)
    )
    asked = client.request_next(held.state, "go", "{}", now=0)
    assert not any(isinstance(output, client.SendGoal) for output in asked.outputs)  # refused locally
    told = explain(at_top, attrs.evolve(goal_zero, id=top))
    assert not told.accepted and told.instead is None and "no id is left above" in told.advice
