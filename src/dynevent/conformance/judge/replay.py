"""Replay a recorded server: drive the machine with the goals a recording's clients sent and the
events its site caused, and set what the machine says beside what the server said.

A recording of a live server (``dynevent record``, read by ``dynevent.bags.reader``) holds
two kinds of thing: what the clients did (goals, action-level cancels) and what the server said
(begin, statuses, goal responses, feedback, answers, cancel responses).  Some of what the server
said comes from its site rather than from the protocol: a task reaching its dynamic event, the
child's own progress and logs, the child's end, a task cancelled by a dispatcher.  :func:`replay`
reads those back as the machine's inputs (:func:`site_events` says how), feeds them in the
recording's order beside the clients' goals, and collects the machine's outputs.
:func:`exchange` reduces either side to the points a client can observe, and :func:`compare`
says where they differ.

The points (:class:`Exchange`): the begins (seq and description); the status sequence, a status
repeated at once counted once; each goal's response, its feedback (id and log tiers, a repeat
counted once) and its answer (goal status, result status, id, whether it failed to begin); each
action-level cancel's response.  Goals are named by their order in the recording; child ids by
their order in the run (``#1``, ``#2``; 0 stays 0), and the ids themselves are a point of their
own (``ids``), so one numbering difference is one difference, not one per status.  Timing is no
point: the machine is driven at the recording's times, and what it says is compared in order.

The clients' goals are the recording's: a recording without them (topics only) cannot be
replayed (:class:`~dynevent.errors.TraceError`).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Sequence
from typing import Any, Protocol

import attrs

from dynevent.errors import TraceError
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.wire.messages import DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.vocab import (
    TASK_SIGNAL_LOGS,
    DynamicState,
    EventType,
    IdPolicy,
    Status,
    Tier,
)

__all__ = [
    "CHANNELS",
    "Comparison",
    "Difference",
    "Exchange",
    "Observation",
    "Replayed",
    "compare",
    "compare_recording",
    "exchange",
    "replay",
    "site_events",
]

#: The points of an exchange, in the order :func:`compare` reports them.
CHANNELS = ("begins", "statuses", "ids", "responses", "feedback", "answers", "cancels")

_STATUSES = frozenset(status.value for status in Status)
_SIGNALS: dict[str, type[ins.TaskCancel] | type[ins.TaskKill]] = {
    Status.CANCELED.value: ins.TaskCancel,
    Status.KILLED.value: ins.TaskKill,
}
_TIERS = frozenset(tier.value for tier in Tier)
_SIGNAL_TEXTS = frozenset(TASK_SIGNAL_LOGS.values())
#: How long after the server acted on a request its client may record it (see :func:`replay`).
CLIENT_LAG = 50_000_000
_GOAL_KINDS = frozenset({"goal_response", "feedback", "result", "cancel_request", "cancel_response"})


class Observation(Protocol):
    """One record of a recording, as :mod:`dynevent.bags` reads it: ``kind`` is ``begin``,
    ``status``, ``goal``, ``goal_response``, ``feedback``, ``result``, ``cancel_request`` or
    ``cancel_response`` (others are skipped); ``time`` integer nanoseconds."""

    @property
    def kind(self) -> str: ...
    @property
    def time(self) -> int: ...
    @property
    def goal_uuid(self) -> str: ...
    @property
    def message(self) -> Any: ...
    @property
    def accepted(self) -> bool: ...
    @property
    def status(self) -> str: ...


@attrs.frozen
class _Said:
    """One thing a server said, in the recording's vocabulary: ``kind`` as an :class:`Observation`'s."""

    kind: str
    goal_uuid: str = ""
    message: Any = None
    accepted: bool = False
    status: str = ""


@attrs.frozen
class Exchange:
    """The points of one side of an exchange, channel by channel (see the module docs)."""

    begins: tuple[str, ...]
    statuses: tuple[str, ...]
    ids: tuple[str, ...]
    responses: tuple[str, ...]
    feedback: tuple[str, ...]
    answers: tuple[str, ...]
    cancels: tuple[str, ...]

    def channel(self, name: str) -> tuple[str, ...]:
        """The points of channel ``name`` (one of :data:`CHANNELS`)."""
        value: tuple[str, ...] = getattr(self, name)
        return value


@attrs.frozen
class Difference:
    """Where the two sides part: on ``channel``, the recorded points ``recorded`` where the machine
    said ``replayed`` (either may be empty), after ``after`` (the last point both said, or ``""``)."""

    channel: str
    after: str
    recorded: tuple[str, ...]
    replayed: tuple[str, ...]

    def __str__(self) -> str:
        where = f" after {self.after!r}" if self.after else " at the start"
        return f"{self.channel}{where}: recorded {list(self.recorded)}, replayed {list(self.replayed)}"


# --- the site, read back ----------------------------------------------------------------------


def _child_inputs(state: State, feedback: Feedback, now: int, run_ends: bool) -> list[ins.Input]:
    """What the running child did, as a feedback of its goal shows it.  A task signal's log line
    (R13.1) where the run then ends (``run_ends``) and the child was not told to stop is the task's
    signal; every other log line is the child's own (a child told to stop may write the same words:
    rmf_ros2's do, D29).  Each log line
    is the child's progress, and an ended status its end."""
    running = state.running
    if running is None or not running.started:
        return []
    texts = [entry.text for entry in feedback.logs]
    events: list[ins.Input] = []
    own = list(feedback.logs)
    if run_ends and not running.canceling and not state.task_signal:
        for status, text in TASK_SIGNAL_LOGS.items():
            if text in texts:
                events.append(_SIGNALS[status](now=now))
                own = [entry for entry in own if entry.text != text]
    status = feedback.status if feedback.status in _STATUSES else running.child_status
    ended = machine.ends_a_child(status)
    progress = running.child_status if ended else status
    events.extend(
        ins.ChildProgress(
            status=progress,
            log_text=entry.text[: ins.MAX_LOG_TEXT_LENGTH],
            tier=entry.tier if entry.tier in _TIERS else "info",
            now=now,
        )
        for entry in own
    )
    if ended:
        events.append(ins.ChildFinished(status=status, now=now))
    elif not own and status != running.child_status:
        events.append(ins.ChildProgress(status=status, now=now))
    return events


