"""dynevent.descriptions: the field's description shapes, judged as the fleet adapter's schemas judge them.

The oracle is the ``jsonschema`` package on the fleet adapter's own schema text
(tests/data/field-schemas): for every description drawn (valid ones from the
schemas themselves, near misses, and valid ones with one part replaced)
dynevent's compiled verdict, its explanation and the package's verdict on the
project's own schemas must all agree with it.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any
from urllib.parse import urljoin

import jsonschema
import pytest
import referencing
from hypothesis import given, settings
from hypothesis import strategies as st

from dynevent import ServerConfig, descriptions
from dynevent import client as cl
from dynevent.descriptions import _compile, shapes
from dynevent.errors import (
    InvalidConfig,
    InvalidEventDescription,
    LocalError,
    RemoteError,
    UnknownCategory,
)
from dynevent.server import inputs, machine
from dynevent.server import outputs as outs
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, RejectReason
from support.field_cases import EVERYDAY_GO_TO_PLACE, EVERYDAY_PERFORM_ACTION

FIELD = Path(__file__).resolve().parents[1] / "data" / "field-schemas"
FIELD_SCHEMAS = {path.stem: json.loads(path.read_text()) for path in FIELD.glob("*.json")}
REGISTRY: Any = referencing.Registry().with_resources(
    (schema["$id"], referencing.Resource.from_contents(schema)) for schema in FIELD_SCHEMAS.values()
)
BY_ID = {schema["$id"]: schema for schema in FIELD_SCHEMAS.values()}


def field_schema(category: str) -> dict[str, Any]:
    result: dict[str, Any] = FIELD_SCHEMAS[f"event_description__{category}"]
    return result


def field_valid(category: str, description: Any) -> bool:
    return bool(
        jsonschema.Draft202012Validator(field_schema(category), registry=REGISTRY).is_valid(description)
    )


def own_valid(category: str, description: Any) -> bool:
    own: Any = referencing.Registry().with_resources(
        (name, referencing.Resource.from_contents(schema)) for name, schema in shapes.schemas().items()
    )
    return bool(jsonschema.Draft202012Validator(shapes.schema(category), registry=own).is_valid(description))


# --------------------------------------------------------------------------- the issue's table


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(("description", "valid"), EVERYDAY_GO_TO_PLACE, ids=json.dumps)
def test_everyday_go_to_place_descriptions_get_the_field_schemas_verdict(
    description: Any, valid: bool
) -> None:
    assert field_valid("go_to_place", description) is valid  # the table is the field's truth
    assert descriptions.conforms("go_to_place", description) is valid
    assert (descriptions.Robot().check("go_to_place", description) == ()) is valid


@pytest.mark.spec("R4.18")
def test_perform_action_wants_an_object_with_category_and_description() -> None:
    robot = descriptions.Robot()
    assert robot.check("perform_action", "clean") == ('/: "clean" is not an object',)
    assert robot.check("perform_action", {"category": "clean"}) == ('/: "description" is required',)
    assert robot.check("perform_action", {"category": "clean", "description": None}) == ()


@pytest.mark.spec("R4.10", "R4.18")
@pytest.mark.parametrize(
    ("category", "description", "errors"),
    [
        ("go_to_place", {"one_of": ["A", 5.5]}, ["/one_of/1: 5.5 is not a place"]),
        ("go_to_place", {"place": "A", "followed_by": [1.5]}, ["/followed_by/0: 1.5 is not a place"]),
        (
            "go_to_place",
            {"place": "A", "start_at_departure": "x"},
            ['/start_at_departure: "x" is not a boolean'],
        ),
        ("go_to_place", {"one_of": []}, ["/one_of: [] has fewer than 1 item"]),
        (
            "go_to_place",
            {"place": {"waypoint": -2}},
            ["/place/waypoint: -2 is less than 0"],
        ),
        ("sequence", [{"category": "clean"}], ['/0: "description" is required']),
        ("sequence", {"activities": "x"}, ['/activities: "x" is not an array']),
        (
            "pickup",
            {"place": "A", "payload": [{"sku": "s", "quantity": 1.5}]},
            ["/payload/0/quantity: 1.5 is not an integer"],
        ),
        ("clean", {"zone": 3}, ["/zone: 3 is not a string"]),
        # the form whose kind the value has explains it: an item that lacks a key, not "not a payload"
        ("pickup", {"place": "A", "payload": {"sku": "s"}}, ['/payload: "quantity" is required']),
        (
            "go_to_place",
            {"place": {"waypoint": 2.5}},
            ["/place/waypoint: 2.5 is not a waypoint (a name, or an index from 0)"],
        ),
        (
            "go_to_place",
            {"waypoint": "A", "place": "B"},
            [
                '/: {"waypoint": "A", "place": "B"} is not a go_to_place description '
                '(a place, {"place": ...} or {"one_of": [...]}): it fits more than one of its forms'
            ],
        ),
    ],
)
def test_every_fault_is_a_line_with_its_json_pointer(
    category: str, description: Any, errors: list[str]
) -> None:
    assert list(descriptions.shape_errors(category, description)) == errors


# --------------------------------------------------------------------------- differential


def _inline(node: Any, base: str) -> Any:
    """``node`` with every ``$ref`` replaced by what it names (the schemas have no cycles), for
    hypothesis-jsonschema, which resolves no reference to another document."""
    if isinstance(node, list):
        return [_inline(item, base) for item in node]
    if not isinstance(node, dict):
        return node
    if "$ref" in node:
        target = urljoin(base, node["$ref"])
        document, _, pointer = target.partition("#")
        found: Any = BY_ID[document]
        for part in filter(None, pointer.split("/")):
            found = found[part]
        rest = {key: value for key, value in node.items() if key != "$ref"}
        inlined = _inline(found, document)
        return {**inlined, **_inline(rest, base)} if rest else inlined
    return {
        key: _inline(value, base) for key, value in node.items() if key not in ("$defs", "$schema", "$id")
    }


def _instances(schema: Any) -> st.SearchStrategy[Any]:
    """Instances of an inlined schema of the keywords these schemas use (hypothesis-jsonschema
    would do this, but no release of it runs with the hypothesis of this project's tests)."""
    if not isinstance(schema, dict) or not set(schema) - {"title", "description", "default"}:
        return NEAR_MISSES
    if "oneOf" in schema:
        rest = {key: value for key, value in schema.items() if key != "oneOf"}
        return st.one_of([_instances({**rest, **branch}) for branch in schema["oneOf"]])
    kind = schema.get("type")
    if kind == "object":
        properties = schema.get("properties", {})
        required = schema.get("required", [])
        optional = {name: _instances(sub) for name, sub in properties.items() if name not in required}
        optional["x"] = NEAR_MISSES  # a key no schema names: allowed
        return st.fixed_dictionaries(
            {name: _instances(properties.get(name, {})) for name in required}, optional=optional
        )
    if kind == "array":
        return st.lists(_instances(schema.get("items", {})), min_size=schema.get("minItems", 0), max_size=3)
    if kind == "string":
        return st.text(max_size=4)
    if kind == "integer":
        low = schema.get("minimum")
        whole = st.integers(min_value=low, max_value=2**70)
        return whole | whole.map(float).filter(math.isfinite)
    if kind == "number":
        return st.integers() | st.floats()
    if kind == "boolean":
        return st.booleans()
    raise AssertionError(f"no strategy for {schema}")


def valid_descriptions(category: str) -> st.SearchStrategy[Any]:
    schema = field_schema(category)
    # a draw may fit two forms of a oneOf at once (the field's schema refuses those): keep the others
    return _instances(_inline(schema, schema["$id"])).filter(lambda value: field_valid(category, value))


KEYS = [
    "waypoint", "orientation", "place", "followed_by", "start_at_departure", "one_of", "constraints",
    "category", "description", "unix_millis_action_duration_estimate", "use_tool_sink",
    "expected_finish_location", "activities", "detail", "zone", "type", "handler", "payload", "sku",
    "quantity", "compartment", "x",
]  # fmt: skip
SCALARS = (
    st.sampled_from([[], {}, -1, 1.5, "", None, True, 0])  # the values at the edge of a keyword
    | st.none()
    | st.booleans()
    | st.integers(min_value=-3, max_value=2**70)
    | st.sampled_from([0.0, 1.0, -1.0, 2.5, 1e300, math.nan, math.inf, -math.inf])
    | st.floats()
    | st.text(max_size=3)
)
NEAR_MISSES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.sampled_from(KEYS), inner, max_size=4),
    max_leaves=12,
)


