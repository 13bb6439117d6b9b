"""§0. Model: the tests of the rules of docs/spec.md §0.

The section's conformance vectors are src/dynevent/conformance/vectors/00-config.json.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import attrs
import pytest

from dynevent.errors import InvalidConfig, InvalidName
from dynevent.server import machine
from dynevent.server.machine import (
    Position,
    QueuedGoal,
    RunningGoal,
    ServerConfig,
    State,
    Stubbornness,
    Transition,
    any_description,
)
from dynevent.wire.vocab import DynamicState
from support.scenario import (
    CONFIG,
    FLEET,
    ROBOT,
    next_goal,
    running,
    u,
)


def _kwargs(field: str, value: Any) -> dict[str, Any]:
    return {field: value}


_BAD_NUMBERS = [0, 0.0, -1, -0.5, True, False, math.nan, math.inf, -math.inf, "2", None]


_BOUNDS = {
    "stubborn_minimum": "expected a number of seconds from 0.001 to 86400",
    "stubborn_refresh": "expected a number of seconds from 0.001 to 86400",
    "stubborn_move_threshold": "expected a number of metres from 0.01 to 1e+06",
}


# --------------------------------------------------------------------------- ServerConfig validation


@pytest.mark.parametrize("value", [["go_to_place"], "go_to_place", None, 3])
def test_categories_must_be_a_mapping(value: Any) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories=value)
    assert isinstance(caught.value, TypeError)
    assert str(caught.value) == (
        f"ServerConfig.categories: expected a mapping of category to validator (got {value!r})"
    )


@pytest.mark.parametrize(
    ("categories", "key"),
    [
        ({1: any_description}, 1),  # a callable validator under a non-str name
        ({"dock": "not callable"}, "dock"),  # a str name mapped to a non-callable
        ({b"dock": None}, b"dock"),
    ],
    ids=["non-str-name", "non-callable", "neither"],
)
def test_each_category_maps_a_str_to_a_callable(categories: Mapping[Any, Any], key: object) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories=categories)
    assert str(caught.value) == (
        f"ServerConfig.categories: each category must map a str to a callable (got {dict(categories)!r})"
    )
    assert caught.value.field == "categories"


def test_categories_are_copied() -> None:
    categories = {"dock": any_description}
    config = ServerConfig(categories=categories)
    categories["other"] = any_description
    assert set(config.categories) == {"dock"}


@pytest.mark.parametrize(
    ("field", "value", "problem"),
    [
        ("id_policy", "bogus", "expected one of ['goal', 'adapter']"),
        ("compatibility", 3, "expected one of ['standard', 'rmf_ros2']"),
        ("max_description_length", 0, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", True, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", 2.5, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", 1_000_001, "expected a positive integer of at most 1000000 (bytes)"),
    ],
)
def test_other_settings_name_the_field(field: str, value: Any, problem: str) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(**_kwargs(field, value))
    assert str(caught.value) == f"ServerConfig.{field}: {problem} (got {value!r})"


@pytest.mark.parametrize(
    ("value", "kept"), [(0.001, 0.01), (0.01, 0.01), (1, 1.0), (0.5, 0.5), (10**6, 1e6)], ids=repr
)
def test_move_threshold_is_at_least_a_centimetre(value: float, kept: float) -> None:
    threshold = ServerConfig(stubborn_move_threshold=value).stubborn_move_threshold
    assert threshold == kept
    assert type(threshold) is float


@pytest.mark.parametrize("field", ["stubborn_minimum", "stubborn_refresh"])
@pytest.mark.parametrize("value", [0.001, 1, 2.5, 86_400])  # the bounds of R0.1 and between
def test_small_positive_periods_are_kept(field: str, value: float) -> None:
    assert getattr(ServerConfig(**_kwargs(field, value)), field) == value


def test_server_config_is_keyword_only() -> None:
    with pytest.raises(TypeError):
        ServerConfig({"dock": any_description})  # type: ignore[call-arg]


def test_server_config_compares_and_hashes_by_identity() -> None:
    # A config holds validators (functions) and a dict: it is hashable by identity,
    # so it can key a cache or sit in a set, and two configs are never "equal".
    first, second = ServerConfig(), ServerConfig()
    alias = first
    assert first == alias
    assert first != second
    assert len({first, second, first}) == 2
    assert {CONFIG: 1}[CONFIG] == 1


def test_validator_type_alias() -> None:
    assert machine.Validator == Callable[[str, Any], Iterable[str]]
    hints = typing.get_type_hints(ServerConfig)
    assert hints["categories"] == Mapping[str, Callable[[str, Any], Iterable[str]]]


def test_handler_table_type() -> None:
    hints = typing.get_type_hints(machine)
    handler = Callable[[State, Any, ServerConfig], Transition]
    assert hints["HANDLERS"] == Mapping[str, handler]


# --------------------------------------------------------------------------- state classes


@pytest.mark.parametrize(
    "build",
    [
        lambda: QueuedGoal(u(1), next_goal(1, 5)),  # type: ignore[call-arg]
        lambda: RunningGoal(u(1), next_goal(1, 5), 5, "underway", True),  # type: ignore[call-arg]
        lambda: Position("L1", 0.0, 0.0),  # type: ignore[call-arg]
        lambda: Stubbornness(2.0, 0, 0, None),  # type: ignore[call-arg]
        lambda: State(FLEET, ROBOT),  # type: ignore[call-arg]
    ],
    ids=["QueuedGoal", "RunningGoal", "Position", "Stubbornness", "State"],
)
def test_state_classes_are_keyword_only(build: Callable[[], object]) -> None:
    with pytest.raises(TypeError):
        build()


@pytest.mark.parametrize("build", [lambda: State.new(FLEET, ROBOT), lambda: State(fleet=FLEET, robot=ROBOT)])
def test_initial_state_is_the_spec_table(build: Callable[[], State]) -> None:
    # docs/spec.md section 0, "State": the initial column
    state = build()
    assert attrs.asdict(state, recurse=False) == {
        "fleet": FLEET,
        "robot": ROBOT,
        "seq": 0,
        "active": False,
        "event_id": 0,
        "description": "",
        "status": "uninitialized",
        "last_id": 0,
        "running": None,
        "queued": (),
        "cancels": (),
        "interrupted": False,
        "task_signal": "",
        "stubborn": None,
        "position": None,
        "log_seq": 0,
        "shutdown": False,
    }
    assert state.phase is DynamicState.INACTIVE
    assert state.current_id == 0


@pytest.mark.parametrize(
    ("fleet", "robot", "field", "value"),
    [("1fleet", ROBOT, "fleet", "1fleet"), (FLEET, "r__1", "robot", "r__1"), ("a/b", "c/d", "fleet", "a/b")],
)
def test_new_state_names_the_bad_token(fleet: str, robot: str, field: str, value: str) -> None:
    with pytest.raises(InvalidName) as caught:
        State.new(fleet, robot)
    assert caught.value.field == field
    assert caught.value.value == value
    assert str(caught.value).startswith(f"{field} name {value!r} is not a valid ROS 2 name token: ")


# --------------------------------------------------------------------------- survivors of the split layout


def test_the_dynamic_event_category_is_refused_naming_the_field() -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories={"dynamic_event": machine.any_description})
    assert caught.value.field == "categories" and caught.value.value == "dynamic_event"
    assert caught.value.problem == (
        "'dynamic_event' can never be a child category: a nested run would break the outer one"
    )


def test_the_smallest_description_limit_is_one_byte() -> None:
    assert ServerConfig(max_description_length=1).max_description_length == 1


@pytest.mark.parametrize("seconds", [1, 86_400])
def test_whole_seconds_become_floats_up_to_the_bound(seconds: int) -> None:
    config = ServerConfig(stubborn_minimum=seconds, stubborn_refresh=seconds)
    assert type(config.stubborn_minimum) is float and type(config.stubborn_refresh) is float


def test_a_zero_period_is_refused_as_given() -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(stubborn_minimum=0)
    assert type(caught.value.value) is int and str(caught.value).endswith("(got 0)")


# --------------------------------------------------------------------------- R0.1


@pytest.mark.spec("R0.1")
@pytest.mark.parametrize("field", sorted(_BOUNDS))
@pytest.mark.parametrize("value", [*_BAD_NUMBERS, 10**400, -(10**400), 1e300], ids=repr)
def test_stubborn_settings_must_be_numbers_the_machine_can_run(field: str, value: Any) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(**_kwargs(field, value))
    assert isinstance(caught.value, ValueError)
    assert str(caught.value).startswith(f"ServerConfig.{field}: {_BOUNDS[field]} (got ")


@pytest.mark.spec("R0.1", "R19.7")
@pytest.mark.parametrize("refresh", [0.001, 86_400.0])
def test_the_extreme_refresh_periods_run(refresh: float) -> None:
    config = ServerConfig(
        categories={"go_to_place": any_description}, stubborn_refresh=refresh, stubborn_minimum=86_400
    )
    run = running(config=config, stubborn=1.0)
    run.child_end()
    assert run.state.stubborn is not None and run.state.stubborn.period == 86_400
    for step in (0, 1, 10**6, 10**15):
        run.tick(now=run.now + step)
