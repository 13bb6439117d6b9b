"""The probe's link to a server in this process: dynevent's machine as ``dynevent serve`` runs one
robot (its ``--config``, either compatibility mode), on simulated time.

:class:`InProcessLink` is a :class:`~dynevent.conformance.probe.runner.Link` whose far end is not a
network but the machine itself, carried out the way serve's binding carries it out: a goal request
is stepped (``GoalRequested``) and, accepted, handed over at the next wait (``GoalStarted``, the
``handle_accepted`` moment: a goal sent with it is asked for first, and may win the race, R5.2); the
outputs are carried out in order (a status published, feedback and answers delivered to the goal's
:class:`~dynevent.conformance.probe.runner.Exchange`, a child started or told to stop); children are
:class:`~dynevent.sim.children.SimulatedChild`, reporting on serve's periods; a run that ends begins
again after serve's ``rebegin``.  Time is simulated: a wait runs what is due up to its end and takes
no time at all, so every case runs in well under a second, and the same cases give the same findings
every run.  Real time is kept apart (``wall``): the run's ``--deadline`` bounds it as it bounds the
simulated time, so that a server that answers slowly, or not at all, is left when the deadline
passes.

The server can be replaced (``stepper``): any ``apply(input) -> outputs`` over the machine's inputs
and outputs, so that a deliberately broken server (the test kit's) is probed the same way.
"""

from __future__ import annotations

import collections
import heapq
import itertools
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import attrs

from dynevent import descriptions
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.conformance.probe import cases as probe_cases
from dynevent.conformance.probe import runner as probe_runner
from dynevent.conformance.probe.cases import Case, CaseFinding
from dynevent.conformance.probe.runner import Exchange, Link, Options
from dynevent.conformance.records import InvalidRecord, input_to_json, output_from_json
from dynevent.conformance.vectors import runner as vectors_runner
from dynevent.errors import DeadlinePassed, ImplementationError
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.adapter import ChildExecution
from dynevent.server.holder import RobotServer
from dynevent.server.machine import ServerConfig
from dynevent.sim.children import SimulatedChild, Whereabouts
from dynevent.sim.config import DEFAULT_DESCRIPTION, ServeConfig, machine_config
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.names import description_service

__all__ = [
    "MAX_CHILDREN",
    "PLACES",
    "START",
    "DriverServer",
    "InProcessLink",
    "Stepper",
    "config_record",
    "probe_in_process",
]

#: Where simulated time starts (ns since the epoch: 2023-11-14, within what the machine accepts).
START = 1_700_000_000 * 1_000_000_000
_SECOND = 1_000_000_000
#: The most children the link simulates at once: the machine runs one; a server under test that
#: starts more (a broken one) gets no more than these, so that it cannot fill memory.
MAX_CHILDREN = 16
#: The places the probe sends the robot to where none is given: the simulated map takes any place
#: when none is configured.
PLACES = ["pantry", "lounge"]

#: A server as the link drives it: one input applied, its outputs in order.
Stepper = Callable[[ins.Input], Sequence[outs.Output]]


class _Child:
    """A running simulated child: the adapter's handle on it (on the link's clock), when it began,
    and what it does."""

    def __init__(self, link: InProcessLink, start: outs.StartChild) -> None:
        self.execution = ChildExecution(link, start, lambda: link.now)
        self.began = link.now
        self.simulation = SimulatedChild(start.category, start.parsed, link.config, link.whereabouts)


