"""A reusable hypothesis state machine that drives any Dynamic Event server and checks §19 of the spec.

The kit has three parts:

- :class:`ServerUnderTest`, the small adapter interface an implementation is
  wrapped in (``reset``, ``apply``, ``view``), with :class:`DyneventServer`
  (dynevent's own machine) and :class:`ImplementationServer` (any program or
  object speaking the conformance driver protocol of :mod:`dynevent.conformance.driver`);
- :class:`Observer`, a small reference model of the protocol state (phase,
  seq, status, current id, the goals and their ROS 2 lifecycle) that is
  derived only from the inputs sent and the outputs received, never from the
  implementation's internals, and that raises :class:`ProtocolViolation` at
  the first output the invariants of docs/spec.md §19 forbid;
- :class:`ServerStateMachine`, a :class:`~hypothesis.stateful.RuleBasedStateMachine`
  whose rules generate well-typed inputs: begins, goal requests of every type
  (valid ones built from the observed state so that runs go deep, and hostile
  ones: wrong seq, unknown event types, text that is not JSON, descriptions
  that fail their category, non-finite stubborn periods, stale and mismatched
  ids), starts of accepted goals in any order, action-level cancels, child
  progress and ends with any status, ticks that move the robot or not,
  interruptions, task cancels and kills, description queries and, rarely,
  shutdown.

Wrapping another implementation::

    class MyServer:  # satisfies ServerUnderTest
        def reset(self, fleet, robot, config): ...
        def apply(self, event): ...   # dynevent outputs, in order
        def view(self): return None   # or a ServerView

    TestMyServer = server_state_machine(MyServer).TestCase

The invariants checked after every step (rule numbers of docs/spec.md):

- R19.1: every accepted goal gets exactly one terminal answer, allowed by its
  ROS 2 lifecycle (succeed or abort once executing, cancel only after an
  accepted cancel); a rejected goal gets none; no output names a goal after
  its answer.  At teardown the kit shuts the server down and checks that
  every accepted goal was answered.
- R19.2: at most one goal holds the running slot: no ``StartChild`` while a
  started child runs, no NEXT accepted while a goal holds the slot.
- R19.3: the seq of begin and status messages changes only at a begin, by one.
- R19.4: every stubborn period applied (begin, hold, clamp) is at least the
  configured minimum, and a hold begins with ``max(requested, minimum)``.
- R19.5 (and R2.3): a step emits a status message exactly when the status the
  model implies changed, as its last output, equal to that status (R2.2)
  with ``time`` the input's ``now``.
- R19.7: ``apply`` never raises.

and, because they cost little once the model exists: a goal that starts in
another run (or with no run) is aborted (R5.2), a notice ``Ignored`` is the
only output of its step (R18.1), ``LogEntry.seq`` counts entries (R7.3), a
description answer matches the model (R16), and the optional view agrees with
the model (R2.1, R2.2).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, ClassVar, Protocol

import attrs
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from dynevent.conformance.records import config_from_json, input_to_json, output_from_json
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.testing.strategies import messages
from dynevent.wire import _json
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import (
    Compatibility,
    DynamicState,
    EventType,
    GoalStatus,
    IdPolicy,
    Status,
    Tier,
    Violation,
)

__all__ = [
    "DEFAULT_CONFIG",
    "DyneventServer",
    "ImplementationServer",
    "Observer",
    "ProtocolViolation",
    "ServerStateMachine",
    "ServerUnderTest",
    "ServerView",
    "input_sequences",
    "server_inputs",
    "server_state_machine",
]

_MS = 1_000_000

#: The configuration record (:func:`dynevent.conformance.records.config_from_json`) the kit uses by default:
#: one category that needs an object with a ``place``, one that takes anything, and a short
#: description limit so that over-long descriptions are cheap to generate.
DEFAULT_CONFIG: Mapping[str, Any] = {
    "categories": {
        "go_to_place": {"accept": "object", "required": ["place"]},
        "perform_action": {"accept": "any"},
    },
    "max_description_length": 256,
}

# Descriptions the generators choose from; which are valid depends on the category's rule.
_DESCRIPTIONS: tuple[str, ...] = (
    '{"place": "pantry"}',
    '{"place": "lobby", "speed": 0.5, "custom": {"keep": [1, 2, null]}}',
    '{"action": "clean", "parameters": {"zone": "A"}}',
    '"dock"',
    "[1, 2, 3]",
    "{}",
    "42",
    '{"place": NaN}',
)
# Text that is not JSON as R4.9 reads it (duplicate keys and deep nesting included).
_NOT_JSON: tuple[str, ...] = (
    "",
    "{",
    "not json",
    '{"place": "a", "place": "b"}',
    "[" * 65 + "]" * 65,
    "{'place': 'pantry'}",
    '{"place": "pantry"} trailing',
)
_BEGIN_DESCRIPTIONS: tuple[str, ...] = (
    "{}",
    '{"category": "patrol"}',
    '{"detail": "inspect", "parameters": [1, {"a": null}], "custom_field": true}',
    '{"estimate": {"category": "go_to_place", "description": {"place": "lobby"}}, '
    '"required": [{"category": "perform_action", "description": "x"}]}',
)
_STUBBORN: tuple[float, ...] = (0.0, 0.0, 0.0, -1.0, 0.5, 1.0, 2.0, 2.5, 10.0)
_NON_FINITE: tuple[float, ...] = (math.nan, math.inf, -math.inf)
_STATUSES: tuple[str, ...] = tuple(status.value for status in Status)
_OUTPUT_CLASSES = tuple(outs.OUTPUT_TYPES.values())
_FAULTS: tuple[str, ...] = (
    "seq",
    "event_type",
    "not_json",
    "invalid",
    "too_long",
    "category",
    "stubborn",
    "stale",
    "cancel_id",
    "fields",
)
_ADVANCE_STATUSES: tuple[str, ...] = tuple(
    status.value
    for status in (Status.COMPLETED, Status.COMPLETED, Status.UNDERWAY, Status.FAILED, Status.CANCELED)
)
_SIGNALS: Mapping[str, Callable[..., ins.Input]] = {
    "interrupt": ins.Interrupt,
    "resume": ins.Resume,
    "task_cancel": ins.TaskCancel,
    "task_kill": ins.TaskKill,
    "describe": ins.DescriptionQuery,
}
_STRAYS: tuple[str, ...] = ("begin", "goal", "start", "cancel", "progress", "finished", "tick", *_SIGNALS)


# --------------------------------------------------------------------------- the adapter interface


@attrs.frozen
class ServerView:
    """What an implementation may expose of its state: the phase, the seq and the current id (R2.2)."""

    phase: DynamicState
    seq: int
    current_id: int


class ServerUnderTest(Protocol):
    """The adapter an implementation is wrapped in to be driven by the kit.

    ``reset`` starts a fresh server for one robot, configured by a
    configuration record (the JSON form of :func:`dynevent.conformance.records.config_from_json`).
    ``apply`` feeds one input and returns the outputs, in order, as dynevent's
    output classes (:mod:`dynevent.server.outputs`); it must not raise.  ``view``
    returns the phase, seq and current id, or ``None`` when the implementation
    does not expose them (the kit then checks the outputs alone).
    """

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """Start a fresh server for ``fleet``/``robot`` with this configuration record."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """Apply one input; return its outputs in order."""

    def view(self) -> ServerView | None:
        """The phase, seq and current id, or ``None``."""


class DyneventServer:
    """dynevent's own machine behind :class:`ServerUnderTest`: :func:`~dynevent.server.machine.step`.

    ``state`` and ``config`` are public so that a test can wrap or perturb the
    server (e.g. to build a deliberately broken one).
    """

    def __init__(self) -> None:
        self.config = ServerConfig()
        self.state: State | None = None

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """A fresh state and the configuration the record describes."""
        self.config = config_from_json(dict(config))
        self.state = State.new(fleet, robot)

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """One step of the machine."""
        if self.state is None:
            raise RuntimeError("apply before reset")
        transition = machine.step(self.state, event, self.config)
        self.state = transition.state
        return list(transition.outputs)

    def view(self) -> ServerView | None:
        """The machine's phase, seq and current id."""
        if self.state is None:
            return None
        return ServerView(self.state.phase, self.state.seq, self.state.current_id)


