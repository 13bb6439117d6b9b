"""The client machine's outputs: goals to send, local refusals, outcomes and notices.

Plain frozen values built by the machine (never by a user), so they are not checked again.
"""

from __future__ import annotations

import enum
from typing import ClassVar, TypeAlias

import attrs

from dynevent.server.outputs import Ignored, Rejected  # one Ignored: the server's notice, also the client's
from dynevent.wire.messages import Goal, LogEntry, Result
from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, RejectReason, Status

__all__ = [
    "OUTCOME_OF_STATUS",
    "AskResult",
    "BackInContact",
    "ClientOutput",
    "Ignored",
    "OutOfContact",
    "Outcome",
    "OutcomeKind",
    "Progress",
    "Refused",
    "RunBegan",
    "SendGoal",
    "TimedOut",
    "ViewChanged",
]


class OutcomeKind(str, enum.Enum):
    """What became of one goal: the closed taxonomy of :class:`Outcome`.

    The first six classify a goal that ran to its end by the final status in
    its :class:`~dynevent.wire.messages.Result` (for a NEXT or CANCEL goal, the
    child event's; for FINISHED, the dynamic event's).  The last four say why
    it did not.
    """

    #: The event ran to its end (final status ``completed``).
    COMPLETED = "completed"
    #: The event was cancelled (final status ``canceled``), by a CANCEL goal or the task.
    CANCELED = "canceled"
    #: The event was killed (final status ``killed``), e.g. the task was killed.
    KILLED = "killed"
    #: The event was skipped (final status ``skipped``).
    SKIPPED = "skipped"
    #: The event ended ``failed``.
    FAILED = "failed"
    #: The event ended ``error``, or with a status that is not a final one.
    ERROR = "error"
    #: The server accepted the goal and could not begin it; ``execution_failure`` holds its string.
    EXECUTION_FAILURE = "execution_failure"
    #: The server refused the goal request; ``reason`` says why when the refusal carried one.
    REJECTED = "rejected"
    #: The NEXT goal outran its timeout; the client cancelled it and it has now ended.
    TIMEOUT = "timeout"
    #: The run ended, or a new run began, before the answer arrived, and the goal never ran.
    SUPERSEDED = "superseded"

    def __str__(self) -> str:
        return self.value


#: The outcome of a NEXT whose child ended with each final status.
OUTCOME_OF_STATUS: dict[str, OutcomeKind] = {
    Status.COMPLETED.value: OutcomeKind.COMPLETED,
    Status.CANCELED.value: OutcomeKind.CANCELED,
    Status.KILLED.value: OutcomeKind.KILLED,
    Status.SKIPPED.value: OutcomeKind.SKIPPED,
    Status.FAILED.value: OutcomeKind.FAILED,
    Status.ERROR.value: OutcomeKind.ERROR,
}

# --------------------------------------------------------------------------- outputs


class _ClientOutput:
    __slots__ = ()

    #: The name of this output in traces.
    KIND: ClassVar[str] = ""


@attrs.frozen(kw_only=True)
class SendGoal(_ClientOutput):
    """Send this goal request on the action, under this goal UUID."""

    KIND: ClassVar[str] = "send_goal"
    goal_uuid: str
    goal: Goal


@attrs.frozen(kw_only=True)
class Refused(_ClientOutput):
    """A command was refused locally: the server, as the client knows it, would refuse the goal.

    ``goal`` is the goal that was not sent (``None`` when none could be
    built); ``rejection`` says why, with the reason the server would give.
    """

    KIND: ClassVar[str] = "refused"
    event_type: EventType
    rejection: Rejected
    goal: Goal | None

    # what a caller reads first of an Outcome, so that a result can be read the same either way
    @property
    def kind(self) -> OutcomeKind:
        """:attr:`OutcomeKind.REJECTED`: the goal was refused, here, before it was sent."""
        return OutcomeKind.REJECTED

    @property
    def text(self) -> str:
        """Why, in a sentence: the rejection's."""
        return f"not sent: {self.rejection.text}"

    @property
    def reason(self) -> RejectReason:
        """The reason the server would give."""
        return self.rejection.reason

    @property
    def id(self) -> int:
        """The id the goal would have named (0 when no goal could be built)."""
        return 0 if self.goal is None else self.goal.id


