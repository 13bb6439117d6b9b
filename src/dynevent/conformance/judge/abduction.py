"""Abduction: the input that explains an observation, from a short, fixed list of candidates, and
the outputs that input owes (see the package docs).  Its names are the vocabulary the judges share
(what was seen of a goal, what an input owes, how an output matches a record)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import attrs

from dynevent.conformance.judge.trace import (
    STATUSES,
    TIERS,
    Record,
)
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    ServerConfig,
    State,
)
from dynevent.wire.messages import DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    TASK_SIGNAL_LOGS,
    DynamicState,
    EventType,
    Failure,
    Status,
)

__all__ = [
    "ANSWERED",
    "Found",
    "GoalSeen",
    "Owed",
    "abduce",
    "candidates",
    "confirmed",
    "failure_of",
    "first_line",
    "foreseen",
    "matches_exactly",
    "result_rule",
    "same_status",
    "simulate",
]

# the input behind each task signal's log line (R13.1)
_SIGNALS: dict[str, type[ins.TaskCancel] | type[ins.TaskKill]] = {
    Status.CANCELED.value: ins.TaskCancel,
    Status.KILLED.value: ins.TaskKill,
}


@attrs.define
class GoalSeen:
    """What the trace showed of one goal.  Its judge changes it through its methods alone, each a
    step of the goal's life on the wire."""

    goal: Goal
    line: int
    responded: bool = False
    accepted: bool = False
    answered: int | None = None  # the line of its terminal answer
    order: int = 0  # how many records were judged before its request (a bag's lines are bag times)
    stopped: bool = False  # its answer says its child was cancelled
    owed: bool = False  # dropped from the state on resynchronisation: its answers are not judged
    heard: bool = True  # False: its response was read from its feedback or answer, never heard
    refusable: bool = False  # seen apart: a state the server passed through since its request refuses it

    def respond(self, accepted: bool) -> None:
        """The server answered the request: accepted or refused."""
        self.responded, self.accepted = True, accepted

    def unheard(self) -> None:
        """Its response was never heard: read as accepted from its feedback or answer."""
        self.heard = False

    def refusable_since(self) -> None:
        """Seen apart: a state the server passed through since its request refuses it."""
        self.refusable = True

    def heard_late(self) -> None:
        """The response it was read without came after all, past the records looked ahead."""
        self.heard = True

    def answer(self, line: int, stopped: bool = False) -> None:
        """Its terminal answer came, on ``line``; ``stopped``: it says the child was cancelled."""
        self.answered, self.stopped = line, stopped

    def let_go(self) -> None:
        """The state no longer follows the goal: what it owes is not judged."""
        self.owed = True

    def take_up(self) -> None:
        """The state follows the goal again (a goal from before the trace starts its child)."""
        self.owed = False

    def close(self) -> None:
        """Answered: what is judged after the answer is the line, not the request."""
        self.goal = ANSWERED


#: The goal an answered goal's record keeps: nothing after its answer reads the request itself.
ANSWERED = Goal()


@attrs.frozen
class Owed:
    """An output of an inferred step that has not been observed yet."""

    channel: str
    output: outs.Output
    rule: str
    line: int = 0  # the line whose step owes it
    exact: bool = (
        True  # False: inferred from a status alone, whose answer is owed but whose content is not known
    )
    #: False: a FINISHED's answer owed while the run's own id (its result's id, R11.1) was not known
    id_known: bool = True


def _channel(output: outs.Output) -> str | None:
    if isinstance(output, outs.PublishStatus):
        return "status"
    if isinstance(output, (outs.PublishFeedback, outs.AnswerGoal)):
        return f"goal:{output.goal_uuid}"
    if isinstance(output, outs.CancelResponse):
        return f"cancel:{output.goal_uuid}"
    return None


def failure_of(output: outs.Output) -> Failure | None:
    """The execution failure an answer reports, if it is one of rmf_ros2's."""
    return Failure.of(output.result.execution_failure) if isinstance(output, outs.AnswerGoal) else None


def result_rule(rule: str) -> str:
    """The rule a wrong result breaks: R8.1 for the answers at a child's end, else the answer's own."""
    at_child_end = rule in (machine.CHILD_END_RULE, machine.WAITING_CANCEL_RULE)
    return machine.CHILD_RESULT_RULE if at_child_end else rule


def first_line(text: str) -> str:
    return text.split("\n", 1)[0]


def same_status(a: DynamicEventStatus, b: DynamicEventStatus) -> bool:
    return (a.dynamic_event_seq, a.dynamic_state, a.status, a.id) == (
        b.dynamic_event_seq,
        b.dynamic_state,
        b.status,
        b.id,
    )


