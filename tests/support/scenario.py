"""A tiny harness for the spec section tests (``tests/spec/test_NN_*.py``).

Not a test module: test files import it as ``from support.scenario import ...``
(``pythonpath`` in pyproject.toml puts ``tests/`` on ``sys.path``).

A :class:`Run` holds one robot's state (``tinyRobot``/``r1``) and a
configuration, and steps it with one method per input; each method returns the
tuple of outputs.  The builders :func:`waiting`, :func:`running`,
:func:`deferred` and :func:`stubborn` bring a fresh robot into the common
situations.  The output constructors (:func:`status`, :func:`feedback`,
:func:`aborted`...) keep expected tuples short; free-form sentences that the
spec does not fix (rejection texts, ``Ignored.why``) compare equal to
:data:`ANY_TEXT`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from decimal import Decimal
from typing import Any

import attrs

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import LockedRobotServer, RobotServer
from dynevent.server.machine import ServerConfig, State, Validator, accept, any_description, step
from dynevent.wire.messages import DynamicEventStatus, Feedback, Goal, LogEntry, Result, Time
from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, IdPolicy, RejectReason, Status

FLEET = "tinyRobot"
ROBOT = "r1"

INACTIVE = DynamicState.INACTIVE
WAITING = DynamicState.WAITING
RUNNING = DynamicState.RUNNING

SUCCEEDED = GoalStatus.SUCCEEDED
ABORTED = GoalStatus.ABORTED
CANCELED = GoalStatus.CANCELED

#: rmf_ros2's execution-failure strings, spelled out from docs/spec.md (not imported from the code).
RACE = "race condition"
SHUTTING_DOWN = "shutting down"
IDLE_CANCEL = "an idle dynamic event cannot be cancelled"
CANCEL_ID = "ID for cancel request does not match current event"
INVALID_EVENT_TYPE = "invalid event_type"
PARSE_FAILURE = "Description parsing failure"
NOT_RUNNING = "cancelled while not running"

#: The dynamic event's own description (a valid ``dynamic_event`` description, R1.5).
DESC = '{"category":"patrol","detail":"lobby loop","custom":[1,2]}'
#: A NEXT description the ``go_to_place`` validator accepts.
PLACE = '"lobby"'


def u(number: int) -> str:
    """The goal UUID ``number`` as 32 hexadecimal digits: ``u(1) == "000...001"``."""
    return f"{number:032x}"


def s(seconds: float) -> int:
    """Seconds as integer nanoseconds, decimal exact: ``s(3) == 3_000_000_000``, ``s(0.1) == 100_000_000``."""
    return int(Decimal(repr(seconds)) * 1_000_000_000)


#: The instant every builder works at, unless told otherwise.
T0 = s(100)


def go_to_place(category: str, description: Any) -> Sequence[str]:
    """Accepts a place name or ``{"place": <name>}``."""
    if isinstance(description, str):
        return ()
    if isinstance(description, dict) and isinstance(description.get("place"), str):
        return ()
    return ("expected a place name or an object with a string 'place'",)


CATEGORIES: Mapping[str, Validator] = {"go_to_place": go_to_place, "perform_action": any_description}
CONFIG = ServerConfig(categories=CATEGORIES)
RMF_ROS2 = ServerConfig.rmf_ros2(CATEGORIES)


class _AnyText:
    """Equal to any non-empty ``str``: for sentences the spec leaves free."""

    def __eq__(self, other: object) -> bool:
        return isinstance(other, str) and other != ""

    def __hash__(self) -> int:
        return 0

    def __repr__(self) -> str:
        return "ANY_TEXT"


ANY_TEXT: Any = _AnyText()


def _loose(message: Any, **fields: Any) -> Any:
    """``message`` with some fields set past its checks (to :data:`ANY_TEXT`), for comparison only."""
    for name, value in fields.items():
        object.__setattr__(message, name, value)
    return message


# --------------------------------------------------------------------------- goals


def goal(
    seq: int,
    event_type: int,
    id: int = 0,
    category: str = "",
    description: str = "",
    stubborn: float = 0.0,
) -> Goal:
    """Any goal, including event types the protocol does not define."""
    return Goal(
        dynamic_event_seq=seq,
        event_type=event_type,
        category=category,
        description=description,
        id=id,
        stubborn_period=stubborn,
    )


def next_goal(
    seq: int, id: int, category: str = "go_to_place", description: str = PLACE, stubborn: float = 0.0
) -> Goal:
    return goal(seq, EventType.NEXT, id, category, description, stubborn)


def cancel_goal(seq: int, id: int) -> Goal:
    return goal(seq, EventType.CANCEL, id)


def finished_goal(seq: int) -> Goal:
    return goal(seq, EventType.FINISHED)


# --------------------------------------------------------------------------- expected outputs


def time(now: int) -> Time:
    return Time.from_nanoseconds(now)


def status(seq: int, phase: DynamicState, text: str, id: int, now: int = T0) -> outs.PublishStatus:
    """``PublishStatus`` of ``DynamicEventStatus(seq, phase, status, id, time=now)``."""
    return outs.PublishStatus(
        message=DynamicEventStatus(
            dynamic_event_seq=seq, dynamic_state=phase, status=text, id=id, time=time(now)
        )
    )


def entry(seq: int, tier: str, now: int, text: str) -> LogEntry:
    """``LogEntry(seq, tier, floor(now / 10**6), text)``; ``text`` may be :data:`ANY_TEXT`."""
    millis = now // 1_000_000
    if text is ANY_TEXT:
        loose: LogEntry = _loose(LogEntry(seq=seq, tier=tier, unix_millis_time=millis), text=text)
        return loose
    return LogEntry(seq=seq, tier=tier, unix_millis_time=millis, text=text)


def feedback(uuid: str, text: str, id: int, *logs: LogEntry) -> outs.PublishFeedback:
    return outs.PublishFeedback(goal_uuid=uuid, feedback=Feedback(status=text, id=id, logs=logs))


def answer(
    uuid: str, goal_status: GoalStatus, failure: str = "", text: str = "", id: int = 0
) -> outs.AnswerGoal:
    """``AnswerGoal(goal_status, Result(failure, text, id))``; ``failure`` may be :data:`ANY_TEXT`."""
    if failure is ANY_TEXT:
        result: Result = _loose(Result(status=text, id=id), execution_failure=failure)
    else:
        result = Result(execution_failure=failure, status=text, id=id)
    return outs.AnswerGoal(goal_uuid=uuid, status=goal_status, result=result)


def aborted(uuid: str, failure: str) -> outs.AnswerGoal:
    """A failure answer: ``AnswerGoal(aborted, Result(execution_failure=failure))``."""
    return answer(uuid, ABORTED, failure)


def start_child(id: int, description: str = PLACE, category: str = "go_to_place") -> outs.StartChild:
    return outs.StartChild(category=category, description=description, id=id, parsed=json.loads(description))


def rejected(uuid: str, reason: RejectReason, text: Any = ANY_TEXT, **values: Any) -> outs.GoalRejected:
    return outs.GoalRejected(goal_uuid=uuid, rejection=outs.Rejected(reason=reason, text=text, **values))


def ignored(kind: str) -> tuple[outs.Ignored]:
    return (outs.Ignored(input=kind, why=ANY_TEXT),)


# --------------------------------------------------------------------------- the run


class Run:
    """One robot's server under test: the state, the config, and a clock ``now``.

    Every input method steps the machine at ``now`` (or the ``now`` given),
    keeps the new state and returns the outputs; ``before`` is the state
    the last step started from.
    """

    def __init__(self, config: ServerConfig = CONFIG, state: State | None = None, now: int = T0) -> None:
        self.config = config
        self.state = state if state is not None else State.new(FLEET, ROBOT)
        self.before = self.state
        self.now = now

    # ---- plumbing

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        self.before = self.state
        transition = step(self.state, event, self.config)
        self.state = transition.state
        return transition.outputs

    def at(self, now: int) -> Run:
        self.now = now
        return self

    def evolve(self, **changes: Any) -> Run:
        """Change state fields directly (``run.evolve(seq=2**32 - 1)``)."""
        self.state = attrs.evolve(self.state, **changes)
        return self

    def accept(self, goal: Goal) -> outs.Decision:
        return accept(self.state, goal, self.config)

    @property
    def phase(self) -> DynamicState:
        return self.state.phase

    @property
    def seq(self) -> int:
        return self.state.seq

    def _now(self, now: int | None) -> int:
        return self.now if now is None else now

    # ---- inputs

    def begin(self, event_id: int = 1, description: str = DESC, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.Begin(description=description, event_id=event_id, now=self._now(now)))

    def request(self, uuid: str, goal: Goal, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.GoalRequested(goal_uuid=uuid, goal=goal, now=self._now(now)))

    def start(self, uuid: str, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.GoalStarted(goal_uuid=uuid, now=self._now(now)))

    def submit(self, uuid: str, goal: Goal, now: int | None = None) -> tuple[Any, ...]:
        """Request (which must be accepted) and start a goal; the start's outputs."""
        outputs = self.request(uuid, goal, now)
        assert outputs == (outs.GoalAccepted(goal_uuid=uuid),), outputs
        return self.start(uuid, now)

    def cancel(self, uuid: str, now: int | None = None) -> tuple[Any, ...]:
        """An action-level cancel request (``handle_cancel``)."""
        return self.step(ins.CancelRequested(goal_uuid=uuid, now=self._now(now)))

    def progress(
        self, text: str, log: str | None = None, tier: str = "info", now: int | None = None
    ) -> tuple[Any, ...]:
        return self.step(ins.ChildProgress(status=text, log_text=log, tier=tier, now=self._now(now)))

    def child_end(self, text: str = "completed", now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.ChildFinished(status=text, now=self._now(now)))

    def tick(
        self, map_name: str = "L1", x: float = 0.0, y: float = 0.0, now: int | None = None
    ) -> tuple[Any, ...]:
        return self.step(ins.Tick(now=self._now(now), map_name=map_name, x=x, y=y))

    def interrupt(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.Interrupt(now=self._now(now)))

    def resume(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.Resume(now=self._now(now)))

    def task_cancel(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.TaskCancel(now=self._now(now)))

    def task_kill(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.TaskKill(now=self._now(now)))

    def shutdown(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.Shutdown(now=self._now(now)))

    def query(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.DescriptionQuery(now=self._now(now)))

    def id_drawn(self, now: int | None = None) -> tuple[Any, ...]:
        return self.step(ins.IdDrawn(now=self._now(now)))

    # ---- checks

    def assert_ignored(self, outputs: tuple[Any, ...], kind: str) -> None:
        """R18.1: ``Ignored`` is the only output and the state did not change."""
        assert outputs == ignored(kind)
        assert self.state == self.before


