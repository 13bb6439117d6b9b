"""A robot server's state (:class:`State`): everything the server knows, as one frozen value.

The machine (:mod:`dynevent.server.machine`) steps it and re-exports every name here; a snapshot
(:mod:`dynevent.server.snapshot`) is it, encoded.  The phase is derived, never stored
(:func:`phase_of`), and so is the id a status reports (:func:`reported_id`).
"""

from __future__ import annotations

from typing import Any

import attrs

from dynevent.server.config import ServerConfig
from dynevent.wire._fields import ANNOTATION, fast_init
from dynevent.wire.messages import Goal
from dynevent.wire.names import validate_token
from dynevent.wire.vocab import DynamicState, Status

__all__ = ["Position", "QueuedGoal", "RunningGoal", "State", "Stubbornness", "phase_of", "reported_id"]


@fast_init
@attrs.frozen(kw_only=True)
class QueuedGoal:
    """A goal that was accepted and has not started yet.

    ``checked`` carries a NEXT's description check from its acceptance to its
    start: ``(config, parsed description)``, the configuration it passed under
    and what it parsed to.  An annotation (no part of equality, never
    encoded): a goal restored from a snapshot, or started under another
    configuration, is checked again (R6.1).
    """

    goal_uuid: str
    goal: Goal
    checked: tuple[ServerConfig, Any] | None = attrs.field(
        default=None, eq=False, repr=False, metadata={ANNOTATION: True}
    )


@fast_init
@attrs.frozen(kw_only=True)
class RunningGoal:
    """The NEXT goal that holds the running slot, and its child event.

    ``started`` is false while the child's start is deferred by an
    interruption.  ``cancel_requested`` records an accepted action-level cancel
    of this goal; ``canceling`` that the child has been told to stop.
    """

    goal_uuid: str
    goal: Goal
    child_id: int
    child_status: str
    started: bool
    cancel_requested: bool = False
    canceling: bool = False


@fast_init
@attrs.frozen(kw_only=True)
class Position:
    """Where a tick last reported the robot."""

    map_name: str
    x: float
    y: float


@fast_init
@attrs.frozen(kw_only=True)
class Stubbornness:
    """An active stubborn hold: ``period`` seconds, held since ``hold_since``, anchored at ``anchor``."""

    period: float
    hold_since: int
    next_refresh: int
    anchor: Position | None


@fast_init
@attrs.frozen(kw_only=True)
class State:
    """Everything the server knows for one robot.

    Build a fresh one with :meth:`new`.  The phase (``INACTIVE``, ``WAITING``,
    ``RUNNING``) is derived, never stored.  ``status`` is the dynamic event's
    own status; ``last_id`` the highest event id used in the current run;
    ``log_seq`` the next ``LogEntry.seq``; ``task_signal`` is ``""``,
    ``"canceled"`` or ``"killed"`` once the task was cancelled or killed.
    """

    fleet: str
    robot: str
    seq: int = 0
    active: bool = False
    event_id: int = 0
    description: str = ""
    status: str = Status.UNINITIALIZED.value
    last_id: int = 0
    running: RunningGoal | None = None
    queued: tuple[QueuedGoal, ...] = ()
    cancels: tuple[str, ...] = ()
    interrupted: bool = False
    task_signal: str = ""
    stubborn: Stubbornness | None = None
    position: Position | None = None
    log_seq: int = 0
    shutdown: bool = False

    @classmethod
    def new(cls, fleet: str, robot: str) -> State:
        """The state of a robot whose server has just started; refuses invalid names."""
        return cls(fleet=validate_token("fleet", fleet), robot=validate_token("robot", robot))

    @property
    def phase(self) -> DynamicState:
        """INACTIVE without an active dynamic event, RUNNING while a goal holds the running slot (R2.1)."""
        return phase_of(self.active, self.running is not None)

    @property
    def current_id(self) -> int:
        """The id the status topic reports (R2.2): the child's while running, else the highest used."""
        running = self.running
        return reported_id(self.active, self.last_id, None if running is None else running.child_id)


def phase_of(active: bool, running: bool) -> DynamicState:
    """The phase of a server (R2.1): INACTIVE when no dynamic event is active, else RUNNING while a
    goal holds the running slot, else WAITING.  :attr:`State.phase` and any other model read it."""
    if not active:
        return DynamicState.INACTIVE
    return DynamicState.RUNNING if running else DynamicState.WAITING


def reported_id(active: bool, last_id: int, child_id: int | None) -> int:
    """The id a status message reports (R2.2): 0 when inactive, else the running child's
    (``child_id``, ``None`` when none runs), else the highest id used in the run."""
    if not active:
        return 0
    return last_id if child_id is None else child_id
