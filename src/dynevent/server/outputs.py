"""What the server machine asks the adapter to do: its outputs, as values.

:func:`dynevent.server.machine.step` returns a tuple of these, in the order the
adapter (or a ROS binding) must carry them out.  They are plain frozen data:
the machine builds them from already-checked state, so they carry no
validation of their own.

Three families:

- answers on the action: :class:`GoalAccepted`, :class:`GoalRejected`,
  :class:`CancelResponse`, :class:`ExecuteGoal`, :class:`PublishFeedback`,
  :class:`AnswerGoal`;
- publications and effects on the robot: :class:`PublishBegin`,
  :class:`PublishStatus`, the child commands, the stubbornness commands,
  :class:`DynamicEventFinished`, :class:`InterruptConfirmed`,
  :class:`DescriptionAnswer`;
- notices: :class:`SeqWrapped`, :class:`StubbornClamped`, :class:`Log`,
  :class:`Ignored`.

Every output, and every :class:`Rejected`, carries ``rule``: the number of
the docs/spec.md rule that produced it (``"R8.2"``).  The rule says *why*,
not *what*: it takes no part in equality or hashing and is not written to
traces or conformance vectors, so two outputs that ask the adapter for the
same thing are equal whichever rule asked.  Tools (``check``, ``explain``,
the client, the test kit) read it instead of working the rule out again.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeAlias

import attrs

from dynevent.wire._fields import ANNOTATION, fast_init
from dynevent.wire.messages import (
    DescriptionResponse,
    DynamicEventDescription,
    DynamicEventStatus,
    Feedback,
    LogEntry,
    Result,
)
from dynevent.wire.vocab import GoalStatus, RejectReason

__all__ = [
    "OUTPUT_TYPES",
    "Accepted",
    "AnswerGoal",
    "CancelChild",
    "CancelResponse",
    "Decision",
    "DescriptionAnswer",
    "DynamicEventFinished",
    "ExecuteGoal",
    "GoalAccepted",
    "GoalRejected",
    "Ignored",
    "InterruptChild",
    "InterruptConfirmed",
    "KillChild",
    "Log",
    "Output",
    "PublishBegin",
    "PublishFeedback",
    "PublishStatus",
    "Rejected",
    "ResumeChild",
    "SeqWrapped",
    "StartChild",
    "StubbornBegin",
    "StubbornClamped",
    "StubbornDelay",
    "StubbornEnd",
    "StubbornHold",
]


def _rule() -> Any:
    return attrs.field(default="", eq=False, metadata={ANNOTATION: True})


@fast_init
@attrs.frozen(kw_only=True)
class _Output:
    #: The name of this output in traces and vectors.
    KIND: ClassVar[str] = ""

    #: The docs/spec.md rule that produced this output (an annotation: see the module docs).
    rule: str = _rule()


@fast_init
@attrs.frozen(kw_only=True)
class Accepted:
    """:func:`~dynevent.server.machine.accept` says yes; ``rule`` is R4.16, or R17.1 when only the
    ``rmf_ros2`` mode lets the goal in (it is then aborted when it starts)."""

    event_type: int
    rule: str = _rule()


@fast_init
@attrs.frozen(kw_only=True)
class Rejected:
    """:func:`~dynevent.server.machine.accept` says no, and why.

    ``reason`` is the closed code; ``text`` a human sentence.  The other fields
    carry the values that explain the refusal where they apply (``None`` or
    empty otherwise): the expected and received seq, the running child's id
    and the requested id, the supported categories, the parse or validation
    errors.  ``execution_failure`` is the exact failure string rmf_ros2 uses
    for the same fault, where it has one, so a ROS binding can log or return
    it verbatim.  ``rule`` is the docs/spec.md rule that refused it (an
    annotation, as on every output).
    """

    reason: RejectReason
    text: str
    expected_seq: int | None = None
    received_seq: int | None = None
    current_id: int | None = None
    requested_id: int | None = None
    categories: tuple[str, ...] = ()
    errors: tuple[str, ...] = ()
    execution_failure: str = ""
    rule: str = _rule()


#: What :func:`~dynevent.server.machine.accept` returns.
Decision: TypeAlias = Accepted | Rejected


@fast_init
@attrs.frozen(kw_only=True)
class GoalAccepted(_Output):
    """Accept the goal request (``handle_goal`` returns ACCEPT)."""

    KIND: ClassVar[str] = "goal_accepted"
    goal_uuid: str


@fast_init
@attrs.frozen(kw_only=True)
class GoalRejected(_Output):
    """Reject the goal request (``handle_goal`` returns REJECT); ``rejection`` says why."""

    KIND: ClassVar[str] = "goal_rejected"
    goal_uuid: str
    rejection: Rejected


@fast_init
@attrs.frozen(kw_only=True)
class CancelResponse(_Output):
    """Answer an action-level cancel request (``handle_cancel``)."""

    KIND: ClassVar[str] = "cancel_response"
    goal_uuid: str
    accepted: bool


@fast_init
@attrs.frozen(kw_only=True)
class ExecuteGoal(_Output):
    """Move the accepted goal to *executing* (``goal_handle.execute()``)."""

    KIND: ClassVar[str] = "execute_goal"
    goal_uuid: str


@fast_init
@attrs.frozen(kw_only=True)
class PublishFeedback(_Output):
    """Publish feedback to the goal."""

    KIND: ClassVar[str] = "publish_feedback"
    goal_uuid: str
    feedback: Feedback


@fast_init
@attrs.frozen(kw_only=True)
class AnswerGoal(_Output):
    """The goal's one terminal answer: succeed, abort or cancel it with ``result``."""

    KIND: ClassVar[str] = "answer_goal"
    goal_uuid: str
    status: GoalStatus
    result: Result