class _Implementation(Protocol):
    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None: ...

    def apply(self, event: Any) -> tuple[list[Any], Any]: ...


class ImplementationServer:
    """Any implementation of the conformance driver protocol behind :class:`ServerUnderTest`.

    ``implementation`` is a :class:`dynevent.conformance.vectors.Implementation` (for
    instance :class:`~dynevent.conformance.vectors.ExternalImplementation` running another
    program); inputs and outputs cross as the JSON records of
    :mod:`dynevent.conformance.records`.  Closing the implementation is the caller's job.
    """

    def __init__(self, implementation: _Implementation) -> None:
        self._implementation = implementation
        self._view: ServerView | None = None

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """Reset the implementation to a fresh server."""
        self._implementation.reset(fleet, robot, dict(config), None)
        self._view = None

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """Send the input record; decode the output records and keep the view."""
        records, view = self._implementation.apply(input_to_json(event))
        self._view = _decode_view(view)
        return [output_from_json(record, f"$.outputs[{index}]") for index, record in enumerate(records)]

    def view(self) -> ServerView | None:
        """The view of the last answer, when the implementation sent one."""
        return self._view


def _decode_view(view: Any) -> ServerView | None:
    if not isinstance(view, dict):
        return None
    try:
        return ServerView(DynamicState[view["phase"]], int(view["seq"]), int(view["current_id"]))
    except (KeyError, TypeError, ValueError):
        return None


