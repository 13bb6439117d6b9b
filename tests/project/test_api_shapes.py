"""The API's shapes: what a step gives unpacks as the pair it is, at every level; one class per idea;
a phase prints as its name; renamed names still work for one release, with a warning."""

from __future__ import annotations

import pytest

import dynevent
from dynevent import SECOND, ServerConfig, State, any_description, client, inputs, outputs, step
from dynevent.server.fleet import Fleet
from dynevent.wire.messages import DynamicEventStatus
from dynevent.wire.vocab import DynamicState

CONFIG = ServerConfig(categories={"go_to_place": any_description})


def test_a_server_step_unpacks_as_state_and_outputs() -> None:
    transition = step(State.new("tinyRobot", "r1"), inputs.Begin(description="{}", now=SECOND), CONFIG)
    state, produced = transition
    assert (state, produced) == (transition.state, transition.outputs)
    assert state.phase is DynamicState.WAITING and isinstance(produced[0], outputs.PublishBegin)


def test_a_client_step_and_command_unpack_as_state_and_outputs() -> None:
    start = client.ClientState.new("0123456789abcdef")
    waiting = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=DynamicState.WAITING, status="standby")
    state, produced = client.step(start, client.StatusReceived(message=waiting))
    assert state.seq == 1 and isinstance(produced, tuple)
    state, (send,) = client.request_next(state, "go_to_place", '"pantry"', timeout=30, now=0)
    assert isinstance(send, client.SendGoal) and state.goals[0].deadline == 30 * SECOND


def test_a_fleet_step_by_name_unpacks_as_robot_and_outputs() -> None:
    fleet = Fleet(config=CONFIG)
    fleet.add("tinyRobot", "r1")
    key, produced = fleet.step_by_name(
        "rmf/dynamic_event/command/tinyRobot/r1", inputs.Begin(description="{}", now=SECOND)
    )
    assert (key.fleet, key.robot) == ("tinyRobot", "r1") and isinstance(produced[0], outputs.PublishBegin)


def test_a_phase_prints_by_name_and_stays_an_int() -> None:
    phase = State.new("tinyRobot", "r1").phase
    assert (str(phase), f"{phase}", f"{phase:>9}", f"{phase:d}", int(phase)) == (
        "INACTIVE",
        "INACTIVE",
        " INACTIVE",
        "0",
        0,
    )
    assert phase == 0 and DynamicState.RUNNING > DynamicState.WAITING


def test_ignored_is_one_class_for_both_machines() -> None:
    assert client.Ignored is outputs.Ignored


@pytest.mark.parametrize("module", [dynevent, dynevent.machine])
def test_no_old_name_is_kept_before_the_first_release(module: object) -> None:
    """0.1.0 is the first release: the names renamed before it (accept_any) are simply gone."""
    with pytest.raises(AttributeError, match="accept_any"):
        module.accept_any  # type: ignore[attr-defined]  # noqa: B018


def test_the_top_level_keeps_the_query_and_the_validator_apart() -> None:
    assert "accept" in dynevent.__all__ and "any_description" in dynevent.__all__
    assert dynevent.accept.__module__ == "dynevent.server.machine"
    assert any_description("go_to_place", {"anything": 1}) == ()


def test_the_observers_resync_operations_live_in_one_module() -> None:
    from dynevent.server import machine, resync

    assert not [name for name in machine.__all__ if name.startswith("resync_")]
    assert callable(resync.seq)
    with pytest.raises(AttributeError):
        machine.resync_seq  # type: ignore[attr-defined]  # noqa: B018
