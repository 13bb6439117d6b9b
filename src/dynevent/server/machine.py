"""The robot-side Dynamic Event machine: pure ``accept`` and ``step`` over a frozen state.

Rule 1: everything that decides what the server does lives in this file (and,
beside it, the configuration's bounds and the state's derived phase and id:
:mod:`dynevent.server.config`, :mod:`dynevent.server.state`).  The rules are
numbered as in docs/spec.md (``R4.2`` and so on) and every rule is
cited where it is carried out: docs/rule-index.md, the one index of the whole project, names
for every rule the places that carry it out (this module's among them) and the tests that cite
it, and tests/project/test_spec_document.py keeps it current.  The machine never raises, never reads a clock
and never does I/O: time arrives in the inputs, and every effect leaves as an
output value (:mod:`dynevent.server.outputs`).

The module reads as the spec does, top down:

- what a state is: :class:`State` and its parts (re-exported from :mod:`dynevent.server.state`,
  with the configuration), and the :class:`Transition` a step gives;
- the table: each input's handler (``_HANDLER_NAMES``) and :data:`TRANSITIONS`, the phases a step
  may lead to from each phase (the source of the diagram in docs/spec.md, checked against the
  behaviour by the tests), with :func:`step`, which dispatches on it;
- the rules, section by section in the order of docs/spec.md (§2 phase and status to §21 restart),
  each section's checks and handlers together;
- the handlers resolved, and the shortcuts for speed: they state no rule, each is derived from
  the tables above it and names the benchmark that justifies it.

The table names its handlers rather than holding them, so that it stands above the functions it
names; :data:`HANDLERS` resolves the names once, at import, at the bottom of the module.
"""

from __future__ import annotations

import enum
import math
import typing
from collections.abc import Callable, Iterator, Mapping
from typing import Any, TypeAlias

import attrs

from dynevent.errors import WrongInput
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.config import (
    MAX_LISTED_ERRORS,
    METRES_RANGE,
    MORE_ERRORS,
    SECONDS_RANGE,
    ServerConfig,
    Validator,
    any_description,
    listed_errors,
)
from dynevent.server.state import (
    Position,
    QueuedGoal,
    RunningGoal,
    State,
    Stubbornness,
    phase_of,
    reported_id,
)
from dynevent.wire import _json
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX, copier, fast_init, maker, replacer, seq_after
from dynevent.wire.messages import (
    DescriptionResponse,
    DynamicEventDescription,
    DynamicEventStatus,
    Feedback,
    Goal,
    LogEntry,
    Result,
    Time,
)
from dynevent.wire.vocab import (
    ENDED_CHILD_STATUSES,
    TASK_SIGNAL_LOGS,
    Compatibility,
    DynamicState,
    EventType,
    Failure,
    GoalStatus,
    IdPolicy,
    RejectReason,
    Status,
)

__all__ = [
    "CHILD_END_RULE",
    "CHILD_RESULT_RULE",
    "CONFIGURED_REFUSALS",
    "DEFERRED_START_RULE",
    "EXECUTION_FAILURES",
    "FINISHED_RULE",
    "MAX_LISTED_ERRORS",
    "METRES_RANGE",
    "MORE_ERRORS",
    "REFUSED_IN_EVERY_STATE",
    "REQUEST_CHECKS",
    "SECONDS_RANGE",
    "START_RULE",
    "TRANSITIONS",
    "UNKNOWN_GOAL",
    "WAITING_CANCEL_RULE",
    "Edge",
    "Position",
    "QueuedGoal",
    "RaceLoss",
    "RequestCheck",
    "RunningGoal",
    "ServerConfig",
    "State",
    "Stubbornness",
    "Transition",
    "Validator",
    "accept",
    "any_description",
    "begin_description",
    "check_index",
    "child_ended",
    "could_refuse_first",
    "fresh_id",
    "listed_errors",
    "log_seq_fault",
    "next_child_id",
    "next_log_seq",
    "next_seq",
    "phase_of",
    "race_loss",
    "race_lost",
    "reported_id",
    "robot_waits",
    "runs_a_child",
    "state_from_status",
    "status_message",
    "status_of",
    "step",
]

# ------------------------------------------------------------ what a state is
#
# A state (:class:`State`, of :mod:`dynevent.server.state`) is a frozen value: the run's seq, whether
# a dynamic event is active, its status, the highest id used, the running goal and its child, the
# goals accepted and not yet started, the waiting CANCEL goals, the stubbornness, the task signal,
# the interruption and the shutdown.  Its phase (INACTIVE, WAITING, RUNNING) is a projection of it
# (:func:`phase_of`).  A step takes a state and an input and gives a :class:`Transition`.


@fast_init
@attrs.frozen
class Transition:
    """What one step did: the new state and the outputs, in order.  A pair: ``state, outputs = step(...)``."""

    state: State
    outputs: tuple[outs.Output, ...]

    def __iter__(self) -> Iterator[Any]:
        """The state, then the outputs, so that a transition unpacks as the pair it is."""
        return iter((self.state, self.outputs))


# --------- the table: each input's handler, and the phases a step may lead to


@attrs.frozen
class Edge:
    """One declared way a step may move the phase: ``source --input [guard]--> target`` (rule)."""

    source: DynamicState
    input: str
    target: DynamicState
    guard: str
    rule: str


_Handler: TypeAlias = Callable[[State, Any, ServerConfig], Transition]
_I, _W, _R = DynamicState.INACTIVE, DynamicState.WAITING, DynamicState.RUNNING

#: Input kind -> the name of its handler, in the order of docs/spec.md's sections.  The names are
#: resolved once, at import, into :data:`HANDLERS` at the bottom of the module, below the handlers.
#: One handler per input; the phases a step may lead to are :data:`TRANSITIONS`.
_HANDLER_NAMES: Mapping[str, str] = {
    ins.Begin.KIND: "_on_begin",  # §3
    ins.GoalRequested.KIND: "_on_goal_requested",  # §4
    ins.GoalSubmitted.KIND: "_on_goal_submitted",  # §5
    ins.GoalStarted.KIND: "_on_goal_started",  # §5, §6, §9, §11
    ins.ChildProgress.KIND: "_on_child_progress",  # §7
    ins.ChildFinished.KIND: "_on_child_finished",  # §8
    ins.CancelRequested.KIND: "_on_cancel_requested",  # §10
    ins.Tick.KIND: "_on_tick",  # §12
    ins.TaskCancel.KIND: "_on_task_signal",  # §13
    ins.TaskKill.KIND: "_on_task_signal",  # §13
    ins.Interrupt.KIND: "_on_interrupt",  # §14
    ins.Resume.KIND: "_on_resume",  # §14
    ins.Shutdown.KIND: "_on_shutdown",  # §15
    ins.DescriptionQuery.KIND: "_on_description_query",  # §16
    ins.IdDrawn.KIND: "_on_id_drawn",  # §17
    ins.Restart.KIND: "_on_restart",  # §21
}

#: Every phase change the machine can make.  A step that is not listed here keeps the phase.
TRANSITIONS: tuple[Edge, ...] = (
    Edge(_I, "begin", _W, "not shut down", "R3.1"),
    Edge(_W, "goal_started", _R, "NEXT", "R6.3, R6.4"),
    Edge(_W, "goal_started", _I, "FINISHED", "R11.1"),
    Edge(_W, "goal_submitted", _R, "NEXT", "R5.3, R6.3, R6.4"),
    Edge(_W, "goal_submitted", _I, "FINISHED", "R5.3, R11.1"),
    Edge(_W, "task_cancel", _I, "", "R13.3"),
    Edge(_W, "task_kill", _I, "", "R13.3"),
    Edge(_W, "shutdown", _I, "", "R15.2"),
    Edge(_R, "child_finished", _W, "task not cancelled", "R8.4"),
    Edge(_R, "child_finished", _I, "task cancelled or killed", "R13.4"),
    Edge(_R, "goal_started", _W, "CANCEL of a deferred child", "R9.4"),
    Edge(_R, "goal_submitted", _W, "CANCEL of a deferred child", "R5.3, R9.4"),
    Edge(_R, "cancel_requested", _W, "of a deferred child", "R10.4"),
    Edge(_R, "task_cancel", _I, "deferred child", "R13.3"),
    Edge(_R, "task_kill", _I, "deferred child", "R13.3"),
    Edge(_R, "shutdown", _I, "", "R15.2"),
    Edge(_R, "restart", _W, "task not cancelled", "R21.2"),
    Edge(_R, "restart", _I, "task cancelled or killed", "R21.2"),
)


