"""``dynevent explain``: would this goal be accepted by a robot whose status message is this, and if not, why?

A ``DynamicEventStatus`` message tells the seq, the phase and the current id
(the dynamic event's own id while WAITING, the running child's while
RUNNING).  :func:`state_from_status` rebuilds the server state those allow;
:func:`explain` runs :func:`dynevent.server.machine.accept` on it, and when the goal
is refused, says which check refused it (reason code, sentence, values, rule)
and what to send instead, re-checking each correction until one passes.

What a status message cannot tell is said, not guessed: the robot's
categories and their description schemas (unless ``categories`` are given),
the highest id used in the run (R4.12), whether the server is shutting down
(R4.1), and what other goals are in flight (an accepted goal can still lose
a race, R5.2).
"""

from __future__ import annotations

import json
from typing import Any

import attrs

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import UNKNOWN_GOAL, ServerConfig, State, state_from_status
from dynevent.wire._fields import U32_MAX
from dynevent.wire._text import goal_text, status_text
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import (
    Compatibility,
    DynamicState,
    EventType,
    Failure,
    GoalStatus,
    RejectReason,
    Status,
)

__all__ = [
    "UNKNOWN_GOAL",
    "Explanation",
    "explain",
    "format_explanation",
    "goal_text",
    "state_from_status",
    "status_text",
]

_CANDIDATE = "0" * 31 + "1"  # the goal under examination, in the simulated server
_STATUSES = frozenset(status.value for status in Status)


@attrs.frozen(kw_only=True)
class Explanation:
    """What :func:`explain` found.

    ``decision`` is the machine's; ``rule`` the docs/spec.md rule that
    decided.  ``at_start`` says what the goal does when it starts right after
    its acceptance (``""`` when refused), ``aborted_at_start`` whether it is
    then aborted (rmf_ros2 mode accepts goals that fail there).  ``then`` are
    the refusals met after correcting the first, in order; ``instead`` the
    goal to send (re-checked: the machine accepts it), if one can be given,
    and ``advice`` what to do, in words.  ``unknown`` lists what the status
    message cannot tell.  ``consistent`` is false when the status message is
    not one a conforming server publishes (R2.2), with the reason in
    ``inconsistency``.
    """

    status: DynamicEventStatus
    goal: Goal
    decision: outs.Decision
    rule: str
    at_start: str
    aborted_at_start: bool
    then: tuple[outs.Rejected, ...]
    instead: Goal | None
    advice: str
    unknown: tuple[str, ...]
    inconsistency: str

    @property
    def accepted(self) -> bool:
        """The goal is accepted and begins (exit status 0 of ``dynevent explain``)."""
        return isinstance(self.decision, outs.Accepted) and not self.aborted_at_start

    def to_dict(self) -> dict[str, Any]:
        """The explanation as plain JSON values."""
        decision = self.decision
        verdict = "rejected"
        if isinstance(decision, outs.Accepted):
            verdict = "aborted_at_start" if self.aborted_at_start else "accepted"
        return {
            "verdict": verdict,
            "rule": self.rule,
            "reason": decision.reason.value if isinstance(decision, outs.Rejected) else None,
            "text": decision.text if isinstance(decision, outs.Rejected) else "",
            "values": _values(decision) if isinstance(decision, outs.Rejected) else {},
            "execution_failure": decision.execution_failure if isinstance(decision, outs.Rejected) else "",
            "at_start": self.at_start,
            "then": [
                {"reason": later.reason.value, "rule": later.rule, "text": later.text} for later in self.then
            ],
            "instead": None if self.instead is None else self.instead.to_dict(),
            "advice": self.advice,
            "unknown": list(self.unknown),
            "consistent": not self.inconsistency,
            "inconsistency": self.inconsistency,
            "status": self.status.to_dict(),
            "goal": self.goal.to_dict(),
        }


def _values(rejection: outs.Rejected) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for name in ("expected_seq", "received_seq", "current_id", "requested_id"):
        value = getattr(rejection, name)
        if value is not None:
            values[name] = value
    if rejection.categories:
        values["categories"] = list(rejection.categories)
    if rejection.errors:
        values["errors"] = list(rejection.errors)
    return values


