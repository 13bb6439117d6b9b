"""The server rules the workloads exercise, written once in plain Python for every peer.

Covered: the seq check, the inactive and busy checks, event types, category
and JSON checks of a NEXT, the stale-id and cancel-id checks, the race check
when a goal starts, the stubborn clamp and stubbornness, and result routing
(the running goal's answer and every waiting CANCEL goal's answer).  Not
covered (no workload needs them): action-level cancel, interruptions, task
cancel and kill, shutdown, ticks.

A peer keeps its data in plain attributes and its phase wherever it likes:
it provides :meth:`Rules.phase` and the four phase moves ``ev_begin``,
``ev_start``, ``ev_child_end`` and ``ev_finish`` (triggers of a state machine
library, or plain methods).  Outputs and decisions are tuples of the common
form of :mod:`bench.peers.script`.
"""

from __future__ import annotations

import json
import math
from typing import Any

INACTIVE, WAITING, RUNNING = 0, 1, 2
NEXT, CANCEL, FINISHED = 1, 2, 3
_U32 = 2**32 - 1
_U64 = 2**64 - 1
_EARLY_END = frozenset({"canceled", "killed", "skipped"})

#: A goal in raw form: (seq, event_type, category, description, id, stubborn_period).
Goal = tuple[int, int, str, str, int, float]

#: The data attributes every peer holds, in snapshot order.
DATA = (
    "fleet",
    "robot",
    "seq",
    "active",
    "event_id",
    "status",
    "last_id",
    "running",
    "queued",
    "cancels",
    "stubborn",
    "log_seq",
)


class Running:
    """The goal holding the running slot and its child."""

    __slots__ = ("canceling", "child_id", "child_status", "goal", "uuid")

    def __init__(self, uuid: str, goal: Goal, child_id: int, child_status: str) -> None:
        self.uuid = uuid
        self.goal = goal
        self.child_id = child_id
        self.child_status = child_status
        self.canceling = False


