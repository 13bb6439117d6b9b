"""The server rules the workloads exercise, written once in plain Python for every peer.

Every peer does dynevent's work, not less:

- **inputs are checked** as dynevent's input classes check them (types, the
  wire's ranges, goal UUIDs, the status and tier vocabularies, the log text
  limit, float32 rounding of the stubborn period, the begin description's
  JSON), and a bad input raises ``ValueError`` naming the field and value;
- **outputs are whole**: each is a tuple holding exactly the fields and values
  of dynevent's output, nested messages included (the feedback's ``LogEntry``
  values with their ``unix_millis_time``, the status messages' ``Time``, the
  child start's category, description and parsed description, a rejection's
  every field and sentence); :func:`bench.peers.script.plain` writes
  dynevent's outputs in the same form, and the tests compare them whole;
- **the state is a value**: a plain tuple (see :data:`DATA`), replaced by a new
  one at every step that changes it, as dynevent replaces its frozen state;
- descriptions are parsed by dynevent's own strict reader (the same work for
  every implementation), and each NEXT's parsed description is carried from
  its acceptance to its start.

Covered: the seq check, the inactive and busy checks, event types, the
category and JSON checks of a NEXT, the stale-id and cancel-id checks, the
race check when a goal starts, the stubborn clamp and stubbornness, and result
routing (the running goal's answer and every waiting CANCEL goal's answer).
Not covered (no workload needs them): action-level cancel, interruptions,
task cancel and kill, shutdown, ticks.

A peer provides :meth:`Rules.phase` and the four phase moves ``ev_begin``,
``ev_start``, ``ev_child_end`` and ``ev_finish`` (triggers of a state-machine
library, or nothing at all when the phase is read from the data).
"""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Callable, Sequence
from typing import Any

from dynevent.server.inputs import LOWER_HEX, MAX_LOG_TEXT_LENGTH, NOW_RANGE
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX
from dynevent.wire._json import JsonProblem, parse, utf8_size
from dynevent.wire.description import MAX_DESCRIPTION_BYTES
from dynevent.wire.vocab import DynamicState, EventType, Failure, Status, Tier

# The protocol's facts, read from dynevent's vocabulary and limits (the peers differ in how they
# work, not in what the protocol says), as plain builtins.
INACTIVE, WAITING, RUNNING = (int(phase) for phase in DynamicState)
NEXT, CANCEL, FINISHED = int(EventType.NEXT), int(EventType.CANCEL), int(EventType.FINISHED)
_U32, _U64 = U32_MAX, U64_MAX
_NOW_LOW, _NOW_HIGH = NOW_RANGE
_MAX_LOG_TEXT = MAX_LOG_TEXT_LENGTH
_MAX_DESCRIPTION = MAX_DESCRIPTION_BYTES
_EARLY_END = frozenset({Status.CANCELED.value, Status.KILLED.value, Status.SKIPPED.value})
_STATUSES = frozenset(status.value for status in Status)
_TIERS = frozenset(tier.value for tier in Tier)
_HEX = LOWER_HEX
_F32 = struct.Struct("<f")

# rmf_ros2's execution-failure strings
RACE = Failure.RACE.value
IDLE_CANCEL = Failure.IDLE_CANCEL.value
CANCEL_ID = Failure.CANCEL_ID.value
EVENT_TYPE = Failure.EVENT_TYPE.value
PARSE = Failure.PARSE.value

#: A goal in raw form: (seq, event_type, category, description, id, stubborn_period).
Goal = tuple[int, int, str, str, int, float]
#: A description validator: (category, parsed) -> errors, as dynevent's ServerConfig takes.
Validator = Callable[[str, Any], Sequence[str]]

