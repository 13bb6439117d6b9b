"""The fleet adapter's side of a server, whatever carries it: what the adapter tells the server on a
clock (:class:`AdapterInputs`), a handle on each running child (:class:`ChildExecution`), what an
adapter implements to run children (:class:`ChildEvents`) and to hold its place after one
(:class:`StubbornHolds`), and the machine's child and stubbornness outputs carried out on them
(:class:`RunningChildren`, :func:`carry_out_stubbornness`).

A binding gives each its stepper and clock: the ROS binding's server
(:class:`dynevent.ros.server.DynamicEventServer`, the node's clock) and the probe's in-process
server (:mod:`dynevent.conformance.probe.in_process`, simulated time) run children through the same
handle.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Protocol

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution, Stepper
from dynevent.wire.vocab import Status

__all__ = [
    "AdapterInputs", "ChildEvents", "ChildExecution", "RunningChildren", "StubbornHolds",
    "carry_out_stubbornness",
]  # fmt: skip


class AdapterInputs(ABC):
    """What the fleet adapter tells a server of the task around the dynamic event, each an input of
    the machine at :meth:`now`, applied by :meth:`step` (which a binding provides)."""

    @abstractmethod
    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        """Apply ``event``; its outputs are carried out as the binding does."""

    @abstractmethod
    def now(self) -> int:
        """The server's clock, in integer nanoseconds within what the machine accepts."""

    def begin(self, description: str, event_id: int, *, interrupted: bool = False) -> None:
        """A task reached its ``dynamic_event`` phase (R3)."""
        now = self.now()
        self.step(ins.Begin(description=description, event_id=event_id, now=now, interrupted=interrupted))

    def interrupt(self) -> None:
        """The task was interrupted (R14)."""
        self.step(ins.Interrupt(now=self.now()))

    def resume(self) -> None:
        """The task's interruption is over (R14)."""
        self.step(ins.Resume(now=self.now()))

    def task_cancel(self) -> None:
        """The whole task was cancelled (R13)."""
        self.step(ins.TaskCancel(now=self.now()))

    def task_kill(self) -> None:
        """The whole task was killed (R13)."""
        self.step(ins.TaskKill(now=self.now()))

    def restart(self) -> None:
        """The state was restored after the process that served it ended (R21)."""
        self.step(ins.Restart(now=self.now()))

    def shutdown(self) -> None:
        """Answer every open goal ``shutting down`` and refuse later requests (R15)."""
        self.step(ins.Shutdown(now=self.now()))


class ChildExecution:
    """The adapter's handle on one running child event, on ``clock`` (integer nanoseconds).

    Report with :meth:`underway`, :meth:`delayed`, :meth:`blocked` and
    :meth:`error` (each with an optional log line) and end it with
    :meth:`finished`.  After a cancel or kill was asked for, :attr:`stopping`
    says which; the status given to :meth:`finished` is then the stop's
    unless it says otherwise.  Calls after the end do nothing.
    """

    def __init__(self, server: Stepper, start: outs.StartChild, clock: Callable[[], int]) -> None:
        self._server = server
        self._clock = clock
        self._execution = Execution(server, start.id, automatic_cancel=False)
        #: The child's id, its category, its description (JSON text) and the parsed description.
        self.id = start.id
        self.category = start.category
        self.description = start.description
        self.parsed = start.parsed

    @property
    def done(self) -> bool:
        """The child has finished."""
        return self._execution.done

    @property
    def stopping(self) -> str | None:
        """``"canceled"`` or ``"killed"`` once the child was told to stop."""
        return self._execution.stopping

    def okay(self) -> bool:
        """Neither told to stop nor finished."""
        return self._execution.okay()

    def underway(self, text: str | None = None) -> None:
        """The child is making progress (an info log line when ``text`` is given)."""
        self._execution.underway(text, now=self._clock())

    def delayed(self, text: str | None = None) -> None:
        """The child is delayed (warning)."""
        self._execution.delayed(text, now=self._clock())

    def blocked(self, text: str | None = None) -> None:
        """The child is blocked (warning)."""
        self._execution.blocked(text, now=self._clock())

    def error(self, text: str | None = None) -> None:
        """The child hit an error (error)."""
        self._execution.error(text, now=self._clock())

    def finished(self, status: Status | str = Status.COMPLETED) -> None:
        """The child ended with ``status`` (``completed`` unless it was stopped early)."""
        self._execution.finished(now=self._clock(), status=Status(status))

    def draw_id(self) -> None:
        """The child drew an id for work of its own from the counter children are numbered with
        (under id policy ``adapter``: a go_to_place's plan, R17.8); nothing after its end."""
        if not self.done:
            self._server.step(ins.IdDrawn(now=self._clock()))

    def stop(self, kill: bool) -> None:
        """Carry out the machine's ``KillChild`` (``kill``) or ``CancelChild``: :attr:`stopping` says
        so from now on; the child ends when the adapter calls :meth:`finished`."""
        now = self._clock()
        if kill:
            self._execution.kill(now=now)
        else:
            self._execution.cancel(now=now)

    def __repr__(self) -> str:
        return f"ChildExecution(id={self.id}, category={self.category!r}, {self._execution!r})"


