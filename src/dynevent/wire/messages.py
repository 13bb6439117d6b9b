"""Frozen mirrors of every Dynamic Event wire message, checked to the wire's ranges.

Each class mirrors one ROS definition field for field, with the same names and
the same defaults (a default-initialized ROS message equals ``Cls()``).  Values
are checked when a message is built, so a message that exists can be put on the
wire as it is:

===============  ==========================================================
wire type        accepted Python value
===============  ==========================================================
``uint8/32/64``  ``int`` (not ``bool``) in ``[0, 2**N - 1]``
``int32/64``     ``int`` (not ``bool``) in ``[-2**(N-1), 2**(N-1) - 1]``
``float32``      ``int`` or ``float`` (not ``bool``); stored rounded to the
                 nearest float32, as the wire carries it.  NaN and the
                 infinities are legal; all NaNs compare equal to each
                 other (messages holding NaN are equal and hash alike)
``string``       ``str`` that is valid Unicode (no lone surrogates, so it
                 can be UTF-8 encoded) and holds no NUL character
``bool``         ``bool``
``T[]``          any iterable of ``T``, stored as a tuple
===============  ==========================================================

Enum members (:class:`~dynevent.wire.vocab.EventType`, :class:`~dynevent.wire.vocab.Tier`,
...) are accepted and stored as their plain ``int``/``str`` value.  A value
outside its range raises :class:`~dynevent.errors.InvalidMessage`, naming the
class, the field and the value.

Every message converts losslessly to a dict with the ROS field names (what a
JSON bridge such as rosbridge carries) and to JSON text, and back.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeVar

import attrs

from dynevent.errors import InvalidMessage, MalformedMessage
from dynevent.wire import _json
from dynevent.wire._fields import (
    SECOND,
    WIRE_KEY,
    boolean_field,
    f32,
    fast_init,
    i32,
    i64,
    message,
    sequence,
    string,
    u8,
    u32,
    u64,
)

__all__ = [
    "MESSAGE_TYPES",
    "DescriptionRequest",
    "DescriptionResponse",
    "DynamicEventDescription",
    "DynamicEventStatus",
    "Feedback",
    "Goal",
    "LogEntry",
    "Result",
    "Time",
    "WireMessage",
]

_M = TypeVar("_M", bound="WireMessage")


class WireMessage:
    """Base of every wire mirror, field for field with its ROS names and defaults (R1.1): conversion
    to and from dicts and JSON text (R1.3)."""

    __slots__ = ()

    #: The ROS interface this class mirrors, e.g. ``"rmf_task_msgs/msg/LogEntry"``.
    ROS_TYPE: ClassVar[str] = ""

    @classmethod
    def wire_types(cls) -> dict[str, str]:
        """Map each field name to its ROS type: ``"uint32"``, ``"string"``, ``"Time"``, ``"LogEntry[]"``..."""
        result: dict[str, str] = {}
        for field in attrs.fields(cls):  # type: ignore[arg-type]
            wire = field.metadata[WIRE_KEY]
            if isinstance(wire, tuple):
                result[field.name] = f"{wire[0].__name__}[]"
            elif isinstance(wire, type):
                result[field.name] = wire.__name__
            else:
                result[field.name] = wire
        return result

    def to_dict(self) -> dict[str, Any]:
        """Return the message as a dict of plain JSON values, keyed by ROS field name."""
        result: dict[str, Any] = {}
        for field in attrs.fields(type(self)):  # type: ignore[arg-type]
            wire = field.metadata[WIRE_KEY]
            value = getattr(self, field.name)
            if isinstance(wire, tuple):
                result[field.name] = [item.to_dict() for item in value]
            elif isinstance(wire, type):
                result[field.name] = value.to_dict()
            else:
                result[field.name] = value
        return result

    def to_json(self) -> str:
        """Return the message as compact JSON text (non-finite floats as ``NaN``/``Infinity``)."""
        return _json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls: type[_M], data: object) -> _M:
        """Build a message from a dict keyed by ROS field name.

        Missing fields take their ROS default; unknown fields are refused.
        Every fault raises :class:`~dynevent.errors.MalformedMessage` (an
        ``InvalidMessage`` from outside) naming the class and the (dotted) field.
        """
        name = cls.__name__
        if not isinstance(data, dict):
            raise MalformedMessage(name, "", data, "expected a JSON object")
        plan = _PLANS.get(cls) or _plan(cls)
        values: dict[str, Any] = {}
        for key, raw in data.items():
            step = plan.get(key) if isinstance(key, str) else None
            if step is None:
                raise MalformedMessage(name, str(key), raw, "unknown field")
            how, wire = step
            if how is _AS_IS:
                values[key] = raw
            elif how is _INTEGER:
                if type(raw) is not int:
                    raise MalformedMessage(name, key, raw, f"expected an integer ({wire})")
                values[key] = raw
            elif how is _NESTED:
                values[key] = _decode_nested(name, key, wire, raw)
            else:
                values[key] = _decode_array(name, key, wire, raw)
        try:
            return cls(**values)
        except InvalidMessage as exc:  # the constructor's check, of a value that came from outside
            raise MalformedMessage.of(exc) from None

    @classmethod
    def from_json(cls: type[_M], text: str | bytes | bytearray) -> _M:
        """Parse JSON text into a message; every fault raises :class:`~dynevent.errors.MalformedMessage`."""
        try:
            data = _json.parse(text)
        except _json.JsonProblem as exc:
            raise MalformedMessage(cls.__name__, "", text, str(exc)) from None
        return cls.from_dict(data)


# How from_dict reads each field of a class: as it is (the constructor checks it), an integer (a JSON
# number with a fraction or exponent is refused, not truncated), a nested message, or an array of them.
_AS_IS, _INTEGER, _NESTED, _ARRAY = "as is", "integer", "nested", "array"
_PLANS: dict[type, dict[str, tuple[str, Any]]] = {}


def _plan(cls: type) -> dict[str, tuple[str, Any]]:
    plan: dict[str, tuple[str, Any]] = {}
    for field in attrs.fields(cls):
        wire = field.metadata[WIRE_KEY]
        if isinstance(wire, tuple):
            plan[field.name] = (_ARRAY, wire[0])
        elif isinstance(wire, type):
            plan[field.name] = (_NESTED, wire)
        elif wire.startswith(("uint", "int")):
            plan[field.name] = (_INTEGER, wire)
        else:
            plan[field.name] = (_AS_IS, wire)
    _PLANS[cls] = plan
    return plan


def _decode_nested(owner: str, key: str, cls: type[WireMessage], raw: object) -> WireMessage:
    try:
        return cls.from_dict(raw)
    except InvalidMessage as exc:
        inner = f"{key}.{exc.field}" if exc.field else key
        raise MalformedMessage(owner, inner, exc.value, exc.problem) from None


def _decode_array(owner: str, key: str, cls: type[WireMessage], raw: object) -> tuple[WireMessage, ...]:
    if not isinstance(raw, list):
        raise MalformedMessage(owner, key, raw, f"expected an array of {cls.__name__}")
    return tuple(_decode_nested(owner, f"{key}[{index}]", cls, item) for index, item in enumerate(raw))


@fast_init
@attrs.frozen(kw_only=True, order=True)
class Time(WireMessage):
    """``builtin_interfaces/msg/Time``: seconds and nanoseconds since the Unix epoch."""

    ROS_TYPE: ClassVar[str] = "builtin_interfaces/msg/Time"

    sec: int = i32()
    nanosec: int = u32()

    @classmethod
    def from_nanoseconds(cls, nanoseconds: int) -> Time:
        """Split a count of nanoseconds since the epoch into ``sec`` and ``nanosec``."""
        sec, nanosec = divmod(nanoseconds, SECOND)
        return cls(sec=sec, nanosec=nanosec)

    @property
    def nanoseconds(self) -> int:
        """The time as one count of nanoseconds since the epoch."""
        return self.sec * SECOND + self.nanosec


@fast_init
@attrs.frozen(kw_only=True)
class Goal(WireMessage):
    """``rmf_task_msgs/action/DynamicEvent`` goal: one command to the robot's server.

    ``event_type`` is any uint32: values outside :class:`~dynevent.wire.vocab.EventType`
    are legal on the wire and refused by the machine with a reason.
    """

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/action/DynamicEvent_Goal"

    dynamic_event_seq: int = u32()
    event_type: int = u32()
    category: str = string()
    description: str = string()
    id: int = u64()
    stubborn_period: float = f32()


@fast_init
@attrs.frozen(kw_only=True)
class Result(WireMessage):
    """``rmf_task_msgs/action/DynamicEvent`` result: the terminal answer to one goal.

    A non-empty ``execution_failure`` means the goal could not begin; the other
    fields are then default-initialized.
    """

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/action/DynamicEvent_Result"

    execution_failure: str = string()
    status: str = string()
    id: int = u64()


@fast_init
@attrs.frozen(kw_only=True)
class LogEntry(WireMessage):
    """``rmf_task_msgs/msg/LogEntry``, matching ``log_entry.json``."""

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/msg/LogEntry"

    seq: int = u32()
    tier: str = string()
    unix_millis_time: int = i64()
    text: str = string()


@fast_init
@attrs.frozen(kw_only=True)
class Feedback(WireMessage):
    """``rmf_task_msgs/action/DynamicEvent`` feedback: status of the running event and new logs."""

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/action/DynamicEvent_Feedback"

    status: str = string()
    id: int = u64()
    logs: tuple[LogEntry, ...] = sequence(LogEntry)


@fast_init
@attrs.frozen(kw_only=True)
class DynamicEventDescription(WireMessage):
    """``rmf_task_msgs/msg/DynamicEventDescription``, published when a dynamic event begins."""

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/msg/DynamicEventDescription"

    fleet: str = string()
    robot: str = string()
    dynamic_event_seq: int = u32()
    description: str = string()
    start_time: Time = message(Time)


@fast_init
@attrs.frozen(kw_only=True)
class DynamicEventStatus(WireMessage):
    """``rmf_task_msgs/msg/DynamicEventStatus``, the robot's dynamic event state."""

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/msg/DynamicEventStatus"

    dynamic_event_seq: int = u32()
    dynamic_state: int = u8()
    status: str = string()
    id: int = u64()
    time: Time = message(Time)


@fast_init
@attrs.frozen(kw_only=True)
class DescriptionRequest(WireMessage):
    """Request of the proposal's description service (ROS requires at least one field)."""

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/srv/DynamicEventDescription_Request"

    at_least_one_field: bool = boolean_field()


@fast_init
@attrs.frozen(kw_only=True)
class DescriptionResponse(WireMessage):
    """Response of the proposal's description service.

    ``running`` is true while a dynamic event is active; otherwise every other
    field is default-initialized.
    """

    ROS_TYPE: ClassVar[str] = "rmf_task_msgs/srv/DynamicEventDescription_Response"

    running: bool = boolean_field()
    status: str = string()
    description: str = string()
    id: int = u64()


#: Every wire mirror, in the order the protocol introduces them.
MESSAGE_TYPES: tuple[type[WireMessage], ...] = (
    Goal,
    Result,
    Feedback,
    LogEntry,
    Time,
    DynamicEventDescription,
    DynamicEventStatus,
    DescriptionRequest,
    DescriptionResponse,
)
