"""What a simulated child does over time, whatever carries it: ``dynevent serve``'s node timers, or
the probe's in-process server on simulated time (:mod:`dynevent.conformance.probe.in_process`).

A :class:`SimulatedChild` is the plan of one child (:func:`~dynevent.sim.config.plan`) and where it
has got to; :meth:`SimulatedChild.report` is one report, made ``elapsed`` seconds after the child
started, through the adapter's handle on the child (:class:`ChildHandle`).  A :class:`Whereabouts`
is where one robot stands, as its go_to_place children leave it: in ``rmf_ros2`` mode a go_to_place
child that has to move draws a second id from the adapter's counter for its plan at its first report
(R17.8), as rmf_ros2's does, and one sent where the robot stands draws none."""

from __future__ import annotations

import bisect
import itertools
from typing import Any, Protocol

from dynevent.sim.config import CategorySpec, ServeConfig, Step, destination, plan
from dynevent.wire.vocab import Compatibility, Status

__all__ = ["ChildHandle", "SimulatedChild", "Whereabouts"]


class Whereabouts:
    """Where one robot stands: the place its last go_to_place child reached (None: not known)."""

    def __init__(self) -> None:
        self.place: str | None = None


class ChildHandle(Protocol):
    """The adapter's handle on a running child, as a simulation reports through it."""

    @property
    def done(self) -> bool: ...

    @property
    def stopping(self) -> str | None: ...

    def underway(self, text: str | None = None) -> Any: ...

    def error(self, text: str | None = None) -> Any: ...

    def finished(self, status: Status = Status.COMPLETED) -> Any: ...

    def draw_id(self) -> Any: ...


class SimulatedChild:
    """One child's steps, each told of by a log line as it begins; a report every :attr:`period`
    seconds (the category's, or the whole child's duration when shorter: a sequence's brief
    activities are each told of at the next report, not by reporting as often as the briefest)."""

    def __init__(
        self, category: str, parsed: Any, config: ServeConfig, robot: Whereabouts | None = None
    ) -> None:
        spec = config.categories.get(category, CategorySpec())
        try:
            steps = plan(category, parsed, config)
        except Exception as exc:  # a defect here must end this child, never whatever carries it
            steps = [Step(category, 0.001, f"the simulation cannot run it: {type(exc).__name__}: {exc}")]
        self.steps = steps
        self._ends = list(itertools.accumulate(step.duration for step in steps))
        self.period = max(min(spec.report_every, self._ends[-1]), 0.001)
        self._told = 0  # the last step told of (the first is told by the progress lines)
        self._reported = False  # a report has been made (the child is on its way)
        self._robot = robot if robot is not None else Whereabouts()
        rmf_ros2 = config.compatibility is Compatibility.RMF_ROS2
        self._goes_to = destination(category, parsed, config) if rmf_ros2 else None
        # no plan, no id: another category, the robot already there, or a place it cannot reach
        self._planned = self._goes_to in (None, self._robot.place) or steps[0].failure is not None
        #: a child that moves the robot other than to a known place leaves it somewhere unknown
        self._moves = rmf_ros2 and (self._goes_to is not None or category == "sequence")

    def report(self, child: ChildHandle, elapsed: float) -> bool:
        """Report ``elapsed`` seconds after the start: progress, or the end (a child told to stop
        ends at its next report); True once the child is done and wants no more reports."""
        if child.done:
            return True
        elapsed += 1e-3
        if child.stopping is not None:
            if self._moves and self._reported:  # stopped on its way: somewhere between
                self._robot.place = None
            child.finished()
            return True
        self._reported = True
        if not self._planned:  # the plan found, at the first report: its id drawn (R17.8)
            self._planned = True
            child.draw_id()
        steps, ends = self.steps, self._ends
        current = min(bisect.bisect_right(ends, elapsed), len(steps) - 1)
        while self._told < current and steps[self._told].failure is None:  # every step is told of
            self._told += 1
            child.underway(f"now {steps[self._told].label}")
        step = steps[self._told]
        if step.failure is not None:
            child.error(step.failure)
            child.finished(Status.FAILED)
            if self._moves and self._told > 0:  # failed on its way
                self._robot.place = None
        elif elapsed >= ends[-1]:
            child.finished()
            if self._moves:
                self._robot.place = self._goes_to  # None after a sequence: not tracked
        else:
            into = elapsed - (ends[self._told] - step.duration)
            child.underway(f"{step.label}: {into:.0f} of {step.duration:g} s")
        return child.done
