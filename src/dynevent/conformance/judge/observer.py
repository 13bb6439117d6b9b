"""The observer: four rooms, each the only keeper of what it holds (the findings, the records ahead,
the server as the machine has it, the goals seen), and one part per kind of record (requests, runs,
feedback, answers) that judges against them and changes them through their methods alone; composed
by :class:`_Observer`, which :func:`check_records` drives."""

from __future__ import annotations

import collections
from collections.abc import Callable, Container, Iterable, Mapping, Sequence

import attrs

from dynevent.conformance.judge.abduction import (
    Found,
    GoalSeen,
    Owed,
    abduce,
    candidates,
    confirmed,
    failure_of,
    first_line,
    matches_exactly,
    result_rule,
    same_status,
    simulate,
)
from dynevent.conformance.judge.trace import (
    SKIPS_OR_LOST,
    TERMINATED,
    Answer,
    Finding,
    Record,
    Report,
    Shown,
    TraceHeader,
    Unreadable,
)
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
from dynevent.wire._fields import U32_MAX, id_not_after
from dynevent.wire._text import answer_text, goal_text, status_text
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    ENDED_CHILD_STATUSES,
    Compatibility,
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


class _Findings:
    """What the observer found, each on the line of the record being judged: the only list of them."""

    def __init__(self) -> None:
        self._found: list[Finding] = []
        self._line = 0

    def at(self, line: int) -> None:
        """The record of ``line`` is being judged."""
        self._line = line

    def flag(
        self, violation: Violation, message: str, expected: str, *, seen: Shown | None = None,
        owed: Shown | None = None, detail: str = "",
    ) -> None:  # fmt: skip
        """Report ``violation`` on the current line; ``seen``, ``owed`` and ``detail``: the finding's
        values (see :class:`Finding`)."""
        self.differs(violation.rule, violation.code, message, expected, seen=seen, owed=owed, detail=detail)

    def differs(
        self, rule: str, code: str, message: str, expected: str, line: int | None = None, *,
        seen: Shown | None = None, owed: Shown | None = None, detail: str = "",
    ) -> None:  # fmt: skip
        """Report an output that differs from the machine's, under the rule of the machine's output, on
        the current line or ``line``."""
        at = self._line if line is None else line
        self._found.append(
            Finding(
                line=at,
                rule=rule,
                code=code,
                message=message,
                expected=expected,
                seen=seen,
                owed=owed,
                detail=detail,
            )
        )

    def all(self) -> tuple[Finding, ...]:
        return tuple(self._found)


class _Lookahead:
    """The records after the one being judged, which the checker's window holds: the only copy."""

    def __init__(self) -> None:
        self.records: tuple[Record, ...] = ()  # the LOOKAHEAD records after it

    def show(self, records: tuple[Record, ...]) -> None:
        self.records = records

    @property
    def upcoming(self) -> Record | None:
        """The record after the one being judged."""
        return self.records[0] if self.records else None

    def answers(self) -> set[tuple[str, str]]:
        """The goal UUIDs and goal statuses of the answers among the records ahead."""
        return {(record.goal_uuid, record.status) for record in self.records if record.kind == "result"}

    def found_ended(self, uuid: str) -> bool:
        """Whether the next cancel response of this goal among the records ahead refused the cancel as
        of a goal already terminated (:data:`~dynevent.conformance.judge.trace.TERMINATED`)."""
        responses = (record for record in self.records if record.kind == "cancel_response")
        response = next((record for record in responses if record.goal_uuid == uuid), None)
        return response is not None and response.status == TERMINATED

    def of_goal(self, uuid: str) -> Record | None:
        """The next feedback or answer of this goal among the records ahead."""
        for record in self.records:
            if record.goal_uuid == uuid and record.kind in ("feedback", "result"):
                return record
        return None

    def answer_of(self, uuid: str) -> Record | None:
        """The answer of this goal among the records ahead, where its feedback before that reports no
        status that ends a child."""
        for record in self.records:
            if record.goal_uuid != uuid:
                continue
            if record.kind == "result":
                return record
            if record.kind == "feedback" and machine.ends_a_child(record.message.status):
                return None
        return None

    def confirms(self, found: Found) -> bool:
        return confirmed(found, self.upcoming)


class _ServerReplica:
    """The server as the machine has it: its state, its configuration, the outputs it owes, the time,
    and what the trace leaves uncertain about it.  The only writer of all of them: the parts change
    them through its methods, each named for what the trace showed."""

    def __init__(self, header: TraceHeader, findings: _Findings, ahead: _Lookahead, *, apart: bool) -> None:
        self._findings = findings
        self._ahead = ahead
        self.apart = apart  # seen apart from the server: see :func:`abduce`
        self.config_known = header.config is not None
        if header.config is not None:
            self.config = header.config
        elif header.compatibility is Compatibility.RMF_ROS2:  # the categories are learned from the goals
            self.config = ServerConfig.rmf_ros2({})
        else:
            self.config = ServerConfig()
        self.state: State | None = None
        self._owed: list[Owed] = []
        self.now = ins.NOW_RANGE[0]
        self._line = 0
        self.order = 0  # how many records were judged before this one: the order, where lines are bag times
        self.partial = False  # the trace begins mid-way: goals it never showed may be open
        self.event_id_unknown = False  # the run began before the trace: its own id is not known
        self.start_uncertain = False  # a RUNNING "queued" status: a deferred child, or one reporting queued

    # ------------------------------------------------------------------ reading

    @property
    def st(self) -> State:
        assert self.state is not None  # set by the first record
        return self.state

    @property
    def owed(self) -> Sequence[Owed]:
        """What the steps so far owe and the trace has not shown yet, oldest first."""
        return self._owed

    def config_for(self, goal: Goal) -> ServerConfig:
        """The configuration; without a config record, every category a goal names is taken as supported."""
        if self.config_known or goal.event_type != EventType.NEXT or goal.category in self.config.categories:
            return self.config
        categories = {**self.config.categories, goal.category: machine.any_description}
        return attrs.evolve(self.config, categories=categories)

    def status(self) -> DynamicEventStatus:
        """The state's status message now."""
        return machine.status_message(self.st, self.now)

    def simulate(self, events: list[ins.Input]) -> tuple[State, list[Owed]]:
        """The state after ``events`` and the outputs they owe, without committing (see :func:`simulate`)."""
        return simulate(self.st, events, self.config)

    def abduce(self, record: Record) -> Found | None:
        """The candidate that explains ``record`` in the current state (see :func:`abduce`)."""
        return abduce(self.st, self.config, record, self.now, self._ahead.records, apart=self.apart)

    # ------------------------------------------------------------------ the trace's opening and time

    def advance(self, time: int, line: int) -> None:
        """The record of ``line``, stamped ``time``, is being judged (the time never goes back)."""
        self.now = max(self.now, time)
        self._line = line
        self.order += 1

    def open(self, record: Record) -> bool:
        """Set the starting state from the first record; True when the record is used up."""
        base = State.new("fleet", "robot")
        self.partial = record.kind == "status" or (
            record.kind == "begin" and record.message.dynamic_event_seq != 1
        )
        if record.kind == "status":
            message: DynamicEventStatus = record.message
            try:
                self.state = state_from_status(message, child_end=False)  # its answer is still to come
            except ValueError as exc:
                self.state = resync.seq(base, message.dynamic_event_seq)
                self._findings.flag(
                    Violation.STATUS_PHASE, f"status {status_text(message)}: {exc}", "dynamic_state 0, 1 or 2"
                )
                return True
            # a status names the highest id used (R2.2), not the dynamic event's own id
            self.event_id_unknown = message.dynamic_state != DynamicState.INACTIVE
            self.start_uncertain = self.st.running is not None and not self.st.running.started
            return True
        if record.kind == "begin":
            self.state = resync.next_run(base, record.message.dynamic_event_seq)
            return False
        self.state = base  # a trace from the server's start
        return False

    # ------------------------------------------------------------------ steps and resynchronisation

    def learn(self, goal: Goal) -> None:
        """An accepted goal names a category the server supports."""
        self.config = self.config_for(goal)

    def commit(self, state: State, owed: Iterable[Owed]) -> None:
        """The step that gave ``state`` and owes ``owed`` took place, at the current line."""
        self.state = state
        unknown = self.event_id_unknown  # a FINISHED's answer then owes an id not known (R11.1)

        def id_known(item: Owed) -> bool:
            finished = item.rule == machine.FINISHED_RULE and isinstance(item.output, outs.AnswerGoal)
            return not (unknown and finished)

        self._owed.extend(attrs.evolve(item, line=self._line, id_known=id_known(item)) for item in owed)

    def resync(self, state: State) -> None:
        """The server is known to be in ``state``, whatever the steps so far say (see :mod:`resync`)."""
        self.state = state

    def begin(self, state: State, begin: ins.Begin) -> None:
        """A run begins from ``state``: its id and its child's start are known again."""
        self.state = state
        self.commit(*self.simulate([begin]))
        self.event_id_unknown = self.start_uncertain = False

    def learn_event_id(self, event_id: int, *, own: bool) -> None:
        """The WAITING status after a begin names ``event_id``; ``own``: it is the begin's own status,
        and so the run's own id (else the highest used so far, and the run's id is still unknown)."""
        self.state = resync.event_id(self.st, event_id)
        if not own:
            self.event_id_unknown = True
        self._owed = [
            attrs.evolve(item, output=outs.PublishStatus(message=attrs.evolve(output.message, id=event_id)))
            if isinstance(output := item.output, outs.PublishStatus)
            and output.message.dynamic_state == DynamicState.WAITING
            and output.message.id == 0
            else item
            for item in self._owed
        ]

    def event_id_lost(self) -> None:
        """The status that named the run's own id was lost: the run's FINISHED's answer tells it."""
        self.event_id_unknown = True

    def learn_event_id_from_finished(self, event_id: int) -> None:
        """The first FINISHED of a run joined late is answered with the run's own id."""
        self.event_id_unknown = False
        self.state = resync.event_id(self.st, event_id)

    def learn_child_id(self, child_id: int) -> None:
        """The running child has ``child_id``, whatever the rules gave it: its owed statuses say so."""
        if self.st.running is None:
            return
        self.state = resync.child_id(self.st, child_id)
        current = self.status()
        self._owed = [
            attrs.evolve(item, output=outs.PublishStatus(message=current))
            if isinstance(item.output, outs.PublishStatus)
            and item.output.message.dynamic_state == DynamicState.RUNNING
            else item
            for item in self._owed
        ]

    def start_uncertain_for(self, uuid: str) -> bool:
        """Is the running goal ``uuid``, with a start a status left uncertain?"""
        running = self.st.running
        return self.start_uncertain and running is not None and running.goal_uuid == uuid

    def settle_start(self, *, started: bool) -> None:
        """The uncertain start is known: the child ``started``, or its start is still deferred."""
        if started:
            self.state = resync.child_started(self.st)
        self.start_uncertain = False

    def abduce_uncertain(self, record: Record) -> Found | None:
        """:meth:`abduce`, also in the world where a child whose start a status left uncertain has started."""
        found = self.abduce(record)
        running = self.st.running
        if not self.start_uncertain or running is None or running.started:
            return found
        if found is not None and matches_exactly(found[3].output, record) and self._ahead.confirms(found):
            return found
        saved = self.st
        self.state = resync.child_started(saved, resumed=True)
        other = self.abduce(record)
        found_exact = found is not None and matches_exactly(found[3].output, record)
        if (
            other is not None
            and matches_exactly(other[3].output, record)
            and (self._ahead.confirms(other) or not found_exact)
        ):
            self.start_uncertain = False
            return other
        self.state = saved
        return found

    # ------------------------------------------------------------------ what is owed

    def forget_channel(self, channel: str) -> None:
        """Nothing owed on ``channel`` is judged any more."""
        self._owed = [item for item in self._owed if item.channel != channel]

    def take(self, index: int) -> Owed:
        """The owed output at ``index`` was seen."""
        return self._owed.pop(index)

    def settle_status(self, message: DynamicEventStatus) -> bool:
        """Is ``message`` an owed status?  It is then seen, and the owed statuses before it with it: a
        status topic keeps one message, and earlier ones may be overwritten unseen."""
        for index, item in enumerate(self._owed):
            output = item.output
            if isinstance(output, outs.PublishStatus) and same_status(output.message, message):
                self._owed = [
                    other for i, other in enumerate(self._owed) if i > index or other.channel != "status"
                ]
                return True
        return False

    def take_answers(self) -> list[Owed]:
        """The answers still owed, which are owed no more (the trace has ended)."""
        answers = [item for item in self._owed if isinstance(item.output, outs.AnswerGoal)]
        self._owed = [item for item in self._owed if not isinstance(item.output, outs.AnswerGoal)]
        return answers