class ChildEvents(Protocol):
    """What the adapter implements to run child events.  Every method must return quickly."""

    def start(self, execution: ChildExecution) -> None:
        """Start the child; report through ``execution`` from any thread."""

    def cancel(self, execution: ChildExecution) -> None:
        """Stop the child, then call ``execution.finished()``."""

    def kill(self, execution: ChildExecution) -> None:
        """Stop the child at once, then call ``execution.finished()``."""

    def interrupt(self, execution: ChildExecution) -> None:
        """The task is interrupted: pause the child."""

    def resume(self, execution: ChildExecution) -> None:
        """The task's interruption is over: go on."""


class StubbornHolds(Protocol):
    """What the adapter implements to hold its place in traffic after a child (stubbornness)."""

    def begin(self, period: float, map_name: str | None, x: float, y: float) -> None:
        """Declare a holding itinerary of ``period`` seconds here and negotiate stubbornly."""

    def hold(self, period: float, map_name: str, x: float, y: float) -> None:
        """The robot moved: hold again from its new place."""

    def delay(self, seconds: float) -> None:
        """Report the cumulative delay since the hold began."""

    def end(self) -> None:
        """Release the hold."""


class RunningChildren:
    """The children ``children`` runs for ``server``, by id: the machine's child outputs carried out
    on them, each child's handle on ``clock``."""

    def __init__(self, server: Stepper, children: ChildEvents, clock: Callable[[], int]) -> None:
        self._server = server
        self._children = children
        self._clock = clock
        self._executions: dict[int, ChildExecution] = {}

    def carry_out(self, output: outs.Output) -> bool:
        """Carry out a child's output (start, cancel, kill, interrupt, resume); False for another."""
        try:
            return self._carry_out(output)
        finally:  # after every output: a child that ended is forgotten
            for child_id in [key for key, execution in self._executions.items() if execution.done]:
                del self._executions[child_id]

    def _carry_out(self, output: outs.Output) -> bool:
        if isinstance(output, outs.StartChild):
            started = ChildExecution(self._server, output, self._clock)
            self._executions[output.id] = started
            self._children.start(started)
        elif isinstance(output, (outs.CancelChild, outs.KillChild)):
            execution = self._executions.get(output.id)
            if execution is not None:
                kill = isinstance(output, outs.KillChild)
                execution.stop(kill)
                (self._children.kill if kill else self._children.cancel)(execution)
        elif isinstance(output, (outs.InterruptChild, outs.ResumeChild)):
            paused = self._executions.get(output.id)
            if paused is not None:
                interrupt = isinstance(output, outs.InterruptChild)
                (self._children.interrupt if interrupt else self._children.resume)(paused)
        else:
            return False
        return True


def carry_out_stubbornness(holds: StubbornHolds | None, output: outs.Output) -> bool:
    """Carry out a stubbornness output (begin, hold, delay, end) on ``holds`` (nothing to hold with
    when None); False for another output."""
    if isinstance(output, outs.StubbornBegin):
        if holds is not None:
            holds.begin(output.period, output.map_name, output.x, output.y)
    elif isinstance(output, outs.StubbornHold):
        if holds is not None:
            holds.hold(output.period, output.map_name, output.x, output.y)
    elif isinstance(output, outs.StubbornDelay):
        if holds is not None:
            holds.delay(output.delay)
    elif isinstance(output, outs.StubbornEnd):
        if holds is not None:
            holds.end()
    else:
        return False
    return True
