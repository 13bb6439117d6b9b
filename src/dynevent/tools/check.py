"""``dynevent check``: replay an observed trace of one robot against the machine, in observer mode.

A trace (docs/trace-format.md) is what was seen on the wire for one robot:
begin and status messages, goal requests with their UUIDs, goal responses,
feedback, terminal answers and action-level cancels, each with its time.
The observer keeps a server state (:class:`dynevent.server.machine.State`) and
infers the server's inputs from what it sees:

- a ``begin`` is a ``Begin`` input (the event id arrives with the status
  message that follows);
- a ``goal`` and its ``goal_response`` are a ``GoalRequested`` input: the
  machine's decision is compared with the response;
- every other observation must be an output of the machine.  An
  observation the machine already owes (an output of an inferred step not
  seen yet) is compared with it.  Otherwise the observer *abduces* the
  input that produced it from a short, fixed list of candidates: the start
  of an accepted goal (``GoalStarted``), a child's progress (``ChildProgress``,
  from feedback), a child's end (``ChildFinished``, from the running goal's
  answer), a task cancel or kill, an interruption or a resume, a shutdown.
  The first candidate whose first output on the action (or whose status
  message) is the observation is taken; its other outputs are owed.

When no candidate explains an observation, or the machine's output differs
from it, the observer reports a :class:`Finding` (line, docs/spec.md rule,
code, what was seen, what was expected), then resynchronises with the
smallest change that makes the state agree with what the server evidently
did (it queues a goal the server accepted, starts a NEXT whose feedback
shows it running, forgets goals the server displaced), so that one fault is
reported once and later records are judged against the server's real
condition.

:func:`check_trace` is the API; :func:`read_trace` parses a trace and raises
:class:`TraceError` (naming the source, line and field) on unreadable input.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import math
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import attrs

from dynevent.conformance.records import InvalidRecord, config_from_json
from dynevent.errors import (
    InvalidMessage,
    TraceError,  # defined there with every error; importable here too
)
from dynevent.server import inputs as ins
from dynevent.server import machine, resync
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    UNKNOWN_GOAL,
    ServerConfig,
    State,
    state_from_status,
)
from dynevent.tools._progress import Progress
from dynevent.wire import _json
from dynevent.wire._fields import SECOND, U32_MAX, seq_after
from dynevent.wire._text import answer_text, goal_text, status_text
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    DynamicState,
    EventType,
    Failure,
    GoalStatus,
    IdPolicy,
    RejectReason,
    Status,
    Tier,
    Violation,
)

__all__ = [
    "RECORD_TYPES",
    "Finding",
    "Record",
    "Report",
    "TraceError",
    "check_records",
    "check_trace",
    "format_report",
    "read_trace",
    "step_records",
    "trace_records",
]

#: The record types of a trace, and the fields each may hold besides ``type`` and ``time``.
RECORD_TYPES: dict[str, frozenset[str]] = {
    "config": frozenset({"fleet", "robot", "config"}),
    "begin": frozenset({"message"}),
    "status": frozenset({"message"}),
    "goal": frozenset({"goal_uuid", "goal"}),
    "goal_response": frozenset({"goal_uuid", "accepted", "reason"}),
    "feedback": frozenset({"goal_uuid", "feedback"}),
    "result": frozenset({"goal_uuid", "status", "result"}),
    "cancel_request": frozenset({"goal_uuid"}),
    "cancel_response": frozenset({"goal_uuid", "accepted"}),
}

_REQUIRED: dict[str, frozenset[str]] = {
    "config": frozenset(),
    "begin": frozenset({"message"}),
    "status": frozenset({"message"}),
    "goal": frozenset({"goal_uuid", "goal"}),
    "goal_response": frozenset({"goal_uuid", "accepted"}),
    "feedback": frozenset({"goal_uuid", "feedback"}),
    "result": frozenset({"goal_uuid", "status", "result"}),
    "cancel_request": frozenset({"goal_uuid"}),
    "cancel_response": frozenset({"goal_uuid", "accepted"}),
}

_STATUSES = frozenset(status.value for status in Status)
_TIERS = frozenset(tier.value for tier in Tier)
_TERMINAL = {
    status.value: status for status in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.CANCELED)
}
_SIGNAL_LOGS: dict[str, type[ins.TaskCancel] | type[ins.TaskKill]] = {
    "Received signal to cancel": ins.TaskCancel,
    "Received signal to kill": ins.TaskKill,
}
# Reasons that depend on the configuration, which a trace without a config record does not give.
_CONFIG_REASONS = frozenset({RejectReason.UNSUPPORTED_CATEGORY, RejectReason.DESCRIPTION_INVALID})
_REASON_ORDER = {reason: index for index, reason in enumerate(RejectReason)}


@attrs.frozen(kw_only=True)
class Record:
    """One observation of a trace.

    ``kind`` is the record's ``type``; ``time`` integer nanoseconds;
    ``message`` the begin or status message, the goal, the feedback or the
    result; ``accepted`` the answer of a goal or cancel response; ``status``
    the goal status of a result; ``reason`` the reason a goal response gave.
    """

    line: int
    kind: str
    time: int
    goal_uuid: str = ""
    message: Any = None
    accepted: bool = False
    status: str = ""
    reason: RejectReason | None = None


@attrs.frozen(kw_only=True)
class Finding:
    """One protocol violation: the trace ``line``, the docs/spec.md ``rule``, a short ``code``, what was
    seen (``message``) and what the rules expect (``expected``)."""

    line: int
    rule: str
    code: str
    message: str
    expected: str

    def to_dict(self) -> dict[str, Any]:
        """The finding as plain JSON values."""
        return {
            "line": self.line,
            "rule": self.rule,
            "code": self.code,
            "message": self.message,
            "expected": self.expected,
        }


@attrs.frozen(kw_only=True)
class Report:
    """What :func:`check_trace` found in a trace of ``records`` observations."""

    source: str
    records: int
    findings: tuple[Finding, ...]

    @property
    def clean(self) -> bool:
        """No violation was found."""
        return not self.findings


# --------------------------------------------------------------------------- reading


def _time(value: Any, source: str, line: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TraceError(source, line, "time", f"expected a number of seconds, got {_json.dumps(value)}")
    nanoseconds = None
    if (isinstance(value, int) or math.isfinite(value)) and abs(value) < 2**32:  # no float() of a huge int
        nanoseconds = value * SECOND if isinstance(value, int) else round(value * SECOND)
    if nanoseconds is None or not ins.NOW_RANGE[0] <= nanoseconds <= ins.NOW_RANGE[1]:
        raise TraceError(source, line, "time", f"{value!r} is outside the range of builtin_interfaces/Time")
    return nanoseconds


def _uuid(data: dict[str, Any], source: str, line: int) -> str:
    try:
        return ins.goal_uuid(data["goal_uuid"])
    except ValueError as exc:
        raise TraceError(source, line, "goal_uuid", str(exc)) from None


def _wire(cls: type[Any], data: dict[str, Any], key: str, source: str, line: int) -> Any:
    try:
        return cls.from_dict(data[key])
    except InvalidMessage as exc:
        field = f"{key}.{exc.field}" if exc.field else key
        raise TraceError(source, line, field, f"{exc.problem} (got {_json.dumps(exc.value)})") from None
    except (TypeError, ValueError) as exc:  # a value JSON cannot hold reached the message
        raise TraceError(source, line, key, str(exc)) from None


def _boolean(data: dict[str, Any], key: str, source: str, line: int) -> bool:
    value = data[key]
    if type(value) is not bool:
        raise TraceError(source, line, key, f"expected true or false, got {_json.dumps(value)}")
    return value


#: Per record type: the fields it may have and those it must have (every record but config has a time).
_FIELDS_OF = {
    kind: (
        frozenset(fields | {"type"} | (set() if kind == "config" else {"time"})),
        frozenset(_REQUIRED[kind] | (set() if kind == "config" else {"time"})),
    )
    for kind, fields in RECORD_TYPES.items()
}


def _record(data: Any, source: str, line: int) -> Record | dict[str, Any]:
    """A trace record, or the fields of the config record."""
    if not isinstance(data, dict):
        raise TraceError(source, line, "$", f"expected a JSON object, got {type(data).__name__}")
    kind = data.get("type")
    if not isinstance(kind, str) or kind not in RECORD_TYPES:
        raise TraceError(source, line, "type", f"expected one of {sorted(RECORD_TYPES)}, got {kind!r}")
    keys = data.keys()
    allowed, required = _FIELDS_OF[kind]
    if not keys <= allowed:
        unknown = sorted(keys - allowed)
        raise TraceError(source, line, unknown[0], f"unknown field of a {kind!r} record")
    if not required <= keys:
        missing = sorted(required - keys)
        raise TraceError(source, line, missing[0], f"missing field of a {kind!r} record")
    if kind == "config":
        return data
    time = _time(data["time"], source, line)
    if kind in ("begin", "status"):
        cls = DynamicEventDescription if kind == "begin" else DynamicEventStatus
        return Record(line=line, kind=kind, time=time, message=_wire(cls, data, "message", source, line))
    uuid = _uuid(data, source, line)
    if kind == "goal":
        goal = _wire(Goal, data, "goal", source, line)
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, message=goal)
    if kind == "goal_response":
        reason = data.get("reason")
        parsed: RejectReason | None = None
        if reason is not None:
            try:
                parsed = RejectReason(reason)
            except ValueError:
                choices = [member.value for member in RejectReason]
                raise TraceError(
                    source, line, "reason", f"expected one of {choices}, got {reason!r}"
                ) from None
        accepted = _boolean(data, "accepted", source, line)
        if accepted and parsed is not None:
            raise TraceError(source, line, "reason", "an accepted goal has no rejection reason")
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, accepted=accepted, reason=parsed)
    if kind == "feedback":
        feedback = _wire(Feedback, data, "feedback", source, line)
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, message=feedback)
    if kind == "result":
        status = data["status"]
        if not isinstance(status, str) or status not in _TERMINAL:  # the type first: a dict is unhashable
            raise TraceError(
                source, line, "status", f"expected one of {sorted(_TERMINAL)}, got {_json.dumps(status)}"
            )
        result = _wire(Result, data, "result", source, line)
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, status=status, message=result)
    if kind == "cancel_response":
        accepted = _boolean(data, "accepted", source, line)
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, accepted=accepted)
    return Record(line=line, kind=kind, time=time, goal_uuid=uuid)


@attrs.frozen(kw_only=True)
class _Header:
    fleet: str | None = None
    robot: str | None = None
    config: ServerConfig | None = None


def _header(data: dict[str, Any], source: str, line: int) -> _Header:
    names: dict[str, str] = {}
    for key in ("fleet", "robot"):
        value = data.get(key)
        if value is not None and not isinstance(value, str):
            raise TraceError(source, line, key, f"expected a string, got {_json.dumps(value)}")
        if value is not None:
            names[key] = value
    config = None
    if "config" in data:
        try:
            config = config_from_json(data["config"], "config")
        except InvalidRecord as exc:
            raise TraceError(source, line, exc.path, exc.problem) from None
    return _Header(fleet=names.get("fleet"), robot=names.get("robot"), config=config)


def read_trace(lines: Iterable[str], source: str = "<trace>") -> tuple[_Header, list[Record]]:
    """Parse a trace: its optional config record and its observations.

    Blank lines and lines starting with ``#`` are skipped.  Raises
    :class:`TraceError` naming ``source``, the line and the field.
    """
    header, records = stream_trace(lines, source)
    return header, list(records)


def stream_trace(lines: Iterable[str], source: str = "<trace>") -> tuple[_Header, Iterator[Record]]:
    """Like :func:`read_trace`, but the observations come one at a time, as ``lines`` are read.

    The config record, if any, is read at once; each later line is parsed when
    the iterator reaches it (and a :class:`TraceError` raised from there).
    """
    parsed = _parsed_lines(lines, source)
    first = next(parsed, None)
    if first is None:
        return _Header(), iter(())
    number, item = first
    if isinstance(item, dict):
        return _header(item, source, number), _observations(parsed, source)
    return _Header(), _observations(itertools.chain([first], parsed), source)


def _parsed_lines(lines: Iterable[str], source: str) -> Iterator[tuple[int, Record | dict[str, Any]]]:
    for number, raw in enumerate(lines, start=1):
        text = raw.strip()
        if not text or text.startswith("#"):
            continue
        try:
            data = _json.parse(text)
        except _json.JsonProblem as exc:
            raise TraceError(source, number, "$", str(exc)) from None
        yield number, _record(data, source, number)


def _observations(parsed: Iterable[tuple[int, Record | dict[str, Any]]], source: str) -> Iterator[Record]:
    for number, item in parsed:
        if isinstance(item, dict):
            raise TraceError(source, number, "type", "a 'config' record must come before every other")
        yield item


def _seconds(now: int) -> int | float:
    return now // SECOND if now % SECOND == 0 else now / SECOND


def step_records(event: ins.Input, outputs: Iterable[outs.Output]) -> list[dict[str, Any]]:
    """The trace records a tap at the server writes for one step of the machine, in order.

    A goal request gives its ``goal`` record, then the ``goal_response``
    (with the reason, as an in-process binding can give it); an action-level
    cancel its ``cancel_request`` and ``cancel_response``; every publication,
    feedback and answer its record.  The other outputs are not on the wire.
    Feeding a server's steps through this gives a trace that
    :func:`check_trace` finds clean.
    """
    time = _seconds(event.now)
    rows: list[dict[str, Any]] = []
    if isinstance(event, ins.GoalRequested):
        rows.append({"type": "goal", "goal_uuid": event.goal_uuid, "goal": event.goal.to_dict()})
    if isinstance(event, ins.CancelRequested):
        rows.append({"type": "cancel_request", "goal_uuid": event.goal_uuid})
    rows.extend(row for row in map(_output_record, outputs) if row is not None)
    return [{"time": time, **row} for row in rows]


def _output_record(output: outs.Output) -> dict[str, Any] | None:
    """The trace record of one output, without its time; ``None`` for one that is not on the wire."""
    if isinstance(output, outs.GoalAccepted):
        return {"type": "goal_response", "goal_uuid": output.goal_uuid, "accepted": True}
    if isinstance(output, outs.GoalRejected):
        reason = output.rejection.reason.value
        return {"type": "goal_response", "goal_uuid": output.goal_uuid, "accepted": False, "reason": reason}
    if isinstance(output, outs.CancelResponse):
        return {"type": "cancel_response", "goal_uuid": output.goal_uuid, "accepted": output.accepted}
    if isinstance(output, outs.PublishBegin):
        return {"type": "begin", "message": output.message.to_dict()}
    if isinstance(output, outs.PublishStatus):
        return {"type": "status", "message": output.message.to_dict()}
    if isinstance(output, outs.PublishFeedback):
        return {"type": "feedback", "goal_uuid": output.goal_uuid, "feedback": output.feedback.to_dict()}
    if isinstance(output, outs.AnswerGoal):
        result = output.result.to_dict()
        return {
            "type": "result",
            "goal_uuid": output.goal_uuid,
            "status": output.status.value,
            "result": result,
        }
    return None


# --------------------------------------------------------------------------- the observer


@attrs.define
class _GoalSeen:
    """What the trace showed of one goal."""

    goal: Goal
    line: int
    responded: bool = False
    accepted: bool = False
    answered: int | None = None  # the line of its terminal answer
    owed: bool = False  # dropped from the state on resynchronisation: its answers are not judged


#: The goal an answered goal's record keeps: nothing after its answer reads the request itself.
_ANSWERED = Goal()


@attrs.frozen
class _Owed:
    """An output of an inferred step that has not been observed yet."""

    channel: str
    output: outs.Output
    rule: str


def _channel(output: outs.Output) -> str | None:
    if isinstance(output, outs.PublishStatus):
        return "status"
    if isinstance(output, (outs.PublishFeedback, outs.AnswerGoal)):
        return f"goal:{output.goal_uuid}"
    if isinstance(output, outs.CancelResponse):
        return f"cancel:{output.goal_uuid}"
    return None


def _failure(output: outs.Output) -> Failure | None:
    """The execution failure an answer reports, if it is one of rmf_ros2's."""
    return Failure.of(output.result.execution_failure) if isinstance(output, outs.AnswerGoal) else None