def _nodes(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = [path]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _nodes(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _nodes(item, (*path, index))
    return found


@st.composite
def mutated(draw: st.DrawFn, category: str) -> Any:
    """A valid description with one part (maybe the whole) replaced by a near miss."""
    value = copy.deepcopy(draw(valid_descriptions(category)))
    path = draw(st.sampled_from(_nodes(value)))
    replacement = draw(NEAR_MISSES)
    if not path:
        return replacement
    holder = value
    for part in path[:-1]:
        holder = holder[part]
    holder[path[-1]] = replacement
    return value


@st.composite
def merged(draw: st.DrawFn, category: str) -> Any:
    """Two instances of the schema's forms made one (an object with the keys of both): the
    descriptions that fit two forms of a ``oneOf`` at once, which a ``oneOf`` refuses."""
    schema = field_schema(category)
    forms = _instances(_inline(schema, schema["$id"]))
    first, second = draw(forms), draw(forms)
    if isinstance(first, dict) and isinstance(second, dict):
        return {**first, **second}
    return [first, second] if draw(st.booleans()) else first


def drawn(category: str) -> st.SearchStrategy[Any]:
    return valid_descriptions(category) | mutated(category) | merged(category) | NEAR_MISSES


def _agree(category: str, description: Any) -> None:
    expected = field_valid(category, description)
    assert descriptions.conforms(category, description) is expected, description
    assert own_valid(category, description) is expected, description
    assert (descriptions.shape_errors(category, description) == ()) is expected, description


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize("category", descriptions.CATEGORIES)
@settings(max_examples=300)
@given(data=st.data())
def test_verdicts_equal_the_jsonschema_packages_on_the_field_schemas(
    category: str, data: st.DataObject
) -> None:
    _agree(category, data.draw(drawn(category)))


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize("category", descriptions.CATEGORIES)
@given(data=st.data())
def test_valid_descriptions_are_drawn_and_accepted(category: str, data: st.DataObject) -> None:
    """The generator of valid descriptions really draws valid ones (else the differential test would
    only ever compare refusals)."""
    description = data.draw(valid_descriptions(category))
    assert field_valid(category, description)
    assert descriptions.shape_errors(category, description) == ()
    if category != "sequence":  # a sequence's activities are of any category: the robot checks those
        assert descriptions.Robot().check(category, description) == ()


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(
    "description",
    [1.0, 2**70, True, math.nan, {"waypoint": math.inf}, {"waypoint": "A", "orientation": math.nan},
     {"waypoint": False}, {"one_of": [0.0]}, {"place": "A", "one_of": ["B"]}, [], {}, "", {"one_of": []},
     {"one_of": [-1]}, {"place": "A", "followed_by": []}, {"place": "A", "constraints": 1}],
)  # fmt: skip
def test_edges_of_json_numbers_and_overlapping_forms(description: Any) -> None:
    _agree("go_to_place", description)


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(
    ("category", "description"),
    [("sequence", []), ("sequence", {"activities": []}),
     ("perform_action", {"category": "a", "description": 1, "unix_millis_action_duration_estimate": 1.0}),
     ("pickup", {"place": 0, "payload": []}),
     ("dropoff", {"place": 0, "payload": {"sku": "s", "quantity": -1}}), ("clean", {"zone": ""})],
)  # fmt: skip
def test_edges_of_the_other_categories(category: str, description: Any) -> None:
    _agree(category, description)


# --------------------------------------------------------------------------- the robot


@pytest.mark.spec("R4.18")
def test_places_on_the_map_by_name_and_index() -> None:
    robot = descriptions.Robot(places=["pantry", None, "lounge"])
    assert robot.check("go_to_place", "pantry") == ()
    assert robot.check("go_to_place", 1) == ()  # an unnamed waypoint, by its index
    assert robot.check("go_to_place", {"waypoint": 2.0, "orientation": 0}) == ()
    assert robot.check("go_to_place", {"one_of": ["pantyr", 3]}) == (
        '/one_of/0: "pantyr" is not a waypoint on this robot\'s map (did you mean "pantry"?)',
        "/one_of/1: waypoint 3 is not on this robot's map (its waypoints are 0 to 2)",
    )
    assert robot.check("go_to_place", {"place": "lounge", "followed_by": ["attic"]}) == (
        '/followed_by/0: "attic" is not a waypoint on this robot\'s map',
    )
    assert robot.check("dropoff", {"place": {"waypoint": 9}, "payload": []}) == (
        "/place/waypoint: waypoint 9 is not on this robot's map (its waypoints are 0 to 2)",
    )
    assert descriptions.Robot(places=[]).check("go_to_place", 0) == (
        "/: waypoint 0 is not on this robot's map (it has no waypoints)",
    )


@pytest.mark.spec("R4.18")
def test_actions_the_robot_performs() -> None:
    robot = descriptions.Robot(places=["dock"], actions=["wave", "teleop"])
    assert robot.check("perform_action", {"category": "wave", "description": {}}) == ()
    assert robot.check(
        "perform_action", {"category": "dance", "description": {}, "expected_finish_location": "x"}
    ) == (
        '/category: "dance" is not an action this robot performs ("teleop", "wave")',
        '/expected_finish_location: "x" is not a waypoint on this robot\'s map',
    )
    assert descriptions.Robot().check("perform_action", {"category": "dance", "description": 1}) == ()


@pytest.mark.spec("R4.18", "R4.17")
def test_a_sequence_checks_each_activity_under_its_own_category() -> None:
    robot = descriptions.Robot(places=["pantry"], categories=["go_to_place", "sequence"])
    activities = [
        {"category": "go_to_place", "description": "pantry"},
        {"category": "go_to_place", "description": "nowhere"},
        {"category": "dynamic_event", "description": {}},
        {
            "category": "sequence",
            "description": {"activities": [{"category": "go_to_place", "description": 4.5}]},
        },
    ]
    assert robot.check("sequence", {"activities": activities}) == (
        '/activities/1/description: "nowhere" is not a waypoint on this robot\'s map',
        '/activities/2/category: "dynamic_event" is not a category this robot supports '
        '("go_to_place", "sequence")',
        "/activities/3/description/activities/0/description: 4.5 is not a go_to_place description "
        '(a place, {"place": ...} or {"one_of": [...]})',
    )
    assert robot.check("sequence", [{"category": "go_to_place", "description": "pantry"}]) == ()
    assert robot.check("perform_action", {"category": "x", "description": 1}) == (
        '/: "perform_action" is not a category this robot supports ("go_to_place", "sequence")',
    )


@pytest.mark.spec("R4.18")
def test_a_sequence_may_use_the_servers_other_categories() -> None:
    def patrol(category: str, description: Any) -> list[str]:
        return [] if isinstance(description, list) else ["/: expected a list of places"]

    validators = descriptions.Robot().validators({"patrol": patrol})
    sequence = validators["sequence"]
    assert sequence("sequence", [{"category": "patrol", "description": ["A"]}]) == ()
    assert sequence("sequence", [{"category": "patrol", "description": "A"}]) == (
        "/0/description: expected a list of places",
    )
    # a line without a pointer is put at the activity's description
    assert descriptions.Robot().validators({"patrol": lambda category, description: ["no"]})["sequence"](
        "sequence", {"activities": [{"category": "patrol", "description": 1}]}
    ) == ("/activities/0/description: no",)


@pytest.mark.spec("R4.10", "R4.18")
def test_the_server_refuses_with_the_lines_as_errors() -> None:
    config = ServerConfig(categories=descriptions.Robot(places=["pantry"]).validators())
    state, _ = machine.step(
        machine.State.new("fleet", "robot"), inputs.Begin(description="{}", event_id=1, now=1), config
    )
    goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place",
                description='{"one_of": ["pantry", 5.5]}', id=2)  # fmt: skip
    decision = machine.accept(state, goal, config)
    assert isinstance(decision, outs.Rejected)
    assert decision.reason is RejectReason.DESCRIPTION_INVALID
    assert decision.errors == ("/one_of/1: 5.5 is not a place",)
    fine = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place",
                description='{"waypoint": "pantry"}', id=2)  # fmt: skip
    assert isinstance(machine.accept(state, fine, config), outs.Accepted)


