"""§19. Invariants: the tests of the rules of docs/spec.md §19.

The section's conformance vectors are src/dynevent/conformance/vectors/19-invariants.json.

Properties of the machine over random input sequences, and the stateful kit of dynevent.testing.

The kit (:mod:`dynevent.testing.stateful`) is tested by use: it drives
dynevent's machine in both compatibility modes and through the conformance
driver protocol and finds nothing, and it catches each of a handful of
deliberately broken servers, several of which copy a defect of rmf_ros2.
The other properties look inside dynevent (states, snapshots, the transition
table), which a black-box kit cannot.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from typing import Any

import attrs
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import run_state_machine_as_test

from dynevent.conformance.records import config_from_json, output_to_json
from dynevent.conformance.vectors import InProcessImplementation
from dynevent.conformance.vectors.driver import Driver
from dynevent.errors import InvalidSnapshot
from dynevent.server import inputs as ins
from dynevent.server import machine, resync, snapshot
from dynevent.server import outputs as outs
from dynevent.server.fleet import Fleet
from dynevent.server.machine import QueuedGoal, ServerConfig, State, any_description
from dynevent.testing import (
    DEFAULT_CONFIG,
    DyneventServer,
    ImplementationServer,
    Observer,
    ProtocolViolation,
    ServerStateMachine,
    ServerUnderTest,
    input_sequences,
    server_state_machine,
)
from dynevent.wire import _json
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import Compatibility, DynamicState, EventType, Status
from scenario import deferred, running, stubborn, waiting

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
PROFILE = os.environ.get("DYNEVENT_HYPOTHESIS_PROFILE", "ci")
#: Steps per stateful run: short in ci, the profile's own count (200 in deep) otherwise.
STEPS = 40 if PROFILE == "ci" else settings.default.stateful_step_count

RMF_ROS2_CONFIG: dict[str, Any] = {**DEFAULT_CONFIG, "compatibility": "rmf_ros2", "id_policy": "adapter"}
CONFIGS = {
    "standard": config_from_json(dict(DEFAULT_CONFIG)),
    "rmf_ros2": config_from_json(RMF_ROS2_CONFIG),
}
CATEGORIES = tuple(DEFAULT_CONFIG["categories"])
SEQUENCES = input_sequences(CATEGORIES, max_size=40)
UUIDS = [f"{index:032x}" for index in range(1, 5)]


# --------------------------------------------------------------------------- the kit on dynevent


class DyneventKit(ServerStateMachine):
    """The kit driving dynevent's own machine in the standard configuration."""

    def make_server(self) -> ServerUnderTest:
        return DyneventServer()


TestDyneventKit = pytest.mark.spec("R19.1", "R19.2", "R19.3", "R19.4", "R19.5", "R19.7")(DyneventKit.TestCase)
TestDyneventKit.settings = settings(settings.default, stateful_step_count=STEPS)


@pytest.mark.spec("R19.1", "R19.2", "R19.3", "R19.4", "R19.5", "R19.7", "R17.1", "R17.3")
def test_kit_finds_nothing_wrong_in_rmf_ros2_mode() -> None:
    machine_class = server_state_machine(DyneventServer, config=RMF_ROS2_CONFIG, name="RmfRos2Kit")
    run_state_machine_as_test(machine_class, settings=settings(settings.default, stateful_step_count=STEPS))


@pytest.mark.spec("R19.1", "R19.5")
def test_kit_drives_an_implementation_through_the_driver_protocol() -> None:
    machine_class = server_state_machine(
        lambda: ImplementationServer(InProcessImplementation()), name="DriverKit"
    )
    run_state_machine_as_test(
        machine_class,
        settings=settings(settings.default, max_examples=min(settings.default.max_examples, 25)),
    )


# --------------------------------------------------------------------------- deliberately broken servers


