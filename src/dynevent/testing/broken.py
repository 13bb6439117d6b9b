"""Deliberately broken servers, for a probe or a judge to catch: each :data:`DEFECTS` entry is one
small change to dynevent's own machine.

A defect is either a change to what the machine decides (a request check that lets through what it
should refuse, a seq that skips), made only while the broken server steps, or a rewrite of the
outputs the machine asks the adapter to carry out (an answer dropped, a status or feedback
changed).  :func:`broken_stepper` is the in-process server of a defect, for
:class:`dynevent.conformance.probe.in_process.InProcessLink`; the test suite's ``broken_serve.py`` puts the
same defects in ``dynevent serve`` over DDS.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import attrs

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.holder import RobotServer
from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, RejectReason, Status, Tier

__all__ = ["DEFECTS", "Defect", "broken_stepper", "patched"]

#: A rewrite of one output: the goals' event types by UUID, what the server has done so far (a
#: dictionary the rewrite keeps its own notes in), and the output; None drops it.
Rewrite = Callable[[Mapping[str, int], dict[str, Any], outs.Output], "outs.Output | None"]


@attrs.frozen
class Defect:
    """One way of breaking the machine: ``patches`` are the machine's functions replaced while it
    steps (by name), ``rewrite`` changes its outputs; ``why`` says what a client sees."""

    why: str
    patches: Mapping[str, Callable[..., Any]] = attrs.field(factory=dict)
    rewrite: Rewrite | None = None


def _accept_despite(reason: RejectReason, only: EventType | None = None) -> dict[str, Callable[..., Any]]:
    """The request check lets through what it should refuse for ``reason`` (for goals of event type
    ``only``, when given: a server that branches on the event type before it checks)."""
    original = machine._decide

    def decide(state: Any, goal: Any, config: Any) -> Any:
        decision, parsed = original(state, goal, config)
        if (
            isinstance(decision, outs.Rejected)
            and decision.reason is reason
            and (only is None or goal.event_type == only)
        ):
            return outs.Accepted(event_type=goal.event_type), parsed
        return decision, parsed

    return {"_decide": decide}


def never_answers_cancel(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """A CANCEL goal is never answered."""
    if isinstance(output, outs.AnswerGoal) and types.get(output.goal_uuid) == EventType.CANCEL:
        return None
    return output


def hangs_next(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """A NEXT whose child completed is never answered."""
    if (
        isinstance(output, outs.AnswerGoal)
        and output.status is GoalStatus.SUCCEEDED
        and types.get(output.goal_uuid) == EventType.NEXT
    ):
        return None
    return output


def running_after_child(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """After a child ends, the status says RUNNING (in standard mode, where it must say WAITING)."""
    if isinstance(output, outs.StartChild):
        notes["ran"] = True
    elif isinstance(output, outs.PublishBegin):
        notes["ran"] = False
    elif (
        isinstance(output, outs.PublishStatus)
        and notes.get("ran", False)
        and output.message.dynamic_state == DynamicState.WAITING
    ):
        completed = Status.COMPLETED.value
        message = attrs.evolve(output.message, dynamic_state=DynamicState.RUNNING, status=completed)
        return attrs.evolve(output, message=message)
    return output


def wrong_feedback_id(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """Every feedback names the id after its child's."""
    if isinstance(output, outs.PublishFeedback):
        return attrs.evolve(output, feedback=attrs.evolve(output.feedback, id=output.feedback.id + 1))
    return output


