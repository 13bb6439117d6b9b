"""Behaviour-tree behaviours that drive one robot's Dynamic Event, on py_trees (the ``bt`` extra).

A behaviour tree is the client the protocol was made for: each leaf runs one
event on the robot, a sequence runs them in turn, a fallback tries another
when one fails, and a branch the tree leaves (a higher priority took over, the
tree was stopped) must not leave its child running on the robot.

- :class:`WaitForRun`: RUNNING until the robot is in a Dynamic Event (its
  status WAITING or RUNNING), then SUCCESS, the run's begin description put
  on the blackboard when asked; FAILURE after ``timeout`` seconds.
- :class:`RunEvent`: a NEXT.  RUNNING while the child runs (the feedback
  message says its id and status), SUCCESS when it ends ``completed``,
  FAILURE otherwise, the :class:`~dynevent.client.Outcome` (or
  :class:`~dynevent.client.Refused`) saying why.  The description is a string,
  or built from the blackboard when the tree ticks the behaviour.  When the
  tree halts it (py_trees calls ``terminate(INVALID)``) while its goal is
  open, the child is cancelled: the client machine withdraws the NEXT
  (:func:`dynevent.client.request_withdraw`) and sends a CANCEL naming the
  child as soon as it is known to run.  A behaviour that starts while
  another of the tree holds the robot waits (RUNNING) for it to be halted
  and its child to end, then sends: py_trees ticks a higher priority before
  it halts the lower one (a selector, a parallel's policy, a timeout or a
  guard); a holder that is not halted in that tick is named in a FAILURE.
- :class:`FinishRun`: FINISHED; SUCCESS when the run ends ``completed``.

The behaviours take a robot client that spins itself
(:class:`dynevent.ros.RobotClient`, opened); every decision is the client
machine's, so a behaviour never sends what the robot would refuse: a refusal
it would meet is a FAILURE at once, with the reason the server would give.
Ticks never block: each reads where the goal stands.  docs/bt.md shows a tree.
"""

from __future__ import annotations

import json
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

try:
    import py_trees
    from py_trees.common import Access, Status
except ImportError as exc:  # pragma: no cover - the extra is missing
    from dynevent.errors import LocalError

    raise LocalError(
        f"dynevent.bt needs py_trees: pip install 'dynevent[bt]' (importing it failed: {exc})"
    ) from None

from dynevent import client as cl
from dynevent.errors import InvalidValue
from dynevent.wire.vocab import DynamicState

if TYPE_CHECKING:
    from dynevent.ros.client import GoalRun

__all__ = ["FinishRun", "Robot", "RunEvent", "WaitForRun", "go_to_place"]

Result = cl.Outcome | cl.Refused


class Robot(Protocol):
    """What the behaviours need of a robot client (:class:`dynevent.ros.RobotClient` is one)."""

    @property
    def state(self) -> cl.ClientState: ...

    def next(
        self,
        category: str,
        description: str,
        *,
        stubborn_period: float = 0.0,
        timeout: float | None = None,
        on_progress: Callable[[cl.Progress], None] | None = None,
    ) -> GoalRun: ...

    def withdraw(self, run: GoalRun) -> None: ...

    def finish(self) -> GoalRun: ...


#: A description: the text itself, or a function of the behaviour's blackboard client that builds it.
Description = str | Callable[[Any], str]


def _said(result: Result) -> str:
    """The feedback message of an ended goal: its outcome kind and why."""
    return f"{result.kind.value}: {result.text}"


def _withdrawing(robot: Robot) -> bool:
    """Is a NEXT this client withdrew still open (its child being cancelled)?"""
    return any(goal.withdrawn for goal in robot.state.goals)


#: The behaviour whose goal holds each robot (sent, and not answered yet): what a behaviour that
#: starts meanwhile waits for, and names when it cannot.
_HOLDERS: weakref.WeakKeyDictionary[Any, _GoalBehaviour] = weakref.WeakKeyDictionary()