# --------------------------------------------------------------------------- what every category allows
# docs/descriptions.md: extra keys, whole numbers as integers, an optional orientation, empty arrays.


def _server_verdict(category: str, text: str) -> outs.Accepted | outs.Rejected:
    """What a server configured with the field's validators says of a NEXT carrying ``text``."""
    config = ServerConfig(categories=descriptions.Robot(places=["pantry", "hall", "lounge"]).validators())
    state, _ = machine.step(
        machine.State.new("fleet", "robot"), inputs.Begin(description="{}", event_id=1, now=1), config
    )
    goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category=category, description=text, id=2)
    return machine.accept(state, goal, config)


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(
    ("category", "description"),
    [("go_to_place", {"waypoint": "A", "speed": 1}), ("go_to_place", {"place": "A", "why": "lunch"}),
     ("go_to_place", {"one_of": [{"waypoint": 0, "x": []}], "constraints": [{"category": "c", "y": 1}]}),
     ("perform_action", {"category": "wave", "description": None, "priority": "high"}),
     ("sequence", {"activities": [{"category": "clean", "description": {"zone": "z"}, "note": 1}], "x": 2}),
     ("clean", {"zone": "z", "robots": 2}),
     ("pickup", {"place": "A", "payload": {"sku": "s", "quantity": 1, "colour": "red"}, "dock": 3})],
)  # fmt: skip
def test_extra_keys_are_accepted_and_not_checked_at_every_level(category: str, description: Any) -> None:
    assert field_valid(category, description)
    assert descriptions.Robot().check(category, description) == ()
    assert descriptions.read(category, description) is not None


