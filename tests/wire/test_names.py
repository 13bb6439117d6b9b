"""Tests of dynevent.wire.names: building and parsing the per-robot ROS 2 names."""

from __future__ import annotations

import enum
import string
from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.errors import InvalidName
from dynevent.wire.names import (
    BEGIN_TOPIC,
    MAX_NAME_LENGTH,
    NameKind,
    ParsedName,
    action_name,
    begin_topic,
    build_name,
    description_service,
    parse_name,
    status_topic,
    validate_token,
)

pytestmark = pytest.mark.spec("R1.4")

BUILDERS: dict[NameKind, Callable[[object, object], str]] = {
    NameKind.ACTION: action_name,
    NameKind.BEGIN: begin_topic,
    NameKind.STATUS: status_topic,
    NameKind.DESCRIPTION: description_service,
}

PREFIXES = {
    NameKind.ACTION: "rmf/dynamic_event/command/",
    NameKind.BEGIN: "rmf/dynamic_event/begin/",
    NameKind.STATUS: "rmf/dynamic_event/status/",
    NameKind.DESCRIPTION: "rmf_dynamic_event/description/",
}


def assert_refused(error: pytest.ExceptionInfo[InvalidName], field: str, value: object, problem: str) -> None:
    """The error names the field, shows the value and says the problem."""
    assert error.value.field == field
    assert error.value.value == value
    assert problem in error.value.problem
    message = str(error.value)
    assert message.startswith(f"{field} name " if field in ("fleet", "robot") else f"{field} ")
    assert repr(value)[:60] in message
    assert problem in message


# ---------------------------------------------------------------------------
# Building


def test_builders_write_the_protocol_names() -> None:
    assert action_name("tinyRobot", "tinyRobot1") == "rmf/dynamic_event/command/tinyRobot/tinyRobot1"
    assert begin_topic("tinyRobot", "tinyRobot1") == "rmf/dynamic_event/begin/tinyRobot/tinyRobot1"
    assert status_topic("tinyRobot", "tinyRobot1") == "rmf/dynamic_event/status/tinyRobot/tinyRobot1"
    assert (
        description_service("tinyRobot", "tinyRobot1") == "rmf_dynamic_event/description/tinyRobot/tinyRobot1"
    )


def test_fleet_wide_begin_topic() -> None:
    assert BEGIN_TOPIC == "rmf/dynamic_event/begin"
    assert begin_topic("f", "r").startswith(BEGIN_TOPIC + "/")


@pytest.mark.parametrize("kind", list(NameKind))
def test_build_name_matches_each_builder(kind: NameKind) -> None:
    assert build_name(kind, "f", "r") == BUILDERS[kind]("f", "r")
    assert build_name(kind, "f", "r") == f"{PREFIXES[kind]}f/r"


def test_build_name_takes_the_kind_value() -> None:
    assert build_name("status", "f", "r") == status_topic("f", "r")  # type: ignore[arg-type]


def test_name_kind_is_a_str_enum() -> None:
    assert [str(kind) for kind in NameKind] == ["action", "begin", "status", "description"]
    assert NameKind("begin") is NameKind.BEGIN


@pytest.mark.parametrize(
    "token",
    ["a", "A", "_", "_a", "a_", "a_b_c", "a1", "robot_01", "_1", "Z9_y8"],
)
def test_valid_tokens(token: str) -> None:
    assert validate_token("fleet", token) == token
    assert action_name(token, token) == f"rmf/dynamic_event/command/{token}/{token}"


def test_str_subclass_token_becomes_plain_str() -> None:
    class Fleet(str, enum.Enum):
        TINY = "tinyRobot"

        def __str__(self) -> str:
            return "something else"

    token = validate_token("fleet", Fleet.TINY)
    assert token == "tinyRobot"
    assert type(token) is str
    assert action_name(Fleet.TINY, "r") == "rmf/dynamic_event/command/tinyRobot/r"