class _Goals:
    """The goals the trace showed, and which of them are closed: the only book of them."""

    def __init__(self, replica: _ServerReplica) -> None:
        self._replica = replica
        self._seen: dict[str, GoalSeen] = {}
        self._closed: collections.deque[str] = collections.deque()  # answered or refused, oldest first
        self._forgotten = False  # a closed goal was let go
        self._finished_seq: int | None = None  # the run the latest FINISHED answered succeeded ended

    def __len__(self) -> int:
        return len(self._seen)

    def __contains__(self, uuid: object) -> bool:
        return uuid in self._seen

    def get(self, uuid: str) -> GoalSeen | None:
        return self._seen.get(uuid)

    def requested(self, uuid: str, goal: Goal, line: int) -> None:
        """A client requested ``goal`` as ``uuid``, on ``line``, the record judged now."""
        self._seen[uuid] = GoalSeen(goal=goal, line=line, order=self._replica.order)

    def unresponded(self, *, unheard: bool = False) -> list[tuple[str, GoalSeen]]:
        """The goals requested in the trace whose response it never shows, in the order requested;
        ``unheard``: those read as accepted from their start, their response never heard, too."""
        found = [
            (uuid, seen)
            for uuid, seen in self._seen.items()
            if seen.line and (not seen.responded or (unheard and not seen.heard))
        ]
        return sorted(found, key=lambda item: item[1].line)

    def bind_unknown(self, uuid: str, running_goal: bool = True) -> GoalSeen | None:
        """What the trace showed of this goal; a goal it never showed may have begun before it.

        In a trace that begins mid-way, the first unknown goal seen while the
        state's running goal is unknown (known from a RUNNING status) is taken
        to be that goal, unless ``running_goal`` says the observation cannot
        be the running goal's; any other unknown goal is not judged.
        """
        replica = self._replica
        if uuid in self._seen:
            return self._seen[uuid]
        if not replica.partial:
            return None
        running = replica.st.running
        if running is None or running.goal_uuid != UNKNOWN_GOAL or not running_goal:
            seen = GoalSeen(goal=Goal(), line=0, responded=True, accepted=True, owed=True)
            self._seen[uuid] = seen
            return seen
        replica.resync(resync.running_goal(replica.st, uuid))
        seen = GoalSeen(goal=running.goal, line=0, responded=True, accepted=True)
        self._seen[uuid] = seen
        return seen

    def ended_run(self, goal: Goal) -> bool:
        """Whether a FINISHED of ``goal``'s run was answered succeeded before ``goal`` came: that run
        had ended, and its end does not wait on ``goal`` to explain it."""
        return goal.dynamic_event_seq == self._finished_seq

    def displace(self, uuids: Iterable[str]) -> None:
        """The server no longer runs these goals as the state says: their answers are not judged."""
        for uuid in uuids:
            seen = self._seen.get(uuid)
            if seen is not None and seen.answered is None:
                seen.let_go()
            self._replica.forget_channel(f"goal:{uuid}")

    def judged(self, record: Record) -> None:
        """``record`` (an answer or a response) was judged: close its goal when it closed it."""
        seen = self._seen.get(record.goal_uuid)
        if seen is None:
            return
        if seen.answered == record.line:
            if seen.goal.event_type == EventType.FINISHED and record.status == GoalStatus.SUCCEEDED.value:
                self._finished_seq = seen.goal.dynamic_event_seq
            seen.close()
            self._close(record.goal_uuid)
        elif record.kind == "goal_response" and seen.responded and not seen.accepted:
            self._close(record.goal_uuid)

    def _close(self, uuid: str) -> None:
        """Goal ``uuid`` was answered or refused: what is judged after that is a record naming it (a
        second answer, feedback after the answer), which the latest :data:`CLOSED_GOALS` closed goals
        keep; an older one is let go, so that memory stays flat on a trace of any length (a record
        naming it is then one of a goal never requested: R19.1 still)."""
        self._closed.append(uuid)
        while len(self._closed) > CLOSED_GOALS:
            old = self._closed.popleft()
            seen = self._seen.get(old)
            if seen is not None and (seen.answered is not None or (seen.responded and not seen.accepted)):
                del self._seen[old]  # unless its UUID was taken again by a goal still open
                self._forgotten = True

    @property
    def unknown_goal(self) -> str:
        """What a goal the observer does not know is."""
        if self._forgotten:
            return f"never requested in this trace, or closed before the latest {CLOSED_GOALS} closed goals"
        return "never requested in this trace"

    def not_accepted(self, seen: GoalSeen | None) -> str:
        """What a goal that was not seen accepted is: unknown, rejected, or not answered yet."""
        if seen is None:
            return self.unknown_goal
        return "rejected" if seen.responded else "no response to it heard"


@attrs.frozen
class AnswerEvidence:
    """What a reader that may not hold every answer (a bag) knows of them at the end: the goals whose
    answer a client asked for (``asked``: a ``get_result`` request event), so that a recording could
    hold it, and the goals whose goal status showed their end (``settled``: goal UUID to ``succeeded``,
    ``canceled`` or ``aborted``), answered whether or not a client asked.  An owed answer is missing
    only when it was asked for and not settled."""

    asked: Container[str] = ()
    settled: Mapping[str, str] = attrs.field(factory=dict)
    #: an answer owed by a step after this line (the recording's end, less the time an answer may
    #: take to arrive) may have been on its way: not missing
    until: int | None = None


@attrs.frozen
class _ObserverState:
    """What the parts judge against, each kept by its own room: the findings, the records ahead, the
    server as the machine has it, and the goals seen."""

    findings: _Findings
    ahead: _Lookahead
    replica: _ServerReplica
    goals: _Goals


class _Part:
    """One part of the observer: it reads the rooms and changes them through their methods alone."""

    def __init__(self, rooms: _ObserverState) -> None:
        self.findings = rooms.findings
        self.ahead = rooms.ahead
        self.replica = rooms.replica
        self.goals = rooms.goals