# --------------------------------------------------------------------------- the reference model


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
            if output.entry.seq != self.log_seq:
                raise self._fail(
                    Violation.LOG_SEQ, f"LogEntry.seq {output.entry.seq}, expected {self.log_seq}"
                )
            self.log_seq = (self.log_seq + 1) & U32_MAX
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
        self.last_id = output.id
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


# --------------------------------------------------------------------------- the state machine


def _valid_descriptions(config: ServerConfig, category: str) -> list[str]:
    """The kit's descriptions that ``config`` accepts for ``category`` (all of them for an unknown one)."""
    validator = config.categories.get(category)
    if validator is None:
        return list(_DESCRIPTIONS)
    limit = config.max_description_length
    return [text for text in _DESCRIPTIONS if len(text) <= limit and _fits(validator, category, text)]


def _next_goal(config: ServerConfig, categories: Sequence[str], model: Observer, data: st.DataObject) -> Goal:
    """A NEXT goal the server must accept in the modelled state (unless it races)."""
    category = data.draw(st.sampled_from(categories or ("none",)), label="category")
    valid = _valid_descriptions(config, category) or list(_DESCRIPTIONS)
    if config.id_policy is IdPolicy.GOAL:
        step = data.draw(st.integers(0, 3), label="id step")  # 0: the server assigns the id (R6.2)
        goal_id = 0 if step == 0 else min(model.last_id + step, U64_MAX)
    else:
        goal_id = data.draw(st.integers(0, 5), label="id")
    return Goal(
        dynamic_event_seq=model.seq,
        event_type=EventType.NEXT,
        category=category,
        description=data.draw(st.sampled_from(valid), label="description"),
        id=goal_id,
        stubborn_period=data.draw(st.sampled_from(_STUBBORN), label="stubborn_period"),
    )