def _result_rule(rule: str) -> str:
    """The rule a wrong result breaks: R8.1 for the answers at a child's end, else the answer's own."""
    at_child_end = rule in (machine.CHILD_END_RULE, machine.WAITING_CANCEL_RULE)
    return machine.CHILD_RESULT_RULE if at_child_end else rule


def _first_line(text: str) -> str:
    return text.split("\n", 1)[0]


def _same_status(a: DynamicEventStatus, b: DynamicEventStatus) -> bool:
    return (a.dynamic_event_seq, a.dynamic_state, a.status, a.id) == (
        b.dynamic_event_seq,
        b.dynamic_state,
        b.status,
        b.id,
    )


def _exact(output: outs.Output, record: Record) -> bool:
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
            _first_line(expected.execution_failure),
        ) == (
            record.status,
            result.id,
            result.status,
            _first_line(result.execution_failure),
        )
    return False


def _owes(owed: _Owed, record: Record) -> bool:
    """Is ``record`` the owed output?"""
    output = owed.output
    if isinstance(output, outs.PublishStatus):
        return record.kind == "status" and _same_status(output.message, record.message)
    if isinstance(output, (outs.PublishFeedback, outs.AnswerGoal)):
        wanted = "feedback" if isinstance(output, outs.PublishFeedback) else "result"
        return record.kind == wanted and record.goal_uuid == output.goal_uuid and _exact(output, record)
    return False


