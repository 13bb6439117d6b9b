"""Tests of dynevent.wire.description: the ``dynamic_event`` event description."""

from __future__ import annotations

import json
import math
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.errors import InvalidDescription
from dynevent.wire._json import MAX_DEPTH, dumps
from dynevent.wire.description import (
    DEFAULT_CATEGORY,
    MAX_DESCRIPTION_BYTES,
    EventDescription,
    EventSpec,
    JsonValue,
)

pytestmark = pytest.mark.spec("R1.5")

FULL = (
    '{"category":"patrol","detail":"patrol the lobby",'
    '"estimate":{"category":"go_to_place","description":{"waypoint":"lobby"},"eta":30},'
    '"required":[{"category":"perform_action","description":{"category":"scan"}},'
    '{"description":null,"category":"go_to_place"}],'
    '"parameters":{"rounds":3,"zones":["a","b"]},"custom":{"nested":[1,2.5,true,null]}}'
)


def refused(text: str | bytes, path: str, problem: str) -> InvalidDescription:
    """Assert that ``text`` is refused at ``path`` with ``problem``; return the error."""
    with pytest.raises(InvalidDescription) as error:
        EventDescription.from_json(text)
    assert error.value.path == path
    assert problem in error.value.problem
    assert f"at {path}: " in str(error.value)
    return error.value


# ---------------------------------------------------------------------------
# Reading


def test_empty_object_has_every_default() -> None:
    description = EventDescription.from_json("{}")
    assert description.estimate is None
    assert description.required == ()
    assert description.category == DEFAULT_CATEGORY == "dynamic_event"
    assert description.detail is None
    assert description.parameters is None
    assert description.extra == ()
    assert description.to_json() == "{}"
    assert description.to_dict() == {}
    assert description == EventDescription()


def test_full_description_fields() -> None:
    description = EventDescription.from_json(FULL)
    assert description.category == "patrol"
    assert description.detail == "patrol the lobby"
    assert description.estimate == EventSpec("go_to_place", {"waypoint": "lobby"}, {"eta": 30})
    assert description.estimate.category == "go_to_place"
    assert description.estimate.description is not None
    assert description.estimate.description.value == {"waypoint": "lobby"}
    assert dict(description.estimate.extra) == {"eta": JsonValue.of(30)}
    assert [spec.category for spec in description.required] == ["perform_action", "go_to_place"]
    assert description.required[1].description == JsonValue.of(None)
    assert description.parameters is not None
    assert description.parameters.value == {"rounds": 3, "zones": ["a", "b"]}
    assert description.extra == (("custom", JsonValue('{"nested":[1,2.5,true,null]}')),)


def test_full_description_round_trips_exactly() -> None:
    description = EventDescription.from_json(FULL)
    assert description.to_json() == FULL
    assert description.to_dict() == json.loads(FULL)
    assert list(description.to_dict()) == list(json.loads(FULL))
    assert EventDescription.from_json(description.to_json()) == description
    assert EventDescription.from_dict(description.to_dict()) == description


def test_whitespace_and_escapes_are_compacted() -> None:
    text = '{ "detail" : "caf\\u00e9 \\"x\\"",\n "parameters" : [ 1 , 2 ] }'
    description = EventDescription.from_json(text)
    assert description.detail == 'café "x"'
    assert description.to_json() == dumps(json.loads(text))


def test_bytes_and_bytearray_are_read_as_utf8() -> None:
    text = '{"detail":"caf\u00e9"}'
    assert EventDescription.from_json(text.encode()).detail == "caf\u00e9"
    assert EventDescription.from_json(bytearray(text.encode())).to_json() == text


