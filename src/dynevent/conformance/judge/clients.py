"""Judging the clients of a server: docs/spec.md section 22, what a client must not send.

A :class:`ClientJudge` follows one robot's server from its steps (the
machine's inputs and outputs, :meth:`ClientJudge.step`) and judges each goal
(:meth:`ClientJudge.goal`) against what its client could know when it sent
it: the status messages published at least ``grace`` seconds before the goal
arrived, every status published within the grace period, and the answers
its own earlier goals had received.  The two feeds may come in either order
(a binding learns a goal's client from introspection, after the step that
answered it): everything is judged by its time, not by when it is fed.

The judge keeps a bounded history: the statuses of the last grace period (and
the one before it), the open goals, and the answers of the last minute.  It
is pure: no clock, no I/O; nothing it is fed makes it raise.

>>> from dynevent.conformance.judge.clients import ClientJudge
>>> judge = ClientJudge("tinyRobot", "r1")
"""

from __future__ import annotations

import collections
from collections.abc import Iterable

import attrs

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.wire._fields import SECOND
from dynevent.wire._text import goal_text, status_text
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import (
    ClientViolation,
    Compatibility,
    DynamicState,
    EventType,
    GoalStatus,
)

__all__ = ["NEVER_ACCEPTED", "ONE_CLIENT", "ClientFinding", "ClientJudge"]

#: The client's name when the server cannot tell clients apart (R22.1).
ONE_CLIENT = "a client"

#: The reasons for which no state accepts a goal (R22.7): what the goal itself gets wrong.
NEVER_ACCEPTED = machine.REFUSED_IN_EVERY_STATE


@attrs.frozen
class ClientFinding:
    """One goal (or run) a client got wrong: when (integer nanoseconds), which robot and client, the
    goal's UUID (empty for a run), the :class:`ClientViolation`, what was sent and what the client
    could know."""

    time: int
    robot: str
    client: str
    goal_uuid: str
    violation: ClientViolation
    sent: str
    knew: str

    @property
    def rule(self) -> str:
        return self.violation.rule

    def line(self) -> str:
        """One line: ``client: R22.4 next_while_running: NEXT seq=1 id=4 (...); expected ...``."""
        return (
            f"{self.client}: {self.rule} {self.violation.code}: {self.sent} ({self.knew}); "
            f"expected {self.violation.instead}"
        )


@attrs.frozen
class _Published:
    time: int
    status: DynamicEventStatus