def ignores_finished(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """FINISHED is answered, but the status never says the run ended."""
    if isinstance(output, outs.PublishStatus) and output.message.dynamic_state == DynamicState.INACTIVE:
        return None
    return output


def ignores_clamp(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """A stubborn period below the minimum is clamped without the warning (the start feedback's)."""
    if isinstance(output, outs.PublishFeedback) and output.feedback.logs:
        logs = tuple(entry for entry in output.feedback.logs if entry.tier != Tier.WARNING.value)
        return attrs.evolve(output, feedback=attrs.evolve(output.feedback, logs=logs))
    return output


def feedback_after_answer(types: Mapping[str, int], notes: dict[str, Any], output: outs.Output) -> Any:
    """A NEXT's answer is followed by one more feedback of its child, without logs (nothing may follow
    an answer, R19.1; no case looks there, the judge over every record does)."""
    if isinstance(output, outs.PublishFeedback):
        notes["feedback"] = output
    elif isinstance(output, outs.AnswerGoal) and types.get(output.goal_uuid) == EventType.NEXT:
        last = notes.get("feedback")
        if last is not None and last.goal_uuid == output.goal_uuid:
            again = attrs.evolve(last, feedback=attrs.evolve(last.feedback, logs=()))
            notes.setdefault("after", []).append(again)
    return output


def _query_names_the_first_id() -> dict[str, Callable[..., Any]]:
    """The description query answers the run's first id (its begin's) where it must answer the current
    one: the child's once a child has run.  A change to the machine's step, which a transport's query
    service calls as the in-process server does."""
    original = machine.step

    def step(state: Any, event: Any, config: Any) -> Any:
        transition = original(state, event, config)
        if not isinstance(event, ins.DescriptionQuery) or not state.active:
            return transition
        outputs = tuple(
            attrs.evolve(output, response=attrs.evolve(output.response, id=state.event_id))
            if isinstance(output, outs.DescriptionAnswer)
            else output
            for output in transition.outputs
        )
        return attrs.evolve(transition, outputs=outputs)

    return {"step": step}


def _ignores_interrupt() -> dict[str, Callable[..., Any]]:
    """The task's interruption changes nothing (R14.2): a NEXT started while the task is interrupted
    starts its child at once, where R6.3 defers it until the resume."""
    original = machine.step

    def step(state: Any, event: Any, config: Any) -> Any:
        if isinstance(event, ins.Interrupt):
            return machine.Transition(state=state, outputs=())
        return original(state, event, config)

    return {"step": step}


DEFECTS: dict[str, Defect] = {
    "skips_seq": Defect(
        "each run's seq is the last one's plus 2 (runs 1, 3, 5)",
        {"next_seq": lambda seq: (seq + 2) % 2**32},
    ),
    "accepts_stale_seq": Defect(
        "a goal for another run is accepted", _accept_despite(RejectReason.SEQ_MISMATCH)
    ),
    "accepts_stale_next": Defect(
        "a NEXT for another run is accepted", _accept_despite(RejectReason.SEQ_MISMATCH, EventType.NEXT)
    ),
    "accepts_stale_cancel": Defect(
        "a CANCEL for another run is accepted",
        _accept_despite(RejectReason.SEQ_MISMATCH, EventType.CANCEL),
    ),
    "accepts_cancel_after_the_run": Defect(
        "a CANCEL after the run ended is accepted", _accept_despite(RejectReason.INACTIVE, EventType.CANCEL)
    ),
    "accepts_unknown_category": Defect(
        "a NEXT of a category the robot lacks is accepted",
        _accept_despite(RejectReason.UNSUPPORTED_CATEGORY),
    ),
    "accepts_when_busy": Defect("a goal while a child runs is accepted", _accept_despite(RejectReason.BUSY)),
    "never_answers_cancel": Defect("a CANCEL goal is never answered", rewrite=never_answers_cancel),
    "hangs_next": Defect("a NEXT whose child completed is never answered", rewrite=hangs_next),
    "running_after_child": Defect("the status says RUNNING after a child ended", rewrite=running_after_child),
    "wrong_feedback_id": Defect("feedback names the wrong child", rewrite=wrong_feedback_id),
    "ignores_finished": Defect("the status never says the run ended", rewrite=ignores_finished),
    "ignores_clamp": Defect("a clamped stubborn period is not warned of", rewrite=ignores_clamp),
    "query_names_the_first_id": Defect(
        "the description query names the run's first id, not the current one", _query_names_the_first_id()
    ),
    "ignores_interrupt": Defect(
        "the task's interruption is ignored: a NEXT's child starts at once", _ignores_interrupt()
    ),
    "feedback_after_answer": Defect(
        "one more feedback follows a NEXT's answer", rewrite=feedback_after_answer
    ),
}


@contextlib.contextmanager
def patched(patches: Mapping[str, Any]) -> Iterator[None]:
    """The machine's module attributes named in ``patches`` replaced while the block runs, then put
    back (one thread)."""
    saved = {name: getattr(machine, name) for name in patches}
    for name, function in patches.items():
        setattr(machine, name, function)
    try:
        yield
    finally:
        for name, function in saved.items():
            setattr(machine, name, function)


def broken_stepper(server: RobotServer, defect: str) -> Callable[[ins.Input], tuple[outs.Output, ...]]:
    """``server``'s step with ``defect`` in it: the machine's functions replaced while it steps, and its
    outputs rewritten (a feedback the defect sends after an answer comes right after it)."""
    broken = DEFECTS[defect]
    types: dict[str, int] = {}
    notes: dict[str, Any] = {}

    def step(event: ins.Input) -> tuple[outs.Output, ...]:
        if isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)):
            types[event.goal_uuid] = event.goal.event_type
        with patched(broken.patches):
            outputs = server.step(event)
        if broken.rewrite is None:
            return outputs
        kept: list[outs.Output] = []
        for output in outputs:
            changed = broken.rewrite(types, notes, output)
            if changed is not None:
                kept.append(changed)
            kept.extend(notes.pop("after", ()))
        return tuple(kept)

    return step