def _hostile(goal: Goal, fault: str, data: st.DataObject, config: ServerConfig, model: Observer) -> Goal:
    """``goal`` made wrong in one way, ``fault``: its seq, event type, description, category, period or id."""
    if fault == "seq":
        shift = data.draw(st.sampled_from((1, 2, U32_MAX)), label="seq shift")
        goal = attrs.evolve(goal, dynamic_event_seq=(model.seq + shift) & U32_MAX)
    elif fault == "event_type":
        event_type = data.draw(st.sampled_from((0, 4, 5, 1000, U32_MAX)), label="event_type")
        goal = attrs.evolve(goal, event_type=event_type)
    elif fault == "not_json":
        goal = attrs.evolve(goal, description=data.draw(st.sampled_from(_NOT_JSON), label="text"))
    elif fault == "invalid":
        valid = set(_valid_descriptions(config, goal.category))
        invalid = [text for text in _DESCRIPTIONS if text not in valid]
        if invalid:
            goal = attrs.evolve(goal, description=data.draw(st.sampled_from(invalid), label="text"))
    elif fault == "too_long":
        length = config.max_description_length + 1
        if length <= 100_000:
            goal = attrs.evolve(goal, description='"' + "x" * (length - 1) + '"')
    elif fault == "category":
        category = data.draw(st.sampled_from(("", "unknown", "Go_To_Place")), label="category")
        goal = attrs.evolve(goal, category=category)
    elif fault == "stubborn":
        goal = attrs.evolve(goal, stubborn_period=data.draw(st.sampled_from(_NON_FINITE), label="period"))
    elif fault == "stale":
        goal = attrs.evolve(goal, id=max(model.last_id - data.draw(st.integers(0, 2), label="back"), 0))
    elif fault == "cancel_id":
        current = model.current_id
        wrong = data.draw(st.sampled_from(((current + 1) & U64_MAX, (current - 1) & U64_MAX, 0)), label="id")
        goal = Goal(dynamic_event_seq=model.seq, event_type=EventType.CANCEL, id=wrong)
    else:  # a CANCEL or FINISHED carrying NEXT's fields, and a NaN period
        event_type = data.draw(st.sampled_from((EventType.CANCEL, EventType.FINISHED)), label="type")
        goal = attrs.evolve(goal, event_type=event_type, stubborn_period=math.nan)
    return goal