@fast_init
@attrs.frozen(kw_only=True)
class PublishBegin(_Output):
    """Publish the begin description on ``rmf/dynamic_event/begin`` and the robot's begin topic."""

    KIND: ClassVar[str] = "publish_begin"
    message: DynamicEventDescription


@fast_init
@attrs.frozen(kw_only=True)
class PublishStatus(_Output):
    """Publish the robot's dynamic event status."""

    KIND: ClassVar[str] = "publish_status"
    message: DynamicEventStatus


@fast_init
@attrs.frozen(kw_only=True)
class StartChild(_Output):
    """Start a child event of ``category`` with this description and ``id``.

    ``description`` is the goal's JSON text; ``parsed`` the same, parsed
    (excluded from hashing, as JSON values may be unhashable).
    """

    KIND: ClassVar[str] = "start_child"
    category: str
    description: str
    id: int
    parsed: Any = attrs.field(hash=False)


@fast_init
@attrs.frozen(kw_only=True)
class CancelChild(_Output):
    """Tell the running child to cancel."""

    KIND: ClassVar[str] = "cancel_child"
    id: int


@fast_init
@attrs.frozen(kw_only=True)
class KillChild(_Output):
    """Tell the running child to stop at once (the task was killed)."""

    KIND: ClassVar[str] = "kill_child"
    id: int


@fast_init
@attrs.frozen(kw_only=True)
class InterruptChild(_Output):
    """Hand the task's interruption to the running child."""

    KIND: ClassVar[str] = "interrupt_child"
    id: int


@fast_init
@attrs.frozen(kw_only=True)
class ResumeChild(_Output):
    """Release the interruption handed to the running child."""

    KIND: ClassVar[str] = "resume_child"
    id: int


@fast_init
@attrs.frozen(kw_only=True)
class StubbornBegin(_Output):
    """Become a stubborn negotiator and declare a hold of ``period`` seconds from ``since``.

    The hold is at the last position a tick reported (``map_name``, ``x``,
    ``y``), or at the robot's current position when no tick has reported one
    (``map_name`` is then ``None``).
    """

    KIND: ClassVar[str] = "stubborn_begin"
    period: float
    since: int
    map_name: str | None
    x: float
    y: float


