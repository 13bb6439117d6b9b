"""What a partial view shows: a robot's topics judged without its goals.

A recording without the action's service events (no introspection) holds a
robot's begins, statuses, feedback and the action's goal statuses, but not
the goals, their responses and their answers: the machine cannot be run
(no input is known), so the observer cannot judge it.  :class:`PartialJudge`
judges what those channels show by themselves, each check one that no lost or
unrecorded message can make false:

- a status message that no state describes (R2.2), a run's seq that goes
  backwards or a run that ended shown active again (R19.3), an id below one
  the run showed before (R6.2: ids rise within a run);
- a begin whose seq goes backwards or repeats an ended run (R3.1), or whose
  description is not one (R1.5), or that names another robot (R3.3);
- a goal whose feedback names two children (R7.1), feedback for a goal after
  a later goal's child started (R19.2: two goals hold the running slot; R19.1
  when the goal was answered), feedback after a goal's answer (R19.1), a log
  seq that repeats or goes backwards (R7.3);
- a goal status that changes after it was terminal, or a second, different
  answer where a client's ``get_result`` events were recorded (R19.1);
- a status still RUNNING the child of an answered goal, in that goal's run,
  a while after the answer, while the server goes on publishing (R2.2, R8.4).

A goal that leaves the action's goal status array (its result expired) is
forgotten: its UUID may be used again.

Records come in the server's order (:class:`~dynevent.bags.reader`
orders them); "a while" is :data:`~dynevent.bags.reader.SKEW` of bag
time, the same margin the ordering takes.  Whatever the recording lacks is
not judged: a status or begin lost on the way (a topic keeps one message, so
one may be overwritten before a recorder reads it) never makes a finding.
"""

from __future__ import annotations

import collections

import attrs

from dynevent.conformance.judge.abduction import same_status
from dynevent.conformance.judge.observer import LogSeqs, tier_faults
from dynevent.conformance.judge.trace import Finding, Record, Report, TraceHeader
from dynevent.errors import InvalidMessage
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.wire._fields import U64_MAX, seq_after
from dynevent.wire._text import status_text
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback
from dynevent.wire.vocab import Compatibility, DynamicState, GoalStatus, Violation

__all__ = ["GOAL_STATUSES", "PartialJudge"]

#: The record kind of one goal status array of the action (``action_msgs/GoalStatusArray``): its
#: ``message`` is a tuple of (goal UUID, :class:`GoalStatus`).
GOAL_STATUSES = "goal_statuses"

#: How many goals a judge remembers; older goals are let go (memory stays flat on any bag).
_GOALS = 1024


@attrs.define
class _Goal:
    """What the topics showed of one goal."""

    order: int  # when its first feedback came, among the goals that had feedback (0: none yet)
    child: int | None = None  # the child its feedback named
    seq: int | None = None  # the run of that child: the status's when its first feedback came
    status: GoalStatus | None = None  # its last goal status
    answered: int | None = None  # the bag time its answer (a terminal status, or a result) was seen
    results: int = 0  # the answers the bag holds (get_result introspection), each different
    flagged: bool = False  # a finding was made on its feedback: one is enough


@attrs.define
class _Due:
    """An answered goal whose child the status must have left by ``due``."""

    due: int
    uuid: str
    child: int
    seq: int
    line: int