class ServerStateMachine(RuleBasedStateMachine):
    """Drive a server with generated inputs and check every step with an :class:`Observer`.

    Subclass it and override :meth:`make_server` (or use
    :func:`server_state_machine`); ``config`` is the configuration record the
    server is reset with, ``fleet`` and ``robot`` its names.  The hypothesis
    ``TestCase`` of the subclass runs it under pytest or unittest.
    """

    fleet: ClassVar[str] = "kit_fleet"
    robot: ClassVar[str] = "kit_robot"
    config: ClassVar[Mapping[str, Any]] = DEFAULT_CONFIG

    def __init__(self) -> None:
        super().__init__()
        self.server_config = config_from_json(dict(self.config))
        self.server = self.make_server()
        self.server.reset(self.fleet, self.robot, self.config)
        self.model = Observer(self.fleet, self.robot, self.server_config)
        self.now = 1_700_000_000 * SECOND
        self.position = ("L1", 0.0, 0.0)
        self._uuids = 0
        self._broken = False
        self.categories = tuple(sorted(self.server_config.categories))

    def make_server(self) -> ServerUnderTest:
        """The server under test; override in a subclass."""
        raise NotImplementedError("override make_server() to return the ServerUnderTest to drive")

    # ---------------------------------------------------------------- plumbing

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """Feed one input to the server and check its outputs (R19.7 and the observer's rules)."""
        try:
            outputs = self.server.apply(event)
        except Exception as exc:
            self._broken = True
            raise ProtocolViolation(
                Violation.FOREIGN_OUTPUT, f"apply raised {type(exc).__name__}: {exc}", event
            ) from exc
        try:
            self.model.observe(event, outputs)
        except ProtocolViolation:
            self._broken = True
            raise
        return outputs

    def _tick(self, step: int = _MS) -> int:
        self.now += step
        return self.now

    def _uuid(self) -> str:
        self._uuids += 1
        return f"{0xD7E0 << 112 | self._uuids:032x}"

    def _request(self, goal: Goal, uuid: str | None = None) -> None:
        self.apply(ins.GoalRequested(goal_uuid=uuid or self._uuid(), goal=goal, now=self._tick()))

    def _valid_descriptions(self, category: str) -> list[str]:
        return _valid_descriptions(self.server_config, category)

    def _next_goal(self, data: st.DataObject) -> Goal:
        return _next_goal(self.server_config, self.categories, self.model, data)

    def _pick(self, data: st.DataObject, uuids: Sequence[str], label: str) -> str:
        return data.draw(st.sampled_from(list(uuids)), label=label)

    def _stray(self, data: st.DataObject) -> str:
        """An answered, rejected or never seen goal UUID."""
        known = self.model.answered_goals + sorted(self.model.rejected)
        reuse: bool = data.draw(st.booleans(), label="reuse a known uuid")
        if known and reuse:
            return self._pick(data, known, "uuid")
        return self._uuid()

    # ---------------------------------------------------------------- rules: runs and goals
    # Rules are drawn uniformly among those whose precondition holds, so the
    # productive moves are gated to the states where they matter and every
    # stray input (ignored or refused in most states) shares one rule.

    @rule(data=st.data())
    def advance(self, data: st.DataObject) -> None:
        """Push the run on with the move a well-behaved task, client and robot would make next."""
        model = self.model
        if model.shut_down:
            self.apply(ins.DescriptionQuery(now=self._tick()))
        elif not model.active:
            event_id = data.draw(st.integers(0, 20), label="event_id")
            self.apply(ins.Begin(description="{}", event_id=event_id, now=self._tick()))
        elif model.queued:
            self.apply(ins.GoalStarted(goal_uuid=model.queued[0], now=self._tick()))
        elif model.child_started:
            status = data.draw(st.sampled_from(_ADVANCE_STATUSES), label="status")
            if status == Status.UNDERWAY.value:
                self.apply(ins.ChildProgress(status=status, log_text="on the way", now=self._tick()))
            else:
                self.apply(ins.ChildFinished(status=status, now=self._tick()))
        elif model.running is not None:
            self.apply(ins.Resume(now=self._tick()))
        elif model.stubborn and data.draw(st.booleans(), label="tick"):
            self._move(SECOND, 0.0, False)
        elif data.draw(st.integers(0, 7), label="finish the run") == 5:
            self._request(Goal(dynamic_event_seq=model.seq, event_type=EventType.FINISHED))
        else:
            self._request(self._next_goal(data))

    @rule(data=st.data())
    def advance_again(self, data: st.DataObject) -> None:
        """The same push, drawn twice as often as any other rule."""
        self.advance(data)

    @precondition(lambda self: not self.model.active and not self.model.shut_down)
    @rule(event_id=st.one_of(st.integers(0, 20), st.just(U64_MAX), st.integers(0, U64_MAX)), data=st.data())
    def begin(self, event_id: int, data: st.DataObject) -> None:
        """A task reaches a dynamic event phase."""
        description = data.draw(st.sampled_from(_BEGIN_DESCRIPTIONS), label="description")
        interrupted = data.draw(st.integers(0, 4), label="interrupted") == 0
        self.apply(
            ins.Begin(description=description, event_id=event_id, now=self._tick(), interrupted=interrupted)
        )

    @precondition(lambda self: self.model.active)
    @rule(data=st.data())
    def request_next(self, data: st.DataObject) -> None:
        """A NEXT built to be valid from the observed state (refused as busy while a goal runs)."""
        self._request(self._next_goal(data))

    @precondition(lambda self: self.model.active)
    @rule(data=st.data())
    def request_next_again(self, data: st.DataObject) -> None:
        """Another valid NEXT: several may be accepted before any starts (R4.16, R5.2)."""
        self._request(self._next_goal(data))

    @precondition(lambda self: self.model.running is not None)
    @rule(period=st.sampled_from((0.0, math.nan)))
    def request_cancel(self, period: float) -> None:
        """A CANCEL naming the running child (its stubborn period is not checked)."""
        running = self.model.running
        assert running is not None
        goal = Goal(
            dynamic_event_seq=self.model.seq,
            event_type=EventType.CANCEL,
            id=running.child_id,
            stubborn_period=period,
        )
        self._request(goal)

    @precondition(lambda self: self.model.active)
    @rule()
    def request_finished(self) -> None:
        """A FINISHED for the current run (refused as busy while a goal runs)."""
        self._request(Goal(dynamic_event_seq=self.model.seq, event_type=EventType.FINISHED))

    @precondition(lambda self: self.model.active)
    @rule(fault=st.sampled_from(_FAULTS), data=st.data())
    def request_hostile(self, fault: str, data: st.DataObject) -> None:
        """A goal valid in every way but one: the wrong seq, event type, description, period or id."""
        goal = _hostile(self._next_goal(data), fault, data, self.server_config, self.model)
        self._request(goal)

    @precondition(lambda self: bool(self.model.open_goals))
    @rule(data=st.data())
    def request_duplicate(self, data: st.DataObject) -> None:
        """A request reusing the UUID of an open goal (R18.2)."""
        uuid = self._pick(data, self.model.open_goals, "uuid")
        self._request(self.model.goals[uuid].goal, uuid)

    @precondition(lambda self: bool(self.model.queued))
    @rule(data=st.data())
    def start_goal(self, data: st.DataObject) -> None:
        """Start one of the accepted goals, in any order."""
        uuid = self._pick(data, self.model.queued, "uuid")
        self.apply(ins.GoalStarted(goal_uuid=uuid, now=self._tick()))

    @precondition(lambda self: bool(self.model.queued))
    @rule(newest=st.booleans())
    def start_goal_again(self, newest: bool) -> None:
        """Start the oldest or the newest accepted goal."""
        uuid = self.model.queued[-1 if newest else 0]
        self.apply(ins.GoalStarted(goal_uuid=uuid, now=self._tick()))

    @precondition(lambda self: bool(self.model.open_goals))
    @rule(data=st.data())
    def cancel_goal(self, data: st.DataObject) -> None:
        """An action-level cancel of an open goal: queued, running or a waiting CANCEL (R10)."""
        uuid = self._pick(data, self.model.open_goals, "uuid")
        self.apply(ins.CancelRequested(goal_uuid=uuid, now=self._tick()))

    # ---------------------------------------------------------------- rules: the child and the task

    @precondition(lambda self: self.model.child_started)
    @rule(
        status=st.sampled_from(_STATUSES),
        text=st.one_of(st.none(), st.sampled_from(("moving", "", "door closed", "\u00e9t\u00e9 \U0001f916"))),
        tier=st.sampled_from(tuple(Tier)),
    )
    def child_progress(self, status: str, text: str | None, tier: Tier) -> None:
        """The running child reports a status, maybe with a log line."""
        self.apply(ins.ChildProgress(status=status, log_text=text, tier=tier, now=self._tick()))

    @precondition(lambda self: self.model.child_started)
    @rule(status=st.sampled_from((Status.COMPLETED.value, Status.COMPLETED.value, *_STATUSES)))
    def child_finished(self, status: str) -> None:
        """The running child ends with some final status (most often completed)."""
        self.apply(ins.ChildFinished(status=status, now=self._tick()))

    @precondition(lambda self: self.model.stubborn)
    @rule(
        step=st.sampled_from((_MS, 500 * _MS, SECOND, 1_500 * _MS, 3 * SECOND)),
        move=st.sampled_from((0.0, 0.0, 0.05, 0.5, 5.0)),
        change_map=st.booleans(),
    )
    def tick(self, step: int, move: float, change_map: bool) -> None:
        """Time passes while stubborn; the robot stays, creeps, moves or changes map."""
        self._move(step, move, change_map)

    @precondition(lambda self: self.model.active and not self.model.interrupted)
    @rule()
    def interrupt(self) -> None:
        """The task is interrupted."""
        self.apply(ins.Interrupt(now=self._tick()))

    @precondition(lambda self: self.model.interrupted)
    @rule()
    def resume(self) -> None:
        """The task's interruption is released."""
        self.apply(ins.Resume(now=self._tick()))

    @precondition(lambda self: self.model.active)
    @rule(kill=st.booleans())
    def task_signal(self, kill: bool) -> None:
        """The whole task is cancelled or killed."""
        self.apply(ins.TaskKill(now=self._tick()) if kill else ins.TaskCancel(now=self._tick()))

    @precondition(lambda self: not self.model.shut_down)
    @rule(roll=st.integers(0, 39))
    def shutdown_rarely(self, roll: int) -> None:
        """Shut down in about one draw of forty (a description query otherwise)."""
        if roll == 23:
            self.apply(ins.Shutdown(now=self._tick()))
        else:
            self.apply(ins.DescriptionQuery(now=self._tick()))

    @rule(kind=st.sampled_from(_STRAYS), data=st.data())
    def stray(self, kind: str, data: st.DataObject) -> None:
        """Any input at any moment, most often ignored or refused (R18), and description queries."""
        now = self._tick()
        event: ins.Input
        if kind == "begin":
            event = ins.Begin(description="{}", event_id=data.draw(st.integers(0, 9), label="id"), now=now)
        elif kind == "goal":
            goal = data.draw(st.one_of(messages(Goal), st.builds(self._next_goal, st.data())), label="goal")
            event = ins.GoalRequested(goal_uuid=self._uuid(), goal=goal, now=now)
        elif kind == "start":
            event = ins.GoalStarted(goal_uuid=self._stray(data), now=now)
        elif kind == "cancel":
            event = ins.CancelRequested(goal_uuid=self._stray(data), now=now)
        elif kind == "progress":
            status = data.draw(st.sampled_from(_STATUSES), label="status")
            event = ins.ChildProgress(status=status, log_text="stray", now=now)
        elif kind == "finished":
            event = ins.ChildFinished(status=data.draw(st.sampled_from(_STATUSES), label="status"), now=now)
        elif kind == "tick":
            step = data.draw(st.sampled_from((0, SECOND, 3 * SECOND)), label="step")
            self._move(step, data.draw(st.sampled_from((0.0, 1.0)), label="move"), False)
            return
        else:
            event = _SIGNALS[kind](now=now)
        self.apply(event)

    def _move(self, step: int, move: float, change_map: bool) -> None:
        map_name, x, y = self.position
        if change_map and move > 1.0:
            map_name = "L2" if map_name == "L1" else "L1"
        self.position = (map_name, x + move, y)
        self.apply(ins.Tick(now=self._tick(step), map_name=map_name, x=x + move, y=y))

    # ---------------------------------------------------------------- invariants and the end

    @invariant()
    def view_agrees_with_outputs(self) -> None:
        """The implementation's view (when it offers one) is the state its outputs imply."""
        try:
            self.model.check_view(self.server.view())
        except ProtocolViolation:
            self._broken = True
            raise

    def teardown(self) -> None:
        """Shut the server down and check that every accepted goal was answered (R19.1)."""
        if self._broken:
            return
        self.apply(ins.Shutdown(now=self._tick()))
        self.model.check_all_answered()