def step(state: State, event: ins.Input, config: ServerConfig) -> Transition:
    """Apply one input to the state: the new state and the outputs, in order.

    Pure and total: the same state and input give the same transition (R19.6), and any well-typed
    input in any state yields one.  A
    value of another type than the three parameters name is refused with
    :class:`~dynevent.errors.WrongInput` (a ``TypeError``).
    """
    handler = _BY_CLASS.get(event.__class__)
    if handler is None or state.__class__ is not State or config.__class__ is not ServerConfig:
        handler = _checked(state, event, config)
    return handler(state, event, config)


def _checked(state: object, event: object, config: object) -> _Handler:
    """The handler of an input given as a subclass; :class:`WrongInput` for a value of a wrong type."""
    if not isinstance(state, State):
        raise WrongInput("step(state, ...)", "a dynevent.server.machine.State", state)
    if not isinstance(config, ServerConfig):
        raise WrongInput("step(..., config)", "a dynevent.server.machine.ServerConfig", config)
    for cls, handler in _BY_CLASS.items():
        if isinstance(event, cls):
            return handler
    raise WrongInput(
        "step(state, event, ...)",
        "a server input of dynevent.server.inputs (Begin, GoalRequested, ...)",
        event,
    )


def allowed_targets(source: DynamicState, kind: str) -> frozenset[DynamicState]:
    """The phases a step of input ``kind`` may lead to from ``source`` (the source itself included)."""
    return frozenset(
        {source} | {edge.target for edge in TRANSITIONS if edge.source is source and edge.input == kind}
    )


# ----------------------------------------------- the vocabulary the rules use


#: rmf_ros2's execution-failure strings by a short name (``"race"``, ``"idle_cancel"``, ...): the
#: values of :class:`~dynevent.wire.vocab.Failure`, kept for code written before it.
EXECUTION_FAILURES: Mapping[str, str] = {failure.name.lower(): failure.value for failure in Failure}

# The vocabulary the steps use most, as module constants: reading an enum member (and its value)
# costs several times reading a global.
_UNINITIALIZED_TYPE, _NEXT, _CANCEL, _FINISHED = (int(event_type) for event_type in EventType)
_INACTIVE, _WAITING, _RUNNING = (int(phase) for phase in DynamicState)
_UNINITIALIZED, _STANDBY, _UNDERWAY = Status.UNINITIALIZED.value, Status.STANDBY.value, Status.UNDERWAY.value
_QUEUED, _CANCELED, _COMPLETED = Status.QUEUED.value, Status.CANCELED.value, Status.COMPLETED.value
_SUCCEEDED, _ABORTED, _CANCELED_GOAL = GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.CANCELED
_STANDARD, _RMF_ROS2, _GOAL_IDS = Compatibility.STANDARD, Compatibility.RMF_ROS2, IdPolicy.GOAL
_PARSE_FAILURE = Failure.PARSE.value
#: "No description parsed yet" (a parsed description may be any JSON value, None included).
_UNCHECKED: Any = object()

# The rules of outputs that others read back (``dynevent check``): each named once, here.
#: A child's start (R6.4), and the report of a start deferred by an interruption (R6.3); a start's
#: feedback carries the warning of a clamped stubborn period (R12.2).
START_RULE = "R6.4"
DEFERRED_START_RULE = "R6.3"
#: The answers at a child's end: its NEXT goal's (R8.2) and the waiting CANCEL goals' (R8.3), whose
#: result carries the child's id and final status (R8.1).
CHILD_END_RULE = "R8.2"
WAITING_CANCEL_RULE = "R8.3"
CHILD_RESULT_RULE = "R8.1"
#: A FINISHED goal's answer, which names the dynamic event's own id (R11.1).
FINISHED_RULE = "R11.1"

# -------------------------------------------------------- §2 phase and status