class InProcessLink(Link):
    """The machine as ``dynevent serve`` runs ``robot`` of ``config`` (its first robot by default), on
    simulated time, with a run begun; ``stepper`` replaces the machine (the server under test);
    ``wall`` is the real clock (seconds) the run's deadline is counted on too, and ``ends_at`` when
    it passes, when it runs from before the link (the run's first begin is within it)."""

    def __init__(
        self,
        config: ServeConfig | None = None,
        *,
        robot: str | None = None,
        trace: TraceWriter | None = None,
        stepper: Stepper | None = None,
        wall: Callable[[], float] = time.monotonic,
        ends_at: float = math.inf,
    ) -> None:
        self.config = ServeConfig() if config is None else config
        self._wall = wall
        robot = self.config.robots[0] if robot is None else robot
        super().__init__(self.config.fleet, robot, trace)
        self.ends_at = ends_at
        self.now = START
        first = self.config.first_state(robot)
        self._server = RobotServer(self.fleet, robot, machine_config(self.config), first)
        self._apply: Stepper = self._server.step if stepper is None else stepper
        self._agenda: list[tuple[int, int, Callable[[], None]]] = []
        self._order = itertools.count()
        self._outbox: collections.deque[outs.Output] = collections.deque()
        self._exchanges: dict[str, Exchange] = {}
        self._ended: set[str] = set()  # the goals the server answered: a cancel of one is refused so
        self._children: dict[int, _Child] = {}
        self.whereabouts = Whereabouts()  # where the robot stands, as its children leave it
        self._latest: DynamicEventStatus | None = None
        self.step(ins.Begin(description=DEFAULT_DESCRIPTION, event_id=1, now=self.now))
        self._drain()

    # ---------------------------------------------------------------- the server's side

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        """Apply ``event`` to the server; its outputs join those to carry out (the child handles step
        through here, as a binding's do)."""
        outputs = self._ask(event)
        self._outbox.extend(outputs)
        self._ended.update(output.goal_uuid for output in outputs if isinstance(output, outs.AnswerGoal))
        return outputs

    def _ask(self, event: ins.Input) -> tuple[outs.Output, ...]:
        """The server's outputs for ``event``; none once the run's deadline has passed in real time,
        nor when it passed while the server was at it (:attr:`cut_off` says so)."""
        if self.time_left() <= 0:
            self.cut_off = True
            return ()
        outputs = tuple(self._apply(event))
        if self.time_left() <= 0:
            self.cut_off = True
            return ()
        return outputs

    def _drain(self) -> None:
        while self._outbox:
            self._carry_out(self._outbox.popleft())

    def _carry_out(self, output: outs.Output) -> None:
        exchange = self._exchanges.get(getattr(output, "goal_uuid", ""))
        if isinstance(output, outs.PublishStatus):
            self._latest = output.message
            self.hear_status(output.message)
        elif isinstance(output, outs.PublishBegin):
            self.hear_begin(output.message)
        elif isinstance(output, outs.PublishFeedback) and exchange is not None:
            self.hear_feedback(exchange, output.feedback)
        elif isinstance(output, outs.AnswerGoal) and exchange is not None:
            self.hear_answer(exchange, output.status, output.result)
        elif isinstance(output, outs.StartChild):
            if output.id in self._children or len(self._children) >= MAX_CHILDREN:
                return  # a server that starts a child twice, or without end, runs no more of them
            child = _Child(self, output)
            self._children[output.id] = child
            self._report_later(output.id, child)
        elif isinstance(output, (outs.CancelChild, outs.KillChild)):
            stopped = self._children.get(output.id)
            if stopped is not None:
                stopped.execution.stop(isinstance(output, outs.KillChild))
        elif isinstance(output, outs.DynamicEventFinished) and self.config.rebegin > 0:
            self._at(self.now + round(self.config.rebegin * _SECOND), self._begin_again)

    def _report_later(self, child_id: int, child: _Child) -> None:
        def report() -> None:
            if self._children.get(child_id) is not child:
                return
            if child.simulation.report(child.execution, (self.now - child.began) / _SECOND):
                del self._children[child_id]
            else:
                self._report_later(child_id, child)

        self._at(self.now + round(child.simulation.period * _SECOND), report)

    def _begin_again(self) -> None:
        self.step(ins.Begin(description=DEFAULT_DESCRIPTION, event_id=1, now=self.now))

    def _at(self, when: int, action: Callable[[], None]) -> None:
        heapq.heappush(self._agenda, (when, next(self._order), action))

    # ---------------------------------------------------------------- the link

    def clock(self) -> float:
        return (self.now - START) / _SECOND

    def real_time(self) -> float:
        return self._wall()

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Run what is due, in time order, until ``condition()`` holds, ``timeout`` seconds of
        simulated time have passed, or the run's deadline in real time."""
        # rounded up: a wait of any positive length lets time pass, so a loop of short waits ends
        end = self.now + (max(math.ceil(timeout * _SECOND), 1) if timeout > 0 else 0)
        while not condition():
            if self.time_left() <= 0:
                self.cut_off = True
                return condition()
            if not self._agenda or self._agenda[0][0] > end:
                self.now = max(self.now, end)
                return condition()
            when, _, action = heapq.heappop(self._agenda)
            self.now = max(self.now, when)
            action()
            self._drain()
        return True

    def wait_for_server(self, timeout: float) -> bool:
        return True

    def late_subscriber(self) -> threading.Event:
        heard = threading.Event()
        if self._latest is not None:
            heard.set()
        return heard

    def send(self, goal: Goal) -> Exchange:
        exchange = Exchange(goal, self)
        self._exchanges[exchange.uuid] = exchange
        self.sent("goal", goal_uuid=exchange.uuid, message=goal)
        self.deliver(exchange)
        return exchange

    def deliver(self, exchange: Exchange) -> None:
        """The server receives ``exchange``'s goal, now (a link whose requests lag calls it later)."""
        outputs = self.step(ins.GoalRequested(goal_uuid=exchange.uuid, goal=exchange.goal, now=self.now))
        if self.cut_off:  # no response heard: the server was not asked, or not waited for
            return
        accepted = any(isinstance(output, outs.GoalAccepted) for output in outputs)
        self._drain()
        exchange.accepted_at = self.now if accepted else None
        self.hear_response(exchange, accepted)
        if accepted:  # handed over for execution now, after what else is asked now (R5.2's race)
            self._at(self.now, lambda: self._start(exchange.uuid))

    def _start(self, uuid: str) -> None:
        """Goal ``uuid``, accepted, is handed over for execution (rclpy's ``handle_accepted``): at the
        first wait after its acceptance, so that a goal sent with it is asked for first, as a server
        with an executor of its own may take it."""
        self.step(ins.GoalStarted(goal_uuid=uuid, now=self.now))

    def cancel(self, exchange: Exchange, timeout: float) -> bool | None:
        self.sent("cancel_request", goal_uuid=exchange.uuid)
        outputs = self.step(ins.CancelRequested(goal_uuid=exchange.uuid, now=self.now))
        response = next((output for output in outputs if isinstance(output, outs.CancelResponse)), None)
        if response is not None:  # the response first: rclpy answers the cancel before its effects
            # a goal the server had answered is refused as terminated, from the goal's own state, as
            # rcl_action does (ERROR_GOAL_TERMINATED), whatever the server's refusal says
            terminated = not response.accepted and exchange.uuid in self._ended
            self.hear_cancel_response(exchange, response.accepted, terminated=terminated)
        self._drain()
        return None if response is None else response.accepted

    interrupts = True

    def interrupt(self) -> str:
        self.step(ins.Interrupt(now=self.now))
        self._drain()
        return ""

    def resume(self) -> str:
        self.step(ins.Resume(now=self.now))
        self._drain()
        return ""

    def describe(self, timeout: float) -> tuple[Any, str]:
        if not self.config.offers_description:  # as serve: none in rmf_ros2 mode (D17)
            return None, f"no description service {description_service(self.fleet, self.robot)}"
        outputs = self._ask(ins.DescriptionQuery(now=self.now))
        answer = next((output for output in outputs if isinstance(output, outs.DescriptionAnswer)), None)
        if answer is None:
            return None, "the description query gave no answer"
        return answer.response, ""