def matches_exactly(output: outs.Output, record: Record) -> bool:
    """Does the machine's feedback or answer say what the record says?"""
    if isinstance(output, outs.PublishFeedback):
        feedback: Feedback = record.message
        return (output.feedback.status, output.feedback.id) == (feedback.status, feedback.id)
    if isinstance(output, outs.AnswerGoal):
        result: Result = record.message
        expected = output.result
        return (
            output.status.value,
            expected.id,
            expected.status,
            first_line(expected.execution_failure),
        ) == (
            record.status,
            result.id,
            result.status,
            first_line(result.execution_failure),
        )
    return False


def _same_but_id(output: outs.Output, record: Record) -> bool:
    """Is ``output`` the feedback ``record`` is but for the child's id (a server that numbers children
    itself, D10)?"""
    return isinstance(output, outs.PublishFeedback) and output.feedback.status == record.message.status


def _owes(owed: Owed, record: Record) -> bool:
    """Is ``record`` the owed output?"""
    output = owed.output
    if isinstance(output, outs.PublishStatus):
        return record.kind == "status" and same_status(output.message, record.message)
    if isinstance(output, (outs.PublishFeedback, outs.AnswerGoal)):
        wanted = "feedback" if isinstance(output, outs.PublishFeedback) else "result"
        return (
            record.kind == wanted and record.goal_uuid == output.goal_uuid and matches_exactly(output, record)
        )
    return False


# --------------------------------------------------------------------------- the abducer

#: A candidate that explains an observation: its inputs, the state after them, the outputs it owes
#: and, among them, the one observed.
Found = tuple[list[ins.Input], State, list[Owed], Owed]


def simulate(state: State, events: list[ins.Input], config: ServerConfig) -> tuple[State, list[Owed]]:
    """The state after ``events`` and the observable outputs they owe: the machine's, nothing else."""
    owed: list[Owed] = []
    for event in events:
        transition = machine.step(state, event, config)
        for output in transition.outputs:
            channel = _channel(output)
            if channel is not None:
                owed.append(Owed(channel, output, output.rule))
        state = transition.state
    return state, owed


def candidates(state: State, record: Record, now: int) -> Iterator[list[ins.Input]]:
    """The inputs that may have produced ``record``, most likely first (see the module docs)."""
    running = state.running
    uuid = record.goal_uuid
    if record.kind == "feedback":
        feedback: Feedback = record.message
        texts = [entry.text for entry in feedback.logs]
        if running is not None and running.goal_uuid == uuid:
            for signal_status, signal_text in TASK_SIGNAL_LOGS.items():
                if signal_text in texts:
                    yield [_SIGNALS[signal_status](now=now)]
            if running.started:
                status = feedback.status if feedback.status in STATUSES else running.child_status
                last = feedback.logs[-1] if feedback.logs else None
                tier = last.tier if last is not None and last.tier in TIERS else "info"
                log_text = last.text[: ins.MAX_LOG_TEXT_LENGTH] if last is not None else None
                yield [ins.ChildProgress(status=status, log_text=log_text, tier=tier, now=now)]
                if machine.ends_a_child(status) and not feedback.logs:
                    yield [ins.ChildFinished(status=status, now=now)]  # its end as feedback (R17.7)
            else:
                yield [ins.Resume(now=now)]
        if any(item.goal_uuid == uuid for item in state.queued):
            yield [ins.GoalStarted(goal_uuid=uuid, now=now)]
            if state.interrupted:
                yield [ins.Resume(now=now), ins.GoalStarted(goal_uuid=uuid, now=now)]
            else:
                yield [ins.Interrupt(now=now), ins.GoalStarted(goal_uuid=uuid, now=now)]
        return
    if record.kind == "result":
        result: Result = record.message
        order = [item.goal_uuid for item in state.queued]
        if uuid in order:
            yield [ins.GoalStarted(goal_uuid=uuid, now=now)]
            before = order[: order.index(uuid)]
            if before:  # the goals accepted before it started first (a race it lost, R5.2)
                yield [
                    *(ins.GoalStarted(goal_uuid=first, now=now) for first in before),
                    ins.GoalStarted(goal_uuid=uuid, now=now),
                ]
        if running is not None and running.started:
            final = result.status if result.status in STATUSES else Status.COMPLETED.value
            yield from _child_ended(state, running.child_id, final, now)
        if running is not None and not running.started and running.goal_uuid == uuid:
            for queued in state.queued:  # a CANCEL's start cancels a deferred child at once (R9.4)
                if queued.goal.event_type == EventType.CANCEL:
                    yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now)]
            yield [ins.TaskCancel(now=now)]
            yield [ins.TaskKill(now=now)]
        if first_line(result.execution_failure) == Failure.SHUTDOWN.value:
            yield [ins.Shutdown(now=now)]
        if first_line(result.execution_failure) == Failure.NOT_RUNNING.value and (
            uuid in order or uuid in state.cancels
        ):  # an action-level cancel whose request the records lack (R10.1, R10.2): seen apart only
            yield [ins.CancelRequested(goal_uuid=uuid, now=now)]
        return
    message: DynamicEventStatus = record.message
    for queued in state.queued:
        yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now)]
    if running is not None and running.started and message.status in STATUSES:
        yield [ins.ChildProgress(status=message.status, now=now)]
    if running is not None and not running.started:
        yield [ins.Resume(now=now)]
    if message.status == Status.KILLED.value:
        yield [ins.TaskKill(now=now)]
    if message.status == Status.CANCELED.value or message.dynamic_state == DynamicState.INACTIVE:
        yield [ins.TaskCancel(now=now)]


