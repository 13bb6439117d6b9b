"""Mutable conveniences over the pure machine, for adapter authors.

:class:`RobotServer` holds one robot's state and configuration and feeds
inputs through :func:`dynevent.server.machine.step`; it adds nothing but holding the
state.  :class:`LockedRobotServer` does the same under one lock, for bindings
whose callbacks run on several threads (rclpy's ``MultiThreadedExecutor``).
:class:`Execution` is the adapter-facing view of one running child event, in
the spirit of rmf_fleet_adapter's ``ActionExecution``: it turns calls such as
``underway("moving")`` or ``finished()`` into machine inputs.
"""

from __future__ import annotations

import threading
from typing import Any, Protocol

from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.machine import ServerConfig, State, Transition
from dynevent.server.outputs import Decision, Output
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import Status, Tier

__all__ = ["Execution", "LockedRobotServer", "RobotServer", "Stepper"]


class Stepper(Protocol):
    """Anything that applies a machine input and returns the outputs: a server, or a binding."""

    def step(self, event: ins.Input) -> tuple[Output, ...]:
        """Apply ``event``; return the outputs to carry out."""


class RobotServer:
    """One robot's server: the current :class:`~dynevent.server.machine.State` and its config.

    Every method is the pure function of :mod:`dynevent.server.machine` applied to
    the held state; :meth:`step` also keeps the new state.
    """

    def __init__(
        self, fleet: str, robot: str, config: ServerConfig | None = None, state: State | None = None
    ) -> None:
        self._config = config if config is not None else ServerConfig()
        self._state = state if state is not None else State.new(fleet, robot)
        if (self._state.fleet, self._state.robot) != (fleet, robot):
            raise ValueError(f"state belongs to {self._state.fleet}/{self._state.robot}, not {fleet}/{robot}")

    @property
    def state(self) -> State:
        """The current state (a frozen value)."""
        return self._state

    @property
    def config(self) -> ServerConfig:
        """The server's configuration."""
        return self._config

    def accept(self, goal: Goal) -> Decision:
        """Would ``goal`` be accepted now?  (:func:`dynevent.server.machine.accept`.)"""
        return machine.accept(self._state, goal, self._config)

    def step(self, event: ins.Input) -> tuple[Output, ...]:
        """Apply ``event``; keep the new state; return the outputs to carry out."""
        transition: Transition = machine.step(self._state, event, self._config)
        self._state = transition.state
        return transition.outputs

    def status_message(self, now: int) -> DynamicEventStatus:
        """The status message describing the current state, e.g. to publish at start-up."""
        return machine.status_message(self._state, now)

    def snapshot(self) -> str:
        """The state as snapshot JSON text (:mod:`dynevent.server.snapshot`)."""
        return snapshot.dumps(self._state)

    @classmethod
    def restore(cls, text: str | bytes, config: ServerConfig | None = None) -> RobotServer:
        """A server holding the state of a snapshot."""
        state = snapshot.loads(text)
        return cls(state.fleet, state.robot, config, state)


class LockedRobotServer(RobotServer):
    """A :class:`RobotServer` whose every operation holds one lock.

    The machine is pure, so one lock around read-step-write is all a
    multi-threaded binding needs: steps are applied one at a time, in the
    order the lock is taken, and each sees the state the previous one left.
    """

    def __init__(
        self, fleet: str, robot: str, config: ServerConfig | None = None, state: State | None = None
    ) -> None:
        super().__init__(fleet, robot, config, state)
        self._lock = threading.Lock()

    @property
    def state(self) -> State:
        """The current state (a frozen value)."""
        with self._lock:
            return self._state

    def accept(self, goal: Goal) -> Decision:
        """Would ``goal`` be accepted now?"""
        with self._lock:
            return machine.accept(self._state, goal, self._config)

    def step(self, event: ins.Input) -> tuple[Output, ...]:
        """Apply ``event`` under the lock; return the outputs."""
        with self._lock:
            transition = machine.step(self._state, event, self._config)
            self._state = transition.state
            return transition.outputs

    def snapshot(self) -> str:
        """The state as snapshot JSON text, taken under the lock."""
        with self._lock:
            return snapshot.dumps(self._state)