def _time(now: int) -> Time:
    return _make_time(sec=now // SECOND, nanosec=now % SECOND)


def status_message(state: State, now: int) -> DynamicEventStatus:
    """The status message that describes ``state`` (R2.2)."""
    running = state.running
    child_id = None if running is None else running.child_id
    return status_of(state.seq, state.active, state.status, state.last_id, child_id, now)


def status_of(
    seq: int, active: bool, status: str, last_id: int, child_id: int | None, now: int
) -> DynamicEventStatus:
    """The status message (R2.2) of a server in run ``seq`` whose dynamic event is ``active`` with
    ``status``, highest id used ``last_id`` and running child ``child_id`` (``None`` when none runs),
    stamped ``now``: what :func:`status_message` gives for a :class:`State`, for any model of one."""
    if not active:
        phase, status, reported = _INACTIVE, _UNINITIALIZED, 0
    elif child_id is None:
        phase, reported = _WAITING, last_id
    else:
        phase, reported = _RUNNING, child_id
    return _make_status(
        dynamic_event_seq=seq, dynamic_state=phase, status=status, id=reported, time=_time(now)
    )


def _status_key(state: State) -> tuple[int, bool, bool, str, int]:
    return (
        state.seq,
        state.active,
        state.running is None,
        state.status if state.active else "",
        state.current_id,
    )


def _finish(before: State, after: State, outputs: list[outs.Output], now: int) -> Transition:
    """Close a step: append the status message when the status changed (R2.3), the state's own (R19.5)."""
    if _status_key(before) != _status_key(after):
        outputs.append(outs.PublishStatus(message=status_message(after, now), rule="R2.3"))
    return Transition(after, tuple(outputs))


#: The goal UUID of a running goal known only from a status message.
UNKNOWN_GOAL = "0" * 32


def state_from_status(
    message: DynamicEventStatus,
    fleet: str = "fleet",
    robot: str = "robot",
    *,
    last_id: int = 0,
    child_end: bool = True,
) -> State:
    """The server state a status message describes, as far as it can (R2.2, R20.2).

    INACTIVE gives an inactive state of that seq.  WAITING gives an active
    run whose highest id used is the message's id (R2.2); the dynamic event's
    own id is taken to be that id too, which holds until its first child.
    RUNNING gives a run whose running goal is unknown (:data:`UNKNOWN_GOAL`),
    with a child of the message's id, started unless the status is ``queued``
    (a start deferred by an interruption, R6.3).  A RUNNING status with a
    child's final status (:func:`child_ended`) gives a waiting run whose
    highest id is the message's (R20.2: the child has ended, status
    ``standby`` as after any child's end, R8.4), its dynamic event's own id
    unknown (0); ``child_end=False`` reads it as the child still running, as
    a judge that follows the goal to its answer does.  ``last_id``, when higher
    than the message's id, is the highest id the caller knows was used in the
    run (a client's own goals, say).  Raises ``ValueError`` for a
    ``dynamic_state`` that is none of 0, 1, 2.
    """
    base = State.new(fleet, robot)
    seq, phase = message.dynamic_event_seq, message.dynamic_state
    if phase == DynamicState.INACTIVE:
        return _replace_state(base, seq=seq, last_id=last_id)
    if phase == DynamicState.WAITING or (child_end and child_ended(message)):
        waiting = phase == DynamicState.WAITING
        return _replace_state(
            base,
            seq=seq,
            active=True,
            event_id=message.id if waiting else 0,
            description="{}",
            status=message.status if waiting else _STANDBY,
            last_id=max(message.id, last_id),
        )
    if phase == DynamicState.RUNNING:
        goal = Goal(dynamic_event_seq=seq, event_type=EventType.NEXT, id=message.id)
        running = RunningGoal(
            goal_uuid=UNKNOWN_GOAL,
            goal=goal,
            child_id=message.id,
            child_status=message.status,
            started=message.status != Status.QUEUED.value,
        )
        return _replace_state(
            base,
            seq=seq,
            active=True,
            description="{}",
            status=message.status,
            last_id=max(message.id, last_id),
            running=running,
            interrupted=not running.started,  # only an interruption defers a child's start (R6.3)
        )
    raise ValueError(f"dynamic_state {phase} is none of INACTIVE (0), WAITING (1), RUNNING (2)")


# ------------------------------------------------------------------- §3 begin


def next_seq(seq: int) -> int:
    """The seq of the run that begins after run ``seq`` (R3.1), wrapping from 2**32 - 1 to 0 (R3.2)."""
    return (seq + 1) & U32_MAX


def begin_description(description: str, config: ServerConfig) -> str:
    """The description a begin message carries for a run that begins with ``description`` (R3.3):
    as given, or re-serialised compact with its keys sorted in rmf_ros2 mode (R17.6).  The text is
    JSON (a :class:`~dynevent.server.inputs.Begin` checked it); anything else is kept as it is."""
    if config.compatibility is not _RMF_ROS2:
        return description
    try:
        return _json.dumps_sorted(_json.parse(description))
    except (_json.JsonProblem, ValueError):  # unreachable from a Begin; the machine cannot raise
        return description


def _on_begin(state: State, event: ins.Begin, config: ServerConfig) -> Transition:
    if state.shutdown:
        return _ignored("R18.1", state, event.KIND, "the server is shutting down")
    if state.active:
        return _ignored("R3.4", state, event.KIND, "a dynamic event is already active")
    outputs: list[outs.Output] = []
    seq = next_seq(state.seq)  # R3.1: the one step that changes the seq (R19.3)
    if seq == 0:
        outputs.append(outs.SeqWrapped(previous=state.seq, seq=seq, rule="R3.2"))
    description = begin_description(event.description, config)  # R3.3, R17.6
    after = _replace_state(
        state,
        seq=seq,
        active=True,
        event_id=event.event_id,
        description=description,
        status=Status.STANDBY.value,
        last_id=event.event_id,
        task_signal="",
        interrupted=event.interrupted,
    )
    outputs.append(
        outs.PublishBegin(
            message=DynamicEventDescription(
                fleet=state.fleet,
                robot=state.robot,
                dynamic_event_seq=seq,
                description=description,
                start_time=_time(event.now),
            ),
            rule="R3.3",
        )
    )
    return _finish(state, after, outputs, event.now)


# ----------------------------------------------------------- §4 goal requests


def _reject(rule: str, reason: RejectReason, text: str, failure: str = "", **values: Any) -> outs.Rejected:
    return outs.Rejected(reason=reason, text=text, execution_failure=failure, rule=rule, **values)


# The checks of R4, one function a rule, each ``(state, goal, config, found) -> Rejected | None``;
# ``found`` is a one-item list where R4.9 leaves the parsed description for R4.10 and the start.  A
# check that is one condition (R4.1, R4.2, R4.3, R4.6) has that condition written in REQUEST_CHECKS
# (``passes``), and its function here builds the refusal alone.
def _shutting_down(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected:
    return _reject("R4.1", RejectReason.SHUTTING_DOWN, "the server is shutting down", Failure.SHUTDOWN.value)


def _seq_mismatch(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected:
    return _reject(
        "R4.2",
        RejectReason.SEQ_MISMATCH,
        f"Expected {state.seq}, received {goal.dynamic_event_seq}",
        expected_seq=state.seq,
        received_seq=goal.dynamic_event_seq,
    )


def _inactive(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected:
    return _reject("R4.3", RejectReason.INACTIVE, "no dynamic event is active for this robot")


def _uninitialized_type(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    if goal.event_type != _UNINITIALIZED_TYPE:
        return None
    return _reject(
        "R4.4",
        RejectReason.UNINITIALIZED_EVENT_TYPE,
        "event_type is 0 (UNINITIALIZED): the goal was default-initialized",
        Failure.EVENT_TYPE.value,
    )


def _unknown_type(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected | None:
    if goal.event_type <= _FINISHED:
        return None
    return _reject(
        "R4.5",
        RejectReason.UNKNOWN_EVENT_TYPE,
        f"event_type {goal.event_type} is none of NEXT (1), CANCEL (2), FINISHED (3)",
        Failure.EVENT_TYPE.value,
    )


def _busy(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected:
    child_id = typing.cast(RunningGoal, state.running).child_id  # called only while a child runs
    return _reject(
        "R4.6",
        RejectReason.BUSY,
        f"event {child_id} is running: only a CANCEL with its id is accepted",
        current_id=child_id,
    )


def _unsupported_category(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    if goal.category in config.categories:
        return None
    supported = tuple(sorted(config.categories))
    problem = f"category {goal.category!r} is not supported; supported: {', '.join(supported) or 'none'}"
    return _reject("R4.7", RejectReason.UNSUPPORTED_CATEGORY, problem, categories=supported)


def _description_too_long(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    description, limit = goal.description, config.max_description_length
    # one byte a character needs no encoding (bench/machine_revisions.py: with the stale-id test then
    # inlined beside it, since given back so that _stale is its one source, it took an accepted NEXT's
    # accept from 1.15 to 1.12 times b54d329's)
    if len(description) <= limit and description.isascii():
        return None
    size = _json.utf8_size(description)
    if size <= limit:
        return None
    problem = f"description is {size} bytes, above the limit of {config.max_description_length}"
    return _reject(
        "R4.8",
        RejectReason.DESCRIPTION_INVALID,
        problem,
        f"{_PARSE_FAILURE}\n -- {problem}",
        errors=(problem,),
    )


def _description_not_json(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    try:
        found[0] = _json.parse(goal.description)
    except _json.JsonProblem as exc:
        return _reject(
            "R4.9",
            RejectReason.DESCRIPTION_NOT_JSON,
            f"the description of the {goal.category!r} event is {exc}",
            f"{_PARSE_FAILURE}\n -- {exc}",
            errors=(str(exc),),
        )
    return None


def _description_invalid(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    validator = config.categories[goal.category]  # R4.7 ran first
    try:
        errors = validator(goal.category, found[0])
        errors = () if type(errors) in (tuple, list) and not errors else listed_errors(errors)  # R4.19
    except Exception as exc:  # a faulty validator must not break the machine (R19.7)
        errors = (f"the validator raised {type(exc).__name__}: {exc}",)
    if not errors:
        return None
    return _reject(
        "R4.10",
        RejectReason.DESCRIPTION_INVALID,
        f"the description does not fit the {goal.category!r} category: " + "; ".join(errors),
        _PARSE_FAILURE + "".join(f"\n -- {error}" for error in errors),
        errors=errors,
    )


def _non_finite_stubborn(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    if math.isfinite(goal.stubborn_period):
        return None
    return _reject(
        "R4.11",
        RejectReason.NON_FINITE_STUBBORN_PERIOD,
        f"stubborn_period {goal.stubborn_period} is not a finite number",
    )


def _stale_id(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected | None:
    if not _stale(state, goal, config):
        return None
    if goal.id == 0:
        text = f"id 0 asks the server for the next id, and none is left above {state.last_id}"
    else:
        text = f"id {goal.id} is not greater than {state.last_id}, the highest id used in this run"
    return _reject("R4.12", RejectReason.STALE_ID, text, current_id=state.last_id, requested_id=goal.id)


def _stale(state: State, goal: Goal, config: ServerConfig) -> bool:
    """R4.12: under id policy ``goal`` a NEXT names a fresh id, or 0 while one is left to assign;
    under id policy ``adapter`` the server numbers children itself and nothing is stale (R17.3)."""
    if config.id_policy is not _GOAL_IDS:
        return False
    return fresh_id(state.last_id) is None if goal.id == 0 else goal.id <= state.last_id


def fresh_id(last_id: int) -> int | None:
    """The id above ``last_id``, the highest of a run (R4.12, R6.2): ``last_id + 1``, or ``None`` when
    ``last_id`` is 2**64 - 1 and no id is left.  What every client, judge and tool that names a
    NEXT's id asks (the client machine, ``explain``, the probe), so that none adds 1 itself."""
    return None if last_id >= U64_MAX else last_id + 1


def _cancel_idle(state: State, goal: Goal, config: ServerConfig, found: list[Any]) -> outs.Rejected | None:
    if state.running is not None:
        return None
    return _reject(
        "R4.13", RejectReason.CANCEL_IDLE, "no event is running to cancel", Failure.IDLE_CANCEL.value
    )


def _cancel_id_mismatch(
    state: State, goal: Goal, config: ServerConfig, found: list[Any]
) -> outs.Rejected | None:
    running = state.running
    if running is None or goal.id == running.child_id:  # R4.13 decides an idle CANCEL
        return None
    return _reject(
        "R4.14",
        RejectReason.CANCEL_ID_MISMATCH,
        f"the running event is {running.child_id}, the CANCEL names {goal.id}",
        Failure.CANCEL_ID.value,
        current_id=running.child_id,
        requested_id=goal.id,
    )


_ALL_TYPES = frozenset({_UNINITIALIZED_TYPE, _NEXT, _CANCEL, _FINISHED, _FINISHED + 1})  # 4: any above 3
_ONLY_NEXT = frozenset({_NEXT})
_ONLY_CANCEL = frozenset({_CANCEL})
_ONLY_UNINITIALIZED = frozenset({_UNINITIALIZED_TYPE})
_ABOVE_FINISHED = frozenset({_FINISHED + 1})


@attrs.frozen
class RequestCheck:
    """One check of R4, as :data:`REQUEST_CHECKS` lists them in the order :func:`accept` walks.

    ``event_types`` are the goal types it checks (4 stands for every type above FINISHED);
    ``standard_only`` marks a check that rmf_ros2 mode leaves out (R17.1); ``configured`` one whose
    verdict a server's configuration decides (its categories and their validators, its description
    limit), so that a judge who does not know the configuration cannot rule it out; ``goal_only`` one
    that reads the goal alone, so that no state of any server accepts a goal it refuses (R22.7).

    ``passes``, for a check that is one condition, is that condition: a Python expression of
    ``state``, ``goal`` and ``config`` under which the goal passes; ``check`` is then compiled from it
    and the refusal (:func:`_one_condition`), and the walks of :func:`accept` test it inline (the
    shortcuts for speed at the bottom of the module).
    """

    rule: str
    reason: RejectReason
    event_types: frozenset[int]
    check: Callable[[State, Goal, ServerConfig, list[Any]], outs.Rejected | None] = attrs.field(
        repr=False, eq=False
    )
    standard_only: bool = False
    configured: bool = False
    goal_only: bool = False
    passes: str = ""


def _one_condition(
    rule: str,
    reason: RejectReason,
    event_types: frozenset[int],
    passes: str,
    refusal: Callable[[State, Goal, ServerConfig, list[Any]], outs.Rejected],
) -> RequestCheck:
    """The check of ``rule`` that lets a goal pass when ``passes`` holds, and else gives ``refusal``'s."""
    source = "\n".join(
        [
            "def check(state, goal, config, found):",
            f"    if {passes}:",
            "        return None",
            "    return refusal(state, goal, config, found)",
        ]
    )
    namespace: dict[str, Any] = {**globals(), "refusal": refusal}
    exec(compile(source, f"<request check {rule}>", "exec"), namespace)
    return RequestCheck(rule, reason, event_types, namespace["check"], passes=passes)


#: The checks of R4, in the order :func:`accept` runs them: the first that refuses decides.
REQUEST_CHECKS: tuple[RequestCheck, ...] = (
    _one_condition("R4.1", RejectReason.SHUTTING_DOWN, _ALL_TYPES, "not state.shutdown", _shutting_down),
    _one_condition(
        "R4.2", RejectReason.SEQ_MISMATCH, _ALL_TYPES, "goal.dynamic_event_seq == state.seq", _seq_mismatch
    ),
    _one_condition("R4.3", RejectReason.INACTIVE, _ALL_TYPES, "state.active", _inactive),
    RequestCheck(
        "R4.4",
        RejectReason.UNINITIALIZED_EVENT_TYPE,
        _ONLY_UNINITIALIZED,
        _uninitialized_type,
        standard_only=True,
        goal_only=True,
    ),
    RequestCheck(
        "R4.5",
        RejectReason.UNKNOWN_EVENT_TYPE,
        _ABOVE_FINISHED,
        _unknown_type,
        standard_only=True,
        goal_only=True,
    ),
    # no NEXT while a goal holds the running slot (R19.2)
    _one_condition("R4.6", RejectReason.BUSY, _ALL_TYPES - _ONLY_CANCEL, "state.running is None", _busy),
    RequestCheck(
        "R4.7", RejectReason.UNSUPPORTED_CATEGORY, _ONLY_NEXT, _unsupported_category, configured=True
    ),
    RequestCheck(
        "R4.8",
        RejectReason.DESCRIPTION_INVALID,
        _ONLY_NEXT,
        _description_too_long,
        configured=True,
        goal_only=True,
    ),
    RequestCheck(
        "R4.9", RejectReason.DESCRIPTION_NOT_JSON, _ONLY_NEXT, _description_not_json, goal_only=True
    ),
    RequestCheck(
        "R4.10",
        RejectReason.DESCRIPTION_INVALID,
        _ONLY_NEXT,
        _description_invalid,
        configured=True,
        goal_only=True,
    ),
    RequestCheck(
        "R4.11", RejectReason.NON_FINITE_STUBBORN_PERIOD, _ONLY_NEXT, _non_finite_stubborn, goal_only=True
    ),
    RequestCheck("R4.12", RejectReason.STALE_ID, _ONLY_NEXT, _stale_id),
    RequestCheck("R4.13", RejectReason.CANCEL_IDLE, _ONLY_CANCEL, _cancel_idle, standard_only=True),
    RequestCheck(
        "R4.14", RejectReason.CANCEL_ID_MISMATCH, _ONLY_CANCEL, _cancel_id_mismatch, standard_only=True
    ),
)
#: The refusals no state of any server turns into an acceptance: the goal itself is at fault (R22.7).
REFUSED_IN_EVERY_STATE = frozenset(check.reason for check in REQUEST_CHECKS if check.goal_only)
#: The refusals a server's configuration decides (its categories, their validators, its limit).
CONFIGURED_REFUSALS = frozenset(check.reason for check in REQUEST_CHECKS if check.configured)
_CHECK_INDEX = {check.rule: index for index, check in enumerate(REQUEST_CHECKS)}
#: The description's checks, which a NEXT's start runs again (R6.1).
_DESCRIPTION_CHECKS = tuple(
    check.check for check in REQUEST_CHECKS if check.rule in ("R4.7", "R4.8", "R4.9", "R4.10")
)


def _walk(standard: bool, event_type: int) -> tuple[RequestCheck, ...]:
    """The checks :func:`accept` runs for a goal of ``event_type`` (4: any above FINISHED), in order;
    in rmf_ros2 mode without those R17.1 leaves out.  (:data:`_STANDARD_WALKS` and
    :data:`_RMF_ROS2_WALKS` run them, compiled.)"""
    return tuple(
        check
        for check in REQUEST_CHECKS
        if event_type in check.event_types and (standard or not check.standard_only)
    )


def _deferred(event_type: int) -> tuple[Callable[..., outs.Rejected | None], ...]:
    """The checks rmf_ros2 mode leaves out (R17.1) for a goal of ``event_type``."""
    return tuple(
        check.check for check in REQUEST_CHECKS if event_type in check.event_types and check.standard_only
    )


_DEFERRED = tuple(_deferred(event_type) for event_type in range(5))


def check_index(rule: str) -> int:
    """The place of the check ``rule`` (``"R4.9"``) in :data:`REQUEST_CHECKS`; ``len(REQUEST_CHECKS)``
    for a rule that is no request check (an acceptance, say)."""
    return _CHECK_INDEX.get(rule, len(REQUEST_CHECKS))


def could_refuse_first(reason: RejectReason, decision: outs.Decision, *, config_known: bool) -> bool:
    """Could a server have refused with ``reason`` where :func:`accept` gave ``decision``?

    Yes when it is the decision's own reason; and, for a judge who does not know the server's
    configuration, when a check that a configuration decides (:attr:`RequestCheck.configured`) can
    refuse with ``reason`` and runs before the decision's check.
    """
    if isinstance(decision, outs.Rejected) and decision.reason is reason:
        return True
    if config_known:
        return False
    limit = check_index(decision.rule)
    return any(check.reason is reason and check.configured for check in REQUEST_CHECKS[:limit])


def _check_description(state: State, goal: Goal, config: ServerConfig) -> tuple[Any, outs.Rejected | None]:
    """A NEXT's category and description checks (R4.7 to R4.10); its parsed description."""
    found: list[Any] = [None]
    for check in _DESCRIPTION_CHECKS:
        problem = check(state, goal, config, found)
        if problem is not None:
            return None, problem
    return found[0], None


def accept(state: State, goal: Goal, config: ServerConfig) -> outs.Decision:
    """Would the server accept ``goal`` now?  A pure query (R4).

    The checks of :data:`REQUEST_CHECKS` run in their order and the first that
    refuses decides.  Usable as it is in a ROS ``handle_goal`` callback.
    """
    if not isinstance(goal, Goal):
        raise WrongInput("accept(state, goal, ...)", "a dynevent.wire.messages.Goal", goal)
    return _decide(state, goal, config)[0]


def _decide(state: State, goal: Goal, config: ServerConfig) -> tuple[outs.Decision, Any]:
    """:func:`accept`'s decision, and a NEXT's parsed description when it is accepted (else None)."""
    event_type = goal.event_type
    kind = event_type if event_type <= _FINISHED else _FINISHED + 1
    found: list[Any] = [None]
    standard = config.compatibility is _STANDARD
    problem = (_STANDARD_WALKS if standard else _RMF_ROS2_WALKS)[kind](state, goal, config, found)
    if problem is not None:
        return problem, None
    if not standard:
        for check in _DEFERRED[kind]:
            if check(state, goal, config, found) is not None:  # a check R17.1 leaves out would refuse it
                return outs.Accepted(event_type=event_type, rule="R17.1"), None
    return _ACCEPTANCES[event_type], found[0]


# R4.16: a goal every check lets in is accepted.  An acceptance holds nothing of the goal but its type
# (NEXT, CANCEL or FINISHED: no other type passes every check), and it is frozen, so the machine hands
# out one shared decision a type: building one was a fifth of an accepted NEXT's accept
# (bench/machine_revisions.py: 1.12 to 0.84 times b54d329's).
_ACCEPTANCES = {kind: outs.Accepted(event_type=kind, rule="R4.16") for kind in (_NEXT, _CANCEL, _FINISHED)}


def _queued(state: State, uuid: str) -> QueuedGoal | None:
    """The accepted goal ``uuid`` waiting to start, or None."""
    for queued in state.queued:
        if queued.goal_uuid == uuid:
            return queued
    return None


def _known_goal(state: State, uuid: str) -> bool:
    running = state.running
    return (
        _queued(state, uuid) is not None
        or (running is not None and running.goal_uuid == uuid)
        or uuid in state.cancels
    )


def _on_goal_requested(state: State, event: ins.GoalRequested, config: ServerConfig) -> Transition:
    if _known_goal(state, event.goal_uuid):
        return _ignored("R18.2", state, event.KIND, "a goal with this uuid is already open")
    decision, parsed = _decide(state, event.goal, config)
    if isinstance(decision, outs.Rejected):
        rejected = outs.GoalRejected(goal_uuid=event.goal_uuid, rejection=decision, rule="R4.15")
        return Transition(state, (rejected,))
    checked = (config, parsed) if event.goal.event_type == _NEXT else None
    queued = (*state.queued, QueuedGoal(goal_uuid=event.goal_uuid, goal=event.goal, checked=checked))
    accepted = outs.GoalAccepted(goal_uuid=event.goal_uuid, rule="R4.16")
    return Transition(_copy_queued(state, queued), (accepted,))


# -------------------------------------------------------------- §5 goal start


def _result(failure: str, status: str, event_id: int) -> Result:
    return _make_result(execution_failure=failure, status=status, id=event_id)


def _failure(rule: str, goal_uuid: str, failure: Failure, detail: str = "") -> outs.AnswerGoal:
    """The goal is aborted with ``failure``, and a `` -- detail`` line after it when there is one."""
    text = f"{failure.value}\n -- {detail}" if detail else failure.value
    return outs.AnswerGoal(
        goal_uuid=goal_uuid, status=GoalStatus.ABORTED, result=_result(text, "", 0), rule=rule
    )


def _on_goal_submitted(state: State, event: ins.GoalSubmitted, config: ServerConfig) -> Transition:
    uuid = event.goal_uuid
    if _known_goal(state, uuid):
        return _ignored("R18.2", state, event.KIND, "a goal with this uuid is already open")
    decision, parsed = _decide(state, event.goal, config)
    if isinstance(decision, outs.Rejected):  # the transport accepted it; it lost a race since
        outputs = (
            outs.ExecuteGoal(goal_uuid=uuid, rule="R5.3"),
            _failure("R5.3", uuid, Failure.RACE, decision.text),
        )
        return Transition(state, outputs)
    checked = (config, parsed) if event.goal.event_type == _NEXT else None
    found = QueuedGoal(goal_uuid=uuid, goal=event.goal, checked=checked)
    return _start_goal(state, _replace_state(state, queued=(*state.queued, found)), found, event.now, config)


class RaceLoss(str, enum.Enum):
    """Why an accepted goal that starts lost the race (R5.2), the checks in the order :func:`race_loss`
    makes them."""

    SEQ = "seq"  # another run began
    ENDED = "ended"  # the dynamic event ended
    SLOT = "slot"  # another goal took the running slot
    ID = "id"  # (id policy ``goal``) another NEXT used its id


def race_loss(state: State, goal: Goal, config: ServerConfig) -> RaceLoss | None:
    """Why an accepted ``goal`` that starts in ``state`` lost the race; None if it did not (R5.2).

    The world may change between a goal's acceptance and its start: another
    run began, the dynamic event ended, another goal took the running slot, or
    (id policy ``goal``) another NEXT used its id.
    """
    if goal.dynamic_event_seq != state.seq:
        return RaceLoss.SEQ
    if not state.active:
        return RaceLoss.ENDED
    if state.running is not None and goal.event_type != _CANCEL:
        return RaceLoss.SLOT
    if goal.event_type == _NEXT and _stale(state, goal, config):
        return RaceLoss.ID
    return None


def race_lost(state: State, goal: Goal, config: ServerConfig) -> str:
    """How an accepted ``goal`` that starts in ``state`` lost the race, in words (:func:`race_loss`);
    ``""`` if it did not (R5.2)."""
    loss = race_loss(state, goal, config)
    if loss is RaceLoss.SEQ:
        return f"its seq {goal.dynamic_event_seq} is no longer the run's seq {state.seq}"
    if loss is RaceLoss.ENDED:
        return "no dynamic event is active any more"
    if loss is RaceLoss.SLOT:
        assert state.running is not None
        return f"event {state.running.child_id} holds the running slot"
    if loss is RaceLoss.ID:
        return f"its id {goal.id} is no longer above {state.last_id}, the highest id used"
    return ""


def _on_goal_started(state: State, event: ins.GoalStarted, config: ServerConfig) -> Transition:
    found = _queued(state, event.goal_uuid)
    if found is None:
        return _ignored("R18.3", state, event.KIND, "no accepted goal with this uuid is waiting to start")
    return _start_goal(state, state, found, event.now, config)


def _start_goal(before: State, state: State, found: QueuedGoal, now: int, config: ServerConfig) -> Transition:
    """Start the queued goal ``found`` (R5): ``before`` is the state the step began from."""
    uuid, goal = found.goal_uuid, found.goal
    rest = () if len(state.queued) == 1 else tuple(queued for queued in state.queued if queued is not found)
    outputs: list[outs.Output] = [outs.ExecuteGoal(goal_uuid=uuid, rule="R5.1")]
    if race_lost(state, goal, config):
        outputs.append(_failure("R5.2", uuid, Failure.RACE))
        return _finish(before, _replace_state(state, queued=rest), outputs, now)
    if goal.event_type == _NEXT:
        checked = found.checked  # kept only under this very configuration (R6.1)
        parsed = (
            checked[1]
            if type(checked) is tuple and len(checked) == 2 and checked[0] is config
            else _UNCHECKED
        )
        started = _start_next(state, rest, uuid, goal, config, outputs, now, parsed)
        if started is not None:  # a goal holds the slot where none did (R5.2): the status changed (R2.3)
            outputs.append(outs.PublishStatus(message=status_message(started, now), rule="R2.3"))
            return Transition(started, tuple(outputs))
        return _finish(before, _replace_state(state, queued=rest), outputs, now)
    state = _replace_state(state, queued=rest)
    if goal.event_type == _CANCEL:
        state = _start_cancel(state, uuid, goal, outputs, now)
    elif goal.event_type == EventType.FINISHED:
        state = _end_stubbornness(state, outputs)
        result = _result("", _COMPLETED, state.event_id)
        outputs.append(outs.AnswerGoal(goal_uuid=uuid, status=_SUCCEEDED, result=result, rule=FINISHED_RULE))
        state = _end_dynamic_event(state, _COMPLETED, outputs)
    else:  # only reachable in rmf_ros2 compatibility
        outputs.append(_failure("R17.2", uuid, Failure.EVENT_TYPE))
    return _finish(before, state, outputs, now)


# -------------------------------------------------------------------- §6 NEXT


def next_child_id(goal: Goal, last_id: int, config: ServerConfig) -> int:
    """The id of the child a NEXT ``goal`` starts in a run whose highest id is ``last_id`` (R6.2): the
    goal's own id, unless it is 0 or the adapter numbers children (id policy ``adapter``), then
    :func:`fresh_id`, modulo 2**64 (under id policy ``goal`` R4.12 refuses id 0 when none is left;
    the adapter's counter wraps to 0)."""
    if config.id_policy is _GOAL_IDS and goal.id != 0:
        return goal.id
    fresh = fresh_id(last_id)
    return 0 if fresh is None else fresh


def _start_next(
    state: State,
    queued: tuple[QueuedGoal, ...],
    uuid: str,
    goal: Goal,
    config: ServerConfig,
    outputs: list[outs.Output],
    now: int,
    parsed: Any = _UNCHECKED,
) -> State | None:
    """Start a NEXT goal (R6): the new state, with ``queued`` the goals left waiting; None when
    its description fails the check again (R6.1) and the goal is aborted.

    ``parsed`` is the description as the goal's acceptance parsed it, under this configuration;
    :data:`_UNCHECKED` has it checked again.
    """
    if parsed is _UNCHECKED:
        parsed, problem = _check_description(state, goal, config)
        if problem is not None:  # rmf_ros2 has no string for R4.7: it never re-checks the category
            failure = problem.execution_failure or f"{_PARSE_FAILURE}\n -- {problem.text}"
            outputs.append(
                outs.AnswerGoal(goal_uuid=uuid, status=_ABORTED, result=_result(failure, "", 0), rule="R6.1")
            )
            return None
    child_id = next_child_id(goal, state.last_id, config)
    logs: tuple[LogEntry, ...] = ()
    log_seq = state.log_seq
    period = goal.stubborn_period
    if 0.0 < period < config.stubborn_minimum:
        outputs.append(outs.StubbornClamped(requested=period, applied=config.stubborn_minimum, rule="R12.2"))
        text = (
            f"stubborn_period {period:g} s is below the minimum of {config.stubborn_minimum:g} s; "
            f"{config.stubborn_minimum:g} s will be used"
        )
        entry = _log_entry(log_seq, text, "warning", now)
        log_seq = next_log_seq(log_seq)  # R7.3
        outputs.append(outs.Log(entry=entry, rule="R12.2"))
        logs = (entry,)
    if state.interrupted:  # the child's start is deferred
        running = RunningGoal(
            goal_uuid=uuid, goal=goal, child_id=child_id, child_status=_QUEUED, started=False
        )
        outputs.append(
            outs.PublishFeedback(
                goal_uuid=uuid,
                feedback=_make_feedback(status=_QUEUED, id=child_id, logs=logs),
                rule=DEFERRED_START_RULE,
            )
        )
        return _replace_state(
            state, queued=queued, last_id=child_id, running=running, status=_QUEUED, log_seq=log_seq
        )
    running = RunningGoal(goal_uuid=uuid, goal=goal, child_id=child_id, child_status=_UNDERWAY, started=True)
    running = _start_child(START_RULE, state, running, outputs, logs, parsed)
    return _copy_at_start(state, queued, child_id, running, _UNDERWAY, None, log_seq)


def _start_child(
    rule: str,
    state: State,
    running: RunningGoal,
    outputs: list[outs.Output],
    logs: tuple[LogEntry, ...],
    parsed: Any = _UNCHECKED,
) -> RunningGoal:
    """Start the running goal's child (R6.4): its outputs, and the goal as started.

    The caller's new state holds the returned goal, status ``underway`` and no stubbornness (R12.5).
    ``parsed`` is the description as R4.9 or R6.1 parsed it; a deferred start (R14.5) parses it again.
    """
    if state.stubborn is not None:  # R12.5
        outputs.append(outs.StubbornEnd(rule="R12.5"))
    goal = running.goal
    if parsed is _UNCHECKED:
        try:
            parsed = _json.parse(goal.description)
        except _json.JsonProblem:  # unreachable after R6.1; kept so the machine cannot raise
            parsed = None
    child_id = running.child_id
    outputs.append(
        outs.StartChild(
            category=goal.category, description=goal.description, id=child_id, parsed=parsed, rule=rule
        )
    )
    if not running.started or running.child_status != _UNDERWAY:
        running = _replace_running(running, started=True, child_status=_UNDERWAY)
    feedback = _make_feedback(status=_UNDERWAY, id=child_id, logs=logs)
    outputs.append(outs.PublishFeedback(goal_uuid=running.goal_uuid, feedback=feedback, rule=rule))
    return running


# ------------------------------------------------- §7 child progress and logs


def next_log_seq(seq: int) -> int:
    """The log seq after ``seq``: one up, modulo 2**32 (R7.3)."""
    return (seq + 1) & U32_MAX


def log_seq_fault(last: int | None, seq: int, *, same_child: bool) -> str:
    """What is wrong with an entry numbered ``seq`` after the robot's entry ``last`` (None: none seen),
    as R7.3 reads wherever entries are seen: ``"repeats"``, ``"backwards"``, ``"skips"`` or ``""``.

    Every entry takes the next log seq, and the feedback carries every entry made while a started
    child runs: an entry after one of the same started child (``same_child``; every entry, to a
    reader of the machine's ``Log`` outputs) takes the seq one up.  After any other (another child's,
    or one made while no child ran) it comes after it in uint32 serial order, maybe more than one up:
    entries made while no child runs, a task signal's (R13.1), are on no feedback.
    """
    if last is None or seq == next_log_seq(last):
        return ""
    if seq == last:
        return "repeats"
    if not seq_after(seq, last):
        return "backwards"
    return "skips" if same_child else ""


def _log_entry(seq: int, text: str, tier: str, now: int) -> LogEntry:
    """The log entry numbered ``seq`` (the robot's next LogEntry.seq, which wraps at 2**32, R7.3)."""
    return _make_log_entry(seq=seq, tier=tier, unix_millis_time=now // 1_000_000, text=text)


def _on_child_progress(state: State, event: ins.ChildProgress, config: ServerConfig) -> Transition:
    running = state.running
    if running is None or not running.started:
        return _ignored("R18.4", state, event.KIND, "no child event is running")
    outputs: list[outs.Output] = []
    logs: tuple[LogEntry, ...] = ()
    log_seq = state.log_seq
    text = event.log_text
    if text is not None:  # the log_seq wraps (R7.3)
        entry = _make_log_entry(
            seq=log_seq, tier=event.tier, unix_millis_time=event.now // 1_000_000, text=text
        )
        log_seq = next_log_seq(log_seq)
        outputs.append(outs.Log(entry=entry, rule="R7.2"))
        logs = (entry,)
    status = event.status
    outputs.append(
        outs.PublishFeedback(
            goal_uuid=running.goal_uuid,
            feedback=_make_feedback(status=status, id=running.child_id, logs=logs),
            rule="R7.1",
        )
    )
    if running.child_status != status:
        running = _replace_running(running, child_status=status)
    after = _copy_at_progress(state, running, state.status if state.task_signal else status, log_seq)  # R7.4
    if config.compatibility is _RMF_ROS2:  # every report, the child's own status
        wire = _running_status(after, status, running.child_id, event.now)
        outputs.append(outs.PublishStatus(message=wire, rule="R17.5"))
    elif after.status != state.status:  # the run, the slot and the id are as they were (R2.3)
        outputs.append(outs.PublishStatus(message=status_message(after, event.now), rule="R2.3"))
    return Transition(after, tuple(outputs))


# --------------------------------------------------------------- §8 child end


# Child statuses that end a child early: its goal is not answered as succeeded (R8.2).
_EARLY_END = frozenset({Status.CANCELED.value, Status.KILLED.value, Status.SKIPPED.value})


def ends_a_child(status: str) -> bool:
    """Whether a child reporting ``status`` has ended: a final status (R8.1)."""
    return status in ENDED_CHILD_STATUSES


def ends_early(status: str) -> bool:
    """Whether a child ending with ``status`` ended early, and its goal is not answered succeeded (R8.2)."""
    return status in _EARLY_END


def _answers_at_child_end(
    state: State,
    running: RunningGoal,
    final: str,
    rule: str = CHILD_END_RULE,
    cancels_rule: str = WAITING_CANCEL_RULE,
) -> list[outs.Output]:
    """The running goal's and every waiting CANCEL goal's answers when the child ends (R8.2, R8.3).

    ``rule`` and ``cancels_rule`` name the rules that end it, when not a child's end (R9.4, R10.4, R13.3).
    """
    result = _result("", final, running.child_id)
    status = _SUCCEEDED
    if final in _EARLY_END:
        status = _CANCELED_GOAL if running.cancel_requested else _ABORTED
    answers: list[outs.Output] = [
        outs.AnswerGoal(goal_uuid=running.goal_uuid, status=status, result=result, rule=rule)
    ]
    for uuid in state.cancels:
        answers.append(outs.AnswerGoal(goal_uuid=uuid, status=_SUCCEEDED, result=result, rule=cancels_rule))
    return answers


def _on_child_finished(state: State, event: ins.ChildFinished, config: ServerConfig) -> Transition:
    running = state.running
    if running is None or not running.started:
        return _ignored("R18.4", state, event.KIND, "no child event is running")
    outputs: list[outs.Output] = []
    if config.compatibility is _RMF_ROS2:  # the child's end as feedback first (R17.7)
        feedback = _make_feedback(status=event.status, id=running.child_id, logs=())
        outputs.append(outs.PublishFeedback(goal_uuid=running.goal_uuid, feedback=feedback, rule="R17.7"))
    outputs += _answers_at_child_end(state, running, event.status)
    if state.task_signal:  # the dynamic event ends with the signal (R13.4)
        after = _replace_state(state, running=None, cancels=())
        after = _end_dynamic_event(after, state.task_signal, outputs, task_over=True)
        return _finish(state, after, outputs, event.now)
    stubborn = None
    period = running.goal.stubborn_period
    if period > 0.0:
        applied = max(period, config.stubborn_minimum)  # never below the minimum (R19.4)
        anchor = state.position
        outputs.append(
            outs.StubbornBegin(
                period=applied,
                since=event.now,
                map_name=None if anchor is None else anchor.map_name,
                x=0.0 if anchor is None else anchor.x,
                y=0.0 if anchor is None else anchor.y,
                rule="R12.1",
            )
        )
        stubborn = Stubbornness(
            period=applied,
            hold_since=event.now,
            next_refresh=event.now + _seconds(config.stubborn_refresh),
            anchor=anchor,
        )
    after = _copy_at_child_end(state, None, (), _STANDBY, stubborn)  # R8.4
    if config.compatibility is _RMF_ROS2:  # published while the slot is still held (R17.4)...
        # ...unless a CANCEL goal ended the child: it freed the slot first (WAITING, D28)
        phase = _WAITING if state.cancels else _RUNNING
        stale = _running_status(after, event.status, running.child_id, event.now, phase)
        outputs.append(outs.PublishStatus(message=stale, rule="R17.4"))
        return Transition(after, tuple(outputs))
    # the slot is free where a goal held it: the status changed (R2.3)
    outputs.append(outs.PublishStatus(message=status_message(after, event.now), rule="R2.3"))
    return Transition(after, tuple(outputs))


# ------------------------------------------------------------------ §9 CANCEL


def _start_cancel(state: State, uuid: str, goal: Goal, outputs: list[outs.Output], now: int) -> State:
    running = state.running
    if running is None:
        outputs.append(_failure("R9.1", uuid, Failure.IDLE_CANCEL))
        return state
    if goal.id != running.child_id:
        outputs.append(_failure("R9.2", uuid, Failure.CANCEL_ID))
        return state
    if not running.started:  # the child never started; it is cancelled at once
        state = _replace_state(state, cancels=(*state.cancels, uuid))
        outputs.extend(_answers_at_child_end(state, running, Status.CANCELED.value, "R9.4", "R9.4"))
        return _replace_state(state, running=None, cancels=(), status=Status.STANDBY.value)
    if not running.canceling:
        outputs.append(outs.CancelChild(id=running.child_id, rule="R9.3"))
        running = _replace_running(running, canceling=True)
    return _replace_state(state, running=running, cancels=(*state.cancels, uuid))


# ---------------------------------------------------- §10 action-level cancel


def _on_cancel_requested(state: State, event: ins.CancelRequested, config: ServerConfig) -> Transition:
    uuid = event.goal_uuid
    not_running = _result(Failure.NOT_RUNNING.value, "", 0)
    if any(queued.goal_uuid == uuid for queued in state.queued):
        after = _replace_state(
            state, queued=tuple(queued for queued in state.queued if queued.goal_uuid != uuid)
        )
        answer = outs.AnswerGoal(goal_uuid=uuid, status=GoalStatus.CANCELED, result=not_running, rule="R10.1")
        return Transition(after, (outs.CancelResponse(goal_uuid=uuid, accepted=True, rule="R10.1"), answer))
    if uuid in state.cancels:
        after = _replace_state(state, cancels=tuple(other for other in state.cancels if other != uuid))
        answer = outs.AnswerGoal(goal_uuid=uuid, status=GoalStatus.CANCELED, result=not_running, rule="R10.2")
        return Transition(after, (outs.CancelResponse(goal_uuid=uuid, accepted=True, rule="R10.2"), answer))
    running = state.running
    if running is None or running.goal_uuid != uuid:
        return Transition(state, (outs.CancelResponse(goal_uuid=uuid, accepted=False, rule="R10.5"),))
    running = _replace_running(running, cancel_requested=True)
    if not running.started:
        outputs: list[outs.Output] = [outs.CancelResponse(goal_uuid=uuid, accepted=True, rule="R10.4")]
        outputs.extend(_answers_at_child_end(state, running, Status.CANCELED.value, "R10.4", "R10.4"))
        after = _replace_state(state, running=None, cancels=(), status=Status.STANDBY.value)
        return _finish(state, after, outputs, event.now)
    outputs = [outs.CancelResponse(goal_uuid=uuid, accepted=True, rule="R10.3")]
    if not running.canceling:
        outputs.append(outs.CancelChild(id=running.child_id, rule="R10.3"))
        running = _replace_running(running, canceling=True)
    return Transition(_replace_state(state, running=running), tuple(outputs))


# ------------------------------------------ §11 FINISHED and the end of a run


def _end_dynamic_event(
    state: State, final: str, outputs: list[outs.Output], task_over: bool = False
) -> State:
    """The dynamic event is over (R11.2, R13.4): the task may move on.

    When a task signal ends it, the task itself is over and its interruption with it (R13.6).
    """
    outputs.append(outs.DynamicEventFinished(status=final, rule="R11.2"))
    interrupted = False if task_over else state.interrupted
    return _replace_state(
        state, active=False, status=final, running=None, cancels=(), interrupted=interrupted
    )


# ----------------------------------------------------------- §12 stubbornness


def _seconds(value: float) -> int:
    return round(value * SECOND)


def _end_stubbornness(state: State, outputs: list[outs.Output], rule: str = "R12.5") -> State:
    """End an active stubbornness (R12.5; a restart's own rule is R21.2)."""
    if state.stubborn is None:
        return state
    outputs.append(outs.StubbornEnd(rule=rule))
    return _replace_state(state, stubborn=None)


def _on_tick(state: State, event: ins.Tick, config: ServerConfig) -> Transition:
    position = Position(map_name=event.map_name, x=event.x, y=event.y)
    stubborn = state.stubborn
    if stubborn is None or event.now < stubborn.next_refresh:  # no refresh is due (R12.3)
        return Transition(_replace_state(state, position=position), ())
    refresh = _seconds(config.stubborn_refresh)
    missed = (event.now - stubborn.next_refresh) // refresh + 1
    next_refresh = stubborn.next_refresh + missed * refresh
    anchor = stubborn.anchor
    moved = (
        anchor is None
        or anchor.map_name != position.map_name
        or math.hypot(position.x - anchor.x, position.y - anchor.y) > config.stubborn_move_threshold
    )
    output: outs.Output
    if moved:
        output = outs.StubbornHold(
            period=stubborn.period,
            since=event.now,
            map_name=position.map_name,
            x=position.x,
            y=position.y,
            rule="R12.4",
        )
        stubborn = Stubbornness(
            period=stubborn.period, hold_since=event.now, next_refresh=next_refresh, anchor=position
        )
    else:
        output = outs.StubbornDelay(delay=(event.now - stubborn.hold_since) / SECOND, rule="R12.4")
        stubborn = _replace_stubborn(stubborn, next_refresh=next_refresh)
    return Transition(_replace_state(state, position=position, stubborn=stubborn), (output,))


# --------------------------------------------------- §13 task cancel and kill


def _on_task_signal(state: State, event: ins.TaskCancel | ins.TaskKill, config: ServerConfig) -> Transition:
    kill = isinstance(event, ins.TaskKill)
    signal = Status.KILLED.value if kill else Status.CANCELED.value
    if not state.active:
        return _ignored("R18.5", state, event.KIND, "no dynamic event is active")
    if state.task_signal in (Status.KILLED.value, signal):  # a kill after a cancel escalates (R13.5)
        return _ignored("R18.7", state, event.KIND, f"the task was already {state.task_signal}")
    outputs: list[outs.Output] = []
    entry = _log_entry(state.log_seq, TASK_SIGNAL_LOGS[signal], "info", event.now)
    outputs.append(outs.Log(entry=entry, rule="R13.1"))
    after = _replace_state(state, task_signal=signal, status=signal, log_seq=next_log_seq(state.log_seq))
    running = after.running
    if running is not None and running.started:
        outputs.append(
            outs.PublishFeedback(
                goal_uuid=running.goal_uuid,
                feedback=_make_feedback(status=running.child_status, id=running.child_id, logs=(entry,)),
                rule="R13.1",
            )
        )
    after = _end_stubbornness(after, outputs)
    if running is not None and running.started:
        if kill:
            outputs.append(outs.KillChild(id=running.child_id, rule="R13.2"))
        elif not running.canceling:
            outputs.append(outs.CancelChild(id=running.child_id, rule="R13.2"))
        after = _replace_state(after, running=_replace_running(running, canceling=True))
        return _finish(state, after, outputs, event.now)
    if running is not None:  # a deferred child ends before it starts
        outputs.extend(_answers_at_child_end(after, running, signal, "R13.3", "R13.3"))
    after = _end_dynamic_event(after, signal, outputs, task_over=True)
    return _finish(state, after, outputs, event.now)


# ----------------------------------------------------------- §14 interruption


def _on_interrupt(state: State, event: ins.Interrupt, config: ServerConfig) -> Transition:
    if not state.active:
        return _ignored("R18.5", state, event.KIND, "no dynamic event is active")
    if state.interrupted:
        return _ignored("R18.6", state, event.KIND, "the task is already interrupted")
    after = _replace_state(state, interrupted=True)
    running = state.running
    if running is not None and running.started:
        return Transition(after, (outs.InterruptChild(id=running.child_id, rule="R14.1"),))
    return Transition(after, (outs.InterruptConfirmed(rule="R14.2"),))


def _on_resume(state: State, event: ins.Resume, config: ServerConfig) -> Transition:
    if not state.interrupted:
        return _ignored("R18.6", state, event.KIND, "the task is not interrupted")
    after = _replace_state(state, interrupted=False)  # R14.3
    running = state.running
    if running is None or not after.active:
        return Transition(after, ())
    if running.started:
        return Transition(after, (outs.ResumeChild(id=running.child_id, rule="R14.4"),))
    outputs: list[outs.Output] = []
    running = _start_child("R14.5", after, running, outputs, ())
    after = _replace_state(after, running=running, status=_UNDERWAY, stubborn=None)
    return _finish(state, after, outputs, event.now)


# --------------------------------------------------------------- §15 shutdown


def _abort_open_goals(rule: str, state: State, failure: Failure) -> list[outs.Output]:
    """Every goal the state holds open, aborted: the running goal, the waiting CANCELs, the queued goals."""
    outputs: list[outs.Output] = []
    if state.running is not None:
        outputs.append(_failure(rule, state.running.goal_uuid, failure))
    outputs.extend(_failure(rule, uuid, failure) for uuid in state.cancels)
    for queued in state.queued:
        outputs.append(outs.ExecuteGoal(goal_uuid=queued.goal_uuid, rule=rule))
        outputs.append(_failure(rule, queued.goal_uuid, failure))
    return outputs


def _on_shutdown(state: State, event: ins.Shutdown, config: ServerConfig) -> Transition:
    if state.shutdown:
        return _ignored("R18.1", state, event.KIND, "the server is already shutting down")
    outputs = _abort_open_goals("R15.1", state, Failure.SHUTDOWN)
    after = _end_stubbornness(state, outputs)
    after = _replace_state(after, shutdown=True, active=False, running=None, queued=(), cancels=())
    return _finish(state, after, outputs, event.now)


# ------------------------------------------------------ §16 description query


def _on_description_query(state: State, event: ins.DescriptionQuery, config: ServerConfig) -> Transition:
    if not state.active:
        return Transition(state, (outs.DescriptionAnswer(response=DescriptionResponse(), rule="R16.1"),))
    response = DescriptionResponse(
        running=True, status=state.status, description=state.description, id=state.current_id
    )
    return Transition(state, (outs.DescriptionAnswer(response=response, rule="R16.2"),))


# ------------------------------------------------- §17 rmf_ros2 compatibility


def _running_status(
    state: State, status: str, child_id: int, now: int, dynamic_state: int = _RUNNING
) -> DynamicEventStatus:
    """A status message naming a child, RUNNING unless told otherwise, whatever the state (rmf_ros2
    mode, R17.4, R17.5)."""
    return _make_status(
        dynamic_event_seq=state.seq,
        dynamic_state=dynamic_state,
        status=status,
        id=child_id,
        time=_time(now),
    )


def _on_id_drawn(state: State, event: ins.IdDrawn, config: ServerConfig) -> Transition:
    """The adapter's counter moved on (R17.8): the next child's id is above the id drawn."""
    if config.id_policy is _GOAL_IDS:
        return _ignored("R18.8", state, event.KIND, "the NEXT goals name the children (id policy goal)")
    if not state.active:
        return _ignored("R18.8", state, event.KIND, "no dynamic event is active")
    fresh = fresh_id(state.last_id)  # the adapter's counter wraps to 0, as next_child_id does
    after = _replace_state(state, last_id=0 if fresh is None else fresh)
    return _finish(state, after, [], event.now)


# -------------------------------------------------- §18 inputs without effect


def _ignored(rule: str, state: State, kind: str, why: str) -> Transition:
    return Transition(state, (outs.Ignored(input=kind, why=why, rule=rule),))


# --------------------------------------------- §20 clients that keep no state


def child_ended(message: DynamicEventStatus) -> bool:
    """R20.2: a RUNNING status carrying a child's final status (:data:`ENDED_CHILD_STATUSES`) names
    a child that has ended (or is about to, R7.4): a client takes the robot as waiting."""
    return message.dynamic_state == _RUNNING and message.status in ENDED_CHILD_STATUSES


def runs_a_child(message: DynamicEventStatus) -> bool:
    """A status that shows a child running: RUNNING, and not a child's final status (R2.2, R20.2)."""
    return message.dynamic_state == _RUNNING and message.status not in ENDED_CHILD_STATUSES


def robot_waits(message: DynamicEventStatus) -> bool:
    """A status that shows the robot waiting for its next goal: WAITING, or a child's end (R20.2)."""
    return message.dynamic_state == _WAITING or child_ended(message)


# ---------------------------------------------------------------- §21 restart


def _on_restart(state: State, event: ins.Restart, config: ServerConfig) -> Transition:
    outputs = _abort_open_goals("R21.1", state, Failure.RESTART)  # the goals of the process that ended
    running = state.running
    after = _end_stubbornness(state, outputs, "R21.2")  # the hold was the ended process's
    after = _replace_state(after, running=None, queued=(), cancels=(), shutdown=False)
    if state.active and running is not None:  # R21.2: the child ended with the process
        if state.task_signal:
            after = _end_dynamic_event(after, state.task_signal, outputs, task_over=True)
        else:
            after = _replace_state(after, status=Status.STANDBY.value)
    outputs.append(outs.PublishStatus(message=status_message(after, event.now), rule="R21.3"))  # always
    return Transition(after, tuple(outputs))


# --------------------------------------------- the table's handlers, resolved


#: Input kind -> its handler: :data:`_HANDLER_NAMES` resolved (a name that is no function fails here).
HANDLERS: Mapping[str, _Handler] = {kind: globals()[name] for kind, name in _HANDLER_NAMES.items()}
#: Input class -> its handler (the lookup :func:`step` makes; a class, not a kind, so that another
#: machine's input of the same kind, the client's ``Tick``, is refused rather than taken).
_BY_CLASS: dict[type, _Handler] = {cls: HANDLERS[cls.KIND] for cls in typing.get_args(ins.Input)}

# -------------------------------------------------------- shortcuts for speed
#
# Nothing below states a rule: each shortcut is derived from the types and tables above, and the
# benchmark named beside it shows what it saves.

# Messages built from checked state skip their converters; copies skip __init__ (attrs.evolve re-runs
# it).  bench/run.py's rows in docs/performance.md ("Changes made, measured") show what each gave.
_make_status = maker(DynamicEventStatus)
_make_feedback = maker(Feedback)
_make_log_entry = maker(LogEntry)
_make_result = maker(Result)
_make_time = maker(Time)
_replace_state = replacer(State)
# the copies of the most frequent steps, each taking the fields it changes positionally
_copy_queued = copier(State, "queued")
_copy_at_start = copier(State, "queued", "last_id", "running", "status", "stubborn", "log_seq")
_copy_at_progress = copier(State, "running", "status", "log_seq")
_copy_at_child_end = copier(State, "running", "cancels", "status", "stubborn")
_replace_running = replacer(RunningGoal)
_replace_stubborn = replacer(Stubbornness)

_Walk: TypeAlias = Callable[[State, Goal, ServerConfig, list[Any]], outs.Rejected | None]


def _compiled_walk(checks: tuple[RequestCheck, ...], name: str) -> _Walk:
    """One function that runs ``checks`` in their order and gives the first refusal, or None.

    A check that is one condition (:attr:`RequestCheck.passes`) is tested inline and called only to
    refuse; any other is called.  Justified by bench/machine_revisions.py: calling the four checks of
    one condition and looping over the rest were a fifth of an accepted NEXT's accept, and compiled
    it takes 0.91 times the time of the loop that started past those four (docs/performance.md).
    """
    namespace: dict[str, Any] = dict(globals())
    lines = ["def walk(state, goal, config, found):"]
    for index, check in enumerate(checks):
        namespace[f"_check_{index}"] = check.check
        lines.append(f"    # {check.rule}")
        if check.passes:
            lines += [
                f"    if not ({check.passes}):",
                f"        return _check_{index}(state, goal, config, found)",
            ]
        else:
            lines += [
                f"    problem = _check_{index}(state, goal, config, found)",
                "    if problem is not None:",
                "        return problem",
            ]
    lines.append("    return None")
    exec(compile("\n".join(lines), f"<request checks: {name}>", "exec"), namespace)
    walk: _Walk = namespace["walk"]
    return walk


# What accept walks, by event type (index 4: any above FINISHED): :func:`_walk`'s checks, compiled.
_STANDARD_WALKS = tuple(_compiled_walk(_walk(True, kind), f"standard, type {kind}") for kind in range(5))
_RMF_ROS2_WALKS = tuple(_compiled_walk(_walk(False, kind), f"rmf_ros2, type {kind}") for kind in range(5))
