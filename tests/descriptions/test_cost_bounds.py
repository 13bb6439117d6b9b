"""R4.19: a description is judged in time linear in its size, whatever it holds.

Time is not asserted here (machines are shared and noisy; bench/hostile_goals.py measures it): the
work is counted instead, as the number of Python-level calls one check makes, which does not depend
on the machine.  A check whose work grows faster than the goal, or at all once the refusal has
listed all it lists, fails these tests.
"""

from __future__ import annotations

import difflib
import json
import sys
from collections.abc import Callable
from types import FrameType
from typing import Any

import pytest

from dynevent import ServerConfig, descriptions
from dynevent.descriptions import _suggest
from dynevent.descriptions._explain import render
from dynevent.errors import InvalidConfig
from dynevent.server import inputs, machine
from dynevent.server import outputs as outs
from dynevent.server.config import MAX_LISTED_ERRORS, MORE_ERRORS
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType

PLACES = [f"place_{number:04d}" for number in range(2_000)]


def calls(work: Callable[[], object]) -> int:
    """How many Python and C functions ``work`` calls."""
    count = 0

    def profile(frame: FrameType, event: str, arg: Any) -> None:
        nonlocal count
        if event in ("call", "c_call"):
            count += 1

    sys.setprofile(profile)
    try:
        work()
    finally:
        sys.setprofile(None)
    return count


@pytest.fixture(scope="module")
def robot() -> descriptions.Robot:
    return descriptions.Robot(places=PLACES)


@pytest.mark.spec("R4.19")
def test_a_refusal_lists_the_first_errors_and_one_line_for_the_rest(robot: descriptions.Robot) -> None:
    names = [name[:-1] + "x" for name in PLACES[:300]]
    errors = robot.check("go_to_place", {"one_of": names})
    assert len(errors) == MAX_LISTED_ERRORS + 1 and errors[-1] == MORE_ERRORS
    assert errors[0].startswith(
        '/one_of/0: "place_000x" is not a waypoint on this robot\'s map (did you mean'
    )
    assert [line.split(":")[0] for line in errors[:-1]] == [f"/one_of/{n}" for n in range(MAX_LISTED_ERRORS)]
    exactly = robot.check("go_to_place", {"one_of": names[:MAX_LISTED_ERRORS]})
    assert len(exactly) == MAX_LISTED_ERRORS and MORE_ERRORS not in exactly


@pytest.mark.spec("R4.19")
def test_only_the_first_unknown_names_get_a_suggestion(
    robot: descriptions.Robot, monkeypatch: pytest.MonkeyPatch
) -> None:
    asked: list[int] = []
    close = difflib.get_close_matches

    def counted(word: str, possibilities: Any, *args: Any, **kwargs: Any) -> list[str]:
        asked.append(len(list(possibilities)))
        return close(word, possibilities, *args, **kwargs)

    monkeypatch.setattr(_suggest.difflib, "get_close_matches", counted)
    errors = robot.check("go_to_place", {"one_of": [name[:-1] + "x" for name in PLACES[:300]]})
    assert len(asked) == 3 and max(asked) <= 16  # three names, each against a few candidates
    assert ["did you mean" in line for line in errors[:5]] == [True, True, True, False, False]
    assert _suggest.Suggestions(PLACES).closest("x" * 65) is None  # too long to be a near miss


def test_suggestions_find_a_near_miss_among_many_names() -> None:
    suggestions = _suggest.Suggestions([*PLACES, "pantry", "lounge"])
    assert suggestions.closest("pantyr") == "pantry"
    assert suggestions.closest("loungee") == "lounge"
    assert suggestions.closest("zzzz") is None
    assert _suggest.Suggestions([]).closest("pantry") is None


@pytest.mark.spec("R4.19")
@pytest.mark.parametrize(
    "shape",
    [
        pytest.param(
            lambda n: ("go_to_place", {"one_of": [f"plaec_{k:05d}" for k in range(n)]}), id="near misses"
        ),
        pytest.param(lambda n: ("go_to_place", {"one_of": [k + 0.5 for k in range(n)]}), id="non-places"),
        pytest.param(lambda n: ("go_to_place", {"one_of": list(range(5_000, 5_000 + n))}), id="off the map"),
        pytest.param(
            lambda n: ("pickup", {"place": "place_0001", "payload": [{"sku": k} for k in range(n)]}),
            id="bad payload items",
        ),
        pytest.param(
            lambda n: ("sequence", [{"category": "go_to_place", "description": f"no_{k}"} for k in range(n)]),
            id="activities off the map",
        ),
        pytest.param(
            lambda n: ("go_to_place", {"one_of": [*PLACES[: n - 1], 0.5]}), id="one fault after valid places"
        ),
    ],
)
def test_the_work_of_a_refusal_grows_no_faster_than_the_goal(
    robot: descriptions.Robot, shape: Callable[[int], tuple[str, Any]]
) -> None:
    small, large = shape(200), shape(2_000)
    assert robot.check(*small) and robot.check(*large)
    robot.check(*small)  # warm: the first check compiles what later ones reuse
    ratio = calls(lambda: robot.check(*large)) / calls(lambda: robot.check(*small))
    assert ratio < 11, ratio  # ten times the goal: at most about ten times the work