class _Requests(_Part):
    """Goal requests, their responses and action-level cancels: the machine's ``accept``, compared."""

    def __init__(self, rooms: _ObserverState, *, apart: bool = False) -> None:
        super().__init__(rooms)
        self.apart = apart  # the records were seen apart from the server (a client, a recorder)
        self.duplicates: set[str] = set()  # goal UUIDs requested again while open
        #: the goals the action's goal statuses showed ended before the record judged (a bag's), the
        #: latest CLOSED_GOALS
        self.ended_shown: collections.OrderedDict[str, None] = collections.OrderedDict()
        #: seen apart: each goal awaiting its response (the latest AWAITING_REFUSALS), with the refusals
        #: the server's states since its request give it; the request reached the server in one of them
        self.refusable: collections.OrderedDict[str, dict[RejectReason, outs.Rejected]] = (
            collections.OrderedDict()
        )
        #: seen apart: the goal whose child ran when each goal awaiting its response was requested
        #: (``""``: none), the latest AWAITING_REFUSALS
        self.running_at_request: collections.OrderedDict[str, str] = collections.OrderedDict()

    def on_goal(self, record: Record) -> None:
        seen = self.goals.get(record.goal_uuid)
        if seen is not None and seen.answered is None and (not seen.responded or seen.accepted):
            self.findings.flag(
                Violation.GOAL_UUID_REUSED,
                f"goal {record.goal_uuid} requested again while it is open (since line {seen.line})",
                "a fresh goal UUID for every goal",
            )
            self.duplicates.add(record.goal_uuid)
            return
        self.goals.requested(record.goal_uuid, record.message, record.line)
        if self.apart:
            self.refusable[record.goal_uuid] = {}
            running = self.replica.st.running
            self.running_at_request[record.goal_uuid] = (
                running.goal_uuid if running and running.started else ""
            )
            for books in (self.refusable, self.running_at_request):
                while len(books) > AWAITING_REFUSALS:
                    books.popitem(last=False)
            self.note_refusals()

    def note_refusals(self) -> None:
        """Seen apart: the server's state now is one a goal awaiting its response may have met."""
        for uuid, refusals in self.refusable.items():
            seen = self.goals.get(uuid)
            if seen is None or seen.responded:
                continue
            decision = machine.accept(self.replica.st, seen.goal, self.replica.config_for(seen.goal))
            if isinstance(decision, outs.Rejected):
                refusals.setdefault(decision.reason, decision)
                seen.refusable_since()

    def refused_earlier(self, uuid: str, record: Record) -> bool:
        """Seen apart: a state the server passed through after the request was sent, before the
        response was heard, refuses the goal as ``record`` says (the request reached the server then,
        and its response came after records of later states)."""
        refusals = self.refusable.get(uuid, {})
        return not record.accepted and any(self.same_reason(refusal, record) for refusal in refusals.values())

    def ended_unseen(self, *, shown: bool = False) -> bool:
        """Whether an accepted goal the machine finds busy found the running child ended: a child
        whose last report was a final status (R20.2), of a goal the trace picked up mid-way (its
        request, so its answer too, may be missing from a trace); or one whose goal the server showed
        ended before (:attr:`ended_shown`: a bag's goal statuses, or the refusal of a cancel of it as
        of a goal terminated, where the answer and the status of the child's end came later or never).
        The child is then taken as ended, as a client takes it, and its answer is not judged.
        ``shown``: only where the server showed it."""
        state = self.replica.st
        running = state.running
        if running is None or not running.started or state.task_signal:
            return False
        bound = self.goals.get(running.goal_uuid)
        if bound is None or bound.answered is not None:
            return False
        mid_way = machine.ends_a_child(running.child_status) and bound.line == 0 and not shown
        if not mid_way and running.goal_uuid not in self.ended_shown:
            return False
        final = running.child_status if machine.ends_a_child(running.child_status) else Status.COMPLETED.value
        ended = ins.ChildFinished(status=final, now=self.replica.now)
        after, _ = self.replica.simulate([ended])
        self.replica.resync(after)
        for uuid in (running.goal_uuid, *state.cancels):  # the CANCELs its end answered, too (R8.3)
            if (waiting := self.goals.get(uuid)) is not None:
                waiting.let_go()
        return True

    def stops_the_child(self, uuid: str) -> bool:
        """Is goal ``uuid`` a CANCEL of the running child, waiting for its end or queued to start?"""
        state = self.replica.st
        running = state.running
        if running is None:
            return False
        if uuid in state.cancels:
            return True
        queued = next((goal for goal in state.queued if goal.goal_uuid == uuid), None)
        return (
            queued is not None
            and queued.goal.event_type == EventType.CANCEL.value
            and queued.goal.id == running.child_id
        )

    def on_goal_response(self, record: Record) -> None:
        if record.goal_uuid in self.duplicates:
            self.duplicates.discard(record.goal_uuid)
            return
        seen = self.goals.get(record.goal_uuid)
        if seen is not None and seen.responded and not seen.heard:
            self.heard_late(seen, record)
            return
        if seen is None or seen.responded:
            raise Unreadable("goal_uuid", "no goal record with this uuid awaits a response")
        seen.respond(record.accepted)
        goal = seen.goal
        refused_earlier = self.refused_earlier(record.goal_uuid, record)
        self.refusable.pop(record.goal_uuid, None)
        sent_before_start = self.sent_before_start(record.goal_uuid)
        self.running_at_request.pop(record.goal_uuid, None)
        decision = machine.accept(self.replica.st, goal, self.replica.config_for(goal))
        busy = isinstance(decision, outs.Rejected) and decision.reason is RejectReason.BUSY
        if busy and record.accepted and self.ended_unseen():
            decision = machine.accept(self.replica.st, goal, self.replica.config_for(goal))
        if not self.agrees(decision, record):
            if refused_earlier:
                return  # a refusal changes nothing: the states since are the server's
            self.explain_response(goal, record, sent_before_start=sent_before_start)
            decision = machine.accept(self.replica.st, goal, self.replica.config_for(goal))
        if record.accepted:
            self.replica.learn(goal)
        if isinstance(decision, outs.Accepted) == record.accepted:
            if isinstance(decision, outs.Rejected) and not self.same_reason(decision, record):
                self.findings.differs(
                    decision.rule,
                    "wrong_reason",
                    f"{goal_text(goal)} rejected as {record.reason}",
                    f"rejected as {decision.reason.value}, the first check that fails: {decision.text}",
                )
            if record.accepted:
                event = ins.GoalRequested(goal_uuid=record.goal_uuid, goal=goal, now=self.replica.now)
                self.replica.commit(*self.replica.simulate([event]))
            return
        if isinstance(decision, outs.Rejected):  # accepted, but the rules refuse it
            ended = decision.reason is RejectReason.INACTIVE and self.goals.ended_run(goal)
            self.findings.differs(
                decision.rule,
                f"accepted_{decision.reason.value}",
                f"{goal_text(goal)} accepted",
                f"rejected: {decision.reason.value} ({decision.text})",
                seen=goal,
                detail="run_ended" if ended else "",
            )
            self.replica.resync(resync.queued(self.replica.st, record.goal_uuid, goal))
            return
        if self.unknowable(goal, record):
            return
        said = f" as {record.reason.value}" if record.reason is not None else ""
        self.findings.flag(
            Violation.REJECTED_ACCEPTABLE,
            f"{goal_text(goal)} rejected{said}",
            "accepted: the goal passes every check of R4",
        )

    def heard_late(self, seen: GoalSeen, record: Record) -> None:
        """Seen apart: the response of a goal read as accepted from its start (its feedback, answer or
        a status), which came after the records looked ahead: a lossy link sent it again late.  A
        refusal contradicts the start the server showed."""
        seen.heard_late()
        if not record.accepted:
            self.findings.flag(
                Violation.RESPONSE_MISMATCH,
                f"goal {record.goal_uuid} rejected",
                "accepted: the server showed its start before",
            )

    def agrees(self, decision: outs.Decision, record: Record) -> bool:
        if isinstance(decision, outs.Accepted) != record.accepted:
            return False
        return not isinstance(decision, outs.Rejected) or self.same_reason(decision, record)

    def same_reason(self, decision: outs.Rejected, record: Record) -> bool:
        reason = record.reason
        return reason is None or machine.could_refuse_first(
            reason, decision, config_known=self.replica.config_known
        )

    def unknowable(self, goal: Goal, record: Record) -> bool:
        """Could an unknown configuration have refused this NEXT?"""
        if self.replica.config_known or goal.event_type != EventType.NEXT:
            return False
        return record.reason is None or record.reason in machine.CONFIGURED_REFUSALS

    def explain_response(self, goal: Goal, record: Record, *, sent_before_start: bool = False) -> None:
        """The response may follow starts of accepted goals whose outputs come later: try them.
        ``sent_before_start``: seen apart, the goal was requested before the running child started."""
        events: list[ins.Input] = []
        for queued in self.replica.st.queued:
            events.append(ins.GoalStarted(goal_uuid=queued.goal_uuid, now=self.replica.now))
            state, owed = self.replica.simulate(events)
            decision = machine.accept(state, goal, self.replica.config_for(goal))
            if self.agrees(decision, record):
                self.replica.commit(state, owed)
                return
        if self.apart and (not record.accepted or sent_before_start):
            # at a client, whose channels lag one another: a request that reached the server after
            # the running child's end, whose answer is heard later and is the next record of that
            # child (no report of it comes first): refused for that end (a CANCEL), or accepted as a
            # fresh goal where it was sent before that child started (a NEXT sent beside another,
            # delivered late, the status of the end lost: found at 30% loss); one sent while the
            # child was seen running is accepted busy (rmf_ros2's D1); the child's reports sent before
            # its end may come between
            for ended in _ended_ahead(self.replica, self.ahead, past_reports=not record.accepted):
                state, owed = self.replica.simulate(ended)
                if self.agrees(machine.accept(state, goal, self.replica.config_for(goal)), record):
                    self.replica.commit(state, owed)
                    return
        if record.reason is RejectReason.SHUTTING_DOWN:
            state, owed = self.replica.simulate([ins.Shutdown(now=self.replica.now)])
            self.replica.commit(state, owed)

    def sent_before_start(self, uuid: str) -> bool:
        """Seen apart: was goal ``uuid`` requested before the running child started?"""
        running = self.replica.st.running
        before = self.running_at_request.get(uuid)
        return running is not None and before is not None and before != running.goal_uuid

    def on_cancel_request(self, record: Record) -> None:
        if self.replica.partial and record.goal_uuid not in self.goals:
            return  # a goal from before the trace, maybe: its response tells (on_cancel_response)
        seen = self.goals.get(record.goal_uuid)
        if seen is not None and seen.owed:
            return  # a goal the state no longer follows: its cancel is not judged either
        running = self.replica.st.running
        ended = record.status == TERMINATED or self.ahead.found_ended(record.goal_uuid)
        if running is not None and ended and self.stops_the_child(record.goal_uuid):
            # a CANCEL of the running child the server had ended: it had started (a client's tap does
            # not see when: the judge may hold it queued), and the child's end answered it (R8.3)
            if record.goal_uuid not in self.replica.st.cancels:
                started = ins.GoalStarted(goal_uuid=record.goal_uuid, now=self.replica.now)
                self.replica.commit(*self.replica.simulate([started]))
            _remember_goal(self.ended_shown, running.goal_uuid)
            self.ended_unseen(shown=True)
        elif running is not None and running.goal_uuid == record.goal_uuid:
            if ended:
                _remember_goal(self.ended_shown, record.goal_uuid)  # its cancel's refusal says so
            self.ended_unseen(shown=True)  # the server showed it ended before the cancel came
        if self.apart and self.ran_unseen(record.goal_uuid):
            started = ins.GoalStarted(goal_uuid=record.goal_uuid, now=self.replica.now)
            self.replica.commit(*self.replica.simulate([started]))
        if self.replica.start_uncertain_for(record.goal_uuid):
            # a deferred child is cancelled at once (R10.4); a started one ends later (R10.3)
            answer = self.ahead.of_goal(record.goal_uuid)  # at once: within the next two records
            deferred = (
                answer is not None
                and answer.kind == "result"
                and answer.status == GoalStatus.CANCELED.value
                and answer.message.status == Status.CANCELED.value
            )
            self.replica.settle_start(started=not deferred)
        self.replica.commit(
            *self.replica.simulate([ins.CancelRequested(goal_uuid=record.goal_uuid, now=self.replica.now)])
        )

    def ran_unseen(self, uuid: str) -> bool:
        """Seen apart: is goal ``uuid`` a NEXT the judge holds queued whose answer, the next of its
        records ahead, shows its child ran (an answer with a child status and no ``cancelled while not
        running``), or, no record of it ahead, the only NEXT queued, whose child's id (the one its
        start would give it, above every id used so far) a status ahead names?  A goal cancelled
        before its start is answered so (R10.1); one that had started when the cancel came was fed
        back and shown running, and a lossy link can lose all of that for good (found at 30% loss:
        the NEXT's start feedback and RUNNING status lost, its answer ``canceled``, ``canceled``, read
        as R10.1's with a wrong id; or that answer late too, and the WAITING status of its child's
        end, naming the child, read as R2.2)."""
        state = self.replica.st
        nexts = [queued.goal_uuid for queued in state.queued if queued.goal.event_type == EventType.NEXT]
        if uuid not in nexts:
            return False
        answer = self.ahead.of_goal(uuid)
        if answer is not None:
            return (
                answer.kind == "result"
                and bool(answer.message.status)
                and first_line(answer.message.execution_failure) != Failure.NOT_RUNNING.value
            )
        running = self.replica.simulate([ins.GoalStarted(goal_uuid=uuid, now=self.replica.now)])[0].running
        if len(nexts) > 1 or running is None or running.goal_uuid != uuid:
            return False  # another NEXT's start could name the same child
        if running.child_id == state.last_id:
            return False
        return any(
            record.kind == "status"
            and (record.message.dynamic_event_seq, record.message.id) == (state.seq, running.child_id)
            for record in self.ahead.records
        )

    def on_cancel_response(self, record: Record) -> None:
        channel = f"cancel:{record.goal_uuid}"
        if not any(item.channel == channel for item in self.replica.owed):
            if self.replica.partial and record.goal_uuid not in self.goals:
                if not record.accepted:
                    return  # a goal unknown to the server as well
                upcoming = self.ahead.upcoming
                queued = (
                    upcoming is not None
                    and upcoming.kind == "result"
                    and upcoming.goal_uuid == record.goal_uuid
                    and first_line(upcoming.message.execution_failure) == Failure.NOT_RUNNING.value
                )
                self.goals.bind_unknown(record.goal_uuid, running_goal=not queued)
                if queued:
                    return  # an accepted goal that had not started (R10.1, R10.2)
            self.on_cancel_request(record)
        index = next((i for i, item in enumerate(self.replica.owed) if item.channel == channel), None)
        if index is None:
            return
        owed = self.replica.take(index)
        assert isinstance(owed.output, outs.CancelResponse)
        seen = self.goals.get(record.goal_uuid)
        answered = seen is not None and seen.answered is not None and not seen.stopped
        if self.apart and owed.output.accepted and answered:
            # at a client: the goal's answer heard before the refusal, and its child not cancelled: the
            # request may have reached the server after that answer (a lost request is sent again,
            # seconds later), where it is rightly refused
            return
        if owed.output.accepted != record.accepted:
            word = {True: "accepted", False: "rejected"}
            self.findings.differs(
                owed.rule,
                "cancel_response",
                f"cancel of goal {record.goal_uuid} {word[record.accepted]}",
                f"{word[owed.output.accepted]} ({owed.rule})",
            )