def _fits(validator: machine.Validator, category: str, text: str) -> bool:
    try:
        return not validator(category, _json.parse(text))
    except Exception:
        return False


def server_state_machine(
    factory: Callable[[], ServerUnderTest],
    *,
    config: Mapping[str, Any] | None = None,
    name: str = "ServerMachine",
) -> type[ServerStateMachine]:
    """A :class:`ServerStateMachine` subclass driving servers made by ``factory``.

    ``config`` (a configuration record) replaces :data:`DEFAULT_CONFIG`.  Use
    the result's ``TestCase`` as a test class, or pass the class to
    :func:`hypothesis.stateful.run_state_machine_as_test`.
    """

    class Machine(ServerStateMachine):
        __doc__ = f"The kit driving servers made by {factory!r}."

        def make_server(self) -> ServerUnderTest:
            return factory()

    if config is not None:
        Machine.config = config
    Machine.__name__ = Machine.__qualname__ = name
    return Machine


# --------------------------------------------------------------------------- plain input strategies


def _same(event: ins.Input) -> ins.Input:
    return event


def server_inputs(
    categories: Sequence[str] = ("go_to_place", "perform_action"),
    *,
    uuids: int = 4,
    seq: int = 1,
    now: st.SearchStrategy[int] | None = None,
    shutdown: bool = True,
) -> st.SearchStrategy[ins.Input]:
    """Any input, drawn from small pools so that random sequences meet often.

    Goal UUIDs come from ``uuids`` fixed values; goal seqs are mostly
    ``seq`` (the run the goals are aimed at), sometimes its neighbours or 0;
    ids come from a handful of small values (and 0 and the largest),
    descriptions and stubborn periods from valid and hostile pools.  Goal
    requests and starts are drawn more often than other inputs.  With
    ``shutdown``, about one input in forty is a shutdown.
    """
    times = now if now is not None else st.integers(0, 20 * SECOND)
    uuid = st.sampled_from([f"{index:032x}" for index in range(1, uuids + 1)])
    goal = st.builds(
        Goal,
        dynamic_event_seq=st.sampled_from((*(seq,) * 8, (seq + 1) & U32_MAX, (seq - 1) & U32_MAX, 0)),
        event_type=st.sampled_from((1, 1, 1, 1, 2, 2, 3, 0, 4)),
        category=st.sampled_from((*categories, *categories, "unknown")),
        description=st.sampled_from((_DESCRIPTIONS[0],) * 4 + _DESCRIPTIONS + _NOT_JSON[:4]),
        id=st.one_of(st.integers(1, 8), st.sampled_from((0, U64_MAX))),
        stubborn_period=st.sampled_from(_STUBBORN + _NON_FINITE),
    )
    status = st.sampled_from(_STATUSES)
    request = st.builds(ins.GoalRequested, goal_uuid=uuid, goal=goal, now=times)
    start = st.builds(ins.GoalStarted, goal_uuid=uuid, now=times)
    progress = st.builds(
        ins.ChildProgress,
        status=status,
        now=times,
        log_text=st.one_of(st.none(), st.just("progress")),
        tier=st.sampled_from(tuple(Tier)),
    )
    finished = st.builds(ins.ChildFinished, status=status, now=times)
    begin = st.builds(
        ins.Begin,
        description=st.sampled_from(_BEGIN_DESCRIPTIONS),
        event_id=st.sampled_from((0, 0, 1, 4, U64_MAX)),
        now=times,
    )
    kinds: dict[str, tuple[int, st.SearchStrategy[ins.Input]]] = {  # weight, strategy
        "begin": (1, begin),
        "request": (4, request),
        "start": (4, start),
        "cancel": (1, st.builds(ins.CancelRequested, goal_uuid=uuid, now=times)),
        "progress": (2, progress),
        "finished": (2, finished),
        "tick": (
            1,
            st.builds(
                ins.Tick,
                now=times,
                map_name=st.sampled_from(("L1", "L2")),
                x=st.sampled_from((0.0, 0.05, 1.0)),
                y=st.just(0.0),
            ),
        ),
        "interrupt": (1, st.builds(ins.Interrupt, now=times)),
        "resume": (1, st.builds(ins.Resume, now=times)),
        "signal": (1, st.one_of(st.builds(ins.TaskCancel, now=times), st.builds(ins.TaskKill, now=times))),
        "describe": (1, st.builds(ins.DescriptionQuery, now=times)),
    }
    # one_of draws its branches alike (and merges equal ones): a weight is that many distinct copies
    common: st.SearchStrategy[ins.Input] = st.one_of(
        [strategy.map(_same) for weight, strategy in kinds.values() for _ in range(weight)]
    )
    if not shutdown:
        return common
    # shutdown ends everything: about one input in forty
    return st.tuples(st.integers(0, 39), common, times).map(
        lambda drawn: ins.Shutdown(now=drawn[2]) if drawn[0] == 23 else drawn[1]
    )