def site_events(state: State, records: Sequence[Observation], index: int) -> list[ins.Input]:
    """The inputs a server's site gave it, read from ``records[index]`` (a record the server
    published), in ``state`` (the machine's, so far):

    - a begin is the task reaching its dynamic event, whose id is the one the run's first status
      names;
    - a feedback of the goal whose child runs is that child's progress, its end, or a task signal
      where the run then ends (:func:`_child_inputs`); that goal's answer, when no feedback showed
      the end, is the child's end;
    - a status that ends the run (INACTIVE) while the machine's run goes on is the task cancelled
      by its site.
    """
    record = records[index]
    now = record.time
    if record.kind == "begin":
        first = _first_status(records, index)
        return [
            ins.Begin(
                description=record.message.description, event_id=0 if first is None else first.id, now=now
            )
        ]
    running = state.running
    if record.kind == "feedback" and running is not None and record.goal_uuid == running.goal_uuid:
        return _child_inputs(state, record.message, now, _run_ends(records, index, state.seq))
    if record.kind == "result" and running is not None and record.goal_uuid == running.goal_uuid:
        result: Result = record.message
        if running.started and not result.execution_failure and machine.ends_a_child(result.status):
            return [ins.ChildFinished(status=result.status, now=now)]
        return []
    if record.kind == "status" and state.active:
        status: DynamicEventStatus = record.message
        if status.dynamic_state == DynamicState.INACTIVE.value and status.dynamic_event_seq == state.seq:
            return [ins.TaskCancel(now=now)] if not state.task_signal else []
    return []


def _run_ends(records: Sequence[Observation], index: int, seq: int) -> bool:
    """Whether run ``seq`` ends after ``records[index]`` with no client asking: a status says INACTIVE
    before any FINISHED of the run."""
    for record in records[index + 1 :]:
        if record.kind == "goal" and record.message.event_type == EventType.FINISHED.value:
            return False
        message = record.message
        if (
            record.kind == "status"
            and message.dynamic_event_seq == seq
            and message.dynamic_state == DynamicState.INACTIVE.value
        ):
            return True
    return False


def _early_end(record: Observation) -> bool:
    """Whether a server's record shows a child or a run ended early: what a CANCEL or a FINISHED
    causes (a canceled or killed status, a task signal's line, an INACTIVE status)."""
    if record.kind == "status":
        message: DynamicEventStatus = record.message
        return message.dynamic_state == DynamicState.INACTIVE.value or machine.ends_early(message.status)
    if record.kind == "feedback":
        feedback: Feedback = record.message
        return machine.ends_early(feedback.status) or any(
            entry.text in _SIGNAL_TEXTS for entry in feedback.logs
        )
    return False