class _Runs(_Part):
    """Begin and status messages: runs, their seq, the dynamic event's id and the status topic."""

    def __init__(self, rooms: _ObserverState, header: TraceHeader, *, apart: bool = False) -> None:
        super().__init__(rooms)
        self.names = (header.fleet, header.robot) if header.fleet or header.robot else None
        # the records were seen away from the server (a client, a recorder on the network): a step's
        # answers may come after its status, on another channel
        self.apart = apart
        self.client = header.tap == "client"  # a tap at a client, whose channels lag one another
        self.event_id_pending = False
        self.begin_seen = False
        # the trace opened with a begin: a tap at a client may have read it latched, long after it
        # was published, and the status after it is then not the begin's own
        self.opened_by_begin = False
        self.latched_begin: DynamicEventDescription | None = None
        #: the runs read as begun from their first status, their begin not seen: (line, seq)
        self.unbegun: list[tuple[int, int]] = []
        self.begin_awaited: int | None = None  # the latest of those, while its begin may still come

    def sync(self, record: Record) -> bool:
        """Set the starting state from the first record; True when the record is used up."""
        self.opened_by_begin = record.kind == "begin"
        return self.replica.open(record)

    def on_begin(self, record: Record) -> None:
        message: DynamicEventDescription = record.message
        names = (message.fleet, message.robot)
        if self.names is None:
            self.names = names
        elif names != self.names:
            self.findings.flag(
                Violation.BEGIN_NAMES,
                f"begin names {message.fleet}/{message.robot}",
                f"the robot of this trace, {self.names[0]}/{self.names[1]}",
            )
        state = self.replica.st
        if self.late_begin(message) or self.begun_before(message):
            return
        self.begin_seen = True
        if state.shutdown:
            self.findings.flag(
                Violation.BEGIN_AFTER_SHUTDOWN, f"begin of run {message.dynamic_event_seq}", "nothing"
            )
            state = resync.serving(state)
        if state.active and self.apart and state is self.replica.st:
            state = self.finished_unseen(state)
        if state.active:
            self.findings.flag(
                Violation.BEGIN_WHILE_ACTIVE,
                f"begin of run {message.dynamic_event_seq} while run {state.seq} is active",
                "the end of the run first: FINISHED, a task cancel or kill, with an INACTIVE status",
            )
            open_goals = [queued.goal_uuid for queued in state.queued] + list(state.cancels)
            if state.running is not None:
                open_goals.append(state.running.goal_uuid)
            self.goals.displace(open_goals)
            state = resync.run_dropped(state)
        expected = (state.seq + 1) & U32_MAX
        if message.dynamic_event_seq != expected:
            self.findings.flag(
                Violation.BEGIN_SEQ,
                f"begin of run {message.dynamic_event_seq}",
                f"seq {expected}, one above the previous run's {state.seq}",
            )
            state = resync.next_run(state, message.dynamic_event_seq)
        try:
            event = ins.Begin(description=message.description, event_id=0, now=self.replica.now)
        except InvalidMessage as exc:
            self.findings.flag(
                Violation.BEGIN_DESCRIPTION,
                f"begin description: {exc.problem}",
                "a dynamic_event description",
            )
            event = ins.Begin(description="{}", event_id=0, now=self.replica.now)
        self.replica.begin(state, event)
        self.latched_begin = message if self.opened_by_begin else None
        self.opened_by_begin = False
        self.event_id_pending = True

    def late_begin(self, message: DynamicEventDescription) -> bool:
        """The begin of the run a trace started in (from its status), read after that status: a late
        subscriber reads the two latched topics in either order (docs/trace-format.md), whether that
        run is active or has ended (its INACTIVE status, then its latched begin)."""
        state = self.replica.st
        if self.begin_seen or not self.replica.partial:
            return False
        self.begin_seen = True
        return message.dynamic_event_seq == state.seq

    def begun_before(self, message: DynamicEventDescription) -> bool:
        """The begin of the run :meth:`begin_lost` read as begun from its first status, come after
        all: read, nothing left to judge."""
        awaited, self.begin_awaited = self.begin_awaited, None
        return awaited == message.dynamic_event_seq

    def begin_lost(self, record: Record) -> bool:
        """Seen apart from the server, the WAITING status a begin publishes, of the run after the one
        that ended, with no begin of that run before it or just ahead (:func:`_response_ahead` puts one
        that came just after it first): the run began, and its begin was lost on the way on every begin
        topic the tap heard (found at 10% loss across hosts: the copies on the robot's own topic and on
        the fleet's each lost for good).  The run is read as begun here, its description unknown, and
        said (:attr:`unbegun`).  At the server's tap every begin is seen: there it is R2.2."""
        message: DynamicEventStatus = record.message
        state = self.replica.st
        if not self.apart or state.active or state.shutdown or message.dynamic_state != DynamicState.WAITING:
            return False
        if message.dynamic_event_seq != machine.next_seq(state.seq):
            return False
        begin = ins.Begin(description="{}", event_id=message.id, now=self.replica.now)
        after, _ = self.replica.simulate([begin])
        if not same_status(machine.status_message(after, self.replica.now), message):
            return False
        self.replica.begin(state, begin)
        self.replica.settle_status(message)
        self.unbegun.append((record.line, message.dynamic_event_seq))
        self.begin_awaited = message.dynamic_event_seq
        return True

    def adopt_event_id(self, message: DynamicEventStatus) -> None:
        """The begin did not say the dynamic event's id; the WAITING status that follows does.  A
        status of the run that shows a child running came after it: seen apart, where that one was lost
        on the way (a status topic keeps one message), the run's own id is unknown until its FINISHED's
        answer tells it (R11.1)."""
        state = self.replica.st
        if self.apart and self.event_id_pending and message.dynamic_state == DynamicState.RUNNING:
            if state.active and message.dynamic_event_seq == state.seq:
                self.event_id_pending, self.latched_begin = False, None
                self.replica.event_id_lost()
            return
        if not (
            self.event_id_pending
            and message.dynamic_state == DynamicState.WAITING
            and state.active
            and state.running is None
            and message.dynamic_event_seq == state.seq
        ):
            return
        self.event_id_pending = False
        begin, self.latched_begin = self.latched_begin, None
        # a status after a latched begin, with another time, is not the begin's own (a step publishes
        # both with one time): the id it names is the highest used so far, and the run's own id is
        # told by its FINISHED's answer
        self.replica.learn_event_id(message.id, own=begin is None or begin.start_time == message.time)

    def on_status(self, record: Record) -> None:
        message: DynamicEventStatus = record.message
        if message.dynamic_state not in (0, 1, 2):
            self.findings.flag(
                Violation.STATUS_PHASE,
                f"status with dynamic_state {message.dynamic_state}",
                "dynamic_state 0 (INACTIVE), 1 (WAITING) or 2 (RUNNING)",
            )
            return
        self.adopt_event_id(message)
        if self.replica.settle_status(message):
            return
        current = self.replica.status()
        if same_status(current, message):
            return  # a repeat of the state's status (e.g. the latched message, read again)
        if self.begin_lost(record):
            return
        # in the server's order a step's answers and feedback come before its status: prefer a
        # candidate that owes none, then accept one whose other outputs are still to come; a tap at a
        # client may see the status first, so a candidate whose answers the next records show wins
        ahead = self.ahead.answers()
        found: tuple[State, list[Owed]] | None = None
        best = (-1, False, True)
        for events in [*candidates(self.replica.st, record, self.replica.now), *self.ended_child()]:
            state, owed = self.replica.simulate(events)
            published = [item.output for item in owed if isinstance(item.output, outs.PublishStatus)]
            if not published or not same_status(published[-1].message, message):
                continue
            # seen apart, a goal's start beats a task signal whose answers are all that come sooner
            signal = self.apart and any(isinstance(event, _TASK_SIGNALS) for event in events)
            rank = (
                len(_answers(owed) & ahead),
                not signal,
                not any(item.channel.startswith("goal:") for item in owed),
            )
            if rank > best:
                found, best = (state, owed), rank
        if found is None:
            found = self.ended_unanswered(message)
        if found is None and self.client:
            found = self.started_unheard(record)
        if found is not None:
            state, owed = found
            self.replica.forget_channel("status")
            self.replica.commit(state, [item for item in owed if item.channel != "status"])
            return
        self.replica.forget_channel("status")
        self.findings.flag(
            Violation.STATUS_MISMATCH,
            f"status {status_text(message)}",
            f"{status_text(current)}, the state's status",
            seen=message,
            owed=current,
        )

    def started_unheard(self, record: Record) -> tuple[State, list[Owed]] | None:
        """At a client, a status no candidate explains: the start of a goal awaiting its response, none
        ahead, that the machine accepts now, no state since its request refused (its response may be
        that refusal, heard later), and whose start publishes that status; where exactly one goal
        does, it is taken as accepted, its response unheard (a lossy link holds responses back, or
        loses them, while statuses come on their own channel: found at 30% loss, a NEXT's child and a
        FINISHED's end of the run heard, their responses never)."""
        replica = self.replica
        ahead = {item.goal_uuid for item in self.ahead.records if item.kind == "goal_response"}
        found: list[tuple[GoalSeen, tuple[State, list[Owed]]]] = []
        for uuid, seen in self.goals.unresponded():
            config = replica.config_for(seen.goal)
            if uuid in ahead or seen.refusable:
                continue
            if not isinstance(machine.accept(replica.st, seen.goal, config), outs.Accepted):
                continue
            requested = ins.GoalRequested(goal_uuid=uuid, goal=seen.goal, now=replica.now)
            accepted, _ = replica.simulate([requested])
            for events in candidates(accepted, record, replica.now):
                state, owed = replica.simulate([requested, *events])
                published = [item.output for item in owed if isinstance(item.output, outs.PublishStatus)]
                if published and same_status(published[-1].message, record.message):
                    found.append((seen, (state, owed)))
                    break
        if len(found) != 1:
            return None
        seen, explained = found[0]
        seen.respond(True)
        seen.unheard()
        replica.learn(seen.goal)
        return explained

    def finished_unseen(self, state: State) -> State:
        """Seen apart from the server, a new run's begin while a FINISHED of the active run is
        accepted and not yet started: the FINISHED started and ended the run, and the INACTIVE status
        it published was taken over on its way by the next run's (the status topic keeps one
        message).  Its answer stays owed; ``state`` as the run's end left it."""
        for queued in state.queued:
            if queued.goal.event_type != EventType.FINISHED or queued.goal.dynamic_event_seq != state.seq:
                continue
            start = ins.GoalStarted(goal_uuid=queued.goal_uuid, now=self.replica.now)
            ended, owed = self.replica.simulate([start])
            if not ended.active:
                self.replica.commit(ended, [item for item in owed if item.channel != "status"])
                return ended
        return state

    def ended_child(self) -> list[list[ins.Input]]:
        """A child's end whose answer the next records show, after the starts of none, one, ... of the
        queued goals (a CANCEL starts silently and stops the child): a tap at a client sees the status
        topic and the answer on separate channels, so the status may come first.  Seen apart from the
        server, also a queued NEXT's start and its child's end, where its answer is ahead and nothing
        of its start was seen (:func:`_run_ahead`)."""
        ends = _ended_ahead(self.replica, self.ahead)
        return [*ends, *_run_ahead(self.replica, self.ahead)] if self.apart else ends

    def ended_unanswered(self, message: DynamicEventStatus) -> tuple[State, list[Owed]] | None:
        """A status that shows the running child's end (WAITING, or INACTIVE under a task signal),
        whose answer no record ahead shows: the end is read from the status alone, and the answers it
        owes stay owed, their content unknown (the child's final status is not on the wire).  An
        answer that never comes is then missing (R19.1) at this status, not a status that disagrees."""
        running = self.replica.st.running
        if running is None or not running.started or message.dynamic_state == DynamicState.RUNNING:
            return None
        final = (
            running.child_status if running.child_status in ENDED_CHILD_STATUSES else Status.COMPLETED.value
        )
        for events in self.child_ends(ins.ChildFinished(status=final, now=self.replica.now)):
            state, owed = self.replica.simulate(events)
            published = [item.output for item in owed if isinstance(item.output, outs.PublishStatus)]
            if published and same_status(published[-1].message, message):
                return state, [
                    attrs.evolve(item, exact=False) if isinstance(item.output, outs.AnswerGoal) else item
                    for item in owed
                ]
        return None

    def child_ends(self, ended: ins.ChildFinished) -> list[list[ins.Input]]:
        """``ended`` after the starts of all, ..., one, none of the queued goals (a CANCEL starts
        silently and stops the child); most starts first: a binding starts a goal as soon as it
        accepts it."""
        return _child_ends(self.replica, ended)


