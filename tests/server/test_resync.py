"""The machine's resync operations: how an observer's state is brought into agreement with a server.

Each operation is checked for exactly what it changes; tests/spec/test_19_invariants.py checks that
every one keeps the machine's invariants on reachable states.
"""

from __future__ import annotations

import attrs

from dynevent.server import machine, resync
from dynevent.server.machine import UNKNOWN_GOAL, QueuedGoal, State
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, Status
from support.scenario import deferred, running, stubborn, u, waiting

FRESH = State.new("fleet", "robot")


def _changes(before: State, after: State) -> dict[str, object]:
    """The fields ``after`` changed, with their new values."""
    return {
        field.name: getattr(after, field.name)
        for field in attrs.fields(State)
        if getattr(before, field.name) != getattr(after, field.name)
    }


def test_seq_and_the_next_run() -> None:
    assert _changes(FRESH, resync.seq(FRESH, 7)) == {"seq": 7}
    assert resync.seq(FRESH, 2**32 + 3).seq == 3  # a seq is a uint32
    assert _changes(FRESH, resync.next_run(FRESH, 7)) == {"seq": 6}
    assert resync.next_run(FRESH, 0).seq == 2**32 - 1  # the run before 0 wraps


def test_serving_again_after_a_shutdown() -> None:
    shut = attrs.evolve(FRESH, shutdown=True)
    assert _changes(shut, resync.serving(shut)) == {"shutdown": False}


def test_a_dropped_run_keeps_its_seq_and_ids() -> None:
    before = running(child_id=5).state
    after = resync.run_dropped(before)
    assert _changes(before, after) == {"active": False, "running": None}
    held = stubborn().state
    assert _changes(held, resync.run_dropped(held)) == {"active": False, "stubborn": None}


def test_the_event_id_raises_the_highest_id_unless_a_child_runs() -> None:
    before = waiting(event_id=1).state
    assert _changes(before, resync.event_id(before, 9)) == {"event_id": 9, "last_id": 9}
    assert _changes(before, resync.event_id(before, 0)) == {"event_id": 0}
    busy = running(child_id=5).state
    assert _changes(busy, resync.event_id(busy, 9)) == {"event_id": 9}


def test_a_goal_queued_and_dropped() -> None:
    before = waiting().state
    goal = Goal(dynamic_event_seq=before.seq, event_type=EventType.NEXT, id=3)
    queued = resync.queued(before, u(4), goal)
    assert _changes(before, queued) == {"queued": (QueuedGoal(goal_uuid=u(4), goal=goal),)}
    assert resync.dropped(queued, u(4)) == before
    assert resync.dropped(queued, u(5)) == queued
    waiting_cancel = attrs.evolve(running().state, cancels=(u(6), u(7)))
    assert resync.dropped(waiting_cancel, u(6)).cancels == (u(7),)


def test_a_deferred_child_started() -> None:
    before = deferred(child_id=5).state
    assert before.interrupted
    started = resync.child_started(before)
    assert started.running is not None and started.running.started and started.interrupted
    resumed = resync.child_started(before, resumed=True)
    assert resumed.running is not None and resumed.running.started and not resumed.interrupted
    idle = waiting().state
    assert resync.child_started(idle, resumed=True) is idle


def test_a_deferred_start_dropped() -> None:
    before = deferred().state
    assert _changes(before, resync.start_dropped(before)) == {
        "running": None,
        "status": Status.STANDBY.value,
    }


def test_the_unknown_running_goal_named() -> None:
    status = DynamicEventStatus(
        dynamic_event_seq=3, dynamic_state=DynamicState.RUNNING, status="underway", id=8
    )
    before = machine.state_from_status(status)
    assert before.running is not None and before.running.goal_uuid == UNKNOWN_GOAL
    after = resync.running_goal(before, u(9))
    assert after.running == attrs.evolve(before.running, goal_uuid=u(9))
    assert resync.running_goal(FRESH, u(9)) is FRESH


def test_the_running_child_renumbered() -> None:
    before = running(child_id=5).state
    after = resync.child_id(before, 12)
    assert after.running is not None and after.running.child_id == 12 and after.last_id == 12
    assert resync.child_id(FRESH, 12) is FRESH


def test_a_next_forced_to_run() -> None:
    before = running(child_id=5, uuid=u(1)).state
    goal = Goal(dynamic_event_seq=before.seq, event_type=EventType.NEXT, id=6)
    queued = resync.queued(resync.queued(before, u(2), goal), u(3), goal)
    after = resync.running(queued, u(2), goal, 6, "underway", [u(1)])
    assert after.running == machine.RunningGoal(
        goal_uuid=u(2), goal=goal, child_id=6, child_status="underway", started=True
    )
    assert [item.goal_uuid for item in after.queued] == [u(3)]
    assert (after.last_id, after.status, after.cancels, after.stubborn, after.active) == (
        6,
        "underway",
        (),
        None,
        True,
    )
    assert not after.interrupted
    held = resync.running(queued, u(2), goal, 6, Status.QUEUED.value, [u(1)])
    assert held.running is not None and not held.running.started and held.interrupted


# --------------------------------------------------------------------------- a status message's state


def test_state_from_status_of_each_phase() -> None:
    def of(phase: DynamicState, text: str, id: int, **kwargs: int) -> State:
        message = DynamicEventStatus(dynamic_event_seq=3, dynamic_state=phase, status=text, id=id)
        return machine.state_from_status(message, **kwargs)

    base = State.new("fleet", "robot")
    assert of(DynamicState.INACTIVE, "uninitialized", 0) == attrs.evolve(base, seq=3)
    assert of(DynamicState.INACTIVE, "uninitialized", 0, last_id=9) == attrs.evolve(base, seq=3, last_id=9)
    assert of(DynamicState.WAITING, "standby", 4, last_id=2) == attrs.evolve(
        base, seq=3, active=True, event_id=4, description="{}", status="standby", last_id=4
    )
    assert of(DynamicState.WAITING, "standby", 4, last_id=6).last_id == 6
    goal = Goal(dynamic_event_seq=3, event_type=EventType.NEXT, id=8)
    unknown = machine.RunningGoal(
        goal_uuid=UNKNOWN_GOAL, goal=goal, child_id=8, child_status="underway", started=True
    )
    assert of(DynamicState.RUNNING, "underway", 8) == attrs.evolve(
        base, seq=3, active=True, description="{}", status="underway", last_id=8, running=unknown
    )
    deferred_start = of(DynamicState.RUNNING, "queued", 8, last_id=10)
    assert deferred_start.running is not None and not deferred_start.running.started
    assert deferred_start.interrupted and deferred_start.last_id == 10
    named = machine.state_from_status(
        DynamicEventStatus(dynamic_event_seq=1, dynamic_state=DynamicState.WAITING), "tinyRobot", "r1"
    )
    assert (named.fleet, named.robot) == ("tinyRobot", "r1")


def test_the_unknown_goal_is_a_goal_uuid_no_client_draws() -> None:
    assert UNKNOWN_GOAL == "0" * 32


def test_state_from_status_refuses_a_phase_that_is_none() -> None:
    message = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=3)
    try:
        machine.state_from_status(message)
    except ValueError as exc:
        assert str(exc) == "dynamic_state 3 is none of INACTIVE (0), WAITING (1), RUNNING (2)"
    else:
        raise AssertionError("no ValueError")