def config_record(config: ServeConfig) -> dict[str, Any]:
    """The machine's configuration of serve's robots (:func:`~dynevent.sim.config.machine_config`) as
    the driver protocol's configuration record: the field's categories as ``{"accept": "field"}``
    with the configured map and actions, the others as ``{"accept": "any"}``."""
    machine = machine_config(config)
    field: dict[str, Any] = {"accept": "field"}
    if config.places is not None:
        field["places"] = list(config.places)
    if config.actions is not None:
        field["actions"] = list(config.actions)
    record: dict[str, Any] = {
        "categories": {
            name: dict(field) if name in descriptions.CATEGORIES else {"accept": "any"}
            for name in config.categories
        }
    }
    for attribute in attrs.fields(ServerConfig):
        if attribute.name != "categories":
            value = getattr(machine, attribute.name)
            record[attribute.name] = getattr(value, "value", value)
    return record


class DriverServer:
    """An implementation behind the driver protocol (``dynevent vectors --impl``'s), as the in-process
    link's server: reset once for the robot, at the seq before ``config``'s first run, then each input
    applied.  Once it breaks the protocol (dies, stalls, answers what is not a record) it says
    nothing more, and :attr:`broken` says why; a request the run's deadline kept or cut short
    (:class:`~dynevent.errors.DeadlinePassed`) gives nothing, and is no break.

    The reset holds no state object (``"state": null``) when the robot starts at seq 0, else one
    whose only field is ``seq``: the one state object docs/conformance.md section 5 says a driver
    must take."""

    def __init__(
        self, implementation: vectors_runner.Implementation, fleet: str, robot: str, config: ServeConfig
    ) -> None:
        self.implementation = implementation
        self.broken: str | None = None
        seq = config.first_state(robot).seq
        state = {"seq": seq} if seq else None
        try:
            implementation.reset(fleet, robot, config_record(config), state)
        except ImplementationError as exc:
            if state is None:
                raise
            raise ImplementationError(
                f'{exc} (the reset held the state {{"seq": {seq}}}, so that the first begin gives seq '
                f"{config.first_seq}: a driver must take a state object holding only a seq, "
                "docs/conformance.md section 5; --first-seq 1 sends none)"
            ) from None

    def __call__(self, event: ins.Input) -> tuple[outs.Output, ...]:
        if self.broken is not None:
            return ()
        try:
            outputs, _ = self.implementation.apply(input_to_json(event))
            return tuple(
                output_from_json(output, f"$.outputs[{index}]") for index, output in enumerate(outputs)
            )
        except DeadlinePassed:
            return ()
        except (ImplementationError, InvalidRecord) as exc:
            self.broken = f"{type(event).__name__}: {exc}"
            return ()