def _answers(owed: Iterable[Owed]) -> set[tuple[str, str]]:
    return {
        (item.output.goal_uuid, item.output.status.value)
        for item in owed
        if isinstance(item.output, outs.AnswerGoal)
    }


_STATUS_VALUES = frozenset(status.value for status in Status)
#: The inputs from the task, which no client sees: seen apart from the server, a status they and a
#: goal's start both explain is read as the goal's start (a binding starts a goal as soon as it
#: accepts it), though the goal's answer has not come yet (a lossy link delivers it later).
_TASK_SIGNALS = (ins.TaskCancel, ins.TaskKill)


#: The tiers a log entry may have (R7.2, the input's tier).
_TIERS = tuple(tier.value for tier in Tier)


def tier_faults(feedback: Feedback) -> list[tuple[str, str]]:
    """The log entries of ``feedback`` whose tier is none of the four (R7.2): what was seen and what
    was expected, for each."""
    return [
        (f"LogEntry.seq {entry.seq} of tier {entry.tier!r}", f"a tier of {', '.join(_TIERS)} (R7.2)")
        for entry in feedback.logs
        if entry.tier not in _TIERS
    ]


class LogSeqs:
    """The robot's last log entry seen on feedback, and whose it was: what R7.3 judges the next entry
    against (:func:`machine.log_seq_fault`)."""

    def __init__(self) -> None:
        self.seq: int | None = None
        self.child: tuple[str, int] | None = None  # the goal and id of the started child it came with

    def faults(self, goal_uuid: str, feedback: Feedback, *, heard_all: bool) -> list[tuple[str, str, str]]:
        """What is wrong with the log seqs of ``feedback``, to goal ``goal_uuid``: each fault's kind
        (see :func:`machine.log_seq_fault`), what was seen and what was expected.  ``heard_all``: the
        reader hears every feedback the server sends (a tap at the server), so a seq that skips is the
        server's (``"skips"``); seen apart, a feedback lost on the way leaves the same gap
        (:data:`~dynevent.conformance.judge.trace.SKIPS_OR_LOST`, an open item)."""
        child = (goal_uuid, feedback.id) if feedback.status != Status.QUEUED.value else None
        faults = []
        for entry in feedback.logs:
            last = self.seq
            fault = machine.log_seq_fault(
                last, entry.seq, same_child=child is not None and child == self.child
            )
            if fault == "skips":
                faults.append(
                    (
                        fault if heard_all else SKIPS_OR_LOST,
                        f"LogEntry.seq {entry.seq} after {last} in the feedback of child {feedback.id}: "
                        "the log seq skips",
                        f"LogEntry.seq {machine.next_log_seq(last or 0)}: the feedback carries every entry "
                        "made while a child runs, and each takes the robot's next log seq",
                    )
                )
            elif fault:
                how = "repeats" if fault == "repeats" else "goes backwards"
                faults.append(
                    (
                        fault,
                        f"LogEntry.seq {entry.seq} after {last}: the log seq {how}",
                        f"a LogEntry.seq above {last}: every entry takes the robot's next log seq",
                    )
                )
            self.seq, self.child = entry.seq, child
        return faults


class _Feedback(_Part):
    """Feedback: a child's start and progress, abduced, compared, and corrected when it disagrees."""

    def __init__(self, rooms: _ObserverState) -> None:
        super().__init__(rooms)
        self.log_seqs = LogSeqs()

    def on_feedback(self, record: Record) -> None:
        feedback: Feedback = record.message
        heard_all = not self.replica.apart
        for fault, message, expected in self.log_seqs.faults(record.goal_uuid, feedback, heard_all=heard_all):
            self.findings.flag(Violation.LOG_SEQ, message, expected, seen=feedback, detail=fault)
        for message, expected in tier_faults(feedback):
            self.findings.flag(Violation.LOG_TIER, message, expected, seen=feedback)
        uuid = record.goal_uuid
        seen = self.goals.bind_unknown(uuid)
        label = f"feedback {feedback.status} id={feedback.id} for goal {uuid}"
        if seen is None or not seen.accepted:
            what = self.goals.not_accepted(seen)
            self.findings.flag(
                Violation.FEEDBACK_NOT_RUNNING, f"{label}, {what}", "no feedback: no goal of it runs"
            )
            return
        if seen.answered is not None:
            self.findings.flag(
                Violation.AFTER_ANSWER,
                f"{label} after its terminal answer (line {seen.answered})",
                "nothing after a goal's terminal answer",
            )
            return
        state = self.replica.st
        if seen.line == 0 and seen.owed and state.active and state.running is None:
            # a NEXT accepted before the trace began starts now
            seen.take_up()
            goal = Goal(dynamic_event_seq=state.seq, event_type=EventType.NEXT, id=feedback.id)
            self.force_start(uuid, goal, feedback)
            return
        if seen.owed:
            return
        channel = f"goal:{uuid}"
        for index, item in enumerate(self.replica.owed):
            if item.channel != channel:
                continue
            if not isinstance(item.output, outs.PublishFeedback):
                break
            if item.output.feedback.status == feedback.status and item.output.feedback.id == feedback.id:
                self.replica.take(index)
                self.check_clamp(item, feedback)
                return
        found = self.replica.abduce_uncertain(record)
        if found is not None:
            events, state, owed, first = found
            owed.remove(first)
            self.replica.commit(state, owed)
            self.compare_feedback(first, feedback, events)
            return
        self.unexplained_feedback(record, seen)

    def _drawn_unseen(self, event: ins.Input, expected: int, got: int) -> bool:
        """R17.8: under id policy ``adapter`` a child just started (not a deferred one resuming, whose id
        was fixed when it was deferred) with an id above the next one took it after ids the adapter
        drew for work of its own, which no wire shows.  (That id may be the NEXT goal's too: the
        deployed adapter's count met a NEXT's id by chance in the lab's re-measure.)"""
        if self.replica.config.id_policy is not IdPolicy.ADAPTER or not isinstance(event, ins.GoalStarted):
            return False
        return id_not_after(expected, got)

    def compare_feedback(self, owed: Owed, feedback: Feedback, events: list[ins.Input]) -> None:
        assert isinstance(owed.output, outs.PublishFeedback)
        expected = owed.output.feedback
        if expected.id != feedback.id:
            started = isinstance(events[-1], (ins.GoalStarted, ins.Resume))
            if self._drawn_unseen(events[-1], expected.id, feedback.id):
                self.replica.learn_child_id(feedback.id)
            elif started and not self._status_names(expected.id):
                policy = (
                    "the NEXT goal's id" if self.replica.config.id_policy is IdPolicy.GOAL else "the next id"
                )
                self.findings.flag(
                    Violation.CHILD_ID,
                    f"the child started for goal {owed.output.goal_uuid} has id {feedback.id}",
                    f"id {expected.id}, {policy}",
                )
                self.replica.learn_child_id(feedback.id)
            else:
                self.findings.differs(
                    owed.rule,
                    "feedback_id",
                    f"feedback id={feedback.id} for goal {owed.output.goal_uuid}",
                    f"id={expected.id}, the running child's",
                )
        if expected.status != feedback.status:
            self.findings.differs(
                owed.rule,
                "feedback_status",
                f"feedback {feedback.status} for goal {owed.output.goal_uuid}",
                f"feedback {expected.status}",
            )
        self.check_clamp(owed, feedback)

    def _status_names(self, child_id: int) -> bool:
        """Does the first status ahead that shows a child running name ``child_id``?  Then the child
        has the id the rules gave it, and a start feedback naming another is the feedback's fault
        (R8.1), not the child's number (R6.2)."""
        for ahead in self.ahead.records:
            if ahead.kind == "status" and ahead.message.dynamic_state == DynamicState.RUNNING:
                message: DynamicEventStatus = ahead.message
                return message.id == child_id
        return False

    def check_clamp(self, owed: Owed, feedback: Feedback) -> None:
        """A start's feedback carries the warning of a clamped stubborn period (R12.2)."""
        output = owed.output
        if owed.rule not in (machine.START_RULE, machine.DEFERRED_START_RULE) or not isinstance(
            output, outs.PublishFeedback
        ):
            return
        warnings = [entry for entry in output.feedback.logs if entry.tier == Tier.WARNING.value]
        if warnings and not any(entry.tier == Tier.WARNING.value for entry in feedback.logs):
            self.findings.flag(
                Violation.CLAMP_NOT_REPORTED,
                f"the start feedback of goal {output.goal_uuid} carries no warning",
                f"a warning log entry: {warnings[0].text}",
            )

    def unexplained_feedback(self, record: Record, seen: GoalSeen) -> None:
        feedback: Feedback = record.message
        uuid = record.goal_uuid
        label = f"feedback {feedback.status} id={feedback.id} for goal {uuid}"
        state = self.replica.st
        goal = seen.goal
        queued = any(item.goal_uuid == uuid for item in state.queued)
        pending = next(
            (
                item
                for item in self.replica.owed
                if item.channel == f"goal:{uuid}" and isinstance(item.output, outs.AnswerGoal)
            ),
            None,
        )
        if queued and goal.event_type == EventType.NEXT:
            _, owed = self.replica.simulate([ins.GoalStarted(goal_uuid=uuid, now=self.replica.now)])
            answer = next((item for item in owed if isinstance(item.output, outs.AnswerGoal)), None)
            if answer is not None and failure_of(answer.output) is Failure.RACE:
                config = self.replica.config_for(goal)
                loss = machine.race_loss(state, goal, config)
                self.findings.flag(
                    Violation.RACE_NOT_LOST,
                    f"{label}: its NEXT ({goal_text(goal)}) started a child",
                    f"aborted: {Failure.RACE.value!r}, as {machine.race_lost(state, goal, config)}",
                    seen=goal,
                    detail=loss.value if loss is not None else "",
                )
            elif answer is not None and isinstance(answer.output, outs.AnswerGoal):
                expected = answer_text(answer.output.status.value, answer.output.result, first_line=True)
                self.findings.differs(
                    answer.rule, "feedback_not_running", f"{label}: its NEXT started a child", expected
                )
            self.force_start(uuid, goal, feedback)
            return
        if pending is not None:
            assert isinstance(pending.output, outs.AnswerGoal)
            unshown = any(isinstance(item.output, outs.PublishStatus) for item in self.replica.owed)
            if self.replica.apart and unshown and _sent_before(feedback, pending.output):
                return  # a report sent before its child's end, which was read before any status showed it
            self.findings.differs(
                pending.rule,
                "feedback_not_running",
                f"{label}, whose event has ended",
                answer_text(pending.output.status.value, pending.output.result, first_line=True),
                seen=feedback,
                owed=Answer(pending.output.status.value, pending.output.result),
                detail="event_ended",
            )
            return
        kind = EventType(goal.event_type).name if goal.event_type <= 3 else f"event_type {goal.event_type}"
        self.findings.flag(
            Violation.FEEDBACK_NOT_RUNNING, f"{label}, a {kind} goal that runs no child", "no feedback"
        )

    def force_start(self, uuid: str, goal: Goal, feedback: Feedback) -> None:
        """The server runs this NEXT, whatever the rules say: make it the running goal."""
        state = self.replica.st
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
        self.goals.displace(displaced)
        self.replica.resync(resync.running(state, uuid, goal, feedback.id, feedback.status, displaced))
        self.replica.forget_channel("status")