# --------------------------------------------------------------------------- the abducer

#: A candidate that explains an observation: its inputs, the state after them, the outputs it owes
#: and, among them, the one observed.
_Found = tuple[list[ins.Input], State, list[_Owed], _Owed]


def simulate(state: State, events: list[ins.Input], config: ServerConfig) -> tuple[State, list[_Owed]]:
    """The state after ``events`` and the observable outputs they owe: the machine's, nothing else."""
    owed: list[_Owed] = []
    for event in events:
        transition = machine.step(state, event, config)
        for output in transition.outputs:
            channel = _channel(output)
            if channel is not None:
                owed.append(_Owed(channel, output, output.rule))
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
            for signal_text, signal in _SIGNAL_LOGS.items():
                if signal_text in texts:
                    yield [signal(now=now)]
            if running.started:
                status = feedback.status if feedback.status in _STATUSES else running.child_status
                last = feedback.logs[-1] if feedback.logs else None
                tier = last.tier if last is not None and last.tier in _TIERS else "info"
                log_text = last.text[: ins.MAX_LOG_TEXT_LENGTH] if last is not None else None
                yield [ins.ChildProgress(status=status, log_text=log_text, tier=tier, now=now)]
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
        if any(item.goal_uuid == uuid for item in state.queued):
            yield [ins.GoalStarted(goal_uuid=uuid, now=now)]
        if running is not None and running.started:
            final = result.status if result.status in _STATUSES else Status.COMPLETED.value
            yield [ins.ChildFinished(status=final, now=now)]
        if running is not None and not running.started and running.goal_uuid == uuid:
            for queued in state.queued:  # a CANCEL's start cancels a deferred child at once (R9.4)
                if queued.goal.event_type == EventType.CANCEL:
                    yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now)]
            yield [ins.TaskCancel(now=now)]
            yield [ins.TaskKill(now=now)]
        if _first_line(result.execution_failure) == Failure.SHUTDOWN.value:
            yield [ins.Shutdown(now=now)]
        return
    message: DynamicEventStatus = record.message
    for queued in state.queued:
        yield [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now)]
    if running is not None and running.started and message.status in _STATUSES:
        yield [ins.ChildProgress(status=message.status, now=now)]
    if running is not None and not running.started:
        yield [ins.Resume(now=now)]
    if message.status == Status.KILLED.value:
        yield [ins.TaskKill(now=now)]
    if message.status == Status.CANCELED.value or message.dynamic_state == DynamicState.INACTIVE:
        yield [ins.TaskCancel(now=now)]


def confirmed(found: _Found, upcoming: Record | None) -> bool:
    """Does the next record show the next output this candidate owes?"""
    rest = [item for item in found[2] if item is not found[3]]
    return bool(rest) and upcoming is not None and _owes(rest[0], upcoming)


def abduce(
    state: State, config: ServerConfig, record: Record, now: int, upcoming: Record | None
) -> _Found | None:
    """The first candidate whose first output on the action is this feedback or answer.

    A candidate that reproduces the observation exactly is preferred; else
    the first whose output is of the same kind for the same goal (the
    differences are then reported).  The abducer only calls the machine.
    """
    channel = f"goal:{record.goal_uuid}"
    kind = outs.PublishFeedback if record.kind == "feedback" else outs.AnswerGoal
    near = None
    exact: list[_Found] = []
    for events in candidates(state, record, now):
        after, owed = simulate(state, events, config)
        first = next((item for item in owed if item.channel.startswith("goal:")), None)
        if first is None or first.channel != channel or not isinstance(first.output, kind):
            continue
        if _exact(first.output, record):
            exact.append((events, after, owed, first))
        elif near is None:
            near = (events, after, owed, first)
    # candidates that agree on this record differ in what comes next: let the next record choose
    for found in exact:
        if confirmed(found, upcoming):
            return found
    return exact[0] if exact else near