def _caused_by_a_goal(records: Sequence[Observation], index: int, state: State) -> int | None:
    """The index of the goal whose request a client recorded up to :data:`CLIENT_LAG` after
    ``records[index]``, a record of its effect: a CANCEL of the child a canceled status or feedback
    names, or a FINISHED of the run an INACTIVE status ends.  A client's introspection stamps a
    request after sending it, so the server may act on it first."""
    record = records[index]
    if not _early_end(record):
        return None
    running = state.running
    if record.kind == "feedback" and (running is None or record.goal_uuid != running.goal_uuid):
        return None
    ends_run = record.kind == "status" and record.message.dynamic_state == DynamicState.INACTIVE.value
    limit = record.time + CLIENT_LAG
    for later in range(index + 1, len(records)):
        goal = records[later]
        if goal.time > limit:
            break
        if goal.kind != "goal" or goal.message.dynamic_event_seq != state.seq:
            continue
        if ends_run and goal.message.event_type == EventType.FINISHED.value:
            return later
        if (
            not ends_run
            and goal.message.event_type == EventType.CANCEL.value
            and goal.message.id == record.message.id
        ):
            return later
    return None


def _first_status(records: Sequence[Observation], index: int) -> DynamicEventStatus | None:
    """The first status of the run whose begin is ``records[index]``."""
    seq = records[index].message.dynamic_event_seq
    for record in records[index + 1 :]:
        if record.kind == "status" and record.message.dynamic_event_seq == seq:
            message: DynamicEventStatus = record.message
            return message
        if record.kind == "begin":
            break
    return None


# --- the replay -------------------------------------------------------------------------------


def _said(output: outs.Output) -> _Said | None:
    """What a client observes of one machine output, in the recording's vocabulary; None for an
    output only the adapter sees."""
    if isinstance(output, outs.PublishBegin):
        return _Said("begin", message=output.message)
    if isinstance(output, outs.PublishStatus):
        return _Said("status", message=output.message)
    if isinstance(output, outs.GoalAccepted):
        return _Said("goal_response", goal_uuid=output.goal_uuid, accepted=True)
    if isinstance(output, outs.GoalRejected):
        return _Said("goal_response", goal_uuid=output.goal_uuid, accepted=False)
    if isinstance(output, outs.PublishFeedback):
        return _Said("feedback", goal_uuid=output.goal_uuid, message=output.feedback)
    if isinstance(output, outs.AnswerGoal):
        return _Said("result", goal_uuid=output.goal_uuid, message=output.result, status=output.status.value)
    if isinstance(output, outs.CancelResponse):
        return _Said("cancel_response", goal_uuid=output.goal_uuid, accepted=output.accepted)
    return None


class _Replay:
    """The machine, driven: each input at its time, after the time that passed (a tick)."""

    def __init__(self, state: State, config: ServerConfig) -> None:
        self.state = state
        self.config = config
        self.said: list[_Said] = []
        self.now = 0

    def feed(self, event: ins.Input) -> tuple[outs.Output, ...]:
        now = max(self.now, event.now)
        if now > self.now and self.state.active:
            self._step(ins.Tick(now=now))
        self.now = now
        return self._step(event)

    def _step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        transition = machine.step(self.state, event, self.config)
        self.state = transition.state
        for output in transition.outputs:
            said = _said(output)
            if said is not None:
                self.said.append(said)
        return transition.outputs


@attrs.frozen
class Replayed:
    """What :func:`replay` gives: what the machine said (``said``, in the recording's vocabulary),
    and where the site's id counter stood above the machine's (``counter``, see :func:`replay`)."""

    said: tuple[_Said, ...]
    counter: tuple[str, ...]
    start: int = 0
    seq: int = 0


def _recorded_child(records: Sequence[Observation], index: int) -> int | None:
    """The id the server gave the child of the NEXT ``records[index]``: its first feedback's."""
    uuid = records[index].goal_uuid
    for record in records[index + 1 :]:
        if record.kind == "feedback" and record.goal_uuid == uuid:
            value: int = record.message.id
            return value
    return None


def _count_as_site(driven: _Replay, records: Sequence[Observation], index: int) -> str | None:
    """Under the ``adapter`` id policy the task's id counter is the site's: its children's own events
    draw on it too (D10), so the counter stands where the server's next child shows it."""
    goal: Goal = records[index].message
    if driven.config.id_policy is not IdPolicy.ADAPTER or goal.event_type != EventType.NEXT.value:
        return None
    child = _recorded_child(records, index)
    state = driven.state
    if child is None or child - 1 <= state.last_id or state.running is not None:
        return None
    driven.state = attrs.evolve(state, last_id=child - 1)
    fresh = machine.fresh_id(state.last_id)
    return f"run {state.seq}: child {child} (the machine's next: {'none left' if fresh is None else fresh})"