class PartialJudge:
    """Judges a robot's begins, statuses, feedback and goal statuses (see the module docs), one record
    at a time (:meth:`push`, in the server's order); :meth:`finish` gives the report.  ``margin`` is
    how long (bag time) a message may take to arrive after another published before it."""

    def __init__(self, header: TraceHeader, margin: int, source: str = "<bag>") -> None:
        self.source = source
        self.names = (header.fleet, header.robot)
        self.compatibility = header.compatibility
        self.margin = margin
        self.findings: list[Finding] = []
        self.records = 0
        self.status: DynamicEventStatus | None = None  # the latest status
        self.top_id: int | None = None  # the highest id the statuses of the current run showed
        self.begin: DynamicEventDescription | None = None  # the latest live begin
        self.log_seqs = LogSeqs()  # the robot's last log entry seen
        self.goals: collections.OrderedDict[str, _Goal] = collections.OrderedDict()
        self.latest = 0  # the order of the goal whose feedback came first most lately
        self.due: collections.deque[_Due] = collections.deque()
        self.listed: set[str] = set()  # the goals of the latest goal status array
        #: the runs read as begun from a status (the observer's, :attr:`Checker.unbegun`): a partial
        #: view reads a status of a run not begun as the run's, without a begin, and says nothing
        self.unbegun: tuple[tuple[int, int], ...] = ()

    def push(self, record: Record) -> None:
        """Judge the next record."""
        self.records += 1
        while self.due and self.due[0].due <= record.time:
            self._settle(self.due.popleft())
        handler = {
            "status": self._status,
            "begin": self._begin,
            "feedback": self._feedback,
            GOAL_STATUSES: self._goal_statuses,
            "result": self._result,
        }.get(record.kind)
        if handler is not None:
            handler(record)

    def finish(self) -> Report:
        """The report.  An answered goal whose check is not due yet (the bag ends first) is not judged."""
        return Report(source=self.source, records=self.records, findings=tuple(self.findings))

    def _flag(
        self, line: int, violation: Violation, message: str, expected: str, *,
        seen: DynamicEventStatus | Feedback | None = None, owed: DynamicEventStatus | None = None,
        detail: str = "",
    ) -> None:  # fmt: skip
        rule, code = violation.rule, violation.code
        self.findings.append(
            Finding(
                line=line,
                rule=rule,
                code=code,
                message=message,
                expected=expected,
                seen=seen,
                owed=owed,
                detail=detail,
            )
        )

    # ------------------------------------------------------------------ the status and begin topics

    def _status(self, record: Record) -> None:
        message: DynamicEventStatus = record.message
        try:
            state = machine.state_from_status(message, child_end=False)
        except ValueError as exc:
            self._flag(
                record.line,
                Violation.STATUS_PHASE,
                f"status {status_text(message)}: {exc}",
                "dynamic_state 0 (INACTIVE), 1 (WAITING) or 2 (RUNNING)",
            )
            return
        if not state.active:
            described = machine.status_message(state, record.time)
            if not same_status(described, message):
                self._flag(
                    record.line,
                    Violation.STATUS_MISMATCH,
                    f"status {status_text(message)}",
                    f"{status_text(described)}: no dynamic event is active",
                    seen=message,
                    owed=described,
                )
        previous, active = self.status, message.dynamic_state != DynamicState.INACTIVE
        if previous is not None:
            seq, before = message.dynamic_event_seq, previous.dynamic_event_seq
            if seq != before and not seq_after(seq, before):
                self._flag(
                    record.line,
                    Violation.STATUS_SEQ,
                    f"status {status_text(message)} after run {before}",
                    f"a seq after {before}: the seq changes only at a begin, one up (R3.1)",
                )
            elif seq == before and active and previous.dynamic_state == DynamicState.INACTIVE:
                self._flag(
                    record.line,
                    Violation.STATUS_SEQ,
                    f"status {status_text(message)} after run {seq} ended",
                    f"a new run, seq {seq} + 1 from its begin (R3.1): a run that ended stays ended",
                )
            elif seq == before and active and self.top_id is not None and message.id < self.top_id < U64_MAX:
                self._flag(
                    record.line,
                    Violation.STATUS_ID,
                    f"status {status_text(message)}",
                    f"an id of at least {self.top_id}, which the run showed before: ids rise in a run "
                    "(R6.2), and WAITING names the highest used (R2.2)",
                )
        if previous is None or previous.dynamic_event_seq != message.dynamic_event_seq or not active:
            self.top_id = None
        if active and (self.top_id is None or message.id >= self.top_id or self.top_id == U64_MAX):
            self.top_id = message.id  # (after the highest id, an adapter's next is 0: ids wrap, R6.2)
        self.status = message

    def _begin(self, record: Record) -> None:
        message: DynamicEventDescription = record.message
        if self.names != (message.fleet, message.robot):
            self._flag(
                record.line,
                Violation.BEGIN_NAMES,
                f"begin names {message.fleet}/{message.robot}",
                f"the robot of its topic, {self.names[0]}/{self.names[1]}",
            )
        try:
            ins.Begin(description=message.description, event_id=0, now=ins.NOW_RANGE[0])
        except InvalidMessage as exc:
            self._flag(
                record.line,
                Violation.BEGIN_DESCRIPTION,
                f"begin description: {exc.problem}",
                "a dynamic_event description",
            )
        stamp = message.start_time.sec * 1_000_000_000 + message.start_time.nanosec
        if abs(record.time - stamp) > self.margin:
            return  # published long before it was recorded (a latched begin) or by another clock: history
        seq, status, begin = message.dynamic_event_seq, self.status, self.begin
        if begin is not None and begin.start_time == message.start_time and begin.dynamic_event_seq == seq:
            return  # the same begin, recorded twice
        if begin is not None and not seq_after(seq, begin.dynamic_event_seq):
            self._flag(
                record.line,
                Violation.BEGIN_SEQ,
                f"begin of run {seq} after the begin of run {begin.dynamic_event_seq}",
                "a seq after the previous begin's: each begin takes the seq one up",
            )
        elif status is not None and not seq_after(seq, status.dynamic_event_seq):
            # the begin's own WAITING status, published with it, may have been read first
            own = seq == status.dynamic_event_seq and status.dynamic_state != DynamicState.INACTIVE
            if not own:
                self._flag(
                    record.line,
                    Violation.BEGIN_SEQ,
                    f"begin of run {seq} after the status {status_text(status)}",
                    f"a seq after {status.dynamic_event_seq}: each begin takes the seq one up",
                )
        self.begin = message

    # ------------------------------------------------------------------ the action's topics

    def _goal(self, uuid: str) -> _Goal:
        goal = self.goals.get(uuid)
        if goal is None:
            goal = self.goals[uuid] = _Goal(order=0)
            while len(self.goals) > _GOALS:
                self.goals.popitem(last=False)
        return goal

    def _feedback(self, record: Record) -> None:
        feedback: Feedback = record.message
        # a recording: feedback lost on the way leaves a gap like a server's skip
        for fault, message, expected in self.log_seqs.faults(record.goal_uuid, feedback, heard_all=False):
            self._flag(record.line, Violation.LOG_SEQ, message, expected, seen=feedback, detail=fault)
        for message, expected in tier_faults(feedback):
            self._flag(record.line, Violation.LOG_TIER, message, expected, seen=feedback)
        uuid, goal = record.goal_uuid, self._goal(record.goal_uuid)
        label = f"feedback {feedback.status} id={feedback.id} for goal {uuid}"
        if goal.order == 0:
            self.latest += 1
            goal.order = self.latest
        if goal.child is None:
            goal.child = feedback.id
            goal.seq = None if self.status is None else self.status.dynamic_event_seq
        elif feedback.id != goal.child:
            self._flag(
                record.line,
                Violation.FEEDBACK_ID,
                label,
                f"id={goal.child}: a goal runs one child, whose id its feedback names",
            )
        if goal.flagged:
            return
        if goal.answered is not None and record.time - goal.answered > self.margin:
            goal.flagged = True
            self._flag(
                record.line,
                Violation.AFTER_ANSWER,
                f"{label}, after its answer",
                "nothing names a goal after its answer",
            )
        elif goal.order < self.latest:
            goal.flagged = True
            violation = Violation.AFTER_ANSWER if goal.answered is not None else Violation.ONE_CHILD
            self._flag(
                record.line,
                violation,
                f"{label}, after a later goal's child started",
                "feedback for the goal holding the running slot alone: a goal's child ends, and "
                "its goal is answered, before the next child starts",
            )

    def _goal_statuses(self, record: Record) -> None:
        listed = {uuid for uuid, _ in record.message}
        for uuid in (
            self.listed - listed
        ):  # its result expired (rclpy: 15 minutes): its UUID may be used again
            self.goals.pop(uuid, None)
        self.listed = listed
        for uuid, status in record.message:
            goal = self._goal(uuid)
            if goal.status is not None and goal.status.is_terminal and status is not goal.status:
                self._flag(
                    record.line,
                    Violation.GOAL_TRANSITION,
                    f"goal {uuid} {status.value} after {goal.status.value}",
                    "a terminal goal status stays: one terminal answer per goal",
                )
            goal.status = status
            if status.is_terminal:
                self._answered(goal, uuid, record.time)

    def _result(self, record: Record) -> None:
        goal = self._goal(record.goal_uuid)
        goal.results += 1
        if goal.results == 2:  # the same answer twice is taken once (bags.py): this one differs
            self._flag(
                record.line,
                Violation.SECOND_ANSWER,
                f"goal {record.goal_uuid} answered {record.status} again",
                "exactly one terminal answer per goal",
            )
        self._answered(goal, record.goal_uuid, record.time)

    def _answered(self, goal: _Goal, uuid: str, time: int) -> None:
        if goal.answered is not None:
            return
        goal.answered = time
        if goal.child is not None and goal.seq is not None:
            self.due.append(_Due(time + self.margin, uuid, goal.child, goal.seq, line=time))

    def _settle(self, due: _Due) -> None:
        """The server has published since a goal's answer: the status must have left its child."""
        status = self.status
        if (
            status is None
            or status.dynamic_state != DynamicState.RUNNING
            or (status.dynamic_event_seq, status.id) != (due.seq, due.child)
        ):
            return
        if self.compatibility is Compatibility.RMF_ROS2 and machine.child_ended(status):
            return  # rmf_ros2 keeps publishing the child's end while the robot waits (R17.4)
        self._flag(
            due.line,
            Violation.STATUS_MISMATCH,
            f"status {status_text(status)} still, after goal {due.uuid}, which ran child {due.child}, "
            "was answered",
            "the status of the child's end: WAITING (R8.4), or INACTIVE when the "
            "task was cancelled or killed (R13.4)",
            seen=status,
            detail="answered",
        )