class _Books:
    """The observer's books, which its parts share: the state, what is owed, the goals seen, the time and
    line, the findings, and the operations on them.  What only one part needs, that part keeps."""

    def __init__(self, header: _Header) -> None:
        self.config_known = header.config is not None
        self.config = header.config if header.config is not None else ServerConfig()
        self.state: State | None = None
        self.owed: list[_Owed] = []
        self.goals: dict[str, _GoalSeen] = {}
        self.findings: list[Finding] = []
        self.now = ins.NOW_RANGE[0]
        self.line = 0
        self.partial = False  # the trace begins mid-way: goals it never showed may be open
        self.upcoming: Record | None = None  # the record after the one being judged
        self.lookahead: tuple[Record, ...] = ()  # the LOOKAHEAD records after it
        self.event_id_unknown = False  # the run began before the trace: its own id is not known
        self.start_uncertain = False  # a RUNNING "queued" status: a deferred child, or one reporting queued

    # ------------------------------------------------------------------ bookkeeping

    def flag(self, violation: Violation, message: str, expected: str) -> None:
        """Report ``violation`` on the current line."""
        self.differs(violation.rule, violation.code, message, expected)

    def differs(self, rule: str, code: str, message: str, expected: str) -> None:
        """Report an output that differs from the machine's, under the rule of the machine's output."""
        self.findings.append(
            Finding(line=self.line, rule=rule, code=code, message=message, expected=expected)
        )

    @property
    def st(self) -> State:
        assert self.state is not None  # set by the first record
        return self.state

    def config_for(self, goal: Goal) -> ServerConfig:
        """The configuration; without a config record, every category a goal names is taken as supported."""
        if self.config_known or goal.event_type != EventType.NEXT or goal.category in self.config.categories:
            return self.config
        categories = {**self.config.categories, goal.category: machine.any_description}
        return attrs.evolve(self.config, categories=categories)

    def learn(self, goal: Goal) -> None:
        self.config = self.config_for(goal)

    def simulate(self, events: list[ins.Input]) -> tuple[State, list[_Owed]]:
        """The state after ``events`` and the outputs they owe, without committing (see :func:`simulate`)."""
        return simulate(self.st, events, self.config)

    def commit(self, state: State, owed: list[_Owed]) -> None:
        self.state = state
        self.owed.extend(owed)

    def forget_channel(self, channel: str) -> None:
        self.owed = [item for item in self.owed if item.channel != channel]

    def displace(self, uuids: Iterable[str]) -> None:
        """The server no longer runs these goals as the state says: their answers are not judged."""
        for uuid in uuids:
            seen = self.goals.get(uuid)
            if seen is not None and seen.answered is None:
                seen.owed = True
            self.forget_channel(f"goal:{uuid}")

    def abduce(self, record: Record) -> _Found | None:
        """The candidate that explains ``record`` in the current state (see :func:`abduce`)."""
        return abduce(self.st, self.config, record, self.now, self.upcoming)

    def confirmed(self, found: _Found) -> bool:
        return confirmed(found, self.upcoming)

    def bind_unknown(self, uuid: str, running_goal: bool = True) -> _GoalSeen | None:
        """What the trace showed of this goal; a goal it never showed may have begun before it.

        In a trace that begins mid-way, the first unknown goal seen while the
        state's running goal is unknown (known from a RUNNING status) is taken
        to be that goal, unless ``running_goal`` says the observation cannot
        be the running goal's; any other unknown goal is not judged.
        """
        running = self.st.running
        if uuid in self.goals:
            return self.goals[uuid]
        if not self.partial:
            return None
        if running is None or running.goal_uuid != UNKNOWN_GOAL or not running_goal:
            seen = _GoalSeen(goal=Goal(), line=0, responded=True, accepted=True, owed=True)
            self.goals[uuid] = seen
            return seen
        self.state = resync.running_goal(self.st, uuid)
        seen = _GoalSeen(goal=running.goal, line=0, responded=True, accepted=True)
        self.goals[uuid] = seen
        return seen

    def abduce_uncertain(self, record: Record) -> tuple[list[ins.Input], State, list[_Owed], _Owed] | None:
        """:meth:`abduce`, also in the world where a child whose start a status left uncertain has started."""
        found = self.abduce(record)
        running = self.st.running
        if not self.start_uncertain or running is None or running.started:
            return found
        if found is not None and _exact(found[3].output, record) and self.confirmed(found):
            return found
        saved = self.st
        self.state = resync.child_started(saved, resumed=True)
        other = self.abduce(record)
        found_exact = found is not None and _exact(found[3].output, record)
        if (
            other is not None
            and _exact(other[3].output, record)
            and (self.confirmed(other) or not found_exact)
        ):
            self.start_uncertain = False
            return other
        self.state = saved
        return found

    def ahead(self, uuid: str) -> Record | None:
        """The next feedback or answer of this goal among the records the observer sees ahead."""
        for record in self.lookahead:
            if record.goal_uuid == uuid and record.kind in ("feedback", "result"):
                return record
        return None