@st.composite
def input_sequences(
    draw: st.DrawFn,
    categories: Sequence[str] = ("go_to_place", "perform_action"),
    *,
    max_size: int = 40,
) -> list[ins.Input]:
    """Up to ``max_size`` inputs of :func:`server_inputs`, in runs; ``now`` never goes back.

    The sequence is cut into one to four runs, each a begin followed by
    inputs whose goals are aimed at that run's seq (the seq the run has when
    every earlier begin took effect), and often closed by a task cancel or
    kill so that the next begin takes effect; about one sequence in ten ends
    with a shutdown.
    """
    runs = draw(st.integers(1, 4), label="runs")
    size = max(max_size // runs - 2, 1)
    events: list[ins.Input] = []
    for run in range(1, runs + 1):
        events.append(ins.Begin(description="{}", event_id=draw(st.sampled_from((0, 1, 5))), now=0))
        body = server_inputs(categories, seq=run, now=st.just(0), shutdown=False)
        events.extend(draw(st.lists(body, min_size=size // 2, max_size=size), label=f"run {run}"))
        ending = draw(st.sampled_from(("kill", "cancel", "none")), label="ending")
        if ending == "kill":
            events.append(ins.TaskKill(now=0))
        elif ending == "cancel":
            events.append(ins.TaskCancel(now=0))
    if draw(st.integers(0, 9), label="shut down") == 7:
        events.append(ins.Shutdown(now=0))
    steps = draw(
        st.lists(
            st.sampled_from((0, _MS, 400 * _MS, SECOND, 2 * SECOND)),
            min_size=len(events),
            max_size=len(events),
        ),
        label="time steps",
    )
    now = 1_700_000_000 * SECOND
    result: list[ins.Input] = []
    for event, step in zip(events, steps, strict=True):
        now += step
        result.append(attrs.evolve(event, now=now))
    return result
