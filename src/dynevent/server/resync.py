"""The observer's corrections: the only ways besides ``step`` that a server state may change.

An observer that replays what it saw of a server (``dynevent check``) keeps a
state of the machine.  When the server evidently did something the rules do
not allow, the observer reports it, then brings its state into agreement with
what the server did, so that one fault is reported once.  Each operation here
says what the server evidently did and keeps the state one the machine can
hold (tests/spec/test_19_invariants.py runs every one on reachable states).
"""

from __future__ import annotations

from collections.abc import Iterable

from dynevent.server.machine import QueuedGoal, RunningGoal, State
from dynevent.wire._fields import U32_MAX, replacer
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import Status

__all__ = [
    "child_id",
    "child_started",
    "dropped",
    "event_id",
    "next_run",
    "queued",
    "run_dropped",
    "running",
    "running_goal",
    "seq",
    "serving",
    "start_dropped",
]

_replace = replacer(State)
_replace_goal = replacer(RunningGoal)


def seq(state: State, seq: int) -> State:
    """The server's current (or last) run is evidently ``seq``."""
    return _replace(state, seq=seq & U32_MAX)


def next_run(state: State, seq: int) -> State:
    """The server's next begin evidently opens run ``seq``: the last run was the one before it."""
    return _replace(state, seq=(seq - 1) & U32_MAX)


def serving(state: State) -> State:
    """The server evidently serves again after its shutdown (it published a begin)."""
    return _replace(state, shutdown=False)


def run_dropped(state: State) -> State:
    """The server evidently dropped its active run, with its goals (it began another)."""
    return _replace(state, active=False, running=None, queued=(), cancels=(), stubborn=None)


def event_id(state: State, event_id: int) -> State:
    """The dynamic event's own id is evidently ``event_id`` (a status or a FINISHED's answer said); it
    is the highest id used unless a higher one was, or a child runs (whose id is then the highest)."""
    last_id = state.last_id if state.running is not None else max(state.last_id, event_id)
    return _replace(state, event_id=event_id, last_id=last_id)


def queued(state: State, goal_uuid: str, goal: Goal) -> State:
    """The server evidently accepted this goal (the rules refuse it): it waits to start."""
    return _replace(state, queued=(*state.queued, QueuedGoal(goal_uuid=goal_uuid, goal=goal)))


def dropped(state: State, goal_uuid: str) -> State:
    """The server evidently no longer holds this accepted goal (waiting, or a CANCEL waiting for a
    child's end): it answered it early."""
    return _replace(
        state,
        queued=tuple(item for item in state.queued if item.goal_uuid != goal_uuid),
        cancels=tuple(other for other in state.cancels if other != goal_uuid),
    )


def child_started(state: State, *, resumed: bool = False) -> State:
    """The running goal's child has evidently started (its start was not deferred, R6.3); with
    ``resumed``, the server is no longer interrupted either.  No running goal: unchanged."""
    running = state.running
    if running is None:
        return state
    interrupted = False if resumed else state.interrupted
    return _replace(state, running=_replace_goal(running, started=True), interrupted=interrupted)


def start_dropped(state: State) -> State:
    """The server evidently dropped the running goal whose child's start was deferred (it answered it).

    No CANCEL waits for a deferred child (R9.4 answers it at once), and none can wait once the
    running goal is gone: any still held are dropped with it, so the state keeps its invariants
    whatever state it is given.
    """
    return _replace(state, running=None, cancels=(), status=Status.STANDBY.value)


def running_goal(state: State, goal_uuid: str) -> State:
    """The running goal, unknown so far (:data:`UNKNOWN_GOAL`), is evidently ``goal_uuid``."""
    running = state.running
    if running is None:
        return state
    return _replace(state, running=_replace_goal(running, goal_uuid=goal_uuid))


def child_id(state: State, child_id: int) -> State:
    """The running child evidently has the id ``child_id`` (its feedback said), now the highest used."""
    running = state.running
    if running is None:
        return state
    return _replace(state, running=_replace_goal(running, child_id=child_id), last_id=child_id)


def running(
    state: State, goal_uuid: str, goal: Goal, child_id: int, child_status: str, displaced: Iterable[str]
) -> State:
    """The server evidently runs this NEXT goal's child (its feedback said), whatever the rules say.

    The goals in ``displaced`` (the running one, CANCELs waiting for it) are no longer held; the run
    is active, with no stubborn hold.  A child that reports ``queued`` is taken as not started yet,
    deferred by an interruption (only an interruption defers a start, R6.3).
    """
    gone = {goal_uuid, *displaced}
    running = RunningGoal(
        goal_uuid=goal_uuid,
        goal=goal,
        child_id=child_id,
        child_status=child_status,
        started=child_status != Status.QUEUED.value,
    )
    return _replace(
        state,
        queued=tuple(item for item in state.queued if item.goal_uuid not in gone),
        running=running,
        cancels=(),
        status=child_status,
        last_id=child_id,
        stubborn=None,
        active=True,
        interrupted=state.interrupted or not running.started,
    )