class _Answers(_Part):
    """Terminal answers: the end of a goal, abduced or owed, compared with the machine's, and at the
    trace's end those never seen."""

    def __init__(self, rooms: _ObserverState) -> None:
        super().__init__(rooms)
        self.last_end: tuple[int, Result] | None = None  # the last child end: its order and result

    def on_result(self, record: Record) -> None:
        result: Result = record.message
        uuid = record.goal_uuid
        # the running goal is answered at its child's end, or at shutdown
        failure = first_line(result.execution_failure)
        seen = self.goals.bind_unknown(uuid, failure in ("", Failure.SHUTDOWN.value))
        label = f"answer {answer_text(record.status, result, first_line=True)} for goal {uuid}"
        if seen is None or not seen.accepted:
            what = self.goals.not_accepted(seen)
            self.findings.flag(
                Violation.ANSWER_NOT_ACCEPTED, f"{label}, {what}", "no answer: the goal was never accepted"
            )
            return
        if seen.answered is not None:
            self.findings.flag(
                Violation.SECOND_ANSWER,
                f"{label}: a second terminal answer (the first on line {seen.answered})",
                "exactly one terminal answer per goal",
            )
            return
        seen.answer(record.line, stopped=record.message.status == Status.CANCELED.value)
        if seen.owed:
            return
        channel = f"goal:{uuid}"
        pending = next(
            (
                item
                for item in self.replica.owed
                if item.channel == channel and isinstance(item.output, outs.AnswerGoal)
            ),
            None,
        )
        if pending is not None:
            self.replica.forget_channel(channel)
            self.compare_answer(pending, record)
            return
        if self.started_unseen(record):
            return
        found = self.replica.abduce_uncertain(record)
        if found is not None:
            events, state, owed, first = found
            self.replica.commit(state, [item for item in owed if item.channel != channel])
            self.compare_answer(first, record)
            if isinstance(events[-1], ins.ChildFinished) and isinstance(first.output, outs.AnswerGoal):
                self.last_end = (self.replica.order, first.output.result)
            return
        self.unexplained_answer(record, seen)

    def never_seen(self, evidence: AnswerEvidence | None = None) -> None:
        """At the trace's end: every answer owed by a step the trace showed, never seen, is missing.
        ``evidence`` (a reader that may not hold every answer, a bag) says which answers it could have
        shown, and the goal statuses that showed others (see :class:`AnswerEvidence`)."""
        missing = Violation.ANSWER_MISSING
        for item in self.replica.take_answers():
            assert isinstance(item.output, outs.AnswerGoal)
            uuid = item.output.goal_uuid
            if evidence is not None:
                if uuid in evidence.settled:
                    continue  # answered: its goal status shows it, though the bag lacks the answer
                if uuid not in evidence.asked:
                    continue  # no client asked for it: no recording could hold it
                if evidence.until is not None and item.line > evidence.until:
                    continue  # the recording stopped while it may have been on its way
            seen = self.goals.get(uuid)
            # a client that never heard the goal's response may have lost its answer the same way
            detail = "response_unheard" if seen is not None and not seen.heard else ""
            if item.exact:
                message = f"goal {uuid} never answered (by the end of the trace)"
                expected = f"{answer_text(item.output.status.value, item.output.result)} ({item.rule})"
            else:  # a child's end read from its status alone: how it ended is not on the wire
                message = f"goal {uuid} never answered, though this status shows its child's end"
                expected = f"one terminal answer, with the child's result, before this status ({item.rule})"
            self.findings.differs(
                missing.rule, missing.code, message, expected, line=item.line, detail=detail
            )

    def heard_out(self) -> None:
        """At a trace's ``end`` record, where the tap heard the server out: every goal request the
        trace shows, never responded to (or read as accepted from its start, its response never
        heard), is missing its response, and so is every action-level cancel
        request (a server responds in the step that takes a request, R19.1); and every accepted goal
        the state still holds queued has started (the transport starts a goal it accepted, R5, no
        client's doing), so that an answer its start owes, never seen, is missing too.  Each is
        reported at the request."""
        missing = Violation.RESPONSE_MISSING
        for uuid, seen in self.goals.unresponded(unheard=True):
            self.findings.differs(
                missing.rule, missing.code, f"goal {uuid}'s request never responded to (by the trace's end)",
                f"a response, accepted or rejected ({missing.rule})", line=seen.line,
            )  # fmt: skip
        replica, answer = self.replica, Violation.ANSWER_MISSING
        for item in replica.owed:
            if isinstance(item.output, outs.CancelResponse):
                uuid = item.output.goal_uuid
                self.findings.differs(
                    missing.rule, missing.code,
                    f"the action-level cancel of goal {uuid} never responded to (by the trace's end)",
                    f"a cancel response, accepted or rejected ({missing.rule})", line=item.line,
                )  # fmt: skip
        if replica.state is None:
            return
        state = replica.st
        for queued in state.queued:
            started = ins.GoalStarted(goal_uuid=queued.goal_uuid, now=replica.now)
            transition = machine.step(state, started, replica.config_for(queued.goal))
            state = transition.state
            for output in transition.outputs:
                if not isinstance(output, outs.AnswerGoal):
                    continue
                owing = self.goals.get(output.goal_uuid)
                if owing is None or not owing.accepted or owing.answered is not None or owing.owed:
                    continue
                self.findings.differs(
                    answer.rule, answer.code,
                    f"goal {output.goal_uuid} never answered (by the trace's end, where it had started)",
                    f"one terminal answer ({answer.rule})", line=owing.line,
                )  # fmt: skip

    def started_unseen(self, record: Record) -> bool:
        """A CANCEL's start shows nothing on the wire: its answer may say it waited for the last child."""
        state = self.replica.st
        uuid = record.goal_uuid
        queued = next((item for item in state.queued if item.goal_uuid == uuid), None)
        seen = self.goals.get(uuid)
        if queued is None or queued.goal.event_type != EventType.CANCEL or self.last_end is None:
            return False
        order, result = self.last_end
        if seen is None or seen.order > order or record.status != GoalStatus.SUCCEEDED.value:
            return False
        if record.message != result:
            return False
        self.replica.resync(resync.dropped(state, uuid))
        return True

    def compare_answer(self, owed: Owed, record: Record) -> None:
        output = owed.output
        assert isinstance(output, outs.AnswerGoal)
        result: Result = record.message
        expected, observed = output.result, result
        label = f"goal {record.goal_uuid} answered {answer_text(record.status, result, first_line=True)}"
        want = answer_text(output.status.value, expected, first_line=True)
        seen_answer, owed_answer = Answer(record.status, result), Answer(output.status.value, expected)
        if not owed.exact:
            # an end read from a status alone: the child's final status is not on the wire, so neither is
            # the answer's goal status; what its result must name is (R8.1: the child, an ended status)
            named = (first_line(observed.execution_failure), observed.id)
            if named != (first_line(expected.execution_failure), expected.id) or (
                observed.status not in ENDED_CHILD_STATUSES
            ):
                rule = result_rule(owed.rule)
                failure = first_line(expected.execution_failure) or "no failure"
                want = f"{failure}, an ended status, id={expected.id}"
                self.findings.differs(rule, "result", label, f"{want} ({rule})", seen=seen_answer)
            return
        seen = self.goals.get(record.goal_uuid)
        early = {record.status, output.status.value} == {GoalStatus.ABORTED.value, GoalStatus.CANCELED.value}
        if early and seen is not None and seen.line == 0:
            pass  # a goal from before the trace: whether it was cancelled through the action is not known
        elif record.status != output.status.value:
            self.findings.differs(
                owed.rule, "goal_status", label, f"{want} ({owed.rule})", seen=seen_answer, owed=owed_answer
            )
        elif owed.rule == machine.FINISHED_RULE and self.replica.event_id_unknown:
            self.replica.learn_event_id_from_finished(observed.id)
        elif expected.id != observed.id and owed.id_known:  # (a run's id may become known too late)
            rule = result_rule(owed.rule)
            self.findings.differs(
                rule,
                "result_id",
                f"{label}: the result id does not match",
                f"{want} ({rule})",
                seen=seen_answer,
                owed=owed_answer,
            )
        elif (first_line(expected.execution_failure), expected.status) != (
            first_line(observed.execution_failure),
            observed.status,
        ):
            rule = result_rule(owed.rule)
            self.findings.differs(
                rule, "result", label, f"{want} ({rule})", seen=seen_answer, owed=owed_answer
            )

    def unexplained_answer(self, record: Record, seen: GoalSeen) -> None:
        uuid = record.goal_uuid
        state = self.replica.st
        label = f"goal {uuid} answered {answer_text(record.status, record.message, first_line=True)}"
        running = state.running
        queued = next((item for item in state.queued if item.goal_uuid == uuid), None)
        if uuid in state.cancels or (
            queued is not None and queued.goal.event_type == EventType.CANCEL and running
        ):
            child = running.child_id if running is not None else 0
            self.findings.flag(
                Violation.CANCEL_ANSWERED_EARLY,
                f"{label} while child {child} still runs",
                f"the CANCEL waits for child {child} to end, then is answered with its result (R8.3)",
            )
            self.replica.resync(resync.dropped(state, uuid))
            return
        if queued is not None:
            start = "its child starts" if queued.goal.event_type == EventType.NEXT else "it runs"
            self.findings.flag(Violation.ANSWER_BEFORE_START, label, f"no answer yet: {start}")
            self.replica.resync(resync.dropped(state, uuid))
            return
        if running is not None and running.goal_uuid == uuid:
            self.findings.flag(
                Violation.ANSWER_WHILE_DEFERRED, label, "no answer while the child's start is deferred"
            )
            self.replica.resync(resync.start_dropped(state))
            return
        self.findings.flag(Violation.ANSWER_NOT_OPEN, label, "no answer: the goal is not open")