class _Requests:
    """Goal requests, their responses and action-level cancels: the machine's ``accept``, compared."""

    def __init__(self, books: _Books) -> None:
        self.books = books
        self.duplicates: set[str] = set()  # goal UUIDs requested again while open

    def on_goal(self, record: Record) -> None:
        seen = self.books.goals.get(record.goal_uuid)
        if seen is not None and seen.answered is None and (not seen.responded or seen.accepted):
            self.books.flag(
                Violation.GOAL_UUID_REUSED,
                f"goal {record.goal_uuid} requested again while it is open (since line {seen.line})",
                "a fresh goal UUID for every goal",
            )
            self.duplicates.add(record.goal_uuid)
            return
        self.books.goals[record.goal_uuid] = _GoalSeen(goal=record.message, line=record.line)

    def on_goal_response(self, record: Record) -> None:
        if record.goal_uuid in self.duplicates:
            self.duplicates.discard(record.goal_uuid)
            return
        seen = self.books.goals.get(record.goal_uuid)
        if seen is None or seen.responded:
            raise _Unreadable("goal_uuid", "no goal record with this uuid awaits a response")
        seen.responded, seen.accepted = True, record.accepted
        goal = seen.goal
        decision = machine.accept(self.books.st, goal, self.books.config_for(goal))
        if not self.agrees(decision, record):
            self.explain_response(goal, record)
            decision = machine.accept(self.books.st, goal, self.books.config_for(goal))
        if record.accepted:
            self.books.learn(goal)
        if isinstance(decision, outs.Accepted) == record.accepted:
            if isinstance(decision, outs.Rejected) and not self.same_reason(decision, record):
                self.books.differs(
                    decision.rule,
                    "wrong_reason",
                    f"{goal_text(goal)} rejected as {record.reason}",
                    f"rejected as {decision.reason.value}, the first check that fails: {decision.text}",
                )
            if record.accepted:
                event = ins.GoalRequested(goal_uuid=record.goal_uuid, goal=goal, now=self.books.now)
                self.books.commit(*self.books.simulate([event]))
            return
        if isinstance(decision, outs.Rejected):  # accepted, but the rules refuse it
            self.books.differs(
                decision.rule,
                f"accepted_{decision.reason.value}",
                f"{goal_text(goal)} accepted",
                f"rejected: {decision.reason.value} ({decision.text})",
            )
            self.books.state = resync.queued(self.books.st, record.goal_uuid, goal)
            return
        if self.unknowable(goal, record):
            return
        said = f" as {record.reason.value}" if record.reason is not None else ""
        self.books.flag(
            Violation.REJECTED_ACCEPTABLE,
            f"{goal_text(goal)} rejected{said}",
            "accepted: the goal passes every check of R4",
        )

    def agrees(self, decision: outs.Decision, record: Record) -> bool:
        if isinstance(decision, outs.Accepted) != record.accepted:
            return False
        return not isinstance(decision, outs.Rejected) or self.same_reason(decision, record)

    def same_reason(self, decision: outs.Rejected, record: Record) -> bool:
        reason = record.reason
        if reason is None or reason is decision.reason:
            return True
        return (
            not self.books.config_known
            and reason in _CONFIG_REASONS
            and _REASON_ORDER[reason] < _REASON_ORDER[decision.reason]
        )

    def unknowable(self, goal: Goal, record: Record) -> bool:
        """Could an unknown configuration have refused this NEXT?"""
        if self.books.config_known or goal.event_type != EventType.NEXT:
            return False
        return record.reason is None or record.reason in _CONFIG_REASONS

    def explain_response(self, goal: Goal, record: Record) -> None:
        """The response may follow starts of accepted goals whose outputs come later: try them."""
        events: list[ins.Input] = []
        for queued in self.books.st.queued:
            events.append(ins.GoalStarted(goal_uuid=queued.goal_uuid, now=self.books.now))
            state, owed = self.books.simulate(events)
            decision = machine.accept(state, goal, self.books.config_for(goal))
            if self.agrees(decision, record):
                self.books.commit(state, owed)
                return
        if record.reason is RejectReason.SHUTTING_DOWN:
            state, owed = self.books.simulate([ins.Shutdown(now=self.books.now)])
            self.books.commit(state, owed)

    def on_cancel_request(self, record: Record) -> None:
        if self.books.partial and record.goal_uuid not in self.books.goals:
            return  # a goal from before the trace, maybe: its response tells (on_cancel_response)
        seen = self.books.goals.get(record.goal_uuid)
        if seen is not None and seen.owed:
            return  # a goal the state no longer follows: its cancel is not judged either
        running = self.books.st.running
        if self.books.start_uncertain and running is not None and running.goal_uuid == record.goal_uuid:
            # a deferred child is cancelled at once (R10.4); a started one ends later (R10.3)
            answer = self.books.ahead(record.goal_uuid)  # at once: within the next two records
            deferred = (
                answer is not None
                and answer.kind == "result"
                and answer.status == GoalStatus.CANCELED.value
                and answer.message.status == Status.CANCELED.value
            )
            if not deferred:
                self.books.state = resync.child_started(self.books.st)
            self.books.start_uncertain = False
        self.books.commit(
            *self.books.simulate([ins.CancelRequested(goal_uuid=record.goal_uuid, now=self.books.now)])
        )

    def on_cancel_response(self, record: Record) -> None:
        channel = f"cancel:{record.goal_uuid}"
        if not any(item.channel == channel for item in self.books.owed):
            if self.books.partial and record.goal_uuid not in self.books.goals:
                if not record.accepted:
                    return  # a goal unknown to the server as well
                upcoming = self.books.upcoming
                queued = (
                    upcoming is not None
                    and upcoming.kind == "result"
                    and upcoming.goal_uuid == record.goal_uuid
                    and _first_line(upcoming.message.execution_failure) == Failure.NOT_RUNNING.value
                )
                self.books.bind_unknown(record.goal_uuid, running_goal=not queued)
                if queued:
                    return  # an accepted goal that had not started (R10.1, R10.2)
            self.on_cancel_request(record)
        index = next((i for i, item in enumerate(self.books.owed) if item.channel == channel), None)
        if index is None:
            return
        owed = self.books.owed.pop(index)
        assert isinstance(owed.output, outs.CancelResponse)
        if owed.output.accepted != record.accepted:
            word = {True: "accepted", False: "rejected"}
            self.books.differs(
                owed.rule,
                "cancel_response",
                f"cancel of goal {record.goal_uuid} {word[record.accepted]}",
                f"{word[owed.output.accepted]} ({owed.rule})",
            )