# --------------------------------------------------------------------------- situations


def waiting(event_id: int = 1, config: ServerConfig = CONFIG, seq: int = 0) -> Run:
    """A robot whose dynamic event ``event_id`` has begun (run ``seq + 1``): WAITING, ``standby``."""
    run = Run(config, attrs.evolve(State.new(FLEET, ROBOT), seq=seq))
    run.begin(event_id)
    assert run.phase is WAITING
    return run


def running(
    child_id: int = 5,
    uuid: str = u(1),
    stubborn: float = 0.0,
    config: ServerConfig = CONFIG,
    event_id: int = 1,
) -> Run:
    """WAITING, then a NEXT (``uuid``) started child ``child_id``: RUNNING, ``underway``."""
    run = waiting(event_id, config)
    run.submit(uuid, next_goal(run.seq, child_id, stubborn=stubborn))
    assert run.phase is RUNNING
    assert run.state.running is not None
    assert run.state.running.started
    return run


def deferred(child_id: int = 5, uuid: str = u(1), config: ServerConfig = CONFIG) -> Run:
    """WAITING, interrupted, then a NEXT (``uuid``) whose child's start is deferred (R6.3)."""
    run = waiting(config=config)
    run.interrupt()
    run.submit(uuid, next_goal(run.seq, child_id))
    assert run.state.running is not None
    assert not run.state.running.started
    return run