# The data tuple's fields, in order.  running = (uuid, goal, child_id, child_status, canceling);
# queued = ((uuid, goal, parsed), ...); cancels = (uuid, ...); stubborn = (period, since) or None.
DATA = (
    "fleet",
    "robot",
    "seq",
    "active",
    "event_id",
    "description",
    "status",
    "last_id",
    "running",
    "queued",
    "cancels",
    "stubborn",
    "log_seq",
)
(
    FLEET,
    ROBOT,
    SEQ,
    ACTIVE,
    EVENT_ID,
    DESCRIPTION,
    STATUS,
    LAST_ID,
    RUNNING_GOAL,
    QUEUED,
    CANCELS,
    STUBBORN,
    LOG_SEQ,
) = range(len(DATA))


# --------------------------------------------------------------------------- input checks


def bad(owner: str, field: str, value: Any, why: str) -> ValueError:
    """The error of a bad input: the field, the value, and why."""
    return ValueError(f"{owner}.{field} = {value!r}: {why}")


def check_int(owner: str, field: str, value: Any, high: int) -> int:
    if type(value) is not int:
        raise bad(owner, field, value, "expected an integer")
    if not 0 <= value <= high:
        raise bad(owner, field, value, f"out of range [0, {high}]")
    return value


def check_string(owner: str, field: str, value: Any) -> str:
    if type(value) is not str:
        raise bad(owner, field, value, "expected a string")
    if not value.isascii():
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            raise bad(owner, field, value, "not UTF-8 encodable") from None
    if "\x00" in value:
        raise bad(owner, field, value, "NUL character")
    return value


def check_now(owner: str, value: Any) -> int:
    if type(value) is not int:
        raise bad(owner, "now", value, "expected integer nanoseconds")
    if not _NOW_LOW <= value <= _NOW_HIGH:
        raise bad(owner, "now", value, "outside the range of builtin_interfaces/Time")
    return value


def check_uuid(owner: str, value: Any) -> str:
    if type(value) is str and len(value) == 32:
        lowered = value.lower()
        if _HEX.issuperset(lowered):
            return lowered
    raise bad(owner, "goal_uuid", value, "expected 32 hexadecimal digits")


def check_one_of(owner: str, field: str, value: Any, allowed: frozenset[str]) -> str:
    if type(value) is not str or value not in allowed:
        raise bad(owner, field, value, f"expected one of {sorted(allowed)}")
    return value


