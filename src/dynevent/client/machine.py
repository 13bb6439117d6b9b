"""The remote action client's Dynamic Event machine: pure commands and ``step`` over a frozen state.

The server machine (:mod:`dynevent.server.machine`) is what a robot runs; this is
what the other end runs: a behaviour tree, a workflow engine or an operator
tool that drives one robot through the action
``rmf/dynamic_event/command/<fleet>/<robot>``.  Like the server, it is a set
of pure functions over a frozen :class:`ClientState`; each returns a
:class:`ClientTransition` (the new state and the outputs, in order).  It reads
no clock (time enters as integer nanoseconds ``now``), does no I/O, draws no
random numbers and never raises once its inputs are built.

The model
---------

*The view.*  The client's view of the robot is the last status message it
adopted: :attr:`ClientState.phase`, :attr:`~ClientState.seq`,
:attr:`~ClientState.current_id` and :attr:`~ClientState.status`, named as
the server's ``State.phase``, ``State.seq`` and ``State.current_id``.  The
server publishes a status message after every step that changes any of them
(R2.3), so once the client has received every status message published so
far its view equals the server's.  Status messages of an older run than one
already seen (seq compared as uint32 serial numbers, so 4294967295 is older
than 0) are stale and ignored.

*What the client knows besides.*  For the newest run it has heard of (from a
begin description or a status message): the run's description, the highest
event id seen in the run (status, feedback, results, rejections and its own
NEXT goals), the highest child id it knows has ended (from answers to its own
goals, which may arrive before the status that reports the end, and from a
RUNNING status that carries a child's final status, R20.2) and whether
its own FINISHED goal ended the run.

*Commands.*  :func:`request_next`, :func:`request_cancel` and
:func:`request_finish` build a :class:`~dynevent.wire.messages.Goal` with the
view's seq and the right ``event_type`` and ``id``, name it with a
deterministic goal UUID (the state's 16-hex-digit prefix and a counter) and
return it as :class:`SendGoal`.  A NEXT's id is one more than the highest id
seen in the run, so it is unique in the run and passes the server's id rule
(R4.12).  A CANCEL names the running child.  When the server, in the state
the client knows of, would refuse the goal, the command returns
:class:`Refused` instead, carrying a :class:`~dynevent.server.outputs.Rejected` with
the reason the server would give.  The checks are the server's own:
:func:`dynevent.server.machine.accept` runs on the server state the client's view
implies (:func:`dynevent.server.machine.state_from_status`, with the ids and the
child ends the client knows of), so the reasons come in the server's order
(R4): ``inactive``, ``busy``, ``unsupported_category`` (when the client was
told the robot's categories), ``description_invalid`` (too long),
``description_not_json``, ``non_finite_stubborn_period``, ``stale_id`` (no
id above the highest one seen is left) and ``cancel_idle``.  The client adds
what only it knows: ``seq_mismatch`` when a newer run has begun and its
status has not arrived, and ``busy`` while a NEXT or FINISHED goal of its own
is still open (a second one would only race it).

*Outcomes.*  Every goal the client sends ends in exactly one :class:`Outcome`
whose :class:`OutcomeKind` says what became of it, in the spirit of
``rst.navigation.CommandResult``: see :class:`OutcomeKind` and docs/client.md.
A NEXT goal with a ``timeout`` that is still open when a tick reaches its
deadline is cancelled by the client (a CANCEL goal, sent as soon as the child
is known to run) and reported ``timeout`` when it ends.

*Contact.*  The binding says when a server process of the robot comes into
contact (:class:`ContactMade`: a status publisher matched, a new process or
one lost before) and when none is any longer (:class:`ContactLost`).  Coming
into contact with goals open, the client asks again for each one's result
(:class:`AskResult`, R21.4, R21.5), at once and then after waits that double
up to :data:`ASK_AGAIN_LONGEST`, until it is answered; lost and found contact
are said (:class:`OutOfContact`, :class:`BackInContact`).  A status or begin
that arrives with its ``now`` and shows an open goal answered (its run over,
or the child it ran or names ended) makes the client ask again for that
goal's result :data:`ANSWER_GRACE` later, unless the answer comes first, and
then as above (R21.6): a network may lose the answer to one client while the
client still hears the robot.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import attrs

from dynevent.client.inputs import (
    BeginReceived,
    ClientInput,
    ContactLost,
    ContactMade,
    FeedbackReceived,
    GoalResponse,
    ResultReceived,
    StatusReceived,
    Tick,
    checked_now,
)
from dynevent.client.outputs import (
    OUTCOME_OF_STATUS,
    AskResult,
    BackInContact,
    ClientOutput,
    Ignored,
    Outcome,
    OutcomeKind,
    OutOfContact,
    Progress,
    Refused,
    RunBegan,
    SendGoal,
    TimedOut,
    ViewChanged,
)
from dynevent.errors import InvalidValue, WrongInput
from dynevent.server import machine
from dynevent.server.machine import ServerConfig, State, Validator
from dynevent.server.outputs import Rejected
from dynevent.wire._fields import SECOND as _SECOND_NS
from dynevent.wire._fields import U64_MAX, id_not_after, seq_after
from dynevent.wire.description import DEFAULT_CATEGORY
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.units import to_nanoseconds
from dynevent.wire.vocab import (
    DynamicState,
    EventType,
    Failure,
    GoalStatus,
    RejectReason,
    Status,
)

__all__ = [
    "ANSWER_GRACE",
    "ASK_AGAIN_LONGEST",
    "ASK_AGAIN_PERIOD",
    "LOST_AFTER_ASKS",
    "SECOND",
    "ClientState",
    "ClientTransition",
    "OpenGoal",
    "next_deadline",
    "request_cancel",
    "request_finish",
    "request_next",
    "request_withdraw",
    "step",
]

#: One second in the unit of instants (integer nanoseconds), e.g. ``now + 30 * SECOND``
#: (:mod:`dynevent.wire.units`: durations, such as ``timeout``, are seconds).
SECOND = _SECOND_NS

#: How long after asking a server again for a goal's result the client asks once more, at first
#: (R21.4): the request may have gone before the server's result service was matched, and such a
#: request is dropped unheard.  Each later wait is twice the one before, up to
#: :data:`ASK_AGAIN_LONGEST`, so that a goal whose child runs for long costs the server a few pending
#: requests, not one a second.  Integer nanoseconds.
ASK_AGAIN_PERIOD = SECOND
#: The longest wait between two requests for the same goal's result (integer nanoseconds).
ASK_AGAIN_LONGEST = 30 * SECOND
#: How long after the robot's status showed a goal answered the client waits for the answer before
#: it asks for it again (R21.6): the status and the answer come on channels of their own, and a
#: network that loses packets brings the answer seconds after the status.  Integer nanoseconds.
ANSWER_GRACE = 2 * SECOND
#: How many requests for the result of a goal whose acceptance the client has not heard are sent on
#: coming into contact before one answered unknown ends it lost (R21.4): the goal's own request may
#: reach the server after them (a process just come into contact; a lossy network repairs a lost
#: request at the writer's next heartbeat, every 3 s with Fast DDS).  The fourth goes 7 s after
#: the contact (waits of 1, 2 and 4 s).
LOST_AFTER_ASKS = 3

_HEX = frozenset("0123456789abcdefABCDEF")


def _prefix(value: Any) -> str:
    if type(value) is not str or len(value) != 16 or not all(ch in _HEX for ch in value):
        raise InvalidValue("ClientState", "uuid_prefix", value, "expected 16 hexadecimal digits")
    return value.lower()


# --------------------------------------------------------------------------- state


@attrs.frozen(kw_only=True)
class OpenGoal:
    """A goal this client sent that has no outcome yet.

    ``accepted`` once the server accepted it; ``child_id`` and
    ``child_status`` (NEXT) once feedback named the child; ``deadline`` the
    instant a NEXT with a timeout times out, ``timed_out`` once a tick
    reached it; ``withdrawn`` once the caller withdrew the NEXT
    (:func:`request_withdraw`).  ``ask_at`` is the instant the client next asks
    the server again for the goal's result (R21.4, R21.5, R21.6; ``None``: the
    request sent with the goal stands), ``asks`` how often it has asked again,
    ``shown_answered`` whether it asks because the robot's status showed the
    goal answered (R21.6) rather than because a server process came into
    contact (R21.4).
    """

    goal_uuid: str
    goal: Goal
    accepted: bool = False
    child_id: int | None = None
    child_status: str = ""
    deadline: int | None = None
    timed_out: bool = False
    withdrawn: bool = False
    ask_at: int | None = None
    asks: int = 0
    shown_answered: bool = False

    @property
    def cancel_owed(self) -> bool:
        """A NEXT whose child this client is to cancel once it is known to run (timed out or withdrawn)."""
        return self.goal.event_type == EventType.NEXT and (self.timed_out or self.withdrawn)


def _validators(value: Any) -> Mapping[str, Validator] | None:
    if value is None:
        return None
    if not isinstance(value, Mapping) or not all(
        isinstance(name, str) and callable(check) for name, check in value.items()
    ):
        raise InvalidValue("ClientState", "validators", value, "expected a mapping of category to validator")
    return dict(value)


def _categories(value: Any) -> frozenset[str] | None:
    if value is None:
        return None
    names = frozenset(value)
    if not all(isinstance(name, str) for name in names):
        raise InvalidValue("ClientState", "categories", value, "expected category names (str)")
    return names


@attrs.frozen(kw_only=True)
class ClientState:
    """Everything the client knows; build a fresh one with :meth:`new`.

    The view (``phase``, ``seq``, ``current_id``, ``status``) is the last
    status message adopted; it starts as a fresh server's.  ``newest_seq`` is
    the newest run heard of (``None`` before any message), ``description``
    its begin description (``""`` until it arrives), ``last_id`` the highest
    id seen in it, ``ended_id`` the highest child id known to have ended in
    it, ``finished`` whether this client's FINISHED ended it.
    ``contact_lost_at`` is the instant the client lost contact with every server
    process of the robot, while it is out of contact (R21.5).  ``goals`` are
    the open goals, in the order they were sent; ``counter`` numbers the goal
    UUIDs (``uuid_prefix`` followed by the counter as 16 hex digits).
    ``categories``, when given, are the robot's supported categories;
    ``validators``, when given, check the descriptions of the categories they
    name as the server would (``dynevent.descriptions.Robot().validators()``:
    the field's schemas), so that a description the server would refuse is
    refused here, with the same errors, and never sent.
    """

    uuid_prefix: str = attrs.field(converter=_prefix)
    counter: int = 0
    categories: frozenset[str] | None = attrs.field(default=None, converter=_categories)
    validators: Mapping[str, Validator] | None = attrs.field(
        default=None, converter=_validators, eq=False, repr=False
    )
    phase: DynamicState = DynamicState.INACTIVE
    seq: int = 0
    current_id: int = 0
    status: str = Status.UNINITIALIZED.value
    newest_seq: int | None = None
    description: str = ""
    last_id: int = 0
    ended_id: int | None = None
    finished: bool = False
    contact_lost_at: int | None = None
    goals: tuple[OpenGoal, ...] = ()

    @classmethod
    def new(
        cls,
        uuid_prefix: str,
        *,
        categories: Iterable[str] | None = None,
        validators: Mapping[str, Validator] | None = None,
    ) -> ClientState:
        """A client that has heard nothing yet; ``uuid_prefix`` is 16 hexadecimal digits."""
        return cls(uuid_prefix=uuid_prefix, categories=categories, validators=validators)

    def goal(self, uuid: str) -> OpenGoal | None:
        """The open goal named ``uuid``, if any."""
        return next((goal for goal in self.goals if goal.goal_uuid == uuid), None)


@attrs.frozen
class ClientTransition:
    """What one command or step did: the new client state and the outputs, in order.  A pair:
    ``state, outputs = client.step(...)``."""

    state: ClientState
    outputs: tuple[ClientOutput, ...]

    def __iter__(self) -> Iterator[Any]:
        """The state, then the outputs, so that a transition unpacks as the pair it is."""
        return iter((self.state, self.outputs))


# --------------------------------------------------------------------------- knowledge


def _run_over(state: ClientState, seq: int) -> bool:
    """Does the client know that run ``seq`` has ended?"""
    if state.newest_seq is None:
        return False
    if state.newest_seq != seq:
        return True
    return state.finished or (state.phase is DynamicState.INACTIVE and state.seq == seq)


def _ended(state: ClientState, child_id: int) -> bool:
    """Does the client know that child ``child_id`` of the newest run has ended?"""
    return state.ended_id is not None and id_not_after(child_id, state.ended_id)


def _child_ended(state: ClientState, child_id: int) -> ClientState:
    """Record that child ``child_id`` of the newest run has ended."""
    if state.ended_id is None or not id_not_after(child_id, state.ended_id):
        return attrs.evolve(state, ended_id=child_id)
    return state


def _answer_shown(state: ClientState, goal: OpenGoal) -> bool:
    """R21.6: does the robot's status show that ``goal`` has been answered?  Its run is over, or (a
    NEXT, whose child the feedback named or, where no feedback came, its own id names; a CANCEL) the
    child it ran or names has ended: a status of its run names that child's end (R20.2), a later
    child, or the robot waiting at that id or later (a NEXT's child, or a CANCEL's target, runs
    before the robot waits at its id)."""
    seq = goal.goal.dynamic_event_seq
    if _run_over(state, seq):
        return True
    if goal.goal.event_type == EventType.NEXT:
        # its response and its feedback may both have been lost (found at 30% loss across hosts)
        child = goal.child_id if goal.child_id is not None else goal.goal.id or None
    elif goal.goal.event_type == EventType.CANCEL:
        child = goal.goal.id
    else:
        return False
    if child is None or seq != state.newest_seq or state.seq != seq:
        return False
    if _ended(state, child):
        return True
    later = id_not_after(child, state.current_id)
    if state.phase is DynamicState.RUNNING:
        return later and state.current_id != child
    return state.phase is DynamicState.WAITING and later


def _watch_answers(state: ClientState, now: int) -> ClientState:
    """R21.6: every open goal the robot's status now shows answered, and not yet asked for again, is
    asked for again :data:`ANSWER_GRACE` from now unless its answer comes first."""
    for goal in state.goals:
        if goal.ask_at is None and _answer_shown(state, goal):
            state = _replace(state, attrs.evolve(goal, ask_at=now + ANSWER_GRACE, shown_answered=True))
    return state


def _new_run(state: ClientState, seq: int) -> ClientState:
    return attrs.evolve(state, newest_seq=seq, description="", last_id=0, ended_id=None, finished=False)


def _seen_id(state: ClientState, seq: int, value: int) -> ClientState:
    """Record an id seen in run ``seq`` (only the newest run's ids matter)."""
    if seq != state.newest_seq or value <= state.last_id:
        return state
    return attrs.evolve(state, last_id=value)


def _take_uuid(state: ClientState) -> tuple[str, ClientState]:
    uuid = f"{state.uuid_prefix}{state.counter:016x}"
    return uuid, attrs.evolve(state, counter=(state.counter + 1) & U64_MAX)


def _running_child(state: ClientState) -> int | None:
    """The id of the child the client believes runs now, if any.

    The child its own open NEXT started comes first: a CANCEL must name it,
    even while a status names another client's child (a status and this
    client's feedback can disagree while messages are in flight).  Otherwise
    the view's child while RUNNING.
    """
    own = [
        goal.child_id
        for goal in state.goals
        if goal.goal.event_type == EventType.NEXT
        and goal.goal.dynamic_event_seq == state.seq
        and goal.child_id is not None
        and not _ended(state, goal.child_id)
    ]
    if own:
        return max(own)
    if state.phase is DynamicState.RUNNING and not _ended(state, state.current_id):
        return state.current_id
    return None


def _cancel_open(state: ClientState, seq: int, child_id: int) -> bool:
    return any(
        goal.goal.event_type == EventType.CANCEL
        and goal.goal.dynamic_event_seq == seq
        and goal.goal.id == child_id
        for goal in state.goals
    )


# --------------------------------------------------------------------------- commands


def _projection(state: ClientState, event_type: int) -> State:
    """The server state the client's view implies (:func:`~dynevent.server.machine.state_from_status`).

    Besides its last status message the client knows the ids it has seen in
    the run, that its own FINISHED ended the run, that a child it was told
    of has ended, and (for a CANCEL) the child its own NEXT started.
    """
    if state.phase is DynamicState.INACTIVE or state.finished:
        view = DynamicEventStatus(dynamic_event_seq=state.seq)
        return machine.state_from_status(view)
    if event_type == EventType.CANCEL:
        child = _running_child(state)
    elif state.phase is DynamicState.RUNNING and not _ended(state, state.current_id):
        child = state.current_id
    else:
        child = None
    view = DynamicEventStatus(
        dynamic_event_seq=state.seq,
        dynamic_state=DynamicState.WAITING if child is None else DynamicState.RUNNING,
        status=state.status,
        id=state.current_id if child is None else child,
    )
    return machine.state_from_status(view, last_id=state.last_id)


def _config(state: ClientState, category: str) -> ServerConfig:
    """The configuration a local check assumes: the robot's categories if known, else the goal's own,
    each checked by its validator when the client has one, else taking any description."""
    names = state.categories if state.categories is not None else (category,)
    known = state.validators or {}
    return ServerConfig(
        categories={
            name: known.get(name, machine.any_description) for name in names if name != DEFAULT_CATEGORY
        }
    )


def _refusal(state: ClientState, goal: Goal) -> Rejected | None:
    """What the server would refuse ``goal`` for, as far as the client knows (R20.1), or ``None``.

    The server's own checks run on the state the client's view implies
    (:func:`_projection`); the client adds what only it knows: a run whose
    begin arrived before its status, and its own open NEXT or FINISHED goal.
    """
    if state.newest_seq is not None and state.newest_seq != state.seq:
        return Rejected(
            reason=RejectReason.SEQ_MISMATCH,
            text=f"run {state.newest_seq} has begun and its status has not arrived; "
            f"a goal for run {state.seq} would be refused",
            expected_seq=state.newest_seq,
            received_seq=state.seq,
            rule="R4.2",
        )
    decision = machine.accept(_projection(state, goal.event_type), goal, _config(state, goal.category))
    if isinstance(decision, Rejected):
        if decision.reason is RejectReason.STALE_ID:  # the client picks ids above those seen: none is left
            text = f"no id above {state.last_id}, the highest id seen in this run, is left"
            return attrs.evolve(decision, text=text)
        return decision
    if goal.event_type == EventType.CANCEL:
        return None
    for opened in state.goals:
        if opened.goal.dynamic_event_seq == state.seq and opened.goal.event_type in (
            EventType.NEXT,
            EventType.FINISHED,
        ):
            kind = EventType(opened.goal.event_type).name
            return Rejected(
                reason=RejectReason.BUSY,
                text=f"this client's {kind} goal {opened.goal_uuid} is still open; another would race it",
                current_id=opened.child_id,
                rule="R4.6",
            )
    return None


def _check_timeout(value: Any) -> int | None:
    """A timeout in seconds as nanoseconds (None: no timeout)."""
    return None if value is None else to_nanoseconds("request_next", "timeout", value, zero=False)


def _send(state: ClientState, goal: Goal, deadline: int | None = None) -> ClientTransition:
    uuid, state = _take_uuid(state)
    opened = OpenGoal(goal_uuid=uuid, goal=goal, deadline=deadline)
    state = attrs.evolve(state, goals=(*state.goals, opened))
    if goal.event_type == EventType.NEXT:
        state = _seen_id(state, goal.dynamic_event_seq, goal.id)
    return ClientTransition(state, (SendGoal(goal_uuid=uuid, goal=goal),))


def _refused(state: ClientState, event_type: EventType, rejection: Rejected, goal: Goal) -> ClientTransition:
    return ClientTransition(state, (Refused(event_type=event_type, rejection=rejection, goal=goal),))


def request_next(
    state: ClientState,
    category: str,
    description: str,
    *,
    stubborn_period: float = 0.0,
    timeout: float | None = None,
    now: int,
) -> ClientTransition:
    """Ask the robot to run the next event: a NEXT goal, or a local refusal.

    The goal's id is one more than the highest id seen in the run.
    ``timeout`` (seconds, as every duration: :mod:`dynevent.wire.units`) makes
    the client cancel the child if the goal is still open ``timeout`` after
    ``now`` (integer nanoseconds, as every instant).  Values the wire cannot
    carry (a category holding NUL, a stubborn period beyond float32) raise
    :class:`~dynevent.errors.InvalidValue`, as does a timeout that is not a
    positive number of seconds up to a week (``30 * SECOND`` is refused: that
    is nanoseconds); NaN and infinite stubborn periods are wire-legal and
    refused locally, as the server would.
    """
    now = checked_now("request_next", now)
    timeout = _check_timeout(timeout)
    fresh = machine.fresh_id(state.last_id)  # none left: the highest, which the machine refuses (R4.12)
    goal = Goal(
        dynamic_event_seq=state.seq,
        event_type=EventType.NEXT,
        category=category,
        description=description,
        id=state.last_id if fresh is None else fresh,
        stubborn_period=stubborn_period,
    )
    refusal = _refusal(state, goal)
    if refusal is not None:
        return _refused(state, EventType.NEXT, refusal, goal)
    return _send(state, goal, None if timeout is None else now + timeout)


def request_cancel(state: ClientState, *, now: int) -> ClientTransition:
    """Ask the robot to cancel the running event: a CANCEL goal naming it, or a local refusal.

    The running event is the newest child the client knows runs: the view's
    while RUNNING, or the child of its own open NEXT goal once feedback named
    it, unless an answer has told the client that child has ended.
    """
    now = checked_now("request_cancel", now)
    target = _running_child(state)
    goal = Goal(
        dynamic_event_seq=state.seq,
        event_type=EventType.CANCEL,
        id=state.current_id if target is None else target,
    )
    refusal = _refusal(state, goal)
    if refusal is not None:
        return _refused(state, EventType.CANCEL, refusal, goal)
    return _send(state, goal)


def request_finish(state: ClientState, *, now: int) -> ClientTransition:
    """Tell the robot the dynamic event is finished: a FINISHED goal, or a local refusal."""
    now = checked_now("request_finish", now)
    goal = Goal(dynamic_event_seq=state.seq, event_type=EventType.FINISHED)
    refusal = _refusal(state, goal)
    if refusal is not None:
        return _refused(state, EventType.FINISHED, refusal, goal)
    return _send(state, goal)


def request_withdraw(state: ClientState, goal_uuid: str, *, now: int) -> ClientTransition:
    """The caller no longer wants this open NEXT of its own: cancel its child once it is known to run.

    The CANCEL goal naming the child is sent at once when the child is known
    to run, else as soon as feedback (or a RUNNING status naming the goal's
    id) shows it, as for a timeout; no CANCEL is added to one of this client's
    already open.  The NEXT's outcome then says how the child ended
    (``canceled``, or ``completed`` if it ended first); a NEXT refused or
    ended before its child ran sends nothing.  A goal that is not an open
    NEXT of this client is :class:`Ignored`, with why.  This is what a
    behaviour tree's halt, or an interrupted command line, asks of a NEXT.
    """
    now = checked_now("request_withdraw", now)
    goal = state.goal(goal_uuid)
    if goal is None:
        return ClientTransition(state, (Ignored(input="withdraw", why=f"goal {goal_uuid} is not open"),))
    if goal.goal.event_type != EventType.NEXT:
        kind = EventType(goal.goal.event_type).name
        why = f"goal {goal_uuid} is a {kind}: only a NEXT's child can be withdrawn"
        return ClientTransition(state, (Ignored(input="withdraw", why=why),))
    if goal.withdrawn:
        why = f"goal {goal_uuid} is already withdrawn"
        return ClientTransition(state, (Ignored(input="withdraw", why=why),))
    withdrawn = attrs.evolve(goal, withdrawn=True)
    state, sent = _owed_cancel(_replace(state, withdrawn), withdrawn)
    return ClientTransition(state, sent)


def next_deadline(state: ClientState) -> int | None:
    """The earliest instant a tick would do something (``None`` if none): time a goal out, or ask a
    server again for a goal's result.  When to tick next."""
    deadlines = [goal.deadline for goal in state.goals if goal.deadline is not None and not goal.cancel_owed]
    deadlines += [goal.ask_at for goal in state.goals if goal.ask_at is not None]
    return min(deadlines) if deadlines else None


# --------------------------------------------------------------------------- step handlers


def _replace(state: ClientState, goal: OpenGoal) -> ClientState:
    return attrs.evolve(
        state, goals=tuple(goal if other.goal_uuid == goal.goal_uuid else other for other in state.goals)
    )


def _remove(state: ClientState, uuid: str) -> ClientState:
    return attrs.evolve(state, goals=tuple(other for other in state.goals if other.goal_uuid != uuid))


def _owed_cancel(state: ClientState, goal: OpenGoal) -> tuple[ClientState, tuple[ClientOutput, ...]]:
    """Send the CANCEL a timed-out or withdrawn NEXT is owed, once its child is known to run and no
    CANCEL of ours naming it is open."""
    seq = goal.goal.dynamic_event_seq
    if not goal.cancel_owed or seq != state.seq or _run_over(state, seq):
        return state, ()
    child = goal.child_id
    if (
        child is None
        and goal.accepted
        and state.phase is DynamicState.RUNNING
        and state.current_id == goal.goal.id
    ):
        child = goal.goal.id  # id policy "goal": the status names our child when feedback was lost
    if child is None or _ended(state, child) or _cancel_open(state, seq, child):
        return state, ()
    cancel = Goal(dynamic_event_seq=seq, event_type=EventType.CANCEL, id=child)
    transition = _send(state, cancel)
    return transition.state, transition.outputs


def _on_begin(state: ClientState, event: BeginReceived) -> ClientTransition:
    message = event.message
    seq = message.dynamic_event_seq
    if state.newest_seq is not None and seq != state.newest_seq and not seq_after(seq, state.newest_seq):
        return ClientTransition(
            state, (Ignored(input=event.KIND, why=f"begin of run {seq}, older than run {state.newest_seq}"),)
        )
    if state.newest_seq is None or seq != state.newest_seq:
        state = _new_run(state, seq)
    if state.description:
        return ClientTransition(state, (Ignored(input=event.KIND, why=f"run {seq} was already described"),))
    state = attrs.evolve(state, description=message.description)
    if event.now is not None:
        state = _watch_answers(state, event.now)
    return ClientTransition(state, (RunBegan(seq=seq, description=message.description),))


def _on_status(state: ClientState, event: StatusReceived) -> ClientTransition:
    message = event.message
    seq = message.dynamic_event_seq
    if state.newest_seq is not None and seq != state.newest_seq and not seq_after(seq, state.newest_seq):
        why = f"status of run {seq}, older than run {state.newest_seq}"
        return ClientTransition(state, (Ignored(input=event.KIND, why=why),))
    try:
        phase = DynamicState(message.dynamic_state)
    except ValueError:
        why = f"dynamic_state {message.dynamic_state} is none of INACTIVE, WAITING, RUNNING"
        return ClientTransition(state, (Ignored(input=event.KIND, why=why),))
    if state.newest_seq is None or seq != state.newest_seq:
        state = _new_run(state, seq)
    before = (state.phase, state.seq, state.current_id, state.status)
    state = attrs.evolve(state, phase=phase, seq=seq, current_id=message.id, status=message.status)
    if phase is not DynamicState.INACTIVE:
        state = _seen_id(state, seq, message.id)
    if machine.child_ended(message):
        state = _child_ended(state, message.id)  # R20.2: the child's final status names its end
    if event.now is not None:
        state = _watch_answers(state, event.now)
    outputs: list[ClientOutput] = []
    if (phase, seq, message.id, message.status) != before:
        outputs.append(ViewChanged(phase=phase, seq=seq, current_id=message.id, status=message.status))
    for goal in state.goals:
        if goal.cancel_owed:
            state, sent = _owed_cancel(state, goal)
            outputs.extend(sent)
    return ClientTransition(state, tuple(outputs))


def _unknown(state: ClientState, event: ClientInput, uuid: str) -> ClientTransition:
    return ClientTransition(state, (Ignored(input=event.KIND, why=f"no open goal {uuid}"),))


def _on_response(state: ClientState, event: GoalResponse) -> ClientTransition:
    goal = state.goal(event.goal_uuid)
    if goal is None:
        return _unknown(state, event, event.goal_uuid)
    if event.accepted:
        goal = attrs.evolve(goal, accepted=True)
        state, sent = _owed_cancel(_replace(state, goal), goal)
        return ClientTransition(state, sent)
    if goal.accepted:
        return ClientTransition(
            state, (Ignored(input=event.KIND, why=f"goal {goal.goal_uuid} was accepted"),)
        )
    rejection = event.rejection
    seq = goal.goal.dynamic_event_seq
    over = _run_over(state, seq)
    state = _remove(state, goal.goal_uuid)
    if rejection is not None and rejection.current_id is not None:  # the server's running or last id
        state = _seen_id(state, seq, rejection.current_id)
    reason = None if rejection is None else rejection.reason
    if over:
        kind, text = OutcomeKind.SUPERSEDED, f"refused after run {seq} ended"
    else:
        kind = OutcomeKind.REJECTED
        text = "refused by the server" + ("" if rejection is None else f": {rejection.text}")
    outcome = Outcome(
        goal_uuid=goal.goal_uuid,
        goal=goal.goal,
        kind=kind,
        id=goal.goal.id,
        status="",
        text=text,
        reason=reason,
        rejection=rejection,
    )
    return ClientTransition(state, (outcome,))


def _on_feedback(state: ClientState, event: FeedbackReceived) -> ClientTransition:
    goal = state.goal(event.goal_uuid)
    if goal is None:
        return _unknown(state, event, event.goal_uuid)
    feedback = event.feedback
    goal = attrs.evolve(goal, accepted=True, child_id=feedback.id, child_status=feedback.status)
    state = _seen_id(_replace(state, goal), goal.goal.dynamic_event_seq, feedback.id)
    outputs: list[ClientOutput] = [
        Progress(goal_uuid=goal.goal_uuid, status=feedback.status, id=feedback.id, logs=feedback.logs)
    ]
    state, sent = _owed_cancel(state, goal)
    outputs.extend(sent)
    return ClientTransition(state, tuple(outputs))


def _classify(state: ClientState, goal: OpenGoal, event: ResultReceived) -> Outcome:
    """The outcome of a goal from its terminal answer, given what the client knew before it."""
    result = event.result
    failure = result.execution_failure
    kind: OutcomeKind
    reason: RejectReason | None = None
    seq = goal.goal.dynamic_event_seq
    if failure:
        known = Failure.of(failure)
        reason = None if known is None else known.reason
        if event.status is GoalStatus.CANCELED:
            kind, text = OutcomeKind.CANCELED, f"cancelled before it began: {failure}"
        elif _run_over(state, seq):
            kind, text = OutcomeKind.SUPERSEDED, f"could not begin after run {seq} ended: {failure}"
        else:
            kind, text = OutcomeKind.EXECUTION_FAILURE, f"could not begin: {failure}"
    elif goal.goal.event_type == EventType.NEXT and goal.timed_out:
        kind = OutcomeKind.TIMEOUT
        text = f"outran its timeout; the event ended {result.status!r}"
    else:
        kind = OUTCOME_OF_STATUS.get(result.status, OutcomeKind.ERROR)
        text = f"the event ended {result.status!r}"
        if result.status not in OUTCOME_OF_STATUS:
            text += ", which is not a final status"
    # a result names the child (or the dynamic event) only when the goal ran; a CANCEL names its target
    event_id = goal.goal.id if failure or goal.goal.event_type == EventType.CANCEL else result.id
    return Outcome(
        goal_uuid=goal.goal_uuid,
        goal=goal.goal,
        kind=kind,
        id=event_id,
        status=result.status,
        text=text,
        reason=reason,
        execution_failure=failure,
        goal_status=event.status,
        result=result,
    )


def _on_result(state: ClientState, event: ResultReceived) -> ClientTransition:
    goal = state.goal(event.goal_uuid)
    if goal is None:
        return _unknown(state, event, event.goal_uuid)
    outcome = _classify(state, goal, event)
    state = _remove(state, goal.goal_uuid)
    result = event.result
    seq = goal.goal.dynamic_event_seq
    if not result.execution_failure and seq == state.newest_seq:
        if goal.goal.event_type == EventType.FINISHED and event.status is GoalStatus.SUCCEEDED:
            state = attrs.evolve(state, finished=True)
        elif goal.goal.event_type in (EventType.NEXT, EventType.CANCEL):
            state = _child_ended(_seen_id(state, seq, result.id), result.id)
    return ClientTransition(state, (outcome,))


def _ask_due(state: ClientState, now: int) -> tuple[ClientState, tuple[ClientOutput, ...]]:
    """Ask again for the result of every goal whose time to ask has come (R21.4, R21.5, R21.6); the next
    time is one wait on, each wait twice the last, up to :data:`ASK_AGAIN_LONGEST`.  An unknown goal
    is lost (``contact``) only where the server came into contact and either accepted the goal or
    was asked :data:`LOST_AFTER_ASKS` times already: a request for a goal whose acceptance was not
    heard may reach the server before the goal's own request (R21.4)."""
    asked: list[ClientOutput] = []
    for goal in state.goals:
        if goal.ask_at is None or now < goal.ask_at:
            continue
        wait = min(ASK_AGAIN_PERIOD << min(goal.asks, 16), ASK_AGAIN_LONGEST)
        state = _replace(state, attrs.evolve(goal, ask_at=min(now + wait, U64_MAX), asks=goal.asks + 1))
        conclusive = not goal.shown_answered and (goal.accepted or goal.asks >= LOST_AFTER_ASKS)
        asked.append(AskResult(goal_uuid=goal.goal_uuid, contact=conclusive))
    return state, tuple(asked)


def _on_contact_made(state: ClientState, event: ContactMade) -> ClientTransition:
    """R21.4, R21.5: a server process came into contact (a new one, or one out of contact until now):
    whatever it answered while the client could not hear it is asked for again, for every open goal."""
    outputs: list[ClientOutput] = []
    if state.contact_lost_at is not None:
        outputs.append(BackInContact(since=state.contact_lost_at, now=event.now))
        state = attrs.evolve(state, contact_lost_at=None)
    asking = (attrs.evolve(goal, ask_at=event.now, asks=0, shown_answered=False) for goal in state.goals)
    state = attrs.evolve(state, goals=tuple(asking))
    state, asked = _ask_due(state, event.now)
    return ClientTransition(state, (*outputs, *asked))


def _on_contact_lost(state: ClientState, event: ContactLost) -> ClientTransition:
    """R21.5: no server process of the robot is in contact any longer."""
    if state.contact_lost_at is not None:
        why = f"out of contact since {state.contact_lost_at} already"
        return ClientTransition(state, (Ignored(input=event.KIND, why=why),))
    state = attrs.evolve(state, contact_lost_at=event.now)
    return ClientTransition(state, (OutOfContact(since=event.now),))


def _on_tick(state: ClientState, event: Tick) -> ClientTransition:
    state, asked = _ask_due(state, event.now)
    outputs: list[ClientOutput] = list(asked)
    for goal in state.goals:
        deadline = goal.deadline
        if deadline is None or goal.cancel_owed or event.now < deadline:  # a withdrawn goal times out no more
            continue
        expired = attrs.evolve(goal, timed_out=True)
        state = _replace(state, expired)
        child = goal.child_id if goal.child_id is not None else goal.goal.id
        outputs.append(TimedOut(goal_uuid=goal.goal_uuid, id=child, deadline=deadline))
        state, sent = _owed_cancel(state, expired)
        outputs.extend(sent)
    return ClientTransition(state, tuple(outputs))


def step(state: ClientState, event: ClientInput) -> ClientTransition:
    """Apply one input to the client state: the new state and the outputs, in order.  Pure and total
    over its inputs; a value of another type is refused with :class:`~dynevent.errors.WrongInput`."""
    if isinstance(event, BeginReceived):
        return _on_begin(state, event)
    if isinstance(event, StatusReceived):
        return _on_status(state, event)
    if isinstance(event, GoalResponse):
        return _on_response(state, event)
    if isinstance(event, FeedbackReceived):
        return _on_feedback(state, event)
    if isinstance(event, ResultReceived):
        return _on_result(state, event)
    if isinstance(event, Tick) and isinstance(state, ClientState):
        return _on_tick(state, event)
    if isinstance(event, ContactMade) and isinstance(state, ClientState):
        return _on_contact_made(state, event)
    if isinstance(event, ContactLost) and isinstance(state, ClientState):
        return _on_contact_lost(state, event)
    if not isinstance(state, ClientState):
        raise WrongInput("client.step(state, ...)", "a dynevent.client.ClientState", state)
    raise WrongInput(
        "client.step(state, event)", "a client input of dynevent.client (StatusReceived, Tick, ...)", event
    )