def stubborn(period: float = 3.0, child_id: int = 5, uuid: str = u(1), position: bool = True) -> Run:
    """A child asking for ``period`` s of stubbornness ended at ``T0``: WAITING and stubborn.

    With ``position``, a tick first reported the robot on map ``L1`` at (1, 2).
    """
    run = running(child_id, uuid, stubborn=period)
    if position:
        run.tick("L1", 1.0, 2.0)
    run.child_end("completed")
    assert run.state.stubborn is not None
    return run


def shut_down() -> Run:
    """A robot whose run began, then shut down (R15.1)."""
    run = waiting()
    run.shutdown()
    return run


# --------------------------------------------------------------------------- shared by several sections

#: The configuration with the server's id policy ``adapter`` (R6.2).
ADAPTER = attrs.evolve(CONFIG, id_policy=IdPolicy.ADAPTER)
#: Every status a child may report (R7.1).
CHILD_STATUSES = [status.value for status in Status]
#: The two robot-server holders, which must behave alike.
SERVER_CLASSES = [RobotServer, LockedRobotServer]


def execute(uuid: str) -> outs.ExecuteGoal:
    return outs.ExecuteGoal(goal_uuid=uuid)


def running_server(cls: type[RobotServer] = RobotServer, child_id: int = 5) -> RobotServer:
    """A holder of ``cls`` whose robot runs child ``child_id`` (started by the NEXT ``u(1)``)."""
    server = cls(FLEET, ROBOT, CONFIG)
    server.step(ins.Begin(description=DESC, event_id=1, now=T0))
    server.step(ins.GoalRequested(goal_uuid=u(1), goal=next_goal(1, child_id), now=T0))
    server.step(ins.GoalStarted(goal_uuid=u(1), now=T0))
    return server
