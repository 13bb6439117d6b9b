"""Wire mirrors: construction, ranges, defaults, conversion (foundation issue)."""

from __future__ import annotations

import json
import math
import struct
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.errors import DyneventError, InvalidMessage
from dynevent.testing.strategies import hostile_json_values, messages, out_of_range_values, wire_dicts
from dynevent.wire import messages as wire
from dynevent.wire.vocab import DynamicState, EventType, Tier

ALL = wire.MESSAGE_TYPES

# The ROS definitions, field for field (name -> type), as the wire declares them.
ROS_FIELDS: dict[type[wire.WireMessage], dict[str, str]] = {
    wire.Goal: {
        "dynamic_event_seq": "uint32",
        "event_type": "uint32",
        "category": "string",
        "description": "string",
        "id": "uint64",
        "stubborn_period": "float32",
    },
    wire.Result: {"execution_failure": "string", "status": "string", "id": "uint64"},
    wire.Feedback: {"status": "string", "id": "uint64", "logs": "LogEntry[]"},
    wire.LogEntry: {"seq": "uint32", "tier": "string", "unix_millis_time": "int64", "text": "string"},
    wire.Time: {"sec": "int32", "nanosec": "uint32"},
    wire.DynamicEventDescription: {
        "fleet": "string",
        "robot": "string",
        "dynamic_event_seq": "uint32",
        "description": "string",
        "start_time": "Time",
    },
    wire.DynamicEventStatus: {
        "dynamic_event_seq": "uint32",
        "dynamic_state": "uint8",
        "status": "string",
        "id": "uint64",
        "time": "Time",
    },
    wire.DescriptionRequest: {"at_least_one_field": "bool"},
    wire.DescriptionResponse: {
        "running": "bool",
        "status": "string",
        "description": "string",
        "id": "uint64",
    },
}

ROS_DEFAULTS = {
    "uint8": 0,
    "uint32": 0,
    "uint64": 0,
    "int32": 0,
    "int64": 0,
    "float32": 0.0,
    "string": "",
    "bool": False,
}


@pytest.mark.spec("R1.1")
@pytest.mark.parametrize("cls", ALL, ids=lambda cls: cls.__name__)
def test_fields_mirror_ros_definition_in_order(cls: type[wire.WireMessage]) -> None:
    assert cls.wire_types() == ROS_FIELDS[cls]
    assert list(cls.wire_types()) == list(ROS_FIELDS[cls])


@pytest.mark.spec("R1.1")
@pytest.mark.parametrize("cls", ALL, ids=lambda cls: cls.__name__)
def test_defaults_are_ros_defaults(cls: type[wire.WireMessage]) -> None:
    message = cls()
    for name, kind in ROS_FIELDS[cls].items():
        value = getattr(message, name)
        if kind == "Time":
            assert value == wire.Time(sec=0, nanosec=0)
        elif kind.endswith("[]"):
            assert value == ()
        else:
            assert value == ROS_DEFAULTS[kind]
            assert type(value) is type(ROS_DEFAULTS[kind])


@pytest.mark.parametrize("cls", ALL, ids=lambda cls: cls.__name__)
def test_frozen_keyword_only_hashable(cls: type[wire.WireMessage]) -> None:
    message = cls()
    with pytest.raises(attrs.exceptions.FrozenInstanceError):
        message.x = 1  # type: ignore[attr-defined]
    if ROS_FIELDS[cls]:
        with pytest.raises(TypeError):
            cls(0)  # type: ignore[call-arg]
    assert hash(message) == hash(cls())
    assert {message, cls()} == {message}
    assert repr(message).startswith(f"{cls.__name__}(")


def test_goal_repr_is_readable() -> None:
    goal = wire.Goal(dynamic_event_seq=3, event_type=EventType.NEXT, category="go_to_place", id=7)
    assert repr(goal) == (
        "Goal(dynamic_event_seq=3, event_type=1, category='go_to_place', "
        "description='', id=7, stubborn_period=0.0)"
    )


