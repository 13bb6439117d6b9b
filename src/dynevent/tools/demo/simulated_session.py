"""A simulated session: one client machine and one server machine in one process, over a simulated
network, deterministic under a seed.

:class:`SimulatedSession` wires a :class:`~dynevent.client.ClientState` to a server
:class:`~dynevent.server.machine.State` the way a ROS 2 binding would, through a
queue of timed deliveries:

- a goal the client sends becomes a ``GoalRequested`` input of the server;
- ``GoalAccepted`` / ``GoalRejected`` go back to the client as its goal
  response, and an accepted goal is then handed to the server as
  ``GoalStarted`` (the ROS ``handle_accepted`` moment), possibly after other
  goals were accepted;
- ``PublishFeedback``, ``AnswerGoal``, ``PublishStatus`` and ``PublishBegin``
  go to the client as feedback, terminal answers, status messages and begin
  descriptions;
- the child commands (``StartChild``, ``CancelChild``, ``KillChild``...) go to
  a scripted :class:`Adapter`, which answers with ``ChildProgress`` and
  ``ChildFinished`` inputs after the delays of its :class:`ChildScript`;
- the client is ticked at its deadlines (:func:`dynevent.client.next_deadline`).

:class:`Options` add message delay, reordering of concurrent goal requests and
of ``GoalStarted`` deliveries (so that two NEXT goals can both be accepted
before either starts: one wins, the other is aborted with ``race condition``),
dropped feedback, and ROS-style rejections without a reason.  All randomness
comes from one ``random.Random(seed)`` held here; the machines never see it,
so a session is replayed exactly by its seed and its calls.

Messages on one topic or channel keep their order (the status topic, the
begin topic, and the action's responses, feedback and results); goal requests
and goal starts keep theirs unless ``reorder`` is set.

Every delivery, command and adapter effect is recorded in :attr:`SimulatedSession.timeline`
as a :class:`TimelineEvent` (time, direction, kind, summary, decision, JSON
record), printable with :func:`format_timeline` and writable as JSON lines
with :func:`timeline_jsonl`.  Directions are ``"client"`` (commands and what
the client concluded), ``"client->server"``, ``"server->client"`` and
``"adapter"`` (the task, the binding and the child events).

This is a test and demonstration harness: adapter authors wire
:mod:`dynevent.server.machine` (or :mod:`dynevent.server.holder`) to their robot and do not
need it.
"""

from __future__ import annotations

import heapq
import itertools
import random
from collections.abc import Callable, Iterable
from typing import Any

import attrs

from dynevent import client as cl
from dynevent.client import SECOND, ClientOutput, ClientState, ClientTransition, Outcome
from dynevent.errors import InvalidValue
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.wire import _json
from dynevent.wire._codec import encode
from dynevent.wire._text import answer_text, goal_text, status_text
from dynevent.wire.messages import DynamicEventDescription, Goal, Time
from dynevent.wire.units import to_nanoseconds
from dynevent.wire.vocab import Status

__all__ = [
    "Adapter",
    "ChildScript",
    "Options",
    "SimulatedSession",
    "TimelineEvent",
    "format_timeline",
    "timeline_jsonl",
]

_STATUSES = frozenset(status.value for status in Status)


def _status(value: Any) -> str:
    plain = value.value if isinstance(value, Status) else value
    if plain not in _STATUSES:
        raise ValueError(f"expected one of the task statuses {sorted(_STATUSES)}, got {value!r}")
    return str(plain)


def _reports(value: Any) -> tuple[tuple[float, str], ...]:
    result = []
    for index, item in enumerate(value):
        delay, status = item
        to_nanoseconds("ChildScript", f"reports[{index}]", delay)
        result.append((delay, _status(status)))
    return tuple(result)


def _seconds(instance: object, attribute: attrs.Attribute[Any], value: Any) -> None:
    """A duration in seconds (:mod:`dynevent.wire.units`); None where the field allows it."""
    if value is not None:
        to_nanoseconds(type(instance).__name__, attribute.name, value)


