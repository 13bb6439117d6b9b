"""Snapshots: a robot's state as JSON, and back, with nothing lost.

A snapshot is a JSON object ``{"format": "dynevent.state", "version": 1,
"state": {...}}``.  :func:`restore` checks the format and version, the shape
of every field, and every value against the range and vocabulary the machine
relies on (seq and ids within uint32/uint64, statuses from the twelve, goal
UUIDs canonical, stubbornness consistent...), and refuses anything else with
:class:`~dynevent.errors.InvalidSnapshot` naming the path.  It never returns a
half-restored state.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import attrs

from dynevent.errors import DyneventError, InvalidSnapshot, short_repr
from dynevent.server.inputs import LOWER_HEX, NOW_RANGE
from dynevent.server.machine import SECONDS_RANGE, State
from dynevent.wire import _json
from dynevent.wire._codec import CodecError, decode, encode
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX, id_not_after
from dynevent.wire.description import EventDescription
from dynevent.wire.names import validate_robot, validate_token
from dynevent.wire.vocab import TASK_SIGNAL_LOGS, EventType, Status

#: A day in nanoseconds: a refresh instant may lie up to one refresh period past the last ``now``.
SECONDS_NS = 86_400 * SECOND

__all__ = ["FORMAT", "VERSION", "check_state", "dumps", "loads", "restore", "snapshot", "state_problems"]

FORMAT = "dynevent.state"
#: The snapshot format version this release writes and reads.
VERSION = 1

_STATUSES = frozenset(status.value for status in Status)
_TASK_SIGNALS = frozenset({"", *TASK_SIGNAL_LOGS})  # none, or the status a task signal gives (R13)
_STATE_FIELDS = frozenset(attrs.fields_dict(State))


def snapshot(state: State) -> dict[str, Any]:
    """The state as plain JSON values, with format and version."""
    return {"format": FORMAT, "version": VERSION, "state": encode(state)}


def dumps(state: State) -> str:
    """The snapshot as JSON text."""
    return _json.dumps(snapshot(state))


def state_problems(state: State) -> list[tuple[str, str]]:
    """Every way ``state`` breaks the state invariants of docs/spec.md (R19.8), as (path, problem).

    Empty for every state the machine can reach; the one check of snapshot
    restore, fleet restore and the conformance driver's reset.
    """
    found: list[tuple[str, str]] = []
    for field in ("fleet", "robot"):
        try:
            validate_token(field, getattr(state, field))
        except DyneventError as exc:
            found.append((f"$.state.{field}", str(exc)))
    if not found:
        try:
            validate_robot(state.fleet, state.robot)  # every protocol name of the robot can be built
        except DyneventError as exc:
            found.append(("$.state", str(exc)))
    found.extend(_phase_problems(state))
    for field, high in (("seq", U32_MAX), ("log_seq", U32_MAX), ("event_id", U64_MAX), ("last_id", U64_MAX)):
        if not 0 <= getattr(state, field) <= high:
            found.append((f"$.state.{field}", f"out of range [0, {high}]"))
    if state.status not in _STATUSES:
        found.append(("$.state.status", f"unknown status {state.status!r}"))
    if state.task_signal not in _TASK_SIGNALS:
        found.append(
            (
                "$.state.task_signal",
                f"expected '', {' or '.join(map(repr, TASK_SIGNAL_LOGS))}, got {state.task_signal!r}",
            )
        )
    uuids = [queued.goal_uuid for queued in state.queued] + list(state.cancels)
    running = state.running
    if running is not None:
        uuids.append(running.goal_uuid)
        if not 0 <= running.child_id <= U64_MAX:
            found.append(("$.state.running.child_id", "out of range for uint64"))
        if running.child_status not in _STATUSES and running.child_status != "":
            found.append(("$.state.running.child_status", f"unknown status {running.child_status!r}"))
        if not state.active:
            found.append(("$.state.running", "a goal runs while no dynamic event is active"))
    elif state.cancels:
        found.append(("$.state.cancels", "CANCEL goals wait while no goal runs"))
    for uuid in uuids:
        if len(uuid) != 32 or not LOWER_HEX.issuperset(uuid):
            found.append(("$.state", f"goal uuid {uuid!r} is not 32 lowercase hexadecimal digits"))
    if len(set(uuids)) != len(uuids):
        found.append(("$.state", "a goal uuid appears twice"))
    stubborn = state.stubborn
    anchor = None if stubborn is None else stubborn.anchor
    for position, where in ((state.position, "position"), (anchor, "stubborn.anchor")):
        if position is not None and not (math.isfinite(position.x) and math.isfinite(position.y)):
            found.append((f"$.state.{where}", "coordinates must be finite"))
    return found


def restore(data: object) -> State:
    """The state a snapshot holds; raises :class:`InvalidSnapshot` for anything else."""
    if not isinstance(data, dict):
        raise InvalidSnapshot("$", f"expected a JSON object, got {type(data).__name__}")
    if data.get("format") != FORMAT:
        raise InvalidSnapshot("$.format", f"expected {FORMAT!r}, got {short_repr(data.get('format'))}")
    version = data.get("version")
    if version != VERSION or type(version) is not int:
        raise InvalidSnapshot(
            "$.version", f"unsupported snapshot version {short_repr(version)}; this release reads {VERSION}"
        )
    extra = set(data) - {"format", "version", "state"}
    if extra:
        raise InvalidSnapshot("$", f"unknown keys {sorted(extra)}")
    try:
        state: State = decode(State, data.get("state"), "$.state")
    except CodecError as exc:
        raise InvalidSnapshot(exc.path, exc.problem) from None
    fields = data.get("state")
    missing = sorted(_STATE_FIELDS - set(fields)) if isinstance(fields, dict) else []
    if missing:
        raise InvalidSnapshot(
            "$.state", f"missing fields {missing}: a snapshot holds exactly the state's fields"
        )
    check_state(state)
    return state


def check_state(state: State) -> State:
    """``state`` if it keeps the state invariants (R19.8); else :class:`InvalidSnapshot` (the first fault)."""
    problems = state_problems(state)
    if problems:
        raise InvalidSnapshot(*problems[0])
    return state


@functools.lru_cache(maxsize=256)
def _description_problem(text: str) -> str | None:
    """Why a begin description cannot be parsed, or None (cached: a fleet's robots share a few)."""
    try:
        EventDescription.from_json(text)
    except DyneventError as exc:
        return str(exc)
    return None


def _phase_problems(state: State) -> list[tuple[str, str]]:
    """The invariants that tie the fields together (R19.8)."""
    found: list[tuple[str, str]] = []
    running, stubborn = state.running, state.stubborn
    if state.description:
        problem = _description_problem(state.description)
        if problem is not None:
            found.append(("$.state.description", problem))
    if state.shutdown and (state.active or state.queued or stubborn is not None):
        found.append(
            ("$.state.shutdown", "a server shutting down has no active run, queued goal or hold (R15.2)")
        )
    if running is not None:
        if running.goal.event_type != EventType.NEXT:
            found.append(("$.state.running.goal", "only a NEXT goal holds the running slot (R2.1)"))
        if not id_not_after(running.child_id, state.last_id):  # ids the adapter drew since (R17.8)
            found.append(
                (
                    "$.state.last_id",
                    f"is {state.last_id}, before the running child's id {running.child_id} (R6.2)",
                )
            )
        if not math.isfinite(running.goal.stubborn_period):
            found.append(
                ("$.state.running.goal.stubborn_period", "not finite: such a NEXT is refused (R4.11)")
            )
        if not running.started and not state.interrupted:
            found.append(
                ("$.state.running.started", "a child's start is deferred only while interrupted (R6.3)")
            )
    if state.cancels and (running is None or not running.started):
        found.append(("$.state.cancels", "CANCEL goals wait only for a started child (R9.3, R9.4)"))
    if stubborn is not None:
        if not state.active or (running is not None and running.started):
            found.append(("$.state.stubborn", "a hold lasts only between children of an active run (R12.5)"))
        low, high = NOW_RANGE
        for field in ("hold_since", "next_refresh"):
            if not low <= getattr(stubborn, field) <= high + SECONDS_NS:
                found.append((f"$.state.stubborn.{field}", "outside the range of builtin_interfaces/Time"))
        if stubborn.next_refresh < stubborn.hold_since:
            found.append(("$.state.stubborn.next_refresh", "before the hold began (R12.3)"))
        if not (math.isfinite(stubborn.period) and stubborn.period >= SECONDS_RANGE[0]):
            found.append(
                ("$.state.stubborn.period", f"expected at least {SECONDS_RANGE[0]:g} s (R0.1, R19.4)")
            )
    return found


def loads(text: str | bytes | bytearray) -> State:
    """Restore a state from snapshot JSON text."""
    try:
        data = _json.parse(text, bounded=False)  # restore decodes against the state's schema
    except _json.JsonProblem as exc:
        raise InvalidSnapshot("$", str(exc)) from None
    return restore(data)
