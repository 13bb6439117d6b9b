"""The closed vocabularies of the Dynamic Event protocol.

The integer enums mirror constants of the ROS definitions; the string enums
mirror string constants and the ``status`` enum of ``task_state.json``.  Wire
messages store plain ``int``/``str`` values (the wire can carry any value of the
field's type); these enums name the values that mean something.
"""

from __future__ import annotations

import enum

__all__ = [
    "TERMINAL_GOAL_STATUSES",
    "DynamicState",
    "EventType",
    "GoalStatus",
    "Status",
    "Tier",
]


class EventType(enum.IntEnum):
    """``DynamicEvent.Goal.event_type`` constants.

    The wire field is a ``uint32``; values other than these four are legal on
    the wire and refused by the machine with a reason.
    """

    UNINITIALIZED = 0
    NEXT = 1
    CANCEL = 2
    FINISHED = 3


class DynamicState(enum.IntEnum):
    """``DynamicEventStatus.dynamic_state`` constants (a ``uint8`` on the wire)."""

    INACTIVE = 0
    WAITING = 1
    RUNNING = 2


class Tier(str, enum.Enum):
    """``LogEntry.tier`` constants."""

    UNINITIALIZED = "uninitialized"
    INFO = "info"
    WARNING = "warning"
    ERROR = "error"

    def __str__(self) -> str:
        return self.value


class Status(str, enum.Enum):
    """The twelve status tokens of ``task_state.json`` (``$defs/status``)."""

    UNINITIALIZED = "uninitialized"
    BLOCKED = "blocked"
    ERROR = "error"
    FAILED = "failed"
    QUEUED = "queued"
    STANDBY = "standby"
    UNDERWAY = "underway"
    DELAYED = "delayed"
    SKIPPED = "skipped"
    CANCELED = "canceled"
    KILLED = "killed"
    COMPLETED = "completed"

    def __str__(self) -> str:
        return self.value


class GoalStatus(str, enum.Enum):
    """The ROS 2 action goal lifecycle, as seen by one goal.

    A goal is ``accepted`` when its request is accepted, ``executing`` once it
    has started, ``canceling`` after an action-level cancel was accepted, and
    ends in exactly one of the three terminal statuses.
    """

    ACCEPTED = "accepted"
    EXECUTING = "executing"
    CANCELING = "canceling"
    SUCCEEDED = "succeeded"
    CANCELED = "canceled"
    ABORTED = "aborted"

    def __str__(self) -> str:
        return self.value

    @property
    def is_terminal(self) -> bool:
        """True for ``succeeded``, ``canceled`` and ``aborted``."""
        return self in TERMINAL_GOAL_STATUSES


TERMINAL_GOAL_STATUSES = frozenset({GoalStatus.SUCCEEDED, GoalStatus.CANCELED, GoalStatus.ABORTED})
