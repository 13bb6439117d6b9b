"""The kit's reference model (:class:`Observer`): the protocol state derived only from the inputs sent
and the outputs received, raising :class:`ProtocolViolation` at the first output docs/spec.md §19
forbids.
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig
from dynevent.testing.servers import ServerView
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import (
    Compatibility,
    DynamicState,
    EventType,
    GoalStatus,
    IdPolicy,
    Status,
    Violation,
)

__all__ = ["Observer", "ProtocolViolation"]


_OUTPUT_CLASSES = tuple(outs.OUTPUT_TYPES.values())


class ProtocolViolation(AssertionError):
    """An output (or its absence) that docs/spec.md forbids: ``violation`` says which, ``rule`` its rule."""

    def __init__(self, violation: Violation, problem: str, event: ins.Input | None = None) -> None:
        self.violation = violation
        self.rule = violation.rule
        self.problem = problem
        self.event = event
        where = "" if event is None else f" (after input {event!r})"
        super().__init__(f"{violation.rule} {violation.code}: {problem}{where}")


@attrs.define
class _GoalRecord:
    goal: Goal
    life: GoalStatus  # ACCEPTED, EXECUTING, CANCELING, or the terminal status once answered


@attrs.define
class _Running:
    goal_uuid: str
    child_id: int
    started: bool


#: The outputs about goals on the action, which :meth:`_Goals._goal_effect` checks.
_GOAL_OUTPUTS = (
    outs.GoalAccepted,
    outs.GoalRejected,
    outs.ExecuteGoal,
    outs.CancelResponse,
    outs.PublishFeedback,
)


class _Model:
    """What the observer's parts share: the modelled state of the robot's server, and how to fail."""

    def __init__(self, fleet: str, robot: str, config: ServerConfig) -> None:
        self.fleet = fleet
        self.robot = robot
        self.config = config
        self.seq = 0
        self.active = False
        self.shut_down = False
        self.event_id = 0
        self.description = ""
        self.status = Status.UNINITIALIZED.value
        self.last_id = 0
        self.task_signal = ""
        self.interrupted = False
        self.stubborn = False
        self.log_seq = 0
        self.running: _Running | None = None
        self.goals: dict[str, _GoalRecord] = {}
        self.rejected: set[str] = set()
        self.queued: list[str] = []
        self.cancels: list[str] = []
        self._event: ins.Input | None = None

    @property
    def _child_id(self) -> int | None:
        return None if self.running is None else self.running.child_id

    def expected_status(self, now: int) -> DynamicEventStatus:
        """The status message R2.2 gives for the modelled state, with ``time`` = ``now``."""
        return machine.status_of(self.seq, self.active, self.status, self.last_id, self._child_id, now)

    def _key(self) -> tuple[int, int, str, int]:
        message = self.expected_status(0)
        return (message.dynamic_event_seq, message.dynamic_state, message.status, message.id)

    @property
    def current_id(self) -> int:
        """The id the status topic must report (R2.2): the running child's, else the highest used."""
        return machine.reported_id(self.active, self.last_id, self._child_id)

    @property
    def child_started(self) -> bool:
        """A started child runs."""
        return self.running is not None and self.running.started

    def check_all_answered(self) -> None:
        """R19.1 at the end of a run: every accepted goal has its terminal answer."""
        unanswered = self.open_goals
        if unanswered:
            raise self._fail(
                Violation.NEVER_ANSWERED, f"accepted goals never answered (even after shutdown): {unanswered}"
            )

    def _require_open(self, uuid: str, what: str) -> _GoalRecord:
        record = self.goals.get(uuid)
        if record is None:
            raise self._fail(
                Violation.ANSWER_NOT_ACCEPTED, f"{what} names goal {uuid}, which was never accepted"
            )
        if record.life.is_terminal:
            raise self._fail(
                Violation.AFTER_ANSWER, f"{what} names goal {uuid} after its terminal answer ({record.life})"
            )
        return record

    @property
    def open_goals(self) -> list[str]:
        """Accepted goals not yet answered, in acceptance order."""
        return [uuid for uuid, record in self.goals.items() if not record.life.is_terminal]

    def _fail(self, violation: Violation, problem: str) -> ProtocolViolation:
        return ProtocolViolation(violation, problem, self._event)