@attrs.frozen(kw_only=True)
class Outcome(_ClientOutput):
    """What became of one goal of this client: sent once, when the goal is over.

    ``id`` is the event the goal concerns (a NEXT's child, as the result
    names it; a CANCEL's target; a FINISHED's dynamic event, or 0 before it
    ran).  ``status`` is the final status of the result (``""`` when the goal
    never ran).  ``reason`` is known for rejections that carried one and for
    the server's execution-failure strings.  ``goal_status`` and ``result``
    are the terminal answer, ``rejection`` the server's refusal, when there
    was one.
    """

    KIND: ClassVar[str] = "outcome"
    goal_uuid: str
    goal: Goal
    kind: OutcomeKind
    id: int
    status: str
    text: str
    reason: RejectReason | None = None
    execution_failure: str = ""
    goal_status: GoalStatus | None = None
    result: Result | None = None
    rejection: Rejected | None = None


@attrs.frozen(kw_only=True)
class Progress(_ClientOutput):
    """Feedback for one of this client's goals: the child's status, id and new log entries."""

    KIND: ClassVar[str] = "progress"
    goal_uuid: str
    status: str
    id: int
    logs: tuple[LogEntry, ...]


@attrs.frozen(kw_only=True)
class RunBegan(_ClientOutput):
    """A new dynamic event run has begun (first news of its description)."""

    KIND: ClassVar[str] = "run_began"
    seq: int
    description: str


@attrs.frozen(kw_only=True)
class ViewChanged(_ClientOutput):
    """The client's view of the robot changed (a status message was adopted)."""

    KIND: ClassVar[str] = "view_changed"
    phase: DynamicState
    seq: int
    current_id: int
    status: str


@attrs.frozen(kw_only=True)
class TimedOut(_ClientOutput):
    """A NEXT goal reached its deadline while open; the client cancels its child."""

    KIND: ClassVar[str] = "timed_out"
    goal_uuid: str
    id: int
    deadline: int


@attrs.frozen(kw_only=True)
class AskResult(_ClientOutput):
    """Ask the server again for this goal's result (a result request under its goal UUID).

    With ``contact`` (R21.4, R21.5), a server process came into contact that may hold the answer the
    last one could not deliver: a server that does not know the goal is answered as R21.4 says (the
    goal is lost; for a goal whose acceptance was not heard, from the fourth request on).  Without it
    (R21.6), the robot's status showed the goal answered and the answer has not come: a server that
    does not know the goal has not received it yet, and that reply is no answer (the machine asks
    again).  Whatever else the server answers goes to the machine as a
    :class:`~dynevent.client.ResultReceived`."""

    KIND: ClassVar[str] = "ask_result"
    goal_uuid: str
    contact: bool = True


@attrs.frozen(kw_only=True)
class OutOfContact(_ClientOutput):
    """No server process of the robot is in contact since ``since`` (R21.5): whoever waits for an
    answer is told so, and a wait that ends at its bound names this cause."""

    KIND: ClassVar[str] = "out_of_contact"
    since: int


@attrs.frozen(kw_only=True)
class BackInContact(_ClientOutput):
    """A server process of the robot is in contact again at ``now``, after none was since ``since``
    (R21.5); the results of the open goals are asked for again (:class:`AskResult`)."""

    KIND: ClassVar[str] = "back_in_contact"
    since: int
    now: int


#: Any output of the client machine.
ClientOutput: TypeAlias = (
    SendGoal
    | Refused
    | Outcome
    | Progress
    | RunBegan
    | ViewChanged
    | TimedOut
    | Ignored
    | AskResult
    | OutOfContact
    | BackInContact
)
