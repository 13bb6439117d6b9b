"""A trace's records: reading them (each field checked, every fault a TraceError naming the line),
and writing the records of a machine step (:func:`step_records`)."""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Iterable, Iterator
from typing import Any, TextIO, TypeAlias

import attrs

from dynevent import files
from dynevent.conformance.records import InvalidRecord, config_from_json
from dynevent.errors import (
    InvalidMessage,
    TraceError,  # defined there with every error; importable here too
)
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    ServerConfig,
)
from dynevent.wire import _json
from dynevent.wire._fields import SECOND
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    Compatibility,
    GoalStatus,
    RejectReason,
    Status,
    Tier,
)

#: The record types of a trace, and the fields each may hold besides ``type`` and ``time``.
RECORD_TYPES: dict[str, frozenset[str]] = {
    "config": frozenset({"fleet", "robot", "config", "tap"}),
    "begin": frozenset({"message"}),
    "status": frozenset({"message"}),
    "goal": frozenset({"goal_uuid", "goal"}),
    "goal_response": frozenset({"goal_uuid", "accepted", "reason"}),
    "feedback": frozenset({"goal_uuid", "feedback"}),
    "result": frozenset({"goal_uuid", "status", "result"}),
    "cancel_request": frozenset({"goal_uuid"}),
    "cancel_response": frozenset({"goal_uuid", "accepted", "terminated"}),
    "end": frozenset(),
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
    "end": frozenset(),
}

STATUSES = frozenset(status.value for status in Status)
TIERS = frozenset(tier.value for tier in Tier)
_TERMINAL = {
    status.value: status for status in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.CANCELED)
}


@attrs.frozen(kw_only=True)
class Record:
    """One observation of a trace.

    ``kind`` is the record's ``type``; ``time`` integer nanoseconds;
    ``message`` the begin or status message, the goal, the feedback or the
    result; ``accepted`` the answer of a goal or cancel response; ``status``
    the goal status of a result, or :data:`TERMINATED` for a cancel response
    that refused a cancel as of a goal already terminated; ``reason`` the
    reason a goal response gave.
    """

    line: int
    kind: str
    time: int
    goal_uuid: str = ""
    message: Any = None
    accepted: bool = False
    status: str = ""
    reason: RejectReason | None = None


@attrs.frozen
class Answer:
    """A goal's terminal answer as values: its goal ``status`` (``succeeded``, ``aborted`` or
    ``canceled``) and its ``result``."""

    status: str
    result: Result


#: The ``status`` of a cancel response (its trace field ``terminated``) that refused the cancel because
#: the goal had terminated when the server took the request (ROS 2:
#: :data:`dynevent.wire.vocab.CANCEL_GOAL_TERMINATED`).
TERMINATED = "terminated"

#: The ``detail`` of a ``log_seq`` finding seen apart from the server (a client's tap, a recording): a
#: log seq that skips within a child, which a feedback lost on the way leaves as a server's skip does
#: (at the server's tap the detail is ``"skips"``, the server's).
SKIPS_OR_LOST = "skips_or_lost"

#: What a finding saw, or what the machine owed in its place, as a value.
Shown: TypeAlias = "DynamicEventStatus | Goal | Feedback | Answer"


@attrs.frozen(kw_only=True)
class Finding:
    """One protocol violation: the trace ``line``, the docs/spec.md ``rule``, a short ``code``, what was
    seen (``message``) and what the rules expect (``expected``).

    The same as values, for a reader that sorts findings (never by their words): ``seen``, the
    status, goal, feedback or answer the finding is about; ``owed``, the status the machine's state
    has or the answer it owes in its place, where it has one; ``detail``, a short name for the
    circumstance where one code covers several (the :class:`~dynevent.server.machine.RaceLoss` of a
    race not lost, ``event_ended`` for feedback of a goal whose event has ended, ``answered`` for a
    status that still shows a child whose goal was answered).  :meth:`to_dict` gives the words."""

    line: int
    rule: str
    code: str
    message: str
    expected: str
    seen: Shown | None = None
    owed: Shown | None = None
    detail: str = ""

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
    if kind == "end":
        return Record(line=line, kind=kind, time=time)
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
        terminated = "terminated" in data and _boolean(data, "terminated", source, line)
        if accepted and terminated:
            raise TraceError(source, line, "terminated", "an accepted cancel's goal had not terminated")
        status = TERMINATED if terminated else ""
        return Record(line=line, kind=kind, time=time, goal_uuid=uuid, accepted=accepted, status=status)
    return Record(line=line, kind=kind, time=time, goal_uuid=uuid)