class _Goals(_Model):
    """The life of each goal on the action, as ROS 2 and the rules allow it (R19.1, R5.2)."""

    def _check_race(self, record: _GoalRecord, seq: int, active: bool) -> None:
        """R5.2: a goal that starts in another run, or with no run active, loses the race."""
        if record.life is GoalStatus.ABORTED:
            return
        if not active or record.goal.dynamic_event_seq != seq:
            where = f"run {seq}" if active else "no active run"
            raise self._fail(
                Violation.RACE_NOT_LOST,
                f"a goal accepted for run {record.goal.dynamic_event_seq} started in {where} "
                f"and was not aborted (it is {record.life})",
            )

    def _answer(self, output: outs.AnswerGoal) -> None:
        uuid = output.goal_uuid
        if uuid in self.rejected and uuid not in self.goals:
            raise self._fail(
                Violation.ANSWER_NOT_ACCEPTED, f"rejected goal {uuid} received an answer ({output.status})"
            )
        record = self._require_open(uuid, f"AnswerGoal({output.status})")
        status = GoalStatus(output.status)
        if not status.is_terminal:
            raise self._fail(Violation.GOAL_TRANSITION, f"AnswerGoal with the non-terminal status {status}")
        allowed = (
            {GoalStatus.CANCELING}
            if status is GoalStatus.CANCELED
            else {GoalStatus.EXECUTING, GoalStatus.CANCELING}
        )
        if record.life not in allowed:
            raise self._fail(
                Violation.GOAL_TRANSITION,
                f"goal {uuid} answered {status} from {record.life}: ROS 2 allows it only from "
                + " or ".join(sorted(str(life) for life in allowed)),
            )
        record.life = status
        if uuid in self.queued:
            self.queued.remove(uuid)
        if uuid in self.cancels:
            self.cancels.remove(uuid)
        if self.running is not None and self.running.goal_uuid == uuid:
            self.running = None

    def _goal_effect(self, output: outs.Output, event: ins.Input) -> None:
        """The goal outputs: a response to a request, a goal's execution, a cancel response, feedback."""
        if isinstance(output, outs.GoalAccepted):
            if not isinstance(event, ins.GoalRequested) or output.goal_uuid != event.goal_uuid:
                raise self._fail(
                    Violation.RESPONSE_MISMATCH, f"{output} does not answer the input's goal request"
                )
            record = self.goals.get(output.goal_uuid)
            if record is not None:
                raise self._fail(Violation.GOAL_TRANSITION, f"goal {output.goal_uuid} accepted a second time")
            if event.goal.event_type == EventType.NEXT and self.running is not None:
                raise self._fail(
                    Violation.ONE_CHILD,
                    f"NEXT goal {output.goal_uuid} accepted while goal {self.running.goal_uuid} "
                    f"holds the running slot (child {self.running.child_id})",
                )
            self.goals[output.goal_uuid] = _GoalRecord(event.goal, GoalStatus.ACCEPTED)
            self.queued.append(output.goal_uuid)
        elif isinstance(output, outs.GoalRejected):
            if not isinstance(event, ins.GoalRequested) or output.goal_uuid != event.goal_uuid:
                raise self._fail(
                    Violation.RESPONSE_MISMATCH, f"{output} does not answer the input's goal request"
                )
            if output.goal_uuid not in self.goals:
                self.rejected.add(output.goal_uuid)
        elif isinstance(output, outs.ExecuteGoal):
            record = self._require_open(output.goal_uuid, "ExecuteGoal")
            started = isinstance(event, ins.GoalStarted) and event.goal_uuid == output.goal_uuid
            if not (started or isinstance(event, ins.Shutdown)) or record.life is not GoalStatus.ACCEPTED:
                raise self._fail(
                    Violation.GOAL_TRANSITION,
                    f"ExecuteGoal for goal {output.goal_uuid} in state {record.life}",
                )
            record.life = GoalStatus.EXECUTING
            self.queued.remove(output.goal_uuid)
            if started and record.goal.event_type == EventType.CANCEL:
                self.cancels.append(output.goal_uuid)
        elif isinstance(output, outs.CancelResponse):
            if not isinstance(event, ins.CancelRequested) or output.goal_uuid != event.goal_uuid:
                raise self._fail(
                    Violation.RESPONSE_MISMATCH, f"{output} does not answer the input's cancel request"
                )
            if output.accepted:
                record = self._require_open(output.goal_uuid, "an accepted CancelResponse")
                record.life = GoalStatus.CANCELING
        elif isinstance(output, outs.PublishFeedback):
            record = self._require_open(output.goal_uuid, "PublishFeedback")
            if record.life is GoalStatus.ACCEPTED:
                raise self._fail(
                    Violation.GOAL_TRANSITION, f"feedback to goal {output.goal_uuid}, which is not executing"
                )
            deferred_start = (
                isinstance(event, ins.GoalStarted)
                and event.goal_uuid == output.goal_uuid
                and record.goal.event_type == EventType.NEXT
                and self.running is None
            )
            if deferred_start:  # R6.3: the goal holds the slot, its child not started
                self.running = _Running(output.goal_uuid, output.feedback.id, started=False)
                self.last_id = output.feedback.id
                self.status = Status.QUEUED.value