def test_absent_fields_stay_absent_and_present_ones_present() -> None:
    assert EventDescription.from_json('{"required":[]}').to_json() == '{"required":[]}'
    assert EventDescription.from_json('{"required":[]}') != EventDescription.from_json("{}")
    assert EventDescription.from_json('{"parameters":null}').to_json() == '{"parameters":null}'
    assert EventDescription.from_json('{"parameters":null}').parameters == JsonValue("null")
    assert EventDescription.from_json('{"category":"dynamic_event"}').to_json() == (
        '{"category":"dynamic_event"}'
    )
    assert EventDescription.from_json('{"detail":""}').to_json() == '{"detail":""}'
    spec = '{"estimate":{"category":"c"}}'
    assert EventDescription.from_json(spec).to_json() == spec


def test_key_order_is_kept_at_every_level() -> None:
    text = '{"z":1,"parameters":{"b":1,"a":2},"estimate":{"x":0,"description":1,"category":"c"},"a":2}'
    description = EventDescription.from_json(text)
    assert description.to_json() == text
    assert [key for key, _ in description.extra] == ["z", "a"]


def test_key_order_counts_in_equality() -> None:
    first = EventDescription.from_json('{"detail":"d","category":"c"}')
    second = EventDescription.from_json('{"category":"c","detail":"d"}')
    assert first != second
    assert second == EventDescription(category="c", detail="d")
    assert hash(second) == hash(EventDescription(category="c", detail="d"))


def test_values_are_hashable_and_equal_by_text() -> None:
    first = EventDescription.from_json(FULL)
    second = EventDescription.from_json(FULL.encode())
    assert first == second
    assert hash(first) == hash(second)
    assert len({first, second}) == 1
    assert JsonValue.of(1) != JsonValue.of(1.0)


def test_parsed_values_are_fresh_copies() -> None:
    description = EventDescription.from_json(FULL)
    assert description.parameters is not None
    copy = description.parameters.value
    copy["rounds"] = 99
    assert description.parameters.value["rounds"] == 3
    as_dict = description.to_dict()
    as_dict["custom"]["nested"].append(5)
    assert description.to_json() == FULL


def test_descriptions_are_frozen() -> None:
    description = EventDescription.from_json(FULL)
    with pytest.raises(attrs.exceptions.FrozenInstanceError):
        description.detail = "x"  # type: ignore[misc]


def test_non_finite_numbers_are_kept() -> None:
    description = EventDescription.from_json('{"parameters":[NaN,Infinity,-Infinity,-0.0]}')
    assert description.to_json() == '{"parameters":[NaN,Infinity,-Infinity,-0.0]}'
    assert description.parameters is not None
    assert math.isnan(description.parameters.value[0])


# ---------------------------------------------------------------------------
# Refusals of text