class _Observer:
    """Observer mode (see the module docs): each record goes to the part that reads its kind.

    The parts judge against the rooms (:class:`_ObserverState`), each the only keeper of what it holds, and
    keep what only they need; none calls another.
    """

    def __init__(self, header: TraceHeader, *, apart: bool = False) -> None:
        findings, ahead = _Findings(), _Lookahead()
        apart = apart or header.tap == "client"
        replica = _ServerReplica(header, findings, ahead, apart=apart)
        self.rooms = _ObserverState(findings=findings, ahead=ahead, replica=replica, goals=_Goals(replica))
        self.requests = _Requests(self.rooms, apart=apart)
        self.runs = _Runs(self.rooms, header, apart=apart)
        self.feedback = _Feedback(self.rooms)
        self.answers = _Answers(self.rooms)
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
        rooms = self.rooms
        rooms.findings.at(record.line)
        rooms.replica.advance(record.time, record.line)
        if rooms.replica.state is None and self.runs.sync(record):
            return
        self._handlers[record.kind](record)
        if record.kind in ("result", "goal_response"):
            rooms.goals.judged(record)
        if self.requests.refusable:
            self.requests.note_refusals()


def _sent_before(feedback: Feedback, answer: outs.AnswerGoal) -> bool:
    """Seen apart, may ``feedback`` be a report the answered goal's child sent before its end (a status
    that does not end it, the child's id), delivered late by a lossy link, where the end was read
    before any status showed it (found at 30% loss: a CANCEL refused as the child ended, its refusal
    heard before six reports of the child and the status of its end)?"""
    return not machine.ends_a_child(feedback.status) and feedback.id == answer.result.id


def _ended_ahead(
    replica: _ServerReplica, ahead: _Lookahead, *, past_reports: bool = False
) -> list[list[ins.Input]]:
    """The running child's end, where its answer is among the records ahead (its status, from
    ``ended_child``'s answer), after the starts of all, ..., none of the queued goals; the answer the
    child's next record, or (``past_reports``) the next after its reports of a status that does not
    end it (feedback sent before the end and delivered late, by a lossy link: found at 30% loss)."""
    running = replica.st.running
    if running is None or not running.started:
        return []
    answer = ahead.answer_of(running.goal_uuid) if past_reports else ahead.of_goal(running.goal_uuid)
    if answer is None or answer.kind != "result" or answer.message.status not in _STATUS_VALUES:
        return []
    return _child_ends(replica, ins.ChildFinished(status=answer.message.status, now=replica.now))


def _run_ahead(replica: _ServerReplica, ahead: _Lookahead) -> list[list[ins.Input]]:
    """With no child running, a queued NEXT whose next record ahead is its answer: its child started
    and ended, after the starts of the goals queued before it, and its start feedback and the status
    that showed it running were lost on the way to a view apart from the server (a lossy link: the
    status topic keeps one message, and the feedback topic its last ten)."""
    if replica.st.running is not None:
        return []
    now = replica.now
    starts: list[ins.Input] = []
    for queued in replica.st.queued:
        starts.append(ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now))
        answer = ahead.of_goal(queued.goal_uuid)
        if queued.goal.event_type != EventType.NEXT or answer is None or answer.kind != "result":
            continue
        if answer.message.status in _STATUS_VALUES:
            return [[*starts, ins.ChildFinished(status=answer.message.status, now=now)]]
    return []


def _child_ends(replica: _ServerReplica, ended: ins.ChildFinished) -> list[list[ins.Input]]:
    """``ended`` after the starts of all, ..., one, none of the queued goals, most starts first."""
    now = replica.now
    starts = [ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now) for queued in replica.st.queued]
    return [[*starts[:count], ended] for count in range(len(starts), -1, -1)]


#: How many closed (answered or refused) goals the observer remembers: a record naming one of the
#: latest is judged against it (a second answer, feedback after the answer).
CLOSED_GOALS = 4096
#: How many goals awaiting their responses a judge seen apart reads each state against (the latest
#: requested): a client has a few goals in flight; more, whose responses never came (a hostile or a
#: lossy trace), are let go, so that each record costs a bounded number of the machine's decisions.
AWAITING_REFUSALS = 32

#: How many records after the one being judged the observer looks at: a trace is checked in one pass
#: with this many records held, whatever its length.
LOOKAHEAD = 2
#: The same for a trace seen at a client (``tap`` ``"client"``): its channels may lag one another by
#: many records (a lossy link sends a lost message again, seconds later), and a goal's response,
#: feedback and answer, or a status, are looked for that far ahead to put them back in the server's
#: order.
CLIENT_LOOKAHEAD = 64


def _response_ahead(rooms: _ObserverState, record: Record, window: Iterable[Record]) -> Record | None:
    """The response, among the records ahead, of the goal whose feedback or answer ``record`` is, when
    the goal awaits it, or of an accepted goal when ``record`` is a status; or the begin of the run
    whose status ``record`` is, when that run has not begun: a tap at a client sees the action's
    channels, the status topic and the begin topic each in order, not one another.  (At the server a goal's
    response follows its request at once, so no record comes between them.)"""

    def awaited(ahead: Record) -> bool:
        seen = rooms.goals.get(ahead.goal_uuid)
        return ahead.kind == "goal_response" and seen is not None and not seen.responded

    def explained(response: Record) -> bool:
        seen = rooms.goals.get(response.goal_uuid)
        if seen is None or rooms.replica.state is None:
            return True
        replica = rooms.replica
        return isinstance(machine.accept(replica.st, seen.goal, replica.config_for(seen.goal)), outs.Accepted)

    def names_another(response: Record, status: DynamicEventStatus) -> bool:
        """The child the status shows running is the one an accepted NEXT queued names (its own id),
        not ``response``'s goal's: not that goal's start (two NEXTs sent at once, the second's
        response heard after the first's child started)."""
        seen = rooms.goals.get(response.goal_uuid)
        if seen is None or rooms.replica.state is None or seen.goal.id == status.id:
            return False
        queued = rooms.replica.st.queued
        return any(item.goal.event_type == EventType.NEXT and item.goal.id == status.id for item in queued)

    if record.kind == "status":
        seq = record.message.dynamic_event_seq
        state = rooms.replica.state
        if state is not None and seq != state.seq and record.message.dynamic_state != DynamicState.INACTIVE:
            # the status of a run whose begin, on the other topic, was read just after it
            begin = next((ahead for ahead in window if ahead.kind == "begin"), None)
            if begin is not None and begin.message.dynamic_event_seq == seq:
                return begin
        late = _late_feedback(rooms.replica.state, record.message, list(window))
        if late is not None:
            return late
        # the status of an accepted goal's start, before its response; where the status shows no child
        # running (a child's end), a response the state before it does not explain stays where it came:
        # its request may have reached the server after that end (a FINISHED sent while a child ran)
        ends = not machine.runs_a_child(record.message)
        if not ends and state is not None and same_status(rooms.replica.status(), record.message):
            return None  # the running child's status, which the state explains: no other goal's start
        return next(
            (
                ahead
                for ahead in window
                if awaited(ahead)
                and ahead.accepted
                and (explained(ahead) or not ends)
                and (ends or not names_another(ahead, record.message))
            ),
            None,
        )
    if record.kind not in ("feedback", "result"):
        return None
    return next((ahead for ahead in window if awaited(ahead) and ahead.goal_uuid == record.goal_uuid), None)


def _late_feedback(state: State | None, status: DynamicEventStatus, ahead: list[Record]) -> Record | None:
    """The running goal's feedback, among the records ahead, received after a status that shows its
    child's end and before the goal's answer: sent before both (the answer goes before the status of
    its step), delivered late (a recorder under load; feedback has no stamp to put it back by)."""
    running = state.running if state is not None else None
    if running is None or not running.started:
        return None
    ended = not machine.runs_a_child(status) or status.id != running.child_id
    uuid = running.goal_uuid
    for index, item in enumerate(ahead if ended else ()):
        answered = any(later.kind == "result" and later.goal_uuid == uuid for later in ahead[index + 1 :])
        if item.kind == "feedback" and item.goal_uuid == uuid and answered:
            return item
    return None