class _Children(_Model):
    """Children, stubbornness, a run's begin and end, the robot's log and the description answer."""

    def _child_effect(self, output: outs.Output, event: ins.Input, ended: Goal | None) -> None:
        """The outputs about children, stubbornness, the run, the robot's log and the description."""
        minimum = self.config.stubborn_minimum
        if isinstance(output, outs.StartChild):
            self._start_child(output, event)
        elif isinstance(output, (outs.CancelChild, outs.KillChild, outs.InterruptChild, outs.ResumeChild)):
            if not self.child_started or self.running is None or self.running.child_id != output.id:
                raise self._fail(Violation.ONE_CHILD, f"{output} while the running child is {self.running}")
        elif isinstance(output, outs.StubbornBegin):
            if ended is None or not ended.stubborn_period > 0:
                raise self._fail(
                    Violation.STUBBORN_UNASKED, f"{output} without a child that asked for stubbornness"
                )
            applied = max(ended.stubborn_period, minimum)
            if not output.period >= minimum or output.period != applied:
                raise self._fail(
                    Violation.STUBBORN_MINIMUM,
                    f"stubborn period {output.period} applied; expected {applied} (minimum {minimum})",
                )
            self.stubborn = True
        elif isinstance(output, outs.StubbornHold):
            if not output.period >= minimum or not self.stubborn:
                raise self._fail(
                    Violation.STUBBORN_MINIMUM, f"{output} (minimum {minimum}, stubborn: {self.stubborn})"
                )
        elif isinstance(output, outs.StubbornClamped):
            if not output.applied >= minimum:
                raise self._fail(
                    Violation.STUBBORN_MINIMUM, f"{output} applies less than the minimum {minimum}"
                )
        elif isinstance(output, outs.StubbornDelay):
            if not self.stubborn:
                raise self._fail(Violation.DELAY_NOT_STUBBORN, f"{output} while not stubborn")
        elif isinstance(output, outs.StubbornEnd):
            self.stubborn = False
        elif isinstance(output, outs.DynamicEventFinished):
            if not self.active:
                raise self._fail(Violation.FINISHED_INACTIVE, f"{output} while no dynamic event is active")
            self.active = False
            self.status = output.status
            self.running = None
        elif isinstance(output, outs.PublishBegin):
            self._begin(output, event)
        elif isinstance(output, outs.Log):
            # the model sees every entry made (R7.3): each takes the log seq, which goes one up
            if output.entry.seq != self.log_seq:
                raise self._fail(
                    Violation.LOG_SEQ, f"LogEntry.seq {output.entry.seq}, expected {self.log_seq}"
                )
            self.log_seq = machine.next_log_seq(self.log_seq)
        elif isinstance(output, outs.DescriptionAnswer):
            response = output.response
            expected = (self.active, self.status, self.description, self.current_id)
            if not self.active:
                expected = (False, "", "", 0)
            got = (response.running, response.status, response.description, response.id)
            if got != expected:
                raise self._fail(
                    Violation.DESCRIPTION_ANSWER, f"description answer {got}, expected {expected}"
                )

    def _start_child(self, output: outs.StartChild, event: ins.Input) -> None:
        running = self.running
        if running is not None and running.started:
            raise self._fail(
                Violation.ONE_CHILD,
                f"StartChild({output.id}) while child {running.child_id} still runs (no end between)",
            )
        if running is not None:  # R14.5: the deferred child starts
            if running.child_id != output.id:
                raise self._fail(
                    Violation.ONE_CHILD, f"StartChild({output.id}) for deferred child {running.child_id}"
                )
            running.started = True
        else:
            if not isinstance(event, ins.GoalStarted):
                raise self._fail(Violation.ONE_CHILD, f"StartChild({output.id}) without a NEXT goal starting")
            record = self._require_open(event.goal_uuid, "StartChild")
            if record.goal.event_type != EventType.NEXT:
                raise self._fail(
                    Violation.ONE_CHILD, f"StartChild for a goal of event type {record.goal.event_type}"
                )
            expected = machine.next_child_id(record.goal, self.last_id, self.config)  # R6.2
            if output.id != expected:
                raise self._fail(
                    Violation.CHILD_ID,
                    f"StartChild({output.id}) for goal id {record.goal.id}, expected {expected}",
                )
            self.running = _Running(event.goal_uuid, output.id, started=True)
            self.last_id = output.id  # a deferred child's id was the highest when it was deferred
        self.status = Status.UNDERWAY.value

    def _begin(self, output: outs.PublishBegin, event: ins.Input) -> None:
        if not isinstance(event, ins.Begin):
            raise self._fail(
                Violation.BEGIN_MESSAGE,
                f"a begin message (seq {output.message.dynamic_event_seq}) without a begin",
            )
        expected = machine.next_seq(self.seq)  # R3.1
        if output.message.dynamic_event_seq != expected:
            raise self._fail(
                Violation.BEGIN_MESSAGE,
                f"begin with seq {output.message.dynamic_event_seq}, expected {expected}",
            )
        if self.active:
            raise self._fail(Violation.BEGIN_WHILE_ACTIVE, "a begin message while a dynamic event is active")
        self.seq = expected
        self.active = True
        self.event_id = event.event_id
        self.description = machine.begin_description(event.description, self.config)  # R3.3, R17.6
        self.last_id = event.event_id
        self.status = Status.STANDBY.value
        self.task_signal = ""
        self.interrupted = event.interrupted  # R3.1: the beginning task's own interruption

    def _after(self, event: ins.Input, outputs: list[outs.Output], emptied: bool) -> None:
        ignored = len(outputs) == 1 and isinstance(outputs[0], outs.Ignored)
        if ignored:
            return
        if isinstance(event, ins.ChildProgress) and self.child_started and not self.task_signal:
            self.status = event.status  # R7.4
        elif isinstance(event, (ins.TaskCancel, ins.TaskKill)) and self.active:
            signal = Status.KILLED.value if isinstance(event, ins.TaskKill) else Status.CANCELED.value
            self.task_signal = signal
            self.status = signal
        elif isinstance(event, ins.Interrupt):
            self.interrupted = True
        elif isinstance(event, ins.Resume):
            self.interrupted = False
        elif (
            isinstance(event, ins.IdDrawn) and self.active and self.config.id_policy is IdPolicy.ADAPTER
        ):  # R17.8
            fresh = machine.fresh_id(self.last_id)  # R17.8: the adapter's counter moved on
            self.last_id = 0 if fresh is None else fresh
        elif isinstance(event, ins.Shutdown):
            self.shut_down = True
            self.active = False
            self.running = None
            self.stubborn = False
            self.check_all_answered()
        if emptied and self.active:  # R8.4, R9.4, R10.4: the slot emptied, the run goes on
            self.status = Status.STANDBY.value