@pytest.mark.parametrize(
    ("text", "path", "problem"),
    [
        ("[]", "$", "expected a JSON object, got array"),
        ('"x"', "$", 'expected a JSON object, got "x"'),
        ("5", "$", "expected a JSON object, got 5"),
        ("null", "$", "expected a JSON object, got null"),
        ("", "$", "not valid JSON"),
        ("{", "$", "not valid JSON"),
        ("{} {}", "$", "not valid JSON"),
        ('{"a":1,"a":2}', "$", "duplicate key 'a'"),
        ("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1), "$", f"nested deeper than {MAX_DEPTH} levels"),
        ('{"estimate":[]}', "$.estimate", 'expected an object with "category" (string)'),
        ('{"estimate":null}', "$.estimate", 'and optional "description", got null'),
        ('{"estimate":{}}', "$.estimate", 'got an object without "category"'),
        ('{"estimate":{"description":{}}}', "$.estimate", 'got an object without "category"'),
        ('{"estimate":{"category":5}}', "$.estimate.category", "expected a string, got 5"),
        ('{"estimate":{"category":null}}', "$.estimate.category", "expected a string, got null"),
        ('{"required":{}}', "$.required", "expected an array of events, got object"),
        ('{"required":null}', "$.required", "expected an array of events, got null"),
        ('{"required":[{"category":"a"},5]}', "$.required[1]", "got 5"),
        (
            '{"required":[{"category":"a"},{"category":5}]}',
            "$.required[1].category",
            "expected a string, got 5",
        ),
        ('{"required":[{}]}', "$.required[0]", 'got an object without "category"'),
        ('{"category":5}', "$.category", "expected a string, got 5"),
        ('{"category":["a"]}', "$.category", "expected a string, got array"),
        ('{"category":null}', "$.category", "expected a string, got null"),
        ('{"detail":false}', "$.detail", "expected a string, got false"),
        ('{"detail":null}', "$.detail", "expected a string, got null"),
        ('{"detail":{"a":1}}', "$.detail", "expected a string, got object"),
        ('{"a":"\\ud800"}', "$.a", "lone surrogate U+D800 at index 0"),
        ('{"parameters":{"k":["x\\udfff"]}}', "$.parameters.k[0]", "lone surrogate U+DFFF"),
        ('{"\\ud800":1}', "$", "lone surrogate U+D800"),
        ('{"detail":"\\ud800"}', "$.detail", "lone surrogate"),
        ('{"estimate":{"category":"\\udc00"}}', "$.estimate.category", "lone surrogate"),
        ('{"odd key":{"x":"\\ud800"}}', '$["odd key"].x', "lone surrogate"),
    ],
)
def test_refusals_are_located(text: str, path: str, problem: str) -> None:
    refused(text, path, problem)


def test_long_values_are_cut_in_the_message() -> None:
    error = refused('{"detail":' + "1" * 100 + "}", "$.detail", "expected a string, got 1111")
    assert "..." in error.problem
    assert len(error.problem) < 80


def test_invalid_utf8_bytes_are_refused_at_the_root() -> None:
    refused(b'{"detail":"\xff"}', "$", "not UTF-8 text")


@pytest.mark.parametrize("value", [5, None, 1.5, ["{}"], {"a": 1}])
def test_from_json_refuses_what_is_not_text(value: object) -> None:
    with pytest.raises(InvalidDescription) as error:
        EventDescription.from_json(value)  # type: ignore[arg-type]
    assert error.value.path == "$"
    assert "expected JSON text (str or bytes)" in error.value.problem


def test_the_size_limit_counts_utf8_bytes_before_parsing() -> None:
    assert MAX_DESCRIPTION_BYTES == 1_000_000
    padding = "x" * (MAX_DESCRIPTION_BYTES - len('{"detail":""}'))
    at_limit = '{"detail":"' + padding + '"}'
    assert len(at_limit.encode()) == MAX_DESCRIPTION_BYTES
    assert EventDescription.from_json(at_limit).detail == padding
    refused(at_limit + " ", "$", "description is 1000001 bytes, above the limit of 1000000")
    refused(at_limit.encode() + b" ", "$", "description is 1000001 bytes, above the limit of 1000000")
    # 2 bytes per character: refused though it has fewer characters than the limit
    wide = '{"detail":"' + "\u00e9" * (MAX_DESCRIPTION_BYTES // 2) + '"}'
    assert len(wide) < MAX_DESCRIPTION_BYTES
    refused(wide, "$", f"description is {len(wide.encode())} bytes, above the limit")
    # not even JSON: the size is checked first
    refused("[" * (MAX_DESCRIPTION_BYTES + 1), "$", "above the limit of 1000000")


def test_nesting_is_limited_from_the_top_level_object() -> None:
    inner = MAX_DEPTH - 1
    deepest = '{"parameters":' + "[" * inner + "]" * inner + "}"
    assert EventDescription.from_json(deepest).to_json() == deepest
    too_deep = '{"parameters":' + "[" * (inner + 1) + "]" * (inner + 1) + "}"
    refused(too_deep, "$", f"nested deeper than {MAX_DEPTH} levels")


# ---------------------------------------------------------------------------
# from_dict


def nested(levels: int) -> Any:
    value: Any = []
    for _ in range(levels - 1):
        value = [value]
    return value


@pytest.mark.parametrize(
    ("obj", "path", "problem"),
    [
        ([], "$", "expected a JSON object, got array"),
        ((), "$", "expected a JSON object, got array"),
        ({1: "a"}, "$", "object key 1 is not a string"),
        ({"parameters": {1: 2}}, "$.parameters", "object key 1 is not a string"),
        ({"parameters": {1, 2}}, "$.parameters", "expected a JSON value, got a Python set"),
        ({"x": [b"raw"]}, "$.x[0]", "expected a JSON value, got a Python bytes"),
        ({"x": object()}, "$.x", "got a Python object"),
        ({"estimate": {"category": "c", "description": {"d": {1}}}}, "$.estimate.description.d", "set"),
        ({"required": [{"category": "c", "extra": [1j]}]}, "$.required[0].extra[0]", "complex"),
        ({"parameters": nested(MAX_DEPTH)}, "$.parameters" + "[0]" * (MAX_DEPTH - 2), "nested deeper"),
        ({"estimate": {"category": "c", "description": nested(MAX_DEPTH - 1)}}, "$.estimate", "nested"),
        ({"parameters": 10**5000}, "$.parameters", "integer has too many digits to write"),
        ({"detail": 10**5000}, "$.detail", "expected a string, got an integer too long to write"),
    ],
)
def test_from_dict_refuses_what_is_not_json(obj: object, path: str, problem: str) -> None:
    with pytest.raises(InvalidDescription) as error:
        EventDescription.from_dict(obj)
    assert error.value.path.startswith(path)
    assert problem in error.value.problem


def test_from_dict_accepts_the_deepest_value() -> None:
    description = EventDescription.from_dict({"parameters": nested(MAX_DEPTH - 1)})
    assert description.to_json() == '{"parameters":' + "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1) + "}"


def test_from_dict_takes_tuples_as_arrays() -> None:
    description = EventDescription.from_dict({"parameters": (1, (2,)), "required": ({"category": "c"},)})
    assert description.to_dict() == {"parameters": [1, [2]], "required": [{"category": "c"}]}


def test_a_cycle_is_refused_not_a_recursion_error() -> None:
    loop: list[object] = []
    loop.append(loop)
    with pytest.raises(InvalidDescription, match="nested deeper"):
        EventDescription.from_dict({"parameters": loop})


def test_from_dict_does_not_keep_references_to_its_input() -> None:
    obj: dict[str, Any] = {"parameters": {"a": [1]}}
    description = EventDescription.from_dict(obj)
    obj["parameters"]["a"].append(2)
    assert description.to_dict() == {"parameters": {"a": [1]}}


# ---------------------------------------------------------------------------
# Construction


def test_construct_with_plain_values() -> None:
    description = EventDescription(
        estimate={"category": "go_to_place", "description": {"waypoint": "a"}},
        required=[EventSpec("perform_action"), {"category": "clean", "zone": 1}],
        category="patrol",
        detail="round",
        parameters={"rounds": 2},
        extra={"custom": [1, 2]},
    )
    assert description.to_json() == (
        '{"estimate":{"category":"go_to_place","description":{"waypoint":"a"}},'
        '"required":[{"category":"perform_action"},{"category":"clean","zone":1}],'
        '"category":"patrol","detail":"round","parameters":{"rounds":2},"custom":[1,2]}'
    )
    assert EventDescription.from_json(description.to_json()) == description


def test_evolve_keeps_the_key_order_of_what_is_left() -> None:
    description = EventDescription.from_json('{"z":1,"detail":"d","estimate":{"category":"c"}}')
    assert attrs.evolve(description, detail=None).to_json() == '{"z":1,"estimate":{"category":"c"}}'
    evolved = attrs.evolve(description, detail=None, category="k")
    assert evolved.to_json() == '{"z":1,"estimate":{"category":"c"},"category":"k"}'
    assert evolved == EventDescription.from_json(evolved.to_json())


def test_extra_as_pairs_or_mapping() -> None:
    from_pairs = EventDescription(extra=(("a", 1), ("b", JsonValue("[2]"))))
    from_mapping = EventDescription(extra={"a": 1, "b": [2]})
    assert from_pairs == from_mapping
    assert from_pairs.to_json() == '{"a":1,"b":[2]}'


def test_explicit_key_order() -> None:
    description = EventDescription(detail="d", extra={"a": 1}, key_order=("a", "detail"))
    assert description.to_json() == '{"a":1,"detail":"d"}'
    assert EventDescription(detail="d", extra={"a": 1}, key_order=("detail", "a")) == EventDescription(
        detail="d", extra={"a": 1}
    )


def test_str_subclasses_become_plain_str() -> None:
    class Text(str):
        pass

    description = EventDescription(category=Text("c"), detail=Text("d"), estimate=EventSpec(Text("e")))
    assert type(description.category) is str
    assert type(description.detail) is str
    assert description.estimate is not None
    assert type(description.estimate.category) is str


@pytest.mark.parametrize(
    ("arguments", "path", "problem"),
    [
        ({"category": 5}, "$.category", "expected a string, got 5"),
        ({"detail": [1]}, "$.detail", "expected a string, got array"),
        ({"detail": "\ud800"}, "$.detail", "lone surrogate"),
        ({"estimate": 5}, "$.estimate", 'expected an object with "category"'),
        ({"estimate": {}}, "$.estimate", 'without "category"'),
        ({"required": 5}, "$.required", "expected an array of events, got 5"),
        ({"required": [5]}, "$.required[0]", 'expected an object with "category"'),
        ({"parameters": {1, 2}}, "$", "got a Python set"),
        ({"extra": {"detail": "x"}}, "$.detail", "'detail' is a known field"),
        ({"extra": {"estimate": 1}}, "$.estimate", "'estimate' is a known field"),
        ({"extra": (("a", 1), ("a", 2))}, "$", "unknown field 'a' is given twice"),
        ({"extra": (("a", 1, 2),)}, "$", "is not a (str, value) pair"),
        ({"extra": {1: 2}}, "$", "object key 1 is not a string"),
        ({"extra": 5}, "$", "expected the unknown fields as a mapping"),
        ({"extra": {"a": {3}}}, "$.a", "got a Python set"),
        ({"key_order": "ab"}, "$", "expected the key order as strings"),
        ({"key_order": (1,)}, "$", "expected the key order as strings"),
        ({"parameters": JsonValue.of(nested(MAX_DEPTH))}, "$.parameters", "nested deeper"),
        ({"extra": {"x": JsonValue.of(nested(MAX_DEPTH))}}, "$.x", "nested deeper"),
        (
            {"estimate": EventSpec("c", JsonValue.of(nested(MAX_DEPTH - 1)))},
            "$.estimate",
            "nested deeper",
        ),
        (
            {"required": [EventSpec("c", JsonValue.of(nested(MAX_DEPTH - 2)))]},
            "$.required[0]",
            "nested deeper",
        ),
    ],
)
def test_construction_refusals(arguments: dict[str, Any], path: str, problem: str) -> None:
    with pytest.raises(InvalidDescription) as error:
        EventDescription(**arguments)
    assert error.value.path == path
    assert problem in error.value.problem


def test_deepest_constructed_values_round_trip() -> None:
    for description in (
        EventDescription(parameters=JsonValue.of(nested(MAX_DEPTH - 1))),
        EventDescription(estimate=EventSpec("c", JsonValue.of(nested(MAX_DEPTH - 2)))),
        EventDescription(required=[EventSpec("c", JsonValue.of(nested(MAX_DEPTH - 3)))]),
    ):
        assert EventDescription.from_json(description.to_json()) == description


# ---------------------------------------------------------------------------
# EventSpec and JsonValue


def test_event_spec_round_trip() -> None:
    spec = EventSpec.from_dict({"description": {"a": 1}, "category": "c", "x": None})
    assert spec.to_json() == '{"description":{"a":1},"category":"c","x":null}'
    assert spec.to_dict() == {"description": {"a": 1}, "category": "c", "x": None}
    assert spec.nesting == 2
    assert spec == EventSpec.from_dict(spec.to_dict())


@pytest.mark.parametrize(
    ("obj", "path", "problem"),
    [
        ([], "$", 'expected an object with "category" (string) and optional "description", got array'),
        ({}, "$", 'got an object without "category"'),
        ({"category": 1.5}, "$.category", "expected a string, got 1.5"),
        ({"category": "c", "description": {1}}, "$.description", "got a Python set"),
    ],
)
def test_event_spec_from_dict_refusals(obj: object, path: str, problem: str) -> None:
    with pytest.raises(InvalidDescription) as error:
        EventSpec.from_dict(obj)
    assert error.value.path == path
    assert problem in error.value.problem


@pytest.mark.parametrize(
    ("arguments", "path", "problem"),
    [
        ({"category": None}, "$.category", "expected a string, got null"),
        ({"category": "c", "extra": {"category": "x"}}, "$.category", "'category' is a known field"),
        ({"category": "c", "extra": {"description": 1}}, "$.description", "is a known field"),
        ({"category": "c", "description": JsonValue.of(nested(MAX_DEPTH))}, "$", "nested deeper"),
    ],
)
def test_event_spec_construction_refusals(arguments: dict[str, Any], path: str, problem: str) -> None:
    with pytest.raises(InvalidDescription) as error:
        EventSpec(**arguments)
    assert error.value.path == path
    assert problem in error.value.problem


def test_json_value_from_text_is_compacted() -> None:
    value = JsonValue('{ "b" : [1, 2],\n "a" : null }')
    assert value.text == '{"b":[1,2],"a":null}'
    assert value == JsonValue.of({"b": [1, 2], "a": None})
    assert value.value == {"b": [1, 2], "a": None}
    assert value.nesting == 2
    assert JsonValue.of(value) is value
    assert JsonValue.of("x").nesting == 0


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("", "not valid JSON"),
        ("{'a': 1}", "not valid JSON"),
        ('{"a":1,"a":1}', "duplicate key"),
        ('"\\ud800"', "lone surrogate"),
        (b"1", "expected JSON text, got a Python bytes"),
        (None, "expected JSON text, got null"),
    ],
)
def test_json_value_refusals(text: object, problem: str) -> None:
    with pytest.raises(InvalidDescription) as error:
        JsonValue(text)  # type: ignore[arg-type]
    assert error.value.path == "$"
    assert problem in error.value.problem


