"""R19.8: restore refuses every state the machine cannot reach, with the path of the fault."""

from __future__ import annotations

import json
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.conformance.driver import Driver
from dynevent.conformance.records import config_from_json
from dynevent.errors import InvalidSnapshot
from dynevent.server import machine, snapshot
from dynevent.server.fleet import Fleet
from dynevent.server.machine import State
from dynevent.testing import DEFAULT_CONFIG, input_sequences
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType, Status
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


def _resyncs(state: State, uuid: str, number: int, status: str) -> dict[str, State]:
    """Every resync operation the machine offers an observer, applied to ``state``."""
    goal = Goal(dynamic_event_seq=state.seq, event_type=EventType.NEXT, id=number)
    displaced = [item.goal_uuid for item in state.queued][:1]
    return {
        "seq": machine.resync_seq(state, number) if not state.active else state,
        "next_run": machine.resync_next_run(state, number) if not state.active else state,
        "serving": machine.resync_serving(state) if not state.active else state,
        "run_dropped": machine.resync_run_dropped(state),
        "event_id": machine.resync_event_id(state, number) if state.active else state,
        "queued": machine.resync_queued(state, uuid, goal) if state.active else state,
        "dropped": machine.resync_dropped(state, (*displaced, uuid)[0]),
        "child_started": machine.resync_child_started(state, resumed=True),
        "start_dropped": machine.resync_start_dropped(state) if state.running is not None else state,
        "running_goal": machine.resync_running_goal(state, uuid),
        "child_id": machine.resync_child_id(state, max(number, state.last_id)),
        "running": machine.resync_running(state, uuid, goal, max(number, state.last_id), status, displaced)
        if state.active and not state.shutdown
        else state,
    }


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
