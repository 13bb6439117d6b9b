"""What happens to one robot's server: the inputs of the server machine.

Each input is a small frozen class, checked on construction like a wire
message (a bad value raises :class:`~dynevent.errors.InvalidMessage` naming the
class, the field and the value), so the machine itself never meets a
malformed input and never raises.

Time enters the machine only here: every input carries ``now``, in integer
nanoseconds since the Unix epoch, within the range a ``builtin_interfaces/Time``
can carry.  Goals are named by their ROS 2 action goal UUID, stored as 32
lowercase hexadecimal digits.
"""

from __future__ import annotations

import math
import operator
import uuid
from typing import Any, ClassVar, TypeAlias

import attrs

from dynevent.errors import DyneventError, InvalidValue
from dynevent.wire import _fields
from dynevent.wire._fields import (
    FAST_KEY,
    SECOND,
    STRING_CHECK,
    boolean_field,
    fast_init,
    integer_check,
    string,
    u64,
)
from dynevent.wire.description import EventDescription
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import Status, Tier

__all__ = [
    "MAX_LOG_TEXT_LENGTH",
    "NOW_RANGE",
    "Begin",
    "CancelRequested",
    "ChildFinished",
    "ChildProgress",
    "DescriptionQuery",
    "GoalRequested",
    "GoalStarted",
    "GoalSubmitted",
    "IdDrawn",
    "Input",
    "Interrupt",
    "Restart",
    "Resume",
    "Shutdown",
    "TaskCancel",
    "TaskKill",
    "Tick",
    "goal_uuid",
]

#: Longest log text a child progress input may carry, in characters.
MAX_LOG_TEXT_LENGTH = 16_384

#: Inclusive range of ``now`` (nanoseconds): what ``builtin_interfaces/Time`` can carry.
NOW_RANGE = (-(2**31) * SECOND, 2**31 * SECOND - 1)

_STATUSES = frozenset(status.value for status in Status)
_TIERS = frozenset(tier.value for tier in Tier)
#: The digits of a stored goal UUID.
LOWER_HEX = frozenset("0123456789abcdef")


def goal_uuid(value: object) -> str:
    """Canonicalize a goal UUID given in any of the shapes the wire and rclpy use: 32 hex digits (any
    case), 8-4-4-4-12 hex digits, 16 bytes, 16 ints from 0 to 255 (a list, or the uint8 array of
    ``goal_handle.goal_id.uuid``), or a :class:`uuid.UUID`.

    Returns 32 lowercase hexadecimal digits.  Raises ``ValueError`` (not the
    project's error: callers wrap it with their own location).
    """
    if isinstance(value, str) and type(value) is not str:  # a str subclass: its characters
        value = str.__str__(value)
    if type(value) is str and len(value) == 32:
        lowered = value.lower()
        if LOWER_HEX.issuperset(lowered):  # int(value, 16) would also take "_", "+" and spaces
            return lowered
    if isinstance(value, uuid.UUID):
        return value.hex
    if isinstance(value, (bytes, bytearray, memoryview)):
        if len(value) != 16:
            raise ValueError(f"a goal UUID is 16 bytes, got {len(value)}")
        return bytes(value).hex()
    if not isinstance(value, str) and hasattr(value, "__len__") and hasattr(value, "__iter__"):
        return _from_octets(value)  # 16 ints: a list, or the uint8 array rclpy hands over
    if isinstance(value, str):  # the hyphenated form, 8-4-4-4-12 (uuid.UUID would also take "_", "+", spaces)
        if len(value) == 36 and all(value[index] == "-" for index in (8, 13, 18, 23)):
            compact = value.replace("-", "").lower()
            if len(compact) == 32 and LOWER_HEX.issuperset(compact):
                return compact
        raise ValueError("expected 32 hexadecimal digits")
    raise ValueError("expected 32 hexadecimal digits, 16 bytes, 16 ints from 0 to 255 or a uuid.UUID")


def _from_octets(value: Any) -> str:
    """16 integers from 0 to 255 (ints, or integer scalars such as numpy's) as 32 hex digits."""
    if len(value) != 16:
        raise ValueError(f"a goal UUID is 16 octets, got {len(value)}")
    octets = []
    for item in value:
        try:
            octet = operator.index(item)
        except TypeError:
            raise ValueError(f"a goal UUID's octets are integers, got {item!r}") from None
        if isinstance(item, bool) or not 0 <= octet <= 255:
            raise ValueError(f"a goal UUID's octets are integers from 0 to 255, got {item!r}")
        octets.append(octet)
    return bytes(octets).hex()