# ---------------------------------------------------------------------------
# Properties

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(allow_nan=False),
    st.text(max_size=8),
)
json_values = st.recursive(
    scalars,
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.dictionaries(st.text(max_size=6), children, max_size=4),
    ),
    max_leaves=12,
)


@st.composite
def json_objects(draw: st.DrawFn, known: tuple[str, ...], values: dict[str, st.SearchStrategy[Any]]) -> Any:
    """A JSON object with some known keys, some unknown ones, in any order."""
    obj: dict[str, Any] = {}
    for key in known:
        if draw(st.booleans()):
            obj[key] = draw(values[key])
    unknown = draw(st.dictionaries(st.text(max_size=6), json_values, max_size=3))
    obj.update((key, value) for key, value in unknown.items() if key not in known)
    keys = draw(st.permutations(list(obj)))
    return {key: obj[key] for key in keys}


specs = json_objects(
    ("category", "description"), {"category": st.text(max_size=8), "description": json_values}
)
maybe_specs = st.one_of(
    specs,
    json_objects(("category", "description"), {"category": json_values, "description": json_values}),
    json_values,
)
descriptions = json_objects(
    ("estimate", "required", "category", "detail", "parameters"),
    {
        "estimate": st.one_of(specs, maybe_specs),
        "required": st.one_of(st.lists(specs, max_size=3), st.lists(maybe_specs, max_size=3), json_values),
        "category": st.one_of(st.text(max_size=8), json_values),
        "detail": st.one_of(st.text(max_size=8), json_values),
        "parameters": json_values,
    },
)