@fast_init
@attrs.frozen(kw_only=True)
class StubbornHold(_Output):
    """The robot moved or changed map: declare a new hold of ``period`` seconds there, from ``since``."""

    KIND: ClassVar[str] = "stubborn_hold"
    period: float
    since: int
    map_name: str
    x: float
    y: float


@fast_init
@attrs.frozen(kw_only=True)
class StubbornDelay(_Output):
    """The robot held still: report ``delay`` seconds of cumulative delay since the hold began."""

    KIND: ClassVar[str] = "stubborn_delay"
    delay: float


@fast_init
@attrs.frozen(kw_only=True)
class StubbornEnd(_Output):
    """Stop being stubborn and release the hold."""

    KIND: ClassVar[str] = "stubborn_end"


@fast_init
@attrs.frozen(kw_only=True)
class DynamicEventFinished(_Output):
    """The dynamic event is over with ``status``; the task may move on."""

    KIND: ClassVar[str] = "dynamic_event_finished"
    status: str


@fast_init
@attrs.frozen(kw_only=True)
class InterruptConfirmed(_Output):
    """The task's interruption took effect (no child was running to hand it to)."""

    KIND: ClassVar[str] = "interrupt_confirmed"


@fast_init
@attrs.frozen(kw_only=True)
class DescriptionAnswer(_Output):
    """The answer to a description query."""

    KIND: ClassVar[str] = "description_answer"
    response: DescriptionResponse


@fast_init
@attrs.frozen(kw_only=True)
class SeqWrapped(_Output):
    """Notice: the dynamic event seq wrapped from ``previous`` (2**32 - 1) to ``seq`` (0)."""

    KIND: ClassVar[str] = "seq_wrapped"
    previous: int
    seq: int


@fast_init
@attrs.frozen(kw_only=True)
class StubbornClamped(_Output):
    """Notice: a stubborn period below the minimum was raised to it."""

    KIND: ClassVar[str] = "stubborn_clamped"
    requested: float
    applied: float


@fast_init
@attrs.frozen(kw_only=True)
class Log(_Output):
    """A log entry for the task's log (also carried by feedback when a goal runs)."""

    KIND: ClassVar[str] = "log"
    entry: LogEntry


@fast_init
@attrs.frozen(kw_only=True)
class Ignored(_Output):
    """Notice: the input had no effect, and why (e.g. a child report with no child running)."""

    KIND: ClassVar[str] = "ignored"
    input: str
    why: str


#: Any output of the server machine.
Output: TypeAlias = (
    GoalAccepted
    | GoalRejected
    | CancelResponse
    | ExecuteGoal
    | PublishFeedback
    | AnswerGoal
    | PublishBegin
    | PublishStatus
    | StartChild
    | CancelChild
    | KillChild
    | InterruptChild
    | ResumeChild
    | StubbornBegin
    | StubbornHold
    | StubbornDelay
    | StubbornEnd
    | DynamicEventFinished
    | InterruptConfirmed
    | DescriptionAnswer
    | SeqWrapped
    | StubbornClamped
    | Log
    | Ignored
)

#: Every output class, by its ``KIND``.
OUTPUT_TYPES: dict[str, type[Output]] = {
    cls.KIND: cls
    for cls in (
        GoalAccepted,
        GoalRejected,
        CancelResponse,
        ExecuteGoal,
        PublishFeedback,
        AnswerGoal,
        PublishBegin,
        PublishStatus,
        StartChild,
        CancelChild,
        KillChild,
        InterruptChild,
        ResumeChild,
        StubbornBegin,
        StubbornHold,
        StubbornDelay,
        StubbornEnd,
        DynamicEventFinished,
        InterruptConfirmed,
        DescriptionAnswer,
        SeqWrapped,
        StubbornClamped,
        Log,
        Ignored,
    )
}