@pytest.mark.spec("R1.2")
def test_unknown_event_type_constructs() -> None:
    assert wire.Goal(event_type=7).event_type == 7
    assert wire.Goal(event_type=2**32 - 1).event_type == 2**32 - 1


def test_enums_are_stored_as_plain_values() -> None:
    goal = wire.Goal(event_type=EventType.CANCEL)
    assert type(goal.event_type) is int
    entry = wire.LogEntry(tier=Tier.WARNING)
    assert type(entry.tier) is str and entry.tier == "warning"
    status = wire.DynamicEventStatus(dynamic_state=DynamicState.RUNNING)
    assert type(status.dynamic_state) is int and status.dynamic_state == 2


@pytest.mark.spec("R1.2")
def test_float32_is_rounded_as_the_wire_carries_it() -> None:
    goal = wire.Goal(stubborn_period=0.1)
    assert goal.stubborn_period == struct.unpack("<f", struct.pack("<f", 0.1))[0]
    assert goal.stubborn_period != 0.1
    assert wire.Goal(stubborn_period=3).stubborn_period == 3.0


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, -0.0, 3.4028234663852886e38, 1e-45])
def test_float32_representable_values_construct(value: float) -> None:
    goal = wire.Goal(stubborn_period=value)
    assert wire.Goal.from_json(goal.to_json()) == goal


@pytest.mark.spec("R1.2")
def test_nan_goals_compare_equal_and_hash_alike() -> None:
    one = wire.Goal(stubborn_period=math.nan)
    other = wire.Goal(stubborn_period=float("nan"))
    assert one == other and hash(one) == hash(other)
    assert one != wire.Goal(stubborn_period=0.0)


@pytest.mark.parametrize(
    ("field", "value", "problem"),
    [
        ("dynamic_event_seq", -1, "out of range for uint32"),
        ("dynamic_event_seq", 2**32, "out of range for uint32"),
        ("id", 2**64, "out of range for uint64"),
        ("id", True, "expected an integer"),
        ("event_type", 1.0, "expected an integer"),
        ("stubborn_period", 1e39, "out of range for float32"),
        ("stubborn_period", "2", "expected a number"),
        ("stubborn_period", False, "expected a number"),
        ("category", "\udc80", "lone surrogate"),
        ("category", "a\x00b", "NUL character at index 1"),
        ("description", b"{}", "expected a string"),
    ],
)
@pytest.mark.spec("R1.2")
def test_goal_refusals_name_class_field_and_value(field: str, value: Any, problem: str) -> None:
    with pytest.raises(InvalidMessage) as caught:
        wire.Goal(**{field: value})
    text = str(caught.value)
    assert text.startswith(f"Goal.{field}: ")
    assert problem in text
    assert repr(value)[:20] in text
    assert caught.value.field == field and caught.value.message_type == "Goal"
    assert isinstance(caught.value, ValueError)


def test_nested_and_array_refusals() -> None:
    with pytest.raises(InvalidMessage, match=r"DynamicEventStatus\.time: expected a Time"):
        wire.DynamicEventStatus(time=(1, 2))  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match=r"Feedback\.logs\[1\]: expected a LogEntry"):
        wire.Feedback(logs=[wire.LogEntry(), {"seq": 1}])  # type: ignore[list-item]
    with pytest.raises(InvalidMessage, match=r"Feedback\.logs: expected a sequence of LogEntry"):
        wire.Feedback(logs="abc")  # type: ignore[arg-type]
    with pytest.raises(InvalidMessage, match=r"DynamicEventStatus\.dynamic_state: out of range for uint8"):
        wire.DynamicEventStatus(dynamic_state=256)
    with pytest.raises(InvalidMessage, match=r"Time\.sec: out of range for int32"):
        wire.Time(sec=2**31)
    with pytest.raises(InvalidMessage, match=r"LogEntry\.unix_millis_time: out of range for int64"):
        wire.LogEntry(unix_millis_time=-(2**63) - 1)
    with pytest.raises(InvalidMessage, match=r"DescriptionRequest\.at_least_one_field: expected a bool"):
        wire.DescriptionRequest(at_least_one_field=1)  # type: ignore[arg-type]


