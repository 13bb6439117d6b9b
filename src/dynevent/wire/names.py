"""The ROS 2 names of the Dynamic Event protocol for one fleet and robot.

Each robot has one action server, two topics and (in the design proposal
only) one service, all named after its fleet and robot::

    rmf/dynamic_event/command/<fleet>/<robot>      action   (action_name)
    rmf/dynamic_event/begin/<fleet>/<robot>        topic    (begin_topic)
    rmf/dynamic_event/status/<fleet>/<robot>       topic    (status_topic)
    rmf_dynamic_event/description/<fleet>/<robot>  service  (description_service)

plus the fleet-wide begin topic :data:`BEGIN_TOPIC`.  :func:`parse_name` is
the inverse, for routing a name back to its ``(kind, fleet, robot)``.

Fleet and robot names are single ROS 2 name tokens, checked by
:func:`validate_token` against these rules:

- a non-empty ``str`` of ASCII letters, digits and ``_``, not starting with a
  digit: what ``rmw_validate_full_topic_name`` and ``rcl_validate_topic_name``
  enforce (a ``/`` would add tokens, so it is refused inside a fleet or robot);
- no repeated underscore ``__``: the ROS 2 design article "Topic and Service
  name mapping to DDS" allows only *single* underscores in name tokens.  The
  rmw and rcl validators do not check this, so this rule is stricter than
  them; it keeps names clear of the ``__`` that DDS mappings and ROS
  arguments (``__ns``, ``__node``) reserve;
- the fully qualified name (leading ``/``, root namespace) is at most
  :data:`MAX_NAME_LENGTH` characters, ``RMW_TOPIC_MAX_NAME_LENGTH`` of
  ``rmw/validate_full_topic_name.h`` (255 less 8 reserved for prefixes).  For
  the action the limit applies to its longest derived name,
  ``<action>/_action/cancel_goal`` (``rcl_action/names.c``), since the
  action cannot exist unless that service name is valid.

The names are relative: a node in a namespace other than ``/`` lengthens them,
and the length check here cannot know that namespace.
"""

from __future__ import annotations

import enum
import re
from typing import NamedTuple

from dynevent.errors import InvalidName

__all__ = [
    "BEGIN_TOPIC",
    "BEGIN_TOPIC_DEPTH",
    "EVENTS_KEPT",
    "MAX_NAME_LENGTH",
    "ROBOT_BEGIN_TOPIC_DEPTH",
    "STATUS_TOPIC_DEPTH",
    "NameKind",
    "ParsedName",
    "action_name",
    "begin_topic",
    "build_name",
    "description_service",
    "parse_name",
    "status_topic",
    "validate_robot",
    "validate_token",
]

#: The fleet-wide begin topic, on which every robot's begin is also published.
BEGIN_TOPIC = "rmf/dynamic_event/begin"

# The topics' history depths (R1.4); all three are reliable and transient-local.
#: The fleet-wide begin topic keeps the last 100 begins (of every robot).
BEGIN_TOPIC_DEPTH = 100
#: A robot's own begin topic keeps its last begin.
ROBOT_BEGIN_TOPIC_DEPTH = 1
#: A robot's status topic keeps its last status message.
STATUS_TOPIC_DEPTH = 1
#: How many of its latest service events (its action's introspection) a server keeps for a follower
#: that joins late (its judge follows a robot from its first goal on: that goal's event is among them).
EVENTS_KEPT = 16

#: ``RMW_TOPIC_MAX_NAME_LENGTH``: longest fully qualified topic or service name.
MAX_NAME_LENGTH = 255 - 8

_TOKEN_CHARACTERS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_")
_DIGITS = frozenset("0123456789")


class NameKind(str, enum.Enum):
    """Which of the four per-robot names a name is."""

    ACTION = "action"
    BEGIN = "begin"
    STATUS = "status"
    DESCRIPTION = "description"

    def __str__(self) -> str:
        return self.value


class ParsedName(NamedTuple):
    """A per-robot name taken apart by :func:`parse_name`."""

    kind: NameKind
    fleet: str
    robot: str


_PREFIX = {
    NameKind.ACTION: "rmf/dynamic_event/command",
    NameKind.BEGIN: BEGIN_TOPIC,
    NameKind.STATUS: "rmf/dynamic_event/status",
    NameKind.DESCRIPTION: "rmf_dynamic_event/description",
}

# rcl_action derives five names from an action name; this suffix is the longest.
_DERIVED_SUFFIX = {NameKind.ACTION: "/_action/cancel_goal"}

_DESCRIBED = {
    NameKind.ACTION: "action name",
    NameKind.BEGIN: "begin topic name",
    NameKind.STATUS: "status topic name",
    NameKind.DESCRIPTION: "description service name",
}


#: A valid token at a glance (the repeated underscore is checked beside it).
_VALID_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def validate_token(field: str, value: object) -> str:
    """Return ``value`` as a plain ``str`` if it is a valid ROS 2 name token.

    ``field`` (``"fleet"`` or ``"robot"``) names the value in the error.  Raise
    :class:`~dynevent.errors.InvalidName` saying exactly what is wrong: not a
    ``str``, empty, a character outside ``[A-Za-z0-9_]`` (with its index), a
    leading digit, or a repeated underscore.  The length of the whole name is
    checked by the functions that build one.
    """
    if type(value) is str and _VALID_TOKEN.fullmatch(value) is not None and "__" not in value:
        return value  # the common case, at C speed; anything else gets the exact reason below
    if not isinstance(value, str):
        raise InvalidName(field, value, f"is not a str but {type(value).__name__}")
    # a str subclass (a str enum, say) may override __str__; keep the characters
    token = str.__str__(value)
    if not token:
        raise InvalidName(field, value, "is empty")
    for index, character in enumerate(token):
        if character not in _TOKEN_CHARACTERS:
            raise InvalidName(field, value, f"contains {character!r} at index {index}")
    if token[0] in _DIGITS:
        raise InvalidName(field, value, "starts with a digit")
    repeated = token.find("__")
    if repeated >= 0:
        raise InvalidName(field, value, f"contains a repeated underscore '__' at index {repeated}")
    return token