class Rules:
    """The rules over the data attributes of :data:`DATA` and an abstract phase."""

    __slots__ = ()

    # attributes the peer holds (declared for readers; set by setup)
    fleet: str
    robot: str
    categories: frozenset[str]
    stubborn_minimum: float
    seq: int
    active: bool
    event_id: int
    status: str
    last_id: int
    running: Running | None
    queued: dict[str, Goal]
    cancels: list[str]
    stubborn: float | None
    log_seq: int

    def setup(self, fleet: str, robot: str, categories: frozenset[str], stubborn_minimum: float) -> None:
        """Fresh data of a robot whose server has just started."""
        self.fleet = fleet
        self.robot = robot
        self.categories = categories
        self.stubborn_minimum = stubborn_minimum
        self.seq = 0
        self.active = False
        self.event_id = 0
        self.status = "uninitialized"
        self.last_id = 0
        self.running = None
        self.queued = {}
        self.cancels = []
        self.stubborn = None
        self.log_seq = 0

    # phase hooks, provided by each peer
    def phase(self) -> int:
        raise NotImplementedError

    # ------------------------------------------------------------------ decisions

    def accept(self, goal: Goal) -> tuple[str, ...]:
        """("accept",) or ("reject", reason), in dynevent's check order."""
        seq, event_type, category, description, goal_id, period = goal
        if seq != self.seq:
            return ("reject", "seq_mismatch")
        phase = self.phase()
        if phase == INACTIVE:
            return ("reject", "inactive")
        if event_type == 0:
            return ("reject", "uninitialized_event_type")
        if event_type > FINISHED:
            return ("reject", "unknown_event_type")
        if phase == RUNNING and event_type != CANCEL:
            return ("reject", "busy")
        if event_type == NEXT:
            if category not in self.categories:
                return ("reject", "unsupported_category")
            try:
                json.loads(description)
            except ValueError:
                return ("reject", "description_not_json")
            if not math.isfinite(period):
                return ("reject", "non_finite_stubborn_period")
            if self.stale(goal_id):
                return ("reject", "stale_id")
        elif event_type == CANCEL:
            running = self.running
            if running is None:
                return ("reject", "cancel_idle")
            if goal_id != running.child_id:
                return ("reject", "cancel_id_mismatch")
        return ("accept",)

    # ------------------------------------------------------------------ inputs

    def stale(self, goal_id: int) -> bool:
        """A NEXT's id is used up (0 asks for the next one, while one is left)."""
        return self.last_id == _U64 if goal_id == 0 else goal_id <= self.last_id

    def begin(self, event_id: int, description: str, now: int) -> list[tuple[Any, ...]]:
        """A dynamic event begins."""
        if self.phase() != INACTIVE:
            return [("ignored", "begin")]
        self.seq = seq = (self.seq + 1) & _U32
        self.active = True
        self.event_id = self.last_id = event_id
        self.status = "standby"
        self.ev_begin()  # type: ignore[attr-defined]
        return [("begin", seq), ("status", seq, WAITING, "standby", event_id)]

    def request(self, uuid: str, goal: Goal, now: int) -> list[tuple[Any, ...]]:
        """A goal request arrives."""
        running = self.running
        if uuid in self.queued or uuid in self.cancels or (running is not None and running.uuid == uuid):
            return [("ignored", "goal_requested")]
        decision = self.accept(goal)
        if decision[0] == "reject":
            return [("rejected", uuid, decision[1])]
        self.queued[uuid] = goal
        return [("accepted", uuid)]

    def start(self, uuid: str, now: int) -> list[tuple[Any, ...]]:
        """An accepted goal starts."""
        goal = self.queued.pop(uuid, None)
        if goal is None:
            return [("ignored", "goal_started")]
        out: list[tuple[Any, ...]] = [("execute", uuid)]
        seq, event_type, _, _, goal_id, period = goal
        phase = self.phase()
        if (
            seq != self.seq
            or phase == INACTIVE
            or (phase == RUNNING and event_type != CANCEL)
            or (event_type == NEXT and self.stale(goal_id))
        ):
            out.append(("answer", uuid, "aborted", "race condition", "", 0))
            return out
        if event_type == NEXT:
            logs: tuple[int, ...] = ()
            minimum = self.stubborn_minimum
            if 0.0 < period < minimum:
                out.append(("clamped", period, minimum))
                text = (
                    f"stubborn_period {period:g} s is below the minimum of {minimum:g} s; "
                    f"{minimum:g} s will be used"
                )
                out.append(("log", self.log_seq, "warning", text))
                logs = (self.log_seq,)
                self.log_seq = (self.log_seq + 1) & _U32
            child_id = goal_id or (self.last_id + 1) & _U64
            self.last_id = child_id
            if self.stubborn is not None:
                self.stubborn = None
                out.append(("stubborn_end",))
            out.append(("start_child", child_id))
            self.running = Running(uuid, goal, child_id, "underway")
            out.append(("feedback", uuid, "underway", goal_id, logs))
            self.status = "underway"
            self.ev_start()  # type: ignore[attr-defined]
            out.append(("status", seq, RUNNING, "underway", goal_id))
        elif event_type == CANCEL:
            running = self.running
            if running is None:
                out.append(("answer", uuid, "aborted", "an idle dynamic event cannot be cancelled", "", 0))
            elif goal_id != running.child_id:
                out.append(
                    ("answer", uuid, "aborted", "ID for cancel request does not match current event", "", 0)
                )
            else:
                if not running.canceling:
                    running.canceling = True
                    out.append(("cancel_child", running.child_id))
                self.cancels.append(uuid)
        else:  # FINISHED
            if self.stubborn is not None:
                self.stubborn = None
                out.append(("stubborn_end",))
            out.append(("answer", uuid, "succeeded", "", "completed", self.event_id))
            out.append(("finished", "completed"))
            self.active = False
            self.status = "completed"
            self.cancels = []
            self.ev_finish()  # type: ignore[attr-defined]
            out.append(("status", seq, INACTIVE, "uninitialized", 0))
        return out

    def progress(self, status: str, text: str | None, tier: str, now: int) -> list[tuple[Any, ...]]:
        """The running child reports a status, maybe with a log line."""
        running = self.running
        if running is None:
            return [("ignored", "child_progress")]
        out: list[tuple[Any, ...]] = []
        logs: tuple[int, ...] = ()
        if text is not None:
            out.append(("log", self.log_seq, tier, text))
            logs = (self.log_seq,)
            self.log_seq = (self.log_seq + 1) & _U32
        out.append(("feedback", running.uuid, status, running.child_id, logs))
        running.child_status = status
        if status != self.status:
            self.status = status
            out.append(("status", self.seq, RUNNING, status, running.child_id))
        return out

    def finished(self, status: str, now: int) -> list[tuple[Any, ...]]:
        """The running child ended: answer its goal and every waiting CANCEL goal."""
        running = self.running
        if running is None:
            return [("ignored", "child_finished")]
        child_id = running.child_id
        outcome = "aborted" if status in _EARLY_END else "succeeded"
        out: list[tuple[Any, ...]] = [("answer", running.uuid, outcome, "", status, child_id)]
        for uuid in self.cancels:
            out.append(("answer", uuid, "succeeded", "", status, child_id))
        self.running = None
        self.cancels = []
        self.status = "standby"
        self.ev_child_end()  # type: ignore[attr-defined]
        period = running.goal[5]
        if period > 0.0:
            applied = max(period, self.stubborn_minimum)
            self.stubborn = applied
            out.append(("stubborn_begin", applied))
        out.append(("status", self.seq, WAITING, "standby", self.last_id))
        return out

    # ------------------------------------------------------------------ snapshots

    def dump(self) -> dict[str, Any]:
        """The data as plain JSON values."""
        data = {name: getattr(self, name) for name in DATA}
        running = self.running
        if running is not None:
            data["running"] = [
                running.uuid,
                list(running.goal),
                running.child_id,
                running.child_status,
                running.canceling,
            ]
        data["queued"] = {uuid: list(goal) for uuid, goal in self.queued.items()}
        data["cancels"] = list(self.cancels)
        return data

    def load(self, data: dict[str, Any]) -> None:
        """Take the data of :meth:`dump` (the peer's phase is set by the caller)."""
        for name in DATA:
            setattr(self, name, data[name])
        running = data["running"]
        if running is not None:
            uuid, goal, child_id, child_status, canceling = running
            self.running = Running(uuid, tuple(goal), child_id, child_status)  # type: ignore[arg-type]
            self.running.canceling = canceling
        self.queued = {uuid: tuple(goal) for uuid, goal in data["queued"].items()}  # type: ignore[misc]
        self.cancels = list(data["cancels"])

    def dumped_phase(self) -> int:
        """The phase implied by the data (for restoring a peer's machine)."""
        if not self.active:
            return INACTIVE
        return WAITING if self.running is None else RUNNING