@attrs.frozen(kw_only=True)
class TraceHeader:
    """What a trace says before its records: the robot it is of, and the configuration of its server
    (from a config record), or how to judge the server without one."""

    fleet: str | None = None
    robot: str | None = None
    config: ServerConfig | None = None
    #: how the server is judged where no config record says: as the spec says, or as rmf_ros2 behaves
    compatibility: Compatibility = Compatibility.STANDARD
    #: where the records were seen: ``"client"`` (each channel in order, not the channels with one
    #: another, any of them late: :data:`TAPS`), ``"server"``, or None (unsaid: read as the server's)
    tap: str | None = None


#: Where a trace's records may be seen (its config record's ``tap``).
TAPS = ("client", "server")


def _header(data: dict[str, Any], source: str, line: int) -> TraceHeader:
    names: dict[str, str] = {}
    for key in ("fleet", "robot"):
        value = data.get(key)
        if value is not None and not isinstance(value, str):
            raise TraceError(source, line, key, f"expected a string, got {_json.dumps(value)}")
        if value is not None:
            names[key] = value
    tap = data.get("tap")
    if tap is not None and tap not in TAPS:
        raise TraceError(source, line, "tap", f"expected one of {list(TAPS)}, got {_json.dumps(tap)}")
    config = None
    if "config" in data:
        try:
            config = config_from_json(data["config"], "config")
        except InvalidRecord as exc:
            raise TraceError(source, line, exc.path, exc.problem) from None
    return TraceHeader(fleet=names.get("fleet"), robot=names.get("robot"), config=config, tap=tap)


def read_trace(lines: Iterable[str], source: str = "<trace>") -> tuple[TraceHeader, list[Record]]:
    """Parse a trace: its optional config record and its observations.

    Blank lines and lines starting with ``#`` are skipped.  Raises
    :class:`TraceError` naming ``source``, the line and the field.
    """
    header, records = stream_trace(lines, source)
    return header, list(records)