class CancelFreesTheRobot(DyneventServer):
    """rmf_ros2: once a CANCEL starts, the robot counts as idle and takes a NEXT as the child winds down."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        state = self.state
        if isinstance(event, ins.GoalRequested) and state is not None and state.cancels:
            open_goals = {queued.goal_uuid for queued in state.queued} | set(state.cancels)
            idle = attrs.evolve(state, running=None, cancels=())
            decision = machine.accept(idle, event.goal, self.config)
            if isinstance(decision, outs.Accepted) and event.goal_uuid not in open_goals:
                queued = QueuedGoal(goal_uuid=event.goal_uuid, goal=event.goal)
                self.state = attrs.evolve(state, queued=(*state.queued, queued))
                return [outs.GoalAccepted(goal_uuid=event.goal_uuid)]
        return super().apply(event)


class StatusWhileTheSlotIsHeld(DyneventServer):
    """rmf_ros2: at a child's end the status is published while the finished goal still holds the slot."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        running = None if before is None else before.running
        if isinstance(event, ins.ChildFinished) and running is not None and running.started:
            assert before is not None
            stale = DynamicEventStatus(
                dynamic_event_seq=before.seq,
                dynamic_state=DynamicState.RUNNING,
                status=event.status,
                id=running.child_id,
                time=machine.status_message(before, event.now).time,
            )
            outputs = [
                outs.PublishStatus(message=stale) if isinstance(output, outs.PublishStatus) else output
                for output in outputs
            ]
        return outputs


class SeqNotRecheckedAtStart(DyneventServer):
    """rmf_ros2: a goal accepted for one run can start in the next (the seq is not checked again)."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        state = self.state
        if isinstance(event, ins.GoalStarted) and state is not None and state.active:
            queued = tuple(
                attrs.evolve(item, goal=attrs.evolve(item.goal, dynamic_event_seq=state.seq))
                if item.goal_uuid == event.goal_uuid
                else item
                for item in state.queued
            )
            self.state = attrs.evolve(state, queued=queued)
        return super().apply(event)


class StubbornPeriodNotClamped(DyneventServer):
    """A hold begins with the requested period even when it is below the minimum."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        if before is not None and before.running is not None:
            requested = before.running.goal.stubborn_period
            outputs = [
                attrs.evolve(output, period=requested) if isinstance(output, outs.StubbornBegin) else output
                for output in outputs
            ]
        return outputs


class ForgetsQueuedGoalsAtShutdown(DyneventServer):
    """Shutdown answers the running goal but forgets goals accepted and not yet started."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        if isinstance(event, ins.Shutdown) and before is not None:
            forgotten = {queued.goal_uuid for queued in before.queued}
            outputs = [output for output in outputs if getattr(output, "goal_uuid", None) not in forgotten]
        return outputs


class RaisesOnKill(DyneventServer):
    """Raises when the task is killed while a child runs."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        if isinstance(event, ins.TaskKill) and self.state is not None and self.state.running is not None:
            raise RuntimeError("kill while running")
        return super().apply(event)


BROKEN: dict[str, tuple[type[DyneventServer], str]] = {
    "cancel_frees_the_robot": (CancelFreesTheRobot, "R19.2"),
    "status_while_the_slot_is_held": (StatusWhileTheSlotIsHeld, "R19.5"),
    "seq_not_rechecked_at_start": (SeqNotRecheckedAtStart, "R5.2"),
    "stubborn_period_not_clamped": (StubbornPeriodNotClamped, "R19.4"),
    "forgets_queued_goals_at_shutdown": (ForgetsQueuedGoalsAtShutdown, "R19.1"),
    "raises_on_kill": (RaisesOnKill, "R19.7"),
}


@pytest.mark.spec("R19.1", "R19.2", "R19.4", "R19.5", "R19.7", "R5.2")
@pytest.mark.parametrize("name", sorted(BROKEN))
def test_kit_catches_a_broken_server(name: str) -> None:
    server_class, rule = BROKEN[name]
    machine_class = server_state_machine(server_class, name=f"Broken_{name}")
    with pytest.raises(ProtocolViolation) as caught:
        run_state_machine_as_test(
            machine_class,
            settings=settings(
                max_examples=2_000,
                stateful_step_count=50,
                deadline=None,
                database=None,
                derandomize=True,
                phases=[Phase.generate],
                report_multiple_bugs=False,
                suppress_health_check=list(HealthCheck),
            ),
        )
    assert caught.value.rule == rule, str(caught.value)


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


@pytest.mark.spec("R19.1", "R19.2", "R19.5")
@configs
@given(events=SEQUENCES)
def test_the_kit_observer_accepts_dynevent_on_random_sequences(mode: str, events: list[ins.Input]) -> None:
    config = CONFIGS[mode]
    observer = Observer("fleet", "robot", config)
    state = State.new("fleet", "robot")
    for event in [*events, ins.Shutdown(now=events[-1].now)]:
        transition = machine.step(state, event, config)
        observer.observe(event, transition.outputs)
        state = transition.state
        assert (observer.phase, observer.seq, observer.current_id) == (
            state.phase,
            state.seq,
            state.current_id,
        )
    observer.check_all_answered()


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