def replay(
    records: Iterable[Observation],
    config: ServerConfig,
    *,
    fleet: str = "fleet",
    robot: str = "robot",
    source: str = "<recording>",
) -> Replayed:
    """What the machine under ``config`` says when driven by the clients' goals and cancels of
    ``records`` (one robot's, in the server's order) and by the site events they show
    (:func:`site_events`).  Under the ``adapter`` id policy a NEXT's child takes the id the server
    gave it when that is above the machine's next id: the ids the site's own events took are
    listed in :attr:`Replayed.counter`."""
    records = [record for record in records]
    start = _start(records)
    driven = _Replay(_state_at(records, start, fleet, robot), config)
    seq = driven.state.seq
    counter: list[str] = []
    goals = 0
    pulled: set[int] = set()  # goals fed before their place in the recording
    for index, record in enumerate(records):
        if index < start or index in pulled:
            continue
        if record.kind == "goal":
            goals += 1
            _feed_goal(driven, records, index, counter)
        elif record.kind == "cancel_request":
            driven.feed(ins.CancelRequested(goal_uuid=record.goal_uuid, now=record.time))
        else:
            cause = _caused_by_a_goal(records, index, driven.state) if driven.state.active else None
            if cause is not None and cause not in pulled:
                pulled.add(cause)
                goals += 1
                _feed_goal(driven, records, cause, counter, now=record.time)
            for event in site_events(driven.state, records, index):
                driven.feed(event)
    if not goals:
        raise TraceError(
            source, 0, "goals", "the recording holds no goal: its clients' part cannot be replayed"
        )
    return Replayed(said=tuple(driven.said), counter=tuple(counter), start=start, seq=seq)


def _feed_goal(
    driven: _Replay, records: Sequence[Observation], index: int, counter: list[str], now: int | None = None
) -> None:
    """Feed the goal ``records[index]`` (at ``now``, its own time unless pulled ahead), and start it
    when it is accepted, as an action server does at once."""
    record = records[index]
    at = record.time if now is None else now
    moved = _count_as_site(driven, records, index)
    if moved is not None:
        counter.append(moved)
    taken = driven.feed(ins.GoalRequested(goal_uuid=record.goal_uuid, goal=record.message, now=at))
    if any(isinstance(output, outs.GoalAccepted) for output in taken):
        driven.feed(ins.GoalStarted(goal_uuid=record.goal_uuid, now=at))


def _start(records: Sequence[Observation]) -> int:
    """Where the replay starts: after the last record that names a goal the recording lost the
    request of (a recorder that came up after its client, say), else at the start."""
    named: set[str] = set()
    start = 0
    for index, record in enumerate(records):
        if record.kind == "goal":
            named.add(record.goal_uuid)
        elif record.kind in _GOAL_KINDS and record.goal_uuid not in named:
            start = index + 1
    return start


def _state_at(records: Sequence[Observation], start: int, fleet: str, robot: str) -> State:
    """The machine's state where the replay starts: a fresh robot at the start of the recording, else
    what the last status before ``start`` shows (R20.2) of the run the last begin described."""
    if start == 0:
        return State.new(fleet, robot)
    status = next((r.message for r in reversed(records[:start]) if r.kind == "status"), None)
    if status is None:
        return State.new(fleet, robot)
    state = machine.state_from_status(status, fleet, robot)
    begin = next((r.message for r in reversed(records[:start]) if r.kind == "begin"), None)
    if begin is not None and begin.dynamic_event_seq == state.seq and state.active:
        state = attrs.evolve(state, description=begin.description)
    return state


# --- the points -------------------------------------------------------------------------------


class _Ids:
    """Child ids by their order in the run: 0 stays 0, the first other id seen is ``#1``."""

    def __init__(self) -> None:
        self.seq: int | None = None
        self.order: dict[int, str] = {}
        self.raw: list[str] = []

    def name(self, seq: int, value: int) -> str:
        if seq != self.seq:
            self.seq, self.order = seq, {}
        if value == 0:
            return "0"
        if value not in self.order:
            self.order[value] = f"#{len(self.order) + 1}"
            self.raw.append(f"run {seq}: {self.order[value]} = {value}")
        return self.order[value]


def _once(points: list[str], point: str) -> None:
    if not points or points[-1] != point:
        points.append(point)


