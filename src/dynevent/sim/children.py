"""What a simulated child does over time, whatever carries it: ``dynevent serve``'s node timers, or
the probe's in-process server on simulated time (:mod:`dynevent.conformance.in_process`).

A :class:`SimulatedChild` is the plan of one child (:func:`~dynevent.sim.config.plan`) and where it
has got to; :meth:`SimulatedChild.report` is one report, made ``elapsed`` seconds after the child
started, through the adapter's handle on the child (:class:`ChildHandle`)."""

from __future__ import annotations

import bisect
import itertools
from typing import Any, Protocol

from dynevent.sim.config import CategorySpec, ServeConfig, Step, plan
from dynevent.wire.vocab import Status

__all__ = ["ChildHandle", "SimulatedChild"]


class ChildHandle(Protocol):
    """The adapter's handle on a running child, as a simulation reports through it."""

    @property
    def done(self) -> bool: ...

    @property
    def stopping(self) -> str | None: ...

    def underway(self, text: str | None = None) -> Any: ...

    def error(self, text: str | None = None) -> Any: ...

    def finished(self, status: Status = Status.COMPLETED) -> Any: ...


class SimulatedChild:
    """One child's steps, each told of by a log line as it begins; a report every :attr:`period`
    seconds (the category's, or the whole child's duration when shorter: a sequence's brief
    activities are each told of at the next report, not by reporting as often as the briefest)."""

    def __init__(self, category: str, parsed: Any, config: ServeConfig) -> None:
        spec = config.categories.get(category, CategorySpec())
        try:
            steps = plan(category, parsed, config)
        except Exception as exc:  # a defect here must end this child, never whatever carries it
            steps = [Step(category, 0.001, f"the simulation cannot run it: {type(exc).__name__}: {exc}")]
        self.steps = steps
        self._ends = list(itertools.accumulate(step.duration for step in steps))
        self.period = max(min(spec.report_every, self._ends[-1]), 0.001)
        self._told = 0  # the last step told of (the first is told by the progress lines)

    def report(self, child: ChildHandle, elapsed: float) -> bool:
        """Report ``elapsed`` seconds after the start: progress, or the end (a child told to stop
        ends at its next report); True once the child is done and wants no more reports."""
        if child.done:
            return True
        elapsed += 1e-3
        if child.stopping is not None:
            child.finished()
            return True
        steps, ends = self.steps, self._ends
        current = min(bisect.bisect_right(ends, elapsed), len(steps) - 1)
        while self._told < current and steps[self._told].failure is None:  # every step is told of
            self._told += 1
            child.underway(f"now {steps[self._told].label}")
        step = steps[self._told]
        if step.failure is not None:
            child.error(step.failure)
            child.finished(Status.FAILED)
        elif elapsed >= ends[-1]:
            child.finished()
        else:
            into = elapsed - (ends[self._told] - step.duration)
            child.underway(f"{step.label}: {into:.0f} of {step.duration:g} s")
        return child.done