def is_spec(value: Any) -> bool:
    return isinstance(value, dict) and isinstance(value.get("category"), str)


def is_valid(obj: dict[str, Any]) -> bool:
    """The reading rules, written independently of dynevent.wire.description."""
    return (
        ("estimate" not in obj or is_spec(obj["estimate"]))
        and (
            "required" not in obj
            or (isinstance(obj["required"], list) and all(map(is_spec, obj["required"])))
        )
        and ("category" not in obj or isinstance(obj["category"], str))
        and ("detail" not in obj or isinstance(obj["detail"], str))
    )


@given(descriptions)
def test_json_objects_round_trip_exactly_or_are_refused(obj: dict[str, Any]) -> None:
    text = json.dumps(obj, ensure_ascii=False)
    try:
        description = EventDescription.from_json(text)
    except InvalidDescription as error:
        assert not is_valid(obj), error
        return
    assert is_valid(obj)
    assert json.loads(description.to_json()) == obj
    assert description.to_json() == dumps(obj)
    assert list(description.to_dict()) == list(obj)
    assert description.to_dict() == obj
    assert EventDescription.from_dict(obj) == description
    assert EventDescription.from_json(description.to_json()) == description
    assert description.category == obj.get("category", DEFAULT_CATEGORY)
    assert len(description.required) == len(obj.get("required", []))