@pytest.mark.spec("R4.19")
def test_a_goal_of_many_faults_costs_the_machine_no_more_than_a_valid_one(robot: descriptions.Robot) -> None:
    config = ServerConfig(categories=robot.validators())
    state = machine.step(
        machine.State.new("fleet", "robot"), inputs.Begin(description="{}", event_id=1, now=1), config
    ).state

    def goal(description: str) -> Goal:
        return Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place",
                    description=description, id=2)  # fmt: skip

    valid = goal(json.dumps({"one_of": PLACES}))
    hostile = goal(json.dumps({"one_of": [name[:-1] + "x" for name in PLACES]}))
    assert isinstance(machine.accept(state, valid, config), outs.Accepted)
    refused = machine.accept(state, hostile, config)
    assert isinstance(refused, outs.Rejected) and refused.errors[-1] == MORE_ERRORS
    assert refused.text.count("did you mean") == 3
    assert calls(lambda: machine.accept(state, hostile, config)) < 2 * calls(
        lambda: machine.accept(state, valid, config)
    )


@pytest.mark.spec("R4.19")
def test_a_lazy_validator_is_read_no_further_than_the_refusal_lists() -> None:
    read: list[int] = []

    def endless(category: str, description: Any) -> Any:
        number = 0
        while True:
            read.append(number)
            yield f"/: fault {number}"
            number += 1

    config = ServerConfig(categories={"patrol": endless})
    state = machine.step(
        machine.State.new("fleet", "robot"), inputs.Begin(description="{}", event_id=1, now=1), config
    ).state
    goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="patrol", description="{}", id=2)
    refused = machine.accept(state, goal, config)
    assert isinstance(refused, outs.Rejected)
    assert refused.errors == (*(f"/: fault {n}" for n in range(MAX_LISTED_ERRORS)), MORE_ERRORS)
    assert len(read) == MAX_LISTED_ERRORS + 1
    assert refused.execution_failure.endswith(f"\n -- {MORE_ERRORS}") and refused.rule == "R4.10"


@pytest.mark.spec("R4.19")
def test_sequences_nested_past_the_wire_limit_are_a_fault_not_a_recursion_error() -> None:
    description: Any = "nowhere"
    category = "go_to_place"
    for _ in range(2_000):
        description = [{"category": category, "description": description}]
        category = "sequence"
    errors = descriptions.Robot(places=["A"]).check("sequence", description)
    assert len(errors) == 1 and errors[0].endswith("sequences nested deeper than 64 levels"), errors
    assert errors[0].startswith("/0/description/0/description/")


@pytest.mark.spec("R4.19")
def test_values_are_quoted_shortened_whatever_their_size() -> None:
    assert render(10**5_000) == "<an integer of about 5001 digits>"
    assert render(10**400) == "1" + "0" * 46 + "…"
    deep: Any = 1
    for _ in range(100_000):
        deep = [deep]
    assert render(deep) == "[" * 47 + "…"
    assert render({"a": "x" * 10**6}) == '{"a": "' + "x" * 40 + "…"
    robot = descriptions.Robot(places=["A"])
    assert robot.check("go_to_place", 10**5_000) == (
        "/: waypoint <an integer of about 5001 digits> is not on this robot's map (its waypoints are 0 to 0)",
    )
    assert str(descriptions.Place(10**5_000)) == "#<an integer of about 5001 digits>"


@pytest.mark.parametrize(
    ("field", "value"),
    [("categories", 0), ("categories", [5]), ("actions", [[]]), ("actions", [3]), ("places", 7)],
)
def test_a_robot_read_from_a_file_names_a_wrong_value(field: str, value: Any) -> None:
    with pytest.raises(InvalidConfig) as raised:
        descriptions.Robot(**{field: value})
    assert raised.value.field == field