class _Runs:
    """Begin and status messages: runs, their seq, the dynamic event's id and the status topic."""

    def __init__(self, books: _Books, header: _Header) -> None:
        self.books = books
        self.names = (header.fleet, header.robot) if header.fleet or header.robot else None
        self.event_id_pending = False

    def sync(self, record: Record) -> bool:
        """Set the starting state from the first record; True when the record is used up."""
        base = State.new("fleet", "robot")
        self.books.partial = record.kind == "status" or (
            record.kind == "begin" and record.message.dynamic_event_seq != 1
        )
        if record.kind == "status":
            message: DynamicEventStatus = record.message
            try:
                self.books.state = state_from_status(message)
                # a status names the highest id used (R2.2), not the dynamic event's own id
                self.books.event_id_unknown = message.dynamic_state != DynamicState.INACTIVE
                self.books.start_uncertain = (
                    self.books.st.running is not None and not self.books.st.running.started
                )
            except ValueError as exc:
                self.books.state = resync.seq(base, message.dynamic_event_seq)
                self.books.flag(
                    Violation.STATUS_PHASE, f"status {status_text(message)}: {exc}", "dynamic_state 0, 1 or 2"
                )
            return True
        if record.kind == "begin":
            self.books.state = resync.next_run(base, record.message.dynamic_event_seq)
            return False
        self.books.state = base  # a trace from the server's start
        return False

    def on_begin(self, record: Record) -> None:
        message: DynamicEventDescription = record.message
        names = (message.fleet, message.robot)
        if self.names is None:
            self.names = names
        elif names != self.names:
            self.books.flag(
                Violation.BEGIN_NAMES,
                f"begin names {message.fleet}/{message.robot}",
                f"the robot of this trace, {self.names[0]}/{self.names[1]}",
            )
        state = self.books.st
        if state.shutdown:
            self.books.flag(
                Violation.BEGIN_AFTER_SHUTDOWN, f"begin of run {message.dynamic_event_seq}", "nothing"
            )
            state = resync.serving(state)
        if state.active:
            self.books.flag(
                Violation.BEGIN_WHILE_ACTIVE,
                f"begin of run {message.dynamic_event_seq} while run {state.seq} is active",
                "the end of the run first: FINISHED, a task cancel or kill, with an INACTIVE status",
            )
            open_goals = [queued.goal_uuid for queued in state.queued] + list(state.cancels)
            if state.running is not None:
                open_goals.append(state.running.goal_uuid)
            self.books.displace(open_goals)
            state = resync.run_dropped(state)
        expected = (state.seq + 1) & U32_MAX
        if message.dynamic_event_seq != expected:
            self.books.flag(
                Violation.BEGIN_SEQ,
                f"begin of run {message.dynamic_event_seq}",
                f"seq {expected}, one above the previous run's {state.seq}",
            )
            state = resync.next_run(state, message.dynamic_event_seq)
        try:
            event = ins.Begin(description=message.description, event_id=0, now=self.books.now)
        except InvalidMessage as exc:
            self.books.flag(
                Violation.BEGIN_DESCRIPTION,
                f"begin description: {exc.problem}",
                "a dynamic_event description",
            )
            event = ins.Begin(description="{}", event_id=0, now=self.books.now)
        self.books.state = state
        self.books.commit(*self.books.simulate([event]))
        self.event_id_pending = True
        self.books.event_id_unknown = self.books.start_uncertain = False

    def adopt_event_id(self, message: DynamicEventStatus) -> None:
        """The begin did not say the dynamic event's id; the WAITING status that follows does."""
        state = self.books.st
        if not (
            self.event_id_pending
            and message.dynamic_state == DynamicState.WAITING
            and state.active
            and state.running is None
            and message.dynamic_event_seq == state.seq
        ):
            return
        self.event_id_pending = False
        self.books.state = resync.event_id(state, message.id)
        patched = []
        for item in self.books.owed:
            output = item.output
            if (
                isinstance(output, outs.PublishStatus)
                and output.message.dynamic_state == DynamicState.WAITING
                and output.message.id == 0
            ):
                fixed = outs.PublishStatus(message=attrs.evolve(output.message, id=message.id))
                patched.append(attrs.evolve(item, output=fixed))
            else:
                patched.append(item)
        self.books.owed = patched

    def on_status(self, record: Record) -> None:
        message: DynamicEventStatus = record.message
        if message.dynamic_state not in (0, 1, 2):
            self.books.flag(
                Violation.STATUS_PHASE,
                f"status with dynamic_state {message.dynamic_state}",
                "dynamic_state 0 (INACTIVE), 1 (WAITING) or 2 (RUNNING)",
            )
            return
        self.adopt_event_id(message)
        statuses = [index for index, item in enumerate(self.books.owed) if item.channel == "status"]
        for index in statuses:
            output = self.books.owed[index].output
            assert isinstance(output, outs.PublishStatus)
            if _same_status(output.message, message):
                # a status topic keeps one message: earlier ones may be overwritten unseen
                self.books.owed = [
                    item for i, item in enumerate(self.books.owed) if i > index or item.channel != "status"
                ]
                return
        current = machine.status_message(self.books.st, self.books.now)
        if _same_status(current, message):
            return  # a repeat of the state's status (e.g. the latched message, read again)
        # in the server's order a step's answers and feedback come before its status: prefer a
        # candidate that owes none, then accept one whose other outputs are still to come
        found: tuple[State, list[_Owed]] | None = None
        for events in candidates(self.books.st, record, self.books.now):
            state, owed = self.books.simulate(events)
            published = [item.output for item in owed if isinstance(item.output, outs.PublishStatus)]
            if not published or not _same_status(published[-1].message, message):
                continue
            if not any(item.channel.startswith("goal:") for item in owed):
                found = (state, owed)
                break
            if found is None:
                found = (state, owed)
        if found is not None:
            state, owed = found
            self.books.commit(state, [item for item in owed if item.channel != "status"])
            self.books.owed = [item for item in self.books.owed if item.channel != "status"]
            return
        self.books.owed = [item for item in self.books.owed if item.channel != "status"]
        self.books.flag(
            Violation.STATUS_MISMATCH,
            f"status {status_text(message)}",
            f"{status_text(current)}, the state's status",
        )