def float32(owner: str, field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise bad(owner, field, value, "expected a number")
    try:
        rounded: float = _F32.unpack(_F32.pack(value))[0]
    except (OverflowError, struct.error):
        raise bad(owner, field, value, "out of range for float32") from None
    return math.nan if math.isnan(rounded) else rounded


def check_goal(raw: Sequence[Any]) -> Goal:
    """A raw goal checked as dynevent's ``Goal`` checks it."""
    seq, event_type, category, description, goal_id, period = raw
    return (
        check_int("Goal", "dynamic_event_seq", seq, _U32),
        check_int("Goal", "event_type", event_type, _U32),
        check_string("Goal", "category", category),
        check_string("Goal", "description", description),
        check_int("Goal", "id", goal_id, _U64),
        float32("Goal", "stubborn_period", period),
    )


# --------------------------------------------------------------------------- JSON
# dynevent's strict reader (duplicate keys refused, nesting bounded, one cached decoder): parsing is
# the same work for every implementation, so they share it, and its sentences.


def check_begin_description(value: Any) -> str:
    """A begin description: strict JSON of at most 1 MB, an object whose category and detail are strings."""
    text = check_string("Begin", "description", value)
    if utf8_size(text) > _MAX_DESCRIPTION:
        raise bad("Begin", "description", value, f"above the limit of {_MAX_DESCRIPTION} bytes")
    try:
        parsed = parse(text)
    except JsonProblem as exc:
        raise bad("Begin", "description", value, str(exc)) from None
    if type(parsed) is not dict:
        raise bad("Begin", "description", value, "expected a JSON object")
    for key in ("category", "detail"):
        if key in parsed and type(parsed[key]) is not str:
            raise bad("Begin", "description", value, f"{key} must be a string")
    return text


# --------------------------------------------------------------------------- outputs


def time(now: int) -> tuple[str, int, int]:
    sec, nanosec = divmod(now, SECOND)
    return ("Time", sec, nanosec)


def refused(
    uuid: str,
    reason: str,
    text: str,
    failure: str = "",
    expected: int | None = None,
    received: int | None = None,
    current: int | None = None,
    requested: int | None = None,
    categories: tuple[str, ...] = (),
    errors: tuple[str, ...] = (),
) -> tuple[tuple[Any, ...], None]:
    """What :meth:`Rules.decide` returns for a refused goal: the ``goal_rejected`` output, no description."""
    rejection = (
        "Rejected",
        reason,
        text,
        expected,
        received,
        current,
        requested,
        categories,
        errors,
        failure,
    )
    return ("goal_rejected", uuid, rejection), None


def answer(uuid: str, status: str, failure: str, result_status: str, result_id: int) -> tuple[Any, ...]:
    return ("answer_goal", uuid, status, ("Result", failure, result_status, result_id))


def status_output(seq: int, phase: int, status: str, event_id: int, now: int) -> tuple[Any, ...]:
    return ("publish_status", ("DynamicEventStatus", seq, phase, status, event_id, time(now)))


def ignored(kind: str, why: str) -> list[tuple[Any, ...]]:
    return [("ignored", kind, why)]


# --------------------------------------------------------------------------- the rules


def fresh(fleet: str, robot: str) -> tuple[Any, ...]:
    """The data of a robot whose server has just started."""
    return (fleet, robot, 0, False, 0, "", "uninitialized", 0, None, (), (), None, 0)


class Rules:
    """The rules over a data tuple (:data:`DATA`) and an abstract phase."""

    __slots__ = ()

    data: tuple[Any, ...]
    categories: dict[str, Validator]
    stubborn_minimum: float

    def __init__(
        self,
        fleet: str,
        robot: str,
        categories: dict[str, Validator],
        stubborn_minimum: float = 2.0,
        initial: str | None = None,
    ) -> None:
        """A fresh robot's server; ``initial`` is the state a library peer's machine starts in (restore)."""
        self.data = fresh(check_string("State", "fleet", fleet), check_string("State", "robot", robot))
        self.categories = categories
        self.stubborn_minimum = stubborn_minimum
        self.start_machine(initial)

    def start_machine(self, initial: str | None) -> None:
        """Build the peer's phase machine, if it has one, in state ``initial`` (None: the first)."""

    # the phase moves, provided by each peer (declared only: a library binds its triggers to these names)
    ev_begin: Callable[[], Any]
    ev_start: Callable[[], Any]
    ev_child_end: Callable[[], Any]
    ev_finish: Callable[[], Any]

    def phase(self) -> int:
        raise NotImplementedError

    # ------------------------------------------------------------------ decisions

    def decide(self, uuid: str, goal: Goal) -> tuple[tuple[Any, ...] | None, Any]:
        """``(None, parsed description)`` when the goal is accepted (the description is None for a
        goal other than NEXT), else ``(the goal_rejected output, None)``: dynevent's checks in its order."""
        data = self.data
        seq, event_type, category, description, goal_id, period = goal
        if seq != data[SEQ]:
            return refused(uuid, "seq_mismatch", f"Expected {data[SEQ]}, received {seq}", "", data[SEQ], seq)
        phase = self.phase()
        if phase == INACTIVE:
            return refused(uuid, "inactive", "no dynamic event is active for this robot")
        if event_type == 0:
            return refused(
                uuid,
                "uninitialized_event_type",
                "event_type is 0 (UNINITIALIZED): the goal was default-initialized",
                EVENT_TYPE,
            )
        if event_type > FINISHED:
            return refused(
                uuid,
                "unknown_event_type",
                f"event_type {event_type} is none of NEXT (1), CANCEL (2), FINISHED (3)",
                EVENT_TYPE,
            )
        running = data[RUNNING_GOAL]
        if phase == RUNNING and event_type != CANCEL:
            return refused(
                uuid,
                "busy",
                f"event {running[2]} is running: only a CANCEL with its id is accepted",
                current=running[2],
            )
        if event_type == NEXT:
            validator = self.categories.get(category)
            if validator is None:
                supported = tuple(sorted(self.categories))
                text = f"category {category!r} is not supported; supported: {', '.join(supported) or 'none'}"
                return refused(uuid, "unsupported_category", text, categories=supported)
            size = utf8_size(description)
            if size > _MAX_DESCRIPTION:
                problem = f"description is {size} bytes, above the limit of {_MAX_DESCRIPTION}"
                return refused(
                    uuid, "description_invalid", problem, f"{PARSE}\n -- {problem}", errors=(problem,)
                )
            try:
                parsed = parse(description)
            except JsonProblem as exc:
                return refused(
                    uuid,
                    "description_not_json",
                    f"the description of the {category!r} event is {exc}",
                    f"{PARSE}\n -- {exc}",
                    errors=(str(exc),),
                )
            errors = tuple(str(error) for error in validator(category, parsed))
            if errors:
                return refused(
                    uuid,
                    "description_invalid",
                    f"the description does not fit the {category!r} category: " + "; ".join(errors),
                    PARSE + "".join(f"\n -- {error}" for error in errors),
                    errors=errors,
                )
            if not math.isfinite(period):
                return refused(
                    uuid, "non_finite_stubborn_period", f"stubborn_period {period} is not a finite number"
                )
            last_id = data[LAST_ID]
            if goal_id == 0 and last_id == _U64:
                text = f"id 0 asks the server for the next id, and none is left above {last_id}"
                return refused(uuid, "stale_id", text, current=last_id, requested=0)
            if goal_id != 0 and goal_id <= last_id:
                text = f"id {goal_id} is not greater than {last_id}, the highest id used in this run"
                return refused(uuid, "stale_id", text, current=last_id, requested=goal_id)
            return None, parsed
        if event_type == CANCEL:
            if running is None:
                return refused(uuid, "cancel_idle", "no event is running to cancel", IDLE_CANCEL)
            if goal_id != running[2]:
                return refused(
                    uuid,
                    "cancel_id_mismatch",
                    f"the running event is {running[2]}, the CANCEL names {goal_id}",
                    CANCEL_ID,
                    current=running[2],
                    requested=goal_id,
                )
        return None, None

    def accept(self, raw: Sequence[Any]) -> tuple[str, ...]:
        """("accept",) or ("reject", reason): a pure query."""
        rejection, _ = self.decide("0" * 32, check_goal(raw))
        return ("accept",) if rejection is None else ("reject", rejection[2][1])

    # ------------------------------------------------------------------ inputs

    def begin(self, event_id: int, description: str, now: int) -> list[tuple[Any, ...]]:
        """A dynamic event begins."""
        event_id = check_int("Begin", "event_id", event_id, _U64)
        description = check_begin_description(description)
        now = check_now("Begin", now)
        if self.phase() != INACTIVE:
            return ignored("begin", "a dynamic event is already active")
        data = self.data
        fleet, robot = data[FLEET], data[ROBOT]
        seq = (data[SEQ] + 1) & _U32
        self.data = (fleet, robot, seq, True, event_id, description, "standby", event_id, *data[8:])
        self.ev_begin()
        stamp = time(now)
        return [
            ("publish_begin", ("DynamicEventDescription", fleet, robot, seq, description, stamp)),
            ("publish_status", ("DynamicEventStatus", seq, WAITING, "standby", event_id, stamp)),
        ]

    def request(self, uuid: str, raw: Sequence[Any], now: int) -> list[tuple[Any, ...]]:
        """A goal request arrives."""
        uuid = check_uuid("GoalRequested", uuid)
        goal = check_goal(raw)
        check_now("GoalRequested", now)
        data = self.data
        running = data[RUNNING_GOAL]
        if (
            any(queued[0] == uuid for queued in data[QUEUED])
            or uuid in data[CANCELS]
            or (running is not None and running[0] == uuid)
        ):
            return ignored("goal_requested", "a goal with this uuid is already open")
        rejection, parsed = self.decide(uuid, goal)
        if rejection is not None:
            return [rejection]
        self.data = (*data[:QUEUED], (*data[QUEUED], (uuid, goal, parsed)), *data[QUEUED + 1 :])
        return [("goal_accepted", uuid)]

    def start(self, uuid: str, now: int) -> list[tuple[Any, ...]]:
        """An accepted goal starts."""
        uuid = check_uuid("GoalStarted", uuid)
        now = check_now("GoalStarted", now)
        data = self.data
        found = next((queued for queued in data[QUEUED] if queued[0] == uuid), None)
        if found is None:
            return ignored("goal_started", "no accepted goal with this uuid is waiting to start")
        _, goal, parsed = found
        queued = tuple(other for other in data[QUEUED] if other is not found)
        out: list[tuple[Any, ...]] = [("execute_goal", uuid)]
        seq, event_type, _category, _description, goal_id, _period = goal
        phase = self.phase()
        last_id = data[LAST_ID]
        if (
            seq != data[SEQ]
            or phase == INACTIVE
            or (phase == RUNNING and event_type != CANCEL)
            or (event_type == NEXT and (last_id == _U64 if goal_id == 0 else goal_id <= last_id))
        ):
            self.data = (*data[:QUEUED], queued, *data[QUEUED + 1 :])
            out.append(answer(uuid, "aborted", RACE, "", 0))
            return out
        if event_type == NEXT:
            return self._start_next(data, queued, uuid, goal, parsed, now, out)
        if event_type == CANCEL:
            running = data[RUNNING_GOAL]
            if running is None:
                out.append(answer(uuid, "aborted", IDLE_CANCEL, "", 0))
            elif goal_id != running[2]:
                out.append(answer(uuid, "aborted", CANCEL_ID, "", 0))
            else:
                if not running[4]:
                    running = (*running[:4], True)
                    out.append(("cancel_child", running[2]))
                self.data = (
                    *data[:RUNNING_GOAL],
                    running,
                    queued,
                    (*data[CANCELS], uuid),
                    *data[CANCELS + 1 :],
                )
                return out
            self.data = (*data[:QUEUED], queued, *data[QUEUED + 1 :])
            return out
        # FINISHED
        if data[STUBBORN] is not None:
            out.append(("stubborn_end",))
        out.append(answer(uuid, "succeeded", "", "completed", data[EVENT_ID]))
        out.append(("dynamic_event_finished", "completed"))
        self.data = (
            *data[:ACTIVE],
            False,
            data[EVENT_ID],
            data[DESCRIPTION],
            "completed",
            last_id,
            None,
            queued,
            (),
            None,
            data[LOG_SEQ],
        )
        self.ev_finish()
        out.append(status_output(seq, INACTIVE, "uninitialized", 0, now))
        return out

    def _start_next(
        self,
        data: tuple[Any, ...],
        queued: tuple[Any, ...],
        uuid: str,
        goal: Goal,
        parsed: Any,
        now: int,
        out: list[tuple[Any, ...]],
    ) -> list[tuple[Any, ...]]:
        seq, _, category, description, goal_id, period = goal
        logs: tuple[Any, ...] = ()
        log_seq = data[LOG_SEQ]
        minimum = self.stubborn_minimum
        if 0.0 < period < minimum:
            out.append(("stubborn_clamped", period, minimum))
            text = (
                f"stubborn_period {period:g} s is below the minimum of {minimum:g} s; "
                f"{minimum:g} s will be used"
            )
            entry = ("LogEntry", log_seq, "warning", now // 1_000_000, text)
            out.append(("log", entry))
            logs = (entry,)
            log_seq = (log_seq + 1) & _U32
        child_id = goal_id or (data[LAST_ID] + 1) & _U64
        if data[STUBBORN] is not None:
            out.append(("stubborn_end",))
        out.append(("start_child", category, description, child_id, parsed))
        out.append(("publish_feedback", uuid, ("Feedback", "underway", child_id, logs)))
        running = (uuid, goal, child_id, "underway", False)
        self.data = (*data[:STATUS], "underway", child_id, running, queued, data[CANCELS], None, log_seq)
        self.ev_start()
        out.append(status_output(seq, RUNNING, "underway", child_id, now))
        return out

    def progress(self, status: str, text: str | None, tier: str, now: int) -> list[tuple[Any, ...]]:
        """The running child reports a status, maybe with a log line."""
        check_one_of("ChildProgress", "status", status, _STATUSES)
        check_now("ChildProgress", now)
        if text is not None:
            check_string("ChildProgress", "log_text", text)
            if len(text) > _MAX_LOG_TEXT:
                raise bad("ChildProgress", "log_text", text, f"above the limit of {_MAX_LOG_TEXT}")
        check_one_of("ChildProgress", "tier", tier, _TIERS)
        data = self.data
        running = data[RUNNING_GOAL]
        if running is None:
            return ignored("child_progress", "no child event is running")
        out: list[tuple[Any, ...]] = []
        logs: tuple[Any, ...] = ()
        log_seq = data[LOG_SEQ]
        if text is not None:
            entry = ("LogEntry", log_seq, tier, now // 1_000_000, text)
            out.append(("log", entry))
            logs = (entry,)
            log_seq = (log_seq + 1) & _U32
        child_id = running[2]
        out.append(("publish_feedback", running[0], ("Feedback", status, child_id, logs)))
        if running[3] != status:
            running = (*running[:3], status, running[4])
        changed = status != data[STATUS]
        self.data = (*data[:STATUS], status, data[LAST_ID], running, *data[QUEUED:LOG_SEQ], log_seq)
        if changed:
            out.append(status_output(data[SEQ], RUNNING, status, child_id, now))
        return out

    def finished(self, status: str, now: int) -> list[tuple[Any, ...]]:
        """The running child ended: answer its goal and every waiting CANCEL goal."""
        check_one_of("ChildFinished", "status", status, _STATUSES)
        check_now("ChildFinished", now)
        data = self.data
        running = data[RUNNING_GOAL]
        if running is None:
            return ignored("child_finished", "no child event is running")
        child_id = running[2]
        result = ("Result", "", status, child_id)
        outcome = "aborted" if status in _EARLY_END else "succeeded"
        out: list[tuple[Any, ...]] = [("answer_goal", running[0], outcome, result)]
        for uuid in data[CANCELS]:
            out.append(("answer_goal", uuid, "succeeded", result))
        period = running[1][5]
        stubborn = None
        if period > 0.0:
            applied = max(period, self.stubborn_minimum)
            stubborn = (applied, now)
            out.append(("stubborn_begin", applied, now, None, 0.0, 0.0))
        self.data = (
            *data[:STATUS],
            "standby",
            data[LAST_ID],
            None,
            data[QUEUED],
            (),
            stubborn,
            data[LOG_SEQ],
        )
        self.ev_child_end()
        out.append(status_output(data[SEQ], WAITING, "standby", data[LAST_ID], now))
        return out

    # ------------------------------------------------------------------ snapshots

    def dump(self) -> dict[str, Any]:
        """The data as plain JSON values."""
        data = dict(zip(DATA, self.data, strict=True))
        running = data["running"]
        if running is not None:
            data["running"] = [running[0], list(running[1]), *running[2:]]
        data["queued"] = [[uuid, list(goal)] for uuid, goal, _ in data["queued"]]
        data["cancels"] = list(data["cancels"])
        if data["stubborn"] is not None:
            data["stubborn"] = list(data["stubborn"])
        return data

    def load(self, data: dict[str, Any]) -> None:
        """Take the data of :meth:`dump`, checked as dynevent checks a snapshot; ``ValueError`` if bad."""
        if type(data) is not dict or set(data) != set(DATA):
            raise bad("snapshot", "$", data, f"expected an object with exactly the keys {list(DATA)}")
        for field in ("fleet", "robot", "description"):
            check_string("snapshot", field, data[field])
        for field, high in (("seq", _U32), ("log_seq", _U32), ("event_id", _U64), ("last_id", _U64)):
            check_int("snapshot", field, data[field], high)
        if type(data["active"]) is not bool:
            raise bad("snapshot", "active", data["active"], "expected a bool")
        check_one_of("snapshot", "status", data["status"], _STATUSES)
        if data["description"]:
            check_begin_description(data["description"])
        uuids = [check_uuid("snapshot", uuid) for uuid in data["cancels"]]
        running = data["running"]
        if running is not None:
            uuid, goal, child_id, child_status, canceling = running
            goal = check_goal(goal)
            running = (check_uuid("snapshot", uuid), goal, check_int("snapshot", "child_id", child_id, _U64))
            running += (check_one_of("snapshot", "child_status", child_status, _STATUSES), bool(canceling))
            uuids.append(running[0])
            if not data["active"] or child_id != data["last_id"] or goal[1] != NEXT:
                raise bad("snapshot", "running", data["running"], "breaks the state invariants")
        elif data["cancels"]:
            raise bad("snapshot", "cancels", data["cancels"], "CANCEL goals wait while no goal runs")
        queued = []
        for uuid, raw in data["queued"]:
            goal = check_goal(raw)
            queued.append((check_uuid("snapshot", uuid), goal, self._reparse(goal)))
            uuids.append(queued[-1][0])
        if len(set(uuids)) != len(uuids):
            raise bad("snapshot", "$", uuids, "a goal uuid appears twice")
        stubborn = data["stubborn"]
        if stubborn is not None:
            period, since = stubborn
            if not math.isfinite(period) or period <= 0 or running is not None or not data["active"]:
                raise bad("snapshot", "stubborn", stubborn, "breaks the state invariants")
            stubborn = (float(period), check_now("snapshot", since))
        cancels = tuple(uuids[: len(data["cancels"])])
        values = {
            **data,
            "running": running,
            "queued": tuple(queued),
            "cancels": cancels,
            "stubborn": stubborn,
        }
        self.data = tuple(values[field] for field in DATA)

    def _reparse(self, goal: Goal) -> Any:
        """A queued NEXT's parsed description (a snapshot holds the text only)."""
        if goal[1] != NEXT:
            return None
        try:
            return parse(goal[3])
        except JsonProblem:
            return None

    def dumped_phase(self) -> int:
        """The phase implied by the data."""
        data = self.data
        if not data[ACTIVE]:
            return INACTIVE
        return WAITING if data[RUNNING_GOAL] is None else RUNNING

    def saved_phase(self) -> str | None:
        """The name of a library peer's machine state, saved beside the data (None: no machine)."""
        return None

    def snapshot(self) -> dict[str, Any]:
        """The robot's data, and its machine's state if it has one, as plain JSON values."""
        data = self.dump()
        phase = self.saved_phase()
        if phase is not None:
            data["phase"] = phase
        return data

    @classmethod
    def restore(
        cls, snapshot: dict[str, Any], categories: dict[str, Validator], stubborn_minimum: float = 2.0
    ) -> Any:
        """A server holding the data of :meth:`snapshot`, checked; a library peer's machine started
        in the saved state, which must agree with the data."""
        if type(snapshot) is not dict:
            raise bad("snapshot", "$", snapshot, "expected a JSON object")
        data = dict(snapshot)
        phase = data.pop("phase", None)
        server = cls(
            str(data.get("fleet")), str(data.get("robot")), categories, stubborn_minimum, initial=phase
        )
        server.load(data)
        if server.phase() != server.dumped_phase():
            raise bad("snapshot", "phase", phase, "does not agree with the data")
        return server

    def dumps(self) -> str:
        """:meth:`snapshot` as JSON text."""
        return json.dumps(self.snapshot())

    @classmethod
    def loads(cls, text: str, categories: dict[str, Validator], stubborn_minimum: float = 2.0) -> Any:
        """A server holding the snapshot of :meth:`dumps`."""
        try:
            snapshot = parse(text)
        except JsonProblem as exc:
            raise bad("snapshot", "$", text, str(exc)) from None
        return cls.restore(snapshot, categories, stubborn_minimum)