REFUSED_TOKENS: list[tuple[object, str]] = [
    ("", "is empty"),
    ("1robot", "starts with a digit"),
    ("0", "starts with a digit"),
    ("a-b", "contains '-' at index 1"),
    ("abc-", "contains '-' at index 3"),
    ("a b", "contains ' ' at index 1"),
    ("a/b", "contains '/' at index 1"),
    ("a.b", "contains '.' at index 1"),
    ("~", "contains '~' at index 0"),
    ("{a}", "contains '{' at index 0"),
    ("robé", "contains 'é' at index 3"),
    ("a\n", "contains '\\n' at index 1"),
    ("a\x00", "contains '\\x00' at index 1"),
    ("٣", "contains '٣' at index 0"),  # a non-ASCII digit is no ASCII letter/digit either
    ("__", "contains a repeated underscore '__' at index 0"),
    ("a__b", "contains a repeated underscore '__' at index 1"),
    ("ab___", "contains a repeated underscore '__' at index 2"),
    (5, "is not a str but int"),
    (None, "is not a str but NoneType"),
    (b"robot", "is not a str but bytes"),
    (1.5, "is not a str but float"),
    (["robot"], "is not a str but list"),
    (True, "is not a str but bool"),
]


@pytest.mark.parametrize(("value", "problem"), REFUSED_TOKENS)
def test_validate_token_refusals(value: object, problem: str) -> None:
    with pytest.raises(InvalidName) as error:
        validate_token("robot", value)
    assert_refused(error, "robot", value, problem)


@pytest.mark.parametrize(("value", "problem"), REFUSED_TOKENS)
@pytest.mark.parametrize("kind", list(NameKind))
def test_builders_refuse_bad_fleet_and_robot(kind: NameKind, value: object, problem: str) -> None:
    with pytest.raises(InvalidName) as error:
        BUILDERS[kind](value, "robot")
    assert_refused(error, "fleet", value, problem)
    with pytest.raises(InvalidName) as error:
        BUILDERS[kind]("fleet", value)
    assert_refused(error, "robot", value, problem)


def test_invalid_name_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="is empty"):
        action_name("", "r")


def test_the_check_order_reports_the_character_before_the_digit() -> None:
    with pytest.raises(InvalidName, match="contains '-' at index 1"):
        validate_token("fleet", "1-")


# ---------------------------------------------------------------------------
# Length


def room(kind: NameKind) -> int:
    """How many characters fleet and robot may share in a ``kind`` name."""
    derived = len("/_action/cancel_goal") if kind is NameKind.ACTION else 0
    return MAX_NAME_LENGTH - 1 - len(PREFIXES[kind]) - 1 - derived


def test_max_name_length_is_rmw_topic_max_name_length() -> None:
    assert MAX_NAME_LENGTH == 247


@pytest.mark.parametrize("kind", list(NameKind))
def test_longest_name_is_accepted(kind: NameKind) -> None:
    robot = "r" * (room(kind) - 1)
    name = build_name(kind, "f", robot)
    assert len("/" + name) + (20 if kind is NameKind.ACTION else 0) == MAX_NAME_LENGTH
    assert parse_name(name) == (kind, "f", robot)


@pytest.mark.parametrize("kind", list(NameKind))
def test_one_character_more_blames_the_robot(kind: NameKind) -> None:
    robot = "r" * room(kind)
    with pytest.raises(InvalidName) as error:
        build_name(kind, "f", robot)
    assert_refused(error, "robot", robot, "characters long")
    assert f"{MAX_NAME_LENGTH + 1} characters long" in error.value.problem
    assert f"above the rmw limit of {MAX_NAME_LENGTH}" in error.value.problem


def test_the_action_limit_counts_its_cancel_goal_service() -> None:
    robot = "r" * (room(NameKind.ACTION))
    assert status_topic("f", robot)
    with pytest.raises(InvalidName, match="'/_action/cancel_goal' service"):
        action_name("f", robot)