class _Feedback:
    """Feedback: a child's start and progress, abduced, compared, and corrected when it disagrees."""

    def __init__(self, books: _Books) -> None:
        self.books = books
        self.log_seq: int | None = None  # the robot's last log seq seen

    def check_logs(self, feedback: Feedback) -> None:
        for entry in feedback.logs:
            last = self.log_seq
            if last is not None and not seq_after(entry.seq, last):
                how = "repeats" if entry.seq == last else "goes backwards"
                self.books.flag(
                    Violation.LOG_SEQ,
                    f"LogEntry.seq {entry.seq} after {last}: the log seq {how}",
                    f"a LogEntry.seq above {last}: every entry takes the robot's next log seq",
                )
            self.log_seq = entry.seq

    def on_feedback(self, record: Record) -> None:
        feedback: Feedback = record.message
        self.check_logs(feedback)
        uuid = record.goal_uuid
        seen = self.books.bind_unknown(uuid)
        label = f"feedback {feedback.status} id={feedback.id} for goal {uuid}"
        if seen is None or not seen.accepted:
            what = "never requested in this trace" if seen is None else "rejected"
            self.books.flag(
                Violation.FEEDBACK_NOT_RUNNING, f"{label}, {what}", "no feedback: no goal of it runs"
            )
            return
        if seen.answered is not None:
            self.books.flag(
                Violation.AFTER_ANSWER,
                f"{label} after its terminal answer (line {seen.answered})",
                "nothing after a goal's terminal answer",
            )
            return
        state = self.books.st
        if seen.line == 0 and seen.owed and state.active and state.running is None:
            # a NEXT accepted before the trace began starts now
            seen.owed = False
            goal = Goal(dynamic_event_seq=state.seq, event_type=EventType.NEXT, id=feedback.id)
            self.force_start(uuid, goal, feedback)
            return
        if seen.owed:
            return
        channel = f"goal:{uuid}"
        for index, item in enumerate(self.books.owed):
            if item.channel != channel:
                continue
            if not isinstance(item.output, outs.PublishFeedback):
                break
            if item.output.feedback.status == feedback.status and item.output.feedback.id == feedback.id:
                del self.books.owed[index]
                self.check_clamp(item, feedback)
                return
        found = self.books.abduce_uncertain(record)
        if found is not None:
            events, state, owed, first = found
            owed.remove(first)
            self.books.commit(state, owed)
            self.compare_feedback(first, feedback, events)
            return
        self.unexplained_feedback(record, seen)

    def compare_feedback(self, owed: _Owed, feedback: Feedback, events: list[ins.Input]) -> None:
        assert isinstance(owed.output, outs.PublishFeedback)
        expected = owed.output.feedback
        if expected.id != feedback.id:
            if isinstance(events[-1], (ins.GoalStarted, ins.Resume)):
                policy = (
                    "the NEXT goal's id" if self.books.config.id_policy is IdPolicy.GOAL else "the next id"
                )
                self.books.flag(
                    Violation.CHILD_ID,
                    f"the child started for goal {owed.output.goal_uuid} has id {feedback.id}",
                    f"id {expected.id}, {policy}",
                )
                self.patch_child_id(feedback.id)
            else:
                self.books.differs(
                    owed.rule,
                    "feedback_id",
                    f"feedback id={feedback.id} for goal {owed.output.goal_uuid}",
                    f"id={expected.id}, the running child's",
                )
        if expected.status != feedback.status:
            self.books.differs(
                owed.rule,
                "feedback_status",
                f"feedback {feedback.status} for goal {owed.output.goal_uuid}",
                f"feedback {expected.status}",
            )
        self.check_clamp(owed, feedback)

    def check_clamp(self, owed: _Owed, feedback: Feedback) -> None:
        """A start's feedback carries the warning of a clamped stubborn period (R12.2)."""
        output = owed.output
        if owed.rule not in (machine.START_RULE, machine.DEFERRED_START_RULE) or not isinstance(
            output, outs.PublishFeedback
        ):
            return
        warnings = [entry for entry in output.feedback.logs if entry.tier == Tier.WARNING.value]
        if warnings and not any(entry.tier == Tier.WARNING.value for entry in feedback.logs):
            self.books.flag(
                Violation.CLAMP_NOT_REPORTED,
                f"the start feedback of goal {output.goal_uuid} carries no warning",
                f"a warning log entry: {warnings[0].text}",
            )

    def patch_child_id(self, child_id: int) -> None:
        running = self.books.st.running
        if running is None:
            return
        self.books.state = resync.child_id(self.books.st, child_id)
        current = machine.status_message(self.books.st, self.books.now)
        self.books.owed = [
            attrs.evolve(item, output=outs.PublishStatus(message=current))
            if isinstance(item.output, outs.PublishStatus)
            and item.output.message.dynamic_state == DynamicState.RUNNING
            else item
            for item in self.books.owed
        ]

    def unexplained_feedback(self, record: Record, seen: _GoalSeen) -> None:
        feedback: Feedback = record.message
        uuid = record.goal_uuid
        label = f"feedback {feedback.status} id={feedback.id} for goal {uuid}"
        state = self.books.st
        goal = seen.goal
        queued = any(item.goal_uuid == uuid for item in state.queued)
        pending = next(
            (
                item
                for item in self.books.owed
                if item.channel == f"goal:{uuid}" and isinstance(item.output, outs.AnswerGoal)
            ),
            None,
        )
        if queued and goal.event_type == EventType.NEXT:
            _, owed = self.books.simulate([ins.GoalStarted(goal_uuid=uuid, now=self.books.now)])
            answer = next((item for item in owed if isinstance(item.output, outs.AnswerGoal)), None)
            if answer is not None and _failure(answer.output) is Failure.RACE:
                race = machine.race_lost(state, goal, self.books.config_for(goal))
                self.books.flag(
                    Violation.RACE_NOT_LOST,
                    f"{label}: its NEXT ({goal_text(goal)}) started a child",
                    f"aborted: {Failure.RACE.value!r}, as {race}",
                )
            elif answer is not None and isinstance(answer.output, outs.AnswerGoal):
                expected = answer_text(answer.output.status.value, answer.output.result, first_line=True)
                self.books.differs(
                    answer.rule, "feedback_not_running", f"{label}: its NEXT started a child", expected
                )
            self.force_start(uuid, goal, feedback)
            return
        if pending is not None:
            assert isinstance(pending.output, outs.AnswerGoal)
            self.books.differs(
                pending.rule,
                "feedback_not_running",
                f"{label}, whose event has ended",
                answer_text(pending.output.status.value, pending.output.result, first_line=True),
            )
            return
        kind = EventType(goal.event_type).name if goal.event_type <= 3 else f"event_type {goal.event_type}"
        self.books.flag(
            Violation.FEEDBACK_NOT_RUNNING, f"{label}, a {kind} goal that runs no child", "no feedback"
        )

    def force_start(self, uuid: str, goal: Goal, feedback: Feedback) -> None:
        """The server runs this NEXT, whatever the rules say: make it the running goal."""
        state = self.books.st
        displaced = list(state.cancels)
        if state.running is not None:
            displaced.append(state.running.goal_uuid)
            # accepted CANCELs of the displaced child, not started yet, wait for it too
            old = state.running.child_id
            displaced.extend(
                item.goal_uuid
                for item in state.queued
                if item.goal.event_type == EventType.CANCEL and item.goal.id == old
            )
        self.books.displace(displaced)
        self.books.state = resync.running(state, uuid, goal, feedback.id, feedback.status, displaced)
        self.books.owed = [item for item in self.books.owed if item.channel != "status"]


class _Answers:
    """Terminal answers: the end of a goal, abduced or owed, compared with the machine's."""

    def __init__(self, books: _Books) -> None:
        self.books = books
        self.last_end: tuple[int, Result] | None = None  # the last child end: its line and result

    def on_result(self, record: Record) -> None:
        result: Result = record.message
        uuid = record.goal_uuid
        # the running goal is answered at its child's end, or at shutdown
        failure = _first_line(result.execution_failure)
        seen = self.books.bind_unknown(uuid, failure in ("", Failure.SHUTDOWN.value))
        label = f"answer {answer_text(record.status, result, first_line=True)} for goal {uuid}"
        if seen is None or not seen.accepted:
            what = "never requested in this trace" if seen is None else "rejected"
            self.books.flag(
                Violation.ANSWER_NOT_ACCEPTED, f"{label}, {what}", "no answer: the goal was never accepted"
            )
            return
        if seen.answered is not None:
            self.books.flag(
                Violation.SECOND_ANSWER,
                f"{label}: a second terminal answer (the first on line {seen.answered})",
                "exactly one terminal answer per goal",
            )
            return
        seen.answered = record.line
        if seen.owed:
            return
        channel = f"goal:{uuid}"
        pending = next(
            (
                item
                for item in self.books.owed
                if item.channel == channel and isinstance(item.output, outs.AnswerGoal)
            ),
            None,
        )
        if pending is not None:
            self.books.forget_channel(channel)
            self.compare_answer(pending, record)
            return
        if self.started_unseen(record):
            return
        found = self.books.abduce_uncertain(record)
        if found is not None:
            events, state, owed, first = found
            self.books.commit(state, [item for item in owed if item.channel != channel])
            self.compare_answer(first, record)
            if isinstance(events[-1], ins.ChildFinished) and isinstance(first.output, outs.AnswerGoal):
                self.last_end = (record.line, first.output.result)
            return
        self.unexplained_answer(record, seen)

    def started_unseen(self, record: Record) -> bool:
        """A CANCEL's start shows nothing on the wire: its answer may say it waited for the last child."""
        state = self.books.st
        uuid = record.goal_uuid
        queued = next((item for item in state.queued if item.goal_uuid == uuid), None)
        seen = self.books.goals.get(uuid)
        if queued is None or queued.goal.event_type != EventType.CANCEL or self.last_end is None:
            return False
        line, result = self.last_end
        if seen is None or seen.line > line or record.status != GoalStatus.SUCCEEDED.value:
            return False
        if record.message != result:
            return False
        self.books.state = resync.dropped(state, uuid)
        return True

    def compare_answer(self, owed: _Owed, record: Record) -> None:
        output = owed.output
        assert isinstance(output, outs.AnswerGoal)
        result: Result = record.message
        expected, observed = output.result, result
        label = f"goal {record.goal_uuid} answered {answer_text(record.status, result, first_line=True)}"
        want = answer_text(output.status.value, expected, first_line=True)
        seen = self.books.goals.get(record.goal_uuid)
        early = {record.status, output.status.value} == {GoalStatus.ABORTED.value, GoalStatus.CANCELED.value}
        if early and seen is not None and seen.line == 0:
            pass  # a goal from before the trace: whether it was cancelled through the action is not known
        elif record.status != output.status.value:
            self.books.differs(owed.rule, "goal_status", label, f"{want} ({owed.rule})")
        elif owed.rule == machine.FINISHED_RULE and self.books.event_id_unknown:
            self.books.event_id_unknown = False  # the first FINISHED of a run joined late names its own id
            self.books.state = resync.event_id(self.books.st, observed.id)
        elif expected.id != observed.id:
            rule = _result_rule(owed.rule)
            self.books.differs(
                rule, "result_id", f"{label}: the result id does not match", f"{want} ({rule})"
            )
        elif (_first_line(expected.execution_failure), expected.status) != (
            _first_line(observed.execution_failure),
            observed.status,
        ):
            rule = _result_rule(owed.rule)
            self.books.differs(rule, "result", label, f"{want} ({rule})")

    def unexplained_answer(self, record: Record, seen: _GoalSeen) -> None:
        uuid = record.goal_uuid
        state = self.books.st
        label = f"goal {uuid} answered {answer_text(record.status, record.message, first_line=True)}"
        running = state.running
        queued = next((item for item in state.queued if item.goal_uuid == uuid), None)
        if uuid in state.cancels or (
            queued is not None and queued.goal.event_type == EventType.CANCEL and running
        ):
            child = running.child_id if running is not None else 0
            self.books.flag(
                Violation.CANCEL_ANSWERED_EARLY,
                f"{label} while child {child} still runs",
                f"the CANCEL waits for child {child} to end, then is answered with its result (R8.3)",
            )
            self.books.state = resync.dropped(state, uuid)
            return
        if queued is not None:
            start = "its child starts" if queued.goal.event_type == EventType.NEXT else "it runs"
            self.books.flag(Violation.ANSWER_BEFORE_START, label, f"no answer yet: {start}")
            self.books.state = resync.dropped(state, uuid)
            return
        if running is not None and running.goal_uuid == uuid:
            self.books.flag(
                Violation.ANSWER_WHILE_DEFERRED, label, "no answer while the child's start is deferred"
            )
            self.books.state = resync.start_dropped(state)
            return
        self.books.flag(Violation.ANSWER_NOT_OPEN, label, "no answer: the goal is not open")