def _uuid(value: Any, instance: object, field: attrs.Attribute[Any]) -> str:
    try:
        return goal_uuid(value)
    except ValueError as exc:
        raise InvalidValue(type(instance).__name__, field.name, value, str(exc)) from None


def _now(value: Any, instance: object, field: attrs.Attribute[Any]) -> int:
    if type(value) is not int:
        raise InvalidValue(type(instance).__name__, field.name, value, "expected integer nanoseconds")
    if not NOW_RANGE[0] <= value <= NOW_RANGE[1]:
        raise InvalidValue(
            type(instance).__name__, field.name, value, "outside the range of builtin_interfaces/Time"
        )
    return value


def _one_of(allowed: frozenset[str], what: str) -> attrs.Converter[Any, Any]:
    def convert(value: Any, instance: object, field: attrs.Attribute[Any]) -> str:
        plain = value.value if isinstance(value, (Status, Tier)) else value
        if type(plain) is not str or plain not in allowed:  # the type first: a dict is unhashable
            raise InvalidValue(
                type(instance).__name__, field.name, value, f"expected one of the {what}: {sorted(allowed)}"
            )
        return plain

    return attrs.Converter(convert, takes_self=True, takes_field=True)


def _log_text(value: Any, instance: object, field: attrs.Attribute[Any]) -> str | None:
    if value is None:
        return None
    text: str = _fields.check_string(value, instance, field)
    if len(text) > MAX_LOG_TEXT_LENGTH:
        raise InvalidValue(
            type(instance).__name__,
            field.name,
            value,
            f"log text of {len(text)} characters is above the limit of {MAX_LOG_TEXT_LENGTH}",
        )
    return text


def _finite(value: Any, instance: object, field: attrs.Attribute[Any]) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidValue(type(instance).__name__, field.name, value, "expected a number")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise InvalidValue(type(instance).__name__, field.name, value, "expected a finite number")
    return number


def _begin_description(value: Any, instance: object, field: attrs.Attribute[Any]) -> str:
    text: str = _fields.check_string(value, instance, field)
    try:
        EventDescription.from_json(text)
    except DyneventError as exc:
        raise InvalidValue(type(instance).__name__, field.name, value, str(exc)) from None
    return text


def _goal(value: Any, instance: object, field: attrs.Attribute[Any]) -> Goal:
    if type(value) is not Goal:
        raise InvalidValue(type(instance).__name__, field.name, value, "expected a Goal")
    return value


def _conv(function: Any) -> Any:
    return attrs.Converter(function, takes_self=True, takes_field=True)


def _checked(function: Any, fast: str | None = None, **kwargs: Any) -> Any:
    """An ``attrs.field`` whose converter is ``function(value, instance, field)``; ``fast`` is the
    check of the values it returns unchanged (see :func:`~dynevent.wire._fields.fast_init`)."""
    metadata = {} if fast is None else {FAST_KEY: fast}
    return attrs.field(converter=_conv(function), metadata=metadata, **kwargs)


def _now_field() -> Any:
    return _checked(_now, integer_check(*NOW_RANGE))


def _uuid_field() -> Any:
    return _checked(_uuid, "type({v}) is str and len({v}) == 32 and LOWER_HEX.issuperset({v})")


def _one_of_field(allowed: str, what: str, **kwargs: Any) -> Any:
    """A field holding one of the names in the module's frozenset ``allowed``."""
    return attrs.field(
        converter=_one_of(globals()[allowed], what),
        metadata={FAST_KEY: f"type({{v}}) is str and {{v}} in {allowed}"},
        **kwargs,
    )


class _Input:
    __slots__ = ()

    #: The name of this input in traces, vectors and diagrams.
    KIND: ClassVar[str] = ""


@fast_init
@attrs.frozen(kw_only=True)
class Begin(_Input):
    """A task reached a ``dynamic_event`` phase: the dynamic event begins.

    ``description`` is the full JSON text of the ``dynamic_event`` event
    description; ``event_id`` is the dynamic event's own id in its task;
    ``interrupted`` says whether that task is interrupted as the run begins
    (an interruption belongs to the task, R3.1).
    """

    KIND: ClassVar[str] = "begin"
    description: str = _checked(_begin_description)
    event_id: int = u64()
    now: int = _now_field()
    interrupted: bool = boolean_field()