@pytest.mark.spec("R4.18")
def test_extra_keys_are_left_out_of_what_read_gives() -> None:
    plain = descriptions.read("go_to_place", {"waypoint": "A", "orientation": 1})
    assert descriptions.read("go_to_place", {"waypoint": "A", "orientation": 1, "speed": 1}) == plain


@pytest.mark.spec("R4.18", "R4.10")
def test_a_whole_number_is_an_integer_and_so_an_index() -> None:
    robot = descriptions.Robot(places=["pantry", "hall", "lounge"])
    for index in (2.0, -0.0, 1e0):
        assert field_valid("go_to_place", index) and robot.check("go_to_place", index) == ()
        assert field_valid("go_to_place", {"waypoint": index})
        assert descriptions.read("go_to_place", index) == descriptions.GoToPlace(
            (descriptions.Place(int(index)),)
        )
    assert robot.check("go_to_place", 3.0) == (
        "/: waypoint 3 is not on this robot's map (its waypoints are 0 to 2)",
    )
    assert not field_valid("go_to_place", 2.5) and robot.check("go_to_place", 2.5) != ()
    item = {"sku": "s", "quantity": 2.0}
    assert robot.check("pickup", {"place": 0, "payload": item}) == ()
    assert descriptions.read("pickup", {"place": 0, "payload": item}).payload == (
        descriptions.PayloadItem("s", 2),
    )
    action = {"category": "wave", "description": None, "unix_millis_action_duration_estimate": 1500.0}
    assert robot.check("perform_action", action) == ()
    # a server reads the goal's JSON text: 2, 2.0 and 2e0 are one verdict, 2.5 another
    for text in ("2", "2.0", "2e0", '{"waypoint": 2.0, "orientation": 0}'):
        assert isinstance(_server_verdict("go_to_place", text), outs.Accepted), text
    refused = _server_verdict("go_to_place", "2.5")
    assert isinstance(refused, outs.Rejected) and refused.reason is RejectReason.DESCRIPTION_INVALID