def stream_trace(lines: Iterable[str], source: str = "<trace>") -> tuple[TraceHeader, Iterator[Record]]:
    """Like :func:`read_trace`, but the observations come one at a time, as ``lines`` are read.

    The config record, if any, is read at once; each later line is parsed when
    the iterator reaches it (and a :class:`TraceError` raised from there).
    """
    parsed = _parsed_lines(lines, source)
    first = next(parsed, None)
    if first is None:
        return TraceHeader(), iter(())
    number, item = first
    if isinstance(item, dict):
        return _header(item, source, number), _observations(parsed, source)
    return TraceHeader(), _observations(itertools.chain([first], parsed), source)


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
    (with the reason, as an in-process binding can give it); a goal submitted
    (accepted by the transport, R5.3) its ``goal`` and an accepted response; an action-level
    cancel its ``cancel_request`` and ``cancel_response``; every publication,
    feedback and answer its record.  The other outputs are not on the wire.
    Feeding a server's steps through this gives a trace that
    :func:`check_trace` finds clean.
    """
    time = _seconds(event.now)
    outputs = tuple(outputs)
    rows: list[dict[str, Any]] = []
    if isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)):
        rows.append({"type": "goal", "goal_uuid": event.goal_uuid, "goal": event.goal.to_dict()})
    if isinstance(event, ins.GoalSubmitted) and not any(
        isinstance(output, outs.Ignored) for output in outputs
    ):
        # the transport accepted it before the step (R5.3): the response the client saw
        rows.append({"type": "goal_response", "goal_uuid": event.goal_uuid, "accepted": True})
    if isinstance(event, ins.CancelRequested):
        rows.append({"type": "cancel_request", "goal_uuid": event.goal_uuid})
    rows.extend(row for row in map(_output_record, outputs) if row is not None)
    return [{"time": time, **row} for row in rows]


def observation(
    kind: str,
    now: int,
    *,
    goal_uuid: str | None = None,
    message: Any = None,
    accepted: bool | None = None,
    status: GoalStatus | None = None,
    terminated: bool = False,
) -> dict[str, Any]:
    """The trace record of one thing seen on the wire at ``now`` (integer nanoseconds), from either end.

    ``message`` is the wire mirror the record holds (a begin or status message, a goal, feedback, a
    result); ``accepted`` the answer of a goal or cancel response; ``status`` a result's goal status;
    ``terminated`` a cancel response's refusal as of a goal already terminated.
    """
    row: dict[str, Any] = {"time": _seconds(now), "type": kind}
    if goal_uuid is not None:
        row["goal_uuid"] = goal_uuid
    if message is not None:
        row[_MESSAGE_FIELD.get(kind, "message")] = message.to_dict()
    if accepted is not None:
        row["accepted"] = accepted
    if status is not None:
        row["status"] = status.value
    if terminated:
        row["terminated"] = True
    return row


_MESSAGE_FIELD = {"goal": "goal", "feedback": "feedback", "result": "result"}


class TraceWriter:
    """Writes a trace file as things happen, one record per line, each line flushed as written (a
    process that dies keeps every record before its end).  Threads may share one writer.

    ``fleet`` and ``robot`` (and the server's ``config`` as JSON, when known) make the config record,
    with ``tap``, where the records are seen (:data:`TAPS`: a client's writer says ``"client"``).
    Raises :class:`~dynevent.errors.FileError` when the file cannot be opened.
    """

    def __init__(
        self,
        path: str | None,
        *,
        fleet: str | None = None,
        robot: str | None = None,
        config: Any = None,
        keep: bool = False,
        tap: str | None = None,
    ) -> None:
        self.path = path
        self.tap = tap
        self._lock = threading.Lock()
        # closed by close(); with no path, the trace is only kept (``keep``) for :meth:`text`
        self._stream: TextIO | None = None if path is None else files.create_text(path, "--trace")
        self._kept: list[str] | None = [] if keep or path is None else None
        self._closed = False
        header: dict[str, Any] = {"type": "config"}
        header.update({key: value for key, value in (("fleet", fleet), ("robot", robot)) if value})
        if config is not None:
            header["config"] = config
        if tap is not None:
            header["tap"] = tap
        self.write(header)

    def write(self, row: dict[str, Any]) -> None:
        """Write one record."""
        self._put(_json.dumps(row))

    def observe(
        self,
        kind: str,
        *,
        goal_uuid: str | None = None,
        message: Any = None,
        accepted: bool | None = None,
        status: GoalStatus | None = None,
        terminated: bool = False,
    ) -> None:
        """Write what a tap saw now (the wall clock): :func:`observation`'s record."""
        fields = {"goal_uuid": goal_uuid, "message": message, "accepted": accepted, "status": status}
        self.write(observation(kind, time.time_ns(), **fields, terminated=terminated))

    def comment(self, text: str) -> None:
        """Write a ``#`` line (skipped by readers), e.g. which probe case the next records belong to."""
        self._put("# " + " ".join(text.split()))

    def _put(self, line: str) -> None:
        with self._lock:
            if self._closed:  # a late callback after close writes nothing
                return
            if self._kept is not None:
                self._kept.append(line)
            if self._stream is not None:
                self._stream.write(line + "\n")
                self._stream.flush()

    def text(self) -> str:
        """Every line written so far, as a trace's text (a writer made with ``keep``, or no path)."""
        with self._lock:
            return "".join(line + "\n" for line in self._kept or ())

    def step(self, event: ins.Input, outputs: Iterable[outs.Output]) -> None:
        """Write the records of one step of a server machine (:func:`step_records`)."""
        for row in step_records(event, outputs):
            self.write(row)

    def close(self) -> None:
        with self._lock:
            self._closed = True
            if self._stream is not None:
                self._stream.close()


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


class Unreadable(Exception):
    """A record the observer cannot use: its field and the problem (turned into a TraceError)."""

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(problem)