@pytest.mark.spec("R1.3")
def test_from_dict_locates_nested_faults() -> None:
    with pytest.raises(InvalidMessage) as caught:
        wire.Feedback.from_dict({"logs": [{}, {"seq": -4}]})
    assert str(caught.value) == "Feedback.logs[1].seq: out of range for uint32 [0, 4294967295] (got -4)"
    with pytest.raises(
        InvalidMessage, match=r"DynamicEventDescription\.start_time\.nanosec: expected an integer"
    ):
        wire.DynamicEventDescription.from_dict({"start_time": {"nanosec": "5"}})
    with pytest.raises(InvalidMessage, match=r"Goal\.colour: unknown field"):
        wire.Goal.from_dict({"colour": "red"})
    with pytest.raises(InvalidMessage, match=r"Goal: expected a JSON object"):
        wire.Goal.from_dict([1, 2])


@pytest.mark.spec("R1.3")
def test_from_dict_missing_fields_take_ros_defaults() -> None:
    assert wire.Goal.from_dict({"event_type": 3}) == wire.Goal(event_type=3)


@pytest.mark.spec("R1.3")
def test_from_json_refuses_bad_text() -> None:
    for text in ["", "{", '{"id": 1, "id": 2}', b"\xff\xfe", "[" * 10_000, '{"id": ' + "9" * 5000 + "}"]:
        with pytest.raises(InvalidMessage) as caught:
            wire.Goal.from_json(text)
        assert str(caught.value).startswith("Goal: ")


def test_time_helpers() -> None:
    time = wire.Time.from_nanoseconds(12_500_000_000)
    assert time == wire.Time(sec=12, nanosec=500_000_000)
    assert time.nanoseconds == 12_500_000_000
    assert wire.Time(sec=1) < wire.Time(sec=1, nanosec=1)


@pytest.mark.spec("R1.3")
@pytest.mark.parametrize("cls", ALL, ids=lambda cls: cls.__name__)
@given(data=st.data())
def test_round_trip_dict_and_json_is_identity(cls: type[wire.WireMessage], data: st.DataObject) -> None:
    message = data.draw(messages(cls))
    assert cls.from_dict(message.to_dict()) == message
    assert cls.from_json(message.to_json()) == message
    assert cls.from_json(message.to_json().encode()) == message
    assert json.loads(message.to_json()) == json.loads(json.dumps(message.to_dict()))


FIELD_CASES = [(cls, name, kind) for cls in ALL for name, kind in cls.wire_types().items()]


@pytest.mark.spec("R1.2")
@pytest.mark.parametrize(("cls", "name", "kind"), FIELD_CASES, ids=lambda v: getattr(v, "__name__", str(v)))
@given(data=st.data())
def test_every_out_of_range_value_is_refused_naming_the_field(
    cls: type[wire.WireMessage], name: str, kind: str, data: st.DataObject
) -> None:
    value = data.draw(out_of_range_values(kind))
    with pytest.raises(InvalidMessage) as caught:
        cls(**{name: value})
    assert str(caught.value).startswith(f"{cls.__name__}.{name}")
    with pytest.raises(InvalidMessage) as caught:
        cls.from_dict({name: value})
    assert str(caught.value).startswith(f"{cls.__name__}.{name}")


@pytest.mark.spec("R1.3")
@pytest.mark.parametrize("cls", ALL, ids=lambda cls: cls.__name__)
@given(data=st.data())
def test_arbitrary_json_gives_a_message_or_the_one_error(
    cls: type[wire.WireMessage], data: st.DataObject
) -> None:
    value = data.draw(st.one_of(hostile_json_values(), wire_dicts(cls)))
    try:
        message = cls.from_dict(value)
    except InvalidMessage:
        return
    assert isinstance(message, cls)
    assert cls.from_dict(message.to_dict()) == message


@given(text=st.one_of(st.text(max_size=60), st.binary(max_size=60)))
def test_arbitrary_text_gives_a_message_or_the_one_error(text: str | bytes) -> None:
    try:
        wire.Feedback.from_json(text)
    except DyneventError as exc:
        assert isinstance(exc, InvalidMessage)