def probe_in_process(
    options: Options,
    cases: list[Case],
    say: Callable[[str], None],
    config: ServeConfig | None = None,
    *,
    write: probe_runner.ReportWriter,
    stepper: Stepper | None = None,
    implementation: vectors_runner.Implementation | None = None,
    wall: Callable[[], float] = time.monotonic,
) -> tuple[int, list[CaseFinding]]:
    """Run ``cases`` against the machine as serve runs ``config``'s robot (or ``stepper``, or
    ``implementation`` behind the driver protocol), judge every record of the exchange, hand the
    reports ``options`` asks for to ``write`` (the command's writer), and say last what the run took
    (on ``wall``, and in simulated time); the exit status and the findings."""
    config = ServeConfig() if config is None else config
    # the deadline runs from the server found: an implementation's reset and first begin are within it
    began = wall()
    ends_at = began + options.deadline
    if isinstance(implementation, vectors_runner.ExternalImplementation):
        implementation.time_left = lambda: ends_at - wall()  # no request waits past the deadline
    server = None
    if implementation is not None:
        stepper = server = DriverServer(implementation, config.fleet, options.robot, config)
    trace = TraceWriter(options.trace, fleet=options.fleet, robot=options.robot, keep=True)
    try:
        link = InProcessLink(
            config, robot=options.robot, trace=trace, stepper=stepper, wall=wall, ends_at=ends_at
        )
        findings = probe_runner.run_cases(link, options, cases, say)
        took = link.real_time() - began
    finally:
        trace.close()
    code, findings = probe_runner.conclude(findings, trace.text(), options, say, write)
    if server is not None and server.broken is not None:
        say(f"the implementation broke the driver protocol at {server.broken}")
        # a break is the implementation's failure wherever it fell: at a request, a case fails with it;
        # at another input (a child's end, a tick), the cases after it are not run, and the run fails
        code = probe_cases.EXIT_FAILED
    say(probe_runner.took(took, options, simulated=link.clock()))
    return code, findings