@pytest.mark.spec("R4.18")
def test_orientation_is_optional_and_a_number_when_given() -> None:
    robot = descriptions.Robot()
    alone = {"waypoint": "A"}
    assert field_valid("go_to_place", alone) and robot.check("go_to_place", alone) == ()
    assert descriptions.read("go_to_place", alone).one_of == (descriptions.Place("A", None),)
    for orientation, shown in ((None, "null"), ("x", '"x"'), ([1], "[1]")):
        place = {"waypoint": "A", "orientation": orientation}
        assert not field_valid("go_to_place", place)
        assert robot.check("go_to_place", place) == (f"/orientation: {shown} is not a number",)


@pytest.mark.spec("R4.18")
def test_arrays_may_be_empty_but_one_of() -> None:
    robot = descriptions.Robot()
    empty = [
        ("sequence", []),
        ("sequence", {"activities": []}),
        ("go_to_place", {"place": "A", "followed_by": []}),
        ("go_to_place", {"one_of": ["A"], "constraints": []}),
        ("pickup", {"place": "A", "payload": []}),
    ]
    for category, description in empty:
        assert field_valid(category, description), description
        assert robot.check(category, description) == (), description
    assert descriptions.read("sequence", []) == descriptions.Sequence(())
    assert not field_valid("go_to_place", {"one_of": []})
    assert robot.check("go_to_place", {"one_of": []}) == ("/one_of: [] has fewer than 1 item",)
    assert isinstance(_server_verdict("sequence", "[]"), outs.Accepted)