def build_name(kind: NameKind, fleet: object, robot: object) -> str:
    """Return the ``kind`` name of ``robot`` in ``fleet`` (R1.4).

    Raise :class:`~dynevent.errors.InvalidName` if either token is invalid or
    the fully qualified name would be longer than :data:`MAX_NAME_LENGTH`.
    """
    kind = NameKind(kind)
    fleet_token = validate_token("fleet", fleet)
    robot_token = validate_token("robot", robot)
    prefix = _PREFIX[kind]
    name = f"{prefix}/{fleet_token}/{robot_token}"
    suffix = _DERIVED_SUFFIX.get(kind, "")
    length = 1 + len(name) + len(suffix)
    if length > MAX_NAME_LENGTH:
        # blame the fleet only if no robot name, even one letter, could fit after it
        fleet_alone = 1 + len(prefix) + 1 + len(fleet_token) + 2 + len(suffix)
        field, value = ("fleet", fleet) if fleet_alone > MAX_NAME_LENGTH else ("robot", robot)
        derived = f" with its {suffix!r} service" if suffix else ""
        raise InvalidName(
            field,
            value,
            f"makes the fully qualified {_DESCRIBED[kind]} {length} characters long"
            f"{derived}, above the rmw limit of {MAX_NAME_LENGTH}",
        )
    return name


def validate_robot(fleet: object, robot: object) -> tuple[str, str]:
    """The two tokens, if every protocol name of ``robot`` in ``fleet`` can be built.

    Raises :class:`~dynevent.errors.InvalidName` as :func:`build_name` does for
    the first name that cannot; checks each token once and builds no name.
    """
    fleet_token = validate_token("fleet", fleet)
    robot_token = validate_token("robot", robot)
    if 3 + _LONGEST_AFFIXES + len(fleet_token) + len(robot_token) <= MAX_NAME_LENGTH:
        return fleet_token, robot_token  # even the longest name fits
    for kind, prefix in _PREFIX.items():
        if 3 + len(prefix) + len(fleet_token) + len(robot_token) + len(_DERIVED_SUFFIX.get(kind, "")) > (
            MAX_NAME_LENGTH
        ):
            build_name(kind, fleet_token, robot_token)  # raises, saying which name and why
    return fleet_token, robot_token


#: The longest prefix and suffix of any protocol name, together.
_LONGEST_AFFIXES = max(len(prefix) + len(_DERIVED_SUFFIX.get(kind, "")) for kind, prefix in _PREFIX.items())


def action_name(fleet: object, robot: object) -> str:
    """Return ``rmf/dynamic_event/command/<fleet>/<robot>``, the robot's action."""
    return build_name(NameKind.ACTION, fleet, robot)


def begin_topic(fleet: object, robot: object) -> str:
    """Return ``rmf/dynamic_event/begin/<fleet>/<robot>``, the robot's begin topic."""
    return build_name(NameKind.BEGIN, fleet, robot)


def status_topic(fleet: object, robot: object) -> str:
    """Return ``rmf/dynamic_event/status/<fleet>/<robot>``, the robot's status topic."""
    return build_name(NameKind.STATUS, fleet, robot)


def description_service(fleet: object, robot: object) -> str:
    """Return ``rmf_dynamic_event/description/<fleet>/<robot>``, the proposal's service."""
    return build_name(NameKind.DESCRIPTION, fleet, robot)


def parse_name(name: object) -> ParsedName:
    """Take a per-robot name apart into ``(kind, fleet, robot)``.

    Accept exactly the names the builders return, with or without one leading
    ``/`` (the fully qualified form in the root namespace).  Raise
    :class:`~dynevent.errors.InvalidName` for anything else, including the
    fleet-wide :data:`BEGIN_TOPIC`, which names no robot.  A fault in the
    fleet or robot token is reported against ``"fleet"`` or ``"robot"``; any
    other fault against ``"name"``.
    """
    if not isinstance(name, str):
        raise InvalidName("name", name, f"is not a str but {type(name).__name__}")
    relative = name[1:] if name.startswith("/") else name
    if relative == BEGIN_TOPIC:
        raise InvalidName("name", name, "is the fleet-wide begin topic, which names no robot")
    for kind, prefix in _PREFIX.items():
        if relative.startswith(prefix + "/"):
            tokens = relative[len(prefix) + 1 :].split("/")
            if len(tokens) != 2:
                raise InvalidName(
                    "name",
                    name,
                    f"has {len(tokens)} tokens after {prefix + '/'!r}, expected <fleet>/<robot>",
                )
            fleet, robot = tokens
            build_name(kind, fleet, robot)
            return ParsedName(kind, fleet, robot)
    expected = " or ".join(f"'{prefix}/<fleet>/<robot>'" for prefix in _PREFIX.values())
    raise InvalidName("name", name, f"is none of the Dynamic Event names {expected}")
