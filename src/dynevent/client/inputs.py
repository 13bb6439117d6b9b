"""The client machine's inputs: what the action, the topics and the clock tell a client.

Each is a frozen value checked where it is built (:class:`~dynevent.errors.InvalidMessage`
names the field and the value); :func:`dynevent.client.step` never raises on one.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeAlias

import attrs

from dynevent.errors import InvalidValue
from dynevent.server.inputs import NOW_RANGE, goal_uuid
from dynevent.server.outputs import Rejected
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Result
from dynevent.wire.vocab import GoalStatus

__all__ = [
    "BeginReceived",
    "ClientInput",
    "ContactLost",
    "ContactMade",
    "FeedbackReceived",
    "GoalResponse",
    "ResultReceived",
    "StatusReceived",
    "Tick",
    "checked_now",
]


# --------------------------------------------------------------------------- checks at the edge


def checked_now(where: str, value: Any) -> int:
    """``value`` as a client input's ``now``: integer nanoseconds within builtin_interfaces/Time, or
    :class:`~dynevent.errors.InvalidValue` naming ``where``."""
    if type(value) is not int:
        raise InvalidValue(where, "now", value, "expected integer nanoseconds")
    if not NOW_RANGE[0] <= value <= NOW_RANGE[1]:
        raise InvalidValue(where, "now", value, "outside the range of builtin_interfaces/Time")
    return value


def _uuid_converter(value: Any, instance: object, field: attrs.Attribute[Any]) -> str:
    try:
        return goal_uuid(value)
    except ValueError as exc:
        raise InvalidValue(type(instance).__name__, field.name, value, str(exc)) from None


def _now_converter(value: Any, instance: object, field: attrs.Attribute[Any]) -> int:
    return checked_now(type(instance).__name__, value)


def _optional_now(value: Any, instance: object, field: attrs.Attribute[Any]) -> int | None:
    return None if value is None else checked_now(type(instance).__name__, value)


def _field(function: Any, **kwargs: Any) -> Any:
    """An ``attrs.field`` whose converter is ``function(value, instance, field)``."""
    return attrs.field(converter=attrs.Converter(function, takes_self=True, takes_field=True), **kwargs)


def _typed(cls: type) -> Any:
    """A field that holds exactly an instance of ``cls``."""

    def check(value: Any, instance: object, field: attrs.Attribute[Any]) -> Any:
        if type(value) is not cls:
            raise InvalidValue(type(instance).__name__, field.name, value, f"expected a {cls.__name__}")
        return value

    return _field(check)


# --------------------------------------------------------------------------- inputs


class _ClientInput:
    __slots__ = ()

    #: The name of this input in traces.
    KIND: ClassVar[str] = ""


@attrs.frozen(kw_only=True)
class BeginReceived(_ClientInput):
    """A begin description arrived (``rmf/dynamic_event/begin/<fleet>/<robot>``)."""

    KIND: ClassVar[str] = "begin_received"
    message: DynamicEventDescription = _typed(DynamicEventDescription)
    #: When it arrived, in integer nanoseconds; ``None``: the client does not watch for the answers
    #: it shows given (R21.6: a newer run shows the FINISHED of the run before answered).
    now: int | None = _field(_optional_now, default=None)


@attrs.frozen(kw_only=True)
class StatusReceived(_ClientInput):
    """A status message arrived (``rmf/dynamic_event/status/<fleet>/<robot>``)."""

    KIND: ClassVar[str] = "status_received"
    message: DynamicEventStatus = _typed(DynamicEventStatus)
    #: When it arrived, in integer nanoseconds; ``None``: the client does not watch for the answers
    #: it shows given (R21.6).
    now: int | None = _field(_optional_now, default=None)


def _rejection(value: Any, instance: object, field: attrs.Attribute[Any]) -> Rejected | None:
    if value is not None and type(value) is not Rejected:
        raise InvalidValue(type(instance).__name__, field.name, value, "expected a Rejected or None")
    return value


@attrs.frozen(kw_only=True)
class GoalResponse(_ClientInput):
    """The server answered a goal request: accepted, or rejected.

    A ROS rejection carries no reason (``rejection`` is ``None``); a client
    talking to dynevent in-process may get the server's
    :class:`~dynevent.server.outputs.Rejected`.
    """

    KIND: ClassVar[str] = "goal_response"
    goal_uuid: str = _field(_uuid_converter)
    accepted: bool = attrs.field(validator=attrs.validators.instance_of(bool))
    rejection: Rejected | None = _field(_rejection, default=None)

    def __attrs_post_init__(self) -> None:
        if self.accepted and self.rejection is not None:
            raise InvalidValue("GoalResponse", "rejection", self.rejection, "an accepted goal has none")


@attrs.frozen(kw_only=True)
class FeedbackReceived(_ClientInput):
    """Feedback arrived for a goal."""

    KIND: ClassVar[str] = "feedback_received"
    goal_uuid: str = _field(_uuid_converter)
    feedback: Feedback = _typed(Feedback)


def _terminal(value: Any, instance: object, field: attrs.Attribute[Any]) -> GoalStatus:
    try:
        status = GoalStatus(value)
    except ValueError:
        status = None
    if status is None or not status.is_terminal:
        raise InvalidValue(
            type(instance).__name__, field.name, value, "expected succeeded, canceled or aborted"
        )
    return status


@attrs.frozen(kw_only=True)
class ResultReceived(_ClientInput):
    """A goal's terminal answer arrived: its final goal status and its result."""

    KIND: ClassVar[str] = "result_received"
    goal_uuid: str = _field(_uuid_converter)
    status: GoalStatus = _field(_terminal)
    result: Result = _typed(Result)


@attrs.frozen(kw_only=True)
class Tick(_ClientInput):
    """Time passed: ``now`` in integer nanoseconds.  Timeouts are checked here."""

    KIND: ClassVar[str] = "tick"
    now: int = _field(_now_converter)


@attrs.frozen(kw_only=True)
class ContactMade(_ClientInput):
    """A publisher of the robot's status topic was matched at ``now``: a server process came into
    contact, a new one (R21.4) or one the client had lost contact with (R21.5)."""

    KIND: ClassVar[str] = "contact_made"
    now: int = _field(_now_converter)


@attrs.frozen(kw_only=True)
class ContactLost(_ClientInput):
    """At ``now`` no publisher of the robot's status topic is matched any longer: the server process
    ended, or the network has cut it off for longer than the middleware's lease (R21.5)."""

    KIND: ClassVar[str] = "contact_lost"
    now: int = _field(_now_converter)


#: Any input of the client machine.
ClientInput: TypeAlias = (
    BeginReceived
    | StatusReceived
    | GoalResponse
    | FeedbackReceived
    | ResultReceived
    | Tick
    | ContactMade
    | ContactLost
)