@fast_init
@attrs.frozen(kw_only=True)
class GoalRequested(_Input):
    """A goal request arrived (a ROS ``handle_goal`` callback)."""

    KIND: ClassVar[str] = "goal_requested"
    goal_uuid: str = _uuid_field()
    goal: Goal = _checked(_goal, "type({v}) is Goal")
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class GoalStarted(_Input):
    """An accepted goal is handed over for execution (a ROS ``handle_accepted`` callback)."""

    KIND: ClassVar[str] = "goal_started"
    goal_uuid: str = _uuid_field()
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class GoalSubmitted(_Input):
    """A goal the transport has already accepted arrives, to be requested and started in one step.

    For bindings whose goal callback cannot name the goal (rclpy's gets no
    goal UUID): they check the goal with :func:`dynevent.server.machine.accept`, let
    the transport accept it, and submit it here with its UUID (R5.3).
    """

    KIND: ClassVar[str] = "goal_submitted"
    goal_uuid: str = _uuid_field()
    goal: Goal = _checked(_goal, "type({v}) is Goal")
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class CancelRequested(_Input):
    """A client asked, through the action protocol, to cancel a goal (``handle_cancel``)."""

    KIND: ClassVar[str] = "cancel_requested"
    goal_uuid: str = _uuid_field()
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class ChildProgress(_Input):
    """The running child event reported a status, optionally with a log line."""

    KIND: ClassVar[str] = "child_progress"
    status: str = _one_of_field("_STATUSES", "task_state statuses")
    now: int = _now_field()
    log_text: str | None = _checked(
        _log_text,
        f"{{v}} is None or ({STRING_CHECK} and len({{v}}) <= {MAX_LOG_TEXT_LENGTH})",
        default=None,
    )
    tier: str = _one_of_field("_TIERS", "log tiers", default="info")


@fast_init
@attrs.frozen(kw_only=True)
class ChildFinished(_Input):
    """The running child event ended with a final status."""

    KIND: ClassVar[str] = "child_finished"
    status: str = _one_of_field("_STATUSES", "task_state statuses")
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class Tick(_Input):
    """Time passed; the robot is on ``map_name`` at ``(x, y)`` metres."""

    KIND: ClassVar[str] = "tick"
    now: int = _now_field()
    map_name: str = string()
    x: float = _checked(_finite, default=0.0)
    y: float = _checked(_finite, default=0.0)


@fast_init
@attrs.frozen(kw_only=True)
class Interrupt(_Input):
    """The task was interrupted (paused)."""

    KIND: ClassVar[str] = "interrupt"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class IdDrawn(_Input):
    """The adapter drew an id for work of its own from the counter it numbers children with (under id
    policy ``adapter``: rmf_ros2's go_to_place child draws one for its plan, R17.8)."""

    KIND: ClassVar[str] = "id_drawn"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class Resume(_Input):
    """The task's interruption was released."""

    KIND: ClassVar[str] = "resume"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class TaskCancel(_Input):
    """The whole task was cancelled."""

    KIND: ClassVar[str] = "task_cancel"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class TaskKill(_Input):
    """The whole task was killed."""

    KIND: ClassVar[str] = "task_kill"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class Shutdown(_Input):
    """The adapter is shutting down."""

    KIND: ClassVar[str] = "shutdown"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class Restart(_Input):
    """The state was restored after the process that served it ended: its goal handles and child with it."""

    KIND: ClassVar[str] = "restart"
    now: int = _now_field()


@fast_init
@attrs.frozen(kw_only=True)
class DescriptionQuery(_Input):
    """A request of the proposal's description service."""

    KIND: ClassVar[str] = "description_query"
    now: int = _now_field()


#: Any input of the server machine.
Input: TypeAlias = (
    Begin
    | GoalRequested
    | GoalStarted
    | GoalSubmitted
    | CancelRequested
    | ChildProgress
    | ChildFinished
    | Tick
    | Interrupt
    | Resume
    | IdDrawn
    | TaskCancel
    | TaskKill
    | Shutdown
    | Restart
    | DescriptionQuery
)

#: Every input class, by its ``KIND``.
INPUT_TYPES: dict[str, type[Input]] = {
    cls.KIND: cls
    for cls in (
        Begin,
        GoalRequested,
        GoalStarted,
        GoalSubmitted,
        CancelRequested,
        ChildProgress,
        ChildFinished,
        Tick,
        Interrupt,
        Resume,
        IdDrawn,
        TaskCancel,
        TaskKill,
        Shutdown,
        Restart,
        DescriptionQuery,
    )
}
