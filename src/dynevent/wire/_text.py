"""One-line renderings of goals, status messages and answers: one home for explain, check and the
simulated session."""

from __future__ import annotations

from dynevent.wire.messages import DynamicEventStatus, Goal, Result
from dynevent.wire.vocab import DynamicState, EventType

__all__ = ["answer_text", "goal_text", "status_text"]


def status_text(message: DynamicEventStatus) -> str:
    """One line for a status message: ``RUNNING seq=3 id=8 underway``."""
    try:
        phase = DynamicState(message.dynamic_state).name
    except ValueError:
        phase = f"dynamic_state={message.dynamic_state}"
    return f"{phase} seq={message.dynamic_event_seq} id={message.id} {message.status}"


def goal_text(goal: Goal) -> str:
    """One line for a goal: ``NEXT seq=1 id=6 go_to_place "pantry" stubborn=0.5``."""
    try:
        name = EventType(goal.event_type).name
    except ValueError:
        name = f"event_type={goal.event_type}"
    text = f"{name} seq={goal.dynamic_event_seq}"
    if goal.event_type != EventType.FINISHED:
        text += f" id={goal.id}"
    if goal.event_type == EventType.NEXT:
        text += f" {goal.category} {goal.description}"
        if goal.stubborn_period != 0.0:
            text += f" stubborn={goal.stubborn_period:g}"
    return text


def answer_text(status: str, result: Result, *, first_line: bool = False) -> str:
    """One line for a goal's terminal answer: ``succeeded: completed id=6`` or ``aborted: race condition``.

    ``first_line`` keeps only the first line of an execution failure, quoted.
    """
    failure = result.execution_failure
    if not failure:
        return f"{status}: {result.status} id={result.id}"
    if first_line:
        first = failure.split("\n", 1)[0]
        return f"{status}: {first!r}"
    return f"{status}: {failure}"