class _Observer:
    """Observer mode (see the module docs): each record goes to the part that reads its kind.

    The parts share the books (:class:`_Books`) and keep what only they need; none calls another.
    """

    def __init__(self, header: _Header) -> None:
        self.books = _Books(header)
        self.requests = _Requests(self.books)
        self.runs = _Runs(self.books, header)
        self.feedback = _Feedback(self.books)
        self.answers = _Answers(self.books)
        self._handlers: dict[str, Callable[[Record], None]] = {
            "goal": self.requests.on_goal,
            "goal_response": self.requests.on_goal_response,
            "cancel_request": self.requests.on_cancel_request,
            "cancel_response": self.requests.on_cancel_response,
            "begin": self.runs.on_begin,
            "status": self.runs.on_status,
            "feedback": self.feedback.on_feedback,
            "result": self.answers.on_result,
        }

    def feed(self, record: Record) -> None:
        books = self.books
        books.line = record.line
        books.now = max(books.now, record.time)
        if books.state is None and self.runs.sync(record):
            return
        self._handlers[record.kind](record)
        if record.kind == "result":
            seen = books.goals.get(record.goal_uuid)
            if seen is not None and seen.answered is not None:
                seen.goal = _ANSWERED  # what is judged after its answer is the line: memory stays flat


class _Unreadable(Exception):
    """A record the observer cannot use: its field and the problem (turned into a TraceError)."""

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(problem)


#: How many records after the one being judged the observer looks at: a trace is checked in one pass
#: with this many records held, whatever its length.
LOOKAHEAD = 2


def check_records(header: _Header, records: Iterable[Record], source: str = "<trace>") -> Report:
    """Replay parsed records in observer mode; see :func:`check_trace`."""
    observer = _Observer(header)
    pending = iter(records)
    window = collections.deque(itertools.islice(pending, LOOKAHEAD))
    count = 0
    while True:
        window.extend(itertools.islice(pending, 1))
        if not window:
            break
        record = window.popleft()
        observer.books.lookahead = tuple(window)
        observer.books.upcoming = window[0] if window else None
        try:
            observer.feed(record)
        except _Unreadable as exc:
            raise TraceError(source, record.line, exc.field, exc.problem) from None
        count += 1
    return Report(source=source, records=count, findings=tuple(observer.books.findings))


def check_trace(text: str | Iterable[str], source: str = "<trace>") -> Report:
    """Check a trace (its text, or its lines) in observer mode; each violation is a :class:`Finding`.

    Raises :class:`TraceError` (naming ``source``, the line and the field)
    when the trace cannot be read.
    """
    lines = text.splitlines() if isinstance(text, str) else text
    header, records = stream_trace(lines, source)
    return check_records(header, records, source)


def format_report(report: Report) -> str:
    """The findings as text, one per line with what was expected, then a summary line."""
    lines = []
    for finding in report.findings:
        lines.append(f"{report.source}:{finding.line}: {finding.rule} {finding.code}: {finding.message}")
        lines.append(f"    expected: {finding.expected}")
    count = len(report.findings)
    noun = "violation" if count == 1 else "violations"
    summary = f"{report.source}: {report.records} records, {count or 'no'} {noun}"
    lines.append(summary)
    return "\n".join(lines) + "\n"


def trace_records(report: Report) -> list[dict[str, Any]]:
    """The JSON lines of ``dynevent check --json``: one object per finding, then a summary."""
    rows: list[dict[str, Any]] = [
        {"type": "violation", "file": report.source, **finding.to_dict()} for finding in report.findings
    ]
    rows.append(
        {
            "type": "summary",
            "file": report.source,
            "records": report.records,
            "violations": len(report.findings),
        }
    )
    return rows


def _run(args: argparse.Namespace) -> int:
    source = args.trace
    try:
        if source == "-":
            report = _check_stream(sys.stdin.buffer, "<stdin>")
        else:
            with open(source, "rb") as stream:
                report = _check_stream(stream, source)
    except OSError as exc:
        print(f"dynevent check: {source}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except TraceError as exc:
        print(f"dynevent check: {exc}", file=sys.stderr)
        return 2
    if report.records == 0:
        print(f"dynevent check: {report.source}: nothing to check: no record in it", file=sys.stderr)
        return 2
    if args.json:
        for row in trace_records(report):
            print(_json.dumps(row))
    else:
        print(format_report(report), end="")
    return 0 if report.clean else 1


def _check_stream(stream: Any, source: str) -> Report:
    """Check a trace read line by line from a binary stream, with a progress line on a terminal."""
    try:
        size: int | None = os.fstat(stream.fileno()).st_size or None
    except (OSError, ValueError, AttributeError):
        size = None
    progress = Progress(f"dynevent check: {source}", size)
    try:
        return check_trace(_text_lines(stream, source, progress), source)
    finally:
        progress.close()


def _text_lines(stream: Any, source: str, progress: Progress) -> Iterator[str]:
    done = 0
    for number, raw in enumerate(stream, start=1):
        done += len(raw)
        progress.update(done, f"(line {number:,})")
        try:
            yield raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise TraceError(source, number, "$", f"not UTF-8 text (byte {exc.start} of the line)") from None