@pytest.mark.parametrize("kind", list(NameKind))
def test_a_fleet_too_long_for_any_robot_blames_the_fleet(kind: NameKind) -> None:
    fleet = "f" * room(kind)
    with pytest.raises(InvalidName) as error:
        build_name(kind, fleet, "r")
    assert_refused(error, "fleet", fleet, "characters long")
    fits = "f" * (room(kind) - 1)
    assert build_name(kind, fits, "r")
    with pytest.raises(InvalidName) as error:
        build_name(kind, fits, "rr")
    assert_refused(error, "robot", "rr", "characters long")


# ---------------------------------------------------------------------------
# Parsing


@pytest.mark.parametrize("kind", list(NameKind))
def test_parse_name_of_each_kind(kind: NameKind) -> None:
    name = BUILDERS[kind]("tinyRobot", "tinyRobot1")
    parsed = parse_name(name)
    assert parsed == ParsedName(kind, "tinyRobot", "tinyRobot1")
    assert parsed.kind is kind
    assert (parsed.fleet, parsed.robot) == ("tinyRobot", "tinyRobot1")
    assert parse_name("/" + name) == parsed


@pytest.mark.parametrize(
    ("name", "problem"),
    [
        ("rmf/dynamic_event/begin", "fleet-wide begin topic"),
        ("/rmf/dynamic_event/begin", "fleet-wide begin topic"),
        ("", "is none of the Dynamic Event names"),
        ("/", "is none of the Dynamic Event names"),
        ("rmf/dynamic_event/command", "is none of the Dynamic Event names"),
        ("rmf/dynamic_event/cancel/f/r", "is none of the Dynamic Event names"),
        ("rmf_dynamic_event/command/f/r", "is none of the Dynamic Event names"),
        ("rmf/dynamic_event/description/f/r", "is none of the Dynamic Event names"),
        ("//rmf/dynamic_event/command/f/r", "is none of the Dynamic Event names"),
        ("rmf/dynamic_event/command/f/r/", "has 3 tokens after 'rmf/dynamic_event/command/'"),
        ("rmf/dynamic_event/status/f/r/x", "has 3 tokens after 'rmf/dynamic_event/status/'"),
        ("rmf/dynamic_event/status/f", "has 1 tokens after 'rmf/dynamic_event/status/'"),
        ("rmf/dynamic_event/status//f/r", "has 3 tokens after 'rmf/dynamic_event/status/'"),
        ("rostopic:///rmf/dynamic_event/status/f/r", "is none of the Dynamic Event names"),
        (7, "is not a str but int"),
        (None, "is not a str but NoneType"),
        (b"rmf/dynamic_event/status/f/r", "is not a str but bytes"),
    ],
)
def test_parse_name_refuses_other_names(name: object, problem: str) -> None:
    with pytest.raises(InvalidName) as error:
        parse_name(name)
    assert_refused(error, "name", name, problem)


@pytest.mark.parametrize(
    ("name", "field", "value", "problem"),
    [
        ("rmf/dynamic_event/command/1f/r", "fleet", "1f", "starts with a digit"),
        ("rmf/dynamic_event/begin/f/r-1", "robot", "r-1", "contains '-' at index 1"),
        ("rmf/dynamic_event/status//r", "fleet", "", "is empty"),
        ("rmf/dynamic_event/status/f/", "robot", "", "is empty"),
        ("rmf_dynamic_event/description/a__b/r", "fleet", "a__b", "repeated underscore"),
        ("/rmf/dynamic_event/command/f/r~", "robot", "r~", "contains '~' at index 1"),
    ],
)
def test_parse_name_reports_bad_tokens_by_field(name: str, field: str, value: str, problem: str) -> None:
    with pytest.raises(InvalidName) as error:
        parse_name(name)
    assert_refused(error, field, value, problem)


def test_parse_name_refuses_a_name_too_long() -> None:
    robot = "r" * room(NameKind.STATUS)
    with pytest.raises(InvalidName) as error:
        parse_name(f"rmf/dynamic_event/status/f/{robot}")
    assert_refused(error, "robot", robot, "characters long")


