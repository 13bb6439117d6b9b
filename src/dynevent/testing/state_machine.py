"""The kit's hypothesis state machine (:class:`ServerStateMachine`): rules that generate well-typed
inputs from the observed state, deep runs and hostile goals alike, checked by the model after every
step; :func:`server_state_machine` binds it to an implementation.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, ClassVar

import attrs
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from dynevent.conformance.records import config_from_json
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig
from dynevent.testing.inputs import (
    BEGIN_DESCRIPTIONS,
    DESCRIPTIONS,
    NON_FINITE,
    NOT_JSON,
    STATUSES,
    STUBBORN_PERIODS,
)
from dynevent.testing.model import Observer, ProtocolViolation
from dynevent.testing.servers import ServerUnderTest
from dynevent.testing.strategies import messages
from dynevent.wire import _json
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import (
    EventType,
    IdPolicy,
    Status,
    Tier,
    Violation,
)

__all__ = ["DEFAULT_CONFIG", "ServerStateMachine", "server_state_machine"]


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


def _valid_descriptions(config: ServerConfig, category: str) -> list[str]:
    """The kit's descriptions that ``config`` accepts for ``category`` (all of them for an unknown one)."""
    validator = config.categories.get(category)
    if validator is None:
        return list(DESCRIPTIONS)
    limit = config.max_description_length
    return [text for text in DESCRIPTIONS if len(text) <= limit and _fits(validator, category, text)]


def _next_goal(config: ServerConfig, categories: Sequence[str], model: Observer, data: st.DataObject) -> Goal:
    """A NEXT goal the server must accept in the modelled state (unless it races)."""
    category = data.draw(st.sampled_from(categories or ("none",)), label="category")
    valid = _valid_descriptions(config, category) or list(DESCRIPTIONS)
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
        stubborn_period=data.draw(st.sampled_from(STUBBORN_PERIODS), label="stubborn_period"),
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
        goal = attrs.evolve(goal, description=data.draw(st.sampled_from(NOT_JSON), label="text"))
    elif fault == "invalid":
        valid = set(_valid_descriptions(config, goal.category))
        invalid = [text for text in DESCRIPTIONS if text not in valid]
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
        goal = attrs.evolve(goal, stubborn_period=data.draw(st.sampled_from(NON_FINITE), label="period"))
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
        description = data.draw(st.sampled_from(BEGIN_DESCRIPTIONS), label="description")
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
        status=st.sampled_from(STATUSES),
        text=st.one_of(st.none(), st.sampled_from(("moving", "", "door closed", "\u00e9t\u00e9 \U0001f916"))),
        tier=st.sampled_from(tuple(Tier)),
    )
    def child_progress(self, status: str, text: str | None, tier: Tier) -> None:
        """The running child reports a status, maybe with a log line."""
        self.apply(ins.ChildProgress(status=status, log_text=text, tier=tier, now=self._tick()))

    @precondition(lambda self: self.model.child_started)
    @rule(status=st.sampled_from((Status.COMPLETED.value, Status.COMPLETED.value, *STATUSES)))
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
            status = data.draw(st.sampled_from(STATUSES), label="status")
            event = ins.ChildProgress(status=status, log_text="stray", now=now)
        elif kind == "finished":
            event = ins.ChildFinished(status=data.draw(st.sampled_from(STATUSES), label="status"), now=now)
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
