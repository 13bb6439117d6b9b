"""§19. Invariants: the tests of the rules of docs/spec.md §19.

The section's conformance vectors are src/dynevent/conformance/vectors/19-invariants.json.

Properties of the machine over random input sequences, and over the deep runs the stateful kit of
dynevent.testing drives.  They look inside dynevent (states, snapshots, the transition table), which
a black-box kit cannot; the kit's own tests (it finds nothing in dynevent, it catches each of a handful
of deliberately broken servers) are tests/testing/test_stateful.py.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import attrs
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.stateful import run_state_machine_as_test

from dynevent.conformance.records import config_from_json, output_to_json
from dynevent.conformance.vectors.driver import Driver
from dynevent.errors import InvalidSnapshot
from dynevent.server import inputs as ins
from dynevent.server import machine, resync, snapshot
from dynevent.server import outputs as outs
from dynevent.server.fleet import Fleet
from dynevent.server.machine import ServerConfig, State, any_description
from dynevent.testing import (
    DEFAULT_CONFIG,
    DyneventServer,
    input_sequences,
    server_state_machine,
)
from dynevent.wire import _json
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import Compatibility, DynamicState, EventType, Status
from support.kit_runs import CONFIGS, RMF_ROS2_CONFIG, SEQUENCES, STEPS
from support.scenario import deferred, running, stubborn, waiting

CONFIG = config_from_json(dict(DEFAULT_CONFIG))


def _tampered(state: State, path: list[Any], value: Any) -> dict[str, Any]:
    data = snapshot.snapshot(state)
    node = data["state"]
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return json.loads(json.dumps(data))


CASES = [
    ("description NUL", lambda: waiting().state, ["description"], '{"detail": "a\x00b"}', "$.state"),
    ("description surrogate", lambda: waiting().state, ["description"], "\ud800", "$.state.description"),
    ("hold_since huge", lambda: stubborn().state, ["stubborn", "hold_since"], -(10**400), "$.state"),
    (
        "infinite period",
        lambda: running().state,
        ["running", "goal", "stubborn_period"],
        float("inf"),
        "$.state",
    ),
    ("shutdown while active", lambda: waiting().state, ["shutdown"], True, "$.state.shutdown"),
    (
        "stubborn while running",
        lambda: running().state,
        ["stubborn"],
        snapshot.snapshot(stubborn().state)["state"]["stubborn"],
        "$.state.stubborn",
    ),
    (
        "stubborn while inactive",
        lambda: attrs.evolve(stubborn().state, active=False),
        [],
        None,
        "$.state.stubborn",
    ),
    (
        "deferred without interruption",
        lambda: deferred().state,
        ["interrupted"],
        False,
        "$.state.running.started",
    ),
    ("last_id below the child", lambda: running(child_id=8).state, ["last_id"], 3, "$.state.last_id"),
    ("period below 1 ms", lambda: stubborn().state, ["stubborn", "period"], 1e-6, "$.state.stubborn.period"),
    ("over-long names", lambda: waiting().state, ["robot"], "r" * 250, "$.state"),
]


def _resyncs(state: State, uuid: str, number: int, status: str) -> dict[str, State]:
    """Every resync operation the machine offers an observer, applied to ``state``."""
    goal = Goal(dynamic_event_seq=state.seq, event_type=EventType.NEXT, id=number)
    displaced = [item.goal_uuid for item in state.queued][:1]
    return {
        "seq": resync.seq(state, number) if not state.active else state,
        "next_run": resync.next_run(state, number) if not state.active else state,
        "serving": resync.serving(state) if not state.active else state,
        "run_dropped": resync.run_dropped(state),
        "event_id": resync.event_id(state, number) if state.active else state,
        "queued": resync.queued(state, uuid, goal) if state.active else state,
        "dropped": resync.dropped(state, (*displaced, uuid)[0]),
        "child_started": resync.child_started(state, resumed=True),
        "start_dropped": resync.start_dropped(state) if state.running is not None else state,
        "running_goal": resync.running_goal(state, uuid),
        "child_id": resync.child_id(state, max(number, state.last_id)),
        "running": resync.running(state, uuid, goal, max(number, state.last_id), status, displaced)
        if state.active and not state.shutdown
        else state,
    }


SECOND = 1_000_000_000
UUIDS = [f"{index:032x}" for index in range(1, 5)]


# --------------------------------------------------------------------------- properties over input lists


def _run(config: ServerConfig, events: Sequence[ins.Input], state: State | None = None) -> list[Any]:
    """Step every input; return (state after, outputs) pairs."""
    state = state if state is not None else State.new("fleet", "robot")
    transitions = []
    for event in events:
        transition = machine.step(state, event, config)
        transitions.append(transition)
        state = transition.state
    return transitions


def _plain(transition: machine.Transition) -> tuple[str, str]:
    """A transition as text: NaN-safe, so equal transitions compare equal."""
    outputs = _json.dumps([output_to_json(output) for output in transition.outputs])
    return snapshot.dumps(transition.state), outputs


configs = pytest.mark.parametrize("mode", sorted(CONFIGS))


def _check_step(
    before: State, event: ins.Input, transition: machine.Transition, config: ServerConfig
) -> None:
    """What every single step must keep, seen from inside dynevent."""
    after = transition.state
    assert after.phase in machine.allowed_targets(before.phase, event.KIND), (  # R2.1, Appendix A
        f"{before.phase.name} --{event.KIND}--> {after.phase.name} is not in machine.TRANSITIONS"
    )
    published = [output for output in transition.outputs if isinstance(output, outs.PublishStatus)]
    running = before.running
    if (
        config.compatibility is Compatibility.RMF_ROS2
        and running is not None
        and running.started
        and isinstance(event, (ins.ChildProgress, ins.ChildFinished))
        and not (isinstance(event, ins.ChildFinished) and before.task_signal)
    ):  # R17.4, R17.5: what rmf_ros2's wire shows, published every time
        freed = isinstance(event, ins.ChildFinished) and before.cancels  # a CANCEL freed the slot (R17.4)
        wire = DynamicEventStatus(
            dynamic_event_seq=before.seq,
            dynamic_state=DynamicState.WAITING if freed else DynamicState.RUNNING,
            status=event.status,
            id=running.child_id,
            time=machine.status_message(after, event.now).time,
        )
        assert [output.message for output in published] == [wire]
        assert transition.outputs[-1] is published[0]
        published = []
    else:
        changed = machine.status_message(before, 0) != machine.status_message(after, 0)
        assert len(published) == int(changed), f"R2.3: {len(published)} status messages, changed: {changed}"
    for output in published:
        assert output.message == machine.status_message(after, event.now)  # R19.5
        assert transition.outputs[-1] is output  # R2.3
    if after.seq != before.seq:  # R19.3
        assert isinstance(event, ins.Begin)
        assert after.seq == (before.seq + 1) % 2**32
    if after.stubborn is not None:  # R19.4
        assert after.stubborn.period >= config.stubborn_minimum
    open_goals = [queued.goal_uuid for queued in after.queued] + list(after.cancels)
    if after.running is not None:
        open_goals.append(after.running.goal_uuid)
    assert len(open_goals) == len(set(open_goals))  # R19.2: one slot, each goal in one place


@pytest.mark.spec("R19.7", "R2.1", "R2.3", "R19.3", "R19.4", "R19.5")
@configs
@given(events=SEQUENCES)
def test_every_step_is_total_declared_and_keeps_the_invariants(mode: str, events: list[ins.Input]) -> None:
    config = CONFIGS[mode]
    state = State.new("fleet", "robot")
    for event in events:
        transition = machine.step(state, event, config)  # R19.7: never raises
        _check_step(state, event, transition, config)
        state = transition.state


@pytest.mark.spec("R19.6")
@configs
@given(events=SEQUENCES, data=st.data())
def test_same_inputs_same_transitions_and_a_restored_snapshot_continues_alike(
    mode: str, events: list[ins.Input], data: st.DataObject
) -> None:
    config = CONFIGS[mode]
    first = [_plain(transition) for transition in _run(config, events)]
    assert first == [_plain(transition) for transition in _run(config, events)]
    cut = data.draw(st.integers(0, len(events)), label="cut")
    head = _run(config, events[:cut])
    state = head[-1].state if head else State.new("fleet", "robot")
    restored = snapshot.loads(snapshot.dumps(state))  # through JSON text
    assert restored == state
    assert snapshot.dumps(restored) == snapshot.dumps(state)
    original = [_plain(transition) for transition in _run(config, events[cut:], state)]
    assert original == [_plain(transition) for transition in _run(config, events[cut:], restored)]
    assert original == first[cut:]


# --------------------------------------------------------------------------- deep runs, checked inside


class CheckedDyneventServer(DyneventServer):
    """dynevent's machine, checking at every step what only its internals show.

    Driven by the kit, whose rules reach deep states (children running,
    CANCELs waiting, stubbornness, deferred starts) that random input lists
    seldom reach.
    """

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        assert before is not None
        transition = machine.step(before, event, self.config)
        again = machine.step(before, event, self.config)
        assert _plain(again) == _plain(transition), "R19.6: the same state and input gave another transition"
        restored = snapshot.loads(snapshot.dumps(before))
        assert restored == before, "R19.6: the snapshot did not restore the state"
        continued = machine.step(restored, event, self.config)
        assert _plain(continued) == _plain(transition), "R19.6: the restored state continued differently"
        _check_step(before, event, transition, self.config)
        after = transition.state
        self.state = after
        return list(transition.outputs)


@pytest.mark.spec("R19.5", "R19.6", "R2.1", "R2.3")
@pytest.mark.parametrize("config", [DEFAULT_CONFIG, RMF_ROS2_CONFIG], ids=["standard", "rmf_ros2"])
def test_determinism_snapshots_transitions_and_status_on_the_kits_runs(config: dict[str, Any]) -> None:
    machine_class = server_state_machine(CheckedDyneventServer, config=config, name="CheckedKit")
    run_state_machine_as_test(machine_class, settings=settings(settings.default, stateful_step_count=STEPS))


# --------------------------------------------------------------------------- configuration changes


OTHER_CONFIGS = {
    "fewer_categories": ServerConfig(categories={"go_to_place": any_description}),
    "no_categories": ServerConfig(),
    "stricter": ServerConfig(
        categories={"perform_action": any_description}, stubborn_minimum=5.0, max_description_length=4
    ),
    "rmf_ros2": CONFIGS["rmf_ros2"],
}


@pytest.mark.spec("R19.7", "R6.1")
@given(events=SEQUENCES, other=st.sampled_from(sorted(OTHER_CONFIGS)), data=st.data())
def test_a_state_restored_under_another_configuration_never_makes_the_machine_raise(
    events: list[ins.Input], other: str, data: st.DataObject
) -> None:
    cut = data.draw(st.integers(0, len(events)), label="cut")
    head = _run(CONFIGS["standard"], events[:cut])
    state = head[-1].state if head else State.new("fleet", "robot")
    restored = snapshot.loads(snapshot.dumps(state))  # the adapter restarts with another configuration
    state = restored
    for event, transition in zip(
        events[cut:], _run(OTHER_CONFIGS[other], events[cut:], restored), strict=True
    ):
        assert transition.state.phase in machine.allowed_targets(state.phase, event.KIND)
        state = transition.state


def _next(seq: int, category: str, child: int) -> Goal:
    return Goal(
        dynamic_event_seq=seq, event_type=EventType.NEXT, category=category, description="{}", id=child
    )


@pytest.mark.spec("R19.7", "R6.1")
def test_a_goal_whose_category_left_the_configuration_is_aborted_at_start() -> None:
    # Found while writing the kit: this start raised KeyError before R6.1 re-checked R4.7.
    before = ServerConfig(categories={"go_to_place": any_description, "perform_action": any_description})
    after = ServerConfig(categories={"go_to_place": any_description})
    state = State.new("fleet", "robot")
    state = machine.step(state, ins.Begin(description="{}", event_id=1, now=SECOND), before).state
    request = ins.GoalRequested(goal_uuid=UUIDS[0], goal=_next(1, "perform_action", 2), now=SECOND)
    state = machine.step(state, request, before).state
    restored = snapshot.loads(snapshot.dumps(state))
    transition = machine.step(restored, ins.GoalStarted(goal_uuid=UUIDS[0], now=2 * SECOND), after)
    execute, answer = transition.outputs
    assert execute == outs.ExecuteGoal(goal_uuid=UUIDS[0])
    assert isinstance(answer, outs.AnswerGoal) and answer.status == "aborted"
    assert answer.result.execution_failure.startswith("Description parsing failure\n -- ")
    assert "perform_action" in answer.result.execution_failure
    assert transition.state.phase is DynamicState.WAITING


# --------------------------------------------------------------------------- R19.8


@pytest.mark.spec("R19.8")
@pytest.mark.parametrize(("label", "build", "path", "value", "where"), CASES, ids=[case[0] for case in CASES])
def test_restore_refuses_a_state_the_machine_cannot_reach(
    label: str, build: Any, path: list[Any], value: Any, where: str
) -> None:
    state = build()
    data = _tampered(state, path, value) if path else snapshot.snapshot(state)
    with pytest.raises(InvalidSnapshot) as caught:
        snapshot.restore(data)
    assert caught.value.path.startswith(where), str(caught.value)
    driver = Driver()  # the conformance driver's reset checks the same invariants
    answer = driver.handle(
        {"op": "reset", "fleet": state.fleet, "robot": state.robot, "config": {}, "state": data["state"]}
    )
    assert answer["ok"] is False, label


@pytest.mark.spec("R19.8")
def test_a_snapshot_holds_exactly_the_states_fields() -> None:
    data = snapshot.snapshot(waiting().state)
    del data["state"]["log_seq"]
    with pytest.raises(InvalidSnapshot, match=r"missing fields \['log_seq'\]"):
        snapshot.restore(data)


@pytest.mark.spec("R19.8")
def test_a_fleet_restore_refuses_a_robot_the_machine_cannot_reach() -> None:
    fleet = Fleet(config=CONFIG)
    fleet.add("tinyRobot", "r1")
    data = json.loads(fleet.dumps())
    data["robots"][0]["state"]["shutdown"] = True
    data["robots"][0]["state"]["active"] = True
    with pytest.raises(InvalidSnapshot):
        Fleet.restore(data, config=CONFIG)


@pytest.mark.spec("R19.8", "R19.6")
@given(events=input_sequences(tuple(DEFAULT_CONFIG["categories"]), max_size=40))
def test_every_state_the_machine_reaches_keeps_the_invariants(events: list[Any]) -> None:
    state = State.new("fleet", "robot")
    for event in events:
        state = machine.step(state, event, CONFIG).state
        assert snapshot.state_problems(state) == []


@pytest.mark.spec("R19.8")
@given(
    events=input_sequences(tuple(DEFAULT_CONFIG["categories"]), max_size=25),
    number=st.integers(0, 2**32 - 1),
    status=st.sampled_from([status.value for status in Status]),
)
def test_every_resync_an_observer_may_make_keeps_the_invariants(
    events: list[Any], number: int, status: str
) -> None:
    state = State.new("fleet", "robot")
    for event in events:
        state = machine.step(state, event, CONFIG).state
    for name, resynced in _resyncs(state, "0" * 31 + "f", number, status).items():
        assert snapshot.state_problems(resynced) == [], name