# ---------------------------------------------------------------------------
# Properties

ALNUM = string.ascii_letters + string.digits
words = st.text(alphabet=ALNUM, min_size=1, max_size=6)
tokens = st.one_of(
    st.just("_"),
    st.builds(
        lambda lead, parts, trail: ("_" if lead else "") + "_".join(parts) + ("_" if trail else ""),
        st.booleans(),
        st.lists(words, min_size=1, max_size=4),
        st.booleans(),
    ).filter(lambda token: token[0] not in string.digits),
)


def is_token(text: str) -> bool:
    """The token rules, written independently of dynevent.wire.names."""
    return (
        text != ""
        and all(c in ALNUM or c == "_" for c in text)
        and text[0] not in string.digits
        and "__" not in text
    )


@given(st.sampled_from(list(NameKind)), tokens, tokens, st.booleans())
def test_names_round_trip_through_parse_name(kind: NameKind, fleet: str, robot: str, rooted: bool) -> None:
    name = build_name(kind, fleet, robot)
    assert parse_name("/" + name if rooted else name) == (kind, fleet, robot)


@given(tokens)
def test_generated_tokens_follow_the_rules(token: str) -> None:
    assert is_token(token)
    assert validate_token("robot", token) == token


@given(st.one_of(st.text(), st.text(alphabet=ALNUM + "_-/ ", max_size=8), tokens))
def test_validate_token_agrees_with_the_rules(text: str) -> None:
    if is_token(text):
        assert validate_token("fleet", text) == text
    else:
        with pytest.raises(InvalidName) as error:
            validate_token("fleet", text)
        assert error.value.field == "fleet"
        assert error.value.value == text


anything = st.one_of(
    st.text(),
    st.none(),
    st.integers(),
    st.floats(),
    st.binary(),
    st.booleans(),
    st.lists(st.text(), max_size=2),
    tokens,
)


@given(st.sampled_from(list(NameKind)), anything, anything)
def test_builders_return_a_name_or_raise_invalid_name(kind: NameKind, fleet: object, robot: object) -> None:
    try:
        name = build_name(kind, fleet, robot)
    except InvalidName as error:
        assert error.field in ("fleet", "robot")
    else:
        assert parse_name(name) == (kind, fleet, robot)


near_names = st.builds(
    lambda root, prefix, tail: root + prefix + tail,
    st.sampled_from(["", "/", "//"]),
    st.sampled_from([*PREFIXES.values(), "rmf/dynamic_event/", BEGIN_TOPIC, ""]),
    st.text(alphabet=ALNUM + "_/-~", max_size=12),
)


@given(st.one_of(st.text(), near_names))
def test_any_text_is_a_name_or_invalid_name(text: str) -> None:
    try:
        parsed = parse_name(text)
    except InvalidName as error:
        assert error.field in ("name", "fleet", "robot")
    else:
        assert build_name(parsed.kind, parsed.fleet, parsed.robot) == text.removeprefix("/")


@given(
    st.integers(min_value=1, max_value=260),
    st.integers(min_value=1, max_value=260),
    st.sampled_from(["a", "_", "9", "é", ""]),
)
def test_validate_robot_refuses_exactly_what_building_every_name_refuses(
    fleet_length: int, robot_length: int, odd: str
) -> None:
    from dynevent.wire.names import NameKind, build_name, validate_robot

    fleet, robot = "f" * fleet_length, "r" * (robot_length - 1) + odd

    def outcome(check: Callable[[], object]) -> str:
        try:
            check()
        except InvalidName as exc:
            return str(exc)
        return "ok"

    built = next(
        (text for kind in NameKind if (text := outcome(lambda k=kind: build_name(k, fleet, robot))) != "ok"),
        "ok",
    )
    assert outcome(lambda: validate_robot(fleet, robot)) == built
