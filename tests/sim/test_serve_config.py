"""``dynevent serve``'s configuration and its simulated children, without ROS 2: the field's categories
by default, a map and actions when configured, and children that do what their descriptions say."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from dynevent import descriptions
from dynevent.errors import ServeError
from dynevent.server import inputs, machine
from dynevent.server import outputs as outs
from dynevent.sim.config import (
    DEFAULT_CATEGORIES,
    ServeConfig,
    Step,
    load_config,
    machine_config,
    plan,
)
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType


def _load(tmp_path: Path, data: Any) -> ServeConfig:
    path = tmp_path / "serve.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    return load_config(str(path))


def _accepts(config: ServeConfig, category: str, description: Any) -> tuple[str, ...]:
    server = machine_config(config)
    state = machine.State.new("tinyRobot", "r1")
    state, _ = machine.step(state, inputs.Begin(description="{}", event_id=1, now=1), server)
    goal = Goal(
        dynamic_event_seq=1,
        event_type=EventType.NEXT,
        category=category,
        description=json.dumps(description),
        id=2,
    )
    decision = machine.accept(state, goal, server)
    return () if isinstance(decision, outs.Accepted) else decision.errors or (decision.reason.value,)


@pytest.mark.spec("R4.18")
def test_by_default_serve_takes_every_field_category_and_every_place() -> None:
    config = load_config()
    assert set(config.categories) == set(descriptions.CATEGORIES)
    assert _accepts(config, "go_to_place", {"waypoint": "A"}) == ()
    assert _accepts(config, "go_to_place", 3) == ()
    assert _accepts(config, "perform_action", {"category": "anything", "description": {}}) == ()
    assert _accepts(config, "go_to_place", {"one_of": ["A", 5.5]}) == ("/one_of/1: 5.5 is not a place",)
    assert _accepts(config, "perform_action", "clean") == ('/: "clean" is not an object',)


@pytest.mark.spec("R4.18")
def test_a_configured_map_and_actions_refuse_the_unknown_by_name(tmp_path: Path) -> None:
    config = _load(tmp_path, {"places": ["pantry", None, "lounge"], "actions": ["wave"]})
    assert _accepts(config, "go_to_place", {"one_of": [1, "lounge"]}) == ()
    assert _accepts(config, "go_to_place", "attic") == ('/: "attic" is not a waypoint on this robot\'s map',)
    assert _accepts(config, "perform_action", {"category": "dance", "description": 1}) == (
        '/category: "dance" is not an action this robot performs ("wave")',
    )


def test_custom_categories_take_any_description_and_may_be_a_sequences_activities(tmp_path: Path) -> None:
    config = _load(tmp_path, {"categories": {"patrol": {"duration": 1}, "sequence": {}}})
    assert _accepts(config, "patrol", [1, {"x": None}]) == ()
    assert _accepts(config, "sequence", [{"category": "patrol", "description": "A"}]) == ()
    assert _accepts(config, "sequence", [{"category": "go_to_place", "description": "A"}]) == (
        '/0/category: "go_to_place" is not a category this robot supports ("patrol", "sequence")',
    )
    assert _accepts(config, "go_to_place", "A") == ("unsupported_category",)


@pytest.mark.parametrize(
    ("data", "problem"),
    [
        ({"places": "pantry"}, "places: expected a list of waypoint names"),
        ({"places": ["a", "a"]}, "Robot.places: waypoint 1: a name is given to two waypoints"),
        ({"actions": [1]}, "actions: expected a list of action names"),
        (
            {"categories": {"go_to_place": {"needs_place": True}}},
            "categories.go_to_place: unknown keys ['needs_place']",
        ),
        ({"zones": []}, "unknown keys ['zones']"),
    ],
)
def test_a_bad_configuration_is_named(tmp_path: Path, data: Any, problem: str) -> None:
    with pytest.raises(ServeError, match=problem.replace("[", r"\[").replace("]", r"\]")):
        _load(tmp_path, data)


SPEC = ServeConfig()


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(
    ("category", "description", "steps"),
    [
        ("go_to_place", "pantry", [Step("go_to_place pantry", 3.0)]),
        ("go_to_place", 4, [Step("go_to_place #4", 3.0)]),
        ("go_to_place", {"waypoint": "A", "orientation": 1.5}, [Step("go_to_place A (facing 1.5 rad)", 3.0)]),
        ("go_to_place", {"one_of": ["nowhere", "lounge"]}, [Step("go_to_place lounge", 3.0)]),
        ("go_to_place", {"one_of": ["nowhere"]},
         [Step("go_to_place nowhere", 3.0, "nowhere: no such place")]),
        ("go_to_place", {"place": "A", "followed_by": ["B", 2]}, [Step("go_to_place A, then B, #2", 3.0)]),
        ("perform_action", {"category": "wave", "description": {}}, [Step("perform_action wave", 2.0)]),
        (
            "perform_action",
            {"category": "wave", "description": {}, "unix_millis_action_duration_estimate": 1500},
            [Step("perform_action wave", 1.5)],
        ),
        ("clean", {"zone": "lobby"}, [Step("clean lobby", 5.0)]),
        ("pickup", {"place": "dock", "payload": {"sku": "box", "quantity": 2}},
         [Step("pickup at dock (2 items)", 2.0)]),
        (
            "sequence",
            {"activities": [
                {"category": "go_to_place", "description": "pantry"},
                {"category": "sequence",
                 "description": [{"category": "clean", "description": {"zone": "z"}}]},
            ]},
            [Step("activity 1 of 2: go_to_place pantry", 3.0),
             Step("activity 2 of 2: activity 1 of 1: clean z", 5.0)],
        ),
        ("sequence", [], [Step("sequence (no activities)", 0.001)]),
    ],
)  # fmt: skip
def test_a_simulated_child_does_what_its_description_says(
    category: str, description: Any, steps: list[Step]
) -> None:
    assert descriptions.Robot().check(category, description) == ()
    assert plan(category, description, SPEC) == steps


def test_the_defaults_are_the_documented_ones() -> None:
    assert DEFAULT_CATEGORIES["go_to_place"].fail_on == ("nowhere",)
    assert DEFAULT_CATEGORIES["go_to_place"].duration == 3.0
    assert DEFAULT_CATEGORIES["perform_action"].duration == 2.0


def test_the_first_runs_seq_is_configured_by_file_or_flag_within_a_uint32(tmp_path: Path) -> None:
    assert load_config().first_seq == 1
    assert _load(tmp_path, {"first_seq": 4294967295}).first_seq == 4294967295
    assert load_config(first_seq=0).first_seq == 0
    for value in (-1, 2**32, 1.5, True, "7"):
        with pytest.raises(ServeError, match=r"serve\.json: first_seq: expected a seq from 0 to 4294967295"):
            _load(tmp_path, {"first_seq": value})
    with pytest.raises(
        ServeError, match=r"^--first-seq: expected a seq from 0 to 4294967295 \(got 4294967296\)$"
    ):
        load_config(first_seq=2**32)