class ClientJudge:
    """Judges the goals of one robot's clients (docs/spec.md section 22).

    ``grace`` is in seconds; ``config`` is the server's (its id policy says
    whether R22.6 applies).
    """

    def __init__(
        self, fleet: str, robot: str, *, grace: float = 0.5, config: ServerConfig | None = None
    ) -> None:
        if isinstance(grace, bool) or not isinstance(grace, (int, float)) or not 0 <= grace <= 3600:
            raise ValueError(f"grace: expected seconds from 0 to 3600, got {grace!r}")
        self.fleet, self.robot = fleet, robot
        self.grace = round(grace * SECOND)
        self.config = config or ServerConfig()
        # a client is judged by the standard's checks (R22), under the server's id policy (R22.6)
        self._judging = attrs.evolve(self.config, compatibility=Compatibility.STANDARD)
        self._statuses: collections.deque[_Published] = collections.deque()
        self._sent: dict[str, tuple[str, Goal, int]] = {}  # goal UUID: client, goal, arrival
        self._accepted: dict[str, int] = {}  # goal UUID: when accepted
        self._ended: dict[str, tuple[int, GoalStatus | None]] = {}  # answered (or refused: None), when
        self._drivers: dict[int, str] = {}  # run seq: the goal UUID of its last accepted NEXT
        self._active_seq: int | None = None
        self._ended_by_task: set[int] = set()
        self.findings: list[ClientFinding] = []

    # ---------------------------------------------------------------- what the server does

    def step(self, event: ins.Input, outputs: Iterable[outs.Output]) -> None:
        """Follow one step of the server (its input and outputs, in order)."""
        now = event.now
        if isinstance(event, (ins.TaskCancel, ins.TaskKill, ins.Restart)) and self._active_seq is not None:
            self._ended_by_task.add(self._active_seq)
        outputs = tuple(outputs)
        if isinstance(event, ins.GoalSubmitted) and not any(
            isinstance(item, outs.Ignored) for item in outputs
        ):
            self._accept(event, now)  # the transport accepted it before the step (R5.3)
        for output in outputs:
            if isinstance(output, outs.PublishStatus):
                self._publish(now, output.message)
            elif isinstance(output, outs.AnswerGoal):
                self._ended[output.goal_uuid] = (now, output.status)
            elif isinstance(output, outs.GoalRejected):
                self._ended[output.goal_uuid] = (now, None)
            elif isinstance(output, outs.GoalAccepted) and isinstance(event, ins.GoalRequested):
                self._accept(event, now)
        self._forget(now)

    def _accept(self, event: ins.GoalRequested | ins.GoalSubmitted, now: int) -> None:
        self._accepted[event.goal_uuid] = now
        seq = event.goal.dynamic_event_seq
        if event.goal.event_type == EventType.NEXT:
            self._drivers[seq] = event.goal_uuid
        elif event.goal.event_type == EventType.FINISHED:
            self._drivers.pop(seq, None)

    def _publish(self, now: int, status: DynamicEventStatus) -> None:
        self._statuses.append(_Published(now, status))
        if status.dynamic_state == DynamicState.INACTIVE:
            if self._active_seq is not None:
                self._drivers.pop(self._active_seq, None)  # the run ended: left open by no one
            self._active_seq = None
        else:
            self._active_seq = status.dynamic_event_seq

    def _forget(self, now: int) -> None:
        """Keep the statuses a goal arriving now could be judged on (the grace period's, the one
        before it, and a second more: a goal's client may be learned a little late), and what is
        known of goals for a minute after they ended."""
        horizon = now - self.grace - SECOND
        while len(self._statuses) > 1 and self._statuses[1].time <= horizon:
            self._statuses.popleft()
        if len(self._ended) > 64:
            old = [uuid for uuid, (time, _) in self._ended.items() if time < now - _MEMORY]
            for uuid in old:
                for books in (self._ended, self._sent, self._accepted):
                    books.pop(uuid, None)

    # ---------------------------------------------------------------- what a client sends

    def goal(self, client: str, goal_uuid: str, goal: Goal, arrived: int) -> list[ClientFinding]:
        """Judge a goal that ``client`` sent, which the server received at ``arrived`` (integer
        nanoseconds, the clock of the steps); the findings, also kept in :attr:`findings`."""
        self._sent[goal_uuid] = (client, goal, arrived)
        found = [
            ClientFinding(arrived, self.robot, client, goal_uuid, violation, goal_text(goal), knew)
            for violation, knew in self._judge(client, goal_uuid, goal, arrived)
        ]
        self.findings.extend(found)
        return found

    def _readable(self, arrived: int) -> list[DynamicEventStatus]:
        """The statuses the client may have read: the last one published at least the grace period
        before ``arrived``, and every one published after it up to ``arrived``."""
        before = [item for item in self._statuses if item.time <= arrived - self.grace]
        within = [item for item in self._statuses if arrived - self.grace < item.time <= arrived]
        return [item.status for item in ([before[-1]] if before else []) + within]

    def _judge(self, client: str, uuid: str, goal: Goal, arrived: int) -> list[tuple[ClientViolation, str]]:
        never = self._never_acceptable(goal)
        if never is not None:
            return [(ClientViolation.NEVER_ACCEPTABLE, never)]
        readable = self._readable(arrived)
        if not readable:
            return []  # nothing published yet: the client could know nothing
        knew = "the status was " + " or ".join(status_text(status) for status in readable[-3:])
        told = self._refused_by_every_status(goal, readable)
        if told in (ClientViolation.STALE_SEQ, ClientViolation.AFTER_FINISHED):
            return [(told, knew)]
        if self._own(client, uuid, goal, arrived, EventType.FINISHED, answered=True):
            return [(ClientViolation.AFTER_FINISHED, "its own FINISHED of this run had succeeded")]
        if told is ClientViolation.NEXT_WHILE_RUNNING:
            return [(told, knew)]
        if goal.event_type in (EventType.NEXT, EventType.FINISHED) and self._own(
            client, uuid, goal, arrived, EventType.NEXT, answered=False
        ):
            return [(ClientViolation.NEXT_WHILE_RUNNING, "its own NEXT of this run was not answered yet")]
        return [] if told is None else [(told, knew)]

    def _refused_by_every_status(
        self, goal: Goal, readable: list[DynamicEventStatus]
    ) -> ClientViolation | None:
        """What the client breaks when the machine, in the state each status it could read implies
        (R20.2 included), refuses the goal for the same reason the client could know (R22.2 to
        R22.6).  What a run holds (a child, its ids) is read from the statuses of the goal's own run
        where the client could read one: a status of another run says nothing of it."""
        config = attrs.evolve(self._judging, categories={goal.category or "-": machine.any_description})
        told: list[tuple[bool, ClientViolation]] = []
        for status in readable:
            decision = machine.accept(machine.state_from_status(status), goal, config)
            violation = (
                ClientViolation.of_refusal(decision.reason) if isinstance(decision, outs.Rejected) else None
            )
            if violation is None:
                return None
            told.append((status.dynamic_event_seq == goal.dynamic_event_seq, violation))
        own_run = {violation for same, violation in told if same}
        if len(own_run) == 1 and own_run <= _OF_THE_RUN:
            return own_run.pop()
        every = {violation for _, violation in told}
        return every.pop() if len(every) == 1 else None

    def _never_acceptable(self, goal: Goal) -> str | None:
        """The machine's own refusal, in a state where only the goal itself can be wrong (R22.7)."""
        config = ServerConfig(categories={goal.category or "-": machine.any_description})
        state = attrs.evolve(_ACTIVE, seq=goal.dynamic_event_seq)
        decision = machine.accept(state, goal, config)
        if isinstance(decision, outs.Rejected) and decision.reason in NEVER_ACCEPTED:
            return f"no server accepts it: {decision.text}"
        return None

    def _own(
        self, client: str, uuid: str, goal: Goal, arrived: int, kind: EventType, *, answered: bool
    ) -> bool:
        """Did ``client`` send, in this run and before, a goal of ``kind`` that the server had answered
        ``succeeded`` (``answered``), or accepted and not yet answered (not ``answered``)?"""
        for other, (owner, sent, time) in self._sent.items():
            if other == uuid or owner != client or sent.event_type != kind or time >= arrived:
                continue
            if sent.dynamic_event_seq != goal.dynamic_event_seq:
                continue
            ended = self._ended.get(other)
            done = ended is not None and ended[0] < arrived
            if answered and done and ended is not None and ended[1] is GoalStatus.SUCCEEDED:
                return True
            accepted = self._accepted.get(other)
            if not answered and not done and accepted is not None and accepted < arrived:
                return True
        return False

    # ---------------------------------------------------------------- the end

    def close(self, now: int) -> list[ClientFinding]:
        """The server stops: a run a client drove and did not end is that client's (R22.8)."""
        seq = self._active_seq
        if seq is None or seq in self._ended_by_task or seq not in self._drivers:
            return []
        uuid = self._drivers[seq]
        client = self._sent[uuid][0] if uuid in self._sent else ONE_CLIENT
        finding = ClientFinding(
            now, self.robot, client, uuid, ClientViolation.RUN_LEFT_OPEN,
            f"run {seq} still active when the server stopped", "a NEXT of its own was accepted in it",
        )  # fmt: skip
        self.findings.append(finding)
        return [finding]


# the violations that concern what a run holds (its child, its ids), not which run it is
_OF_THE_RUN = frozenset(
    {ClientViolation.NEXT_WHILE_RUNNING, ClientViolation.CANCEL_NOT_RUNNING, ClientViolation.STALE_ID}
)

#: How long what is known of a goal is kept after it ended (a client's goals are minutes apart at most).
_MEMORY = 60 * SECOND

_ACTIVE = machine.step(
    State.new("fleet", "robot"), ins.Begin(description="{}", event_id=0, now=0), ServerConfig()
).state