@given(descriptions, descriptions)
def test_equality_is_equality_of_text(first: dict[str, Any], second: dict[str, Any]) -> None:
    try:
        a = EventDescription.from_dict(first)
        b = EventDescription.from_dict(second)
    except InvalidDescription:
        return
    assert (a == b) == (a.to_json() == b.to_json())
    if a == b:
        assert hash(a) == hash(b)


@given(descriptions)
def test_constructing_from_the_fields_gives_the_same_value(obj: dict[str, Any]) -> None:
    try:
        description = EventDescription.from_dict(obj)
    except InvalidDescription:
        return
    rebuilt = EventDescription(
        estimate=description.estimate,
        required=obj.get("required"),
        category=obj.get("category"),
        detail=description.detail,
        parameters=description.parameters,
        extra=description.extra,
        key_order=tuple(obj),
    )
    assert rebuilt == description


@given(st.one_of(st.text(), st.binary(), st.text(alphabet='{}[]":,0123456789.eE-+ \\nultrfasu', max_size=30)))
def test_any_text_is_a_description_or_invalid_description(text: str | bytes) -> None:
    try:
        description = EventDescription.from_json(text)
    except InvalidDescription as error:
        assert error.path.startswith("$")
    else:
        assert EventDescription.from_json(description.to_json()) == description


python_values = st.recursive(
    st.one_of(
        scalars,
        st.floats(),
        st.binary(max_size=3),
        st.complex_numbers(),
        st.sets(st.integers(), max_size=2),
        st.sampled_from(["\ud800", "a\udfff"]),
    ),
    lambda children: st.one_of(
        st.lists(children, max_size=3),
        st.tuples(children),
        st.dictionaries(st.one_of(st.text(max_size=3), st.integers(), st.none()), children, max_size=3),
    ),
    max_leaves=10,
)


@given(
    st.one_of(python_values, st.dictionaries(st.sampled_from(["estimate", "required", "x"]), python_values))
)
def test_any_python_value_is_a_description_or_invalid_description(obj: object) -> None:
    try:
        description = EventDescription.from_dict(obj)
    except InvalidDescription as error:
        assert error.path.startswith("$")
    else:
        assert EventDescription.from_json(description.to_json()) == description
