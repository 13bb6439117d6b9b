"""The closed vocabularies of the Dynamic Event protocol.

The integer enums mirror constants of the ROS definitions; the string enums
mirror string constants and the ``status`` enum of ``task_state.json``.  Wire
messages store plain ``int``/``str`` values (the wire can carry any value of the
field's type); these enums name the values that mean something.
"""

from __future__ import annotations

import enum

__all__ = [
    "CANCEL_GOAL_TERMINATED",
    "ENDED_CHILD_STATUSES",
    "TASK_SIGNAL_LOGS",
    "TERMINAL_GOAL_STATUSES",
    "ClientViolation",
    "Compatibility",
    "DynamicState",
    "EventType",
    "Failure",
    "GoalStatus",
    "IdPolicy",
    "RejectReason",
    "Status",
    "Tier",
    "Violation",
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
    """``DynamicEventStatus.dynamic_state`` constants (a ``uint8`` on the wire).

    An ``int`` on the wire and in comparisons; printed by name (``WAITING``), as a
    reader of a state or a log wants it.  ``int(phase)`` or ``f"{phase:d}"`` gives the number.
    """

    INACTIVE = 0
    WAITING = 1
    RUNNING = 2

    def __str__(self) -> str:
        return self.name

    def __format__(self, spec: str) -> str:
        return (
            self.name.__format__(spec)
            if not spec or spec[-1] not in "bcdoxXn"
            else int.__format__(self, spec)
        )


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


#: The statuses a child reports when it ends (R20.2): a RUNNING status message carrying one of them
#: names a child that has ended (rmf_ros2 keeps publishing it while the robot waits, R17.4) or is
#: about to.  ``error`` is not among them: a child reports it while it runs too.
ENDED_CHILD_STATUSES = frozenset(
    {
        Status.COMPLETED.value,
        Status.FAILED.value,
        Status.SKIPPED.value,
        Status.CANCELED.value,
        Status.KILLED.value,
    }
)

#: The log line a task signal writes (R13.1), by the status it gives the dynamic event: rmf_ros2's
#: own words, which a judge reads back to tell a signal from a child's progress.
TASK_SIGNAL_LOGS: dict[str, str] = {
    Status.CANCELED.value: "Received signal to cancel",
    Status.KILLED.value: "Received signal to kill",
}


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

#: action_msgs/CancelGoal's return code ``ERROR_GOAL_TERMINATED``: the server refused an action-level
#: cancel because the goal had already terminated when it took the request.  rcl_action gives it
#: from the goal's own state, before any cancel callback runs (a callback's refusal of a goal still
#: open is ``ERROR_REJECTED``, 1), so it shows the goal answered before the cancel (R10.5).
CANCEL_GOAL_TERMINATED = 3


class RejectReason(str, enum.Enum):
    """Why a goal request was refused, or why an accepted goal could not start.

    One closed vocabulary shared by the server machine (:func:`dynevent.server.machine.accept`),
    the client machine's local refusals and the conformance vectors.  The
    order of the checks is given in docs/spec.md.
    """

    SHUTTING_DOWN = "shutting_down"
    SEQ_MISMATCH = "seq_mismatch"
    INACTIVE = "inactive"
    UNINITIALIZED_EVENT_TYPE = "uninitialized_event_type"
    UNKNOWN_EVENT_TYPE = "unknown_event_type"
    BUSY = "busy"
    UNSUPPORTED_CATEGORY = "unsupported_category"
    DESCRIPTION_NOT_JSON = "description_not_json"
    DESCRIPTION_INVALID = "description_invalid"
    NON_FINITE_STUBBORN_PERIOD = "non_finite_stubborn_period"
    STALE_ID = "stale_id"
    CANCEL_IDLE = "cancel_idle"
    CANCEL_ID_MISMATCH = "cancel_id_mismatch"
    RACE = "race"

    def __str__(self) -> str:
        return self.value


class Failure(str, enum.Enum):
    """Why a goal that was accepted is aborted: rmf_ros2's execution-failure strings.

    The value is the exact first line of ``Result.execution_failure`` (the
    machine may add detail lines after it, each starting with ``" -- "``).  :attr:`reason` is
    the refusal the failure reports, where it is one a request could have
    met; :meth:`of` reads a failure back from a result's text.
    """

    RACE = "race condition"
    SHUTDOWN = "shutting down"
    IDLE_CANCEL = "an idle dynamic event cannot be cancelled"
    CANCEL_ID = "ID for cancel request does not match current event"
    EVENT_TYPE = "invalid event_type"
    PARSE = "Description parsing failure"
    NOT_RUNNING = "cancelled while not running"
    RESTART = "server restarted"
    #: Not a server's: a client's, for a goal whose result request the server answered as unknown: a
    #: new process that never took it (R21.4), or a request the network lost (R21.5).
    LOST = "goal lost: unknown to the server"

    def __str__(self) -> str:
        return self.value

    @property
    def reason(self) -> RejectReason | None:
        """The reject reason this failure reports, or ``None`` when no request check matches it."""
        return _FAILURE_REASONS[self]

    @classmethod
    def of(cls, execution_failure: str) -> Failure | None:
        """The failure a ``Result.execution_failure`` text starts with, if it is one of these."""
        return _FAILURES_BY_TEXT.get(execution_failure.split("\n", 1)[0])


_FAILURE_REASONS: dict[Failure, RejectReason | None] = {
    Failure.RACE: RejectReason.RACE,
    Failure.SHUTDOWN: RejectReason.SHUTTING_DOWN,
    Failure.IDLE_CANCEL: RejectReason.CANCEL_IDLE,
    Failure.CANCEL_ID: RejectReason.CANCEL_ID_MISMATCH,
    Failure.EVENT_TYPE: RejectReason.UNKNOWN_EVENT_TYPE,
    Failure.PARSE: RejectReason.DESCRIPTION_INVALID,
    Failure.NOT_RUNNING: None,
    Failure.RESTART: None,
    Failure.LOST: None,
}
_FAILURES_BY_TEXT: dict[str, Failure] = {failure.value: failure for failure in Failure}


class IdPolicy(str, enum.Enum):
    """Where a child event's id comes from."""

    #: The NEXT goal's ``id`` becomes the child's id, as the action text says.
    GOAL = "goal"
    #: The server assigns the next id itself, ignoring the goal's ``id`` (rmf_ros2).
    ADAPTER = "adapter"

    def __str__(self) -> str:
        return self.value


class Compatibility(str, enum.Enum):
    """Which reading of the protocol the server follows where sources disagree."""

    #: The action text is normative: bad event types and bad CANCELs are rejected at request time.
    STANDARD = "standard"
    #: rmf_ros2's accept-then-abort for event types and CANCEL checks.
    RMF_ROS2 = "rmf_ros2"

    def __str__(self) -> str:
        return self.value


class ClientViolation(enum.Enum):
    """What a client can be seen sending that docs/spec.md section 22 says it must not: a code, the
    rule, and what a well-behaved client does instead.  ``dynevent serve`` reports each under one."""

    code: str
    rule: str
    instead: str

    def __init__(self, code: str, rule: str, instead: str) -> None:
        self.code = code
        self.rule = rule
        self.instead = instead

    STALE_SEQ = ("stale_seq", "R22.2", "the seq of the run the status shows")
    AFTER_FINISHED = ("after_finished", "R22.3", "no goal until a run begins")
    NEXT_WHILE_RUNNING = ("next_while_running", "R22.4", "a NEXT or FINISHED once the child has ended")
    CANCEL_NOT_RUNNING = ("cancel_not_running", "R22.5", "a CANCEL naming the running child, while one runs")
    STALE_ID = ("stale_id", "R22.6", "id 0, or above the id the status shows")
    NEVER_ACCEPTABLE = ("never_acceptable", "R22.7", "a goal some state accepts")
    RUN_LEFT_OPEN = ("run_left_open", "R22.8", "a FINISHED at the end of the run it drove")

    @classmethod
    def of_refusal(cls, reason: RejectReason) -> ClientViolation | None:
        """What a client breaks by sending a goal that every status it could read says is refused
        with ``reason`` (R22.2 to R22.6); None for a refusal the client could not know of."""
        return _VIOLATION_OF_REFUSAL.get(reason)


_VIOLATION_OF_REFUSAL = {
    RejectReason.SEQ_MISMATCH: ClientViolation.STALE_SEQ,
    RejectReason.INACTIVE: ClientViolation.AFTER_FINISHED,
    RejectReason.BUSY: ClientViolation.NEXT_WHILE_RUNNING,
    RejectReason.CANCEL_IDLE: ClientViolation.CANCEL_NOT_RUNNING,
    RejectReason.CANCEL_ID_MISMATCH: ClientViolation.CANCEL_NOT_RUNNING,
    RejectReason.STALE_ID: ClientViolation.STALE_ID,
}


class Violation(enum.Enum):
    """What a server can be seen doing that docs/spec.md forbids: a code, and the rule it breaks.

    ``dynevent check`` reports each finding under one (``Finding.code`` and
    ``Finding.rule``); the test kit raises ``ProtocolViolation`` naming one.
    Where a server's output differs from the one the machine gives (a wrong
    reason, answer or feedback), the finding names the rule of the machine's
    output instead (``Output.rule``), so those are not listed here.
    """

    code: str
    rule: str

    def __init__(self, code: str, rule: str) -> None:
        self.code = code
        self.rule = rule

    # a begin and the run it opens
    BEGIN_DESCRIPTION = ("begin_description", "R1.5")
    BEGIN_SEQ = ("begin_seq", "R3.1")
    BEGIN_NAMES = ("begin_names", "R3.3")
    BEGIN_WHILE_ACTIVE = ("begin_while_active", "R3.4")
    BEGIN_AFTER_SHUTDOWN = ("begin_after_shutdown", "R15.2")
    BEGIN_MESSAGE = ("begin_message", "R19.3")
    # the status topic
    STATUS_PHASE = ("status_phase", "R2.2")
    STATUS_MISMATCH = ("status_mismatch", "R2.2")
    VIEW_MISMATCH = ("view_mismatch", "R2.2")
    STATUS_PUBLICATION = ("status_publication", "R2.3")
    STATUS_AFTER_CHILD_END = ("status_after_child_end", "R17.4")
    STATUS_AFTER_REPORT = ("status_after_report", "R17.5")
    STATUS_NOT_STATE = ("status_not_state", "R19.5")
    STATUS_SEQ = ("status_seq", "R19.3")
    STATUS_ID = ("status_id", "R6.2")
    # goal requests, the running slot and children
    REJECTED_ACCEPTABLE = ("rejected_acceptable", "R4.16")
    RACE_NOT_LOST = ("race_not_lost", "R5.2")
    CHILD_ID = ("child_id", "R6.2")
    ANSWER_BEFORE_START = ("unexpected_answer", "R6.4")
    ANSWER_WHILE_DEFERRED = ("unexpected_answer", "R6.3")
    ONE_CHILD = ("one_child", "R19.2")
    # feedback and logs
    FEEDBACK_NOT_RUNNING = ("feedback_not_running", "R7.1")
    LOG_SEQ = ("log_seq", "R7.3")
    LOG_TIER = ("log_tier", "R7.2")
    FEEDBACK_ID = ("feedback_id", "R7.1")
    # cancels, the end of a run, stubbornness, the description service
    CANCEL_ANSWERED_EARLY = ("cancel_answered_early", "R9.3")
    FINISHED_INACTIVE = ("finished_inactive", "R11.2")
    STUBBORN_UNASKED = ("stubborn_unasked", "R12.1")
    CLAMP_NOT_REPORTED = ("clamp_not_reported", "R12.2")
    DELAY_NOT_STUBBORN = ("delay_not_stubborn", "R12.3")
    STUBBORN_MINIMUM = ("stubborn_minimum", "R19.4")
    DESCRIPTION_ANSWER = ("description_answer", "R16.2")
    # the life of a goal on the action
    IGNORED_NOT_ALONE = ("ignored_not_alone", "R18.1")
    GOAL_UUID_REUSED = ("goal_uuid_reused", "R18.2")
    ANSWER_NOT_ACCEPTED = ("answer_not_accepted", "R19.1")
    ANSWER_NOT_OPEN = ("unexpected_answer", "R19.1")
    ANSWER_MISSING = ("answer_missing", "R19.1")
    RESPONSE_MISSING = ("response_missing", "R19.1")
    SECOND_ANSWER = ("second_answer", "R19.1")
    AFTER_ANSWER = ("after_answer", "R19.1")
    NEVER_ANSWERED = ("never_answered", "R19.1")
    GOAL_TRANSITION = ("goal_transition", "R19.1")
    RESPONSE_MISMATCH = ("response_mismatch", "R19.1")
    FOREIGN_OUTPUT = ("foreign_output", "R19.7")