def exchange(said: Iterable[Observation | _Said], seq: int = 0) -> Exchange:
    """The points a client observes of what a server said (a recording's records, or
    :func:`replay`'s), in order, from a run ``seq`` (see the module docs)."""
    ids = _Ids()
    goal_names: dict[str, str] = {}
    begins: list[str] = []
    statuses: list[str] = []
    responses: list[str] = []
    feedback: dict[str, list[str]] = {}
    tiers: dict[str, list[str]] = {}
    answers: list[str] = []
    cancels: list[str] = []

    def goal(uuid: str) -> str:
        return goal_names.setdefault(uuid, f"goal {len(goal_names) + 1}")

    for record in said:
        kind = record.kind
        if kind == "goal":
            goal(record.goal_uuid)
        elif kind == "begin":
            seq = record.message.dynamic_event_seq
            begins.append(f"seq={seq} {record.message.description}")
        elif kind == "status":
            message: DynamicEventStatus = record.message
            seq = message.dynamic_event_seq
            state = DynamicState(message.dynamic_state).name if message.dynamic_state <= 2 else "?"
            _once(statuses, f"seq={seq} {state} {message.status} id={ids.name(seq, message.id)}")
        elif kind == "goal_response":
            responses.append(f"{goal(record.goal_uuid)} {'accepted' if record.accepted else 'refused'}")
        elif kind == "feedback":
            fed: Feedback = record.message
            name = goal(record.goal_uuid)
            _once(feedback.setdefault(name, []), f"{fed.status} id={ids.name(seq, fed.id)}")
            tiers.setdefault(name, []).extend(entry.tier for entry in fed.logs)
        elif kind == "result":
            result: Result = record.message
            failed = " failed to begin" if result.execution_failure else ""
            child = ids.name(seq, result.id)
            answers.append(f"{goal(record.goal_uuid)} {record.status} {result.status} id={child}{failed}")
        elif kind == "cancel_response":
            cancels.append(f"{goal(record.goal_uuid)} {'accepted' if record.accepted else 'refused'}")
    return Exchange(
        begins=tuple(begins),
        statuses=tuple(statuses),
        ids=tuple(ids.raw),
        responses=tuple(responses),
        feedback=tuple(
            point
            for name, points in feedback.items()
            for point in (*(f"{name}: {point}" for point in points), f"{name}: logs {','.join(tiers[name])}")
        ),
        answers=tuple(answers),
        cancels=tuple(cancels),
    )


def _goals_first(records: Sequence[Observation], said: Sequence[_Said]) -> list[Observation | _Said]:
    """The replayed side, with the recording's goals before it: goals keep their recorded names."""
    return [record for record in records if record.kind == "goal"] + list(said)


def compare(recorded: Exchange, replayed: Exchange) -> tuple[Difference, ...]:
    """Where the replayed exchange differs from the recorded one, channel by channel (smallest edits,
    as difflib finds them)."""
    found: list[Difference] = []
    for name in CHANNELS:
        left, right = recorded.channel(name), replayed.channel(name)
        matcher = difflib.SequenceMatcher(a=left, b=right, autojunk=False)
        for tag, a0, a1, b0, b1 in matcher.get_opcodes():
            if tag == "equal":
                continue
            after = left[a0 - 1] if a0 else ""
            found.append(Difference(name, after, tuple(left[a0:a1]), tuple(right[b0:b1])))
    return tuple(found)


@attrs.frozen
class Comparison:
    """What :func:`compare_recording` found: the ``differences`` (none when the machine said what
    the recorded server said, point by point), the site's id counter (:attr:`Replayed.counter`), the
    record the replay started at (``start``), and the number of client ``goals`` replayed."""

    differences: tuple[Difference, ...]
    counter: tuple[str, ...]
    start: int
    goals: int


def compare_recording(
    records: Sequence[Observation],
    config: ServerConfig,
    *,
    fleet: str = "fleet",
    robot: str = "robot",
    source: str = "<recording>",
) -> Comparison:
    """Replay one robot's ``records`` (of the recording ``source``) under ``config`` and compare:
    where the machine parts from the recorded server.  Raises :class:`~dynevent.errors.TraceError`
    for a recording that holds no goal."""
    replayed = replay(records, config, fleet=fleet, robot=robot, source=source)
    held = records[replayed.start :]
    recorded = exchange(held, replayed.seq)
    ours = exchange(_goals_first(held, replayed.said), replayed.seq)
    goals = sum(1 for record in held if record.kind == "goal")
    return Comparison(compare(recorded, ours), replayed.counter, replayed.start, goals)