def _started_before_cancel(state: State | None, record: Record, window: Iterable[Record]) -> Record | None:
    """The first record ahead of the goal an action-level cancel ``record`` names, where it is the
    start feedback of an accepted NEXT not yet started (see :func:`_lagged_ahead`)."""
    if record.kind != "cancel_request" or state is None:
        return None
    if not any(
        item.goal_uuid == record.goal_uuid and item.goal.event_type == EventType.NEXT for item in state.queued
    ):
        return None
    ahead = next(
        (
            item
            for item in window
            if item.goal_uuid == record.goal_uuid and item.kind in ("feedback", "result")
        ),
        None,
    )
    return ahead if ahead is not None and ahead.kind == "feedback" else None


def _lagged_ahead(rooms: _ObserverState, record: Record, window: Iterable[Record]) -> Record | None:
    """At a client, whose channels lag one another (a lossy link): the record among those ahead that
    the server sent before ``record``, on another channel.  A goal's feedback before its answer (R19.1:
    nothing follows an answer); the INACTIVE status that ended a run before the next run's begin
    (R3.4: a run begins once the last has ended); with no child running, the start feedback of an
    accepted NEXT's child before a status that names that child (R6.4: its start feeds back first);
    the running child's feedback whose log entries the server made before the status that shows that
    child's end was stamped (the two stamps are the server's clock); the start feedback of an
    accepted NEXT before an action-level cancel of it (a binding that starts a goal with its
    acceptance had started it when the cancel came; one cancelled before its start is never fed
    back, R10.1)."""
    ended = _fed_back_before(rooms.replica.state, record, window)
    if ended is not None:
        return ended
    started = _started_before_cancel(rooms.replica.state, record, window)
    if started is not None:
        return started
    if record.kind == "result":
        uuid = record.goal_uuid
        return next((ahead for ahead in window if ahead.kind == "feedback" and ahead.goal_uuid == uuid), None)
    state = rooms.replica.state
    if record.kind == "status" and state is not None and state.running is None:
        nexts = {queued.goal_uuid for queued in state.queued if queued.goal.event_type == EventType.NEXT}
        return next(
            (
                ahead
                for ahead in window
                if ahead.kind == "feedback"
                and ahead.goal_uuid in nexts
                and ahead.message.id == record.message.id
            ),
            None,
        )
    if (
        record.kind == "begin"
        and state is not None
        and state.active
        and record.message.dynamic_event_seq != state.seq  # the next run's, not the current's read latched
    ):
        return next(
            (
                ahead
                for ahead in window
                if ahead.kind == "status"
                and ahead.message.dynamic_event_seq == state.seq
                and ahead.message.dynamic_state == DynamicState.INACTIVE
            ),
            None,
        )
    return None


def _fed_back_before(state: State | None, record: Record, window: Iterable[Record]) -> Record | None:
    """The running child's first feedback among the records ahead, where one of them (it, or one
    after it: feedback comes in the order sent) has a last log entry made before ``record``, a
    status that shows that child ended, was stamped (see :func:`_lagged_ahead`)."""
    running = state.running if state is not None else None
    if record.kind != "status" or running is None or not running.started:
        return None
    status: DynamicEventStatus = record.message
    if machine.runs_a_child(status) and status.id == running.child_id:
        return None
    stamped = status.time.sec * 1_000_000_000 + status.time.nanosec
    first: Record | None = None  # the child's feedback comes in the order sent: the first ahead goes first
    for ahead in window:
        if ahead.kind != "feedback" or ahead.goal_uuid != running.goal_uuid:
            continue
        first = first or ahead
        if ahead.message.logs and ahead.message.logs[-1].unix_millis_time * 1_000_000 < stamped:
            return first
    return None


class Checker:
    """The observer fed one record at a time (:meth:`push`), for a reader that interleaves the
    records of several robots (a bag); :meth:`finish` gives the report.  It holds
    :data:`LOOKAHEAD` records, whatever the length of what it reads.  ``apart``: the records were
    seen away from the server (a recorder on the network), so a step's answers may come after its
    status, as at a client's tap."""

    def __init__(self, header: TraceHeader, source: str = "<trace>", *, apart: bool = False) -> None:
        self.source = source
        self._observer = _Observer(header, apart=apart)
        self._pushed = 0
        self._shown: collections.deque[tuple[int, str]] = collections.deque()  # (before record, goal)
        self._window: collections.deque[Record] = collections.deque()
        self._count = 0
        self._client = header.tap == "client"
        self._lookahead = CLIENT_LOOKAHEAD if self._client else LOOKAHEAD
        self._end: int | None = None  # the line of the end record: the tap heard the server out

    def push(self, record: Record) -> None:
        """Take the next record; the one :data:`LOOKAHEAD` records before it (:data:`CLIENT_LOOKAHEAD`
        at a client) is judged.  An ``end`` record (the tap heard the server out) is the last."""
        if self._end is not None:
            raise TraceError(
                self.source, record.line, "type", f"a record after the trace's end (line {self._end})"
            )
        if record.kind == "end":
            self._end = record.line
            return
        self._window.append(record)
        self._pushed += 1
        if len(self._window) > self._lookahead:
            self._judge_first()

    @property
    def pending(self) -> tuple[Record, ...]:
        """The records pushed and not judged yet, in order (what :meth:`cut` would hand on)."""
        return tuple(self._window)

    @property
    def unbegun(self) -> tuple[tuple[int, int], ...]:
        """The runs read as begun from their first status, their begin not seen (lost on the way, seen
        apart from the server): (line, seq)."""
        return tuple(self._observer.runs.unbegun)

    def goal_ended(self, uuid: str) -> None:
        """The action's goal statuses (a bag's, between the records pushed so far and the next)
        showed goal ``uuid`` ended: a NEXT accepted after it finds that goal's child ended, where its
        answer and the status of its end were lost on the way (:meth:`_Requests.ended_unseen`)."""
        self._shown.append((self._pushed, uuid))

    def finish(self, evidence: AnswerEvidence | None = None) -> Report:
        """Judge what is held, then what never came (answers owed; ``evidence``: which answers the
        reader could have shown, see :class:`AnswerEvidence`; after an ``end`` record, responses
        too); the report."""
        while self._window:
            self._judge_first()
        self._observer.answers.never_seen(evidence)
        if self._end is not None:
            self._observer.answers.heard_out()
        return Report(source=self.source, records=self._count, findings=self._observer.rooms.findings.all())

    def cut(self) -> tuple[Report, list[Record]]:
        """Stop here, for a reader that goes on with a new observer (a bag that lost a goal's request):
        the report of what was judged, in which no owed answer is missing yet, and the records pushed
        but not judged."""
        pending = list(self._window)
        self._window.clear()
        findings = self._observer.rooms.findings.all()
        return Report(source=self.source, records=self._count, findings=findings), pending

    def _judge_first(self) -> None:
        window, rooms = self._window, self._observer.rooms
        record = window.popleft()
        response = _response_ahead(rooms, record, window) or (
            _lagged_ahead(rooms, record, window) if self._client else None
        )
        if response is not None:  # a tap at a client: the goal's feedback or answer came first
            window.remove(response)
            window.appendleft(record)
            record = response
        elif self._client and _response_lost(rooms, record, window):
            # a server feeds back and answers only a goal it accepted: the response was lost on the way
            window.appendleft(record)
            record = attrs.evolve(record, kind="goal_response", message=None, accepted=True, status="")
            unheard = rooms.goals.get(record.goal_uuid)
            if unheard is not None:
                unheard.unheard()
        rooms.ahead.show(tuple(window))
        ended = self._observer.requests.ended_shown
        while self._shown and self._shown[0][0] <= self._count:  # shown before this record
            _remember_goal(ended, self._shown.popleft()[1])
        try:
            self._observer.feed(record)
        except Unreadable as exc:
            raise TraceError(self.source, record.line, exc.field, exc.problem) from None
        self._count += 1
        if self._client and record.kind == "goal":
            _response_next(rooms, record, window)


def _response_lost(rooms: _ObserverState, record: Record, window: Iterable[Record]) -> bool:
    """Whether ``record`` is the feedback or answer of a goal requested whose response was not heard
    and is not among the records ahead: lost on the way to a client (a lossy link, a service response
    sent while the client's host was cut off)."""
    if record.kind not in ("feedback", "result"):
        return False
    seen = rooms.goals.get(record.goal_uuid)
    if seen is None or seen.responded:
        return False
    return not any(ahead.kind == "goal_response" and ahead.goal_uuid == record.goal_uuid for ahead in window)


def _remember_goal(books: collections.OrderedDict[str, None], uuid: str) -> None:
    """Keep ``uuid`` in ``books``, the latest :data:`CLOSED_GOALS` only."""
    books[uuid] = None
    while len(books) > CLOSED_GOALS:
        books.popitem(last=False)


def _response_next(rooms: _ObserverState, goal: Record, window: collections.deque[Record]) -> None:
    """At a client: the response to ``goal``, among the records ahead, goes next when the machine
    decides as it says in the state the goal's request found.  At the server a response follows its
    request at once; a client hears it late over a lagging link, after statuses the server published
    since (a child's end, a new run's begin), and read there it would look decided on a state the
    server had not reached.  A response the state at its request does not explain stays where it
    came (the request itself may have reached the server late), as does one heard after a status
    that shows the robot waiting, or after another goal's feedback, which came before its goal's
    first feedback: that goal's child started after another's end, so the server took the goal
    after it (a NEXT accepted while a child runs, or beside another NEXT, never starts after that
    child's end)."""
    uuid = goal.goal_uuid
    responses = (ahead for ahead in window if ahead.kind == "goal_response" and ahead.goal_uuid == uuid)
    response = next(responses, None)
    if response is None or response is (window[0] if window else None):
        return
    if _started_after_an_end(uuid, window, response):
        return
    replica = rooms.replica
    decision = machine.accept(replica.st, goal.message, replica.config_for(goal.message))
    if isinstance(decision, outs.Accepted) == bool(response.accepted):
        window.remove(response)
        window.appendleft(response)


def _started_after_an_end(uuid: str, window: Iterable[Record], response: Record) -> bool:
    """Whether, among the records ahead, a status showing the robot waiting, or the feedback of
    another goal's child (which ran first: two NEXTs accepted at once never both run, R5.2), comes
    before both goal ``uuid``'s first feedback and its ``response``."""
    waited = responded = False
    for ahead in window:
        if ahead is response:
            responded = True
        elif (ahead.kind == "status" and machine.robot_waits(ahead.message)) or (
            ahead.kind == "feedback" and ahead.goal_uuid != uuid
        ):
            waited = waited or not responded
        elif ahead.kind == "feedback":
            return waited
    return False


def check_records(header: TraceHeader, records: Iterable[Record], source: str = "<trace>") -> Report:
    """Replay parsed records in observer mode; see :func:`check_trace`."""
    checker = Checker(header, source)
    for record in records:
        checker.push(record)
    return checker.finish()