class Execution:
    """The adapter's handle on one running child event.

    Status reports map to child progress inputs with the tier rmf_fleet_adapter
    uses: ``underway`` info, ``delayed`` and ``blocked`` warning, ``error``
    error.  With automatic cancel (the default) a cancel or kill of the child
    counts at once as the child finishing canceled or killed; without it, the
    adapter winds down, watching :meth:`okay`, and calls :meth:`finished`.
    After the child has finished every method does nothing and returns ``()``.
    """

    def __init__(self, server: Stepper, child_id: int, *, automatic_cancel: bool = True) -> None:
        self._server = server
        self.child_id = child_id
        self.automatic_cancel = automatic_cancel
        self._stopping: str | None = None
        self._done = False
        self.remaining_time: float | None = None

    def okay(self) -> bool:
        """False once the child was told to cancel or stop, or has finished."""
        return self._stopping is None and not self._done

    @property
    def done(self) -> bool:
        """The child has finished (:meth:`finished` was called, or an automatic cancel finished it)."""
        return self._done

    @property
    def stopping(self) -> str | None:
        """``"canceled"`` or ``"killed"`` once the child was told to stop, else None."""
        return self._stopping

    def _report(self, status: Status, text: str | None, tier: Tier, now: int) -> tuple[Output, ...]:
        if self._done:
            return ()
        return self._server.step(ins.ChildProgress(status=status, log_text=text, tier=tier, now=now))

    def underway(self, text: str | None = None, *, now: int) -> tuple[Output, ...]:
        """The child is making progress (info log)."""
        return self._report(Status.UNDERWAY, text, Tier.INFO, now)

    def delayed(self, text: str | None = None, *, now: int) -> tuple[Output, ...]:
        """The child is delayed (warning log)."""
        return self._report(Status.DELAYED, text, Tier.WARNING, now)

    def blocked(self, text: str | None = None, *, now: int) -> tuple[Output, ...]:
        """The child is blocked (warning log)."""
        return self._report(Status.BLOCKED, text, Tier.WARNING, now)

    def error(self, text: str | None = None, *, now: int) -> tuple[Output, ...]:
        """The child hit an error (error log)."""
        return self._report(Status.ERROR, text, Tier.ERROR, now)

    def update_remaining_time(self, seconds: float) -> None:
        """Record the adapter's estimate of the time left; it feeds no rule."""
        self.remaining_time = seconds

    def finished(self, *, now: int, status: Status = Status.COMPLETED) -> tuple[Output, ...]:
        """The child ended; ``status`` is ``completed`` unless it was stopped early."""
        if self._done:
            return ()
        self._done = True
        final = status
        if self._stopping is not None and status is Status.COMPLETED:
            final = Status(self._stopping)
        return self._server.step(ins.ChildFinished(status=final, now=now))

    def _stop(self, status: Status, now: int) -> tuple[Output, ...]:
        if self._done:
            return ()
        self._stopping = status.value
        if self.automatic_cancel:
            return self.finished(now=now, status=status)
        return ()

    def cancel(self, *, now: int) -> tuple[Output, ...]:
        """Carry out a ``CancelChild`` output."""
        return self._stop(Status.CANCELED, now)

    def kill(self, *, now: int) -> tuple[Output, ...]:
        """Carry out a ``KillChild`` output."""
        return self._stop(Status.KILLED, now)

    def __repr__(self) -> str:
        state: Any = "finished" if self._done else (self._stopping or "running")
        return f"Execution(child_id={self.child_id}, {state}, automatic_cancel={self.automatic_cancel})"