def _inconsistency(message: DynamicEventStatus) -> str:
    phase = message.dynamic_state
    if phase not in (0, 1, 2):
        return f"dynamic_state {phase} is none of INACTIVE (0), WAITING (1), RUNNING (2)"
    if phase == DynamicState.INACTIVE and (message.status != Status.UNINITIALIZED.value or message.id != 0):
        return "an INACTIVE status message always says status 'uninitialized' and id 0 (R2.2)"
    if message.status not in _STATUSES:
        return f"status {message.status!r} is none of the 12 task statuses"
    return ""


def _start(state: State, goal: Goal, config: ServerConfig) -> tuple[str, bool]:
    """What the accepted goal does when it starts at once: a sentence, and whether it is aborted."""
    now = 0
    requested = machine.step(state, ins.GoalRequested(goal_uuid=_CANDIDATE, goal=goal, now=now), config)
    started = machine.step(requested.state, ins.GoalStarted(goal_uuid=_CANDIDATE, now=now), config)
    for output in started.outputs:
        if isinstance(output, outs.AnswerGoal) and output.goal_uuid == _CANDIDATE:
            result = output.result
            if output.status is GoalStatus.ABORTED:
                failure = result.execution_failure.split("\n", 1)[0]
                return f"it is aborted when it starts: {failure!r} ({output.rule})", True
            if goal.event_type == EventType.CANCEL:
                return (
                    f"the deferred child {result.id} is cancelled at once; the goal succeeds with status "
                    f"{result.status!r} ({output.rule})",
                    False,
                )
            return (
                f"the dynamic event ends: the goal succeeds with status {result.status!r} and id "
                f"{result.id} ({output.rule})",
                False,
            )
    clamp = ""
    for output in started.outputs:
        if isinstance(output, outs.StubbornClamped):
            clamp = (
                f"; its stubborn period of {output.requested:g} s will be raised to "
                f"{output.applied:g} s, with a warning ({output.rule})"
            )
    for output in started.outputs:
        if isinstance(output, outs.StartChild):
            return f"child {output.id} starts ({output.rule}){clamp}", False
        if isinstance(output, outs.PublishFeedback) and output.feedback.status == Status.QUEUED.value:
            return (
                f"child {output.feedback.id} is deferred until the task resumes ({output.rule}){clamp}",
                False,
            )
        if isinstance(output, outs.CancelChild):
            return (
                f"child {output.id} is told to cancel; "
                f"the goal is answered when the child ends ({output.rule})",
                False,
            )
    if goal.event_type == EventType.CANCEL:
        return "the child is already stopping; the goal is answered when it ends (R9.3)", False
    return "", False


def _fix(state: State, goal: Goal, rejection: outs.Rejected) -> tuple[Goal | None, str, bool]:
    """A corrected goal (or ``None``), the advice, and whether to keep correcting it."""
    reason = rejection.reason
    running = state.running
    if reason is RejectReason.SEQ_MISMATCH:
        if state.active:
            return attrs.evolve(goal, dynamic_event_seq=state.seq), f"use the run's seq, {state.seq}", True
        return None, _no_run(state), False
    if reason is RejectReason.INACTIVE:
        return None, _no_run(state), False
    if reason in (RejectReason.UNINITIALIZED_EVENT_TYPE, RejectReason.UNKNOWN_EVENT_TYPE):
        return None, "set event_type to 1 (NEXT), 2 (CANCEL) or 3 (FINISHED)", False
    if reason is RejectReason.BUSY and running is not None:
        cancel = Goal(dynamic_event_seq=state.seq, event_type=EventType.CANCEL, id=running.child_id)
        return (
            cancel,
            f"event {running.child_id} is running: CANCEL it first (the goal above), or wait until the "
            "status says WAITING, then send the goal again",
            False,
        )
    if reason is RejectReason.UNSUPPORTED_CATEGORY:
        supported = ", ".join(rejection.categories) or "none"
        unquoted = _unquoted(goal.category)
        if unquoted is not None and unquoted in rejection.categories:
            return (
                attrs.evolve(goal, category=unquoted),
                f"the category is JSON-quoted ({goal.category}): a category is a plain name, {unquoted}",
                True,
            )
        return None, f"use one of the robot's categories: {supported}", False
    if reason is RejectReason.DESCRIPTION_NOT_JSON:
        quoted = json.dumps(goal.description, ensure_ascii=False)
        return (
            attrs.evolve(goal, description=quoted),
            "the description is JSON text: a plain name is written in quotes",
            True,
        )
    if reason is RejectReason.NON_FINITE_STUBBORN_PERIOD:
        return attrs.evolve(goal, stubborn_period=0.0), "give a finite stubborn_period (0 for none)", True
    if reason is RejectReason.STALE_ID:
        fresh = machine.fresh_id(state.last_id)
        if fresh is None:
            return None, f"no id is left above {state.last_id} in this run: FINISH it, begin another", False
        return (
            attrs.evolve(goal, id=fresh),
            f"give the NEXT a fresh id, above every id used in the run (at least {fresh}), "
            "or id 0 to let the server choose it",
            True,
        )
    if reason is RejectReason.CANCEL_IDLE:
        return None, "nothing is running: there is nothing to cancel", False
    if reason is RejectReason.CANCEL_ID_MISMATCH and running is not None:
        return (
            attrs.evolve(goal, id=running.child_id),
            f"a CANCEL names the running event, {running.child_id}",
            True,
        )
    return None, rejection.text, False