def _ns(seconds: float) -> int:
    """A checked duration as the nanoseconds of the session's clock."""
    return round(seconds * SECOND)


@attrs.frozen(kw_only=True)
class ChildScript:
    """How one child event behaves, in seconds after the moment it is told something.

    ``reports`` are ``(delay after start, status)`` progress reports, each
    with a log line; the child ends ``final_status`` ``finish_after`` its
    start (never by itself when ``None``).  Told to cancel, it ends
    ``canceled`` ``cancel_after`` later; told to stop (kill), ``killed``
    ``kill_after`` later.  Whichever end comes first counts.
    """

    reports: tuple[tuple[float, str], ...] = attrs.field(
        default=((0.5, Status.UNDERWAY.value),), converter=_reports
    )
    finish_after: float | None = attrs.field(default=2.0, validator=_seconds)
    final_status: str = attrs.field(default=Status.COMPLETED.value, converter=_status)
    cancel_after: float = attrs.field(default=0.1, validator=_seconds)
    kill_after: float = attrs.field(default=0.0, validator=_seconds)


def _scripts(value: Iterable[ChildScript]) -> tuple[ChildScript, ...]:
    scripts = tuple(value)
    if not all(isinstance(script, ChildScript) for script in scripts):
        raise ValueError(f"expected ChildScript values, got {scripts!r}")
    return scripts


@attrs.frozen(kw_only=True)
class Adapter:
    """A scripted fleet adapter: the n-th child started follows ``scripts[n]``, later ones ``default``.

    :meth:`react` answers one server output with the server inputs to
    deliver later.  It is a pure policy; the session drops an input whose
    child is no longer the running one when it comes due.
    """

    scripts: tuple[ChildScript, ...] = attrs.field(default=(), converter=_scripts)
    default: ChildScript = ChildScript()

    def script(self, index: int) -> ChildScript:
        """The script of the ``index``-th child started in the session (from 0)."""
        return self.scripts[index] if index < len(self.scripts) else self.default

    def react(self, output: outs.Output, *, now: int, index: int) -> tuple[tuple[int, ins.Input], ...]:
        """The ``(instant, input)`` pairs that answer ``output``, for the ``index``-th child."""
        script = self.script(index)
        if isinstance(output, outs.StartChild):
            planned: list[tuple[int, ins.Input]] = []
            for delay, status in script.reports:
                at = now + _ns(delay)
                text = f"child {output.id}: {status}"
                planned.append((at, ins.ChildProgress(status=status, log_text=text, now=at)))
            if script.finish_after is not None:
                at = now + _ns(script.finish_after)
                planned.append((at, ins.ChildFinished(status=script.final_status, now=at)))
            return tuple(planned)
        if isinstance(output, outs.CancelChild):
            at = now + _ns(script.cancel_after)
            return ((at, ins.ChildFinished(status=Status.CANCELED, now=at)),)
        if isinstance(output, outs.KillChild):
            at = now + _ns(script.kill_after)
            return ((at, ins.ChildFinished(status=Status.KILLED, now=at)),)
        return ()


def _range(instance: object, attribute: attrs.Attribute[Any], value: Any) -> None:
    low, high = value
    owner = type(instance).__name__
    if to_nanoseconds(owner, attribute.name, low) > to_nanoseconds(owner, attribute.name, high):
        raise InvalidValue(owner, attribute.name, value, "expected (low, high) seconds with low <= high")