def _child_ended(state: State, child: int, final: str, now: int) -> Iterator[list[ins.Input]]:
    """The running child ``child`` ended ``final``: of itself, or, ended canceled, stopped by a queued
    CANCEL's start (unseen apart from the server); first by a CANCEL that names it (found dropping
    messages of a 30% run's bag: the status of the child's end lost, its plain end read first, the
    CANCEL's later answer as of one started after it, R9.2)."""
    ended = ins.ChildFinished(status=final, now=now)
    cancels = [
        queued for queued in state.queued
        if queued.goal.event_type == EventType.CANCEL and final == Status.CANCELED.value
    ]  # fmt: skip
    naming = [queued for queued in cancels if queued.goal.id == child]
    for queued in naming:
        yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now), ended]
    yield [ended]
    for queued in cancels:
        if queued not in naming:
            yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now), ended]


def confirmed(found: Found, upcoming: Record | None) -> bool:
    """Does the next record show the next output this candidate owes?"""
    rest = [item for item in found[2] if item is not found[3]]
    return bool(rest) and upcoming is not None and _owes(rest[0], upcoming)


def foreseen(found: Found, ahead: Sequence[Record]) -> bool:
    """Does a record ahead show exactly an answer this candidate owes to another goal?  (Seen away
    from the server, a goal's answer may come many records late: the answer of a CANCEL that stopped
    the child, heard after the next child started.)"""
    rest = [item for item in found[2] if item is not found[3] and isinstance(item.output, outs.AnswerGoal)]
    return any(_owes(item, record) for item in rest for record in ahead)


def abduce(
    state: State,
    config: ServerConfig,
    record: Record,
    now: int,
    ahead: Sequence[Record],
    *,
    apart: bool = False,
) -> Found | None:
    """The first candidate whose first output on the action is this feedback or answer.

    A candidate that reproduces the observation exactly is preferred: of those, one that owes another
    goal's answer a record ahead shows (``ahead``: the records after this one), else one whose next
    output is the next record; else the first whose output is of the same kind for the same goal
    (the differences are then reported).  Seen ``apart`` from the server (a client, a recorder), an
    answer is the first output on its own goal's channel: a goal's answer comes by a service of its
    own, in no order with another goal's feedback or answer.  The abducer only calls the machine.
    """
    channel = f"goal:{record.goal_uuid}"
    kind = outs.PublishFeedback if record.kind == "feedback" else outs.AnswerGoal
    near = None
    exact: list[Found] = []
    for events in candidates(state, record, now):
        if not apart and any(isinstance(event, ins.CancelRequested) for event in events):
            continue  # a tap at the server records every cancel request it takes
        after, owed = simulate(state, events, config)
        if kind is outs.AnswerGoal:  # a feedback owed before the answer (R17.7) may have come already
            owed = [
                item
                for item in owed
                if item.channel != channel or not isinstance(item.output, outs.PublishFeedback)
            ]
        mine = apart and kind is outs.AnswerGoal
        first = next((item for item in owed if item.channel == channel or (
            not mine and item.channel.startswith("goal:"))), None)  # fmt: skip
        if first is None or first.channel != channel or not isinstance(first.output, kind):
            continue
        if matches_exactly(first.output, record):
            exact.append((events, after, owed, first))
        elif near is None or (_same_but_id(first.output, record) > _same_but_id(near[3].output, record)):
            near = (events, after, owed, first)  # one that differs in the child's id alone first (D10)
    # candidates that agree on this record differ in what comes next: let the next record choose
    upcoming = ahead[0] if ahead else None
    for found in exact:
        if foreseen(found, ahead):
            return found
    for found in exact:
        if confirmed(found, upcoming):
            return found
    return exact[0] if exact else near