def _unquoted(category: str) -> str | None:
    """The name inside a JSON-quoted category (``"go_to_place"`` with its quotes), else None."""
    if not (category.startswith('"') and category.endswith('"')):
        return None
    try:
        name = json.loads(category)
    except ValueError:
        return None
    return name if isinstance(name, str) else None


def _no_run(state: State) -> str:
    if state.active:
        return f"the run's seq is {state.seq}"
    return (
        "no dynamic event is active: wait for the next begin "
        f"(it will carry seq {(state.seq + 1) & U32_MAX}) and its WAITING status"
    )


def _unknowns(state: State, goal: Goal, decision: outs.Decision, categories_known: bool) -> list[str]:
    unknown = ["whether the server is shutting down (R4.1)"]
    next_goal = goal.event_type == EventType.NEXT
    if next_goal and not categories_known:
        unknown.append(
            f"the robot's categories: a status message does not list them, so {goal.category!r} was "
            "taken as supported (give --categories)"
        )
    if next_goal:
        unknown.append(
            "whether the description fits its category's schema: only its JSON was checked (R4.10)"
        )
    if isinstance(decision, outs.Accepted):
        unknown.append("goals accepted before this one: one that starts first makes it lose the race (R5.2)")
    running = state.running
    if running is not None and not running.started:
        unknown.append(
            f"whether child {running.child_id} is deferred by an interruption (R6.3), as taken here, or "
            "has started and reported 'queued': a status message shows both alike"
        )
    if goal.event_type == EventType.CANCEL and state.running is not None:
        unknown.append(
            "whether the child ends before the CANCEL starts: it is then aborted with "
            f"{Failure.IDLE_CANCEL.value!r} (R9.1)"
        )
    return unknown


def explain(
    status: DynamicEventStatus,
    goal: Goal,
    *,
    categories: tuple[str, ...] | None = None,
    compatibility: Compatibility | str = Compatibility.STANDARD,
) -> Explanation:
    """Would a robot whose last status message is ``status`` accept ``goal``?  See the module docs.

    Without ``categories`` the goal's own category is taken as supported.
    ``compatibility="rmf_ros2"`` judges as rmf_ros2 does (R17): bad event
    types and CANCELs are accepted, then aborted when they start.
    """
    compatibility = Compatibility(compatibility)
    inconsistency = _inconsistency(status)
    fallback = (
        attrs.evolve(status, dynamic_state=DynamicState.INACTIVE) if status.dynamic_state > 2 else status
    )
    state = state_from_status(fallback)
    names = categories if categories is not None else ((goal.category,) if goal.category else ())
    validators = dict.fromkeys(names, machine.any_description)
    if compatibility is Compatibility.RMF_ROS2:
        config = ServerConfig.rmf_ros2(validators)
    else:
        config = ServerConfig(categories=validators)
    decision = machine.accept(state, goal, config)
    strict = ServerConfig(categories=validators)  # the standard's checks, which rmf_ros2 defers (R17.1)
    at_start, aborted = "", False
    then: tuple[outs.Rejected, ...] = ()
    if isinstance(decision, outs.Accepted):
        at_start, aborted = _start(state, goal, config)
        instead, advice = _instead_of_an_abort(state, goal, strict) if aborted else (None, "")
    else:
        then, instead, advice = _corrections(state, goal, decision, strict)
    return Explanation(
        status=status,
        goal=goal,
        decision=decision,
        rule=decision.rule,
        at_start=at_start,
        aborted_at_start=aborted,
        then=then,
        instead=instead,
        advice=advice,
        unknown=tuple(_unknowns(state, goal, decision, categories is not None)),
        inconsistency=inconsistency,
    )