# --------------------------------------------------------------------------- reading and errors


def test_read_gives_typed_values() -> None:
    read = descriptions.read
    assert read("go_to_place", 3) == descriptions.GoToPlace((descriptions.Place(3),))
    assert read("go_to_place", {"place": {"waypoint": "A", "orientation": 1}, "followed_by": [2.0]}) == (
        descriptions.GoToPlace((descriptions.Place("A", 1.0),), followed_by=(descriptions.Place(2),))
    )
    action = read("perform_action", {"category": "wave", "description": {"arm": 1},
                                     "unix_millis_action_duration_estimate": 2500})  # fmt: skip
    assert action == descriptions.PerformAction("wave", {"arm": 1}, duration_estimate=2.5)
    sequence = read(
        "sequence", {"activities": [{"category": "clean", "description": {"zone": "z"}}], "category": "c"}
    )
    assert sequence == descriptions.Sequence((descriptions.Activity("clean", {"zone": "z"}),), category="c")
    transfer = read("pickup", {"place": "A", "payload": {"sku": "s", "quantity": 2}, "handler": "h"})
    assert transfer == descriptions.PayloadTransfer(
        "pickup", descriptions.Place("A"), (descriptions.PayloadItem("s", 2),), handler="h"
    )
    assert str(descriptions.Place(3, 1.5)) == "#3 (facing 1.5 rad)"


def test_bad_input_is_refused_at_the_edge_with_the_field_named() -> None:
    with pytest.raises(InvalidEventDescription, match=r"go_to_place description refused: /: null") as refused:
        descriptions.read("go_to_place", None)
    assert isinstance(refused.value, RemoteError)
    with pytest.raises(UnknownCategory, match="no description schema for category 'patrol'") as unknown:
        descriptions.schema("patrol")
    assert isinstance(unknown.value, LocalError) and isinstance(unknown.value, KeyError)
    for field, value, text in [
        ("places", "pantry", "Robot.places: expected a list of waypoint names"),
        ("places", ["a", "a"], "Robot.places: waypoint 1: a name is given to two waypoints"),
        ("places", [""], "Robot.places: waypoint 0: expected a name or null"),
        ("actions", [3], "Robot.actions: expected a non-empty name"),
        ("categories", ["patrol"], "Robot.categories: expected categories from go_to_place"),
    ]:
        with pytest.raises(InvalidConfig, match=text):
            descriptions.Robot(**{field: value})


def test_the_compiler_refuses_a_keyword_it_cannot_judge() -> None:
    with pytest.raises(InvalidConfig, match=r"keywords s.json uses and this compiler has not.*pattern"):
        _compile.compile_schema("s.json", {"s.json": {"type": "string", "pattern": "^a"}})
    with pytest.raises(InvalidConfig, match="not in the registry"):
        _compile.compile_schema("s.json", {"s.json": {"$ref": "other.json"}})


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(("description", "valid"), EVERYDAY_PERFORM_ACTION, ids=json.dumps)
def test_everyday_perform_action_descriptions_get_the_field_schemas_verdict(
    description: Any, valid: bool
) -> None:
    assert field_valid("perform_action", description) is valid
    assert (descriptions.Robot().check("perform_action", description) == ()) is valid


# --------------------------------------------------------------------------- the client side


@pytest.mark.spec("R4.18", "R20.1")
@pytest.mark.parametrize("category", descriptions.CATEGORIES)
@given(data=st.data())
def test_a_client_with_the_validators_refuses_exactly_what_the_server_would(
    category: str, data: st.DataObject
) -> None:
    """The client machine, given the robot's validators, refuses locally the very descriptions the
    server refuses, with the same reason and errors; and sends every other."""
    robot = descriptions.Robot(places=["pantry", None, "lounge"], actions=["wave"])
    config = ServerConfig(categories=robot.validators())
    server, _ = machine.step(
        machine.State.new("f", "r"), inputs.Begin(description="{}", event_id=1, now=1), config
    )
    client = cl.ClientState.new("0" * 16, validators=robot.validators())
    status = DynamicEventStatus(
        dynamic_event_seq=1, dynamic_state=DynamicState.WAITING, status="standby", id=1
    )
    client, _ = cl.step(client, cl.StatusReceived(message=status))
    text = json.dumps(data.draw(drawn(category)))
    _, (sent,) = cl.request_next(client, category, text, now=3)
    goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category=category, description=text, id=2)
    decision = machine.accept(server, goal, config)
    if isinstance(decision, outs.Accepted):
        assert isinstance(sent, cl.SendGoal) and sent.goal == goal
    else:
        assert isinstance(sent, cl.Refused)
        assert (sent.rejection.reason, sent.rejection.errors) == (decision.reason, decision.errors)