def _probability(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise ValueError(f"expected a probability in [0, 1], got {value!r}")
    return float(value)


@attrs.frozen(kw_only=True)
class Options:
    """How the session's simulated network behaves; every random draw comes from the session's seed.

    ``delay``: each message takes a uniformly drawn ``[low, high]``
    seconds (drawn in whole nanoseconds).  ``start_delay``: an accepted goal starts that long after
    its acceptance.  ``reorder``: goal requests and goal starts may overtake
    each other (they keep their order otherwise).  ``drop_feedback``: the
    probability that a feedback message is lost.  ``ros_rejections``:
    rejections reach the client without a reason, as over ROS.
    """

    delay: tuple[float, float] = attrs.field(default=(0, 0), validator=_range)
    start_delay: tuple[float, float] = attrs.field(default=(0, 0), validator=_range)
    reorder: bool = False
    drop_feedback: float = attrs.field(default=0.0, converter=_probability)
    ros_rejections: bool = False


@attrs.frozen(kw_only=True)
class TimelineEvent:
    """One line of the session's timeline.

    ``time`` in nanoseconds; ``direction`` one of ``"client"``,
    ``"client->server"``, ``"server->client"``, ``"adapter"``; ``kind`` the
    input, output or command (``"goal_requested"``, ``"publish_status"``,
    ``"request_next"``...); ``summary`` one human line; ``decision`` what the
    receiver made of it (``"accepted"``, ``"rejected: busy"``, ``"dropped"``...);
    ``record`` the JSON record of the message or output; ``outputs``, for an
    input of the server, the machine's outputs of that step (each with its
    ``rule``), for tools that read what the server decided as values, not text.
    """

    time: int
    direction: str
    kind: str
    summary: str
    decision: str = ""
    record: dict[str, Any] = attrs.field(factory=dict, eq=False, hash=False)
    outputs: tuple[outs.Output, ...] = attrs.field(default=(), eq=False, hash=False)

    def to_dict(self) -> dict[str, Any]:
        """The event as plain JSON values."""
        return {
            "time": self.time,
            "direction": self.direction,
            "kind": self.kind,
            "summary": self.summary,
            "decision": self.decision,
            "record": self.record,
        }


def format_timeline(events: Iterable[TimelineEvent]) -> str:
    """The timeline as aligned text, one event per line (seconds, direction, kind, summary, decision)."""
    lines = []
    for event in events:
        line = f"{event.time / SECOND:9.3f}  {event.direction:<14}  {event.kind:<20}  {event.summary}"
        if event.decision:
            line += f"  -> {event.decision}"
        lines.append(line)
    return "\n".join(lines) + ("\n" if lines else "")


def timeline_jsonl(events: Iterable[TimelineEvent]) -> str:
    """The timeline as JSON lines, one object per event."""
    return "".join(_json.dumps(event.to_dict()) + "\n" for event in events)


# --------------------------------------------------------------------------- summaries


def _record(kind: str, value: Any) -> dict[str, Any]:
    record: dict[str, Any] = {"type": kind}
    record.update(encode(value))
    return record


def _short(uuid: str) -> str:
    return f"{uuid[:4]}..{uuid[-4:]}"


def _client_text(output: ClientOutput) -> str:
    if isinstance(output, cl.SendGoal):
        return f"send {_short(output.goal_uuid)}"
    if isinstance(output, cl.Refused):
        return f"refused: {output.rejection.reason.value} ({output.rejection.text})"
    if isinstance(output, cl.Outcome):
        detail = output.reason.value if output.reason is not None else output.status
        shown = detail and detail != output.kind.value
        return f"outcome {output.kind.value}" + (f" ({detail})" if shown else "")
    if isinstance(output, cl.Progress):
        return f"progress {output.status} id={output.id}"
    if isinstance(output, cl.RunBegan):
        return f"run {output.seq} began"
    if isinstance(output, cl.ViewChanged):
        return f"view {output.phase.name} seq={output.seq} id={output.current_id}"
    if isinstance(output, cl.TimedOut):
        return f"timed out {_short(output.goal_uuid)}"
    if isinstance(output, cl.AskResult):
        return f"ask again for {_short(output.goal_uuid)}'s result"
    if isinstance(output, cl.OutOfContact):
        return "out of contact"
    if isinstance(output, cl.BackInContact):
        return "back in contact"
    return f"ignored: {output.why}"


def _server_text(output: outs.Output) -> str:
    if isinstance(output, outs.GoalAccepted):
        return "accepted"
    if isinstance(output, outs.GoalRejected):
        return f"rejected: {output.rejection.reason.value} ({output.rejection.text})"
    if isinstance(output, outs.AnswerGoal):
        return answer_text(output.status.value, output.result)
    if isinstance(output, outs.Ignored):
        return f"ignored: {output.why}"
    if isinstance(output, outs.StartChild):
        return f"start child {output.id}"
    return output.KIND


_QUIET = frozenset({"execute_goal", "publish_feedback", "publish_status", "publish_begin", "log"})

# Outputs that the adapter (or the task) acts on, recorded as adapter events when they happen.
_ADAPTER_EFFECTS = (
    outs.StartChild,
    outs.CancelChild,
    outs.KillChild,
    outs.InterruptChild,
    outs.ResumeChild,
    outs.StubbornBegin,
    outs.StubbornHold,
    outs.StubbornDelay,
    outs.StubbornEnd,
    outs.DynamicEventFinished,
    outs.InterruptConfirmed,
    outs.SeqWrapped,
    outs.StubbornClamped,
)


def _effect_text(output: outs.Output) -> str:
    if isinstance(output, outs.StartChild):
        return f"child {output.id} {output.category} {output.description}"
    if isinstance(output, (outs.CancelChild, outs.KillChild, outs.InterruptChild, outs.ResumeChild)):
        return f"child {output.id}"
    if isinstance(output, outs.DynamicEventFinished):
        return output.status
    if isinstance(output, (outs.StubbornBegin, outs.StubbornHold)):
        return f"hold {output.period:g} s"
    if isinstance(output, outs.StubbornDelay):
        return f"delay {output.delay:g} s"
    if isinstance(output, outs.SeqWrapped):
        return f"{output.previous} -> {output.seq}"
    if isinstance(output, outs.StubbornClamped):
        return f"{output.requested:g} s -> {output.applied:g} s"
    return ""


# --------------------------------------------------------------------------- the session


@attrs.frozen
class _Delivery:
    """One scheduled delivery: ``kind`` is goal, start, adapter, client or tick."""

    kind: str
    payload: Any
    goal_uuid: str = ""
    tag: tuple[int, int] | None = None


#: The wire message each client input stands for, in the timeline.
_DELIVERY_KINDS: dict[type, str] = {
    cl.BeginReceived: "publish_begin",
    cl.StatusReceived: "publish_status",
    cl.GoalResponse: "goal_response",
    cl.FeedbackReceived: "publish_feedback",
    cl.ResultReceived: "answer_goal",
}


def _input_text(event: ins.Input) -> str:
    """One line for a task, adapter or binding input."""
    if isinstance(event, ins.Begin):
        return f"event {event.event_id} {event.description}"
    if isinstance(event, (ins.ChildProgress, ins.ChildFinished)):
        return event.status
    if isinstance(event, (ins.GoalStarted, ins.GoalRequested, ins.CancelRequested)):
        return _short(event.goal_uuid)
    return ""


def _delivery_text(event: cl.ClientInput) -> str:
    """One line for a message delivered to the client."""
    if isinstance(event, cl.StatusReceived):
        return status_text(event.message)
    if isinstance(event, cl.BeginReceived):
        return f"seq={event.message.dynamic_event_seq} {event.message.description}"
    if isinstance(event, cl.GoalResponse):
        return f"{_short(event.goal_uuid)} " + ("accepted" if event.accepted else "rejected")
    if isinstance(event, cl.FeedbackReceived):
        return f"{_short(event.goal_uuid)} {event.feedback.status} id={event.feedback.id}"
    if isinstance(event, cl.ResultReceived):
        result = event.result
        detail = result.execution_failure or f"{result.status} id={result.id}"
        return f"{_short(event.goal_uuid)} {event.status.value}: {detail}"
    return ""


class _Wire:
    """The simulated transport: deliveries queued by time, channels kept in order, seeded draws.

    Everything random in a session is drawn here, in the order the session asks, so the same seed
    gives the same session.
    """

    def __init__(self, options: Options, seed: int) -> None:
        self.options = options
        self.rng = random.Random(seed)
        self._queue: list[tuple[int, float, int, _Delivery]] = []
        self._order = itertools.count()
        self._channels: dict[str, int] = {}

    def draw(self, bounds: tuple[float, float]) -> int:
        """A delay in nanoseconds, drawn from ``bounds`` in seconds."""
        low, high = _ns(bounds[0]), _ns(bounds[1])
        return low if low == high else self.rng.randint(low, high)

    def schedule(self, at: int, delivery: _Delivery, channel: str | None, shuffle: bool = False) -> None:
        """Queue ``delivery`` at ``at``; a channel keeps its deliveries in order unless shuffled."""
        mixed = shuffle and self.options.reorder
        if channel is not None and not mixed:
            at = max(at, self._channels.get(channel, at))
            self._channels[channel] = at
        tiebreak = self.rng.random() if mixed else 0.0
        heapq.heappush(self._queue, (at, tiebreak, next(self._order), delivery))

    def send(
        self, now: int, delay: tuple[float, float], delivery: _Delivery, channel: str, shuffle: bool = False
    ) -> None:
        """Queue ``delivery`` a drawn ``delay`` after ``now``."""
        self.schedule(now + self.draw(delay), delivery, channel, shuffle)

    def next_at(self) -> int | None:
        """When the next delivery falls due (``None`` when nothing is queued)."""
        return self._queue[0][0] if self._queue else None

    def pop(self) -> tuple[int, _Delivery]:
        at, _, _, delivery = heapq.heappop(self._queue)
        return at, delivery

    def deliveries(self) -> list[tuple[int, _Delivery]]:
        """What is queued, in delivery order."""
        return [(at, delivery) for at, _, _, delivery in sorted(self._queue)]


class SimulatedSession:
    """One client machine and one server machine, wired in-process; see the module docs.

    ``client`` and ``server`` are the current states (frozen values, replaced
    at each step); ``now`` the session's time in nanoseconds; ``timeline``
    every event so far; ``outcomes`` every outcome the client reported.  At
    construction the client is sent the server's current status message (and
    its begin description, when a run is active), as transient-local topics
    give a client that joins late.

    ``on_send``, when given, is called with the session and each goal the
    client emits, before it is put on the wire: the server state and what is
    in flight are then exactly those the goal meets when it leaves.
    """

    def __init__(
        self,
        client: ClientState,
        server: State,
        config: ServerConfig | None = None,
        *,
        adapter: Adapter | None = None,
        options: Options | None = None,
        seed: int = 0,
        now: int = 0,
        on_send: Callable[[SimulatedSession, cl.SendGoal], None] | None = None,
    ) -> None:
        self.client = client
        self.server = server
        self.config = config if config is not None else ServerConfig()
        self.adapter = adapter if adapter is not None else Adapter()
        self.options = options if options is not None else Options()
        self.now = cl.Tick(now=now).now  # checked like any input's now
        self.on_send = on_send
        self.timeline: list[TimelineEvent] = []
        self.outcomes: list[Outcome] = []
        self._wire = _Wire(self.options, seed)
        self._ticks: set[int] = set()
        self._children: dict[tuple[int, int], int] = {}
        self._foreign = itertools.count()
        self._ours: set[str] = set()
        if server.active:
            begin = DynamicEventDescription(
                fleet=server.fleet,
                robot=server.robot,
                dynamic_event_seq=server.seq,
                description=server.description,
                start_time=Time.from_nanoseconds(self.now),
            )
            self._to_client("begin", cl.BeginReceived(message=begin))
        self._to_client("status", cl.StatusReceived(message=machine.status_message(server, self.now)))

    # ------------------------------------------------------------------ scheduling

    def _to_client(self, channel: str, event: cl.ClientInput, uuid: str = "") -> None:
        self._wire.send(self.now, self.options.delay, _Delivery("client", event, uuid), channel)

    def _record(
        self,
        direction: str,
        kind: str,
        summary: str,
        decision: str,
        record: dict[str, Any],
        outputs: tuple[outs.Output, ...] = (),
    ) -> None:
        line = {"direction": direction, "kind": kind, "summary": summary, "decision": decision}
        self.timeline.append(TimelineEvent(time=self.now, record=record, outputs=outputs, **line))

    # ------------------------------------------------------------------ the client side

    def _client_step(self, transition: ClientTransition, command: str = "") -> tuple[ClientOutput, ...]:
        """Keep the client's new state, put its goals on the wire and record what it concluded."""
        self.client = transition.state
        if self.on_send is not None:
            for output in transition.outputs:
                if isinstance(output, cl.SendGoal):
                    self.on_send(self, output)
        for output in transition.outputs:
            if isinstance(output, cl.SendGoal):
                self._ours.add(output.goal_uuid)
                request = _Delivery("goal", output.goal, output.goal_uuid)
                self._wire.send(self.now, self.options.delay, request, "goal", shuffle=True)
            if command and isinstance(output, (cl.SendGoal, cl.Refused)):
                goal = output.goal
                summary = "" if goal is None else goal_text(goal)
                self._record("client", command, summary, _client_text(output), _record(output.KIND, output))
            elif isinstance(output, (cl.SendGoal, cl.Outcome, cl.TimedOut)):
                summary = goal_text(output.goal) if isinstance(output, (cl.SendGoal, cl.Outcome)) else ""
                self._record(
                    "client", output.KIND, summary, _client_text(output), _record(output.KIND, output)
                )
            if isinstance(output, cl.Outcome):
                self.outcomes.append(output)
        deadline = cl.next_deadline(self.client)
        if deadline is not None and deadline not in self._ticks:
            self._ticks.add(deadline)
            self._wire.schedule(max(deadline, self.now), _Delivery("tick", deadline), None)
        return transition.outputs

    def _command(self, kind: str, transition: ClientTransition) -> tuple[ClientOutput, ...]:
        return self._client_step(transition, kind)

    def request_next(
        self,
        category: str,
        description: str,
        *,
        stubborn_period: float = 0.0,
        timeout: float | None = None,
    ) -> tuple[ClientOutput, ...]:
        """:func:`dynevent.client.request_next` now; a goal it sends is put on the wire."""
        transition = cl.request_next(
            self.client,
            category,
            description,
            stubborn_period=stubborn_period,
            timeout=timeout,
            now=self.now,
        )
        return self._command("request_next", transition)

    def request_cancel(self) -> tuple[ClientOutput, ...]:
        """:func:`dynevent.client.request_cancel` now."""
        return self._command("request_cancel", cl.request_cancel(self.client, now=self.now))

    def request_withdraw(self, goal_uuid: str) -> tuple[ClientOutput, ...]:
        """:func:`dynevent.client.request_withdraw` now: cancel this NEXT's child once it runs."""
        return self._command("request_withdraw", cl.request_withdraw(self.client, goal_uuid, now=self.now))

    def request_finish(self) -> tuple[ClientOutput, ...]:
        """:func:`dynevent.client.request_finish` now."""
        return self._command("request_finish", cl.request_finish(self.client, now=self.now))

    def send_foreign(self, goal: Goal) -> str:
        """Send ``goal`` from another client, unknown to the client machine; returns its goal UUID.

        The server's answers to it are recorded but go nowhere: this is how
        two goals race (R5.2) with one client machine in the session.
        """
        uuid = f"{'f' * 16}{next(self._foreign):016x}"
        self._record("client", "send_foreign", goal_text(goal), f"send {_short(uuid)}", _record("goal", goal))
        self._wire.send(self.now, self.options.delay, _Delivery("goal", goal, uuid), "goal", shuffle=True)
        return uuid

    # ------------------------------------------------------------------ the server side

    def server_input(self, event: ins.Input) -> tuple[outs.Output, ...]:
        """Apply a task, adapter or binding input to the server now (its ``now`` is the caller's)."""
        return self._server_step(event, "adapter", _input_text(event))

    def begin(self, description: str = "{}", event_id: int = 0) -> tuple[outs.Output, ...]:
        """A task reaches a ``dynamic_event`` phase now."""
        return self.server_input(ins.Begin(description=description, event_id=event_id, now=self.now))

    def task_cancel(self) -> tuple[outs.Output, ...]:
        """The task is cancelled now."""
        return self.server_input(ins.TaskCancel(now=self.now))

    def task_kill(self) -> tuple[outs.Output, ...]:
        """The task is killed now."""
        return self.server_input(ins.TaskKill(now=self.now))

    def interrupt(self) -> tuple[outs.Output, ...]:
        """The task is interrupted now."""
        return self.server_input(ins.Interrupt(now=self.now))

    def resume(self) -> tuple[outs.Output, ...]:
        """The task's interruption is released now."""
        return self.server_input(ins.Resume(now=self.now))

    def shutdown(self) -> tuple[outs.Output, ...]:
        """The adapter shuts down now."""
        return self.server_input(ins.Shutdown(now=self.now))

    def _server_step(self, event: ins.Input, direction: str, summary: str) -> tuple[outs.Output, ...]:
        transition = machine.step(self.server, event, self.config)
        self.server = transition.state
        decision = "; ".join(
            _server_text(output) for output in transition.outputs if output.KIND not in _QUIET
        )
        if isinstance(event, ins.GoalStarted) and not decision:
            decision = "executing"
        if isinstance(event, ins.GoalRequested):  # a goal request is recorded as a delivery
            summary = goal_text(event.goal)
        self._record(direction, event.KIND, summary, decision, _record(event.KIND, event), transition.outputs)
        for output in transition.outputs:
            self._route(output)
        return transition.outputs

    def _route(self, output: outs.Output) -> None:
        ours = getattr(output, "goal_uuid", "") in self._ours
        if isinstance(output, outs.GoalAccepted):
            if ours:
                self._to_client("action", cl.GoalResponse(goal_uuid=output.goal_uuid, accepted=True))
            start = _Delivery("start", output.goal_uuid, output.goal_uuid)
            self._wire.send(self.now, self.options.start_delay, start, "start", shuffle=True)
        elif isinstance(output, outs.GoalRejected) and ours:
            rejection = None if self.options.ros_rejections else output.rejection
            response = cl.GoalResponse(goal_uuid=output.goal_uuid, accepted=False, rejection=rejection)
            self._to_client("action", response)
        elif isinstance(output, outs.PublishFeedback) and ours:
            event = cl.FeedbackReceived(goal_uuid=output.goal_uuid, feedback=output.feedback)
            if self.options.drop_feedback and self._wire.rng.random() < self.options.drop_feedback:
                summary = f"{output.feedback.status} id={output.feedback.id}"
                self._record(
                    "server->client", "publish_feedback", summary, "dropped", _record(event.KIND, event)
                )
            else:
                self._to_client("action", event)
        elif isinstance(output, outs.AnswerGoal) and ours:
            answer = cl.ResultReceived(goal_uuid=output.goal_uuid, status=output.status, result=output.result)
            self._to_client("action", answer)
        elif isinstance(output, outs.PublishStatus):
            self._to_client("status", cl.StatusReceived(message=output.message))
        elif isinstance(output, outs.PublishBegin):
            self._to_client("begin", cl.BeginReceived(message=output.message))
        elif isinstance(output, _ADAPTER_EFFECTS):
            self._record("adapter", output.KIND, _effect_text(output), "", _record(output.KIND, output))
            self._adapter(output)

    def _adapter(self, output: outs.Output) -> None:
        if not isinstance(output, (outs.StartChild, outs.CancelChild, outs.KillChild)):
            return
        tag = (self.server.seq, output.id)
        if isinstance(output, outs.StartChild):
            self._children.setdefault(tag, len(self._children))
        index = self._children.get(tag, len(self._children))
        for at, event in self.adapter.react(output, now=self.now, index=index):
            self._wire.schedule(max(at, self.now), _Delivery("adapter", event, tag=tag), None)

    # ------------------------------------------------------------------ time

    def _deliver(self, delivery: _Delivery) -> None:
        if delivery.kind == "goal":
            goal: Goal = delivery.payload
            event = ins.GoalRequested(goal_uuid=delivery.goal_uuid, goal=goal, now=self.now)
            self._server_step(event, "client->server", goal_text(goal))
        elif delivery.kind == "start":
            start = ins.GoalStarted(goal_uuid=delivery.payload, now=self.now)
            self._server_step(start, "adapter", _short(start.goal_uuid))
        elif delivery.kind == "adapter":
            self._adapter_input(delivery)
        elif delivery.kind == "tick":
            self._ticks.discard(delivery.payload)
            self._client_step(cl.step(self.client, cl.Tick(now=self.now)))
        else:
            self._client_delivery(delivery.payload)

    def _adapter_input(self, delivery: _Delivery) -> None:
        event: ins.Input = delivery.payload
        running = self.server.running
        tag = delivery.tag
        if running is None or not running.started or (self.server.seq, running.child_id) != tag:
            why = "the child is no longer running" if tag is None else f"child {tag[1]} is no longer running"
            self._record(
                "adapter", event.KIND, _input_text(event), f"stale: {why}", _record(event.KIND, event)
            )
            return
        self._server_step(event, "adapter", _input_text(event))

    def _client_delivery(self, event: cl.ClientInput) -> None:
        transition = cl.step(self.client, event)
        outputs = transition.outputs
        kind = _DELIVERY_KINDS.get(type(event), event.KIND)
        summary = _delivery_text(event)
        decision = "; ".join(
            _client_text(output) for output in outputs if not isinstance(output, (cl.SendGoal, cl.Outcome))
        )
        self._record("server->client", kind, summary, decision, _record(event.KIND, event))
        self._client_step(transition)

    def step(self) -> bool:
        """Deliver the next scheduled item, moving ``now`` to its time; False when nothing is scheduled."""
        if self._wire.next_at() is None:
            return False
        at, delivery = self._wire.pop()
        self.now = max(self.now, at)
        self._deliver(delivery)
        return True

    def run(self, until: int | None = None, *, limit: int = 100_000) -> None:
        """Deliver everything due up to ``until`` (everything when ``None``), then move ``now`` there.

        Raises ``RuntimeError`` after ``limit`` deliveries, so a session that
        never settles fails instead of hanging.
        """
        for _ in range(limit):
            due = self._wire.next_at()
            if due is None or (until is not None and due > until):
                break
            self.step()
        else:
            raise RuntimeError(f"the session did not settle within {limit} deliveries")
        if until is not None:
            self.now = max(self.now, until)

    def advance(self, duration: float) -> None:
        """Let ``duration`` seconds pass, delivering what falls due."""
        self.run(self.now + to_nanoseconds("SimulatedSession.advance", "duration", duration))

    # ------------------------------------------------------------------ inspection

    def pending(self) -> tuple[tuple[int, str], ...]:
        """What is scheduled, in delivery order: ``(time, kind)``.

        Kinds: ``goal`` (a goal request), ``start`` (a goal start),
        ``adapter`` (a child report), ``client`` (a message to the client),
        ``tick`` (a client deadline).
        """
        return tuple((at, delivery.kind) for at, delivery in self._wire.deliveries())

    @property
    def quiescent(self) -> bool:
        """No message is in flight: no goal request, goal start or message to the client is pending.

        The client has then seen everything the server said, and the server
        every goal the client sent, so the client's view is the server's.
        """
        return not any(
            delivery.kind in ("goal", "start", "client") for _, delivery in self._wire.deliveries()
        )

    @property
    def statuses_in_flight(self) -> bool:
        """Is a status message on its way to the client?"""
        return any(
            delivery.kind == "client" and isinstance(delivery.payload, cl.StatusReceived)
            for _, delivery in self._wire.deliveries()
        )

    def timeline_jsonl(self) -> str:
        """The timeline as JSON lines."""
        return timeline_jsonl(self.timeline)

    def format_timeline(self) -> str:
        """The timeline as aligned text."""
        return format_timeline(self.timeline)