def _instead_of_an_abort(state: State, goal: Goal, strict: ServerConfig) -> tuple[Goal | None, str]:
    """A goal rmf_ros2 accepts and aborts at its start: the standard's refusal, and its correction."""
    advice = "see the refusal above: standard servers refuse this goal at once"
    refusal = machine.accept(state, goal, strict)
    if not isinstance(refusal, outs.Rejected):
        return None, advice
    instead, fix, _ = _fix(state, goal, refusal)
    return instead, f"{refusal.reason.value}: {refusal.text}; {fix}"


def _corrections(
    state: State, goal: Goal, decision: outs.Rejected, strict: ServerConfig
) -> tuple[tuple[outs.Rejected, ...], Goal | None, str]:
    """The refusals after the first, the corrected goal (``None`` when none is accepted), the advice.

    A correction must begin, not only be accepted: it is checked as the standard does (rmf_ros2
    aborts at start exactly the goals the standard refuses, R17.1).
    """
    then: list[outs.Rejected] = []
    instead, advice, keep = _fix(state, goal, decision)
    for _ in range(8):  # each correction removes one refusal; there are fewer than eight kinds
        if instead is None or not keep:
            break
        later = machine.accept(state, instead, strict)
        if isinstance(later, outs.Accepted):
            break
        then.append(later)
        fixed, more, keep = _fix(state, instead, later)
        advice = f"{advice}; then {more}"
        instead = fixed
    if instead is not None and not isinstance(machine.accept(state, instead, strict), outs.Accepted):
        instead = None
    return tuple(then), instead, advice


def format_explanation(explanation: Explanation) -> str:
    """The explanation as aligned text."""
    lines = [f"robot:    {status_text(explanation.status)}", f"goal:     {goal_text(explanation.goal)}"]
    if explanation.inconsistency:
        lines.append(f"warning:  this status message is inconsistent: {explanation.inconsistency}")
    decision = explanation.decision
    if isinstance(decision, outs.Rejected):
        lines.append(f"verdict:  rejected: {decision.reason.value} ({explanation.rule})")
        lines.append(f"why:      {decision.text}")
        values = _values(decision)
        if values:
            lines.append("values:   " + ", ".join(f"{name}={value}" for name, value in values.items()))
        if decision.execution_failure:
            first = decision.execution_failure.split("\n", 1)[0]
            lines.append(f"rmf_ros2: {first!r}")
        for later in explanation.then:
            lines.append(f"then:     {later.reason.value} ({later.rule}): {later.text}")
    elif explanation.aborted_at_start:
        lines.append(f"verdict:  accepted ({explanation.rule}), then aborted")
        lines.append(f"start:    {explanation.at_start}")
    else:
        lines.append(f"verdict:  accepted ({explanation.rule})")
        if explanation.at_start:
            lines.append(f"start:    {explanation.at_start}")
    if explanation.instead is not None:
        lines.append(f"instead:  {explanation.instead.to_json()}")
        lines.append(f"          ({goal_text(explanation.instead)})")
    if explanation.advice:
        lines.append(f"advice:   {explanation.advice}")
    lines.append("unknown:  " + explanation.unknown[0])
    lines.extend(f"          {item}" for item in explanation.unknown[1:])
    return "\n".join(lines) + "\n"