def test_the_modules_own_example_runs() -> None:
    import doctest

    import dynevent.descriptions

    failed, attempted = doctest.testmod(dynevent.descriptions, raise_on_error=False)
    assert attempted >= 4 and failed == 0


def test_a_robot_knows_its_waypoints_by_name_and_index() -> None:
    robot = descriptions.Robot(places=["pantry", None])
    assert robot.knows("pantry") and robot.knows(0) and robot.knows(1)
    assert not robot.knows("attic") and not robot.knows(2)
    assert descriptions.Robot().knows("anything") and descriptions.Robot().knows(10**9)


@pytest.mark.spec("R4.18")
def test_a_clients_validators_leave_the_servers_own_categories_to_the_server() -> None:
    """A client cannot know the categories a server adds (serve's ``patrol``): a sequence's activity
    of one passes, while an activity of a field category is still checked by its schema."""
    check = descriptions.shape_validators()["sequence"]
    assert check("sequence", [{"category": "patrol", "description": {}}]) == ()
    assert check("sequence", [{"category": "go_to_place", "description": 5.5}]) == (
        '/0/description: 5.5 is not a go_to_place description (a place, {"place": ...} or {"one_of": [...]})',
    )
    assert descriptions.Robot().check("sequence", [{"category": "patrol", "description": {}}]) != ()


@pytest.mark.spec("R4.18")
@pytest.mark.parametrize(
    ("description", "place", "faults"),
    [
        ({"place": "A", "one_of": [5.5]}, "A", ()),  # the {"place"} form, with a key of its own
        ({"place": "attic", "one_of": []}, None, ('/place: "attic" is not a waypoint on this robot\'s map',)),
        ({"place": "A", "one_of": False}, "A", ()),
        ({"waypoint": "A", "one_of": 7}, "A", ()),  # a place (a waypoint object), not a one_of
        ({"waypoint": "B", "place": 1.5}, "B", ()),
    ],
)
def test_a_go_to_place_is_read_by_the_form_it_fits_not_by_its_keys(
    description: Any, place: str | None, faults: tuple[str, ...]
) -> None:
    robot = descriptions.Robot(places=["A", "B"])
    assert robot.check("go_to_place", description) == faults
    if place is not None:
        assert descriptions.read("go_to_place", description).one_of == (descriptions.Place(place),)


def test_numbers_beyond_a_float_are_read_as_infinite() -> None:
    huge = int("1" + "0" * 400)
    assert (
        descriptions.read("go_to_place", {"waypoint": "A", "orientation": -huge}).one_of[0].orientation
        == -math.inf
    )
    action = descriptions.read("perform_action", {"category": "a", "description": 1,
                                                  "unix_millis_action_duration_estimate": huge})  # fmt: skip
    assert isinstance(action, descriptions.PerformAction) and action.duration_estimate == math.inf
    assert descriptions.Robot(places=["A"]).check("go_to_place", huge) == (
        f"/: waypoint {str(huge)[:47]}… is not on this robot's map (its waypoints are 0 to 0)",
    )


def test_without_jsonschema_the_verdict_stands_and_the_line_says_how_to_learn_more() -> None:
    import subprocess
    import sys

    script = (
        "import sys; sys.modules['jsonschema'] = None\n"
        "from dynevent import descriptions\n"
        "from dynevent.descriptions import shapes\n"
        "print(descriptions.Robot().check('go_to_place', {'one_of': ['A', 5.5]}))\n"
        "print(descriptions.Robot().check('go_to_place', {'one_of': ['A']}))\n"
        "try:\n    shapes.require_explanations()\n"
        "except Exception as exc:\n    print(type(exc).__name__, exc)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, check=True
    )
    assert done.stdout.splitlines() == [
        '(\'/: {"one_of": ["A", 5.5]} is not a go_to_place description (a place, {"place": ...} or '
        "{\"one_of\": [...]}) (pip install \\'dynevent[descriptions]\\' to be told where)',)",
        "()",
        "MissingExtra jsonschema is not installed; it says where a refused description goes wrong: "
        "pip install 'dynevent[descriptions]'",
    ]
