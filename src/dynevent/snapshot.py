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

import math
from typing import Any

from . import _json
from ._codec import CodecError, decode, encode
from .errors import DyneventError, InvalidSnapshot
from .machine import State
from .names import validate_token
from .vocab import Status

__all__ = ["FORMAT", "VERSION", "dumps", "loads", "restore", "snapshot"]

FORMAT = "dynevent.state"
#: The snapshot format version this release writes and reads.
VERSION = 1

_STATUSES = frozenset(status.value for status in Status)
_U32 = 2**32 - 1
_U64 = 2**64 - 1


def snapshot(state: State) -> dict[str, Any]:
    """The state as plain JSON values, with format and version."""
    return {"format": FORMAT, "version": VERSION, "state": encode(state)}


def dumps(state: State) -> str:
    """The snapshot as JSON text."""
    return _json.dumps(snapshot(state))


def _problems(state: State) -> list[tuple[str, str]]:
    """Every way ``state`` breaks what the machine relies on, as (path, problem)."""
    found: list[tuple[str, str]] = []
    for field in ("fleet", "robot"):
        try:
            validate_token(field, getattr(state, field))
        except DyneventError as exc:
            found.append((f"$.state.{field}", str(exc)))
    for field, high in (("seq", _U32), ("log_seq", _U32), ("event_id", _U64), ("last_id", _U64)):
        if not 0 <= getattr(state, field) <= high:
            found.append((f"$.state.{field}", f"out of range [0, {high}]"))
    if state.status not in _STATUSES:
        found.append(("$.state.status", f"unknown status {state.status!r}"))
    if state.task_signal not in ("", "canceled", "killed"):
        found.append(
            ("$.state.task_signal", f"expected '', 'canceled' or 'killed', got {state.task_signal!r}")
        )
    uuids = [queued.goal_uuid for queued in state.queued] + list(state.cancels)
    running = state.running
    if running is not None:
        uuids.append(running.goal_uuid)
        if not 0 <= running.child_id <= _U64:
            found.append(("$.state.running.child_id", "out of range for uint64"))
        if running.child_status not in _STATUSES and running.child_status != "":
            found.append(("$.state.running.child_status", f"unknown status {running.child_status!r}"))
        if not state.active:
            found.append(("$.state.running", "a goal runs while no dynamic event is active"))
    elif state.cancels:
        found.append(("$.state.cancels", "CANCEL goals wait while no goal runs"))
    for uuid in uuids:
        if len(uuid) != 32 or any(char not in "0123456789abcdef" for char in uuid):
            found.append(("$.state", f"goal uuid {uuid!r} is not 32 lowercase hexadecimal digits"))
    if len(set(uuids)) != len(uuids):
        found.append(("$.state", "a goal uuid appears twice"))
    stubborn = state.stubborn
    if stubborn is not None and not (math.isfinite(stubborn.period) and stubborn.period > 0):
        found.append(("$.state.stubborn.period", "expected a positive finite number of seconds"))
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
        raise InvalidSnapshot("$.format", f"expected {FORMAT!r}, got {data.get('format')!r}")
    version = data.get("version")
    if version != VERSION or type(version) is not int:
        raise InvalidSnapshot(
            "$.version", f"unsupported snapshot version {version!r}; this release reads {VERSION}"
        )
    extra = set(data) - {"format", "version", "state"}
    if extra:
        raise InvalidSnapshot("$", f"unknown keys {sorted(extra)}")
    try:
        state: State = decode(State, data.get("state"), "$.state")
    except CodecError as exc:
        raise InvalidSnapshot(exc.path, exc.problem) from None
    problems = _problems(state)
    if problems:
        raise InvalidSnapshot(*problems[0])
    return state


def loads(text: str | bytes | bytearray) -> State:
    """Restore a state from snapshot JSON text."""
    try:
        data = _json.parse(text)
    except _json.JsonProblem as exc:
        raise InvalidSnapshot("$", str(exc)) from None
    return restore(data)