class Observer(_Goals, _Children):
    """A reference model of one robot's server, built from inputs and outputs only.

    Feed it every input and the outputs the implementation answered with
    (:meth:`observe`); it raises :class:`ProtocolViolation` at the first
    breach of the checked rules (see the module docs) and otherwise keeps
    the state those outputs imply.  :meth:`check_all_answered` is the end of
    run check of R19.1.  Its attributes are what a client could know, and what
    the kit's rules build goals from; besides the views below it offers
    ``current_id``, ``child_started``, ``open_goals`` and ``answered_goals``.
    """

    # ---------------------------------------------------------------- views

    @property
    def phase(self) -> DynamicState:
        """The phase the outputs imply (R2.1)."""
        return machine.phase_of(self.active, self.running is not None)

    @property
    def answered_goals(self) -> list[str]:
        """Goals that received their terminal answer."""
        return [uuid for uuid, record in self.goals.items() if record.life.is_terminal]

    def check_view(self, view: ServerView | None) -> None:
        """The implementation's own view agrees with the model (R2.1, R2.2)."""
        if view is None:
            return
        expected = ServerView(self.phase, self.seq, self.current_id)
        if view != expected:
            raise ProtocolViolation(
                Violation.VIEW_MISMATCH, f"the implementation's view is {view}, the outputs imply {expected}"
            )

    def observe(self, event: ins.Input, outputs: Sequence[outs.Output]) -> None:
        """Check one step's outputs against the model, then advance the model."""
        self._event = event
        outputs = list(outputs)
        for output in outputs:
            if not isinstance(output, _OUTPUT_CLASSES):
                raise self._fail(
                    Violation.FOREIGN_OUTPUT, f"apply returned {output!r}, which is not a dynevent output"
                )
        if any(isinstance(output, outs.Ignored) for output in outputs) and len(outputs) != 1:
            raise self._fail(
                Violation.IGNORED_NOT_ALONE, f"Ignored must be the only output of its step, got {outputs}"
            )
        if isinstance(event, ins.GoalRequested):  # a request reusing a finished goal's UUID is a new goal
            record = self.goals.get(event.goal_uuid)
            if record is not None and record.life.is_terminal:
                del self.goals[event.goal_uuid]
            self.rejected.discard(event.goal_uuid)
        before = self._key()
        wire_status = self._wire_status(event)
        seq_before, active_before = self.seq, self.active
        ended = self.running
        ended_goal = None if ended is None else self.goals[ended.goal_uuid].goal
        emptied = False
        statuses = [output for output in outputs if isinstance(output, outs.PublishStatus)]
        for output in outputs:
            if isinstance(output, outs.AnswerGoal):
                if self.running is not None and self.running.goal_uuid == output.goal_uuid:
                    emptied = True
                self._answer(output)
            elif isinstance(output, outs.PublishStatus):
                continue
            else:
                self._effect(output, event, outputs, ended_goal)
        self._after(event, outputs, emptied)
        if isinstance(event, ins.GoalStarted) and any(
            isinstance(output, outs.ExecuteGoal) and output.goal_uuid == event.goal_uuid for output in outputs
        ):
            self._check_race(self.goals[event.goal_uuid], seq_before, active_before)
        after = self._key()
        if wire_status is not None:  # R17.4, R17.5: rmf_ros2 mode publishes what rmf_ros2's wire shows
            if len(statuses) != 1 or outputs[-1] is not statuses[0] or statuses[0].message != wire_status:
                raise self._fail(
                    Violation.STATUS_AFTER_CHILD_END
                    if isinstance(event, ins.ChildFinished)
                    else Violation.STATUS_AFTER_REPORT,
                    f"status message {wire_status} as the last output expected; got {outputs}",
                )
            return
        if statuses:
            if len(statuses) > 1 or outputs[-1] is not statuses[0]:
                raise self._fail(
                    Violation.STATUS_PUBLICATION,
                    f"one status message, as the last output, expected; got {outputs}",
                )
            expected = self.expected_status(event.now)
            if statuses[0].message != expected:
                raise self._fail(
                    Violation.STATUS_NOT_STATE,
                    f"status message {statuses[0].message} but the state implies {expected}",
                )
        if (before != after) != bool(statuses):
            what = "changed without a status message" if before != after else "did not change"
            raise self._fail(
                Violation.STATUS_PUBLICATION,
                f"status {before} -> {after} {what}; status messages: {[s.message for s in statuses]}",
            )

    def _wire_status(self, event: ins.Input) -> DynamicEventStatus | None:
        """The status message rmf_ros2 mode publishes for a child's report or end (R17.4, R17.5)."""
        running = self.running
        if self.config.compatibility is not Compatibility.RMF_ROS2 or running is None or not running.started:
            return None
        if isinstance(event, ins.ChildFinished) and self.task_signal:
            return None  # the run ends: R13.4 and R2.3 as in standard mode
        if not isinstance(event, (ins.ChildProgress, ins.ChildFinished)):
            return None
        if isinstance(event, ins.ChildFinished) and self.cancels:  # a CANCEL freed the slot first (R17.4)
            return machine.status_of(self.seq, True, event.status, running.child_id, None, event.now)
        return machine.status_of(self.seq, True, event.status, self.last_id, running.child_id, event.now)

    def _effect(
        self, output: outs.Output, event: ins.Input, outputs: list[outs.Output], ended: Goal | None
    ) -> None:
        if isinstance(output, _GOAL_OUTPUTS):
            self._goal_effect(output, event)
        else:
            self._child_effect(output, event, ended)