class _GoalBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour that sends one goal when it starts and reads its run on every tick."""

    def __init__(self, name: str, robot: Robot) -> None:
        super().__init__(name)
        self.robot = robot
        self._waited = False  # this start has already waited one tick for the robot's holder
        #: The goal of the current (or last) start, once sent.
        self.run: GoalRun | None = None
        #: How the last goal ended (None while it runs, or before the first).
        self.result: Result | None = None

    def initialise(self) -> None:
        self.run, self.result = None, None
        self._waited = False

    def send(self) -> GoalRun:  # pragma: no cover - every behaviour sends its own goal
        raise NotImplementedError

    def _wait(self) -> Status | None:
        """RUNNING while the robot is held by another behaviour of the tree that is being halted (its
        NEXT withdrawn, the child ending), or that may be halted in this very tick: py_trees ticks a
        higher priority before it halts the lower one it takes over from.  FAILURE, naming it, when
        the holder ran on through the tick after; ``None`` when the robot is free."""
        if _withdrawing(self.robot):
            self.feedback_message = "waiting for a withdrawn event to end"
            return Status.RUNNING
        holder = _HOLDERS.get(self.robot)
        if holder is None or holder is self or holder.run is None or holder.run.done():
            return None
        if not self._waited:
            self._waited = True
            self.feedback_message = f"waiting for {holder.name!r}, which holds the robot, to be halted"
            return Status.RUNNING
        self.feedback_message = f"the robot is held by {holder.name!r}, which runs on: it was not halted"
        return Status.FAILURE

    def ended(self, result: Result) -> Status:
        """SUCCESS when the goal ran to a ``completed`` end, else FAILURE."""
        return Status.SUCCESS if result.kind is cl.OutcomeKind.COMPLETED else Status.FAILURE

    def update(self) -> Status:
        if self.run is None:
            waiting = self._wait()
            if waiting is not None:
                return waiting
            self.run = self.send()
            if not self.run.done():
                _HOLDERS[self.robot] = self
        run = self.run
        if not run.done():
            progress = run.progress[-1] if run.progress else None
            self.feedback_message = "sent" if progress is None else f"event {progress.id}: {progress.status}"
            return Status.RUNNING
        assert run.result is not None
        self.result = run.result
        self.feedback_message = _said(run.result)
        return self.ended(run.result)


class RunEvent(_GoalBehaviour):
    """Run one event on the robot (a NEXT of ``category``): SUCCESS when it completes.

    ``description`` is the event's description (JSON text), or a function that
    builds it from this behaviour's blackboard client, called when the
    behaviour starts; ``blackboard_keys`` are the keys it may read.
    ``stubborn_period`` and ``timeout`` (seconds) are the NEXT's.
    """

    def __init__(
        self,
        name: str,
        robot: Robot,
        category: str,
        description: Description,
        *,
        blackboard_keys: tuple[str, ...] = (),
        stubborn_period: float = 0.0,
        timeout: float | None = None,
    ) -> None:
        super().__init__(name, robot)
        if not isinstance(description, str) and not callable(description):
            raise InvalidValue("RunEvent", "description", description, "expected a str or a callable")
        self.category = category
        self.description = description
        self.stubborn_period = stubborn_period
        self.timeout = timeout
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in blackboard_keys:
            self.blackboard.register_key(key=key, access=Access.READ)

    def send(self) -> GoalRun:
        description = self.description
        text = description if isinstance(description, str) else description(self.blackboard)
        if not isinstance(text, str):
            text = json.dumps(text)  # a description built as JSON values
        return self.robot.next(
            self.category, text, stubborn_period=self.stubborn_period, timeout=self.timeout
        )

    def terminate(self, new_status: Status) -> None:
        """Halted (``INVALID``) while the goal is open: withdraw it, so its child is cancelled."""
        run = self.run
        if new_status is Status.INVALID and run is not None and not run.done():
            self.robot.withdraw(run)
            self.feedback_message = "halted: the child is being cancelled"


class FinishRun(_GoalBehaviour):
    """End the Dynamic Event (FINISHED): SUCCESS when the run ends ``completed``."""

    def send(self) -> GoalRun:
        return self.robot.finish()


def go_to_place(key: str) -> Callable[[Any], str]:
    """A ``go_to_place`` description from the blackboard: ``{"one_of": [place]}`` for a place name,
    or ``{"one_of": places}`` for a list of them, read from ``key``."""

    def build(blackboard: Any) -> str:
        value = blackboard.get(key)
        places = [value] if isinstance(value, (str, int)) else list(value)
        return json.dumps({"one_of": places})

    return build


class WaitForRun(py_trees.behaviour.Behaviour):
    """RUNNING until the robot is in a Dynamic Event, then SUCCESS; FAILURE after ``timeout`` seconds.

    With ``description_key``, the run's begin description (JSON text) is
    written on the blackboard under that key, once the client has heard it.
    """

    def __init__(
        self, name: str, robot: Robot, *, timeout: float = 30.0, description_key: str | None = None
    ) -> None:
        super().__init__(name)
        self.robot = robot
        self.timeout = timeout
        self.description_key = description_key
        self._started = 0.0
        self.blackboard = self.attach_blackboard_client(name=name)
        if description_key is not None:
            self.blackboard.register_key(key=description_key, access=Access.WRITE)

    def initialise(self) -> None:
        self._started = time.monotonic()

    def update(self) -> Status:
        state = self.robot.state
        active = state.newest_seq is not None and state.phase is not DynamicState.INACTIVE
        if active and not state.finished and (self.description_key is None or state.description):
            if self.description_key is not None:
                self.blackboard.set(self.description_key, state.description)
            self.feedback_message = f"run {state.seq}"
            return Status.SUCCESS
        if time.monotonic() - self._started >= self.timeout:
            self.feedback_message = f"no Dynamic Event within {self.timeout:g} s"
            return Status.FAILURE
        self.feedback_message = "waiting for a Dynamic Event"
        return Status.RUNNING
